/*
 * test_sbvh.c - the split BVH (bvh:build=sbvh, bvh/build_sbvh.c): chopped
 * boxes that contain the exact parts of their triangles (and a
 * round-to-nearest twin that does not, so the check can fail), every
 * triangle covered by the leaves that hold it, the duplicate budget, the
 * oracle on slivers, the stiff cases and degenerate inputs with spatial
 * splits everywhere, saving and loading, and the spec errors.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rays/stiff.h"
#include "bvh/split_common.h"
#include "support.h"
#include "test_bvh.h"

/* ---- chopped boxes ------------------------------------------------------------------- */

/* Does the float box contain the point (long double, no tolerance)? */
static int box_has(box3 b, const long double *p)
{
    return p[0] >= b.min.x && p[0] <= b.max.x && p[1] >= b.min.y && p[1] <= b.max.y &&
           p[2] >= b.min.z && p[2] <= b.max.z;
}

/* The points that span the exact part of tri on each side of the plane
 * (the vertices on that side and the edge crossings), in long double, so
 * more precisely than the builder's double; each must lie in the part's
 * box, unless the ref box itself (here: the triangle's own box) cuts it.
 * Returns the number of points missed. */
static int chop_misses(const float *tri, int axis, double plane, int outward)
{
    box3 box = box3_empty(), l, r;
    for (int v = 0; v < 3; v++) box = box3_grow(box, v3_load(tri + 3 * v));
    bvh_sbvh_chop(tri, box, axis, plane, outward, &l, &r);
    int misses = 0;
    for (int e = 0; e < 3; e++) {
        long double a[3], b[3], p[3];
        for (int k = 0; k < 3; k++) a[k] = tri[3 * e + k], b[k] = tri[3 * ((e + 1) % 3) + k];
        if (a[axis] <= plane) misses += !box_has(l, a);
        if (a[axis] >= plane) misses += !box_has(r, a);
        if ((a[axis] < plane && b[axis] > plane) || (a[axis] > plane && b[axis] < plane)) {
            long double s = ((long double)plane - a[axis]) / (b[axis] - a[axis]);
            for (int k = 0; k < 3; k++) p[k] = k == axis ? (long double)plane : a[k] + s * (b[k] - a[k]);
            misses += !box_has(l, p) + !box_has(r, p);
        }
    }
    return misses;
}

