/*
 * test_bvh_wide_stream.c - the wide BVHs' ray streams (traverse=stream,
 * bvh/wide/stream.h): every ray answers what the single-ray kernel of the
 * same tree answers with order=branchy (the octant order for any number
 * of hit children; width 4's order=octant is that order too), bit for bit,
 * with the same per-ray steps and primitive tests, whatever the stream
 * size, hybrid=, the batch size and the thread count; and agrees with the
 * double-precision reference by FORMATS.md's rule. On primary, shadow and
 * diffuse rays (the incoherent sets the mode is for), random rays with +0
 * and -0 direction components, rays from inside the scene with t_near > 0,
 * axis-parallel rays, rays behind their origin (t_near < 0) and rays
 * that cannot hit (NaN or infinite components, an empty range), in
 * batches that are not multiples of the stream size.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

/* Each stream spec and the single-ray spec it must equal bit for bit. */
static const char *const stream_pairs[][2] = {
    {"bvh:width=8,traverse=stream", "bvh:width=8,order=branchy"},
    {"bvh:width=8,traverse=stream,stream=8,hybrid=0", "bvh:width=8,order=branchy"},
    {"bvh:width=8,traverse=stream,stream=100,hybrid=64", "bvh:width=8,order=branchy"},
    {"bvh:width=8,block=4,traverse=stream,stream=37,hybrid=3", "bvh:width=8,block=4,order=branchy"},
    {"bvh:width=4,traverse=stream,stream=333", "bvh:width=4"},
    {"bvh:width=4,block=4,traverse=stream,stream=8192,hybrid=0", "bvh:width=4,block=4"},
};
#define PAIR_COUNT (sizeof stream_pairs / sizeof *stream_pairs)

typedef struct {
    accel_hit *hits;
    uint8_t *occ;
    uint32_t *steps, *prims;
    accel_counters c;
} run_out;

static int run_alloc(run_out *o, size_t n)
{
    memset(o, 0, sizeof *o);
    size_t m = n ? n : 1;
    o->hits = malloc(m * sizeof *o->hits), o->occ = malloc(m);
    o->steps = malloc(m * sizeof *o->steps), o->prims = malloc(m * sizeof *o->prims);
    return o->hits && o->occ && o->steps && o->prims;
}

static void run_free(run_out *o)
{
    free(o->hits), free(o->occ), free(o->steps), free(o->prims);
}

/* Closest hits counted (per-ray steps and primitive tests) on `threads`
 * threads, and the any-hit answers uncounted. */
static void run_spec(const accel_kind *k, const void *a, const accel_ray *rays, size_t n, int threads,
                     run_out *o)
{
    memset(&o->c, 0, sizeof o->c);
    o->c.ray_steps = o->steps, o->c.ray_prims = o->prims;
    accel_trace(k, a, rays, o->hits, n, threads, &o->c);
    accel_trace_occluded(k, a, rays, o->occ, n, threads, NULL);
}

/* The stream spec against its single-ray twin and the reference on one
 * ray set: returns the rays that differ in any way. */
