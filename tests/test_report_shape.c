/*
 * test_report_shape.c - issue 39's limits on the report a reader gets:
 * REPORT.md at most 800 lines, no line over 400 characters, the whole
 * summary within the first 60 lines, the user's three questions (step
 * cost, grid resolution, SAH and binning) answered right under it, each by
 * one table and one plot (issue 52), and every number of a summary row present in the section
 * it links to. Checked on the quick report (build/quick-report, made once
 * for all the report tests), and mkreport's cutting (mdcut.h) on a
 * section made up here, where the answer is known.
 */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "test.h"
#include "experiments/engine/claims.h"
#include "experiments/engine/mdcut.h"

#define REPORT "build/quick-report/REPORT.md"

/* Characters (UTF-8 code points) of the line starting at p. */
static size_t line_chars(const char *p)
{
    size_t n = 0;
    for (; *p && *p != '\n'; p++) n += ((unsigned char)*p & 0xC0) != 0x80;
    return n;
}

/* The text of section `name` in the report: from its anchor to the next. */
static char *section_of(const char *r, const char *name)
{
    char tag[160];
    snprintf(tag, sizeof tag, "<a id=\"%s\"></a>", name);
    const char *a = strstr(r, tag);
    if (!a) return NULL;
    const char *b = strstr(a + strlen(tag), "<a id=\"");
    size_t n = b ? (size_t)(b - a) : strlen(a);
    char *s = malloc(n + 1);
    if (s) memcpy(s, a, n), s[n] = 0;
    return s;
}

TEST(report_shape_limits)
{
    if (!test_quick_report()) return;
    char *r = test_read_file(REPORT, NULL);
    CHECKF(r != NULL, REPORT " missing");
    if (!r) return;
    int lines = 0, summary_end = 0, long_lines = 0;
    for (char *p = r; *p;) {
        lines++;
        size_t c = line_chars(p);
        if (c > MD_MAX_CHARS && long_lines++ < 3)
            CHECKF(0, "line %d has %zu characters: %.120s", lines, c, p);
        char *nl = strchr(p, '\n');
        /* a summary row: a table row that links to its section (on this
         * line: the tables under the summary link nowhere) */
        const char *link = strstr(p, "](#");
        if (!strncmp(p, "| ", 2) && lines < 100 && link && (!nl || link < nl)) summary_end = lines;
        p = nl ? nl + 1 : p + strlen(p);
    }
    CHECKF(lines <= 800, "REPORT.md has %d lines (at most 800)", lines);
    CHECKF(long_lines == 0, "%d lines over %d characters", long_lines, MD_MAX_CHARS);
    /* The summary: a row for every claim, all within the first 60 lines. */
    CHECKF(summary_end > 0 && summary_end <= 60, "the summary ends on line %d", summary_end);
    const char *contents = strstr(r, "## Contents");
    for (int c = 0; c < exp_claim_count; c++) {
        char tag[96];
        snprintf(tag, sizeof tag, " `%s` |", exp_claims[c].id);
        const char *row = strstr(r, tag);
        CHECKF(row && (!contents || row < contents), "no summary row for %s", exp_claims[c].id);
    }
    /* The three questions (issue 52): answered right under the summary, in
     * "## The three answers", each by one table and one plot and a link to
     * its section: step cost on equal terms (C_intersect fixed), grid
     * resolution, SAH and binning on every scene exp_sah measured. */
    const char *top = strstr(r, "\n## The three answers\n");
    CHECKF(top != NULL, "no \"## The three answers\" section in the report");
    CHECKF(top && contents && top < contents, "the three answers are not before the contents");
    int top_line = 1;
    for (const char *p = r; top && p < top; p++) top_line += *p == '\n';
    CHECKF(top && top_line <= 70, "the three answers start on line %d (at most 70)", top_line);
    static const char *const answers[3] = {"exp_step_cost", "exp_grid_resolution", "exp_sah"};
    const char *from = top;
    for (int i = 0; i < 3 && from; i++) {
        char link[96];
        snprintf(link, sizeof link, "The full section: [");
        const char *end = strstr(from, link);
        CHECKF(end != NULL, "answer %d (%s): no link to its section", i + 1, answers[i]);
        if (!end) break;
        const char *eol = strchr(end, '\n');
        size_t n = (size_t)(end - from);
        char *blk = malloc(n + 1);
        if (!blk) break;
        memcpy(blk, from, n), blk[n] = 0;
        snprintf(link, sizeof link, "(#%s)", answers[i]);
        CHECKF(eol && strstr(end, link) && strstr(end, link) < eol,
               "answer %d links elsewhere than %s: %.100s", i + 1, answers[i], end);
        int tables = 0;
        for (const char *p = blk; (p = strstr(p, "\n|---")); p++) tables++;
        CHECKF(tables == 1, "%s's answer has %d tables (one)", answers[i], tables);
        CHECKF(strstr(blk, ".svg)") != NULL, "%s's answer has no plot", answers[i]);
        if (i == 0)
            CHECKF(strstr(blk, "C_intersect ns (fixed)") != NULL,
                   "the step-cost answer is not the equal-terms table (C_intersect fixed)");
        if (i == 2) { /* one row per scene of exp_sah's speed-up table */
            char *csv = test_read_file("build/quick-report/exp_sah_speedup.csv", NULL);
            int scenes = 0, rows = 0;
            char seen[16][128];
            for (char *p = csv ? strchr(csv, '\n') : NULL; p && p[1]; p = strchr(p + 1, '\n')) {
                char sc[128];
                if (sscanf(p + 1, "%127[^,]", sc) != 1) continue;
                int k = 0;
                while (k < scenes && strcmp(seen[k], sc)) k++;
                if (k == scenes && scenes < 16) snprintf(seen[scenes++], sizeof seen[0], "%s", sc);
            }
            const char *t = strstr(blk, "\n|---");
            for (const char *p = t ? strchr(t + 1, '\n') : NULL; p && p[1] == '|'; p = strchr(p + 1, '\n'))
                rows++;
            CHECKF(csv && scenes > 0 && rows == scenes, "the SAH answer has %d rows for %d scenes",
                   rows, scenes);
            free(csv);
        }
        free(blk);
        from = eol;
    }
    /* Each answering section still has a table and a plot of its own, and
     * points to its answer at the top. */
    static const char *const sections[4] = {"exp_step_cost", "exp_grid_resolution", "exp_sah",
                                            "exp_binning"};
    for (int i = 0; i < 4; i++) {
        char *s = section_of(r, sections[i]);
        CHECKF(s && strstr(s, "\n|---") && strstr(s, ".svg)"), "%s: no table or no plot",
               sections[i]);
        if (i < 3)
            CHECKF(s && strstr(s, "(#the-three-answers)"), "%s does not point to its answer",
                   sections[i]);
        free(s);
    }
    free(r);
}

