/*
 * test_nested_grid.c - nested-grid tests: parameters and refusals, the
 * structure it builds (depth 1 is the regular grid; dense clusters get
 * sub-grids; useless sub-grids are not kept), the cost model against a
 * Monte Carlo estimate, auto mode's response to its costs, the hierarchical
 * walk against the reference (cluster, lattice with sub-cells aligned to the
 * rays, flat, far, tiny and empty scenes, rays from inside, axis-parallel
 * rays with +0/-0 components), per-level counters, the cross-level mailbox,
 * and identical builds for any thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nested_grid/ngrid.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "test.h"

/* ---- helpers ------------------------------------------------------------------ */

static uint64_t seed_state = 0x2545F4914F6CDD1Dull;
static float rnd(void)
{
    seed_state ^= seed_state >> 12;
    seed_state ^= seed_state << 25;
    seed_state ^= seed_state >> 27;
    return (float)((seed_state * 0x2545F4914F6CDD1Dull) >> 40) / 16777216.0f;
}
static float rnd_in(float lo, float hi) { return lo + (hi - lo) * rnd(); }

static accel_ray ray_of(vec3 o, vec3 d, float t_near, float t_far)
{
    accel_ray r = {o.x, o.y, o.z, t_near, d.x, d.y, d.z, t_far};
    return r;
}

static vec3 rnd_point(box3 b)
{
    return v3(rnd_in(b.min.x, b.max.x), rnd_in(b.min.y, b.max.y), rnd_in(b.min.z, b.max.z));
}

static void add_small_tri(scene_builder *b, vec3 c, float size)
{
    accel_error err = {0};
    vec3 p[3];
    for (int k = 0; k < 3; k++)
        p[k] = v3_add(c, v3(rnd_in(-size, size), rnd_in(-size, size), rnd_in(-size, size)));
    scene_builder_add_tri(b, p[0], p[1], p[2], &err);
}

static int finish_scene(scene_builder *b, const char *name, accel_scene *s)
{
    accel_error err = {0};
    int rc = scene_finish(b, name, s, &err);
    CHECKF(rc == 0, "scene %s: %s", name, err.msg);
    return rc == 0;
}

/*
 * A dense cluster in a sparse scene: `cluster` small triangles in the unit
 * cube at (50,50,50) and 300 large ones spread over [0,100]^3 (the teapot in
 * a stadium, in miniature), plus `spheres` spheres in the cluster.
 */
static int cluster_scene(accel_scene *s, int cluster, int spheres)
{
    scene_builder b = {0};
    accel_error err = {0};
    seed_state = 1234567;
    box3 all = {{0, 0, 0}, {100, 100, 100}};
    box3 dense = {{50, 50, 50}, {51, 51, 51}};
    for (int i = 0; i < 300; i++) add_small_tri(&b, rnd_point(all), 6.0f);
    for (int i = 0; i < cluster; i++) add_small_tri(&b, rnd_point(dense), 0.02f);
    for (int i = 0; i < spheres; i++)
        scene_builder_add_sphere(&b, rnd_point(dense), rnd_in(0.001f, 0.03f), &err);
    return finish_scene(&b, "cluster", s);
}

/* Rays for the cluster scene: from outside towards the cluster, from inside
 * it in every direction (some with finite t ranges), and axis-parallel ones
 * through it with +0/-0 in the other components. */
