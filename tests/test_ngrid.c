/*
 * test_ngrid.c - nested-grid tests: parameters and refusals, the
 * structure it builds (depth 1 is the regular grid; dense clusters get
 * sub-grids; useless sub-grids are not kept), and identical builds for any
 * thread count. The walk against the reference is in
 * test_ngrid_walk.c, the cost model and auto mode in
 * test_ngrid_cost.c; the cluster scene they share in
 * test_ngrid.h.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_ngrid.h"

/* A triangle with corners within `size` of c on every axis. */
static void add_small_tri(scene_builder *b, vec3 c, float size)
{
    vec3 p[3];
    for (int k = 0; k < 3; k++)
        p[k] = v3_add(
            c, v3(test_rand_in(-size, size), test_rand_in(-size, size), test_rand_in(-size, size)));
    test_add_tri(b, p[0], p[1], p[2]);
}

int test_ngrid_cluster_scene(accel_scene *s, int cluster, int spheres)
{
    scene_builder b = {0};
    accel_error err = {0};
    test_seed(1234567);
    box3 all = {{0, 0, 0}, {100, 100, 100}};
    box3 dense = {{50, 50, 50}, {51, 51, 51}};
    for (int i = 0; i < 300; i++) add_small_tri(&b, test_rand_point(all), 6.0f);
    for (int i = 0; i < cluster; i++) add_small_tri(&b, test_rand_point(dense), 0.02f);
    for (int i = 0; i < spheres; i++)
        scene_builder_add_sphere(&b, test_rand_point(dense), test_rand_in(0.001f, 0.03f), &err);
    return test_finish(&b, "cluster", s);
}

void test_ngrid_cluster_rays(test_rays *r)
{
    test_seed(99);
    box3 around = {{-20, -20, -20}, {120, 120, 120}};
    box3 dense = {{50, 50, 50}, {51, 51, 51}};
    for (int i = 0; i < 2500; i++) {
        vec3 o = test_rand_point(around), t = test_rand_point(dense);
        test_rays_push(r, test_ray(o, v3_sub(t, o), 0.0f, INFINITY));
    }
    for (int i = 0; i < 2000; i++) {
        vec3 o = test_rand_point(dense);
        vec3 d = v3(test_rand_in(-1, 1), test_rand_in(-1, 1), test_rand_in(-1, 1));
        test_rays_push(r, test_ray(o, d, i % 3 == 0 ? 0.01f : 0.0f, i % 2 ? 0.3f : INFINITY));
    }
    for (int i = 0; i < 1200; i++) {
        int axis = i % 3;
        vec3 o = test_rand_point(dense);
        float c[3] = {o.x, o.y, o.z}, d[3];
        c[axis] = (i & 8) ? 120.0f : -20.0f;
        for (int a = 0; a < 3; a++) d[a] = (i & 16) ? -0.0f : 0.0f;
        d[axis] = (i & 8) ? -1.0f : 1.0f;
        test_rays_push(r, test_ray(v3(c[0], c[1], c[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY));
    }
}

int test_ngrid_build(const char *spec, const accel_scene *s, int threads, void **accel,
                     accel_build_stats *st, accel_error *err)
{
    const accel_kind *kind;
    return accel_build_spec(spec, s, threads, &kind, accel, st, err);
}

/* ---- parameters and refusals ------------------------------------------------------ */

TEST(ngrid_params_refused)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 500, 0)) return;
    accel_error err = {0};
    void *a;
    accel_build_stats st;
    static const char *const bad[] = {
        "nested_grid:depth=0",     "nested_grid:depth=5",       "nested_grid:threshold=-1",
        "nested_grid:sub_res=1",   "nested_grid:sub_res=300",   "nested_grid:res=5x6",
        "nested_grid:overlap=sat", "nested_grid:lambda=0",      "nested_grid:c_step=0",
        "nested_grid:colour=red",  "nested_grid:threshold=1.5", "nested_grid:auto=maybe",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err.msg[0] = 0;
        int rc = test_ngrid_build(bad[i], &s, 1, &a, &st, &err);
        CHECKF(rc == ACCEL_ERR_SPEC || rc == ACCEL_ERR_RANGE, "%s accepted (rc %d)", bad[i], rc);
        CHECKF(rc == 0 || strstr(err.msg, "nested_grid"), "%s: message '%s' does not name the kind",
               bad[i], err.msg);
        if (rc == 0) accel_kind_nested_grid.destroy(a);
    }
    /* Memory limit: the top level alone, then the sub-grids of the cluster. */
    err.msg[0] = 0;
    CHECK(test_ngrid_build("nested_grid:res=1024,max_mb=16", &s, 1, &a, &st, &err) ==
          ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "MiB") != NULL, "message: %s", err.msg);
    err.msg[0] = 0;
    int rc =
        test_ngrid_build("nested_grid:threshold=0,sub_res=256,max_mb=64", &s, 1, &a, &st, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "sub-grid") && strstr(err.msg, "max_mb"),
           "sub-grids over the limit: rc %d, '%s'", rc, err.msg);
    if (rc == 0) accel_kind_nested_grid.destroy(a);
    /* Same with 2 threads: the same refusal. */
    char first[sizeof err.msg];
    snprintf(first, sizeof first, "%s", err.msg);
    rc = test_ngrid_build("nested_grid:threshold=0,sub_res=256,max_mb=64", &s, 2, &a, &st, &err);
    CHECKF(rc == ACCEL_ERR_RANGE && !strcmp(first, err.msg), "2 threads: rc %d, '%s' vs '%s'", rc,
           err.msg, first);
    if (rc == 0) accel_kind_nested_grid.destroy(a);
    scene_free(&s);
}

