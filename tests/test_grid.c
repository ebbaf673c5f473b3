/*
 * test_grid.c - grid-specific tests: the resolution rule, res parsing,
 * overflow refusal, the overlap tests of overlap.h, DDA edge cases against
 * the reference (rays through cell corners and edges, +0/-0 components,
 * origins on cell boundaries and inside the grid), flat/thin/far scenes,
 * mailboxing, counters, and identical builds with 1 and 2 threads.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid/grid.h"
#include "grid/overlap.h"
#include "core/prim.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "test.h"

/* ---- helpers ------------------------------------------------------------------ */

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static float frand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (float)(rng_state >> 40) / 16777216.0f;
}
static float frange(float lo, float hi) { return lo + (hi - lo) * frand(); }

static accel_ray mk_ray(float ox, float oy, float oz, float dx, float dy, float dz, float t_near,
                        float t_far)
{
    accel_ray r = {ox, oy, oz, t_near, dx, dy, dz, t_far};
    return r;
}

static int add_tri(scene_builder *b, vec3 a, vec3 c, vec3 d)
{
    accel_error err = {0};
    return scene_builder_add_tri(b, a, c, d, &err) == 0;
}

static int finish(scene_builder *b, const char *name, accel_scene *s)
{
    accel_error err = {0};
    int rc = scene_finish(b, name, s, &err);
    CHECKF(rc == 0, "scene_finish %s: %s", name, err.msg);
    return rc == 0;
}

/*
 * Builds `spec` on s and traces the rays: closest hits against the
 * reference (FORMATS.md rule: zero holes, false hits, disagreements),
 * occluded against the reference's hit/miss, counted against uncounted.
 * Returns the number of bad rays.
 */
/* Every live primitive against every ray with the shared float kernels
 * (prim.h), no accelerator: the grid must give exactly these answers (up to
 * ties), since it runs the same tests on a subset. */
static void float_brute(const accel_scene *s, const accel_ray *rays, accel_hit *hits, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        if (accel_prep_ray(&rays[i], &p)) {
            float t = p.t_far, u = 0, v = 0;
            for (uint32_t k = 0; k < s->live_count; k++)
                if (accel_prim_hit(s, s->live[k], &p, &t, &u, &v, 0, s->sphere_count > 0))
                    h.t = t, h.u = u, h.v = v, h.prim = s->live[k];
        }
        hits[i] = h;
    }
}

static int oracle_float; /* 0: the double-precision reference; 1: float_brute */

