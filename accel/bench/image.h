/*
 * image.h - PNG and PPM output written by the project itself (no zlib:
 * PNG's deflate stream uses stored blocks, which every reader accepts),
 * a colour scale for heatmaps and a tiny digit font for its legend.
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

/* Perceptually ordered colour scale: x in [0,1] -> dark blue .. yellow .. white. */
void image_heat_color(float x, uint8_t rgb[3]);

/* Heatmap of per-pixel values with a legend strip (scale bar with the
 * minimum and maximum printed) below the image. values has width*height
 * entries; the scale runs from 0 to vmax (vmax <= 0: the maximum). */
int image_heatmap(const float *values, int width, int height, float vmax, image_rgb *out,
                  accel_error *err);

/* Draws digits, '.', '-', 'e', 'x', ' ' and a few letters at (x, y), scale s. */
void image_text(image_rgb *img, int x, int y, int s, const char *text, const uint8_t rgb[3]);

/* CRC-32 (PNG) and Adler-32 (zlib), exposed for tests. */
uint32_t image_crc32(const uint8_t *data, size_t n, uint32_t crc);
uint32_t image_adler32(const uint8_t *data, size_t n);

#ifdef __cplusplus
}
#endif

#endif
