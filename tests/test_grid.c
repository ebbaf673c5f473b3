/*
 * test_grid.c - grid-specific tests: the resolution rule, res parsing,
 * overflow refusal, DDA step counts, mailboxing and counters, and identical
 * builds with 1 and 2 threads. The overlap tests of overlap.h are in
 * test_grid_overlap.c, the traversal's edge cases in test_grid_dda.c.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid/grid.h"
#include "grid/grid_core.h"
#include "support.h"

/* ---- resolution rule and sizing --------------------------------------------- */

TEST(grid_resolution_rule)
{
    int r[3];
    box3 cube = {{0, 0, 0}, {1, 1, 1}};
    grid_resolution(cube, 1000, 4, r);
    CHECKF(r[0] == 16 && r[1] == 16 && r[2] == 16, "cube: %dx%dx%d, want 16^3 (cbrt 4000)", r[0],
           r[1], r[2]);
    box3 brick = {{0, 0, 0}, {2, 1, 1}};
    grid_resolution(brick, 1000, 4, r); /* s = cbrt(2000) = 12.6 */
    CHECKF(r[0] == 25 && r[1] == 13 && r[2] == 13, "brick: %dx%dx%d, want 25x13x13", r[0], r[1],
           r[2]);
    box3 flat = {{0, 0, 5}, {1, 1, 5}};
    grid_resolution(flat, 1000, 4, r); /* 2D: sqrt(4000) = 63.2 */
    CHECKF(r[0] == 63 && r[1] == 63 && r[2] == 1, "flat: %dx%dx%d, want 63x63x1", r[0], r[1], r[2]);
    box3 thin = {{0, 0, 0}, {1, 1, 1e-4f}};
    grid_resolution(thin, 1000, 4, r); /* 3D rule gives z 0.34 cells: redone in 2D */
    CHECKF(r[0] == 63 && r[1] == 63 && r[2] == 1, "thin: %dx%dx%d, want 63x63x1", r[0], r[1], r[2]);
    box3 line = {{0, 0, 0}, {10, 1e-5f, 0}};
    grid_resolution(line, 1000, 4, r);
    CHECKF(r[0] == 4000 && r[1] == 1 && r[2] == 1, "line: %dx%dx%d, want 4000x1x1", r[0], r[1],
           r[2]);
    grid_resolution(cube, 1e15, 1000, r);
    CHECKF(r[0] == GRID_MAX_AXIS_RES && r[2] == GRID_MAX_AXIS_RES, "huge: %d clamped", r[0]);
    grid_resolution(box3_empty(), 1000, 4, r);
    CHECK(r[0] == 1 && r[1] == 1 && r[2] == 1);
    grid_resolution(cube, 0, 4, r);
    CHECK(r[0] == 1 && r[1] == 1 && r[2] == 1);
    grid_resolution(cube, 1, 0.001, r);
    CHECK(r[0] == 1 && r[1] == 1 && r[2] == 1);
    /* Random boxes: the cell count stays near lambda*N. */
    for (int k = 0; k < 200; k++) {
        box3 b = {{0, 0, 0},
                  {test_rand_in(0.1f, 10), test_rand_in(0.1f, 10), test_rand_in(0.1f, 10)}};
        double n = 1000 + 100000 * test_rand(), lambda = 0.5 + 8 * test_rand();
        grid_resolution(b, n, lambda, r);
        double cells = (double)r[0] * r[1] * r[2];
        CHECKF(cells > 0.6 * lambda * n && cells < 1.6 * lambda * n,
               "box %gx%gx%g n %g lambda %g: %dx%dx%d = %g cells", b.max.x, b.max.y, b.max.z, n,
               lambda, r[0], r[1], r[2], cells);
    }
}

