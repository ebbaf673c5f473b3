/*
 * support.c - the shared test helpers of support.h: random numbers, scene
 * helpers, ray constructors, the oracle and the comparison with it (files,
 * folders and commands are in support_files.c).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>
#include <time.h>

#include "support.h"

/* ---- random numbers ------------------------------------------------------------ */

static uint64_t rng_state = TEST_SEED;

void test_seed(uint64_t seed) { rng_state = seed; }

uint64_t test_xorshift(uint64_t *state)
{
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return *state;
}

float test_rand_of(uint64_t *state) { return (float)(test_xorshift(state) >> 40) / 16777216.0f; }

uint64_t test_rand_u64(void) { return test_xorshift(&rng_state); }

float test_rand(void) { return test_rand_of(&rng_state); }

float test_rand_in(float lo, float hi) { return lo + (hi - lo) * test_rand(); }

vec3 test_rand_point(box3 b)
{
    float x = test_rand_in(b.min.x, b.max.x);
    float y = test_rand_in(b.min.y, b.max.y);
    return v3(x, y, test_rand_in(b.min.z, b.max.z));
}

float test_rand_lattice(float lo, float step, int count)
{
    return lo + step * (float)(int)(test_rand() * (float)count);
}

/* ---- scenes ------------------------------------------------------------------------ */

int test_add_tri(scene_builder *b, vec3 p, vec3 q, vec3 r)
{
    accel_error err = {0};
    int rc = scene_builder_add_tri(b, p, q, r, &err);
    CHECKF(rc == 0, "scene_builder_add_tri: %s", err.msg);
    return rc == 0;
}

int test_finish(scene_builder *b, const char *name, accel_scene *s)
{
    accel_error err = {0};
    int rc = scene_finish(b, name, s, &err);
    scene_builder_free(b);
    CHECKF(rc == 0, "scene_finish %s: %s", name, err.msg);
    return rc == 0;
}

int test_make_scene(const char *spec, accel_scene *s)
{
    accel_error err = {0};
    int rc = scene_create(spec, s, &err);
    CHECKF(rc == 0, "scene %s: %s", spec, err.msg);
    return rc == 0;
}

int test_build_rc(const char *spec, const accel_scene *s, accel_error *err)
{
    const accel_kind *k;
    void *a;
    accel_build_stats st;
    memset(err, 0, sizeof *err);
    int rc = accel_build_spec(spec, s, 1, &k, &a, &st, err);
    if (rc == 0) k->destroy(a);
    return rc;
}

/* ---- rays ------------------------------------------------------------------------ */

accel_ray test_ray(vec3 o, vec3 d, float t_near, float t_far)
{
    accel_ray r = {o.x, o.y, o.z, t_near, d.x, d.y, d.z, t_far};
    return r;
}

void test_rays_push(test_rays *r, accel_ray ray)
{
    if (r->failed) return;
    if (r->count == r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 1024;
        accel_ray *p = realloc(r->rays, cap * sizeof *p);
        if (!p) {
            test_fail(__FILE__, __LINE__, "out of memory for %zu rays", cap);
            r->failed = 1;
            return;
        }
        r->rays = p;
        r->cap = cap;
    }
    r->rays[r->count++] = ray;
}

void test_rays_free(test_rays *r)
{
    free(r->rays);
    memset(r, 0, sizeof *r);
}

