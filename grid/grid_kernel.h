/*
 * grid_kernel.h - the one traversal kernel of the `grid` kind (closest hit
 * and any hit, every skipping mode), private to grid/. Described in
 * grid_trace.c. GRID_KERNELS(NAME, SKIP) compiles it into the variant
 * tables NAME_hit_table and NAME_occ_table (core/variant.h) for one
 * skipping mode.
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 *
 * Each skipping mode's tables live in their own translation unit
 * (grid_trace.c, grid_trace_cloud.c, grid_trace_macro.c): GCC's inlining
 * budget is per unit, and three modes' copies in one unit pushed the
 * sphere test out of line in all of them, the plain walk's included (+16%
 * instructions on sphereflake, callgrind).
 */
#ifndef GRID_GRID_KERNEL_H
#define GRID_GRID_KERNEL_H

#include "core/variant.h"
#include "grid_blocks.h"
#include "grid_impl.h"

#ifdef __cplusplus
extern "C" {
#endif

/* In an empty cell: the box of empty cells around it that skipping knows
 * (grid_skip.h), as inclusive cell ranges; 0 when it is not worth a jump. */
static inline __attribute__((always_inline)) int
skip_box(const grid_accel *g, const grid_dda *d, grid_skip_mode skip, int lo[3], int hi[3])
{
    const grid_frame *f = &g->frame;
    if (skip == GRID_SKIP_CLOUD) {
        int r = (int)g->skip_dist[d->cell] - 1; /* every cell within r is empty */
        if (r < g->skip_min) return 0;
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

/* The jump from an empty cell: 1 after a jump or when none is worth it
 * (*moved says which), 0 when the walk is over. */
static inline __attribute__((always_inline)) int
skip_jump(const grid_accel *g, grid_dda *d, double t_end, grid_skip_mode skip, int *moved)
{
    int lo[3], hi[3];
    *moved = skip_box(g, d, skip, lo, hi);
    if (!*moved) return 1;
    return grid_dda_leave_box(d, &g->frame, lo, hi, t_end);
}

/* The same out of line, for the copies that test spheres: inlined there it
 * pushes the sphere test out of line instead (GCC's growth limits), which
 * costs more (+24% instructions on sphereflake, callgrind) than the call. */
static __attribute__((noinline)) int skip_jump_call(const grid_accel *g, grid_dda *d, double t_end,
                                                    grid_skip_mode skip, int *moved)
{
    return skip_jump(g, d, t_end, skip, moved);
}

static inline __attribute__((always_inline)) void
grid_kernel(const grid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
            size_t count, accel_counters *c, int naive, int spheres, int mailbox,
            grid_skip_mode skip, int use_blocks)
{
    const accel_scene *s = &g->store.prims;
    const grid_frame *f = &g->frame;
    const uint32_t *offsets = g->cells.offsets;
    const uint32_t *refs = g->cells.refs;
    const uint64_t bound = (uint64_t)f->res[0] + f->res[1] + f->res[2] + 3;
    /* cells=blocks: the shared block test (grid_blocks.h), a constant of
     * the copy: only the kernel unit k8_cells.c compiles it (once per ISA),
     * for triangles with the watertight test and no mailbox (grid_build.c),
     * and grid_trace.c sends a grid with blocks there. */
    const grid_cell_blocks *blocks = use_blocks ? &g->blocks : NULL;
    (void)naive, (void)spheres, (void)mailbox;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t steps = 0, empty = 0, tests = 0, skips = 0, boxes = 0;
        if (grid_ray_enter(f, &rays[i], g->cells.ref_count > 0, &p, &boxes)) {
            /* Set up 3D DDA for the ray. */
            grid_dda d;
            grid_dda_init(&d, f, &p, p.t_near);
            uint32_t mail[GRID_MAILBOX];
            if (mailbox && !blocks) grid_mailbox_clear(mail);
            wide_leaf_ray_8 lr; /* a few broadcasts: set always, used by blocks */
            leaf_setup_8(&lr, &p);
            float t = p.t_far, u = 0.0f, v = 0.0f;
            /* Walk the ray through the cells. */
            for (;;) {
                if (c) steps++;
                if (ACCEL_STEP_BOUND_BROKEN(c, steps, bound)) break;
                uint32_t k = offsets[d.cell], end = offsets[d.cell + 1];
                if (c && k == end) empty++;
                if (skip != GRID_SKIP_NONE && k == end) {
                    /* Jump out of a box of empty cells (grid_skip.h). */
                    int moved;
                    if (!(spheres ? skip_jump_call(g, &d, t, skip, &moved)
                                  : skip_jump(g, &d, t, skip, &moved)))
                        break;
                    if (moved) continue;
                }
                /* The cell's primitives, nearest hit kept (grid_core.h). */
                if (blocks) {
                    if (c) tests += end - k;
                    if (k != end && grid_cell_hit_blocks(blocks, d.cell, s->tri_count, &lr, &p,
                                                         &h, &t, &u, &v, occ != NULL))
                        goto done;
                } else if (grid_cell_hit(s, refs + k, end - k, &p, &h, &t, &u, &v, mail, &tests,
                                         &skips, c, occ != NULL, naive, spheres, mailbox)) {
                    goto done;
                }
                /* A hit (or the ray's end) before this cell's exit: nothing
                 * in a later cell can be nearer. */
                if (grid_dda_exit(&d) >= t) break;
                if (!grid_dda_step(&d)) break;
            }
        }
    done:
        accel_prim_store_answer(&g->store, h, hits, occ, i);
        if (c) accel_count_ray(c, i, steps, empty, boxes, tests, skips);
    }
}

/* Tables per query for one skipping mode (a constant in each copy), with
 * the timed copies KEEP_HIT and KEEP_OCC (core/variant.h,
 * ACCEL_KERNEL_TABLE_SEL: the flag combinations the experiments time). */
#define GRID_KERNELS(NAME, SKIP, KEEP_HIT, KEEP_OCC)                                        \
    static inline __attribute__((always_inline)) void NAME##_mode_kernel(                  \
        const void *a, const accel_ray *rays, accel_hit *hits, uint8_t *occ, size_t count,  \
        accel_counters *c, int naive, int spheres, int mailbox)                             \
    {                                                                                       \
        grid_kernel(a, rays, hits, occ, count, c, naive, spheres, mailbox, SKIP, 0);        \
    }                                                                                       \
    ACCEL_KERNEL_PAIR_SEL(NAME, NAME##_mode_kernel, KEEP_HIT, KEEP_OCC)

/* The same on blocks (cells=blocks) for one skipping mode: triangles, the
 * watertight test, no mailbox, so the flags are always 0 (the timed copy 0
 * and the counted one; the flags passed are ignored). Compiled by the
 * kernel unit k8_cells.c, once per ISA. */
#define GRID_BLOCK_KERNELS(NAME, SKIP)                                                      \
    static inline __attribute__((always_inline)) void NAME##_mode_kernel(                  \
        const void *a, const accel_ray *rays, accel_hit *hits, uint8_t *occ, size_t count,  \
        accel_counters *c, int naive, int spheres, int mailbox)                             \
    {                                                                                       \
        (void)naive, (void)spheres, (void)mailbox;                                          \
        grid_kernel(a, rays, hits, occ, count, c, 0, 0, 0, SKIP, 1);                        \
    }                                                                                       \
    ACCEL_KERNEL_PAIR_SEL(NAME, NAME##_mode_kernel, (1, 0, 0, 0, 0, 0, 0, 0),               \
                          (1, 0, 0, 0, 0, 0, 0, 0))

/* The skipping modes' tables (grid_trace_cloud.c, grid_trace_macro.c):
 * [0] closest hit, [1] any hit. */
extern const accel_kernel_table *const grid_cloud_tables[2];
extern const accel_kernel_table *const grid_macro_tables[2];

/* The block kernels' table of a skipping mode (GRID_SKIP_*) and query (0
 * closest hit, 1 any hit), from the kernel unit k8_cells.c: the AVX2 copy
 * and, where the build has it, the AVX-512 one (core/isa.h). */
const accel_kernel_table *grid_k8_cells(int skip, int query);
const accel_kernel_table *grid_k8_cells_avx512(int skip, int query);

#ifdef __cplusplus
}
#endif

#endif
