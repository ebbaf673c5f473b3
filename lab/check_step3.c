/*
 * check_step3.c - step 3 of the lab (LAB.md): many meshes, rays in object
 * space. The subject's kind becomes the bottom level of the two-level
 * kind `instanced` (one structure per mesh, in object space, shared by
 * the mesh's instances), walked through the kind's accel.h walk; every
 * triangle the walk hands over is decided on its world-space copy. The
 * result must agree with the oracle on the flattened scene, ray by ray,
 * on multi-mesh scenes with scaled, mirrored, rotated and far instances.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_common.h"
#include "instanced/instanced.h"
#include "scene/scene.h"

/* Mirrored, scaled, rotated and far instances (1e5: the flattened
 * triangles are quantized there to 2^-7, so a walk without the pad
 * misses triangles the reference hits). */
const char *const lab_far_scene =
    "mesh s sphere:segments=6\n"
    "mesh t teapot_stadium:n=2,stadium=3,tiers=0\n"
    "instance s scale -1 1 1 translate 1e5 1e5 1e5\n"
    "instance s rotate 1 1 0 33 scale 2 -1 0.5 translate 100002.5 1e5 1e5\n"
    "instance t scale 0.01 translate 1e5 100001.3 1e5\n"
    "instance s rotate 0 0 1 10 translate 99998 1e5 1e5\n"
    "camera eye 100000 99990 100003 look 100001 100000 100000\n";

/* The instance and its local triangle for a flattened id. */
static void name_prim(const accel_scene *sc, uint32_t prim, lab_result *r)
{
    const accel_instances *set = sc->instances;
    for (uint32_t k = 0; set && k < set->instance_count; k++) {
        const accel_instance *in = &set->instances[k];
        uint32_t n = set->meshes[in->mesh].prim_count;
        if (prim >= in->base && prim < in->base + n) {
            lab_say(r, "triangle %u (instance %u, triangle %u of its mesh %u)", prim, k,
                    prim - in->base, in->mesh);
            return;
        }
    }
    lab_say(r, "triangle %u", prim);
}

static int compare(const lab_subject *s, const void *a, const accel_scene *sc, const char *what,
                   const rays_set *rays, lab_result *r)
{
    const accel_kind *k = &accel_kind_instanced;
    size_t n = rays->count;
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref), *hits = malloc((n ? n : 1) * sizeof *hits);
    uint8_t *occ = malloc(n ? n : 1);
    int ok = 0;
    if (!ref || !hits || !occ) {
        lab_fail(r, "out of memory");
        goto out;
    }
    lab_where(r, "scene %s, ray set %s", sc->name, what);
    accel_reference_trace(sc, rays->rays, ref, n, s->threads);
    accel_trace(k, a, rays->rays, hits, n, 1, NULL);
    hits_diff d = hits_compare(sc, rays->rays, ref, hits, n);
    if (d.first_bad != SIZE_MAX) {
        size_t i = d.first_bad;
        const accel_ray *ray = &rays->rays[i];
        lab_fail(r, "%s / %s rays: %zu holes (the reference hits, your bottom level never "
                    "handed the triangle over), %zu false hits, %zu other disagreements (a "
                    "farther or another triangle) of %zu rays. First: ray %zu",
                 sc->name, what, d.holes, d.false_hits, d.disagreements, n, i);
        lab_say(r, "         world ray o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g) t in [%g, %g]\n",
                ray->ox, ray->oy, ray->oz, ray->dx, ray->dy, ray->dz, ray->t_near, ray->t_far);
        lab_say(r, "         the reference hits ");
        if (ref[i].prim != ACCEL_MISS) {
            name_prim(sc, ref[i].prim, r);
            lab_say(r, " at t=%.9g; ", ref[i].t);
        } else {
            lab_say(r, "nothing; ");
        }
        if (hits[i].prim != ACCEL_MISS) {
            lab_say(r, "yours hits ");
            name_prim(sc, hits[i].prim, r);
            lab_say(r, " at t=%.9g\n", hits[i].t);
        } else {
            lab_say(r, "yours misses\n");
        }
        /* instanced decides every triangle itself, so a walk's mistakes are
         * holes (nothing, or a farther triangle): the rays say which. A walk
         * without the pad, or one that filters with its own triangle test,
         * passes field's primary and shadow rays and fails its vertex rays;
         * one that loses whole leaves fails the primary rays. */
        int hole = hits[i].prim == ACCEL_MISS ||
                   (ref[i].prim != ACCEL_MISS && hits[i].t > ref[i].t);
        const char *hint =
            !hole ? "a nearer hit than the reference, which a walk should not be able to cause "
                    "(instanced decides every triangle in world space): is lab_walk() as the "
                    "starter has it, and does visit() get scene ids, b->store.scene_id[...]?"
            : strcmp(what, "vertex and axis") == 0
                ? "these rays pass through triangle vertices and edges, where the object-space "
                  "mesh and its world-space copy differ: grow every box by pad on every side "
                  "(bmin - pad, bmax + pad) before box3_slab, the root's too, and hand every "
                  "primitive of a reached leaf to visit(), hit or not (no accel_prim_hit of "
                  "yours)"
                : "walk_ray() must hand every primitive of every leaf whose box, grown by pad, "
                  "the ray reaches to visit(), hit or not (no accel_prim_hit of yours), with "
                  "its scene id b->store.scene_id[b->order[left_first + i]]; test boxes "
                  "against [p->t_near, t_max] with the t_max visit() returns, never against 1 "
                  "or a world t (the walk's ray is in the mesh's object space: scaled, "
                  "mirrored, not normalized)";
        lab_say(r, "         hint: %s\n", hint);
        goto out;
    }
    accel_trace_occluded(k, a, rays->rays, occ, n, 1, NULL);
    for (size_t i = 0; i < n; i++)
        if (occ[i] != (ref[i].prim != ACCEL_MISS)) {
            lab_fail(r, "%s / %s rays: occluded() says %d for ray %zu, the reference %s: stop "
                        "the walk when visit() returns a t_max below t_near",
                     sc->name, what, occ[i], i, ref[i].prim != ACCEL_MISS ? "hits" : "misses");
            goto out;
        }
    ok = 1;
