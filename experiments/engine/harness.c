/*
 * harness.c - options, output files and measurement helpers shared by every
 * experiment binary (see harness.h).
 */
#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include "harness.h"
#include "machine.h"
#include "svg.h"
#include "cli/cli.h"
#include "image/image.h"
#include "cli/spec_check.h"

static int opt_mesh(const cli_option *o, void *field, char **v, accel_error *err)
{
    exp_ctx *x = (exp_ctx *)((char *)field - offsetof(exp_ctx, meshes));
    if (x->mesh_count == EXP_MAX_MESHES)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: at most %d meshes", o->name, EXP_MAX_MESHES);
    int rc = scene_spec_check(v[0], err);
    if (rc) return rc;
    x->meshes[x->mesh_count++] = v[0];
    return 0;
}

/* --kinds: every name a registered kind, none empty. */
static int opt_kinds(const cli_option *o, void *field, char **v, accel_error *err)
{
    for (const char *p = v[0];; p++) {
        size_t n = strcspn(p, ",");
        char name[64];
        snprintf(name, sizeof name, "%.*s", (int)n, p);
        if (n == 0 || n >= sizeof name || !accel_find_kind(name)) {
            char names[400] = "";
            for (size_t i = 0; i < accel_kind_count; i++) {
                size_t len = strlen(names);
                snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "",
                         accel_kinds[i]->name);
            }
            return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: unknown kind '%s'; registered: %s",
                              o->name, v[0], name, names);
        }
        p += n;
        if (!*p) break;
    }
    return cli_string(o, field, v, err);
}

static int opt_scene(const cli_option *o, void *field, char **v, accel_error *err)
{
    exp_ctx *x = (exp_ctx *)((char *)field - offsetof(exp_ctx, scenes));
    if (x->scene_count == EXP_MAX_MESHES)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: at most %d scenes", o->name, EXP_MAX_MESHES);
    int rc = scene_spec_check(v[0], err);
    if (rc) return rc;
    x->scenes[x->scene_count++] = v[0];
    return 0;
}

static int opt_threads(const cli_option *o, void *field, char **v, accel_error *err)
{
    exp_ctx *x = (exp_ctx *)((char *)field - offsetof(exp_ctx, threads));
    x->threads_given = 1;
    return cli_int(o, field, v, err);
}

static int opt_accel(const cli_option *o, void *field, char **v, accel_error *err)
{
    exp_ctx *x = (exp_ctx *)((char *)field - offsetof(exp_ctx, accels));
    if (x->accel_count == EXP_MAX_ACCELS)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: at most %d specs", o->name, EXP_MAX_ACCELS);
    /* Checked in full (kind, keys, values): a typo is an error before any
     * work, not a green report without the configuration. */
    int rc = spec_check_accel(o->name, v[0], err);
    if (rc) return rc;
    x->accels[x->accel_count++] = v[0];
    return 0;
}

