/*
 * inst_packet.h - the packets of the `instanced` kind (traverse=packet),
 * internal to instanced/: the packet and its views (inst_packet.c walks
 * them, inst_packet_rays.c fills them), and the 8-ray pieces both use:
 * the slab test of 8 rays against one child box and the frustum test of
 * a node (bvh/wide/packet.h's, with the pads) and the entry cull at a
 * pop; the leaves are the shared block test's (core/block_test.h, ray by
 * ray, inst_packet.c). A kernel body (C only): it instantiates
 * bvh/wide/'s templates, and is not part of an interface a C++ program
 * includes.
 */
#ifndef INSTANCED_INST_PACKET_H
#define INSTANCED_INST_PACKET_H

#include <math.h>

#include "core/prim.h"
#include "inst_impl.h"
#include "inst_ray.h"
/* bvh/wide/'s packet pieces and the block test (8 wide). */
#define WIDE_NW 8
#define WIDE_LB 8
#include "core/block_test.h"
#include "bvh/wide/kernel.h"
#include "bvh/wide/packet.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { IP_RAYS = 64 };
#define IP_STACK ((INST_WIDE - 1) * BVH_MAX_DEPTH + 1)
#define IP_BIT(r) ((uint64_t)1 << (r))

/* The packet's rays as one walk sees them: the world rays at the top
 * level, one instance's object-space rays (from its box entry) below.
 * Rows of 64 floats, each 32-byte aligned for 8-lane loads. */
typedef struct {
    float ox[IP_RAYS] __attribute__((aligned(32)));
    float oy[IP_RAYS], oz[IP_RAYS], ix[IP_RAYS], iy[IP_RAYS], iz[IP_RAYS];
    float lo[IP_RAYS], hi[IP_RAYS]; /* the range in the walk's parameter */
    float pad[IP_RAYS];             /* each ray's box growth (padded) */
    double shift[IP_RAYS];          /* walk parameter = t - shift */
    float slack;                    /* relative widening of hi (inst_walk_hi) */
    int padded;
    /* The frustum (frustum != 0: one octant, finite reciprocals). */
    int frustum, octant;
    float o_lo[3], o_hi[3], i_lo[3], i_hi[3], t_lo, t_hi, pad_max;
} ip_view;

typedef struct {
    /* The prepared world rays (accel_prep_ray) as rows: origins, inverse
     * directions and t_near are the top view's ox..iz and lo; ip_prep
     * puts one back together for the scalar tests. */
    ip_view top;                /* world rays: shift 0, slack 0, no pad */
    float dx[IP_RAYS] __attribute__((aligned(32))); /* directions */
    float dy[IP_RAYS] __attribute__((aligned(32)));
    float dz[IP_RAYS] __attribute__((aligned(32)));
    float sx[IP_RAYS] __attribute__((aligned(32))); /* shears */
    float sy[IP_RAYS] __attribute__((aligned(32)));
    float sz[IP_RAYS] __attribute__((aligned(32)));
    float tf[IP_RAYS] __attribute__((aligned(32))); /* their t_far: the whole range's end */
    int32_t kx[IP_RAYS] __attribute__((aligned(32))); /* their permuted axes */
    int32_t ky[IP_RAYS] __attribute__((aligned(32)));
    int32_t kz[IP_RAYS] __attribute__((aligned(32)));
    float t[IP_RAYS], u[IP_RAYS], v[IP_RAYS];
    uint32_t prim[IP_RAYS];
    uint64_t live;              /* valid rays still looking (any hit: until one) */
    int any;
    int shared;                 /* every valid ray has the same origin and axes */
    /* With shared: each group's rectangle of shears (centre, half sizes,
     * largest |sx| and |sy|) for the leaf cull, made at the first leaf that
     * culls (rects set); the cull's record (inst_packet.c). */
    int rects;
    float gcx[IP_RAYS / 8], gcy[IP_RAYS / 8], ghx[IP_RAYS / 8], ghy[IP_RAYS / 8];
    float gxa[IP_RAYS / 8], gya[IP_RAYS / 8];
    uint32_t cull_tries, cull_wins, cull_skips;
    uint32_t top_steps[IP_RAYS], bottom_steps[IP_RAYS], boxes[IP_RAYS], prims[IP_RAYS];
} ip_packet;

/* Ray r's prepared form, as accel_prep_ray made it (ip_load). */
INST_INLINE void ip_prep(const ip_packet *pk, unsigned r, accel_ray_prep *p)
{
    p->org = v3(pk->top.ox[r], pk->top.oy[r], pk->top.oz[r]);
    p->dir = v3(pk->dx[r], pk->dy[r], pk->dz[r]);
    p->inv_dir = v3(pk->top.ix[r], pk->top.iy[r], pk->top.iz[r]);
    p->neg[0] = signbit(pk->dx[r]) != 0, p->neg[1] = signbit(pk->dy[r]) != 0;
    p->neg[2] = signbit(pk->dz[r]) != 0;
    p->kx = pk->kx[r], p->ky = pk->ky[r], p->kz = pk->kz[r];
    p->sx = pk->sx[r], p->sy = pk->sy[r], p->sz = pk->sz[r];
    p->t_near = pk->top.lo[r], p->t_far = pk->tf[r];
}

