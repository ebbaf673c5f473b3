/*
 * test_bvh_packets.c - BVH packets of mixed, invalid and coherent rays, 8x8
 * primary tiles and their shadow rays, the counters of every traversal,
 * and saving and loading a BVH (with corrupted files refused).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "support.h"
#include "test_bvh.h"

/* ---- packets ------------------------------------------------------------------ */

TEST(bvh_packets_mixed_rays)
{
    /* Packets need not be coherent: 64-ray groups that mix direction
     * signs, origins, zero components, invalid rays (NaN, zero direction,
     * t_near > t_far), and a batch length that is not a multiple of 64. */
    accel_scene s;
    if (!test_make_scene("tetra:level=5", &s)) return;
    size_t n = 64 * 9 + 37;
    test_rays r = {0};
    test_rays_random(&r, s.bounds, n);
    accel_ray *rays = r.rays;
    for (size_t i = 0; i < n; i += 17) rays[i].ox = NAN;
    for (size_t i = 5; i < n; i += 29) rays[i].dx = rays[i].dy = rays[i].dz = 0.0f;
    for (size_t i = 9; i < n; i += 31) rays[i].t_near = 2.0f, rays[i].t_far = 1.0f;
    /* one packet entirely invalid, one coherent (shared origin, same signs) */
    for (size_t i = 128; i < 192; i++) rays[i].dx = NAN;
    for (size_t i = 256; i < 320; i++) {
        rays[i] = (accel_ray){
            -3, 0.5f, 0.5f, 0, 1, 0.01f * (float)(i % 8), 0.01f * (float)(i / 8 % 8), INFINITY};
    }
    /* two packets of same-sign directions from spread-out origins (the
     * frustum test's interval case), one with finite t ranges */
    vec3 lo = s.bounds.min, ext = box3_extent(s.bounds);
    for (size_t i = 320; i < 448; i++) {
        vec3 o = v3_sub(lo, v3_mul(ext, v3(test_rand(), test_rand(), test_rand())));
        vec3 target = v3_add(lo, v3_mul(ext, v3(test_rand(), test_rand(), test_rand())));
        vec3 d = v3_sub(target, o);
        rays[i] = (accel_ray){o.x, o.y, o.z, 0.0f,
                              d.x, d.y, d.z, i < 384 ? INFINITY : 0.9f + 0.2f * test_rand()};
    }
    const char *specs[] = {"bvh:traverse=packet", "bvh:traverse=packet,frustum=1",
                           "bvh:traverse=packet,frustum=1,build=sah,leaf=1"};
    for (size_t i = 0; i < 3; i++) {
        void *a = test_build(specs[i], &s, 1, NULL);
        if (!a) continue;
        test_check_accel(&s, &accel_kind_bvh, a, specs[i], rays, n, NULL, NULL);
        /* and a batch shorter than one packet */
        test_check_accel(&s, &accel_kind_bvh, a, specs[i], rays + 256, 10, NULL, NULL);
        accel_kind_bvh.destroy(a);
    }
    test_rays_free(&r);
    scene_free(&s);
}

TEST(bvh_packets_primary_tiles)
{
    /* The packets' intended use: 8x8 tiles of primary rays, plus the
     * shadow rays of their hits (with and without the frustum test). */
    accel_scene s;
    if (!test_make_scene("sphereflake:level=2,spheres=0,segments=3", &s)) return;
    accel_error err = {0};
    rays_set pr = {0}, sh = {0};
    CHECK(rays_primary(&s.camera, 48, 40, &pr, &err) == 0);
    accel_hit *ref = malloc(pr.count * sizeof *ref);
    accel_reference_trace(&s, pr.rays, ref, pr.count, 2);
    CHECK(rays_shadow(&s, &pr, ref, &sh, &err) == 0);
    const char *specs[] = {"bvh:traverse=packet", "bvh:traverse=packet,frustum=1"};
    for (size_t i = 0; i < 2; i++) {
        void *a = test_build(specs[i], &s, 1, NULL);
        if (!a) continue;
        test_check_accel(&s, &accel_kind_bvh, a, specs[i], pr.rays, pr.count, NULL, NULL);
        test_check_accel(&s, &accel_kind_bvh, a, specs[i], sh.rays, sh.count, NULL, NULL);
        accel_kind_bvh.destroy(a);
    }
    free(ref);
    rays_free(&pr);
    rays_free(&sh);
    scene_free(&s);
}

/* ---- counters ---------------------------------------------------------------------- */

