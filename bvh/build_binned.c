/*
 * build_binned.c - binned SAH construction (build=binned).
 *
 * Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
 * IEEE Symposium on Interactive Ray Tracing 2007, section 3: instead of
 * evaluating the SAH at every primitive, drop the centroids into K equal
 * bins along an axis of the node's centroid bounds, keep a box and a count
 * per bin, and evaluate the K-1 planes between bins with one sweep from
 * each side. One pass over the references per axis set, then one in-place
 * partition pass: O(N) per level, O(N log N) in all.
 *
 * Knobs: bins = K (2..256) and axes = 1 (only the axis of greatest centroid
 * extent, as the lecture describes) or 3 (all axes, the better plane).
 * Near the root the binning pass is split across threads; the per-chunk
 * bins are merged with min/max and integer sums, which are exact, so the
 * chosen plane does not depend on the thread count.
 */
#include <stdlib.h>
#include <string.h>

#include "build_common.h"

#define BINS_MAX 256
/* References per chunk of the parallel binning pass. */
#define BIN_CHUNK 16384

/* Bins of up to three axes. The box is kept as two float[4] so that the
 * grow step is two 4-wide min/max operations. */
typedef struct {
    float lo[4], hi[4];
} bin_box;

typedef struct {
    bin_box box[3][BINS_MAX];
    uint32_t count[3][BINS_MAX];
} bin_set;

/* Which axes to bin and how centroids map to bins on each. */
typedef struct {
    int axis_count;
    int axis[3];
    float cmin[3];
    float scale[3]; /* bins per unit of centroid coordinate */
    int bins;
} bin_plan;

static inline int bin_index(float c, float cmin, float scale, int last)
{
    /* c >= cmin, so f >= 0; f <= bins (times 1 + a few ulps) by construction. */
    int b = (int)((c - cmin) * scale);
    return b < last ? b : last;
}

static void clear_bins(bin_set *s, const bin_plan *p)
{
    for (int k = 0; k < p->axis_count; k++) {
        memset(s->count[k], 0, (size_t)p->bins * sizeof(uint32_t));
        for (int i = 0; i < p->bins; i++)
            for (int j = 0; j < 4; j++) s->box[k][i].lo[j] = INFINITY, s->box[k][i].hi[j] = -INFINITY;
    }
}

static inline void grow_bin(bin_box *b, const bvh_ref *r)
{
    for (int j = 0; j < 3; j++) {
        b->lo[j] = minf(b->lo[j], r->lo[j]);
        b->hi[j] = maxf(b->hi[j], r->hi[j]);
    }
}

static void bin_range(const bvh_ref *refs, size_t begin, size_t end, const bin_plan *p, bin_set *s)
{
    int last = p->bins - 1;
    if (p->axis_count == 3) {
        for (size_t i = begin; i < end; i++) {
            const bvh_ref *r = &refs[i];
            for (int k = 0; k < 3; k++) {
                int b = bin_index(bvh_ref_centroid(r, k), p->cmin[k], p->scale[k], last);
                s->count[k][b]++;
                grow_bin(&s->box[k][b], r);
            }
        }
        return;
    }
    for (size_t i = begin; i < end; i++) {
        const bvh_ref *r = &refs[i];
        for (int k = 0; k < p->axis_count; k++) {
            int a = p->axis[k];
            int b = bin_index(bvh_ref_centroid(r, a), p->cmin[k], p->scale[k], last);
            s->count[k][b]++;
            grow_bin(&s->box[k][b], r);
        }
    }
}

typedef struct {
    const bvh_ref *refs;
    size_t first;
    const bin_plan *plan;
    bin_set *sets; /* one per thread */
} bin_job;

static void bin_chunk(void *p, size_t begin, size_t end, int thread)
{
    bin_job *j = p;
    bin_range(j->refs, j->first + begin, j->first + end, j->plan, &j->sets[thread]);
}

static box3 bin_to_box(const bin_box *b)
{
    box3 r = {{b->lo[0], b->lo[1], b->lo[2]}, {b->hi[0], b->hi[1], b->hi[2]}};
    return r;
}

/* Sets up the axes worth binning: those with a positive, finite centroid
 * extent and a finite bin scale. */
static void plan_bins(const bvh_build *ctx, const bvh_task *t, bin_plan *p)
{
    vec3 ext = box3_extent(t->cbounds);
    int order[3] = {0, 1, 2}, n = 3;
    if (ctx->opts.axes == 1) {
        order[0] = v3_max_axis(ext);
        n = 1;
    }
    p->bins = ctx->opts.bins;
    p->axis_count = 0;
    for (int i = 0; i < n; i++) {
        int a = order[i];
        float e = v3_get(ext, a);
        float scale = (float)p->bins / e;
        if (!(e > 0.0f) || !isfinite(scale)) continue;
        p->axis[p->axis_count] = a;
        p->cmin[p->axis_count] = v3_get(t->cbounds.min, a);
        p->scale[p->axis_count] = scale;
        p->axis_count++;
    }
}

