/*
 * compare.c - FORMATS.md's rule for comparing two tracers' answers ray by
 * ray (rays.h, "comparison"): the same triangle at the same t, u, v, or a
 * true tie verified on the scene.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>

#include "core/prim.h"
#include "rays/rays.h"

#define HITS_UV_TOL 1e-3

/* tol(t) of FORMATS.md around t1. Equal distances are the same distance,
 * +infinity included: a hit beyond FLT_MAX (a ray from 1e38 away) rounds
 * t to +infinity in every tracer, where |t1 - t2| would be NaN. */
static int same_t(double t1, double t2)
{
    if (t1 == t2) return 1;
    return fabs(t1 - t2) <= 1e-4 * fmax(1.0, fabs(t1));
}

/* The exact t of a hit reported as the float tf: +infinity stands for any
 * t that rounds to it. */
static int t_matches(double exact, float tf)
{
    if (isinf(tf)) return tf > 0 && exact >= (double)FLT_MAX;
    return same_t(tf, exact);
}

/*
 * The watertight test (core/prim.h) in double, with each edge function
 * allowed to be negative by a float tracer's rounding: 64u times the terms
 * of the tight bound of ACCEL_EDGE_FILTER (u = 2^-24), four times the float
 * kernels' own filter, for tracers whose float arithmetic is not ours
 * (Moller-Trumbore, Embree's). The slack scales with the sheared
 * coordinates, which are about the size of the triangle near the ray, so a
 * point outside the triangle by more than some 1e-6 of the triangle's
 * distance from the origin is a miss, as it should be.
 */
static int tri_hit_d(const accel_ray_prep *p, const float *tri, double *t, double *u, double *v)
{
    accel_ray_d r;
    accel_prep_ray_d(p, &r);
    double a[3], b[3], c[3];
    for (int i = 0; i < 3; i++) {
        a[i] = (double)tri[i] - r.o[i];
        b[i] = (double)tri[3 + i] - r.o[i];
        c[i] = (double)tri[6 + i] - r.o[i];
    }
    double ax = a[r.kx] - r.sx * a[r.kz], ay = a[r.ky] - r.sy * a[r.kz];
    double bx = b[r.kx] - r.sx * b[r.kz], by = b[r.ky] - r.sy * b[r.kz];
    double cx = c[r.kx] - r.sx * c[r.kz], cy = c[r.ky] - r.sy * c[r.kz];
    double U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
    double sxa = fabs(r.sx), sya = fabs(r.sy);
    double max_ = fabs(a[r.kx]) + sxa * fabs(a[r.kz]), may_ = fabs(a[r.ky]) + sya * fabs(a[r.kz]);
    double mbx_ = fabs(b[r.kx]) + sxa * fabs(b[r.kz]), mby_ = fabs(b[r.ky]) + sya * fabs(b[r.kz]);
    double mcx_ = fabs(c[r.kx]) + sxa * fabs(c[r.kz]), mcy_ = fabs(c[r.ky]) + sya * fabs(c[r.kz]);
    const double k = 64.0 * 0x1p-24, k2 = 128.0 * 0x1p-48, tiny = 0x1p-126;
    double eu = k * (fabs(cx) * mby_ + fabs(by) * mcx_ + fabs(cy) * mbx_ + fabs(bx) * mcy_) +
                k2 * (mcx_ * mby_ + mcy_ * mbx_) + tiny;
    double ev = k * (fabs(ax) * mcy_ + fabs(cy) * max_ + fabs(ay) * mcx_ + fabs(cx) * may_) +
                k2 * (max_ * mcy_ + may_ * mcx_) + tiny;
    double ew = k * (fabs(bx) * may_ + fabs(ay) * mbx_ + fabs(by) * max_ + fabs(ax) * mby_) +
                k2 * (mbx_ * may_ + mby_ * max_) + tiny;
    /* Inside (up to the slack) on one side: all >= -e, or all <= +e. */
    int pos = U >= -eu && V >= -ev && W >= -ew;
    int neg = U <= eu && V <= ev && W <= ew;
    if (!pos && !neg) return 0;
    double det = U + V + W;
    /* A ray in the triangle's plane (det within its slack of zero) has no
     * single hit point: not a hit. */
    if (!(fabs(det) > eu + ev + ew)) return 0;
    double num = U * a[r.kz] + V * b[r.kz] + W * c[r.kz];
    *t = num * r.sz / det;
    *u = V / det;
    *v = W / det;
    return 1;
}

