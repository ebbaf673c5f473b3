/*
 * test_views.c - default views frame what they show: the built-in cube's
 * camera keeps all 8 corners inside the image at 1:1 and 4:3, and a mesh
 * file's default view looks at the mesh's front (the side it leans toward,
 * scene.c mesh_front) with every vertex inside the image.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"
#include "support.h"

/* Where p lands in the image of cam at width/height = aspect, as rays.c
 * makes primary rays: (-1, -1) to (1, 1) from the bottom left to the top
 * right corner. Returns 0 when p is not in front of the eye. */
static int project(const accel_camera *cam, vec3 p, double aspect, double *x, double *y)
{
    vec3 fwd = v3_norm(v3_sub(cam->look_at, cam->eye));
    vec3 right = v3_norm(v3_cross(fwd, cam->up));
    vec3 up = v3_cross(right, fwd);
    vec3 q = v3_sub(p, cam->eye);
    double depth = v3_dot(q, fwd), th = tan(0.5 * cam->fov_deg * 3.14159265358979 / 180.0);
    if (!(depth > 0)) return 0;
    *x = v3_dot(q, right) / depth / (aspect * th);
    *y = v3_dot(q, up) / depth / th;
    return 1;
}

/* Whether every point lies inside the image, `margin` of the half-frame
 * away from its edges, at each of the aspect ratios of the report (1:1,
 * 4:3 as 800x600 and 640x480, and trace's default 512x512). */
static int all_inside(const accel_camera *cam, const vec3 *p, size_t n, double margin,
                      const char *what)
{
    static const double aspects[] = {1.0, 4.0 / 3.0};
    int ok = 1;
    for (size_t a = 0; a < sizeof aspects / sizeof aspects[0]; a++) {
        double worst = 0;
        for (size_t i = 0; i < n; i++) {
            double x, y;
            if (!project(cam, p[i], aspects[a], &x, &y)) {
                worst = INFINITY;
                break;
            }
            worst = fmax(worst, fmax(fabs(x), fabs(y)));
        }
        CHECKF(worst <= 1.0 - margin, "%s at aspect %.3f: a point at %.3f of the half-frame",
               what, aspects[a], worst);
        ok &= worst <= 1.0 - margin;
    }
    return ok;
}

/* The old camera (2.1, 1.7, 2.75) put corners at 1.37 of the half-frame. */
TEST(views_cube_inside_frame)
{
    accel_scene s;
    if (!test_make_scene("cube", &s)) return;
    vec3 corners[8];
    for (int i = 0; i < 8; i++)
        corners[i] = v3(i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 1.0f : -1.0f);
    all_inside(&s.camera, corners, 8, 0.05, "cube corner");
    scene_free(&s);
}

/* Every vertex of a loaded mesh inside its default view's image. */
static void check_mesh_inside(const accel_scene *s, const char *what)
{
    size_t n = 3 * (size_t)s->tri_count;
    vec3 *p = malloc((n ? n : 1) * sizeof *p);
    if (!p) return;
    for (size_t i = 0; i < n; i++) p[i] = v3_load(s->tris + 3 * i);
    all_inside(&s->camera, p, n, 0.0, what);
    free(p);
}

/* A box of side 1 with its top square moved by (dx, 0, dz), as an OFF file:
 * a column leaning toward (dx, dz), or upright. */
static int load_column(const char *dir, double dx, double dz, accel_scene *s)
{
    static const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                     {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                     {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    char path[600], text[2048];
    int len = snprintf(text, sizeof text, "OFF\n8 12 0\n");
    for (int i = 0; i < 8; i++) {
        double top = i & 4 ? 1.0 : 0.0;
        len += snprintf(text + len, sizeof text - (size_t)len, "%g %g %g\n",
                        (i & 1) + top * dx, 4 * top, (i & 2 ? 1.0 : 0.0) + top * dz);
    }
    for (int f = 0; f < 12; f++)
        len += snprintf(text + len, sizeof text - (size_t)len, "3 %d %d %d\n", faces[f][0],
                        faces[f][1], faces[f][2]);
    snprintf(path, sizeof path, "%s/column.off", dir);
    if (!test_write_file(path, text)) return 0;
    accel_error err = {0};
    int rc = scene_load_file(path, s, &err);
    CHECKF(rc == 0, "%s: %s", path, err.msg);
    return rc == 0;
}

/* The rule is general: the eye goes to the side a mesh leans toward. (An
 * upright column of 12 triangles is left out: which vertices its
 * triangulation repeats tilts it by a third of a side, over the 2% that
 * keeps +z; on a scanned mesh's fine triangles that bias vanishes.) */
TEST(views_mesh_file_faces_its_lean)
{
    char dir[512];
    if (!test_temp_dir("views", dir, sizeof dir)) return;
    static const struct {
        double dx, dz;
        int axis, sign; /* the eye's side of the look-at point */
    } cases[] = {{2, 0, 0, 1}, {0, -2, 2, -1}, {-1, 1, 0, -1}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        accel_scene s;
        if (!load_column(dir, cases[c].dx, cases[c].dz, &s)) continue;
        vec3 d = v3_sub(s.camera.eye, s.camera.look_at);
        float side = cases[c].axis == 0 ? d.x : d.z;
        CHECKF(side * (float)cases[c].sign > 0,
               "column leaning (%g, %g): eye at (%g, %g, %g) from the centre", cases[c].dx,
               cases[c].dz, d.x, d.y, d.z);
        CHECKF(d.y > 0, "column leaning (%g, %g): eye below the centre", cases[c].dx,
               cases[c].dz);
        check_mesh_inside(&s, "column vertex");
        scene_free(&s);
    }
    test_remove_dir(dir);
}

/* The armadillo of the shared scenes faces -z (its face, belly and claws;
 * rendered and looked at): its default view used to show its back shell
 * from +z. The bunny's head is at -x. */
TEST(views_shared_meshes_show_their_front)
{
    char paths[16][512];
    int count = test_shared_files(".off", paths, 16);
    for (int i = 0; i < count; i++) {
        const char *name = strrchr(paths[i], '/') + 1;
        accel_scene s;
        accel_error err = {0};
        if (scene_load_file(paths[i], &s, &err)) {
            CHECKF(0, "%s: %s", paths[i], err.msg);
            continue;
        }
        vec3 d = v3_sub(s.camera.eye, s.camera.look_at);
        if (!strcmp(name, "armadillo.off"))
            CHECKF(d.z < 0 && fabsf(d.x) < -d.z, "armadillo: eye at (%g, %g, %g) from the centre",
                   d.x, d.y, d.z);
        if (!strcmp(name, "bunny.off"))
            CHECKF(d.x < 0, "bunny: eye at (%g, %g, %g) from the centre", d.x, d.y, d.z);
        check_mesh_inside(&s, name);
        scene_free(&s);
    }
}
