/*
 * coherence.c - packets in any ray order (core/coherence.h): the raster
 * path (a camera's rays in pixel order: tiles by index arithmetic), sort
 * keys, the keep-or-sort decision, the coherent/incoherent split and the
 * scatter back to the caller's order.
 *
 * Where the time went before the raster path (perf, armadillo 1024x768
 * primaries): every block paid for keys (two divisions and a branchy
 * Hilbert loop per ray), a radix sort and group extents before the
 * keep-or-sort decision, even in tile order, where every block was kept:
 * the layer took about as long as the grid's packet kernel. Now tile order
 * costs one pass over the first 16 rays and a check per row start (perf:
 * 1.5% of bvh:width=8 packets), scanline order an index gather.
 *
 * The sort key follows ray-sorting work (Garanzha & Loop, "Fast ray sorting
 * and breadth-first packet traversal for GPU ray tracing", EG 2010: a key of
 * quantized origin and direction; Moon et al., "Cache-oblivious ray
 * reordering", TOG 2010: a space-filling curve over ray space): the octant
 * of the direction on top, under it a Morton code interleaving the
 * quantized origin (x, y, z) and the octahedral direction
 * (|dx|, |dy|) / (|dx| + |dy| + |dz|) (Meyer et al., "On floating-point
 * normal vectors", EGSR 2010). Only the dimensions that vary in a block
 * take part, each with the same number of bits, so a camera's rays (one
 * origin) are ordered by a 2D Morton curve over the image: groups of 64
 * become 8x8-like tiles whatever the file order.
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/coherence.h"
#include "core/coherence_raster.h"

#define BLOCK ACCEL_COHERENCE_BLOCK
#define P 64             /* rays per packet, as every packet kernel */
#define DIMS 5           /* origin x, y, z; octahedral direction x, y */
#define MORTON_BITS 28   /* under the 3 octant bits: a 31-bit key */
#define MAX_DIM_BITS 10  /* per dimension: 1024 levels */
/* Two varying dimensions (a camera's rays: one origin) take a Hilbert curve
 * instead, 256 x 256 cells for at most 4096 rays: a Morton curve's jumps
 * (between quadrants) split a third of a camera's groups of 64 into far
 * apart pieces, the Hilbert curve's consecutive cells are neighbours. */
#define HILBERT_BITS 8
/* A group is traced as a packet when its rays share an octant, its
 * directions span at most DIR_SPREAD in octahedral units (an octant is the
 * unit triangle; 0.03 is about 3 degrees) and its origins at most
 * ORIGIN_FRAC of the block's origin extent. Diffuse bounces sorted in a
 * 4096-ray block keep about one bit per dimension per group of 64 (5
 * dimensions, 6 bits): a spread of half the range, far above both. So do
 * shuffled primaries: 4096 of armadillo's 1024x768 rays sorted make groups
 * of about 128x96 pixels (5 degrees); as packets they ran at half the
 * single-ray speed with a spread limit of 0.1 (bvh:width=8). */
#define DIR_SPREAD 0.03f
#define ORIGIN_FRAC 0.25f
/* Converging rays as they come: a block whose groups of 64, as given,
 * mostly share an octant and converge (finite ends o + t_far d no farther
 * apart, max-norm, than their origins: shadow rays cast to one point
 * light) and fold (see FOLD) is traced in its order, those groups as
 * packets whatever the spreads of their directions and origins, no keys
 * and no sort. A tile's shadow rays exceed the spreads wherever its hits
 * lie at different depths (a third of animated's groups) and went ray by
 * ray after a sort: as packets, on animated's shadow rays (800x600, tile
 * order, 1 thread), bvh:width=8,traverse=packet ran 1.5x and
 * instanced:traverse=packet 1.3x faster (issue 41). Their origins must
 * lie within CONE_SPREAD of the shortest ray's length (max-norm): tiles of
 * animated's shadow rays (800x600) have at most 0.16 in 19 of 20 groups,
 * of sphereflake's (88x128) 0.6 in 7 of 8; the same rays shuffled 0.68 to
 * 0.9 and 1.9 to 2.9. Other blocks are sorted as before, their groups
 * judged by the spreads alone. */
