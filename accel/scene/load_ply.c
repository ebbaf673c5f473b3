/*
 * load_ply.c - the PLY polygon file format (Greg Turk, "The PLY Polygon File
 * Format", 1994), ascii, binary_little_endian and binary_big_endian.
 *
 * Used: element `vertex` with scalar properties x, y, z (float or double;
 * integer types are accepted too), and element `face` with the list property
 * `vertex_indices` (or `vertex_index`) of any integer count and index types.
 * Every other property and element is skipped. Faces are fan-triangulated in
 * file order (FORMATS.md); the vertex element must come before the face
 * element (as every writer puts it), so that one pass suffices.
 *
 * Errors name the header or ascii line, or for binary data the byte offset
 * from the start of the file. Declared element counts are checked against
 * the bytes that follow the header (each instance takes at least the size of
 * its scalars and list counts in binary, two characters per value in ascii)
 * before anything is allocated.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/load_common.h"
#include "scene/scene.h"

typedef enum { PLY_I8, PLY_U8, PLY_I16, PLY_U16, PLY_I32, PLY_U32, PLY_F32, PLY_F64 } ply_type;

static const unsigned type_size[] = {1, 1, 2, 2, 4, 4, 4, 8};

static const struct {
    const char *name;
    ply_type type;
} type_names[] = {
    {"char", PLY_I8},    {"int8", PLY_I8},     {"uchar", PLY_U8},   {"uint8", PLY_U8},
    {"short", PLY_I16},  {"int16", PLY_I16},   {"ushort", PLY_U16}, {"uint16", PLY_U16},
    {"int", PLY_I32},    {"int32", PLY_I32},   {"uint", PLY_U32},   {"uint32", PLY_U32},
    {"float", PLY_F32},  {"float32", PLY_F32}, {"double", PLY_F64}, {"float64", PLY_F64},
};

#define PLY_NAME_MAX 48 /* longer names are kept truncated: they match nothing we use */
#define PLY_MAX_ELEMS 64
#define PLY_MAX_PROPS 256
/* Shortest ascii value: one character and a separator (bytes). */
#define PLY_ASCII_MIN_VALUE 2

typedef struct {
    char name[PLY_NAME_MAX];
    int is_list;
    ply_type type;       /* the scalar's type, or the list items' type */
    ply_type count_type; /* lists: type of the item count */
} ply_prop;

typedef struct {
    char name[PLY_NAME_MAX];
    uint64_t count;
    size_t first, n; /* its properties: props[first .. first+n-1] */
    size_t line;     /* header line that declares it */
} ply_elem;

enum { PLY_ASCII, PLY_BINARY_LE, PLY_BINARY_BE };

typedef struct {
    load_text t;
    int format; /* -1 until the format line */
    ply_elem elems[PLY_MAX_ELEMS];
    size_t elem_count;
    ply_prop props[PLY_MAX_PROPS];
    size_t prop_count;
    /* found by check_header */
    const ply_elem *vertex, *face;
    size_t px, py, pz; /* prop indices of x, y, z */
    size_t pindex;     /* prop index of the face index list */
    /* data */
    float *verts;
    size_t vert_count;
} ply_file;

static int is_int_type(ply_type t) { return t != PLY_F32 && t != PLY_F64; }

/* ---- header -------------------------------------------------------------- */

/* Next whitespace-separated word of [*p, end): returns its length (0: none). */
static size_t next_word(const char **p, const char *end, const char **word)
{
    const char *q = *p;
    while (q < end && load_is_hspace(*q)) q++;
    *word = q;
    while (q < end && !load_is_hspace(*q)) q++;
    *p = q;
    return (size_t)(q - *word);
}

static int word_is(const char *w, size_t len, const char *s)
{
    return strlen(s) == len && memcmp(w, s, len) == 0;
}

/* Names go into messages: bytes that are not printable ASCII become '?'
 * (such a name matches nothing the loader looks for anyway). */
static void copy_name(char *dst, const char *w, size_t len)
{
    if (len >= PLY_NAME_MAX) len = PLY_NAME_MAX - 1;
    for (size_t i = 0; i < len; i++) dst[i] = w[i] > 0x20 && w[i] < 0x7F ? w[i] : '?';
    dst[len] = 0;
}

