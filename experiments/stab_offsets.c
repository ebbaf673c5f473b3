/*
 * stab_offsets.c - exp_stability's study of secondary-ray origins.
 *
 * A secondary ray leaves a hit point p of a closed mesh along a direction
 * on the side the primary ray came from. Its origin is p moved along the
 * normal n on that side by one of five rules: a fixed 1e-4; 1e-4 and 1e-6
 * times the scene's size (the largest side of its bounds); 32 ulps of p's
 * largest coordinate; the robust integer-ulp offset of Waechter and Binder
 * (Ray Tracing Gems, 2019: rays_offset_origin). Each ray is traced by the
 * exact reference. Counted per rule: self-intersections (the first hit is
 * the triangle p lies on), and against the robust rule's answer for the
 * same ray: holes (robust hits, this rule misses), false hits (robust
 * misses, this rule hits another triangle); a hit of another triangle at
 * another t is no fault, since the origins differ. Rays that
 * leave a hit of a leak ray (a ray from inside a closed mesh) point back
 * into that mesh: each must hit (a miss is a light leak), and so must its
 * shadow version (any-hit, t_far infinite) traced by the default BVH. The
 * meshes are spheres, whose creases are mild: a point moved off a face
 * into the mesh is inside the planes of its neighbours too. (On a cube's
 * 90-degree edges it stays on the neighbour's plane: no leak test there.)
 *
 * GRIDBVH_STABILITY_PLANT=1 in the environment plants a broken robust rule
 * (p + 3 x size x n: past the whole mesh), so that tests can check that
 * the study counts a leak when there is one (tests/test_stiff.c).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stab_offsets.h"
#include "cli/cli.h"
#include "rays/stiff.h"

enum { M_FIXED, M_REL4, M_REL6, M_ULPS, M_ROBUST, M_COUNT };
static const char *const method_name[M_COUNT] = {"fixed 1e-4", "1e-4 x size", "1e-6 x size",
                                                 "32 ulps of max |p|", "robust (Waechter-Binder)"};

typedef struct {
    size_t self, holes, false_hits, leaks, shadow_leaks;
} offset_counts;

static vec3 origin_of(int m, vec3 p, vec3 n, float size, int planted)
{
    float a = fmaxf(fabsf(p.x), fmaxf(fabsf(p.y), fabsf(p.z)));
    switch (m) {
    case M_FIXED: return v3_add(p, v3_scale(n, 1e-4f));
    case M_REL4: return v3_add(p, v3_scale(n, 1e-4f * size));
    case M_REL6: return v3_add(p, v3_scale(n, 1e-6f * size));
    case M_ULPS: return v3_add(p, v3_scale(n, 32.0f * (nextafterf(a, INFINITY) - a)));
    default: return planted ? v3_add(p, v3_scale(n, 3.0f * size)) : rays_offset_origin(p, n);
    }
}

static void rate_of(char *buf, size_t len, size_t k, size_t of)
{
    if (!of) snprintf(buf, len, "-");
    else if (!k) snprintf(buf, len, "0 (< %.1f)", 3e6 / (double)of);
    else snprintf(buf, len, "%.1f", 1e6 * (double)k / (double)of);
}

/* One case: counts per rule into cnt; returns the secondary rays (n) and
 * those leaving an inside hit (*inside). */
