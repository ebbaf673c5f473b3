/*
 * group_run.c - a group's timed rounds (group.h): the builds, the
 * replica processes that take turns with this one, the rounds of each,
 * the reference kernel and the thread probe in them, and the estimates
 * over processes. Split from group.c, which adds configurations.
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "group.h"

/* Builds every configuration again in rounds; the last structure built is
 * dropped at once (the traced one stays). */
/* One timed build of cf, the structure freed: its ms, -1 when it fails. */
static double build_ms(const exp_cfg *cf, const accel_scene *s)
{
    const accel_kind *kind;
    void *a;
    accel_build_stats st;
    accel_error err = {0};
    if (accel_build_spec(cf->spec, s, cf->threads, &kind, &a, &st, &err)) return -1;
    kind->destroy(a);
    return st.ms;
}

static void build_rounds(exp_group *g)
{
    exp_ctx *x = g->x;
    int reps[256] = {0}, most = 0, n = g->count < 256 ? g->count : 256;
    for (int c = 0; c < n; c++) {
        if (!g->cfg[c].ok || g->cfg[c].build_procs) continue; /* built in the processes */
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
            double ms = build_ms(cf, g->s);
            if (ms < 0) continue;
            cf->build_samples[r] = ms;
            exp_est_of(cf->build_samples, r + 1, &cf->build_ms);
        }
    bench_progress_end(x->progress);
}

/* The rays a sample traces: the set's timed share (group.h), else the set. */
static const rays_set *timed_set(const exp_group *g, int bit)
{
    const rays_set *sub = &g->sub[exp_set_index(bit)];
    return sub->count ? sub : bench_sets_get(g->sets, bit);
}

/* ms of a full pass over ms of a share pass (1 without a share): measured
 * (measure_scale), else the ray count ratio. */
static double share_scale(const exp_group *g, int bit)
{
    int i = exp_set_index(bit);
    const rays_set *sub = &g->sub[i];
    if (!sub->count) return 1.0;
    if (g->sub_scale[i] > 0) return g->sub_scale[i];
    return (double)bench_sets_get(g->sets, bit)->count / (double)sub->count;
}

#define SCALE_PASSES 5
/* A full pass of the fastest configuration longer than this keeps the
 * ray count ratio (the measurement would cost more than the rounds). */
#define SCALE_MAX_PASS_MS 400.0

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* group.h: the scale of set `bit`'s share, from the group's fastest
 * configuration timed on alternate full and share passes. */
static void measure_scale(exp_group *g, int bit, exp_scratch *sc)
{
    int i = exp_set_index(bit), best = -1;
    for (int c = 0; c < g->count; c++)
        if (g->cfg[c].ok && g->cfg[c].set[i].have &&
            (best < 0 || g->cfg[c].set[i].pass_ms < g->cfg[best].set[i].pass_ms))
            best = c;
    if (best < 0 || g->cfg[best].set[i].pass_ms > SCALE_MAX_PASS_MS) return;
    const rays_set *full = bench_sets_get(g->sets, bit), *sub = &g->sub[i];
    /* the share is timed in batches as long as a tenth of a full pass */
    double share_ms = g->cfg[best].set[i].pass_ms * (double)sub->count / (double)full->count;
    int batch = share_ms > 0 ? (int)ceil(0.1 * g->cfg[best].set[i].pass_ms / share_ms) : 1;
    if (batch < 1) batch = 1;
    double f[SCALE_PASSES], h[SCALE_PASSES];
    exp_group_pass(&g->cfg[best], bit, sub, sc->hits, sc->occ, NULL); /* warm */
    for (int k = 0; k < SCALE_PASSES; k++) {
        double t0 = accel_now_ms();
        exp_group_pass(&g->cfg[best], bit, full, sc->hits, sc->occ, NULL);
        double t1 = accel_now_ms();
        for (int b = 0; b < batch; b++) exp_group_pass(&g->cfg[best], bit, sub, sc->hits, sc->occ, NULL);
        f[k] = t1 - t0, h[k] = (accel_now_ms() - t1) / batch;
    }
    qsort(f, SCALE_PASSES, sizeof *f, cmp_double);
    qsort(h, SCALE_PASSES, sizeof *h, cmp_double);
    if (f[SCALE_PASSES / 2] > 0 && h[SCALE_PASSES / 2] > 0)
        g->sub_scale[i] = f[SCALE_PASSES / 2] / h[SCALE_PASSES / 2];
}

