/*
 * test_tools_heat.c - exp_wide's heatmaps, run as a subprocess and read
 * back: one colour scale per row of widths (the captions and the decoded
 * PNG pixels).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "image/image.h"
#include "png_decode.h"
#include "support.h"
#include "test.h"

#define DIR "build/test_tools_heat"

static int run(const char *cmd, char **out, char **err) { return test_run(DIR, cmd, out, err); }

/* ---- exp_wide's heatmaps: one colour scale per row ---------------------- */

/* The row `prefix`'s captions in md, in order: the top of each image's
 * scale and its mean per ray. Returns how many. */
static int heat_row(const char *md, const char *prefix, double *top, double *mean, int cap)
{
    int n = 0;
    for (int i = 0; i < cap; i++) {
        char tag[96];
        snprintf(tag, sizeof tag, "<!-- image: %s_%d -->", prefix, i);
        const char *img = strstr(md, tag);
        if (!img) break;
        /* the caption is the paragraph before the tag */
        const char *c = img;
        while (c > md && !(c[-1] == '\n' && c[0] == '`')) c--;
        const char *m = strstr(c, "(mean "), *s = strstr(c, "colour scale from 0 to ");
        if (!m || m > img || sscanf(m, "(mean %lf", &mean[n]) != 1) break;
        if (!s || s > img || sscanf(s, "colour scale from 0 to %lf", &top[n]) != 1) break;
        n++;
    }
    return n;
}

/* Pixels of the image part (above the legend) of a heatmap PNG in the top
 * colour of the scale; -1 if it cannot be read. */
static long top_colour_pixels(const char *path, int want_w, int want_h)
{
    size_t n;
    char *png = test_read_file(path, &n);
    if (!png) return -1;
    int w, h;
    uint8_t *rgb = NULL, top[3];
    char msg[200];
    png_stats st;
    long count = -1;
    image_heat_color(1.0f, top);
    if (test_png_decode((const uint8_t *)png, n, &w, &h, &rgb, &st, msg, sizeof msg) == 0 &&
        w == want_w && h > want_h) {
        count = 0;
        for (long p = 0; p < (long)want_w * want_h; p++) count += !memcmp(rgb + 3 * p, top, 3);
    }
    free(rgb);
    free(png);
    return count;
}

/* Issue 11's "look at the heatmaps of the wide trees": exp_wide draws node
 * visits and primitive tests per primary ray of widths 2, 4 and 8 (and the
 * 8-wide packets) on one scale per row, topped at the row's 99.5th
 * percentile, so colours compare across widths: every caption of a row
 * names the same top, the top colour appears in the binary tree's image
 * (whose outline reaches it) and not in the 8-wide one's (with each image
 * on its own scale, every image would have it), and wider trees visit
 * fewer nodes. */
TEST(tools_exp_wide_heatmaps_share_a_scale)
{
    mkdir(DIR, 0755);
    CHECK(run("bin/exp_wide --quick --quiet --out " DIR "/wide --scene teapot_stadium:n=3,stadium=24,tiers=3 "
              "--only-accels --accel bvh:width=8",
              NULL, NULL) == 0);
    char *md = test_read_file(DIR "/wide/exp_wide.md", NULL);
    CHECK(md != NULL);
    if (!md) return;
    double top[4], mean[4];
    int steps = heat_row(md, "wide_heat_steps_0", top, mean, 4);
    CHECKF(steps == 4, "%d step heatmaps with captions, want 4 (bvh, widths 4 and 8, packets)", steps);
    for (int i = 1; i < steps; i++)
        CHECKF(top[i] == top[0], "image %d's scale tops at %g, image 0's at %g", i, top[i], top[0]);
    for (int i = 0; i < steps; i++)
        CHECKF(mean[i] <= top[i], "image %d: mean %g above the scale's top %g", i, mean[i], top[i]);
    if (steps == 4) {
        CHECKF(mean[0] > mean[1] && mean[1] > mean[2], "nodes per ray: bvh %g, width 4 %g, width 8 %g",
               mean[0], mean[1], mean[2]);
        long px[4];
        for (int i = 0; i < 4; i++) {
            char path[256];
            snprintf(path, sizeof path, DIR "/wide/wide_heat_steps_0_%d.png", i);
            px[i] = top_colour_pixels(path, 320, 240);
            CHECKF(px[i] >= 0, "%s: not a 320-pixel-wide heatmap", path);
        }
        /* the binary tree's silhouette pixels reach the row's top; the
         * 8-wide single-ray kernel, at a third of its visits, does not */
        CHECKF(px[0] > 0, "the row's top colour missing from bvh's image");
        CHECKF(px[2] == 0, "width 8's image has %ld pixels at the row's top", px[2]);
    }
    int prims = heat_row(md, "wide_heat_prims_0", top, mean, 3);
    CHECKF(prims == 3, "%d primitive heatmaps, want 3", prims);
    for (int i = 1; i < prims; i++)
        CHECKF(top[i] == top[0], "primitive row: image %d tops at %g, image 0 at %g", i, top[i], top[0]);
    free(md);
}
