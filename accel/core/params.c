/*
 * params.c - spec strings: "kind:key=value,key=value,flag".
 *
 * Every parameter is declared once in its kind's table (key, type, default,
 * range, help, and where its value goes in the kind's spec struct); the same
 * table drives parsing, range checks and --help. A spec is parsed once into
 * that struct, typed, so kinds read fields, not keys. An unknown key is an
 * error that lists the accepted ones: never a warning with a silent
 * fallback; a table mistake is ACCEL_ERR_INTERNAL, never an assert.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "accel.h"

/* Their offsets are into accel_params itself (the parser's own fields). */
const accel_param_def accel_common_params[] = {
    {.key = "tri", .type = ACCEL_PARAM_ENUM, .def = "watertight", .choices = "watertight|naive",
     .help = "triangle test: watertight (Woop et al. 2013) or naive (Moller-Trumbore)",
     .offset = offsetof(accel_params, naive)},
    {.key = "reorder", .type = ACCEL_PARAM_BOOL, .def = "1", .min = 0, .max = 1,
     .help = "primitive store: copy the primitives in Morton order of their centroids (0: scene "
             "order; bvh alone defaults to 0: its tree copies them in leaf order itself)",
     .offset = offsetof(accel_params, reorder)},
};
const size_t accel_common_param_count = sizeof accel_common_params / sizeof accel_common_params[0];

static void list_keys(const accel_param_def *defs, size_t n, char *buf, size_t size)
{
    size_t len = strlen(buf);
    for (size_t i = 0; i < n && len + 1 < size; i++) {
        snprintf(buf + len, size - len, "%s%s", len && buf[len - 1] != ' ' ? ", " : "", defs[i].key);
        len = strlen(buf);
    }
}

static int choice_index(const char *choices, const char *value)
{
    int idx = 0;
    const char *p = choices;
    size_t vlen = strlen(value);
    while (*p) {
        const char *bar = strchr(p, '|');
        size_t len = bar ? (size_t)(bar - p) : strlen(p);
        if (len == vlen && strncmp(p, value, len) == 0) return idx;
        idx++;
        if (!bar) break;
        p = bar + 1;
    }
    return -1;
}

/* What an ENUM stores for the choice `value` at position idx: the choice
 * itself when it is written as an integer ("2|4|8"), else idx. */
static int choice_number(const char *value, int idx)
{
    char *end = NULL;
    errno = 0;
    long x = strtol(value, &end, 10);
    if (*value && !*end && errno == 0 && x >= INT_MIN && x <= INT_MAX) return (int)x;
    return idx;
}

const char *accel_param_choice(const char *choices, int value, char *buf, size_t size)
{
    int idx = 0;
    const char *p = choices;
    if (size) buf[0] = 0;
    while (p && *p) {
        const char *bar = strchr(p, '|');
        size_t len = bar ? (size_t)(bar - p) : strlen(p);
        char text[ACCEL_PARAM_TEXT];
        snprintf(text, sizeof text, "%.*s", (int)len, p);
        if (choice_number(text, idx) == value) {
            snprintf(buf, size, "%s", text);
            break;
        }
        idx++;
        p = bar ? bar + 1 : NULL;
    }
    return buf;
}

