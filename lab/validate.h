/*
 * validate.h - the tree check the starter's build runs after your
 * build_node() (LAB.md, step 1): a BVH is right when
 *   - every child index lies inside the node pool and every node is reached
 *     once (a tree, no cycles), at most LAB_TREE_MAX_DEPTH levels deep;
 *   - no reachable leaf is empty;
 *   - every primitive lies in exactly one reachable leaf;
 *   - every node's box holds its primitives' boxes (a leaf) and its
 *     children's boxes (an interior node).
 * A broken tree fails the build with "node 17: ...", so that a wrong box or
 * a lost primitive is reported where it is made, not as a hole (or a crash)
 * in a later step. Nothing to change here.
 */
#ifndef LAB_VALIDATE_H
#define LAB_VALIDATE_H

#include <stdlib.h>
#include <string.h>

#include "core/prim.h"

/* The lecture's node as the validator reads it (the starter's lab_node). */
typedef struct {
    float bmin[3];
    uint32_t left_first;
    float bmax[3];
    uint32_t count;
} lab_tree_node;

#define LAB_TREE_MAX_DEPTH 64

/* 1 when box [lo, hi] holds box [in_lo, in_hi] (NaN anywhere: no). */
static inline int lab_box_holds(const float *lo, const float *hi, const float *in_lo,
                                const float *in_hi)
{
    for (int a = 0; a < 3; a++)
        if (!(lo[a] <= in_lo[a]) || !(in_hi[a] <= hi[a])) return 0;
    return 1;
}

static inline int lab_box_fail(accel_error *err, uint32_t idx, const char *what, uint32_t id,
                               const lab_tree_node *nd, const float *lo, const float *hi)
{
    return accel_fail(err, ACCEL_ERR_INTERNAL,
                      "node %u: its box (%g %g %g)-(%g %g %g) does not hold %s %u's box "
                      "(%g %g %g)-(%g %g %g): a node's box is the union of its primitives' "
                      "full boxes (accel_prim_bounds), not of their centroids or of one of "
                      "them%s",
                      idx, nd->bmin[0], nd->bmin[1], nd->bmin[2], nd->bmax[0], nd->bmax[1],
                      nd->bmax[2], what, id, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
                      nd->count ? "; and a leaf's left_first is `first`, the start of the "
                                  "range its box was made from" : "");
}

/* Checks one leaf: its range, its primitives (each seen once), their boxes. */
static inline int lab_check_leaf(const lab_tree_node *nd, uint32_t idx, const uint32_t *order,
                                 const accel_scene *prims, uint8_t *seen, accel_error *err)
{
    uint32_t n = prims->prim_count;
    if (nd->count == 0)
        return accel_fail(err, ACCEL_ERR_INTERNAL,
                          "node %u: a reachable leaf with no primitives (count 0 makes it a "
                          "leaf only when it has primitives; an interior node has count 0 "
                          "and two children): never make an empty child, split count "
                          "primitives into two non-empty halves",
                          idx);
    if (nd->left_first > n || nd->count > n - nd->left_first)
        return accel_fail(err, ACCEL_ERR_INTERNAL,
                          "node %u: a leaf of %u primitives from order[%u]: past the end of "
                          "order[] (%u primitives): a leaf's left_first is `first`, the start "
                          "of its own range",
                          idx, nd->count, nd->left_first, n);
    for (uint32_t i = 0; i < nd->count; i++) {
        uint32_t prim = order[nd->left_first + i];
        if (prim >= n)
            return accel_fail(err, ACCEL_ERR_INTERNAL, "node %u: order[%u] = %u is not a "
                              "primitive (there are %u)", idx, nd->left_first + i, prim, n);
        if (seen[prim])
            return accel_fail(err, ACCEL_ERR_INTERNAL,
                              "node %u: primitive %u (order[%u]) is in a second leaf: every "
                              "primitive belongs to exactly one leaf (is a leaf's left_first "
                              "the start `first` of its own range?)",
                              idx, prim, nd->left_first + i);
        seen[prim] = 1;
        box3 pb = accel_prim_bounds(prims, prim);
        const float lo[3] = {pb.min.x, pb.min.y, pb.min.z}, hi[3] = {pb.max.x, pb.max.y, pb.max.z};
        if (!lab_box_holds(nd->bmin, nd->bmax, lo, hi))
            return lab_box_fail(err, idx, "primitive", prim, nd, lo, hi);
    }
    return ACCEL_OK;
}

/* 1 when the node's box holds the boxes of order[first, first + count). */
static inline int lab_box_holds_range(const lab_tree_node *nd, const uint32_t *order,
                                      uint32_t first, uint32_t count, const accel_scene *prims)
{
    uint32_t n = prims->prim_count;
    if (count == 0 || first > n || count > n - first) return 0;
    for (uint32_t i = 0; i < count; i++) {
        if (order[first + i] >= n) return 0;
        box3 pb = accel_prim_bounds(prims, order[first + i]);
        const float lo[3] = {pb.min.x, pb.min.y, pb.min.z}, hi[3] = {pb.max.x, pb.max.y, pb.max.z};
        if (!lab_box_holds(nd->bmin, nd->bmax, lo, hi)) return 0;
    }
    return 1;
}

