/*
 * load_common.c - file reading, text checks, messages and exact number
 * parsing shared by the mesh loaders. See load_common.h for the method
 * (Clinger's fast path with a strtof fallback).
 */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "scene/load_common.h"

int load_read_file(const char *path, char **data, size_t *size, accel_error *err)
{
    *data = NULL;
    *size = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    /* The stat size is only a hint (the file may grow or be a pipe): read
     * until EOF, growing when the hint was short. */
    size_t cap = 65536;
    struct stat st;
    int have_st = fstat(fileno(f), &st) == 0;
    /* A directory, or a device such as /dev/zero (which would be read until
     * memory runs out), is no scene file; regular files and pipes are. */
    if (have_st && (S_ISDIR(st.st_mode) || S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode))) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_IO, "%s: not a regular file (a %s)", path,
                          S_ISDIR(st.st_mode) ? "directory" : "device");
    }
    if (have_st && S_ISREG(st.st_mode) && st.st_size >= 0 &&
        (unsigned long long)st.st_size < (unsigned long long)SIZE_MAX - 1)
        cap = (size_t)st.st_size + 1;
    char *buf = malloc(cap);
    if (!buf) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory reading %zu bytes", path, cap);
    }
    size_t n = 0;
    for (;;) {
        if (n == cap) {
            if (cap > SIZE_MAX / 2) {
                free(buf);
                fclose(f);
                return accel_fail(err, ACCEL_ERR_NOMEM, "%s: file too large", path);
            }
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                fclose(f);
                return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory reading %zu bytes",
                                  path, cap * 2);
            }
            buf = nb;
            cap *= 2;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) break;
    }
    int failed = ferror(f);
    int saved = errno;
    fclose(f);
    if (failed) {
        free(buf);
        return accel_fail(err, ACCEL_ERR_IO, "%s: cannot read: %s", path, strerror(saved));
    }
    *data = buf;
    *size = n;
    return 0;
}

int load_parse_file(const char *path, load_parse_fn parse, scene_builder *b, accel_error *err)
{
    char *data;
    size_t size;
    int rc = load_read_file(path, &data, &size, err);
    if (rc) return rc;
    rc = parse(path, data, size, b, err);
    free(data);
    return rc;
}

/* Line number (1-based) of position pos, counting "\n", "\r\n" and "\r". */
static size_t line_of(const char *data, size_t pos)
{
    size_t line = 1;
    for (size_t i = 0; i < pos; i++) {
        if (data[i] == '\n') {
            line++;
        } else if (data[i] == '\r') {
            line++;
            if (i + 1 < pos && data[i + 1] == '\n') i++;
        }
    }
    return line;
}

int load_check_text(const char *name, const char *data, size_t size, size_t text_size,
                    size_t *skip, accel_error *err)
{
    const unsigned char *u = (const unsigned char *)data;
    *skip = 0;
    if (size >= 4 && ((u[0] == 0xFF && u[1] == 0xFE && u[2] == 0 && u[3] == 0) ||
                      (u[0] == 0 && u[1] == 0 && u[2] == 0xFE && u[3] == 0xFF)))
        return accel_fail(err, ACCEL_ERR_PARSE,
                          "%s: file is UTF-32 encoded (byte order mark): save it as ASCII or UTF-8",
                          name);
    if (size >= 2 && ((u[0] == 0xFF && u[1] == 0xFE) || (u[0] == 0xFE && u[1] == 0xFF)))
        return accel_fail(err, ACCEL_ERR_PARSE,
                          "%s: file is UTF-16 encoded (byte order mark %02X %02X): save it as "
                          "ASCII or UTF-8",
                          name, u[0], u[1]);
    if (size >= 3 && u[0] == 0xEF && u[1] == 0xBB && u[2] == 0xBF) *skip = 3;
    if (text_size > size) text_size = size;
    const char *nul = text_size ? memchr(data, 0, text_size) : NULL;
    if (nul)
        return accel_fail(err, ACCEL_ERR_PARSE,
                          "%s:%zu: NUL byte in a text file (UTF-16 without byte order mark, or "
                          "not a text file?)",
                          name, line_of(data, (size_t)(nul - data)));
    return 0;
}

