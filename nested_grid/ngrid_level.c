/*
 * ngrid_level.c - one level of the nested grid's sub-grids: planned, then
 * checked against the memory limit, then built, in parallel.
 *
 * Plan. Every cell holding enough primitives is a job. Its plan is the
 * sub-grid's box (the parent cell's own boundary planes), its resolution
 * (sub_res, the rule on sub_lambda, or the cost model in auto mode) and
 * cell count; a sub-grid much finer than its primitives (more than
 * NGRID_PRECOUNT_CELLS cells per primitive, e.g. sub_res=256 over a few
 * triangles) also gets its exact reference count, from the same
 * membership test without any cell array (grid_count_refs), so that the
 * rule dropping sub-grids that copy their primitives more than 8 times
 * over drops it without building it. So does a sub-grid whose first
 * primitives' bounding boxes span more than 64 cells each (a sample: then
 * its exact count runs, stopping at the limit; 1,000 near
 * copies of one triangle built 1,079 such sub-grids only to drop them: 22 s,
 * now 0.3 s). The result is the one building it would give, at a cost that
 * follows references, not cells; dropped plans no longer count in the
 * memory check below.
 *
 * Check. A level's sub-grids are all held until the level is gathered, so
 * the planned cell arrays (and counted references) must fit what max_mb
 * leaves, and all cells a 32-bit index: otherwise the build is refused
 * before anything is built, with the numbers, instead of building for
 * minutes and failing at the end (sub_res=256 made 1500 sub-grids of 16.7M
 * cells each over a 2,000-triangle soup: 138 s, then all dropped).
 *
 * Build. The largest jobs one at a time with every thread, the rest spread
 * over threads one job each. Every plan and job depends on its inputs
 * alone and results are gathered in job order, so any thread count builds
 * the same arrays and reports the same errors.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ngrid_impl.h"

/* Sub-grids with at least this many primitives are built one at a time
 * with every thread rather than as one job among many. */
#define NGRID_BIG_JOB 16384
/* Auto mode: smallest primitive count of a cell worth pricing. */
#define NGRID_AUTO_MIN_PRIMS 2
/* Cells per primitive above which a planned sub-grid's references are
 * counted ahead (cells). Below it building costs about what counting does. */
#define NGRID_PRECOUNT_CELLS 64
/* A planned sub-grid whose first primitives' bounding boxes span more than
 * this many times NGRID_MAX_COPIES cells each gets its exact count ahead of
 * building (plan_sub): a flat triangle fills about half of its box's
 * cells, so such a sub-grid is almost always dropped, and the count is not
 * wasted on the many that are kept. */
#define NGRID_BOX_FACTOR 8

void ngrid_bgrid_free(ngrid_bgrid *g)
{
    if (!g) return;
    grid_cells_free(&g->cells);
    free(g->planes);
    free(g);
}

double ngrid_bgrid_bytes(const ngrid_bgrid *g)
{
    return ((double)g->cells.cell_count + 1.0 + (double)g->cells.ref_count) * sizeof(uint32_t) +
           (double)grid_plane_count(g->frame.res) * sizeof(float);
}

int ngrid_wrap_error(accel_error *err, int rc, const char *context)
{
    if (!err) return rc;
    char inner[sizeof err->msg];
    snprintf(inner, sizeof inner, "%s", err->msg);
    const char *rest = inner;
    if (!strncmp(rest, "nested_grid: ", 13))
        rest += 13;
    else if (!strncmp(rest, "grid: ", 6))
        rest += 6;
    return accel_fail(err, rc, "nested_grid: %s: %s", context, rest);
}

int ngrid_bgrid_new(box3 box, const int res[3], int level, ngrid_bgrid **out, accel_error *err)
{
    *out = NULL;
    ngrid_bgrid *g = calloc(1, sizeof *g);
    if (g) g->planes = malloc(grid_plane_count(res) * sizeof *g->planes);
    if (!g || !g->planes) {
        free(g);
        return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory for a %dx%dx%d grid",
                          res[0], res[1], res[2]);
    }
    grid_frame_init(&g->frame, box, res, g->planes);
    g->level = level;
    *out = g;
    return ACCEL_OK;
}

