/*
 * grid_impl.h - the built grid, shared by the builder (grid_build.c) and
 * the traversal (grid_trace.c). Private to grid/.
 */
#ifndef GRID_GRID_IMPL_H
#define GRID_GRID_IMPL_H

#include "grid.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    /* The live primitives, copied in the order of the Morton code of their
     * centroids (or in scene order with reorder=0): local ids 0..T-1 are
     * triangles, T..T+S-1 spheres, so that accel_prim_hit works on `local`
     * unchanged. Cells hold local ids; prim_id maps them back. */
    accel_scene local;
    uint32_t *prim_id;
    grid_frame frame;
    grid_cells cells;
    float *planes;      /* storage behind frame.planes */
    int naive;          /* tri=naive */
    int mailbox;        /* mailbox=1 */
    int has_spheres;
} grid_accel;

/* Traversal entry points (grid_trace.c). */
void grid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                    accel_counters *counters);
void grid_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded, size_t count,
                   accel_counters *counters);

#ifdef __cplusplus
}
#endif

#endif
