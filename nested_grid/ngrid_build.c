/*
 * ngrid_build.c - parameters, build and bookkeeping of the `nested_grid`
 * kind.
 *
 * The build goes level by level. Every grid, the top one and each
 * sub-grid, is made by the shared grid API (grid/grid_core.h): resolution
 * rule, overflow-checked cell count, frame and boundary planes, then the
 * count / prefix-sum / fill passes over its primitives. A sub-grid is laid
 * over one parent cell's box (the parent's own boundary planes, so that
 * both walks compute the very same crossing distances at the shared
 * boundary) and built over that cell's reference list only.
 *
 * Which cells get a sub-grid: with fixed parameters, every cell holding
 * more than `threshold` primitives, at the resolution the rule gives for
 * sub_lambda on the cell's own count and box (or sub_res), as long as the
 * sub-grid separates anything; in auto mode, the cost model decides
 * (ngrid_cost.c).
 *
 * Then everything is flattened into the compact form the traversal reads
 * (ngrid.h): one array of cell words for all grids, one array of
 * count-prefixed primitive lists, one plane table, one node array. No
 * per-cell allocation survives the build.
 *
 * Threads: the top grid's passes run on all threads; the sub-grids of a
 * level are independent jobs (the largest built one at a time with all
 * threads, the rest spread over threads one job each). Every job's result
 * depends on its inputs alone and results are gathered in job order, so
 * any thread count builds the same arrays.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ngrid_impl.h"

#define STR_(x) #x
#define STR(x) STR_(x)

/* Sub-grids with at least this many primitives are built one at a time
 * with every thread rather than as one job among many. */
#define NGRID_BIG_JOB 16384
/* Auto mode: smallest primitive count of a cell worth pricing. */
#define NGRID_AUTO_MIN_PRIMS 2

static const accel_param_def ngrid_params[] = {
    {"lambda", ACCEL_PARAM_FLOAT, STR(NGRID_DEFAULT_LAMBDA), 0.001, 1000.0, NULL,
     "top level: cells per primitive, n_i = d_i*cbrt(lambda*N/V)"},
    {"res", ACCEL_PARAM_STR, "auto", 0, 0, NULL,
     "top level: cells per axis, auto (from lambda or the cost model), N or NxNyNz"},
    {"sub_lambda", ACCEL_PARAM_FLOAT, STR(NGRID_DEFAULT_SUB_LAMBDA), 0.001, 1000.0, NULL,
     "sub-grids: cells per primitive, on the cell's own primitive count and box"},
    {"sub_res", ACCEL_PARAM_INT, "0", 0, 256, NULL,
     "sub-grids: cells per axis of every sub-grid (0: from sub_lambda)"},
    {"threshold", ACCEL_PARAM_INT, STR(NGRID_DEFAULT_THRESHOLD), 0, 1e9, NULL,
     "a cell holding more than this many primitives gets a sub-grid (primitives)"},
    {"depth", ACCEL_PARAM_INT, STR(NGRID_DEFAULT_DEPTH), 1, NGRID_MAX_LEVELS, NULL,
     "most levels, the top included (1: a regular grid)"},
    {"auto", ACCEL_PARAM_BOOL, "0", 0, 0, NULL,
     "cost model picks the top resolution and every sub-grid (ignores lambda, sub_lambda, "
     "sub_res, threshold)"},
    {"lookahead", ACCEL_PARAM_BOOL, "0", 0, 0, NULL,
     "auto: price a cell that may still get a sub-grid by its best sub-grid's estimate "
     "(0: as a leaf)"},
    {"c_step", ACCEL_PARAM_FLOAT, STR(NGRID_DEFAULT_C_STEP), 1e-3, 1e6, NULL,
     "auto: cost of one cell step, ns"},
    {"c_isect", ACCEL_PARAM_FLOAT, STR(NGRID_DEFAULT_C_ISECT), 1e-3, 1e6, NULL,
     "auto: cost of one primitive test, ns"},
    {"overlap", ACCEL_PARAM_ENUM, "exact", 0, 0, "exact|bbox",
     "cell membership: exact primitive/box overlap, or bounding box only"},
    {"mailbox", ACCEL_PARAM_BOOL, "1", 0, 0, NULL,
     "test a primitive spanning several cells once per ray, across levels (16-entry cache)"},
    {"max_mb", ACCEL_PARAM_FLOAT, "4096", 1.0, 1048576.0, NULL,
     "memory limit for all levels (cells, references, planes), MiB"},
};

