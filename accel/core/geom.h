/*
 * geom.h - small vector and box math shared by every backend.
 *
 * Everything here is static inline so that each backend's kernels see the
 * same arithmetic: differences between accelerators then come from traversal
 * alone, never from a different box test.
 *
 * The slab test follows Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013:
 * the reciprocal direction is computed with IEEE division (1/±0 = ±inf), the
 * near and far planes are picked by the sign of the direction, and the far
 * distance is enlarged by 2*gamma(3) so that rounding in the slab products
 * can never make a box the ray touches look missed.
 */
#ifndef ACCEL_GEOM_H
#define ACCEL_GEOM_H

#include <float.h>
#include <math.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct { float x, y, z; } vec3;
typedef struct { vec3 min, max; } box3;

static inline vec3 v3(float x, float y, float z) { vec3 r = {x, y, z}; return r; }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v3_scale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline float v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v3_len(vec3 a) { return sqrtf(v3_dot(a, a)); }
static inline vec3 v3_norm(vec3 a)
{
    float l = v3_len(a);
    return l > 0.0f ? v3_scale(a, 1.0f / l) : a;
}
/* min/max as compare-and-select: compiles to minss/maxss, and a NaN in the
 * second operand leaves the first (the slab test relies on that). */
static inline float minf(float acc, float x) { return x < acc ? x : acc; }
static inline float maxf(float acc, float x) { return x > acc ? x : acc; }
static inline vec3 v3_min(vec3 a, vec3 b) { return v3(minf(a.x, b.x), minf(a.y, b.y), minf(a.z, b.z)); }
static inline vec3 v3_max(vec3 a, vec3 b) { return v3(maxf(a.x, b.x), maxf(a.y, b.y), maxf(a.z, b.z)); }
static inline float v3_get(vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }
static inline vec3 v3_load(const float *p) { return v3(p[0], p[1], p[2]); }
static inline int v3_max_axis(vec3 a)
{
    return (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2);
}

/* An empty box has min > max on every axis, so growing it by any point works. */
static inline box3 box3_empty(void)
{
    box3 b = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    return b;
}
static inline box3 box3_grow(box3 b, vec3 p)
{
    b.min = v3_min(b.min, p);
    b.max = v3_max(b.max, p);
    return b;
}
static inline box3 box3_union(box3 a, box3 b)
{
    a.min = v3_min(a.min, b.min);
    a.max = v3_max(a.max, b.max);
    return a;
}
static inline int box3_is_empty(box3 b) { return !(b.min.x <= b.max.x); }
static inline vec3 box3_extent(box3 b) { return v3_sub(b.max, b.min); }
static inline vec3 box3_center(box3 b) { return v3_scale(v3_add(b.min, b.max), 0.5f); }
/* Half the surface area: the SAH only ever compares areas, so the factor 2 is dropped. */
static inline float box3_half_area(box3 b)
{
    if (box3_is_empty(b)) return 0.0f;
    vec3 e = box3_extent(b);
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

/* The float nearest to a double bound x on the outer side: at or below x
 * (a box's low end), at or above it (its high end). */
static inline float accel_float_down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}
static inline float accel_float_up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

/* gamma(n) = n*eps/(1-n*eps) with eps = 2^-24 (pbrt-v3, section 3.9). */
#define ACCEL_GAMMA(n) (((float)(n) * 0x1p-24f) / (1.0f - (float)(n) * 0x1p-24f))
/* Ize 2013: enlarging t_far by 2*gamma(3)*|t_far| makes the float slab test conservative. */
#define ACCEL_SLAB_PAD (2.0f * ACCEL_GAMMA(3))

/*
 * The far planes' padding folded into the ray (the "far" reciprocals):
 * Ize's robust slab test (2013) pads the far distance t1 to
 * t1 + |t1| 2 gamma(3) after the minimum, three dependent operations on
 * every node's path from its load to the next. The BVH kernels (binary
 * bvh_slab and the wide slab_planes) multiply the far planes' distances
 * by ixf = 1/d (1 + ACCEL_FAR_PAD) instead of 1/d, and t_far by
 * 1 + ACCEL_FAR_PAD before the minimum, which the node's load does not
 * wait for. The same guarantee: a computed far distance (plane - o) ixf
 * is the exact one times (1 + p)(1 +- u)^4 (the difference, 1/d, its
 * padding and the product each rounded once), a near one the exact one
 * times (1 +- u)^3, and every sign is exact (fl(plane - o) has the sign
 * of plane - o); so with p = 2^-20 = 16u >= 7u + O(u^2) a computed near
 * distance never exceeds a computed far one the exact ones are ordered
 * by, whenever the far one is >= 0. A negative far distance only matters
 * to a ray with t_near < 0 (otherwise t0 >= t_near >= 0 rejects the box
 * either way); such rays (not folded) keep the padding after the minimum.
 */
#define ACCEL_FAR_PAD 0x1p-20f

