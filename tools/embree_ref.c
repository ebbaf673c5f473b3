/*
 * embree_ref.c - bin/embree_ref: the industrial reference, Embree 3, on the
 * project's own triangles and rays. Optional: built only by `make embree`
 * when libembree-dev (embree3/rtcore.h, -lembree3) is installed; `make`,
 * `make test` and `make report` never need it.
 *
 *   trace --scene bunny.off --export-obj b.obj --size 1024x768 \
 *         --rays primary,diffuse,shadow --dump-rays b
 *   embree_ref --obj b.obj --rays b.primary.rays --hits e.hits
 *   embree_ref --obj b.obj --rays b.shadow.rays --mode occluded --hits e.hits
 *   trace compare REF.hits e.hits        (trace compare --occluded for shadow)
 *
 * The scene is read by the project's own loader (FORMATS.md triangle order)
 * and handed to Embree as one triangle geometry of 3 vertices per triangle
 * (shared buffers, no welding), so Embree's primID is the project's triangle
 * id and the hit files compare ray by ray. Embree's u and v are the weights
 * of the 2nd and 3rd vertex (rtcore_ray.h, RTCHit), as FORMATS.md's are.
 *
 * Printed: one line of key=value fields (mode, rays, Mrays/s as the median
 * of --passes timed passes after one warm-up pass, with min and max; build
 * ms as the median of --builds builds; the bytes Embree allocated for the
 * scene, from its memory monitor callback; the ISA Embree chose).
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <embree3/rtcore.h>

#include "cli/cli.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "embree_ref/vs.h"

typedef struct {
    const char *obj, *rays, *hits, *mode, *quality, *isa, *vs;
    int threads, build_threads, passes, builds, occluded, coherent, check, help;
} options;

#define OPT(f) offsetof(options, f)
static const cli_option ref_options[] = {
    {"--obj", "F", "the scene: an OBJ from `trace --export-obj` (or any mesh file the\n"
     "project reads: .obj .ply .off); triangles only", cli_string, OPT(obj), 0, 0},
    {"--rays", "F.rays", "the rays (FORMATS.md), e.g. from `trace --dump-rays`", cli_string,
     OPT(rays), 0, 0},
    {"--hits", "F.hits", "write the answers (FORMATS.md; any-hit answers with --occluded)",
     cli_string, OPT(hits), 0, 0},
    {"--mode", "M", "single (rtcIntersect1, default), packet16 (rtcIntersect16 over 16\n"
     "consecutive rays), stream (rtcIntersect1M over 256 consecutive rays), or\n"
     "occluded (= single --occluded: rtcOccluded1)", cli_string, OPT(mode), 0, 0},
    {"--occluded", NULL, "occlusion queries (rtcOccluded1/16/1M): any-hit answers", cli_flag,
     OPT(occluded), 0, 0},
    {"--coherent", NULL, "tell Embree the rays are coherent (RTC_INTERSECT_CONTEXT_FLAG_COHERENT)",
     cli_flag, OPT(coherent), 0, 0},
    {"--quality", "Q", "build quality: low, medium (Embree's default), high", cli_string,
     OPT(quality), 0, 0},
    {"--isa", "ISA", "highest ISA Embree may use: sse2, sse4.2, avx, avx2, avx512 (max_isa)",
     cli_string, OPT(isa), 0, 0},
    {"--threads", "N", "tracing threads, each its own context and slice of rays (default 1)",
     cli_int, OPT(threads), 1, 256},
    {"--build-threads", "N", "Embree's threads (device config threads=N; default 1)", cli_int,
     OPT(build_threads), 1, 256},
    {"--passes", "N", "timed passes after one warm-up pass (default 5)", cli_int, OPT(passes), 1,
     1000},
    {"--builds", "N", "timed builds, the median printed (default 3)", cli_int, OPT(builds), 1,
     100},
    {"--check", NULL, "compare Embree's answers with the project's oracle (double precision,\n"
     "watertight): holes, false hits, disagreements (FORMATS.md rules)", cli_flag, OPT(check), 0, 0},
    {"--vs", "SPEC", "also time this project's SPEC here on the same rays, pass for pass in\n"
     "turn with Embree's (embree_ref/vs.h): a line `vs`", cli_string, OPT(vs), 0, 0},
    {"--help", NULL, "this text", cli_flag, OPT(help), 0, 0},
};
#define OPTION_COUNT (sizeof ref_options / sizeof ref_options[0])

enum { LAYOUT_SINGLE, LAYOUT_PACKET16, LAYOUT_STREAM };
#define STREAM_CHUNK 256


/* ---- device: errors, memory, ISA ------------------------------------------ */