static int parse_type(ply_file *f, const char *w, size_t len, ply_type *out)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++) {
        if (word_is(w, len, type_names[i].name)) {
            *out = type_names[i].type;
            return 0;
        }
    }
    char tok[200];
    load_token_text(w, w + len, tok, sizeof tok);
    return load_fail(&f->t, ACCEL_ERR_PARSE,
                     "unknown property type '%s' (accepted: char uchar short ushort int uint "
                     "float double, int8 .. uint32, float32, float64)",
                     len ? tok : "");
}

/* Parses one header line [ls, le); returns 1 at end_header. */
static int parse_header_line(ply_file *f, const char *ls, const char *le, int *done)
{
    load_text *t = &f->t;
    const char *p = ls, *w;
    size_t len = next_word(&p, le, &w);
    if (len == 0) return 0; /* blank line */
    if (word_is(w, len, "comment") || word_is(w, len, "obj_info")) return 0;
    const char *words[6];
    size_t lens[6];
    int n = 0;
    words[n] = w, lens[n++] = len;
    while (n < 6 && (len = next_word(&p, le, &w))) words[n] = w, lens[n++] = len;
    if (n == 6 || next_word(&p, le, &w))
        return load_fail(t, ACCEL_ERR_PARSE, "too many words on a header line");
    if (word_is(words[0], lens[0], "end_header")) {
        if (n != 1) return load_fail(t, ACCEL_ERR_PARSE, "unexpected words after end_header");
        *done = 1;
        return 0;
    }
    if (word_is(words[0], lens[0], "format")) {
        if (f->format >= 0) return load_fail(t, ACCEL_ERR_PARSE, "second format line");
        if (n != 3) return load_fail(t, ACCEL_ERR_PARSE, "expected 'format TYPE 1.0'");
        if (word_is(words[1], lens[1], "ascii"))
            f->format = PLY_ASCII;
        else if (word_is(words[1], lens[1], "binary_little_endian"))
            f->format = PLY_BINARY_LE;
        else if (word_is(words[1], lens[1], "binary_big_endian"))
            f->format = PLY_BINARY_BE;
        else
            return load_fail(t, ACCEL_ERR_PARSE,
                             "unknown format (accepted: ascii, binary_little_endian, "
                             "binary_big_endian)");
        if (!word_is(words[2], lens[2], "1.0") && !word_is(words[2], lens[2], "1"))
            return load_fail(t, ACCEL_ERR_PARSE, "unsupported PLY version (1.0 expected)");
        return 0;
    }
    if (word_is(words[0], lens[0], "element")) {
        if (n != 3) return load_fail(t, ACCEL_ERR_PARSE, "expected 'element NAME COUNT'");
        if (f->elem_count == PLY_MAX_ELEMS)
            return load_fail(t, ACCEL_ERR_RANGE, "more than %d elements", PLY_MAX_ELEMS);
        const char *q;
        int64_t count;
        if (load_parse_int(words[2], le, &q, &count) != LOAD_NUM_OK || q != words[2] + lens[2] ||
            count < 0)
            return load_fail(t, ACCEL_ERR_PARSE, "element count is not a non-negative integer");
        ply_elem *e = &f->elems[f->elem_count++];
        copy_name(e->name, words[1], lens[1]);
        e->count = (uint64_t)count;
        e->first = f->prop_count;
        e->n = 0;
        e->line = t->line;
        return 0;
    }
    if (word_is(words[0], lens[0], "property")) {
        if (f->elem_count == 0) return load_fail(t, ACCEL_ERR_PARSE, "property before any element");
        if (f->prop_count == PLY_MAX_PROPS)
            return load_fail(t, ACCEL_ERR_RANGE, "more than %d properties", PLY_MAX_PROPS);
        ply_prop pr = {0};
        int rc;
        if (n >= 2 && word_is(words[1], lens[1], "list")) {
            if (n != 5) return load_fail(t, ACCEL_ERR_PARSE, "expected 'property list COUNT_TYPE TYPE NAME'");
            if ((rc = parse_type(f, words[2], lens[2], &pr.count_type))) return rc;
            if (!is_int_type(pr.count_type))
                return load_fail(t, ACCEL_ERR_PARSE, "list count type must be an integer type");
            if ((rc = parse_type(f, words[3], lens[3], &pr.type))) return rc;
            pr.is_list = 1;
            copy_name(pr.name, words[4], lens[4]);
        } else {
            if (n != 3) return load_fail(t, ACCEL_ERR_PARSE, "expected 'property TYPE NAME'");
            if ((rc = parse_type(f, words[1], lens[1], &pr.type))) return rc;
            copy_name(pr.name, words[2], lens[2]);
        }
        f->props[f->prop_count++] = pr;
        f->elems[f->elem_count - 1].n++;
        return 0;
    }
    char tok[200];
    load_token_text(words[0], le, tok, sizeof tok);
    return load_fail(t, ACCEL_ERR_PARSE, "unknown header keyword '%s'", tok);
}

