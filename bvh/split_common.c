/*
 * split_common.c - what every BVH builder shares: aligned allocation, the
 * SAH termination rule, the object-median split and the (parallel,
 * deterministic) top-down recursion that calls a builder's split function.
 * The driver that runs a builder and lays out its result is build_driver.c.
 *
 * The recursion follows the usual top-down recursion (pbrt-v3 section 4.3;
 * Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
 * RT 2007): near the root the split functions may use all threads for
 * their per-node loops (binning), below that each subtree is one task.
 */
#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "split_common.h"

/* Tasks with fewer references than this are built by a single thread: a
 * subtree of a few thousand primitives takes about a millisecond. */
#define BVH_PAR_MIN_REFS 4096u
/* Subtree tasks handed to the threads per thread (load balance). */
#define BVH_TASKS_PER_THREAD 8
#define BVH_MAX_TOP_TASKS 512

bvh_node *bvh_alloc_nodes(size_t n)
{
    return accel_alloc_large(n ? n : 1, sizeof(bvh_node), BVH_NODE_ALIGN);
}

void *bvh_alloc_array(size_t n, size_t size)
{
    return accel_alloc_large(n, size, sizeof(void *));
}

int bvh_split_pays(const bvh_build_ctx *ctx, const bvh_task *t, double split_sum)
{
    if (t->count > (uint32_t)ctx->opts.max_leaf) return 1;
    if (ctx->opts.term_none) return 0;
    double area = bvh_half_area(t->bounds);
    if (!(area > 0.0)) return 0;
    double leaf = (double)ctx->opts.ci * t->count;
    double split = (double)ctx->opts.ct + (double)ctx->opts.ci * split_sum / area;
    return split < leaf;
}

double bvh_split_sum(const bvh_split *s, uint32_t count)
{
    return bvh_half_area(s->left) * s->left_count +
           bvh_half_area(s->right) * (count - s->left_count);
}

int bvh_leaf_certain(const bvh_build_ctx *ctx, const bvh_task *t)
{
    if (t->count > (uint32_t)ctx->opts.max_leaf) return 0;
    double area = bvh_half_area(t->bounds);
    if (!(area > 0.0)) return 0;
    double sum = 0.0;
    for (uint32_t i = t->first; i < t->first + t->count; i++)
        sum += bvh_half_area(bvh_ref_box(&ctx->refs[i]));
    double leaf = (double)ctx->opts.ci * t->count;
    double bound = (double)ctx->opts.ct + (double)ctx->opts.ci * sum / area;
    return bound > leaf * (1.0 + 1e-3);
}

void bvh_refs_bounds(const bvh_ref *refs, uint32_t first, uint32_t count, box3 *bounds,
                     box3 *cbounds)
{
    box3 b = box3_empty(), c = box3_empty();
    for (uint32_t i = first; i < first + count; i++) {
        b = box3_union(b, bvh_ref_box(&refs[i]));
        c = box3_grow(c, bvh_ref_center(&refs[i]));
    }
    *bounds = b;
    *cbounds = c;
}

/* ---- object median ------------------------------------------------------ */

/* The order the median uses: centroid on `axis`, then primitive id, so that
 * equal centroids (coincident primitives) still have one answer. */
static inline int ref_before(const bvh_ref *a, const bvh_ref *b, int axis)
{
    float ca = bvh_ref_centroid(a, axis), cb = bvh_ref_centroid(b, axis);
    return ca < cb || (ca == cb && a->prim < b->prim);
}

static inline void swap_refs(bvh_ref *a, bvh_ref *b)
{
    bvh_ref t = *a;
    *a = *b;
    *b = t;
}

/* Quickselect (Hoare 1961) with a median-of-three pivot: afterwards r[k] is
 * the k-th reference in ref_before order, everything before it precedes it
 * and everything after it follows it. */
static void select_kth(bvh_ref *r, uint32_t n, uint32_t k, int axis)
{
    uint32_t lo = 0, hi = n - 1;
    while (hi > lo) {
        if (hi - lo == 1) {
            if (ref_before(&r[hi], &r[lo], axis)) swap_refs(&r[lo], &r[hi]);
            return;
        }
        uint32_t mid = lo + (hi - lo) / 2;
        if (ref_before(&r[mid], &r[lo], axis)) swap_refs(&r[mid], &r[lo]);
        if (ref_before(&r[hi], &r[lo], axis)) swap_refs(&r[hi], &r[lo]);
        if (ref_before(&r[hi], &r[mid], axis)) swap_refs(&r[hi], &r[mid]);
        if (hi - lo == 2) return;
        /* r[lo] <= pivot <= r[hi] are sentinels for the two scans. */
        swap_refs(&r[mid], &r[hi - 1]);
        bvh_ref pivot = r[hi - 1];
        uint32_t i = lo, j = hi - 1;
        for (;;) {
            while (ref_before(&r[++i], &pivot, axis)) {}
            while (ref_before(&pivot, &r[--j], axis)) {}
            if (i >= j) break;
            swap_refs(&r[i], &r[j]);
        }
        swap_refs(&r[i], &r[hi - 1]);
        if (k == i) return;
        if (k < i)
            hi = i - 1;
        else
            lo = i + 1;
    }
}