out:
    free(ref);
    free(hits);
    free(occ);
    return ok;
}

/* The walk's work per primary ray through instanced (nodes of the bottom
 * level and triangles handed over), against the same with the project's
 * median-split BVH as the bottom level: a walk that hands over every
 * primitive is correct and does no real work. 1 when within the rule. */
/* The walk's rule: a correct walk measures 1.00-1.09x the work of
 * bvh:build=median as the bottom level (instanced's own work per instance
 * is the same in both), one whose t_max never shrinks 1.4-1.8x, one that
 * ignores the tree 10-40x. */
#define LAB_WALK_RATIO 1.25

static int compare_work(const accel_scene *sc, const void *a, const rays_set *rays, lab_result *r,
                        accel_error *err)
{
    const accel_kind *k = &accel_kind_instanced, *bvh = accel_find_kind("bvh");
    void *ref = NULL;
    accel_build_stats st;
    if (!bvh || instanced_build_with_bottom(sc, "", bvh, "build=median", 1, &ref, &st, err)) {
        lab_say(r, "       (no yardstick for the walk's work: %s)\n", bvh ? err->msg : "no bvh");
        return 1;
    }
    accel_hit *h = malloc((rays->count ? rays->count : 1) * sizeof *h);
    accel_counters mine = {0}, theirs = {0};
    int ok = 1;
    if (h) {
        accel_trace(k, a, rays->rays, h, rays->count, 1, &mine);
        accel_trace(k, ref, rays->rays, h, rays->count, 1, &theirs);
        double n = rays->count ? (double)rays->count : 1.0;
        double m_nodes = (double)mine.level_steps[1] / n;
        double t_nodes = (double)theirs.level_steps[1] / n;
        double m_tris = (double)mine.prim_tests / n, t_tris = (double)theirs.prim_tests / n;
        double m = m_nodes + m_tris, t = t_nodes + t_tris;
        if (!(m_nodes > 0.0)) {
            lab_fail(r, "%s: your walk counts no node visits (*steps stays 0; per primary ray "
                        "0.0 nodes, the reference %.1f): count every node walk_ray() visits in "
                        "*steps, as trace_ray() does",
                     sc->name, t_nodes);
            ok = 0;
        } else if (t > 0.0 && m > LAB_WALK_RATIO * t) {
            lab_slow(r, "%s: your walk is right, but per primary ray it visits %.1f nodes and "
                        "hands over %.1f triangles; with the project's median-split BVH as the "
                        "bottom level (instanced:bottom=bvh:build=median) %.1f and %.1f (%.2fx "
                        "the work; at most %.2fx passes). Hint: %s",
                     sc->name, m_nodes, m_tris, t_nodes, t_tris, m / t, LAB_WALK_RATIO,
                     m > LAB_BOX_RATIO * t
                         ? "walk the tree as in step 2: hand over only the primitives of leaves "
                           "whose padded box the ray reaches, not every primitive"
                         : "test boxes against [p->t_near, t_max] with the t_max visit() "
                           "returns (it shrinks with every hit), and drop a popped node with "
                           "!box3_entry_before(entry, t_max): a walk whose t_max never shrinks "
                           "measures 1.4-1.8x; nearer child first");
            ok = 0;
        } else if (t_nodes > 0.0 && m_nodes < LAB_COUNT_LOW * t_nodes) {
            lab_fail(r, "%s: your walk's counter *steps says %.1f nodes per primary ray, %.2fx "
                        "the reference's %.1f, below what any correct walk counts (at least "
                        "%.2fx): count every node visited, interior nodes too, not only leaves",
                     sc->name, m_nodes, m_nodes / t_nodes, t_nodes, LAB_COUNT_LOW);
            ok = 0;
        } else {
            lab_say(r, "       %s: %.1f nodes and %.1f triangles per primary ray "
                       "(instanced:bottom=bvh:build=median: %.1f and %.1f)\n",
                    sc->name, m_nodes, m_tris, t_nodes, t_tris);
        }
    }
    free(h);
    k->destroy(ref);
    return ok;
}

