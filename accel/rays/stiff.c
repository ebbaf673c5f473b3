/*
 * stiff.c - the stiff and extreme cases (see stiff.h).
 *
 * The closed meshes come from the built-in `cube` and `sphere` generators,
 * whose shared vertices are bit-identical: a watertight tracer must never
 * let a ray from inside escape through a shared edge or vertex. The
 * inside rays follow Woop et al. 2013 (a ray through an edge must hit one
 * of its two triangles) and Ize 2013 (box tests must be conservative, or
 * a vertex on a node boundary leaks).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"
#include "rays/stiff.h"
#include "rays/stiff_impl.h"

static int reserve(rays_set *r, size_t more, size_t *cap, accel_error *err)
{
    if (r->count + more <= *cap) return 0;
    size_t n = (*cap ? *cap * 2 : 1024);
    while (n < r->count + more) n *= 2;
    accel_ray *q = realloc(r->rays, n * sizeof *q);
    if (!q) return accel_fail(err, ACCEL_ERR_NOMEM, "stiff: out of memory for %zu rays", n);
    r->rays = q;
    *cap = n;
    return 0;
}

static void push(rays_set *r, vec3 o, vec3 d, float t_near, float t_far)
{
    accel_ray ray = {o.x, o.y, o.z, t_near, d.x, d.y, d.z, t_far};
    r->rays[r->count++] = ray;
}

/* Capacity bookkeeping lives beside the set while a case is built. */
typedef struct {
    rays_set *r;
    size_t cap;
    accel_error *err;
    int rc;
} ray_sink;

static void add(ray_sink *k, vec3 o, vec3 d, float t_near, float t_far)
{
    if (k->rc) return;
    k->rc = reserve(k->r, 1, &k->cap, k->err);
    if (!k->rc) push(k->r, o, d, t_near, t_far);
}

static vec3 target_of(const accel_scene *s, uint32_t prim, uint64_t seed, uint64_t i)
{
    const float *t = s->tris + 9 * (size_t)prim;
    int c = (int)(rays_rand(seed, i, 1) * 3);
    vec3 a = v3_load(t + 3 * c), b = v3_load(t + 3 * ((c + 1) % 3));
    /* Even: a vertex exactly; odd: an edge midpoint (exact when representable). */
    return (i & 1) ? v3_scale(v3_add(a, b), 0.5f) : a;
}

static void vertex_rays(ray_sink *k, const accel_scene *s, vec3 eye, size_t count, uint64_t seed)
{
    if (s->tri_count == 0 || s->live_count == 0) return;
    for (size_t i = 0; i < count; i++) {
        uint32_t prim = s->live[(size_t)(rays_rand(seed, i, 0) * s->live_count)];
        if (prim >= s->tri_count) continue;
        add(k, eye, v3_sub(target_of(s, prim, seed, i), eye), 0.0f, INFINITY);
    }
}

int stiff_add_vertex_rays(const accel_scene *s, vec3 eye, size_t count, uint64_t seed,
                          rays_set *r, accel_error *err)
{
    ray_sink k = {r, r->count, err, 0};
    vertex_rays(&k, s, eye, count, seed);
    return k.rc;
}

/* Eyes around the bounds (outside), deterministic. */
static vec3 outside_eye(box3 b, uint64_t seed, uint64_t i)
{
    vec3 c = box3_center(b);
    float r = v3_len(box3_extent(b));
    if (!(r > 0)) r = 1;
    float z = 2 * rays_rand(seed, i, 7) - 1, ph = 6.2831853f * rays_rand(seed, i, 8);
    float rr = sqrtf(fmaxf(0, 1 - z * z));
    return v3_add(c, v3_scale(v3(rr * cosf(ph), rr * sinf(ph), z), 1.5f * r));
}

/* A point of the central box of b (0.3 of its extent on each axis, centred):
 * inside every closed convex mesh of the cases whose bounds are b. The
 * cube fills b; the spheres' faces are at least cos(pi/12) > 0.96 of the
 * radius from the centre, and the box's corners at 0.15 sqrt(3) < 0.27. */
