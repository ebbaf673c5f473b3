/*
 * brute.c - the `brute` kind: every primitive against every ray, in float,
 * with the shared kernels of prim.h. The study's O(N*M) baseline, and the
 * smallest complete accelerator kind: the template a student copies to
 * start a new one. Its parts, in the order a kind needs them:
 *
 *   1. the built structure: here only the primitive store (accel.h), the
 *      copy of the live primitives every kind starts from;
 *   2. build: parse nothing (no parameters of its own), copy the store;
 *   3. the kernel, written once as an always-inline function taking a
 *      counters pointer and the variant flags, compiled into one table of
 *      specialized copies per query (core/variant.h);
 *   4. the batch entries, memory, destroy, and the kind's table, which
 *      core/registry.c lists.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"
#include "core/variant.h"

typedef struct {
    accel_prim_store store; /* the live primitives, local ids (accel.h) */
    int naive;              /* tri=naive */
} brute_accel;

static void brute_destroy(void *a)
{
    brute_accel *b = a;
    if (!b) return;
    accel_prim_store_free(&b->store);
    free(b);
}

static size_t brute_memory(const void *a)
{
    const brute_accel *b = a;
    return sizeof *b + accel_prim_store_bytes(&b->store);
}

static int brute_build(const accel_scene *scene, const accel_params *params, int threads,
                       void **out, accel_build_stats *stats, accel_error *err)
{
    (void)threads;
    *out = NULL;
    brute_accel *b = calloc(1, sizeof *b);
    if (!b) return accel_fail(err, ACCEL_ERR_NOMEM, "brute: out of memory");
    int rc = accel_prim_store_build(scene, params->reorder, &b->store, err);
    if (rc) {
        free(b);
        return rc;
    }
    b->naive = params->naive;
    memset(stats, 0, sizeof *stats);
    stats->bytes = brute_memory(b);
    stats->refs = b->store.prims.prim_count;
    stats->sah_cost = NAN;
    *out = b;
    return 0;
}

/* One kernel for both queries (occ != NULL: any hit). The flags are
 * literals in every timed copy, so the sphere and naive branches vanish;
 * brute has no option of its own (opt). */
static inline __attribute__((always_inline)) void
brute_kernel(const brute_accel *b, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres, int opt)
{
    (void)opt;
    const accel_scene *s = &b->store.prims;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t tests = 0;
        if (accel_prep_ray(&rays[i], &p)) {
            float t = p.t_far, u, v;
            for (uint32_t k = 0; k < s->prim_count; k++) {
                tests++;
                if (accel_prim_hit(s, k, &p, &t, &u, &v, naive, spheres)) {
                    h.t = t, h.u = u, h.v = v, h.prim = k;
                    if (occ) break;
                }
            }
        }
        accel_prim_store_answer(&b->store, h, hits, occ, i);
        if (c) accel_count_ray(c, i, 0, 0, 0, tests, 0);
    }
}

ACCEL_KERNEL_PAIR_NO_OPT(brute, brute_kernel)

static unsigned brute_flags(const brute_accel *b)
{
    return accel_variant_flags(b->naive, b->store.prims.sphere_count > 0, 0);
}

static void brute_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,
                            accel_counters *c)
{
    accel_run_kernel(&brute_hit_table, a, rays, hits, n, c, brute_flags(a));
}

static void brute_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,
                           accel_counters *c)
{
    accel_run_kernel(&brute_occ_table, a, rays, occ, n, c, brute_flags(a));
}

static const char *const brute_variants[] = {"", "tri=naive", "reorder=0", NULL};

/* accel.h's conservative walk (brute): every primitive whose bounding
 * box grown by the pad the ray reaches (the store's own walk). */
static int brute_walk(const void *a, const accel_ray *ray, float pad, accel_walk_visit visit,
                       void *ctx, uint32_t *steps)
{
    return accel_prim_store_walk(&((const brute_accel *)a)->store, ray, pad, visit, ctx, steps);
}

const accel_kind accel_kind_brute = {
    .name = "brute",
    .summary = "every primitive against every ray (float): the O(N*M) baseline",
    .step_name = "nodes",
    .params = NULL,
    .param_count = 0,
    .variants = brute_variants,
    .build = brute_build,
    .intersect = brute_intersect,
    .occluded = brute_occluded,
    .memory = brute_memory,
    .destroy = brute_destroy,
    .walk = brute_walk,
};
