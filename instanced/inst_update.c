/*
 * inst_update.c - the `instanced` kind from one animation frame to the next
 * (accel_kind.update): a mesh whose vertices moved has its bottom level
 * refit (boxes recomputed bottom-up, the tree kept: Wald, Boulos and
 * Shirley, "Ray Tracing Deformable Scenes Using Dynamic Bounding Volume
 * Hierarchies", ACM TOG 26(1), 2007) or rebuilt; meshes that did not change
 * keep theirs untouched; moved instances only need the per-instance data
 * and the top level, which are rebuilt every frame (they are small: one
 * entry per instance), and (world=blocks) their world blocks made again.
 *
 * A refit tree stays exact (its boxes bound the new triangles), but its
 * splits were chosen for the old shape: the study measures how much slower
 * it traces after k frames than a fresh build.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "inst_impl.h"

/* Children come after their parent in the node pool (bvh_build_boxes
 * numbers them depth first), so one backward pass sees every child before
 * its parent. Node 1 is padding, referenced by nothing: it stays empty. */
static void refit_bvh(inst_bottom *b)
{
    bvh_box_tree *h = &b->bvh;
    const accel_scene *m = b->mesh;
    for (uint32_t i = h->node_count; i-- > 0;) {
        if (i == 1) continue;
        bvh_node *n = &h->nodes[i];
        box3 bb = box3_empty();
        if (n->count) {
            for (uint32_t k = 0; k < n->count; k++) {
                const float *t = m->tris + 9 * (size_t)h->order[n->left_first + k];
                for (int c = 0; c < 3; c++) bb = box3_grow(bb, v3_load(t + 3 * c));
            }
        } else {
            for (int c = 0; c < 2; c++) {
                const bvh_node *ch = &h->nodes[n->left_first + c];
                bb = box3_grow(bb, v3(ch->bmin[0], ch->bmin[1], ch->bmin[2]));
                bb = box3_grow(bb, v3(ch->bmax[0], ch->bmax[1], ch->bmax[2]));
            }
        }
        n->bmin[0] = bb.min.x, n->bmin[1] = bb.min.y, n->bmin[2] = bb.min.z;
        n->bmax[0] = bb.max.x, n->bmax[1] = bb.max.y, n->bmax[2] = bb.max.z;
    }
    /* The tree holds every triangle of the mesh: its root box is the mesh's. */
    b->box = box3_empty();
    if (h->node_count) {
        b->box.min = v3(h->nodes[0].bmin[0], h->nodes[0].bmin[1], h->nodes[0].bmin[2]);
        b->box.max = v3(h->nodes[0].bmax[0], h->nodes[0].bmax[1], h->nodes[0].bmax[2]);
    }
    const float *lo = &b->box.min.x, *hi = &b->box.max.x;
    b->abs_max = 0.0;
    for (int k = 0; k < 3; k++) {
        b->box_lo[k] = lo[k], b->box_hi[k] = hi[k];
        if (h->node_count) b->abs_max = fmax(b->abs_max, fmax(fabs(lo[k]), fabs(hi[k])));
    }
    /* Then every box grown as the build grows them (core/geom.h): the pad
     * is monotone, so growing each union is growing the leaves. */
    float delta = box3_hit_delta((float)b->abs_max);
    for (uint32_t i = 0; i < h->node_count; i++) {
        if (i == 1) continue;
        bvh_node *n = &h->nodes[i];
        box3 g = box3_hit_pad((box3){{n->bmin[0], n->bmin[1], n->bmin[2]}, {n->bmax[0], n->bmax[1], n->bmax[2]}},
                              delta);
        n->bmin[0] = g.min.x, n->bmin[1] = g.min.y, n->bmin[2] = g.min.z;
        n->bmax[0] = g.max.x, n->bmax[1] = g.max.y, n->bmax[2] = g.max.z;
    }
}

