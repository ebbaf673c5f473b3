/*
 * build_sah.c - exact SAH construction with a full sweep (build=sah).
 *
 * The quality reference: every node considers every split "first k
 * primitives left, the rest right" in centroid order on each of the three
 * axes, and takes the one with the least A_L*N_L + A_R*N_R (MacDonald and
 * Booth, "Heuristics for ray tracing using space subdivision", The Visual
 * Computer 6(3), 1990; the sweep as in Wald, Boulos and Shirley, "Ray
 * Tracing Deformable Scenes Using Dynamic Bounding Volume Hierarchies",
 * ACM TOG 26(1), 2007).
 *
 * To avoid sorting at every node, the references are sorted once per axis
 * (an LSD radix sort of the centroids, ties by reference index), and each
 * split keeps the three lists sorted with stable partitions: O(N) per
 * level, O(N log N) in all, but with three sweeps and random access to the
 * reference boxes it is several times slower than binning.
 *
 * Task ranges here are positions in the three order lists (the references
 * themselves stay put until the end, when they are permuted into the
 * leaf order of list 0). Scratch arrays are indexed by position or by
 * reference, so concurrent subtree tasks never share an entry.
 */
#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "split_common.h"

typedef struct {
    uint32_t *order[3]; /* reference indices, sorted by centroid per axis within each task */
    float *key[3];      /* centroid of each reference per axis */
    double *area[3];    /* sweep scratch by position: area of the right part */
    uint32_t *tmp[3];   /* stable partition scratch by position */
    uint8_t *side;      /* by reference: 1 when it goes left */
} sweep_data;

/* ---- sorting ---------------------------------------------------------------- */

/* An unsigned key with the order of the float (Terdiman's radix trick):
 * negative floats flip all bits, positive ones set the sign bit. */
static inline uint32_t sortable(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

/* Sorts references by centroid on one axis: an LSD radix sort of
 * (key << 32 | index), 8 bits a pass over the key half. Stable, so equal
 * centroids stay in index order. */
static void sort_axis(const float *key, uint32_t n, uint64_t *a, uint64_t *b, uint32_t *out)
{
    for (uint32_t i = 0; i < n; i++) a[i] = (uint64_t)sortable(key[i]) << 32 | i;
    for (int pass = 0; pass < 4; pass++) {
        int shift = 32 + 8 * pass;
        uint32_t hist[256] = {0};
        for (uint32_t i = 0; i < n; i++) hist[(a[i] >> shift) & 255]++;
        uint32_t sum = 0;
        for (int k = 0; k < 256; k++) {
            uint32_t c = hist[k];
            hist[k] = sum;
            sum += c;
        }
        for (uint32_t i = 0; i < n; i++) b[hist[(a[i] >> shift) & 255]++] = a[i];
        uint64_t *t = a;
        a = b;
        b = t;
    }
    for (uint32_t i = 0; i < n; i++) out[i] = (uint32_t)a[i];
}

typedef struct {
    sweep_data *d;
    uint32_t n;
    uint64_t *scratch; /* 2n per axis */
} sort_job;

static void sort_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    sort_job *j = p;
    for (size_t a = begin; a < end; a++)
        sort_axis(j->d->key[a], j->n, j->scratch + 2 * (size_t)j->n * a,
                  j->scratch + 2 * (size_t)j->n * a + j->n, j->d->order[a]);
}

/* ---- the split ---------------------------------------------------------------- */

typedef struct {
    bvh_build_ctx *ctx;
    const bvh_task *t;
    double cost[3];
    uint32_t at[3];   /* best split position (left count) per axis */
    int skip;         /* axis whose list is already in order (partition jobs) */
} sweep_job;

/* One axis: suffix areas right to left, then prefix costs left to right. */
static void sweep_axis(sweep_job *j, int a)
{
    const sweep_data *d = j->ctx->data;
    const bvh_ref *refs = j->ctx->refs;
    uint32_t n = j->t->count;
    const uint32_t *o = d->order[a] + j->t->first;
    double *right = d->area[a] + j->t->first;
    box3 acc = box3_empty();
    for (uint32_t k = n - 1; k >= 1; k--) {
        acc = box3_union(acc, bvh_ref_box(&refs[o[k]]));
        right[k] = bvh_half_area(acc);
    }
    acc = box3_empty();
    double best = INFINITY;
    uint32_t at = 0;
    for (uint32_t k = 1; k < n; k++) {
        acc = box3_union(acc, bvh_ref_box(&refs[o[k - 1]]));
        double cost = bvh_half_area(acc) * k + right[k] * (n - k);
        if (cost < best) {
            best = cost;
            at = k;
        }
    }
    j->cost[a] = best;
    j->at[a] = at;
}

static void sweep_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    for (size_t a = begin; a < end; a++) sweep_axis(p, (int)a);
}

/* Stable partition of one list by side[]: left references keep their
 * order at the front, right ones theirs behind them. */
static void partition_axis(sweep_job *j, int b)
{
    sweep_data *d = j->ctx->data;
    uint32_t f = j->t->first, n = j->t->count;
    uint32_t *o = d->order[b] + f, *tmp = d->tmp[b] + f;
    uint32_t l = 0, r = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t x = o[k];
        if (d->side[x])
            o[l++] = x;
        else
            tmp[r++] = x;
    }
    memcpy(o + l, tmp, (size_t)r * sizeof *o);
}

