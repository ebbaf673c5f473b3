/*
 * test_oracle.c - the culled oracle (accel_oracle_*, accel_reference_trace)
 * returns bitwise what the brute-force loop (accel_reference_trace_brute)
 * returns: t, prim, u and v, ties included, on every stiff case, every
 * built-in scene and adversarial rays (axis rays with +-0 components
 * through vertices and from box faces, origins at 1e22, rays in triangles'
 * planes, tangents to spheres from their surface, NaN and empty ranges),
 * and on odd scenes (non-finite coordinates, negative radii, duplicated and
 * shuffled live lists, no primitives, exponentially spaced primitives).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/oracle_bvh.h"
#include "rays/rays.h"
#include "rays/stiff.h"
#include "scene/scene.h"
#include "support.h"

/* ---- comparing against brute force ------------------------------------------ */

/* Traces with the culled oracle (1 and 2 threads, built once), with the
 * one-shot wrapper, and by brute force; every hit must match bitwise.
 * Returns the brute-force hits in *ref_out when not NULL (caller frees). */
static void check_same(const accel_scene *s, const accel_ray *rays, size_t n, const char *what,
                       accel_hit **ref_out)
{
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref);
    accel_hit *h1 = malloc((n ? n : 1) * sizeof *h1);
    accel_hit *h2 = malloc((n ? n : 1) * sizeof *h2);
    accel_hit *hw = malloc((n ? n : 1) * sizeof *hw);
    CHECK(ref && h1 && h2 && hw);
    accel_oracle *o = NULL;
    accel_error err = {0};
    int rc = accel_oracle_build(s, &o, &err);
    CHECKF(rc == 0, "%s: oracle build: %s", what, err.msg);
    if (ref && h1 && h2 && hw && rc == 0) {
        accel_reference_trace_brute(s, rays, ref, n, 2);
        accel_oracle_trace(o, rays, h1, n, 1, NULL);
        accel_oracle_trace(o, rays, h2, n, 2, NULL);
        accel_reference_trace(s, rays, hw, n, 2);
        size_t bad = 0, first = n;
        for (size_t i = 0; i < n; i++) {
            int same = !memcmp(&ref[i], &h1[i], sizeof ref[i]) &&
                       !memcmp(&ref[i], &h2[i], sizeof ref[i]) &&
                       !memcmp(&ref[i], &hw[i], sizeof ref[i]);
            if (!same && bad++ == 0) first = i;
        }
        if (bad) {
            const accel_ray *r = &rays[first];
            test_fail(__FILE__, __LINE__,
                      "%s: %zu of %zu rays differ from brute force; first, ray %zu "
                      "(o %a %a %a d %a %a %a t %a..%a): brute t %a prim %u u %a v %a, "
                      "culled t %a prim %u u %a v %a",
                      what, bad, n, first, r->ox, r->oy, r->oz, r->dx, r->dy, r->dz, r->t_near,
                      r->t_far, ref[first].t, ref[first].prim, ref[first].u, ref[first].v,
                      h1[first].t, h1[first].prim, h1[first].u, h1[first].v);
        }
    }
    accel_oracle_free(o);
    free(h1);
    free(h2);
    free(hw);
    if (ref_out) *ref_out = ref;
    else free(ref);
}

/* ---- ray sets ------------------------------------------------------------------ */

static void push(test_rays *l, vec3 o, vec3 d, float t_near, float t_far)
{
    test_rays_push(l, test_ray(o, d, t_near, t_far));
}

static void push_set(test_rays *l, const rays_set *set)
{
    for (size_t i = 0; i < set->count; i++) test_rays_push(l, set->rays[i]);
}

static float rnd(uint64_t seed, uint64_t i, uint32_t dim) { return rays_rand(seed, i, dim); }

/* A vertex of a deterministic random live triangle (spheres: the centre). */
static vec3 some_point(const accel_scene *s, uint64_t seed, uint64_t i)
{
    uint32_t prim = s->live[(size_t)(rnd(seed, i, 0) * s->live_count)];
    if (prim >= s->tri_count) return v3_load(s->spheres + 4 * (size_t)(prim - s->tri_count));
    return v3_load(s->tris + 9 * (size_t)prim + 3 * (size_t)(rnd(seed, i, 1) * 3));
}

