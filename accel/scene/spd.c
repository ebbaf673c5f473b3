/*
 * spd.c - three of Eric Haines' Standard Procedural Databases: sphereflake
 * ("balls"), tetra and mount.
 *
 * E. Haines, "A Proposal for Standard Graphics Environments", IEEE CG&A
 * 7(11), November 1987, pp. 3-5; the generators balls.c, tetra.c and mount.c
 * of the SPD package (version 3.14, 2005). Each scene follows its generator:
 * same construction, same constants, same primitive order, same view (eye,
 * look-at, up, 45 degree field of view) and the first of its lights (a scene
 * here has one point light). `level` is the SPD size factor.
 *
 * The SPD's matrices act on row vectors (p' = p M), with its rotation
 * conventions; they are written out the same way here, in double precision,
 * so that the databases match the SPD's output to double rounding before the
 * final conversion to float.
 *
 * Published statistics (SPD README, "Database Analysis", default size
 * factors, 513 x 513 eye rays through the pixel corners of a 512 x 512 image
 * whose 45 degree field of view spans the outermost rays):
 *
 *   database  size  primitives                  eye rays that hit
 *   balls     4     7381 spheres + 1 polygon    263169 (all, 0% background)
 *   mount     6     8192 triangles + 4 spheres  173125 (34% background)
 *   tetra     6     4096 triangles               49788 (81% background)
 *
 * "The numbers given can vary noticeably from a given ray tracer, but should
 * all be within about 10%." The SPD uses a left-handed coordinate system, so
 * an image rendered here may be the mirror image of the SPD's; hit counts
 * are unaffected.
 */
#include <math.h>

#include "scene/builtin.h"
#include "scene/mesh.h"

#define SPD_PI 3.14159265358979323846

/* ---- SPD matrix conventions (lib_create_axis_rotate_matrix etc.) ----------- */

typedef double spd_mat[3][3];

/* Rotation by `angle` about the unit vector `axis`, for row vectors. */
static void axis_rotation(spd_mat m, dvec3 axis, double angle)
{
    double c = cos(angle), s = sin(angle), omc = 1.0 - c;
    double x = axis.x, y = axis.y, z = axis.z;
    m[0][0] = x * x + (1.0 - x * x) * c;
    m[0][1] = x * y * omc + z * s;
    m[0][2] = x * z * omc - y * s;
    m[1][0] = x * y * omc - z * s;
    m[1][1] = y * y + (1.0 - y * y) * c;
    m[1][2] = y * z * omc + x * s;
    m[2][0] = x * z * omc + y * s;
    m[2][1] = y * z * omc - x * s;
    m[2][2] = z * z + (1.0 - z * z) * c;
}

/* Rotation about a coordinate axis (0 = x, 1 = y, 2 = z), SPD sign convention. */
static void axis_rotation_xyz(spd_mat m, int axis, double angle)
{
    double c = cos(angle), s = sin(angle);
    int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) m[i][j] = 0.0;
    m[axis][axis] = 1.0;
    m[a][a] = c;
    m[b][b] = c;
    m[a][b] = s;
    m[b][a] = -s;
}

static dvec3 row_times(dvec3 v, spd_mat m)
{
    dvec3 r = {v.x * m[0][0] + v.y * m[1][0] + v.z * m[2][0],
               v.x * m[0][1] + v.y * m[1][1] + v.z * m[2][1],
               v.x * m[0][2] + v.y * m[1][2] + v.z * m[2][2]};
    return r;
}

static dvec3 dnormalize(dvec3 v)
{
    double len = sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    if (len > 0.0) v.x /= len, v.y /= len, v.z /= len;
    return v;
}

static accel_camera spd_view(vec3 from, vec3 at, vec3 up)
{
    accel_camera c = {from, at, up, 45.0f};
    return c;
}

/* ---- sphereflake (balls.c) -------------------------------------------------- */

/*
 * A sphere of radius 1/2 at the origin; each sphere carries 9 children of a
 * third of its radius, touching it: 6 around its equator and 3 on its upper
 * hemisphere, "up" being the direction from its parent. Level L has
 * (9^(L+1) - 1) / 8 spheres, plus the 24 x 24 floor square at z = -1/2 as two
 * triangles (ids 0 and 1).
 */
enum { FLAKE_LEVEL, FLAKE_SPHERES, FLAKE_SEGMENTS };

