/*
 * ngrid_cost.c - the step/intersect cost model of the nested grid's auto
 * mode: which resolution, if any, a grid over a box should have.
 *
 * The lecture's model prices a ray as C_step*N_steps + C_intersect*N_tests.
 * For a ray known to cross a box B (the scene, or one cell being considered
 * for a sub-grid), geometric probability gives both expectations for a
 * uniform grid over B without tracing anything (Cauchy-Crofton: an
 * isotropic random line crossing B crosses a convex C inside B with
 * probability area(C)/area(B); the argument MacDonald & Booth, "Heuristics
 * for Ray Tracing Using Space Subdivision", The Visual Computer 1990, use
 * for the SAH):
 *   E[cells] = sum over cells of area(cell)/area(B)   (ngrid_expected_cells)
 *   E[tests] = references * area(cell)/area(B)        (every cell the same size)
 * The reference count of a candidate resolution comes from the shared count
 * pass (grid_count_pass), so exact overlap is priced exactly as it is built.
 *
 * What the model leaves out, on purpose: rays stop at their first hit (both
 * terms shrink about alike), and the mailbox tests a primitive spanning
 * several cells once, so E[tests] is an upper bound that grows with the
 * resolution, which pushes towards coarser grids. (Measured, the larger
 * error goes the other way: pricing cells as leaves makes the top level
 * too fine for a nested grid; see cell_cost and nested_grid/README.md.)
 *
 * Decisions are greedy and local, as in SAH tree builds: a cell holding n
 * primitives gets the sub-grid of least expected cost when that cost, plus
 * the cost of entering it, is below testing its n primitives; each cell of
 * the chosen sub-grid is then decided the same way.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ngrid_impl.h"

/* Cost of entering a sub-grid, in cell steps: the DDA setup of the
 * sub-grid (three reciprocals, entry and cell per axis), measured at 3.5 to
 * 4.3 times a step by the micro-benchmark in nested_grid/README.md. */
#define NGRID_ENTER_STEPS 4.0
/* Most primitives the top-level candidates are counted on: a deterministic
 * stride subset, its counts scaled by N / subset size. */
#define NGRID_AUTO_SAMPLE 32768
/* Cells-per-primitive ladders the auto mode chooses from: the resolution
 * rule's result for each (duplicates and 1x1x1 skipped), tried from coarse
 * to fine until the cost rises (it is unimodal in practice: steps grow and
 * tests shrink with the resolution), which spares the count passes of the
 * finest, most expensive candidates. */
static const double top_ladder[] = {0.0625, 0.125, 0.25, 0.5, 1, 2, 4, 8};
static const double sub_ladder[] = {0.25, 0.5, 1, 2, 4, 8, 16};

static void extents(const grid_frame *f, double d[3])
{
    for (int a = 0; a < 3; a++) d[a] = (double)f->hi[a] - f->lo[a];
}

double ngrid_expected_cells(const grid_frame *f)
{
    double d[3];
    extents(f, d);
    double area = d[1] * d[2] + d[2] * d[0] + d[0] * d[1];
    if (!(area > 0.0)) return 1.0;
    return (f->res[0] * d[1] * d[2] + f->res[1] * d[2] * d[0] + f->res[2] * d[0] * d[1]) / area;
}

double ngrid_cell_probability(const grid_frame *f)
{
    double d[3], c[3];
    extents(f, d);
    for (int a = 0; a < 3; a++) c[a] = d[a] / f->res[a];
    double area = d[1] * d[2] + d[2] * d[0] + d[0] * d[1];
    if (!(area > 0.0)) return 1.0;
    return (c[1] * c[2] + c[2] * c[0] + c[0] * c[1]) / area;
}

/*
 * Expected cost of a ray crossing a cell that holds n primitives: testing
 * all of them, or, when the cell may still get a sub-grid of its own (a
 * one-level lookahead), the cheaper of that and an estimate of the best
 * sub-grid. The estimate takes the n primitives as small and spread over a
 * cube cell: a sub-grid of k cells is crossed in about k^(1/3) cells, with
 * about n/k^(2/3) tests, so c_step*k^(1/3) + c_isect*n*k^(-2/3) is least at
 * k = 2*c_isect*n/c_step, where it is (3/2)*c_step*k^(1/3); entering it
 * costs NGRID_ENTER_STEPS steps more. Without the lookahead (the default,
 * lookahead=0) every candidate is priced as if its cells stayed leaves: the
 * top level comes out about as fine as the best regular grid and the
 * sub-grids refine what it leaves dense. With it, coarse levels look cheap
 * wherever refinement could follow; for isotropic rays that is right, but
 * rays that all converge on one small dense region (the camera's rays on
 * the teapot in its stadium) find that region under-resolved when the depth
 * runs out (nested_grid/README.md has the numbers).
 */
static double cell_cost(double n, int deeper, const ngrid_costs *m)
{
    double leaf = m->c_isect * n;
    if (!deeper) return leaf;
    double k = 2.0 * m->c_isect * n / m->c_step;
    double sub = m->c_step * (NGRID_ENTER_STEPS + 1.5 * cbrt(k));
    return sub < leaf ? sub : leaf;
}

/*
 * Expected cost, for a ray crossing box, of a grid of resolution res over
 * it holding prims[]: c_step*E[cells] + P(cell) * sum over cells of
 * cell_cost(count * scale). Padded as a sub-grid of a grid padded by
 * parent_pad (ngrid_sub_pad), or as the top grid when parent_pad is NULL.
 * Returns 0, or 1 when the grid is too large for max_bytes (a candidate to
 * skip, not an error), 2 when it would hold more than max_refs references
 * (the count stops there), or an error status.
 */