static void on_error(void *user, enum RTCError code, const char *str)
{
    (void)user;
    fprintf(stderr, "embree_ref: Embree error %d: %s\n", (int)code, str ? str : "");
}

/* Bytes Embree holds now and at most (rtcSetDeviceMemoryMonitorFunction:
 * bytes > 0 before an allocation, < 0 after a free). */
static long long mem_now, mem_peak;
static pthread_mutex_t mem_lock = PTHREAD_MUTEX_INITIALIZER;

static bool on_memory(void *user, ssize_t bytes, bool post)
{
    (void)user, (void)post;
    pthread_mutex_lock(&mem_lock);
    mem_now += bytes;
    if (mem_now > mem_peak) mem_peak = mem_now;
    pthread_mutex_unlock(&mem_lock);
    return true;
}

/* Words of the line of `text` that holds `tag`, after its "Targets :". */
static int isa_words(const char *text, const char *tag, char words[16][16])
{
    const char *tagp = strstr(text, tag);
    if (!tagp) return 0;
    const char *line = tagp;
    while (line > text && line[-1] != '\n') line--;
    const char *p = strstr(line, ":");
    if (!p || p > tagp) p = line;
    else p++;
    int n = 0;
    while (p < tagp && n < 16) {
        while (p < tagp && *p == ' ') p++;
        int len = 0;
        while (p + len < tagp && p[len] != ' ' && p[len] != '\n') len++;
        if (len > 0 && len < 16) memcpy(words[n], p, (size_t)len), words[n++][len] = 0;
        p += len;
    }
    return n;
}

/* The ISA the device of `config` runs: Embree says so only in its verbose
 * banner (stdout), so a probe device is made with stdout sent to a temporary
 * file; the ISA is the best compiled-in target among the supported ones. */
static void probe_isa(const char *config, char *isa, size_t size)
{
    snprintf(isa, size, "unknown");
    char cfg[256];
    snprintf(cfg, sizeof cfg, "%s,verbose=1", config);
    FILE *tmp = tmpfile();
    if (!tmp) return;
    fflush(stdout);
    int saved = dup(STDOUT_FILENO);
    if (saved < 0) { fclose(tmp); return; }
    dup2(fileno(tmp), STDOUT_FILENO);
    RTCDevice probe = rtcNewDevice(cfg);
    fflush(stdout);
    dup2(saved, STDOUT_FILENO);
    close(saved);
    if (probe) rtcReleaseDevice(probe);
    static char text[16384];
    rewind(tmp);
    size_t got = fread(text, 1, sizeof text - 1, tmp);
    text[got] = 0;
    fclose(tmp);
    char sup[16][16], built[16][16];
    int ns = isa_words(text, "(supported)", sup), nb = isa_words(text, "(compile time enabled)", built);
    for (int b = 0; b < nb; b++)
        for (int s = 0; s < ns; s++)
            if (!strcmp(built[b], sup[s])) snprintf(isa, size, "%.15s", built[b]);
}

/* ---- the scene --------------------------------------------------------------- */

typedef struct {
    float *verts;        /* 3 vertices per triangle, plus the padding Embree reads past the end */
    unsigned *index;     /* 3i, 3i+1, 3i+2 */
    unsigned tri_count;
    enum RTCBuildQuality quality;
    accel_scene scene;   /* as the project loaded it, for --check */
} ref_mesh;

/* An Embree scene of one triangle geometry over the mesh's shared buffers;
 * filter, if not NULL, is its occlusion filter (the recording pass). */
static RTCScene make_scene(RTCDevice dev, const ref_mesh *m, RTCFilterFunctionN filter, void *user)
{
    RTCScene sc = rtcNewScene(dev);
    rtcSetSceneBuildQuality(sc, m->quality);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, m->quality);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m->verts, 0,
                               3 * sizeof(float), (size_t)m->tri_count * 3);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m->index, 0,
                               3 * sizeof(unsigned), m->tri_count);
    if (filter) {
        rtcSetGeometryOccludedFilterFunction(g, filter);
        rtcSetGeometryUserData(g, user);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(sc, g, 0);
    rtcReleaseGeometry(g);
    rtcCommitScene(sc);
    return sc;
}