/* ---- grids under construction ------------------------------------------------ */

typedef struct {
    int level;
    uint32_t parent_cell;   /* linear cell index in the parent grid */
    grid_frame frame;
    float *planes;          /* storage behind frame.planes */
    grid_cells cells;
    uint32_t first_child;   /* children: grids[first_child .. +child_count), by cell */
    uint32_t child_count;
} bgrid;

typedef struct {
    const accel_scene *scene;
    grid_overlap mode;
    int is_auto, lookahead, depth, sub_res;
    double sub_lambda;
    uint32_t threshold;
    ngrid_costs costs;
    double max_bytes;
    bgrid **grids;    /* breadth-first */
    uint32_t grid_count, grid_cap;
    double bytes;     /* offsets, references and planes of every grid so far */
} builder;

static void bgrid_free(bgrid *g)
{
    if (!g) return;
    grid_cells_free(&g->cells);
    free(g->planes);
    free(g);
}

static double bgrid_bytes(const bgrid *g)
{
    return ((double)g->cells.cell_count + 1.0 + (double)g->cells.ref_count) * sizeof(uint32_t) +
           (double)grid_plane_count(g->frame.res) * sizeof(float);
}

static uint32_t cell_prims(const bgrid *g, uint32_t cell)
{
    return g->cells.offsets[cell + 1] - g->cells.offsets[cell];
}

/* Puts "nested_grid: <context>: " before a message from the grid API. */
static int wrap_error(accel_error *err, int rc, const char *context)
{
    if (!err) return rc;
    char inner[sizeof err->msg];
    snprintf(inner, sizeof inner, "%s", err->msg);
    const char *rest = inner;
    if (!strncmp(rest, "nested_grid: ", 13)) rest += 13;
    else if (!strncmp(rest, "grid: ", 6)) rest += 6;
    return accel_fail(err, rc, "nested_grid: %s: %s", context, rest);
}

