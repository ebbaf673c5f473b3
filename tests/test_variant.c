/*
 * test_variant.c - the one kernel-variant mechanism (core/variant.h) and
 * its step-bound policy: a broken structure is reported through the
 * counters and the library's error channel, never by abort(), and the
 * counted and timed copies agree.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/bvh.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"

/* A bvh whose interior node points back at the root loops for ever in a
 * traversal without a bound: the counted run must stop every ray at the
 * bound, record it, and accel_counters_status must name the kernel. */
TEST(variant_broken_tree_reported_not_aborted)
{
    accel_scene s;
    accel_error err = {0};
    if (!test_make_scene("soup:tris=24,seed=3", &s)) return;
    const accel_kind *k;
    void *a;
    accel_build_stats st;
    CHECKF(accel_build_spec("bvh:leaf=1", &s, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
    uint32_t node_count;
    bvh_node *nodes = (bvh_node *)bvh_nodes(a, &node_count);
    CHECK(node_count > 3 && node_count < 60); /* the pushes stay below the stack's depth */
    /* Every interior node's children become the root pair's: a cycle. */
    uint32_t interior = 0;
    for (uint32_t i = 2; i < node_count; i++)
        if (nodes[i].count == 0) {
            nodes[i].left_first = nodes[0].left_first;
            interior++;
        }
    CHECK(interior > 0);
    rays_set r;
    CHECK(rays_primary(&s.camera, 16, 16, &r, &err) == 0);
    accel_hit *hits = malloc(r.count * sizeof *hits);
    accel_counters c;
    memset(&c, 0, sizeof c);
    accel_trace(k, a, r.rays, hits, r.count, 2, &c);
    CHECKF(c.broken > 0, "the looping tree went unreported (%llu broken)",
           (unsigned long long)c.broken);
    CHECK(c.broken <= r.count);
    accel_error e2 = {0};
    CHECK(accel_counters_status(&c, &e2) == ACCEL_ERR_INTERNAL);
    CHECKF(strstr(e2.msg, "bvh_single.c") && strstr(e2.msg, "step bound"), "message: %s", e2.msg);
    /* An intact structure reports nothing. */
    k->destroy(a);
    CHECK(accel_build_spec("bvh:leaf=1", &s, 1, &k, &a, &st, &err) == 0);
    memset(&c, 0, sizeof c);
    accel_trace(k, a, r.rays, hits, r.count, 2, &c);
    CHECK(c.broken == 0);
    CHECK(accel_counters_status(&c, &e2) == 0);
    k->destroy(a);
    free(hits);
    rays_free(&r);
    scene_free(&s);
}

/* Every kind builds over the primitive store: the scene may be freed as
 * soon as build returns (the ownership rule of accel.h), and the answers
 * do not change. */
TEST(variant_structure_outlives_scene)
{
    for (size_t i = 0; i < accel_kind_count; i++) {
        const accel_kind *kind = accel_kinds[i];
        if (!test_kind_selected(kind->name)) continue;
        if (!strcmp(kind->name, "instanced")) continue; /* follows a caller-owned scene (accel.h) */
        accel_scene s;
        accel_error err = {0};
        if (!test_make_scene("sphereflake:level=1", &s)) continue;
        rays_set r;
        CHECK(rays_primary(&s.camera, 24, 24, &r, &err) == 0);
        accel_hit *ref = malloc(r.count * sizeof *ref), *hits = malloc(r.count * sizeof *hits);
        const accel_kind *k;
        void *a;
        accel_build_stats st;
        CHECKF(accel_build_spec(kind->name, &s, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
        accel_trace(k, a, r.rays, ref, r.count, 1, NULL);
        /* Poison and free the scene before tracing. */
        memset(s.tris, 0xFF, (size_t)s.tri_count * 9 * sizeof(float));
        memset(s.spheres, 0xFF, (size_t)s.sphere_count * 4 * sizeof(float));
        scene_free(&s);
        accel_trace(k, a, r.rays, hits, r.count, 1, NULL);
        size_t differ = 0, hit = 0;
        for (size_t j = 0; j < r.count; j++) {
            differ += memcmp(&hits[j], &ref[j], sizeof hits[j]) != 0;
            hit += ref[j].prim != ACCEL_MISS;
        }
        CHECK(hit > r.count / 4);
        CHECKF(differ == 0, "%s: %zu of %zu rays changed once the scene was freed", kind->name,
               differ, r.count);
        k->destroy(a);
        free(ref);
        free(hits);
        rays_free(&r);
    }
}
