/*
 * grid_trace.c - traversal of the `grid` kind: the 3D-DDA of Amanatides &
 * Woo (Eurographics 1987) over the compact cells, closest-hit and any-hit.
 *
 * Per ray: clip to the grid box with the robust slab test (geom.h), set up
 * the DDA at the entry distance (grid_dda_init), then walk cells in order.
 * Every primitive of a cell is tested against the whole ray (not against
 * the cell), and the nearest hit so far is kept even when it lies beyond
 * the current cell; the walk stops once the current cell's exit distance
 * reaches that hit, so the first hit accepted is the nearest one and a
 * primitive tested early is never lost (this is what makes mailboxing safe
 * without remembering per-primitive distances).
 *
 * Mailboxing (Amanatides & Woo 1987; per-ray rather than per-object
 * so that any number of threads can trace at once): a 16-entry direct-mapped
 * cache of the ids tested by this ray, on the stack. A primitive that spans
 * several consecutive cells is found in it and skipped; a collision only
 * costs a repeated test, never a wrong answer.
 *
 * Empty-space skipping (skip=cloud|macro, grid_skip.h): in an empty cell
 * inside a known box of empty cells, the walk jumps to where the ray leaves
 * the box, re-locating its cell on the same plane distances.
 *
 * Kernels are written once (grid_kernel, in grid_kernel.h) and compiled
 * into one variant table per query and skipping mode (core/variant.h):
 * spheres, naive triangles and mailbox (ACCEL_V_OPT) as constants. The
 * uncounted copies contain no counting code and no step-bound check;
 * counted runs check the bound nx+ny+nz+3 cells. The kernels on blocks
 * (cells=blocks) live in the kernel unit k8_cells.c, compiled once per
 * ISA (core/isa.h); grid_table picks the grid's.
 */
#include "core/isa.h"
#include "grid_kernel.h"

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): mailbox=0 (index 0), the default on triangles (4) and spheres (6),
 * and closest hits with the naive test (5). */
GRID_KERNELS(grid, GRID_SKIP_NONE, (1, 0, 0, 0, 1, 1, 1, 0), (1, 0, 0, 0, 1, 0, 1, 0))

/* The table of g's skipping mode; query 0: closest hit, 1: any hit. With
 * cells=blocks the kernel unit's (k8_cells.c) of the grid's isa. */
static const accel_kernel_table *grid_table(const grid_accel *g, int query)
{
    if (g->blocks.offsets) {
#ifdef GRIDBVH_AVX512
        if (g->isa == ACCEL_ISA_AVX512) return grid_k8_cells_avx512(g->skip, query);
#endif
        return grid_k8_cells(g->skip, query);
    }
    if (g->skip == GRID_SKIP_CLOUD) return grid_cloud_tables[query];
    if (g->skip == GRID_SKIP_MACRO) return grid_macro_tables[query];
    return query ? &grid_occ_table : &grid_hit_table;
}

void grid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                    accel_counters *counters)
{
    const grid_accel *g = accel;
    accel_run_kernel(grid_table(g, 0), accel, rays, hits, count, counters, grid_variant_flags(g));
}

void grid_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded, size_t count,
                   accel_counters *counters)
{
    const grid_accel *g = accel;
    accel_run_kernel(grid_table(g, 1), accel, rays, occluded, count, counters,
                     grid_variant_flags(g));
}
