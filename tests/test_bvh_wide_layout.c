/*
 * test_bvh_wide_layout.c - issue 50's single-ray ideas for the wide BVH:
 * layout=bfs|mixed (nodes and leaf blocks placed otherwise in memory) and
 * any_order=octant|area|leaf (the child order of any-hit queries).
 *
 * layout= promises the default's hits and counts bit for bit (the same
 * tree, only placed elsewhere): every closest and any-hit answer, and the
 * steps, box and primitive tests of every ray, equal those of the same
 * spec without it. The placement itself is checked on the tree: dfs is
 * the collapse's depth-first numbering, bfs numbers the nodes level by
 * level, mixed puts a node's leaf children's blocks right after it.
 * any_order= promises the default's closest hits (its tables serve them)
 * and any-hit answers equal to the reference's hit/miss on every ray, and
 * stores orders that really are largest-first and leaf-first.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/bvh.h"
#include "bvh/wide/node.h"
#include "rays/rays.h"
#include "rays/stiff.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

typedef struct {
    const char *name;
    rays_set rays;
    accel_hit *ref;
} lay_set;

static int lay_sets(const accel_scene *s, int size, lay_set *sets)
{
    accel_error err = {0};
    memset(sets, 0, 4 * sizeof *sets);
    sets[0].name = "primary", sets[1].name = "shadow", sets[2].name = "diffuse", sets[3].name = "vertex";
    if (rays_primary(&s->camera, size, size, &sets[0].rays, &err)) return 0;
    size_t n0 = sets[0].rays.count;
    sets[0].ref = malloc((n0 ? n0 : 1) * sizeof *sets[0].ref);
    accel_reference_trace(s, sets[0].rays.rays, sets[0].ref, n0, accel_cpu_count());
    if (rays_shadow(s, &sets[0].rays, sets[0].ref, &sets[1].rays, &err) ||
        rays_diffuse(s, &sets[0].rays, sets[0].ref, 5, &sets[2].rays, &err) ||
        stiff_add_vertex_rays(s, s->camera.eye, 400, 11, &sets[3].rays, &err)) {
        test_fail(__FILE__, __LINE__, "%s: rays: %s", s->name, err.msg);
        return 0;
    }
    for (int i = 1; i < 4; i++) {
        size_t n = sets[i].rays.count;
        sets[i].ref = malloc((n ? n : 1) * sizeof *sets[i].ref);
        accel_reference_trace(s, sets[i].rays.rays, sets[i].ref, n, accel_cpu_count());
    }
    return 1;
}

static void lay_free(lay_set *sets)
{
    for (int i = 0; i < 4; i++) {
        rays_free(&sets[i].rays);
        free(sets[i].ref);
    }
}

/* One query's answers and per-ray costs. */
typedef struct {
    accel_hit *hits;
    uint8_t *occ;
    uint32_t *steps, *prims;
    accel_counters c;
} lay_run;

static void lay_trace(const accel_kind *k, const void *a, const lay_set *set, int any_hit, lay_run *r)
{
    size_t n = set->rays.count ? set->rays.count : 1;
    memset(r, 0, sizeof *r);
    r->steps = calloc(n, sizeof *r->steps);
    r->prims = calloc(n, sizeof *r->prims);
    r->c.ray_steps = r->steps, r->c.ray_prims = r->prims;
    if (any_hit) {
        r->occ = calloc(n, 1);
        accel_trace_occluded(k, a, set->rays.rays, r->occ, set->rays.count, 1, &r->c);
    } else {
        r->hits = calloc(n, sizeof *r->hits);
        accel_trace(k, a, set->rays.rays, r->hits, set->rays.count, 1, &r->c);
    }
}

static void lay_run_free(lay_run *r)
{
    free(r->hits), free(r->occ), free(r->steps), free(r->prims);
}

static const bvh_wide *wide_of(const void *a) { return ((const bvh *)a)->wide; }

/* The reference's hit/miss against an any-hit run. */
static size_t occ_mismatches(const lay_set *set, const lay_run *r)
{
    size_t bad = 0;
    for (size_t i = 0; i < set->rays.count; i++) bad += r->occ[i] != (set->ref[i].prim != ACCEL_MISS);
    return bad;
}

/* spec against base on every set: counts = 1 also asks for the same
 * counters and per-ray costs; closest_same = 1 for the same closest hits
 * bit for bit. The any-hit answers must agree with the reference always. */
