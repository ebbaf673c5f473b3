/*
 * test_bvh.c - BVH-specific tests: the node layout and pool invariants of
 * every builder, SAH cost values on hand-made scenes, the termination rule,
 * byte-identical builds for 1, 2 and 3 threads, degenerate inputs
 * (coincident primitives, equal centroids, a geometric progression that
 * would make a tree hundreds of levels deep, non-finite vertices, empty
 * scenes), packets of mixed and invalid rays, counters, saving and loading,
 * and spec errors. Every trace is compared against the double-precision
 * reference with the FORMATS.md rule.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bvh/bvh.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "test.h"

/* ---- helpers ------------------------------------------------------------------ */

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static float frand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (float)(rng >> 40) / 16777216.0f;
}
static float frange(float lo, float hi) { return lo + (hi - lo) * frand(); }

static void add_tri(scene_builder *b, vec3 a, vec3 c, vec3 d)
{
    accel_error err = {0};
    CHECKF(scene_builder_add_tri(b, a, c, d, &err) == 0, "add_tri: %s", err.msg);
}

static int finish(scene_builder *b, const char *name, accel_scene *s)
{
    accel_error err = {0};
    int rc = scene_finish(b, name, s, &err);
    scene_builder_free(b);
    CHECKF(rc == 0, "scene_finish %s: %s", name, err.msg);
    return rc == 0;
}

static int make_scene(const char *spec, accel_scene *s)
{
    accel_error err = {0};
    int rc = scene_create(spec, s, &err);
    CHECKF(rc == 0, "scene %s: %s", spec, err.msg);
    return rc == 0;
}

/* Random rays: origins in the bounds grown by half their size, random
 * directions (a few with +-0 components), some finite t ranges. */
static accel_ray *random_rays(const accel_scene *s, size_t n)
{
    accel_ray *r = malloc(n * sizeof *r);
    box3 b = box3_is_empty(s->bounds) ? (box3){{-1, -1, -1}, {1, 1, 1}} : s->bounds;
    vec3 e = box3_extent(b);
    for (size_t i = 0; r && i < n; i++) {
        vec3 o = v3(frange(b.min.x - 0.5f * e.x, b.max.x + 0.5f * e.x),
                    frange(b.min.y - 0.5f * e.y, b.max.y + 0.5f * e.y),
                    frange(b.min.z - 0.5f * e.z, b.max.z + 0.5f * e.z));
        vec3 target = v3(frange(b.min.x, b.max.x), frange(b.min.y, b.max.y), frange(b.min.z, b.max.z));
        vec3 d = v3_sub(target, o);
        if (i % 7 == 3) d.x = (i & 8) ? -0.0f : 0.0f;
        if (i % 11 == 5) d.y = (i & 16) ? -0.0f : 0.0f;
        float len = v3_len(d);
        r[i] = (accel_ray){o.x, o.y, o.z, 0.0f, d.x, d.y, d.z, INFINITY};
        if (i % 5 == 1) r[i].t_far = 0.7f;
        if (i % 13 == 2 && len > 0) r[i].t_near = 0.3f;
    }
    return r;
}

/* Builds spec with `threads` threads; NULL (and a failed check) on error. */
static void *build(const char *spec, const accel_scene *s, int threads, accel_build_stats *st)
{
    accel_error err = {0};
    const accel_kind *k;
    void *a = NULL;
    accel_build_stats local;
    if (!st) st = &local;
    int rc = accel_build_spec(spec, s, threads, &k, &a, st, &err);
    CHECKF(rc == 0, "%s on %s: %s", spec, s->name, err.msg);
    return rc ? NULL : a;
}

/* Traces rays with spec's accel, compares hits and occlusion against the
 * reference. Returns the number of bad rays. */
static size_t check_trace(const accel_scene *s, const void *a, const char *spec,
                          const accel_ray *rays, size_t n)
{
    accel_hit *ref = malloc(n * sizeof *ref), *hits = malloc(n * sizeof *hits);
    uint8_t *occ = malloc(n);
    accel_reference_trace(s, rays, ref, n, 2);
    accel_trace(&accel_kind_bvh, a, rays, hits, n, 1, NULL);
    accel_trace_occluded(&accel_kind_bvh, a, rays, occ, n, 1, NULL);
    hits_diff d = hits_compare(ref, hits, n);
    size_t occ_bad = 0;
    for (size_t i = 0; i < n; i++) occ_bad += occ[i] != (ref[i].prim != ACCEL_MISS);
    size_t bad = d.holes + d.false_hits + d.disagreements + occ_bad;
    if (bad) {
        size_t i = d.first_bad != SIZE_MAX ? d.first_bad : 0;
        test_fail(__FILE__, __LINE__,
                  "%s on %s: %zu holes, %zu false hits, %zu disagreements, %zu occluded "
                  "mismatches of %zu rays (first %zu: ref prim %u t %.9g, got %u t %.9g)",
                  spec, s->name, d.holes, d.false_hits, d.disagreements, occ_bad, n, i, ref[i].prim,
                  ref[i].t, hits[i].prim, hits[i].t);
    }
    free(ref);
    free(hits);
    free(occ);
    return bad;
}

