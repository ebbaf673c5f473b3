/*
 * load_obj.c - the Wavefront OBJ format, geometry only.
 *
 *   v x y z [w] [r g b]     a vertex (extra values ignored)
 *   f a b c ...             a polygon; each corner is v, v/vt, v//vn or
 *                           v/vt/vn, where only v is used
 *
 * Vertex indices start at 1; a negative index is relative to the vertices
 * defined so far (-1 is the last one), as the OBJ specification says. A face
 * may only use vertices defined before it (single pass, as every exporter
 * writes them). Faces are fan-triangulated in file order (FORMATS.md).
 * Every other statement (vt, vn, vp, g, o, s, usemtl, mtllib, l, p, curves,
 * unknown keywords) is ignored, '#' starts a comment, and a backslash as the
 * last character of a line joins it to the next.
 */
#include <stdlib.h>
#include <string.h>

#include "scene/load_common.h"
#include "scene/scene.h"

typedef struct {
    float *v;
    size_t count, cap; /* vertices (3 floats each) */
} vertex_list;

/* A backslash followed by a line end (or the end of the file) joins lines. */
static inline int at_continuation(const load_text *t, const char *p)
{
    return p < t->end && *p == '\\' && (p + 1 == t->end || p[1] == '\n' || p[1] == '\r');
}

static void skip_hspace(load_text *t)
{
    for (;;) {
        load_skip_hspace(t);
        if (!at_continuation(t, t->p)) return;
        t->p++;
        load_eat_newline(t);
    }
}

/* Skips the rest of the statement, continuation lines included. */
static void skip_statement(load_text *t)
{
    while (t->p < t->end) {
        char c = *t->p;
        if (c == '\n' || c == '\r') {
            load_eat_newline(t);
            return;
        }
        if (c == '#') {
            load_next_line(t);
            return;
        }
        if (at_continuation(t, t->p)) {
            t->p++;
            load_eat_newline(t);
        } else {
            t->p++;
        }
    }
}

/* A token may end where a continuation begins. */
static inline int token_ends(const load_text *t, const char *q)
{
    return q >= t->end || load_is_delim(t, *q) || at_continuation(t, q);
}

static int parse_vertex(load_text *t, vertex_list *vl)
{
    static const char *const axis[3] = {"x coordinate", "y coordinate", "z coordinate"};
    if (vl->count == vl->cap) {
        size_t cap = vl->cap ? 2 * vl->cap : 4096;
        if (cap > SIZE_MAX / (3 * sizeof(float)))
            return load_fail(t, ACCEL_ERR_NOMEM, "too many vertices");
        float *nv = realloc(vl->v, cap * 3 * sizeof(float));
        if (!nv) return load_fail(t, ACCEL_ERR_NOMEM, "out of memory for %zu vertices", cap);
        vl->v = nv;
        vl->cap = cap;
    }
    float *p = vl->v + 3 * vl->count;
    for (int k = 0; k < 3; k++) {
        skip_hspace(t);
        const char *q;
        float x;
        load_num_status st = load_parse_float(t->p, t->end, &q, &x);
        if (st == LOAD_NUM_NONE || !token_ends(t, q)) return load_fail_expected(t, axis[k]);
        if (st != LOAD_NUM_OK) {
            char tok[200];
            load_token_text(t->p, t->end, tok, sizeof tok);
            return load_fail(t, ACCEL_ERR_PARSE,
                             "%s '%s' is NaN or infinite (or beyond the float range)", axis[k], tok);
        }
        p[k] = x;
        t->p = q;
    }
    vl->count++;
    skip_statement(t);
    return 0;
}

/* One optional index after a '/' (texture or normal): syntax only. */
static int skip_slash_index(load_text *t, const char **q)
{
    if (*q < t->end && **q == '/') {
        ++*q;
        int64_t unused;
        const char *r;
        load_num_status st = load_parse_int(*q, t->end, &r, &unused);
        if (st == LOAD_NUM_RANGE) return -1;
        if (st == LOAD_NUM_OK) *q = r;
    }
    return 0;
}

