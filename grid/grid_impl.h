/*
 * grid_impl.h - the built grid, shared by the builder (grid_build.c) and
 * the traversal (grid_trace.c). Private to grid/.
 */
#ifndef GRID_GRID_IMPL_H
#define GRID_GRID_IMPL_H

#include "grid.h"
#include "grid_skip.h"

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
    /* Empty-space skipping (grid_skip.h): skip=cloud keeps one distance
     * byte per cell, skip=macro one empty flag per block of 2^macro_shift
     * cells per axis (macro_res blocks per axis). */
    grid_skip_mode skip;
    uint8_t *skip_dist;  /* cloud: cell_count bytes */
    uint8_t *macro_empty;/* macro: macro_res[0]*[1]*[2] bytes */
    int skip_min;        /* cloud: smallest radius jumped (cells) */
    int macro_shift;
    int macro_res[3];
} grid_accel;

/* Traversal entry points (grid_trace.c). */
void grid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                    accel_counters *counters);
void grid_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded, size_t count,
                   accel_counters *counters);

#endif
