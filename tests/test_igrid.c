/*
 * test_igrid.c - the irregular grid: its structure's invariants
 * (every voxel maps to a cell whose exit box holds it; every voxel of an
 * exit box belongs to a cell whose primitives are a subset of the box's
 * cell; every primitive touching a voxel is in that voxel's cell), answers
 * against the reference for each build step on and off (clusters with
 * spheres, a lattice scene with rays through voxel corners and edges, flat
 * and far-from-origin scenes), what each step buys in the counters, memory
 * refusals and thread-count independence. Two nested-grid tests are here
 * too, named igrid_near_copies_ngrid_* (the family is the file's: igrid):
 * they share this file's near-copies scene and check_small.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"
#include "grid/overlap.h"
#include "irregular_grid/igrid.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

static uint64_t rng = 0x853C49E6748FEA9Bull;
static float frand(void) { return test_rand_of(&rng); }
static float frange(float lo, float hi) { return lo + (hi - lo) * frand(); }

static accel_ray mk_ray(vec3 o, vec3 d, float t_near, float t_far)
{
    accel_ray r = {o.x, o.y, o.z, t_near, d.x, d.y, d.z, t_far};
    return r;
}

/* Clusters of small triangles and a few spheres in a large box. */
static int cluster_scene(accel_scene *s, float offset)
{
    scene_builder b = {0};
    accel_error err = {0};
    rng = 99;
    for (int k = 0; k < 5; k++) {
        vec3 c = v3(offset + frand() * 100, offset + frand() * 100, offset + frand() * 30);
        float spread = k == 0 ? 40.0f : 5.0f;
        for (int i = 0; i < 300; i++) {
            vec3 p = v3_add(c, v3(frand() * spread, frand() * spread, frand() * 5));
            float sz = frand() < 0.05f ? 8.0f : 0.8f;
            vec3 q = v3_add(p, v3(frange(-sz, sz), frange(-sz, sz), frange(-sz, sz)));
            vec3 r = v3_add(p, v3(frange(-sz, sz), frange(-sz, sz), frange(-sz, sz)));
            scene_builder_add_tri(&b, p, q, r, &err);
        }
    }
    for (int i = 0; i < 20; i++)
        scene_builder_add_sphere(&b, v3(offset + frand() * 100, offset + frand() * 100,
                                        offset + frand() * 30), frange(0.2f, 4.0f), &err);
    return scene_finish(&b, offset != 0.0f ? "far clusters" : "clusters", s, &err) == 0;
}

/* Triangles with vertices on the lattice of step 0.5 in [0,4]^3: on the
 * voxel planes of an 8^3 lattice over the box. */
static int lattice_scene(accel_scene *s)
{
    scene_builder b = {0};
    accel_error err = {0};
    rng = 7;
    scene_builder_add_tri(&b, v3(0, 0, 0), v3(0.5f, 0, 0), v3(0, 0.5f, 0), &err);
    scene_builder_add_tri(&b, v3(4, 4, 4), v3(3.5f, 4, 4), v3(4, 3.5f, 4), &err);
    for (int i = 0; i < 300; i++) {
        vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = v3(0.5f * (int)(frand() * 9), 0.5f * (int)(frand() * 9), 0.5f * (int)(frand() * 9));
        scene_builder_add_tri(&b, p[0], p[1], p[2], &err);
    }
    return scene_finish(&b, "lattice", s, &err) == 0;
}

/* ---- structure ------------------------------------------------------------------------ */

/* Builds spec on s on one thread; NULL (and a failed check) when it fails. */
static void *build_or_fail(const char *spec, const accel_scene *s, const accel_kind **kind,
                           accel_build_stats *st)
{
    void *accel;
    accel_error err = {0};
    if (accel_build_spec(spec, s, 1, kind, &accel, st, &err)) {
        test_fail(__FILE__, __LINE__, "%s on %s: %s", spec, s->name, err.msg);
        return NULL;
    }
    return accel;
}

static int sorted_find(const uint32_t *v, uint32_t n, uint32_t x)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t m = (lo + hi) / 2;
        if (v[m] < x) lo = m + 1; else hi = m;
    }
    return lo < n && v[lo] == x;
}

