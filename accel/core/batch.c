/*
 * batch.c - the batch trace entry: accel_trace and accel_trace_occluded
 * hand a ray set to a kind's batch functions in chunks, over threads.
 *
 * Every chunk is traced by one call of the kind's batch function; per-thread
 * counters are summed after the join (no atomics in kernels), so results and
 * counts are identical for any thread count.
 */
#include <stdlib.h>
#include <string.h>

#include "accel.h"

typedef struct {
    const accel_kind *kind;
    const void *accel;
    const accel_ray *rays;
    accel_hit *hits;
    uint8_t *occluded;
    accel_counters *total;     /* NULL: uncounted */
    accel_counters per_thread[256];
} trace_job;

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
    if (j->hits)
        j->kind->intersect(j->accel, j->rays + begin, j->hits + begin, end - begin, c);
    else
        j->kind->occluded(j->accel, j->rays + begin, j->occluded + begin, end - begin, c);
    if (c) accel_counters_add(&j->per_thread[thread], c);
}

static void run_trace(trace_job *j, size_t count, int threads)
{
    if (threads < 1) threads = 1;
    if (threads > 256) threads = 256;
    if (j->total) memset(j->per_thread, 0, sizeof(accel_counters) * (size_t)threads);
    accel_parallel_for(count, ACCEL_CHUNK, threads, trace_chunk, j);
    if (j->total)
        for (int i = 0; i < threads; i++) accel_counters_add(j->total, &j->per_thread[i]);
}

void accel_trace(const accel_kind *kind, const void *accel, const accel_ray *rays, accel_hit *hits,
                 size_t count, int threads, accel_counters *counters)
{
    trace_job *j = calloc(1, sizeof *j);
    if (!j) abort();
    j->kind = kind;
    j->accel = accel;
    j->rays = rays;
    j->hits = hits;
    j->total = counters;
    run_trace(j, count, threads);
    free(j);
}

void accel_trace_occluded(const accel_kind *kind, const void *accel, const accel_ray *rays,
                          uint8_t *occluded, size_t count, int threads, accel_counters *counters)
{
    trace_job *j = calloc(1, sizeof *j);
    if (!j) abort();
    j->kind = kind;
    j->accel = accel;
    j->rays = rays;
    j->occluded = occluded;
    j->total = counters;
    run_trace(j, count, threads);
    free(j);
}
