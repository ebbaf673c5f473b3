/*
 * check.c - the lab's step checks (see check.h and LAB.md).
 *
 * Every check is a comparison with something known to be right: the
 * double-precision oracle (accel_reference_trace) for answers, and the
 * project's median-split BVH (bvh:build=median) for costs. On failure the
 * report says what is wrong in the student's terms: which ray, which
 * triangle, what the reference found, how many nodes a ray visits against
 * the reference, and a hint. Sizes are small (a check takes seconds); step
 * 5 is the one that measures speed, and it reports, never fails on speed.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "measure/bench.h"
#include "image/image.h"
#include "check.h"
#include "scene/scene.h"

const char *lab_step_title(int step)
{
    static const char *const titles[LAB_STEPS + 1] = {
        "",
        "a median-split BVH (build)",
        "single-ray traversal with a ray/box test and the depth view",
        "many meshes: your kind as the bottom level, rays in object space",
        "packet traversal (traverse=packet)",
        "real time: frames per second at 800x600, primary and shadow rays",
        "optional: a uniform grid (lab/grid_starter.c), single rays and the cells they step",
        "optional: your own top level (lab_top_student): instances, inverse transforms",
    };
    return step >= 1 && step <= LAB_STEPS ? titles[step] : "no such step";
}


/* The yardstick of step 2's cost rule (step 6: the project's grid in its
 * plain form, with the subject's parameters, e.g. lambda). */
typedef struct {
    const char *kind, *kv, *what, *unit, *hint;
} yardstick;

static const yardstick bvh_yard = {
    "bvh", "build=median", "a median-split BVH", "nodes",
    "visit the nearer child first (the smaller entry distance), test boxes against the closest "
    "hit so far (the t that accel_prim_hit shrinks), drop a popped node with "
    "!box3_entry_before(entry, t), and split at the median of the sorted centroids"};
static const yardstick grid_yard = {
    "grid", "overlap=bbox,mailbox=0", "the project's grid at the same lambda", "cells",
    "step only through the cells the ray crosses, in its order (3D DDA), start at the cell where "
    "it enters the grid's box, and stop once the closest hit lies before the current cell's "
    "exit"};
/* Far above every mistake of order (1.3-1.9x): the boxes themselves. */
static const char *const lab_box_hint =
    "this is far more than any traversal order costs (1.3-1.9x): look at the boxes and the depth "
    "view (lab/out/step2_depth_*.png beside the reference's). Boxes much larger than their "
    "primitives (a box from the parent's range, or not shrunk to the node's own primitives), "
    "or a split that leaves most primitives on one side, light up the whole view";
static const yardstick *yard = &bvh_yard; /* set by lab_check before the children start */

/* ---- step 1 -------------------------------------------------------------- */

/* Does the kind take parameter `key`? */
static int has_param(const accel_kind *k, const char *key)
{
    for (size_t i = 0; i < k->param_count; i++)
        if (!strcmp(k->params[i].key, key)) return 1;
    return 0;
}

