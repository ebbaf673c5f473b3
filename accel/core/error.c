/*
 * error.c - errors, clocks, core count, counters and the traversal step bound.
 */

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "accel.h"

int accel_fail(accel_error *err, int code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        err->code = code;
    }
    return code;
}

double accel_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

int accel_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (int)n;
}

void accel_counters_add(accel_counters *a, const accel_counters *b)
{
    a->rays += b->rays;
    a->steps += b->steps;
    a->empty_steps += b->empty_steps;
    a->box_tests += b->box_tests;
    a->prim_tests += b->prim_tests;
    a->mailbox_skips += b->mailbox_skips;
    for (int i = 0; i < 4; i++) a->level_steps[i] += b->level_steps[i];
    a->packet_box_tests += b->packet_box_tests;
}

void accel_step_bound_exceeded(const char *file, int line, uint64_t bound)
{
    fprintf(stderr, "%s:%d: traversal exceeded its step bound (%llu): endless loop?\n", file, line,
            (unsigned long long)bound);
    abort();
}
