/*
 * prim.h - ray preparation and ray/primitive intersection, shared by every
 * backend (and by the double-precision reference, the oracle: core/oracle.c).
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

#include <string.h>

#include "core/geom.h"
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

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
    p->kx = 0, p->ky = 1, p->kz = 2;
    p->sx = p->sy = p->sz = 0.0f;
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

/* A triangle with no interior: its edge cross product, computed in double,
 * is exactly zero. scene_finish
 * leaves such triangles out of the live list; a kind that makes triangles
 * on the fly (the two-level kind's world-space copies) applies the same
 * test, so it never hits one that the flattened scene holds dead. */
static inline int accel_tri_is_degenerate(const float *t)
{
    double e1[3], e2[3];
    for (int i = 0; i < 3; i++) {
        e1[i] = (double)t[3 + i] - t[i];
        e2[i] = (double)t[6 + i] - t[i];
    }
    double cx = e1[1] * e2[2] - e1[2] * e2[1];
    double cy = e1[2] * e2[0] - e1[0] * e2[2];
    double cz = e1[0] * e2[1] - e1[1] * e2[0];
    return cx == 0.0 && cy == 0.0 && cz == 0.0;
}

static inline float v3_idx(vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }

/* ---- double precision: the reference's arithmetic ------------------------
 * The oracle (core/oracle.c) runs these on every primitive. The float kernels
 * below fall back to them whenever their own rounding could change an
 * inside/outside decision, so that a float kernel and the reference decide
 * every ray through an edge, a vertex or a silhouette the same way. */
typedef struct {
    double o[3], d[3];
    int kx, ky, kz;
    double sx, sy, sz;
    double t_near;
} accel_ray_d;

static inline void accel_prep_ray_d(const accel_ray_prep *p, accel_ray_d *r)
{
    r->o[0] = p->org.x, r->o[1] = p->org.y, r->o[2] = p->org.z;
    r->d[0] = p->dir.x, r->d[1] = p->dir.y, r->d[2] = p->dir.z;
    r->kx = p->kx, r->ky = p->ky, r->kz = p->kz;
    r->sx = r->d[r->kx] / r->d[r->kz];
    r->sy = r->d[r->ky] / r->d[r->kz];
    r->sz = 1.0 / r->d[r->kz];
    r->t_near = p->t_near;
}

/*
 * t of a triangle hit from its plane: t = n.(v0 - o) / n.d with the normal
 * n = (v1 - v0) x (v2 - v0) in double, for the rare hit whose watertight t
 * is not certain (accel_tri_watertight_d). a = v0 - o as rounded there.
 * *err gets a bound on |t - exact plane t| (exact for the float vertices
 * and ray), to first order in eps = 2^-53: each edge component is rounded
 * once, a normal component n_i = p - q errs by at most 4 eps (|p| + |q|)
 * =: 4 eps nb_i, so n_i a_i errs by at most 6 eps nb_i |a_i| and the sum
 * adds 2 eps sum |n_i a_i| <= 2 eps sum nb_i |a_i|: 8 eps, and 7 eps for
 * n.d (d is exact), taken as 16 eps. Unlike the watertight form, whose
 * numerator sums the vertices' offsets along the ray's dominant axis, the
 * plane form weights each axis by the normal: for a huge, nearly flat
 * triangle (vertices at 1e30 in x and y, z in [-3.5, -3]) and a ray whose
 * dominant axis is x, the offsets +-1e30 cancel in the watertight sum
 * (error ~ eps 1e30 in t) but carry a tiny normal weight here.
 * err is +inf when n.d is within its error of zero (a ray along the plane).
 */
static double accel_tri_plane_t_d(const accel_ray_d *r, const float *tri, const double *a,
                                  double *err) __attribute__((noinline, cold));
static double accel_tri_plane_t_d(const accel_ray_d *r, const float *tri, const double *a,
                                  double *err)
{
    double e1[3], e2[3], num = 0, den = 0, bn = 0, bd = 0;
    for (int i = 0; i < 3; i++) {
        e1[i] = (double)tri[3 + i] - tri[i];
        e2[i] = (double)tri[6 + i] - tri[i];
    }
    for (int i = 0; i < 3; i++) {
        int j = i == 2 ? 0 : i + 1, k = j == 2 ? 0 : j + 1;
        double p = e1[j] * e2[k], q = e1[k] * e2[j], n = p - q, nb = fabs(p) + fabs(q);
        num += n * a[i];
        den += n * r->d[i];
        bn += nb * fabs(a[i]);
        bd += nb * fabs(r->d[i]);
    }
    const double eps = 16.0 * 0x1p-53;
    double t = num / den, ed = eps * bd;
    *err = ed < 0.5 * fabs(den)
               ? (eps * bn + fabs(t) * ed) / (fabs(den) - ed) + 0x1p-52 * fabs(t)
               : INFINITY;
    return t;
}

