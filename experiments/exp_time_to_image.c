/*
 * exp_time_to_image - build plus trace time against the number of rays.
 *
 * A structure that is slower to build but faster to trace wins once enough
 * rays are traced. With build time B and trace rate R (rays/s, measured on a
 * primary+diffuse mix), the time to trace n rays is B + n/R; two structures
 * cross at n* = (B2 - B1) / (1/R1 - 1/R2). The contenders: the regular
 * grid, binned SAH and full-sweep SAH BVHs (when registered).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"

#define MAX_CONFIGS 8

/* One scene: every configuration measured, then the crossovers of every pair. */
static void measure_scene(exp_ctx *x, const char *spec, const char *const *configs,
                          int config_count, char *findings, size_t fn)
{
    accel_scene s;
    exp_scene(x, spec, &s);
    bench_sets sets;
    exp_sets(x, &s, BENCH_PRIMARY | BENCH_DIFFUSE, &sets);
    exp_md(x, "\n### %s (%u primitives)\n", s.name, s.live_count);
    exp_md_table(x, "structure|build ms|Mrays/s (primary+diffuse)|time for 1M rays, ms|"
                    "for 100M rays, ms");
    double B[MAX_CONFIGS], R[MAX_CONFIGS];
    int ok[MAX_CONFIGS] = {0};
    for (int c = 0; c < config_count; c++) {
        exp_measure m;
        char why[600];
        if (exp_run(x, configs[c], &s, &sets, BENCH_PRIMARY | BENCH_DIFFUSE, &m, why, sizeof why)) {
            exp_md(x, "| %s | skipped: %s | | | |\n", configs[c], why);
            continue;
        }
        double rays = (double)(m.res[0].rays + m.res[2].rays);
        double ms = m.res[0].ms.median + m.res[2].ms.median;
        B[c] = m.build_ms.median;
        R[c] = ms > 0 ? rays / (ms * 1e-3) : INFINITY; /* rays per second */
        ok[c] = 1;
        char bt[64];
        exp_md(x, "| %s | %s | %.2f | %.0f | %.0f |\n", configs[c],
               exp_fmt_timing(bt, sizeof bt, &m.build_ms, 1), R[c] / 1e6, B[c] + 1e9 / R[c],
               B[c] + 1e11 / R[c]);
        exp_csv(x, "%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", s.name, configs[c], B[c],
                m.build_ms.min, m.build_ms.max, R[c] / 1e6, B[c] + 1e9 / R[c], B[c] + 1e11 / R[c]);
    }
    exp_md(x, "\nCrossovers (the faster-tracing structure wins beyond n* rays):\n\n");
    for (int a = 0; a < config_count; a++)
        for (int b = a + 1; b < config_count; b++) {
            if (!ok[a] || !ok[b]) continue;
            /* Let f be the faster builder, g the faster tracer. */
            int f = B[a] <= B[b] ? a : b, g = f == a ? b : a;
            char line[512];
            if (R[g] <= R[f]) {
                snprintf(line, sizeof line, "- %s builds faster and traces at least as fast "
                         "as %s: it wins at every ray count.\n", configs[f], configs[g]);
            } else {
                double n = (B[g] - B[f]) / 1e3 / (1.0 / R[f] - 1.0 / R[g]);
                snprintf(line, sizeof line, "- %s overtakes %s after %.3g rays (%.2f %dx%d "
                         "images of primary+diffuse rays, %.2f 1080p primary frames).\n",
                         configs[g], configs[f], n,
                         n / (double)(sets.primary.count + sets.diffuse.count), x->size, x->size,
                         n / 2073600.0);
            }
            exp_md(x, "%s", line);
            exp_append(findings, fn, "- %s: %s", s.name, line + 2);
        }
    bench_sets_free(&sets);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_time_to_image",
             "At how many rays does a slower-to-build, faster-to-trace structure overtake a "
             "faster-to-build one?",
             NULL);
    static const char *const wanted[] = {"grid", "nested_grid", "bvh:build=binned",
                                         "bvh:build=sah", "bvh:build=mid"};
    const char *configs[MAX_CONFIGS];
    int config_count = 0;
    for (size_t i = 0; i < sizeof wanted / sizeof wanted[0]; i++) {
        accel_params p;
        accel_error err;
        if (accel_params_parse(wanted[i], &p, &err) == 0) configs[config_count++] = wanted[i];
    }
    const char *scenes[8];
    int scene_count = 0;
    if (x.quick) {
        scenes[scene_count++] = "soup:tris=5000";
    } else {
        scenes[scene_count++] = "soup:tris=300000";
        scenes[scene_count++] = "teapot_stadium";
        scenes[scene_count++] = "sphereflake";
        for (int i = 0; i < x.mesh_count && scene_count < 8; i++) scenes[scene_count++] = x.meshes[i];
    }
    exp_md(&x, "## Time to image (exp_time_to_image)\n\n"
               "**Question:** counting build time, how many rays must be traced before a "
               "structure that is slower to build but faster to trace pays off? Trace rate R is "
               "measured on primary plus diffuse rays (%dx%d image); time(n) = build + n/R; two "
               "structures cross at n* = (B2 - B1) / (1/R1 - 1/R2). One 1080p frame is 2.07M "
               "primary rays.\n",
               x.size, x.size);
    exp_csv(&x, "scene,spec,build_ms,build_ms_min,build_ms_max,mrays_mix,time_1M_rays_ms,"
                "time_100M_rays_ms\n");
    char findings[4096] = "";
    for (int si = 0; si < scene_count; si++)
        measure_scene(&x, scenes[si], configs, config_count, findings, sizeof findings);
    exp_md(&x, "\n**Findings:**\n\n%s", findings);
    return exp_finish(&x);
}
