/*
 * test_loader.c - the OBJ, PLY and OFF loaders: the same mesh in every
 * format (text and binary PLY in both byte orders) gives the same
 * triangles in the same (fan) order, OBJ relative indices, line endings and
 * syntax variants, and binary PLY errors at the right byte offset.
 * Malformed text input is in test_loader_errors.c, number parsing in
 * test_loader_numbers.c, the shared scenes and fuzz inputs in
 * test_loader_files.c.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_loader.h"

parse_fn test_loader_parser(const char *name)
{
    const char *dot = strrchr(name, '.');
    if (dot && !strcmp(dot, ".obj")) return scene_parse_obj;
    if (dot && !strcmp(dot, ".ply")) return scene_parse_ply;
    return scene_parse_off;
}

/* ---- the reference mesh: two quads and a pentagon ------------------------ */

/* Coordinates chosen so that decimal text, float and double storage round
 * to the same floats. */
static const float quad_verts[6][3] = {
    {0.1f, -2.5f, 0.003f}, {1.0f, 0.0f, 0.0f},     {1.0f, 1.0f, 0.25f},
    {0.0f, 1.0f, -1e-3f},  {2.75f, 0.0f, 123.456f}, {2.0f, 1.0f, 0.5f},
};
static const char *const quad_vert_text[6] = {
    "0.1 -2.5 0.003", "1 0 0", "1.0 1.0 0.25", "0 1 -1e-3", "2.75 0 123.456", "2 1 .5",
};
static const int quad_faces[3][5] = {{0, 1, 2, 3, -1}, {1, 4, 5, 2, -1}, {3, 2, 5, 4, 0}};
/* FORMATS.md fan order: (v0,v1,v2), (v0,v2,v3), ... */
static const int quad_tris[7][3] = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2},
                                    {3, 2, 5}, {3, 5, 4}, {3, 4, 0}};

static int face_size(int f) { return quad_faces[f][4] < 0 ? 4 : 5; }

static int check_quads(const scene_builder *b, const char *what)
{
    if (b->tri_count != 7) {
        test_fail(__FILE__, __LINE__, "%s: %zu triangles, expected 7", what, b->tri_count);
        return 0;
    }
    for (int t = 0; t < 7; t++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++) {
                float got = b->tris[9 * t + 3 * c + k], want = quad_verts[quad_tris[t][c]][k];
                if (memcmp(&got, &want, sizeof got)) {
                    test_fail(__FILE__, __LINE__, "%s: triangle %d corner %d axis %d: %.9g != %.9g",
                              what, t, c, k, got, want);
                    return 0;
                }
            }
    return 1;
}

static void quads_obj(char *buf, size_t size)
{
    size_t n = (size_t)snprintf(buf, size, "# quads\nmtllib quads.mtl\no quads\n");
    for (int i = 0; i < 6; i++) {
        n += (size_t)snprintf(buf + n, size - n, "v %s\nvt 0.5 0.5\nvn 0 0 1\n", quad_vert_text[i]);
    }
    n += (size_t)snprintf(buf + n, size - n, "g group\nusemtl red\ns 1\n");
    static const char *const forms[4] = {"%d", "%d/%d", "%d//%d", "%d/%d/%d"};
    for (int f = 0; f < 3; f++) {
        n += (size_t)snprintf(buf + n, size - n, "f");
        for (int k = 0; k < face_size(f); k++) {
            int v = quad_faces[f][k] + 1;
            n += (size_t)snprintf(buf + n, size - n, " ");
            n += (size_t)snprintf(buf + n, size - n, forms[(f + k) % 4], v, v, v);
        }
        n += (size_t)snprintf(buf + n, size - n, " # face %d\n", f);
    }
}

static void quads_off(char *buf, size_t size)
{
    size_t n = (size_t)snprintf(buf, size, "OFF\n# a comment\n6 3 0\n");
    for (int i = 0; i < 6; i++) n += (size_t)snprintf(buf + n, size - n, "%s\n", quad_vert_text[i]);
    for (int f = 0; f < 3; f++) {
        n += (size_t)snprintf(buf + n, size - n, "%d", face_size(f));
        for (int k = 0; k < face_size(f); k++)
            n += (size_t)snprintf(buf + n, size - n, " %d", quad_faces[f][k]);
        n += (size_t)snprintf(buf + n, size - n, f == 1 ? " 255 0 0\n" : "\n"); /* a colour */
    }
}

