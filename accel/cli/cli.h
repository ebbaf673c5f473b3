/*
 * cli.h - command-line options from one table, for bin/trace and the
 * experiments: each row names an option, its argument(s), its help line and
 * the parser that checks and stores its value, so that parsing and --help
 * cannot drift apart. Numbers are parsed strictly (the whole argument, in
 * range): "--seed abc", "--size 10x10q", "--threads -1" are usage errors.
 * Also the exit statuses every tool documents in its --help.
 */
#ifndef ACCEL_CLI_H
#define ACCEL_CLI_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Exit statuses of bin/trace and of every experiment. */
enum {
    CLI_EXIT_OK = 0,
    CLI_EXIT_DIFFER = 1,   /* results disagree (--check, trace compare) */
    CLI_EXIT_USAGE = 2,    /* bad option, number, spec, ray set name or camera */
    CLI_EXIT_INPUT = 3,    /* a file that cannot be read or written, bad or empty scene */
    CLI_EXIT_INTERNAL = 4  /* a broken invariant in a counted run, out of memory */
};

/* The exit status for an accel_error code (ACCEL_ERR_*). */
int cli_exit_of(int accel_status);
/* The "Exit status:" paragraph of --help. */
void cli_help_exit_codes(FILE *f);

typedef struct cli_option cli_option;
/* Checks and stores the values of one option; field points into the
 * options struct at opt->offset. Returns 0 or an ACCEL_ERR_SPEC in err. */
typedef int (*cli_parser)(const cli_option *opt, void *field, char **values, accel_error *err);

struct cli_option {
    const char *name; /* "--threads" */
    const char *arg;  /* "N", or "steps|prims FILE" (one word per value); NULL for a flag */
    const char *help;
    cli_parser parse;
    size_t offset;    /* of the field parse fills, in the options struct */
    double lo, hi;    /* accepted range of a number */
};

/* Parses argv[first..argc) into opts (the struct the offsets refer to).
 * "-h" stands for "--help". Stops at the first error. */
int cli_parse(const cli_option *table, size_t n, int argc, char **argv, int first, void *opts,
              accel_error *err);
/* One line per option: name, argument, help (help may hold '\n'). */
void cli_help(FILE *f, const cli_option *table, size_t n);

/* Parsers for the common field types. */
int cli_flag(const cli_option *o, void *field, char **v, accel_error *err);   /* int = 1 */
int cli_unflag(const cli_option *o, void *field, char **v, accel_error *err); /* int = 0 */
int cli_string(const cli_option *o, void *field, char **v, accel_error *err); /* const char * */
int cli_int(const cli_option *o, void *field, char **v, accel_error *err);    /* int in [lo, hi] */
int cli_u64(const cli_option *o, void *field, char **v, accel_error *err);    /* uint64_t, decimal */
int cli_float(const cli_option *o, void *field, char **v, accel_error *err);  /* float in [lo, hi] */
int cli_double(const cli_option *o, void *field, char **v, accel_error *err); /* double in [lo, hi] */
int cli_heat_scale(const cli_option *o, void *field, char **v, accel_error *err); /* image_heat_scale */

/* The rows every tool shares, for an options struct T with the fields
 * heat_scale (image_heat_scale), quiet, help (int) and progress_after
 * (double, seconds). */
#define CLI_COMMON_ROWS(T)                                                                  \
    {"--heat-scale", "SPEC", "heatmap scale: auto (0..image max, default), max=N (fixed, so\n" \
     "images compare), log (log(1+v)); e.g. log,max=200", cli_heat_scale,                  \
     offsetof(T, heat_scale), 0, 0},                                                        \
    {"--quiet", NULL, "no progress lines on stderr", cli_flag, offsetof(T, quiet), 0, 0},   \
    {"--progress-after", "S", "show progress of phases longer than S seconds (default 2)",  \
     cli_double, offsetof(T, progress_after), 0, 1e6},                                      \
    {"--help", NULL, "this text", cli_flag, offsetof(T, help), 0, 0}

/* A vector option "X,Y,Z" and whether it was given. */
typedef struct {
    vec3 v;
    int given;
} cli_vec3;
int cli_vec(const cli_option *o, void *field, char **v, accel_error *err);  /* cli_vec3 */
int cli_size(const cli_option *o, void *field, char **v, accel_error *err); /* int[2] from WxH in [lo, hi] */

/* An output file: its directory must exist and be writable, and its name
 * end in one of `exts` ("png ppm"; NULL: any). 0 or an error naming opt. */
int cli_check_output(const char *opt, const char *path, const char *exts, accel_error *err);

/* Strict conversions of a whole string: 1 on success, 0 otherwise. */
int cli_to_long(const char *s, long lo, long hi, long *out);
int cli_to_double(const char *s, double lo, double hi, double *out);

#ifdef __cplusplus
}
#endif

#endif
