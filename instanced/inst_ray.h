/*
 * inst_ray.h - the per-ray steps every walk of the `instanced` kind
 * shares (k8_trace.c ray by ray, inst_packet.c in packets), so that both
 * compute them with the very same operations: a world ray taken to an
 * instance's object space with the pad that keeps the bottom walk
 * conservative, and the world triangles the decision is made on (a
 * leaf's world block for the shared block test, core/block_test.h; one
 * triangle for the walks that meet them one by one). README.md explains
 * the pad and why the decision is made in world space.
 */
#ifndef INSTANCED_INST_RAY_H
#define INSTANCED_INST_RAY_H

#include <math.h>

#include "core/prim.h"
#include "inst_impl.h"

#include "core/simd.h"

/* AVX2 where bvh/wide's vectors are (core/simd.h: not with BVH_NO_SIMD). */
#if WIDE_AVX
#include <immintrin.h>
#define INST_WIDE_AVX 1
#else
#define INST_WIDE_AVX 0
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define INST_INLINE static inline __attribute__((always_inline))

/* Object block ob (instance it's mesh, core/block.h) taken to world
 * space into wb: every vertex by accel_xform_vertex's expression (per row
 * fma(r0, x, fma(r1, y, fma(r2, z, r3))) rounded once to float), 4 lanes
 * per double vector, so each lane is the flattened triangle bit for bit;
 * ids base + q. A lane dead in the flattened scene (no area; only where
 * the instance has such lanes) becomes a point, which the block test
 * never hits (U = V = W = 0: its double test finds det = 0). */
INST_INLINE void inst_world_block(const inst_item *it, const accel_block8 *ob, accel_block8 *wb)
{
    const double *m = it->xform;
#if INST_WIDE_AVX && defined(__FMA__)
    for (int h = 0; h < 8; h += 4)
        for (int vtx = 0; vtx < 3; vtx++) {
            __m256d x = _mm256_cvtps_pd(_mm_loadu_ps(&ob->v[vtx][0][h]));
            __m256d y = _mm256_cvtps_pd(_mm_loadu_ps(&ob->v[vtx][1][h]));
            __m256d z = _mm256_cvtps_pd(_mm_loadu_ps(&ob->v[vtx][2][h]));
            for (int r = 0; r < 3; r++) {
                const double *row = m + 4 * r;
                __m256d acc = _mm256_fmadd_pd(_mm256_set1_pd(row[2]), z, _mm256_set1_pd(row[3]));
                acc = _mm256_fmadd_pd(_mm256_set1_pd(row[1]), y, acc);
                acc = _mm256_fmadd_pd(_mm256_set1_pd(row[0]), x, acc);
                _mm_storeu_ps(&wb->v[vtx][r][h], _mm256_cvtpd_ps(acc));
            }
        }
#else
    for (int lane = 0; lane < 8; lane++)
        for (int vtx = 0; vtx < 3; vtx++) {
            float p[3] = {ob->v[vtx][0][lane], ob->v[vtx][1][lane], ob->v[vtx][2][lane]}, w[3];
            accel_xform_vertex(m, p, w);
            for (int r = 0; r < 3; r++) wb->v[vtx][r][lane] = w[r];
        }
#endif
    for (int lane = 0; lane < 8; lane++) wb->id[lane] = it->base + ob->id[lane];
    if (!it->has_dead) return;
    for (int lane = 0; lane < 8; lane++) {
        float t[9];
        for (int k = 0; k < 9; k++) t[k] = wb->v[k / 3][k % 3][lane];
        if (accel_tri_is_degenerate(t))
            for (int k = 3; k < 9; k++) wb->v[k / 3][k % 3][lane] = t[k % 3];
    }
}

/* Compare-and-select (libm's fmax is a call: it must order NaNs). */
INST_INLINE double inst_dmax(double a, double b) { return a > b ? a : b; }
INST_INLINE double inst_dmin(double a, double b) { return a < b ? a : b; }

/* A world ray in an instance's object space. */
typedef struct {
    double o[3], d[3]; /* o' = A^-1 (o - T), d' = A^-1 d, in double */
    double oa, da;     /* max |o'|, max |d'| */
    double e_ray;      /* bound on the rounding of o' and d' */
    double pad;        /* the object-space pad (0 with pad=0) */
    double s0;         /* start of the range clipped to the mesh's padded box */
} inst_oray;

/* Takes the world ray (wo, wd) with range [t_near, t_far] to instance
 * it's object space and clips it to its mesh's box grown by the pad.
 * Returns -1 when the ray cannot reach the mesh without a box test (a
 * direction that vanishes in object space, an axis-parallel ray outside
 * the slab), 0 when the clipped range is empty, 1 when it is not. */
