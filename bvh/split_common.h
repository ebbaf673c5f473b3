/*
 * split_common.h - what every BVH builder shares (internal to bvh/).
 *
 * Names: a builder is a split algorithm (bvh_builder, BVH_BUILD_*, the
 * build= parameter; one file build_<name>.c each); its working state is
 * the build context (bvh_build_ctx); the split code they share is
 * split_common.c; the driver that runs one and lays out the finished tree
 * is build_driver.c (bvh_build_run).
 *
 * A build works on an array of primitive references (one 32-byte record per
 * primitive: its box and its scene id) and a temporary node pool of 2N
 * nodes. A builder is one split function: given a task (a node and its run
 * of references) it either declares a leaf or partitions the run in place,
 * quicksort-like, into a left and a right part. The common driver
 * (split_common.c) does everything else: the SAH termination rule, the depth
 * bound, node allocation, the parallel schedule, and the final pass that
 * writes the compact node pool and the primitives in leaf order.
 *
 * Determinism: node indices never depend on timing. A task over n references
 * owns a fixed region of 2(n-1) node slots for its descendants (its children
 * pair first, then the left child's region, then the right child's), so the
 * same splits give the same temporary pool whichever thread makes them; the
 * final pass closes the gaps in place (the regions already lie in
 * depth-first order). Parallel binning merges
 * per-chunk bins with min, max and integer sums, which are exact in any
 * order. So the tree is byte-identical for any thread count.
 */
#ifndef BVH_SPLIT_COMMON_H
#define BVH_SPLIT_COMMON_H

#include <assert.h>
#include <float.h>
#include <math.h>
#include <string.h>

#include "bvh_node.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A primitive reference: the box and the scene id, 32 bytes like a node so
 * that the partition passes stream whole cache lines. */
typedef struct {
    float lo[3];
    uint32_t prim;
    float hi[3];
    uint32_t pad;
} bvh_ref;

static_assert(sizeof(bvh_ref) == 32, "bvh_ref is one half cache line");

/* Whether all of primitive `prim`'s coordinates are finite (the build
 * leaves out the others: no finite ray hits them, and their boxes would
 * poison every area above them; refit checks the same). */
static inline int bvh_prim_finite(const accel_scene *s, uint32_t prim)
{
    const float *p = prim < s->tri_count ? s->tris + 9 * (size_t)prim
                                         : s->spheres + 4 * (size_t)(prim - s->tri_count);
    int n = prim < s->tri_count ? 9 : 4;
    for (int i = 0; i < n; i++)
        if (!isfinite(p[i])) return 0;
    return 1;
}

/*
 * Every box the BVH stores is a primitive's bounds grown by box3_hit_pad
 * (core/geom.h), with delta from the scene's largest coordinate magnitude,
 * so that the exact slab test never rejects a hit the exact triangle test
 * claims (found by a hostile-ray audit: rays starting on a surface 1e-30
 * from a shared edge at z = 0 leaked through the closed cube). The pads are
 * far under a float ulp of the scene's extent: trees do not change
 * measurably.
 */
static inline float bvh_box_delta(const accel_scene *s)
{
    float m = box3_abs_max(s->bounds);
    if (!(m <= FLT_MAX)) { /* a non-finite primitive: the finite ones decide */
        m = 0.0f;
        for (uint32_t i = 0; i < s->live_count; i++)
            if (bvh_prim_finite(s, s->live[i])) m = fmaxf(m, box3_abs_max(accel_prim_bounds(s, s->live[i])));
    }
    return box3_hit_delta(m);
}

/* The box the BVH stores for a primitive (above). */
static inline box3 bvh_prim_box(const accel_scene *s, uint32_t prim, float delta)
{
    return box3_hit_pad(accel_prim_bounds(s, prim), delta);
}

/* The BVH_SLOT_FLOATS floats of a primitive slot: a triangle's 9, or a
 * sphere's 4 followed by zeros. */
static inline void bvh_prim_slot(const accel_scene *s, uint32_t prim, float *dst)
{
    if (prim < s->tri_count) {
        memcpy(dst, s->tris + 9 * (size_t)prim, 9 * sizeof(float));
    } else {
        memcpy(dst, s->spheres + 4 * (size_t)(prim - s->tri_count), 4 * sizeof(float));
        memset(dst + 4, 0, 5 * sizeof(float));
    }
}

/* The builder (split algorithm) of the build= parameter, in its order. */
typedef enum {
    BVH_BUILD_BINNED = 0,
    BVH_BUILD_SAH,
    BVH_BUILD_MID,
    BVH_BUILD_MEDIAN,
    BVH_BUILD_SBVH
} bvh_builder;