/* After a failed check: is some leaf's left_first and count the other way
 * round (its box holds order[count, count + left_first), not its own
 * range)? Then that, not a box, is the mistake to report. */
static inline int lab_swapped_leaf(const lab_tree_node *nodes, uint32_t node_count,
                                   const uint32_t *order, const accel_scene *prims,
                                   accel_error *err)
{
    for (uint32_t i = 0; i < node_count; i++) {
        const lab_tree_node *nd = &nodes[i];
        if (nd->count == 0 || nd->left_first == 0 ||
            lab_box_holds_range(nd, order, nd->left_first, nd->count, prims) ||
            !lab_box_holds_range(nd, order, nd->count, nd->left_first, prims))
            continue;
        return accel_fail(err, ACCEL_ERR_INTERNAL,
                          "node %u: a leaf with left_first %u and count %u, whose box holds "
                          "order[%u, %u), the range read the other way round: left_first and "
                          "count swapped? (a leaf's left_first = first, count = count)",
                          i, nd->left_first, nd->count, nd->count, nd->count + nd->left_first);
    }
    return ACCEL_OK;
}

/* Checks the tree of node_count nodes (root 0) over prims->prim_count
 * primitives listed in order[]; 0 or ACCEL_ERR_INTERNAL with the message. */
static inline int lab_validate_tree(const lab_tree_node *nodes, uint32_t node_count,
                                    const uint32_t *order, const accel_scene *prims,
                                    accel_error *err)
{
    uint32_t n = prims->prim_count;
    if (n == 0) return ACCEL_OK;
    if (node_count == 0 || node_count > 2 * n)
        return accel_fail(err, ACCEL_ERR_INTERNAL, "the tree has %u nodes for %u primitives "
                          "(a binary tree has at most 2N-1)", node_count, n);
    uint8_t *seen = calloc((size_t)n + node_count, 1), *reached = seen ? seen + n : NULL;
    if (!seen) return accel_fail(err, ACCEL_ERR_NOMEM, "lab: out of memory for the tree check");
    uint32_t stack[2 * LAB_TREE_MAX_DEPTH + 2], level[2 * LAB_TREE_MAX_DEPTH + 2];
    int sp = 0, rc = ACCEL_OK;
    stack[sp] = 0, level[sp++] = 1;
    while (sp > 0 && rc == ACCEL_OK) {
        uint32_t idx = stack[--sp], lv = level[sp];
        const lab_tree_node *nd = &nodes[idx];
        if (reached[idx]++) {
            rc = accel_fail(err, ACCEL_ERR_INTERNAL, "node %u: reached twice: two interior "
                            "nodes share a child pair (take two new nodes per split)", idx);
        } else if (idx == 0 && nd->count == 0 && nd->left_first == 0) {
            rc = accel_fail(err, ACCEL_ERR_INTERNAL, "node 0 (the root): neither a leaf "
                            "(count > 0) nor split (left_first > 0): is build_node() written "
                            "(step 1)?");
        } else if (nd->count > 0) {
            rc = lab_check_leaf(nd, idx, order, prims, seen, err);
        } else if (!(nd->bmin[0] <= nd->bmax[0])) {
            rc = accel_fail(err, ACCEL_ERR_INTERNAL,
                            "node %u: count 0 and an empty box: an empty leaf? (count 0 marks "
                            "an interior node, so a leaf needs primitives: never make a child "
                            "of no primitives, split count primitives into two non-empty "
                            "halves)", idx);
        } else if (nd->left_first == 0 || nd->left_first >= node_count - 1) {
            rc = accel_fail(err, ACCEL_ERR_INTERNAL,
                            "node %u: an interior node (count 0) whose children %u and %u are "
                            "not nodes 1..%u of the pool (b->node_count): a leaf needs count > 0; "
                            "an interior node's left_first is the first of its two new nodes",
                            idx, nd->left_first, nd->left_first + 1, node_count - 1);
        } else if (lv >= LAB_TREE_MAX_DEPTH) {
            rc = accel_fail(err, ACCEL_ERR_INTERNAL, "node %u: deeper than %d levels (the "
                            "traversal stack's size): a median split halves the primitives "
                            "at every level", idx, LAB_TREE_MAX_DEPTH);
        } else {
            for (uint32_t c = nd->left_first; c < nd->left_first + 2 && rc == ACCEL_OK; c++)
                if (!lab_box_holds(nd->bmin, nd->bmax, nodes[c].bmin, nodes[c].bmax))
                    rc = lab_box_fail(err, idx, "child node", c, nd, nodes[c].bmin,
                                      nodes[c].bmax);
            stack[sp] = nd->left_first + 1, level[sp++] = lv + 1;
            stack[sp] = nd->left_first, level[sp++] = lv + 1;
        }
    }
    for (uint32_t p = 0; p < n && rc == ACCEL_OK; p++)
        if (!seen[p])
            rc = accel_fail(err, ACCEL_ERR_INTERNAL,
                            "primitive %u is in no leaf: the leaves' ranges order[left_first, "
                            "left_first + count) must cover order[] exactly once", p);
    free(seen);
    if (rc == ACCEL_ERR_INTERNAL && err) {
        accel_error swapped = {0};
        if (lab_swapped_leaf(nodes, node_count, order, prims, &swapped)) *err = swapped;
    }
    return rc;
}

#endif
