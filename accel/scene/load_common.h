/*
 * load_common.h - lexing shared by the file readers (load_obj.c, load_ply.c,
 * load_off.c, load_scene.c): whole-file reading, line tracking, exact number
 * parsing and error messages that name the file and the line or byte
 * offset; and the .scene reader's entry, which load.c calls.
 *
 * Every parser works on a buffer that is NOT NUL-terminated (fuzz inputs,
 * memory-mapped data): every read is bounded by `end`, never by a NUL.
 *
 * Line ends are "\n", "\r\n" and a lone "\r", counted as one line each, so
 * files written on any system (or concatenated from several) number their
 * lines the way an editor shows them.
 *
 * Decimal to float conversion is exact (correctly rounded, as strtof) by
 * Clinger's fast path: W. D. Clinger, "How to Read Floating Point Numbers
 * Accurately", PLDI 1990. When the significand and the power of ten are
 * both exact in float (<= 2^24 and 10^|e| with |e| <= 10), one float
 * multiplication or division rounds once and is exact. Otherwise, when they
 * are exact in double (<= 2^53, |e| <= 22), the double result is correctly
 * rounded, and rounding it again to float is correct unless the double lands
 * exactly on a midpoint between two floats (double rounding); those rare
 * cases, float subnormals, and long or far-exponent forms go to strtof on a
 * bounded NUL-terminated copy of the token.
 */
#ifndef ACCEL_LOAD_COMMON_H
#define ACCEL_LOAD_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "accel.h"
#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A cursor over a text buffer, with the 1-based number of the line it is on. */
typedef struct {
    const char *name; /* file name for messages */
    const char *begin, *p, *end;
    size_t line;
    char comment; /* comment character ('#'), or 0 when the format has none */
    accel_error *err;
} load_text;

/* Reads a whole file into a malloc'ed buffer (*data, *size; free with free()).
 * An empty file gives a valid 1-byte allocation and *size == 0. */
int load_read_file(const char *path, char **data, size_t *size, accel_error *err);

/* A mesh parser on a buffer: scene_parse_obj, _ply or _off (scene.h). */
typedef int (*load_parse_fn)(const char *name, const char *data, size_t size, scene_builder *b,
                             accel_error *err);
/* Reads the file at path and parses it with parse (messages name path):
 * scene_load_obj, _ply and _off. */
int load_parse_file(const char *path, load_parse_fn parse, scene_builder *b, accel_error *err);

/* Rejects UTF-16/UTF-32 (byte order mark or NUL bytes) with a clear message
 * and returns in *skip the length of a UTF-8 byte order mark (0 or 3) to be
 * skipped. Only the first `text_size` bytes are scanned for NULs (PLY: the
 * header). */
int load_check_text(const char *name, const char *data, size_t size, size_t text_size,
                    size_t *skip, accel_error *err);
/* load_check_text, then *t over the buffer past the byte order mark, at
 * line 1, with the format's comment character (0: none). */
int load_text_begin(load_text *t, const char *name, const char *data, size_t size,
                    size_t text_size, char comment, accel_error *err);

/* "name:line: message" (text) */
int load_fail(const load_text *t, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* "name:line: unexpected end of file" followed by the message, naming the last line of a
 * file that ends with a line end (not the empty line after it). */
int load_fail_eof(const load_text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* "name:line: expected WHAT, found 'TOKEN'" (or "found end of line / end of file") */
int load_fail_expected(const load_text *t, const char *what);

/* Puts a location (formatted by fmt: "name:line", "name: byte N") before
 * the message another module set in err (the scene builder's "out of
 * memory"), so that every loader error names the file. Returns rc. */
int load_prefix(accel_error *err, int rc, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Copies the token at p (up to a delimiter, at most 40 characters) into buf
 * with non-printable bytes escaped as \xNN, for messages. */
void load_token_text(const char *p, const char *end, char *buf, size_t size);

/* ---- number parsing ------------------------------------------------------ */

typedef enum {
    LOAD_NUM_OK = 0,
    LOAD_NUM_NONE,     /* not a number (no digits) */
    LOAD_NUM_NONFINITE,/* nan, inf, infinity, or a value beyond the float range */
    LOAD_NUM_RANGE     /* integer that does not fit int64 */
} load_num_status;

/* Parses [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)? at p,
 * correctly rounded to float; sets *endp after the number. The caller checks
 * what follows (a delimiter). */
load_num_status load_parse_float(const char *p, const char *end, const char **endp, float *out);
/* Parses [+-]? digits at p into int64; sets *endp after the number. */
load_num_status load_parse_int(const char *p, const char *end, const char **endp, int64_t *out);

/* ---- inline lexing ------------------------------------------------------- */

static inline int load_is_hspace(char c)
{
    return c == ' ' || c == '\t' || c == '\v' || c == '\f';
}

/* True when the character ends a token: whitespace, line end, or comment. */
static inline int load_is_delim(const load_text *t, char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f' ||
           (t->comment && c == t->comment);
}

static inline void load_skip_hspace(load_text *t)
{
    while (t->p < t->end && load_is_hspace(*t->p)) t->p++;
}

/* At a line end, a comment, or the end of the buffer. */
static inline int load_at_eol(const load_text *t)
{
    return t->p >= t->end || *t->p == '\n' || *t->p == '\r' || (t->comment && *t->p == t->comment);
}

/* Consumes one line end ("\n", "\r\n" or "\r") at p, if there is one. */
static inline void load_eat_newline(load_text *t)
{
    if (t->p >= t->end) return;
    if (*t->p == '\n') {
        t->p++;
        t->line++;
    } else if (*t->p == '\r') {
        t->p++;
        if (t->p < t->end && *t->p == '\n') t->p++;
        t->line++;
    }
}

/* Skips the rest of the line and its line end. */
void load_next_line(load_text *t);

/* Skips whitespace, line ends and comments (token-stream formats). */
void load_skip_space(load_text *t);

/* Parses a float token ending at a delimiter; on failure fills the error
 * ("expected WHAT", or a NaN/infinity message). */
int load_float_token(load_text *t, const char *what, float *out);
/* Parses an integer token ending at a delimiter (unlike load_float_token the
 * caller may allow other terminators: see load_parse_int). */
int load_int_token(load_text *t, const char *what, int64_t *out);

/* The .scene reader (load_scene.c) on a buffer: scene_parse_scene with
 * opt and opt->load_mesh given (load.c supplies the default mesh loader,
 * which may load built-in scenes and mesh files through scene_create). */
int load_scene_parse(const char *name, const char *dir, const char *data, size_t size,
                     const scene_file_options *opt, accel_scene *s, accel_error *err);

/* Appends triangle (a, c, d) of the vertex array v (3 floats per vertex). */
static inline int load_add_tri(scene_builder *b, const float *v, size_t a, size_t c, size_t d,
                               accel_error *err)
{
    return scene_builder_add_tri(b, v3_load(v + 3 * a), v3_load(v + 3 * c), v3_load(v + 3 * d),
                                 err);
}

#ifdef __cplusplus
}
#endif

#endif
