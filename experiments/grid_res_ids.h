/*
 * grid_res_ids.h - where the grid's optimum lay with the old kernel: the
 * per-id cells (grid:cells=ids, the scalar triangle test) swept over
 * lambda 1..32 in interleaved rounds of their own, with the block cells'
 * best timed in the same rounds (two groups time different shares of a
 * slow set, so only ratios within one group compare), and the pick of a
 * cost model fitted on the per-id rows (exp_grid_resolution's kernel
 * table).
 */
#ifndef EXPERIMENTS_GRID_RES_IDS_H
#define EXPERIMENTS_GRID_RES_IDS_H

#include "engine/group.h"

typedef struct {
    int ok;           /* the sweep ran and found a best */
    int blocks_apply; /* the block best holds blocks (not a scene with spheres) */
    double best_l;    /* the per-id cells' best lambda */
    double pick_l;    /* their own fit's pick (0: no fit) */
    double ratio;     /* time of the per-id best / the block best, same rounds */
} grid_res_ids;

/* lambda of "grid:cells=ids,lambda=L" (0 otherwise). */
double grid_res_ids_lambda(const char *spec);

/* Sweeps the per-id cells on s (the sets in mask) beside block_best (a
 * spec), writes its sentence into the section, fills *r. */
void grid_res_ids_sweep(exp_ctx *x, const accel_scene *s, const bench_sets *sets, int mask,
                        const char *block_best, grid_res_ids *r);

#endif
