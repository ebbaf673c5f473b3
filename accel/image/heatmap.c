/*
 * heatmap.c - per-pixel cost images: a colour scale (linear or logarithmic,
 * from 0 to a fixed or automatic maximum, so that two images can share
 * one), and a legend under the image: a title naming the unit, the colour
 * bar, and ticks at the scale's ends and at round values between.
 * The text uses a 5x7 pixel font drawn here (ASCII 32..126).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image/image.h"

void image_heat_color(float x, uint8_t rgb[3])
{
    /* Control points of a dark-blue -> purple -> orange -> yellow -> white ramp
     * (monotone in lightness, so cost order reads from brightness alone). */
    static const float stops[][3] = {{0.02f, 0.02f, 0.12f}, {0.25f, 0.05f, 0.55f},
                                     {0.75f, 0.15f, 0.40f}, {0.98f, 0.50f, 0.05f},
                                     {1.00f, 0.90f, 0.20f}, {1.00f, 1.00f, 1.00f}};
    const int n = (int)(sizeof stops / sizeof stops[0]);
    if (!(x > 0.0f)) x = 0.0f;
    if (x > 1.0f) x = 1.0f;
    float f = x * (float)(n - 1);
    int i = (int)f;
    if (i >= n - 1) i = n - 2;
    float w = f - (float)i;
    for (int c = 0; c < 3; c++)
        rgb[c] = (uint8_t)lrintf(255.0f * (stops[i][c] * (1 - w) + stops[i + 1][c] * w));
}

/* 5x7 glyphs in an 8-row cell (row 7 holds descenders): one byte per row,
 * top row first, bit 4 the leftmost pixel. Characters not listed are blank. */
#define GLYPH(ch, ...) [(ch) - 32] = {__VA_ARGS__}
static const uint8_t font[95][8] = {
    GLYPH('!', 0x04, 0x04, 0x04, 0x04, 0x04, 0x00, 0x04),
    GLYPH('"', 0x0A, 0x0A, 0x00, 0x00, 0x00, 0x00, 0x00),
    GLYPH('#', 0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A),
    GLYPH('%', 0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03),
    GLYPH('\'', 0x04, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00),
    GLYPH('(', 0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02),
    GLYPH(')', 0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08),
    GLYPH('*', 0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00),
    GLYPH('+', 0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00),
    GLYPH(',', 0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08),
    GLYPH('-', 0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00),
    GLYPH('.', 0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C),
    GLYPH('/', 0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00),
    GLYPH('0', 0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E),
    GLYPH('1', 0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E),
    GLYPH('2', 0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F),
    GLYPH('3', 0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E),
    GLYPH('4', 0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02),
    GLYPH('5', 0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E),
    GLYPH('6', 0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E),
    GLYPH('7', 0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08),
    GLYPH('8', 0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E),
    GLYPH('9', 0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C),
    GLYPH(':', 0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00),
    GLYPH(';', 0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x04, 0x08),
    GLYPH('<', 0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02),
    GLYPH('=', 0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00),
    GLYPH('>', 0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08),
    GLYPH('?', 0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04),
    GLYPH('A', 0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11),
    GLYPH('B', 0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E),
    GLYPH('C', 0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E),
    GLYPH('D', 0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E),
    GLYPH('E', 0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F),
    GLYPH('F', 0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10),
    GLYPH('G', 0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F),
    GLYPH('H', 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11),
    GLYPH('I', 0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E),
    GLYPH('J', 0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C),
    GLYPH('K', 0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11),
    GLYPH('L', 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F),
    GLYPH('M', 0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11),
    GLYPH('N', 0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11),
    GLYPH('O', 0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E),
    GLYPH('P', 0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10),
    GLYPH('Q', 0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D),
    GLYPH('R', 0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11),
    GLYPH('S', 0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E),
    GLYPH('T', 0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04),
    GLYPH('U', 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E),
    GLYPH('V', 0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04),
    GLYPH('W', 0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A),
    GLYPH('X', 0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11),
    GLYPH('Y', 0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04),
    GLYPH('Z', 0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F),
    GLYPH('[', 0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E),
    GLYPH(']', 0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E),
    GLYPH('^', 0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00),
    GLYPH('_', 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F),
    GLYPH('a', 0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F),
    GLYPH('b', 0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E),
    GLYPH('c', 0x00, 0x00, 0x0E, 0x10, 0x10, 0x11, 0x0E),
    GLYPH('d', 0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F),
    GLYPH('e', 0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E),
    GLYPH('f', 0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08),
    GLYPH('g', 0x00, 0x00, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x0E),
    GLYPH('h', 0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11),
    GLYPH('i', 0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E),
    GLYPH('j', 0x02, 0x00, 0x06, 0x02, 0x02, 0x02, 0x12, 0x0C),
    GLYPH('k', 0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12),
    GLYPH('l', 0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E),
    GLYPH('m', 0x00, 0x00, 0x1A, 0x15, 0x15, 0x15, 0x15),
    GLYPH('n', 0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11),
    GLYPH('o', 0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E),
    GLYPH('p', 0x00, 0x00, 0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10),
    GLYPH('q', 0x00, 0x00, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x01),
    GLYPH('r', 0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10),
    GLYPH('s', 0x00, 0x00, 0x0F, 0x10, 0x0E, 0x01, 0x1E),
    GLYPH('t', 0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06),
    GLYPH('u', 0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D),
    GLYPH('v', 0x00, 0x00, 0x11, 0x11, 0x11, 0x0A, 0x04),
    GLYPH('w', 0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0A),
    GLYPH('x', 0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11),
    GLYPH('y', 0x00, 0x00, 0x11, 0x11, 0x11, 0x0F, 0x01, 0x0E),
    GLYPH('z', 0x00, 0x00, 0x1F, 0x02, 0x04, 0x08, 0x1F),
    GLYPH('|', 0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04),
};
#undef GLYPH