static int load_mesh(const char *path, const char *quality, ref_mesh *m)
{
    accel_scene s;
    accel_error err;
    m->verts = NULL, m->index = NULL;
    if (scene_load_file(path, &s, &err)) {
        fprintf(stderr, "embree_ref: %s\n", err.msg);
        return CLI_EXIT_INPUT;
    }
    if (s.sphere_count || !s.tri_count) {
        fprintf(stderr, "embree_ref: %s: %u spheres, %u triangles: triangles only (export the "
                "scene with trace --export-obj)\n", path, s.sphere_count, s.tri_count);
        scene_free(&s);
        return CLI_EXIT_INPUT;
    }
    m->tri_count = s.tri_count;
    m->verts = malloc(((size_t)s.tri_count * 9 + 4) * sizeof(float));
    m->index = malloc((size_t)s.tri_count * 3 * sizeof(unsigned));
    if (!m->verts || !m->index) {
        scene_free(&s);
        free(m->verts), free(m->index);
        fprintf(stderr, "embree_ref: out of memory\n");
        return CLI_EXIT_INTERNAL;
    }
    memcpy(m->verts, s.tris, (size_t)s.tri_count * 9 * sizeof(float));
    memset(m->verts + (size_t)s.tri_count * 9, 0, 4 * sizeof(float));
    for (size_t i = 0; i < (size_t)s.tri_count * 3; i++) m->index[i] = (unsigned)i;
    m->scene = s;
    m->quality = !strcmp(quality, "low")    ? RTC_BUILD_QUALITY_LOW
                 : !strcmp(quality, "high") ? RTC_BUILD_QUALITY_HIGH
                                            : RTC_BUILD_QUALITY_MEDIUM;
    return 0;
}

/* ---- rays ----------------------------------------------------------------- */

/* Embree traces rays with 0 <= tnear <= tfar and finite origin and direction
 * (rtcIntersect1(3)), and marks an occluded ray by tfar = -inf. A negative
 * tnear starts at 0 here; a ray FORMATS.md calls invalid (rays_invalid_count:
 * traced as a miss), or one left with no segment at t >= 0, becomes a ray
 * with tnear = 1 > tfar = 0 from the origin, which hits nothing and stays
 * unoccluded. Returns how many rays were changed. */
static size_t prepare_rays(accel_ray *r, size_t n)
{
    static const accel_ray none = {0, 0, 0, 1, 1, 0, 0, 0};
    size_t changed = 0;
    for (size_t i = 0; i < n; i++) {
        const char *why;
        size_t first;
        int bad = rays_invalid_count(&r[i], 1, &first, &why) != 0;
        if (!bad && r[i].t_near < 0) {
            r[i].t_near = 0;
            bad = r[i].t_far < 0;
            changed += !bad;
        }
        if (bad) r[i] = none, changed++;
    }
    return changed;
}

static void fill_ray(struct RTCRay *o, const accel_ray *r, unsigned id)
{
    o->org_x = r->ox, o->org_y = r->oy, o->org_z = r->oz, o->tnear = r->t_near;
    o->dir_x = r->dx, o->dir_y = r->dy, o->dir_z = r->dz, o->time = 0;
    o->tfar = r->t_far, o->mask = ~0u, o->id = id, o->flags = 0;
}

static accel_hit hit_of(float t, unsigned prim, float u, float v)
{
    accel_hit h = {INFINITY, ACCEL_MISS, 0.0f, 0.0f};
    if (prim != RTC_INVALID_GEOMETRY_ID) h.t = t, h.prim = prim, h.u = u, h.v = v;
    return h;
}

/* ---- tracing ---------------------------------------------------------------- */

typedef struct {
    RTCScene scene;
    const accel_ray *rays;
    size_t begin, end; /* this thread's slice */
    int layout, occluded, coherent;
    accel_hit *hits;   /* closest-hit answers */
    uint8_t *occ;      /* occlusion answers */
} job;

static void init_context(struct RTCIntersectContext *ctx, int coherent)
{
    rtcInitIntersectContext(ctx);
    if (coherent) ctx->flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
}

