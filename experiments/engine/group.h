/*
 * group.h - configurations compared on one scene, measured in interleaved
 * rounds.
 *
 * Every configuration (a spec and a thread count) is built once and traced
 * once counted (the hardware-independent counts) and once uncounted (the
 * warm-up, which also sizes the samples). Then the builds are repeated in
 * rounds A B C A B C ..., and so are the timed traces: a round times one
 * sample of every configuration and ray set, with the order rotated each
 * round, so that the drift of a shared machine falls on every configuration
 * alike and round i of A pairs with round i of B (paired ratios, stats.h).
 * A sample is the mean of enough back-to-back passes to last
 * x->sample_ms; a configuration gets x->repeats rounds, fewer when its
 * passes are slow (x->set_budget_ms of timed work per ray set, at least one).
 *
 * Replication (issue 52): the process is the unit. Every group runs in
 * x->procs processes (8: this one and 7 replicas, forked processes that
 * build every configuration again and copy the rays, so that structures
 * and rays lie in their own fresh memory; the code is the parent's).
 * The replicas are forked together after the configurations are added and
 * take turns with this process, one process-round at a time (never two at
 * once: they never compete for the cores): round k of processes 0..7,
 * then round k + 1 of processes 7..0, ..., so that the processes are
 * interleaved in time and a drift of the machine falls on all of them.
 * Each process times x->proc_rounds (2) paired rounds of every
 * configuration, the order of the slots rotated per process and reversed
 * in its second round (A B C, then C B A). Sample r belongs to process
 * round_proc[r]; every estimate is the mean over processes of each
 * process's log time (or log ratio; the mean of its rounds, their median
 * from 3 rounds on: stats.c) with the t-interval over
 * processes (stats.h). A structure whose build took more than
 * EXP_REPLICA_REBUILD_MS is not built again: the replica times the
 * parent's copy, which fork hands it.
 *
 * Shorter processes, not more time (issue 52): a sample lasts
 * x->sample_ms (passes batched) but never more than 2 x sample_ms nor
 * the set budget over the samples (10 ms at the full budget, 2 ms at the
 * quick one): a set whose slowest configuration passes slower than that is
 * timed on a fixed share of its rays for every configuration of the group
 * (blocks of 64 consecutive rays, 8x8 tiles, spread evenly over the set;
 * at least 16 blocks), and the samples are scaled to a full pass (the
 * counts are always the full pass's). The scale is measured, not the ray
 * count ratio: the share's tiles may be cheaper or dearer than the set's
 * mean (sky against mesh), which made absolute ns per ray of two groups
 * differ by up to 1.77x on one scene; the group's fastest configuration
 * times alternate full and share passes (SCALE_PASSES each, medians) and
 * their ratio scales every configuration, so that ratios within the group
 * are untouched and absolute numbers are full-pass numbers.
 *
 * Builds (time_builds): a configuration whose build fits the build budget
 * x procs is built in every process after each of its odd rounds (once
 * with 2 rounds per process, twice with 4; each time twice over, A B A B,
 * in a group that asks for it (build_twice) where the build fits the
 * budget twice: build_procs 2), its sample the fastest
 * of them (build_samples[p], build_procs >= 1: the build time's interval is
 * over processes too; a slow spell of the machine, 0.2-1 s, covers a
 * whole build and only adds time); a slower one is built in interleaved
 * rounds in this process before the replicas start, as many as the budget
 * allows.
 *
 * The reference kernel (harness.h) is one more slot of every round: its
 * times give the group's machine factor (ref) and its stray (the process
 * means' max / min - 1); steal time is read from /proc/stat around every
 * round.
 *
 * The A/A control: configuration 0 is timed twice per round, in two slots;
 * the paired ratio of the two is what an identical configuration differs
 * by here and now, and its interval gives the group's noise floor.
 *
 * The thread probe, when asked for (thread_probe) and a configuration runs
 * on more threads than one: work that touches no memory (independent
 * multiply-adds that fill a core's floating-point units) timed on 1 thread
 * and on that many threads, in one more
 * slot of the same rotation. Its paired ratio is what the machine gave
 * those threads during these rounds: a kernel that scales less than 1.9x
 * on a machine whose probe also stays under it says nothing about the
 * kernel. (A kernel can scale past the probe: two cores also bring two
 * caches.)
 *
 * Configurations that mean nothing are left out with their reason, never
 * measured into rows: a spec that does not parse or build in this build,
 * the same structure as an earlier configuration (equal build statistics
 * and equal counts on every ray set), or a collapsed one (a first pass
 * longer than collapse_ms).
 */