/* Builds and checks against the reference with random rays. */
static void check_spec(const accel_scene *s, const char *spec, size_t nrays)
{
    void *a = build(spec, s, 1, NULL);
    if (!a) return;
    accel_ray *rays = random_rays(s, nrays);
    check_trace(s, a, spec, rays, nrays);
    free(rays);
    accel_kind_bvh.destroy(a);
}

static box3 node_box(const bvh_node *n)
{
    return (box3){{n->bmin[0], n->bmin[1], n->bmin[2]}, {n->bmax[0], n->bmax[1], n->bmax[2]}};
}

static int box_contains(box3 outer, box3 inner)
{
    return outer.min.x <= inner.min.x && outer.min.y <= inner.min.y && outer.min.z <= inner.min.z &&
           outer.max.x >= inner.max.x && outer.max.y >= inner.max.y && outer.max.z >= inner.max.z;
}

/*
 * The structural invariants of a built pool: 64-byte alignment; node 1
 * unused; children pairs at even indices after their parent, each node
 * reached exactly once; boxes nest; leaves tile the slot array in order
 * and hold at most max_leaf primitives; the slots are a permutation of the
 * live primitives; depth within BVH_MAX_DEPTH and as reported.
 */
static void check_pool(const accel_scene *s, const void *a, int max_leaf, const char *spec)
{
    uint32_t nc, pc;
    const bvh_node *nodes = bvh_nodes(a, &nc);
    const uint32_t *ids = bvh_prim_ids(a, &pc);
    CHECKF(pc == s->live_count, "%s: %u slots for %u live primitives", spec, pc, s->live_count);
    if (nc == 0) {
        CHECK(pc == 0);
        return;
    }
    CHECKF(((uintptr_t)nodes & 63) == 0, "%s: node pool not 64-byte aligned", spec);
    CHECKF(nc <= 2 * pc, "%s: %u nodes for %u primitives", spec, nc, pc);
    uint8_t *seen = calloc(nc, 1);
    uint8_t *prim_seen = calloc(s->prim_count ? s->prim_count : 1, 1);
    uint32_t stack[2 * BVH_MAX_DEPTH + 2];
    int level[2 * BVH_MAX_DEPTH + 2];
    int sp = 0, depth = 0, bad = 0;
    uint32_t next_slot = 0;
    stack[sp] = 0, level[sp++] = 1;
    while (sp > 0 && !bad) {
        sp--;
        uint32_t i = stack[sp];
        int lv = level[sp];
        if (lv > depth) depth = lv;
        if (seen[i]++) { bad = 1; test_fail(__FILE__, __LINE__, "%s: node %u reached twice", spec, i); break; }
        const bvh_node *n = &nodes[i];
        if (n->count) {
            CHECKF(n->count <= (uint32_t)max_leaf, "%s: leaf of %u > %d", spec, n->count, max_leaf);
            /* depth-first from the left: leaves appear in slot order */
            CHECKF(n->left_first == next_slot, "%s: leaf %u starts at %u, expected %u", spec, i,
                   n->left_first, next_slot);
            next_slot = n->left_first + n->count;
            for (uint32_t k = n->left_first; k < n->left_first + n->count && k < pc; k++) {
                CHECK(box_contains(node_box(n), accel_prim_bounds(s, ids[k])));
                if (ids[k] < s->prim_count) prim_seen[ids[k]]++;
            }
            continue;
        }
        uint32_t l = n->left_first;
        if (l <= i || l < 2 || (l & 1) || l + 1 >= nc) {
            test_fail(__FILE__, __LINE__, "%s: node %u has children %u", spec, i, l);
            bad = 1;
            break;
        }
        CHECK(box_contains(node_box(n), node_box(&nodes[l])));
        CHECK(box_contains(node_box(n), node_box(&nodes[l + 1])));
        /* the pair shares one cache line */
        CHECK((((uintptr_t)&nodes[l]) >> 6) == (((uintptr_t)&nodes[l + 1]) >> 6));
        stack[sp] = l + 1, level[sp++] = lv + 1;
        stack[sp] = l, level[sp++] = lv + 1;
    }
    CHECKF(next_slot == pc || bad, "%s: leaves cover %u of %u slots", spec, next_slot, pc);
    CHECKF(depth <= BVH_MAX_DEPTH, "%s: depth %d", spec, depth);
    if (nc > 1) CHECKF(!seen[1], "%s: padding node 1 is referenced", spec);
    uint32_t reached = 0;
    for (uint32_t i = 0; i < nc; i++) reached += seen[i];
    CHECKF(reached == nc - (nc > 1) || bad, "%s: %u of %u nodes reachable", spec, reached, nc);
    for (uint32_t k = 0; k < s->live_count; k++)
        CHECKF(prim_seen[s->live[k]] == 1, "%s: live primitive %u stored %d times", spec,
               s->live[k], prim_seen[s->live[k]]);
    free(seen);
    free(prim_seen);
}

