/*
 * test_ngrid_compact.c - the nested grid's compact two-level layout
 * (`nested_grid:layout=compact`, nested_grid/ngrid_compact.c): against the
 * reference oracle on the stiff cases and built-in scenes, hit for hit and
 * counter for counter the same walk as the word layout at depth=2, fewer
 * bytes where the word layout pays a node and planes per sub-grid, and its
 * refusals (other depths, max_mb).
 */
#include <stdlib.h>
#include <string.h>

#include "rays/stiff.h"
#include "test_ngrid.h"

static const char *const compact_specs[][2] = {
    /* word layout, compact layout of the same structure */
    {"nested_grid:depth=2", "nested_grid:layout=compact"},
    {"nested_grid:depth=2,threshold=0,sub_res=5", "nested_grid:layout=compact,threshold=0,sub_res=5"},
    {"nested_grid:depth=2,threshold=2,mailbox=0,overlap=bbox",
     "nested_grid:layout=compact,threshold=2,mailbox=0,overlap=bbox"},
    {"nested_grid:depth=2,auto", "nested_grid:layout=compact,auto"},
};
#define COMPACT_PAIRS (sizeof compact_specs / sizeof compact_specs[0])

/* Both layouts against the oracle's ref (NULL: the reference) on rays, and
 * against each other: the same counters (the walks are the same walk). */
static void check_pairs(const accel_scene *s, const accel_ray *rays, size_t n, const accel_hit *ref,
                        size_t pairs)
{
    for (size_t i = 0; i < pairs; i++) {
        accel_counters cw, cc;
        accel_build_stats sw, sc;
        memset(&cw, 0, sizeof cw);
        memset(&cc, 0, sizeof cc);
        size_t bad_w = test_check_spec(s, compact_specs[i][0], rays, n, ref, &sw, &cw);
        size_t bad_c = test_check_spec(s, compact_specs[i][1], rays, n, ref, &sc, &cc);
        CHECKF(bad_w == 0 && bad_c == 0, "%s / %s on %s: %zu / %zu bad rays", compact_specs[i][0],
               compact_specs[i][1], s->name, bad_w, bad_c);
        CHECKF(cw.steps == cc.steps && cw.empty_steps == cc.empty_steps &&
                   cw.prim_tests == cc.prim_tests && cw.mailbox_skips == cc.mailbox_skips &&
                   cw.level_steps[0] == cc.level_steps[0] && cw.level_steps[1] == cc.level_steps[1],
               "%s on %s: steps %llu/%llu (top %llu/%llu), empty %llu/%llu, tests %llu/%llu, "
               "skips %llu/%llu (words/compact)",
               compact_specs[i][1], s->name, (unsigned long long)cw.steps,
               (unsigned long long)cc.steps, (unsigned long long)cw.level_steps[0],
               (unsigned long long)cc.level_steps[0], (unsigned long long)cw.empty_steps,
               (unsigned long long)cc.empty_steps, (unsigned long long)cw.prim_tests,
               (unsigned long long)cc.prim_tests, (unsigned long long)cw.mailbox_skips,
               (unsigned long long)cc.mailbox_skips);
        CHECKF(sw.refs == sc.refs && sw.leaves == sc.leaves && sc.depth == sw.depth,
               "%s on %s: %llu/%llu references, %llu/%llu leaves, depth %d", compact_specs[i][1],
               s->name, (unsigned long long)sw.refs, (unsigned long long)sc.refs,
               (unsigned long long)sw.leaves, (unsigned long long)sc.leaves, sc.depth);
    }
}

TEST(ngrid_compact_stiff_cases)
{
    for (int ci = 0; ci < stiff_case_count(); ci++) {
        stiff_case c;
        if (!test_stiff_case(ci, &c)) continue;
        accel_hit *ref = test_oracle_hits(&c.scene, c.rays.rays, c.rays.count,
                                          TEST_ORACLE_REFERENCE);
        if (ref) {
            check_pairs(&c.scene, c.rays.rays, c.rays.count, ref, 2); /* no auto: time */
            /* Rays starting inside a closed mesh must hit it. */
            accel_hit *hits = malloc((c.rays.count ? c.rays.count : 1) * sizeof *hits);
            void *a = test_build("nested_grid:layout=compact", &c.scene, 1, NULL);
            if (a && hits) {
                accel_trace(&accel_kind_nested_grid, a, c.rays.rays, hits, c.rays.count, 1, NULL);
                size_t leaks = 0;
                for (size_t i = c.leak_begin; i < c.rays.count; i++)
                    leaks += hits[i].prim == ACCEL_MISS;
                CHECKF(leaks == 0, "layout=compact on %s: %zu leaks", c.name, leaks);
            }
            if (a) accel_kind_nested_grid.destroy(a);
            free(hits);
        }
        free(ref);
        stiff_case_free(&c);
    }
}

TEST(ngrid_compact_builtin_scenes)
{
    static const char *const scenes[] = {"sphereflake:level=2", "teapot_stadium:n=4", "tetra",
                                          "soup:tris=3000"};
    for (size_t k = 0; k < sizeof scenes / sizeof scenes[0]; k++) {
        accel_scene s;
        if (!test_make_scene(scenes[k], &s)) continue;
        test_rays r = {0};
        test_seed(977 + k);
        test_rays_random(&r, s.bounds, 3000);
        test_rays_inside(&r, s.bounds, 1000, 31 + k);
        check_pairs(&s, r.rays, r.count, NULL, COMPACT_PAIRS);
        test_rays_free(&r);
        scene_free(&s);
    }
}