static void check_build(const lab_subject *s, const char *spec, lab_result *r, accel_error *err)
{
    accel_scene scene;
    if (scene_create(spec, &scene, err)) {
        lab_fail(r, "scene %s: %s", spec, err->msg);
        return;
    }
    void *a = NULL;
    accel_build_stats st;
    uint32_t n = scene.live_count;
    lab_where(r, "scene %s, your build", spec);
    if (lab_build_subject(s, "", &scene, &a, &st, err)) {
        lab_fail(r, "%s: your build failed: %s", spec, err->msg);
    } else if (st.nodes == 0 || st.leaves == 0) {
        lab_fail(r, "%s: your build made no nodes (stats: %llu nodes, %llu leaves) for %u "
                "primitives: write build_node() and count the nodes and leaves",
             spec, (unsigned long long)st.nodes, (unsigned long long)st.leaves, n);
    } else if (st.nodes != 2 * st.leaves - 1 && st.nodes != 2 * st.leaves) {
        lab_fail(r, "%s: %llu nodes for %llu leaves: a binary tree with L leaves has 2L-1 nodes "
                "(does every interior node get exactly two children?)",
             spec, (unsigned long long)st.nodes, (unsigned long long)st.leaves);
    } else if (st.refs != n) {
        lab_fail(r, "%s: your leaves hold %llu primitives, the scene has %u: each primitive "
                "belongs to exactly one leaf (check the split: first..first+count)",
             spec, (unsigned long long)st.refs, n);
    } else {
        int bound = (int)ceil(log2((double)(n > 1 ? n : 2))) + 2;
        if (st.depth < 1 || st.depth > bound)
            lab_fail(r, "%s: depth %d for %u primitives: a median split halves the primitives "
                    "at every level, so the depth is at most %d (split at the median of the "
                    "centroids along the largest axis, not at the middle of the box)",
                 spec, st.depth, n, bound);
        else
            lab_say(r, "  ok   %s: %u primitives, %llu nodes, %llu leaves, depth %d, %.1f ms, "
                   "%.0f bytes/primitive\n",
                spec, n, (unsigned long long)st.nodes, (unsigned long long)st.leaves, st.depth,
                st.ms, (double)st.bytes / (n ? n : 1));
    }
    if (a) s->kind->destroy(a);
    a = NULL;
    /* leaf=1, the conformance suite's variant (step 5): one primitive per
     * leaf, where a leaf rule `count < leaf` never stops splitting. */
    if (r->passed && has_param(s->kind, "leaf")) {
        lab_where(r, "scene %s, your build with leaf=1", spec);
        if (lab_build_subject(s, "leaf=1", &scene, &a, &st, err))
            lab_fail(r, "%s: your build with leaf=1 failed: %s", spec, err->msg);
        else if (st.leaves != n || st.refs != n ||
                 (st.nodes != 2 * st.leaves - 1 && st.nodes != 2 * st.leaves))
            lab_fail(r, "%s: with leaf=1, %llu leaves holding %llu primitives in %llu nodes, for "
                        "%u primitives: a leaf holds at most `leaf` primitives, so at leaf=1 "
                        "every primitive has its own leaf (a leaf when count <= leaf)",
                     spec, (unsigned long long)st.leaves, (unsigned long long)st.refs,
                     (unsigned long long)st.nodes, n);
        if (a) s->kind->destroy(a);
    }
    scene_free(&scene);
}

/* ---- rays for step 2 ----------------------------------------------------- */

typedef struct {
    const char *name;
    rays_set rays;
    int packets; /* traced in 8x8 packets: a failure names the packet and the lane */
} ray_group;

static void describe_ray(lab_result *r, const accel_ray *ray)
{
    lab_say(r, "         ray o=(%.7g, %.7g, %.7g) d=(%.7g, %.7g, %.7g) t in [%g, %g]\n", ray->ox,
        ray->oy, ray->oz, ray->dx, ray->dy, ray->dz, ray->t_near, ray->t_far);
}

