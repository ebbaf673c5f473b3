/*
 * test_conformance.c - every registered kind, every listed variant (plus the
 * naive triangle test when the list lacks it), on every built-in scene at
 * small size and on the shared scanned meshes, against the double-precision
 * reference. One test per kind (conformance_grid, conformance_bvh, ...:
 * TEST_PER_KIND), so that
 * `make test T=conformance_grid` runs one kind's and a new kind gets its own.
 *
 * Ray sets per scene: primary (the scene's camera), shadow and diffuse from
 * the reference's primary hits, rays aimed exactly at mesh vertices and at
 * edge midpoints, rays along the axes (with +0 and -0 components) starting
 * on the bounding box faces, random rays starting inside the scene with
 * finite t ranges, and the primary rays that hit ending exactly at their
 * hit (t_far = its t) and moved past it with t_near < 0 (the hit behind
 * the origin).
 * Required for the watertight kernels: zero holes, zero false hits, zero
 * disagreements (FORMATS.md rule). The naive kernels' counts are printed
 * and held to a loose sanity bound: their failures are the study's subject.
 *
 * Invariants for all: occluded agrees with the reference's hit/miss (also on
 * rays shortened to stop just before their hit), counted and uncounted
 * traces give identical hits, 1 and 2 threads give identical hits.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

#define SET_COUNT 10

typedef struct {
    const char *name;
    rays_set rays;
    accel_hit *ref; /* reference hits */
} test_set;

typedef struct {
    char spec[512];
    accel_scene scene;
    test_set sets[SET_COUNT];
    int set_count;
} test_scene;

/* Moves a constructed ray list into set t and traces the reference on it. */
static void add_set(test_scene *ts, const char *name, test_rays *r)
{
    test_set *t = &ts->sets[ts->set_count++];
    t->name = name;
    t->rays.rays = r->rays;
    t->rays.count = r->count;
    t->ref = test_oracle_hits(&ts->scene, t->rays.rays, t->rays.count, TEST_ORACLE_REFERENCE);
}

/* Ray sets and their reference hits on one scene (see the top of the file). */
static int prepare_scene(test_scene *ts, const char *spec, int size)
{
    accel_error err = {0};
    memset(ts, 0, sizeof *ts);
    snprintf(ts->spec, sizeof ts->spec, "%s", spec);
    if (!test_make_scene(spec, &ts->scene)) return 0;
    accel_scene *s = &ts->scene;
    test_set *primary = &ts->sets[0];
    rays_primary(&s->camera, size, size, &primary->rays, &err);
    primary->name = "primary";
    primary->ref =
        test_oracle_hits(s, primary->rays.rays, primary->rays.count, TEST_ORACLE_REFERENCE);
    int k = 1;
    ts->sets[k].name = "shadow";
    rays_shadow(s, &primary->rays, primary->ref, &ts->sets[k].rays, &err);
    ts->sets[k].ref =
        test_oracle_hits(s, ts->sets[k].rays.rays, ts->sets[k].rays.count, TEST_ORACLE_REFERENCE);
    k++;
    ts->sets[k].name = "diffuse";
    rays_diffuse(s, &primary->rays, primary->ref, 3, &ts->sets[k].rays, &err);
    ts->sets[k].ref =
        test_oracle_hits(s, ts->sets[k].rays.rays, ts->sets[k].rays.count, TEST_ORACLE_REFERENCE);
    k++;
    ts->set_count = k;
    test_rays r = {0};
    test_rays_at_vertices(&r, s, s->camera.eye, 512, 7);
    add_set(ts, "vertex", &r);
    r = (test_rays){0};
    test_rays_at_edges(&r, s, s->camera.eye, 512, 8);
    add_set(ts, "edge", &r);
    r = (test_rays){0};
    test_rays_axis_from_faces(&r, s->bounds, 12);
    add_set(ts, "axis", &r);
    r = (test_rays){0};
    test_rays_inside(&r, s->bounds, 512, 9);
    add_set(ts, "inside", &r);
    r = (test_rays){0};
    test_rays_shortened(&r, primary->rays.rays, primary->ref, primary->rays.count);
    add_set(ts, "shortened", &r);
    r = (test_rays){0};
    test_rays_ending_at_hit(&r, primary->rays.rays, primary->ref, primary->rays.count);
    add_set(ts, "ending at the hit", &r);
    r = (test_rays){0};
    test_rays_behind(&r, primary->rays.rays, primary->ref, primary->rays.count);
    add_set(ts, "behind the origin", &r);
    return 1;
}

