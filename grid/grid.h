/*
 * grid.h - the regular grid accelerator kind `grid`.
 *
 * A uniform grid over the scene bounds (Fujimoto et al. 1986; Amanatides &
 * Woo 1987), stored compactly (one offset per cell into one array of
 * primitive ids), built with exact primitive/cell overlap, traversed with a
 * 3D-DDA that stops at the first cell whose exit lies beyond the nearest
 * hit. See grid/README.md for how it works and what its knobs cost.
 *
 * Spec parameters (`grid:key=value,...`):
 *   lambda   cells per primitive (target density; default GRID_DEFAULT_LAMBDA):
 *            n_i = d_i * cbrt(lambda * N / V), see grid_resolution()
 *   res      auto | N | NxNyNz: cells per axis, overriding lambda
 *   overlap  exact | bbox: membership by exact triangle/sphere-box overlap,
 *            or by bounding box only
 *   mailbox  0/1: test a primitive spanning several cells once per ray
 *   reorder  0/1: copy the primitives in Morton order of their centroids
 *   max_mb   memory limit for offsets + references (+ skip table), MiB (larger is refused)
 *   skip     none | cloud | macro: empty-space skipping (grid_skip.h)
 *   skip_min cloud: smallest box radius worth a jump, cells
 *   macro    macro: cells per macro cell along each axis (power of two)
 *   traverse single | packet: the 3D-DDA per ray, or coherent grid traversal
 *            of 64-ray packets slice by slice (grid_packet_trace.c; the mailbox
 *            is then per packet)
 *   cells    blocks | ids: a cell's triangles copied 8 to a block for the
 *            shared block test (single rays and packets; no mailbox for
 *            single rays), or its primitive ids tested one by one
 *   tri      watertight | naive (common to all kinds)
 */
#ifndef GRID_GRID_H
#define GRID_GRID_H

#include "accel.h"
#include "grid_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Default cells per primitive, from the sweep reported in grid/README.md. */
#define GRID_DEFAULT_LAMBDA 8
/* The density when cells hold blocks (cells=blocks) and lambda is not
 * given, single rays (packets keep GRID_DEFAULT_LAMBDA: unmeasured with
 * blocks): a test of 8 triangles at once costs about what one scalar test
 * did, so the cost model's optimum moves to coarser grids (at 256x192 on
 * the bunny, soup:tris=100000 and the armadillo, lambda=1 gave 1.07-3.4
 * Mrays/s against 0.78-2.2 at lambda=2 and 0.64-2.4 at lambda=4). */
#define GRID_BLOCKS_LAMBDA 1

extern const accel_kind accel_kind_grid;

/* The kind's parameters as parsed, one field per key (grid_build.c's
 * table: ACCEL_SPEC(params, grid_spec)); choices hold their position in
 * the table's list (traverse: single 0, packet 1; skip: none, cloud, macro;
 * isa: ACCEL_ISA_AUTO, _AVX2, _AVX512, core/isa.h). */
typedef struct {
    double lambda, max_mb;
    char res[ACCEL_PARAM_TEXT];
    int overlap, mailbox, traverse, skip, skip_min, macro, cells, isa;
} grid_spec;

/* Read-only view of a built grid (tests, tools, heatmaps). */
typedef struct {
    const grid_frame *frame;
    const uint32_t *offsets; /* cell_count + 1 */
    const uint32_t *refs;    /* ref_count local primitive ids */
    const uint32_t *prim_id; /* local id -> scene primitive id */
    uint32_t prim_count;     /* local ids: the scene's live primitives */
    uint64_t cell_count, ref_count;
} grid_view;

/* Fills *v from an accelerator built by accel_kind_grid. */
void grid_get_view(const void *accel, grid_view *v);

#ifdef __cplusplus
}
#endif

#endif
