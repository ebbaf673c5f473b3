/*
 * exp_stability - holes per million rays on the stiff and extreme cases.
 *
 * Every kind (and the traversals and kinds this build adds: packets, wide
 * BVHs, grid packets and skipping, the irregular grid), with the
 * watertight (default) and the naive (Moller-Trumbore) triangle test, on
 * every case of rays/stiff.c and on the shared meshes: holes (the
 * reference hits, the tracer misses), false hits and disagreements per
 * million rays, and leaks per million of the rays that can leak (those
 * starting inside a closed mesh). A rate of zero is shown with its 95%
 * upper bound (Clopper-Pearson; 1 - 0.05^(1/n), about 3/n): zero in 2,400
 * rays means "below 1,250 per million", not "never". Rows that are all
 * zero are folded; so are rows equal for every kind. Speeds (interleaved
 * rounds) show the performance cliffs. Then self-intersection of secondary
 * rays: a fixed epsilon offset against the robust offset of Waechter and
 * Binder (Ray Tracing Gems, 2019), on a closed mesh moved from the origin.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "group.h"
#include "cli/cli.h"
#include "rays/stiff.h"
#include "stab_offsets.h"
#include "core/coherence.h"

#define MAX_CFG 64
#define CLIFF 10.0
/* Rays per built-in case in the certification: a fixed count, never a time
 * limit (issue 52: what is certified must not move with the machine). */
#define CERT_RAYS 1000000
#define CERT_RAYS_QUICK 20000

/* Every packet and stream mode and the wide kernels, beside the kinds:
 * packets and streams have numerics of their own (a packet's slab tests,
 * a stream's node tests per ray, the wide nodes' SIMD lanes), so none is
 * left out as "the same structure" as its single-ray kind. */
static const char *const extras[] = {
    "bvh:traverse=packet", "bvh:traverse=packet,frustum=1", "bvh:width=4", "bvh:width=8",
    "bvh:width=4,traverse=packet", "bvh:width=8,traverse=packet", "bvh:width=4,traverse=stream",
    "bvh:width=8,traverse=stream", "grid:traverse=packet", "grid:skip=macro", "irregular_grid",
    "nested_grid:traverse=packet", "instanced:traverse=packet"};

/* The only (case, configuration) pairs certified on fewer rays than the
 * case's, each a fixed count: single-ray walks that the case defeats
 * (the counts per ray of the base rays quoted beside them in the report).
 * A packet or stream mode and the wide kernels are never here. */
static const struct {
    const char *case_name, *spec;
    size_t rays;
} cert_fewer[] = {
    {"tiny_huge", "grid", 100000},         {"tiny_huge", "grid:skip=macro", 100000},
    {"tiny_huge", "nested_grid", 100000},  {"same_centroid", "bvh", 250000},
    {"same_centroid", "instanced", 250000}};

typedef struct {
    double value;
    exp_text what;
} worst;

typedef struct {
    uint64_t robust_rays, robust_bad_cases, cases;
    /* the cases' own rays, each counted once: every configuration traces
     * the same rays, so a rate bound per configuration rests on these */
    uint64_t distinct_rays;
    worst holes, leaks;
    exp_text clean, cliffs, speeds, left;
    /* the certification: every built-in case again with >= 10^6 rays */
    uint64_t cert_cases, cert_bad, cert_rays, cert_min_n, cert_leak_min, cert_traces;
    uint64_t cert_leaks, cert_leak_rays, contact_leak_rays, contact_leaks;
    /* pairs (case, configuration) listed, certified on the case's rays,
     * on a fixed fewer (cert_fewer), not at all (with the reason) */
    uint64_t cert_listed, cert_full, cert_fewer_n, cert_none, cert_fewer_min;
    int cert_configs_min, cert_configs_max; /* configurations listed per case */
    /* each packet mode in the default (sorted) order on the base rays: the
     * rays its packet kernel traced, of all its rays */
    struct {
        char spec[256];
        uint64_t packet, rays;
    } share[MAX_CFG];
    int shares;
    exp_text cert_rows, cert_notes;
} study;

typedef struct {
    size_t holes, false_hits, dis, leaks;
} counts;

static void rate(char *buf, size_t n, size_t k, size_t of)
{
    if (!of)
        snprintf(buf, n, "-");
    else
        snprintf(buf, n, "%.0f (< %.0f)", 1e6 * (double)k / (double)of, 1e6 * exp_binom_upper(k, of));
}

/* The worst naive configuration of a case by holes (what 0) or leaks (1)
 * per million; equal counts are a tie, so every configuration that has
 * them is named. */