int test_ray_in_a_plane(const accel_scene *s, const accel_ray *r)
{
    for (uint32_t k = 0; k < s->live_count; k++) {
        if (s->live[k] >= s->tri_count) continue;
        const float *t = s->tris + 9 * (size_t)s->live[k];
        double e1[3], e2[3], n[3], w[3];
        for (int a = 0; a < 3; a++) {
            e1[a] = (double)t[3 + a] - t[a];
            e2[a] = (double)t[6 + a] - t[a];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        w[0] = (double)r->ox - t[0], w[1] = (double)r->oy - t[1], w[2] = (double)r->oz - t[2];
        if (n[0] * r->dx + n[1] * r->dy + n[2] * r->dz == 0.0 &&
            n[0] * w[0] + n[1] * w[1] + n[2] * w[2] == 0.0)
            return 1;
    }
    return 0;
}

/* The point of a random live triangle each draw aims at: a vertex, or the
 * midpoint of an edge. Returns 0 when the draw picks a sphere. */
static int aim_point(const accel_scene *s, uint64_t seed, size_t i, int edge, vec3 *out)
{
    uint32_t prim = s->live[(size_t)(rays_rand(seed, i, 0) * s->live_count)];
    if (prim >= s->tri_count) return 0;
    int corner = (int)(rays_rand(seed, i, 1) * 3);
    const float *t = s->tris + 9 * (size_t)prim;
    vec3 v = v3_load(t + 3 * corner);
    if (edge) v = v3_scale(v3_add(v, v3_load(t + 3 * ((corner + 1) % 3))), 0.5f);
    *out = v;
    return 1;
}

static void aimed_rays(test_rays *r, const accel_scene *s, vec3 eye, size_t draws, uint64_t seed,
                       int edge)
{
    if (s->tri_count == 0 || s->live_count == 0) return;
    for (size_t i = 0; i < draws; i++) {
        vec3 v;
        if (aim_point(s, seed, i, edge, &v))
            test_rays_push(r, test_ray(eye, v3_sub(v, eye), 0.0f, INFINITY));
    }
}

void test_rays_at_vertices(test_rays *r, const accel_scene *s, vec3 eye, size_t draws,
                           uint64_t seed)
{
    aimed_rays(r, s, eye, draws, seed, 0);
}

void test_rays_at_edges(test_rays *r, const accel_scene *s, vec3 eye, size_t draws, uint64_t seed)
{
    aimed_rays(r, s, eye, draws, seed, 1);
}

static vec3 vec_of(const float v[3]) { return v3(v[0], v[1], v[2]); }

void test_rays_axis_from_faces(test_rays *r, box3 b, int per_side)
{
    const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    const float last = (float)(per_side - 1);
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++)
            for (int i = 0; i < per_side; i++)
                for (int j = 0; j < per_side; j++) {
                    float o[3], d[3];
                    int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
                    /* i or j = 0 or per_side-1: exactly on the box's edges. */
                    o[a1] = lo[a1] + (hi[a1] - lo[a1]) * (float)i / last;
                    o[a2] = lo[a2] + (hi[a2] - lo[a2]) * (float)j / last;
                    o[axis] = side ? hi[axis] : lo[axis];
                    d[axis] = side ? -1.0f : 1.0f;
                    d[a1] = ((i + j) & 1) ? -0.0f : 0.0f;
                    d[a2] = (i & 2) ? -0.0f : 0.0f;
                    test_rays_push(r, test_ray(vec_of(o), vec_of(d), 0.0f, INFINITY));
                }
}

/* Push ray unless it lies in the plane of a triangle of skip (when given). */
static int push_unless_in_plane(test_rays *r, accel_ray ray, const accel_scene *skip)
{
    if (skip && test_ray_in_a_plane(skip, &ray)) return 0;
    test_rays_push(r, ray);
    return 1;
}

void test_rays_axis_lattice(test_rays *r, box3 b, float step, int j_stride, unsigned starts,
                            const accel_scene *skip_planes_of)
{
    const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    for (int axis = 0; axis < 3; axis++) {
        int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        int n1 = (int)((hi[a1] - lo[a1]) / step + 0.5f),
            n2 = (int)((hi[a2] - lo[a2]) / step + 0.5f);
        for (int i = 0; i <= n1; i++)
            for (int j = 0; j <= n2; j += j_stride)
                for (int start = 0; start < 4; start++) {
                    if (!(starts & (1u << start))) continue;
                    float o[3], d[3];
                    o[a1] = lo[a1] + step * (float)i;
                    o[a2] = lo[a2] + step * (float)j;
                    o[axis] = start == 0   ? lo[axis] - 1.0f
                              : start == 1 ? hi[axis] + 1.0f
                              : start == 2 ? lo[axis]
                                           : 0.5f * (lo[axis] + hi[axis]);
                    d[axis] = start == 1 ? -1.0f : (start == 3 && (i & 1)) ? -2.0f : 1.0f;
                    d[a1] = (i + j) & 1 ? -0.0f : 0.0f;
                    d[a2] = j & 2 ? -0.0f : 0.0f;
                    push_unless_in_plane(r, test_ray(vec_of(o), vec_of(d), 0.0f, INFINITY),
                                         skip_planes_of);
                }
    }
}