TEST(grid_res_parse)
{
    accel_error err = {0};
    int r[3];
    CHECK(grid_parse_res("auto", r, &err) == 0 && r[0] == 0);
    CHECK(grid_parse_res("128", r, &err) == 0 && r[0] == 128 && r[1] == 128 && r[2] == 128);
    CHECK(grid_parse_res("128x64x32", r, &err) == 0 && r[0] == 128 && r[1] == 64 && r[2] == 32);
    CHECK(grid_parse_res("65536x1x1", r, &err) == 0 && r[0] == 65536);
    static const char *const bad[] = {"0",       "12x",   "x",      "1x2",
                                      "1x2x3x4", "65537", "-3",     "abc",
                                      "4x4x0",   "4 ",    "4x-4x4", "99999999999999999999",
                                      "1.5",     "4X4X4", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        if (!*bad[i]) continue; /* empty means auto */
        err.msg[0] = 0;
        int rc = grid_parse_res(bad[i], r, &err);
        CHECKF(rc != 0 && strstr(err.msg, "res="), "res=%s accepted (rc %d, msg '%s')", bad[i], rc,
               err.msg);
    }
    /* Through the spec parser and the build. */
    accel_scene s;
    scene_builder b = {0};
    test_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 1));
    if (!test_finish(&b, "one", &s)) return;
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    int rc = accel_build_spec("grid:res=5x6x7", &s, 1, &kind, &accel, &st, &err);
    CHECKF(rc == 0, "res=5x6x7: %s", err.msg);
    if (rc == 0) {
        CHECK(st.res[0] == 5 && st.res[1] == 6 && st.res[2] == 7 && st.nodes == 210);
        kind->destroy(accel);
    }
    CHECK(accel_build_spec("grid:res=5x6", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_build_spec("grid:lambda=0", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_build_spec("grid:overlap=sat", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_SPEC);
    scene_free(&s);
}

TEST(grid_overflow_refused)
{
    accel_error err = {0};
    uint64_t cells = 0;
    int huge[3] = {65536, 65536, 65536};
    CHECK(grid_cell_count("grid", huge, 1e30, &cells, &err) == ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "cells") != NULL, "message: %s", err.msg);
    int big[3] = {2048, 2048, 1024}; /* 2^32 cells: does not fit a uint32 index */
    CHECK(grid_cell_count("grid", big, 1e30, &cells, &err) == ACCEL_ERR_RANGE);
    int ok[3] = {1024, 1024, 1023};
    CHECK(grid_cell_count("grid", ok, 1e30, &cells, &err) == 0 && cells == 1024ull * 1024 * 1023);
    int mid[3] = {512, 512, 512}; /* 512 MiB of offsets */
    CHECK(grid_cell_count("grid", mid, 256.0 * 1048576, &cells, &err) == ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "MiB") != NULL, "message: %s", err.msg);
    int zero[3] = {0, 4, 4};
    CHECK(grid_cell_count("grid", zero, 1e30, &cells, &err) == ACCEL_ERR_RANGE);

    /* Through the build: cells, then references, above max_mb. */
    scene_builder b = {0};
    for (int i = 0; i < 200; i++) /* large triangles crossing the whole box */
        test_add_tri(&b, v3(0, test_rand(), 0), v3(1, test_rand(), 1),
                     v3(test_rand(), 1, test_rand()));
    accel_scene s;
    if (!test_finish(&b, "big-tris", &s)) return;
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    CHECK(accel_build_spec("grid:res=65536", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_RANGE);
    CHECK(accel_build_spec("grid:res=256,max_mb=16", &s, 1, &kind, &accel, &st, &err) ==
          ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "max_mb") != NULL, "message: %s", err.msg);
    /* 64^3 offsets fit 2 MiB, but 200 triangles x ~5000 cells of references do not. */
    err.msg[0] = 0;
    CHECK(accel_build_spec("grid:res=64,max_mb=2", &s, 1, &kind, &accel, &st, &err) ==
          ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "references") != NULL, "message: %s", err.msg);
    int rc = accel_build_spec("grid:res=32", &s, 1, &kind, &accel, &st, &err);
    CHECKF(rc == 0, "res=32: %s", err.msg);
    if (rc == 0) {
        CHECKF(st.refs > 200 * 500, "refs %llu", (unsigned long long)st.refs);
        kind->destroy(accel);
    }
    scene_free(&s);
}

