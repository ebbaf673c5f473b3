/*
 * multi.c - the built-in scenes of many meshes (each mesh built once,
 * placed by instances, flattened by compose.c with the ids of FORMATS.md):
 *
 *   field     procedural meshes (teapots, spheres coarse and dense, SPD
 *             tetrahedra) scattered over a ground slab at scales from 0.05
 *             to 3 and in a dense cluster of tiny ones: very different
 *             scales and densities, overlapping instances, arbitrary
 *             rotations, mirrored instances.
 *   animated  a function of the frame number: teapots, spheres and tetra on
 *             two rings orbiting, bobbing and spinning around a blob whose
 *             vertices move (a deforming mesh), over a ground slab.
 *
 * Both are deterministic (scene_rng, seeded from the parameters) and need no
 * files. World is z up; every mesh stands on z = 0 before it is placed.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/builtin.h"
#include "scene/compose.h"
#include "scene/mesh.h"
#include "scene/teapot.h"

#define MULTI_PI 3.14159265358979323846

/* ---- meshes ------------------------------------------------------------------ */

static int add_built(scene_compose *c, scene_builder *b, const char *name, uint32_t *idx,
                     accel_error *err)
{
    accel_scene m;
    int rc = scene_finish(b, name, &m, err);
    scene_builder_free(b);
    if (rc) return rc;
    rc = scene_compose_add_mesh(c, &m, idx, err);
    if (rc) scene_free(&m);
    return rc;
}

/* Newell's teapot, n x n quads per patch (z up, on z = 0, about 6.5 long). */
static int add_teapot(scene_compose *c, int n, uint32_t *idx, accel_error *err)
{
    scene_builder b = {0};
    int rc = scene_teapot_add(&b, n, err);
    if (rc) {
        scene_builder_free(&b);
        return rc;
    }
    char name[64];
    snprintf(name, sizeof name, "teapot n=%d", n);
    return add_built(c, &b, name, idx, err);
}

/*
 * A unit cube-sphere resting on z = 0 (centre (0,0,1)), each vertex moved
 * along its direction by `wave` times a travelling wave of phase `phase`
 * (wave = 0: the sphere). Every copy of a shared vertex is computed from the
 * same double vertex by the same expression, so the blob stays watertight.
 */
static int add_blob(scene_compose *c, int segments, double wave, double phase, uint32_t *idx,
                    accel_error *err)
{
    scene_mesh m;
    int rc = scene_mesh_cube_sphere(&m, segments, err);
    if (rc) return rc;
    for (size_t i = 0; i < m.vert_count; i++) {
        dvec3 *v = &m.verts[i];
        double r = 1.0 + wave * sin(3.0 * MULTI_PI * v->x + phase) *
                             cos(2.0 * MULTI_PI * v->y - 0.7 * phase) * (0.6 + 0.4 * v->z);
        v->x *= r, v->y *= r, v->z *= r;
    }
    scene_builder b = {0};
    rc = scene_mesh_add(&m, &b, (dvec3){0, 0, 1}, 1.0, err);
    scene_mesh_free(&m);
    if (rc) {
        scene_builder_free(&b);
        return rc;
    }
    char name[64];
    snprintf(name, sizeof name, "%s segments=%d", wave ? "blob" : "sphere", segments);
    return add_built(c, &b, name, idx, err);
}

/* SPD tetra (a Sierpinski pyramid in [-1,1]^3, touching at corners), lifted to z >= 0. */
static int add_tetra(scene_compose *c, int level, uint32_t *idx, accel_error *err)
{
    char spec[64];
    snprintf(spec, sizeof spec, "tetra:level=%d", level);
    accel_scene raw;
    int rc = scene_create(spec, &raw, err);
    if (rc) return rc;
    scene_builder b = {0};
    rc = scene_builder_reserve_tris(&b, raw.tri_count, err);
    for (uint32_t i = 0; i < raw.tri_count && rc == 0; i++) {
        const float *t = raw.tris + 9 * (size_t)i;
        rc = scene_builder_add_tri(&b, v3(t[0], t[1], t[2] + 1), v3(t[3], t[4], t[5] + 1),
                                   v3(t[6], t[7], t[8] + 1), err);
    }
    scene_free(&raw);
    if (rc) {
        scene_builder_free(&b);
        return rc;
    }
    return add_built(c, &b, spec, idx, err);
}

/* The cube [-1,1]^3 with n x n squares per face: flattened into a slab by its instance. */
static int add_slab(scene_compose *c, int n, uint32_t *idx, accel_error *err)
{
    scene_mesh m;
    int rc = scene_mesh_cube(&m, n, err);
    if (rc) return rc;
    scene_builder b = {0};
    rc = scene_mesh_add(&m, &b, (dvec3){0, 0, 0}, 1.0, err);
    scene_mesh_free(&m);
    if (rc) {
        scene_builder_free(&b);
        return rc;
    }
    return add_built(c, &b, "slab", idx, err);
}

