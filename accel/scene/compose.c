/*
 * compose.c - the flattener of scenes of many meshes, and 3x4 transforms
 * (see compose.h).
 *
 * Every world coordinate of the flattened scene is accel_xform_vertex of an
 * object-space vertex (accel.h): double precision with fused multiply-adds,
 * rounded to float once. Nothing else in the project computes a world
 * vertex another way, so a two-level kind recomputing a triangle gets the
 * flattened one bit for bit.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene/compose.h"

#define COMPOSE_PI 3.14159265358979323846

/* ---- transforms ------------------------------------------------------------ */

void scene_xform_identity(double m[12])
{
    static const double id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    memcpy(m, id, sizeof id);
}

void scene_xform_then(double m[12], const double t[12])
{
    double r[12];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 4; j++) {
            double s = t[4 * i] * m[j] + t[4 * i + 1] * m[4 + j] + t[4 * i + 2] * m[8 + j];
            r[4 * i + j] = j == 3 ? s + t[4 * i + 3] : s;
        }
    }
    memcpy(m, r, sizeof r);
}

void scene_xform_translate(double t[12], double x, double y, double z)
{
    scene_xform_identity(t);
    t[3] = x, t[7] = y, t[11] = z;
}

void scene_xform_scale(double t[12], double sx, double sy, double sz)
{
    scene_xform_identity(t);
    t[0] = sx, t[5] = sy, t[10] = sz;
}

int scene_xform_rotate(double t[12], double ax, double ay, double az, double deg)
{
    double len = sqrt(ax * ax + ay * ay + az * az);
    if (!(len > 0.0) || !isfinite(len) || !isfinite(deg)) return 1;
    double x = ax / len, y = ay / len, z = az / len;
    double c, s, r = fmod(deg, 360.0);
    if (fmod(r, 90.0) == 0.0) {
        /* Quarter turns exactly: cos(pi/2) in double is 6e-17, not 0, and
         * would move a rotated vertex off the one its neighbour shares. */
        static const double cs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
        int q = ((int)(r / 90.0) % 4 + 4) % 4;
        c = cs[q][0], s = cs[q][1];
    } else {
        double rad = r * (COMPOSE_PI / 180.0);
        c = cos(rad), s = sin(rad);
    }
    double k = 1.0 - c;
    scene_xform_identity(t);
    t[0] = c + x * x * k, t[1] = x * y * k - z * s, t[2] = x * z * k + y * s;
    t[4] = y * x * k + z * s, t[5] = c + y * y * k, t[6] = y * z * k - x * s;
    t[8] = z * x * k - y * s, t[9] = z * y * k + x * s, t[10] = c + z * z * k;
    return 0;
}

double scene_xform_det(const double m[12])
{
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
}

int scene_xform_invert(const double m[12], double inv[12])
{
    for (int i = 0; i < 12; i++)
        if (!isfinite(m[i])) return 1;
    double det = scene_xform_det(m);
    double rows = 1.0;
    for (int i = 0; i < 3; i++)
        rows *= sqrt(m[4 * i] * m[4 * i] + m[4 * i + 1] * m[4 * i + 1] + m[4 * i + 2] * m[4 * i + 2]);
    if (!(fabs(det) > 0x1p-40 * rows) || !isfinite(det)) return 1;
    double c[9] = {
        m[5] * m[10] - m[6] * m[9], m[2] * m[9] - m[1] * m[10], m[1] * m[6] - m[2] * m[5],
        m[6] * m[8] - m[4] * m[10], m[0] * m[10] - m[2] * m[8], m[2] * m[4] - m[0] * m[6],
        m[4] * m[9] - m[5] * m[8], m[1] * m[8] - m[0] * m[9], m[0] * m[5] - m[1] * m[4],
    };
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) inv[4 * i + j] = c[3 * i + j] / det;
        inv[4 * i + 3] = -(inv[4 * i] * m[3] + inv[4 * i + 1] * m[7] + inv[4 * i + 2] * m[11]);
    }
    for (int i = 0; i < 12; i++)
        if (!isfinite(inv[i])) return 1;
    return 0;
}

