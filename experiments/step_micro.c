/*
 * step_micro.c - the micro-benchmarks of exp_step_cost (step_micro.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"
#include "step_micro.h"

/* The shared block test (the wide BVH's leaves, the grids' cell blocks),
 * compiled here for the baseline instruction set. */
#define WIDE_LB 8
#include "core/block_test.h"
#undef WIDE_LB
#define WIDE_LB 4
#include "core/block_test.h"
#undef WIDE_LB


static volatile double micro_sink;
/* Each repetition rereads its inputs: without this barrier the compiler
 * may hoist the loop-invariant work out of the repetitions. */
#define MICRO_FRESH() __asm__ __volatile__("" ::: "memory")

/* ns per operation of `ops` operations done by fn, as the median of 15
 * samples with its interval. */
static exp_est micro_time(double (*fn)(long reps), long reps, double ops_per_rep)
{
    double samples[15];
    fn(reps / 8 + 1); /* warm up */
    for (int i = 0; i < 15; i++) {
        double t0 = accel_now_ms();
        micro_sink += fn(reps);
        samples[i] = (accel_now_ms() - t0) * 1e6 / ((double)reps * ops_per_rep);
    }
    exp_est e;
    exp_est_of(samples, 15, &e);
    return e;
}

/* 8 triangles around the ray's path (half hit, half miss), 8 tests per rep. */
static float micro_tris[8][9];
static accel_ray_prep micro_ray;

static double micro_tri(long reps)
{
    double acc = 0;
    for (long r = 0; r < reps; r++) {
        MICRO_FRESH();
        for (int k = 0; k < 8; k++) {
            float t = 1e30f, u, v;
            acc += accel_tri_watertight(&micro_ray, micro_tris[k], &t, &u, &v);
        }
    }
    return acc;
}

/* The shared block test on one block of 8 (4) triangles, half of its
 * lanes hit: 4 blocks per rep, ns per block. */
static accel_block8 micro_b8[4] __attribute__((aligned(32)));
static accel_block4 micro_b4[4] __attribute__((aligned(32)));

/* One micro-benchmark per block width LB: the LB-lane block test on the
 * four blocks micro_b<LB>. */
#define MICRO_BLOCK(LB)                                                                     \
    static double micro_block##LB(long reps)                                                \
    {                                                                                       \
        wide_leaf_ray_##LB lr;                                                              \
        leaf_setup_##LB(&lr, &micro_ray);                                                   \
        double acc = 0;                                                                     \
        for (long r = 0; r < reps; r++) {                                                   \
            MICRO_FRESH();                                                                  \
            for (int k = 0; k < 4; k++) {                                                   \
                float t = 1e30f, u, v;                                                      \
                uint32_t id = ACCEL_MISS;                                                   \
                acc += leaf_block_##LB(&micro_b##LB[k], &lr, &micro_ray, &t, &u, &v, &id,   \
                                       1u << 30, 0, 0, 0);                                  \
            }                                                                               \
        }                                                                                   \
        return acc;                                                                         \
    }
MICRO_BLOCK(8)
MICRO_BLOCK(4)

/* The same tests from memory: arrays of a scene's size, visited in a
 * shuffled order. The primitive met at the i-th visit has the shape of
 * micro_tris[i % 8] (micro_b<LB>[i % 4]), so the hits and misses come in
 * the hot micro's predictable order and only the memory differs. */
static float *mem_tris;          /* 9 floats per triangle */
static uint32_t *mem_ids;        /* visit i reads triangle mem_ids[i] */
static accel_block8 *mem_b8;     /* mem_tris as blocks of 8 */
static accel_block4 *mem_b4;     /* and of 4 */
static uint32_t *mem_order8, *mem_order4; /* visit i reads block mem_order<LB>[i] */
static long mem_n, mem_pos;

static double micro_tri_mem(long reps)
{
    double acc = 0;
    long pos = mem_pos;
    for (long r = 0; r < reps; r++) {
        MICRO_FRESH();
        for (int k = 0; k < 8; k++) {
            float t = 1e30f, u, v;
            acc += accel_tri_watertight(&micro_ray, mem_tris + 9 * (size_t)mem_ids[pos], &t, &u, &v);
            if (++pos == mem_n) pos = 0;
        }
    }
    mem_pos = pos;
    return acc;
}

