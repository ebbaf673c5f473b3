/*
 * test_bvh_wide_collapse.c - the collapse of the binary tree into wide nodes
 * (bvh/wide/collapse.c): the binary build stopped at one block gives the
 * same greedy wide tree as the fully split one, and collapse=dp finds
 * trees no greedy collapse beats under its own cost (and cheaper ones on
 * most scenes), within its leaf_blocks bound. The trees' structural
 * invariants are in test_bvh_wide.c, traces against the reference in
 * test_bvh_wide_trace.c.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/split_common.h"
#include "bvh/bvh.h"
#include "bvh/wide/node.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

/* The scenes of the collapse tests: a soup, closed meshes, a huge stadium
 * round a small teapot, long slivers among small triangles. */
static const char *const collapse_scenes[] = {"soup:tris=6000", "sphereflake:level=2,spheres=0",
                                              "teapot_stadium:n=2", "slivers:tris=2000,slivers=100"};
#define COLLAPSE_SCENES (sizeof collapse_scenes / sizeof *collapse_scenes)

/* The binary build of a wide tree stops at tasks of one block (leaf_below):
 * the collapse makes the same wide tree as from the fully split binary
 * tree: the same node, leaf and block counts, depth and wide SAH cost (the
 * same boxes and leaf sets), on 1 and 2 threads. */
static void wide_counts(const accel_scene *s, int width, int leaf_below, int threads, accel_build_stats *st,
                        uint32_t *blocks)
{
    bvh_build_opts o;
    memset(&o, 0, sizeof o);
    o.builder = BVH_BUILD_BINNED, o.bins = 16, o.axes = 3, o.max_leaf = 4, o.ct = 1.0f, o.ci = 1.0f;
    o.reorder = 1, o.max_mb = 4096, o.leaf_below = leaf_below;
    bvh b;
    accel_error err = {0};
    const bvh_wide_collapse greedy = {0, 1.5, 2, 0, WIDE_LAYOUT_DFS, WIDE_ANY_NEAR};
    memset(st, 0, sizeof *st);
    *blocks = 0;
    if (bvh_build_run(s, &o, threads, &b, st, &err) ||
        bvh_wide_build(&b, &b.wide, width, 8, WIDE_ORDER_OCTANT, 0, &greedy, threads, 1.0, 1.0, st, &err)) {
        test_fail(__FILE__, __LINE__, "%s: %s", s->name, err.msg);
        return;
    }
    *blocks = b.wide->block_count;
    bvh_wide_free(b.wide);
}

TEST(bvh_wide_binary_stops_at_one_block)
{
    for (size_t i = 0; i < COLLAPSE_SCENES; i++) {
        accel_scene s;
        if (!test_make_scene(collapse_scenes[i], &s)) continue;
        for (int width = 4; width <= 8; width += 4)
            for (int threads = 1; threads <= 2; threads++) {
                accel_build_stats a, b;
                uint32_t ba, bb;
                wide_counts(&s, width, 0, threads, &a, &ba);
                wide_counts(&s, width, 8, threads, &b, &bb);
                CHECKF(a.nodes == b.nodes && a.leaves == b.leaves && ba == bb && a.depth == b.depth &&
                           a.sah_cost == b.sah_cost,
                       "%s width %d, %d threads: nodes %llu/%llu, leaves %llu/%llu, blocks %u/%u, depth "
                       "%d/%d, SAH %.9g/%.9g",
                       s.name, width, threads, (unsigned long long)a.nodes, (unsigned long long)b.nodes,
                       (unsigned long long)a.leaves, (unsigned long long)b.leaves, ba, bb, a.depth, b.depth,
                       a.sah_cost, b.sah_cost);
            }
        scene_free(&s);
    }
}

/* The collapse=dp objective of a built wide tree (bvh/wide/collapse.c's plan_dp):
 * every wide node below the root costs its half area, every leaf its half
 * area x leaf_cost x its blocks; the areas are the child boxes of the
 * parents' rows, which are the binary nodes' boxes. */
static double dp_objective(const bvh_wide *w, double leaf_cost)
{
    double sum = 0.0;
    for (uint32_t n = 0; n < w->node_count; n++) {
        const float *rows = w->width == 8 ? ((const wide_node8 *)w->nodes)[n].box[0]
                                          : ((const wide_node4 *)w->nodes)[n].box[0];
        const uint32_t *child = (const uint32_t *)(rows + 6 * w->width);
        for (int i = 0; i < w->width; i++) {
            if (child[i] == WIDE_EMPTY) continue;
            double dx = (double)rows[1 * w->width + i] - rows[0 * w->width + i];
            double dy = (double)rows[3 * w->width + i] - rows[2 * w->width + i];
            double dz = (double)rows[5 * w->width + i] - rows[4 * w->width + i];
            double a = dx * dy + dy * dz + dz * dx;
            sum += child[i] & WIDE_LEAF ? a * leaf_cost * wide_leaf_blocks(child[i]) : a;
        }
    }
    return sum;
}

