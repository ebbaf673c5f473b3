/*
 * trace.c - bin/trace: build any accelerator on any scene, trace any ray
 * set, and report build time, memory, Mrays/s (median/min/max of repeats
 * after a warm-up) and counter averages from a separate counted pass.
 *
 *   trace --scene bunny.off --accel bvh:build=binned --rays primary,diffuse
 *   trace compare A.hits B.hits
 *
 * Run `trace --help` for every option, accelerator and scene parameter.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/bench.h"
#include "bench/image.h"
#include "scene/scene.h"

#define MAX_ACCELS 32
#define MAX_SETS 8

typedef struct {
    const char *scene;
    const char *accels[MAX_ACCELS];
    int accel_count;
    const char *rays;
    int width, height;
    accel_camera cam;
    int cam_set[4]; /* eye, look, up, fov given */
    int threads, repeat, warmup, build_repeat;
    int counters, check, csv;
    const char *image, *heatmap_kind, *heatmap, *dump_rays, *dump_hits, *export_obj;
    const char *gen_accel;
    uint64_t seed;
    int ao_samples;
    float ao_radius;
    image_heat_scale heat_scale;
} options;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: trace [options]\n"
            "       trace compare REFERENCE.hits OTHER.hits\n"
            "Builds accelerators on a scene, traces ray sets, reports speed and costs.\n\n"
            "  --scene SPEC        built-in scene (name:key=value,...) or mesh file (.obj .ply .off)\n"
            "                      (default sphereflake)\n"
            "  --accel SPEC        accelerator kind:key=value,...; repeat to compare several\n"
            "                      (default bvh when registered, else brute)\n"
            "  --rays LIST         comma list of primary,shadow,diffuse,ao, or a .rays file\n"
            "                      (default primary)\n"
            "  --size WxH          image / primary ray grid (default 512x512)\n"
            "  --eye X,Y,Z --look X,Y,Z --up X,Y,Z --fov DEG   override the scene's camera\n"
            "  --threads N         trace and build threads (default 1)\n"
            "  --repeat N          timed passes per ray set (default 5), after --warmup N (1)\n"
            "  --build-repeat N    builds timed per accelerator (default 3, up to 10 s)\n"
            "  --no-counters       skip the counted pass (steps, box and primitive tests)\n"
            "  --check             compare every result against the double-precision reference\n"
            "  --image F.png       shaded image of the primary hits (.png or .ppm)\n"
            "  --heatmap steps|prims F.png   cost per pixel with a colour scale\n"
            "  --heat-scale SPEC   heatmap scale: auto (0..image max, default), max=N (fixed,\n"
            "                      so images compare), log (log(1+v)); e.g. log,max=200\n"
            "  --dump-rays F       write the ray set(s) in FORMATS.md .rays (F.<set>.rays if several)\n"
            "  --dump-hits F       write the hits of the last accelerator (F.<set>.hits if several)\n"
            "  --export-obj F      write the scene as OBJ (spheres tessellated) and continue\n"
            "  --csv               one machine-readable line per measurement\n"
            "  --gen-accel SPEC    accelerator that finds the primary hits secondary rays start\n"
            "                      from (default bvh, else brute)\n"
            "  --seed N --ao-samples N --ao-radius R   secondary ray generation\n"
            "  --help              this text\n\nAccelerators:\n");
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
}

static int parse_vec(const char *s, vec3 *v)
{
    char *end;
    float a = strtof(s, &end);
    if (*end != ',') return 0;
    float b = strtof(end + 1, &end);
    if (*end != ',') return 0;
    float c = strtof(end + 1, &end);
    if (*end || !isfinite(a) || !isfinite(b) || !isfinite(c)) return 0;
    *v = v3(a, b, c);
    return 1;
}

static int parse_int(const char *s, int lo, int hi, int *out)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (!*s || *end || v < lo || v > hi) return 0;
    *out = (int)v;
    return 1;
}