static const char *const builders[] = {"bvh:build=binned", "bvh:build=sah", "bvh:build=mid",
                                       "bvh:build=median"};

/* ---- layout ------------------------------------------------------------------- */

_Static_assert(sizeof(bvh_node) == 32, "32-byte node");
_Static_assert(_Alignof(bvh_node) == 4, "no hidden alignment padding");
_Static_assert(BVH_NODE_ALIGN % (2 * sizeof(bvh_node)) == 0, "a sibling pair fits one aligned line");

TEST(bvh_layout_every_builder)
{
    accel_scene s;
    if (!make_scene("soup:tris=5000", &s)) return;
    const char *extra[] = {"bvh:leaf=1", "bvh:build=sah,leaf=1", "bvh:leaf=3,bins=2",
                           "bvh:ct=0,leaf=256", "bvh:axes=1,bins=256"};
    for (size_t i = 0; i < 4 + 5; i++) {
        const char *spec = i < 4 ? builders[i] : extra[i - 4];
        accel_params p;
        accel_error err;
        CHECK(accel_params_parse(spec, &p, &err) == 0);
        accel_build_stats st;
        void *a = build(spec, &s, 1, &st);
        if (!a) continue;
        check_pool(&s, a, (int)accel_param_num(&p, "leaf"), spec);
        uint32_t nc;
        bvh_nodes(a, &nc);
        CHECK(st.nodes == nc);
        CHECK(st.refs == s.live_count);
        CHECK(st.depth >= 1 && st.depth <= BVH_MAX_DEPTH);
        CHECK(st.leaves >= 1 && st.leaves <= s.live_count);
        /* a binary tree: leaves = interior nodes + 1 */
        CHECK(nc == 2 * st.leaves);
        CHECK(st.bytes == accel_kind_bvh.memory(a));
        accel_kind_bvh.destroy(a);
    }
    scene_free(&s);
}

/* ---- SAH cost ------------------------------------------------------------------ */

/* Two unit right triangles in the z = 0 plane, 10 apart along x: root box
 * [0,11]x[0,1]x0 (half area 11), each child box [.,.+1]x[0,1]x0 (half area 1). */
static int two_far_tris(accel_scene *s)
{
    scene_builder b = {0};
    add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0));
    add_tri(&b, v3(10, 0, 0), v3(11, 0, 0), v3(10, 1, 0));
    return finish(&b, "two_far_tris", s);
}

TEST(bvh_sah_cost_hand_made)
{
    accel_scene s;
    if (!two_far_tris(&s)) return;
    for (size_t i = 0; i < 4; i++) {
        char spec[128];
        accel_build_stats st;
        /* split: ct*1 + ci*(1*1 + 1*1)/11 = 1 + 2/11 < leaf ci*2 = 2 */
        void *a = build(builders[i], &s, 1, &st);
        if (a) {
            CHECKF(fabs(st.sah_cost - (1.0 + 2.0 / 11.0)) < 1e-9, "%s: sah %.9g", builders[i], st.sah_cost);
            CHECK(st.depth == 2 && st.nodes == 4 && st.leaves == 2);
            accel_kind_bvh.destroy(a);
        }
        /* ct = 5: splitting costs 5 + 2/11 > 2: one leaf of two, cost ci*2*11/11 */
        snprintf(spec, sizeof spec, "%s,ct=5", builders[i]);
        a = build(spec, &s, 1, &st);
        if (a) {
            CHECKF(fabs(st.sah_cost - 2.0) < 1e-9, "%s: sah %.9g", spec, st.sah_cost);
            CHECK(st.depth == 1 && st.nodes == 1 && st.leaves == 1);
            accel_kind_bvh.destroy(a);
        }
        /* ...unless the leaf may hold one primitive only: 5 + 2*0.5/11 with ci = 0.5 */
        snprintf(spec, sizeof spec, "%s,ct=5,ci=0.5,leaf=1", builders[i]);
        a = build(spec, &s, 1, &st);
        if (a) {
            CHECKF(fabs(st.sah_cost - (5.0 + 1.0 / 11.0)) < 1e-9, "%s: sah %.9g", spec, st.sah_cost);
            accel_kind_bvh.destroy(a);
        }
    }
    scene_free(&s);

    /* One triangle: a root leaf, cost ci. */
    scene_builder b = {0};
    add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 1));
    if (finish(&b, "one", &s)) {
        accel_build_stats st;
        void *a = build("bvh:ci=3", &s, 1, &st);
        if (a) {
            CHECK(fabs(st.sah_cost - 3.0) < 1e-9 && st.depth == 1 && st.nodes == 1);
            accel_kind_bvh.destroy(a);
        }
        scene_free(&s);
    }

    /* bvh_sah_cost on a hand-written pool: root [0,2]^3 (half area 12),
     * children [0,1]^3 with 3 primitives and [1,2]x[0,1]x[0,2] with 1
     * (half areas 3 and 5): ct*12/12 + ci*(3*3 + 1*5)/12. */
    bvh_node n[4];
    memset(n, 0, sizeof n);
    float r0[6] = {0, 0, 0, 2, 2, 2}, r2[6] = {0, 0, 0, 1, 1, 1}, r3[6] = {1, 0, 0, 2, 1, 2};
    memcpy(n[0].bmin, r0, 12), memcpy(n[0].bmax, r0 + 3, 12);
    memcpy(n[2].bmin, r2, 12), memcpy(n[2].bmax, r2 + 3, 12);
    memcpy(n[3].bmin, r3, 12), memcpy(n[3].bmax, r3 + 3, 12);
    n[0].left_first = 2;
    n[2].count = 3;
    n[3].left_first = 3, n[3].count = 1;
    CHECK(fabs(bvh_sah_cost(n, 4, 1.0, 1.0) - (1.0 + 14.0 / 12.0)) < 1e-12);
    CHECK(fabs(bvh_sah_cost(n, 4, 2.0, 0.5) - (2.0 + 7.0 / 12.0)) < 1e-12);
    CHECK(bvh_sah_cost(n, 0, 1.0, 1.0) == 0.0);
}

