/*
 * mkreport - assembles REPORT.md from the experiments' outputs.
 *
 * Reads, from the output directory, every experiment's Markdown section
 * (<name>.md), its verdicts (<name>.verdicts.csv: claim, verdict,
 * evidence, scenes, section and, for exp_verdict_num, deciding, value, lo,
 * hi, threshold, sense, margin, n), what it left out (<name>.leftout.csv)
 * and the machine (machine.md), and writes two files (issue 39):
 * - REPORT.md: the first screen is the whole summary (one line per claim:
 *   verdict, ONE deciding number with its interval, n and margin, the scene
 *   with its triangle count, a link), the machine in one line, the three
 *   answers (issue 52: each answering section's <!-- answer --> block, one
 *   table and one plot), the contents, then every section cut to its share
 *   of REPORT_MAX_LINES:
 *   its head, verdicts, first table, plots, findings and footer stay;
 *   blocks inside <!-- appendix --> ... <!-- /appendix --> and, from the
 *   end backwards, the other blocks that do not fit go;
 * - appendix.md (beside the sections): every section in full, the
 *   machine record and the method. A line over MD_MAX_CHARS is cut in
 *   REPORT.md with a link to its full text there: nothing is lost silently.
 * Usage (experiments/report.sh runs it):
 *   mkreport --out DIR --report FILE [--links PREFIX] [--budget TEXT]
 *            [--commit TEXT] [--flags TEXT] [--run TEXT] [--load TEXT] exp_a exp_b ...
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "claims.h"
#include "mdcut.h"
#include "stats.h"

#define MAX_ROWS 256
#define REPORT_MAX_LINES 800
#define CELL_CHARS 190   /* a summary cell: evidence cut here */
#define SCENE_CHARS 90
/* The sections that answer the user's three questions get twice the share. */
static const char *const answers[] = {"exp_step_cost", "exp_grid_resolution", "exp_sah",
                                      "exp_binning"};

typedef struct {
    const char *claim, *verdict, *evidence, *scenes, *section, *what;
    double value, lo, hi, threshold, margin;
    int sense, n, num; /* num: the row has a deciding number (exp_verdict_num) */
} verdict;

static verdict verdicts[MAX_ROWS];
static int verdict_count;
static int left[5];

static double field_num(const char *s)
{
    return s && *s ? strtod(s, NULL) : NAN;
}

static void load_outputs(const char *dir, char **names, int count)
{
    for (int e = 0; e < count; e++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s.verdicts.csv", dir, names[e]);
        char *text = md_slurp(path); /* kept: the rows point into it */
        static md_row rows[MAX_ROWS];
        int n = text ? md_parse_csv(text, rows, MAX_ROWS) : 0;
        if (n < 0) fprintf(stderr, "mkreport: %s: not RFC 4180 CSV\n", path);
        for (int i = 1; i < n && verdict_count < MAX_ROWS; i++) {
            char **f = rows[i].f;
            if (rows[i].n != 5 && rows[i].n != 13) continue;
            verdict v = {f[0], f[1], f[2], f[3], f[4], "", NAN, NAN, NAN, NAN, NAN, 0, 0, 0};
            if (rows[i].n == 13 && f[6][0]) {
                v.what = f[5], v.value = field_num(f[6]), v.lo = field_num(f[7]);
                v.hi = field_num(f[8]), v.threshold = field_num(f[9]), v.sense = atoi(f[10]);
                v.margin = field_num(f[11]), v.n = atoi(f[12]), v.num = 1;
            }
            verdicts[verdict_count++] = v;
        }
        snprintf(path, sizeof path, "%s/%s.leftout.csv", dir, names[e]);
        char *lo = md_slurp(path);
        md_row lr[2];
        if (lo && md_parse_csv(lo, lr, 2) == 2 && lr[1].n == 6)
            for (int k = 0; k < 5; k++) left[k] += atoi(lr[1].f[k + 1]);
        free(lo);
    }
}

/* Scene sizes from the sections' headings "### ... name (N primitives)". */
typedef struct {
    char name[128];
    long tris;
} scene_size;
static scene_size sizes[96];
static int size_count;

