/*
 * build_binned.c - binned SAH construction (build=binned).
 *
 * Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
 * IEEE Symposium on Interactive Ray Tracing 2007: instead of
 * evaluating the SAH at every primitive, drop the centroids into K equal
 * bins along an axis of the node's centroid bounds, keep a box and a count
 * per bin, and evaluate the K-1 planes between bins with one sweep from
 * each side. One pass over the references per axis set, then one in-place
 * partition pass: O(N) per level, O(N log N) in all.
 *
 * Knobs: bins = K (2..256) and axes = 1 (only the axis of greatest centroid
 * extent, as the lecture describes) or 3 (all axes, the better plane). A
 * bin holding a large share of a big node's centroids is binned again
 * (refine_cluster, below: the teapot in a stadium).
 * Near the root the binning pass is split across threads; the per-chunk
 * bins are merged with min/max and integer sums, which are exact, so the
 * chosen plane does not depend on the thread count.
 */
#include <stdlib.h>
#include <string.h>

#include "build_binned_view.h"
#include "split_common.h"

#define BINS_MAX 256
/* Tasks of at least 2 * BIN_CHUNK references are binned by all threads. */
#define BIN_CHUNK 16384

/* ---- bins ------------------------------------------------------------------- */

/* A bin's box. With AVX, lo and -hi side by side in one 256-bit vector, so
 * that one min grows both halves: a bin update is one load, one min and
 * one store instead of two of each (max(hi, x) = -min(-hi, -x) exactly;
 * binned references are finite). */
#if BVH_SSE && defined(__AVX__)
typedef struct {
    __m256 v; /* lanes 0-3: lo, lanes 4-7: -hi */
} bin_box;

static inline void bin_box_clear(bin_box *b) { b->v = _mm256_set1_ps(INFINITY); }
static inline void bin_box_union(bin_box *b, const bin_box *o) { b->v = _mm256_min_ps(b->v, o->v); }
static inline void bin_box_of(bin_box *b, const box4 *x)
{
    b->v = _mm256_insertf128_ps(_mm256_castps128_ps256(x->lo), _mm_xor_ps(x->hi, _mm_set1_ps(-0.0f)), 1);
}
static inline box4 bin_box_get(const bin_box *b)
{
    box4 r = {_mm256_castps256_ps128(b->v), _mm_xor_ps(_mm256_extractf128_ps(b->v, 1), _mm_set1_ps(-0.0f))};
    return r;
}
#else
typedef box4 bin_box;
static inline void bin_box_clear(bin_box *b) { box4_clear(b); }
static inline void bin_box_union(bin_box *b, const bin_box *o) { box4_union(b, o); }
static inline void bin_box_of(bin_box *b, const box4 *x) { *b = *x; }
static inline box4 bin_box_get(const bin_box *b) { return *b; }
#endif

/* Bins of all three axes. */
typedef struct {
    bin_box box[3][BINS_MAX];
    uint32_t count[3][BINS_MAX];
} bin_set;

/* The non-empty bins of one axis in bin order: the only places a plane
 * can separate anything (a plane after an empty bin partitions like the
 * plane after the non-empty bin before it, at the same cost, and the
 * sweep keeps the first plane of equal cost, which is that one). */
typedef struct {
    box4 box;
    uint32_t count;
    int bin;
    int sub; /* a sub-bin of the refined bin (refine_cluster), -1: the whole bin */
} bin_group;

static void clear_bins(bin_set *s, const bin_plan *p)
{
    for (int k = 0; k < p->axis_count; k++) {
        int a = p->axis[k];
        memset(s->count[a], 0, (size_t)p->bins * sizeof(uint32_t));
        for (int i = 0; i < p->bins; i++) bin_box_clear(&s->box[a][i]);
    }
}

/* One reference (its view v, its box as a bin box b) into its bin on axis a. */
static inline void bin_add(bin_set *s, int a, const ref_view *v, const bin_box *b)
{
    s->count[a][v->bin[a]]++;
    bin_box_union(&s->box[a][v->bin[a]], b);
}

/* src's bins into dst's (min, max and integer sums: exact in any order). */
static void merge_bins(bin_set *dst, const bin_set *src, const bin_plan *p)
{
    for (int k = 0; k < p->axis_count; k++) {
        int a = p->axis[k];
        for (int b = 0; b < p->bins; b++) {
            dst->count[a][b] += src->count[a][b];
            bin_box_union(&dst->box[a][b], &src->box[a][b]);
        }
    }
}

