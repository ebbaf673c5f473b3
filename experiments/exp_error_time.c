/*
 * exp_error_time - error against run time.
 *
 * (a) Ambient occlusion images at 1, 2, 4, ... samples per pixel: RMSE
 *     against a converged image (many more samples, another seed) against
 *     the wall time of tracing them, per accelerator; and which accelerator
 *     reaches the lowest error within a fixed time budget (build included).
 * (b) Holes and disagreements against the double-precision reference
 *     against Mrays/s, for the watertight and the naive (Moller-Trumbore)
 *     triangle tests of every kind, on rays aimed exactly at mesh vertices
 *     and edge midpoints of a closed mesh plus ordinary primary rays.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "bench/cli.h"

/* Fraction of unoccluded AO rays per pixel. */
static void ao_image(const rays_set *ao, const uint8_t *occ, int samples, double *img, int pixels)
{
    for (int i = 0; i < pixels; i++) img[i] = -1;
    double *sum = calloc((size_t)pixels, sizeof *sum);
    int *cnt = calloc((size_t)pixels, sizeof *cnt);
    for (size_t i = 0; sum && cnt && i < ao->count; i++) {
        uint32_t p = ao->pixel[i];
        sum[p] += occ[i] ? 0.0 : 1.0;
        cnt[p]++;
    }
    for (int i = 0; sum && cnt && i < pixels; i++)
        if (cnt[i]) img[i] = sum[i] / cnt[i];
    (void)samples;
    free(sum);
    free(cnt);
}

static double rmse(const double *a, const double *b, int n)
{
    double s = 0;
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (a[i] < 0 || b[i] < 0) continue;
        s += (a[i] - b[i]) * (a[i] - b[i]);
        m++;
    }
    return m ? sqrt(s / m) : 0;
}

/* Rays from the camera eye aimed exactly at vertices and at edge midpoints. */
static void stiff_rays(const accel_scene *s, rays_set *out, size_t want)
{
    memset(out, 0, sizeof *out);
    out->rays = malloc(want * sizeof *out->rays);
    if (!out->rays || s->tri_count == 0) return;
    vec3 eye = s->camera.eye;
    size_t k = 0;
    for (size_t i = 0; i < want; i++) {
        uint32_t prim = s->live[(size_t)(rays_rand(11, i, 0) * s->live_count)];
        if (prim >= s->tri_count) continue;
        const float *t = s->tris + 9 * (size_t)prim;
        int c = (int)(rays_rand(11, i, 1) * 3);
        vec3 a = v3_load(t + 3 * c), b = v3_load(t + 3 * ((c + 1) % 3));
        vec3 target = (i & 1) ? v3_scale(v3_add(a, b), 0.5f) : a;
        vec3 d = v3_sub(target, eye);
        accel_ray r = {eye.x, eye.y, eye.z, 0, d.x, d.y, d.z, INFINITY};
        out->rays[k++] = r;
    }
    out->count = k;
}

/* The converged AO image: ref_spp samples with another seed, traced once
 * with the generator structure. */
static void converged_image(exp_ctx *x, const accel_scene *s, const bench_sets *base, int ref_spp,
                            double *ref_img, int pixels)
{
    accel_error err = {0};
    rays_set ref_ao;
    if (rays_ao(s, &base->primary, base->primary_hits, ref_spp,
                0.1f * v3_len(box3_extent(s->bounds)), 999, &ref_ao, &err)) {
        fprintf(stderr, "exp_error_time: %s\n", err.msg);
        exit(cli_exit_of(err.code));
    }
    const accel_kind *k;
    void *a;
    accel_build_stats st;
    const char *gen = accel_find_kind("bvh") ? "bvh" : "brute";
    if (accel_build_spec(gen, s, x->threads, &k, &a, &st, &err)) {
        fprintf(stderr, "exp_error_time: %s\n", err.msg);
        exit(cli_exit_of(err.code));
    }
    uint8_t *occ = malloc(ref_ao.count ? ref_ao.count : 1);
    if (!occ) exit(CLI_EXIT_INTERNAL);
    bench_progress_begin(x->progress, "converged AO image", (double)ref_ao.count, 1);
    accel_trace_occluded(k, a, ref_ao.rays, occ, ref_ao.count, x->threads, NULL);
    bench_progress_end(x->progress);
    ao_image(&ref_ao, occ, ref_spp, ref_img, pixels);
    free(occ);
    k->destroy(a);
    rays_free(&ref_ao);
}

