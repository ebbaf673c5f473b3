/*
 * grid_build.c - parameters, build and bookkeeping of the `grid` kind.
 *
 * The build is the shared grid API end to end: the resolution rule (or an
 * explicit res), the overflow-checked cell count, the frame with its
 * boundary planes, then the count / prefix-sum / fill passes over the live
 * primitives (grid_core.c). Traversal lives in grid_trace.c.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grid_impl.h"

#define STR_(x) #x
#define STR(x) STR_(x)

static const accel_param_def grid_params[] = {
    {"lambda", ACCEL_PARAM_FLOAT, STR(GRID_DEFAULT_LAMBDA), 0.001, 1000.0, NULL,
     "cells per primitive: n_i = d_i*cbrt(lambda*N/V) (ignored when res is given)"},
    {"res", ACCEL_PARAM_STR, "auto", 0, 0, NULL,
     "cells per axis: auto (from lambda), N, or NxNyNz (each 1..65536)"},
    {"overlap", ACCEL_PARAM_ENUM, "exact", 0, 0, "exact|bbox",
     "cell membership: exact primitive/box overlap, or bounding box only"},
    {"mailbox", ACCEL_PARAM_BOOL, "1", 0, 0, NULL,
     "test a primitive spanning several cells once per ray (16-entry per-ray cache)"},
    {"reorder", ACCEL_PARAM_BOOL, "1", 0, 0, NULL,
     "copy the primitives in Morton order of their centroids (0: scene order)"},
    {"max_mb", ACCEL_PARAM_FLOAT, "4096", 1.0, 1048576.0, NULL,
     "memory limit for cell offsets + references, MiB: larger grids are refused"},
};

static void grid_destroy(void *a)
{
    grid_accel *g = a;
    if (!g) return;
    grid_cells_free(&g->cells);
    free(g->planes);
    free(g->local.tris);
    free(g->local.spheres);
    free(g->prim_id);
    free(g);
}

static size_t grid_memory(const void *a)
{
    const grid_accel *g = a;
    return sizeof *g + (size_t)(g->cells.cell_count + 1) * sizeof(uint32_t) +
           (size_t)g->cells.ref_count * sizeof(uint32_t) +
           grid_plane_count(g->frame.res) * sizeof(float) +
           (size_t)g->local.tri_count * 9 * sizeof(float) +
           (size_t)g->local.sphere_count * 4 * sizeof(float) +
           (size_t)g->local.prim_count * sizeof(uint32_t);
}

/* Spreads the low 10 bits of x to every third bit (bit i -> bit 3i). */
static uint32_t spread_bits(uint32_t x)
{
    x &= 0x3FF;
    x = (x | (x << 16)) & 0x030000FF;
    x = (x | (x << 8)) & 0x0300F00F;
    x = (x | (x << 4)) & 0x030C30C3;
    x = (x | (x << 2)) & 0x09249249;
    return x;
}

/* 30-bit Morton code of a point quantized to 1024 steps per axis of box. */
static uint32_t morton_of(vec3 p, box3 box)
{
    const float c[3] = {p.x, p.y, p.z};
    const float lo[3] = {box.min.x, box.min.y, box.min.z};
    const float hi[3] = {box.max.x, box.max.y, box.max.z};
    uint32_t q[3];
    for (int a = 0; a < 3; a++) {
        float x = (c[a] - lo[a]) / (hi[a] - lo[a]) * 1024.0f;
        q[a] = !(x > 0.0f) ? 0 : (x >= 1023.0f ? 1023 : (uint32_t)x);
    }
    return spread_bits(q[0]) | (spread_bits(q[1]) << 1) | (spread_bits(q[2]) << 2);
}

/* Stable LSD radix sort of n items (key in the high 32 bits, payload low)
 * by their 30-bit keys, in three passes of 10 bits; tmp holds n items. */
static void sort_by_key(uint64_t *v, uint64_t *tmp, size_t n)
{
    for (int shift = 32; shift < 62; shift += 10) {
        size_t count[1025] = {0};
        for (size_t i = 0; i < n; i++) count[((v[i] >> shift) & 1023) + 1]++;
        for (int b = 0; b < 1024; b++) count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++) tmp[count[(v[i] >> shift) & 1023]++] = v[i];
        memcpy(v, tmp, n * sizeof *v);
    }
}

/*
 * Copies the live primitives into g->local (triangles first, then spheres,
 * each group in Morton order of the centroids when `reorder`) and fills
 * g->prim_id. Traversal then reads triangles that are neighbours in space
 * from neighbouring memory, whatever the scene's file order.
 */
