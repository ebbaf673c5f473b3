/*
 * heatmap.c - the experiments' heatmaps (harness.h): a counted pass of
 * primary rays, steps or primitive tests per pixel, written as PNG with a
 * colour scale and placed in the section; one image (exp_heatmap), or a
 * row of specs on one shared scale (exp_heatmaps_shared).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "image/image.h"
#include "engine/harness.h"

#define HEAT_MIN_WIDTH 320

/* The counted primary pass of exp_heatmap: steps ('s') or primitive tests
 * ('p') per pixel into *values (malloc'ed, width*height of the set), their
 * mean per ray and the kind. Returns 0 or nonzero (reason in why). */
static int heat_values(exp_ctx *x, const char *spec, const accel_scene *s, const bench_sets *sets,
                       char what, float **values, double *mean, const accel_kind **kind_out, char *why,
                       size_t why_n)
{
    accel_error err = {0};
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    *values = NULL;
    if (accel_build_spec(spec, s, x->threads, &kind, &accel, &st, &err)) {
        snprintf(why, why_n, "%s", err.msg);
        return 1;
    }
    const rays_set *r = &sets->primary;
    size_t n = r->count;
    uint32_t *steps = calloc(n ? n : 1, sizeof *steps), *prims = calloc(n ? n : 1, sizeof *prims);
    float *v = calloc((size_t)r->width * r->height, sizeof *v);
    accel_hit *hits = malloc((n ? n : 1) * sizeof *hits);
    int rc = 1;
    if (steps && prims && v && hits) {
        accel_counters c = {0};
        c.ray_steps = steps;
        c.ray_prims = prims;
        accel_trace(kind, accel, r->rays, hits, n, x->threads, &c);
        if (accel_counters_status(&c, &err)) {
            exp_internal(x, spec, &err);
            snprintf(why, why_n, "%s", err.msg);
        } else {
            double total = 0;
            for (size_t i = 0; i < n; i++) {
                uint32_t val = what == 's' ? steps[i] : prims[i];
                v[r->pixel[i]] = (float)val;
                total += val;
            }
            *mean = n ? total / (double)n : 0.0;
            *kind_out = kind;
            *values = v;
            v = NULL;
            rc = 0;
        }
    } else {
        snprintf(why, why_n, "out of memory");
    }
    free(steps);
    free(prims);
    free(v);
    free(hits);
    kind->destroy(accel);
    return rc;
}

/* Writes the values of heat_values as DIR/<image_name>.png on `scale` and
 * adds it to the section. */
static int heat_write(exp_ctx *x, const char *spec, const accel_kind *kind, const rays_set *r,
                      const float *v, double mean, char what, const image_heat_scale *scale,
                      const char *top_note, const char *image_name, const char *caption, char *why,
                      size_t why_n)
{
    accel_error err = {0};
    image_rgb img;
    char path[1024], title[256], scale_text[160];
    const char *unit = what == 's' ? kind->step_name : "primitive tests";
    snprintf(path, sizeof path, "%s/%s.png", x->out_dir, image_name);
    image_heat_title(title, sizeof title, spec, kind, what != 's');
    if (scale->max > 0)
        snprintf(scale_text, sizeof scale_text, "%s colour scale from 0 to %g%s%s%s",
                 scale->log ? "logarithmic" : "linear", (double)scale->max, top_note ? " (" : "",
                 top_note ? top_note : "", top_note ? ")" : "");
    else
        snprintf(scale_text, sizeof scale_text, "%s colour scale from 0 to the image's maximum",
                 scale->log ? "logarithmic" : "linear");
    /* Issue 39: at least HEAT_MIN_WIDTH pixels wide. A smaller ray set is
     * drawn with each ray a k x k block (nearest neighbour, k an integer),
     * so that the image is readable and its colour scale keeps its text. */
    int k = r->width > 0 && r->width < HEAT_MIN_WIDTH ? (HEAT_MIN_WIDTH + r->width - 1) / r->width : 1;
    int w = r->width * k, h = r->height * k;
    float *big = k > 1 ? malloc((size_t)w * (size_t)h * sizeof *big) : NULL;
    if (big)
        for (int y = 0; y < h; y++)
            for (int q = 0; q < w; q++) big[(size_t)y * w + q] = v[(size_t)(y / k) * r->width + q / k];
    else
        w = r->width, h = r->height, k = 1;
    int rc = image_heatmap(big ? big : v, w, h, scale, title, &img, &err);
    free(big);
    if (rc == 0) {
        rc = image_write(path, &img, &err);
        image_free(&img);
    }
    if (rc == 0)
        exp_md(x, "\n%s (mean %.1f %s per ray; %s, printed under the image%s):\n\n"
                  "<!-- image: %s -->\n",
               caption, mean, unit, scale_text, k > 1 ? "; each ray a block of pixels" : "",
               image_name);
    else
        snprintf(why, why_n, "%s", err.msg);
    return rc;
}