#define OPT(f) offsetof(exp_ctx, f)
static const cli_option exp_options[] = {
    {"--quick", NULL, "smoke-test budget (tiny scenes, 1 repeat)", cli_flag, OPT(quick), 0, 0},
    {"--out", "DIR", "where <name>.csv and <name>.md go (default experiments/out)", cli_string,
     OPT(out_dir), 0, 0},
    {"--threads", "N", "threads of every build, trace and reference (default 1;\n"
     "exp_threads: the largest count, default every core)", opt_threads, OPT(threads), 1, 256},
    {"--repeat", "N", "interleaved timed rounds per configuration (default 12, quick 3)", cli_int,
     OPT(repeats), 1, EXP_MAX_SAMPLES},
    {"--procs", "N", "spread the timed rounds over N processes: this one and N-1 forked\n"
     "replicas that rebuild every structure in fresh memory, interleaved in time (default 8; 1: no replicas)", cli_int,
     OPT(procs), 1, 16},
    {"--size", "N", "primary image N x N (default 128, quick 64)", cli_int, OPT(size), 8, 8192},
    {"--rt-size", "WxH", "image of the lecture's real-time claims (default 800x600, quick 160x120)",
     cli_size, OPT(rt_size), 8, 8192},
    {"--accel", "SPEC", "add SPEC to the experiment's configurations (repeatable; specs of kinds\n"
     "the experiment does not compare are ignored; an unknown kind, key or value is an error)",
     opt_accel, OPT(accels), 0, 0},
    {"--only-accels", NULL, "the --accel specs replace the experiment's own list", cli_flag,
     OPT(only_accels), 0, 0},
    {"--kinds", "LIST", "only these kinds, e.g. grid,bvh (make report KINDS=...); unknown: an error",
     opt_kinds, OPT(kinds), 0, 0},
    {"--scene", "SPEC|FILE", "measure exactly this scene (repeatable): a built-in spec, a mesh or\n"
     "a .scene file, in place of the experiment's own scenes (make report SCENES=...)",
     opt_scene, OPT(scenes), 0, 0},
    {"--mesh", "FILE", "add a mesh (repeatable; default ../shared/scenes/*.off if present)",
     opt_mesh, OPT(meshes), 0, 0},
    {"--no-meshes", NULL, "no default meshes (the --mesh ones stay)", cli_flag, OPT(no_meshes),
     0, 0},
    {"--check", NULL, "check the options and this experiment's limits on --scene and --mesh,\n"
     "then exit (0: it would run) without any work or output (make report runs\n"
     "every experiment so before the first one starts)", cli_flag, OPT(check), 0, 0},
    CLI_COMMON_ROWS(exp_ctx),
};
#define OPTION_COUNT (sizeof exp_options / sizeof exp_options[0])

static void usage(const exp_ctx *x, const char *question, const char *extra)
{
    printf("usage: %s [options]\n%s\n\n", x->name, question);
    cli_help(stdout, exp_options, OPTION_COUNT);
    printf("%s\n", extra ? extra : "");
    cli_help_exit_codes(stdout);
}

static void find_default_meshes(exp_ctx *x)
{
    static const char *const dirs[] = {"../shared/scenes", "../../shared/scenes"};
    static char paths[EXP_MAX_MESHES][512];
    for (size_t d = 0; d < sizeof dirs / sizeof dirs[0]; d++) {
        DIR *dir = opendir(dirs[d]);
        if (!dir) continue;
        struct dirent *e;
        while ((e = readdir(dir)) && x->mesh_count < EXP_MAX_MESHES) {
            const char *dot = strrchr(e->d_name, '.');
            if (!dot || (strcmp(dot, ".off") && strcmp(dot, ".obj") && strcmp(dot, ".ply")))
                continue;
            snprintf(paths[x->mesh_count], sizeof paths[0], "%s/%s", dirs[d], e->d_name);
            x->meshes[x->mesh_count] = paths[x->mesh_count];
            x->mesh_count++;
        }
        closedir(dir);
        /* Sorted so that reports list meshes in a stable order. */
        for (int i = 1; i < x->mesh_count; i++)
            for (int j = i; j > 0 && strcmp(x->meshes[j - 1], x->meshes[j]) > 0; j--) {
                const char *t = x->meshes[j];
                x->meshes[j] = x->meshes[j - 1];
                x->meshes[j - 1] = t;
            }
        return;
    }
}

