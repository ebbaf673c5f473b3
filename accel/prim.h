/*
 * prim.h - ray preparation and ray/primitive intersection, shared by every
 * backend (and by the double-precision reference in reference.c).
 *
 * Triangles: the watertight test of Woop, Benthin and Wald, "Watertight
 * Ray/Triangle Intersection", JCGT 2(1), 2013, is the default: a ray that
 * crosses a shared edge or vertex hits at least one of the triangles meeting
 * there. The Moller-Trumbore test (JGT 1997) is kept as the "naive" variant
 * because the stability experiments compare the two.
 *
 * Spheres: the numerically careful form of Haines et al., "Precision
 * Improvements for Ray/Sphere Intersection", Ray Tracing Gems ch. 7, 2019
 * (the discriminant from the squared distance of the centre to the ray).
 *
 * Barycentrics follow FORMATS.md: u and v weigh the second and third vertex.
 */
#ifndef ACCEL_PRIM_H
#define ACCEL_PRIM_H

#include "geom.h"
#include "accel.h"

/* Per-ray constants every kernel needs, computed once per ray. */
typedef struct {
    vec3 org, dir, inv_dir;
    int neg[3];           /* sign bit of dir per axis: picks slab near planes */
    int kx, ky, kz;       /* watertight: kz = dominant axis, winding-preserving kx, ky */
    float sx, sy, sz;     /* watertight shear constants */
    float t_near, t_far;
} accel_ray_prep;

/* Fills *p from *r. Returns 0 for a ray that can hit nothing: NaN or infinite
 * origin or direction, a zero direction, NaN bounds or t_near > t_far. */
static inline int accel_prep_ray(const accel_ray *r, accel_ray_prep *p)
{
    p->org = v3(r->ox, r->oy, r->oz);
    p->dir = v3(r->dx, r->dy, r->dz);
    p->t_near = r->t_near;
    p->t_far = r->t_far;
    if (!(isfinite(r->ox) && isfinite(r->oy) && isfinite(r->oz) && isfinite(r->dx) &&
          isfinite(r->dy) && isfinite(r->dz)))
        return 0;
    if (!(r->t_near <= r->t_far)) return 0; /* also rejects NaN */
    p->inv_dir = v3(1.0f / r->dx, 1.0f / r->dy, 1.0f / r->dz);
    p->neg[0] = signbit(r->dx) != 0;
    p->neg[1] = signbit(r->dy) != 0;
    p->neg[2] = signbit(r->dz) != 0;
    float ax = fabsf(r->dx), ay = fabsf(r->dy), az = fabsf(r->dz);
    int kz = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
    const float d[3] = {r->dx, r->dy, r->dz};
    if (d[kz] == 0.0f) return 0; /* zero direction */
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0f) { int t = kx; kx = ky; ky = t; }
    p->kx = kx; p->ky = ky; p->kz = kz;
    p->sx = d[kx] / d[kz];
    p->sy = d[ky] / d[kz];
    p->sz = 1.0f / d[kz];
    return 1;
}

static inline float v3_idx(vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }

/* Watertight triangle test. On a hit within [t_near, *t] stores t, u, v and returns 1. */
static inline int accel_tri_watertight(const accel_ray_prep *p, const float *tri, float *t,
                                       float *u, float *v)
{
    vec3 a = v3_sub(v3_load(tri), p->org);
    vec3 b = v3_sub(v3_load(tri + 3), p->org);
    vec3 c = v3_sub(v3_load(tri + 6), p->org);
    float az_ = v3_idx(a, p->kz), bz_ = v3_idx(b, p->kz), cz_ = v3_idx(c, p->kz);
    float ax = v3_idx(a, p->kx) - p->sx * az_, ay = v3_idx(a, p->ky) - p->sy * az_;
    float bx = v3_idx(b, p->kx) - p->sx * bz_, by = v3_idx(b, p->ky) - p->sy * bz_;
    float cx = v3_idx(c, p->kx) - p->sx * cz_, cy = v3_idx(c, p->ky) - p->sy * cz_;
    float U = cx * by - cy * bx;
    float V = ax * cy - ay * cx;
    float W = bx * ay - by * ax;
    /* An edge function that rounds to exactly zero is redone in double, so
     * that a ray through an edge or vertex is decided consistently for every
     * triangle sharing it (Woop et al. 2013, section 3). */
    if (U == 0.0f || V == 0.0f || W == 0.0f) {
        U = (float)((double)cx * by - (double)cy * bx);
        V = (float)((double)ax * cy - (double)ay * cx);
        W = (float)((double)bx * ay - (double)by * ax);
    }
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return 0;
    float det = U + V + W;
    if (det == 0.0f) return 0;
    float T = U * (p->sz * az_) + V * (p->sz * bz_) + W * (p->sz * cz_);
    /* Compare T/det against the t range without dividing. A hit at exactly
     * *t is accepted, so t = t_far is inside the ray as FORMATS.md says. */
    float sgn = det < 0.0f ? -1.0f : 1.0f;
    det *= sgn;
    T *= sgn;
    if (T < p->t_near * det || T > *t * det) return 0;
    float rcp = 1.0f / det;
    *t = T * rcp;
    *u = V * sgn * rcp;
    *v = W * sgn * rcp;
    return 1;
}

