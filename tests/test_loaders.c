/*
 * test_loaders.c - the OBJ, PLY and OFF loaders: the same mesh in every
 * format gives the same triangles in the same (fan) order, OBJ relative
 * indices, exact decimal parsing (against strtof), every malformed input
 * rejected with the file name and the right line or byte offset in the
 * message, the shared scenes checked against an independent strtof-based
 * reader, and the fuzz regression inputs.
 */
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/load_common.h"
#include "scene/scene.h"
#include "test.h"

typedef int (*parse_fn)(const char *, const char *, size_t, scene_builder *, accel_error *);

static parse_fn parser_for(const char *name)
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
        "ply\nformat ascii 1.0\ncomment made by test_loaders.c\nelement vertex 6\n"
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
        int rc = parser_for(texts[i].name)(texts[i].name, text, strlen(text), &b, &err);
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
        int rc = parser_for(names[i])(names[i], buf[i], strlen(buf[i]), &b, &err);
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
        int rc = parser_for(ok[i].name)(ok[i].name, ok[i].text, strlen(ok[i].text), &b, &err);
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

/* ---- malformed input: the message names the file and the line ----------- */

typedef struct {
    const char *name;
    const char *data;
    size_t size; /* 0: strlen */
    const char *want; /* substring of the message */
} bad_case;

/* a literal with NUL bytes and its exact size */
#define BIN(s) s, sizeof(s) - 1

#define PLY_HEAD                                                                               \
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"            \
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
#define OFF_HEAD "OFF\n3 1 0\n0.0 0 0\n1 0 0\n0 1 0\n"
#define OBJ_HEAD "v 0 0 0\nv 1 0 0\nv 0 1 0\n"