static void quads_ply_ascii(char *buf, size_t size)
{
    size_t n = (size_t)snprintf(
        buf, size,
        "ply\nformat ascii 1.0\ncomment made by test_loader.c\nelement vertex 6\n"
        "property float x\nproperty uchar red\nproperty float y\nproperty double z\n"
        "property list uchar float extra\nelement edge 1\nproperty int a\nproperty int b\n"
        "element face 3\nproperty int flags\nproperty list uchar int vertex_indices\n"
        "element material 2\nproperty list ushort uchar name\nend_header\n");
    for (int i = 0; i < 6; i++) {
        float x, y, z;
        sscanf(quad_vert_text[i], "%f %f %f", &x, &y, &z);
        const char *t = quad_vert_text[i];
        const char *s1 = strchr(t, ' '), *s2 = strchr(s1 + 1, ' ');
        n += (size_t)snprintf(buf + n, size - n, "%.*s 255 %.*s %s 2 1.5 nan\n", (int)(s1 - t), t,
                              (int)(s2 - s1 - 1), s1 + 1, s2 + 1);
    }
    n += (size_t)snprintf(buf + n, size - n, "0 1\n");
    for (int f = 0; f < 3; f++) {
        n += (size_t)snprintf(buf + n, size - n, "7 %d", face_size(f));
        for (int k = 0; k < face_size(f); k++)
            n += (size_t)snprintf(buf + n, size - n, " %d", quad_faces[f][k]);
        n += (size_t)snprintf(buf + n, size - n, "\n");
    }
    n += (size_t)snprintf(buf + n, size - n, "3 65 66 67\n0\n");
}

/* A binary PLY writer for tests, in either byte order. */
typedef struct {
    char buf[4096];
    size_t n;
    int big;
} bin_writer;

static void put_bytes(bin_writer *w, const void *p, size_t n)
{
    memcpy(w->buf + w->n, p, n);
    w->n += n;
}
static void put_str(bin_writer *w, const char *s) { put_bytes(w, s, strlen(s)); }
static void put_uint(bin_writer *w, uint64_t v, int size)
{
    for (int i = 0; i < size; i++)
        w->buf[w->n++] = (char)(uint8_t)(v >> (8 * (w->big ? size - 1 - i : i)));
}
static void put_f32(bin_writer *w, float x)
{
    uint32_t u;
    memcpy(&u, &x, 4);
    put_uint(w, u, 4);
}
static void put_f64(bin_writer *w, double x)
{
    uint64_t u;
    memcpy(&u, &x, 8);
    put_uint(w, u, 8);
}

/* Little-endian: float coordinates, uchar/int faces. Big-endian: double
 * coordinates, ushort/uint16 faces named vertex_index. Both with properties
 * and elements to skip. */
static void quads_ply_binary(bin_writer *w, int big)
{
    w->n = 0;
    w->big = big;
    put_str(w, big ? "ply\r\nformat binary_big_endian 1.0\r\n" : "ply\nformat binary_little_endian 1.0\n");
    if (big)
        put_str(w, "element vertex 6\nproperty short s\nproperty double x\nproperty double y\n"
                   "property double z\nproperty list int8 int16 extra\n"
                   "element face 3\nproperty list ushort uint16 vertex_index\nproperty uint8 f\n"
                   "element tail 2\nproperty float a\nproperty float64 b\nend_header\r\n");
    else
        put_str(w, "element vertex 6\nproperty float x\nproperty uchar red\nproperty float y\n"
                   "property float z\nproperty list uchar float extra\nelement edge 1\n"
                   "property int a\nproperty int b\nelement face 3\nproperty int flags\n"
                   "property list uchar int vertex_indices\nelement none 4000000000\nend_header\n");
    for (int i = 0; i < 6; i++) {
        if (big) {
            put_uint(w, 0xFFFE, 2);
            for (int k = 0; k < 3; k++) {
                /* the double nearest each decimal, as a writer in double would store */
                const char *t = quad_vert_text[i];
                for (int s = 0; s < k; s++) t = strchr(t, ' ') + 1;
                put_f64(w, strtod(t, NULL));
            }
            put_uint(w, 2, 1);
            put_uint(w, 7, 2);
            put_uint(w, 9, 2);
        } else {
            put_f32(w, quad_verts[i][0]);
            put_uint(w, 200, 1);
            put_f32(w, quad_verts[i][1]);
            put_f32(w, quad_verts[i][2]);
            put_uint(w, 1, 1);
            put_f32(w, NAN); /* skipped: never looked at */
        }
    }
    if (!big) put_uint(w, 1, 4), put_uint(w, 2, 4);
    for (int f = 0; f < 3; f++) {
        if (!big) put_uint(w, 0xABCD, 4);
        put_uint(w, (uint64_t)face_size(f), big ? 2 : 1);
        for (int k = 0; k < face_size(f); k++) put_uint(w, (uint64_t)quad_faces[f][k], big ? 2 : 4);
        if (big) put_uint(w, 1, 1);
    }
    if (big)
        for (int i = 0; i < 2; i++) put_f32(w, 1.0f), put_f64(w, 2.0);
}

