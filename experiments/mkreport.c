/*
 * mkreport - assembles REPORT.md from the experiments' outputs.
 *
 * Reads, from the output directory, every experiment's Markdown section
 * (<name>.md), its verdicts (<name>.verdicts.csv: claim, verdict,
 * evidence, scenes, section), what it left out (<name>.leftout.csv) and
 * the machine (machine.md), and writes one report: a summary table of
 * every claim of claims.c with its verdict, deciding numbers and a link to
 * its section (claims no experiment answered say so), a contents list, the
 * machine, compiler, flags, commit and run, the method, then the sections,
 * each led by its question, the lecture's words and its verdicts. Plots
 * (<name>.svg) and images (<name>.png) are linked where the sections
 * placed them. Usage (experiments/report.sh runs it):
 *   mkreport --out DIR --report FILE [--links PREFIX] [--budget TEXT]
 *            [--commit TEXT] [--flags TEXT] [--run TEXT] [--load TEXT] exp_a exp_b ...
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "claims.h"

#define MAX_ROWS 256
#define MAX_FIELDS 16

typedef struct {
    char *f[MAX_FIELDS];
    int n;
} row;

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 4096, len = 0;
    char *buf = malloc(cap);
    size_t got;
    while (buf && (got = fread(buf + len, 1, cap - len - 1, f)) > 0) {
        len += got;
        if (len + 1 == cap) {
            char *b = realloc(buf, cap *= 2);
            if (!b) free(buf);
            buf = b;
        }
    }
    fclose(f);
    if (buf) buf[len] = 0;
    return buf;
}

/* Parses RFC 4180 records (quoted fields, doubled quotes, LF or CRLF) into
 * rows; returns the count, -1 on a malformed record. */
static int parse_csv(char *s, row *rows, int max)
{
    int n = 0;
    while (*s && n < max) {
        row *r = &rows[n];
        r->n = 0;
        for (;;) {
            char *out = s, *start = s;
            if (*s == '"') {
                s++;
                for (;;) {
                    if (!*s) return -1;
                    if (*s == '"' && s[1] == '"') *out++ = '"', s += 2;
                    else if (*s == '"') { s++; break; }
                    else *out++ = *s++;
                }
            } else {
                while (*s && *s != ',' && *s != '\n' && *s != '\r') {
                    if (*s == '"') return -1;
                    *out++ = *s++;
                }
            }
            char end = *s, next = end ? s[1] : 0;
            *out = 0; /* may overwrite the separator: `end` and `next` keep it */
            if (r->n < MAX_FIELDS) r->f[r->n++] = start;
            if (end == ',') { s++; continue; }
            if (end == '\r' && next == '\n') s += 2;
            else if (end == '\n') s++;
            else if (end) return -1;
            break;
        }
        n++;
    }
    return n;
}

typedef struct {
    const char *claim, *verdict, *evidence, *scenes, *section;
} verdict;

static verdict verdicts[MAX_ROWS];
static int verdict_count;
static int left[5];

static void load_outputs(const char *dir, char **names, int count)
{
    for (int e = 0; e < count; e++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s.verdicts.csv", dir, names[e]);
        char *text = slurp(path); /* kept: the rows point into it */
        static row rows[MAX_ROWS];
        int n = text ? parse_csv(text, rows, MAX_ROWS) : 0;
        if (n < 0) fprintf(stderr, "mkreport: %s: not RFC 4180 CSV\n", path);
        for (int i = 1; i < n && verdict_count < MAX_ROWS; i++)
            if (rows[i].n == 5 || rows[i].n == 13)
                verdicts[verdict_count++] = (verdict){rows[i].f[0], rows[i].f[1], rows[i].f[2],
                                                      rows[i].f[3], rows[i].f[4]};
        snprintf(path, sizeof path, "%s/%s.leftout.csv", dir, names[e]);
        char *lo = slurp(path);
        row lr[2];
        if (lo && parse_csv(lo, lr, 2) == 2 && lr[1].n == 6)
            for (int k = 0; k < 5; k++) left[k] += atoi(lr[1].f[k + 1]);
        free(lo);
    }
}

/* A claim's verdict over its lines: the same label everywhere, or partly. */
static const char *combined(const char *claim, int *lines)
{
    const char *v = NULL;
    *lines = 0;
    for (int i = 0; i < verdict_count; i++) {
        if (strcmp(verdicts[i].claim, claim)) continue;
        (*lines)++;
        if (!v) v = verdicts[i].verdict;
        else if (strcmp(v, verdicts[i].verdict)) v = EXP_PARTLY;
    }
    return v;
}

