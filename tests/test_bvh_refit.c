/*
 * test_bvh_refit.c - the `bvh` kind's update (bvh/bvh_refit.c): a tree
 * built at frame 0 of the animated scene and refit frame by frame answers
 * exactly what the oracle answers on the new frame, for the binary and
 * wide trees, packets and the spatial-split builder; a refit that leaves
 * the boxes stale is caught; other primitive counts are refused.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/bvh.h"
#include "rays/rays.h"
#include "support.h"
#include "test.h"
#include "test_instanced.h"

#define ANIM "animated:instances=8,detail=2"

static int make_frame(int frame, accel_scene *s)
{
    char spec[128];
    snprintf(spec, sizeof spec, ANIM ",frame=%d", frame);
    accel_error err = {0};
    int rc = scene_create(spec, s, &err);
    CHECKF(rc == 0, "%s: %s", spec, err.msg);
    return rc == 0;
}

/* Camera rays (64-ray tiles, so packets are exercised) and the stiff rays
 * of test_instanced.c (at vertices and edge midpoints, shadow rays). */
static void frame_rays(const accel_scene *s, ray_list *l)
{
    inst_make_rays(s, l);
    rays_set p;
    accel_error err = {0};
    if (rays_primary(&s->camera, 48, 48, &p, &err) != 0) {
        CHECKF(0, "%s", err.msg);
        return;
    }
    accel_ray *r = realloc(l->r, (l->n + p.count) * sizeof *r);
    CHECK(r != NULL);
    if (r) {
        memcpy(r + l->n, p.rays, p.count * sizeof *r);
        l->r = r;
        l->n += p.count;
    }
    rays_free(&p);
}

/* Bad rays (holes, false hits, disagreements, occlusion mismatches) of a
 * built structure on scene s against the reference; *holes gets the holes. */
static size_t bad_rays(const accel_kind *k, const void *a, const accel_scene *s, size_t *holes)
{
    ray_list l = {0};
    frame_rays(s, &l);
    accel_hit *ref = test_oracle_hits(s, l.r, l.n, TEST_ORACLE_REFERENCE);
    size_t bad = l.n ? l.n : 1;
    if (ref) {
        test_diff d = test_trace_diff(k, a, l.r, l.n, ref, 1, NULL, NULL);
        bad = test_diff_bad(&d);
        if (holes) *holes = d.holes;
    }
    CHECK(l.n > 1000);
    free(ref);
    free(l.r);
    return bad;
}

static const char *const refit_specs[] = {
    "bvh", "bvh:width=4", "bvh:width=8", "bvh:width=8,traverse=packet", "bvh:build=sbvh",
    "bvh:traverse=packet", NULL,
};

TEST(bvh_refit_frames_match_oracle)
{
    for (const char *const *spec = refit_specs; *spec; spec++) {
        accel_scene s;
        if (!make_frame(0, &s)) return;
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        accel_error err = {0};
        int rc = accel_build_spec(*spec, &s, 1, &k, &a, &st, &err);
        scene_free(&s); /* the tree copies what it traverses */
        CHECKF(rc == 0, "%s: %s", *spec, err.msg);
        if (rc) continue;
        CHECK(k->update != NULL);
        for (int f = 1; f <= 20; f++) {
            if (!make_frame(f, &s)) break;
            accel_update_stats us;
            rc = k->update(a, &s, 1, &us, &err);
            CHECKF(rc == 0, "%s frame %d: %s", *spec, f, err.msg);
            CHECKF(us.meshes_refit == 1 && us.meshes_rebuilt == 0, "%s frame %d: refit %u rebuilt %u",
                   *spec, f, us.meshes_refit, us.meshes_rebuilt);
            if (f == 1 || f == 7 || f == 20) {
                size_t bad = bad_rays(k, a, &s, NULL);
                CHECKF(bad == 0, "%s refit to frame %d: %zu bad rays", *spec, f, bad);
            }
            scene_free(&s);
        }
        k->destroy(a);
    }
}

/* The refit without its box pass: the primitives moved out of their old
 * boxes, so rays miss them. Shows the test above can fail. */
TEST(bvh_refit_stale_boxes_show_holes)
{
    const char *const specs[] = {"bvh", "bvh:width=8,traverse=packet"};
    for (int i = 0; i < 2; i++) {
        accel_scene s0, s1;
        if (!make_frame(0, &s0)) return;
        if (!make_frame(20, &s1)) return;
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        accel_error err = {0};
        CHECKF(accel_build_spec(specs[i], &s0, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
        if (a) {
            bvh_refit_stale(a, &s1);
            size_t holes = 0, bad = bad_rays(k, a, &s1, &holes);
            CHECKF(holes > 100 && bad >= holes, "%s, stale boxes: %zu holes, %zu bad", specs[i],
                   holes, bad);
            /* The real update repairs it. */
            accel_update_stats us;
            CHECK(k->update(a, &s1, 1, &us, &err) == 0);
            CHECK(bad_rays(k, a, &s1, NULL) == 0);
            k->destroy(a);
        }
        scene_free(&s0);
        scene_free(&s1);
    }
}

/* refit = 0 rebuilds; another primitive count is refused, and the tree
 * still answers the scene it was built on. */
TEST(bvh_refit_rebuild_and_refusal)
{
    accel_scene s0, s1, other;
    accel_error err = {0};
    if (!make_frame(0, &s0) || !make_frame(9, &s1)) return;
    CHECK(scene_create("animated:instances=9,detail=2", &other, &err) == 0);
    CHECK(other.tri_count != s0.tri_count);
    const accel_kind *k;
    void *a = NULL;
    accel_build_stats st;
    CHECKF(accel_build_spec("bvh:width=4", &s0, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
    if (a) {
        accel_update_stats us;
        err.msg[0] = 0;
        int rc = k->update(a, &other, 1, &us, &err);
        CHECK(rc == ACCEL_ERR_SPEC && err.code == ACCEL_ERR_SPEC);
        CHECKF(strstr(err.msg, "same primitive counts") != NULL, "message: %s", err.msg);
        CHECK(bad_rays(k, a, &s0, NULL) == 0);
        CHECK(k->update(a, &other, 0, &us, &err) == ACCEL_ERR_SPEC);
        CHECKF(k->update(a, &s1, 0, &us, &err) == 0, "%s", err.msg);
        CHECK(us.meshes_rebuilt == 1 && us.meshes_refit == 0);
        CHECK(bad_rays(k, a, &s1, NULL) == 0);
        k->destroy(a);
    }
    scene_free(&s0);
    scene_free(&s1);
    scene_free(&other);
}
