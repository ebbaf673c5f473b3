/*
 * harness_sets.c - the ray sets of an experiment's scenes (harness.h):
 * the standard sets, the lecture's 800x600 image thinned to one in k of
 * its 8x8 tiles, and the double-precision reference. Split from
 * harness.c.
 */
#include <stdlib.h>

#include "harness.h"
#include "cli/cli.h"

void exp_scene_section(exp_ctx *x, const char *spec, accel_scene *s, int mask, int rt,
                       bench_sets *sets)
{
    exp_scene(x, spec, s);
    if (rt > 1)
        exp_sets_tiles(x, s, mask, rt, sets);
    else if (rt)
        exp_sets_wh(x, s, mask, x->rt_size[0], x->rt_size[1], 1, sets);
    else
        exp_sets(x, s, mask, sets);
    exp_md(x, "\n### %s (%u primitives)\n", s->name, s->live_count);
    if (rt > 1)
        exp_md(x, "\nRays of one in %d of the 8x8 pixel tiles of the %dx%d image (its density "
                  "and coherence at 1/%d of its work).\n", rt, x->rt_size[0], x->rt_size[1], rt);
}

void exp_sets(exp_ctx *x, const accel_scene *s, int mask, bench_sets *out)
{
    exp_sets_wh(x, s, mask, x->size, x->size, 4, out);
}

void exp_note_image(exp_ctx *x, int w, int h)
{
    for (int i = 0; i < x->image_count; i++)
        if (x->images[i][0] == w && x->images[i][1] == h) return;
    if (x->image_count < 4) x->images[x->image_count][0] = w, x->images[x->image_count++][1] = h;
}

void exp_sets_wh(exp_ctx *x, const accel_scene *s, int mask, int w, int h, int ao_samples,
                 bench_sets *out)
{
    accel_error err = {0};
    exp_note_image(x, w, h);
    bench_set_opts o = {NULL, w, h, ao_samples, 0, 1, x->threads, NULL};
    bench_progress_begin(x->progress, "make ray sets", 0, 0);
    int rc = bench_sets_make(s, &o, mask, out, &err);
    bench_progress_end(x->progress);
    if (rc) {
        fprintf(stderr, "%s: ray sets for %s: %s\n", x->name, s->name, err.msg);
        exit(cli_exit_of(err.code));
    }
}

/* Keeps the rays of r (and hits, when given) whose pixel lies in a kept
 * tile; rays without pixels are kept. */
static void keep_tiles(rays_set *r, accel_hit *hits, int w, int stride)
{
    if (!r->pixel || !r->count || w <= 0) return;
    size_t k = 0;
    int tiles_x = (w + 7) / 8;
    for (size_t i = 0; i < r->count; i++) {
        uint32_t p = r->pixel[i];
        uint32_t tile = (p / (uint32_t)w / 8) * (uint32_t)tiles_x + (p % (uint32_t)w) / 8;
        if (tile % (uint32_t)stride) continue;
        r->rays[k] = r->rays[i], r->pixel[k] = p;
        if (hits) hits[k] = hits[i];
        k++;
    }
    r->count = k;
}

int exp_sets_tiles(exp_ctx *x, const accel_scene *s, int mask, int stride, bench_sets *out)
{
    int w = x->rt_size[0], h = x->rt_size[1];
    if (stride <= 0) stride = (int)((double)w * h / ((double)x->size * x->size));
    if (stride < 1) stride = 1;
    exp_sets_wh(x, s, mask, w, h, 1, out);
    keep_tiles(&out->primary, out->primary_hits, w, stride);
    keep_tiles(&out->shadow, NULL, w, stride);
    keep_tiles(&out->diffuse, NULL, w, stride);
    keep_tiles(&out->ao, NULL, w, stride);
    return stride;
}

void exp_reference(exp_ctx *x, const accel_scene *s, const accel_ray *rays, accel_hit *hits,
                   size_t count)
{
    char phase[200];
    snprintf(phase, sizeof phase, "reference on %s", s->name);
    bench_progress_begin(x->progress, phase, (double)count, 1);
    accel_reference_trace(s, rays, hits, count, x->threads);
    bench_progress_end(x->progress);
}

