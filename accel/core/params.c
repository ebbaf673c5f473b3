/*
 * params.c - spec strings: "kind:key=value,key=value,flag".
 *
 * Every parameter is declared once in its kind's table (key, type, default,
 * range, help); the same table drives parsing, range checks and --help. An
 * unknown key is an error that lists the accepted ones: never a warning with
 * a silent fallback.
 */
#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "accel.h"

const accel_param_def accel_common_params[] = {
    {"tri", ACCEL_PARAM_ENUM, "watertight", 0, 0, "watertight|naive",
     "triangle test: watertight (Woop et al. 2013) or naive (Moller-Trumbore)"},
    {"reorder", ACCEL_PARAM_BOOL, "1", 0, 0, NULL,
     "primitive store: copy the primitives in Morton order of their centroids (0: scene order; "
     "bvh alone defaults to 0: its tree copies them in leaf order itself)"},
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
        *num = idx;
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
        int rc = parse_value(what, &defs[i], defs[i].def, &num[i], str[i], err);
        assert(rc == 0 && "a parameter default must parse");
        (void)rc;
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

int accel_params_parse_kind(const accel_kind *k, const char *kv, accel_params *out,
                            accel_error *err)
{
    memset(out, 0, sizeof *out);
    /* The kind's own parameters and the common ones share one table. */
    accel_param_def defs[ACCEL_MAX_PARAMS];
    size_t n = k->param_count + accel_common_param_count;
    assert(n <= ACCEL_MAX_PARAMS);
    if (k->param_count) memcpy(defs, k->params, k->param_count * sizeof *defs);
    memcpy(defs + k->param_count, accel_common_params, accel_common_param_count * sizeof *defs);
    out->kind = k;
    int rc = accel_parse_kv(k->name, kv, defs, n, out->num, out->str, out->given, err);
    if (rc) return rc;
    out->naive = out->num[k->param_count] == 1; /* tri: 0 watertight, 1 naive */
    out->reorder = out->num[k->param_count + 1] != 0.0;
    /* Canonical spec: the name and the parameters given, in table order. */
    size_t len = (size_t)snprintf(out->spec, sizeof out->spec, "%s", k->name);
    int first = 1;
    for (size_t i = 0; i < n && len < sizeof out->spec; i++) {
        if (!out->given[i]) continue;
        len += (size_t)snprintf(out->spec + len, sizeof out->spec - len, "%s%s=%s",
                                first ? ":" : ",", defs[i].key, out->str[i]);
        first = 0;
    }
    return 0;
}

static size_t key_index(const accel_params *p, const char *key)
{
    const accel_kind *k = p->kind;
    for (size_t i = 0; i < k->param_count; i++)
        if (!strcmp(k->params[i].key, key)) return i;
    for (size_t i = 0; i < accel_common_param_count; i++)
        if (!strcmp(accel_common_params[i].key, key)) return k->param_count + i;
    fprintf(stderr, "accel: kind %s has no parameter '%s'\n", k->name, key);
    assert(0 && "parameter lookup with an undeclared key");
    return 0;
}

double accel_param_num(const accel_params *p, const char *key) { return p->num[key_index(p, key)]; }
const char *accel_param_str(const accel_params *p, const char *key)
{
    return p->str[key_index(p, key)];
}
int accel_param_given(const accel_params *p, const char *key) { return p->given[key_index(p, key)]; }
