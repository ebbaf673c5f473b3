/*
 * trace.c - bin/trace: build any accelerator on any scene, trace any ray
 * set, and report build time, memory, Mrays/s (median/min/max of repeats
 * after a warm-up) and counter averages from a separate counted pass.
 *
 *   trace --scene bunny.off --accel bvh:build=binned --rays primary,diffuse
 *   trace compare A.hits B.hits
 *
 * Run `trace --help` for every option, accelerator, scene parameter and
 * exit status. Every option and spec is checked before any work starts;
 * main is a list of named steps: parse, check, load the scene, set the
 * camera, make the rays, then per accelerator build, trace, check, write.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "measure/bench.h"
#include "cli/cli.h"
#include "measure/csv.h"
#include "image/shade.h"
#include "scene/scene.h"
#include "cli/spec_check.h"
#include "core/coherence.h"
#include "tools/trace/hitfiles.h"
#include "tools/trace/run.h"

static int opt_accel(const cli_option *o, void *field, char **v, accel_error *err)
{
    options *opts = (options *)((char *)field - offsetof(options, accels));
    if (opts->accel_count == MAX_ACCELS)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: at most %d accelerators", o->name, MAX_ACCELS);
    opts->accels[opts->accel_count++] = v[0];
    return 0;
}

static int opt_heatmap(const cli_option *o, void *field, char **v, accel_error *err)
{
    const char **hm = field;
    if (strcmp(v[0], "steps") && strcmp(v[0], "prims"))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected steps or prims", o->name, v[0]);
    hm[0] = v[0], hm[1] = v[1];
    return 0;
}

static int opt_ray_order(const cli_option *o, void *field, char **v, accel_error *err)
{
    rays_order ord;
    if (rays_order_parse(v[0], &ord))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected tiles8, scanline or shuffle", o->name, v[0]);
    *(int *)field = (int)ord + 1;
    return 0;
}

static int opt_packet_order(const cli_option *o, void *field, char **v, accel_error *err)
{
    if (strcmp(v[0], "sort") && strcmp(v[0], "keep"))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: expected sort or keep", o->name, v[0]);
    *(int *)field = strcmp(v[0], "sort") ? ACCEL_ORDER_KEEP : ACCEL_ORDER_SORT;
    return 0;
}

#define OPT(f) offsetof(options, f)
static const cli_option trace_options[] = {
    {"--scene", "SPEC", "built-in scene (name:key=value,...), mesh file (.obj .ply .off) or .scene\n"
     "file (meshes placed as instances, camera and light: FORMATS.md); default sphereflake;\n"
     "its point light (printed) shades --image and starts the shadow rays", cli_string, OPT(scene), 0, 0},
    {"--accel", "SPEC", "accelerator kind:key=value,...; repeat to compare several\n"
     "(default bvh when registered, else brute)", opt_accel, OPT(accels), 0, 0},
    {"--rays", "LIST", "comma list of primary,shadow,diffuse,ao, or a .rays file (default primary)",
     cli_string, OPT(rays), 0, 0},
    {"--occluded", NULL, "trace the rays of a .rays file as any-hit (occlusion) queries, as shadow\n"
     "and ao rays are (default: closest hit)", cli_flag, OPT(occluded), 0, 0},
    {"--size", "WxH", "image / primary ray grid (default 512x512)", cli_size, OPT(size), 1, 16384},
    {"--eye", "X,Y,Z", "camera position (default: the scene's camera)", cli_vec, OPT(eye), 0, 0},
    {"--look", "X,Y,Z", "point the camera looks at", cli_vec, OPT(look), 0, 0},
    {"--up", "X,Y,Z", "camera up vector (not parallel to the view)", cli_vec, OPT(up), 0, 0},
    {"--fov", "DEG", "vertical field of view in degrees, (0, 179)", cli_double, OPT(fov), 1e-3, 179},
    {"--threads", "N", "threads of every phase: builds, traces, ray generation, --check (default 1)",
     cli_int, OPT(threads), 1, 256},
    {"--repeat", "N", "timed passes per ray set (default 5)", cli_int, OPT(repeat), 1, 100},
    {"--warmup", "N", "untimed passes first (default 1)", cli_int, OPT(warmup), 0, 100},
    {"--build-repeat", "N", "builds timed per accelerator (default 3, within --budget)", cli_int,
     OPT(build_repeat), 1, 64},
    {"--budget", "S", "seconds of timed passes per ray set and of builds per accelerator\n"
     "(default 10): slower ones stop repeating, and the row says so", cli_double, OPT(budget),
     0.001, 1e6},
    {"--no-counters", NULL, "skip the counted pass (steps, box and primitive tests)", cli_unflag,
     OPT(counters), 0, 0},
    {"--check", NULL, "compare every result against the double-precision reference", cli_flag,
     OPT(check), 0, 0},
    {"--image", "F.png", "shaded image of the primary hits (.png or .ppm)", cli_string, OPT(image),
     0, 0},
    {"--heatmap", "steps|prims F.png", "cost per pixel of the last --accel with a colour scale\n"
     "(F.<set>.png if several sets; one file: with several --accel it holds the last)",
     opt_heatmap, OPT(heatmap), 0, 0},
    {"--dump-rays", "F", "write the ray set(s) as FORMATS.md .rays (F.<set>.rays if several;\n"
     "a trailing .rays of F is taken off first: eye.rays gives eye.primary.rays)",
     cli_string, OPT(dump_rays), 0, 0},
    {"--dump-hits", "F", "write the hits of the last accelerator, a file per set (F.<set>.hits\n"
     "if several; a trailing .hits of F is taken off first: eye.hits gives\n"
     "eye.primary.hits); shadow, ao and --occluded rays as FORMATS.md any-hit answers",
     cli_string, OPT(dump_hits), 0, 0},
    {"--export-obj", "F", "write the scene as OBJ (spheres tessellated) and continue", cli_string,
     OPT(export_obj), 0, 0},
    {"--csv", NULL, "one RFC 4180 CSV record per measurement on stdout, after a header", cli_flag,
     OPT(csv), 0, 0},
    {"--gen-accel", "SPEC", "accelerator that finds the primary hits secondary rays start from\n"
     "(default bvh, else brute)", cli_string, OPT(gen_accel), 0, 0},
    {"--ray-order", "tiles8|scanline|shuffle", "put every ray set (before --dump-rays) in 8x8 pixel\n"
     "tiles, scanline (pixel) order or a shuffle seeded by --seed (default: as made, tiles)",
     opt_ray_order, OPT(ray_order), 0, 0},
    {"--packet-order", "sort|keep", "sort (default): packet modes form coherent packets first\n"
     "(raster tiles or a key sort, core/coherence.h); keep: 64 consecutive rays a packet", opt_packet_order,
     OPT(packet_order), 0, 0},
    {"--seed", "N", "seed of the secondary rays (default 1)", cli_u64, OPT(seed), 0, 0},
    {"--ao-samples", "N", "ambient occlusion rays per primary hit (default 4)", cli_int,
     OPT(ao_samples), 1, 4096},
    {"--ao-radius", "R", "ambient occlusion ray length (default 0: 10% of the scene diagonal)",
     cli_float, OPT(ao_radius), 0, 1e30},
    CLI_COMMON_ROWS(options),
};
#define OPTION_COUNT (sizeof trace_options / sizeof trace_options[0])

static void usage(FILE *f)
{
    fprintf(f, "usage: trace [options]\n"
               "       trace compare REFERENCE.hits OTHER.hits\n"
               "Builds accelerators on a scene, traces ray sets, reports speed and costs.\n\n");
    cli_help(f, trace_options, OPTION_COUNT);
    fprintf(f, "\nAccelerators:\n");
    for (size_t i = 0; i < accel_kind_count; i++) {
        const accel_kind *k = accel_kinds[i];
        char buf[4096] = "";
        accel_params_help(k->params, k->param_count, buf, sizeof buf);
        fprintf(f, "  %s: %s\n%s", k->name, k->summary, buf);
    }
    char common[1024] = "";
    accel_params_help(accel_common_params, accel_common_param_count, common, sizeof common);
    fprintf(f, "  (every kind):\n%s\nScenes:\n", common);
    for (size_t i = 0; i < scene_generator_count; i++) {
        const scene_generator *g = scene_generators[i];
        char buf[4096] = "";
        accel_params_help(g->params, g->param_count, buf, sizeof buf);
        fprintf(f, "  %s: %s\n%s", g->name, g->summary, buf);
    }
    fprintf(f, "\n");
    cli_help_exit_codes(f);
}


/* The ray sets of --rays: names, or one .rays file that must open. */
static int parse_ray_sets(const char *list, run *r, accel_error *err)
{
    if (!strstr(list, ".rays")) {
        int rc = bench_sets_parse(list, r->bits, &r->set_count, err);
        for (int s = 0; s < r->set_count; s++) r->set_names[s] = bench_set_name(r->bits[s]);
        return rc;
    }
    r->from_file = 1;
    r->bits[0] = 0;
    r->set_names[0] = "file";
    r->set_count = 1;
    FILE *f = fopen(list, "rb");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open", list);
    fclose(f);
    return 0;
}

