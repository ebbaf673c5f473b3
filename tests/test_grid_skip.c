/*
 * test_grid_skip.c - empty-space skipping of the regular grid (grid:skip=):
 * the proximity cloud against a brute-force Chebyshev distance, the macro
 * flags against a brute-force scan, skipping walks that test exactly the
 * primitives of the plain walk (no non-empty cell skipped) with fewer
 * steps, and the refusals (max_mb, macro not a power of two).
 * Hits against the reference on edge, corner, flat and far cases: the grid
 * variants list (test_grid.c, conformance and stability suites).
 */
#include <stdlib.h>
#include <string.h>

#include "grid/grid.h"
#include "grid/grid_skip.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static float frand01(void) { return test_rand_of(&rng); }

/* Offsets of a grid whose cell c is non-empty when occ[c]. */
static uint32_t *offsets_of(const uint8_t *occ, size_t cells)
{
    uint32_t *o = malloc((cells + 1) * sizeof *o);
    o[0] = 0;
    for (size_t c = 0; c < cells; c++) o[c + 1] = o[c] + (occ[c] ? 1u : 0u);
    return o;
}

static int brute_cheb(const int res[3], const uint8_t *occ, int x, int y, int z)
{
    int best = GRID_SKIP_CAP;
    for (int k = 0; k < res[2]; k++)
        for (int j = 0; j < res[1]; j++)
            for (int i = 0; i < res[0]; i++) {
                if (!occ[i + res[0] * (j + res[1] * k)]) continue;
                int d = abs(i - x);
                d = abs(j - y) > d ? abs(j - y) : d;
                d = abs(k - z) > d ? abs(k - z) : d;
                best = d < best ? d : best;
            }
    return best;
}

TEST(grid_skip_cloud_is_chebyshev_distance)
{
    static const int shapes[][3] = {{13, 7, 9}, {1, 1, 1}, {30, 1, 1}, {1, 17, 5}, {8, 8, 8},
                                    {300, 1, 2}, {5, 40, 3}};
    static const float density[] = {0.0f, 0.002f, 0.02f, 0.3f, 1.0f};
    for (size_t si = 0; si < sizeof shapes / sizeof shapes[0]; si++)
        for (size_t di = 0; di < sizeof density / sizeof density[0]; di++) {
            const int *res = shapes[si];
            size_t cells = (size_t)res[0] * res[1] * res[2];
            float planes[512];
            grid_frame f;
            box3 box = {{0, 0, 0}, {1, 1, 1}};
            grid_frame_init(&f, box, res, planes);
            uint8_t *occ = malloc(cells), *dist = malloc(cells);
            for (size_t c = 0; c < cells; c++) occ[c] = frand01() < density[di];
            if (si == 5 && di == 1) { /* one occupied cell: distances run past the cap */
                memset(occ, 0, cells);
                occ[0] = 1;
            }
            uint32_t *o = offsets_of(occ, cells);
            for (int threads = 1; threads <= 2; threads++) {
                accel_error err = {0};
                memset(dist, 0xAB, cells);
                CHECK(grid_skip_cloud(&f, o, dist, threads, &err) == 0);
                size_t bad = 0, first = 0;
                int want_first = 0;
                for (int z = 0; z < res[2]; z++)
                    for (int y = 0; y < res[1]; y++)
                        for (int x = 0; x < res[0]; x++) {
                            size_t c = (size_t)x + res[0] * ((size_t)y + (size_t)res[1] * z);
                            int want = brute_cheb(res, occ, x, y, z);
                            if (dist[c] != want && bad++ == 0) first = c, want_first = want;
                        }
                CHECKF(bad == 0, "%dx%dx%d density %g threads %d: %zu wrong distances, cell %zu: "
                       "%d, want %d", res[0], res[1], res[2], density[di], threads, bad, first,
                       dist[first], want_first);
            }
            /* Macro flags: a block is empty exactly when all its cells are. */
            for (int shift = 1; shift <= 3; shift++) {
                int mres[3];
                grid_skip_macro_res(res, shift, mres);
                size_t mcount = (size_t)mres[0] * mres[1] * mres[2];
                uint8_t *empty = malloc(mcount), *want = malloc(mcount);
                memset(want, 1, mcount);
                for (int z = 0; z < res[2]; z++)
                    for (int y = 0; y < res[1]; y++)
                        for (int x = 0; x < res[0]; x++)
                            if (occ[(size_t)x + res[0] * ((size_t)y + (size_t)res[1] * z)])
                                want[(x >> shift) + mres[0] * ((y >> shift) + mres[1] * (z >> shift))] = 0;
                grid_skip_macro(&f, o, shift, empty);
                CHECKF(memcmp(empty, want, mcount) == 0, "%dx%dx%d: macro flags, shift %d",
                       res[0], res[1], res[2], shift);
                free(empty);
                free(want);
            }
            free(o);
            free(occ);
            free(dist);
        }
}

/* Clusters of small triangles in a large empty box: much empty space. */
static int cluster_scene(accel_scene *s)
{
    scene_builder b = {0};
    accel_error err = {0};
    rng = 77;
    for (int k = 0; k < 6; k++) {
        vec3 c = v3(frand01() * 100, frand01() * 100, frand01() * 100);
        for (int i = 0; i < 400; i++) {
            vec3 p = v3_add(c, v3(frand01() * 6, frand01() * 6, frand01() * 6));
            vec3 q = v3_add(p, v3(frand01() - 0.5f, frand01() - 0.5f, frand01() - 0.5f));
            vec3 r = v3_add(p, v3(frand01() - 0.5f, frand01() - 0.5f, frand01() - 0.5f));
            scene_builder_add_tri(&b, p, q, r, &err);
        }
    }
    scene_builder_add_sphere(&b, v3(50, 50, 50), 3.0f, &err);
    return scene_finish(&b, "clusters", s, &err) == 0;
}

