/*
 * grid_starter.c - the lab's optional grid step (LAB.md, "A grid with a
 * tuned resolution"): a uniform grid kind with its plumbing in place and
 * two functions left to write.
 *
 * `make lab` copies this file to lab/student_grid.c (kind "student_grid")
 * the first time, compiled only in the lab build (bin-lab/); you edit
 * lab/student_grid.c, never this file: `make test` checks that the grid
 * step's check fails on this untouched starter. `make lab STEP=6` checks it.
 *
 *   build_cells()  the resolution from lambda (Cleary and Wyvill: cells per
 *                  axis n_i = d_i * cbrt(lambda * N / V), at least 1), and
 *                  the cells' primitive lists (every cell a primitive's box
 *                  overlaps), as offsets cell_start[] into cell_prims[]
 *   trace_ray()    the 3D DDA (Amanatides and Woo, "A Fast Voxel Traversal
 *                  Algorithm for Ray Tracing", Eurographics 1987): from the
 *                  cell where the ray enters the grid, cell by cell in the
 *                  ray's order, testing each cell's primitives, until a hit
 *                  lies before the current cell's exit
 *
 * Useful, in accel/core/: box3_slab (geom.h: where the ray enters and leaves
 * the grid's box), accel_prim_bounds, accel_prim_hit (prim.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"
#include "core/variant.h"

typedef struct {
    accel_prim_store store; /* the primitives (local ids) and scene_id[] */
    float lo[3], hi[3];     /* the grid's box: the bounds of every primitive */
    int res[3];             /* cells per axis */
    float cell[3], inv_cell[3]; /* a cell's size per axis, and its inverse */
    uint32_t cell_count;    /* res[0] * res[1] * res[2] */
    uint32_t *cell_start;   /* cell c holds cell_prims[cell_start[c], cell_start[c + 1]) */
    uint32_t *cell_prims;   /* local primitive ids, cell after cell */
    uint32_t ref_count;     /* entries of cell_prims */
    double lambda;          /* lambda=X: cells per primitive */
    int naive;              /* tri=naive */
} lab_grid;

typedef struct {
    double lambda;
} lab_grid_spec;

static const accel_param_def lab_grid_params[] = {
    {.key = "lambda", .type = ACCEL_PARAM_FLOAT, .def = "8", .min = 0.01, .max = 1024.0,
     .help = "cells per primitive: n_i = d_i*cbrt(lambda*N/V)",
     .offset = offsetof(lab_grid_spec, lambda)},
};

/* The cell of (x, y, z), each in 0..res-1 (unused until you write the
 * build and the walk: marked so that no compiler warns before). */
static inline __attribute__((unused)) uint32_t cell_index(const lab_grid *g, int x, int y, int z)
{
    return ((uint32_t)z * (uint32_t)g->res[1] + (uint32_t)y) * (uint32_t)g->res[0] + (uint32_t)x;
}

/*
 * To do (the grid step): set g->res[] from g->lambda and the grid's box
 * (g->lo, g->hi; an axis of zero extent gets one cell), g->cell[] and
 * g->inv_cell[], g->cell_count; then the cells' lists: count the cells each
 * primitive's box overlaps, turn the counts into offsets cell_start[0..
 * cell_count] (malloc'd), and fill cell_prims[] (malloc'd, ref_count
 * entries). Return 0 or an accel_fail status (e.g. ACCEL_ERR_NOMEM).
 */
static int build_cells(lab_grid *g, accel_error *err)
{
    (void)g;
    (void)err;
    return ACCEL_OK; /* TODO: no cells yet */
}

/*
 * To do (the grid step): the closest hit (any_hit == 0) or any hit of one
 * ray: clip it to the grid's box (box3_slab with p->t_near, p->t_far), find
 * the cell where it enters, then step (3D DDA) through the cells it
 * crosses, testing each cell's primitives with accel_prim_hit (it keeps the
 * nearest hit in t). A primitive spans several cells: a hit found in a cell
 * may lie beyond it, so stop only when the closest t lies before the
 * current cell's exit. Count every cell stepped in *steps and every
 * primitive test in *prims. Return the local id hit (or ACCEL_MISS).
 */
static inline __attribute__((always_inline)) uint32_t
trace_ray(const lab_grid *g, const accel_ray_prep *p, int any_hit, int naive, int spheres,
          float *t_out, float *u_out, float *v_out, uint32_t *steps, uint32_t *prims)
{
    (void)g;
    (void)p;
    (void)any_hit;
    (void)naive;
    (void)spheres;
    (void)t_out;
    (void)u_out;
    (void)v_out;
    (void)steps;
    (void)prims;
    return ACCEL_MISS; /* TODO */
}

/* ---- the kind (nothing to do below) -------------------------------------- */

