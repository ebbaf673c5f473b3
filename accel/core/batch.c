/*
 * batch.c - the batch trace entry: accel_trace and accel_trace_occluded
 * hand a ray set to a kind's batch functions in chunks, over threads.
 *
 * Every chunk is traced by one call of the kind's batch function; per-thread
 * counters are summed after the join (no atomics in kernels), so results and
 * counts are identical for any thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"

/* Counters are summed per thread; beyond this many threads, chunks share. */
#define BATCH_MAX_THREADS 256

typedef struct {
    const accel_kind *kind;
    const void *accel;
    const accel_ray *rays;
    accel_hit *hits;
    uint8_t *occluded;
    accel_counters *total;     /* NULL: uncounted */
    accel_counters *per_thread;
} trace_job;

/*
 * A direction whose largest component is under 2^-64 (all of it tiny, e.g.
 * 2^-125: hits at t ~ 1e38) overflows the kernels' 1/d and loses the hits a
 * slab test would see at such t (a hostile-ray audit: every kind but brute
 * missed them). Such a ray is traced as o + t' (d 2^k) with t' = t 2^-k,
 * 2^k bringing its largest component to [1, 2): the same line and the same
 * points, scaled exactly (powers of two; t bounds only lose bits if they
 * fall to subnormals), and each hit's t is scaled back. Ordinary rays are
 * only read: no copy, no change.
 */
static inline int tiny_dir(const accel_ray *r)
{
    /* plain compares (fmaxf is a libm call without -ffinite-math-only);
     * a NaN component is not tiny (the kernels miss such rays) */
    float x = fabsf(r->dx), y = fabsf(r->dy), z = fabsf(r->dz);
    return (x < 0x1p-64f) & (y < 0x1p-64f) & (z < 0x1p-64f) & ((x > 0.0f) | (y > 0.0f) | (z > 0.0f));
}

/* Copies the chunk with every tiny direction scaled by 2^k[i] (k[i] = 0
 * for the others). */
static void rescale(const accel_ray *rays, size_t n, accel_ray *out, int *k)
{
    for (size_t i = 0; i < n; i++) {
        out[i] = rays[i];
        k[i] = 0;
        if (!tiny_dir(&rays[i])) continue;
        float x = fabsf(rays[i].dx), y = fabsf(rays[i].dy), z = fabsf(rays[i].dz);
        float m = x > y ? x : y;
        k[i] = -ilogbf(m > z ? m : z);
        out[i].dx = ldexpf(rays[i].dx, k[i]), out[i].dy = ldexpf(rays[i].dy, k[i]);
        out[i].dz = ldexpf(rays[i].dz, k[i]);
        out[i].t_near = ldexpf(rays[i].t_near, -k[i]), out[i].t_far = ldexpf(rays[i].t_far, -k[i]);
    }
}

static void trace_chunk(void *p, size_t begin, size_t end, int thread)
{
    trace_job *j = p;
    accel_counters *c = NULL, local;
    if (j->total) {
        memset(&local, 0, sizeof local);
        local.ray_steps = j->total->ray_steps ? j->total->ray_steps + begin : NULL;
        local.ray_prims = j->total->ray_prims ? j->total->ray_prims + begin : NULL;
        c = &local;
    }
    size_t n = end - begin;
    const accel_ray *rays = j->rays + begin;
    accel_ray *scaled = NULL;
    int *k = NULL;
    /* |dx| alone first: almost never tiny, one predicted branch per ray
     * (the full test on every ray cost 3-5% of 8-wide primary packets) */
    int any = 0;
    for (size_t i = 0; i < n; i++)
        if (fabsf(rays[i].dx) < 0x1p-64f && tiny_dir(&rays[i])) {
            any = 1;
            break;
        }
    if (any) {
        scaled = malloc(n * sizeof *scaled), k = malloc(n * sizeof *k);
        if (scaled && k) rescale(rays, n, scaled, k), rays = scaled;
        /* without memory the rays go as they are: only such far hits are
         * lost, as before */
    }
    if (j->hits)
        j->kind->intersect(j->accel, rays, j->hits + begin, n, c);
    else
        j->kind->occluded(j->accel, rays, j->occluded + begin, n, c);
    if (rays == scaled && j->hits)
        for (size_t i = 0; i < n; i++)
            if (k[i] && j->hits[begin + i].prim != ACCEL_MISS)
                j->hits[begin + i].t = ldexpf(j->hits[begin + i].t, k[i]);
    free(scaled);
    free(k);
    if (c) accel_counters_add(&j->per_thread[thread], c);
}

size_t accel_trace_chunk(size_t count, int threads)
{
    /* About 16 chunks per thread so that a thread drawing cheap rays takes
     * more of them, in whole multiples of 64 rays (8x8 packets stay whole),
     * at most ACCEL_CHUNK. A fixed 4096 would leave a 5,000-ray job two
     * chunks, whatever the thread count. */
    if (threads <= 1) return ACCEL_CHUNK;
    size_t chunk = count / ((size_t)threads * 16);
    chunk = (chunk + 63) / 64 * 64;
    if (chunk < 64) chunk = 64;
    if (chunk > ACCEL_CHUNK) chunk = ACCEL_CHUNK;
    return chunk;
}

static void run_trace(trace_job *j, size_t count, int threads)
{
    if (threads < 1) threads = 1;
    if (threads > BATCH_MAX_THREADS) threads = BATCH_MAX_THREADS;
    accel_counters one;
    if (j->total) {
        /* Counted runs need one counter block per thread; without memory
         * for them the run is still right on one thread. */
        j->per_thread = threads > 1 ? calloc((size_t)threads, sizeof *j->per_thread) : NULL;
        if (!j->per_thread) {
            threads = 1;
            memset(&one, 0, sizeof one);
            j->per_thread = &one;
        }
    }
    accel_parallel_for(count, accel_trace_chunk(count, threads), threads, trace_chunk, j);
    if (j->total) {
        for (int i = 0; i < threads; i++) accel_counters_add(j->total, &j->per_thread[i]);
        if (j->per_thread != &one) free(j->per_thread);
    }
}

void accel_trace(const accel_kind *kind, const void *accel, const accel_ray *rays, accel_hit *hits,
                 size_t count, int threads, accel_counters *counters)
{
    trace_job j = {kind, accel, rays, hits, NULL, counters, NULL};
    run_trace(&j, count, threads);
}

void accel_trace_occluded(const accel_kind *kind, const void *accel, const accel_ray *rays,
                          uint8_t *occluded, size_t count, int threads, accel_counters *counters)
{
    trace_job j = {kind, accel, rays, NULL, occluded, counters, NULL};
    run_trace(&j, count, threads);
}
