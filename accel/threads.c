/*
 * threads.c - a dynamic parallel-for on pthreads and the batch trace entry.
 *
 * Rays are handed out in chunks from an atomic counter, so a thread that
 * draws cheap rays takes more chunks. Every chunk is traced by one call of
 * the kind's batch function; per-thread counters are summed after the join
 * (no atomics in kernels), so results and counts are identical for any
 * thread count.
 */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"

typedef struct {
    size_t count, chunk;
    atomic_size_t next;
    void (*fn)(void *, size_t, size_t, int);
    void *ctx;
} pf_job;

typedef struct {
    pf_job *job;
    int thread;
} pf_arg;

static void *pf_worker(void *p)
{
    pf_arg *a = p;
    pf_job *job = a->job;
    for (;;) {
        size_t begin = atomic_fetch_add(&job->next, job->chunk);
        if (begin >= job->count) break;
        size_t end = begin + job->chunk < job->count ? begin + job->chunk : job->count;
        job->fn(job->ctx, begin, end, a->thread);
    }
    return NULL;
}

void accel_parallel_for(size_t count, size_t chunk, int threads,
                        void (*fn)(void *ctx, size_t begin, size_t end, int thread), void *ctx)
{
    if (chunk == 0) chunk = 1;
    if (threads > 256) threads = 256;
    if (threads <= 1 || count <= chunk) {
        for (size_t b = 0; b < count; b += chunk) fn(ctx, b, b + chunk < count ? b + chunk : count, 0);
        return;
    }
    pf_job job = {count, chunk, 0, fn, ctx};
    pthread_t tid[256];
    pf_arg args[256];
    int started = 1;
    for (int i = 1; i < threads; i++) {
        args[i].job = &job;
        args[i].thread = i;
        if (pthread_create(&tid[i], NULL, pf_worker, &args[i]) != 0) break;
        started++;
    }
    args[0].job = &job;
    args[0].thread = 0;
    pf_worker(&args[0]);
    for (int i = 1; i < started; i++) pthread_join(tid[i], NULL);
}

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
