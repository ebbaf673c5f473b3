/*
 * mdcut.c - the text pieces of bin/mkreport (mdcut.h): files, RFC 4180
 * records, and cutting a Markdown section to a number of lines.
 */
#include <stdlib.h>
#include <string.h>

#include "mdcut.h"

char *md_slurp(const char *path)
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
int md_parse_csv(char *s, md_row *rows, int max)
{
    int n = 0;
    while (*s && n < max) {
        md_row *r = &rows[n];
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
            if (r->n < MD_MAX_FIELDS) r->f[r->n++] = start;
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



void md_lines_push(md_lines *l, const char *text)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 256;
        char **s = realloc(l->s, (size_t)cap * sizeof *s);
        if (!s) exit(3);
        l->s = s, l->cap = cap;
    }
    l->s[l->n] = strdup(text);
    if (!l->s[l->n]) exit(3);
    l->n++;
}

void md_lines_free(md_lines *l)
{
    for (int i = 0; i < l->n; i++) free(l->s[i]);
    free(l->s);
    memset(l, 0, sizeof *l);
}

/* Copies at most max bytes of src, cut at a UTF-8 boundary (and a space
 * when one is near) with an ellipsis; returns 1 when it cut. */
int md_cut(char *dst, size_t n, const char *src, size_t max)
{
    size_t len = strlen(src);
    if (len <= max || max + 4 > n) {
        snprintf(dst, n, "%s", src);
        return 0;
    }
    size_t k = max;
    while (k > 0 && ((unsigned char)src[k] & 0xC0) == 0x80) k--;
    size_t sp = k;
    while (sp > max * 3 / 4 && src[sp] != ' ') sp--;
    if (src[sp] == ' ') k = sp;
    snprintf(dst, n, "%.*s\xe2\x80\xa6", (int)k, src);
    return 1;
}

int md_cell(char *dst, size_t n, const char *src, size_t max)
{
    int cut = md_cut(dst, n, src, max);
    for (char *s = dst; *s; s++)
        if (*s == '|') *s = '/';
        else if (*s == '\n' || *s == '\r') *s = ' ';
    return cut;
}


void md_put(md_out *o, const char *line, const char *anchor)
{
    o->lines++;
    if (!o->f) return;
    if (strlen(line) <= MD_MAX_CHARS) {
        fprintf(o->f, "%s\n", line);
        return;
    }
    /* The cut line with its link stays within MD_MAX_CHARS bytes: the
     * text gets what the link and the ellipsis (3 bytes) leave, at most
     * MD_CUT_AT. */
    char link[256], cut[MD_CUT_AT + 8];
    snprintf(link, sizeof link, " [cut: full text in the appendix](%sappendix.md#%s)", o->links,
             anchor);
    size_t room = strlen(link) + 3 < MD_MAX_CHARS ? MD_MAX_CHARS - strlen(link) - 3 : 0;
    md_cut(cut, sizeof cut, line, room < MD_CUT_AT ? room : MD_CUT_AT);
    fprintf(o->f, "%s%s\n", cut, link);
}


void md_classify(const md_lines *l, int *kind)
{
    int head = 1, appendix = 0, table = 0, find = 0, plots = 0;
    for (int i = 0; i < l->n; i++) {
        const char *s = l->s[i];
        if (!strcmp(s, "<!-- appendix -->") || !strcmp(s, "<!-- /appendix -->")) {
            appendix = s[5] != '/';
            kind[i] = K_APPENDIX;
            continue;
        }
        if (appendix) { kind[i] = K_APPENDIX; continue; }
        if (!*s) { kind[i] = K_BLANK; continue; }
        if (head && (s[0] == '|' || !strncmp(s, "### ", 4) || (i > 0 && !strncmp(s, "**", 2) &&
                     strncmp(s, "**Question", 10) && strncmp(s, "**In the", 8))))
            head = 0;
        if (head || s[0] == '>') { kind[i] = K_HEAD; continue; }
        if (!strncmp(s, "**Findings", 10)) find = 1;
        else if (find && strncmp(s, "- ", 2)) find = 0;
        if (find) { kind[i] = K_FIND; continue; }
        if (s[0] == '_' && (strstr(s, " ran in ") || strstr(s, "Noise floor of this section"))) {
            kind[i] = K_KEEP;
            continue;
        }
        if (!strncmp(s, "![", 2) && strstr(s, ".svg)") && plots < 2) {
            plots++;
            kind[i] = K_KEEP;
            continue;
        }
        if (s[0] == '|' && table <= 1) {
            table = 1;
            kind[i] = K_TABLE1;
            continue;
        }
        if (table == 1) table = 2;
        kind[i] = K_OTHER;
    }
    /* The two short blocks before the first table (its scene heading, its
     * caption) stay with it. */
    int t = 0;
    while (t < l->n && kind[t] != K_TABLE1) t++;
    for (int b = 0, i = t - 1; b < 2 && i >= 0; b++) {
        while (i >= 0 && (kind[i] == K_BLANK || kind[i] == K_APPENDIX)) i--;
        int j = i;
        while (j >= 0 && kind[j] == K_OTHER) j--;
        if (j == i || i - j > 3) break;
        for (int q = j + 1; q <= i; q++) kind[q] = K_KEEP;
        i = j;
    }
}

/* Emits the kept lines (blank runs collapsed); returns the count. */
int md_emit(md_out *o, const md_lines *l, const int *kind, const char *keep, const char *anchor,
                const char *note)
{
    int before = o->lines, blank = 1, noted = !note;
    for (int i = 0; i < l->n; i++) {
        if (!keep[i]) continue;
        if (!noted && kind[i] != K_HEAD && kind[i] != K_BLANK) {
            md_put(o, note, anchor), md_put(o, "", anchor), noted = 1, blank = 1;
        }
        if (kind[i] == K_BLANK) {
            if (!blank) md_put(o, "", anchor);
            blank = 1;
            continue;
        }
        md_put(o, l->s[i], anchor);
        blank = 0;
    }
    if (!blank) md_put(o, "", anchor);
    return o->lines - before;
}

/* Drops md_lines of `kind` k from the end backwards, a block (md_lines between
 * blanks) at a time, until the section fits `budget`; keeps `spare`
 * md_lines of that kind. Returns 1 when it dropped any. */
int md_drop(const md_lines *l, const int *kind, char *keep, int k, int spare, int budget,
                const char *note)
{
    int dropped = 0, have = 0;
    for (int i = 0; i < l->n; i++) have += keep[i] && kind[i] == k;
    for (int i = l->n - 1; i >= 0 && have > spare; i--) {
        md_out count = {NULL, 0, ""};
        if (md_emit(&count, l, kind, keep, "", note) <= budget) break;
        if (!keep[i] || kind[i] != k) continue;
        /* a table row: one at a time; anything else: the whole block */
        int j = i;
        if (k != K_TABLE1 && k != K_FIND)
            while (j > 0 && kind[j - 1] == k && keep[j - 1]) j--;
        for (int q = j; q <= i && have > spare; q++) keep[q] = 0, have--, dropped = 1;
        i = j;
    }
    /* A kept line that introduces what follows (it ends with ':') goes
     * with it when what follows went: no caption over nothing. */
    for (int i = 0; i < l->n; i++) {
        size_t len = strlen(l->s[i]);
        if (!keep[i] || kind[i] != K_OTHER || !len || l->s[i][len - 1] != ':') continue;
        int j = i + 1;
        while (j < l->n && kind[j] == K_BLANK) j++;
        if (j < l->n && !keep[j]) keep[i] = 0, dropped = 1;
    }
    return dropped;
}