TEST(sbvh_chop_conservative)
{
    /* Triangles of every scale and place: unit, tiny, huge, far from the
     * origin with a small extent, and mixed magnitudes; planes drawn
     * between the extreme vertices. Outward rounding must contain every
     * exact point; rounding to nearest (the builder without its care)
     * must miss some, or this test could not tell them apart. */
    test_seed(11);
    static const float scale[] = {1.0f, 1e-30f, 1e30f, 1.0f, 1e-3f};
    static const float offset[] = {0.0f, 0.0f, 0.0f, 1.0e7f, -3.0e4f};
    long outward_misses = 0, nearest_misses = 0, cases = 0;
    for (int c = 0; c < 5; c++)
        for (int i = 0; i < 4000; i++) {
            float tri[9];
            for (int k = 0; k < 9; k++) tri[k] = offset[c] + scale[c] * test_rand_in(-1.0f, 1.0f);
            int axis = i % 3;
            double lo = fmin(fmin(tri[axis], tri[3 + axis]), tri[6 + axis]);
            double hi = fmax(fmax(tri[axis], tri[3 + axis]), tri[6 + axis]);
            double plane = lo + (hi - lo) * test_rand();
            if (i % 50 == 0) plane = tri[3 + axis]; /* exactly through a vertex */
            outward_misses += chop_misses(tri, axis, plane, 1);
            nearest_misses += chop_misses(tri, axis, plane, 0);
            cases++;
        }
    /* Cancellation: an edge from y = -M to y = +M crossing the plane near
     * its middle, so the crossing's y is tiny while |a| + |b| is not; the
     * double rounding of the crossing then exceeds a float ulp of the
     * result, and only the pad (not the outward rounding) covers it. */
    for (int i = 0; i < 2000; i++) {
        float m = i % 2 ? 1e6f : 3.0f;
        float tri[9] = {-1.0f, -m, test_rand(), 1.0f, m, test_rand(), test_rand_in(-1, 1), 0.25f, 2.0f};
        double plane = (test_rand() - 0.5) * 1e-15 * (1 + i % 7);
        outward_misses += chop_misses(tri, 0, plane, 1);
        nearest_misses += chop_misses(tri, 0, plane, 0);
        cases++;
    }
    test_note("%ld cases: outward chop misses %ld exact points, round-to-nearest %ld",
              cases, outward_misses, nearest_misses);
    CHECKF(outward_misses == 0, "outward chop misses %ld exact points in %ld cases", outward_misses,
           cases);
    CHECKF(nearest_misses > cases / 20,
           "the round-to-nearest chop misses only %ld points in %ld cases: the check is blind",
           nearest_misses, cases);
    /* Empty parts: a plane beyond the triangle leaves one side empty. */
    float t[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    box3 box = {{0, 0, 0}, {1, 1, 0}}, l, r;
    bvh_sbvh_chop(t, box, 0, 2.0, 1, &l, &r);
    CHECK(l.min.x == 0.0f && l.max.x == 1.0f && !(r.min.x <= r.max.x));
}

/* ---- the built tree ------------------------------------------------------------------ */

/* Every sample point of every live triangle (vertices, points along the
 * edges, interior points, in long double) lies in the box of some leaf
 * holding that triangle, within a tolerance far below a float ulp (the
 * samples themselves round). Returns the points missed. */
static size_t coverage_misses(const accel_scene *s, const void *a)
{
    uint32_t nc, pc;
    const bvh_node *nodes = bvh_nodes(a, &nc);
    const uint32_t *ids = bvh_prim_ids(a, &pc);
    /* leaf boxes per slot, slots grouped by primitive */
    box3 *slot_box = malloc((pc ? pc : 1) * sizeof *slot_box);
    uint32_t *order = malloc((pc ? pc : 1) * sizeof *order);
    uint32_t *start = calloc((size_t)s->prim_count + 1, sizeof *start);
    if (!slot_box || !order || !start) {
        free(slot_box), free(order), free(start);
        return 1;
    }
    for (uint32_t i = 0; i < nc; i++) {
        if (!nodes[i].count || (i == 1 && nc > 1)) continue;
        box3 b = {{nodes[i].bmin[0], nodes[i].bmin[1], nodes[i].bmin[2]},
                  {nodes[i].bmax[0], nodes[i].bmax[1], nodes[i].bmax[2]}};
        for (uint32_t k = 0; k < nodes[i].count; k++) slot_box[nodes[i].left_first + k] = b;
    }
    for (uint32_t k = 0; k < pc; k++) start[ids[k] + 1]++;
    for (uint32_t p = 0; p < s->prim_count; p++) start[p + 1] += start[p];
    uint32_t *fill = calloc((size_t)s->prim_count + 1, sizeof *fill);
    for (uint32_t k = 0; fill && k < pc; k++) order[start[ids[k]] + fill[ids[k]]++] = k;
    free(fill);
    size_t misses = 0;
    for (uint32_t li = 0; li < s->live_count; li++) {
        uint32_t prim = s->live[li];
        if (prim >= s->tri_count) continue;
        const float *t = s->tris + 9 * (size_t)prim;
        long double tol = 0.0L;
        for (int k = 0; k < 9; k++) tol = fmaxl(tol, fabsl((long double)t[k]));
        tol *= 1e-15L;
        for (int i = 0; i <= 8; i++)
            for (int j = 0; i + j <= 8; j++) {
                long double u = i / 8.0L, v = j / 8.0L, w = 1.0L - u - v, p[3];
                for (int k = 0; k < 3; k++) p[k] = w * t[k] + u * t[3 + k] + v * t[6 + k];
                int in = 0;
                for (uint32_t q = start[prim]; q < start[prim + 1] && !in; q++) {
                    box3 b = slot_box[order[q]];
                    in = p[0] >= b.min.x - tol && p[0] <= b.max.x + tol && p[1] >= b.min.y - tol &&
                         p[1] <= b.max.y + tol && p[2] >= b.min.z - tol && p[2] <= b.max.z + tol;
                }
                misses += !in;
            }
    }
    free(slot_box), free(order), free(start);
    return misses;
}

/* Rays for a scene: primary from its camera, shadow and diffuse from
 * their reference hits, and rays aimed exactly at vertices and edges. */
static void scene_rays(const accel_scene *s, int size, test_rays *out)
{
    accel_error err = {0};
    rays_set pr = {0}, sh = {0}, df = {0};
    rays_primary(&s->camera, size, size, &pr, &err);
    accel_hit *ref = test_oracle_hits(s, pr.rays, pr.count, TEST_ORACLE_REFERENCE);
    if (ref) {
        rays_shadow(s, &pr, ref, &sh, &err);
        rays_diffuse(s, &pr, ref, 1, &df, &err);
    }
    for (size_t i = 0; i < pr.count; i++) test_rays_push(out, pr.rays[i]);
    for (size_t i = 0; i < sh.count; i++) test_rays_push(out, sh.rays[i]);
    for (size_t i = 0; i < df.count; i++) test_rays_push(out, df.rays[i]);
    test_rays_at_vertices(out, s, s->camera.eye, 300, 5);
    test_rays_at_edges(out, s, s->camera.eye, 300, 6);
    free(ref);
    rays_free(&pr), rays_free(&sh), rays_free(&df);
}

TEST(sbvh_slivers_oracle)
{
    /* The scene spatial splits are for: needles across the whole cube
     * among small triangles. Every width and traversal against the
     * reference; the tree duplicates references within the budget, and
     * its SAH cost is well below the binned tree's. */
    accel_scene s;
    if (!test_make_scene("slivers:tris=3000,slivers=150", &s)) return;
    test_rays r = {0};
    scene_rays(&s, 48, &r);
    accel_hit *ref = test_oracle_hits(&s, r.rays, r.count, TEST_ORACLE_REFERENCE);
    accel_build_stats bin;
    void *b = test_build("bvh", &s, 1, &bin);
    if (b) accel_kind_bvh.destroy(b);
    static const char *const specs[] = {
        "bvh:build=sbvh",         "bvh:build=sbvh,traverse=packet",
        "bvh:build=sbvh,width=4", "bvh:build=sbvh,width=4,traverse=packet",
        "bvh:build=sbvh,width=8", "bvh:build=sbvh,width=8,traverse=packet",
        "bvh:build=sbvh,bins=32,split_budget=1,alpha=0,leaf=2",
    };
    for (size_t i = 0; ref && i < sizeof specs / sizeof specs[0]; i++) {
        accel_build_stats st;
        test_check_spec(&s, specs[i], r.rays, r.count, ref, &st, NULL);
        double budget = i == 6 ? 1.0 : 0.3;
        CHECKF(st.refs > s.live_count && st.refs <= s.live_count + floor(budget * s.live_count),
               "%s: %llu references for %u primitives", specs[i], (unsigned long long)st.refs,
               s.live_count);
        CHECKF(st.sah_cost < 0.8 * bin.sah_cost, "%s: SAH cost %.1f against binned %.1f", specs[i],
               st.sah_cost, bin.sah_cost);
    }
    /* the binary tree's structure: every triangle covered by its leaves */
    void *a = test_build("bvh:build=sbvh,split_budget=1,alpha=0", &s, 1, NULL);
    if (a) {
        CHECKF(coverage_misses(&s, a) == 0, "sbvh leaves leave parts of triangles uncovered");
        accel_kind_bvh.destroy(a);
    }
    free(ref);
    test_rays_free(&r);
    scene_free(&s);
}

TEST(sbvh_budget)
{
    /* refs <= N + floor(budget * N) for every budget; budget 0 is an
     * object-split tree over the primitives once each. Memory counts every
     * slot. */
    accel_scene s;
    if (!test_make_scene("slivers:tris=2000,slivers=200", &s)) return;
    static const double budgets[] = {0.0, 0.01, 0.1, 0.3, 2.0};
    uint64_t last = 0;
    for (size_t i = 0; i < sizeof budgets / sizeof budgets[0]; i++) {
        char spec[128];
        snprintf(spec, sizeof spec, "bvh:build=sbvh,alpha=0,split_budget=%g", budgets[i]);
        accel_build_stats st;
        void *a = test_build(spec, &s, 1, &st);
        if (!a) continue;
        uint64_t cap = s.live_count + (uint64_t)floor(budgets[i] * s.live_count);
        CHECKF(st.refs >= s.live_count && st.refs <= cap, "%s: %llu references, budget %llu", spec,
               (unsigned long long)st.refs, (unsigned long long)cap);
        if (budgets[i] == 0.0) test_bvh_check_pool(&s, a, 8, spec);
        CHECKF(st.refs >= last, "%s: %llu references, fewer than a smaller budget's %llu", spec,
               (unsigned long long)st.refs, (unsigned long long)last);
        last = st.refs;
        uint32_t nc, pc;
        bvh_nodes(a, &nc);
        bvh_prim_ids(a, &pc);
        CHECK(pc == st.refs && nc <= 2 * pc);
        CHECK(st.bytes == accel_kind_bvh.memory(a) &&
              st.bytes >= (size_t)pc * (BVH_SLOT_FLOATS * sizeof(float) + sizeof(uint32_t)));
        CHECKF(coverage_misses(&s, a) == 0, "%s: parts of triangles uncovered", spec);
        accel_kind_bvh.destroy(a);
    }
    CHECKF(last > s.live_count, "no budget made any spatial split (%llu references)",
           (unsigned long long)last);
    scene_free(&s);
}

TEST(sbvh_stiff_cases)
{
    /* The stability suite's cases with spatial splits tried everywhere and
     * a large budget, binary and 8 wide: no hole, false hit, disagreement
     * or leak. */
    static const char *const specs[] = {"bvh:build=sbvh,alpha=0,split_budget=1,leaf=2",
                                        "bvh:build=sbvh,alpha=0,split_budget=1,width=8",
                                        "bvh:build=sbvh,alpha=0,split_budget=1,width=4,traverse=packet"};
    for (int ci = 0; ci < stiff_case_count(); ci++) {
        stiff_case c;
        if (!test_stiff_case(ci, &c)) continue;
        accel_error err = {0};
        size_t n = c.rays.count;
        accel_hit *ref = test_oracle_hits(&c.scene, c.rays.rays, n, TEST_ORACLE_REFERENCE);
        for (size_t i = 0; ref && i < sizeof specs / sizeof specs[0]; i++) {
            accel_build_stats st;
            test_check_spec(&c.scene, specs[i], c.rays.rays, n, ref, &st, NULL);
            CHECKF(st.depth <= BVH_MAX_DEPTH, "%s on %s: depth %d", specs[i], c.name, st.depth);
            accel_hit *hits = malloc((n ? n : 1) * sizeof *hits);
            const accel_kind *k;
            void *a;
            if (hits && accel_build_spec(specs[i], &c.scene, 1, &k, &a, &st, &err) == 0) {
                accel_trace(k, a, c.rays.rays, hits, n, 1, NULL);
                size_t leaks = 0;
                for (size_t j = c.leak_begin; j < n; j++) leaks += hits[j].prim == ACCEL_MISS;
                CHECKF(leaks == 0, "%s on %s: %zu leaks", specs[i], c.name, leaks);
                k->destroy(a);
            }
            free(hits);
        }
        free(ref);
        stiff_case_free(&c);
    }
}

TEST(sbvh_degenerate_inputs)
{
    /* Coincident copies, a geometric progression (a deep tree), flat and
     * zero-area triangles, a huge triangle among small ones, triangles far
     * from the origin and tiny ones: the build ends within the depth bound
     * and the budget, and random rays agree with the reference. */
    scene_builder b = {0};
    for (int i = 0; i < 300; i++) test_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0));
    float x = 1.0f;
    for (int i = 0; i < 150; i++, x /= 1.5f)
        test_add_tri(&b, v3(x, 0, 0), v3(1.2f * x, 0, 0), v3(x, 0.2f * x, 0.1f * x));
    for (int i = 0; i < 100; i++) { /* zero area: collinear, and a point */
        float t = (float)i;
        test_add_tri(&b, v3(t, 2, 0), v3(t + 1, 2, 0), v3(t + 2, 2, 0));
        test_add_tri(&b, v3(t, 3, 1), v3(t, 3, 1), v3(t, 3, 1));
    }
    test_add_tri(&b, v3(-1e30f, -1e30f, -3.0f), v3(1e30f, -1e30f, -3.0f), v3(0, 1e30f, -3.5f));
    for (int i = 0; i < 200; i++) {
        vec3 p = test_rand_point((box3){{1e7f, 1e7f, 1e7f}, {1.0001e7f, 1.0001e7f, 1.0001e7f}});
        test_add_tri(&b, p, v3_add(p, v3(1, 0, 0)), v3_add(p, v3(0, 900, 1)));
        vec3 q = test_rand_point((box3){{0, 0, 0}, {1e-30f, 1e-30f, 1e-30f}});
        test_add_tri(&b, q, v3_add(q, v3(1e-31f, 0, 0)), v3_add(q, v3(0, 1e-31f, 1e-32f)));
    }
    accel_scene s;
    if (!test_finish(&b, "sbvh_degenerate", &s)) return;
    static const char *const specs[] = {"bvh:build=sbvh", "bvh:build=sbvh,alpha=0,split_budget=4,leaf=1",
                                        "bvh:build=sbvh,alpha=0,split_budget=4,bins=2,width=8"};
    test_rays r = {0};
    test_rays_random(&r, s.bounds, 800);
    box3 far = {{1e7f, 1e7f, 1e7f}, {1.0001e7f, 1.0001e7f, 1.0001e7f}};
    for (int i = 0; i < 400; i++) { /* from outside the far cluster, into it */
        vec3 o = test_rand_point(far), t = test_rand_point(far);
        o.x = 0.9999e7f;
        test_rays_push(&r, test_ray(o, v3_sub(t, o), 0.0f, INFINITY));
    }
    test_rays_random(&r, (box3){{-2, -2, -2}, {3, 3, 3}}, 400);
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        accel_build_stats st;
        test_check_spec(&s, specs[i], r.rays, r.count, NULL, &st, NULL);
        double budget = i == 0 ? 0.3 : 4.0;
        CHECKF(st.depth >= 1 && st.depth <= BVH_MAX_DEPTH, "%s: depth %d", specs[i], st.depth);
        CHECKF(st.refs <= s.live_count + floor(budget * s.live_count) && isfinite(st.sah_cost),
               "%s: %llu references, SAH %g", specs[i], (unsigned long long)st.refs, st.sah_cost);
    }
    test_rays_free(&r);
    scene_free(&s);
}