static void note_worst(worst *w, const exp_group *g, const counts *cnt, int m, size_t of, int what,
                       const char *name)
{
    double v[MAX_CFG], top = 0;
    int naive_n = 0, at_top = 0;
    for (int k = 0; k < m; k++) {
        v[k] = -1;
        if (!g->cfg[k].ok || !strstr(g->cfg[k].spec, "tri=naive") || !of) continue;
        v[k] = 1e6 * (double)(what ? cnt[k].leaks : cnt[k].holes) / (double)of;
        naive_n++;
        if (v[k] > top) top = v[k], at_top = 0;
        at_top += v[k] == top;
    }
    if (!(top > w->value)) return;
    w->value = top;
    exp_text_free(&w->what);
    if (at_top == naive_n && naive_n > 1) {
        exp_text_add(&w->what, "every naive configuration alike on %s: a tie, the triangle test "
                     "is shared", name);
        return;
    }
    for (int k = 0; k < m; k++)
        if (v[k] == top) exp_text_add(&w->what, "%s`%s`", w->what.len ? ", " : "", g->cfg[k].spec);
    exp_text_add(&w->what, " on %s", name);
}

static int cert_threads(const exp_ctx *x)
{
    return x->threads_given ? x->threads : accel_cpu_count();
}

/* The certification's rays for `spec` on case `name`: the case's own n,
 * or the fixed count of cert_fewer. */
static size_t cert_rays_for(const char *name, const char *spec, size_t n)
{
    for (size_t i = 0; i < sizeof cert_fewer / sizeof cert_fewer[0]; i++)
        if (!strcmp(cert_fewer[i].case_name, name) && !strcmp(cert_fewer[i].spec, spec))
            return cert_fewer[i].rays < n ? cert_fewer[i].rays : n;
    return n;
}

static int is_packet_mode(const char *spec) { return strstr(spec, "traverse=packet") != NULL; }

/* Rays [0, n) taken every `step`-th from src into a new array (step 1: src
 * itself, not copied). */
static const accel_ray *spread(const accel_ray *src, size_t n, size_t step, accel_ray **owned)
{
    *owned = NULL;
    if (step <= 1) return src;
    size_t m = (n + step - 1) / step;
    *owned = malloc((m ? m : 1) * sizeof **owned);
    if (!*owned) exit(CLI_EXIT_INTERNAL);
    for (size_t i = 0; i < m; i++) (*owned)[i] = src[i * step];
    return *owned;
}

typedef struct {
    size_t n, nl, ns; /* rays, leak rays, shadow rays traced */
    hits_diff d;
    size_t leaks, sleaks;
} cert_counts;

/* One configuration on the case: every ray (step 1) or every step-th ray,
 * against the reference; packet modes with every 64 consecutive rays a
 * packet (ACCEL_ORDER_KEEP), so that their packet kernels trace every ray. */
static cert_counts cert_one(const stiff_case *big, const accel_hit *ref, const accel_kind *kind,
                            const void *accel, int packet, size_t step, int T, accel_hit *h,
                            uint8_t *occ)
{
    cert_counts r = {0};
    size_t n = big->rays.count, ns = big->shadow.count;
    accel_ray *own = NULL, *sown = NULL;
    const accel_ray *rays = spread(big->rays.rays, n, step, &own);
    const accel_ray *srays = spread(big->shadow.rays, ns, step, &sown);
    r.n = (n + step - 1) / step;
    r.ns = (ns + step - 1) / step;
    int order = accel_coherence_get();
    if (packet) accel_coherence_set(ACCEL_ORDER_KEEP);
    accel_trace(kind, accel, rays, h, r.n, T, NULL);
    if (r.ns) accel_trace_occluded(kind, accel, srays, occ, r.ns, T, NULL);
    accel_coherence_set(order);
    if (step <= 1) {
        r.d = hits_compare(&big->scene, rays, ref, h, r.n);
    } else { /* the reference of the rays taken */
        accel_hit *sub = malloc((r.n ? r.n : 1) * sizeof *sub);
        if (!sub) exit(CLI_EXIT_INTERNAL);
        for (size_t i = 0; i < r.n; i++) sub[i] = ref[i * step];
        r.d = hits_compare(&big->scene, rays, sub, h, r.n);
        free(sub);
    }
    for (size_t i = 0; i < r.n; i++)
        if (i * step >= big->leak_begin) r.nl++, r.leaks += h[i].prim == ACCEL_MISS;
    for (size_t i = 0; i < r.ns; i++) r.sleaks += !occ[i];
    free(own), free(sown);
    return r;
}

/* Case ci again with at least CERT_RAYS distinct rays, traced by every
 * watertight configuration of g but brute force (the reference's own
 * loop), on every core: holes, false hits and disagreements against the
 * exact reference, leaks of the rays from inside, and of the shadow rays.
 * A configuration the group left out (collapsed on the base rays) is built
 * here; one that cannot be built is named with the reason. Long on purpose
 * (84 lines): the configurations in turn, then the case's row, sharing the
 * reference and the tallies. */