#define CONE_SPREAD 0.5f
/* The caller's order is kept when its groups are at most this much looser
 * than the sorted ones (summed extents of the quantized coordinates). */
#define KEEP_SLACK 1.125

static atomic_int order_mode = ACCEL_ORDER_SORT;
static _Atomic uint64_t st_kept, st_sorted, st_tiled, st_packet, st_single;

void accel_coherence_set(int order) { atomic_store(&order_mode, order); }
int accel_coherence_get(void) { return atomic_load(&order_mode); }

void accel_coherence_stats_get(accel_coherence_stats *out)
{
    out->kept_blocks = atomic_load(&st_kept), out->sorted_blocks = atomic_load(&st_sorted);
    out->packet_rays = atomic_load(&st_packet), out->single_rays = atomic_load(&st_single);
    out->tiled_blocks = atomic_load(&st_tiled);
}

/* ---- per-thread scratch, allocated once ----------------------------------- */

typedef struct {
    accel_ray rays[BLOCK];          /* the block in sorted order */
    accel_hit hits[BLOCK];          /* answers in sorted order (occ: as bytes) */
    uint32_t steps[BLOCK], prims[BLOCK];
    uint32_t key[BLOCK], key2[BLOCK];
    uint16_t idx[BLOCK], idx2[BLOCK];
    uint16_t q[BLOCK][DIMS];        /* quantized coordinates, caller's order */
    uint8_t oct[BLOCK];             /* direction octants, caller's order */
    uint8_t coherent[BLOCK / P];
} scratch;

/* The Hilbert index of cell (x, y) of a 2^bits square (Hilbert 1891; the
 * loop of the usual xy2d, e.g. Wikipedia's "Hilbert curve"): per level the
 * quadrant's digit, then the quadrant rotated into the curve's frame. */
static inline uint32_t hilbert_index(uint32_t x, uint32_t y, int bits)
{
    uint32_t d = 0;
    for (uint32_t s = 1u << (bits - 1); s > 0; s >>= 1) {
        const uint32_t rx = (x & s) != 0, ry = (y & s) != 0;
        d += s * s * ((3u * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) x = s - 1 - (x & (s - 1)), y = s - 1 - (y & (s - 1));
            const uint32_t t = x; x = y, y = t;
        }
    }
    return d;
}

static pthread_key_t scratch_key;
static pthread_once_t scratch_once = PTHREAD_ONCE_INIT;
static uint32_t spread_table[DIMS + 1][1u << MAX_DIM_BITS];
/* hilbert_table[y << HILBERT_BITS | x]: hilbert_index(x, y), looked up (the
 * loop's branches on random rays' bits mispredict: perf put it at half of
 * the layer's time on shuffled primaries) */
static uint16_t hilbert_table[1u << (2 * HILBERT_BITS)];

/* spread_table[k][v]: the bits of v at positions 0, k, 2k, ... */
static void init_once(void)
{
    (void)pthread_key_create(&scratch_key, free);
    for (int k = 1; k <= DIMS; k++)
        for (uint32_t v = 0; v < (1u << MAX_DIM_BITS); v++) {
            uint32_t s = 0;
            for (int b = 0; b < MAX_DIM_BITS && b * k < 32; b++) s |= ((v >> b) & 1u) << (b * k);
            spread_table[k][v] = s;
        }
    for (uint32_t y = 0; y < (1u << HILBERT_BITS); y++)
        for (uint32_t x = 0; x < (1u << HILBERT_BITS); x++)
            hilbert_table[y << HILBERT_BITS | x] = (uint16_t)hilbert_index(x, y, HILBERT_BITS);
}

static scratch *get_scratch(void)
{
    pthread_once(&scratch_once, init_once);
    scratch *s = pthread_getspecific(scratch_key);
    if (!s) {
        s = aligned_alloc(64, (sizeof(scratch) + 63) / 64 * 64);
        if (s && pthread_setspecific(scratch_key, s) != 0) free(s), s = NULL;
    }
    return s;
}