static int parse_header(ply_file *f)
{
    load_text *t = &f->t;
    int first = 1, done = 0;
    while (!done) {
        if (t->p >= t->end)
            return load_fail_eof(t, " in the header (no end_header)");
        const char *ls = t->p, *le = ls;
        while (le < t->end && *le != '\n' && *le != '\r') le++;
        if (memchr(ls, 0, (size_t)(le - ls)))
            return load_fail(t, ACCEL_ERR_PARSE,
                             "NUL byte in the header (UTF-16 without byte order mark, or not a "
                             "PLY file?)");
        if (first) {
            const char *p = ls, *w;
            size_t len = next_word(&p, le, &w);
            if (w != ls || !word_is(w, len, "ply") || next_word(&p, le, &w))
                return load_fail(t, ACCEL_ERR_PARSE, "not a PLY file (the first line must be 'ply')");
            first = 0;
        } else {
            int rc = parse_header_line(f, ls, le, &done);
            if (rc) return rc;
        }
        if (done && f->format < 0)
            return load_fail(t, ACCEL_ERR_PARSE, "no format line in the header");
        t->p = le;
        load_eat_newline(t); /* exactly one line end: binary data may follow */
    }
    return 0;
}

static int find_prop(const ply_file *f, const ply_elem *e, const char *name, size_t *out)
{
    for (size_t i = e->first; i < e->first + e->n; i++) {
        if (!strcmp(f->props[i].name, name)) {
            *out = i;
            return 1;
        }
    }
    return 0;
}

/* Finds the vertex and face elements, and bounds every declared count by the
 * bytes that follow the header. */
static int check_header(ply_file *f)
{
    load_text *t = &f->t;
    for (size_t i = 0; i < f->elem_count; i++) {
        const ply_elem *e = &f->elems[i];
        t->line = e->line;
        if (!strcmp(e->name, "vertex")) {
            if (f->vertex) return load_fail(t, ACCEL_ERR_PARSE, "second vertex element");
            f->vertex = e;
            static const char *const axis[3] = {"x", "y", "z"};
            size_t *slot[3] = {&f->px, &f->py, &f->pz};
            for (int k = 0; k < 3; k++) {
                if (!find_prop(f, e, axis[k], slot[k]))
                    return load_fail(t, ACCEL_ERR_PARSE, "vertex element has no property '%s'",
                                     axis[k]);
                if (f->props[*slot[k]].is_list)
                    return load_fail(t, ACCEL_ERR_PARSE, "vertex property '%s' is a list", axis[k]);
            }
        } else if (!strcmp(e->name, "face")) {
            if (f->face) return load_fail(t, ACCEL_ERR_PARSE, "second face element");
            f->face = e;
            if (!find_prop(f, e, "vertex_indices", &f->pindex) &&
                !find_prop(f, e, "vertex_index", &f->pindex))
                return load_fail(t, ACCEL_ERR_PARSE,
                                 "face element has no list 'vertex_indices' or 'vertex_index'");
            const ply_prop *pr = &f->props[f->pindex];
            if (!pr->is_list || !is_int_type(pr->type))
                return load_fail(t, ACCEL_ERR_PARSE,
                                 "face property '%s' must be a list of an integer type", pr->name);
            if (!f->vertex && e->count > 0)
                return load_fail(t, ACCEL_ERR_PARSE,
                                 "face element without a vertex element before it (the "
                                 "vertex element must come first)");
        }
    }
    /* The least bytes each instance can take: binary, its scalars and list
     * counts (a face list needs 3 indices); ascii, two characters a value. */
    uint64_t left = (uint64_t)(t->end - t->p) + (f->format == PLY_ASCII ? 1 : 0);
    uint64_t need = 0;
    for (size_t i = 0; i < f->elem_count; i++) {
        const ply_elem *e = &f->elems[i];
        uint64_t min = 0;
        for (size_t j = e->first; j < e->first + e->n; j++) {
            const ply_prop *pr = &f->props[j];
            int face_list = e == f->face && j == f->pindex;
            if (f->format == PLY_ASCII)
                min += PLY_ASCII_MIN_VALUE * (face_list ? 4 : 1);
            else if (pr->is_list)
                min += type_size[pr->count_type] + (face_list ? 3 * type_size[pr->type] : 0);
            else
                min += type_size[pr->type];
        }
        if (min == 0) continue; /* no properties: no data whatever the count */
        if (e->count > left / min || need + e->count * min > left) {
            t->line = e->line;
            return load_fail(t, ACCEL_ERR_RANGE,
                             "element '%s' declares %llu instances, but only %zu bytes of data "
                             "follow the header (truncated file or corrupt count)",
                             e->name, (unsigned long long)e->count, (size_t)(t->end - t->p));
        }
        need += e->count * min;
    }
    return 0;
}