static accel_ray *cluster_rays(size_t *n)
{
    size_t cap = 6000, k = 0;
    accel_ray *r = malloc(cap * sizeof *r);
    if (!r) return NULL;
    seed_state = 99;
    box3 around = {{-20, -20, -20}, {120, 120, 120}};
    box3 dense = {{50, 50, 50}, {51, 51, 51}};
    for (int i = 0; i < 2500; i++) {
        vec3 o = rnd_point(around), t = rnd_point(dense);
        r[k++] = ray_of(o, v3_sub(t, o), 0.0f, INFINITY);
    }
    for (int i = 0; i < 2000; i++) {
        vec3 o = rnd_point(dense);
        vec3 d = v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1));
        r[k++] = ray_of(o, d, i % 3 == 0 ? 0.01f : 0.0f, i % 2 ? 0.3f : INFINITY);
    }
    for (int i = 0; i < 1200; i++) {
        int axis = i % 3;
        vec3 o = rnd_point(dense);
        float c[3] = {o.x, o.y, o.z}, d[3];
        c[axis] = (i & 8) ? 120.0f : -20.0f;
        for (int a = 0; a < 3; a++) d[a] = (i & 16) ? -0.0f : 0.0f;
        d[axis] = (i & 8) ? -1.0f : 1.0f;
        r[k++] = ray_of(v3(c[0], c[1], c[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
    }
    *n = k;
    return r;
}

/* The oracle's hits: the double-precision reference, or the float brute
 * force when brute (the same float kernel without any structure). */
static accel_hit *oracle_hits(const accel_scene *s, const accel_ray *rays, size_t n, int brute)
{
    accel_hit *ref = malloc((n + 1) * sizeof *ref);
    if (!ref) return NULL;
    if (brute) {
        const accel_kind *bk;
        void *ba;
        accel_build_stats bst;
        accel_error err = {0};
        if (accel_build_spec("brute", s, 1, &bk, &ba, &bst, &err)) {
            free(ref);
            return NULL;
        }
        accel_trace(bk, ba, rays, ref, n, 2, NULL);
        bk->destroy(ba);
    } else {
        accel_reference_trace(s, rays, ref, n, 2);
    }
    return ref;
}

/*
 * Builds spec on s and traces the rays: closest hits against the oracle's
 * ref (FORMATS.md rule: zero holes, false hits, disagreements), occluded
 * against its hit/miss, counted against uncounted, level counters against
 * the total. Returns the number of bad rays; *stats gets the build's stats
 * and *cnt the counters (either may be NULL).
 */
static size_t check_against(const accel_scene *s, const char *spec, const accel_ray *rays,
                            size_t n, const accel_hit *ref, accel_build_stats *stats,
                            accel_counters *cnt)
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
    accel_hit *hits = malloc((n + 1) * sizeof *hits), *hits_c = malloc((n + 1) * sizeof *hits_c);
    uint8_t *occ = malloc(n + 1);
    if (!ref || !hits || !hits_c || !occ) {
        test_fail(__FILE__, __LINE__, "out of memory");
        free(hits);
        free(hits_c);
        free(occ);
        kind->destroy(accel);
        return n;
    }
    accel_counters c;
    memset(&c, 0, sizeof c);
    accel_trace(kind, accel, rays, hits, n, 1, NULL);
    accel_trace(kind, accel, rays, hits_c, n, 1, &c);
    accel_trace_occluded(kind, accel, rays, occ, n, 1, NULL);
    hits_diff d = hits_compare(ref, hits, n);
    size_t occ_bad = 0, first_occ = SIZE_MAX;
    for (size_t i = 0; i < n; i++)
        if (occ[i] != (ref[i].prim != ACCEL_MISS)) {
            occ_bad++;
            if (first_occ == SIZE_MAX) first_occ = i;
        }
    size_t bad = d.holes + d.false_hits + d.disagreements + occ_bad;
    if (bad) {
        size_t i = d.first_bad != SIZE_MAX ? d.first_bad : first_occ;
        const accel_ray *r = &rays[i];
        test_fail(__FILE__, __LINE__,
                  "%s on %s: %zu holes, %zu false hits, %zu disagreements, %zu occluded "
                  "mismatches of %zu; ray %zu o=(%.9g,%.9g,%.9g) d=(%.9g,%.9g,%.9g) t=[%g,%g] "
                  "ref %u@%.9g got %u@%.9g occ %d",
                  spec, s->name, d.holes, d.false_hits, d.disagreements, occ_bad, n, i, r->ox,
                  r->oy, r->oz, r->dx, r->dy, r->dz, r->t_near, r->t_far, ref[i].prim, ref[i].t,
                  hits[i].prim, hits[i].t, occ[i]);
    }
    CHECKF(memcmp(hits, hits_c, n * sizeof *hits) == 0, "%s on %s: counted and uncounted differ",
           spec, s->name);
    uint64_t level_sum = c.level_steps[0] + c.level_steps[1] + c.level_steps[2] + c.level_steps[3];
    CHECKF(c.rays == n && level_sum == c.steps && c.empty_steps <= c.steps,
           "%s on %s: counters: %llu rays of %zu, %llu steps but %llu summed over levels, %llu "
           "empty", spec, s->name, (unsigned long long)c.rays, n, (unsigned long long)c.steps,
           (unsigned long long)level_sum, (unsigned long long)c.empty_steps);
    if (cnt) *cnt = c;
    kind->destroy(accel);
    free(hits);
    free(hits_c);
    free(occ);
    return bad;
}

/* check_against with the double-precision reference as the oracle. */
static size_t check_spec(const accel_scene *s, const char *spec, const accel_ray *rays, size_t n,
                         accel_build_stats *stats, accel_counters *cnt)
{
    accel_hit *ref = oracle_hits(s, rays, n, 0);
    size_t bad = check_against(s, spec, rays, n, ref, stats, cnt);
    free(ref);
    return bad;
}

/* Every listed variant (the conformance set) plus extra specs, against
 * the reference or (brute_oracle) the float brute force. */
static void check_variants(const accel_scene *s, const accel_ray *rays, size_t n,
                           const char *const *extra, int brute_oracle)
{
    char spec[256];
    accel_hit *ref = oracle_hits(s, rays, n, brute_oracle);
    CHECK(ref != NULL);
    if (!ref) return;
    for (const char *const *v = accel_kind_nested_grid.variants; *v; v++) {
        snprintf(spec, sizeof spec, "nested_grid%s%s", **v ? ":" : "", *v);
        check_against(s, spec, rays, n, ref, NULL, NULL);
    }
    for (const char *const *v = extra; v && *v; v++) {
        snprintf(spec, sizeof spec, "nested_grid:%s", *v);
        check_against(s, spec, rays, n, ref, NULL, NULL);
    }
    free(ref);
}

static int build(const char *spec, const accel_scene *s, int threads, void **accel,
                 accel_build_stats *st, accel_error *err)
{
    const accel_kind *kind;
    return accel_build_spec(spec, s, threads, &kind, accel, st, err);
}

/* ---- parameters and refusals ------------------------------------------------------ */

TEST(ngrid_params_refused)
{
    accel_scene s;
    if (!cluster_scene(&s, 500, 0)) return;
    accel_error err = {0};
    void *a;
    accel_build_stats st;
    static const char *const bad[] = {
        "nested_grid:depth=0",     "nested_grid:depth=5",       "nested_grid:threshold=-1",
        "nested_grid:sub_res=1",   "nested_grid:sub_res=300",   "nested_grid:res=5x6",
        "nested_grid:overlap=sat", "nested_grid:lambda=0",      "nested_grid:c_step=0",
        "nested_grid:colour=red",  "nested_grid:threshold=1.5", "nested_grid:auto=maybe",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err.msg[0] = 0;
        int rc = build(bad[i], &s, 1, &a, &st, &err);
        CHECKF(rc == ACCEL_ERR_SPEC || rc == ACCEL_ERR_RANGE, "%s accepted (rc %d)", bad[i], rc);
        CHECKF(rc == 0 || strstr(err.msg, "nested_grid"), "%s: message '%s' does not name the kind",
               bad[i], err.msg);
        if (rc == 0) accel_kind_nested_grid.destroy(a);
    }
    /* Memory limit: the top level alone, then the sub-grids of the cluster. */
    err.msg[0] = 0;
    CHECK(build("nested_grid:res=1024,max_mb=16", &s, 1, &a, &st, &err) == ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "MiB") != NULL, "message: %s", err.msg);
    err.msg[0] = 0;
    int rc = build("nested_grid:threshold=0,sub_res=256,max_mb=64", &s, 1, &a, &st, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "sub-grid") && strstr(err.msg, "max_mb"),
           "sub-grids over the limit: rc %d, '%s'", rc, err.msg);
    if (rc == 0) accel_kind_nested_grid.destroy(a);
    /* Same with 2 threads: the same refusal. */
    char first[sizeof err.msg];
    snprintf(first, sizeof first, "%s", err.msg);
    rc = build("nested_grid:threshold=0,sub_res=256,max_mb=64", &s, 2, &a, &st, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && !strcmp(first, err.msg), "2 threads: rc %d, '%s' vs '%s'", rc,
           err.msg, first);
    if (rc == 0) accel_kind_nested_grid.destroy(a);
    scene_free(&s);
}

