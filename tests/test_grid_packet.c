/*
 * test_grid_packet.c - the coherent grid traversal (grid:traverse=packet,
 * grid/grid_packet_trace.c) against the double-precision reference, on packets
 * built to walk: a common origin (camera), rays converging on a point
 * (shadow rays to a light), scattered origins with finite and offset t
 * ranges, axis rays with +0/-0 components starting on the box faces, rays
 * aimed exactly at vertices, invalid rays inside packets, partial packets;
 * every walk direction (x, y, z, each sign); several resolutions; a scene
 * far from the origin. Zero holes, false hits, disagreements and occlusion
 * mismatches are required, and the counters must show that the packets
 * were walked (4-ray filter evaluations), not handed to the single-ray
 * kernel. Also: incoherent packets fall back (hits byte-identical to the
 * single-ray grid), and packets test far fewer primitives per ray.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/coherence.h"
#include "grid/grid.h"
#include "rays/rays.h"
#include "support.h"
#include "scene/scene.h"
#include "test.h"

#define PACKETS 48

static float rnd(uint64_t i, uint32_t d) { return rays_rand(0x5eed, i, d); }

/* Packet p of coherent rays (64, fewer for the last) into r; returns the count. */
static size_t coherent_packet(const accel_scene *s, int p, accel_ray *r, int n)
{
    const float lo[3] = {s->bounds.min.x, s->bounds.min.y, s->bounds.min.z};
    const float hi[3] = {s->bounds.max.x, s->bounds.max.y, s->bounds.max.z};
    float c[3], e[3], diag = 0.0f;
    for (int a = 0; a < 3; a++) {
        c[a] = 0.5f * (lo[a] + hi[a]);
        e[a] = hi[a] - lo[a];
        diag += e[a] * e[a];
    }
    diag = sqrtf(diag);
    const int mode = p % 6, K = (p / 6) % 3;
    const float sg = (p / 18) % 2 ? -1.0f : 1.0f;
    float base[3], eye[3], light[3];
    for (int a = 0; a < 3; a++) {
        base[a] = a == K ? sg : 0.6f * (rnd((uint64_t)p, (uint32_t)a) - 0.5f);
        eye[a] = c[a] - (a == K ? sg * diag : 0.2f * diag * (rnd((uint64_t)p, 3u + (uint32_t)a) - 0.5f));
        light[a] = c[a] + (a == K ? sg * diag : 0.5f * e[a] * (rnd((uint64_t)p, 6u + (uint32_t)a) - 0.5f));
    }
    for (int i = 0; i < n; i++) {
        const uint64_t q = (uint64_t)p * 64 + (uint64_t)i;
        float o[3], d[3], t_near = 0.0f, t_far = INFINITY;
        for (int a = 0; a < 3; a++) {
            o[a] = eye[a];
            d[a] = base[a] + (a == K ? 0.0f : 0.05f * (rnd(q, 10u + (uint32_t)a) - 0.5f));
        }
        if (mode == 1 || mode == 2) { /* scattered origins */
            for (int a = 0; a < 3; a++) o[a] = lo[a] + e[a] * rnd(q, 20u + (uint32_t)a);
        }
        if (mode == 1) { /* converging on a light, as shadow rays */
            for (int a = 0; a < 3; a++) d[a] = light[a] - o[a];
            t_far = 1.0f - 0x1p-12f;
        } else if (mode == 2) {
            t_near = i % 3 == 0 ? 0.1f * diag * rnd(q, 30) : 0.0f;
            t_far = i % 2 == 0 ? 0.6f * diag : INFINITY;
        } else if (mode == 3) { /* axis rays from the box face, +0/-0 elsewhere */
            for (int a = 0; a < 3; a++) {
                const int g = a == (K + 1) % 3 ? i % 8 : i / 8;
                o[a] = a == K ? (sg > 0 ? lo[a] : hi[a]) : lo[a] + e[a] * (float)g / 7.0f;
                d[a] = a == K ? sg : ((i + a) & 1 ? -0.0f : 0.0f);
            }
        } else if (mode == 4 && s->tri_count) { /* exactly at vertices */
            const uint32_t prim = s->live[(size_t)(rnd(q, 40) * (float)s->live_count)];
            if (prim < s->tri_count) {
                const float *v = s->tris + 9 * (size_t)prim + 3 * (i % 3);
                for (int a = 0; a < 3; a++) d[a] = v[a] - o[a];
            }
        } else if (mode == 5) { /* invalid rays among valid ones */
            if (i == 5) o[0] = NAN;
            if (i == 9) t_near = 2.0f, t_far = 1.0f;
            if (i == 13) d[0] = d[1] = d[2] = 0.0f;
            if (i == 17) d[(K + 1) % 3] = -0.0f;
        }
        accel_ray ray = {o[0], o[1], o[2], t_near, d[0], d[1], d[2], t_far};
        r[i] = ray;
    }
    return (size_t)n;
}

