/*
 * test_parallel.c - accel_parallel_for (core/parallel.c): every item once,
 * thread numbers in range, the helper threads really running at the same
 * time, over calls that grow and shrink the pool of kept workers, and the
 * calls the pool cannot take (from inside a job, from two threads at once,
 * in a forked child) done by threads of their own.
 */
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "test.h"

#define PT_ITEMS 5000
#define PT_MAX_THREADS 8

typedef struct {
    atomic_int seen[PT_ITEMS];
    atomic_int bad_thread;
    int threads;
} pt_count;

static void pt_count_items(void *ctx, size_t b, size_t e, int t)
{
    pt_count *c = ctx;
    if (t < 0 || t >= c->threads) atomic_fetch_add(&c->bad_thread, 1);
    for (size_t i = b; i < e; i++) atomic_fetch_add(&c->seen[i], 1);
}

/* Runs one job of `count` items and returns the number of items not seen
 * exactly once plus calls with a thread number out of range. */
static int pt_run(size_t count, size_t chunk, int threads)
{
    pt_count *c = calloc(1, sizeof *c);
    if (!c) return -1;
    c->threads = threads;
    accel_parallel_for(count, chunk, threads, pt_count_items, c);
    int wrong = atomic_load(&c->bad_thread);
    for (size_t i = 0; i < PT_ITEMS; i++) wrong += atomic_load(&c->seen[i]) != (i < count);
    free(c);
    return wrong;
}

static double pt_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* One item per thread; each waits (at most 2 s) until every item has
 * started, which only happens when `threads` threads run the job at once. */
typedef struct {
    atomic_int arrived, timed_out;
    int want;
} pt_gather;

static void pt_gather_items(void *ctx, size_t b, size_t e, int t)
{
    (void)t;
    pt_gather *g = ctx;
    for (size_t i = b; i < e; i++) atomic_fetch_add(&g->arrived, 1);
    double until = pt_now() + 2.0;
    while (atomic_load(&g->arrived) < g->want)
        if (pt_now() > until) {
            atomic_store(&g->timed_out, 1);
            return;
        }
}

TEST(parallel_for_every_item_once_as_the_pool_grows_and_shrinks)
{
    const int threads[] = {2, 4, 3, 2, 8, 1, 5, 2};
    const size_t counts[] = {PT_ITEMS, 1, 63, 64, 65, 4097, PT_ITEMS - 7, 0};
    const size_t chunks[] = {1, 7, 64, 4096};
    for (size_t a = 0; a < sizeof threads / sizeof *threads; a++)
        for (size_t b = 0; b < sizeof counts / sizeof *counts; b++)
            for (size_t k = 0; k < sizeof chunks / sizeof *chunks; k++) {
                int wrong = pt_run(counts[b], chunks[k], threads[a]);
                CHECKF(wrong == 0, "%d threads, %zu items in chunks of %zu: %d items not seen once", threads[a],
                       counts[b], chunks[k], wrong);
            }
    /* Many short calls in a row (the pattern of a build's large nodes). */
    int wrong = 0;
    for (int r = 0; r < 300; r++) wrong += pt_run(200, 16, 2 + r % 3);
    CHECKF(wrong == 0, "300 short calls: %d items wrong", wrong);
}

TEST(parallel_for_threads_run_at_once)
{
    for (int threads = 2; threads <= PT_MAX_THREADS; threads += 3) {
        for (int rep = 0; rep < 3; rep++) {
            pt_gather g = {0, 0, threads};
            accel_parallel_for((size_t)threads, 1, threads, pt_gather_items, &g);
            CHECKF(!atomic_load(&g.timed_out) && atomic_load(&g.arrived) == threads,
                   "%d threads: %d of %d items started together", threads, atomic_load(&g.arrived), threads);
        }
    }
}

/* A job whose items run a parallel job of their own. */
static void pt_nested(void *ctx, size_t b, size_t e, int t)
{
    (void)t;
    atomic_int *wrong = ctx;
    for (size_t i = b; i < e; i++) atomic_fetch_add(wrong, pt_run(300 + i, 8, 2));
}

static void *pt_caller(void *p)
{
    int *wrong = p;
    for (int r = 0; r < 50; r++) *wrong += pt_run(1000, 32, 2);
    return NULL;
}

TEST(parallel_for_calls_the_pool_cannot_take)
{
    atomic_int wrong = 0;
    accel_parallel_for(6, 1, 2, pt_nested, &wrong);
    CHECKF(atomic_load(&wrong) == 0, "nested jobs: %d items wrong", atomic_load(&wrong));
    /* Two threads of the program calling at the same time. */
    int w1 = 0, w2 = 0;
    pthread_t other;
    CHECK(pthread_create(&other, NULL, pt_caller, &w1) == 0);
    pt_caller(&w2);
    pthread_join(other, NULL);
    CHECKF(w1 == 0 && w2 == 0, "concurrent callers: %d and %d items wrong", w1, w2);
    /* A child forked after the pool exists: its workers did not survive
     * the fork, so it must not wait for them (alarm: a hang fails). */
    CHECK(pt_run(PT_ITEMS, 16, 2) == 0);
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        alarm(20);
        int bad = 0;
        for (int r = 0; r < 20; r++) bad += pt_run(PT_ITEMS, 16, 1 + r % 3);
        _exit(bad == 0 ? 0 : 1);
    }
    CHECK(pid > 0);
    if (pid <= 0) return;
    int status = -1;
    CHECK(waitpid(pid, &status, 0) == pid);
    CHECKF(WIFEXITED(status) && WEXITSTATUS(status) == 0, "forked child: status %d", status);
    CHECK(pt_run(PT_ITEMS, 16, 2) == 0); /* the parent's pool still works */
}
