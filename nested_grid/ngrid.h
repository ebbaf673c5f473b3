/*
 * ngrid.h - the nested grid accelerator kind `nested_grid`.
 *
 * A uniform top-level grid whose dense cells hold uniform grids of their
 * own, recursively (Jevans & Wyvill, "Adaptive Voxel Subdivision for Ray
 * Tracing", Graphics Interface 1989; Klimaszewski & Sederberg, "Faster Ray
 * Tracing Using Adaptive Grids", IEEE CG&A 1997). Every level is built and
 * walked with the shared grid API (grid/grid_core.h): the same resolution
 * rule, exact overlap, overflow-checked sizing and 3D-DDA as the regular
 * grid. The walk is hierarchical: a cell that holds a sub-grid is walked in
 * the sub-grid from the ray's entry into that cell, and leaving the sub-grid
 * resumes the parent's walk. See nested_grid/README.md.
 *
 * Spec parameters (`nested_grid:key=value,...`):
 *   lambda      top level: cells per primitive (n_i = d_i*cbrt(lambda*N/V))
 *   res         top level: auto | N | NxNyNz cells per axis (overrides lambda)
 *   sub_lambda  sub-grids: cells per primitive, on the cell's own count and box
 *   sub_res     sub-grids: N cells per axis for every sub-grid (0 = from sub_lambda)
 *   threshold   a cell holding more than this many primitives gets a sub-grid
 *   depth       levels including the top, 1..NGRID_MAX_LEVELS (1: a regular grid)
 *   auto        pick the top resolution and every sub-grid (or none) from the
 *               cost model c_step*E[cells] + c_isect*E[tests] instead of
 *               lambda, sub_lambda and threshold
 *   lookahead   auto: price cells that may still be subdivided by an estimate of
 *               their best sub-grid rather than as leaves (ngrid_cost.c)
 *   c_step      cost model: cost of one cell step, ns
 *   c_isect     cost model: cost of one primitive test, ns
 *   overlap     exact | bbox cell membership
 *   mailbox     0/1: test a primitive once per ray across cells and levels
 *   max_mb      memory limit for the whole structure, MiB
 *   layout      words (cell words, any depth) | compact (two levels: 8-byte top
 *               cells with their own sub-grid resolution, 4-byte leaf cells,
 *               one reference array; ngrid_compact.c)
 *   traverse    single | packet (64-ray coherent grid traversal through every
 *               level, ngrid_packet.c)
 *   cells       ids | blocks: a leaf cell's list tested id by id, or its
 *               triangles copied 8 to a block for the shared block test
 *               (layout=words; single rays without the mailbox, packets
 *               with theirs)
 *   tri         watertight | naive (common to all kinds)
 */
#ifndef NESTED_GRID_NGRID_H
#define NESTED_GRID_NGRID_H

#include "accel.h"
#include "grid/grid_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Most levels a nested grid has, the top included (accel_counters has one
 * level_steps entry per level). */
#define NGRID_MAX_LEVELS 4

/* Defaults, from the sweep reported in nested_grid/README.md. */
#define NGRID_DEFAULT_LAMBDA 2
#define NGRID_DEFAULT_SUB_LAMBDA 4
#define NGRID_DEFAULT_THRESHOLD 12
#define NGRID_DEFAULT_DEPTH 3
/* Cost model defaults, ns: least-squares fit of this kernel's trace times
 * against its counters on this machine (calibration in README.md). */
#define NGRID_DEFAULT_C_STEP 7
#define NGRID_DEFAULT_C_ISECT 13
/* The cost of one triangle test when leaf cells hold blocks
 * (cells=blocks: 8 triangles per block test), ns per triangle: what auto
 * mode prices a test at there when c_isect is not given. Not fitted on
 * this kernel: taken from the report's step-cost table, where the 8-wide
 * BVH's leaf blocks (the same block test) cost 1.2-1.7 ns per triangle,
 * rounded up for the padded lanes of a cell's last block. A block cell
 * is priced per triangle, linear in n (a cell of 1..8 triangles really
 * costs one block); refit with the step-cost experiment before trusting
 * its choices. The non-auto densities lambda and sub_lambda stay the
 * per-id defaults with blocks; by this price a leaf of blocks breaks even
 * with a sub-grid at about 13/2 times the triangles, so the threshold
 * rises (NGRID_BLOCKS_THRESHOLD). */
#define NGRID_BLOCKS_C_ISECT 2
/* The threshold with cells=blocks for single rays when none is given
 * (packets keep the per-id densities, as the grid's do). Measured on the
 * diffuse rays of the scanned meshes (1024x768 primaries' bounces, one
 * process each, 2026-12-07, AVX2): threshold 12 (the per-id default),
 * 24, 32, 48 gave 1.00, 1.27, 1.86, 1.67 Mrays/s on armadillo and (24, 32,
 * 48) 2.23, 2.25, 1.93 on bunny; the per-id cells' best of 6, 12, 32 was 6 (1.00 and
 * 1.19 Mrays/s). */
#define NGRID_BLOCKS_THRESHOLD 32

extern const accel_kind accel_kind_nested_grid;

/* ---- read-only view of a built nested grid (tests, tools) -------------------- */

/* A cell word: either an index into lists[] (the cell's primitive list,
 * lists[w] = count followed by count ids; 0 is the shared empty list) or
 * NGRID_CHILD | index of the grid the cell holds. */
#define NGRID_CHILD 0x80000000u

typedef struct {
    grid_frame frame;   /* box, resolution, boundary planes, padding */
    uint32_t cell_base; /* index of this grid's cell 0 in the cell words */
    uint32_t level;     /* 0 = top */
} ngrid_node;

typedef struct {
    const ngrid_node *nodes; /* grids in breadth-first order; nodes[0] is the top */
    uint32_t node_count;
    const uint32_t *cells;   /* cell words of every grid, cell_count */
    uint64_t cell_count;
    const uint32_t *lists;   /* count-prefixed primitive lists, list_len */
    uint64_t list_len;
    uint64_t ref_count;      /* primitive ids stored in lists */
    const uint32_t *prim_id; /* lists hold local ids: local id -> scene primitive id */
    uint32_t prim_count;     /* local ids: the scene's live primitives */
    int levels;              /* levels actually built */
} ngrid_view;

/* Fills *v from an accelerator built by accel_kind_nested_grid. With
 * layout=compact the word arrays are freed after the build: nodes, cells
 * and lists are then NULL with counts 0 (ref_count, levels and the id map
 * stay). */
void ngrid_get_view(const void *accel, ngrid_view *v);

/* ---- the cost model (ngrid_cost.c) --------------------------------------------- */

/*
 * Expected number of cells of frame f that a random line crossing f's box
 * crosses. For isotropic random lines, a line crossing a convex body A also
 * crosses a convex body B inside it with probability area(B)/area(A)
 * (Cauchy-Crofton; Santalo, "Integral Geometry and Geometric Probability",
 * 1976); summed over the cells of an nx*ny*nz grid over a box of extents d:
 *   E[cells] = (nx d_y d_z + ny d_z d_x + nz d_x d_y) / (d_y d_z + d_z d_x + d_x d_y),
 * that is (nx + ny + nz)/3 for a cube.
 */
double ngrid_expected_cells(const grid_frame *f);

/* Probability that a random line crossing f's box crosses one given cell:
 * area(cell)/area(box), the same for every cell of a uniform grid. */
double ngrid_cell_probability(const grid_frame *f);

#ifdef __cplusplus
}
#endif

#endif