static size_t check_pair(const accel_scene *s, const char *set, const accel_ray *rays, size_t n,
                         const accel_hit *ref, const char *stream_spec, const char *single_spec)
{
    const accel_kind *ks, *k1;
    void *as = test_build_kind(stream_spec, s, 1, &ks, NULL);
    void *a1 = test_build_kind(single_spec, s, 1, &k1, NULL);
    size_t bad = 0;
    run_out o1, os, o2;
    if (as && a1 && run_alloc(&o1, n) && run_alloc(&os, n) && run_alloc(&o2, n)) {
        run_spec(k1, a1, rays, n, 1, &o1);
        run_spec(ks, as, rays, n, 1, &os);
        size_t diff_hit = 0, diff_occ = 0, diff_count = 0, first = SIZE_MAX;
        for (size_t i = 0; i < n; i++) {
            int h = memcmp(&o1.hits[i], &os.hits[i], sizeof o1.hits[i]) != 0;
            int q = o1.occ[i] != os.occ[i];
            int cn = o1.steps[i] != os.steps[i] || o1.prims[i] != os.prims[i];
            diff_hit += h, diff_occ += q, diff_count += cn;
            if ((h || q || cn) && first == SIZE_MAX) first = i;
        }
        CHECKF(diff_hit + diff_occ + diff_count == 0,
               "%s vs %s on %s/%s: %zu hits, %zu any-hit answers, %zu per-ray counts differ of %zu "
               "(first %zu: prim %u t %.9g, stream prim %u t %.9g; steps %u vs %u)",
               stream_spec, single_spec, s->name, set, diff_hit, diff_occ, diff_count, n,
               first == SIZE_MAX ? 0 : first, first == SIZE_MAX ? 0 : o1.hits[first].prim,
               first == SIZE_MAX ? 0.0 : o1.hits[first].t, first == SIZE_MAX ? 0 : os.hits[first].prim,
               first == SIZE_MAX ? 0.0 : os.hits[first].t, first == SIZE_MAX ? 0 : o1.steps[first],
               first == SIZE_MAX ? 0 : os.steps[first]);
        CHECKF(o1.c.steps == os.c.steps && o1.c.box_tests == os.c.box_tests &&
                   o1.c.prim_tests == os.c.prim_tests && os.c.rays == n && !os.c.broken,
               "%s on %s/%s: counters %llu/%llu/%llu steps/boxes/prims, single %llu/%llu/%llu", stream_spec,
               s->name, set, (unsigned long long)os.c.steps, (unsigned long long)os.c.box_tests,
               (unsigned long long)os.c.prim_tests, (unsigned long long)o1.c.steps,
               (unsigned long long)o1.c.box_tests, (unsigned long long)o1.c.prim_tests);
        bad += diff_hit + diff_occ + diff_count;
        /* 3 threads cut the batch into other streams: the same answers. */
        run_spec(ks, as, rays, n, 3, &o2);
        CHECKF(!memcmp(os.hits, o2.hits, n * sizeof *os.hits) && !memcmp(os.occ, o2.occ, n),
               "%s on %s/%s: 3 threads differ from 1", stream_spec, s->name, set);
        /* The reference, by FORMATS.md's rule. */
        test_diff d = test_trace_diff(s, ks, as, rays, n, ref, 1, o2.hits, o2.occ);
        if (test_diff_bad(&d)) {
            char label[512];
            snprintf(label, sizeof label, "%s on %s/%s", stream_spec, s->name, set);
            test_fail_diff(__FILE__, __LINE__, label, &d, rays, ref, o2.hits, o2.occ);
        }
        bad += test_diff_bad(&d);
        run_free(&o2);
    } else if (as && a1) {
        test_fail(__FILE__, __LINE__, "out of memory");
    }
    run_free(&o1);
    run_free(&os);
    if (as) ks->destroy(as);
    if (a1) k1->destroy(a1);
    return bad;
}

static void check_set(const accel_scene *s, const char *set, const accel_ray *rays, size_t n)
{
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref);
    if (!ref) return;
    accel_reference_trace(s, rays, ref, n, accel_cpu_count());
    for (size_t p = 0; p < PAIR_COUNT; p++) check_pair(s, set, rays, n, ref, stream_pairs[p][0], stream_pairs[p][1]);
    free(ref);
}

/* Primary, shadow and diffuse rays (the latter two in pixel order, as
 * they come), then random and inside rays, axis-parallel rays and rays
 * behind their origin. */
static void check_scene(const accel_scene *s, int size)
{
    accel_error err = {0};
    rays_set prim = {0}, shadow = {0}, diffuse = {0};
    if (rays_primary(&s->camera, size, size - 3, &prim, &err)) {
        test_fail(__FILE__, __LINE__, "%s: rays: %s", s->name, err.msg);
        return;
    }
    accel_hit *ph = malloc(prim.count * sizeof *ph);
    if (!ph) return;
    accel_reference_trace(s, prim.rays, ph, prim.count, accel_cpu_count());
    if (rays_shadow(s, &prim, ph, &shadow, &err) || rays_diffuse(s, &prim, ph, 7, &diffuse, &err)) {
        test_fail(__FILE__, __LINE__, "%s: rays: %s", s->name, err.msg);
    } else {
        CHECKF(diffuse.count > 100 && shadow.count > 100, "%s: %zu diffuse, %zu shadow rays", s->name,
               diffuse.count, shadow.count);
        check_set(s, "primary", prim.rays, prim.count);
        check_set(s, "shadow", shadow.rays, shadow.count);
        check_set(s, "diffuse", diffuse.rays, diffuse.count);
    }
    test_rays more = {0};
    test_rays_random(&more, s->bounds, 1001);
    test_rays_inside(&more, s->bounds, 777, 5);
    check_set(s, "random and inside", more.rays, more.count);
    test_rays_free(&more);
    test_rays axis = {0};
    test_rays_axis_from_faces(&axis, s->bounds, 9);
    check_set(s, "axis-parallel", axis.rays, axis.count);
    test_rays_free(&axis);
    test_rays behind = {0};
    test_rays_behind(&behind, prim.rays, ph, prim.count);
    check_set(s, "behind the origin", behind.rays, behind.count);
    test_rays_free(&behind);
    free(ph);
    rays_free(&prim);
    rays_free(&shadow);
    rays_free(&diffuse);
}

