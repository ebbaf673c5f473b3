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
    /* The primitive store (accel.h): the live primitives copied in Morton
     * order (reorder=1) or scene order; cells hold local ids, and
     * store.scene_id maps a hit back. */
    accel_prim_store store;
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
