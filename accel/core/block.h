/*
 * block.h - the primitive block every structure may store its triangles
 * in: 4 or 8 triangles side by side (structure of arrays, one row per
 * vertex coordinate), copied in the order the structure visits them, with
 * their scene ids. core/block_test.h tests one ray against a whole block
 * (the watertight test on all lanes at once, the exact fallback); the
 * wide BVH stores its leaves so, and the grids their cells
 * (grid:cells=blocks), so that the study compares structures on one
 * triangle kernel.
 *
 * A block that holds fewer primitives than lanes repeats its last one
 * (accel_block_fill): a repeated lane can only give the same answer again,
 * so no lane ever needs masking and no padding value can leak a hit.
 */
#ifndef ACCEL_CORE_BLOCK_H
#define ACCEL_CORE_BLOCK_H

#include <assert.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    float v[3][3][8]; /* v[vertex][axis][lane] */
    uint32_t id[8];
} accel_block8;

typedef struct {
    float v[3][3][4];
    uint32_t id[4];
} accel_block4;

static_assert(sizeof(accel_block8) == 320, "a block of 8 is 36 + 4 bytes per primitive");
static_assert(sizeof(accel_block4) == 160, "a block of 4 is 36 + 4 bytes per primitive");
static_assert(offsetof(accel_block8, id) == 288 && offsetof(accel_block4, id) == 144,
              "ids follow the vertex rows");

/* One lane of a block's rows (v[(3 * vertex + axis) * lanes + lane]) from
 * a primitive's 9 floats. */
static inline void accel_block_put_lane(float *v, int lanes, int lane, const float *tri)
{
    for (int vtx = 0; vtx < 3; vtx++)
        for (int axis = 0; axis < 3; axis++)
            v[(3 * vtx + axis) * lanes + lane] = tri[3 * vtx + axis];
}

/* Fills the rows v and ids of one block of `lanes` (4 or 8) from count
 * (1..lanes) primitives: primitive k's 9 floats at tris + 9 * k and its id
 * ids[k]; the lanes past count repeat the last primitive. */
static inline void accel_block_fill(float *v, uint32_t *id, int lanes, const float *const *tris,
                                    const uint32_t *ids, int count)
{
    for (int lane = 0; lane < lanes; lane++) {
        int k = lane < count ? lane : count - 1;
        accel_block_put_lane(v, lanes, lane, tris[k]);
        id[lane] = ids[k];
    }
}

#ifdef __cplusplus
}
#endif

#endif