static const accel_param_def flake_params[] = {
    {.key = "level", .type = ACCEL_PARAM_INT, .def = "4", .min = 0, .max = 8,
     .help = "SPD size factor: (9^(level+1)-1)/8 spheres (SPD default 4: 7381)"},
    {.key = "spheres", .type = ACCEL_PARAM_BOOL, .def = "1", .min = 0, .max = 1,
     .help = "1: true spheres; 0: each sphere a closed mesh of 12*segments^2 triangles"},
    {.key = "segments", .type = ACCEL_PARAM_INT, .def = "4", .min = 1, .max = 256,
     .help = "tessellated spheres: squares per cube-face edge (SPD default 4: 192 triangles)"},
};

typedef struct {
    dvec3 objset[9];         /* child directions around +z, from create_objset */
    int spheres;             /* true spheres or meshes */
    const scene_mesh *mesh;  /* the tessellated unit sphere when !spheres */
    scene_builder *b;
    accel_error *err;
} flake_ctx;

/* The 9 child offsets for a parent pointing up +z (balls.c create_objset):
 * three directions rotated up by asin(2/sqrt 6), repeated at 120 degrees. */
static void flake_objset(dvec3 objset[9])
{
    double d = 1.0 / sqrt(2.0);
    dvec3 trio[3] = {{d, d, 0.0}, {d, 0.0, -d}, {0.0, d, -d}};
    spd_mat m;
    axis_rotation(m, dnormalize((dvec3){1.0, -1.0, 0.0}), asin(2.0 / sqrt(6.0)));
    for (int v = 0; v < 3; v++) trio[v] = row_times(trio[v], m);
    for (int set = 0; set < 3; set++) {
        axis_rotation_xyz(m, 2, set * 2.0 * SPD_PI / 3.0);
        for (int v = 0; v < 3; v++) objset[set * 3 + v] = row_times(trio[v], m);
    }
}

/* balls.c output_object: the sphere, then its children depth first.
 * `ratio` is the child/parent radius ratio (1/3). */
static int flake_object(flake_ctx *f, int depth, dvec3 centre, double radius, dvec3 dir,
                        double ratio)
{
    int rc = f->spheres ? scene_builder_add_sphere(f->b, dvec3_to_float(centre), (float)radius,
                                                   f->err)
                        : scene_mesh_add(f->mesh, f->b, centre, radius, f->err);
    if (rc || depth == 0) return rc;
    /* Rotation taking +z to dir (the identity when dir is +z). */
    spd_mat m = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (dir.z <= -1.0)
        axis_rotation_xyz(m, 1, SPD_PI);
    else if (dir.z < 1.0)
        axis_rotation(m, dnormalize((dvec3){-dir.y, dir.x, 0.0}), acos(dir.z));
    double scale = radius * (1.0 + ratio);
    for (int k = 0; k < 9 && rc == 0; k++) {
        dvec3 p = row_times(f->objset[k], m);
        p.x = p.x * scale + centre.x;
        p.y = p.y * scale + centre.y;
        p.z = p.z * scale + centre.z;
        dvec3 child_dir = {(p.x - centre.x) / scale, (p.y - centre.y) / scale,
                           (p.z - centre.z) / scale};
        rc = flake_object(f, depth - 1, p, radius * ratio, child_dir, ratio);
    }
    return rc;
}

static int gen_sphereflake(const double *values, scene_builder *b, accel_camera *cam,
                           vec3 *light, accel_error *err)
{
    int level = (int)values[FLAKE_LEVEL];
    int spheres = values[FLAKE_SPHERES] != 0.0;
    int segments = (int)values[FLAKE_SEGMENTS];
    uint64_t count = 1;
    for (int i = 0; i < level; i++) count = count * 9 + 1;
    uint64_t per_sphere = spheres ? 1 : 12ull * (uint64_t)segments * (uint64_t)segments;
    uint64_t prims = 2 + count * per_sphere;
    int rc = scene_check_count("sphereflake", prims, err);
    if (rc) return rc;
    if (!spheres) rc = scene_builder_reserve_tris(b, (size_t)prims, err);
    if (rc) return rc;

    /* The floor polygon (12 * radius square, radius 1), split as a fan. */
    vec3 f0 = v3(12, 12, -0.5f), f1 = v3(-12, 12, -0.5f), f2 = v3(-12, -12, -0.5f),
         f3 = v3(12, -12, -0.5f);
    rc = scene_add_quad(b, f0, f1, f2, f3, err);
    if (rc) return rc;

    scene_mesh mesh = {0};
    if (!spheres) rc = scene_mesh_cube_sphere(&mesh, segments, err);
    if (rc == 0) {
        flake_ctx f = {.spheres = spheres, .mesh = &mesh, .b = b, .err = err};
        flake_objset(f.objset);
        rc = flake_object(&f, level, (dvec3){0, 0, 0}, 0.5, (dvec3){0, 0, 1}, 1.0 / 3.0);
    }
    scene_mesh_free(&mesh);
    *cam = spd_view(v3(2.1f, 1.3f, 1.7f), v3(0, 0, 0), v3(0, 0, 1));
    *light = v3(4, 3, 2); /* the SPD's others: (1,-4,4), (-3,1,5) */
    return rc;
}