/* A flat scene wider than the float range: one triangle in z = 0 from
 * -2e38 to 2e38 in x. The frame's largest extent (4e38) overflowed a
 * float, the flat axis got an infinite half-size, and every grid traced
 * holes (96 of 256 camera rays, found by an audit, 2026-12-04). */
TEST(grid_flat_scene_wider_than_floats)
{
    scene_builder b = {0};
    test_add_tri(&b, v3(2e38f, 0, 0), v3(-2e38f, 1, 0), v3(0, 2e38f, 0));
    accel_scene s;
    if (!test_finish(&b, "flat 4e38", &s)) return;
    box3 fb = grid_frame_box(s.bounds);
    CHECKF(isfinite(fb.min.z) && isfinite(fb.max.z) && fb.min.z < 0 && fb.max.z > 0,
           "flat axis framed as %g..%g", fb.min.z, fb.max.z);
    test_rays r = {0};
    test_seed(4);
    for (int i = 0; i < 200; i++) {
        /* points inside the triangle, from above and from a camera */
        float u = test_rand(), v = test_rand();
        if (u + v > 1) u = 1 - u, v = 1 - v;
        vec3 p = v3(2e38f * (1 - u - v) - 2e38f * u, v * 2e38f, 0.0f);
        test_rays_push(&r, test_ray(v3(p.x, p.y, 5), v3(0, 0, -1), 0, INFINITY));
        test_rays_push(&r, test_ray(v3(0.1f, 0.1f, 5), v3_sub(p, v3(0.1f, 0.1f, 5)), 0, INFINITY));
    }
    static const char *const specs[] = {"grid", "grid:traverse=packet", "grid:skip=macro",
                                        "grid:res=4", "nested_grid", "irregular_grid"};
    for (size_t k = 0; k < sizeof specs / sizeof specs[0]; k++)
        test_check_spec(&s, specs[k], r.rays, r.count, NULL, NULL, NULL);
    test_rays_free(&r);
    scene_free(&s);
}

/* ---- counters, step counts, mailbox ---------------------------------------------- */

