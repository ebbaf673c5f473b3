/*
 * build_binned_view.h - how the binned SAH builder (build_binned.c) sees a
 * reference: its box and centroid 4-wide where the machine has SSE, the
 * bin plan of a node (which axes, where the bins start, bins per unit),
 * and a reference's bin on each axis. Binning, the refinement of a
 * clustered bin and both partitions use view_ref alone, so that they can
 * never disagree about a reference.
 * A kernel body (C only): included by build_binned.c, not part of the
 * interface a C++ program includes.
 */
#ifndef BVH_BUILD_BINNED_VIEW_H
#define BVH_BUILD_BINNED_VIEW_H

#include "split_common.h"

#if BVH_SSE
#include <immintrin.h>
#endif

/* ---- boxes and bin indices, 4-wide where the machine has SSE ------------- */

#if BVH_SSE
typedef struct {
    __m128 lo, hi; /* lane 3 unused */
} box4;

static inline void box4_clear(box4 *b)
{
    b->lo = _mm_set1_ps(INFINITY);
    b->hi = _mm_set1_ps(-INFINITY);
}

static inline void box4_union(box4 *b, const box4 *o)
{
    b->lo = _mm_min_ps(b->lo, o->lo);
    b->hi = _mm_max_ps(b->hi, o->hi);
}

static inline box3 box4_to_box3(const box4 *b)
{
    float lo[4], hi[4];
    _mm_storeu_ps(lo, b->lo);
    _mm_storeu_ps(hi, b->hi);
    box3 r = {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    return r;
}
#else
typedef struct {
    box3 b;
} box4;

static inline void box4_clear(box4 *b) { b->b = box3_empty(); }
static inline void box4_union(box4 *b, const box4 *o) { b->b = box3_union(b->b, o->b); }
static inline box3 box4_to_box3(const box4 *b) { return b->b; }
#endif

/*
 * Half area of a box with its extents scaled by `scale` (1 / the node's
 * largest extent): the same factor on every axis keeps areas proportional,
 * and relative areas are at most 3, so the sweep can run in float without
 * overflow whatever the scene's size.
 */
#if BVH_SSE
static inline float box4_scaled_area(const box4 *b, __m128 scale)
{
    __m128 e = _mm_mul_ps(_mm_sub_ps(b->hi, b->lo), scale); /* lane 3: 0 */
    __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1))); /* xy yz zx 0 */
    p = _mm_add_ps(p, _mm_movehl_ps(p, p));
    return _mm_cvtss_f32(_mm_add_ss(p, _mm_shuffle_ps(p, p, 1)));
}
#else
static inline float box4_scaled_area(const box4 *b, float scale)
{
    vec3 e = v3_scale(box3_extent(b->b), scale);
    return e.x * e.y + e.y * e.z + e.z * e.x;
}
#endif

/* Which axes to bin and how centroids map to bins, per axis (lane). */
typedef struct {
    int axis_count;
    int axis[3];             /* the axes binned */
    _Alignas(16) float cmin[4];
    _Alignas(16) float scale[4]; /* bins per unit of centroid coordinate; 0 on unused axes */
    int bins;
} bin_plan;

/*
 * A reference as the binner sees it: its box, its centroid, and its bin on
 * each axis (bin[axis]). Binning and partitioning both use this one
 * function, so that they can never disagree about a reference. The
 * centroid is 0.5*lo + 0.5*hi as bvh_ref_centroid computes it; a rounding
 * difference from the centroid bounds only moves a reference by a bin, and
 * the clamps keep every bin inside [0, bins-1].
 */
typedef struct {
    box4 box;
#if BVH_SSE
    __m128 c; /* lane 3: 0 */
#else
    vec3 c;
#endif
    int bin[4];
} ref_view;

#if BVH_SSE
/* A reference's box (lo, hi), centroid c and bin coordinates per axis,
 * clamped to [0, bins-1] (`top`): the bin is their truncation. cmin and
 * scale are the plan's, passed in so that a loop keeps them in registers. */
static inline __m128 view_coords(const bvh_ref *r, __m128 cmin, __m128 scale, __m128 top, box4 *box,
                                 __m128 *c)
{
    /* Lane 3 (id bits: a denormal as a float) is cleared before any
     * arithmetic: denormal operands cost a microcode assist each. */
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    const __m128 half = _mm_set1_ps(0.5f);
    box->lo = _mm_and_ps(_mm_loadu_ps(r->lo), xyz);
    box->hi = _mm_and_ps(_mm_loadu_ps(r->hi), xyz);
    *c = _mm_add_ps(_mm_mul_ps(box->lo, half), _mm_mul_ps(box->hi, half));
    __m128 f = _mm_mul_ps(_mm_sub_ps(*c, cmin), scale);
    f = _mm_max_ps(f, _mm_setzero_ps()); /* also turns a NaN into 0 */
    return _mm_min_ps(f, top);
}
#endif

static inline void view_ref(const bin_plan *p, const bvh_ref *r, ref_view *v)
{
#if BVH_SSE
    __m128 f = view_coords(r, _mm_load_ps(p->cmin), _mm_load_ps(p->scale),
                           _mm_set1_ps((float)(p->bins - 1)), &v->box, &v->c);
    _mm_storeu_si128((__m128i *)v->bin, _mm_cvttps_epi32(f));
#else
    v->box.b = bvh_ref_box(r);
    v->c = bvh_ref_center(r);
    for (int a = 0; a < 3; a++) {
        float f = (v3_get(v->c, a) - p->cmin[a]) * p->scale[a];
        f = f > 0.0f ? f : 0.0f;
        f = f < (float)(p->bins - 1) ? f : (float)(p->bins - 1);
        v->bin[a] = (int)f;
    }
#endif
}

#endif