static box3 live_bounds(const accel_scene *s)
{
    box3 b = box3_empty();
    for (uint32_t k = 0; k < s->live_count; k++) {
        box3 p = accel_prim_bounds(s, s->live[k]);
        if (isfinite(p.min.x + p.min.y + p.min.z + p.max.x + p.max.y + p.max.z))
            b = box3_union(b, p);
    }
    return box3_is_empty(b) ? (box3){{-1, -1, -1}, {1, 1, 1}} : b;
}

/*
 * The adversarial rays: along the axes with +-0 components through
 * vertices (from outside, and starting exactly on the bounds' faces), along
 * face diagonals, from 1e22 away, in a triangle's plane, and the invalid
 * ones (NaN, zero direction, t_near > t_far).
 */
static void add_adversarial(const accel_scene *s, test_rays *l, size_t count, uint64_t seed)
{
    box3 b = live_bounds(s);
    vec3 ext = box3_extent(b);
    for (size_t i = 0; s->live_count && i < count; i++) {
        vec3 p = some_point(s, seed, i);
        int axis = (int)i % 3, neg = (int)(i / 3) % 2;
        float zero = (i / 6) % 2 ? -0.0f : 0.0f;
        float dp[3] = {zero, zero, zero}, op[3] = {p.x, p.y, p.z};
        const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
        dp[axis] = neg ? -1.0f : 1.0f;
        /* From outside, then from exactly on the face the ray enters by. */
        op[axis] = neg ? hi[axis] + v3_get(ext, axis) : lo[axis] - v3_get(ext, axis);
        push(l, v3(op[0], op[1], op[2]), v3(dp[0], dp[1], dp[2]), 0.0f, INFINITY);
        op[axis] = neg ? hi[axis] : lo[axis];
        push(l, v3(op[0], op[1], op[2]), v3(dp[0], dp[1], dp[2]), 0.0f, INFINITY);
        /* A face diagonal through the vertex, one component +-0. */
        vec3 d = axis == 0 ? v3(zero, 1, neg ? -1 : 1) : axis == 1 ? v3(1, zero, neg ? -1 : 1)
                                                                 : v3(neg ? -1 : 1, 1, zero);
        push(l, v3_sub(p, v3_scale(d, 2 * (ext.x + ext.y + ext.z))), d, 0.0f, INFINITY);
        /* From 1e22 away, aimed at the vertex, and axis-parallel from 1e22. */
        vec3 u = v3_norm(
            v3(rnd(seed, i, 2) - 0.5f, rnd(seed, i, 3) - 0.5f, rnd(seed, i, 4) - 0.5f));
        push(l, v3_add(p, v3_scale(u, 1e22f)), v3_scale(u, -1.0f), 0.0f, INFINITY);
        op[axis] = neg ? 1e22f : -1e22f;
        push(l, v3(op[0], op[1], op[2]), v3(dp[0], dp[1], dp[2]), 0.0f, INFINITY);
        /* Inside the bounds, random direction, sometimes a t range. */
        vec3 q = v3_add(b.min, v3_mul(ext, v3(rnd(seed, i, 5), rnd(seed, i, 6), rnd(seed, i, 7))));
        float tn = (i % 4 == 0) ? 0.1f * rnd(seed, i, 8) * (ext.x + ext.y + ext.z) : 0.0f;
        push(l, q, v3_sub(p, q), tn, i % 5 == 0 ? 1.0f : INFINITY);
    }
    /* In a triangle's plane: from beyond an edge, along the opposite edge,
     * exactly and nudged by one float step (the edge-on rule's territory). */
    for (size_t i = 0; s->live_count && i < count; i++) {
        uint32_t prim = s->live[(size_t)(rnd(seed + 1, i, 0) * s->live_count)];
        if (prim >= s->tri_count) continue;
        const float *t = s->tris + 9 * (size_t)prim;
        vec3 a = v3_load(t), e1 = v3_sub(v3_load(t + 3), a), e2 = v3_sub(v3_load(t + 6), a);
        vec3 o = v3_add(a, v3_add(v3_scale(e1, 1.5f), v3_scale(e2, -0.25f)));
        vec3 d = v3_sub(e2, e1);
        if (i % 2) d.x = nextafterf(d.x, INFINITY);
        push(l, o, d, 0.0f, INFINITY);
        push(l, o, v3_scale(d, -1.0f), 0.0f, INFINITY);
        push(l, a, e1, 0.0f, INFINITY); /* along an edge from its vertex */
    }
    const float nan = NAN;
    push(l, v3(nan, 0, 0), v3(0, 0, 1), 0.0f, INFINITY);
    push(l, v3(0, 0, 0), v3(0, nan, 1), 0.0f, INFINITY);
    push(l, v3(0, 0, 0), v3(0, 0, 0), 0.0f, INFINITY);
    push(l, v3(0, 0, 0), v3(-0.0f, 0.0f, -0.0f), 0.0f, INFINITY);
    push(l, b.min, v3(1, 1, 1), 2.0f, 1.0f);
    push(l, b.min, v3(1, 1, 1), 0.0f, nan);
    push(l, v3(INFINITY, 0, 0), v3(-1, 0, 0), 0.0f, INFINITY);
    push(l, b.min, box3_extent(b), 0.5f, 0.5f);
}