void bvh_split_median(bvh_build_ctx *ctx, const bvh_task *t, bvh_split *out)
{
    assert(t->count >= 2);
    int axis = v3_max_axis(box3_extent(t->cbounds));
    uint32_t half = t->count / 2;
    bvh_ref *r = ctx->refs + t->first;
    select_kth(r, t->count, half, axis);
    out->left_count = half;
    bvh_refs_bounds(ctx->refs, t->first, half, &out->left, &out->left_c);
    bvh_refs_bounds(ctx->refs, t->first + half, t->count - half, &out->right, &out->right_c);
}

/* ---- the driver ---------------------------------------------------------- */

/* Splits one task (or makes it a leaf). Returns 1 and fills the children
 * tasks when it split. The children's pair goes to the task's region
 * start, or, when `bump` is given (inside one subtree, built by one
 * thread), to the next free pair of the subtree's region: its nodes then
 * lie together at the region's start, in depth-first order, and the pages
 * of the region's unused tail are never touched. */
static int split_task(bvh_build_ctx *ctx, const bvh_task *t, int threads, bvh_task *l, bvh_task *r,
                      uint32_t *bump)
{
    bvh_node *node = &ctx->nodes[t->node];
    bvh_split s;
    s.left_count = 0;
    if (t->count > 1 && t->count > (uint32_t)ctx->opts.leaf_below) {
        ctx->split(ctx, t, threads, &s);
        /* A split function must split an oversized task; the median always can. */
        if (s.left_count == 0 && t->count > (uint32_t)ctx->opts.max_leaf)
            bvh_split_median(ctx, t, &s);
    }
    if (s.left_count == 0) {
        node->left_first = t->first;
        node->count = t->count;
        return 0;
    }
    assert(s.left_count < t->count);
    assert(t->level < BVH_MAX_DEPTH);
    uint32_t pair = t->region;
    if (bump) pair = *bump, *bump += 2;
    uint32_t nl = s.left_count, nr = t->count - nl;
    node->left_first = pair;
    node->count = 0;
    bvh_node_set_box(&ctx->nodes[pair], s.left);
    bvh_node_set_box(&ctx->nodes[pair + 1], s.right);
    *l = (bvh_task){pair, t->first, nl, pair + 2, t->level + 1, s.left, s.left_c};
    *r = (bvh_task){pair + 1, t->first + nl, nr, pair + 2 + 2 * (nl - 1), t->level + 1, s.right,
                    s.right_c};
    return 1;
}

/* Depth-first, one thread. Pending right siblings: at most one per level.
 * The subtree's pairs are handed out in the order of its splits (left
 * first, depth-first): at most 2(count - 1) nodes, inside its region. */
static void build_subtree(bvh_build_ctx *ctx, const bvh_task *root)
{
    bvh_task stack[BVH_MAX_DEPTH + 1];
    int sp = 0;
    uint32_t bump = root->region;
    stack[sp++] = *root;
    while (sp > 0) {
        bvh_task t = stack[--sp], l, r;
        if (!split_task(ctx, &t, 1, &l, &r, &bump)) continue;
        assert(sp + 2 <= BVH_MAX_DEPTH + 1);
        stack[sp++] = r;
        stack[sp++] = l;
    }
}

typedef struct {
    bvh_build_ctx *ctx;
    bvh_task *tasks;
} subtree_job;

static void subtree_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    subtree_job *j = p;
    for (size_t i = begin; i < end; i++) build_subtree(j->ctx, &j->tasks[i]);
}

static int by_count_desc(const void *a, const void *b)
{
    uint32_t x = ((const bvh_task *)a)->count, y = ((const bvh_task *)b)->count;
    return x < y ? 1 : x > y ? -1 : 0;
}

void bvh_build_tree(bvh_build_ctx *ctx)
{
    bvh_task root;
    root.node = 0;
    root.first = 0;
    root.count = ctx->ref_count;
    root.region = 2;
    root.level = 1;
    bvh_refs_bounds(ctx->refs, 0, ctx->ref_count, &root.bounds, &root.cbounds);
    bvh_node_set_box(&ctx->nodes[0], root.bounds);
    int threads = ctx->threads;
    if (threads <= 1 || ctx->ref_count < 2 * BVH_PAR_MIN_REFS) {
        build_subtree(ctx, &root);
        return;
    }
    /* Top of the tree: split the largest task with every thread helping,
     * until there are enough subtrees to keep the threads busy. */
    bvh_task tasks[BVH_MAX_TOP_TASKS];
    size_t n = 1, want = (size_t)threads * BVH_TASKS_PER_THREAD;
    if (want > BVH_MAX_TOP_TASKS - 1) want = BVH_MAX_TOP_TASKS - 1;
    tasks[0] = root;
    while (n < want) {
        size_t big = 0;
        for (size_t i = 1; i < n; i++)
            if (tasks[i].count > tasks[big].count) big = i;
        if (tasks[big].count < BVH_PAR_MIN_REFS) break;
        bvh_task l, r;
        if (split_task(ctx, &tasks[big], threads, &l, &r, NULL)) {
            tasks[big] = l;
            tasks[n++] = r;
        } else {
            tasks[big] = tasks[--n]; /* became a leaf: done */
            if (n == 0) return;
        }
    }
    /* The rest: one subtree per task, largest first. */
    qsort(tasks, n, sizeof tasks[0], by_count_desc);
    subtree_job job = {ctx, tasks};
    accel_parallel_for(n, 1, threads, subtree_chunk, &job);
}

