/*
 * test_image.c - PNG output by round trip through an independent decoder
 * (tests/png_decode.c): every image decodes to exactly its pixels, with
 * valid CRCs, Adler-32 and complete Huffman codes; incompressible data
 * falls back to stored blocks; matches reach across the 32 KiB window; a
 * rendered image and its heatmap come out at least 3x smaller than the
 * stored-block encoding. Heatmap scales: parsing, positions, and a fixed
 * maximum giving equal colours to equal values in two images.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "image/image.h"
#include "png_decode.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"

/* A random byte from the tests' generator (support.h: reseeded before
 * every test, so a test's images do not depend on the tests before it). */
static uint8_t rand_byte(void) { return (uint8_t)(test_rand_u64() >> 56); }

/* Encodes img at `level`, decodes it, and checks every pixel. Returns the
 * PNG size (0 on failure) and the decoder's statistics. */
static size_t roundtrip(const char *name, const image_rgb *img, int level, png_stats *st)
{
    accel_error err = {0};
    uint8_t *png = NULL, *rgb = NULL;
    size_t n = 0;
    int rc = image_png_encode(img, level, &png, &n, &err);
    CHECKF(rc == 0, "%s level %d: %s", name, level, err.msg);
    if (rc) return 0;
    char msg[256] = "";
    int w = 0, h = 0;
    png_stats local;
    rc = test_png_decode(png, n, &w, &h, &rgb, st ? st : &local, msg, sizeof msg);
    CHECKF(rc == 0, "%s level %d (%dx%d): decode: %s", name, level, img->width, img->height, msg);
    free(png);
    if (rc) return 0;
    CHECKF(w == img->width && h == img->height, "%s: decoded %dx%d", name, w, h);
    size_t bytes = (size_t)img->width * img->height * 3, bad = 0;
    if (w == img->width && h == img->height) {
        while (bad < bytes && rgb[bad] == img->rgb[bad]) bad++;
        CHECKF(bad == bytes, "%s level %d: first differing byte %zu of %zu", name, level, bad,
               bytes);
    }
    free(rgb);
    return bad == bytes ? n : 0;
}

/* Size of today's baseline: unfiltered rows in stored blocks (level 0),
 * by formula: signature, IHDR, IDAT (zlib header, 5 bytes per 65535-byte
 * block, Adler-32), IEND. */
static size_t stored_size(int w, int h)
{
    size_t raw = ((size_t)w * 3 + 1) * (size_t)h, blocks = raw ? (raw + 65534) / 65535 : 1;
    return 8 + 25 + 12 + 2 + raw + 5 * blocks + 4 + 12;
}

/* The most a PNG may exceed the stored size: a stored block's 5 bytes of
 * framing per block of up to 32768 symbols the encoder decides on, plus a
 * few bytes of bit padding and a last empty block. */
static size_t stored_slack(int w, int h)
{
    size_t raw = ((size_t)w * 3 + 1) * (size_t)h;
    return 5 * (raw / 32768 + 1) + 8;
}

/* Something like a render: a vertical background gradient, two shaded
 * discs with soft edges, and a checkered floor. */
static void fill_rendered(image_rgb *img)
{
    int w = img->width, h = img->height;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            uint8_t *p = img->rgb + ((size_t)y * w + x) * 3;
            float fy = (float)y / (float)h, fx = (float)x / (float)w;
            float c[3] = {0.25f + 0.3f * fy, 0.3f + 0.3f * fy, 0.45f + 0.2f * fy};
            if (fy > 0.7f) {
                int check = ((int)(fx * 12) + (int)(fy * 30)) & 1;
                float k = check ? 0.8f : 0.35f;
                c[0] = c[1] = c[2] = k * (0.6f + 0.4f * fy);
            }
            for (int d = 0; d < 2; d++) {
                float cx = d ? 0.65f : 0.3f, cy = 0.45f, r = d ? 0.22f : 0.15f;
                float dx = (fx - cx) * (float)w / (float)h, dy = fy - cy;
                float q = (dx * dx + dy * dy) / (r * r);
                if (q < 1) {
                    float nz = sqrtf(1 - q), lam = fmaxf(0.0f, 0.5f * nz - 0.6f * dx / r - 0.4f * dy / r);
                    c[0] = 0.1f + 0.85f * lam, c[1] = 0.08f + 0.6f * lam, c[2] = 0.05f + 0.4f * lam;
                }
            }
            for (int k = 0; k < 3; k++) p[k] = (uint8_t)fminf(255.0f, 255.0f * c[k]);
        }
}

