/*
 * mesh.c - pieces every built-in generator shares (builtin.c, spd.c,
 * teapot.c): the primitive-count limit, quads, and the closed indexed
 * meshes (cube, cube-sphere, lat/long sphere) placed in double precision.
 *
 * The closed meshes compute every vertex from integers by one expression, so
 * a vertex shared by several triangles is bit-identical in all of them: the
 * meshes are watertight by construction, which the stability experiments
 * rely on.
 */
#include <math.h>
#include <stdlib.h>

#include "scene/mesh.h"

#define BUILTIN_PI 3.14159265358979323846

int scene_check_count(const char *scene, uint64_t count, accel_error *err)
{
    if (count > SCENE_BUILTIN_MAX_PRIMS)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "scene %s: %llu primitives exceed the limit of %llu; "
                          "choose a smaller size",
                          scene, (unsigned long long)count, SCENE_BUILTIN_MAX_PRIMS);
    return 0;
}

int scene_add_quad(scene_builder *b, vec3 a, vec3 c, vec3 d, vec3 e, accel_error *err)
{
    int rc = scene_builder_add_tri(b, a, c, d, err);
    return rc ? rc : scene_builder_add_tri(b, a, d, e, err);
}

/* ---- meshes ---------------------------------------------------------------- */

void scene_mesh_free(scene_mesh *m)
{
    free(m->verts);
    free(m->tris);
    m->verts = NULL;
    m->tris = NULL;
    m->vert_count = m->tri_count = 0;
}

static int mesh_alloc(scene_mesh *m, size_t verts, size_t tris, const char *what, accel_error *err)
{
    m->verts = NULL;
    m->tris = NULL;
    m->vert_count = m->tri_count = 0;
    if (verts > UINT32_MAX || verts > SIZE_MAX / sizeof *m->verts ||
        tris > SIZE_MAX / 3 / sizeof *m->tris)
        return accel_fail(err, ACCEL_ERR_RANGE, "%s: mesh too large (%zu vertices)", what, verts);
    m->verts = malloc(verts * sizeof *m->verts);
    m->tris = malloc(tris * 3 * sizeof *m->tris);
    if (!m->verts || !m->tris) {
        scene_mesh_free(m);
        return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory for %zu triangles", what, tris);
    }
    m->vert_count = verts;
    m->tri_count = tris;
    return 0;
}

/*
 * The surface of the lattice cube {0..n}^3: face f has axis f/2 and points
 * out along + (f even) or - (f odd). Its (n+1)^2 grid points are stored per
 * face; a point on a cube edge is stored by every face holding it, each time
 * computed by map() from the same integer triple, hence bit-identical.
 */
static int mesh_cube_lattice(scene_mesh *m, int n, int sphere, const char *what, accel_error *err)
{
    if (n < 1 || n > 4096)
        return accel_fail(err, ACCEL_ERR_RANGE, "%s: %d divisions per cube edge (1..4096)", what,
                          n);
    size_t side = (size_t)n + 1;
    int rc = mesh_alloc(m, 6 * side * side, 12 * (size_t)n * (size_t)n, what, err);
    if (rc) return rc;
    /* Lattice coordinate k as a cube coordinate in [-1, 1]; for the sphere
     * the angle is split evenly instead (equally spaced great circles). */
    double *coord = malloc(side * sizeof *coord);
    if (!coord) {
        scene_mesh_free(m);
        return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory", what);
    }
    for (int k = 0; k <= n; k++) {
        double c = (double)(2 * k - n) / n;
        coord[k] = sphere ? tan(0.25 * BUILTIN_PI * c) : c;
    }
    dvec3 *v = m->verts;
    uint32_t *t = m->tris;
    for (int f = 0; f < 6; f++) {
        int axis = f / 2, u = (axis + 1) % 3, w = (axis + 2) % 3, out = f % 2 == 0;
        uint32_t base = (uint32_t)(v - m->verts);
        for (int i = 0; i <= n; i++) {
            for (int j = 0; j <= n; j++) {
                int lattice[3];
                lattice[axis] = out ? n : 0;
                lattice[u] = i;
                lattice[w] = j;
                dvec3 p = {coord[lattice[0]], coord[lattice[1]], coord[lattice[2]]};
                if (sphere) {
                    double len = sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
                    p.x /= len, p.y /= len, p.z /= len;
                }
                *v++ = p;
            }
        }
        /* e_u x e_w = e_axis, so (i,j) -> (i+1,j) -> (i+1,j+1) turns
         * counter-clockwise seen from +axis; the - faces run it backwards. */
        for (int i = 0; i < n; i++) {
            for (int j = 0; j < n; j++) {
                uint32_t c00 = base + (uint32_t)(i * side + j), c01 = c00 + 1;
                uint32_t c10 = c00 + (uint32_t)side, c11 = c10 + 1;
                uint32_t quad[6] = {c00, c10, c11, c00, c11, c01};
                if (!out) quad[1] = c11, quad[2] = c10, quad[4] = c01, quad[5] = c11;
                for (int q = 0; q < 6; q++) *t++ = quad[q];
            }
        }
    }
    free(coord);
    return 0;
}