void exp_init(exp_ctx *x, int argc, char **argv, const char *name, const char *question,
              const char *extra_help)
{
    memset(x, 0, sizeof *x);
    x->name = name;
    x->out_dir = "experiments/out";
    x->threads = 1;
    x->repeats = -1;
    x->size = -1;
    x->progress_after = BENCH_PROGRESS_AFTER_MS / 1e3;
    accel_error err = {0};
    if (cli_parse(exp_options, OPTION_COUNT, argc, argv, 1, x, &err)) {
        fprintf(stderr, "%s: %s\n", name, err.msg);
        exit(err.code == ACCEL_ERR_IO ? CLI_EXIT_INPUT : CLI_EXIT_USAGE);
    }
    if (x->help) {
        usage(x, question, extra_help);
        exit(CLI_EXIT_OK);
    }
    /* Issue 52: every group times its configurations in 8 processes
     * interleaved in time, 2 paired rounds each (16 samples, df = 7), with
     * samples of 5 ms (10 before: 16 x 5 ms is less than the 10 x 10 ms of
     * issue 38's 10 rounds), and a sample never longer than the set budget
     * over 16: a slower pass is timed on a fixed spread share of its rays
     * (group.h). --repeat is the rounds of the experiments that time
     * outside groups (anim.c, exp_stability). */
    if (x->repeats < 0) x->repeats = x->quick ? 3 : 10;
    if (x->procs <= 0) x->procs = x->quick ? EXP_PROCS_QUICK : EXP_PROCS;
    x->proc_rounds = EXP_PROC_ROUNDS;
    if (x->size < 0) x->size = x->quick ? 64 : 128;
    if (x->rt_size[0] <= 0) x->rt_size[0] = x->quick ? 160 : 800, x->rt_size[1] = x->quick ? 120 : 600;
    x->sample_ms = x->quick ? 1.0 : 5.0;
    x->set_budget_ms = x->quick ? 100.0 : 400.0;
    x->build_budget_ms = x->quick ? 100.0 : 1000.0;
    x->meshes_given = x->mesh_count > 0;
    if (x->quick && x->meshes_given) {
        fprintf(stderr, "%s: --mesh %s: the quick budget measures its own tiny scenes, not the "
                "meshes; --scene %s measures exactly it\n", name, x->meshes[0], x->meshes[0]);
        exit(CLI_EXIT_USAGE);
    }
    if (x->check) return; /* exp_limits exits: no file is written */
    if (!x->no_meshes && !x->mesh_count && !x->quick) find_default_meshes(x);
    mkdir(x->out_dir, 0777);
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.csv", x->out_dir, name);
    FILE *csv = fopen(path, "w");
    snprintf(path, sizeof path, "%s/%s.md", x->out_dir, name);
    x->md = fopen(path, "w");
    snprintf(path, sizeof path, "%s/%s.verdicts.csv", x->out_dir, name);
    FILE *vf = fopen(path, "w");
    if (!csv || !x->md || !vf) {
        fprintf(stderr, "%s: cannot write into %s\n", name, x->out_dir);
        exit(CLI_EXIT_INPUT);
    }
    csv_open(&x->csv, csv);
    csv_open(&x->verdicts, vf);
    csv_row(&x->verdicts, "claim,verdict,evidence,scenes,section,deciding,value,lo,hi,threshold,sense,"
                          "margin,n\n");
    exp_loadavg(x->load_start);
    x->others_start = exp_others_running();
    x->progress = bench_progress_start(x->quiet ? NULL : stderr, name, x->progress_after * 1e3);
    x->t_start = accel_now_ms();
    fprintf(stderr, "%s: %s\n", name, x->quick ? "quick budget" : "full budget");
}

static void write_leftout(exp_ctx *x)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.leftout.csv", x->out_dir, x->name);
    FILE *f = fopen(path, "w");
    if (!f) return;
    csv_file c;
    csv_open(&c, f);
    csv_row(&c, "section,identical,collapsed,not_in_build,pointless,failed\n");
    csv_row(&c, "%s,%d,%d,%d,%d,%d\n", x->name, x->left[EXP_LEFT_IDENTICAL],
            x->left[EXP_LEFT_COLLAPSED], x->left[EXP_LEFT_UNPARSED], x->left[EXP_LEFT_POINTLESS],
            x->left[EXP_LEFT_FAILED]);
    fclose(f);
}

/* DIR/machine.md: the machine and the compiler of this run (report.sh
 * puts it in the report's header; every experiment writes the same). */
static void write_machine(exp_ctx *x)
{
    char path[1024], table[2048];
    snprintf(path, sizeof path, "%s/machine.md", x->out_dir);
    FILE *f = fopen(path, "w");
    if (!f) return;
    exp_machine m;
    exp_machine_read(&m);
    exp_machine_markdown(&m, table, sizeof table);
    fprintf(f, "%s| compiler | %s |\n", table, exp_compiler());
    fclose(f);
}

