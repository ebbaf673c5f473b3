/*
 * igrid.h - the irregular grid accelerator kind `irregular_grid`.
 *
 * After Perard-Gayot, Kalojanov & Slusallek, "GPU Ray Tracing using
 * Irregular Grids", Eurographics 2017 (Computer Graphics Forum 36(2)): a
 * flat subdivision of the scene box into axis-aligned cells of varying
 * size, all laid on one fine virtual lattice of voxels. Built in three
 * steps, each selectable:
 *   1. subdivision: a coarse uniform top grid, and in every non-empty top
 *      cell an octree down to a depth set by the cell's own primitive count
 *      (the leaves are the first cells);
 *   2. merge: neighbouring cells with the same cross-section are merged
 *      while a surface-area cost, area * (primitives + ct), does not grow;
 *   3. expansion: each cell's exit box is grown over the neighbouring cells
 *      whose primitives are a subset of its own (empty cells included), so
 *      that a ray leaving the cell skips them.
 * Traversal: find the cell holding the ray's current voxel (top grid, then
 * the octree under it: the voxel map), test its primitives, jump to where
 * the ray leaves the cell's exit box, repeat. See irregular_grid/README.md.
 *
 * Spec parameters (`irregular_grid:key=value,...`):
 *   top_lambda  top grid: cells per primitive (n_i = d_i*cbrt(lambda*N/V))
 *   sub_lambda  octree density: cells per primitive the resolution rule aims
 *               at within a top cell (see split)
 *   max_depth   deepest octree level (the virtual lattice is the top grid
 *               times 2^depth per axis, at most 65536 voxels per axis)
 *   split       adaptive | cell: every non-empty octree node is split down to
 *               a depth set per top cell by the rule on its count (cell, the
 *               paper); adaptive goes on below it with nodes holding at
 *               least split_min primitives while a split separates them
 *   split_ratio adaptive: a split is undone when its octants hold more than
 *               this many references per primitive of the node
 *   subdivide   0/1: step 1 (0: the top grid's cells alone)
 *   merge       0/1: step 2
 *   alpha       merge passes go on while they remove at least 1-alpha of the cells
 *   ct          merge cost: cost of a cell step, in primitive tests
 *   expand      step 3: expansion passes over the six faces (0: off)
 *   mailbox     0/1: test a primitive spanning several cells once per ray
 *   max_mb      memory limit for the whole structure, MiB
 *   cells       ids | blocks: a cell's references as ids tested one by one
 *               (through the mailbox), or its triangles copied 8 to a block
 *               and tested with the shared block test (grid/grid_blocks.h,
 *               no mailbox; triangles with the watertight test only)
 *   tri         watertight | naive (common to all kinds)
 */
#ifndef IRREGULAR_GRID_IGRID_H
#define IRREGULAR_GRID_IGRID_H

#include <assert.h>
#include "accel.h"
#include "grid/grid_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Defaults, from the sweeps in irregular_grid/README.md. */
#define IGRID_DEFAULT_TOP_LAMBDA 0.12
#define IGRID_DEFAULT_SUB_LAMBDA 2.4
#define IGRID_DEFAULT_MAX_DEPTH 12
#define IGRID_MAX_DEPTH 16
#define IGRID_DEFAULT_ALPHA 0.995
#define IGRID_DEFAULT_EXPAND 3
#define IGRID_DEFAULT_SPLIT_MIN 16

extern const accel_kind accel_kind_irregular_grid;

/* One cell: its exit box on the virtual lattice (voxels lo..hi-1 per
 * axis; with expansion it holds the cell's own voxels and more) and its
 * references refs[begin..end). 32 bytes. */
typedef struct {
    int32_t lo[3];
    uint32_t begin;
    int32_t hi[3];
    uint32_t end;
} igrid_cell;
static_assert(sizeof(igrid_cell) == 32, "igrid_cell is 32 bytes");

/*
 * The voxel map: entry of top cell (x, y, z) at map[x + tx*(y + ty*z)];
 * an entry with bit 0 set is an octree node whose 8 children start at
 * map[entry >> 1] (child index: bit 0 = x, bit 1 = y, bit 2 = z half);
 * bit 0 clear: a leaf, entry >> 1 is the cell id. Returns the cell id of
 * voxel (x, y, z) of a lattice of top_res << shift voxels per axis.
 */
static inline uint32_t igrid_lookup(const uint32_t *map, const int top_res[3], int shift, int x,
                                    int y, int z)
{
    uint32_t e = map[(size_t)(x >> shift) +
                     (size_t)top_res[0] * ((size_t)(y >> shift) + (size_t)top_res[1] * (size_t)(z >> shift))];
    int s = shift;
    while (e & 1u) {
        s--;
        uint32_t child = (uint32_t)((x >> s) & 1) | (uint32_t)((y >> s) & 1) << 1 |
                         (uint32_t)((z >> s) & 1) << 2;
        e = map[(e >> 1) + child];
    }
    return e >> 1;
}

/* Read-only view of a built irregular grid (tests, tools). */
typedef struct {
    const grid_frame *frame;  /* the virtual lattice: box, voxels per axis, planes, padding */
    int top_res[3], shift;    /* top grid, octree depth: frame->res = top_res << shift */
    const uint32_t *map;      /* voxel map (igrid_lookup) */
    uint64_t map_len;
    const igrid_cell *cells;
    uint32_t cell_count;
    const uint32_t *refs;     /* local primitive ids */
    uint64_t ref_count;
    const uint32_t *prim_id;  /* local id -> scene primitive id */
    uint32_t prim_count;      /* local ids: the scene's live primitives */
} igrid_view;

void igrid_get_view(const void *accel, igrid_view *v);

#ifdef __cplusplus
}
#endif

#endif