int scene_mesh_cube(scene_mesh *m, int n, accel_error *err)
{
    return mesh_cube_lattice(m, n, 0, "cube", err);
}

int scene_mesh_cube_sphere(scene_mesh *m, int n, accel_error *err)
{
    return mesh_cube_lattice(m, n, 1, "sphere", err);
}

int scene_mesh_uv_sphere(scene_mesh *m, int segments, accel_error *err)
{
    if (segments < 4 || segments > 65536)
        return accel_fail(err, ACCEL_ERR_RANGE, "uv sphere: %d segments (4..65536)", segments);
    size_t seg = (size_t)segments, bands = seg / 2;
    int rc = mesh_alloc(m, 2 + (bands - 1) * seg, 2 * seg * (bands - 1), "uv sphere", err);
    if (rc) return rc;
    /* Vertex 0 is the +z pole, then the rings b = 1..bands-1, then -z. */
    dvec3 *v = m->verts;
    *v++ = (dvec3){0.0, 0.0, 1.0};
    for (size_t b = 1; b < bands; b++) {
        double theta = BUILTIN_PI * (double)b / (double)bands;
        for (size_t k = 0; k < seg; k++) {
            double phi = 2.0 * BUILTIN_PI * (double)k / (double)seg;
            *v++ = (dvec3){sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
        }
    }
    *v = (dvec3){0.0, 0.0, -1.0};
    uint32_t south = (uint32_t)(m->vert_count - 1);
    uint32_t *t = m->tris;
    for (size_t b = 0; b < bands; b++) {
        for (size_t k = 0; k < seg; k++) {
            size_t k1 = (k + 1) % seg; /* the seam reuses the first meridian */
            /* ring b (above, unused for b = 0) and ring b + 1 (below) */
            size_t above = 1 + (b - 1) * seg, below = 1 + b * seg;
            uint32_t a0 = (uint32_t)(above + k), a1 = (uint32_t)(above + k1);
            uint32_t c0 = (uint32_t)(below + k), c1 = (uint32_t)(below + k1);
            if (b == 0) {
                *t++ = 0, *t++ = c0, *t++ = c1;
            } else if (b == bands - 1) {
                *t++ = a0, *t++ = south, *t++ = a1;
            } else {
                *t++ = a0, *t++ = c0, *t++ = c1;
                *t++ = a0, *t++ = c1, *t++ = a1;
            }
        }
    }
    return 0;
}

int scene_mesh_add(const scene_mesh *m, scene_builder *b, dvec3 centre, double scale,
                   accel_error *err)
{
    int rc = scene_builder_reserve_tris(b, m->tri_count, err);
    for (size_t i = 0; i < m->tri_count && rc == 0; i++) {
        vec3 p[3];
        for (int k = 0; k < 3; k++) {
            dvec3 v = m->verts[m->tris[3 * i + k]];
            p[k] = v3((float)(centre.x + scale * v.x), (float)(centre.y + scale * v.y),
                      (float)(centre.z + scale * v.z));
        }
        rc = scene_builder_add_tri(b, p[0], p[1], p[2], err);
    }
    return rc;
}