static size_t offset_case(exp_ctx *x, const stiff_case *c, int threads, int planted,
                          offset_counts cnt[M_COUNT], size_t *inside)
{
    const accel_scene *s = &c->scene;
    size_t n0 = c->rays.count, n = 0;
    accel_hit *ph = malloc((n0 ? n0 : 1) * sizeof *ph);
    accel_ray *sec = malloc((n0 ? n0 : 1) * M_COUNT * sizeof *sec);
    uint32_t *src = malloc((n0 ? n0 : 1) * sizeof *src);
    uint8_t *in = malloc(n0 ? n0 : 1), *occ = malloc((n0 ? n0 : 1) * M_COUNT);
    accel_hit *hh = malloc((n0 ? n0 : 1) * M_COUNT * sizeof *hh);
    if (!ph || !sec || !src || !in || !occ || !hh) exit(CLI_EXIT_INTERNAL);
    stiff_reference(s, c->rays.rays, ph, n0, threads);
    vec3 e = box3_extent(s->bounds);
    float size = fmaxf(e.x, fmaxf(e.y, e.z));
    for (size_t r = 0; r < n0; r++) {
        vec3 p, nn;
        if (!rays_hit_frame(s, &c->rays.rays[r], &ph[r], &p, &nn)) continue;
        vec3 d = v3_norm(v3_add(nn, v3(rays_rand(3, r, 0) - 0.5f, rays_rand(3, r, 1) - 0.5f,
                                       rays_rand(3, r, 2) - 0.5f)));
        if (v3_dot(d, nn) <= 0.05f) continue;
        for (int m = 0; m < M_COUNT; m++) {
            vec3 o = origin_of(m, p, nn, size, planted);
            accel_ray q = {o.x, o.y, o.z, 0, d.x, d.y, d.z, INFINITY};
            sec[(size_t)m * n0 + n] = q;
        }
        src[n] = ph[r].prim;
        in[n++] = r >= c->leak_begin;
    }
    const accel_kind *k = NULL;
    void *a = NULL;
    accel_build_stats bs;
    accel_error err = {0};
    if (accel_build_spec(accel_find_kind("bvh") ? "bvh" : "brute", s, threads, &k, &a, &bs, &err))
        exp_internal(x, "offset study: build", &err);
    for (int m = 0; m < M_COUNT; m++) {
        stiff_reference(s, sec + (size_t)m * n0, hh + (size_t)m * n0, n, threads);
        if (a) accel_trace_occluded(k, a, sec + (size_t)m * n0, occ + (size_t)m * n0, n, threads, NULL);
    }
    *inside = 0;
    memset(cnt, 0, M_COUNT * sizeof *cnt);
    const accel_hit *rob = hh + (size_t)M_ROBUST * n0;
    for (size_t i = 0; i < n; i++) {
        *inside += in[i];
        for (int m = 0; m < M_COUNT; m++) {
            const accel_hit *h = hh + (size_t)m * n0 + i;
            int hit = h->prim != ACCEL_MISS, rhit = rob[i].prim != ACCEL_MISS && rob[i].prim != src[i];
            cnt[m].leaks += in[i] && !hit;
            cnt[m].shadow_leaks += in[i] && a && !occ[(size_t)m * n0 + i];
            if (hit && h->prim == src[i]) {
                cnt[m].self++;
                continue;
            }
            if (m == M_ROBUST) continue;
            cnt[m].holes += rhit && !hit;
            cnt[m].false_hits += !rhit && hit;
        }
    }
    if (a) k->destroy(a);
    free(ph), free(sec), free(src), free(in), free(occ), free(hh);
    return n;
}