static vec3 inner_point(box3 b, uint64_t j)
{
    vec3 e = box3_extent(b);
    vec3 f = v3(rays_rand(55, j, 0) - 0.5f, rays_rand(55, j, 1) - 0.5f, rays_rand(55, j, 2) - 0.5f);
    return v3_add(box3_center(b), v3_mul(e, v3_scale(f, 0.3f)));
}

/* Vertex/edge rays from eyes * scale outside eyes, then leak rays from
 * inside: from `inside` (scale 1), and from scale - 1 more inner points. */
static void closed_mesh_rays(ray_sink *k, const accel_scene *s, vec3 inside, size_t per_eye,
                             int eyes, int scale, size_t *leak_begin)
{
    for (int e = 0; e < eyes * scale; e++)
        vertex_rays(k, s, outside_eye(s->bounds, 21, (uint64_t)e), per_eye, 100 + (uint64_t)e);
    *leak_begin = k->r->count;
    vertex_rays(k, s, inside, per_eye * 2, 77);
    for (int j = 1; j < scale; j++)
        vertex_rays(k, s, inner_point(s->bounds, (uint64_t)j), per_eye * 2, 1000 + (uint64_t)j);
}

/* Axis rays (+-x, +-y, +-z; other components +0 or -0) and cell-diagonal
 * rays starting on a lattice of planes at k/16 of the bounds: every
 * power-of-two grid up to 16 cells has its boundaries there, and the
 * centre planes are the spatial-median split planes of a BVH. */