static int grid_cost(const accel_scene *s, box3 box, const float *parent_pad, const int res[3],
                     const uint32_t *prims, uint32_t n, double scale, int deeper,
                     grid_overlap mode, double max_bytes, uint64_t max_refs,
                     const ngrid_costs *m, double *cost, accel_error *err)
{
    uint64_t cells;
    accel_error ignore;
    if (grid_cell_count("nested_grid", res, max_bytes, &cells, &ignore)) return 1;
    float *planes = malloc(grid_plane_count(res) * sizeof *planes);
    uint32_t *counts = calloc(cells, sizeof *counts);
    if (!planes || !counts) {
        free(planes);
        free(counts);
        return accel_fail(err, ACCEL_ERR_NOMEM,
                          "nested_grid: out of memory for a %dx%dx%d cost estimate", res[0],
                          res[1], res[2]);
    }
    grid_frame f;
    grid_frame_init(&f, box, res, planes);
    if (parent_pad) ngrid_sub_pad(&f, parent_pad);
    if (grid_count_pass_upto(&f, s, prims, n, mode, counts, max_refs) > max_refs) {
        free(counts);
        free(planes);
        return 2;
    }
    double tests = 0.0;
    for (uint64_t c = 0; c < cells; c++)
        if (counts[c]) tests += cell_cost(counts[c] * scale, deeper, m);
    free(counts);
    free(planes);
    *cost = m->c_step * ngrid_expected_cells(&f) + ngrid_cell_probability(&f) * tests;
    return 0;
}

static int same_res(const int a[3], const int b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

int ngrid_auto_top_res(const accel_scene *s, box3 box, grid_overlap mode, int deeper,
                       const ngrid_costs *m, double max_bytes, int res[3], accel_error *err)
{
    uint32_t n = s->live_count;
    grid_resolution(s->bounds, (double)n, 1.0, res);
    if (n == 0) return ACCEL_OK;
    /* A stride subset stands for the whole scene: each cell's count,
     * scaled by n/sample, estimates the full one. */
    uint32_t stride = n > NGRID_AUTO_SAMPLE ? (n + NGRID_AUTO_SAMPLE - 1) / NGRID_AUTO_SAMPLE : 1;
    uint32_t sample_n = (n + stride - 1) / stride;
    uint32_t *sample = s->live;
    if (stride > 1) {
        sample = malloc((size_t)sample_n * sizeof *sample);
        if (!sample) return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
        for (uint32_t i = 0; i < sample_n; i++) sample[i] = s->live[(size_t)i * stride];
    }
    double scale = (double)n / sample_n;
    double best = INFINITY, prev_cost = INFINITY;
    int prev[3] = {0, 0, 0};
    int rc = ACCEL_OK;
    for (size_t k = 0; k < sizeof top_ladder / sizeof top_ladder[0]; k++) {
        int r[3];
        grid_resolution(s->bounds, (double)n, top_ladder[k], r);
        if (same_res(r, prev)) continue;
        memcpy(prev, r, sizeof prev);
        double cost;
        rc = grid_cost(s, box, NULL, r, sample, sample_n, scale, deeper, mode, max_bytes,
                       UINT64_MAX, m, &cost, err);
        if (rc == 1) {
            rc = ACCEL_OK;
            continue;
        }
        if (rc) break;
        if (cost < best) {
            best = cost;
            memcpy(res, r, sizeof r);
        }
        if (cost > prev_cost) break;
        prev_cost = cost;
    }
    if (sample != s->live) free(sample);
    return rc;
}

int ngrid_auto_sub_res(const accel_scene *s, box3 box, const float parent_pad[3],
                       const uint32_t *prims, uint32_t prim_count, grid_overlap mode, int deeper,
                       const ngrid_costs *m, double max_bytes, int res[3], accel_error *err)
{
    res[0] = res[1] = res[2] = 0;
    /* Testing the cell's primitives: every one of them, once. */
    double best = m->c_isect * prim_count;
    /* No sub-grid can cost less than entering it and stepping one cell. */
    if (best <= m->c_step * (NGRID_ENTER_STEPS + 1.0)) return ACCEL_OK;
    double prev_cost = INFINITY;
    int prev[3] = {1, 1, 1};
    for (size_t k = 0; k < sizeof sub_ladder / sizeof sub_ladder[0]; k++) {
        int r[3];
        grid_resolution(box, (double)prim_count, sub_ladder[k], r);
        if (same_res(r, prev)) continue;
        memcpy(prev, r, sizeof prev);
        double cost;
        /* Primitives as large as the cell (1,000 near copies of one
         * triangle: each top cell's candidates held all of them in most
         * of their cells, and the sub-grid of 250 cells was priced as a
         * small gain over the leaf and built, over 10 minutes for one
         * build): the count stops at the guard, and finer candidates,
         * which copy as much or more, are not tried. */
        int rc = grid_cost(s, box, parent_pad, r, prims, prim_count, 1.0, deeper, mode, max_bytes,
                           NGRID_AUTO_MAX_COPIES * (uint64_t)prim_count, m, &cost, err);
        if (rc == 2) break;
        if (rc == 1) continue;
        if (rc) return rc;
        cost += m->c_step * NGRID_ENTER_STEPS;
        if (cost < best) {
            best = cost;
            memcpy(res, r, sizeof r);
        }
        if (cost > prev_cost) break;
        prev_cost = cost;
    }
    return ACCEL_OK;
}