static size_t check_spec(const accel_scene *s, const char *spec, const accel_ray *rays, size_t n,
                         const char *label)
{
    accel_error err = {0};
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    if (accel_build_spec(spec, s, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s: build %s failed: %s", label, spec, err.msg);
        return n ? n : 1;
    }
    accel_hit *ref = malloc(n * sizeof *ref), *hits = malloc(n * sizeof *hits);
    accel_hit *hits_c = malloc(n * sizeof *hits_c);
    uint8_t *occ = malloc(n);
    if (oracle_float)
        float_brute(s, rays, ref, n);
    else
        accel_reference_trace(s, rays, ref, n, 1);
    accel_trace(kind, accel, rays, hits, n, 1, NULL);
    accel_counters cnt;
    memset(&cnt, 0, sizeof cnt);
    accel_trace(kind, accel, rays, hits_c, n, 1, &cnt);
    accel_trace_occluded(kind, accel, rays, occ, n, 1, NULL);
    hits_diff d = hits_compare(ref, hits, n);
    size_t occ_bad = 0;
    for (size_t i = 0; i < n; i++) occ_bad += occ[i] != (ref[i].prim != ACCEL_MISS);
    size_t bad = d.holes + d.false_hits + d.disagreements + occ_bad;
    if (bad) {
        size_t i = d.first_bad;
        if (i == SIZE_MAX)
            for (i = 0; i < n && occ[i] == (ref[i].prim != ACCEL_MISS); i++) {
            }
        const accel_ray *r = &rays[i];
        test_fail(__FILE__, __LINE__,
                  "%s %s: %zu holes, %zu false hits, %zu disagreements, %zu occluded mismatches of "
                  "%zu; ray %zu o=(%.9g,%.9g,%.9g) d=(%.9g,%.9g,%.9g) t=[%g,%g] ref %u@%.9g got "
                  "%u@%.9g occ %d",
                  label, spec, d.holes, d.false_hits, d.disagreements, occ_bad, n, i, r->ox, r->oy,
                  r->oz, r->dx, r->dy, r->dz, r->t_near, r->t_far, ref[i].prim, ref[i].t,
                  hits[i].prim, hits[i].t, occ[i]);
    }
    CHECKF(memcmp(hits, hits_c, n * sizeof *hits) == 0, "%s %s: counted and uncounted differ",
           label, spec);
    CHECKF(cnt.rays == n, "%s %s: counted %llu rays of %zu", label, spec,
           (unsigned long long)cnt.rays, n);
    kind->destroy(accel);
    free(ref);
    free(hits);
    free(hits_c);
    free(occ);
    return bad;
}

/* Every variant the kind lists, plus the edge-case ones given. */
static void check_all_variants(const accel_scene *s, const accel_ray *rays, size_t n,
                               const char *const *extra, const char *label)
{
    char spec[256];
    for (const char *const *v = accel_kind_grid.variants; *v; v++) {
        if (strstr(*v, "tri=naive")) continue; /* not watertight: the conformance suite's business */
        snprintf(spec, sizeof spec, "grid%s%s", **v ? ":" : "", *v);
        check_spec(s, spec, rays, n, label);
    }
    for (const char *const *v = extra; v && *v; v++) {
        snprintf(spec, sizeof spec, "grid:%s", *v);
        check_spec(s, spec, rays, n, label);
    }
}

/* ---- resolution rule and sizing --------------------------------------------- */

TEST(grid_resolution_rule)
{
    int r[3];
    box3 cube = {{0, 0, 0}, {1, 1, 1}};
    grid_resolution(cube, 1000, 4, r);
    CHECKF(r[0] == 16 && r[1] == 16 && r[2] == 16, "cube: %dx%dx%d, want 16^3 (cbrt 4000)", r[0],
           r[1], r[2]);
    box3 brick = {{0, 0, 0}, {2, 1, 1}};
    grid_resolution(brick, 1000, 4, r); /* s = cbrt(2000) = 12.6 */
    CHECKF(r[0] == 25 && r[1] == 13 && r[2] == 13, "brick: %dx%dx%d, want 25x13x13", r[0], r[1],
           r[2]);
    box3 flat = {{0, 0, 5}, {1, 1, 5}};
    grid_resolution(flat, 1000, 4, r); /* 2D: sqrt(4000) = 63.2 */
    CHECKF(r[0] == 63 && r[1] == 63 && r[2] == 1, "flat: %dx%dx%d, want 63x63x1", r[0], r[1], r[2]);
    box3 thin = {{0, 0, 0}, {1, 1, 1e-4f}};
    grid_resolution(thin, 1000, 4, r); /* 3D rule gives z 0.34 cells: redone in 2D */
    CHECKF(r[0] == 63 && r[1] == 63 && r[2] == 1, "thin: %dx%dx%d, want 63x63x1", r[0], r[1], r[2]);
    box3 line = {{0, 0, 0}, {10, 1e-5f, 0}};
    grid_resolution(line, 1000, 4, r);
    CHECKF(r[0] == 4000 && r[1] == 1 && r[2] == 1, "line: %dx%dx%d, want 4000x1x1", r[0], r[1],
           r[2]);
    grid_resolution(cube, 1e15, 1000, r);
    CHECKF(r[0] == GRID_MAX_AXIS_RES && r[2] == GRID_MAX_AXIS_RES, "huge: %d clamped", r[0]);
    grid_resolution(box3_empty(), 1000, 4, r);
    CHECK(r[0] == 1 && r[1] == 1 && r[2] == 1);
    grid_resolution(cube, 0, 4, r);
    CHECK(r[0] == 1 && r[1] == 1 && r[2] == 1);
    grid_resolution(cube, 1, 0.001, r);
    CHECK(r[0] == 1 && r[1] == 1 && r[2] == 1);
    /* Random boxes: the cell count stays near lambda*N. */
    for (int k = 0; k < 200; k++) {
        box3 b = {{0, 0, 0}, {frange(0.1f, 10), frange(0.1f, 10), frange(0.1f, 10)}};
        double n = 1000 + 100000 * frand(), lambda = 0.5 + 8 * frand();
        grid_resolution(b, n, lambda, r);
        double cells = (double)r[0] * r[1] * r[2];
        CHECKF(cells > 0.6 * lambda * n && cells < 1.6 * lambda * n,
               "box %gx%gx%g n %g lambda %g: %dx%dx%d = %g cells", b.max.x, b.max.y, b.max.z, n,
               lambda, r[0], r[1], r[2], cells);
    }
}

TEST(grid_res_parse)
{
    accel_error err = {0};
    int r[3];
    CHECK(grid_parse_res("auto", r, &err) == 0 && r[0] == 0);
    CHECK(grid_parse_res("128", r, &err) == 0 && r[0] == 128 && r[1] == 128 && r[2] == 128);
    CHECK(grid_parse_res("128x64x32", r, &err) == 0 && r[0] == 128 && r[1] == 64 && r[2] == 32);
    CHECK(grid_parse_res("65536x1x1", r, &err) == 0 && r[0] == 65536);
    static const char *const bad[] = {"0",   "12x",   "x",     "1x2",  "1x2x3x4", "65537",
                                      "-3",  "abc",   "4x4x0", "4 ",   "4x-4x4",  "99999999999999999999",
                                      "1.5", "4X4X4", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        if (!*bad[i]) continue; /* empty means auto */
        err.msg[0] = 0;
        int rc = grid_parse_res(bad[i], r, &err);
        CHECKF(rc != 0 && strstr(err.msg, "res="), "res=%s accepted (rc %d, msg '%s')", bad[i], rc,
               err.msg);
    }
    /* Through the spec parser and the build. */
    accel_scene s;
    scene_builder b = {0};
    add_tri(&b, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 1));
    if (!finish(&b, "one", &s)) return;
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    int rc = accel_build_spec("grid:res=5x6x7", &s, 1, &kind, &accel, &st, &err);
    CHECKF(rc == 0, "res=5x6x7: %s", err.msg);
    if (rc == 0) {
        CHECK(st.res[0] == 5 && st.res[1] == 6 && st.res[2] == 7 && st.nodes == 210);
        kind->destroy(accel);
    }
    CHECK(accel_build_spec("grid:res=5x6", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_build_spec("grid:lambda=0", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_build_spec("grid:overlap=sat", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_SPEC);
    scene_free(&s);
}

TEST(grid_overflow_refused)
{
    accel_error err = {0};
    uint64_t cells = 0;
    int huge[3] = {65536, 65536, 65536};
    CHECK(grid_cell_count("grid", huge, 1e30, &cells, &err) == ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "cells") != NULL, "message: %s", err.msg);
    int big[3] = {2048, 2048, 1024}; /* 2^32 cells: does not fit a uint32 index */
    CHECK(grid_cell_count("grid", big, 1e30, &cells, &err) == ACCEL_ERR_RANGE);
    int ok[3] = {1024, 1024, 1023};
    CHECK(grid_cell_count("grid", ok, 1e30, &cells, &err) == 0 && cells == 1024ull * 1024 * 1023);
    int mid[3] = {512, 512, 512}; /* 512 MiB of offsets */
    CHECK(grid_cell_count("grid", mid, 256.0 * 1048576, &cells, &err) == ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "MiB") != NULL, "message: %s", err.msg);
    int zero[3] = {0, 4, 4};
    CHECK(grid_cell_count("grid", zero, 1e30, &cells, &err) == ACCEL_ERR_RANGE);

    /* Through the build: cells, then references, above max_mb. */
    scene_builder b = {0};
    for (int i = 0; i < 200; i++) /* large triangles crossing the whole box */
        add_tri(&b, v3(0, frand(), 0), v3(1, frand(), 1), v3(frand(), 1, frand()));
    accel_scene s;
    if (!finish(&b, "big-tris", &s)) return;
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    CHECK(accel_build_spec("grid:res=65536", &s, 1, &kind, &accel, &st, &err) == ACCEL_ERR_RANGE);
    CHECK(accel_build_spec("grid:res=256,max_mb=16", &s, 1, &kind, &accel, &st, &err) ==
          ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "max_mb") != NULL, "message: %s", err.msg);
    /* 64^3 offsets fit 2 MiB, but 200 triangles x ~5000 cells of references do not. */
    err.msg[0] = 0;
    CHECK(accel_build_spec("grid:res=64,max_mb=2", &s, 1, &kind, &accel, &st, &err) ==
          ACCEL_ERR_RANGE);
    CHECKF(strstr(err.msg, "references") != NULL, "message: %s", err.msg);
    int rc = accel_build_spec("grid:res=32", &s, 1, &kind, &accel, &st, &err);
    CHECKF(rc == 0, "res=32: %s", err.msg);
    if (rc == 0) {
        CHECKF(st.refs > 200 * 500, "refs %llu", (unsigned long long)st.refs);
        kind->destroy(accel);
    }
    scene_free(&s);
}

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
    CHECK(tri_box(1.5f, 0.5f, 0.5f, 0.5f, 1.5f, 0.5f, 2, 2, 0.5f, 0, 1)); /* edge x+y=2 through corner (1,1) */
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
    CHECK(tri_box(-1, 0.5f, 0.5f, 2, 0.5f, 0.5f, 3, 0.5f, 0.5f, 0, 1)); /* collinear segment through */
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
        for (int i = 0; i < 9; i++) t[i] = frange(-1.5f, 2.5f);
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
    rng_state = 606;
    add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0)); /* pin the bounds to [0,10]^3 */
    add_tri(&b, v3(10, 10, 10), v3(9.99f, 10, 10), v3(10, 9.99f, 10));
    const uint32_t first = 2, random_count = 300, lattice_count = 200;
    for (uint32_t i = 0; i < random_count; i++) {
        float sz = i % 10 == 0 ? 9.0f : (i % 3 ? 0.6f : 2.5f);
        vec3 c = v3(frange(0.5f, 9.5f), frange(0.5f, 9.5f), frange(0.5f, 9.5f));
        vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = v3_min(v3(10, 10, 10), v3_max(v3(0, 0, 0), v3_add(c, v3(frange(-sz, sz),
                                                                            frange(-sz, sz),
                                                                            frange(-sz, sz)))));
        add_tri(&b, p[0], p[1], p[2]);
    }
    /* On the lattice of a 10^3 grid (cells of 1): vertices on cell corners,
     * edge midpoints, face centres. */
    for (uint32_t i = 0; i < lattice_count; i++) {
        vec3 base = v3((float)(int)(frand() * 9), (float)(int)(frand() * 9), (float)(int)(frand() * 9));
        vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = v3_add(base, v3(0.5f * (int)(frand() * 3), 0.5f * (int)(frand() * 3),
                                   0.5f * (int)(frand() * 3)));
        add_tri(&b, p[0], p[1], p[2]);
    }
    scene_builder_add_sphere(&b, v3(5, 5, 5), 3.7f, &err);
    scene_builder_add_sphere(&b, v3(2, 2, 2), 1.0f, &err); /* touches cell planes exactly */
    accel_scene s;
    if (!finish(&b, "membership", &s)) return;
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
                    uint64_t c = (uint64_t)x + f->stride[1] * (uint64_t)y + f->stride[2] * (uint64_t)z;
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
        vec3 o = v3(5 + frange(-r, r), 5 + frange(-r, r), 5 + frange(-r, r));
        vec3 d = v3(frange(-1, 1), frange(-1, 1), frange(-1, 1));
        rays[i] = mk_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0, INFINITY);
    }
    static const char *const extra[] = {"res=10", "res=40", NULL};
    check_all_variants(&s, rays, n, extra, "membership");
    free(rays);
    scene_free(&s);
}

