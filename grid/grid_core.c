/*
 * grid_core.c - resolution rule, sizing, frame, cell ranges, membership and
 * the count / prefix-sum / fill passes of the shared grid API (grid_core.h).
 *
 * Storage follows the compact layout of Lagae & Dutre, "Compact, Fast and
 * Robust Grids for Ray Tracing", EGSR 2008: one offset per cell into a single
 * array of primitive ids, built by counting, a prefix sum and filling, with
 * no per-cell lists or pointers.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid_core.h"
#include "overlap.h"

/* ---- resolution and sizing ------------------------------------------------ */

void grid_resolution(box3 bounds, double prim_count, double lambda, int res[3])
{
    res[0] = res[1] = res[2] = 1;
    if (box3_is_empty(bounds) || !(prim_count > 0.0) || !(lambda > 0.0)) return;
    double d[3] = {(double)bounds.max.x - bounds.min.x, (double)bounds.max.y - bounds.min.y,
                   (double)bounds.max.z - bounds.min.z};
    int active[3];
    for (int a = 0; a < 3; a++) active[a] = d[a] > 0.0 && isfinite(d[a]);
    double n[3] = {1.0, 1.0, 1.0};
    /* At most three rounds: each one either succeeds or retires an axis. */
    for (int round = 0; round < 3; round++) {
        int k = 0;
        double log_v = 0.0;
        for (int a = 0; a < 3; a++)
            if (active[a]) {
                k++;
                log_v += log(d[a]);
            }
        if (k == 0) break;
        /* s = (lambda N / V)^(1/k), in logs so that no product overflows. */
        double log_s = (log(lambda) + log(prim_count) - log_v) / k;
        int worst = -1;
        for (int a = 0; a < 3; a++) {
            if (!active[a]) continue;
            n[a] = exp(log(d[a]) + log_s);
            if (n[a] < 1.0 && (worst < 0 || n[a] < n[worst])) worst = a;
        }
        if (worst < 0) break;
        active[worst] = 0;
        n[worst] = 1.0;
    }
    for (int a = 0; a < 3; a++) {
        double x = floor(n[a] + 0.5);
        res[a] = !(x >= 1.0) ? 1 : (x > GRID_MAX_AXIS_RES ? GRID_MAX_AXIS_RES : (int)x);
    }
}

int grid_parse_res(const char *text, int res[3], accel_error *err)
{
    res[0] = res[1] = res[2] = 0;
    if (!text || !*text || !strcmp(text, "auto")) return ACCEL_OK;
    long v[3];
    int count = 0;
    const char *p = text;
    int bad = 0;
    for (;;) {
        char *end;
        errno = 0;
        if (count == 3 || *p < '0' || *p > '9') { /* a digit must follow start and every 'x' */
            bad = 1;
            break;
        }
        v[count++] = strtol(p, &end, 10);
        if (errno == ERANGE) v[count - 1] = LONG_MAX;
        p = end;
        if (*p != 'x') break;
        p++;
    }
    if (bad || *p || (count != 1 && count != 3))
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "grid: res=%s: expected auto, N or NxNyNz (cells per axis)", text);
    for (int a = 0; a < 3; a++) {
        long x = v[count == 1 ? 0 : a];
        if (x < 1 || x > GRID_MAX_AXIS_RES)
            return accel_fail(err, ACCEL_ERR_RANGE,
                              "grid: res=%s: cells per axis must be in [1, %d]", text,
                              GRID_MAX_AXIS_RES);
        res[a] = (int)x;
    }
    return ACCEL_OK;
}

int grid_cell_count(const char *what, const int res[3], double max_bytes, uint64_t *cells,
                    accel_error *err)
{
    for (int a = 0; a < 3; a++)
        if (res[a] < 1 || res[a] > GRID_MAX_AXIS_RES)
            return accel_fail(err, ACCEL_ERR_RANGE, "%s: %d cells on axis %d (accepted 1..%d)",
                              what, res[a], a, GRID_MAX_AXIS_RES);
    /* Each factor is at most 2^16, so the product fits 48 bits. */
    uint64_t n = (uint64_t)res[0] * (uint64_t)res[1] * (uint64_t)res[2];
    double bytes = (double)(n + 1) * sizeof(uint32_t) + (double)grid_plane_count(res) * sizeof(float);
    if (n >= UINT32_MAX)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "%s: %dx%dx%d = %llu cells exceed the 32-bit cell index limit", what,
                          res[0], res[1], res[2], (unsigned long long)n);
    if (bytes > max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "%s: %dx%dx%d = %llu cells need %.1f MiB of offsets, above the limit "
                          "of %.1f MiB (lower lambda or res, or raise max_mb)",
                          what, res[0], res[1], res[2], (unsigned long long)n, bytes / 1048576.0,
                          max_bytes / 1048576.0);
    *cells = n;
    return ACCEL_OK;
}