/* Places mesh `mesh`: scale (mirrored in x when `mirror`), turn by `yaw`
 * degrees about z and `tilt` about x, then move to (x, y, z). */
static int place(scene_compose *c, uint32_t mesh, double scale, int mirror, double tilt,
                 double yaw, double x, double y, double z, accel_error *err)
{
    double m[12], t[12];
    scene_xform_scale(m, mirror ? -scale : scale, scale, scale);
    if (tilt != 0.0 && scene_xform_rotate(t, 1, 0, 0, tilt) == 0) scene_xform_then(m, t);
    if (scene_xform_rotate(t, 0, 0, 1, yaw) == 0) scene_xform_then(m, t);
    scene_xform_translate(t, x, y, z);
    scene_xform_then(m, t);
    return scene_compose_add_instance(c, mesh, m, err);
}

/* The ground: the slab mesh as a w x w x 0.2 plate whose top is z = 0. */
static int place_ground(scene_compose *c, uint32_t slab, double w, accel_error *err)
{
    double m[12], t[12];
    scene_xform_scale(m, 0.5 * w, 0.5 * w, 0.1);
    scene_xform_translate(t, 0, 0, -0.1);
    scene_xform_then(m, t);
    return scene_compose_add_instance(c, slab, m, err);
}

static accel_camera view(vec3 eye, vec3 look, float fov)
{
    accel_camera cam = {eye, look, v3(0, 0, 1), fov};
    return cam;
}

/* ---- field ----------------------------------------------------------------- */

enum { FIELD_INSTANCES, FIELD_DETAIL, FIELD_SEED };
static const accel_param_def field_params[] = {
    {.key = "instances", .type = ACCEL_PARAM_INT, .def = "200", .min = 1, .max = 1e7,
     .help = "meshes placed (besides the ground); a quarter in a dense cluster of tiny ones"},
    {.key = "detail", .type = ACCEL_PARAM_INT, .def = "4", .min = 1, .max = 64,
     .help = "tessellation: teapot n=detail (64 d^2 triangles), sphere 12 (d+2)^2, dense sphere "
             "12 (4d)^2, tetra level 2+d/4, ground 12 (2d)^2"},
    {.key = "seed", .type = ACCEL_PARAM_INT, .def = "1", .min = 0, .max = 4e9,
     .help = "random seed"},
};

static int gen_field(const double *values, scene_compose *c, accel_camera *cam, vec3 *light,
                     accel_error *err)
{
    uint32_t count = (uint32_t)values[FIELD_INSTANCES];
    int d = (int)values[FIELD_DETAIL];
    scene_rng r = {(uint64_t)values[FIELD_SEED] * 0xD1B54A32D192ED03ull ^ 0x6669u};
    uint32_t mesh[5], slab;
    int rc = add_teapot(c, d, &mesh[0], err);
    if (rc == 0) rc = add_blob(c, d + 2, 0.0, 0.0, &mesh[1], err);
    if (rc == 0) rc = add_blob(c, 4 * d, 0.0, 0.0, &mesh[2], err);
    if (rc == 0) rc = add_tetra(c, 2 + (d / 4 < 4 ? d / 4 : 4), &mesh[3], err);
    if (rc == 0) rc = add_slab(c, 2 * d, &slab, err);
    /* Unit-ish sizes: the teapot is 6.5 long, the others 2. */
    static const double unit[4] = {1.0 / 3.25, 1.0, 1.0, 1.0};
    double w = 3.0 * sqrt((double)count) + 6.0;
    if (rc == 0) rc = place_ground(c, slab, w, err);
    for (uint32_t i = 0; i < count && rc == 0; i++) {
        int cluster = i % 4 == 3;
        int kind = (int)(scene_rng_next(&r) % 4);
        /* Log-uniform scales: 0.25..3 in the open, 0.05..0.25 in the cluster. */
        double lo = cluster ? 0.05 : 0.25, hi = cluster ? 0.25 : 3.0;
        double s = lo * pow(hi / lo, scene_rng_uniform(&r));
        double x, y;
        if (cluster) {
            double a = 2 * MULTI_PI * scene_rng_uniform(&r), rad = 2.5 * sqrt(scene_rng_uniform(&r));
            x = 0.2 * w + rad * cos(a), y = -0.1 * w + rad * sin(a);
        } else {
            x = (scene_rng_uniform(&r) - 0.5) * (w - 4.0);
            y = (scene_rng_uniform(&r) - 0.5) * (w - 4.0);
        }
        double yaw = 360.0 * scene_rng_uniform(&r);
        double tilt = scene_rng_next(&r) % 5 == 0 ? 30.0 * scene_rng_uniform(&r) : 0.0;
        int mirror = scene_rng_next(&r) % 3 == 0;
        rc = place(c, mesh[kind], s * unit[kind], mirror, tilt, yaw, x, y, 0.0, err);
    }
    *cam = view(v3((float)(-0.45 * w), (float)(-0.6 * w), (float)(0.5 * w)),
                v3((float)(0.02 * w), (float)(0.02 * w), 0.0f), 40.0f);
    *light = v3((float)(0.6 * w), (float)(-0.9 * w), (float)(1.5 * w));
    return rc;
}

