/*
 * inst_struct.c - the two structures over boxes that both levels of the
 * `instanced` kind use: a BVH, the bvh backend's binned SAH tree over boxes
 * (bvh/bvh.h's bvh_build_boxes: the lecture's 32-byte nodes); and a uniform
 * grid of about lambda * n cells (Cleary and Wyvill 1988's rule) whose
 * cells list every box, grown by a pad, that reaches them: grid_core.h's
 * frame and cell storage over boxes. Both are deterministic: the same
 * boxes give the same bytes.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "inst_impl.h"

/* ---- BVH ------------------------------------------------------------------------- */

static_assert(sizeof(box3) == 6 * sizeof(float), "box3 is bvh_build_boxes' 6 floats");

/* A box bvh_build_boxes takes: finite, lo <= hi on every axis. The only
 * others here are empty boxes (an instance of a mesh without triangles, a
 * scene without primitives; NaN once grown by box3_hit_pad), which hold
 * nothing a ray can hit: the tree leaves them out. */
static int box_usable(const box3 *b)
{
    const float *lo = &b->min.x, *hi = &b->max.x;
    for (int a = 0; a < 3; a++)
        if (!(isfinite(lo[a]) && isfinite(hi[a]) && lo[a] <= hi[a])) return 0;
    return 1;
}

int inst_bvh_build(const box3 *boxes, uint32_t n, int max_leaf, int threads, const uint32_t *ids,
                   bvh_box_tree *out, accel_error *err)
{
    uint32_t used = 0;
    for (uint32_t i = 0; i < n; i++) used += (uint32_t)box_usable(&boxes[i]);
    const box3 *given = boxes;
    box3 *kept_box = NULL;
    uint32_t *kept = NULL; /* box index of each kept box */
    if (used < n) {
        kept_box = malloc((used ? used : 1) * sizeof *kept_box);
        kept = malloc((used ? used : 1) * sizeof *kept);
        if (!kept_box || !kept) {
            free(kept_box), free(kept);
            memset(out, 0, sizeof *out);
            return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory for a BVH of %u boxes", n);
        }
        for (uint32_t i = 0, k = 0; i < n; i++)
            if (box_usable(&boxes[i])) kept_box[k] = boxes[i], kept[k++] = i;
        given = kept_box;
    }
    int rc = bvh_build_boxes(&given->min.x, used, max_leaf, threads, out, err);
    free(kept_box);
    /* The leaf order names kept boxes: make it box indices, then ids. */
    for (uint32_t i = 0; rc == 0 && i < out->count; i++) {
        uint32_t box = kept ? kept[out->order[i]] : out->order[i];
        out->order[i] = ids ? ids[box] : box;
    }
    free(kept);
    return rc;
}

/* ---- grid ---------------------------------------------------------------------------
 * grid_core.h's grid over boxes: the resolution rule, the frame and the
 * cell lists are the regular grid's, capped for a structure rebuilt every
 * frame. */

#define INST_GRID_MAX_RES 512
#define INST_GRID_MAX_CELLS (1u << 24)

/* b grown by pad on every side, rounded outwards to float. */
static box3 grow_box(box3 b, double pad)
{
    float *lo = &b.min.x, *hi = &b.max.x;
    for (int a = 0; a < 3; a++) {
        double l = lo[a] - pad, h = hi[a] + pad;
        lo[a] = (float)l;
        hi[a] = (float)h;
        if (lo[a] > l) lo[a] = nextafterf(lo[a], -INFINITY);
        if (hi[a] < h) hi[a] = nextafterf(hi[a], INFINITY);
    }
    return b;
}

int inst_grid_build(const box3 *boxes, uint32_t n, double lambda, double pad, inst_grid *g,
                    accel_error *err)
{
    memset(g, 0, sizeof *g);
    box3 *grown = malloc((n ? n : 1) * sizeof *grown);
    if (!grown) return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory for a grid");
    box3 bounds = box3_empty();
    for (uint32_t i = 0; i < n; i++) {
        grown[i] = box3_is_empty(boxes[i]) ? boxes[i] : grow_box(boxes[i], pad);
        if (!box3_is_empty(grown[i])) bounds = box3_union(bounds, grown[i]);
    }
    /* The grid box: the grown boxes with one more pad of margin. */
    bounds = box3_is_empty(bounds) ? (box3){{-1.0f, -1.0f, -1.0f}, {1.0f, 1.0f, 1.0f}}
                                   : grow_box(bounds, pad);
    int res[3];
    grid_resolution(bounds, n ? n : 1, lambda, res);
    uint64_t cells = 1;
    for (int a = 0; a < 3; a++) {
        res[a] = res[a] > INST_GRID_MAX_RES ? INST_GRID_MAX_RES : res[a];
        cells *= (uint64_t)res[a];
    }
    while (cells > INST_GRID_MAX_CELLS) {
        cells = 1;
        for (int a = 0; a < 3; a++) {
            res[a] = res[a] > 1 ? (res[a] + 1) / 2 : 1;
            cells *= (uint64_t)res[a];
        }
    }
    g->planes = malloc(grid_plane_count(res) * sizeof *g->planes);
    if (!g->planes) {
        free(grown);
        return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory for a grid");
    }
    grid_frame_init(&g->frame, grid_frame_box(bounds), res, g->planes);
    int rc = grid_cells_build_boxes(&g->frame, grown, n, &g->cells, err);
    free(grown);
    if (rc) inst_grid_free(g);
    return rc;
}

void inst_grid_free(inst_grid *g)
{
    free(g->planes);
    grid_cells_free(&g->cells);
    memset(g, 0, sizeof *g);
}