typedef struct {
    bvh_builder builder;
    int bins;      /* binned: bins per axis, 2..256 */
    int axes;      /* binned: 1 (largest centroid extent) or 3 */
    int max_leaf;  /* most primitives a leaf may hold */
    float ct, ci;  /* SAH: cost of a node visit and of a primitive test (one unit) */
    int term_none; /* term=none: split every node over max_leaf, never stop by the SAH rule */
    int reorder;       /* common parameter: Morton-ordered primitive store */
    double split_budget; /* sbvh: most duplicated references, as a fraction of the primitives */
    double max_mb;       /* memory limit of the build, MiB (build_driver.c checks it up front) */
    double alpha;        /* sbvh: spatial splits only where the object split's children overlap
                          * by more than alpha times the root's (half) area */
    int leaf_below;      /* a task of at most this many references is a leaf, unsplit (0: none;
                          * the wide builds' block size: the collapse makes any subtree that
                          * fits one block a single leaf, so splitting it is wasted) */
} bvh_build_opts;

/* A node to build: its place in the temporary pool and its references. */
typedef struct {
    uint32_t node;   /* index in the temporary pool */
    uint32_t first;  /* first reference */
    uint32_t count;  /* references, >= 1 */
    uint32_t region; /* first of the 2(count-1) node slots its descendants own */
    int level;       /* root = 1 */
    box3 bounds;     /* of the primitives */
    box3 cbounds;    /* of their centroids */
} bvh_task;

/* A split function's answer. */
typedef struct {
    uint32_t left_count;  /* 0: make the task a leaf */
    box3 left, right;     /* children's bounds */
    box3 left_c, right_c; /* children's centroid bounds */
} bvh_split;

struct bvh_build_ctx;
/* Decides the task's split and partitions its references in place so that
 * the left part comes first. `threads` > 1 only near the root, for the
 * builder's own data-parallel loops; the answer must not depend on it. A
 * split function cannot fail: scratch memory is allocated up front. */
typedef void (*bvh_split_fn)(struct bvh_build_ctx *ctx, const bvh_task *t, int threads, bvh_split *out);

typedef struct bvh_build_ctx {
    const accel_scene *scene;
    bvh_build_opts opts;
    bvh_ref *refs;        /* ref_count references */
    uint32_t ref_count;
    bvh_node *nodes;      /* temporary pool, 2 * ref_count nodes */
    bvh_split_fn split;
    void *data;           /* the builder's scratch */
    int threads;
} bvh_build_ctx;

/* Centroid of a reference on one axis: halves first, so that it never
 * overflows for any finite box; separate statements, so that no compiler
 * contracts it into a fused multiply-add (it must round the same way
 * everywhere). */
static inline float bvh_ref_centroid(const bvh_ref *r, int axis)
{
    float lo = 0.5f * r->lo[axis];
    float hi = 0.5f * r->hi[axis];
    return lo + hi;
}

static inline box3 bvh_ref_box(const bvh_ref *r)
{
    box3 b = {{r->lo[0], r->lo[1], r->lo[2]}, {r->hi[0], r->hi[1], r->hi[2]}};
    return b;
}

static inline vec3 bvh_ref_center(const bvh_ref *r)
{
    return v3(bvh_ref_centroid(r, 0), bvh_ref_centroid(r, 1), bvh_ref_centroid(r, 2));
}

/* Half surface area in double: extents of float boxes can neither overflow
 * nor underflow there, so SAH costs stay finite and comparable. */
static inline double bvh_half_area(box3 b)
{
    if (box3_is_empty(b)) return 0.0;
    double x = (double)b.max.x - b.min.x, y = (double)b.max.y - b.min.y,
           z = (double)b.max.z - b.min.z;
    return x * y + y * z + z * x;
}

/* ceil(log2(n)) for n >= 1. */
static inline int bvh_ceil_log2(uint32_t n)
{
    int k = 0;
    while (k < 32 && ((uint64_t)1 << k) < n) k++;
    return k;
}

/* The depth bound: when even halving the task at every level could only
 * just fit under BVH_MAX_DEPTH, the task must be split at the object
 * median. Once true it stays true for both halves (each level removes one
 * level of room and one halving), so no leaf lies deeper than the bound. */
static inline int bvh_task_forced(const bvh_task *t)
{
    return t->level + bvh_ceil_log2(t->count) >= BVH_MAX_DEPTH;
}

/* The SAH termination rule (Goldsmith & Salmon 1987; MacDonald & Booth
 * 1990; Wald 2007, eq. 1): a split into parts costing `split_sum` =
 * A_L*N_L + A_R*N_R (half areas) is worth its node visit when
 *   ct + ci * split_sum / A_node  <  ci * N.
 * A task larger than max_leaf is always split; with term=none (the
 * lecture's lab: split until a leaf is small enough) nothing else is. */
int bvh_split_pays(const bvh_build_ctx *ctx, const bvh_task *t, double split_sum);