/* (a) RMSE against samples per pixel and time, per accelerator. */
static void error_against_time(exp_ctx *x, const accel_scene *s, const bench_sets *base,
                               const double *ref_img, double *img, int pixels)
{
    accel_error err = {0};
    int max_spp = x->quick ? 4 : 64;
    double budget_ms = x->quick ? 50 : 500;
    char best_line[512] = "";
    double best_err = INFINITY;
    exp_md_table(x, "kind|spp|rays|trace ms|build ms|RMSE");
    for (size_t kk = 0; kk < accel_kind_count; kk++) {
        const accel_kind *kind = accel_kinds[kk];
        if (!strcmp(kind->name, "brute") && !x->quick) {
            exp_md(x, "| brute | skipped: %u primitives x %zu rays per sample is minutes of "
                      "O(N*M) work | | | | |\n", s->live_count, base->primary.count);
            continue;
        }
        const accel_kind *k;
        void *a;
        accel_build_stats st;
        accel_timing bt;
        if (bench_build(kind->name, s, x->threads, x->quick ? 1 : 3, 3000, &k, &a, &st, &bt,
                        x->progress, &err)) {
            exp_md(x, "| %s | skipped: %s | | | | |\n", kind->name, err.msg);
            continue;
        }
        double err_in_budget = NAN;
        int spp_in_budget = 0;
        for (int spp = 1; spp <= max_spp; spp *= 2) {
            rays_set ao;
            if (rays_ao(s, &base->primary, base->primary_hits, spp,
                        0.1f * v3_len(box3_extent(s->bounds)), 5, &ao, &err))
                break;
            uint8_t *occ = malloc(ao.count ? ao.count : 1);
            bench_trace_opts o = {.threads = x->threads, .warmup = 1, .repeats = x->repeats,
                                  .occluded = occ, .progress = x->progress,
                                  .progress_name = "trace ao"};
            bench_result r;
            bench_trace(k, a, &ao, 1, &o, &r, &err);
            ao_image(&ao, occ, spp, img, pixels);
            double e = rmse(img, ref_img, pixels);
            double total = bt.median + r.ms.median;
            if (total <= budget_ms) err_in_budget = e, spp_in_budget = spp;
            exp_md(x, "| %s | %d | %zu | %.1f | %.1f | %.4f |\n", kind->name, spp, ao.count,
                   r.ms.median, bt.median, e);
            exp_csv(x, "ao,%s,%s,%d,%zu,%.4f,%.4f,%.4f,%.6f,,,%.4f\n", s->name, kind->name, spp,
                    ao.count, r.ms.median, bt.median, total, e, r.mrays.median);
            free(occ);
            rays_free(&ao);
        }
        if (spp_in_budget && err_in_budget < best_err) {
            best_err = err_in_budget;
            snprintf(best_line, sizeof best_line,
                     "within %.0f ms (build + trace), %s reaches the lowest error: RMSE %.4f at "
                     "%d samples per pixel.", budget_ms, kind->name, err_in_budget, spp_in_budget);
        }
        k->destroy(a);
    }
    exp_md(x, "\n**Finding (a):** %s\n", best_line[0] ? best_line
                                                       : "no accelerator fits the time budget.");
    exp_md(x, "\nRMSE falls as 1/sqrt(spp) for every accelerator alike (they trace the same "
              "rays to the same answers); what differs is the time per sample, so the fastest "
              "tracer after its build wins any fixed budget.\n");
}