/* ---- ascii data ---------------------------------------------------------- */

static int ascii_eof(ply_file *f, const ply_elem *e, uint64_t i)
{
    return load_fail_eof(&f->t, " in element '%s' (instance %llu of %llu)", e->name,
                         (unsigned long long)i, (unsigned long long)e->count);
}

/* A value we do not use: any number (NaN and infinity too). */
static int ascii_skip_value(ply_file *f)
{
    load_text *t = &f->t;
    const char *q;
    float unused;
    if (load_parse_float(t->p, t->end, &q, &unused) == LOAD_NUM_NONE ||
        (q < t->end && !load_is_delim(t, *q)))
        return load_fail_expected(t, "a number");
    t->p = q;
    return 0;
}

static int ascii_element(ply_file *f, const ply_elem *e, scene_builder *b)
{
    load_text *t = &f->t;
    int rc;
    if (e->n == 0) return 0; /* no properties: no data, whatever the count */
    for (uint64_t i = 0; i < e->count; i++) {
        for (size_t j = e->first; j < e->first + e->n; j++) {
            const ply_prop *pr = &f->props[j];
            load_skip_space(t);
            if (t->p >= t->end) return ascii_eof(f, e, i);
            if (e == f->vertex && (j == f->px || j == f->py || j == f->pz)) {
                int k = j == f->px ? 0 : j == f->py ? 1 : 2;
                static const char *const axis[3] = {"x coordinate", "y coordinate",
                                                    "z coordinate"};
                if ((rc = load_float_token(t, axis[k], &f->verts[3 * i + (size_t)k]))) return rc;
                continue;
            }
            if (!pr->is_list) {
                if ((rc = ascii_skip_value(f))) return rc;
                continue;
            }
            int64_t n;
            if ((rc = load_int_token(t, "list count", &n))) return rc;
            if (n < 0) return load_fail(t, ACCEL_ERR_PARSE, "negative list count %lld", (long long)n);
            int face = e == f->face && j == f->pindex;
            if (face && n < 3)
                return load_fail(t, ACCEL_ERR_PARSE, "face with %lld vertices (at least 3 needed)",
                                 (long long)n);
            size_t first = 0, prev = 0;
            for (int64_t k = 0; k < n; k++) {
                load_skip_space(t);
                if (t->p >= t->end) return ascii_eof(f, e, i);
                if (!face) {
                    if ((rc = ascii_skip_value(f))) return rc;
                    continue;
                }
                int64_t idx;
                if ((rc = load_int_token(t, "vertex index", &idx))) return rc;
                if (idx < 0)
                    return load_fail(t, ACCEL_ERR_PARSE, "negative face index %lld", (long long)idx);
                if ((uint64_t)idx >= f->vert_count)
                    return load_fail(t, ACCEL_ERR_PARSE, "face index %lld >= vertex count %zu",
                                     (long long)idx, f->vert_count);
                if (k == 0) first = (size_t)idx;
                if (k >= 2 && (rc = load_add_tri(b, f->verts, first, prev, (size_t)idx, t->err)))
                    return load_prefix(t->err, rc, "%s:%zu", t->name, t->line);
                prev = (size_t)idx;
            }
        }
    }
    return 0;
}

/* ---- binary data --------------------------------------------------------- */

