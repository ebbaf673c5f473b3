/*
 * test_oracle_huge.c - the reference's t on huge, nearly flat triangles
 * (vertices at 1e30 and 1e20 along two axes, a slope of 0.5 / 2e30 along
 * the third) is right. The watertight t sums the vertices' offsets along the
 * ray's dominant axis weighted by the edge functions; with offsets of
 * +-1e30 along that axis the sum cancels to an error of about eps 1e30, so
 * before core/prim.h bounded that error and fell back to the plane form,
 * the reference reported hits behind the ray (ray o=(-0.273, 0.291, -2.176)
 * d=(3.07, -1.78, 2.47): t 0.044 for a plane hit at t -0.435).
 *
 * Checked against an independent closest hit computed in long double
 * (64-bit significand on x86-64) from the plane, n.(v0 - o) / n.d, and 2D
 * edge functions of the hit point, with its own error bound: rays whose
 * answer that bound leaves open (through an edge, at t_near) are skipped,
 * and the rest must agree on hit or miss, the primitive and t within 1e-6.
 * The culled oracle must still equal the brute-force loop bitwise, and bvh
 * and grid must agree with the reference.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

/* ---- the independent closest hit, in long double ---------------------------- */

enum { LD_MISS, LD_HIT, LD_UNSURE };

/* One triangle: LD_HIT with *t in [t_near, t_far], LD_MISS, or LD_UNSURE
 * when the long double rounding could change the answer (*t: the plane's
 * t, -inf for a ray along the plane). */
static int ld_tri(const float *v, const accel_ray *ray, long double *t_out)
{
    const long double ld_eps = 0x1p-63L;
    long double o[3] = {ray->ox, ray->oy, ray->oz}, d[3] = {ray->dx, ray->dy, ray->dz};
    long double e1[3], e2[3], ao[3], n[3];
    for (int i = 0; i < 3; i++) {
        e1[i] = (long double)v[3 + i] - v[i];
        e2[i] = (long double)v[6 + i] - v[i];
        ao[i] = (long double)v[i] - o[i];
    }
    long double num = 0, den = 0, bn = 0, bd = 0, nmax = 0;
    int k = 0;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, l = (i + 2) % 3;
        n[i] = e1[j] * e2[l] - e1[l] * e2[j];
        long double nb = fabsl(e1[j] * e2[l]) + fabsl(e1[l] * e2[j]);
        num += n[i] * ao[i];
        den += n[i] * d[i];
        bn += nb * fabsl(ao[i]);
        bd += nb * fabsl(d[i]);
        if (fabsl(n[i]) > nmax) nmax = fabsl(n[i]), k = i;
    }
    if (fabsl(den) <= 64 * ld_eps * bd) return LD_UNSURE; /* along the plane */
    long double t = num / den;
    *t_out = t; /* where an unsure answer lies along the ray */
    long double et = 64 * ld_eps * (bn + fabsl(t) * bd) / fabsl(den) + 4 * ld_eps * fabsl(t);
    if (t + et < ray->t_near || t - et > ray->t_far) return LD_MISS;
    /* The hit point, projected along the normal's largest axis. */
    int x = (k + 1) % 3, y = (k + 2) % 3;
    long double px = o[x] + t * d[x], py = o[y] + t * d[y];
    long double epx = 4 * ld_eps * fabsl(px) + et * fabsl(d[x]);
    long double epy = 4 * ld_eps * fabsl(py) + et * fabsl(d[y]);
    int neg = 0, pos = 0, unsure = 0;
    for (int i = 0; i < 3; i++) {
        const float *p = v + 3 * i, *q = v + 3 * ((i + 1) % 3);
        /* (p - hit) x edge: linear in the hit point, so its error is the
         * point's error times the edge, not times the distance. */
        long double ax = p[x] - px, ay = p[y] - py;
        long double ex = (long double)q[x] - p[x], ey = (long double)q[y] - p[y];
        long double w = ax * ey - ay * ex;
        long double ew = 8 * ld_eps * (fabsl(ax * ey) + fabsl(ay * ex)) + epx * fabsl(ey) +
                         epy * fabsl(ex);
        if (w > ew) pos = 1;
        else if (w < -ew) neg = 1;
        else unsure = 1;
    }
    if (pos && neg) return LD_MISS;
    if (unsure) return LD_UNSURE;
    if (t - et < ray->t_near || t + et > ray->t_far) return LD_UNSURE;
    *t_out = t;
    return LD_HIT;
}

/* The closest hit of all live triangles: 1 and *prim, *t when certain (no
 * unsure triangle before it; *prim = MISS for a certain miss), 2 when
 * another triangle is hit within 1e-6 of *t (t certain, the primitive
 * not), 0 when the ray is skipped. */