/* Allocates a grid with its frame over box at resolution res. */
static int bgrid_new(box3 box, const int res[3], int level, bgrid **out, accel_error *err)
{
    *out = NULL;
    bgrid *g = calloc(1, sizeof *g);
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

/*
 * The sub-grid of parent cell `cell`, or *out = NULL when the cell stays a
 * leaf. budget: bytes this grid may take.
 */
static int build_sub(const builder *b, const bgrid *parent, uint32_t cell, int threads,
                     double budget, bgrid **out, accel_error *err)
{
    *out = NULL;
    const grid_frame *pf = &parent->frame;
    const uint32_t idx[3] = {cell % pf->stride[1], (cell / pf->stride[1]) % (uint32_t)pf->res[1],
                             cell / pf->stride[2]};
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = pf->planes[a][idx[a]];
        hi[a] = pf->planes[a][idx[a] + 1];
        if (!(hi[a] > lo[a])) return ACCEL_OK; /* a cell thinner than a float step */
    }
    box3 box = {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    const uint32_t *prims = parent->cells.refs + parent->cells.offsets[cell];
    uint32_t n = cell_prims(parent, cell);
    int res[3];
    if (b->is_auto) {
        int deeper = b->lookahead && parent->level + 2 < b->depth;
        int rc = ngrid_auto_sub_res(b->scene, box, pf->pad, prims, n, b->mode, deeper, &b->costs,
                                    budget, res, err);
        if (rc) return rc;
        if (res[0] == 0) return ACCEL_OK;
    } else if (b->sub_res > 0) {
        res[0] = res[1] = res[2] = b->sub_res;
    } else {
        grid_resolution(box, (double)n, b->sub_lambda, res);
    }
    if (res[0] == 1 && res[1] == 1 && res[2] == 1) return ACCEL_OK;
    char context[96];
    snprintf(context, sizeof context, "level %d sub-grid of %u primitives", parent->level + 1, n);
    uint64_t cells;
    int rc = grid_cell_count("nested_grid", res, budget, &cells, err);
    if (rc) return wrap_error(err, rc, context);
    bgrid *g;
    rc = bgrid_new(box, res, parent->level + 1, &g, err);
    if (rc) return rc;
    ngrid_sub_pad(&g->frame, pf->pad);
    g->parent_cell = cell;
    rc = grid_cells_build(&g->frame, b->scene, prims, n, b->mode, threads, budget, &g->cells, err);
    if (rc) {
        bgrid_free(g);
        return wrap_error(err, rc, context);
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
     * tests. */
    if (!b->is_auto && nonempty > 0 &&
        (g->cells.ref_count * 2 > (uint64_t)n * nonempty || g->cells.ref_count > 8 * (uint64_t)n)) {
        bgrid_free(g);
        return ACCEL_OK;
    }
    *out = g;
    return ACCEL_OK;
}

/* ---- one level of sub-grids, in parallel ------------------------------------------ */

typedef struct {
    uint32_t parent; /* index in builder.grids */
    uint32_t cell;
} sub_job;

typedef struct {
    size_t job; /* lowest failed job seen by this thread (SIZE_MAX: none) */
    int rc;
    accel_error err;
} job_failure;

typedef struct {
    const builder *b;
    const sub_job *jobs;
    const size_t *order; /* job indices to run */
    bgrid **out;         /* per job */
    double budget;
    int threads;         /* threads each job's own passes use */
    job_failure *fail;   /* per thread */
} level_run;

static void run_jobs(void *ctx, size_t begin, size_t end, int thread)
{
    level_run *r = ctx;
    for (size_t k = begin; k < end; k++) {
        size_t j = r->order[k];
        accel_error err = {0};
        const sub_job *job = &r->jobs[j];
        int rc = build_sub(r->b, r->b->grids[job->parent], job->cell, r->threads, r->budget,
                           &r->out[j], &err);
        job_failure *f = &r->fail[thread];
        if (rc && j < f->job) {
            f->job = j;
            f->rc = rc;
            f->err = err;
        }
    }
}

static int push_grid(builder *b, bgrid *g, accel_error *err)
{
    if (b->grid_count == b->grid_cap) {
        uint32_t cap = b->grid_cap ? 2 * b->grid_cap : 64;
        if (cap <= b->grid_cap || cap >= NGRID_CHILD)
            return accel_fail(err, ACCEL_ERR_RANGE, "nested_grid: too many sub-grids");
        bgrid **p = realloc(b->grids, cap * sizeof *p);
        if (!p) return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
        b->grids = p;
        b->grid_cap = cap;
    }
    b->grids[b->grid_count++] = g;
    b->bytes += bgrid_bytes(g);
    return ACCEL_OK;
}

/* Builds the sub-grids of grids[begin, end) (all of one level). */
static int build_level(builder *b, uint32_t begin, uint32_t end, int threads, accel_error *err)
{
    uint32_t min_prims = b->is_auto ? NGRID_AUTO_MIN_PRIMS : b->threshold + 1;
    size_t job_count = 0;
    for (uint32_t gi = begin; gi < end; gi++) {
        const bgrid *g = b->grids[gi];
        for (uint64_t c = 0; c < g->cells.cell_count; c++)
            job_count += cell_prims(g, (uint32_t)c) >= min_prims;
    }
    if (job_count == 0) return ACCEL_OK;
    sub_job *jobs = malloc(job_count * sizeof *jobs);
    size_t *order = malloc(job_count * sizeof *order);
    bgrid **out = calloc(job_count, sizeof *out);
    int nthreads = threads < 1 ? 1 : (threads > 256 ? 256 : threads);
    job_failure *fail = malloc((size_t)nthreads * sizeof *fail);
    if (!jobs || !order || !out || !fail) {
        free(jobs);
        free(order);
        free(out);
        free(fail);
        return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory for %zu sub-grid jobs",
                          job_count);
    }
    size_t j = 0;
    for (uint32_t gi = begin; gi < end; gi++) {
        const bgrid *g = b->grids[gi];
        for (uint64_t c = 0; c < g->cells.cell_count; c++)
            if (cell_prims(g, (uint32_t)c) >= min_prims) {
                jobs[j].parent = gi;
                jobs[j].cell = (uint32_t)c;
                j++;
            }
    }
    for (int t = 0; t < nthreads; t++) {
        fail[t].job = SIZE_MAX;
        fail[t].rc = 0;
    }
    level_run run = {b, jobs, order, out, b->max_bytes - b->bytes, nthreads, fail};
    /* Large jobs one at a time with every thread, then the rest in parallel. */
    size_t big = 0, small = 0;
    for (j = 0; j < job_count; j++)
        if (cell_prims(b->grids[jobs[j].parent], jobs[j].cell) >= NGRID_BIG_JOB) order[big++] = j;
    for (j = 0; j < big; j++) run_jobs(&run, j, j + 1, 0);
    for (j = 0; j < job_count; j++)
        if (cell_prims(b->grids[jobs[j].parent], jobs[j].cell) < NGRID_BIG_JOB) order[small++] = j;
    run.threads = 1;
    accel_parallel_for(small, 64, nthreads, run_jobs, &run);

    int rc = ACCEL_OK;
    size_t first = SIZE_MAX;
    for (int t = 0; t < nthreads; t++)
        if (fail[t].job < first) {
            first = fail[t].job;
            rc = fail[t].rc;
            if (err) *err = fail[t].err;
        }
    /* Gather in job order: each parent's children end up contiguous and
     * sorted by cell. */
    double level_bytes = 0.0;
    for (j = 0; j < job_count; j++)
        if (out[j]) level_bytes += bgrid_bytes(out[j]);
    if (!rc && b->bytes + level_bytes > b->max_bytes)
        rc = accel_fail(err, ACCEL_ERR_RANGE,
                        "nested_grid: level %d sub-grids need %.1f MiB on top of %.1f MiB, above "
                        "the limit of %.1f MiB (raise threshold or max_mb, lower sub_lambda or "
                        "depth)",
                        b->grids[begin]->level + 1, level_bytes / 1048576.0,
                        b->bytes / 1048576.0, b->max_bytes / 1048576.0);
    for (j = 0; j < job_count; j++) {
        if (!out[j]) continue;
        if (rc) {
            bgrid_free(out[j]);
            continue;
        }
        bgrid *parent = b->grids[jobs[j].parent];
        if (parent->child_count == 0) parent->first_child = b->grid_count;
        parent->child_count++;
        rc = push_grid(b, out[j], err);
        if (rc) {
            parent->child_count--;
            bgrid_free(out[j]);
        }
    }
    free(jobs);
    free(order);
    free(out);
    free(fail);
    return rc;
}

/* ---- the flat structure ------------------------------------------------------------ */

static void ngrid_destroy(void *a)
{
    ngrid_accel *g = a;
    if (!g) return;
    free(g->nodes);
    free(g->cells);
    free(g->lists);
    free(g->planes);
    accel_prim_store_free(&g->store);
    free(g);
}

static size_t ngrid_memory(const void *a)
{
    const ngrid_accel *g = a;
    return sizeof *g + (size_t)g->node_count * sizeof *g->nodes +
           (size_t)g->cell_count * sizeof *g->cells + (size_t)g->list_len * sizeof *g->lists +
           g->plane_count * sizeof *g->planes + accel_prim_store_bytes(&g->store);
}

/* Is cell c of grid g one that holds a sub-grid? `next` walks g's children
 * in cell order. */
static int is_child_cell(const builder *b, const bgrid *g, uint32_t *next, uint64_t c)
{
    return *next < g->first_child + g->child_count && b->grids[*next]->parent_cell == c;
}

static int flatten(const builder *b, ngrid_accel *g, accel_error *err)
{
    uint64_t cells = 0, list_len = 1, refs = 0, leaves = 0;
    size_t planes = 0;
    for (uint32_t i = 0; i < b->grid_count; i++) {
        const bgrid *q = b->grids[i];
        uint32_t next = q->first_child;
        for (uint64_t c = 0; c < q->cells.cell_count; c++) {
            if (is_child_cell(b, q, &next, c)) {
                next++;
                continue;
            }
            uint32_t n = cell_prims(q, (uint32_t)c);
            if (n) {
                list_len += 1 + (uint64_t)n;
                refs += n;
                leaves++;
            }
        }
        cells += q->cells.cell_count;
        planes += grid_plane_count(q->frame.res);
    }
    if (cells >= UINT32_MAX || list_len >= NGRID_CHILD)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: %llu cells and %llu list words exceed the 32-bit index "
                          "limits (raise threshold, lower lambda or sub_lambda)",
                          (unsigned long long)cells, (unsigned long long)list_len);
    double bytes = (double)sizeof *g + (double)b->grid_count * sizeof(ngrid_node) +
                   ((double)cells + (double)list_len) * sizeof(uint32_t) +
                   (double)planes * sizeof(float);
    if (bytes > b->max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: %llu cells and %llu references need %.1f MiB, above the "
                          "limit of %.1f MiB (raise max_mb or threshold)",
                          (unsigned long long)cells, (unsigned long long)refs, bytes / 1048576.0,
                          b->max_bytes / 1048576.0);
    g->nodes = malloc((size_t)b->grid_count * sizeof *g->nodes);
    g->cells = malloc((size_t)cells * sizeof *g->cells);
    g->lists = malloc((size_t)list_len * sizeof *g->lists);
    g->planes = malloc(planes * sizeof *g->planes);
    if (!g->nodes || !g->cells || !g->lists || !g->planes)
        return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory for %.1f MiB",
                          bytes / 1048576.0);
    g->node_count = b->grid_count;
    g->cell_count = cells;
    g->list_len = list_len;
    g->plane_count = planes;
    g->ref_count = refs;
    g->leaf_count = leaves;
    g->lists[0] = 0;
    uint64_t cell_at = 0, list_at = 1;
    size_t plane_at = 0;
    for (uint32_t i = 0; i < b->grid_count; i++) {
        const bgrid *q = b->grids[i];
        ngrid_node *node = &g->nodes[i];
        node->frame = q->frame;
        node->cell_base = (uint32_t)cell_at;
        node->level = (uint32_t)q->level;
        for (int a = 0; a < 3; a++) {
            size_t np = (size_t)q->frame.res[a] + 1;
            memcpy(g->planes + plane_at, q->frame.planes[a], np * sizeof(float));
            node->frame.planes[a] = g->planes + plane_at;
            plane_at += np;
        }
        uint32_t next = q->first_child;
        for (uint64_t c = 0; c < q->cells.cell_count; c++) {
            uint32_t *word = &g->cells[cell_at + c];
            if (is_child_cell(b, q, &next, c)) {
                *word = NGRID_CHILD | next++;
                continue;
            }
            uint32_t n = cell_prims(q, (uint32_t)c);
            if (!n) {
                *word = 0;
                continue;
            }
            *word = (uint32_t)list_at;
            g->lists[list_at] = n;
            memcpy(g->lists + list_at + 1, q->cells.refs + q->cells.offsets[c], n * sizeof(uint32_t));
            list_at += 1 + (uint64_t)n;
        }
        cell_at += q->cells.cell_count;
        if (q->level + 1 > g->levels) g->levels = q->level + 1;
    }
    /* Step bound: every cell of a grid crossed, each one possibly holding
     * the most expensive child. Children come after their parents. */
    uint64_t *bound = calloc(b->grid_count, sizeof *bound);
    if (!bound) return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
    for (uint32_t i = b->grid_count; i-- > 0;) {
        const bgrid *q = b->grids[i];
        uint64_t worst = 0;
        for (uint32_t k = 0; k < q->child_count; k++)
            if (bound[q->first_child + k] > worst) worst = bound[q->first_child + k];
        uint64_t walk = (uint64_t)q->frame.res[0] + q->frame.res[1] + q->frame.res[2] + 3;
        bound[i] = worst >= UINT64_MAX / 2 / walk ? UINT64_MAX / 2 : walk * (1 + worst);
    }
    g->step_bound = bound[0];
    free(bound);
    return ACCEL_OK;
}

