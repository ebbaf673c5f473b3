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

#include "grid_packet.h"

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
    {"max_mb", ACCEL_PARAM_FLOAT, "4096", 1.0, 1048576.0, NULL,
     "memory limit for cell offsets + references, MiB: larger grids are refused"},
    {"traverse", ACCEL_PARAM_ENUM, "single", 0, 0, "single|packet",
     "single rays (3D-DDA), or coherent grid traversal of 64 consecutive rays (8x8 tiles) "
     "slice by slice"},
};

static void grid_destroy(void *a)
{
    grid_accel *g = a;
    if (!g) return;
    grid_cells_free(&g->cells);
    free(g->planes);
    free(g->macro);
    accel_prim_store_free(&g->store);
    free(g);
}

static size_t grid_memory(const void *a)
{
    const grid_accel *g = a;
    return sizeof *g + (size_t)(g->cells.cell_count + 1) * sizeof(uint32_t) +
           (size_t)g->cells.ref_count * sizeof(uint32_t) +
           grid_plane_count(g->frame.res) * sizeof(float) + accel_prim_store_bytes(&g->store) +
           (g->macro ? (size_t)g->macro_res[0] * g->macro_res[1] * g->macro_res[2] : 0);
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
    g->traverse = (int)accel_param_num(params, "traverse") == 1 ? GRID_TRAVERSE_PACKET
                                                                 : GRID_TRAVERSE_SINGLE;
    g->has_spheres = scene->sphere_count > 0;
    g->planes = malloc(grid_plane_count(res) * sizeof *g->planes);
    if (!g->planes) {
        grid_destroy(g);
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for plane tables");
    }
    grid_frame_init(&g->frame, box, res, g->planes);
    rc = accel_prim_store_build(scene, params->reorder, &g->store, err);
    if (rc) {
        grid_destroy(g);
        return rc;
    }
    grid_overlap mode = (int)accel_param_num(params, "overlap") == 1 ? GRID_OVERLAP_BBOX
                                                                      : GRID_OVERLAP_EXACT;
    rc = grid_cells_build(&g->frame, &g->store.prims, NULL, g->store.prims.prim_count, mode, threads,
                          max_bytes, &g->cells, err);
    if (rc) {
        grid_destroy(g);
        return rc;
    }

    if (g->traverse == GRID_TRAVERSE_PACKET && (rc = grid_macro_build(g, err))) {
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
    v->prim_id = g->store.scene_id;
    v->prim_count = g->store.prims.prim_count;
    v->cell_count = g->cells.cell_count;
    v->ref_count = g->cells.ref_count;
}

/* The batch entries: single rays or packets (grid_packet.c). */
static void grid_trace_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                                 size_t count, accel_counters *counters)
{
    const grid_accel *g = accel;
    if (g->traverse == GRID_TRAVERSE_PACKET)
        grid_packet_intersect(accel, rays, hits, count, counters);
    else
        grid_intersect(accel, rays, hits, count, counters);
}

static void grid_trace_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                                size_t count, accel_counters *counters)
{
    const grid_accel *g = accel;
    if (g->traverse == GRID_TRAVERSE_PACKET)
        grid_packet_occluded(accel, rays, occluded, count, counters);
    else
        grid_occluded(accel, rays, occluded, count, counters);
}

/* The conformance suite runs each: defaults, a single cell (the brute force
 * limit), a very fine grid, bounding-box membership, no mailbox, the naive
 * triangle test, the two ends of the density range, and the packet
 * traversal with and without its mailbox, on a fine and a flat grid. */
static const char *const grid_variants[] = {
    "", "res=1", "res=128", "res=7x1x13", "overlap=bbox", "mailbox=0", "tri=naive",
    "lambda=0.05", "lambda=64", "overlap=bbox,mailbox=0", "reorder=0", "traverse=packet",
    "traverse=packet,mailbox=0", "traverse=packet,res=128", "traverse=packet,res=7x1x13",
    "traverse=packet,tri=naive", NULL,
};

const accel_kind accel_kind_grid = {
    .name = "grid",
    .summary = "uniform grid, compact cells, exact overlap, 3D-DDA with mailboxing",
    .step_name = "cells",
    .params = grid_params,
    .param_count = sizeof grid_params / sizeof grid_params[0],
    .variants = grid_variants,
    .build = grid_build,
    .intersect = grid_trace_intersect,
    .occluded = grid_trace_occluded,
    .memory = grid_memory,
    .destroy = grid_destroy,
};
