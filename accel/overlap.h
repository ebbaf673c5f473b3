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
 * over axes of the distance to the nearer face, where outside) against r^2.
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
 * The same test for one triangle against many boxes of one size (the cells
 * of a grid): everything that does not depend on the box's position is
 * computed once. For each of the nine edge axes and the normal, the
 * triangle's projection (relative to v0) widened by the box's radius along
 * that axis gives an interval; a box centred at c is separated along the
 * axis when axis.(c - v0) falls outside it. The three box normals are NOT
 * tested: the caller must already know that the triangle's bounding box
 * touches the box (a grid gets that from the cell range of the bounds).
 * Zero axes (degenerate edges, a zero normal) are dropped: they separate
 * nothing. The slack covers double rounding for boxes whose centres lie
 * within the triangle's bounds widened by the box size.
 */
typedef struct {
    double v0[3];
    double axis[10][3];
    double lo[10], hi[10];
    int count;
} accel_tri_cells;

/* Adds axis L to c unless it is zero (p: vertices relative to v0). */
static inline void overlap_add_axis(accel_tri_cells *c, double lx, double ly, double lz,
                                    const double p[3][3], const double half[3], double reach)
{
    double norm1 = fabs(lx) + fabs(ly) + fabs(lz);
    if (norm1 == 0.0) return;
    double q1 = lx * p[1][0] + ly * p[1][1] + lz * p[1][2]; /* v0 projects to 0 */
    double q2 = lx * p[2][0] + ly * p[2][1] + lz * p[2][2];
    double r = half[0] * fabs(lx) + half[1] * fabs(ly) + half[2] * fabs(lz);
    double qmin = overlap_min3(0.0, q1, q2), qmax = overlap_max3(0.0, q1, q2);
    double slack = ACCEL_OVERLAP_SLACK * (fabs(qmin) + fabs(qmax) + r + norm1 * reach);
    int k = c->count++;
    c->axis[k][0] = lx, c->axis[k][1] = ly, c->axis[k][2] = lz;
    c->lo[k] = qmin - r - slack;
    c->hi[k] = qmax + r + slack;
}

static inline void accel_tri_cells_prep(accel_tri_cells *c, const float *tri, const double half[3])
{
    double p[3][3], e[3][3], reach = 0.0;
    for (int a = 0; a < 3; a++) {
        c->v0[a] = tri[a];
        p[0][a] = 0.0;
        p[1][a] = (double)tri[3 + a] - tri[a];
        p[2][a] = (double)tri[6 + a] - tri[a];
        double ext = overlap_max3(0.0, p[1][a], p[2][a]) - overlap_min3(0.0, p[1][a], p[2][a]);
        reach = fmax(reach, ext + 2.0 * half[a]);
    }
    for (int a = 0; a < 3; a++) {
        e[0][a] = p[1][a];
        e[1][a] = p[2][a] - p[1][a];
        e[2][a] = -p[2][a];
    }
    c->count = 0;
    /* unit(x) x e = (0, -ez, ey), unit(y) x e = (ez, 0, -ex), unit(z) x e = (-ey, ex, 0). */
    for (int k = 0; k < 3; k++) {
        overlap_add_axis(c, 0.0, -e[k][2], e[k][1], p, half, reach);
        overlap_add_axis(c, e[k][2], 0.0, -e[k][0], p, half, reach);
        overlap_add_axis(c, -e[k][1], e[k][0], 0.0, p, half, reach);
    }
    overlap_add_axis(c, e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                     e[0][0] * e[1][1] - e[0][1] * e[1][0], p, half, reach);
}

/* Does the prepared triangle touch the box centred at `centre` (of the
 * half-size given to the prep), given that their bounding boxes touch? */
static inline int accel_tri_cells_overlap(const accel_tri_cells *c, const double centre[3])
{
    const double d[3] = {centre[0] - c->v0[0], centre[1] - c->v0[1], centre[2] - c->v0[2]};
    for (int k = 0; k < c->count; k++) {
        double q = c->axis[k][0] * d[0] + c->axis[k][1] * d[1] + c->axis[k][2] * d[2];
        if (q < c->lo[k] || q > c->hi[k]) return 0;
    }
    return 1;
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

#endif
