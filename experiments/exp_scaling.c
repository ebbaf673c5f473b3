/*
 * exp_scaling - how does each accelerator's cost grow with the triangle count?
 *
 * For every registered kind (default parameters) on `soup` (uniform) and
 * `teapot_stadium` (non-uniform) from ~1k triangles up to what the budget
 * allows: build time, memory per triangle, Mrays/s on primary and diffuse
 * rays, steps and primitive tests per ray. The growth exponent k of
 * cost ~ N^k is fitted by least squares on the log-log points.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"

typedef struct {
    double n, build_ms, trace_us_per_ray;
} point;

/* Least-squares slope of log(y) against log(x). */
static double loglog_slope(const double *x, const double *y, int n)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (!(x[i] > 0 && y[i] > 0)) continue;
        double lx = log(x[i]), ly = log(y[i]);
        sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
        m++;
    }
    if (m < 2) return NAN;
    return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

/* Scene families: printf patterns taking the size parameter; the teapot's
 * n gives 64n^2 - 8n triangles (plus a fixed stadium). */
static const char *const families[][2] = {{"soup", "soup:tris=%d"},
                                          {"teapot_stadium", "teapot_stadium:n=%d"}};
#define FAMILY_COUNT 2

/* One kind on one size of a family: a table row and a CSV record. Returns
 * 0 and fills its point, or 1 when the kind could not be measured. */
static int measure_size(exp_ctx *x, int f, const accel_kind *kind, const char *spec,
                        double *tris, double *build_ms, double *trace_ms)
{
    accel_scene s;
    exp_scene(x, spec, &s);
    bench_sets sets;
    exp_sets(x, &s, BENCH_PRIMARY | BENCH_DIFFUSE, &sets);
    exp_measure m;
    char why[600];
    int rc = exp_run(x, kind->name, &s, &sets, BENCH_PRIMARY | BENCH_DIFFUSE, &m, why, sizeof why);
    if (rc) {
        exp_md(x, "| %s | %u | skipped: %s | | | | | | | | |\n", kind->name, s.live_count, why);
    } else {
        const bench_result *p = &m.res[0], *d = &m.res[2];
        char bt[64], pm[64], dm[64];
        exp_md(x, "| %s | %u | %s | %.1f | %.0f | %s | %.1f | %.1f | %s | %.1f | %.1f |\n",
               kind->name, s.live_count, exp_fmt_timing(bt, sizeof bt, &m.build_ms, 1),
               m.build.bytes / 1048576.0, (double)m.build.bytes / s.live_count,
               exp_fmt_timing(pm, sizeof pm, &p->mrays, 2), exp_per_ray(p->counters.steps, p),
               exp_per_ray(p->counters.prim_tests, p), exp_fmt_timing(dm, sizeof dm, &d->mrays, 2),
               exp_per_ray(d->counters.steps, d), exp_per_ray(d->counters.prim_tests, d));
        exp_csv(x, "%s,%s,%s,%u,%.4f,%.4f,%.4f,%zu,%.2f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,"
                   "%.3f,%.3f\n",
                families[f][0], kind->name, kind->name, s.live_count, m.build_ms.median,
                m.build_ms.min, m.build_ms.max, m.build.bytes,
                (double)m.build.bytes / s.live_count, p->mrays.median, p->mrays.min,
                p->mrays.max, d->mrays.median, d->mrays.min, d->mrays.max,
                exp_per_ray(p->counters.steps, p), exp_per_ray(p->counters.prim_tests, p),
                exp_per_ray(d->counters.steps, d), exp_per_ray(d->counters.prim_tests, d));
        *tris = s.live_count;
        *build_ms = m.build_ms.median;
        *trace_ms = p->ms.median + d->ms.median;
    }
    bench_sets_free(&sets);
    scene_free(&s);
    return rc;
}

