/*
 * render.c - bin/render: the frame loop of an animated scene, the
 * lecture's real-time target (800x600, primary and shadow rays, 20 frames
 * per second).
 *
 *   render --scene animated:instances=24,detail=8 --accel instanced --frames 30
 *   render --accel bvh --update rebuild            (a flattened structure, rebuilt each frame)
 *   render --accel instanced --update refit --out frames/f   (writes frames/f_0000.png ...)
 *
 * Per frame: make the frame's scene (a built-in with a `frame` parameter:
 * the tool appends frame=N; a still, any other scene, is made once and
 * kept), bring the structure to it (--update refit or
 * rebuild: the kind's own update when it has one, bottom levels refit or
 * rebuilt and the top level rebuilt; --update full or a kind without one:
 * a new build), trace the primary rays and the shadow rays of their hits,
 * shade. Printed per frame: the milliseconds of each step, and the frames
 * per second of update + tracing (the renderer's loop: the scene making is
 * the animation system's, reported apart). --verify compares every frame
 * against a structure built from scratch on that frame (FORMATS.md rule).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include "cli/cli.h"
#include "image/image.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "cli/spec_check.h"

typedef struct {
    const char *scene, *accel, *out;
    int frames, first, step, width, height, threads, verify, counters;
    int mode; /* 0 refit, 1 rebuild (bottom levels), 2 full build */
    int last; /* first + (frames - 1) * step, checked by parse */
    int still; /* the scene has no frame parameter (a mesh, a .scene file): every frame the same */
} options;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: render [options]\n"
            "Renders the frames of an animated scene; reports per-frame times and frames/s.\n\n"
            "  --scene SPEC      built-in scene (default animated), mesh or .scene file;\n"
            "                    a scene with a frame parameter is animated (frame=N is\n"
            "                    appended per frame), any other renders as a still: made\n"
            "                    once and kept, the structure updated each frame\n"
            "  --accel SPEC      accelerator (default instanced)\n"
            "  --update MODE     refit | rebuild | full (default refit): refit or rebuild the\n"
            "                    changed meshes and the top level through the kind's update, or\n"
            "                    build everything anew (kinds without an update always do)\n"
            "  --frames N        frames to render (default 10)\n"
            "  --first F         first frame number (default 0); --step S between frames (1)\n"
            "  --size WxH        image size (default 800x600)\n"
            "  --threads T       tracing threads (default: every core)\n"
            "  --out PREFIX      write PREFIX_NNNN.png per frame (PREFIX's folder is made)\n"
            "  --verify          compare each frame with a fresh build (holes, disagreements)\n"
            "  --counters        a counted primary pass per frame (after the timed one): nodes,\n"
            "                    boxes and primitives per ray, the time-free cost of a refit tree\n\n");
    cli_help_exit_codes(f);
}


/* A whole decimal number in [lo, hi], nothing after it ("2abc" and
 * "99999999999" are bad values, not 2 and an overflow). */
static int whole(const char *v, long lo, long hi, int *out)
{
    char *end;
    errno = 0;
    long n = strtol(v, &end, 10);
    if (end == v || *end || errno || n < lo || n > hi) return 0;
    *out = (int)n;
    return 1;
}

/* A built-in scene with a frame parameter is animated; any other scene (a
 * mesh, a .scene file, a generator without frame) is a still. */
static int animated(const char *scene)
{
    size_t n = strcspn(scene, ":");
    for (size_t i = 0; i < scene_generator_count; i++) {
        const scene_generator *g = scene_generators[i];
        if (strlen(g->name) != n || strncmp(g->name, scene, n)) continue;
        for (size_t k = 0; k < g->param_count; k++)
            if (!strcmp(g->params[k].key, "frame")) return 1;
    }
    return 0;
}

/* --out PREFIX: its folder is made (with its parents) and must take files. */
static int make_out_dir(const char *prefix, accel_error *err)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", prefix);
    char *slash = strrchr(dir, '/');
    if (slash && slash != dir) {
        *slash = 0;
        for (char *p = dir + 1; *p; p++)
            if (*p == '/') *p = 0, mkdir(dir, 0777), *p = '/';
        mkdir(dir, 0777);
        struct stat st;
        if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
            return accel_fail(err, ACCEL_ERR_IO, "--out %s: %s is not a folder and cannot be made",
                              prefix, dir);
    }
    char probe[1100];
    snprintf(probe, sizeof probe, "%s_0000.png", prefix);
    return cli_check_output("--out", probe, "png", err);
}