TEST(bvh_counters)
{
    accel_scene s;
    if (!test_make_scene("soup:tris=3000", &s)) return;
    size_t n = 1000;
    test_rays r = {0};
    test_rays_random(&r, s.bounds, n);
    accel_ray *rays = r.rays;
    const char *specs[] = {"bvh", "bvh:traverse=packet", "bvh:traverse=packet,frustum=1"};
    for (size_t i = 0; i < 3; i++) {
        void *a = test_build(specs[i], &s, 1, NULL);
        if (!a) continue;
        accel_hit *h0 = malloc(n * sizeof *h0), *h1 = malloc(n * sizeof *h1);
        uint32_t *steps = malloc(n * sizeof *steps), *prims = malloc(n * sizeof *prims);
        accel_counters c;
        memset(&c, 0, sizeof c);
        c.ray_steps = steps;
        c.ray_prims = prims;
        accel_kind_bvh.intersect(a, rays, h0, n, NULL);
        accel_kind_bvh.intersect(a, rays, h1, n, &c);
        CHECKF(memcmp(h0, h1, n * sizeof *h0) == 0, "%s: counted trace differs", specs[i]);
        uint64_t ss = 0, sp = 0;
        for (size_t k = 0; k < n; k++) ss += steps[k], sp += prims[k];
        CHECK(c.rays == n);
        CHECKF(ss == c.steps && sp == c.prim_tests, "%s: per-ray sums %llu/%llu vs %llu/%llu",
               specs[i], (unsigned long long)ss, (unsigned long long)sp,
               (unsigned long long)c.steps, (unsigned long long)c.prim_tests);
        CHECK(c.steps > 0 && c.box_tests > 0 && c.prim_tests > 0);
        /* every ray that hits tested at least one primitive and visited a leaf */
        for (size_t k = 0; k < n; k++)
            if (h0[k].prim != ACCEL_MISS) CHECK(steps[k] >= 1 && prims[k] >= 1);
        /* single rays: one root test, then two per interior node visited */
        if (i == 0) CHECK(c.box_tests <= c.rays + 2 * c.steps && c.box_tests > c.steps);
        if (i < 2) CHECK(c.packet_box_tests == 0);
        free(h0);
        free(h1);
        free(steps);
        free(prims);
        accel_kind_bvh.destroy(a);
    }
    test_rays_free(&r);
    /* The frustum test runs on coherent packets (primary tiles) only. */
    accel_error err = {0};
    rays_set pr = {0};
    void *a = test_build("bvh:traverse=packet,frustum=1", &s, 1, NULL);
    if (a && rays_primary(&s.camera, 32, 32, &pr, &err) == 0) {
        accel_hit *h = malloc(pr.count * sizeof *h);
        accel_counters c;
        memset(&c, 0, sizeof c);
        accel_kind_bvh.intersect(a, pr.rays, h, pr.count, &c);
        CHECK(c.packet_box_tests > 0 && c.rays == pr.count);
        free(h);
    }
    rays_free(&pr);
    if (a) accel_kind_bvh.destroy(a);
    scene_free(&s);
}

/* ---- saving and loading ----------------------------------------------------------------- */

TEST(bvh_save_load)
{
    accel_scene s;
    if (!test_make_scene("sphereflake:level=2", &s)) return;
    void *a = test_build("bvh:traverse=packet", &s, 1, NULL);
    if (!a) {
        scene_free(&s);
        return;
    }
    char path[64];
    snprintf(path, sizeof path, "/tmp/gridbvh_test_%d.bvh", (int)getpid());
    accel_error err = {0};
    CHECKF(bvh_save(a, path, &err) == 0, "save: %s", err.msg);
    void *b = NULL;
    CHECKF(bvh_load(path, &b, &err) == 0, "load: %s", err.msg);
    if (b) {
        uint32_t n1, n2, p1, p2;
        const bvh_node *x = bvh_nodes(a, &n1), *y = bvh_nodes(b, &n2);
        CHECK(n1 == n2 && memcmp(x, y, n1 * sizeof *x) == 0);
        CHECK(((uintptr_t)y & 63) == 0);
        const uint32_t *i1 = bvh_prim_ids(a, &p1), *i2 = bvh_prim_ids(b, &p2);
        CHECK(p1 == p2 && memcmp(i1, i2, p1 * sizeof *i1) == 0);
        test_rays r = {0};
        test_rays_random(&r, s.bounds, 700);
        accel_ray *rays = r.rays;
        test_check_accel(&s, &accel_kind_bvh, b, "loaded bvh", rays, 700, NULL, NULL);
        test_rays_free(&r);
        accel_kind_bvh.destroy(b);
    }
    /* Point a child pair at another node's pair (two parents): refused. */
    uint32_t nc;
    const bvh_node *nodes = bvh_nodes(a, &nc);
    uint32_t victim = 0; /* an interior node whose pair is not 2 */
    for (uint32_t i = 2; i < nc && !victim; i++)
        if (!nodes[i].count && nodes[i].left_first != 2) victim = i;
    CHECK(victim != 0);
    FILE *f = fopen(path, "r+b");
    if (f && victim) {
        uint32_t two = 2;
        fseek(f, 32 + 32 * (long)victim + 12, SEEK_SET);
        fwrite(&two, 4, 1, f);
        fclose(f);
        b = NULL;
        CHECK(bvh_load(path, &b, &err) == ACCEL_ERR_PARSE && b == NULL);
        CHECK(bvh_save(a, path, &err) == 0); /* restore for the next case */
    } else if (f) {
        fclose(f);
    }
    /* Corrupt a child index: the loader refuses the file. */
    f = fopen(path, "r+b");
    if (f) {
        uint32_t bad = 1; /* node 0's left_first: odd, and the padding node */
        fseek(f, 32 + 12, SEEK_SET);
        fwrite(&bad, 4, 1, f);
        fclose(f);
        b = NULL;
        CHECK(bvh_load(path, &b, &err) == ACCEL_ERR_PARSE && b == NULL);
        CHECK(strstr(err.msg, "child") != NULL);
    }
    /* Truncated file. */
    f = fopen(path, "wb");
    if (f) {
        fwrite("BVH1", 1, 4, f);
        fclose(f);
        CHECK(bvh_load(path, &b, &err) == ACCEL_ERR_PARSE);
    }
    remove(path);
    CHECK(bvh_load("/nonexistent/x.bvh", &b, &err) == ACCEL_ERR_IO);
    accel_kind_bvh.destroy(a);
    scene_free(&s);
}