TEST(bvh_wide_stream_single_answers_built_in_scenes)
{
    static const char *const scenes[] = {"teapot_stadium:n=4,stadium=16,tiers=3", "sphereflake:level=2",
                                         "slivers:tris=3000,slivers=100"};
    for (size_t si = 0; si < sizeof scenes / sizeof *scenes; si++) {
        accel_scene s;
        if (!test_make_scene(scenes[si], &s)) continue;
        check_scene(&s, 41);
        scene_free(&s);
    }
}

TEST(bvh_wide_stream_single_answers_bunny)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_skip("../shared/scenes not found");
        return;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/bunny.off", dir);
    accel_scene s;
    accel_error err = {0};
    if (scene_create(path, &s, &err)) {
        test_skip("%s: %s", path, err.msg);
        return;
    }
    check_scene(&s, 64);
    scene_free(&s);
}

/* Rays that cannot hit or barely can, mixed with ordinary ones in one
 * batch, traced through the kind's entry in batches of every size from 1
 * to 70 (a stream of 8 rays then holds several octants' remainders). */
TEST(bvh_wide_stream_degenerate_rays_in_odd_batches)
{
    accel_scene s;
    if (!test_make_scene("teapot_stadium:n=2,stadium=8,tiers=2", &s)) return;
    test_rays r = {0};
    test_rays_random(&r, s.bounds, 60);
    const float nan = NAN, inf = INFINITY;
    vec3 c = box3_center(s.bounds);
    accel_ray odd[] = {
        {c.x, c.y, c.z, nan, 0.3f, 0.2f, 0, inf},   {c.x, c.y, c.z, 0.1f, nan, nan, 0, inf},
        {nan, c.y, c.z, 0.1f, 0.2f, 0.3f, 0, inf},  {c.x, c.y, c.z, 0, 0, 0, 0, inf},
        {inf, c.y, c.z, -1, 0, 0, 0, inf},          {c.x, c.y, c.z, 0.1f, 0.2f, 0.3f, 2, 1},
        {c.x, c.y, c.z, 0.1f, 0.2f, 0.3f, nan, inf}, {c.x, c.y, c.z, 0.1f, 0.2f, 0.3f, 0, nan},
        {c.x, c.y, c.z, -0.0f, -0.0f, 1, 0, inf},   {c.x, c.y, c.z, 0.0f, -1, -0.0f, 0, inf},
        {c.x, c.y, c.z, 0.3f, -0.2f, 0.1f, -5, inf}, {c.x, c.y, c.z, inf, 0, 0, 0, inf},
    };
    for (size_t i = 0; i < sizeof odd / sizeof *odd; i++) test_rays_push(&r, odd[i]);
    size_t n = r.count;
    accel_hit *ref = malloc(n * sizeof *ref), *h1 = malloc(n * sizeof *h1), *hs = malloc(n * sizeof *hs);
    uint8_t *o1 = malloc(n), *os = malloc(n);
    const accel_kind *ks, *k1;
    void *as = test_build_kind("bvh:width=8,traverse=stream,stream=8,hybrid=0", &s, 1, &ks, NULL);
    void *a1 = test_build_kind("bvh:width=8,order=branchy", &s, 1, &k1, NULL);
    if (ref && h1 && hs && o1 && os && as && a1) {
        accel_reference_trace(&s, r.rays, ref, n, 1);
        k1->intersect(a1, r.rays, h1, n, NULL);
        k1->occluded(a1, r.rays, o1, n, NULL);
        size_t batches = 0, differ = 0;
        for (size_t b = 1; b <= 70; b++) {
            for (size_t at = 0; at < n; at += b) {
                size_t m = n - at < b ? n - at : b;
                ks->intersect(as, r.rays + at, hs + at, m, NULL);
                ks->occluded(as, r.rays + at, os + at, m, NULL);
            }
            batches++;
            differ += memcmp(h1, hs, n * sizeof *h1) != 0 || memcmp(o1, os, n) != 0;
        }
        CHECKF(differ == 0, "stream: %zu of %zu batch sizes answer differently from single rays", differ, batches);
        for (size_t i = 0; i < sizeof odd / sizeof *odd; i++) {
            size_t k = n - sizeof odd / sizeof *odd + i;
            if (i < 8 || i == 11)
                CHECKF(hs[k].prim == ACCEL_MISS && hs[k].t == INFINITY && !os[k],
                       "degenerate ray %zu: prim %u t %g occluded %d", i, hs[k].prim, hs[k].t, os[k]);
        }
        test_diff d = test_trace_diff(&s, ks, as, r.rays, n, ref, 1, NULL, NULL);
        if (test_diff_bad(&d)) test_fail_diff(__FILE__, __LINE__, "stream, odd rays", &d, r.rays, ref, hs, os);
    }
    if (as) ks->destroy(as);
    if (a1) k1->destroy(a1);
    free(ref), free(h1), free(hs), free(o1), free(os);
    test_rays_free(&r);
    scene_free(&s);
}