/* ---- keys ------------------------------------------------------------------ */

typedef struct {
    int active[DIMS], k, bits;   /* the varying dimensions, how many, bits each */
    float lo[DIMS], scale[DIMS]; /* quantization: (x - lo) * scale */
    float dir_limit, origin_limit; /* the coherence spreads in quantized units */
    float dir_ext, ext[DIMS];      /* the largest direction extent, each extent */
} quant;

/* Whether the rays [g, end) converge: finite ends no farther apart than
 * their origins, and origins within CONE_SPREAD of the shortest ray's
 * length (a narrow cone; see ORIGIN_FRAC). */
static int converging(const accel_ray *rays, size_t g, size_t end)
{
    float olo[3] = {INFINITY, INFINITY, INFINITY}, ohi[3] = {-INFINITY, -INFINITY, -INFINITY};
    float elo[3] = {INFINITY, INFINITY, INFINITY}, ehi[3] = {-INFINITY, -INFINITY, -INFINITY};
    float len = INFINITY;
    for (size_t i = g; i < end; i++) {
        const accel_ray *r = &rays[i];
        if (!(fabsf(r->t_far) < INFINITY)) return 0;
        const float ax = fabsf(r->dx), ay = fabsf(r->dy), az = fabsf(r->dz);
        const float l = fabsf(r->t_far) * (ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az));
        len = l < len ? l : len;
        const float o[3] = {r->ox, r->oy, r->oz};
        const float e[3] = {r->ox + r->t_far * r->dx, r->oy + r->t_far * r->dy, r->oz + r->t_far * r->dz};
        for (int a = 0; a < 3; a++) {
            olo[a] = o[a] < olo[a] ? o[a] : olo[a], ohi[a] = o[a] > ohi[a] ? o[a] : ohi[a];
            elo[a] = e[a] < elo[a] ? e[a] : elo[a], ehi[a] = e[a] > ehi[a] ? e[a] : ehi[a];
        }
    }
    float oe = 0.0f, ee = 0.0f;
    for (int a = 0; a < 3; a++) {
        oe = ohi[a] - olo[a] > oe ? ohi[a] - olo[a] : oe;
        ee = ehi[a] - elo[a] > ee ? ehi[a] - elo[a] : ee;
    }
    return ee <= oe && oe <= CONE_SPREAD * len; /* NaN: no */
}

static inline void ray_coords(const accel_ray *r, float x[DIMS], unsigned *oct)
{
    const float ax = fabsf(r->dx), ay = fabsf(r->dy), az = fabsf(r->dz), l1 = ax + ay + az;
    x[0] = r->ox, x[1] = r->oy, x[2] = r->oz;
    const float inv = l1 > 0.0f ? 1.0f / l1 : 0.0f; /* NaN stays NaN, quantized to 0 below */
    x[3] = ax * inv, x[4] = ay * inv;
    *oct = (r->dx < 0.0f) | (unsigned)(r->dy < 0.0f) << 1 | (unsigned)(r->dz < 0.0f) << 2;
}

/* The block's bounds (finite values only), its varying dimensions and the
 * quantization that gives every varying dimension the same bits. */