const scene_generator scene_gen_sphereflake = {
    "sphereflake",
    "SPD balls: fractal spheres, 9 children per sphere, on a floor square (Haines 1987)",
    flake_params,
    sizeof flake_params / sizeof flake_params[0],
    gen_sphereflake,
    "sphereflake:level=3", NULL,
};

/* ---- tetra (tetra.c) ------------------------------------------------------- */

/*
 * A tetrahedron (alternate corners of the cube [-1,1]^3) replaced recursively
 * by the 4 half-size tetrahedra at its corners: 4^level triangles. Every
 * coordinate is a dyadic fraction, so all vertices are exact and the small
 * tetrahedra touch exactly at their corners.
 */
enum { TETRA_LEVEL };

static const accel_param_def tetra_params[] = {
    {.key = "level", .type = ACCEL_PARAM_INT, .def = "7", .min = 1, .max = 13,
     .help = "SPD size factor: 4^level triangles (SPD default 6: 4096)"},
};

static int tetra_object(scene_builder *b, int depth, double cx, double cy, double cz, double w,
                        accel_error *err)
{
    if (depth <= 1) {
        /* Cube corners with x*y*z = +1, in the SPD loop order. */
        vec3 p[4];
        int n = 0;
        for (int x = -1; x <= 1; x += 2)
            for (int y = -1; y <= 1; y += 2)
                for (int z = -1; z <= 1; z += 2)
                    if (x * y * z == 1)
                        p[n++] = v3((float)(cx + x * w), (float)(cy + y * w), (float)(cz + z * w));
        /* Faces 0 1 2, 3 2 1, 2 3 0, 1 0 3: (f, f+1, f+2) mod 4, odd faces reversed. */
        for (int face = 0; face < 4; face++) {
            int a = face, c = (face + 1) % 4, d = (face + 2) % 4;
            int rc = face % 2 ? scene_builder_add_tri(b, p[d], p[c], p[a], err)
                              : scene_builder_add_tri(b, p[a], p[c], p[d], err);
            if (rc) return rc;
        }
        return 0;
    }
    for (int x = -1; x <= 1; x += 2)
        for (int y = -1; y <= 1; y += 2)
            for (int z = -1; z <= 1; z += 2)
                if (x * y * z == 1) {
                    int rc = tetra_object(b, depth - 1, cx + x * w / 2.0, cy + y * w / 2.0,
                                          cz + z * w / 2.0, w / 2.0, err);
                    if (rc) return rc;
                }
    return 0;
}

static int gen_tetra(const double *values, scene_builder *b, accel_camera *cam, vec3 *light,
                     accel_error *err)
{
    int level = (int)values[TETRA_LEVEL];
    uint64_t prims = 1ull << (2 * level);
    int rc = scene_check_count("tetra", prims, err);
    if (rc == 0) rc = scene_builder_reserve_tris(b, (size_t)prims, err);
    if (rc == 0) rc = tetra_object(b, level, 0.0, 0.0, 0.0, 1.0, err);
    /* Kay and Kajiya's view, in the SPD's coordinates. */
    *cam = spd_view(v3(1.022846f, -3.177154f, -2.174512f), v3(-0.004103f, -0.004103f, 0.216539f),
                    v3(-0.816497f, -0.816497f, 0.816497f));
    *light = v3(2, -18, -5);
    return rc;
}

const scene_generator scene_gen_tetra = {
    "tetra",
    "SPD tetra: recursive tetrahedra, a Sierpinski pyramid (Haines 1987)",
    tetra_params,
    sizeof tetra_params / sizeof tetra_params[0],
    gen_tetra,
    "tetra:level=5", NULL,
};

/* ---- mount (mount.c) ------------------------------------------------------- */