static int dp_objective_of(const accel_scene *s, const char *spec, double leaf_cost, double *objective)
{
    const accel_kind *k;
    void *a = test_build_kind(spec, s, 1, &k, NULL);
    if (!a) return -1;
    *objective = dp_objective(((const bvh *)a)->wide, leaf_cost);
    k->destroy(a);
    return 0;
}

/* collapse=dp is optimal under its cost: on the same binary tree (the same
 * leaf_below), no greedy collapse costs less by plan_dp's measure, and on
 * most scenes the DP finds strictly cheaper trees (it is not the greedy
 * one under another name). Its leaf_blocks bound holds. */
TEST(bvh_wide_dp_collapse_costs_least)
{
    static const double costs[] = {0.5, 1.5, 4.0};
    int cheaper = 0, compared = 0;
    for (size_t i = 0; i < COLLAPSE_SCENES; i++) {
        accel_scene s;
        accel_error err = {0};
        if (!test_make_scene(collapse_scenes[i], &s)) continue;
        for (int width = 4; width <= 8; width += 4)
            for (size_t c = 0; c < sizeof costs / sizeof *costs; c++) {
                char greedy[96], dp[128];
                snprintf(greedy, sizeof greedy, "bvh:width=%d,collapse=greedy,leaf_below=8", width);
                snprintf(dp, sizeof dp, "bvh:width=%d,collapse=dp,leaf_below=8,leaf_cost=%g,leaf_blocks=8",
                         width, costs[c]);
                double og, od;
                if (dp_objective_of(&s, greedy, costs[c], &og) || dp_objective_of(&s, dp, costs[c], &od)) continue;
                compared++;
                CHECKF(od <= og * (1 + 1e-5), "%s %s: DP objective %.9g above greedy %.9g", s.name, dp, od, og);
                cheaper += od < og * (1 - 1e-4);
            }
        /* leaf_blocks=1: no leaf of several blocks except binary leaves
         * (at most leaf=8 primitives, one block of 8) */
        char spec[96];
        snprintf(spec, sizeof spec, "bvh:width=8,collapse=dp,leaf_blocks=1,leaf_cost=0.01");
        const accel_kind *k;
        void *a;
        accel_build_stats st;
        if (accel_build_spec(spec, &s, 1, &k, &a, &st, &err) == 0) {
            const bvh_wide *w = ((const bvh *)a)->wide;
            int over = 0;
            for (uint32_t n = 0; n < w->node_count; n++) {
                const uint32_t *child = ((const wide_node8 *)w->nodes)[n].child;
                for (int l = 0; l < 8; l++)
                    over += child[l] != WIDE_EMPTY && (child[l] & WIDE_LEAF) && wide_leaf_blocks(child[l]) > 1;
            }
            CHECKF(over == 0, "%s %s: %d leaves of more than one block", s.name, spec, over);
            k->destroy(a);
        } else {
            test_fail(__FILE__, __LINE__, "%s: %s", spec, err.msg);
        }
        scene_free(&s);
    }
    CHECKF(cheaper * 2 > compared, "the DP collapse was strictly cheaper in only %d of %d trees", cheaper,
           compared);
}


/* max_mb covers the collapse too: with leaves of one primitive, blocks of
 * 8 (320 bytes a triangle) and the collapse's tables cost far more than
 * the binary build's peak, so a limit the binary build fits is refused by
 * the collapse with a message that names the limit and the account, never
 * built past it; a limit that fits builds the same tree as no limit. */
TEST(bvh_wide_collapse_within_max_mb)
{
    accel_scene s;
    accel_error err = {0};
    if (!test_make_scene("soup:tris=20000", &s)) return;
    /* binary peak: 20000 x (32 + 64 + 40) bytes, about 2.6 MiB */
    static const char *const refused[] = {"bvh:width=8,leaf=1,leaf_below=1,max_mb=4",
                                          "bvh:width=8,leaf=1,leaf_below=1,collapse=greedy,max_mb=4",
                                          "bvh:width=4,leaf=1,leaf_below=1,block=8,max_mb=3.5"};
    for (size_t i = 0; i < sizeof refused / sizeof *refused; i++) {
        int rc = test_build_rc(refused[i], &s, &err);
        CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "max_mb") && strstr(err.msg, "binary tree"),
               "%s: rc %d (%s)", refused[i], rc, err.msg);
    }
    const accel_kind *k;
    void *a, *b;
    accel_build_stats sa, sb;
    if (accel_build_spec("bvh:width=8,leaf=1,leaf_below=1,max_mb=64", &s, 1, &k, &a, &sa, &err) ||
        accel_build_spec("bvh:width=8,leaf=1,leaf_below=1", &s, 1, &k, &b, &sb, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        scene_free(&s);
        return;
    }
    CHECKF(sa.nodes == sb.nodes && sa.bytes == sb.bytes && sa.sah_cost == sb.sah_cost,
           "max_mb=64 changed the tree: %llu/%llu nodes", (unsigned long long)sa.nodes,
           (unsigned long long)sb.nodes);
    /* the limit held: the tree kept is well under it */
    CHECKF(sa.bytes < 64.0 * 1048576.0, "%zu bytes", (size_t)sa.bytes);
    k->destroy(a);
    k->destroy(b);
    scene_free(&s);
}