static void check_structure(const accel_scene *s, const char *spec)
{
    const accel_kind *kind;
    accel_build_stats st;
    void *accel = build_or_fail(spec, s, &kind, &st);
    if (!accel) return;
    igrid_view v;
    igrid_get_view(accel, &v);
    const int *res = v.frame->res;
    size_t bad_box = 0, bad_sub = 0, bad_member = 0, bad_list = 0;
    for (int a = 0; a < 3; a++) CHECK(res[a] == v.top_res[a] << v.shift);
    for (uint32_t c = 0; c < v.cell_count; c++) {
        const igrid_cell *cell = &v.cells[c];
        for (int a = 0; a < 3; a++)
            bad_box += !(0 <= cell->lo[a] && cell->lo[a] < cell->hi[a] && cell->hi[a] <= res[a]);
        for (uint32_t k = cell->begin; k + 1 < cell->end; k++) bad_list += v.refs[k] >= v.refs[k + 1];
    }
    /* Every voxel of every exit box: its cell's list is a subset of the box's
     * cell's list, and the voxel's own cell's exit box holds it. */
    for (uint32_t c = 0; c < v.cell_count && !bad_box; c++) {
        const igrid_cell *cell = &v.cells[c];
        for (int z = cell->lo[2]; z < cell->hi[2]; z++)
            for (int y = cell->lo[1]; y < cell->hi[1]; y++)
                for (int x = cell->lo[0]; x < cell->hi[0]; x++) {
                    const igrid_cell *w = &v.cells[igrid_lookup(v.map, v.top_res, v.shift, x, y, z)];
                    bad_box += !(w->lo[0] <= x && x < w->hi[0] && w->lo[1] <= y && y < w->hi[1] &&
                                 w->lo[2] <= z && z < w->hi[2]);
                    for (uint32_t k = w->begin; k < w->end; k++)
                        if (!sorted_find(v.refs + cell->begin, cell->end - cell->begin, v.refs[k])) {
                            bad_sub++;
                            break;
                        }
                }
    }
    /* Every primitive touching a voxel (unpadded, exact test) is in its cell. */
    uint32_t *local_of = malloc(s->prim_count * sizeof *local_of);
    memset(local_of, 0xFF, s->prim_count * sizeof *local_of);
    for (uint32_t i = 0; i < v.prim_count; i++) local_of[v.prim_id[i]] = i;
    for (uint32_t p = 0; p < s->prim_count; p++) {
        uint32_t local = local_of[p];
        if (local == UINT32_MAX) continue; /* degenerate */
        int lo[3], hi[3];
        if (!grid_cell_range(v.frame, accel_prim_bounds(s, p), lo, hi)) continue;
        for (int z = lo[2]; z <= hi[2]; z++)
            for (int y = lo[1]; y <= hi[1]; y++)
                for (int x = lo[0]; x <= hi[0]; x++) {
                    const int idx[3] = {x, y, z};
                    double blo[3], bhi[3];
                    for (int a = 0; a < 3; a++) {
                        blo[a] = v.frame->planes[a][idx[a]];
                        bhi[a] = v.frame->planes[a][idx[a] + 1];
                    }
                    int touch = p < s->tri_count
                                    ? accel_overlap_tri_box(s->tris + 9 * (size_t)p, blo, bhi)
                                    : accel_overlap_sphere_surface_box(
                                          s->spheres + 4 * (size_t)(p - s->tri_count), blo, bhi);
                    if (!touch) continue;
                    const igrid_cell *w = &v.cells[igrid_lookup(v.map, v.top_res, v.shift, x, y, z)];
                    int miss = !sorted_find(v.refs + w->begin, w->end - w->begin, local);
                    if (miss && !bad_member)
                        test_note("%s: prim %u (local %u) touches voxel %d %d %d, cell %u [%d %d %d - %d %d %d] %u refs",
                                  spec, p, local, x, y, z, igrid_lookup(v.map, v.top_res, v.shift, x, y, z),
                                  w->lo[0], w->lo[1], w->lo[2], w->hi[0], w->hi[1], w->hi[2], w->end - w->begin);
                    bad_member += miss;
                }
    }
    free(local_of);
    CHECKF(!bad_box && !bad_sub && !bad_member && !bad_list,
           "%s on %s: %zu voxels outside their cell's exit box, %zu exit-box voxels not a subset, "
           "%zu missing memberships, %zu unsorted lists (%u cells)",
           spec, s->name, bad_box, bad_sub, bad_member, bad_list, v.cell_count);
    kind->destroy(accel);
}

