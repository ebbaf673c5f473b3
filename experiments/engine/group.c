/*
 * group.c - a group's configurations added, built, counted and checked
 * (see group.h); group_run.c times them.
 */
#include <math.h>
#include <time.h>
#include <stdlib.h>
#include <string.h>

#include "group.h"
#include "cli/cli.h"

void exp_group_init(exp_group *g, exp_ctx *x, const accel_scene *s, const bench_sets *sets,
                    int mask)
{
    memset(g, 0, sizeof *g);
    g->x = x;
    g->s = s;
    g->sets = sets;
    g->mask = mask & sets->made;
    g->control = 1;
    g->time_builds = 1;
    g->floor = EXP_MIN_FLOOR;
}

void exp_group_pass(const exp_cfg *c, int bit, const rays_set *r, accel_hit *hits, uint8_t *occ,
                    accel_counters *cnt)
{
    if (bench_set_is_occlusion(bit))
        accel_trace_occluded(c->kind, c->accel, r->rays, occ, r->count, c->threads, cnt);
    else
        accel_trace(c->kind, c->accel, r->rays, hits, r->count, c->threads, cnt);
}

exp_scratch exp_group_scratch(const exp_group *g)
{
    size_t most = 1;
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1)
        if (g->mask & bit) {
            size_t n = bench_sets_get(g->sets, bit)->count;
            if (n > most) most = n;
        }
    exp_scratch s = {malloc(most * sizeof *s.hits), malloc(most)};
    if (!s.hits || !s.occ) {
        fprintf(stderr, "%s: out of memory for %zu results\n", g->x->name, most);
        exit(CLI_EXIT_INTERNAL);
    }
    return s;
}

/* CPU time of this process, ms: the collapse rule's clock (issue 52: a
 * limit in wall time moved with the machine; on a loaded machine a
 * counted pass of 0.25 s CPU took 0.6 s and was left out as collapsed). */
static double cpu_ms(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts)) return accel_now_ms();
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

static int same_structure(const exp_cfg *a, const exp_cfg *b, int mask)
{
    const accel_build_stats *p = &a->build, *q = &b->build;
    if (a->kind != b->kind || a->threads != b->threads || p->bytes != q->bytes ||
        p->test_lanes != q->test_lanes ||
        p->nodes != q->nodes || p->leaves != q->leaves || p->refs != q->refs ||
        p->depth != q->depth || memcmp(p->res, q->res, sizeof p->res) ||
        !((isnan(p->sah_cost) && isnan(q->sah_cost)) || p->sah_cost == q->sah_cost))
        return 0;
    /* Kernel choices that change answers or layout but not the counts. */
    accel_params pa, pb;
    accel_error err;
    if (accel_params_parse(a->spec, &pa, &err) || accel_params_parse(b->spec, &pb, &err) ||
        pa.naive != pb.naive || pa.reorder != pb.reorder)
        return 0;
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
        if (!(mask & bit)) continue;
        if (a->set[exp_set_index(bit)].have != b->set[exp_set_index(bit)].have) return 0;
        const accel_counters *u = &a->set[exp_set_index(bit)].counters;
        const accel_counters *v = &b->set[exp_set_index(bit)].counters;
        if (u->steps != v->steps || u->box_tests != v->box_tests ||
            u->prim_tests != v->prim_tests || u->empty_steps != v->empty_steps ||
            u->mailbox_skips != v->mailbox_skips || u->packet_steps != v->packet_steps)
            return 0;
    }
    return 1;
}

static void leave_out(exp_group *g, exp_cfg *c, int why_kind)
{
    c->ok = 0;
    c->left = why_kind;
    /* A spec this build lacks counts once per section, however many scenes. */
    if (why_kind != EXP_LEFT_UNPARSED || exp_note_unparsed(g->x, c->spec)) exp_note_left(g->x, why_kind);
    if (c->accel) c->kind->destroy(c->accel);
    c->accel = NULL;
}

/* Before a counted pass that may take minutes: PROBE_BLOCKS blocks of 64
 * consecutive rays (8x8 tiles, so packets stay coherent) spread evenly over
 * the set are traced, counted, then timed; when the pass they predict is
 * longer than 1.25 collapse_ms the configuration is collapsed without the
 * full pass (one such pass of `grid` on teapot_stadium at 800x600 took
 * 143 s). */
