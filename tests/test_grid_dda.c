/*
 * test_grid_dda.c - the grid's traversal against the oracle on the cases
 * that break a 3D-DDA: rays through cell corners and along cell edges, +0/-0
 * components, origins on cell boundaries and inside the grid, rays grazing
 * a cell edge from far away; flat, thin, far, tiny and empty scenes; a soup
 * of triangles and spheres. Every listed variant, plus extra resolutions.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid/grid.h"
#include "support.h"

/* ---- DDA edge cases against the reference ----------------------------------------- */

/*
 * A scene on a lattice: bounds exactly [0,4]^3 and triangles whose vertices
 * lie on the half-integer lattice, so that with res=4 (and 8) many of them
 * lie in cell boundary planes, along cell edges, or touch cell corners.
 */
static int lattice_scene(accel_scene *s)
{
    scene_builder b = {0};
    test_seed(12345);
    for (int i = 0; i < 300; i++) {
        vec3 p[3];
        vec3 base = v3(test_rand_lattice(0, 0.5f, 8), test_rand_lattice(0, 0.5f, 8),
                       test_rand_lattice(0, 0.5f, 8));
        for (int k = 0; k < 3; k++)
            p[k] = v3_add(base, v3(test_rand_lattice(0, 0.5f, 3), test_rand_lattice(0, 0.5f, 3),
                                   test_rand_lattice(0, 0.5f, 3)));
        test_add_tri(&b, p[0], p[1], p[2]);
    }
    /* Axis-aligned squares lying exactly in the planes x = 2, y = 1, z = 3. */
    test_add_tri(&b, v3(2, 0.5f, 0.5f), v3(2, 1.5f, 0.5f), v3(2, 1.5f, 1.5f));
    test_add_tri(&b, v3(2, 0.5f, 0.5f), v3(2, 1.5f, 1.5f), v3(2, 0.5f, 1.5f));
    test_add_tri(&b, v3(0.5f, 1, 2.5f), v3(1.5f, 1, 2.5f), v3(1.5f, 1, 3.5f));
    test_add_tri(&b, v3(2.5f, 2.5f, 3), v3(3.5f, 2.5f, 3), v3(3.5f, 3.5f, 3));
    /* Pin the bounds to [0,4]^3. */
    test_add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0));
    test_add_tri(&b, v3(4, 4, 4), v3(3.99f, 4, 4), v3(4, 3.99f, 4));
    return test_finish(&b, "lattice", s);
}

/* Lattice points (multiples of 1/2, some beyond the box) as origins and
 * targets, and axis-parallel rays along lattice lines (cell edges and
 * faces) from outside, from the faces and inside, so rays run through cell
 * corners and along cell edges; then diagonals in a plane and random rays.
 * Rays in the plane of a triangle are left out (test_ray_in_a_plane). */
