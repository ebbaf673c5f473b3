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
    /* In double: an extent from -2e38 to 2e38 overflows a float, and an
     * infinite half-size made the flat axis -inf..inf (NaN padding, holes
     * on every ray). */
    double big = 0.0;
    for (int a = 0; a < 3; a++) big = fmax(big, (double)hi[a] - lo[a]);
    for (int a = 0; a < 3; a++) {
        if (hi[a] > lo[a]) continue;
        /* A flat axis: one thousandth of the largest extent, and at least
         * a few ulps of the coordinate so that lo < hi survives rounding;
         * within the finite floats. */
        double mag = fmax(fabs((double)lo[a]), fabs((double)hi[a]));
        double half = fmax(fmax(5e-4 * big, 8.0 * FLT_EPSILON * mag), FLT_MIN);
        lo[a] = (float)fmax((double)lo[a] - half, -FLT_MAX);
        hi[a] = (float)fmin((double)hi[a] + half, FLT_MAX);
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

/* COUNT: counts[cell]++; FILL: writes the reference; TALLY: one 64-bit
 * total in *offsets; COUNT_TALLY: counts[cell]++ and the total in *refs. */
typedef enum { VISIT_COUNT, VISIT_FILL, VISIT_TALLY, VISIT_COUNT_TALLY } visit_kind;

/* min/max as compare-and-select (fmin/fmax are library calls without fast-math). */
static inline double dmin(double a, double b) { return b < a ? b : a; }
static inline double dmax(double a, double b) { return b > a ? b : a; }

/*
 * Cells k in [k_lo, k_hi] of axis a whose padded slab, widened by slack,
 * meets [bmin, bmax]: written to *i..*j; returns 0 when there are none.
 */
static inline int slab_range(const grid_frame *f, int a, double bmin, double bmax, double slack,
                             int k_lo, int k_hi, int *i_out, int *j_out)
{
    const float *pl = f->planes[a];
    double pad = (double)f->pad[a] + slack;
    double g = (bmin - f->lo[a]) * f->inv_cell[a];
    int i = g >= k_hi ? k_hi : (g > k_lo ? (int)g : k_lo); /* also maps NaN to k_lo */
    while (i > k_lo && pl[i] + pad >= bmin) i--;
    while (i < k_hi && pl[i + 1] + pad < bmin) i++;
    g = (bmax - f->lo[a]) * f->inv_cell[a];
    int j = g >= k_hi ? k_hi : (g > k_lo ? (int)g : k_lo);
    while (j < k_hi && pl[j + 1] - pad <= bmax) j++;
    while (j > k_lo && pl[j] - pad > bmax) j--;
    if (j < i || pl[i + 1] + pad < bmin || pl[j] - pad > bmax) return 0;
    *i_out = i;
    *j_out = j;
    return 1;
}

static inline __attribute__((always_inline)) void
emit_cell(const grid_frame *f, int x, int y, int z, uint32_t prim, visit_kind kind, int atomic,
          uint32_t *offsets, uint32_t *refs)
{
    if (kind == VISIT_TALLY) { /* offsets holds one 64-bit total */
        ++*(uint64_t *)(void *)offsets;
        return;
    }
    uint32_t cell = (uint32_t)x + f->stride[1] * (uint32_t)y + f->stride[2] * (uint32_t)z;
    if (kind == VISIT_COUNT_TALLY) {
        offsets[cell]++;
        ++*(uint64_t *)(void *)refs;
        return;
    }
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

/*
 * Visits every cell primitive `prim` belongs to: counts it or writes it.
 * `kind` and `atomic` are constants in each caller.
 *
 * A primitive whose cell range has more than one cell along at most one
 * axis overlaps all of them (it is connected and spans its bounds along
 * that axis). Otherwise a triangle is clipped to each z slab of its range,
 * the clipped polygon to each y slab it reaches, and the x extent of what
 * remains gives the run of cells in that row (exact: the polygon is the
 * triangle's part in the row's slabs, and it is convex). The cost follows
 * the cells the triangle crosses, not the volume of its bounding box. A
 * sphere is tested per cell of its range against its surface.
 */
static inline __attribute__((always_inline)) void
visit_prim(const grid_frame *f, const accel_scene *s, uint32_t prim, grid_overlap mode,
           visit_kind kind, int atomic, uint32_t *offsets, uint32_t *refs)
{
    int lo[3], hi[3];
    if (!grid_cell_range(f, accel_prim_bounds(s, prim), lo, hi)) return;
    int spread = (hi[0] > lo[0]) + (hi[1] > lo[1]) + (hi[2] > lo[2]);
    if (mode != GRID_OVERLAP_EXACT || spread < 2) {
        for (int z = lo[2]; z <= hi[2]; z++)
            for (int y = lo[1]; y <= hi[1]; y++)
                for (int x = lo[0]; x <= hi[0]; x++)
                    emit_cell(f, x, y, z, prim, kind, atomic, offsets, refs);
        return;
    }
    if (prim >= s->tri_count) {
        const float *sphere = s->spheres + 4 * (size_t)(prim - s->tri_count);
        for (int z = lo[2]; z <= hi[2]; z++)
            for (int y = lo[1]; y <= hi[1]; y++)
                for (int x = lo[0]; x <= hi[0]; x++) {
                    double blo[3], bhi[3];
                    grid_cell_box(f, x, y, z, blo, bhi);
                    if (accel_overlap_sphere_surface_box(sphere, blo, bhi))
                        emit_cell(f, x, y, z, prim, kind, atomic, offsets, refs);
                }
        return;
    }
    const float *t = s->tris + 9 * (size_t)prim;
    double v[3][3], mag = 0.0;
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) {
            v[k][a] = t[3 * k + a];
            mag = dmax(mag, dmax(fabs(v[k][a]), dmax(fabs((double)f->lo[a]), fabs((double)f->hi[a]))));
        }
    /* Covers the rounding of the clipping, far below any padding. */
    const double slack = ACCEL_OVERLAP_SLACK * mag;
    const float *pz = f->planes[2], *py = f->planes[1];
    for (int z = lo[2]; z <= hi[2]; z++) {
        double in_z[8][3];
        int nz = accel_clip_slab((const double(*)[3])v, 3, 2, pz[z] - (double)f->pad[2] - slack,
                                 pz[z + 1] + (double)f->pad[2] + slack, in_z);
        if (!nz) continue;
        double ymin = in_z[0][1], ymax = in_z[0][1];
        for (int k = 1; k < nz; k++) ymin = dmin(ymin, in_z[k][1]), ymax = dmax(ymax, in_z[k][1]);
        int y0, y1;
        if (!slab_range(f, 1, ymin, ymax, slack, lo[1], hi[1], &y0, &y1)) continue;
        for (int y = y0; y <= y1; y++) {
            double in_zy[8][3];
            int n = accel_clip_slab((const double(*)[3])in_z, nz, 1,
                                    py[y] - (double)f->pad[1] - slack,
                                    py[y + 1] + (double)f->pad[1] + slack, in_zy);
            if (!n) continue;
            double xmin = in_zy[0][0], xmax = in_zy[0][0];
            for (int k = 1; k < n; k++) xmin = dmin(xmin, in_zy[k][0]), xmax = dmax(xmax, in_zy[k][0]);
            int x0, x1;
            if (!slab_range(f, 0, xmin, xmax, slack, lo[0], hi[0], &x0, &x1)) continue;
            for (int x = x0; x <= x1; x++) emit_cell(f, x, y, z, prim, kind, atomic, offsets, refs);
        }
    }
}

/* The i-th primitive of a pass: prims[i], or i itself for a NULL list. */
#define PRIM_AT(prims, i) ((prims) ? (prims)[i] : (uint32_t)(i))

typedef struct {
    const grid_frame *f;
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
            visit_prim(j->f, j->s, PRIM_AT(j->prims, i), j->mode, VISIT_COUNT, 1, j->offsets, NULL);
        else
            visit_prim(j->f, j->s, PRIM_AT(j->prims, i), j->mode, VISIT_FILL, 1, j->offsets,
                       j->refs);
    }
}

