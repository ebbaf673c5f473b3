/*
 * trace4.c - the wide BVH's batch entries: one kernel table
 * (core/variant.h) per width, block size and query, each compiled from the
 * templates leaf.h (the SIMD watertight leaf test) and kernel.h
 * (the traversal), instantiated by tables.h: the 4-wide tables are
 * here, the 8-wide ones in trace8.c (bvh_wide_kernels8).
 */
#include "node.h"

#define WIDE_NW 4
#include "tables.h"

static const accel_kernel_table *table_of(const bvh_wide *w, int row, int any_hit)
{
    return w->width == 8 ? bvh_wide_kernels8(row, any_hit, w->block == 8)
                         : wide_tables[row][any_hit][w->block == 8];
}

/* Packets keep their own order (octant); order=branchy selects the third
 * single-ray table, quant=1 the fourth (quantized nodes, branchy push). */
static int table_row(const bvh_wide *w)
{
    return w->packets ? 1 : w->quant ? 3 : w->order == WIDE_ORDER_BRANCHY ? 2 : 0;
}

static unsigned kernel_flags(const bvh_wide *w, int naive, int has_spheres)
{
    return accel_variant_flags(naive, has_spheres, w->order != WIDE_ORDER_DIST);
}

void bvh_wide_intersect(const bvh_wide *w, const accel_ray *rays, accel_hit *hits, size_t count,
                        accel_counters *c, int naive, int has_spheres)
{
    accel_run_kernel(table_of(w, table_row(w), 0), w, rays, hits, count, c,
                     kernel_flags(w, naive, has_spheres));
}

void bvh_wide_occluded(const bvh_wide *w, const accel_ray *rays, uint8_t *occ, size_t count,
                       accel_counters *c, int naive, int has_spheres)
{
    accel_run_kernel(table_of(w, table_row(w), 1), w, rays, occ, count, c,
                     kernel_flags(w, naive, has_spheres));
}