INST_INLINE int inst_object_ray(const inst_accel *a, const inst_item *it, const inst_bottom *b,
                                const double *wo, const double *wd, double t_near, double t_far,
                                inst_oray *q)
{
    const double *m = it->inverse;
    double eo = 0.0, ed = 0.0, oa = 0.0, da = 0.0;
    for (int i = 0; i < 3; i++) {
        const double *row = m + 4 * i;
        q->o[i] = row[0] * wo[0] + row[1] * wo[1] + row[2] * wo[2] + row[3];
        q->d[i] = row[0] * wd[0] + row[1] * wd[1] + row[2] * wd[2];
        eo = inst_dmax(eo, fabs(row[0] * wo[0]) + fabs(row[1] * wo[1]) + fabs(row[2] * wo[2]) +
                              fabs(row[3]));
        ed = inst_dmax(ed, fabs(row[0] * wd[0]) + fabs(row[1] * wd[1]) + fabs(row[2] * wd[2]));
        oa = inst_dmax(oa, fabs(q->o[i]));
        da = inst_dmax(da, fabs(q->d[i]));
    }
    if (!(da > 0.0) || !isfinite(oa) || !isfinite(da)) return -1;
    q->oa = oa, q->da = da;
    /* Points that matter lie in the padded box: |t d| <= |o| + B + pad. */
    double reach = oa + b->abs_max + 4.0 * it->pad + 1.0;
    q->e_ray = 0x1p-50 * (eo + ed * reach / da);
    double pad = a->no_pad ? 0.0 : 2.0 * it->pad + q->e_ray;
    q->pad = pad;
    /* Clip to the mesh's box grown by the pad. */
    double s0 = t_near, s1 = t_far;
    for (int i = 0; i < 3; i++) {
        double lo = b->box_lo[i] - pad, hi = b->box_hi[i] + pad;
        if (q->d[i] == 0.0) {
            if (q->o[i] < lo || q->o[i] > hi) return -1;
            continue;
        }
        /* One division (a product's extra rounding is far inside the
         * slack); a reciprocal that overflows (d subnormal) divides. */
        double inv = 1.0 / q->d[i];
        double t0 = isfinite(inv) ? (lo - q->o[i]) * inv : (lo - q->o[i]) / q->d[i];
        double t1 = isfinite(inv) ? (hi - q->o[i]) * inv : (hi - q->o[i]) / q->d[i];
        if (t0 > t1) { double x = t0; t0 = t1; t1 = x; }
        double slack = 0x1p-40 * (fabs(t0) + fabs(t1));
        s0 = inst_dmax(s0, t0 - slack);
        s1 = inst_dmin(s1, t1 + slack);
    }
    q->s0 = s0;
    return s0 <= s1;
}

/* The float ray a BVH walk follows: from the box entry (parameter t - s0),
 * so that its rounding is bounded by the box's size, not by how far away
 * the ray started; *pad the box growth that covers it. */
INST_INLINE void inst_object_float(const inst_accel *a, const inst_bottom *b, const inst_oray *q,
                                   vec3 *org, vec3 *dir, float *pad)
{
    const double *o = q->o, *d = q->d, s0 = q->s0;
    *org = v3((float)(o[0] + s0 * d[0]), (float)(o[1] + s0 * d[1]), (float)(o[2] + s0 * d[2]));
    *dir = v3((float)d[0], (float)d[1], (float)d[2]);
    double pf = a->no_pad ? 0.0
                          : q->pad + 0x1p-20 * (b->abs_max + 2.0 * q->pad) +
                                0x1p-50 * (q->oa + fabs(s0) * q->da);
    *pad = (float)(pf * (1.0 + 0x1p-20));
}

/* The walk's range [t_near, t] in its parameter (t - shift), widened by a
 * relative slack for non-identity instances (the world test decides). */
INST_INLINE float inst_walk_lo(float t_near, double shift, float slack)
{
    float lo = (float)((double)t_near - shift);
    if (slack != 0.0f) lo -= fabsf(lo) * slack; /* never 0 * inf */
    return lo;
}
INST_INLINE float inst_walk_hi(float t, double shift, float slack)
{
    float hi = (float)((double)t - shift);
    if (slack != 0.0f) hi += fabsf(hi) * slack;
    return hi;
}

/* The decision of one primitive for the walks that meet primitives one
 * by one (width=2, the grids, a walked kind): the shared scalar tests of
 * core/prim.h (those the block test runs on its uncertain and sphere
 * lanes), on the world triangle tri (or a plain scene's sphere) within
 * [t_near, *t]; a triangle dead in the flattened scene (no area: checked
 * where the instance has such triangles, dead) is never hit. Returns 1
 * when id becomes the closest hit. */
INST_INLINE int inst_decide(const accel_ray_prep *p, const float *tri, const float *sphere,
                            uint32_t id, int naive, int dead, float *t, float *u, float *v,
                            uint32_t *prim)
{
    float th = *t, uh = 0.0f, vh = 0.0f;
    int hit = sphere  ? accel_sphere_hit(p, sphere, &th, &uh, &vh)
              : naive ? accel_tri_naive(p, tri, &th, &uh, &vh)
                      : accel_tri_watertight(p, tri, &th, &uh, &vh);
    if (!hit || (dead && !sphere && accel_tri_is_degenerate(tri))) return 0;
    *t = th, *u = uh, *v = vh, *prim = id;
    return 1;
}

#ifdef __cplusplus
}
#endif

#endif
