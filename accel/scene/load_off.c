/*
 * load_off.c - the OFF mesh format (Geomview "Object File Format").
 *
 *   OFF                      header keyword (COFF, NOFF, CNOFF, STOFF... too:
 *   nv nf [ne]               their extra per-vertex values are ignored);
 *   x y z                    the counts may follow OFF on the same line
 *   ... (nv vertex lines)
 *   n i0 i1 ... i(n-1) [r g b [a]]   faces of any size, 0-based indices,
 *   ... (nf face lines)              colour values after the indices ignored
 *
 * '#' starts a comment anywhere; blank lines are skipped. As Geomview allows,
 * the header keyword may be left out. Binary OFF and the n-dimensional or
 * homogeneous variants (nOFF, 4OFF) are rejected with a message.
 *
 * Each vertex and each face is one line. Faces are fan-triangulated in file
 * order (FORMATS.md): (i0,i1,i2), (i0,i2,i3), ...
 */
#include <stdlib.h>
#include <string.h>

#include "scene/load_common.h"
#include "scene/scene.h"

/* Shortest possible vertex line "0 0 0\n" and face line "3 0 0 0\n" (bytes):
 * the bound that rejects absurd declared counts before allocating. */
#define OFF_MIN_VERTEX_BYTES 6
#define OFF_MIN_FACE_BYTES 8

/* OFF, or a variant whose only difference is extra per-vertex values:
 * [ST][C][N]OFF. */
static int plain_variant(const char *k, size_t len)
{
    if (len >= 2 && k[0] == 'S' && k[1] == 'T') k += 2, len -= 2;
    if (len >= 1 && k[0] == 'C') k++, len--;
    if (len >= 1 && k[0] == 'N') k++, len--;
    return len == 3 && memcmp(k, "OFF", 3) == 0;
}

static int parse_header(load_text *t)
{
    load_skip_space(t);
    if (t->p >= t->end) return load_fail(t, ACCEL_ERR_PARSE, "empty file (no OFF header)");
    const char *k = t->p, *q = t->p;
    int digits = 1;
    for (; q < t->end && !load_is_delim(t, *q); q++) digits &= (unsigned)(*q - '0') < 10u;
    if (digits) return 0; /* no keyword: the counts come first */
    size_t len = (size_t)(q - k);
    if (!plain_variant(k, len)) {
        char tok[200];
        load_token_text(k, t->end, tok, sizeof tok);
        if (len >= 3 && memcmp(q - 3, "OFF", 3) == 0)
            return load_fail(t, ACCEL_ERR_PARSE,
                             "OFF variant '%s' is not supported (only OFF and its C, N, ST "
                             "forms with 3D vertices)",
                             tok);
        return load_fail(t, ACCEL_ERR_PARSE, "not an OFF file: expected the header 'OFF', found '%s'",
                         tok);
    }
    t->p = q;
    load_skip_hspace(t);
    if (t->end - t->p >= 6 && memcmp(t->p, "BINARY", 6) == 0)
        return load_fail(t, ACCEL_ERR_PARSE, "binary OFF is not supported");
    return 0;
}

