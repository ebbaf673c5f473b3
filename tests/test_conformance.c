/*
 * test_conformance.c - every registered kind, every listed variant (plus the
 * naive triangle test), on every built-in scene at small size and on the
 * shared scanned meshes, against the double-precision reference.
 *
 * Ray sets per scene: primary (the scene's camera), shadow and diffuse from
 * the reference's primary hits, rays aimed exactly at mesh vertices, rays
 * along the axes (with +0 and -0 components) starting on the bounding box
 * faces, and random rays starting inside the scene with finite t ranges.
 * Required for the watertight kernels: zero holes, zero false hits, zero
 * disagreements (FORMATS.md rule). The naive kernels' counts are printed
 * and held to a loose sanity bound: their failures are the study's subject.
 *
 * Invariants for all: occluded agrees with the reference's hit/miss (also on
 * rays shortened to stop just before their hit), counted and uncounted
 * traces give identical hits, 1 and 2 threads give identical hits.
 */
#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rays/rays.h"
#include "scene/scene.h"
#include "test.h"

#define SET_COUNT 7

typedef struct {
    const char *name;
    rays_set rays;
    accel_hit *ref;   /* reference hits */
    uint8_t *ref_occ; /* reference hit/miss for occlusion checks */
} test_set;

typedef struct {
    accel_scene scene;
    test_set sets[SET_COUNT];
    int set_count;
} test_scene;

static int make_set(test_set *t, const char *name, accel_ray *rays, size_t n)
{
    t->name = name;
    t->rays.rays = rays;
    t->rays.count = n;
    return 0;
}

static accel_ray make_ray(vec3 o, vec3 d, float t_near, float t_far)
{
    accel_ray r = {o.x, o.y, o.z, t_near, d.x, d.y, d.z, t_far};
    return r;
}

/* Rays aimed at vertices of live triangles from the camera eye. */
static accel_ray *vertex_rays(const accel_scene *s, size_t *n)
{
    size_t want = 512, k = 0;
    accel_ray *r = malloc(want * sizeof *r);
    if (!r || s->tri_count == 0) { *n = 0; return r; }
    vec3 eye = s->camera.eye;
    for (size_t i = 0; i < want; i++) {
        uint32_t prim = s->live[(size_t)(rays_rand(7, i, 0) * s->live_count)];
        if (prim >= s->tri_count) continue;
        int corner = (int)(rays_rand(7, i, 1) * 3);
        vec3 v = v3_load(s->tris + 9 * (size_t)prim + 3 * corner);
        r[k++] = make_ray(eye, v3_sub(v, eye), 0.0f, INFINITY);
    }
    *n = k;
    return r;
}

/* Axis-parallel rays starting exactly on the bounds' faces, pointing in,
 * the other two components +0 or -0. */