void test_rays_lattice_points(test_rays *r, box3 b, float step, float margin, size_t count,
                              const accel_scene *skip_planes_of)
{
    const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    int n_org[3], n_tgt[3];
    for (int a = 0; a < 3; a++) {
        n_tgt[a] = (int)((hi[a] - lo[a]) / step + 0.5f) + 1;
        n_org[a] = (int)((hi[a] - lo[a] + 2.0f * margin) / step + 0.5f) + 1;
    }
    for (size_t k = 0; k < count && !r->failed;) {
        float o[3], t[3];
        for (int a = 0; a < 3; a++) {
            o[a] = test_rand_lattice(lo[a] - margin, step, n_org[a]);
            t[a] = test_rand_lattice(lo[a], step, n_tgt[a]);
        }
        vec3 d = v3(t[0] - o[0], t[1] - o[1], t[2] - o[2]);
        if (d.x == 0 && d.y == 0 && d.z == 0) continue;
        float t_near = k % 5 == 0 ? 0.5f : 0.0f;
        float t_far = k % 7 == 0 ? 1.0f : INFINITY; /* some end exactly on a lattice point */
        k += push_unless_in_plane(r, test_ray(vec_of(o), d, t_near, t_far), skip_planes_of);
    }
}

void test_rays_inside(test_rays *r, box3 b, size_t count, uint64_t seed)
{
    vec3 e = box3_extent(b);
    float diag = v3_len(e);
    for (size_t i = 0; i < count; i++) {
        vec3 o = v3_add(b.min, v3_mul(e, v3(rays_rand(seed, i, 0), rays_rand(seed, i, 1),
                                            rays_rand(seed, i, 2))));
        float z = 2 * rays_rand(seed, i, 3) - 1, ph = 6.2831853f * rays_rand(seed, i, 4);
        float rr = sqrtf(fmaxf(0, 1 - z * z));
        vec3 d = v3(rr * cosf(ph), rr * sinf(ph), z);
        float t_near = (i % 3 == 0) ? 0.05f * diag * rays_rand(seed, i, 5) : 0.0f;
        float t_far = (i % 2 == 0) ? 0.5f * diag : INFINITY;
        test_rays_push(r, test_ray(o, d, t_near, t_far));
    }
}

void test_rays_random(test_rays *r, box3 b, size_t count)
{
    if (box3_is_empty(b)) b = (box3){{-1, -1, -1}, {1, 1, 1}};
    vec3 e = box3_extent(b);
    for (size_t i = 0; i < count; i++) {
        vec3 o = v3(test_rand_in(b.min.x - 0.5f * e.x, b.max.x + 0.5f * e.x),
                    test_rand_in(b.min.y - 0.5f * e.y, b.max.y + 0.5f * e.y),
                    test_rand_in(b.min.z - 0.5f * e.z, b.max.z + 0.5f * e.z));
        vec3 d = v3_sub(test_rand_point(b), o);
        if (i % 7 == 3) d.x = (i & 8) ? -0.0f : 0.0f;
        if (i % 11 == 5) d.y = (i & 16) ? -0.0f : 0.0f;
        accel_ray ray = test_ray(o, d, 0.0f, INFINITY);
        if (i % 5 == 1) ray.t_far = 0.7f;
        if (i % 13 == 2 && v3_len(d) > 0) ray.t_near = 0.3f;
        test_rays_push(r, ray);
    }
}

void test_rays_shortened(test_rays *r, const accel_ray *rays, const accel_hit *ref, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (ref[i].prim == ACCEL_MISS) continue;
        accel_ray ray = rays[i];
        ray.t_far = ref[i].t * (1.0f - 1e-3f);
        test_rays_push(r, ray);
    }
}

void test_rays_ending_at_hit(test_rays *r, const accel_ray *rays, const accel_hit *ref, size_t n)
{
    rays_set in = {(accel_ray *)rays, NULL, n, 0, 0}, out;
    accel_error err = {0};
    if (rays_ending_at_hit(&in, ref, &out, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        r->failed = 1;
        return;
    }
    for (size_t i = 0; i < out.count; i++) test_rays_push(r, out.rays[i]);
    rays_free(&out);
}

void test_rays_behind(test_rays *r, const accel_ray *rays, const accel_hit *ref, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (ref[i].prim == ACCEL_MISS) continue;
        accel_ray ray = rays[i];
        float m = 1.5f * ref[i].t;
        ray.ox += m * ray.dx, ray.oy += m * ray.dy, ray.oz += m * ray.dz;
        ray.t_near = -m;
        ray.t_far = (i % 2) ? INFINITY : 0.25f * m;
        test_rays_push(r, ray);
    }
}

/* ---- the oracle and the comparison ----------------------------------------------------- */

