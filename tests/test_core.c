/*
 * test_core.c - unit tests of the shared layer: spec parsing, ray
 * preparation, slab and triangle edge cases, sphere test, ray/hit files,
 * PNG output, comparison rule, deterministic ray sets.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image/image.h"
#include "core/prim.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

TEST(core_spec_parsing)
{
    accel_params p;
    accel_error err = {0};
    CHECK(accel_params_parse("brute", &p, &err) == 0);
    CHECK(p.naive == 0);
    CHECK(accel_params_parse("brute:tri=naive", &p, &err) == 0);
    CHECK(p.naive == 1);
    CHECK(strcmp(p.spec, "brute:tri=naive") == 0);
    CHECK(accel_params_parse("nosuchkind", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "brute") != NULL, "unknown kind message lists kinds: %s", err.msg);
    CHECK(accel_params_parse("brute:foo=1", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "tri") != NULL, "unknown key message lists keys: %s", err.msg);
    CHECK(accel_params_parse("brute:tri=fast", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "watertight|naive") != NULL, "enum message lists values: %s", err.msg);
    CHECK(accel_params_parse("brute:tri", &p, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_params_parse("brute:tri=naive,tri=naive", &p, &err) == ACCEL_ERR_SPEC);

    static const accel_param_def defs[] = {
        {.key = "n", .type = ACCEL_PARAM_INT, .def = "4", .min = 1, .max = 10, .help = "count"},
        {.key = "x", .type = ACCEL_PARAM_FLOAT, .def = "0.5", .min = 0, .max = 1,
         .help = "fraction"},
        {.key = "on", .type = ACCEL_PARAM_BOOL, .def = "0", .min = 0, .max = 1, .help = "flag"},
    };
    double num[3];
    char str[3][64];
    unsigned char given[3];
    CHECK(accel_parse_kv("t", "n=7,x=0.25,on", defs, 3, num, str, given, &err) == 0);
    CHECK(num[0] == 7 && num[1] == 0.25 && num[2] == 1 && given[0] && given[2]);
    CHECK(accel_parse_kv("t", "", defs, 3, num, str, given, &err) == 0);
    CHECK(num[0] == 4 && num[1] == 0.5 && num[2] == 0 && !given[0]);
    CHECK(accel_parse_kv("t", "n=11", defs, 3, num, str, given, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "out of range") != NULL, "%s", err.msg);
    CHECK(accel_parse_kv("t", "n=2.5", defs, 3, num, str, given, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_parse_kv("t", "x=nan", defs, 3, num, str, given, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_parse_kv("t", "x=", defs, 3, num, str, given, &err) == ACCEL_ERR_SPEC);
    CHECK(accel_parse_kv("t", "on=maybe", defs, 3, num, str, given, &err) == ACCEL_ERR_SPEC);
}

TEST(core_ray_prep_rejects_bad_rays)
{
    accel_ray_prep p;
    accel_ray ok = {0, 0, 0, 0, 0, 0, 1, INFINITY};
    CHECK(accel_prep_ray(&ok, &p) == 1);
    CHECK(p.kz == 2);
    accel_ray zero = {0, 0, 0, 0, 0, 0, 0, INFINITY};
    CHECK(accel_prep_ray(&zero, &p) == 0);
    accel_ray nan_o = {NAN, 0, 0, 0, 0, 0, 1, INFINITY};
    CHECK(accel_prep_ray(&nan_o, &p) == 0);
    accel_ray inv = {0, 0, 0, 2, 0, 0, 1, 1};
    CHECK(accel_prep_ray(&inv, &p) == 0);
    accel_ray nan_t = {0, 0, 0, NAN, 0, 0, 1, 1};
    CHECK(accel_prep_ray(&nan_t, &p) == 0);
}

TEST(core_slab_edge_cases)
{
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    accel_ray_prep p;
    float te;
    /* Along +x with y on the box's face plane and -0 / +0 components. */
    accel_ray r1 = {-1, 0, 0.5f, 0, 1, -0.0f, 0.0f, INFINITY};
    accel_prep_ray(&r1, &p);
    CHECK(box3_slab(lo, hi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 1);
    CHECK(te == 1.0f);
    accel_ray r2 = {-1, 1, 1, 0, 1, 0.0f, -0.0f, INFINITY}; /* along an edge */
    accel_prep_ray(&r2, &p);
    CHECK(box3_slab(lo, hi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 1);
    accel_ray r3 = {-1, 1.0001f, 0.5f, 0, 1, 0.0f, 0.0f, INFINITY}; /* just outside */
    accel_prep_ray(&r3, &p);
    CHECK(box3_slab(lo, hi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 0);
    accel_ray r4 = {0.5f, 0.5f, 0.5f, 0, 1, 1, 1, INFINITY}; /* inside */
    accel_prep_ray(&r4, &p);
    CHECK(box3_slab(lo, hi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 1);
    CHECK(te == 0.0f);
    accel_ray r5 = {-1, 0.5f, 0.5f, 0, 1, 0, 0, 0.5f}; /* stops short */
    accel_prep_ray(&r5, &p);
    CHECK(box3_slab(lo, hi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 0);
    accel_ray r6 = {2, 0.5f, 0.5f, 0, -1, 0, 0, INFINITY}; /* from the other side */
    accel_prep_ray(&r6, &p);
    CHECK(box3_slab(lo, hi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 1);
    CHECK(te == 1.0f);
    /* Flat box (zero thickness in z), ray in its plane and across it. */
    const float flo[3] = {0, 0, 0}, fhi[3] = {1, 1, 0};
    accel_ray r7 = {0.5f, 0.5f, 1, 0, 0, 0, -1, INFINITY};
    accel_prep_ray(&r7, &p);
    CHECK(box3_slab(flo, fhi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 1);
    accel_ray r8 = {-1, 0.5f, 0, 0, 1, 0, 0, INFINITY};
    accel_prep_ray(&r8, &p);
    CHECK(box3_slab(flo, fhi, p.org, p.inv_dir, p.neg, p.t_near, p.t_far, &te) == 1);
}

/* Two triangles sharing the diagonal of the unit square in z = 0. */
static const float quad[2][9] = {{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}};

static int hits_quad(const accel_ray *r, int naive, float *t_out)
{
    accel_ray_prep p;
    if (!accel_prep_ray(r, &p)) return 0;
    int n = 0;
    for (int i = 0; i < 2; i++) {
        float t = p.t_far, u, v;
        int h = naive ? accel_tri_naive(&p, quad[i], &t, &u, &v)
                      : accel_tri_watertight(&p, quad[i], &t, &u, &v);
        if (h) {
            n++;
            *t_out = t;
        }
    }
    return n;
}

TEST(core_watertight_edges_and_vertices)
{
    float t = 0;
    /* Exactly through the shared diagonal, many positions and slopes. */
    int misses = 0;
    for (int i = 1; i < 200; i++) {
        float s = (float)i / 200.0f;
        /* Straight down, and slanted rays that cross z = 0 at (s, s) exactly. */
        accel_ray straight = {s, s, 1, 0, 0, 0, -1, INFINITY};
        accel_ray slanted = {s - 0.25f, s + 0.125f, 1, 0, 0.25f, -0.125f, -1, INFINITY};
        if (hits_quad(&straight, 0, &t) == 0) misses++;
        if (hits_quad(&slanted, 0, &t) == 0) misses++;
    }
    CHECKF(misses == 0, "%d rays through the shared edge missed both triangles", misses);
    /* The shared vertex (0,0,0) and the square's corners: hit, t = 1. */
    accel_ray v0 = {0, 0, 1, 0, 0, 0, -1, INFINITY};
    CHECK(hits_quad(&v0, 0, &t) >= 1 && t == 1.0f);
    accel_ray v1 = {1, 1, 1, 0, 0, 0, -1, INFINITY};
    CHECK(hits_quad(&v1, 0, &t) >= 1);
    /* Outside by one ULP: miss. */
    accel_ray out = {nextafterf(1.0f, 2.0f), 0.5f, 1, 0, 0, 0, -1, INFINITY};
    CHECK(hits_quad(&out, 0, &t) == 0);
    /* t range is inclusive of t_far and exclusive beyond. */
    accel_ray at = {0.25f, 0.5f, 1, 0, 0, 0, -1, 1.0f};
    CHECK(hits_quad(&at, 0, &t) == 1);
    accel_ray before = {0.25f, 0.5f, 1, 0, 0, 0, -1, 0.999f};
    CHECK(hits_quad(&before, 0, &t) == 0);
    accel_ray after = {0.25f, 0.5f, 1, 1.001f, 0, 0, -1, INFINITY};
    CHECK(hits_quad(&after, 0, &t) == 0);
    /* Barycentrics: u, v weigh the 2nd and 3rd vertex. */
    accel_ray_prep p;
    accel_ray b = {0.75f, 0.25f, 1, 0, 0, 0, -1, INFINITY};
    accel_prep_ray(&b, &p);
    float tt = INFINITY, u = -1, v = -1;
    CHECK(accel_tri_watertight(&p, quad[0], &tt, &u, &v) == 1);
    CHECKF(fabsf(u - 0.5f) < 1e-6f && fabsf(v - 0.25f) < 1e-6f, "u %g v %g", u, v);
    /* Degenerate triangle: never hit. */
    const float deg[9] = {0, 0, 0, 1, 1, 0, 2, 2, 0};
    accel_ray d = {1, 1, 1, 0, 0, 0, -1, INFINITY};
    accel_prep_ray(&d, &p);
    tt = INFINITY;
    CHECK(accel_tri_watertight(&p, deg, &tt, &u, &v) == 0);
}

/* The absolute slacks every bound of the triangle tests adds are normal
 * floats: a subnormal operand takes a microcode assist on Intel cores (the
 * 2^-140 this slack once was made the 8-wide kernels 5x slower there;
 * core/prim.h), and the slack of the packets' leaf cull likewise. */
TEST(core_bound_slacks_are_normal_floats)
{
    CHECKF(ACCEL_EDGE_TINY >= FLT_MIN, "ACCEL_EDGE_TINY %g is subnormal", (double)ACCEL_EDGE_TINY);
    CHECKF(ACCEL_AFF_ABS >= FLT_MIN, "ACCEL_AFF_ABS %g is subnormal", (double)ACCEL_AFF_ABS);
    CHECK(ACCEL_AFF_REL > 0.0f && ACCEL_AFF_REL < 0x1p-8f);
}

TEST(core_naive_moller_trumbore_agrees_inside)
{
    float t = 0;
    accel_ray r = {0.7f, 0.2f, 3, 0, 0.01f, 0.02f, -1, INFINITY};
    CHECK(hits_quad(&r, 1, &t) == 1);
    CHECKF(fabsf(t - 3.0f) < 1e-5f, "t %g", t);
}

TEST(core_sphere_hits)
{
    const float s[4] = {0, 0, 10, 2};
    accel_ray_prep p;
    accel_ray r = {0, 0, 0, 0, 0, 0, 1, INFINITY};
    accel_prep_ray(&r, &p);
    float t = INFINITY, u, v;
    CHECK(accel_sphere_hit(&p, s, &t, &u, &v) == 1 && fabsf(t - 8) < 1e-5f);
    accel_ray inside = {0, 0, 10, 0, 1, 0, 0, INFINITY};
    accel_prep_ray(&inside, &p);
    t = INFINITY;
    CHECK(accel_sphere_hit(&p, s, &t, &u, &v) == 1 && fabsf(t - 2) < 1e-5f);
    accel_ray miss = {0, 2.01f, 0, 0, 0, 0, 1, INFINITY};
    accel_prep_ray(&miss, &p);
    t = INFINITY;
    CHECK(accel_sphere_hit(&p, s, &t, &u, &v) == 0);
    /* Far away, small sphere: the cancellation-free form still hits. */
    const float far[4] = {0, 0, 1e6f, 1};
    accel_ray fr = {0.5f, 0, 0, 0, 0, 0, 1, INFINITY};
    accel_prep_ray(&fr, &p);
    t = INFINITY;
    CHECK(accel_sphere_hit(&p, far, &t, &u, &v) == 1);
}

TEST(core_ray_hit_files_round_trip)
{
    accel_error err = {0};
    accel_ray rays[3] = {{1, 2, 3, 0, 0, 0, 1, INFINITY},
                         {-1, -2, -3, 0.5f, 1, 0, 0, 7},
                         {0, -0.0f, 0, 0, 0, 1, 0, 1e30f}};
    const char *rp = "build/test_roundtrip.rays", *hp = "build/test_roundtrip.hits";
    CHECK(rays_write(rp, rays, 3, &err) == 0);
    rays_set in;
    CHECK(rays_read(rp, &in, &err) == 0);
    CHECK(in.count == 3 && memcmp(in.rays, rays, sizeof rays) == 0);
    rays_free(&in);
    accel_hit hits[2] = {{1.5f, 7, 0.25f, 0.5f}, accel_hit_miss()};
    CHECK(hits_write(hp, hits, 2, &err) == 0);
    accel_hit *h;
    size_t n;
    CHECK(hits_read(hp, &h, &n, &err) == 0);
    CHECK(n == 2 && memcmp(h, hits, sizeof hits) == 0);
    free(h);
    /* The header is exactly FORMATS.md's: magic, version 1, u64 count. */
    FILE *f = fopen(hp, "rb");
    unsigned char head[16];
    CHECK(f && fread(head, 1, 16, f) == 16);
    if (f) fclose(f);
    CHECK(memcmp(head, "HITS", 4) == 0 && head[4] == 1 && head[8] == 2 && head[15] == 0);
    /* A lying count is refused before allocating. */
    f = fopen(rp, "r+b");
    if (f) {
        fseek(f, 8, SEEK_SET);
        unsigned char big[8] = {0, 0, 0, 0x80, 0, 0, 0, 0};
        fwrite(big, 1, 8, f);
        fclose(f);
    }
    CHECK(rays_read(rp, &in, &err) == ACCEL_ERR_PARSE);
    CHECKF(strstr(err.msg, rp) != NULL, "message names the file: %s", err.msg);
    CHECK(rays_read("build/does_not_exist.rays", &in, &err) == ACCEL_ERR_IO);
    /* A directory is named as one, not as a truncated header. */
    CHECK(rays_read("build", &in, &err) == ACCEL_ERR_IO);
    CHECKF(strstr(err.msg, "not a regular file (a directory)") != NULL, "%s", err.msg);
    /* Records FORMATS.md does not allow: a miss with a distance, a NaN t
     * (which no |t1 - t2| test would ever call a disagreement). */
    accel_hit miss_at = accel_hit_miss(), nan_t = {NAN, 3, 0, 0};
    miss_at.t = 2.0f;
    const accel_hit *bad[2] = {&miss_at, &nan_t};
    const char *why[2] = {"hit record 1 is a miss (prim 0xFFFFFFFF) whose t is not +infinity",
                          "hit record 1 is a hit whose t is NaN"};
    for (int k = 0; k < 2; k++) {
        accel_hit two[2] = {{1.5f, 7, 0.25f, 0.5f}, *bad[k]};
        CHECK(hits_write(hp, two, 2, &err) == 0);
        h = NULL;
        CHECK(hits_read(hp, &h, &n, &err) == ACCEL_ERR_PARSE && h == NULL && n == 0);
        CHECKF(strstr(err.msg, why[k]) && strstr(err.msg, hp) && strstr(err.msg, "byte 32"), "%s",
               err.msg);
    }
}

TEST(core_compare_rule)
{
    /* Without the scene: the same triangle at the same t, u, v agrees; a
     * different triangle at the same t is an unverified tie, never an
     * agreement; the same triangle at another t or u is a disagreement. */
    accel_hit a = {10.0f, 1, 0.25f, 0.25f}, b = {10.0005f, 2, 0, 0}, c = {10.01f, 2, 0, 0};
    accel_hit a_u = {10.0f, 1, 0.3f, 0.25f}, a_t = {10.01f, 1, 0.25f, 0.25f};
    accel_hit m = accel_hit_miss();
    CHECK(hits_match_ray(NULL, NULL, &a, &a) == HITS_AGREE);
    CHECK(hits_match_ray(NULL, NULL, &a, &b) == HITS_TIE_UNVERIFIED && !hits_agree(NULL, NULL, &a, &b));
    CHECK(hits_match_ray(NULL, NULL, &a, &c) == HITS_DISAGREE);
    CHECK(hits_match_ray(NULL, NULL, &a, &a_u) == HITS_DISAGREE);
    CHECK(hits_match_ray(NULL, NULL, &a, &a_t) == HITS_DISAGREE);
    CHECK(hits_match_ray(NULL, NULL, &a, &m) == HITS_HOLE);
    CHECK(hits_match_ray(NULL, NULL, &m, &a) == HITS_FALSE_HIT);
    CHECK(hits_agree(NULL, NULL, &m, &m));
    /* Two hits beyond FLT_MAX (t rounded to +inf in both) on one triangle
     * are at the same distance (FORMATS.md's |t1 - t2| is NaN there). */
    accel_hit fi = {INFINITY, 3, 0, 0}, gi = {INFINITY, 4, 0, 0};
    CHECK(hits_agree(NULL, NULL, &fi, &fi) &&
          hits_match_ray(NULL, NULL, &fi, &gi) == HITS_TIE_UNVERIFIED);
    accel_hit x[4] = {a, a, m, a}, y[4] = {c, m, a, b};
    hits_diff d = hits_compare(NULL, NULL, x, y, 4);
    CHECK(d.disagreements == 1 && d.holes == 1 && d.false_hits == 1 && d.unverified == 1 &&
          d.agree == 0 && d.first_bad == 0);

    /* With the scene: two triangles sharing the edge x = 1 of the square
     * [0,2]x[0,1] in z = 0, rays straight down (t = 5). */
    scene_builder sb = {0};
    test_add_tri(&sb, v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0)); /* 0 */
    test_add_tri(&sb, v3(1, 0, 0), v3(2, 0, 0), v3(1, 1, 0)); /* 1: shares the edge (1,0)-(1,1) */
    test_add_tri(&sb, v3(5, 5, 0), v3(6, 5, 0), v3(5, 6, 0)); /* 2: far away */
    accel_scene s;
    if (!test_finish(&sb, "two", &s)) return;
    accel_ray edge = {1.0f, 0.5f, 5.0f, 0.0f, 0.0f, 0.0f, -1.0f, INFINITY};
    accel_ray in0 = {0.75f, 0.25f, 5.0f, 0.0f, 0.0f, 0.0f, -1.0f, INFINITY};
    accel_hit ref[2], got[2];
    accel_reference_trace(&s, &edge, &ref[0], 1, 1);
    accel_reference_trace(&s, &in0, &ref[1], 1, 1);
    CHECKF(ref[0].prim <= 1 && ref[1].prim == 0 && ref[1].t == 5.0f, "oracle: prims %u %u",
           ref[0].prim, ref[1].prim);
    /* the other triangle at the shared edge, with its own u, v: a true tie */
    accel_hit other = {5.0f, 1 - ref[0].prim, 0.0f, 0.0f};
    other.u = other.prim == 1 ? 0.0f : 0.5f, other.v = 0.5f;
    CHECK(hits_verify(&s, &edge, &ref[0]) && hits_verify(&s, &edge, &other));
    CHECK(hits_match_ray(&s, &edge, &ref[0], &other) == HITS_TIE);
    /* inside triangle 0 only: triangle 1 or 2 at the right t is wrong */
    got[1] = ref[1], got[1].prim = 1;
    CHECK(!hits_verify(&s, &in0, &got[1]) && hits_match_ray(&s, &in0, &ref[1], &got[1]) == HITS_DISAGREE);
    got[1].prim = 2;
    CHECK(hits_match_ray(&s, &in0, &ref[1], &got[1]) == HITS_DISAGREE);
    /* a triangle's own hit with u, v of another point: not hit there */
    got[1] = ref[1], got[1].u += 0.1f;
    CHECK(!hits_verify(&s, &in0, &got[1]));
    /* compare over both rays, and the any-hit rule's triangle check */
    accel_ray rs[2] = {edge, in0};
    got[0] = other, got[1] = ref[1];
    d = hits_compare(&s, rs, ref, got, 2);
    CHECKF(d.agree == 2 && d.ties == 1, "agree %zu ties %zu", d.agree, d.ties);
    got[1].prim = 2;
    hits_anyhit_diff ad = hits_compare_anyhit(&s, rs, ref, got, 2);
    CHECKF(ad.agree == 1 && ad.false_hits == 1 && ad.first_bad == 1, "any-hit: agree %zu false %zu",
           ad.agree, ad.false_hits);
    scene_free(&s);
}

TEST(core_ray_sets_deterministic)
{
    accel_camera cam = {{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 45};
    rays_set a, b;
    accel_error err = {0};
    CHECK(rays_primary(&cam, 20, 13, &a, &err) == 0);
    CHECK(rays_primary(&cam, 20, 13, &b, &err) == 0);
    CHECK(a.count == 260 && memcmp(a.rays, b.rays, a.count * sizeof *a.rays) == 0);
    /* Every pixel exactly once; the first 64 rays are the first 8x8 tile. */
    int seen[260] = {0}, ok = 1;
    for (size_t i = 0; i < a.count; i++) seen[a.pixel[i]]++;
    for (int i = 0; i < 260; i++) ok &= seen[i] == 1;
    CHECK(ok);
    CHECK(a.pixel[63] == 7 * 20 + 7 && a.pixel[64] == 8);
    rays_free(&a);
    rays_free(&b);
    CHECK(rays_rand(1, 2, 3) == rays_rand(1, 2, 3) && rays_rand(1, 2, 3) != rays_rand(1, 3, 3));
    double sum = 0;
    for (int i = 0; i < 10000; i++) sum += rays_rand(5, (uint64_t)i, 0);
    CHECKF(fabs(sum / 10000 - 0.5) < 0.02, "mean %g", sum / 10000);
}

TEST(core_offset_origin_leaves_surface)
{
    /* A point on a tilted plane far from the origin: the offset origin must
     * be strictly on the normal side, so a ray leaving never re-hits it. */
    const float tri[9] = {1e4f, 1e4f, 1e4f, 1e4f + 3, 1e4f + 1, 1e4f, 1e4f, 1e4f + 2, 1e4f + 5};
    vec3 a = v3_load(tri), b = v3_load(tri + 3), c = v3_load(tri + 6);
    vec3 n = v3_norm(v3_cross(v3_sub(b, a), v3_sub(c, a)));
    int bad = 0;
    for (int i = 0; i < 1000; i++) {
        float u = rays_rand(3, (uint64_t)i, 0) * 0.5f, v = rays_rand(3, (uint64_t)i, 1) * 0.5f;
        vec3 p = v3_add(v3_scale(a, 1 - u - v), v3_add(v3_scale(b, u), v3_scale(c, v)));
        vec3 o = rays_offset_origin(p, n);
        /* Leave along a grazing direction: mostly tangent, slightly up. */
        vec3 t = v3_norm(v3_sub(b, a));
        vec3 d = v3_add(t, v3_scale(n, 1e-3f));
        accel_ray r = {o.x, o.y, o.z, 0, d.x, d.y, d.z, INFINITY};
        accel_ray_prep pr;
        accel_prep_ray(&r, &pr);
        float tt = INFINITY, uu, vv;
        if (accel_tri_watertight(&pr, tri, &tt, &uu, &vv)) bad++;
    }
    CHECKF(bad == 0, "%d of 1000 offset rays re-hit their own triangle", bad);
}

TEST(core_huge_coordinates_no_nan)
{
    /* Coordinates near 1e22: float products overflow; the decision must
     * fall to the double test, never a NaN hit. */
    const float big = 1.25e22f;
    const float tri[9] = {big, -1e21f, 0, big + 1e21f, 1e21f, 0, big - 1e21f, 1e21f, 0};
    accel_ray_prep p;
    accel_ray r = {big, 0, 1e22f, 0, 0, 0, -1, INFINITY};
    CHECK(accel_prep_ray(&r, &p) == 1);
    float t = INFINITY, u, v;
    int hit = accel_tri_watertight(&p, tri, &t, &u, &v);
    CHECKF(!hit || (t == t && fabsf(t - 1e22f) <= 1e16f), "hit %d t %g", hit, t);
    accel_ray miss = {big * 3, 0, 1e22f, 0, 0, 0, -1, INFINITY};
    accel_prep_ray(&miss, &p);
    t = INFINITY;
    CHECK(accel_tri_watertight(&p, tri, &t, &u, &v) == 0);
}

TEST(core_ray_in_triangle_plane_misses)
{
    /* The ray lies in the triangle's plane: edge-on, no hit (the rounded
     * determinant is tiny, not zero, and must not yield an arbitrary t). */
    const float tri[9] = {2, 1, 4, 2, 0, 4.5f, 1.5f, 0, 4};
    accel_ray r = {3, 1, 5, 0, -2, 3, -3.5f, INFINITY};
    accel_ray_prep p;
    CHECK(accel_prep_ray(&r, &p) == 1);
    float t = INFINITY, u, v;
    int hit = accel_tri_watertight(&p, tri, &t, &u, &v);
    accel_hit ref;
    accel_scene s = {0};
    float tris[9];
    memcpy(tris, tri, sizeof tris);
    uint32_t live = 0;
    s.tri_count = s.prim_count = s.live_count = 1;
    s.tris = tris;
    s.live = &live;
    accel_reference_trace(&s, &r, &ref, 1, 1);
    CHECKF(ref.prim == ACCEL_MISS, "reference hits an edge-on triangle at t %g", ref.t);
    CHECKF(!hit, "float kernel hits an edge-on triangle at t %g", t);
}

TEST(core_huge_triangle_grazing_origin)
{
    /* A ray starting just above a huge ground triangle and leaving it: the
     * float T sums large terms to a tiny value; it must not report a hit
     * (found on teapot_stadium's ground by the nested grid's tests). */
    const float tri[9] = {0, 0, -0.00999999978f, 870.854004f, 2870.82104f, -0.00999999978f,
                          728.940552f, 2910.09375f, -0.00999999978f};
    accel_ray r = {11.3944912f, 41.7122116f, -0.00998474099f, 0,
                   -0.532983184f, 0.705718935f, 0.466786623f, INFINITY};
    accel_ray_prep p;
    CHECK(accel_prep_ray(&r, &p) == 1);
    float t = INFINITY, u, v;
    CHECKF(accel_tri_watertight(&p, tri, &t, &u, &v) == 0, "false hit at t %g", t);
}

/* The float test decides only what the double test decides the same way:
 * small triangles far from the origin and from the ray's origin (where the
 * edge filter's tight bound matters: sheared coordinates tiny next to the
 * distances), rays aimed at edges, vertices and points a few ULPs off them,
 * t ranges ending at the hit. Every float answer (hit or miss, and the hit's
 * t to 1e-3) must equal the double test's. */
TEST(core_edge_filter_agrees_with_double)
{
    int disagree = 0, prepared = 0, total = 0;
    for (int i = 0; i < 60000; i++) {
        float rr[12];
        for (int k = 0; k < 12; k++) rr[k] = rays_rand(11, (uint64_t)i, (uint32_t)k);
        float scale = powf(10.0f, -4.0f + 4.0f * rr[0]);   /* triangle size 1e-4..1 */
        float far = powf(10.0f, -1.0f + 5.0f * rr[1]);     /* origin distance 0.1..1e4 */
        float cx = 1000.0f * (rr[2] - 0.5f), cy = -300.0f * rr[3], cz = 50.0f;
        float tri[9];
        for (int k = 0; k < 9; k++) tri[k] = (k % 3 == 0 ? cx : k % 3 == 1 ? cy : cz) +
                                             scale * (rays_rand(12, (uint64_t)i, (uint32_t)k) - 0.5f);
        /* Target: a vertex, an edge point or an inside point, nudged by 0..4 ULPs. */
        int e = (int)(rr[4] * 3.0f) % 3, kind = (int)(rr[5] * 3.0f) % 3;
        const float *p0 = tri + 3 * e, *p1 = tri + 3 * ((e + 1) % 3), *p2 = tri + 3 * ((e + 2) % 3);
        float s = rr[6], w = kind == 2 ? 0.3f : 0.0f;
        float tgt[3];
        for (int k = 0; k < 3; k++) {
            float x = kind == 0 ? p0[k] : (1 - s - w) * p0[k] + s * p1[k] + w * p2[k];
            for (int n = (int)(rr[7] * 5.0f); n > 0; n--) x = nextafterf(x, rr[8] < 0.5f ? -INFINITY : INFINITY);
            tgt[k] = x;
        }
        float d0 = rr[9] - 0.5f, d1 = rr[10] - 0.5f, d2 = rr[11] - 0.5f;
        float dl = sqrtf(d0 * d0 + d1 * d1 + d2 * d2) + 1e-6f;
        accel_ray r = {tgt[0] - far * d0 / dl, tgt[1] - far * d1 / dl, tgt[2] - far * d2 / dl, 0,
                       d0, d1, d2, INFINITY};
        accel_ray_prep p;
        if (!accel_prep_ray(&r, &p)) continue;
        for (int range = 0; range < 2; range++) {
            float tf = INFINITY, uf, vf;
            double td = INFINITY, ud, vd;
            accel_ray_d rd;
            accel_prep_ray_d(&p, &rd);
            if (range) { /* a t range ending about at the hit: t decided at its end */
                if (!accel_tri_watertight_d(&rd, tri, &td, &ud, &vd)) continue;
                tf = (float)td;
                td = tf;
            }
            int hf = accel_tri_watertight(&p, tri, &tf, &uf, &vf);
            int hd = accel_tri_watertight_d(&rd, tri, &td, &ud, &vd);
            total++;
            /* t: float's T / det on slivers is good to about 1e-5 only */
            if (hf != hd || (hf && fabs(tf - td) > 1e-3 * fabs(td))) disagree++;
        }
        prepared++;
    }
    CHECKF(disagree == 0, "%d of %d float answers differ from the double test", disagree, total);
    CHECKF(prepared > 50000 && total > 80000, "only %d rays prepared, %d answers", prepared, total);
}
