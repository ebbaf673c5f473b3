/*
 * test_instanced.c - the two-level kind against the oracle on the flattened
 * scene, on stiff scenes of many instances: instances sharing edges
 * exactly (a sheet of unit squares placed by integer translations, and the
 * same sheet turned and moved to 1e5), mirrored and scaled instances of a
 * closed sphere (rays from inside must not leak), instances far from the
 * origin (1e5, where the flattened triangles are visibly quantized: the
 * float spacing there is 2^-7), and overlapping and coincident instances.
 * Rays: aimed exactly at world vertices and edge midpoints from several
 * eyes, from inside closed instances, camera rays, shadow rays. Every
 * combination of top and bottom level must give zero holes, zero false
 * hits, zero disagreements and matching occlusion; the pad=0 control must
 * not (it shows what the pads are for).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rays/rays.h"
#include "scene/scene.h"
#include "test.h"
#include "test_instanced.h"

/* "quad": the unit square as two triangles; anything else is a built-in spec. */
int inst_stiff_mesh(void *ctx, const char *source, const char *dir, accel_scene *mesh,
                      accel_error *err)
{
    (void)ctx;
    (void)dir;
    if (strcmp(source, "quad")) return scene_create(source, mesh, err);
    scene_builder b = {0};
    int rc = scene_builder_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0), err);
    if (rc == 0) rc = scene_builder_add_tri(&b, v3(0, 0, 0), v3(1, 1, 0), v3(0, 1, 0), err);
    if (rc == 0) rc = scene_finish(&b, "quad", mesh, err);
    scene_builder_free(&b);
    return rc;
}

static void push(ray_list *l, vec3 o, vec3 d, float t_near, float t_far)
{
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 1024;
        l->r = realloc(l->r, l->cap * sizeof *l->r);
        if (!l->r) abort();
    }
    accel_ray ray = {o.x, o.y, o.z, t_near, d.x, d.y, d.z, t_far};
    l->r[l->n++] = ray;
}

/* Rays at world vertices and edge midpoints of random live triangles from
 * four eyes around the scene, rays from the centres of instances (inside
 * closed meshes), camera rays and shadow rays from the oracle's hits. */
void inst_make_rays(const accel_scene *s, ray_list *l)
{
    vec3 c = box3_center(s->bounds), e = box3_extent(s->bounds);
    float r = v3_len(e) + 1.0f;
    for (int k = 0; k < 4; k++) {
        vec3 eye = v3_add(c, v3(r * (k & 1 ? 1.1f : -0.9f), r * (k & 2 ? 0.8f : -1.2f), r * 0.7f));
        for (uint64_t i = 0; i < 600 && s->live_count; i++) {
            uint32_t prim = s->live[(size_t)(rays_rand(31 + k, i, 0) * s->live_count)];
            const float *t = s->tris + 9 * (size_t)prim;
            int a = (int)(rays_rand(31 + k, i, 1) * 3);
            vec3 p = v3_load(t + 3 * a), q = v3_load(t + 3 * ((a + 1) % 3));
            vec3 target = (i & 1) ? v3_scale(v3_add(p, q), 0.5f) : p;
            push(l, eye, v3_sub(target, eye), 0.0f, INFINITY);
        }
    }
    for (uint32_t k = 0; s->instances && k < s->instances->instance_count; k++) {
        vec3 o = box3_center(s->instances->instances[k].bounds);
        for (uint64_t i = 0; i < 40; i++) {
            float z = 2 * rays_rand(77, k * 64 + i, 0) - 1, ph = 6.2831853f * rays_rand(77, k * 64 + i, 1);
            float rr = sqrtf(fmaxf(0, 1 - z * z));
            push(l, o, v3(rr * cosf(ph), rr * sinf(ph), z), 0.0f, INFINITY);
        }
    }
    rays_set prim = {0}, shadow = {0};
    accel_error err;
    if (rays_primary(&s->camera, 48, 48, &prim, &err) == 0) {
        accel_hit *h = malloc(prim.count * sizeof *h);
        accel_reference_trace(s, prim.rays, h, prim.count, 2);
        for (size_t i = 0; i < prim.count; i++) {
            const accel_ray *p = &prim.rays[i];
            push(l, v3(p->ox, p->oy, p->oz), v3(p->dx, p->dy, p->dz), p->t_near, p->t_far);
        }
        if (rays_shadow(s, &prim, h, &shadow, &err) == 0)
            for (size_t i = 0; i < shadow.count; i++) {
                const accel_ray *p = &shadow.rays[i];
                push(l, v3(p->ox, p->oy, p->oz), v3(p->dx, p->dy, p->dz), p->t_near, p->t_far);
            }
        free(h);
    }
    rays_free(&prim);
    rays_free(&shadow);
}