accel_hit *test_oracle_hits(const accel_scene *s, const accel_ray *rays, size_t n, test_oracle o)
{
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref);
    if (!ref) {
        test_fail(__FILE__, __LINE__, "out of memory for %zu oracle hits", n);
        return NULL;
    }
    if (o == TEST_ORACLE_REFERENCE) {
        accel_reference_trace(s, rays, ref, n, accel_cpu_count());
        return ref;
    }
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    accel_error err = {0};
    if (accel_build_spec("brute", s, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "the float brute force on %s: %s", s->name, err.msg);
        free(ref);
        return NULL;
    }
    accel_trace(kind, accel, rays, ref, n, accel_cpu_count(), NULL);
    kind->destroy(accel);
    return ref;
}

test_diff test_trace_diff(const accel_scene *scene, const accel_kind *kind, const void *accel, const accel_ray *rays,
                          size_t n, const accel_hit *ref, int threads, accel_hit *hits,
                          uint8_t *occ)
{
    test_diff d = {.rays = n, .first_bad = SIZE_MAX};
    accel_hit *own_hits = hits ? NULL : malloc((n ? n : 1) * sizeof *own_hits);
    uint8_t *own_occ = occ ? NULL : malloc(n ? n : 1);
    if (!hits) hits = own_hits;
    if (!occ) occ = own_occ;
    if (!hits || !occ) {
        test_fail(__FILE__, __LINE__, "out of memory for %zu rays", n);
        d.holes = n ? n : 1;
    } else {
        /* Counted: step bounds are checked in counted runs only
         * (core/variant.h), so a traversal loop is caught here, not hung in. */
        accel_counters c = {0}, c_occ = {0};
        accel_trace(kind, accel, rays, hits, n, threads, &c);
        accel_trace_occluded(kind, accel, rays, occ, n, threads, &c_occ);
        accel_error broken = {0};
        if (accel_counters_status(&c, &broken) || accel_counters_status(&c_occ, &broken))
            test_fail(__FILE__, __LINE__, "%s: %s", kind->name, broken.msg);
        hits_diff h = hits_compare(scene, rays, ref, hits, n);
        d.holes = h.holes;
        d.false_hits = h.false_hits;
        d.disagreements = h.disagreements;
        d.ties = h.ties;
        d.first_bad = h.first_bad;
        for (size_t i = 0; i < n; i++)
            if (occ[i] != (ref[i].prim != ACCEL_MISS)) {
                d.occ_bad++;
                if (d.first_bad == SIZE_MAX) d.first_bad = i;
            }
    }
    free(own_hits);
    free(own_occ);
    return d;
}

void test_fail_diff(const char *file, int line, const char *label, const test_diff *d,
                    const accel_ray *rays, const accel_hit *ref, const accel_hit *hits,
                    const uint8_t *occ)
{
    size_t i = d->first_bad;
    if (i == SIZE_MAX || !hits || !occ) {
        test_fail(file, line,
                  "%s: %zu holes, %zu false hits, %zu disagreements, %zu occluded "
                  "mismatches of %zu rays",
                  label, d->holes, d->false_hits, d->disagreements, d->occ_bad, d->rays);
        return;
    }
    const accel_ray *r = &rays[i];
    test_fail(file, line,
              "%s: %zu holes, %zu false hits, %zu disagreements, %zu occluded mismatches of %zu "
              "rays; first ray %zu o=(%.9g,%.9g,%.9g) d=(%.9g,%.9g,%.9g) t=[%.9g,%.9g]: ref prim "
              "%u t %.9g, got prim %u t %.9g, occluded %d",
              label, d->holes, d->false_hits, d->disagreements, d->occ_bad, d->rays, i, r->ox,
              r->oy, r->oz, r->dx, r->dy, r->dz, r->t_near, r->t_far, ref[i].prim, ref[i].t,
              hits[i].prim, hits[i].t, occ[i]);
}

void *test_build_kind(const char *spec, const accel_scene *s, int threads,
                      const accel_kind **kind, accel_build_stats *st)
{
    accel_error err = {0};
    void *accel = NULL;
    accel_build_stats local;
    int rc = accel_build_spec(spec, s, threads, kind, &accel, st ? st : &local, &err);
    CHECKF(rc == 0, "%s on %s: %s", spec, s->name, err.msg);
    return rc ? NULL : accel;
}

void *test_build(const char *spec, const accel_scene *s, int threads, accel_build_stats *st)
{
    const accel_kind *kind;
    return test_build_kind(spec, s, threads, &kind, st);
}

