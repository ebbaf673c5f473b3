/*
 * test_bvh_wide_trace.c - the wide BVHs traced against the double-precision
 * reference where the shared suites do not reach: the scanned meshes
 * (test_conformance.c runs only each kind's default there) with primary,
 * shadow, diffuse and vertex-aimed rays, for every width and block size;
 * the invariants the conformance suite checks only for defaults (counted
 * and uncounted traces identical, 1 and 2 threads identical, the step
 * bound never broken); the naive triangle test, spheres, and empty scenes.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rays/stiff.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

static const char *const wide_specs[] = {"bvh:width=4", "bvh:width=8", "bvh:width=4,block=4",
                                         "bvh:width=8,block=4", "bvh:width=8,order=dist",
                                         "bvh:width=4,block=4,order=dist", "bvh:width=8,traverse=packet",
                                         "bvh:width=4,block=4,traverse=packet"};
#define WIDE_SPEC_COUNT 8

typedef struct {
    const char *name;
    rays_set rays;
    accel_hit *ref;
} ref_set;

static void ref_of(const accel_scene *s, ref_set *r)
{
    size_t n = r->rays.count;
    r->ref = malloc((n ? n : 1) * sizeof *r->ref);
    accel_reference_trace(s, r->rays.rays, r->ref, n, accel_cpu_count());
}

/* Traces one set with an accel; fails on any hole, false hit,
 * disagreement or occlusion mismatch. Returns the bad ray count. */
static size_t check_set(const accel_kind *k, const void *a, const accel_scene *s, const ref_set *r,
                        const char *spec)
{
    size_t n = r->rays.count;
    accel_hit *h = malloc((n ? n : 1) * sizeof *h);
    uint8_t *occ = malloc(n ? n : 1);
    accel_trace(k, a, r->rays.rays, h, n, 1, NULL);
    accel_trace_occluded(k, a, r->rays.rays, occ, n, 1, NULL);
    hits_diff d = hits_compare(s, r->rays.rays, r->ref, h, n);
    size_t occ_bad = 0;
    for (size_t i = 0; i < n; i++) occ_bad += occ[i] != (r->ref[i].prim != ACCEL_MISS);
    size_t bad = d.holes + d.false_hits + d.disagreements + occ_bad;
    if (bad) {
        size_t i = d.first_bad != SIZE_MAX ? d.first_bad : 0;
        test_fail(__FILE__, __LINE__,
                  "%s on %s/%s: %zu holes, %zu false hits, %zu disagreements, %zu occluded "
                  "mismatches of %zu rays (first %zu: ref %u t %.9g, got %u t %.9g)",
                  spec, s->name, r->name, d.holes, d.false_hits, d.disagreements, occ_bad, n, i,
                  r->ref[i].prim, r->ref[i].t, h[i].prim, h[i].t);
    }
    free(h);
    free(occ);
    return bad;
}

/* Primary, shadow, diffuse and vertex-aimed rays on one scene. */
static int make_sets(const accel_scene *s, int size, ref_set *sets)
{
    accel_error err = {0};
    memset(sets, 0, 4 * sizeof *sets);
    sets[0].name = "primary";
    if (rays_primary(&s->camera, size, size, &sets[0].rays, &err)) return 0;
    ref_of(s, &sets[0]);
    sets[1].name = "shadow";
    sets[2].name = "diffuse";
    sets[3].name = "vertex";
    if (rays_shadow(s, &sets[0].rays, sets[0].ref, &sets[1].rays, &err) ||
        rays_diffuse(s, &sets[0].rays, sets[0].ref, 5, &sets[2].rays, &err) ||
        stiff_add_vertex_rays(s, s->camera.eye, 400, 11, &sets[3].rays, &err)) {
        test_fail(__FILE__, __LINE__, "%s: rays: %s", s->name, err.msg);
        return 0;
    }
    for (int i = 1; i < 4; i++) ref_of(s, &sets[i]);
    return 1;
}

static void free_sets(ref_set *sets)
{
    for (int i = 0; i < 4; i++) {
        rays_free(&sets[i].rays);
        free(sets[i].ref);
    }
}