TEST(grid_dda_step_counts)
{
    /* Bounds exactly [0,8]^3 from two triangles off the main diagonal. */
    scene_builder b = {0};
    test_add_tri(&b, v3(0, 0, 1), v3(0, 1, 0), v3(0, 1, 1));
    test_add_tri(&b, v3(8, 8, 7), v3(8, 7, 8), v3(8, 7, 7));
    accel_scene s;
    if (!test_finish(&b, "corners", &s)) return;
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    accel_error err = {0};
    if (accel_build_spec("grid:res=8", &s, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        return;
    }
    struct {
        accel_ray ray;
        uint64_t steps;
        const char *what;
    } cases[] = {
        {test_ray(v3(-1, 4.5f, 4.5f), v3(1, 0, 0), 0, INFINITY), 8, "along x through cell centres"},
        {test_ray(v3(-1, 4, 4), v3(1, -0.0f, 0), 0, INFINITY), 8, "along x on a cell edge line"},
        {test_ray(v3(9, 4, 4), v3(-1, 0, -0.0f), 0, INFINITY), 8, "along -x on a cell edge line"},
        {test_ray(v3(3.5f, 4.5f, 4.5f), v3(1, 0, 0), 0, INFINITY), 5, "inside, from cell 3"},
        {test_ray(v3(3, 4.5f, 4.5f), v3(1, 0, 0), 0, INFINITY), 5, "origin on the plane x=3, +x"},
        {test_ray(v3(3, 4.5f, 4.5f), v3(-1, 0, 0), 0, INFINITY), 3, "origin on the plane x=3, -x"},
        {test_ray(v3(3, 4.5f, 4.5f), v3(1, 0, 0), 0, 2.5f), 3, "ending inside cell 5"},
        {test_ray(v3(3, 4.5f, 4.5f), v3(1, 0, 0), 0, 2.0f), 2, "ending on the plane x=5"},
        {test_ray(v3(-1, -1, -1), v3(1, 1, 1), 0, INFINITY), 22, "main diagonal through corners"},
        {test_ray(v3(9, 9, 9), v3(-1, -1, -1), 0, INFINITY), 22, "main diagonal backwards"},
        {test_ray(v3(0, 0, 4.5f), v3(1, 1, 0), 0, INFINITY), 15, "face diagonal through edges"},
        {test_ray(v3(-1, 4.5f, 4.5f), v3(0, 1, 0), 0, INFINITY), 0, "parallel, outside"},
        {test_ray(v3(8, 4.5f, 4.5f), v3(0, 1, 0), 0, INFINITY), 4, "parallel in the face x=8"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        accel_counters c;
        memset(&c, 0, sizeof c);
        uint32_t ray_steps = 99, ray_prims = 99;
        c.ray_steps = &ray_steps;
        c.ray_prims = &ray_prims;
        accel_hit h;
        accel_trace(kind, accel, &cases[i].ray, &h, 1, 1, &c);
        CHECKF(c.steps == cases[i].steps && ray_steps == cases[i].steps,
               "%s: %llu steps (per ray %u), want %llu", cases[i].what, (unsigned long long)c.steps,
               ray_steps, (unsigned long long)cases[i].steps);
        CHECKF(h.prim == ACCEL_MISS, "%s: hit %u", cases[i].what, h.prim);
        CHECKF(c.empty_steps <= c.steps && ray_prims == c.prim_tests, "%s: counters",
               cases[i].what);
    }
    kind->destroy(accel);
    scene_free(&s);
}

TEST(grid_mailbox_counts)
{
    /* Large triangles on a fine grid: each spans many cells along a ray. */
    scene_builder b = {0};
    test_seed(31);
    for (int i = 0; i < 100; i++) {
        vec3 c = v3(test_rand_in(0, 10), test_rand_in(0, 10), test_rand_in(0, 10));
        test_add_tri(&b, c, v3_add(c, v3(3, test_rand_in(-1, 1), 0.5f)),
                     v3_add(c, v3(0.3f, 3, test_rand_in(-1, 1))));
    }
    accel_scene s;
    if (!test_finish(&b, "big", &s)) return;
    size_t n = 2000;
    accel_ray *rays = malloc(n * sizeof *rays);
    for (size_t i = 0; i < n; i++)
        rays[i] = test_ray(v3(test_rand_in(0, 10), test_rand_in(0, 10), -5),
                           v3(test_rand_in(-0.3f, 0.3f), test_rand_in(-.3f, .3f), 1), 0, INFINITY);
    accel_counters c[2];
    accel_hit *h[2];
    for (int mb = 0; mb < 2; mb++) {
        const accel_kind *kind;
        void *accel;
        accel_build_stats st;
        accel_error err = {0};
        h[mb] = malloc(n * sizeof *h[mb]);
        memset(&c[mb], 0, sizeof c[mb]);
        if (accel_build_spec(mb ? "grid:res=64,cells=ids,mailbox=1" : "grid:res=64,cells=ids,mailbox=0", &s, 1, &kind,
                             &accel, &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s", err.msg);
            return;
        }
        accel_trace(kind, accel, rays, h[mb], n, 2, &c[mb]);
        kind->destroy(accel);
    }
    /* Same answers (a tie between two primitives at one distance may go
     * either way when a repeated test is skipped). */
    hits_diff d = hits_compare(&s, rays, h[0], h[1], n);
    CHECKF(d.agree == n, "mailbox changes %zu answers", n - d.agree);
    CHECK(c[0].mailbox_skips == 0);
    CHECKF(c[1].mailbox_skips > 0 && c[1].prim_tests < c[0].prim_tests &&
               c[1].prim_tests + c[1].mailbox_skips == c[0].prim_tests,
           "mailbox: %llu tests + %llu skips vs %llu tests without",
           (unsigned long long)c[1].prim_tests, (unsigned long long)c[1].mailbox_skips,
           (unsigned long long)c[0].prim_tests);
    CHECK(c[0].steps == c[1].steps && c[0].rays == n && c[0].box_tests == n);
    free(h[0]);
    free(h[1]);
    free(rays);
    scene_free(&s);
}

/* ---- thread-count independence ----------------------------------------------------- */

TEST(grid_build_threads_identical)
{
    scene_builder b = {0};
    accel_error err = {0};
    test_seed(2024);
    for (int i = 0; i < 30000; i++) {
        vec3 c = v3(test_rand_in(0, 10), test_rand_in(0, 10), test_rand_in(0, 10));
        float sz = test_rand() < 0.05f ? 2.0f : 0.2f;
        test_add_tri(
            &b, c,
            v3_add(c, v3(test_rand_in(-sz, sz), test_rand_in(-sz, sz), test_rand_in(-sz, sz))),
            v3_add(c, v3(test_rand_in(-sz, sz), test_rand_in(-sz, sz), test_rand_in(-sz, sz))));
    }
    for (int i = 0; i < 500; i++)
        scene_builder_add_sphere(&b,
                                 v3(test_rand_in(0, 10), test_rand_in(0, 10), test_rand_in(0, 10)),
                                 test_rand_in(0.01f, 1), &err);
    accel_scene s;
    if (!test_finish(&b, "threads", &s)) return;
    static const char *const specs[] = {"grid", "grid:overlap=bbox", "grid:res=200x3x90"};
    for (size_t k = 0; k < sizeof specs / sizeof specs[0]; k++) {
        const accel_kind *kind;
        void *a1, *a2;
        accel_build_stats s1, s2;
        if (accel_build_spec(specs[k], &s, 1, &kind, &a1, &s1, &err) ||
            accel_build_spec(specs[k], &s, 2, &kind, &a2, &s2, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[k], err.msg);
            continue;
        }
        grid_view v1, v2;
        grid_get_view(a1, &v1);
        grid_get_view(a2, &v2);
        CHECK(v1.cell_count == v2.cell_count && v1.ref_count == v2.ref_count);
        if (v1.cell_count == v2.cell_count && v1.ref_count == v2.ref_count) {
            CHECKF(memcmp(v1.offsets, v2.offsets, (v1.cell_count + 1) * sizeof *v1.offsets) == 0,
                   "%s: offsets differ", specs[k]);
            CHECKF(memcmp(v1.refs, v2.refs, v1.ref_count * sizeof *v1.refs) == 0, "%s: refs differ",
                   specs[k]);
        }
        CHECK(s1.refs == s2.refs && s1.leaves == s2.leaves && s1.bytes == s2.bytes);
        /* Sanity of the arrays: offsets increase, lists sorted, every live
         * primitive referenced at least once. */
        int ok = v1.offsets[0] == 0 && v1.offsets[v1.cell_count] == v1.ref_count;
        uint8_t *seen = calloc(s.prim_count, 1);
        ok &= v1.prim_count == s.live_count &&
              memcmp(v1.prim_id, v2.prim_id, v1.prim_count * sizeof *v1.prim_id) == 0;
        for (uint64_t c = 0; c < v1.cell_count && ok; c++) {
            ok &= v1.offsets[c] <= v1.offsets[c + 1];
            for (uint32_t r = v1.offsets[c]; ok && r < v1.offsets[c + 1]; r++) {
                ok &= v1.refs[r] < v1.prim_count;
                if (r > v1.offsets[c]) ok &= v1.refs[r] > v1.refs[r - 1];
                if (ok) seen[v1.prim_id[v1.refs[r]]] = 1;
            }
        }
        CHECKF(ok, "%s: malformed cell arrays", specs[k]);
        for (uint32_t i = 0; i < s.live_count && ok; i++) ok &= seen[s.live[i]];
        CHECKF(ok, "%s: a live primitive is in no cell", specs[k]);
        free(seen);
        /* Exact overlap stores fewer references than bounding boxes. */
        if (k == 1) {
            accel_build_stats se;
            void *ae;
            if (accel_build_spec("grid", &s, 2, &kind, &ae, &se, &err) == 0) {
                CHECKF(se.refs < s1.refs, "exact %llu refs vs bbox %llu",
                       (unsigned long long)se.refs, (unsigned long long)s1.refs);
                kind->destroy(ae);
            }
        }
        kind->destroy(a1);
        kind->destroy(a2);
    }
    scene_free(&s);
}