static void offset_rows(exp_ctx *x, const char *name, double distance, size_t n, size_t inside,
                        const offset_counts cnt[M_COUNT], stab_offsets_result *res)
{
    for (int m = 0; m < M_COUNT; m++) {
        char sb[48], hb[48], fb[48], lb[48], sl[48];
        rate_of(sb, sizeof sb, cnt[m].self, n), rate_of(lb, sizeof lb, cnt[m].leaks, inside);
        rate_of(sl, sizeof sl, cnt[m].shadow_leaks, inside);
        if (m == M_ROBUST) {
            snprintf(hb, sizeof hb, "(reference)"), snprintf(fb, sizeof fb, "(reference)");
        } else {
            rate_of(hb, sizeof hb, cnt[m].holes, n), rate_of(fb, sizeof fb, cnt[m].false_hits, n);
        }
        exp_md(x, "| %s | %zu (%zu) | %s | %s | %s | %s | %s | %s |\n", m ? "" : name, n,
               inside, method_name[m], sb, hb, fb, lb, sl);
        exp_csv(x, "offset,%s,%s,%zu,%zu,%zu,%zu,%zu,,%zu,%zu,%zu,,%g,\n", name, method_name[m],
                n, inside, inside, cnt[m].holes, cnt[m].false_hits, cnt[m].leaks,
                cnt[m].shadow_leaks, cnt[m].self, distance);
        if (n) {
            res->worst_self[m] = fmax(res->worst_self[m], 1e6 * (double)cnt[m].self / (double)n);
            res->worst_false[m] = fmax(res->worst_false[m], 1e6 * (double)cnt[m].false_hits / (double)n);
        }
        res->leaks[m] += cnt[m].leaks + cnt[m].shadow_leaks;
        res->self[m] += cnt[m].self;
    }
    if (distance >= STAB_FAR_DISTANCE && n && inside) {
        for (int m = 0; m < M_COUNT; m++) {
            double lk = (double)cnt[m].leaks / (double)inside, sf = (double)cnt[m].self / (double)n;
            int first = res->far_cases == 0;
            res->far_leak_lo[m] = first ? lk : fmin(res->far_leak_lo[m], lk);
            res->far_leak_hi[m] = first ? lk : fmax(res->far_leak_hi[m], lk);
            res->far_self_lo[m] = first ? sf : fmin(res->far_self_lo[m], sf);
            res->far_self_hi[m] = first ? sf : fmax(res->far_self_hi[m], sf);
        }
        res->far_d_lo = res->far_cases ? fmin(res->far_d_lo, distance) : distance;
        res->far_d_hi = res->far_cases ? fmax(res->far_d_hi, distance) : distance;
        res->far_cases++;
    }
    res->rays += n;
    res->inside += inside;
    res->min_n = res->min_n && res->min_n < n ? res->min_n : n;
}

void stab_offsets(exp_ctx *x, int threads, stab_offsets_result *res)
{
    static const float dist[] = {0, 1e2f, 1e4f, 1e5f, 1e6f};
    static const char *const contacts[] = {"spheres_touching", "spheres_interpenetrating"};
    const int nd = x->quick ? 2 : 5, nc = x->quick ? 1 : 2;
    const size_t want = x->quick ? 3000 : 100000;
    const char *plant = getenv("GRIDBVH_STABILITY_PLANT");
    int planted = plant && *plant && strcmp(plant, "0");
    memset(res, 0, sizeof *res);
    exp_md(x, "\n### Secondary-ray origins: scene-scaled epsilons against the robust offset\n\n"
              "Secondary rays leave the hits of each case's rays (stiff.c: vertex and edge rays "
              "from outside, leak rays from inside) on the side they came from, one per hit. "
              "Origin = hit point + e x normal: e = 1e-4; 1e-4 and 1e-6 x the scene's size; 32 "
              "ulps of the hit point's largest coordinate; or the robust offset of Waechter and "
              "Binder (2019). Every ray traced by the exact reference. Self-hits: the first hit "
              "is the ray's own triangle; holes and false hits against the robust offset's "
              "answer for the same ray (a hit of another triangle at another t is no fault: "
              "the origins differ); leaks: of the rays leaving a hit from "
              "inside a closed mesh (back into it: each must hit), closest-hit and shadow "
              "(any-hit, default BVH). Per million rays; a zero carries the rule-of-three "
              "bound 3/n (95%%).%s\n", planted ? " **PLANTED: the robust offset is replaced by "
              "a broken one (GRIDBVH_STABILITY_PLANT).**" : "");
    exp_md_table(x, "case|rays (inside)|origin rule|self-hits per million|holes|false hits|"
                    "leaks per million inside rays|shadow leaks");
    for (int i = 0; i < nd + nc; i++) {
        stiff_case c;
        accel_error err = {0};
        char name[96];
        int rc;
        if (i < nd) {
            accel_scene base, s;
            exp_scene(x, "sphere:segments=24", &base);
            rc = scene_transform(&base, 1.0f, v3(dist[i], dist[i], dist[i]), &s, &err);
            scene_free(&base);
            snprintf(name, sizeof name, "sphere at (d,d,d), d = %g", dist[i]);
            if (rc == 0) rc = stiff_case_closed(&s, name, want, &c, &err);
        } else {
            snprintf(name, sizeof name, "%s", contacts[i - nd]);
            rc = stiff_case_make_n(stiff_case_index(name), want, &c, &err);
        }
        if (rc) {
            exp_internal(x, "offset study: case", &err);
            continue;
        }
        offset_counts cnt[M_COUNT];
        size_t inside = 0, n = offset_case(x, &c, threads, planted, cnt, &inside);
        offset_rows(x, name, i < nd ? dist[i] : 0, n, inside, cnt, res);
        stiff_case_free(&c);
    }
    res->planted = planted;
}

