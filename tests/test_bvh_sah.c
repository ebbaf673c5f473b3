/*
 * test_bvh_sah.c - the BVH's SAH cost on hand-made scenes and pools, the
 * termination rule, the quality order of the builders, small and extreme
 * knobs on triangles and spheres, and spec errors.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "test_bvh.h"

/* ---- SAH cost ------------------------------------------------------------------ */

/* Two unit right triangles in the z = 0 plane, 10 apart along x: root box
 * [0,11]x[0,1]x0 (half area 11), each child box [.,.+1]x[0,1]x0 (half area 1). */
static int two_far_tris(accel_scene *s)
{
    scene_builder b = {0};
    test_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0));
    test_add_tri(&b, v3(10, 0, 0), v3(11, 0, 0), v3(10, 1, 0));
    return test_finish(&b, "two_far_tris", s);
}

/* The stored boxes are the primitives' bounds grown by 2^-22 of each
 * coordinate plus 2^-40 of the scene's size (split_common.h: so that the
 * box test never rejects a hit the exact triangle test claims): costs match
 * the hand computation to about 1e-6. */
#define SAH_TOL 1e-5

TEST(bvh_sah_cost_hand_made)
{
    accel_scene s;
    if (!two_far_tris(&s)) return;
    for (size_t i = 0; i < 4; i++) {
        char spec[128];
        accel_build_stats st;
        /* split: ct*1 + ci*(1*1 + 1*1)/11 = 1 + 2/11 < leaf ci*2 = 2 */
        void *a = test_build(test_bvh_builders[i], &s, 1, &st);
        if (a) {
            CHECKF(fabs(st.sah_cost - (1.0 + 2.0 / 11.0)) < SAH_TOL, "%s: sah %.9g",
                   test_bvh_builders[i], st.sah_cost);
            CHECK(st.depth == 2 && st.nodes == 4 && st.leaves == 2);
            accel_kind_bvh.destroy(a);
        }
        /* ct = 5: splitting costs 5 + 2/11 > 2: one leaf of two, cost ci*2*11/11 */
        snprintf(spec, sizeof spec, "%s,ct=5", test_bvh_builders[i]);
        a = test_build(spec, &s, 1, &st);
        if (a) {
            CHECKF(fabs(st.sah_cost - 2.0) < SAH_TOL, "%s: sah %.9g", spec, st.sah_cost);
            CHECK(st.depth == 1 && st.nodes == 1 && st.leaves == 1);
            accel_kind_bvh.destroy(a);
        }
        /* ...unless the leaf may hold one primitive only: 5 + 2*0.5/11 with ci = 0.5 */
        snprintf(spec, sizeof spec, "%s,ct=5,ci=0.5,leaf=1", test_bvh_builders[i]);
        a = test_build(spec, &s, 1, &st);
        if (a) {
            CHECKF(fabs(st.sah_cost - (5.0 + 1.0 / 11.0)) < SAH_TOL, "%s: sah %.9g", spec,
                   st.sah_cost);
            accel_kind_bvh.destroy(a);
        }
    }
    scene_free(&s);

    /* One triangle: a root leaf, cost ci. */
    scene_builder b = {0};
    test_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 1));
    if (test_finish(&b, "one", &s)) {
        accel_build_stats st;
        void *a = test_build("bvh:ci=3", &s, 1, &st);
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
    if (!test_make_scene("slivers:tris=3000,slivers=100", &s)) return;
    double c[6];
    const char *specs[6] = {"bvh:build=sah",      "bvh:bins=256",  "bvh:bins=4",
                            "bvh:bins=16,axes=1", "bvh:build=mid", "bvh:build=median"};
    for (int i = 0; i < 6; i++) {
        accel_build_stats st;
        void *a = test_build(specs[i], &s, 1, &st);
        c[i] = a ? st.sah_cost : NAN;
        if (a) accel_kind_bvh.destroy(a);
    }
    CHECKF(c[0] <= c[1] * 1.02 && c[1] <= c[2] * 1.02, "sah %g, 256 bins %g, 4 bins %g", c[0], c[1],
           c[2]);
    CHECKF(c[0] < c[4] && c[0] < c[5], "sah %g, mid %g, median %g", c[0], c[4], c[5]);
    CHECKF(c[3] > 0 && isfinite(c[3]), "axes=1: %g", c[3]);
    scene_free(&s);
}

TEST(bvh_small_knobs_and_spheres)
{
    /* bins=2, leaf=1, extreme costs, on triangles and on a scene mixing
     * triangles and true spheres. */
    const char *scenes[] = {"soup:tris=2000", "sphereflake:level=2"};
    const char *specs[] = {"bvh:bins=2",
                           "bvh:bins=2,axes=1",
                           "bvh:leaf=1",
                           "bvh:leaf=1,bins=2",
                           "bvh:ct=0",
                           "bvh:ci=1000",
                           "bvh:build=sah,ct=0.1",
                           "bvh:traverse=packet,leaf=1",
                           "bvh:traverse=packet,frustum=1,bins=2"};
    for (size_t k = 0; k < 2; k++) {
        accel_scene s;
        if (!test_make_scene(scenes[k], &s)) continue;
        test_rays r = {0};
        test_rays_random(&r, s.bounds, 1500);
        accel_hit *ref = test_oracle_hits(&s, r.rays, r.count, TEST_ORACLE_REFERENCE);
        for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++)
            test_check_spec(&s, specs[i], r.rays, r.count, ref, NULL, NULL);
        free(ref);
        test_rays_free(&r);
        scene_free(&s);
    }
}