/* ---- DDA edge cases against the reference ----------------------------------------- */

/*
 * A scene on a lattice: bounds exactly [0,4]^3 and triangles whose vertices
 * lie on the half-integer lattice, so that with res=4 (and 8) many of them
 * lie in cell boundary planes, along cell edges, or touch cell corners.
 */
static int lattice_scene(accel_scene *s)
{
    scene_builder b = {0};
    rng_state = 12345;
    for (int i = 0; i < 300; i++) {
        vec3 p[3];
        vec3 base = v3(0.5f * (int)(frand() * 8), 0.5f * (int)(frand() * 8), 0.5f * (int)(frand() * 8));
        for (int k = 0; k < 3; k++)
            p[k] = v3_add(base, v3(0.5f * (int)(frand() * 3), 0.5f * (int)(frand() * 3),
                                   0.5f * (int)(frand() * 3)));
        add_tri(&b, p[0], p[1], p[2]);
    }
    /* Axis-aligned squares lying exactly in the planes x = 2, y = 1, z = 3. */
    add_tri(&b, v3(2, 0.5f, 0.5f), v3(2, 1.5f, 0.5f), v3(2, 1.5f, 1.5f));
    add_tri(&b, v3(2, 0.5f, 0.5f), v3(2, 1.5f, 1.5f), v3(2, 0.5f, 1.5f));
    add_tri(&b, v3(0.5f, 1, 2.5f), v3(1.5f, 1, 2.5f), v3(1.5f, 1, 3.5f));
    add_tri(&b, v3(2.5f, 2.5f, 3), v3(3.5f, 2.5f, 3), v3(3.5f, 3.5f, 3));
    /* Pin the bounds to [0,4]^3. */
    add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0));
    add_tri(&b, v3(4, 4, 4), v3(3.99f, 4, 4), v3(4, 3.99f, 4));
    return finish(&b, "lattice", s);
}