/* Compares the subject with the oracle on one ray group; 1 when it agrees. */
static int compare_group(const accel_kind *k, const void *a, const accel_scene *sc,
                         const ray_group *g, int threads, lab_result *r)
{
    size_t n = g->rays.count;
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref), *hits = malloc((n ? n : 1) * sizeof *hits);
    uint8_t *occ = malloc(n ? n : 1);
    int ok = 1;
    if (!ref || !hits || !occ) {
        lab_fail(r, "out of memory");
        ok = 0;
        goto out;
    }
    lab_where(r, "scene %s, ray set %s", sc->name, g->name);
    accel_reference_trace(sc, g->rays.rays, ref, n, threads);
    accel_counters c = {0};
    accel_trace(k, a, g->rays.rays, hits, n, 1, &c);
    accel_error broken = {0};
    if (accel_counters_status(&c, &broken)) {
        lab_fail(r, "%s / %s rays: %s", sc->name, g->name, broken.msg);
        ok = 0;
        goto out;
    }
    hits_diff d = hits_compare(sc, g->rays.rays, ref, hits, n);
    if (d.first_bad != SIZE_MAX) {
        size_t i = d.first_bad;
        lab_fail(r, "%s / %s rays: %zu holes (the reference hits, you miss), %zu false hits, %zu "
                "other disagreements of %zu rays. First: ray %zu",
             sc->name, g->name, d.holes, d.false_hits, d.disagreements, n, i);
        if (g->packets)
            lab_say(r, "         (packet %zu, lane %zu: rays %zu..%zu travel together)\n", i / 64,
                    i % 64, i - i % 64, (i - i % 64 + 64 < n ? i - i % 64 + 64 : n) - 1);
        describe_ray(r, &g->rays.rays[i]);
        if (ref[i].prim != ACCEL_MISS)
            lab_say(r, "         the reference hits triangle %u at t=%.9g; ", ref[i].prim, ref[i].t);
        else
            lab_say(r, "         the reference misses; ");
        if (hits[i].prim != ACCEL_MISS)
            lab_say(r, "you report triangle %u at t=%.9g\n", hits[i].prim, hits[i].t);
        else
            lab_say(r, "you report a miss\n");
        size_t mine = 0;
        for (size_t j = 0; j < n; j++) mine += hits[j].prim != ACCEL_MISS;
        int ending = strstr(g->name, "ending") != NULL;
        const accel_ray *ray = &g->rays.rays[i];
        /* Causes the answer itself tells: a triangle the ray does not hit
         * where the reference misses (a lane or a hit never written), or
         * another triangle at the reference's very distance (an id that
         * is not the triangle's). */
        int unreal = hits[i].prim != ACCEL_MISS && !hits_verify(sc, ray, &hits[i]);
        int same_t = hits[i].prim != ACCEL_MISS && ref[i].prim != ACCEL_MISS &&
                     hits[i].prim != ref[i].prim &&
                     fabsf(hits[i].t - ref[i].t) <= 1e-4f * fmaxf(1.0f, fabsf(ref[i].t));
        lab_say(r, "         hint: %s\n",
            mine == 0 ? "you report no hit on any ray: is the traversal written (trace_ray, "
                        "step 2; trace_packet, step 4) and does it return the local id it hit?"
            : same_t && unreal
                ? "the reference's distance, but another triangle, which this ray does not hit "
                  "there: report the triangle's id, b->store.scene_id[prim] with prim = "
                  "b->order[left_first + i], not its position in your order (left_first + i) "
                  "or in the leaf"
            : unreal && ref[i].prim == ACCEL_MISS
                ? g->packets
                    ? "a hit on a triangle this ray does not hit, where the reference misses: "
                      "an uninitialized lane (its hit, t or id never written: set every lane's "
                      "hit to ACCEL_MISS before the walk, not only the lanes that hit; the "
                      "lanes of a packet's last rows too)"
                    : "a hit on a triangle this ray does not hit, where the reference misses: "
                      "an uninitialized hit (set the hit to ACCEL_MISS before the walk and "
                      "write it only where accel_prim_hit says so)"
            : ending && g->packets && hits[i].prim == ACCEL_MISS
                ? "these rays end exactly at their hit (t_far = the hit's t): a lane enters a "
                  "box when box3_slab(..., p->t_near, t[lane], &entry) says so, with the lane's "
                  "closest t as the far end; a cull of your own (entry < t) loses the hit"
            : ending && hits[i].prim == ACCEL_MISS
                ? "these rays end exactly at their hit (t_far = the hit's t), where a box's "
                  "entry can round to just past t: cull a popped node with "
                  "!box3_entry_before(entry, t) (geom.h), the slab test's own padding, never "
                  "`entry < t` or `entry <= t`"
            : g->packets && hits[i].prim == ACCEL_MISS
                ? "a packet enters a node when ANY active lane from `first` on hits its box, "
                  "not only the first lane; a leaf is tested with every active lane from there"
            : hits[i].prim == ACCEL_MISS
                ? "a box test that rejects a box the ray touches (t range, +-0 directions), or "
                  "a node never visited (is the far child pushed and popped?)"
                : "keep the nearest hit: pass the closest t so far to every test, and never "
                  "stop at the first leaf that hits");
        ok = 0;
        goto out;
    }
    accel_trace_occluded(k, a, g->rays.rays, occ, n, 1, NULL);
    for (size_t i = 0; i < n; i++)
        if (occ[i] != (ref[i].prim != ACCEL_MISS)) {
            lab_fail(r, "%s / %s rays: occluded() says %d for ray %zu, the reference %s", sc->name,
                 g->name, occ[i], i, ref[i].prim != ACCEL_MISS ? "hits" : "misses");
            describe_ray(r, &g->rays.rays[i]);
            ok = 0;
            break;
        }
