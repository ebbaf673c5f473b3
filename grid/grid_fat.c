/*
 * grid_fat.c - the "fat" 3D-DDA of grid_core.h: the cells whose boxes,
 * grown by a pad, a ray segment reaches. It serves accel.h's conservative
 * walk for the regular grid (grid_walk.c) and the nested grid (each level
 * walks its part of the segment the same way).
 *
 * The segment is cut into pieces, one per cell the grid's own DDA
 * (Amanatides and Woo 1987, with grid_core.h's robustness contract)
 * visits, plus the pieces before the grid's box and after it that still
 * lie within the pad of it (the whole segment when the ray misses the
 * box but passes within the pad). Each piece's bounding box, grown by the
 * pad and a margin over the double rounding of its end points, becomes
 * the range of cells it touches (grid_cell_range, whose padded cells are
 * the builder's membership test). A primitive within the pad of a point of
 * the segment then lies in a cell of that range (it touches the cell
 * holding its nearest point to the ray), so no candidate is missed.
 */
#include <math.h>

#include "grid_core.h"

/* The cells the piece [ta, tb] grown by the pad touches; 0 when fn ended
 * the walk. */
static int piece(const grid_frame *f, const accel_ray_prep *p, double ta, double tb, float pad,
                 grid_fat_cell_fn fn, void *ctx)
{
    const double o[3] = {p->org.x, p->org.y, p->org.z}, d[3] = {p->dir.x, p->dir.y, p->dir.z};
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        double pa = o[a] + ta * d[a], pb = o[a] + tb * d[a];
        double m = pad + 0x1p-40 * (fabs(o[a]) + fabs(pa) + fabs(pb)) + 1e-300;
        lo[a] = (pa < pb ? pa : pb) - m;
        hi[a] = (pa < pb ? pb : pa) + m;
    }
    box3 b = {{accel_float_down(lo[0]), accel_float_down(lo[1]), accel_float_down(lo[2])},
              {accel_float_up(hi[0]), accel_float_up(hi[1]), accel_float_up(hi[2])}};
    int c0[3], c1[3];
    if (!grid_cell_range(f, b, c0, c1)) return 1;
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                uint32_t cell = x * f->stride[0] + y * f->stride[1] + z * f->stride[2];
                if (!fn(ctx, cell, ta, tb)) return 0;
            }
    return 1;
}

int grid_fat_walk(const grid_frame *f, const accel_ray_prep *p, double ta, double tb, float pad,
                  const float *t_max, grid_fat_cell_fn fn, void *ctx)
{
    const float of[3] = {p->org.x, p->org.y, p->org.z}, df[3] = {p->dir.x, p->dir.y, p->dir.z};
    /* The segment clipped to the box grown by the pad and the membership
     * padding, in double with a relative slack. */
    double s0 = ta, s1 = tb;
    for (int a = 0; a < 3; a++) {
        double lo = (double)f->lo[a] - pad - f->pad[a], hi = (double)f->hi[a] + pad + f->pad[a];
        if (df[a] == 0.0f) {
            if (of[a] < lo || of[a] > hi) return 1;
            continue;
        }
        double t0 = (lo - of[a]) / df[a], t1 = (hi - of[a]) / df[a];
        if (t0 > t1) {
            double x = t0;
            t0 = t1;
            t1 = x;
        }
        double slack = 0x1p-40 * (fabs(t0) + fabs(t1));
        s0 = t0 - slack > s0 ? t0 - slack : s0;
        s1 = t1 + slack < s1 ? t1 + slack : s1;
    }
    if (!(s0 <= s1)) return 1;
    float e;
    if (!box3_slab(f->lo, f->hi, p->org, p->inv_dir, p->neg, (float)ta, (float)tb, &e))
        return piece(f, p, s0, s1 < *t_max ? s1 : *t_max, pad, fn, ctx);
    grid_dda d;
    double t = grid_dda_init(&d, f, p, ta);
    /* Before the box, within the pad of it. */
    if (s0 < t && !piece(f, p, s0, t < *t_max ? t : *t_max, pad, fn, ctx)) return 0;
    for (;;) {
        if (t > *t_max || t > s1) return 1;
        double x = grid_dda_exit(&d);
        double end = x < *t_max ? x : *t_max;
        if (!piece(f, p, t, end < s1 ? end : s1, pad, fn, ctx)) return 0;
        t = x;
        if (!grid_dda_step(&d)) break;
    }
    /* After it, within the pad of it. */
    if (t < s1 && t <= *t_max) return piece(f, p, t, s1 < *t_max ? s1 : *t_max, pad, fn, ctx);
    return 1;
}