static void trace_single(const job *j)
{
    struct RTCIntersectContext ctx;
    init_context(&ctx, j->coherent);
    for (size_t i = j->begin; i < j->end; i++) {
        if (j->occluded) {
            struct RTCRay r;
            fill_ray(&r, &j->rays[i], (unsigned)i);
            rtcOccluded1(j->scene, &ctx, &r);
            j->occ[i] = r.tfar < 0; /* rtcOccluded1(3): tfar = -inf when occluded */
        } else {
            struct RTCRayHit rh;
            fill_ray(&rh.ray, &j->rays[i], (unsigned)i);
            rh.hit.geomID = rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(j->scene, &ctx, &rh);
            j->hits[i] = hit_of(rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v);
        }
    }
}

/* 16 consecutive rays as one packet (SOA, RTCRayHit16); the valid mask
 * leaves out the lanes past the slice's end. */
static void trace_packet16(const job *j)
{
    struct RTCIntersectContext ctx;
    init_context(&ctx, j->coherent);
    struct RTCRayHit16 p;
    int valid[16];
    for (size_t b = j->begin; b < j->end; b += 16) {
        for (unsigned k = 0; k < 16; k++) {
            size_t i = b + k;
            valid[k] = i < j->end ? -1 : 0;
            const accel_ray *r = &j->rays[i < j->end ? i : b];
            p.ray.org_x[k] = r->ox, p.ray.org_y[k] = r->oy, p.ray.org_z[k] = r->oz;
            p.ray.dir_x[k] = r->dx, p.ray.dir_y[k] = r->dy, p.ray.dir_z[k] = r->dz;
            p.ray.tnear[k] = r->t_near, p.ray.tfar[k] = r->t_far, p.ray.time[k] = 0;
            p.ray.mask[k] = ~0u, p.ray.id[k] = (unsigned)i, p.ray.flags[k] = 0;
            p.hit.geomID[k] = p.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
        }
        if (j->occluded) rtcOccluded16(valid, j->scene, &ctx, &p.ray);
        else rtcIntersect16(valid, j->scene, &ctx, &p);
        for (unsigned k = 0; k < 16 && b + k < j->end; k++) {
            if (j->occluded) j->occ[b + k] = p.ray.tfar[k] < 0;
            else j->hits[b + k] = hit_of(p.ray.tfar[k], p.hit.primID[k], p.hit.u[k], p.hit.v[k]);
        }
    }
}

/* STREAM_CHUNK consecutive rays as one stream (AOS, rtcIntersect1M). */
static void trace_stream(const job *j)
{
    struct RTCIntersectContext ctx;
    init_context(&ctx, j->coherent);
    static _Thread_local struct RTCRayHit s[STREAM_CHUNK];
    for (size_t b = j->begin; b < j->end; b += STREAM_CHUNK) {
        unsigned m = (unsigned)(j->end - b < STREAM_CHUNK ? j->end - b : STREAM_CHUNK);
        for (unsigned k = 0; k < m; k++) {
            fill_ray(&s[k].ray, &j->rays[b + k], (unsigned)(b + k));
            s[k].hit.geomID = s[k].hit.primID = RTC_INVALID_GEOMETRY_ID;
        }
        if (j->occluded) rtcOccluded1M(j->scene, &ctx, &s[0].ray, m, sizeof s[0]);
        else rtcIntersect1M(j->scene, &ctx, s, m, sizeof s[0]);
        for (unsigned k = 0; k < m; k++) {
            if (j->occluded) j->occ[b + k] = s[k].ray.tfar < 0;
            else j->hits[b + k] = hit_of(s[k].ray.tfar, s[k].hit.primID, s[k].hit.u, s[k].hit.v);
        }
    }
}

static void *run_job(void *arg)
{
    const job *j = arg;
    if (j->layout == LAYOUT_PACKET16) trace_packet16(j);
    else if (j->layout == LAYOUT_STREAM) trace_stream(j);
    else trace_single(j);
    return NULL;
}

/* One pass over all rays on `threads` threads (the calling one included),
 * each a contiguous slice (a multiple of 16 rays, so packets stay whole);
 * returns its milliseconds. */