/* Whether a ray's far padding is folded (t_near >= 0; false for NaN), the
 * factor of its far planes' reciprocals, and its padded t (t >= t_near >= 0
 * when folded). The binary and the wide slab tests share them, so that a
 * wide node accepts exactly the boxes the binary kernel would. */
static inline int accel_far_folded(float t_near) { return t_near >= 0.0f; }
static inline float accel_far_factor(int folded) { return folded ? 1.0f + ACCEL_FAR_PAD : 1.0f; }
static inline float accel_far_limit(float t, int folded) { return folded ? t + t * ACCEL_FAR_PAD : t; }


/*
 * A box grown outward by delta plus 2^-22 of each coordinate's magnitude
 * (clamped to the finite range): what a tree stores so that its exact box
 * test never rejects a hit the exact triangle test (core/prim.h) claims.
 * That test decides on coordinates sheared relative to the ray origin, so it
 * may place a hit about 8 * 2^-53 * |vertex - origin| outside the
 * triangle's box: for a ray that starts on a surface next to a shared edge,
 * the triangle across the edge can own the hit while its box is missed.
 * Callers pass delta = box3_hit_delta(largest coordinate magnitude of the
 * structure); the relative part covers errors that grow with the distance
 * along the ray.
 */
static inline float box3_hit_delta(float abs_max)
{
    return 0x1p-40f * (abs_max <= FLT_MAX ? abs_max : FLT_MAX) + 0x1p-126f;
}

/* The largest coordinate magnitude of a box (0 for an empty one, +inf
 * for a box with an infinite or NaN bound). */
static inline float box3_abs_max(box3 b)
{
    if (!(b.min.x <= b.max.x)) return b.min.x == INFINITY ? 0.0f : INFINITY;
    float m = 0.0f;
    const float *c[2] = {&b.min.x, &b.max.x};
    for (int k = 0; k < 2; k++)
        for (int a = 0; a < 3; a++) {
            float v = fabsf(c[k][a]);
            m = v > m || v != v ? v : m;
        }
    return m;
}

static inline float box3_hit_pad_lo(float v, float delta)
{
    float r = v - (delta + fabsf(v) * 0x1p-22f);
    return r < -FLT_MAX ? -FLT_MAX : r;
}

static inline float box3_hit_pad_hi(float v, float delta)
{
    float r = v + (delta + fabsf(v) * 0x1p-22f);
    return r > FLT_MAX ? FLT_MAX : r;
}

static inline box3 box3_hit_pad(box3 b, float delta)
{
    b.min = v3(box3_hit_pad_lo(b.min.x, delta), box3_hit_pad_lo(b.min.y, delta),
               box3_hit_pad_lo(b.min.z, delta));
    b.max = v3(box3_hit_pad_hi(b.max.x, delta), box3_hit_pad_hi(b.max.y, delta),
               box3_hit_pad_hi(b.max.z, delta));
    return b;
}

/*
 * Robust slab test against box [lo, hi] (given as two float[3]).
 * inv_dir = 1/dir per component (±inf for a ±0 component); neg[a] = 1 when
 * the direction's sign bit is set on axis a, which picks the near plane.
 * A zero direction component with the origin exactly on a plane gives
 * 0*inf = NaN: maxf/minf then keep the running value, so the ray counts as
 * inside that slab (it lies in the face's plane: the conservative answer).
 * Returns nonzero when [t_near, t_far] overlaps the box; *t_entry gets the
 * entry distance (clamped to t_near).
 */
static inline int box3_slab(const float *lo, const float *hi, vec3 org, vec3 inv_dir,
                            const int *neg, float t_near, float t_far, float *t_entry)
{
    float nx = neg[0] ? hi[0] : lo[0], fx = neg[0] ? lo[0] : hi[0];
    float ny = neg[1] ? hi[1] : lo[1], fy = neg[1] ? lo[1] : hi[1];
    float nz = neg[2] ? hi[2] : lo[2], fz = neg[2] ? lo[2] : hi[2];
    float t0 = t_near, t1 = t_far;
    t0 = maxf(t0, (nx - org.x) * inv_dir.x);
    t0 = maxf(t0, (ny - org.y) * inv_dir.y);
    t0 = maxf(t0, (nz - org.z) * inv_dir.z);
    t1 = minf(t1, (fx - org.x) * inv_dir.x);
    t1 = minf(t1, (fy - org.y) * inv_dir.y);
    t1 = minf(t1, (fz - org.z) * inv_dir.z);
    *t_entry = t0;
    return t0 <= t1 + fabsf(t1) * ACCEL_SLAB_PAD;
}

/* A box whose slab test gave entry distance t_entry can still hold a hit
 * at or before t: the slab test's own padding, so that a far child pushed
 * earlier is skipped only when the slab test itself would now reject it,
 * and a box entered at exactly t (a hit at t_far, before any other) is not
 * dropped for its entry's rounding. Every BVH walk's pop uses it. */
static inline int box3_entry_before(float t_entry, float t)
{
    return t_entry <= t + fabsf(t) * ACCEL_SLAB_PAD;
}

#ifdef __cplusplus
}
#endif

#endif