#ifndef EXP_GROUP_H
#define EXP_GROUP_H

#include "harness.h"

typedef struct {
    int have;                 /* the set was traced */
    size_t rays;
    accel_counters counters;  /* totals of the counted pass */
    double pass_ms;           /* one uncounted pass (the warm-up) */
    int batch;                /* passes per timed sample */
    double samples[EXP_MAX_SAMPLES]; /* ms per pass, round by round */
    int n;
    exp_est ms;               /* ms per pass */
    uint32_t *ray_steps, *ray_prims; /* per ray: the primary set, with per_ray */
} exp_trace;

typedef struct {
    char spec[256];
    int threads;
    const accel_kind *kind;
    void *accel;
    accel_build_stats build;
    double build_samples[EXP_MAX_SAMPLES];
    exp_est build_ms;
    int ok;        /* measured: belongs in the tables */
    int left;      /* EXP_LEFT_* when left out */
    char why[640]; /* the reason it was left out */
    int same_as;   /* the configuration with the same structure, or -1 */
    int want;      /* timed rounds */
    double counted_ms; /* the longest counted pass (a collapsed configuration's only time) */
    int build_procs;   /* build_samples[p] is process p's (fastest) build, else rounds here;
                          2: built twice over after each odd round */
    exp_trace set[4]; /* indexed by exp_set_index */
} exp_cfg;

typedef struct {
    exp_ctx *x;
    const accel_scene *s;
    const bench_sets *sets;
    int mask;
    exp_cfg *cfg;
    int count, cap;
    /* Options (set before the first exp_group_add). */
    int control;        /* A/A control of configuration 0 (default 1) */
    int per_ray;        /* keep per-ray steps and tests of the primary set */
    int time_builds;    /* time builds in interleaved rounds (default 1) */
    int build_twice;    /* builds that fit the budget twice are built twice over after each
                           odd round (build_procs 2; default 0: once) */
    double collapse_ms; /* leave out a configuration whose first pass is longer (0: never) */
    int keep_same;      /* measure configurations of the same structure too (a control whose
                           difference the counts cannot show, e.g. instanced:world=flat) */
    int add_mask;       /* sets of the next exp_group_add (0: every set of mask) */
    int proc_rounds;    /* rounds per process (0: the experiment's, 2): 4 gives each half of a
                           best chosen and judged on half the rounds 2 rounds per process */
    int thread_probe;   /* time the thread probe in the rounds (default 0) */
    int duel;           /* a decider pass (exp_group_duel): no A/A floor of its own */
    int want_procs;     /* processes (0: x->procs; at most 16) */
    /* Results of exp_group_run. */
    double aa_samples[4][EXP_MAX_SAMPLES];
    exp_est aa;         /* configuration 0 against itself: paired ratio over the mask */
    int probe_threads;  /* the most threads of a configuration; the probe runs when > 1 */
    double probe_samples[2][EXP_MAX_SAMPLES]; /* ms of the probe on 1 and on probe_threads */
    exp_est probe;      /* time(1 thread) / time(probe_threads), paired per round (n 0: none) */
    double floor;       /* the noise floor of this group, relative */
    int rounds;
    int per_proc;       /* rounds per process (round r is round r % per_proc of process r / per_proc) */
    /* Issue 52: a "best" is chosen on half the rounds and judged on the
     * other half. While half is 1 every estimate of the group (times,
     * speed-ups, exp_group_best) reads only each process's even rounds, the
     * choosing half; while 2 only the odd ones, the judging half; 0 (the
     * default) every round. Each half keeps every process (2 rounds per
     * process: one each), so its intervals are still over processes. */
    int half;
    int procs;          /* processes the rounds ran in (the replicas that returned, plus this one) */
    int round_proc[EXP_MAX_SAMPLES]; /* the process of each round (0: this one) */
    rays_set sub[4];    /* the timed share of each set (count 0: the whole set) */
    double sub_scale[4]; /* full-pass ms over share-pass ms, measured (0: the ray count ratio) */
    double ref_samples[EXP_MAX_SAMPLES]; /* the reference kernel, ns per ray, per round */
    exp_est ref;        /* the reference over the processes (n 0: none) */
    double ref_lo, ref_hi; /* the fastest and the slowest process's mean reference, ns per ray
                              (its stray: ref_hi / ref_lo - 1) */
    double steal;       /* steal time over the rounds, a fraction of the CPU time */
} exp_group;