static void lab_grid_destroy(void *a)
{
    lab_grid *g = a;
    if (!g) return;
    accel_prim_store_free(&g->store);
    free(g->cell_start);
    free(g->cell_prims);
    free(g);
}

static size_t lab_grid_memory(const void *a)
{
    const lab_grid *g = a;
    return sizeof *g + accel_prim_store_bytes(&g->store) +
           (g->cell_start ? ((size_t)g->cell_count + 1) * sizeof(uint32_t) : 0) +
           (size_t)g->ref_count * sizeof(uint32_t);
}

static int lab_grid_build(const accel_scene *scene, const accel_params *params, int threads,
                          void **out, accel_build_stats *stats, accel_error *err)
{
    (void)threads;
    *out = NULL;
    lab_grid *g = calloc(1, sizeof *g);
    if (!g) return accel_fail(err, ACCEL_ERR_NOMEM, "lab grid: out of memory");
    int rc = accel_prim_store_build(scene, params->reorder, &g->store, err);
    if (rc) {
        free(g);
        return rc;
    }
    g->lambda = ACCEL_SPEC(params, lab_grid_spec)->lambda;
    g->naive = params->naive;
    box3 b = box3_empty();
    for (uint32_t i = 0; i < g->store.prims.prim_count; i++)
        b = box3_union(b, accel_prim_bounds(&g->store.prims, i));
    g->lo[0] = b.min.x, g->lo[1] = b.min.y, g->lo[2] = b.min.z;
    g->hi[0] = b.max.x, g->hi[1] = b.max.y, g->hi[2] = b.max.z;
    if (g->store.prims.prim_count > 0 && (rc = build_cells(g, err)) == 0 &&
        (!g->cell_start || !g->cell_prims || g->cell_count == 0))
        rc = accel_fail(err, ACCEL_ERR_INTERNAL, "%s: no cells: build_cells() is not written yet "
                        "(the optional grid step, LAB.md)", params->kind->name);
    if (rc) {
        lab_grid_destroy(g);
        return rc;
    }
    memset(stats, 0, sizeof *stats);
    stats->nodes = g->cell_start ? g->cell_count : 0;
    for (uint32_t c = 0; g->cell_start && c < g->cell_count; c++)
        stats->leaves += g->cell_start[c + 1] > g->cell_start[c];
    stats->refs = g->ref_count;
    stats->depth = 1;
    stats->sah_cost = NAN;
    stats->bytes = lab_grid_memory(g);
    *out = g;
    return ACCEL_OK;
}

static inline __attribute__((always_inline)) void
lab_grid_kernel(const lab_grid *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                size_t count, accel_counters *c, int naive, int spheres, int opt)
{
    (void)opt;
    for (size_t r = 0; r < count; r++) {
        accel_ray_prep p;
        uint32_t steps = 0, prims = 0, local = ACCEL_MISS;
        float t = INFINITY, u = 0.0f, v = 0.0f;
        if (g->cell_start && accel_prep_ray(&rays[r], &p)) {
            t = p.t_far;
            local = trace_ray(g, &p, occ != NULL, naive, spheres, &t, &u, &v, &steps, &prims);
        }
        if (occ) {
            occ[r] = local != ACCEL_MISS;
        } else if (local != ACCEL_MISS) {
            accel_hit h = {t, g->store.scene_id[local], u, v};
            hits[r] = h;
        } else {
            hits[r] = accel_hit_miss();
        }
        if (c) accel_count_ray(c, r, steps, 0, 0, prims, 0);
    }
}

ACCEL_KERNEL_PAIR_NO_OPT(lab_grid, lab_grid_kernel)

static unsigned lab_grid_flags(const lab_grid *g)
{
    return accel_variant_flags(g->naive, g->store.prims.sphere_count > 0, 0);
}

static void lab_grid_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,
                               accel_counters *c)
{
    accel_run_kernel(&lab_grid_hit_table, a, rays, hits, n, c, lab_grid_flags(a));
}

static void lab_grid_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,
                              accel_counters *c)
{
    accel_run_kernel(&lab_grid_occ_table, a, rays, occ, n, c, lab_grid_flags(a));
}

static const char *const lab_grid_variants[] = {"", "lambda=1", "lambda=64", NULL};

const accel_kind accel_kind_grid_starter = {
    .name = "grid_starter",
    .summary = "the lab's uniform grid (LAB.md, the optional grid step)",
    .step_name = "cells",
    .params = lab_grid_params,
    .param_count = sizeof lab_grid_params / sizeof lab_grid_params[0],
    .spec_size = sizeof(lab_grid_spec),
    .variants = lab_grid_variants,
    .build = lab_grid_build,
    .intersect = lab_grid_intersect,
    .occluded = lab_grid_occluded,
    .memory = lab_grid_memory,
    .destroy = lab_grid_destroy,
};