static const char *const structure_specs[] = {
    "irregular_grid", "irregular_grid:merge=0", "irregular_grid:expand=0",
    "irregular_grid:subdivide=0", "irregular_grid:merge=0,expand=0",
    "irregular_grid:top_lambda=0.0001,max_depth=3,sub_lambda=1000",
    "irregular_grid:top_lambda=0.3,max_depth=4,sub_lambda=20,expand=6", NULL};

TEST(igrid_structure_invariants)
{
    accel_scene s[2];
    int ok0 = cluster_scene(&s[0], 0.0f), ok1 = lattice_scene(&s[1]);
    CHECK(ok0 && ok1);
    for (int k = 0; k < 2; k++) {
        if (!(k ? ok1 : ok0)) continue;
        for (const char *const *spec = structure_specs; *spec; spec++) check_structure(&s[k], *spec);
        scene_free(&s[k]);
    }
}

/* ---- answers against the reference -------------------------------------------------------- */

/* Every live primitive against every ray with the float kernels of prim.h:
 * on lattice-aligned rays the grid must give exactly these answers, since it
 * runs the same tests on a subset (any difference is a skipped cell). */
static void float_brute(const accel_scene *s, const accel_ray *rays, accel_hit *hits, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        if (accel_prep_ray(&rays[i], &p)) {
            float t = p.t_far, u = 0, v = 0;
            for (uint32_t k = 0; k < s->live_count; k++)
                if (accel_prim_hit(s, s->live[k], &p, &t, &u, &v, 0, s->sphere_count > 0))
                    h.t = t, h.u = u, h.v = v, h.prim = s->live[k];
        }
        hits[i] = h;
    }
}

static void check_answers(const accel_scene *s, const char *spec, const accel_ray *rays, size_t n,
                          const accel_hit *ref)
{
    const accel_kind *kind;
    accel_build_stats st;
    void *accel = build_or_fail(spec, s, &kind, &st);
    if (!accel) return;
    accel_hit *h = malloc(n * sizeof *h), *hc = malloc(n * sizeof *hc);
    uint8_t *occ = malloc(n);
    accel_counters c = {0};
    accel_trace(kind, accel, rays, h, n, 1, NULL);
    accel_trace(kind, accel, rays, hc, n, 2, &c);
    accel_trace_occluded(kind, accel, rays, occ, n, 1, NULL);
    hits_diff d = hits_compare(s, rays, ref, h, n);
    size_t occ_bad = 0;
    for (size_t i = 0; i < n; i++) occ_bad += occ[i] != (ref[i].prim != ACCEL_MISS);
    size_t i = d.first_bad == SIZE_MAX ? 0 : d.first_bad;
    CHECKF(d.holes + d.false_hits + d.disagreements + occ_bad == 0,
           "%s on %s: %zu holes, %zu false hits, %zu disagreements, %zu occluded mismatches of %zu; "
           "ray %zu o=(%.9g,%.9g,%.9g) d=(%.9g,%.9g,%.9g): ref %u@%.9g got %u@%.9g",
           spec, s->name, d.holes, d.false_hits, d.disagreements, occ_bad, n, i, rays[i].ox,
           rays[i].oy, rays[i].oz, rays[i].dx, rays[i].dy, rays[i].dz, ref[i].prim, ref[i].t,
           h[i].prim, h[i].t);
    CHECKF(memcmp(h, hc, n * sizeof *h) == 0, "%s on %s: counted run differs", spec, s->name);
    accel_error broken = {0};
    CHECKF(accel_counters_status(&c, &broken) == 0, "%s on %s: %s", spec, s->name, broken.msg);
    free(h);
    free(hc);
    free(occ);
    kind->destroy(accel);
}

/* Every listed variant, plus the specs given. */
static void check_all(const accel_scene *s, const accel_ray *rays, size_t n, const accel_hit *ref,
                      const char *const *extra)
{
    char spec[256];
    for (const char *const *v = accel_kind_irregular_grid.variants; *v; v++) {
        snprintf(spec, sizeof spec, "irregular_grid%s%s", **v ? ":" : "", *v);
        check_answers(s, spec, rays, n, ref);
    }
    for (const char *const *v = extra; v && *v; v++) check_answers(s, *v, rays, n, ref);
}

