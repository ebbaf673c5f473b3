/*
 * exp_threads - how do build and trace scale from 1 to nproc threads?
 *
 * Every registered kind (default parameters, brute left out: it says
 * nothing about structures) builds and traces primary and diffuse rays with
 * 1..nproc threads. Speed-up = time(1) / time(n); efficiency = speed-up / n.
 * The lecture claims "near-linear scaling in cores, about +20% from
 * hyper-threading".
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"

/* One kind with 1..max_threads threads: a row per count, and its finding. */
static void scale_kind(exp_ctx *x, const accel_kind *kind, const accel_scene *s,
                       const bench_sets *sets, int max_threads, char *findings, size_t fn)
{
    int base_threads = x->threads;
    double b1 = 0, p1 = 0, d1 = 0;
    for (int t = 1; t <= max_threads; t++) {
        x->threads = t;
        exp_measure m;
        char why[600];
        if (exp_run(x, kind->name, s, sets, BENCH_PRIMARY | BENCH_DIFFUSE, &m, why, sizeof why)) {
            exp_md(x, "| %s | %d | skipped: %s | | | | | | | |\n", kind->name, t, why);
            break;
        }
        double b = m.build_ms.median, p = m.res[0].mrays.median, d = m.res[2].mrays.median;
        if (t == 1) b1 = b, p1 = p, d1 = d;
        char bt[64], pt[64], dt[64];
        exp_md(x, "| %s | %d | %s | %.2f | %s | %.2f | %.0f%% | %s | %.2f | %.0f%% |\n",
               kind->name, t, exp_fmt_timing(bt, sizeof bt, &m.build_ms, 1), b > 0 ? b1 / b : 0,
               exp_fmt_timing(pt, sizeof pt, &m.res[0].mrays, 2), p1 > 0 ? p / p1 : 0,
               p1 > 0 ? 100 * p / p1 / t : 0, exp_fmt_timing(dt, sizeof dt, &m.res[2].mrays, 2),
               d1 > 0 ? d / d1 : 0, d1 > 0 ? 100 * d / d1 / t : 0);
        exp_csv(x, "%s,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", kind->name, t, b,
                m.build_ms.min, m.build_ms.max, p, m.res[0].mrays.min, m.res[0].mrays.max, d,
                m.res[2].mrays.min, m.res[2].mrays.max);
        if (t == max_threads && t > 1)
            exp_append(findings, fn,
                       "- %s: %d threads trace primary rays %.2fx and diffuse rays %.2fx as fast "
                       "as 1 (efficiency %.0f%% / %.0f%%); build %.2fx.\n",
                       kind->name, t, p / p1, d / d1, 100 * p / p1 / t, 100 * d / d1 / t,
                       b > 0 ? b1 / b : 0);
    }
    x->threads = base_threads;
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_threads",
             "How do build and trace times scale with the number of threads?", NULL);
    int nproc = accel_cpu_count();
    /* --threads is the largest count measured; the ray sets and the
     * reference builds use it as well. */
    int max_threads = x.threads_given ? x.threads : nproc;
    const char *scene_spec = x.quick ? "soup:tris=20000"
                             : x.mesh_count ? x.meshes[0] : "soup:tris=200000";
    accel_scene s;
    exp_scene(&x, scene_spec, &s);
    exp_md(&x, "## Thread scaling (exp_threads)\n\n"
               "**Question:** how do build and trace times scale from 1 to %d threads (%s)? "
               "Scene `%s` (%u primitives), %dx%d primary rays and one diffuse "
               "bounce; rays are handed out from a shared counter in chunks of about 1/16 of a "
               "thread's share (%zu primary rays per chunk at %d threads, at most %d).\n\n"
               "**Lecture's claim:** \"near-linear scaling in cores, and about +20%% from "
               "hyper-threading\".\n",
               max_threads, x.threads_given ? "the --threads limit" : "this machine's cores",
               s.name, s.live_count, x.size, x.size,
               accel_trace_chunk((size_t)x.size * x.size, max_threads), max_threads, ACCEL_CHUNK);
    exp_csv(&x, "kind,threads,build_ms,build_ms_min,build_ms_max,primary_mrays,primary_min,"
                "primary_max,diffuse_mrays,diffuse_min,diffuse_max\n");
    exp_md_table(&x, "kind|threads|build ms|build speed-up|primary Mrays/s|speed-up|efficiency|"
                     "diffuse Mrays/s|speed-up|efficiency");
    bench_sets sets;
    exp_sets(&x, &s, BENCH_PRIMARY | BENCH_DIFFUSE, &sets);
    char findings[2048] = "";
    if (max_threads < 2)
        snprintf(findings, sizeof findings, "- skipped scaling: %s, nothing to scale.\n",
                 x.threads_given ? "--threads 1 allows one thread" : "this machine has one core");
    for (size_t k = 0; k < accel_kind_count; k++)
        if (strcmp(accel_kinds[k]->name, "brute"))
            scale_kind(&x, accel_kinds[k], &s, &sets, max_threads, findings, sizeof findings);
    exp_md(&x, "\n**Findings:**\n\n%s", findings);
    exp_md(&x, "\nThis machine exposes %d logical CPUs; whether they are separate cores or "
               "hyper-threads of one core is not visible from inside a virtual machine, so the "
               "+20%% hyper-threading claim cannot be separated from core scaling here.\n",
           nproc);
    bench_sets_free(&sets);
    scene_free(&s);
    return exp_finish(&x);
}