/* ---- structure ------------------------------------------------------------------- */

TEST(ngrid_depth1_is_the_regular_grid)
{
    accel_scene s;
    if (!cluster_scene(&s, 3000, 0)) return;
    static const char *const lambdas[] = {"0.5", "3", "20"};
    for (int i = 0; i < 3; i++) {
        char ns[64], gs[64];
        snprintf(ns, sizeof ns, "nested_grid:depth=1,lambda=%s", lambdas[i]);
        snprintf(gs, sizeof gs, "grid:lambda=%s", lambdas[i]);
        accel_error err = {0};
        void *a, *b;
        accel_build_stats sa, sb;
        const accel_kind *kb;
        if (build(ns, &s, 1, &a, &sa, &err) || accel_build_spec(gs, &s, 1, &kb, &b, &sb, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", ns, err.msg);
            continue;
        }
        CHECKF(sa.depth == 1 && sa.res[0] == sb.res[0] && sa.res[1] == sb.res[1] &&
                   sa.res[2] == sb.res[2] && sa.nodes == sb.nodes && sa.refs == sb.refs &&
                   sa.leaves == sb.leaves,
               "%s: %dx%dx%d, %llu cells, %llu refs, %llu leaves; grid: %dx%dx%d, %llu, %llu, %llu",
               ns, sa.res[0], sa.res[1], sa.res[2], (unsigned long long)sa.nodes,
               (unsigned long long)sa.refs, (unsigned long long)sa.leaves, sb.res[0], sb.res[1],
               sb.res[2], (unsigned long long)sb.nodes, (unsigned long long)sb.refs,
               (unsigned long long)sb.leaves);
        accel_kind_nested_grid.destroy(a);
        kb->destroy(b);
    }
    scene_free(&s);
}

TEST(ngrid_cluster_gets_subgrids)
{
    accel_scene s;
    if (!cluster_scene(&s, 20000, 0)) return;
    size_t n;
    accel_ray *rays = cluster_rays(&n);
    if (!rays) return;
    accel_build_stats flat, deep;
    accel_counters cf, cd;
    const size_t m = 600; /* rays from outside into the cluster */
    check_spec(&s, "nested_grid:depth=1", rays, m, &flat, &cf);
    check_spec(&s, "nested_grid", rays, m, &deep, &cd);
    CHECKF(deep.depth == NGRID_DEFAULT_DEPTH, "default depth %d", deep.depth);
    CHECKF(cd.level_steps[1] > 0 && cd.level_steps[2] > 0, "levels 1, 2: %llu, %llu steps",
           (unsigned long long)cd.level_steps[1], (unsigned long long)cd.level_steps[2]);
    /* The cluster sits in one top cell: a flat grid tests most of it per ray. */
    CHECKF(cf.prim_tests > 1000 * (uint64_t)m && cd.prim_tests * 50 < cf.prim_tests,
           "primitive tests per ray: %.1f flat, %.1f nested", cf.prim_tests / (double)m,
           cd.prim_tests / (double)m);
    /* Each level holds the cluster at a finer resolution. */
    void *a;
    accel_error err = {0};
    if (build("nested_grid:depth=4,threshold=4", &s, 1, &a, &deep, &err) == 0) {
        ngrid_view v;
        ngrid_get_view(a, &v);
        CHECK(v.levels == 4 && v.nodes[0].level == 0);
        double cell[4] = {0};
        for (uint32_t i = 0; i < v.node_count; i++) {
            const grid_frame *f = &v.nodes[i].frame;
            double c = ((double)f->hi[0] - f->lo[0]) / f->res[0];
            uint32_t l = v.nodes[i].level;
            CHECKF(i == 0 || v.nodes[i].level >= v.nodes[i - 1].level, "not breadth-first");
            if (cell[l] == 0 || c < cell[l]) cell[l] = c;
        }
        CHECKF(cell[1] < cell[0] / 2 && cell[2] < cell[1] / 2 && cell[3] < cell[2] / 2,
               "finest cells per level: %g %g %g %g", cell[0], cell[1], cell[2], cell[3]);
        accel_kind_nested_grid.destroy(a);
    } else {
        test_fail(__FILE__, __LINE__, "depth=4: %s", err.msg);
    }
    /* Subdivision never kicks in with a huge threshold. */
    if (build("nested_grid:threshold=100000", &s, 1, &a, &deep, &err) == 0) {
        CHECK(deep.depth == 1 && deep.nodes == flat.nodes);
        accel_kind_nested_grid.destroy(a);
    }
    free(rays);
    scene_free(&s);
}

/* Large triangles all through the centre of their bounds: a 2x2x2
 * sub-grid each cell of which holds all of them separates nothing and is
 * not kept. */
TEST(ngrid_useless_subgrid_dropped)
{
    scene_builder b = {0};
    accel_error err = {0};
    seed_state = 8;
    vec3 c = v3(0.5f, 0.5f, 0.5f);
    for (int i = 0; i < 20; i++) {
        vec3 u = v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1));
        vec3 w = v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1));
        vec3 uw = v3_add(u, w);
        /* The triangle and its reflection through c: both contain c, and
         * together their bounds are centred on it. */
        scene_builder_add_tri(&b, v3_add(c, u), v3_add(c, w), v3_sub(c, uw), &err);
        scene_builder_add_tri(&b, v3_sub(c, u), v3_sub(c, w), v3_add(c, uw), &err);
    }
    accel_scene s;
    if (!finish_scene(&b, "star", &s)) return;
    void *a;
    accel_build_stats st;
    if (build("nested_grid:res=1,sub_res=2,threshold=4", &s, 1, &a, &st, &err) == 0) {
        CHECKF(st.depth == 1 && st.nodes == 1, "depth %d, %llu cells", st.depth,
               (unsigned long long)st.nodes);
        accel_kind_nested_grid.destroy(a);
    } else {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
    }
    /* With sub_res=3 the centre lies inside the middle cell only: kept. */
    if (build("nested_grid:res=1,sub_res=3,threshold=4,depth=2", &s, 1, &a, &st, &err) == 0) {
        CHECKF(st.depth == 2 && st.nodes == 28, "depth %d, %llu cells", st.depth,
               (unsigned long long)st.nodes);
        accel_kind_nested_grid.destroy(a);
    }
    scene_free(&s);
}

