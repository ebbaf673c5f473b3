/*
 * test_ngrid_walk.c - the nested grid's hierarchical walk against the
 * oracle (a cluster, a lattice with sub-cells aligned to the rays, flat,
 * far, tiny and empty scenes, rays from inside, axis-parallel rays with
 * +0/-0 components), per-level counters and the cross-level mailbox.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_ngrid.h"

/* ---- the hierarchical walk against the reference --------------------------------------- */

TEST(ngrid_cluster_against_reference)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 2000, 300)) return;
    test_rays r = {0};
    test_ngrid_cluster_rays(&r);
    accel_ray *rays = r.rays;
    size_t n = r.count;
    static const char *const extra[] = {"depth=4",
                                        "depth=4,threshold=2,sub_lambda=1",
                                        "sub_res=3,threshold=0,depth=4",
                                        "auto,depth=4,mailbox=0",
                                        "auto,lookahead=1",
                                        "lambda=0.01,sub_lambda=30",
                                        NULL};
    test_check_variants(&s, &accel_kind_nested_grid, extra, rays, n, TEST_ORACLE_REFERENCE);
    test_rays_free(&r);
    scene_free(&s);
}

/*
 * The lattice: bounds [0,4]^3, triangles with vertices on the 1/4 lattice,
 * some lying in lattice planes. With res=4 and sub_res=2 the sub-cells of
 * every level have lattice boundaries too (1, 1/2, 1/4), so rays between
 * lattice points run along cell edges and through cell corners at every
 * level, and start on sub-grid boundaries.
 */
TEST(ngrid_lattice_edges_and_corners)
{
    scene_builder b = {0};
    test_seed(31337);
    for (int i = 0; i < 400; i++) {
        vec3 base = v3(test_rand_lattice(0, 0.25f, 15), test_rand_lattice(0, 0.25f, 15),
                       test_rand_lattice(0, 0.25f, 15));
        vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = v3_add(base, v3(test_rand_lattice(0, 0.25f, 3), test_rand_lattice(0, 0.25f, 3),
                                   test_rand_lattice(0, 0.25f, 3)));
        test_add_tri(&b, p[0], p[1], p[2]);
    }
    test_add_tri(&b, v3(2, 0.5f, 0.5f), v3(2, 1.5f, 0.5f), v3(2, 1.5f, 1.5f));
    test_add_tri(&b, v3(0.5f, 1.25f, 2.5f), v3(1.5f, 1.25f, 2.5f), v3(1.5f, 1.25f, 3.5f));
    test_add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0));
    test_add_tri(&b, v3(4, 4, 4), v3(3.99f, 4, 4), v3(4, 3.99f, 4));
    accel_scene s;
    if (!test_finish(&b, "lattice", &s)) return;
    /* Between lattice points (origins up to 1 outside the box), and along
     * lattice lines from before, past and the middle of the box. */
    const box3 box = {{0, 0, 0}, {4, 4, 4}};
    test_rays r = {0};
    test_rays_lattice_points(&r, box, 0.25f, 1.0f, 7000, NULL);
    test_rays_axis_lattice(&r, box, 0.25f, 2,
                           TEST_START_BEFORE | TEST_START_AFTER | TEST_START_MIDDLE, NULL);
    static const char *const extra[] = {"res=4,sub_res=2,threshold=0,depth=3",
                                        "res=4,sub_res=2,threshold=0,depth=4",
                                        "res=2,sub_res=4,threshold=3,depth=3",
                                        "res=4,sub_res=2,threshold=0,depth=4,overlap=bbox",
                                        "res=1,sub_res=2,threshold=0,depth=4,mailbox=0",
                                        NULL};
    /* Along lattice edges the float kernel and the reference may both be
     * right within rounding yet differ: the float brute force is the oracle
     * here, so any difference is a cell the walk skipped. */
    test_check_variants(&s, &accel_kind_nested_grid, extra, r.rays, r.count,
                        TEST_ORACLE_FLOAT_BRUTE);
    test_rays_free(&r);
    scene_free(&s);
}