/*
 * Carpenter's midpoint displacement on the square [-1,1]^2 (z = 0 at the four
 * corners), subdivided `level` times: 2 * 4^level triangles. Edge and centre
 * heights are the mean of their parents plus a Gaussian displacement scaled
 * by the half side and the roughness of fractal dimension 2.2; the Gaussian
 * is seeded by a hash of the point's integer grid position, so neighbouring
 * squares compute identical shared heights (the terrain is watertight).
 * Then 4 glass spheres in a pyramid, after the SPD (which outputs them first;
 * here triangles come first, as in every scene).
 */
enum { MOUNT_LEVEL, MOUNT_SPHERES, MOUNT_SEGMENTS };

static const accel_param_def mount_params[] = {
    {.key = "level", .type = ACCEL_PARAM_INT, .def = "7", .min = 1, .max = 12,
     .help = "SPD size factor: 2*4^level terrain triangles (SPD default 6: 8192)"},
    {.key = "spheres", .type = ACCEL_PARAM_BOOL, .def = "1", .min = 0, .max = 1,
     .help = "1: the 4 spheres as true spheres; 0: as closed meshes of 12*segments^2 triangles"},
    {.key = "segments", .type = ACCEL_PARAM_INT, .def = "4", .min = 1, .max = 256,
     .help = "tessellated spheres: squares per cube-face edge (SPD default 4)"},
};

#define MOUNT_FRACTAL_DIMENSION 2.2
#define MOUNT_NO 21 /* "change MOUNTAIN_NO to get a different mountain" */

/*
 * lib_gauss_rand of the SPD: a Gaussian deviate by the polar method from a
 * small linear congruential generator (Numerical Recipes' M1 = 134456,
 * A1 = 8121, C1 = 28411) started at `seed`. For each of the 65536 seeds the
 * mountain can use the loop ends within 9 rounds and never meets r = 0
 * (checked exhaustively); the bound only guards the library.
 */
static double spd_gauss(long seed)
{
    const long m1 = 134456, a1 = 8121, c1 = 28411;
    long ix2 = seed;
    for (int iter = 0; iter < 10000; iter++) {
        long ix1 = (c1 + ix2 * a1) % m1;
        ix2 = (c1 + ix1 * a1) % m1;
        double v1 = ix1 * 2.0 / m1 - 1.0;
        double v2 = ix2 * 2.0 / m1 - 1.0;
        double r = v1 * v1 + v2 * v2;
        if (r < 1.0 && r > 0.0) return v1 * sqrt(-2.0 * log(r) / r);
    }
    return 0.0;
}

/*
 * Seed hash of a grid point. Levels up to 7 use the SPD's original function
 * (the one behind the published images and statistics, repetitive as its
 * README warns). It shifts left by 7 - level, undefined above level 7, so
 * finer mountains hash with the SplitMix64 finalizer instead; both keep 16
 * bits, as the original does.
 */
static long mount_hash(int a, int b, int level)
{
    if (level <= 7) {
        uint64_t ua = (uint64_t)a, ub = (uint64_t)b;
        return (long)(((ua << (23 - level)) + (ub << (15 - level)) + (ua << (7 - level))) & 0xffff);
    }
    scene_rng r = {((uint64_t)(uint32_t)a << 32 | (uint32_t)b) ^ ((uint64_t)level << 58)};
    return (long)(scene_rng_next(&r) & 0xffff);
}

typedef struct {
    int level;
    double fnum;      /* 2^level grid squares per side */
    double roughness;
    scene_builder *b;
    accel_error *err;
} mount_ctx;

/* The Gaussian displacement at grid point (x, y): a function of the point
 * alone, so both squares sharing an edge displace its midpoint alike. */
static double mount_gauss(const mount_ctx *m, int x, int y)
{
    return spd_gauss(MOUNT_NO + mount_hash(x, y, m->level));
}