TEST(bvh_sah_quality_order)
{
    /* On a real scene the exact sweep is at least as good as binning with
     * many bins, which is at least roughly as good as few bins; the SAH
     * builders beat the medians. Not a theorem (greedy top-down), so with
     * a little slack. */
    accel_scene s;
    if (!make_scene("slivers:tris=3000,slivers=100", &s)) return;
    double c[6];
    const char *specs[6] = {"bvh:build=sah", "bvh:bins=256", "bvh:bins=4", "bvh:bins=16,axes=1",
                            "bvh:build=mid", "bvh:build=median"};
    for (int i = 0; i < 6; i++) {
        accel_build_stats st;
        void *a = build(specs[i], &s, 1, &st);
        c[i] = a ? st.sah_cost : NAN;
        if (a) accel_kind_bvh.destroy(a);
    }
    CHECKF(c[0] <= c[1] * 1.02 && c[1] <= c[2] * 1.02, "sah %g, 256 bins %g, 4 bins %g", c[0], c[1], c[2]);
    CHECKF(c[0] < c[4] && c[0] < c[5], "sah %g, mid %g, median %g", c[0], c[4], c[5]);
    CHECKF(c[3] > 0 && isfinite(c[3]), "axes=1: %g", c[3]);
    scene_free(&s);
}

/* ---- determinism ----------------------------------------------------------------- */

/* 60000 triangles in the plane x = 0 (every centroid has x = 0, so the
 * binner drops that axis), spread 10 times longer along z than along y. */
static int flat_long_scene(accel_scene *s)
{
    scene_builder b = {0};
    for (int i = 0; i < 60000; i++) {
        vec3 p = v3(0.0f, frand(), 10.0f * frand());
        add_tri(&b, p, v3_add(p, v3(0, 0.01f, 0)), v3_add(p, v3(0, 0.003f, 0.02f)));
    }
    return finish(&b, "flat_long", s);
}

TEST(bvh_build_identical_for_any_thread_count)
{
    /* Large enough for the parallel top (binning with all threads, then
     * subtrees as tasks); the flat scene makes the binned axes differ from
     * 0, 1, 2 (a skipped axis, a longest axis z). */
    accel_scene flat;
    if (flat_long_scene(&flat)) {
        const char *specs[] = {"bvh", "bvh:axes=1", "bvh:build=sah"};
        for (size_t i = 0; i < 3; i++) {
            void *a1 = build(specs[i], &flat, 1, NULL), *a2 = build(specs[i], &flat, 2, NULL);
            if (a1 && a2) {
                uint32_t n1, n2;
                const bvh_node *x = bvh_nodes(a1, &n1), *y = bvh_nodes(a2, &n2);
                CHECKF(n1 == n2 && memcmp(x, y, n1 * sizeof *x) == 0,
                       "%s on flat_long: 2 threads build a different tree", specs[i]);
                check_pool(&flat, a2, 8, specs[i]);
            }
            if (a1) accel_kind_bvh.destroy(a1);
            if (a2) accel_kind_bvh.destroy(a2);
        }
        scene_free(&flat);
    }
    accel_scene s;
    if (!make_scene("soup:tris=60000", &s)) return;
    const char *specs[] = {"bvh:build=binned", "bvh:build=binned,axes=1,bins=2", "bvh:build=sah",
                           "bvh:build=mid", "bvh:build=median", "bvh:leaf=1"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        accel_build_stats st1;
        void *a1 = build(specs[i], &s, 1, &st1);
        if (!a1) continue;
        uint32_t nc1, pc1;
        const bvh_node *n1 = bvh_nodes(a1, &nc1);
        const uint32_t *p1 = bvh_prim_ids(a1, &pc1);
        for (int threads = 2; threads <= 3; threads++) {
            accel_build_stats st;
            void *a = build(specs[i], &s, threads, &st);
            if (!a) continue;
            uint32_t nc, pc;
            const bvh_node *n = bvh_nodes(a, &nc);
            const uint32_t *p = bvh_prim_ids(a, &pc);
            CHECKF(nc == nc1 && memcmp(n, n1, nc * sizeof *n) == 0, "%s: %d threads: node pools differ",
                   specs[i], threads);
            CHECKF(pc == pc1 && memcmp(p, p1, pc * sizeof *p) == 0, "%s: %d threads: leaf order differs",
                   specs[i], threads);
            CHECK(st.sah_cost == st1.sah_cost && st.depth == st1.depth);
            accel_kind_bvh.destroy(a);
        }
        accel_kind_bvh.destroy(a1);
    }
    scene_free(&s);
}