#define PROBE_BLOCKS 32
static int probe_collapsed(exp_group *g, exp_cfg *c, int bit, const rays_set *r)
{
    const size_t block = 64, n = PROBE_BLOCKS * block;
    if (r->count < 4 * n) return 0;
    accel_ray *rays = malloc(n * sizeof *rays);
    accel_hit *hits = malloc(n * sizeof *hits);
    uint8_t *occ = malloc(n);
    if (!rays || !hits || !occ) {
        free(rays), free(hits), free(occ);
        return 0;
    }
    size_t blocks = r->count / block;
    for (size_t b = 0; b < PROBE_BLOCKS; b++)
        memcpy(rays + b * block, r->rays + (b * blocks / PROBE_BLOCKS) * block, block * sizeof *rays);
    rays_set probe = {rays, NULL, n, 0, 0};
    accel_counters cnt = {0};
    /* Timed warm (the first touch of a fresh structure is slow): the
     * counted pass warms it, the second is timed. */
    exp_group_pass(c, bit, &probe, hits, occ, &cnt);
    double t0 = cpu_ms();
    exp_group_pass(c, bit, &probe, hits, occ, NULL);
    double est_ms = (cpu_ms() - t0) / (c->threads > 1 ? c->threads : 1) * (double)r->count / (double)n;
    free(rays), free(hits), free(occ);
    /* Only a clear collapse is decided by the probe (a 25% margin for its
     * noise); a near one gets the full counted pass and the rule below. */
    if (est_ms <= 1.25 * g->collapse_ms) return 0;
    c->counted_ms = est_ms;
    snprintf(c->why, sizeof c->why,
             "collapsed: %.0f primitive tests per %s ray (of %u primitives) in a probe of %zu "
             "rays, which predicts %.1f s per pass",
             (double)cnt.prim_tests / (double)n, bench_set_name(bit), g->s->live_count, n,
             est_ms / 1e3);
    return 1;
}

/* Long on purpose (123 lines): the steps of adding one configuration
 * (parse, build with its budget, the probe, the refusal messages) fill one
 * exp_cfg in order; each refusal says why in its own words. */
