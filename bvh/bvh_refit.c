/*
 * bvh_refit.c - the `bvh` kind from one animation frame to the next
 * (accel_kind.update): the tree's topology is kept, the primitives it
 * copied at build are copied again from the new scene, and every box is
 * recomputed bottom-up (refitting; Wald, Boulos and Shirley, "Ray Tracing
 * Deformable Scenes Using Dynamic Bounding Volume Hierarchies", ACM TOG
 * 26(1), 2007).
 *
 * What the tree copies at build, and so what a refit copies again:
 *   - binary tree (width=2): the 9-float slots in leaf order (prim_data),
 *     each from the scene id prim_ids[slot] names;
 *   - wide tree (width=4|8; the binary pools are freed after the collapse):
 *     the SoA leaf blocks, each lane from the scene id the lane holds
 *     (wide/refit.c).
 * The boxes are then what the build computes: a leaf's box is the union of
 * bvh_prim_box of its primitives (the references' boxes of build_driver.c's
 * make_refs, grown as split_common.h explains), an interior box the union of its
 * children's. A spatial-split tree (build=sbvh) clipped its references to
 * split planes; refit boxes hold whole primitives, so they are larger
 * (still conservative, the tree only gets slower).
 *
 * Nodes come before their children (build_driver.c's compact_nodes; the wide
 * tree likewise), so one backward pass over the node pool sees every child
 * before its parent. The kind's path (bvh_node.h) picks the binary refit
 * here or the wide one.
 *
 * The new scene must hold the same primitive counts; a scene whose set of
 * traced primitives changed (a triangle that became degenerate or stopped
 * being degenerate, a non-finite coordinate) cannot be refit with the same
 * topology and is rebuilt by the caller (bvh.c).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "split_common.h"
#include "bvh.h"

/* Marks the scene ids a tree holds (mark[id] = 1); 0 when one is not an id
 * of a scene of `total` primitives (a tree loaded from a file does not know
 * its scene's sphere count). */
int bvh_mark_ids_binary(const bvh *b, uint8_t *mark, size_t total)
{
    for (uint32_t i = 0; i < b->prim_count; i++) {
        if (b->prim_ids[i] >= total) return 0;
        mark[b->prim_ids[i]] = 1;
    }
    return 1;
}

int bvh_refit_compatible(const bvh *b, const accel_scene *s, accel_error *err)
{
    if (s->tri_count != b->tri_count || (s->sphere_count > 0) != b->has_spheres ||
        (b->scene_prims && s->tri_count + s->sphere_count != b->scene_prims))
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "bvh: update from %u triangles and %u spheres to %u and %u (refit keeps the "
                          "topology: same primitive counts and ids)",
                          b->tri_count, b->scene_prims ? b->scene_prims - b->tri_count : 0, s->tri_count,
                          s->sphere_count);
    size_t total = (size_t)s->tri_count + s->sphere_count;
    uint8_t *mark = calloc(total ? total : 1, 1);
    if (!mark) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory");
    if (!b->path->mark_ids(b, mark, total)) {
        free(mark);
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "bvh: the tree holds primitive ids beyond the new scene's %zu (refit keeps "
                          "the topology: same primitive counts and ids)",
                          total);
    }
    int same = 1;
    for (uint32_t i = 0; same && i < s->live_count; i++) {
        uint32_t id = s->live[i];
        if (!bvh_prim_finite(s, id)) continue; /* left out by the build as well */
        if (mark[id] != 1) same = 0;       /* not in the tree */
        mark[id] = 2;
    }
    for (size_t i = 0; same && i < total; i++)
        if (mark[i] == 1) same = 0; /* in the tree, no longer live and finite */
    free(mark);
    return same ? 0 : -1;
}

/* ---- binary tree ------------------------------------------------------------ */

typedef struct {
    bvh *b;
    const accel_scene *s;
} copy_job;

static void copy_slots(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    copy_job *j = p;
    for (size_t i = begin; i < end; i++)
        bvh_prim_slot(j->s, j->b->prim_ids[i], j->b->prim_data + BVH_SLOT_FLOATS * i);
}

int bvh_refit_binary(bvh *b, const accel_scene *s, int threads, int boxes, accel_error *err)
{
    (void)err; /* the binary refit needs no memory: it cannot fail */
    copy_job job = {b, s};
    accel_parallel_for(b->prim_count, 16384, threads, copy_slots, &job);
    if (!boxes) return 0;
    float delta = bvh_box_delta(s);
    for (uint32_t i = b->node_count; i-- > 0;) {
        if (i == 1) continue; /* padding */
        bvh_node *n = &b->nodes[i];
        box3 box = box3_empty();
        if (n->count) {
            for (uint32_t k = 0; k < n->count; k++)
                box = box3_union(box, bvh_prim_box(s, b->prim_ids[n->left_first + k], delta));
        } else {
            box = box3_union(bvh_node_box(&b->nodes[n->left_first]),
                             bvh_node_box(&b->nodes[n->left_first + 1]));
        }
        bvh_node_set_box(n, box);
    }
    return 0;
}

int bvh_refit_run(bvh *b, const accel_scene *s, int threads, int boxes, accel_error *err)
{
    if (threads < 1) threads = 1;
    return b->path->refit(b, s, threads, boxes, err);
}
