/*
 * grid_blocks.c - a grid's cells as primitive blocks (grid_core.h,
 * grid_cell_blocks): every cell's references copied, in order, into
 * blocks of 8 triangles (core/block.h), for the shared block test.
 */
#include <stdlib.h>
#include <string.h>

#include "grid_blocks.h"

/* The n primitives ids[] of one cell or list into blocks[b ...], 8 to a
 * block; returns the next free block. */
static uint32_t fill_blocks(const accel_scene *s, const uint32_t *ids, uint32_t n,
                            accel_block8 *blocks, uint32_t b)
{
    for (uint32_t k = 0; k < n; k += 8, b++) {
        const float *tris[8];
        int lanes = n - k < 8 ? (int)(n - k) : 8;
        for (int l = 0; l < lanes; l++) tris[l] = s->tris + 9 * (size_t)ids[k + (uint32_t)l];
        accel_block_fill(blocks[b].v[0][0], blocks[b].id, 8, tris, ids + k, lanes);
    }
    return b;
}

int grid_cell_blocks_build(const grid_cells *cells, const accel_scene *s, double max_bytes,
                           grid_cell_blocks *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    if (s->sphere_count)
        return accel_fail(err, ACCEL_ERR_SPEC, "grid cells as blocks hold triangles only");
    uint64_t count = 0;
    for (uint64_t c = 0; c < cells->cell_count; c++)
        count += (cells->offsets[c + 1] - cells->offsets[c] + 7u) / 8u;
    double bytes = (double)count * sizeof(accel_block8) + (double)(cells->cell_count + 1) * 4.0;
    if (count >= UINT32_MAX || bytes > max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "grid: %llu cell blocks (%.0f MiB) exceed the limit of %.0f MiB "
                          "(max_mb, or cells=ids)",
                          (unsigned long long)count, bytes / 1048576.0, max_bytes / 1048576.0);
    out->offsets = malloc((size_t)(cells->cell_count + 1) * sizeof *out->offsets);
    out->blocks = accel_alloc_large(count ? count : 1, sizeof *out->blocks, 64);
    if (!out->offsets || !out->blocks) {
        grid_cell_blocks_free(out);
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for %llu cell blocks",
                          (unsigned long long)count);
    }
    uint32_t b = 0;
    for (uint64_t c = 0; c < cells->cell_count; c++) {
        out->offsets[c] = b;
        b = fill_blocks(s, cells->refs + cells->offsets[c],
                        cells->offsets[c + 1] - cells->offsets[c], out->blocks, b);
    }
    out->offsets[cells->cell_count] = b;
    out->block_count = b;
    out->cell_count = cells->cell_count;
    return ACCEL_OK;
}

void grid_cell_blocks_free(grid_cell_blocks *b)
{
    free(b->offsets);
    free(b->blocks);
    memset(b, 0, sizeof *b);
}

size_t grid_cell_blocks_bytes(const grid_cell_blocks *b)
{
    if (!b->offsets) return 0;
    return (size_t)b->block_count * sizeof(accel_block8) +
           (size_t)(b->cell_count + 1) * sizeof(uint32_t);
}

int grid_list_blocks_build(const uint32_t *lists, uint64_t list_len, const accel_scene *s,
                           double max_bytes, grid_list_blocks *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    if (s->sphere_count)
        return accel_fail(err, ACCEL_ERR_SPEC, "grid lists as blocks hold triangles only");
    uint64_t count = 0;
    for (uint64_t w = 1; w < list_len; w += lists[w] + 1) count += (lists[w] + 7u) / 8u;
    double bytes = (double)count * sizeof(accel_block8) + (double)list_len * 4.0;
    if (count >= UINT32_MAX || bytes > max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "%llu list blocks (%.0f MiB) exceed the limit of %.0f MiB (max_mb, "
                          "or cells=ids)",
                          (unsigned long long)count, bytes / 1048576.0, max_bytes / 1048576.0);
    out->first = calloc(list_len ? list_len : 1, sizeof *out->first);
    out->blocks = accel_alloc_large(count ? count : 1, sizeof *out->blocks, 64);
    if (!out->first || !out->blocks) {
        grid_list_blocks_free(out);
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for %llu list blocks",
                          (unsigned long long)count);
    }
    uint32_t b = 0;
    for (uint64_t w = 1; w < list_len; w += lists[w] + 1) {
        out->first[w] = b;
        b = fill_blocks(s, lists + w + 1, lists[w], out->blocks, b);
    }
    out->block_count = b;
    out->list_len = list_len;
    return ACCEL_OK;
}

void grid_list_blocks_free(grid_list_blocks *b)
{
    free(b->first);
    free(b->blocks);
    memset(b, 0, sizeof *b);
}

size_t grid_list_blocks_bytes(const grid_list_blocks *b)
{
    if (!b->first) return 0;
    return (size_t)b->block_count * sizeof(accel_block8) + (size_t)b->list_len * sizeof(uint32_t);
}
