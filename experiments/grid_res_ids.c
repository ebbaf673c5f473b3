/*
 * grid_res_ids.c - exp_grid_resolution's sweep of the per-id cells
 * (grid_res_ids.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid_res_ids.h"

#define GRID_RES_IDS_MAX 16

/* lambda of "grid:cells=ids,lambda=L" (0 otherwise). */
double grid_res_ids_lambda(const char *spec)
{
    const char *l = strstr(spec, "lambda=");
    return strstr(spec, "cells=ids") && l ? atof(l + 7) : 0;
}

/* Where the optimum lay with the old kernel: the per-id cells (the scalar
 * triangle test, one reference at a time) swept over fewer lambdas, in
 * their own interleaved rounds; its best and the pick of a cost model
 * fitted on it, beside the block cells' best and pick. */
void grid_res_ids_sweep(exp_ctx *x, const accel_scene *s, const bench_sets *sets, int mask,
                        const char *block_best, grid_res_ids *r)
{
    static const double full_l[] = {1, 2, 4, 8, 16, 32};
    static const double quick_l[] = {2, 8};
    const double *ls = x->quick ? quick_l : full_l;
    int nl = x->quick ? 2 : 6;
    exp_group g;
    exp_group_init(&g, x, s, sets, mask);
    g.per_ray = 1;
    g.collapse_ms = x->quick ? 1000 : 4000;
    g.time_builds = 0;
    for (int i = 0; i < nl; i++) {
        char spec[64];
        snprintf(spec, sizeof spec, "grid:cells=ids,lambda=%g", ls[i]);
        exp_group_add(&g, spec, 0);
    }
    /* The block cells' best again, in these rounds: times of two groups
     * are not comparable (each times its own share of the rays), so the
     * ratio of the two bests is taken here. */
    exp_group_add(&g, block_best, 0);
    exp_group_run(&g);
    int best = -1, blocks = exp_group_find(&g, block_best);
    for (int c = 0; c < g.count; c++)
        if (g.cfg[c].ok && c != blocks && grid_res_ids_lambda(g.cfg[c].spec) > 0 &&
            (best < 0 || exp_group_ns(&g, c, mask).median < exp_group_ns(&g, best, mask).median))
            best = c;
    memset(r, 0, sizeof *r);
    if (best >= 0) {
        /* the per-id configurations' own fit and pick (the block row left out) */
        double sv[GRID_RES_IDS_MAX], pv[GRID_RES_IDS_MAX], yv[GRID_RES_IDS_MAX], one[GRID_RES_IDS_MAX];
        int idx[GRID_RES_IDS_MAX], m = 0, pick = -1;
        for (int c = 0; c < g.count && m < GRID_RES_IDS_MAX; c++)
            if (g.cfg[c].ok && grid_res_ids_lambda(g.cfg[c].spec) > 0) {
                sv[m] = exp_group_steps(&g, c, mask), pv[m] = exp_group_prims(&g, c, mask);
                yv[m] = exp_group_ns(&g, c, mask).median, one[m] = 1, idx[m++] = c;
            }
        const double *cols[3] = {sv, pv, one};
        exp_fit own;
        if (m >= 4 && exp_nnls(cols, 3, yv, m, &own) == 0) {
            double v = INFINITY;
            for (int i = 0; i < m; i++) {
                double e = own.coef[0] * sv[i] + own.coef[1] * pv[i] + own.coef[2];
                if (e < v) v = e, pick = idx[i];
            }
        }
        int both = blocks >= 0 && g.cfg[blocks].ok;
        r->ok = 1;
        r->best_l = grid_res_ids_lambda(g.cfg[best].spec);
        /* time(ids) / time(blocks); a block row left out as the same
         * structure (a scene with spheres keeps id lists) has no blocks */
        r->ratio = both ? exp_group_speedup(&g, best, blocks, mask).median : 1;
        r->blocks_apply = both && g.cfg[blocks].build.test_lanes != 0;
        r->pick_l = pick >= 0 ? grid_res_ids_lambda(g.cfg[pick].spec) : 0;
        exp_md(x, "\nThe per-id cells (`cells=ids`, the scalar test) on the same rays, lambda %g "
                  "to %g, in rounds of their own with the block cells' best (`%s`)%s: best "
                  "lambda=%g, %.2fx the time of the block cells' best; a model fitted on them "
                  "picks %s.\n",
               ls[0], ls[nl - 1], block_best,
               r->blocks_apply ? "" : " (no blocks here: the scene has spheres, so both are id lists)",
               r->best_l, r->ratio, pick >= 0 ? g.cfg[pick].spec : "nothing (too few points)");
    }
    exp_group_note(&g);
    exp_group_free(&g);
}