/* Builds each spec (on `threads` threads) and checks it on every set. */
static void check_specs_on(const accel_scene *s, const char *const *specs, size_t spec_count, int threads,
                           const ref_set *sets, int set_count)
{
    for (size_t k = 0; k < spec_count; k++) {
        accel_error err = {0};
        const accel_kind *kind;
        void *a;
        accel_build_stats st;
        if (accel_build_spec(specs[k], s, threads, &kind, &a, &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s on %s: %s", specs[k], s->name, err.msg);
            continue;
        }
        for (int i = 0; i < set_count; i++) check_set(kind, a, s, &sets[i], specs[k]);
        kind->destroy(a);
    }
}

TEST(bvh_wide_shared_meshes_against_reference)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_skip("../shared/scenes not found");
        return;
    }
    static const char *const meshes[] = {"bunny.off", "armadillo.off"};
    for (size_t m = 0; m < 2; m++) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s", dir, meshes[m]);
        accel_scene s;
        accel_error err = {0};
        if (scene_create(path, &s, &err)) {
            test_note("skipped %s: %s", path, err.msg);
            continue;
        }
        ref_set sets[4];
        if (make_sets(&s, 32, sets)) check_specs_on(&s, wide_specs, WIDE_SPEC_COUNT, 2, sets, 4);
        free_sets(sets);
        scene_free(&s);
    }
}

/* Built-in scenes with the wide specs' counted traces: same hits as the
 * timed copies, the same with 2 threads and a 2-thread build, no broken
 * step bound, per-ray costs filled in. */
