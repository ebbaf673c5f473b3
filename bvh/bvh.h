/*
 * bvh.h - the bounding volume hierarchy accelerator (kind "bvh").
 *
 * A binary BVH with the lecture's 32-byte nodes (below), built by one
 * of five builders and traced one ray at a time or in 64-ray packets:
 *
 *   bvh:build=binned,bins=16,axes=3   binned SAH (Wald 2007), the default
 *   bvh:build=sah                     exact SAH, full sweep on all three axes
 *   bvh:build=mid | build=median      spatial / object median of the longest axis
 *   bvh:build=sbvh,split_budget=0.3   binned SAH with spatial splits (Stich et al.
 *                                     2009): references duplicated, at most +30%
 *   bvh:leaf=4,ct=1,ci=1              leaf size bound and SAH costs
 *   bvh:build=median,term=none,leaf=4 the lecture's pure median split: no SAH
 *                                     termination, leaves of at most 4
 *   bvh:traverse=packet,frustum=1     64-ray packets with an interval early-out
 *   bvh:width=8,traverse=stream       ray streams (wide trees only): the tree
 *                                     walked once per stream of rays
 *
 * `bin/trace --help` lists every parameter with its unit and range;
 * bvh/README.md explains how each part works and what it costs.
 *
 * Use it through accel.h (accel_build_spec("bvh:...", ...)). The functions
 * below are for tests and tools that look inside a built tree.
 */
#ifndef BVH_BVH_H
#define BVH_BVH_H

#include <assert.h>
#include <stddef.h>
#include <stdint.h>

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

extern const accel_kind accel_kind_bvh;

/*
 * The node, public because bvh_nodes below hands out the pool: the
 * lecture's 32-byte node (see ../shared/LECTURE.md, 2):
 *
 *   offset  0  float bmin[3]     12 bytes
 *   offset 12  uint32 left_first  4 bytes: leaf: first primitive slot;
 *                                          interior: left child (right = left + 1)
 *   offset 16  float bmax[3]     12 bytes
 *   offset 28  uint32 count       4 bytes: > 0 for a leaf, 0 for an interior node
 *
 * All nodes live in one 64-byte aligned pool. The root is node 0, node 1 is
 * padding, and every child pair starts at an even index, so the two children
 * an interior node tests together always share one 64-byte cache line. A
 * tree over N primitives has at most N leaves, hence at most N-1 interior
 * nodes and 2 + 2(N-1) = 2N nodes with the padding: the lecture's "2N".
 *
 * Nothing in the structure is a pointer: nodes name their children and
 * primitives by index, so the pools can be written to a file and read back
 * anywhere (bvh_save / bvh_load in bvh_io.c).
 *
 * Primitives are stored in leaf order: slot i holds the 9 floats of a
 * triangle (v0, v1, v2) or the 4 floats of a sphere (centre, radius) in the
 * first 4 of its 9, and prim_ids[i] the scene id reported in hits. A leaf's
 * primitives are then one contiguous run of memory.
 */
typedef struct {
    float bmin[3];
    uint32_t left_first;
    float bmax[3];
    uint32_t count;
} bvh_node;

static_assert(sizeof(bvh_node) == 32, "bvh_node must be the lecture's 32-byte node");
static_assert(offsetof(bvh_node, left_first) == 12, "left_first follows bmin");
static_assert(offsetof(bvh_node, bmax) == 16, "bmax starts the second 16 bytes");
static_assert(offsetof(bvh_node, count) == 28, "count closes the node");

/* Alignment of the node pool: one cache line holds a sibling pair. */
#define BVH_NODE_ALIGN 64

/* Floats per primitive slot (a triangle's three vertices). */
#define BVH_SLOT_FLOATS 9

/* The builders never make a tree deeper than this (the root is level 1),
 * so a traversal stack of BVH_MAX_DEPTH entries cannot overflow: each entry
 * is a far child of one node on the current root-to-node path. */
#define BVH_MAX_DEPTH 64

/* The kind's parameters as parsed, one field per key (bvh.c's table:
 * ACCEL_SPEC(params, bvh_spec)). Choices hold their position in the
 * table's list (build: binned 0, sah, mid, median, sbvh 4; traverse:
 * single 0, packet 1, stream 2; ...), those written as numbers their number (width
 * 2, 4 or 8; axes 1 or 3; block 4 or 8, 0 for auto). */
typedef struct {
    int build, bins, axes, leaf;
    double split_budget, alpha, max_mb, ct, ci;
    int term, traverse, frustum, width, block, order, collapse;
    double leaf_cost;
    int leaf_blocks, leaf_below, hybrid, quant, first, pairs, isa, stream;
    int layout, any_order; /* wide/wide.h: WIDE_LAYOUT_*, WIDE_ANY_* */
} bvh_spec;

/* The node pool of a built bvh (node 0 is the root; node 1 is padding) and
 * the scene id of every primitive slot, in leaf order. */
const bvh_node *bvh_nodes(const void *accel, uint32_t *node_count);
const uint32_t *bvh_prim_ids(const void *accel, uint32_t *prim_count);

/* A binary SAH tree over n boxes, for a kind that builds its own two-level
 * structure (the top level over instance boxes). boxes holds 6 floats per
 * box: lo x, y, z, then hi x, y, z, finite with lo <= hi (else
 * ACCEL_ERR_SPEC). The tree is the default builder's (binned SAH, 16 bins,
 * 3 axes, ct = ci = 1) with leaves of at most max_leaf boxes (1..256); the
 * boxes are used as given (no pad). nodes is the lecture's pool of 32-byte
 * nodes as above (node 0 the root, node 1 padding; BVH_NODE_ALIGN-aligned;
 * node_count used), and a leaf's count boxes are order[left_first ..
 * left_first + count - 1], indices into boxes, each index in exactly one
 * leaf. The same tree for any thread count. An empty set gives no nodes. */
typedef struct {
    bvh_node *nodes;     /* node_count used, 0 for n = 0 */
    uint32_t node_count;
    uint32_t *order;     /* count box indices in leaf order */
    uint32_t count;      /* n */
    int depth;           /* levels (a lone leaf is 1) */
} bvh_box_tree;
int bvh_build_boxes(const float *boxes, uint32_t n, int max_leaf, int threads, bvh_box_tree *out,
                    accel_error *err);
void bvh_box_tree_free(bvh_box_tree *t);

/* SAH cost of a node pool, normalized by the root's area (half areas):
 *   sum over interior nodes of ct * A(n) / A(root)
 * + sum over leaves of ci * count(n) * A(n) / A(root).
 * 0 for an empty pool. Also the `sah_cost` of the build stats. */
double bvh_sah_cost(const bvh_node *nodes, uint32_t node_count, double ct, double ci);

/* Writes a built bvh to a file and reads it back: the pools are index-based
 * (relocatable), so the file is the pools as they are in memory after a
 * small header (magic "BVH1", version 1, counts, flags; little-endian).
 * bvh_load returns an accel usable with accel_kind_bvh. */
int bvh_save(const void *accel, const char *path, accel_error *err);
int bvh_load(const char *path, void **accel_out, accel_error *err);

/* A deliberately broken refit, for tests only: copies the primitives of
 * `scene` into the tree but leaves every box as it was, so rays miss what
 * moved out of its old boxes (the kind's update refits the boxes too). */
void bvh_refit_stale(void *accel, const accel_scene *scene);

#ifdef __cplusplus
}
#endif

#endif