static void note_sizes(const char *md)
{
    for (const char *p = md; (p = strstr(p, " primitives)")); p++) {
        const char *d = p;
        while (d > md && d[-1] >= '0' && d[-1] <= '9') d--;
        if (d == p || d - md < 3 || d[-1] != '(' || d[-2] != ' ') continue;
        const char *e = d - 2, *b = e;
        while (b > md && b[-1] != ' ' && b[-1] != '\n' && b[-1] != '#') b--;
        size_t len = (size_t)(e - b);
        if (!len || len >= sizeof sizes[0].name || size_count >= 96) continue;
        int seen = 0;
        for (int i = 0; i < size_count; i++)
            seen |= strlen(sizes[i].name) == len && !strncmp(sizes[i].name, b, len);
        if (seen) continue;
        memcpy(sizes[size_count].name, b, len);
        sizes[size_count].name[len] = 0;
        sizes[size_count++].tris = atol(d);
    }
}

static const char *fmt_tris(char *b, size_t n, long t)
{
    if (t < 1000) snprintf(b, n, "%ld", t);
    else if (t < 10000) snprintf(b, n, "%.1fk", t / 1e3);
    else if (t < 1000000) snprintf(b, n, "%.0fk", t / 1e3);
    else snprintf(b, n, "%.2fM", t / 1e6);
    return b;
}

/* A scenes field with each known scene's triangle count, cut to max. */
static void scene_cell(char *dst, size_t n, const char *scenes, size_t max)
{
    char buf[2048] = "", one[256], t[32];
    size_t len = 0;
    for (const char *p = scenes; *p && len < sizeof buf - 1;) {
        while (*p == ' ') p++;
        size_t k = 0; /* list items end at ", " or "; " (a scene spec holds bare commas) */
        while (p[k] && !((p[k] == ',' || p[k] == ';') && p[k + 1] == ' ')) k++;
        snprintf(one, sizeof one, "%.*s", (int)k, p);
        const char *tris = NULL;
        for (int i = 0; i < size_count; i++)
            if (!strcmp(sizes[i].name, one)) tris = fmt_tris(t, sizeof t, sizes[i].tris);
        len += (size_t)snprintf(buf + len, sizeof buf - len, "%s%s%s%s%s", len ? ", " : "", one,
                                tris ? " (" : "", tris ? tris : "", tris ? " tris)" : "");
        if (len >= sizeof buf) len = sizeof buf - 1;
        p += k;
        if (*p) p++;
    }
    md_cell(dst, n, buf, max);
}

static const char *num(char *b, size_t n, double v)
{
    double a = fabs(v);
    if (!isfinite(v)) snprintf(b, n, "n/a");
    else if (a >= 100) snprintf(b, n, "%.0f", v);
    else if (a >= 10) snprintf(b, n, "%.1f", v);
    else snprintf(b, n, "%.3g", v);
    return b;
}

/* A margin (exp_margin): the distance from the threshold to the
 * interval's near end, in percent of the threshold; 0 when the interval
 * straddles it. */
static const char *fmt_margin(char *b, size_t n, double m)
{
    if (!isfinite(m)) snprintf(b, n, "n/a");
    else if (m == 0) snprintf(b, n, "0 (straddles)");
    else snprintf(b, n, "%+.1f%%", 100 * m);
    return b;
}

/* "what: value [lo, hi] (claim >= threshold)", the same in the summary and
 * in the section (the test finds the one in the other). */
static void deciding_cell(char *dst, size_t n, const verdict *v)
{
    char a[32], b[32], c[32], d[32], what[CELL_CHARS + 8];
    md_cell(what, sizeof what, v->what, CELL_CHARS - 60);
    /* Issue 52: an interval on fewer than 6 units is never shown as 95%;
     * one of zero width from 2 or more is no interval. */
    const char *note = v->n >= 2 && !(v->hi != v->lo) ? " (zero width: not an interval)"
                       : v->n >= 2 && v->n < 6 ? " (n < 6: not a 95% interval)" : "";
    if (v->n <= 1 && v->lo == v->hi) /* an exact number (counts): no interval to show */
        snprintf(dst, n, "%s%s%s (exact) (claim %s %s)", what, what[0] ? ": " : "",
                 num(a, sizeof a, v->value), v->sense > 0 ? ">=" : v->sense < 0 ? "<=" : "vs",
                 num(d, sizeof d, v->threshold));
    else if (exp_span_unresolved(v->lo, v->hi)) /* stats.h: not printed as an interval */
        snprintf(dst, n, "%s%s%s (its interval spans more than %.0fx: not resolved) (claim %s %s)",
                 what, what[0] ? ": " : "", num(a, sizeof a, v->value), EXP_MAX_SPAN,
                 v->sense > 0 ? ">=" : v->sense < 0 ? "<=" : "vs", num(d, sizeof d, v->threshold));
    else
        snprintf(dst, n, "%s%s%s [%s, %s]%s (claim %s %s)", what, what[0] ? ": " : "",
                 num(a, sizeof a, v->value), num(b, sizeof b, v->lo), num(c, sizeof c, v->hi),
                 note, v->sense > 0 ? ">=" : v->sense < 0 ? "<=" : "vs",
                 num(d, sizeof d, v->threshold));
}