int exp_finish(exp_ctx *x)
{
    double s = (accel_now_ms() - x->t_start) / 1e3;
    if (x->floor_count) {
        double lo = x->floors[0], hi = x->floors[0];
        for (int i = 1; i < x->floor_count; i++) lo = fmin(lo, x->floors[i]), hi = fmax(hi, x->floors[i]);
        exp_md(x, "\n_Noise floor of this section: %.1f%% (the largest of %d group%s, from %.1f%%; "
                  "%d measured by an A/A control: one configuration timed twice per round). "
                  "Differences within a 95%% interval or under the floor are ties._\n",
               100 * hi, x->floor_count, x->floor_count > 1 ? "s" : "", 100 * lo,
               x->floors_measured);
    }
    double load_end[3];
    exp_loadavg(load_end);
    struct rusage ru;
    double cpu = 0;
    if (getrusage(RUSAGE_SELF, &ru) == 0)
        cpu = (double)ru.ru_utime.tv_sec + ru.ru_utime.tv_usec / 1e6 + (double)ru.ru_stime.tv_sec +
              ru.ru_stime.tv_usec / 1e6;
    char images[96] = "no ray images";
    for (int i = 0, len = 0; i < x->image_count && len < 80; i++)
        len += snprintf(images + len, sizeof images - (size_t)len, "%s%dx%d", i ? (i + 1 == x->image_count ? " and " : ", ") : "images ",
                        x->images[i][0], x->images[i][1]);
    exp_md(x, "\n_%s ran in %.1f s, %.1f s of CPU time (%s budget, %d thread%s unless a table says otherwise; "
              "%d to %d interleaved timed rounds per configuration (%d processes x %d rounds; a "
              "set slower than the budget is timed on a spread share of its rays), samples of at "
              "least %.0f ms; %s; load average %.2f "
              "at the start, %.2f at the end; %.1f other runnable threads at the start)._\n",
           x->name, s, cpu, x->quick ? "quick" : "full", x->threads, x->threads > 1 ? "s" : "",
           x->rounds_lo, x->rounds_hi, x->procs, x->proc_rounds, x->sample_ms, images, x->load_start[0],
           load_end[0], x->others_start);
    if (x->procs_used > 1)
        exp_md(x, "\n_Timed rounds in %d processes interleaved in time (this one and %d forked "
                  "replicas that rebuild every structure built in under %.0f ms, and copy the rays, "
                  "into fresh memory; they take turns, one round each, never two at once), %d "
                  "paired rounds of every configuration per process in alternating order. The "
                  "process is the unit: an estimate is the mean over processes of each process's "
                  "log time (or log ratio: the mean of its rounds, their median from 3 on), its "
                  "interval the t-interval over processes "
                  "(df = processes - 1) at the stated level._\n",
               x->procs_used, x->procs_used - 1, EXP_REPLICA_REBUILD_MS, x->proc_rounds);
    exp_ref_footer(x);
    bench_progress_stop(x->progress);
    x->progress = NULL;
    if (x->csv.bad_rows || x->verdicts.bad_rows) {
        fprintf(stderr, "%s: %d CSV record(s) refused, the first: %s\n", x->name,
                x->csv.bad_rows + x->verdicts.bad_rows,
                x->csv.bad_rows ? x->csv.first_bad : x->verdicts.first_bad);
        x->status = CLI_EXIT_INTERNAL;
    }
    write_leftout(x);
    write_machine(x);
    fclose(x->csv.f);
    fclose(x->verdicts.f);
    fclose(x->md);
    free(x->floors);
    exp_ref_free(x);
    exp_text_free(&x->unparsed);
    fprintf(stderr, "%s: done in %.1f s (%.1f s CPU)%s\n", x->name, s, cpu,
            x->status ? " (with errors, see above)" : "");
    return x->status;
}