TEST(image_crc_adler_known_values)
{
    CHECK(image_adler32((const uint8_t *)"Wikipedia", 9) == 0x11E60398u);
    CHECK(image_crc32((const uint8_t *)"123456789", 9, 0) == 0xCBF43926u); /* CRC-32 check value */
    static uint8_t big[200000]; /* past the 5552-byte reduction interval, all 0xff: worst case */
    memset(big, 0xff, sizeof big);
    uint32_t a = 1, b = 0;
    for (size_t i = 0; i < sizeof big; i++) a = (a + big[i]) % 65521u, b = (b + a) % 65521u;
    CHECK(image_adler32(big, sizeof big) == (b << 16 | a));
}

TEST(image_png_roundtrip_shapes)
{
    static const int sizes[][2] = {{1, 1}, {2, 1}, {1, 2}, {7, 3}, {1, 37}, {37, 1}, {333, 77}, {64, 64}};
    png_stats all = {0};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        image_rgb img;
        accel_error err = {0};
        if (image_alloc(&img, sizes[s][0], sizes[s][1], &err)) continue;
        for (int kind = 0; kind < 3; kind++) { /* rendered-like, noise, constant */
            if (kind == 0) fill_rendered(&img);
            for (size_t i = 0; kind > 0 && i < (size_t)img.width * img.height * 3; i++)
                img.rgb[i] = kind == 1 ? rand_byte() : 173;
            static const char *const names[] = {"rendered", "noise", "constant"};
            char name[64];
            snprintf(name, sizeof name, "%s %dx%d", names[kind], img.width, img.height);
            for (int level = 0; level <= 9; level += 3) {
                png_stats st;
                size_t n = roundtrip(name, &img, level, &st);
                CHECKF(n <= stored_size(img.width, img.height) + stored_slack(img.width, img.height), "%s level %d: %zu > stored %zu",
                       name, level, n, stored_size(img.width, img.height));
                if (level == 0) CHECKF(st.blocks[1] + st.blocks[2] == 0 && st.filters[0] == (size_t)img.height,
                                       "%s: level 0 is stored and unfiltered", name);
                for (int k = 0; k < 3; k++) all.blocks[k] += st.blocks[k];
                for (int k = 0; k < 5; k++) all.filters[k] += st.filters[k];
            }
        }
        image_free(&img);
    }
    /* Every block type and every row filter was produced and decoded. */
    test_note("blocks stored/fixed/dynamic %zu/%zu/%zu; rows by filter %zu/%zu/%zu/%zu/%zu",
              all.blocks[0], all.blocks[1], all.blocks[2], all.filters[0], all.filters[1],
              all.filters[2], all.filters[3], all.filters[4]);
    for (int k = 0; k < 3; k++) CHECKF(all.blocks[k] > 0, "no block of type %d", k);
    for (int k = 0; k < 5; k++) CHECKF(all.filters[k] > 0, "no row with filter %d", k);
}

