/*
 * coherence_raster.c - the raster order of the packet layer
 * (core/coherence.h): a camera's rays in pixel order are found from the
 * steps between consecutive rays, and gathered into tiles.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "core/coherence_raster.h"

#define P 64 /* rays per packet, as every packet kernel */

/* ---- raster order ------------------------------------------------------------ */

/* A raster (a camera's rays in pixel order, rows W wide, or 8x8 tiles, which
 * look like a raster 8 wide) steps regularly from ray to ray and jumps at
 * the start of each row: a step (max-norm, origins and directions apart)
 * over RASTER_JUMP times the last regular one is a row start. Going back
 * W - 1 pixels and down one is about W - 1 steps, so rows of at least
 * RASTER_MIN_W rays are told apart from their steps. Whatever this finds,
 * the answers are the same (only the packets change). */
#define RASTER_JUMP 4.0f
#define RASTER_MIN_W 5

static inline void ray_step(const accel_ray *a, const accel_ray *b, float *so, float *sd)
{
    const float ox = fabsf(b->ox - a->ox), oy = fabsf(b->oy - a->oy), oz = fabsf(b->oz - a->oz);
    const float dx = fabsf(b->dx - a->dx), dy = fabsf(b->dy - a->dy), dz = fabsf(b->dz - a->dz);
    const float o = ox > oy ? ox : oy, d = dx > dy ? dx : dy;
    *so = o > oz ? o : oz, *sd = d > dz ? d : dz;
}

/* A step from a to b (max-norm of the origin and direction parts) jumps
 * over the step from c to d: NaN steps jump. */
static inline int jumps(const accel_ray *a, const accel_ray *b, const accel_ray *c,
                        const accel_ray *d)
{
    float so, sd, ro, rd;
    ray_step(a, b, &so, &sd);
    ray_step(c, d, &ro, &rd);
    return !(so <= RASTER_JUMP * ro) || !(sd <= RASTER_JUMP * rd);
}

/* 1 when rays[0..n) look like a raster: rows W long (*w = W, *first = the
 * first row start in the block; *w = 0 when the block holds fewer than
 * two row starts). The rays are scanned up to the second row start; after
 * it, each predicted row start p is checked (a jump from p - 1 to p over
 * the steps on both sides, which agree), not every ray: tile order (W = 8)
 * costs a few operations a ray, and a wrong guess only loses speed. */
int accel_find_raster(const accel_ray *rays, size_t n, size_t *w, size_t *first)
{
    *w = *first = 0;
    if (n < 3) return 0;
    float ro, rd, so, sd;
    ray_step(&rays[0], &rays[1], &ro, &rd);
    ray_step(&rays[1], &rays[2], &so, &sd);
    ro = so < ro ? so : ro, rd = sd < rd ? sd : rd; /* one of the two is in a row */
    size_t i = 1;
    for (; i < n && !*w; i++) {
        ray_step(&rays[i - 1], &rays[i], &so, &sd);
        if (so <= RASTER_JUMP * ro && sd <= RASTER_JUMP * rd) {
            ro = so, rd = sd;
        } else if (!*first) {
            *first = i;
        } else if ((*w = i - *first) < RASTER_MIN_W || *first > *w) {
            return 0;
        }
    }
    if (!*w) return 1; /* a row or two */
    const accel_ray *r = rays;
    for (size_t p = *first + 2 * *w; p < n; p += *w) {
        const size_t q = p + 1 < n ? p + 1 : p - 2; /* the step after p, or before p - 1 */
        if (!jumps(&r[p - 1], &r[p], &r[p - 2], &r[p - 1]) || !jumps(&r[p - 1], &r[p], &r[q - 1], &r[q]) ||
            jumps(&r[p - 2], &r[p - 1], &r[q - 1], &r[q]) || jumps(&r[q - 1], &r[q], &r[p - 2], &r[p - 1]))
            return 0;
    }
    return 1;
}

/* The block's rays in tiles (8 rows of 8, or 4 of 16, 2 of 32: as many
 * whole rows as the block holds) of a raster W wide whose first row
 * starts at index first (0 < first <= W), into idx; the rays of no whole
 * tile (partial rows, a band's last columns) follow in their order.
 * Returns 0 (order kept) when the block holds fewer than two whole rows. */
int accel_tile_order(size_t n, size_t w, size_t first, uint16_t *idx)
{
    const size_t c0 = first < w ? w - first : 0; /* the column of ray 0 */
    const size_t y0 = c0 ? 1 : 0, y1 = (c0 + n) / w, rows = y1 > y0 ? y1 - y0 : 0;
    const size_t th = rows >= 8 ? 8 : rows >= 4 ? 4 : rows >= 2 ? 2 : 0;
    if (!th) return 0;
    const size_t tw = P / th, bands = rows / th, tiles = w / tw;
    size_t k = 0;
    for (size_t b = 0; b < bands; b++)
        for (size_t t = 0; t < tiles; t++)
            for (size_t y = 0; y < th; y++) {
                const size_t base = (y0 + b * th + y) * w + t * tw - c0;
                for (size_t x = 0; x < tw; x++) idx[k++] = (uint16_t)(base + x);
            }
    const size_t yend = y0 + bands * th, xend = tiles * tw;
    size_t x = c0, y = 0;
    for (size_t i = 0; i < n; i++) {
        if (y < y0 || y >= yend || x >= xend) idx[k++] = (uint16_t)i;
        if (++x == w) x = 0, y++;
    }
    return 1;
}