void exp_text_add(exp_text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int need = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (need < 0) return;
    if (t->len + (size_t)need + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 256;
        while (cap < t->len + (size_t)need + 1) cap *= 2;
        char *s = realloc(t->s, cap);
        if (!s) {
            fprintf(stderr, "out of memory for text\n");
            exit(CLI_EXIT_INTERNAL);
        }
        t->s = s, t->cap = cap;
    }
    va_start(ap, fmt);
    vsnprintf(t->s + t->len, t->cap - t->len, fmt, ap);
    va_end(ap);
    t->len += (size_t)need;
}

const char *exp_text_str(const exp_text *t) { return t->s ? t->s : ""; }

void exp_text_free(exp_text *t)
{
    free(t->s);
    memset(t, 0, sizeof *t);
}

int exp_kind_wanted(const exp_ctx *x, const char *name)
{
    if (!x->kinds || !*x->kinds) return 1;
    size_t len = strlen(name);
    for (const char *p = x->kinds; *p;) {
        size_t n = strcspn(p, ",");
        if (n == len && !strncmp(p, name, n)) return 1;
        p += n;
        if (*p) p++;
    }
    return 0;
}

/* The kind part of a spec ("bvh" of "bvh:width=4"). */
static void kind_of(const char *spec, char *kind, size_t n)
{
    size_t len = strcspn(spec, ":");
    snprintf(kind, n, "%.*s", (int)(len < n - 1 ? len : n - 1), spec);
}

void exp_list_make(exp_ctx *x, const char *const *defaults, int n, const char *accept,
                   exp_list *out)
{
    out->count = 0;
    out->spec = malloc((size_t)(n + x->accel_count + 1) * sizeof *out->spec);
    if (!out->spec) exit(CLI_EXIT_INTERNAL);
    for (int pass = 0; pass < 2; pass++) {
        int m = pass == 0 ? (x->only_accels ? 0 : n) : x->accel_count;
        for (int i = 0; i < m; i++) {
            const char *spec = pass == 0 ? defaults[i] : x->accels[i];
            char kind[64];
            kind_of(spec, kind, sizeof kind);
            if (!exp_kind_wanted(x, kind)) continue;
            if (pass == 1 && accept) {
                exp_ctx probe = *x;
                probe.kinds = accept;
                if (!exp_kind_wanted(&probe, kind)) continue;
            }
            int dup = 0;
            for (int j = 0; j < out->count; j++) dup |= !strcmp(out->spec[j], spec);
            if (!dup) out->spec[out->count++] = spec;
        }
    }
}

void exp_list_free(exp_list *l)
{
    free(l->spec);
    memset(l, 0, sizeof *l);
}

/* The longest evidence a verdicts record holds (csv.c: 1023 per field). */
#define EVIDENCE_MAX 1000

/* Writes one verdicts row; d may be NULL (no deciding number). */
static void verdict_row(exp_ctx *x, const char *claim, const char *verdict, const exp_decider *d,
                        const char *scenes, const char *evidence_fmt, va_list ap0)
{
    if (!exp_claim_find(claim) || !exp_verdict_valid(verdict)) {
        fprintf(stderr, "%s: internal: bad verdict '%s' on claim '%s'\n", x->name, verdict, claim);
        x->status = CLI_EXIT_INTERNAL;
        return;
    }
    va_list ap;
    va_copy(ap, ap0);
    int need = vsnprintf(NULL, 0, evidence_fmt, ap);
    va_end(ap);
    char *ev = malloc(need > 0 ? (size_t)need + 1 : 1);
    if (!ev) exit(CLI_EXIT_INTERNAL);
    va_copy(ap, ap0);
    vsnprintf(ev, (size_t)need + 1, evidence_fmt, ap);
    va_end(ap);
    /* The CSV writer takes fields of at most 1023 characters: a longer
     * evidence goes to the section in full and is cut in the CSV at a list
     * boundary, saying so (never silently; a record it still refuses fails
     * the run, exit 4). */
    if (strlen(ev) > EVIDENCE_MAX) {
        exp_md(x, "\n_The evidence of the `%s` verdict in full: %s._\n", claim, ev);
        size_t cut = EVIDENCE_MAX - 80;
        while (cut > 200 && !(ev[cut] == ';' || (ev[cut] == ',' && ev[cut + 1] == ' '))) cut--;
        snprintf(ev + cut, (size_t)need + 1 - cut, " ... (cut here: the whole evidence is in the "
                 "section %s)", x->name);
    }
    if (d)
        csv_row(&x->verdicts, "%s,%s,%s,%s,%s,%s,%.6g,%.6g,%.6g,%.6g,%d,%.3g,%d\n", claim,
                verdict, ev, scenes, x->name, d->what ? d->what : "", d->value, d->lo, d->hi,
                d->threshold, d->sense, exp_margin(d), d->n);
    else
        csv_row(&x->verdicts, "%s,%s,%s,%s,%s,,,,,,,,\n", claim, verdict, ev, scenes, x->name);
    free(ev);
    x->verdict_count++;
}