TEST(bvh_wide_invariants)
{
    static const char *const scenes[] = {"teapot_stadium:n=4,stadium=16,tiers=3", "sphereflake:level=2",
                                         "slivers:tris=3000,slivers=100"};
    for (size_t si = 0; si < sizeof scenes / sizeof *scenes; si++) {
        accel_scene s;
        accel_error err = {0};
        if (scene_create(scenes[si], &s, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", scenes[si], err.msg);
            continue;
        }
        ref_set sets[4];
        if (!make_sets(&s, 24, sets)) {
            free_sets(sets);
            scene_free(&s);
            continue;
        }
        check_specs_on(&s, wide_specs, WIDE_SPEC_COUNT, 2, sets, 4);
        for (int k = 0; k < WIDE_SPEC_COUNT; k++) {
            const accel_kind *kind, *k2;
            void *a, *a2;
            accel_build_stats st, st2;
            if (accel_build_spec(wide_specs[k], &s, 1, &kind, &a, &st, &err)) continue;
            if (accel_build_spec(wide_specs[k], &s, 2, &k2, &a2, &st2, &err)) {
                kind->destroy(a);
                continue;
            }
            CHECKF(st.bytes == st2.bytes && st.nodes == st2.nodes, "%s: 2-thread build differs", wide_specs[k]);
            for (int i = 0; i < 4; i++) {
                size_t n = sets[i].rays.count;
                accel_hit *h1 = malloc((n ? n : 1) * sizeof *h1), *h2 = malloc((n ? n : 1) * sizeof *h2);
                uint32_t *steps = calloc(n ? n : 1, sizeof *steps);
                accel_counters c = {0};
                c.ray_steps = steps;
                accel_trace(kind, a, sets[i].rays.rays, h1, n, 1, NULL);
                accel_trace(kind, a, sets[i].rays.rays, h2, n, 1, &c);
                CHECKF(!memcmp(h1, h2, n * sizeof *h1), "%s on %s/%s: counted trace differs",
                       wide_specs[k], s.name, sets[i].name);
                CHECKF(accel_counters_status(&c, &err) == 0, "%s: %s", wide_specs[k], err.msg);
                CHECKF(c.rays == n && (n == 0 || c.steps > 0), "%s: counters %llu rays", wide_specs[k],
                       (unsigned long long)c.rays);
                uint64_t sum = 0;
                for (size_t r = 0; r < n; r++) sum += steps[r];
                CHECKF(sum == c.steps, "%s: per-ray steps sum to %llu of %llu", wide_specs[k],
                       (unsigned long long)sum, (unsigned long long)c.steps);
                accel_trace(k2, a2, sets[i].rays.rays, h2, n, 2, NULL);
                CHECKF(!memcmp(h1, h2, n * sizeof *h1), "%s on %s/%s: 2 threads / 2-thread build differ",
                       wide_specs[k], s.name, sets[i].name);
                free(h1);
                free(h2);
                free(steps);
            }
            kind->destroy(a);
            k2->destroy(a2);
        }
        free_sets(sets);
        scene_free(&s);
    }
}

/* The naive test per lane: the wide trees find the same closest hits as
 * the binary tree with the same (non-robust) triangle test. */
TEST(bvh_wide_naive_matches_binary_naive)
{
    accel_scene s;
    accel_error err = {0};
    if (scene_create("soup:tris=3000", &s, &err)) return;
    ref_set sets[4];
    if (make_sets(&s, 32, sets)) {
        const accel_kind *k;
        void *bin, *w;
        accel_build_stats st;
        if (accel_build_spec("bvh:tri=naive", &s, 1, &k, &bin, &st, &err) == 0) {
            const char *specs[] = {"bvh:width=4,tri=naive", "bvh:width=8,block=8,tri=naive"};
            for (int j = 0; j < 2; j++) {
                if (accel_build_spec(specs[j], &s, 1, &k, &w, &st, &err)) {
                    test_fail(__FILE__, __LINE__, "%s: %s", specs[j], err.msg);
                    continue;
                }
                for (int i = 0; i < 4; i++) {
                    size_t n = sets[i].rays.count;
                    accel_hit *h1 = malloc((n ? n : 1) * sizeof *h1), *h2 = malloc((n ? n : 1) * sizeof *h2);
                    accel_trace(k, bin, sets[i].rays.rays, h1, n, 1, NULL);
                    accel_trace(k, w, sets[i].rays.rays, h2, n, 1, NULL);
                    hits_diff d = hits_compare(&s, sets[i].rays.rays, h1, h2, n);
                    CHECKF(d.agree == n, "%s/%s: %zu of %zu rays differ from bvh:tri=naive", specs[j],
                           sets[i].name, n - d.agree, n);
                    free(h1);
                    free(h2);
                }
                k->destroy(w);
            }
            k->destroy(bin);
        }
    }
    free_sets(sets);
    scene_free(&s);
}

/* Empty scenes and scenes of one primitive (the root is then a leaf). */
TEST(bvh_wide_tiny_scenes)
{
    scene_builder b = {0};
    accel_error err = {0};
    accel_scene one, none;
    CHECK(scene_builder_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), &err) == 0);
    CHECK(scene_finish(&b, "one", &one, &err) == 0);
    scene_builder_free(&b);
    memset(&b, 0, sizeof b);
    CHECK(scene_finish(&b, "none", &none, &err) == 0);
    scene_builder_free(&b);
    accel_ray rays[3] = {{0.2f, 0.2f, 1, 0, 0, 0, -1, INFINITY},
                         {0.2f, 0.2f, 1, 0, 0, 0, -1, 0.5f},
                         {2, 2, 1, 0, 0, 0, -1, INFINITY}};
    for (int k = 0; k < WIDE_SPEC_COUNT; k++) {
        for (int sc = 0; sc < 2; sc++) {
            const accel_kind *kind;
            void *a;
            accel_build_stats st;
            if (accel_build_spec(wide_specs[k], sc ? &none : &one, 1, &kind, &a, &st, &err)) {
                test_fail(__FILE__, __LINE__, "%s: %s", wide_specs[k], err.msg);
                continue;
            }
            accel_hit h[3];
            uint8_t occ[3];
            accel_counters c = {0};
            accel_trace(kind, a, rays, h, 3, 1, &c);
            accel_trace_occluded(kind, a, rays, occ, 3, 1, NULL);
            int expect0 = sc == 0;
            CHECKF((h[0].prim == 0) == expect0 && occ[0] == expect0, "%s: ray 0", wide_specs[k]);
            if (expect0) CHECKF(fabsf(h[0].t - 1.0f) < 1e-6f, "%s: t %g", wide_specs[k], h[0].t);
            CHECKF(h[1].prim == ACCEL_MISS && !occ[1], "%s: ray 1 stops short", wide_specs[k]);
            CHECKF(h[2].prim == ACCEL_MISS && !occ[2] && h[2].t == INFINITY, "%s: ray 2", wide_specs[k]);
            kind->destroy(a);
        }
    }
    scene_free(&one);
    scene_free(&none);
}