/*
 * Fine fixed sub-grids (sub_res=256, 16.7M cells each) over a few
 * primitives per cell. Over a 2,000-triangle soup every one of them would
 * copy its triangles more than 8 times over and is dropped: the plan counts
 * their references ahead instead of building them (138 s before, all
 * dropped in the end), and the result is the grid without them. Over many
 * small clusters they would all be kept: the level is refused before
 * anything is built, by memory, or by the 32-bit cell index when max_mb
 * allows it, with the same message for any thread count.
 */
TEST(ngrid_fine_sub_res_fast_or_refused)
{
    accel_scene soup;
    if (test_make_scene("soup:tris=2000", &soup)) {
        accel_build_stats fine, flat;
        void *a;
        accel_error err = {0};
        double t0 = accel_now_ms();
        int rc = test_ngrid_build("nested_grid:sub_res=256,threshold=1", &soup, 2, &a, &fine, &err);
        double ms = accel_now_ms() - t0;
        CHECKF(rc == 0, "sub_res=256 on the soup: %s", err.msg);
        if (rc == 0) accel_kind_nested_grid.destroy(a);
        CHECKF(ms < 20000, "sub_res=256 on the soup built in %.0f ms", ms);
        test_note("sub_res=256,threshold=1 on a 2000-triangle soup: %.0f ms", ms);
        if (test_ngrid_build("nested_grid:depth=1", &soup, 1, &a, &flat, &err) == 0) {
            CHECKF(rc == 0 && fine.depth == 1 && fine.nodes == flat.nodes &&
                       fine.bytes == flat.bytes,
                   "sub_res=256: depth %d, %llu cells, %zu bytes; depth=1: %llu cells, %zu bytes",
                   fine.depth, (unsigned long long)fine.nodes, fine.bytes,
                   (unsigned long long)flat.nodes, flat.bytes);
            accel_kind_nested_grid.destroy(a);
        }
        /* Coarser: some sub-grids kept, and the walk through them right. */
        test_rays r = {0};
        test_rays_random(&r, soup.bounds, 2000);
        accel_build_stats kept;
        test_check_spec(&soup, "nested_grid:sub_res=64,threshold=1", r.rays, r.count, NULL, &kept,
                        NULL);
        CHECKF(kept.depth == 2, "sub_res=64: depth %d", kept.depth);
        test_rays_free(&r);
        scene_free(&soup);
    }
    /* 300 clusters of 30 tiny triangles, about one per top cell. */
    scene_builder b = {0};
    box3 all = {{0, 0, 0}, {100, 100, 100}};
    for (int c = 0; c < 300; c++) {
        vec3 centre = test_rand_point(all);
        for (int i = 0; i < 30; i++) {
            vec3 p = v3_add(centre, v3(test_rand_in(-0.1f, 0.1f), test_rand_in(-0.1f, 0.1f),
                                       test_rand_in(-0.1f, 0.1f)));
            test_add_tri(&b, p, v3_add(p, v3(0.001f, 0, 0)), v3_add(p, v3(0, 0.001f, 0.0005f)));
        }
    }
    accel_scene s;
    if (!test_finish(&b, "clusters", &s)) return;
    static const char *const specs[] = {"nested_grid:sub_res=256,threshold=1,max_mb=256",
                                        "nested_grid:sub_res=256,threshold=1,max_mb=1048576"};
    static const char *const why[] = {"max_mb", "32-bit"};
    for (int k = 0; k < 2; k++) {
        char first[sizeof((accel_error *)0)->msg] = "";
        for (int threads = 1; threads <= 2; threads++) {
            accel_build_stats st;
            void *a;
            accel_error err = {0};
            double t0 = accel_now_ms();
            int rc = test_ngrid_build(specs[k], &s, threads, &a, &st, &err);
            double ms = accel_now_ms() - t0;
            if (rc == 0) accel_kind_nested_grid.destroy(a);
            CHECKF(rc == ACCEL_ERR_RANGE && strstr(err.msg, "refused before building") &&
                       strstr(err.msg, why[k]) && ms < 5000,
                   "%s, %d threads: rc %d after %.0f ms, '%s'", specs[k], threads, rc, ms, err.msg);
            if (threads == 1)
                snprintf(first, sizeof first, "%s", err.msg);
            else
                CHECKF(!strcmp(first, err.msg), "%s: 2 threads say '%s', 1 '%s'", specs[k], err.msg,
                       first);
        }
    }
    scene_free(&s);
}

