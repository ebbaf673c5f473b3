/*
 * reference.c - the oracle and the brute-force baseline.
 *
 * accel_reference_trace: every live primitive against every ray, in double
 * precision, with the watertight triangle test (Woop, Benthin, Wald, JCGT
 * 2013) and the cancellation-free sphere test. Its only job is to be right:
 * every test compares the accelerators against it with the FORMATS.md rule.
 *
 * brute: the same O(N*M) loop in float with the shared kernels of prim.h:
 * the study's baseline, and the simplest example of an accelerator kind.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "prim.h"

typedef struct {
    const accel_scene *scene;
    const accel_ray *rays;
    accel_hit *hits;
} ref_job;

static void ref_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    ref_job *j = p;
    const accel_scene *s = j->scene;
    for (size_t i = begin; i < end; i++) {
        accel_hit h = accel_hit_miss();
        accel_ray_prep fp;
        accel_ray_d r;
        if (accel_prep_ray(&j->rays[i], &fp)) {
            accel_prep_ray_d(&fp, &r);
            double t = fp.t_far, u = 0, v = 0;
            uint32_t best = ACCEL_MISS;
            for (uint32_t k = 0; k < s->live_count; k++) {
                uint32_t prim = s->live[k];
                int hit = prim < s->tri_count
                              ? accel_tri_watertight_d(&r, s->tris + 9 * (size_t)prim, &t, &u, &v)
                              : accel_sphere_hit_d(&r, s->spheres + 4 * (size_t)(prim - s->tri_count), &t);
                if (hit) {
                    best = prim;
                    if (prim >= s->tri_count) u = v = 0;
                }
            }
            if (best != ACCEL_MISS) {
                h.t = (float)t;
                h.prim = best;
                h.u = (float)u;
                h.v = (float)v;
            }
        }
        j->hits[i] = h;
    }
}

void accel_reference_trace(const accel_scene *scene, const accel_ray *rays, accel_hit *hits,
                           size_t count, int threads)
{
    ref_job j = {scene, rays, hits};
    accel_parallel_for(count, 256, threads, ref_chunk, &j);
}

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
