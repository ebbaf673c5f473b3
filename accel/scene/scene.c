/*
 * scene.c - scene construction, framing, export and transformation.
 *
 * Loaders and generators append primitives to a scene_builder; scene_finish
 * then fixes the scene: the list of live (non-degenerate) primitives, the
 * bounds and a default camera. A triangle is degenerate when its edge cross
 * product is exactly zero in double precision: such a triangle has no
 * interior, keeps its id (FORMATS.md numbering) and is never hit.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/prim.h"
#include "scene/scene.h"

#define SCENE_MAX_PRIMS 0xFFFFFFFEu /* ids are uint32 and 0xFFFFFFFF means miss */

static int grow(void **p, size_t *cap, size_t need, size_t elem, accel_error *err)
{
    if (need <= *cap) return 0;
    size_t n = *cap ? *cap : 1024;
    while (n < need) {
        if (n > ((size_t)SCENE_MAX_PRIMS + 1) / 2 + 1) { n = need; break; }
        n *= 2;
    }
    if (n > SIZE_MAX / elem) return accel_fail(err, ACCEL_ERR_NOMEM, "scene too large");
    void *q = realloc(*p, n * elem);
    if (!q)
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory growing a scene to %zu primitives",
                          n);
    *p = q;
    *cap = n;
    return 0;
}

int scene_builder_reserve_tris(scene_builder *b, size_t n, accel_error *err)
{
    if (n > SCENE_MAX_PRIMS || b->tri_count + n > SCENE_MAX_PRIMS)
        return accel_fail(err, ACCEL_ERR_RANGE, "too many triangles (%zu)", n);
    return grow((void **)&b->tris, &b->tri_cap, b->tri_count + n, 9 * sizeof(float), err);
}

int scene_builder_add_tri(scene_builder *b, vec3 a, vec3 c, vec3 d, accel_error *err)
{
    if (b->tri_count >= SCENE_MAX_PRIMS)
        return accel_fail(err, ACCEL_ERR_RANGE, "more than %u triangles", SCENE_MAX_PRIMS);
    if (b->tri_count == b->tri_cap) {
        int rc = grow((void **)&b->tris, &b->tri_cap, b->tri_count + 1, 9 * sizeof(float), err);
        if (rc) return rc;
    }
    float *t = b->tris + 9 * b->tri_count++;
    t[0] = a.x, t[1] = a.y, t[2] = a.z;
    t[3] = c.x, t[4] = c.y, t[5] = c.z;
    t[6] = d.x, t[7] = d.y, t[8] = d.z;
    return 0;
}

int scene_builder_add_sphere(scene_builder *b, vec3 centre, float radius, accel_error *err)
{
    if (b->sphere_count == b->sphere_cap) {
        int rc = grow((void **)&b->spheres, &b->sphere_cap, b->sphere_count + 1,
                      4 * sizeof(float), err);
        if (rc) return rc;
    }
    float *s = b->spheres + 4 * b->sphere_count++;
    s[0] = centre.x, s[1] = centre.y, s[2] = centre.z, s[3] = radius;
    return 0;
}

void scene_builder_free(scene_builder *b)
{
    free(b->tris);
    free(b->spheres);
    memset(b, 0, sizeof *b);
}

accel_camera scene_camera_framing(box3 bounds, vec3 from, float fov_deg)
{
    /* Tightest distance at which all 8 box corners project inside a square
     * frame: a corner at offset q from the centre needs
     * d >= max(|q.right|, |q.up|) / tan(fov/2) - q.fwd. */
    accel_camera c;
    vec3 centre = box3_center(bounds);
    vec3 back = v3_norm(from), fwd = v3_scale(back, -1.0f);
    c.up = fabsf(fwd.y) > 0.99f ? v3(0, 0, 1) : v3(0, 1, 0);
    vec3 right = v3_norm(v3_cross(fwd, c.up));
    vec3 up = v3_cross(right, fwd);
    float t = tanf(0.5f * fov_deg * 3.14159265f / 180.0f);
    float dist = 0.0f;
    for (int i = 0; i < 8; i++) {
        vec3 p = v3(i & 1 ? bounds.max.x : bounds.min.x, i & 2 ? bounds.max.y : bounds.min.y,
                    i & 4 ? bounds.max.z : bounds.min.z);
        vec3 q = v3_sub(p, centre);
        float need = fmaxf(fabsf(v3_dot(q, right)), fabsf(v3_dot(q, up))) / t - v3_dot(q, fwd);
        dist = fmaxf(dist, need);
    }
    if (!(dist > 0.0f)) dist = 1.0f;
    c.look_at = centre;
    c.eye = v3_add(centre, v3_scale(back, dist * 1.02f));
    c.fov_deg = fov_deg;
    return c;
}

