/*
 * error.c - errors, clocks, core count and counters (with their record of
 * broken invariants).
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
    a->packet_steps += b->packet_steps;
    if (b->broken && !a->broken_file) {
        a->broken_file = b->broken_file;
        a->broken_line = b->broken_line;
        a->broken_bound = b->broken_bound;
    }
    a->broken += b->broken;
}

int accel_counters_note_broken(accel_counters *c, const char *file, int line, uint64_t bound)
{
    if (!c->broken_file) {
        c->broken_file = file;
        c->broken_line = line;
        c->broken_bound = bound;
    }
    c->broken++;
    return 1;
}

int accel_counters_status(const accel_counters *c, accel_error *err)
{
    if (!c || !c->broken) return 0;
    return accel_fail(err, ACCEL_ERR_INTERNAL,
                      "%s:%d: %llu ray(s) exceeded the traversal step bound (%llu): a broken "
                      "structure or an endless loop",
                      c->broken_file, c->broken_line, (unsigned long long)c->broken,
                      (unsigned long long)c->broken_bound);
}
