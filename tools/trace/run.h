/*
 * run.h - what bin/trace's steps share (tools/trace.c runs them; the
 * pieces in tools/trace/ print and write what they measured).
 */
#ifndef TOOLS_TRACE_RUN_H
#define TOOLS_TRACE_RUN_H

#include <stdint.h>
#include <stdio.h>

#include "measure/bench.h"
#include "cli/cli.h"
#include "measure/csv.h"
#include "image/image.h"
#include "scene/scene.h"

#define MAX_ACCELS 32
#define MAX_SETS 4

typedef struct {
    const char *scene;
    const char *accels[MAX_ACCELS];
    int accel_count;
    const char *rays;
    int size[2]; /* width, height */
    cli_vec3 eye, look, up;
    double fov; /* 0: the scene's */
    int threads, repeat, warmup, build_repeat;
    int counters, check, csv, quiet, help, occluded;
    double budget; /* seconds of timed passes per ray set, and of builds per accelerator */
    double progress_after; /* seconds */
    const char *image, *heatmap[2], *dump_rays, *dump_hits, *export_obj;
    const char *gen_accel;
    uint64_t seed;
    int ao_samples;
    float ao_radius;
    image_heat_scale heat_scale;
    int ray_order;    /* rays_order + 1; 0: as made (tiles for camera sets, a file's own) */
    int packet_order; /* core/coherence.h's ACCEL_ORDER_* */
} options;

/* One cell of the closing summary: an accelerator on a ray set. */
typedef struct {
    char spec[256];
    int set;
    double mrays, build_ms;
    size_t bytes;
} summary_cell;

/* Everything one run holds between its steps. */
typedef struct {
    accel_scene scene;
    accel_camera cam;
    bench_sets sets;
    rays_set file_rays;
    int from_file, set_count, bits[MAX_SETS];
    const char *set_names[MAX_SETS];
    bench_progress *progress;
    csv_file csv;
    int status; /* the worst exit status so far */
    summary_cell summary[MAX_ACCELS * MAX_SETS];
    int summary_count;
} run;

/* One ray set traced by one accelerator: its results and measurements. */
typedef struct {
    const rays_set *rays;
    int set, occl;
    accel_hit *hits;
    uint8_t *occ;
    uint32_t *steps, *prims; /* per-ray costs for --heatmap */
    bench_result br;
    hits_diff diff;
    int checked;
} set_run;

/* Prints "trace: msg" and keeps the worst exit status; returns code. */
int report(run *r, int code, const char *msg);
int report_err(run *r, const accel_error *err);
/* The stream of the informative lines: stdout, or stderr with --csv
 * (NULL with --csv --quiet). */
FILE *trace_info(const options *o);

/* output.c: the CSV header, one measured row, and the outputs of the last
 * accelerator (--dump-hits, --image, --heatmap). */
void print_csv_header(run *r);
void print_row(const options *o, run *r, const accel_kind *kind, const accel_params *canon,
               const accel_build_stats *st, const accel_timing *bt, const set_run *t);
/* The closing table (text output): accelerators by ray sets, Mrays/s, then
 * build ms and MiB, as tinybvh's speedtest and Embree's tools end. */
void print_summary(const options *o, const run *r);
void write_outputs(const options *o, run *r, const set_run *t, const accel_kind *kind,
                   const void *accel, const char *spec);
/* The file of ray set `set` for an output option given `base`: base itself
 * for one set; for several, base with a trailing .ext (or .alt) taken off,
 * then .<set>.ext: --dump-hits eye.hits writes eye.primary.hits, never
 * eye.hits.primary.hits (ext and alt without the dot; alt may be NULL). */
void trace_set_path(char *buf, size_t n, const char *base, int several, const char *set,
                    const char *ext, const char *alt);

#endif
