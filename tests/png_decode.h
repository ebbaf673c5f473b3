/*
 * png_decode.h - an independent reader for the PNG files the library
 * writes, used by tests/test_image.c to check them by round trip: its own
 * inflate (RFC 1951: stored, fixed and dynamic blocks), zlib framing
 * (RFC 1950, Adler-32), chunk CRCs and the five PNG row filters. Strict:
 * anything the specifications forbid is an error, and so is an incomplete
 * Huffman code (which the writer never emits).
 */
#ifndef TESTS_PNG_DECODE_H
#define TESTS_PNG_DECODE_H

#include <stddef.h>
#include <stdint.h>

/* What a decode saw, for tests that assert on the encoder's choices. */
typedef struct {
    size_t blocks[3];   /* deflate blocks by BTYPE: stored, fixed, dynamic */
    size_t matches;     /* LZ77 back-references */
    unsigned max_dist;  /* the farthest one, bytes */
    unsigned max_len;   /* the longest one, bytes */
    size_t filters[5];  /* PNG rows by filter type */
    size_t idat_chunks;
} png_stats;

/* Inflates a raw deflate stream into out (capacity cap). Returns the
 * decoded size, or -1 with a message in msg; *used = input bytes consumed. */
long test_inflate(const uint8_t *in, size_t n, uint8_t *out, size_t cap, size_t *used,
                  png_stats *st, char *msg, size_t msg_n);

/* Decodes a zlib stream (header, deflate, Adler-32, nothing after). */
long test_zlib_decode(const uint8_t *in, size_t n, uint8_t *out, size_t cap, png_stats *st,
                      char *msg, size_t msg_n);

/* Decodes an 8-bit RGB, non-interlaced PNG into *rgb (malloc'ed). Returns
 * 0, or -1 with a message. */
int test_png_decode(const uint8_t *png, size_t n, int *width, int *height, uint8_t **rgb,
                    png_stats *st, char *msg, size_t msg_n);

#endif
