/*
 * accel.h - the shared ray/primitive interface of gridbvh.
 *
 * Every accelerator kind (brute, grid, nested_grid, bvh, a student's own) is
 * a table of functions (accel_kind) listed once in registry.c. Tools, tests
 * and experiments only ever go through this table, so that all kinds are
 * built from the same scene and traced with the same rays.
 *
 * Rules for a kind (see ../shared/STYLE.md):
 *  - build returns a status and fills a caller-owned accel_error; it never
 *    exits or prints;
 *  - the built structure is immutable; intersect/occluded are reentrant and
 *    may be called from many threads at once on disjoint ray ranges;
 *  - intersect/occluded are called per batch of rays. counters == NULL is
 *    the timing path: kernels are written once as always-inline functions
 *    taking a counters pointer, and the batch entry calls them with a
 *    literal NULL so the compiler emits a copy without any counting code.
 */
#ifndef ACCEL_ACCEL_H
#define ACCEL_ACCEL_H

#include <assert.h>
#include <stddef.h>
#include <stdint.h>

#include "core/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- rays and hits: exactly the FORMATS.md records ---------------------- */

typedef struct {
    float ox, oy, oz, t_near;
    float dx, dy, dz, t_far;
} accel_ray;

typedef struct {
    float t;       /* +inf on a miss */
    uint32_t prim; /* ACCEL_MISS on a miss */
    float u, v;    /* barycentric weights of the 2nd and 3rd vertex */
} accel_hit;

static_assert(sizeof(accel_ray) == 32, "accel_ray must be the 32-byte FORMATS.md record");
static_assert(sizeof(accel_hit) == 16, "accel_hit must be the 16-byte FORMATS.md record");

#define ACCEL_MISS 0xFFFFFFFFu

static inline accel_hit accel_hit_miss(void)
{
    accel_hit h = {INFINITY, ACCEL_MISS, 0.0f, 0.0f};
    return h;
}

/* ---- errors ------------------------------------------------------------- */

typedef enum {
    ACCEL_OK = 0,
    ACCEL_ERR_IO,      /* cannot open / read / write a file */
    ACCEL_ERR_PARSE,   /* malformed input: the message names file and line */
    ACCEL_ERR_RANGE,   /* a value or size out of the accepted range */
    ACCEL_ERR_NOMEM,   /* an allocation failed */
    ACCEL_ERR_SPEC,    /* bad spec string or command-line option */
    ACCEL_ERR_INTERNAL /* a broken invariant (e.g. a traversal step bound hit) */
} accel_status;

typedef struct {
    int code;
    char msg[512];
} accel_error;