static const bad_case bad_cases[] = {
    /* OFF */
    {"t.off", OFF_HEAD "3 0 1 3\n", 0, "t.off:6: face index 3 >= vertex count 3"},
    {"t.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", 0, "t.off:4: x coordinate 'nan' is NaN"},
    {"t.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 -inf\n3 0 1 2\n", 0, "t.off:5: z coordinate '-inf' is NaN or infinite"},
    {"t.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1e39 0\n3 0 1 2\n", 0, "t.off:5: y coordinate '1e39' is NaN or infinite"},
    {"t.off", OFF_HEAD "2 0 1\n", 0, "t.off:6: face with 2 vertices (at least 3 needed)"},
    {"t.off", OFF_HEAD "4 0 1 2\n", 0, "t.off:6: face of 4 vertices lists only 3 indices"},
    {"t.off", OFF_HEAD "3 0 -1 2\n", 0, "t.off:6: negative face index -1"},
    {"t.off", OFF_HEAD "3 0 1 2x\n", 0, "t.off:6: expected vertex index, found '2x'"},
    {"t.off", OFF_HEAD "3 0 1 99999999999999999999\n", 0, "t.off:6: vertex index '99999999999999999999' is out of range"},
    {"t.off", "OFF\n3 2 0\n0.0000000 0.0000000 0.0000000\n1 0 0\n0 1 0\n3 0 1 2\n", 0,
     "t.off:6: unexpected end of file: 1 of 2 faces read"},
    {"t.off", "OFF\n3 1 0\n0.00000000000 0 0\n1 0 0\n0 1", 0, "t.off:5: unexpected end of file: expected z coordinate"},
    {"t.off", "OFF\n2147483648 1 0\n", 0, "t.off:2: 2147483648 vertices and 1 faces declared, but only 0 bytes follow"},
    {"t.off", "OFF\n# a kilobyte would not hold them\n3 4294967296\n0 0 0\n", 0, "t.off:3: 3 vertices and 4294967296 faces declared"},
    {"t.off", "OFF\n-3 1 0\n", 0, "t.off:2: negative count"},
    {"t.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n", 0, "t.off:4: expected y coordinate, found 'zero'"},
    {"t.off", "OFF\n3 1 0\n0 0 0\n1.5.3 0 0\n0 1 0\n3 0 1 2\n", 0, "t.off:4: expected x coordinate, found '1.5.3'"},
    {"t.off", "OFF 3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", 0, "t.off:5: face index 5 >= vertex count 3"},
    {"t.off", "# c\nOFF\n# c2\n\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", 0, "t.off:9: face index 7"},
    {"t.off", "OFF\r\n3 1 0\r0 0 0\n1 0 0\r\n0 1 0\r3 0 1 9\n", 0, "t.off:6: face index 9 >= vertex count 3"},
    {"t.off", BIN("\xFF\xFEO\0F\0F\0\n\0"), "t.off: file is UTF-16 encoded"},
    {"t.off", BIN("O\0F\0F\0\n\0"), "t.off:1: NUL byte"},
    {"t.off", BIN("OFF\n3 1 0\n0 0 0\n1 0\0 0\n"), "t.off:4: NUL byte"},
    {"t.off", "ply\n", 0, "t.off:1: not an OFF file"},
    {"t.off", "4OFF\n", 0, "t.off:1: OFF variant '4OFF' is not supported"},
    {"t.off", "OFF BINARY\n", 0, "t.off:1: binary OFF is not supported"},
    {"t.off", "", 0, "t.off:1: empty file"},
    {"t.off", "OFF\n3\n", 0, "t.off:2: expected face count, found end of line"},
    {"t.off", "OFF\n3 1 0 junk\n", 0, "t.off:2: expected end of line after the counts, found 'junk'"},
    /* OBJ */
    {"t.obj", OBJ_HEAD "f 1 2 0\n", 0, "t.obj:4: face index 0 (OBJ indices start at 1)"},
    {"t.obj", OBJ_HEAD "f 1 2 4\n", 0, "t.obj:4: face index 4 > vertex count 3"},
    {"t.obj", OBJ_HEAD "f -4 -3 -2\n", 0, "t.obj:4: relative face index -4 reaches before the first vertex"},
    {"t.obj", OBJ_HEAD "\n\nf 1 2\n", 0, "t.obj:6: face with 2 vertices"},
    {"t.obj", OBJ_HEAD "f\n", 0, "t.obj:4: face with 0 vertices"},
    {"t.obj", "v 0 0 0\nv 1 0\n", 0, "t.obj:2: expected z coordinate, found end of line"},
    {"t.obj", "v 0 0 nan\n", 0, "t.obj:1: z coordinate 'nan' is NaN"},
    {"t.obj", "# x\nv 0 INF 0\n", 0, "t.obj:2: y coordinate 'INF' is NaN"},
    {"t.obj", "v 0 1e-400 1e400\n", 0, "t.obj:1: z coordinate '1e400' is NaN or infinite"},
    {"t.obj", OBJ_HEAD "f 1 2 x\n", 0, "t.obj:4: expected vertex index, found 'x'"},
    {"t.obj", OBJ_HEAD "f 1/1/1/1 2 3\n", 0, "t.obj:4: expected vertex index (v, v/vt, v//vn or v/vt/vn), found '1/1/1/1'"},
    {"t.obj", OBJ_HEAD "f 1 2 3 99999999999999999999\n", 0, "t.obj:4: face index '99999999999999999999' is out of range"},
    {"t.obj", "v 0 0 \\\n0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 3 4\n", 0, "t.obj:6: face index 4 > vertex count 3"},
    {"t.obj", "# c\r\nv 0 0 0\rv 1 0 0\nv 0 1 0\r\n\rf 1 2 5\n", 0, "t.obj:6: face index 5 > vertex count 3"},
    {"t.obj", BIN("\xFE\xFF\0v\0 \0\x31"), "t.obj: file is UTF-16 encoded"},
    {"t.obj", BIN("v 0 0 0\nv 1 0 0\nv\0 0"), "t.obj:3: NUL byte"},
    {"t.obj", "v 1.0e 0 0\n", 0, "t.obj:1: expected x coordinate, found '1.0e'"},
    {"t.obj", "v - 0 0\n", 0, "t.obj:1: expected x coordinate, found '-'"},
    {"t.obj", "v . 0 0\n", 0, "t.obj:1: expected x coordinate, found '.'"},
    {"t.obj", "v 0x10 0 0\n", 0, "t.obj:1: expected x coordinate, found '0x10'"},
    {"t.obj", "f 1 2 3\n", 0, "t.obj:1: face index 1 > vertex count 0"},
    /* PLY ascii: the header has 9 lines */
    {"t.ply", PLY_HEAD "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", 0, "t.ply:13: face index 3 >= vertex count 3"},
    {"t.ply", PLY_HEAD "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", 0, "t.ply:11: y coordinate 'nan' is NaN"},
    {"t.ply", PLY_HEAD "0 0 0\n1 a 0\n0 1 0\n3 0 1 2\n", 0, "t.ply:11: expected y coordinate, found 'a'"},
    {"t.ply", PLY_HEAD "0.0 0.0 0.0\n1 0 0\n0 1 0\n2 0 1\n", 0, "t.ply:13: face with 2 vertices"},
    {"t.ply", PLY_HEAD "0.0 0.0 0.0\n1 0 0\n0 1 0\n3 0 -1 2\n", 0, "t.ply:13: negative face index -1"},
    {"t.ply", PLY_HEAD "0.0 0.0 0.0\n1 0 0\n0 1 0\n4 0 1 2\n", 0,
     "t.ply:13: unexpected end of file in element 'face' (instance 0 of 1)"},
    {"t.ply", "ply\nformat ascii 1.0\nelement vertex 2147483648\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n0 0 0\n", 0,
     "t.ply:3: element 'vertex' declares 2147483648 instances, but only 6 bytes"},
    {"t.ply", "ply\nformat ascii 1.0\nelement vertex 0\n", 0, "t.ply:3: unexpected end of file in the header"},
    {"t.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty flot x\n", 0, "t.ply:4: unknown property type 'flot'"},
    {"t.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
              "property float z\nelement face 0\nproperty list uchar float vertex_indices\nend_header\n", 0,
     "t.ply:7: face property 'vertex_indices' must be a list of an integer type"},
    {"t.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n", 0,
     "t.ply:3: vertex element has no property 'z'"},
    {"t.ply", "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
              "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
              "3 0 1 2\n0 0 0\n0 0 0\n0 0 0\n", 0, "t.ply:3: face element without a vertex element before it"},
    {"t.ply", "plx\n", 0, "t.ply:1: not a PLY file"},
    {"t.ply", "ply\nelement vertex 0\nend_header\n", 0, "t.ply:3: no format line"},
    {"t.ply", "ply\nformat utf8 1.0\n", 0, "t.ply:2: unknown format"},
    {"t.ply", "ply\nformat ascii 1.0\nelement vertex -1\n", 0, "t.ply:3: element count is not a non-negative integer"},
    {"t.ply", "ply\nformat ascii 1.0\nproperty float x\n", 0, "t.ply:3: property before any element"},
    {"t.ply", "ply\nformat ascii 1.0\nbogus\n", 0, "t.ply:3: unknown header keyword 'bogus'"},
    {"t.ply", BIN("\xFF\xFEp\0l\0y\0"), "t.ply: file is UTF-16 encoded"},
    {"t.ply", BIN("ply\nfor\0mat"), "t.ply:2: NUL byte in the header"},
    {"t.ply", "ply\r\nformat ascii 1.0\relement vertex 3\nproperty float x\r\nproperty float y\r"
              "property float z\nelement face 1\r\nproperty list uchar int vertex_indices\r"
              "end_header\n0.0 0 0\r\n1 0 0\r0 1 0\n3 0 1 7\r\n", 0, "t.ply:13: face index 7 >= vertex count 3"},
    {"t.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nproperty list uchar int n\nend_header\n0 0 0 -2\n1 0 0 0\n0 1 0 0\n", 0,
     "t.ply:9: negative list count -2"},
};