static void binned_split(bvh_build *ctx, const bvh_task *t, int threads, bvh_split *out)
{
    out->left_count = 0;
    if (bvh_task_forced(t)) {
        bvh_split_median(ctx, t, out);
        return;
    }
    bin_plan plan;
    plan_bins(ctx, t, &plan);
    if (plan.axis_count == 0) return; /* all centroids equal: leaf, or the driver's median */

    /* 1. Bin the centroids. Subtree tasks run concurrently and bin into
     * their own stack copy; only the top splits (one caller, all threads
     * helping) use the shared per-thread sets. */
    bin_set local, *sets = &local;
    if (threads > 1 && t->count >= 2 * BIN_CHUNK) {
        int nsets = threads;
        sets = ctx->data;
        for (int i = 0; i < nsets; i++) clear_bins(&sets[i], &plan);
        bin_job job = {ctx->refs, t->first, &plan, sets};
        accel_parallel_for(t->count, BIN_CHUNK, threads, bin_chunk, &job);
        for (int i = 1; i < nsets; i++)
            for (int k = 0; k < plan.axis_count; k++)
                for (int b = 0; b < plan.bins; b++) {
                    sets[0].count[k][b] += sets[i].count[k][b];
                    for (int j = 0; j < 3; j++) {
                        sets[0].box[k][b].lo[j] = minf(sets[0].box[k][b].lo[j], sets[i].box[k][b].lo[j]);
                        sets[0].box[k][b].hi[j] = maxf(sets[0].box[k][b].hi[j], sets[i].box[k][b].hi[j]);
                    }
                }
    } else {
        clear_bins(&sets[0], &plan);
        bin_range(ctx->refs, t->first, (size_t)t->first + t->count, &plan, &sets[0]);
    }
    const bin_set *s = &sets[0];

    /* 2. Sweep: right-to-left suffix areas, then left-to-right costs. The
     * plane after bin i sends bins 0..i left. Ties keep the first plane
     * found, so the choice is unique. */
    double best = INFINITY;
    int best_k = -1, best_bin = -1;
    for (int k = 0; k < plan.axis_count; k++) {
        double right_area[BINS_MAX];
        uint32_t right_count[BINS_MAX];
        box3 acc = box3_empty();
        uint32_t cnt = 0;
        for (int i = plan.bins - 1; i >= 1; i--) {
            acc = box3_union(acc, bin_to_box(&s->box[k][i]));
            cnt += s->count[k][i];
            right_area[i] = bvh_half_area(acc);
            right_count[i] = cnt;
        }
        acc = box3_empty();
        cnt = 0;
        for (int i = 0; i < plan.bins - 1; i++) {
            acc = box3_union(acc, bin_to_box(&s->box[k][i]));
            cnt += s->count[k][i];
            if (cnt == 0 || right_count[i + 1] == 0) continue;
            double cost = bvh_half_area(acc) * cnt + right_area[i + 1] * right_count[i + 1];
            if (cost < best) {
                best = cost;
                best_k = k;
                best_bin = i;
            }
        }
    }
    if (best_k < 0 || !bvh_split_pays(ctx, t, best)) return;

    /* 3. Partition in place (Hoare-style), growing the children's centroid
     * bounds on the way; their boxes come from the bins. */
    int a = plan.axis[best_k], last = plan.bins - 1;
    float cmin = plan.cmin[best_k], scale = plan.scale[best_k];
    bvh_ref *r = ctx->refs;
    uint32_t i = t->first, j = t->first + t->count; /* [i, j) unclassified */
    box3 lc = box3_empty(), rc = box3_empty();
    while (i < j) {
        if (bin_index(bvh_ref_centroid(&r[i], a), cmin, scale, last) <= best_bin) {
            lc = box3_grow(lc, bvh_ref_center(&r[i]));
            i++;
        } else {
            j--;
            bvh_ref tmp = r[i];
            r[i] = r[j];
            r[j] = tmp;
            rc = box3_grow(rc, bvh_ref_center(&r[j]));
        }
    }
    box3 lb = box3_empty(), rb = box3_empty();
    for (int b = 0; b <= best_bin; b++) lb = box3_union(lb, bin_to_box(&s->box[best_k][b]));
    for (int b = best_bin + 1; b < plan.bins; b++) rb = box3_union(rb, bin_to_box(&s->box[best_k][b]));
    out->left_count = i - t->first;
    out->left = lb;
    out->right = rb;
    out->left_c = lc;
    out->right_c = rc;
}

int bvh_build_binned(bvh_build *ctx, accel_error *err)
{
    int sets = ctx->threads > 1 ? ctx->threads : 1;
    bin_set *bins = bvh_alloc_array((size_t)sets, sizeof(bin_set));
    if (!bins) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for %d bin sets", sets);
    ctx->data = bins;
    ctx->split = binned_split;
    bvh_build_tree(ctx);
    free(bins);
    ctx->data = NULL;
    return 0;
}
