/*
 * progress.h - progress with an estimate, on stderr, for long phases of the
 * tools and experiments (a build, the timed passes of a ray set, the
 * reference trace of --check).
 *
 * A phase has a name and a total in units; the units done come either from
 * the caller (builds finished) or, for traces, from accel_parallel_done()
 * (rays finished by every thread), so no kernel is touched. A background
 * thread shows a phase once it has run longer than `after_ms`: percent,
 * elapsed time and the time left (elapsed * left / done), redrawn in place
 * on a terminal, a line every 10 s otherwise; a shown phase ends with
 * "name: done in S s". Every function accepts NULL (quiet: --quiet).
 */
#ifndef ACCEL_PROGRESS_H
#define ACCEL_PROGRESS_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bench_progress bench_progress;

/* The default threshold: phases shorter than this stay silent. */
#define BENCH_PROGRESS_AFTER_MS 2000.0

/* Starts a reporter writing to out (stderr); out == NULL returns NULL, the
 * quiet reporter. `tool` prefixes every line. NULL also if no thread starts. */
bench_progress *bench_progress_start(FILE *out, const char *tool, double after_ms);
void bench_progress_stop(bench_progress *p);

/* Begins a phase of `total` units (0: unknown). With traced != 0 the units
 * are rays counted through accel_parallel_done(), else calls of
 * bench_progress_add. Ends the phase before it if still open. */
void bench_progress_begin(bench_progress *p, const char *name, double total, int traced);
void bench_progress_total(bench_progress *p, double total);
void bench_progress_add(bench_progress *p, double units);
void bench_progress_end(bench_progress *p);

/* One progress line: "name: 40% after 3.1 s, about 4.6 s left", or
 * "name: 3.1 s, no estimate yet" while nothing is done or total is 0. */
void bench_progress_format(char *buf, size_t n, const char *name, double done, double total,
                           double elapsed_ms);

#ifdef __cplusplus
}
#endif

#endif