static double trace_pass(const job *proto, size_t n, int threads)
{
    job jobs[256];
    pthread_t tid[256];
    size_t per = (n + (size_t)threads - 1) / (size_t)threads;
    per = (per + 15) / 16 * 16;
    int created[256] = {0};
    double t0 = accel_now_ms();
    for (int t = 0; t < threads; t++) {
        jobs[t] = *proto;
        jobs[t].begin = (size_t)t * per < n ? (size_t)t * per : n;
        jobs[t].end = jobs[t].begin + per < n ? jobs[t].begin + per : n;
    }
    for (int t = 1; t < threads; t++) created[t] = pthread_create(&tid[t], NULL, run_job, &jobs[t]) == 0;
    run_job(&jobs[0]);
    for (int t = 1; t < threads; t++) {
        if (created[t]) pthread_join(tid[t], NULL);
        else run_job(&jobs[t]); /* no thread: this one traces the slice */
    }
    return accel_now_ms() - t0;
}

/* ---- any-hit answers ---------------------------------------------------------- */

/* The occlusion filter of the recording pass: keeps the first hit each ray
 * reports (accepted, so it is the one that ends the query), its t from the
 * ray's tfar (the hit distance while a filter runs), its primID, u and v;
 * ray and hit are SOA packets of N lanes (rtcore_ray.h, RTCRayN/RTCHitN:
 * tfar is field 8, id 10; u 3, v 4, primID 5). */
static void on_occluded_hit(const struct RTCFilterFunctionNArguments *a)
{
    accel_hit *rec = a->geometryUserPtr;
    const unsigned n = a->N;
    const float *rf = (const float *)a->ray, *hf = (const float *)a->hit;
    const unsigned *ru = (const unsigned *)a->ray, *hu = (const unsigned *)a->hit;
    for (unsigned i = 0; i < n; i++) {
        if (!a->valid[i]) continue;
        accel_hit *h = &rec[ru[10 * n + i]];
        if (h->prim == ACCEL_MISS) *h = hit_of(rf[8 * n + i], hu[5 * n + i], hf[3 * n + i], hf[4 * n + i]);
    }
}

/* FORMATS.md any-hit answers for the timed occlusion answers occ: a miss,
 * or the triangle Embree's own occlusion query stopped at (an untimed pass
 * on a scene with the recording filter; where it records none, the closest
 * hit of the timed scene). Returns how many occluded rays neither gave a
 * triangle (written as misses). */
static size_t anyhit_answers(RTCDevice dev, const ref_mesh *m, RTCScene timed, const accel_ray *rays,
                             const uint8_t *occ, size_t n, accel_hit *out)
{
    for (size_t i = 0; i < n; i++) out[i] = hit_of(INFINITY, RTC_INVALID_GEOMETRY_ID, 0, 0);
    RTCScene rec = make_scene(dev, m, on_occluded_hit, out);
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    size_t lost = 0;
    for (size_t i = 0; i < n; i++) {
        if (!occ[i]) continue;
        struct RTCRay r;
        fill_ray(&r, &rays[i], (unsigned)i);
        rtcOccluded1(rec, &ctx, &r);
        if (out[i].prim != ACCEL_MISS) continue;
        struct RTCRayHit rh;
        fill_ray(&rh.ray, &rays[i], (unsigned)i);
        rh.hit.geomID = rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(timed, &ctx, &rh);
        out[i] = hit_of(rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v);
        lost += out[i].prim == ACCEL_MISS;
    }
    for (size_t i = 0; i < n; i++)
        if (!occ[i]) out[i] = hit_of(INFINITY, RTC_INVALID_GEOMETRY_ID, 0, 0);
    rtcReleaseScene(rec);
    return lost;
}

/* ---- main ------------------------------------------------------------------- */

