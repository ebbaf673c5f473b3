/*
 * harness.c - options, output files and measurement helpers shared by every
 * experiment binary (see harness.h).
 */
#include <dirent.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "harness.h"
#include "bench/cli.h"
#include "bench/image.h"

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

static int opt_threads(const cli_option *o, void *field, char **v, accel_error *err)
{
    exp_ctx *x = (exp_ctx *)((char *)field - offsetof(exp_ctx, threads));
    x->threads_given = 1;
    return cli_int(o, field, v, err);
}

#define OPT(f) offsetof(exp_ctx, f)
static int opt_heat_scale(const cli_option *o, void *field, char **v, accel_error *err)
{
    (void)o;
    return image_heat_scale_parse(v[0], field, err);
}

static const cli_option exp_options[] = {
    {"--quick", NULL, "smoke-test budget (tiny scenes, 1 repeat)", cli_flag, OPT(quick), 0, 0},
    {"--out", "DIR", "where <name>.csv and <name>.md go (default experiments/out)", cli_string,
     OPT(out_dir), 0, 0},
    {"--threads", "N", "threads of every build, trace and reference (default 1;\n"
     "exp_threads: the largest count, default every core)", opt_threads, OPT(threads), 1, 256},
    {"--repeat", "N", "timed passes per measurement (default 5, quick 1)", cli_int, OPT(repeats),
     1, 100},
    {"--size", "N", "primary image N x N (default 128, quick 64)", cli_int, OPT(size), 8, 8192},
    {"--mesh", "FILE", "add a mesh (repeatable; default ../shared/scenes/*.off if present)",
     opt_mesh, OPT(meshes), 0, 0},
    {"--no-meshes", NULL, "built-in scenes only", cli_flag, OPT(no_meshes), 0, 0},
    {"--heat-scale", "SPEC", "heatmap scale: auto (default), max=N, log, e.g. log,max=200",
     opt_heat_scale, OPT(heat_scale), 0, 0},
    {"--quiet", NULL, "no progress lines on stderr", cli_flag, OPT(quiet), 0, 0},
    {"--progress-after", "S", "show progress of phases longer than S seconds (default 2)",
     cli_double, OPT(progress_after), 0, 1e6},
    {"--help", NULL, "this text", cli_flag, OPT(help), 0, 0},
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
    if (x->repeats < 0) x->repeats = x->quick ? 1 : 5;
    if (x->size < 0) x->size = x->quick ? 64 : 128;
    if (x->no_meshes)
        x->mesh_count = 0;
    else if (!x->mesh_count && !x->quick)
        find_default_meshes(x);
    mkdir(x->out_dir, 0777);
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.csv", x->out_dir, name);
    FILE *csv = fopen(path, "w");
    snprintf(path, sizeof path, "%s/%s.md", x->out_dir, name);
    x->md = fopen(path, "w");
    if (!csv || !x->md) {
        fprintf(stderr, "%s: cannot write into %s\n", name, x->out_dir);
        exit(CLI_EXIT_INPUT);
    }
    csv_open(&x->csv, csv);
    x->progress = bench_progress_start(x->quiet ? NULL : stderr, name, x->progress_after * 1e3);
    x->t_start = accel_now_ms();
    fprintf(stderr, "%s: %s\n", name, x->quick ? "quick budget" : "full budget");
}

int exp_finish(exp_ctx *x)
{
    double s = (accel_now_ms() - x->t_start) / 1e3;
    exp_md(x, "\n_%s ran in %.1f s (%s budget, %d thread%s, %d timed repeat%s, images %dx%d)._\n",
           x->name, s, x->quick ? "quick" : "full", x->threads, x->threads > 1 ? "s" : "",
           x->repeats, x->repeats > 1 ? "s" : "", x->size, x->size);
    bench_progress_stop(x->progress);
    x->progress = NULL;
    if (x->csv.bad_rows) {
        fprintf(stderr, "%s: %d CSV record(s) refused, the first: %s\n", x->name, x->csv.bad_rows,
                x->csv.first_bad);
        x->status = CLI_EXIT_INTERNAL;
    }
    fclose(x->csv.f);
    fclose(x->md);
    fprintf(stderr, "%s: done in %.1f s%s\n", x->name, s,
            x->status ? " (with errors, see above)" : "");
    return x->status;
}

