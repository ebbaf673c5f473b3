/*
 * test_grid_overlap.c - the primitive/box overlap tests of grid/overlap.h
 * (triangle/box SAT, slab clipping, sphere/box) on touching, grazing and
 * degenerate cases and random triangles, and the grid build's cell
 * membership against the SAT on every padded cell.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid/grid.h"
#include "grid/overlap.h"
#include "support.h"

/* ---- overlap tests --------------------------------------------------------------- */

static int tri_box(float ax, float ay, float az, float bx, float by, float bz, float cx, float cy,
                   float cz, double lo, double hi)
{
    const float t[9] = {ax, ay, az, bx, by, bz, cx, cy, cz};
    const double l[3] = {lo, lo, lo}, h[3] = {hi, hi, hi};
    return accel_overlap_tri_box(t, l, h);
}

TEST(grid_overlap_triangle_box)
{
    /* Inside, crossing, containing. */
    CHECK(tri_box(0.2f, 0.2f, 0.2f, 0.8f, 0.2f, 0.5f, 0.5f, 0.8f, 0.7f, 0, 1));
    CHECK(tri_box(-5, -5, 0.5f, 5, -5, 0.5f, 0, 5, 0.5f, 0, 1));
    /* Touching a face exactly (lying in the plane x = 1), and just off it. */
    CHECK(tri_box(1, 0.2f, 0.2f, 1, 0.8f, 0.2f, 1, 0.5f, 0.9f, 0, 1));
    CHECK(!tri_box(1.001f, 0.2f, 0.2f, 1.001f, 0.8f, 0.2f, 1.001f, 0.5f, 0.9f, 0, 1));
    /* Touching a face with one vertex only, from outside. */
    CHECK(tri_box(1, 0.5f, 0.5f, 2, 0.2f, 0.5f, 2, 0.8f, 0.6f, 0, 1));
    /* Touching an edge with an edge (segment crossing the box edge x=1,y=1). */
    CHECK(tri_box(1, 1, 0.5f, 2, 1, 0.5f, 1.5f, 2, 0.5f, 0, 1));
    CHECK(tri_box(1.5f, 0.5f, 0.5f, 0.5f, 1.5f, 0.5f, 2, 2, 0.5f, 0,
                  1)); /* edge x+y=2 through corner (1,1) */
    /* Touching a corner with a vertex, and 1e-4 away. */
    CHECK(tri_box(1, 1, 1, 2, 1.5f, 1.2f, 1.5f, 2, 1.3f, 0, 1));
    CHECK(!tri_box(1.0001f, 1.0001f, 1.0001f, 2, 1.5f, 1.2f, 1.5f, 2, 1.3f, 0, 1));
    /* Bounding boxes overlap but an edge axis separates (edge x+y = 2.5). */
    CHECK(!tri_box(0.9f, 1.6f, 0.5f, 1.6f, 0.9f, 0.5f, 1.6f, 1.6f, 0.5f, 0, 1));
    /* ... and with the edge moved to x+y = 2 it touches the corner (1,1). */
    CHECK(tri_box(0.9f, 1.1f, 0.5f, 1.1f, 0.9f, 0.5f, 1.6f, 1.6f, 0.5f, 0, 1));
    /* Bounding boxes touch at the corner but the plane x+y+z = 3.2 separates. */
    CHECK(!tri_box(1.2f, 1, 1, 1, 1.2f, 1, 1, 1, 1.2f, 0, 1));
    CHECK(tri_box(1, 1, 1, 1.2f, 1, 0.8f, 0.9f, 1.1f, 1.0f, 0, 1)); /* plane through the corner */
    /* Needle and degenerate triangles along the box edge or through the box. */
    CHECK(tri_box(0.2f, 1, 1, 0.8f, 1, 1, 0.5f, 1, 1.0000001f, 0, 1));
    CHECK(tri_box(-1, 0.5f, 0.5f, 2, 0.5f, 0.5f, 3, 0.5f, 0.5f, 0,
                  1)); /* collinear segment through */
    CHECK(!tri_box(-1, 1.5f, 0.5f, 2, 1.5f, 0.5f, 3, 1.5f, 0.5f, 0, 1));
    CHECK(tri_box(1.2f, -0.5f, 0.5f, -0.5f, 1.2f, 0.5f, 1.2f, -0.5f, 0.5f, 0, 1)); /* x+y = 0.7 */
    /* A zero-size box (a point): inside the triangle, on its edge, beside it. */
    CHECK(tri_box(0, 0, 0, 2, 0, 0, 0, 2, 0, 0.5, 0.5) == 0); /* z = 0 plane, point at z = .5 */
    {
        const float t[9] = {0, 0, 0, 2, 0, 0, 0, 2, 0};
        const double p[3] = {1, 1, 0}, q[3] = {1.0000001, 1, 0}, r[3] = {0.5, 0.5, 0};
        CHECK(accel_overlap_tri_box(t, p, p));  /* on the hypotenuse */
        CHECK(!accel_overlap_tri_box(t, q, q)); /* just past it */
        CHECK(accel_overlap_tri_box(t, r, r));
    }

    /* Property: a sampled point of the triangle inside the box means overlap;
     * all three vertices outside on one side of a face means no overlap. */
    int found_sep = 0;
    for (int k = 0; k < 20000; k++) {
        float t[9];
        for (int i = 0; i < 9; i++) t[i] = test_rand_in(-1.5f, 2.5f);
        const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
        int ov = accel_overlap_tri_box(t, lo, hi);
        int inside = 0;
        for (int i = 0; i <= 16 && !inside; i++)
            for (int j = 0; i + j <= 16 && !inside; j++) {
                float u = i / 16.0f, v = j / 16.0f, w = 1 - u - v;
                int in = 1;
                for (int a = 0; a < 3; a++) {
                    float x = w * t[a] + u * t[3 + a] + v * t[6 + a];
                    in &= x >= 0 && x <= 1;
                }
                inside = in;
            }
        CHECKF(!inside || ov, "triangle %d has a point in the box but no overlap", k);
        for (int a = 0; a < 3; a++) {
            int below = t[a] < 0 && t[3 + a] < 0 && t[6 + a] < 0;
            int above = t[a] > 1 && t[3 + a] > 1 && t[6 + a] > 1;
            CHECKF(!(below || above) || !ov, "triangle %d beside the box overlaps", k);
        }
        found_sep += !ov && !inside;
    }
    CHECK(found_sep > 0);
}

