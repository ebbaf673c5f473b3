/*
 * grid_skip.c - the tables behind empty-space skipping (grid_skip.h): the
 * proximity cloud (per-cell Chebyshev distance to the nearest non-empty
 * cell, Cohen & Sheffer 1994) and the macro-cell empty flags; and the
 * occupancy of GRID_MACRO^3 blocks that the packet walk (grid_packet_trace.c)
 * skips empty layers with.
 *
 * The distance transform is separable (Meijster, Roerdink & Hesselink,
 * ISMM 2000): pass 1 gives, per row along x, the distance to the nearest
 * non-empty cell of the row; passes 2 and 3 apply along y, then z, the 1D
 * min-max transform f(u) = min_i max(|u - i|, g(i)), whose composition is
 * the 3D Chebyshev distance. Each 1D transform is the lower envelope of the
 * functions x -> max(|x - i|, g(i)), found with a stack in one forward
 * scan and read back in one backward scan (the paper's chessboard case).
 * Capping at 255 commutes with every pass (min(f, C) = transform of
 * min(g, C)), so the table is bytes from the start.
 */
#include <stdlib.h>
#include <string.h>

#include "grid_impl.h"

typedef struct {
    const grid_frame *f;
    const uint32_t *offsets;
    uint8_t *dist;
    int axis; /* the pass: 0 (x), 1 (y) or 2 (z) */
    int failed;
} cloud_job;

/* f(x, i) and Sep(i, u) of Meijster et al. for the chessboard metric:
 * Sep is the last x at which i's function is still <= u's (i < u). */
static inline int cheb_f(int x, int i, const int *g)
{
    int dx = x > i ? x - i : i - x;
    return dx > g[i] ? dx : g[i];
}

static inline int cheb_sep(int i, int u, const int *g)
{
    int mid = (i + u) / 2;
    if (g[i] <= g[u]) return i + g[u] > mid ? i + g[u] : mid;
    return u - g[i] < mid ? u - g[i] : mid;
}

/* In place along one line of m bytes spaced `stride` apart; g, s, t are
 * scratch of m ints. */
static void minmax_line(uint8_t *line, size_t stride, int m, int *g, int *s, int *t)
{
    for (int u = 0; u < m; u++) g[u] = line[(size_t)u * stride];
    int q = 0;
    s[0] = 0;
    t[0] = 0;
    for (int u = 1; u < m; u++) {
        while (q >= 0 && cheb_f(t[q], s[q], g) > cheb_f(t[q], u, g)) q--;
        if (q < 0) {
            q = 0;
            s[0] = u;
        } else {
            int w = 1 + cheb_sep(s[q], u, g);
            if (w < m) {
                q++;
                s[q] = u;
                t[q] = w;
            }
        }
    }
    for (int u = m - 1; u >= 0; u--) {
        int v = cheb_f(u, s[q], g);
        line[(size_t)u * stride] = (uint8_t)(v < GRID_SKIP_CAP ? v : GRID_SKIP_CAP);
        if (u == t[q]) q--;
    }
}

/* Lines of the pass: rows along x (pass 0), columns along y (1), along z (2),
 * numbered over the two other axes. */
static void cloud_chunk(void *ctx, size_t begin, size_t end, int thread)
{
    (void)thread;
    cloud_job *j = ctx;
    const grid_frame *f = j->f;
    const int nx = f->res[0];
    const int m = f->res[j->axis];
    int *scratch = j->axis ? malloc(3 * (size_t)m * sizeof *scratch) : NULL;
    if (j->axis && !scratch) {
        __atomic_store_n(&j->failed, 1, __ATOMIC_RELAXED);
        return;
    }
    for (size_t line = begin; line < end; line++) {
        if (j->axis == 0) {
            /* Distance along the row to its nearest non-empty cell. */
            size_t c0 = line * (size_t)nx;
            const uint32_t *o = j->offsets + c0;
            uint8_t *row = j->dist + c0;
            int run = GRID_SKIP_CAP;
            for (int x = 0; x < nx; x++) {
                run = o[x] != o[x + 1] ? 0 : (run < GRID_SKIP_CAP ? run + 1 : GRID_SKIP_CAP);
                row[x] = (uint8_t)run;
            }
            run = GRID_SKIP_CAP;
            for (int x = nx - 1; x >= 0; x--) {
                run = row[x] == 0 ? 0 : (run < GRID_SKIP_CAP ? run + 1 : GRID_SKIP_CAP);
                if (run < row[x]) row[x] = (uint8_t)run;
            }
        } else if (j->axis == 1) {
            size_t x = line % (size_t)nx, z = line / (size_t)nx;
            minmax_line(j->dist + x + z * f->stride[2], f->stride[1], m, scratch, scratch + m,
                        scratch + 2 * (size_t)m);
        } else {
            minmax_line(j->dist + line, f->stride[2], m, scratch, scratch + m,
                        scratch + 2 * (size_t)m);
        }
    }
    free(scratch);
}