TEST(loader_roundtrip_all_formats)
{
    char text[4096];
    struct {
        const char *name;
        void (*make)(char *, size_t);
    } texts[] = {{"quads.obj", quads_obj}, {"quads.off", quads_off}, {"quads.ply", quads_ply_ascii}};
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        texts[i].make(text, sizeof text);
        scene_builder b = {0};
        accel_error err = {0};
        int rc = test_loader_parser(texts[i].name)(texts[i].name, text, strlen(text), &b, &err);
        CHECKF(rc == 0, "%s: %s", texts[i].name, err.msg);
        if (rc == 0) check_quads(&b, texts[i].name);
        scene_builder_free(&b);
    }
    for (int big = 0; big <= 1; big++) {
        bin_writer w;
        quads_ply_binary(&w, big);
        scene_builder b = {0};
        accel_error err = {0};
        int rc = scene_parse_ply("quads.ply", w.buf, w.n, &b, &err);
        CHECKF(rc == 0, "binary %s: %s", big ? "BE" : "LE", err.msg);
        if (rc == 0) check_quads(&b, big ? "binary big-endian PLY" : "binary little-endian PLY");
        scene_builder_free(&b);
    }
}

TEST(loader_files_and_dispatch)
{
    static const char *const files[] = {"tests/data/quads.obj", "tests/data/quads.off",
                                        "tests/data/quads.ply", "tests/data/quads_be.ply"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        FILE *f = fopen(files[i], "rb");
        if (!f) {
            test_note("skipped: %s absent (run from the repository root)", files[i]);
            continue;
        }
        fclose(f);
        accel_scene s;
        accel_error err = {0};
        int rc = scene_load_file(files[i], &s, &err);
        CHECKF(rc == 0, "%s: %s", files[i], err.msg);
        if (rc) continue;
        scene_builder b = {s.tris, s.tri_count, s.tri_count, NULL, 0, 0};
        check_quads(&b, files[i]);
        CHECK(s.degenerate_count == 0 && s.live_count == 7);
        scene_free(&s);
    }
    accel_scene s;
    accel_error err = {0};
    CHECK(scene_load_file("tests/data/no_such_file.off", &s, &err) == ACCEL_ERR_IO);
    CHECKF(strstr(err.msg, "tests/data/no_such_file.off: cannot open") != NULL, "%s", err.msg);
    /* A device is refused at once (a z.obj linked to /dev/zero was read
     * until memory ran out). */
    remove("build/test_zero.obj");
    if (symlink("/dev/zero", "build/test_zero.obj") == 0) {
        if (scene_load_file("build/test_zero.obj", &s, &err) == 0) {
            test_fail(__FILE__, __LINE__, "/dev/zero loaded as a scene");
            scene_free(&s);
        } else {
            CHECKF(strstr(err.msg, "build/test_zero.obj: not a regular file") != NULL, "%s", err.msg);
        }
        remove("build/test_zero.obj");
    }
    FILE *f = fopen("tests/data/bad_index.off", "rb");
    if (f) {
        fclose(f);
        CHECK(scene_load_file("tests/data/bad_index.off", &s, &err) == ACCEL_ERR_PARSE);
        CHECKF(strstr(err.msg, "tests/data/bad_index.off:9: face index 4 >= vertex count 4"),
               "%s", err.msg);
    }
}

/* Coordinates of triangle t of a builder as text, for compact checks. */
static void tri_text(const scene_builder *b, size_t t, char *buf, size_t size)
{
    const float *p = b->tris + 9 * t;
    snprintf(buf, size, "%g %g %g|%g %g %g|%g %g %g", p[0], p[1], p[2], p[3], p[4], p[5], p[6],
             p[7], p[8]);
}

