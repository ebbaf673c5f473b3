/*
 * bench.c - ray sets of a view, timed traces and builds (see bench.h).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "measure/bench.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void accel_timing_of(double *samples, int n, accel_timing *out)
{
    memset(out, 0, sizeof *out);
    if (n <= 0) return;
    qsort(samples, (size_t)n, sizeof *samples, cmp_double);
    out->n = n;
    out->min = samples[0];
    out->max = samples[n - 1];
    out->median = n % 2 ? samples[n / 2] : 0.5 * (samples[n / 2 - 1] + samples[n / 2]);
}

int bench_set_bit_of(const char *name)
{
    if (!strcmp(name, "primary")) return BENCH_PRIMARY;
    if (!strcmp(name, "shadow")) return BENCH_SHADOW;
    if (!strcmp(name, "diffuse")) return BENCH_DIFFUSE;
    if (!strcmp(name, "ao")) return BENCH_AO;
    return 0;
}

const char *bench_set_name(int bit)
{
    switch (bit) {
    case BENCH_PRIMARY: return "primary";
    case BENCH_SHADOW: return "shadow";
    case BENCH_DIFFUSE: return "diffuse";
    case BENCH_AO: return "ao";
    }
    return "?";
}

int bench_sets_parse(const char *list, int bits[4], int *count, accel_error *err)
{
    *count = 0;
    int mask = 0;
    for (const char *p = list; *p;) {
        size_t len = strcspn(p, ",");
        char name[32];
        snprintf(name, sizeof name, "%.*s", (int)(len < 31 ? len : 31), p);
        int bit = len < 31 ? bench_set_bit_of(name) : 0;
        if (!bit)
            return accel_fail(err, ACCEL_ERR_SPEC, "unknown ray set '%.*s'; accepted: primary, "
                              "shadow, diffuse, ao, or a .rays file", (int)len, p);
        if (!(mask & bit)) bits[(*count)++] = bit;
        mask |= bit;
        p += len;
        if (*p) p++;
    }
    if (!*count) return accel_fail(err, ACCEL_ERR_SPEC, "'%s' names no ray set", list);
    return 0;
}

const rays_set *bench_sets_get(const bench_sets *b, int bit)
{
    switch (bit) {
    case BENCH_PRIMARY: return &b->primary;
    case BENCH_SHADOW: return &b->shadow;
    case BENCH_DIFFUSE: return &b->diffuse;
    case BENCH_AO: return &b->ao;
    }
    return NULL;
}

void bench_sets_free(bench_sets *b)
{
    rays_free(&b->primary);
    rays_free(&b->shadow);
    rays_free(&b->diffuse);
    rays_free(&b->ao);
    free(b->primary_hits);
    memset(b, 0, sizeof *b);
}

int bench_sets_make(const accel_scene *s, const bench_set_opts *o, int mask, bench_sets *out,
                    accel_error *err)
{
    memset(out, 0, sizeof *out);
    const accel_camera *cam = o->camera ? o->camera : &s->camera;
    int rc = rays_primary(cam, o->width, o->height, &out->primary, err);
    if (rc) return rc;
    out->made = BENCH_PRIMARY;
    if (!(mask & (BENCH_SHADOW | BENCH_DIFFUSE | BENCH_AO))) return 0;
    out->primary_hits = malloc(out->primary.count * sizeof *out->primary_hits);
    if (!out->primary_hits) {
        bench_sets_free(out);
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for primary hits");
    }
    const char *gen = o->gen_spec ? o->gen_spec : (accel_find_kind("bvh") ? "bvh" : "brute");
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    rc = accel_build_spec(gen, s, o->threads, &kind, &accel, &st, err);
    if (rc) {
        bench_sets_free(out);
        return rc;
    }
    accel_trace(kind, accel, out->primary.rays, out->primary_hits, out->primary.count, o->threads,
                NULL);
    kind->destroy(accel);
    float diag = v3_len(box3_extent(s->bounds));
    float radius = o->ao_radius > 0 ? o->ao_radius : 0.1f * (diag > 0 ? diag : 1.0f);
    if (!rc && (mask & BENCH_SHADOW)) {
        rc = rays_shadow(s, &out->primary, out->primary_hits, &out->shadow, err);
        if (!rc) out->made |= BENCH_SHADOW;
    }
    if (!rc && (mask & BENCH_DIFFUSE)) {
        rc = rays_diffuse(s, &out->primary, out->primary_hits, o->seed, &out->diffuse, err);
        if (!rc) out->made |= BENCH_DIFFUSE;
    }
    if (!rc && (mask & BENCH_AO)) {
        rc = rays_ao(s, &out->primary, out->primary_hits, o->ao_samples > 0 ? o->ao_samples : 4,
                     radius, o->seed, &out->ao, err);
        if (!rc) out->made |= BENCH_AO;
    }
    if (rc) bench_sets_free(out);
    return rc;
}

static void one_pass(const accel_kind *kind, const void *accel, const rays_set *rays,
                     int occlusion, int threads, accel_hit *hits, uint8_t *occ,
                     accel_counters *c)
{
    if (occlusion)
        accel_trace_occluded(kind, accel, rays->rays, occ, rays->count, threads, c);
    else
        accel_trace(kind, accel, rays->rays, hits, rays->count, threads, c);
}

int bench_trace(const accel_kind *kind, const void *accel, const rays_set *rays, int occlusion,
                const bench_trace_opts *o, bench_result *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    size_t n = rays->count;
    accel_hit *hits = o->hits;
    uint8_t *occ = o->occluded;
    accel_hit *own_hits = NULL;
    uint8_t *own_occ = NULL;
    if (!occlusion && !hits) hits = own_hits = malloc((n ? n : 1) * sizeof *hits);
    if (occlusion && !occ) occ = own_occ = malloc(n ? n : 1);
    if ((!occlusion && !hits) || (occlusion && !occ))
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for %zu results", n);
    int passes = o->warmup + (o->repeats < 1 ? 1 : o->repeats) + (o->count_pass != 0);
    bench_progress_begin(o->progress, o->progress_name ? o->progress_name : "trace",
                         (double)passes * (double)n, 1);
    double warm_ms = 0;
    for (int i = 0; i < o->warmup; i++) {
        double t0 = accel_now_ms();
        one_pass(kind, accel, rays, occlusion, o->threads, hits, occ, NULL);
        warm_ms = accel_now_ms() - t0;
    }
    double samples[100];
    int reps = 0, want = o->repeats < 1 ? 1 : o->repeats;
    if (o->max_ms > 0 && warm_ms * want > o->max_ms) {
        want = (int)(o->max_ms / (warm_ms > 0 ? warm_ms : 1));
        if (want < 1) want = 1;
    }
    /* A single pass longer than a quarter of the budget: the warm-up pass
     * itself is the one sample (n = 1 says so); the caches it warms matter
     * little against seconds of work. */
    int reuse_warmup = o->max_ms > 0 && o->warmup > 0 && warm_ms * 4 > o->max_ms;
    bench_progress_total(o->progress, (double)(o->warmup + want - reuse_warmup +
                                               (o->count_pass != 0)) * (double)n);
    double total = 0;
    if (reuse_warmup) samples[reps++] = warm_ms, total = warm_ms;
    while (reps < 100 && (reps < want || (total < o->min_ms && reps < o->repeats * 20))) {
        double t0 = accel_now_ms();
        one_pass(kind, accel, rays, occlusion, o->threads, hits, occ, NULL);
        samples[reps] = accel_now_ms() - t0;
        total += samples[reps++];
    }
    double mr[100];
    for (int i = 0; i < reps; i++) mr[i] = samples[i] > 0 ? (double)n / (samples[i] * 1e3) : 0;
    accel_timing_of(samples, reps, &out->ms);
    accel_timing_of(mr, reps, &out->mrays);
    out->rays = n;
    for (size_t i = 0; i < n; i++)
        out->hits += occlusion ? occ[i] != 0 : hits[i].prim != ACCEL_MISS;
    if (o->count_pass) {
        out->counters.ray_steps = o->ray_steps;
        out->counters.ray_prims = o->ray_prims;
        one_pass(kind, accel, rays, occlusion, o->threads, hits, occ, &out->counters);
        out->counters.ray_steps = out->counters.ray_prims = NULL;
        out->counted = 1;
    }
    bench_progress_end(o->progress);
    free(own_hits);
    free(own_occ);
    return out->counted ? accel_counters_status(&out->counters, err) : 0;
}