static void bin_range(const bvh_ref *refs, size_t begin, size_t end, const bin_plan *p, bin_set *s)
{
    ref_view v, w;
    bin_box vb, wb;
    size_t i = begin;
    if (p->axis_count == 3 && end - begin >= 8 * (size_t)p->bins) {
        /* Neighbouring references of a mesh mostly fall in the same bin, so
         * each bin update waited on the previous one through memory. Odd
         * references go to a second set, merged after the pairs (the same
         * bins exactly); build time about -5% on bunny. At most one
         * reference is left for the loop below. */
        static _Thread_local bin_set odd;
        clear_bins(&odd, p);
        for (; i + 1 < end; i += 2) {
            view_ref(p, &refs[i], &v);
            view_ref(p, &refs[i + 1], &w);
            bin_box_of(&vb, &v.box), bin_box_of(&wb, &w.box);
            for (int a = 0; a < 3; a++) bin_add(s, a, &v, &vb), bin_add(&odd, a, &w, &wb);
        }
        merge_bins(s, &odd, p);
    }
    if (p->axis_count == 3) { /* the common case, with constant axes */
        for (; i < end; i++) {
            view_ref(p, &refs[i], &v);
            bin_box_of(&vb, &v.box);
            for (int a = 0; a < 3; a++) bin_add(s, a, &v, &vb);
        }
        return;
    }
    for (; i < end; i++) {
        view_ref(p, &refs[i], &v);
        bin_box_of(&vb, &v.box);
        for (int k = 0; k < p->axis_count; k++) bin_add(s, p->axis[k], &v, &vb);
    }
}

/* Parallel binning: the task's references in BIN_SPLITS * threads equal
 * chunks, each binned into its own set, whichever thread takes it; the
 * sets are then merged in chunk order. */
#define BIN_SPLITS 4

typedef struct {
    const bvh_ref *refs;
    size_t first, count, chunks;
    const bin_plan *plan;
    bin_set *sets; /* one per chunk */
} bin_job;

static void bin_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    bin_job *j = p;
    for (size_t c = begin; c < end; c++) {
        size_t lo = j->count * c / j->chunks, hi = j->count * (c + 1) / j->chunks;
        clear_bins(&j->sets[c], j->plan);
        bin_range(j->refs, j->first + lo, j->first + hi, j->plan, &j->sets[c]);
    }
}

/* Sets up the axes worth binning: those with a positive, finite centroid
 * extent and a finite bin scale. */
static void plan_bins(const bvh_build_ctx *ctx, const bvh_task *t, bin_plan *p)
{
    vec3 ext = box3_extent(t->cbounds);
    int order[3] = {0, 1, 2}, n = 3;
    if (ctx->opts.axes == 1) {
        order[0] = v3_max_axis(ext);
        n = 1;
    }
    p->bins = ctx->opts.bins;
    p->axis_count = 0;
    for (int a = 0; a < 4; a++) p->cmin[a] = 0.0f, p->scale[a] = 0.0f;
    for (int i = 0; i < n; i++) {
        int a = order[i];
        float e = v3_get(ext, a);
        float scale = (float)p->bins / e;
        if (!(e > 0.0f) || !isfinite(scale)) continue;
        p->axis[p->axis_count++] = a;
        p->cmin[a] = v3_get(t->cbounds.min, a);
        p->scale[a] = scale;
    }
}

/* Large tasks: bin every reference (with all threads near the root), then
 * keep the non-empty bins. */
static void groups_from_bins(bvh_build_ctx *ctx, const bvh_task *t, int threads, const bin_plan *plan,
                             bin_group (*g)[BINS_MAX], int *ng)
{
    /* Subtree tasks run concurrently and bin into their own stack copy; only
     * the top splits (one caller, all threads helping) use the shared sets. */
    bin_set local, *sets = &local;
    if (threads > 1 && t->count >= 2 * BIN_CHUNK) {
        sets = ctx->data;
        size_t chunks = (size_t)threads * BIN_SPLITS;
        bin_job job = {ctx->refs, t->first, t->count, chunks, plan, sets};
        accel_parallel_for(chunks, 1, threads, bin_chunk, &job);
        for (size_t c = 1; c < chunks; c++) merge_bins(&sets[0], &sets[c], plan);
    } else {
        clear_bins(sets, plan);
        bin_range(ctx->refs, t->first, (size_t)t->first + t->count, plan, sets);
    }
    for (int k = 0; k < plan->axis_count; k++) {
        int a = plan->axis[k];
        ng[k] = 0;
        /* Branch-free: every bin is written to the next slot, which only a
         * non-empty bin keeps (an empty one is a coin flip to predict). */
        int m = 0;
        for (int b = 0; b < plan->bins; b++) {
            bin_group *x = &g[k][m];
            x->box = bin_box_get(&sets->box[a][b]);
            x->count = sets->count[a][b];
            x->bin = b;
            x->sub = -1;
            m += sets->count[a][b] != 0;
        }
        ng[k] = m;
    }
}