/* Does the ray's line lie in the plane of a live triangle? Such a ray has
 * no well-defined hit with it (the watertight determinant is zero up to
 * rounding, so any t may come out); exact in double for lattice input. */
static int ray_in_a_plane(const accel_scene *s, const accel_ray *r)
{
    for (uint32_t k = 0; k < s->live_count; k++) {
        const float *t = s->tris + 9 * (size_t)s->live[k];
        double e1[3], e2[3], n[3], w[3];
        for (int a = 0; a < 3; a++) {
            e1[a] = (double)t[3 + a] - t[a];
            e2[a] = (double)t[6 + a] - t[a];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        w[0] = (double)r->ox - t[0], w[1] = (double)r->oy - t[1], w[2] = (double)r->oz - t[2];
        if (n[0] * r->dx + n[1] * r->dy + n[2] * r->dz == 0.0 &&
            n[0] * w[0] + n[1] * w[1] + n[2] * w[2] == 0.0)
            return 1;
    }
    return 0;
}

/* Lattice points (multiples of 1/2, some beyond the box) as origins and
 * targets, so rays run through cell corners and along cell edges. Rays in
 * the plane of a triangle are left out (ray_in_a_plane). */
static accel_ray *lattice_rays(const accel_scene *s, size_t *n)
{
    size_t cap = 20000, k = 0;
    accel_ray *r = malloc(cap * sizeof *r);
    if (!r) return NULL;
    rng_state = 777;
    /* Point to point: corners to corners, inside and from outside. */
    while (k < 8000) {
        float o[3], t[3];
        for (int a = 0; a < 3; a++) {
            o[a] = 0.5f * (int)(frand() * 13) - 1.0f; /* -1 .. 5 */
            t[a] = 0.5f * (int)(frand() * 9);         /* 0 .. 4 */
        }
        float d[3] = {t[0] - o[0], t[1] - o[1], t[2] - o[2]};
        if (d[0] == 0 && d[1] == 0 && d[2] == 0) continue;
        float t_near = (k % 5 == 0) ? 0.5f : 0.0f;
        float t_far = (k % 7 == 0) ? 1.0f : INFINITY; /* some end exactly on a lattice point */
        r[k] = mk_ray(o[0], o[1], o[2], d[0], d[1], d[2], t_near, t_far);
        k += !ray_in_a_plane(s, &r[k]);
    }
    /* Axis-parallel along lattice lines (cell edges and faces) with +0/-0
     * in the other components, from outside, from the faces and inside. */
    for (int axis = 0; axis < 3; axis++)
        for (int i = 0; i <= 8; i++)
            for (int j = 0; j <= 8; j++)
                for (int var = 0; var < 4; var++) {
                    float o[3], d[3];
                    int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
                    o[a1] = 0.5f * i;
                    o[a2] = 0.5f * j;
                    o[axis] = var == 0 ? -1.0f : var == 1 ? 5.0f : var == 2 ? 0.0f : 2.0f;
                    d[axis] = var == 1 ? -1.0f : (var == 3 && (i & 1)) ? -2.0f : 1.0f;
                    d[a1] = (i + j) & 1 ? -0.0f : 0.0f;
                    d[a2] = j & 2 ? -0.0f : 0.0f;
                    r[k] = mk_ray(o[0], o[1], o[2], d[0], d[1], d[2], 0.0f, INFINITY);
                    k += !ray_in_a_plane(s, &r[k]);
                }
    /* Diagonals in a plane: through cell edges with one zero component. */
    for (int i = 0; i < 400; i++) {
        float o[3] = {0.5f * (int)(frand() * 9), 0.5f * (int)(frand() * 9), 0.5f * (int)(frand() * 9)};
        int zero = i % 3;
        float d[3] = {frand() < 0.5f ? 1.0f : -1.0f, frand() < 0.5f ? 1.0f : -1.0f,
                      frand() < 0.5f ? 1.0f : -1.0f};
        d[zero] = (i & 4) ? -0.0f : 0.0f;
        r[k] = mk_ray(o[0], o[1], o[2], d[0], d[1], d[2], 0.0f, INFINITY);
        k += !ray_in_a_plane(s, &r[k]);
    }
    /* Random directions from random points, some far away. */
    for (int i = 0; i < 2000; i++) {
        float scale = i % 4 == 0 ? 40.0f : 3.0f;
        float o[3] = {frange(-scale, 4 + scale), frange(-scale, 4 + scale), frange(-scale, 4 + scale)};
        float t[3] = {frange(0, 4), frange(0, 4), frange(0, 4)};
        r[k++] = mk_ray(o[0], o[1], o[2], t[0] - o[0], t[1] - o[1], t[2] - o[2], 0.0f, INFINITY);
    }
    *n = k;
    return r;
}

TEST(grid_dda_lattice_edges_corners)
{
    accel_scene s;
    if (!lattice_scene(&s)) return;
    size_t n;
    accel_ray *rays = lattice_rays(&s, &n);
    CHECK(rays != NULL && n > 9000);
    if (!rays) return;
    static const char *const extra[] = {"res=4",
                                        "res=8",
                                        "res=4,mailbox=0",
                                        "res=8,overlap=bbox",
                                        "res=3x5x4",
                                        "res=16",
                                        "res=64x1x1",
                                        "res=1x2x64",
                                        NULL};
    /* The traversal is checked against the same float kernels without an
     * accelerator, so that any difference is a cell the DDA skipped, however
     * the float kernels and the double reference decide rays through these
     * vertices and open edges (the note reports how they compare). */
    accel_hit *ref = malloc(n * sizeof *ref), *brute = malloc(n * sizeof *brute);
    if (ref && brute) {
        accel_reference_trace(&s, rays, ref, n, 1);
        float_brute(&s, rays, brute, n);
        hits_diff d = hits_compare(ref, brute, n);
        test_note("float kernels vs reference on the lattice: %zu holes, %zu false hits, %zu "
                  "disagreements of %zu rays", d.holes, d.false_hits, d.disagreements, n);
    }
    free(ref);
    free(brute);
    oracle_float = 1;
    check_all_variants(&s, rays, n, extra, "lattice");
    oracle_float = 0;
    free(rays);
    scene_free(&s);
}

/*
 * Rays that graze a cell edge or enter near a cell boundary, where rounding
 * in the DDA decides which side they pass: triangles placed a few ulps
 * inside one cell only, rays aimed a few ulps past the edge or boundary
 * from afar. Without padded membership or the entry correction of
 * grid_dda_init, a ray can walk past the one cell holding its hit.
 */
TEST(grid_dda_grazing)
{
    scene_builder b = {0};
    const float e = 2.0f * 0x1p-22f; /* 2 ulps at 2 */
    /* In the plane x = y, just inside cell (2,2) of a 4^3 grid over [0,4]^3. */
    add_tri(&b, v3(2 + e, 2 + e, 0.5f), v3(2 + e, 2 + e, 3.5f), v3(3.5f, 3.5f, 2));
    /* A square in the face x = 0, in the row y < 1 only, reaching up to a
     * hundredth of a cell below y = 1. */
    const float top = 0.99f;
    add_tri(&b, v3(0, 0.2f, 0.2f), v3(0, top, 0.2f), v3(0, top, 3.8f));
    add_tri(&b, v3(0, 0.2f, 0.2f), v3(0, top, 3.8f), v3(0, 0.2f, 3.8f));
    add_tri(&b, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0));
    add_tri(&b, v3(4, 4, 4), v3(3.99f, 4, 4), v3(4, 3.99f, 4));
    accel_scene s;
    if (!finish(&b, "grazing", &s)) return;
    size_t n = 20000;
    accel_ray *rays = malloc(n * sizeof *rays);
    rng_state = 8080;
    for (size_t i = 0; i < n / 2; i++) {
        /* Anti-diagonal through (2+k ulps, 2+k ulps, z): crosses cell (2,2)
         * for a length of a few ulps near its corner. */
        float k = (float)(int)(frand() * 8) * 0x1p-22f;
        float z = frange(0.6f, 3.4f), back = 0.5f * powf(10, 9 * frand()); /* 0.5 .. 5e8 */
        vec3 target = v3(2 + k, 2 + k, z), dir = v3(1, -1, frange(-0.01f, 0.01f));
        vec3 o = v3_sub(target, v3_scale(dir, back));
        rays[i] = mk_ray(o.x, o.y, o.z, dir.x, dir.y, dir.z, 0, INFINITY);
    }
    for (size_t i = n / 2; i < n; i++) {
        /* From 10^5..10^6 away (entry point rounding well above the
         * membership padding), entering the face x = 0 within 0.1 of the
         * plane y = 1, where the square lies in row y < 1 only. */
        float k = frange(-0.05f, 0.1f);
        float z = frange(0.3f, 3.0f), back = frange(1e5f, 1e6f);
        vec3 dir = v3(0.7f, i % 2 ? 0.3f : -0.3f, frange(-1e-5f, 1e-5f));
        vec3 entry = v3(0, 1 - k, z);
        vec3 o = v3_sub(entry, v3_scale(dir, back));
        rays[i] = mk_ray(o.x, o.y, o.z, dir.x, dir.y, dir.z, 0, INFINITY);
    }
    static const char *const extra[] = {"res=4", "res=4,mailbox=0", "res=8", NULL};
    check_all_variants(&s, rays, n, extra, "grazing");
    free(rays);
    scene_free(&s);
}

