/*
 * png_decode.c - see png_decode.h. Written from the specifications (RFC
 * 1950, RFC 1951, PNG ISO/IEC 15948) and sharing no code with the writer
 * (accel/image/deflate.c, image.c): CRC and Adler-32 are recomputed here
 * bit by bit, Huffman codes are decoded canonically one bit at a time.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "png_decode.h"

typedef struct {
    const uint8_t *in;
    size_t n, pos;
    uint32_t bits; /* pending input bits, LSB first */
    int count;
    int overrun;
} reader;

static uint32_t get_bits(reader *r, int need)
{
    while (r->count < need) {
        if (r->pos >= r->n) {
            r->overrun = 1;
            return 0;
        }
        r->bits |= (uint32_t)r->in[r->pos++] << r->count;
        r->count += 8;
    }
    uint32_t v = need ? r->bits & ((1u << need) - 1) : 0;
    r->bits = need == 32 ? 0 : r->bits >> need;
    r->count -= need;
    return v;
}

/* Canonical code: count[len] codes per length, symbols in code order. */
typedef struct {
    uint16_t count[16];
    uint16_t symbol[320];
} huffman;

/* Returns 0 for a complete code, 1 for incomplete, -1 over-subscribed. */
static int build(huffman *h, const uint8_t *len, int n)
{
    uint16_t offs[16];
    memset(h->count, 0, sizeof h->count);
    for (int i = 0; i < n; i++) h->count[len[i]]++;
    int used = n - h->count[0];
    long left = 1;
    for (int l = 1; l < 16; l++) {
        left = 2 * left - h->count[l];
        if (left < 0) return -1;
    }
    offs[1] = 0;
    for (int l = 1; l < 15; l++) offs[l + 1] = (uint16_t)(offs[l] + h->count[l]);
    for (int i = 0; i < n; i++)
        if (len[i]) h->symbol[offs[len[i]]++] = (uint16_t)i;
    return left > 0 && used > 1 ? 1 : 0; /* one code of length 1 is allowed (RFC 1951 3.2.7) */
}

static int decode(reader *r, const huffman *h)
{
    int code = 0, first = 0, index = 0;
    for (int l = 1; l < 16; l++) {
        code |= (int)get_bits(r, 1);
        if (code - first < h->count[l]) return h->symbol[index + code - first];
        index += h->count[l];
        first = (first + h->count[l]) << 1;
        code <<= 1;
    }
    return -1;
}

static const uint16_t lbase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                   31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
static const uint16_t dbase[30] = {1,    2,    3,    4,    5,    7,    9,    13,    17,    25,
                                   33,   49,   65,   97,   129,  193,  257,  385,   513,   769,
                                   1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};

static long fail(char *msg, size_t msg_n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, msg_n, fmt, ap);
    va_end(ap);
    return -1;
}

/* Symbols of one Huffman-coded block until end-of-block. */
static long codes(reader *r, const huffman *lit, const huffman *dist, uint8_t *out, size_t cap,
                  size_t *k, png_stats *st, char *msg, size_t msg_n)
{
    for (;;) {
        int s = decode(r, lit);
        if (r->overrun) return fail(msg, msg_n, "input ends inside a block");
        if (s < 0) return fail(msg, msg_n, "invalid literal/length code");
        if (s < 256) {
            if (*k >= cap) return fail(msg, msg_n, "output exceeds %zu bytes", cap);
            out[(*k)++] = (uint8_t)s;
            continue;
        }
        if (s == 256) return 0;
        s -= 257;
        if (s >= 29) return fail(msg, msg_n, "length symbol %d", s + 257);
        int lextra = s < 8 || s == 28 ? 0 : (s - 4) / 4;
        unsigned len = lbase[s] + get_bits(r, lextra);
        int d = decode(r, dist);
        if (d < 0 || d >= 30) return fail(msg, msg_n, "invalid distance code");
        int dextra = d < 4 ? 0 : (d - 2) / 2;
        unsigned dd = dbase[d] + get_bits(r, dextra);
        if (r->overrun) return fail(msg, msg_n, "input ends inside a match");
        if (dd > *k) return fail(msg, msg_n, "distance %u before the start (at %zu)", dd, *k);
        if (*k + len > cap) return fail(msg, msg_n, "output exceeds %zu bytes", cap);
        for (unsigned i = 0; i < len; i++, (*k)++) out[*k] = out[*k - dd]; /* may overlap */
        st->matches++;
        if (dd > st->max_dist) st->max_dist = dd;
        if (len > st->max_len) st->max_len = len;
    }
}

