/*
 * image.c - PNG (stored deflate blocks, RFC 1950/1951, PNG spec ISO 15948)
 * and binary PPM output, heat colour scale, legend text.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/image.h"

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

uint32_t image_adler32(const uint8_t *data, size_t n)
{
    uint32_t a = 1, b = 0;
    for (size_t i = 0; i < n; i++) {
        a = (a + data[i]) % 65521u;
        b = (b + a) % 65521u;
    }
    return (b << 16) | a;
}

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24), p[1] = (uint8_t)(v >> 16), p[2] = (uint8_t)(v >> 8), p[3] = (uint8_t)v;
}

static int write_chunk(FILE *f, const char *type, const uint8_t *data, size_t n)
{
    uint8_t head[8], tail[4];
    put32(head, (uint32_t)n);
    memcpy(head + 4, type, 4);
    uint32_t crc = image_crc32((const uint8_t *)type, 4, 0);
    crc = image_crc32(data, n, crc);
    put32(tail, crc);
    return fwrite(head, 1, 8, f) == 8 && (n == 0 || fwrite(data, 1, n, f) == n) &&
           fwrite(tail, 1, 4, f) == 4;
}

int image_write_png(const char *path, const image_rgb *img, accel_error *err)
{
    size_t row = (size_t)img->width * 3 + 1; /* filter byte + pixels */
    size_t raw_n = row * (size_t)img->height;
    size_t blocks = (raw_n + 65534) / 65535;
    size_t z_n = 2 + raw_n + 5 * blocks + 4;
    uint8_t *raw = malloc(raw_n), *z = malloc(z_n);
    if (!raw || !z) {
        free(raw);
        free(z);
        return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory", path);
    }
    for (int y = 0; y < img->height; y++) {
        raw[(size_t)y * row] = 0; /* filter: none */
        memcpy(raw + (size_t)y * row + 1, img->rgb + (size_t)y * img->width * 3,
               (size_t)img->width * 3);
    }
    size_t k = 0;
    z[k++] = 0x78, z[k++] = 0x01; /* zlib header: deflate, 32K window, no dict */
    for (size_t off = 0; off < raw_n; off += 65535) {
        size_t len = raw_n - off < 65535 ? raw_n - off : 65535;
        z[k++] = off + len == raw_n; /* BFINAL, BTYPE = 00 (stored) */
        z[k++] = (uint8_t)len, z[k++] = (uint8_t)(len >> 8);
        z[k++] = (uint8_t)~len, z[k++] = (uint8_t)(~len >> 8);
        memcpy(z + k, raw + off, len);
        k += len;
    }
    put32(z + k, image_adler32(raw, raw_n));
    k += 4;
    free(raw);
    FILE *f = fopen(path, "wb");
    if (!f) {
        free(z);
        return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open for writing: %s", path,
                          strerror(errno));
    }
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    uint8_t ihdr[13];
    put32(ihdr, (uint32_t)img->width);
    put32(ihdr + 4, (uint32_t)img->height);
    ihdr[8] = 8, ihdr[9] = 2, ihdr[10] = 0, ihdr[11] = 0, ihdr[12] = 0; /* 8-bit RGB */
    int ok = fwrite(sig, 1, 8, f) == 8 && write_chunk(f, "IHDR", ihdr, 13) &&
             write_chunk(f, "IDAT", z, k) && write_chunk(f, "IEND", NULL, 0);
    free(z);
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

/* 3x5 glyphs, one row per 3-bit group, top row first. */
static const char *glyph(char ch)
{
    switch (ch) {
    case '0': return "111101101101111";
    case '1': return "010110010010111";
    case '2': return "111001111100111";
    case '3': return "111001111001111";
    case '4': return "101101111001001";
    case '5': return "111100111001111";
    case '6': return "111100111101111";
    case '7': return "111001010010010";
    case '8': return "111101111101111";
    case '9': return "111101111001111";
    case '.': return "000000000000010";
    case '-': return "000000111000000";
    case '+': return "000010111010000";
    case 'e': return "000111101110011";
    case 'x': return "000101010101000";
    case 'k': return "100101110101101";
    case 'M': return "101111111101101";
    case '/': return "001001010100100";
    case ':': return "000010000010000";
    default: return "000000000000000";
    }
}

void image_text(image_rgb *img, int x, int y, int s, const char *text, const uint8_t rgb[3])
{
    for (; *text; text++, x += 4 * s) {
        const char *g = glyph(*text);
        for (int gy = 0; gy < 5; gy++)
            for (int gx = 0; gx < 3; gx++) {
                if (g[gy * 3 + gx] != '1') continue;
                for (int dy = 0; dy < s; dy++)
                    for (int dx = 0; dx < s; dx++) {
                        int px = x + gx * s + dx, py = y + gy * s + dy;
                        if (px < 0 || py < 0 || px >= img->width || py >= img->height) continue;
                        memcpy(img->rgb + ((size_t)py * img->width + px) * 3, rgb, 3);
                    }
            }
    }
}

int image_heatmap(const float *values, int width, int height, float vmax, image_rgb *out,
                  accel_error *err)
{
    int legend = 24;
    int rc = image_alloc(out, width, height + legend, err);
    if (rc) return rc;
    float vmin = INFINITY, top = 0;
    for (size_t i = 0; i < (size_t)width * height; i++) {
        if (values[i] > top) top = values[i];
        if (values[i] < vmin) vmin = values[i];
    }
    if (vmax <= 0) vmax = top > 0 ? top : 1;
    for (size_t i = 0; i < (size_t)width * height; i++)
        image_heat_color(values[i] / vmax, out->rgb + 3 * i);
    /* Legend: a colour bar over the width, "0" at the left, vmax at the right. */
    for (int y = height + 2; y < height + 10; y++)
        for (int x = 0; x < width; x++)
            image_heat_color((float)x / (float)(width > 1 ? width - 1 : 1),
                             out->rgb + ((size_t)y * width + x) * 3);
    static const uint8_t white[3] = {255, 255, 255};
    char label[32];
    image_text(out, 2, height + 13, 2, "0", white);
    snprintf(label, sizeof label, "%.0f", vmax);
    int lw = (int)strlen(label) * 8;
    image_text(out, width - lw - 2, height + 13, 2, label, white);
    return 0;
}