static void certify(exp_ctx *x, study *st, int ci, const exp_group *g, int m)
{
    stiff_case big;
    accel_error err = {0};
    if (stiff_case_make_n(ci, x->quick ? CERT_RAYS_QUICK : CERT_RAYS, &big, &err)) {
        exp_internal(x, "stiff case", &err);
        return;
    }
    int T = cert_threads(x);
    size_t n = big.rays.count, nl = n - big.leak_begin, ns = big.shadow.count, ref_leaks = 0;
    accel_hit *ref = malloc(n * sizeof *ref), *h = malloc(n * sizeof *h);
    uint8_t *occ = malloc(ns ? ns : 1);
    if (!ref || !h || !occ) exit(CLI_EXIT_INTERNAL);
    char phase[160];
    snprintf(phase, sizeof phase, "certification of %s (%zu rays)", big.name, n);
    bench_progress_begin(x->progress, phase, 0, 1);
    stiff_reference(&big.scene, big.rays.rays, ref, n, T);
    for (size_t i = big.leak_begin; i < n; i++) ref_leaks += ref[i].prim == ACCEL_MISS;
    exp_text faults = {0};
    int done = 0, listed = 0, fewer = 0;
    for (int k = 0; k < m; k++) {
        const exp_cfg *f = &g->cfg[k];
        if (strstr(f->spec, "tri=naive") || !strncmp(f->spec, "brute", 5)) continue;
        listed++;
        const accel_kind *kind = f->kind;
        void *accel = f->ok ? f->accel : NULL, *own = NULL;
        if (!accel && f->left != EXP_LEFT_UNPARSED) {
            accel_build_stats bs;
            if (accel_build_spec(f->spec, &big.scene, T, &kind, &own, &bs, &err) == 0) accel = own;
        }
        if (!accel) {
            exp_text_add(&st->cert_notes, "- %s: `%s` not certified (%s).\n", big.name, f->spec,
                         f->why[0] ? f->why : err.msg);
            exp_csv(x, "cert,%s,%s,0,0,0,,,,,,,,,not certified: %s\n", big.name, f->spec,
                    f->why[0] ? f->why : err.msg);
            st->cert_none++;
            continue;
        }
        size_t want = cert_rays_for(big.name, f->spec, n), step = want ? n / want : 1;
        if (step < 1) step = 1;
        cert_counts r = cert_one(&big, ref, kind, accel, is_packet_mode(f->spec), step, T, h, occ);
        if (own) kind->destroy(own);
        char note[200] = "";
        if (step > 1) {
            if (f->ok)
                snprintf(note, sizeof note, "a fixed %zu of %zu rays (every %zu-th): %.0f steps "
                         "and %.0f primitive tests per ray on the base rays", r.n, n, step,
                         exp_group_steps(g, k, BENCH_PRIMARY), exp_group_prims(g, k, BENCH_PRIMARY));
            else
                snprintf(note, sizeof note, "a fixed %zu of %zu rays (every %zu-th)", r.n, n, step);
            exp_text_add(&st->cert_notes, "- %s: `%s` on %s (below %.0f per million).\n", big.name,
                         f->spec, note, 3e6 / (double)r.n);
            fewer++;
            st->cert_fewer_n++;
            st->cert_fewer_min = st->cert_fewer_min && st->cert_fewer_min < r.n ? st->cert_fewer_min : r.n;
        } else {
            st->cert_full++;
        }
        exp_csv(x, "cert,%s,%s,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,,,,%s\n", big.name, f->spec, r.n,
                r.nl, r.ns, r.d.holes, r.d.false_hits, r.d.disagreements, r.leaks, r.sleaks, note);
        if (r.d.holes || r.d.false_hits || r.d.disagreements || r.leaks || r.sleaks) {
            exp_text_add(&faults, "%s`%s` %zu/%zu/%zu/%zu/%zu", faults.len ? ", " : "", f->spec,
                         r.d.holes, r.d.false_hits, r.d.disagreements, r.leaks, r.sleaks);
            if (r.d.first_bad != SIZE_MAX) {
                const accel_ray *q = &big.rays.rays[r.d.first_bad * step];
                exp_text_add(&faults, " (first: ray %zu, o = (%.9g, %.9g, %.9g), d = (%.9g, %.9g, "
                             "%.9g))", r.d.first_bad * step, q->ox, q->oy, q->oz, q->dx, q->dy, q->dz);
            }
        }
        st->cert_traces += r.n + r.ns;
        st->cert_leaks += r.leaks + r.sleaks;
        if (strstr(big.name, "touching") || strstr(big.name, "interpenetrating"))
            st->contact_leaks += r.leaks + r.sleaks;
        done++;
    }
    bench_progress_end(x->progress);
    if (ref_leaks) exp_text_add(&faults, "%sthe reference itself misses %zu leak rays (the case "
                                "is wrong)", faults.len ? "; " : "", ref_leaks);
    char lb[48] = "-", sb[48] = "-", cb[80];
    if (nl) snprintf(lb, sizeof lb, "%zu (< %.1f)", nl, 3e6 / (double)nl);
    if (ns) snprintf(sb, sizeof sb, "%zu (< %.1f)", ns, 3e6 / (double)ns);
    if (fewer) snprintf(cb, sizeof cb, "%d of %d (%d on fewer rays)", done, listed, fewer);
    else snprintf(cb, sizeof cb, "%d of %d", done, listed);
    exp_text_add(&st->cert_rows, "| %s | %zu (< %.1f) | %s | %s | %s | %s |\n", big.name, n,
                 3e6 / (double)n, lb, sb, cb, faults.len ? exp_text_str(&faults) : "none");
    st->cert_cases++;
    st->cert_listed += (uint64_t)listed;
    if (!st->cert_configs_min || listed < st->cert_configs_min) st->cert_configs_min = listed;
    if (listed > st->cert_configs_max) st->cert_configs_max = listed;
    st->cert_bad += faults.len > 0;
    st->cert_rays += n;
    st->cert_min_n = st->cert_min_n && st->cert_min_n < n ? st->cert_min_n : n;
    if (nl) {
        st->cert_leak_min = st->cert_leak_min && st->cert_leak_min < nl ? st->cert_leak_min : nl;
        st->cert_leak_rays += nl + ns;
        if (strstr(big.name, "touching") || strstr(big.name, "interpenetrating"))
            st->contact_leak_rays += nl + ns;
    }
    exp_text_free(&faults);
    free(ref), free(h), free(occ);
    stiff_case_free(&big);
}