static int ld_closest(const accel_scene *s, const accel_ray *ray, uint32_t *prim, long double *t)
{
    long double best = INFINITY, unsure_min = INFINITY, second = INFINITY;
    uint32_t bp = ACCEL_MISS;
    for (uint32_t i = 0; i < s->live_count; i++) {
        long double ti = -INFINITY;
        int r = ld_tri(s->tris + 9 * (size_t)s->live[i], ray, &ti);
        if (r == LD_UNSURE) {
            unsure_min = fminl(unsure_min, ti);
        } else if (r == LD_HIT) {
            if (ti < best) second = best, best = ti, bp = s->live[i];
            else second = fminl(second, ti);
        }
    }
    if (bp == ACCEL_MISS ? unsure_min < INFINITY : unsure_min <= best * (1 + 1e-6L)) return 0;
    *prim = bp;
    *t = best;
    return bp != ACCEL_MISS && second <= best * (1 + 1e-6L) ? 2 : 1;
}

/* ---- the scene and the rays ------------------------------------------------------ */

/* Huge triangles with small slopes, across z (below and above), across x,
 * at 1e30 and 1e20, around small clutter near the origin. */
static const float huge_tris[][9] = {
    {-1e30f, -1e30f, -3.0f, 1e30f, -1e30f, -3.0f, 0, 1e30f, -3.5f},
    {-1e30f, 1e30f, 3.0f, 1e30f, 1e30f, 3.5f, 0, -1e30f, 3.0f},
    {2.0f, -1e30f, -1e30f, 2.5f, 1e30f, -1e30f, 2.0f, 0, 1e30f},
    {-1e20f, -1e20f, -5.0f, 1e20f, -1e20f, -5.25f, 0, 1e20f, -5.0f},
    {-4.0f, 1e20f, -1e20f, -4.0f, -1e20f, -1e20f, -4.5f, 0, 1e20f},
};
enum { HUGE_COUNT = sizeof huge_tris / sizeof huge_tris[0] };

static int make_scene(accel_scene *s)
{
    scene_builder b = {0};
    for (int i = 0; i < HUGE_COUNT; i++) {
        const float *v = huge_tris[i];
        test_add_tri(&b, v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]), v3(v[6], v[7], v[8]));
    }
    box3 clutter = {{-1.5f, -1.5f, -1.5f}, {1.5f, 1.5f, 1.5f}};
    for (int i = 0; i < 120; i++) {
        vec3 p = test_rand_point(clutter);
        vec3 q = v3_add(p, v3(test_rand_in(-0.3f, 0.3f), test_rand_in(-0.3f, 0.3f), 0.1f));
        vec3 r = v3_add(p, v3(test_rand_in(-0.3f, 0.3f), 0.2f, test_rand_in(-0.3f, 0.3f)));
        test_add_tri(&b, p, q, r);
    }
    return test_finish(&b, "oracle_huge", s);
}

/* A point of huge triangle h: barycentric weights at least 0.05 each, or
 * (near = 1) the point of its plane over a small (a, b) of the two wide axes. */
static vec3 on_plane(int h, int near)
{
    const float *v = huge_tris[h];
    long double p[3];
    if (!near) {
        long double w1 = 0.05L + 0.45L * test_rand(), w2 = 0.05L + 0.45L * test_rand();
        for (int i = 0; i < 3; i++) p[i] = v[i] + w1 * (v[3 + i] - v[i]) + w2 * (v[6 + i] - v[i]);
        return v3((float)p[0], (float)p[1], (float)p[2]);
    }
    long double e1[3], e2[3], n[3];
    for (int i = 0; i < 3; i++) e1[i] = (long double)v[3 + i] - v[i], e2[i] = (long double)v[6 + i] - v[i];
    int k = 0;
    for (int i = 0; i < 3; i++) {
        n[i] = e1[(i + 1) % 3] * e2[(i + 2) % 3] - e1[(i + 2) % 3] * e2[(i + 1) % 3];
        if (fabsl(n[i]) > fabsl(n[k])) k = i;
    }
    int x = (k + 1) % 3, y = (k + 2) % 3;
    p[x] = test_rand_in(-10.0f, 10.0f);
    p[y] = test_rand_in(-10.0f, 10.0f);
    p[k] = v[k] - (n[x] * (p[x] - v[x]) + n[y] * (p[y] - v[y])) / n[k];
    return v3((float)p[0], (float)p[1], (float)p[2]);
}

/* Rays aimed at each huge triangle from both sides of its plane, mostly
 * along it (the dominant axis is one of its wide axes), and the same rays
 * reversed (pointing away: they must miss it). */
