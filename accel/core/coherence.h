/*
 * coherence.h - packets in any ray order: the one layer every packet mode
 * (grid, nested_grid, bvh binary packets, bvh wide packets, instanced)
 * puts in front of its packet kernel.
 *
 * The packet kernels take 64 consecutive rays as a packet. Given rays in
 * any order (a renderer's scanline order, secondary rays, a shuffled file),
 * accel_coherent_intersect / _occluded
 *   1. key every ray by direction octant and a Morton code of its quantized
 *      origin and octahedral direction (only the dimensions that vary in
 *      the batch, all with the same number of bits),
 *   2. radix-sort the keys (O(n), stable, passes over constant bytes
 *      skipped),
 *   3. keep the caller's order when its groups of 64 are as tight as the
 *      sorted ones (8x8 tiles stay as they are, no copy), else gather the
 *      rays in sorted order,
 *   4. trace every group of 64 whose rays share an octant and whose
 *      directions and origins are close (a measured spread, coherence.c)
 *      with the packet kernel, every other group with the kind's
 *      single-ray kernel, so incoherent (diffuse) rays never pay for
 *      packets (kinds whose packet kernel has its own fallback skip this),
 *   5. scatter the answers (and the per-ray counters) back to the caller's
 *      order.
 * Before all this, a block of converging rays (shadow rays cast to one
 * point light: finite ends no farther apart than their origins, origins
 * within a narrow cone) whose groups of 64 mostly converge as they come is
 * traced as it comes, those groups as packets whatever their spreads, no
 * keys and no sort (coherence.c: CONE_SPREAD, FOLD); other blocks are
 * sorted, their groups judged by the spreads alone.
 * Before that, a block that is a raster (a camera's rays in pixel order,
 * found from the steps between consecutive rays) skips the keys: 8x8 tile
 * order and rasters up to 16 wide are kept, wider ones gathered into tiles
 * of whole rows (8x8 when a block holds 8 rows: 8192 rays, 8 rows of 1024;
 * 4096-ray blocks gave 1024-wide images 16x4 tiles, and the grid packets
 * 0.75 of their tile-order speed in scanline order where 8x8 give 0.96).
 * A block that no sort could make coherent (diffuse bounces, by its
 * extents) goes ray by ray in its order, for the kinds with a split.
 * Exactness: a packet kernel's answer for a ray must not depend on the
 * other rays of its packet (tests/test_coherence.c traces shuffled ray sets
 * against the unshuffled ones for every packet mode). The binary and 4-wide
 * BVH packets give the same bits whatever the mates. The grids' packets
 * give the same primitive and occlusion, but t/u/v may move by a few float
 * steps: core/prim.h's watertight test decides a hit within its error of
 * the current nearest one in double, so which primitives a ray tested
 * before (its packet's walk, mailbox repeats) picks the float or the
 * double computation of the same hit. The 8-wide packets keep t and the
 * primitive but, rarely, not u/v: bunny's 96x72 primaries in scanline
 * against tile order, packets kept as given, differ in u/v on 4 of 6912
 * rays (sphereflake, the test's scene, on none). Scratch memory is per thread,
 * allocated once (freed when the thread ends).
 */
#ifndef ACCEL_CORE_COHERENCE_H
#define ACCEL_CORE_COHERENCE_H

#include "accel.h"
#include "core/variant.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef void (*accel_hit_batch_fn)(const void *accel, const accel_ray *rays, accel_hit *hits,
                                   size_t count, accel_counters *c);
typedef void (*accel_occ_batch_fn)(const void *accel, const accel_ray *rays, uint8_t *occ,
                                   size_t count, accel_counters *c);