/* ---- structure ------------------------------------------------------------------- */

TEST(ngrid_depth1_is_the_regular_grid)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 3000, 0)) return;
    static const char *const lambdas[] = {"0.5", "3", "20"};
    for (int i = 0; i < 3; i++) {
        char ns[64], gs[64];
        snprintf(ns, sizeof ns, "nested_grid:depth=1,lambda=%s", lambdas[i]);
        snprintf(gs, sizeof gs, "grid:lambda=%s", lambdas[i]);
        accel_error err = {0};
        void *a, *b;
        accel_build_stats sa, sb;
        const accel_kind *kb;
        if (test_ngrid_build(ns, &s, 1, &a, &sa, &err) ||
            accel_build_spec(gs, &s, 1, &kb, &b, &sb, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", ns, err.msg);
            continue;
        }
        CHECKF(sa.depth == 1 && sa.res[0] == sb.res[0] && sa.res[1] == sb.res[1] &&
                   sa.res[2] == sb.res[2] && sa.nodes == sb.nodes && sa.refs == sb.refs &&
                   sa.leaves == sb.leaves,
               "%s: %dx%dx%d, %llu cells, %llu refs, %llu leaves; grid: %dx%dx%d, %llu, %llu, %llu",
               ns, sa.res[0], sa.res[1], sa.res[2], (unsigned long long)sa.nodes,
               (unsigned long long)sa.refs, (unsigned long long)sa.leaves, sb.res[0], sb.res[1],
               sb.res[2], (unsigned long long)sb.nodes, (unsigned long long)sb.refs,
               (unsigned long long)sb.leaves);
        accel_kind_nested_grid.destroy(a);
        kb->destroy(b);
    }
    scene_free(&s);
}

