/*
 * brute.c - the `brute` kind: every live primitive against every ray, in
 * float, with the shared kernels of prim.h. The study's O(N*M) baseline,
 * and the smallest complete accelerator kind: the template a student
 * copies to start a new one (parameters, build, batch kernels through the
 * variant table, memory, destroy).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"

/* ---- brute: the float O(N*M) baseline ------------------------------------ */

typedef struct {
    const accel_scene *scene;
    int naive;
} brute_accel;

static int brute_build(const accel_scene *scene, const accel_params *params, int threads,
                       void **out, accel_build_stats *stats, accel_error *err)
{
    (void)threads;
    brute_accel *b = malloc(sizeof *b);
    if (!b) return accel_fail(err, ACCEL_ERR_NOMEM, "brute: out of memory");
    b->scene = scene;
    b->naive = params->naive;
    memset(stats, 0, sizeof *stats);
    stats->bytes = sizeof *b;
    stats->sah_cost = NAN;
    *out = b;
    return 0;
}

/* One kernel for both queries; the flags are constants in every copy. */
static inline __attribute__((always_inline)) void
brute_kernel(const brute_accel *b, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres)
{
    const accel_scene *s = b->scene;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t tests = 0;
        if (accel_prep_ray(&rays[i], &p)) {
            float t = p.t_far, u, v;
            for (uint32_t k = 0; k < s->live_count; k++) {
                tests++;
                if (accel_prim_hit(s, s->live[k], &p, &t, &u, &v, naive, spheres)) {
                    h.t = t, h.u = u, h.v = v, h.prim = s->live[k];
                    if (occ) break;
                }
            }
        }
        if (occ)
            occ[i] = h.prim != ACCEL_MISS;
        else
            hits[i] = h;
        if (c) {
            c->rays++;
            c->prim_tests += tests;
            if (c->ray_steps) c->ray_steps[i] = 0;
            if (c->ray_prims) c->ray_prims[i] = tests;
        }
    }
}

#define BRUTE_DISPATCH(b, rays, hits, occ, n, c)                                        \
    do {                                                                                \
        int sph_ = (b)->scene->sphere_count > 0;                                        \
        if (c) {                                                                        \
            brute_kernel(b, rays, hits, occ, n, c, (b)->naive, sph_);                   \
        } else if ((b)->naive) {                                                        \
            if (sph_) brute_kernel(b, rays, hits, occ, n, NULL, 1, 1);                  \
            else brute_kernel(b, rays, hits, occ, n, NULL, 1, 0);                       \
        } else {                                                                        \
            if (sph_) brute_kernel(b, rays, hits, occ, n, NULL, 0, 1);                  \
            else brute_kernel(b, rays, hits, occ, n, NULL, 0, 0);                       \
        }                                                                               \
    } while (0)

static void brute_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,
                            accel_counters *c)
{
    const brute_accel *b = a;
    c = ACCEL_COUNTERS_ON(c);
    BRUTE_DISPATCH(b, rays, hits, (uint8_t *)NULL, n, c);
}

static void brute_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,
                           accel_counters *c)
{
    const brute_accel *b = a;
    c = ACCEL_COUNTERS_ON(c);
    BRUTE_DISPATCH(b, rays, (accel_hit *)NULL, occ, n, c);
}

static size_t brute_memory(const void *a)
{
    (void)a;
    return sizeof(brute_accel);
}

static void brute_destroy(void *a) { free(a); }

static const char *const brute_variants[] = {"", "tri=naive", NULL};

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
};