static accel_ray *coherent_rays(const accel_scene *s, size_t *count)
{
    accel_ray *r = malloc((size_t)PACKETS * 64 * sizeof *r);
    size_t n = 0;
    for (int p = 0; r && p < PACKETS; p++)
        n += coherent_packet(s, p, r + n, p == PACKETS - 1 ? 37 : 64);
    *count = n;
    return r;
}

/* Traces rays with spec; checks hits and occlusion against ref and that
 * packets were walked. Returns the counted pass's counters. */
static accel_counters check_spec(const accel_scene *s, const char *spec, const accel_ray *rays,
                                 size_t n, const accel_hit *ref)
{
    accel_counters c;
    memset(&c, 0, sizeof c);
    const accel_kind *k;
    void *a = test_build_kind(spec, s, 1, &k, NULL);
    if (!a) return c;
    accel_hit *h = malloc(n * sizeof *h), *h2 = malloc(n * sizeof *h2);
    uint8_t *occ = malloc(n);
    accel_trace(k, a, rays, h, n, 1, NULL);
    accel_trace_occluded(k, a, rays, occ, n, 1, NULL);
    accel_trace(k, a, rays, h2, n, 2, &c);
    hits_diff d = hits_compare(s, rays, ref, h, n);
    size_t occ_bad = 0;
    for (size_t i = 0; i < n; i++) occ_bad += occ[i] != (ref[i].prim != ACCEL_MISS);
    CHECKF(d.holes + d.false_hits + d.disagreements + occ_bad == 0,
           "%s on %s: %zu holes, %zu false hits, %zu disagreements, %zu occluded mismatches of %zu "
           "(first ray %zu)", spec, s->name, d.holes, d.false_hits, d.disagreements, occ_bad, n,
           d.first_bad);
    CHECKF(memcmp(h, h2, n * sizeof *h) == 0, "%s on %s: counted, 2-thread trace differs", spec,
           s->name);
    accel_error broken = {0};
    CHECKF(accel_counters_status(&c, &broken) == 0, "%s: %s", spec, broken.msg);
    CHECKF(c.rays == n, "%s: counters saw %llu rays of %zu", spec, (unsigned long long)c.rays, n);
    free(h);
    free(h2);
    free(occ);
    k->destroy(a);
    return c;
}

