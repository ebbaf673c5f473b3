/*
 * region.h - a group's configurations timed per screen region (issue 38:
 * "region dependence timed per 4x4 region", not judged by a model whose
 * absolute error exceeds the effect). The primary rays of the group are
 * split by pixel into regions x regions screen tiles; in each round every
 * tile is traced by every configuration in turn (a fresh order each round,
 * reversed on every other tile; each timed sample after an untimed pass of
 * the same tile), so the times one tile compares are taken milliseconds
 * apart.
 * The choice (a configuration per tile, and the best single one) is made
 * on the odd rounds and judged on the even ones, so that picking the
 * minimum of noisy medians does not flatter the per-tile choice.
 */
#ifndef EXP_REGION_H
#define EXP_REGION_H

#include "engine/group.h"

typedef struct {
    exp_est gain;    /* time(best single) / time(a configuration per tile), per evaluation round */
    int best_single; /* index into cfgs */
    int chosen;      /* distinct configurations the tiles choose */
    int rounds;      /* evaluation rounds */
} exp_region_result;

/* Times cfgs[0..n) of g (built, measured: cfg[].ok) per tile over
 * 2 * half_rounds rounds. Returns 0, or -1 (no primary rays with pixels,
 * fewer than 2 configurations, out of memory). */
int exp_region_time(exp_ctx *x, const exp_group *g, const int *cfgs, int n, int regions,
                    int half_rounds, exp_region_result *out);

#endif