const char *stab_offsets_name(int m) { return m >= 0 && m < M_COUNT ? method_name[m] : "?"; }

/* A percentage short enough for the summary: 0, 0.006, 68. */
static void pct(char *b, size_t n, double f)
{
    double p = 100 * f;
    if (p == 0) snprintf(b, n, "0");
    else if (p < 1) snprintf(b, n, "%.1g", p);
    else snprintf(b, n, "%.0f", p);
}

/* "lo-hi%" of fractions, or "v%" when they print alike. */
static void pct_range(char *b, size_t n, double lo, double hi)
{
    char l[12], h[12];
    pct(l, sizeof l, lo), pct(h, sizeof h, hi);
    if (!strcmp(l, h)) snprintf(b, n, "%s%%", l);
    else snprintf(b, n, "%s-%s%%", l, h);
}

/* 1e5 for a power of ten, else %g. */
static void dist_text(char *b, size_t n, double d)
{
    double e = round(log10(d));
    if (d > 0 && pow(10, e) == d) snprintf(b, n, "1e%.0f", e);
    else snprintf(b, n, "%g", d);
}

void stab_offsets_far_text(const stab_offsets_result *o, int brief, char *buf, size_t n)
{
    if (!o->far_cases) {
        snprintf(buf, n, "leak at distance >= 1e5: not measured in this budget");
        return;
    }
    double elo = 1, ehi = 0, slo = 1, shi = 0; /* the three epsilon rules together */
    for (int m = 0; m < STAB_OFFSET_ULPS; m++) {
        elo = fmin(elo, o->far_leak_lo[m]), ehi = fmax(ehi, o->far_leak_hi[m]);
        slo = fmin(slo, o->far_self_lo[m]), shi = fmax(shi, o->far_self_hi[m]);
    }
    char d0[16], d1[16], rb[32], ub[32], eb[32], sb[32], dist[40];
    dist_text(d0, sizeof d0, o->far_d_lo), dist_text(d1, sizeof d1, o->far_d_hi);
    if (strcmp(d0, d1)) snprintf(dist, sizeof dist, "%s-%s", d0, d1);
    else snprintf(dist, sizeof dist, "%s", d0);
    pct_range(rb, sizeof rb, o->far_leak_lo[STAB_OFFSET_ROBUST], o->far_leak_hi[STAB_OFFSET_ROBUST]);
    pct_range(ub, sizeof ub, o->far_leak_lo[STAB_OFFSET_ULPS], o->far_leak_hi[STAB_OFFSET_ULPS]);
    pct_range(eb, sizeof eb, elo, ehi), pct_range(sb, sizeof sb, slo, shi);
    snprintf(buf, n, "leak%s at distance %s: robust offset %s, 32 ulps %s, epsilons %s (%s"
             "self-hits %s)", brief ? "" : " of the secondary rays from inside (a sphere at (d,d,d))",
             dist, rb, ub, eb, brief ? "" : "their ", sb);
}