/* A claim's verdict over its lines: the study's one tally rule
 * (claims.h: exp_combine, EXP_EVERY: a claim's rows are its scenes; one
 * decisive refutation refutes); *pick: the row that makes the word
 * (exp_decisive), else the first row. */
static const char *combined(const char *claim, int *lines, int *pick)
{
    const char *words[MAX_ROWS];
    double margins[MAX_ROWS];
    int rows[MAX_ROWS];
    *lines = 0, *pick = -1;
    for (int i = 0; i < verdict_count; i++) {
        if (strcmp(verdicts[i].claim, claim)) continue;
        rows[*lines] = i;
        words[*lines] = verdicts[i].verdict;
        margins[*lines] = verdicts[i].num ? verdicts[i].margin : NAN;
        (*lines)++;
    }
    if (!*lines) return NULL;
    const char *v = exp_combine(words, *lines, EXP_EVERY);
    int k = exp_decisive(v, words, margins, *lines);
    *pick = rows[k >= 0 ? k : 0];
    return v;
}

static void summary(FILE *f)
{
    fprintf(f, "## Summary\n\nOne line per claim of the lecture (../shared/LECTURE.md), request of "
               "the user and question of the study: the verdict, the number that decides it with "
               "its interval, the processes (n) behind it and the margin\n(the distance from the "
               "claim's threshold to the interval's near end, in percent of the threshold: "
               "positive confirms, negative refutes, 0 straddles), the scene.\nA claim of several "
               "rows is refuted by one decisive refutation and confirmed only when every row "
               "confirms (claims.h: the study's one tally rule).\nRows without a deciding number "
               "quote their evidence.\n\n"
               "| # | claim | verdict | deciding number [95%% interval] | n | margin | scene |\n"
               "|---|---|---|---|---|---|---|\n");
    for (int c = 0; c < exp_claim_count; c++) {
        const exp_claim *cl = &exp_claims[c];
        int lines, pick;
        const char *v = combined(cl->id, &lines, &pick);
        if (!strncmp(cl->section, "exp_", 4))
            fprintf(f, "| %d | [%s](#%s) `%s` | ", c + 1, cl->topic, cl->section, cl->id);
        else
            fprintf(f, "| %d | %s `%s` | ", c + 1, cl->topic, cl->id);
        if (!strcmp(cl->id, "leave-out")) {
            int total = left[0] + left[1] + left[2] + left[3] + left[4];
            fprintf(f, "%s | %d configurations left out, each with its reason in its section "
                       "(%d identical, %d collapsed, %d not in this build, %d pointless, %d "
                       "failed) | | | every scene |\n", EXP_ANSWERED, total, left[0], left[1],
                    left[2], left[3], left[4]);
            continue;
        }
        if (!v) {
            fprintf(f, "not measured in this run | the section `%s` did not run | | | |\n",
                    cl->section);
            continue;
        }
        const verdict *d = &verdicts[pick];
        char cell[512], sc[SCENE_CHARS + 8], m[32] = "", nn[16] = "";
        if (d->num) {
            deciding_cell(cell, sizeof cell, d);
            fmt_margin(m, sizeof m, d->margin);
            snprintf(nn, sizeof nn, "%d", d->n);
        } else {
            md_cell(cell, sizeof cell, d->evidence, CELL_CHARS);
        }
        scene_cell(sc, sizeof sc, d->scenes, SCENE_CHARS);
        char label[64];
        if (lines > 1) snprintf(label, sizeof label, "%s (%d rows)", v, lines);
        else snprintf(label, sizeof label, "%s", v);
        fprintf(f, "%s | %s | %s | %s | %s |\n", label, cell, nn, m, sc);
    }
}
/* The verdict md_lines of section `name`: the deciding number exactly as the
 * summary shows it, then the evidence. */
