/*
 * grid_impl.h - the built grid, shared by the builder (grid_build.c) and
 * the traversal (grid_trace.c). Private to grid/.
 */
#ifndef GRID_GRID_IMPL_H
#define GRID_GRID_IMPL_H

#include "grid.h"

typedef struct {
    const accel_scene *scene;
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

#endif