/* The smallest noise floor the study uses: differences under 1% are never findings. */
#define EXP_MIN_FLOOR 0.01

void exp_group_init(exp_group *g, exp_ctx *x, const accel_scene *s, const bench_sets *sets,
                    int mask);
/* Adds, builds and checks a configuration (threads <= 0: x->threads).
 * Returns its index; cfg[i].ok says whether it will be measured. */
int exp_group_add(exp_group *g, const char *spec, int threads);
/* The interleaved build and trace rounds, then the estimates and the floor
 * (recorded for the section with exp_note_floor). */
void exp_group_run(exp_group *g);
/* Writes "Left out: ..." for the configurations left out (nothing if none). */
void exp_group_note(exp_group *g);
void exp_group_free(exp_group *g);

/* Per-round ms of the sets in mask, summed, over the rounds of the
 * group's half (half); returns their number. */
int exp_group_round_ms(const exp_group *g, int c, int mask, double *out);
/* The process of each round exp_group_round_ms returns (buf: room for
 * EXP_MAX_SAMPLES, used when a half is set). */
const int *exp_group_procs(const exp_group *g, int *buf);
/* Rays of the sets in mask. */
size_t exp_group_rays(const exp_group *g, int c, int mask);
/* ns per ray over the sets in mask, and Mrays/s. */
exp_est exp_group_ns(const exp_group *g, int c, int mask);
exp_est exp_group_mrays(const exp_group *g, int c, int mask);
/* Speed of c relative to base over the sets in mask: time(base) / time(c)
 * per round (> 1: c is faster), paired. */
exp_est exp_group_speedup(const exp_group *g, int base, int c, int mask);
/* The same with its interval at `level` (a verdict over m comparisons:
 * exp_tally_level). */
exp_est exp_group_speedup_level(const exp_group *g, int base, int c, int mask, double level);
/* ns per ray with its interval at `level`. */
exp_est exp_group_ns_level(const exp_group *g, int c, int mask, double level);
/* Counts per ray over the sets in mask. */
double exp_group_steps(const exp_group *g, int c, int mask);
double exp_group_prims(const exp_group *g, int c, int mask);
double exp_group_boxes(const exp_group *g, int c, int mask);
/* The comparisons table: its header, then one row per comparison
 * "| `c` against `base` | time +x% [lo, hi] | slower / faster / a tie |".
 * exp_group_compare puts the change in buf (for findings that quote it,
 * with " (a tie)" after it when it is one) and returns exp_ratio_cmp of
 * the time ratio (0: a tie). */
void exp_group_compare_head(exp_group *g);
int exp_group_compare(exp_group *g, int c, int base, int mask, char *buf, size_t n);
/* The build time ratio a / b at `level`: over processes when both were
 * built in every process (group.h: each process's fastest), else over this
 * process's build rounds. */