/* ms of one pass over the whole set, from a batch over the timed rays. */
static double time_sample(const exp_cfg *c, int bit, const exp_group *g, exp_scratch *sc)
{
    const exp_trace *t = &c->set[exp_set_index(bit)];
    const rays_set *r = timed_set(g, bit);
    double t0 = accel_now_ms();
    for (int b = 0; b < t->batch; b++) exp_group_pass(c, bit, r, sc->hits, sc->occ, NULL);
    return (accel_now_ms() - t0) / t->batch * share_scale(g, bit);
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

const char *exp_thread_gate(exp_ctx *x, int threads, const char *verdict, char *why, size_t n)
{
    if (n) why[0] = 0;
    if (threads < 2 || !verdict) return verdict;
    if (x->thread_eff_n != threads) {
        probe_job j = {.iters = probe_size(x)};
        double r[9];
        for (int i = 0; i < 9; i++) {
            double t1 = probe_ms(&j, 1), tn = probe_ms(&j, threads);
            r[i] = tn > 0 ? t1 / tn : 0;
        }
        qsort(r, 9, sizeof *r, cmp_double);
        x->thread_eff = r[4] / threads, x->thread_eff_n = threads;
    }
    int held = x->thread_eff < EXP_PROBE_LINEAR;
    snprintf(why, n, "the thread probe (work that touches no memory) reached %.0f%% efficiency on "
             "%d threads%s", 100 * x->thread_eff, threads,
             !held ? "" : strcmp(verdict, EXP_CONFIRMED) ? ", below 90%: the machine held the "
             "threads down, so a miss on them is not testable here"
                     : ", below 90%: the claim is met even so");
    return held && strcmp(verdict, EXP_CONFIRMED) ? EXP_UNTESTABLE : verdict;
}

/* Round k of process p (sample index p * rounds + k): the reference kernel,
 * then every slot once, the configurations, the A/A control and the thread
 * probe, rotated by p and reversed in odd rounds (A B C, then C B A). */
static void run_round(exp_group *g, int p, int k, int rounds, probe_job *probe, int aa, exp_scratch *sc)
{
    int r = p * rounds + k, has_probe = g->probe_threads > 1;
    /* The reference kernel first, at the start of the process's turn,
     * never right after a configuration: it measures the machine, not
     * what the slot before it left behind (after 2-thread slots its
     * process means strayed by 15-26%, after 1-thread ones by 3-4%). */
    g->ref_samples[r] = exp_ref_time(g->x);
    int slots = g->count + aa + has_probe;
    for (int i = 0; i < slots; i++) {
        int slot = ((k % 2 ? slots - 1 - i : i) + p) % slots;
        if (has_probe && slot == g->count + aa) { /* the probe: 1 thread, then all */
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
            double ms = time_sample(cf, bit, g, sc);
            if (slot == g->count)
                g->aa_samples[exp_set_index(bit)][r] = ms;
            else
                t->samples[r] = ms;
        }
    }
    int last = k == rounds - 1, first = k == (rounds > 1 ? 1 : 0);
    if (k % 2 == 0 && !last) return;
    /* The process's builds (group.h), after its odd rounds, rotated by
     * p + k, twice over (A B C A B C) for a build that fits the budget
     * twice (build_procs 2): its sample is the fastest of them. */
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < g->count; i++) {
            exp_cfg *cf = &g->cfg[(i + p + k) % g->count];
            if (!cf->ok || !cf->build_procs || (pass && cf->build_procs < 2)) continue;
            double ms = build_ms(cf, g->s);
            if (ms >= 0 && ((first && !pass) || ms < cf->build_samples[p]))
                cf->build_samples[p] = ms;
        }
}

/* The numbers a replica sends back, in this order, for each of its rounds:
 * every configuration's four sets, the A/A control's four, the probe's
 * two, the reference. With v NULL only counts them. */