static void lattice_rays(ray_sink *k, box3 b, int fine)
{
    const int n = 16 * fine; /* fine > 1: more planes, the k/16 ones among them */
    vec3 e = box3_extent(b);
    for (int axis = 0; axis < 3; axis++)
        for (int i = 0; i <= n; i += 2)
            for (int j = 0; j <= n; j += 2)
                for (int side = 0; side < 2; side++) {
                    float o[3], d[3] = {0, 0, 0};
                    const float lo[3] = {b.min.x, b.min.y, b.min.z};
                    const float ex[3] = {e.x, e.y, e.z};
                    int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
                    o[a1] = lo[a1] + ex[a1] * (float)i / (float)n;
                    o[a2] = lo[a2] + ex[a2] * (float)j / (float)n;
                    o[axis] = side ? lo[axis] + ex[axis] : lo[axis];
                    d[axis] = side ? -1.0f : 1.0f;
                    d[a1] = ((i / 2 + j / 2) & 1) ? -0.0f : 0.0f;
                    d[a2] = (i & 4) ? -0.0f : 0.0f;
                    add(k, v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
                    /* The same ray starting inside, exactly on the centre plane. */
                    o[axis] = lo[axis] + ex[axis] * 0.5f;
                    add(k, v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
                }
    /* Cell diagonals: direction = extent (the diagonal of every cell of any
     * n x n x n grid), from lattice corners, in the 8 sign combinations. */
    for (int i = 0; i <= n; i += 4)
        for (int j = 0; j <= n; j += 4)
            for (int sgn = 0; sgn < 8; sgn++) {
                vec3 d = v3(sgn & 1 ? -e.x : e.x, sgn & 2 ? -e.y : e.y, sgn & 4 ? -e.z : e.z);
                vec3 o = v3(sgn & 1 ? b.max.x : b.min.x, b.min.y + e.y * (float)i / (float)n,
                            b.min.z + e.z * (float)j / (float)n);
                if (sgn & 2) o.y = b.max.y - e.y * (float)i / (float)n;
                add(k, o, d, 0.0f, INFINITY);
            }
}

/* Rays lying in the planes of the cube's faces and along its edges. */
static void grazing_rays(ray_sink *k, box3 b, int fine)
{
    const int n = 8 * fine + 1;
    for (int f = 0; f < 6; f++) {
        int axis = f / 2;
        float plane = f & 1 ? v3_get(b.max, axis) : v3_get(b.min, axis);
        for (int i = 0; i < n; i++) {
            float t = (float)i / (float)(n - 1);
            float c[3] = {b.min.x + (b.max.x - b.min.x) * t, b.min.y + (b.max.y - b.min.y) * t,
                          b.min.z + (b.max.z - b.min.z) * t};
            c[axis] = plane;
            int a1 = (axis + 1) % 3;
            float o[3] = {c[0], c[1], c[2]}, d[3] = {0, 0, 0};
            o[a1] = v3_get(b.min, a1) - 1.0f;
            d[a1] = 1.0f;
            add(k, v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
        }
    }
}

/* Random rays starting inside random primitives' boxes. */
static void inside_box_rays(ray_sink *k, const accel_scene *s, size_t count)
{
    for (size_t i = 0; i < count && s->live_count; i++) {
        uint32_t prim = s->live[(size_t)(rays_rand(31, i, 0) * s->live_count)];
        box3 b = accel_prim_bounds(s, prim);
        vec3 e = box3_extent(b);
        vec3 o = v3_add(b.min, v3_mul(e, v3(rays_rand(31, i, 1), rays_rand(31, i, 2),
                                            rays_rand(31, i, 3))));
        float z = 2 * rays_rand(31, i, 4) - 1, ph = 6.2831853f * rays_rand(31, i, 5);
        float rr = sqrtf(fmaxf(0, 1 - z * z));
        add(k, o, v3(rr * cosf(ph), rr * sinf(ph), z), 0.0f, INFINITY);
    }
}

/* Rays starting on the surface of the box b (a closed cube's faces) next to
 * the edges of its n x n faces: offsets 0, 1e-30, 1e-20, 1e-10 and 1e-7
 * from a grid line (0 among them), random directions, half of them nearly
 * parallel to the face (a component of 1e-38, subnormal, or 1e-30) with a
 * negative t_near; one in 16 from outside with its whole direction scaled
 * by 2^-124 (1/d overflows). The float test loses such offsets while the box test
 * keeps them (a hostile-ray audit found rays like these leaking through
 * the BVHs' exact boxes, and a subnormal determinant giving t = NaN). */
static void surface_rays(ray_sink *k, box3 b, int n, size_t count)
{
    static const float offs[] = {0.0f, 1e-30f, -1e-30f, 1e-20f, -1e-20f, 1e-10f, -1e-10f, 1e-7f, -1e-7f};
    static const float tiny[] = {1e-38f, -1e-38f, 1e-30f, -1e-30f};
    const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    for (size_t i = 0; i < count; i++) {
        int axis = (int)(rays_rand(37, i, 0) * 3) % 3, side = rays_rand(37, i, 1) < 0.5f;
        float o[3], d[3];
        for (int a = 0; a < 3; a++) o[a] = lo[a] + (hi[a] - lo[a]) * rays_rand(37, i, 2 + (uint64_t)a);
        o[axis] = side ? hi[axis] : lo[axis];
        /* next to a grid line of the face, on one of its two axes */
        int a1 = (axis + 1 + (rays_rand(37, i, 5) < 0.5f)) % 3;
        float cell = (hi[a1] - lo[a1]) / (float)n;
        float line = lo[a1] + cell * floorf(rays_rand(37, i, 6) * (float)(n + 1));
        o[a1] = line + offs[(int)(rays_rand(37, i, 7) * 9) % 9];
        float z = 2 * rays_rand(37, i, 8) - 1, ph = 6.2831853f * rays_rand(37, i, 9);
        float rr = sqrtf(fmaxf(0, 1 - z * z));
        d[0] = rr * cosf(ph), d[1] = rr * sinf(ph), d[2] = z;
        float t_near = 0.0f;
        if (i & 1) { /* nearly parallel to the face */
            d[axis] = tiny[(i >> 1) & 3];
            t_near = -0.5f * rays_rand(37, i, 10);
        }
        if (i % 16 == 2) {
            /* From 3 outside the face, 0.01 aside, to the surface point,
             * with the whole direction scaled by 2^-124: the hit lies at
             * t ~ 2^124 and 1/d overflows on the 0.01 axis. */
            float q[3] = {o[0], o[1], o[2]};
            q[axis] += side ? 3.0f : -3.0f;
            q[a1] += (i & 4) ? 0.01f : -0.01f;
            for (int a = 0; a < 3; a++) d[a] = ldexpf(o[a] - q[a], -124), o[a] = q[a];
            t_near = 0.0f;
        }
        add(k, v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), t_near, INFINITY);
    }
}

typedef struct {
    const char *name;
    const char *what;
    const char *scene;      /* built-in spec, or NULL for a hand-made scene */
    int kind;               /* how rays are made, see stiff_case_make */
    float scale;            /* scene transform */
    float offset;
    float overlap;          /* RAYS_CONTACT: how far the mirror image reaches into the mesh */
} case_def;

enum { RAYS_CLOSED, RAYS_LATTICE, RAYS_GRAZING, RAYS_INSIDE_BOXES, RAYS_MIXED, RAYS_SURFACE,
       RAYS_CONTACT };

static const case_def cases[] = {
    {"cube_edges", "closed cube: rays exactly at shared vertices and edge midpoints; leak rays from inside",
     "cube:n=8", RAYS_CLOSED, 1, 0, 0},
    {"sphere_edges", "closed cube-sphere: vertex and edge rays; leak rays from inside",
     "sphere:segments=12", RAYS_CLOSED, 1, 0, 0},
    {"uvsphere_poles", "closed lat/long sphere (pole fans): vertex and edge rays; leak rays",
     "sphere:segments=24,tess=uv", RAYS_CLOSED, 1, 0, 0},
    {"sphere_far_1e4", "closed sphere moved to (1e4,1e4,1e4): vertex, edge and leak rays",
     "sphere:segments=12", RAYS_CLOSED, 1, 1e4f, 0},
    {"sphere_far_1e6", "closed sphere moved to (1e6,1e6,1e6): vertex, edge and leak rays",
     "sphere:segments=12", RAYS_CLOSED, 1, 1e6f, 0},
    {"cube_tiny_1e-4", "closed cube scaled by 1e-4", "cube:n=8", RAYS_CLOSED, 1e-4f, 0, 0},
    {"cube_huge_1e6", "closed cube scaled by 1e6", "cube:n=8", RAYS_CLOSED, 1e6f, 0, 0},
    {"soup_lattice", "axis rays (+-0 components) and cell-diagonal rays from cell boundaries and split planes",
     "soup:tris=3000", RAYS_LATTICE, 1, 0, 0},
    {"cube_lattice", "axis and diagonal rays on the closed cube: along faces, edges and vertex rows",
     "cube:n=4", RAYS_LATTICE, 1, 0, 0},
    {"cube_grazing", "rays lying in the cube's face planes and along its edges", "cube:n=4",
     RAYS_GRAZING, 1, 0, 0},
    {"cube_surface", "rays starting on the closed cube's faces 0 to 1e-7 from its edges, half of them "
     "nearly parallel to the face (a 1e-38 or 1e-30 component), some with directions of 1e-37", "cube:n=8", RAYS_SURFACE, 1, 0, 0},
    {"soup_inside_boxes", "random rays starting inside primitives' bounding boxes",
     "soup:tris=3000,size=3", RAYS_INSIDE_BOXES, 1, 0, 0},
    {"flat", "zero-thickness scene: every triangle in the plane z = 0, rays across and in it",
     NULL, RAYS_MIXED, 1, 0, 0},
    {"tiny_huge", "tiny (1e-4) and huge (1e4) triangles side by side", NULL, RAYS_MIXED, 1, 0, 0},
    {"degenerate", "zero-area and collinear triangles among normal ones (never to be hit)",
     NULL, RAYS_MIXED, 1, 0, 0},
    {"coincident", "many coincident and coplanar triangles (ties in t)", NULL, RAYS_MIXED, 1, 0, 0},
    {"same_centroid", "every triangle with the same centroid (binning must not divide by zero)",
     NULL, RAYS_MIXED, 1, 0, 0},
    /* Far from the origin in units of the scene's size (2): 1e5 x, where a
     * float's spacing is 1/64 of the sphere's radius, and 1e6 x for the
     * cube, whose vertices (multiples of 1/4) stay exact there. At 1e7 x
     * the spacing (2^-23 of 2e7: 2 units) exceeds the object itself:
     * every triangle collapses to a point and nothing is left to trace. */
    {"sphere_far_1e5x", "closed sphere moved by 1e5 x its size to (2e5,2e5,2e5): vertex, edge and "
     "leak rays", "sphere:segments=12", RAYS_CLOSED, 1, 2e5f, 0},
    {"cube_far_1e6x", "closed cube moved by 1e6 x its size to (2e6,2e6,2e6), its vertices still "
     "exact: vertex, edge and leak rays", "cube:n=8", RAYS_CLOSED, 1, 2e6f, 0},
    /* Contacts: the mesh and its mirror image through the plane x = p
     * (x' = 2p - x, the same operation on every copy of a shared vertex, so
     * the image is closed too). p = the mesh's largest x: touching (the
     * cubes share a face, the spheres a vertex row); p inside: they
     * interpenetrate. Leak rays from inside either mesh aim at its own
     * vertices and edges, half of them next to the contact plane. */
    {"cubes_touching", "two closed cubes sharing a face (coincident triangles): leak and shadow "
     "rays from inside either through the contact face's vertices and edges", "cube:n=4",
     RAYS_CONTACT, 1, 0, 0},
    {"cubes_interpenetrating", "two closed cubes overlapping by 0.3 of their size (coplanar "
     "overlapping faces): leak and shadow rays", "cube:n=4", RAYS_CONTACT, 1, 0, 0.15f},
    {"spheres_touching", "two closed spheres touching at their poles' vertex rows: leak and "
     "shadow rays", "sphere:segments=12", RAYS_CONTACT, 1, 0, 0},
    {"spheres_interpenetrating", "two closed spheres overlapping by 0.3 of their size: leak and "
     "shadow rays", "sphere:segments=12", RAYS_CONTACT, 1, 0, 0.15f},
};

int stiff_case_count(void) { return (int)(sizeof cases / sizeof cases[0]); }

void stiff_case_free(stiff_case *c)
{
    scene_free(&c->scene);
    rays_free(&c->rays);
    rays_free(&c->shadow);
}

/* Hand-made scenes for the RAYS_MIXED cases. */
static int make_special(const char *name, scene_builder *b, accel_error *err)
{
    int rc = 0;
    uint64_t seed = 5;
    if (!strcmp(name, "flat")) {
        for (int i = 0; rc == 0 && i < 2000; i++) {
            vec3 a = v3(rays_rand(seed, (uint64_t)i, 0), rays_rand(seed, (uint64_t)i, 1), 0);
            vec3 c = v3_add(a, v3(0.05f * rays_rand(seed, (uint64_t)i, 2), 0.03f, 0));
            vec3 d = v3_add(a, v3(-0.02f, 0.05f * rays_rand(seed, (uint64_t)i, 3), 0));
            rc = scene_builder_add_tri(b, a, c, d, err);
        }
    } else if (!strcmp(name, "tiny_huge")) {
        rc = scene_builder_add_tri(b, v3(-1e4f, -1e4f, 0), v3(1e4f, -1e4f, 0), v3(0, 1e4f, 0), err);
        for (int i = 0; rc == 0 && i < 2000; i++) {
            vec3 a = v3(2 * rays_rand(seed, (uint64_t)i, 0) - 1, 2 * rays_rand(seed, (uint64_t)i, 1) - 1,
                        1e-3f + rays_rand(seed, (uint64_t)i, 2));
            rc = scene_builder_add_tri(b, a, v3_add(a, v3(1e-4f, 0, 0)), v3_add(a, v3(0, 1e-4f, 1e-5f)), err);
        }
        for (int i = 0; rc == 0 && i < 4; i++)
            rc = scene_builder_add_tri(b, v3(-1e4f, 3e3f * (float)i, -5e3f), v3(1e4f, 3e3f * (float)i, -5e3f),
                                       v3(0, 3e3f * (float)i, 1e4f), err);
    } else if (!strcmp(name, "degenerate")) {
        for (int i = 0; rc == 0 && i < 1500; i++) {
            vec3 a = v3(rays_rand(seed, (uint64_t)i, 0), rays_rand(seed, (uint64_t)i, 1),
                        rays_rand(seed, (uint64_t)i, 2));
            vec3 e = v3(0.05f, 0.02f, 0.01f);
            switch (i % 3) {
            case 0: rc = scene_builder_add_tri(b, a, a, v3_add(a, e), err); break;          /* repeated vertex */
            case 1: rc = scene_builder_add_tri(b, a, v3_add(a, e), v3_add(a, v3_scale(e, 2)), err); break; /* collinear */
            default: rc = scene_builder_add_tri(b, a, v3_add(a, e), v3_add(a, v3(0, 0.04f, 0)), err); break;
            }
        }
    } else if (!strcmp(name, "coincident")) {
        for (int i = 0; rc == 0 && i < 400; i++) {
            vec3 a = v3(rays_rand(seed, (uint64_t)(i / 8), 0), rays_rand(seed, (uint64_t)(i / 8), 1), 0.5f);
            rc = scene_builder_add_tri(b, a, v3_add(a, v3(0.2f, 0, 0)), v3_add(a, v3(0, 0.2f, 0)), err);
        }
        for (int i = 0; rc == 0 && i < 200; i++) /* coplanar, overlapping, different shapes */
            rc = scene_builder_add_tri(b, v3(0, 0, 0.25f), v3(1, 0.005f * (float)i, 0.25f),
                                       v3(0.005f * (float)i, 1, 0.25f), err);
    } else if (!strcmp(name, "same_centroid")) {
        for (int i = 0; rc == 0 && i < 1000; i++) {
            float ang = 6.2831853f * (float)i / 1000.0f, r = 0.2f + 0.8f * rays_rand(seed, (uint64_t)i, 0);
            vec3 u = v3(cosf(ang), sinf(ang), 0.3f * rays_rand(seed, (uint64_t)i, 1));
            vec3 w = v3(-sinf(ang) * 0.5f, cosf(ang) * 0.5f, 1);
            /* Vertices p, q, -(p+q) around the origin: centroid exactly 0. */
            vec3 p = v3_scale(u, r), q = v3_scale(w, r * 0.7f);
            rc = scene_builder_add_tri(b, p, q, v3_scale(v3_add(p, q), -1.0f), err);
        }
    }
    return rc;
}

/* The mesh `spec` and its mirror image through x = max x - overlap * size
 * (stiff.c's cases table says why it stays closed); *split = the first
 * triangle of the image. */
static int make_contact(const case_def *d, accel_scene *out, uint32_t *split, float *plane,
                        accel_error *err)
{
    accel_scene base;
    int rc = scene_create(d->scene, &base, err);
    if (rc) return rc;
    float p = base.bounds.max.x - d->overlap * (base.bounds.max.x - base.bounds.min.x), p2 = p + p;
    scene_builder b = {0};
    for (int m = 0; rc == 0 && m < 2; m++)
        for (uint32_t t = 0; rc == 0 && t < base.tri_count; t++) {
            vec3 v[3];
            for (int j = 0; j < 3; j++) {
                v[j] = v3_load(base.tris + 9 * (size_t)t + 3 * j);
                if (m) v[j].x = p2 - v[j].x;
            }
            rc = scene_builder_add_tri(&b, v[0], v[1], v[2], err);
        }
    if (rc == 0) rc = scene_finish(&b, d->name, out, err);
    *split = base.tri_count;
    *plane = p;
    scene_builder_free(&b);
    scene_free(&base);
    return rc;
}

/* Leak rays of a contact case: from `scale` inner points of each mesh to
 * its own vertices and edge midpoints, every other one on a triangle with
 * a vertex within 0.25 of the mesh's size from the contact plane. */
static void contact_rays(ray_sink *k, const accel_scene *s, uint32_t split, float plane,
                         size_t count, int scale)
{
    uint8_t *live = calloc(s->tri_count ? s->tri_count : 1, 1);
    uint32_t *near = malloc((s->tri_count ? s->tri_count : 1) * sizeof *near);
    uint32_t *all = malloc((s->tri_count ? s->tri_count : 1) * sizeof *all);
    if (!live || !near || !all) {
        k->rc = accel_fail(k->err, ACCEL_ERR_NOMEM, "stiff: out of memory");
        count = 0;
    }
    for (uint32_t i = 0; count && i < s->live_count; i++)
        if (s->live[i] < s->tri_count) live[s->live[i]] = 1;
    for (int m = 0; count && m < 2; m++) {
        uint32_t lo = m ? split : 0, hi = m ? s->tri_count : split, nn = 0, na = 0;
        box3 b = box3_empty();
        for (uint32_t t = lo; t < hi; t++)
            for (int j = 0; j < 3; j++) b = box3_grow(b, v3_load(s->tris + 9 * (size_t)t + 3 * j));
        float reach = 0.25f * (b.max.x - b.min.x);
        for (uint32_t t = lo; t < hi; t++) {
            if (!live[t]) continue;
            all[na++] = t;
            const float *v = s->tris + 9 * (size_t)t;
            if (fabsf(v[0] - plane) <= reach || fabsf(v[3] - plane) <= reach || fabsf(v[6] - plane) <= reach)
                near[nn++] = t;
        }
        if (!na) continue;
        for (int j = 0; j < scale; j++) {
            vec3 o = inner_point(b, (uint64_t)(2 * j + m) + 7);
            uint64_t seed = 300 + (uint64_t)(2 * j + m);
            for (size_t i = 0; i < count; i++) {
                int pick_near = (i & 2) && nn;
                uint32_t t = pick_near ? near[(size_t)(rays_rand(seed, i, 0) * nn) % nn]
                                       : all[(size_t)(rays_rand(seed, i, 0) * na) % na];
                add(k, o, v3_sub(target_of(s, t, seed, i), o), 0.0f, INFINITY);
            }
        }
    }
    free(live);
    free(near);
    free(all);
}

static int make_scene(const case_def *d, stiff_case *c, uint32_t *split, float *plane,
                      accel_error *err)
{
    if (d->kind == RAYS_CONTACT) return make_contact(d, &c->scene, split, plane, err);
    int rc;
    if (d->scene) {
        accel_scene base;
        rc = scene_create(d->scene, &base, err);
        if (rc || (d->scale == 1.0f && d->offset == 0.0f)) {
            c->scene = base;
            return rc;
        }
        rc = scene_transform(&base, d->scale, v3(d->offset, d->offset, d->offset), &c->scene, err);
        scene_free(&base);
        return rc;
    }
    scene_builder b = {0};
    rc = make_special(d->name, &b, err);
    if (rc == 0) rc = scene_finish(&b, d->name, &c->scene, err);
    scene_builder_free(&b);
    return rc;
}

/* Case i with every random count times `scale` and lattices ceil(sqrt(scale))
 * times finer; scale 1 is the base case (no repeats dropped). */
static int make_scaled(int i, int scale, stiff_case *c, accel_error *err)
{
    memset(c, 0, sizeof *c);
    if (i < 0 || i >= stiff_case_count())
        return accel_fail(err, ACCEL_ERR_RANGE, "stiff case %d out of range", i);
    const case_def *d = &cases[i];
    snprintf(c->name, sizeof c->name, "%s", d->name);
    snprintf(c->what, sizeof c->what, "%s", d->what);
    uint32_t split = 0;
    float plane = 0;
    int rc = make_scene(d, c, &split, &plane, err);
    if (rc) return rc;
    int fine = (int)ceil(sqrt((double)scale));
    size_t sc = (size_t)scale;
    ray_sink k = {&c->rays, 0, err, 0};
    const accel_scene *s = &c->scene;
    c->leak_begin = SIZE_MAX;
    switch (d->kind) {
    case RAYS_CLOSED:
        closed_mesh_rays(&k, s, box3_center(s->bounds), 400, 4, scale, &c->leak_begin);
        break;
    case RAYS_CONTACT:
        for (int e = 0; e < 4 * scale; e++)
            vertex_rays(&k, s, outside_eye(s->bounds, 21, (uint64_t)e), 400, 100 + (uint64_t)e);
        c->leak_begin = k.r->count;
        contact_rays(&k, s, split, plane, 400, scale);
        break;
    case RAYS_LATTICE:
        lattice_rays(&k, s->bounds, fine);
        break;
    case RAYS_GRAZING:
        grazing_rays(&k, s->bounds, fine);
        lattice_rays(&k, s->bounds, fine);
        break;
    case RAYS_INSIDE_BOXES:
        inside_box_rays(&k, s, 2000 * sc);
        break;
    case RAYS_SURFACE:
        surface_rays(&k, s->bounds, 8, 4000 * sc);
        break;
    case RAYS_MIXED:
        for (int e = 0; e < 3 * scale; e++) vertex_rays(&k, s, outside_eye(s->bounds, 3, (uint64_t)e), 300, 40 + (uint64_t)e);
        lattice_rays(&k, s->bounds, fine);
        inside_box_rays(&k, s, 500 * sc);
        break;
    }
    if (c->leak_begin == SIZE_MAX) c->leak_begin = c->rays.count;
    rc = k.rc;
    if (rc == 0 && scale > 1) rc = stiff_dedupe(c, err);
    if (rc == 0 && (d->kind == RAYS_CLOSED || d->kind == RAYS_CONTACT)) rc = stiff_make_shadow(c, err);
    if (rc) stiff_case_free(c);
    return rc;
}

int stiff_case_make(int i, stiff_case *c, accel_error *err) { return make_scaled(i, 1, c, err); }

int stiff_case_make_n(int i, size_t min_rays, stiff_case *c, accel_error *err)
{
    int scale = 1;
    for (;;) {
        int rc = make_scaled(i, scale, c, err);
        if (rc || c->rays.count >= min_rays || scale >= (1 << 20)) return rc;
        double f = (double)min_rays / (double)(c->rays.count ? c->rays.count : 1);
        int next = (int)ceil((double)scale * f * 1.05);
        stiff_case_free(c);
        scale = next > scale ? next : scale + 1;
    }
}

int stiff_case_index(const char *name)
{
    for (int i = 0; i < stiff_case_count(); i++)
        if (!strcmp(cases[i].name, name)) return i;
    return -1;
}

int stiff_case_closed(accel_scene *s, const char *name, size_t min_rays, stiff_case *c,
                      accel_error *err)
{
    memset(c, 0, sizeof *c);
    c->scene = *s;
    memset(s, 0, sizeof *s);
    snprintf(c->name, sizeof c->name, "%s", name);
    snprintf(c->what, sizeof c->what, "vertex and edge rays from outside, leak rays from inside");
    int scale = 1, rc = 0;
    for (;;) {
        ray_sink k = {&c->rays, 0, err, 0};
        closed_mesh_rays(&k, &c->scene, box3_center(c->scene.bounds), 400, 4, scale, &c->leak_begin);
        rc = k.rc;
        if (rc == 0 && scale > 1) rc = stiff_dedupe(c, err);
        if (rc || c->rays.count >= min_rays || scale >= (1 << 20)) break;
        double f = (double)min_rays / (double)(c->rays.count ? c->rays.count : 1);
        int next = (int)ceil((double)scale * f * 1.05);
        rays_free(&c->rays);
        scale = next > scale ? next : scale + 1;
    }
    if (rc == 0) rc = stiff_make_shadow(c, err);
    if (rc) stiff_case_free(c);
    return rc;
}

int stiff_case_from_scene(const char *spec, int closed, stiff_case *c, accel_error *err)
{
    memset(c, 0, sizeof *c);
    int rc = scene_create(spec, &c->scene, err);
    if (rc) return rc;
    snprintf(c->name, sizeof c->name, "%s", c->scene.name);
    snprintf(c->what, sizeof c->what, "vertex and edge rays from outside%s",
             closed ? ", leak rays from inside" : "");
    ray_sink k = {&c->rays, 0, err, 0};
    if (closed)
        closed_mesh_rays(&k, &c->scene, box3_center(c->scene.bounds), 500, 4, 1, &c->leak_begin);
    else {
        for (int e = 0; e < 4; e++)
            vertex_rays(&k, &c->scene, outside_eye(c->scene.bounds, 21, (uint64_t)e), 500, 100 + (uint64_t)e);
        vertex_rays(&k, &c->scene, c->scene.camera.eye, 1000, 99);
        c->leak_begin = c->rays.count;
    }
    if (k.rc) stiff_case_free(c);
    return k.rc;
}
