/*
 * progress.c - the progress reporter of progress.h: one thread that wakes
 * four times a second and prints the open phase's state when it is long.
 */
#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "accel.h"
#include "measure/progress.h"

#define TICK_MS 250
#define LINE_EVERY_MS 10000.0 /* when out is not a terminal */

struct bench_progress {
    FILE *out;
    char tool[64];
    double after_ms;
    int tty;
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t wake;
    int stop;
    /* The open phase (name[0] == 0: none). */
    char name[192];
    double t0, total, done, last_print;
    int traced, shown, drawn;
    uint64_t base;
    size_t line_len;
};

void bench_progress_format(char *buf, size_t n, const char *name, double done, double total,
                           double elapsed_ms)
{
    double s = elapsed_ms / 1e3;
    if (total > 0 && done > 0) {
        double frac = done < total ? done / total : 1.0;
        double left = s * (1.0 - frac) / frac;
        snprintf(buf, n, "%s: %.0f%% after %.1f s, about %.1f s left", name, 100.0 * frac, s, left);
    } else {
        snprintf(buf, n, "%s: %.1f s, no estimate yet", name, s);
    }
}

static double done_now(const bench_progress *p)
{
    double d = p->done;
    if (p->traced) d += (double)(accel_parallel_done() - p->base);
    return d;
}

/* Prints the open phase's line; lock held. */
static void draw(bench_progress *p, double now)
{
    char line[320];
    bench_progress_format(line, sizeof line, p->name, done_now(p), p->total, now - p->t0);
    if (p->tty) {
        size_t len = strlen(line);
        fprintf(p->out, "\r%s: %s%*s", p->tool, line,
                p->line_len > len ? (int)(p->line_len - len) : 0, "");
        p->line_len = len;
        p->drawn = 1;
    } else {
        fprintf(p->out, "%s: %s\n", p->tool, line);
    }
    fflush(p->out);
    p->shown = 1;
    p->last_print = now;
}

static void *ticker(void *arg)
{
    bench_progress *p = arg;
    pthread_mutex_lock(&p->lock);
    while (!p->stop) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += TICK_MS * 1000000L;
        if (ts.tv_nsec >= 1000000000L) ts.tv_sec++, ts.tv_nsec -= 1000000000L;
        int rc = pthread_cond_timedwait(&p->wake, &p->lock, &ts);
        if (p->stop) break;
        if (rc != ETIMEDOUT || !p->name[0]) continue;
        double now = accel_now_ms();
        if (now - p->t0 < p->after_ms) continue;
        if (!p->tty && p->shown && now - p->last_print < LINE_EVERY_MS) continue;
        draw(p, now);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

bench_progress *bench_progress_start(FILE *out, const char *tool, double after_ms)
{
    if (!out) return NULL;
    bench_progress *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    p->out = out;
    snprintf(p->tool, sizeof p->tool, "%s", tool);
    p->after_ms = after_ms;
    p->tty = isatty(fileno(out));
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->wake, NULL);
    if (pthread_create(&p->thread, NULL, ticker, p) != 0) {
        pthread_mutex_destroy(&p->lock);
        pthread_cond_destroy(&p->wake);
        free(p);
        return NULL;
    }
    return p;
}

/* Closes the open phase; lock held. */
static void end_locked(bench_progress *p)
{
    if (!p->name[0]) return;
    double ms = accel_now_ms() - p->t0;
    if (p->shown || ms >= p->after_ms) {
        if (p->drawn) fprintf(p->out, "\r");
        char line[320];
        snprintf(line, sizeof line, "%s: %s: done in %.1f s", p->tool, p->name, ms / 1e3);
        size_t len = strlen(line), prev = p->line_len + strlen(p->tool) + 2;
        fprintf(p->out, "%s%*s\n", line, p->drawn && prev > len ? (int)(prev - len) : 0, "");
        fflush(p->out);
    }
    p->name[0] = 0;
    p->shown = p->drawn = 0;
    p->line_len = 0;
}

void bench_progress_stop(bench_progress *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    end_locked(p);
    p->stop = 1;
    pthread_cond_signal(&p->wake);
    pthread_mutex_unlock(&p->lock);
    pthread_join(p->thread, NULL);
    pthread_mutex_destroy(&p->lock);
    pthread_cond_destroy(&p->wake);
    free(p);
}

void bench_progress_begin(bench_progress *p, const char *name, double total, int traced)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    end_locked(p);
    snprintf(p->name, sizeof p->name, "%s", name[0] ? name : "working");
    p->t0 = accel_now_ms();
    p->total = total;
    p->done = 0;
    p->traced = traced;
    p->base = traced ? accel_parallel_done() : 0;
    pthread_mutex_unlock(&p->lock);
}

void bench_progress_total(bench_progress *p, double total)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->total = total;
    pthread_mutex_unlock(&p->lock);
}

void bench_progress_add(bench_progress *p, double units)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->done += units;
    pthread_mutex_unlock(&p->lock);
}

void bench_progress_end(bench_progress *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    end_locked(p);
    pthread_mutex_unlock(&p->lock);
}
