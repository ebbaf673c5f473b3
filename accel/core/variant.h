/*
 * variant.h - specialized kernel copies, picked once per batch: the one
 * mechanism every kind uses (brute, grid, nested_grid, every bvh traversal).
 *
 * A kernel is written once as an always-inline function
 *
 *     KERNEL(const void *accel, const accel_ray *rays, void *out, size_t count,
 *            accel_counters *c, unsigned flags)
 *
 * (out is accel_hit * for closest hit, uint8_t * for any hit). The macro
 * ACCEL_KERNEL_TABLE(name, KERNEL) compiles it ACCEL_V_COPIES times: one
 * copy per combination of the flags below with counters == NULL and the
 * flags as literals, so each timed copy holds no counting code and no
 * branch on a flag; and one counted copy that takes the flags at run time.
 * The two combinations of tri=naive with spheres share one timed copy
 * instead (ACCEL_KERNEL_NAIVE_SPHERES_: naive and spheres literal, the
 * kind's switch at run time): no experiment times the naive test on a
 * scene with spheres (the naive rows of exp_error_time and exp_stability
 * trace triangle meshes, and conformance runs counted), so they were two
 * full kernel bodies per table compiled for nothing (issue 53's build).
 * ACCEL_KERNEL_PAIR(name, KERNEL) does that for the usual kernel that serves
 * both queries. accel_run_kernel() picks the copy for a batch. This is the C form of the
 * variant tables of Embree and madmann91/bvh (see ../shared/STYLE.md).
 *
 * Counters are switched off where a batch enters the code that counts, and
 * nowhere else: accel_run_kernel applies ACCEL_COUNTERS_ON to every kernel
 * table, and so do the packet layer's entries (accel_coherent_intersect and
 * _occluded, core/coherence.c), which count too; no kind applies it itself.
 * With -DACCEL_COUNTERS=0 the counted copy is the uncounted kernel too.
 *
 * The step bound (the guard that turns a traversal bug into a reported
 * error instead of an endless loop) follows one policy for every kind: it
 * is checked in counted runs only, where it costs nothing measured, and a
 * broken bound is recorded in the counters (accel_counters.broken), never
 * by abort(). accel_counters_status() turns it into an accel_error. The
 * conformance and stability suites trace every case counted, so a loop is
 * caught there; timed copies carry no bound check.
 */
#ifndef ACCEL_CORE_VARIANT_H
#define ACCEL_CORE_VARIANT_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The flags a kernel copy is specialized on (unsigned, so that C++ mixes
 * them with other unsigned values without warnings). */
#define ACCEL_V_NAIVE 1u   /* tri=naive: Moller-Trumbore instead of watertight */
#define ACCEL_V_SPHERES 2u /* the scene holds spheres (triangle-only scenes skip the branch) */
#define ACCEL_V_OPT 4u     /* the kind's own switch: mailbox (grids), frustum (bvh packets) */
#define ACCEL_V_COPIES 8

typedef void (*accel_kernel_fn)(const void *accel, const accel_ray *rays, void *out, size_t count,
                                accel_counters *c, unsigned flags);

typedef struct {
    accel_kernel_fn counted;              /* counters on, flags at run time */
    accel_kernel_fn fast[ACCEL_V_COPIES]; /* counters compiled out, flags constant */
} accel_kernel_table;

#define ACCEL_KERNEL_COPY_(NAME, KERNEL, F)                                                 \
    static void NAME##_v##F(const void *a, const accel_ray *r, void *o, size_t n,           \
                            accel_counters *c, unsigned f)                                  \
    {                                                                                       \
        (void)c;                                                                            \
        (void)f;                                                                            \
        KERNEL(a, r, o, n, (accel_counters *)NULL, F##u);                                   \
    }

#if ACCEL_COUNTERS
#define ACCEL_KERNEL_COUNTED_(NAME, KERNEL)                                                 \
    static void NAME##_counted(const void *a, const accel_ray *r, void *o, size_t n,        \
                               accel_counters *c, unsigned f)                               \
    {                                                                                       \
        KERNEL(a, r, o, n, c, f);                                                           \
    }
