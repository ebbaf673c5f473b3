/*
 * image.c - PNG (ISO/IEC 15948, "PNG Specification, Second Edition") and
 * binary PPM output. PNG rows are filtered with the filter the spec's
 * heuristic picks per row, then compressed by deflate.c.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image/image.h"

#define IDAT_MAX ((size_t)1 << 20) /* bytes of compressed data per IDAT chunk */

int image_alloc(image_rgb *img, int width, int height, accel_error *err)
{
    img->rgb = NULL;
    img->width = img->height = 0;
    if (width < 1 || height < 1 || width > 65536 || height > 65536)
        return accel_fail(err, ACCEL_ERR_RANGE, "image size %dx%d out of range", width, height);
    img->rgb = calloc((size_t)width * height, 3);
    if (!img->rgb) return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for an image");
    img->width = width;
    img->height = height;
    return 0;
}

void image_free(image_rgb *img)
{
    free(img->rgb);
    img->rgb = NULL;
}

uint32_t image_crc32(const uint8_t *data, size_t n, uint32_t crc)
{
    static uint32_t table[256];
    static int ready;
    if (!ready) { /* benign race: every thread writes the same values */
        for (uint32_t i = 0; i < 256; i++) {
            uint32_t c = i;
            for (int k = 0; k < 8; k++) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
            table[i] = c;
        }
        ready = 1;
    }
    crc = ~crc;
    for (size_t i = 0; i < n; i++) crc = table[(crc ^ data[i]) & 0xff] ^ (crc >> 8);
    return ~crc;
}

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24), p[1] = (uint8_t)(v >> 16), p[2] = (uint8_t)(v >> 8), p[3] = (uint8_t)v;
}

/* Appends a chunk (length, type, data, CRC over type and data) at *k. */
static void put_chunk(uint8_t *out, size_t *k, const char *type, const uint8_t *data, size_t n)
{
    uint8_t *p = out + *k;
    put32(p, (uint32_t)n);
    memcpy(p + 4, type, 4);
    if (n) memcpy(p + 8, data, n);
    put32(p + 8 + n, image_crc32(p + 4, n + 4, 0));
    *k += 12 + n;
}