/* Rays from inside and outside the box, with finite and offset t ranges. */
static accel_ray *box_rays(const accel_scene *s, size_t n)
{
    accel_ray *r = malloc(n * sizeof *r);
    vec3 lo = s->bounds.min, e = box3_extent(s->bounds);
    for (size_t i = 0; i < n; i++) {
        float out = i % 3 == 0 ? 1.5f : 0.0f;
        vec3 o = v3_add(lo, v3_mul(e, v3(frange(-out, 1 + out), frange(-out, 1 + out),
                                         frange(-out, 1 + out))));
        vec3 t = v3_add(lo, v3_mul(e, v3(frand(), frand(), frand())));
        vec3 d = v3_sub(t, o);
        if (i % 7 == 0) d = v3(d.x, i % 2 ? 0.0f : -0.0f, d.z); /* a zero component */
        r[i] = mk_ray(o, d, i % 5 == 0 ? 0.3f : 0.0f, i % 4 == 0 ? 0.8f : INFINITY);
    }
    return r;
}

TEST(igrid_clusters_far_and_flat_against_reference)
{
    static const char *const extra[] = {
        "irregular_grid:top_lambda=1,max_depth=4,sub_lambda=20,expand=6",
        "irregular_grid:alpha=0,ct=0.1", "irregular_grid:ct=50", NULL};
    for (int k = 0; k < 3; k++) {
        accel_scene s;
        if (k < 2) {
            if (!cluster_scene(&s, k ? 1e5f : 0.0f)) continue;
        } else {
            /* A flat scene: every triangle in the plane z = 1. */
            scene_builder b = {0};
            accel_error err = {0};
            for (int i = 0; i < 500; i++) {
                vec3 p = v3(frange(0, 10), frange(0, 10), 1);
                scene_builder_add_tri(&b, p, v3_add(p, v3(frange(-1, 1), 0.3f, 0)),
                                      v3_add(p, v3(0.2f, frange(-1, 1), 0)), &err);
            }
            if (scene_finish(&b, "flat", &s, &err)) continue;
        }
        rng = 1234 + (uint64_t)k;
        size_t n = 3000;
        accel_ray *rays = box_rays(&s, n);
        accel_hit *ref = malloc(n * sizeof *ref);
        accel_reference_trace(&s, rays, ref, n, 2);
        check_all(&s, rays, n, ref, extra);
        free(ref);
        free(rays);
        scene_free(&s);
    }
}

/* Rays along the voxel lattice: through corners and along edges and faces,
 * with +0 and -0 components, from lattice points. */