out:
    free(ref);
    free(hits);
    free(occ);
    return ok;
}

/* Mean nodes visited per primary ray by a built structure (counted run). */
static double steps_per_ray(const accel_kind *k, const void *a, const rays_set *rays,
                            uint32_t *ray_steps)
{
    accel_counters c = {0};
    c.ray_steps = ray_steps;
    accel_hit *h = malloc((rays->count ? rays->count : 1) * sizeof *h);
    if (!h) return NAN;
    accel_trace(k, a, rays->rays, h, rays->count, 1, &c);
    free(h);
    return rays->count ? (double)c.steps / (double)rays->count : 0.0;
}

/* Nodes visited and primitives tested per ray by a counted run: closest
 * hits, or any hits (occluded) when occluded != 0. */
typedef struct {
    double steps, prims;
} ray_work;

static ray_work work_per_ray(const accel_kind *k, const void *a, const rays_set *rays, int occluded)
{
    ray_work w = {NAN, NAN};
    accel_counters c = {0};
    size_t n = rays->count ? rays->count : 1;
    void *out = malloc(n * (occluded ? sizeof(uint8_t) : sizeof(accel_hit)));
    if (!out) return w;
    if (occluded) accel_trace_occluded(k, a, rays->rays, out, rays->count, 1, &c);
    else accel_trace(k, a, rays->rays, out, rays->count, 1, &c);
    free(out);
    w.steps = (double)c.steps / (double)n;
    w.prims = (double)c.prim_tests / (double)n;
    return w;
}

/* The rays of a and b that hit something (the kind's occluded(), checked
 * against the oracle before): where an any-hit query can stop early. */
static int occluded_subset(const accel_kind *k, const void *acc, const rays_set *a,
                           const rays_set *b, rays_set *out)
{
    size_t n = a->count + b->count;
    uint8_t *occ = malloc(n ? n : 1);
    out->rays = malloc((n ? n : 1) * sizeof *out->rays);
    out->count = 0;
    if (!occ || !out->rays) {
        free(occ);
        return -1;
    }
    accel_trace_occluded(k, acc, a->rays, occ, a->count, 1, NULL);
    accel_trace_occluded(k, acc, b->rays, occ + a->count, b->count, 1, NULL);
    for (size_t i = 0; i < n; i++)
        if (occ[i]) out->rays[out->count++] = i < a->count ? a->rays[i] : b->rays[i - a->count];
    free(occ);
    return 0;
}

/* The depth view: nodes visited per pixel, at 256x256 (the check's own
 * rays are too few pixels to see a tree in). */
