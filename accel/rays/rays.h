/*
 * rays.h - ray sets, ray and hit files, hit comparison.
 *
 * Ray sets are generated deterministically: every random number comes from a
 * hash of (seed, ray index), so every accelerator and every thread count
 * traces exactly the same rays. Primary rays are emitted in 8x8 pixel tiles
 * (the packet shape of the BVH issue); pixel[i] maps ray i back to its pixel.
 *
 * Secondary rays start at primary hit points computed from the hit's
 * triangle and barycentrics (not o + t*d), offset along the geometric normal
 * with the integer-ULP method of Waechter and Binder, "A Fast and Robust
 * Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6, 2019.
 */
#ifndef ACCEL_RAYS_H
#define ACCEL_RAYS_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    accel_ray *rays;
    uint32_t *pixel; /* pixel index (y*width + x) of each ray, or NULL */
    size_t count;
    int width, height; /* image the rays belong to (0 for a plain ray file) */
} rays_set;

void rays_free(rays_set *r);

/* 0, or ACCEL_ERR_RANGE naming the fault of a camera that defines no view:
 * non-finite vectors, a field of view outside (0, 180) degrees, eye == look,
 * a zero up vector, or up parallel to the view direction. */
int rays_camera_check(const accel_camera *cam, accel_error *err);

/* Pinhole camera rays, W x H, in 8x8 tiles; t range [0, inf]. Fails on a
 * camera rays_camera_check refuses. */
int rays_primary(const accel_camera *cam, int width, int height, rays_set *out, accel_error *err);

/* Hit point, geometric normal facing the incoming ray, and the robustly
 * offset origin for a secondary ray leaving the surface on that side. */
int rays_hit_frame(const accel_scene *s, const accel_ray *r, const accel_hit *h, vec3 *point,
                   vec3 *normal);
vec3 rays_offset_origin(vec3 p, vec3 n);

/* Secondary rays from each primary hit (misses produce no ray; pixel[]
 * follows the primary's pixel):
 *   shadow:  towards s->light, t_far just short of the light (any-hit);
 *   diffuse: one cosine-weighted bounce around the normal;
 *   ao:      `samples` cosine-weighted rays per hit, t_far = ao_radius. */
int rays_shadow(const accel_scene *s, const rays_set *prim, const accel_hit *hits, rays_set *out,
                accel_error *err);
int rays_diffuse(const accel_scene *s, const rays_set *prim, const accel_hit *hits, uint64_t seed,
                 rays_set *out, accel_error *err);
/* The rays of `prim` that hit (hits[i].prim != ACCEL_MISS), each ending
 * exactly at its hit (t_far = hits[i].t): a hit at the very end of the
 * range, where a traversal that culls boxes with an unpadded `entry < t`
 * loses it (the conformance suite's "ending at the hit" set). */
int rays_ending_at_hit(const rays_set *prim, const accel_hit *hits, rays_set *out,
                       accel_error *err);
int rays_ao(const accel_scene *s, const rays_set *prim, const accel_hit *hits, int samples,
            float ao_radius, uint64_t seed, rays_set *out, accel_error *err);

/* The order of a ray set: 8x8 pixel tiles (rays_primary's), scanline
 * (pixel index order, as a renderer writes an image) or a seeded shuffle.
 * rays_reorder puts r's rays (and pixel[]) in that order, stable within a
 * pixel (ao samples stay together); tiles and scanline need pixel[] and
 * width (ACCEL_ERR_SPEC without them), shuffle works on any set. */
typedef enum { RAYS_ORDER_TILES8, RAYS_ORDER_SCANLINE, RAYS_ORDER_SHUFFLE } rays_order;
int rays_order_parse(const char *name, rays_order *out); /* 0, or -1 on an unknown name */
int rays_reorder(rays_set *r, rays_order order, uint64_t seed, accel_error *err);

/* A deterministic uniform float in [0,1) from (seed, index, dimension). */
float rays_rand(uint64_t seed, uint64_t index, uint32_t dim);

/* ---- files (FORMATS.md) --------------------------------------------------- */

int rays_write(const char *path, const accel_ray *rays, size_t count, accel_error *err);
int rays_read(const char *path, rays_set *out, accel_error *err);
int hits_write(const char *path, const accel_hit *hits, size_t count, accel_error *err);
int hits_read(const char *path, accel_hit **hits, size_t *count, accel_error *err);