/* (b) Holes and disagreements against speed, watertight and naive. */
static void robustness_against_speed(exp_ctx *x)
{
    accel_error err = {0};
    const char *closed = "sphere"; /* a closed mesh: every ray at it crosses the surface */
    accel_scene cs;
    exp_scene(x, closed, &cs);
    rays_set stiff;
    stiff_rays(&cs, &stiff, x->quick ? 2000 : 100000);
    accel_hit *ref = malloc((stiff.count ? stiff.count : 1) * sizeof *ref);
    if (!ref) exit(CLI_EXIT_INTERNAL);
    exp_reference(x, &cs, stiff.rays, ref, stiff.count);
    exp_md(x, "\n**Question (b):** on %zu rays aimed exactly at vertices and edge midpoints of "
              "`%s` (%u triangles), how many holes (reference hits, tracer misses) and "
              "disagreements per million rays does each kernel make, and how fast is it?\n",
           stiff.count, cs.name, cs.live_count);
    exp_md_table(x, "kind|triangle test|Mrays/s|holes per million|disagreements per million");
    char worst[512] = "";
    double worst_holes = -1;
    for (size_t kk = 0; kk < accel_kind_count; kk++)
        for (int naive = 0; naive < 2; naive++) {
            char spec[128];
            snprintf(spec, sizeof spec, "%s%s", accel_kinds[kk]->name, naive ? ":tri=naive" : "");
            if (!strcmp(accel_kinds[kk]->name, "brute") && cs.live_count > 20000) continue;
            const accel_kind *k;
            void *a;
            accel_build_stats st;
            if (accel_build_spec(spec, &cs, x->threads, &k, &a, &st, &err)) continue;
            accel_hit *h = malloc((stiff.count ? stiff.count : 1) * sizeof *h);
            bench_trace_opts o = {.threads = x->threads, .warmup = 1, .repeats = x->repeats,
                                  .hits = h, .progress = x->progress, .progress_name = spec};
            bench_result r;
            bench_trace(k, a, &stiff, 0, &o, &r, &err);
            hits_diff d = hits_compare(ref, h, stiff.count);
            double hpm = 1e6 * d.holes / (double)(stiff.count ? stiff.count : 1);
            double dpm = 1e6 * (d.disagreements + d.false_hits) / (double)(stiff.count ? stiff.count : 1);
            exp_md(x, "| %s | %s | %.2f | %.0f | %.0f |\n", k->name,
                   naive ? "naive (Moller-Trumbore)" : "watertight", r.mrays.median, hpm, dpm);
            exp_csv(x, "robust,%s,%s,,%zu,%.4f,,,,%.2f,%.2f,%.4f\n", cs.name, spec, stiff.count,
                    r.ms.median, hpm, dpm, r.mrays.median);
            if (naive && hpm > worst_holes) {
                worst_holes = hpm;
                snprintf(worst, sizeof worst, "the naive test leaks up to %.0f holes per million "
                         "such rays (%s)", hpm, k->name);
            }
            free(h);
            k->destroy(a);
        }
    exp_md(x, "\n**Finding (b):** %s; the watertight rows are the robust defaults.\n",
           worst[0] ? worst : "no naive kernel was measured");
    free(ref);
    rays_free(&stiff);
    scene_free(&cs);
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_error_time",
             "Which accelerator reaches the lowest image error in a fixed time, and what do "
             "naive kernels trade in holes for their speed?",
             NULL);
    const char *scene_spec = x.quick ? "sphereflake:level=1" : "sphereflake";
    accel_scene s;
    exp_scene(&x, scene_spec, &s);
    int ref_spp = x.quick ? 16 : 256;
    int pixels = x.size * x.size;
    exp_md(&x, "## Error against run time (exp_error_time)\n\n"
               "**Question (a):** ambient occlusion of `%s` at %dx%d: how does the image error "
               "(RMSE of the unoccluded fraction against a %d-sample converged image with "
               "another seed) fall with samples per pixel and time, per accelerator; which one "
               "gives the lowest error within a fixed time, build included?\n",
               s.name, x.size, x.size, ref_spp);
    exp_csv(&x, "part,scene,spec,spp,rays,trace_ms,build_ms,total_ms,rmse,holes_per_million,"
                "disagreements_per_million,mrays\n");
    bench_sets base;
    exp_sets(&x, &s, BENCH_PRIMARY | BENCH_SHADOW, &base);
    double *ref_img = malloc((size_t)pixels * sizeof *ref_img);
    double *img = malloc((size_t)pixels * sizeof *img);
    if (!ref_img || !img) {
        fprintf(stderr, "exp_error_time: out of memory\n");
        return CLI_EXIT_INTERNAL;
    }
    converged_image(&x, &s, &base, ref_spp, ref_img, pixels);
    error_against_time(&x, &s, &base, ref_img, img, pixels);
    robustness_against_speed(&x);
    free(ref_img);
    free(img);
    bench_sets_free(&base);
    scene_free(&s);
    return exp_finish(&x);
}
