/*
 * stiff_post.c - what the stiff cases of stiff.c share once their rays are
 * made: dropping repeated rays, the shadow rays of the leak rays, and the
 * reference on an exactly translated copy of a scene far from the origin.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"
#include "rays/stiff.h"
#include "rays/stiff_impl.h"

/* Drops repeated rays (bitwise equal: a repeat is no new trial), keeping
 * the first of each in order; leak_begin follows. One hash table over all
 * rays (a flat scene's lattice repeats rays far apart in the sequence). */
int stiff_dedupe(stiff_case *c, accel_error *err)
{
    size_t n = c->rays.count, cap = 16, w = 0, lb = c->leak_begin >= n ? SIZE_MAX : 0;
    while (cap < 2 * n) cap *= 2;
    if (n >= UINT32_MAX) return accel_fail(err, ACCEL_ERR_RANGE, "stiff: %zu rays", n);
    uint32_t *tab = calloc(cap, sizeof *tab);
    if (!tab) return accel_fail(err, ACCEL_ERR_NOMEM, "stiff: out of memory for %zu rays", n);
    accel_ray *r = c->rays.rays;
    for (size_t i = 0; i < n; i++) {
        if (i == c->leak_begin) lb = w;
        uint64_t h = 1469598103934665603ull; /* FNV-1a over the ray's bytes, then mixed */
        const unsigned char *b = (const unsigned char *)&r[i];
        for (size_t j = 0; j < sizeof r[i]; j++) h = (h ^ b[j]) * 1099511628211ull;
        h ^= h >> 33, h *= 0xff51afd7ed558ccdull, h ^= h >> 33;
        size_t slot = (size_t)h & (cap - 1);
        int dup = 0;
        while (tab[slot] && !(dup = !memcmp(&r[tab[slot] - 1], &r[i], sizeof r[i])))
            slot = (slot + 1) & (cap - 1);
        if (dup) continue;
        r[w] = r[i];
        tab[slot] = (uint32_t)++w;
    }
    free(tab);
    c->rays.count = w;
    c->leak_begin = lb == SIZE_MAX ? w : lb;
    return 0;
}

/* Shadow rays: the leak rays of a case whose every leak ray aims at a
 * point of the (convex) mesh it starts in, at t = 1: with t_far = 1.25 the
 * segment ends outside that mesh, so it crosses its surface. */
int stiff_make_shadow(stiff_case *c, accel_error *err)
{
    size_t n = c->rays.count - c->leak_begin;
    if (!n) return 0;
    c->shadow.rays = malloc(n * sizeof *c->shadow.rays);
    if (!c->shadow.rays) return accel_fail(err, ACCEL_ERR_NOMEM, "stiff: out of memory");
    memcpy(c->shadow.rays, c->rays.rays + c->leak_begin, n * sizeof *c->shadow.rays);
    for (size_t i = 0; i < n; i++) c->shadow.rays[i].t_far = 1.25f;
    c->shadow.count = n;
    return 0;
}

/* x - t in float, when exact (1), checked in double, where the difference
 * of two floats of the magnitudes here is exact. */
static int exact_sub(float x, float t, float *out)
{
    *out = x - t;
    return (double)*out == (double)x - (double)t;
}

/* The translated copy: every vertex and origin coordinate minus T, each
 * exact, or 0 (nothing made). */
static int translate(const accel_scene *s, const accel_ray *rays, size_t n, const float T[3],
                     accel_scene *out, accel_ray **moved)
{
    accel_error err = {0};
    scene_builder b = {0};
    int ok = s->sphere_count == 0 && scene_builder_reserve_tris(&b, s->tri_count, &err) == 0;
    for (uint32_t t = 0; ok && t < s->tri_count; t++) {
        float v[9];
        for (int j = 0; j < 9; j++) ok &= exact_sub(s->tris[9 * (size_t)t + j], T[j % 3], &v[j]);
        ok = ok && scene_builder_add_tri(&b, v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]),
                                         v3(v[6], v[7], v[8]), &err) == 0;
    }
    *moved = ok ? malloc((n ? n : 1) * sizeof **moved) : NULL;
    ok = ok && *moved;
    for (size_t i = 0; ok && i < n; i++) {
        (*moved)[i] = rays[i];
        ok = exact_sub(rays[i].ox, T[0], &(*moved)[i].ox) && exact_sub(rays[i].oy, T[1], &(*moved)[i].oy) &&
             exact_sub(rays[i].oz, T[2], &(*moved)[i].oz);
    }
    ok = ok && scene_finish(&b, s->name, out, &err) == 0;
    scene_builder_free(&b);
    if (ok && out->live_count != s->live_count) scene_free(out), ok = 0;
    if (!ok) free(*moved), *moved = NULL;
    return ok;
}

/* The oracle's culling boxes are widened by 2^-20 of the largest coordinate
 * (core/oracle.c): at 1e6 and more they are wider than the objects here
 * and it tests every triangle. Its double test only ever uses vertex -
 * origin and vertex - vertex differences (core/prim.h), which an exact
 * translation of both leaves bitwise the same, so the copy moved to the
 * origin has bitwise the same answer, at the usual speed. */
void stiff_reference(const accel_scene *s, const accel_ray *rays, accel_hit *hits, size_t n,
                     int threads)
{
    vec3 c = box3_center(s->bounds), e = box3_extent(s->bounds);
    float size = fmaxf(e.x, fmaxf(e.y, e.z)), far = fmaxf(fabsf(c.x), fmaxf(fabsf(c.y), fabsf(c.z)));
    accel_scene moved;
    accel_ray *mr = NULL;
    const float T[3] = {c.x, c.y, c.z};
    if (far > 1e3f * size && translate(s, rays, n, T, &moved, &mr)) {
        accel_reference_trace(&moved, mr, hits, n, threads);
        scene_free(&moved);
        free(mr);
        return;
    }
    accel_reference_trace(s, rays, hits, n, threads);
}