/* How the packet modes order their rays (process-wide; tools set it once
 * before tracing): ACCEL_ORDER_SORT (default) forms packets as above;
 * ACCEL_ORDER_KEEP hands the caller's order to the packet kernel as it is,
 * 64 consecutive rays a packet. SORT became the default once it stopped
 * losing in tile order: 8x8 tiles are found as a raster 8 wide and kept
 * (no keys, no copy), scanline blocks are gathered into tiles by index.
 * Measured before that (armadillo 1024x768 primaries, one thread):
 * bvh:width=8,traverse=packet 15.6 Mrays/s sorted against 41.0 kept in
 * tile order: every kept block had paid for keys and a sort first. */
enum { ACCEL_ORDER_KEEP = 0, ACCEL_ORDER_SORT = 1 };
void accel_coherence_set(int order);
int accel_coherence_get(void);

/* Rays per sorting block: a larger batch is ordered block by block. */
#define ACCEL_COHERENCE_BLOCK 8192

/* The batch entry of a packet mode: packet(accel, ...) traces groups of 64
 * consecutive rays as packets, single(accel, ...) the incoherent rays.
 * single == NULL: no split, every group goes to the packet kernel (the
 * grids: their packet kernels fall back to single rays themselves, on
 * their walk's own criterion, and a collapsed grid's single-ray walk costs
 * thousands of tests per ray where its packets cost a hundred). */
void accel_coherent_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                              size_t count, accel_counters *c, accel_hit_batch_fn packet,
                              accel_hit_batch_fn single);
void accel_coherent_occluded(const void *accel, const accel_ray *rays, uint8_t *occ, size_t count,
                             accel_counters *c, accel_occ_batch_fn packet,
                             accel_occ_batch_fn single);

/* A packet mode's two batch entries, as ACCEL_KERNEL_ENTRIES (variant.h)
 * but through the layer above: HIT_TABLE/OCC_TABLE are the packet kernels,
 * SINGLE_HIT/SINGLE_OCC the kind's single-ray batch functions (taking
 * const void *accel) for the incoherent groups, or NULL. */
#define ACCEL_COHERENT_ENTRIES(HIT_FN, OCC_FN, ACCEL_T, HIT_TABLE, OCC_TABLE, FLAGS, SINGLE_HIT,  \
                               SINGLE_OCC)                                                      \
    static void HIT_FN##_packets_(const void *a, const accel_ray *r, accel_hit *h, size_t n,      \
                                  accel_counters *c)                                            \
    {                                                                                           \
        accel_run_kernel(&HIT_TABLE, a, r, h, n, c, FLAGS((ACCEL_T *)a));                       \
    }                                                                                           \
    static void OCC_FN##_packets_(const void *a, const accel_ray *r, uint8_t *o, size_t n,        \
                                  accel_counters *c)                                            \
    {                                                                                           \
        accel_run_kernel(&OCC_TABLE, a, r, o, n, c, FLAGS((ACCEL_T *)a));                       \
    }                                                                                           \
    void HIT_FN(ACCEL_T *accel, const accel_ray *rays, accel_hit *hits, size_t count,           \
                accel_counters *c)                                                              \
    {                                                                                           \
        accel_coherent_intersect(accel, rays, hits, count, c, HIT_FN##_packets_, SINGLE_HIT);   \
    }                                                                                           \
    void OCC_FN(ACCEL_T *accel, const accel_ray *rays, uint8_t *occ, size_t count,              \
                accel_counters *c)                                                              \
    {                                                                                           \
        accel_coherent_occluded(accel, rays, occ, count, c, OCC_FN##_packets_, SINGLE_OCC);     \
    }

/* Counts of the last-block decisions, summed process-wide (relaxed atomics,
 * once per block): blocks kept in their order, blocks sorted, rays traced in
 * packets and rays sent to the single-ray kernel, raster blocks gathered
 * into tiles. For tests and tools. */
typedef struct {
    uint64_t kept_blocks, sorted_blocks, packet_rays, single_rays, tiled_blocks;
} accel_coherence_stats;
void accel_coherence_stats_get(accel_coherence_stats *out);

#ifdef __cplusplus
}
#endif

#endif