/* Small tasks (fewer references than bins): the same groups without
 * clearing and sweeping all K bins. A bitmask records which bins are
 * occupied; a bin is initialized when first touched, and the groups are
 * read off the set bits in order. Bit-identical to groups_from_bins. */
static void groups_sparse(const bvh_build_ctx *ctx, const bvh_task *t, const bin_plan *plan,
                          bin_group (*g)[BINS_MAX], int *ng)
{
    const bvh_ref *refs = ctx->refs + t->first;
    uint32_t n = t->count;
    ref_view v[BINS_MAX];
    for (uint32_t i = 0; i < n; i++) view_ref(plan, &refs[i], &v[i]);
    int words = (plan->bins + 63) / 64;
    for (int k = 0; k < plan->axis_count; k++) {
        int a = plan->axis[k];
        uint64_t used[BINS_MAX / 64] = {0};
        box4 box[BINS_MAX];
        uint32_t count[BINS_MAX];
        /* Two branch-free passes (clear each touched bin, then fill it)
         * instead of a branch on "first reference of its bin", which is a
         * coin flip for the branch predictor. */
        for (uint32_t i = 0; i < n; i++) {
            int x = v[i].bin[a];
            used[x >> 6] |= (uint64_t)1 << (x & 63);
            box4_clear(&box[x]);
            count[x] = 0;
        }
        for (uint32_t i = 0; i < n; i++) {
            int x = v[i].bin[a];
            box4_union(&box[x], &v[i].box);
            count[x]++;
        }
        ng[k] = 0;
        for (int w = 0; w < words; w++)
            for (uint64_t m = used[w]; m; m &= m - 1) {
                int x = 64 * w + __builtin_ctzll(m);
                bin_group *gr = &g[k][ng[k]++];
                gr->box = box[x];
                gr->count = count[x];
                gr->bin = x;
                gr->sub = -1;
            }
    }
}

/* Swaps two references (a == b allowed) with whole-reference vector loads
 * and stores. A plain struct swap was compiled to 8-byte stores that the
 * next iteration reloads as one 32-byte vector: the failed store
 * forwarding stalled that load, the partition's hottest instruction (perf:
 * 16% of the binned split on bunny). */
static inline void ref_swap(bvh_ref *a, bvh_ref *b)
{
#if !BVH_SSE /* -DBVH_NO_SIMD or no SSE2: the plain swap */
    bvh_ref x = *a;
    *a = *b;
    *b = x;
#elif defined(__AVX__)
    __m256i x = _mm256_loadu_si256((const __m256i *)a), y = _mm256_loadu_si256((const __m256i *)b);
    _mm256_storeu_si256((__m256i *)a, y);
    _mm256_storeu_si256((__m256i *)b, x);
#else
    __m128i x0 = _mm_loadu_si128((const __m128i *)a), x1 = _mm_loadu_si128((const __m128i *)a + 1);
    __m128i y0 = _mm_loadu_si128((const __m128i *)b), y1 = _mm_loadu_si128((const __m128i *)b + 1);
    _mm_storeu_si128((__m128i *)a, y0);
    _mm_storeu_si128((__m128i *)a + 1, y1);
    _mm_storeu_si128((__m128i *)b, x0);
    _mm_storeu_si128((__m128i *)b + 1, x1);
#endif
}

/* The sub-plan of bin `bin` on axis a: the bin's extent cut in plan->bins. */
static void sub_plan(const bin_plan *plan, int a, int bin, bin_plan *sp)
{
    *sp = *plan;
    sp->axis_count = 1;
    sp->axis[0] = a;
    for (int k = 0; k < 4; k++) sp->scale[k] = 0.0f, sp->cmin[k] = 0.0f;
    sp->cmin[a] = plan->cmin[a] + (float)bin / plan->scale[a];
    sp->scale[a] = plan->scale[a] * (float)plan->bins;
}

