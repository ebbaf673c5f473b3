/*
 * build_sbvh_chop.c - chopping a reference at a split plane for the split
 * BVH (build_sbvh.c; Stich, Friedrich and Dietrich, "Spatial Splits in
 * Bounding Volume Hierarchies", HPG 2009, section 4.3).
 *
 * A chopped box must contain the exact part of its primitive on its side
 * of the plane, or a ray could miss the part no leaf box holds. The part
 * of a triangle is spanned by its vertices on that side and the points
 * where its edges cross the plane; those points are computed in double
 * (every float vertex is exact there), padded by a bound on the double
 * rounding, and rounded outward to float: the min down, the max up. The
 * plane's own coordinate is exact in double and rounds outward like the
 * rest, so the two sides' boxes may overlap by an ulp but never leave a
 * gap. tests/test_sbvh.c checks the boxes against the exact points in long
 * double, and that rounding to nearest, or leaving out the pad, fails.
 */
#include <float.h>
#include <math.h>

#include "split_common.h"

static inline box3 box_clip(box3 a, box3 b)
{
    a.min = v3_max(a.min, b.min);
    a.max = v3_min(a.max, b.max);
    return a;
}

typedef struct {
    double lo[3], hi[3];
} dbox;

static inline void dbox_clear(dbox *b)
{
    for (int k = 0; k < 3; k++) b->lo[k] = INFINITY, b->hi[k] = -INFINITY;
}

static inline void dbox_grow(dbox *b, const double *p, const double *pad)
{
    for (int k = 0; k < 3; k++) {
        if (p[k] - pad[k] < b->lo[k]) b->lo[k] = p[k] - pad[k];
        if (p[k] + pad[k] > b->hi[k]) b->hi[k] = p[k] + pad[k];
    }
}

/* To float: outward (min down, max up) or, for the test of this very
 * property, to nearest. */
static box3 dbox_to_box3(const dbox *b, int outward)
{
    box3 r;
    if (outward) {
        r.min = v3(accel_float_down(b->lo[0]), accel_float_down(b->lo[1]), accel_float_down(b->lo[2]));
        r.max = v3(accel_float_up(b->hi[0]), accel_float_up(b->hi[1]), accel_float_up(b->hi[2]));
    } else {
        r.min = v3((float)b->lo[0], (float)b->lo[1], (float)b->lo[2]);
        r.max = v3((float)b->hi[0], (float)b->hi[1], (float)b->hi[2]);
    }
    return r;
}

void bvh_sbvh_chop(const float *tri, box3 box, int axis, double plane, int outward, box3 *left,
                   box3 *right)
{
    dbox l, r;
    dbox_clear(&l);
    dbox_clear(&r);
    const double zero[3] = {0.0, 0.0, 0.0};
    for (int e = 0; e < 3; e++) {
        double a[3], b[3];
        for (int k = 0; k < 3; k++) a[k] = tri[3 * e + k], b[k] = tri[3 * ((e + 1) % 3) + k];
        if (a[axis] <= plane) dbox_grow(&l, a, zero);
        if (a[axis] >= plane) dbox_grow(&r, a, zero);
        if ((a[axis] < plane && b[axis] > plane) || (a[axis] > plane && b[axis] < plane)) {
            /* The edge crosses the plane at p = a + s (b - a). In double each
             * coordinate is off by a few units in the last place of
             * |a| + |b| (the difference, the quotient, the product and the
             * sum each round once); 8 units cover it. The plane coordinate
             * itself is exact. */
            double s = (plane - a[axis]) / (b[axis] - a[axis]), p[3], pad[3];
            for (int k = 0; k < 3; k++) {
                p[k] = k == axis ? plane : a[k] + s * (b[k] - a[k]);
                pad[k] = k == axis || !outward ? 0.0 : 8.0 * DBL_EPSILON * (fabs(a[k]) + fabs(b[k]));
            }
            dbox_grow(&l, p, pad);
            dbox_grow(&r, p, pad);
        }
    }
    *left = box_clip(dbox_to_box3(&l, outward), box);
    *right = box_clip(dbox_to_box3(&r, outward), box);
}

void bvh_sbvh_chop_box(box3 box, int axis, double plane, box3 *left, box3 *right)
{
    dbox l, r;
    for (int k = 0; k < 3; k++) {
        l.lo[k] = r.lo[k] = v3_get(box.min, k);
        l.hi[k] = r.hi[k] = v3_get(box.max, k);
    }
    l.hi[axis] = plane;
    r.lo[axis] = plane;
    *left = box_clip(dbox_to_box3(&l, 1), box);
    *right = box_clip(dbox_to_box3(&r, 1), box);
}