void exp_csv(exp_ctx *x, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    csv_vrow(&x->csv, fmt, ap); /* refusals are counted; exp_finish reports them */
    va_end(ap);
}

void exp_append(char *buf, size_t n, const char *fmt, ...)
{
    size_t len = strlen(buf);
    if (len >= n) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + len, n - len, fmt, ap);
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

void exp_md_table(exp_ctx *x, const char *cols)
{
    int n = 1;
    for (const char *p = cols; *p; p++) n += *p == '|';
    exp_md(x, "\n| %s |\n|", cols);
    for (int i = 0; i < n; i++) exp_md(x, "---|");
    exp_md(x, "\n");
}

const char *exp_fmt_timing(char *buf, size_t n, const accel_timing *t, int decimals)
{
    snprintf(buf, n, "%.*f (%.*f-%.*f)", decimals, t->median, decimals, t->min, decimals, t->max);
    return buf;
}

void exp_scene(exp_ctx *x, const char *spec, accel_scene *s)
{
    accel_error err = {0};
    char phase[300];
    snprintf(phase, sizeof phase, "make scene %s", spec);
    bench_progress_begin(x->progress, phase, 0, 0);
    int rc = scene_create(spec, s, &err);
    bench_progress_end(x->progress);
    if (rc == 0 && s->live_count == 0)
        rc = accel_fail(&err, ACCEL_ERR_RANGE, "scene %s has nothing to hit", spec);
    if (rc) {
        fprintf(stderr, "%s: %s\n", x->name, err.msg);
        exit(cli_exit_of(err.code));
    }
}

void exp_sets(exp_ctx *x, const accel_scene *s, int mask, bench_sets *out)
{
    accel_error err = {0};
    bench_set_opts o = {NULL, x->size, x->size, 4, 0, 1, x->threads, NULL};
    bench_progress_begin(x->progress, "make ray sets", 0, 0);
    int rc = bench_sets_make(s, &o, mask, out, &err);
    bench_progress_end(x->progress);
    if (rc) {
        fprintf(stderr, "%s: ray sets for %s: %s\n", x->name, s->name, err.msg);
        exit(cli_exit_of(err.code));
    }
}

void exp_reference(exp_ctx *x, const accel_scene *s, const accel_ray *rays, accel_hit *hits,
                   size_t count)
{
    char phase[200];
    snprintf(phase, sizeof phase, "reference on %s", s->name);
    bench_progress_begin(x->progress, phase, (double)count, 1);
    accel_reference_trace(s, rays, hits, count, x->threads);
    bench_progress_end(x->progress);
}

int exp_run(exp_ctx *x, const char *spec, const accel_scene *s, const bench_sets *sets, int mask,
            exp_measure *m, char *why, size_t why_n)
{
    memset(m, 0, sizeof *m);
    accel_error err = {0};
    const accel_kind *kind;
    void *accel;
    int build_reps = x->quick ? 1 : 3;
    if (bench_build(spec, s, x->threads, build_reps, 5000.0, &kind, &accel, &m->build,
                    &m->build_ms, x->progress, &err)) {
        snprintf(why, why_n, "%s", err.msg);
        return 1;
    }
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
        if (!(mask & bit) || !(sets->made & bit)) continue;
        int i = exp_set_index(bit);
        char phase[320];
        snprintf(phase, sizeof phase, "trace %s with %s", bench_set_name(bit), spec);
        bench_trace_opts o = {.threads = x->threads, .warmup = 1, .repeats = x->repeats,
                              .count_pass = 1, .min_ms = x->quick ? 0.0 : 50.0,
                              .max_ms = x->quick ? 2000.0 : 10000.0,
                              .progress = x->progress, .progress_name = phase};
        if (bench_trace(kind, accel, bench_sets_get(sets, bit), bench_set_is_occlusion(bit), &o,
                        &m->res[i], &err)) {
            snprintf(why, why_n, "%s", err.msg);
            if (err.code == ACCEL_ERR_INTERNAL) exp_internal(x, spec, &err);
            kind->destroy(accel);
            return 1;
        }
        m->have[i] = 1;
    }
    kind->destroy(accel);
    return 0;
}