/*
 * The watertight t made certain to float precision. tt = num sz / det is
 * the watertight form with error bound et (see below); when et is not below
 * 2^-24 |tt| (finer than the float the reference reports) or does not
 * decide tt against t_near, the plane form is tried and taken when its own
 * bound is smaller. It is then clamped into [tt - et, tt + et] (the exact t
 * lies there too, so clamping only brings it closer) and into [min, max] of
 * the vertices' offsets along kz times sz, where tt lies up to its own
 * rounding and where a hit's exact t lies (the hit point is in the
 * triangle): oracle.c's culling argument (its point 2) stays true. Depends
 * on the ray and the triangle only, never on the current hit, so the
 * brute-force loop and the culled oracle, which test in different orders,
 * get the same t bitwise.
 */
static double accel_tri_refine_t_d(const accel_ray_d *r, const float *tri, const double *a,
                                   const double *z, double tt, double et)
    __attribute__((noinline, cold));
static double accel_tri_refine_t_d(const accel_ray_d *r, const float *tri, const double *a,
                                   const double *z, double tt, double et)
{
    double ep, tp = accel_tri_plane_t_d(r, tri, a, &ep);
    if (!(ep < et) || !isfinite(tp)) return tt;
    double t0 = z[0] * r->sz, t1 = z[1] * r->sz, t2 = z[2] * r->sz;
    double lo = fmin(t0, fmin(t1, t2)), hi = fmax(t0, fmax(t1, t2));
    tp = fmin(fmax(tp, tt - et), tt + et);
    return fmin(fmax(tp, lo), hi);
}

/* Watertight test (Woop et al. 2013) in double; hit if t in [t_near, *t]. */
static inline int accel_tri_watertight_d(const accel_ray_d *r, const float *tri, double *t,
                                         double *u, double *v)
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
    /* All three edge functions within double rounding of zero: the ray lies
     * in the triangle's plane (its projection is a segment), and a tiny
     * rounded determinant would give an arbitrary t. Edge-on is a miss. */
    double mx[3], my[3];
    const double *pts[3] = {a, b, c};
    for (int i = 0; i < 3; i++) {
        mx[i] = fabs(pts[i][r->kx]) + fabs(r->sx * pts[i][r->kz]);
        my[i] = fabs(pts[i][r->ky]) + fabs(r->sy * pts[i][r->kz]);
    }
    const double eps = 16.0 * 0x1p-53;
    double eU = eps * (mx[2] * my[1] + my[2] * mx[1]);
    double eV = eps * (mx[0] * my[2] + my[0] * mx[2]);
    double eW = eps * (mx[1] * my[0] + my[1] * mx[0]);
    if (fabs(U) <= eU && fabs(V) <= eV && fabs(W) <= eW) return 0;
    const double z[3] = {a[r->kz], b[r->kz], c[r->kz]};
    double num = U * z[0] + V * z[1] + W * z[2];
    double tt = num * r->sz / det;
    /* Its error bound, as the float test's (same filter constant): the sum's
     * rounding plus each edge function's bound carried by its offset, and
     * det's error (eU + eV + eW) through the division; the shear's rounded
     * ratios move the direction by a few eps, negligible beside these. For
     * vertices at 1e30 along kz, the offsets cancel in num and et ~ 1e14
     * (tests/test_oracle_huge.c). In ordinary scenes et is some tens of
     * eps times the offsets' size in t units (max |z| |sz|), below
     * 2^-24 |tt| except for hits at t under about 2^-23 of that size: a ray
     * leaving a surface it starts on (t ~ 0), where the plane form gives
     * t = 0 for an origin exactly in the plane instead of +-2^-60 noise.
     * Primary rays of the built-in scenes keep every answer bitwise. */
    double za = fabs(z[0]), zb = fabs(z[1]), zc = fabs(z[2]), ed = eU + eV + eW;
    double en = eps * (fabs(U) * za + fabs(V) * zb + fabs(W) * zc) + eU * za + eV * zb + eW * zc;
    double et = ed < 0.5 * fabs(det)
                    ? (fabs(r->sz) * en + fabs(tt) * ed) / (fabs(det) - ed) + eps * fabs(tt)
                    : INFINITY;
    if (!(et <= 0x1p-24 * fabs(tt) && fabs(tt - r->t_near) > et))
        tt = accel_tri_refine_t_d(r, tri, a, z, tt, et);
    if (!(tt >= r->t_near && tt <= *t)) return 0;
    *t = tt;
    *u = V / det;
    *v = W / det;
    return 1;
}

