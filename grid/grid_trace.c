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
 * Kernels are written once (grid_kernel) and compiled into one variant
 * table per query and skipping mode (core/variant.h): spheres, naive
 * triangles and mailbox (ACCEL_V_OPT) as constants. The uncounted copies contain no counting code
 * and no step-bound check; counted runs check the bound nx+ny+nz+3 cells.
 */
#include <string.h>

#include "core/variant.h"
#include "grid_impl.h"

/* Entries of the per-ray mailbox (power of two). */
#define GRID_MAILBOX 16

/* In an empty cell: the box of empty cells around it that skipping knows
 * (grid_skip.h), as inclusive cell ranges; 0 when it is not worth a jump. */
static inline __attribute__((always_inline)) int
skip_box(const grid_accel *g, const grid_dda *d, grid_skip_mode skip, int lo[3], int hi[3])
{
    const grid_frame *f = &g->frame;
    if (skip == GRID_SKIP_CLOUD) {
        int r = (int)g->skip_dist[d->cell] - 1; /* every cell within r is empty */
        if (r < GRID_SKIP_MIN_RADIUS) return 0;
        for (int a = 0; a < 3; a++) {
            lo[a] = d->idx[a] - r > 0 ? d->idx[a] - r : 0;
            hi[a] = d->idx[a] + r < f->res[a] - 1 ? d->idx[a] + r : f->res[a] - 1;
        }
        return 1;
    }
    const int sh = g->macro_shift;
    size_t m = (size_t)(d->idx[0] >> sh) +
               (size_t)g->macro_res[0] *
                   ((size_t)(d->idx[1] >> sh) + (size_t)g->macro_res[1] * (size_t)(d->idx[2] >> sh));
    if (!g->macro_empty[m]) return 0;
    for (int a = 0; a < 3; a++) {
        lo[a] = d->idx[a] >> sh << sh;
        hi[a] = lo[a] + (1 << sh) - 1 < f->res[a] - 1 ? lo[a] + (1 << sh) - 1 : f->res[a] - 1;
    }
    return 1;
}

static inline __attribute__((always_inline)) void
grid_kernel(const grid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
            size_t count, accel_counters *c, int naive, int spheres, int mailbox,
            grid_skip_mode skip)
{
    const accel_scene *s = &g->store.prims;
    const grid_frame *f = &g->frame;
    const uint32_t *offsets = g->cells.offsets;
    const uint32_t *refs = g->cells.refs;
    const uint64_t bound = (uint64_t)f->res[0] + f->res[1] + f->res[2] + 3;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t steps = 0, empty = 0, tests = 0, skips = 0, boxes = 0;
        float t_entry; /* unused: grid_dda_init recomputes it in double */
        int live = accel_prep_ray(&rays[i], &p) && g->cells.ref_count > 0;
        if (live) {
            boxes = 1;
            live = box3_slab(f->lo, f->hi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &t_entry);
        }
        if (live) {
            /* Set up 3D DDA for the ray. */
            grid_dda d;
            grid_dda_init(&d, f, &p, p.t_near);
            uint32_t mail[GRID_MAILBOX];
            if (mailbox) memset(mail, 0xFF, sizeof mail); /* ACCEL_MISS: no primitive */
            float t = p.t_far, u = 0.0f, v = 0.0f;
            /* Walk the ray through the cells. */
            for (;;) {
                if (c) steps++;
                if (ACCEL_STEP_BOUND_BROKEN(c, steps, bound)) break;
                uint32_t k = offsets[d.cell], end = offsets[d.cell + 1];
                if (c && k == end) empty++;
                if (skip != GRID_SKIP_NONE && k == end) {
                    /* Jump out of a box of empty cells (grid_skip.h). */
                    int lo[3], hi[3];
                    if (skip_box(g, &d, skip, lo, hi)) {
                        if (!grid_dda_leave_box(&d, f, &p, lo, hi, t)) break;
                        continue;
                    }
                }
                for (; k < end; k++) {
                    uint32_t prim = refs[k];
                    if (mailbox) {
                        uint32_t *slot = &mail[prim & (GRID_MAILBOX - 1)];
                        if (*slot == prim) {
                            if (c) skips++;
                            continue;
                        }
                        *slot = prim;
                    }
                    if (c) tests++;
                    if (accel_prim_hit(s, prim, &p, &t, &u, &v, naive, spheres)) {
                        h.t = t, h.u = u, h.v = v, h.prim = prim; /* local id until done */
                        if (occ) goto done;
                    }
                }
                /* A hit (or the ray's end) before this cell's exit: nothing
                 * in a later cell can be nearer. */
                if (grid_dda_exit(&d) >= t) break;
                if (!grid_dda_step(&d)) break;
            }
        }
    done:
        if (h.prim != ACCEL_MISS) h.prim = g->store.scene_id[h.prim];
        if (occ)
            occ[i] = h.prim != ACCEL_MISS;
        else
            hits[i] = h;
        if (c) {
            c->rays++;
            c->steps += steps;
            c->empty_steps += empty;
            c->prim_tests += tests;
            c->mailbox_skips += skips;
            c->box_tests += boxes;
            if (c->ray_steps) c->ray_steps[i] = steps;
            if (c->ray_prims) c->ray_prims[i] = tests;
        }
    }
}

