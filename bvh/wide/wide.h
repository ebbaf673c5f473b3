/*
 * wide.h - the wide BVH (`bvh:width=4|8`) as the kind sees it: its type,
 * the collapse that makes it from the binary tree, its batch entries, its
 * conservative walk and its refit. The one header of bvh/wide/ that the
 * binary tree's files include (bvh.c, the kind); the layouts (node.h) and
 * the kernel templates (kernel.h, packet.h, tables.h; the block test core/block_test.h and core/simd.h) are
 * internal to bvh/wide/.
 */
#ifndef BVH_WIDE_WIDE_H
#define BVH_WIDE_WIDE_H

#include <stddef.h>
#include <stdint.h>

#include "accel.h"
#include "core/prim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Ordering of the hit children (parameter order=): per-ray entry
 * distances with branches on the hit count, the node's precomputed octant
 * order with a compress-store onto the stack, or the octant order pushed
 * with one branch per child (branchy; single rays only). */
enum { WIDE_ORDER_DIST = 0, WIDE_ORDER_OCTANT = 1, WIDE_ORDER_BRANCHY = 2 };

/* Placement of nodes and leaf blocks in memory (parameter layout=; issue
 * 50): dfs, the collapse's own numbering (nodes depth-first in one pool,
 * each child's subtree before its next sibling's; blocks in a second pool
 * in the order the collapse reaches the leaves, also depth-first); bfs,
 * the same two pools renumbered level by level (the top levels packed
 * together); mixed, one pool in which each node is followed by the blocks
 * of its leaf children, then its node children's subtrees depth-first
 * (Embree's allocation order), references counting 64-byte lines from the
 * pool's start (width 8, single rays; its own kernel unit, k8_mixed.c). */
enum { WIDE_LAYOUT_DFS = 0, WIDE_LAYOUT_BFS = 1, WIDE_LAYOUT_MIXED = 2 };

/* The child order of any-hit queries (parameter any_order=; single rays,
 * width 8): near, the closest-hit order (entry distance for two hit
 * children, the octant order for more); octant, the octant order for any
 * count (no distance compare); area, the largest child box first; leaf,
 * leaf children first (most blocks first, then largest box), then nodes by
 * largest box. area and leaf are stored in the unused bits 24..29 of each
 * node's perm rows (node.h), so the kernel's octant push serves them. */
enum { WIDE_ANY_NEAR = 0, WIDE_ANY_OCTANT = 1, WIDE_ANY_AREA = 2, WIDE_ANY_LEAF = 3 };
#define WIDE_PERM_AREA_SHIFT 24
#define WIDE_PERM_LEAF_SHIFT 27

/* The wide tree: its own type, which the kind's wide code path (bvh.c)
 * holds. Immutable after the build, but for a refit (refit.c). */
typedef struct bvh_wide {
    int width;            /* children per node: 4 or 8 */
    int block;            /* primitives per leaf block: 4 or 8 */
    int order;            /* WIDE_ORDER_*: how hit children are ordered */
    int packets;          /* traverse=packet: 64-ray packets (packet.h) */
    int hybrid;           /* packets: entries spanning at most this many rays go ray by ray;
                           * streams: entries of at most this many rays */
    int stream;           /* traverse=stream: rays per stream (stream.h); 0: not a stream tree */
    int quant;            /* quant=1: nodes are wide_qnode8 (width 8 only) */
    int isa;              /* ACCEL_ISA_AVX2 or _AVX512 (core/isa.h): whose kernel units run */
    uint32_t root;        /* reference of the root, WIDE_EMPTY for an empty scene */
    uint32_t node_count;  /* wide nodes */
    uint32_t leaf_count;  /* leaves */
    uint32_t block_count; /* leaf blocks */
    uint32_t prim_count;  /* primitives stored (not counting padding lanes) */
    uint32_t tri_count;   /* scene ids >= tri_count are spheres */
    uint32_t step_bound;  /* nodes + leaves: a ray visits each at most once */
    int depth;            /* levels of wide nodes and leaves (a lone leaf is 1) */
    void *nodes;          /* wide_node4 or wide_node8, 64-byte aligned */
    void *blocks;         /* wide_block4 or wide_block8, 64-byte aligned */
    /* issue 50's variants, after the fields the default kernels read (so
     * that their offsets, and the default kernels' code, stay as they were) */
    int layout;           /* WIDE_LAYOUT_*: where nodes and blocks sit in memory */
    int any_order;        /* WIDE_ANY_*: the child order of any-hit queries */
    int any_shift;        /* any_order=area|leaf: its perm bits' shift; else -1 (the ray's octant) */
    size_t pool_bytes;    /* layout=mixed: bytes of the one pool (nodes == blocks) */
    uint64_t *block_at;   /* layout=mixed: byte offset of block k in the pool; else NULL */
} bvh_wide;