/* Ray/sphere in double, same formulation as the float test below. */
static inline int accel_sphere_hit_d(const accel_ray_d *r, const float *s, double *t)
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

/*
 * Bound on the float error of an edge function (the filter idea of
 * Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
 * Geometric Predicates", 1997). With u = 2^-24, a sheared coordinate such as
 * ax = (v0 - o)[kx] - sx (v0 - o)[kz] is within 4u M_ax of its exact value,
 * M_ax = |ax_| + |sx| |az_| (the origin subtraction, sx's own rounding, the
 * product and the difference). U = cx by - cy bx then errs by at most
 *   6u (|cx| M_by + |by| M_cx + |cy| M_bx + |bx| M_cy) + 16u^2 (M_cx M_by + M_cy M_bx)
 * (the inputs' errors carried by the other factor, plus the products' and
 * the difference's rounding; the second term is the product of two input
 * errors). The filter takes 16u and 32u^2: room for the bound's own
 * rounding and for the double reference's much smaller error. The first
 * term scales with the sheared coordinates, which are small next to the
 * distances M for a triangle near the ray: an earlier bound,
 * 16u (M_cx M_by + M_cy M_bx), sent 0.4 of the primary rays that hit the
 * armadillo to the double test (41,900 calls for 110,631 hits, callgrind,
 * 800x600), against 1 in 90 with this one (1,267 calls).
 */
#define ACCEL_EDGE_FILTER (16.0f * 0x1p-24f)
#define ACCEL_EDGE_FILTER2 (32.0f * 0x1p-48f)
/* The bounds above are relative: a product or difference that falls into
 * the subnormal range errs by up to half a subnormal step (2^-150) instead,
 * whatever its size. Every bound adds ACCEL_EDGE_TINY for that: a ray
 * within ~1e-38 of a triangle's plane (a direction component of 1e-38) made
 * sheared coordinates subnormal and a float sign "sure" that the double
 * test contradicts (a hostile-ray audit). It is 2^-126, the smallest normal
 * float (2^24 such steps), not a subnormal: it enters every bound of every
 * test, and on Intel cores an operation with a subnormal operand takes a
 * microcode assist. With 2^-140 there, the 8-wide single-ray kernel traced
 * teapot_stadium's primary rays at 1.0 Mrays/s instead of 5.0 on an Intel
 * Xeon (model 207, 2026-12-04; AMD's cores take subnormals at full speed,
 * which is why the runs after the audit did not show it). A larger slack
 * only sends more tests to the double test: the answers stay exact. */
#define ACCEL_EDGE_TINY 0x1p-126f

/*
 * Precision of a sure float hit. FORMATS.md compares answers with t within
 * 1e-4 max(1, |t|) and u, v within 1e-3 of the exact ones; the float test
 * misses that for a triangle tiny beside its distance from the ray's origin
 * (rounding of the origin-relative coordinates), a grazing ray (a small
 * det) or a huge triangle (T sums large offsets to a small t): the strict
 * comparison found such hits in 8 stiff scenes of the suites (tiny_huge,
 * grazing, mirrored_scaled, ...), t off by up to 6e-4 relative, u by 3e-3.
 * To first order in u = 2^-24, an edge function U errs by u e_U with
 * e_U = |cx| M_by + |by| M_cx + |cy| M_bx + |bx| M_cy (the bracket of the
 * tight bound of ACCEL_EDGE_FILTER), so u, v err by about
 * 2 u (e_U + e_V + e_W) / det and t by
 * u (4 sum |U_i| |z_i| + sum e_i |z_i - t|) / det (z_i: vertex i's offset
 * along the ray in t units; a change of the edge functions moves t by
 * their weights times z_i - t, and the products and sums round). A hit
 * is imprecise when the first bound may exceed 1e-3 (e sum > 2^13 det) or
 * the second 2^-15 max(1, |t|); such hits take the double test, like an
 * uncertain sign. Measured on the primary and diffuse rays of the bunny,
 * soup:tris=100000 and teapot_stadium (512x384), the largest u, v error
 * below the first threshold was 1.8e-4, and 0.00-0.29% of hits were sent
 * to the double test. Any-hit queries need not ask (hit or miss is exact).
 * NaN or overflow anywhere is imprecise.
 */