static int replica_values(exp_group *g, int p, int rounds, double **v)
{
    int n = 0;
    for (int k = 0; k < rounds; k++) {
        int r = p * rounds + k;
        for (int c = 0; c < g->count; c++)
            for (int i = 0; i < 4; i++, n++)
                if (v) v[n] = &g->cfg[c].set[i].samples[r];
        for (int i = 0; i < 4; i++, n++)
            if (v) v[n] = &g->aa_samples[i][r];
        for (int i = 0; i < 2; i++, n++)
            if (v) v[n] = &g->probe_samples[i][r];
        if (v) v[n] = &g->ref_samples[r];
        n++;
    }
    for (int c = 0; c < g->count; c++, n++)
        if (v) v[n] = &g->cfg[c].build_samples[p];
    return n;
}

/* A fresh copy of one ray set (the replica's own memory). */
static void copy_set(rays_set *r)
{
    accel_ray *rays = malloc((r->count ? r->count : 1) * sizeof *rays);
    if (!rays) _exit(1);
    memcpy(rays, r->rays, r->count * sizeof *rays);
    r->rays = rays;
    r->pixel = NULL;
}

static int write_all(int fd, const void *buf, size_t n)
{
    const char *p = buf;
    while (n) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w, n -= (size_t)w;
    }
    return 0;
}

static int read_all(int fd, void *buf, size_t n)
{
    char *p = buf;
    while (n) {
        ssize_t rd = read(fd, p, n);
        if (rd < 0 && errno == EINTR) continue;
        if (rd <= 0) return -1;
        p += rd, n -= (size_t)rd;
    }
    return 0;
}

#define REPLICA_WARM_MS 200.0 /* timed passes longer than this are not warmed in a replica */

/* A replica: processes in turn with this one (group.h). */
typedef struct {
    pid_t pid;
    int cmd, rep; /* the parent's ends: commands to it, its answers */
    int alive;
} replica;

/* Replica p in the forked process: the rays copied and the structures
 * rebuilt into its own fresh memory, one warm pass each, then the rounds
 * the parent sends (a round index; -1: done, send the values). Never
 * returns. */
static void replica_main(exp_group *g, int p, int rounds, int cmd, int rep, probe_job *probe, int aa)
{
    bench_sets fresh = *g->sets;
    rays_set *all[4] = {&fresh.primary, &fresh.shadow, &fresh.diffuse, &fresh.ao};
    for (int i = 0; i < 4; i++) {
        if (g->sub[i].count) copy_set(&g->sub[i]);
        else if (all[i]->count) copy_set(all[i]);
    }
    g->sets = &fresh;
    /* A group that times builds only (no set: a duel of builders) traces
     * nothing: its structures are not built again here. */
    for (int c = 0; c < g->count && g->mask; c++) {
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
    exp_scratch sc = exp_group_scratch(g);
    for (int c = 0; c < g->count; c++)
        for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
            const exp_trace *t = &g->cfg[c].set[exp_set_index(bit)];
            if (g->cfg[c].ok && t->have && t->pass_ms / share_scale(g, bit) <= REPLICA_WARM_MS)
                exp_group_pass(&g->cfg[c], bit, timed_set(g, bit), sc.hits, sc.occ, NULL);
        }
    char ready = 'r';
    if (write_all(rep, &ready, 1)) _exit(1);
    for (;;) {
        int k;
        if (read_all(cmd, &k, sizeof k)) _exit(1);
        if (k < 0) break;
        run_round(g, p, k, rounds, probe, aa, &sc);
        char done = 'd';
        if (write_all(rep, &done, 1)) _exit(1);
    }
    int n = replica_values(g, p, rounds, NULL);
    double **where = malloc((size_t)(n ? n : 1) * sizeof *where);
    double *buf = malloc((size_t)(n ? n : 1) * sizeof *buf);
    if (!where || !buf) _exit(1);
    replica_values(g, p, rounds, where);
    for (int i = 0; i < n; i++) buf[i] = *where[i];
    _exit(write_all(rep, buf, (size_t)n * sizeof *buf) ? 1 : 0);
}

/* Forks replica p (rp->pid 0: it could not start); replica_ready then
 * waits for it. */
