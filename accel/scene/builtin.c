/*
 * builtin.c - the table of built-in scenes and the small synthetic scenes
 * (soup, slivers, teapot_stadium, cube, sphere). The SPD scenes live in
 * spd.c, the teapot's patches in teapot.c, the shared meshes in mesh.c.
 *
 * Every generator is deterministic (its random numbers come from a
 * scene_rng seeded from its parameters), scales through one size parameter
 * from about a thousand to tens of millions of primitives, and sets a view
 * in which most primary rays hit something, as in a real render.
 * */
#include <math.h>
#include <stdlib.h>

#include "scene/builtin.h"
#include "scene/mesh.h"
#include "scene/teapot.h"

#define BUILTIN_PI 3.14159265358979323846

static accel_camera camera(vec3 eye, vec3 look_at, vec3 up, float fov_deg)
{
    accel_camera c = {eye, look_at, up, fov_deg};
    return c;
}

/* ---- cube, sphere: closed meshes for the stability suite -------------------- */

enum { CUBE_N };
static const accel_param_def cube_params[] = {
    {.key = "n", .type = ACCEL_PARAM_INT, .def = "32", .min = 1, .max = 4096,
     .help = "squares per face edge: 12*n^2 triangles on the cube [-1,1]^3"},
};

static int gen_cube(const double *values, scene_builder *b, accel_camera *cam, vec3 *light,
                    accel_error *err)
{
    int n = (int)values[CUBE_N];
    scene_mesh m;
    int rc = scene_check_count("cube", 12ull * (uint64_t)n * (uint64_t)n, err);
    if (rc == 0) rc = scene_mesh_cube(&m, n, err);
    if (rc) return rc;
    rc = scene_mesh_add(&m, b, (dvec3){0, 0, 0}, 1.0, err);
    scene_mesh_free(&m);
    /* Far enough that all 8 corners are inside the frame at 1:1 and wider
     * (the vertical field binds): within 89% of the half-frame, looking a
     * little below the centre, where perspective puts the projected cube's. */
    *cam = camera(v3(2.7f, 2.2f, 3.6f), v3(0, -0.2f, 0), v3(0, 1, 0), 40.0f);
    *light = v3(3, 5, 4);
    return rc;
}

static const scene_generator gen_cube_def = {
    "cube",
    "closed cube [-1,1]^3, n x n squares per face (watertight: shared vertices bit-identical)",
    cube_params, sizeof cube_params / sizeof cube_params[0], gen_cube, "cube:n=16", NULL,
};

enum { SPHERE_SEGMENTS, SPHERE_TESS };
static const accel_param_def sphere_params[] = {
    {.key = "segments", .type = ACCEL_PARAM_INT, .def = "32", .min = 1, .max = 4096,
     .help = "cube: squares per cube-face edge (12*s^2 triangles); uv: meridians (2*s*(s/2-1))"},
    {.key = "tess", .type = ACCEL_PARAM_ENUM, .def = "cube", .choices = "cube|uv",
     .help = "cube: projected cube, no poles; uv: latitude/longitude with pole fans"},
};

static int gen_sphere(const double *values, scene_builder *b, accel_camera *cam, vec3 *light,
                      accel_error *err)
{
    int seg = (int)values[SPHERE_SEGMENTS];
    int uv = values[SPHERE_TESS] == 1.0;
    uint64_t count = uv ? 2ull * (uint64_t)seg * (uint64_t)(seg / 2 > 0 ? seg / 2 - 1 : 0)
                        : 12ull * (uint64_t)seg * (uint64_t)seg;
    scene_mesh m;
    int rc = scene_check_count("sphere", count, err);
    if (rc == 0 && uv && seg < 4)
        rc = accel_fail(err, ACCEL_ERR_SPEC, "scene sphere: tess=uv needs segments >= 4 (got %d)",
                        seg);
    if (rc == 0)
        rc = uv ? scene_mesh_uv_sphere(&m, seg, err) : scene_mesh_cube_sphere(&m, seg, err);
    if (rc) return rc;
    rc = scene_mesh_add(&m, b, (dvec3){0, 0, 0}, 1.0, err);
    scene_mesh_free(&m);
    *cam = camera(v3(0.75f, 0.9f, 2.3f), v3(0, 0, 0), v3(0, 1, 0), 45.0f);
    *light = v3(3, 5, 4);
    return rc;
}

