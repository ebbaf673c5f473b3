/*
 * inst_packet.c - traverse=packet: the `instanced` kind's rays walked in
 * packets of 64 through both 8-wide levels (top=bvh, bottom=bvh, width=8).
 *
 * The packet walks the top level's wide nodes together: one child box is
 * tested against 8 rays per AVX sequence, lane by lane the very float
 * operations of the single-ray walk's box3_slab (the near and far
 * planes picked per lane by the sign of the reciprocal direction, so rays
 * of several octants may share a packet). At an instance, every ray of the
 * packet that reached it goes to object space as the single-ray walk takes
 * it (inst_ray.h: the same double transform, pad, clip and float ray from
 * the box entry), and the rays that reach the mesh's padded box walk its
 * wide bottom level as a packet, each lane's box grown by its own ray's
 * pad. At a bottom leaf each world block (the instance's copy, or
 * computed once for the packet) is tested by every ray of the packet that
 * reached the leaf with the shared block test (core/block_test.h), as
 * bvh/wide/packet.h's leaves do. So a ray gets the single-ray walk's
 * primitive; its t, u, v too but for rare near-ties, where which of the
 * test's float or double steps decides depends on the closest hit the ray
 * carries (bvh/wide/packet.h says the same of its packets).
 *
 * A stack entry holds the mask of the rays that hit its box and the
 * smallest of their entry distances; at the pop, rays whose closest hit
 * now lies before that entry leave the entry. When the walk's rays share
 * one octant (per level: a rotation may split an octant), a frustum test
 * first bounds every ray's slab interval for the node's 8 children at
 * once by interval arithmetic over the rays' origins, reciprocal
 * directions, ranges and pads (the largest), as bvh/wide/packet.h does
 * (Boulos, Wald and Shirley, UUCS-06-010, 2006): a child no ray can hit
 * is dropped before its per-ray tests.
 *
 * Rays reach the packets through core/coherence.h: any ray order, and
 * groups of 64 with no coherence go to the single-ray walk instead.
 */
#include <math.h>
#include <string.h>

#include "core/coherence.h"
#include "core/isa.h"
#include "core/variant.h"
#include "inst_packet.h"

/* Each group's rectangle of its live rays' shears: centre and half sizes,
 * rounded up so that it holds every ray's (sx, sy), and the largest |sx|,
 * |sy| (aff_cull_rect, core/block_test.h; bvh/wide/packet.h makes its
 * packets' the same way). */
static void ip_rects(ip_packet *pk)
{
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        float xl = INFINITY, xh = -INFINITY, yl = INFINITY, yh = -INFINITY;
        for (unsigned m = (unsigned)(pk->live >> (8 * g)) & 0xFFu; m; m &= m - 1) {
            unsigned r = 8 * g + (unsigned)__builtin_ctz(m);
            xl = fminf(xl, pk->sx[r]), xh = fmaxf(xh, pk->sx[r]);
            yl = fminf(yl, pk->sy[r]), yh = fmaxf(yh, pk->sy[r]);
        }
        float cx = 0.5f * (xl + xh), cy = 0.5f * (yl + yh);
        pk->gcx[g] = cx, pk->gcy[g] = cy;
        pk->ghx[g] = fmaxf(xh - cx, cx - xl) * (1.0f + 0x1p-20f) + 0x1p-100f;
        pk->ghy[g] = fmaxf(yh - cy, cy - yl) * (1.0f + 0x1p-20f) + 0x1p-100f;
        pk->gxa[g] = fmaxf(fabsf(xl), fabsf(xh)), pk->gya[g] = fmaxf(fabsf(yl), fabsf(yh));
    }
    pk->rects = 1;
}

/* The leaf cull of rays that share their origin and axes (the block's
 * relative vertices q): the groups of m whose rectangle of shears surely
 * misses every lane of the block (the exact test's first rule: edge
 * functions of mixed signs) skip it, charged its lanes all the same;
 * returns the others. As bvh/wide/packet.h's leaf cull. */