exp_est exp_group_build_ratio_level(const exp_group *g, int a, int b, double level);
/* The same for build times (paired interleaved build rounds). */
int exp_group_compare_build(exp_group *g, int c, int base, char *buf, size_t n);
/* The fastest configuration over mask among those of [lo, hi) whose spec
 * starts with prefix ("" for all): the lowest median time, then the one
 * with the lowest paired ratio against it, so that "the best" never loses a
 * paired comparison to another candidate. -1 when none was measured.
 * The caller's half applies: set half to 1 to choose on the choosing half. */
int exp_group_best(const exp_group *g, int mask, int lo, int hi, const char *prefix);
/* A decider with an absolute threshold (fps, Mrays/s, Hz: rate = 1; ms:
 * rate = 0) judged on the number normalized to the stated reference rate
 * (harness.h, EXP_REF_NS_PER_RAY, exp_ref_normalize): the value times the
 * group's reference factor (ref / stated) for a rate, divided by it for a
 * time, so that a machine running the reference 1.8x slower does not move
 * the verdict; the interval's ends by the fastest and the slowest process's
 * factor. Returns exp_judge of the normalized decider (*d is normalized in
 * place), or EXP_UNTESTABLE with the reason in why when the reference was
 * not measured, or strayed by more than EXP_REF_STRAY over the group's
 * processes and the word straddles. why always gets a note of the factor. */
const char *exp_group_absolute(const exp_group *g, exp_decider *d, int rate, char *why, size_t n);
/* Internal to group.c and group_run.c: one pass of c over the rays r of
 * set bit (counted when cnt is given), and scratch results for the
 * largest set of g (exits on no memory). */
void exp_group_pass(const exp_cfg *c, int bit, const rays_set *r, accel_hit *hits, uint8_t *occ,
                    accel_counters *cnt);
typedef struct {
    accel_hit *hits;
    uint8_t *occ;
} exp_scratch;
exp_scratch exp_group_scratch(const exp_group *g);
/* The decider pass (issue 52). A verdict that rests on one comparison
 * of two configurations of a group (a best against a pick, a builder
 * against another) is judged on the pair timed again alone: d gets
 * copies of configurations a and b (d's 0 and 1; the structures stay
 * g's), timed on the sets of mask in x->procs fresh processes of
 * EXP_DUEL_ROUNDS rounds each, A B then B A, and, with builds, built after
 * every odd round twice over (A B A B), each process's fastest kept (a
 * budget of EXP_DUEL_BUILD_MS per process) in EXP_DUEL_BUILD_PROCS
 * processes: a build's time depends on where its process's allocator
 * puts it (armadillo's SAH build ran 39.5-42.9 ms, the fastest of 6 in
 * each of 8 processes, its ratio to the median split's 2.02-2.17), so a
 * build ratio needs more processes than a trace ratio. In the group's rounds the
 * two were timed up to a dozen configurations apart, and their per-round
 * ratio scattered from 0.79 to 1.39 on one scene (slivers, the model's
 * pick against the best lambda); back to back the ratio is the two
 * structures', not the machine's minute. The choice (which best, which
 * pick) is made on the group's rounds and judged on the duel's, so the
 * judging rounds are never the choosing ones. Free d with
 * exp_group_duel_free (never exp_group_free). */
#define EXP_DUEL_ROUNDS 6
#define EXP_DUEL_ROUNDS_QUICK 2
#define EXP_DUEL_BUILD_MS 1000.0
#define EXP_DUEL_BUILD_PROCS 16
void exp_group_duel(const exp_group *g, int a, int b, int mask, int builds, exp_group *d);
void exp_group_duel_free(exp_group *d);
/* Index of the configuration named spec, or -1. */
int exp_group_find(const exp_group *g, const char *spec);

#endif