void exp_verdict(exp_ctx *x, const char *claim, const char *verdict, const char *scenes,
                 const char *evidence_fmt, ...)
{
    va_list ap;
    va_start(ap, evidence_fmt);
    verdict_row(x, claim, verdict, NULL, scenes, evidence_fmt, ap);
    va_end(ap);
}

void exp_verdict_num(exp_ctx *x, const char *claim, const char *verdict, const exp_decider *d,
                     const char *scenes, const char *evidence_fmt, ...)
{
    va_list ap;
    va_start(ap, evidence_fmt);
    verdict_row(x, claim, verdict, d, scenes, evidence_fmt, ap);
    va_end(ap);
}

int exp_tiles_stride(const exp_ctx *x)
{
    int k = x->rt_size[0] * x->rt_size[1] / (x->size * x->size);
    return k > 1 ? k : 1;
}

exp_decider exp_decider_of(const char *what, const exp_est *e, double threshold, int sense)
{
    exp_decider d = {what, e->median, e->lo, e->hi, threshold, sense, e->n};
    return d;
}

const char *exp_no_difference(double floor)
{
    return floor <= EXP_NOISY ? EXP_REFUTED : EXP_UNTESTABLE;
}

int exp_note_unparsed(exp_ctx *x, const char *spec)
{
    char line[300];
    snprintf(line, sizeof line, "\n%s\n", spec);
    if (strstr(exp_text_str(&x->unparsed), line)) return 0;
    exp_text_add(&x->unparsed, "%s%s\n", x->unparsed.len ? "" : "\n", spec);
    return 1;
}

const char *exp_slow_verdict(const exp_ctx *x, const char *verdict)
{
    return !strcmp(verdict, EXP_REFUTED) && exp_busy(x) ? EXP_UNTESTABLE : verdict;
}

int exp_busy(const exp_ctx *x) { return !(x->others_start >= 0 && x->others_start < 0.5); }

void exp_note_left(exp_ctx *x, int why)
{
    if (why > 0 && why < EXP_LEFT_KINDS) x->left[why]++;
}

void exp_note_floor(exp_ctx *x, double floor, int measured)
{
    double *f = realloc(x->floors, (size_t)(x->floor_count + 1) * sizeof *f);
    if (!f) exit(CLI_EXIT_INTERNAL);
    x->floors = f;
    x->floors[x->floor_count++] = floor;
    x->floors_measured += measured != 0;
}

double exp_section_floor(const exp_ctx *x)
{
    double hi = 0;
    for (int i = 0; i < x->floor_count; i++) hi = fmax(hi, x->floors[i]);
    return x->floor_count ? hi : 0.05;
}

void exp_csv(exp_ctx *x, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    csv_vrow(&x->csv, fmt, ap); /* refusals are counted; exp_finish reports them */
    va_end(ap);
}

void exp_internal(exp_ctx *x, const char *what, const accel_error *err)
{
    fprintf(stderr, "%s: %s: %s\n", x->name, what, err->msg);
    x->status = CLI_EXIT_INTERNAL;
}

void exp_md(exp_ctx *x, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfprintf(x->md, fmt, ap);
    va_end(ap);
    fflush(x->md);
}