static inline __attribute__((always_inline)) int
accel_tri_imprecise(float eU, float eV, float eW, float aU, float aV, float aW, float za, float zb,
                    float zc, float det, float t)
{
    float m1 = fabsf(t) > 1.0f ? fabsf(t) : 1.0f;
    float sum = aU * fabsf(za) + aV * fabsf(zb) + aW * fabsf(zc);
    float et = 4.0f * sum + eU * fabsf(za - t) + eV * fabsf(zb - t) + eW * fabsf(zc - t);
    return !(eU + eV + eW <= 0x1p13f * det && et <= 0x1p9f * det * m1);
}

static int accel_tri_fallback(const accel_ray_prep *p, const float *tri, float *t, float *u,
                              float *v) __attribute__((noinline, cold));
static int accel_tri_fallback(const accel_ray_prep *p, const float *tri, float *t, float *u,
                              float *v)
{
    accel_ray_d r;
    accel_prep_ray_d(p, &r);
    double tt = *t, uu, vv;
    if (!accel_tri_watertight_d(&r, tri, &tt, &uu, &vv)) return 0;
    float tf = (float)tt;
    if (tf > *t) tf = *t; /* rounding must not push the hit past the current one */
    *t = tf;
    *u = (float)uu;
    *v = (float)vv;
    return 1;
}

/* A triangle's vertices relative to a ray's origin, on its permuted axes:
 * the part of the watertight test that depends on the ray only through its
 * origin and kx, ky, kz, so that rays sharing them (a packet of primary
 * rays from a pinhole camera) compute it once per triangle. */
typedef struct {
    float ax_, ay_, az_, bx_, by_, bz_, cx_, cy_, cz_;
} accel_tri_rel;

/* 1 when accel_tri_rel_of gives the same for rays a and b: the same origin,
 * bit for bit, and the same permuted axes. */
static inline int accel_prep_same_frame(const accel_ray_prep *a, const accel_ray_prep *b)
{
    return memcmp(&a->org, &b->org, sizeof a->org) == 0 && a->kx == b->kx && a->ky == b->ky &&
           a->kz == b->kz;
}

static inline void accel_tri_rel_of(const accel_ray_prep *p, const float *tri, accel_tri_rel *q)
{
    vec3 a = v3_sub(v3_load(tri), p->org);
    vec3 b = v3_sub(v3_load(tri + 3), p->org);
    vec3 c = v3_sub(v3_load(tri + 6), p->org);
    q->az_ = v3_idx(a, p->kz), q->bz_ = v3_idx(b, p->kz), q->cz_ = v3_idx(c, p->kz);
    q->ax_ = v3_idx(a, p->kx), q->ay_ = v3_idx(a, p->ky);
    q->bx_ = v3_idx(b, p->kx), q->by_ = v3_idx(b, p->ky);
    q->cx_ = v3_idx(c, p->kx), q->cy_ = v3_idx(c, p->ky);
}

/* Watertight triangle test; accel_tri_watertight_rel takes the triangle's
 * relative vertices *q, accel_tri_rel_of(p, tri) or of a ray with p's
 * origin and axes, and accel_tri_watertight computes them. On a hit
 * within [t_near, *t] stores t, u, v and returns 1. The edge functions are
 * computed in float; when one of them is too close to zero for its sign to
 * be certain (a ray through an edge, a vertex or a silhouette), the whole
 * test is redone in double exactly as the reference does it, so float and
 * reference never disagree on coverage. */