/* Long on purpose (108 lines): one stiff case's runs against the reference,
 * table and findings, in the order the report prints them; the steps share
 * the group, its per-configuration arrays and the study's tallies, which
 * separate functions would take as a dozen parameters each. */
static void measure_case(exp_ctx *x, study *st, stiff_case *c, int ci, const exp_list *list)
{
    size_t n = c->rays.count, leakable = n - c->leak_begin;
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref), *h = malloc((n ? n : 1) * sizeof *h);
    if (!ref || !h) exit(CLI_EXIT_INTERNAL);
    exp_reference(x, &c->scene, c->rays.rays, ref, n);
    bench_sets one = {0};
    one.primary = c->rays;
    one.made = BENCH_PRIMARY;
    exp_group g;
    exp_group_init(&g, x, &c->scene, &one, BENCH_PRIMARY);
    g.collapse_ms = x->quick ? 500 : 3000;
    g.time_builds = 0; /* no build time is reported here */
    g.keep_same = 1;   /* packets and streams share their kind's tree, not its numerics */
    for (int i = 0; i < list->count; i++) {
        if (!strncmp(list->spec[i], "brute", 5) && (!list->spec[i][5] || list->spec[i][5] == ':') &&
            c->scene.live_count > 20000) {
            if (!strcmp(list->spec[i], "brute"))
                exp_text_add(&st->left, "- %s: `brute` (%u primitives against every ray: minutes "
                             "per pass; both tests).\n", c->name, c->scene.live_count);
            exp_note_left(x, EXP_LEFT_POINTLESS);
            continue;
        }
        exp_group_add(&g, list->spec[i], 0);
    }
    exp_group_run(&g);
    counts cnt[MAX_CFG] = {{0}};
    int m = g.count < MAX_CFG ? g.count : MAX_CFG, all_zero = 1, wt_zero = 1, any_wt = 0;
    for (int k = 0; k < m; k++) {
        if (!g.cfg[k].ok) continue;
        int packet = is_packet_mode(g.cfg[k].spec), naive = strstr(g.cfg[k].spec, "tri=naive") != NULL;
        if (packet && !naive) { /* the share the default order gives the packet kernel */
            accel_coherence_stats s0, s1;
            accel_coherence_stats_get(&s0);
            accel_trace(g.cfg[k].kind, g.cfg[k].accel, c->rays.rays, h, n, x->threads, NULL);
            accel_coherence_stats_get(&s1);
            int j = 0;
            while (j < st->shares && strcmp(st->share[j].spec, g.cfg[k].spec)) j++;
            if (j == st->shares && j < MAX_CFG)
                snprintf(st->share[st->shares++].spec, sizeof st->share[0].spec, "%s", g.cfg[k].spec);
            if (j < st->shares) {
                st->share[j].packet += s1.packet_rays - s0.packet_rays;
                st->share[j].rays += n;
            }
        }
        int order = accel_coherence_get();
        if (packet) accel_coherence_set(ACCEL_ORDER_KEEP);
        accel_trace(g.cfg[k].kind, g.cfg[k].accel, c->rays.rays, h, n, x->threads, NULL);
        accel_coherence_set(order);
        hits_diff d = hits_compare(&c->scene, c->rays.rays, ref, h, n);
        cnt[k].holes = d.holes, cnt[k].false_hits = d.false_hits, cnt[k].dis = d.disagreements;
        for (size_t i = c->leak_begin; i < n; i++) cnt[k].leaks += h[i].prim == ACCEL_MISS;
        int zero = !cnt[k].holes && !cnt[k].false_hits && !cnt[k].dis && !cnt[k].leaks;
        all_zero &= zero;
        if (!naive) {
            wt_zero &= zero;
            any_wt = 1;
            st->robust_rays += n;
        }
        exp_csv(x, "stiff,%s,%s,%zu,%zu,0,%zu,%zu,%zu,%zu,,,%.4f,,\n", c->name, g.cfg[k].spec, n,
                leakable, cnt[k].holes, cnt[k].false_hits, cnt[k].dis, cnt[k].leaks,
                exp_group_mrays(&g, k, BENCH_PRIMARY).median);
    }
    note_worst(&st->holes, &g, cnt, m, n, 0, c->name);
    note_worst(&st->leaks, &g, cnt, m, leakable, 1, c->name);
    st->cases++;
    st->robust_bad_cases += !wt_zero;
    if (any_wt) st->distinct_rays += n;
    char hb[64], fb[64], db[64], lb[64];
    rate(hb, sizeof hb, 0, n), rate(lb, sizeof lb, 0, leakable);
    if (all_zero) {
        exp_text_add(&st->clean, "- %s (%zu rays%s): every configuration, both tests: no holes, "
                     "false hits, disagreements or leaks; per million rays %s%s%s.\n", c->name, n,
                     leakable ? ", some starting inside" : "", hb, leakable ? ", per million leak "
                     "rays " : "", leakable ? lb : "");
    } else {
        exp_md(x, "| **%s** | | %zu (%zu) | | | | |\n", c->name, n, leakable);
        for (int naive = 0; naive < 2; naive++) {
            /* One row when every configuration of this test counts the same. */
            int first = -1, same = 1;
            for (int k = 0; k < m; k++) {
                if (!g.cfg[k].ok || (strstr(g.cfg[k].spec, "tri=naive") != NULL) != naive) continue;
                if (first < 0) first = k;
                else same &= !memcmp(&cnt[k], &cnt[first], sizeof cnt[k]);
            }
            for (int k = 0; k < m && first >= 0; k++) {
                if (!g.cfg[k].ok || (strstr(g.cfg[k].spec, "tri=naive") != NULL) != naive) continue;
                if (same && k != first) continue;
                rate(hb, sizeof hb, cnt[k].holes, n), rate(fb, sizeof fb, cnt[k].false_hits, n);
                rate(db, sizeof db, cnt[k].dis, n), rate(lb, sizeof lb, cnt[k].leaks, leakable);
                exp_md(x, "| %s | %s | %s | %s | %s | %s | %s |\n",
                       same ? "every configuration" : g.cfg[k].spec, naive ? "naive" : "watertight",
                       "", hb, fb, db, lb);
            }
        }
    }
    /* Speeds of the watertight configurations: the cliffs. */
    int fast = -1, slow = -1;
    exp_text_add(&st->speeds, "| %s |", c->name);
    for (int k = 0; k < m; k++) {
        if (!g.cfg[k].ok || strstr(g.cfg[k].spec, "tri=naive")) continue;
        exp_est r = exp_group_mrays(&g, k, BENCH_PRIMARY);
        exp_text_add(&st->speeds, "%s `%s` %.2f", st->speeds.s[st->speeds.len - 1] == '|' ? "" : ",",
                     g.cfg[k].spec, r.median);
        if (!strcmp(g.cfg[k].spec, "brute")) continue;
        if (fast < 0 || r.median > exp_group_mrays(&g, fast, BENCH_PRIMARY).median) fast = k;
        if (slow < 0 || r.median < exp_group_mrays(&g, slow, BENCH_PRIMARY).median) slow = k;
    }
    double ratio = 0;
    if (fast >= 0 && slow >= 0) {
        ratio = exp_group_mrays(&g, fast, BENCH_PRIMARY).median / exp_group_mrays(&g, slow, BENCH_PRIMARY).median;
        if (ratio >= CLIFF)
            exp_text_add(&st->cliffs, "- A performance cliff on %s: `%s` traces %.1fx slower than "
                         "`%s`.\n", c->name, g.cfg[slow].spec, ratio, g.cfg[fast].spec);
    }
    exp_text_add(&st->speeds, " | %.1f |\n", ratio);
    if (ci >= 0) certify(x, st, ci, &g, m);
    for (int k = 0; k < g.count; k++)
        if (g.cfg[k].left && (g.cfg[k].left != EXP_LEFT_UNPARSED ||
                              (st->cases == 1 && !strstr(g.cfg[k].spec, "tri=naive"))))
            exp_text_add(&st->left, "- %s%s`%s` (%s).\n", g.cfg[k].left == EXP_LEFT_UNPARSED ? ""
                         : c->name, g.cfg[k].left == EXP_LEFT_UNPARSED ? "" : ": ", g.cfg[k].spec,
                         g.cfg[k].why);
    exp_group_free(&g);
    free(ref);
    free(h);
}