typedef struct {
    uint32_t ref;
    float entry; /* smallest entry distance of the rays in mask */
    uint64_t mask;
} ip_entry;

/* ---- 8 rays against one child box ------------------------------------------------ */

#if INST_WIDE_AVX
/* The lanes of bits m (8 rays) as an AVX mask. */
INST_INLINE __m256 ip_lanes(unsigned m)
{
    return _mm256_castsi256_ps(_mm256_cmpgt_epi32(
        _mm256_and_si256(_mm256_set1_epi32((int)m), _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)),
        _mm256_setzero_si256()));
}
#else
INST_INLINE f8 ip_lanes(unsigned m)
{
    f8 r;
    for (int i = 0; i < 8; i++) r.v[i] = f8_float_(m >> i & 1 ? 0xFFFFFFFFu : 0u);
    return r;
}
#endif

/* Rays of group g (candidates m) whose range meets child c's box grown by
 * their pads; *entry lowered to the smallest entry among them (lane-wise:
 * the caller reduces it). bvh/wide/packet.h's 8-ray slab test, each lane
 * with its own octant and pad. */
typedef f8 ip_entries;
INST_INLINE unsigned ip_group(const ip_view *v, const wide_node8 *n, unsigned c, unsigned g,
                              unsigned m, ip_entries *entry)
{
    const unsigned r = 8 * g;
    f8 t0, in = group_slab_mixed_8_8(v->ox + r, v->oy + r, v->oz + r, v->ix + r, v->iy + r, v->iz + r,
                                     v->lo + r, v->hi + r, v->padded ? v->pad + r : NULL, n->box[0], c, &t0);
    unsigned h = (unsigned)f8_mask(in) & m;
    if (h) *entry = f8_min(*entry, f8_blend(f8_set1(INFINITY), t0, ip_lanes(h)));
    return h;
}

/* The smallest of the lanes ip_group lowered. */
INST_INLINE float ip_entry_min(ip_entries e)
{
#if INST_WIDE_AVX
    __m128 x = _mm_min_ps(_mm256_castps256_ps128(e), _mm256_extractf128_ps(e, 1));
    x = _mm_min_ps(x, _mm_movehl_ps(x, x));
    x = _mm_min_ss(x, _mm_shuffle_ps(x, x, 1));
    return _mm_cvtss_f32(x);
#else
    return f8_hmin(e);
#endif
}

/* Slots of node n that hold a child. */
INST_INLINE unsigned ip_children(const wide_node8 *n)
{
#if INST_WIDE_AVX
    __m256i none = _mm256_cmpeq_epi32(_mm256_load_si256((const __m256i *)n->child),
                                      _mm256_set1_epi32((int)WIDE_EMPTY));
    return ~(unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(none)) & 0xFFu;
#else
    unsigned cand = 0;
    for (unsigned c = 0; c < INST_WIDE; c++) cand |= (unsigned)(n->child[c] != WIDE_EMPTY) << c;
    return cand;
#endif
}

/* Children some ray of the view may hit (the frustum test, see above):
 * bvh/wide/packet.h's, with every box grown by the view's largest pad. */
INST_INLINE unsigned ip_frustum(const ip_view *v, const wide_node8 *n)
{
#if INST_WIDE_AVX
    return frustum_rows_8_8(v->octant, v->o_lo, v->o_hi, v->i_lo, v->i_hi, v->t_lo, v->t_hi, n->box[0],
                            v->pad_max, 1);
#else
    (void)v, (void)n;
    return 0xFFu;
#endif
}

/* The rays of m whose range still reaches an entry at `entry`
 * (box3_entry_before on each ray's current end). */
INST_INLINE uint64_t ip_still(const ip_view *v, uint64_t m, float entry)
{
    uint64_t keep = 0;
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        unsigned gm = (unsigned)(m >> (8 * g)) & 0xFFu;
        if (!gm) continue;
#if INST_WIDE_AVX
        __m256 hi = _mm256_load_ps(v->hi + 8 * g);
        __m256 lim = _mm256_add_ps(
            hi, _mm256_mul_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), hi), _mm256_set1_ps(ACCEL_SLAB_PAD)));
        gm &= (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(_mm256_set1_ps(entry), lim, _CMP_LE_OQ));
#else
        for (unsigned k = gm; k; k &= k - 1) {
            unsigned l = (unsigned)__builtin_ctz(k);
            if (!box3_entry_before(entry, v->hi[8 * g + l])) gm &= ~(1u << l);
        }
#endif
        keep |= (uint64_t)gm << (8 * g);
    }
    return keep;
}

/* inst_packet_rays.c: rays [0, n) into the packet (the rest of its 64
 * lanes dead); the rays m of the packet in instance it's object space,
 * into the view ov (returns the rays that reach its mesh's padded box,
 * with the frustum's bounds set); the frustum's bounds of a view. */
void ip_load(ip_packet *pk, const accel_ray *rays, unsigned n, int any, int counted);
uint64_t ip_objects(const inst_accel *a, const inst_item *it, const inst_bottom *b, ip_packet *pk,
                    ip_view *ov, uint64_t m, int counted);
void ip_bounds(ip_view *v, uint64_t m);

#ifdef __cplusplus
}
#endif

#endif