TEST(sbvh_save_load)
{
    /* Duplicated references: more slots than primitives; the file keeps
     * them and the loaded tree traces like the built one. */
    accel_scene s;
    if (!test_make_scene("slivers:tris=1000,slivers=100", &s)) return;
    accel_build_stats st;
    void *a = test_build("bvh:build=sbvh", &s, 1, &st);
    if (!a) {
        scene_free(&s);
        return;
    }
    CHECK(st.refs > s.live_count);
    char path[64];
    snprintf(path, sizeof path, "/tmp/gridbvh_sbvh_%d.bvh", (int)getpid());
    accel_error err = {0};
    CHECKF(bvh_save(a, path, &err) == 0, "save: %s", err.msg);
    void *b = NULL;
    CHECKF(bvh_load(path, &b, &err) == 0, "load: %s", err.msg);
    if (b) {
        uint32_t p1, p2;
        const uint32_t *i1 = bvh_prim_ids(a, &p1), *i2 = bvh_prim_ids(b, &p2);
        CHECK(p1 == p2 && p1 == st.refs && memcmp(i1, i2, p1 * sizeof *i1) == 0);
        test_rays r = {0};
        test_rays_random(&r, s.bounds, 700);
        test_check_accel(&s, &accel_kind_bvh, b, "loaded sbvh", r.rays, r.count, NULL, NULL);
        test_rays_free(&r);
        accel_kind_bvh.destroy(b);
    }
    unlink(path);
    accel_kind_bvh.destroy(a);
    scene_free(&s);
}