/* ---- the cost model ------------------------------------------------------------------ */

/* Isotropic random lines crossing a box: the entry point is uniform over
 * the surface and the direction cosine-distributed about the inward normal.
 * The mean number of cells the DDA visits must match ngrid_expected_cells,
 * and the fraction of lines crossing a sub-box its area ratio. */
TEST(ngrid_cost_model_matches_random_lines)
{
    static const int shapes[][3] = {{8, 8, 8}, {20, 3, 7}, {1, 1, 30}};
    const float ext[3] = {2.0f, 1.0f, 3.0f};
    for (int k = 0; k < 3; k++) {
        box3 box = {{0, 0, 0}, {ext[0], ext[1], ext[2]}};
        float planes[64];
        grid_frame f;
        grid_frame_init(&f, box, shapes[k], planes);
        double area[3] = {ext[1] * ext[2], ext[2] * ext[0], ext[0] * ext[1]};
        double total = area[0] + area[1] + area[2];
        box3 inner = {{0.5f, 0.2f, 1.0f}, {1.0f, 0.6f, 2.5f}};
        double inner_ratio = (0.5 * 0.4 + 0.4 * 1.5 + 1.5 * 0.5) / total;
        seed_state = 777 + k;
        const int lines = 40000;
        double cells = 0;
        int through_inner = 0;
        for (int i = 0; i < lines; i++) {
            double pick = rnd() * total;
            int axis = pick < area[0] ? 0 : (pick < area[0] + area[1] ? 1 : 2);
            int side = rnd() < 0.5f;
            float o[3] = {rnd() * ext[0], rnd() * ext[1], rnd() * ext[2]};
            o[axis] = side ? ext[axis] : 0.0f;
            /* Cosine-weighted about the inward normal (Malley's method). */
            float r = sqrtf(rnd()), phi = 6.2831853f * rnd();
            float d[3];
            int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            d[a1] = r * cosf(phi);
            d[a2] = r * sinf(phi);
            d[axis] = sqrtf(fmaxf(0.0f, 1.0f - r * r)) * (side ? -1.0f : 1.0f);
            if (d[axis] == 0.0f) continue;
            accel_ray ray = {o[0], o[1], o[2], 0.0f, d[0], d[1], d[2], INFINITY};
            accel_ray_prep p;
            if (!accel_prep_ray(&ray, &p)) continue;
            grid_dda dda;
            grid_dda_init(&dda, &f, &p, 0.0);
            int count = 1;
            while (grid_dda_step(&dda)) count++;
            cells += count;
            float t0;
            through_inner += box3_slab(&inner.min.x, &inner.max.x, p.org, p.inv_dir, p.neg, 0.0f,
                                       INFINITY, &t0);
        }
        double measured = cells / lines, predicted = ngrid_expected_cells(&f);
        CHECKF(fabs(measured - predicted) < 0.02 * predicted,
               "%dx%dx%d: %.3f cells crossed on average, model %.3f", shapes[k][0], shapes[k][1],
               shapes[k][2], measured, predicted);
        double frac = (double)through_inner / lines;
        CHECKF(fabs(frac - inner_ratio) < 0.02, "sub-box crossed by %.3f of the lines, model %.3f",
               frac, inner_ratio);
        double cell_p = ngrid_cell_probability(&f);
        double cx = (double)ext[0] / shapes[k][0], cy = (double)ext[1] / shapes[k][1];
        double cz = (double)ext[2] / shapes[k][2], want = (cx * cy + cy * cz + cz * cx) / total;
        CHECKF(fabs(cell_p - want) < 1e-9 * want, "cell probability %g, want %g", cell_p, want);
    }
    int cube[3] = {5, 6, 7};
    box3 unit = {{0, 0, 0}, {1, 1, 1}};
    float planes[32];
    grid_frame f;
    grid_frame_init(&f, unit, cube, planes);
    CHECKF(fabs(ngrid_expected_cells(&f) - 6.0) < 1e-9, "cube: (5+6+7)/3 = 6, got %g",
           ngrid_expected_cells(&f));
}