static void lattice_rays(const accel_scene *s, test_rays *r)
{
    const box3 box = {{0, 0, 0}, {4, 4, 4}};
    test_seed(777);
    test_rays_lattice_points(r, box, 0.5f, 1.0f, 8000, s);
    test_rays_axis_lattice(r, box, 0.5f, 1, TEST_START_ALL, s);
    /* Diagonals in a plane: through cell edges with one zero component. */
    for (int i = 0; i < 400; i++) {
        float o[3] = {test_rand_lattice(0, 0.5f, 9), test_rand_lattice(0, 0.5f, 9),
                      test_rand_lattice(0, 0.5f, 9)};
        int zero = i % 3;
        float d[3] = {test_rand() < 0.5f ? 1.0f : -1.0f, test_rand() < 0.5f ? 1.0f : -1.0f,
                      test_rand() < 0.5f ? 1.0f : -1.0f};
        d[zero] = (i & 4) ? -0.0f : 0.0f;
        accel_ray ray = test_ray(v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
        if (!test_ray_in_a_plane(s, &ray)) test_rays_push(r, ray);
    }
    /* Random directions from random points, some far away. */
    for (int i = 0; i < 2000; i++) {
        float scale = i % 4 == 0 ? 40.0f : 3.0f;
        box3 around = {{-scale, -scale, -scale}, {4 + scale, 4 + scale, 4 + scale}};
        vec3 o = test_rand_point(around);
        test_rays_push(r, test_ray(o, v3_sub(test_rand_point(box), o), 0.0f, INFINITY));
    }
}

TEST(grid_dda_lattice_edges_corners)
{
    accel_scene s;
    if (!lattice_scene(&s)) return;
    test_rays r = {0};
    lattice_rays(&s, &r);
    CHECKF(r.count > 9000, "%zu lattice rays", r.count);
    static const char *const extra[] = {
        "res=4",     "res=8",  "res=4,mailbox=0", "res=8,overlap=bbox",
        "res=3x5x4", "res=16", "res=64x1x1",      "res=1x2x64",
        NULL};
    /* The traversal is checked against the same float kernels without an
     * accelerator, so that any difference is a cell the DDA skipped, however
     * the float kernels and the double reference decide rays through these
     * vertices and open edges (the note reports how they compare). */
    accel_hit *ref = test_oracle_hits(&s, r.rays, r.count, TEST_ORACLE_REFERENCE);
    accel_hit *brute = test_oracle_hits(&s, r.rays, r.count, TEST_ORACLE_FLOAT_BRUTE);
    if (ref && brute) {
        hits_diff d = hits_compare(&s, r.rays, ref, brute, r.count);
        test_note("float kernels vs reference on the lattice: %zu holes, %zu false hits, %zu "
                  "disagreements of %zu rays",
                  d.holes, d.false_hits, d.disagreements, r.count);
    }
    free(ref);
    free(brute);
    test_check_variants(&s, &accel_kind_grid, extra, r.rays, r.count, TEST_ORACLE_FLOAT_BRUTE);
    test_rays_free(&r);
    scene_free(&s);
}

/*
 * Rays that graze a cell edge or enter near a cell boundary, where rounding
 * in the DDA decides which side they pass: triangles placed a few ulps
 * inside one cell only, rays aimed a few ulps past the edge or boundary
 * from afar. Without padded membership or the entry correction of
 * grid_dda_init, a ray can walk past the one cell holding its hit.
 */
TEST(grid_dda_grazing)
{
    scene_builder b = {0};
    const float e = 2.0f * 0x1p-22f; /* 2 ulps at 2 */
    /* In the plane x = y, just inside cell (2,2) of a 4^3 grid over [0,4]^3. */
    test_add_tri(&b, v3(2 + e, 2 + e, 0.5f), v3(2 + e, 2 + e, 3.5f), v3(3.5f, 3.5f, 2));
    /* A square in the face x = 0, in the row y < 1 only, reaching up to a
     * hundredth of a cell below y = 1. */
    const float top = 0.99f;
    test_add_tri(&b, v3(0, 0.2f, 0.2f), v3(0, top, 0.2f), v3(0, top, 3.8f));
    test_add_tri(&b, v3(0, 0.2f, 0.2f), v3(0, top, 3.8f), v3(0, 0.2f, 3.8f));
    test_add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0));
    test_add_tri(&b, v3(4, 4, 4), v3(3.99f, 4, 4), v3(4, 3.99f, 4));
    accel_scene s;
    if (!test_finish(&b, "grazing", &s)) return;
    size_t n = 20000;
    accel_ray *rays = malloc(n * sizeof *rays);
    test_seed(8080);
    for (size_t i = 0; i < n / 2; i++) {
        /* Anti-diagonal through (2+k ulps, 2+k ulps, z): crosses cell (2,2)
         * for a length of a few ulps near its corner. */
        float k = (float)(int)(test_rand() * 8) * 0x1p-22f;
        float z = test_rand_in(0.6f, 3.4f),
              back = 0.5f * powf(10, 9 * test_rand()); /* 0.5 .. 5e8 */
        vec3 target = v3(2 + k, 2 + k, z), dir = v3(1, -1, test_rand_in(-0.01f, 0.01f));
        vec3 o = v3_sub(target, v3_scale(dir, back));
        rays[i] = test_ray(o, dir, 0, INFINITY);
    }
    for (size_t i = n / 2; i < n; i++) {
        /* From 10^5..10^6 away (entry point rounding well above the
         * membership padding), entering the face x = 0 within 0.1 of the
         * plane y = 1, where the square lies in row y < 1 only. */
        float k = test_rand_in(-0.05f, 0.1f);
        float z = test_rand_in(0.3f, 3.0f), back = test_rand_in(1e5f, 1e6f);
        vec3 dir = v3(0.7f, i % 2 ? 0.3f : -0.3f, test_rand_in(-1e-5f, 1e-5f));
        vec3 entry = v3(0, 1 - k, z);
        vec3 o = v3_sub(entry, v3_scale(dir, back));
        rays[i] = test_ray(o, dir, 0, INFINITY);
    }
    static const char *const extra[] = {"res=4", "res=4,mailbox=0", "res=8", NULL};
    test_check_variants(&s, &accel_kind_grid, extra, rays, n, TEST_ORACLE_REFERENCE);
    free(rays);
    scene_free(&s);
}