static void verdict_lines(md_lines *l, const char *name)
{
    for (int i = 0; i < verdict_count; i++) {
        const verdict *v = &verdicts[i];
        if (strcmp(v->section, name)) continue;
        const exp_claim *cl = exp_claim_find(v->claim);
        char cell[512] = "", head[700] = "";
        if (v->num) {
            deciding_cell(cell, sizeof cell, v);
            char m[32];
            snprintf(head, sizeof head, "Deciding: %s; n = %d, margin %s. ", cell, v->n,
                     fmt_margin(m, sizeof m, v->margin));
        }
        size_t need = strlen(v->evidence) + strlen(v->scenes) + sizeof head + 256;
        char *t = malloc(need);
        if (!t) exit(3);
        snprintf(t, need, "> **Verdict on %s: %s.** %s%s (%s).", cl ? cl->topic : v->claim,
                 v->verdict, head, v->evidence, v->scenes);
        md_lines_push(l, t);
        md_lines_push(l, ">");
        free(t);
    }
}

static int expand(const char *dir, const char *name, const char *links, md_lines *l)
{
    char path[1024], buf[1024], tag[256];
    snprintf(path, sizeof path, "%s/%s.md", dir, name);
    char *md = md_slurp(path);
    if (!md) return -1;
    note_sizes(md);
    for (char *line = md; line && *line;) {
        char *nl = strchr(line, '\n');
        if (nl) *nl = 0;
        if (!strcmp(line, "<!-- verdicts -->")) {
            verdict_lines(l, name);
        } else if (sscanf(line, "<!-- image: %255[^ ] -->", tag) == 1) {
            snprintf(buf, sizeof buf, "![%s](%s%s.png)", tag, links, tag);
            md_lines_push(l, buf);
        } else if (sscanf(line, "<!-- plot: %255[^ ] -->", tag) == 1) {
            snprintf(buf, sizeof buf, "![%s](%s%s.svg)", tag, links, tag);
            md_lines_push(l, buf);
        } else {
            md_lines_push(l, line);
        }
        line = nl ? nl + 1 : NULL;
    }
    free(md);
    return 0;
}

/* Issue 52: a section's answer (a table and a plot between <!-- answer -->
 * and <!-- /answer -->) goes to the top of REPORT.md. take_answer moves
 * those lines from l into a (when not NULL) and leaves, in l, one line that
 * points there: a quote line after the verdicts (the head, which is never
 * cut), or where the block was when there are none. Returns the blocks. */
#define ANSWERS_ANCHOR "the-three-answers"
#define ANSWER_POINTER "> _This section's answer, one table and one plot, is at the top: " \
                       "[the three answers](#" ANSWERS_ANCHOR ")._"
static int take_answer(md_lines *l, md_lines *a)
{
    md_lines keep = {0};
    int in = 0, blocks = 0, at = -1;
    for (int i = 0; i < l->n; i++) {
        if (!strcmp(l->s[i], "<!-- answer -->")) {
            in = 1, blocks++;
            if (at < 0) at = keep.n;
            continue;
        }
        if (!strcmp(l->s[i], "<!-- /answer -->")) {
            in = 0;
            continue;
        }
        if (in && a) md_lines_push(a, l->s[i]);
        else if (!in) md_lines_push(&keep, l->s[i]);
    }
    md_lines_free(l);
    *l = (md_lines){0};
    int q = 0; /* after the first run of quote lines (the verdicts) */
    while (q < keep.n && keep.s[q][0] != '>') q++;
    while (q < keep.n && keep.s[q][0] == '>') q++;
    if (q < keep.n || (keep.n && keep.s[keep.n - 1][0] == '>')) at = q;
    for (int i = 0; i <= keep.n; i++) {
        if (blocks && i == at) md_lines_push(l, ANSWER_POINTER);
        if (i < keep.n) md_lines_push(l, keep.s[i]);
    }
    md_lines_free(&keep);
    return blocks;
}