static void check_scene(const lab_subject *s, const char *name, const char *text, lab_result *r,
                        accel_error *err)
{
    accel_scene sc;
    int rc = text ? scene_parse_scene(name, "", text, strlen(text), NULL, &sc, err)
                  : scene_create(name, &sc, err);
    if (rc) {
        lab_fail(r, "scene %s: %s", name, err->msg);
        return;
    }
    rays_set g[3];
    memset(g, 0, sizeof g);
    static const char *const what[3] = {"primary", "shadow", "vertex and axis"};
    accel_hit *ph = NULL;
    void *a = NULL;
    accel_build_stats st;
    int size = s->quick ? 40 : 64;
    if (rays_primary(&sc.camera, size, size, &g[0], err) ||
        !(ph = malloc(g[0].count * sizeof *ph))) {
        lab_fail(r, "%s: could not make the rays", name);
        goto out;
    }
    accel_reference_trace(&sc, g[0].rays, ph, g[0].count, s->threads);
    if (rays_shadow(&sc, &g[0], ph, &g[1], err) || lab_make_stiff_rays(&sc, &g[2], err)) {
        lab_fail(r, "%s: could not make the rays: %s", name, err->msg);
        goto out;
    }
    lab_where(r, "scene %s, your build (once per mesh)", name);
    if (instanced_build_with_bottom(&sc, "", s->kind, s->kv, 1, &a, &st, err)) {
        lab_fail(r, "%s: instanced with your kind as the bottom level: %s", name, err->msg);
        goto out;
    }
    for (int i = 0; i < 3; i++)
        if (!compare(s, a, &sc, what[i], &g[i], r)) goto out;
    if (!compare_work(&sc, a, &g[0], r, err)) goto out;
    lab_say(r, "  ok   %s: %u meshes, %u instances, %zu rays agree with the reference on the "
               "flattened scene\n",
            name, sc.instances ? sc.instances->mesh_count : 1,
            sc.instances ? sc.instances->instance_count : 1, g[0].count + g[1].count + g[2].count);
out:
    if (a) accel_kind_instanced.destroy(a);
    for (int i = 0; i < 3; i++) rays_free(&g[i]);
    free(ph);
    scene_free(&sc);
}

static void check_builtin(const lab_subject *s, const char *scene, lab_result *r, accel_error *err)
{
    check_scene(s, scene, NULL, r, err);
}

static void check_far(const lab_subject *s, const char *scene, lab_result *r, accel_error *err)
{
    check_scene(s, scene, lab_far_scene, r, err);
}

void lab_check_step3(const lab_subject *s, lab_result *r, accel_error *err)
{
    if (!s->kind->walk) {
        lab_fail(r, "your kind has no walk (accel_kind.walk): write walk_ray() (LAB.md, step 3) "
                    "and keep `.walk = lab_walk` in the kind's table");
        return;
    }
    lab_run_isolated(check_builtin, s, "field:instances=30,detail=2", r, err);
    if (r->passed)
        lab_run_isolated(check_builtin, s, "animated:frame=77,instances=6,detail=2", r, err);
    if (r->passed) lab_run_isolated(check_far, s, "far_instances", r, err);
}
