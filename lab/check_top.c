/*
 * check_top.c - the optional step 7 of the lab (LAB.md): the top level of a
 * two-level scene written by the student (lab/top.h), as the lecture's step
 * 3 means it: a loop over instances, the world ray taken to each mesh's
 * object space by the inverse transform, t kept in world units.
 *
 * The yardstick is the same loop over the same instances with the
 * project's median-split BVH per mesh, written here: in object space both
 * kinds are exact, so on the same object rays they agree. A student whose
 * transform differs in rounding (float instead of double) moves a few rays
 * across triangle edges and silhouettes; those disagreements are allowed up
 * to LAB_TOP_EDGE_SHARE of the rays. Not allowed: a hit at another t (t in
 * object units: a renormalized direction), a farther instance than the
 * nearest (not the nearest over instances), or many misses (no, or the
 * wrong, transform).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_common.h"
#include "scene/scene.h"

#define LAB_TOP_EDGE_SHARE 0.02

/* The check's own top level: the yardstick (see the file's comment). */
static void reference_top(const lab_top *top, const accel_ray *ray, accel_hit *hit)
{
    *hit = accel_hit_miss();
    const double o[3] = {ray->ox, ray->oy, ray->oz}, d[3] = {ray->dx, ray->dy, ray->dz};
    for (uint32_t k = 0; k < top->instance_count; k++) {
        const double *m = top->instances[k].inverse;
        float oo[3], od[3];
        for (int r = 0; r < 3; r++) {
            oo[r] = (float)(m[4 * r] * o[0] + m[4 * r + 1] * o[1] + m[4 * r + 2] * o[2] +
                            m[4 * r + 3]);
            od[r] = (float)(m[4 * r] * d[0] + m[4 * r + 1] * d[1] + m[4 * r + 2] * d[2]);
        }
        accel_ray obj = {oo[0], oo[1], oo[2], ray->t_near, od[0], od[1], od[2],
                         hit->prim != ACCEL_MISS ? hit->t : ray->t_far};
        accel_hit h;
        top->kind->intersect(top->mesh_accel[top->instances[k].mesh], &obj, &h, 1, NULL);
        if (h.prim != ACCEL_MISS && (hit->prim == ACCEL_MISS || h.t < hit->t)) {
            *hit = h;
            hit->prim = top->instances[k].base + h.prim;
        }
    }
}

/* The instance a flattened id belongs to (instances are in base order). */
static uint32_t instance_of(const lab_top *top, uint32_t prim)
{
    uint32_t k = 0;
    while (k + 1 < top->instance_count && top->instances[k + 1].base <= prim) k++;
    return k;
}

/* Builds `kind` over every mesh of sc; 0 or an error status. */
static int build_meshes(const accel_kind *kind, const char *kv, const accel_scene *sc,
                        lab_top *top, accel_error *err)
{
    const accel_instances *set = sc->instances;
    void **a = calloc(set->mesh_count ? set->mesh_count : 1, sizeof *a);
    if (!a) return accel_fail(err, ACCEL_ERR_NOMEM, "lab: out of memory");
    top->kind = kind;
    top->mesh_accel = a;
    top->instances = set->instances;
    top->instance_count = set->instance_count;
    for (uint32_t m = 0; m < set->mesh_count; m++) {
        accel_build_stats st;
        int rc = accel_build_kind(kind, kv, &set->meshes[m], 1, &a[m], &st, err);
        if (rc) return rc;
    }
    return 0;
}

static void free_meshes(const accel_scene *sc, lab_top *top)
{
    for (uint32_t m = 0; top->mesh_accel && m < sc->instances->mesh_count; m++)
        if (top->mesh_accel[m]) top->kind->destroy(top->mesh_accel[m]);
    free((void *)top->mesh_accel);
}