const scene_generator scene_gen_field = {
    .name = "field",
    .summary = "many meshes: instanced teapots, spheres and tetra at scales 0.05-3 on a ground, "
               "with a dense cluster (a scene of instances)",
    .params = field_params,
    .param_count = sizeof field_params / sizeof field_params[0],
    .generate = NULL,
    .small_spec = "field:instances=40,detail=2",
    .compose = gen_field,
};

/* ---- animated ---------------------------------------------------------------- */

enum { ANIM_FRAME, ANIM_INSTANCES, ANIM_DETAIL };
static const accel_param_def anim_params[] = {
    {.key = "frame", .type = ACCEL_PARAM_INT, .def = "0", .min = 0, .max = 1e7,
     .help = "frame number (60 frames per second of motion)"},
    {.key = "instances", .type = ACCEL_PARAM_INT, .def = "24", .min = 1, .max = 1e6,
     .help = "meshes on the two orbiting rings"},
    {.key = "detail", .type = ACCEL_PARAM_INT, .def = "8", .min = 1, .max = 64,
     .help = "tessellation: teapot n=detail (64 d^2 triangles), sphere 12 (d+2)^2, tetra level "
             "2+d/4, blob 12 (4d)^2"},
};

static int gen_animated(const double *values, scene_compose *c, accel_camera *cam, vec3 *light,
                        accel_error *err)
{
    double t = values[ANIM_FRAME] / 60.0;
    uint32_t count = (uint32_t)values[ANIM_INSTANCES];
    int d = (int)values[ANIM_DETAIL];
    uint32_t mesh[3], blob, slab;
    int rc = add_teapot(c, d, &mesh[0], err);
    if (rc == 0) rc = add_blob(c, d + 2, 0.0, 0.0, &mesh[1], err);
    if (rc == 0) rc = add_tetra(c, 2 + (d / 4 < 4 ? d / 4 : 4), &mesh[2], err);
    if (rc == 0) rc = add_blob(c, 4 * d, 0.18, 2.0 * t, &blob, err);
    if (rc == 0) rc = add_slab(c, 4, &slab, err);
    static const double size[3] = {0.35, 0.8, 0.8};
    double outer = 6.0 + 0.25 * count;
    if (rc == 0) rc = place_ground(c, slab, 2.0 * outer + 8.0, err);
    if (rc == 0) rc = place(c, blob, 2.2, 0, 0.0, 25.0 * t, 0.0, 0.0, 0.0, err);
    for (uint32_t i = 0; i < count && rc == 0; i++) {
        int ring = i % 2, kind = (int)(i % 3);
        double radius = ring ? outer : 0.6 * outer;
        double speed = (ring ? -0.25 : 0.4) * (1.0 + 0.1 * (i % 5));
        double a = 2.0 * MULTI_PI * i / count + speed * t;
        double bob = kind == 0 ? 0.0 : 0.6 + 0.5 * sin(2.0 * t + i);
        double spin = (90.0 + 20.0 * (i % 4)) * t + 37.0 * i;
        rc = place(c, mesh[kind], size[kind] * (1.0 + 0.3 * (i % 3)), i % 7 == 3,
                   kind == 2 ? 15.0 * sin(t + i) : 0.0, spin, radius * cos(a), radius * sin(a),
                   bob, err);
    }
    *cam = view(v3((float)(-1.0 * outer), (float)(-1.4 * outer), (float)(1.1 * outer)),
                v3(0.0f, 0.0f, 0.5f), 45.0f);
    *light = v3((float)outer, (float)(-2.0 * outer), (float)(3.0 * outer));
    return rc;
}

const scene_generator scene_gen_animated = {
    .name = "animated",
    .summary = "many meshes moving with the frame number: orbiting, spinning instances around a "
               "deforming blob (a scene of instances)",
    .params = anim_params,
    .param_count = sizeof anim_params / sizeof anim_params[0],
    .generate = NULL,
    .small_spec = "animated:frame=30,instances=8,detail=3",
    .compose = gen_animated,
};