#define LAB_VIEW_SIZE 256
static void write_depth_view(const lab_subject *s, const accel_kind *kind, const char *whose,
                             const char *scene, const accel_scene *sc, const void *a, lab_result *r)
{
    if (!s->out_dir) return;
    const int w = LAB_VIEW_SIZE, h = LAB_VIEW_SIZE;
    rays_set rays = {0};
    uint32_t *steps = malloc((size_t)w * h * sizeof *steps);
    float *v = malloc((size_t)w * h * sizeof *v);
    image_rgb img = {0};
    accel_error err = {0};
    float vmax = 1.0f;
    char path[512];
    snprintf(path, sizeof path, "%s/%s_depth_%s%s.png", s->out_dir,
             yard == &grid_yard ? "grid" : "step2", scene, whose);
    for (char *p = path + strlen(s->out_dir) + 1; *p; p++)
        if (*p == ':' || *p == '=' || *p == ',') *p = '_';
    if (!steps || !v || rays_primary(&sc->camera, w, h, &rays, &err)) goto out;
    steps_per_ray(kind, a, &rays, steps);
    for (size_t i = 0; i < rays.count; i++) { /* rays come in 8x8 tiles: pixel[] places them */
        float x = (float)steps[i];
        v[rays.pixel ? rays.pixel[i] : i] = x;
        if (x > vmax) vmax = x;
    }
    char title[128];
    image_heat_title(title, sizeof title, kind->name, kind, 0);
    if (image_heatmap(v, w, h, NULL, title, &img, &err) == 0 && image_write(path, &img, &err) == 0)
        lab_say(r, "       depth view (%s per pixel, white = %.0f), %s: %s\n", kind->step_name,
                vmax, *whose ? "the reference's" : "yours", path);
out:
    if (err.code) lab_say(r, "       no depth view %s: %s\n", path, err.msg);
    image_free(&img);
    rays_free(&rays);
    free(steps);
    free(v);
}

/* ---- step 2 -------------------------------------------------------------- */