static int die(const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "trace: ");
    fprintf(stderr, fmt, a, b);
    fprintf(stderr, "\n");
    return 2;
}

static int parse_options(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->scene = "sphereflake";
    o->rays = "primary";
    o->width = o->height = 512;
    o->threads = 1;
    o->repeat = 5;
    o->warmup = 1;
    o->build_repeat = 3;
    o->counters = 1;
    o->seed = 1;
    o->ao_samples = 4;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
#define NEED_VALUE()                                                         \
    do {                                                                     \
        if (!v) return die("option %s needs a value%s", a, "");              \
        i++;                                                                 \
    } while (0)
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            exit(0);
        } else if (!strcmp(a, "--scene")) {
            NEED_VALUE();
            o->scene = v;
        } else if (!strcmp(a, "--accel")) {
            NEED_VALUE();
            if (o->accel_count == MAX_ACCELS) return die("at most 32 --accel%s%s", "", "");
            o->accels[o->accel_count++] = v;
        } else if (!strcmp(a, "--rays")) {
            NEED_VALUE();
            o->rays = v;
        } else if (!strcmp(a, "--size")) {
            NEED_VALUE();
            if (sscanf(v, "%dx%d", &o->width, &o->height) != 2 || o->width < 1 || o->height < 1 ||
                o->width > 16384 || o->height > 16384)
                return die("--size %s: expected WxH with 1 <= W, H <= 16384%s", v, "");
        } else if (!strcmp(a, "--eye") || !strcmp(a, "--look") || !strcmp(a, "--up")) {
            NEED_VALUE();
            vec3 *dst = a[2] == 'e' ? &o->cam.eye : a[2] == 'l' ? &o->cam.look_at : &o->cam.up;
            if (!parse_vec(v, dst)) return die("%s %s: expected X,Y,Z", a, v);
            o->cam_set[a[2] == 'e' ? 0 : a[2] == 'l' ? 1 : 2] = 1;
        } else if (!strcmp(a, "--fov")) {
            NEED_VALUE();
            char *end;
            o->cam.fov_deg = strtof(v, &end);
            if (*end || !(o->cam.fov_deg > 0 && o->cam.fov_deg < 179))
                return die("--fov %s: expected degrees in (0, 179)%s", v, "");
            o->cam_set[3] = 1;
        } else if (!strcmp(a, "--threads")) {
            NEED_VALUE();
            if (!parse_int(v, 1, 256, &o->threads)) return die("--threads %s: expected 1..256%s", v, "");
        } else if (!strcmp(a, "--repeat")) {
            NEED_VALUE();
            if (!parse_int(v, 1, 100, &o->repeat)) return die("--repeat %s: expected 1..100%s", v, "");
        } else if (!strcmp(a, "--warmup")) {
            NEED_VALUE();
            if (!parse_int(v, 0, 100, &o->warmup)) return die("--warmup %s: expected 0..100%s", v, "");
        } else if (!strcmp(a, "--build-repeat")) {
            NEED_VALUE();
            if (!parse_int(v, 1, 64, &o->build_repeat))
                return die("--build-repeat %s: expected 1..64%s", v, "");
        } else if (!strcmp(a, "--no-counters")) {
            o->counters = 0;
        } else if (!strcmp(a, "--check")) {
            o->check = 1;
        } else if (!strcmp(a, "--csv")) {
            o->csv = 1;
        } else if (!strcmp(a, "--image")) {
            NEED_VALUE();
            o->image = v;
        } else if (!strcmp(a, "--heatmap")) {
            if (i + 2 >= argc) return die("--heatmap needs steps|prims and a file%s%s", "", "");
            o->heatmap_kind = argv[++i];
            o->heatmap = argv[++i];
            if (strcmp(o->heatmap_kind, "steps") && strcmp(o->heatmap_kind, "prims"))
                return die("--heatmap %s: expected steps or prims%s", o->heatmap_kind, "");
        } else if (!strcmp(a, "--heat-scale")) {
            NEED_VALUE();
            accel_error e = {0};
            if (image_heat_scale_parse(v, &o->heat_scale, &e)) return die("%s%s", e.msg, "");
        } else if (!strcmp(a, "--dump-rays")) {
            NEED_VALUE();
            o->dump_rays = v;
        } else if (!strcmp(a, "--dump-hits")) {
            NEED_VALUE();
            o->dump_hits = v;
        } else if (!strcmp(a, "--export-obj")) {
            NEED_VALUE();
            o->export_obj = v;
        } else if (!strcmp(a, "--gen-accel")) {
            NEED_VALUE();
            o->gen_accel = v;
        } else if (!strcmp(a, "--seed")) {
            NEED_VALUE();
            o->seed = strtoull(v, NULL, 10);
        } else if (!strcmp(a, "--ao-samples")) {
            NEED_VALUE();
            if (!parse_int(v, 1, 4096, &o->ao_samples))
                return die("--ao-samples %s: expected 1..4096%s", v, "");
        } else if (!strcmp(a, "--ao-radius")) {
            NEED_VALUE();
            o->ao_radius = strtof(v, NULL);
        } else {
            return die("unknown option '%s' (see --help)%s", a, "");
        }
