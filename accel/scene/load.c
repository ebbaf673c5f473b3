/*
 * load.c - a scene from a spec: a built-in generator ("sphereflake:level=3")
 * or a file, dispatched to its loader by extension (.obj, .ply, .off, and
 * .scene for scenes of many meshes, load_scene.c). The .scene reader is
 * handed its mesh loader: the default one here makes a built-in scene or
 * loads a mesh file, so the reader itself never calls back into this file.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "scene/compose.h"
#include "scene/load_common.h"
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
    else if (!ext[0])
        rc = accel_fail(err, ACCEL_ERR_SPEC,
                        "%s: no file extension (accepted: .obj, .ply, .off, .scene)", path);
    else
        rc = accel_fail(err, ACCEL_ERR_SPEC,
                        "%s: unknown file format '.%s' (accepted: .obj, .ply, .off, .scene)",
                        path, ext);
    if (rc == 0) {
        const char *slash = strrchr(path, '/');
        rc = scene_finish(&b, slash ? slash + 1 : path, s, err);
        if (rc == 0) scene_camera_front(s);
    }
    scene_builder_free(&b);
    return rc;
}

/* The generator named by spec's part before ':' (NULL if none); *args is
 * the text after the ':' ("" without one). */
static const scene_generator *find_generator(const char *spec, const char **args)
{
    const char *colon = strchr(spec, ':');
    size_t nlen = colon ? (size_t)(colon - spec) : strlen(spec);
    *args = colon ? colon + 1 : "";
    for (size_t i = 0; i < scene_generator_count; i++) {
        const scene_generator *g = scene_generators[i];
        if (strlen(g->name) == nlen && !strncmp(g->name, spec, nlen)) return g;
    }
    return NULL;
}

static int parse_generator_args(const scene_generator *g, const char *args, double *num,
                                accel_error *err)
{
    char str[ACCEL_MAX_PARAMS][64];
    unsigned char given[ACCEL_MAX_PARAMS];
    char what[96];
    snprintf(what, sizeof what, "scene %s", g->name);
    return accel_parse_kv(what, args, g->params, g->param_count, num, str, given, err);
}

static int unknown_scene(const char *spec, accel_error *err)
{
    char names[512] = "";
    for (size_t i = 0; i < scene_generator_count; i++) {
        size_t len = strlen(names);
        snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "", scene_generators[i]->name);
    }
    return accel_fail(err, ACCEL_ERR_SPEC,
                      "unknown scene '%s': give a file (.obj, .ply, .off, .scene) or one of: %s",
                      spec, names);
}

int scene_spec_check(const char *spec, accel_error *err)
{
    const char *args;
    const scene_generator *g = find_generator(spec, &args);
    if (g) {
        double num[ACCEL_MAX_PARAMS];
        return parse_generator_args(g, args, num, err);
    }
    if (!strchr(spec, '.')) return unknown_scene(spec, err);
    const char *ext = extension(spec);
    if (strcasecmp(ext, "obj") && strcasecmp(ext, "ply") && strcasecmp(ext, "off") &&
        strcasecmp(ext, "scene"))
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "%s: unknown file format '.%s' (accepted: .obj, .ply, .off, .scene)",
                          spec, ext);
    FILE *f = fopen(spec, "rb");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open: %s", spec, strerror(errno));
    fclose(f);
    return 0;
}

int scene_create(const char *spec, accel_scene *s, accel_error *err)
{
    memset(s, 0, sizeof *s);
    const char *args;
    const scene_generator *g = find_generator(spec, &args);
    if (g) {
        double num[ACCEL_MAX_PARAMS];
        int rc = parse_generator_args(g, args, num, err);
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
    if (strchr(spec, '.')) return scene_load_file(spec, s, err);
    return unknown_scene(spec, err);
}

/* ---- .scene files --------------------------------------------------------- */

/* A mesh of a .scene file without its own loader (scene_file_options): a
 * built-in scene by its name before ':', else a mesh file relative to the
 * scene file's folder (never another .scene: scene files do not nest). */
static int default_load_mesh(void *ctx, const char *source, const char *dir, accel_scene *mesh,
                             accel_error *err)
{
    (void)ctx;
    const char *args;
    if (find_generator(source, &args)) return scene_create(source, mesh, err);
    /* No '.' and no '/' before a ':' (or in the whole source): a built-in
     * scene's name, misspelt ("sofa:tris=300"), not a file. */
    size_t head = strcspn(source, ":");
    if (!memchr(source, '.', head) && !memchr(source, '/', head)) return unknown_scene(source, err);
    const char *dot = strrchr(source, '.'), *slash = strrchr(source, '/');
    if (dot && (!slash || dot > slash) && !strcasecmp(dot, ".scene"))
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "%s: a mesh cannot be a .scene file (scene files do not nest)", source);
    char path[4096];
    int n = (source[0] == '/' || !dir[0]) ? snprintf(path, sizeof path, "%s", source)
                                          : snprintf(path, sizeof path, "%s/%s", dir, source);
    if (n < 0 || (size_t)n >= sizeof path)
        return accel_fail(err, ACCEL_ERR_RANGE, "%s: path too long", source);
    return scene_load_file(path, mesh, err);
}

int scene_parse_scene(const char *name, const char *dir, const char *data, size_t size,
                      const scene_file_options *opt, accel_scene *s, accel_error *err)
{
    scene_file_options o = {opt ? opt->max_prims : 0, default_load_mesh, NULL};
    if (opt && opt->load_mesh) o = *opt;
    return load_scene_parse(name, dir, data, size, &o, s, err);
}

int scene_load_scene(const char *path, accel_scene *s, accel_error *err)
{
    memset(s, 0, sizeof *s);
    char *data;
    size_t size;
    int rc = load_read_file(path, &data, &size, err);
    if (rc) return rc;
    char dir[4096];
    const char *slash = strrchr(path, '/');
    size_t n = slash ? (size_t)(slash - path) : 0;
    if (n >= sizeof dir) {
        free(data);
        return accel_fail(err, ACCEL_ERR_RANGE, "%s: path too long", path);
    }
    memcpy(dir, path, n);
    dir[n] = 0;
    if (slash && n == 0) strcpy(dir, "/");
    rc = scene_parse_scene(path, dir, data, size, NULL, s, err);
    free(data);
    return rc;
}
