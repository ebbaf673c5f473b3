/*
 * igrid_kernel.h - the `irregular_grid` kind's walk (described in
 * igrid_trace.c), with the cells as ids or as blocks (use_blocks, a
 * constant of the copy). A kernel body (C only), private to
 * irregular_grid/: igrid_trace.c compiles the copies on ids, the kernel
 * unit k8_cells.c those on blocks, once per ISA (core/isa.h), since they
 * inline the shared block test.
 */
#ifndef IRREGULAR_GRID_IGRID_KERNEL_H
#define IRREGULAR_GRID_IGRID_KERNEL_H

#include "core/variant.h"
#include "grid/grid_blocks.h"
#include "igrid_impl.h"

/* Distance at which the ray leaves box [lo, hi) on axis a (+inf on an axis
 * it does not move along). */
static inline __attribute__((always_inline)) double
exit_t(const grid_dda *d, const grid_frame *f, int a, const igrid_cell *cell)
{
    if (d->step[a] > 0) return grid_plane_t(d, a, f->planes[a][cell->hi[a]]);
    if (d->step[a] < 0) return grid_plane_t(d, a, f->planes[a][cell->lo[a]]);
    return INFINITY;
}

/* Step 4 on axis a: the voxel at t_exit. Returns 0 when the ray leaves the
 * grid there. */
static inline __attribute__((always_inline)) int
settle(grid_dda *d, const grid_frame *f, int a, float dir, const igrid_cell *cell, double t_a,
       double t_exit)
{
    const int step = d->step[a];
    if (step == 0) return 1;
    if (t_a == t_exit) {
        int i = step > 0 ? cell->hi[a] : cell->lo[a] - 1;
        d->idx[a] = i;
        return i != d->out[a];
    }
    const float *pl = f->planes[a];
    const int near = d->idx[a];
    const int lo = step > 0 ? near : cell->lo[a], hi = step > 0 ? cell->hi[a] - 1 : near;
    double g = (d->org[a] + t_exit * dir - f->lo[a]) * f->inv_cell[a];
    int i = g >= hi ? hi : (g > lo ? (int)g : lo);
    /* Planes tied at t_exit (grid_dda_init): the first voxel of the run. */
    if (step > 0) {
        while (i > lo && grid_plane_t(d, a, pl[i]) > t_exit) i--;
        while (i < hi && grid_plane_t(d, a, pl[i + 1]) <= t_exit) i++;
        while (i > lo && grid_plane_t(d, a, pl[i - 1]) == t_exit) i--;
    } else {
        while (i < hi && grid_plane_t(d, a, pl[i + 1]) > t_exit) i++;
        while (i > lo && grid_plane_t(d, a, pl[i]) <= t_exit) i--;
        while (i < hi && grid_plane_t(d, a, pl[i + 2]) == t_exit) i++;
    }
    d->idx[a] = i;
    return 1;
}

static inline __attribute__((always_inline)) void
igrid_kernel(const igrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres, int mailbox, int use_blocks)
{
    const accel_scene *s = &g->store.prims;
    const grid_frame *f = &g->frame;
    const igrid_cell *cells = g->cells;
    const uint32_t *refs = g->refs, *map = g->map;
    const int shift = g->shift;
    /* cells=blocks, a constant of the copy: compiled by the kernel unit
     * k8_cells.c only (once per ISA). */
    const grid_cell_blocks *blocks = use_blocks ? &g->blocks : NULL;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t steps = 0, empty = 0, tests = 0, skips = 0, boxes = 0;
        if (grid_ray_enter(f, &rays[i], g->ref_count > 0, &p, &boxes)) {
            grid_dda d;
            grid_dda_init(&d, f, &p, p.t_near);
            uint32_t mail[GRID_MAILBOX];
            if (mailbox) grid_mailbox_clear(mail);
            wide_leaf_ray_8 lr; /* a few broadcasts: set always, used by blocks */
            leaf_setup_8(&lr, &p);
            float t = p.t_far, u = 0.0f, v = 0.0f;
            for (;;) {
                if (c) steps++;
                if (ACCEL_STEP_BOUND_BROKEN(c, steps, g->step_bound)) break;
                /* 1. The cell of the current voxel. */
                const igrid_cell *cell =
                    &cells[igrid_lookup(map, g->top_res, shift, d.idx[0], d.idx[1], d.idx[2])];
                /* 2. Its primitives. */
                uint32_t k = cell->begin, end = cell->end;
                if (c && k == end) empty++;
                if (blocks) {
                    /* Cell ids index the blocks' offsets (cells are
                     * numbered as their lists lie in refs). */
                    const uint32_t cid = (uint32_t)(cell - cells);
                    if (c) tests += end - k;
                    if (k != end && grid_cell_hit_blocks(blocks, cid, s->tri_count, &lr, &p, &h,
                                                         &t, &u, &v, occ != NULL))
                        goto done;
                } else if (grid_cell_hit(s, refs + k, end - k, &p, &h, &t, &u, &v, mail, &tests,
                                         &skips, c, occ != NULL, naive, spheres, mailbox)) {
                    goto done;
                }
                /* 3. Where the ray leaves the exit box. */
                double t0 = exit_t(&d, f, 0, cell), t1 = exit_t(&d, f, 1, cell);
                double t2 = exit_t(&d, f, 2, cell);
                double t_exit = t0 < t1 ? t0 : t1;
                t_exit = t_exit < t2 ? t_exit : t2;
                if (t_exit >= t) break;
                /* 4. The voxel there. */
                if (!(settle(&d, f, 0, p.dir.x, cell, t0, t_exit) &
                      settle(&d, f, 1, p.dir.y, cell, t1, t_exit) &
                      settle(&d, f, 2, p.dir.z, cell, t2, t_exit)))
                    break;
            }
        }
    done:
        accel_prim_store_answer(&g->store, h, hits, occ, i);
        if (c) accel_count_ray(c, i, steps, empty, boxes, tests, skips);
    }
}

/* The blocks' tables (k8_cells.c): query 0 closest hit, 1 any hit; the
 * AVX2 copy and, where the build has it, the AVX-512 one. */
const accel_kernel_table *igrid_k8_cells(int query);
const accel_kernel_table *igrid_k8_cells_avx512(int query);

#endif