/* 0, or the exit status of a bad command line (bench/cli.h: 2 usage, 3 input). */
static int parse(int argc, char **argv, options *o)
{
    *o = (options){"animated", "instanced", NULL, 10, 0, 1, 800, 600, accel_cpu_count(), 0, 0, 0, 0, 0};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            exit(0);
        }
        if (!strcmp(a, "--verify") || !strcmp(a, "--counters")) {
            *(a[2] == 'v' ? &o->verify : &o->counters) = 1;
            continue;
        }
        static const char *const valued[] = {"--scene", "--accel", "--out", "--frames", "--first",
                                             "--step", "--threads", "--size", "--update"};
        int known = 0;
        for (size_t k = 0; k < sizeof valued / sizeof valued[0]; k++) known |= !strcmp(a, valued[k]);
        if (!known) {
            fprintf(stderr, "render: unknown option %s (see --help)\n", a);
            return CLI_EXIT_USAGE;
        }
        if (!v) {
            fprintf(stderr, "render: %s needs a value (see --help)\n", a);
            return CLI_EXIT_USAGE;
        }
        i++;
        /* A bad value names what the option takes, as trace's messages do. */
        const char *expect = NULL;
        if (!strcmp(a, "--scene")) o->scene = v;
        else if (!strcmp(a, "--accel")) o->accel = v;
        else if (!strcmp(a, "--out")) o->out = v;
        else if (!strcmp(a, "--frames")) {
            if (!whole(v, 1, 100000, &o->frames)) expect = "a whole number in 1..100000";
        } else if (!strcmp(a, "--first")) {
            if (!whole(v, 0, 100000000, &o->first)) expect = "a whole number in 0..100000000";
        } else if (!strcmp(a, "--step")) {
            if (!whole(v, 1, 100000000, &o->step)) expect = "a whole number in 1..100000000";
        } else if (!strcmp(a, "--threads")) {
            if (!whole(v, 1, 256, &o->threads)) expect = "a whole number in 1..256";
        } else if (!strcmp(a, "--size")) {
            char w[32], *x = strchr(v, 'x');
            size_t wl = x ? (size_t)(x - v) : 0;
            int bad = !x || wl == 0 || wl >= sizeof w;
            if (!bad) {
                memcpy(w, v, wl), w[wl] = 0;
                bad = !whole(w, 1, 16384, &o->width) || !whole(x + 1, 1, 16384, &o->height);
            }
            if (bad) expect = "WxH with 1 <= W, H <= 16384";
        } else if (!strcmp(a, "--update")) {
            o->mode = !strcmp(v, "refit") ? 0 : !strcmp(v, "rebuild") ? 1 : !strcmp(v, "full") ? 2 : -1;
            if (o->mode < 0) expect = "refit, rebuild or full";
        } else {
            fprintf(stderr, "render: unknown option %s (see --help)\n", a);
            return CLI_EXIT_USAGE;
        }
        if (expect) {
            fprintf(stderr, "render: %s %s: expected %s\n", a, v, expect);
            return CLI_EXIT_USAGE;
        }
    }
    long long last = o->first + (long long)(o->frames - 1) * o->step;
    if (last > 100000000) {
        fprintf(stderr, "render: the last frame, --first %d + (--frames %d - 1) x --step %d = %lld, "
                "is past 100000000\n", o->first, o->frames, o->step, last);
        return CLI_EXIT_USAGE;
    }
    o->last = (int)last;
    o->still = !animated(o->scene);
    if (!o->still && strstr(o->scene, "frame=")) {
        fprintf(stderr, "render: --scene %s: leave frame= out, the tool sets it\n", o->scene);
        return CLI_EXIT_USAGE;
    }
    accel_error err = {0};
    if (scene_spec_check(o->scene, &err) || spec_check_accel("--accel", o->accel, &err) ||
        (o->out && make_out_dir(o->out, &err))) {
        fprintf(stderr, "render: %s\n", err.msg);
        return cli_exit_of(err.code);
    }
    return 0;
}

static int make_frame(const options *o, int frame, accel_scene *s, accel_error *err)
{
    char spec[600];
    if (o->still)
        snprintf(spec, sizeof spec, "%s", o->scene);
    else
        snprintf(spec, sizeof spec, "%s%sframe=%d", o->scene, strchr(o->scene, ':') ? "," : ":",
                 frame);
    return scene_create(spec, s, err);
}

