/*
 * grid_walk.c - accel.h's conservative walk for the grid kind, which lets
 * a grid serve as instanced's bottom level (instanced:bottom=grid:...).
 *
 * A "fat" 3D-DDA: the ray is cut into pieces, one per cell the grid's own
 * DDA (grid_core.h, Amanatides and Woo 1987, with its robustness contract)
 * visits, plus the pieces before the grid's box and after it that still
 * lie within the pad of it. Each piece's bounding box, grown by the pad
 * (and a margin over the double rounding of its end points), is turned
 * into the range of cells it touches (grid_cell_range, whose padded cells
 * are the builder's membership test), and every primitive of those cells
 * is handed to the visitor. A primitive within the pad of a point of the
 * ray then lies in a cell of that range: the walk misses none. Pieces come
 * nearest first; a small mailbox drops most repeated visits of a
 * primitive listed in neighbouring cells (the contract allows repeats, so
 * a mailbox miss only costs a visit). When the pad is below the membership
 * padding (pad = 0: a plain trace) the range is the DDA's own cell.
 */
#include <math.h>
#include <string.h>

#include "grid_core.h"
#include "grid_impl.h"

#define WALK_MAILBOX 16

typedef struct {
    const grid_accel *g;
    accel_ray_prep p;
    double o[3], d[3];
    float pad, t_max;
    accel_walk_visit visit;
    void *ctx;
    uint32_t *steps;
    uint32_t mailbox[WALK_MAILBOX];
} walker;

/* Float bound of a double, rounded outward. */
static float down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}
static float up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

/* Visits every primitive of the cells the piece [ta, tb] of the ray,
 * grown by the pad, touches. Returns 0 when the visitor ended the walk. */
static int visit_piece(walker *w, double ta, double tb)
{
    const grid_frame *f = &w->g->frame;
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        double pa = w->o[a] + ta * w->d[a], pb = w->o[a] + tb * w->d[a];
        double m = w->pad + 0x1p-40 * (fabs(w->o[a]) + fabs(pa) + fabs(pb)) + 1e-300;
        lo[a] = (pa < pb ? pa : pb) - m;
        hi[a] = (pa < pb ? pb : pa) + m;
    }
    box3 b = {{down(lo[0]), down(lo[1]), down(lo[2])}, {up(hi[0]), up(hi[1]), up(hi[2])}};
    int c0[3], c1[3];
    if (!grid_cell_range(f, b, c0, c1)) return 1;
    const grid_cells *cells = &w->g->cells;
    const uint32_t *scene_id = w->g->store.scene_id;
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                uint32_t cell = x * f->stride[0] + y * f->stride[1] + z * f->stride[2];
                (*w->steps)++;
                for (uint32_t i = cells->offsets[cell]; i < cells->offsets[cell + 1]; i++) {
                    uint32_t local = cells->refs[i], *slot = &w->mailbox[local % WALK_MAILBOX];
                    if (*slot == local) continue;
                    *slot = local;
                    w->t_max = w->visit(w->ctx, scene_id[local], w->t_max);
                    if (w->t_max < w->p.t_near) return 0;
                }
            }
    return 1;
}

int grid_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit,
              void *ctx, uint32_t *steps)
{
    if (!visit) return 0;
    walker w;
    w.g = accel;
    if (!accel_prep_ray(ray, &w.p)) return 0;
    const grid_frame *f = &w.g->frame;
    w.pad = pad, w.t_max = w.p.t_far, w.visit = visit, w.ctx = ctx, w.steps = steps;
    memset(w.mailbox, 0xFF, sizeof w.mailbox);
    const float of[3] = {w.p.org.x, w.p.org.y, w.p.org.z}, df[3] = {w.p.dir.x, w.p.dir.y, w.p.dir.z};
    /* The ray clipped to the grid's box grown by the pad (and its
     * membership padding), in double with a relative slack. */
    double s0 = w.p.t_near, s1 = w.p.t_far;
    for (int a = 0; a < 3; a++) {
        w.o[a] = of[a], w.d[a] = df[a];
        double lo = (double)f->lo[a] - pad - f->pad[a], hi = (double)f->hi[a] + pad + f->pad[a];
        if (df[a] == 0.0f) {
            if (w.o[a] < lo || w.o[a] > hi) return 0;
            continue;
        }
        double t0 = (lo - w.o[a]) / w.d[a], t1 = (hi - w.o[a]) / w.d[a];
        if (t0 > t1) { double x = t0; t0 = t1; t1 = x; }
        double slack = 0x1p-40 * (fabs(t0) + fabs(t1));
        s0 = t0 - slack > s0 ? t0 - slack : s0;
        s1 = t1 + slack < s1 ? t1 + slack : s1;
    }
    if (!(s0 <= s1)) return 0;
    float e;
    if (!box3_slab(f->lo, f->hi, w.p.org, w.p.inv_dir, w.p.neg, w.p.t_near, w.p.t_far, &e)) {
        visit_piece(&w, s0, s1 < w.t_max ? s1 : w.t_max);
        return 0;
    }
    grid_dda dda;
    double t = grid_dda_init(&dda, f, &w.p, w.p.t_near);
    /* Before the grid's box, within the pad of it. */
    if (s0 < t && !visit_piece(&w, s0, t)) return 0;
    for (;;) {
        if (t > w.t_max) return 0;
        double x = grid_dda_exit(&dda);
        if (!visit_piece(&w, t, x < w.t_max ? x : w.t_max)) return 0;
        t = x;
        if (!grid_dda_step(&dda)) break;
    }
    /* After it, within the pad of it. */
    if (t < s1 && t <= w.t_max) visit_piece(&w, t, s1 < w.t_max ? s1 : w.t_max);
    return 0;
}
