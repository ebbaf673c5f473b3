/*
 * test_exp_twolevel.c - bin/exp_twolevel --quick into a temporary
 * directory: its CSV parses as strict RFC 4180 with one schema, holds the
 * rows the section promises (every flattened kind and two-level combination
 * on both scenes, the control once, refit at k = 1 and 3, the frame loops),
 * finite numbers with lo <= median <= hi, zero disagreements everywhere, and
 * the three verdicts of its claims.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "support.h"
#include "test.h"
#include "experiments/engine/claims.h"

#define COLS 11
#define MAX_RECORDS 2000

typedef struct {
    char *f[COLS];
} record;

/* Strict RFC 4180 into records of exactly COLS fields (quoted fields with
 * doubled quotes; no quote inside an unquoted field). Fields point into s,
 * which is rewritten. Returns the record count, or -1 with the reason. */
static int parse_strict(char *s, record *out, int max, char *why, size_t wn)
{
    int n = 0;
    while (*s) {
        if (n == max) return snprintf(why, wn, "more than %d records", max), -1;
        int fields = 0;
        for (;;) {
            char *start = s, *w = s;
            if (*s == '"') {
                for (s++;; s++) {
                    if (!*s) return snprintf(why, wn, "record %d: unterminated quote", n + 1), -1;
                    if (*s == '"' && s[1] == '"') *w++ = '"', s++;
                    else if (*s == '"') { s++; break; }
                    else *w++ = *s;
                }
            } else {
                for (; *s && *s != ',' && *s != '\n' && *s != '\r'; s++, w++) {
                    if (*s == '"') return snprintf(why, wn, "record %d: quote in an unquoted field", n + 1), -1;
                    *w = *s;
                }
            }
            char end = *s, next = end ? s[1] : 0;
            *w = 0;
            if (fields == COLS) return snprintf(why, wn, "record %d: more than %d fields", n + 1, COLS), -1;
            out[n].f[fields++] = start;
            if (end == ',') { s++; continue; }
            if (end == '\r' && next == '\n') s += 2;
            else if (end == '\n') s++;
            else if (end) return snprintf(why, wn, "record %d: text after a closing quote", n + 1), -1;
            break;
        }
        if (fields != COLS) return snprintf(why, wn, "record %d: %d fields, not %d", n + 1, fields, COLS), -1;
        n++;
    }
    return n;
}

/* A finite number filling the whole field. */
static int number(const char *s, double *v)
{
    char *end;
    *v = strtod(s, &end);
    return *s && !*end && !isspace((unsigned char)*s) && isfinite(*v);
}

/* A word nan or inf (any case) in s. */
static int nonfinite_word(const char *s)
{
    for (const char *p = s; *p; p++)
        if ((p == s || !isalnum((unsigned char)p[-1])) &&
            (!strncasecmp(p, "nan", 3) || !strncasecmp(p, "inf", 3)) && !isalnum((unsigned char)p[3]))
            return 1;
    return 0;
}

/* Records of part, with scene (NULL: any), config (NULL: any), frame (< 0: any), quantity. */
static int count(record *r, int n, const char *part, const char *scene, const char *config,
                 int frame, const char *quantity)
{
    int k = 0;
    for (int i = 1; i < n; i++)
        k += !strcmp(r[i].f[0], part) && (!scene || !strcmp(r[i].f[1], scene)) &&
             (!config || !strcmp(r[i].f[3], config)) && (frame < 0 || atoi(r[i].f[5]) == frame) &&
             !strcmp(r[i].f[6], quantity);
    return k;
}