static void plan_quant(const accel_ray *rays, size_t n, quant *qz)
{
    float lo[DIMS], hi[DIMS];
    for (int d = 0; d < DIMS; d++) lo[d] = INFINITY, hi[d] = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        float x[DIMS];
        unsigned oct;
        ray_coords(&rays[i], x, &oct);
        for (int d = 0; d < DIMS; d++)
            if (fabsf(x[d]) < INFINITY) lo[d] = x[d] < lo[d] ? x[d] : lo[d], hi[d] = x[d] > hi[d] ? x[d] : hi[d];
    }
    float ext_o = 0.0f, ext_d = 0.0f;
    for (int d = 0; d < DIMS; d++) {
        if (!(hi[d] > lo[d])) lo[d] = hi[d] = 0.0f;
        if (d < 3 && hi[d] - lo[d] > ext_o) ext_o = hi[d] - lo[d];
        if (d >= 3 && hi[d] - lo[d] > ext_d) ext_d = hi[d] - lo[d];
    }
    qz->k = 0;
    for (int d = 0; d < DIMS; d++)
        if (hi[d] > lo[d]) qz->active[qz->k++] = d;
    qz->bits = qz->k ? MORTON_BITS / qz->k : 0;
    if (qz->bits > MAX_DIM_BITS) qz->bits = MAX_DIM_BITS;
    if (qz->k == 2) qz->bits = HILBERT_BITS;
    const float levels = (float)((1u << qz->bits) - 1u);
    for (int d = 0; d < DIMS; d++) {
        const float e = d < 3 ? ext_o : ext_d;
        qz->lo[d] = lo[d], qz->ext[d] = hi[d] - lo[d];
        qz->scale[d] = e > 0.0f && !(hi[d] == lo[d]) ? levels / e : 0.0f;
    }
    qz->dir_ext = ext_d;
    qz->dir_limit = ext_d > 0.0f ? DIR_SPREAD * levels / ext_d : 0.0f;
    qz->origin_limit = ORIGIN_FRAC * levels;
}

/* 1 when no group of 64 can pass the spread limits however the block is
 * sorted. A camera's block (directions alone vary, k <= 2 of them) evenly
 * filled leaves a group (64/n * the product of the extents)^(1/k) wide
 * (shuffled primaries of armadillo 1024x768: 0.048, over DIR_SPREAD; a
 * block of 4 scanline rows: far under it). Otherwise n rays spread over k
 * varying dimensions leave a group 1 / (n / 64)^(1/k) of each extent, k
 * taken as at most 3 (shadow rays' directions follow their origins):
 * diffuse bounces (a direction extent near 1) leave 1/4 of it, far above
 * the limit; twice the limits leave room for uneven spreads (armadillo's
 * shadow rays, an extent of 0.2, still sort into packets). */
static int hopeless(const quant *qz, size_t n)
{
    if (!qz->k || n <= P) return 0;
    int origins = 0;
    float area = (float)P / (float)n;
    for (int j = 0; j < qz->k; j++) origins |= qz->active[j] < 3, area *= qz->ext[qz->active[j]];
    if (!origins) return powf(area, 1.0f / (float)qz->k) > DIR_SPREAD;
    const float frac = powf((float)P / (float)n, 1.0f / (float)(qz->k < 3 ? qz->k : 3));
    return frac * qz->dir_ext > 2.0f * DIR_SPREAD || frac > 2.0f * ORIGIN_FRAC;
}

static inline uint16_t quantize(float x, float lo, float scale, float levels)
{
    float v = (x - lo) * scale;
    v = v > 0.0f ? v : 0.0f; /* NaN and below the range: 0 */
    v = v < levels ? v : levels;
    return (uint16_t)v;
}

/* Keys and quantized coordinates of the block; returns the summed extents
 * of the quantized coordinates over the groups of 64 in the given order. */
static double make_keys(const accel_ray *rays, size_t n, const quant *qz, scratch *s)
{
    const float levels = (float)((1u << qz->bits) - 1u);
    const uint32_t *spread = spread_table[qz->k ? qz->k : 1];
    double sum = 0.0;
    for (size_t g = 0; g < n; g += P) {
        const size_t end = g + P < n ? g + P : n;
        uint16_t mn[DIMS], mx[DIMS];
        for (int d = 0; d < DIMS; d++) mn[d] = 0xFFFF, mx[d] = 0;
        for (size_t i = g; i < end; i++) {
            float x[DIMS];
            unsigned oct;
            ray_coords(&rays[i], x, &oct);
            uint32_t m = 0;
            for (int j = 0; j < qz->k; j++) {
                const int d = qz->active[j];
                const uint16_t v = quantize(x[d], qz->lo[d], qz->scale[d], levels);
                s->q[i][d] = v;
                mn[d] = v < mn[d] ? v : mn[d], mx[d] = v > mx[d] ? v : mx[d];
                m |= spread[v] << (qz->k - 1 - j);
            }
            if (qz->k == 2)
                m = hilbert_table[(uint32_t)s->q[i][qz->active[1]] << HILBERT_BITS |
                                  s->q[i][qz->active[0]]];
            s->oct[i] = (uint8_t)oct;
            s->key[i] = (uint32_t)oct << MORTON_BITS | m;
            s->idx[i] = (uint16_t)i;
        }
        for (int j = 0; j < qz->k; j++) sum += mx[qz->active[j]] - mn[qz->active[j]];
    }
    return sum;
}