static int mount_grow(mount_ctx *m, int width, int llx, int lly, double ll, double lr, double ur,
                      double ul)
{
    if (width == 1) {
        /* Corners at -1 + 2 * index / fnum: exact (fnum is a power of two). */
        float lx = (float)(-1.0 + llx * 2.0 / m->fnum);
        float rx = (float)(-1.0 + (llx + 1) * 2.0 / m->fnum);
        float ly = (float)(-1.0 + lly * 2.0 / m->fnum);
        float uy = (float)(-1.0 + (lly + 1) * 2.0 / m->fnum);
        vec3 p0 = v3(lx, ly, (float)ll), p1 = v3(rx, ly, (float)lr), p2 = v3(rx, uy, (float)ur),
             p3 = v3(lx, uy, (float)ul);
        int rc = scene_builder_add_tri(m->b, p0, p1, p2, m->err);
        return rc ? rc : scene_builder_add_tri(m->b, p2, p3, p0, m->err);
    }
    int half = width >> 1;
    double rise = (double)half * 2.0 / m->fnum * m->roughness;
    double lower = (ll + lr) / 2.0 + rise * mount_gauss(m, llx + half, lly);
    double right = (lr + ur) / 2.0 + rise * mount_gauss(m, llx + width, lly + half);
    double upper = (ur + ul) / 2.0 + rise * mount_gauss(m, llx + half, lly + width);
    double left = (ul + ll) / 2.0 + rise * mount_gauss(m, llx, lly + half);
    double middle =
        (ll + lr + ur + ul) / 4.0 + 1.4142136 * rise * mount_gauss(m, llx + half, lly + half);
    int rc = mount_grow(m, half, llx, lly, ll, lower, middle, left);
    if (rc == 0) rc = mount_grow(m, half, llx + half, lly, lower, lr, right, middle);
    if (rc == 0) rc = mount_grow(m, half, llx + half, lly + half, middle, right, ur, upper);
    if (rc == 0) rc = mount_grow(m, half, llx, lly + half, left, middle, upper, ul);
    return rc;
}

/* mount.c create_spheres: one sphere above the centre, three around below it. */
static void mount_sphere_centres(dvec3 centre, double radius, dvec3 out[4])
{
    dvec3 pt = {0.0, 0.0, radius * sqrt(3.0 / 2.0)};
    out[0] = (dvec3){centre.x + pt.x, centre.y + pt.y, centre.z + pt.z};
    spd_mat m;
    axis_rotation(m, dnormalize((dvec3){1.0, 1.0, 0.0}), acos(-1.0 / 3.0));
    dvec3 tilted = row_times(pt, m);
    for (int i = 0; i < 3; i++) {
        axis_rotation_xyz(m, 2, i * 2.0 * SPD_PI / 3.0);
        dvec3 p = row_times(tilted, m);
        out[1 + i] = (dvec3){p.x + centre.x, p.y + centre.y, p.z + centre.z};
    }
}

static int gen_mount(const double *values, scene_builder *b, accel_camera *cam, vec3 *light,
                     accel_error *err)
{
    int level = (int)values[MOUNT_LEVEL];
    int spheres = values[MOUNT_SPHERES] != 0.0;
    int segments = (int)values[MOUNT_SEGMENTS];
    uint64_t terrain = 2ull << (2 * level);
    uint64_t sphere_tris = spheres ? 0 : 4ull * 12ull * (uint64_t)segments * (uint64_t)segments;
    int rc = scene_check_count("mount", terrain + (spheres ? 4 : sphere_tris), err);
    if (rc == 0) rc = scene_builder_reserve_tris(b, (size_t)(terrain + sphere_tris), err);
    if (rc) return rc;

    double ratio = 2.0 / exp(log(2.0) / (MOUNT_FRACTAL_DIMENSION - 1.0));
    mount_ctx m = {level, (double)(1 << level), sqrt(ratio * ratio - 1.0), b, err};
    rc = mount_grow(&m, 1 << level, 0, 0, 0.0, 0.0, 0.0, 0.0);

    dvec3 centres[4];
    const double radius = 0.17;
    mount_sphere_centres((dvec3){-0.8, 0.8, 1.0}, radius, centres);
    scene_mesh mesh = {0};
    if (rc == 0 && !spheres) rc = scene_mesh_cube_sphere(&mesh, segments, err);
    for (int i = 0; i < 4 && rc == 0; i++)
        rc = spheres ? scene_builder_add_sphere(b, dvec3_to_float(centres[i]), (float)radius, err)
                     : scene_mesh_add(&mesh, b, centres[i], radius, err);
    scene_mesh_free(&mesh);
    *cam = spd_view(v3(-1.6f, 1.6f, 1.7f), v3(0, 0, 0), v3(0, 0, 1));
    *light = v3(-100, -100, 100);
    return rc;
}

const scene_generator scene_gen_mount = {
    "mount",
    "SPD mount: fractal midpoint-displacement terrain and 4 glass spheres (Haines 1987)",
    mount_params,
    sizeof mount_params / sizeof mount_params[0],
    gen_mount,
    "mount:level=5", NULL,
};