static __attribute__((noinline)) uint64_t ip_cull(ip_packet *pk, const wide_leaf_rel_8 *q, uint64_t m,
                                                  uint32_t lanes, int counted)
{
    if (!pk->rects) ip_rects(pk);
    wide_leaf_aff_8 f;
    leaf_aff_8(q, &f);
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        uint64_t gm = m & ((uint64_t)0xFF << (8 * g));
        if (!gm) continue;
        pk->cull_tries++;
        if (aff_cull_rect_8(&f, pk->gcx[g], pk->gcy[g], pk->ghx[g], pk->ghy[g], pk->gxa[g], pk->gya[g]) !=
            0xFF)
            continue;
        pk->cull_wins++;
        for (uint64_t k = counted ? gm : 0; k; k &= k - 1) pk->prims[__builtin_ctzll(k)] += lanes;
        m &= ~gm;
    }
    return m;
}

/* A bottom leaf, blocks [first, first + nb) of instance it's bottom
 * level w, for the rays m: each world block (k8_trace.c's test_blocks:
 * the plain scene's own, the instance's copies, or computed once here for
 * all the rays) tested by every ray with the shared block test, as
 * bvh/wide/packet.h's leaves do. Rays that share their origin and axes (a
 * pinhole camera's) share the block's vertices relative to it
 * (leaf_block_rel), and groups of 8 of them skip a block their shears
 * surely miss (ip_cull: tried from 8 rays on, and where it wins in one
 * try of 4 or more, else at every 16th leaf, as bvh/wide does). */
INST_INLINE void ip_leaf(const inst_accel *a, ip_packet *pk, ip_view *v, const inst_item *it,
                         const inst_wide *w, uint32_t first, uint32_t nb, uint64_t m, int naive,
                         int spheres, int counted)
{
    const uint32_t tri_count = a->scene->tri_count;
    const accel_block8 *blk = a->plain ? w->blocks + first : it->world ? it->world + first : NULL;
    const uint64_t reached = m;
    for (uint32_t k = 0; k < nb && (m &= pk->live); k++) {
        accel_block8 tmp __attribute__((aligned(64)));
        const accel_block8 *b = blk ? blk + k : &tmp;
        if (!blk) inst_world_block(it, w->blocks + first + k, &tmp);
        uint32_t lanes = 1;
        for (int l = 1; l < 8; l++) lanes += b->id[l] != b->id[l - 1];
        const int shared = pk->shared && !naive;
        wide_leaf_rel_8 q;
        uint64_t todo = m;
        if (shared) {
            accel_ray_prep p0;
            wide_leaf_ray_8 lr0;
            ip_prep(pk, (unsigned)__builtin_ctzll(m), &p0);
            leaf_setup_8(&lr0, &p0);
            leaf_rel_8(b, &lr0, &q);
            leaf_rel_mags_8(&q);
            if (!spheres && __builtin_popcountll(m) >= 8 &&
                (pk->cull_tries < 64 || 4 * pk->cull_wins >= pk->cull_tries || (++pk->cull_skips & 15) == 0))
                todo = ip_cull(pk, &q, m, lanes, counted);
        }
        for (; todo; todo &= todo - 1) {
            unsigned r = (unsigned)__builtin_ctzll(todo);
            accel_ray_prep p;
            wide_leaf_ray_8 lr;
            ip_prep(pk, r, &p);
            leaf_setup_8(&lr, &p);
            if (counted) pk->prims[r] += lanes;
            int hit = shared ? leaf_block_rel_8(b, &q, &lr, 1, &p, &pk->t[r], &pk->u[r], &pk->v[r],
                                                &pk->prim[r], tri_count, spheres, pk->any)
                             : leaf_block_8(b, &lr, &p, &pk->t[r], &pk->u[r], &pk->v[r], &pk->prim[r],
                                            tri_count, naive, spheres, pk->any);
            if (hit && pk->any) {
                pk->prim[r] = b->id[0]; /* occluded: which primitive does not matter */
                pk->live &= ~IP_BIT(r);
            }
        }
    }
    for (uint64_t k = reached; k; k &= k - 1) {
        unsigned r = (unsigned)__builtin_ctzll(k);
        v->hi[r] = inst_walk_hi(pk->t[r], v->shift[r], v->slack);
        pk->top.hi[r] = pk->t[r];
    }
}

static void ip_instance(const inst_accel *a, ip_packet *pk, uint32_t k, uint64_t m, int naive,
                        int spheres, int counted);