static inline __attribute__((always_inline)) int
accel_tri_watertight_impl(const accel_ray_prep *p, const float *tri, const accel_tri_rel *given, float *t,
                          float *u, float *v)
{
    /* accel_tri_rel_of written out, not called: through a struct, gcc 12
     * shuffled nine registers more on every kind's scalar test. */
    float az_, bz_, cz_, ax_, ay_, bx_, by_, cx_, cy_;
    if (given) {
        az_ = given->az_, bz_ = given->bz_, cz_ = given->cz_;
        ax_ = given->ax_, ay_ = given->ay_, bx_ = given->bx_, by_ = given->by_;
        cx_ = given->cx_, cy_ = given->cy_;
    } else {
        vec3 a = v3_sub(v3_load(tri), p->org);
        vec3 b = v3_sub(v3_load(tri + 3), p->org);
        vec3 c = v3_sub(v3_load(tri + 6), p->org);
        az_ = v3_idx(a, p->kz), bz_ = v3_idx(b, p->kz), cz_ = v3_idx(c, p->kz);
        ax_ = v3_idx(a, p->kx), ay_ = v3_idx(a, p->ky);
        bx_ = v3_idx(b, p->kx), by_ = v3_idx(b, p->ky);
        cx_ = v3_idx(c, p->kx), cy_ = v3_idx(c, p->ky);
    }
    float ax = ax_ - p->sx * az_, ay = ay_ - p->sy * az_;
    float bx = bx_ - p->sx * bz_, by = by_ - p->sy * bz_;
    float cx = cx_ - p->sx * cz_, cy = cy_ - p->sy * cz_;
    float U = cx * by - cy * bx;
    float V = ax * cy - ay * cx;
    float W = bx * ay - by * ax;
    /* Quick reject: a clear sign mix is a miss whatever the rounding. */
    float sxa = fabsf(p->sx), sya = fabsf(p->sy);
    float max_ = fabsf(ax_) + sxa * fabsf(az_), may_ = fabsf(ay_) + sya * fabsf(az_);
    float mbx_ = fabsf(bx_) + sxa * fabsf(bz_), mby_ = fabsf(by_) + sya * fabsf(bz_);
    float mcx_ = fabsf(cx_) + sxa * fabsf(cz_), mcy_ = fabsf(cy_) + sya * fabsf(cz_);
    /* The cheap bound 16u (M_cx M_by + M_cy M_bx) first (valid too: the
     * sheared coordinates are at most about M); when it leaves a sign
     * uncertain, the tight bound of ACCEL_EDGE_FILTER, the smaller kept. */
    float eu = ACCEL_EDGE_FILTER * (mcx_ * mby_ + mcy_ * mbx_) + ACCEL_EDGE_TINY;
    float ev = ACCEL_EDGE_FILTER * (max_ * mcy_ + may_ * mcx_) + ACCEL_EDGE_TINY;
    float ew = ACCEL_EDGE_FILTER * (mbx_ * may_ + mby_ * max_) + ACCEL_EDGE_TINY;
    for (int pass = 0;; pass++) {
        int sure_neg = U < -eu || V < -ev || W < -ew;
        int sure_pos = U > eu || V > ev || W > ew;
        if (sure_neg && sure_pos) return 0;
        if (fabsf(U) > eu && fabsf(V) > ev && fabsf(W) > ew) break;
        if (pass) return accel_tri_fallback(p, tri, t, u, v);
        const float f2 = ACCEL_EDGE_FILTER2 / ACCEL_EDGE_FILTER;
        float tu = ACCEL_EDGE_FILTER * (fabsf(cx) * mby_ + fabsf(by) * mcx_ + fabsf(cy) * mbx_ +
                                        fabsf(bx) * mcy_) + f2 * eu + ACCEL_EDGE_TINY;
        float tv = ACCEL_EDGE_FILTER * (fabsf(ax) * mcy_ + fabsf(cy) * max_ + fabsf(ay) * mcx_ +
                                        fabsf(cx) * may_) + f2 * ev + ACCEL_EDGE_TINY;
        float tw = ACCEL_EDGE_FILTER * (fabsf(bx) * may_ + fabsf(ay) * mbx_ + fabsf(by) * max_ +
                                        fabsf(ax) * mby_) + f2 * ew + ACCEL_EDGE_TINY;
        /* the smaller; a NaN bound stays NaN (the sign stays uncertain) */
        eu = tu < eu ? tu : eu, ev = tv < ev ? tv : ev, ew = tw < ew ? tw : ew;
    }
    float det = U + V + W;
    float T = U * (p->sz * az_) + V * (p->sz * bz_) + W * (p->sz * cz_);
    /* Compare T/det against the t range without dividing. A hit at exactly
     * *t is accepted, so t = t_far is inside the ray as FORMATS.md says. */
    float sgn = det < 0.0f ? -1.0f : 1.0f;
    det *= sgn;
    T *= sgn;
    /* A subnormal det (a ray within ~1e-38 of the triangle's plane) has no
     * finite reciprocal, and the range products below would underflow:
     * 1/det was infinite and t = T/det NaN (a hostile-ray audit: a 1e-38
     * direction component along a cube face). The double test decides. */
    if (!(det >= 0x1p-126f)) return accel_tri_fallback(p, tri, t, u, v);
    /* T carries rounding too: a hit within its error of either end of the
     * t range (a secondary ray re-hitting its own surface at t ~ 0, a hit
     * at the current closest distance) is decided in double as well. */
    /* Its bound: the rounding of the sum itself, plus each edge function's
     * own error bound carried through its factor (a huge triangle seen from
     * just above its plane sums large terms to a tiny T). */
    float za = fabsf(p->sz * az_), zb = fabsf(p->sz * bz_), zc = fabsf(p->sz * cz_);
    float et = ACCEL_EDGE_FILTER * (fabsf(U) * za + fabsf(V) * zb + fabsf(W) * zc) +
               eu * za + ev * zb + ew * zc + ACCEL_EDGE_TINY;
    /* det errs by at most ed = eu + ev + ew, plus its sum's rounding
     * (covered by et's slack): the exact det lies in [dlo, dhi], and each
     * end of the t range times det in the product's range for its sign. */
    float ed = eu + ev + ew, dlo = det - ed, dhi = det + ed;
    int near_pos = p->t_near >= 0.0f, far_pos = *t >= 0.0f;
    float lo_out = p->t_near * (near_pos ? dlo : dhi), lo_in = p->t_near * (near_pos ? dhi : dlo);
    float hi_out = *t * (far_pos ? dhi : dlo), hi_in = *t * (far_pos ? dlo : dhi);
    if (T < lo_out - et || T > hi_out + et) return 0;
    /* Written so that a NaN (overflow at coordinates near FLT_MAX, or an
     * infinite *t times a det within its error of 0) also goes to the
     * double test, whose range covers it. */
    if (!(T > lo_in + et && T < hi_in - et)) return accel_tri_fallback(p, tri, t, u, v);
    float rcp = 1.0f / det, tt = T * rcp;
    /* A sure hit whose t, u, v float cannot give to FORMATS.md's
     * tolerance (accel_tri_imprecise) is redone in double as well. */
    float eU = fabsf(cx) * mby_ + fabsf(by) * mcx_ + fabsf(cy) * mbx_ + fabsf(bx) * mcy_;
    float eV = fabsf(ax) * mcy_ + fabsf(cy) * max_ + fabsf(ay) * mcx_ + fabsf(cx) * may_;
    float eW = fabsf(bx) * may_ + fabsf(ay) * mbx_ + fabsf(by) * max_ + fabsf(ax) * mby_;
    if (accel_tri_imprecise(eU, eV, eW, fabsf(U), fabsf(V), fabsf(W), p->sz * az_, p->sz * bz_,
                            p->sz * cz_, det, tt))
        return accel_tri_fallback(p, tri, t, u, v);
    *t = tt;
    *u = V * sgn * rcp;
    *v = W * sgn * rcp;
    return 1;
}

