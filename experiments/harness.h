/*
 * harness.h - the shared frame of every experiment binary.
 *
 * An experiment answers one question. It parses the common options
 * (--quick, --out DIR, --threads N, --repeat N, --mesh FILE..., --heat-scale SPEC,
 * --help),
 * measures through bench.h, writes its raw numbers to DIR/<name>.csv and one
 * Markdown section to DIR/<name>.md: the question, a table (medians with
 * min-max, and the hardware-independent counts beside every time), a
 * finding computed from the numbers, and the lecture's claim beside the
 * measurement. experiments/report.sh stitches the sections into REPORT.md.
 */
#ifndef EXP_HARNESS_H
#define EXP_HARNESS_H

#include <stdio.h>

#include "bench/bench.h"
#include "bench/image.h"
#include "scene/scene.h"

#define EXP_MAX_MESHES 16

typedef struct {
    const char *name;     /* e.g. "exp_sah" */
    int quick;            /* smoke-test budget: tiny scenes, few repeats */
    const char *out_dir;  /* default experiments/out */
    int threads;          /* trace/build threads (default 1) */
    int repeats;          /* timed passes per measurement */
    int size;             /* primary image size (square) */
    const char *meshes[EXP_MAX_MESHES]; /* extra mesh files (default: the meshes in ../shared/scenes) */
    int mesh_count;
    image_heat_scale heat_scale; /* --heat-scale: colours of exp_heatmap images */
    FILE *csv;
    FILE *md;
    double t_start;
} exp_ctx;

/* Parses the common options; `extra_help` is printed under --help. Exits on
 * --help (0) or a bad option (2): experiments are programs, not library. */
void exp_init(exp_ctx *x, int argc, char **argv, const char *name, const char *question,
              const char *extra_help);
/* Closes files, prints the elapsed time. Returns 0. */
int exp_finish(exp_ctx *x);

void exp_csv(exp_ctx *x, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void exp_md(exp_ctx *x, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A Markdown table header: cols separated by '|'. */
void exp_md_table(exp_ctx *x, const char *cols);
/* "12.3 (11.9-12.8)": a median with its min-max range. */
const char *exp_fmt_timing(char *buf, size_t n, const accel_timing *t, int decimals);

/* Loads a scene spec or dies with its error (experiments stop on bad input). */
void exp_scene(const char *spec, accel_scene *s);
/* Builds the standard ray sets (mask of bench_set_bit) for s at x->size. */
void exp_sets(exp_ctx *x, const accel_scene *s, int mask, bench_sets *out);

/* One accelerator configuration measured on one scene and some ray sets. */
typedef struct {
    accel_build_stats build;
    accel_timing build_ms;
    bench_result res[4]; /* indexed by set: 0 primary, 1 shadow, 2 diffuse, 3 ao */
    int have[4];
} exp_measure;

/* Builds spec (repeats per the budget) and traces every set in mask.
 * Returns 0, or prints the error and returns nonzero (the caller reports a
 * skipped configuration with the reason). */
int exp_run(exp_ctx *x, const char *spec, const accel_scene *s, const bench_sets *sets, int mask,
            exp_measure *m, char *why, size_t why_n);

static inline int exp_set_index(int bit)
{
    return bit == BENCH_PRIMARY ? 0 : bit == BENCH_SHADOW ? 1 : bit == BENCH_DIFFUSE ? 2 : 3;
}

/* Per-ray averages from a measurement's counters. */
static inline double exp_per_ray(uint64_t v, const bench_result *r)
{
    return r->rays ? (double)v / (double)r->rays : 0.0;
}

/* Writes DIR/<plot_name>.gp drawing DIR/<plot_name>.png; the script may use
 * the variable `csv` (this experiment's CSV). report.sh runs it when gnuplot exists. */
void exp_plot(exp_ctx *x, const char *plot_name, const char *script);

/* Traces the primary rays of `sets` with spec on s in a counted pass and
 * writes DIR/<image_name>.png: steps (what='s') or primitive tests ('p')
 * per pixel with a colour scale; adds the image to the Markdown section.
 * Returns 0 or nonzero (reason in why). */
int exp_heatmap(exp_ctx *x, const char *spec, const accel_scene *s, const bench_sets *sets,
                char what, const char *image_name, const char *caption, char *why, size_t why_n);

#endif