int image_text_width(const char *text, int s)
{
    int n = (int)strlen(text);
    return n ? (n * 6 - 1) * s : 0;
}

void image_text(image_rgb *img, int x, int y, int s, const char *text, const uint8_t rgb[3])
{
    for (; *text; text++, x += 6 * s) {
        unsigned ch = (unsigned char)*text;
        if (ch < 32 || ch > 126) continue;
        const uint8_t *g = font[ch - 32];
        for (int gy = 0; gy < 8; gy++)
            for (int gx = 0; gx < 5; gx++) {
                if (!(g[gy] >> (4 - gx) & 1)) continue;
                for (int dy = 0; dy < s; dy++)
                    for (int dx = 0; dx < s; dx++) {
                        int px = x + gx * s + dx, py = y + gy * s + dy;
                        if (px < 0 || py < 0 || px >= img->width || py >= img->height) continue;
                        memcpy(img->rgb + ((size_t)py * img->width + px) * 3, rgb, 3);
                    }
            }
    }
}

int image_heat_scale_parse(const char *spec, image_heat_scale *out, accel_error *err)
{
    image_heat_scale sc = {0, 0};
    const char *p = spec;
    for (;;) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        if (len == 0) {
            return accel_fail(err, ACCEL_ERR_SPEC, "heat scale '%s': empty item", spec);
        } else if (len == 3 && !strncmp(p, "log", 3)) {
            sc.log = 1;
        } else if ((len == 3 && !strncmp(p, "lin", 3)) || (len == 6 && !strncmp(p, "linear", 6))) {
            sc.log = 0;
        } else if (len == 4 && !strncmp(p, "auto", 4)) {
            sc.max = 0;
        } else if (len > 4 && !strncmp(p, "max=", 4)) {
            char num[64], *e;
            snprintf(num, sizeof num, "%.*s", (int)(len - 4), p + 4);
            double v = strtod(num, &e);
            if (*e || !(v > 0) || !(v < 1e30))
                return accel_fail(err, ACCEL_ERR_SPEC, "heat scale '%s': max=%s is not a positive number",
                                  spec, num);
            sc.max = (float)v;
        } else {
            return accel_fail(err, ACCEL_ERR_SPEC,
                              "heat scale '%s': expected a comma list of auto, lin, log, max=N", spec);
        }
        if (!end) break;
        p = end + 1;
    }
    *out = sc;
    return 0;
}

float image_heat_position(const image_heat_scale *sc, float v)
{
    if (!(v > 0) || !(sc->max > 0)) return 0.0f;
    float x = sc->log ? log1pf(v) / log1pf(sc->max) : v / sc->max;
    return x < 1.0f ? x : 1.0f;
}

void image_heat_title(char *buf, size_t n, const char *spec, const accel_kind *kind, int prims)
{
    if (prims)
        snprintf(buf, n, "%s: primitive tests per ray", spec);
    else
        snprintf(buf, n, "%s: %s %s per ray", spec, kind->step_name,
                 strcmp(kind->step_name, "cells") ? "visited" : "stepped");
}

/* A tick label: integers as such, other values with 3 significant digits. */
static void format_value(char *buf, size_t n, double v, int clipped)
{
    if (v == floor(v) && v < 1e6)
        snprintf(buf, n, "%.0f%s", v, clipped ? "+" : "");
    else
        snprintf(buf, n, "%.3g%s", v, clipped ? "+" : "");
}

/* Draws the label centred on x (kept inside the image) unless it would
 * overlap an interval in used[]; returns whether it drew. */
static int place_label(image_rgb *img, int x, int y, int s, const char *label, int used[][2],
                       int *used_n)
{
    int w = image_text_width(label, s), x0 = x - w / 2;
    if (x0 < 1) x0 = 1;
    if (x0 + w > img->width - 1) x0 = img->width - 1 - w;
    for (int i = 0; i < *used_n; i++)
        if (x0 < used[i][1] + 3 * s && x0 + w + 3 * s > used[i][0]) return 0;
    static const uint8_t white[3] = {255, 255, 255};
    image_text(img, x0, y, s, label, white);
    used[*used_n][0] = x0, used[*used_n][1] = x0 + w;
    (*used_n)++;
    return 1;
}