/* A section cut to `budget` md_lines into o; the full one into the appendix. */
static void section(md_out *o, FILE *app, const char *dir, const char *name, int budget)
{
    md_lines full = {0}, l = {0};
    if (expand(dir, name, "", &full) || expand(dir, name, o->links, &l)) {
        md_lines_free(&full);
        return;
    }
    take_answer(&l, NULL); /* shown at the top (answers) */
    fprintf(app, "\n<a id=\"%s\"></a>\n\n", name);
    for (int i = 0; i < full.n; i++)
        if (strcmp(full.s[i], "<!-- appendix -->") && strcmp(full.s[i], "<!-- /appendix -->") &&
            strcmp(full.s[i], "<!-- answer -->") && strcmp(full.s[i], "<!-- /answer -->"))
            fprintf(app, "%s\n", full.s[i]);
    int *kind = calloc((size_t)l.n + 1, sizeof *kind);
    char *keep = calloc((size_t)l.n + 1, 1);
    if (!kind || !keep) exit(3);
    md_classify(&l, kind);
    int moved = 0;
    for (int i = 0; i < l.n; i++) keep[i] = kind[i] != K_APPENDIX, moved |= !keep[i];
    char note[512];
    snprintf(note, sizeof note, "_Cut to fit the report: the full section, with every table, is in "
             "[the appendix](%sappendix.md#%s)._", o->links, name);
    /* Order of sacrifice: other blocks, then findings beyond 6, then the first table beyond 12 rows. */
    moved |= md_drop(&l, kind, keep, K_OTHER, 0, budget, note);
    moved |= md_drop(&l, kind, keep, K_FIND, 8, budget, note);
    moved |= md_drop(&l, kind, keep, K_TABLE1, 14, budget, note);
    md_put(o, "", name);
    char anchor[300];
    snprintf(anchor, sizeof anchor, "<a id=\"%s\"></a>", name);
    md_put(o, anchor, name);
    md_put(o, "", name);
    md_emit(o, &l, kind, keep, name, moved ? note : NULL);
    free(kind);
    free(keep);
    md_lines_free(&full);
    md_lines_free(&l);
}

/* The value of row `key` of machine.md ("| key | value |"), or "". */
static void machine_value(const char *mach, const char *key, char *dst, size_t n)
{
    char tag[128];
    snprintf(tag, sizeof tag, "| %s | ", key);
    const char *p = mach ? strstr(mach, tag) : NULL;
    dst[0] = 0;
    if (!p) return;
    p += strlen(tag);
    size_t k = strcspn(p, "\n");
    while (k >= 2 && !strncmp(p + k - 2, " |", 2)) k -= 2;
    snprintf(dst, n, "%.*s", (int)k, p);
}

static int is_answer(const char *name)
{
    for (size_t i = 0; i < sizeof answers / sizeof answers[0]; i++)
        if (!strcmp(answers[i], name)) return 1;
    return 0;
}

/* "[title](#name)" of a section, from its first line. */
static void section_link(const char *dir, const char *name, char *dst, size_t n)
{
    char path[1024], title[256] = "";
    snprintf(path, sizeof path, "%s/%s.md", dir, name);
    FILE *m = fopen(path, "r");
    if (m && fgets(title, sizeof title, m)) title[strcspn(title, "\n")] = 0;
    if (m) fclose(m);
    char *paren = strstr(title, " (exp_");
    if (paren) *paren = 0;
    snprintf(dst, n, "[%s](#%s)", title[0] == '#' ? title + 3 : name, name);
}

/* One paragraph of section links (the answers, or the rest), its lines
 * kept short (Markdown joins them). */
static void contents(FILE *f, const char *dir, char **names, int count, int answers_)
{
    char link[512];
    int col = fprintf(f, "%s", answers_ ? "**The three answers in full:**" : "**Then:**");
    for (int e = 0, k = 0; e < count; e++) {
        if (is_answer(names[e]) != answers_) continue;
        section_link(dir, names[e], link, sizeof link);
        if (col + (int)strlen(link) > 300) fprintf(f, "\n"), col = 0;
        col += fprintf(f, "%s%s", k++ ? " \xc2\xb7 " : " ", link);
    }
    fprintf(f, ".\n\n");
}

typedef struct {
    const char *dir, *out, *links, *budget, *commit, *flags, *run, *load;
} opts;

/* The study's three answers (issue 52), right under the summary: each
 * answering section's table and plot, in the order of the sections, with a
 * link to the section. Nothing when no section has an answer block. */
