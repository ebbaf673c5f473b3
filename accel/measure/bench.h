/*
 * bench.h - the measurement discipline shared by bin/trace and every
 * experiment: the standard ray sets of a scene, and timed traces reported
 * as median / min / max over repetitions after a warm-up, with the
 * hardware-independent counters taken in a separate counted pass (so the
 * timed passes run the counter-free kernels).
 */
#ifndef ACCEL_BENCH_H
#define ACCEL_BENCH_H

#include "measure/progress.h"
#include "rays/rays.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double median, min, max;
    int n;
} accel_timing;

/* Median, min and max of n samples (samples are reordered). */
void accel_timing_of(double *samples, int n, accel_timing *out);

/* The ray sets of one view. Secondary sets start at the primary hits found
 * by one fixed generator kind (gen_spec, default "bvh", or "brute" when no
 * bvh is registered), so every accelerator traces the same rays. */
typedef enum { BENCH_PRIMARY = 1, BENCH_SHADOW = 2, BENCH_DIFFUSE = 4, BENCH_AO = 8 } bench_set_bit;

typedef struct {
    rays_set primary, shadow, diffuse, ao;
    accel_hit *primary_hits;
    int made; /* bench_set_bit mask */
} bench_sets;

typedef struct {
    const accel_camera *camera; /* NULL: the scene's default */
    int width, height;          /* primary image size */
    int ao_samples;             /* per primary hit */
    float ao_radius;            /* <= 0: 10% of the scene's diagonal */
    uint64_t seed;
    int threads;
    const char *gen_spec;       /* NULL: "bvh" if registered, else "brute" */
} bench_set_opts;

int bench_sets_make(const accel_scene *s, const bench_set_opts *o, int mask, bench_sets *out,
                    accel_error *err);
void bench_sets_free(bench_sets *b);
/* Name -> bit ("primary", "shadow", "diffuse", "ao"); 0 if unknown. */
int bench_set_bit_of(const char *name);
/* Bit -> name ("?" if none). */
const char *bench_set_name(int bit);
/* A comma list of set names: each bit once, in the order given (*count of
 * them, at most 4). Unknown names and an empty list are ACCEL_ERR_SPEC. */
int bench_sets_parse(const char *list, int bits[4], int *count, accel_error *err);
const rays_set *bench_sets_get(const bench_sets *b, int bit);
/* shadow and ao rays are any-hit (occluded) queries. */
static inline int bench_set_is_occlusion(int bit) { return bit == BENCH_SHADOW || bit == BENCH_AO; }

typedef struct {
    accel_timing ms;     /* wall-clock per pass */
    accel_timing mrays;  /* million rays per second per pass */
    size_t rays, hits;   /* hits: rays that hit (or are occluded) */
    int counted;
    accel_counters counters; /* totals of the counted pass */
} bench_result;

typedef struct {
    int threads;
    int warmup;        /* untimed passes first (>= 0) */
    int repeats;       /* timed passes (>= 1) */
    int count_pass;    /* run one extra counted pass for counters */
    double min_ms;     /* keep repeating (up to 100 passes) until this much time is timed */
    double max_ms;     /* > 0: fewer timed passes (at least 1) when the warm-up pass shows
                          that `repeats` of them would exceed this; the timing's n says so */
    accel_hit *hits;   /* optional: closest-hit results (ray count entries) */
    uint8_t *occluded; /* optional: any-hit results */
    uint32_t *ray_steps, *ray_prims; /* optional per-ray costs from the counted pass */
    bench_progress *progress;        /* optional: shows the passes as phase progress_name */
    const char *progress_name;
} bench_trace_opts;

/* Times `kind` on `rays`; occlusion selects the any-hit query. When the
 * counted pass saw a broken invariant (accel_counters_status), *out is
 * still filled and the ACCEL_ERR_INTERNAL is returned. */
int bench_trace(const accel_kind *kind, const void *accel, const rays_set *rays, int occlusion,
                const bench_trace_opts *o, bench_result *out, accel_error *err);

/* Builds spec `repeats` times (at least once; stops repeating once the
 * builds took more than budget_ms in total) and keeps the last structure.
 * build->ms holds the median build time; *timing all of them. progress
 * (may be NULL) shows the builds as the phase "build <spec>". */
int bench_build(const char *spec, const accel_scene *s, int threads, int repeats, double budget_ms,
                const accel_kind **kind, void **accel, accel_build_stats *stats,
                accel_timing *timing, bench_progress *progress, accel_error *err);


#ifdef __cplusplus
}
#endif

#endif