int ngrid_push_grid(ngrid_builder *b, ngrid_bgrid *g, accel_error *err)
{
    if (b->grid_count == b->grid_cap) {
        uint32_t cap = b->grid_cap ? 2 * b->grid_cap : 64;
        if (cap <= b->grid_cap || cap >= NGRID_CHILD)
            return accel_fail(err, ACCEL_ERR_RANGE, "nested_grid: too many sub-grids");
        ngrid_bgrid **p = realloc(b->grids, cap * sizeof *p);
        if (!p) return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
        b->grids = p;
        b->grid_cap = cap;
    }
    b->grids[b->grid_count++] = g;
    b->bytes += ngrid_bgrid_bytes(g);
    b->cells += g->cells.cell_count;
    return ACCEL_OK;
}

/* ---- plan ----------------------------------------------------------------------- */

/* What one job builds: res[0] == 0 when the cell stays a leaf. */
typedef struct {
    box3 box;
    int res[3];
    uint64_t cells;
    uint64_t refs; /* counted ahead, else 0 */
} sub_plan;

typedef struct {
    uint32_t parent; /* index in builder.grids */
    uint32_t cell;
} sub_job;

static const uint32_t *job_prims(const ngrid_builder *b, const sub_job *job, uint32_t *n)
{
    const ngrid_bgrid *parent = b->grids[job->parent];
    *n = ngrid_cell_prims(parent, job->cell);
    return parent->cells.refs + parent->cells.offsets[job->cell];
}

static void job_context(const ngrid_builder *b, const sub_job *job, char *out, size_t size)
{
    snprintf(out, size, "level %d sub-grid of %u primitives", b->grids[job->parent]->level + 1,
             ngrid_cell_prims(b->grids[job->parent], job->cell));
}

/* The frame a sub-grid over plan's box gets: its planes, and the padding
 * of ngrid_sub_pad under the parent's. */
static void sub_frame(const ngrid_bgrid *parent, const sub_plan *p, grid_frame *f, float *planes)
{
    grid_frame_init(f, p->box, p->res, planes);
    ngrid_sub_pad(f, parent->frame.pad);
}

/* 1 when the first (at most 16) primitives' bounding boxes, measured in
 * cells of the planned sub-grid (box, res), span more than `per_prim`
 * cells each on average: a sample and an estimate, only to decide whether
 * an exact count ahead is worth trying (plan_sub); the exact count alone
 * decides a drop, so this never changes a structure. */
static int boxes_span_above(box3 box, const int res[3], const accel_scene *s, const uint32_t *prims,
                            uint32_t n, double per_prim)
{
    uint32_t k = n < 16 ? n : 16;
    double cell[3], total = 0.0;
    for (int a = 0; a < 3; a++) cell[a] = ((double)v3_idx(box.max, a) - v3_idx(box.min, a)) / res[a];
    for (uint32_t i = 0; i < k; i++) {
        box3 pb = accel_prim_bounds(s, prims[i]);
        double span = 1.0;
        for (int a = 0; a < 3; a++) {
            double c = ((double)v3_idx(pb.max, a) - v3_idx(pb.min, a)) / cell[a] + 1.0;
            span *= c < res[a] ? c : res[a];
        }
        total += span;
    }
    return k > 0 && total > per_prim * k;
}