static void compare_specs(const accel_scene *s, const lay_set *sets, const char *base, const char *spec,
                          int counts)
{
    accel_error err = {0};
    const accel_kind *kb, *kv;
    void *ab, *av;
    accel_build_stats sb, sv;
    if (accel_build_spec(base, s, 2, &kb, &ab, &sb, &err)) {
        test_fail(__FILE__, __LINE__, "%s on %s: %s", base, s->name, err.msg);
        return;
    }
    if (accel_build_spec(spec, s, 2, &kv, &av, &sv, &err)) {
        test_fail(__FILE__, __LINE__, "%s on %s: %s", spec, s->name, err.msg);
        kb->destroy(ab);
        return;
    }
    CHECKF(sb.nodes == sv.nodes && sb.leaves == sv.leaves && sb.depth == sv.depth,
           "%s on %s: tree differs from %s (%llu/%llu nodes)", spec, s->name, base,
           (unsigned long long)sv.nodes, (unsigned long long)sb.nodes);
    for (int i = 0; i < 4; i++) {
        size_t n = sets[i].rays.count;
        for (int q = 0; q < 2; q++) {
            lay_run rb, rv;
            lay_trace(kb, ab, &sets[i], q, &rb);
            lay_trace(kv, av, &sets[i], q, &rv);
            if (q == 0) {
                CHECKF(!memcmp(rb.hits, rv.hits, n * sizeof *rb.hits), "%s on %s/%s: closest hits differ from %s",
                       spec, s->name, sets[i].name, base);
            } else {
                CHECKF(occ_mismatches(&sets[i], &rv) == 0, "%s on %s/%s: %zu any-hit answers differ from the "
                       "reference", spec, s->name, sets[i].name, occ_mismatches(&sets[i], &rv));
                CHECKF(!memcmp(rb.occ, rv.occ, n), "%s on %s/%s: any-hit answers differ from %s", spec, s->name,
                       sets[i].name, base);
            }
            if (counts || q == 0) {
                CHECKF(rb.c.steps == rv.c.steps && rb.c.box_tests == rv.c.box_tests &&
                           rb.c.prim_tests == rv.c.prim_tests,
                       "%s on %s/%s (%s): counters %llu/%llu/%llu steps/boxes/prims, %s %llu/%llu/%llu", spec,
                       s->name, sets[i].name, q ? "any" : "closest", (unsigned long long)rv.c.steps,
                       (unsigned long long)rv.c.box_tests, (unsigned long long)rv.c.prim_tests, base,
                       (unsigned long long)rb.c.steps, (unsigned long long)rb.c.box_tests,
                       (unsigned long long)rb.c.prim_tests);
                CHECKF(!memcmp(rb.steps, rv.steps, n * sizeof *rb.steps) &&
                           !memcmp(rb.prims, rv.prims, n * sizeof *rb.prims),
                       "%s on %s/%s: per-ray costs differ from %s", spec, s->name, sets[i].name, base);
            }
            CHECKF(accel_counters_status(&rv.c, &err) == 0, "%s: %s", spec, err.msg);
            lay_run_free(&rb);
            lay_run_free(&rv);
        }
    }
    kb->destroy(ab);
    kv->destroy(av);
}

static const char *const lay_scenes[] = {"teapot_stadium:n=4,stadium=16,tiers=3", "sphereflake:level=2",
                                         "slivers:tris=3000,slivers=100"};

/* Runs fn on the built-in scenes and on bunny and armadillo where
 * ../shared has them. */
static void on_scenes(void (*fn)(const accel_scene *s, const lay_set *sets))
{
    const char *dir = test_shared_scenes();
    for (int si = 0; si < 5; si++) {
        char path[512];
        if (si < 3) {
            snprintf(path, sizeof path, "%s", lay_scenes[si]);
        } else if (dir) {
            snprintf(path, sizeof path, "%s/%s", dir, si == 3 ? "bunny.off" : "armadillo.off");
        } else {
            continue;
        }
        accel_scene s;
        accel_error err = {0};
        if (scene_create(path, &s, &err)) {
            if (si < 3) test_fail(__FILE__, __LINE__, "%s: %s", path, err.msg);
            else test_note("skipped %s: %s", path, err.msg);
            continue;
        }
        lay_set sets[4];
        if (lay_sets(&s, 24, sets)) fn(&s, sets);
        lay_free(sets);
        scene_free(&s);
    }
}