static int has_primary(const run *r)
{
    for (int s = 0; s < r->set_count; s++)
        if (r->bits[s] == BENCH_PRIMARY) return 1;
    return 0;
}

/* Step 1: options, defaults, and every check that needs no scene. */
static int parse_options(int argc, char **argv, options *o, run *r, accel_error *err)
{
    memset(o, 0, sizeof *o);
    o->scene = "sphereflake";
    o->rays = "primary";
    o->size[0] = o->size[1] = 512;
    o->threads = 1;
    o->repeat = 5;
    o->warmup = 1;
    o->build_repeat = 3;
    o->budget = 10;
    o->counters = 1;
    o->seed = 1;
    o->ao_samples = 4;
    o->progress_after = BENCH_PROGRESS_AFTER_MS / 1e3;
    o->packet_order = accel_coherence_get(); /* the library's default */
    int rc = cli_parse(trace_options, OPTION_COUNT, argc, argv, 1, o, err);
    if (rc || o->help) return rc;
    if (o->accel_count == 0) o->accels[o->accel_count++] = accel_find_kind("bvh") ? "bvh" : "brute";
    for (int a = 0; a < o->accel_count; a++)
        if ((rc = spec_check_accel("--accel", o->accels[a], err))) return rc;
    if (o->gen_accel && (rc = spec_check_accel("--gen-accel", o->gen_accel, err))) return rc;
    if ((rc = scene_spec_check(o->scene, err))) return rc;
    if ((rc = parse_ray_sets(o->rays, r, err))) return rc;
    if (o->image && (r->from_file || !has_primary(r)))
        return accel_fail(err, ACCEL_ERR_SPEC, "--image needs primary rays: add primary to --rays "
                          "(a .rays file has no pixels)");
    if (o->heatmap[0] && r->from_file)
        return accel_fail(err, ACCEL_ERR_SPEC, "--heatmap needs rays made from the camera, not a "
                          ".rays file (it has no pixels)");
    if (o->occluded && !r->from_file)
        return accel_fail(err, ACCEL_ERR_SPEC, "--occluded needs a .rays file in --rays (shadow "
                          "and ao sets are any-hit queries already)");
    if (o->eye.given && o->look.given && v3_len(v3_sub(o->eye.v, o->look.v)) == 0)
        return accel_fail(err, ACCEL_ERR_SPEC, "--eye and --look are the same point");
    if (o->up.given && v3_len(o->up.v) == 0)
        return accel_fail(err, ACCEL_ERR_SPEC, "--up must not be the zero vector");
    if (o->eye.given && o->look.given && o->up.given) {
        accel_camera c = {o->eye.v, o->look.v, o->up.v, o->fov > 0 ? (float)o->fov : 45.0f};
        if ((rc = rays_camera_check(&c, err))) return rc;
    }
    if ((rc = cli_check_output("--image", o->image, "png ppm", err)) ||
        (rc = cli_check_output("--heatmap", o->heatmap[1], r->set_count > 1 ? NULL : "png ppm",
                           err)) ||
        (rc = cli_check_output("--dump-rays", o->dump_rays, NULL, err)) ||
        (rc = cli_check_output("--dump-hits", o->dump_hits, NULL, err)) ||
        (rc = cli_check_output("--export-obj", o->export_obj, NULL, err)))
        return rc;
    return 0;
}