static int parse_off(load_text *t, scene_builder *b, float **verts_out)
{
    int rc = parse_header(t);
    if (rc) return rc;
    load_skip_space(t);
    int64_t nv, nf, ne;
    if ((rc = load_int_token(t, "vertex count", &nv))) return rc;
    load_skip_hspace(t);
    if ((rc = load_int_token(t, "face count", &nf))) return rc;
    load_skip_hspace(t);
    if (!load_at_eol(t)) {
        if ((rc = load_int_token(t, "edge count", &ne))) return rc;
        load_skip_hspace(t);
        if (!load_at_eol(t)) return load_fail_expected(t, "end of line after the counts");
    }
    if (nv < 0 || nf < 0)
        return load_fail(t, ACCEL_ERR_PARSE, "negative count (%lld vertices, %lld faces)",
                         (long long)nv, (long long)nf);
    size_t counts_line = t->line;
    load_next_line(t);
    /* Bound the declared counts by what the rest of the file could hold
     * (the last line may lack its line end) before allocating anything. */
    uint64_t left = (uint64_t)(t->end - t->p) + 1;
    /* Twice the bytes left, plus a little: a file a few bytes short of its
     * counts' minimum (a short line "0" where a face belongs) is parsed, so
     * that the error names that line; only counts far beyond the file are
     * refused here, and the allocation stays within a few times its size. */
    uint64_t room = 2 * left + 64;
    if ((uint64_t)nv > left || (uint64_t)nf > left ||
        (uint64_t)nv * OFF_MIN_VERTEX_BYTES + (uint64_t)nf * OFF_MIN_FACE_BYTES > room) {
        t->line = counts_line;
        return load_fail(t, ACCEL_ERR_RANGE,
                         "%lld vertices and %lld faces declared, but only %zu bytes follow "
                         "(truncated file or corrupt counts)",
                         (long long)nv, (long long)nf, (size_t)(t->end - t->p));
    }
    float *v = malloc(nv ? (size_t)nv * 3 * sizeof *v : 1);
    if (!v) {
        t->line = counts_line;
        return load_fail(t, ACCEL_ERR_NOMEM, "out of memory for %lld vertices", (long long)nv);
    }
    *verts_out = v;
    if ((rc = scene_builder_reserve_tris(b, (size_t)nf, t->err)))
        return load_prefix(t->err, rc, "%s:%zu", t->name, counts_line);

    static const char *const axis[3] = {"x coordinate", "y coordinate", "z coordinate"};
    for (int64_t i = 0; i < nv; i++) {
        load_skip_space(t);
        if (t->p >= t->end)
            return load_fail_eof(t, ": %lld of %lld vertices read", (long long)i, (long long)nv);
        for (int k = 0; k < 3; k++) {
            if (k) load_skip_hspace(t);
            if ((rc = load_float_token(t, axis[k], &v[3 * i + k]))) return rc;
        }
        load_next_line(t); /* colours, normals, texture coordinates of the variants */
    }
    for (int64_t f = 0; f < nf; f++) {
        load_skip_space(t);
        if (t->p >= t->end)
            return load_fail_eof(t, ": %lld of %lld faces read", (long long)f, (long long)nf);
        int64_t n;
        if ((rc = load_int_token(t, "face vertex count", &n))) return rc;
        if (n < 3)
            return load_fail(t, ACCEL_ERR_PARSE, "face with %lld vertices (at least 3 needed)",
                             (long long)n);
        size_t first = 0, prev = 0;
        for (int64_t k = 0; k < n; k++) {
            load_skip_hspace(t);
            if (load_at_eol(t))
                return load_fail(t, ACCEL_ERR_PARSE, "face of %lld vertices lists only %lld indices",
                                 (long long)n, (long long)k);
            int64_t idx;
            if ((rc = load_int_token(t, "vertex index", &idx))) return rc;
            if (idx < 0)
                return load_fail(t, ACCEL_ERR_PARSE, "negative face index %lld", (long long)idx);
            if (idx >= nv)
                return load_fail(t, ACCEL_ERR_PARSE, "face index %lld >= vertex count %lld",
                                 (long long)idx, (long long)nv);
            size_t i = (size_t)idx;
            if (k == 0) first = i;
            if (k >= 2 && (rc = load_add_tri(b, v, first, prev, i, t->err)))
                return load_prefix(t->err, rc, "%s:%zu", t->name, t->line);
            prev = i;
        }
        load_next_line(t); /* optional face colour */
    }
    /* Faces past the declared count would be dropped without a word (a
     * header that undercounts them): refused, with the line. */
    load_skip_space(t);
    if (t->p < t->end)
        return load_fail(t, ACCEL_ERR_PARSE,
                         "data after the %lld faces the header declares (is the face count "
                         "too small?)",
                         (long long)nf);
    return 0;
}

int scene_parse_off(const char *name, const char *data, size_t size, scene_builder *b,
                    accel_error *err)
{
    if (!data) data = "", size = 0;
    load_text t;
    int rc = load_text_begin(&t, name, data, size, size, '#', err);
    if (rc) return rc;
    size_t tri_start = b->tri_count;
    float *verts = NULL;
    rc = parse_off(&t, b, &verts);
    free(verts);
    if (rc) b->tri_count = tri_start; /* a failed load adds nothing */
    return rc;
}

int scene_load_off(const char *path, scene_builder *b, accel_error *err)
{
    return load_parse_file(path, scene_parse_off, b, err);
}