/* Bad rays (holes + false hits + disagreements + occlusion mismatches) of
 * one spec on one scene, against the oracle. */
size_t inst_bad_rays(const accel_scene *s, const ray_list *l, const accel_hit *ref,
                     const char *spec, size_t *holes)
{
    accel_error err = {0};
    const accel_kind *kind;
    void *a;
    accel_build_stats st;
    if (accel_build_spec(spec, s, 1, &kind, &a, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s: %s", spec, err.msg);
        return 1;
    }
    size_t bad = inst_count_bad(kind, a, s, l, ref, spec, holes);
    kind->destroy(a);
    return bad;
}

/* Bad rays of a built structure; a note names the first one (not for the
 * pad=0 control, which is expected to have many). */
size_t inst_count_bad(const accel_kind *kind, const void *a, const accel_scene *s,
                      const ray_list *l, const accel_hit *ref, const char *spec, size_t *holes)
{
    accel_hit *h = malloc(l->n * sizeof *h);
    uint8_t *occ = malloc(l->n);
    accel_trace(kind, a, l->r, h, l->n, 1, NULL);
    accel_trace_occluded(kind, a, l->r, occ, l->n, 1, NULL);
    hits_diff d = hits_compare(s, l->r, ref, h, l->n);
    size_t occ_bad = 0;
    for (size_t i = 0; i < l->n; i++) occ_bad += occ[i] != (ref[i].prim != ACCEL_MISS);
    if (holes) *holes = d.holes;
    size_t bad = d.holes + d.false_hits + d.disagreements + occ_bad;
    if (bad && strstr(spec, "pad=0") == NULL && d.first_bad != SIZE_MAX) {
        const accel_ray *r = &l->r[d.first_bad];
        test_note("%s on %s: first bad ray o=(%.9g,%.9g,%.9g) d=(%.9g,%.9g,%.9g): ref %u t %.9g, "
                  "got %u t %.9g", spec, s->name, r->ox, r->oy, r->oz, r->dx, r->dy, r->dz,
                  ref[d.first_bad].prim, ref[d.first_bad].t, h[d.first_bad].prim, h[d.first_bad].t);
    }
    free(h);
    free(occ);
    return bad;
}

static const char *const combos[] = {
    "instanced", "instanced:top=grid", "instanced:bottom=grid", "instanced:top=grid,bottom=grid",
    "instanced:world=compute,leaf=1", "instanced:width=2", "bvh", "grid",
};

/* Every combination agrees with the oracle; returns the pad=0 control's bad rays. */
static size_t check_scene(const char *name, const char *text)
{
    accel_scene s;
    accel_error err = {0};
    scene_file_options o = {0, inst_stiff_mesh, NULL};
    if (scene_parse_scene(name, "", text, strlen(text), &o, &s, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        return 0;
    }
    ray_list l = {0};
    inst_make_rays(&s, &l);
    accel_hit *ref = malloc(l.n * sizeof *ref);
    accel_reference_trace(&s, l.r, ref, l.n, 2);
    size_t hits = 0;
    for (size_t i = 0; i < l.n; i++) hits += ref[i].prim != ACCEL_MISS;
    CHECKF(hits > l.n / 4, "%s: only %zu of %zu rays hit", name, hits, l.n);
    for (size_t c = 0; c < sizeof combos / sizeof combos[0]; c++) {
        size_t bad = inst_bad_rays(&s, &l, ref, combos[c], NULL);
        CHECKF(bad == 0, "%s on %s: %zu bad rays of %zu", combos[c], name, bad, l.n);
    }
    size_t control = inst_bad_rays(&s, &l, ref, "instanced:pad=0", NULL) +
                     inst_bad_rays(&s, &l, ref, "instanced:pad=0,bottom=grid", NULL);
    test_note("%s: %zu rays, %zu hit; pad=0 control: %zu bad", name, l.n, hits, control);
    free(ref);
    free(l.r);
    scene_free(&s);
    return control;
}

/* The stiff scenes (also traced by test_anybottom.c). */
const char *const inst_scene_mirrored_scaled =
    "mesh s sphere:segments=6\nmesh c cube:n=3\n"
    "instance s scale -1 1 1\n"
    "instance s scale 2 -3 0.5 rotate 0 1 0 30 translate 5 0 0\n"
    "instance c scale 1e-3 translate -3 0 0\n"
    "instance c scale 1e3 -1e3 1e3 translate 0 0 -3000\n"
    "instance s matrix -1 0 0 0  0 0 1 2  0 1 0 -2\n"
    "camera eye 2 -12 4 look 1 0 0\n";
const char *const inst_scene_far =
    "mesh s sphere:segments=6\nmesh t teapot_stadium:n=2,stadium=3,tiers=0\n"
    "instance s translate 1e5 1e5 1e5\n"
    "instance s rotate 1 1 0 33 scale -1 1 1 translate 100002.5 1e5 1e5\n"
    "instance s scale 0.01 translate 1e5 100001.3 1e5\n"
    "instance s rotate 0 0 1 10 translate -1e5 0 0\n"
    "camera eye 100000 99990 100003 look 100001 100000 100000\n";
const char *const inst_scene_overlap =
    "mesh s sphere:segments=5\nmesh q quad\n"
    "instance s\ninstance s\ninstance s rotate 0 0 1 45\n"
    "instance s scale 1.0000001 rotate 1 0 0 90 translate 0.5 0 0\n"
    "instance q scale 4 translate -2 -2 0\ninstance q scale 4 translate -2 -2 0\n"
    "instance q scale 4 rotate 1 0 0 90 translate -2 0 -2\n";

/* A sheet of n x n unit squares, each its own instance, placed by `place`
 * (a transform applied after the integer translation). */
char *inst_sheet(int n, const char *place)
{
    size_t cap = 64 + (size_t)n * n * (64 + strlen(place));
    char *t = malloc(cap);
    size_t k = (size_t)snprintf(t, cap, "mesh q quad\n");
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            k += (size_t)snprintf(t + k, cap - k, "instance q translate %d %d 0 %s\n", i - n / 2,
                                  j - n / 2, place);
    return t;
}

TEST(instanced_shared_edges)
{
    char *t = inst_sheet(8, "");
    check_scene("sheet", t);
    free(t);
    /* Turned and moved far: shared vertices are no longer bit-identical in
     * the flattened scene (each instance rounds its own), and the oracle's
     * own holes are what the two-level kind must reproduce. */
    t = inst_sheet(8, "rotate 1 2 3 37 translate 100000 100000 0");
    size_t control = check_scene("sheet_far_turned", t);
    CHECKF(control > 0, "the pad=0 control agrees everywhere: the far sheet tests nothing");
    free(t);
}

TEST(instanced_mirrored_scaled_far)
{
    check_scene("mirrored_scaled",
                inst_scene_mirrored_scaled);
    size_t control = check_scene("far",
                                 inst_scene_far);
    CHECKF(control > 0, "the pad=0 control agrees everywhere: the far case tests nothing");
}

TEST(instanced_overlapping)
{
    check_scene("overlap",
                inst_scene_overlap);
}

TEST(instanced_builtin_multi_meshes)
{
    /* The field and animated scenes at test size: every combination against
     * the oracle on camera, vertex and inside rays (the conformance suite
     * runs the defaults too; this adds the grids at both levels). */
    static const char *const specs[] = {"field:instances=30,detail=2",
                                        "animated:frame=77,instances=6,detail=2"};
    for (size_t i = 0; i < 2; i++) {
        accel_scene s;
        accel_error err = {0};
        if (scene_create(specs[i], &s, &err)) {
            test_fail(__FILE__, __LINE__, "%s", err.msg);
            continue;
        }
        ray_list l = {0};
        inst_make_rays(&s, &l);
        accel_hit *ref = malloc(l.n * sizeof *ref);
        accel_reference_trace(&s, l.r, ref, l.n, 2);
        for (size_t c = 0; c < 6; c++) {
            size_t bad = inst_bad_rays(&s, &l, ref, combos[c], NULL);
            CHECKF(bad == 0, "%s on %s: %zu bad rays of %zu", combos[c], specs[i], bad, l.n);
        }
        free(ref);
        free(l.r);
        scene_free(&s);
    }
}

/* Frame to frame: refit or rebuild of the deforming blob, top level
 * rebuilt, exact against the oracle on every frame's flattened scene. The
 * instances move from frame to frame, so world blocks (world=blocks)
 * left stale by the update fail it. */
TEST(instanced_update_frames)
{
    static const char *const specs[] = {"instanced", "instanced:top=grid,bottom=grid",
                                        "instanced:world=compute", "instanced:traverse=packet"};
    for (size_t v = 0; v < sizeof specs / sizeof specs[0]; v++)
        for (int refit = 0; refit <= 1; refit++) {
            const int grid = strstr(specs[v], "bottom=grid") != NULL;
            /* The structure refers to its scene by address: two slots. */
            accel_scene slot[2];
            int cur = 0;
            accel_error err = {0};
            char spec[128];
            if (scene_create("animated:frame=0,instances=6,detail=2", &slot[0], &err)) {
                test_fail(__FILE__, __LINE__, "%s", err.msg);
                return;
            }
            const accel_kind *kind;
            void *a;
            accel_build_stats st;
            if (accel_build_spec(specs[v], &slot[0], 1, &kind, &a, &st, &err)) {
                test_fail(__FILE__, __LINE__, "%s", err.msg);
                scene_free(&slot[0]);
                return;
            }
            CHECK(kind->update != NULL);
            for (int frame = 20; frame <= 60 && kind->update; frame += 40) {
                accel_scene *next = &slot[1 - cur];
                snprintf(spec, sizeof spec, "animated:frame=%d,instances=6,detail=2", frame);
                if (scene_create(spec, next, &err)) break;
                accel_update_stats us;
                int rc = kind->update(a, next, refit, &us, &err);
                CHECKF(rc == 0, "%s", err.msg);
                scene_free(&slot[cur]);
                cur = 1 - cur;
                if (rc) break;
                const accel_scene *sc = &slot[cur];
                /* Only the blob changes shape: one mesh refit (bvh) or rebuilt. */
                CHECKF(grid || us.meshes_refit + us.meshes_rebuilt == 1,
                       "%s refit=%d frame %d: %u refit, %u rebuilt", specs[v], refit, frame,
                       us.meshes_refit, us.meshes_rebuilt);
                CHECK(grid || us.meshes_refit == (uint32_t)refit);
                ray_list l = {0};
                inst_make_rays(sc, &l);
                accel_hit *ref = malloc(l.n * sizeof *ref), *h = malloc(l.n * sizeof *h);
                accel_reference_trace(sc, l.r, ref, l.n, 2);
                accel_trace(kind, a, l.r, h, l.n, 1, NULL);
                hits_diff d = hits_compare(sc, l.r, ref, h, l.n);
                CHECKF(d.holes + d.false_hits + d.disagreements == 0,
                       "%s refit=%d frame %d: %zu holes %zu false %zu disagreements of %zu",
                       specs[v], refit, frame, d.holes, d.false_hits, d.disagreements, l.n);
                free(ref);
                free(h);
                free(l.r);
            }
            kind->destroy(a);
            scene_free(&slot[cur]);
        }
    /* A plain scene has nothing to update; a changed topology is refused. */
    accel_scene p, q;
    accel_error err = {0};
    const accel_kind *kind;
    void *a;
    accel_build_stats st;
    accel_update_stats us;
    if (scene_create("animated:frame=0,instances=6,detail=2", &p, &err) == 0 &&
        scene_create("animated:frame=0,instances=6,detail=3", &q, &err) == 0 &&
        accel_build_spec("instanced", &p, 1, &kind, &a, &st, &err) == 0) {
        CHECK(kind->update(a, &q, 1, &us, &err) == ACCEL_ERR_SPEC && strstr(err.msg, "topology"));
        kind->destroy(a);
    }
    scene_free(&p);
    scene_free(&q);
}

/* The same answers from every walk, and from the flattened scene's 8-wide
 * BVH, by FORMATS.md's rule (hits_compare: the same triangle, t to 1e-4,
 * or a verified tie): every walk decides a triangle on the flattened
 * scene's floats with the shared tests (the block test at 8-wide leaves,
 * the scalar test where triangles come one by one), which agree but for
 * the last bits of t, u, v near the float test's bounds (which of its float
 * or double steps decides depends on the closest hit so far, hence on the
 * order a walk meets the triangles). Shadow rays: the same answer, bit for
 * bit. */
static void same_hits_every_walk(const accel_scene *s, const char *name)
{
    static const char *const walks[] = {
        "instanced:width=2", "instanced:top=grid", "instanced:bottom=grid",
        "instanced:top=grid,bottom=grid,width=2", "instanced:bottom=nested_grid",
        "instanced:bottom=bvh:width=8", "instanced:leaf=1", "instanced:world=compute",
        "instanced:traverse=packet", "instanced:traverse=packet,world=compute,leaf=1",
        "bvh:width=8", "bvh:width=8,traverse=packet",
    };
    ray_list l = {0};
    inst_make_rays(s, &l);
    accel_hit *ref = malloc(l.n * sizeof *ref), *h = malloc(l.n * sizeof *h);
    uint8_t *occ_ref = malloc(l.n), *occ = malloc(l.n);
    accel_error err = {0};
    const accel_kind *kind;
    void *a;
    accel_build_stats st;
    size_t hits = 0;
    if (accel_build_spec("instanced", s, 1, &kind, &a, &st, &err) == 0) {
        accel_trace(kind, a, l.r, ref, l.n, 1, NULL);
        accel_trace_occluded(kind, a, l.r, occ_ref, l.n, 1, NULL);
        kind->destroy(a);
        for (size_t i = 0; i < l.n; i++) hits += ref[i].prim != ACCEL_MISS;
    }
    CHECKF(hits > l.n / 4, "%s: only %zu of %zu rays hit", name, hits, l.n);
    for (size_t w = 0; w < sizeof walks / sizeof walks[0]; w++) {
        if (accel_build_spec(walks[w], s, 1, &kind, &a, &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", walks[w], err.msg);
            continue;
        }
        accel_trace(kind, a, l.r, h, l.n, 1, NULL);
        accel_trace_occluded(kind, a, l.r, occ, l.n, 1, NULL);
        kind->destroy(a);
        hits_diff d = hits_compare(s, l.r, ref, h, l.n);
        size_t first = d.first_bad == SIZE_MAX ? 0 : d.first_bad, occ_bad = 0;
        for (size_t i = 0; i < l.n; i++) occ_bad += occ[i] != occ_ref[i];
        CHECKF(d.holes + d.false_hits + d.disagreements + d.unverified == 0,
               "%s on %s: %zu holes, %zu false hits, %zu disagreements, %zu unverified of %zu "
               "against instanced (first: ray %zu, prim %u t %.9g, got %u t %.9g)",
               walks[w], name, d.holes, d.false_hits, d.disagreements, d.unverified, l.n, first,
               ref[first].prim, ref[first].t, h[first].prim, h[first].t);
        CHECKF(occ_bad == 0, "%s on %s: %zu of %zu shadow answers differ", walks[w], name, occ_bad,
               l.n);
    }
    free(ref);
    free(h);
    free(occ_ref);
    free(occ);
    free(l.r);
}

/* world=compute and world=blocks give the same hits, bit for bit: the
 * same walk tests the same blocks (the flattener's expression computes the
 * very floats the copies hold) in the same order. Single rays and packets,
 * closest and any hit. */
static void compute_equals_blocks(const accel_scene *s, const char *name)
{
    static const char *const pairs[][2] = {
        {"instanced", "instanced:world=compute"},
        {"instanced:leaf=1", "instanced:leaf=1,world=compute"},
        {"instanced:top=grid", "instanced:top=grid,world=compute"},
        {"instanced:traverse=packet", "instanced:traverse=packet,world=compute"},
    };
    ray_list l = {0};
    inst_make_rays(s, &l);
    accel_hit *h[2] = {malloc(l.n * sizeof(accel_hit)), malloc(l.n * sizeof(accel_hit))};
    uint8_t *occ[2] = {malloc(l.n), malloc(l.n)};
    for (size_t p = 0; p < sizeof pairs / sizeof pairs[0]; p++) {
        size_t hits = 0;
        for (int k = 0; k < 2; k++) {
            accel_error err = {0};
            const accel_kind *kind;
            void *a;
            accel_build_stats st;
            memset(h[k], 0xAB, l.n * sizeof(accel_hit));
            memset(occ[k], 0xAB, l.n);
            if (accel_build_spec(pairs[p][k], s, 1, &kind, &a, &st, &err)) {
                test_fail(__FILE__, __LINE__, "%s: %s", pairs[p][k], err.msg);
                continue;
            }
            accel_trace(kind, a, l.r, h[k], l.n, 1, NULL);
            accel_trace_occluded(kind, a, l.r, occ[k], l.n, 1, NULL);
            kind->destroy(a);
        }
        size_t differ = 0, occ_differ = 0;
        for (size_t i = 0; i < l.n; i++) {
            hits += h[0][i].prim != ACCEL_MISS;
            differ += memcmp(&h[0][i], &h[1][i], sizeof(accel_hit)) != 0;
            occ_differ += occ[0][i] != occ[1][i];
        }
        CHECKF(hits > l.n / 4, "%s on %s: only %zu of %zu rays hit", pairs[p][0], name, hits, l.n);
        CHECKF(differ == 0 && occ_differ == 0, "%s against %s on %s: %zu hits, %zu shadow answers "
               "of %zu differ", pairs[p][1], pairs[p][0], name, differ, occ_differ, l.n);
    }
    free(h[0]), free(h[1]), free(occ[0]), free(occ[1]);
    free(l.r);
}

/* fn on each of the three stiff instance scenes (mirrored and scaled, far
 * from the origin, overlapping instances). */
static void on_stiff_scenes(void (*fn)(const accel_scene *, const char *))
{
    const char *const texts[] = {inst_scene_mirrored_scaled, inst_scene_far, inst_scene_overlap};
    for (size_t i = 0; i < 3; i++) {
        accel_scene s;
        accel_error err = {0};
        scene_file_options o = {0, inst_stiff_mesh, NULL};
        if (scene_parse_scene("stiff", "", texts[i], strlen(texts[i]), &o, &s, &err)) {
            test_fail(__FILE__, __LINE__, "%s", err.msg);
            continue;
        }
        fn(&s, texts[i]);
        scene_free(&s);
    }
}

TEST(instanced_world_compute_equals_blocks)
{
    on_stiff_scenes(compute_equals_blocks);
    accel_scene s;
    accel_error err = {0};
    if (scene_create("animated:frame=41,instances=6,detail=2", &s, &err) == 0) {
        compute_equals_blocks(&s, "animated");
        scene_free(&s);
    } else {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
    }
}

TEST(instanced_same_hits_every_walk)
{
    on_stiff_scenes(same_hits_every_walk);
    static const char *const specs[] = {"animated:frame=41,instances=6,detail=2", "cube:n=8",
                                        "sphereflake:level=2"};
    for (size_t i = 0; i < 3; i++) {
        accel_scene s;
        accel_error err = {0};
        if (scene_create(specs[i], &s, &err)) {
            test_fail(__FILE__, __LINE__, "%s", err.msg);
            continue;
        }
        same_hits_every_walk(&s, specs[i]);
        scene_free(&s);
    }
}

/* A camera's rays in packets: they share their origin and axes, so the
 * packets' leaves take the shared-origin path (leaf_block_rel) and their
 * leaf cull (groups of 8 rays whose shears surely miss a block skip it).
 * Exact against the oracle, closest and any hit, both world modes. */
TEST(instanced_packet_camera_rays)
{
    accel_scene s;
    accel_error err = {0};
    if (scene_create("animated:frame=33,instances=6,detail=2", &s, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        return;
    }
    rays_set prim = {0};
    if (rays_primary(&s.camera, 160, 120, &prim, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        scene_free(&s);
        return;
    }
    ray_list l = {prim.rays, prim.count, prim.count};
    accel_hit *ref = malloc(l.n * sizeof *ref);
    accel_reference_trace(&s, l.r, ref, l.n, 2);
    size_t hits = 0;
    for (size_t i = 0; i < l.n; i++) hits += ref[i].prim != ACCEL_MISS;
    CHECKF(hits > l.n / 4, "only %zu of %zu camera rays hit", hits, l.n);
    static const char *const specs[] = {"instanced:traverse=packet",
                                        "instanced:traverse=packet,world=compute"};
    for (size_t k = 0; k < 2; k++) {
        size_t bad = inst_bad_rays(&s, &l, ref, specs[k], NULL);
        CHECKF(bad == 0, "%s on camera rays: %zu bad of %zu", specs[k], bad, l.n);
    }
    free(ref);
    rays_free(&prim);
    scene_free(&s);
}