/* A skipping walk visits every non-empty cell of the plain walk (tie rays
 * through edges aside, none here): with mailbox=0 each ray runs exactly
 * the same primitive tests, and the same hits come out, in fewer steps. */
TEST(grid_skip_tests_what_the_plain_walk_tests)
{
    accel_scene s;
    if (!cluster_scene(&s)) {
        test_fail(__FILE__, __LINE__, "cluster scene");
        return;
    }
    size_t n = 4000;
    accel_ray *rays = malloc(n * sizeof *rays);
    for (size_t i = 0; i < n; i++) {
        vec3 o = v3(frand01() * 140 - 20, frand01() * 140 - 20, frand01() * 140 - 20);
        vec3 t = v3(frand01() * 100, frand01() * 100, frand01() * 100);
        vec3 d = v3_sub(t, o);
        float t_far = i % 3 == 0 ? 0.7f : INFINITY;
        accel_ray r = {o.x, o.y, o.z, i % 5 == 0 ? 0.2f : 0.0f, d.x, d.y, d.z, t_far};
        rays[i] = r;
    }
    static const char *const specs[] = {
        "grid:mailbox=0", "grid:mailbox=0,skip=cloud", "grid:mailbox=0,skip=macro",
        "grid:mailbox=0,skip=macro,macro=16", "grid:mailbox=0,skip=cloud,res=97x5x61"};
    accel_hit *h0 = malloc(n * sizeof *h0), *h = malloc(n * sizeof *h);
    uint32_t *tests0 = malloc(n * sizeof *tests0), *tests = malloc(n * sizeof *tests);
    uint32_t *steps = malloc(n * sizeof *steps);
    uint64_t steps0 = 0;
    for (size_t k = 0; k < sizeof specs / sizeof specs[0]; k++) {
        const accel_kind *kind;
        void *accel;
        accel_build_stats st;
        accel_error err = {0};
        /* The last spec changes the resolution: compare it with its own plain walk. */
        const char *plain = k == 4 ? "grid:mailbox=0,res=97x5x61" : specs[0];
        for (int pass = (k == 0 || k == 4) ? 0 : 1; pass < (k == 0 ? 1 : 2); pass++) {
            const char *spec = pass == 0 ? plain : specs[k];
            if (accel_build_spec(spec, &s, 1, &kind, &accel, &st, &err)) {
                test_fail(__FILE__, __LINE__, "%s: %s", spec, err.msg);
                continue;
            }
            accel_counters c = {0};
            c.ray_prims = pass == 0 ? tests0 : tests;
            c.ray_steps = steps;
            accel_trace(kind, accel, rays, pass == 0 ? h0 : h, n, 1, &c);
            if (pass == 0) {
                steps0 = c.steps;
            } else {
                size_t bad = 0, first = 0;
                for (size_t i = 0; i < n; i++)
                    if (tests[i] != tests0[i] && bad++ == 0) first = i;
                CHECKF(bad == 0, "%s: %zu rays test other primitives than the plain walk (ray "
                       "%zu: %u tests, plain %u)", spec, bad, first, tests[first], tests0[first]);
                CHECKF(memcmp(h, h0, n * sizeof *h) == 0, "%s: hits differ from the plain walk",
                       spec);
                CHECKF(c.steps * 4 < steps0 * 3, "%s: %llu steps, plain walk %llu", spec,
                       (unsigned long long)c.steps, (unsigned long long)steps0);
                accel_error broken = {0};
                CHECKF(accel_counters_status(&c, &broken) == 0, "%s: %s", spec, broken.msg);
            }
            kind->destroy(accel);
        }
    }
    free(h0);
    free(h);
    free(tests0);
    free(tests);
    free(steps);
    free(rays);
    scene_free(&s);
}

TEST(grid_skip_refusals)
{
    accel_scene s;
    if (!cluster_scene(&s)) return;
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    accel_error err = {0};
    /* 60^3 cells: 0.82 MiB of offsets fit 1 MiB; the cloud's 0.21 MiB does not. */
    int rc = test_build_rc("grid:res=60,max_mb=1", &s, &err);
    CHECKF(rc == 0, "plain grid refused: %s", err.msg);
    rc = test_build_rc("grid:res=60,max_mb=1,skip=cloud", &s, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "skip=cloud") && strstr(err.msg, "max_mb"),
           "cloud over max_mb: rc %d, %s", rc, err.msg);
    rc = test_build_rc("grid:skip=macro,macro=6", &s, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "power of two"), "macro=6: rc %d, %s", rc,
           err.msg);
    /* The reported memory holds the table. */
    size_t bytes[2];
    for (int k = 0; k < 2; k++) {
        rc = accel_build_spec(k ? "grid:res=60,skip=cloud" : "grid:res=60", &s, 1, &kind, &accel,
                              &st, &err);
        bytes[k] = rc == 0 ? kind->memory(accel) : 0;
        if (rc == 0) kind->destroy(accel);
    }
    CHECKF(bytes[1] == bytes[0] + 60 * 60 * 60, "memory %zu with the cloud, %zu without", bytes[1],
           bytes[0]);
    scene_free(&s);
}
