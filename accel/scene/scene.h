/*
 * scene.h - building, loading, exporting and freeing scenes.
 *
 * A scene comes either from a mesh file (OBJ, PLY, OFF: load.c and friends)
 * or from a built-in procedural generator (builtin.c), selected by a spec:
 *   "bunny.off"                      a file (format from the extension)
 *   "sphereflake:level=3,spheres=1"  a built-in scene with its parameters
 * Built-in scenes are deterministic: the same spec gives the same primitives.
 */
#ifndef ACCEL_SCENE_H
#define ACCEL_SCENE_H

#include <stdio.h>

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- construction (used by loaders and generators) ----------------------- */

/* Growable triangle/sphere lists used while a scene is generated or loaded. */
typedef struct {
    float *tris;
    size_t tri_count, tri_cap;
    float *spheres;
    size_t sphere_count, sphere_cap;
} scene_builder;

int scene_builder_add_tri(scene_builder *b, vec3 a, vec3 c, vec3 d, accel_error *err);
int scene_builder_add_sphere(scene_builder *b, vec3 centre, float radius, accel_error *err);
/* Reserve room for n more triangles up front (when a file states its counts). */
int scene_builder_reserve_tris(scene_builder *b, size_t n, accel_error *err);
void scene_builder_free(scene_builder *b);

/* Moves the builder's arrays into *s, computes live list, degenerate count and
 * bounds, and sets a default camera framing the bounds (generators then
 * override it). The builder is left empty. Fails above 2^32-2 primitives. */
int scene_finish(scene_builder *b, const char *name, accel_scene *s, accel_error *err);

void scene_free(accel_scene *s);
/* Releases a description of many meshes (accel_scene.instances): every
 * mesh, the meshes and instances arrays; scene_free calls it. */
void scene_instances_free(accel_instances *set);

/* The default view of a mesh file: framing its primitives like
 * scene_finish's, from the side the mesh faces (scanned figures, +y up,
 * lean toward their front: scene.c mesh_front). */
void scene_camera_front(accel_scene *s);

/* A camera looking at the bounds from direction `from` (not normalized),
 * far enough that the whole box fits the field of view. */
accel_camera scene_camera_framing(box3 bounds, vec3 from, float fov_deg);

/* ---- loading ------------------------------------------------------------- */

/* Loads OBJ, PLY or OFF by extension (case-insensitive). Errors name the
 * file and the line (text) or byte offset (binary). */
/* A camera the ray generators can use: finite, a field of view in
 * (0, 180) degrees, eye and look distinct, up not along the view (checked
 * in double). Messages start with "camera: ". */
int scene_camera_check(const accel_camera *cam, accel_error *err);
int scene_load_file(const char *path, accel_scene *s, accel_error *err);
int scene_load_obj(const char *path, scene_builder *b, accel_error *err);
int scene_load_ply(const char *path, scene_builder *b, accel_error *err);
int scene_load_off(const char *path, scene_builder *b, accel_error *err);
/* The same parsers on a memory buffer (fuzz targets and tests); `name` is
 * used in error messages. */
int scene_parse_obj(const char *name, const char *data, size_t size, scene_builder *b,
                    accel_error *err);
int scene_parse_ply(const char *name, const char *data, size_t size, scene_builder *b,
                    accel_error *err);
int scene_parse_off(const char *name, const char *data, size_t size, scene_builder *b,
                    accel_error *err);

/* ---- scene files (.scene, FORMATS.md): many meshes, instances ------------- */

/* How a scene file finds its meshes. NULL options (or a NULL load_mesh):
 * a SOURCE whose name (before ':') is a built-in scene is made by
 * scene_create, anything else is a mesh file relative to `dir` (a .scene
 * file cannot be a mesh: scene files do not nest, so they cannot cycle). */
typedef struct {
    uint64_t max_prims; /* limit on the flattened scene's primitives (0: the id limit 2^32-2) */
    int (*load_mesh)(void *ctx, const char *source, const char *dir, accel_scene *mesh,
                     accel_error *err);
    void *ctx;
} scene_file_options;

/* Reads a .scene file: the flattened scene, with its meshes and instances in
 * s->instances. Every error names the file and the line. */
int scene_load_scene(const char *path, accel_scene *s, accel_error *err);
/* The same on a buffer (not NUL-terminated); `name` is used in messages and
 * `dir` is the folder mesh paths are relative to ("" for the current one). */
int scene_parse_scene(const char *name, const char *dir, const char *data, size_t size,
                      const scene_file_options *opt, accel_scene *s, accel_error *err);

/* ---- built-in scenes ----------------------------------------------------- */

struct scene_compose;

typedef struct {
    const char *name;
    const char *summary;
    const accel_param_def *params;
    size_t param_count;
    /* Fills the builder and sets *cam and *light (the scene's default view). */
    int (*generate)(const double *values, scene_builder *b, accel_camera *cam, vec3 *light,
                    accel_error *err);
    const char *small_spec; /* a spec with a few thousand primitives, for tests */
    /* Scenes of many meshes set this instead of generate: they fill a
     * scene_compose (compose.h) with meshes and instances, which is then
     * flattened, keeping the description in accel_scene.instances. */
    int (*compose)(const double *values, struct scene_compose *c, accel_camera *cam, vec3 *light,
                   accel_error *err);
} scene_generator;

extern const scene_generator *const scene_generators[];
extern const size_t scene_generator_count;

/* Creates a scene from a spec: a built-in name (with parameters) or a file. */
int scene_create(const char *spec, accel_scene *s, accel_error *err);
/* Checks a spec without making the scene: a built-in's name and parameters,
 * or a file's extension and that it opens. Tools call it before any work. */
int scene_spec_check(const char *spec, accel_error *err);

/* Writes the scene as OBJ (spheres tessellated, `segments` around). */
int scene_export_obj(const accel_scene *s, const char *path, int segments, accel_error *err);

/* Copy of s with every primitive transformed by p*scale + offset (stability
 * cases: far from the origin, tiny, huge). The camera moves along. */
int scene_transform(const accel_scene *s, float scale, vec3 offset, accel_scene *out,
                    accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
