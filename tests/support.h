/*
 * support.h - what the test files share, written once:
 *
 *  - one random number generator, reseeded before every test (main.c), so
 *    that a test draws the same numbers whichever tests ran before it;
 *  - scene helpers that record a failed check instead of returning quietly;
 *  - one set of ray constructors for the rays that break traversals: rays
 *    aimed exactly at vertices and edge midpoints, axis-parallel rays with
 *    +0/-0 components along lattice lines or from a box's faces, rays
 *    between lattice points, rays from inside a box, rays shortened to stop
 *    just before their hit, random rays around a box;
 *  - one comparison against the oracle (the double-precision reference, or
 *    the float kernels without any structure), by the FORMATS.md rule:
 *    holes, false hits, disagreements, occluded mismatches, with the first
 *    bad ray printed in full.
 */
#ifndef TESTS_SUPPORT_H
#define TESTS_SUPPORT_H

#include <stdint.h>

#include "accel.h"
#include "rays/stiff.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "test.h"

/* ---- random numbers ------------------------------------------------------------ */

/* The seed main.c gives the generator before every test. */
#define TEST_SEED 0x9E3779B97F4A7C15ull

/* xorshift64 (13, 7, 17): Marsaglia, "Xorshift RNGs", Journal of
 * Statistical Software 8(14), 2003. One state, for the running test. */
void test_seed(uint64_t seed);
uint64_t test_rand_u64(void);
/* Uniform in [0, 1), from the state's top 24 bits. */
float test_rand(void);
/* The same generator and mapping on a caller's own state (a test file
 * that keeps its own sequence across its tests). */
uint64_t test_xorshift(uint64_t *state);
float test_rand_of(uint64_t *state);
float test_rand_in(float lo, float hi);
/* A uniform point of box b. */
vec3 test_rand_point(box3 b);
/* lo + step * k for a uniform integer k in [0, count). */
float test_rand_lattice(float lo, float step, int count);

/* ---- scenes ------------------------------------------------------------------------ */

/* Adds a triangle; a failure is a failed check. Returns 1 on success. */
int test_add_tri(scene_builder *b, vec3 p, vec3 q, vec3 r);
/* scene_finish, then frees the builder; a failure is a failed check.
 * Returns 1 on success. */
int test_finish(scene_builder *b, const char *name, accel_scene *s);
/* scene_create(spec); a failure is a failed check. Returns 1 on success. */
int test_make_scene(const char *spec, accel_scene *s);
/* Builds `spec` on s with one thread and destroys what it built: the
 * build's return code, its message in *err (cleared first). For specs a
 * test expects refused. */
int test_build_rc(const char *spec, const accel_scene *s, accel_error *err);

/* Paths of the files of ../shared/scenes whose extension is one of `exts`
 * (space-separated, e.g. ".off .obj"), sorted, at most max. Returns the
 * count, or -1 after a note when the folder is absent or unreadable (the
 * caller then skips). */
int test_shared_files(const char *exts, char (*paths)[512], int max);

/* The backend folders as sources.mk defines them: every top-level folder
 * holding .c files, less its NOT_BACKENDS list; sorted, at most max.
 * Returns the count, or -1 (a failed check) when sources.mk has no
 * NOT_BACKENDS line (the tests run from the repository root). */
int test_backend_folders(char (*names)[256], int max);
/* The subfolders of a backend folder ("bvh/wide"), whose .c files sources.mk
 * builds into the library too; sorted, at most max. */
int test_backend_subfolders(const char *backend, char (*names)[256], int max);

/* A whole file, NUL-terminated (its size in *size when size is not NULL);
 * NULL when it cannot be read. */
char *test_read_file(const char *path, size_t *size);

/* Writes text to path, replacing the file: 1, or 0 after a failed check. */
int test_write_file(const char *path, const char *text);

/* A new empty folder /tmp/gridbvh_<stem>_XXXXXX, its path in dir (size
 * bytes): 1, or 0 after a failed check. test_remove_dir removes it and all
 * it holds (a note when it cannot). */
int test_temp_dir(const char *stem, char *dir, size_t size);
void test_remove_dir(const char *dir);

/* Runs a shell command with its stdout and stderr captured in files of
 * `dir` (made if absent); returns its exit status (-1 if it did not exit).
 * *out and *err (either may be NULL) are malloc'd copies, or NULL. */
int test_run(const char *dir, const char *cmd, char **out, char **err);