static void check_traversal(const lab_subject *s, const char *spec, lab_result *r,
                            accel_error *err)
{
    accel_scene sc;
    if (scene_create(spec, &sc, err)) {
        lab_fail(r, "scene %s: %s", spec, err->msg);
        return;
    }
    int size = s->quick ? 32 : 64;
    enum { GROUPS = 5 };
    ray_group g[GROUPS];
    memset(g, 0, sizeof g);
    g[0].name = "primary";
    g[1].name = "shadow";
    g[2].name = "diffuse";
    g[3].name = "vertex and axis";
    g[4].name = "ending exactly at the hit";
    accel_hit *ph = NULL;
    void *a = NULL, *ref_a = NULL;
    accel_build_stats st;
    rays_set blocked = {0}; /* the shadow and diffuse rays that hit: any hit's cost */
    const accel_kind *refk = accel_find_kind(yard->kind);
    int ok = rays_primary(&sc.camera, size, size, &g[0].rays, err) == 0;
    if (ok) ph = malloc(g[0].rays.count * sizeof *ph);
    ok = ok && ph;
    if (ok) accel_reference_trace(&sc, g[0].rays.rays, ph, g[0].rays.count, s->threads);
    ok = ok && rays_shadow(&sc, &g[0].rays, ph, &g[1].rays, err) == 0 &&
         rays_diffuse(&sc, &g[0].rays, ph, 7, &g[2].rays, err) == 0 &&
         lab_make_stiff_rays(&sc, &g[3].rays, err) == 0 &&
         rays_ending_at_hit(&g[0].rays, ph, &g[4].rays, err) == 0;
    if (!ok) {
        lab_fail(r, "%s: could not make the rays: %s", spec, err->msg);
        goto out;
    }
    lab_where(r, "scene %s, your build", spec);
    if (lab_build_subject(s, "", &sc, &a, &st, err)) {
        lab_fail(r, "%s: your build failed: %s", spec, err->msg);
        goto out;
    }
    for (int i = 0; i < GROUPS; i++)
        if (!compare_group(s->kind, a, &sc, &g[i], s->threads, r)) goto out;
    int grid = yard == &grid_yard;
    ray_work mine = work_per_ray(s->kind, a, &g[0].rays, 0);
    if (!(mine.steps > 0.0)) {
        lab_fail(r, "%s: your traversal counts no %s (*steps stays 0): the depth view and the "
                "cost comparison need them",
             spec, grid ? "cells stepped" : "node visits");
        goto out;
    }
    if (!(mine.prims > 0.0)) {
        lab_fail(r, "%s: your traversal counts no primitive tests (*prims stays 0): count every "
                    "accel_prim_hit() call, %s",
                 spec, grid ? "in every cell" : "in every leaf the ray reaches");
        goto out;
    }
    write_depth_view(s, s->kind, "", spec, &sc, a, r);
    ray_work theirs = {NAN, NAN}, theirs_occ = {NAN, NAN}, mine_occ = {NAN, NAN};
    char ykv[256];
    snprintf(ykv, sizeof ykv, "%s%s%s", yard->kv, grid && *s->kv ? "," : "", grid ? s->kv : "");
    if (refk && accel_build_kind(refk, ykv, &sc, 1, &ref_a, &st, err) == 0) {
        theirs = work_per_ray(refk, ref_a, &g[0].rays, 0);
        if (occluded_subset(s->kind, a, &g[1].rays, &g[2].rays, &blocked) == 0) {
            theirs_occ = work_per_ray(refk, ref_a, &blocked, 1);
            mine_occ = work_per_ray(s->kind, a, &blocked, 1);
        }
    }
    if (ref_a) write_depth_view(s, refk, "_reference", spec, &sc, ref_a, r);
    size_t rays = 0;
    for (int i = 0; i < GROUPS; i++) rays += g[i].rays.count;
    if (!(theirs.steps > 0.0 && theirs.prims > 0.0)) { /* no yardstick: answers only */
        lab_say(r, "  ok   %s: %zu rays agree with the reference (no cost yardstick)\n", spec,
                rays);
        goto out;
    }
    double steps_x = mine.steps / theirs.steps, prims_x = mine.prims / theirs.prims;
    /* The counters, both ways: a correct walk visits every node on the way
     * to every leaf it tests, so it cannot count far fewer than the
     * reference (correct solutions: 0.86-1.06x). */
    if (steps_x < LAB_COUNT_LOW || prims_x < LAB_COUNT_LOW) {
        int st_low = steps_x < LAB_COUNT_LOW;
        lab_fail(r, "%s: your counter %s says %.2fx the %s of %s (%.1f against %.1f per primary "
                    "ray), below what any correct walk counts (at least %.2fx): %s",
                 spec, st_low ? "*steps" : "*prims",
                 st_low ? steps_x : prims_x, st_low ? yard->unit : "primitive tests", yard->what,
                 st_low ? mine.steps : mine.prims, st_low ? theirs.steps : theirs.prims,
                 LAB_COUNT_LOW,
                 st_low ? (grid ? "count every cell the ray steps through, empty ones too"
                                : "count every node the walk visits, interior nodes too, not "
                                  "only the leaves")
                        : "count every accel_prim_hit() call, hit or not");
        goto out;
    }
    /* The work rule: nodes visited (primitive tests depend on the leaf size,
     * which the reference chooses its own way). */
    if (steps_x > LAB_SLOW_RATIO) {
        lab_slow(r, "%s: all %zu rays agree with the reference, but your traversal visits %.2fx "
                "the %s of %s (%.1f against %.1f per primary ray; a good solution: at most "
                "%.2fx). Hint: %s",
             spec, rays, steps_x, yard->unit, yard->what, mine.steps, theirs.steps,
             LAB_SLOW_RATIO, steps_x > LAB_BOX_RATIO && !grid ? lab_box_hint : yard->hint);
        goto out;
    }
    /* Any hit (occluded(), shadow rays): the first hit found ends the ray,
     * so on the shadow rays it does less than a closest-hit query does;
     * measured against the same saving of the reference. */
    ray_work mine_cl = work_per_ray(s->kind, a, &blocked, 0);
    ray_work theirs_cl = work_per_ray(refk, ref_a, &blocked, 0);
    double occ_mine = (mine_occ.steps + mine_occ.prims) / (mine_cl.steps + mine_cl.prims);
    double occ_theirs =
        (theirs_occ.steps + theirs_occ.prims) / (theirs_cl.steps + theirs_cl.prims);
    if (blocked.count >= 16 && occ_theirs < 0.95 && occ_mine > 1.0 - 0.5 * (1.0 - occ_theirs)) {
        lab_slow(r, "%s: on the %zu shadow and diffuse rays that hit something, your "
                    "occluded() does %.2fx the work of your closest-hit trace of the same rays "
                    "(%.1f %s and %.1f primitive tests per ray against %.1f and %.1f); %s's "
                    "any-hit query does %.2fx of its own: an any-hit query (any_hit, "
                    "occluded()) ends at the first hit it finds, it does not search on for the "
                    "closest",
                 spec, blocked.count, occ_mine, mine_occ.steps, yard->unit, mine_occ.prims,
                 mine_cl.steps, mine_cl.prims, yard->what, occ_theirs);
        goto out;
    }
    char occ_note[160];
    if (blocked.count >= 16)
        snprintf(occ_note, sizeof occ_note, "any hit on the %zu rays that hit %.2fx the work of "
                 "closest hit (%s: %.2fx)", blocked.count, occ_mine, yard->what, occ_theirs);
    else
        snprintf(occ_note, sizeof occ_note, "too few shadow and diffuse rays hit (%zu) to cost "
                 "any hit", blocked.count);
    lab_say(r, "  ok   %s: %zu rays agree with the reference; per primary ray %.1f %s and %.1f "
               "primitive tests (%s: %.1f and %.1f; %.2fx the %s); %s\n",
            spec, rays, mine.steps, yard->unit, mine.prims, yard->what, theirs.steps,
            theirs.prims, steps_x, yard->unit, occ_note);
out:
    if (a) s->kind->destroy(a);
    if (ref_a) refk->destroy(ref_a);
    for (int i = 0; i < GROUPS; i++) rays_free(&g[i].rays);
    free(blocked.rays);
    free(ph);
    scene_free(&sc);
}

