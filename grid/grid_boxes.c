/*
 * grid_boxes.c - compact cell storage over boxes (grid_core.h): every cell
 * lists the boxes that reach it, by grid_cell_range (the box against the
 * cells' boxes grown by frame.pad), in increasing box index. For the
 * structures built over boxes rather than over a scene's primitives:
 * instanced's grid levels (instances' world bounds, a mesh's padded
 * triangle boxes). Single-threaded: such grids hold a few thousand boxes.
 */
#include <stdlib.h>
#include <string.h>

#include "grid_core.h"

int grid_cells_build_boxes(const grid_frame *f, const box3 *boxes, uint32_t n, grid_cells *out,
                           accel_error *err)
{
    memset(out, 0, sizeof *out);
    const uint64_t cells = (uint64_t)f->res[0] * (uint64_t)f->res[1] * (uint64_t)f->res[2];
    if (cells >= UINT32_MAX)
        return accel_fail(err, ACCEL_ERR_RANGE, "grid: %llu cells exceed the 32-bit cell index",
                          (unsigned long long)cells);
    uint32_t *offsets = calloc((size_t)cells + 1, sizeof *offsets);
    if (!offsets) return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for cell offsets");
    /* Count pass (totals in 64 bits: a cell's count cannot pass the box count). */
    uint64_t refs = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t i = 0; i < n; i++) {
            int lo[3], hi[3];
            if (box3_is_empty(boxes[i]) || !grid_cell_range(f, boxes[i], lo, hi)) continue;
            for (int z = lo[2]; z <= hi[2]; z++)
                for (int y = lo[1]; y <= hi[1]; y++) {
                    uint32_t c = (uint32_t)lo[0] + f->stride[1] * (uint32_t)y + f->stride[2] * (uint32_t)z;
                    for (int x = lo[0]; x <= hi[0]; x++, c++) {
                        if (pass == 0)
                            offsets[c]++;
                        else
                            out->refs[offsets[c]++] = i;
                    }
                }
            if (pass == 0) refs += (uint64_t)(hi[0] - lo[0] + 1) * (uint64_t)(hi[1] - lo[1] + 1) *
                                   (uint64_t)(hi[2] - lo[2] + 1);
        }
        if (pass == 1) break;
        uint64_t total;
        int rc = refs > UINT32_MAX ? accel_fail(err, ACCEL_ERR_RANGE,
                                                "grid: %llu box references exceed the 32-bit "
                                                "offset limit", (unsigned long long)refs)
                                   : grid_prefix_sum(offsets, cells, 1, &total, err);
        out->refs = rc ? NULL : malloc((total ? total : 1) * sizeof *out->refs);
        if (!out->refs) {
            free(offsets);
            return rc ? rc : accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for references");
        }
    }
    /* The fill moved every offset to its cell's end: shift back. */
    for (uint64_t c = cells; c > 0; c--) offsets[c] = offsets[c - 1];
    offsets[0] = 0;
    out->offsets = offsets;
    out->cell_count = cells;
    out->ref_count = refs;
    return ACCEL_OK;
}