TEST(ngrid_cluster_gets_subgrids)
{
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 20000, 0)) return;
    test_rays r = {0};
    test_ngrid_cluster_rays(&r);
    accel_ray *rays = r.rays;
    accel_build_stats flat, deep;
    accel_counters cf, cd;
    const size_t m = 600; /* rays from outside into the cluster */
    test_check_spec(&s, "nested_grid:depth=1", rays, m, NULL, &flat, &cf);
    test_check_spec(&s, "nested_grid", rays, m, NULL, &deep, &cd);
    CHECKF(deep.depth == NGRID_DEFAULT_DEPTH, "default depth %d", deep.depth);
    CHECKF(cd.level_steps[1] > 0 && cd.level_steps[2] > 0, "levels 1, 2: %llu, %llu steps",
           (unsigned long long)cd.level_steps[1], (unsigned long long)cd.level_steps[2]);
    /* The cluster sits in one top cell: a flat grid tests most of it per ray. */
    CHECKF(cf.prim_tests > 1000 * (uint64_t)m && cd.prim_tests * 50 < cf.prim_tests,
           "primitive tests per ray: %.1f flat, %.1f nested", cf.prim_tests / (double)m,
           cd.prim_tests / (double)m);
    /* Each level holds the cluster at a finer resolution. */
    void *a;
    accel_error err = {0};
    if (test_ngrid_build("nested_grid:depth=4,threshold=4", &s, 1, &a, &deep, &err) == 0) {
        ngrid_view v;
        ngrid_get_view(a, &v);
        CHECK(v.levels == 4 && v.nodes[0].level == 0);
        double cell[4] = {0};
        for (uint32_t i = 0; i < v.node_count; i++) {
            const grid_frame *f = &v.nodes[i].frame;
            double c = ((double)f->hi[0] - f->lo[0]) / f->res[0];
            uint32_t l = v.nodes[i].level;
            CHECKF(i == 0 || v.nodes[i].level >= v.nodes[i - 1].level, "not breadth-first");
            if (cell[l] == 0 || c < cell[l]) cell[l] = c;
        }
        CHECKF(cell[1] < cell[0] / 2 && cell[2] < cell[1] / 2 && cell[3] < cell[2] / 2,
               "finest cells per level: %g %g %g %g", cell[0], cell[1], cell[2], cell[3]);
        accel_kind_nested_grid.destroy(a);
    } else {
        test_fail(__FILE__, __LINE__, "depth=4: %s", err.msg);
    }
    /* Subdivision never kicks in with a huge threshold. */
    if (test_ngrid_build("nested_grid:threshold=100000", &s, 1, &a, &deep, &err) == 0) {
        CHECK(deep.depth == 1 && deep.nodes == flat.nodes);
        accel_kind_nested_grid.destroy(a);
    }
    test_rays_free(&r);
    scene_free(&s);
}

/* Large triangles all through the centre of their bounds: a 2x2x2
 * sub-grid each cell of which holds all of them separates nothing and is
 * not kept. */
