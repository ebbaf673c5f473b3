/*
 * test_scene_file.c - the `.scene` reader and the flattener (FORMATS.md):
 * primitive ids (instances in order, each its mesh's primitives in order),
 * transforms against hand-computed points, the kept description (matrix,
 * inverse, base id, bounds), files relative to the scene's folder, and
 * every malformed input rejected with the exact file:line message.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scene/compose.h"
#include "scene/scene.h"
#include "support.h"

/* ---- meshes served by name, so the tests know every vertex ---------------- */

/* "tri": one triangle (1,0,0) (0,1,0) (0,0,1); "pair": two triangles;
 * "ball": one sphere; "huge": 2^31 primitives claimed, nothing allocated
 * (only the count is read before the limit check). */
static int test_mesh(void *ctx, const char *source, const char *dir, accel_scene *mesh,
                     accel_error *err)
{
    (void)ctx;
    (void)dir;
    scene_builder b = {0};
    int rc = 0;
    if (!strcmp(source, "tri")) {
        rc = scene_builder_add_tri(&b, v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1), err);
    } else if (!strcmp(source, "pair")) {
        rc = scene_builder_add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), err);
        if (rc == 0) rc = scene_builder_add_tri(&b, v3(1, 0, 0), v3(1, 1, 0), v3(0, 1, 0), err);
    } else if (!strcmp(source, "ball")) {
        rc = scene_builder_add_sphere(&b, v3(0, 0, 0), 1.0f, err);
    } else if (!strcmp(source, "huge")) {
        memset(mesh, 0, sizeof *mesh);
        snprintf(mesh->name, sizeof mesh->name, "huge");
        mesh->prim_count = 0x80000000u;
        return 0;
    } else {
        return accel_fail(err, ACCEL_ERR_IO, "%s: no such test mesh", source);
    }
    if (rc == 0) rc = scene_finish(&b, source, mesh, err);
    scene_builder_free(&b);
    return rc;
}

static int parse(const char *text, accel_scene *s, accel_error *err, uint64_t max_prims)
{
    scene_file_options o = {max_prims, test_mesh, NULL};
    return scene_parse_scene("t.scene", "", text, strlen(text), &o, s, err);
}

static int same_vec(const float *got, float x, float y, float z)
{
    return got[0] == x && got[1] == y && got[2] == z;
}

/* ---- ids and transforms ---------------------------------------------------- */

TEST(scene_file_ids)
{
    accel_scene s;
    accel_error err = {0};
    const char *text = "mesh p pair\nmesh t tri\nmesh unused tri\n"
                       "instance t translate 10 0 0\ninstance p\ninstance t\ninstance p scale 2\n";
    if (parse(text, &s, &err, 0)) {
        test_fail(__FILE__, __LINE__, "parse: %s", err.msg);
        return;
    }
    CHECK(s.prim_count == 6 && s.tri_count == 6 && s.instances);
    const accel_instances *set = s.instances;
    CHECK(set->mesh_count == 3 && set->instance_count == 4);
    static const uint32_t base[4] = {0, 1, 3, 4}, mesh[4] = {1, 0, 1, 0};
    for (uint32_t k = 0; k < 4 && k < set->instance_count; k++) {
        CHECKF(set->instances[k].base == base[k], "instance %u base %u", k, set->instances[k].base);
        CHECKF(set->instances[k].mesh == mesh[k], "instance %u mesh %u", k, set->instances[k].mesh);
    }
    /* id 0: tri moved by 10; ids 1-2: pair as is; 3: tri; 4-5: pair doubled. */
    CHECK(same_vec(s.tris + 0, 11, 0, 0) && same_vec(s.tris + 6, 10, 0, 1));
    CHECK(same_vec(s.tris + 9, 0, 0, 0) && same_vec(s.tris + 18 + 3, 1, 1, 0));
    CHECK(same_vec(s.tris + 27, 1, 0, 0));
    CHECK(same_vec(s.tris + 36 + 3, 2, 0, 0) && same_vec(s.tris + 45 + 3, 2, 2, 0));
    /* Every flattened triangle is accel_xform_vertex of its mesh's triangle. */
    for (uint32_t k = 0; k < set->instance_count; k++) {
        const accel_instance *in = &set->instances[k];
        const accel_scene *m = &set->meshes[in->mesh];
        for (uint32_t q = 0; q < m->tri_count; q++)
            for (int c = 0; c < 3; c++) {
                float w[3];
                accel_xform_vertex(in->xform, m->tris + 9 * q + 3 * c, w);
                CHECK(!memcmp(w, s.tris + 9 * ((size_t)in->base + q) + 3 * c, sizeof w));
            }
    }
    box3 b = set->instances[3].bounds;
    CHECK(b.min.x == 0 && b.min.y == 0 && b.max.x == 2 && b.max.y == 2 && b.max.z == 0);
    scene_free(&s);
}