/* Step 2: the scene, which must hold something to hit. */
static int load_scene(const options *o, run *r, accel_error *err)
{
    bench_progress_begin(r->progress, "load scene", 0, 0);
    double t0 = accel_now_ms();
    int rc = scene_create(o->scene, &r->scene, err);
    bench_progress_end(r->progress);
    if (rc) return rc;
    const accel_scene *s = &r->scene;
    if (s->live_count == 0)
        return accel_fail(err, ACCEL_ERR_RANGE, "scene %s has nothing to hit: %u primitives, %u "
                          "of them degenerate", s->name, s->prim_count, s->degenerate_count);
    FILE *info = trace_info(o);
    if (info)
        fprintf(info, "scene %s: %u primitives (%u triangles, %u spheres), %u degenerate, made in "
                "%.1f ms\n  bounds (%.6g, %.6g, %.6g) to (%.6g, %.6g, %.6g)\n",
                s->name, s->prim_count, s->tri_count, s->sphere_count, s->degenerate_count,
                accel_now_ms() - t0, s->bounds.min.x, s->bounds.min.y, s->bounds.min.z,
                s->bounds.max.x, s->bounds.max.y, s->bounds.max.z);
    if (info)
        fprintf(info, "  light (%.6g, %.6g, %.6g): shading and shadow rays\n", s->light.x,
                s->light.y, s->light.z);
    if (o->export_obj) {
        if ((rc = scene_export_obj(s, o->export_obj, 24, err))) return rc;
        if (info) fprintf(info, "exported %s\n", o->export_obj);
    }
    return 0;
}