/* A_L*N_L + A_R*N_R of a split (half areas), for bvh_split_pays. */
double bvh_split_sum(const bvh_split *s, uint32_t count);

/* A lower bound that spares small tasks the split search: every part's box
 * contains the boxes of its primitives, so A_L*N_L + A_R*N_R is at least
 * the sum of the primitives' own areas, and when even that bound makes a
 * split cost more than the leaf (by a margin that covers rounding in the
 * builders' own cost sums), any split function would answer "leaf" too.
 * Only for tasks whose references lie at refs[first, first+count). */
int bvh_leaf_certain(const bvh_build_ctx *ctx, const bvh_task *t);

/* Object median on the axis of largest centroid extent (quickselect on the
 * centroid, ties broken by primitive id so the result is unique): the
 * `median` builder, and every builder's fallback when forced by the depth
 * bound or when no other split separates the references. Always splits
 * (count >= 2); fills both children's bounds. */
void bvh_split_median(bvh_build_ctx *ctx, const bvh_task *t, bvh_split *out);

/* Bounds and centroid bounds of refs[first, first+count). */
void bvh_refs_bounds(const bvh_ref *refs, uint32_t first, uint32_t count, box3 *bounds,
                     box3 *cbounds);

/* The common driver: builds the whole tree in ctx->nodes with ctx->split,
 * using ctx->threads threads (binning near the root, subtrees as tasks). */
void bvh_build_tree(bvh_build_ctx *ctx);

/* The builders (one file each). Each sets ctx->split, allocates its scratch,
 * runs bvh_build_tree and leaves ctx->refs in leaf order. */
int bvh_build_binned(bvh_build_ctx *ctx, accel_error *err);
int bvh_build_sah(bvh_build_ctx *ctx, accel_error *err);
int bvh_build_mid(bvh_build_ctx *ctx, accel_error *err);
int bvh_build_median(bvh_build_ctx *ctx, accel_error *err);
/* The split BVH (build_sbvh.c): it replaces ctx->refs and ctx->nodes by
 * larger arrays (N(1 + split_budget) references, twice that many nodes) and
 * sets ctx->ref_count to the references of the finished tree (>= N). */
int bvh_build_sbvh(bvh_build_ctx *ctx, accel_error *err);

/* The boxes of the parts of triangle `tri` (9 floats) on either side of the
 * plane x[axis] = plane, each intersected with `box`: computed in double and,
 * with outward = 1, rounded outward to float with a pad for the double
 * rounding of the edge/plane intersections, so that each contains the exact
 * part (build_sbvh_chop.c; outward = 0 rounds to nearest, for the test that shows
 * the difference). An empty part has min > max on some axis. */
void bvh_sbvh_chop(const float *tri, box3 box, int axis, double plane, int outward, box3 *left,
                   box3 *right);
/* The same for a box alone (a sphere's part lies in its box's part). */
void bvh_sbvh_chop_box(box3 box, int axis, double plane, box3 *left, box3 *right);

/* Builds a complete bvh (nodes, primitives in leaf order, stats) over the
 * scene's live primitives. Fills stats->nodes, leaves, refs, sah_cost,
 * depth; the caller sets the traversal fields of *out. */
int bvh_build_run(const accel_scene *scene, const bvh_build_opts *opts, int threads, bvh *out,
                  accel_build_stats *stats, accel_error *err);

/* Frees what bvh_build_run allocated in b. */
void bvh_release(bvh *b);
/* pairs=split (build_driver.c): moves the node pool 32 bytes off the cache line
 * grid; frees the old pool. */
int bvh_split_pairs(bvh *b, int shift, accel_error *err);

/* bvh_refit.c (the kind's update). bvh_refit_compatible: 0 when s holds the
 * same primitives the tree traces (counts, and the same live, finite ids:
 * the refit keeps the topology), -1 when the set of traced primitives
 * changed (the tree must be rebuilt: -1), or the error code of *err (other
 * primitive counts: refused). bvh_refit_run copies every primitive the tree
 * holds from s again and, with boxes = 1, recomputes every box bottom-up
 * (boxes = 0 leaves stale boxes: the broken refit a test shows failing);
 * it fails (out of memory) before it changes anything. */
int bvh_refit_compatible(const bvh *b, const accel_scene *s, accel_error *err);
int bvh_refit_run(bvh *b, const accel_scene *s, int threads, int boxes, accel_error *err);

/* Allocates n nodes aligned to BVH_NODE_ALIGN (NULL on failure or overflow). */
bvh_node *bvh_alloc_nodes(size_t n);
/* malloc(n * size) with the product checked (NULL on overflow); n = 0 allocates one byte. */
void *bvh_alloc_array(size_t n, size_t size);

#ifdef __cplusplus
}
#endif

#endif