static accel_ray *axis_rays(const accel_scene *s, size_t *n)
{
    const int grid = 12;
    accel_ray *r = malloc((size_t)6 * grid * grid * sizeof *r);
    size_t k = 0;
    box3 b = s->bounds;
    const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    for (int axis = 0; r && axis < 3; axis++)
        for (int side = 0; side < 2; side++)
            for (int i = 0; i < grid; i++)
                for (int j = 0; j < grid; j++) {
                    float o[3], d[3];
                    int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
                    /* Include the exact box faces (i or j = 0 or grid-1). */
                    o[a1] = lo[a1] + (hi[a1] - lo[a1]) * (float)i / (float)(grid - 1);
                    o[a2] = lo[a2] + (hi[a2] - lo[a2]) * (float)j / (float)(grid - 1);
                    o[axis] = side ? hi[axis] : lo[axis];
                    d[axis] = side ? -1.0f : 1.0f;
                    d[a1] = ((i + j) & 1) ? -0.0f : 0.0f;
                    d[a2] = (i & 2) ? -0.0f : 0.0f;
                    r[k++] = make_ray(v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
                }
    *n = k;
    return r;
}

/* Random rays from inside the bounds with finite, sometimes offset, t ranges. */
static accel_ray *inside_rays(const accel_scene *s, size_t *n)
{
    size_t want = 512;
    accel_ray *r = malloc(want * sizeof *r);
    vec3 e = box3_extent(s->bounds);
    float diag = v3_len(e);
    for (size_t i = 0; r && i < want; i++) {
        vec3 o = v3_add(s->bounds.min, v3_mul(e, v3(rays_rand(9, i, 0), rays_rand(9, i, 1),
                                                    rays_rand(9, i, 2))));
        float z = 2 * rays_rand(9, i, 3) - 1, ph = 6.2831853f * rays_rand(9, i, 4);
        float rr = sqrtf(fmaxf(0, 1 - z * z));
        vec3 d = v3(rr * cosf(ph), rr * sinf(ph), z);
        float t_near = (i % 3 == 0) ? 0.05f * diag * rays_rand(9, i, 5) : 0.0f;
        float t_far = (i % 2 == 0) ? 0.5f * diag : INFINITY;
        r[i] = make_ray(o, d, t_near, t_far);
    }
    *n = r ? want : 0;
    return r;
}

/* Shadow rays: from the reference's primary hits, plus shortened copies of
 * primary rays that stop just before their hit (must not be occluded unless
 * something else lies in front, which the reference decides). */
static accel_ray *shortened_rays(const rays_set *prim, const accel_hit *ref, size_t *n)
{
    accel_ray *r = malloc((prim->count ? prim->count : 1) * sizeof *r);
    size_t k = 0;
    for (size_t i = 0; r && i < prim->count; i++) {
        if (ref[i].prim == ACCEL_MISS) continue;
        r[k] = prim->rays[i];
        r[k].t_far = ref[i].t * (1.0f - 1e-3f);
        k++;
    }
    *n = k;
    return r;
}

static void reference_of(const accel_scene *s, test_set *t)
{
    size_t n = t->rays.count;
    t->ref = malloc((n ? n : 1) * sizeof *t->ref);
    t->ref_occ = malloc(n ? n : 1);
    accel_reference_trace(s, t->rays.rays, t->ref, n, accel_cpu_count());
    for (size_t i = 0; i < n; i++) t->ref_occ[i] = t->ref[i].prim != ACCEL_MISS;
}

static int prepare_scene(test_scene *ts, const char *spec, int size)
{
    accel_error err = {0};
    memset(ts, 0, sizeof *ts);
    if (scene_create(spec, &ts->scene, &err)) {
        test_fail(__FILE__, __LINE__, "scene %s: %s", spec, err.msg);
        return 0;
    }
    accel_scene *s = &ts->scene;
    test_set *primary = &ts->sets[0];
    rays_primary(&s->camera, size, size, &primary->rays, &err);
    primary->name = "primary";
    reference_of(s, primary);
    size_t n;
    accel_ray *r;
    int k = 1;
    ts->sets[k].name = "shadow";
    rays_shadow(s, &primary->rays, primary->ref, &ts->sets[k].rays, &err);
    reference_of(s, &ts->sets[k++]);
    ts->sets[k].name = "diffuse";
    rays_diffuse(s, &primary->rays, primary->ref, 3, &ts->sets[k].rays, &err);
    reference_of(s, &ts->sets[k++]);
    r = vertex_rays(s, &n);
    make_set(&ts->sets[k], "vertex", r, n);
    reference_of(s, &ts->sets[k++]);
    r = axis_rays(s, &n);
    make_set(&ts->sets[k], "axis", r, n);
    reference_of(s, &ts->sets[k++]);
    r = inside_rays(s, &n);
    make_set(&ts->sets[k], "inside", r, n);
    reference_of(s, &ts->sets[k++]);
    r = shortened_rays(&primary->rays, primary->ref, &n);
    make_set(&ts->sets[k], "shortened", r, n);
    reference_of(s, &ts->sets[k++]);
    ts->set_count = k;
    return 1;
}

static void free_scene(test_scene *ts)
{
    for (int i = 0; i < ts->set_count; i++) {
        rays_free(&ts->sets[i].rays);
        free(ts->sets[i].ref);
        free(ts->sets[i].ref_occ);
    }
    scene_free(&ts->scene);
}

static int hits_identical(const accel_hit *a, const accel_hit *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

/* Runs one kind variant on one prepared scene; returns the number of bad rays. */
static size_t check_variant(test_scene *ts, const char *spec, int naive, int invariants)
{
    accel_error err = {0};
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    if (accel_build_spec(spec, &ts->scene, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s on %s: build failed: %s", spec, ts->scene.name, err.msg);
        return 1;
    }
    size_t bad_total = 0;
    for (int si = 0; si < ts->set_count; si++) {
        test_set *t = &ts->sets[si];
        size_t n = t->rays.count;
        accel_hit *hits = malloc((n ? n : 1) * sizeof *hits);
        uint8_t *occ = malloc(n ? n : 1);
        accel_trace(kind, accel, t->rays.rays, hits, n, 1, NULL);
        accel_trace_occluded(kind, accel, t->rays.rays, occ, n, 1, NULL);
        hits_diff d = hits_compare(t->ref, hits, n);
        size_t occ_bad = 0, first_occ = SIZE_MAX;
        for (size_t i = 0; i < n; i++)
            if (occ[i] != t->ref_occ[i]) {
                occ_bad++;
                if (first_occ == SIZE_MAX) first_occ = i;
            }
        size_t bad = d.holes + d.false_hits + d.disagreements + occ_bad;
        if (naive) {
            /* Reported, not hidden; only gross failure (>1% of ordinary
             * rays) fails: rays aimed at vertices and along axes are the
             * naive test's known weakness, counted by the stability suite. */
            int stiff = !strcmp(t->name, "vertex") || !strcmp(t->name, "axis");
            if (bad) test_note("%s on %s/%s: %zu holes, %zu false hits, %zu disagreements, %zu "
                               "occluded mismatches of %zu rays", spec, ts->scene.name, t->name,
                               d.holes, d.false_hits, d.disagreements, occ_bad, n);
            CHECKF(stiff || bad * 100 <= n + 100, "%s on %s/%s: %zu bad rays of %zu", spec, ts->scene.name,
                   t->name, bad, n);
        } else if (bad) {
            size_t i = d.first_bad != SIZE_MAX ? d.first_bad : first_occ;
            const accel_ray *r = &t->rays.rays[i];
            test_fail(__FILE__, __LINE__,
                      "%s on %s/%s: %zu holes, %zu false hits, %zu disagreements, %zu occluded "
                      "mismatches of %zu rays; first ray %zu o=(%.9g,%.9g,%.9g) d=(%.9g,%.9g,%.9g) "
                      "t=[%.9g,%.9g]: ref prim %u t %.9g, got prim %u t %.9g, occluded %d",
                      spec, ts->scene.name, t->name, d.holes, d.false_hits, d.disagreements,
                      occ_bad, n, i, r->ox, r->oy, r->oz, r->dx, r->dy, r->dz, r->t_near,
                      r->t_far, t->ref[i].prim, t->ref[i].t, hits[i].prim, hits[i].t, occ[i]);
        }
        bad_total += bad;
        if (invariants) {
            /* Counted and uncounted traces agree; 2 threads agree with 1. */
            accel_hit *h2 = malloc((n ? n : 1) * sizeof *h2);
            accel_counters c = {0};
            accel_trace(kind, accel, t->rays.rays, h2, n, 1, &c);
            CHECKF(hits_identical(hits, h2, n), "%s on %s/%s: counted trace differs", spec,
                   ts->scene.name, t->name);
            CHECKF(c.rays == n, "%s on %s/%s: counters saw %llu rays of %zu", spec,
                   ts->scene.name, t->name, (unsigned long long)c.rays, n);
            accel_error broken = {0};
            CHECKF(accel_counters_status(&c, &broken) == 0, "%s on %s/%s: %s", spec,
                   ts->scene.name, t->name, broken.msg);
            accel_trace(kind, accel, t->rays.rays, h2, n, 2, NULL);
            CHECKF(hits_identical(hits, h2, n), "%s on %s/%s: 2 threads differ from 1", spec,
                   ts->scene.name, t->name);
            free(h2);
        }
        free(hits);
        free(occ);
    }
    if (invariants) {
        /* A build with 2 threads traces identically to the 1-thread build. */
        const accel_kind *k2;
        void *a2;
        accel_build_stats st2;
        if (accel_build_spec(spec, &ts->scene, 2, &k2, &a2, &st2, &err) == 0) {
            test_set *t = &ts->sets[0];
            size_t n = t->rays.count;
            accel_hit *h1 = malloc((n ? n : 1) * sizeof *h1), *h2 = malloc((n ? n : 1) * sizeof *h2);
            accel_trace(kind, accel, t->rays.rays, h1, n, 1, NULL);
            accel_trace(k2, a2, t->rays.rays, h2, n, 1, NULL);
            CHECKF(hits_identical(h1, h2, n), "%s on %s: 2-thread build traces differently", spec,
                   ts->scene.name);
            CHECKF(st.bytes == st2.bytes && st.nodes == st2.nodes,
                   "%s on %s: 2-thread build differs (%zu vs %zu bytes)", spec, ts->scene.name,
                   st.bytes, st2.bytes);
            free(h1);
            free(h2);
            k2->destroy(a2);
        } else {
            test_fail(__FILE__, __LINE__, "%s: 2-thread build failed: %s", spec, err.msg);
        }
    }
    kind->destroy(accel);
    return bad_total;
}

/* all_variants = 0: only each kind's default (plus its naive twin), for the
 * large scanned meshes where every variant would cost minutes. */
static void run_all_kinds(test_scene *ts, int all_variants)
{
    for (size_t k = 0; k < accel_kind_count; k++) {
        const accel_kind *kind = accel_kinds[k];
        if (!test_kind_selected(kind->name)) continue;
        const char *const *vars = kind->variants;
        static const char *const none[] = {"", NULL};
        if (!vars) vars = none;
        for (int v = 0; vars[v] && (all_variants || v == 0); v++) {
            char spec[256];
            snprintf(spec, sizeof spec, "%s%s%s", kind->name, vars[v][0] ? ":" : "", vars[v]);
            check_variant(ts, spec, strstr(spec, "tri=naive") != NULL, v == 0);
            if (v == 0 && !strstr(spec, "tri=naive")) {
                snprintf(spec, sizeof spec, "%s:tri=naive", kind->name);
                check_variant(ts, spec, 1, 0);
            }
        }
    }
}

TEST(conformance_builtin_scenes)
{
    for (size_t g = 0; g < scene_generator_count; g++) {
        test_scene ts;
        const char *spec = scene_generators[g]->small_spec;
        if (!prepare_scene(&ts, spec ? spec : scene_generators[g]->name, 40)) continue;
        run_all_kinds(&ts, 1);
        free_scene(&ts);
    }
}

TEST(conformance_shared_meshes)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_note("skipped: ../shared/scenes not found");
        return;
    }
    DIR *d = opendir(dir);
    if (!d) {
        test_note("skipped: cannot list %s", dir);
        return;
    }
    struct dirent *e;
    char paths[16][512];
    int count = 0;
    while ((e = readdir(d)) && count < 16) {
        const char *dot = strrchr(e->d_name, '.');
        if (!dot || strcmp(dot, ".off")) continue;
        snprintf(paths[count++], sizeof paths[0], "%s/%s", dir, e->d_name);
    }
    closedir(d);
    for (int i = 0; i < count; i++) {
        test_scene ts;
        if (!prepare_scene(&ts, paths[i], 24)) continue;
        run_all_kinds(&ts, 0);
        free_scene(&ts);
    }
}