static void top_answers(md_out *o, const opts *op, char **names, int count)
{
    int head = 0;
    for (int e = 0; e < count; e++) {
        md_lines l = {0}, a = {0};
        if (!is_answer(names[e]) || expand(op->dir, names[e], op->links, &l) ||
            !take_answer(&l, &a) || !a.n) {
            md_lines_free(&l), md_lines_free(&a);
            continue;
        }
        if (!head++) {
            md_put(o, "", ANSWERS_ANCHOR);
            md_put(o, "<a id=\"" ANSWERS_ANCHOR "\"></a>", ANSWERS_ANCHOR);
            md_put(o, "", ANSWERS_ANCHOR);
            md_put(o, "## The three answers", ANSWERS_ANCHOR);
            md_put(o, "", ANSWERS_ANCHOR);
            md_put(o, "The study's three questions, each answered by one table and one plot; "
                      "the verdicts are in the summary above, the sections below hold the rest.",
                   ANSWERS_ANCHOR);
        }
        int blank = 0;
        for (int i = 0; i < a.n; i++) {
            if (!a.s[i][0] && blank) continue; /* blank runs collapsed */
            blank = !a.s[i][0];
            md_put(o, a.s[i], names[e]);
        }
        char link[512], line[700];
        section_link(op->dir, names[e], link, sizeof link);
        snprintf(line, sizeof line, "The full section: %s.", link);
        if (!blank) md_put(o, "", names[e]);
        md_put(o, line, names[e]);
        md_lines_free(&l), md_lines_free(&a);
    }
}

/* The head, the summary, the machine line, the contents and the short
 * machine table: everything before the sections. */
static void front(md_out *o, FILE *app, const opts *op, char **names, int count)
{
    FILE *f = o->f;
    char path[1024], cpu[256], isa[256], cores[256];
    snprintf(path, sizeof path, "%s/machine.md", op->dir);
    char *mach = md_slurp(path);
    machine_value(mach, "machine", cpu, sizeof cpu);
    machine_value(mach, "kernel ISA", isa, sizeof isa);
    machine_value(mach, "cores", cores, sizeof cores);
    fprintf(f, "# gridbvh report\n\n_Generated by `make report` (%s budget); never edited by hand. "
               "Per-scene tables, long lists and the full sections: [appendix](%sappendix.md)._\n\n",
            op->budget, op->links);
    summary(f);
    cores[strcspn(cores, ":")] = 0;
    fprintf(f, "\n**Machine:** %s, %s; kernels: %s. Commit %s.\n", cpu[0] ? cpu : "unknown",
            cores[0] ? cores : "unknown CPUs", isa[0] ? isa : "not recorded", op->commit);
    top_answers(o, op, names, count);
    fprintf(f, "\n## Contents\n\n");
    contents(f, op->dir, names, count, 1);
    contents(f, op->dir, names, count, 0);
    time_t now = time(NULL);
    char date[64];
    strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", gmtime(&now));
    fprintf(app, "# gridbvh report: appendix\n\nThe full sections of [the report](REPORT.md), with "
                 "every table; the report keeps each section's head, verdicts, first table, plots "
                 "and findings.\n\n<a id=\"machine-and-method\"></a>\n\n## Machine and method\n\n"
                 "| | |\n|---|---|\n%s", mach ? mach : "| machine | unknown |\n");
    fprintf(f, "\n## Machine and method\n\n| | |\n|---|---|\n");
    /* Rows of any length (flags, the run record with its options) go through
     * md_put: over the limit, cut with their full text in the appendix. */
    const char *key[7] = {"machine", "kernel ISA", "load average", "flags", "commit", "date", "run"};
    const char *val[7] = {cpu, isa, op->load, op->flags, op->commit, date, op->run};
    for (int i = 0; i < 7; i++) {
        size_t need = strlen(val[i]) + 64;
        char *row = malloc(need);
        if (!row) exit(3);
        snprintf(row, need, i == 3 ? "| %s | `%s` |" : "| %s | %s |", key[i], val[i]);
        md_put(&(md_out){f, 0, op->links}, row, "machine-and-method");
        if (i >= 2) fprintf(app, "%s\n", row); /* the run's own rows, in full */
        free(row);
    }
    fprintf(f, "\nThe full machine record and how the numbers were taken (rounds, intervals, noise "
               "floors, ties): [appendix](%sappendix.md#machine-and-method).\n", op->links);
    fprintf(app, "\nHow the numbers were taken. Every configuration a section compares is built "
               "and traced once counted (steps, box and primitive tests per ray: the "
               "hardware-independent counts beside every time) and once as a warm-up; then the "
               "builds and the timed traces run in interleaved rounds (A B C A B C ..., the order "
               "rotated each round), so that the drift of a shared machine falls on every "
               "configuration alike. A sample is the mean of enough back-to-back passes to last "
               "the sample time. A time is the median of its rounds with its 95%% interval; a "
               "comparison is the median of the paired per-round ratios with its interval. Each "
               "group of configurations times its first one twice per round (an A/A control): how "
               "far it strays from itself is the group's noise floor, and each section states the "
               "largest. Two numbers whose intervals overlap, or that differ by less than the "
               "floor, are a tie, never a win. Rates of rare events carry their 95%% "
               "Clopper-Pearson bound.\n");
    free(mach);
}