/* ---- degenerate inputs ---------------------------------------------------------------- */

TEST(bvh_coincident_primitives)
{
    /* 1000 copies of one triangle, plus 1000 different triangles sharing one
     * centroid: no axis can separate them; every builder must still end
     * (leaf=1 forces splits down to single primitives) within the depth bound. */
    scene_builder b = {0};
    for (int i = 0; i < 1000; i++) add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0));
    for (int i = 0; i < 1000; i++) {
        float a = 6.2831853f * (float)i / 1000.0f;
        vec3 p = v3(cosf(a), sinf(a), 0.25f), q = v3(-sinf(a), cosf(a), -0.5f);
        /* vertices p, q, -(p+q): centroid exactly 0 up to rounding of the sum */
        add_tri(&b, v3_add(p, v3(5, 5, 5)), v3_add(q, v3(5, 5, 5)),
                v3_add(v3_scale(v3_add(p, q), -1.0f), v3(5, 5, 5)));
    }
    accel_scene s;
    if (!finish(&b, "coincident", &s)) return;
    const char *extra[] = {"bvh:leaf=1", "bvh:build=sah,leaf=1", "bvh:build=mid,leaf=1",
                           "bvh:build=median,leaf=1", "bvh:bins=2,leaf=1", "bvh:axes=1,leaf=2"};
    for (size_t i = 0; i < 4 + 6; i++) {
        const char *spec = i < 4 ? builders[i] : extra[i - 4];
        accel_build_stats st;
        void *a = build(spec, &s, 2, &st);
        if (!a) continue;
        accel_params p;
        accel_error err;
        accel_params_parse(spec, &p, &err);
        check_pool(&s, a, (int)accel_param_num(&p, "leaf"), spec);
        CHECK(isfinite(st.sah_cost) && st.depth <= BVH_MAX_DEPTH);
        accel_ray *rays = random_rays(&s, 500);
        check_trace(&s, a, spec, rays, 500);
        free(rays);
        accel_kind_bvh.destroy(a);
    }
    scene_free(&s);
}

TEST(bvh_depth_bound)
{
    /* Triangles shrinking towards the origin, x = 1.5^-i: a middle split
     * or a two-bin split cuts off the largest two, and the SAH sweep cuts
     * off about as few: a tree of a hundred levels or more unless the
     * builder bounds the depth (without the bound this test trips the
     * driver's depth assertion or the depth check below). */
    scene_builder b = {0};
    float x = 1.0f;
    for (int i = 0; i < 200; i++, x /= 1.5f)
        add_tri(&b, v3(x, 0, 0), v3(1.2f * x, 0, 0), v3(x, 0.2f * x, 0.1f * x));
    accel_scene s;
    if (!finish(&b, "geometric", &s)) return;
    const char *specs[] = {"bvh:build=mid,leaf=1", "bvh:bins=2,leaf=1", "bvh:build=sah,leaf=1",
                           "bvh:build=sah,leaf=1,traverse=packet", "bvh:build=mid"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        accel_build_stats st;
        void *a = build(specs[i], &s, 1, &st);
        if (!a) continue;
        CHECKF(st.depth <= BVH_MAX_DEPTH && st.depth >= 9, "%s: depth %d", specs[i], st.depth);
        check_pool(&s, a, i == 4 ? 8 : 1, specs[i]);
        /* rays down onto every triangle, and along the row */
        accel_ray rays[400];
        float px = 1.0f;
        for (int k = 0; k < 200; k++, px /= 1.5f) {
            rays[2 * k] = (accel_ray){1.05f * px, 0.05f * px, 1.0f, 0.0f, 0.0f, 0.0f, -1.0f, INFINITY};
            rays[2 * k + 1] = (accel_ray){2.0f, 0.02f * px, 0.01f * px, 0.0f, -1.0f, 0.0f, 0.0f, INFINITY};
        }
        check_trace(&s, a, specs[i], rays, 400);
        accel_kind_bvh.destroy(a);
    }
    scene_free(&s);
}