/* The first vertex (1,0,0), second (0,1,0), third (0,0,1) of "tri" after a
 * transform written on an instance line. */
static void check_xform(const char *xf, const float want[9], float tol)
{
    char text[512];
    snprintf(text, sizeof text, "mesh t tri\ninstance t %s\n", xf);
    accel_scene s;
    accel_error err = {0};
    if (parse(text, &s, &err, 0)) {
        test_fail(__FILE__, __LINE__, "'%s': %s", xf, err.msg);
        return;
    }
    for (int i = 0; i < 9; i++)
        CHECKF(fabsf(s.tris[i] - want[i]) <= tol, "'%s': coordinate %d is %.9g, expected %.9g", xf,
               i, s.tris[i], want[i]);
    /* The kept inverse maps every world vertex back to the mesh. */
    const accel_instance *in = &s.instances->instances[0];
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) {
            const double *row = in->inverse + 4 * r;
            double o = row[0] * s.tris[3 * c] + row[1] * s.tris[3 * c + 1] +
                       row[2] * s.tris[3 * c + 2] + row[3];
            double want_o = (r == c) ? 1.0 : 0.0;
            CHECKF(fabs(o - want_o) <= 1e-6 * (1 + fabs(in->xform[3]) + fabs(in->xform[7])),
                   "'%s': inverse of vertex %d axis %d gives %.9g", xf, c, r, o);
        }
    scene_free(&s);
}

TEST(scene_file_transforms)
{
    const float s2 = 0.70710678f;
    static const float id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    check_xform("", id, 0);
    check_xform("translate 1 2 3", (const float[9]){2, 2, 3, 1, 3, 3, 1, 2, 4}, 0);
    check_xform("scale 2", (const float[9]){2, 0, 0, 0, 2, 0, 0, 0, 2}, 0);
    check_xform("scale 1 -2 3", (const float[9]){1, 0, 0, 0, -2, 0, 0, 0, 3}, 0);
    /* Left to right: translate first, then scale (the offset is scaled). */
    check_xform("translate 1 0 0 scale 2", (const float[9]){4, 0, 0, 2, 2, 0, 2, 0, 2}, 0);
    check_xform("scale 2 translate 1 0 0", (const float[9]){3, 0, 0, 1, 2, 0, 1, 0, 2}, 0);
    /* Right-handed quarter turns, exact: about z, x -> y; about x, y -> z. */
    check_xform("rotate 0 0 1 90", (const float[9]){0, 1, 0, -1, 0, 0, 0, 0, 1}, 0);
    check_xform("rotate 2 0 0 90", (const float[9]){1, 0, 0, 0, 0, 1, 0, -1, 0}, 0);
    check_xform("rotate 0 1 0 -270", (const float[9]){0, 0, -1, 0, 1, 0, 1, 0, 0}, 0);
    check_xform("rotate 0 0 1 45", (const float[9]){s2, s2, 0, -s2, s2, 0, 0, 0, 1}, 1e-7f);
    /* About the diagonal by 120 degrees: the axes cycle x -> y -> z. */
    check_xform("rotate 1 1 1 120", (const float[9]){0, 1, 0, 0, 0, 1, 1, 0, 0}, 1e-7f);
    check_xform("rotate 0 0 1 90 translate 5 0 0", (const float[9]){5, 1, 0, 4, 0, 0, 5, 0, 1}, 0);
    check_xform("matrix 0 1 0 7  1 0 0 0  0 0 -1 1", (const float[9]){7, 1, 1, 8, 0, 1, 7, 0, 0}, 0);
    check_xform("translate 1e5 0 0", (const float[9]){100001, 0, 0, 1e5f, 1, 0, 1e5f, 0, 1}, 0);
}

/* ---- files ----------------------------------------------------------------- */