#define MICRO_BLOCK_MEM(LB)                                                                 \
    static double micro_block##LB##_mem(long reps)                                          \
    {                                                                                       \
        wide_leaf_ray_##LB lr;                                                              \
        leaf_setup_##LB(&lr, &micro_ray);                                                   \
        double acc = 0;                                                                     \
        long n = mem_n / LB, pos = mem_pos % n;                                             \
        for (long r = 0; r < reps; r++) {                                                   \
            MICRO_FRESH();                                                                  \
            for (int k = 0; k < 4; k++) {                                                   \
                float t = 1e30f, u, v;                                                      \
                uint32_t id = ACCEL_MISS;                                                   \
                acc += leaf_block_##LB(&mem_b##LB[mem_order##LB[pos]], &lr, &micro_ray, &t, \
                                       &u, &v, &id, 1u << 30, 0, 0, 0);                     \
                if (++pos == n) pos = 0;                                                    \
            }                                                                               \
        }                                                                                   \
        mem_pos = pos;                                                                      \
        return acc;                                                                         \
    }
MICRO_BLOCK_MEM(8)
MICRO_BLOCK_MEM(4)

/* A random permutation of 0..n-1 (a fixed seed: the same order in every
 * run). */
static void mem_shuffle(uint32_t *a, long n)
{
    uint64_t s = 0x9E3779B97F4A7C15u;
    for (long i = 0; i < n; i++) a[i] = (uint32_t)i;
    for (long i = n - 1; i > 0; i--) {
        s ^= s << 13, s ^= s >> 7, s ^= s << 17;
        long j = (long)(s % (uint64_t)(i + 1));
        uint32_t x = a[i];
        a[i] = a[j], a[j] = x;
    }
}

/* The memory micro's arrays (n a multiple of 8); 0, or -1 without memory. */
static int mem_make(long n)
{
    mem_n = n, mem_pos = 0;
    mem_tris = malloc((size_t)n * 9 * sizeof *mem_tris);
    mem_ids = malloc((size_t)n * sizeof *mem_ids);
    mem_b8 = aligned_alloc(64, (size_t)(n / 8) * sizeof *mem_b8);
    mem_b4 = aligned_alloc(64, (size_t)(n / 4) * sizeof *mem_b4);
    mem_order8 = malloc((size_t)(n / 8) * sizeof *mem_order8);
    mem_order4 = malloc((size_t)(n / 4) * sizeof *mem_order4);
    if (!mem_tris || !mem_ids || !mem_b8 || !mem_b4 || !mem_order8 || !mem_order4) return -1;
    mem_shuffle(mem_ids, n);
    for (long i = 0; i < n; i++) memcpy(mem_tris + 9 * (size_t)mem_ids[i], micro_tris[i % 8], 9 * sizeof(float));
    mem_shuffle(mem_order8, n / 8);
    for (long i = 0; i < n / 8; i++) mem_b8[mem_order8[i]] = micro_b8[i % 4];
    mem_shuffle(mem_order4, n / 4);
    for (long i = 0; i < n / 4; i++) mem_b4[mem_order4[i]] = micro_b4[i % 4];
    return 0;
}

static void mem_free(void)
{
    free(mem_tris), free(mem_ids), free(mem_b8), free(mem_b4), free(mem_order8), free(mem_order4);
    mem_tris = NULL, mem_ids = NULL, mem_b8 = NULL, mem_b4 = NULL, mem_order8 = mem_order4 = NULL;
}

/* A binary node's visit: the slab test of its two child boxes (Kay and
 * Kajiya 1986, with the precomputed inverse direction); 8 nodes per rep. */
static float micro_boxes[16][6];

static double micro_node(long reps)
{
    const accel_ray_prep *p = &micro_ray;
    double acc = 0;
    for (long r = 0; r < reps; r++) {
        MICRO_FRESH();
        for (int k = 0; k < 16; k++) {
            const float *b = micro_boxes[k];
            float tx0 = (b[0] - p->org.x) * p->inv_dir.x, tx1 = (b[3] - p->org.x) * p->inv_dir.x;
            float ty0 = (b[1] - p->org.y) * p->inv_dir.y, ty1 = (b[4] - p->org.y) * p->inv_dir.y;
            float tz0 = (b[2] - p->org.z) * p->inv_dir.z, tz1 = (b[5] - p->org.z) * p->inv_dir.z;
            float tn = maxf(maxf(minf(tx0, tx1), minf(ty0, ty1)), maxf(minf(tz0, tz1), p->t_near));
            float tf = minf(minf(maxf(tx0, tx1), maxf(ty0, ty1)), minf(maxf(tz0, tz1), p->t_far));
            acc += tn <= tf;
        }
    }
    return acc;
}

