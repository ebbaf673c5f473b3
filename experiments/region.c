/*
 * region.c - timing per screen region (region.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "region.h"

#define MAX_CFG 64
#define MAX_TILES 64

static double median_of(double *v, int n)
{
    for (int i = 1; i < n; i++) /* insertion sort: a handful of rounds */
        for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
            double t = v[j];
            v[j] = v[j - 1], v[j - 1] = t;
        }
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The rays of each tile, copied out of the primary set. */
static int split_tiles(const rays_set *pr, int regions, accel_ray **tile, size_t *count)
{
    int w = pr->width, h = pr->height, tiles = regions * regions;
    memset(count, 0, (size_t)tiles * sizeof *count);
    for (int q = 0; q < tiles; q++) tile[q] = malloc((pr->count ? pr->count : 1) * sizeof **tile);
    for (int q = 0; q < tiles; q++)
        if (!tile[q]) return -1;
    for (size_t i = 0; i < pr->count; i++) {
        uint32_t px = pr->pixel[i];
        int q = (int)((px % (uint32_t)w) * (uint32_t)regions / (uint32_t)w) +
                regions * (int)((px / (uint32_t)w) * (uint32_t)regions / (uint32_t)h);
        if (q >= tiles) q = tiles - 1;
        tile[q][count[q]++] = pr->rays[i];
    }
    return 0;
}

/* The choice on the odd rounds: a configuration per tile and one for all. */
static void choose(double (*t)[MAX_CFG][MAX_TILES], int rounds, int n, int tiles, int *per_tile,
                   int *single)
{
    double med[MAX_CFG][MAX_TILES], v[EXP_MAX_SAMPLES];
    for (int c = 0; c < n; c++)
        for (int q = 0; q < tiles; q++) {
            int k = 0;
            for (int r = 1; r < rounds; r += 2) v[k++] = t[r][c][q];
            med[c][q] = median_of(v, k);
        }
    double best = INFINITY;
    for (int c = 0; c < n; c++) {
        double s = 0;
        for (int q = 0; q < tiles; q++) s += med[c][q];
        if (s < best) best = s, *single = c;
    }
    for (int q = 0; q < tiles; q++) {
        per_tile[q] = 0;
        for (int c = 1; c < n; c++)
            if (med[c][q] < med[per_tile[q]][q]) per_tile[q] = c;
    }
}

int exp_region_time(exp_ctx *x, const exp_group *g, const int *cfgs, int n, int regions,
                    int half_rounds, exp_region_result *out)
{
    const rays_set *pr = &g->sets->primary;
    int tiles = regions * regions, rounds = 2 * half_rounds;
    memset(out, 0, sizeof *out);
    if (n < 2 || n > MAX_CFG || tiles > MAX_TILES || rounds > EXP_MAX_SAMPLES || !pr->pixel ||
        pr->width <= 0 || pr->height <= 0)
        return -1;
    accel_ray *tile[MAX_TILES] = {0};
    size_t count[MAX_TILES];
    double (*t)[MAX_CFG][MAX_TILES] = calloc((size_t)rounds, sizeof *t);
    accel_hit *hits = malloc((pr->count ? pr->count : 1) * sizeof *hits);
    int rc = -1;
    if (t && hits && split_tiles(pr, regions, tile, count) == 0) {
        bench_progress_begin(x->progress, "time per screen region", 0, 0);
        /* A warm-up pass sizes each sample: passes of one tile repeated to
         * last about half a millisecond (a tile's single pass can be a few
         * microseconds, under the timer's and the scheduler's noise). */
        static int reps[MAX_CFG][MAX_TILES];
        for (int c = 0; c < n; c++)
            for (int q = 0; q < tiles; q++) {
                const exp_cfg *cf = &g->cfg[cfgs[c]];
                double t0 = accel_now_ms();
                if (count[q]) accel_trace(cf->kind, cf->accel, tile[q], hits, count[q], x->threads, NULL);
                double ms = accel_now_ms() - t0;
                reps[c][q] = ms >= 0.5 ? 1 : ms <= 0.5 / 64 ? 64 : (int)ceil(0.5 / ms);
            }
        uint64_t seed = 0x9E3779B97F4A7C15ull;
        for (int r = 0; r < rounds; r++) {
            int order[MAX_CFG];
            for (int k = 0; k < n; k++) order[k] = k;
            for (int k = n - 1; k > 0; k--) { /* a fresh order each round (Fisher-Yates) */
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                int j = (int)((seed >> 33) % (uint64_t)(k + 1)), tmp = order[k];
                order[k] = order[j], order[j] = tmp;
            }
            /* Tile by tile, every configuration in turn (the round's order,
             * reversed on every other tile): the times a tile compares lie
             * within a few milliseconds, so a slow spell of the host (0.2-1
             * s, engine/harness.h) scales all of them alike instead of
             * falling on some configurations' whole passes. */
            for (int q = 0; q < tiles; q++) {
                if (!count[q]) continue;
                for (int k = 0; k < n; k++) {
                    int c = order[q % 2 ? n - 1 - k : k];
                    const exp_cfg *cf = &g->cfg[cfgs[c]];
                    /* untimed: this tile's part of the structure back in the caches */
                    accel_trace(cf->kind, cf->accel, tile[q], hits, count[q], x->threads, NULL);
                    double t0 = accel_now_ms();
                    for (int i = 0; i < reps[c][q]; i++)
                        accel_trace(cf->kind, cf->accel, tile[q], hits, count[q], x->threads, NULL);
                    t[r][c][q] = (accel_now_ms() - t0) / reps[c][q];
                }
            }
        }
        bench_progress_end(x->progress);
        int per_tile[MAX_TILES], single = 0, used[MAX_CFG] = {0};
        choose(t, rounds, n, tiles, per_tile, &single);
        double ratio[EXP_MAX_SAMPLES];
        int m = 0;
        for (int r = 0; r < rounds; r += 2) { /* judged on the even rounds */
            double a = 0, b = 0;
            for (int q = 0; q < tiles; q++) a += t[r][single][q], b += t[r][per_tile[q]][q];
            if (b > 0) ratio[m++] = a / b;
        }
        for (int q = 0; q < tiles; q++) used[per_tile[q]] = 1;
        for (int c = 0; c < n; c++) out->chosen += used[c];
        exp_est_of(ratio, m, &out->gain);
        out->best_single = single, out->rounds = m;
        rc = m ? 0 : -1;
    }
    for (int q = 0; q < tiles; q++) free(tile[q]);
    free(t);
    free(hits);
    return rc;
}