/* Step 3: the scene's camera with the overrides, which must define a view. */
static int set_camera(const options *o, run *r, accel_error *err)
{
    accel_camera *c = &r->cam;
    *c = r->scene.camera;
    if (r->from_file) return 0; /* a .rays file brings its own rays: no view to make */
    if (o->eye.given) c->eye = o->eye.v;
    if (o->look.given) c->look_at = o->look.v;
    if (o->up.given) c->up = o->up.v;
    if (o->fov > 0) c->fov_deg = (float)o->fov;
    int rc = rays_camera_check(c, err);
    if (rc) {
        /* Options the user gave make a usage error; the scene's own camera an input one. */
        if (o->eye.given || o->look.given || o->up.given || o->fov > 0) {
            err->code = ACCEL_ERR_SPEC;
            return rc;
        }
        /* The scene's own view: name the scene, and the way out. */
        char msg[sizeof err->msg];
        snprintf(msg, sizeof msg, "%s", err->msg);
        return accel_fail(err, err->code, "%s: the scene's camera (its file's, or the default that "
                          "frames its bounds) is not usable: %s; give --eye, --look and --up",
                          o->scene, msg);
    }
    FILE *info = trace_info(o);
    if (info)
        fprintf(info, "  camera eye (%.6g, %.6g, %.6g) look (%.6g, %.6g, %.6g) up (%.6g, %.6g, "
                "%.6g) fov %.6g deg, %dx%d\n", c->eye.x, c->eye.y, c->eye.z, c->look_at.x,
                c->look_at.y, c->look_at.z, c->up.x, c->up.y, c->up.z, c->fov_deg, o->size[0],
                o->size[1]);
    return 0;
}