/* ---- rays ------------------------------------------------------------------------ */

accel_ray test_ray(vec3 o, vec3 d, float t_near, float t_far);

/* A growable ray list; the constructors below append to it. An allocation
 * failure is a failed check, after which nothing more is appended. */
typedef struct {
    accel_ray *rays;
    size_t count, cap;
    int failed;
} test_rays;

void test_rays_push(test_rays *r, accel_ray ray);
void test_rays_free(test_rays *r);

/* Does the ray's line lie in the plane of a live triangle of s? Such a ray
 * has no well-defined hit with it (the watertight determinant is zero up
 * to rounding, so any t may come out). Exact for lattice input. */
int test_ray_in_a_plane(const accel_scene *s, const accel_ray *r);

/* From eye, aimed exactly at a vertex (or at the midpoint of an edge) of
 * the live triangles picked by rays_rand(seed, i, .) for i < draws; draws
 * that pick a sphere add no ray. */
void test_rays_at_vertices(test_rays *r, const accel_scene *s, vec3 eye, size_t draws,
                           uint64_t seed);
void test_rays_at_edges(test_rays *r, const accel_scene *s, vec3 eye, size_t draws, uint64_t seed);

/* Axis-parallel rays starting exactly on the faces of b, pointing in, from
 * a per_side x per_side lattice of points on each face (its edges
 * included); the other two direction components are +0 or -0. */
void test_rays_axis_from_faces(test_rays *r, box3 b, int per_side);

/* Where test_rays_axis_lattice starts its rays on the ray's own axis. */
enum {
    TEST_START_BEFORE = 1, /* one unit before b, pointing in */
    TEST_START_AFTER = 2,  /* one unit past b, pointing back */
    TEST_START_FACE = 4,   /* on b's lower face, pointing in */
    TEST_START_MIDDLE = 8, /* in b's middle, alternately forward and back (length 2) */
    TEST_START_ALL = 15
};

/*
 * Axis-parallel rays along the lines of the lattice of spacing `step`
 * over b: on each axis, through the points (lo + i*step, lo + j*step) of
 * the other two for every i and every j_stride-th j; the other direction
 * components +0 or -0 in a pattern over (i, j). `starts`: TEST_START_*.
 * With skip_planes_of, rays lying in the plane of one of its triangles are
 * left out (test_ray_in_a_plane).
 */
void test_rays_axis_lattice(test_rays *r, box3 b, float step, int j_stride, unsigned starts,
                            const accel_scene *skip_planes_of);

/*
 * count rays between lattice points of spacing `step`: origins from b
 * grown by `margin`, targets in b (drawn with test_rand). Every 5th ray
 * starts at t_near = 0.5, every 7th stops at t_far = 1 (on a lattice
 * point). With skip_planes_of, rays in a triangle's plane are redrawn.
 */
void test_rays_lattice_points(test_rays *r, box3 b, float step, float margin, size_t count,
                              const accel_scene *skip_planes_of);

/* count rays from uniform points of b in uniform directions (rays_rand(seed,
 * i, .)): every 3rd with t_near up to 5% of b's diagonal, every 2nd with
 * t_far half the diagonal. */
void test_rays_inside(test_rays *r, box3 b, size_t count, uint64_t seed);

/* Random rays around b (test_rand): origins in b grown by half its size on
 * every side, aimed at points of b; some with a +0 or -0 component, some
 * with t_far = 0.7 or t_near = 0.3. An empty b stands for [-1,1]^3. */
void test_rays_random(test_rays *r, box3 b, size_t count);

/* For every ray with a hit in ref, a copy stopping just before it:
 * t_far = t * (1 - 1e-3). Not occluded, unless something else lies in
 * front (which the oracle decides). */
void test_rays_shortened(test_rays *r, const accel_ray *rays, const accel_hit *ref, size_t n);
/* The rays that hit, ending exactly at their hit (t_far = its t): a hit at
 * the range's end is decided as the reference decides it. */
void test_rays_ending_at_hit(test_rays *r, const accel_ray *rays, const accel_hit *ref, size_t n);
/* The rays that hit, moved 1.5 times their hit distance forward, their
 * range reaching back to where they started (t_near < 0, as a .rays file
 * may give): the first hit now lies behind the origin. */
void test_rays_behind(test_rays *r, const accel_ray *rays, const accel_hit *ref, size_t n);

/* ---- the oracle and the comparison ----------------------------------------------------- */

