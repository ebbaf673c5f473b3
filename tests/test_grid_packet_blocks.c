/*
 * test_grid_packet_blocks.c - the packet walks of grid and nested_grid on
 * blocks (cells=blocks, grid_packet_test_blocks in grid/grid_packet_walk.h):
 * against the reference on primary and shadow rays, walking the packets
 * through the very cells the per-id packet walk visits (the same cells and
 * filter evaluations), with the block test as the only difference.
 */
#include <stdlib.h>
#include <string.h>

#include "rays/rays.h"
#include "support.h"
#include "test.h"

/* Within 1% (a block test's t may differ from the scalar test's in its
 * last bits and retire a ray a slice sooner or later). */
static int near1(uint64_t a, uint64_t b)
{
    uint64_t d = a > b ? a - b : b - a;
    return d <= (a > b ? a : b) / 100;
}

/* ids and blocks, the same structure otherwise: both against the
 * reference, then the counters and bytes compared. */
static void compare_pair(const accel_scene *s, const char *ids, const char *blk,
                         const rays_set *r, const accel_hit *ref, const char *set)
{
    accel_build_stats st[2];
    accel_counters c[2];
    const char *spec[2] = {ids, blk};
    for (int i = 0; i < 2; i++)
        if (test_check_spec(s, spec[i], r->rays, r->count, ref, &st[i], &c[i])) return;
    /* Each (ray, triangle) pair the filter keeps is a ray tested against
     * the triangle's block: at least one test per pair, at most 8. The
     * filter runs on primary rays (shadow rays from a soup may all fall
     * back to single rays). */
    CHECKF((c[1].packet_box_tests > 0 || strcmp(set, "primary")) && near1(c[0].packet_box_tests, c[1].packet_box_tests) &&
               near1(c[0].steps, c[1].steps) && c[1].prim_tests >= c[0].prim_tests * 99 / 100 &&
               c[1].prim_tests <= 8 * c[0].prim_tests + r->count,
           "%s on %s, %s rays: filter %llu/%llu, steps %llu/%llu, tests %llu/%llu", blk, s->name,
           set, (unsigned long long)c[0].packet_box_tests,
           (unsigned long long)c[1].packet_box_tests, (unsigned long long)c[0].steps,
           (unsigned long long)c[1].steps, (unsigned long long)c[0].prim_tests,
           (unsigned long long)c[1].prim_tests);
    /* The blocks: at least 40 bytes per reference (36 of vertices and an
     * id per lane) on top of the id lists. */
    CHECKF(st[1].refs == st[0].refs && st[1].bytes >= st[0].bytes + 40 * st[0].refs,
           "%s on %s: %llu bytes, %llu with ids, %llu references", blk, s->name,
           (unsigned long long)st[1].bytes, (unsigned long long)st[0].bytes,
           (unsigned long long)st[0].refs);
}

TEST(grid_packet_blocks_same_walk_as_ids)
{
    static const char *const scenes[] = {"sphere:segments=16", "teapot_stadium:n=4,stadium=32",
                                         "soup:tris=4000,seed=2", NULL};
    static const char *const pairs[][2] = {
        {"grid:traverse=packet,cells=ids", "grid:traverse=packet"},
        {"grid:traverse=packet,cells=ids,mailbox=0,res=48",
         "grid:traverse=packet,mailbox=0,res=48"},
        {"nested_grid:traverse=packet", "nested_grid:traverse=packet,cells=blocks"},
        {"nested_grid:traverse=packet,threshold=1,depth=3,sub_res=3",
         "nested_grid:traverse=packet,cells=blocks,threshold=1,depth=3,sub_res=3"}};
    for (const char *const *sc = scenes; *sc; sc++) {
        accel_scene s;
        if (!test_make_scene(*sc, &s)) continue;
        accel_error err = {0};
        rays_set prim = {0}, shadow = {0};
        accel_hit *ref = NULL, *sref = NULL;
        int ok = rays_primary(&s.camera, 48, 48, &prim, &err) == 0;
        if (ok) ok = (ref = malloc(prim.count * sizeof *ref)) != NULL;
        if (ok) {
            accel_reference_trace(&s, prim.rays, ref, prim.count, 1);
            ok = rays_shadow(&s, &prim, ref, &shadow, &err) == 0;
        }
        if (ok) ok = (sref = malloc((shadow.count ? shadow.count : 1) * sizeof *sref)) != NULL;
        if (ok) accel_reference_trace(&s, shadow.rays, sref, shadow.count, 1);
        CHECKF(ok, "%s: rays: %s", *sc, err.msg);
        for (size_t p = 0; ok && p < sizeof pairs / sizeof pairs[0]; p++) {
            compare_pair(&s, pairs[p][0], pairs[p][1], &prim, ref, "primary");
            compare_pair(&s, pairs[p][0], pairs[p][1], &shadow, sref, "shadow");
        }
        free(ref);
        free(sref);
        rays_free(&prim);
        rays_free(&shadow);
        scene_free(&s);
    }
}