/* Parses one value into num/str; returns 0 or an error. */
static int parse_value(const char *what, const accel_param_def *d, const char *value, double *num,
                       char *str, accel_error *err)
{
    if (strlen(value) >= 64)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: value of '%s' is too long", what, d->key);
    snprintf(str, 64, "%s", value);
    char *end = NULL;
    switch (d->type) {
    case ACCEL_PARAM_INT:
    case ACCEL_PARAM_FLOAT: {
        errno = 0;
        double x = strtod(value, &end);
        if (!*value || *end || errno == ERANGE || !isfinite(x))
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: '%s=%s' is not a number", what, d->key,
                              value);
        if (d->type == ACCEL_PARAM_INT && x != floor(x))
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: '%s=%s' must be an integer", what, d->key,
                              value);
        if (x < d->min || x > d->max)
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: '%s=%s' is out of range [%g, %g]", what,
                              d->key, value, d->min, d->max);
        *num = x;
        return 0;
    }
    case ACCEL_PARAM_BOOL:
        if (!strcmp(value, "1") || !strcasecmp(value, "on") || !strcasecmp(value, "true") ||
            !strcasecmp(value, "yes"))
            *num = 1;
        else if (!strcmp(value, "0") || !strcasecmp(value, "off") || !strcasecmp(value, "false") ||
                 !strcasecmp(value, "no"))
            *num = 0;
        else
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: '%s=%s': expected 0/1/on/off/true/false",
                              what, d->key, value);
        return 0;
    case ACCEL_PARAM_ENUM: {
        int idx = choice_index(d->choices, value);
        if (idx < 0)
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: '%s=%s': accepted values are %s", what,
                              d->key, value, d->choices);
        *num = choice_number(value, idx);
        return 0;
    }
    case ACCEL_PARAM_STR:
        *num = 0;
        return 0;
    }
    return accel_fail(err, ACCEL_ERR_INTERNAL, "%s: bad parameter type", what);
}

int accel_parse_kv(const char *what, const char *text, const accel_param_def *defs, size_t n,
                   double *num, char (*str)[64], unsigned char *given, accel_error *err)
{
    for (size_t i = 0; i < n; i++) {
        given[i] = 0;
        if (!defs[i].def || parse_value(what, &defs[i], defs[i].def, &num[i], str[i], err))
            return accel_fail(err, ACCEL_ERR_INTERNAL, "%s: the default of parameter '%s' does "
                              "not parse", what, defs[i].key);
    }
    if (!text || !*text) return 0;
    char buf[512];
    if (strlen(text) >= sizeof buf)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: parameter string too long", what);
    snprintf(buf, sizeof buf, "%s", text);
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        char *eq = strchr(tok, '=');
        const char *value = "1";
        if (eq) {
            *eq = 0;
            value = eq + 1;
        }
        size_t i = 0;
        while (i < n && strcmp(defs[i].key, tok) != 0) i++;
        if (i == n) {
            char keys[400] = "";
            list_keys(defs, n, keys, sizeof keys);
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: unknown parameter '%s'; accepted: %s",
                              what, tok, n ? keys : "(none)");
        }
        if (!eq && defs[i].type != ACCEL_PARAM_BOOL)
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: parameter '%s' needs a value (%s=...)",
                              what, tok, tok);
        if (given[i])
            return accel_fail(err, ACCEL_ERR_SPEC, "%s: parameter '%s' given twice", what, tok);
        int rc = parse_value(what, &defs[i], value, &num[i], str[i], err);
        if (rc) return rc;
        given[i] = 1;
    }
    return 0;
}

void accel_params_help(const accel_param_def *defs, size_t n, char *buf, size_t size)
{
    static const char *type_names[] = {"int", "float", "choice", "bool", "text"};
    for (size_t i = 0; i < n; i++) {
        const accel_param_def *d = &defs[i];
        char range[96] = "";
        if (d->type == ACCEL_PARAM_INT || d->type == ACCEL_PARAM_FLOAT)
            snprintf(range, sizeof range, ", %g..%g", d->min, d->max);
        else if (d->type == ACCEL_PARAM_ENUM)
            snprintf(range, sizeof range, ", %s", d->choices);
        size_t len = strlen(buf);
        if (len + 1 >= size) return;
        snprintf(buf + len, size - len, "    %-12s %s (%s, default %s%s)\n", d->key, d->help,
                 type_names[d->type], d->def, range);
    }
}

int accel_params_parse(const char *spec, accel_params *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    char name[64];
    const char *colon = strchr(spec, ':');
    size_t nlen = colon ? (size_t)(colon - spec) : strlen(spec);
    if (nlen >= sizeof name) nlen = sizeof name - 1;
    memcpy(name, spec, nlen);
    name[nlen] = 0;
    const accel_kind *k = accel_find_kind(name);
    if (!k) {
        char names[400] = "";
        for (size_t i = 0; i < accel_kind_count; i++) {
            size_t len = strlen(names);
            snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "", accel_kinds[i]->name);
        }
        return accel_fail(err, ACCEL_ERR_SPEC, "unknown accelerator '%s'; accepted: %s", name,
                          names);
    }
    return accel_params_parse_kind(k, colon ? colon + 1 : "", out, err);
}