TEST(scene_file_from_disk)
{
    char dir[64];
    if (!test_temp_dir("scene", dir, sizeof dir)) return;
    char sub[600], mesh[700], scene[700];
    snprintf(sub, sizeof sub, "%s/meshes", dir);
    mkdir(sub, 0700);
    snprintf(mesh, sizeof mesh, "%s/quad.off", sub);
    snprintf(scene, sizeof scene, "%s/two.scene", dir);
    test_write_file(mesh, "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
    test_write_file(scene, "mesh q meshes/quad.off   # relative to the scene's folder\r\n"
                           "mesh c cube:n=1\r\n"
                           "instance q translate 0 0 -1\r\ninstance c scale 0.5\r\ninstance q\r\n"
                           "camera eye 0 0 5 look 0 0 0 fov 30\r\nlight 1 2 3\r\n");
    accel_scene s;
    accel_error err = {0};
    if (test_make_scene(scene, &s)) {
        CHECK(s.prim_count == 2 + 12 + 2 && s.instances && s.instances->instance_count == 3);
        CHECK(same_vec(s.tris + 6, 1, 1, -1));          /* quad: (0,1,2), z moved */
        CHECK(same_vec(s.tris + 9 * 14 + 6, 1, 1, 0));   /* third instance, first triangle */
        CHECK(!strcmp(s.name, "two.scene"));
        CHECK(s.camera.fov_deg == 30.0f && s.camera.eye.z == 5.0f && s.light.y == 2.0f);
        scene_free(&s);
    }
    /* A missing mesh file: the scene's line, then the loader's message. */
    test_write_file(scene, "\nmesh gone meshes/missing.ply\n");
    int rc = scene_create(scene, &s, &err);
    char want[900];
    snprintf(want, sizeof want, "%s:2: mesh gone: %s/meshes/missing.ply: cannot open", scene, dir);
    CHECKF(rc == ACCEL_ERR_IO && !strncmp(err.msg, want, strlen(want)), "got '%s'", err.msg);
    /* A misspelt built-in scene: the file, the line and the unknown scene
     * with the names it could be, not "unknown file format '.'". */
    static const char *const typos[] = {"sofa:tris=300", "sopu", "cube:n=0.5x"};
    for (int i = 0; i < 3; i++) {
        char text[128];
        snprintf(text, sizeof text, "mesh c cube:n=1\nmesh a %s\ninstance a\n", typos[i]);
        test_write_file(scene, text);
        rc = scene_create(scene, &s, &err);
        if (i == 2) { /* a known scene with a bad value: the parameter's message */
            CHECKF(rc != 0 && strstr(err.msg, ":2: mesh a: ") && !strstr(err.msg, "file format"),
                   "got '%s'", err.msg);
            continue;
        }
        snprintf(want, sizeof want, "%s:2: mesh a: unknown scene '%s': give a file", scene, typos[i]);
        CHECKF(rc == ACCEL_ERR_SPEC && !strncmp(err.msg, want, strlen(want)) &&
               strstr(err.msg, "soup"), "%s: got '%s'", typos[i], err.msg);
    }
    /* A file without an extension says so. */
    test_write_file(scene, "mesh a meshes/quad\n");
    rc = scene_create(scene, &s, &err);
    CHECKF(rc == ACCEL_ERR_SPEC && strstr(err.msg, ":1: mesh a: ") &&
           strstr(err.msg, "meshes/quad: no file extension (accepted: .obj"), "got '%s'", err.msg);
    test_remove_dir(dir);
}

/* ---- bad input --------------------------------------------------------------- */

static void check_error(const char *text, int code, const char *want, uint64_t max_prims)
{
    accel_scene s;
    accel_error err = {0};
    int rc = parse(text, &s, &err, max_prims);
    if (rc == 0) {
        test_fail(__FILE__, __LINE__, "accepted: %s", text);
        scene_free(&s);
        return;
    }
    CHECKF(!strncmp(err.msg, want, strlen(want)) && rc == code,
           "input '%s':\n      got (%d) '%s'\n expected (%d) '%s'", text, rc, err.msg, code, want);
    CHECK(s.tris == NULL && s.instances == NULL && s.prim_count == 0);
}

TEST(scene_file_errors)
{
    const int P = ACCEL_ERR_PARSE, R = ACCEL_ERR_RANGE;
    check_error("mesh\n", P, "t.scene:1: expected a mesh name, found end of line", 0);
    check_error("mesh a\n", P, "t.scene:1: expected a mesh source", 0);
    check_error("mesh a tri extra\n", P, "t.scene:1: unexpected 'extra' after the mesh source", 0);
    check_error("mesh a tri\n\nmesh a pair\n", P, "t.scene:3: mesh 'a' is already declared at line 1",
                0);
    check_error("mesh a nothing\n", ACCEL_ERR_IO, "t.scene:1: mesh a: nothing: no such test mesh", 0);
    check_error("mesh b ball\n", R, "t.scene:1: mesh b: ball holds 1 spheres", 0);
    check_error("mesh a tri\ninstance b\n", P, "t.scene:2: unknown mesh 'b'", 0);
    check_error("instance\n", P, "t.scene:1: expected the name of a mesh to place", 0);
    check_error("mesh a tri\ninstance a scale 0\n", R,
                "t.scene:2: instance a: the transform is singular (determinant 0)", 0);
    check_error("mesh a tri\ninstance a scale 1 0 1\n", R, "t.scene:2: instance a: the transform is singular", 0);
    check_error("mesh a tri\ninstance a matrix 1 0 0 0 0 1 0 0 1 1 0 0\n", R,
                "t.scene:2: instance a: the transform is singular", 0);
    check_error("mesh a tri\ninstance a scale 1e200 scale 1e200\n", R,
                "t.scene:2: instance a: the transform has a non-finite entry", 0);
    check_error("mesh a tri\ninstance a scale 1e39\n", R,
                "t.scene:2: instance a: the transform moves vertices of tri beyond the float range",
                0);
    check_error("mesh a tri\ninstance a scale nan\n", P, "t.scene:2: a scale factor is not a finite number", 0);
    check_error("mesh a tri\ninstance a translate -inf 0 0\n", P,
                "t.scene:2: a translate offset (3 numbers) is not a finite number", 0);
    check_error("mesh a tri\ninstance a translate 1e999 0 0\n", R,
                "t.scene:2: a translate offset (3 numbers) 1e999 is out of range", 0);
    check_error("mesh a tri\ninstance a translate 1 2\n", P,
                "t.scene:2: expected a translate offset (3 numbers), found end of line", 0);
    check_error("mesh a tri\ninstance a translate 1 2 x\n", P,
                "t.scene:2: expected a translate offset (3 numbers), found 'x'", 0);
    check_error("mesh a tri\ninstance a translate 1 2 3x\n", P,
                "t.scene:2: expected a translate offset (3 numbers), found '3x'", 0);
    check_error("mesh a tri\ninstance a translate 1 2 0x10\n", P,
                "t.scene:2: expected a translate offset (3 numbers), found '0x10'", 0);
    check_error("mesh a tri\ninstance a scale 1 2\n", P,
                "t.scene:2: expected a third scale factor (scale takes 1 or 3 numbers)", 0);
    check_error("mesh a tri\ninstance a rotate 0 0 0 90\n", R,
                "t.scene:2: rotation axis (0, 0, 0) has no direction", 0);
    check_error("mesh a tri\ninstance a rotate 1 0 0\n", P,
                "t.scene:2: expected a rotation axis and angle (4 numbers), found end of line", 0);
    check_error("mesh a tri\ninstance a matrix 1 0 0 0 0 1 0 0 0 0 1\n", P,
                "t.scene:2: expected a matrix entry (12 numbers, 3 rows of 4)", 0);
    check_error("mesh a tri\ninstance a wobble 3\n", P,
                "t.scene:2: unknown transform 'wobble' (expected translate, scale, rotate or matrix)", 0);
    check_error("mesh a tri\ninstance a 1 2 3\n", P, "t.scene:2: unknown transform '1'", 0);
    check_error("frobnicate 1\n", P,
                "t.scene:1: unknown keyword 'frobnicate' (expected mesh, instance, camera or light)", 0);
    check_error("# comment\r\n\r\n  Mesh a tri\r\n", P, "t.scene:3: unknown keyword 'Mesh'", 0);
    /* Words quoted in a message show control and non-ASCII bytes escaped,
     * as the mesh loaders do: no terminal escape reaches the screen. */
    check_error("\x1b[31mred\x1b[0m 1\n", P,
                "t.scene:1: unknown keyword '\\x1B[31mred\\x1B[0m' (expected mesh", 0);
    check_error("mesh a tri\ninstance \xed\xa0\x80\n", P, "t.scene:2: unknown mesh '\\xED\\xA0\\x80'", 0);
    check_error("\rmesh a tri\rinstance a scale 0\r", R, "t.scene:3: instance a: the transform is singular", 0);
    check_error("camera eye 0 0 0\n", P, "t.scene:1: camera needs eye and look", 0);
    check_error("camera eye 0 0 1 look 0 0 1\n", R, "t.scene:1: camera: eye and look are the same point", 0);
    /* The generators' check in double, with the line: an up 0.0006 degrees
     * off the view is refused here, not later without a file. */
    check_error("camera eye 0 0 1 look 0 0 0 up 0.00001 0 1\n", R,
                "t.scene:1: camera: up (1e-05, 0, 1) is parallel to the view direction", 0);
    check_error("camera eye 0 0 1 look 0 0 0 up 0 0 2\n", R,
                "t.scene:1: camera: up (0, 0, 2) is parallel to the view direction", 0);
    check_error("camera eye 0 0 1 look 0 0 0 fov 180\n", R,
                "t.scene:1: camera fov 180 is not in (0, 180) degrees", 0);
    check_error("camera eye 0 0 1 look 0 0 0 zoom 2\n", P,
                "t.scene:1: unknown camera word 'zoom' (expected eye, look, up or fov)", 0);
    check_error("camera eye 0 0 1 eye 0 0 0\n", P, "t.scene:1: camera eye given twice", 0);
    check_error("camera eye 0 0 1e39 look 0 0 0\n", R,
                "t.scene:1: camera eye (3 numbers) (0, 0, 1e+39) is beyond the float range", 0);
    check_error("camera eye 0 0 1 look 0 0 0\ncamera eye 0 0 1 look 0 0 0\n", P,
                "t.scene:2: second camera (the first is at line 1)", 0);
    check_error("light 1 2\n", P, "t.scene:1: expected a light position (3 numbers), found end of line", 0);
    check_error("light 1 2 3 4\n", P, "t.scene:1: unexpected '4' after the light position", 0);
    check_error("light 1 2 3\n# x\nlight 1 2 3\n", P, "t.scene:3: second light (the first is at line 1)", 0);
    check_error("light 1 2", P, "t.scene:1: unexpected end of file: expected a light position", 0);
    /* Counts: over a given limit, and over the 32-bit id limit with meshes
     * that claim 2^31 primitives (nothing is allocated before the check). */
    check_error("mesh p pair\ninstance p\ninstance p\n\ninstance p\n", R,
                "t.scene:5: instance p: the scene would hold 6 primitives, over the limit of 5", 5);
    /* 2^31 primitives flattened are 80 GiB: over half the memory of most
     * machines (refused at the first instance, with its line), else over
     * the id limit at the second. */
    {
        accel_scene hs;
        accel_error he = {0};
        int hrc = parse("mesh h huge\ninstance h\ninstance h\n", &hs, &he, 0);
        if (hrc == 0) {
            test_fail(__FILE__, __LINE__, "2^32 primitives accepted");
            scene_free(&hs);
        } else {
            const char *mem = "t.scene:2: instance h: the flattened scene would hold 2147483648 "
                              "primitives (80.0 GiB), over half of this machine's memory";
            const char *ids = "t.scene:3: instance h: the scene would hold 4294967296 primitives, "
                              "over the limit of 4294967294";
            CHECKF(hrc == R && (!strncmp(he.msg, mem, strlen(mem)) || !strcmp(he.msg, ids)),
                   "got (%d) '%s'", hrc, he.msg);
        }
    }
    /* The default loader: scene files do not nest; built-in specs are checked. */
    accel_scene s;
    accel_error err = {0};
    const char *nest = "mesh x other.scene\n";
    int rc = scene_parse_scene("n.scene", "", nest, strlen(nest), NULL, &s, &err);
    CHECKF(rc && !strcmp(err.msg, "n.scene:1: mesh x: other.scene: a mesh cannot be a .scene file "
                                  "(scene files do not nest)"), "got '%s'", err.msg);
    const char *bad = "mesh c cube:n=0\n";
    rc = scene_parse_scene("n.scene", "", bad, strlen(bad), NULL, &s, &err);
    CHECKF(rc && !strncmp(err.msg, "n.scene:1: mesh c: ", 19) && strstr(err.msg, "n"), "got '%s'",
           err.msg);
}

TEST(scene_file_empty_and_comments)
{
    accel_scene s;
    accel_error err = {0};
    CHECK(parse("", &s, &err, 0) == 0 && s.prim_count == 0 && s.instances);
    scene_free(&s);
    CHECK(parse("# nothing\n\n   # still nothing\nmesh a tri # declared, never placed\n", &s, &err,
                0) == 0 &&
          s.prim_count == 0 && s.instances->mesh_count == 1);
    scene_free(&s);
    /* A ray at the default camera's look point hits the framed scene. */
    CHECK(parse("mesh a tri\ninstance a scale 3 translate 1 1 1\n", &s, &err, 0) == 0);
    accel_ray r = {s.camera.eye.x, s.camera.eye.y, s.camera.eye.z, 0,
                   s.camera.look_at.x - s.camera.eye.x, s.camera.look_at.y - s.camera.eye.y,
                   s.camera.look_at.z - s.camera.eye.z, INFINITY};
    accel_hit h;
    accel_reference_trace(&s, &r, &h, 1, 1);
    CHECK(h.prim == 0);
    scene_free(&s);
}

/* ---- the built-in scenes of many meshes ------------------------------------- */

/* The description matches the flattened triangles bit for bit. */
static void check_description(const accel_scene *s)
{
    const accel_instances *set = s->instances;
    if (!set) {
        test_fail(__FILE__, __LINE__, "%s: no instance description", s->name);
        return;
    }
    uint64_t next = 0;
    size_t bad = 0;
    for (uint32_t k = 0; k < set->instance_count; k++) {
        const accel_instance *in = &set->instances[k];
        const accel_scene *m = &set->meshes[in->mesh];
        CHECK(in->base == next);
        next += m->prim_count;
        for (uint32_t q = 0; q < m->tri_count; q++)
            for (int c = 0; c < 3; c++) {
                float w[3];
                accel_xform_vertex(in->xform, m->tris + 9 * q + 3 * c, w);
                bad += memcmp(w, s->tris + 9 * ((size_t)in->base + q) + 3 * c, sizeof w) != 0;
            }
    }
    CHECKF(next == s->prim_count && bad == 0, "%s: %llu primitives described, %zu vertices differ",
           s->name, (unsigned long long)next, bad);
}

TEST(scene_builtin_multi_meshes)
{
    accel_scene a, b, c;
    if (!test_make_scene("field:instances=40,detail=2", &a)) return;
    check_description(&a);
    CHECK(a.instances->mesh_count == 5 && a.instances->instance_count == 41);
    /* Some instances are mirrored (negative determinant). */
    int mirrored = 0;
    for (uint32_t k = 0; k < a.instances->instance_count; k++)
        mirrored += scene_xform_det(a.instances->instances[k].xform) < 0;
    CHECK(mirrored > 0);
    scene_free(&a);
    /* animated: a function of the frame; the blob (mesh 3) deforms. */
    const char *s0 = "animated:frame=0,instances=8,detail=3", *s1 = "animated:frame=30,instances=8,detail=3";
    if (!test_make_scene(s0, &a) || !test_make_scene(s1, &b) || !test_make_scene(s1, &c)) return;
    check_description(&b);
    CHECK(a.prim_count == b.prim_count && b.prim_count == c.prim_count);
    CHECK(!memcmp(b.tris, c.tris, 9 * sizeof(float) * b.tri_count));
    const accel_instances *ia = a.instances, *ib = b.instances;
    CHECK(memcmp(ia->meshes[3].tris, ib->meshes[3].tris, 9 * sizeof(float) * ib->meshes[3].tri_count));
    CHECK(!memcmp(ia->meshes[0].tris, ib->meshes[0].tris, 9 * sizeof(float) * ib->meshes[0].tri_count));
    int moved = 0;
    for (uint32_t k = 0; k < ib->instance_count; k++)
        moved += memcmp(ia->instances[k].xform, ib->instances[k].xform, sizeof ia->instances[k].xform) != 0;
    CHECKF(moved >= (int)ib->instance_count - 1, "%d of %u instances moved", moved, ib->instance_count);
    scene_free(&a);
    scene_free(&b);
    scene_free(&c);
}