void exp_header(exp_ctx *x, const char *title, const char *words, const char *question_fmt, ...)
{
    if (x->check || !x->limits_checked) {
        /* A programming error: --check would run the whole experiment. */
        fprintf(stderr, "%s: internal: no exp_limits before the section's header\n", x->name);
        exit(CLI_EXIT_INTERNAL);
    }
    exp_md(x, "## %s (%s)\n\n**Question:** ", title, x->name);
    va_list ap;
    va_start(ap, question_fmt);
    vfprintf(x->md, question_fmt, ap);
    va_end(ap);
    exp_md(x, "\n\n**In the lecture's words:** %s\n\n<!-- verdicts -->\n", words);
}

void exp_md_table(exp_ctx *x, const char *cols)
{
    int n = 1;
    for (const char *p = cols; *p; p++) n += *p == '|';
    exp_md(x, "\n| %s |\n|", cols);
    for (int i = 0; i < n; i++) exp_md(x, "---|");
    exp_md(x, "\n");
}

static void scene_room(const exp_ctx *x, int max)
{
    if (x->scene_count <= max) return;
    fprintf(stderr, "%s: %d --scene given, this experiment measures at most %d: none is "
            "dropped silently; give fewer\n", x->name, x->scene_count, max);
    exit(CLI_EXIT_USAGE);
}

void exp_limits(exp_ctx *x, int max_scenes, int max_meshes)
{
    if (max_scenes > 0) scene_room(x, max_scenes);
    exp_mesh_room(x, max_meshes);
    x->limits_checked = 1;
    if (x->check) exit(CLI_EXIT_OK);
}

int exp_scene_list(exp_ctx *x, const char **list, int n, int max)
{
    if (!x->scene_count) return n;
    scene_room(x, max);
    for (int i = 0; i < x->scene_count; i++) list[i] = x->scenes[i];
    return x->scene_count;
}

void exp_mesh_room(exp_ctx *x, int max)
{
    if (!x->meshes_given || x->mesh_count <= max || x->scene_count) return;
    fprintf(stderr, "%s: %d --mesh given, this experiment measures the first %d: none is dropped "
            "silently; give fewer, or --scene for each scene to measure\n", x->name,
            x->mesh_count, max);
    exit(CLI_EXIT_USAGE);
}

void exp_scenes_unused(exp_ctx *x, const char *why)
{
    if (!x->scene_count) return;
    fprintf(stderr, "%s: note: --scene not measured here: %s\n", x->name, why);
    exp_md(x, "\n_The --scene scenes are not measured in this section: %s._\n", why);
}

void exp_scene(exp_ctx *x, const char *spec, accel_scene *s)
{
    char why[sizeof ((accel_error *)0)->msg];
    int rc = exp_scene_try(x, spec, s, why, sizeof why);
    if (rc) {
        fprintf(stderr, "%s: %s\n", x->name, why);
        exit(cli_exit_of(rc));
    }
}

int exp_scene_try(exp_ctx *x, const char *spec, accel_scene *s, char *why, size_t why_n)
{
    accel_error err = {0};
    char phase[300];
    snprintf(phase, sizeof phase, "make scene %s", spec);
    bench_progress_begin(x->progress, phase, 0, 0);
    int rc = scene_create(spec, s, &err);
    bench_progress_end(x->progress);
    if (rc == 0 && s->live_count == 0) {
        scene_free(s);
        rc = accel_fail(&err, ACCEL_ERR_RANGE, "scene %s has nothing to hit", spec);
    }
    if (rc) snprintf(why, why_n, "%s", err.msg);
    return rc;
}

void exp_svg(exp_ctx *x, void *plot, const char *name, const char *caption)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.svg", x->out_dir, name);
    if (svg_write(plot, path) == 0)
        exp_md(x, "\n%s:\n\n<!-- plot: %s -->\n", caption, name);
    else
        exp_md(x, "\n(plot %s not written: cannot write %s)\n", name, path);
    svg_free(plot);
}

const char *exp_fmt_timing(char *buf, size_t n, const accel_timing *t, int decimals)
{
    snprintf(buf, n, "%.*f (%.*f-%.*f)", decimals, t->median, decimals, t->min, decimals, t->max);
    return buf;
}