/* Sets err (if not NULL) and returns code, so that `return accel_fail(...)` reads well. */
int accel_fail(accel_error *err, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* ---- scenes ------------------------------------------------------------- */

typedef struct {
    vec3 eye, look_at, up;
    float fov_deg; /* full vertical field of view, degrees */
} accel_camera;

/*
 * A scene is a list of primitives: ids 0..tri_count-1 are triangles (in file
 * order, FORMATS.md numbering), ids tri_count..prim_count-1 are spheres.
 * A triangle-only scene has sphere_count == 0, and kernels specialize on it.
 *
 * Degenerate triangles (zero area in double precision) keep their ids but are
 * left out of `live`: builders build over live[0..live_count-1] only, so a
 * degenerate triangle can never be hit.
 */
typedef struct accel_scene {
    char name[128];          /* spec string or file name it came from */
    uint32_t tri_count;
    uint32_t sphere_count;
    uint32_t prim_count;     /* tri_count + sphere_count */
    float *tris;             /* 9 floats per triangle: v0, v1, v2 */
    float *spheres;          /* 4 floats per sphere: centre, radius */
    uint32_t live_count;
    uint32_t *live;          /* ids of the non-degenerate primitives */
    uint32_t degenerate_count;
    box3 bounds;             /* of all live primitives */
    accel_camera camera;     /* default view */
    vec3 light;              /* point light for shadow rays */
    /* Optional, NULL for a plain scene: the meshes and instances this scene
     * was flattened from (a .scene file, the built-in field and animated
     * scenes). Owned by the scene (scene_free releases it). Every kind may
     * ignore it: the arrays above always hold the flattened scene. */
    struct accel_instances *instances;
} accel_scene;

/* ---- instanced scenes ----------------------------------------------------
 * A scene composed of meshes, each placed any number of times (FORMATS.md,
 * `.scene`). The flattened scene (the accel_scene holding the description)
 * has, for instance k in order, the primitives of its mesh transformed to
 * world space, ids base(k) + local id. Its triangles are exactly
 * accel_xform_vertex of the mesh's vertices: a two-level kind that computes
 * a world triangle with accel_xform_vertex gets the flattened triangle bit
 * for bit, and so decides every ray as the oracle on the flattened scene.
 * Meshes hold triangles only (no spheres). */
typedef struct {
    uint32_t mesh;      /* index into accel_instances.meshes */
    uint32_t base;      /* id of its first primitive in the flattened scene */
    double xform[12];   /* object -> world, rows of a 3x4 matrix: world = M * (x, y, z, 1) */
    double inverse[12]; /* world -> object */
    box3 bounds;        /* world bounds of all its flattened triangles (empty if none) */
} accel_instance;

typedef struct accel_instances {
    uint32_t mesh_count;
    struct accel_scene *meshes; /* object space; local ids 0..prim_count-1 */
    uint32_t instance_count;
    accel_instance *instances;
} accel_instances;

/* The flattener's one expression: each world coordinate is the matrix row
 * applied in double with fused multiply-adds (bit-identical on every
 * compiler and flag set: no contraction choice is left to the compiler),
 * rounded once to float. */
static inline __attribute__((always_inline)) void accel_xform_vertex(const double *m,
                                                                   const float *p, float *out)
{
    for (int r = 0; r < 3; r++) {
        const double *row = m + 4 * r;
        out[r] = (float)fma(row[0], (double)p[0],
                            fma(row[1], (double)p[1], fma(row[2], (double)p[2], row[3])));
    }
}

/* Primitive bounds and centroid (for builders). */
box3 accel_prim_bounds(const accel_scene *s, uint32_t prim);
vec3 accel_prim_centroid(const accel_scene *s, uint32_t prim);

/* ---- the primitive store: what every kind builds over --------------------
 *
 * Ownership rule, the same for every kind: a kind's build copies what it
 * traverses. When build returns, the built structure owns all it reads; the
 * caller's scene may be changed or freed at once, and the structure lives
 * until kind->destroy. Nothing a kind returns points into the scene.
 * The one exception is instanced: its `update` entry follows a
 * caller-owned animated scene frame by frame, so it reads that scene, which
 * must outlive it (its README says so; the ownership test skips it with
 * this reason). bvh's update copies again from the new scene instead.
 *
 * Every kind starts from the same copy, an accel_prim_store: the scene's
 * live primitives (degenerate triangles left out), triangles first and then
 * spheres, each group in Morton order of the centroids (the common
 * parameter reorder=1, the default for every kind but bvh) or in scene
 * order (reorder=0). Its `prims` is itself a scene in which every primitive is
 * live (live[i] == i), so a kind builds and traverses over local ids and
 * maps a hit back with scene_id[] once per ray. A kind may keep the store
 * (grid, nested_grid, brute) or copy it once more into its own layout and
 * free it; bvh, which copies the primitives into 9-float slots in leaf
 * order, builds over the scene in place unless reorder=1 is given. Each
 * backend README says what it keeps. */
typedef struct {
    accel_scene prims;  /* local ids: 0..tri_count-1 triangles, then spheres; all live */
    uint32_t *scene_id; /* local id -> the scene's primitive id */
} accel_prim_store;

/* Writes ray i's answer h, found over the store's local ids: to hits[i]
 * with its primitive mapped back to the scene's id, or, when occ is not
 * NULL (an any-hit query), whether it hit to occ[i]. */
static inline void accel_prim_store_answer(const accel_prim_store *st, accel_hit h, accel_hit *hits,
                                           uint8_t *occ, size_t i)
{
    if (occ) {
        occ[i] = h.prim != ACCEL_MISS;
        return;
    }
    if (h.prim != ACCEL_MISS) h.prim = st->scene_id[h.prim];
    hits[i] = h;
}

int accel_prim_store_build(const accel_scene *scene, int reorder, accel_prim_store *out,
                           accel_error *err);
void accel_prim_store_free(accel_prim_store *st);
/* Bytes held by the store (primitives, live list, id map). */
size_t accel_prim_store_bytes(const accel_prim_store *st);

/* ---- counters ----------------------------------------------------------- */

/* Traversal statistics summed over the rays of a batch. Which fields a kind
 * fills is its own choice (a BVH leaves mailbox_skips at zero); steps means
 * cells stepped for grids and nodes visited for trees (accel_kind.step_name). */
typedef struct {
    uint64_t rays;
    uint64_t steps;         /* grid cells stepped / BVH nodes visited */
    uint64_t empty_steps;   /* cells stepped that held no primitive */
    uint64_t box_tests;     /* ray/box slab tests */
    uint64_t prim_tests;    /* ray/primitive intersection tests */
    uint64_t mailbox_skips; /* primitive tests avoided by mailboxing */
    uint64_t level_steps[4];/* nested grids: steps per level (0 = top) */
    uint64_t packet_box_tests; /* packets: box tests done for whole packets */
    uint64_t packet_steps;     /* packets: nodes / cells fetched once for a whole packet */
    /* Broken invariants seen by a counted run (a traversal over its step
     * bound, see core/variant.h): how many rays, and where the first was. */
    uint64_t broken;
    const char *broken_file;
    int broken_line;
    uint64_t broken_bound;
    /* Optional per-ray costs for heatmaps (index = ray index in the batch),
     * filled with the ray's steps and primitive tests when not NULL. */
    uint32_t *ray_steps;
    uint32_t *ray_prims;
} accel_counters;

/* Compiling with -DACCEL_COUNTERS=0 removes every counter statement: the
 * reference build against which `make bench` shows that the counter-free
 * kernel copies (counters == NULL) of a normal build run at the same speed.
 * accel_run_kernel (core/variant.h) applies it: the one place counters are
 * switched off. */
#ifndef ACCEL_COUNTERS
#define ACCEL_COUNTERS 1
#endif
#define ACCEL_COUNTERS_ON(c) (ACCEL_COUNTERS ? (c) : (accel_counters *)NULL)

/* One ray's costs into a counted run's counters: the totals, and the
 * per-ray arrays at the ray's index i in the batch when they are asked for.
 * Kernels call it once per ray under `if (c)`. */
static inline void accel_count_ray(accel_counters *c, size_t i, uint32_t steps, uint32_t empty,
                                   uint32_t boxes, uint32_t prims, uint32_t skips)
{
    c->rays++;
    c->steps += steps;
    c->empty_steps += empty;
    c->box_tests += boxes;
    c->prim_tests += prims;
    c->mailbox_skips += skips;
    if (c->ray_steps) c->ray_steps[i] = steps;
    if (c->ray_prims) c->ray_prims[i] = prims;
}

/* Adds b's totals into a (not the per-ray arrays). */
void accel_counters_add(accel_counters *a, const accel_counters *b);
/* Records a broken invariant in c (the first one's place is kept); returns 1. */
int accel_counters_note_broken(accel_counters *c, const char *file, int line, uint64_t bound);
/* ACCEL_ERR_INTERNAL with a message naming the kernel's file and line when
 * a counted run saw a broken invariant, else 0. */
int accel_counters_status(const accel_counters *c, accel_error *err);

/* ---- parameters and spec strings ----------------------------------------- */

typedef enum {
    ACCEL_PARAM_INT,
    ACCEL_PARAM_FLOAT,
    ACCEL_PARAM_ENUM, /* one of choices, "a|b|c" */
    ACCEL_PARAM_BOOL, /* 0/1/on/off/true/false; a bare key means 1 */
    ACCEL_PARAM_STR   /* free text checked by the kind (e.g. res=128x64x32) */
} accel_param_type;

typedef struct {
    const char *key;
    accel_param_type type;
    const char *def;     /* default, as it would be written in a spec */
    double min, max;     /* accepted range for INT and FLOAT */
    const char *choices; /* ENUM: "a|b|c" */
    const char *help;    /* meaning, with its unit */
    /* Where the parser stores the value in the kind's spec struct
     * (offsetof): an int for INT, BOOL (0/1) and ENUM, a double for FLOAT,
     * char[ACCEL_PARAM_TEXT] for STR. An ENUM stores the chosen choice's
     * integer when it is written as one ("2|4|8" stores 2, 4 or 8), else its
     * position ("binned|sah" stores 0 or 1; "auto|4|8": 0, 4 or 8). */
    size_t offset;
} accel_param_def;

#define ACCEL_MAX_PARAMS 32
#define ACCEL_PARAM_TEXT 64   /* a STR field: char key[ACCEL_PARAM_TEXT] */
#define ACCEL_SPEC_BYTES 512  /* largest spec struct a kind may declare */

struct accel_kind;

/* A parsed spec. The kind's own parameters are in its spec struct (every
 * one filled, defaults included), read with ACCEL_SPEC; whether the user
 * wrote a key, with ACCEL_GIVEN. */
typedef struct {
    const struct accel_kind *kind;
    char spec[256];                     /* canonical "kind:key=value,..." of the given keys */
    int naive;                          /* common parameter tri=naive (Moller-Trumbore) */
    int reorder;                        /* common parameter reorder: Morton-ordered store */
    int reorder_given;                  /* reorder was written (bvh's default differs) */
    union {
        double d;
        int64_t i;
        void *p;
        unsigned char bytes[ACCEL_SPEC_BYTES];
    } values;                           /* the kind's spec struct (kind->spec_size bytes) */
    unsigned char given[ACCEL_SPEC_BYTES]; /* given[offset]: the key of that field was written */
} accel_params;

/* The kind's spec struct of a parsed spec: ACCEL_SPEC(p, bvh_spec)->bins. */
#define ACCEL_SPEC(p, type) ((const type *)(const void *)(p)->values.bytes)
/* 1 if the user wrote the parameter stored in `field`: ACCEL_GIVEN(p, bvh_spec, bins). */
#define ACCEL_GIVEN(p, type, field) ((p)->given[offsetof(type, field)] != 0)

/* Parameters every kind accepts, handled by the parser itself. */
extern const accel_param_def accel_common_params[];
extern const size_t accel_common_param_count;

/* Parses "key=value,key=value,flag" against a parameter table: fills num[]
 * (ENUM: as stored in a spec struct), str[] (the text) and given[]
 * (defaults first; a default that does not parse is ACCEL_ERR_INTERNAL).
 * `what` names the thing in messages ("bvh", "scene sphereflake"). Shared
 * by accelerator and scene specs. */
int accel_parse_kv(const char *what, const char *text, const accel_param_def *defs, size_t n,
                   double *num, char (*str)[64], unsigned char *given, accel_error *err);
/* The choice of `choices` ("a|b|c") that an ENUM stores as `value`, copied
 * into buf ("" when none does); returns buf. For messages that name it. */
const char *accel_param_choice(const char *choices, int value, char *buf, size_t size);
/* Appends "  key  (type, default D, range) help" lines for a table to buf. */
void accel_params_help(const accel_param_def *defs, size_t n, char *buf, size_t size);

/* Parses "kind" or "kind:key=value,key=value,flag". Unknown kinds, keys,
 * bad numbers and out-of-range values fail with a message that lists what
 * is accepted. */
int accel_params_parse(const char *spec, accel_params *out, accel_error *err);
/* The same for a kind given directly (registered or not, e.g. the lab's
 * starter kind): kv is the part after "name:". A kind whose table does not
 * fit its spec struct is ACCEL_ERR_INTERNAL. */
int accel_params_parse_kind(const struct accel_kind *kind, const char *kv, accel_params *out,
                            accel_error *err);

/* ---- the accelerator kind table ----------------------------------------- */

typedef struct {
    double ms;         /* wall-clock build time */
    size_t bytes;      /* memory held by the built structure */
    uint64_t nodes;    /* BVH nodes / grid cells (all levels) */
    uint64_t leaves;   /* BVH leaves / non-empty cells */
    uint64_t refs;     /* primitive references stored (grids: >= prims) */
    double sah_cost;   /* BVH: SAH cost normalized by the root area; NAN if n/a */
    int depth;         /* tree depth / grid nesting depth */
    int res[3];        /* grids: top-level resolution */
    const char *isa;   /* kernels of several ISAs (wide BVH): the one built for; else NULL */
    int test_lanes;    /* how single rays test primitives: 0 one at a time (accel_prim_hit),
                        * 4 or 8 in blocks of that many lanes (core/block_test.h) */
} accel_build_stats;

/* What a per-frame update (accel_kind.update) did, and how long it took. */
typedef struct {
    double bottom_ms;        /* refit or rebuild of the meshes that changed */
    double top_ms;           /* per-instance data and the top level */
    uint32_t meshes_refit, meshes_rebuilt;
} accel_update_stats;

/* ---- the conservative walk (optional accel_kind.walk) ----------------------
 *
 * What a kind must offer to serve as the bottom level of a two-level
 * structure that decides every primitive itself (instanced: it tests the
 * world-space copy of each candidate; instanced/README.md says why a
 * closest-hit answer cannot serve). The contract:
 *
 *  - walk(accel, ray, pad, visit, ctx, steps) calls visit(ctx, id, t_max)
 *    for EVERY primitive of the scene the structure was built on (id: its
 *    scene id, as in hits) that has a point within `pad` (max norm: per
 *    axis) of a point o + t d of the ray with t in [t_near, t_max]. t_max
 *    starts at ray->t_far; each call returns the new t_max (the visitor
 *    decides what a hit is; return t_max unchanged to keep it, a smaller
 *    value to let the walk cull, -INFINITY to end the walk).
 *  - It is conservative: visiting more primitives is allowed (a box or a
 *    cell grown by the pad holds more than the primitive), and so is
 *    visiting one primitive more than once; missing one is not. Up to its
 *    float rounding: a walk may lose a few float ulps of its coordinates
 *    (at most 2^-20 relative to the largest |coordinate| of the structure
 *    plus the pad) and a relative 2^-20 of t; a caller that needs
 *    exactness grows pad and [t_near, t_max] by that (instanced does).
 *    With pad = 0 it reaches at least every primitive the kind's own trace
 *    of that ray would test (the same robust box and cell tests): a caller
 *    deciding on the structure's own floats needs no margin (instanced's
 *    identity instances, a plain scene).
 *  - Order: roughly nearest first where the structure allows (a tree's
 *    nearer child first, a grid's cells along the ray), so that shrinking
 *    t_max culls; a walk that cannot order (brute) visits in its own order.
 *  - The direction need not be normalized and may have zero components
 *    (not all three); t keeps the caller's parameterization.
 *  - *steps gets the nodes or cells visited added (the depth view).
 *  - Returns 0; or, called with visit == NULL, answers whether this BUILT
 *    structure can walk (0) or not (ACCEL_ERR_SPEC, e.g. a mode that keeps
 *    no walkable structure): callers probe once at build.
 *  - Reentrant like intersect; reads only the built structure.
 * A kind without it (walk == NULL) cannot be such a bottom level, and
 * instanced refuses it at build, naming the kind. */
typedef float (*accel_walk_visit)(void *ctx, uint32_t prim, float t_max);

/* The simplest walk, for any kind that keeps the primitive store: every
 * primitive whose bounding box grown by pad the ray reaches within
 * [t_near, t_max], in store order (brute; nested_grid and irregular_grid
 * fall back to it, see their READMEs). */
int accel_prim_store_walk(const accel_prim_store *st, const accel_ray *ray, float pad,
                          accel_walk_visit visit, void *ctx, uint32_t *steps);

typedef struct accel_kind {
    const char *name;
    const char *summary;       /* one line for --help */
    const char *step_name;     /* "cells" or "nodes": what counters.steps counts */
    const accel_param_def *params;
    size_t param_count;
    size_t spec_size;          /* sizeof the struct params' offsets point into */
    /* Parameter strings (after "name:") the conformance and stability suites
     * run, NULL-terminated; the first should be "" (defaults). */
    const char *const *variants;

    int (*build)(const accel_scene *scene, const accel_params *params, int threads,
                 void **out, accel_build_stats *stats, accel_error *err);
    void (*intersect)(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                      accel_counters *counters);
    /* occluded[i] = 1 if any primitive is hit within [t_near, t_far]. */
    void (*occluded)(const void *accel, const accel_ray *rays, uint8_t *occluded, size_t count,
                     accel_counters *counters);
    size_t (*memory)(const void *accel);
    void (*destroy)(void *accel);
    /* Optional (NULL: rebuild instead): moves a built structure to the next
     * frame of an animation. `scene` holds the same meshes and instances
     * (same counts) as the scene the structure was built on, with new
     * transforms and vertex positions; the old scene must still be alive
     * during the call, not after. refit = 1 updates the boxes of a changed
     * mesh's structure bottom-up, keeping its topology; refit = 0 rebuilds
     * it. Not reentrant with traversal: no ray may be in flight. */
    int (*update)(void *accel, const accel_scene *scene, int refit, accel_update_stats *stats,
                  accel_error *err);
    /* Optional (NULL: none): the conservative walk above, which lets the
     * kind serve as instanced's bottom level (instanced:bottom=<spec>). */
    int (*walk)(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit,
                void *ctx, uint32_t *steps);
} accel_kind;

/* registry.c: every kind, one line each. */
extern const accel_kind *const accel_kinds[];
extern const size_t accel_kind_count;
const accel_kind *accel_find_kind(const char *name);

/* Convenience: parse spec, build with the given thread count, time it.
 * On success *kind_out and *accel_out are set; destroy with kind->destroy. */
int accel_build_spec(const char *spec, const accel_scene *scene, int threads,
                     const accel_kind **kind_out, void **accel_out, accel_build_stats *stats,
                     accel_error *err);
/* The same for a kind given directly; kv is the part after "name:". */
int accel_build_kind(const accel_kind *kind, const char *kv, const accel_scene *scene,
                     int threads, void **accel_out, accel_build_stats *stats, accel_error *err);

/* Traces count rays with `threads` threads, in chunks of
 * accel_trace_chunk(count, threads) rays: a multiple of 64 so that 8x8
 * packets stay whole, at most ACCEL_CHUNK, about 16 per thread. counters may
 * be NULL; a counted run records broken invariants in them
 * (accel_counters_status). */
#define ACCEL_CHUNK 8192 /* 8 rows of 1024: scanline files tile 8x8 (core/coherence.h) */
size_t accel_trace_chunk(size_t count, int threads);
void accel_trace(const accel_kind *kind, const void *accel, const accel_ray *rays, accel_hit *hits,
                 size_t count, int threads, accel_counters *counters);
void accel_trace_occluded(const accel_kind *kind, const void *accel, const accel_ray *rays,
                          uint8_t *occluded, size_t count, int threads, accel_counters *counters);

/* Runs fn(ctx, begin, end, thread) over [0, count) in chunks of `chunk`
 * items, handed out dynamically to `threads` pthreads (the calling thread
 * is one of them; threads <= 1 runs inline). `thread` is in [0, threads).
 * The helper threads are kept asleep between calls (core/parallel.c), so a
 * process that once asked for N threads keeps N - 1 idle ones. */
void accel_parallel_for(size_t count, size_t chunk, int threads,
                        void (*fn)(void *ctx, size_t begin, size_t end, int thread), void *ctx);
/* Items finished by every accel_parallel_for of the process so far (all
 * callers, never reset): the difference of two readings measures a long
 * trace's progress (measure/progress.h) without touching its kernels. */
uint64_t accel_parallel_done(void);

/* Memory for a large array of n items of `size` bytes (a build's
 * references, node pools, leaf data), aligned to `align` (a power of two,
 * at least sizeof(void *)). A block of 4 MiB or more starts on a 2 MiB
 * boundary and asks the kernel for transparent huge pages (Linux madvise;
 * a hint other systems lack): the kernel time of an 8-wide build on a
 * 1M-triangle soup, mostly faulting in fresh 4 KiB pages, was about a
 * fifth of it (perf), and the build took 0.78x the time with huge pages.
 * The price is a slower worst case when the kernel must compact memory to
 * find free 2 MiB pages (bvh/README.md). NULL when n * size overflows or
 * memory runs out; freed with free(). */
void *accel_alloc_large(size_t n, size_t size, size_t align);

/* ---- the oracle ---------------------------------------------------------- */

/*
 * The reference every test compares against. Its answer is DEFINED by the
 * brute-force loop, accel_reference_trace_brute: every live primitive, in
 * live order, against every ray, in double precision with the watertight
 * triangle test and the careful sphere test of core/prim.h; the closest
 * accepted t wins, and on equal t the primitive latest in live order.
 *
 * accel_reference_trace returns exactly (bitwise t, prim, u, v) the same
 * hits, fast: it builds a conservative culling tree over the scene for the
 * call (core/oracle.c argues why no accepted hit is ever culled) and runs
 * the same double tests on the candidates. To trace several ray sets over
 * one scene, build once with accel_oracle_build, trace with
 * accel_oracle_trace, release with accel_oracle_free. The oracle borrows
 * the scene, which must outlive it and not change. `threads` is honoured
 * (the build is single-threaded); counters, when not NULL, get rays, steps
 * (tree nodes visited), box_tests and prim_tests added.
 */
void accel_reference_trace(const accel_scene *scene, const accel_ray *rays, accel_hit *hits,
                           size_t count, int threads);
void accel_reference_trace_brute(const accel_scene *scene, const accel_ray *rays, accel_hit *hits,
                                 size_t count, int threads);

typedef struct accel_oracle accel_oracle;
int accel_oracle_build(const accel_scene *scene, accel_oracle **out, accel_error *err);
void accel_oracle_trace(const accel_oracle *oracle, const accel_ray *rays, accel_hit *hits,
                        size_t count, int threads, accel_counters *counters);
size_t accel_oracle_memory(const accel_oracle *oracle); /* bytes */
void accel_oracle_free(accel_oracle *oracle);

/* ---- small shared utilities ---------------------------------------------- */

double accel_now_ms(void);
/* Number of usable cores. */
int accel_cpu_count(void);
/* The instruction set the kernels that have several (the wide BVH's) run
 * on by default in this process: "avx512" or "avx2" (core/isa.h). */
const char *accel_isa_name(void);

#ifdef __cplusplus
}
#endif

#endif