/* The cluster scene (a dense cube in a sparse box) with its rays, and the
 * bytes: with a sub-grid in most top cells the word layout pays a 104-byte
 * node and its planes per sub-grid and 4 bytes of count per non-empty leaf,
 * the compact one 4 more bytes per top cell. */
TEST(ngrid_compact_cluster_and_bytes)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 2000, 300)) return;
    test_rays r = {0};
    test_ngrid_cluster_rays(&r);
    check_pairs(&s, r.rays, r.count, NULL, COMPACT_PAIRS);
    test_rays_free(&r);

    accel_build_stats sw, sc;
    void *w = test_build("nested_grid:depth=2,res=6,threshold=0,sub_res=3", &s, 1, &sw);
    void *c = test_build("nested_grid:layout=compact,res=6,threshold=0,sub_res=3", &s, 1, &sc);
    if (w && c) {
        ngrid_view v;
        ngrid_get_view(w, &v);
        const double s_grids = v.node_count - 1;
        /* Same cells and references. Per sub-grid the word layout pays a
         * node and 12 planes, the compact one 4 bytes less (its top cell
         * has no leaf offset of its own); per non-empty leaf the word
         * layout pays a count; per top cell the compact one pays 8 bytes
         * and a leaf offset against a 4-byte word; the word layout's top
         * node, shared empty list and the compact one's last leaf end and
         * struct (below 256 bytes) make up the rest. */
        double expect = (double)sw.bytes - s_grids * (sizeof(ngrid_node) + 12 * sizeof(float) + 4) -
                        (double)sw.leaves * 4 + 216 * 8 - sizeof(ngrid_node);
        CHECKF(v.node_count > 100, "only %u sub-grids", v.node_count);
        CHECKF(sc.bytes < sw.bytes, "compact %zu bytes, words %zu", sc.bytes, sw.bytes);
        double diff = (double)sc.bytes - expect;
        CHECKF(diff > 0 && diff < 256, "compact %zu bytes, expected %.0f + its struct (%.0f)",
               sc.bytes, expect, diff);
        CHECKF(sc.nodes == 216 + (uint64_t)(v.node_count - 1) * 27 + (216 - (v.node_count - 1)),
               "compact: %llu cells (216 top cells and their leaves)",
               (unsigned long long)sc.nodes);
        test_note("cluster res=6 sub_res=3: words %zu bytes, compact %zu bytes", sw.bytes,
                  sc.bytes);
    }
    if (w) accel_kind_nested_grid.destroy(w);
    if (c) accel_kind_nested_grid.destroy(c);
    scene_free(&s);
}

TEST(ngrid_compact_refusals)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 500, 0)) return;
    void *a = NULL;
    accel_build_stats st;
    accel_error err = {0};
    /* Another depth. */
    int rc = test_ngrid_build("nested_grid:layout=compact,depth=3", &s, 1, &a, &st, &err);
    CHECKF(rc != 0 && strstr(err.msg, "layout=compact has exactly two levels") &&
               strstr(err.msg, "depth=3"),
           "depth=3: rc %d, message '%s'", rc, err.msg);
    if (!rc) accel_kind_nested_grid.destroy(a);
    /* depth=2 given explicitly is accepted. */
    rc = test_ngrid_build("nested_grid:layout=compact,depth=2", &s, 1, &a, &st, &err);
    CHECKF(rc == 0 && st.depth == 2, "depth=2: rc %d, '%s'", rc, err.msg);
    if (!rc) accel_kind_nested_grid.destroy(a);
    /* A sparse top grid of 10^6 cells: 4 MB of cell words fit max_mb=8,
     * 12 bytes per plain-leaf top cell do not. */
    rc = test_ngrid_build("nested_grid:layout=words,depth=2,res=100,threshold=100000,max_mb=8", &s,
                          1, &a, &st, &err);
    CHECKF(rc == 0, "words at max_mb=8: '%s'", err.msg);
    if (!rc) accel_kind_nested_grid.destroy(a);
    rc = test_ngrid_build("nested_grid:layout=compact,res=100,threshold=100000,max_mb=8", &s, 1, &a,
                          &st, &err);
    CHECKF(rc != 0 && strstr(err.msg, "nested_grid:layout=compact: 1000000 top cells") &&
               strstr(err.msg, "above the limit of 8.0 MiB"),
           "compact at max_mb=8: rc %d, message '%s'", rc, err.msg);
    if (!rc) accel_kind_nested_grid.destroy(a);
    rc = test_ngrid_build("nested_grid:layout=compact,res=100,threshold=100000,max_mb=16", &s, 1,
                          &a, &st, &err);
    CHECKF(rc == 0 && st.bytes > 12000000 && st.bytes < 16u << 20,
           "compact at max_mb=16: rc %d, %zu bytes, '%s'", rc, rc ? 0 : st.bytes, err.msg);
    if (!rc) accel_kind_nested_grid.destroy(a);
    scene_free(&s);
}