TEST(image_png_noise_and_constant)
{
    image_rgb img;
    accel_error err = {0};
    int w = 800, h = 500; /* 1.2 MB: more than one 1 MiB IDAT chunk when incompressible */
    CHECK(image_alloc(&img, w, h, &err) == 0);
    for (size_t i = 0; i < (size_t)w * h * 3; i++) img.rgb[i] = rand_byte();
    png_stats st;
    size_t n = roundtrip("noise 800x500", &img, IMAGE_PNG_LEVEL, &st);
    CHECKF(st.blocks[0] > 0, "incompressible data goes out as stored blocks (%zu stored)", st.blocks[0]);
    CHECKF(st.idat_chunks == 2, "%zu IDAT chunks", st.idat_chunks);
    CHECKF(n <= stored_size(w, h) + stored_slack(w, h), "noise: %zu bytes, stored %zu", n,
           stored_size(w, h));
    memset(img.rgb, 90, (size_t)w * h * 3);
    n = roundtrip("constant 800x500", &img, IMAGE_PNG_LEVEL, &st);
    CHECKF(n > 0 && n < 2500, "constant image: %zu bytes", n);
    CHECKF(st.max_len == 258, "longest match %u, expected 258", st.max_len);
    image_free(&img);
}

/* Rows repeat with a period just under the window, so every match reaches
 * back about 32,000 bytes: the window's far end is used and decoded. */
TEST(image_png_beyond_window)
{
    int w = 400, period = 27, h = 120; /* 27 rows * 1201 bytes = 32427 < 32767 */
    image_rgb img;
    accel_error err = {0};
    CHECK(image_alloc(&img, w, h, &err) == 0);
    for (int y = 0; y < period; y++)
        for (int i = 0; i < w * 3; i++) img.rgb[(size_t)y * w * 3 + i] = rand_byte();
    for (int y = period; y < h; y++)
        memcpy(img.rgb + (size_t)y * w * 3, img.rgb + (size_t)(y - period) * w * 3, (size_t)w * 3);
    png_stats st;
    size_t n = roundtrip("periodic 400x120", &img, IMAGE_PNG_LEVEL, &st);
    CHECKF(st.max_dist > 32000 && st.max_dist <= 32768, "farthest match %u bytes", st.max_dist);
    CHECKF(n > 0 && n < stored_size(w, h) / 3, "periodic image %zu bytes, stored %zu", n,
           stored_size(w, h));
    image_free(&img);
}

TEST(image_zlib_roundtrip_streams)
{
    enum { N = 150000 };
    static uint8_t in[N], out[N + 1];
    size_t len[] = {0, 1, 2, 3, 258, 259, 1000, N};
    for (int pattern = 0; pattern < 4; pattern++) {
        for (size_t i = 0; i < N; i++) {
            if (pattern == 0) in[i] = 0;                                   /* long runs */
            if (pattern == 1) in[i] = rand_byte();                         /* incompressible */
            if (pattern == 2) in[i] = (uint8_t)("the quick brown fox "[i % 20] ^ (i % 997 == 0)); /* text */
            if (pattern == 3) in[i] = i < 32767 ? rand_byte() : in[i - 32767]; /* far copy */
        }
        for (size_t l = 0; l < sizeof len / sizeof len[0]; l++)
            for (int level = 0; level <= 9; level++) {
                if (level % 4 && len[l] != N) continue; /* every level on the full stream only */
                accel_error err = {0};
                uint8_t *z = NULL;
                size_t zn = 0;
                CHECK(image_zlib_compress(in, len[l], level, &z, &zn, &err) == 0);
                if (!z) continue;
                png_stats st = {0};
                char msg[256] = "";
                long got = test_zlib_decode(z, zn, out, sizeof out, &st, msg, sizeof msg);
                CHECKF(got == (long)len[l] && memcmp(in, out, len[l]) == 0,
                       "pattern %d, %zu bytes, level %d: %ld bytes back (%s)", pattern, len[l],
                       level, got, msg);
                if (pattern == 3 && len[l] == N && level >= 1)
                    CHECKF(st.max_dist == 32767 && zn < N / 3,
                           "far copy, level %d: max distance %u, %zu bytes", level, st.max_dist, zn);
                if (pattern == 0 && len[l] == N && level >= 1) CHECKF(zn < 400, "zeros: %zu bytes", zn);
                free(z);
            }
    }
    uint8_t *z;
    size_t zn;
    accel_error err = {0};
    CHECK(image_zlib_compress(in, 10, 10, &z, &zn, &err) == ACCEL_ERR_RANGE);
}