TEST(igrid_lattice_edges_corners)
{
    accel_scene s;
    if (!lattice_scene(&s)) return;
    size_t n = 6000, k = 0;
    accel_ray *rays = malloc(n * sizeof *rays);
    rng = 55;
    while (k < n) {
        vec3 o = v3(0.5f * (int)(frand() * 9), 0.5f * (int)(frand() * 9), 0.5f * (int)(frand() * 9));
        float d[3] = {frand() < 0.5f ? 1.0f : -1.0f, frand() < 0.5f ? 1.0f : -1.0f,
                      frand() < 0.5f ? 1.0f : -1.0f};
        int zero = (int)(frand() * 4); /* 3: none */
        if (zero < 3) d[zero] = frand() < 0.5f ? 0.0f : -0.0f;
        if (k % 3 == 0) d[(zero + 1) % 3] *= 2.0f; /* through edges, not only diagonals */
        vec3 back = v3_scale(v3(d[0], d[1], d[2]), k % 2 ? 3.0f : 0.0f);
        rays[k++] = mk_ray(v3_sub(o, back), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
    }
    accel_hit *ref = malloc(n * sizeof *ref);
    float_brute(&s, rays, ref, n);
    static const char *const extra[] = {
        "irregular_grid:top_lambda=0.0001,max_depth=3,sub_lambda=1000",
        "irregular_grid:top_lambda=0.0001,max_depth=3,sub_lambda=1000,merge=0",
        "irregular_grid:top_lambda=0.0001,max_depth=3,sub_lambda=1000,expand=0",
        "irregular_grid:top_lambda=0.01,max_depth=2,sub_lambda=1000", NULL};
    check_all(&s, rays, n, ref, extra);
    free(ref);
    free(rays);
    scene_free(&s);
}

/* ---- what each step buys, refusals, threads ------------------------------------------------- */

typedef struct {
    accel_counters c;
    uint64_t cells;
} run_stats;

static int run(const accel_scene *s, const char *spec, const accel_ray *rays, size_t n,
               run_stats *out)
{
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    accel_error err = {0};
    if (accel_build_spec(spec, s, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s: %s", spec, err.msg);
        return 0;
    }
    accel_hit *h = malloc(n * sizeof *h);
    memset(&out->c, 0, sizeof out->c);
    accel_trace(kind, accel, rays, h, n, 1, &out->c);
    out->cells = st.nodes;
    free(h);
    kind->destroy(accel);
    return 1;
}

TEST(igrid_steps_what_each_step_buys)
{
    accel_scene s;
    if (!cluster_scene(&s, 0.0f)) return;
    rng = 31337;
    size_t n = 4000;
    accel_ray *rays = box_rays(&s, n);
    run_stats top, sub, merged, expanded;
    if (run(&s, "irregular_grid:subdivide=0,merge=0,expand=0", rays, n, &top) &&
        run(&s, "irregular_grid:merge=0,expand=0", rays, n, &sub) &&
        run(&s, "irregular_grid:expand=0", rays, n, &merged) &&
        run(&s, "irregular_grid", rays, n, &expanded)) {
        /* Subdivision: fewer primitive tests than the coarse top grid. */
        CHECKF(sub.c.prim_tests * 2 < top.c.prim_tests, "subdivision: %llu tests, top grid %llu",
               (unsigned long long)sub.c.prim_tests, (unsigned long long)top.c.prim_tests);
        /* Merge: fewer cells and fewer steps. */
        CHECKF(merged.cells * 4 < sub.cells * 3 && merged.c.steps < sub.c.steps,
               "merge: %llu cells and %llu steps, before %llu and %llu",
               (unsigned long long)merged.cells, (unsigned long long)merged.c.steps,
               (unsigned long long)sub.cells, (unsigned long long)sub.c.steps);
        /* Expansion: same cells, fewer steps, no more tests. */
        CHECKF(expanded.cells == merged.cells && expanded.c.steps < merged.c.steps &&
                   expanded.c.prim_tests <= merged.c.prim_tests,
               "expansion: %llu steps and %llu tests, before %llu and %llu",
               (unsigned long long)expanded.c.steps, (unsigned long long)expanded.c.prim_tests,
               (unsigned long long)merged.c.steps, (unsigned long long)merged.c.prim_tests);
    }
    free(rays);
    scene_free(&s);
}

TEST(igrid_refusals_and_threads)
{
    accel_scene s;
    if (!cluster_scene(&s, 0.0f)) return;
    const accel_kind *kind;
    void *a1, *a2;
    accel_build_stats st;
    accel_error err = {0};
    int rc = test_build_rc("irregular_grid:max_depth=8,sub_lambda=1000,max_mb=1", &s, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "max_mb"), "deep octrees in 1 MiB: rc %d, %s",
           rc, err.msg);
    rc = test_build_rc("irregular_grid:top_lambda=100,max_mb=1", &s, &err);
    CHECKF(rc == ACCEL_ERR_RANGE, "fine top grid in 1 MiB: rc %d, %s", rc, err.msg);
    static const char *const specs[] = {"irregular_grid", "irregular_grid:top_lambda=1,expand=6"};
    for (int k = 0; k < 2; k++) {
        if (accel_build_spec(specs[k], &s, 1, &kind, &a1, &st, &err) ||
            accel_build_spec(specs[k], &s, 2, &kind, &a2, &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[k], err.msg);
            continue;
        }
        igrid_view v1, v2;
        igrid_get_view(a1, &v1);
        igrid_get_view(a2, &v2);
        CHECKF(v1.cell_count == v2.cell_count && v1.map_len == v2.map_len &&
                   v1.ref_count == v2.ref_count &&
                   !memcmp(v1.cells, v2.cells, v1.cell_count * sizeof *v1.cells) &&
                   !memcmp(v1.map, v2.map, v1.map_len * sizeof *v1.map) &&
                   !memcmp(v1.refs, v2.refs, v1.ref_count * sizeof *v1.refs),
               "%s: 1 and 2 threads build different structures", specs[k]);
        kind->destroy(a1);
        kind->destroy(a2);
    }
    scene_free(&s);
}

/* Paper-thin meshes: a sphere flattened to 1e-20 (and thinner, down to
 * subnormal) along one axis, seen from its camera. The octree splits the
 * thin axis into voxels far thinner than the rounding of plane - origin, so
 * the walk meets runs of planes at one and the same distance; it must visit
 * every voxel of such a run (it used to start past them: 289 holes of
 * 1024 at 32x32). Primary, shadow and diffuse rays against the reference. */
TEST(igrid_paper_thin_against_reference)
{
    static const char *const scales[] = {"1 1 1e-20", "1 1e-20 1", "1e-30 1 1", "1 1 1e-40",
                                         "1e-3 1e-3 1e-23", NULL};
    for (const char *const *sc = scales; *sc; sc++) {
        char text[128];
        int len = snprintf(text, sizeof text, "mesh s sphere:segments=8\ninstance s scale %s\n", *sc);
        accel_scene s;
        accel_error err = {0};
        if (scene_parse_scene("thin", "", text, (size_t)len, NULL, &s, &err)) {
            test_fail(__FILE__, __LINE__, "scale %s: %s", *sc, err.msg);
            continue;
        }
        rays_set prim = {0}, shadow = {0}, diffuse = {0};
        accel_hit *ref = NULL;
        int ok = rays_primary(&s.camera, 32, 32, &prim, &err) == 0;
        if (ok) {
            ref = malloc(prim.count * sizeof *ref);
            ok = ref != NULL;
        }
        if (ok) {
            accel_reference_trace(&s, prim.rays, ref, prim.count, 1);
            ok = rays_shadow(&s, &prim, ref, &shadow, &err) == 0 &&
                 rays_diffuse(&s, &prim, ref, 1, &diffuse, &err) == 0;
        }
        CHECKF(ok, "scale %s: rays: %s", *sc, err.msg);
        const rays_set *sets[3] = {&prim, &shadow, &diffuse};
        for (int k = 0; k < 3 && ok; k++) {
            accel_hit *r = malloc(sets[k]->count * sizeof *r);
            if (!r) break;
            accel_reference_trace(&s, sets[k]->rays, r, sets[k]->count, 1);
            check_answers(&s, "irregular_grid", sets[k]->rays, sets[k]->count, r);
            check_answers(&s, "irregular_grid:merge=0,expand=0", sets[k]->rays, sets[k]->count, r);
            check_answers(&s, "irregular_grid:cells=blocks", sets[k]->rays, sets[k]->count, r);
            free(r);
        }
        free(ref);
        rays_free(&prim);
        rays_free(&shadow);
        rays_free(&diffuse);
        scene_free(&s);
    }
}

/* Builds spec on s, which must succeed within the spec's max_mb and stay
 * below max_bytes and max_cells; then answers against the reference. */
static void check_small(const accel_scene *s, const char *spec, size_t max_bytes,
                        uint64_t max_cells)
{
    const accel_kind *kind;
    accel_build_stats st;
    void *accel = build_or_fail(spec, s, &kind, &st);
    if (!accel) return;
    CHECKF(st.bytes < max_bytes && st.nodes <= max_cells,
           "%s on %s: %zu bytes, %llu cells (expected below %zu bytes, at most %llu cells)", spec,
           s->name, (size_t)st.bytes, (unsigned long long)st.nodes, max_bytes,
           (unsigned long long)max_cells);
    kind->destroy(accel);
    rng = 4242;
    size_t n = 600;
    accel_ray *rays = box_rays(s, n);
    accel_hit *ref = malloc(n * sizeof *ref);
    accel_reference_trace(s, rays, ref, n, 1);
    check_answers(s, spec, rays, n, ref);
    free(ref);
    free(rays);
}

/* 1000 near copies of one triangle, every vertex moved by up to 1e-6 so
 * that no two are coincident (seeded: the same scene each time). */
static int near_copies(accel_scene *s)
{
    scene_builder near = {0};
    test_seed(77);
    for (int i = 0; i < 1000; i++) {
        vec3 v[3] = {v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)};
        for (int k = 0; k < 3; k++)
            v[k] = v3_add(v[k], v3(test_rand_in(-1e-6f, 1e-6f), test_rand_in(-1e-6f, 1e-6f),
                                   test_rand_in(-1e-6f, 1e-6f)));
        test_add_tri(&near, v[0], v[1], v[2]);
    }
    return test_finish(&near, "1000 near copies", s);
}