/* One table per query and skipping mode (the mode is a constant in each). */
#define GRID_KERNELS(NAME, SKIP)                                                            \
    static inline __attribute__((always_inline)) void NAME##_hit_kernel(                    \
        const void *a, const accel_ray *rays, void *out, size_t count, accel_counters *c,   \
        unsigned f)                                                                         \
    {                                                                                       \
        grid_kernel(a, rays, out, NULL, count, c, (f & ACCEL_V_NAIVE) != 0,                 \
                    (f & ACCEL_V_SPHERES) != 0, (f & ACCEL_V_OPT) != 0, SKIP);              \
    }                                                                                       \
    static inline __attribute__((always_inline)) void NAME##_occ_kernel(                    \
        const void *a, const accel_ray *rays, void *out, size_t count, accel_counters *c,   \
        unsigned f)                                                                         \
    {                                                                                       \
        grid_kernel(a, rays, NULL, out, count, c, (f & ACCEL_V_NAIVE) != 0,                 \
                    (f & ACCEL_V_SPHERES) != 0, (f & ACCEL_V_OPT) != 0, SKIP);              \
    }                                                                                       \
    ACCEL_KERNEL_TABLE(NAME##_hit_table, NAME##_hit_kernel)                                 \
    ACCEL_KERNEL_TABLE(NAME##_occ_table, NAME##_occ_kernel)

GRID_KERNELS(grid, GRID_SKIP_NONE)
GRID_KERNELS(grid_cloud, GRID_SKIP_CLOUD)
GRID_KERNELS(grid_macro, GRID_SKIP_MACRO)

static const accel_kernel_table *const grid_hit_tables[3] = {
    &grid_hit_table, &grid_cloud_hit_table, &grid_macro_hit_table};
static const accel_kernel_table *const grid_occ_tables[3] = {
    &grid_occ_table, &grid_cloud_occ_table, &grid_macro_occ_table};

static unsigned grid_flags(const grid_accel *g)
{
    return (g->naive ? ACCEL_V_NAIVE : 0u) | (g->has_spheres ? ACCEL_V_SPHERES : 0u) |
           (g->mailbox ? ACCEL_V_OPT : 0u);
}

void grid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                    accel_counters *counters)
{
    const grid_accel *g = accel;
    accel_run_kernel(grid_hit_tables[g->skip], accel, rays, hits, count, counters, grid_flags(g));
}

void grid_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded, size_t count,
                   accel_counters *counters)
{
    const grid_accel *g = accel;
    accel_run_kernel(grid_occ_tables[g->skip], accel, rays, occluded, count, counters,
                     grid_flags(g));
}