static void aimed_rays(test_rays *r, int per_tri)
{
    for (int h = 0; h < HUGE_COUNT; h++) {
        const float *v = huge_tris[h];
        int k = fabsf(v[0]) < 1e10f ? 0 : 2; /* the thin axis */
        for (int i = 0; i < per_tri; i++) {
            int near = i % 2;
            vec3 target = on_plane(h, near);
            float scale = near ? 1.0f : 1e-2f * fabsf(v[1]);
            float dv[3];
            for (int a = 0; a < 3; a++) dv[a] = test_rand_in(-10.0f, 10.0f) * scale;
            float side = (i / 2) % 2 ? 1.0f : -1.0f;
            dv[k] = side * test_rand_in(0.01f, 1.0f) * (near ? 1.0f : 1e-3f * scale);
            vec3 d = v3(dv[0], dv[1], dv[2]);
            vec3 o = v3_sub(target, d);
            test_rays_push(r, test_ray(o, d, 0.0f, INFINITY));
            test_rays_push(r, test_ray(o, v3_scale(d, -1.0f), 0.0f, INFINITY));
        }
    }
}

static void all_rays(const accel_scene *s, test_rays *r)
{
    /* The ray of the report (random, from tests/test_sbvh.c): its line
     * meets triangle 0's plane at t -0.435 (the old t was +0.044) and
     * triangle 2 at t 0.78. */
    test_rays_push(r, test_ray(v3(-0.27301693f, 0.291233063f, -2.17646742f),
                               v3(3.07129002f, -1.77735853f, 2.46713471f), 0.0f, INFINITY));
    test_rays_random(r, s->bounds, 800);
    test_rays_random(r, (box3){{-2, -2, -2}, {3, 3, 3}}, 800);
    aimed_rays(r, 160);
}

/* ---- the tests ------------------------------------------------------------------ */

TEST(oracle_huge_triangles_exact_t)
{
    accel_scene s;
    if (!make_scene(&s)) return;
    test_rays r = {0};
    all_rays(&s, &r);
    accel_hit *ref = malloc(r.count * sizeof *ref);
    CHECK(ref != NULL);
    if (ref) {
        accel_reference_trace_brute(&s, r.rays, ref, r.count, 2);
        size_t checked = 0, huge_hits = 0, bad = 0, first = r.count;
        for (size_t i = 0; i < r.count; i++) {
            uint32_t prim;
            long double t;
            int c = ld_closest(&s, &r.rays[i], &prim, &t);
            if (!c) continue;
            checked++;
            int ok = (c == 2 ? ref[i].prim != ACCEL_MISS : ref[i].prim == prim) &&
                     (prim == ACCEL_MISS || fabsl(ref[i].t - t) <= 1e-6L * fabsl(t) + 1e-30L);
            if (prim < HUGE_COUNT) huge_hits++;
            if (!ok && bad++ == 0) first = i;
        }
        if (bad) {
            const accel_ray *q = &r.rays[first];
            uint32_t prim = ACCEL_MISS;
            long double t = 0;
            ld_closest(&s, q, &prim, &t);
            test_fail(__FILE__, __LINE__,
                      "%zu of %zu checked rays disagree with the long double plane test; first, "
                      "ray %zu o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g) t=[%g, %g]: reference "
                      "prim %u t %.9g, long double prim %u t %.9Lg",
                      bad, checked, first, q->ox, q->oy, q->oz, q->dx, q->dy, q->dz, q->t_near,
                      q->t_far, ref[first].prim, ref[first].t, prim, t);
        }
        test_note("%zu of %zu rays checked, %zu hit a huge triangle", checked, r.count, huge_hits);
        CHECKF(ref[0].prim != 0 && ref[0].t > 0.5f, "the reported ray: prim %u t %g", ref[0].prim,
               ref[0].t); /* it hits triangle 2 (x = 2.1) at t 0.78 */
        /* Not vacuous: most rays are decided, many of them hit a huge triangle. */
        CHECKF(checked >= r.count * 9 / 10 && huge_hits >= 800, "%zu of %zu rays checked, %zu huge hits",
               checked, r.count, huge_hits);
    }
    free(ref);
    test_rays_free(&r);
    scene_free(&s);
}

TEST(oracle_huge_triangles_culled_and_kinds)
{
    accel_scene s;
    if (!make_scene(&s)) return;
    test_rays r = {0};
    all_rays(&s, &r);
    accel_hit *ref = malloc(r.count * sizeof *ref), *h = malloc(r.count * sizeof *h);
    accel_oracle *o = NULL;
    accel_error err = {0};
    CHECKF(accel_oracle_build(&s, &o, &err) == 0, "oracle build: %s", err.msg);
    if (ref && h && o) {
        accel_reference_trace_brute(&s, r.rays, ref, r.count, 2);
        accel_oracle_trace(o, r.rays, h, r.count, 2, NULL);
        size_t differ = 0;
        for (size_t i = 0; i < r.count; i++) differ += memcmp(&ref[i], &h[i], sizeof *h) != 0;
        CHECKF(differ == 0, "culled oracle: %zu of %zu rays differ from brute force", differ,
               r.count);
    }
    accel_oracle_free(o);
    static const char *const specs[] = {"bvh", "bvh:build=sbvh", "grid"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++)
        test_check_spec(&s, specs[i], r.rays, r.count, NULL, NULL, NULL);
    free(ref);
    free(h);
    test_rays_free(&r);
    scene_free(&s);
}