TEST(bvh_empty_and_nonfinite)
{
    /* Only degenerate triangles: nothing to build, everything misses. */
    scene_builder b = {0};
    add_tri(&b, v3(0, 0, 0), v3(1, 1, 1), v3(2, 2, 2));
    accel_scene s;
    if (finish(&b, "degenerate", &s)) {
        for (size_t i = 0; i < 4; i++) {
            accel_build_stats st;
            void *a = build(builders[i], &s, 1, &st);
            if (!a) continue;
            CHECK(st.nodes == 0 && st.sah_cost == 0.0);
            accel_ray r = {0, 0, -1, 0, 0.1f, 0.1f, 1, INFINITY};
            accel_hit h;
            uint8_t o = 1;
            accel_kind_bvh.intersect(a, &r, &h, 1, NULL);
            accel_kind_bvh.occluded(a, &r, &o, 1, NULL);
            CHECK(h.prim == ACCEL_MISS && isinf(h.t) && o == 0);
            accel_kind_bvh.destroy(a);
        }
        scene_free(&s);
    }
    /* A triangle with an infinite or NaN vertex is never hit by the
     * reference; the BVH leaves it out instead of letting its box poison
     * the areas. */
    b = (scene_builder){0};
    for (int i = 0; i < 200; i++) {
        vec3 p = v3(frand(), frand(), frand());
        add_tri(&b, p, v3_add(p, v3(0.05f, 0, 0)), v3_add(p, v3(0, 0.05f, 0.02f)));
    }
    add_tri(&b, v3(0, 0, 0), v3(INFINITY, 0, 0), v3(0, 1, 0));
    add_tri(&b, v3(0, 0, NAN), v3(1, 0, 0), v3(0, 1, 0));
    if (finish(&b, "nonfinite", &s)) {
        for (size_t i = 0; i < 4; i++) {
            accel_build_stats st;
            void *a = build(builders[i], &s, 1, &st);
            if (!a) continue;
            CHECK(isfinite(st.sah_cost));
            CHECK(st.refs <= 200);
            accel_ray *rays = random_rays(&s, 400);
            check_trace(&s, a, builders[i], rays, 400);
            free(rays);
            accel_kind_bvh.destroy(a);
        }
        scene_free(&s);
    }
}

TEST(bvh_small_knobs_and_spheres)
{
    /* bins=2, leaf=1, extreme costs, on triangles and on a scene mixing
     * triangles and true spheres. */
    const char *scenes[] = {"soup:tris=2000", "sphereflake:level=2"};
    const char *specs[] = {"bvh:bins=2", "bvh:bins=2,axes=1", "bvh:leaf=1", "bvh:leaf=1,bins=2",
                           "bvh:ct=0", "bvh:ci=1000", "bvh:build=sah,ct=0.1",
                           "bvh:traverse=packet,leaf=1", "bvh:traverse=packet,frustum=1,bins=2"};
    for (size_t k = 0; k < 2; k++) {
        accel_scene s;
        if (!make_scene(scenes[k], &s)) continue;
        for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) check_spec(&s, specs[i], 1500);
        scene_free(&s);
    }
}

/* ---- packets ------------------------------------------------------------------ */

TEST(bvh_packets_mixed_rays)
{
    /* Packets need not be coherent: 64-ray groups that mix direction
     * signs, origins, zero components, invalid rays (NaN, zero direction,
     * t_near > t_far), and a batch length that is not a multiple of 64. */
    accel_scene s;
    if (!make_scene("tetra:level=5", &s)) return;
    size_t n = 64 * 9 + 37;
    accel_ray *rays = random_rays(&s, n);
    for (size_t i = 0; i < n; i += 17) rays[i].ox = NAN;
    for (size_t i = 5; i < n; i += 29) rays[i].dx = rays[i].dy = rays[i].dz = 0.0f;
    for (size_t i = 9; i < n; i += 31) rays[i].t_near = 2.0f, rays[i].t_far = 1.0f;
    /* one packet entirely invalid, one coherent (shared origin, same signs) */
    for (size_t i = 128; i < 192; i++) rays[i].dx = NAN;
    for (size_t i = 256; i < 320; i++) {
        rays[i] = (accel_ray){-3, 0.5f, 0.5f, 0, 1, 0.01f * (float)(i % 8), 0.01f * (float)(i / 8 % 8), INFINITY};
    }
    /* two packets of same-sign directions from spread-out origins (the
     * frustum test's interval case), one with finite t ranges */
    vec3 lo = s.bounds.min, ext = box3_extent(s.bounds);
    for (size_t i = 320; i < 448; i++) {
        vec3 o = v3_sub(lo, v3_mul(ext, v3(frand(), frand(), frand())));
        vec3 target = v3_add(lo, v3_mul(ext, v3(frand(), frand(), frand())));
        vec3 d = v3_sub(target, o);
        rays[i] = (accel_ray){o.x, o.y, o.z, 0.0f, d.x, d.y, d.z, i < 384 ? INFINITY : 0.9f + 0.2f * frand()};
    }
    const char *specs[] = {"bvh:traverse=packet", "bvh:traverse=packet,frustum=1",
                           "bvh:traverse=packet,frustum=1,build=sah,leaf=1"};
    for (size_t i = 0; i < 3; i++) {
        void *a = build(specs[i], &s, 1, NULL);
        if (!a) continue;
        check_trace(&s, a, specs[i], rays, n);
        /* and a batch shorter than one packet */
        check_trace(&s, a, specs[i], rays + 256, 10);
        accel_kind_bvh.destroy(a);
    }
    free(rays);
    scene_free(&s);
}