/* Primary (w x h), shadow and diffuse rays from the camera, vertex rays
 * from the eye and from the centre, and the adversarial set. */
static void scene_rays(const accel_scene *s, int w, int h, size_t vertex, size_t adversarial,
                       test_rays *l)
{
    accel_error err = {0};
    rays_set prim = {0}, sh = {0}, df = {0}, vx = {0};
    CHECKF(rays_primary(&s->camera, w, h, &prim, &err) == 0, "%s: %s", s->name, err.msg);
    accel_hit *hits = malloc((prim.count ? prim.count : 1) * sizeof *hits);
    if (hits) {
        accel_reference_trace(s, prim.rays, hits, prim.count, 2);
        CHECK(rays_shadow(s, &prim, hits, &sh, &err) == 0);
        CHECK(rays_diffuse(s, &prim, hits, 11, &df, &err) == 0);
    }
    CHECK(stiff_add_vertex_rays(s, s->camera.eye, vertex, 5, &vx, &err) == 0);
    CHECK(stiff_add_vertex_rays(s, box3_center(live_bounds(s)), vertex, 6, &vx, &err) == 0);
    push_set(l, &prim);
    push_set(l, &sh);
    push_set(l, &df);
    push_set(l, &vx);
    add_adversarial(s, l, adversarial, 3);
    free(hits);
    rays_free(&prim);
    rays_free(&sh);
    rays_free(&df);
    rays_free(&vx);
}

/* ---- tests -------------------------------------------------------------------- */

TEST(oracle_stiff_cases_match_brute)
{
    for (int ci = 0; ci < stiff_case_count(); ci++) {
        stiff_case c;
        accel_error err = {0};
        if (!test_stiff_case(ci, &c)) continue;
        test_rays l = {0};
        push_set(&l, &c.rays);
        /* Secondary rays from the hits of every other ray of the case (the
         * hits come from the oracle under test, checked just below). */
        rays_set own = {malloc((c.rays.count / 2 + 1) * sizeof(accel_ray)), NULL,
                        c.rays.count / 2, 0, 0};
        rays_set sh = {0}, df = {0};
        accel_hit *hits = malloc((own.count + 1) * sizeof *hits);
        if (hits && own.rays) {
            for (size_t i = 0; i < own.count; i++) own.rays[i] = c.rays.rays[2 * i];
            accel_reference_trace(&c.scene, own.rays, hits, own.count, 2);
            CHECK(rays_shadow(&c.scene, &own, hits, &sh, &err) == 0);
            CHECK(rays_diffuse(&c.scene, &own, hits, 3, &df, &err) == 0);
            push_set(&l, &sh);
            push_set(&l, &df);
        }
        add_adversarial(&c.scene, &l, 32, (uint64_t)ci);
        check_same(&c.scene, l.rays, l.count, c.name, NULL);
        free(hits);
        free(own.rays);
        test_rays_free(&l);
        rays_free(&sh);
        rays_free(&df);
        stiff_case_free(&c);
    }
}