/* Paeth predictor (PNG spec 9.4): the neighbour nearest to a + b - c. */
static inline uint8_t paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return (uint8_t)(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

/* Filters one row of n bytes with filter type t (PNG spec 9.2: 0 none,
 * 1 sub, 2 up, 3 average, 4 Paeth); prev is the unfiltered row above
 * (zeros for the first row). Returns the sum of the output bytes read as
 * signed: the "minimum sum of absolute differences" the spec (12.8)
 * recommends for choosing a filter per row. */
static unsigned filter_row(int t, const uint8_t *cur, const uint8_t *prev, size_t n, uint8_t *out)
{
    const size_t bpp = 3; /* bytes per pixel: 8-bit RGB */
    size_t i = 0;
    switch (t) { /* the first pixel has no left neighbour (a = c = 0) */
    case 0: memcpy(out, cur, n); break;
    case 1:
        for (; i < bpp; i++) out[i] = cur[i];
        for (; i < n; i++) out[i] = (uint8_t)(cur[i] - cur[i - bpp]);
        break;
    case 2:
        for (; i < n; i++) out[i] = (uint8_t)(cur[i] - prev[i]);
        break;
    case 3:
        for (; i < bpp; i++) out[i] = (uint8_t)(cur[i] - (prev[i] >> 1));
        for (; i < n; i++) out[i] = (uint8_t)(cur[i] - ((cur[i - bpp] + prev[i]) >> 1));
        break;
    default:
        for (; i < bpp; i++) out[i] = (uint8_t)(cur[i] - prev[i]); /* Paeth(0, b, 0) = b */
        for (; i < n; i++) out[i] = (uint8_t)(cur[i] - paeth(cur[i - bpp], prev[i], prev[i - bpp]));
        break;
    }
    unsigned sum = 0;
    for (i = 0; i < n; i++) sum += out[i] < 128 ? out[i] : 256u - out[i];
    return sum;
}

int image_png_encode(const image_rgb *img, int level, uint8_t **png, size_t *png_n,
                     accel_error *err)
{
    *png = NULL;
    *png_n = 0;
    if (!img->rgb || img->width < 1 || img->height < 1)
        return accel_fail(err, ACCEL_ERR_RANGE, "cannot encode an empty image");
    size_t w3 = (size_t)img->width * 3, row = w3 + 1; /* filter byte + pixels */
    size_t raw_n = row * (size_t)img->height;
    uint8_t *raw = malloc(raw_n), *scratch = malloc(6 * w3);
    if (!raw || !scratch) {
        free(raw), free(scratch);
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for a %dx%d PNG", img->width,
                          img->height);
    }
    uint8_t *zero = scratch + 5 * w3;
    memset(zero, 0, w3);
    for (int y = 0; y < img->height; y++) {
        const uint8_t *cur = img->rgb + (size_t)y * w3, *prev = y ? cur - w3 : zero;
        uint8_t *dst = raw + (size_t)y * row;
        int best = 0;
        if (level > 0) { /* level 0 keeps the unfiltered rows of a plain stored stream */
            unsigned best_sum = UINT32_MAX;
            for (int t = 0; t < 5; t++) {
                unsigned sum = filter_row(t, cur, prev, w3, scratch + (size_t)t * w3);
                if (sum < best_sum) best_sum = sum, best = t;
            }
            memcpy(dst + 1, scratch + (size_t)best * w3, w3);
        } else {
            memcpy(dst + 1, cur, w3);
        }
        dst[0] = (uint8_t)best;
    }
    free(scratch);
    uint8_t *z;
    size_t z_n;
    int rc = image_zlib_compress(raw, raw_n, level, &z, &z_n, err);
    free(raw);
    if (rc) return rc;
    /* IDAT split in chunks of at most IDAT_MAX bytes (a chunk length must stay below 2^31). */
    size_t idat_count = z_n ? (z_n + IDAT_MAX - 1) / IDAT_MAX : 1;
    uint8_t *out = malloc(8 + 25 + 12 * idat_count + z_n + 12);
    if (!out) {
        free(z);
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for a %zu-byte PNG", z_n);
    }
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    uint8_t ihdr[13];
    put32(ihdr, (uint32_t)img->width);
    put32(ihdr + 4, (uint32_t)img->height);
    ihdr[8] = 8, ihdr[9] = 2, ihdr[10] = 0, ihdr[11] = 0, ihdr[12] = 0; /* 8-bit RGB */
    size_t k = 8;
    memcpy(out, sig, 8);
    put_chunk(out, &k, "IHDR", ihdr, 13);
    for (size_t off = 0; off < z_n; off += IDAT_MAX)
        put_chunk(out, &k, "IDAT", z + off, z_n - off < IDAT_MAX ? z_n - off : IDAT_MAX);
    put_chunk(out, &k, "IEND", NULL, 0);
    free(z);
    *png = out;
    *png_n = k;
    return 0;
}

int image_write_png(const char *path, const image_rgb *img, accel_error *err)
{
    uint8_t *png;
    size_t n;
    int rc = image_png_encode(img, IMAGE_PNG_LEVEL, &png, &n, err);
    if (rc) return rc;
    FILE *f = fopen(path, "wb");
    if (!f) {
        free(png);
        return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open for writing: %s", path,
                          strerror(errno));
    }
    int ok = fwrite(png, 1, n, f) == n;
    free(png);
    if (fclose(f) != 0) ok = 0;
    return ok ? 0 : accel_fail(err, ACCEL_ERR_IO, "%s: write failed", path);
}

int image_write_ppm(const char *path, const image_rgb *img, accel_error *err)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open for writing: %s", path,
                          strerror(errno));
    size_t n = (size_t)img->width * img->height * 3;
    int ok = fprintf(f, "P6\n%d %d\n255\n", img->width, img->height) > 0 &&
             fwrite(img->rgb, 1, n, f) == n;
    if (fclose(f) != 0) ok = 0;
    return ok ? 0 : accel_fail(err, ACCEL_ERR_IO, "%s: write failed", path);
}

int image_write(const char *path, const image_rgb *img, accel_error *err)
{
    const char *dot = strrchr(path, '.');
    if (dot && !strcmp(dot, ".ppm")) return image_write_ppm(path, img, err);
    if (dot && !strcmp(dot, ".png")) return image_write_png(path, img, err);
    return accel_fail(err, ACCEL_ERR_SPEC, "%s: image format must be .png or .ppm", path);
}
