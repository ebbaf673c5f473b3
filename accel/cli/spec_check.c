/*
 * spec_check.c - an accelerator spec checked in full before any work
 * (spec_check.h says which steps).
 */
#include <stdio.h>
#include <string.h>

#include "cli/spec_check.h"
#include "measure/bench.h"
#include "scene/scene.h"

/* The bottom= value of spec (up to the next ','), copied into out; 0 if none. */
int spec_check_bottom(const char *spec, char *out, size_t n)
{
    const char *colon = strchr(spec, ':');
    for (const char *p = colon; p && *p; p = strchr(p + 1, ','))
        if (!strncmp(p + 1, "bottom=", 7)) {
            const char *v = p + 8;
            snprintf(out, n, "%.*s", (int)strcspn(v, ","), v);
            return 1;
        }
    return 0;
}

/* 0, or ACCEL_ERR_SPEC with "<opt> <spec>: <reason>" in err. */
int spec_check_accel(const char *opt, const char *spec, accel_error *err)
{
    accel_params p;
    accel_error e = {0};
    if (accel_params_parse(spec, &p, &e))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: %s", opt, spec, e.msg);
    char bottom[256], sub[256];
    if (spec_check_bottom(spec, bottom, sizeof bottom) && strcmp(bottom, "bvh") &&
        strcmp(bottom, "grid")) {
        snprintf(sub, sizeof sub, "%s", bottom);
        for (char *c = sub; *c; c++)
            if (*c == ';') *c = ',';
        accel_params q;
        if (accel_params_parse(sub, &q, &e))
            return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: bottom=%s: %s", opt, spec, bottom,
                              e.msg);
    }
    accel_scene tiny;
    if (scene_create("soup:tris=12", &tiny, &e)) return 0; /* nothing to try it on */
    const accel_kind *kind;
    void *accel = NULL;
    accel_build_stats st;
    accel_timing bt;
    int rc = bench_build(spec, &tiny, 1, 1, 0.0, &kind, &accel, &st, &bt, NULL, &e);
    if (!rc) kind->destroy(accel);
    scene_free(&tiny);
    if (rc && (e.code == ACCEL_ERR_SPEC || e.code == ACCEL_ERR_RANGE))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: %s", opt, spec, e.msg);
    return 0;
}

