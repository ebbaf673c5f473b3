/*
 * test_params.c - parameter tables and typed spec structs: every kind's
 * table fits its struct, defaults parse, the parser stores typed values
 * and given flags, and user text (a misspelt key, a value out of range)
 * gives ACCEL_ERR_SPEC, never an assert.
 */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene/scene.h"
#include "test.h"

extern const accel_kind accel_kind_starter; /* lab/starter.c */

static size_t field_bytes(accel_param_type t)
{
    return t == ACCEL_PARAM_FLOAT ? sizeof(double)
           : t == ACCEL_PARAM_STR ? ACCEL_PARAM_TEXT
                                  : sizeof(int);
}

/* The value an ENUM stores for each choice, in order; returns the count. */
static int enum_values(const accel_param_def *d, const char *what, int *out, int cap)
{
    char choices[256];
    snprintf(choices, sizeof choices, "%s", d->choices);
    int n = 0;
    char *save = NULL;
    for (char *c = strtok_r(choices, "|", &save); c && n < cap; c = strtok_r(NULL, "|", &save)) {
        double num[ACCEL_MAX_PARAMS];
        char str[ACCEL_MAX_PARAMS][64];
        unsigned char given[ACCEL_MAX_PARAMS];
        char kv[128];
        snprintf(kv, sizeof kv, "%s=%s", d->key, c);
        accel_error err;
        int rc = accel_parse_kv(what, kv, d, 1, num, str, given, &err);
        CHECKF(rc == 0, "%s: %s does not parse: %s", what, kv, err.msg);
        out[n++] = rc ? -1 : (int)num[0];
    }
    return n;
}

/* A table's own checks, shared by kinds and scenes. */
static void check_table(const char *what, const accel_param_def *defs, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const accel_param_def *d = &defs[i];
        CHECKF(d->key && d->help && d->def, "%s: parameter %zu lacks key, help or default", what, i);
        for (size_t j = 0; j < i; j++)
            CHECKF(strcmp(defs[j].key, d->key), "%s: key '%s' twice", what, d->key);
        if (d->type == ACCEL_PARAM_INT || d->type == ACCEL_PARAM_FLOAT)
            CHECKF(d->min <= d->max, "%s: '%s' range [%g, %g]", what, d->key, d->min, d->max);
        if (d->type == ACCEL_PARAM_ENUM) {
            int v[16];
            int m = d->choices ? enum_values(d, what, v, 16) : 0;
            CHECKF(m >= 2, "%s: enum '%s' has %d choices", what, d->key, m);
            for (int a = 0; a < m; a++)
                for (int b = 0; b < a; b++)
                    CHECKF(v[a] != v[b], "%s: two choices of '%s' store %d", what, d->key, v[a]);
        }
    }
}

