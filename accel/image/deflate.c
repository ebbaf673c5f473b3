/*
 * deflate.c - the zlib stream (RFC 1950) inside PNG's IDAT, compressed with
 * deflate (RFC 1951) written here, libc only.
 *
 * Phases: (1) LZ77 over a 32 KiB window: every position is hashed on its
 * first 3 bytes into chains of earlier positions with the same hash; the
 * longest match along a bounded chain is taken one position late when the
 * next position has a longer one (the "lazy" matching RFC 1951 section 4
 * describes). (2) The literal, length and distance symbols of a block are
 * counted and given Huffman code lengths limited to 15 bits (7 for the
 * code-length code) by package-merge (Larmore & Hirschberg, "A fast
 * algorithm for optimal length-limited Huffman codes", JACM 1990), so the
 * lengths are optimal under the limit. (3) Each block goes out as dynamic
 * Huffman, fixed Huffman or stored, whichever is fewest bits, so no input
 * grows by more than the stored framing.
 */
#include <stdlib.h>
#include <string.h>

#include "image/image.h"

#define WSIZE 32768u      /* LZ77 window, bytes (the deflate maximum) */
#define WMASK (WSIZE - 1u)
#define HASH_BITS 15      /* hash table: 2^15 chain heads */
#define MIN_MATCH 3
#define MAX_MATCH 258
#define TOO_FAR 4096      /* a 3-byte match further than this costs more than 3 literals */
#define BLOCK_TOKENS 32768 /* symbols per block before the codes are rebuilt */
#define LL_CODES 286      /* literal/length alphabet in use (286, 287 never occur) */
#define D_CODES 30
#define CL_CODES 19
#define SEGMENT ((size_t)1 << 30) /* input bytes matched with one position numbering */