TEST(grid_overlap_clip_slab)
{
    const double tri[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
    double out[8][3];
    /* Crossing: the part with 0.5 <= x <= 1 is a quadrilateral. */
    int n = accel_clip_slab(tri, 3, 0, 0.5, 1.0, out);
    CHECKF(n == 4, "crossing: %d vertices", n);
    double xmin = 9, xmax = -9, ymax = -9;
    for (int k = 0; k < n; k++) {
        xmin = out[k][0] < xmin ? out[k][0] : xmin;
        xmax = out[k][0] > xmax ? out[k][0] : xmax;
        ymax = out[k][1] > ymax ? out[k][1] : ymax;
    }
    CHECK(xmin == 0.5 && xmax == 1.0 && ymax == 1.5);
    /* Touching with a vertex only (slab [2, 3]), with an edge (y in [-1, 0]),
     * and disjoint by a hair. */
    n = accel_clip_slab(tri, 3, 0, 2.0, 3.0, out);
    CHECKF(n >= 1 && out[0][0] == 2.0 && out[0][1] == 0.0, "vertex touch: %d vertices", n);
    n = accel_clip_slab(tri, 3, 1, -1.0, 0.0, out);
    CHECKF(n >= 2, "edge touch: %d vertices", n);
    for (int k = 0; k < n; k++) CHECK(out[k][1] == 0.0);
    CHECK(accel_clip_slab(tri, 3, 0, 2.0000001, 3.0, out) == 0);
    CHECK(accel_clip_slab(tri, 3, 2, 1e-9, 1.0, out) == 0);
    /* A flat slab (lo == hi) through the triangle: a segment. */
    n = accel_clip_slab(tri, 3, 1, 1.0, 1.0, out);
    CHECKF(n >= 2, "flat slab: %d vertices", n);
    /* A degenerate polygon (one point) inside and outside. */
    const double pt[1][3] = {{0.5, 0.5, 0.5}};
    CHECK(accel_clip_slab(pt, 1, 2, 0.5, 0.5, out) == 1);
    CHECK(accel_clip_slab(pt, 1, 2, 0.6, 0.7, out) == 0);
}

TEST(grid_overlap_sphere_box)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    const float face[4] = {2, 0.5f, 0.5f, 1}, face_off[4] = {2, 0.5f, 0.5f, 0.999f};
    CHECK(accel_overlap_sphere_box(face, lo, hi));
    CHECK(!accel_overlap_sphere_box(face_off, lo, hi));
    const float corner[4] = {2, 2, 2, 1.7320509f}, corner_off[4] = {2, 2, 2, 1.73f};
    CHECK(accel_overlap_sphere_box(corner, lo, hi));
    CHECK(!accel_overlap_sphere_box(corner_off, lo, hi));
    const float edge[4] = {2, 2, 0.5f, 1.4142136f}, edge_off[4] = {2, 2, 0.5f, 1.414f};
    CHECK(accel_overlap_sphere_box(edge, lo, hi));
    CHECK(!accel_overlap_sphere_box(edge_off, lo, hi));
    const float inside[4] = {0.5f, 0.5f, 0.5f, 0.01f}, around[4] = {0.5f, 0.5f, 0.5f, 10};
    CHECK(accel_overlap_sphere_box(inside, lo, hi));
    CHECK(accel_overlap_sphere_box(around, lo, hi));
}