static int make_local(grid_accel *g, const accel_scene *scene, box3 box, int reorder,
                      accel_error *err)
{
    uint32_t n = scene->live_count, tris = 0;
    while (tris < n && scene->live[tris] < scene->tri_count) tris++; /* live is increasing */
    accel_scene *l = &g->local;
    l->tri_count = tris;
    l->sphere_count = n - tris;
    l->prim_count = n;
    l->bounds = scene->bounds;
    l->tris = malloc(((size_t)tris * 9 + 1) * sizeof *l->tris);
    l->spheres = malloc(((size_t)(n - tris) * 4 + 1) * sizeof *l->spheres);
    g->prim_id = malloc(((size_t)n + 1) * sizeof *g->prim_id);
    uint64_t *order = malloc(((size_t)n + 1) * sizeof *order);
    uint64_t *tmp = reorder ? malloc(((size_t)n + 1) * sizeof *tmp) : NULL;
    if (!l->tris || !l->spheres || !g->prim_id || !order || (reorder && !tmp)) {
        free(order);
        free(tmp);
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory copying %u primitives", n);
    }
    for (uint32_t k = 0; k < n; k++) {
        uint32_t prim = scene->live[k];
        uint64_t key = reorder ? morton_of(accel_prim_centroid(scene, prim), box) : 0;
        order[k] = key << 32 | prim;
    }
    if (reorder) {
        sort_by_key(order, tmp, tris);
        sort_by_key(order + tris, tmp, n - tris);
    }
    for (uint32_t k = 0; k < n; k++) {
        uint32_t prim = (uint32_t)order[k];
        g->prim_id[k] = prim;
        if (k < tris)
            memcpy(l->tris + 9 * (size_t)k, scene->tris + 9 * (size_t)prim, 9 * sizeof(float));
        else
            memcpy(l->spheres + 4 * (size_t)(k - tris),
                   scene->spheres + 4 * (size_t)(prim - scene->tri_count), 4 * sizeof(float));
    }
    free(order);
    free(tmp);
    return ACCEL_OK;
}

static int grid_build(const accel_scene *scene, const accel_params *params, int threads,
                      void **out, accel_build_stats *stats, accel_error *err)
{
    *out = NULL;
    double lambda = accel_param_num(params, "lambda");
    double max_bytes = accel_param_num(params, "max_mb") * 1048576.0;
    int res[3];
    int rc = grid_parse_res(accel_param_str(params, "res"), res, err);
    if (rc) return rc;
    box3 box = grid_frame_box(scene->bounds);
    if (res[0] == 0) grid_resolution(scene->bounds, (double)scene->live_count, lambda, res);
    uint64_t cells;
    rc = grid_cell_count("grid", res, max_bytes, &cells, err);
    if (rc) return rc;

    grid_accel *g = calloc(1, sizeof *g);
    if (!g) return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory");
    g->naive = params->naive;
    g->mailbox = accel_param_num(params, "mailbox") != 0.0;
    g->has_spheres = scene->sphere_count > 0;
    g->planes = malloc(grid_plane_count(res) * sizeof *g->planes);
    if (!g->planes) {
        grid_destroy(g);
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for plane tables");
    }
    grid_frame_init(&g->frame, box, res, g->planes);
    rc = make_local(g, scene, box, accel_param_num(params, "reorder") != 0.0, err);
    if (rc) {
        grid_destroy(g);
        return rc;
    }
    grid_overlap mode = (int)accel_param_num(params, "overlap") == 1 ? GRID_OVERLAP_BBOX
                                                                      : GRID_OVERLAP_EXACT;
    rc = grid_cells_build(&g->frame, &g->local, NULL, g->local.prim_count, mode, threads,
                          max_bytes, &g->cells, err);
    if (rc) {
        grid_destroy(g);
        return rc;
    }

    memset(stats, 0, sizeof *stats);
    stats->bytes = grid_memory(g);
    stats->nodes = g->cells.cell_count;
    for (uint64_t c = 0; c < g->cells.cell_count; c++)
        stats->leaves += g->cells.offsets[c + 1] != g->cells.offsets[c];
    stats->refs = g->cells.ref_count;
    stats->sah_cost = NAN;
    stats->depth = 1;
    for (int a = 0; a < 3; a++) stats->res[a] = g->frame.res[a];
    *out = g;
    return ACCEL_OK;
}

void grid_get_view(const void *accel, grid_view *v)
{
    const grid_accel *g = accel;
    v->frame = &g->frame;
    v->offsets = g->cells.offsets;
    v->refs = g->cells.refs;
    v->prim_id = g->prim_id;
    v->prim_count = g->local.prim_count;
    v->cell_count = g->cells.cell_count;
    v->ref_count = g->cells.ref_count;
}

/* The conformance suite runs each: defaults, a single cell (the brute force
 * limit), a very fine grid, bounding-box membership, no mailbox, the naive
 * triangle test, and the two ends of the density range. */
static const char *const grid_variants[] = {
    "", "res=1", "res=128", "res=7x1x13", "overlap=bbox", "mailbox=0", "tri=naive",
    "lambda=0.05", "lambda=64", "overlap=bbox,mailbox=0", "reorder=0", NULL,
};

const accel_kind accel_kind_grid = {
    .name = "grid",
    .summary = "uniform grid, compact cells, exact overlap, 3D-DDA with mailboxing",
    .step_name = "cells",
    .params = grid_params,
    .param_count = sizeof grid_params / sizeof grid_params[0],
    .variants = grid_variants,
    .build = grid_build,
    .intersect = grid_intersect,
    .occluded = grid_occluded,
    .memory = grid_memory,
    .destroy = grid_destroy,
};
