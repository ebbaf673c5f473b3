/*
 * parallel.c - a dynamic parallel-for on pthreads.
 *
 * Items are handed out in chunks from an atomic counter, so a thread that
 * draws cheap items takes more chunks. Finished items are also added to one
 * process-wide counter (one relaxed atomic add per chunk), which tools read
 * for progress estimates of long traces (accel_parallel_done).
 */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"

static atomic_uint_fast64_t items_done;

uint64_t accel_parallel_done(void)
{
    return (uint64_t)atomic_load_explicit(&items_done, memory_order_relaxed);
}

static void note_done(size_t n)
{
    atomic_fetch_add_explicit(&items_done, (uint_fast64_t)n, memory_order_relaxed);
}

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
        note_done(end - begin);
    }
    return NULL;
}

void accel_parallel_for(size_t count, size_t chunk, int threads,
                        void (*fn)(void *ctx, size_t begin, size_t end, int thread), void *ctx)
{
    if (chunk == 0) chunk = 1;
    if (threads > 256) threads = 256;
    if (threads <= 1 || count <= chunk) {
        for (size_t b = 0; b < count; b += chunk) {
            size_t e = b + chunk < count ? b + chunk : count;
            fn(ctx, b, e, 0);
            note_done(e - b);
        }
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