/* Auto mode follows its costs: cheap tests never subdivide, cheap steps do. */
TEST(ngrid_auto_follows_costs)
{
    accel_scene s;
    if (!cluster_scene(&s, 4000, 0)) return;
    accel_error err = {0};
    void *a;
    accel_build_stats cheap_tests, cheap_steps, dflt;
    int ok = build("nested_grid:auto,c_step=100,c_isect=0.01", &s, 1, &a, &cheap_tests, &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    ok = build("nested_grid:auto,c_step=0.01,c_isect=100", &s, 1, &a, &cheap_steps, &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    ok = build("nested_grid:auto", &s, 1, &a, &dflt, &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    CHECKF(cheap_tests.depth == 1 && cheap_steps.depth >= 2 && dflt.depth >= 2,
           "depths: cheap tests %d, cheap steps %d, default %d", cheap_tests.depth,
           cheap_steps.depth, dflt.depth);
    /* The lookahead prices dense cells by their future sub-grids: the top
     * level comes out no finer than without it. */
    accel_build_stats ahead;
    ok = build("nested_grid:auto,lookahead=1", &s, 1, &a, &ahead, &err) == 0;
    CHECKF(ok, "%s", err.msg);
    if (ok) accel_kind_nested_grid.destroy(a);
    CHECKF((uint64_t)ahead.res[0] * ahead.res[1] * ahead.res[2] <=
               (uint64_t)dflt.res[0] * dflt.res[1] * dflt.res[2],
           "top level with lookahead %dx%dx%d, without %dx%dx%d", ahead.res[0], ahead.res[1],
           ahead.res[2], dflt.res[0], dflt.res[1], dflt.res[2]);
    CHECKF(cheap_tests.nodes < dflt.nodes && dflt.nodes < cheap_steps.nodes,
           "cells: cheap tests %llu, default %llu, cheap steps %llu",
           (unsigned long long)cheap_tests.nodes, (unsigned long long)dflt.nodes,
           (unsigned long long)cheap_steps.nodes);
    /* Auto beats the flat grid at its own top resolution on the cluster. */
    size_t n;
    accel_ray *rays = cluster_rays(&n);
    if (rays) {
        accel_counters c_auto, c_flat;
        char flat[96];
        snprintf(flat, sizeof flat, "nested_grid:depth=1,res=%dx%dx%d", dflt.res[0], dflt.res[1],
                 dflt.res[2]);
        check_spec(&s, "nested_grid:auto", rays, 2500, NULL, &c_auto);
        check_spec(&s, flat, rays, 2500, NULL, &c_flat);
        const double cs = NGRID_DEFAULT_C_STEP, ci = NGRID_DEFAULT_C_ISECT;
        double cost_auto = cs * c_auto.steps + ci * c_auto.prim_tests;
        double cost_flat = cs * c_flat.steps + ci * c_flat.prim_tests;
        CHECKF(cost_auto < 0.5 * cost_flat, "model cost per ray: auto %.1f, flat %.1f",
               cost_auto / 2500, cost_flat / 2500);
        free(rays);
    }
    scene_free(&s);
}

/* ---- the hierarchical walk against the reference --------------------------------------- */

TEST(ngrid_cluster_against_reference)
{
    accel_scene s;
    if (!cluster_scene(&s, 2000, 300)) return;
    size_t n;
    accel_ray *rays = cluster_rays(&n);
    if (!rays) return;
    static const char *const extra[] = {"depth=4",
                                        "depth=4,threshold=2,sub_lambda=1",
                                        "sub_res=3,threshold=0,depth=4",
                                        "auto,depth=4,mailbox=0",
                                        "auto,lookahead=1",
                                        "lambda=0.01,sub_lambda=30",
                                        NULL};
    check_variants(&s, rays, n, extra, 0);
    free(rays);
    scene_free(&s);
}

/*
 * The lattice: bounds [0,4]^3, triangles with vertices on the 1/4 lattice,
 * some lying in lattice planes. With res=4 and sub_res=2 the sub-cells of
 * every level have lattice boundaries too (1, 1/2, 1/4), so rays between
 * lattice points run along cell edges and through cell corners at every
 * level, and start on sub-grid boundaries.
 */
TEST(ngrid_lattice_edges_and_corners)
{
    scene_builder b = {0};
    accel_error err = {0};
    seed_state = 31337;
    for (int i = 0; i < 400; i++) {
        vec3 base = v3(0.25f * (int)(rnd() * 15), 0.25f * (int)(rnd() * 15), 0.25f * (int)(rnd() * 15));
        vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = v3_add(base, v3(0.25f * (int)(rnd() * 3), 0.25f * (int)(rnd() * 3),
                                   0.25f * (int)(rnd() * 3)));
        scene_builder_add_tri(&b, p[0], p[1], p[2], &err);
    }
    scene_builder_add_tri(&b, v3(2, 0.5f, 0.5f), v3(2, 1.5f, 0.5f), v3(2, 1.5f, 1.5f), &err);
    scene_builder_add_tri(&b, v3(0.5f, 1.25f, 2.5f), v3(1.5f, 1.25f, 2.5f), v3(1.5f, 1.25f, 3.5f), &err);
    scene_builder_add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0), &err);
    scene_builder_add_tri(&b, v3(4, 4, 4), v3(3.99f, 4, 4), v3(4, 3.99f, 4), &err);
    accel_scene s;
    if (!finish_scene(&b, "lattice", &s)) return;
    size_t cap = 12000, n = 0;
    accel_ray *rays = malloc(cap * sizeof *rays);
    if (!rays) return;
    while (n < 7000) {
        float o[3], t[3];
        for (int a = 0; a < 3; a++) {
            o[a] = 0.25f * (int)(rnd() * 25) - 1.0f; /* -1 .. 5 */
            t[a] = 0.25f * (int)(rnd() * 17);        /* 0 .. 4 */
        }
        vec3 d = v3(t[0] - o[0], t[1] - o[1], t[2] - o[2]);
        if (d.x == 0 && d.y == 0 && d.z == 0) continue;
        rays[n] = ray_of(v3(o[0], o[1], o[2]), d, n % 5 == 0 ? 0.5f : 0.0f,
                         n % 7 == 0 ? 1.0f : INFINITY);
        n++;
    }
    for (int axis = 0; axis < 3; axis++)
        for (int i = 0; i <= 16; i += 1)
            for (int j = 0; j <= 16; j += 2)
                for (int var = 0; var < 3; var++) {
                    float o[3], d[3];
                    int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
                    o[a1] = 0.25f * i;
                    o[a2] = 0.25f * j;
                    o[axis] = var == 0 ? -1.0f : (var == 1 ? 5.0f : 2.0f);
                    d[axis] = var == 1 ? -1.0f : 1.0f;
                    d[a1] = (i + j) & 1 ? -0.0f : 0.0f;
                    d[a2] = j & 2 ? -0.0f : 0.0f;
                    rays[n++] = ray_of(v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
                }
    static const char *const extra[] = {"res=4,sub_res=2,threshold=0,depth=3",
                                        "res=4,sub_res=2,threshold=0,depth=4",
                                        "res=2,sub_res=4,threshold=3,depth=3",
                                        "res=4,sub_res=2,threshold=0,depth=4,overlap=bbox",
                                        "res=1,sub_res=2,threshold=0,depth=4,mailbox=0",
                                        NULL};
    /* Along lattice edges the float kernel and the reference may both be
     * right within rounding yet differ: the float brute force is the oracle
     * here, so any difference is a cell the walk skipped. */
    check_variants(&s, rays, n, extra, 1);
    free(rays);
    scene_free(&s);
}

/* Flat, far and tiny scenes, with rays starting far away. */
TEST(ngrid_flat_far_tiny_scenes)
{
    static const float offsets[] = {0.0f, 1e4f, 0.0f};
    static const float scales[] = {1.0f, 1.0f, 1e-4f};
    for (int c = 0; c < 3; c++) {
        scene_builder b = {0};
        accel_error err = {0};
        seed_state = 40 + c;
        float o = offsets[c], sc = scales[c];
        int flat = c == 0;
        for (int i = 0; i < 3000; i++) {
            /* Dense in one corner, sparse elsewhere. */
            float span = i < 2500 ? 0.5f : 8.0f;
            vec3 p = v3(o + sc * rnd_in(0, span), o + sc * rnd_in(0, span),
                        flat ? 0.0f : o + sc * rnd_in(0, span));
            vec3 q = v3_add(p, v3(sc * rnd_in(-.05f, .05f), sc * rnd_in(-.05f, .05f), 0));
            vec3 r = v3_add(p, v3(sc * rnd_in(-.05f, .05f), sc * rnd_in(-.05f, .05f),
                                  flat ? 0.0f : sc * rnd_in(-.05f, .05f)));
            scene_builder_add_tri(&b, p, q, r, &err);
        }
        accel_scene s;
        if (!finish_scene(&b, c == 0 ? "flat" : (c == 1 ? "far" : "tiny"), &s)) return;
        size_t n = 3000;
        accel_ray *rays = malloc(n * sizeof *rays);
        if (!rays) return;
        for (size_t i = 0; i < n; i++) {
            float reach = i % 4 == 0 ? 1000.0f : 10.0f;
            vec3 org = v3(o + sc * rnd_in(-reach, reach), o + sc * rnd_in(-reach, reach),
                          o + sc * rnd_in(-reach, reach));
            float span = i % 2 ? 0.5f : 8.0f;
            vec3 tgt = v3(o + sc * rnd_in(0, span), o + sc * rnd_in(0, span),
                          flat ? 0.0f : o + sc * rnd_in(0, span));
            if (flat && i % 5 == 0) org.z = 0.0f; /* in the plane */
            vec3 d = v3_sub(tgt, org);
            if (flat && i % 10 == 0) d.z = (i & 32) ? -0.0f : 0.0f;
            rays[i] = ray_of(org, d, 0.0f, INFINITY);
        }
        static const char *const extra[] = {"threshold=1,depth=3", NULL};
        check_variants(&s, rays, n, extra, 0);
        free(rays);
        scene_free(&s);
    }
}

/* No live primitive (only degenerate triangles): builds, misses everything. */
TEST(ngrid_empty_scene)
{
    scene_builder b = {0};
    accel_error err = {0};
    scene_builder_add_tri(&b, v3(0, 0, 0), v3(1, 1, 1), v3(2, 2, 2), &err);
    accel_scene s;
    if (!finish_scene(&b, "degenerate", &s)) return;
    accel_ray rays[3] = {ray_of(v3(-1, -1, -1), v3(1, 1, 1), 0, INFINITY),
                         ray_of(v3(0.5f, 0.5f, 0.5f), v3(0, 0, 1), 0, INFINITY),
                         ray_of(v3(0, 0, 0), v3(1, 1, 1), 0, 1)};
    check_variants(&s, rays, 3, NULL, 0);
    scene_free(&s);
}

/* ---- counters and mailbox ---------------------------------------------------------------- */

TEST(ngrid_counters_and_mailbox)
{
    /* Long thin triangles across the cluster's sub-cells: the mailbox is
     * what stops them from being tested in every cell. */
    scene_builder b = {0};
    accel_error err = {0};
    seed_state = 5;
    for (int i = 0; i < 3000; i++) {
        vec3 p = v3(rnd_in(0, 1), rnd_in(0, 1), rnd_in(0, 1));
        vec3 q = v3(rnd_in(0, 1), rnd_in(0, 1), rnd_in(0, 1));
        scene_builder_add_tri(&b, p, q, v3_add(p, v3(0.01f, 0.01f, 0.0f)), &err);
    }
    scene_builder_add_tri(&b, v3(-50, -50, -50), v3(50, -50, -50), v3(-50, 50, 50), &err);
    accel_scene s;
    if (!finish_scene(&b, "needles", &s)) return;
    size_t n = 2000;
    accel_ray *rays = malloc(n * sizeof *rays);
    if (!rays) return;
    for (size_t i = 0; i < n; i++) {
        vec3 o = v3(rnd_in(-3, 4), rnd_in(-3, 4), rnd_in(-3, 4));
        vec3 t = v3(rnd_in(0, 1), rnd_in(0, 1), rnd_in(0, 1));
        rays[i] = ray_of(o, v3_sub(t, o), 0.0f, INFINITY);
    }
    accel_counters on, off;
    accel_build_stats st;
    check_spec(&s, "nested_grid:threshold=8", rays, n, &st, &on);
    check_spec(&s, "nested_grid:threshold=8,mailbox=0", rays, n, NULL, &off);
    CHECKF(st.depth >= 2, "depth %d", st.depth);
    CHECKF(on.mailbox_skips > 0 && off.mailbox_skips == 0, "skips %llu / %llu",
           (unsigned long long)on.mailbox_skips, (unsigned long long)off.mailbox_skips);
    CHECKF(on.prim_tests + on.mailbox_skips == off.prim_tests && on.steps == off.steps,
           "mailbox: %llu tests + %llu skips, without: %llu tests; steps %llu / %llu",
           (unsigned long long)on.prim_tests, (unsigned long long)on.mailbox_skips,
           (unsigned long long)off.prim_tests, (unsigned long long)on.steps,
           (unsigned long long)off.steps);
    /* Per-ray arrays add up to the totals. */
    const accel_kind *kind;
    void *a;
    if (accel_build_spec("nested_grid:threshold=8", &s, 1, &kind, &a, &st, &err) == 0) {
        uint32_t *rs = calloc(n, sizeof *rs), *rp = calloc(n, sizeof *rp);
        accel_hit *h = malloc(n * sizeof *h);
        uint8_t *occ = malloc(n);
        if (rs && rp && h && occ) {
            accel_counters c;
            memset(&c, 0, sizeof c);
            c.ray_steps = rs;
            c.ray_prims = rp;
            kind->intersect(a, rays, h, n, &c);
            uint64_t ss = 0, sp = 0;
            for (size_t i = 0; i < n; i++) ss += rs[i], sp += rp[i];
            CHECKF(ss == c.steps && sp == c.prim_tests && c.box_tests == n,
                   "per-ray sums %llu/%llu, totals %llu/%llu", (unsigned long long)ss,
                   (unsigned long long)sp, (unsigned long long)c.steps,
                   (unsigned long long)c.prim_tests);
            /* Any-hit stops early: never more tests than closest-hit. */
            accel_counters co;
            memset(&co, 0, sizeof co);
            kind->occluded(a, rays, occ, n, &co);
            CHECKF(co.prim_tests <= c.prim_tests && co.rays == n, "occluded %llu tests, closest %llu",
                   (unsigned long long)co.prim_tests, (unsigned long long)c.prim_tests);
        }
        free(rs);
        free(rp);
        free(h);
        free(occ);
        kind->destroy(a);
    }
    free(rays);
    scene_free(&s);
}

/* ---- threads ----------------------------------------------------------------------------- */

static int same_view(const ngrid_view *a, const ngrid_view *b)
{
    if (a->node_count != b->node_count || a->cell_count != b->cell_count ||
        a->list_len != b->list_len || a->ref_count != b->ref_count || a->levels != b->levels)
        return 0;
    if (memcmp(a->cells, b->cells, a->cell_count * sizeof *a->cells) ||
        memcmp(a->lists, b->lists, a->list_len * sizeof *a->lists))
        return 0;
    for (uint32_t i = 0; i < a->node_count; i++) {
        const ngrid_node *x = &a->nodes[i], *y = &b->nodes[i];
        if (x->cell_base != y->cell_base || x->level != y->level ||
            memcmp(x->frame.res, y->frame.res, sizeof x->frame.res) ||
            memcmp(x->frame.lo, y->frame.lo, sizeof x->frame.lo) ||
            memcmp(x->frame.hi, y->frame.hi, sizeof x->frame.hi) ||
            memcmp(x->frame.pad, y->frame.pad, sizeof x->frame.pad))
            return 0;
    }
    return 1;
}

TEST(ngrid_threads_build_identical)
{
    /* 20000 triangles in one top cell: a job large enough to be built with
     * every thread, beside many small ones spread over threads. */
    accel_scene s;
    if (!cluster_scene(&s, 20000, 50)) return;
    static const char *const specs[] = {"nested_grid", "nested_grid:auto", "nested_grid:depth=4,threshold=4"};
    for (int k = 0; k < 3; k++) {
        void *one, *many;
        accel_build_stats s1, sn;
        accel_error err = {0};
        if (build(specs[k], &s, 1, &one, &s1, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[k], err.msg);
            continue;
        }
        ngrid_view v1;
        ngrid_get_view(one, &v1);
        for (int threads = 2; threads <= 5; threads += 3) {
            if (build(specs[k], &s, threads, &many, &sn, &err)) {
                test_fail(__FILE__, __LINE__, "%s, %d threads: %s", specs[k], threads, err.msg);
                continue;
            }
            ngrid_view vn;
            ngrid_get_view(many, &vn);
            CHECKF(same_view(&v1, &vn) && s1.bytes == sn.bytes,
                   "%s: %d threads build differently (%u vs %u grids, %zu vs %zu bytes)", specs[k],
                   threads, vn.node_count, v1.node_count, sn.bytes, s1.bytes);
            accel_kind_nested_grid.destroy(many);
        }
        accel_kind_nested_grid.destroy(one);
    }
    scene_free(&s);
}