static int parse(int argc, char **argv, options *o, int *layout)
{
    *o = (options){.mode = "single", .quality = "medium", .threads = 1, .build_threads = 1,
                   .passes = 5, .builds = 3};
    accel_error err;
    if (cli_parse(ref_options, OPTION_COUNT, argc, argv, 1, o, &err)) {
        fprintf(stderr, "embree_ref: %s\n", err.msg);
        return CLI_EXIT_USAGE;
    }
    if (o->help) {
        printf("usage: embree_ref --obj SCENE.obj --rays F.rays [options]\n"
               "Traces a ray file with Embree %s on the project's triangles (FORMATS.md ids).\n\n",
               RTC_VERSION_STRING);
        cli_help(stdout, ref_options, OPTION_COUNT);
        cli_help_exit_codes(stdout);
        exit(CLI_EXIT_OK);
    }
    *layout = LAYOUT_SINGLE;
    if (!strcmp(o->mode, "occluded")) o->occluded = 1;
    else if (!strcmp(o->mode, "packet16")) *layout = LAYOUT_PACKET16;
    else if (!strcmp(o->mode, "stream")) *layout = LAYOUT_STREAM;
    else if (strcmp(o->mode, "single")) {
        fprintf(stderr, "embree_ref: --mode %s: expected single, occluded, packet16 or stream\n", o->mode);
        return CLI_EXIT_USAGE;
    }
    if (strcmp(o->quality, "low") && strcmp(o->quality, "medium") && strcmp(o->quality, "high")) {
        fprintf(stderr, "embree_ref: --quality %s: expected low, medium or high\n", o->quality);
        return CLI_EXIT_USAGE;
    }
    if (!o->obj || !o->rays) {
        fprintf(stderr, "embree_ref: --obj and --rays are needed (see --help)\n");
        return CLI_EXIT_USAGE;
    }
    if (o->hits && cli_check_output("--hits", o->hits, "hits", &err)) {
        fprintf(stderr, "embree_ref: %s\n", err.msg);
        return CLI_EXIT_USAGE;
    }
    return 0;
}

/* --builds timed builds (each a fresh scene; the last is kept): their median
 * milliseconds, and the bytes Embree allocated for the kept one. */
static RTCScene build(RTCDevice dev, const ref_mesh *m, int builds, double *ms, long long *bytes)
{
    double t[100];
    RTCScene sc = NULL;
    for (int b = 0; b < builds; b++) {
        if (sc) rtcReleaseScene(sc);
        long long before = mem_now;
        double t0 = accel_now_ms();
        sc = make_scene(dev, m, NULL, NULL);
        t[b] = accel_now_ms() - t0;
        *bytes = mem_now - before;
    }
    *ms = vs_median(t, builds);
    return sc;
}

/* A warm-up pass, then --passes timed ones: median, min and max Mrays/s. */
static void time_passes(const job *proto, size_t n, const options *o, double mr[3])
{
    double ms[1000];
    trace_pass(proto, n, o->threads);
    for (int p = 0; p < o->passes; p++) ms[p] = trace_pass(proto, n, o->threads);
    double med = vs_median(ms, o->passes);
    mr[0] = n / (med * 1e3), mr[1] = n / (ms[o->passes - 1] * 1e3), mr[2] = n / (ms[0] * 1e3);
}

/* --check: Embree's answers against the project's oracle on the rays as the
 * file gives them, by FORMATS.md's closest-hit or any-hit rule (the lines
 * `trace compare` prints). */
static void check_answers(const ref_mesh *m, const accel_ray *rays, const accel_hit *hits, size_t n,
                          int occluded, int threads)
{
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref);
    if (!ref) {
        fprintf(stderr, "embree_ref: out of memory for the oracle's answers\n");
        return;
    }
    accel_reference_trace(&m->scene, rays, ref, n, threads);
    if (occluded) {
        hits_anyhit_diff d = hits_compare_anyhit(&m->scene, rays, ref, hits, n);
        printf("check vs oracle, any-hit rule: rays %zu  agree %zu  leaks %zu  false_occlusions "
               "%zu  false_hits %zu\n", d.rays, d.agree, d.leaks, d.false_occlusions, d.false_hits);
    } else {
        hits_diff d = hits_compare(&m->scene, rays, ref, hits, n);
        printf("check vs oracle: rays %zu  agree %zu (%zu verified ties)  holes %zu  false_hits "
               "%zu  disagreements %zu\n", d.rays, d.agree, d.ties, d.holes, d.false_hits,
               d.disagreements);
    }
    free(ref);
}

/* The device of the options (threads, max_isa), reporting errors and
 * counting memory; the ISA it runs into isa. */
static RTCDevice make_device(const options *o, char *isa, size_t size)
{
    char config[128];
    snprintf(config, sizeof config, "threads=%d%s%s", o->build_threads, o->isa ? ",max_isa=" : "",
             o->isa ? o->isa : "");
    probe_isa(config, isa, size);
    RTCDevice dev = rtcNewDevice(config);
    if (!dev) {
        fprintf(stderr, "embree_ref: rtcNewDevice(\"%s\") failed (error %d)\n", config,
                (int)rtcGetDeviceError(NULL));
        return NULL;
    }
    rtcSetDeviceErrorFunction(dev, on_error, NULL);
    rtcSetDeviceMemoryMonitorFunction(dev, on_memory, NULL);
    return dev;
}

