/*
 * grid_blocks.h - the cell visit on primitive blocks (grid_core.h,
 * grid_cell_blocks): the shared block test (core/block_test.h, 8 lanes)
 * over a cell's blocks, the running nearest hit kept as grid_cell_hit
 * keeps it. A kernel body (C only), included by the grid family's kernel
 * units; they are compiled for the baseline instruction set (AVX2).
 *
 * No mailbox: a block is tested whole, and a triangle met again in a later
 * cell is tested again (it gives the same hit, never a different answer:
 * grid_core.h's contract point 4). Counted runs count the cell's real
 * primitives as tests (not the repeated lanes of its last block).
 */
#ifndef GRID_GRID_BLOCKS_H
#define GRID_GRID_BLOCKS_H

#include "grid_core.h"

#define WIDE_LB 8
#include "core/block_test.h"
#undef WIDE_LB

/* Cell `cell`'s blocks against the ray (lr: its leaf_setup_8); as
 * grid_cell_hit: returns 1 when an any-hit query found a hit. */
static inline __attribute__((always_inline)) int
grid_cell_hit_blocks(const grid_cell_blocks *b, uint32_t cell, uint32_t tri_count,
                     const wide_leaf_ray_8 *lr, const accel_ray_prep *p, accel_hit *h, float *t,
                     float *u, float *v, int any)
{
    uint32_t id = ACCEL_MISS;
    int hit = 0;
    for (uint32_t k = b->offsets[cell], end = b->offsets[cell + 1]; k < end; k++)
        if (leaf_block_8(&b->blocks[k], lr, p, t, u, v, &id, tri_count, 0, 0, any)) {
            if (any) { /* the block test names no lane then: only "hit" counts */
                h->prim = b->blocks[k].id[0];
                return 1;
            }
            hit = 1;
        }
    if (hit) h->t = *t, h->u = *u, h->v = *v, h->prim = id;
    return 0;
}

#endif
