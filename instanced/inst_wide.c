/*
 * inst_wide.c - the 8-wide form of the `instanced` kind's BVHs (both
 * levels; inst_impl.h's inst_wide): a bvh_box_tree collapsed so that a
 * ray tests 8 child boxes per node in one sequence of 8-lane instructions
 * (inst_wide.h) instead of 2 per binary node.
 *
 * The collapse is the greedy one of the wide-BVH literature (Wald et al.,
 * "Getting Rid of Packets", RT 2008; Embree's BVH8): a wide node starts
 * with its binary node's two children and opens, while it has fewer than
 * 8, the interior child of largest surface area into its own two children.
 * Each slot keeps its binary node's box exactly (src) and a leaf slot names
 * the binary leaf, so the wide tree holds the same boxes over the same
 * leaves: a walk of it with the same slab test reaches every leaf a walk of
 * the binary tree reaches (a slot whose ancestors the binary walk would
 * have tested first can only add leaves), which is all the exactness
 * argument of README.md asks of the bottom level. Refit copies the boxes
 * of the refit binary tree into the slots again.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "inst_impl.h"

static double half_area(const bvh_node *n)
{
    double x = (double)n->bmax[0] - n->bmin[0], y = (double)n->bmax[1] - n->bmin[1],
           z = (double)n->bmax[2] - n->bmin[2];
    return x * y + y * z + z * x;
}

static void set_slot(inst_wnode *w, int c, const bvh_node *n, uint32_t src)
{
    w->box[0][c] = n->bmin[0], w->box[1][c] = n->bmax[0];
    w->box[2][c] = n->bmin[1], w->box[3][c] = n->bmax[1];
    w->box[4][c] = n->bmin[2], w->box[5][c] = n->bmax[2];
    w->src[c] = src;
}

/* Wide node `at` over binary interior node b; returns the next free wide
 * node. Recursion depth is the binary tree's (at most BVH_MAX_DEPTH). */
static uint32_t collapse(const bvh_box_tree *h, inst_wide *w, uint32_t at, uint32_t b)
{
    uint32_t slot[INST_WIDE];
    int n = 2;
    slot[0] = h->nodes[b].left_first, slot[1] = slot[0] + 1;
    while (n < INST_WIDE) {
        int best = -1;
        double area = -1.0;
        for (int c = 0; c < n; c++) {
            const bvh_node *s = &h->nodes[slot[c]];
            if (s->count == 0 && half_area(s) > area) area = half_area(s), best = c;
        }
        if (best < 0) break;
        uint32_t open = h->nodes[slot[best]].left_first;
        slot[best] = open;
        slot[n++] = open + 1;
    }
    inst_wnode *node = &w->nodes[at];
    uint32_t next = at + 1;
    for (int c = 0; c < INST_WIDE; c++) {
        for (int k = 0; k < 6; k++) node->box[k][c] = k & 1 ? -INFINITY : INFINITY;
        node->child[c] = INST_WIDE_NONE;
        node->src[c] = INST_WIDE_NONE;
    }
    for (int c = 0; c < n; c++) {
        const bvh_node *s = &h->nodes[slot[c]];
        set_slot(node, c, s, slot[c]);
        if (s->count) {
            node->child[c] = INST_WIDE_LEAF | slot[c];
        } else {
            node->child[c] = next;
            next = collapse(h, w, next, slot[c]);
        }
    }
    return next;
}

int inst_wide_build(const bvh_box_tree *h, inst_wide *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    out->root = INST_WIDE_NONE;
    if (!h->node_count) return 0;
    if (h->nodes[0].count) {
        out->root = INST_WIDE_LEAF | 0u;
        return 0;
    }
    /* At most one wide node per binary interior node (each opens >= 1). */
    size_t cap = h->node_count / 2 + 1;
    out->nodes = aligned_alloc(64, cap * sizeof *out->nodes);
    if (!out->nodes)
        return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory for a wide BVH");
    out->node_count = collapse(h, out, 0, 0);
    out->root = 0;
    return 0;
}

void inst_wide_refit(const bvh_box_tree *h, inst_wide *w)
{
    for (uint32_t i = 0; i < w->node_count; i++) {
        inst_wnode *n = &w->nodes[i];
        for (int c = 0; c < INST_WIDE; c++)
            if (n->src[c] != INST_WIDE_NONE) set_slot(n, c, &h->nodes[n->src[c]], n->src[c]);
    }
}

void inst_wide_free(inst_wide *w)
{
    free(w->nodes);
    memset(w, 0, sizeof *w);
    w->root = INST_WIDE_NONE;
}