static int parse_face(load_text *t, const vertex_list *vl, scene_builder *b)
{
    size_t face_line = t->line;
    size_t n = 0, first = 0, prev = 0;
    for (;;) {
        skip_hspace(t);
        if (load_at_eol(t)) break;
        const char *q;
        int64_t idx;
        load_num_status st = load_parse_int(t->p, t->end, &q, &idx);
        if (st == LOAD_NUM_NONE) return load_fail_expected(t, "vertex index");
        if (st == LOAD_NUM_OK && (skip_slash_index(t, &q) || skip_slash_index(t, &q)))
            st = LOAD_NUM_RANGE;
        if (!token_ends(t, q)) return load_fail_expected(t, "vertex index (v, v/vt, v//vn or v/vt/vn)");
        if (st == LOAD_NUM_RANGE) {
            char tok[200];
            load_token_text(t->p, t->end, tok, sizeof tok);
            return load_fail(t, ACCEL_ERR_PARSE, "face index '%s' is out of range", tok);
        }
        size_t i;
        if (idx > 0) {
            if ((uint64_t)idx > vl->count)
                return load_fail(t, ACCEL_ERR_PARSE, "face index %lld > vertex count %zu",
                                 (long long)idx, vl->count);
            i = (size_t)idx - 1;
        } else if (idx < 0) {
            if ((uint64_t)0 - (uint64_t)idx > vl->count)
                return load_fail(t, ACCEL_ERR_PARSE,
                                 "relative face index %lld reaches before the first vertex "
                                 "(%zu defined so far)",
                                 (long long)idx, vl->count);
            i = vl->count - (size_t)((uint64_t)0 - (uint64_t)idx);
        } else {
            return load_fail(t, ACCEL_ERR_PARSE, "face index 0 (OBJ indices start at 1)");
        }
        t->p = q;
        if (n == 0) first = i;
        if (n >= 2) {
            int rc = load_add_tri(b, vl->v, first, prev, i, t->err);
            if (rc) return load_prefix(t->err, rc, "%s:%zu", t->name, t->line);
        }
        prev = i;
        n++;
    }
    if (n < 3) {
        t->line = face_line;
        return load_fail(t, ACCEL_ERR_PARSE, "face with %zu vertices (at least 3 needed)", n);
    }
    skip_statement(t);
    return 0;
}

static int parse_obj(load_text *t, vertex_list *vl, scene_builder *b)
{
    while (t->p < t->end) {
        skip_hspace(t);
        if (load_at_eol(t)) {
            load_next_line(t);
            continue;
        }
        const char *k = t->p, *q = t->p;
        while (q < t->end && !token_ends(t, q)) q++;
        size_t len = (size_t)(q - k);
        int rc = 0;
        if (len == 1 && k[0] == 'v') {
            t->p = q;
            rc = parse_vertex(t, vl);
        } else if (len == 1 && k[0] == 'f') {
            t->p = q;
            rc = parse_face(t, vl, b);
        } else {
            skip_statement(t);
        }
        if (rc) return rc;
    }
    return 0;
}

int scene_parse_obj(const char *name, const char *data, size_t size, scene_builder *b,
                    accel_error *err)
{
    if (!data) data = "", size = 0;
    load_text t;
    int rc = load_text_begin(&t, name, data, size, size, '#', err);
    if (rc) return rc;
    size_t tri_start = b->tri_count;
    vertex_list vl = {0};
    rc = parse_obj(&t, &vl, b);
    free(vl.v);
    if (rc) b->tri_count = tri_start; /* a failed load adds nothing */
    return rc;
}

int scene_load_obj(const char *path, scene_builder *b, accel_error *err)
{
    return load_parse_file(path, scene_parse_obj, b, err);
}