#undef NEED_VALUE
    }
    if (o->accel_count == 0) o->accels[o->accel_count++] = accel_find_kind("bvh") ? "bvh" : "brute";
    return 0;
}

static int cmd_compare(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: trace compare REFERENCE.hits OTHER.hits\n");
        return 2;
    }
    accel_error err = {0};
    accel_hit *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    if (hits_read(argv[2], &a, &na, &err) || hits_read(argv[3], &b, &nb, &err)) {
        fprintf(stderr, "trace: %s\n", err.msg);
        free(a);
        return 2;
    }
    if (na != nb) {
        fprintf(stderr, "trace: %s has %zu hits, %s has %zu\n", argv[2], na, argv[3], nb);
        free(a), free(b);
        return 2;
    }
    hits_diff d = hits_compare(a, b, na);
    printf("rays %zu  agree %zu  holes %zu  false_hits %zu  disagreements %zu\n", d.rays, d.agree,
           d.holes, d.false_hits, d.disagreements);
    if (d.first_bad != SIZE_MAX) {
        size_t i = d.first_bad;
        printf("first difference: ray %zu: %s prim %u t %.9g, %s prim %u t %.9g\n", i, argv[2],
               a[i].prim, a[i].t, argv[3], b[i].prim, b[i].t);
    }
    free(a), free(b);
    return d.agree == d.rays ? 0 : 1;
}

/* File name for a per-set output: F itself for one set, F.<set>.<ext> otherwise. */
static void set_path(char *out, size_t n, const char *base, const char *set, const char *ext,
                     int several)
{
    if (several)
        snprintf(out, n, "%s.%s.%s", base, set, ext);
    else
        snprintf(out, n, "%s", base);
}

static void shade(const accel_scene *s, const rays_set *r, const accel_hit *hits, image_rgb *img)
{
    for (size_t i = 0; i < r->count; i++) {
        uint32_t px = r->pixel ? r->pixel[i] : (uint32_t)i;
        if (px >= (uint32_t)(img->width * img->height)) continue;
        uint8_t *c = img->rgb + 3 * (size_t)px;
        vec3 p, n;
        if (!rays_hit_frame(s, &r->rays[i], &hits[i], &p, &n)) {
            c[0] = 30, c[1] = 34, c[2] = 48;
            continue;
        }
        vec3 d = v3_norm(v3(r->rays[i].dx, r->rays[i].dy, r->rays[i].dz));
        vec3 l = v3_norm(v3_sub(s->light, p));
        float head = fabsf(v3_dot(n, d));
        float lamb = fmaxf(0.0f, v3_dot(n, l));
        float k = 0.15f + 0.45f * head + 0.4f * lamb;
        float base[3] = {0.85f, 0.85f, 0.9f};
        if (hits[i].prim >= s->tri_count) base[0] = 0.95f, base[1] = 0.75f, base[2] = 0.55f;
        for (int j = 0; j < 3; j++) c[j] = (uint8_t)fminf(255.0f, 255.0f * k * base[j]);
    }
}