static accel_camera camera_fit_prims(const accel_scene *s, vec3 from, float fov_deg);

int scene_finish(scene_builder *b, const char *name, accel_scene *s, accel_error *err)
{
    memset(s, 0, sizeof *s);
    size_t n = b->tri_count + b->sphere_count;
    if (n > SCENE_MAX_PRIMS)
        return accel_fail(err, ACCEL_ERR_RANGE, "%s: %zu primitives exceed the limit of %u", name,
                          n, SCENE_MAX_PRIMS);
    snprintf(s->name, sizeof s->name, "%s", name);
    s->tri_count = (uint32_t)b->tri_count;
    s->sphere_count = (uint32_t)b->sphere_count;
    s->prim_count = (uint32_t)n;
    s->live = malloc((n ? n : 1) * sizeof *s->live);
    if (!s->live) return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory", name);
    s->tris = b->tris;
    s->spheres = b->spheres;
    b->tris = b->spheres = NULL;
    b->tri_count = b->tri_cap = b->sphere_count = b->sphere_cap = 0;
    s->bounds = box3_empty();
    for (uint32_t i = 0; i < s->prim_count; i++) {
        int dead;
        if (i < s->tri_count) {
            dead = accel_tri_is_degenerate(s->tris + 9 * (size_t)i);
        } else {
            float r = s->spheres[4 * (size_t)(i - s->tri_count) + 3];
            dead = !(r > 0.0f) || !isfinite(r);
        }
        if (dead) {
            s->degenerate_count++;
            continue;
        }
        s->live[s->live_count++] = i;
        s->bounds = box3_union(s->bounds, accel_prim_bounds(s, i));
    }
    box3 frame = box3_is_empty(s->bounds) ? (box3){{-1, -1, -1}, {1, 1, 1}} : s->bounds;
    s->camera = box3_is_empty(s->bounds) ? scene_camera_framing(frame, v3(0.3f, 0.35f, 1.0f), 40.0f)
                                          : camera_fit_prims(s, v3(0.3f, 0.35f, 1.0f), 40.0f);
    vec3 ext = box3_extent(frame);
    s->light = v3_add(frame.max, v3_scale(ext, 0.5f));
    return 0;
}

/* Frames the primitives themselves (not their box) from direction `from`:
 * centres the view on the projected extent of every vertex and moves the
 * eye to the nearest distance at which all of them fit the square frame,
 * so that a mesh fills the image as a real render would. */
static accel_camera camera_fit_prims(const accel_scene *s, vec3 from, float fov_deg)
{
    accel_camera c = scene_camera_framing(s->bounds, from, fov_deg);
    vec3 fwd = v3_norm(v3_sub(c.look_at, c.eye));
    vec3 right = v3_norm(v3_cross(fwd, c.up));
    vec3 up = v3_cross(right, fwd);
    vec3 centre = c.look_at;
    float x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int pass = 0; pass < 2; pass++) {
        float t = tanf(0.5f * fov_deg * 3.14159265f / 180.0f), dist = 0.0f;
        for (uint32_t k = 0; k < s->live_count; k++) {
            box3 b = accel_prim_bounds(s, s->live[k]);
            int corners = s->live[k] < s->tri_count ? 3 : 8;
            const float *tri = s->tris + 9 * (size_t)s->live[k];
            for (int i = 0; i < corners; i++) {
                vec3 p = corners == 3 ? v3_load(tri + 3 * i)
                                      : v3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                           i & 4 ? b.max.z : b.min.z);
                vec3 q = v3_sub(p, centre);
                float x = v3_dot(q, right), y = v3_dot(q, up);
                if (pass == 0) {
                    x0 = minf(x0, x), x1 = maxf(x1, x), y0 = minf(y0, y), y1 = maxf(y1, y);
                } else {
                    dist = maxf(dist, maxf(fabsf(x), fabsf(y)) / t - v3_dot(q, fwd));
                }
            }
        }
        if (pass == 0) {
            if (!(x0 <= x1)) return c;
            centre = v3_add(centre, v3_add(v3_scale(right, 0.5f * (x0 + x1)),
                                           v3_scale(up, 0.5f * (y0 + y1))));
        } else if (dist > 0.0f) {
            c.look_at = centre;
            c.eye = v3_sub(centre, v3_scale(fwd, dist * 1.03f));
        }
    }
    return c;
}