static void replica_start(exp_group *g, replica *rp, int p, int rounds, probe_job *probe, int aa,
                          const replica *earlier, int earlier_n)
{
    int c2r[2], r2c[2];
    rp->alive = 0, rp->pid = 0;
    if (pipe(c2r)) return;
    if (pipe(r2c)) {
        close(c2r[0]), close(c2r[1]);
        return;
    }
    fflush(NULL); /* nothing buffered is written twice */
    pid_t pid = fork();
    if (pid < 0) {
        close(c2r[0]), close(c2r[1]), close(r2c[0]), close(r2c[1]);
        return;
    }
    if (pid == 0) {
        /* The parent's ends of the earlier replicas' pipes: closed here, so
         * that each sees the end of its pipe when the parent's end closes. */
        for (int q = 0; q < earlier_n; q++)
            if (earlier[q].pid > 0) close(earlier[q].cmd), close(earlier[q].rep);
        close(c2r[1]), close(r2c[0]);
        replica_main(g, p, rounds, c2r[0], r2c[1], probe, aa);
    }
    close(c2r[0]), close(r2c[1]);
    rp->pid = pid, rp->cmd = c2r[1], rp->rep = r2c[0];
}

/* Waits for a started replica's 'r': its `alive` says whether it is ready. */
static void replica_ready(replica *rp)
{
    char ready;
    rp->alive = rp->pid > 0 && read_all(rp->rep, &ready, 1) == 0 && ready == 'r';
}

static void replica_stop(replica *rp)
{
    if (!rp->pid) return;
    close(rp->cmd), close(rp->rep);
    int status;
    while (waitpid(rp->pid, &status, 0) < 0 && errno == EINTR) {}
    rp->pid = 0, rp->alive = 0;
}

/* The timed share of each set and every configuration's batch (group.h). */
static void plan_samples(exp_group *g, int samples)
{
    exp_ctx *x = g->x;
    /* A sample lasts at most 2 x sample_ms (10 ms at the full budget), and
     * never more than the set budget over the samples: 16 samples of a
     * slow configuration cost 160 ms per set where issue 38's rounds cost
     * 400 ms, or up to 1600 ms with its 10 rounds. */
    double cap = fmin(x->set_budget_ms / (samples > 0 ? samples : 1), 2 * x->sample_ms);
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
        if (!(g->mask & bit)) continue;
        int i = exp_set_index(bit);
        double slowest = 0;
        for (int c = 0; c < g->count; c++)
            if (g->cfg[c].ok && g->cfg[c].set[i].have) slowest = fmax(slowest, g->cfg[c].set[i].pass_ms);
        const rays_set *r = bench_sets_get(g->sets, bit);
        size_t blocks = r->count / 64, keep = blocks;
        if (slowest > cap && blocks >= 32) {
            keep = (size_t)ceil((double)blocks * cap / slowest);
            if (keep < 16) keep = 16;
        }
        if (keep < blocks) {
            accel_ray *rays = malloc(keep * 64 * sizeof *rays);
            if (rays) {
                for (size_t b = 0; b < keep; b++)
                    memcpy(rays + b * 64, r->rays + (b * blocks / keep) * 64, 64 * sizeof *rays);
                g->sub[i] = (rays_set){rays, NULL, keep * 64, r->width, r->height};
            }
        }
        if (g->sub[i].count) {
            exp_scratch sc = exp_group_scratch(g);
            measure_scale(g, bit, &sc);
            free(sc.hits), free(sc.occ);
        }
        double scale = share_scale(g, bit);
        for (int c = 0; c < g->count; c++) {
            exp_trace *t = &g->cfg[c].set[i];
            if (!g->cfg[c].ok || !t->have) continue;
            double pass = t->pass_ms / scale;
            t->batch = pass > 0 ? (int)ceil(x->sample_ms / pass) : 1;
            if (t->batch < 1) t->batch = 1;
            if (t->batch > 1000) t->batch = 1000;
        }
    }
}

/* The smallest and largest of the processes' geometric means of v (values
 * <= 0 left out); 0, 0 when none. */
static void proc_mean_range(const double *v, const int *proc, int n, double *lo, double *hi)
{
    double l = INFINITY, h = -INFINITY;
    for (int id = 0; id < EXP_MAX_SAMPLES; id++) {
        double sum = 0;
        int m = 0;
        for (int i = 0; i < n; i++)
            if (proc[i] == id && v[i] > 0) sum += log(v[i]), m++;
        if (!m) continue;
        l = fmin(l, sum / m), h = fmax(h, sum / m);
    }
    *lo = h >= l ? exp(l) : 0, *hi = h >= l ? exp(h) : 0;
}