TEST(ngrid_useless_subgrid_dropped)
{
    scene_builder b = {0};
    accel_error err = {0};
    test_seed(8);
    vec3 c = v3(0.5f, 0.5f, 0.5f);
    for (int i = 0; i < 20; i++) {
        vec3 u = v3(test_rand_in(-1, 1), test_rand_in(-1, 1), test_rand_in(-1, 1));
        vec3 w = v3(test_rand_in(-1, 1), test_rand_in(-1, 1), test_rand_in(-1, 1));
        vec3 uw = v3_add(u, w);
        /* The triangle and its reflection through c: both contain c, and
         * together their bounds are centred on it. */
        scene_builder_add_tri(&b, v3_add(c, u), v3_add(c, w), v3_sub(c, uw), &err);
        scene_builder_add_tri(&b, v3_sub(c, u), v3_sub(c, w), v3_add(c, uw), &err);
    }
    accel_scene s;
    if (!test_finish(&b, "star", &s)) return;
    void *a;
    accel_build_stats st;
    if (test_ngrid_build("nested_grid:res=1,sub_res=2,threshold=4", &s, 1, &a, &st, &err) == 0) {
        CHECKF(st.depth == 1 && st.nodes == 1, "depth %d, %llu cells", st.depth,
               (unsigned long long)st.nodes);
        accel_kind_nested_grid.destroy(a);
    } else {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
    }
    /* With sub_res=3 the centre lies inside the middle cell only: kept. */
    if (test_ngrid_build("nested_grid:res=1,sub_res=3,threshold=4,depth=2", &s, 1, &a, &st, &err) ==
        0) {
        CHECKF(st.depth == 2 && st.nodes == 28, "depth %d, %llu cells", st.depth,
               (unsigned long long)st.nodes);
        accel_kind_nested_grid.destroy(a);
    }
    scene_free(&s);
}

/* ---- threads ----------------------------------------------------------------------------- */

static int same_view(const ngrid_view *a, const ngrid_view *b)
{
    if (a->node_count != b->node_count || a->cell_count != b->cell_count ||
        a->list_len != b->list_len || a->ref_count != b->ref_count || a->levels != b->levels)
        return 0;
    if (memcmp(a->cells, b->cells, a->cell_count * sizeof *a->cells) ||
        memcmp(a->lists, b->lists, a->list_len * sizeof *a->lists))
        return 0;
    for (uint32_t i = 0; i < a->node_count; i++) {
        const ngrid_node *x = &a->nodes[i], *y = &b->nodes[i];
        if (x->cell_base != y->cell_base || x->level != y->level ||
            memcmp(x->frame.res, y->frame.res, sizeof x->frame.res) ||
            memcmp(x->frame.lo, y->frame.lo, sizeof x->frame.lo) ||
            memcmp(x->frame.hi, y->frame.hi, sizeof x->frame.hi) ||
            memcmp(x->frame.pad, y->frame.pad, sizeof x->frame.pad))
            return 0;
    }
    return 1;
}

TEST(ngrid_threads_build_identical)
{
    /* 20000 triangles in one top cell: a job large enough to be built with
     * every thread, beside many small ones spread over threads. */
    accel_scene s;
    if (!test_ngrid_cluster_scene(&s, 20000, 50)) return;
    static const char *const specs[] = {"nested_grid", "nested_grid:auto",
                                        "nested_grid:depth=4,threshold=4"};
    for (int k = 0; k < 3; k++) {
        void *one, *many;
        accel_build_stats s1, sn;
        accel_error err = {0};
        if (test_ngrid_build(specs[k], &s, 1, &one, &s1, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[k], err.msg);
            continue;
        }
        ngrid_view v1;
        ngrid_get_view(one, &v1);
        for (int threads = 2; threads <= 5; threads += 3) {
            if (test_ngrid_build(specs[k], &s, threads, &many, &sn, &err)) {
                test_fail(__FILE__, __LINE__, "%s, %d threads: %s", specs[k], threads, err.msg);
                continue;
            }
            ngrid_view vn;
            ngrid_get_view(many, &vn);
            CHECKF(same_view(&v1, &vn) && s1.bytes == sn.bytes,
                   "%s: %d threads build differently (%u vs %u grids, %zu vs %zu bytes)", specs[k],
                   threads, vn.node_count, v1.node_count, sn.bytes, s1.bytes);
            accel_kind_nested_grid.destroy(many);
        }
        accel_kind_nested_grid.destroy(one);
    }
    scene_free(&s);
}