int grid_skip_cloud(const grid_frame *f, const uint32_t *offsets, uint8_t *dist, int threads,
                    accel_error *err)
{
    const size_t nx = (size_t)f->res[0], ny = (size_t)f->res[1], nz = (size_t)f->res[2];
    const size_t lines[3] = {ny * nz, nx * nz, nx * ny};
    for (int axis = 0; axis < 3; axis++) {
        if (axis > 0 && f->res[axis] == 1) continue; /* a single cell: f = g */
        cloud_job j = {f, offsets, dist, axis, 0};
        accel_parallel_for(lines[axis], 256, threads, cloud_chunk, &j);
        if (j.failed)
            return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for the proximity cloud");
    }
    return ACCEL_OK;
}

void grid_skip_macro(const grid_frame *f, const uint32_t *offsets, int shift, uint8_t *empty)
{
    int mres[3];
    grid_skip_macro_res(f->res, shift, mres);
    size_t count = (size_t)mres[0] * mres[1] * mres[2];
    memset(empty, 1, count);
    uint32_t c = 0;
    for (int z = 0; z < f->res[2]; z++)
        for (int y = 0; y < f->res[1]; y++) {
            size_t row = (size_t)mres[0] * ((size_t)(y >> shift) + (size_t)mres[1] * (z >> shift));
            for (int x = 0; x < f->res[0]; x++, c++)
                if (offsets[c] != offsets[c + 1]) empty[row + (x >> shift)] = 0;
        }
}

/* ---- traverse=packet: occupied blocks of GRID_MACRO^3 cells ---------------- */

int grid_macro_build(grid_accel *g, accel_error *err)
{
    const grid_frame *f = &g->frame;
    const int M = GRID_MACRO;
    uint64_t n = 1;
    for (int a = 0; a < 3; a++) {
        g->macro_res[a] = (f->res[a] + M - 1) / M;
        n *= (uint64_t)g->macro_res[a];
    }
    g->macro = calloc(n, 1);
    if (!g->macro) return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for macro cells");
    for (int z = 0; z < f->res[2]; z++)
        for (int y = 0; y < f->res[1]; y++)
            for (int x = 0; x < f->res[0]; x++) {
                const uint64_t c = (uint64_t)x + (uint64_t)f->stride[1] * y + (uint64_t)f->stride[2] * z;
                if (g->cells.offsets[c] != g->cells.offsets[c + 1])
                    g->macro[x / M + (size_t)g->macro_res[0] * (y / M + (size_t)g->macro_res[1] * (z / M))] = 1;
            }
    return ACCEL_OK;
}

int grid_macro_any(const grid_accel *g, int K, int a1, int a2, int layer, const int lo[2],
                   const int hi[2])
{
    const int M = GRID_MACRO;
    size_t st[3];
    st[0] = 1, st[1] = (size_t)g->macro_res[0], st[2] = st[1] * (size_t)g->macro_res[1];
    for (int j = lo[1] / M; j <= hi[1] / M; j++)
        for (int i = lo[0] / M; i <= hi[0] / M; i++)
            if (g->macro[(size_t)layer * st[K] + (size_t)j * st[a2] + (size_t)i * st[a1]]) return 1;
    return 0;
}