/* ---- the walk of one level ------------------------------------------------------- */

/* The packet's rays m through the wide tree (h, w): the top level (it ==
 * NULL, view pk->top, leaves are instances) or instance it's bottom level
 * (view v; lt its leaf-ordered triangles). */
INST_INLINE void ip_walk(const inst_accel *a, ip_packet *pk, ip_view *v, const inst_wide *w,
                         const inst_item *it, uint64_t m, int naive, int spheres, int counted)
{
    if (w->root == WIDE_EMPTY || !m) return;
    const int top = it == NULL;
    ip_entry stack[IP_STACK];
    int sp = 0;
    stack[sp++] = (ip_entry){w->root, -INFINITY, m};
    while (sp > 0) {
        ip_entry e = stack[--sp];
        uint64_t em = e.mask & pk->live;
        if (em && e.entry > -INFINITY) em = ip_still(v, em, e.entry);
        if (!em) continue;
        if (e.ref & WIDE_LEAF) {
            uint32_t first = wide_leaf_first(e.ref), nb = wide_leaf_blocks(e.ref);
            if (top) {
                for (uint32_t i = 0; i < nb && (em &= pk->live); i++)
                    ip_instance(a, pk, w->ids[first + i], em, naive, spheres, counted);
            } else {
                ip_leaf(a, pk, v, it, w, first, nb, em, naive, spheres, counted);
            }
            continue;
        }
        const wide_node8 *nd = (const wide_node8 *)w->nodes + e.ref;
        if (counted)
            for (uint64_t k = em; k; k &= k - 1) {
                unsigned r = (unsigned)__builtin_ctzll(k);
                if (top)
                    pk->top_steps[r]++;
                else
                    pk->bottom_steps[r]++;
                pk->boxes[r] += INST_WIDE;
            }
        unsigned cand = v->frustum ? ip_frustum(v, nd) : ip_children(nd); /* empty slots fail both */
        ip_entry hit[INST_WIDE];
        int nh = 0;
        for (; cand; cand &= cand - 1) {
            unsigned c = (unsigned)__builtin_ctz(cand);
            uint64_t cm = 0;
            ip_entries es = f8_set1(INFINITY);
            for (unsigned g = 0; g < IP_RAYS / 8; g++) {
                unsigned gm = (unsigned)(em >> (8 * g)) & 0xFFu;
                if (gm) cm |= (uint64_t)ip_group(v, nd, c, g, gm, &es) << (8 * g);
            }
            if (!cm) continue;
            float entry = ip_entry_min(es);
            int j = nh++; /* insertion, farthest first */
            while (j > 0 && hit[j - 1].entry < entry) hit[j] = hit[j - 1], j--;
            hit[j] = (ip_entry){nd->child[c], entry, cm};
        }
        /* The nearest child is tested again at its pop: its entry is
         * already known to be reached. */
        for (int j = 0; j < nh; j++) stack[sp++] = hit[j];
        if (nh) stack[sp - 1].entry = -INFINITY;
    }
}

/* The rays m of the packet through instance k (see the file's comment). */
static __attribute__((noinline)) void ip_instance(const inst_accel *a, ip_packet *pk, uint32_t k,
                                                  uint64_t m, int naive, int spheres, int counted)
{
    const inst_item *it = &a->items[k];
    const inst_bottom *b = &a->bottoms[it->bottom];
    if (it->identity) { /* the world rays themselves, no pad */
        ip_walk(a, pk, &pk->top, &b->wide, it, m, naive, spheres, counted);
        return;
    }
    ip_view ov;
    uint64_t keep = ip_objects(a, it, b, pk, &ov, m, counted);
    if (!keep) return;
    ip_walk(a, pk, &ov, &b->wide, it, keep, naive, spheres, counted);
}

/* ---- the batch kernel --------------------------------------------------------------- */

