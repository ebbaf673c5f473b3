/*
 * group.c - configurations measured in interleaved rounds (see group.h).
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

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

static void one_pass(const exp_cfg *c, int bit, const rays_set *r, accel_hit *hits, uint8_t *occ,
                     accel_counters *cnt)
{
    if (bench_set_is_occlusion(bit))
        accel_trace_occluded(c->kind, c->accel, r->rays, occ, r->count, c->threads, cnt);
    else
        accel_trace(c->kind, c->accel, r->rays, hits, r->count, c->threads, cnt);
}

/* Scratch results for the largest set (one buffer serves every pass). */
typedef struct {
    accel_hit *hits;
    uint8_t *occ;
} scratch;

static scratch scratch_make(const exp_group *g)
{
    size_t most = 1;
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1)
        if (g->mask & bit) {
            size_t n = bench_sets_get(g->sets, bit)->count;
            if (n > most) most = n;
        }
    scratch s = {malloc(most * sizeof *s.hits), malloc(most)};
    if (!s.hits || !s.occ) {
        fprintf(stderr, "%s: out of memory for %zu results\n", g->x->name, most);
        exit(CLI_EXIT_INTERNAL);
    }
    return s;
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
    one_pass(c, bit, &probe, hits, occ, &cnt);
    double t0 = accel_now_ms();
    one_pass(c, bit, &probe, hits, occ, NULL);
    double est_ms = (accel_now_ms() - t0) * (double)r->count / (double)n;
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
    scratch sc = scratch_make(g);
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
        double t0 = accel_now_ms();
        one_pass(c, bit, r, sc.hits, sc.occ, &t->counters);
        double counted_ms = accel_now_ms() - t0;
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
        if (g->collapse_ms > 0 && counted_ms > g->collapse_ms) {
            snprintf(c->why, sizeof c->why,
                     "collapsed: %.0f primitive tests per %s ray (of %u primitives), one counted "
                     "pass takes %.1f s",
                     (double)t->counters.prim_tests / (double)(r->count ? r->count : 1),
                     bench_set_name(bit), g->s->live_count, counted_ms / 1e3);
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
            one_pass(c, bit, r, sc.hits, sc.occ, NULL);
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
    double round_ms = 0;
    int nsets = 0;
    for (int i = 0; i < 4; i++)
        if (c->set[i].have) round_ms += c->set[i].batch * c->set[i].pass_ms, nsets++;
    double budget = x->set_budget_ms * (nsets ? nsets : 1);
    c->want = round_ms > 0 ? (int)(budget / round_ms) : x->repeats;
    if (c->want > x->repeats) c->want = x->repeats;
    if (c->want < g->min_rounds) {
        /* min_rounds, but within 4 budgets: a configuration of seconds per
         * pass keeps fewer rounds (its n says so) rather than minutes. */
        int most = round_ms > 0 ? (int)(4 * budget / round_ms) : g->min_rounds;
        int want = g->min_rounds < x->repeats ? g->min_rounds : x->repeats;
        if (want > most) want = most > 3 ? most : 3 < want ? 3 : want;
        if (want > c->want) c->want = want;
    }
    if (c->want < 1) c->want = 1;
    if (c->want > EXP_MAX_SAMPLES) c->want = EXP_MAX_SAMPLES;
    c->ok = 1;
    return idx;
}

/* Builds every configuration again in rounds; the last structure built is
 * dropped at once (the traced one stays). */
static void build_rounds(exp_group *g)
{
    exp_ctx *x = g->x;
    int reps[256] = {0}, most = 0, n = g->count < 256 ? g->count : 256;
    for (int c = 0; c < n; c++) {
        if (!g->cfg[c].ok) continue;
        double first = g->cfg[c].build.ms;
        int r = x->quick ? 3 : 10; /* 10 rounds for verdicts on build time (issue 38) */
        if (first > 0 && first * r > x->build_budget_ms) r = (int)(x->build_budget_ms / first);
        /* A build longer than half the budget keeps its first (add-time) sample
         * instead of being built once more for a single sample. */
        reps[c] = r < 2 ? 0 : r;
        if (reps[c] > most) most = reps[c];
    }
    bench_progress_begin(x->progress, "interleaved builds", most * n, 0);
    for (int r = 0; r < most; r++)
        for (int k = 0; k < n; k++) {
            int c = (k + r) % n;
            exp_cfg *cf = &g->cfg[c];
            bench_progress_add(x->progress, 1);
            if (!cf->ok || r >= reps[c]) continue;
            const accel_kind *kind;
            void *a;
            accel_build_stats st;
            accel_error err = {0};
            if (accel_build_spec(cf->spec, g->s, cf->threads, &kind, &a, &st, &err)) continue;
            kind->destroy(a);
            cf->build_samples[r] = st.ms;
            exp_est_of(cf->build_samples, r + 1, &cf->build_ms);
        }
    bench_progress_end(x->progress);
}