/* Every stiff case (three in the quick budget), then the meshes. */
static void stiff_cases(exp_ctx *x, study *st, const exp_list *list)
{
    exp_md_table(x, "configuration|triangle test|rays (leak rays)|holes per million (95% bound)|"
                    "false hits per million|disagreements per million|leaks per million leak rays");
    int count = x->quick ? 3 : stiff_case_count();
    for (int i = 0; i < count; i++) {
        stiff_case c;
        accel_error err = {0};
        if (stiff_case_make(i, &c, &err)) {
            exp_text_add(&st->left, "- case %d: %s.\n", i, err.msg);
            continue;
        }
        measure_case(x, st, &c, i, list);
        stiff_case_free(&c);
    }
    for (int m = 0; m < x->mesh_count; m++) {
        stiff_case c;
        accel_error err = {0};
        if (stiff_case_from_scene(x->meshes[m], 0, &c, &err)) continue;
        measure_case(x, st, &c, -1, list);
        stiff_case_free(&c);
    }
    for (int m = 0; m < x->scene_count; m++) { /* a scene given explicitly: measured, or an error */
        stiff_case c;
        accel_error err = {0};
        if (stiff_case_from_scene(x->scenes[m], 0, &c, &err)) {
            fprintf(stderr, "%s: --scene %s: %s\n", x->name, x->scenes[m], err.msg);
            exit(CLI_EXIT_INPUT);
        }
        measure_case(x, st, &c, -1, list);
        stiff_case_free(&c);
    }
}

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

