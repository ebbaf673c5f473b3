/*
 * load.c - a scene from a spec: a built-in generator ("sphereflake:level=3")
 * or a file, dispatched to its loader by extension (.obj, .ply, .off, and
 * .scene for scenes of many meshes, load_scene.c).
 */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "scene/builtin.h"
#include "scene/compose.h"
#include "scene/scene.h"

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return (dot && (!slash || dot > slash)) ? dot + 1 : "";
}

int scene_load_file(const char *path, accel_scene *s, accel_error *err)
{
    scene_builder b = {0};
    const char *ext = extension(path);
    int rc;
    if (!strcasecmp(ext, "scene")) return scene_load_scene(path, s, err);
    if (!strcasecmp(ext, "obj"))
        rc = scene_load_obj(path, &b, err);
    else if (!strcasecmp(ext, "ply"))
        rc = scene_load_ply(path, &b, err);
    else if (!strcasecmp(ext, "off"))
        rc = scene_load_off(path, &b, err);
    else
        rc = accel_fail(err, ACCEL_ERR_SPEC,
                        "%s: unknown file format '.%s' (accepted: .obj, .ply, .off, .scene)",
                        path, ext);
    if (rc == 0) {
        const char *slash = strrchr(path, '/');
        rc = scene_finish(&b, slash ? slash + 1 : path, s, err);
    }
    scene_builder_free(&b);
    return rc;
}

int scene_create(const char *spec, accel_scene *s, accel_error *err)
{
    memset(s, 0, sizeof *s);
    char name[64];
    const char *colon = strchr(spec, ':');
    size_t nlen = colon ? (size_t)(colon - spec) : strlen(spec);
    if (nlen < sizeof name) {
        memcpy(name, spec, nlen);
        name[nlen] = 0;
        for (size_t i = 0; i < scene_generator_count; i++) {
            const scene_generator *g = scene_generators[i];
            if (strcmp(g->name, name) != 0) continue;
            double num[ACCEL_MAX_PARAMS];
            char str[ACCEL_MAX_PARAMS][64];
            unsigned char given[ACCEL_MAX_PARAMS];
            char what[96];
            snprintf(what, sizeof what, "scene %s", g->name);
            int rc = accel_parse_kv(what, colon ? colon + 1 : "", g->params, g->param_count, num,
                                    str, given, err);
            if (rc) return rc;
            accel_camera cam;
            vec3 light;
            if (g->compose) {
                scene_compose c;
                memset(&c, 0, sizeof c);
                rc = g->compose(num, &c, &cam, &light, err);
                if (rc == 0) rc = scene_compose_finish(&c, spec, s, err);
                scene_compose_free(&c);
            } else {
                scene_builder b = {0};
                rc = g->generate(num, &b, &cam, &light, err);
                if (rc == 0) rc = scene_finish(&b, spec, s, err);
                scene_builder_free(&b);
            }
            if (rc) return rc;
            s->camera = cam;
            s->light = light;
            return 0;
        }
    }
    if (strchr(spec, '.')) return scene_load_file(spec, s, err);
    char names[512] = "";
    for (size_t i = 0; i < scene_generator_count; i++) {
        size_t len = strlen(names);
        snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "", scene_generators[i]->name);
    }
    return accel_fail(err, ACCEL_ERR_SPEC,
                      "unknown scene '%s': give a file (.obj, .ply, .off, .scene) or one of: %s",
                      spec, names);
}