/* The nested grid on the same 1000 near copies (here for check_small):
 * every top cell holds all of them, and each cell's sub-grid copied them
 * into most of its cells, then was dropped (more than 8 copies per
 * primitive). Planned sub-grids whose first primitives' boxes span many of
 * their cells now get an exact count that stops at that limit
 * (ngrid_level.c, plan_sub), so they are dropped before building: 22 s
 * before, 0.5 s now (with tracing and --check), with the same
 * structure; and the memory check no longer counts them, so a small max_mb
 * builds where it was refused ("16.9 MiB on top of 4.1 MiB"). */
TEST(igrid_near_copies_ngrid_drops_subgrids_before_building)
{
    accel_scene s;
    if (near_copies(&s)) {
        check_small(&s, "nested_grid:max_mb=8", 8u << 20, 4096);
        scene_free(&s);
    }
}

/* The same stack in auto mode: the cost model priced each top cell's
 * sub-grid of 250 cells, every one holding all 1000 copies, as a small gain
 * over the leaf, and built them all (over 10 minutes, gigabytes). Now a
 * candidate with more than 128 references per primitive is not priced
 * (NGRID_AUTO_MAX_COPIES): 23 MB, a few seconds. Before, max_mb=64 refused
 * the build after 26 s ("level 1 sub-grids need 1388.0 MiB"). */