/* --vs (embree_ref/vs.h): one of Embree's passes. */
typedef struct {
    const job *proto;
    size_t n;
    int threads;
} vs_ctx;

static double vs_embree_pass(void *p)
{
    const vs_ctx *c = p;
    return trace_pass(c->proto, c->n, c->threads);
}

/* Builds, traces, prints the measurement line; the answers into hits. */
static int measure(const options *o, int layout, const ref_mesh *m, accel_ray *rays, size_t n,
                   accel_hit *hits, uint8_t *occ, const accel_ray *ours_rays)
{
    char isa[32];
    RTCDevice dev = make_device(o, isa, sizeof isa);
    if (!dev) return CLI_EXIT_INTERNAL;
    double build_ms, mr[3];
    long long bytes = 0;
    RTCScene sc = build(dev, m, o->builds, &build_ms, &bytes);
    long long peak = mem_peak; /* of the builds, before the recording scene */
    job proto = {sc, rays, 0, n, layout, o->occluded, o->coherent, hits, occ};
    time_passes(&proto, n, o, mr);
    vs_ctx vc = {&proto, n, o->threads};
    int vs_rc = o->vs ? vs_time(o->vs, &m->scene, ours_rays, n, o->threads, o->occluded, o->passes,
                                vs_embree_pass, &vc) : 0;
    size_t lost = o->occluded ? anyhit_answers(dev, m, sc, rays, occ, n, hits) : 0;
    size_t hit_count = 0;
    for (size_t i = 0; i < n; i++) hit_count += hits[i].prim != ACCEL_MISS;
    printf("embree mode=%s%s rays=%zu hits=%zu mrays=%.3f min=%.3f max=%.3f passes=%d "
           "build_ms=%.2f builds=%d quality=%s build_threads=%d threads=%d bytes=%lld "
           "peak_bytes=%lld isa=%s version=%s\n",
           o->mode, o->occluded && strcmp(o->mode, "occluded") ? "+occluded" : "", n, hit_count,
           mr[0], mr[1], mr[2], o->passes, build_ms, o->builds, o->quality, o->build_threads,
           o->threads, bytes, peak, isa, RTC_VERSION_STRING);
    fflush(stdout);
    if (lost)
        fprintf(stderr, "embree_ref: %zu occluded rays without a triangle to record (written as "
                "misses)\n", lost);
    rtcReleaseScene(sc);
    rtcReleaseDevice(dev);
    return vs_rc;
}

int main(int argc, char **argv)
{
    options o;
    int layout, rc = parse(argc, argv, &o, &layout);
    if (rc) return rc;
    ref_mesh m;
    if ((rc = load_mesh(o.obj, o.quality, &m))) return rc;
    rays_set rs, orig = {0};
    accel_error err;
    if (rays_read(o.rays, &rs, &err) || ((o.check || o.vs) && rays_read(o.rays, &orig, &err))) {
        fprintf(stderr, "embree_ref: %s\n", err.msg);
        return CLI_EXIT_INPUT;
    }
    size_t n = rs.count, changed = prepare_rays(rs.rays, n);
    if (changed)
        fprintf(stderr, "embree_ref: %zu rays invalid by FORMATS.md (traced as misses) or with "
                "tnear < 0 (started at 0)\n", changed);
    accel_hit *hits = calloc(n ? n : 1, sizeof *hits);
    uint8_t *occ = calloc(n ? n : 1, 1);
    if (!hits || !occ) {
        fprintf(stderr, "embree_ref: out of memory\n");
        return CLI_EXIT_INTERNAL;
    }
    rc = measure(&o, layout, &m, rs.rays, n, hits, occ, orig.rays);
    if (!rc && o.check) check_answers(&m, orig.rays, hits, n, o.occluded, o.threads);
    if (!rc && o.hits && hits_write(o.hits, hits, n, &err)) {
        fprintf(stderr, "embree_ref: %s\n", err.msg);
        rc = CLI_EXIT_INPUT;
    }
    free(hits), free(occ), free(m.verts), free(m.index);
    scene_free(&m.scene);
    rays_free(&rs), rays_free(&orig);
    return rc;
}