static void free_scene(test_scene *ts)
{
    for (int i = 0; i < ts->set_count; i++) {
        rays_free(&ts->sets[i].rays);
        free(ts->sets[i].ref);
    }
    scene_free(&ts->scene);
}

static int hits_identical(const accel_hit *a, const accel_hit *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

/* Counted and uncounted traces agree, and 2 threads agree with 1. */
static void check_trace_invariants(const accel_kind *kind, const void *accel, const char *label,
                                   const test_set *t, const accel_hit *hits)
{
    size_t n = t->rays.count;
    accel_hit *h2 = malloc((n ? n : 1) * sizeof *h2);
    if (!h2) return;
    accel_counters c = {0};
    accel_trace(kind, accel, t->rays.rays, h2, n, 1, &c);
    CHECKF(hits_identical(hits, h2, n), "%s: counted trace differs", label);
    CHECKF(c.rays == n, "%s: counters saw %llu rays of %zu", label, (unsigned long long)c.rays, n);
    accel_trace(kind, accel, t->rays.rays, h2, n, 2, NULL);
    CHECKF(hits_identical(hits, h2, n), "%s: 2 threads differ from 1", label);
    free(h2);
}

/* A build with 2 threads traces identically to the 1-thread build. */
static void check_build_invariants(test_scene *ts, const char *spec, const accel_kind *kind,
                                   const void *accel, const accel_build_stats *st)
{
    accel_error err = {0};
    const accel_kind *k2;
    void *a2;
    accel_build_stats st2;
    if (accel_build_spec(spec, &ts->scene, 2, &k2, &a2, &st2, &err)) {
        test_fail(__FILE__, __LINE__, "%s: 2-thread build failed: %s", spec, err.msg);
        return;
    }
    const test_set *t = &ts->sets[0];
    size_t n = t->rays.count;
    accel_hit *h1 = malloc((n ? n : 1) * sizeof *h1), *h2 = malloc((n ? n : 1) * sizeof *h2);
    if (h1 && h2) {
        accel_trace(kind, accel, t->rays.rays, h1, n, 1, NULL);
        accel_trace(k2, a2, t->rays.rays, h2, n, 1, NULL);
        CHECKF(hits_identical(h1, h2, n), "%s on %s: 2-thread build traces differently", spec,
               ts->scene.name);
    }
    CHECKF(st->bytes == st2.bytes && st->nodes == st2.nodes,
           "%s on %s: 2-thread build differs (%zu vs %zu bytes)", spec, ts->scene.name, st->bytes,
           st2.bytes);
    free(h1);
    free(h2);
    k2->destroy(a2);
}

/* The primitive tests a set's rays may cost a kind (thin = 1): a kind that
 * tests every primitive per ray (brute force: 75k per ray on the bunny;
 * conformance_brute was 65 s of the suite's CPU, the largest test), or a
 * quarter of them (grid:res=1), is checked on every k-th ray of each set
 * instead, k chosen to keep the largest set of a scene under this many
 * tests and over 128 rays (the scanned meshes: every 6th ray; built-in
 * scenes: every 2nd to 9th), each sampled ray meeting every primitive of
 * the scene. A structure that pays (fewer tests per ray) keeps every ray,
 * however slow its scene. */
#define THIN_TESTS_PER_SET 2e6

/* The stride of every k-th ray for kind's built accel on ts (1: every ray),
 * from a counted probe of the first 64 primary rays (its primitive tests
 * per ray into *per_ray_out). */
static size_t thin_stride(const test_scene *ts, const accel_kind *kind, const void *accel,
                          double *per_ray_out)
{
    const test_set *t = &ts->sets[0];
    size_t probe = t->rays.count < 64 ? t->rays.count : 64;
    accel_hit *h = malloc((probe ? probe : 1) * sizeof *h);
    if (!h || !probe) {
        free(h);
        return 1;
    }
    accel_counters c = {0};
    accel_trace(kind, accel, t->rays.rays, h, probe, 1, &c);
    free(h);
    double per_ray = (double)c.prim_tests / (double)probe, most = 1;
    *per_ray_out = per_ray;
    for (int si = 0; si < ts->set_count; si++)
        if ((double)ts->sets[si].rays.count > most) most = (double)ts->sets[si].rays.count;
    /* Only a walk that tests a quarter of the primitives or more per ray:
     * brute force, or a structure that degenerates to it (grid:res=1). */
    if (per_ray * 4 < (double)ts->scene.prim_count) return 1;
    double k = ceil(per_ray * most / THIN_TESTS_PER_SET);
    if (k > most / 128) k = floor(most / 128); /* the largest set keeps 128 rays or more */
    return k > 1 ? (size_t)k : 1;
}

/* Every stride-th ray of t and its reference hit, into rays and ref
 * (caller frees); the count. */
static size_t thin_set(const test_set *t, size_t stride, accel_ray **rays, accel_hit **ref)
{
    size_t m = (t->rays.count + stride - 1) / stride;
    *rays = malloc((m ? m : 1) * sizeof **rays);
    *ref = malloc((m ? m : 1) * sizeof **ref);
    if (!*rays || !*ref) {
        free(*rays), free(*ref);
        *rays = NULL, *ref = NULL;
        return 0;
    }
    for (size_t i = 0; i < m; i++) (*rays)[i] = t->rays.rays[i * stride], (*ref)[i] = t->ref[i * stride];
    return m;
}

/* Runs one kind variant on one prepared scene; returns the number of bad
 * rays. `given` (a kind outside the registry, built with its defaults)
 * and `quiet` (count without failing) serve the mutant test below; `thin`
 * lets a kind that tests every primitive per ray run every k-th ray
 * (thin_stride). */
static size_t check_variant_of(test_scene *ts, const accel_kind *given, const char *spec, int naive,
                               int invariants, int quiet, int thin)
{
    accel_error err = {0};
    const accel_kind *kind = given;
    void *accel;
    accel_build_stats st;
    if (given ? accel_build_kind(given, "", &ts->scene, 1, &accel, &st, &err)
              : accel_build_spec(spec, &ts->scene, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s on %s: build failed: %s", spec, ts->scene.name, err.msg);
        return 1;
    }
    size_t bad_total = 0;
    double probe_tests = 0;
    size_t stride = thin ? thin_stride(ts, kind, accel, &probe_tests) : 1;
    if (stride > 1)
        test_note("%s on %s: 1 ray in %zu of each set (%.0f primitive tests per ray)", spec,
                  ts->scene.name, stride, probe_tests);
    for (int si = 0; si < ts->set_count; si++) {
        const test_set *t = &ts->sets[si];
        test_set thinned = *t;
        accel_ray *own_rays = NULL;
        accel_hit *own_ref = NULL;
        if (stride > 1) {
            thinned.rays.count = thin_set(t, stride, &own_rays, &own_ref);
            thinned.rays.rays = own_rays, thinned.ref = own_ref;
            CHECKF(own_rays != NULL || !t->rays.count, "%s: out of memory", spec);
            t = &thinned;
        }
        size_t n = t->rays.count;
        char label[600];
        snprintf(label, sizeof label, "%s on %s/%s", spec, ts->scene.name, t->name);
        accel_hit *hits = malloc((n ? n : 1) * sizeof *hits);
        uint8_t *occ = malloc(n ? n : 1);
        if (!hits || !occ) {
            test_fail(__FILE__, __LINE__, "%s: out of memory", label);
            free(hits);
            free(occ);
            free(own_rays), free(own_ref);
            continue;
        }
        test_diff d = test_trace_diff(&ts->scene, kind, accel, t->rays.rays, n, t->ref, 1, hits, occ);
        size_t bad = test_diff_bad(&d);
        if (naive) {
            /* Reported, not hidden; only gross failure (>1% of ordinary
             * rays) fails: rays aimed at vertices, edges and along axes are
             * the naive test's known weakness, counted by the stability suite. */
            int stiff =
                !strcmp(t->name, "vertex") || !strcmp(t->name, "edge") || !strcmp(t->name, "axis") ||
                !strcmp(t->name, "ending at the hit");
            if (bad)
                test_note("%s: %zu holes, %zu false hits, %zu disagreements, %zu occluded "
                          "mismatches of %zu rays",
                          label, d.holes, d.false_hits, d.disagreements, d.occ_bad, n);
            CHECKF(stiff || bad * 100 <= n + 100, "%s: %zu bad rays of %zu", label, bad, n);
        } else if (bad && !quiet) {
            test_fail_diff(__FILE__, __LINE__, label, &d, t->rays.rays, t->ref, hits, occ);
        }
        bad_total += bad;
        if (invariants) check_trace_invariants(kind, accel, label, t, hits);
        free(hits);
        free(occ);
        free(own_rays), free(own_ref);
    }
    if (invariants) check_build_invariants(ts, spec, kind, accel, &st);
    kind->destroy(accel);
    return bad_total;
}

static size_t check_variant(test_scene *ts, const char *spec, int naive, int invariants)
{
    return check_variant_of(ts, NULL, spec, naive, invariants, 0, 1);
}

enum { MAX_SPECS = 64 };

/* The specs the suite runs for a kind, in order: each listed variant and,
 * right after the default, its naive twin ("kind:tri=naive") unless the
 * default is naive already or the list holds the twin (grid lists
 * "tri=naive" itself, which used to run twice). Returns the count. */
static int conformance_specs(const accel_kind *kind, char specs[][256], int max)
{
    const char *const *vars = kind->variants;
    static const char *const none[] = {"", NULL};
    if (!vars) vars = none;
    int listed = 0, count = 0;
    while (vars[listed]) listed++;
    for (int v = 0; v < listed && count < max; v++) {
        snprintf(specs[count++], 256, "%s%s%s", kind->name, vars[v][0] ? ":" : "", vars[v]);
        if (v != 0 || strstr(specs[0], "tri=naive") || count == max) continue;
        int twin_listed = 0;
        for (int w = 1; w < listed; w++) twin_listed |= !strcmp(vars[w], "tri=naive");
        if (!twin_listed) snprintf(specs[count++], 256, "%s:tri=naive", kind->name);
    }
    return count;
}

/* Every spec the conformance suite runs for a kind is run once. */
TEST(conformance_naive_twin_and_variants_run_once)
{
    for (size_t k = 0; k < accel_kind_count; k++) {
        static char specs[MAX_SPECS][256];
        int n = conformance_specs(accel_kinds[k], specs, MAX_SPECS);
        CHECKF(n > 0 && n < MAX_SPECS, "%s: %d conformance specs", accel_kinds[k]->name, n);
        int naive = 0;
        for (int i = 0; i < n; i++) {
            naive |= strstr(specs[i], "tri=naive") != NULL;
            for (int j = 0; j < i; j++)
                CHECKF(strcmp(specs[i], specs[j]), "%s: %s is run twice", accel_kinds[k]->name,
                       specs[i]);
        }
        CHECKF(naive, "%s: no naive triangle spec is run", accel_kinds[k]->name);
    }
}

/* all_variants = 0: only the kind's default, answers against the oracle,
 * for the large scanned meshes where every variant would cost minutes. The
 * invariants (counted and uncounted, 1 and 2 threads, build statistics) and
 * the naive twin are checked on every built-in scene already; on the meshes
 * they would triple the passes (brute force: 42 of its 63 s went there).
 * A kind that tests every primitive per ray runs every k-th ray of a large
 * set (thin_stride). */
static void run_kind(test_scene *ts, const accel_kind *kind, int all_variants)
{
    static char specs[MAX_SPECS][256];
    int n = conformance_specs(kind, specs, MAX_SPECS);
    for (int i = 0; i < (all_variants ? n : 1); i++)
        check_variant(ts, specs[i], strstr(specs[i], "tri=naive") != NULL, all_variants && i == 0);
}

/*
 * The prepared scenes, kept from one kind's test to the next: the reference
 * is traced once per scene, whichever kinds run. Freed at exit.
 */
enum { MAX_SCENES = 32 };
static test_scene *prepared[MAX_SCENES];
static int prepared_count;

static void free_prepared(void)
{
    for (int i = 0; i < prepared_count; i++) {
        free_scene(prepared[i]);
        free(prepared[i]);
    }
    prepared_count = 0;
}

/* The prepared scene of spec (primary rays size x size); NULL on failure. */
static test_scene *scene_for(const char *spec, int size)
{
    for (int i = 0; i < prepared_count; i++)
        if (!strcmp(prepared[i]->spec, spec)) return prepared[i];
    if (prepared_count == MAX_SCENES) {
        test_fail(__FILE__, __LINE__, "more than %d conformance scenes", MAX_SCENES);
        return NULL;
    }
    test_scene *ts = malloc(sizeof *ts);
    if (!ts || !prepare_scene(ts, spec, size)) {
        free(ts);
        return NULL;
    }
    if (prepared_count == 0) atexit(free_prepared);
    prepared[prepared_count++] = ts;
    return ts;
}

/* conformance_<kind>: every listed variant on every built-in scene at
 * small size, and the kind's default on the shared scanned meshes. */
TEST_PER_KIND(conformance)
{
    for (size_t g = 0; g < scene_generator_count; g++) {
        const char *spec = scene_generators[g]->small_spec;
        test_scene *ts = scene_for(spec ? spec : scene_generators[g]->name, 40);
        if (ts) run_kind(ts, kind, 1);
    }
    char paths[16][512];
    int count = test_shared_files(".off", paths, 16);
    for (int i = 0; i < count; i++) {
        test_scene *ts = scene_for(paths[i], 24);
        if (ts) run_kind(ts, kind, 0);
    }
}

/*
 * A kernel of our own that names the wrong triangle at the right t, u, v:
 * the 8-wide BVH with every hit's id moved to its neighbour in scene
 * order (id ^ 1), as a padded SIMD lane or a student's "index into my own
 * order" would. The old rule (the same t is enough) passed it; the
 * conformance check must find it on every scene the rays hit.
 */
typedef struct {
    const accel_kind *kind;
    void *accel;
    uint32_t prim_count;
} mutant;

static int mutant_build(const accel_scene *scene, const accel_params *params, int threads,
                        void **out, accel_build_stats *stats, accel_error *err)
{
    (void)params;
    mutant *m = calloc(1, sizeof *m);
    if (!m) return accel_fail(err, ACCEL_ERR_NOMEM, "no memory");
    m->prim_count = scene->prim_count;
    if (accel_build_spec("bvh:width=8", scene, threads, &m->kind, &m->accel, stats, err)) {
        free(m);
        return err->code;
    }
    *out = m;
    return 0;
}

static void mutant_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                             size_t count, accel_counters *c)
{
    const mutant *m = accel;
    m->kind->intersect(m->accel, rays, hits, count, c);
    for (size_t i = 0; i < count; i++)
        if (hits[i].prim != ACCEL_MISS && (hits[i].prim ^ 1u) < m->prim_count) hits[i].prim ^= 1u;
}

static void mutant_occluded(const void *accel, const accel_ray *rays, uint8_t *occ, size_t count,
                            accel_counters *c)
{
    const mutant *m = accel;
    m->kind->occluded(m->accel, rays, occ, count, c);
}

static size_t mutant_memory(const void *accel)
{
    const mutant *m = accel;
    return sizeof *m + m->kind->memory(m->accel);
}

static void mutant_destroy(void *accel)
{
    mutant *m = accel;
    m->kind->destroy(m->accel);
    free(m);
}

TEST(conformance_catches_a_wrong_triangle_at_the_right_t)
{
    static const accel_kind kind = {
        .name = "mutant", .summary = "bvh:width=8 naming each hit's neighbour", .step_name = "nodes",
        .build = mutant_build, .intersect = mutant_intersect, .occluded = mutant_occluded,
        .memory = mutant_memory, .destroy = mutant_destroy};
    int scenes = 0;
    for (size_t g = 0; g < scene_generator_count; g++) {
        const char *spec = scene_generators[g]->small_spec;
        test_scene *ts = scene_for(spec ? spec : scene_generators[g]->name, 40);
        if (!ts) continue;
        size_t hits = 0;
        for (int si = 0; si < ts->set_count; si++)
            for (size_t i = 0; i < ts->sets[si].rays.count; i++)
                hits += ts->sets[si].ref[i].prim != ACCEL_MISS;
        size_t bad = check_variant_of(ts, &kind, "mutant", 0, 0, 1, 0);
        /* the unmutated kernel passes on the same rays */
        size_t good = check_variant_of(ts, NULL, "bvh:width=8", 0, 0, 1, 0);
        CHECKF(good == 0, "bvh:width=8 on %s: %zu bad rays", ts->scene.name, good);
        CHECKF(!hits || bad * 2 >= hits, "the mutant on %s: only %zu of %zu hits caught",
               ts->scene.name, bad, hits);
        scenes += hits > 0;
    }
    CHECKF(scenes >= 5, "only %d scenes with hits", scenes);
}
