/*
 * test_igrid_blocks.c - the irregular grid's cells as blocks
 * (irregular_grid:cells=blocks, grid/grid_blocks.h): against the
 * reference, walking the very cells cells=ids walks, with the bytes the
 * blocks add and nothing else; a scene with spheres keeps its ids.
 */
#include <stdlib.h>
#include <string.h>

#include "irregular_grid/igrid.h"
#include "support.h"
#include "test.h"

/* Builds spec, checks it against the reference on rays (test_check_spec),
 * and returns its counters, bytes and, from the view, the blocks of 8 its
 * cells' lists make and the cell count. 0 when the build failed. */
static int run_spec(const accel_scene *s, const char *spec, const test_rays *r,
                    accel_counters *c, size_t *bytes, uint64_t *blocks, uint64_t *cells)
{
    accel_build_stats st;
    if (test_check_spec(s, spec, r->rays, r->count, NULL, &st, c)) return 0;
    const accel_kind *kind;
    void *a = test_build_kind(spec, s, 1, &kind, NULL);
    if (!a) return 0;
    CHECKF(st.bytes == kind->memory(a), "%s on %s: stats %zu bytes, memory %zu", spec, s->name,
           (size_t)st.bytes, kind->memory(a));
    const int lanes = strstr(spec, "cells=blocks") && s->sphere_count == 0 ? 8 : 0;
    CHECKF(st.test_lanes == lanes, "%s on %s: test_lanes %d, expected %d", spec, s->name,
           st.test_lanes, lanes);
    igrid_view v;
    igrid_get_view(a, &v);
    *bytes = st.bytes;
    *cells = v.cell_count;
    *blocks = 0;
    for (uint32_t k = 0; k < v.cell_count; k++)
        *blocks += (v.cells[k].end - v.cells[k].begin + 7u) / 8u;
    kind->destroy(a);
    return 1;
}

/* Within 0.1% (a hit's t may differ from the scalar test's in its last
 * bits, block_test.h, and end a ray one cell sooner or later when it lies
 * on a cell's exit plane: the cube's faces lie on cell planes). */
static int near(uint64_t a, uint64_t b)
{
    uint64_t d = a > b ? a - b : b - a;
    return d <= (a > b ? a : b) / 1000;
}

/* cells=blocks against cells=ids (without the mailbox, which blocks do
 * not have): the same cells visited, one test counted per reference of
 * each visited cell, 320 bytes per block of 8 and a block offset per cell
 * on top of the id lists. With spheres the blocks are not built: the
 * counts and bytes of cells=ids (its mailbox on) exactly. */
TEST(igrid_blocks_walk_the_same_cells)
{
    static const char *const scenes[] = {"soup:tris=3000,seed=5", "cube:n=6",
                                         "teapot_stadium:n=3,stadium=24,tiers=3",
                                         "mount:level=4", NULL};
    static const char *const params[] = {"", ",merge=0,expand=0",
                                         ",top_lambda=0.0001,max_depth=3,sub_lambda=1000",
                                         ",top_lambda=2,max_depth=2"};
    for (const char *const *sc = scenes; *sc; sc++) {
        accel_scene s;
        if (!test_make_scene(*sc, &s)) continue;
        test_rays r = {0};
        test_seed(4242);
        test_rays_random(&r, s.bounds, 1500);
        test_rays_inside(&r, s.bounds, 1500, 17);
        const int spheres = s.sphere_count > 0;
        for (size_t p = 0; p < sizeof params / sizeof params[0]; p++) {
            char ids[160], blk[160];
            snprintf(ids, sizeof ids, "irregular_grid:cells=ids%s%s", spheres ? "" : ",mailbox=0",
                     params[p]);
            snprintf(blk, sizeof blk, "irregular_grid:cells=blocks%s", params[p]);
            accel_counters c[2];
            size_t bytes[2];
            uint64_t blocks[2], cells[2];
            if (!run_spec(&s, ids, &r, &c[0], &bytes[0], &blocks[0], &cells[0]) ||
                !run_spec(&s, blk, &r, &c[1], &bytes[1], &blocks[1], &cells[1]))
                continue;
            CHECKF(cells[0] == cells[1] && c[0].steps > r.count / 2 && c[0].prim_tests > 0,
                   "%s on %s: %llu/%llu cells, %llu steps", blk, s.name,
                   (unsigned long long)cells[0], (unsigned long long)cells[1],
                   (unsigned long long)c[0].steps);
            CHECKF(spheres ? c[0].steps == c[1].steps && c[0].prim_tests == c[1].prim_tests &&
                                 c[0].mailbox_skips == c[1].mailbox_skips
                           : near(c[0].steps, c[1].steps) &&
                                 near(c[0].prim_tests, c[1].prim_tests) &&
                                 c[1].mailbox_skips == 0,
                   "%s on %s: steps %llu/%llu, tests %llu/%llu, skips %llu/%llu", blk, s.name,
                   (unsigned long long)c[0].steps, (unsigned long long)c[1].steps,
                   (unsigned long long)c[0].prim_tests, (unsigned long long)c[1].prim_tests,
                   (unsigned long long)c[0].mailbox_skips, (unsigned long long)c[1].mailbox_skips);
            const size_t extra = spheres ? 0 : (size_t)blocks[0] * 320 + (size_t)(cells[0] + 1) * 4;
            CHECKF(bytes[1] == bytes[0] + extra,
                   "%s on %s: %zu bytes, cells=ids %zu + %zu expected (%llu blocks, %llu cells)",
                   blk, s.name, bytes[1], bytes[0], extra, (unsigned long long)blocks[0],
                   (unsigned long long)cells[0]);
        }
        test_rays_free(&r);
        scene_free(&s);
    }
}

/* The blocks count against max_mb: at the smallest limit (whole MiB)
 * the id lists fit, the blocks (about 2.5 times as much here) are refused,
 * naming cells=ids as the way out. */
TEST(igrid_blocks_within_max_mb)
{
    accel_scene s;
    if (!test_make_scene("soup:tris=20000,seed=3", &s)) return;
    accel_error err = {0};
    int mb = 1;
    char spec[96];
    for (; mb <= 64; mb++) {
        snprintf(spec, sizeof spec, "irregular_grid:cells=ids,max_mb=%d", mb);
        if (test_build_rc(spec, &s, &err) == 0) break;
    }
    CHECKF(mb <= 64, "cells=ids does not fit 64 MiB: %s", err.msg);
    snprintf(spec, sizeof spec, "irregular_grid:cells=blocks,max_mb=%d", mb);
    int rc = test_build_rc(spec, &s, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "irregular_grid: ") == err.msg &&
               strstr(err.msg, "cells=ids"),
           "%s: rc %d, %s", spec, rc, err.msg);
    snprintf(spec, sizeof spec, "irregular_grid:cells=blocks,max_mb=%d", 4 * mb);
    CHECKF(test_build_rc(spec, &s, &err) == 0, "%s: %s", spec, err.msg);
    scene_free(&s);
}
