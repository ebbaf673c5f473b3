/*
 * inst_struct.c - the two structures over boxes that both levels of the
 * `instanced` kind use: a BVH built by binned SAH (Wald, "On fast
 * Construction of SAH-based Bounding Volume Hierarchies", IRT 2007; 16 bins
 * on each axis, an object median when binning cannot separate the
 * centroids), flattened into 32-byte nodes as in pbrt-v3; and a uniform
 * grid of about lambda * n cells (Cleary and Wyvill 1988's rule) whose
 * cells list every box, grown by a pad, that reaches them: grid_core.h's
 * frame and cell storage over boxes. Both are deterministic: the same
 * boxes give the same bytes.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "inst_impl.h"

#define INST_BINS 16
#define INST_MAX_DEPTH 48 /* then object medians only: at most 32 more levels */

/* ---- BVH ------------------------------------------------------------------------- */

typedef struct {
    const box3 *boxes;
    float *cent;      /* 3 per item */
    uint32_t *items;
    inst_node *nodes;
    uint32_t node_count;
    int max_leaf;
    int depth;
    int sort_axis;    /* for the median fallback's comparator */
} bvh_builder;

static _Thread_local const bvh_builder *sort_ctx; /* qsort has no context argument */

static int by_centroid(const void *pa, const void *pb)
{
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    float ca = sort_ctx->cent[3 * a + sort_ctx->sort_axis];
    float cb = sort_ctx->cent[3 * b + sort_ctx->sort_axis];
    if (ca != cb) return ca < cb ? -1 : 1;
    return a < b ? -1 : a > b;
}

static void set_box(inst_node *n, box3 b)
{
    n->lo[0] = b.min.x, n->lo[1] = b.min.y, n->lo[2] = b.min.z;
    n->hi[0] = b.max.x, n->hi[1] = b.max.y, n->hi[2] = b.max.z;
}

/* Where to split items[begin, end): returns the first item of the right
 * half, or `begin` for no split (all centroids alike). */
static uint32_t split_binned(bvh_builder *b, uint32_t begin, uint32_t end, box3 cb)
{
    float lo[3] = {cb.min.x, cb.min.y, cb.min.z}, ext[3] = {cb.max.x - cb.min.x,
                                                             cb.max.y - cb.min.y,
                                                             cb.max.z - cb.min.z};
    float best = INFINITY;
    int best_axis = -1, best_bin = 0;
    for (int axis = 0; axis < 3; axis++) {
        if (!(ext[axis] > 0.0f)) continue;
        box3 bin_box[INST_BINS];
        uint32_t bin_n[INST_BINS] = {0};
        for (int i = 0; i < INST_BINS; i++) bin_box[i] = box3_empty();
        float k = INST_BINS / ext[axis];
        for (uint32_t i = begin; i < end; i++) {
            uint32_t it = b->items[i];
            int bin = (int)((b->cent[3 * it + axis] - lo[axis]) * k);
            bin = bin < 0 ? 0 : bin >= INST_BINS ? INST_BINS - 1 : bin;
            bin_n[bin]++;
            bin_box[bin] = box3_union(bin_box[bin], b->boxes[it]);
        }
        /* SAH: area(left) * n(left) + area(right) * n(right), by sweeps. */
        float right_cost[INST_BINS];
        box3 acc = box3_empty();
        uint32_t n = 0;
        for (int i = INST_BINS - 1; i > 0; i--) {
            acc = box3_union(acc, bin_box[i]);
            n += bin_n[i];
            right_cost[i] = box3_half_area(acc) * (float)n;
        }
        acc = box3_empty();
        n = 0;
        for (int i = 0; i < INST_BINS - 1; i++) {
            acc = box3_union(acc, bin_box[i]);
            n += bin_n[i];
            if (n == 0 || n == end - begin) continue;
            float cost = box3_half_area(acc) * (float)n + right_cost[i + 1];
            if (cost < best) best = cost, best_axis = axis, best_bin = i + 1;
        }
    }
    if (best_axis < 0) return begin;
    float k = INST_BINS / ext[best_axis];
    uint32_t i = begin, j = end;
    while (i < j) {
        uint32_t it = b->items[i];
        int bin = (int)((b->cent[3 * it + best_axis] - lo[best_axis]) * k);
        bin = bin < 0 ? 0 : bin >= INST_BINS ? INST_BINS - 1 : bin;
        if (bin < best_bin) {
            i++;
        } else {
            b->items[i] = b->items[--j];
            b->items[j] = it;
        }
    }
    return (i == begin || i == end) ? begin : i;
}

static void build_node(bvh_builder *b, uint32_t node, uint32_t begin, uint32_t end, int depth)
{
    box3 bb = box3_empty(), cb = box3_empty();
    for (uint32_t i = begin; i < end; i++) {
        uint32_t it = b->items[i];
        bb = box3_union(bb, b->boxes[it]);
        cb = box3_grow(cb, v3_load(b->cent + 3 * it));
    }
    inst_node *n = &b->nodes[node];
    set_box(n, bb);
    if (depth > b->depth) b->depth = depth;
    if (end - begin <= (uint32_t)b->max_leaf) {
        n->index = begin;
        n->count = end - begin;
        return;
    }
    uint32_t mid = depth < INST_MAX_DEPTH ? split_binned(b, begin, end, cb) : begin;
    if (mid == begin) {
        /* Object median on the widest centroid axis (items in id order on ties). */
        vec3 e = box3_extent(cb);
        b->sort_axis = box3_is_empty(cb) ? 0 : v3_max_axis(e);
        sort_ctx = b;
        qsort(b->items + begin, end - begin, sizeof *b->items, by_centroid);
        mid = begin + (end - begin) / 2;
    }
    uint32_t left = b->node_count;
    b->node_count += 2;
    n->index = left;
    n->count = 0;
    build_node(b, left, begin, mid, depth + 1);
    build_node(b, left + 1, mid, end, depth + 1);
}

int inst_bvh_build(const box3 *boxes, uint32_t n, int max_leaf, inst_bvh *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    bvh_builder b;
    memset(&b, 0, sizeof b);
    b.boxes = boxes;
    b.max_leaf = max_leaf < 1 ? 1 : max_leaf;
    size_t nodes = 2 * (size_t)(n ? n : 1);
    b.cent = malloc(3 * sizeof(float) * (n ? n : 1));
    b.items = malloc(sizeof(uint32_t) * (n ? n : 1));
    b.nodes = malloc(nodes * sizeof *b.nodes);
    if (!b.cent || !b.items || !b.nodes) {
        free(b.cent), free(b.items), free(b.nodes);
        return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory for a BVH of %u boxes", n);
    }
    for (uint32_t i = 0; i < n; i++) {
        vec3 c = box3_center(boxes[i]);
        b.cent[3 * i] = c.x, b.cent[3 * i + 1] = c.y, b.cent[3 * i + 2] = c.z;
        b.items[i] = i;
    }
    b.node_count = n ? 1 : 0; /* no boxes: no root (a leaf of 0 would read as inner) */
    if (n) build_node(&b, 0, 0, n, 1);
    free(b.cent);
    inst_node *shrunk = realloc(b.nodes, (b.node_count ? b.node_count : 1) * sizeof *b.nodes);
    out->nodes = shrunk ? shrunk : b.nodes;
    out->node_count = b.node_count;
    out->items = b.items;
    out->item_count = n;
    out->depth = b.depth;
    return 0;
}

void inst_bvh_free(inst_bvh *b)
{
    free(b->nodes);
    free(b->items);
    memset(b, 0, sizeof *b);
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
