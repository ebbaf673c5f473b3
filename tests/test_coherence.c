/*
 * test_coherence.c - packets in any ray order (core/coherence.h): every
 * packet mode traced on shuffled and scanline-ordered rays gives, ray by
 * ray and bit for bit, the answers of the same kernel on 8x8 tiles without
 * reordering (ACCEL_ORDER_KEEP); the packet kernels' answers do not depend
 * on their packet mates (shuffled rays with ACCEL_ORDER_KEEP); per-ray
 * counters land at the caller's index; scanline primaries are sorted into
 * packets and diffuse bounces go ray by ray. Also rays_reorder's orders.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/coherence.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

static const char *const packet_specs[] = {
    "grid:traverse=packet",          "nested_grid:traverse=packet",
    "bvh:traverse=packet",           "bvh:traverse=packet,frustum=1",
    "bvh:width=4,traverse=packet",   "bvh:width=8,traverse=packet",
    "bvh:width=8,traverse=packet,hybrid=0", "instanced:traverse=packet",
};

/* perm: a seeded shuffle of 0..n-1 */
static size_t *shuffle_perm(size_t n, uint64_t seed)
{
    size_t *p = malloc((n ? n : 1) * sizeof *p);
    for (size_t i = 0; i < n; i++) p[i] = i;
    for (size_t i = n; i > 1; i--) {
        size_t j = (size_t)(rays_rand(seed, i, 7) * (float)i);
        if (j >= i) j = i - 1;
        size_t t = p[i - 1]; p[i - 1] = p[j], p[j] = t;
    }
    return p;
}

/* Traces rays[perm[i]] (perm NULL: in order) with the packet order `order`
 * and returns the answers at the original indices. */
static void trace_perm(const accel_kind *k, const void *a, const accel_ray *rays, const size_t *perm,
                       size_t n, int occl, int order, accel_hit *hits, uint8_t *occ)
{
    accel_ray *r = malloc((n ? n : 1) * sizeof *r);
    accel_hit *h = malloc((n ? n : 1) * sizeof *h);
    uint8_t *o = malloc(n ? n : 1);
    for (size_t i = 0; i < n; i++) r[i] = rays[perm ? perm[i] : i];
    const int before = accel_coherence_get();
    accel_coherence_set(order);
    if (occl) k->occluded(a, r, o, n, NULL);
    else k->intersect(a, r, h, n, NULL);
    accel_coherence_set(before);
    for (size_t i = 0; i < n; i++) {
        const size_t j = perm ? perm[i] : i;
        if (occl) occ[j] = o[i];
        else hits[j] = h[i];
    }
    free(r), free(h), free(o);
}

/* Within `ulps` float steps of the larger (0: the same bits); barycentrics
 * (in [0, 1], rounded on the scale of 1) within ulps steps of 1. */
static int close_floats(float a, float b, int ulps, int bary)
{
    if (!memcmp(&a, &b, sizeof a)) return 1;
    const float scale = bary ? 1.0f : fmaxf(fabsf(a), fabsf(b));
    return ulps > 0 && fabsf(a - b) <= (float)ulps * 0x1p-23f * scale;
}

/* Rays whose answers differ from the reference: any bit when ulps == 0,
 * else the primitive or the occlusion, or t, u, v by more than ulps steps. */
static size_t differences(const accel_hit *ref, const accel_hit *hits, const uint8_t *ref_occ,
                          const uint8_t *occ, size_t n, int occl, int ulps)
{
    size_t bad = 0;
    for (size_t i = 0; i < n; i++) {
        const int d = occl ? ref_occ[i] != occ[i]
                           : ref[i].prim != hits[i].prim || !close_floats(ref[i].t, hits[i].t, ulps, 0) ||
                                 !close_floats(ref[i].u, hits[i].u, ulps, 1) ||
                                 !close_floats(ref[i].v, hits[i].v, ulps, 1);
        if (d && bad < 3 && !occl && getenv("COH_DEBUG"))
            test_note("ray %zu: %a %u %a %a vs %a %u %a %a", i, ref[i].t, ref[i].prim, ref[i].u,
                      ref[i].v, hits[i].t, hits[i].prim, hits[i].u, hits[i].v);
        bad += d;
    }
    return bad;
}