/* Stable LSD radix sort of (key, idx) by bytes, skipping constant bytes. */
static void sort_keys(scratch *s, size_t n)
{
    uint32_t hist[4][256];
    memset(hist, 0, sizeof hist);
    for (size_t i = 0; i < n; i++)
        for (int b = 0; b < 4; b++) hist[b][(s->key[i] >> (8 * b)) & 0xFF]++;
    uint32_t *k = s->key, *k2 = s->key2;
    uint16_t *x = s->idx, *x2 = s->idx2;
    for (int b = 0; b < 4; b++) {
        if (hist[b][(k[0] >> (8 * b)) & 0xFF] == n) continue; /* one value: no change */
        uint32_t pos[256], sum = 0;
        for (int v = 0; v < 256; v++) pos[v] = sum, sum += hist[b][v];
        for (size_t i = 0; i < n; i++) {
            const uint32_t p = pos[(k[i] >> (8 * b)) & 0xFF]++;
            k2[p] = k[i], x2[p] = x[i];
        }
        uint32_t *tk = k; k = k2, k2 = tk;
        uint16_t *tx = x; x = x2, x2 = tx;
    }
    if (k != s->key) {
        memcpy(s->key, k, n * sizeof *k);
        memcpy(s->idx, x, n * sizeof *x);
    }
}

/* Summed group extents in sorted order (s->idx), as make_keys's. */
static double sorted_extent(const scratch *s, size_t n, const quant *qz)
{
    double sum = 0.0;
    for (size_t g = 0; g < n; g += P) {
        const size_t end = g + P < n ? g + P : n;
        for (int j = 0; j < qz->k; j++) {
            const int d = qz->active[j];
            uint16_t mn = 0xFFFF, mx = 0;
            for (size_t i = g; i < end; i++) {
                const uint16_t v = s->q[s->idx[i]][d];
                mn = v < mn ? v : mn, mx = v > mx ? v : mx;
            }
            sum += mx - mn;
        }
    }
    return sum;
}

/* Marks the groups of the order map[] (NULL: the caller's) that are
 * coherent enough for a packet; returns how many. */
static size_t classify(scratch *s, size_t n, const quant *qz, const uint16_t *map)
{
    size_t count = 0;
    for (size_t g = 0; g < n; g += P) {
        const size_t end = g + P < n ? g + P : n;
        const uint8_t oct = s->oct[map ? map[g] : g];
        uint16_t mn[DIMS], mx[DIMS];
        for (int d = 0; d < DIMS; d++) mn[d] = 0xFFFF, mx[d] = 0;
        int ok = 1;
        for (size_t i = g; i < end; i++) {
            const size_t r = map ? map[i] : i;
            ok &= s->oct[r] == oct;
            for (int j = 0; j < qz->k; j++) {
                const int d = qz->active[j];
                const uint16_t v = s->q[r][d];
                mn[d] = v < mn[d] ? v : mn[d], mx[d] = v > mx[d] ? v : mx[d];
            }
        }
        for (int j = 0; j < qz->k && ok; j++) {
            const int d = qz->active[j];
            const float spread = (float)(mx[d] - mn[d]);
            ok = d < 3 ? spread <= qz->origin_limit : spread <= qz->dir_limit;
        }
        s->coherent[g / P] = (uint8_t)ok;
        count += (size_t)ok;
    }
    return count;
}