/* Random triangles and spheres, plus rays from inside and outside. */
TEST(grid_soup_with_spheres)
{
    scene_builder b = {0};
    accel_error err = {0};
    rng_state = 4242;
    for (int i = 0; i < 2000; i++) {
        vec3 c = v3(frange(-10, 10), frange(-10, 10), frange(-3, 3));
        float sz = frand() < 0.1f ? 4.0f : 0.5f;
        add_tri(&b, v3_add(c, v3(frange(-sz, sz), frange(-sz, sz), frange(-sz, sz))),
                v3_add(c, v3(frange(-sz, sz), frange(-sz, sz), frange(-sz, sz))),
                v3_add(c, v3(frange(-sz, sz), frange(-sz, sz), frange(-sz, sz))));
    }
    for (int i = 0; i < 200; i++)
        scene_builder_add_sphere(&b, v3(frange(-10, 10), frange(-10, 10), frange(-3, 3)),
                                 frange(0.05f, 1.5f), &err);
    accel_scene s;
    if (!finish(&b, "soup+spheres", &s)) return;
    size_t n = 6000;
    accel_ray *rays = malloc(n * sizeof *rays);
    for (size_t i = 0; i < n; i++) {
        float o[3], t[3];
        int inside = i % 2;
        for (int a = 0; a < 3; a++) {
            o[a] = inside ? frange(-10, 10) : frange(-40, 40);
            t[a] = frange(-10, 10);
        }
        float t_far = i % 3 == 0 ? frange(0.1f, 1.0f) : INFINITY;
        rays[i] = mk_ray(o[0], o[1], o[2], t[0] - o[0], t[1] - o[1], t[2] - o[2], 0, t_far);
    }
    check_all_variants(&s, rays, n, NULL, "soup");
    free(rays);
    scene_free(&s);
}