/* The bits a packet mode's answers may change with its packet mates. The
 * grids' packets test a primitive for a ray in another order, and with
 * other repeats, than their single-ray kernel: the watertight test decides
 * a hit within its error of the current nearest one in double
 * (core/prim.h), so t, u, v of the same primitive may come from either
 * computation (a few float steps apart). The BVH packets' answers are the
 * same bits whatever their mates, and so are instanced's (each ray's
 * triangles decided on its whole range, inst_ray.h). */
static int mate_ulps(const char *spec)
{
    return strncmp(spec, "bvh", 3) && strncmp(spec, "instanced", 9) ? 16 : 0;
}

typedef struct {
    const char *name;
    rays_set set;
    int occl;
} ray_case;

/* Primary rays (tiles), their shadow and diffuse rays on s, and primary
 * rays of a 4-degree view (shuffled, they still sort into packets: the
 * gather path of every kind). */
#define CASES 4
static int make_cases(const accel_scene *s, ray_case c[CASES])
{
    accel_error err;
    memset(c, 0, CASES * sizeof *c);
    accel_camera narrow = s->camera;
    narrow.fov_deg = 4.0f;
    /* Two sorting blocks, the second starting mid-row (88 does not divide
     * the block). */
    _Static_assert(88 * 128 > ACCEL_COHERENCE_BLOCK && 88 * 128 <= 2 * ACCEL_COHERENCE_BLOCK &&
                       ACCEL_COHERENCE_BLOCK % 88 != 0, "two blocks, the second mid-row");
    if (rays_primary(&s->camera, 88, 128, &c[0].set, &err)) return 0;
    if (rays_primary(&narrow, 88, 64, &c[3].set, &err)) return 0;
    c[3].name = "narrow primary";
    accel_hit *ref = malloc(c[0].set.count * sizeof *ref);
    accel_reference_trace(s, c[0].set.rays, ref, c[0].set.count, 1);
    int ok = !rays_shadow(s, &c[0].set, ref, &c[1].set, &err) &&
             !rays_diffuse(s, &c[0].set, ref, 3, &c[2].set, &err);
    free(ref);
    c[0].name = "primary", c[1].name = "shadow", c[2].name = "diffuse", c[1].occl = 1;
    return ok;
}

/* check(spec, kind, a, cases) for each spec of specs[0..nspecs) built on
 * sphereflake:level=2, with its ray cases (make_cases). */
typedef void (*kind_check)(const char *spec, const accel_kind *kind, const void *a, const ray_case *cases);
static void each_kind_on_cases(const char *const *specs, size_t nspecs, kind_check check)
{
    accel_scene s;
    if (!test_make_scene("sphereflake:level=2", &s)) return;
    ray_case cases[CASES];
    CHECK(make_cases(&s, cases));
    for (size_t k = 0; k < nspecs; k++) {
        const accel_kind *kind;
        void *a = test_build_kind(specs[k], &s, 1, &kind, NULL);
        if (!a) continue;
        check(specs[k], kind, a, cases);
        kind->destroy(a);
    }
    for (int ci = 0; ci < CASES; ci++) rays_free(&cases[ci].set);
    scene_free(&s);
}
#define PACKET_SPECS packet_specs, sizeof packet_specs / sizeof *packet_specs