TEST(loader_rejects_malformed_input)
{
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
        const bad_case *c = &bad_cases[i];
        size_t size = c->size ? c->size : strlen(c->data);
        /* a copy of exactly `size` bytes, so that ASan catches any read past the end */
        char *copy = malloc(size ? size : 1);
        if (!copy) continue;
        memcpy(copy, c->data, size);
        scene_builder b = {0};
        accel_error err = {0};
        /* a builder already holding a triangle: a failed load must leave it alone */
        scene_builder_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), &err);
        int rc = parser_for(c->name)(c->name, copy, size, &b, &err);
        CHECKF(rc != 0, "case %zu (%s) accepted; expected '%s'", i, c->name, c->want);
        CHECKF(rc == 0 || strstr(err.msg, c->want), "case %zu: message '%s', expected '%s'", i,
               err.msg, c->want);
        CHECKF(b.tri_count == 1, "case %zu: failed load left %zu triangles", i, b.tri_count);
        scene_builder_free(&b);
        free(copy);
    }
}

TEST(loader_error_prefix)
{
    /* errors from the scene builder get the file and line put before them */
    accel_error err = {0};
    accel_fail(&err, ACCEL_ERR_NOMEM, "out of memory growing a scene");
    CHECK(load_prefix(&err, ACCEL_ERR_NOMEM, "%s:%d", "a.obj", 3) == ACCEL_ERR_NOMEM);
    CHECKF(!strcmp(err.msg, "a.obj:3: out of memory growing a scene"), "%s", err.msg);
    memset(err.msg, 'x', sizeof err.msg - 1);
    err.msg[sizeof err.msg - 1] = 0;
    load_prefix(&err, 1, "%s: byte %d", "b.ply", 12);
    CHECK(!strncmp(err.msg, "b.ply: byte 12: xxx", 19) && strlen(err.msg) == sizeof err.msg - 1);
}

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