/* Every number of a summary row's deciding cell (after the claim cell) is
 * in the section the row links to. */
static void check_row_numbers(const char *r, const char *row)
{
    char line[1024];
    snprintf(line, sizeof line, "%.*s", (int)strcspn(row, "\n"), row);
    const char *link = strstr(line, "](#");
    if (!link) return;
    char name[128];
    if (sscanf(link + 3, "%127[^)]", name) != 1) return;
    char *sec = section_of(r, name);
    if (!sec) return; /* "not measured in this run" has no section */
    /* the cells after the claim cell: verdict, deciding, n, margin (not the scenes) */
    const char *p = strchr(link, '|');
    int checked = 0;
    for (int cell = 0; p && cell < 4; cell++, p = strchr(p + 1, '|')) {
        const char *end = strchr(p + 1, '|');
        if (!end) break;
        for (const char *q = p + 1; q < end; q++) {
            if (!isdigit((unsigned char)*q) || (q > line && (isalnum((unsigned char)q[-1]) ||
                                                             q[-1] == '.' || q[-1] == '_' || q[-1] == '=')))
                continue;
            const char *e = q;
            while (e < end && (isdigit((unsigned char)*e) || *e == '.')) e++;
            if (e[-1] == '.') e--;
            if (memchr(q, '.', (size_t)(e - q)) || *e == '%' || *e == ']' || *e == ',') {
                char tok[64];
                snprintf(tok, sizeof tok, "%.*s", (int)(e - q), q);
                CHECKF(strstr(sec, tok) != NULL, "summary number %s is not in section %s: %.200s",
                       tok, name, line);
                checked++;
            }
            q = e;
        }
    }
    (void)checked;
    free(sec);
}