TEST(bvh_packets_primary_tiles)
{
    /* The packets' intended use: 8x8 tiles of primary rays, plus the
     * shadow rays of their hits (with and without the frustum test). */
    accel_scene s;
    if (!make_scene("sphereflake:level=2,spheres=0,segments=3", &s)) return;
    accel_error err = {0};
    rays_set pr = {0}, sh = {0};
    CHECK(rays_primary(&s.camera, 48, 40, &pr, &err) == 0);
    accel_hit *ref = malloc(pr.count * sizeof *ref);
    accel_reference_trace(&s, pr.rays, ref, pr.count, 2);
    CHECK(rays_shadow(&s, &pr, ref, &sh, &err) == 0);
    const char *specs[] = {"bvh:traverse=packet", "bvh:traverse=packet,frustum=1"};
    for (size_t i = 0; i < 2; i++) {
        void *a = build(specs[i], &s, 1, NULL);
        if (!a) continue;
        check_trace(&s, a, specs[i], pr.rays, pr.count);
        check_trace(&s, a, specs[i], sh.rays, sh.count);
        accel_kind_bvh.destroy(a);
    }
    free(ref);
    rays_free(&pr);
    rays_free(&sh);
    scene_free(&s);
}

/* ---- counters ---------------------------------------------------------------------- */

TEST(bvh_counters)
{
    accel_scene s;
    if (!make_scene("soup:tris=3000", &s)) return;
    size_t n = 1000;
    accel_ray *rays = random_rays(&s, n);
    const char *specs[] = {"bvh", "bvh:traverse=packet", "bvh:traverse=packet,frustum=1"};
    for (size_t i = 0; i < 3; i++) {
        void *a = build(specs[i], &s, 1, NULL);
        if (!a) continue;
        accel_hit *h0 = malloc(n * sizeof *h0), *h1 = malloc(n * sizeof *h1);
        uint32_t *steps = malloc(n * sizeof *steps), *prims = malloc(n * sizeof *prims);
        accel_counters c;
        memset(&c, 0, sizeof c);
        c.ray_steps = steps;
        c.ray_prims = prims;
        accel_kind_bvh.intersect(a, rays, h0, n, NULL);
        accel_kind_bvh.intersect(a, rays, h1, n, &c);
        CHECKF(memcmp(h0, h1, n * sizeof *h0) == 0, "%s: counted trace differs", specs[i]);
        uint64_t ss = 0, sp = 0;
        for (size_t k = 0; k < n; k++) ss += steps[k], sp += prims[k];
        CHECK(c.rays == n);
        CHECKF(ss == c.steps && sp == c.prim_tests, "%s: per-ray sums %llu/%llu vs %llu/%llu",
               specs[i], (unsigned long long)ss, (unsigned long long)sp,
               (unsigned long long)c.steps, (unsigned long long)c.prim_tests);
        CHECK(c.steps > 0 && c.box_tests > 0 && c.prim_tests > 0);
        /* every ray that hits tested at least one primitive and visited a leaf */
        for (size_t k = 0; k < n; k++)
            if (h0[k].prim != ACCEL_MISS) CHECK(steps[k] >= 1 && prims[k] >= 1);
        /* single rays: one root test, then two per interior node visited */
        if (i == 0) CHECK(c.box_tests <= c.rays + 2 * c.steps && c.box_tests > c.steps);
        if (i < 2) CHECK(c.packet_box_tests == 0);
        free(h0);
        free(h1);
        free(steps);
        free(prims);
        accel_kind_bvh.destroy(a);
    }
    free(rays);
    /* The frustum test runs on coherent packets (primary tiles) only. */
    accel_error err = {0};
    rays_set pr = {0};
    void *a = build("bvh:traverse=packet,frustum=1", &s, 1, NULL);
    if (a && rays_primary(&s.camera, 32, 32, &pr, &err) == 0) {
        accel_hit *h = malloc(pr.count * sizeof *h);
        accel_counters c;
        memset(&c, 0, sizeof c);
        accel_kind_bvh.intersect(a, pr.rays, h, pr.count, &c);
        CHECK(c.packet_box_tests > 0 && c.rays == pr.count);
        free(h);
    }
    rays_free(&pr);
    if (a) accel_kind_bvh.destroy(a);
    scene_free(&s);
}

/* ---- saving and loading ----------------------------------------------------------------- */