/* ---- the frame -------------------------------------------------------------- */

box3 grid_frame_box(box3 bounds)
{
    if (box3_is_empty(bounds)) {
        box3 unit = {{0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}};
        return unit;
    }
    float lo[3] = {bounds.min.x, bounds.min.y, bounds.min.z};
    float hi[3] = {bounds.max.x, bounds.max.y, bounds.max.z};
    float big = 0.0f;
    for (int a = 0; a < 3; a++) big = maxf(big, hi[a] - lo[a]);
    for (int a = 0; a < 3; a++) {
        if (hi[a] > lo[a]) continue;
        /* A flat axis: one thousandth of the largest extent, and at least
         * a few ulps of the coordinate so that lo < hi survives rounding. */
        float mag = maxf(fabsf(lo[a]), fabsf(hi[a]));
        float half = maxf(5e-4f * big, 8.0f * FLT_EPSILON * mag);
        half = maxf(half, FLT_MIN);
        lo[a] -= half;
        hi[a] += half;
    }
    box3 b = {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    return b;
}

void grid_frame_init(grid_frame *f, box3 box, const int res[3], float *planes)
{
    const float lo[3] = {box.min.x, box.min.y, box.min.z};
    const float hi[3] = {box.max.x, box.max.y, box.max.z};
    float *p = planes;
    for (int a = 0; a < 3; a++) {
        int n = res[a];
        double ext = (double)hi[a] - lo[a];
        double mag = fabs((double)lo[a]) > fabs((double)hi[a]) ? fabs((double)lo[a]) : fabs((double)hi[a]);
        /* Cells narrower than the rounding margin of their coordinates buy
         * nothing (every primitive in one is also padded into its
         * neighbours) and, far from the origin, make every primitive fall
         * into every cell: the resolution is capped so that a cell is at
         * least twice the ulp margin wide. Callers sized planes for res[a],
         * which is never exceeded. */
        double ulp_margin = GRID_PAD_ULPS * FLT_EPSILON * mag;
        if (ulp_margin > 0 && ext / n < 2.0 * ulp_margin) {
            double cap = floor(ext / (2.0 * ulp_margin));
            n = cap < 1.0 ? 1 : (int)cap;
        }
        f->lo[a] = lo[a];
        f->hi[a] = hi[a];
        f->res[a] = n;
        f->inv_cell[a] = (float)(n / ext);
        f->pad[a] = (float)(ext / n * GRID_PAD_CELLS + GRID_PAD_ULPS * FLT_EPSILON * mag);
        for (int k = 0; k <= n; k++) p[k] = (float)((double)lo[a] + ext * k / n);
        p[0] = lo[a];
        p[n] = hi[a];

        f->planes[a] = p;
        p += n + 1;
    }
    f->stride[0] = 1;
    f->stride[1] = (uint32_t)f->res[0];
    f->stride[2] = (uint32_t)f->res[0] * (uint32_t)f->res[1];
}

int grid_cell_range(const grid_frame *f, box3 b, int lo[3], int hi[3])
{
    const float bmin[3] = {b.min.x, b.min.y, b.min.z};
    const float bmax[3] = {b.max.x, b.max.y, b.max.z};
    for (int a = 0; a < 3; a++) {
        const int n = f->res[a];
        const float *pl = f->planes[a];
        const float pad = f->pad[a];
        if (!(bmin[a] <= bmax[a]) || bmax[a] < pl[0] - pad || bmin[a] > pl[n] + pad) return 0;
        float g = (bmin[a] - f->lo[a]) * f->inv_cell[a];
        int i = g >= (float)n ? n - 1 : (g > 0.0f ? (int)g : 0);
        /* Lowest cell whose padded top plane reaches bmin. */
        while (i > 0 && pl[i] + pad >= bmin[a]) i--;
        while (i < n - 1 && pl[i + 1] + pad < bmin[a]) i++;
        g = (bmax[a] - f->lo[a]) * f->inv_cell[a];
        int j = g >= (float)n ? n - 1 : (g > 0.0f ? (int)g : 0);
        /* Highest cell whose padded bottom plane reaches bmax. */
        while (j < n - 1 && pl[j + 1] - pad <= bmax[a]) j++;
        while (j > 0 && pl[j] - pad > bmax[a]) j--;
        if (j < i) j = i;
        lo[a] = i;
        hi[a] = j;
    }
    return 1;
}

void grid_cell_box(const grid_frame *f, int x, int y, int z, double lo[3], double hi[3])
{
    const int idx[3] = {x, y, z};
    for (int a = 0; a < 3; a++) {
        lo[a] = (double)f->planes[a][idx[a]] - f->pad[a];
        hi[a] = (double)f->planes[a][idx[a] + 1] + f->pad[a];
    }
}

/* ---- membership ------------------------------------------------------------- */

typedef enum { VISIT_COUNT, VISIT_FILL } visit_kind;

/*
 * Visits every cell primitive `prim` belongs to: counts it or writes it.
 * A primitive whose cell range has more than one cell along at most one
 * axis overlaps all of them (it is connected and spans its bounds along that
 * axis), so exact tests run only for ranges that extend along two or three
 * axes. Spelled once; `kind` and `atomic` are constants in each caller.
 */
static inline __attribute__((always_inline)) void
visit_prim(const grid_frame *f, const double cell_half[3], const accel_scene *s, uint32_t prim,
           grid_overlap mode, visit_kind kind, int atomic, uint32_t *offsets, uint32_t *refs)
{
    int lo[3], hi[3];
    if (!grid_cell_range(f, accel_prim_bounds(s, prim), lo, hi)) return;
    int spread = (hi[0] > lo[0]) + (hi[1] > lo[1]) + (hi[2] > lo[2]);
    int exact = mode == GRID_OVERLAP_EXACT && spread >= 2;
    int is_tri = prim < s->tri_count;
    accel_tri_cells tri;
    const float *sphere = NULL;
    if (exact) {
        /* Triangles: each cell's padded box lies within the box of half-size
         * cell_half around its centre, which is tested instead (a superset:
         * still conservative). */
        if (is_tri)
            accel_tri_cells_prep(&tri, s->tris + 9 * (size_t)prim, cell_half);
        else
            sphere = s->spheres + 4 * (size_t)(prim - s->tri_count);
    }
    for (int z = lo[2]; z <= hi[2]; z++)
        for (int y = lo[1]; y <= hi[1]; y++)
            for (int x = lo[0]; x <= hi[0]; x++) {
                if (exact) {
                    int hit;
                    if (is_tri) {
                        const double c[3] = {
                            0.5 * ((double)f->planes[0][x] + f->planes[0][x + 1]),
                            0.5 * ((double)f->planes[1][y] + f->planes[1][y + 1]),
                            0.5 * ((double)f->planes[2][z] + f->planes[2][z + 1])};
                        hit = accel_tri_cells_overlap(&tri, c);
                    } else {
                        double blo[3], bhi[3];
                        grid_cell_box(f, x, y, z, blo, bhi);
                        hit = accel_overlap_sphere_box(sphere, blo, bhi);
                    }
                    if (!hit) continue;
                }
                uint32_t cell = (uint32_t)x + f->stride[1] * (uint32_t)y + f->stride[2] * (uint32_t)z;
                if (kind == VISIT_COUNT) {
                    if (atomic)
                        __atomic_fetch_add(&offsets[cell], 1u, __ATOMIC_RELAXED);
                    else
                        offsets[cell]++;
                } else {
                    uint32_t at = atomic ? __atomic_fetch_add(&offsets[cell], 1u, __ATOMIC_RELAXED)
                                         : offsets[cell]++;
                    refs[at] = prim;
                }
            }
}

/* The i-th primitive of a pass: prims[i], or i itself for a NULL list. */
#define PRIM_AT(prims, i) ((prims) ? (prims)[i] : (uint32_t)(i))

/* Largest padded cell half-size per axis (cells differ by float rounding). */
static void largest_half(const grid_frame *f, double half[3])
{
    for (int a = 0; a < 3; a++) {
        const float *pl = f->planes[a];
        double h = 0.0;
        for (int k = 0; k < f->res[a]; k++) h = fmax(h, 0.5 * ((double)pl[k + 1] - pl[k]));
        half[a] = h + f->pad[a];
    }
}

typedef struct {
    const grid_frame *f;
    double cell_half[3];
    const accel_scene *s;
    const uint32_t *prims;
    grid_overlap mode;
    uint32_t *offsets;
    uint32_t *refs;
    visit_kind kind;
} pass_job;

static void pass_chunk(void *ctx, size_t begin, size_t end, int thread)
{
    (void)thread;
    const pass_job *j = ctx;
    for (size_t i = begin; i < end; i++) {
        if (j->kind == VISIT_COUNT)
            visit_prim(j->f, j->cell_half, j->s, PRIM_AT(j->prims, i), j->mode, VISIT_COUNT, 1,
                       j->offsets, NULL);
        else
            visit_prim(j->f, j->cell_half, j->s, PRIM_AT(j->prims, i), j->mode, VISIT_FILL, 1,
                       j->offsets, j->refs);
    }
}

/* Primitives per work item of the parallel passes. */
#define GRID_PASS_CHUNK 1024

static void run_pass(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                     uint32_t prim_count, grid_overlap mode, visit_kind kind, uint32_t *offsets,
                     uint32_t *refs, int threads)
{
    double half[3];
    largest_half(f, half);
    if (threads <= 1 || prim_count <= GRID_PASS_CHUNK) {
        for (uint32_t i = 0; i < prim_count; i++) {
            if (kind == VISIT_COUNT)
                visit_prim(f, half, s, PRIM_AT(prims, i), mode, VISIT_COUNT, 0, offsets, NULL);
            else
                visit_prim(f, half, s, PRIM_AT(prims, i), mode, VISIT_FILL, 0, offsets, refs);
        }
        return;
    }
    pass_job j = {f, {half[0], half[1], half[2]}, s, prims, mode, offsets, refs, kind};
    accel_parallel_for(prim_count, GRID_PASS_CHUNK, threads, pass_chunk, &j);
}

void grid_count_pass(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                     uint32_t prim_count, grid_overlap mode, uint32_t *counts, int threads)
{
    run_pass(f, s, prims, prim_count, mode, VISIT_COUNT, counts, NULL, threads);
}

/* ---- prefix sum --------------------------------------------------------------- */

/* Cells per block of the parallel scan. */
#define GRID_SCAN_BLOCK 65536

typedef struct {
    uint32_t *a;
    uint64_t n;
    uint64_t *block_sum; /* pass 1: block totals; pass 2: block start offsets */
    int add;             /* 0: sum blocks, 1: write offsets */
} scan_job;

static void scan_chunk(void *ctx, size_t begin, size_t end, int thread)
{
    (void)thread;
    scan_job *j = ctx;
    for (size_t b = begin; b < end; b++) {
        uint64_t lo = (uint64_t)b * GRID_SCAN_BLOCK;
        uint64_t hi = lo + GRID_SCAN_BLOCK < j->n ? lo + GRID_SCAN_BLOCK : j->n;
        if (!j->add) {
            uint64_t sum = 0;
            for (uint64_t i = lo; i < hi; i++) sum += j->a[i];
            j->block_sum[b] = sum;
        } else {
            uint64_t run = j->block_sum[b];
            for (uint64_t i = lo; i < hi; i++) {
                uint32_t c = j->a[i];
                j->a[i] = (uint32_t)run;
                run += c;
            }
        }
    }
}

int grid_prefix_sum(uint32_t *a, uint64_t n, int threads, uint64_t *total, accel_error *err)
{
    uint64_t blocks = (n + GRID_SCAN_BLOCK - 1) / GRID_SCAN_BLOCK;
    uint64_t *sums = threads > 1 && blocks > 1 ? malloc(blocks * sizeof *sums) : NULL;
    uint64_t sum = 0;
    if (sums) {
        scan_job j = {a, n, sums, 0};
        accel_parallel_for(blocks, 1, threads, scan_chunk, &j);
        for (uint64_t b = 0; b < blocks; b++) {
            uint64_t s = sums[b];
            sums[b] = sum;
            sum += s;
        }
    } else {
        for (uint64_t i = 0; i < n; i++) sum += a[i];
    }
    if (sum > UINT32_MAX) {
        free(sums);
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "grid: %llu primitive references exceed the 32-bit offset limit "
                          "(lower lambda or res)",
                          (unsigned long long)sum);
    }
    if (sums) {
        scan_job j = {a, n, sums, 1};
        accel_parallel_for(blocks, 1, threads, scan_chunk, &j);
        free(sums);
    } else {
        uint32_t run = 0;
        for (uint64_t i = 0; i < n; i++) {
            uint32_t c = a[i];
            a[i] = run;
            run += c;
        }
    }
    a[n] = (uint32_t)sum;
    *total = sum;
    return ACCEL_OK;
}