void exp_plot(exp_ctx *x, const char *plot_name, const char *script)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.gp", x->out_dir, plot_name);
    FILE *f = fopen(path, "w");
    if (!f) return;
    fprintf(f, "set terminal png size 800,500 noenhanced\nset output '%s/%s.png'\n"
               "csv = '%s/%s.csv'\nset datafile separator ','\nset key outside\nset grid\n%s\n",
            x->out_dir, plot_name, x->out_dir, x->name, script);
    fclose(f);
    exp_md(x, "\n<!-- plot: %s -->\n", plot_name);
}

int exp_heatmap(exp_ctx *x, const char *spec, const accel_scene *s, const bench_sets *sets,
                char what, const char *image_name, const char *caption, char *why, size_t why_n)
{
    accel_error err = {0};
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    if (accel_build_spec(spec, s, x->threads, &kind, &accel, &st, &err)) {
        snprintf(why, why_n, "%s", err.msg);
        return 1;
    }
    const rays_set *r = &sets->primary;
    size_t n = r->count;
    uint32_t *steps = calloc(n ? n : 1, sizeof *steps), *prims = calloc(n ? n : 1, sizeof *prims);
    float *v = calloc((size_t)r->width * r->height, sizeof *v);
    accel_hit *hits = malloc((n ? n : 1) * sizeof *hits);
    int rc = 1;
    if (steps && prims && v && hits) {
        accel_counters c = {0};
        c.ray_steps = steps;
        c.ray_prims = prims;
        accel_trace(kind, accel, r->rays, hits, n, x->threads, &c);
        if (accel_counters_status(&c, &err)) {
            exp_internal(x, spec, &err);
            snprintf(why, why_n, "%s", err.msg);
            goto done;
        }
        double total = 0;
        for (size_t i = 0; i < n; i++) {
            uint32_t val = what == 's' ? steps[i] : prims[i];
            v[r->pixel[i]] = (float)val;
            total += val;
        }
        image_rgb img;
        char path[1024], title[256], scale[96];
        const char *unit = what == 's' ? kind->step_name : "primitive tests";
        snprintf(path, sizeof path, "%s/%s.png", x->out_dir, image_name);
        image_heat_title(title, sizeof title, spec, kind, what != 's');
        snprintf(scale, sizeof scale, "%s colour scale from 0 to %s",
                 x->heat_scale.log ? "logarithmic" : "linear",
                 x->heat_scale.max > 0 ? "a fixed maximum" : "the image's maximum");
        if (image_heatmap(v, r->width, r->height, &x->heat_scale, title, &img, &err) == 0) {
            rc = image_write(path, &img, &err);
            image_free(&img);
        }
        if (rc == 0)
            exp_md(x, "\n%s (mean %.1f %s per ray; %s, printed under the image):\n\n"
                      "<!-- image: %s -->\n",
                   caption, n ? total / (double)n : 0.0, unit, scale, image_name);
        else
            snprintf(why, why_n, "%s", err.msg);
    } else {
        snprintf(why, why_n, "out of memory");
    }
done:
    free(steps);
    free(prims);
    free(v);
    free(hits);
    kind->destroy(accel);
    return rc;
}