/* Renders a small scene through the library: shaded primary hits over a
 * background gradient, and the BVH's steps per ray. */
static int render(const char *spec, int w, int h, image_rgb *shaded, image_rgb *heat)
{
    accel_error err = {0};
    accel_scene s;
    if (!test_make_scene(spec, &s)) return 1;
    rays_set r;
    const accel_kind *kind;
    void *accel;
    accel_build_stats bs;
    const char *accel_spec = accel_find_kind("bvh") ? "bvh" : "brute";
    int rc = rays_primary(&s.camera, w, h, &r, &err);
    if (rc == 0) rc = accel_build_spec(accel_spec, &s, 1, &kind, &accel, &bs, &err);
    CHECKF(rc == 0, "%s", err.msg);
    if (rc) {
        scene_free(&s);
        return 1;
    }
    accel_hit *hits = malloc(r.count * sizeof *hits);
    uint32_t *steps = calloc(r.count, sizeof *steps);
    float *v = calloc((size_t)w * h, sizeof *v);
    rc = !hits || !steps || !v || image_alloc(shaded, w, h, &err);
    if (!rc) {
        accel_counters c = {0};
        c.ray_steps = steps;
        accel_trace(kind, accel, r.rays, hits, r.count, 1, &c);
        for (size_t i = 0; i < r.count; i++) {
            uint8_t *p = shaded->rgb + 3 * (size_t)r.pixel[i];
            float fy = (float)(r.pixel[i] / (uint32_t)w) / (float)h;
            vec3 pt, n;
            float k = 0.0f;
            if (rays_hit_frame(&s, &r.rays[i], &hits[i], &pt, &n))
                k = 0.2f + 0.8f * fmaxf(0.0f, v3_dot(n, v3_norm(v3_sub(s.light, pt))));
            for (int j = 0; j < 3; j++)
                p[j] = (uint8_t)(k > 0 ? 255.0f * k * (j == 0 ? 0.95f : j == 1 ? 0.75f : 0.55f)
                                       : 60.0f + 90.0f * fy + 20.0f * (float)j);
            v[r.pixel[i]] = (float)steps[i];
        }
        rc = image_heatmap(v, w, h, NULL, "bvh: nodes visited per ray", heat, &err);
        if (rc) image_free(shaded);
    }
    free(hits), free(steps), free(v);
    kind->destroy(accel);
    rays_free(&r);
    scene_free(&s);
    return rc;
}

TEST(image_png_rendered_3x_smaller)
{
    image_rgb shaded, heat;
    if (render("sphereflake", 320, 240, &shaded, &heat)) return;
    const image_rgb *imgs[2] = {&shaded, &heat};
    for (int k = 0; k < 2; k++) {
        const char *name = k ? "sphereflake heatmap" : "sphereflake render";
        size_t stored = roundtrip(name, imgs[k], 0, NULL);
        size_t packed = roundtrip(name, imgs[k], IMAGE_PNG_LEVEL, NULL);
        CHECKF(stored == stored_size(imgs[k]->width, imgs[k]->height), "%s: stored %zu", name, stored);
        CHECKF(packed > 0 && packed * 3 <= stored, "%s: %zu bytes vs %zu stored (%.2fx)", name,
               packed, stored, packed ? (double)stored / (double)packed : 0.0);
        test_note("%s 320x240: %zu bytes, stored %zu (%.2fx smaller)", name, packed, stored,
                  packed ? (double)stored / (double)packed : 0.0);
    }
    /* The synthetic render too, at a size with several blocks of every kind. */
    image_rgb img;
    accel_error err = {0};
    CHECK(image_alloc(&img, 800, 600, &err) == 0);
    fill_rendered(&img);
    size_t packed = roundtrip("rendered 800x600", &img, IMAGE_PNG_LEVEL, NULL);
    CHECKF(packed > 0 && packed * 3 <= stored_size(800, 600), "rendered 800x600: %zu bytes", packed);
    image_free(&img);
    image_free(&shaded);
    image_free(&heat);
}