static void same_answers_one_case(const char *spec, const accel_kind *kind, const void *a, const ray_case *c,
                                  int ci)
{
    const size_t n = c->set.count;
    accel_hit *ref = malloc(n * sizeof *ref), *hits = malloc(n * sizeof *hits);
    uint8_t *ref_occ = malloc(n), *occ = malloc(n);
    size_t *perm = shuffle_perm(n, 11 + (uint64_t)ci);
    trace_perm(kind, a, c->set.rays, NULL, n, c->occl, ACCEL_ORDER_KEEP, ref, ref_occ);
    /* packet mates must not matter: shuffled packets as they come */
    trace_perm(kind, a, c->set.rays, perm, n, c->occl, ACCEL_ORDER_KEEP, hits, occ);
    size_t bad = differences(ref, hits, ref_occ, occ, n, c->occl, mate_ulps(spec));
    CHECKF(bad == 0, "%s, %s rays shuffled, packets kept: %zu of %zu answers differ", spec, c->name, bad, n);
    /* sorted into packets, scattered back */
    accel_coherence_stats st0, st1;
    accel_coherence_stats_get(&st0);
    trace_perm(kind, a, c->set.rays, perm, n, c->occl, ACCEL_ORDER_SORT, hits, occ);
    accel_coherence_stats_get(&st1);
    bad = differences(ref, hits, ref_occ, occ, n, c->occl, mate_ulps(spec));
    CHECKF(bad == 0, "%s, %s rays shuffled, sorted: %zu of %zu answers differ", spec, c->name, bad, n);
    CHECKF(ci != 3 || (st1.sorted_blocks > st0.sorted_blocks && st1.packet_rays - st0.packet_rays >= n / 2),
           "%s, %s rays shuffled: not sorted into packets", spec, c->name);
    free(ref), free(hits), free(ref_occ), free(occ), free(perm);
}

static void same_answers_any_order(const char *spec, const accel_kind *kind, const void *a,
                                   const ray_case *cases)
{
    for (int ci = 0; ci < CASES; ci++) same_answers_one_case(spec, kind, a, &cases[ci], ci);
}

TEST(coherence_any_order_same_answers)
{
    each_kind_on_cases(PACKET_SPECS, same_answers_any_order);
}

/* Ray i of a set poisoned (every POISON_EVERY-th, and every ray of the
 * second packet of 64): one of the rays FORMATS.md lets a file hold that
 * can hit nothing (a NaN or zero direction, an infinite origin, an empty
 * or NaN range). Returns 1 when ray i was replaced. */
#define POISON_EVERY 29
static int poison(accel_ray *r, size_t i)
{
    if (i % POISON_EVERY != 3 && (i < 64 || i >= 128)) return 0;
    switch (i % 6) {
    case 0: r->dx = NAN; break;
    case 1: r->dx = r->dy = r->dz = 0.0f; break;
    case 2: r->ox = INFINITY; break;
    case 3: r->t_near = 5.0f, r->t_far = 1.0f; break;
    case 4: r->t_far = NAN; break;
    default: r->dy = -INFINITY; break;
    }
    return 1;
}

/* Rays that can hit nothing, mixed into the packets (and one packet made
 * of them alone), in every order: each misses, and every other ray keeps
 * the answer it has among clean mates. */
static void bad_rays_miss_one_case(const char *spec, const accel_kind *kind, const void *a, const ray_case *c,
                                   int ci)
{
    const size_t n = c->set.count;
    accel_hit *ref = malloc(n * sizeof *ref), *hits = malloc(n * sizeof *hits);
    uint8_t *ref_occ = malloc(n), *occ = malloc(n), *bad_ray = malloc(n);
    accel_ray *rays = malloc(n * sizeof *rays);
    size_t *perm = shuffle_perm(n, 5 + (uint64_t)ci), poisoned = 0;
    for (size_t i = 0; i < n; i++) {
        rays[i] = c->set.rays[i];
        poisoned += bad_ray[i] = (uint8_t)poison(&rays[i], i);
    }
    trace_perm(kind, a, c->set.rays, NULL, n, c->occl, ACCEL_ORDER_KEEP, ref, ref_occ);
    for (int order = 0; order < 3; order++) { /* tiles kept, sorted, shuffled and sorted */
        trace_perm(kind, a, rays, order == 2 ? perm : NULL, n, c->occl,
                   order == 0 ? ACCEL_ORDER_KEEP : ACCEL_ORDER_SORT, hits, occ);
        size_t missed = 0;
        for (size_t i = 0; i < n; i++) {
            if (!bad_ray[i]) continue;
            missed += c->occl ? !occ[i] : hits[i].prim == ACCEL_MISS && hits[i].t == INFINITY;
            /* the reference takes the bad ray's answer: differences() below
             * sees the clean rays only */
            if (c->occl) ref_occ[i] = occ[i];
            else ref[i] = hits[i];
        }
        const size_t differ = differences(ref, hits, ref_occ, occ, n, c->occl, mate_ulps(spec));
        CHECKF(missed == poisoned, "%s, %s rays (order %d): %zu of %zu bad rays miss", spec, c->name, order,
               missed, poisoned);
        CHECKF(differ == 0, "%s, %s rays (order %d): %zu clean answers changed by bad mates", spec, c->name,
               order, differ);
    }
    free(ref), free(hits), free(ref_occ), free(occ), free(bad_ray), free(rays), free(perm);
}