static const scene_generator gen_sphere_def = {
    "sphere",
    "closed unit sphere mesh (watertight: shared vertices bit-identical)",
    sphere_params, sizeof sphere_params / sizeof sphere_params[0], gen_sphere, "sphere:segments=16", NULL,
};

/* ---- soup and slivers: random triangles in the unit cube -------------------- */

/* A triangle of random shape near `centre`: each vertex offset by up to
 * half of `size` on every axis. */
static int add_random_tri(scene_builder *b, scene_rng *r, dvec3 centre, double size,
                          accel_error *err)
{
    vec3 p[3];
    for (int k = 0; k < 3; k++) {
        double dx = scene_rng_uniform(r) - 0.5, dy = scene_rng_uniform(r) - 0.5,
               dz = scene_rng_uniform(r) - 0.5;
        p[k] = v3((float)(centre.x + size * dx), (float)(centre.y + size * dy),
                  (float)(centre.z + size * dz));
    }
    return scene_builder_add_tri(b, p[0], p[1], p[2], err);
}

static dvec3 random_point(scene_rng *r)
{
    double x = scene_rng_uniform(r), y = scene_rng_uniform(r), z = scene_rng_uniform(r);
    return (dvec3){x, y, z};
}

/* Looking into the unit cube from outside, its front faces filling the view. */
static void cube_view(accel_camera *cam, vec3 *light)
{
    *cam = camera(v3(1.23f, 1.15f, 2.13f), v3(0.5f, 0.5f, 0.5f), v3(0, 1, 0), 36.0f);
    *light = v3(2.0f, 3.0f, 2.5f);
}

enum { SOUP_TRIS, SOUP_SIZE, SOUP_SEED };
static const accel_param_def soup_params[] = {
    {.key = "tris", .type = ACCEL_PARAM_INT, .def = "100000", .min = 1, .max = 4e9,
     .help = "number of triangles"},
    {.key = "size", .type = ACCEL_PARAM_FLOAT, .def = "1", .min = 1e-3, .max = 1e3,
     .help = "triangle extent per axis, in mean spacings (1/cbrt(tris))"},
    {.key = "seed", .type = ACCEL_PARAM_INT, .def = "1", .min = 0, .max = 4e9,
     .help = "random seed"},
};

static int gen_soup(const double *values, scene_builder *b, accel_camera *cam, vec3 *light,
                    accel_error *err)
{
    uint64_t n = (uint64_t)values[SOUP_TRIS];
    double size = values[SOUP_SIZE] / cbrt((double)n);
    scene_rng r = {(uint64_t)values[SOUP_SEED] * 0xD1B54A32D192ED03ull ^ 0x50u};
    int rc = scene_check_count("soup", n, err);
    if (rc == 0) rc = scene_builder_reserve_tris(b, (size_t)n, err);
    for (uint64_t i = 0; i < n && rc == 0; i++)
        rc = add_random_tri(b, &r, random_point(&r), size, err);
    cube_view(cam, light);
    return rc;
}

static const scene_generator gen_soup_def = {
    "soup",
    "random small triangles uniformly filling the unit cube",
    soup_params, sizeof soup_params / sizeof soup_params[0], gen_soup, "soup:tris=3000", NULL,
};

/*
 * Slivers: `slivers` needles from a random point of one face of the unit
 * cube to a random point of the opposite face, `width` mean spacings wide at
 * their start, among `tris` small random triangles (as in soup). Every
 * needle crosses the whole scene: a uniform grid sized for the small
 * triangles stores each needle in about cbrt(tris) cells.
 */
enum { SLIV_TRIS, SLIV_SLIVERS, SLIV_SIZE, SLIV_WIDTH, SLIV_SEED };
static const accel_param_def sliver_params[] = {
    {.key = "tris", .type = ACCEL_PARAM_INT, .def = "50000", .min = 0, .max = 4e9,
     .help = "number of small triangles"},
    {.key = "slivers", .type = ACCEL_PARAM_INT, .def = "1000", .min = 0, .max = 4e9,
     .help = "number of long thin triangles"},
    {.key = "size", .type = ACCEL_PARAM_FLOAT, .def = "1", .min = 1e-3, .max = 1e3,
     .help = "small triangle extent per axis, in mean spacings (1/cbrt(tris))"},
    {.key = "width", .type = ACCEL_PARAM_FLOAT, .def = "0.5", .min = 1e-6, .max = 1e3,
     .help = "sliver width, in mean spacings"},
    {.key = "seed", .type = ACCEL_PARAM_INT, .def = "1", .min = 0, .max = 4e9,
     .help = "random seed"},
};

