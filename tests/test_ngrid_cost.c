/*
 * test_ngrid_cost.c - the nested grid's cost model against a Monte
 * Carlo estimate (isotropic random lines crossing a box), and auto mode's
 * response to its costs.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_ngrid.h"

/* ---- the cost model ------------------------------------------------------------------ */

/* Isotropic random lines crossing a box: the entry point is uniform over
 * the surface and the direction cosine-distributed about the inward normal.
 * The mean number of cells the DDA visits must match ngrid_expected_cells,
 * and the fraction of lines crossing a sub-box its area ratio. */
TEST(ngrid_cost_model_matches_random_lines)
{
    static const int shapes[][3] = {{8, 8, 8}, {20, 3, 7}, {1, 1, 30}};
    const float ext[3] = {2.0f, 1.0f, 3.0f};
    for (int k = 0; k < 3; k++) {
        box3 box = {{0, 0, 0}, {ext[0], ext[1], ext[2]}};
        float planes[64];
        grid_frame f;
        grid_frame_init(&f, box, shapes[k], planes);
        double area[3] = {ext[1] * ext[2], ext[2] * ext[0], ext[0] * ext[1]};
        double total = area[0] + area[1] + area[2];
        box3 inner = {{0.5f, 0.2f, 1.0f}, {1.0f, 0.6f, 2.5f}};
        double inner_ratio = (0.5 * 0.4 + 0.4 * 1.5 + 1.5 * 0.5) / total;
        test_seed(777 + k);
        const int lines = 40000;
        double cells = 0;
        int through_inner = 0;
        for (int i = 0; i < lines; i++) {
            double pick = test_rand() * total;
            int axis = pick < area[0] ? 0 : (pick < area[0] + area[1] ? 1 : 2);
            int side = test_rand() < 0.5f;
            float o[3] = {test_rand() * ext[0], test_rand() * ext[1], test_rand() * ext[2]};
            o[axis] = side ? ext[axis] : 0.0f;
            /* Cosine-weighted about the inward normal (Malley's method). */
            float r = sqrtf(test_rand()), phi = 6.2831853f * test_rand();
            float d[3];
            int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            d[a1] = r * cosf(phi);
            d[a2] = r * sinf(phi);
            d[axis] = sqrtf(fmaxf(0.0f, 1.0f - r * r)) * (side ? -1.0f : 1.0f);
            if (d[axis] == 0.0f) continue;
            accel_ray ray = {o[0], o[1], o[2], 0.0f, d[0], d[1], d[2], INFINITY};
            accel_ray_prep p;
            if (!accel_prep_ray(&ray, &p)) continue;
            grid_dda dda;
            grid_dda_init(&dda, &f, &p, 0.0);
            int count = 1;
            while (grid_dda_step(&dda)) count++;
            cells += count;
            float t0;
            through_inner +=
                box3_slab(&inner.min.x, &inner.max.x, p.org, p.inv_dir, p.neg, 0.0f, INFINITY, &t0);
        }
        double measured = cells / lines, predicted = ngrid_expected_cells(&f);
        CHECKF(fabs(measured - predicted) < 0.02 * predicted,
               "%dx%dx%d: %.3f cells crossed on average, model %.3f", shapes[k][0], shapes[k][1],
               shapes[k][2], measured, predicted);
        double frac = (double)through_inner / lines;
        CHECKF(fabs(frac - inner_ratio) < 0.02, "sub-box crossed by %.3f of the lines, model %.3f",
               frac, inner_ratio);
        double cell_p = ngrid_cell_probability(&f);
        double cx = (double)ext[0] / shapes[k][0], cy = (double)ext[1] / shapes[k][1];
        double cz = (double)ext[2] / shapes[k][2], want = (cx * cy + cy * cz + cz * cx) / total;
        CHECKF(fabs(cell_p - want) < 1e-9 * want, "cell probability %g, want %g", cell_p, want);
    }
    int cube[3] = {5, 6, 7};
    box3 unit = {{0, 0, 0}, {1, 1, 1}};
    float planes[32];
    grid_frame f;
    grid_frame_init(&f, unit, cube, planes);
    CHECKF(fabs(ngrid_expected_cells(&f) - 6.0) < 1e-9, "cube: (5+6+7)/3 = 6, got %g",
           ngrid_expected_cells(&f));
}