static void builder_free(builder *b)
{
    for (uint32_t i = 0; i < b->grid_count; i++) bgrid_free(b->grids[i]);
    free(b->grids);
}

/* ---- the kind -------------------------------------------------------------------- */

/* Builds over the primitive store's scene (every primitive live, local ids). */
static int build_over(const accel_scene *scene, const accel_params *params, int threads,
                      ngrid_accel **out, accel_build_stats *stats, accel_error *err)
{
    *out = NULL;
    builder b;
    memset(&b, 0, sizeof b);
    b.scene = scene;
    b.mode = (int)accel_param_num(params, "overlap") == 1 ? GRID_OVERLAP_BBOX : GRID_OVERLAP_EXACT;
    b.is_auto = accel_param_num(params, "auto") != 0.0;
    b.lookahead = accel_param_num(params, "lookahead") != 0.0;
    b.depth = (int)accel_param_num(params, "depth");
    b.sub_res = (int)accel_param_num(params, "sub_res");
    b.sub_lambda = accel_param_num(params, "sub_lambda");
    b.threshold = (uint32_t)accel_param_num(params, "threshold");
    b.costs.c_step = accel_param_num(params, "c_step");
    b.costs.c_isect = accel_param_num(params, "c_isect");
    b.max_bytes = accel_param_num(params, "max_mb") * 1048576.0;
    if (b.sub_res == 1)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: sub_res=1 makes sub-grids of one cell (use 0 or 2..256)");

    int res[3];
    int rc = grid_parse_res(accel_param_str(params, "res"), res, err);
    if (rc) return wrap_error(err, rc, "top level");
    box3 box = grid_frame_box(scene->bounds);
    if (res[0] == 0) {
        if (b.is_auto) {
            rc = ngrid_auto_top_res(scene, box, b.mode, b.lookahead && b.depth > 1, &b.costs,
                                    b.max_bytes, res, err);
            if (rc) return rc;
        } else {
            grid_resolution(scene->bounds, (double)scene->live_count,
                            accel_param_num(params, "lambda"), res);
        }
    }
    uint64_t cells;
    rc = grid_cell_count("nested_grid", res, b.max_bytes, &cells, err);
    if (rc) return rc;

    bgrid *top;
    rc = bgrid_new(box, res, 0, &top, err);
    if (rc) return rc;
    rc = grid_cells_build(&top->frame, scene, scene->live, scene->live_count, b.mode, threads,
                          b.max_bytes, &top->cells, err);
    if (rc) {
        bgrid_free(top);
        return wrap_error(err, rc, "top level");
    }
    rc = push_grid(&b, top, err);
    if (rc) {
        bgrid_free(top);
        return rc;
    }
    /* Level by level: the grids of level L are grids[begin, end). */
    uint32_t begin = 0, end = 1;
    for (int level = 0; !rc && level + 1 < b.depth && begin < end; level++) {
        rc = build_level(&b, begin, end, threads, err);
        begin = end;
        end = b.grid_count;
    }

    ngrid_accel *g = NULL;
    if (!rc) {
        g = calloc(1, sizeof *g);
        if (!g) rc = accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
    }
    if (!rc) {
        g->naive = params->naive;
        g->mailbox = accel_param_num(params, "mailbox") != 0.0;
        g->has_spheres = scene->sphere_count > 0;
        rc = flatten(&b, g, err);
    }
    builder_free(&b);
    if (rc) {
        ngrid_destroy(g);
        return rc;
    }

    memset(stats, 0, sizeof *stats);
    stats->bytes = ngrid_memory(g);
    stats->nodes = g->cell_count;
    stats->leaves = g->leaf_count;
    stats->refs = g->ref_count;
    stats->sah_cost = NAN;
    stats->depth = g->levels;
    for (int a = 0; a < 3; a++) stats->res[a] = res[a];
    *out = g;
    return ACCEL_OK;
}

