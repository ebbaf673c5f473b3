/*
 * test_tools.c - tools that never surprise: bin/trace and the experiments
 * run as subprocesses (small sizes), their pieces (cli/cli.h, measure/csv.h,
 * measure/progress.h) called directly; CSV is read back by an RFC 4180 reader here.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "measure/bench.h"
#include "cli/cli.h"
#include "measure/csv.h"
#include "measure/progress.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

#define DIR "build/test_tools"

/* The text written to a tmpfile, which is closed. */
static void slurp(FILE *f, char *text, size_t size)
{
    rewind(f);
    size_t n = fread(text, 1, size - 1, f);
    text[n] = 0;
    fclose(f);
}

/* Runs a shell command in DIR's sense (support.h: test_run). */
static int run(const char *cmd, char **out, char **err) { return test_run(DIR, cmd, out, err); }

/* ---- a small RFC 4180 reader -------------------------------------------- */

#define MAX_RECORDS 512
#define MAX_FIELDS 64

typedef struct {
    int count;
    int fields[MAX_RECORDS];
    char *field[MAX_RECORDS][MAX_FIELDS];
    int bad; /* a quote inside an unquoted field, text after a closing quote, an open quote */
} csv_doc;

static void csv_doc_free(csv_doc *d)
{
    for (int r = 0; r < d->count; r++)
        for (int f = 0; f < d->fields[r] && f < MAX_FIELDS; f++) free(d->field[r][f]);
}

/* Fields are split at commas outside quotes; a quoted field may hold
 * commas, CR, LF and doubled quotes; records end at LF or CRLF. */
static void csv_read(const char *text, csv_doc *d)
{
    memset(d, 0, sizeof *d);
    const char *p = text;
    while (*p && d->count < MAX_RECORDS) {
        int r = d->count++;
        for (;;) {
            char buf[2048];
            size_t n = 0;
            if (*p == '"') {
                for (p++; *p && !(*p == '"' && p[1] != '"'); p += *p == '"' ? 2 : 1)
                    if (n < sizeof buf - 1) buf[n++] = *p;
                if (*p) p++; /* the closing quote */
                else d->bad++;
                if (*p && *p != ',' && *p != '\n' && !(*p == '\r' && p[1] == '\n')) d->bad++;
            } else {
                for (; *p && *p != ',' && *p != '\n' && !(*p == '\r' && p[1] == '\n'); p++) {
                    d->bad += *p == '"';
                    if (n < sizeof buf - 1) buf[n++] = *p;
                }
            }
            buf[n] = 0;
            int f = d->fields[r]++;
            if (f < MAX_FIELDS) d->field[r][f] = strdup(buf);
            if (*p == ',') {
                p++;
                continue;
            }
            if (*p == '\r') p++;
            if (*p == '\n') p++;
            break;
        }
    }
}

/* Every record has the header's field count and the text is well formed. */
static void check_one_schema(const char *what, const csv_doc *d, int min_records)
{
    CHECKF(d->bad == 0, "%s: %d malformed quoted fields", what, d->bad);
    CHECKF(d->count >= min_records, "%s: %d records, expected at least %d", what, d->count,
           min_records);
    for (int r = 1; r < d->count; r++)
        CHECKF(d->fields[r] == d->fields[0], "%s: record %d has %d fields, the header %d", what,
               r + 1, d->fields[r], d->fields[0]);
}

static int column(const csv_doc *d, const char *name)
{
    for (int f = 0; d->count && f < d->fields[0] && f < MAX_FIELDS; f++)
        if (!strcmp(d->field[0][f], name)) return f;
    return -1;
}

/* ---- pieces called directly ----------------------------------------------- */

typedef struct {
    int n, flag;
    const char *name;
    uint64_t seed;
    double x;
    int size[2];
} toy_opts;

static const cli_option toy_table[] = {
    {"--n", "N", "a count", cli_int, offsetof(toy_opts, n), 1, 10},
    {"--flag", NULL, "a switch", cli_flag, offsetof(toy_opts, flag), 0, 0},
    {"--name", "S", "a name", cli_string, offsetof(toy_opts, name), 0, 0},
    {"--seed", "N", "a seed", cli_u64, offsetof(toy_opts, seed), 0, 0},
    {"--x", "R", "a number", cli_double, offsetof(toy_opts, x), -1, 1},
    {"--size", "WxH", "a size", cli_size, offsetof(toy_opts, size), 1, 100},
};

