/*
 * mdcut.h - the text pieces of bin/mkreport (issue 39's report shape):
 * reading files and RFC 4180 records, cutting text at a UTF-8 boundary,
 * and cutting a Markdown section to a number of lines. A section's lines
 * are classified (md_classify); md_drop removes, from the end backwards,
 * the lines of one class until md_emit would write at most `budget`
 * lines; md_put writes a line, cutting one over MD_MAX_CHARS with a link
 * to its full text in the appendix. Only mkreport (and its test) use it.
 */
#ifndef EXP_MDCUT_H
#define EXP_MDCUT_H

#include <stddef.h>
#include <stdio.h>

#define MD_MAX_CHARS 400 /* no line of REPORT.md is longer */
#define MD_CUT_AT 330    /* where an over-long line is cut (bytes, UTF-8 safe) */
#define MD_MAX_FIELDS 16

typedef struct {
    char *f[MD_MAX_FIELDS];
    int n;
} md_row;

/* A whole file, NUL-terminated; NULL when it cannot be read. */
char *md_slurp(const char *path);
/* Parses RFC 4180 records (quoted fields, doubled quotes, LF or CRLF) into
 * rows, in place; returns the count, -1 on a malformed record. */
int md_parse_csv(char *s, md_row *rows, int max);
/* Copies src, or its first max bytes cut at a UTF-8 boundary (at a space
 * when one is near) with an ellipsis. Returns 1 when it cut. */
int md_cut(char *dst, size_t n, const char *src, size_t max);
/* md_cut for a table cell: '|' becomes '/', newlines spaces. */
int md_cell(char *dst, size_t n, const char *src, size_t max);

typedef struct {
    char **s;
    int n, cap;
} md_lines;
void md_lines_push(md_lines *l, const char *text);
void md_lines_free(md_lines *l);

/* Where REPORT.md goes (f NULL: lines are only counted). */
typedef struct {
    FILE *f;
    int lines;
    const char *links; /* prefix of links to the appendix and plots */
} md_out;
/* Writes one line; over MD_MAX_CHARS it is cut with a link to
 * <links>appendix.md#anchor, where the full text is. */
void md_put(md_out *o, const char *line, const char *anchor);

/* The classes of a section's lines: the head (title, question, verdicts),
 * lines that always stay (footer, the first two plots, the blocks that
 * introduce the first table), the first table, the findings, the rest, and
 * what <!-- appendix --> ... <!-- /appendix --> markers hold. */
enum { K_BLANK, K_HEAD, K_KEEP, K_TABLE1, K_FIND, K_OTHER, K_APPENDIX };
void md_classify(const md_lines *l, int *kind);
/* Writes the kept lines (runs of blank lines collapsed; `note`, when not
 * NULL, after the head); returns how many. */
int md_emit(md_out *o, const md_lines *l, const int *kind, const char *keep, const char *anchor,
            const char *note);
/* Unkeeps lines of class k from the end backwards (a block at a time, a
 * line at a time for tables and findings), keeping `spare` of them, until
 * md_emit would write at most budget lines. 1 when it dropped any. */
int md_drop(const md_lines *l, const int *kind, char *keep, int k, int spare, int budget,
            const char *note);

#endif
