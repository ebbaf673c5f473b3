/*
 * image.h - PNG and PPM output written by the project itself (libc only:
 * PNG rows are filtered per row and compressed by our own deflate, see
 * deflate.c), heatmaps of per-pixel costs with a colour scale and a
 * titled legend, and a small pixel font for that legend.
 */
#ifndef ACCEL_IMAGE_H
#define ACCEL_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int width, height;
    uint8_t *rgb; /* width*height*3 bytes, row-major, top row first */
} image_rgb;

int image_alloc(image_rgb *img, int width, int height, accel_error *err);
void image_free(image_rgb *img);
/* Format from the extension: .png or .ppm. */
int image_write(const char *path, const image_rgb *img, accel_error *err);
int image_write_png(const char *path, const image_rgb *img, accel_error *err);
int image_write_ppm(const char *path, const image_rgb *img, accel_error *err);

/* Compression level image_write_png uses (see image_zlib_compress). */
#define IMAGE_PNG_LEVEL 6
/* The whole PNG file in memory (*png malloc'ed, the caller frees it).
 * level 0: unfiltered rows in stored deflate blocks (no compression);
 * 1..9: rows filtered per row (PNG spec 12.8 heuristic), then deflated. */
int image_png_encode(const image_rgb *img, int level, uint8_t **png, size_t *png_n,
                     accel_error *err);
/* A zlib stream (RFC 1950) of in[0..n) in deflate blocks (RFC 1951):
 * level 0 stored blocks only, 1..9 LZ77 + Huffman with growing search
 * effort. Each block is stored when that is smaller, so the output never
 * exceeds the stored size by more than a few bytes. *out malloc'ed. */
int image_zlib_compress(const uint8_t *in, size_t n, int level, uint8_t **out, size_t *out_n,
                        accel_error *err);

/* Perceptually ordered colour scale: x in [0,1] -> dark blue .. yellow .. white. */
void image_heat_color(float x, uint8_t rgb[3]);

/* How heatmap values map to colours. Two images with the same fixed max
 * (and the same log flag) can be compared colour for colour. */
typedef struct {
    float max; /* top of the scale, values above saturate; <= 0: each image's maximum */
    int log;   /* 0: position v / max; 1: log(1 + v) / log(1 + max), for costs spanning decades */
} image_heat_scale;

/* Parses a comma list of "auto" (max = the image's maximum, the default),
 * "max=N", "lin" (default) and "log", e.g. "log,max=200". */
int image_heat_scale_parse(const char *spec, image_heat_scale *out, accel_error *err);
/* Position 0..1 of value v on scale sc (sc->max > 0). */
float image_heat_position(const image_heat_scale *sc, float v);

/* Heatmap of per-pixel values (width*height entries, >= 0) with a legend
 * under the image: the title (the unit, e.g. "bvh: nodes visited per
 * ray"; word-wrapped; ", log scale" appended on a log scale), the colour
 * bar, and ticks at 0, at the scale's maximum (printed "N+" when values
 * above a fixed maximum saturate) and at round values between. scale may
 * be NULL (linear, automatic maximum); title may be NULL. */
int image_heatmap(const float *values, int width, int height, const image_heat_scale *scale,
                  const char *title, image_rgb *out, accel_error *err);

/* A heatmap title in the project's vocabulary: "SPEC: nodes visited per
 * ray" (trees), "SPEC: cells stepped per ray" (grids, kind->step_name
 * "cells"), "SPEC: primitive tests per ray" (prims != 0). */
void image_heat_title(char *buf, size_t n, const char *spec, const accel_kind *kind, int prims);

/* Draws printable ASCII at (x, y) (top-left), 5x7 glyphs in 6x8 cells,
 * scaled by s; pixels outside the image are skipped. */
void image_text(image_rgb *img, int x, int y, int s, const char *text, const uint8_t rgb[3]);
/* Width in pixels of text drawn at scale s. */
int image_text_width(const char *text, int s);

/* CRC-32 (PNG) and Adler-32 (zlib), exposed for tests. */
uint32_t image_crc32(const uint8_t *data, size_t n, uint32_t crc);
uint32_t image_adler32(const uint8_t *data, size_t n);

#ifdef __cplusplus
}
#endif

#endif