/* Rays whose range starts behind their origin (t_near < 0, as a .rays
 * file may give): the primary rays that hit moved forward past their hit,
 * with t_near reaching back to the camera, so that the answer is mostly a
 * hit behind the origin; and the primary rays ending exactly at their hit
 * (the sets support.c makes for the conformance suite). The wide kernels
 * take the slab test's old padding for the first (ACCEL_FAR_PAD in
 * core/geom.h: the folded padding is proven for t_near >= 0 only); every
 * width, order and layout against the reference, which the conformance
 * suite runs only for the kinds' listed variants. */
TEST(bvh_wide_negative_t_near)
{
    static const char *const specs[] = {"bvh:width=8", "bvh:width=8,order=branchy", "bvh:width=8,quant=1",
                                        "bvh:width=4,block=4,order=branchy", "bvh:width=8,order=dist",
                                        "bvh:width=8,traverse=packet", "bvh"};
    static const char *const scenes[] = {"teapot_stadium:n=4,stadium=16,tiers=3", "sphereflake:level=2"};
    for (size_t si = 0; si < sizeof scenes / sizeof *scenes; si++) {
        accel_scene s;
        accel_error err = {0};
        if (!test_make_scene(scenes[si], &s)) continue;
        ref_set primary = {"primary", {0}, NULL};
        if (rays_primary(&s.camera, 40, 40, &primary.rays, &err)) {
            test_fail(__FILE__, __LINE__, "%s: rays: %s", s.name, err.msg);
            scene_free(&s);
            continue;
        }
        ref_of(&s, &primary);
        ref_set sets[2] = {{"behind the origin", {0}, NULL}, {"ending at the hit", {0}, NULL}};
        test_rays behind = {0}, ending = {0};
        test_rays_behind(&behind, primary.rays.rays, primary.ref, primary.rays.count);
        test_rays_ending_at_hit(&ending, primary.rays.rays, primary.ref, primary.rays.count);
        sets[0].rays.rays = behind.rays, sets[0].rays.count = behind.count;
        sets[1].rays.rays = ending.rays, sets[1].rays.count = ending.count;
        ref_of(&s, &sets[0]);
        ref_of(&s, &sets[1]);
        size_t back = 0, hits = 0;
        for (size_t i = 0; i < sets[0].rays.count; i++) {
            hits += sets[0].ref[i].prim != ACCEL_MISS;
            back += sets[0].ref[i].prim != ACCEL_MISS && sets[0].ref[i].t < 0.0f;
        }
        CHECKF(back > hits / 2, "%s: %zu hits behind the origin of %zu hits", s.name, back, hits);
        check_specs_on(&s, specs, sizeof specs / sizeof *specs, 1, sets, 2);
        for (int i = 0; i < 2; i++) {
            free(sets[i].rays.rays);
            free(sets[i].ref);
        }
        rays_free(&primary.rays);
        free(primary.ref);
        scene_free(&s);
    }
}

/* The packet class of a ray: its octant and dominant axis (rays of one
 * class from one origin share the watertight test's permuted axes). */
static int packet_class(const accel_ray *r)
{
    float d[3] = {r->dx, r->dy, r->dz};
    float ax = fabsf(d[0]), ay = fabsf(d[1]), az = fabsf(d[2]);
    int kz = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
    return (signbit(d[0]) != 0) | (signbit(d[1]) != 0) << 1 | (signbit(d[2]) != 0) << 2 | kz << 3;
}

static int by_class(const void *a, const void *b)
{
    int ca = packet_class(a), cb = packet_class(b);
    return (ca > cb) - (ca < cb);
}