/* Flat, far and tiny scenes, with rays starting far away. */
TEST(ngrid_flat_far_tiny_scenes)
{
    static const float offsets[] = {0.0f, 1e4f, 0.0f};
    static const float scales[] = {1.0f, 1.0f, 1e-4f};
    for (int c = 0; c < 3; c++) {
        scene_builder b = {0};
        accel_error err = {0};
        test_seed(40 + c);
        float o = offsets[c], sc = scales[c];
        int flat = c == 0;
        for (int i = 0; i < 3000; i++) {
            /* Dense in one corner, sparse elsewhere. */
            float span = i < 2500 ? 0.5f : 8.0f;
            vec3 p = v3(o + sc * test_rand_in(0, span), o + sc * test_rand_in(0, span),
                        flat ? 0.0f : o + sc * test_rand_in(0, span));
            vec3 q =
                v3_add(p, v3(sc * test_rand_in(-.05f, .05f), sc * test_rand_in(-.05f, .05f), 0));
            vec3 r = v3_add(p, v3(sc * test_rand_in(-.05f, .05f), sc * test_rand_in(-.05f, .05f),
                                  flat ? 0.0f : sc * test_rand_in(-.05f, .05f)));
            scene_builder_add_tri(&b, p, q, r, &err);
        }
        accel_scene s;
        if (!test_finish(&b, c == 0 ? "flat" : (c == 1 ? "far" : "tiny"), &s)) return;
        size_t n = 3000;
        accel_ray *rays = malloc(n * sizeof *rays);
        if (!rays) return;
        for (size_t i = 0; i < n; i++) {
            float reach = i % 4 == 0 ? 1000.0f : 10.0f;
            vec3 org =
                v3(o + sc * test_rand_in(-reach, reach), o + sc * test_rand_in(-reach, reach),
                   o + sc * test_rand_in(-reach, reach));
            float span = i % 2 ? 0.5f : 8.0f;
            vec3 tgt = v3(o + sc * test_rand_in(0, span), o + sc * test_rand_in(0, span),
                          flat ? 0.0f : o + sc * test_rand_in(0, span));
            if (flat && i % 5 == 0) org.z = 0.0f; /* in the plane */
            vec3 d = v3_sub(tgt, org);
            if (flat && i % 10 == 0) d.z = (i & 32) ? -0.0f : 0.0f;
            rays[i] = test_ray(org, d, 0.0f, INFINITY);
        }
        static const char *const extra[] = {"threshold=1,depth=3", NULL};
        test_check_variants(&s, &accel_kind_nested_grid, extra, rays, n, TEST_ORACLE_REFERENCE);
        free(rays);
        scene_free(&s);
    }
}

/* No live primitive (only degenerate triangles): builds, misses everything. */
TEST(ngrid_empty_scene)
{
    scene_builder b = {0};
    accel_error err = {0};
    scene_builder_add_tri(&b, v3(0, 0, 0), v3(1, 1, 1), v3(2, 2, 2), &err);
    accel_scene s;
    if (!test_finish(&b, "degenerate", &s)) return;
    accel_ray rays[3] = {test_ray(v3(-1, -1, -1), v3(1, 1, 1), 0, INFINITY),
                         test_ray(v3(0.5f, 0.5f, 0.5f), v3(0, 0, 1), 0, INFINITY),
                         test_ray(v3(0, 0, 0), v3(1, 1, 1), 0, 1)};
    test_check_variants(&s, &accel_kind_nested_grid, NULL, rays, 3, TEST_ORACLE_REFERENCE);
    scene_free(&s);
}

/* ---- counters and mailbox ---------------------------------------------------------------- */