int bench_build(const char *spec, const accel_scene *s, int threads, int repeats, double budget_ms,
                const accel_kind **kind, void **accel, accel_build_stats *stats,
                accel_timing *timing, bench_progress *progress, accel_error *err)
{
    double samples[64];
    int n = 0;
    double total = 0;
    *accel = NULL;
    if (repeats < 1) repeats = 1;
    if (repeats > 64) repeats = 64;
    char name[300];
    snprintf(name, sizeof name, "build %s", spec);
    bench_progress_begin(progress, name, repeats, 0);
    while (n < repeats) {
        if (*accel) (*kind)->destroy(*accel);
        *accel = NULL;
        int rc = accel_build_spec(spec, s, threads, kind, accel, stats, err);
        if (rc) {
            bench_progress_end(progress);
            return rc;
        }
        samples[n++] = stats->ms;
        total += stats->ms;
        bench_progress_add(progress, 1);
        if (total > budget_ms) break;
        /* The builds the budget still lets run, at the mean time so far. */
        double mean = total / n;
        if (mean > 0 && n + (budget_ms - total) / mean + 1 < repeats)
            bench_progress_total(progress, n + (int)((budget_ms - total) / mean) + 1);
    }
    bench_progress_end(progress);
    accel_timing_of(samples, n, timing);
    stats->ms = timing->median;
    return 0;
}
