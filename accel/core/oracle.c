/*
 * oracle.c - the double-precision reference every test compares against.
 *
 * accel_reference_trace: every live primitive against every ray, in double
 * precision, with the watertight triangle test (Woop, Benthin, Wald, JCGT
 * 2013) and the cancellation-free sphere test. Its only job is to be right:
 * every test compares the accelerators against it with the FORMATS.md rule.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"

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