/* RFC 1951 section 3.2.5: base value and extra bits of each length and distance code. */
static const uint16_t len_base[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                      31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
static const uint8_t len_extra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                      2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
static const uint16_t dist_base[30] = {1,    2,    3,    4,    5,    7,     9,     13,    17,  25,
                                       33,   49,   65,   97,   129,  193,   257,   385,   513, 769,
                                       1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
static const uint8_t dist_extra[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                                       6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
/* Order in which the code-length code's lengths are sent (RFC 1951 3.2.7). */
static const uint8_t cl_order[CL_CODES] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                           11, 4,  12, 3, 13, 2, 14, 1, 15};

/* Search effort per level: chain = candidates tried, lazy = no second look
 * when the held match is at least this long, good = quarter the chain past
 * this length, nice = stop at a match this long. Level 0 = stored only. */
static const struct { uint16_t chain, lazy, good, nice; } effort[10] = {
    {0, 0, 0, 0},       {4, 4, 4, 16},     {8, 8, 4, 32},     {16, 16, 8, 64},
    {32, 16, 8, 64},    {64, 32, 16, 128}, {128, 32, 16, 128}, {256, 64, 32, 258},
    {1024, 128, 64, 258}, {4096, 258, 258, 258}};

typedef struct {
    uint8_t *buf;
    size_t n, cap;
    uint64_t acc; /* pending bits, LSB first (deflate packs from the low bit) */
    int bits;
} bit_writer;

typedef struct {
    const uint8_t *in;
    size_t n;
    int chain, lazy, good, nice;
    int32_t head[1 << HASH_BITS]; /* newest position per hash, -1 = none */
    int32_t prev[WSIZE];          /* previous position with the same hash, by pos & WMASK */
    uint16_t sym[BLOCK_TOKENS];   /* 0..255 literal, 256 + (length - 3) match */
    uint16_t dist[BLOCK_TOKENS];
    int tokens;
    size_t block_start;           /* first input byte the pending tokens cover */
    uint32_t ll_freq[LL_CODES], d_freq[D_CODES];
    uint8_t len_sym[MAX_MATCH + 1]; /* length -> length code - 257 */
    bit_writer w;
} deflater;

/* ------------------------------------------------------------------ bits */

static int reserve(bit_writer *w, size_t more)
{
    if (w->cap - w->n >= more) return 1;
    size_t cap = w->cap * 2 > w->n + more ? w->cap * 2 : w->n + more;
    uint8_t *b = realloc(w->buf, cap);
    if (!b) return 0;
    w->buf = b, w->cap = cap;
    return 1;
}

/* n <= 32 bits; the caller reserved the bytes. */
static inline void put_bits(bit_writer *w, uint32_t v, int n)
{
    w->acc |= (uint64_t)v << w->bits;
    w->bits += n;
    while (w->bits >= 8) {
        w->buf[w->n++] = (uint8_t)w->acc;
        w->acc >>= 8;
        w->bits -= 8;
    }
}

static void align_byte(bit_writer *w)
{
    if (w->bits > 0) put_bits(w, 0, 8 - w->bits);
}

static inline uint32_t reverse_bits(uint32_t v, int n)
{
    uint32_t r = 0;
    for (int i = 0; i < n; i++, v >>= 1) r = r << 1 | (v & 1);
    return r;
}

/* --------------------------------------------------------------- Huffman */

/* Code lengths <= limit minimizing sum freq*len over the symbols with
 * freq > 0 (package-merge). Needs count of used symbols <= 2^limit. One
 * used symbol gets length 1. Lists: level 0 holds the leaves sorted by
 * weight; level k merges the leaves with the pairs ("packages") of level
 * k-1. The first 2m-2 items of the last level are the optimal choice; a
 * leaf's length is the number of levels whose chosen prefix holds it, and
 * since leaves keep their sorted order in every list that prefix is the
 * lightest leaves, so counting leaves per level is enough. */
static void huff_lengths(const uint32_t *freq, int n, int limit, uint8_t *len)
{
    int sym[LL_CODES], m = 0;
    for (int i = 0; i < n; i++) {
        len[i] = 0;
        if (!freq[i]) continue;
        int j = m++; /* insertion sort by weight, stable by symbol */
        while (j > 0 && freq[sym[j - 1]] > freq[i]) sym[j] = sym[j - 1], j--;
        sym[j] = i;
    }
    if (m == 0) return;
    if (m == 1) {
        len[sym[0]] = 1;
        return;
    }
    uint64_t weight[2][2 * LL_CODES];
    uint8_t is_leaf[15][2 * LL_CODES];
    int count = m;
    for (int k = 0; k < m; k++) weight[0][k] = freq[sym[k]], is_leaf[0][k] = 1;
    for (int lev = 1; lev < limit; lev++) {
        const uint64_t *pw = weight[(lev - 1) & 1];
        uint64_t *cw = weight[lev & 1];
        int packages = count / 2, a = 0, b = 0, c = 0;
        while (a < m || b < packages) {
            uint64_t pack = b < packages ? pw[2 * b] + pw[2 * b + 1] : UINT64_MAX;
            if (a < m && (uint64_t)freq[sym[a]] <= pack)
                cw[c] = freq[sym[a++]], is_leaf[lev][c++] = 1;
            else
                cw[c] = pack, is_leaf[lev][c++] = 0, b++;
        }
        count = c;
    }
    int take = 2 * m - 2;
    for (int lev = limit - 1; lev >= 0; lev--) {
        int leaves = 0;
        for (int k = 0; k < take; k++) leaves += is_leaf[lev][k];
        for (int k = 0; k < leaves; k++) len[sym[k]]++;
        take = 2 * (take - leaves);
    }
}

/* Canonical codes (RFC 1951 3.2.2), bit-reversed for LSB-first output. */
static void huff_codes(const uint8_t *len, int n, uint16_t *code)
{
    int count[16] = {0}, next[16];
    for (int i = 0; i < n; i++) count[len[i]]++;
    count[0] = 0;
    int c = 0;
    for (int b = 1; b < 16; b++) {
        c = (c + count[b - 1]) << 1;
        next[b] = c;
    }
    for (int i = 0; i < n; i++)
        code[i] = len[i] ? (uint16_t)reverse_bits((uint32_t)next[len[i]]++, len[i]) : 0;
}

static inline int dist_code(unsigned d)
{
    unsigned v = d - 1;
    if (v < 4) return (int)v;
    int b = 31 - __builtin_clz(v);
    return 2 * b + (int)((v >> (b - 1)) & 1);
}

/* Run-length form of the code lengths (RFC 1951 3.2.7): symbols 0-15, 16
 * (repeat previous 3-6 times), 17 (3-10 zeros), 18 (11-138 zeros); extra
 * value in the high byte. Returns the number of entries. */
static int rle_lengths(const uint8_t *lens, int n, uint16_t *out)
{
    int k = 0;
    for (int i = 0; i < n;) {
        int v = lens[i], run = 1;
        while (i + run < n && lens[i + run] == v) run++;
        if (v == 0 && run >= 3) {
            int r = run > 138 ? 138 : run;
            out[k++] = r >= 11 ? (uint16_t)(18 | (r - 11) << 8) : (uint16_t)(17 | (r - 3) << 8);
            i += r;
        } else if (v != 0 && run >= 4) {
            out[k++] = (uint16_t)v; /* sent once, then repeated */
            int r = run - 1 > 6 ? 6 : run - 1;
            out[k++] = (uint16_t)(16 | (r - 3) << 8);
            i += 1 + r;
        } else {
            out[k++] = (uint16_t)v;
            i++;
        }
    }
    return k;
}

/* ---------------------------------------------------------------- blocks */

static void fixed_lengths(uint8_t *ll, uint8_t *d)
{
    for (int i = 0; i < 288; i++) ll[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
    for (int i = 0; i < D_CODES; i++) d[i] = 5;
}

/* Bits of the pending tokens' data under the given code lengths. */
static uint64_t data_bits(const deflater *z, const uint8_t *ll, const uint8_t *d)
{
    uint64_t bits = 0;
    for (int s = 0; s < LL_CODES; s++)
        bits += (uint64_t)z->ll_freq[s] * (ll[s] + (s >= 257 ? len_extra[s - 257] : 0));
    for (int s = 0; s < D_CODES; s++) bits += (uint64_t)z->d_freq[s] * (d[s] + dist_extra[s]);
    return bits;
}

static void put_tokens(deflater *z, const uint8_t *ll, const uint16_t *llc, const uint8_t *d,
                       const uint16_t *dc)
{
    bit_writer *w = &z->w;
    for (int t = 0; t < z->tokens; t++) {
        unsigned s = z->sym[t];
        if (s < 256) {
            put_bits(w, llc[s], ll[s]);
            continue;
        }
        unsigned length = s - 256 + MIN_MATCH, lc = z->len_sym[length];
        put_bits(w, llc[257 + lc], ll[257 + lc]);
        if (len_extra[lc]) put_bits(w, length - len_base[lc], len_extra[lc]);
        unsigned dist = z->dist[t];
        int dcode = dist_code(dist);
        put_bits(w, dc[dcode], d[dcode]);
        if (dist_extra[dcode]) put_bits(w, dist - dist_base[dcode], dist_extra[dcode]);
    }
    put_bits(w, llc[256], ll[256]);
}

static void put_stored(deflater *z, size_t start, size_t end, int final)
{
    bit_writer *w = &z->w;
    do {
        size_t len = end - start > 65535 ? 65535 : end - start;
        put_bits(w, (final && start + len == end) ? 1u : 0u, 1);
        put_bits(w, 0, 2);
        align_byte(w);
        put_bits(w, (uint32_t)len, 16);
        put_bits(w, (uint32_t)len ^ 0xffffu, 16);
        memcpy(w->buf + w->n, z->in + start, len);
        w->n += len;
        start += len;
    } while (start < end);
}

/* Emits the pending tokens (covering in[block_start..end)) as one block. */
static int flush_block(deflater *z, size_t end, int final)
{
    size_t raw = end - z->block_start;
    if (!reserve(&z->w, raw + 5 * (raw / 65535 + 1) + 1024)) return 0;
    z->ll_freq[256] = 1;
    uint8_t ll[288], d[D_CODES], fll[288], fd[D_CODES], cl[CL_CODES];
    /* Two used distance codes at least: one-code trees are legal but some
     * decoders reject incomplete codes; a zero-frequency code costs nothing. */
    uint32_t dfreq[D_CODES];
    memcpy(dfreq, z->d_freq, sizeof dfreq);
    int dused = 0;
    for (int i = 0; i < D_CODES; i++) dused += dfreq[i] != 0;
    for (int i = 0; dused < 2; i++)
        if (!dfreq[i]) dfreq[i] = 1, dused++;
    uint32_t llfreq[LL_CODES];
    memcpy(llfreq, z->ll_freq, sizeof llfreq);
    if (z->tokens == 0) llfreq[0] = 1; /* EOB alone: give the tree a second leaf */
    huff_lengths(llfreq, LL_CODES, 15, ll);
    huff_lengths(dfreq, D_CODES, 15, d);
    int hlit = LL_CODES, hdist = D_CODES;
    while (hlit > 257 && !ll[hlit - 1]) hlit--;
    while (hdist > 1 && !d[hdist - 1]) hdist--;
    uint8_t all[LL_CODES + D_CODES];
    memcpy(all, ll, (size_t)hlit);
    memcpy(all + hlit, d, (size_t)hdist);
    uint16_t rle[LL_CODES + D_CODES];
    int rn = rle_lengths(all, hlit + hdist, rle);
    uint32_t cl_freq[CL_CODES] = {0};
    for (int i = 0; i < rn; i++) cl_freq[rle[i] & 0xff]++;
    huff_lengths(cl_freq, CL_CODES, 7, cl);
    int hclen = CL_CODES;
    while (hclen > 4 && !cl[cl_order[hclen - 1]]) hclen--;
    static const uint8_t rle_extra[3] = {2, 3, 7};
    uint64_t dyn = 3 + 5 + 5 + 4 + 3 * (uint64_t)hclen + data_bits(z, ll, d);
    for (int i = 0; i < rn; i++) {
        int s = rle[i] & 0xff;
        dyn += cl[s] + (s >= 16 ? rle_extra[s - 16] : 0);
    }
    fixed_lengths(fll, fd);
    uint64_t fix = 3 + data_bits(z, fll, fd);
    uint64_t stored = 8 * (raw + 5 * (raw / 65535 + 1)) + 10;
    if (stored < dyn && stored < fix) {
        put_stored(z, z->block_start, end, final);
    } else if (fix <= dyn) {
        uint16_t fllc[288], fdc[D_CODES];
        huff_codes(fll, 288, fllc);
        huff_codes(fd, D_CODES, fdc);
        put_bits(&z->w, final ? 1u : 0u, 1);
        put_bits(&z->w, 1, 2); /* BTYPE 01: fixed codes */
        put_tokens(z, fll, fllc, fd, fdc);
    } else {
        uint16_t llc[LL_CODES], dc[D_CODES], clc[CL_CODES];
        huff_codes(ll, LL_CODES, llc);
        huff_codes(d, D_CODES, dc);
        huff_codes(cl, CL_CODES, clc);
        bit_writer *w = &z->w;
        put_bits(w, final ? 1u : 0u, 1);
        put_bits(w, 2, 2); /* BTYPE 10: dynamic codes */
        put_bits(w, (uint32_t)(hlit - 257), 5);
        put_bits(w, (uint32_t)(hdist - 1), 5);
        put_bits(w, (uint32_t)(hclen - 4), 4);
        for (int i = 0; i < hclen; i++) put_bits(w, cl[cl_order[i]], 3);
        for (int i = 0; i < rn; i++) {
            int s = rle[i] & 0xff;
            put_bits(w, clc[s], cl[s]);
            if (s >= 16) put_bits(w, rle[i] >> 8, rle_extra[s - 16]);
        }
        put_tokens(z, ll, llc, d, dc);
    }
    z->tokens = 0;
    z->block_start = end;
    memset(z->ll_freq, 0, sizeof z->ll_freq);
    memset(z->d_freq, 0, sizeof z->d_freq);
    return 1;
}

/* ----------------------------------------------------------------- LZ77 */

static inline uint32_t hash3(const uint8_t *p)
{
    uint32_t v = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16;
    return (v * 2654435761u) >> (32 - HASH_BITS); /* Knuth's multiplicative hash */
}

/* Links pos into its hash chain; returns the previous head (-1: none). */
static inline int32_t insert(deflater *z, size_t pos)
{
    if (pos + MIN_MATCH > z->n) return -1;
    uint32_t h = hash3(z->in + pos);
    int32_t cand = z->head[h];
    z->prev[pos & WMASK] = cand;
    z->head[h] = (int32_t)pos;
    return cand;
}

static inline uint32_t load32(const uint8_t *p)
{
    uint32_t v;
    memcpy(&v, p, 4);
    return v;
}

static inline uint64_t load64(const uint8_t *p)
{
    uint64_t v;
    memcpy(&v, p, 8);
    return v;
}

/* Longest match for pos longer than `beat`, along the chain from cand.
 * Distances stay below WSIZE: the chain slot of pos - WSIZE was just
 * reused by pos itself. Returns the length (0: none better) and *dist. */
static int longest_match(const deflater *z, size_t pos, int32_t cand, int beat, unsigned *dist)
{
    size_t avail = z->n - pos;
    int max_len = avail < MAX_MATCH ? (int)avail : MAX_MATCH;
    int best = beat < MIN_MATCH - 1 ? MIN_MATCH - 1 : beat;
    if (best >= max_len) return 0;
    int chain = beat >= z->good ? z->chain >> 2 : z->chain, found = 0;
    const uint8_t *b = z->in + pos;
    int64_t limit = (int64_t)pos - (int64_t)(WSIZE - 1);
    while (cand >= 0 && cand >= limit && chain-- > 0) {
        const uint8_t *a = z->in + cand;
        /* Cheap rejection: a longer match must agree at both ends of the current best. */
        if (best >= 3 ? load32(a + best - 3) == load32(b + best - 3) && load32(a) == load32(b)
                      : a[2] == b[2] && a[0] == b[0] && a[1] == b[1]) {
            int l = best >= 3 ? 4 : 3;
            while (l + 8 <= max_len && load64(a + l) == load64(b + l)) l += 8;
            while (l < max_len && a[l] == b[l]) l++;
            if (l > best) {
                best = l, found = 1;
                *dist = (unsigned)(pos - (size_t)cand);
                if (l >= z->nice || l == max_len) break;
            }
        }
        cand = z->prev[cand & WMASK];
    }
    return found ? best : 0;
}

static inline int add_literal(deflater *z, size_t pos)
{
    z->sym[z->tokens] = z->in[pos];
    z->dist[z->tokens++] = 0;
    z->ll_freq[z->in[pos]]++;
    return z->tokens == BLOCK_TOKENS ? flush_block(z, pos + 1, 0) : 1;
}

static inline int add_match(deflater *z, size_t pos, int len, unsigned dist)
{
    z->sym[z->tokens] = (uint16_t)(256 + len - MIN_MATCH);
    z->dist[z->tokens++] = (uint16_t)dist;
    z->ll_freq[257 + z->len_sym[len]]++;
    z->d_freq[dist_code(dist)]++;
    return z->tokens == BLOCK_TOKENS ? flush_block(z, pos + (size_t)len, 0) : 1;
}

/* Lazy matching: a match found at pos is held for one step; if pos + 1
 * has a longer one, pos goes out as a literal instead. */
static int compress_lz77(deflater *z)
{
    size_t pos = 0, n = z->n;
    int held = 0, held_len = 0;
    unsigned held_dist = 0;
    while (pos < n) {
        int32_t cand = insert(z, pos);
        int len = 0;
        unsigned dist = 0;
        if (cand >= 0 && held_len < z->lazy) len = longest_match(z, pos, cand, held_len, &dist);
        if (len == MIN_MATCH && dist > TOO_FAR) len = 0;
        if (held && held_len >= MIN_MATCH && len <= held_len) {
            size_t start = pos - 1, end = start + (size_t)held_len;
            if (!add_match(z, start, held_len, held_dist)) return 0;
            for (size_t p = pos + 1; p < end; p++) insert(z, p);
            pos = end;
            held = 0, held_len = 0;
            continue;
        }
        if (held && !add_literal(z, pos - 1)) return 0;
        held = 1, held_len = len, held_dist = dist;
        pos++;
    }
    if (held && !add_literal(z, n - 1)) return 0;
    return 1;
}

static uint32_t adler32_update(const uint8_t *data, size_t n)
{
    /* Reduce every 5552 bytes: the largest k with 255 k (k + 1) / 2 + (k + 1) 65520
     * < 2^32, so neither sum overflows before the modulo. */
    uint32_t a = 1, b = 0;
    while (n) {
        size_t k = n < 5552 ? n : 5552;
        n -= k;
        while (k--) a += *data++, b += a;
        a %= 65521u, b %= 65521u;
    }
    return (b << 16) | a;
}

uint32_t image_adler32(const uint8_t *data, size_t n)
{
    return adler32_update(data, n);
}

int image_zlib_compress(const uint8_t *in, size_t n, int level, uint8_t **out, size_t *out_n,
                        accel_error *err)
{
    *out = NULL;
    *out_n = 0;
    if (level < 0 || level > 9) return accel_fail(err, ACCEL_ERR_RANGE, "zlib level %d not in 0..9", level);
    deflater *z = malloc(sizeof *z);
    if (!z) return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for the compressor");
    memset(z->ll_freq, 0, sizeof z->ll_freq);
    memset(z->d_freq, 0, sizeof z->d_freq);
    z->in = in, z->n = n;
    z->chain = effort[level].chain, z->lazy = effort[level].lazy;
    z->good = effort[level].good, z->nice = effort[level].nice;
    z->tokens = 0, z->block_start = 0;
    for (int c = 0; c < 29; c++)
        for (int l = len_base[c]; l < len_base[c] + (1 << len_extra[c]) && l <= MAX_MATCH; l++)
            z->len_sym[l] = (uint8_t)c; /* 258 ends in code 28 (symbol 285), its own code */
    z->w = (bit_writer){0};
    int ok = reserve(&z->w, 64);
    if (ok) {
        put_bits(&z->w, 0x78, 8); /* CMF: deflate, 32 KiB window */
        /* FLG: no dictionary, level hint, check bits so that CMF*256 + FLG is a multiple of 31 */
        put_bits(&z->w, level == 0 ? 0x01 : 0x9c, 8);
        if (level == 0) {
            ok = reserve(&z->w, n + 5 * (n / 65535 + 1) + 8);
            if (ok) put_stored(z, 0, n, 1);
        } else {
            /* Positions are int32: inputs past SEGMENT bytes are matched in
             * segments (no match crosses a boundary; the stream is one). */
            for (size_t seg = 0; ok && (seg < n || seg == 0); seg += SEGMENT) {
                size_t seg_n = n - seg < SEGMENT ? n - seg : SEGMENT;
                z->in = in + seg, z->n = seg_n, z->block_start = 0;
                memset(z->head, 0xff, sizeof z->head);
                ok = compress_lz77(z) && flush_block(z, seg_n, seg + seg_n == n);
            }
        }
    }
    if (ok) ok = reserve(&z->w, 8);
    if (ok) {
        align_byte(&z->w);
        uint32_t adler = adler32_update(in, n);
        for (int s = 24; s >= 0; s -= 8) put_bits(&z->w, (adler >> s) & 0xff, 8);
        *out = z->w.buf;
        *out_n = z->w.n;
    } else {
        free(z->w.buf);
    }
    free(z);
    return ok ? 0 : accel_fail(err, ACCEL_ERR_NOMEM, "out of memory compressing %zu bytes", n);
}