static int ngrid_build(const accel_scene *scene, const accel_params *params, int threads,
                       void **out, accel_build_stats *stats, accel_error *err)
{
    *out = NULL;
    accel_prim_store store;
    int rc = accel_prim_store_build(scene, params->reorder, &store, err);
    if (rc) return rc;
    ngrid_accel *g;
    rc = build_over(&store.prims, params, threads, &g, stats, err);
    if (rc) {
        accel_prim_store_free(&store);
        return rc;
    }
    g->store = store;
    stats->bytes = ngrid_memory(g);
    *out = g;
    return ACCEL_OK;
}

void ngrid_get_view(const void *accel, ngrid_view *v)
{
    const ngrid_accel *g = accel;
    v->nodes = g->nodes;
    v->node_count = g->node_count;
    v->cells = g->cells;
    v->cell_count = g->cell_count;
    v->lists = g->lists;
    v->prim_id = g->store.scene_id;
    v->prim_count = g->store.prims.prim_count;
    v->list_len = g->list_len;
    v->ref_count = g->ref_count;
    v->levels = g->levels;
}

/* The conformance suite runs each: defaults, the cost model, a single
 * level (the regular grid), subdividing almost every cell (with a small
 * depth), never subdividing, bounding-box membership, no mailbox. */
static const char *const ngrid_variants[] = {
    "", "auto", "depth=1", "threshold=1,depth=2", "threshold=100000", "overlap=bbox,mailbox=0",
    NULL,
};

const accel_kind accel_kind_nested_grid = {
    .name = "nested_grid",
    .summary = "nested uniform grids: dense cells hold sub-grids, hierarchical 3D-DDA, auto mode "
               "from the step/intersect cost model",
    .step_name = "cells",
    .params = ngrid_params,
    .param_count = sizeof ngrid_params / sizeof ngrid_params[0],
    .variants = ngrid_variants,
    .build = ngrid_build,
    .intersect = ngrid_intersect,
    .occluded = ngrid_occluded,
    .memory = ngrid_memory,
    .destroy = ngrid_destroy,
};