static void layout_pairs(const accel_scene *s, const lay_set *sets)
{
    static const char *const pairs[][2] = {
        {"bvh:width=8", "bvh:width=8,layout=bfs"},
        {"bvh:width=8", "bvh:width=8,layout=mixed"},
        {"bvh:width=8,block=4", "bvh:width=8,block=4,layout=mixed"},
        {"bvh:width=8,order=dist", "bvh:width=8,order=dist,layout=mixed"},
        {"bvh:width=8,collapse=greedy", "bvh:width=8,collapse=greedy,layout=mixed"},
        {"bvh:width=4,block=4", "bvh:width=4,block=4,layout=bfs"},
        {"bvh:width=8,traverse=packet", "bvh:width=8,traverse=packet,layout=bfs"},
        {"bvh:width=8,traverse=stream", "bvh:width=8,traverse=stream,layout=bfs"},
    };
    for (size_t p = 0; p < sizeof pairs / sizeof *pairs; p++) compare_specs(s, sets, pairs[p][0], pairs[p][1], 1);
}

/* layout=: the default's hits, any-hit answers and counts, bit for bit. */
TEST(bvh_wide_layout_same_hits_and_counts)
{
    on_scenes(layout_pairs);
}

static void any_pairs(const accel_scene *s, const lay_set *sets)
{
    static const char *const specs[] = {"bvh:width=8,any_order=octant", "bvh:width=8,any_order=area",
                                        "bvh:width=8,any_order=leaf", "bvh:width=8,block=4,any_order=area",
                                        "bvh:width=8,layout=bfs,any_order=leaf"};
    for (size_t p = 0; p < sizeof specs / sizeof *specs; p++)
        compare_specs(s, sets, p == 3 ? "bvh:width=8,block=4" : "bvh:width=8", specs[p], 0);
}

/* any_order=: the default's closest hits and counts, any-hit answers
 * equal to the reference's. */
TEST(bvh_wide_any_order_exact)
{
    on_scenes(any_pairs);
}

/* ---- the placement and the stored orders, on the tree ---------------------- */

static double half_area_of(const wide_node8 *n, int c)
{
    double d[3];
    for (int a = 0; a < 3; a++) d[a] = (double)n->box[2 * a + 1][c] - (double)n->box[2 * a][c];
    return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
}