/* The horizontal direction a mesh faces, for its default view: scanned
 * figures stand with +y up and lean toward their front (a head and arms
 * forward of the legs, a back shell or haunches behind), so the front is
 * where the centroid of the vertices above the bounds' middle lies seen
 * from the centroid of those below it. The armadillo of the Stanford
 * repository faces -z this way, the bunny -x and -z (its head). A lean
 * under 2% of the horizontal extent (a flat sheet, an upright finely
 * tessellated body) keeps +z; vertices count once per triangle, so a
 * coarse mesh's triangulation can tilt its front. */
static vec3 mesh_front(const accel_scene *s)
{
    double sum[2][3] = {{0, 0, 0}, {0, 0, 0}};
    float mid = 0.5f * (s->bounds.min.y + s->bounds.max.y);
    for (uint32_t k = 0; k < s->live_count; k++) {
        if (s->live[k] >= s->tri_count) continue;
        const float *tri = s->tris + 9 * (size_t)s->live[k];
        for (int i = 0; i < 3; i++) {
            double *acc = sum[tri[3 * i + 1] > mid];
            acc[0] += tri[3 * i], acc[1] += tri[3 * i + 2], acc[2] += 1;
        }
    }
    vec3 ext = box3_extent(s->bounds);
    if (!(sum[0][2] > 0 && sum[1][2] > 0)) return v3(0, 0, 1);
    double dx = sum[1][0] / sum[1][2] - sum[0][0] / sum[0][2];
    double dz = sum[1][1] / sum[1][2] - sum[0][1] / sum[0][2];
    double len = sqrt(dx * dx + dz * dz);
    if (!(len >= 0.02 * fmax(ext.x, ext.z))) return v3(0, 0, 1);
    return v3((float)(dx / len), 0, (float)(dz / len));
}

void scene_camera_front(accel_scene *s)
{
    if (box3_is_empty(s->bounds)) return;
    /* The usual default direction (0.3, 0.35, 1), turned about +y so that
     * its +z goes to the front: a three-quarter view from slightly above. */
    vec3 f = mesh_front(s);
    vec3 from = v3(0.3f * f.z + f.x, 0.35f, -0.3f * f.x + f.z);
    s->camera = camera_fit_prims(s, from, 40.0f);
}

void scene_instances_free(accel_instances *set)
{
    if (!set) return;
    for (uint32_t i = 0; i < set->mesh_count; i++) scene_free(&set->meshes[i]);
    free(set->meshes);
    free(set->instances);
    memset(set, 0, sizeof *set);
}

void scene_free(accel_scene *s)
{
    free(s->tris);
    free(s->spheres);
    free(s->live);
    if (s->instances) {
        scene_instances_free(s->instances);
        free(s->instances);
    }
    memset(s, 0, sizeof *s);
}