/* ---- exact decimal parsing ------------------------------------------------ */

static uint64_t rng_next(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static void check_float_text(const char *txt)
{
    const char *end = txt + strlen(txt), *q;
    float got = 0;
    load_num_status st = load_parse_float(txt, end, &q, &got);
    float want = strtof(txt, NULL);
    if (!isfinite(want)) {
        CHECKF(st == LOAD_NUM_NONFINITE, "'%s': status %d, strtof gives %g", txt, (int)st, want);
        return;
    }
    CHECKF(st == LOAD_NUM_OK && q == end && memcmp(&got, &want, sizeof got) == 0,
           "'%s': parsed %.9g (status %d), strtof %.9g", txt, got, (int)st, want);
}

TEST(loader_float_parsing_is_exact)
{
    /* hand-picked: midpoints between floats (ties to even), the double
     * rounding trap, subnormals, overflow, long digit strings */
    static const char *const cases[] = {
        "0", "-0", "1", "0.1", "-2.5", "3.4028234e38", "3.4028235e38", "3.40282357e38",
        "3.4028236e38", "1e39", "1.17549435e-38", "1e-45", "1.4e-45", "7e-46", "7.1e-46", "1e-46",
        "16777216", "16777217", "16777217.0000000001", "16777218", "16777219", "33554435",
        "1.00000005960464477539062500", "1.000000059604644775390625001",
        "1.0000000596046447753906249999999999999999999999999", "9007199254740993",
        "0.000000000000000000000000000000000000000000001", "123456789012345678901234567890",
        "4.5035996e15", "1e22", "1e23", "1e-22", "1e-23", "8.589973e9", "2.8823036e+17",
        "1.5e-7", "0.6666666666666666666666666666666666666666666666667", ".5", "5.", "+.5e+1",
        "1E5", "1e-0", "1.7014118346046923173168730371588410572800000000000000001e38",
        "3.402823466385288598117041834845169254400000000000000000000000000000000000000000000000000000000000000000000000000000000000000001e38",
        "1.000000178813934326171875", "1.0000001788139343261718749",
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) check_float_text(cases[i]);

    /* random decimals: 1-25 digits, a point anywhere, exponents from -50 to 40 */
    uint64_t s = 0x9E3779B97F4A7C15ull;
    char buf[96];
    for (int it = 0; it < 300000; it++) {
        size_t n = 0;
        if (rng_next(&s) & 1) buf[n++] = '-';
        int digits = 1 + (int)(rng_next(&s) % 25);
        if (it % 3 == 0) digits = 1 + (int)(rng_next(&s) % 8); /* the common short forms */
        int point = (int)(rng_next(&s) % (uint64_t)(digits + 1));
        for (int d = 0; d < digits; d++) {
            if (d == point) buf[n++] = '.';
            buf[n++] = (char)('0' + rng_next(&s) % 10);
        }
        if (rng_next(&s) % 3 == 0)
            n += (size_t)snprintf(buf + n, sizeof buf - n, "e%d", (int)(rng_next(&s) % 91) - 50);
        buf[n] = 0;
        check_float_text(buf);
    }
    /* every float's shortest round-trip text ("%.9g") reads back to itself */
    for (int it = 0; it < 100000; it++) {
        uint32_t u = (uint32_t)rng_next(&s);
        float x;
        memcpy(&x, &u, 4);
        if (!isfinite(x)) continue;
        snprintf(buf, sizeof buf, it & 1 ? "%.9g" : "%.8e", x);
        check_float_text(buf);
    }
    /* integers */
    static const struct {
        const char *text;
        load_num_status st;
        int64_t value;
        size_t used;
    } ints[] = {
        {"-9223372036854775808", LOAD_NUM_OK, INT64_MIN, 20},
        {"9223372036854775807", LOAD_NUM_OK, INT64_MAX, 19},
        {"9223372036854775808", LOAD_NUM_RANGE, 0, 19},
        {"99999999999999999999999", LOAD_NUM_RANGE, 0, 23},
        {"+42x", LOAD_NUM_OK, 42, 3},
        {"-0", LOAD_NUM_OK, 0, 2},
        {"-", LOAD_NUM_NONE, 0, 0},
        {"x1", LOAD_NUM_NONE, 0, 0},
    };
    for (size_t i = 0; i < sizeof ints / sizeof ints[0]; i++) {
        const char *q;
        int64_t v = 0;
        load_num_status st = load_parse_int(ints[i].text, ints[i].text + strlen(ints[i].text), &q, &v);
        CHECKF(st == ints[i].st && (size_t)(q - ints[i].text) == ints[i].used &&
                   (st != LOAD_NUM_OK || v == ints[i].value),
               "'%s': status %d, value %lld, used %zu", ints[i].text, (int)st, (long long)v,
               (size_t)(q - ints[i].text));
    }
}

/* ---- the shared scenes against an independent reader --------------------- */

/* A deliberately different OFF reader: stdio, strtol and strtof. Returns the
 * triangles of a triangle-only file (NULL when a face is not a triangle). */
static float *reference_off(const char *path, size_t *tri_count, long *nv_out, long *nf_out)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)size + 1);
    float *v = NULL, *tris = NULL;
    if (!text || fread(text, 1, (size_t)size, f) != (size_t)size) goto done;
    text[size] = 0;
    char *p = strstr(text, "OFF");
    if (!p) goto done;
    p += 3;
    long nv = strtol(p, &p, 10), nf = strtol(p, &p, 10);
    strtol(p, &p, 10);
    *nv_out = nv;
    *nf_out = nf;
    v = malloc((size_t)nv * 3 * sizeof *v);
    tris = malloc((size_t)nf * 9 * sizeof *tris);
    if (!v || !tris) goto fail;
    for (long i = 0; i < 3 * nv; i++) v[i] = strtof(p, &p);
    for (long i = 0; i < nf; i++) {
        if (strtol(p, &p, 10) != 3) goto fail;
        for (int c = 0; c < 3; c++) {
            long idx = strtol(p, &p, 10);
            if (idx < 0 || idx >= nv) goto fail;
            memcpy(tris + 9 * i + 3 * c, v + 3 * idx, 3 * sizeof *v);
        }
    }
    *tri_count = (size_t)nf;
    goto done;
