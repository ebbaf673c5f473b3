/*
 * harness.h - the shared frame of every experiment binary.
 *
 * An experiment answers one question. It parses the common options (one
 * table in harness.c drives parsing and --help: --quick, --out DIR,
 * --threads N, --repeat N, --size N, --rt-size WxH, --scene SPEC..., --mesh FILE...,
 * --accel SPEC..., --only-accels, --kinds LIST, --heat-scale SPEC, --quiet,
 * --help), measures configurations in interleaved rounds (group.h), writes
 * its raw numbers to DIR/<name>.csv (RFC 4180, one schema: the first
 * record is the header), one Markdown section to DIR/<name>.md (the
 * question, the lecture's words, tables of medians with their 95%
 * intervals and the hardware-independent counts beside every time,
 * findings computed from the numbers, the section's noise floor), its
 * verdicts to DIR/<name>.verdicts.csv (claim, verdict, evidence, scenes,
 * section: claims.h) and what it left out to DIR/<name>.leftout.csv.
 * experiments/report.sh runs them; bin/mkreport assembles REPORT.md.
 *
 * Exit statuses are those of cli/cli.h: 2 for a bad option, 3 for a scene
 * that cannot be made, 4 when a counted pass broke a traversal invariant or
 * a CSV record did not fit the header (the run goes on; exp_finish returns 4).
 */
#ifndef EXP_HARNESS_H
#define EXP_HARNESS_H

#include <stdio.h>

#include "measure/bench.h"
#include "measure/csv.h"
#include "image/image.h"
#include "scene/scene.h"
#include "claims.h"
#include "stats.h"

#define EXP_MAX_MESHES 16
#define EXP_MAX_ACCELS 32

