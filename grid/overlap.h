/*
 * overlap.h - exact primitive/box overlap tests for grid builders.
 *
 * Triangle/box: the separating axis theorem as laid out by Akenine-Moller,
 * "Fast 3D Triangle-Box Overlap Testing", JGT 6(1), 2001: a triangle and a
 * box are disjoint exactly when one of 13 axes separates them: the three box
 * normals, the triangle normal, and the nine cross products of a box normal
 * with a triangle edge.
 *
 * Sphere/box: Arvo, "A Simple Method for Box-Sphere Intersection Testing",
 * Graphics Gems, 1990: the squared distance from the centre to the box (sum
 * over axes of the distance to the nearer face, where outside) against r^2;
 * for the sphere's surface also the distance to the farthest corner.
 *
 * Both tests are conservative, which is what a grid needs: a primitive that
 * touches the box, even on a single face, edge or corner point, counts as
 * overlapping, and so do degenerate or needle-thin triangles (a zero edge or
 * a zero normal gives an axis that separates nothing). All arithmetic is in
 * double on float input: float differences and their pairwise products are
 * then nearly exact, and a relative slack of ACCEL_OVERLAP_SLACK on every
 * comparison absorbs what rounding remains. A primitive within that slack of
 * the box may be reported as overlapping; one that touches is never missed.
 * Callers that also need robustness against the rounding of their *own*
 * arithmetic (a DDA) pass a box enlarged by their own margin.
 */
#ifndef ACCEL_OVERLAP_H
#define ACCEL_OVERLAP_H

#include <math.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Relative slack on every separation test (far above double rounding, far
 * below any distance a float scene can express). */
#define ACCEL_OVERLAP_SLACK 1e-12

/* A triangle prepared once for testing against many boxes. */
typedef struct {
    double v[3][3]; /* vertices */
    double e[3][3]; /* edges v1-v0, v2-v1, v0-v2 */
    double n[3];    /* normal e0 x e1 (not normalized; may be zero) */
} accel_tri_overlap;

static inline void accel_tri_overlap_prep(accel_tri_overlap *t, const float *tri)
{
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) t->v[k][a] = tri[3 * k + a];
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) t->e[k][a] = t->v[(k + 1) % 3][a] - t->v[k][a];
    const double *e0 = t->e[0], *e1 = t->e[1];
    t->n[0] = e0[1] * e1[2] - e0[2] * e1[1];
    t->n[1] = e0[2] * e1[0] - e0[0] * e1[2];
    t->n[2] = e0[0] * e1[1] - e0[1] * e1[0];
}

/* Is the interval [lo, hi] (projected triangle) disjoint from [-r, r]
 * (projected box), by more than the slack? Touching is not disjoint. */
static inline int overlap_separated(double lo, double hi, double r)
{
    double slack = ACCEL_OVERLAP_SLACK * (fabs(lo) + fabs(hi) + r);
    return lo > r + slack || hi < -r - slack;
}

static inline double overlap_min3(double a, double b, double c)
{
    double m = a < b ? a : b;
    return m < c ? m : c;
}

static inline double overlap_max3(double a, double b, double c)
{
    double m = a > b ? a : b;
    return m > c ? m : c;
}

/*
 * Does the prepared triangle touch the box centre +- half (half >= 0)?
 * Returns 1 on overlap or contact, 0 when a separating axis exists.
 */
static inline int accel_tri_overlap_box(const accel_tri_overlap *t, const double centre[3],
                                        const double half[3])
{
    double p[3][3]; /* vertices relative to the box centre */
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) p[k][a] = t->v[k][a] - centre[a];

    /* The three box normals: the triangle's bounds against the box. */
    for (int a = 0; a < 3; a++)
        if (overlap_separated(overlap_min3(p[0][a], p[1][a], p[2][a]),
                              overlap_max3(p[0][a], p[1][a], p[2][a]), half[a]))
            return 0;

    /* The nine axes unit(a) x edge. For unit(a) x e the projection of a
     * point q is q[a2]*e[a1] - q[a1]*e[a2] (a1, a2 the other two axes, in
     * cyclic order), and the box's radius along it is
     * half[a1]*|e[a2]| + half[a2]*|e[a1]|. */
    for (int k = 0; k < 3; k++) {
        const double *e = t->e[k];
        for (int a = 0; a < 3; a++) {
            int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
            double q0 = p[0][a2] * e[a1] - p[0][a1] * e[a2];
            double q1 = p[1][a2] * e[a1] - p[1][a1] * e[a2];
            double q2 = p[2][a2] * e[a1] - p[2][a1] * e[a2];
            double r = half[a1] * fabs(e[a2]) + half[a2] * fabs(e[a1]);
            if (overlap_separated(overlap_min3(q0, q1, q2), overlap_max3(q0, q1, q2), r))
                return 0;
        }
    }

    /* The triangle's plane against the box: the plane n.x = n.v0 is
     * separated when its distance along n exceeds the box's radius along n. */
    double d = t->n[0] * p[0][0] + t->n[1] * p[0][1] + t->n[2] * p[0][2];
    double r = half[0] * fabs(t->n[0]) + half[1] * fabs(t->n[1]) + half[2] * fabs(t->n[2]);
    if (overlap_separated(d, d, r)) return 0;
    return 1;
}