int inst_update(void *acc, const accel_scene *scene, int refit, accel_update_stats *st,
                accel_error *err)
{
    inst_accel *a = acc;
    memset(st, 0, sizeof *st);
    const accel_instances *set = scene->instances, *old = a->scene->instances;
    if (!set || !old)
        return accel_fail(err, ACCEL_ERR_SPEC, "instanced: update needs scenes of instances");
    if (set->mesh_count != a->bottom_count || set->instance_count != a->item_count)
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "instanced: update from %u meshes and %u instances to %u and %u",
                          a->bottom_count, a->item_count, set->mesh_count, set->instance_count);
    for (uint32_t i = 0; i < set->mesh_count; i++)
        if (set->meshes[i].tri_count != old->meshes[i].tri_count)
            return accel_fail(err, ACCEL_ERR_SPEC,
                              "instanced: mesh %u changed from %u to %u triangles (update keeps "
                              "the topology)",
                              i, old->meshes[i].tri_count, set->meshes[i].tri_count);
    double t0 = accel_now_ms();
    uint8_t *changed = calloc(a->bottom_count ? a->bottom_count : 1, 1);
    double *grid_pad = calloc(a->bottom_count ? a->bottom_count : 1, sizeof *grid_pad);
    if (!changed || !grid_pad) {
        free(changed), free(grid_pad);
        return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
    }
    for (uint32_t i = 0; i < a->bottom_count; i++)
        changed[i] = memcmp(set->meshes[i].tris, old->meshes[i].tris,
                            9 * sizeof(float) * (size_t)set->meshes[i].tri_count) != 0;
    /* Instances that moved (or changed mesh) need their world blocks again. */
    uint8_t *moved = calloc(a->item_count ? a->item_count : 1, 1);
    if (!moved) {
        free(changed), free(grid_pad);
        return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
    }
    for (uint32_t k = 0; k < a->item_count; k++)
        moved[k] = memcmp(a->items[k].xform, set->instances[k].xform, sizeof a->items[k].xform) != 0 ||
                   a->items[k].bottom != set->instances[k].mesh ||
                   a->items[k].base != set->instances[k].base;
    int rc = inst_set_items(a, scene, grid_pad, err);
    double t1 = accel_now_ms();
    for (uint32_t i = 0; rc == 0 && i < a->bottom_count; i++) {
        inst_bottom *b = &a->bottoms[i];
        if (a->bottom_kind == INST_WALK) {
            /* A walked kind has no refit here: a changed mesh is rebuilt
             * (its walk takes the pad per ray, so unchanged ones stay). */
            if (!changed[i]) continue;
        } else if (a->bottom_kind == INST_BVH) {
            if (!changed[i]) continue;
            if (refit) {
                refit_bvh(b);
                if (a->width == INST_WIDE) rc = inst_wide_refit(&b->bvh, b->mesh, &b->wide, err);
                st->meshes_refit++;
                continue;
            }
        } else if (!changed[i] && grid_pad[i] + 0x1p-24 * b->abs_max <= b->grid_pad) {
            /* A grid cannot be refit; an unchanged one is kept while the
             * pads its instances need still fit the ones it was built with. */
            continue;
        }
        rc = inst_build_bottom(a, i, grid_pad[i], err);
        st->meshes_rebuilt++;
    }
    /* World blocks (world=blocks): the flattened triangles of every
     * instance that moved or whose mesh changed, in its (new) leaf order. */
    for (uint32_t k = 0; rc == 0 && k < a->item_count; k++)
        if (moved[k] || changed[a->items[k].bottom]) rc = inst_world_blocks(a, k, err);
    double t2 = accel_now_ms();
    if (rc == 0) rc = inst_build_top(a, err);
    double t3 = accel_now_ms();
    st->bottom_ms = t2 - t1;
    st->top_ms = (t1 - t0) + (t3 - t2);
    free(changed);
    free(grid_pad);
    free(moved);
    return rc;
}