/*
 * The partition in scalar code, for any plane the sweep prices: a
 * reference goes left when its bin on `axis` is below `bin`, or is `bin`
 * with its sub-bin (sub_plan, the same view_ref as refine_cluster's) at
 * most `sub`; sub = bins - 1 sends the whole bin left. The partition of
 * builds without SSE, and of planes inside a refined bin (rare: the top of
 * clustered scenes).
 */
static uint32_t partition_scalar(bvh_ref *r, uint32_t n, const bin_plan *plan, int axis, int bin,
                                 int sub, box3 *lc, box3 *rc)
{
    bin_plan sp;
    sub_plan(plan, axis, bin, &sp);
    *lc = box3_empty();
    *rc = box3_empty();
    uint32_t l = 0;
    for (uint32_t i = 0; i < n; i++) {
        ref_view v, w;
        view_ref(plan, &r[i], &v);
        int left = v.bin[axis] < bin;
        if (v.bin[axis] == bin) {
            left = 1;
            if (sub < plan->bins - 1) {
                view_ref(&sp, &r[i], &w);
                left = w.bin[axis] <= sub;
            }
        }
#if BVH_SSE
        float c4[4];
        _mm_storeu_ps(c4, v.c);
        vec3 c = v3(c4[0], c4[1], c4[2]);
#else
        vec3 c = v.c;
#endif
        if (left)
            *lc = box3_grow(*lc, c);
        else
            *rc = box3_grow(*rc, c);
        ref_swap(r + i, r + l);
        l += (uint32_t)left;
    }
    return l;
}

/*
 * Branch-free Lomuto partition: every reference is swapped with the first
 * right-side slot, and that slot advances only for a left reference.
 * Which side a reference goes to is a coin flip for the branch predictor;
 * two 32-byte copies per reference cost less than a misprediction.
 */
static uint32_t partition(bvh_ref *r, uint32_t n, const bin_plan *plan, int axis, int best_bin,
                          box3 *lc, box3 *rc)
{
#if BVH_SSE
    uint32_t l = 0;
    __m128 llo = _mm_set1_ps(INFINITY), lhi = _mm_set1_ps(-INFINITY);
    __m128 rlo = llo, rhi = lhi;
#ifdef __AVX__
    /* The side without the bin's integer: view_ref's bin is the truncation
     * of a clamped f in [0, bins-1], so bin <= best_bin exactly when
     * f < best_bin + 1. Comparing f and spreading lane `axis` to every lane
     * gives the mask in registers, where the integer bins went through the
     * stack and back (a store forwarded to a load on every reference). */
    const __m128 cmin = _mm_load_ps(plan->cmin), scale = _mm_load_ps(plan->scale);
    const __m128 top = _mm_set1_ps((float)(plan->bins - 1));
    const __m128 limit = _mm_set1_ps((float)best_bin + 1.0f);
    const __m128i lane = _mm_set1_epi32(axis);
#endif
    for (uint32_t i = 0; i < n; i++) {
#ifdef __AVX__
        box4 box;
        __m128 c, f = view_coords(&r[i], cmin, scale, top, &box, &c);
        __m128 m = _mm_permutevar_ps(_mm_cmplt_ps(f, limit), lane);
        int left = _mm_movemask_ps(m) & 1;
#else
        ref_view v;
        view_ref(plan, &r[i], &v);
        int left = v.bin[axis] <= best_bin;
        __m128 c = v.c;
        __m128 m = _mm_castsi128_ps(_mm_set1_epi32(-left));
#endif
        /* grow the chosen side's centroid box: min/max with c, or with +-inf */
#ifdef __SSE4_1__
        const __m128 inf = _mm_set1_ps(INFINITY), ninf = _mm_set1_ps(-INFINITY);
        llo = _mm_min_ps(llo, _mm_blendv_ps(inf, c, m));
        rlo = _mm_min_ps(rlo, _mm_blendv_ps(c, inf, m));
        lhi = _mm_max_ps(lhi, _mm_blendv_ps(ninf, c, m));
        rhi = _mm_max_ps(rhi, _mm_blendv_ps(c, ninf, m));
#else
        __m128 cl = _mm_or_ps(_mm_and_ps(m, c), _mm_andnot_ps(m, _mm_set1_ps(INFINITY)));
        __m128 cr = _mm_or_ps(_mm_andnot_ps(m, c), _mm_and_ps(m, _mm_set1_ps(INFINITY)));
        llo = _mm_min_ps(llo, cl);
        rlo = _mm_min_ps(rlo, cr);
        cl = _mm_or_ps(_mm_and_ps(m, c), _mm_andnot_ps(m, _mm_set1_ps(-INFINITY)));
        cr = _mm_or_ps(_mm_andnot_ps(m, c), _mm_and_ps(m, _mm_set1_ps(-INFINITY)));
        lhi = _mm_max_ps(lhi, cl);
        rhi = _mm_max_ps(rhi, cr);
#endif
        ref_swap(r + i, r + l);
        l += (uint32_t)left;
    }
    box4 L = {llo, lhi}, R = {rlo, rhi};
    *lc = box4_to_box3(&L);
    *rc = box4_to_box3(&R);
    return l;
#else
    return partition_scalar(r, n, plan, axis, best_bin, plan->bins - 1, lc, rc);
#endif
}