/* The watertight test of one ray and triangle (the body above, with the
 * relative vertices computed in it: the same code as before the split). */
static inline int accel_tri_watertight(const accel_ray_prep *p, const float *tri, float *t,
                                       float *u, float *v)
{
    return accel_tri_watertight_impl(p, tri, NULL, t, u, v);
}

static inline int accel_tri_watertight_rel(const accel_ray_prep *p, const float *tri,
                                           const accel_tri_rel *q, float *t, float *u, float *v)
{
    return accel_tri_watertight_impl(p, tri, q, t, u, v);
}

/*
 * A triangle's edge functions as affine functions of the ray's shear, for
 * rays that share its relative vertices *q (one origin, the same axes):
 * E = e0 + sx e1 + sy e2 for U, V, W (the sx sy terms of the sheared
 * products cancel), with the magnitudes m0 + |sx| m1 + |sy| m2 of the same
 * sums of absolute values. A packet culls the triangle for a ray whose
 * edge functions are surely of mixed signs (accel_tri_aff_miss): the exact
 * test's first rule, so the ray's answer is what it would have been.
 * "Surely" means beyond ACCEL_AFF_REL times the magnitude plus
 * ACCEL_AFF_ABS: far above the roundings that separate these float values
 * from the double test's (its relative vertices and shear rounded once
 * each in float, about 10 roundings of 2^-24 in all, and underflow); a NaN
 * or infinity fails every comparison, so never culls. The 8-wide form is
 * core/block_test.h's leaf_aff.
 */