static int gen_slivers(const double *values, scene_builder *b, accel_camera *cam, vec3 *light,
                       accel_error *err)
{
    uint64_t n = (uint64_t)values[SLIV_TRIS], ns = (uint64_t)values[SLIV_SLIVERS];
    double spacing = 1.0 / cbrt((double)(n ? n : 1));
    double size = values[SLIV_SIZE] * spacing, width = values[SLIV_WIDTH] * spacing;
    scene_rng r = {(uint64_t)values[SLIV_SEED] * 0xD1B54A32D192ED03ull ^ 0x51u};
    int rc = scene_check_count("slivers", n + ns, err);
    if (rc == 0 && n + ns == 0)
        rc = accel_fail(err, ACCEL_ERR_SPEC, "scene slivers: tris and slivers are both 0");
    if (rc == 0) rc = scene_builder_reserve_tris(b, (size_t)(n + ns), err);
    for (uint64_t i = 0; i < n && rc == 0; i++)
        rc = add_random_tri(b, &r, random_point(&r), size, err);
    for (uint64_t i = 0; i < ns && rc == 0; i++) {
        int axis = (int)(scene_rng_next(&r) % 3);
        dvec3 p = random_point(&r), q = random_point(&r);
        double *pa = axis == 0 ? &p.x : axis == 1 ? &p.y : &p.z;
        double *qa = axis == 0 ? &q.x : axis == 1 ? &q.y : &q.z;
        *pa = 0.0, *qa = 1.0;
        if (scene_rng_next(&r) & 1) *pa = 1.0, *qa = 0.0;
        /* The wide end: p moved by `width` in a random direction (rejection
         * sampling of the unit ball). */
        dvec3 d;
        double len2;
        do {
            d = random_point(&r);
            d.x = 2 * d.x - 1, d.y = 2 * d.y - 1, d.z = 2 * d.z - 1;
            len2 = d.x * d.x + d.y * d.y + d.z * d.z;
        } while (len2 > 1.0 || len2 < 1e-6);
        double s = width / sqrt(len2);
        vec3 e = v3((float)(p.x + s * d.x), (float)(p.y + s * d.y), (float)(p.z + s * d.z));
        rc = scene_builder_add_tri(b, dvec3_to_float(p), dvec3_to_float(q), e, err);
    }
    cube_view(cam, light);
    return rc;
}

static const scene_generator gen_slivers_def = {
    "slivers",
    "long thin triangles spanning the unit cube among many small ones (a grid's worst case)",
    sliver_params, sizeof sliver_params / sizeof sliver_params[0], gen_slivers,
    "slivers:tris=3000,slivers=100", NULL,
};

/* ---- teapot in a stadium ---------------------------------------------------- */

/*
 * Haines' "teapot in a stadium": a small detailed object inside a huge
 * sparse one, the classic case where a uniform grid sized by the primitive
 * count puts the whole teapot in a cell or two. The teapot (about 6.5 units
 * long) stands at the centre of a round field of radius 3000 (1 cell = 1
 * floor triangle of a fan of `stadium` slices); around it `tiers` steps of
 * 50 units rise 40 units apart, a bowl 8000 units across: about 1200 times
 * the teapot. The field lies 0.01 below the teapot so that the teapot's
 * bottom does not coincide with it.
 */
#define STADIUM_FIELD_RADIUS 3000.0
#define STADIUM_TIER_DEPTH 40.0  /* units, radial */
#define STADIUM_TIER_HEIGHT 50.0 /* units */
#define STADIUM_FIELD_Z (-0.01)

enum { TS_N, TS_STADIUM, TS_TIERS };
static const accel_param_def stadium_params[] = {
    {.key = "n", .type = ACCEL_PARAM_INT, .def = "32", .min = 1, .max = 8192,
     .help = "teapot quads per patch side: 64*n^2-8*n triangles"},
    {.key = "stadium", .type = ACCEL_PARAM_INT, .def = "128", .min = 3, .max = 1 << 20,
     .help = "stadium slices around: stadium*(1+4*tiers) triangles"},
    {.key = "tiers", .type = ACCEL_PARAM_INT, .def = "24", .min = 0, .max = 1000,
     .help = "steps of the stadium bowl"},
};