/* Long on purpose (about 100 lines): the plan, the replicas' start, the
 * interleaved turns, the values' return and the estimates, in order. */
void exp_group_run(exp_group *g)
{
    exp_ctx *x = g->x;
    int procs = g->want_procs > 0 && x->procs > 1 ? g->want_procs : x->procs;
    procs = procs < 1 ? 1 : procs > 16 ? 16 : procs;
    /* a duel's builds: every build point of every process (group.h) */
    double budget = g->duel ? EXP_DUEL_BUILD_MS * procs / (x->quick ? 4 : 1)
                            : x->build_budget_ms;
    int points = g->duel ? (g->proc_rounds + 1) / 2 : 1;
    for (int c = 0; c < g->count; c++)
        g->cfg[c].build_procs = g->time_builds && procs > 1 && g->cfg[c].ok &&
                                        g->cfg[c].build.ms * procs * points <= budget
                                    ? 1 + (g->build_twice &&
                                           g->cfg[c].build.ms * procs * points * 2 <= budget)
                                    : 0;
    if (g->time_builds) build_rounds(g);
    exp_ref_ready(x);
    g->probe_threads = 1;
    for (int c = 0; g->thread_probe && c < g->count; c++)
        if (g->cfg[c].ok && g->cfg[c].threads > g->probe_threads) g->probe_threads = g->cfg[c].threads;
    probe_job probe = {.iters = g->probe_threads > 1 ? probe_size(x) : 0};
    int aa = g->control && g->count && g->cfg[0].ok;
    int rounds = procs == 1 ? x->repeats : g->proc_rounds > 0 ? g->proc_rounds : x->proc_rounds;
    if (rounds < 1) rounds = 1;
    if (procs * rounds > EXP_MAX_SAMPLES) rounds = EXP_MAX_SAMPLES / procs;
    int total = procs * rounds;
    for (int c = 0; c < g->count; c++) g->cfg[c].want = total;
    plan_samples(g, total);
    void (*old_pipe)(int) = signal(SIGPIPE, SIG_IGN); /* a dead replica is a failed write */
    replica rep[16] = {{0}};
    bench_progress_begin(x->progress, "start the replica processes", 0, 0);
    int live = 0; /* no replica for a group with nothing to measure */
    for (int c = 0; c < g->count; c++) live += g->cfg[c].ok;
    /* Two replicas build at a time, one per core (untimed: their rounds
     * start when every replica is ready). */
    for (int p = 1; p < procs && live; p += 2) {
        int q = p + 1 < procs ? p + 1 : p;
        for (int i = p; i <= q; i++) replica_start(g, &rep[i], i, rounds, &probe, aa, rep, i);
        for (int i = p; i <= q; i++) replica_ready(&rep[i]);
    }
    bench_progress_end(x->progress);
    for (int r = 0; r < total; r++) g->round_proc[r] = r / rounds;
    exp_scratch sc = exp_group_scratch(g);
    double steal = 0, cpu = 0;
    char phase[96];
    snprintf(phase, sizeof phase, "interleaved rounds in %d processes", procs);
    bench_progress_begin(x->progress, phase, total, 0);
    for (int k = 0; k < rounds; k++)
        for (int i = 0; i < procs; i++) {
            int p = k % 2 ? procs - 1 - i : i;
            double s0, c0, s1, c1;
            int ticks = exp_cpu_ticks(&s0, &c0) == 0;
            char done = 0;
            if (p > 0 && rep[p].alive &&
                (write_all(rep[p].cmd, &k, sizeof k) || read_all(rep[p].rep, &done, 1) || done != 'd'))
                rep[p].alive = 0;
            if (p == 0 || !rep[p].alive) { /* this process (also for a replica that failed) */
                run_round(g, p, k, rounds, &probe, aa, &sc);
                if (p > 0) g->round_proc[p * rounds + k] = 0;
            }
            if (ticks && exp_cpu_ticks(&s1, &c1) == 0) steal += s1 - s0, cpu += c1 - c0;
            bench_progress_add(x->progress, 1);
        }
    bench_progress_end(x->progress);
    g->procs = 1;
    for (int p = 1; p < procs; p++) {
        if (!rep[p].alive) {
            replica_stop(&rep[p]);
            continue;
        }
        int stop = -1, n = replica_values(g, p, rounds, NULL);
        double **where = malloc((size_t)(n ? n : 1) * sizeof *where);
        double *buf = malloc((size_t)(n ? n : 1) * sizeof *buf);
        int ok = where && buf && !write_all(rep[p].cmd, &stop, sizeof stop) &&
                 !read_all(rep[p].rep, buf, (size_t)n * sizeof *buf);
        if (ok) {
            replica_values(g, p, rounds, where);
            for (int i = 0; i < n; i++) *where[i] = buf[i];
            g->procs++;
        }
        free(where), free(buf);
        replica_stop(&rep[p]);
        if (!ok) { /* its values are lost: its rounds run again here */
            fprintf(stderr, "%s: replica %d failed; its rounds run in this process\n", x->name, p + 1);
            for (int k = 0; k < rounds; k++) {
                run_round(g, p, k, rounds, &probe, aa, &sc);
                g->round_proc[p * rounds + k] = 0;
            }
        }
    }
    signal(SIGPIPE, old_pipe);
    free(sc.hits), free(sc.occ);
    g->steal = cpu > 0 ? steal / cpu : 0;
    x->steal_ticks += steal, x->cpu_ticks += cpu;
    x->procs_used = g->procs > x->procs_used ? g->procs : x->procs_used;
    for (int c = 0; c < g->count; c++)
        for (int i = 0; i < 4; i++)
            if (g->cfg[c].ok && g->cfg[c].set[i].have) g->cfg[c].set[i].n = total;
    g->rounds = total, g->per_proc = rounds;
    for (int c = 0; c < g->count; c++) {
        if (!g->cfg[c].ok) continue;
        if (!x->rounds_hi || total < x->rounds_lo) x->rounds_lo = total;
        if (total > x->rounds_hi) x->rounds_hi = total;
    }
    for (int c = 0; c < g->count; c++)
        for (int i = 0; i < 4; i++)
            if (g->cfg[c].ok && g->cfg[c].set[i].have)
                exp_est_of_procs(g->cfg[c].set[i].samples, g->round_proc, total, &g->cfg[c].set[i].ms);
    if (g->probe_threads > 1)
        exp_est_ratio_procs(g->probe_samples[0], g->probe_samples[1], g->round_proc, total, &g->probe);
    int ids[16];
    for (int p = 0; p < 16; p++) ids[p] = p;
    for (int c = 0; c < g->count; c++)
        if (g->cfg[c].ok && g->cfg[c].build_procs)
            exp_est_of_procs(g->cfg[c].build_samples, ids, procs, &g->cfg[c].build_ms);
    if (x->ref_state == 1) {
        exp_est_of_procs(g->ref_samples, g->round_proc, total, &g->ref);
        proc_mean_range(g->ref_samples, g->round_proc, total, &g->ref_lo, &g->ref_hi);
        exp_ref_note(x, g->ref_samples, total);
    }
    /* The floor: configuration 0's systematic offset from itself, the A/A
     * ratio's estimate (issue 52: the A/A interval's width is the noise
     * every comparison's interval already holds, measured the same way; a
     * floor from its ends made ties of differences whose intervals exclude
     * 1). */
    g->floor = 0.05;
    if (aa && total >= 3) {
        double a[EXP_MAX_SAMPLES], b[EXP_MAX_SAMPLES];
        int n = exp_group_round_ms(g, 0, g->mask, a);
        for (int r = 0; r < n; r++) {
            b[r] = 0;
            for (int i = 0; i < 4; i++)
                if (g->cfg[0].set[i].have) b[r] += g->aa_samples[i][r];
        }
        exp_est_ratio_procs(a, b, g->round_proc, n, &g->aa);
        g->floor = fmax(fabs(g->aa.median - 1), fabs(1 / g->aa.median - 1));
        if (!(g->floor >= EXP_MIN_FLOOR)) g->floor = EXP_MIN_FLOOR;
    }
    if (!g->duel) exp_note_floor(x, g->floor, g->aa.n >= 3);
}