/* Converging rays (shadow rays to a point light, in an order that keeps
 * neighbours together, see CONE_SPREAD): a group's origins fold back on
 * themselves when the path from ray to ray (max-norm steps) is at least
 * FOLD times the group's origin extent, as a tile's 8 rows do (median 5.9
 * to 6.5 on animated, sphereflake and armadillo), where a scanline's 64
 * consecutive rays run straight along one row (median 2.05 on armadillo,
 * whose shadow rays as such strips ran at 0.70 of the sorted ones:
 * bvh:width=8,traverse=packet, 800x600). */
#define FOLD 3.0f
/* Group [g, end): 1 when it converges; *fold when its origins fold too. */
static int converging_group(const accel_ray *rays, size_t g, size_t end, int *fold)
{
    const accel_ray *r0 = &rays[g];
    const unsigned oct0 = (r0->dx < 0.0f) | (unsigned)(r0->dy < 0.0f) << 1 | (unsigned)(r0->dz < 0.0f) << 2;
    float path = 0.0f, lo[3] = {r0->ox, r0->oy, r0->oz}, hi[3] = {r0->ox, r0->oy, r0->oz};
    *fold = 0;
    for (size_t i = g + 1; i < end; i++) {
        const accel_ray *r = &rays[i], *q = &rays[i - 1];
        if (((r->dx < 0.0f) | (unsigned)(r->dy < 0.0f) << 1 | (unsigned)(r->dz < 0.0f) << 2) != oct0) return 0;
        const float o[3] = {r->ox, r->oy, r->oz};
        const float st[3] = {fabsf(r->ox - q->ox), fabsf(r->oy - q->oy), fabsf(r->oz - q->oz)};
        path += st[0] > st[1] ? (st[0] > st[2] ? st[0] : st[2]) : (st[1] > st[2] ? st[1] : st[2]);
        for (int a = 0; a < 3; a++) lo[a] = o[a] < lo[a] ? o[a] : lo[a], hi[a] = o[a] > hi[a] ? o[a] : hi[a];
    }
    if (!converging(rays, g, end)) return 0;
    float ext = hi[0] - lo[0];
    ext = hi[1] - lo[1] > ext ? hi[1] - lo[1] : ext;
    ext = hi[2] - lo[2] > ext ? hi[2] - lo[2] : ext;
    *fold = path >= FOLD * ext;
    return 1;
}

/* Whether the block goes as it comes: its groups, 3 in 4 or more, converge
 * and, 1 in 2 or more, fold; then each group is marked coherent when it
 * converges. One group in 8 is looked at first (a block that is not such
 * costs an eighth of a pass). */
static int converging_block(const accel_ray *rays, size_t n, scratch *s)
{
    const size_t groups = (n + P - 1) / P;
    for (int pass = 0; pass < 2; pass++) {
        const size_t stride = pass ? 1 : 8, looked = (groups + stride - 1) / stride;
        size_t conv = 0, folded = 0;
        for (size_t k = 0; k < groups; k += stride) {
            const size_t g = k * P, end = g + P < n ? g + P : n;
            int fold, ok = converging_group(rays, g, end, &fold);
            conv += (size_t)ok, folded += (size_t)(ok && fold);
            if (pass) s->coherent[k] = (uint8_t)ok;
        }
        if (conv < looked * 3 / 4 || folded < looked / 2) return 0;
    }
    return 1;
}

/* ---- tracing ---------------------------------------------------------------- */

typedef struct {
    const void *accel;
    accel_hit_batch_fn hit_packet, hit_single;
    accel_occ_batch_fn occ_packet, occ_single;
    size_t esz; /* sizeof(accel_hit), or 1 for any hit */
} job;