/* ---- fill pass and per-cell sort ---------------------------------------------- */

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

static void sort_ids(uint32_t *v, uint32_t n)
{
    if (n > 24) {
        qsort(v, n, sizeof *v, cmp_u32);
        return;
    }
    for (uint32_t i = 1; i < n; i++) {
        uint32_t x = v[i], k = i;
        while (k > 0 && v[k - 1] > x) {
            v[k] = v[k - 1];
            k--;
        }
        v[k] = x;
    }
}

typedef struct {
    const uint32_t *offsets;
    uint32_t *refs;
} sort_job;

static void sort_chunk(void *ctx, size_t begin, size_t end, int thread)
{
    (void)thread;
    sort_job *j = ctx;
    for (size_t c = begin; c < end; c++)
        sort_ids(j->refs + j->offsets[c], j->offsets[c + 1] - j->offsets[c]);
}

static int ids_increasing(const uint32_t *prims, uint32_t n)
{
    if (!prims) return 1;
    for (uint32_t i = 1; i < n; i++)
        if (prims[i] <= prims[i - 1]) return 0;
    return 1;
}

void grid_fill_pass(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                    uint32_t prim_count, grid_overlap mode, uint32_t *offsets, uint32_t *refs,
                    int threads)
{
    uint64_t cells = (uint64_t)f->res[0] * (uint64_t)f->res[1] * (uint64_t)f->res[2];
    /* offsets[c] serves as cell c's write cursor; afterwards it holds the
     * end of c, which is the start of c+1: shift back by one. */
    run_pass(f, s, prims, prim_count, mode, VISIT_FILL, offsets, refs, threads);
    memmove(offsets + 1, offsets, cells * sizeof *offsets);
    offsets[0] = 0;
    /* One thread writes each cell's list in input order: already sorted for
     * an increasing input. Several threads interleave: sort every cell. */
    if (threads > 1 && prim_count > GRID_PASS_CHUNK) {
        sort_job j = {offsets, refs};
        accel_parallel_for(cells, 4096, threads, sort_chunk, &j);
    } else if (!ids_increasing(prims, prim_count)) {
        sort_job j = {offsets, refs};
        sort_chunk(&j, 0, cells, 0);
    }
}