/* The class, then a Morton code of the direction's two minor components
 * over its dominant one (the watertight test's shear, up to order and
 * sign): neighbours in this order are neighbours on the screen, so the
 * groups of 8 of a packet have small rectangles of shears, as a tile of
 * primary rays has, and the leaf cull (core/block_test.h, aff_cull_rect; the
 * binary packets' aff_misses) is tried with its margins on rays through
 * vertices and edges. */
static uint64_t shear_key(const accel_ray *r)
{
    float d[3] = {r->dx, r->dy, r->dz};
    int c = packet_class(r), kz = c >> 3, kx = (kz + 1) % 3, ky = (kz + 2) % 3;
    uint32_t q[2];
    for (int i = 0; i < 2; i++) {
        float s = d[i ? ky : kx] / fabsf(d[kz]); /* in [-1, 1] */
        q[i] = (uint32_t)((s + 1.0f) * 32767.0f);
    }
    uint64_t m = 0;
    for (int bit = 0; bit < 16; bit++)
        m |= (uint64_t)(q[0] >> bit & 1) << (2 * bit) | (uint64_t)(q[1] >> bit & 1) << (2 * bit + 1);
    return (uint64_t)c << 32 | m;
}

static int by_class_shear(const void *a, const void *b)
{
    uint64_t ka = shear_key(a), kb = shear_key(b);
    return (ka > kb) - (ka < kb);
}

/* Packets whose rays share their origin and permuted axes test a leaf's
 * blocks with the block's vertices relative to that origin computed once
 * (bvh/wide/packet.h, leaf_by_block; the binary packets likewise per
 * triangle, bvh_packet.c). Rays from one eye aimed exactly at
 * vertices and edge midpoints, grouped by class so that most packets of
 * 64 are such packets, put every lane's error bounds and the double
 * fallback to work there; hybrid=0 keeps every leaf in the packet. */
TEST(bvh_wide_packets_shared_origin_at_vertices)
{
    static const char *const specs[] = {"bvh:width=8,traverse=packet,hybrid=0",
                                        "bvh:width=4,block=4,traverse=packet,hybrid=0",
                                        "bvh:width=8,block=4,traverse=packet", "bvh:traverse=packet",
                                        "bvh:traverse=packet,frustum=1"};
    static const char *const scenes[] = {"teapot_stadium:n=4,stadium=16,tiers=3",
                                         "sphereflake:level=2,spheres=0"};
    for (size_t si = 0; si < sizeof scenes / sizeof *scenes; si++) {
        accel_scene s;
        accel_error err = {0};
        if (!test_make_scene(scenes[si], &s)) continue;
        ref_set set = {"vertex, one eye", {0}, NULL};
        if (stiff_add_vertex_rays(&s, s.camera.eye, 6000, 5, &set.rays, &err)) {
            test_fail(__FILE__, __LINE__, "%s: rays: %s", s.name, err.msg);
            scene_free(&s);
            continue;
        }
        for (int order = 0; order < 2; order++) {
            qsort(set.rays.rays, set.rays.count, sizeof *set.rays.rays, order ? by_class_shear : by_class);
            size_t shared = 0;
            for (size_t b = 0; b + 64 <= set.rays.count; b += 64)
                shared += packet_class(&set.rays.rays[b]) == packet_class(&set.rays.rays[b + 63]);
            CHECKF(shared >= set.rays.count / 64 / 2, "%s: %zu of %zu packets of one class", s.name, shared,
                   set.rays.count / 64);
            free(set.ref);
            set.ref = NULL;
            ref_of(&s, &set);
            size_t hits = 0;
            for (size_t i = 0; i < set.rays.count; i++) hits += set.ref[i].prim != ACCEL_MISS;
            CHECKF(hits > set.rays.count / 2, "%s: %zu hits of %zu rays", s.name, hits, set.rays.count);
            check_specs_on(&s, specs, sizeof specs / sizeof *specs, 1, &set, 1);
        }
        rays_free(&set.rays);
        free(set.ref);
        scene_free(&s);
    }
}