static void call(const job *j, int packet, const accel_ray *rays, void *out, size_t n,
                 accel_counters *c)
{
    if (j->esz == 1)
        (packet ? j->occ_packet : j->occ_single)(j->accel, rays, out, n, c);
    else
        (packet ? j->hit_packet : j->hit_single)(j->accel, rays, out, n, c);
}

/* Traces rays[0..n) into out in runs of equally classified groups; the
 * per-ray counters go to steps/prims (either may be NULL) at the same
 * index. */
static void trace_runs(const job *j, const scratch *s, const accel_ray *rays, char *out, size_t n,
                       accel_counters *c, uint32_t *steps, uint32_t *prims)
{
    uint64_t packed = 0;
    for (size_t start = 0; start < n;) {
        const int coh = s->coherent[start / P];
        size_t end = start;
        while (end < n && s->coherent[end / P] == coh) end += P;
        if (end > n) end = n;
        uint32_t *rs = steps ? steps + start : NULL, *rp = prims ? prims + start : NULL;
        if (c && !coh) {
            /* The single-ray runs' counters without their per-level steps:
             * the packet kernels do not split steps by level (nested_grid),
             * and a batch's levels must add up to its steps or be zero. */
            accel_counters sub;
            memset(&sub, 0, sizeof sub);
            sub.ray_steps = rs, sub.ray_prims = rp;
            call(j, 0, rays + start, out + start * j->esz, end - start, &sub);
            memset(sub.level_steps, 0, sizeof sub.level_steps);
            accel_counters_add(c, &sub);
        } else {
            if (c) c->ray_steps = rs, c->ray_prims = rp;
            call(j, coh, rays + start, out + start * j->esz, end - start, c);
        }
        if (coh) packed += end - start;
        start = end;
    }
    atomic_fetch_add_explicit(&st_packet, packed, memory_order_relaxed);
    atomic_fetch_add_explicit(&st_single, n - packed, memory_order_relaxed);
}

/* Traces the block in the order idx (all groups as classified in
 * s->coherent) and scatters the answers and per-ray counters back. */
static void trace_gathered(const job *j, scratch *s, const accel_ray *rays, char *out, size_t n,
                           accel_counters *c, uint32_t *steps, uint32_t *prims)
{
    for (size_t i = 0; i < n; i++) s->rays[i] = rays[s->idx[i]];
    trace_runs(j, s, s->rays, (char *)s->hits, n, c, steps ? s->steps : NULL,
               prims ? s->prims : NULL);
    if (j->esz == 1)
        for (size_t i = 0; i < n; i++) out[s->idx[i]] = ((const char *)s->hits)[i];
    else
        for (size_t i = 0; i < n; i++) ((accel_hit *)out)[s->idx[i]] = s->hits[i];
    if (steps)
        for (size_t i = 0; i < n; i++) steps[s->idx[i]] = s->steps[i];
    if (prims)
        for (size_t i = 0; i < n; i++) prims[s->idx[i]] = s->prims[i];
}

/* A raster block: kept as it comes (8x8 tiles, narrow rasters, a row or
 * two) or gathered into tiles, every group a packet. Returns 0 when the
 * block is no raster. */
static int trace_raster(const job *j, scratch *s, const accel_ray *rays, char *out, size_t n,
                        accel_counters *c, uint32_t *steps, uint32_t *prims)
{
    size_t w, first;
    if (!accel_find_raster(rays, n, &w, &first)) return 0;
    memset(s->coherent, 1, (n + P - 1) / P);
    if (w > ACCEL_RASTER_KEEP_W && accel_tile_order(n, w, first, s->idx)) {
        trace_gathered(j, s, rays, out, n, c, steps, prims);
        atomic_fetch_add_explicit(&st_tiled, 1, memory_order_relaxed);
    } else {
        call(j, 1, rays, out, n, c);
        atomic_fetch_add_explicit(&st_kept, 1, memory_order_relaxed);
        atomic_fetch_add_explicit(&st_packet, n, memory_order_relaxed);
    }
    return 1;
}

/* One block of at most BLOCK rays: a raster's tiles, or keys, the
 * keep-or-sort decision, the split, the trace and the scatter back. */