/* ---- step 4 -------------------------------------------------------------- */

static void check_packets(const lab_subject *s, const char *spec, lab_result *r, accel_error *err)
{
    accel_scene sc;
    if (scene_create(spec, &sc, err)) {
        lab_fail(r, "scene %s: %s", spec, err->msg);
        return;
    }
    ray_group g[3];
    memset(g, 0, sizeof g);
    g[0].name = "primary (8x8 packets)";
    g[1].name = "shadow (packets)";
    g[2].name = "primary ending exactly at the hit (packets)";
    for (int i = 0; i < 3; i++) g[i].packets = 1;
    void *single = NULL, *packet = NULL;
    accel_build_stats st;
    accel_hit *ph = NULL;
    int size = s->quick ? 48 : 96;
    if (rays_primary(&sc.camera, size, size, &g[0].rays, err) ||
        !(ph = malloc(g[0].rays.count * sizeof *ph))) {
        lab_fail(r, "%s: could not make the rays", spec);
        goto out;
    }
    accel_reference_trace(&sc, g[0].rays.rays, ph, g[0].rays.count, s->threads);
    if (rays_shadow(&sc, &g[0].rays, ph, &g[1].rays, err) ||
        rays_ending_at_hit(&g[0].rays, ph, &g[2].rays, err)) {
        lab_fail(r, "%s: could not make the shadow rays: %s", spec, err->msg);
        goto out;
    }
    lab_where(r, "scene %s, your build with traverse=packet", spec);
    if (lab_build_subject(s, "traverse=packet", &sc, &packet, &st, err)) {
        lab_fail(r, "%s: your kind does not build with traverse=packet: %s", spec, err->msg);
        goto out;
    }
    for (int i = 0; i < 3; i++)
        if (!compare_group(s->kind, packet, &sc, &g[i], s->threads, r)) goto out;
    if (lab_build_subject(s, "", &sc, &single, &st, err)) {
        lab_fail(r, "%s: your build failed: %s", spec, err->msg);
        goto out;
    }
    accel_counters cp = {0};
    accel_hit *h = malloc(g[0].rays.count * sizeof *h);
    if (!h) goto out;
    accel_trace(s->kind, packet, g[0].rays.rays, h, g[0].rays.count, 1, &cp);
    free(h);
    double per_ray = steps_per_ray(s->kind, single, &g[0].rays, NULL);
    double fetched = (double)cp.packet_steps / (double)g[0].rays.count;
    if (!(fetched > 0.0)) {
        lab_fail(r, "%s: your packets fetch no node for the packet as a whole (counters.packet_steps "
                "stays 0): the packet mode still walks the tree once per ray. Walk it once per "
                "packet, entering a node when any active ray hits its box, and count each node "
                "the packet enters in packet_steps",
             spec);
        goto out;
    }
    /* A packet fetches at least every node its busiest ray needs, so the
     * fetches of all packets are at least the single rays' visits / 64. */
    size_t packets = (g[0].rays.count + 63) / 64;
    if (fetched * 64.0 < per_ray) {
        lab_fail(r, "%s: your %zu packets fetch %llu nodes in all (%.3f per ray), fewer than "
                "their rays need: single rays visit %.2f nodes each, so a packet of 64 fetches "
                "at least %.1f (every node its busiest ray visits). *packet_steps must count "
                "the nodes the packet's one walk enters, once per node, not packets or a "
                "number of your own",
             spec, packets, (unsigned long long)cp.packet_steps, fetched, per_ray, per_ray);
        goto out;
    }
    /* A packet enters a node once, for all its lanes: more fetches per ray
     * than a single ray's visits is a count per lane, not a slow walk. */
    if (fetched > per_ray) {
        lab_fail(r, "%s: your packets fetch %.2f nodes per ray, more than a single ray visits "
                    "(%.2f): *packet_steps counts a node once per lane, not once per packet. "
                    "Count each node the packet's one walk enters once, whatever the number "
                    "of lanes that enter it",
                 spec, fetched, per_ray);
        goto out;
    }
    if (fetched > 0.25 * per_ray) {
        lab_slow(r, "%s: your packets fetch %.2f nodes per ray, single rays visit %.2f: a packet of "
                "64 coherent rays should share most nodes (at most a quarter of a single ray's "
                "visits per ray). Hint: keep the first active ray's index, and pop a node "
                "only when no ray of the packet needs it",
             spec, fetched, per_ray);
        goto out;
    }
    lab_say(r, "  ok   %s: packets agree with the reference; %.3f node fetches per ray against %.1f "
           "node visits per single ray (%.0fx fewer)\n",
        spec, fetched, per_ray, per_ray / fetched);
out:
    if (single) s->kind->destroy(single);
    if (packet) s->kind->destroy(packet);
    for (int i = 0; i < 3; i++) rays_free(&g[i].rays);
    free(ph);
    scene_free(&sc);
}