#else
#define ACCEL_KERNEL_COUNTED_(NAME, KERNEL)                                                 \
    static void NAME##_counted(const void *a, const accel_ray *r, void *o, size_t n,        \
                               accel_counters *c, unsigned f)                               \
    {                                                                                       \
        (void)c;                                                                            \
        KERNEL(a, r, o, n, (accel_counters *)NULL, f);                                      \
    }
#endif

/* The timed copy of tri=naive on a scene with spheres: both literal, the
 * kind's own switch (ACCEL_V_OPT) read at run time. */
#define ACCEL_KERNEL_NAIVE_SPHERES_(NAME, KERNEL)                                           \
    static void NAME##_vns(const void *a, const accel_ray *r, void *o, size_t n,            \
                           accel_counters *c, unsigned f)                                   \
    {                                                                                       \
        (void)c;                                                                            \
        KERNEL(a, r, o, n, (accel_counters *)NULL,                                          \
               (f & ACCEL_V_OPT) | ACCEL_V_NAIVE | ACCEL_V_SPHERES);                         \
    }

/* Defines `static const accel_kernel_table NAME` from an always-inline KERNEL. */
#define ACCEL_KERNEL_TABLE(NAME, KERNEL)                                                    \
    ACCEL_KERNEL_COUNTED_(NAME, KERNEL)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 0)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 1)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 2)                                                     \
    ACCEL_KERNEL_NAIVE_SPHERES_(NAME, KERNEL)                                               \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 4)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 5)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 6)                                                     \
    static const accel_kernel_table NAME = {                                                \
        NAME##_counted,                                                                     \
        {NAME##_v0, NAME##_v1, NAME##_v2, NAME##_vns, NAME##_v4, NAME##_v5, NAME##_v6,      \
         NAME##_vns}};

/* The copies a kind can select, nothing more: a kind whose flags never set
 * ACCEL_V_OPT (no switch of its own: brute, instanced, the lab's kinds)
 * compiles only the four copies with it clear; the entries with it set
 * repeat them and are never selected (accel_variant_flags(.., 0)). Half the
 * compile work of such a table. */
#define ACCEL_KERNEL_TABLE_NO_OPT(NAME, KERNEL)                                             \
    ACCEL_KERNEL_COUNTED_(NAME, KERNEL)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 0)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 1)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 2)                                                     \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 3)                                                     \
    static const accel_kernel_table NAME = {                                                \
        NAME##_counted,                                                                     \
        {NAME##_v0, NAME##_v1, NAME##_v2, NAME##_v3, NAME##_v0, NAME##_v1, NAME##_v2,       \
         NAME##_v3}};

/* The copies a kind's runs select, nothing more: ACCEL_KERNEL_TABLE_SEL(NAME,
 * KERNEL, KEEP) compiles the counted copy and, for each of the eight flag
 * combinations whose bit in KEEP is 1 (KEEP: a parenthesised list of eight
 * 0/1 tokens, indexed by the flags: 1 naive, 2 spheres, 4 ACCEL_V_OPT; e.g.
 * (0, 0, 0, 0, 1, 0, 0, 0) for index 4 alone), its timed copy. A combination whose bit is 0 runs the
 * counted copy with counters off (NULL) and its flags read at run time:
 * the same source, so the same hits bit for bit (-std=c11 contracts no
 * float operation), only without the constant flags' specialisation. The
 * kept combinations are the ones the experiments time (issue 53: a
 * GRIDBVH_KLOG run of make test, the quick report and every experiment on
 * its full scenes logged each table's combinations; the tables' KEEP
 * comments name them); a new experiment that times another combination
 * adds its bit. Each dropped copy was one full forced-inline kernel body
 * of compile time. */
#define ACCEL_KERNEL_SLOT_0(NAME, F) NAME##_counted
#define ACCEL_KERNEL_SLOT_1(NAME, F) NAME##_v##F
#define ACCEL_KERNEL_SLOT_(NAME, F, K) ACCEL_KERNEL_SLOT_##K(NAME, F)
#define ACCEL_KERNEL_KEEP_0(NAME, KERNEL, F)
#define ACCEL_KERNEL_KEEP_1(NAME, KERNEL, F) ACCEL_KERNEL_COPY_(NAME, KERNEL, F)
#define ACCEL_KERNEL_KEEP_(NAME, KERNEL, F, K) ACCEL_KERNEL_KEEP_##K(NAME, KERNEL, F)
#define ACCEL_KERNEL_UNPACK_(...) __VA_ARGS__
#define ACCEL_KERNEL_TABLE_SEL(NAME, KERNEL, KEEP) ACCEL_KERNEL_TABLE_SEL_X_(NAME, KERNEL, ACCEL_KERNEL_UNPACK_ KEEP)
#define ACCEL_KERNEL_TABLE_SEL_X_(NAME, KERNEL, ...) ACCEL_KERNEL_TABLE_SEL_(NAME, KERNEL, __VA_ARGS__)
#define ACCEL_KERNEL_TABLE_SEL_(NAME, KERNEL, k0, k1, k2, k3, k4, k5, k6, k7)                \
    ACCEL_KERNEL_COUNTED_(NAME, KERNEL)                                                     \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 0, k0)                                                 \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 1, k1)                                                 \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 2, k2)                                                 \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 3, k3)                                                 \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 4, k4)                                                 \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 5, k5)                                                 \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 6, k6)                                                 \
    ACCEL_KERNEL_KEEP_(NAME, KERNEL, 7, k7)                                                 \
    static const accel_kernel_table NAME = {                                                \
        NAME##_counted,                                                                     \
        {ACCEL_KERNEL_SLOT_(NAME, 0, k0), ACCEL_KERNEL_SLOT_(NAME, 1, k1),                  \
         ACCEL_KERNEL_SLOT_(NAME, 2, k2), ACCEL_KERNEL_SLOT_(NAME, 3, k3),                  \
         ACCEL_KERNEL_SLOT_(NAME, 4, k4), ACCEL_KERNEL_SLOT_(NAME, 5, k5),                  \
         ACCEL_KERNEL_SLOT_(NAME, 6, k6), ACCEL_KERNEL_SLOT_(NAME, 7, k7)}};

