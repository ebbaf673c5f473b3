/*
 * k8_quant.c - the 8-wide kernels of single rays over quantized nodes (quant=1): tables.h for one
 * width and row, a unit of its own (tables.h says why).
 */
#define WIDE_NW 8
#define WIDE_ROW WIDE_ROW_QUANT
#include "tables.h"

const accel_kernel_table *WIDE_UNIT(bvh_wide_k8_quant)(int any_hit, int block8)
{
    return wide_row[any_hit][block8];
}
