/*
 * exp_wide - how much faster are the wide BVHs (bvh:width=4|8) than the
 * binary one, per ray set, and what do they cost in build time and memory?
 *
 * Measured for a shared machine: every configuration is built and traced
 * in turn within each round (A B C A B C ...), timed in thread CPU time
 * (CLOCK_THREAD_CPUTIME_ID, so time spent descheduled by other jobs is not
 * counted), and each round's speed is divided by the first configuration's
 * speed in the same round. Reported: the median speed with its min-max
 * over the rounds, and the median (min-max) of the per-round ratios.
 *
 *   bin/exp_wide [--spec SPEC]... [--wh 800x600] [--scene SPEC]... [harness options]
 * Defaults: bvh, bvh:width=4, bvh:width=8; the shared meshes, sphereflake
 * and teapot_stadium; 800x600; 7 rounds (--repeat).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "harness.h"

#define MAX_SPECS 12
#define MAX_ROUNDS 64
#define MAX_SCENES 16

static double thread_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

static void stats_of(const double *v, int n, accel_timing *t)
{
    double tmp[MAX_ROUNDS];
    memcpy(tmp, v, (size_t)n * sizeof *v);
    accel_timing_of(tmp, n, t);
}

int main(int argc, char **argv)
{
    const char *specs[MAX_SPECS], *scenes[MAX_SCENES];
    int spec_count = 0, scene_count = 0, w = 800, h = 600;
    char *rest[64];
    int rest_count = 0;
    for (int i = 0; i < argc && rest_count < 63; i++) {
        if (i + 1 < argc && !strcmp(argv[i], "--spec") && spec_count < MAX_SPECS)
            specs[spec_count++] = argv[++i];
        else if (i + 1 < argc && !strcmp(argv[i], "--scene") && scene_count < MAX_SCENES)
            scenes[scene_count++] = argv[++i];
        else if (i + 1 < argc && !strcmp(argv[i], "--wh"))
            sscanf(argv[++i], "%dx%d", &w, &h);
        else
            rest[rest_count++] = argv[i];
    }
    rest[rest_count] = NULL;
    exp_ctx x;
    exp_init(&x, rest_count, rest, "exp_wide",
             "How much faster than the binary BVH are 4- and 8-wide BVHs with SIMD kernels?",
             "  --spec SPEC      a configuration (repeatable; the first is the 1.00 reference)\n"
             "  --scene SPEC     a scene (repeatable; default: meshes, sphereflake, teapot_stadium)\n"
             "  --wh WxH         primary rays (default 800x600)\n");
    if (spec_count == 0) {
        specs[spec_count++] = "bvh";
        specs[spec_count++] = "bvh:width=4";
        specs[spec_count++] = "bvh:width=8";
    }
    if (scene_count == 0) {
        if (x.quick) {
            scenes[scene_count++] = "sphereflake:level=1";
            w = h = 64;
        } else {
            for (int i = 0; i < x.mesh_count && scene_count < MAX_SCENES - 2; i++)
                scenes[scene_count++] = x.meshes[i];
            scenes[scene_count++] = "sphereflake";
            scenes[scene_count++] = "teapot_stadium";
        }
    }
    int rounds = x.repeats > 0 ? x.repeats : (x.quick ? 1 : 7);
    if (rounds > MAX_ROUNDS) rounds = MAX_ROUNDS;
    exp_md(&x, "## Wide BVHs (exp_wide)\n\n**Question:** how much faster than the binary BVH "
               "are the 4- and 8-wide BVHs, per ray set, and what do they cost? %dx%d, 1 "
               "thread, %d interleaved rounds, thread CPU time; ratio = per-round speed over "
               "the first configuration's in the same round.\n",
           w, h, rounds);
    exp_csv(&x, "scene,spec,set,rays,mrays_med,mrays_min,mrays_max,ratio_med,ratio_min,"
                "ratio_max,build_ms,bytes_per_prim,steps_per_ray,box_per_ray,prims_per_ray\n");
    static const char *const set_names[3] = {"primary", "shadow", "diffuse"};
    char findings[4096] = "";
    static const int set_bits[3] = {BENCH_PRIMARY, BENCH_SHADOW, BENCH_DIFFUSE};
    for (int si = 0; si < scene_count; si++) {
        accel_scene s;
        exp_scene(&x, scenes[si], &s);
        bench_set_opts so = {NULL, w, h, 1, 0.0f, 1, 1, NULL};
        bench_sets sets;
        accel_error err = {0};
        if (bench_sets_make(&s, &so, BENCH_PRIMARY | BENCH_SHADOW | BENCH_DIFFUSE, &sets, &err)) {
            fprintf(stderr, "%s: %s\n", s.name, err.msg);
            return 1;
        }
        const accel_kind *kind[MAX_SPECS];
        void *accel[MAX_SPECS];
        accel_build_stats st[MAX_SPECS];
        double build_ms[MAX_SPECS][MAX_ROUNDS];
        double mrays[MAX_SPECS][3][MAX_ROUNDS];
        accel_counters cnt[MAX_SPECS][3];
        memset(cnt, 0, sizeof cnt);
        for (int c = 0; c < spec_count; c++) accel[c] = NULL;
        size_t max_rays = 1;
        for (int k = 0; k < 3; k++) {
            size_t n = bench_sets_get(&sets, set_bits[k])->count;
            if (n > max_rays) max_rays = n;
        }
        accel_hit *hits = malloc(max_rays * sizeof *hits);
        uint8_t *occ = malloc(max_rays);
        for (int r = 0; r < rounds; r++)
            for (int c = 0; c < spec_count; c++) {
                /* Build (timed), then trace every set (timed). */
                if (accel[c]) kind[c]->destroy(accel[c]);
                double t0 = thread_ms();
                if (accel_build_spec(specs[c], &s, 1, &kind[c], &accel[c], &st[c], &err)) {
                    fprintf(stderr, "%s on %s: %s\n", specs[c], s.name, err.msg);
                    return 1;
                }
                build_ms[c][r] = thread_ms() - t0;
                for (int k = 0; k < 3; k++) {
                    const rays_set *rs = bench_sets_get(&sets, set_bits[k]);
                    if (r == 0) { /* warm-up pass, which is also the counted one */
                        if (k == 1)
                            accel_trace_occluded(kind[c], accel[c], rs->rays, occ, rs->count, 1, &cnt[c][k]);
                        else
                            accel_trace(kind[c], accel[c], rs->rays, hits, rs->count, 1, &cnt[c][k]);
                    }
                    t0 = thread_ms();
                    if (k == 1)
                        accel_trace_occluded(kind[c], accel[c], rs->rays, occ, rs->count, 1, NULL);
                    else
                        accel_trace(kind[c], accel[c], rs->rays, hits, rs->count, 1, NULL);
                    double ms = thread_ms() - t0;
                    mrays[c][k][r] = ms > 0 ? rs->count / (ms * 1e3) : 0.0;
                }
            }
        exp_md(&x, "\n### %s (%u primitives)\n", s.name, s.live_count);
        double best[3] = {0, 0, 0};
        int best_c[3] = {0, 0, 0};
        exp_md_table(&x, "spec|build ms|B/prim|ray set|Mrays/s|ratio|nodes/ray|boxes/ray|prims/ray");
        for (int c = 0; c < spec_count; c++) {
            accel_timing bt;
            stats_of(build_ms[c], rounds, &bt);
            double bpp = s.live_count ? (double)st[c].bytes / s.live_count : 0.0;
            for (int k = 0; k < 3; k++) {
                accel_timing mt, rt;
                double ratio[MAX_ROUNDS];
                for (int r = 0; r < rounds; r++) ratio[r] = mrays[c][k][r] / mrays[0][k][r];
                stats_of(mrays[c][k], rounds, &mt);
                stats_of(ratio, rounds, &rt);
                if (c > 0 && rt.median > best[k]) best[k] = rt.median, best_c[k] = c;
                const accel_counters *q = &cnt[c][k];
                double n = q->rays ? (double)q->rays : 1.0;
                char a[64];
                exp_md(&x, "| `%s` | %.1f | %.1f | %s | %s | %.2f (%.2f-%.2f) | %.1f | %.1f | %.1f |\n",
                       specs[c], bt.median, bpp, set_names[k], exp_fmt_timing(a, sizeof a, &mt, 2),
                       rt.median, rt.min, rt.max, q->steps / n, q->box_tests / n, q->prim_tests / n);
                exp_csv(&x, "%s,%s,%s,%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.2f,%.3f,%.3f,%.3f\n",
                        s.name, specs[c], set_names[k], bench_sets_get(&sets, set_bits[k])->count,
                        mt.median, mt.min, mt.max, rt.median, rt.min, rt.max, bt.median, bpp,
                        q->steps / n, q->box_tests / n, q->prim_tests / n);
            }
        }
        if (spec_count > 1) {
            size_t len = strlen(findings);
            snprintf(findings + len, sizeof findings - len,
                     "- %s: fastest over `%s`: primary %.2fx (`%s`), shadow %.2fx (`%s`), diffuse "
                     "%.2fx (`%s`).\n",
                     s.name, specs[0], best[0], specs[best_c[0]], best[1], specs[best_c[1]], best[2],
                     specs[best_c[2]]);
        }
        for (int c = 0; c < spec_count; c++) kind[c]->destroy(accel[c]);
        free(hits);
        free(occ);
        bench_sets_free(&sets);
        scene_free(&s);
    }
    exp_md(&x, "\n**Findings:**\n\n%s", findings);
    exp_md(&x, "\nThe issue's targets for the best wide single-ray kernel are 2.8x `bvh` on primary "
               "rays and 3.7x on shadow and diffuse rays (bvh/README.md discusses where the time "
               "goes).\n");
    return exp_finish(&x);
}