TEST(image_heat_scale_parse_and_position)
{
    accel_error err = {0};
    image_heat_scale sc;
    CHECK(image_heat_scale_parse("auto", &sc, &err) == 0 && sc.max == 0 && !sc.log);
    CHECK(image_heat_scale_parse("log", &sc, &err) == 0 && sc.max == 0 && sc.log);
    CHECK(image_heat_scale_parse("max=50", &sc, &err) == 0 && sc.max == 50 && !sc.log);
    CHECK(image_heat_scale_parse("log,max=2.5e3", &sc, &err) == 0 && sc.max == 2500 && sc.log);
    CHECK(image_heat_scale_parse("max=200,lin", &sc, &err) == 0 && sc.max == 200 && !sc.log);
    static const char *const bad[] = {"max=abc", "max=-1", "max=0", "max=", "lg", "log,", "max=5x", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        int rc = image_heat_scale_parse(bad[i], &sc, &err);
        CHECKF(rc == ACCEL_ERR_SPEC && strstr(err.msg, "heat scale"), "'%s' accepted (%d)", bad[i], rc);
    }
    image_heat_scale lin = {100, 0}, lg = {99, 1};
    CHECK(image_heat_position(&lin, 25) == 0.25f);
    CHECK(image_heat_position(&lin, 250) == 1.0f && image_heat_position(&lin, -3) == 0.0f);
    CHECK(fabsf(image_heat_position(&lg, 9) - 0.5f) < 1e-6f); /* log(10) / log(100) */
    CHECK(image_heat_position(&lg, 0) == 0.0f && image_heat_position(&lg, 99) == 1.0f);
}

/* The reason for a fixed scale: equal values get equal colours in two
 * images with different maxima; an automatic scale does not do that. */
TEST(image_heatmap_fixed_scale_compares)
{
    enum { W = 200, H = 40 };
    static float a[W * H], b[W * H];
    for (int i = 0; i < W * H; i++) a[i] = (float)(i % W) / 10.0f, b[i] = (float)(i % W) / 2.0f;
    /* a: 0..19.9, b: 0..99.5; value 10 sits at x = 100 in a and x = 20 in b */
    accel_error err = {0};
    image_rgb ia, ib;
    for (int pass = 0; pass < 3; pass++) {
        image_heat_scale sc = {pass == 0 ? 0.0f : 120.0f, pass == 2};
        CHECK(image_heatmap(a, W, H, &sc, "test: steps per ray", &ia, &err) == 0);
        CHECK(image_heatmap(b, W, H, &sc, "test: steps per ray", &ib, &err) == 0);
        int same = !memcmp(ia.rgb + 3 * 100, ib.rgb + 3 * 20, 3);
        CHECKF(pass == 0 ? !same : same, "pass %d: equal values %s colours", pass, same ? "share" : "differ in");
        uint8_t want[3];
        image_heat_color(image_heat_position(&sc, 10.0f), want);
        if (pass) CHECK(!memcmp(ia.rgb + 3 * 100, want, 3));
        /* The legend sits below the image and holds white text pixels. */
        CHECK(ia.height > H + 20 && ia.width == W);
        size_t white = 0;
        for (size_t i = (size_t)W * H; i < (size_t)ia.width * ia.height; i++)
            white += ia.rgb[3 * i] == 255 && ia.rgb[3 * i + 1] == 255 && ia.rgb[3 * i + 2] == 255;
        CHECKF(white > 100, "pass %d: %zu legend text pixels", pass, white);
        image_free(&ia);
        image_free(&ib);
    }
    /* Saturation above a fixed max, and the title changes the legend. */
    image_heat_scale sc = {5, 0};
    image_rgb t1, t2;
    CHECK(image_heatmap(b, W, H, &sc, "one title", &t1, &err) == 0);
    CHECK(image_heatmap(b, W, H, &sc, "another", &t2, &err) == 0);
    uint8_t top[3];
    image_heat_color(1.0f, top);
    CHECK(!memcmp(t1.rgb + 3 * (W - 1), top, 3));
    CHECK(t1.height == t2.height && memcmp(t1.rgb, t2.rgb, (size_t)W * H * 3) == 0);
    CHECK(memcmp(t1.rgb, t2.rgb, (size_t)t1.width * t1.height * 3) != 0);
    image_free(&t1);
    image_free(&t2);
}