/* ---- the steps ------------------------------------------------------------- */

static const char *const step_scenes[] = {"soup:tris=3000,seed=7", "teapot_stadium:n=4",
                                          "sphereflake:level=2", "cube:n=6"};

int lab_check(int step, const lab_subject *s, lab_result *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    out->passed = 1;
    if (step < 1 || step > LAB_STEPS)
        return accel_fail(err, ACCEL_ERR_SPEC, "lab: no step %d (steps are 1..%d)", step,
                          LAB_STEPS);
    lab_say(out, "step %d: %s, kind %s%s%s\n", step, lab_step_title(step), s->kind->name,
        *s->kv ? ":" : "", s->kv);
    /* Each scene's check runs in a child process: a crash is a report. */
    size_t n = sizeof step_scenes / sizeof step_scenes[0];
    switch (step) {
    case 1:
        for (size_t i = 0; i < n && out->passed; i++)
            lab_run_isolated(check_build, s, step_scenes[i], out, err);
        break;
    case 2:
    case 6:
        yard = step == 6 ? &grid_yard : &bvh_yard;
        for (size_t i = 0; i < n && out->passed; i++)
            lab_run_isolated(check_traversal, s, step_scenes[i], out, err);
        yard = &bvh_yard;
        break;
    case 3:
        lab_check_step3(s, out, err);
        break;
    case 4:
        for (size_t i = 0; i < 2 && out->passed; i++)
            lab_run_isolated(check_packets, s, step_scenes[i], out, err);
        break;
    case 5:
        lab_check_step5(s, step_scenes, n, out, err);
        break;
    case 7:
        lab_check_top(s, out, err);
        break;
    }
    return 0;
}