/*
 * Clustered centroids (Haines' "teapot in a stadium"): when one bin of an
 * axis holds most of a large node's references, every plane the K bins
 * offer either leaves the cluster whole among far larger primitives or
 * cuts through it where a bin boundary happens to fall: with 16 bins over
 * teapot_stadium's 8000 units, the root's best plane kept the first tier
 * of the stands with the teapot, and the next one cut the teapot in half,
 * so rays to its near half tested the 36 floor triangles under it first
 * (REPORT.md's heatmaps showed it; the full sweep, build=sah, kept the
 * teapot whole). Such a bin is binned again into K sub-bins of its own
 * extent, and the sweep sees the planes between them too: more
 * candidates, never a worse greedy choice, for one more pass over the
 * node's references. Only nodes of at least REFINE_MIN references with
 * more than a quarter of them, and more than four times a bin's share, in
 * one bin qualify (so never with 2 or 4 bins): the scanned meshes, the
 * soups and slivers have none, and their trees are the ones before, bit
 * for bit (bvh/README.md, "Clustered centroids").
 */
#define REFINE_MIN 1024

/* If axis k's fullest group holds more than a quarter of t's references
 * and four times a bin's share, the groups of that axis with its bin
 * replaced by its non-empty sub-bins, in order. */
static void refine_cluster(const bvh_build_ctx *ctx, const bvh_task *t, const bin_plan *plan, int k,
                          bin_group *g, int *ng)
{
    if (t->count < REFINE_MIN || *ng < 1 || *ng - 1 + plan->bins > BINS_MAX) return;
    int c = 0;
    for (int i = 1; i < *ng; i++) c = g[i].count > g[c].count ? i : c;
    /* four times its share of the node and a quarter of it: with 2 or 4
     * bins every node has such a bin, and those are the knob's own study
     * (exp_binning), so they are never refined */
    uint64_t most = g[c].count;
    if (most * 4 <= t->count || most * (uint64_t)plan->bins <= 4ull * t->count) return;
    int a = plan->axis[k], bin = g[c].bin;
    bin_plan sp;
    sub_plan(plan, a, bin, &sp);
    if (!(sp.scale[a] > 0.0f) || !isfinite(sp.scale[a]) || !isfinite(sp.cmin[a])) return;
    box4 box[BINS_MAX];
    uint32_t count[BINS_MAX] = {0};
    for (int i = 0; i < plan->bins; i++) box4_clear(&box[i]);
    const bvh_ref *refs = ctx->refs + t->first;
    for (uint32_t i = 0; i < t->count; i++) {
        ref_view v, w;
        view_ref(plan, &refs[i], &v);
        if (v.bin[a] != bin) continue;
        view_ref(&sp, &refs[i], &w);
        box4_union(&box[w.bin[a]], &w.box);
        count[w.bin[a]]++;
    }
    int subs = 0;
    for (int i = 0; i < plan->bins; i++) subs += count[i] != 0;
    if (subs < 2) return; /* one sub-bin: nothing new to cut */
    /* shift the groups after the cluster to make room, then fill it */
    memmove(&g[c + subs], &g[c + 1], (size_t)(*ng - c - 1) * sizeof *g);
    int m = c;
    for (int i = 0; i < plan->bins; i++) {
        if (!count[i]) continue;
        g[m].box = box[i];
        g[m].count = count[i];
        g[m].bin = bin;
        g[m].sub = i;
        m++;
    }
    *ng += subs - 1;
}