INST_INLINE void ip_kernel(const void *acc, const accel_ray *rays, void *out, size_t count,
                           accel_counters *c, unsigned flags, int any)
{
    const inst_accel *a = acc;
    const int naive = (flags & ACCEL_V_NAIVE) != 0, spheres = (flags & ACCEL_V_SPHERES) != 0;
    ip_packet pk;
    pk.cull_tries = pk.cull_wins = pk.cull_skips = 0;
    for (unsigned r = 0; r < IP_RAYS; r++) pk.top.pad[r] = 0.0f, pk.top.shift[r] = 0.0; /* world rays */
    for (size_t base = 0; base < count; base += IP_RAYS) {
        unsigned n = count - base < IP_RAYS ? (unsigned)(count - base) : IP_RAYS;
        ip_load(&pk, rays + base, n, any, c != NULL);
        ip_walk(a, &pk, &pk.top, &a->top_wide, NULL, pk.live, naive, spheres, c != NULL);
        for (unsigned r = 0; r < n; r++) {
            size_t i = base + r;
            if (any) {
                ((uint8_t *)out)[i] = pk.prim[r] != ACCEL_MISS;
            } else {
                accel_hit hh = accel_hit_miss();
                if (pk.prim[r] != ACCEL_MISS)
                    hh.t = pk.t[r], hh.prim = pk.prim[r], hh.u = pk.u[r], hh.v = pk.v[r];
                ((accel_hit *)out)[i] = hh;
            }
            if (c) {
                accel_count_ray(c, i, pk.top_steps[r] + pk.bottom_steps[r], 0, pk.boxes[r],
                                pk.prims[r], 0);
                c->level_steps[0] += pk.top_steps[r];
                c->level_steps[1] += pk.bottom_steps[r];
            }
        }
    }
}

#define IP_CLOSEST(a, r, o, n, c, f) ip_kernel(a, r, o, n, c, f, 0)
#define IP_ANY(a, r, o, n, c, f) ip_kernel(a, r, o, n, c, f, 1)
/* The copies timed (core/variant.h; issue 53's GRIDBVH_KLOG runs): the
 * experiments time index 0; spheres (2) and closest hits with the naive
 * test (1) as for the single-ray kernels (k8_trace.c), which
 * instanced:traverse=packet's stability rows time. */
ACCEL_KERNEL_TABLE_SEL(ip_closest_table, IP_CLOSEST, (1, 1, 1, 0, 0, 0, 0, 0))
ACCEL_KERNEL_TABLE_SEL(ip_any_table, IP_ANY, (1, 0, 1, 0, 0, 0, 0, 0))

static unsigned ip_flags(const inst_accel *a)
{
    return accel_variant_flags(a->naive, a->spheres, 0);
}

ACCEL_COHERENT_ENTRIES(inst_packet_intersect, inst_packet_occluded, const void, ip_closest_table,
                       ip_any_table, ip_flags, inst_single_intersect, inst_single_occluded)

/* The single-ray traversal in the structure's ISA (k8_trace.c). */
void inst_single_intersect(const void *acc, const accel_ray *rays, accel_hit *hits, size_t n,
                           accel_counters *c)
{
#ifdef GRIDBVH_AVX512
    if (((const inst_accel *)acc)->isa == ACCEL_ISA_AVX512) {
        inst_trace_intersect_avx512(acc, rays, hits, n, c);
        return;
    }
#endif
    inst_trace_intersect(acc, rays, hits, n, c);
}

void inst_single_occluded(const void *acc, const accel_ray *rays, uint8_t *occ, size_t n,
                          accel_counters *c)
{
#ifdef GRIDBVH_AVX512
    if (((const inst_accel *)acc)->isa == ACCEL_ISA_AVX512) {
        inst_trace_occluded_avx512(acc, rays, occ, n, c);
        return;
    }
#endif
    inst_trace_occluded(acc, rays, occ, n, c);
}

void inst_intersect(const void *acc, const accel_ray *rays, accel_hit *hits, size_t n,
                    accel_counters *c)
{
    const inst_accel *a = acc;
    if (a->packets)
        inst_packet_intersect(acc, rays, hits, n, c);
    else
        inst_single_intersect(acc, rays, hits, n, c);
}

void inst_occluded(const void *acc, const accel_ray *rays, uint8_t *occ, size_t n,
                   accel_counters *c)
{
    const inst_accel *a = acc;
    if (a->packets)
        inst_packet_occluded(acc, rays, occ, n, c);
    else
        inst_single_occluded(acc, rays, occ, n, c);
}