/* ---- spec errors ----------------------------------------------------------------------- */

TEST(bvh_spec_errors)
{
    accel_scene s;
    if (!test_make_scene("soup:tris=100", &s)) return;
    const char *bad[] = {"bvh:build=sah,bins=8", "bvh:build=mid,axes=1", "bvh:frustum=1",
                         "bvh:bins=1",           "bvh:bins=257",         "bvh:axes=2",
                         "bvh:leaf=0",           "bvh:build=fast",       "bvh:ci=0"};
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

/* ---- clustered centroids: the teapot in the stadium ------------------------------ */

/* Triangles below `node` in the set (in[id]) and outside it; a tree is
 * at most 64 levels deep (BVH_MAX_DEPTH), so the stack cannot overflow. */
static void subtree_counts(const bvh_node *n, const uint32_t *ids, const uint8_t *in, uint32_t node,
                           uint32_t *inside, uint32_t *others)
{
    uint32_t stack[2 * 64 + 2], sp = 0;
    *inside = *others = 0;
    stack[sp++] = node;
    while (sp) {
        const bvh_node *y = &n[stack[--sp]];
        if (y->count) {
            for (uint32_t k = 0; k < y->count; k++) {
                int i = in[ids[y->left_first + k]];
                *inside += (uint32_t)i, *others += (uint32_t)!i;
            }
        } else {
            stack[sp++] = y->left_first, stack[sp++] = y->left_first + 1;
        }
    }
}

/* Triangles outside the set below the lowest node that holds all `want`
 * triangles of the set. */
static uint32_t lca_others(const bvh_node *n, const uint32_t *ids, const uint8_t *in, uint32_t want)
{
    uint32_t node = 0, inside, others;
    for (;;) {
        const bvh_node *x = &n[node];
        if (x->count) break;
        subtree_counts(n, ids, in, x->left_first, &inside, &others);
        if (inside == want) {
            node = x->left_first;
            continue;
        }
        subtree_counts(n, ids, in, x->left_first + 1, &inside, &others);
        if (inside != want) break;
        node = x->left_first + 1;
    }
    subtree_counts(n, ids, in, node, &inside, &others);
    return others;
}

/* teapot_stadium: 65,280 teapot triangles (84% of the scene) within a few
 * units of the centre of a stadium 8000 units across. With 16 bins the
 * root's best bin plane kept the first tier of the stands (512 triangles)
 * with the teapot, and the next cut the teapot in half, so that rays to one
 * half first tested the floor under the other. Binning the fullest bin
 * again (build_binned.c, refine_cluster) keeps the teapot whole, as the
 * full sweep does: the lowest node holding all of it holds only the floor
 * fan besides (128 triangles, each touching the field's centre, which no
 * centroid plane can part from the teapot). Exact answers either way. */
TEST(bvh_binned_keeps_a_clustered_object_whole)
{
    accel_scene s;
    if (!test_make_scene("teapot_stadium", &s)) return;
    uint8_t *in = calloc(s.tri_count, 1);
    uint32_t want = 0;
    for (uint32_t i = 0; in && i < s.tri_count; i++) {
        const float *t = s.tris + 9 * (size_t)i;
        int near = 1;
        for (int k = 0; k < 3; k++)
            near &= fabsf(t[3 * k]) < 10 && fabsf(t[3 * k + 1]) < 10 && t[3 * k + 2] > -0.005f;
        in[i] = (uint8_t)near;
        want += (uint32_t)near;
    }
    CHECKF(want == 65280, "%u teapot triangles, want 65280", want);
    const char *specs[2] = {"bvh", "bvh:build=sah"};
    for (int i = 0; in && i < 2; i++) {
        void *a = test_build(specs[i], &s, 1, NULL);
        if (!a) continue;
        uint32_t nc, pc;
        const bvh_node *n = bvh_nodes(a, &nc);
        const uint32_t *ids = bvh_prim_ids(a, &pc);
        uint32_t others = lca_others(n, ids, in, want);
        CHECKF(others <= 128, "%s: the lowest node holding the whole teapot holds %u stadium triangles",
               specs[i], others);
        accel_kind_bvh.destroy(a);
    }
    /* the refined splits' trees answer exactly */
    rays_set prim;
    accel_error err = {0};
    if (rays_primary(&s.camera, 48, 36, &prim, &err) == 0) {
        test_check_spec(&s, "bvh", prim.rays, prim.count, NULL, NULL, NULL);
        test_check_spec(&s, "bvh:width=8", prim.rays, prim.count, NULL, NULL, NULL);
        rays_free(&prim);
    } else {
        CHECKF(0, "primary rays: %s", err.msg);
    }
    free(in);
    scene_free(&s);
}