/* Auto mode follows its costs: cheap tests never subdivide, cheap steps do. */
TEST(ngrid_auto_follows_costs)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 4000, 0)) return;
    accel_error err = {0};
    void *a;
    accel_build_stats cheap_tests, cheap_steps, dflt;
    int ok = test_ngrid_build("nested_grid:auto,c_step=100,c_isect=0.01", &s, 1, &a, &cheap_tests,
                              &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    ok = test_ngrid_build("nested_grid:auto,c_step=0.01,c_isect=100", &s, 1, &a, &cheap_steps,
                          &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    ok = test_ngrid_build("nested_grid:auto", &s, 1, &a, &dflt, &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    CHECKF(cheap_tests.depth == 1 && cheap_steps.depth >= 2 && dflt.depth >= 2,
           "depths: cheap tests %d, cheap steps %d, default %d", cheap_tests.depth,
           cheap_steps.depth, dflt.depth);
    /* The lookahead prices dense cells by their future sub-grids: the top
     * level comes out no finer than without it. */
    accel_build_stats ahead;
    ok = test_ngrid_build("nested_grid:auto,lookahead=1", &s, 1, &a, &ahead, &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    CHECKF((uint64_t)ahead.res[0] * ahead.res[1] * ahead.res[2] <=
               (uint64_t)dflt.res[0] * dflt.res[1] * dflt.res[2],
           "top level with lookahead %dx%dx%d, without %dx%dx%d", ahead.res[0], ahead.res[1],
           ahead.res[2], dflt.res[0], dflt.res[1], dflt.res[2]);
    CHECKF(cheap_tests.nodes < dflt.nodes && dflt.nodes < cheap_steps.nodes,
           "cells: cheap tests %llu, default %llu, cheap steps %llu",
           (unsigned long long)cheap_tests.nodes, (unsigned long long)dflt.nodes,
           (unsigned long long)cheap_steps.nodes);
    /* Auto beats the flat grid at its own top resolution on the cluster. */
    test_rays r = {0};
    test_ngrid_cluster_rays(&r);
    if (!r.failed) {
        const accel_ray *rays = r.rays;
        accel_counters c_auto, c_flat;
        char flat[96];
        snprintf(flat, sizeof flat, "nested_grid:depth=1,res=%dx%dx%d", dflt.res[0], dflt.res[1],
                 dflt.res[2]);
        test_check_spec(&s, "nested_grid:auto", rays, 2500, NULL, NULL, &c_auto);
        test_check_spec(&s, flat, rays, 2500, NULL, NULL, &c_flat);
        const double cs = NGRID_DEFAULT_C_STEP, ci = NGRID_DEFAULT_C_ISECT;
        double cost_auto = cs * c_auto.steps + ci * c_auto.prim_tests;
        double cost_flat = cs * c_flat.steps + ci * c_flat.prim_tests;
        CHECKF(cost_auto < 0.5 * cost_flat, "model cost per ray: auto %.1f, flat %.1f",
               cost_auto / 2500, cost_flat / 2500);
    }
    test_rays_free(&r);
    scene_free(&s);
}

/* cells=blocks prices a test at NGRID_BLOCKS_C_ISECT unless c_isect is
 * given: with c_isect=13 written out the block build has the per-id
 * build's structure exactly; without it, cheaper tests make no finer a
 * structure (no more cells, no more levels) than the per-id default; a
 * scene with spheres (no blocks) keeps the per-id price. */
TEST(ngrid_auto_blocks_price_their_test)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 4000, 0)) return;
    static const char *const specs[3] = {"nested_grid:auto", "nested_grid:auto,cells=blocks,c_isect=13",
                                         "nested_grid:auto,cells=blocks"};
    accel_build_stats st[3];
    accel_error err = {0};
    for (int i = 0; i < 3; i++) {
        void *a;
        int ok = test_ngrid_build(specs[i], &s, 1, &a, &st[i], &err) == 0;
        CHECKF(ok, "%s: %s", specs[i], err.msg);
        if (!ok) {
            scene_free(&s);
            return;
        }
        accel_kind_nested_grid.destroy(a);
    }
    CHECKF(st[1].nodes == st[0].nodes && st[1].refs == st[0].refs && st[1].depth == st[0].depth &&
               !memcmp(st[1].res, st[0].res, sizeof st[0].res),
           "c_isect=13 on blocks: %llu cells, %llu refs, depth %d; ids %llu, %llu, %d",
           (unsigned long long)st[1].nodes, (unsigned long long)st[1].refs, st[1].depth,
           (unsigned long long)st[0].nodes, (unsigned long long)st[0].refs, st[0].depth);
    CHECKF(st[2].nodes < st[0].nodes && st[2].depth <= st[0].depth,
           "blocks' price: %llu cells, depth %d; ids %llu cells, depth %d",
           (unsigned long long)st[2].nodes, st[2].depth, (unsigned long long)st[0].nodes,
           st[0].depth);
    scene_free(&s);
    /* Spheres: no blocks, so the per-id price and the per-id structure. */
    if (!test_ngrid_cluster_scene(&s, 2000, 50)) return;
    for (int i = 0; i < 3; i += 2) {
        void *a;
        int ok = test_ngrid_build(specs[i], &s, 1, &a, &st[i], &err) == 0;
        CHECKF(ok, "%s with spheres: %s", specs[i], err.msg);
        if (ok) accel_kind_nested_grid.destroy(a);
    }
    CHECKF(st[2].nodes == st[0].nodes && st[2].refs == st[0].refs,
           "with spheres: blocks %llu cells, ids %llu", (unsigned long long)st[2].nodes,
           (unsigned long long)st[0].nodes);
    scene_free(&s);
}