int exp_group_add(exp_group *g, const char *spec, int threads)
{
    exp_ctx *x = g->x;
    if (g->count == g->cap) {
        int cap = g->cap ? 2 * g->cap : 16;
        exp_cfg *n = realloc(g->cfg, (size_t)cap * sizeof *n);
        if (!n) {
            fprintf(stderr, "%s: out of memory\n", x->name);
            exit(CLI_EXIT_INTERNAL);
        }
        g->cfg = n, g->cap = cap;
    }
    int idx = g->count++;
    exp_cfg *c = &g->cfg[idx];
    memset(c, 0, sizeof *c);
    snprintf(c->spec, sizeof c->spec, "%s", spec);
    c->threads = threads > 0 ? threads : x->threads;
    c->same_as = -1;
    accel_error err = {0};
    accel_params p;
    if (accel_params_parse(spec, &p, &err)) {
        snprintf(c->why, sizeof c->why, "not in this build: %s", err.msg);
        leave_out(g, c, EXP_LEFT_UNPARSED);
        return idx;
    }
    char phase[320];
    snprintf(phase, sizeof phase, "build %s", spec);
    bench_progress_begin(x->progress, phase, 0, 0);
    int rc = accel_build_spec(spec, g->s, c->threads, &c->kind, &c->accel, &c->build, &err);
    bench_progress_end(x->progress);
    if (rc) {
        snprintf(c->why, sizeof c->why, "%s", err.msg);
        c->accel = NULL;
        leave_out(g, c, EXP_LEFT_FAILED);
        return idx;
    }
    c->build_samples[0] = c->build.ms;
    exp_est_of(c->build_samples, 1, &c->build_ms);
    exp_scratch sc = exp_group_scratch(g);
    int cmask = g->add_mask ? g->mask & g->add_mask : g->mask;
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
        if (!(cmask & bit)) continue;
        exp_trace *t = &c->set[exp_set_index(bit)];
        const rays_set *r = bench_sets_get(g->sets, bit);
        t->rays = r->count;
        if (g->per_ray && bit == BENCH_PRIMARY) {
            t->ray_steps = calloc(r->count ? r->count : 1, sizeof *t->ray_steps);
            t->ray_prims = calloc(r->count ? r->count : 1, sizeof *t->ray_prims);
            t->counters.ray_steps = t->ray_steps;
            t->counters.ray_prims = t->ray_prims;
        }
        if (g->collapse_ms > 0 && probe_collapsed(g, c, bit, r)) {
            free(sc.hits), free(sc.occ);
            leave_out(g, c, EXP_LEFT_COLLAPSED);
            return idx;
        }
        snprintf(phase, sizeof phase, "count %s with %s", bench_set_name(bit), spec);
        bench_progress_begin(x->progress, phase, (double)r->count, 1);
        double t0 = accel_now_ms(), c0 = cpu_ms();
        exp_group_pass(c, bit, r, sc.hits, sc.occ, &t->counters);
        double counted_ms = accel_now_ms() - t0;
        /* The collapse rule on CPU time per thread (cpu_ms), never more than the wall time. */
        double counted_cpu = fmin(counted_ms, (cpu_ms() - c0) / (c->threads > 1 ? c->threads : 1));
        bench_progress_end(x->progress);
        if (counted_ms > c->counted_ms) c->counted_ms = counted_ms;
        t->counters.ray_steps = t->counters.ray_prims = NULL;
        if (accel_counters_status(&t->counters, &err)) {
            exp_internal(x, spec, &err);
            snprintf(c->why, sizeof c->why, "broken invariant: %s", err.msg);
            free(sc.hits), free(sc.occ);
            leave_out(g, c, EXP_LEFT_FAILED);
            return idx;
        }
        if (g->collapse_ms > 0 && counted_cpu > g->collapse_ms) {
            snprintf(c->why, sizeof c->why,
                     "collapsed: %.0f primitive tests per %s ray (of %u primitives), one counted "
                     "pass takes %.1f s of CPU time",
                     (double)t->counters.prim_tests / (double)(r->count ? r->count : 1),
                     bench_set_name(bit), g->s->live_count, counted_cpu / 1e3);
            free(sc.hits), free(sc.occ);
            leave_out(g, c, EXP_LEFT_COLLAPSED);
            return idx;
        }
        /* The warm-up: a pass as long as a sample budget already warmed the
         * caches in the counted pass and stands in for it. */
        if (counted_ms > 4 * x->sample_ms) {
            t->pass_ms = counted_ms;
        } else {
            t0 = accel_now_ms();
            exp_group_pass(c, bit, r, sc.hits, sc.occ, NULL);
            t->pass_ms = accel_now_ms() - t0;
        }
        t->have = 1;
        t->batch = t->pass_ms > 0 ? (int)ceil(x->sample_ms / t->pass_ms) : 1;
        if (t->batch < 1) t->batch = 1;
        if (t->batch > 1000) t->batch = 1000;
    }
    free(sc.hits), free(sc.occ);
    for (int d = 0; d < idx && !g->keep_same; d++)
        if (g->cfg[d].ok && same_structure(&g->cfg[d], c, g->mask)) {
            c->same_as = d;
            snprintf(c->why, sizeof c->why, "the same structure as `%s` (equal build statistics "
                     "and counts per ray)", g->cfg[d].spec);
            leave_out(g, c, EXP_LEFT_IDENTICAL);
            return idx;
        }
    /* Every configuration gets procs x proc_rounds rounds (group.h); the
     * batch is set in exp_group_run, when the timed share of each set is
     * known. */
    c->want = (x->procs < 1 ? 1 : x->procs) * (x->proc_rounds < 1 ? 1 : x->proc_rounds);
    if (c->want > EXP_MAX_SAMPLES) c->want = EXP_MAX_SAMPLES;
    c->ok = 1;
    return idx;
}

void exp_group_note(exp_group *g)
{
    int any = 0;
    for (int c = 0; c < g->count; c++)
        if (g->cfg[c].left) {
            exp_md(g->x, "%s`%s` (%s)", any ? "; " : "\nLeft out: ", g->cfg[c].spec, g->cfg[c].why);
            any = 1;
        }
    if (any) exp_md(g->x, ".\n");
}

void exp_group_free(exp_group *g)
{
    for (int c = 0; c < g->count; c++) {
        exp_cfg *cf = &g->cfg[c];
        if (cf->accel) cf->kind->destroy(cf->accel);
        for (int i = 0; i < 4; i++) free(cf->set[i].ray_steps), free(cf->set[i].ray_prims);
    }
    for (int i = 0; i < 4; i++) free(g->sub[i].rays);
    free(g->cfg);
    memset(g, 0, sizeof *g);
}

