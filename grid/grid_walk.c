/*
 * grid_walk.c - accel.h's conservative walk for the grid kind, which lets
 * a grid serve as instanced's bottom level (instanced:bottom=grid:...):
 * grid_core.h's fat walk over the cells (grid_fat.c: the cells whose boxes
 * grown by the pad the ray reaches, along the ray), every primitive of
 * each cell handed to the visitor through grid_core.h's cell visit: its
 * mailbox drops most repeated visits of a primitive listed in neighbouring
 * cells (the contract allows repeats, so a mailbox miss only costs a visit).
 */
#include "grid_core.h"
#include "grid_impl.h"

typedef struct {
    const grid_accel *g;
    float t_max, t_near;
    accel_walk_visit visit;
    void *ctx;
    uint32_t *steps;
    uint32_t mailbox[GRID_MAILBOX];
} walker;

/* One primitive (a local id) to the visitor; 0 once the walk is over. */
static inline __attribute__((always_inline)) int visit_prim(void *ctx, uint32_t local)
{
    walker *w = ctx;
    w->t_max = w->visit(w->ctx, w->g->store.scene_id[local], w->t_max);
    return !(w->t_max < w->t_near);
}

static int visit_cell(void *ctx, uint32_t cell, double ta, double tb)
{
    (void)ta, (void)tb;
    walker *w = ctx;
    const grid_cells *cells = &w->g->cells;
    const uint32_t begin = cells->offsets[cell];
    uint32_t skips = 0; /* not reported: the walk counts cells only */
    (*w->steps)++;
    return grid_cell_visit(cells->refs + begin, cells->offsets[cell + 1] - begin, w->mailbox,
                           &skips, visit_prim, w);
}

int grid_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit,
              void *ctx, uint32_t *steps)
{
    if (!visit) return 0;
    accel_ray_prep p;
    if (!accel_prep_ray(ray, &p)) return 0;
    walker w = {accel, p.t_far, p.t_near, visit, ctx, steps, {0}};
    grid_mailbox_clear(w.mailbox);
    grid_fat_walk(&w.g->frame, &p, p.t_near, p.t_far, pad, &w.t_max, visit_cell, &w);
    return 0;
}