int scene_export_obj(const accel_scene *s, const char *path, int segments, accel_error *err)
{
    FILE *f = fopen(path, "w");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open for writing", path);
    if (segments < 3) segments = 3;
    fprintf(f, "# gridbvh scene %s: %u triangles, %u spheres (tessellated)\n", s->name,
            s->tri_count, s->sphere_count);
    size_t v = 1;
    for (uint32_t i = 0; i < s->tri_count; i++) {
        const float *t = s->tris + 9 * (size_t)i;
        for (int k = 0; k < 3; k++)
            fprintf(f, "v %.9g %.9g %.9g\n", t[3 * k], t[3 * k + 1], t[3 * k + 2]);
        fprintf(f, "f %zu %zu %zu\n", v, v + 1, v + 2);
        v += 3;
    }
    int rings = segments / 2 < 2 ? 2 : segments / 2;
    for (uint32_t i = 0; i < s->sphere_count; i++) {
        const float *sp = s->spheres + 4 * (size_t)i;
        /* UV sphere: rings+1 latitude rows of segments vertices (poles repeated). */
        for (int r = 0; r <= rings; r++) {
            double th = 3.14159265358979 * r / rings;
            for (int k = 0; k < segments; k++) {
                double ph = 2 * 3.14159265358979 * k / segments;
                fprintf(f, "v %.9g %.9g %.9g\n", sp[0] + sp[3] * sin(th) * cos(ph),
                        sp[1] + sp[3] * cos(th), sp[2] + sp[3] * sin(th) * sin(ph));
            }
        }
        for (int r = 0; r < rings; r++)
            for (int k = 0; k < segments; k++) {
                size_t a = v + (size_t)r * segments + k;
                size_t bb = v + (size_t)r * segments + (k + 1) % segments;
                size_t c = a + segments, d = bb + segments;
                if (r > 0) fprintf(f, "f %zu %zu %zu\n", a, bb, c);
                if (r < rings - 1) fprintf(f, "f %zu %zu %zu\n", bb, d, c);
            }
        v += (size_t)(rings + 1) * segments;
    }
    int bad = ferror(f);
    if (fclose(f) != 0 || bad) return accel_fail(err, ACCEL_ERR_IO, "%s: write failed", path);
    return 0;
}

int scene_transform(const accel_scene *s, float scale, vec3 offset, accel_scene *out,
                    accel_error *err)
{
    scene_builder b = {0};
    int rc = scene_builder_reserve_tris(&b, s->tri_count, err);
    for (uint32_t i = 0; rc == 0 && i < s->tri_count; i++) {
        const float *t = s->tris + 9 * (size_t)i;
        vec3 p[3];
        for (int k = 0; k < 3; k++) p[k] = v3_add(v3_scale(v3_load(t + 3 * k), scale), offset);
        rc = scene_builder_add_tri(&b, p[0], p[1], p[2], err);
    }
    for (uint32_t i = 0; rc == 0 && i < s->sphere_count; i++) {
        const float *sp = s->spheres + 4 * (size_t)i;
        rc = scene_builder_add_sphere(&b, v3_add(v3_scale(v3_load(sp), scale), offset),
                                      sp[3] * fabsf(scale), err);
    }
    char name[256];
    snprintf(name, sizeof name, "%.100s*%g+(%g,%g,%g)", s->name, scale, offset.x, offset.y,
             offset.z);
    if (rc == 0) rc = scene_finish(&b, name, out, err);
    scene_builder_free(&b);
    if (rc) return rc;
    out->camera = s->camera;
    out->camera.eye = v3_add(v3_scale(s->camera.eye, scale), offset);
    out->camera.look_at = v3_add(v3_scale(s->camera.look_at, scale), offset);
    out->light = v3_add(v3_scale(s->light, scale), offset);
    return 0;
}

static int cam_finite3(vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

int scene_camera_check(const accel_camera *cam, accel_error *err)
{
    if (!cam_finite3(cam->eye) || !cam_finite3(cam->look_at) || !cam_finite3(cam->up))
        return accel_fail(err, ACCEL_ERR_RANGE, "camera: eye, look and up must be finite");
    if (!(cam->fov_deg > 0 && cam->fov_deg < 180))
        return accel_fail(err, ACCEL_ERR_RANGE, "camera: field of view %g is not in (0, 180) degrees",
                          cam->fov_deg);
    /* In double, so that a tiny but valid view vector is not lost to
     * float underflow of its squared length. */
    double f[3] = {(double)cam->look_at.x - cam->eye.x, (double)cam->look_at.y - cam->eye.y,
                   (double)cam->look_at.z - cam->eye.z};
    double u[3] = {cam->up.x, cam->up.y, cam->up.z};
    double fl = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(fl > 0))
        return accel_fail(err, ACCEL_ERR_RANGE, "camera: eye and look are the same point (%g, %g, %g)",
                          cam->eye.x, cam->eye.y, cam->eye.z);
    if (!(ul > 0)) return accel_fail(err, ACCEL_ERR_RANGE, "camera: the up vector is zero");
    double c[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]};
    double sine = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / (fl * ul);
    /* 1e-4: under 0.006 degrees apart the image's right axis is mostly rounding noise. */
    if (!(sine > 1e-4))
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "camera: up (%g, %g, %g) is parallel to the view direction", cam->up.x,
                          cam->up.y, cam->up.z);
    return 0;
}