/* 3D-DDA through a 16^3 grid of cell counts (16 KB, in L1): one step =
 * the axis of the nearest boundary, its t advanced, the index moved, the
 * cell read. A ray that leaves restarts at its entry cell. */
#define DDA_N 16
static uint32_t micro_cells[DDA_N * DDA_N * DDA_N];

static double micro_step(long reps)
{
    const float d[3] = {0.57f, 0.61f, 0.55f}; /* the diagonal-ish ray crosses ~3N cells */
    double acc = 0;
    long done = 0;
    while (done < reps) {
        MICRO_FRESH();
        int c[3] = {0, 0, 0}, step = 0;
        float tmax[3], dt[3];
        for (int a = 0; a < 3; a++) dt[a] = 1.0f / d[a], tmax[a] = 0.5f * dt[a] * (1 + 0.1f * (float)a);
        for (;;) {
            int a = tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2);
            if (++c[a] >= DDA_N) break;
            tmax[a] += dt[a];
            acc += micro_cells[(c[2] * DDA_N + c[1]) * DDA_N + c[0]];
            step++;
        }
        done += step;
    }
    return acc;
}

void step_micro_run(exp_ctx *x, step_micro *m)
{
    accel_ray ray = {0};
    ray.oz = -5, ray.dz = 1, ray.dx = 0.01f, ray.dy = 0.02f, ray.t_near = 0, ray.t_far = 1e30f;
    accel_prep_ray(&ray, &micro_ray);
    for (int k = 0; k < 8; k++) { /* even k: around the ray's path; odd: beside it */
        float off = k % 2 ? 3.0f : 0.0f, z = (float)k;
        float v[9] = {-1 + off, -1, z, 1 + off, -1, z, 0 + off, 1, z};
        memcpy(micro_tris[k], v, sizeof v);
    }
    for (int k = 0; k < 4; k++) { /* the 8 triangles above in every block, shifted in z */
        const float *tris[8];
        float shifted[8][9];
        uint32_t ids[8];
        for (int j = 0; j < 8; j++) {
            memcpy(shifted[j], micro_tris[j], sizeof shifted[j]);
            for (int q = 2; q < 9; q += 3) shifted[j][q] += (float)k;
            tris[j] = shifted[j], ids[j] = (uint32_t)(8 * k + j);
        }
        accel_block_fill(&micro_b8[k].v[0][0][0], micro_b8[k].id, 8, tris, ids, 8);
        accel_block_fill(&micro_b4[k].v[0][0][0], micro_b4[k].id, 4, tris, ids, 4);
    }
    for (int k = 0; k < 16; k++) {
        float off = k % 4 == 3 ? 5.0f : 0.0f, z = (float)k;
        float b[6] = {-1 + off, -1, z, 1 + off, 1, z + 0.5f};
        memcpy(micro_boxes[k], b, sizeof b);
    }
    for (int i = 0; i < DDA_N * DDA_N * DDA_N; i++) micro_cells[i] = (uint32_t)(i * 2654435761u) >> 29;
    long reps = x->quick ? 20000 : 200000;
    m->tri = micro_time(micro_tri, reps, 8);
    m->block8 = micro_time(micro_block8, reps, 4);
    m->block4 = micro_time(micro_block4, reps, 4);
    m->node = micro_time(micro_node, reps, 8); /* 16 boxes: 8 binary nodes */
    m->step = micro_time(micro_step, reps * 8, 1);
    long n = x->quick ? STEP_MICRO_MEM_TRIS_QUICK : STEP_MICRO_MEM_TRIS;
    m->mem_tris = 0;
    if (mem_make(n) == 0) {
        /* one pass over the arrays per sample, or more */
        long mreps = (reps > n / 8 ? reps : n / 8) / 4;
        m->mem_tris = (int)n;
        m->tri_mem = micro_time(micro_tri_mem, mreps, 8);
        m->block8_mem = micro_time(micro_block8_mem, mreps, 4);
        m->block4_mem = micro_time(micro_block4_mem, mreps, 4);
    } else {
        m->tri_mem = m->tri, m->block8_mem = m->block8, m->block4_mem = m->block4;
    }
    mem_free();
}