/* Step 4: the ray sets of the view, or the .rays file; then --dump-rays. */
static int make_rays(const options *o, run *r, accel_error *err)
{
    int rc;
    if (r->from_file) {
        rc = rays_read(o->rays, &r->file_rays, err);
        if (!rc && r->file_rays.count == 0)
            rc = accel_fail(err, ACCEL_ERR_RANGE, "%s holds no rays", o->rays);
        size_t first, n = rc ? 0 : r->file_rays.count;
        const char *why;
        size_t bad = rays_invalid_count(r->file_rays.rays, n, &first, &why);
        /* Traced as misses, as FORMATS.md's rule gives them, but never silently. */
        if (bad)
            fprintf(stderr, "warning: %s: %zu of %zu rays can hit nothing and are traced as misses "
                    "(the first: ray %zu, byte %llu, has %s)\n", o->rays, bad,
                    r->file_rays.count, first, 16ull + 32ull * first, why);
    } else {
        int mask = 0;
        for (int s = 0; s < r->set_count; s++) mask |= r->bits[s];
        bench_set_opts so = {&r->cam, o->size[0], o->size[1], o->ao_samples, o->ao_radius,
                             o->seed, o->threads, o->gen_accel};
        bench_progress_begin(r->progress, "make ray sets", 0, 0);
        rc = bench_sets_make(&r->scene, &so, mask, &r->sets, err);
        bench_progress_end(r->progress);
    }
    for (int s = 0; !rc && o->ray_order && s < r->set_count; s++) {
        rays_set *rs = r->from_file ? &r->file_rays : (rays_set *)bench_sets_get(&r->sets, r->bits[s]);
        rc = rays_reorder(rs, (rays_order)(o->ray_order - 1), o->seed, err);
    }
    accel_coherence_set(o->packet_order);
    for (int s = 0; !rc && o->dump_rays && s < r->set_count; s++) {
        const rays_set *rs = r->from_file ? &r->file_rays : bench_sets_get(&r->sets, r->bits[s]);
        char path[1024];
        trace_set_path(path, sizeof path, o->dump_rays, r->set_count > 1, r->set_names[s], "rays",
                       NULL);
        rc = rays_write(path, rs->rays, rs->count, err);
        FILE *info = trace_info(o);
        if (!rc && info)
            fprintf(info, "wrote %s: %zu %s rays (FORMATS.md .rays)\n", path, rs->count,
                    r->set_names[s]);
    }
    return rc;
}


/* The double-precision reference with --threads, compared as hits or as
 * hit / miss for occlusion queries. */
static int check_set(const options *o, run *r, set_run *t, accel_error *err)
{
    size_t n = t->rays->count;
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref);
    if (!ref) return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for %zu reference hits", n);
    char name[96];
    snprintf(name, sizeof name, "reference for %s", r->set_names[t->set]);
    bench_progress_begin(r->progress, name, (double)n, 1);
    accel_reference_trace(&r->scene, t->rays->rays, ref, n, o->threads);
    bench_progress_end(r->progress);
    hits_diff d = {0};
    if (t->occl) {
        for (size_t i = 0; i < n; i++) {
            int rh = ref[i].prim != ACCEL_MISS;
            d.holes += rh && !t->occ[i];
            d.false_hits += !rh && t->occ[i];
        }
    } else {
        d = hits_compare(&r->scene, t->rays->rays, ref, t->hits, n);
    }
    free(ref);
    t->diff = d;
    t->checked = 1;
    if ((d.holes || d.false_hits || d.disagreements) && r->status < CLI_EXIT_DIFFER)
        r->status = CLI_EXIT_DIFFER;
    return 0;
}

/* A structure that degenerates on this scene (thousands of primitive tests
 * per ray: the regular grid around teapot_stadium's teapot) in one line. */
static void warn_collapse(const run *r, const accel_kind *kind, const accel_params *canon,
                          const set_run *t)
{
    double n = t->rays->count ? (double)t->rays->count : 1.0;
    double prims = t->br.counted ? (double)t->br.counters.prim_tests / n : 0;
    if (prims >= 1000 && strcmp(kind->name, "brute"))
        fprintf(stderr, "trace: warning: %s collapses on %s: %.0f primitive tests per %s ray (of "
                "%u primitives); try another kind or parameter\n", canon->spec, r->scene.name,
                prims, r->set_names[t->set], r->scene.live_count);
}

/* "12 s", "3.5 min", "1.2 h". */
static const char *fmt_duration(char *buf, size_t n, double s)
{
    if (s < 120) snprintf(buf, n, "%.0f s", s);
    else if (s < 7200) snprintf(buf, n, "%.1f min", s / 60);
    else snprintf(buf, n, "%.1f h", s / 3600);
    return buf;
}