/* Bytes a parameter of this type takes in a spec struct. */
static size_t field_size(accel_param_type type)
{
    return type == ACCEL_PARAM_FLOAT ? sizeof(double)
           : type == ACCEL_PARAM_STR ? ACCEL_PARAM_TEXT
                                     : sizeof(int);
}

/* Stores a parsed value at base + d->offset, typed. */
static void store_value(unsigned char *base, const accel_param_def *d, double num,
                        const char *text)
{
    unsigned char *at = base + d->offset;
    if (d->type == ACCEL_PARAM_FLOAT) {
        memcpy(at, &num, sizeof num);
    } else if (d->type == ACCEL_PARAM_STR) {
        snprintf((char *)at, ACCEL_PARAM_TEXT, "%s", text);
    } else {
        int v = (int)num;
        memcpy(at, &v, sizeof v);
    }
}

/* A kind's table must fit its spec struct (a table mistake, never the
 * user's: ACCEL_ERR_INTERNAL). */
static int check_table(const accel_kind *k, accel_error *err)
{
    if (k->param_count + accel_common_param_count > ACCEL_MAX_PARAMS ||
        k->spec_size > ACCEL_SPEC_BYTES)
        return accel_fail(err, ACCEL_ERR_INTERNAL,
                          "%s: %zu parameters in a %zu-byte spec struct (at most %zu and %d)",
                          k->name, k->param_count, k->spec_size,
                          ACCEL_MAX_PARAMS - accel_common_param_count, ACCEL_SPEC_BYTES);
    for (size_t i = 0; i < k->param_count; i++) {
        const accel_param_def *d = &k->params[i];
        if (!d->key || !d->help)
            return accel_fail(err, ACCEL_ERR_INTERNAL, "%s: parameter %zu has no key or help",
                              k->name, i);
        if (d->offset + field_size(d->type) > k->spec_size ||
            (d->type == ACCEL_PARAM_INT && (d->min < INT_MIN || d->max > INT_MAX)))
            return accel_fail(err, ACCEL_ERR_INTERNAL,
                              "%s: parameter '%s' does not fit its field of the spec struct",
                              k->name, d->key);
    }
    return 0;
}

int accel_params_parse_kind(const accel_kind *k, const char *kv, accel_params *out,
                            accel_error *err)
{
    memset(out, 0, sizeof *out);
    int rc = check_table(k, err);
    if (rc) return rc;
    /* The kind's own parameters and the common ones share one table. */
    accel_param_def defs[ACCEL_MAX_PARAMS];
    size_t n = k->param_count + accel_common_param_count;
    if (k->param_count) memcpy(defs, k->params, k->param_count * sizeof *defs);
    memcpy(defs + k->param_count, accel_common_params, accel_common_param_count * sizeof *defs);
    out->kind = k;
    double num[ACCEL_MAX_PARAMS];
    char str[ACCEL_MAX_PARAMS][64];
    unsigned char given[ACCEL_MAX_PARAMS];
    rc = accel_parse_kv(k->name, kv, defs, n, num, str, given, err);
    if (rc) return rc;
    /* Typed values: the kind's into its spec struct, the common ones into
     * out's own fields. */
    for (size_t i = 0; i < n; i++) {
        int common = i >= k->param_count;
        store_value(common ? (unsigned char *)out : out->values.bytes, &defs[i], num[i], str[i]);
        if (!common)
            out->given[defs[i].offset] |= given[i];
        else if (defs[i].offset == offsetof(accel_params, reorder))
            out->reorder_given = given[i];
    }
    /* Canonical spec: the name and the parameters given, in table order. */
    size_t len = (size_t)snprintf(out->spec, sizeof out->spec, "%s", k->name);
    int first = 1;
    for (size_t i = 0; i < n && len < sizeof out->spec; i++) {
        if (!given[i]) continue;
        len += (size_t)snprintf(out->spec + len, sizeof out->spec - len, "%s%s=%s",
                                first ? ":" : ",", defs[i].key, str[i]);
        first = 0;
    }
    return 0;
}