/* Moller-Trumbore, single precision, no epsilon tricks beyond a zero
 * determinant check: the classic "naive" test of the stability study. */
static inline int accel_tri_naive(const accel_ray_prep *p, const float *tri, float *t, float *u,
                                  float *v)
{
    vec3 v0 = v3_load(tri);
    vec3 e1 = v3_sub(v3_load(tri + 3), v0);
    vec3 e2 = v3_sub(v3_load(tri + 6), v0);
    vec3 pv = v3_cross(p->dir, e2);
    float det = v3_dot(e1, pv);
    if (det == 0.0f) return 0;
    float inv = 1.0f / det;
    vec3 s = v3_sub(p->org, v0);
    float bu = v3_dot(s, pv) * inv;
    if (bu < 0.0f || bu > 1.0f) return 0;
    vec3 q = v3_cross(s, e1);
    float bv = v3_dot(p->dir, q) * inv;
    if (bv < 0.0f || bu + bv > 1.0f) return 0;
    float tt = v3_dot(e2, q) * inv;
    if (!(tt >= p->t_near && tt <= *t)) return 0;
    *t = tt;
    *u = bu;
    *v = bv;
    return 1;
}

/* Ray/sphere (centre xyz, radius w). Reports the nearest root in
 * [t_near, *t]; u = v = 0 for spheres. */
static inline int accel_sphere_hit(const accel_ray_prep *p, const float *s, float *t, float *u,
                                   float *v)
{
    vec3 c = v3_load(s);
    float r = s[3];
    vec3 f = v3_sub(p->org, c);
    float a = v3_dot(p->dir, p->dir);
    float b = -v3_dot(f, p->dir); /* half of -b in the textbook quadratic */
    /* |f - (f.d/a) d|^2: the squared distance of the centre to the ray's line,
     * computed without cancellation (Ray Tracing Gems, eq. 7.5). */
    vec3 l = v3_add(f, v3_scale(p->dir, b / a));
    float disc = r * r - v3_dot(l, l);
    if (disc < 0.0f) return 0;
    float q = b + copysignf(sqrtf(a * disc), b);
    float t0 = q / a, t1 = v3_dot(f, f) - r * r;
    t1 = q != 0.0f ? t1 / q : t0;
    if (t0 > t1) { float tmp = t0; t0 = t1; t1 = tmp; }
    float tt = t0 >= p->t_near ? t0 : t1;
    if (!(tt >= p->t_near && tt <= *t)) return 0;
    *t = tt;
    *u = 0.0f;
    *v = 0.0f;
    return 1;
}

/*
 * Intersect primitive `prim` of scene `s`. The flags are meant to be
 * compile-time constants in each kernel copy: with has_spheres = 0 the
 * type dispatch disappears, with naive = 0 only the watertight test is
 * emitted. Returns 1 and updates *t, *u, *v on a closer hit.
 */
static inline int accel_prim_hit(const accel_scene *s, uint32_t prim, const accel_ray_prep *p,
                                 float *t, float *u, float *v, int naive, int has_spheres)
{
    if (has_spheres && prim >= s->tri_count)
        return accel_sphere_hit(p, s->spheres + 4 * (size_t)(prim - s->tri_count), t, u, v);
    const float *tri = s->tris + 9 * (size_t)prim;
    return naive ? accel_tri_naive(p, tri, t, u, v) : accel_tri_watertight(p, tri, t, u, v);
}

#endif
