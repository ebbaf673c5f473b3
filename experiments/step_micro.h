/*
 * step_micro.h - exp_step_cost's micro-benchmarks, hot in L1 (ns per
 * operation, median of 15 samples with its interval): the scalar
 * watertight triangle test (core/prim.h), the shared block test on blocks
 * of 8 and 4 (core/block_test.h, the baseline instruction set), the slab
 * test of a binary node's two child boxes, and one 3D-DDA cell step with
 * its cell read. They give the C_intersect the step-cost fit holds fixed
 * and bound the fitted constants from below.
 */
#ifndef EXPERIMENTS_STEP_MICRO_H
#define EXPERIMENTS_STEP_MICRO_H

#include "engine/harness.h"

typedef struct {
    exp_est tri, block8, block4, node, step;
} step_micro;

void step_micro_run(exp_ctx *x, step_micro *m);

#endif