/* The decoder the round trips rely on can fail: a flipped bit in the
 * compressed data is caught (by the chunk CRC, or with the CRC recomputed
 * by inflate, the Adler-32 or the pixel comparison). */
TEST(image_png_decoder_rejects_corruption)
{
    image_rgb img;
    accel_error err = {0};
    CHECK(image_alloc(&img, 120, 90, &err) == 0);
    fill_rendered(&img);
    /* Low-bit noise: still Huffman-coded, but no two stretches alike, so a
     * flipped distance cannot copy identical bytes from elsewhere. */
    for (size_t i = 0; i < (size_t)120 * 90 * 3; i++) img.rgb[i] ^= (uint8_t)(rand_byte() & 3);
    uint8_t *png = NULL;
    size_t n = 0;
    CHECK(image_png_encode(&img, IMAGE_PNG_LEVEL, &png, &n, &err) == 0);
    size_t idat = 8 + 25, idat_len = png ? (size_t)png[idat] << 24 | png[idat + 1] << 16 |
                                                  png[idat + 2] << 8 | png[idat + 3] : 0;
    int caught_crc = 0, caught_data = 0, trials = 0;
    size_t st_dyn = 0;
    for (size_t at = idat + 8 + 2; png && at < idat + 8 + idat_len; at += idat_len / 50 + 1, trials++) {
        png[at] ^= 0x10;
        int w, h;
        uint8_t *rgb = NULL;
        png_stats st;
        char msg[256];
        caught_crc += test_png_decode(png, n, &w, &h, &rgb, &st, msg, sizeof msg) != 0;
        if (trials == 0) { /* the unflipped stream: Huffman-coded, as intended */
            png[at] ^= 0x10;
            CHECK(test_png_decode(png, n, &w, &h, &rgb, &st, msg, sizeof msg) == 0);
            st_dyn = st.blocks[2];
            free(rgb);
            rgb = NULL;
            png[at] ^= 0x10;
        }
        free(rgb);
        /* Same flip with a valid CRC: the deflate data itself must give it away. */
        uint32_t crc = image_crc32(png + idat + 4, idat_len + 4, 0);
        uint8_t *c = png + idat + 8 + idat_len, saved[4];
        memcpy(saved, c, 4);
        c[0] = (uint8_t)(crc >> 24), c[1] = (uint8_t)(crc >> 16), c[2] = (uint8_t)(crc >> 8), c[3] = (uint8_t)crc;
        rgb = NULL;
        int rc = test_png_decode(png, n, &w, &h, &rgb, &st, msg, sizeof msg);
        caught_data += rc != 0 || memcmp(rgb, img.rgb, (size_t)120 * 90 * 3) != 0;
        free(rgb);
        memcpy(c, saved, 4);
        png[at] ^= 0x10;
    }
    CHECKF(st_dyn > 0 && trials > 20 && caught_crc == trials && caught_data == trials,
           "%d flips: %d caught by CRC, %d by the data", trials, caught_crc, caught_data);
    free(png);
    image_free(&img);
}

TEST(image_heat_title_names_the_unit)
{
    char t[128];
    for (size_t i = 0; i < accel_kind_count; i++) {
        const accel_kind *k = accel_kinds[i];
        image_heat_title(t, sizeof t, k->name, k, 0);
        const char *want = !strcmp(k->step_name, "cells") ? "cells stepped per ray" : "nodes visited per ray";
        CHECKF(!strncmp(t, k->name, strlen(k->name)) && strstr(t, want), "%s: '%s'", k->name, t);
        image_heat_title(t, sizeof t, k->name, k, 1);
        CHECKF(strstr(t, ": primitive tests per ray") != NULL, "%s: '%s'", k->name, t);
    }
}