/* All triangles in the plane z = 0: a flat grid; rays in and across the plane. */
TEST(grid_flat_and_thin_scenes)
{
    for (int thin = 0; thin < 2; thin++) {
        scene_builder b = {0};
        rng_state = 99 + thin;
        for (int i = 0; i < 1000; i++) {
            float x = frange(0, 10), y = frange(0, 10);
            float z0 = thin ? frange(0, 1e-3f) : 0, z1 = thin ? frange(0, 1e-3f) : 0;
            add_tri(&b, v3(x, y, z0), v3(x + frange(0, 0.5f), y + frange(-0.2f, 0.2f), z1),
                    v3(x + frange(-0.2f, 0.2f), y + frange(0, 0.5f), z0));
        }
        accel_scene s;
        if (!finish(&b, thin ? "thin" : "flat", &s)) return;
        const accel_kind *kind;
        void *accel;
        accel_build_stats st;
        accel_error err = {0};
        if (accel_build_spec("grid", &s, 1, &kind, &accel, &st, &err) == 0) {
            CHECKF(st.res[2] == 1 && st.res[0] > 20 && st.res[1] > 20, "%s: res %dx%dx%d",
                   s.name, st.res[0], st.res[1], st.res[2]);
            kind->destroy(accel);
        } else {
            test_fail(__FILE__, __LINE__, "%s: %s", s.name, err.msg);
        }
        size_t n = 4000;
        accel_ray *rays = malloc(n * sizeof *rays);
        for (size_t i = 0; i < n; i++) {
            float ox = frange(-2, 12), oy = frange(-2, 12);
            if (i % 4 == 0) /* lying in the plane */
                rays[i] = mk_ray(ox, oy, 0, frange(-1, 1), frange(-1, 1), i % 8 ? 0.0f : -0.0f, 0,
                                 INFINITY);
            else if (i % 4 == 1) /* straight down, +0/-0 sideways */
                rays[i] = mk_ray(ox, oy, 5, i % 8 == 1 ? -0.0f : 0.0f, 0.0f, -1, 0, INFINITY);
            else
                rays[i] = mk_ray(ox, oy, frange(-5, 5), frange(0, 10) - ox, frange(0, 10) - oy,
                                 frange(-1, 1), 0, INFINITY);
        }
        check_all_variants(&s, rays, n, NULL, s.name);
        free(rays);
        scene_free(&s);
    }
}

/* A scene far from the origin and a tiny one: the padding scales along. */
TEST(grid_far_and_tiny_scenes)
{
    static const float offsets[] = {1e4f, 0.0f};
    static const float scales[] = {1.0f, 1e-4f};
    for (int c = 0; c < 2; c++) {
        scene_builder b = {0};
        rng_state = 5 + c;
        float o = offsets[c], sc = scales[c];
        for (int i = 0; i < 1500; i++) {
            vec3 p = v3(o + sc * frange(0, 8), o + sc * frange(0, 8), o + sc * frange(0, 8));
            add_tri(&b, p, v3_add(p, v3(sc * frange(-.5f, .5f), sc * frange(-.5f, .5f), 0)),
                    v3_add(p, v3(0, sc * frange(-.5f, .5f), sc * frange(-.5f, .5f))));
        }
        accel_scene s;
        if (!finish(&b, c ? "tiny" : "far", &s)) return;
        size_t n = 3000;
        accel_ray *rays = malloc(n * sizeof *rays);
        for (size_t i = 0; i < n; i++) {
            vec3 org = v3(o + sc * frange(-4, 12), o + sc * frange(-4, 12), o + sc * frange(-4, 12));
            vec3 tgt = v3(o + sc * frange(0, 8), o + sc * frange(0, 8), o + sc * frange(0, 8));
            vec3 d = v3_sub(tgt, org);
            rays[i] = mk_ray(org.x, org.y, org.z, d.x, d.y, d.z, 0, INFINITY);
        }
        static const char *const extra[] = {"res=64", NULL};
        check_all_variants(&s, rays, n, extra, s.name);
        free(rays);
        scene_free(&s);
    }
}