TEST(grid_packet_coherent_packets_match_reference)
{
    static const char *const scenes[] = {"sphere:segments=16", "soup:tris=1500,seed=4",
                                         "sphereflake:level=1", "cube:n=8", "tetra:level=3"};
    static const char *const specs[] = {"grid:traverse=packet", "grid:traverse=packet,res=64",
                                        "grid:traverse=packet,res=7x1x13",
                                        "grid:traverse=packet,mailbox=0",
                                        "grid:traverse=packet,lambda=0.5",
                                        /* the nested grid's levels (ngrid_packet.c) */
                                        "nested_grid:traverse=packet",
                                        "nested_grid:traverse=packet,threshold=1,depth=4,sub_res=3",
                                        "nested_grid:traverse=packet,layout=compact,threshold=1",
                                        "nested_grid:traverse=packet,mailbox=0,threshold=2"};
    for (size_t si = 0; si < sizeof scenes / sizeof scenes[0]; si++) {
        accel_scene s;
        accel_error err = {0};
        if (scene_create(scenes[si], &s, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", scenes[si], err.msg);
            continue;
        }
        size_t n;
        accel_ray *rays = coherent_rays(&s, &n);
        accel_hit *ref = malloc(n * sizeof *ref);
        accel_reference_trace(&s, rays, ref, n, 2);
        size_t hits = 0;
        for (size_t i = 0; i < n; i++) hits += ref[i].prim != ACCEL_MISS;
        CHECKF(hits > n / 8, "%s: only %zu of %zu rays hit: the packets test too little", s.name,
               hits, n);
        for (size_t v = 0; v < sizeof specs / sizeof specs[0]; v++) {
            accel_counters c = check_spec(&s, specs[v], rays, n, ref);
            /* Walked, not handed to the single-ray kernel: the 4-ray filter ran. */
            CHECKF(c.packet_box_tests > 0, "%s on %s: no packet was walked", specs[v], s.name);
        }
        free(ref);
        free(rays);
        scene_free(&s);
    }
}

TEST(grid_packet_far_from_origin)
{
    accel_scene base, s;
    accel_error err = {0};
    CHECK(scene_create("sphere:segments=12", &base, &err) == 0);
    for (int f = 0; f < 2; f++) {
        const float off = f ? 1e6f : -3e4f;
        CHECKF(scene_transform(&base, f ? 0.5f : 2.0f, v3(off, -off, 0.5f * off), &s, &err) == 0,
               "%s", err.msg);
        size_t n;
        accel_ray *rays = coherent_rays(&s, &n);
        accel_hit *ref = malloc(n * sizeof *ref);
        accel_reference_trace(&s, rays, ref, n, 2);
        accel_counters c = check_spec(&s, "grid:traverse=packet", rays, n, ref);
        CHECKF(c.packet_box_tests > 0, "offset %g: no packet was walked", (double)off);
        check_spec(&s, "grid:traverse=packet,res=32", rays, n, ref);
        c = check_spec(&s, "nested_grid:traverse=packet,threshold=1,sub_res=4", rays, n, ref);
        CHECKF(c.packet_box_tests > 0, "offset %g: no nested packet was walked", (double)off);
        free(ref);
        free(rays);
        scene_free(&s);
    }
    scene_free(&base);
}

/* Primary rays of a closed mesh: the same hits as the single-ray grid with
 * far fewer exact primitive tests per ray: with ids (a test per ray and
 * triangle the filter keeps) a quarter; with blocks (a block test of 8
 * lanes per ray some triangle of the block kept, counted as its real
 * lanes) a half. */
TEST(grid_packet_fewer_tests_than_single_rays)
{
    accel_scene s;
    accel_error err = {0};
    CHECK(scene_create("sphere:segments=48", &s, &err) == 0);
    rays_set r;
    CHECK(rays_primary(&s.camera, 128, 128, &r, &err) == 0);
    static const char *const pairs[2][2] = {{"grid:cells=ids", "grid:traverse=packet,cells=ids"},
                                            {"grid:lambda=8", "grid:traverse=packet"}};
    static const int factor[2] = {4, 2};
    for (int p = 0; p < 2; p++) {
        accel_hit *h[2];
        accel_counters c[2];
        for (int i = 0; i < 2; i++) {
            const accel_kind *k;
            void *a;
            accel_build_stats st;
            CHECK(accel_build_spec(pairs[p][i], &s, 1, &k, &a, &st, &err) == 0);
            h[i] = malloc(r.count * sizeof *h[i]);
            memset(&c[i], 0, sizeof c[i]);
            accel_trace(k, a, r.rays, h[i], r.count, 1, &c[i]);
            k->destroy(a);
        }
        size_t agree = 0, hit = 0;
        for (size_t i = 0; i < r.count; i++) {
            agree += hits_agree(&s, &r.rays[i], &h[0][i], &h[1][i]);
            hit += h[0][i].prim != ACCEL_MISS;
        }
        CHECKF(agree == r.count, "%s: %zu of %zu primary hits differ", pairs[p][1],
               r.count - agree, r.count);
        CHECK(hit > r.count / 10);
        CHECKF(c[1].prim_tests * (uint64_t)factor[p] < c[0].prim_tests && c[1].prim_tests >= hit,
               "%s: exact tests: packet %llu, single %llu, hits %zu", pairs[p][1],
               (unsigned long long)c[1].prim_tests, (unsigned long long)c[0].prim_tests, hit);
        CHECK(c[0].packet_box_tests == 0 && c[1].packet_box_tests > 0);
        CHECK(c[1].steps > 0 && c[1].box_tests == r.count);
        for (int i = 0; i < 2; i++) free(h[i]);
    }
    rays_free(&r);
    scene_free(&s);
}

/* Packets with mixed direction signs (diffuse-like) go to the single-ray
 * kernel: byte-identical hits, no filter evaluated; on blocks the
 * single-ray kernel is the block grid's (no mailbox, at the packets'
 * lambda 8), on ids the per-id grid's. */
TEST(grid_packet_incoherent_packets_fall_back)
{
    accel_scene s;
    accel_error err = {0};
    CHECK(scene_create("soup:tris=800,seed=9", &s, &err) == 0);
    const size_t n = 64 * 20 + 11;
    accel_ray *rays = malloc(n * sizeof *rays);
    vec3 c = v3_scale(v3_add(s.bounds.min, s.bounds.max), 0.5f);
    for (size_t i = 0; i < n; i++) {
        /* Ray 0 of each packet points +x, ray 1 -x, and so on: mixed signs on every axis. */
        float d[3];
        for (int a = 0; a < 3; a++) d[a] = (rnd(i, 50u + (uint32_t)a) - 0.5f) * ((i & 1) ? -1.0f : 1.0f);
        d[i % 3] = (i & 1) ? -1.0f : 1.0f;
        accel_ray r = {c.x, c.y, c.z, 0.0f, d[0], d[1], d[2], INFINITY};
        rays[i] = r;
    }
    static const char *const pairs[2][2] = {{"grid:cells=ids", "grid:traverse=packet,cells=ids"},
                                            {"grid:lambda=8", "grid:traverse=packet"}};
    /* the packets as given: sorted (core/coherence.h), these rays make
     * coherent packets that walk */
    const int order = accel_coherence_get();
    accel_coherence_set(ACCEL_ORDER_KEEP);
    for (int p = 0; p < 2; p++) {
        accel_hit *h[2];
        accel_counters cn[2];
        const char *const *specs = pairs[p];
        for (int i = 0; i < 2; i++) {
            const accel_kind *k;
            void *a;
            accel_build_stats st;
            CHECK(accel_build_spec(specs[i], &s, 1, &k, &a, &st, &err) == 0);
            h[i] = malloc(n * sizeof *h[i]);
            memset(&cn[i], 0, sizeof cn[i]);
            accel_trace(k, a, rays, h[i], n, 1, &cn[i]);
            k->destroy(a);
        }
        CHECKF(memcmp(h[0], h[1], n * sizeof *h[0]) == 0, "%s: hits differ", specs[1]);
        CHECKF(cn[1].packet_box_tests == 0, "%s: a packet walked", specs[1]);
        CHECKF(cn[0].steps == cn[1].steps && cn[0].prim_tests == cn[1].prim_tests && cn[1].rays == n &&
                   cn[1].mailbox_skips == cn[0].mailbox_skips,
               "%s: steps %llu/%llu, tests %llu/%llu", specs[1], (unsigned long long)cn[0].steps,
               (unsigned long long)cn[1].steps, (unsigned long long)cn[0].prim_tests,
               (unsigned long long)cn[1].prim_tests);
        for (int i = 0; i < 2; i++) free(h[i]);
    }
    accel_coherence_set(order);
    free(rays);
    scene_free(&s);
}

TEST(grid_packet_spec)
{
    accel_params p;
    accel_error err = {0};
    CHECK(accel_params_parse("grid:traverse=packet", &p, &err) == 0);
    CHECK(ACCEL_SPEC(&p, grid_spec)->traverse == 1);
    CHECK(accel_params_parse("grid", &p, &err) == 0);
    CHECK(ACCEL_SPEC(&p, grid_spec)->traverse == 0);
    CHECK(accel_params_parse("grid:traverse=frustum", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "single") && strstr(err.msg, "packet"), "message: %s", err.msg);
}