TEST(oracle_builtin_scenes_match_brute)
{
    for (size_t i = 0; i < scene_generator_count; i++) {
        accel_scene s;
        const char *spec = scene_generators[i]->small_spec;
        if (!test_make_scene(spec, &s)) continue;
        test_rays l = {0};
        scene_rays(&s, 16, 16, 64, 48, &l);
        check_same(&s, l.rays, l.count, spec, NULL);
        test_rays_free(&l);
        scene_free(&s);
    }
}

TEST(oracle_mesh_file_matches_brute)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_skip("../shared/scenes absent");
        return;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/bunny.off", dir);
    accel_scene s;
    accel_error err = {0};
    if (scene_load_file(path, &s, &err)) {
        test_skip("%s", err.msg);
        return;
    }
    test_rays l = {0};
    scene_rays(&s, 8, 8, 24, 8, &l);
    check_same(&s, l.rays, l.count, "bunny.off", NULL);
    test_rays_free(&l);
    scene_free(&s);
}

/* Coincident triangles tie on t: brute force keeps the last in live order.
 * Reversing the live list must change winners, identically in both. */
TEST(oracle_ties_follow_live_order)
{
    for (int ci = 0; ci < stiff_case_count(); ci++) {
        stiff_case c;
        if (!test_stiff_case(ci, &c)) continue;
        if (strcmp(c.name, "coincident") != 0) {
            stiff_case_free(&c);
            continue;
        }
        size_t n = c.rays.count;
        accel_hit *fwd = NULL, *rev = NULL;
        check_same(&c.scene, c.rays.rays, n, "coincident, live order", &fwd);
        uint32_t *live = c.scene.live;
        for (uint32_t a = 0, b = c.scene.live_count; a + 1 < b; a++, b--) {
            uint32_t t = live[a];
            live[a] = live[b - 1];
            live[b - 1] = t;
        }
        check_same(&c.scene, c.rays.rays, n, "coincident, live reversed", &rev);
        size_t changed = 0;
        for (size_t i = 0; fwd && rev && i < n; i++) changed += fwd[i].prim != rev[i].prim;
        CHECKF(changed > 0, "no tie decided by live order among %zu rays", n);
        free(fwd);
        free(rev);
        stiff_case_free(&c);
        return;
    }
    test_fail(__FILE__, __LINE__, "stiff case 'coincident' not found");
}

/* A hand-made scene: non-finite vertices (live, as scene_finish leaves
 * them), coordinates near FLT_MAX, spheres with a negative radius, tangent
 * rays from sphere surfaces, a shuffled live list with duplicates. */
/* A scene over caller-owned arrays: tri_count triangles, then
 * sphere_count spheres, live[0..live_count-1] live. */
static accel_scene raw_scene(float *tris, uint32_t tri_count, float *spheres,
                             uint32_t sphere_count, uint32_t *live, uint32_t live_count)
{
    accel_scene s = {0};
    s.tri_count = tri_count;
    s.sphere_count = sphere_count;
    s.prim_count = tri_count + sphere_count;
    s.tris = tris;
    s.spheres = spheres;
    s.live = live;
    s.live_count = live_count;
    return s;
}