/* The flags of a built structure's switches. */
static inline unsigned accel_variant_flags(int naive, int spheres, int opt)
{
    return (naive ? ACCEL_V_NAIVE : 0u) | (spheres ? ACCEL_V_SPHERES : 0u) | (opt ? ACCEL_V_OPT : 0u);
}

/* The usual case: one always-inline kernel serves both queries,
 *
 *     KERNEL(accel, rays, hits, occ, count, c, naive, spheres, opt)
 *
 * (occ == NULL: closest hits into hits; else any hit into occ), and the
 * macro defines its two tables, NAME_hit_table and NAME_occ_table. In each
 * copy one of hits and occ is a literal NULL, so a kernel tests `occ` for
 * the query; one that wants it as a literal argument uses two
 * ACCEL_KERNEL_TABLEs instead (bvh_single.c). */
#define ACCEL_KERNEL_ADAPT_(NAME, KERNEL, Q, HITS, OCC)                                     \
    static inline __attribute__((always_inline)) void NAME##_##Q##_kernel_(                \
        const void *a, const accel_ray *r, void *o, size_t n, accel_counters *c, unsigned f) \
    {                                                                                       \
        (void)o;                                                                            \
        KERNEL(a, r, HITS, OCC, n, c, (f & ACCEL_V_NAIVE) != 0, (f & ACCEL_V_SPHERES) != 0, \
               (f & ACCEL_V_OPT) != 0);                                                     \
    }