long test_inflate(const uint8_t *in, size_t n, uint8_t *out, size_t cap, size_t *used,
                  png_stats *st, char *msg, size_t msg_n)
{
    reader r = {in, n, 0, 0, 0, 0};
    size_t k = 0;
    int last;
    do {
        last = (int)get_bits(&r, 1);
        int type = (int)get_bits(&r, 2);
        if (r.overrun) return fail(msg, msg_n, "input ends before a block header");
        if (type == 3) return fail(msg, msg_n, "block type 3 (reserved)");
        st->blocks[type]++;
        if (type == 0) {
            r.bits = 0, r.count = 0; /* skip to the byte boundary */
            if (r.pos + 4 > n) return fail(msg, msg_n, "stored header cut");
            unsigned len = in[r.pos] | in[r.pos + 1] << 8, nlen = in[r.pos + 2] | in[r.pos + 3] << 8;
            if (len != (~nlen & 0xffffu)) return fail(msg, msg_n, "stored LEN/NLEN mismatch");
            r.pos += 4;
            if (r.pos + len > n) return fail(msg, msg_n, "stored block cut");
            if (k + len > cap) return fail(msg, msg_n, "output exceeds %zu bytes", cap);
            memcpy(out + k, in + r.pos, len);
            r.pos += len, k += len;
            continue;
        }
        huffman lit, dist;
        uint8_t len[320];
        if (type == 1) { /* fixed codes, RFC 1951 3.2.6 */
            for (int i = 0; i < 288; i++) len[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
            build(&lit, len, 288);
            for (int i = 0; i < 30; i++) len[i] = 5;
            build(&dist, len, 30);
        } else { /* dynamic codes, RFC 1951 3.2.7 */
            static const uint8_t order[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5,
                                              11, 4, 12, 3, 13, 2, 14, 1, 15};
            int nlen = (int)get_bits(&r, 5) + 257, ndist = (int)get_bits(&r, 5) + 1;
            int ncode = (int)get_bits(&r, 4) + 4;
            if (nlen > 286 || ndist > 30) return fail(msg, msg_n, "HLIT %d / HDIST %d too large", nlen, ndist);
            uint8_t cl[19] = {0};
            for (int i = 0; i < ncode; i++) cl[order[i]] = (uint8_t)get_bits(&r, 3);
            huffman clh;
            if (build(&clh, cl, 19) != 0) return fail(msg, msg_n, "code-length code not complete");
            for (int i = 0; i < nlen + ndist;) {
                int s = decode(&r, &clh);
                if (r.overrun || s < 0) return fail(msg, msg_n, "bad code-length symbol");
                if (s < 16) {
                    len[i++] = (uint8_t)s;
                    continue;
                }
                int rep, val = 0;
                if (s == 16) {
                    if (i == 0) return fail(msg, msg_n, "repeat with no previous length");
                    val = len[i - 1], rep = 3 + (int)get_bits(&r, 2);
                } else {
                    rep = s == 17 ? 3 + (int)get_bits(&r, 3) : 11 + (int)get_bits(&r, 7);
                }
                if (i + rep > nlen + ndist) return fail(msg, msg_n, "lengths overrun HLIT+HDIST");
                while (rep--) len[i++] = (uint8_t)val;
            }
            if (len[256] == 0) return fail(msg, msg_n, "no end-of-block code");
            if (build(&lit, len, nlen) != 0) return fail(msg, msg_n, "literal/length code not complete");
            if (build(&dist, len + nlen, ndist) != 0) return fail(msg, msg_n, "distance code not complete");
        }
        if (codes(&r, &lit, &dist, out, cap, &k, st, msg, msg_n)) return -1;
    } while (!last);
    *used = r.pos; /* the final partial byte's padding is part of the stream */
    return (long)k;
}

static uint32_t adler(const uint8_t *p, size_t n)
{
    uint32_t a = 1, b = 0;
    for (size_t i = 0; i < n; i++) a = (a + p[i]) % 65521u, b = (b + a) % 65521u;
    return b << 16 | a;
}

static uint32_t crc(const uint8_t *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = c & 1 ? (c >> 1) ^ 0xedb88320u : c >> 1;
    }
    return ~c;
}

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