TEST(oracle_odd_scenes_match_brute)
{
    enum { TRIS = 300, SPHERES = 40 };
    static float tris[9 * TRIS], spheres[4 * SPHERES];
    static uint32_t live[TRIS + SPHERES + 20];
    for (int i = 0; i < TRIS; i++) {
        vec3 a = v3(rnd(21, i, 0) * 10 - 5, rnd(21, i, 1) * 10 - 5, rnd(21, i, 2) * 10 - 5);
        for (int k = 0; k < 3; k++) {
            tris[9 * i + 3 * k + 0] = a.x + (k ? rnd(22, i, 3 * k) : 0);
            tris[9 * i + 3 * k + 1] = a.y + (k ? rnd(22, i, 3 * k + 1) : 0);
            tris[9 * i + 3 * k + 2] = a.z + (k ? rnd(22, i, 3 * k + 2) : 0);
        }
    }
    const float odd[] = {INFINITY, -INFINITY, NAN, 3e38f, -3.4e38f};
    for (int i = 0; i < 10; i++) tris[9 * (i * 29) + (i % 9)] = odd[i % 5];
    for (int i = 0; i < SPHERES; i++) {
        for (int k = 0; k < 3; k++) spheres[4 * i + k] = (float)(int)(rnd(23, i, k) * 12 - 6);
        spheres[4 * i + 3] = (i % 3 ? 1.0f : -0.5f) * (0.25f + (float)(i % 4));
    }
    spheres[4 * 7] = INFINITY;
    spheres[4 * 8 + 1] = 3e38f;
    uint32_t n = 0;
    for (uint32_t i = 0; i < TRIS + SPHERES; i++) live[n++] = (i * 7919u) % (TRIS + SPHERES);
    for (uint32_t i = 0; i < 20; i++) live[n++] = live[i * 3];
    accel_scene s = raw_scene(tris, TRIS, spheres, SPHERES, live, n);
    snprintf(s.name, sizeof s.name, "odd");
    s.camera.eye = v3(0, 0, 30);
    s.camera.up = v3(0, 1, 0);
    s.camera.fov_deg = 40;
    test_rays l = {0};
    scene_rays(&s, 16, 16, 64, 128, &l);
    /* From exact surface points of the spheres (centre + r on an axis),
     * tangent and one float step off tangent, with and without t_near. */
    for (int i = 0; i < SPHERES; i++) {
        vec3 c = v3_load(spheres + 4 * i);
        float r = fabsf(spheres[4 * i + 3]);
        vec3 p = v3_add(c, v3(r, 0, 0));
        for (int k = 0; k < 4; k++) {
            vec3 d = v3(k & 1 ? nextafterf(0.0f, (k & 2) ? -1.0f : 1.0f) : 0.0f, 1, 0.5f);
            push(&l, p, d, 0.0f, INFINITY);
            push(&l, p, d, 1e-3f, INFINITY);
            push(&l, p, v3_scale(d, -1.0f), 1e-3f, INFINITY);
        }
    }
    check_same(&s, l.rays, l.count, "odd scene", NULL);
    /* The same rays on no primitives at all, and on only non-finite ones. */
    s.live_count = 0;
    check_same(&s, l.rays, l.count, "empty live list", NULL);
    live[0] = 0;
    live[1] = 29;
    live[2] = TRIS + 7;
    s.live_count = 3;
    check_same(&s, l.rays, l.count, "only non-finite primitives", NULL);
    test_rays_free(&l);
}

/* Centroids spaced by powers of 1.3 up to 1e37: binned SAH peels a few
 * primitives per level, an unbalanced tree with boxes of every scale. */