static double time_sample(const exp_cfg *c, int bit, const exp_group *g, scratch *sc)
{
    const exp_trace *t = &c->set[exp_set_index(bit)];
    const rays_set *r = bench_sets_get(g->sets, bit);
    double t0 = accel_now_ms();
    for (int b = 0; b < t->batch; b++) one_pass(c, bit, r, sc->hits, sc->occ, NULL);
    return (accel_now_ms() - t0) / t->batch;
}

/* The thread probe (group.h): PROBE_ITEMS items of `iters` steps each, a
 * step 256 independent multiply-adds (vectorized: enough independent
 * chains to fill a core's floating-point units, so that two threads
 * sharing one physical core would show it), on no memory but the item's
 * own registers. */
#define PROBE_ITEMS 32
#define PROBE_LANES 256

typedef struct {
    long iters;
    volatile float out[PROBE_ITEMS];
} probe_job;

static void probe_items(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    probe_job *j = p;
    const float a = 1.0f - 1.0f / 65536.0f;
    for (size_t i = begin; i < end; i++) {
        float v[PROBE_LANES], sum = 0.0f;
        for (int l = 0; l < PROBE_LANES; l++) v[l] = (float)(i + (size_t)l);
        for (long k = 0; k < j->iters; k++)
            for (int l = 0; l < PROBE_LANES; l++) v[l] = v[l] * a + 1.0f;
        for (int l = 0; l < PROBE_LANES; l++) sum += v[l];
        j->out[i] = sum;
    }
}

static double probe_ms(probe_job *j, int threads)
{
    double t0 = accel_now_ms();
    accel_parallel_for(PROBE_ITEMS, 1, threads, probe_items, j);
    return accel_now_ms() - t0;
}

/* Iterations for a 1-thread probe of about x->sample_ms, at least 10 ms:
 * shorter, the wake-up of the other threads (tens of microseconds on a
 * VM) would weigh on the ratio. */
static long probe_size(const exp_ctx *x)
{
    probe_job j = {.iters = 1 << 14};
    double ms = probe_ms(&j, 1);
    for (int i = 0; i < 8 && ms < 1.0; i++) j.iters *= 4, ms = probe_ms(&j, 1);
    double want = x->sample_ms > 10.0 ? x->sample_ms : 10.0;
    return ms > 0 ? (long)fmax(1.0, (double)j.iters * want / ms) : j.iters;
}

/* Times the rounds r of [0, most) with r % procs == part (group.h: the
 * replicas). progress: report to the progress line (never in a forked
 * replica: the progress thread did not survive the fork). */
static void run_rounds(exp_group *g, int most, int procs, int part, probe_job *probe, int aa,
                       int progress)
{
    exp_ctx *x = g->x;
    int slots = g->count + aa + (g->probe_threads > 1);
    scratch sc = scratch_make(g);
    for (int r = part; r < most; r += procs)
        for (int k = 0; k < slots; k++) {
            int slot = (k + r) % slots;
            if (slot == g->count + aa) { /* the probe's slot: 1 thread, then all */
                g->probe_samples[0][r] = probe_ms(probe, 1);
                g->probe_samples[1][r] = probe_ms(probe, g->probe_threads);
                continue;
            }
            int c = slot == g->count ? 0 : slot; /* slot count: the A/A control */
            exp_cfg *cf = &g->cfg[c];
            if (!cf->ok || r >= cf->want) continue;
            for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
                exp_trace *t = &cf->set[exp_set_index(bit)];
                if (!t->have) continue;
                double ms = time_sample(cf, bit, g, &sc);
                if (slot == g->count)
                    g->aa_samples[exp_set_index(bit)][r] = ms;
                else
                    t->samples[r] = ms;
                if (progress) bench_progress_add(x->progress, ms * t->batch);
            }
        }
    free(sc.hits), free(sc.occ);
}

/* The numbers a replica sends back, in this order, for its rounds: every
 * configuration's four sets, the A/A control's four, the probe's two. With
 * v NULL only counts them. */