/* The stream shares its fetches: on diffuse rays of one batch, far fewer
 * node and leaf fetches (packet_steps) than ray visits (steps), and a
 * stream of 8 rays shares less than one of 1024. */
TEST(bvh_wide_stream_shares_fetches)
{
    accel_scene s;
    if (!test_make_scene("teapot_stadium:n=4,stadium=16,tiers=3", &s)) return;
    accel_error err = {0};
    rays_set prim = {0}, diffuse = {0};
    accel_hit *ph = NULL;
    if (rays_primary(&s.camera, 64, 64, &prim, &err) || !(ph = malloc(prim.count * sizeof *ph))) {
        test_fail(__FILE__, __LINE__, "rays: %s", err.msg);
    } else {
        accel_reference_trace(&s, prim.rays, ph, prim.count, 1);
        if (rays_diffuse(&s, &prim, ph, 3, &diffuse, &err)) test_fail(__FILE__, __LINE__, "rays: %s", err.msg);
    }
    double share[2] = {0, 0};
    static const char *const specs[2] = {"bvh:width=8,traverse=stream,stream=1024,hybrid=0",
                                         "bvh:width=8,traverse=stream,stream=8,hybrid=0"};
    accel_hit *h = malloc((diffuse.count ? diffuse.count : 1) * sizeof *h);
    for (int k = 0; k < 2 && h && diffuse.count; k++) {
        const accel_kind *kind;
        void *a = test_build_kind(specs[k], &s, 1, &kind, NULL);
        if (!a) continue;
        accel_counters c = {0};
        accel_trace(kind, a, diffuse.rays, h, diffuse.count, 1, &c);
        CHECKF(c.packet_steps > 0 && c.packet_steps <= c.steps, "%s: %llu fetches, %llu steps", specs[k],
               (unsigned long long)c.packet_steps, (unsigned long long)c.steps);
        share[k] = c.packet_steps ? (double)c.steps / (double)c.packet_steps : 0;
        kind->destroy(a);
    }
    test_note("diffuse rays (%zu): %.2f ray visits per fetch with streams of 1024, %.2f of 8", diffuse.count,
              share[0], share[1]);
    CHECKF(share[0] > 4.0 && share[0] > 2.0 * share[1], "rays per fetch %.2f (1024) and %.2f (8)", share[0],
           share[1]);
    free(h);
    free(ph);
    rays_free(&prim);
    rays_free(&diffuse);
    scene_free(&s);
}

TEST(bvh_wide_stream_spec_errors)
{
    accel_scene s;
    if (!test_make_scene("teapot_stadium:n=2,stadium=8,tiers=2", &s)) return;
    static const char *const bad[] = {"bvh:traverse=stream", "bvh:width=8,stream=64",
                                      "bvh:width=8,traverse=stream,order=dist",
                                      "bvh:width=8,traverse=stream,order=branchy",
                                      "bvh:width=8,traverse=stream,quant=1", "bvh:width=8,traverse=stream,stream=4",
                                      "bvh:width=8,traverse=stream,stream=8193", "bvh:width=8,hybrid=4"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        accel_error err = {0};
        CHECKF(test_build_rc(bad[i], &s, &err) == ACCEL_ERR_SPEC, "%s: accepted (%s)", bad[i], err.msg);
    }
    static const char *const good[] = {"bvh:width=8,traverse=stream,order=octant",
                                       "bvh:width=4,traverse=stream,stream=8,hybrid=64"};
    for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
        accel_error err = {0};
        CHECKF(test_build_rc(good[i], &s, &err) == 0, "%s: %s", good[i], err.msg);
    }
    scene_free(&s);
}