/* Primitives per work item of the parallel passes. */
#define GRID_PASS_CHUNK 1024

static void run_pass(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                     uint32_t prim_count, grid_overlap mode, visit_kind kind, uint32_t *offsets,
                     uint32_t *refs, int threads)
{
    if (threads <= 1 || prim_count <= GRID_PASS_CHUNK) {
        for (uint32_t i = 0; i < prim_count; i++) {
            if (kind == VISIT_COUNT)
                visit_prim(f, s, PRIM_AT(prims, i), mode, VISIT_COUNT, 0, offsets, NULL);
            else
                visit_prim(f, s, PRIM_AT(prims, i), mode, VISIT_FILL, 0, offsets, refs);
        }
        return;
    }
    pass_job j = {f, s, prims, mode, offsets, refs, kind};
    accel_parallel_for(prim_count, GRID_PASS_CHUNK, threads, pass_chunk, &j);
}

uint64_t grid_count_refs(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                         uint32_t prim_count, grid_overlap mode, uint64_t stop_above)
{
    uint64_t total = 0;
    for (uint32_t i = 0; i < prim_count && total <= stop_above; i++)
        visit_prim(f, s, PRIM_AT(prims, i), mode, VISIT_TALLY, 0, (uint32_t *)(void *)&total, NULL);
    return total;
}

void grid_count_pass(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                     uint32_t prim_count, grid_overlap mode, uint32_t *counts, int threads)
{
    run_pass(f, s, prims, prim_count, mode, VISIT_COUNT, counts, NULL, threads);
}

uint64_t grid_count_pass_upto(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                              uint32_t prim_count, grid_overlap mode, uint32_t *counts,
                              uint64_t stop_above)
{
    uint64_t total = 0;
    for (uint32_t i = 0; i < prim_count && total <= stop_above; i++)
        visit_prim(f, s, PRIM_AT(prims, i), mode, VISIT_COUNT_TALLY, 0, counts,
                   (uint32_t *)(void *)&total);
    return total;
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
    uint32_t *offsets = accel_alloc_large(cells + 1, sizeof *offsets, sizeof(void *));
    if (!offsets)
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for %llu cell offsets",
                          (unsigned long long)cells);
    memset(offsets, 0, (cells + 1) * sizeof *offsets);
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
    uint32_t *refs = accel_alloc_large(total ? total : 1, sizeof *refs, sizeof(void *));
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
