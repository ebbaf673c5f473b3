/*
 * cli.c - table-driven option parsing and help (see cli.h).
 */
#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "image/image.h"

int cli_exit_of(int accel_status)
{
    switch (accel_status) {
    case ACCEL_OK: return CLI_EXIT_OK;
    case ACCEL_ERR_SPEC: return CLI_EXIT_USAGE;
    case ACCEL_ERR_IO:
    case ACCEL_ERR_PARSE:
    case ACCEL_ERR_RANGE: return CLI_EXIT_INPUT;
    default: return CLI_EXIT_INTERNAL;
    }
}

void cli_help_exit_codes(FILE *f)
{
    fprintf(f, "Exit status:\n"
               "  0  success\n"
               "  1  results disagree (--check against the reference, trace compare)\n"
               "  2  usage error: unknown option, bad number, spec, ray set name or camera\n"
               "  3  input error: a file cannot be read or written, a bad or empty scene\n"
               "  4  internal error: a broken traversal invariant in a counted run, out of "
               "memory\n");
}

static int arg_count(const cli_option *o)
{
    if (!o->arg) return 0;
    int n = 1;
    for (const char *p = o->arg; *p; p++) n += *p == ' ';
    return n;
}

int cli_parse(const cli_option *table, size_t n, int argc, char **argv, int first, void *opts,
              accel_error *err)
{
    for (int i = first; i < argc; i++) {
        const char *a = !strcmp(argv[i], "-h") ? "--help" : argv[i];
        const cli_option *o = NULL;
        for (size_t k = 0; k < n && !o; k++)
            if (!strcmp(table[k].name, a)) o = &table[k];
        if (!o) return accel_fail(err, ACCEL_ERR_SPEC, "unknown option '%s' (see --help)", argv[i]);
        int na = arg_count(o);
        if (i + na >= argc)
            return accel_fail(err, ACCEL_ERR_SPEC, "option %s needs %s", o->name, o->arg);
        int rc = o->parse(o, (char *)opts + o->offset, argv + i + 1, err);
        if (rc) return rc;
        i += na;
    }
    return 0;
}

void cli_help(FILE *f, const cli_option *table, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        const cli_option *o = &table[k];
        char head[96];
        snprintf(head, sizeof head, "%s%s%s", o->name, o->arg ? " " : "", o->arg ? o->arg : "");
        /* Help lines after the first align under the first. */
        fprintf(f, "  %-22s", head);
        if (strlen(head) > 22) fprintf(f, "\n  %-22s", "");
        for (const char *p = o->help; *p; p++) {
            fputc(*p, f);
            if (*p == '\n' && p[1]) fprintf(f, "  %-22s", "");
        }
        fputc('\n', f);
    }
}

int cli_to_long(const char *s, long lo, long hi, long *out)
{
    if (!*s || isspace((unsigned char)*s)) return 0;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (*end || errno || v < lo || v > hi) return 0;
    *out = v;
    return 1;
}

int cli_to_double(const char *s, double lo, double hi, double *out)
{
    if (!*s || isspace((unsigned char)*s)) return 0;
    char *end;
    double v = strtod(s, &end);
    if (*end || !isfinite(v) || v < lo || v > hi) return 0;
    *out = v;
    return 1;
}

int cli_flag(const cli_option *o, void *field, char **v, accel_error *err)
{
    (void)o, (void)v, (void)err;
    *(int *)field = 1;
    return 0;
}

int cli_unflag(const cli_option *o, void *field, char **v, accel_error *err)
{
    (void)o, (void)v, (void)err;
    *(int *)field = 0;
    return 0;
}

int cli_string(const cli_option *o, void *field, char **v, accel_error *err)
{
    if (!v[0][0]) return accel_fail(err, ACCEL_ERR_SPEC, "%s: empty %s", o->name, o->arg);
    *(const char **)field = v[0];
    return 0;
}