/* The far-geometry leak of each origin rule, for the findings and (brief)
 * the summary: "leak at distance 1e5-1e6: robust offset 68-100%, 32 ulps
 * 0-90%, epsilons 0-0.006% (self-hits 49%)": the fractions of the inside
 * rays that leak, over the far cases, least to most. */
static void far_leak_text(const stab_offsets_result *o, int brief, char *buf, size_t n)
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

/* Long on purpose (140 lines): the options, then each case and scene in
 * turn, then the verdicts, read top to bottom as the section they write;
 * each step is a few lines of calls. */
int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_stability",
             "How many rays do naive and watertight kernels lose on stiff and extreme cases?",
             NULL);
    exp_limits(&x, 0, EXP_MAX_MESHES);
    exp_scenes_unused(&x, "its question needs its own stiff and extreme cases");
    /* The timings here only show performance cliffs (ratios of 10x and
     * more) and decide no verdict: 3 rounds in this process give their
     * interval (no replicas: 23 cases of some 24 configurations each,
     * rebuilt twice, were a third of the section); the counts are exact. */
    if (x.repeats > 3) x.repeats = 3;
    if (!x.quick) x.procs = 1;
    exp_header(&x, "Stability on stiff and extreme cases", "the user's request: \"stability on "
               "stiff and extreme cases\"",
               "on rays aimed exactly at shared vertices and edges of closed meshes, along axes "
               "and cell diagonals from cell boundaries and split planes, grazing faces, at "
               "contacts of closed meshes that touch or interpenetrate, and on far (up to 1e6 "
               "times their size from the origin), tiny, huge, flat, degenerate, coincident and "
               "same-centroid scenes: how many holes (reference hits, tracer misses), false hits, "
               "disagreements and leaks (rays and shadow rays from inside a closed mesh that "
               "escape) does each configuration make with the watertight test (Woop et al. 2013, "
               "default) and with the naive Moller-Trumbore test, at what speed, and how do "
               "scene-scaled epsilons compare with the robust offset for secondary rays? The "
               "reference is exact (double precision). First every configuration and both tests "
               "on each case's base rays (rates of zero with their 95%% bound; rows equal for every "
               "configuration folded); then the watertight kernels on every built-in case again "
               "with a million distinct rays and more (a zero is below 3/n by the rule of three: "
               "Hanley and Lippman-Hand, JAMA 249, 1983: 3 per million at n = 10^6).");
    exp_csv(&x, "part,case,spec,rays,leak_rays,shadow_rays,holes,false_hits,disagreements,leaks,"
                "shadow_leaks,self_hits,mrays,distance,note\n");
    const char *names[MAX_CFG / 2];
    int nk = 0;
    const int n_extras = (int)(sizeof extras / sizeof extras[0]);
    for (size_t k = 0; k < accel_kind_count && nk < MAX_CFG / 2 - n_extras; k++) names[nk++] = accel_kinds[k]->name;
    for (size_t e = 0; e < sizeof extras / sizeof extras[0]; e++) names[nk++] = extras[e];
    exp_list base;
    exp_list_make(&x, names, nk, NULL, &base);
    const char *both[MAX_CFG];
    static char naive[MAX_CFG][300];
    int nb = 0;
    for (int i = 0; i < base.count && nb < MAX_CFG - 1; i++) {
        both[nb++] = base.spec[i];
        snprintf(naive[nb], sizeof naive[0], "%s%stri=naive", base.spec[i], strchr(base.spec[i], ':') ? "," : ":");
        both[nb] = naive[nb];
        nb++;
    }
    exp_list list = {both, nb};
    study st = {0};
    stiff_cases(&x, &st, &list);
    if (st.clean.len) exp_md(&x, "\nCases with nothing to report (folded):\n\n%s", exp_text_str(&st.clean));
    if (st.left.len) exp_md(&x, "\nLeft out:\n\n%s", exp_text_str(&st.left));
    /* Every configuration traces the same rays: the bound of one
     * configuration's rate rests on the distinct rays, not on the sum. */
    double bound = 1e6 * exp_binom_upper(0, st.distinct_rays);
    exp_md(&x, "\nThe watertight kernels over all cases: %llu ray traces (%llu distinct rays, each "
               "traced by every configuration), %llu case%s with any hole, false hit, "
               "disagreement or leak; for each configuration, a rate of zero is below %.1f per "
               "million (95%%, over its %llu rays).\n", (unsigned long long)st.robust_rays,
           (unsigned long long)st.distinct_rays, (unsigned long long)st.robust_bad_cases,
           st.robust_bad_cases == 1 ? "" : "s", bound, (unsigned long long)st.distinct_rays);
    exp_text shares = {0};
    for (int j = 0; j < st.shares; j++)
        exp_text_add(&shares, "%s`%s` %.0f%%", j ? ", " : "", st.share[j].spec,
                     st.share[j].rays ? 100.0 * (double)st.share[j].packet / (double)st.share[j].rays : 0.0);
    if (!st.shares) exp_text_add(&shares, "(no packet mode measured)");
    exp_md(&x, "\n### Certification: a million rays and more per case (watertight kernels)\n\n"
               "Each built-in case again, its scene unchanged, with every random count scaled up "
               "and its lattices refined until it has at least %d distinct rays (repeats "
               "dropped: a repeat is no new trial), traced on %d thread%s by every watertight "
               "configuration of the table above but brute force (the reference's own loop): "
               "the packet modes (binary, frustum, 4- and 8-wide, grids, instances), the 4- and "
               "8-wide streams and kernels and every kind. A fixed ray count per case and "
               "configuration, never a time limit: the few pairs on fewer rays are named below "
               "with their counts per ray. The packet modes trace with every 64 consecutive rays "
               "a packet (the caller's order kept), so their packet kernels see every ray: in the "
               "default sorted order the coherence layer gives the packet kernels only coherent "
               "groups of 64 (core/coherence.h), on these cases' base rays %s, the rest to the "
               "kinds' single-ray kernels. "
               "Bounds are per configuration and case, rule of three (95%%): 3/n per million "
               "rays. Faults: holes/false hits/disagreements/leaks/shadow leaks, with the first "
               "faulty ray.\n",
           x.quick ? CERT_RAYS_QUICK : CERT_RAYS, cert_threads(&x), cert_threads(&x) > 1 ? "s" : "",
           exp_text_str(&shares));
    exp_md_table(&x, "case|rays (bound per million)|leak rays (bound)|shadow rays (bound)|"
                     "configurations certified|faults");
    exp_md(&x, "%s", exp_text_str(&st.cert_rows));
    exp_text_free(&shares);
    if (st.cert_notes.len)
        exp_md(&x, "\nOn fewer rays or not certified:\n\n%s", exp_text_str(&st.cert_notes));
    exp_md(&x, "\n### Speed on the stiff cases (watertight, Mrays/s, interleaved rounds)\n");
    exp_md_table(&x, "case|Mrays/s per configuration|fastest / slowest (brute aside)");
    exp_md(&x, "%s", exp_text_str(&st.speeds));
    stab_offsets_result off;
    stab_offsets(&x, cert_threads(&x), &off);
    double cb = st.cert_min_n ? 3e6 / (double)st.cert_min_n : 0;
    double lb = st.cert_leak_min ? 3e6 / (double)st.cert_leak_min : 0;
    exp_text findings = {0};
    exp_text_add(&findings, "- The watertight kernels, base rays: %s over %llu distinct rays in "
                 "%llu cases (each configuration: fewer than %.1f per million at 95%%).\n",
                 st.robust_bad_cases ? "SOME CASES FAILED (see the rows above)"
                 : "no hole, false hit, disagreement or leak", (unsigned long long)st.distinct_rays,
                 (unsigned long long)st.cases, bound);
    char fewer_txt[160] = "";
    if (st.cert_fewer_n)
        snprintf(fewer_txt, sizeof fewer_txt, "; %llu pair%s on a fixed fewer, at least %llu "
                 "rays: below %.0f", (unsigned long long)st.cert_fewer_n,
                 st.cert_fewer_n == 1 ? "" : "s", (unsigned long long)st.cert_fewer_min,
                 3e6 / (double)st.cert_fewer_min);
    char per_case[32];
    if (st.cert_configs_min == st.cert_configs_max) snprintf(per_case, sizeof per_case, "%d", st.cert_configs_max);
    else snprintf(per_case, sizeof per_case, "%d to %d", st.cert_configs_min, st.cert_configs_max);
    exp_text_add(&findings, "- Certification: %llu of %llu cases with any fault; %s "
                 "configurations listed per case, %llu (case, configuration) pairs: %llu on the "
                 "case's rays, %llu on fewer, %llu not certified; %llu rays in all (at least %llu "
                 "per case: each configuration's rate per case below %.1f per million by the rule "
                 "of three%s; leak rays at least %llu per case: below %.1f), %llu ray traces.\n",
                 (unsigned long long)st.cert_bad, (unsigned long long)st.cert_cases,
                 per_case, (unsigned long long)st.cert_listed,
                 (unsigned long long)st.cert_full, (unsigned long long)st.cert_fewer_n,
                 (unsigned long long)st.cert_none, (unsigned long long)st.cert_rays,
                 (unsigned long long)st.cert_min_n, cb, fewer_txt,
                 (unsigned long long)st.cert_leak_min, lb, (unsigned long long)st.cert_traces);
    exp_text_add(&findings, "- Light leaking at contacts of closed meshes (touching, "
                 "interpenetrating): %llu leaks in %llu leak and shadow rays, each configuration "
                 "(the certification rows of the contact cases).\n",
                 (unsigned long long)st.contact_leaks, (unsigned long long)st.contact_leak_rays);
    exp_text_add(&findings, "- The naive kernels: up to %.0f holes per million rays (%s) and %.0f "
                 "leaks per million leak rays (%s).\n", st.holes.value,
                 st.holes.what.len ? exp_text_str(&st.holes.what) : "none", st.leaks.value,
                 st.leaks.what.len ? exp_text_str(&st.leaks.what) : "none");
    exp_text_add(&findings, "%s", exp_text_str(&st.cliffs));
    exp_text_add(&findings, "- Secondary-ray origins (%zu rays, at least %zu per case):",
                 off.rays, off.min_n);
    for (int m = 0; m < STAB_OFFSET_RULES; m++)
    {
        char sb[32], fb[32];
        snprintf(sb, sizeof sb, off.worst_self[m] > 0 ? "%.1f" : "0", off.worst_self[m]);
        snprintf(fb, sizeof fb, off.worst_false[m] > 0 ? "%.1f" : "0", off.worst_false[m]);
        exp_text_add(&findings, "%s %s: up to %s self-hits and %s false hits per million in a "
                     "case, %zu self-hits and %zu closest-hit and shadow leaks in all",
                     m ? ";" : "", stab_offsets_name(m), sb, fb, off.self[m], off.leaks[m]);
    }
    exp_text_add(&findings, ".%s\n", off.planted ? " PLANTED broken robust offset." : "");
    char far[400];
    far_leak_text(&off, 0, far, sizeof far);
    exp_text_add(&findings, "- Far geometry, %s.\n", far);
    far_leak_text(&off, 1, far, sizeof far);
    exp_md(&x, "\n**Findings:**\n\n%s", exp_text_str(&findings));
    size_t rob_bad = off.self[STAB_OFFSET_ROBUST] + off.leaks[STAB_OFFSET_ROBUST];
    /* A request is answered with its numbers (issue 38); the certification
     * and the far-geometry leak of each origin rule lead the evidence, the
     * part the summary shows (issue 52). */
    char fewer_pairs[96] = "";
    if (st.cert_fewer_n || st.cert_none)
        snprintf(fewer_pairs, sizeof fewer_pairs, " (%llu pairs fewer%s)",
                 (unsigned long long)st.cert_fewer_n, st.cert_none ? ", some not certified" : "");
    exp_verdict(&x, "stability", EXP_ANSWERED, "every stiff case",
                "%llu of %llu cases faulty, %d configurations each (packets, streams, wide) at "
                ">= %llu rays%s; %s; contacts: %llu leaks in %llu leak and shadow rays; robust "
                "offset: %zu self-hits and leaks in %zu secondary rays (epsilon rules: up to %.0f "
                "self-hits per million in a case); naive kernels up to %.0f holes per million "
                "rays and %.0f leaks per million leak rays; base rays: %llu of %llu cases "
                "faulty%s%s", (unsigned long long)st.cert_bad, (unsigned long long)st.cert_cases,
                st.cert_configs_max, (unsigned long long)st.cert_min_n,
                fewer_pairs, far,
                (unsigned long long)st.contact_leaks, (unsigned long long)st.contact_leak_rays,
                rob_bad, off.rays,
                fmax(fmax(off.worst_self[0], off.worst_self[1]), fmax(off.worst_self[2], off.worst_self[3])),
                st.holes.value, st.leaks.value, (unsigned long long)st.robust_bad_cases,
                (unsigned long long)st.cases, st.cert_configs_min != st.cert_configs_max
                ? "; configurations per case differ: see the section" : "",
                st.cliffs.len ? "; performance cliffs: see the findings" : "");
    exp_text_free(&findings);
    exp_text_free(&st.clean);
    exp_text_free(&st.cliffs);
    exp_text_free(&st.speeds);
    exp_text_free(&st.left);
    exp_text_free(&st.cert_rows);
    exp_text_free(&st.cert_notes);
    exp_text_free(&st.holes.what);
    exp_text_free(&st.leaks.what);
    exp_list_free(&base);
    return exp_finish(&x);
}
