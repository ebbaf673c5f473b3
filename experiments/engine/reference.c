/*
 * reference.c - the reference kernel timed in every round (harness.h,
 * issue 52) and the steal time of /proc/stat.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"

int exp_ref_ready(exp_ctx *x)
{
    if (x->ref_state) return x->ref_state > 0 ? 0 : -1;
    x->ref_state = -1;
    accel_error err = {0};
    if (scene_create("soup:tris=250", &x->ref_scene, &err)) {
        fprintf(stderr, "%s: reference scene: %s\n", x->name, err.msg);
        return -1;
    }
    bench_set_opts o = {NULL, 32, 32, 0, 0, 1, 1, NULL};
    if (bench_sets_make(&x->ref_scene, &o, BENCH_PRIMARY, &x->ref_sets, &err)) {
        fprintf(stderr, "%s: reference rays: %s\n", x->name, err.msg);
        scene_free(&x->ref_scene);
        return -1;
    }
    const accel_kind *kind = NULL;
    accel_build_stats st;
    if (accel_build_spec("brute", &x->ref_scene, 1, &kind, &x->ref_accel, &st, &err)) {
        fprintf(stderr, "%s: reference kernel: %s\n", x->name, err.msg);
        bench_sets_free(&x->ref_sets);
        scene_free(&x->ref_scene);
        return -1;
    }
    x->ref_kind = kind;
    x->ref_state = 1;
    return 0;
}

double exp_ref_time(const exp_ctx *x)
{
    if (x->ref_state != 1) return 0;
    const accel_kind *kind = x->ref_kind;
    const rays_set *r = &x->ref_sets.primary;
    static accel_hit hits[4096];
    size_t n = r->count < 4096 ? r->count : 4096;
    if (!n) return 0;
    /* the median of 3 passes (about 2 ms each): one pass caught by an
     * interrupt or a neighbour's burst made a process's mean stray */
    double t[3];
    for (int i = 0; i < 3; i++) {
        double t0 = accel_now_ms();
        accel_trace(kind, x->ref_accel, r->rays, hits, n, 1, NULL);
        t[i] = (accel_now_ms() - t0) * 1e6 / (double)n;
    }
    double lo = fmin(t[0], t[1]), hi = fmax(t[0], t[1]);
    return t[2] < lo ? lo : t[2] > hi ? hi : t[2];
}

void exp_ref_note(exp_ctx *x, const double *ns, int n)
{
    if (x->ref_n + n > x->ref_cap) {
        int cap = x->ref_cap ? 2 * x->ref_cap : 256;
        while (cap < x->ref_n + n) cap *= 2;
        double *m = realloc(x->ref_ms, (size_t)cap * sizeof *m);
        if (!m) return;
        x->ref_ms = m, x->ref_cap = cap;
    }
    for (int i = 0; i < n; i++)
        if (ns[i] > 0) x->ref_ms[x->ref_n++] = ns[i];
}

int exp_cpu_ticks(double *steal, double *total)
{
    *steal = *total = 0;
    FILE *f = fopen("/proc/stat", "r");
    if (!f) return -1;
    double v[10] = {0};
    int got = fscanf(f, "cpu %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4],
                     &v[5], &v[6], &v[7]);
    fclose(f);
    if (got < 8) return -1;
    for (int i = 0; i < 8; i++) *total += v[i];
    *steal = v[7];
    return 0;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void exp_ref_footer(exp_ctx *x)
{
    if (x->ref_n < 2) return;
    double *v = malloc((size_t)x->ref_n * sizeof *v);
    if (!v) return;
    memcpy(v, x->ref_ms, (size_t)x->ref_n * sizeof *v);
    qsort(v, (size_t)x->ref_n, sizeof *v, cmp_d);
    int n = x->ref_n;
    double med = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    double p10 = v[n / 10], p90 = v[n - 1 - n / 10];
    exp_md(x, "\n_Reference kernel (brute force over soup:tris=250, 1024 rays, one thread) in "
              "every timed round: %.0f ns per ray at the median of %d rounds (the stated rate %.0f: "
              "this machine ran at %.2fx its time), 10th-90th percentile %.0f-%.0f (%+.1f%% to "
              "%+.1f%%), min-max %.0f-%.0f; steal time %.1f%% of the CPU time during the "
              "section's rounds._\n",
           med, n, EXP_REF_NS_PER_RAY, med / EXP_REF_NS_PER_RAY, p10, p90, 100 * (p10 / med - 1),
           100 * (p90 / med - 1), v[0], v[n - 1],
           x->cpu_ticks > 0 ? 100 * x->steal_ticks / x->cpu_ticks : 0.0);
    free(v);
}

const char *exp_ref_absolute(exp_ctx *x, const double *ns, int n, exp_decider *d, int rate,
                             char *why, size_t why_n)
{
    double v[EXP_MAX_SAMPLES];
    int m = 0;
    for (int i = 0; i < n && m < EXP_MAX_SAMPLES; i++)
        if (ns[i] > 0) v[m++] = ns[i];
    exp_ref_note(x, v, m);
    if (m < 2) {
        snprintf(why, why_n, "the reference kernel was not timed beside these rounds: an absolute "
                 "threshold cannot be judged here");
        return EXP_UNTESTABLE;
    }
    qsort(v, (size_t)m, sizeof *v, cmp_d);
    double med = m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2]);
    double p10 = v[m / 10], p90 = v[m - 1 - m / 10];
    return exp_ref_normalize(d, rate, med, p10, p90, "10th to 90th percentile", p90 / p10 - 1,
                             why, why_n);
}

void exp_ref_free(exp_ctx *x)
{
    if (x->ref_state == 1) {
        ((const accel_kind *)x->ref_kind)->destroy(x->ref_accel);
        bench_sets_free(&x->ref_sets);
        scene_free(&x->ref_scene);
    }
    x->ref_state = 0;
    free(x->ref_ms);
    x->ref_ms = NULL;
    x->ref_n = x->ref_cap = 0;
}