TEST(oracle_exponential_spacing_matches_brute)
{
    enum { TRIS = 330 };
    static float tris[9 * TRIS];
    static uint32_t live[TRIS];
    float x = 1.0f;
    for (int i = 0; i < TRIS; i++, x *= 1.3f) {
        const float t[9] = {x, 0, 0, x, 1, 0, x, 0, 1};
        memcpy(tris + 9 * i, t, sizeof t);
        live[i] = (uint32_t)i;
    }
    accel_scene s = {0};
    s.tri_count = s.prim_count = s.live_count = TRIS;
    s.tris = tris;
    s.live = live;
    accel_oracle *o = NULL;
    accel_error err = {0};
    CHECK(accel_oracle_build(&s, &o, &err) == 0);
    if (o) CHECKF(o->depth > 20, "tree depth %d", o->depth);
    accel_oracle_free(o);
    test_rays l = {0};
    for (int i = 0; i < TRIS; i += 3) {
        const float *t = tris + 9 * i;
        push(&l, v3(-1, 0.25f, 0.25f), v3(1, 0, 0), 0.0f, INFINITY);
        push(&l, v3(t[0] * 2, 0.25f, 0.5f), v3(-1, -0.0f, 0), 0.0f, INFINITY);
        push(&l, v3(t[0], -1, 0.25f), v3(0, 1, 0), 0.0f, INFINITY);
        push(&l, v3(t[0] * 0.9f, 0.1f, 0.1f), v3(1, 0.001f * (float)i, 0), 0.0f, INFINITY);
    }
    check_same(&s, l.rays, l.count, "exponential spacing", NULL);
    test_rays_free(&l);
}

/* The oracle must actually cull: on a 24k-triangle sphere, primary rays
 * test a few primitives each, not all of them. */
TEST(oracle_culls)
{
    accel_scene s;
    accel_error err = {0};
    if (!test_make_scene("sphere:segments=64", &s)) return;
    rays_set prim = {0};
    CHECK(rays_primary(&s.camera, 32, 32, &prim, &err) == 0);
    accel_oracle *o = NULL;
    CHECK(accel_oracle_build(&s, &o, &err) == 0);
    if (o && prim.count) {
        accel_hit *h = malloc(prim.count * sizeof *h);
        accel_counters c;
        memset(&c, 0, sizeof c);
        accel_oracle_trace(o, prim.rays, h, prim.count, 2, &c);
        double per_ray = (double)c.prim_tests / (double)prim.count;
        CHECKF(c.rays == prim.count && c.steps > 0, "counters: %llu rays, %llu steps",
               (unsigned long long)c.rays, (unsigned long long)c.steps);
        CHECKF(per_ray < 64, "%.1f primitive tests per ray of %u primitives", per_ray,
               s.live_count);
        CHECK(accel_oracle_memory(o) > (size_t)s.live_count * sizeof(oracle_item));
        free(h);
    }
    accel_oracle_free(o);
    rays_free(&prim);
    scene_free(&s);
}

/* The k-th number of a stream (a function call, so that several draws in
 * one expression are sequenced). */
static float draw(uint64_t seed, uint64_t *k) { return rnd(seed, (*k)++, 0); }

/* Random soups at scales 1e-20..1e20 and offsets up to 1e15: shared edges,
 * coplanar neighbours, axis-aligned planes, float-step perturbations,
 * spheres of every size; rays through vertices and edges, along edges,
 * from 1e22, axis-parallel with +-0, random t ranges. */