static vec3 ring_point(double radius, double c, double s, double z)
{
    return v3((float)(radius * c), (float)(radius * s), (float)z);
}

static int add_stadium(scene_builder *b, int slices, int tiers, accel_error *err)
{
    double *cs = malloc(2 * (size_t)slices * sizeof *cs);
    if (!cs) return accel_fail(err, ACCEL_ERR_NOMEM, "teapot_stadium: out of memory");
    for (int j = 0; j < slices; j++) {
        double phi = 2.0 * BUILTIN_PI * j / slices;
        cs[2 * j] = cos(phi);
        cs[2 * j + 1] = sin(phi);
    }
    int rc = 0;
    const double field = STADIUM_FIELD_RADIUS, zf = STADIUM_FIELD_Z;
    for (int j = 0; j < slices && rc == 0; j++) {
        const double *a = cs + 2 * j, *c = cs + 2 * ((j + 1) % slices);
        rc = scene_builder_add_tri(b, v3(0, 0, (float)zf), ring_point(field, a[0], a[1], zf),
                                   ring_point(field, c[0], c[1], zf), err);
    }
    for (int k = 0; k < tiers && rc == 0; k++) {
        double r0 = STADIUM_FIELD_RADIUS + k * STADIUM_TIER_DEPTH, r1 = r0 + STADIUM_TIER_DEPTH;
        double z0 = STADIUM_FIELD_Z + k * STADIUM_TIER_HEIGHT, z1 = z0 + STADIUM_TIER_HEIGHT;
        for (int j = 0; j < slices && rc == 0; j++) {
            const double *a = cs + 2 * j, *c = cs + 2 * ((j + 1) % slices);
            /* Riser facing the field, then the tread facing up. */
            vec3 in_a0 = ring_point(r0, a[0], a[1], z0), in_c0 = ring_point(r0, c[0], c[1], z0);
            vec3 in_a1 = ring_point(r0, a[0], a[1], z1), in_c1 = ring_point(r0, c[0], c[1], z1);
            vec3 out_a1 = ring_point(r1, a[0], a[1], z1), out_c1 = ring_point(r1, c[0], c[1], z1);
            rc = scene_add_quad(b, in_a0, in_a1, in_c1, in_c0, err);
            if (rc == 0) rc = scene_add_quad(b, in_a1, out_a1, out_c1, in_c1, err);
        }
    }
    free(cs);
    return rc;
}

static int gen_teapot_stadium(const double *values, scene_builder *b, accel_camera *cam,
                              vec3 *light, accel_error *err)
{
    int n = (int)values[TS_N], slices = (int)values[TS_STADIUM], tiers = (int)values[TS_TIERS];
    uint64_t stadium = (uint64_t)slices * (1ull + 4ull * (uint64_t)tiers);
    uint64_t count = scene_teapot_tri_count(n) + stadium;
    int rc = scene_check_count("teapot_stadium", count, err);
    if (rc == 0) rc = scene_builder_reserve_tris(b, (size_t)count, err);
    if (rc == 0) rc = scene_teapot_add(b, n, err);
    if (rc == 0) rc = add_stadium(b, slices, tiers, err);
    /* Close to the teapot, a little above it: the teapot fills the middle of
     * the frame, the field and the lower tiers the rest. */
    *cam = camera(v3(-4.4f, -7.8f, 3.4f), v3(0.2f, 0.0f, 1.3f), v3(0, 0, 1), 40.0f);
    *light = v3(-1500.0f, -2500.0f, 4000.0f);
    return rc;
}

static const scene_generator gen_teapot_stadium_def = {
    "teapot_stadium",
    "Newell's teapot at the centre of a stadium 1000x its size (the case that defeats grids)",
    stadium_params, sizeof stadium_params / sizeof stadium_params[0], gen_teapot_stadium,
    "teapot_stadium:n=6,stadium=32,tiers=4", NULL,
};

/* ---- the table -------------------------------------------------------------- */

const scene_generator *const scene_generators[] = {
    &scene_gen_sphereflake, &scene_gen_tetra, &scene_gen_mount, &gen_soup_def,
    &gen_teapot_stadium_def, &gen_slivers_def, &gen_cube_def, &gen_sphere_def,
    &scene_gen_field, &scene_gen_animated,
};
const size_t scene_generator_count = sizeof scene_generators / sizeof scene_generators[0];