static void trace_block(const job *j, scratch *s, const accel_ray *rays, char *out, size_t n,
                        accel_counters *c)
{
    uint32_t *steps = c ? c->ray_steps : NULL, *prims = c ? c->ray_prims : NULL;
    if (trace_raster(j, s, rays, out, n, c, steps, prims)) return;
    const int split = j->esz == 1 ? j->occ_single != NULL : j->hit_single != NULL;
    /* Converging rays whose groups of 64 are mostly packets as they come
     * and mostly folded (shadow rays cast from a tiled image's hits): no
     * keys, no sort. A group of rays with an infinite end fails at its
     * first ray. */
    if (converging_block(rays, n, s)) {
        if (!split) memset(s->coherent, 1, (n + P - 1) / P);
        trace_runs(j, s, rays, out, n, c, steps, prims);
        atomic_fetch_add_explicit(&st_kept, 1, memory_order_relaxed);
        return;
    }
    quant qz;
    plan_quant(rays, n, &qz);
    /* Without a coherent group (none possible, or none after the sort) the
     * block goes as it comes, no copy: ray by ray where the kind has a
     * split, else to the packet kernel, whose own fallback then sees
     * packets as incoherent as they come (nested_grid's packets walked
     * sorted shuffled primaries at a quarter of their single-ray speed,
     * armadillo 1024x768). */
    int keep = 1;
    if (!hopeless(&qz, n)) {
        const double kept = make_keys(rays, n, &qz, s);
        if (n > P) {
            sort_keys(s, n);
            keep = kept <= KEEP_SLACK * sorted_extent(s, n, &qz);
        }
        if (!classify(s, n, &qz, keep ? NULL : s->idx)) keep = 1;
    } else {
        memset(s->coherent, 0, (n + P - 1) / P);
    }
    if (!split) memset(s->coherent, 1, (n + P - 1) / P);
    if (keep) {
        trace_runs(j, s, rays, out, n, c, steps, prims);
        atomic_fetch_add_explicit(&st_kept, 1, memory_order_relaxed);
    } else {
        trace_gathered(j, s, rays, out, n, c, steps, prims);
        atomic_fetch_add_explicit(&st_sorted, 1, memory_order_relaxed);
    }
    if (c) c->ray_steps = steps, c->ray_prims = prims;
}

static void run(const job *j, const accel_ray *rays, char *out, size_t count, accel_counters *c)
{
    scratch *s = accel_coherence_get() == ACCEL_ORDER_SORT ? get_scratch() : NULL;
    if (!s) { /* ACCEL_ORDER_KEEP, or no memory: the caller's order as it is */
        call(j, 1, rays, out, count, c);
        return;
    }
    uint32_t *steps = c ? c->ray_steps : NULL, *prims = c ? c->ray_prims : NULL;
    for (size_t b = 0; b < count; b += BLOCK) {
        const size_t n = count - b < BLOCK ? count - b : BLOCK;
        if (c) c->ray_steps = steps ? steps + b : NULL, c->ray_prims = prims ? prims + b : NULL;
        trace_block(j, s, rays + b, out + b * j->esz, n, c);
    }
    if (c) c->ray_steps = steps, c->ray_prims = prims;
}

void accel_coherent_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                              size_t count, accel_counters *c, accel_hit_batch_fn packet,
                              accel_hit_batch_fn single)
{
    const job j = {accel, packet, single, NULL, NULL, sizeof(accel_hit)};
    run(&j, rays, (char *)hits, count, ACCEL_COUNTERS_ON(c)); /* core/variant.h */
}

void accel_coherent_occluded(const void *accel, const accel_ray *rays, uint8_t *occ, size_t count,
                             accel_counters *c, accel_occ_batch_fn packet,
                             accel_occ_batch_fn single)
{
    const job j = {accel, NULL, NULL, packet, single, 1};
    run(&j, rays, (char *)occ, count, ACCEL_COUNTERS_ON(c)); /* core/variant.h */
}
