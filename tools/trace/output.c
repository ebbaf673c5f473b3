/*
 * output.c - what bin/trace prints and writes for one ray set traced by one
 * accelerator: the CSV record or the text row, and the outputs of the last
 * accelerator (--dump-hits, one file per set; --image; --heatmap).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench/shade.h"
#include "tools/trace/hitfiles.h"
#include "tools/trace/trace.h"

void print_csv_header(run *r)
{
    csv_row(&r->csv, "csv,kind,spec,scene,rayset,rays,hits,threads,build_ms,build_ms_min,"
            "build_ms_max,bytes,nodes,refs,sah_cost,depth,trace_ms,mrays_median,mrays_min,"
            "mrays_max,steps_per_ray,empty_per_ray,box_per_ray,prims_per_ray,"
            "mailbox_skips_per_ray,holes,false_hits,disagreements\n");
}

void print_row(const options *o, run *r, const accel_kind *kind, const accel_params *canon,
               const accel_build_stats *st, const accel_timing *bt, const set_run *t)
{
    const bench_result *br = &t->br;
    const accel_counters *c = &br->counters;
    double nr = t->rays->count ? (double)t->rays->count : 1.0;
    const char *name = r->set_names[t->set];
    if (o->csv) {
        char cnt[256] = ",,,,", chk[96] = ",,";
        if (br->counted)
            snprintf(cnt, sizeof cnt, "%.4f,%.4f,%.4f,%.4f,%.4f", c->steps / nr,
                     c->empty_steps / nr, c->box_tests / nr, c->prim_tests / nr,
                     c->mailbox_skips / nr);
        if (t->checked)
            snprintf(chk, sizeof chk, "%zu,%zu,%zu", t->diff.holes, t->diff.false_hits,
                     t->diff.disagreements);
        /* cnt and chk are whole runs of numeric fields: spliced into the format. */
        char fmt[512];
        snprintf(fmt, sizeof fmt, "csv,%%s,%%s,%%s,%%s,%%zu,%%zu,%%d,%%.4f,%%.4f,%%.4f,%%zu,%%llu,"
                 "%%llu,%%.6g,%%d,%%.4f,%%.4f,%%.4f,%%.4f,%s,%s\n", cnt, chk);
        if (csv_row(&r->csv, fmt, kind->name, canon->spec, r->scene.name, name, t->rays->count,
                    br->hits, o->threads, bt->median, bt->min, bt->max, st->bytes,
                    (unsigned long long)st->nodes, (unsigned long long)st->refs, st->sah_cost,
                    st->depth, br->ms.median, br->mrays.median, br->mrays.min, br->mrays.max))
            report(r, CLI_EXIT_INTERNAL, r->csv.first_bad);
        return;
    }
    printf("  %-8s %9zu rays %9zu %s  %8.3f Mrays/s (min %.3f, max %.3f; %.2f ms)", name,
           t->rays->count, br->hits, t->occl ? "occluded" : "hit", br->mrays.median,
           br->mrays.min, br->mrays.max, br->ms.median);
    if (br->ms.n < o->repeat)
        printf(" [%d of %d timed passes: a pass takes %.1f s, over the %g s budget]", br->ms.n,
               o->repeat, br->ms.median / 1e3, o->budget);
    if (br->counted)
        printf("  per ray: %.2f %s, %.2f empty, %.2f box, %.2f prim, %.2f mailbox skips",
               c->steps / nr, kind->step_name, c->empty_steps / nr, c->box_tests / nr,
               c->prim_tests / nr, c->mailbox_skips / nr);
    printf("\n");
    if (t->checked)
        printf("    check vs reference: %zu holes, %zu false hits, %zu disagreements\n",
               t->diff.holes, t->diff.false_hits, t->diff.disagreements);
}

static int write_heatmap(const options *o, run *r, const set_run *t, const accel_kind *kind,
                         const char *spec, accel_error *err)
{
    const rays_set *rs = t->rays;
    size_t n = rs->count;
    float *v = calloc((size_t)rs->width * rs->height, sizeof *v);
    if (!v) return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for a heatmap");
    const uint32_t *src = !strcmp(o->heatmap[0], "steps") ? t->steps : t->prims;
    for (size_t i = 0; i < n; i++)
        if (rs->pixel[i] < (uint32_t)(rs->width * rs->height)) v[rs->pixel[i]] += src[i];
    char path[1024];
    snprintf(path, sizeof path, r->set_count > 1 ? "%s.%s.png" : "%s", o->heatmap[1],
             r->set_names[t->set]);
    image_rgb img;
    char title[256];
    image_heat_title(title, sizeof title, spec, kind, src == t->prims);
    int rc = image_heatmap(v, rs->width, rs->height, &o->heat_scale, title, &img, err);
    if (rc == 0) {
        rc = image_write(path, &img, err);
        image_free(&img);
    }
    free(v);
    return rc;
}

/* --dump-hits of one set: closest hits, or the any-hit answers of an
 * occlusion set (FORMATS.md), named on the way. */
static void dump_hits(const options *o, run *r, const set_run *t, const accel_kind *kind,
                      const void *accel)
{
    accel_error err = {0};
    const char *name = r->set_names[t->set];
    char path[1024];
    snprintf(path, sizeof path, r->set_count > 1 ? "%s.%s.hits" : "%s", o->dump_hits, name);
    size_t n = t->rays->count, lost = 0;
    if (t->occl) {
        lost = trace_anyhit_answers(kind, accel, &r->scene, t->rays->rays, t->occ, n, o->threads,
                                    t->hits);
        if (lost)
            report(r, CLI_EXIT_INTERNAL, "--dump-hits: some occluded rays hit no triangle in a "
                   "closest-hit query or the reference: written as misses");
    }
    if (hits_write(path, t->hits, n, &err)) {
        report_err(r, &err);
        return;
    }
    FILE *info = trace_info(o);
    if (info)
        fprintf(info, "wrote %s: %zu %s of %s rays%s\n", path, n,
                t->occl ? "any-hit answers" : "closest hits", name,
                t->occl ? " (trace compare --occluded compares them)" : "");
}

/* The outputs of the last accelerator: --dump-hits, --image, --heatmap. */
void write_outputs(const options *o, run *r, const set_run *t, const accel_kind *kind,
                   const void *accel, const char *spec)
{
    accel_error err = {0};
    if (o->dump_hits) dump_hits(o, r, t, kind, accel);
    if (o->image && r->bits[t->set] == BENCH_PRIMARY) {
        image_rgb img;
        if (image_alloc(&img, t->rays->width, t->rays->height, &err) == 0) {
            bench_shade(&r->scene, t->rays, t->hits, &img);
            if (image_write(o->image, &img, &err)) report_err(r, &err);
            image_free(&img);
        } else {
            report_err(r, &err);
        }
    }
    if (t->steps && write_heatmap(o, r, t, kind, spec, &err)) report_err(r, &err);
}