static void check_kind_table(const accel_kind *k)
{
    check_table(k->name, k->params, k->param_count);
    CHECKF(k->spec_size <= ACCEL_SPEC_BYTES, "%s: spec struct of %zu bytes", k->name, k->spec_size);
    CHECKF(k->param_count + accel_common_param_count <= ACCEL_MAX_PARAMS, "%s: %zu parameters",
           k->name, k->param_count);
    for (size_t i = 0; i < k->param_count; i++) {
        const accel_param_def *d = &k->params[i];
        size_t end = d->offset + field_bytes(d->type);
        CHECKF(end <= k->spec_size, "%s: '%s' at %zu..%zu outside its %zu-byte struct", k->name,
               d->key, d->offset, end, k->spec_size);
        if (d->type == ACCEL_PARAM_INT)
            CHECKF(d->min >= INT_MIN && d->max <= INT_MAX, "%s: '%s' range beyond an int", k->name,
                   d->key);
        for (size_t j = 0; j < i; j++) {
            const accel_param_def *e = &k->params[j];
            size_t e_end = e->offset + field_bytes(e->type);
            CHECKF(end <= e->offset || e_end <= d->offset, "%s: '%s' and '%s' share bytes",
                   k->name, d->key, e->key);
        }
    }
    accel_params p;
    accel_error err;
    CHECKF(accel_params_parse_kind(k, "", &p, &err) == 0, "%s: defaults: %s", k->name, err.msg);
    CHECK(strcmp(p.spec, k->name) == 0);

    /* A misspelt key: an error listing every accepted key. */
    CHECK(accel_params_parse_kind(k, "nosuchkey=1", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "unknown parameter 'nosuchkey'; accepted: "), "%s: %s", k->name, err.msg);
    for (size_t i = 0; i < k->param_count; i++)
        CHECKF(strstr(err.msg, k->params[i].key), "%s: '%s' not listed: %s", k->name,
               k->params[i].key, err.msg);

    /* Out of range, on either side: an error naming the range. */
    for (size_t i = 0; i < k->param_count; i++) {
        const accel_param_def *d = &k->params[i];
        if (d->type != ACCEL_PARAM_INT && d->type != ACCEL_PARAM_FLOAT) continue;
        char kv[128];
        snprintf(kv, sizeof kv, "%s=%.17g", d->key, d->max + fabs(d->max) + 1);
        CHECKF(accel_params_parse_kind(k, kv, &p, &err) == ACCEL_ERR_SPEC, "%s: %s", k->name, kv);
        CHECKF(strstr(err.msg, "out of range"), "%s: %s", k->name, err.msg);
        snprintf(kv, sizeof kv, "%s=%.17g", d->key, d->min - fabs(d->min) - 1);
        CHECKF(accel_params_parse_kind(k, kv, &p, &err) == ACCEL_ERR_SPEC, "%s: %s", k->name, kv);
    }
}

TEST(params_kind_tables)
{
    for (size_t i = 0; i < accel_kind_count; i++) check_kind_table(accel_kinds[i]);
    check_kind_table(&accel_kind_starter);
    check_table("common", accel_common_params, accel_common_param_count);
}

TEST(params_scene_tables)
{
    for (size_t i = 0; i < scene_generator_count; i++) {
        const scene_generator *g = scene_generators[i];
        check_table(g->name, g->params, g->param_count);
        double num[ACCEL_MAX_PARAMS];
        char str[ACCEL_MAX_PARAMS][64];
        unsigned char given[ACCEL_MAX_PARAMS];
        accel_error err;
        CHECK(g->param_count <= ACCEL_MAX_PARAMS);
        CHECKF(accel_parse_kv(g->name, "", g->params, g->param_count, num, str, given, &err) == 0,
               "scene %s: defaults: %s", g->name, err.msg);
        CHECK(accel_parse_kv(g->name, "nosuchkey=1", g->params, g->param_count, num, str, given,
                             &err) == ACCEL_ERR_SPEC);
    }
}

/* A kind of every parameter type, parsed but never built. */
typedef struct {
    int n, on, pick, width;
    double x;
    char name[ACCEL_PARAM_TEXT];
} toy_spec;

static const accel_param_def toy_params[] = {
    {.key = "n", .type = ACCEL_PARAM_INT, .def = "4", .min = 1, .max = 10, .help = "count",
     .offset = offsetof(toy_spec, n)},
    {.key = "x", .type = ACCEL_PARAM_FLOAT, .def = "0.5", .min = 0, .max = 1, .help = "fraction",
     .offset = offsetof(toy_spec, x)},
    {.key = "on", .type = ACCEL_PARAM_BOOL, .def = "0", .help = "flag",
     .offset = offsetof(toy_spec, on)},
    {.key = "pick", .type = ACCEL_PARAM_ENUM, .def = "b", .choices = "a|b|c", .help = "letter",
     .offset = offsetof(toy_spec, pick)},
    {.key = "width", .type = ACCEL_PARAM_ENUM, .def = "auto", .choices = "auto|4|8",
     .help = "number", .offset = offsetof(toy_spec, width)},
    {.key = "name", .type = ACCEL_PARAM_STR, .def = "none", .help = "text",
     .offset = offsetof(toy_spec, name)},
};

