/*
 * isa.h - which SIMD instruction set the kernels that have several run on
 * (the kernel units k<digit>_*.c: the wide BVH's, bvh/wide/, instanced/'s,
 * and the grid family's block kernels, grid/, nested_grid/,
 * irregular_grid/): AVX2 (the build's baseline, ARCH in the Makefile) or
 * AVX-512 (units compiled a second time with ARCH512), chosen once per
 * build of a structure from the CPU (isa.c), from the environment variable
 * GRIDBVH_ISA (avx2|avx512|auto) or from a kind's own parameter (isa=).
 */
#ifndef ACCEL_CORE_ISA_H
#define ACCEL_CORE_ISA_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A request (AUTO: the best the CPU and the build have) or a choice. */
enum { ACCEL_ISA_AUTO = 0, ACCEL_ISA_AVX2 = 1, ACCEL_ISA_AVX512 = 2 };
/* The names of the three, in that order, as a parameter's choices. */
#define ACCEL_ISA_CHOICES "auto|avx2|avx512"

/* A kernel unit's own exported name: the Makefile compiles each unit a
 * second time with WIDE_AVX512_UNIT defined (and ARCH512), whose names end
 * in _avx512 (bvh/wide/node.h's WIDE_UNIT is the same rule). A caller
 * declares both and takes the _avx512 one only where the Makefile defines
 * GRIDBVH_AVX512 for it (the build linked the twins). */
#ifdef WIDE_AVX512_UNIT
#define ACCEL_ISA_UNIT(name) name##_avx512
#else
#define ACCEL_ISA_UNIT(name) name
#endif

/* 1 when the CPU has every AVX-512 subset the AVX-512 units are compiled
 * for (x86-64-v4: F, CD, BW, DQ, VL) and the OS saves the zmm and mask
 * registers (XCR0); 0 elsewhere (and on other architectures). */
int accel_isa_cpu_avx512(void);
/* 1 when this build linked the AVX-512 units (the Makefile's ARCH512). */
int accel_isa_built_avx512(void);
/* The ISA a request resolves to: `requested` (ACCEL_ISA_*) when not AUTO,
 * else GRIDBVH_ISA when set, else AVX-512 where both the CPU and the build
 * have it, AVX2 elsewhere. AVX-512 asked for where it is missing, or an
 * unknown GRIDBVH_ISA, is ACCEL_ERR_SPEC with a message saying why. */
int accel_isa_resolve(int requested, int *isa_out, accel_error *err);
/* "avx2" or "avx512". */
const char *accel_isa_label(int isa);

#ifdef __cplusplus
}
#endif

#endif