TEST(bvh_save_load)
{
    accel_scene s;
    if (!make_scene("sphereflake:level=2", &s)) return;
    void *a = build("bvh:traverse=packet", &s, 1, NULL);
    if (!a) { scene_free(&s); return; }
    char path[64];
    snprintf(path, sizeof path, "/tmp/gridbvh_test_%d.bvh", (int)getpid());
    accel_error err = {0};
    CHECKF(bvh_save(a, path, &err) == 0, "save: %s", err.msg);
    void *b = NULL;
    CHECKF(bvh_load(path, &b, &err) == 0, "load: %s", err.msg);
    if (b) {
        uint32_t n1, n2, p1, p2;
        const bvh_node *x = bvh_nodes(a, &n1), *y = bvh_nodes(b, &n2);
        CHECK(n1 == n2 && memcmp(x, y, n1 * sizeof *x) == 0);
        CHECK(((uintptr_t)y & 63) == 0);
        const uint32_t *i1 = bvh_prim_ids(a, &p1), *i2 = bvh_prim_ids(b, &p2);
        CHECK(p1 == p2 && memcmp(i1, i2, p1 * sizeof *i1) == 0);
        accel_ray *rays = random_rays(&s, 700);
        check_trace(&s, b, "loaded bvh", rays, 700);
        free(rays);
        accel_kind_bvh.destroy(b);
    }
    /* Point a child pair at another node's pair (two parents): refused. */
    uint32_t nc;
    const bvh_node *nodes = bvh_nodes(a, &nc);
    uint32_t victim = 0; /* an interior node whose pair is not 2 */
    for (uint32_t i = 2; i < nc && !victim; i++)
        if (!nodes[i].count && nodes[i].left_first != 2) victim = i;
    CHECK(victim != 0);
    FILE *f = fopen(path, "r+b");
    if (f && victim) {
        uint32_t two = 2;
        fseek(f, 32 + 32 * (long)victim + 12, SEEK_SET);
        fwrite(&two, 4, 1, f);
        fclose(f);
        b = NULL;
        CHECK(bvh_load(path, &b, &err) == ACCEL_ERR_PARSE && b == NULL);
        CHECK(bvh_save(a, path, &err) == 0); /* restore for the next case */
    } else if (f) {
        fclose(f);
    }
    /* Corrupt a child index: the loader refuses the file. */
    f = fopen(path, "r+b");
    if (f) {
        uint32_t bad = 1; /* node 0's left_first: odd, and the padding node */
        fseek(f, 32 + 12, SEEK_SET);
        fwrite(&bad, 4, 1, f);
        fclose(f);
        b = NULL;
        CHECK(bvh_load(path, &b, &err) == ACCEL_ERR_PARSE && b == NULL);
        CHECK(strstr(err.msg, "child") != NULL);
    }
    /* Truncated file. */
    f = fopen(path, "wb");
    if (f) {
        fwrite("BVH1", 1, 4, f);
        fclose(f);
        CHECK(bvh_load(path, &b, &err) == ACCEL_ERR_PARSE);
    }
    remove(path);
    CHECK(bvh_load("/nonexistent/x.bvh", &b, &err) == ACCEL_ERR_IO);
    accel_kind_bvh.destroy(a);
    scene_free(&s);
}

/* ---- spec errors ----------------------------------------------------------------------- */

TEST(bvh_spec_errors)
{
    accel_scene s;
    if (!make_scene("soup:tris=100", &s)) return;
    const char *bad[] = {"bvh:build=sah,bins=8", "bvh:build=mid,axes=1", "bvh:frustum=1",
                         "bvh:bins=1", "bvh:bins=257", "bvh:axes=2", "bvh:leaf=0", "bvh:build=fast",
                         "bvh:ci=0"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        accel_error err = {0};
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        int rc = accel_build_spec(bad[i], &s, 1, &k, &a, &st, &err);
        CHECKF(rc == ACCEL_ERR_SPEC && a == NULL, "%s: accepted (rc %d)", bad[i], rc);
        CHECKF(err.msg[0] != 0, "%s: no message", bad[i]);
    }
    scene_free(&s);
}

/* ---- the shared scanned meshes --------------------------------------------------------------- */

TEST(bvh_bunny)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_note("skipped: ../shared/scenes not found");
        return;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/bunny.off", dir);
    accel_scene s;
    if (!make_scene(path, &s)) return;
    const char *specs[] = {"bvh", "bvh:build=sah", "bvh:traverse=packet,frustum=1"};
    accel_error err = {0};
    rays_set pr = {0};
    CHECK(rays_primary(&s.camera, 24, 24, &pr, &err) == 0);
    accel_ray *rays = random_rays(&s, 300);
    for (size_t i = 0; i < 3; i++) {
        accel_build_stats st;
        void *a = build(specs[i], &s, 2, &st);
        if (!a) continue;
        check_pool(&s, a, 8, specs[i]);
        check_trace(&s, a, specs[i], pr.rays, pr.count);
        check_trace(&s, a, specs[i], rays, 300);
        accel_kind_bvh.destroy(a);
    }
    free(rays);
    rays_free(&pr);
    scene_free(&s);
}
