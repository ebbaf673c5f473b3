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
    double o[3], d[3];
    int kx, ky, kz;
    double sx, sy, sz;
    double t_near, t_far;
} ref_ray;

static int ref_prep(const accel_ray *r, ref_ray *p)
{
    accel_ray_prep fp;
    if (!accel_prep_ray(r, &fp)) return 0;
    p->o[0] = r->ox, p->o[1] = r->oy, p->o[2] = r->oz;
    p->d[0] = r->dx, p->d[1] = r->dy, p->d[2] = r->dz;
    p->kx = fp.kx, p->ky = fp.ky, p->kz = fp.kz;
    p->sx = p->d[p->kx] / p->d[p->kz];
    p->sy = p->d[p->ky] / p->d[p->kz];
    p->sz = 1.0 / p->d[p->kz];
    p->t_near = r->t_near;
    p->t_far = r->t_far;
    return 1;
}

static int ref_tri(const ref_ray *r, const float *tri, double *t, double *u, double *v)
{
    double a[3], b[3], c[3];
    for (int i = 0; i < 3; i++) {
        a[i] = (double)tri[i] - r->o[i];
        b[i] = (double)tri[3 + i] - r->o[i];
        c[i] = (double)tri[6 + i] - r->o[i];
    }
    double ax = a[r->kx] - r->sx * a[r->kz], ay = a[r->ky] - r->sy * a[r->kz];
    double bx = b[r->kx] - r->sx * b[r->kz], by = b[r->ky] - r->sy * b[r->kz];
    double cx = c[r->kx] - r->sx * c[r->kz], cy = c[r->ky] - r->sy * c[r->kz];
    double U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
    if ((U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0)) return 0;
    double det = U + V + W;
    if (det == 0.0) return 0;
    double T = (U * a[r->kz] + V * b[r->kz] + W * c[r->kz]) * r->sz;
    double tt = T / det;
    if (!(tt >= r->t_near && tt <= *t)) return 0;
    *t = tt;
    *u = V / det;
    *v = W / det;
    return 1;
}

static int ref_sphere(const ref_ray *r, const float *s, double *t)
{
    double f[3], a = 0, b = 0, ff = 0;
    for (int i = 0; i < 3; i++) {
        f[i] = r->o[i] - (double)s[i];
        a += r->d[i] * r->d[i];
        b -= f[i] * r->d[i];
        ff += f[i] * f[i];
    }
    double rr = (double)s[3] * s[3], l2 = 0;
    for (int i = 0; i < 3; i++) {
        double l = f[i] + r->d[i] * (b / a);
        l2 += l * l;
    }
    double disc = rr - l2;
    if (disc < 0) return 0;
    double q = b + copysign(sqrt(a * disc), b);
    double t0 = q / a, t1 = q != 0 ? (ff - rr) / q : t0;
    if (t0 > t1) { double x = t0; t0 = t1; t1 = x; }
    double tt = t0 >= r->t_near ? t0 : t1;
    if (!(tt >= r->t_near && tt <= *t)) return 0;
    *t = tt;
    return 1;
}

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
        ref_ray r;
        if (ref_prep(&j->rays[i], &r)) {
            double t = r.t_far, u = 0, v = 0;
            uint32_t best = ACCEL_MISS;
            for (uint32_t k = 0; k < s->live_count; k++) {
                uint32_t prim = s->live[k];
                int hit = prim < s->tri_count
                              ? ref_tri(&r, s->tris + 9 * (size_t)prim, &t, &u, &v)
                              : ref_sphere(&r, s->spheres + 4 * (size_t)(prim - s->tri_count), &t);
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