/* Text that grows as it is written: findings are never cut off. */
typedef struct {
    char *s;
    size_t len, cap;
} exp_text;
void exp_text_add(exp_text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The text so far ("" when empty). */
const char *exp_text_str(const exp_text *t);
void exp_text_free(exp_text *t);

/* Why a configuration was left out (counted per section for the report). */
enum {
    EXP_LEFT_NONE,
    EXP_LEFT_IDENTICAL, /* the same structure as another configuration */
    EXP_LEFT_COLLAPSED, /* a structure that degenerates on this scene (seconds per pass) */
    EXP_LEFT_UNPARSED,  /* a spec this build does not know (a kind or parameter not merged yet) */
    EXP_LEFT_POINTLESS, /* means nothing here (e.g. brute force at minutes per pass) */
    EXP_LEFT_FAILED,    /* the build failed (e.g. over its memory limit) */
    EXP_LEFT_KINDS
};

/* Builds longer than this are not repeated in the replicas (group.h): 7
 * replicas rebuild at most 7 x 25 ms per configuration, less than the 2 x
 * 100 ms of the 3 processes before issue 52. */
#define EXP_REPLICA_REBUILD_MS 25.0
/* Processes and rounds per process of every group (issue 52: the process
 * is the unit of replication; 8 processes give df = 7). */
#define EXP_PROCS 8
/* --quick (the tests' smoke report): 6 processes, df = 5, the fewest whose
 * intervals are still printed at 95% (claims.h); a quarter of the quick
 * rounds' time saved in `make test`. */
#define EXP_PROCS_QUICK 6
#define EXP_PROC_ROUNDS 2

typedef struct {
    const char *name;     /* e.g. "exp_sah" */
    int quick;            /* smoke-test budget: tiny scenes, few repeats */
    const char *out_dir;  /* default experiments/out */
    int threads;          /* threads of every build, trace and reference (default 1) */
    int threads_given;    /* --threads was on the command line */
    int repeats;          /* timed passes per measurement */
    int procs;            /* processes the timed rounds run in, interleaved (group.h; default 8) */
    int proc_rounds;      /* rounds of every configuration in each process (default 2) */
    int procs_used;       /* the most that returned rounds in one group of this section */
    int size;             /* primary image size (square) */
    int rt_size[2];       /* the lecture's real-time image (default 800x600) */
    const char *accels[EXP_MAX_ACCELS]; /* --accel: specs added to the experiment's list */
    int accel_count;
    int only_accels;      /* --only-accels: the --accel specs replace the list */
    const char *kinds;    /* --kinds a,b: only these kinds (NULL: all) */
    double sample_ms;     /* one timed sample lasts at least this (passes are batched) */
    double set_budget_ms; /* timed work per configuration and ray set */
    double build_budget_ms; /* interleaved builds per configuration */
    const char *scenes[EXP_MAX_MESHES]; /* --scene: exactly these scenes (specs, meshes, .scene files) */
    int scene_count;
    const char *meshes[EXP_MAX_MESHES]; /* extra mesh files (default: the meshes in ../shared/scenes) */
    int mesh_count;
    int meshes_given;     /* the meshes came from --mesh (not the default folder) */
    int no_meshes, quiet, help;
    int check;            /* --check: the options and limits only (exp_limits exits 0) */
    int limits_checked;   /* exp_limits ran (exp_header refuses --check without it) */
    double progress_after; /* seconds */
    image_heat_scale heat_scale; /* --heat-scale: colours of exp_heatmap images */
    FILE *md;
    csv_file csv;
    bench_progress *progress; /* NULL with --quiet */
    int status;           /* exit status exp_finish returns (CLI_EXIT_*) */
    double t_start;
    double load_start[3];
    double others_start;  /* other runnable threads at the start (exp_others_running) */
    csv_file verdicts;    /* DIR/<name>.verdicts.csv */
    int verdict_count;
    int left[EXP_LEFT_KINDS]; /* configurations left out, by reason */
    exp_text unparsed;    /* specs not in this build, one per line */
    int rounds_lo, rounds_hi; /* timed rounds per configuration over the section */
    double *floors;       /* noise floors of the section's groups */
    int floor_count, floors_measured;
    int images[4][2], image_count; /* ray-set sizes exp_sets_wh made (the footer names them) */
    /* The reference kernel (reference.c), timed in every round of every group. */
    int ref_state;        /* 0 not made yet, 1 ready, -1 could not be made */
    double thread_eff;    /* exp_thread_gate's probe efficiency (0: not measured yet) */
    int thread_eff_n;     /* the threads it was measured on */
    const void *ref_kind; /* const accel_kind * */
    void *ref_accel;
    accel_scene ref_scene;
    bench_sets ref_sets;
    double *ref_ms;       /* every round's reference time in this section */
    int ref_n, ref_cap;
    double steal_ticks, cpu_ticks; /* /proc/stat over the section's timed rounds */
} exp_ctx;

/* Parses the common options; `extra_help` is printed under --help. Exits on
 * --help (0) or a bad option (2): experiments are programs, not library. */
void exp_init(exp_ctx *x, int argc, char **argv, const char *name, const char *question,
              const char *extra_help);
/* Closes files, prints the elapsed time. Returns the exit status: 0, or 4
 * after a broken invariant or a refused CSV record. */
int exp_finish(exp_ctx *x);

/* One CSV record: commas of fmt separate fields, %s values are quoted as
 * RFC 4180 needs; the first call writes the header. */
void exp_csv(exp_ctx *x, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* "median (min-max)" of a timing, with `decimals` decimals, into buf. */
const char *exp_fmt_timing(char *buf, size_t n, const accel_timing *t, int decimals);
void exp_md(exp_ctx *x, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The section's head: "## title (name)", the question, the lecture's (or
 * the user's) words, and the place where the report puts the verdicts. */
void exp_header(exp_ctx *x, const char *title, const char *words, const char *question_fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* A Markdown table header: cols separated by '|'. */
void exp_md_table(exp_ctx *x, const char *cols);
/* The scenes of an experiment's scene loop: exactly the --scene ones when
 * given (into list, replacing the experiment's own *n), else list as it is.
 * `max` is the loop's room: more --scene than that is an error (exit 2)
 * naming the limit, never a silent drop. Returns the new count. */
int exp_scene_list(exp_ctx *x, const char **list, int n, int max);
/* The experiment's limits, declared right after exp_init and before any
 * work: at most max_scenes --scene (0: the experiment does not measure
 * --scene; exp_scenes_unused says so) and max_meshes --mesh; more is an
 * error (exit 2) naming the limit. With --check, exits 0 here: make report
 * checks every experiment so before the first one starts. */
void exp_limits(exp_ctx *x, int max_scenes, int max_meshes);
/* For an experiment whose question fixes its own scenes: with --scene, a
 * line on stderr and in the section says that they are not measured here. */
void exp_scenes_unused(exp_ctx *x, const char *why);
/* An experiment that measures the first `max` meshes: more --mesh than that
 * is an error (exit 2) that says so, never a silent drop. */
void exp_mesh_room(exp_ctx *x, int max);
/* Loads a scene spec or dies with its error (experiments stop on bad
 * input): exit 3, also for a scene with nothing to hit. */
void exp_scene(exp_ctx *x, const char *spec, accel_scene *s);
/* The same for a scene that may not exist in this build (a generator not
 * merged yet): 0, or nonzero with the reason in why. */
int exp_scene_try(exp_ctx *x, const char *spec, accel_scene *s, char *why, size_t why_n);
/* A scene's subsection: exp_scene, its ray sets of mask (exp_sets; with rt
 * at x->rt_size with one AO sample per hit, as exp_sets_wh; rt > 1: one in
 * rt of that image's 8x8 tiles, exp_sets_tiles, said under the heading),
 * and the heading "### name (N primitives)". */
void exp_scene_section(exp_ctx *x, const char *spec, accel_scene *s, int mask, int rt,
                       bench_sets *sets);
/* Records a ray image size this section used (exp_sets_wh does it); the
 * footer names exactly these (issue 39: footers that are true). */
void exp_note_image(exp_ctx *x, int w, int h);
/* Builds the standard ray sets (mask of bench_set_bit) for s at x->size. */
void exp_sets(exp_ctx *x, const accel_scene *s, int mask, bench_sets *out);
/* The lecture's image at a smaller cost (issue 38: every lecture claim
 * measured at 800x600): the ray sets of x->rt_size (one AO ray per hit),
 * keeping the rays of one in `stride` of its 8x8 pixel tiles (tile index
 * mod stride == 0), so that rays keep the density and coherence of the
 * 800x600 image at the work of a smaller one. stride <= 0: the stride that
 * leaves about x->size^2 primary rays. Returns the stride used. */
int exp_sets_tiles(exp_ctx *x, const accel_scene *s, int mask, int stride, bench_sets *out);
/* The same at w x h with ao_samples ambient occlusion rays per hit. */
void exp_sets_wh(exp_ctx *x, const accel_scene *s, int mask, int w, int h, int ao_samples,
                 bench_sets *out);

/* A list of specs for one question: the experiment's defaults (or only the
 * --accel specs with --only-accels) plus the --accel specs whose kind is in
 * `accept` (a comma list of kind names; NULL: every kind), without the
 * kinds --kinds leaves out (--kinds and --accel are checked in full by
 * exp_init: a typo is exit 2). Default specs this build cannot parse stay in the list:
 * exp_group_add leaves them out with the reason, so the report works before
 * and after the kinds and parameters it names have landed. */
typedef struct {
    const char **spec;
    int count;
} exp_list;
void exp_list_make(exp_ctx *x, const char *const *defaults, int n, const char *accept,
                   exp_list *out);
void exp_list_free(exp_list *l);
/* Whether --kinds lets kind `name` run (always 1 without --kinds). */
int exp_kind_wanted(const exp_ctx *x, const char *name);

/* One verdict on a claim of claims.h: verdict is one of claims.h's labels; evidence gives the deciding numbers with
 * their intervals; scenes names where they were measured. A bad claim id or
 * label is an internal error (exit 4). */
void exp_verdict(exp_ctx *x, const char *claim, const char *verdict, const char *scenes,
                 const char *evidence_fmt, ...) __attribute__((format(printf, 5, 6)));
/* exp_verdict with its deciding number: the verdicts CSV gets the columns
 * deciding,value,lo,hi,threshold,sense,margin,n (exp_verdict leaves them
 * empty), which mkreport shows in the summary. verdict is usually
 * exp_judge(d); a compound claim passes EXP_PARTLY and says which part
 * holds in the evidence. */
void exp_verdict_num(exp_ctx *x, const char *claim, const char *verdict, const exp_decider *d,
                     const char *scenes, const char *evidence_fmt, ...)
    __attribute__((format(printf, 6, 7)));
/* The verdict for a claim that comes out as "no difference": refuted when
 * the noise floor could have shown the effect (floor <= EXP_NOISY),
 * otherwise not testable (the run was too noisy to tell). */
#define EXP_NOISY 0.25
const char *exp_no_difference(double floor);
/* A decider from an estimate: value median, interval [lo, hi], n. */
/* 1 in how many of x->rt_size's 8x8 tiles give as many rays as an
 * x->size square image (at least 1): the sections that sample the 800x600
 * image at the density of their former 128x128 one. */
int exp_tiles_stride(const exp_ctx *x);
exp_decider exp_decider_of(const char *what, const exp_est *e, double threshold, int sense);
/* For an absolute verdict that says "too slow" (never a ratio of two
 * configurations timed in the same rounds): on a busy machine (exp_busy) a
 * refutation is not testable here, since the measured times are upper
 * bounds of a quiet machine's. */
const char *exp_slow_verdict(const exp_ctx *x, const char *verdict);
/* Issue 52: every verdict on more than one thread is gated by the thread
 * probe as the threads row is. The probe (group_run.c: work that touches
 * no memory) is timed on 1 and on `threads` threads, paired, 9 times, once
 * per section; below EXP_PROBE_LINEAR efficiency the machine held the
 * threads down, so a verdict on `threads` threads may confirm a claim it
 * meets anyway but not refute one: a word other than confirmed becomes
 * not testable here. why gets the probe's number (empty on 1 thread).
 * Returns the gated word. */
#define EXP_PROBE_LINEAR 0.90
const char *exp_thread_gate(exp_ctx *x, int threads, const char *verdict, char *why, size_t n);
/* 1 when other threads competed for the cores at the start (on average half
 * a runnable thread or more besides this experiment, or unknown): a
 * 2-thread measurement has no free core, a "too slow" verdict is an upper
 * bound. */
int exp_busy(const exp_ctx *x);
/* 1 the first time spec is reported as not in this build in this section. */
int exp_note_unparsed(exp_ctx *x, const char *spec);
/* Counts a configuration left out (exp_group does it for its own). */
void exp_note_left(exp_ctx *x, int why);
/* Records a group's noise floor (measured: from an A/A control). */
void exp_note_floor(exp_ctx *x, double floor, int measured);
/* The section's noise floor so far: the largest of its groups' (EXP_MIN_FLOOR... 5% when none). */
double exp_section_floor(const exp_ctx *x);
/* The double-precision reference with x->threads, shown as a progress phase. */
void exp_reference(exp_ctx *x, const accel_scene *s, const accel_ray *rays, accel_hit *hits,
                   size_t count);
/* The reference kernel (reference.c, issue 52): brute force over the 250
 * triangles of soup:tris=250, 1024 primary rays of a 32x32 image, one
 * thread, a few ms: a fixed piece of work timed beside the configurations
 * in every round, so that each section says what the machine gave it. Its
 * stated rate EXP_REF_NS_PER_RAY and the stray limit EXP_REF_STRAY are in
 * claims.h, beside the rule that uses them (exp_ref_normalize).
 * exp_ref_ready makes it once per section (0 when ready). */
int exp_ref_ready(exp_ctx *x);
/* The reference rays traced 3 times: the median ns per ray (0 when not ready). */
double exp_ref_time(const exp_ctx *x);
/* Records reference times (ns per ray) of the section's rounds. */
void exp_ref_note(exp_ctx *x, const double *ns, int n);
/* Cumulative steal and total CPU ticks of /proc/stat (0 when unreadable). */
int exp_cpu_ticks(double *steal, double *total);
/* The footer line: the reference's spread over the section and the steal
 * time of its rounds (nothing when no round ran). */
void exp_ref_footer(exp_ctx *x);
/* exp_ref_normalize: claims.h (the one normalization of an absolute decider). */
/* exp_group_absolute (group.h) for timings of one process (n reference
 * times, ns per ray, taken beside the timed work): the decider normalized
 * by exp_ref_normalize over the reference's 10th to 90th percentile;
 * "not testable here" when no reference was timed. */
const char *exp_ref_absolute(exp_ctx *x, const double *ns, int n, exp_decider *d, int rate,
                             char *why, size_t why_n);
/* Frees the reference kernel and the section's record. */
void exp_ref_free(exp_ctx *x);

/* Records an internal error (printed; exp_finish returns 4). */
void exp_internal(exp_ctx *x, const char *what, const accel_error *err);

static inline int exp_set_index(int bit)
{
    return bit == BENCH_PRIMARY ? 0 : bit == BENCH_SHADOW ? 1 : bit == BENCH_DIFFUSE ? 2 : 3;
}

/* Per-ray averages from a measurement's counters. */
static inline double exp_per_ray(uint64_t v, const bench_result *r)
{
    return r->rays ? (double)v / (double)r->rays : 0.0;
}

/* Writes the svg_plot (svg.h) `plot` to DIR/<name>.svg and places it in the
 * section with its caption (mkreport links it); frees the plot. */
void exp_svg(exp_ctx *x, void *plot, const char *name, const char *caption);

/* Traces the primary rays of `sets` with spec on s in a counted pass and
 * writes DIR/<image_name>.png: steps (what='s') or primitive tests ('p')
 * per pixel with a colour scale; adds the image to the Markdown section.
 * Returns 0 or nonzero (reason in why). */
int exp_heatmap(exp_ctx *x, const char *spec, const accel_scene *s, const bench_sets *sets,
                char what, const char *image_name, const char *caption, char *why, size_t why_n);
/* The same for each of `count` specs on one colour scale (a fixed
 * --heat-scale max, else the 99.5th percentile of all the images'
 * pixels; brighter ones saturate), so the row compares colour for colour: DIR/<prefix>_<i>.png. A spec that
 * cannot be built or traced is skipped with its reason in the section.
 * Returns the number of images written. */
int exp_heatmaps_shared(exp_ctx *x, const char *const *specs, int count, const accel_scene *s,
                        const bench_sets *sets, char what, const char *prefix);

#endif