TEST(exp_twolevel_quick_csv)
{
    char dir[] = "build/exp_twolevel.XXXXXX", cmd[256], path[256];
    CHECK(mkdtemp(dir) != NULL);
    snprintf(cmd, sizeof cmd, "bin/exp_twolevel --quick --quiet --out %s > %s/log 2>&1", dir, dir);
    int rc = system(cmd);
    CHECKF(rc == 0, "exp_twolevel --quick failed (%d): see %s/log", rc, dir);
    snprintf(path, sizeof path, "%s/exp_twolevel.csv", dir);
    char *csv = test_read_file(path, NULL);
    CHECKF(csv != NULL, "%s not written", path);
    if (!csv) return;
    static record r[MAX_RECORDS];
    char why[160] = "";
    int n = parse_strict(csv, r, MAX_RECORDS, why, sizeof why);
    CHECKF(n > 1, "%s: not strict RFC 4180 CSV of %d fields: %s", path, COLS, why);
    if (n <= 1) { free(csv); return; }
    static const char *const head[COLS] = {"part", "scene", "triangles", "config", "threads",
                                           "frame", "quantity", "median", "lo", "hi", "n"};
    for (int c = 0; c < COLS; c++) CHECKF(!strcmp(r[0].f[c], head[c]), "header field %d: %s", c, r[0].f[c]);
    for (int i = 1; i < n; i++) {
        double v[COLS];
        int ok = 1;
        for (int c = 0; c < COLS; c++)
            if (c == 2 || c >= 4) ok &= c == 6 || number(r[i].f[c], &v[c]);
        CHECKF(ok, "record %d: a numeric field is not a finite number: %s %s %s %s %s", i + 1,
               r[i].f[3], r[i].f[6], r[i].f[7], r[i].f[8], r[i].f[9]);
        if (!ok) continue;
        CHECKF(v[8] <= v[7] && v[7] <= v[9], "record %d (%s %s): lo %g, median %g, hi %g", i + 1,
               r[i].f[3], r[i].f[6], v[8], v[7], v[9]);
        if (strstr(r[i].f[6], "disagreements"))
            CHECKF(v[7] == 0, "record %d: %s of %s on %s: %g", i + 1, r[i].f[6], r[i].f[3], r[i].f[1], v[7]);
        if (!strncmp(r[i].f[6], "mrays_", 6) || !strcmp(r[i].f[6], "fps"))
            CHECKF(v[7] > 0, "record %d: %s of %s is %g", i + 1, r[i].f[6], r[i].f[3], v[7]);
    }
    /* Part 1: every configuration on both default quick scenes. */
    static const char *const scenes[2] = {"field:instances=40,detail=2",
                                          "animated:instances=8,detail=3,frame=0"};
    static const char *const configs[8] = {"bvh", "bvh:width=8", "grid", "nested_grid",
                                           "instanced:top=bvh,bottom=bvh", "instanced:top=grid,bottom=bvh",
                                           "instanced:top=bvh,bottom=grid", "instanced:top=grid,bottom=grid"};
    static const char *const q1[8] = {"build_ms", "bytes_per_tri", "bytes_read_per_tri", "mrays_primary",
                                      "mrays_shadow", "mrays_diffuse", "speed_vs_first_primary",
                                      "disagreements_diffuse"};
    for (int s = 0; s < 2; s++)
        for (int c = 0; c < 8; c++)
            for (int q = 0; q < 8; q++)
                CHECKF(count(r, n, "two_level", scenes[s], configs[c], 0, q1[q]) == 1,
                       "no single %s row for %s on %s", q1[q], configs[c], scenes[s]);
    CHECKF(count(r, n, "two_level", NULL, "instanced:world=compute", 0, "mrays_primary") == 1,
           "the control is not measured exactly once");
    /* Part 2: refit at k = 1 and 3, the update times. */
    for (int k = 1; k <= 3; k += 2) {
        CHECKF(count(r, n, "refit", NULL, NULL, k, "time_refit_over_fresh") == 1, "no refit loss at k=%d", k);
        CHECKF(count(r, n, "refit", NULL, NULL, k, "disagreements") == 1, "no refit answers at k=%d", k);
    }
    CHECK(count(r, n, "refit", NULL, NULL, 3, "bottom_ms_refit") == 1);
    CHECK(count(r, n, "refit", NULL, NULL, 3, "bottom_ms_rebuild") == 1);
    /* Part 3: three configurations (two-level, flattened, and the flattened
     * bvh's coherent mode), a fourth (that mode refit) when bvh has an
     * update, a fifth (the two-level's packets) when the fastest two-level
     * one is instanced's BVHs, 1 and (on 2 cores) 2 threads each. */
    int loops = count(r, n, "fps", NULL, NULL, -1, "fps"), two_packets = 0;
    for (int i = 1; i < n; i++)
        two_packets += !strcmp(r[i].f[0], "fps") && !strcmp(r[i].f[6], "fps") &&
                       !strncmp(r[i].f[3], "instanced", 9) && strstr(r[i].f[3], "traverse=packet");
    int nconf = 3 + (accel_find_kind("bvh")->update != NULL) + (two_packets > 0);
    CHECKF(loops == (accel_cpu_count() >= 2 ? 2 : 1) * nconf, "%d frame loops", loops);
    CHECKF(two_packets == 0 || count(r, n, "fps", NULL, NULL, -1, "frame_ratio_to_flattened_packets") == 1,
           "%d two-level packet loops, no frame ratio", two_packets);
    CHECK(count(r, n, "fps", NULL, NULL, -1, "disagreements_primary") == 1);
    CHECK(count(r, n, "fps", NULL, NULL, -1, "disagreements_shadow") == 1);
    free(csv);
    /* The verdicts: one line per claim of the section, valid labels. */
    snprintf(path, sizeof path, "%s/exp_twolevel.verdicts.csv", dir);
    char *vf = test_read_file(path, NULL);
    CHECKF(vf != NULL, "%s not written", path);
    static const char *const claims[3] = {"\nrealtime-animated,", "\ntwo-level,", "\nrefit,"};
    for (int c = 0; vf && c < 3; c++) {
        const char *p = strstr(vf, claims[c]);
        CHECKF(p != NULL, "no verdict for %s", claims[c] + 1);
        if (!p) continue;
        p += strlen(claims[c]);
        char word[64];
        snprintf(word, sizeof word, "%.*s", (int)strcspn(p, ","), p);
        CHECKF(exp_verdict_valid(word), "bad verdict: %.80s", p); /* one of claims.h's six */
    }
    free(vf);
    /* The section: findings, the footer, no nan or inf in a table. */
    snprintf(path, sizeof path, "%s/exp_twolevel.md", dir);
    char *md = test_read_file(path, NULL);
    CHECKF(md && strstr(md, "\n**Findings:**") && strstr(md, " ran in "), "%s: no findings or footer", path);
    for (char *line = md ? strtok(md, "\n") : NULL; line; line = strtok(NULL, "\n"))
        if (line[0] == '|')
            CHECKF(!nonfinite_word(line), "a table row holds nan or inf: %.200s", line);
    free(md);
    snprintf(cmd, sizeof cmd, "rm -r %s", dir);
    if (system(cmd) != 0) test_note("could not remove %s", dir);
}