int load_text_begin(load_text *t, const char *name, const char *data, size_t size,
                    size_t text_size, char comment, accel_error *err)
{
    size_t skip;
    int rc = load_check_text(name, data, size, text_size, &skip, err);
    if (rc) return rc;
    *t = (load_text){name, data, data + skip, data + size, 1, comment, err};
    return 0;
}

/* msg with control characters and bytes above ASCII as \xNN, as
 * load_token_text shows tokens: words quoted from a file (a .scene's
 * unknown keyword) must not put terminal escapes on the screen. */
static void escape_controls(const char *msg, char *out, size_t size)
{
    size_t n = 0;
    for (const unsigned char *p = (const unsigned char *)msg; *p && n + 5 < size; p++) {
        if (*p < 0x20 || *p >= 0x7F)
            n += (size_t)snprintf(out + n, size - n, "\\x%02X", *p);
        else
            out[n++] = (char)*p;
    }
    out[n] = 0;
}

int load_fail(const load_text *t, int code, const char *fmt, ...)
{
    if (!t->err) return code;
    char msg[400], shown[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    escape_controls(msg, shown, sizeof shown);
    return accel_fail(t->err, code, "%s:%zu: %s", t->name, t->line, shown);
}

int load_fail_eof(const load_text *t, const char *fmt, ...)
{
    if (!t->err) return ACCEL_ERR_PARSE;
    char msg[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    /* In a file that ends with a line end, name its last line (as an editor
     * numbers them), not the empty one after it. */
    size_t line = t->line;
    if (line > 1 && t->end > t->begin && (t->end[-1] == '\n' || t->end[-1] == '\r')) line--;
    return accel_fail(t->err, ACCEL_ERR_PARSE, "%s:%zu: unexpected end of file%s", t->name, line,
                      msg);
}

int load_prefix(accel_error *err, int rc, const char *fmt, ...)
{
    if (!err) return rc;
    char where[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(where, sizeof where, fmt, ap);
    va_end(ap);
    size_t wl = strlen(where), cap = sizeof err->msg;
    if (wl + 3 > cap) return rc;
    size_t ml = strnlen(err->msg, cap - 1);
    if (ml > cap - 1 - (wl + 2)) ml = cap - 1 - (wl + 2); /* truncate the old message */
    memmove(err->msg + wl + 2, err->msg, ml);
    memcpy(err->msg, where, wl);
    memcpy(err->msg + wl, ": ", 2);
    err->msg[wl + 2 + ml] = 0;
    return rc;
}

void load_token_text(const char *p, const char *end, char *buf, size_t size)
{
    size_t n = 0;
    for (int i = 0; p < end && i < 40 && n + 5 < size; i++, p++) {
        unsigned char c = (unsigned char)*p;
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f') break;
        if (c < 0x20 || c >= 0x7F || c == '\'' || c == '\\') {
            n += (size_t)snprintf(buf + n, size - n, "\\x%02X", c);
        } else {
            buf[n++] = (char)c;
        }
    }
    if (n < size) buf[n] = 0;
    if (p < end && n + 4 < size && !(*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r'))
        memcpy(buf + n, "...", 4);
}

int load_fail_expected(const load_text *t, const char *what)
{
    if (t->p >= t->end) return load_fail_eof(t, ": expected %s", what);
    if (*t->p == '\n' || *t->p == '\r')
        return load_fail(t, ACCEL_ERR_PARSE, "expected %s, found end of line", what);
    if (t->comment && *t->p == t->comment)
        return load_fail(t, ACCEL_ERR_PARSE, "expected %s, found a comment", what);
    char tok[200];
    load_token_text(t->p, t->end, tok, sizeof tok);
    return load_fail(t, ACCEL_ERR_PARSE, "expected %s, found '%s'", what, tok);
}

void load_next_line(load_text *t)
{
    const char *p = t->p, *end = t->end;
    while (p < end && *p != '\n' && *p != '\r') p++;
    t->p = p;
    load_eat_newline(t);
}

void load_skip_space(load_text *t)
{
    while (t->p < t->end) {
        char c = *t->p;
        if (load_is_hspace(c)) {
            t->p++;
        } else if (c == '\n' || c == '\r') {
            load_eat_newline(t);
        } else if (t->comment && c == t->comment) {
            load_next_line(t);
        } else {
            break;
        }
    }
}

/* ---- numbers ------------------------------------------------------------- */

static const float pow10_float[11] = {1e0f, 1e1f, 1e2f, 1e3f, 1e4f, 1e5f,
                                      1e6f, 1e7f, 1e8f, 1e9f, 1e10f};
static const double pow10_double[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                        1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                        1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

static inline int is_digit(char c) { return (unsigned)(c - '0') < 10u; }

/* Case-insensitive match of the word w (lower case) at p. */
static int match_word(const char *p, const char *end, const char *w)
{
    for (; *w; w++, p++)
        if (p >= end || (*p | 0x20) != *w) return 0;
    return 1;
}

/* Correctly rounded conversion of the decimal at [s, e) (a number already
 * validated by load_parse_float; `exp10` its explicit exponent) by strtof on
 * a canonical copy: the significant digits, at most KEEP of them plus one
 * sticky digit standing for anything nonzero dropped, and an exponent. The
 * exact value of a float, or of a midpoint between two floats, has at most
 * 113 significant decimal digits (a 25-bit integer times 5^150 for 2^-150),
 * so the digits dropped beyond KEEP = 120 can only matter through being
 * nonzero, which the sticky digit preserves. */
#define KEEP 120
static float slow_float(const char *s, const char *e, int neg, int64_t exp10)
{
    char buf[KEEP + 40];
    size_t n = 0;
    int64_t shift = 0;
    int seen = 0, sticky = 0, frac = 0;
    size_t kept = 0;
    if (neg) buf[n++] = '-';
    for (const char *p = s; p < e; p++) {
        if (*p == '.') {
            frac = 1;
            continue;
        }
        if (!is_digit(*p)) continue; /* the sign */
        if (!seen && *p == '0') {
            if (frac) shift--;
            continue;
        }
        seen = 1;
        if (kept < KEEP) {
            buf[n++] = *p;
            kept++;
            if (frac) shift--;
        } else {
            if (!frac) shift++;
            if (*p != '0') sticky = 1;
        }
    }
    if (!seen) return neg ? -0.0f : 0.0f;
    if (sticky) {
        buf[n++] = '1';
        shift--;
    }
    snprintf(buf + n, sizeof buf - n, "e%lld", (long long)(shift + exp10));
    return strtof(buf, NULL);
}

load_num_status load_parse_float(const char *p, const char *end, const char **endp, float *out)
{
    const char *s = p;
    int neg = 0;
    *endp = s;
    if (p < end && (*p == '+' || *p == '-')) neg = *p++ == '-';
    if (p < end && ((*p | 0x20) == 'n' || (*p | 0x20) == 'i')) {
        if (match_word(p, end, "nan")) {
            *endp = p + 3;
            return LOAD_NUM_NONFINITE;
        }
        if (match_word(p, end, "infinity")) {
            *endp = p + 8;
            return LOAD_NUM_NONFINITE;
        }
        if (match_word(p, end, "inf")) {
            *endp = p + 3;
            return LOAD_NUM_NONFINITE;
        }
        return LOAD_NUM_NONE;
    }
    uint64_t m = 0;
    int digits = 0, any = 0, truncated = 0;
    int64_t e10 = 0;
    while (p < end && is_digit(*p)) {
        unsigned d = (unsigned)(*p++ - '0');
        any = 1;
        if (m == 0 && d == 0) continue;
        if (digits < 19) {
            m = m * 10 + d;
            digits++;
        } else {
            e10++;
            truncated |= d != 0;
        }
    }
    if (p < end && *p == '.') {
        p++;
        while (p < end && is_digit(*p)) {
            unsigned d = (unsigned)(*p++ - '0');
            any = 1;
            if (m == 0 && d == 0) {
                e10--;
            } else if (digits < 19) {
                m = m * 10 + d;
                digits++;
                e10--;
            } else {
                truncated |= d != 0;
            }
        }
    }
    if (!any) return LOAD_NUM_NONE;
    const char *mant_end = p;
    int64_t exp10 = 0;
    if (p < end && (*p == 'e' || *p == 'E')) {
        const char *q = p + 1;
        int eneg = 0;
        if (q < end && (*q == '+' || *q == '-')) eneg = *q++ == '-';
        if (q < end && is_digit(*q)) {
            while (q < end && is_digit(*q)) {
                if (exp10 < 1000000) exp10 = exp10 * 10 + (*q - '0');
                q++;
            }
            if (eneg) exp10 = -exp10;
            p = q;
        }
        /* else: "1e" or "1e+" is left for the caller to reject at the 'e' */
    }
    *endp = p;
    if (m == 0) {
        *out = neg ? -0.0f : 0.0f;
        return LOAD_NUM_OK;
    }
    e10 += exp10;
    float f;
    if (!truncated && m <= (1u << 24) && e10 >= -10 && e10 <= 10) {
        /* both operands exact in float: one rounding */
        f = (float)m;
        f = e10 < 0 ? f / pow10_float[-e10] : f * pow10_float[e10];
    } else if (!truncated && m <= (UINT64_C(1) << 53) && e10 >= -22 && e10 <= 22) {
        /* correctly rounded double, in [1e-22, 9e37]: inside float's normal
         * range, so rounding to float is exact unless d sits on a midpoint */
        double d = (double)m;
        d = e10 < 0 ? d / pow10_double[-e10] : d * pow10_double[e10];
        uint64_t bits;
        memcpy(&bits, &d, sizeof bits);
        if ((bits & ((UINT64_C(1) << 29) - 1)) == (UINT64_C(1) << 28))
            f = slow_float(s, mant_end, 0, exp10);
        else
            f = (float)d;
    } else {
        f = slow_float(s, mant_end, 0, exp10);
        if (!isfinite(f)) return LOAD_NUM_NONFINITE;
    }
    *out = neg ? -f : f;
    return LOAD_NUM_OK;
}

load_num_status load_parse_int(const char *p, const char *end, const char **endp, int64_t *out)
{
    int neg = 0, over = 0;
    *endp = p;
    if (p < end && (*p == '+' || *p == '-')) neg = *p++ == '-';
    if (p >= end || !is_digit(*p)) return LOAD_NUM_NONE;
    uint64_t m = 0;
    while (p < end && is_digit(*p)) {
        unsigned d = (unsigned)(*p++ - '0');
        if (m > (UINT64_MAX - d) / 10)
            over = 1;
        else
            m = m * 10 + d;
    }
    *endp = p;
    if (over || m > (uint64_t)INT64_MAX + (uint64_t)neg) return LOAD_NUM_RANGE;
    *out = neg ? (int64_t)(0 - m) : (int64_t)m;
    return LOAD_NUM_OK;
}

int load_float_token(load_text *t, const char *what, float *out)
{
    const char *q;
    load_num_status st = load_parse_float(t->p, t->end, &q, out);
    if (st == LOAD_NUM_NONE || (q < t->end && !load_is_delim(t, *q)))
        return load_fail_expected(t, what);
    if (st != LOAD_NUM_OK) {
        char tok[200];
        load_token_text(t->p, t->end, tok, sizeof tok);
        return load_fail(t, ACCEL_ERR_PARSE, "%s '%s' is NaN or infinite (or beyond the float range)",
                         what, tok);
    }
    t->p = q;
    return 0;
}

int load_int_token(load_text *t, const char *what, int64_t *out)
{
    const char *q;
    load_num_status st = load_parse_int(t->p, t->end, &q, out);
    if (st == LOAD_NUM_NONE || (q < t->end && !load_is_delim(t, *q)))
        return load_fail_expected(t, what);
    if (st == LOAD_NUM_RANGE) {
        char tok[200];
        load_token_text(t->p, t->end, tok, sizeof tok);
        return load_fail(t, ACCEL_ERR_RANGE, "%s '%s' is out of range", what, tok);
    }
    t->p = q;
    return 0;
}
