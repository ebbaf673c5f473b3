/*
 * ngrid_kernel.h - the `nested_grid` kind's single-ray walk (described in
 * ngrid_trace.c), with the leaf lists as ids or as blocks (use_blocks, a
 * constant of the copy). A kernel body (C only), private to nested_grid/:
 * ngrid_trace.c compiles the copies on ids, the kernel unit k8_cells.c
 * those on blocks, once per ISA (core/isa.h), since they inline the shared
 * block test.
 */
#ifndef NESTED_GRID_NGRID_KERNEL_H
#define NESTED_GRID_NGRID_KERNEL_H

#include "core/variant.h"
#include "ngrid_impl.h"

static inline __attribute__((always_inline)) void
ngrid_kernel(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres, int mailbox, int use_blocks)
{
    const accel_scene *s = &g->store.prims;
    const ngrid_node *nodes = g->nodes;
    const grid_frame *top = &nodes[0].frame;
    const uint32_t *lists = g->lists;
    /* cells=blocks: the shared block test (grid/grid_blocks.h), a constant
     * of the copy: compiled by the kernel unit k8_cells.c only (once per
     * ISA), for triangles with the watertight test and no mailbox. */
    const grid_list_blocks *blocks = use_blocks ? &g->blocks : NULL;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t steps = 0, empty = 0, tests = 0, skips = 0, boxes = 0;
        uint32_t level_steps[NGRID_MAX_LEVELS] = {0};
        if (grid_ray_enter(top, &rays[i], g->ref_count > 0, &p, &boxes)) {
            /* Set up the top-level 3D DDA for the ray. The current level's
             * walk lives in `d` (registers); the parents' walks wait on a
             * small stack while a sub-grid is walked. Distances are doubles
             * (grid_core.h); t_cell is where the ray entered the current
             * cell, at whatever level. */
            grid_dda d, parents[NGRID_MAX_LEVELS - 1];
            const uint32_t *parent_words[NGRID_MAX_LEVELS - 1];
            int level = 0;
            double t_cell = grid_dda_init(&d, top, &p, p.t_near);
            const uint32_t *words = g->cells + nodes[0].cell_base;
            uint32_t box[GRID_MAILBOX];
            wide_leaf_ray_8 lr; /* a few broadcasts: set always, used by blocks */
            leaf_setup_8(&lr, &p);
            if (mailbox) grid_mailbox_clear(box);
            float t = p.t_far, u = 0.0f, v = 0.0f;
            /* Walk the ray through the cells, descending into sub-grids. */
            for (;;) {
                if (c) {
                    steps++;
                    level_steps[level]++;
                }
                if (ACCEL_STEP_BOUND_BROKEN(c, steps, g->step_bound)) break;
                uint32_t w = words[d.cell];
                if (w & NGRID_CHILD) {
                    /* Continue in the sub-grid from the ray's entry into this cell. */
                    const ngrid_node *child = &nodes[w & ~NGRID_CHILD];
                    parents[level] = d;
                    parent_words[level] = words;
                    level++;
                    words = g->cells + child->cell_base;
                    grid_dda_init(&d, &child->frame, &p, t_cell);
                    continue;
                }
                const uint32_t *list = lists + w;
                uint32_t n = list[0];
                if (c && n == 0) empty++;
                if (blocks) {
                    if (c) tests += n;
                    uint32_t b0 = blocks->first[w];
                    if (n && grid_blocks_hit(blocks->blocks, b0, b0 + (n + 7) / 8, s->tri_count,
                                             &lr, &p, &h, &t, &u, &v, occ != NULL))
                        goto done;
                } else if (grid_cell_hit(s, list + 1, n, &p, &h, &t, &u, &v, box, &tests, &skips,
                                         c, occ != NULL, naive, spheres, mailbox)) {
                    goto done;
                }
                /* A hit (or the ray's end) before this cell's exit: nothing
                 * in a later cell, at any level, can be nearer. */
                double t_exit = grid_dda_exit(&d);
                if (t_exit >= t) break;
                /* Next cell of this grid; once the ray leaves a sub-grid,
                 * the parent's walk resumes with its next cell. */
                while (!grid_dda_step(&d)) {
                    if (level == 0) goto done;
                    level--;
                    d = parents[level];
                    words = parent_words[level];
                }
                t_cell = t_exit;
            }
        }
    done:
        accel_prim_store_answer(&g->store, h, hits, occ, i);
        if (c) {
            accel_count_ray(c, i, steps, empty, boxes, tests, skips);
            for (int l = 0; l < NGRID_MAX_LEVELS; l++) c->level_steps[l] += level_steps[l];
        }
    }
}

/* The blocks' tables (k8_cells.c): query 0 closest hit, 1 any hit; the
 * AVX2 copy and, where the build has it, the AVX-512 one. */
const accel_kernel_table *ngrid_k8_cells(int query);
const accel_kernel_table *ngrid_k8_cells_avx512(int query);

#endif