/* Random triangles and spheres, plus rays from inside and outside. */
TEST(grid_soup_with_spheres)
{
    scene_builder b = {0};
    accel_error err = {0};
    test_seed(4242);
    for (int i = 0; i < 2000; i++) {
        vec3 c = v3(test_rand_in(-10, 10), test_rand_in(-10, 10), test_rand_in(-3, 3));
        float sz = test_rand() < 0.1f ? 4.0f : 0.5f;
        test_add_tri(
            &b, v3_add(c, v3(test_rand_in(-sz, sz), test_rand_in(-sz, sz), test_rand_in(-sz, sz))),
            v3_add(c, v3(test_rand_in(-sz, sz), test_rand_in(-sz, sz), test_rand_in(-sz, sz))),
            v3_add(c, v3(test_rand_in(-sz, sz), test_rand_in(-sz, sz), test_rand_in(-sz, sz))));
    }
    for (int i = 0; i < 200; i++)
        scene_builder_add_sphere(
            &b, v3(test_rand_in(-10, 10), test_rand_in(-10, 10), test_rand_in(-3, 3)),
            test_rand_in(0.05f, 1.5f), &err);
    accel_scene s;
    if (!test_finish(&b, "soup+spheres", &s)) return;
    size_t n = 6000;
    accel_ray *rays = malloc(n * sizeof *rays);
    for (size_t i = 0; i < n; i++) {
        float o[3], t[3];
        int inside = i % 2;
        for (int a = 0; a < 3; a++) {
            o[a] = inside ? test_rand_in(-10, 10) : test_rand_in(-40, 40);
            t[a] = test_rand_in(-10, 10);
        }
        float t_far = i % 3 == 0 ? test_rand_in(0.1f, 1.0f) : INFINITY;
        rays[i] =
            test_ray(v3(o[0], o[1], o[2]), v3(t[0] - o[0], t[1] - o[1], t[2] - o[2]), 0, t_far);
    }
    test_check_variants(&s, &accel_kind_grid, NULL, rays, n, TEST_ORACLE_REFERENCE);
    free(rays);
    scene_free(&s);
}