static void bad_rays_miss(const char *spec, const accel_kind *kind, const void *a, const ray_case *cases)
{
    for (int ci = 0; ci < 2; ci++) bad_rays_miss_one_case(spec, kind, a, &cases[ci], ci); /* primary, shadow */
}

TEST(coherence_bad_rays_in_packets_miss)
{
    each_kind_on_cases(PACKET_SPECS, bad_rays_miss);
}

/* Scanline primaries: gathered into tiles (not kept, not sent ray by ray),
 * the same answers, per-ray counters at the caller's index. */
TEST(coherence_scanline_tiled_into_packets)
{
    accel_scene s;
    if (!test_make_scene("sphereflake:level=2", &s)) return;
    ray_case cases[CASES];
    CHECK(make_cases(&s, cases));
    rays_set scan = cases[0].set;
    const size_t n = scan.count;
    scan.rays = malloc(n * sizeof *scan.rays), scan.pixel = malloc(n * sizeof *scan.pixel);
    memcpy(scan.rays, cases[0].set.rays, n * sizeof *scan.rays);
    memcpy(scan.pixel, cases[0].set.pixel, n * sizeof *scan.pixel);
    accel_error err;
    CHECK(rays_reorder(&scan, RAYS_ORDER_SCANLINE, 0, &err) == 0);
    size_t *perm = malloc(n * sizeof *perm), *tile_of = malloc(n * sizeof *tile_of);
    for (size_t i = 0; i < n; i++) tile_of[cases[0].set.pixel[i]] = i;
    for (size_t i = 0; i < n; i++) {
        CHECK(scan.pixel[i] == i); /* scanline: pixel index order */
        perm[i] = tile_of[scan.pixel[i]];
    }
    for (size_t k = 0; k < sizeof packet_specs / sizeof *packet_specs; k++) {
        const accel_kind *kind;
        void *a = test_build_kind(packet_specs[k], &s, 1, &kind, NULL);
        if (!a) continue;
        accel_hit *ref = malloc(n * sizeof *ref), *hits = malloc(n * sizeof *hits);
        trace_perm(kind, a, cases[0].set.rays, NULL, n, 0, ACCEL_ORDER_KEEP, ref, NULL);
        accel_coherence_stats st0, st1;
        accel_coherence_stats_get(&st0);
        trace_perm(kind, a, cases[0].set.rays, perm, n, 0, ACCEL_ORDER_SORT, hits, NULL);
        accel_coherence_stats_get(&st1);
        const size_t bad = differences(ref, hits, NULL, NULL, n, 0, mate_ulps(packet_specs[k]));
        CHECKF(bad == 0, "%s, scanline primaries: %zu of %zu answers differ", packet_specs[k], bad, n);
        /* other tests may run at once in this process: lower bounds only.
         * 88 wide: both blocks (the second starts mid-row) are gathered
         * into 8x8 tiles, no key sort */
        CHECKF(st1.tiled_blocks - st0.tiled_blocks >= 2, "%s: scanline blocks were not tiled",
               packet_specs[k]);
        CHECKF(st1.packet_rays - st0.packet_rays >= n * 8 / 10, "%s: %llu of %zu rays in packets",
               packet_specs[k], (unsigned long long)(st1.packet_rays - st0.packet_rays), n);
        /* per-ray counters at the caller's index: their sum is the total */
        accel_counters c;
        memset(&c, 0, sizeof c);
        uint32_t *steps = calloc(n, sizeof *steps);
        c.ray_steps = steps;
        const int before = accel_coherence_get();
        accel_coherence_set(ACCEL_ORDER_SORT);
        kind->intersect(a, scan.rays, hits, n, &c);
        accel_coherence_set(before);
        uint64_t sum = 0;
        for (size_t i = 0; i < n; i++) sum += steps[i];
        CHECKF(sum == c.steps && c.ray_steps == steps, "%s: per-ray steps sum %llu, total %llu",
               packet_specs[k], (unsigned long long)sum, (unsigned long long)c.steps);
        free(steps), free(ref), free(hits);
        kind->destroy(a);
    }
    free(perm), free(tile_of), rays_free(&scan);
    for (int ci = 0; ci < CASES; ci++) rays_free(&cases[ci].set);
    scene_free(&s);
}