static int toy_parse(const char *a, const char *b, toy_opts *o, accel_error *err)
{
    char *argv[3] = {"toy", (char *)a, (char *)b};
    memset(o, 0, sizeof *o);
    return cli_parse(toy_table, 6, b ? 3 : 2, argv, 1, o, err);
}

TEST(tools_cli_table_parses_strictly)
{
    toy_opts o;
    accel_error err = {0};
    CHECK(toy_parse("--n", "7", &o, &err) == 0 && o.n == 7);
    CHECK(toy_parse("--flag", NULL, &o, &err) == 0 && o.flag == 1);
    CHECK(toy_parse("--seed", "18446744073709551615", &o, &err) == 0 &&
          o.seed == 18446744073709551615ull);
    CHECK(toy_parse("--x", "-0.5", &o, &err) == 0 && o.x == -0.5);
    CHECK(toy_parse("--size", "12x34", &o, &err) == 0 && o.size[0] == 12 && o.size[1] == 34);
    static const char *const bad[][2] = {
        {"--n", "abc"},    {"--n", "3q"},     {"--n", "11"},       {"--n", "-1"},
        {"--n", ""},       {"--seed", "abc"}, {"--seed", "-1"},    {"--seed", "1e3"},
        {"--x", "2"},      {"--x", "nan"},    {"--size", "10xq"},  {"--size", "10x10q"},
        {"--size", "x10"}, {"--size", "0x10"}, {"--nope", "1"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        CHECKF(toy_parse(bad[i][0], bad[i][1], &o, &err) == ACCEL_ERR_SPEC, "%s %s accepted",
               bad[i][0], bad[i][1]);
    char *argv[2] = {"toy", "--n"};
    CHECKF(cli_parse(toy_table, 6, 2, argv, 1, &o, &err) == ACCEL_ERR_SPEC &&
           strstr(err.msg, "needs"), "a missing value: %s", err.msg);
    /* --help is drawn from the same table: every option and its argument. */
    FILE *f = tmpfile();
    cli_help(f, toy_table, 6);
    cli_help_exit_codes(f);
    char text[4096];
    slurp(f, text, sizeof text);
    for (size_t i = 0; i < 6; i++)
        CHECKF(strstr(text, toy_table[i].name) && strstr(text, toy_table[i].help),
               "%s missing from the help", toy_table[i].name);
    CHECK(strstr(text, "--size WxH") != NULL);
    for (int code = 0; code <= 4; code++) {
        char line[16];
        snprintf(line, sizeof line, "\n  %d  ", code);
        CHECKF(strstr(text, line) != NULL, "exit status %d not documented", code);
    }
    CHECK(cli_exit_of(ACCEL_ERR_SPEC) == CLI_EXIT_USAGE && cli_exit_of(ACCEL_ERR_IO) == CLI_EXIT_INPUT &&
          cli_exit_of(ACCEL_ERR_INTERNAL) == CLI_EXIT_INTERNAL);
}

TEST(tools_csv_quotes_fields_and_keeps_one_schema)
{
    char buf[512];
    int n = csv_format(buf, sizeof buf, "%s,%d,%s,%.2f,x%sy\n", "bvh:build=binned,bins=8", 3,
                       "say \"hi\"", 1.5, "plain");
    CHECK(n == 5);
    CHECKF(!strcmp(buf, "\"bvh:build=binned,bins=8\",3,\"say \"\"hi\"\"\",1.50,xplainy"), "%s", buf);
    CHECK(csv_format(buf, sizeof buf, "%zu,%llu,%5.1f,%*d,%%", (size_t)7, 8ull, 2.25, 3, 4) == 5);
    CHECKF(!strcmp(buf, "7,8,  2.2,  4,%") || !strcmp(buf, "7,8,  2.3,  4,%"), "%s", buf);
    CHECK(csv_format(buf, 8, "%s", "far too long for eight") == -1);
    FILE *f = tmpfile();
    csv_file c;
    csv_open(&c, f);
    CHECK(csv_row(&c, "a,b,c\n") == 0);
    CHECK(csv_row(&c, "%s,%d,%s\n", "x,y", 1, "line\nbreak") == 0);
    CHECK(csv_row(&c, "%d,%d\n", 1, 2) == -1); /* two fields under a three-field header */
    CHECK(c.bad_rows == 1 && c.rows == 1 && c.columns == 3);
    char text[512];
    slurp(f, text, sizeof text);
    csv_doc d;
    csv_read(text, &d);
    check_one_schema("csv_row", &d, 2);
    CHECK(d.count == 2 && !strcmp(d.field[1][0], "x,y") && !strcmp(d.field[1][2], "line\nbreak"));
    csv_doc_free(&d);
}

static void count_items(void *ctx, size_t b, size_t e, int t)
{
    (void)ctx, (void)b, (void)e, (void)t;
}

TEST(tools_progress_estimates_and_reports_phases)
{
    char line[256];
    bench_progress_format(line, sizeof line, "build bvh", 2, 5, 3000);
    CHECKF(strstr(line, "40%") && strstr(line, "after 3.0 s") && strstr(line, "about 4.5 s left"),
           "%s", line);
    bench_progress_format(line, sizeof line, "build bvh", 0, 5, 3000);
    CHECKF(strstr(line, "no estimate yet") != NULL, "%s", line);
    /* Traced phases count rays through accel_parallel_done. */
    uint64_t before = accel_parallel_done();
    accel_parallel_for(10000, 64, 2, count_items, NULL);
    CHECK(accel_parallel_done() - before == 10000);
    /* A phase longer than the threshold ends with a "done" line; quiet is NULL. */
    FILE *f = tmpfile();
    bench_progress *p = bench_progress_start(f, "tool", 0);
    CHECK(p != NULL);
    bench_progress_begin(p, "phase one", 3, 0);
    bench_progress_add(p, 3);
    bench_progress_end(p);
    bench_progress_stop(p);
    char text[1024];
    slurp(f, text, sizeof text);
    CHECKF(strstr(text, "tool: phase one: done in") != NULL, "%s", text);
    CHECK(bench_progress_start(NULL, "tool", 0) == NULL);
    bench_progress_begin(NULL, "x", 1, 1); /* quiet: every call is a no-op */
    bench_progress_end(NULL);
}

TEST(tools_camera_and_scene_spec_checks)
{
    accel_error err = {0};
    accel_camera ok = {v3(0, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 45};
    CHECK(rays_camera_check(&ok, &err) == 0);
    accel_camera bad[] = {{v3(1, 2, 3), v3(1, 2, 3), v3(0, 1, 0), 45},
                          {v3(0, 0, 5), v3(0, 0, 0), v3(0, 0, 0), 45},
                          {v3(0, 0, 5), v3(0, 0, 0), v3(0, 0, 2), 45},
                          {v3(0, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 0},
                          {v3(0, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 180},
                          {v3(NAN, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 45}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECKF(rays_camera_check(&bad[i], &err) == ACCEL_ERR_RANGE, "camera %zu accepted", i);
        rays_set r;
        CHECKF(rays_primary(&bad[i], 8, 8, &r, &err) != 0, "rays from camera %zu", i);
    }
    CHECK(scene_spec_check("sphereflake:level=2", &err) == 0);
    CHECK(scene_spec_check("sphereflake:levle=2", &err) == ACCEL_ERR_SPEC);
    CHECK(scene_spec_check("no_such_scene", &err) == ACCEL_ERR_SPEC);
    CHECK(scene_spec_check(DIR "/absent.off", &err) == ACCEL_ERR_IO);
    CHECK(scene_spec_check("mesh.stl", &err) == ACCEL_ERR_SPEC);
}

/* A kind whose counted runs record a broken step bound on every batch. */
static void broken_intersect(const void *a, const accel_ray *r, accel_hit *h, size_t n,
                             accel_counters *c)
{
    (void)a, (void)r;
    for (size_t i = 0; i < n; i++) h[i] = accel_hit_miss();
    if (c) accel_counters_note_broken(c, "broken.c", 42, 7);
}

TEST(tools_counted_pass_reports_broken_invariant)
{
    accel_kind broken = {0};
    broken.name = "broken";
    broken.intersect = broken_intersect;
    accel_camera cam = {v3(0, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 45};
    rays_set rs;
    accel_error err = {0};
    CHECK(rays_primary(&cam, 16, 16, &rs, &err) == 0);
    bench_trace_opts o = {.threads = 1, .warmup = 0, .repeats = 1, .count_pass = 1};
    bench_result br;
    int rc = bench_trace(&broken, NULL, &rs, 0, &o, &br, &err);
    CHECKF(rc == ACCEL_ERR_INTERNAL && strstr(err.msg, "broken.c"), "rc %d: %s", rc, err.msg);
    CHECK(br.counted && br.rays == 256); /* the measurement itself is still there */
    CHECK(cli_exit_of(rc) == CLI_EXIT_INTERNAL);
    o.count_pass = 0; /* timed copies check no bound: nothing to report */
    CHECK(bench_trace(&broken, NULL, &rs, 0, &o, &br, &err) == 0);
    rays_free(&rs);
}

/* ---- bin/trace ------------------------------------------------------------ */

/* Runs cmd: its exit status must be code, with `text` in its stderr. */
static void expect_error(const char *cmd, int code, const char *text)
{
    char *err = NULL;
    int rc = run(cmd, NULL, &err);
    CHECKF(rc == code && err && strstr(err, text), "%s: exit %d (expected %d): %s", cmd, rc, code,
           err ? err : "");
    free(err);
}

#define TRACE "bin/trace --size 16x16 --repeat 1 --build-repeat 1 "

TEST(tools_trace_checks_everything_before_work)
{
    /* Each must fail with a usage error before anything is built or printed. */
    static const char *const usage[] = {
        "--scene soup:tris=2000 --accel grid --accel bvhh",
        "--accel grid --accel bvh:bins=0",
        "--scene sphereflake:levle=2",
        "--rays primary,shadw",
        "--seed abc",
        "--size 10xq",
        "--size 10x10q",
        "--threads -1",
        "--threads 2x",
        "--ao-radius abc",
        "--repeat 0",
        "--image " DIR "/x.png --rays diffuse",
        "--image " DIR "/x.jpg",
        "--eye 0,0,0 --look 0,0,0",
        "--up 0,0,0",
        "--eye 0,0,5 --look 0,0,0 --up 0,0,1",
        "--eye 1,2",
        "--heatmap cells " DIR "/h.png",
        "--bogus",
    };
    for (size_t i = 0; i < sizeof usage / sizeof usage[0]; i++) {
        char cmd[512], *out = NULL, *err = NULL;
        snprintf(cmd, sizeof cmd, TRACE "%s", usage[i]);
        int rc = run(cmd, &out, &err);
        CHECKF(rc == CLI_EXIT_USAGE, "%s: exit %d, expected 2 (%s)", usage[i], rc, err ? err : "");
        CHECKF(out && !out[0], "%s: printed before failing: %s", usage[i], out ? out : "");
        CHECKF(err && strstr(err, "trace: "), "%s: no message", usage[i]);
        free(out), free(err);
    }
    /* Input errors: a file that is not there, or a directory that cannot take output. */
    expect_error(TRACE "--scene " DIR "/absent.off", CLI_EXIT_INPUT, "absent.off");
    expect_error(TRACE "--image /nonexistent-dir/x.png", CLI_EXIT_INPUT, "nonexistent-dir");
}

TEST(tools_trace_refuses_silent_success)
{
    mkdir("build", 0777);
    mkdir(DIR, 0777);
    FILE *f = fopen(DIR "/empty.off", "w");
    if (f) fputs("OFF\n0 0 0\n", f), fclose(f);
    f = fopen(DIR "/flat.off", "w");
    if (f) fputs("OFF\n3 1 0\n0 0 0\n1 1 1\n2 2 2\n3 0 1 2\n", f), fclose(f);
    expect_error(TRACE "--scene " DIR "/empty.off", CLI_EXIT_INPUT, "nothing to hit");
    expect_error(TRACE "--scene " DIR "/flat.off", CLI_EXIT_INPUT, "nothing to hit");
    /* Bounds of 6e38 leave float no room for a default camera: the file is
     * named and the way out given; and --eye takes any finite float. */
    f = fopen(DIR "/huge.off", "w");
    if (f) fputs("OFF\n3 1 0\n3e38 0 0\n-3e38 0 0\n0 1 0\n3 0 1 2\n", f), fclose(f);
    expect_error(TRACE "--scene " DIR "/huge.off", CLI_EXIT_INPUT, "huge.off: the scene's camera");
    expect_error(TRACE "--scene " DIR "/huge.off", CLI_EXIT_INPUT, "give --eye, --look and --up");
    CHECK(run(TRACE "--scene " DIR "/huge.off --eye 0,0.5,3e38 --look 0,0.5,0 --check", NULL,
              NULL) == 0);
    /* Up parallel to the scene's own view (sphereflake looks from (2.1, 1.3, 1.7) at 0). */
    expect_error(TRACE "--up 2.1,1.3,1.7", CLI_EXIT_USAGE, "parallel");
    /* .rays files carry no pixels: neither an image nor a heatmap. */
    CHECK(run(TRACE "--dump-rays " DIR "/p.rays", NULL, NULL) == 0);
    expect_error(TRACE "--rays " DIR "/p.rays --image " DIR "/p.png", CLI_EXIT_USAGE, "pixels");
    expect_error(TRACE "--rays " DIR "/p.rays --heatmap steps " DIR "/p.png", CLI_EXIT_USAGE,
                 "pixels");
}

/* Rays that can hit nothing are traced as misses, with a warning naming the
 * file, how many, and the first one's index, byte offset and fault. */
TEST(tools_trace_warns_of_rays_that_hit_nothing)
{
    mkdir("build", 0777);
    mkdir(DIR, 0777);
    const float inf = INFINITY;
    accel_ray rays[5] = {
        {0, 0, 5, 0, 0, 0, -1, inf},    /* a good ray, straight at the sphereflake */
        {NAN, 0, 5, 0, 0, 0, -1, inf},  /* NaN origin */
        {0, 0, 5, 0, 0, 0, 0, inf},     /* zero direction */
        {0, 0, 5, 0, 0, 0, -1, inf},    /* good */
        {0, 0, 5, 10, 0, 0, -1, 1},     /* tnear > tfar */
    };
    accel_error e = {0};
    CHECK(rays_write(DIR "/bad.rays", rays, 5, &e) == 0);
    char *err = NULL;
    int rc = run(TRACE "--rays " DIR "/bad.rays --accel bvh --dump-hits " DIR "/bad.hits --check",
                 NULL, &err);
    CHECKF(rc == 0 && err && strstr(err, "bad.rays: 3 of 5 rays can hit nothing") &&
               strstr(err, "ray 1, byte 48, has a NaN or infinite origin"),
           "exit %d: %s", rc, err ? err : "");
    free(err);
    accel_hit *hits = NULL;
    size_t n = 0;
    CHECK(hits_read(DIR "/bad.hits", &hits, &n, &e) == 0 && n == 5);
    for (size_t i = 0; hits && i < n; i++)
        CHECKF((hits[i].prim != ACCEL_MISS) == (i == 0 || i == 3), "ray %zu: prim %u", i,
               hits[i].prim);
    free(hits);
    /* A file of good rays gets no warning. */
    CHECK(rays_write(DIR "/good.rays", rays, 1, &e) == 0);
    rc = run(TRACE "--rays " DIR "/good.rays --accel bvh", NULL, &err);
    CHECKF(rc == 0 && err && !strstr(err, "warning"), "exit %d: %s", rc, err ? err : "");
    free(err);
}

/* Reads "word (a, b, c)" after `key` in text. */
static int read_vec(const char *text, const char *key, double v[3])
{
    const char *p = strstr(text, key);
    return p && sscanf(p + strlen(key), " (%lf, %lf, %lf)", &v[0], &v[1], &v[2]) == 3;
}

TEST(tools_trace_prints_camera_and_bounds)
{
    char *out = NULL;
    int rc = run(TRACE "--scene soup:tris=300 --accel brute", &out, NULL);
    CHECK(rc == 0 && out);
    accel_scene s;
    accel_error err = {0};
    if (!out || scene_create("soup:tris=300", &s, &err)) {
        free(out);
        return;
    }
    double got[5][3]; /* bounds min, max; eye, look, up */
    for (int k = 0; k < 15; k++) got[k / 3][k % 3] = NAN;
    double *lo = got[0], *hi = got[1], *eye = got[2], *look = got[3], *up = got[4];
    CHECKF(read_vec(out, "bounds", lo) && read_vec(out, ") to", hi), "no bounds in: %s", out);
    const char *cam = strstr(out, "camera eye");
    CHECKF(cam && read_vec(cam, "camera eye", eye) && read_vec(cam, ") look", look) &&
           read_vec(cam, ") up", up), "no camera in: %s", out);
    vec3 want[5] = {s.bounds.min, s.bounds.max, s.camera.eye, s.camera.look_at, s.camera.up};
    for (int k = 0; k < 5; k++)
        for (int i = 0; i < 3; i++) {
            double w = i == 0 ? want[k].x : i == 1 ? want[k].y : want[k].z;
            CHECKF(fabs(got[k][i] - w) <= 1e-5 * (1 + fabs(w)), "printed %g, scene has %g "
                   "(vector %d)", got[k][i], w, k);
        }
    const char *fov = strstr(out, "fov");
    CHECK(fov && fabs(atof(fov + 3) - s.camera.fov_deg) < 1e-4);
    free(out);
    /* An override is what is printed. */
    rc = run(TRACE "--scene soup:tris=300 --accel brute --eye 0.5,-2,0.25", &out, NULL);
    CHECK(rc == 0 && out && read_vec(out, "camera eye", eye) && eye[0] == 0.5 && eye[1] == -2 &&
          eye[2] == 0.25);
    free(out);
    scene_free(&s);
}

TEST(tools_trace_csv_is_rfc4180)
{
    char *out = NULL;
    int rc = run(TRACE "--csv --check --scene soup:tris=500 --accel bvh:build=binned,bins=8 "
                       "--accel grid:lambda=2,mailbox=0 --rays primary,shadow", &out, NULL);
    CHECKF(rc == 0, "exit %d", rc);
    if (!out) return;
    csv_doc d;
    csv_read(out, &d);
    check_one_schema("trace --csv", &d, 5);
    int spec = column(&d, "spec"), holes = column(&d, "holes"), set = column(&d, "rayset");
    CHECK(spec >= 0 && holes >= 0 && set >= 0 && d.count == 5);
    if (d.count == 5 && spec >= 0 && holes >= 0) {
        CHECK(!strcmp(d.field[1][spec], "bvh:build=binned,bins=8"));
        CHECK(!strcmp(d.field[4][spec], "grid:lambda=2,mailbox=0"));
        CHECK(!strcmp(d.field[2][set], "shadow"));
        for (int r = 1; r < 5; r++) CHECK(!strcmp(d.field[r][holes], "0"));
    }
    csv_doc_free(&d);
    free(out);
}

/* stdout is line-buffered: with progress shown from the start, stdout and
 * stderr interleave in the order the steps happen. */
TEST(tools_trace_flushes_output_in_order)
{
    int st = system("bin/trace --size 16x16 --repeat 1 --build-repeat 1 --scene soup:tris=500 "
                    "--progress-after 0 > " DIR "/both.txt 2>&1");
    CHECK(st == 0);
    char *all = test_read_file(DIR "/both.txt", NULL);
    if (!all) return;
    const char *order[] = {"scene soup", "trace: build bvh: done in", "accel bvh:",
                           "trace: trace primary with bvh: done in", "  primary "};
    const char *prev = all;
    for (size_t i = 0; i < sizeof order / sizeof order[0]; i++) {
        const char *p = strstr(prev, order[i]);
        CHECKF(p != NULL, "'%s' missing or out of order in:\n%s", order[i], all);
        if (p) prev = p;
    }
    free(all);
    char *err = NULL;
    CHECK(run("bin/trace --size 16x16 --repeat 1 --build-repeat 1 --progress-after 0 --quiet",
              NULL, &err) == 0);
    CHECKF(err && !err[0], "--quiet printed: %s", err ? err : "");
    free(err);
}

/* The most threads /proc shows the running process pid with, sampled
 * until it exits; -1 without /proc. Returns through *status its exit status. */
static int max_threads_of(pid_t pid, int *status)
{
    char path[64];
    snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
    int most = -1;
    for (;;) {
        FILE *f = fopen(path, "r");
        char line[256];
        while (f && fgets(line, sizeof line, f))
            if (!strncmp(line, "Threads:", 8) && atoi(line + 8) > most) most = atoi(line + 8);
        if (f) fclose(f);
        int st;
        pid_t w = waitpid(pid, &st, WNOHANG);
        if (w == pid) {
            *status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
            return most;
        }
        if (w < 0) return most;
        usleep(500);
    }
}

/* With --threads 1 every phase, the reference of --check included (it used
 * to take every core), runs on the main thread alone; --quiet starts no
 * progress thread. */
TEST(tools_trace_threads_bound_every_phase)
{
    for (int threads = 1; threads <= 2; threads++) {
        char t[8];
        snprintf(t, sizeof t, "%d", threads);
        pid_t pid = fork();
        if (pid == 0) {
            if (!freopen("/dev/null", "w", stdout)) _exit(127);
            execl("bin/trace", "bin/trace", "--quiet", "--threads", t, "--check", "--scene",
                  "soup:tris=8000", "--size", "32x32", "--repeat", "1", "--build-repeat", "1",
                  "--no-counters", (char *)NULL);
            _exit(127);
        }
        CHECK(pid > 0);
        if (pid <= 0) return;
        int status = -1;
        int most = max_threads_of(pid, &status);
        CHECK(status == 0);
        if (most < 0) {
            test_skip("no /proc to count threads");
            return;
        }
        /* Two threads may come and go between samples; one must never be exceeded. */
        CHECKF(threads == 1 ? most == 1 : most >= 1 && most <= threads,
               "--threads %d: the process ran %d threads at once", threads, most);
    }
}

TEST(tools_trace_help_documents_options_and_exit_codes)
{
    char *out = NULL;
    CHECK(run("bin/trace --help", &out, NULL) == 0 && out);
    static const char *const want[] = {"--threads N", "--quiet", "--progress-after S", "--csv",
                                       "--heatmap steps|prims F.png", "Exit status:",
                                       "  2  usage error", "  4  internal error", "Accelerators:"};
    for (size_t i = 0; out && i < sizeof want / sizeof want[0]; i++)
        CHECKF(strstr(out, want[i]) != NULL, "'%s' missing from trace --help", want[i]);
    free(out);
    CHECK(run("bin/exp_sah --help", &out, NULL) == 0 && out && strstr(out, "--quiet") &&
          strstr(out, "Exit status:") && strstr(out, "  3  input error"));
    free(out);
}

/* ---- experiments ------------------------------------------------------------ */

/* Runs an experiment on the quick budget; its CSV must have one schema and,
 * when spec_with_comma is given, hold that text as one field. */
static void check_experiment_csv(const char *exp, const char *spec_with_comma)
{
    char cmd[256], path[256];
    snprintf(cmd, sizeof cmd, "bin/%s --quick --quiet --out " DIR "/exp", exp);
    CHECKF(run(cmd, NULL, NULL) == 0, "%s failed", exp);
    snprintf(path, sizeof path, DIR "/exp/%s.csv", exp);
    char *text = test_read_file(path, NULL);
    CHECKF(text != NULL, "%s not written", path);
    if (!text) return;
    csv_doc d;
    csv_read(text, &d);
    check_one_schema(path, &d, 3);
    int found = !spec_with_comma;
    for (int r = 1; !found && r < d.count; r++)
        for (int f = 0; f < d.fields[r] && f < MAX_FIELDS; f++)
            found |= !strcmp(d.field[r][f], spec_with_comma);
    CHECKF(found, "%s: no field '%s'", path, spec_with_comma);
    csv_doc_free(&d);
    free(text);
}

TEST(tools_experiments_write_rfc4180_csv)
{
    check_experiment_csv("exp_binning", "bvh:build=binned,bins=16,axes=3");
    check_experiment_csv("exp_stability", NULL);
    expect_error("bin/exp_sah --quick --out " DIR "/exp --repeat 3q", CLI_EXIT_USAGE, "--repeat");
    expect_error("bin/exp_sah --quick --out " DIR "/exp --size 64x", CLI_EXIT_USAGE, "--size");
    expect_error("bin/exp_sah --quick --out " DIR "/exp --mesh " DIR "/absent.off", CLI_EXIT_INPUT,
                 "absent.off");
}

/* exp_threads measures 1..N threads for --threads N (default: every core). */
TEST(tools_exp_threads_takes_threads_as_largest_count)
{
    for (int t = 1; t <= 2; t++) {
        char cmd[256];
        snprintf(cmd, sizeof cmd, "bin/exp_threads --quick --quiet --threads %d --out " DIR
                 "/exp", t);
        CHECK(run(cmd, NULL, NULL) == 0);
        char *text = test_read_file(DIR "/exp/exp_threads.csv", NULL);
        if (!text) continue;
        csv_doc d;
        csv_read(text, &d);
        check_one_schema("exp_threads.csv", &d, 2);
        int col = column(&d, "threads"), most = 0;
        for (int r = 1; col >= 0 && r < d.count; r++) {
            int v = atoi(d.field[r][col]);
            CHECKF(v >= 1 && v <= t, "--threads %d measured %d threads", t, v);
            if (v > most) most = v;
        }
        CHECKF(most == t, "--threads %d: largest count measured %d", t, most);
        csv_doc_free(&d);
        free(text);
    }
}