int cli_int(const cli_option *o, void *field, char **v, accel_error *err)
{
    long x;
    if (!cli_to_long(v[0], (long)o->lo, (long)o->hi, &x))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected a whole number in %.0f..%.0f",
                          o->name, v[0], o->lo, o->hi);
    *(int *)field = (int)x;
    return 0;
}

int cli_u64(const cli_option *o, void *field, char **v, accel_error *err)
{
    const char *s = v[0];
    char *end;
    errno = 0;
    unsigned long long x = isdigit((unsigned char)s[0]) ? strtoull(s, &end, 10) : 0;
    if (!isdigit((unsigned char)s[0]) || *end || errno)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected a whole number in 0..2^64-1",
                          o->name, s);
    *(uint64_t *)field = (uint64_t)x;
    return 0;
}

int cli_double(const cli_option *o, void *field, char **v, accel_error *err)
{
    double x;
    if (!cli_to_double(v[0], o->lo, o->hi, &x))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected a number in [%g, %g]", o->name,
                          v[0], o->lo, o->hi);
    *(double *)field = x;
    return 0;
}

int cli_float(const cli_option *o, void *field, char **v, accel_error *err)
{
    double x = 0;
    int rc = cli_double(o, &x, v, err);
    if (rc == 0) *(float *)field = (float)x;
    return rc;
}

int cli_vec(const cli_option *o, void *field, char **v, accel_error *err)
{
    cli_vec3 *dst = field;
    double c[3];
    const char *p = v[0];
    for (int i = 0; i < 3; i++) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        char num[64];
        if ((i < 2) != (end != NULL) || len >= sizeof num)
            return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected X,Y,Z", o->name, v[0]);
        memcpy(num, p, len);
        num[len] = 0;
        if (!cli_to_double(num, -FLT_MAX, FLT_MAX, &c[i]))
            return accel_fail(err, ACCEL_ERR_SPEC,
                              "%s %s: expected X,Y,Z, three numbers each a finite float (at most "
                              "3.4e38 in size)", o->name, v[0]);
        p = end ? end + 1 : p + len;
    }
    dst->v = v3((float)c[0], (float)c[1], (float)c[2]);
    dst->given = 1;
    return 0;
}

int cli_size(const cli_option *o, void *field, char **v, accel_error *err)
{
    int *wh = field;
    const char *x = strchr(v[0], 'x');
    char w[32];
    long a = 0, b = 0;
    int ok = x && (size_t)(x - v[0]) < sizeof w;
    if (ok) {
        memcpy(w, v[0], (size_t)(x - v[0]));
        w[x - v[0]] = 0;
        ok = cli_to_long(w, (long)o->lo, (long)o->hi, &a) &&
             cli_to_long(x + 1, (long)o->lo, (long)o->hi, &b);
    }
    if (!ok)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected WxH with %.0f <= W, H <= %.0f",
                          o->name, v[0], o->lo, o->hi);
    wh[0] = (int)a, wh[1] = (int)b;
    return 0;
}

int cli_check_output(const char *opt, const char *path, const char *exts, accel_error *err)
{
    if (!path) return 0;
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == dir)
        dir[1] = 0;
    else
        *slash = 0;
    if (access(dir, W_OK) != 0)
        return accel_fail(err, ACCEL_ERR_IO, "%s %s: cannot write into directory %s", opt, path,
                          dir);
    if (!exts) return 0;
    const char *dot = strrchr(path, '.');
    size_t len = dot ? strlen(dot + 1) : 0;
    for (const char *e = exts; dot && len && *e;) {
        size_t el = strcspn(e, " ");
        if (el == len && !strncmp(e, dot + 1, len)) return 0;
        e += el;
        while (*e == ' ') e++;
    }
    return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: the file name must end in one of: %s", opt,
                      path, exts);
}

int cli_heat_scale(const cli_option *o, void *field, char **v, accel_error *err)
{
    (void)o;
    return image_heat_scale_parse(v[0], field, err);
}