/* The block decisions on one camera's rays in the three orders, 96 x 64
 * (two blocks, the second starting mid-row): 8x8 tiles are kept as they
 * come, scanline blocks gathered into tiles, shuffled ones key-sorted;
 * every ray in a packet either way. */
TEST(coherence_block_decisions)
{
    accel_scene s;
    if (!test_make_scene("sphereflake:level=1", &s)) return;
    const accel_kind *kind;
    void *a = test_build_kind("bvh:traverse=packet", &s, 1, &kind, NULL);
    rays_set r;
    accel_error err;
    _Static_assert(96 * 128 > ACCEL_COHERENCE_BLOCK && 96 * 128 <= 2 * ACCEL_COHERENCE_BLOCK,
                   "two sorting blocks");
    if (!a || rays_primary(&s.camera, 96, 128, &r, &err)) {
        if (a) kind->destroy(a);
        scene_free(&s);
        CHECK(0);
        return;
    }
    const rays_order orders[3] = {RAYS_ORDER_TILES8, RAYS_ORDER_SCANLINE, RAYS_ORDER_SHUFFLE};
    accel_hit *hits = malloc(r.count * sizeof *hits);
    for (int o = 0; o < 3; o++) {
        CHECK(rays_reorder(&r, orders[o], 3, &err) == 0);
        accel_coherence_stats st0, st1;
        const int before = accel_coherence_get();
        accel_coherence_set(ACCEL_ORDER_SORT);
        accel_coherence_stats_get(&st0);
        kind->intersect(a, r.rays, hits, r.count, NULL);
        accel_coherence_stats_get(&st1);
        accel_coherence_set(before);
        const uint64_t kept = st1.kept_blocks - st0.kept_blocks,
                       tiled = st1.tiled_blocks - st0.tiled_blocks,
                       sorted = st1.sorted_blocks - st0.sorted_blocks;
        CHECKF(o != 0 || (kept == 2 && tiled == 0 && sorted == 0), "tiles: %llu kept, %llu tiled",
               (unsigned long long)kept, (unsigned long long)tiled);
        CHECKF(o != 1 || (kept == 0 && tiled == 2 && sorted == 0), "scanline: %llu kept, %llu tiled",
               (unsigned long long)kept, (unsigned long long)tiled);
        CHECKF(o != 2 || (tiled == 0 && kept + sorted == 2), "shuffle: %llu tiled, %llu sorted",
               (unsigned long long)tiled, (unsigned long long)sorted);
        CHECK(o == 2 || st1.packet_rays - st0.packet_rays == r.count);
    }
    free(hits);
    rays_free(&r);
    kind->destroy(a);
    scene_free(&s);
}

/* Shadow rays cast to the point light from a tiled image's hits converge:
 * their groups go as packets as they come, no keys and no sort (every
 * block kept), whatever their directions' spread; the same rays shuffled
 * are not kept as they come. */