static void summary(FILE *f)
{
    fprintf(f, "## Summary\n\nEvery claim of the lecture (../shared/LECTURE.md), every request "
               "of the user and the study's own question, with the verdict the measurements "
               "support and the numbers that decide it (medians with 95%% intervals; \"a tie\" "
               "means inside the intervals or under the section's noise floor).\n\n"
               "| # | claim | source | verdict | deciding numbers | scenes | section |\n"
               "|---|---|---|---|---|---|---|\n");
    for (int c = 0; c < exp_claim_count; c++) {
        const exp_claim *cl = &exp_claims[c];
        int lines;
        const char *v = combined(cl->id, &lines);
        fprintf(f, "| %d | **%s** (`%s`): %s | %s | ", c + 1, cl->topic, cl->id, cl->words, cl->source);
        if (!strcmp(cl->id, "leave-out")) {
            int total = left[0] + left[1] + left[2] + left[3] + left[4];
            fprintf(f, "%s | %d configurations left out, each with its reason in its section: "
                       "%d the same structure as another, %d collapsed (seconds per pass), %d "
                       "not in this build, %d pointless (e.g. brute force at minutes per pass), "
                       "%d failed builds | every scene | every section |\n",
                    EXP_CONFIRMED, total, left[0], left[1], left[2], left[3], left[4]);
            continue;
        }
        if (!v) {
            fprintf(f, "not measured in this run | the section `%s` did not run | | |\n", cl->section);
            continue;
        }
        fprintf(f, "%s | ", v);
        int k = 0;
        for (int i = 0; i < verdict_count; i++)
            if (!strcmp(verdicts[i].claim, cl->id))
                fprintf(f, "%s%s%s", k++ ? "; " : "", lines > 1 ? verdicts[i].verdict : "",
                        lines > 1 ? ": " : ""), fputs(verdicts[i].evidence, f);
        fprintf(f, " | ");
        k = 0;
        for (int i = 0; i < verdict_count; i++)
            if (!strcmp(verdicts[i].claim, cl->id)) fprintf(f, "%s%s", k++ ? "; " : "", verdicts[i].scenes);
        fprintf(f, " | [%s](#%s) |\n", cl->section, cl->section);
    }
}

/* Copies a section, the verdicts in place of its marker, links for its
 * plots and images. */
static void section(FILE *f, const char *dir, const char *name, const char *links)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.md", dir, name);
    char *md = slurp(path);
    if (!md) return;
    fprintf(f, "\n<a id=\"%s\"></a>\n\n", name);
    for (char *line = md; line && *line;) {
        char *nl = strchr(line, '\n');
        if (nl) *nl = 0;
        char tag[256];
        if (!strcmp(line, "<!-- verdicts -->")) {
            for (int i = 0; i < verdict_count; i++) {
                if (strcmp(verdicts[i].section, name)) continue;
                const exp_claim *cl = exp_claim_find(verdicts[i].claim);
                fprintf(f, "> **Verdict on %s: %s.** %s (%s).\n>\n", cl ? cl->topic : verdicts[i].claim,
                        verdicts[i].verdict, verdicts[i].evidence, verdicts[i].scenes);
            }
            fprintf(f, "> _Evidence: the tables below._\n");
        } else if (sscanf(line, "<!-- image: %255[^ ] -->", tag) == 1) {
            fprintf(f, "![%s](%s%s.png)\n", tag, links, tag);
        } else if (sscanf(line, "<!-- plot: %255[^ ] -->", tag) == 1) {
            fprintf(f, "![%s](%s%s.svg)\n", tag, links, tag);
        } else {
            fprintf(f, "%s\n", line);
        }
        line = nl ? nl + 1 : NULL;
    }
    free(md);
}