static int plan_sub(const ngrid_builder *b, const sub_job *job, double budget, sub_plan *p,
                    accel_error *err)
{
    memset(p, 0, sizeof *p);
    const ngrid_bgrid *parent = b->grids[job->parent];
    const grid_frame *pf = &parent->frame;
    const uint32_t cell = job->cell;
    const uint32_t idx[3] = {cell % pf->stride[1], (cell / pf->stride[1]) % (uint32_t)pf->res[1],
                             cell / pf->stride[2]};
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = pf->planes[a][idx[a]];
        hi[a] = pf->planes[a][idx[a] + 1];
        if (!(hi[a] > lo[a])) return ACCEL_OK; /* a cell thinner than a float step */
    }
    p->box = (box3){{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    uint32_t n;
    const uint32_t *prims = job_prims(b, job, &n);
    int res[3];
    if (b->is_auto) {
        int deeper = b->lookahead && parent->level + 2 < b->depth;
        int rc = ngrid_auto_sub_res(b->scene, p->box, pf->pad, prims, n, b->mode, deeper, &b->costs,
                                    budget, res, err);
        if (rc) return rc;
        if (res[0] == 0) return ACCEL_OK;
    } else if (b->sub_res > 0) {
        res[0] = res[1] = res[2] = b->sub_res;
    } else {
        grid_resolution(p->box, (double)n, b->sub_lambda, res);
    }
    for (int a = 0; b->max_sub_res && a < 3; a++)
        if (res[a] > b->max_sub_res) res[a] = b->max_sub_res;
    if (res[0] == 1 && res[1] == 1 && res[2] == 1) return ACCEL_OK;
    int rc = grid_cell_count("nested_grid", res, budget, &p->cells, err);
    if (rc) {
        char context[96];
        job_context(b, job, context, sizeof context);
        return ngrid_wrap_error(err, rc, context);
    }
    memcpy(p->res, res, sizeof res);
    if (b->is_auto) return ACCEL_OK;
    const int precount = p->cells > NGRID_PRECOUNT_CELLS * (uint64_t)n;
    if (!precount && !boxes_span_above(p->box, res, b->scene, prims, n, NGRID_BOX_FACTOR * NGRID_MAX_COPIES))
        return ACCEL_OK;
    float *planes = malloc(grid_plane_count(res) * sizeof *planes);
    if (!planes) return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
    grid_frame f;
    sub_frame(parent, p, &f, planes);
    const uint64_t most = NGRID_MAX_COPIES * (uint64_t)n;
    if (precount) {
        p->refs = grid_count_refs(&f, b->scene, prims, n, b->mode, most);
        if (p->refs > most) p->res[0] = 0; /* build_sub would drop it */
    } else if (grid_count_refs(&f, b->scene, prims, n, b->mode, most) > most) {
        /* Primitives as large as the cell (1,000 near copies of one
         * triangle: each top cell's sub-grid copied all of them into most
         * of its cells, 22 s, to drop every one): the same drop, decided
         * by a count that stops at the limit. p->refs stays 0 otherwise,
         * as before, so the memory check sees what it saw. */
        p->res[0] = 0;
    }
    free(planes);
    return ACCEL_OK;
}

/* ---- build ---------------------------------------------------------------------- */

/* The planned sub-grid of a job, or *out = NULL when the cell stays a leaf.
 * budget: bytes this grid may take. */
static int build_sub(const ngrid_builder *b, const sub_job *job, const sub_plan *p, int threads,
                     double budget, ngrid_bgrid **out, accel_error *err)
{
    *out = NULL;
    if (p->res[0] == 0) return ACCEL_OK;
    const ngrid_bgrid *parent = b->grids[job->parent];
    uint32_t n;
    const uint32_t *prims = job_prims(b, job, &n);
    ngrid_bgrid *g;
    int rc = ngrid_bgrid_new(p->box, p->res, parent->level + 1, &g, err);
    if (rc) return rc;
    ngrid_sub_pad(&g->frame, parent->frame.pad);
    g->parent_cell = job->cell;
    rc = grid_cells_build(&g->frame, b->scene, prims, n, b->mode, threads, budget, &g->cells, err);
    if (rc) {
        char context[96];
        job_context(b, job, context, sizeof context);
        ngrid_bgrid_free(g);
        return ngrid_wrap_error(err, rc, context);
    }
    /* A sub-grid whose non-empty cells still hold, on average, more than
     * half of the primitives separates almost nothing (large primitives
     * spanning the cell, all sharing one region): keep the leaf. Without
     * this, overlapping primitives multiply their references level after
     * level (1000 triangles around one centroid reached 140M references). */
    uint64_t nonempty = 0;
    for (uint64_t c = 0; c < g->cells.cell_count; c++)
        nonempty += g->cells.offsets[c + 1] != g->cells.offsets[c];
    /* Likewise a sub-grid that copies its primitives more than 8 times over
     * (primitives much larger than its cells) costs memory without saving
     * tests (plan_sub applies this one ahead to the finest sub-grids). */
    if (!b->is_auto && nonempty > 0 &&
        (g->cells.ref_count * 2 > (uint64_t)n * nonempty ||
         g->cells.ref_count > NGRID_MAX_COPIES * (uint64_t)n)) {
        ngrid_bgrid_free(g);
        return ACCEL_OK;
    }
    *out = g;
    return ACCEL_OK;
}

/* ---- one level, in parallel ------------------------------------------------------- */

typedef struct {
    size_t job; /* lowest failed job seen by this thread (SIZE_MAX: none) */
    int rc;
    accel_error err;
} job_failure;

typedef struct {
    const ngrid_builder *b;
    const sub_job *jobs;
    sub_plan *plans;
    const size_t *order; /* job indices to run */
    ngrid_bgrid **out;   /* per job; NULL: plan only */
    double budget;
    int threads;         /* threads each job's own passes use */
    job_failure *fail;   /* per thread */
} level_run;

static void run_jobs(void *ctx, size_t begin, size_t end, int thread)
{
    level_run *r = ctx;
    for (size_t k = begin; k < end; k++) {
        size_t j = r->order ? r->order[k] : k;
        accel_error err = {0};
        int rc = r->out ? build_sub(r->b, &r->jobs[j], &r->plans[j], r->threads, r->budget,
                                    &r->out[j], &err)
                        : plan_sub(r->b, &r->jobs[j], r->budget, &r->plans[j], &err);
        job_failure *f = &r->fail[thread];
        if (rc && j < f->job) {
            f->job = j;
            f->rc = rc;
            f->err = err;
        }
    }
}

/* The error of the lowest failed job (the same for any thread count). */
static int first_failure(const job_failure *fail, int nthreads, accel_error *err)
{
    int rc = ACCEL_OK;
    size_t first = SIZE_MAX;
    for (int t = 0; t < nthreads; t++)
        if (fail[t].job < first) {
            first = fail[t].job;
            rc = fail[t].rc;
            if (err) *err = fail[t].err;
        }
    return rc;
}

/* Refuses the level when its planned sub-grids cannot fit. */
static int check_plans(const ngrid_builder *b, int level, const sub_plan *plans, size_t count,
                       accel_error *err)
{
    uint64_t cells = 0, refs = 0, grids = 0;
    double bytes = 0.0;
    size_t largest = SIZE_MAX;
    for (size_t j = 0; j < count; j++) {
        if (plans[j].res[0] == 0) continue;
        grids++;
        cells += plans[j].cells;
        refs += plans[j].refs;
        bytes += ((double)plans[j].cells + 1.0 + (double)plans[j].refs) * sizeof(uint32_t) +
                 (double)grid_plane_count(plans[j].res) * sizeof(float);
        if (largest == SIZE_MAX || plans[j].cells > plans[largest].cells) largest = j;
    }
    if (!grids) return ACCEL_OK;
    const int *r = plans[largest].res;
    if (b->bytes + bytes > b->max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: level %d would make %llu sub-grids of %llu cells in all "
                          "(the largest %dx%dx%d) and at least %llu references: %.1f MiB on top of "
                          "%.1f MiB, above the limit of max_mb=%.1f MiB; refused before building "
                          "(raise threshold or max_mb, lower sub_res, sub_lambda or depth)",
                          level, (unsigned long long)grids, (unsigned long long)cells, r[0], r[1],
                          r[2], (unsigned long long)refs, bytes / 1048576.0, b->bytes / 1048576.0,
                          b->max_bytes / 1048576.0);
    if (b->cells + cells >= UINT32_MAX)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: level %d would make %llu sub-grids of %llu cells in all "
                          "(the largest %dx%dx%d), beyond the 32-bit cell index; refused before "
                          "building (raise threshold, lower sub_res, sub_lambda or depth)",
                          level, (unsigned long long)grids, (unsigned long long)cells, r[0], r[1],
                          r[2]);
    return ACCEL_OK;
}