static int replica_values(exp_group *g, int most, int procs, int part, double **v)
{
    int n = 0;
    for (int r = part; r < most; r += procs) {
        for (int c = 0; c < g->count; c++)
            for (int i = 0; i < 4; i++, n++)
                if (v) v[n] = &g->cfg[c].set[i].samples[r];
        for (int i = 0; i < 4; i++, n++)
            if (v) v[n] = &g->aa_samples[i][r];
        for (int i = 0; i < 2; i++, n++)
            if (v) v[n] = &g->probe_samples[i][r];
    }
    return n;
}

/* A fresh copy of one ray set (the replica's own memory). */
static void copy_set(rays_set *r)
{
    accel_ray *rays = malloc((r->count ? r->count : 1) * sizeof *rays);
    if (!rays) _exit(1);
    memcpy(rays, r->rays, r->count * sizeof *rays);
    r->rays = rays;
}

#define REPLICA_WARM_MS 200.0 /* passes longer than this are not warmed in a replica */

/* Replica `part` in a forked process: every configuration built again and
 * the rays copied, so that the structures and rays lie in the replica's
 * own fresh memory (the page placement a fresh process gets), then its
 * share of the rounds, sent to the parent through the pipe. 0 when its
 * values arrived. */
static int run_replica(exp_group *g, int most, int procs, int part, probe_job *probe, int aa)
{
    int fd[2];
    if (pipe(fd)) return -1;
    fflush(NULL); /* nothing buffered is written twice */
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]), close(fd[1]);
        return -1;
    }
    int n = replica_values(g, most, procs, part, NULL);
    double **where = malloc((size_t)(n ? n : 1) * sizeof *where);
    if (!where) {
        if (pid == 0) _exit(1);
        return -1;
    }
    replica_values(g, most, procs, part, where);
    if (pid == 0) {
        close(fd[0]);
        bench_sets fresh = *g->sets;
        rays_set *all[4] = {&fresh.primary, &fresh.shadow, &fresh.diffuse, &fresh.ao};
        for (int i = 0; i < 4; i++)
            if (all[i]->count) copy_set(all[i]);
        g->sets = &fresh;
        for (int c = 0; c < g->count; c++) {
            exp_cfg *cf = &g->cfg[c];
            /* A slow build is not repeated (group.h: EXP_REPLICA_REBUILD_MS):
             * the replica times the parent's structure, inherited by fork. */
            if (!cf->ok || cf->build.ms > EXP_REPLICA_REBUILD_MS) continue;
            accel_build_stats st;
            accel_error err = {0};
            /* The parent's copy stays where it is (never freed here). */
            if (accel_build_spec(cf->spec, g->s, cf->threads, &cf->kind, &cf->accel, &st, &err))
                _exit(2);
        }
        /* One warm pass each, as the parent's warm-up before its rounds;
         * not for passes over REPLICA_WARM_MS, whose first sample the
         * refill of the caches cannot move by more than a few tenths of
         * a percent (a cache of megabytes refills in about a millisecond),
         * and whose warm pass was a third of a slow replica's time. */
        scratch sc = scratch_make(g);
        for (int c = 0; c < g->count; c++)
            for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
                const exp_trace *t = &g->cfg[c].set[exp_set_index(bit)];
                if (g->cfg[c].ok && t->have && t->pass_ms <= REPLICA_WARM_MS)
                    one_pass(&g->cfg[c], bit, bench_sets_get(g->sets, bit), sc.hits, sc.occ, NULL);
            }
        free(sc.hits), free(sc.occ);
        run_rounds(g, most, procs, part, probe, aa, 0);
        double *buf = malloc((size_t)(n ? n : 1) * sizeof *buf);
        if (!buf) _exit(1);
        for (int i = 0; i < n; i++) buf[i] = *where[i];
        size_t left = (size_t)n * sizeof *buf;
        const char *p = (const char *)buf;
        while (left) {
            ssize_t w = write(fd[1], p, left);
            if (w < 0 && errno == EINTR) continue;
            if (w <= 0) _exit(1);
            p += w, left -= (size_t)w;
        }
        _exit(0);
    }
    close(fd[1]);
    double *buf = malloc((size_t)(n ? n : 1) * sizeof *buf);
    size_t got = 0, want = (size_t)n * sizeof *buf;
    while (buf && got < want) {
        ssize_t rd = read(fd[0], (char *)buf + got, want - got);
        if (rd < 0 && errno == EINTR) continue;
        if (rd <= 0) break;
        got += (size_t)rd;
    }
    close(fd[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    int ok = buf && got == want && WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (ok)
        for (int i = 0; i < n; i++) *where[i] = buf[i];
    free(buf), free(where);
    return ok ? 0 : -1;
}

void exp_group_run(exp_group *g)
{
    exp_ctx *x = g->x;
    if (g->time_builds) build_rounds(g);
    g->probe_threads = 1;
    for (int c = 0; g->thread_probe && c < g->count; c++)
        if (g->cfg[c].ok && g->cfg[c].threads > g->probe_threads) g->probe_threads = g->cfg[c].threads;
    probe_job probe = {.iters = g->probe_threads > 1 ? probe_size(x) : 0};
    int aa = g->control && g->count && g->cfg[0].ok;
    int most = 0;
    double total_ms = 0;
    for (int c = 0; c < g->count; c++) {
        if (!g->cfg[c].ok) continue;
        if (g->cfg[c].want > most) most = g->cfg[c].want;
        for (int i = 0; i < 4; i++)
            total_ms += g->cfg[c].want * g->cfg[c].set[i].batch * g->cfg[c].set[i].pass_ms;
    }
    /* Round r runs in process r % procs: the parent, then each replica in
     * turn (one at a time: they never compete for the cores). */
    int procs = x->procs < 1 ? 1 : x->procs > most ? (most > 0 ? most : 1) : x->procs;
    bench_progress_begin(x->progress, "interleaved timed rounds", total_ms, 0);
    run_rounds(g, most, procs, 0, &probe, aa, 1);
    bench_progress_end(x->progress);
    g->procs = 1;
    for (int r = 0; r < most; r++) g->round_proc[r] = 0;
    for (int p = 1; p < procs; p++) {
        char phase[80];
        snprintf(phase, sizeof phase, "replica %d of %d (a forked process)", p + 1, procs);
        bench_progress_begin(x->progress, phase, 0, 0);
        int ok = run_replica(g, most, procs, p, &probe, aa) == 0;
        bench_progress_end(x->progress);
        if (!ok) { /* the replica failed: its rounds run here (and count as the parent's) */
            fprintf(stderr, "%s: replica %d failed; its rounds run in this process\n", x->name, p + 1);
            run_rounds(g, most, procs, p, &probe, aa, 0);
            continue;
        }
        g->procs++;
        for (int r = p; r < most; r += procs) g->round_proc[r] = p;
    }
    x->procs_used = g->procs > x->procs_used ? g->procs : x->procs_used;
    for (int c = 0; c < g->count; c++)
        for (int i = 0; i < 4; i++)
            if (g->cfg[c].ok && g->cfg[c].set[i].have) g->cfg[c].set[i].n = g->cfg[c].want;
    g->rounds = most;
    for (int c = 0; c < g->count; c++) {
        if (!g->cfg[c].ok) continue;
        if (!x->rounds_hi || g->cfg[c].want < x->rounds_lo) x->rounds_lo = g->cfg[c].want;
        if (g->cfg[c].want > x->rounds_hi) x->rounds_hi = g->cfg[c].want;
    }
    for (int c = 0; c < g->count; c++)
        for (int i = 0; i < 4; i++)
            if (g->cfg[c].ok && g->cfg[c].set[i].have)
                exp_est_of_procs(g->cfg[c].set[i].samples, g->round_proc, g->cfg[c].set[i].n,
                                 &g->cfg[c].set[i].ms);
    if (g->probe_threads > 1 && most >= 3)
        exp_est_ratio_procs(g->probe_samples[0], g->probe_samples[1], g->round_proc, most, &g->probe);
    /* The floor: how far configuration 0 strays from itself. */
    g->floor = 0.05;
    if (aa && g->cfg[0].want >= 3) {
        double a[EXP_MAX_SAMPLES], b[EXP_MAX_SAMPLES];
        int n = exp_group_round_ms(g, 0, g->mask, a);
        for (int r = 0; r < n; r++) {
            b[r] = 0;
            for (int i = 0; i < 4; i++)
                if (g->cfg[0].set[i].have) b[r] += g->aa_samples[i][r];
        }
        exp_est_ratio_procs(a, b, g->round_proc, n, &g->aa);
        g->floor = fmax(fabs(g->aa.median - 1), fmax(fabs(g->aa.hi - 1), fabs(1 - g->aa.lo)));
        if (g->floor < EXP_MIN_FLOOR) g->floor = EXP_MIN_FLOOR;
    }
    exp_note_floor(x, g->floor, g->aa.n >= 3);
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
    free(g->cfg);
    memset(g, 0, sizeof *g);
}