static const accel_kind toy_kind = {
    .name = "toy",
    .params = toy_params,
    .param_count = sizeof toy_params / sizeof toy_params[0],
    .spec_size = sizeof(toy_spec),
};

TEST(params_typed_spec)
{
    check_kind_table(&toy_kind);
    accel_params p;
    accel_error err;
    CHECK(accel_params_parse_kind(&toy_kind, "", &p, &err) == 0);
    const toy_spec *t = ACCEL_SPEC(&p, toy_spec);
    CHECK(t->n == 4 && t->x == 0.5 && t->on == 0 && t->pick == 1 && t->width == 0);
    CHECK(strcmp(t->name, "none") == 0);
    CHECK(!ACCEL_GIVEN(&p, toy_spec, n) && !ACCEL_GIVEN(&p, toy_spec, name));
    CHECK(p.reorder == 1 && !p.reorder_given && p.naive == 0);

    CHECK(accel_params_parse_kind(&toy_kind, "name=abc,width=8,on,n=7,pick=c,x=0.25,reorder=0",
                                  &p, &err) == 0);
    CHECK(t->n == 7 && t->x == 0.25 && t->on == 1 && t->pick == 2 && t->width == 8);
    CHECK(strcmp(t->name, "abc") == 0);
    CHECK(ACCEL_GIVEN(&p, toy_spec, n) && ACCEL_GIVEN(&p, toy_spec, x) &&
          ACCEL_GIVEN(&p, toy_spec, on) && ACCEL_GIVEN(&p, toy_spec, pick) &&
          ACCEL_GIVEN(&p, toy_spec, width) && ACCEL_GIVEN(&p, toy_spec, name));
    CHECK(p.reorder == 0 && p.reorder_given);
    /* Canonical: the given keys in table order, their text as written. */
    CHECKF(strcmp(p.spec, "toy:n=7,x=0.25,on=1,pick=c,width=8,name=abc,reorder=0") == 0, "%s",
           p.spec);
    CHECK(accel_params_parse_kind(&toy_kind, "width=4", &p, &err) == 0 && t->width == 4 &&
          t->pick == 1 && ACCEL_GIVEN(&p, toy_spec, width) && !ACCEL_GIVEN(&p, toy_spec, pick));

    CHECK(accel_params_parse_kind(&toy_kind, "nn=3", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "toy: unknown parameter 'nn'; accepted: n, x, on, pick, width, name, "
                           "tri, reorder"), "%s", err.msg);
    CHECK(accel_params_parse_kind(&toy_kind, "n=11", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "out of range [1, 10]"), "%s", err.msg);
    CHECK(accel_params_parse_kind(&toy_kind, "width=5", &p, &err) == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "accepted values are auto|4|8"), "%s", err.msg);
}

/* A table that does not fit its struct is the kind's bug: an error, not an
 * assert and not a write past the struct. */
TEST(params_bad_table_is_an_error)
{
    static const accel_param_def bad_params[] = {
        {.key = "x", .type = ACCEL_PARAM_FLOAT, .def = "1", .min = 0, .max = 2, .help = "x",
         .offset = 4},
    };
    static const accel_kind bad = {
        .name = "bad", .params = bad_params, .param_count = 1, .spec_size = 8};
    accel_params p;
    accel_error err;
    CHECK(accel_params_parse_kind(&bad, "", &p, &err) == ACCEL_ERR_INTERNAL);
    CHECKF(strstr(err.msg, "'x'"), "%s", err.msg);
    static const accel_param_def bad_default[] = {
        {.key = "n", .type = ACCEL_PARAM_INT, .def = "20", .min = 0, .max = 2, .help = "n"},
    };
    static const accel_kind bad2 = {
        .name = "bad2", .params = bad_default, .param_count = 1, .spec_size = sizeof(int)};
    CHECK(accel_params_parse_kind(&bad2, "n=1", &p, &err) == ACCEL_ERR_INTERNAL);
    CHECKF(strstr(err.msg, "default"), "%s", err.msg);
}