/* Splits text into lines of at most `cols` characters at spaces (a longer
 * word is cut). Returns the number of lines written into lines[][]. */
static int wrap_text(const char *text, int cols, char lines[][128], int max_lines)
{
    int count = 0;
    if (cols > 127) cols = 127;
    if (cols < 1) cols = 1;
    while (*text && count < max_lines) {
        while (*text == ' ') text++;
        int n = (int)strlen(text);
        if (!n) break;
        int take = n <= cols ? n : cols;
        if (n > cols) {
            int cut = take;
            while (cut > 0 && text[cut] != ' ') cut--;
            if (cut > 0) take = cut;
        }
        snprintf(lines[count++], 128, "%.*s", take, text);
        text += take;
    }
    return count;
}

int image_heatmap(const float *values, int width, int height, const image_heat_scale *scale,
                  const char *title, image_rgb *out, accel_error *err)
{
    image_heat_scale sc = scale ? *scale : (image_heat_scale){0, 0};
    float top = 0;
    for (size_t i = 0; i < (size_t)width * height; i++)
        if (values[i] > top) top = values[i];
    int clipped = sc.max > 0 && top > sc.max;
    if (!(sc.max > 0)) sc.max = top > 0 ? top : 1;
    /* Legend geometry: text scale s, title lines, bar, tick marks, labels. */
    int s = width >= 400 ? 2 : 1, line = 9 * s, pad = 3 * s;
    char full[256], lines[8][128];
    snprintf(full, sizeof full, "%s%s%s", title ? title : "", title && *title && sc.log ? ", " : "",
             sc.log ? "log scale" : "");
    int title_lines = wrap_text(full, (width - 2) / (6 * s), lines, 8);
    int bar_y = height + pad + title_lines * line + (title_lines ? s : 0), bar_h = 5 * s;
    int tick_h = 2 * s, label_y = bar_y + bar_h + tick_h + s;
    int legend = label_y + line + pad - height;
    int rc = image_alloc(out, width, height + legend, err);
    if (rc) return rc;
    for (size_t i = 0; i < (size_t)width * height; i++)
        image_heat_color(image_heat_position(&sc, values[i]), out->rgb + 3 * i);
    static const uint8_t white[3] = {255, 255, 255};
    for (int l = 0; l < title_lines; l++)
        image_text(out, (width - image_text_width(lines[l], s)) / 2, height + pad + l * line, s,
                   lines[l], white);
    /* The bar spans x0..x1; the colour at x is the scale's colour at that fraction. */
    int x0 = width > 2 ? 1 : 0, x1 = width > 2 ? width - 2 : width - 1;
    for (int y = bar_y; y < bar_y + bar_h; y++)
        for (int x = x0; x <= x1; x++)
            image_heat_color((float)(x - x0) / (float)(x1 > x0 ? x1 - x0 : 1),
                             out->rgb + ((size_t)y * width + x) * 3);
    /* Ticks: both ends first (they always print), then round values between:
     * powers of ten on a log scale, multiples of a 1-2-5 step otherwise. */
    double ticks[64];
    int tick_n = 0;
    ticks[tick_n++] = sc.max;
    ticks[tick_n++] = 0;
    if (sc.log) {
        for (double v = 1; v < sc.max && tick_n < 62; v *= 10) /* 1, 2, 5 per decade */
            for (int m = 0; m < 3; m++)
                if (v * (m == 0 ? 1 : m == 1 ? 2 : 5) < sc.max * 0.999)
                    ticks[tick_n++] = v * (m == 0 ? 1 : m == 1 ? 2 : 5);
    } else {
        int want = width / (s * 40) > 1 ? width / (s * 40) : 1; /* about 40s pixels per label */
        double raw = sc.max / want, mag = pow(10, floor(log10(raw))), step = mag;
        if (raw > 5 * mag) step = 10 * mag;
        else if (raw > 2 * mag) step = 5 * mag;
        else if (raw > mag) step = 2 * mag;
        for (double v = step; v < sc.max * 0.999 && tick_n < 64; v += step) ticks[tick_n++] = v;
    }
    int used[64][2], used_n = 0;
    for (int t = 0; t < tick_n; t++) {
        int x = x0 + (int)lrintf(image_heat_position(&sc, (float)ticks[t]) * (float)(x1 - x0));
        char label[32];
        format_value(label, sizeof label, ticks[t], t == 0 && clipped);
        if (!place_label(out, x, label_y, s, label, used, &used_n)) continue;
        for (int y = bar_y + bar_h; y < bar_y + bar_h + tick_h; y++)
            for (int dx = 0; dx < s; dx++)
                if (x + dx <= x1) memcpy(out->rgb + ((size_t)y * width + x + dx) * 3, white, 3);
    }
    return 0;
}