fail:
    free(tris);
    tris = NULL;
done:
    free(v);
    free(text);
    fclose(f);
    return tris;
}

TEST(loader_shared_scenes)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_note("skipped: ../shared/scenes absent");
        return;
    }
    DIR *d = opendir(dir);
    if (!d) {
        test_note("skipped: cannot list %s", dir);
        return;
    }
    struct dirent *ent;
    int seen = 0;
    while ((ent = readdir(d))) {
        const char *dot = strrchr(ent->d_name, '.');
        if (!dot || (strcmp(dot, ".off") && strcmp(dot, ".obj") && strcmp(dot, ".ply"))) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, ent->d_name);
        accel_scene s;
        accel_error err = {0};
        double t0 = accel_now_ms();
        int rc = scene_load_file(path, &s, &err);
        double ms = accel_now_ms() - t0;
        CHECKF(rc == 0, "%s: %s", path, err.msg);
        if (rc) continue;
        seen++;
        test_note("%s: %u triangles, %u degenerate, loaded in %.1f ms", ent->d_name, s.tri_count,
                  s.degenerate_count, ms);
        if (!strcmp(ent->d_name, "bunny.off")) CHECK(s.tri_count == 75408);
        if (!strcmp(dot, ".off")) {
            size_t n = 0;
            long nv = 0, nf = 0;
            float *ref = reference_off(path, &n, &nv, &nf);
            if (!ref) {
                test_note("%s: not a triangle-only OFF, header counts not compared", ent->d_name);
            } else {
                /* every face a triangle: the header's face count is the triangle count */
                CHECKF(s.tri_count == (uint32_t)nf, "%s: %u triangles, header says %ld faces",
                       ent->d_name, s.tri_count, nf);
                CHECKF(n == s.tri_count && memcmp(ref, s.tris, n * 9 * sizeof(float)) == 0,
                       "%s: triangles differ from the strtof reader", ent->d_name);
                free(ref);
            }
        }
        scene_free(&s);
    }
    closedir(d);
    CHECK(seen > 0);
}