static int bin_fail(ply_file *f, const char *at, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int bin_fail(ply_file *f, const char *at, const char *fmt, ...)
{
    if (!f->t.err) return ACCEL_ERR_PARSE;
    char msg[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return accel_fail(f->t.err, ACCEL_ERR_PARSE, "%s: byte %zu: %s", f->t.name,
                      (size_t)(at - f->t.begin), msg);
}

/* Reported at the end of the file: where the missing data should be. */
static int bin_eof(ply_file *f, const ply_elem *e, uint64_t i)
{
    return bin_fail(f, f->t.end, "unexpected end of file in element '%s' (instance %llu of %llu)",
                    e->name, (unsigned long long)i, (unsigned long long)e->count);
}

static inline uint64_t load_bits(const unsigned char *p, unsigned size, int big)
{
    uint64_t v = 0;
    if (big)
        for (unsigned i = 0; i < size; i++) v = v << 8 | p[i];
    else
        for (unsigned i = size; i-- > 0;) v = v << 8 | p[i];
    return v;
}

static inline int64_t int_value(uint64_t u, ply_type type)
{
    switch (type) {
    case PLY_I8: return (int8_t)(uint8_t)u;
    case PLY_I16: return (int16_t)(uint16_t)u;
    case PLY_I32: return (int32_t)(uint32_t)u;
    default: return (int64_t)u; /* unsigned types */
    }
}

static inline float float_value(uint64_t u, ply_type type)
{
    if (type == PLY_F32) {
        uint32_t w = (uint32_t)u;
        float x;
        memcpy(&x, &w, sizeof x);
        return x;
    }
    if (type == PLY_F64) {
        double d;
        memcpy(&d, &u, sizeof d);
        return (float)d; /* beyond float range becomes infinite and is rejected */
    }
    return (float)int_value(u, type);
}

static int binary_element(ply_file *f, const ply_elem *e, scene_builder *b)
{
    const char *p = f->t.p, *end = f->t.end;
    int big = f->format == PLY_BINARY_BE;
    if (e->n == 0) return 0; /* no properties: no data, whatever the count */
    int has_list = 0;
    size_t fixed = 0;
    for (size_t j = e->first; j < e->first + e->n; j++) {
        has_list |= f->props[j].is_list;
        fixed += type_size[f->props[j].type];
    }
    if (e != f->vertex && e != f->face && !has_list) {
        /* fixed-size instances: skip them all at once (check_header bounded the count) */
        if (e->count > (uint64_t)(end - p) / (fixed ? fixed : 1))
            return bin_eof(f, e, (uint64_t)(end - p) / (fixed ? fixed : 1));
        f->t.p = p + e->count * fixed;
        return 0;
    }
    for (uint64_t i = 0; i < e->count; i++) {
        for (size_t j = e->first; j < e->first + e->n; j++) {
            const ply_prop *pr = &f->props[j];
            if (!pr->is_list) {
                unsigned sz = type_size[pr->type];
                if ((size_t)(end - p) < sz) return bin_eof(f, e, i);
                if (e == f->vertex && (j == f->px || j == f->py || j == f->pz)) {
                    int k = j == f->px ? 0 : j == f->py ? 1 : 2;
                    float x = float_value(load_bits((const unsigned char *)p, sz, big), pr->type);
                    if (!isfinite(x))
                        return bin_fail(f, p, "vertex %llu: %c coordinate is NaN or infinite (or "
                                        "beyond the float range)",
                                        (unsigned long long)i, "xyz"[k]);
                    f->verts[3 * i + (size_t)k] = x;
                }
                p += sz;
                continue;
            }
            unsigned csz = type_size[pr->count_type], isz = type_size[pr->type];
            if ((size_t)(end - p) < csz) return bin_eof(f, e, i);
            int64_t n = int_value(load_bits((const unsigned char *)p, csz, big), pr->count_type);
            if (n < 0) return bin_fail(f, p, "negative list count %lld", (long long)n);
            int face = e == f->face && j == f->pindex;
            if (face && n < 3)
                return bin_fail(f, p, "face %llu has %lld vertices (at least 3 needed)",
                                (unsigned long long)i, (long long)n);
            p += csz;
            if ((uint64_t)n > (uint64_t)(end - p) / isz) return bin_eof(f, e, i);
            if (!face) {
                p += (size_t)n * isz;
                continue;
            }
            size_t first = 0, prev = 0;
            for (int64_t k = 0; k < n; k++, p += isz) {
                int64_t idx = int_value(load_bits((const unsigned char *)p, isz, big), pr->type);
                if (idx < 0)
                    return bin_fail(f, p, "face %llu: negative face index %lld",
                                    (unsigned long long)i, (long long)idx);
                if ((uint64_t)idx >= f->vert_count)
                    return bin_fail(f, p, "face %llu: face index %lld >= vertex count %zu",
                                    (unsigned long long)i, (long long)idx, f->vert_count);
                if (k == 0) first = (size_t)idx;
                if (k >= 2) {
                    int rc = load_add_tri(b, f->verts, first, prev, (size_t)idx, f->t.err);
                    if (rc)
                        return load_prefix(f->t.err, rc, "%s: byte %zu", f->t.name,
                                           (size_t)(p - f->t.begin));
                }
                prev = (size_t)idx;
            }
        }
    }
    f->t.p = p;
    return 0;
}

/* ---- driver -------------------------------------------------------------- */

static int parse_ply(ply_file *f, scene_builder *b)
{
    int rc = parse_header(f);
    if (rc) return rc;
    size_t data_line = f->t.line;
    if ((rc = check_header(f))) return rc;
    f->t.line = data_line;
    if (f->format == PLY_ASCII) {
        const char *nul = memchr(f->t.p, 0, (size_t)(f->t.end - f->t.p));
        if (nul) {
            load_text u = f->t;
            while (u.p < nul) {
                if (*u.p == '\n' || *u.p == '\r')
                    load_eat_newline(&u);
                else
                    u.p++;
            }
            return load_fail(&u, ACCEL_ERR_PARSE,
                             "NUL byte in ascii data (UTF-16, or a binary file marked ascii?)");
        }
    }
    for (size_t i = 0; i < f->elem_count; i++) {
        const ply_elem *e = &f->elems[i];
        if (e == f->vertex) {
            /* check_header bounded the count by the file size */
            f->verts = malloc(e->count ? (size_t)e->count * 3 * sizeof(float) : 1);
            if (!f->verts)
                return accel_fail(f->t.err, ACCEL_ERR_NOMEM, "%s:%zu: out of memory for %llu vertices",
                                  f->t.name, e->line, (unsigned long long)e->count);
            f->vert_count = (size_t)e->count;
        }
        if (e == f->face && (rc = scene_builder_reserve_tris(b, (size_t)e->count, f->t.err))) {
            f->t.line = e->line;
            return load_prefix(f->t.err, rc, "%s:%zu", f->t.name, e->line);
        }
        rc = f->format == PLY_ASCII ? ascii_element(f, e, b) : binary_element(f, e, b);
        if (rc) return rc;
    }
    /* Data after the last declared element would be dropped without a word
     * (a count that is too small): refused. Binary files may end in a
     * newline or two. */
    if (f->format == PLY_ASCII) {
        load_skip_space(&f->t);
        if (f->t.p < f->t.end)
            return load_fail(&f->t, ACCEL_ERR_PARSE,
                             "data after the declared elements (is an element count too small?)");
    } else {
        size_t left = (size_t)(f->t.end - f->t.p), nl = 0;
        while (nl < left && nl < 2 && (f->t.p[nl] == '\n' || f->t.p[nl] == '\r')) nl++;
        if (left > nl)
            return accel_fail(f->t.err, ACCEL_ERR_PARSE,
                              "%s: %zu bytes after the declared elements at byte %zu (is an "
                              "element count too small?)",
                              f->t.name, left, (size_t)(f->t.p - f->t.begin));
    }
    return 0;
}

int scene_parse_ply(const char *name, const char *data, size_t size, scene_builder *b,
                    accel_error *err)
{
    if (!data) data = "", size = 0;
    load_text t;
    int rc = load_text_begin(&t, name, data, size, 0, 0, err);
    if (rc) return rc;
    ply_file *f = calloc(1, sizeof *f);
    if (!f) return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory", name);
    f->t = t;
    f->format = -1;
    size_t tri_start = b->tri_count;
    rc = parse_ply(f, b);
    free(f->verts);
    free(f);
    if (rc) b->tri_count = tri_start; /* a failed load adds nothing */
    return rc;
}

int scene_load_ply(const char *path, scene_builder *b, accel_error *err)
{
    return load_parse_file(path, scene_parse_ply, b, err);
}