/* All triangles in the plane z = 0: a flat grid; rays in and across the plane. */
TEST(grid_flat_and_thin_scenes)
{
    for (int thin = 0; thin < 2; thin++) {
        scene_builder b = {0};
        test_seed(99 + (uint64_t)thin);
        for (int i = 0; i < 1000; i++) {
            float x = test_rand_in(0, 10), y = test_rand_in(0, 10);
            float z0 = thin ? test_rand_in(0, 1e-3f) : 0, z1 = thin ? test_rand_in(0, 1e-3f) : 0;
            test_add_tri(&b, v3(x, y, z0),
                         v3(x + test_rand_in(0, 0.5f), y + test_rand_in(-0.2f, 0.2f), z1),
                         v3(x + test_rand_in(-0.2f, 0.2f), y + test_rand_in(0, 0.5f), z0));
        }
        accel_scene s;
        if (!test_finish(&b, thin ? "thin" : "flat", &s)) return;
        const accel_kind *kind;
        void *accel;
        accel_build_stats st;
        accel_error err = {0};
        if (accel_build_spec("grid", &s, 1, &kind, &accel, &st, &err) == 0) {
            CHECKF(st.res[2] == 1 && st.res[0] > 20 && st.res[1] > 20, "%s: res %dx%dx%d", s.name,
                   st.res[0], st.res[1], st.res[2]);
            kind->destroy(accel);
        } else {
            test_fail(__FILE__, __LINE__, "%s: %s", s.name, err.msg);
        }
        size_t n = 4000;
        accel_ray *rays = malloc(n * sizeof *rays);
        for (size_t i = 0; i < n; i++) {
            float ox = test_rand_in(-2, 12), oy = test_rand_in(-2, 12);
            if (i % 4 == 0) /* lying in the plane */
                rays[i] =
                    test_ray(v3(ox, oy, 0),
                             v3(test_rand_in(-1, 1), test_rand_in(-1, 1), i % 8 ? 0.0f : -0.0f), 0,
                             INFINITY);
            else if (i % 4 == 1) /* straight down, +0/-0 sideways */
                rays[i] =
                    test_ray(v3(ox, oy, 5), v3(i % 8 == 1 ? -0.0f : 0.0f, 0.0f, -1), 0, INFINITY);
            else
                rays[i] = test_ray(
                    v3(ox, oy, test_rand_in(-5, 5)),
                    v3(test_rand_in(0, 10) - ox, test_rand_in(0, 10) - oy, test_rand_in(-1, 1)), 0,
                    INFINITY);
        }
        test_check_variants(&s, &accel_kind_grid, NULL, rays, n, TEST_ORACLE_REFERENCE);
        free(rays);
        scene_free(&s);
    }
}

/* A scene far from the origin and a tiny one: the padding scales along. */
TEST(grid_far_and_tiny_scenes)
{
    static const float offsets[] = {1e4f, 0.0f};
    static const float scales[] = {1.0f, 1e-4f};
    for (int c = 0; c < 2; c++) {
        scene_builder b = {0};
        test_seed(5 + (uint64_t)c);
        float o = offsets[c], sc = scales[c];
        for (int i = 0; i < 1500; i++) {
            vec3 p = v3(o + sc * test_rand_in(0, 8), o + sc * test_rand_in(0, 8),
                        o + sc * test_rand_in(0, 8));
            test_add_tri(
                &b, p, v3_add(p, v3(sc * test_rand_in(-.5f, .5f), sc * test_rand_in(-.5f, .5f), 0)),
                v3_add(p, v3(0, sc * test_rand_in(-.5f, .5f), sc * test_rand_in(-.5f, .5f))));
        }
        accel_scene s;
        if (!test_finish(&b, c ? "tiny" : "far", &s)) return;
        size_t n = 3000;
        accel_ray *rays = malloc(n * sizeof *rays);
        for (size_t i = 0; i < n; i++) {
            vec3 org = v3(o + sc * test_rand_in(-4, 12), o + sc * test_rand_in(-4, 12),
                          o + sc * test_rand_in(-4, 12));
            vec3 tgt = v3(o + sc * test_rand_in(0, 8), o + sc * test_rand_in(0, 8),
                          o + sc * test_rand_in(0, 8));
            vec3 d = v3_sub(tgt, org);
            rays[i] = test_ray(org, d, 0, INFINITY);
        }
        static const char *const extra[] = {"res=64", NULL};
        test_check_variants(&s, &accel_kind_grid, extra, rays, n, TEST_ORACLE_REFERENCE);
        free(rays);
        scene_free(&s);
    }
}

/* No live primitive: builds, misses everything. */
TEST(grid_empty_scene)
{
    scene_builder b = {0};
    test_add_tri(&b, v3(0, 0, 0), v3(1, 1, 1), v3(2, 2, 2)); /* degenerate */
    accel_scene s;
    if (!test_finish(&b, "empty", &s)) return;
    accel_ray r[2] = {test_ray(v3(0, 0, -1), v3(0.1f, 0.1f, 1), 0, INFINITY),
                      test_ray(v3(1, 1, 1), v3(1, 0, 0), 0, INFINITY)};
    test_check_variants(&s, &accel_kind_grid, NULL, r, 2, TEST_ORACLE_REFERENCE);
    scene_free(&s);
}
