/*
 * wide_kernel.h - single-ray traversal of a wide BVH with WIDE_NW (4 or 8)
 * children per node and leaf blocks of WIDE_LB (4 or 8) primitives:
 * closest hit and any hit.
 *
 * A template: wide_trace.c includes it once per (WIDE_NW, WIDE_LB) pair
 * after wide_leaf.h for WIDE_LB (4 and 4 when included alone). It defines
 * the always-inline kernels wide_closest_<NW>_<LB> and wide_any_<NW>_<LB>
 * in the form core/variant.h's ACCEL_KERNEL_TABLE expects.
 *
 * The loop follows Embree's single-ray BVH4/BVH8 traversal (Wald et al.,
 * "Embree: A Kernel Framework for Efficient CPU Ray Tracing", SIGGRAPH
 * 2014) and the stack discipline of Aila and Laine (HPG 2009):
 *  - one ray against all W child boxes with the robust slab test of
 *    bvh_slab (Ize 2013) lane by lane: the same subtractions, products,
 *    NaN-dropping min/max and 2*gamma(3) padding of the far distance, so a
 *    wide node accepts exactly the boxes the binary kernel would;
 *  - the hit children visited near to far: one hit child is entered
 *    directly; of two, the nearer is entered and the farther pushed with
 *    its entry distance; three or more are pushed, sorted by entry distance
 *    (insertion sort on at most 8 entries, the nearest on top) and the top
 *    popped;
 *  - leaves are children like nodes (pushed and ordered by distance);
 *  - a popped entry whose entry distance lies beyond the closest hit found
 *    since it was pushed is dropped unvisited;
 *  - any hit returns at the first hit.
 * Counters (steps = nodes and leaves visited, box tests = W per node,
 * primitive tests = primitives of the blocks tested) and the step bound
 * (ACCEL_STEP_BOUND_BROKEN: a ray visits each node and leaf at most once)
 * exist in the counted copy only.
 */
#ifndef WIDE_NW
#define WIDE_NW 4
#endif
#ifndef WIDE_LB
#define WIDE_LB 4
#include "wide_leaf.h"
#endif
#include "core/variant.h"
#include "wide_node.h"
#include "wide_simd.h"

#define WK_CAT_(a, b, c) a##_##b##_##c
#define WK_CAT(a, b, c) WK_CAT_(a, b, c)
#define WK(name) WK_CAT(name, WIDE_NW, WIDE_LB)
#define WL2_(a, b) a##_##b
#define WL2(a, b) WL2_(a, b)
#define KL(name) WL2(name, WIDE_LB)
#define NV(op) WIDE_V(WIDE_NW, op)
#define NF WIDE_T(WIDE_NW)
#define WK_JOIN_(a, b) a##b
#define WK_JOIN(a, b) WK_JOIN_(a, b)
#define KNODE WK_JOIN(wide_node, WIDE_NW)
#define KBLOCK WK_JOIN(wide_block, WIDE_LB)