TEST(report_shape_summary_numbers_in_sections)
{
    if (!test_quick_report()) return;
    char *r = test_read_file(REPORT, NULL);
    if (!r) {
        test_fail(__FILE__, __LINE__, REPORT " missing after the quick report ran");
        return;
    }
    const char *sum = strstr(r, "## Summary"), *end = strstr(r, "## Contents");
    CHECK(sum && end && sum < end);
    int rows = 0;
    for (const char *p = sum; p && end && p < end; p = strchr(p, '\n'), p = p ? p + 1 : NULL)
        if (p[0] == '|' && isdigit((unsigned char)p[2]))
            check_row_numbers(r, p), rows++;
    CHECKF(rows >= exp_claim_count, "%d summary rows for %d claims", rows, exp_claim_count);
    free(r);
}

/* mdcut on a section made up here: 3 scene blocks of 10-row tables,
 * findings, a footer. Cut to 30 lines it keeps the head, the first table,
 * the findings and the footer, and drops the later scenes from the end. */
TEST(report_shape_cut_section)
{
    md_lines l = {0};
    md_lines_push(&l, "## A section (exp_x)");
    md_lines_push(&l, "");
    md_lines_push(&l, "**Question:** q");
    md_lines_push(&l, "");
    md_lines_push(&l, "> **Verdict on x: confirmed.** 1.5 [1.2, 1.8]");
    md_lines_push(&l, "");
    for (int s = 0; s < 3; s++) {
        char b[64];
        snprintf(b, sizeof b, "### scene%d (%d primitives)", s, 1000 * (s + 1));
        md_lines_push(&l, b);
        md_lines_push(&l, "");
        md_lines_push(&l, "| a | b |");
        md_lines_push(&l, "|---|---|");
        for (int i = 0; i < 10; i++) {
            snprintf(b, sizeof b, "| s%d row%d | %d |", s, i, i);
            md_lines_push(&l, b);
        }
        md_lines_push(&l, "");
    }
    md_lines_push(&l, "<!-- appendix -->");
    md_lines_push(&l, "a long list");
    md_lines_push(&l, "<!-- /appendix -->");
    md_lines_push(&l, "");
    md_lines_push(&l, "**Findings:**");
    md_lines_push(&l, "");
    md_lines_push(&l, "- one.");
    md_lines_push(&l, "- two.");
    md_lines_push(&l, "");
    md_lines_push(&l, "_exp_x ran in 1.0 s._");
    int kind[128];
    char keep[128];
    md_classify(&l, kind);
    for (int i = 0; i < l.n; i++) keep[i] = kind[i] != K_APPENDIX;
    CHECK(md_drop(&l, kind, keep, K_OTHER, 0, 30, "note") == 1);
    md_out count = {NULL, 0, ""};
    int n = md_emit(&count, &l, kind, keep, "exp_x", "note");
    CHECKF(n <= 30, "cut to %d lines, not 30", n);
    int head = 0, s0 = 0, s2 = 0, find = 0, foot = 0, list = 0;
    for (int i = 0; i < l.n; i++) {
        if (!keep[i]) continue;
        head |= strstr(l.s[i], "Verdict on x") != NULL;
        s0 |= !strcmp(l.s[i], "| s0 row9 | 9 |");
        s2 |= strstr(l.s[i], "s2 row") != NULL;
        find |= !strcmp(l.s[i], "- two.");
        foot |= strstr(l.s[i], " ran in ") != NULL;
        list |= !strcmp(l.s[i], "a long list");
    }
    CHECK(head && s0 && find && foot);
    CHECKF(!s2 && !list, "the last scene (%d) or the appendix block (%d) stayed", s2, list);
    CHECK(kind[6] == K_KEEP); /* the first table's scene heading stays with it */
    /* A line over the limit is cut, with a link to the full text. */
    char longline[1200];
    memset(longline, 'x', sizeof longline - 1);
    longline[sizeof longline - 1] = 0;
    FILE *f = tmpfile();
    md_out o = {f, 0, "report/"};
    md_put(&o, longline, "exp_x");
    rewind(f);
    char back[1300] = "";
    CHECK(f && fgets(back, sizeof back, f));
    CHECKF(line_chars(back) <= MD_MAX_CHARS && strstr(back, "report/appendix.md#exp_x"),
           "cut line: %zu characters", line_chars(back));
    if (f) fclose(f);
    md_lines_free(&l);
}
