/*
 * csv.c - RFC 4180 records from printf formats (see csv.h).
 *
 * The format is walked once: literal text and conversions build the
 * current field; a literal comma closes it. Each conversion is formatted
 * on its own with snprintf, its argument fetched here by type, so that the
 * field can be quoted as a whole when its text needs it.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "measure/csv.h"

typedef struct {
    char *buf;
    size_t n, len;
    int overflow;
} out_buf;

static void put(out_buf *o, const char *s, size_t len)
{
    if (o->len + len + 1 > o->n) {
        o->overflow = 1;
        return;
    }
    memcpy(o->buf + o->len, s, len);
    o->len += len;
    o->buf[o->len] = 0;
}

/* Appends field text f, quoted when it holds , " CR or LF. */
static void put_field(out_buf *o, const char *f, size_t len)
{
    int quote = 0;
    for (size_t i = 0; i < len; i++)
        if (f[i] == ',' || f[i] == '"' || f[i] == '\r' || f[i] == '\n') quote = 1;
    if (!quote) {
        put(o, f, len);
        return;
    }
    put(o, "\"", 1);
    for (size_t i = 0; i < len; i++) {
        if (f[i] == '"') put(o, "\"", 1);
        put(o, f + i, 1);
    }
    put(o, "\"", 1);
}

int csv_vformat(char *buf, size_t n, const char *fmt, va_list ap)
{
    out_buf o = {buf, n, 0, 0};
    if (n) buf[0] = 0;
    char field[4096];
    size_t flen = 0;
    int fields = 1;
    for (const char *p = fmt; *p; p++) {
        if (*p == '\n' && p[1] == 0) break;
        if (*p == ',') {
            put_field(&o, field, flen);
            put(&o, ",", 1);
            flen = 0;
            fields++;
            continue;
        }
        char piece[1024];
        int plen;
        if (*p != '%') {
            piece[0] = *p;
            plen = 1;
        } else if (p[1] == '%') {
            piece[0] = '%';
            plen = 1;
            p++;
        } else {
            /* One conversion: flags, width, precision, length, type. */
            char spec[32];
            size_t sl = 0;
            int stars[2], nstar = 0;
            spec[sl++] = *p++;
            while (*p && strchr("-+ #0", *p) && sl < 20) spec[sl++] = *p++;
            if (*p == '*') stars[nstar++] = va_arg(ap, int), spec[sl++] = *p++;
            while (*p >= '0' && *p <= '9' && sl < 24) spec[sl++] = *p++;
            if (*p == '.') {
                spec[sl++] = *p++;
                if (*p == '*') stars[nstar++] = va_arg(ap, int), spec[sl++] = *p++;
                while (*p >= '0' && *p <= '9' && sl < 26) spec[sl++] = *p++;
            }
            char len[3] = "";
            size_t ll = 0;
            while (*p && strchr("hljztL", *p) && ll < 2) len[ll++] = spec[sl++] = *p++;
            len[ll] = 0;
            char conv = *p;
            if (!conv) return -1;
            spec[sl++] = conv;
            spec[sl] = 0;
#define PIECE(v)                                                                           \
    (nstar == 0   ? snprintf(piece, sizeof piece, spec, v)                                 \
     : nstar == 1 ? snprintf(piece, sizeof piece, spec, stars[0], v)                       \
                  : snprintf(piece, sizeof piece, spec, stars[0], stars[1], v))
            if (strchr("di", conv)) {
                if (!strcmp(len, "l")) plen = PIECE(va_arg(ap, long));
                else if (!strcmp(len, "ll")) plen = PIECE(va_arg(ap, long long));
                else if (!strcmp(len, "z")) plen = PIECE(va_arg(ap, ptrdiff_t));
                else if (!strcmp(len, "j")) plen = PIECE(va_arg(ap, intmax_t));
                else if (!strcmp(len, "t")) plen = PIECE(va_arg(ap, ptrdiff_t));
                else plen = PIECE(va_arg(ap, int));
            } else if (strchr("uoxX", conv)) {
                if (!strcmp(len, "l")) plen = PIECE(va_arg(ap, unsigned long));
                else if (!strcmp(len, "ll")) plen = PIECE(va_arg(ap, unsigned long long));
                else if (!strcmp(len, "z")) plen = PIECE(va_arg(ap, size_t));
                else if (!strcmp(len, "j")) plen = PIECE(va_arg(ap, uintmax_t));
                else if (!strcmp(len, "t")) plen = PIECE(va_arg(ap, ptrdiff_t));
                else plen = PIECE(va_arg(ap, unsigned));
            } else if (strchr("fFeEgGaA", conv)) {
                if (!strcmp(len, "L")) plen = PIECE(va_arg(ap, long double));
                else plen = PIECE(va_arg(ap, double));
            } else if (conv == 'c') {
                plen = PIECE(va_arg(ap, int));
            } else if (conv == 's') {
                const char *s = va_arg(ap, const char *);
                plen = PIECE(s ? s : "");
            } else if (conv == 'p') {
                plen = PIECE(va_arg(ap, void *));
            } else {
                return -1;
            }
#undef PIECE
            if (plen < 0 || (size_t)plen >= sizeof piece) return -1;
        }
        if (flen + (size_t)plen >= sizeof field) return -1;
        memcpy(field + flen, piece, (size_t)plen);
        flen += (size_t)plen;
    }
    put_field(&o, field, flen);
    return o.overflow ? -1 : fields;
}

int csv_format(char *buf, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = csv_vformat(buf, n, fmt, ap);
    va_end(ap);
    return rc;
}

void csv_open(csv_file *c, FILE *f)
{
    memset(c, 0, sizeof *c);
    c->f = f;
}

int csv_vrow(csv_file *c, const char *fmt, va_list ap)
{
    char line[16384];
    int fields = csv_vformat(line, sizeof line, fmt, ap);
    const char *why = NULL;
    if (fields < 0)
        why = "cannot format the record";
    else if (c->columns && fields != c->columns)
        why = "record's field count differs from the header's";
    if (why) {
        if (!c->bad_rows)
            snprintf(c->first_bad, sizeof c->first_bad, "%s (%d fields, header %d): %.120s", why,
                     fields, c->columns, fmt);
        c->bad_rows++;
        return -1;
    }
    if (!c->columns)
        c->columns = fields;
    else
        c->rows++;
    fputs(line, c->f);
    fputc('\n', c->f);
    fflush(c->f);
    return 0;
}

int csv_row(csv_file *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = csv_vrow(c, fmt, ap);
    va_end(ap);
    return rc;
}