/* Lambert with a shadow term; background for misses. */
static void shade(const accel_scene *s, const rays_set *prim, const accel_hit *hits,
                  const uint8_t *lit, image_rgb *img)
{
    for (size_t i = 0; i < prim->count; i++) {
        uint32_t px = prim->pixel ? prim->pixel[i] : (uint32_t)i;
        uint8_t *c = img->rgb + 3 * (size_t)px;
        vec3 p, n;
        if (!rays_hit_frame(s, &prim->rays[i], &hits[i], &p, &n)) {
            c[0] = 30, c[1] = 34, c[2] = 48;
            continue;
        }
        float lamb = fmaxf(0.0f, v3_dot(n, v3_norm(v3_sub(s->light, p))));
        float k = 0.18f + 0.82f * lamb * (lit[px] ? 1.0f : 0.0f);
        c[0] = (uint8_t)(230 * k), c[1] = (uint8_t)(225 * k), c[2] = (uint8_t)(215 * k);
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Long on purpose (139 lines): the options and their checks, then the
 * frames in order (build or update, trace, shade, write); each step is a
 * few lines of calls and splitting them would pass the whole state. */
int main(int argc, char **argv)
{
    options o;
    int prc = parse(argc, argv, &o);
    if (prc) return prc;
    accel_error err = {0};
    accel_scene slot[2];
    int cur = 0;
    double t = accel_now_ms();
    if (make_frame(&o, o.first, &slot[0], &err)) {
        fprintf(stderr, "render: %s\n", err.msg);
        return cli_exit_of(err.code);
    }
    double scene_ms = accel_now_ms() - t;
    /* The last frame is made once here, so that a range the scene refuses
     * fails before any work instead of after the frames before it. */
    if (o.frames > 1 && !o.still) {
        if (make_frame(&o, o.last, &slot[1], &err)) {
            fprintf(stderr, "render: frame %d, the last one: %s\n", o.last, err.msg);
            scene_free(&slot[0]);
            return cli_exit_of(err.code);
        }
        scene_free(&slot[1]);
    }
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    if (accel_build_spec(o.accel, &slot[0], o.threads, &kind, &accel, &st, &err)) {
        fprintf(stderr, "render: %s\n", err.msg);
        return cli_exit_of(err.code);
    }
    int mode = kind->update ? o.mode : 2;
    static const char *const mode_name[] = {"refit", "rebuild", "full build"};
    printf("render %s, %s, %dx%d, %d threads, %s per frame; %u triangles, %u instances\n", o.scene,
           o.accel, o.width, o.height, o.threads, mode_name[mode], slot[0].tri_count,
           slot[0].instances ? slot[0].instances->instance_count : 0);
    if (o.still)
        printf("%s has no frame parameter: a still, made once and kept (scene_ms 0 after frame "
               "0); the structure is still brought to it each frame (--update)\n", o.scene);
    printf("frame 0 build %.2f ms, %zu bytes\n", st.ms, st.bytes);
    rays_set prim = {0};
    if (rays_primary(&slot[0].camera, o.width, o.height, &prim, &err)) {
        fprintf(stderr, "render: %s\n", err.msg);
        return cli_exit_of(err.code);
    }
    size_t npx = (size_t)o.width * o.height;
    accel_hit *hits = malloc(prim.count * sizeof *hits), *ref = malloc(prim.count * sizeof *ref);
    uint8_t *lit = malloc(npx), *occ = malloc(prim.count);
    image_rgb img = {0};
    if (!hits || !ref || !lit || !occ || image_alloc(&img, o.width, o.height, &err)) {
        fprintf(stderr, "render: out of memory\n");
        return CLI_EXIT_INTERNAL;
    }
    double *fps = malloc(o.frames * sizeof *fps), *fps_all = malloc(o.frames * sizeof *fps_all);
    printf("%6s %9s %9s %9s %9s %9s %9s %7s %7s\n", "frame", "scene_ms", "bottom_ms", "top_ms",
           "prim_ms", "shadow_ms", "total_ms", "fps", "fps+sc");
    int rc = 0, differ = 0; /* rc: an ACCEL_ERR_* that stops the loop */
    for (int f = 0; f < o.frames && rc == 0 && !differ; f++) {
        int frame = o.first + f * o.step;
        double bottom_ms = 0, top_ms = 0;
        if (f > 0) {
            /* A still is kept: nothing moves, so nothing is made (its frames
             * per second with the scene making are those of the renderer). */
            accel_scene *next = o.still ? &slot[cur] : &slot[1 - cur];
            scene_ms = 0;
            if (!o.still) {
                t = accel_now_ms();
                rc = make_frame(&o, frame, next, &err);
                if (rc) break;
                scene_ms = accel_now_ms() - t;
            }
            if (mode < 2) {
                accel_update_stats us;
                rc = kind->update(accel, next, mode == 0, &us, &err);
                bottom_ms = us.bottom_ms, top_ms = us.top_ms;
            } else {
                kind->destroy(accel);
                rc = accel_build_spec(o.accel, next, o.threads, &kind, &accel, &st, &err);
                top_ms = st.ms;
            }
            if (!o.still) {
                scene_free(&slot[cur]);
                cur = 1 - cur;
            }
            if (rc) break;
        }
        const accel_scene *s = &slot[cur];
        t = accel_now_ms();
        accel_trace(kind, accel, prim.rays, hits, prim.count, o.threads, NULL);
        double prim_ms = accel_now_ms() - t;
        t = accel_now_ms();
        rays_set shadow = {0};
        rc = rays_shadow(s, &prim, hits, &shadow, &err);
        if (rc) break;
        accel_trace_occluded(kind, accel, shadow.rays, occ, shadow.count, o.threads, NULL);
        memset(lit, 0, npx);
        for (size_t i = 0; i < shadow.count; i++) lit[shadow.pixel[i]] = !occ[i];
        double shadow_ms = accel_now_ms() - t;
        rays_free(&shadow);
        double total = bottom_ms + top_ms + prim_ms + shadow_ms;
        fps[f] = 1000.0 / total;
        fps_all[f] = 1000.0 / (total + scene_ms);
        printf("%6d %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %7.2f %7.2f", frame, scene_ms, bottom_ms,
               top_ms, prim_ms, shadow_ms, total, fps[f], fps_all[f]);
        if (o.counters) {
            accel_counters c = {0};
            accel_trace(kind, accel, prim.rays, hits, prim.count, o.threads, &c);
            double n = c.rays ? (double)c.rays : 1.0;
            printf("  per ray: %.2f nodes, %.2f boxes, %.2f prims", c.steps / n, c.box_tests / n,
                   c.prim_tests / n);
        }
        if (o.verify) {
            const accel_kind *k2;
            void *fresh;
            accel_build_stats st2;
            rc = accel_build_spec(o.accel, s, o.threads, &k2, &fresh, &st2, &err);
            if (rc) break;
            accel_trace(k2, fresh, prim.rays, ref, prim.count, o.threads, NULL);
            hits_diff d = hits_compare(s, prim.rays, ref, hits, prim.count);
            printf("  verify: %zu holes, %zu false hits, %zu disagreements", d.holes, d.false_hits,
                   d.disagreements);
            k2->destroy(fresh);
            if (d.holes + d.false_hits + d.disagreements) differ = 1;
        }
        printf("\n");
        if (o.out) {
            char path[1024];
            snprintf(path, sizeof path, "%s_%04d.png", o.out, frame);
            shade(s, &prim, hits, lit, &img);
            if ((rc = image_write(path, &img, &err))) break;
        }
    }
    if (rc) fprintf(stderr, "render: %s\n", err.msg);
    if (rc == 0 && !differ && o.frames > 1) {
        /* Frame 0 carries the first build, not an update: left out. */
        int n = o.frames - 1, mid = 1 + (n - 1) / 2;
        qsort(fps + 1, n, sizeof *fps, cmp_double);
        qsort(fps_all + 1, n, sizeof *fps_all, cmp_double);
        printf("median over %d updated frames: %.2f frames/s (update + trace), %.2f with the "
               "scene making\n", n, fps[mid], fps_all[mid]);
    }
    kind->destroy(accel);
    scene_free(&slot[cur]);
    rays_free(&prim);
    image_free(&img);
    free(hits), free(ref), free(lit), free(occ), free(fps), free(fps_all);
    return rc ? cli_exit_of(rc) : differ ? CLI_EXIT_DIFFER : CLI_EXIT_OK;
}
