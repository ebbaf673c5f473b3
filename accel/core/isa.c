/*
 * isa.c - the instruction set of the kernels that come in several
 * (core/isa.h): the CPU's and the OS's support for AVX-512, read with
 * cpuid and xgetbv, and the choice GRIDBVH_ISA or a parameter makes.
 *
 * The test is the one the Intel SDM gives ("Detection of Intel AVX-512
 * Foundation Instructions", vol. 1, 15.2-15.3): CPUID.1:ECX.OSXSAVE[27] = 1
 * (the OS uses XSAVE and allows xgetbv), XCR0[2:1] = 11b (XMM and YMM
 * state) and XCR0[7:5] = 111b (opmask, upper halves of ZMM0-15, ZMM16-31)
 * enabled by the OS, then the subsets themselves in CPUID.(EAX=7,ECX=0):EBX
 * (F bit 16, DQ 17, CD 28, BW 30, VL 31; the x86-64-v4 level the units are
 * compiled for). A CPU with the instructions under an OS that does not
 * save zmm state must not run them: its registers would be lost at every
 * context switch.
 */
#include <stdlib.h>
#include <string.h>

#include "core/isa.h"

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>

static int detect_avx512(void)
{
    unsigned a, b, c, d;
    if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & (1u << 27))) return 0;
    unsigned lo, hi;
    __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0u)); /* XCR0 */
    (void)hi;
    if ((lo & 0xE6u) != 0xE6u) return 0;
    if (__get_cpuid_max(0, NULL) < 7) return 0;
    __cpuid_count(7, 0, a, b, c, d);
    const unsigned need = 1u << 16 | 1u << 17 | 1u << 28 | 1u << 30 | 1u << 31;
    return (b & need) == need;
}
#else
static int detect_avx512(void) { return 0; }
#endif

int accel_isa_cpu_avx512(void)
{
    /* cpuid is not free (a serializing instruction, microseconds under a
     * hypervisor): read once; the race of two first calls writes the same
     * value. */
    static volatile int cached = -1;
    if (cached < 0) cached = detect_avx512();
    return cached;
}

int accel_isa_built_avx512(void)
{
#ifdef GRIDBVH_AVX512
    return 1;
#else
    return 0;
#endif
}

const char *accel_isa_label(int isa)
{
    return isa == ACCEL_ISA_AVX512 ? "avx512" : isa == ACCEL_ISA_AVX2 ? "avx2" : "auto";
}

int accel_isa_resolve(int requested, int *isa_out, accel_error *err)
{
    const char *how = "isa=avx512";
    if (requested == ACCEL_ISA_AUTO) {
        const char *env = getenv("GRIDBVH_ISA");
        if (env && *env && strcmp(env, "auto") != 0) {
            if (!strcmp(env, "avx2"))
                requested = ACCEL_ISA_AVX2;
            else if (!strcmp(env, "avx512"))
                requested = ACCEL_ISA_AVX512, how = "GRIDBVH_ISA=avx512";
            else
                return accel_fail(err, ACCEL_ERR_SPEC, "GRIDBVH_ISA=%s: expected avx2, avx512 or auto", env);
        }
    }
    int have = accel_isa_built_avx512() && accel_isa_cpu_avx512();
    if (requested == ACCEL_ISA_AVX512 && !have)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: %s", how,
                          !accel_isa_built_avx512()
                              ? "this build has no AVX-512 kernels (built with ARCH512 empty or a compiler "
                                "without -march=x86-64-v4)"
                              : "this CPU lacks AVX-512 F/CD/BW/DQ/VL or the OS does not save its "
                                "registers (XCR0); use avx2 or auto");
    *isa_out = requested == ACCEL_ISA_AUTO ? (have ? ACCEL_ISA_AVX512 : ACCEL_ISA_AVX2) : requested;
    return 0;
}

const char *accel_isa_name(void)
{
    int isa = ACCEL_ISA_AVX2;
    if (accel_isa_resolve(ACCEL_ISA_AUTO, &isa, NULL)) return "invalid GRIDBVH_ISA";
    return accel_isa_label(isa);
}
