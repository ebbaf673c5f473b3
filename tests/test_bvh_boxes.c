/*
 * test_bvh_boxes.c - the public builder over boxes (bvh.h's
 * bvh_build_boxes, for a two-level kind's top level) against a brute-force
 * check of its tree: every box index in exactly one leaf, every leaf's box
 * holding its boxes, every node's box holding its children's, leaves of at
 * most max_leaf boxes; and the same tree for 1 and 2 threads.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "test_bvh.h"

static int box_holds(const float *lo, const float *hi, const float *box)
{
    for (int a = 0; a < 3; a++)
        if (!(lo[a] <= box[a] && box[3 + a] <= hi[a])) return 0;
    return 1;
}

/* Brute force: walks every node from the root and checks the contract. */
static void check_box_tree(const float *boxes, uint32_t n, int max_leaf, const bvh_box_tree *t)
{
    CHECKF(t->count == n, "%u indices for %u boxes", t->count, n);
    if (n == 0) {
        CHECK(t->node_count == 0);
        return;
    }
    uint32_t *seen = calloc(n, sizeof *seen);
    uint32_t *stack = malloc(sizeof *stack * (t->node_count + 1));
    if (!seen || !stack) {
        free(seen);
        free(stack);
        test_fail(__FILE__, __LINE__, "out of memory");
        return;
    }
    uint32_t visited = 0, sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node *nd = &t->nodes[stack[--sp]];
        visited++;
        if (nd->count) {
            CHECKF((int)nd->count <= max_leaf, "a leaf of %u boxes (max_leaf %d)", nd->count, max_leaf);
            CHECKF(nd->left_first + nd->count <= n, "leaf slots %u+%u of %u", nd->left_first, nd->count, n);
            for (uint32_t k = 0; k < nd->count && nd->left_first + k < n; k++) {
                uint32_t box = t->order[nd->left_first + k];
                CHECKF(box < n, "box index %u of %u", box, n);
                if (box >= n) continue;
                seen[box]++;
                CHECKF(box_holds(nd->bmin, nd->bmax, boxes + 6 * (size_t)box),
                       "leaf box does not hold box %u", box);
            }
            continue;
        }
        uint32_t l = nd->left_first;
        CHECKF(l >= 2 && l + 1 < t->node_count && l % 2 == 0, "children %u of %u nodes", l, t->node_count);
        if (!(l >= 2 && l + 1 < t->node_count)) continue;
        for (uint32_t c = l; c <= l + 1; c++) {
            float cb[6] = {t->nodes[c].bmin[0], t->nodes[c].bmin[1], t->nodes[c].bmin[2],
                           t->nodes[c].bmax[0], t->nodes[c].bmax[1], t->nodes[c].bmax[2]};
            CHECKF(box_holds(nd->bmin, nd->bmax, cb), "node box does not hold child %u", c);
            stack[sp++] = c;
        }
    }
    for (uint32_t i = 0; i < n; i++) CHECKF(seen[i] == 1, "box %u in %u leaves", i, seen[i]);
    CHECKF(visited + 1 == t->node_count || (t->node_count == 1 && visited == 1),
           "%u nodes reached of %u (node 1 is padding)", visited, t->node_count);
    free(seen);
    free(stack);
}

/* n random boxes: scattered, some degenerate (points), some duplicates. */
static float *random_boxes(uint32_t n)
{
    float *b = malloc(6 * sizeof(float) * (n ? n : 1));
    if (!b) return NULL;
    for (uint32_t i = 0; i < n; i++) {
        float *x = b + 6 * (size_t)i;
        if (i > 0 && i % 7 == 0) {
            memcpy(x, x - 6, 6 * sizeof(float)); /* a duplicate */
            continue;
        }
        for (int a = 0; a < 3; a++) {
            float lo = test_rand_in(-100.0f, 100.0f);
            float ext = i % 5 == 0 ? 0.0f : test_rand_in(0.0f, 10.0f);
            x[a] = lo, x[3 + a] = lo + ext;
        }
    }
    return b;
}

TEST(bvh_boxes_every_box_in_one_leaf)
{
    static const uint32_t sizes[] = {0, 1, 2, 3, 8, 9, 100, 5000};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        uint32_t n = sizes[s];
        float *boxes = random_boxes(n);
        CHECK(boxes != NULL);
        if (!boxes) return;
        for (int max_leaf = 1; max_leaf <= 8; max_leaf *= 2) {
            bvh_box_tree one, two;
            accel_error err = {0};
            CHECKF(bvh_build_boxes(boxes, n, max_leaf, 1, &one, &err) == 0, "n %u: %s", n, err.msg);
            CHECKF(bvh_build_boxes(boxes, n, max_leaf, 2, &two, &err) == 0, "n %u: %s", n, err.msg);
            check_box_tree(boxes, n, max_leaf, &one);
            /* memcmp only with blocks to compare: an empty tree's may be NULL */
            CHECKF(one.node_count == two.node_count &&
                       (!one.node_count || !memcmp(one.nodes, two.nodes, one.node_count * sizeof(bvh_node))) &&
                       (!n || !memcmp(one.order, two.order, n * sizeof(uint32_t))),
                   "n %u, max_leaf %d: 1 and 2 threads build different trees", n, max_leaf);
            bvh_box_tree_free(&one);
            bvh_box_tree_free(&two);
        }
        free(boxes);
    }
}

TEST(bvh_boxes_refuses_bad_boxes)
{
    float boxes[12] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 1, 3, 3}; /* the second is inverted on x */
    bvh_box_tree t;
    accel_error err = {0};
    CHECK(bvh_build_boxes(boxes, 2, 4, 1, &t, &err) == ACCEL_ERR_SPEC);
    boxes[6] = NAN;
    CHECK(bvh_build_boxes(boxes, 2, 4, 1, &t, &err) == ACCEL_ERR_SPEC);
    CHECK(bvh_build_boxes(boxes, 1, 0, 1, &t, &err) == ACCEL_ERR_SPEC); /* max_leaf < 1 */
}