static void shadow_rays_kept(const char *spec, const accel_kind *kind, const void *a, const ray_case *cases)
{
    (void)spec;
    const rays_set *sh = &cases[1].set;
    const size_t n = sh->count;
    uint8_t *occ = malloc(n);
    accel_coherence_stats st0, st1, st2;
    const int before = accel_coherence_get();
    accel_coherence_set(ACCEL_ORDER_SORT);
    accel_coherence_stats_get(&st0);
    kind->occluded(a, sh->rays, occ, n, NULL);
    accel_coherence_stats_get(&st1);
    CHECKF(n > 2 * 64 && st1.sorted_blocks == st0.sorted_blocks && st1.kept_blocks > st0.kept_blocks,
           "tiled shadow rays: %llu blocks sorted, %llu kept",
           (unsigned long long)(st1.sorted_blocks - st0.sorted_blocks),
           (unsigned long long)(st1.kept_blocks - st0.kept_blocks));
    CHECKF(st1.packet_rays - st0.packet_rays >= n * 3 / 4, "tiled shadow rays: %llu of %zu in packets",
           (unsigned long long)(st1.packet_rays - st0.packet_rays), n);
    size_t *perm = shuffle_perm(n, 5);
    accel_ray *shuffled = malloc(n * sizeof *shuffled);
    for (size_t i = 0; i < n; i++) shuffled[i] = sh->rays[perm[i]];
    kind->occluded(a, shuffled, occ, n, NULL);
    accel_coherence_stats_get(&st2);
    CHECKF(st2.sorted_blocks > st1.sorted_blocks || st2.single_rays > st1.single_rays,
           "shuffled shadow rays kept as packets as they came");
    accel_coherence_set(before);
    free(occ), free(perm), free(shuffled);
}

TEST(coherence_shadow_rays_converge_into_packets)
{
    static const char *const spec[] = {"bvh:width=8,traverse=packet"};
    each_kind_on_cases(spec, 1, shadow_rays_kept);
}

/* Diffuse bounces are not traced as packets: the spread test sends them
 * ray by ray. */
static void diffuse_rays_single(const char *spec, const accel_kind *kind, const void *a, const ray_case *cases)
{
    (void)spec;
    const size_t n = cases[2].set.count;
    accel_hit *hits = malloc(n * sizeof *hits);
    accel_coherence_stats st0, st1;
    const int before = accel_coherence_get();
    accel_coherence_set(ACCEL_ORDER_SORT);
    accel_coherence_stats_get(&st0);
    kind->intersect(a, cases[2].set.rays, hits, n, NULL);
    accel_coherence_stats_get(&st1);
    accel_coherence_set(before);
    CHECKF(st1.single_rays - st0.single_rays >= n * 9 / 10, "diffuse: %llu of %zu rays single",
           (unsigned long long)(st1.single_rays - st0.single_rays), n);
    free(hits);
}

TEST(coherence_diffuse_rays_go_single)
{
    static const char *const spec[] = {"bvh:traverse=packet"};
    each_kind_on_cases(spec, 1, diffuse_rays_single);
}

TEST(coherence_ray_orders)
{
    accel_scene s;
    if (!test_make_scene("sphere:segments=8", &s)) return;
    rays_set r;
    accel_error err;
    if (rays_primary(&s.camera, 20, 12, &r, &err)) return;
    CHECK(rays_reorder(&r, RAYS_ORDER_SCANLINE, 0, &err) == 0);
    for (size_t i = 0; i < r.count; i++) CHECK(r.pixel[i] == i);
    CHECK(rays_reorder(&r, RAYS_ORDER_TILES8, 0, &err) == 0);
    /* the first 8x8 tile, then the next one to its right */
    CHECK(r.pixel[0] == 0 && r.pixel[7] == 7 && r.pixel[8] == 20 && r.pixel[63] == 7 * 20 + 7);
    CHECK(r.pixel[64] == 8);
    rays_order o;
    CHECK(rays_order_parse("shuffle", &o) == 0 && o == RAYS_ORDER_SHUFFLE);
    CHECK(rays_order_parse("zigzag", &o) != 0);
    CHECK(rays_reorder(&r, RAYS_ORDER_SHUFFLE, 5, &err) == 0);
    uint8_t *seen = calloc(r.count, 1);
    size_t moved = 0;
    for (size_t i = 0; i < r.count; i++) seen[r.pixel[i]]++, moved += r.pixel[i] != i;
    for (size_t i = 0; i < r.count; i++) CHECK(seen[i] == 1);
    CHECK(moved > r.count / 2);
    free(seen);
    free(r.pixel), r.pixel = NULL;
    CHECK(rays_reorder(&r, RAYS_ORDER_SCANLINE, 0, &err) == ACCEL_ERR_SPEC);
    rays_free(&r);
    scene_free(&s);
}
