/*
 * check_common.c - what the step checks share (check.c and check_step3.c):
 * the report a check writes, and rays aimed at the cases a careless
 * traversal gets wrong.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check_common.h"

void lab_say(lab_result *r, const char *fmt, ...)
{
    size_t len = strlen(r->report);
    if (len + 1 >= sizeof r->report) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->report + len, sizeof r->report - len, fmt, ap);
    va_end(ap);
}

static void failv(lab_result *r, lab_outcome how, const char *tag, const char *fmt, va_list ap)
{
    size_t len = strlen(r->report), tl = strlen(tag);
    if (len + tl + 1 < sizeof r->report) {
        memcpy(r->report + len, tag, tl + 1);
        vsnprintf(r->report + len + tl, sizeof r->report - len - tl, fmt, ap);
        lab_say(r, "\n");
    }
    if (r->passed) r->outcome = how; /* the first failure is the one to fix */
    r->passed = 0;
}

void lab_fail(lab_result *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    failv(r, LAB_WRONG, "  FAIL ", fmt, ap);
    va_end(ap);
}

void lab_slow(lab_result *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    failv(r, LAB_SLOW, "  SLOW correct but slow: ", fmt, ap);
    va_end(ap);
}

static void crashed(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void crashed(lab_result *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    failv(r, LAB_CRASHED, "  CRASH ", fmt, ap);
    va_end(ap);
}

/* Builds the subject with extra parameters appended to its own. */
int lab_build_subject(const lab_subject *s, const char *extra, const accel_scene *scene, void **a,
                      accel_build_stats *st, accel_error *err)
{
    char kv[256];
    snprintf(kv, sizeof kv, "%s%s%s", s->kv, *s->kv && *extra ? "," : "", extra);
    return accel_build_kind(s->kind, kv, scene, 1, a, st, err);
}

void lab_where(lab_result *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->where, sizeof r->where, fmt, ap);
    va_end(ap);
}

/* What a crash report adds: make lab runs the checks under the sanitizers
 * where the compiler has them (bin-lab/lab-safe, Makefile), which stop the
 * child with status 1 and a report naming the line; a signal means a run
 * without them (bin-lab/lab, the tests), so the report points there. */
const char *const lab_sanitizer_note =
    "AddressSanitizer or UBSan stopped your code: the report above (its first \"#0 ... "
    "lab/student.c:LINE\" line) names the line (a read or write past an array: a traversal "
    "stack smaller than the tree is deep, an index past node_count or order[]; or undefined "
    "behaviour)";
static const char *const lab_safe_hint =
    " (`make lab STEP=n` runs the check under AddressSanitizer and UBSan where the compiler has "
    "them, bin-lab/lab-safe: their report names the line)";

/* The child runs the check on a copy of the result in shared memory, so
 * that what it found before dying, and where it was, reach the parent. */
void lab_run_isolated(lab_scene_check fn, const lab_subject *s, const char *scene, lab_result *r,
                      accel_error *err)
{
    lab_result *shared = mmap(NULL, sizeof *shared, PROT_READ | PROT_WRITE,
                              MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    pid_t pid = -1;
    if (shared != MAP_FAILED) {
        *shared = *r;
        lab_where(shared, "scene %s", scene);
        fflush(NULL);
        pid = fork();
    }
    if (pid < 0) { /* no child: run here (a crash then ends the check) */
        if (shared != MAP_FAILED) munmap(shared, sizeof *shared);
        fn(s, scene, r, err);
        return;
    }
    if (pid == 0) {
        struct rlimit no_core = {0, 0};
        setrlimit(RLIMIT_CORE, &no_core); /* a crash leaves a report, not a core file */
        alarm(LAB_SCENE_TIMEOUT);
        fn(s, scene, shared, err);
        fflush(NULL);
        _exit(0);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) continue;
    *r = *shared;
    munmap(shared, sizeof *shared);
    if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM)
        crashed(r, "no answer within %d s on %s: an endless loop (a node that is its own "
                   "child, a pop that never empties the stack)?",
                LAB_SCENE_TIMEOUT, r->where);
    else if (WIFSIGNALED(status) && strstr(r->where, "build"))
        crashed(r, "crashed (%s) on %s: an endless recursion in build_node() (a leaf rule "
                   "that never stops: `count < leaf` at leaf=1, a split that leaves every "
                   "primitive on one side) or a write past the node pool (2N nodes)%s",
                strsignal(WTERMSIG(status)), r->where, lab_safe_hint);
    else if (WIFSIGNALED(status))
        crashed(r, "crashed (%s) on %s: a node index out of range or a traversal stack "
                   "overflow? (a child index past b->node_count, a pop from an empty stack, a "
                   "push beyond LAB_MAX_DEPTH)%s",
                strsignal(WTERMSIG(status)), r->where, lab_safe_hint);
    else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        crashed(r, "ended with status %d on %s: %s%s", WEXITSTATUS(status), r->where,
                lab_sanitizer_note,
                strstr(r->where, "build") ? ". In a build, the usual cause is an endless "
                                            "recursion in build_node() (a leaf rule that never "
                                            "stops: `count < leaf` at leaf=1), which writes past "
                                            "the node pool (2N nodes) first" : "");
}

/* Rays from the eye through triangle vertices (the cases that leak through
 * a careless edge test), and axis-parallel rays with +-0 components from
 * the faces of the scene box (the cases that break a careless slab test). */
int lab_make_stiff_rays(const accel_scene *sc, rays_set *out, accel_error *err)
{
    size_t verts = sc->tri_count < 150 ? sc->tri_count : 150;
    size_t n = verts * 3 + 6 * 64;
    memset(out, 0, sizeof *out);
    out->rays = malloc(n * sizeof *out->rays);
    if (!out->rays) return accel_fail(err, ACCEL_ERR_NOMEM, "lab: out of memory");
    size_t k = 0;
    vec3 eye = sc->camera.eye;
    for (size_t i = 0; i < verts; i++) {
        size_t tri = i * (sc->tri_count / (verts ? verts : 1));
        for (int v = 0; v < 3; v++) {
            const float *p = sc->tris + 9 * tri + 3 * v;
            accel_ray r = {eye.x, eye.y, eye.z, 0.0f, p[0] - eye.x, p[1] - eye.y, p[2] - eye.z,
                           INFINITY};
            out->rays[k++] = r;
        }
    }
    box3 b = sc->bounds;
    const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    for (int axis = 0; axis < 3; axis++)
        for (int sign = 0; sign < 2; sign++)
            for (int j = 0; j < 64; j++) {
                int u = (axis + 1) % 3, w = (axis + 2) % 3;
                float o[3], d[3] = {-0.0f, -0.0f, -0.0f};
                o[axis] = sign ? hi[axis] : lo[axis];
                o[u] = lo[u] + (hi[u] - lo[u]) * (float)(j % 8) / 7.0f;
                o[w] = lo[w] + (hi[w] - lo[w]) * (float)(j / 8) / 7.0f;
                if (j & 1) d[u] = 0.0f; /* +0 and -0 both */
                d[axis] = sign ? -1.0f : 1.0f;
                accel_ray r = {o[0], o[1], o[2], 0.0f, d[0], d[1], d[2], INFINITY};
                out->rays[k++] = r;
            }
    out->count = k;
    return 0;
}