/* Before a pass that may take minutes (brute force on a real mesh, a grid
 * that collapses on the scene): a probe of PROBE_BLOCKS blocks of
 * consecutive rays spread over the set (tiles stay coherent) is traced and
 * timed, with blocks of 1, then 8, then 64 rays until the probe lasts
 * PROBE_MS (a slow kind is found in a fraction of a second), and a
 * predicted pass over SLOW_PASS_S is said before the work starts, with the
 * estimate (warn_collapse says why after the pass). */
#define PROBE_BLOCKS 8
#define PROBE_MS 20.0
#define SLOW_PASS_S 60.0
static double probe_ms(const options *o, const accel_kind *kind, const void *accel,
                       const set_run *t, size_t block)
{
    size_t n = PROBE_BLOCKS * block, blocks = t->rays->count / block;
    accel_ray *rays = malloc(n * sizeof *rays);
    accel_hit *hits = malloc(n * sizeof *hits);
    uint8_t *occ = malloc(n);
    accel_error err = {0};
    bench_result br = {0};
    int rc = !rays || !hits || !occ;
    if (!rc) {
        for (size_t b = 0; b < PROBE_BLOCKS; b++)
            memcpy(rays + b * block, t->rays->rays + (b * blocks / PROBE_BLOCKS) * block,
                   block * sizeof *rays);
        rays_set probe = {rays, NULL, n, 0, 0};
        bench_trace_opts to = {.threads = o->threads, .warmup = 0, .repeats = 1, .hits = hits,
                               .occluded = occ};
        rc = bench_trace(kind, accel, &probe, t->occl, &to, &br, &err);
    }
    free(rays), free(hits), free(occ);
    return rc ? -1 : br.ms.median; /* the pass itself reports any error */
}

static void warn_slow_pass(const options *o, const run *r, const accel_kind *kind,
                           const void *accel, const accel_params *canon, const set_run *t,
                           int count_pass)
{
    size_t count = t->rays->count, n = 0;
    double ms = -1;
    for (size_t block = 1; block <= 64; block *= 8) {
        if (4 * PROBE_BLOCKS * block > count) break; /* a probe is at most a quarter of the pass */
        n = PROBE_BLOCKS * block;
        ms = probe_ms(o, kind, accel, t, block);
        if (ms < 0 || ms >= PROBE_MS) break;
    }
    if (ms <= 0) return;
    double pass_s = ms * 1e-3 * (double)count / (double)n;
    if (pass_s <= SLOW_PASS_S) return;
    int passes = count_pass + o->warmup + 1;
    char one[32], all[32];
    fprintf(stderr, "trace: warning: %s on %s: about %s per %s pass of %zu rays (a probe of %zu "
            "rays took %.0f ms on %d thread%s); at least %d passes follow (counted, warm-up, "
            "timed), about %s; --size, --rays or another kind make it shorter\n",
            canon->spec, r->scene.name, fmt_duration(one, sizeof one, pass_s),
            r->set_names[t->set], count, n, ms, o->threads, o->threads > 1 ? "s" : "",
            passes, fmt_duration(all, sizeof all, passes * pass_s));
}

/* Step 6: one ray set on one built accelerator. */
static void trace_set(const options *o, run *r, int s, int last, const accel_kind *kind,
                      const void *accel, const accel_params *canon, const accel_build_stats *st,
                      const accel_timing *bt)
{
    accel_error err = {0};
    set_run t = {0};
    t.rays = r->from_file ? &r->file_rays : bench_sets_get(&r->sets, r->bits[s]);
    t.set = s;
    t.occl = r->from_file ? o->occluded : bench_set_is_occlusion(r->bits[s]);
    size_t n = t.rays->count, m = n ? n : 1;
    int heat = o->heatmap[0] && last && t.rays->pixel;
    t.hits = malloc(m * sizeof *t.hits);
    t.occ = malloc(m);
    if (heat) t.steps = calloc(m, sizeof *t.steps), t.prims = calloc(m, sizeof *t.prims);
    if (!t.hits || !t.occ || (heat && (!t.steps || !t.prims))) {
        report(r, CLI_EXIT_INTERNAL, "out of memory for the results of a ray set");
        goto done;
    }
    char phase[320];
    snprintf(phase, sizeof phase, "trace %s with %s", r->set_names[s], canon->spec);
    bench_trace_opts to = {.threads = o->threads, .warmup = o->warmup, .repeats = o->repeat,
                           .max_ms = o->budget * 1e3,
                           .count_pass = o->counters || heat, .hits = t.hits, .occluded = t.occ,
                           .ray_steps = t.steps, .ray_prims = t.prims,
                           .progress = r->progress, .progress_name = phase};
    warn_slow_pass(o, r, kind, accel, canon, &t, to.count_pass);
    int rc = bench_trace(kind, accel, t.rays, t.occl, &to, &t.br, &err);
    /* A broken invariant of the counted pass leaves the timings valid: they
     * are printed, then the error is reported. */
    if (rc && err.code != ACCEL_ERR_INTERNAL) {
        report_err(r, &err);
        goto done;
    }
    accel_error cerr = {0};
    if (o->check && check_set(o, r, &t, &cerr)) report_err(r, &cerr);
    print_row(o, r, kind, canon, st, bt, &t);
    warn_collapse(r, kind, canon, &t);
    if (rc) report_err(r, &err);
    if (last) write_outputs(o, r, &t, kind, accel, canon->spec);
done:
    free(t.hits);
    free(t.occ);
    free(t.steps);
    free(t.prims);
}