typedef enum {
    TEST_ORACLE_REFERENCE,  /* accel_reference_trace: exact, in double */
    TEST_ORACLE_FLOAT_BRUTE /* the brute kind: the same float kernels without a structure */
} test_oracle;

/* Stiff case ci (rays/stiff.h) into *c: 1, or 0 after failing the test
 * with the reason (a case that cannot be made). */
int test_stiff_case(int ci, stiff_case *c);

/* The oracle's closest hits for rays (malloc'd, free with free()); NULL
 * after a failed check. The float brute force is the oracle where the
 * float kernels and the reference may both be right within rounding yet
 * differ (rays along lattice edges): any difference is then a cell or node
 * the traversal skipped. */
accel_hit *test_oracle_hits(const accel_scene *s, const accel_ray *rays, size_t n, test_oracle o);

/* A comparison with the oracle by the FORMATS.md rule. */
typedef struct {
    size_t rays, holes, false_hits, disagreements;
    size_t ties;      /* agreements that are true ties (another triangle at the same t), verified */
    size_t occ_bad;   /* occluded differs from the oracle's hit or miss */
    size_t first_bad; /* first ray with a wrong hit, else with a wrong occluded, else SIZE_MAX */
} test_diff;

static inline size_t test_diff_bad(const test_diff *d)
{
    return d->holes + d->false_hits + d->disagreements + d->occ_bad;
}

/* Traces rays through a built accelerator on `threads` threads, closest
 * hits into hits and any-hit answers into occ (either may be NULL: then
 * kept internally), and compares both with the oracle's ref by FORMATS.md's
 * rule, ties verified on scene. */
test_diff test_trace_diff(const accel_scene *scene, const accel_kind *kind, const void *accel, const accel_ray *rays,
                          size_t n, const accel_hit *ref, int threads, accel_hit *hits,
                          uint8_t *occ);

/* Records a failed check: "label: N holes, N false hits, N disagreements,
 * N occluded mismatches of N rays; first ray i o=(..) d=(..) t=[..]: ref
 * prim P t T, got prim P t T, occluded O". */
void test_fail_diff(const char *file, int line, const char *label, const test_diff *d,
                    const accel_ray *rays, const accel_hit *ref, const accel_hit *hits,
                    const uint8_t *occ);

/* Builds spec on s with `threads` threads (st may be NULL); NULL after a
 * failed check naming the spec, the scene and the error. */
void *test_build(const char *spec, const accel_scene *s, int threads, accel_build_stats *st);
/* The same, its kind in *kind too (for the caller's kind->destroy). */
void *test_build_kind(const char *spec, const accel_scene *s, int threads,
                      const accel_kind **kind, accel_build_stats *st);

/*
 * The check of one built accelerator (built from spec on s) against the
 * oracle's ref, NULL standing for the reference traced here: closest hit
 * and occluded on 1 thread with zero bad rays; a counted trace identical to
 * the uncounted one, counting n rays, with empty_steps <= steps, the
 * per-level steps (when a kind fills them) adding up to steps, and no
 * broken invariant. Failures are labelled "spec on <scene>". Returns the
 * number of bad rays; *cnt (when not NULL) gets the counted run's counters.
 */
size_t test_check_accel(const accel_scene *s, const accel_kind *kind, const void *accel,
                        const char *spec, const accel_ray *rays, size_t n, const accel_hit *ref,
                        accel_counters *cnt);

/* Builds spec on s with 1 thread and runs test_check_accel against ref
 * (NULL: the reference). A failed build is a
 * failed check and counts as n bad rays (at least 1). *stats and *cnt get
 * the build's statistics and the counters (either may be NULL). */
size_t test_check_spec(const accel_scene *s, const char *spec, const accel_ray *rays, size_t n,
                       const accel_hit *ref, accel_build_stats *stats, accel_counters *cnt);

/* test_check_spec for every variant `kind` lists but the naive triangle
 * test (not watertight: the conformance suite's business) and for
 * "kind:<extra>" of every extra spec (NULL-terminated, may be NULL), all
 * against one oracle. */
void test_check_variants(const accel_scene *s, const accel_kind *kind, const char *const *extra,
                         const accel_ray *rays, size_t n, test_oracle o);

/* The quick report (experiments/report.sh --quick into build/quick-report/),
 * made once per test process: the report tests share it. 0 (after a failed
 * check naming the log) when it cannot be made. */
int test_quick_report(void);

#endif