/* ---- fuzz regressions ---------------------------------------------------- */

/* Runs every file of dir named obj-*, ply-* or off-* (or, with `format`, every
 * file) through its parser: it must load or fail with a message naming the
 * file; files whose name ends in "-ok" (and seed corpus files) must load. */
static int run_inputs(const char *dir, const char *format, int must_load)
{
    DIR *d = opendir(dir);
    if (!d) return -1;
    struct dirent *ent;
    int count = 0;
    while ((ent = readdir(d))) {
        const char *fmt = format;
        if (!fmt) {
            if (strlen(ent->d_name) < 4 || ent->d_name[3] != '-') continue;
            fmt = ent->d_name;
        }
        parse_fn parse = !strncmp(fmt, "obj", 3)   ? scene_parse_obj
                         : !strncmp(fmt, "ply", 3) ? scene_parse_ply
                         : !strncmp(fmt, "off", 3) ? scene_parse_off
                                                   : NULL;
        if (!parse || ent->d_name[0] == '.') continue;
        size_t len = strlen(ent->d_name);
        int load = must_load || (len > 3 && !strcmp(ent->d_name + len - 3, "-ok"));
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, ent->d_name);
        char *data;
        size_t size;
        accel_error err = {0};
        if (load_read_file(path, &data, &size, &err)) {
            CHECKF(0, "%s", err.msg);
            continue;
        }
        char *copy = malloc(size ? size : 1); /* exact size: reads past it are caught */
        if (!copy) {
            free(data);
            continue;
        }
        memcpy(copy, data, size);
        scene_builder b = {0};
        int rc = parse(ent->d_name, copy, size, &b, &err);
        CHECKF(rc == 0 || (!load && strstr(err.msg, ent->d_name) == err.msg), "%s: message '%s'",
               path, err.msg);
        CHECKF(rc == 0 || b.tri_count == 0, "%s: a failed load left triangles", path);
        scene_builder_free(&b);
        free(copy);
        free(data);
        count++;
    }
    closedir(d);
    return count;
}

/* tests/data/fuzz_regress/ keeps every input that made a fuzz target fail
 * (none so far) and, from the fuzzers' corpora, the smallest input reaching
 * each distinct loader outcome; tests/fuzz/corpus/ holds the seeds, all valid.
 * Under `make sanitize` this also checks them for memory errors and leaks. */
TEST(loader_fuzz_regressions)
{
    int n = run_inputs("tests/data/fuzz_regress", NULL, 0);
    if (n < 0) {
        test_note("skipped: tests/data/fuzz_regress absent (run from the repository root)");
        return;
    }
    CHECK(n > 0);
    int seeds = 0;
    static const char *const formats[3] = {"obj", "ply", "off"};
    for (int i = 0; i < 3; i++) {
        char dir[64];
        snprintf(dir, sizeof dir, "tests/fuzz/corpus/%s", formats[i]);
        int k = run_inputs(dir, formats[i], 1);
        CHECKF(k > 0, "%s: no seed inputs", dir);
        seeds += k > 0 ? k : 0;
    }
    test_note("%d fuzz regression inputs, %d seeds", n, seeds);
}