TEST(loader_obj_relative_indices)
{
    /* -1 is the last vertex defined so far, wherever the face is */
    const char *obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                      "f -4 -3 -2 -1\n"
                      "v 5 5 5\n"
                      "f -1 -5 3/1 -3//2\n"
                      "f 1 2 -1\n";
    scene_builder b = {0};
    accel_error err = {0};
    int rc = scene_parse_obj("rel.obj", obj, strlen(obj), &b, &err);
    CHECKF(rc == 0, "%s", err.msg);
    CHECK(b.tri_count == 5);
    static const char *const want[5] = {
        "0 0 0|1 0 0|1 1 0", "0 0 0|1 1 0|0 1 0",     /* quad 1 2 3 4 */
        "5 5 5|0 0 0|1 1 0", "5 5 5|1 1 0|1 1 0",     /* 5 1 3 3: a degenerate kept */
        "0 0 0|1 0 0|5 5 5",
    };
    for (size_t t = 0; t < b.tri_count && t < 5; t++) {
        char got[128];
        tri_text(&b, t, got, sizeof got);
        CHECKF(!strcmp(got, want[t]), "triangle %zu: %s, expected %s", t, got, want[t]);
    }
    scene_builder_free(&b);
}

TEST(loader_fan_order_every_format)
{
    /* a hexagon: (0,1,2) (0,2,3) (0,3,4) (0,4,5), starting at its first corner 3 */
    const char *v = "0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 2 0\n-1 1 0\n";
    char buf[3][512];
    snprintf(buf[0], 512, "OFF\n6 1 0\n%s6 3 4 5 0 1 2\n", v);
    snprintf(buf[1], 512,
             "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar uint vertex_indices\n"
             "end_header\n%s6 3 4 5 0 1 2\n",
             v);
    char objv[256] = "";
    for (const char *p = v; *p;) {
        const char *nl = strchr(p, '\n');
        size_t l = strlen(objv);
        snprintf(objv + l, sizeof objv - l, "v %.*s\n", (int)(nl - p), p);
        p = nl + 1;
    }
    snprintf(buf[2], 512, "%sf 4 5 6 1 2 3\n", objv);
    const char *names[3] = {"hex.off", "hex.ply", "hex.obj"};
    static const int order[4][3] = {{3, 4, 5}, {3, 5, 0}, {3, 0, 1}, {3, 1, 2}};
    static const float coords[6][3] = {{0, 0, 0}, {1, 0, 0}, {2, 1, 0},
                                       {1, 2, 0}, {0, 2, 0}, {-1, 1, 0}};
    for (int i = 0; i < 3; i++) {
        scene_builder b = {0};
        accel_error err = {0};
        int rc = test_loader_parser(names[i])(names[i], buf[i], strlen(buf[i]), &b, &err);
        CHECKF(rc == 0 && b.tri_count == 4, "%s: rc %d, %zu triangles: %s", names[i], rc,
               b.tri_count, err.msg);
        for (size_t t = 0; rc == 0 && t < 4 && t < b.tri_count; t++)
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 3; k++)
                    CHECKF(b.tris[9 * t + 3 * (size_t)c + (size_t)k] == coords[order[t][c]][k],
                           "%s: triangle %zu corner %d is not vertex %d", names[i], t, c,
                           order[t][c]);
        scene_builder_free(&b);
    }
}