/* The reported answer h against the exact t, u, v of its primitive. */
static int answer_matches(const accel_ray *ray, const accel_hit *h, double t, double u, double v)
{
    if (!t_matches(t, h->t)) return 0;
    if (!(h->t >= ray->t_near || same_t(ray->t_near, h->t))) return 0;
    if (!(h->t <= ray->t_far || same_t(ray->t_far, h->t))) return 0;
    return fabs(u - h->u) <= HITS_UV_TOL && fabs(v - h->v) <= HITS_UV_TOL;
}

int hits_verify(const accel_scene *s, const accel_ray *ray, const accel_hit *h)
{
    if (!s || !ray || h->prim == ACCEL_MISS || h->prim >= s->prim_count) return 0;
    accel_ray_prep p;
    if (!accel_prep_ray(ray, &p)) return 0;
    double t, u = 0.0, v = 0.0;
    if (h->prim >= s->tri_count) {
        accel_ray_d r;
        accel_prep_ray_d(&p, &r);
        t = INFINITY;
        if (!accel_sphere_hit_d(&r, s->spheres + 4 * (size_t)(h->prim - s->tri_count), &t))
            return 0;
    } else {
        const float *tri = s->tris + 9 * (size_t)h->prim;
        if (accel_tri_is_degenerate(tri)) return 0;
        /* The oracle's own test first (a ray starting in the triangle's
         * plane, a hit at t = 0, is decided there as the oracle decides
         * it); then the same test with a float tracer's slack. */
        accel_ray_d r;
        accel_prep_ray_d(&p, &r);
        double te = INFINITY, ue, ve;
        if (accel_tri_watertight_d(&r, tri, &te, &ue, &ve) && answer_matches(ray, h, te, ue, ve))
            return 1;
        if (!tri_hit_d(&p, tri, &t, &u, &v)) return 0;
    }
    return answer_matches(ray, h, t, u, v);
}

hits_match hits_match_ray(const accel_scene *scene, const accel_ray *ray, const accel_hit *a,
                          const accel_hit *b)
{
    int ha = a->prim != ACCEL_MISS, hb = b->prim != ACCEL_MISS;
    if (!ha || !hb) return ha == hb ? HITS_AGREE : (ha ? HITS_HOLE : HITS_FALSE_HIT);
    if (!same_t(a->t, b->t)) return HITS_DISAGREE;
    if (a->prim == b->prim)
        return fabsf(a->u - b->u) <= HITS_UV_TOL && fabsf(a->v - b->v) <= HITS_UV_TOL
                   ? HITS_AGREE
                   : HITS_DISAGREE;
    if (!scene || !ray) return HITS_TIE_UNVERIFIED;
    return hits_verify(scene, ray, a) && hits_verify(scene, ray, b) ? HITS_TIE : HITS_DISAGREE;
}

int hits_agree(const accel_scene *scene, const accel_ray *ray, const accel_hit *a,
               const accel_hit *b)
{
    hits_match m = hits_match_ray(scene, ray, a, b);
    return m == HITS_AGREE || m == HITS_TIE;
}

hits_diff hits_compare(const accel_scene *scene, const accel_ray *rays, const accel_hit *a,
                       const accel_hit *b, size_t n)
{
    hits_diff d = {0};
    d.rays = n;
    d.first_bad = SIZE_MAX;
    for (size_t i = 0; i < n; i++) {
        hits_match m = hits_match_ray(rays ? scene : NULL, rays ? &rays[i] : NULL, &a[i], &b[i]);
        if (m == HITS_AGREE || m == HITS_TIE) {
            d.agree++;
            d.ties += m == HITS_TIE;
            continue;
        }
        if (d.first_bad == SIZE_MAX) d.first_bad = i;
        d.unverified += m == HITS_TIE_UNVERIFIED;
        d.holes += m == HITS_HOLE;
        d.false_hits += m == HITS_FALSE_HIT;
        d.disagreements += m == HITS_DISAGREE;
    }
    return d;
}

hits_anyhit_diff hits_compare_anyhit(const accel_scene *scene, const accel_ray *rays,
                                     const accel_hit *a, const accel_hit *b, size_t n)
{
    hits_anyhit_diff d = {0};
    d.rays = n;
    d.first_bad = SIZE_MAX;
    for (size_t i = 0; i < n; i++) {
        int ha = a[i].prim != ACCEL_MISS, hb = b[i].prim != ACCEL_MISS;
        int bad = ha != hb;
        d.leaks += ha && !hb;
        d.false_occlusions += !ha && hb;
        if (!bad && hb && scene && rays && !hits_verify(scene, &rays[i], &b[i]))
            d.false_hits++, bad = 1;
        d.agree += !bad;
        if (bad && d.first_bad == SIZE_MAX) d.first_bad = i;
    }
    return d;
}