/* Rays that can hit nothing by FORMATS.md's rule and are traced as misses:
 * a NaN or infinite origin or direction component, a zero direction, a NaN
 * tnear or tfar, or tnear > tfar. Returns how many; *first is the index of
 * the first (SIZE_MAX if none) and *why names its fault. */
size_t rays_invalid_count(const accel_ray *rays, size_t count, size_t *first, const char **why);

/* ---- comparison (FORMATS.md rule) -----------------------------------------
 *
 * FORMATS.md "Comparing two hit files": two closest-hit answers agree when
 * both miss; or they name the same triangle with t within
 * tol(t) = 1e-4 max(1, |t|) and u, v each within 1e-3; or they name two
 * different triangles at the same t and the ray really hits each of them
 * there (a true tie at a shared edge or vertex, or coincident triangles),
 * which only the scene can tell. Without the scene (scene == NULL) such a
 * ray is an unverified tie: counted apart, never as an agreement. A wrong
 * triangle at the right t, or the right triangle at a wrong t, u or v,
 * is a disagreement. */

typedef enum {
    HITS_AGREE,           /* both miss, or the same triangle at the same t, u, v */
    HITS_TIE,             /* different triangles, the same t, both verified on the scene */
    HITS_TIE_UNVERIFIED,  /* different triangles, the same t, no scene to verify them on */
    HITS_HOLE,            /* the reference hits, the other misses */
    HITS_FALSE_HIT,       /* the reference misses, the other hits */
    HITS_DISAGREE         /* both hit, and not as above */
} hits_match;

typedef struct {
    size_t rays;
    size_t agree;           /* HITS_AGREE and HITS_TIE */
    size_t ties;            /* of agree: verified ties (different triangles) */
    size_t unverified;      /* HITS_TIE_UNVERIFIED: neither agree nor a disagreement */
    size_t holes;           /* a hits, b misses */
    size_t false_hits;      /* a misses, b hits */
    size_t disagreements;   /* both hit, not the same answer and not a true tie */
    size_t first_bad;       /* index of the first ray that does not agree, or SIZE_MAX */
} hits_diff;

/* Does ray r really hit primitive h->prim of scene s at h->t, with h's u
 * and v (a triangle) or u = v = 0 (a sphere)? Decided in double on the
 * scene's own floats: the edge functions of the watertight test may be
 * negative by the rounding bound of a float tracer (so a float tracer's
 * pick at a shared edge counts), t must be within tol(t) of the exact t
 * and inside [t_near, t_far] (within tol), u and v within 1e-3. A
 * degenerate or out-of-range primitive is never hit. */
int hits_verify(const accel_scene *s, const accel_ray *r, const accel_hit *h);

/* Hit b (the tested answer) against a (the reference) on one ray. scene
 * and ray may be NULL: then different triangles at the same t are
 * HITS_TIE_UNVERIFIED. */
hits_match hits_match_ray(const accel_scene *scene, const accel_ray *ray, const accel_hit *a,
                          const accel_hit *b);
/* 1 when hits_match_ray says HITS_AGREE or HITS_TIE. */
int hits_agree(const accel_scene *scene, const accel_ray *ray, const accel_hit *a,
               const accel_hit *b);
/* Compares b against the reference a over n rays; scene and rays may be
 * NULL (a comparison of two files: ties by distance only are counted in
 * `unverified`). */
hits_diff hits_compare(const accel_scene *scene, const accel_ray *rays, const accel_hit *a,
                       const accel_hit *b, size_t n);

/* Any-hit answers (FORMATS.md "Any-hit answers"): both miss or both hit.
 * With the scene, an occluded answer of b whose triangle is not really hit
 * (hits_verify) is a false hit too. */
typedef struct {
    size_t rays;
    size_t agree;
    size_t leaks;            /* a occluded, b lets the ray through */
    size_t false_occlusions; /* a clear, b occluded */
    size_t false_hits;       /* both occluded, b's triangle not hit at its t (scene only) */
    size_t first_bad;
} hits_anyhit_diff;
hits_anyhit_diff hits_compare_anyhit(const accel_scene *scene, const accel_ray *rays,
                                     const accel_hit *a, const accel_hit *b, size_t n);

#ifdef __cplusplus
}
#endif

#endif
