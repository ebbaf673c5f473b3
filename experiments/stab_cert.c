/*
 * stab_cert.c - exp_stability's certification: each built-in stiff case
 * again with a million rays and more (stiff_case_make_n), traced by every
 * watertight configuration of the case's group but brute force, against
 * the exact reference: holes, false hits, disagreements (rays/compare.c's
 * rule), leaks of the rays from inside and of the shadow rays.
 *
 * What runs is fixed, never a time limit: every configuration on every
 * ray of the case, but for the pairs of cert_fewer (a fixed spread share,
 * named in the report with the counts per ray that justify it); a
 * configuration the group left out (collapsed on the base rays) is built
 * here, one that cannot be built gets a row with the reason. Packet modes
 * trace with every 64 consecutive rays a packet (ACCEL_ORDER_KEEP): in the
 * default sorted order the coherence layer sends incoherent rays to the
 * single-ray kernels, which would certify those again.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stab_cert.h"
#include "cli/cli.h"
#include "core/coherence.h"
#include "rays/stiff.h"

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

int stab_cert_threads(const exp_ctx *x)
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

int stab_cert_is_packet(const char *spec) { return strstr(spec, "traverse=packet") != NULL; }

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
 * (102 lines): the configurations in turn, then the case's row, sharing the
 * reference and the tallies. */
void stab_cert_case(exp_ctx *x, stab_cert *cs, int ci, const exp_group *g, int m)
{
    stiff_case big;
    accel_error err = {0};
    if (stiff_case_make_n(ci, x->quick ? STAB_CERT_RAYS_QUICK : STAB_CERT_RAYS, &big, &err)) {
        exp_internal(x, "stiff case", &err);
        return;
    }
    int T = stab_cert_threads(x);
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
            exp_text_add(&cs->notes, "- %s: `%s` not certified (%s).\n", big.name, f->spec,
                         f->why[0] ? f->why : err.msg);
            exp_csv(x, "cert,%s,%s,0,0,0,,,,,,,,,not certified: %s\n", big.name, f->spec,
                    f->why[0] ? f->why : err.msg);
            cs->none++;
            continue;
        }
        size_t want = cert_rays_for(big.name, f->spec, n), step = want ? n / want : 1;
        if (step < 1) step = 1;
        cert_counts r = cert_one(&big, ref, kind, accel, stab_cert_is_packet(f->spec), step, T, h, occ);
        if (own) kind->destroy(own);
        char note[200] = "";
        if (step > 1) {
            if (f->ok)
                snprintf(note, sizeof note, "a fixed %zu of %zu rays (every %zu-th): %.0f steps "
                         "and %.0f primitive tests per ray on the base rays", r.n, n, step,
                         exp_group_steps(g, k, BENCH_PRIMARY), exp_group_prims(g, k, BENCH_PRIMARY));
            else
                snprintf(note, sizeof note, "a fixed %zu of %zu rays (every %zu-th)", r.n, n, step);
            exp_text_add(&cs->notes, "- %s: `%s` on %s (below %.0f per million).\n", big.name,
                         f->spec, note, 3e6 / (double)r.n);
            fewer++;
            cs->fewer++;
            cs->fewer_min = cs->fewer_min && cs->fewer_min < r.n ? cs->fewer_min : r.n;
        } else {
            cs->full++;
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
        cs->traces += r.n + r.ns;
        cs->leaks += r.leaks + r.sleaks;
        if (strstr(big.name, "touching") || strstr(big.name, "interpenetrating"))
            cs->contact_leaks += r.leaks + r.sleaks;
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
    exp_text_add(&cs->rows, "| %s | %zu (< %.1f) | %s | %s | %s | %s |\n", big.name, n,
                 3e6 / (double)n, lb, sb, cb, faults.len ? exp_text_str(&faults) : "none");
    cs->cases++;
    cs->listed += (uint64_t)listed;
    if (!cs->configs_min || listed < cs->configs_min) cs->configs_min = listed;
    if (listed > cs->configs_max) cs->configs_max = listed;
    cs->bad += faults.len > 0;
    cs->rays += n;
    cs->min_n = cs->min_n && cs->min_n < n ? cs->min_n : n;
    if (nl) {
        cs->leak_min = cs->leak_min && cs->leak_min < nl ? cs->leak_min : nl;
        cs->leak_rays += nl + ns;
        if (strstr(big.name, "touching") || strstr(big.name, "interpenetrating"))
            cs->contact_leak_rays += nl + ns;
    }
    exp_text_free(&faults);
    free(ref), free(h), free(occ);
    stiff_case_free(&big);
}

void stab_cert_free(stab_cert *cs)
{
    exp_text_free(&cs->rows);
    exp_text_free(&cs->notes);
}
