/*
 * prims.c - primitive bounds and centroids of a scene's primitives, and the
 * primitive store every kind builds over (see accel.h).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"
#include "core/prim.h"

box3 accel_prim_bounds(const accel_scene *s, uint32_t prim)
{
    box3 b = box3_empty();
    if (prim < s->tri_count) {
        const float *t = s->tris + 9 * (size_t)prim;
        b = box3_grow(b, v3_load(t));
        b = box3_grow(b, v3_load(t + 3));
        b = box3_grow(b, v3_load(t + 6));
    } else {
        const float *sp = s->spheres + 4 * (size_t)(prim - s->tri_count);
        vec3 r = v3(sp[3], sp[3], sp[3]);
        b.min = v3_sub(v3_load(sp), r);
        b.max = v3_add(v3_load(sp), r);
    }
    return b;
}

vec3 accel_prim_centroid(const accel_scene *s, uint32_t prim)
{
    return box3_center(accel_prim_bounds(s, prim));
}


/* ---- the primitive store --------------------------------------------------- */

/* Spreads the low 10 bits of x to every third bit (bit i -> bit 3i). */
static uint32_t spread_bits(uint32_t x)
{
    x &= 1023;
    x = (x | (x << 16)) & 0x030000FF;
    x = (x | (x << 8)) & 0x0300F00F;
    x = (x | (x << 4)) & 0x030C30C3;
    x = (x | (x << 2)) & 0x09249249;
    return x;
}

/* 30-bit Morton code of a point quantized to 1024 steps per axis of box. */
static uint32_t morton_of(vec3 p, box3 box)
{
    const float c[3] = {p.x, p.y, p.z};
    const float lo[3] = {box.min.x, box.min.y, box.min.z};
    const float hi[3] = {box.max.x, box.max.y, box.max.z};
    uint32_t q[3];
    for (int a = 0; a < 3; a++) {
        float x = (c[a] - lo[a]) / (hi[a] - lo[a]) * 1024.0f;
        q[a] = !(x > 0.0f) ? 0 : (x >= 1023.0f ? 1023 : (uint32_t)x);
    }
    return spread_bits(q[0]) | (spread_bits(q[1]) << 1) | (spread_bits(q[2]) << 2);
}

/* Stable LSD radix sort of n items (key in the high 32 bits, payload low)
 * by their 30-bit keys, in three passes of 10 bits; tmp holds n items. */
static void sort_by_key(uint64_t *v, uint64_t *tmp, size_t n)
{
    for (int shift = 32; shift < 62; shift += 10) {
        size_t count[1025] = {0};
        for (size_t i = 0; i < n; i++) count[((v[i] >> shift) & 1023) + 1]++;
        for (int b = 0; b < 1024; b++) count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++) tmp[count[(v[i] >> shift) & 1023]++] = v[i];
        memcpy(v, tmp, n * sizeof *v);
    }
}

void accel_prim_store_free(accel_prim_store *st)
{
    free(st->prims.tris);
    free(st->prims.spheres);
    free(st->prims.live);
    free(st->scene_id);
    memset(st, 0, sizeof *st);
}

size_t accel_prim_store_bytes(const accel_prim_store *st)
{
    const accel_scene *p = &st->prims;
    return (size_t)p->tri_count * 9 * sizeof(float) + (size_t)p->sphere_count * 4 * sizeof(float) +
           (size_t)p->prim_count * 2 * sizeof(uint32_t);
}

/*
 * Copies the live primitives (triangles first, then spheres, each group in
 * Morton order of the centroids when `reorder`). Traversal then reads
 * primitives that are neighbours in space from neighbouring memory,
 * whatever the scene's file order.
 */
int accel_prim_store_build(const accel_scene *scene, int reorder, accel_prim_store *out,
                           accel_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t n = scene->live_count, tris = 0;
    while (tris < n && scene->live[tris] < scene->tri_count) tris++; /* live is increasing */
    accel_scene *l = &out->prims;
    snprintf(l->name, sizeof l->name, "%s", scene->name);
    l->tri_count = tris;
    l->sphere_count = n - tris;
    l->prim_count = n;
    l->live_count = n;
    l->bounds = scene->bounds;
    l->camera = scene->camera;
    l->light = scene->light;
    l->tris = accel_alloc_large((size_t)tris * 9 + 1, sizeof *l->tris, sizeof(void *));
    l->spheres = malloc(((size_t)(n - tris) * 4 + 1) * sizeof *l->spheres);
    l->live = malloc(((size_t)n + 1) * sizeof *l->live);
    out->scene_id = malloc(((size_t)n + 1) * sizeof *out->scene_id);
    uint64_t *order = accel_alloc_large((size_t)n + 1, sizeof *order, sizeof(void *));
    uint64_t *tmp = reorder ? accel_alloc_large((size_t)n + 1, sizeof *tmp, sizeof(void *)) : NULL;
    if (!l->tris || !l->spheres || !l->live || !out->scene_id || !order || (reorder && !tmp)) {
        free(order);
        free(tmp);
        accel_prim_store_free(out);
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory copying %u primitives", n);
    }
    box3 box = scene->bounds;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t prim = scene->live[k];
        uint64_t key = reorder ? morton_of(accel_prim_centroid(scene, prim), box) : 0;
        order[k] = key << 32 | prim;
    }
    if (reorder) {
        sort_by_key(order, tmp, tris);
        sort_by_key(order + tris, tmp, n - tris);
    }
    for (uint32_t k = 0; k < n; k++) {
        uint32_t prim = (uint32_t)order[k];
        out->scene_id[k] = prim;
        l->live[k] = k;
        if (k < tris)
            memcpy(l->tris + 9 * (size_t)k, scene->tris + 9 * (size_t)prim, 9 * sizeof(float));
        else
            memcpy(l->spheres + 4 * (size_t)(k - tris),
                   scene->spheres + 4 * (size_t)(prim - scene->tri_count), 4 * sizeof(float));
    }
    free(order);
    free(tmp);
    return ACCEL_OK;
}

/* accel.h: the simplest conservative walk, over the store's primitives in
 * order, each bounding box grown by pad and tested with the robust slab
 * test against the current [t_near, t_max]. */
int accel_prim_store_walk(const accel_prim_store *st, const accel_ray *ray, float pad,
                          accel_walk_visit visit, void *ctx, uint32_t *steps)
{
    if (!visit) return 0;
    accel_ray_prep p;
    if (!accel_prep_ray(ray, &p)) return 0;
    float t_max = p.t_far;
    const accel_scene *s = &st->prims;
    for (uint32_t k = 0; k < s->prim_count && t_max >= p.t_near; k++) {
        box3 b = accel_prim_bounds(s, k);
        float lo[3] = {b.min.x - pad, b.min.y - pad, b.min.z - pad};
        float hi[3] = {b.max.x + pad, b.max.y + pad, b.max.z + pad};
        float entry;
        (*steps)++;
        if (box3_slab(lo, hi, p.org, p.inv_dir, p.neg, p.t_near, t_max, &entry))
            t_max = visit(ctx, st->scene_id[k], t_max);
    }
    return 0;
}