TEST(igrid_near_copies_ngrid_auto_stays_bounded)
{
    accel_scene s;
    if (near_copies(&s)) {
        check_small(&s, "nested_grid:auto=1,max_mb=64", 32u << 20, 2000000);
        scene_free(&s);
    }
}

/* Coincident copies and needles: 1000 copies of one triangle (a mesh's
 * duplicate faces), 100 instances of a sphere placed over each other, and a
 * sphere stretched 3000 times along y. The subdivision used to take the
 * copies for a dense cluster and split every node they touch down to the
 * depth their count asks for (1000 copies: over 30 s and 575 MB; 30
 * instances: 34 s, 213 MB), and to refine a needle's short axes as finely as
 * its long one (3000x: 59k cells, 17 MB, 245 MB during the build). Each
 * build must now fit a small max_mb and stay small; so must 1000 near
 * copies, no two coincident. */
TEST(igrid_copies_and_needles_stay_small)
{
    scene_builder b = {0};
    accel_scene s;
    for (int i = 0; i < 1000; i++) test_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0));
    if (test_finish(&b, "1000 copies", &s)) {
        check_small(&s, "irregular_grid:max_mb=16", 1 << 20, 64);
        scene_free(&s);
    }
    /* Near copies: every vertex moved by up to 1e-6, so that no two are
     * coincident (158 s and 898 MB before the guard on large nodes above
     * the paper's depth, IGRID_MUST_GUARD_MIN). */
    if (near_copies(&s)) {
        check_small(&s, "irregular_grid:max_mb=16", 1 << 20, 2000);
        scene_free(&s);
    }
    static const char *const texts[] = {NULL, "mesh s sphere:segments=8\ninstance s scale 1 3e3 1\n"};
    char inst[2048];
    int len = snprintf(inst, sizeof inst, "mesh s sphere:segments=8\n");
    for (int i = 0; i < 100; i++) len += snprintf(inst + len, sizeof inst - (size_t)len, "instance s\n");
    for (int k = 0; k < 2; k++) {
        const char *text = k ? texts[1] : inst;
        accel_error err = {0};
        if (scene_parse_scene(k ? "needle" : "100 instances", "", text, strlen(text), NULL, &s,
                              &err)) {
            test_fail(__FILE__, __LINE__, "%s", err.msg);
            continue;
        }
        if (k == 0)
            check_small(&s, "irregular_grid:max_mb=32", 16u << 20, 20000);
        else
            check_small(&s, "irregular_grid:max_mb=64", 8u << 20, 20000);
        scene_free(&s);
    }
}
