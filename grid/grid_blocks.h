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

/* Blocks [first, end) against the ray (lr: its leaf_setup_8): the running
 * nearest hit kept as grid_cell_hit keeps it; returns 1 when an any-hit
 * query found a hit. */
static inline __attribute__((always_inline)) int
grid_blocks_hit(const accel_block8 *blocks, uint32_t first, uint32_t end, uint32_t tri_count,
                const wide_leaf_ray_8 *lr, const accel_ray_prep *p, accel_hit *h, float *t,
                float *u, float *v, int any)
{
    uint32_t id = ACCEL_MISS;
    int hit = 0;
    for (uint32_t k = first; k < end; k++)
        if (leaf_block_8(&blocks[k], lr, p, t, u, v, &id, tri_count, 0, 0, any)) {
            if (any) { /* the block test names no lane then: only "hit" counts */
                h->prim = blocks[k].id[0];
                return 1;
            }
            hit = 1;
        }
    if (hit) h->t = *t, h->u = *u, h->v = *v, h->prim = id;
    return 0;
}

/* A grid's cell `cell` (grid_cell_blocks). */
static inline __attribute__((always_inline)) int
grid_cell_hit_blocks(const grid_cell_blocks *b, uint32_t cell, uint32_t tri_count,
                     const wide_leaf_ray_8 *lr, const accel_ray_prep *p, accel_hit *h, float *t,
                     float *u, float *v, int any)
{
    return grid_blocks_hit(b->blocks, b->offsets[cell], b->offsets[cell + 1], tri_count, lr, p, h,
                           t, u, v, any);
}

/* Count-prefixed id lists (lists[w] = n, then n ids: the nested grid's
 * pool) as blocks: list w's blocks start at first[w] and number
 * (n + 7) / 8; first[] has an entry per pool word (used at list heads
 * only). Built by grid_list_blocks_build (grid_blocks.c). */
typedef struct {
    uint32_t *first;
    accel_block8 *blocks;
    uint64_t block_count, list_len;
} grid_list_blocks;

int grid_list_blocks_build(const uint32_t *lists, uint64_t list_len, const accel_scene *s,
                           double max_bytes, grid_list_blocks *out, accel_error *err);
void grid_list_blocks_free(grid_list_blocks *b);
size_t grid_list_blocks_bytes(const grid_list_blocks *b);

#endif