/* ---- composing ------------------------------------------------------------- */

void scene_compose_free(scene_compose *c)
{
    scene_instances_free(&c->set);
    free(c->mesh_vert_bounds);
    memset(c, 0, sizeof *c);
}

int scene_compose_add_mesh(scene_compose *c, accel_scene *mesh, uint32_t *index, accel_error *err)
{
    if (mesh->sphere_count)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "%s holds %u spheres: a scene places triangle meshes only", mesh->name,
                          mesh->sphere_count);
    if (c->set.mesh_count >= UINT32_MAX - 1)
        return accel_fail(err, ACCEL_ERR_RANGE, "too many meshes");
    if (c->set.mesh_count == c->mesh_cap) {
        uint32_t cap = !c->mesh_cap ? 8 : c->mesh_cap > UINT32_MAX / 2 ? UINT32_MAX - 1
                                                                       : c->mesh_cap * 2;
        accel_scene *m = realloc(c->set.meshes, (size_t)cap * sizeof *m);
        if (!m) return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for %u meshes", cap);
        c->set.meshes = m;
        box3 *b = realloc(c->mesh_vert_bounds, (size_t)cap * sizeof *b);
        if (!b) return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for %u meshes", cap);
        c->mesh_vert_bounds = b;
        c->mesh_cap = cap;
    }
    if (mesh->instances) {
        /* A scene of many meshes used as one mesh: its flattened triangles. */
        scene_instances_free(mesh->instances);
        free(mesh->instances);
        mesh->instances = NULL;
    }
    box3 vb = box3_empty();
    for (size_t i = 0; i < 3 * (size_t)mesh->tri_count; i++) vb = box3_grow(vb, v3_load(mesh->tris + 3 * i));
    *index = c->set.mesh_count;
    c->mesh_vert_bounds[*index] = vb;
    c->set.meshes[c->set.mesh_count++] = *mesh;
    memset(mesh, 0, sizeof *mesh);
    return 0;
}

/* Whether every transformed vertex of mesh `mi` is a finite float. A bound
 * from the vertex box settles almost every case without touching a vertex. */
static int xform_fits_float(const scene_compose *c, uint32_t mi, const double m[12])
{
    box3 vb = c->mesh_vert_bounds[mi];
    if (box3_is_empty(vb)) return 1;
    double ext[3] = {fmax(fabs(vb.min.x), fabs(vb.max.x)), fmax(fabs(vb.min.y), fabs(vb.max.y)),
                     fmax(fabs(vb.min.z), fabs(vb.max.z))};
    double bound = 0.0;
    for (int r = 0; r < 3; r++) {
        const double *row = m + 4 * r;
        bound = fmax(bound, fabs(row[0]) * ext[0] + fabs(row[1]) * ext[1] + fabs(row[2]) * ext[2] +
                                fabs(row[3]));
    }
    if (bound < 0.5 * FLT_MAX) return 1;
    const accel_scene *mesh = &c->set.meshes[mi];
    for (size_t i = 0; i < 3 * (size_t)mesh->tri_count; i++) {
        float w[3];
        accel_xform_vertex(m, mesh->tris + 3 * i, w);
        if (!isfinite(w[0]) || !isfinite(w[1]) || !isfinite(w[2])) return 0;
    }
    return 1;
}

/* Bytes of the flattened scene per primitive: 9 floats and a live id. */
#define SCENE_FLAT_BYTES 40ull

/* Half the physical memory in bytes (0 when unknown: no limit). */
static uint64_t scene_compose_memory_limit(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || size <= 0) return 0;
    return (uint64_t)pages * (uint64_t)size / 2;
}