TEST(ngrid_counters_and_mailbox)
{
    /* Long thin triangles across the cluster's sub-cells: the mailbox is
     * what stops them from being tested in every cell. */
    scene_builder b = {0};
    accel_error err = {0};
    test_seed(5);
    for (int i = 0; i < 3000; i++) {
        vec3 p = v3(test_rand_in(0, 1), test_rand_in(0, 1), test_rand_in(0, 1));
        vec3 q = v3(test_rand_in(0, 1), test_rand_in(0, 1), test_rand_in(0, 1));
        scene_builder_add_tri(&b, p, q, v3_add(p, v3(0.01f, 0.01f, 0.0f)), &err);
    }
    scene_builder_add_tri(&b, v3(-50, -50, -50), v3(50, -50, -50), v3(-50, 50, 50), &err);
    accel_scene s;
    if (!test_finish(&b, "needles", &s)) return;
    size_t n = 2000;
    accel_ray *rays = malloc(n * sizeof *rays);
    if (!rays) return;
    for (size_t i = 0; i < n; i++) {
        vec3 o = v3(test_rand_in(-3, 4), test_rand_in(-3, 4), test_rand_in(-3, 4));
        vec3 t = v3(test_rand_in(0, 1), test_rand_in(0, 1), test_rand_in(0, 1));
        rays[i] = test_ray(o, v3_sub(t, o), 0.0f, INFINITY);
    }
    accel_counters on, off;
    accel_build_stats st;
    test_check_spec(&s, "nested_grid:threshold=8", rays, n, NULL, &st, &on);
    test_check_spec(&s, "nested_grid:threshold=8,mailbox=0", rays, n, NULL, NULL, &off);
    CHECKF(st.depth >= 2, "depth %d", st.depth);
    CHECKF(on.mailbox_skips > 0 && off.mailbox_skips == 0, "skips %llu / %llu",
           (unsigned long long)on.mailbox_skips, (unsigned long long)off.mailbox_skips);
    CHECKF(on.prim_tests + on.mailbox_skips == off.prim_tests && on.steps == off.steps,
           "mailbox: %llu tests + %llu skips, without: %llu tests; steps %llu / %llu",
           (unsigned long long)on.prim_tests, (unsigned long long)on.mailbox_skips,
           (unsigned long long)off.prim_tests, (unsigned long long)on.steps,
           (unsigned long long)off.steps);
    /* Per-ray arrays add up to the totals. */
    const accel_kind *kind;
    void *a;
    if (accel_build_spec("nested_grid:threshold=8", &s, 1, &kind, &a, &st, &err) == 0) {
        uint32_t *rs = calloc(n, sizeof *rs), *rp = calloc(n, sizeof *rp);
        accel_hit *h = malloc(n * sizeof *h);
        uint8_t *occ = malloc(n);
        if (rs && rp && h && occ) {
            accel_counters c;
            memset(&c, 0, sizeof c);
            c.ray_steps = rs;
            c.ray_prims = rp;
            kind->intersect(a, rays, h, n, &c);
            uint64_t ss = 0, sp = 0;
            for (size_t i = 0; i < n; i++) ss += rs[i], sp += rp[i];
            CHECKF(ss == c.steps && sp == c.prim_tests && c.box_tests == n,
                   "per-ray sums %llu/%llu, totals %llu/%llu", (unsigned long long)ss,
                   (unsigned long long)sp, (unsigned long long)c.steps,
                   (unsigned long long)c.prim_tests);
            /* Any-hit stops early: never more tests than closest-hit. */
            accel_counters co;
            memset(&co, 0, sizeof co);
            kind->occluded(a, rays, occ, n, &co);
            CHECKF(co.prim_tests <= c.prim_tests && co.rays == n,
                   "occluded %llu tests, closest %llu", (unsigned long long)co.prim_tests,
                   (unsigned long long)c.prim_tests);
        }
        free(rs);
        free(rp);
        free(h);
        free(occ);
        kind->destroy(a);
    }
    free(rays);
    scene_free(&s);
}