static inline __attribute__((always_inline)) void
WK(trace_ray)(const bvh_wide *w, const accel_ray *ray, accel_hit *hit_out, uint8_t *occ_out,
              accel_counters *c, size_t ray_idx, unsigned flags, int any_hit)
{
    const int naive = (flags & ACCEL_V_NAIVE) != 0, has_spheres = (flags & ACCEL_V_SPHERES) != 0;
    accel_hit hit = accel_hit_miss();
    uint32_t steps = 0, boxes = 0, prims = 0;
    accel_ray_prep p;
    if (w->root != WIDE_EMPTY && wide_prep_ray(ray, &p)) {
        /* Set up the slab test: origin, 1/dir and the row of each axis's
         * near and far plane, picked by the direction's sign bit. */
        NF ox = NV(set1)(p.org.x), oy = NV(set1)(p.org.y), oz = NV(set1)(p.org.z);
        NF ix = NV(set1)(p.inv_dir.x), iy = NV(set1)(p.inv_dir.y), iz = NV(set1)(p.inv_dir.z);
        NF t_near = NV(set1)(p.t_near), pad = NV(set1)(ACCEL_SLAB_PAD);
        const int nx = (0 + p.neg[0]) * WIDE_NW, fx = (1 - p.neg[0]) * WIDE_NW;
        const int ny = (2 + p.neg[1]) * WIDE_NW, fy = (3 - p.neg[1]) * WIDE_NW;
        const int nz = (4 + p.neg[2]) * WIDE_NW, fz = (5 - p.neg[2]) * WIDE_NW;
        KL(wide_leaf_ray) lr;
        KL(leaf_setup)(&lr, &p);
        const KNODE *nodes = w->nodes;
        const KBLOCK *blocks = w->blocks;
        float t = p.t_far;
        uint32_t hit_id = ACCEL_MISS;
        wide_stack_entry stack[WIDE_STACK(WIDE_NW)];
        int sp = 0;
        uint32_t ref = w->root;
        for (;;) {
            steps++;
            if (ACCEL_STEP_BOUND_BROKEN(c, steps, w->step_bound)) break;
            if (!(ref & WIDE_LEAF)) {
                /* Interior: all children's boxes at once. */
                const KNODE *n = &nodes[ref];
                const float *b = n->box[0];
                NF t0 = NV(max)(NV(mul)(NV(sub)(NV(load)(b + nx), ox), ix), t_near);
                t0 = NV(max)(NV(mul)(NV(sub)(NV(load)(b + ny), oy), iy), t0);
                t0 = NV(max)(NV(mul)(NV(sub)(NV(load)(b + nz), oz), iz), t0);
                NF t1 = NV(min)(NV(mul)(NV(sub)(NV(load)(b + fx), ox), ix), NV(set1)(t));
                t1 = NV(min)(NV(mul)(NV(sub)(NV(load)(b + fy), oy), iy), t1);
                t1 = NV(min)(NV(mul)(NV(sub)(NV(load)(b + fz), oz), iz), t1);
                unsigned mask = (unsigned)NV(mask)(NV(le)(t0, NV(add)(t1, NV(mul)(NV(abs)(t1), pad))));
                boxes += WIDE_NW;
                if (mask) {
                    unsigned i = (unsigned)__builtin_ctz(mask);
                    mask &= mask - 1;
                    if (!mask) { /* one hit child: enter it */
                        ref = n->child[i];
                        continue;
                    }
                    float te[WIDE_NW] __attribute__((aligned(32)));
                    NV(store)(te, t0);
                    unsigned j = (unsigned)__builtin_ctz(mask);
                    mask &= mask - 1;
                    if (!mask) { /* two: enter the nearer, push the farther */
                        int swap = te[j] < te[i];
                        unsigned near = swap ? j : i, far = swap ? i : j;
                        stack[sp].ref = n->child[far];
                        stack[sp].t_entry = te[far];
                        sp++;
                        ref = n->child[near];
                        continue;
                    }
                    /* Three or more: push all, sort the run far to near
                     * (insertion sort), enter the nearest. */
                    int base = sp;
                    stack[sp].ref = n->child[i], stack[sp].t_entry = te[i], sp++;
                    stack[sp].ref = n->child[j], stack[sp].t_entry = te[j], sp++;
                    do {
                        unsigned k = (unsigned)__builtin_ctz(mask);
                        mask &= mask - 1;
                        stack[sp].ref = n->child[k], stack[sp].t_entry = te[k], sp++;
                    } while (mask);
                    for (int a = base + 1; a < sp; a++) {
                        wide_stack_entry e = stack[a];
                        int k = a;
                        while (k > base && stack[k - 1].t_entry < e.t_entry) {
                            stack[k] = stack[k - 1];
                            k--;
                        }
                        stack[k] = e;
                    }
                    ref = stack[--sp].ref;
                    continue;
                }
            } else {
                /* Leaf: its blocks are consecutive. */
                const KBLOCK *blk = &blocks[wide_leaf_first(ref)];
                uint32_t nb = wide_leaf_blocks(ref);
                for (uint32_t k = 0; k < nb; k++) {
                    if (c) {
                        prims++;
                        for (int lane = 1; lane < WIDE_LB; lane++)
                            prims += blk[k].id[lane] != blk[k].id[lane - 1];
                    }
                    if (KL(leaf_block)(&blk[k], &lr, &p, &t, &hit.u, &hit.v, &hit_id, w->tri_count,
                                       naive, has_spheres, any_hit) &&
                        any_hit) {
                        hit_id = 0; /* occluded: which primitive does not matter */
                        goto done;
                    }
                }
            }
            /* Pop the next entry that can still hold a closer hit. */
            for (;;) {
                if (sp == 0) goto done;
                sp--;
                if (bvh_entry_before(stack[sp].t_entry, t)) {
                    ref = stack[sp].ref;
                    break;
                }
            }
        }
    done:
        if (hit_id != ACCEL_MISS) {
            hit.t = t;
            hit.prim = hit_id;
        } else {
            hit.u = hit.v = 0.0f;
        }
    }
    if (any_hit)
        occ_out[ray_idx] = hit.prim != ACCEL_MISS;
    else
        hit_out[ray_idx] = hit;
    if (c) {
        c->rays++;
        c->steps += steps;
        c->box_tests += boxes;
        c->prim_tests += prims;
        if (c->ray_steps) c->ray_steps[ray_idx] = steps;
        if (c->ray_prims) c->ray_prims[ray_idx] = prims;
    }
}

static inline __attribute__((always_inline)) void
WK(wide_closest)(const void *a, const accel_ray *rays, void *out, size_t count, accel_counters *c,
                 unsigned flags)
{
    for (size_t i = 0; i < count; i++)
        WK(trace_ray)(a, &rays[i], out, NULL, c, i, flags, 0);
}

static inline __attribute__((always_inline)) void
WK(wide_any)(const void *a, const accel_ray *rays, void *out, size_t count, accel_counters *c,
             unsigned flags)
{
    for (size_t i = 0; i < count; i++)
        WK(trace_ray)(a, &rays[i], NULL, out, c, i, flags, 1);
}

#undef WK_CAT_
#undef WK_CAT
#undef WK
#undef WL2_
#undef WL2
#undef KL
#undef NV
#undef NF
#undef KNODE
#undef KBLOCK
#undef WK_JOIN_
#undef WK_JOIN