static void binned_split(bvh_build_ctx *ctx, const bvh_task *t, int threads, bvh_split *out)
{
    out->left_count = 0;
    if (bvh_task_forced(t)) {
        bvh_split_median(ctx, t, out);
        if (!bvh_split_pays(ctx, t, bvh_split_sum(out, t->count))) out->left_count = 0;
        return;
    }
    if (bvh_leaf_certain(ctx, t)) return;
    bin_plan plan;
    plan_bins(ctx, t, &plan);
    if (plan.axis_count == 0) return; /* all centroids equal: leaf, or the driver's median */

    /* 1. Bin the centroids: the non-empty bins of each axis, in order. */
    bin_group groups[3][BINS_MAX];
    int ng[3];
    if (t->count < (uint32_t)plan.bins)
        groups_sparse(ctx, t, &plan, groups, ng);
    else
        groups_from_bins(ctx, t, threads, &plan, groups, ng);
    for (int k = 0; k < plan.axis_count; k++) refine_cluster(ctx, t, &plan, k, groups[k], &ng[k]);

    /* 2. Sweep: right-to-left suffix areas, then left-to-right costs. The
     * plane after group i sends groups 0..i left. Ties keep the first plane
     * found, so the choice is unique. */
    vec3 ext = box3_extent(t->bounds);
    float scale = 1.0f / maxf(maxf(ext.x, ext.y), ext.z);
    if (!isfinite(scale)) scale = 0.0f; /* a degenerate or overflowing node: all areas 0 */
#if BVH_SSE
    const __m128 sc = _mm_set1_ps(scale);
#else
    const float sc = scale;
#endif
    float best = INFINITY;
    int best_k = -1, best_g = -1;
    for (int k = 0; k < plan.axis_count; k++) {
        const bin_group *g = groups[k];
        float right_area[BINS_MAX];
        box4 acc;
        box4_clear(&acc);
        for (int i = ng[k] - 1; i >= 1; i--) {
            box4_union(&acc, &g[i].box);
            right_area[i] = box4_scaled_area(&acc, sc);
        }
        box4_clear(&acc);
        uint32_t left = 0;
        for (int i = 0; i < ng[k] - 1; i++) {
            box4_union(&acc, &g[i].box);
            left += g[i].count;
            float cost = box4_scaled_area(&acc, sc) * (float)left +
                         right_area[i + 1] * (float)(t->count - left);
            if (cost < best) {
                best = cost;
                best_k = k;
                best_g = i;
            }
        }
    }
    /* back to absolute half areas for the termination rule */
    double sum = scale > 0.0f ? (double)best / ((double)scale * scale) : 0.0;
    if (best_k < 0 || !bvh_split_pays(ctx, t, sum)) return;

    /* 3. Partition in place, growing the children's centroid bounds on the
     * way; their boxes come from the groups. */
    int best_bin = groups[best_k][best_g].bin, best_sub = groups[best_k][best_g].sub;
    box3 lc, rc;
    uint32_t nl = best_sub < 0 ? partition(ctx->refs + t->first, t->count, &plan, plan.axis[best_k], best_bin,
                                           &lc, &rc)
                               : partition_scalar(ctx->refs + t->first, t->count, &plan, plan.axis[best_k],
                                                  best_bin, best_sub, &lc, &rc);
    box4 lb, rb;
    box4_clear(&lb);
    box4_clear(&rb);
    for (int g = 0; g < ng[best_k]; g++) box4_union(g <= best_g ? &lb : &rb, &groups[best_k][g].box);
    out->left_count = nl;
    out->left = box4_to_box3(&lb);
    out->right = box4_to_box3(&rb);
    out->left_c = lc;
    out->right_c = rc;
}

int bvh_build_binned(bvh_build_ctx *ctx, accel_error *err)
{
    int sets = ctx->threads > 1 ? ctx->threads * BIN_SPLITS : 1;
    /* Aligned for the bins' vectors (bin_box: 32 bytes with AVX). */
    bin_set *bins = accel_alloc_large((size_t)sets, sizeof(bin_set), 64);
    if (!bins) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for %d bin sets", sets);
    ctx->data = bins;
    ctx->split = binned_split;
    bvh_build_tree(ctx);
    free(bins);
    ctx->data = NULL;
    return 0;
}