int grid_cells_build(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                     uint32_t prim_count, grid_overlap mode, int threads, double max_bytes,
                     grid_cells *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t cells = (uint64_t)f->res[0] * (uint64_t)f->res[1] * (uint64_t)f->res[2];
    if (cells >= UINT32_MAX || (double)(cells + 1) * sizeof(uint32_t) > max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE, "grid: %llu cells exceed the memory limit",
                          (unsigned long long)cells);
    uint32_t *offsets = calloc(cells + 1, sizeof *offsets);
    if (!offsets)
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for %llu cell offsets",
                          (unsigned long long)cells);
    grid_count_pass(f, s, prims, prim_count, mode, offsets, threads);
    uint64_t total;
    int rc = grid_prefix_sum(offsets, cells, threads, &total, err);
    if (rc) {
        free(offsets);
        return rc;
    }
    double bytes = ((double)cells + 1.0 + (double)total) * sizeof(uint32_t);
    if (bytes > max_bytes) {
        free(offsets);
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "grid: %llu cells and %llu references need %.1f MiB, above the limit of "
                          "%.1f MiB (lower lambda or res, or raise max_mb)",
                          (unsigned long long)cells, (unsigned long long)total, bytes / 1048576.0,
                          max_bytes / 1048576.0);
    }
    uint32_t *refs = malloc((total ? total : 1) * sizeof *refs);
    if (!refs) {
        free(offsets);
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for %llu references",
                          (unsigned long long)total);
    }
    grid_fill_pass(f, s, prims, prim_count, mode, offsets, refs, threads);
    out->offsets = offsets;
    out->refs = refs;
    out->cell_count = cells;
    out->ref_count = total;
    return ACCEL_OK;
}

void grid_cells_free(grid_cells *c)
{
    free(c->offsets);
    free(c->refs);
    memset(c, 0, sizeof *c);
}