long test_zlib_decode(const uint8_t *in, size_t n, uint8_t *out, size_t cap, png_stats *st,
                      char *msg, size_t msg_n)
{
    if (n < 6) return fail(msg, msg_n, "zlib stream of %zu bytes", n);
    if ((in[0] & 15) != 8 || (in[0] >> 4) > 7) return fail(msg, msg_n, "CMF 0x%02x", in[0]);
    if ((in[0] * 256u + in[1]) % 31 != 0) return fail(msg, msg_n, "FCHECK fails");
    if (in[1] & 0x20) return fail(msg, msg_n, "preset dictionary");
    size_t used;
    long k = test_inflate(in + 2, n - 2, out, cap, &used, st, msg, msg_n);
    if (k < 0) return -1;
    if (2 + used + 4 != n) return fail(msg, msg_n, "%zu bytes after the deflate data, expected 4", n - 2 - used);
    if (be32(in + 2 + used) != adler(out, (size_t)k)) return fail(msg, msg_n, "Adler-32 mismatch");
    return k;
}

static uint8_t paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return (uint8_t)(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

int test_png_decode(const uint8_t *png, size_t n, int *width, int *height, uint8_t **rgb,
                    png_stats *st, char *msg, size_t msg_n)
{
    *rgb = NULL;
    memset(st, 0, sizeof *st);
    if (n < 8 || memcmp(png, "\x89PNG\r\n\x1a\n", 8)) return (int)fail(msg, msg_n, "no PNG signature");
    uint8_t *z = malloc(n);
    size_t zn = 0, off = 8;
    int w = 0, h = 0, seen_ihdr = 0, seen_iend = 0;
    if (!z) return (int)fail(msg, msg_n, "out of memory");
    while (off + 12 <= n && !seen_iend) {
        uint32_t len = be32(png + off);
        const uint8_t *type = png + off + 4, *data = png + off + 8;
        if (len > n - off - 12) { free(z); return (int)fail(msg, msg_n, "chunk cut at %zu", off); }
        if (crc(type, len + 4) != be32(data + len)) {
            free(z);
            return (int)fail(msg, msg_n, "CRC mismatch in %.4s", (const char *)type);
        }
        if (!memcmp(type, "IHDR", 4)) {
            if (off != 8 || len != 13) { free(z); return (int)fail(msg, msg_n, "bad IHDR"); }
            w = (int)be32(data), h = (int)be32(data + 4), seen_ihdr = 1;
            if (w < 1 || h < 1 || data[8] != 8 || data[9] != 2 || data[10] || data[11] || data[12]) {
                free(z);
                return (int)fail(msg, msg_n, "IHDR not 8-bit RGB non-interlaced (%dx%d)", w, h);
            }
        } else if (!memcmp(type, "IDAT", 4)) {
            st->idat_chunks++;
            memcpy(z + zn, data, len);
            zn += len;
        } else if (!memcmp(type, "IEND", 4)) {
            seen_iend = 1;
            if (len) { free(z); return (int)fail(msg, msg_n, "IEND with data"); }
        }
        off += 12 + len;
    }
    if (!seen_ihdr || !seen_iend || off != n) {
        free(z);
        return (int)fail(msg, msg_n, "missing IHDR/IEND or bytes after IEND");
    }
    size_t row = (size_t)w * 3 + 1, raw_n = row * (size_t)h;
    uint8_t *raw = malloc(raw_n + 1), *img = malloc(raw_n);
    long got = raw && img ? test_zlib_decode(z, zn, raw, raw_n + 1, st, msg, msg_n) : -1;
    free(z);
    if (got != (long)raw_n) {
        if (got >= 0) fail(msg, msg_n, "image data %ld bytes, expected %zu", got, raw_n);
        free(raw), free(img);
        return -1;
    }
    size_t w3 = (size_t)w * 3;
    for (int y = 0; y < h; y++) {
        const uint8_t *f = raw + (size_t)y * row + 1;
        uint8_t *cur = img + (size_t)y * w3;
        const uint8_t *up = y ? cur - w3 : NULL;
        int type = raw[(size_t)y * row];
        if (type > 4) {
            free(raw), free(img);
            return (int)fail(msg, msg_n, "row %d: filter type %d", y, type);
        }
        st->filters[type]++;
        for (size_t i = 0; i < w3; i++) {
            int a = i >= 3 ? cur[i - 3] : 0, b = up ? up[i] : 0, c = up && i >= 3 ? up[i - 3] : 0;
            int pred = type == 0 ? 0 : type == 1 ? a : type == 2 ? b : type == 3 ? (a + b) / 2 : paeth(a, b, c);
            cur[i] = (uint8_t)(f[i] + pred);
        }
    }
    free(raw);
    *width = w, *height = h, *rgb = img;
    return 0;
}