#define ACCEL_AFF_REL 0x1p-16f
#define ACCEL_AFF_ABS 0x1p-120f
typedef struct {
    float e0[3], e1[3], e2[3], m0[3], m1[3], m2[3];
} accel_tri_aff;

static inline void accel_tri_aff_edge(accel_tri_aff *f, int k, float px, float py, float pz, float qx,
                                      float qy, float qz)
{
    f->e0[k] = px * qy - py * qx, f->e1[k] = py * qz - pz * qy, f->e2[k] = pz * qx - px * qz;
    f->m0[k] = fabsf(px * qy) + fabsf(py * qx), f->m1[k] = fabsf(py * qz) + fabsf(pz * qy);
    f->m2[k] = fabsf(pz * qx) + fabsf(px * qz);
}

static inline void accel_tri_aff_of(const accel_tri_rel *q, accel_tri_aff *f)
{
    accel_tri_aff_edge(f, 0, q->cx_, q->cy_, q->cz_, q->bx_, q->by_, q->bz_); /* U */
    accel_tri_aff_edge(f, 1, q->ax_, q->ay_, q->az_, q->cx_, q->cy_, q->cz_); /* V */
    accel_tri_aff_edge(f, 2, q->bx_, q->by_, q->bz_, q->ax_, q->ay_, q->az_); /* W */
}

/* 1 when the ray of shear (sx, sy) surely misses the triangle of *f. */
static inline int accel_tri_aff_miss(const accel_tri_aff *f, float sx, float sy)
{
    int neg = 0, pos = 0;
    for (int k = 0; k < 3; k++) {
        float e = f->e0[k] + sx * f->e1[k] + sy * f->e2[k];
        float m = ACCEL_AFF_REL * (f->m0[k] + fabsf(sx) * f->m1[k] + fabsf(sy) * f->m2[k]) + ACCEL_AFF_ABS;
        neg |= e < -m, pos |= e > m;
    }
    return neg & pos;
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

static int accel_sphere_fallback(const accel_ray_prep *p, const float *s, float *t, float *u,
                                 float *v) __attribute__((noinline, cold));
static int accel_sphere_fallback(const accel_ray_prep *p, const float *s, float *t, float *u,
                                 float *v)
{
    accel_ray_d r;
    accel_prep_ray_d(p, &r);
    double tt = *t;
    if (!accel_sphere_hit_d(&r, s, &tt)) return 0;
    float tf = (float)tt;
    *t = tf > *t ? *t : tf;
    *u = *v = 0.0f;
    return 1;
}

/* Ray/sphere (centre xyz, radius w). Reports the nearest root in
 * [t_near, *t]; u = v = 0 for spheres. A grazing ray (discriminant within
 * its rounding error of zero) is decided in double, as by the reference. */
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
    float l2 = v3_dot(l, l), rr = r * r;
    float disc = rr - l2;
    float err = ACCEL_EDGE_FILTER * (rr + v3_dot(f, f));
    if (disc < -err) return 0;
    if (disc <= err) return accel_sphere_fallback(p, s, t, u, v);
    float q = b + copysignf(sqrtf(a * disc), b);
    float t0 = q / a, t1 = v3_dot(f, f) - rr;
    t1 = q != 0.0f ? t1 / q : t0;
    if (t0 > t1) { float tmp = t0; t0 = t1; t1 = tmp; }
    /* A root within rounding of t_near (a ray leaving the sphere's surface)
     * or of *t (a hit at the ray's end t_far, or at the current closest
     * distance) is decided in double, as by the reference. */
    float et = ACCEL_EDGE_FILTER * (sqrtf(v3_dot(f, f)) + r) / sqrtf(a);
    if (fabsf(t0 - p->t_near) <= et || fabsf(t1 - p->t_near) <= et || fabsf(t0 - *t) <= et ||
        fabsf(t1 - *t) <= et)
        return accel_sphere_fallback(p, s, t, u, v);
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

#ifdef __cplusplus
}
#endif

#endif