int scene_compose_add_instance(scene_compose *c, uint32_t mesh, const double m[12],
                               accel_error *err)
{
    if (mesh >= c->set.mesh_count)
        return accel_fail(err, ACCEL_ERR_RANGE, "mesh index %u out of range", mesh);
    accel_instance in;
    memset(&in, 0, sizeof in);
    for (int i = 0; i < 12; i++)
        if (!isfinite(m[i]))
            return accel_fail(err, ACCEL_ERR_RANGE, "the transform has a non-finite entry (%g)",
                              m[i]);
    if (scene_xform_invert(m, in.inverse))
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "the transform is singular (determinant %g): it has no inverse",
                          scene_xform_det(m));
    uint64_t limit = c->max_prims ? c->max_prims : SCENE_COMPOSE_MAX_PRIMS;
    if (limit > SCENE_COMPOSE_MAX_PRIMS) limit = SCENE_COMPOSE_MAX_PRIMS;
    uint64_t n = c->set.meshes[mesh].prim_count;
    if (c->prim_total + n > limit)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "the scene would hold %llu primitives, over the limit of %llu",
                          (unsigned long long)(c->prim_total + n), (unsigned long long)limit);
    /* The flattened scene holds every instance's triangles (36 bytes and an
     * id each): a few instance lines must not ask for more than the machine
     * has (30,000 instances of a 120k-triangle mesh asked for 150 GB and
     * failed later, naming no file). Refused here, where the caller names
     * the line, past half the physical memory. */
    uint64_t mem = scene_compose_memory_limit();
    if (mem && (c->prim_total + n) * SCENE_FLAT_BYTES > mem)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "the flattened scene would hold %llu primitives (%.1f GiB), over half "
                          "of this machine's memory (%.1f GiB)",
                          (unsigned long long)(c->prim_total + n),
                          (double)((c->prim_total + n) * SCENE_FLAT_BYTES) / 1073741824.0,
                          (double)mem / 1073741824.0);
    if (!xform_fits_float(c, mesh, m))
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "the transform moves vertices of %s beyond the float range",
                          c->set.meshes[mesh].name);
    if (c->set.instance_count == c->instance_cap) {
        uint32_t cap = c->instance_cap ? c->instance_cap * 2 : 16;
        if (cap < c->instance_cap || (uint64_t)cap * sizeof in > SIZE_MAX / 2)
            return accel_fail(err, ACCEL_ERR_RANGE, "too many instances");
        accel_instance *p = realloc(c->set.instances, (size_t)cap * sizeof *p);
        if (!p) return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for %u instances", cap);
        c->set.instances = p;
        c->instance_cap = cap;
    }
    in.mesh = mesh;
    in.base = (uint32_t)c->prim_total;
    memcpy(in.xform, m, sizeof in.xform);
    in.bounds = box3_empty();
    c->set.instances[c->set.instance_count++] = in;
    c->prim_total += n;
    return 0;
}

int scene_compose_finish(scene_compose *c, const char *name, accel_scene *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    scene_builder b = {0};
    int rc = scene_builder_reserve_tris(&b, (size_t)c->prim_total, err);
    for (uint32_t k = 0; rc == 0 && k < c->set.instance_count; k++) {
        const accel_instance *in = &c->set.instances[k];
        const accel_scene *mesh = &c->set.meshes[in->mesh];
        if (mesh->tri_count == 0) continue;
        float *dst = b.tris + 9 * b.tri_count;
        for (size_t i = 0; i < 3 * (size_t)mesh->tri_count; i++)
            accel_xform_vertex(in->xform, mesh->tris + 3 * i, dst + 3 * i);
        b.tri_count += mesh->tri_count;
    }
    accel_instances *set = NULL;
    if (rc == 0) {
        set = malloc(sizeof *set);
        if (!set) rc = accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory", name);
    }
    if (rc == 0) rc = scene_finish(&b, name, out, err);
    scene_builder_free(&b);
    if (rc) {
        free(set);
        return rc;
    }
    for (uint32_t k = 0; k < c->set.instance_count; k++) {
        accel_instance *in = &c->set.instances[k];
        uint32_t n = c->set.meshes[in->mesh].tri_count;
        box3 bb = box3_empty();
        for (size_t i = 0; i < 3 * (size_t)n; i++)
            bb = box3_grow(bb, v3_load(out->tris + 9 * (size_t)in->base + 3 * i));
        in->bounds = bb;
    }
    *set = c->set;
    memset(&c->set, 0, sizeof c->set);
    out->instances = set;
    scene_compose_free(c);
    return 0;
}