/* One-shot form: triangle as 9 floats, box as lo/hi corners (double). */
static inline int accel_overlap_tri_box(const float *tri, const double lo[3], const double hi[3])
{
    accel_tri_overlap t;
    accel_tri_overlap_prep(&t, tri);
    double c[3], h[3];
    for (int a = 0; a < 3; a++) {
        c[a] = 0.5 * (lo[a] + hi[a]);
        h[a] = 0.5 * (hi[a] - lo[a]);
    }
    return accel_tri_overlap_box(&t, c, h);
}

/*
 * Clipping a convex polygon to an axis-aligned slab (Sutherland & Hodgman,
 * "Reentrant Polygon Clipping", CACM 1974), for grid builders that walk the
 * rows of cells a triangle crosses instead of testing every cell of its
 * bounding box. Inclusive: a polygon that only touches the slab keeps the
 * touching point, so the result is empty only when they are disjoint.
 * Each half-space adds at most one vertex: a triangle clipped to two slabs
 * has at most 7. Crossing points are interpolated in double and then set
 * exactly on the plane; callers widen the slab by their own slack to stay
 * conservative against that rounding.
 */
static inline int overlap_clip_half(const double (*in)[3], int n, int axis, double c, double sgn,
                                    double (*out)[3])
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        const double *a = in[i], *b = in[i + 1 == n ? 0 : i + 1];
        double da = sgn * (a[axis] - c), db = sgn * (b[axis] - c);
        if (da >= 0.0) {
            out[m][0] = a[0], out[m][1] = a[1], out[m][2] = a[2];
            m++;
        }
        if ((da >= 0.0) != (db >= 0.0)) {
            double t = da / (da - db);
            for (int k = 0; k < 3; k++) out[m][k] = a[k] + t * (b[k] - a[k]);
            out[m][axis] = c;
            m++;
        }
    }
    return m;
}

/* Clips polygon in[0..n-1] (n <= 5) to lo <= p[axis] <= hi; out needs n + 2
 * entries. Returns the vertex count, 0 when the polygon misses the slab. */
static inline int accel_clip_slab(const double (*in)[3], int n, int axis, double lo, double hi,
                                  double (*out)[3])
{
    double tmp[8][3];
    int m = overlap_clip_half(in, n, axis, lo, 1.0, tmp);
    return m ? overlap_clip_half((const double(*)[3])tmp, m, axis, hi, -1.0, out) : 0;
}

/*
 * Does the sphere (centre xyz, radius w: 4 floats) touch the box [lo, hi]?
 * Arvo 1990: sum the squared distances to the box along each axis where the
 * centre lies outside the slab; compare with r^2 (with the relative slack).
 */
static inline int accel_overlap_sphere_box(const float *sphere, const double lo[3],
                                           const double hi[3])
{
    double d2 = 0.0, scale = 0.0;
    for (int a = 0; a < 3; a++) {
        double c = sphere[a];
        double d = c < lo[a] ? lo[a] - c : (c > hi[a] ? c - hi[a] : 0.0);
        d2 += d * d;
        scale += fabs(c) + fabs(lo[a]) + fabs(hi[a]);
    }
    double r = sphere[3];
    double slack = ACCEL_OVERLAP_SLACK * (scale + r);
    return d2 <= (r + slack) * (r + slack);
}

/*
 * Does the sphere's surface (not the ball) touch the box? As above, and the
 * box must not lie entirely inside the ball: its farthest corner from the
 * centre must be at least r away. A ray can only hit a sphere where its
 * surface is, so a cell deep inside a large ball need not reference it.
 */
static inline int accel_overlap_sphere_surface_box(const float *sphere, const double lo[3],
                                                   const double hi[3])
{
    if (!accel_overlap_sphere_box(sphere, lo, hi)) return 0;
    double far2 = 0.0, scale = 0.0;
    for (int a = 0; a < 3; a++) {
        double c = sphere[a];
        double dl = fabs(c - lo[a]), dh = fabs(c - hi[a]);
        double d = dl > dh ? dl : dh;
        far2 += d * d;
        scale += fabs(c) + fabs(lo[a]) + fabs(hi[a]);
    }
    double r = sphere[3];
    double slack = ACCEL_OVERLAP_SLACK * (scale + r);
    double inner = r - slack;
    return inner <= 0.0 || far2 >= inner * inner;
}

#ifdef __cplusplus
}
#endif

#endif
