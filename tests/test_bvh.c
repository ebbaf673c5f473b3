/*
 * test_bvh.c - the BVH's node layout and pool invariants for every builder
 * (test_bvh_check_pool, shared with the other test_bvh_*.c files through
 * test_bvh.h), byte-identical builds for 1, 2 and 3 threads, and the shared
 * scanned meshes. SAH costs are in test_bvh_sah.c, degenerate inputs in
 * test_bvh_degenerate.c, packets, counters and saving in
 * test_bvh_packets.c. Every trace is compared against the double-precision
 * reference with the FORMATS.md rule.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "test_bvh.h"

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
void test_bvh_check_pool(const accel_scene *s, const void *a, int max_leaf, const char *spec)
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
        if (seen[i]++) {
            bad = 1;
            test_fail(__FILE__, __LINE__, "%s: node %u reached twice", spec, i);
            break;
        }
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

const char *const test_bvh_builders[TEST_BVH_BUILDERS] = {"bvh:build=binned", "bvh:build=sah",
                                                          "bvh:build=mid", "bvh:build=median"};

/* ---- layout ------------------------------------------------------------------- */

_Static_assert(sizeof(bvh_node) == 32, "32-byte node");
_Static_assert(_Alignof(bvh_node) == 4, "no hidden alignment padding");
_Static_assert(BVH_NODE_ALIGN % (2 * sizeof(bvh_node)) == 0,
               "a sibling pair fits one aligned line");

TEST(bvh_layout_every_builder)
{
    accel_scene s;
    if (!test_make_scene("soup:tris=5000", &s)) return;
    const char *extra[] = {"bvh:leaf=1", "bvh:build=sah,leaf=1", "bvh:leaf=3,bins=2",
                           "bvh:ct=0,leaf=256", "bvh:axes=1,bins=256"};
    for (size_t i = 0; i < 4 + 5; i++) {
        const char *spec = i < 4 ? test_bvh_builders[i] : extra[i - 4];
        accel_params p;
        accel_error err;
        CHECK(accel_params_parse(spec, &p, &err) == 0);
        accel_build_stats st;
        void *a = test_build(spec, &s, 1, &st);
        if (!a) continue;
        test_bvh_check_pool(&s, a, ACCEL_SPEC(&p, bvh_spec)->leaf, spec);
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

/* ---- determinism ----------------------------------------------------------------- */

/* 60000 triangles in the plane x = 0 (every centroid has x = 0, so the
 * binner drops that axis), spread 10 times longer along z than along y. */
static int flat_long_scene(accel_scene *s)
{
    scene_builder b = {0};
    for (int i = 0; i < 60000; i++) {
        vec3 p = v3(0.0f, test_rand(), 10.0f * test_rand());
        test_add_tri(&b, p, v3_add(p, v3(0, 0.01f, 0)), v3_add(p, v3(0, 0.003f, 0.02f)));
    }
    return test_finish(&b, "flat_long", s);
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
            void *a1 = test_build(specs[i], &flat, 1, NULL),
                 *a2 = test_build(specs[i], &flat, 2, NULL);
            if (a1 && a2) {
                uint32_t n1, n2;
                const bvh_node *x = bvh_nodes(a1, &n1), *y = bvh_nodes(a2, &n2);
                CHECKF(n1 == n2 && memcmp(x, y, n1 * sizeof *x) == 0,
                       "%s on flat_long: 2 threads build a different tree", specs[i]);
                test_bvh_check_pool(&flat, a2, 8, specs[i]);
            }
            if (a1) accel_kind_bvh.destroy(a1);
            if (a2) accel_kind_bvh.destroy(a2);
        }
        scene_free(&flat);
    }
    accel_scene s;
    if (!test_make_scene("soup:tris=60000", &s)) return;
    const char *specs[] = {"bvh:build=binned", "bvh:build=binned,axes=1,bins=2",
                           "bvh:build=sah",    "bvh:build=mid",
                           "bvh:build=median", "bvh:leaf=1"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        accel_build_stats st1;
        void *a1 = test_build(specs[i], &s, 1, &st1);
        if (!a1) continue;
        uint32_t nc1, pc1;
        const bvh_node *n1 = bvh_nodes(a1, &nc1);
        const uint32_t *p1 = bvh_prim_ids(a1, &pc1);
        for (int threads = 2; threads <= 3; threads++) {
            accel_build_stats st;
            void *a = test_build(specs[i], &s, threads, &st);
            if (!a) continue;
            uint32_t nc, pc;
            const bvh_node *n = bvh_nodes(a, &nc);
            const uint32_t *p = bvh_prim_ids(a, &pc);
            CHECKF(nc == nc1 && memcmp(n, n1, nc * sizeof *n) == 0,
                   "%s: %d threads: node pools differ", specs[i], threads);
            CHECKF(pc == pc1 && memcmp(p, p1, pc * sizeof *p) == 0,
                   "%s: %d threads: leaf order differs", specs[i], threads);
            CHECK(st.sah_cost == st1.sah_cost && st.depth == st1.depth);
            accel_kind_bvh.destroy(a);
        }
        accel_kind_bvh.destroy(a1);
    }
    scene_free(&s);
}

/* ---- the shared scanned meshes --------------------------------------------------------------- */

TEST(bvh_bunny)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_skip("../shared/scenes not found");
        return;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/bunny.off", dir);
    accel_scene s;
    if (!test_make_scene(path, &s)) return;
    const char *specs[] = {"bvh", "bvh:build=sah", "bvh:traverse=packet,frustum=1"};
    accel_error err = {0};
    rays_set pr = {0};
    CHECK(rays_primary(&s.camera, 24, 24, &pr, &err) == 0);
    test_rays r = {0};
    test_rays_random(&r, s.bounds, 300);
    accel_ray *rays = r.rays;
    for (size_t i = 0; i < 3; i++) {
        accel_build_stats st;
        void *a = test_build(specs[i], &s, 2, &st);
        if (!a) continue;
        test_bvh_check_pool(&s, a, 8, specs[i]);
        test_check_accel(&s, &accel_kind_bvh, a, specs[i], pr.rays, pr.count, NULL, NULL);
        test_check_accel(&s, &accel_kind_bvh, a, specs[i], rays, 300, NULL, NULL);
        accel_kind_bvh.destroy(a);
    }
    test_rays_free(&r);
    rays_free(&pr);
    scene_free(&s);
}