TEST(loader_line_endings_and_syntax)
{
    /* \r\n, \r and \n mixed; a UTF-8 byte order mark; an OBJ continuation;
     * comments at the ends of lines; counts on the OFF line; extra values */
    struct {
        const char *name, *text;
        size_t tris;
    } ok[] = {
        {"a.off", "\xEF\xBB\xBFOFF 3 1 0\r\n0 0 0\r1 0 0\n\n0 1 0 # c\r\n3 0 1 2 0.5 0.5 0.5 1\r", 1},
        {"b.off", "3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2", 1}, /* no header keyword, no final newline */
        {"c.off", "COFF\n3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 2 1 0\n", 1},
        {"d.obj", "v 0 0 0\r\nv 1 0 0 1\rv 0 1 0 1 0.5 0.5 0.5\nf 1 \\\n 2 \\\r\n3\r\nl 1 2\nvp 1\n", 1},
        {"e.obj", "v +1e0 -0 0#c\nv 1. 0 0\nv 0 1 .0\nf 1 2 3#c\nf\t3\t2\t1\n", 2},
        {"f.obj", "", 0},
        {"g.ply", "ply\r\nformat ascii 1.0\rcomment x\nobj_info y\nelement vertex 3\n"
                  "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                  "property list uchar int vertex_index\nend_header\r\n0 0 0\r1 0 0\r\n0 1 0\n"
                  "3 0 1 2\n", 1},
        {"h.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                  "property float z\nend_header\n", 0},
        {"i.off", "OFF\n3 1 0\n0 0 0\n0 0 0\n0 0 0\n3 0 0 0\n", 1}, /* degenerate: kept */
        /* an element without properties holds no data, however many it declares */
        {"j.ply", "ply\nformat ascii 1.0\nelement nothing 9000000000000000000\nelement vertex 3\n"
                  "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                  "property list uchar int vertex_indices\nelement nothing2 99999999999\n"
                  "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 1},
    };
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++) {
        scene_builder b = {0};
        accel_error err = {0};
        int rc = test_loader_parser(ok[i].name)(ok[i].name, ok[i].text, strlen(ok[i].text), &b, &err);
        CHECKF(rc == 0, "%s: %s", ok[i].name, err.msg);
        CHECKF(b.tri_count == ok[i].tris, "%s: %zu triangles, expected %zu", ok[i].name,
               b.tri_count, ok[i].tris);
        if (rc == 0 && b.tri_count) {
            char got[128];
            tri_text(&b, 0, got, sizeof got);
            if (ok[i].name[0] == 'a' || ok[i].name[0] == 'd' || ok[i].name[0] == 'g')
                CHECKF(!strcmp(got, "0 0 0|1 0 0|0 1 0"), "%s: %s", ok[i].name, got);
        }
        scene_builder_free(&b);
    }
}

/* ---- binary PLY errors: the message names the byte ------------------------ */

/* Offset of the first byte after "end_header\n" (or \r\n). */
static size_t data_offset(const bin_writer *w)
{
    const char *e = memmem(w->buf, w->n, "end_header", 10);
    size_t off = (size_t)(e - w->buf) + 10;
    if (w->buf[off] == '\r') off++;
    return off + 1;
}

TEST(loader_ply_binary_errors)
{
    static const char *const head =
        "ply\nformat binary_%s_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n";
    for (int big = 0; big <= 1; big++) {
        bin_writer w = {.big = big};
        char h[512];
        snprintf(h, sizeof h, head, big ? "big" : "little");
        struct {
            int face_n, bad_index, nan_vertex, cut;
            const char *want;
        } cases[] = {
            {3, 5, -1, 0, "face 0: face index 5 >= vertex count 3"},
            {3, -1, -1, 0, "face 0: negative face index -1"},
            {4, 0, -1, 2, "unexpected end of file in element 'face' (instance 0 of 1)"},
            {3, 0, 1, 0, "vertex 1: y coordinate is NaN"},
            {2, 0, -1, 0, "face 0 has 2 vertices"},
            {3, 0, -1, 3, "element 'face' declares 1 instances, but only 46 bytes"},
        };
        for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
            w.n = 0;
            put_str(&w, h);
            size_t data = data_offset(&w);
            for (int v = 0; v < 3; v++)
                for (int k = 0; k < 3; k++)
                    put_f32(&w, v == cases[c].nan_vertex && k == 1 ? NAN : (float)(v == k));
            size_t face_at = w.n;
            put_uint(&w, (uint64_t)cases[c].face_n, 1);
            for (int k = 0; k < cases[c].face_n; k++)
                put_uint(&w, (uint64_t)(k == 2 ? cases[c].bad_index : k), 4);
            if (cases[c].face_n == 2) put_uint(&w, 0, 8); /* enough bytes to pass the count check */
            w.n -= (size_t)cases[c].cut;
            size_t at = cases[c].bad_index != 0 ? face_at + 1 + 8
                      : cases[c].nan_vertex >= 0 ? data + 12 * (size_t)cases[c].nan_vertex + 4
                      : cases[c].face_n == 2     ? face_at
                      : cases[c].cut == 2        ? w.n
                                                 : 0;
            char want[256];
            if (cases[c].cut == 3)
                snprintf(want, sizeof want, "b.ply:7: %s", cases[c].want);
            else
                snprintf(want, sizeof want, "b.ply: byte %zu: %s", at, cases[c].want);
            scene_builder b = {0};
            accel_error err = {0};
            char *copy = malloc(w.n);
            memcpy(copy, w.buf, w.n);
            int rc = scene_parse_ply("b.ply", copy, w.n, &b, &err);
            CHECKF(rc != 0 && strstr(err.msg, want), "%s case %zu: rc %d '%s', expected '%s'",
                   big ? "BE" : "LE", c, rc, err.msg, want);
            CHECK(b.tri_count == 0);
            scene_builder_free(&b);
            free(copy);
        }
    }
}