struct bvh;
/* How the binary tree is collapsed: greedy (dp = 0: open the largest
 * child, every subtree of one block a leaf) or the optimal collapse under
 * the SAH (dp = 1, collapse.c's plan_dp), with a leaf block costing
 * leaf_cost wide node visits and leaves of at most leaf_blocks blocks. */
typedef struct {
    int dp;
    double leaf_cost;
    int leaf_blocks;
    double max_mb; /* the build's memory limit (bvh's max_mb), MiB; 0: none */
    int layout;    /* WIDE_LAYOUT_* */
    int any_order; /* WIDE_ANY_*: area and leaf store their orders in the perm rows */
} bvh_wide_collapse;
/* Collapses the built binary tree of b into *out (width 4 or 8, leaf
 * blocks of `block` primitives) and frees the binary pools, which the wide
 * kernels do not use. Fills stats->nodes, leaves and depth, and
 * stats->sah_cost with the wide tree's SAH cost under node cost ct and
 * primitive cost ci (the binary tree's formula over the wide nodes and
 * leaves). The binary tree is best built with leaf_below = block
 * (split_common.h): a subtree that fits one block becomes one leaf. */
int bvh_wide_build(struct bvh *b, bvh_wide **out, int width, int block, int order, int quant,
                   const bvh_wide_collapse *cc, int threads, double ct, double ci, accel_build_stats *stats, accel_error *err);
/* Bytes held by the wide tree (nodes, blocks, the struct itself). */
size_t bvh_wide_memory(const bvh_wide *w);
void bvh_wide_free(bvh_wide *w);

/* Kernels (trace.c, which picks the table a unit k<width>_<row>.c compiled). */
void bvh_wide_intersect(const bvh_wide *w, const accel_ray *rays, accel_hit *hits, size_t count,
                        accel_counters *c, int naive, int has_spheres);
void bvh_wide_occluded(const bvh_wide *w, const accel_ray *rays, uint8_t *occ, size_t count,
                       accel_counters *c, int naive, int has_spheres);
/* The same with the single-ray table whatever w->packets (and w->stream): where the packet
 * layer (core/coherence.h) sends the rays of an incoherent group. */
void bvh_wide_single_intersect(const bvh_wide *w, const accel_ray *rays, accel_hit *hits,
                               size_t count, accel_counters *c, int naive, int has_spheres);
void bvh_wide_single_occluded(const bvh_wide *w, const accel_ray *rays, uint8_t *occ, size_t count,
                              accel_counters *c, int naive, int has_spheres);

/* accel.h's conservative walk over the wide tree (walk.c): bvh_walk's
 * contract, for a prepared ray. */
void bvh_wide_walk(const bvh_wide *w, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                   void *ctx, uint32_t *steps);

/* The kind's update (refit.c). bvh_wide_mark_ids sets mark[id] = 1 for
 * every scene id the tree holds; 0 when one is not below total.
 * bvh_wide_refit copies every primitive again from s and, with boxes = 1,
 * recomputes every box bottom-up (bvh_refit_run's contract). */
int bvh_wide_mark_ids(const bvh_wide *w, uint8_t *mark, size_t total);
int bvh_wide_refit(bvh_wide *w, const accel_scene *s, int threads, int boxes, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