/*
 * The build's membership (slab clipping, grid_core.c) against the SAT of
 * overlap.h on every padded cell: equal for random triangles, and a
 * superset for triangles on the cell lattice (touching faces, edges and
 * corners, where both must say yes). Spheres: the cells cut by the surface,
 * none deep inside the ball.
 */
TEST(grid_membership_matches_sat)
{
    scene_builder b = {0};
    accel_error err = {0};
    test_seed(606);
    test_add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0),
                 v3(0, 0.01f, 0)); /* pin the bounds to [0,10]^3 */
    test_add_tri(&b, v3(10, 10, 10), v3(9.99f, 10, 10), v3(10, 9.99f, 10));
    const uint32_t first = 2, random_count = 300, lattice_count = 200;
    for (uint32_t i = 0; i < random_count; i++) {
        float sz = i % 10 == 0 ? 9.0f : (i % 3 ? 0.6f : 2.5f);
        vec3 c = v3(test_rand_in(0.5f, 9.5f), test_rand_in(0.5f, 9.5f), test_rand_in(0.5f, 9.5f));
        vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = v3_min(
                v3(10, 10, 10),
                v3_max(v3(0, 0, 0), v3_add(c, v3(test_rand_in(-sz, sz), test_rand_in(-sz, sz),
                                                 test_rand_in(-sz, sz)))));
        test_add_tri(&b, p[0], p[1], p[2]);
    }
    /* On the lattice of a 10^3 grid (cells of 1): vertices on cell corners,
     * edge midpoints, face centres. */
    for (uint32_t i = 0; i < lattice_count; i++) {
        vec3 base = v3((float)(int)(test_rand() * 9), (float)(int)(test_rand() * 9),
                       (float)(int)(test_rand() * 9));
        vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = v3_add(base, v3(0.5f * (int)(test_rand() * 3), 0.5f * (int)(test_rand() * 3),
                                   0.5f * (int)(test_rand() * 3)));
        test_add_tri(&b, p[0], p[1], p[2]);
    }
    scene_builder_add_sphere(&b, v3(5, 5, 5), 3.7f, &err);
    scene_builder_add_sphere(&b, v3(2, 2, 2), 1.0f, &err); /* touches cell planes exactly */
    accel_scene s;
    if (!test_finish(&b, "membership", &s)) return;
    static const char *const specs[] = {"grid:res=10", "grid:res=13x17x11"};
    for (int sp = 0; sp < 2; sp++) {
        const accel_kind *kind;
        void *accel;
        accel_build_stats st;
        if (accel_build_spec(specs[sp], &s, 1, &kind, &accel, &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[sp], err.msg);
            continue;
        }
        grid_view v;
        grid_get_view(accel, &v);
        const grid_frame *f = v.frame;
        uint8_t *member = calloc((size_t)s.prim_count * v.cell_count, 1);
        uint8_t *live = calloc(s.prim_count, 1);
        for (uint32_t k = 0; k < s.live_count; k++) live[s.live[k]] = 1;
        for (uint64_t c = 0; c < v.cell_count; c++)
            for (uint32_t r = v.offsets[c]; r < v.offsets[c + 1]; r++)
                member[(size_t)v.prim_id[v.refs[r]] * v.cell_count + c] = 1;
        size_t missing = 0, extra_random = 0, inside_ball = 0, shell_missing = 0;
        for (int z = 0; z < f->res[2]; z++)
            for (int y = 0; y < f->res[1]; y++)
                for (int x = 0; x < f->res[0]; x++) {
                    uint64_t c =
                        (uint64_t)x + f->stride[1] * (uint64_t)y + f->stride[2] * (uint64_t)z;
                    double lo[3], hi[3];
                    grid_cell_box(f, x, y, z, lo, hi);
                    for (uint32_t k = first; k < s.tri_count; k++) {
                        int sat = accel_overlap_tri_box(s.tris + 9 * (size_t)k, lo, hi);
                        int got = member[(size_t)k * v.cell_count + c];
                        sat &= live[k]; /* degenerate triangles are in no cell */
                        missing += sat && !got;
                        extra_random += k < first + random_count && got && !sat;
                    }
                    for (uint32_t k = s.tri_count; k < s.prim_count; k++) {
                        const float *sph = s.spheres + 4 * (size_t)(k - s.tri_count);
                        int got = member[(size_t)k * v.cell_count + c];
                        int ball = accel_overlap_sphere_box(sph, lo, hi);
                        int shell = accel_overlap_sphere_surface_box(sph, lo, hi);
                        inside_ball += got && ball && !shell;
                        shell_missing += shell && !got;
                    }
                }
        CHECKF(missing == 0, "%s: %zu (triangle, cell) pairs the SAT finds are missing", specs[sp],
               missing);
        CHECKF(extra_random == 0, "%s: %zu extra (triangle, cell) pairs for random triangles",
               specs[sp], extra_random);
        CHECKF(inside_ball == 0 && shell_missing == 0,
               "%s: spheres: %zu cells inside a ball referenced, %zu cut cells missing", specs[sp],
               inside_ball, shell_missing);
        free(member);
        free(live);
        kind->destroy(accel);
    }
    /* The big sphere hit from inside and outside, through the thinned cells. */
    size_t n = 3000;
    accel_ray *rays = malloc(n * sizeof *rays);
    for (size_t i = 0; i < n; i++) {
        float r = i % 2 ? 2.0f : 12.0f;
        vec3 o = v3(5 + test_rand_in(-r, r), 5 + test_rand_in(-r, r), 5 + test_rand_in(-r, r));
        vec3 d = v3(test_rand_in(-1, 1), test_rand_in(-1, 1), test_rand_in(-1, 1));
        rays[i] = test_ray(o, d, 0, INFINITY);
    }
    static const char *const extra[] = {"res=10", "res=40", NULL};
    test_check_variants(&s, &accel_kind_grid, extra, rays, n, TEST_ORACLE_REFERENCE);
    free(rays);
    scene_free(&s);
}
