/*
 * step_micro.h - exp_step_cost's micro-benchmarks (ns per operation,
 * median of 15 samples with its interval). Hot in L1: the scalar
 * watertight triangle test (core/prim.h), the shared block test on blocks
 * of 8 and 4 (core/block_test.h, the baseline instruction set), the slab
 * test of a binary node's two child boxes, and one 3D-DDA cell step with
 * its cell read. From memory (the *_mem fields): the same triangle and
 * block tests on primitives read in a shuffled order from arrays the size
 * of a scene's (STEP_MICRO_MEM_TRIS triangles: the triangle array read
 * through an id array, as the per-id cells and the binary BVH read it,
 * and the same triangles as blocks), so that every test pays the cache
 * misses of a scattered ray. The hot ones give the C_intersect the
 * step-cost fit holds fixed and bound the fitted constants from below;
 * the memory ones are printed beside them (too unsteady on a shared
 * machine to hold a fit: exp_step_cost.c, micro_per_prim).
 */
#ifndef EXPERIMENTS_STEP_MICRO_H
#define EXPERIMENTS_STEP_MICRO_H

#include "engine/harness.h"

/* The memory micro's size: soup:tris=100000's, the fit's first scene
 * (its quick run: soup:tris=4000's). */
#define STEP_MICRO_MEM_TRIS 100000
#define STEP_MICRO_MEM_TRIS_QUICK 4000

typedef struct {
    exp_est tri, block8, block4, node, step;
    exp_est tri_mem, block8_mem, block4_mem;
    int mem_tris; /* triangles in the memory micro's arrays */
} step_micro;

void step_micro_run(exp_ctx *x, step_micro *m);

#endif