/* No live primitive: builds, misses everything. */
TEST(grid_empty_scene)
{
    scene_builder b = {0};
    add_tri(&b, v3(0, 0, 0), v3(1, 1, 1), v3(2, 2, 2)); /* degenerate */
    accel_scene s;
    if (!finish(&b, "empty", &s)) return;
    accel_ray r[2] = {mk_ray(0, 0, -1, 0.1f, 0.1f, 1, 0, INFINITY),
                      mk_ray(1, 1, 1, 1, 0, 0, 0, INFINITY)};
    check_all_variants(&s, r, 2, NULL, "empty");
    scene_free(&s);
}

/* ---- counters, step counts, mailbox ---------------------------------------------- */

TEST(grid_dda_step_counts)
{
    /* Bounds exactly [0,8]^3 from two triangles off the main diagonal. */
    scene_builder b = {0};
    add_tri(&b, v3(0, 0, 1), v3(0, 1, 0), v3(0, 1, 1));
    add_tri(&b, v3(8, 8, 7), v3(8, 7, 8), v3(8, 7, 7));
    accel_scene s;
    if (!finish(&b, "corners", &s)) return;
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    accel_error err = {0};
    if (accel_build_spec("grid:res=8", &s, 1, &kind, &accel, &st, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        return;
    }
    struct {
        accel_ray ray;
        uint64_t steps;
        const char *what;
    } cases[] = {
        {mk_ray(-1, 4.5f, 4.5f, 1, 0, 0, 0, INFINITY), 8, "along x through cell centres"},
        {mk_ray(-1, 4, 4, 1, -0.0f, 0, 0, INFINITY), 8, "along x on a cell edge line"},
        {mk_ray(9, 4, 4, -1, 0, -0.0f, 0, INFINITY), 8, "along -x on a cell edge line"},
        {mk_ray(3.5f, 4.5f, 4.5f, 1, 0, 0, 0, INFINITY), 5, "inside, from cell 3"},
        {mk_ray(3, 4.5f, 4.5f, 1, 0, 0, 0, INFINITY), 5, "origin on the plane x=3, +x"},
        {mk_ray(3, 4.5f, 4.5f, -1, 0, 0, 0, INFINITY), 3, "origin on the plane x=3, -x"},
        {mk_ray(3, 4.5f, 4.5f, 1, 0, 0, 0, 2.5f), 3, "ending inside cell 5"},
        {mk_ray(3, 4.5f, 4.5f, 1, 0, 0, 0, 2.0f), 2, "ending on the plane x=5"},
        {mk_ray(-1, -1, -1, 1, 1, 1, 0, INFINITY), 22, "main diagonal through corners"},
        {mk_ray(9, 9, 9, -1, -1, -1, 0, INFINITY), 22, "main diagonal backwards"},
        {mk_ray(0, 0, 4.5f, 1, 1, 0, 0, INFINITY), 15, "face diagonal through edges"},
        {mk_ray(-1, 4.5f, 4.5f, 0, 1, 0, 0, INFINITY), 0, "parallel, outside"},
        {mk_ray(8, 4.5f, 4.5f, 0, 1, 0, 0, INFINITY), 4, "parallel in the face x=8"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        accel_counters c;
        memset(&c, 0, sizeof c);
        uint32_t ray_steps = 99, ray_prims = 99;
        c.ray_steps = &ray_steps;
        c.ray_prims = &ray_prims;
        accel_hit h;
        accel_trace(kind, accel, &cases[i].ray, &h, 1, 1, &c);
        CHECKF(c.steps == cases[i].steps && ray_steps == cases[i].steps,
               "%s: %llu steps (per ray %u), want %llu", cases[i].what,
               (unsigned long long)c.steps, ray_steps, (unsigned long long)cases[i].steps);
        CHECKF(h.prim == ACCEL_MISS, "%s: hit %u", cases[i].what, h.prim);
        CHECKF(c.empty_steps <= c.steps && ray_prims == c.prim_tests, "%s: counters", cases[i].what);
    }
    kind->destroy(accel);
    scene_free(&s);
}

TEST(grid_mailbox_counts)
{
    /* Large triangles on a fine grid: each spans many cells along a ray. */
    scene_builder b = {0};
    rng_state = 31;
    for (int i = 0; i < 100; i++) {
        vec3 c = v3(frange(0, 10), frange(0, 10), frange(0, 10));
        add_tri(&b, c, v3_add(c, v3(3, frange(-1, 1), 0.5f)), v3_add(c, v3(0.3f, 3, frange(-1, 1))));
    }
    accel_scene s;
    if (!finish(&b, "big", &s)) return;
    size_t n = 2000;
    accel_ray *rays = malloc(n * sizeof *rays);
    for (size_t i = 0; i < n; i++)
        rays[i] = mk_ray(frange(0, 10), frange(0, 10), -5, frange(-0.3f, 0.3f), frange(-.3f, .3f), 1,
                         0, INFINITY);
    accel_counters c[2];
    accel_hit *h[2];
    for (int mb = 0; mb < 2; mb++) {
        const accel_kind *kind;
        void *accel;
        accel_build_stats st;
        accel_error err = {0};
        h[mb] = malloc(n * sizeof *h[mb]);
        memset(&c[mb], 0, sizeof c[mb]);
        if (accel_build_spec(mb ? "grid:res=64,mailbox=1" : "grid:res=64,mailbox=0", &s, 1, &kind,
                             &accel, &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s", err.msg);
            return;
        }
        accel_trace(kind, accel, rays, h[mb], n, 2, &c[mb]);
        kind->destroy(accel);
    }
    /* Same answers (a tie between two primitives at one distance may go
     * either way when a repeated test is skipped). */
    hits_diff d = hits_compare(h[0], h[1], n);
    CHECKF(d.agree == n, "mailbox changes %zu answers", n - d.agree);
    CHECK(c[0].mailbox_skips == 0);
    CHECKF(c[1].mailbox_skips > 0 && c[1].prim_tests < c[0].prim_tests &&
               c[1].prim_tests + c[1].mailbox_skips == c[0].prim_tests,
           "mailbox: %llu tests + %llu skips vs %llu tests without",
           (unsigned long long)c[1].prim_tests, (unsigned long long)c[1].mailbox_skips,
           (unsigned long long)c[0].prim_tests);
    CHECK(c[0].steps == c[1].steps && c[0].rays == n && c[0].box_tests == n);
    free(h[0]);
    free(h[1]);
    free(rays);
    scene_free(&s);
}

/* ---- thread-count independence ----------------------------------------------------- */

TEST(grid_build_threads_identical)
{
    scene_builder b = {0};
    accel_error err = {0};
    rng_state = 2024;
    for (int i = 0; i < 30000; i++) {
        vec3 c = v3(frange(0, 10), frange(0, 10), frange(0, 10));
        float sz = frand() < 0.05f ? 2.0f : 0.2f;
        add_tri(&b, c, v3_add(c, v3(frange(-sz, sz), frange(-sz, sz), frange(-sz, sz))),
                v3_add(c, v3(frange(-sz, sz), frange(-sz, sz), frange(-sz, sz))));
    }
    for (int i = 0; i < 500; i++)
        scene_builder_add_sphere(&b, v3(frange(0, 10), frange(0, 10), frange(0, 10)),
                                 frange(0.01f, 1), &err);
    accel_scene s;
    if (!finish(&b, "threads", &s)) return;
    static const char *const specs[] = {"grid", "grid:overlap=bbox", "grid:res=200x3x90"};
    for (size_t k = 0; k < sizeof specs / sizeof specs[0]; k++) {
        const accel_kind *kind;
        void *a1, *a2;
        accel_build_stats s1, s2;
        if (accel_build_spec(specs[k], &s, 1, &kind, &a1, &s1, &err) ||
            accel_build_spec(specs[k], &s, 2, &kind, &a2, &s2, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[k], err.msg);
            continue;
        }
        grid_view v1, v2;
        grid_get_view(a1, &v1);
        grid_get_view(a2, &v2);
        CHECK(v1.cell_count == v2.cell_count && v1.ref_count == v2.ref_count);
        if (v1.cell_count == v2.cell_count && v1.ref_count == v2.ref_count) {
            CHECKF(memcmp(v1.offsets, v2.offsets, (v1.cell_count + 1) * sizeof *v1.offsets) == 0,
                   "%s: offsets differ", specs[k]);
            CHECKF(memcmp(v1.refs, v2.refs, v1.ref_count * sizeof *v1.refs) == 0,
                   "%s: refs differ", specs[k]);
        }
        CHECK(s1.refs == s2.refs && s1.leaves == s2.leaves && s1.bytes == s2.bytes);
        /* Sanity of the arrays: offsets increase, lists sorted, every live
         * primitive referenced at least once. */
        int ok = v1.offsets[0] == 0 && v1.offsets[v1.cell_count] == v1.ref_count;
        uint8_t *seen = calloc(s.prim_count, 1);
        ok &= v1.prim_count == s.live_count &&
              memcmp(v1.prim_id, v2.prim_id, v1.prim_count * sizeof *v1.prim_id) == 0;
        for (uint64_t c = 0; c < v1.cell_count && ok; c++) {
            ok &= v1.offsets[c] <= v1.offsets[c + 1];
            for (uint32_t r = v1.offsets[c]; ok && r < v1.offsets[c + 1]; r++) {
                ok &= v1.refs[r] < v1.prim_count;
                if (r > v1.offsets[c]) ok &= v1.refs[r] > v1.refs[r - 1];
                if (ok) seen[v1.prim_id[v1.refs[r]]] = 1;
            }
        }
        CHECKF(ok, "%s: malformed cell arrays", specs[k]);
        for (uint32_t i = 0; i < s.live_count && ok; i++) ok &= seen[s.live[i]];
        CHECKF(ok, "%s: a live primitive is in no cell", specs[k]);
        free(seen);
        /* Exact overlap stores fewer references than bounding boxes. */
        if (k == 1) {
            accel_build_stats se;
            void *ae;
            if (accel_build_spec("grid", &s, 2, &kind, &ae, &se, &err) == 0) {
                CHECKF(se.refs < s1.refs, "exact %llu refs vs bbox %llu",
                       (unsigned long long)se.refs, (unsigned long long)s1.refs);
                kind->destroy(ae);
            }
        }
        kind->destroy(a1);
        kind->destroy(a2);
    }
    scene_free(&s);
}
