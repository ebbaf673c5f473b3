/*
 * bvh.h - the bounding volume hierarchy accelerator (kind "bvh").
 *
 * A binary BVH with the lecture's 32-byte nodes (bvh_node.h), built by one
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
 *
 * `bin/trace --help` lists every parameter with its unit and range;
 * bvh/README.md explains how each part works and what it costs.
 *
 * Use it through accel.h (accel_build_spec("bvh:...", ...)). The functions
 * below are for tests and tools that look inside a built tree.
 */
#ifndef BVH_BVH_H
#define BVH_BVH_H

#include "accel.h"
#include "bvh_node.h"

#ifdef __cplusplus
extern "C" {
#endif

extern const accel_kind accel_kind_bvh;

/* The kind's parameters as parsed, one field per key (bvh.c's table:
 * ACCEL_SPEC(params, bvh_spec)). Choices hold their position in the
 * table's list (build: binned 0, sah, mid, median, sbvh 4; traverse:
 * single 0, packet 1; ...), those written as numbers their number (width
 * 2, 4 or 8; axes 1 or 3; block 4 or 8, 0 for auto). */
typedef struct {
    int build, bins, axes, leaf;
    double split_budget, alpha, max_mb, ct, ci;
    int term, traverse, frustum, width, block, order, collapse;
    double leaf_cost;
    int leaf_blocks, leaf_below, hybrid, quant, first, pairs;
} bvh_spec;

/* The node pool of a built bvh (node 0 is the root; node 1 is padding) and
 * the scene id of every primitive slot, in leaf order. */
const bvh_node *bvh_nodes(const void *accel, uint32_t *node_count);
const uint32_t *bvh_prim_ids(const void *accel, uint32_t *prim_count);

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