/* One kind over the sizes of family f, then its growth exponents. */
static void measure_kind(exp_ctx *x, int f, const accel_kind *kind, char *findings, size_t fn)
{
    static const int full_sizes[] = {1000, 4000, 16000, 64000, 256000, 1000000};
    static const int quick_sizes[] = {1000, 4000};
    static const int teapot_full[] = {4, 8, 16, 32, 64, 128};
    const int *sizes = x->quick ? quick_sizes : full_sizes;
    int size_count = x->quick ? 2 : (int)(sizeof full_sizes / sizeof full_sizes[0]);
    double xs[16], build[16], trace[16];
    int pts = 0;
    double last_trace_ms = 0;
    for (int si = 0; si < size_count; si++) {
        char spec[128];
        snprintf(spec, sizeof spec, families[f][1], f == 1 ? teapot_full[si] : sizes[si]);
        /* brute costs N*M: skip sizes whose predicted time exceeds the budget. */
        if (pts > 0 && last_trace_ms * 4 > (x->quick ? 500 : 4000)) {
            exp_md(x, "| %s | next size | skipped: predicted %.0f s per pass (4x the "
                      "triangles, O(N) per ray) | | | | | | | | |\n",
                   kind->name, last_trace_ms * 4 / 1e3);
            break;
        }
        if (measure_size(x, f, kind, spec, &xs[pts], &build[pts], &trace[pts])) break;
        last_trace_ms = trace[pts];
        pts++;
    }
    if (pts >= 2) {
        double kb = loglog_slope(xs, build, pts), kt = loglog_slope(xs, trace, pts);
        exp_append(findings, fn,
                   "- %s on %s: build time grows as N^%.2f, trace time per ray as N^%.2f "
                   "(%.0f to %.0f triangles).\n",
                   kind->name, families[f][0], isnan(kb) ? 0 : kb, isnan(kt) ? 0 : kt, xs[0],
                   xs[pts - 1]);
    }
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_scaling",
             "How do build time, memory and trace time grow with the triangle count, per "
             "accelerator?",
             NULL);
    exp_md(&x, "## Scaling with scene size (exp_scaling)\n\n"
               "**Question:** how do build time, memory and trace time grow with the number of "
               "triangles, for each accelerator? Scenes: `soup` (uniform random triangles) and "
               "`teapot_stadium` (a teapot in a stadium: non-uniform), default parameters of "
               "every kind, %dx%d primary rays and one diffuse bounce.\n",
               x.size, x.size);
    exp_csv(&x, "scene,kind,spec,tris,build_ms,build_ms_min,build_ms_max,bytes,bytes_per_tri,"
                "primary_mrays,primary_mrays_min,primary_mrays_max,diffuse_mrays,diffuse_mrays_min,"
                "diffuse_mrays_max,primary_steps,primary_prims,diffuse_steps,diffuse_prims\n");
    char findings[4096] = "";
    for (int f = 0; f < FAMILY_COUNT; f++) {
        exp_md(&x, "\n### %s\n", families[f][0]);
        exp_md_table(&x, "kind|triangles|build ms|MB|B/tri|primary Mrays/s|steps/ray|prims/ray|"
                         "diffuse Mrays/s|steps/ray|prims/ray");
        for (size_t k = 0; k < accel_kind_count; k++)
            measure_kind(&x, f, accel_kinds[k], findings, sizeof findings);
    }
    exp_md(&x, "\n**Findings** (least-squares exponents of the log-log points):\n\n%s", findings);
    exp_md(&x, "\nA structure whose trace cost grows as N^0.1-0.3 is doing its job "
               "(ideal: log N); brute force grows as N^1. Build costs near N^1 (grids) or "
               "N log N (sorting builders) are expected.\n");
    exp_plot(&x, "exp_scaling",
             "set logscale xy\nset xlabel 'triangles'\nset ylabel 'primary Mrays/s'\n"
             "plot for [k in 'brute grid nested_grid bvh'] csv "
             "using ($4):(strcol(2) eq k && strcol(1) eq 'soup' ? $10 : 1/0) with linespoints "
             "title k");
    return exp_finish(&x);
}
