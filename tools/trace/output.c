/*
 * output.c - what bin/trace prints and writes: its error reports and exit
 * status, and for one ray set traced by one accelerator the CSV record or
 * the text row, and the outputs of the last accelerator (--dump-hits, one
 * file per set; --image; --heatmap).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "image/shade.h"
#include "tools/trace/hitfiles.h"
#include "tools/trace/run.h"

int report(run *r, int code, const char *msg)
{
    fprintf(stderr, "trace: %s\n", msg);
    if (code > r->status) r->status = code;
    return code;
}

int report_err(run *r, const accel_error *err) { return report(r, cli_exit_of(err->code), err->msg); }

FILE *trace_info(const options *o) { return o->csv ? (o->quiet ? NULL : stderr) : stdout; }

void print_csv_header(run *r)
{
    csv_row(&r->csv, "csv,kind,spec,scene,prims,rayset,width,height,rays,hits,threads,build_ms,"
            "build_ms_min,build_ms_max,bytes,nodes,refs,sah_cost,depth,grid_res,trace_ms,"
            "timed_passes,mrays_median,mrays_min,"
            "mrays_max,steps_per_ray,empty_per_ray,box_per_ray,prims_per_ray,"
            "mailbox_skips_per_ray,holes,false_hits,disagreements,isa\n");
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
        /* Fields that do not apply are empty, never nan: the image size of
         * rays from a file, the SAH cost of a grid, the resolution of a tree. */
        char wh[32] = ",", sah[32] = "", res[48] = "";
        if (!r->from_file) snprintf(wh, sizeof wh, "%d,%d", o->size[0], o->size[1]);
        if (isfinite(st->sah_cost) && st->sah_cost != 0) snprintf(sah, sizeof sah, "%.6g", st->sah_cost);
        if (st->res[0]) snprintf(res, sizeof res, "%dx%dx%d", st->res[0], st->res[1], st->res[2]);
        /* cnt and chk are whole runs of numeric fields: spliced into the format. */
        char fmt[512];
        snprintf(fmt, sizeof fmt, "csv,%%s,%%s,%%s,%%u,%%s,%s,%%zu,%%zu,%%d,%%.4f,%%.4f,%%.4f,%%zu,"
                 "%%llu,%%llu,%s,%%d,%s,%%.4f,%%d,%%.4f,%%.4f,%%.4f,%s,%s,%%s\n", wh, sah, res, cnt, chk);
        if (csv_row(&r->csv, fmt, kind->name, canon->spec, r->scene.name, r->scene.live_count, name,
                    t->rays->count, br->hits, o->threads, bt->median, bt->min, bt->max, st->bytes,
                    (unsigned long long)st->nodes, (unsigned long long)st->refs, st->depth,
                    br->ms.median, br->ms.n, br->mrays.median, br->mrays.min, br->mrays.max,
                    st->isa ? st->isa : ""))
            report(r, CLI_EXIT_INTERNAL, r->csv.first_bad);
        return;
    }
    if (r->summary_count < MAX_ACCELS * MAX_SETS) {
        summary_cell *cell = &r->summary[r->summary_count++];
        snprintf(cell->spec, sizeof cell->spec, "%s", canon->spec);
        cell->set = t->set, cell->mrays = br->mrays.median, cell->build_ms = bt->median;
        cell->bytes = st->bytes;
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
        printf("    check vs reference: %zu holes, %zu false hits, %zu disagreements (%zu true "
               "ties verified)\n", t->diff.holes, t->diff.false_hits, t->diff.disagreements,
               t->diff.ties);
}

void print_summary(const options *o, const run *r)
{
    if (o->csv || r->summary_count == 0) return;
    int w = 11;
    for (int i = 0; i < r->summary_count; i++) {
        int len = (int)strlen(r->summary[i].spec);
        if (len > w) w = len;
    }
    printf("\nsummary: Mrays/s (median of the timed passes) per ray set; build ms (median); MiB\n");
    printf("  %-*s", w, "accelerator");
    for (int s = 0; s < r->set_count; s++) printf(" %10s", r->set_names[s]);
    printf(" %10s %9s\n", "build ms", "MiB");
    for (int i = 0; i < r->summary_count;) {
        const summary_cell *first = &r->summary[i];
        printf("  %-*s", w, first->spec);
        int j = i;
        for (int s = 0; s < r->set_count; s++) {
            if (j < r->summary_count && !strcmp(r->summary[j].spec, first->spec) &&
                r->summary[j].set == s)
                printf(" %10.3f", r->summary[j++].mrays);
            else
                printf(" %10s", "-");
        }
        printf(" %10.2f %9.2f\n", first->build_ms, (double)first->bytes / (1024.0 * 1024.0));
        i = j > i ? j : i + 1;
    }
}

void trace_set_path(char *buf, size_t n, const char *base, int several, const char *set,
                    const char *ext, const char *alt)
{
    if (!several) {
        snprintf(buf, n, "%s", base);
        return;
    }
    size_t len = strlen(base);
    const char *kept = ext;
    for (int k = 0; k < 2; k++) {
        const char *e = k ? alt : ext;
        size_t el = e ? strlen(e) : 0;
        if (e && len > el + 1 && base[len - el - 1] == '.' && !strcmp(base + len - el, e) &&
            base[len - el - 2] != '/') {
            len -= el + 1, kept = e;
            break;
        }
    }
    snprintf(buf, n, "%.*s.%s.%s", (int)len, base, set, kept);
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
    trace_set_path(path, sizeof path, o->heatmap[1], r->set_count > 1, r->set_names[t->set], "png",
                   "ppm");
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
    trace_set_path(path, sizeof path, o->dump_hits, r->set_count > 1, name, "hits", NULL);
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
            image_shade(&r->scene, t->rays, t->hits, &img);
            if (image_write(o->image, &img, &err)) report_err(r, &err);
            image_free(&img);
        } else {
            report_err(r, &err);
        }
    }
    if (t->steps && write_heatmap(o, r, t, kind, spec, &err)) report_err(r, &err);
}