static void partition_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    sweep_job *j = p;
    for (size_t b = begin; b < end; b++)
        if ((int)b != j->skip) partition_axis(j, (int)b);
}

static void list_bounds(const bvh_build_ctx *ctx, const uint32_t *o, uint32_t n, box3 *b, box3 *c)
{
    *b = box3_empty();
    *c = box3_empty();
    for (uint32_t k = 0; k < n; k++) {
        const bvh_ref *r = &ctx->refs[o[k]];
        *b = box3_union(*b, bvh_ref_box(r));
        *c = box3_grow(*c, bvh_ref_center(r));
    }
}

static void sweep_split(bvh_build_ctx *ctx, const bvh_task *t, int threads, bvh_split *out)
{
    sweep_data *d = ctx->data;
    uint32_t n = t->count, f = t->first;
    int par = threads > 1 && n >= 8192;
    sweep_job job;
    memset(&job, 0, sizeof job);
    job.ctx = ctx;
    job.t = t;
    int axis, forced = bvh_task_forced(t);
    uint32_t at;
    if (forced) {
        /* Object median by rank on the axis of largest centroid extent. */
        float ext[3];
        for (int a = 0; a < 3; a++) ext[a] = d->key[a][d->order[a][f + n - 1]] - d->key[a][d->order[a][f]];
        axis = (ext[0] >= ext[1] && ext[0] >= ext[2]) ? 0 : (ext[1] >= ext[2] ? 1 : 2);
        at = n / 2;
    } else {
        if (par)
            accel_parallel_for(3, 1, threads < 3 ? threads : 3, sweep_chunk, &job);
        else
            for (int a = 0; a < 3; a++) sweep_axis(&job, a);
        axis = 0;
        for (int a = 1; a < 3; a++)
            if (job.cost[a] < job.cost[axis]) axis = a;
        at = job.at[axis];
        assert(at > 0 && at < n);
        if (!bvh_split_pays(ctx, t, job.cost[axis])) {
            out->left_count = 0;
            return;
        }
    }
    const uint32_t *o = d->order[axis] + f;
    for (uint32_t k = 0; k < n; k++) d->side[o[k]] = k < at;
    job.skip = axis;
    if (par)
        accel_parallel_for(3, 1, threads < 3 ? threads : 3, partition_chunk, &job);
    else
        partition_chunk(&job, 0, 3, 0);
    out->left_count = at;
    list_bounds(ctx, o, at, &out->left, &out->left_c);
    list_bounds(ctx, o + at, n - at, &out->right, &out->right_c);
    /* A forced median may still end as a leaf (the lists stay valid: each
     * holds the same references in its own order). */
    if (forced && !bvh_split_pays(ctx, t, bvh_split_sum(out, n))) out->left_count = 0;
}

int bvh_build_sah(bvh_build_ctx *ctx, accel_error *err)
{
    uint32_t n = ctx->ref_count;
    sweep_data d;
    memset(&d, 0, sizeof d);
    int ok = 1;
    for (int a = 0; a < 3; a++) {
        d.order[a] = bvh_alloc_array(n, sizeof(uint32_t));
        d.key[a] = bvh_alloc_array(n, sizeof(float));
        d.area[a] = bvh_alloc_array(n, sizeof(double));
        d.tmp[a] = bvh_alloc_array(n, sizeof(uint32_t));
        ok = ok && d.order[a] && d.key[a] && d.area[a] && d.tmp[a];
    }
    d.side = bvh_alloc_array(n, 1);
    /* 2n sort records per axis, all three axes at once. */
    uint64_t *scratch = bvh_alloc_array(n, 6 * sizeof(uint64_t));
    bvh_ref *sorted = bvh_alloc_array(n, sizeof(bvh_ref));
    int rc = 0;
    if (!ok || !d.side || !scratch || !sorted) {
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for the SAH sweep of %u references", n);
    } else {
        for (uint32_t i = 0; i < n; i++)
            for (int a = 0; a < 3; a++) d.key[a][i] = bvh_ref_centroid(&ctx->refs[i], a);
        sort_job sj = {&d, n, scratch};
        accel_parallel_for(3, 1, ctx->threads < 3 ? ctx->threads : 3, sort_chunk, &sj);
        free(scratch);
        scratch = NULL;
        ctx->data = &d;
        ctx->split = sweep_split;
        bvh_build_tree(ctx);
        ctx->data = NULL;
        /* Leaf order: list 0 (every list holds the same set per leaf). */
        for (uint32_t i = 0; i < n; i++) sorted[i] = ctx->refs[d.order[0][i]];
        memcpy(ctx->refs, sorted, (size_t)n * sizeof(bvh_ref));
    }
    free(scratch);
    free(sorted);
    for (int a = 0; a < 3; a++) {
        free(d.order[a]);
        free(d.key[a]);
        free(d.area[a]);
        free(d.tmp[a]);
    }
    free(d.side);
    return rc;
}