static void print_csv_header(void)
{
    printf("csv,kind,spec,scene,rayset,rays,hits,threads,build_ms,build_ms_min,build_ms_max,bytes,"
           "nodes,refs,sah_cost,depth,trace_ms,mrays_median,mrays_min,mrays_max,steps_per_ray,"
           "empty_per_ray,box_per_ray,prims_per_ray,mailbox_skips_per_ray,holes,false_hits,"
           "disagreements\n");
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "compare")) return cmd_compare(argc, argv);
    options o;
    int rc = parse_options(argc, argv, &o);
    if (rc) return rc;
    accel_error err = {0};
    accel_scene scene;
    double t0 = accel_now_ms();
    if (scene_create(o.scene, &scene, &err)) {
        fprintf(stderr, "trace: %s\n", err.msg);
        return 1;
    }
    double load_ms = accel_now_ms() - t0;
    if (!o.csv)
        printf("scene %s: %u primitives (%u triangles, %u spheres), %u degenerate, made in %.1f ms\n",
               scene.name, scene.prim_count, scene.tri_count, scene.sphere_count,
               scene.degenerate_count, load_ms);
    if (o.export_obj) {
        if (scene_export_obj(&scene, o.export_obj, 24, &err)) {
            fprintf(stderr, "trace: %s\n", err.msg);
            return 1;
        }
        if (!o.csv) printf("exported %s\n", o.export_obj);
    }
    accel_camera cam = scene.camera;
    if (o.cam_set[0]) cam.eye = o.cam.eye;
    if (o.cam_set[1]) cam.look_at = o.cam.look_at;
    if (o.cam_set[2]) cam.up = o.cam.up;
    if (o.cam_set[3]) cam.fov_deg = o.cam.fov_deg;

    /* Ray sets: named sets of the view, or one .rays file. */
    bench_sets sets = {0};
    rays_set file_rays = {0};
    int bits[MAX_SETS], set_count = 0;
    const char *set_names[MAX_SETS];
    int from_file = strstr(o.rays, ".rays") != NULL;
    if (from_file) {
        if (rays_read(o.rays, &file_rays, &err)) {
            fprintf(stderr, "trace: %s\n", err.msg);
            return 1;
        }
        bits[0] = 0;
        set_names[0] = "file";
        set_count = 1;
    } else {
        char buf[256];
        snprintf(buf, sizeof buf, "%s", o.rays);
        int mask = 0;
        char *save = NULL;
        for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
            int bit = bench_set_bit_of(tok);
            if (!bit) {
                fprintf(stderr, "trace: unknown ray set '%s'; accepted: primary, shadow, diffuse, "
                                "ao, or a .rays file\n", tok);
                return 2;
            }
            if (set_count == MAX_SETS || (mask & bit)) continue;
            mask |= bit;
            bits[set_count] = bit;
            set_names[set_count++] = bit == BENCH_PRIMARY   ? "primary"
                                     : bit == BENCH_SHADOW  ? "shadow"
                                     : bit == BENCH_DIFFUSE ? "diffuse"
                                                            : "ao";
        }
        bench_set_opts so = {&cam, o.width, o.height, o.ao_samples, o.ao_radius, o.seed,
                             o.threads, o.gen_accel};
        if (bench_sets_make(&scene, &so, mask, &sets, &err)) {
            fprintf(stderr, "trace: %s\n", err.msg);
            return 1;
        }
    }
    if (o.dump_rays)
        for (int s = 0; s < set_count; s++) {
            const rays_set *r = from_file ? &file_rays : bench_sets_get(&sets, bits[s]);
            char path[1024];
            set_path(path, sizeof path, o.dump_rays, set_names[s], "rays", set_count > 1);
            if (rays_write(path, r->rays, r->count, &err)) {
                fprintf(stderr, "trace: %s\n", err.msg);
                return 1;
            }
        }
    if (o.csv) print_csv_header();

    int status = 0;
    for (int a = 0; a < o.accel_count; a++) {
        const accel_kind *kind;
        void *accel;
        accel_build_stats st;
        accel_timing bt;
        if (bench_build(o.accels[a], &scene, o.threads, o.build_repeat, 10000.0, &kind, &accel,
                        &st, &bt, &err)) {
            fprintf(stderr, "trace: %s\n", err.msg);
            status = 1;
            continue;
        }
        accel_params canon;
        accel_params_parse(o.accels[a], &canon, &err);
        if (!o.csv) {
            printf("accel %s: build %.2f ms (min %.2f, max %.2f, %d runs), %.2f Mprims/s, %zu bytes "
                   "(%.1f B/prim), %llu %s",
                   canon.spec, bt.median, bt.min, bt.max, bt.n,
                   bt.median > 0 ? scene.live_count / (bt.median * 1e3) : 0.0, st.bytes,
                   scene.live_count ? (double)st.bytes / scene.live_count : 0.0,
                   (unsigned long long)st.nodes, kind->step_name);
            if (!isnan(st.sah_cost) && st.sah_cost != 0) printf(", SAH cost %.2f", st.sah_cost);
            if (st.depth) printf(", depth %d", st.depth);
            if (st.res[0]) printf(", res %dx%dx%d", st.res[0], st.res[1], st.res[2]);
            printf("\n");
        }
        for (int s = 0; s < set_count; s++) {
            const rays_set *r = from_file ? &file_rays : bench_sets_get(&sets, bits[s]);
            int occl = !from_file && bench_set_is_occlusion(bits[s]);
            size_t n = r->count;
            accel_hit *hits = malloc((n ? n : 1) * sizeof *hits);
            uint8_t *occ = malloc(n ? n : 1);
            uint32_t *steps = NULL, *prims = NULL;
            int want_heat = o.heatmap && a == o.accel_count - 1 && r->pixel;
            if (want_heat) {
                steps = calloc(n ? n : 1, sizeof *steps);
                prims = calloc(n ? n : 1, sizeof *prims);
            }
            if (!hits || !occ || (want_heat && (!steps || !prims))) {
                fprintf(stderr, "trace: out of memory for %zu rays\n", n);
                return 1;
            }
            bench_trace_opts to = {.threads = o.threads, .warmup = o.warmup,
                                   .repeats = o.repeat, .count_pass = o.counters || want_heat,
                                   .hits = hits, .occluded = occ, .ray_steps = steps,
                                   .ray_prims = prims};
            bench_result br;
            if (bench_trace(kind, accel, r, occl, &to, &br, &err)) {
                fprintf(stderr, "trace: %s\n", err.msg);
                return 1;
            }
            hits_diff d = {0};
            int checked = 0;
            if (o.check) {
                accel_hit *ref = malloc((n ? n : 1) * sizeof *ref);
                if (!ref) return 1;
                accel_reference_trace(&scene, r->rays, ref, n, accel_cpu_count());
                if (occl) /* compare occlusion as hit / miss */
                    for (size_t i = 0; i < n; i++) {
                        int rh = ref[i].prim != ACCEL_MISS;
                        if (rh && !occ[i]) d.holes++;
                        if (!rh && occ[i]) d.false_hits++;
                    }
                else
                    d = hits_compare(ref, hits, n);
                free(ref);
                checked = 1;
                if (d.holes || d.false_hits || d.disagreements) status = 1;
            }
            double nr = n ? (double)n : 1.0;
            const accel_counters *c = &br.counters;
            if (o.csv) {
                printf("csv,%s,%s,%s,%s,%zu,%zu,%d,%.4f,%.4f,%.4f,%zu,%llu,%llu,%.6g,%d,%.4f,%.4f,"
                       "%.4f,%.4f,",
                       kind->name, canon.spec, scene.name, set_names[s], n, br.hits, o.threads,
                       bt.median, bt.min, bt.max, st.bytes, (unsigned long long)st.nodes,
                       (unsigned long long)st.refs, st.sah_cost, st.depth, br.ms.median,
                       br.mrays.median, br.mrays.min, br.mrays.max);
                if (br.counted)
                    printf("%.4f,%.4f,%.4f,%.4f,%.4f,", c->steps / nr, c->empty_steps / nr,
                           c->box_tests / nr, c->prim_tests / nr, c->mailbox_skips / nr);
                else
                    printf(",,,,,");
                if (checked)
                    printf("%zu,%zu,%zu\n", d.holes, d.false_hits, d.disagreements);
                else
                    printf(",,\n");
            } else {
                printf("  %-8s %9zu rays %9zu %s  %8.3f Mrays/s (min %.3f, max %.3f; %.2f ms)", set_names[s],
                       n, br.hits, occl ? "occluded" : "hit", br.mrays.median, br.mrays.min,
                       br.mrays.max, br.ms.median);
                if (br.counted)
                    printf("  per ray: %.2f %s, %.2f empty, %.2f box, %.2f prim, %.2f mailbox skips",
                           c->steps / nr, kind->step_name, c->empty_steps / nr, c->box_tests / nr,
                           c->prim_tests / nr, c->mailbox_skips / nr);
                printf("\n");
                if (checked)
                    printf("    check vs reference: %zu holes, %zu false hits, %zu disagreements\n",
                           d.holes, d.false_hits, d.disagreements);
            }
            if (a == o.accel_count - 1) {
                if (o.dump_hits && !occl) {
                    char path[1024];
                    set_path(path, sizeof path, o.dump_hits, set_names[s], "hits", set_count > 1);
                    if (hits_write(path, hits, n, &err)) {
                        fprintf(stderr, "trace: %s\n", err.msg);
                        return 1;
                    }
                }
                if (o.image && bits[s] == BENCH_PRIMARY) {
                    image_rgb img;
                    if (image_alloc(&img, r->width, r->height, &err) == 0) {
                        shade(&scene, r, hits, &img);
                        if (image_write(o.image, &img, &err)) status = 1;
                        image_free(&img);
                    }
                    if (status) fprintf(stderr, "trace: %s\n", err.msg);
                }
                if (want_heat) {
                    float *v = calloc((size_t)r->width * r->height, sizeof *v);
                    uint32_t *src = !strcmp(o.heatmap_kind, "steps") ? steps : prims;
                    for (size_t i = 0; v && i < n; i++)
                        if (r->pixel[i] < (uint32_t)(r->width * r->height)) v[r->pixel[i]] += src[i];
                    image_rgb img;
                    char path[1024], title[256];
                    set_path(path, sizeof path, o.heatmap, set_names[s], "png", set_count > 1);
                    image_heat_title(title, sizeof title, o.accels[a], kind, src == prims);
                    if (v && image_heatmap(v, r->width, r->height, &o.heat_scale, title, &img,
                                           &err) == 0) {
                        if (image_write(path, &img, &err)) {
                            fprintf(stderr, "trace: %s\n", err.msg);
                            status = 1;
                        }
                        image_free(&img);
                    }
                    free(v);
                }
            }
            free(hits);
            free(occ);
            free(steps);
            free(prims);
        }
        kind->destroy(accel);
    }
    bench_sets_free(&sets);
    rays_free(&file_rays);
    scene_free(&scene);
    return status;
}