#define ACCEL_KERNEL_QUERY_(NAME, KERNEL, Q, HITS, OCC, TABLE)                              \
    ACCEL_KERNEL_ADAPT_(NAME, KERNEL, Q, HITS, OCC)                                         \
    TABLE(NAME##_##Q##_table, NAME##_##Q##_kernel_)

#define ACCEL_KERNEL_PAIR(NAME, KERNEL)                                                     \
    ACCEL_KERNEL_QUERY_(NAME, KERNEL, hit, (accel_hit *)o, (uint8_t *)NULL, ACCEL_KERNEL_TABLE) \
    ACCEL_KERNEL_QUERY_(NAME, KERNEL, occ, (accel_hit *)NULL, (uint8_t *)o, ACCEL_KERNEL_TABLE)
/* The same for a kind whose flags never set ACCEL_V_OPT (above). */
#define ACCEL_KERNEL_PAIR_NO_OPT(NAME, KERNEL)                                              \
    ACCEL_KERNEL_QUERY_(NAME, KERNEL, hit, (accel_hit *)o, (uint8_t *)NULL,                 \
                        ACCEL_KERNEL_TABLE_NO_OPT)                                          \
    ACCEL_KERNEL_QUERY_(NAME, KERNEL, occ, (accel_hit *)NULL, (uint8_t *)o,                 \
                        ACCEL_KERNEL_TABLE_NO_OPT)

/* The same with the copies each query's runs select (ACCEL_KERNEL_TABLE_SEL):
 * KEEP_HIT for the closest-hit table, KEEP_OCC for the any-hit one. */
#define ACCEL_KERNEL_PAIR_SEL(NAME, KERNEL, KEEP_HIT, KEEP_OCC)                              \
    ACCEL_KERNEL_QUERY_SEL_(NAME, KERNEL, hit, (accel_hit *)o, (uint8_t *)NULL, KEEP_HIT)   \
    ACCEL_KERNEL_QUERY_SEL_(NAME, KERNEL, occ, (accel_hit *)NULL, (uint8_t *)o, KEEP_OCC)
#define ACCEL_KERNEL_QUERY_SEL_(NAME, KERNEL, Q, HITS, OCC, KEEP)                           \
    ACCEL_KERNEL_ADAPT_(NAME, KERNEL, Q, HITS, OCC)                                         \
    ACCEL_KERNEL_TABLE_SEL(NAME##_##Q##_table, NAME##_##Q##_kernel_, KEEP)

/* Runs one batch with the copy for these flags: the counted copy when
 * counters are given (and compiled in), else the specialized one. */
static inline void accel_run_kernel(const accel_kernel_table *t, const void *accel,
                                    const accel_ray *rays, void *out, size_t count,
                                    accel_counters *c, unsigned flags)
{
    c = ACCEL_COUNTERS_ON(c);
    if (c)
        t->counted(accel, rays, out, count, c, flags);
    else
        t->fast[flags & (ACCEL_V_COPIES - 1)](accel, rays, out, count, NULL, flags);
}

/* True (and recorded in c) when a counted traversal has taken more than
 * `bound` steps: the kernel then ends that ray. Always false in the timed
 * copies, where c is a literal NULL and the test compiles away. */
#define ACCEL_STEP_BOUND_BROKEN(c, steps, bound)                                            \
    ((c) != NULL && (uint64_t)(steps) > (uint64_t)(bound) &&                                \
     accel_counters_note_broken((c), __FILE__, __LINE__, (uint64_t)(bound)))

/* A kind's two batch entry points, closest hit and any hit, each running
 * its table with the flags FLAGS(accel) of the built structure:
 *
 *     ACCEL_KERNEL_ENTRIES(kind_intersect, kind_occluded, const kind_accel,
 *                          kind_hit_table, kind_occ_table, kind_flags)
 *
 * (ACCEL_T is the accel parameter's pointee type, as the header declares it). */
#define ACCEL_KERNEL_ENTRIES(HIT_FN, OCC_FN, ACCEL_T, HIT_TABLE, OCC_TABLE, FLAGS)          \
    void HIT_FN(ACCEL_T *accel, const accel_ray *rays, accel_hit *hits, size_t count,       \
                accel_counters *c)                                                          \
    {                                                                                       \
        accel_run_kernel(&HIT_TABLE, accel, rays, hits, count, c, FLAGS(accel));           \
    }                                                                                       \
    void OCC_FN(ACCEL_T *accel, const accel_ray *rays, uint8_t *occ, size_t count,          \
                accel_counters *c)                                                          \
    {                                                                                       \
        accel_run_kernel(&OCC_TABLE, accel, rays, occ, count, c, FLAGS(accel));            \
    }

#ifdef __cplusplus
}
#endif

#endif