/* Compares the subject's top level with the yardstick on the rays. */
static void compare_top(const lab_subject *s, const lab_top *mine, const lab_top *ref,
                        const char *scene, const rays_set *rays, lab_result *r)
{
    size_t edge = 0, n = rays->count;
    for (size_t i = 0; i < n; i++) {
        accel_hit a, b;
        reference_top(ref, &rays->rays[i], &a);
        s->top(mine, &rays->rays[i], &b);
        if (a.prim == ACCEL_MISS && b.prim == ACCEL_MISS) continue;
        int both = a.prim != ACCEL_MISS && b.prim != ACCEL_MISS;
        uint32_t ia = both ? instance_of(ref, a.prim) : 0, ib = both ? instance_of(ref, b.prim) : 0;
        int same_t = both && fabsf(a.t - b.t) <= 1e-4f * fmaxf(1.0f, fabsf(a.t));
        if (!both || (ia != ib && same_t)) { /* across an edge or silhouette */
            edge++;
            continue;
        }
        if (same_t) continue;
        const accel_ray *ray = &rays->rays[i];
        lab_fail(r, "%s / primary rays: ray %zu o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g): the "
                    "reference hits instance %u (triangle %u of its mesh) at t=%.9g, yours "
                    "instance %u (triangle %u) at t=%.9g",
                 scene, i, ray->ox, ray->oy, ray->oz, ray->dx, ray->dy, ray->dz, ia,
                 a.prim - ref->instances[ia].base, a.t, ib, b.prim - ref->instances[ib].base,
                 b.t);
        lab_say(r, "         hint: %s\n",
                ia == ib ? "the same triangle at another t: keep t in world units (do not "
                           "renormalize the object-space direction; the instance may be scaled, "
                           "even mirrored or scaled differently per axis)"
                : b.t > a.t ? "a farther instance than the nearest: pass the nearest t so far as "
                              "t_far to every instance's trace, and keep the smallest t"
                            : "a nearer hit than the reference: are ids base + h.prim, and the "
                              "direction transformed without the translation column?");
        return;
    }
    if ((double)edge > LAB_TOP_EDGE_SHARE * (double)n) {
        lab_fail(r, "%s / primary rays: %zu of %zu rays hit where the reference misses, or miss "
                    "where it hits (more than %.0f%%: not the rounding of a few edges). Hint: "
                    "the object ray is inverse * (origin, 1) and inverse * (direction, 0): the "
                    "world -> object matrix (`inverse`), the translation column for the origin "
                    "only",
                 scene, edge, n, 100.0 * LAB_TOP_EDGE_SHARE);
        return;
    }
    lab_say(r, "  ok   %s: %zu instances, %zu primary rays agree with the reference top level "
               "(%zu across edges)\n",
            scene, (size_t)ref->instance_count, n, edge);
}

static void check_top_scene(const lab_subject *s, const char *name, lab_result *r,
                            accel_error *err)
{
    const char *text = strcmp(name, "far_instances") == 0 ? lab_far_scene : NULL;
    accel_scene sc;
    int rc = text ? scene_parse_scene(name, "", text, strlen(text), NULL, &sc, err)
                  : scene_create(name, &sc, err);
    if (rc) {
        lab_fail(r, "scene %s: %s", name, err->msg);
        return;
    }
    lab_top mine = {0}, ref = {0};
    rays_set rays = {0};
    const accel_kind *bvh = accel_find_kind("bvh");
    int size = s->quick ? 40 : 64;
    lab_where(r, "scene %s, your kind built per mesh", name);
    if (!sc.instances || !bvh) {
        lab_fail(r, "%s: no instances, or no bvh kind in this build", name);
    } else if (build_meshes(s->kind, s->kv, &sc, &mine, err)) {
        lab_fail(r, "%s: your build of a mesh failed: %s", name, err->msg);
    } else if (build_meshes(bvh, "build=median", &sc, &ref, err) ||
               rays_primary(&sc.camera, size, size, &rays, err)) {
        lab_fail(r, "%s: the reference could not run: %s", name, err->msg);
    } else {
        lab_where(r, "scene %s, ray set primary, your top level", name);
        compare_top(s, &mine, &ref, name, &rays, r);
    }
    if (sc.instances) {
        free_meshes(&sc, &mine);
        free_meshes(&sc, &ref);
    }
    rays_free(&rays);
    scene_free(&sc);
}

void lab_check_top(const lab_subject *s, lab_result *r, accel_error *err)
{
    if (!s->top) {
        lab_fail(r, "no top level to check: step 7 checks lab_top_student() in lab/student.c "
                    "(bin-lab/lab --step 7 with the kind `student`)");
        return;
    }
    lab_run_isolated(check_top_scene, s, "far_instances", r, err);
    if (r->passed) lab_run_isolated(check_top_scene, s, "field:instances=30,detail=2", r, err);
}
