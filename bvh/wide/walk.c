/*
 * walk.c - accel.h's conservative walk over the wide tree (../bvh_walk.c
 * describes the binary one): the collapsed tree walked one child lane at
 * a time (scalar; the SIMD kernels stay the timed path), every box grown
 * by the pad before the robust slab test; the hit children are ordered by
 * entry distance and pushed far to near; a leaf visits every lane of its
 * blocks (padding lanes repeat their leaf's last primitive: a repeated
 * visit, which the contract allows).
 */
#include "node.h"

/* One wide node seen through its rows (width 4 or 8). */
void bvh_wide_walk(const bvh_wide *w, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                   void *ctx, uint32_t *steps)
{
    if (w->root == WIDE_EMPTY) return;
    const int W = w->width;
    const size_t block_bytes = w->block == 8 ? sizeof(wide_block8) : sizeof(wide_block4);
    const size_t id_ofs = w->block == 8 ? offsetof(wide_block8, id) : offsetof(wide_block4, id);
    float t_max = p->t_far;
    bvh_walk_entry stack[WIDE_STACK(8)];
    int sp = 0;
    stack[sp].node = w->root;
    stack[sp++].entry = -INFINITY;
    while (sp > 0) {
        bvh_walk_entry top = stack[--sp];
        if (!box3_entry_before(top.entry, t_max)) continue;
        (*steps)++;
        if (top.node & WIDE_LEAF) {
            const char *blk = wide_leaf_addr(w, top.node);
            for (uint32_t k = 0; k < wide_leaf_blocks(top.node); k++, blk += block_bytes) {
                const uint32_t *ids = (const uint32_t *)(blk + id_ofs);
                for (int lane = 0; lane < w->block; lane++) {
                    t_max = visit(ctx, ids[lane], t_max);
                    if (t_max < p->t_near) return;
                }
            }
            continue;
        }
        const char *nd = wide_node_addr(w, top.node);
        const float *rows = (const float *)nd;
        const uint32_t *child = w->quant ? ((const wide_qnode8 *)nd)->child
                                         : (const uint32_t *)(nd + (size_t)6 * W * sizeof(float));
        bvh_walk_entry hit[8];
        int n = 0;
        for (int c = 0; c < W; c++) {
            if (child[c] == WIDE_EMPTY) continue;
            float lo[3], hi[3];
            if (w->quant) {
                bvh_wide_qbox((const wide_qnode8 *)nd, c, lo, hi);
            } else {
                lo[0] = rows[0 * W + c], lo[1] = rows[2 * W + c], lo[2] = rows[4 * W + c];
                hi[0] = rows[1 * W + c], hi[1] = rows[3 * W + c], hi[2] = rows[5 * W + c];
            }
            float e;
            if (!bvh_padded_slab(lo, hi, pad, p, t_max, &e)) continue;
            /* Insertion by entry, farthest first: the nearest is pushed last. */
            int j = n++;
            while (j > 0 && hit[j - 1].entry < e) hit[j] = hit[j - 1], j--;
            hit[j].node = child[c];
            hit[j].entry = e;
        }
        for (int c = 0; c < n; c++) stack[sp++] = hit[c];
    }
}