/* Step 5: build one accelerator (checked up front), then trace every set. */
static void run_accel(const options *o, run *r, int a)
{
    accel_error err = {0};
    const accel_kind *kind;
    void *accel;
    accel_build_stats st;
    accel_timing bt;
    if (bench_build(o->accels[a], &r->scene, o->threads, o->build_repeat, o->budget * 1e3, &kind,
                    &accel, &st, &bt, r->progress, &err)) {
        report_err(r, &err);
        return;
    }
    accel_params canon;
    accel_params_parse(o->accels[a], &canon, &err);
    if (!o->csv) {
        unsigned live = r->scene.live_count;
        printf("accel %s: build %.2f ms (min %.2f, max %.2f, %d runs), %.2f Mprims/s, %zu bytes "
               "(%.1f B/prim), %llu %s", canon.spec, bt.median, bt.min, bt.max, bt.n,
               bt.median > 0 ? live / (bt.median * 1e3) : 0.0, st.bytes,
               (double)st.bytes / live, (unsigned long long)st.nodes, kind->step_name);
        if (!isnan(st.sah_cost) && st.sah_cost != 0) printf(", SAH cost %.2f", st.sah_cost);
        if (st.depth) printf(", depth %d", st.depth);
        if (st.res[0]) printf(", res %dx%dx%d", st.res[0], st.res[1], st.res[2]);
        if (st.isa) printf(", isa %s", st.isa);
        printf("\n");
    }
    for (int s = 0; s < r->set_count; s++)
        trace_set(o, r, s, a == o->accel_count - 1, kind, accel, &canon, &st, &bt);
    kind->destroy(accel);
}

int main(int argc, char **argv)
{
    /* Lines reach a pipe or file as they are printed, in order with stderr. */
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (argc > 1 && !strcmp(argv[1], "compare")) return trace_compare(argc, argv);
    options o;
    run r = {0};
    accel_error err = {0};
    if (parse_options(argc, argv, &o, &r, &err)) {
        fprintf(stderr, "trace: %s\n", err.msg);
        /* Before any work every fault is the command line's, but a file
         * that cannot be opened. */
        return err.code == ACCEL_ERR_IO ? CLI_EXIT_INPUT : CLI_EXIT_USAGE;
    }
    if (o.help) {
        usage(stdout);
        return CLI_EXIT_OK;
    }
    r.progress = bench_progress_start(o.quiet ? NULL : stderr, "trace", o.progress_after * 1e3);
    csv_open(&r.csv, stdout);
    if (load_scene(&o, &r, &err) || set_camera(&o, &r, &err) || make_rays(&o, &r, &err)) {
        report_err(&r, &err);
    } else {
        if (o.csv) print_csv_header(&r);
        for (int a = 0; a < o.accel_count; a++) run_accel(&o, &r, a);
        print_summary(&o, &r);
    }
    bench_progress_stop(r.progress);
    bench_sets_free(&r.sets);
    rays_free(&r.file_rays);
    scene_free(&r.scene);
    return r.status;
}