TEST(sbvh_spec_errors)
{
    accel_scene s;
    if (!test_make_scene("soup:tris=200", &s)) return;
    static const char *const bad[] = {"bvh:split_budget=0.5", "bvh:build=sah,alpha=0",
                                      "bvh:build=sbvh,axes=1", "bvh:build=sbvh,split_budget=5",
                                      "bvh:build=mid,bins=8"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        accel_error err = {0};
        int rc = accel_build_spec(bad[i], &s, 1, &k, &a, &st, &err);
        CHECKF(rc != 0 && a == NULL, "%s: accepted", bad[i]);
    }
    void *a = test_build("bvh:build=sbvh,bins=64,split_budget=0.5,alpha=1e-3", &s, 1, NULL);
    if (a) accel_kind_bvh.destroy(a);
    scene_free(&s);
    /* max_mb bounds the build's peak, duplicates included: 3000 triangles
     * need about 0.65 MiB with +30%, 2.4 MiB with +400%. */
    if (!test_make_scene("soup:tris=3000", &s)) return;
    a = test_build("bvh:build=sbvh,max_mb=1", &s, 1, NULL);
    if (a) accel_kind_bvh.destroy(a);
    const accel_kind *k;
    accel_build_stats st;
    accel_error err = {0};
    a = NULL;
    int rc = accel_build_spec("bvh:build=sbvh,split_budget=4,max_mb=1", &s, 1, &k, &a, &st, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && a == NULL && strstr(err.msg, "max_mb") &&
               strstr(err.msg, "split_budget"),
           "budget over max_mb: rc %d, %s", rc, err.msg);
    scene_free(&s);
}