TEST(oracle_random_scales_match_brute)
{
    enum { SCENES = 24, TRIS = 200, SPHERES = 24, RAYS = 600 };
    static float tris[9 * TRIS], spheres[4 * SPHERES];
    static uint32_t live[TRIS + SPHERES];
    test_rays l = {0};
    for (uint64_t sc = 0; sc < SCENES; sc++) {
        uint64_t k = 0;
#define DRAW() draw(100 + sc, &k)
        double scale = pow(10.0, (int)(DRAW() * 9) * 5 - 20);
        double off = DRAW() < 0.3f ? pow(10.0, (int)(DRAW() * 5) * 5 - 5) * (DRAW() - 0.5) : 0;
        double size = sc % 3 == 0 ? scale * 1e-6 : scale * DRAW();
        for (int i = 0; i < TRIS; i++) {
            float *t = tris + 9 * i;
            if (i > 0 && DRAW() < 0.25f) {
                const float *p = tris + 9 * (int)(DRAW() * i);
                memcpy(t, p, 9 * sizeof *t);
                double a = 4 * DRAW() - 2, b = 4 * DRAW() - 2; /* a coplanar neighbour */
                for (int c = 0; c < 3; c++)
                    t[6 + c] = (float)(p[c] + a * (p[3 + c] - p[c]) + b * (p[6 + c] - p[c]));
                continue;
            }
            for (int c = 0; c < 3; c++) {
                double centre = off + scale * (2 * DRAW() - 1);
                for (int v = 0; v < 3; v++)
                    t[3 * v + c] = (float)(centre + (v ? size * (2 * DRAW() - 1) : 0));
            }
            if (DRAW() < 0.15f) t[3 + (int)(DRAW() * 6)] = nextafterf(t[0], INFINITY);
            if (DRAW() < 0.15f) { /* an axis-aligned plane */
                int a = (int)(DRAW() * 3);
                t[3 + a] = t[6 + a] = t[a];
            }
        }
        for (int i = 0; i < SPHERES; i++) {
            for (int c = 0; c < 3; c++)
                spheres[4 * i + c] = (float)(off + scale * (2 * DRAW() - 1));
            spheres[4 * i + 3] = (float)(scale * pow(10.0, -(int)(DRAW() * 8))) * (i % 5 ? 1 : -1);
        }
        uint32_t n = 0;
        for (uint32_t i = 0; i < TRIS + (sc % 2 ? SPHERES : 0); i++)
            if (DRAW() < 0.9f) live[n++] = i;
        accel_scene s = raw_scene(tris, TRIS, spheres, SPHERES, live, n);
        l.count = 0;
        for (int i = 0; n && i < RAYS; i++) {
            uint32_t prim = live[(int)(DRAW() * n)];
            const float *p = prim < TRIS ? tris + 9 * prim : spheres + 4 * (prim - TRIS);
            int v = prim < TRIS ? (int)(DRAW() * 3) : 0, w = (v + 1) % 3;
            float a = i % 3 == 0 ? 0.5f : (i % 3 == 1 ? 0.0f : DRAW());
            vec3 target = prim < TRIS ? v3_add(v3_scale(v3_load(p + 3 * v), 1 - a),
                                               v3_scale(v3_load(p + 3 * w), a))
                                      : v3_add(v3_load(p), v3(fabsf(p[3]), 0, 0));
            vec3 o = v3((float)(off + 3 * scale * (2 * DRAW() - 1)),
                        (float)(off + 3 * scale * (2 * DRAW() - 1)),
                        (float)(off + 3 * scale * (2 * DRAW() - 1)));
            vec3 d = v3_sub(target, o);
            switch (i % 6) {
            case 0: o = v3_add(target, v3_scale(v3(DRAW() - 0.5f, DRAW() - 0.5f, 1), 1e22f)); break;
            case 1: /* from the target, along its edge or tangent to its sphere */
                o = target;
                d = prim < TRIS ? v3_sub(v3_load(p + 3 * w), v3_load(p + 3 * v)) : v3(0, 1, DRAW());
                d.y = nextafterf(d.y, i % 4 ? INFINITY : -INFINITY);
                break;
            case 2: { /* axis-parallel through the target */
                int axis = (int)(DRAW() * 3);
                float zero = DRAW() < 0.5f ? 0.0f : -0.0f, t3[3] = {target.x, target.y, target.z};
                float o3[3] = {t3[0], t3[1], t3[2]}, d3[3] = {zero, zero, zero};
                d3[axis] = DRAW() < 0.5f ? 1.0f : -1.0f;
                o3[axis] = t3[axis] - d3[axis] * (float)(4 * scale + fabs(off));
                o = v3(o3[0], o3[1], o3[2]);
                d = v3(d3[0], d3[1], d3[2]);
                break;
            }
            default: break;
            }
            float t_near = DRAW() < 0.2f ? (DRAW() - 0.3f) * (float)scale : 0.0f;
            push(&l, o, d, t_near, DRAW() < 0.2f ? 2 * DRAW() : INFINITY);
        }
#undef DRAW
        char what[64];
        snprintf(what, sizeof what, "random scene %d (scale %g)", (int)sc, scale);
        check_same(&s, l.rays, l.count, what, NULL);
    }
    test_rays_free(&l);
}