size_t test_check_accel(const accel_scene *s, const accel_kind *kind, const void *accel,
                        const char *spec, const accel_ray *rays, size_t n, const accel_hit *ref,
                        accel_counters *cnt)
{
    char label[300];
    snprintf(label, sizeof label, "%s on %s", spec, s->name);
    accel_hit *own = ref ? NULL : test_oracle_hits(s, rays, n, TEST_ORACLE_REFERENCE);
    if (!ref) ref = own;
    accel_hit *hits = malloc((n ? n : 1) * sizeof *hits);
    accel_hit *hits_c = malloc((n ? n : 1) * sizeof *hits_c);
    uint8_t *occ = malloc(n ? n : 1);
    if (!ref || !hits || !hits_c || !occ) {
        test_fail(__FILE__, __LINE__, "%s: out of memory or no oracle", label);
        free(own);
        free(hits);
        free(hits_c);
        free(occ);
        return n ? n : 1;
    }
    test_diff d = test_trace_diff(s, kind, accel, rays, n, ref, 1, hits, occ);
    size_t bad = test_diff_bad(&d);
    if (bad) test_fail_diff(__FILE__, __LINE__, label, &d, rays, ref, hits, occ);

    accel_counters c;
    memset(&c, 0, sizeof c);
    accel_trace(kind, accel, rays, hits_c, n, 1, &c);
    CHECKF(memcmp(hits, hits_c, n * sizeof *hits) == 0, "%s: counted and uncounted traces differ",
           label);
    uint64_t level_sum = 0;
    for (int l = 0; l < 4; l++) level_sum += c.level_steps[l];
    CHECKF(c.rays == n && c.empty_steps <= c.steps && (level_sum == 0 || level_sum == c.steps),
           "%s: counters: %llu rays of %zu, %llu steps, %llu empty, %llu summed over levels", label,
           (unsigned long long)c.rays, n, (unsigned long long)c.steps,
           (unsigned long long)c.empty_steps, (unsigned long long)level_sum);
    CHECKF(c.broken == 0, "%s: %llu rays broke an invariant (first at %s:%d)", label,
           (unsigned long long)c.broken, c.broken_file ? c.broken_file : "?", c.broken_line);
    if (cnt) *cnt = c;
    free(own);
    free(hits);
    free(hits_c);
    free(occ);
    return bad;
}

size_t test_check_spec(const accel_scene *s, const char *spec, const accel_ray *rays, size_t n,
                       const accel_hit *ref, accel_build_stats *stats, accel_counters *cnt)
{
    accel_error err = {0};
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    if (accel_build_spec(spec, s, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s on %s: build failed: %s", spec, s->name, err.msg);
        return n ? n : 1;
    }
    if (stats) *stats = st;
    size_t bad = test_check_accel(s, kind, accel, spec, rays, n, ref, cnt);
    kind->destroy(accel);
    return bad;
}

void test_check_variants(const accel_scene *s, const accel_kind *kind, const char *const *extra,
                         const accel_ray *rays, size_t n, test_oracle o)
{
    accel_hit *ref = test_oracle_hits(s, rays, n, o);
    if (!ref) return;
    char spec[256];
    static const char *const none[] = {"", NULL};
    for (const char *const *v = kind->variants ? kind->variants : none; *v; v++) {
        if (strstr(*v, "tri=naive")) continue;
        snprintf(spec, sizeof spec, "%s%s%s", kind->name, **v ? ":" : "", *v);
        test_check_spec(s, spec, rays, n, ref, NULL, NULL);
    }
    for (const char *const *v = extra; v && *v; v++) {
        snprintf(spec, sizeof spec, "%s:%s", kind->name, *v);
        test_check_spec(s, spec, rays, n, ref, NULL, NULL);
    }
    free(ref);
}

static time_t test_process_start;
__attribute__((constructor)) static void test_note_start(void) { test_process_start = time(NULL); }

int test_quick_report(void)
{
    struct stat st;
    if (stat("build/quick-report/REPORT.md", &st) == 0 && st.st_mtime >= test_process_start)
        return 1;
    /* A file no run writes (issue 36: a stale plot in report/): the run must remove it. */
    if (system("mkdir -p build/quick-report && touch build/quick-report/stale_plot.png")) {}
    if (system("experiments/report.sh --quick > build/quick-report.log 2>&1") != 0) {
        test_fail(__FILE__, __LINE__,
                  "experiments/report.sh --quick failed: see build/quick-report.log");
        return 0;
    }
    return 1;
}

int test_stiff_case(int ci, stiff_case *c)
{
    accel_error err = {0};
    if (stiff_case_make(ci, c, &err) == 0) return 1;
    test_fail(__FILE__, __LINE__, "stiff case %d: %s", ci, err.msg);
    return 0;
}