static int usage(void)
{
    fprintf(stderr, "usage: mkreport --out DIR --report FILE [--links P] [--budget T] "
                    "[--commit T] [--flags T] [--run T] [--load T] exp_a exp_b ...\n");
    return 2;
}

int main(int argc, char **argv)
{
    opts op = {NULL, NULL, "", "full", "unknown", "see Makefile", "", ""};
    char *names[64];
    int count = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: mkreport --out DIR --report FILE [--links P] [--budget T] [--commit T]\n"
                   "                [--flags T] [--run T] [--load T] exp_a exp_b ...\n"
                   "Assembles REPORT.md (at most %d md_lines of at most %d characters: the summary,\n"
                   "the machine, each section cut to its share) and DIR/appendix.md (every section\n"
                   "in full) from the experiments' sections in DIR (experiments/report.sh runs it).\n\n"
                   "Exit status:\n  0  success\n  2  usage error\n  3  a file cannot be read "
                   "or written\n", REPORT_MAX_LINES, MD_MAX_CHARS);
            return 0;
        }
        const char **opt = !strcmp(argv[i], "--out") ? &op.dir : !strcmp(argv[i], "--report") ? &op.out
                         : !strcmp(argv[i], "--links") ? &op.links : !strcmp(argv[i], "--budget") ? &op.budget
                         : !strcmp(argv[i], "--commit") ? &op.commit : !strcmp(argv[i], "--flags") ? &op.flags
                         : !strcmp(argv[i], "--run") ? &op.run : !strcmp(argv[i], "--load") ? &op.load : NULL;
        if (opt && i + 1 < argc) *opt = argv[++i];
        else if (argv[i][0] != '-' && count < 64) names[count++] = argv[i];
        else return usage();
    }
    if (!op.dir || !op.out) {
        fprintf(stderr, "mkreport: --md_out and --report are required\n");
        return 2;
    }
    load_outputs(op.dir, names, count);
    for (int e = 0; e < count; e++) { /* the scene sizes the summary names */
        md_lines l = {0};
        expand(op.dir, names[e], "", &l);
        md_lines_free(&l);
    }
    char tmp[1024], app_path[1024];
    snprintf(tmp, sizeof tmp, "%s.tmp", op.out);
    snprintf(app_path, sizeof app_path, "%s/appendix.md", op.dir);
    FILE *f = fopen(tmp, "w"), *app = fopen(app_path, "w");
    if (!f || !app) {
        fprintf(stderr, "mkreport: cannot write %s or %s\n", tmp, app_path);
        return 3;
    }
    fflush(f);
    front(&(md_out){f, 0, op.links}, app, &op, names, count);
    fflush(f);
    md_out o = {f, 0, op.links};
    /* What the front used, then each section's share (answers count twice). */
    FILE *r = fopen(tmp, "r");
    for (int c; r && (c = fgetc(r)) != EOF;) o.lines += c == '\n';
    if (r) fclose(r);
    int weight = 0;
    for (int e = 0; e < count; e++) weight += 1 + is_answer(names[e]);
    int room = REPORT_MAX_LINES - 10 - o.lines - 4 * count;
    for (int e = 0; e < count; e++) {
        int share = weight ? room * (1 + is_answer(names[e])) / weight : room;
        section(&o, app, op.dir, names[e], share < 16 ? 16 : share);
    }
    fclose(app);
    if (fclose(f) || rename(tmp, op.out)) {
        fprintf(stderr, "mkreport: cannot write %s\n", op.out);
        return 3;
    }
    return 0;
}
