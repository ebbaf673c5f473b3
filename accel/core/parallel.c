/*
 * parallel.c - a dynamic parallel-for on pthreads.
 *
 * Items are handed out in chunks from an atomic counter, so a thread that
 * draws cheap items takes more chunks. Finished items are also added to one
 * process-wide counter (one relaxed atomic add per chunk), which tools read
 * for progress estimates of long traces (accel_parallel_done).
 *
 * The helper threads are kept between calls in a pool and woken by a
 * condition variable. Measured on the 2-core virtual machine of this study
 * (2026-12-03): a thread created while its creator computes starts 0.2-2 ms
 * later (the scheduler queues it on the creator's core until a balancing
 * pass moves it), a pooled one waits 8-25 us for its wake-up. 2 threads
 * over 1 on one call of fixed work: 1.41-1.45x created, 1.72-1.78x pooled
 * for 0.45 ms of work, 1.92-1.94x and 1.99-2.06x for 13.6 ms; 2-thread
 * builds of a 100k-triangle soup about 5% faster. A call made while the pool
 * is busy (from inside a job, or from a second thread at the same time)
 * starts its own threads as before; so does a process forked from one that
 * had a pool (its workers did not survive the fork).
 */
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* The pool: workers 1..workers, the ones numbered up to `wanted` take
 * part in the job of generation `gen`. */
#define POOL_MAX 255
static struct {
    pthread_mutex_t lock;
    pthread_cond_t wake, done;
    int workers, wanted, finished;
    unsigned long gen;
    pf_job *job;
    pid_t pid; /* the process whose workers these are */
} pool = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, PTHREAD_COND_INITIALIZER, 0, 0, 0, 0, NULL, 0};
static atomic_int pool_busy;

static void *pool_worker(void *p)
{
    int idx = (int)(intptr_t)p;
    /* A worker starts inside pool_run, before the job it was started for
     * is published (gen >= 1 from then on), and takes part in it. */
    unsigned long seen = 0;
    pthread_mutex_lock(&pool.lock);
    for (;;) {
        while (pool.gen == seen) pthread_cond_wait(&pool.wake, &pool.lock);
        seen = pool.gen;
        if (idx > pool.wanted) continue;
        pf_arg a = {pool.job, idx};
        pthread_mutex_unlock(&pool.lock);
        pf_worker(&a);
        pthread_mutex_lock(&pool.lock);
        if (++pool.finished == pool.wanted) pthread_cond_signal(&pool.done);
    }
    return NULL;
}

/* Runs `job` on the calling thread and up to threads - 1 pool workers;
 * 0 when the pool is busy or belongs to another process (the caller then
 * starts its own threads). */
static int pool_run(pf_job *job, int threads)
{
    if (atomic_exchange(&pool_busy, 1)) return 0;
    pid_t me = getpid();
    if (pool.workers && pool.pid != me) return 0; /* forked: stays busy in this process */
    pthread_mutex_lock(&pool.lock);
    pool.pid = me;
    while (pool.workers < threads - 1 && pool.workers < POOL_MAX) {
        pthread_t tid;
        pthread_attr_t attr;
        int ok = pthread_attr_init(&attr) == 0;
        ok = ok && pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED) == 0;
        ok = ok && pthread_create(&tid, &attr, pool_worker, (void *)(intptr_t)(pool.workers + 1)) == 0;
        pthread_attr_destroy(&attr);
        if (!ok) break;
        pool.workers++;
    }
    pool.job = job;
    pool.wanted = threads - 1 < pool.workers ? threads - 1 : pool.workers;
    pool.finished = 0;
    pool.gen++;
    pthread_cond_broadcast(&pool.wake);
    pthread_mutex_unlock(&pool.lock);
    pf_arg a = {job, 0};
    pf_worker(&a);
    pthread_mutex_lock(&pool.lock);
    while (pool.finished < pool.wanted) pthread_cond_wait(&pool.done, &pool.lock);
    pool.job = NULL;
    pthread_mutex_unlock(&pool.lock);
    atomic_store(&pool_busy, 0);
    return 1;
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
    if (pool_run(&job, threads)) return;
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