int ngrid_build_level(ngrid_builder *b, uint32_t begin, uint32_t end, int threads,
                      accel_error *err)
{
    uint32_t min_prims = b->is_auto ? NGRID_AUTO_MIN_PRIMS : b->threshold + 1;
    size_t job_count = 0;
    for (uint32_t gi = begin; gi < end; gi++) {
        const ngrid_bgrid *g = b->grids[gi];
        for (uint64_t c = 0; c < g->cells.cell_count; c++)
            job_count += ngrid_cell_prims(g, (uint32_t)c) >= min_prims;
    }
    if (job_count == 0) return ACCEL_OK;
    sub_job *jobs = malloc(job_count * sizeof *jobs);
    sub_plan *plans = calloc(job_count, sizeof *plans);
    size_t *order = malloc(job_count * sizeof *order);
    ngrid_bgrid **out = calloc(job_count, sizeof *out);
    int nthreads = threads < 1 ? 1 : (threads > 256 ? 256 : threads);
    job_failure *fail = malloc((size_t)nthreads * sizeof *fail);
    if (!jobs || !plans || !order || !out || !fail) {
        free(jobs);
        free(plans);
        free(order);
        free(out);
        free(fail);
        return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory for %zu sub-grid jobs",
                          job_count);
    }
    size_t j = 0;
    for (uint32_t gi = begin; gi < end; gi++) {
        const ngrid_bgrid *g = b->grids[gi];
        for (uint64_t c = 0; c < g->cells.cell_count; c++)
            if (ngrid_cell_prims(g, (uint32_t)c) >= min_prims) {
                jobs[j].parent = gi;
                jobs[j].cell = (uint32_t)c;
                j++;
            }
    }
    for (int t = 0; t < nthreads; t++) {
        fail[t].job = SIZE_MAX;
        fail[t].rc = 0;
    }
    const int level = b->grids[begin]->level + 1;
    level_run run = {b, jobs, plans, NULL, NULL, b->max_bytes - b->bytes, 1, fail};
    accel_parallel_for(job_count, 64, nthreads, run_jobs, &run);
    int rc = first_failure(fail, nthreads, err);
    if (!rc) rc = check_plans(b, level, plans, job_count, err);

    if (!rc) {
        /* Large jobs one at a time with every thread, then the rest in parallel. */
        size_t big = 0, small = 0;
        for (j = 0; j < job_count; j++)
            if (ngrid_cell_prims(b->grids[jobs[j].parent], jobs[j].cell) >= NGRID_BIG_JOB)
                order[big++] = j;
        run.order = order;
        run.out = out;
        run.threads = nthreads;
        for (j = 0; j < big; j++) run_jobs(&run, j, j + 1, 0);
        for (j = 0; j < job_count; j++)
            if (ngrid_cell_prims(b->grids[jobs[j].parent], jobs[j].cell) < NGRID_BIG_JOB)
                order[small++] = j;
        run.threads = 1;
        accel_parallel_for(small, 64, nthreads, run_jobs, &run);
        rc = first_failure(fail, nthreads, err);
    }

    /* Gather in job order: each parent's children end up contiguous and
     * sorted by cell. */
    double level_bytes = 0.0;
    for (j = 0; j < job_count; j++)
        if (out[j]) level_bytes += ngrid_bgrid_bytes(out[j]);
    if (!rc && b->bytes + level_bytes > b->max_bytes)
        rc = accel_fail(err, ACCEL_ERR_RANGE,
                        "nested_grid: level %d sub-grids need %.1f MiB on top of %.1f MiB, above "
                        "the limit of %.1f MiB (raise threshold or max_mb, lower sub_lambda or "
                        "depth)",
                        level, level_bytes / 1048576.0, b->bytes / 1048576.0,
                        b->max_bytes / 1048576.0);
    for (j = 0; j < job_count; j++) {
        if (!out[j]) continue;
        if (rc) {
            ngrid_bgrid_free(out[j]);
            continue;
        }
        ngrid_bgrid *parent = b->grids[jobs[j].parent];
        if (parent->child_count == 0) parent->first_child = b->grid_count;
        parent->child_count++;
        rc = ngrid_push_grid(b, out[j], err);
        if (rc) {
            parent->child_count--;
            ngrid_bgrid_free(out[j]);
        }
    }
    free(jobs);
    free(plans);
    free(order);
    free(out);
    free(fail);
    return rc;
}