int main(int argc, char **argv)
{
    const char *dir = NULL, *out = NULL, *links = "", *budget = "full", *commit = "unknown",
               *flags = "see Makefile", *run = "", *load = "";
    char *names[64];
    int count = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: mkreport --out DIR --report FILE [--links P] [--budget T] [--commit T]\n"
                   "                [--flags T] [--run T] [--load T] exp_a exp_b ...\n"
                   "Assembles REPORT.md from the experiments' sections in DIR (experiments/report.sh\n"
                   "runs it): the claims' summary, contents, the machine, then each section.\n\n"
                   "Exit status:\n  0  success\n  2  usage error\n  3  a file cannot be read "
                   "or written\n");
            return 0;
        }
        const char **opt = !strcmp(argv[i], "--out") ? &dir : !strcmp(argv[i], "--report") ? &out
                         : !strcmp(argv[i], "--links") ? &links : !strcmp(argv[i], "--budget") ? &budget
                         : !strcmp(argv[i], "--commit") ? &commit : !strcmp(argv[i], "--flags") ? &flags
                         : !strcmp(argv[i], "--run") ? &run : !strcmp(argv[i], "--load") ? &load : NULL;
        if (opt && i + 1 < argc) *opt = argv[++i];
        else if (argv[i][0] != '-' && count < 64) names[count++] = argv[i];
        else {
            fprintf(stderr, "usage: mkreport --out DIR --report FILE [--links P] [--budget T] "
                            "[--commit T] [--flags T] [--run T] [--load T] exp_a exp_b ...\n");
            return 2;
        }
    }
    if (!dir || !out) {
        fprintf(stderr, "mkreport: --out and --report are required\n");
        return 2;
    }
    load_outputs(dir, names, count);
    char tmp[1024];
    snprintf(tmp, sizeof tmp, "%s.tmp", out);
    FILE *f = fopen(tmp, "w");
    if (!f) {
        fprintf(stderr, "mkreport: cannot write %s\n", tmp);
        return 3;
    }
    fprintf(f, "# gridbvh report\n\n_Generated by `make report` (%s budget); never edited by hand. "
               "Regenerate with `make report` (full) or `make report QUICK=1` (smoke test, "
               "writes build/quick-report/)._\n\n", budget);
    summary(f);
    fprintf(f, "\n## Contents\n\n- [Summary](#summary)\n- [Machine and method](#machine-and-method)\n");
    for (int e = 0; e < count; e++) {
        char path[1024], title[256] = "";
        snprintf(path, sizeof path, "%s/%s.md", dir, names[e]);
        FILE *m = fopen(path, "r");
        if (m && fgets(title, sizeof title, m)) title[strcspn(title, "\n")] = 0;
        if (m) fclose(m);
        fprintf(f, "- [%s](#%s)\n", title[0] == '#' ? title + 3 : names[e], names[e]);
    }
    time_t now = time(NULL);
    char date[64];
    strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", gmtime(&now));
    fprintf(f, "\n## Machine and method\n\n| | |\n|---|---|\n");
    char path[1024];
    snprintf(path, sizeof path, "%s/machine.md", dir);
    char *mach = slurp(path);
    fprintf(f, "%s", mach ? mach : "| machine | unknown |\n");
    free(mach);
    fprintf(f, "| load average | %s |\n| flags | `%s` |\n| commit | %s |\n| date | %s |\n"
               "| run | %s |\n", load, flags, commit, date, run);
    fprintf(f, "\nHow the numbers were taken. Every configuration a section compares is built "
               "and traced once counted (steps, box and primitive tests per ray: the "
               "hardware-independent counts beside every time) and once as a warm-up; then the "
               "builds and the timed traces run in interleaved rounds (A B C A B C ..., the order "
               "rotated each round), so that the drift of a shared machine falls on every "
               "configuration alike. A sample is the mean of enough back-to-back passes to last "
               "the sample time. A time is the median of its rounds with a 95%% bootstrap "
               "interval (percentile method, 2000 resamples, fixed seed); a comparison is the "
               "median of the paired per-round ratios with its interval. Each group of "
               "configurations times its first one twice per round (an A/A control): how far it "
               "strays from itself is the group's noise floor, and each section states the "
               "largest. Two numbers whose intervals overlap, or that differ by less than the "
               "floor, are a tie, never a win. Rates of rare events carry their 95%% "
               "Clopper-Pearson bound. Verdicts that rest on \"no difference\" are \"not testable "
               "here\" when the floor exceeds 25%%.\n");
    for (int e = 0; e < count; e++) section(f, dir, names[e], links);
    fclose(f);
    if (rename(tmp, out)) {
        fprintf(stderr, "mkreport: cannot rename %s\n", tmp);
        return 3;
    }
    return 0;
}