int exp_heatmap(exp_ctx *x, const char *spec, const accel_scene *s, const bench_sets *sets,
                char what, const char *image_name, const char *caption, char *why, size_t why_n)
{
    float *v;
    double mean;
    const accel_kind *kind;
    if (heat_values(x, spec, s, sets, what, &v, &mean, &kind, why, why_n)) return 1;
    int rc = heat_write(x, spec, kind, &sets->primary, v, mean, what, &x->heat_scale, NULL, image_name,
                        caption, why, why_n);
    free(v);
    return rc;
}

/* The share of a shared heatmap row's pixels below the top of its scale. */
#define HEAT_ROW_QUANTILE 0.995

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

int exp_heatmaps_shared(exp_ctx *x, const char *const *specs, int count, const accel_scene *s,
                        const bench_sets *sets, char what, const char *prefix)
{
    const rays_set *r = &sets->primary;
    size_t pixels = (size_t)r->width * r->height;
    float **v = calloc((size_t)count, sizeof *v);
    double *mean = calloc((size_t)count, sizeof *mean);
    const accel_kind **kind = calloc((size_t)count, sizeof *kind);
    char why[600];
    int written = 0;
    if (!v || !mean || !kind) {
        exp_md(x, "\nHeatmaps on %s: skipped (out of memory)\n", s->name);
        goto done;
    }
    /* One scale for the row: a fixed --heat-scale max, else the 99.5th
     * percentile of all its images' pixels (the largest value alone is one
     * silhouette pixel that leaves every other image dark; the few above
     * it saturate, and the legend says "N+"). */
    image_heat_scale scale = x->heat_scale;
    float *pool = malloc((size_t)count * pixels * sizeof *pool);
    size_t pooled = 0;
    for (int i = 0; i < count; i++) {
        if (heat_values(x, specs[i], s, sets, what, &v[i], &mean[i], &kind[i], why, sizeof why)) {
            exp_md(x, "\n`%s` on %s: skipped (%s)\n", specs[i], s->name, why);
            continue;
        }
        if (pool) {
            memcpy(pool + pooled, v[i], pixels * sizeof *pool);
            pooled += pixels;
        }
    }
    if (scale.max <= 0) {
        float top = 0;
        if (pooled) {
            qsort(pool, pooled, sizeof *pool, cmp_float);
            top = pool[(size_t)ceil(HEAT_ROW_QUANTILE * (double)pooled) - 1];
            if (top <= 0) top = pool[pooled - 1];
        }
        scale.max = top > 0 ? top : 1;
    }
    free(pool);
    for (int i = 0; i < count; i++) {
        if (!v[i]) continue;
        char name[160], caption[256];
        snprintf(name, sizeof name, "%s_%d", prefix, i);
        snprintf(caption, sizeof caption, "`%s` on %s", specs[i], s->name);
        if (heat_write(x, specs[i], kind[i], r, v[i], mean[i], what, &scale,
                       x->heat_scale.max > 0 ? NULL : "the row's 99.5th percentile, brighter pixels saturate",
                       name, caption, why, sizeof why))
            exp_md(x, "\n`%s` on %s: skipped (%s)\n", specs[i], s->name, why);
        else
            written++;
    }
done:
    if (v)
        for (int i = 0; i < count; i++) free(v[i]);
    free(v);
    free(mean);
    free(kind);
    return written;
}

