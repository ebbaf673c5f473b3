/*
 * test_loader_errors.c - every malformed OBJ, PLY and OFF input rejected
 * with the file name and the right line in the message, leaving the
 * builder as it was; the prefix put before errors from the scene builder.
 */
#include <stdlib.h>
#include <string.h>

#include "scene/load_common.h"
#include "test_loader.h"

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
    {"t.off", OFF_HEAD "3 0 1 2\n3 2 1 0\n3 0 1 7\n", 0,
     "t.off:7: data after the 1 faces the header declares"},
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
    /* a few bytes short of the counts' minimum: parsed, so the line is named */
    {"t.off", OFF_HEAD "0\n", 0, "t.off:6: face with 0 vertices (at least 3 needed)"},
    {"t.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1\n3 0 1 2\n", 0, "t.off:5: expected z coordinate, found end of line"},
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
    {"t.ply", PLY_HEAD "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n", 0,
     "t.ply:14: data after the declared elements"},
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
        int rc = test_loader_parser(c->name)(c->name, copy, size, &b, &err);
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