TEST(bvh_wide_layout_placement)
{
    accel_scene s;
    accel_error err = {0};
    if (scene_create("teapot_stadium:n=4,stadium=16,tiers=3", &s, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        return;
    }
    static const char *const specs[] = {"bvh:width=8", "bvh:width=8,layout=bfs", "bvh:width=8,layout=mixed",
                                        "bvh:width=8,any_order=area"};
    for (int k = 0; k < 4; k++) {
        const accel_kind *kind;
        void *a;
        accel_build_stats st;
        if (accel_build_spec(specs[k], &s, 2, &kind, &a, &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[k], err.msg);
            continue;
        }
        const bvh_wide *w = wide_of(a);
        CHECKF(w->node_count > 10 && !(w->root & WIDE_LEAF), "%s: %u nodes", specs[k], w->node_count);
        /* every node reached once; visit order depth-first (slot order) or
         * level by level, with the node's address */
        uint32_t *queue = malloc((size_t)w->node_count * sizeof *queue);
        uint32_t head = 0, tail = 0, seen = 0, dfs_ok = 1, bfs_ok = 1, mixed_ok = 1, area_ok = 1, leaf_children = 0;
        uint32_t stack[8 * 64];
        int sp = 0;
        stack[sp++] = w->root;
        queue[tail++] = w->root;
        /* depth-first, slot order: the dfs numbering is 0, 1, 2, ... */
        while (sp > 0) {
            uint32_t ref = stack[--sp];
            const wide_node8 *n = (const wide_node8 *)wide_node_addr(w, ref);
            if (w->layout == WIDE_LAYOUT_DFS) dfs_ok &= ref == seen;
            seen++;
            uint64_t at = (uint64_t)((const char *)n - (const char *)w->nodes), next = at + sizeof *n;
            for (int c = 7; c >= 0; c--)
                if (n->child[c] != WIDE_EMPTY && !(n->child[c] & WIDE_LEAF)) stack[sp++] = n->child[c];
            for (int c = 0; c < 8; c++) {
                uint32_t r = n->child[c];
                if (r == WIDE_EMPTY || !(r & WIDE_LEAF)) continue;
                leaf_children++;
                /* mixed: the leaf children's blocks follow the node in slot order */
                if (w->layout == WIDE_LAYOUT_MIXED) {
                    uint64_t la = (uint64_t)(wide_leaf_addr(w, r) - (const char *)w->nodes);
                    mixed_ok &= la == next;
                    next = la + wide_leaf_blocks(r) * sizeof(wide_block8);
                }
            }
            if (w->any_shift >= 0) { /* area order: non-increasing areas by rank */
                int used = 0;
                while (used < 8 && n->child[used] != WIDE_EMPTY) used++;
                for (int r = 1; r < used; r++) {
                    int c0 = (int)(n->perm[r - 1] >> WIDE_PERM_AREA_SHIFT & 7),
                        c1 = (int)(n->perm[r] >> WIDE_PERM_AREA_SHIFT & 7);
                    area_ok &= half_area_of(n, c0) >= half_area_of(n, c1);
                }
            }
        }
        /* level by level */
        while (head < tail) {
            uint32_t ref = queue[head];
            if (w->layout == WIDE_LAYOUT_BFS) bfs_ok &= ref == head;
            head++;
            const wide_node8 *n = (const wide_node8 *)wide_node_addr(w, ref);
            for (int c = 0; c < 8; c++)
                if (n->child[c] != WIDE_EMPTY && !(n->child[c] & WIDE_LEAF)) queue[tail++] = n->child[c];
        }
        CHECKF(seen == w->node_count && tail == w->node_count, "%s: %u of %u nodes reached", specs[k], seen,
               w->node_count);
        CHECKF(dfs_ok, "%s: the default numbering is not depth-first in slot order", specs[k]);
        CHECKF(bfs_ok, "%s: layout=bfs is not level by level", specs[k]);
        CHECKF(mixed_ok && leaf_children > 0, "%s: layout=mixed: a leaf's blocks do not follow its node", specs[k]);
        CHECKF(area_ok, "%s: any_order=area's order is not largest first", specs[k]);
        if (w->layout == WIDE_LAYOUT_MIXED)
            CHECKF(w->pool_bytes >= (size_t)w->node_count * sizeof(wide_node8) +
                                        (size_t)w->block_count * sizeof(wide_block8) &&
                       w->blocks == w->nodes,
                   "%s: pool of %zu bytes", specs[k], w->pool_bytes);
        free(queue);
        kind->destroy(a);
    }
    scene_free(&s);
}

/* ---- the conservative walk (wide/walk.c) on every layout ---------------------- */

typedef struct {
    uint32_t *ids;
    size_t n, cap;
} walk_log;

static float log_visit(void *ctx, uint32_t prim, float t_max)
{
    walk_log *l = ctx;
    if (l->n < l->cap) l->ids[l->n] = prim;
    l->n++;
    return t_max;
}

/* The same tree placed otherwise: the walk visits the same primitives in
 * the same order, with the same step count, ray by ray. */
TEST(bvh_wide_layout_walk_same_visits)
{
    accel_scene s;
    accel_error err = {0};
    if (scene_create("teapot_stadium:n=4,stadium=16,tiers=3", &s, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        return;
    }
    lay_set sets[4];
    if (!lay_sets(&s, 16, sets)) {
        lay_free(sets);
        scene_free(&s);
        return;
    }
    static const char *const specs[] = {"bvh:width=8", "bvh:width=8,layout=bfs", "bvh:width=8,layout=mixed"};
    const accel_kind *kinds[3];
    void *accels[3] = {NULL, NULL, NULL};
    accel_build_stats st;
    int built = 1;
    for (int k = 0; k < 3; k++)
        if (accel_build_spec(specs[k], &s, 1, &kinds[k], &accels[k], &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[k], err.msg);
            built = 0;
        }
    enum { CAP = 4096 };
    static uint32_t ids[3][CAP];
    size_t walked = 0, differ = 0, visits = 0;
    for (int i = 0; built && i < 4; i++) {
        for (size_t r = 0; r < sets[i].rays.count; r += 3) {
            walk_log logs[3];
            uint32_t steps[3];
            for (int k = 0; k < 3; k++) {
                logs[k] = (walk_log){ids[k], 0, CAP};
                steps[k] = 0;
                kinds[k]->walk(accels[k], &sets[i].rays.rays[r], 1e-3f, log_visit, &logs[k], &steps[k]);
            }
            walked++;
            visits += logs[0].n;
            for (int k = 1; k < 3; k++)
                differ += logs[k].n != logs[0].n || steps[k] != steps[0] ||
                          memcmp(ids[k], ids[0], (logs[0].n < CAP ? logs[0].n : CAP) * sizeof(uint32_t)) != 0;
        }
    }
    CHECKF(!built || (walked > 100 && visits > walked), "%zu rays walked, %zu visits", walked, visits);
    CHECKF(differ == 0, "%zu walks differ from layout=dfs's", differ);
    for (int k = 0; k < 3; k++)
        if (accels[k]) kinds[k]->destroy(accels[k]);
    lay_free(sets);
    scene_free(&s);
}
