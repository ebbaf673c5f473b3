/*
 * test_stiff.c - the stiff cases make what they claim, and exp_stability
 * counts a leak when there is one.
 *
 * Checked against the exact reference: the leak rays of the closed and
 * contact cases aim at a vertex or edge midpoint of the mesh they start in
 * and reach it (at t = 1, on a triangle that holds the point: a ray that
 * ends exactly on a shared edge hits a triangle of that edge); their shadow
 * rays are occluded; the scaled cases have the rays they promise, none
 * repeated; the reference on the moved copy of a far scene is bitwise the
 * plain one. Then exp_stability --quick with a planted broken offset must
 * report leaks of the "robust" rule, and without it none; and its
 * certification must cover every configuration it lists (the packet,
 * stream and wide modes by name), or say why not.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rays/stiff.h"
#include "support.h"

/* Is p on triangle t (closed), up to a relative 1e-6, in double? */
static int on_triangle(const float *t, const double p[3])
{
    double e1[3], e2[3], w[3], n[3];
    for (int i = 0; i < 3; i++) e1[i] = (double)t[3 + i] - t[i], e2[i] = (double)t[6 + i] - t[i];
    for (int i = 0; i < 3; i++) w[i] = p[i] - t[i];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2], d11 = 0, d12 = 0, d22 = 0, w1 = 0, w2 = 0;
    double size = sqrt(fmax(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2], e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]));
    double off = (w[0] * n[0] + w[1] * n[1] + w[2] * n[2]) / sqrt(nn);
    if (fabs(off) > 1e-6 * size) return 0;
    for (int i = 0; i < 3; i++) {
        d11 += e1[i] * e1[i], d12 += e1[i] * e2[i], d22 += e2[i] * e2[i];
        w1 += w[i] * e1[i], w2 += w[i] * e2[i];
    }
    double det = d11 * d22 - d12 * d12, u = (w1 * d22 - w2 * d12) / det, v = (w2 * d11 - w1 * d12) / det;
    return u >= -1e-6 && v >= -1e-6 && u + v <= 1 + 1e-6;
}

static void check_leak_rays(const char *name, int exact_t)
{
    int ci = stiff_case_index(name);
    stiff_case c;
    CHECKF(ci >= 0, "no stiff case %s", name);
    if (ci < 0 || !test_stiff_case(ci, &c)) return;
    size_t n = c.rays.count, nl = n - c.leak_begin, on_edge = 0, bad = 0;
    CHECKF(nl >= 400 && c.shadow.count == nl, "%s: %zu leak rays, %zu shadow rays", name, nl,
           c.shadow.count);
    accel_hit *ref = test_oracle_hits(&c.scene, c.rays.rays, n, TEST_ORACLE_REFERENCE);
    accel_hit *sh = test_oracle_hits(&c.scene, c.shadow.rays, c.shadow.count, TEST_ORACLE_REFERENCE);
    for (size_t i = c.leak_begin; ref && sh && i < n; i++) {
        const accel_ray *r = &c.rays.rays[i];
        const accel_hit *h = &ref[i];
        int ok = h->prim != ACCEL_MISS && h->prim < c.scene.tri_count &&
                 (exact_t ? fabsf(h->t - 1.0f) <= 1e-5f : h->t <= 1.0f + 1e-5f);
        /* the target: o + d, in double (d was made as target - o) */
        double p[3] = {(double)r->ox + r->dx, (double)r->oy + r->dy, (double)r->oz + r->dz};
        if (ok && exact_t) {
            ok = on_triangle(c.scene.tris + 9 * (size_t)h->prim, p);
            on_edge += ((i - c.leak_begin) & 1) != 0;
        }
        ok = ok && sh[i - c.leak_begin].prim != ACCEL_MISS;
        if (!ok && bad++ < 3)
            test_fail(__FILE__, __LINE__, "%s: leak ray %zu: prim %u at t %.9g (shadow prim %u)",
                      name, i, h->prim, (double)h->t, sh[i - c.leak_begin].prim);
    }
    CHECKF(!exact_t || on_edge >= nl / 3, "%s: %zu edge rays checked", name, on_edge);
    free(ref);
    free(sh);
    stiff_case_free(&c);
}

TEST(stiff_leak_rays_reach_their_targets)
{
    check_leak_rays("cube_edges", 1);
    check_leak_rays("cube_far_1e6x", 1);
    check_leak_rays("cubes_touching", 1);
    check_leak_rays("spheres_touching", 1);
    check_leak_rays("cubes_interpenetrating", 0);
    check_leak_rays("spheres_interpenetrating", 0);
}

static int ray_cmp(const void *a, const void *b) { return memcmp(a, b, sizeof(accel_ray)); }

TEST(stiff_scaled_cases_have_distinct_rays)
{
    static const char *const names[] = {"cube_edges", "cube_lattice", "cubes_touching", "flat"};
    for (int k = 0; k < 4; k++) {
        stiff_case base, big;
        accel_error err = {0};
        int ci = stiff_case_index(names[k]);
        if (!test_stiff_case(ci, &base)) continue;
        CHECKF(stiff_case_make_n(ci, 30000, &big, &err) == 0, "%s: %s", names[k], err.msg);
        CHECKF(big.rays.count >= 30000 && big.rays.count < 200000, "%s: %zu rays", names[k],
               big.rays.count);
        CHECKF(big.scene.tri_count == base.scene.tri_count &&
               !memcmp(big.scene.tris, base.scene.tris, 9 * sizeof(float) * base.scene.tri_count),
               "%s: another scene", names[k]);
        CHECKF((big.leak_begin < big.rays.count) == (base.leak_begin < base.rays.count) &&
               big.shadow.count == big.rays.count - big.leak_begin, "%s: leak rays", names[k]);
        accel_ray *r = malloc(big.rays.count * sizeof *r);
        if (r) {
            memcpy(r, big.rays.rays, big.rays.count * sizeof *r);
            qsort(r, big.rays.count, sizeof *r, ray_cmp);
            size_t rep = 0;
            for (size_t i = 1; i < big.rays.count; i++) rep += !memcmp(&r[i - 1], &r[i], sizeof *r);
            CHECKF(rep == 0, "%s: %zu repeated rays of %zu", names[k], rep, big.rays.count);
            free(r);
        }
        stiff_case_free(&big);
        stiff_case_free(&base);
    }
}

TEST(stiff_reference_far_is_bitwise_plain)
{
    static const char *const names[] = {"sphere_far_1e6", "cube_far_1e6x", "sphere_far_1e5x"};
    for (int k = 0; k < 3; k++) {
        stiff_case c;
        if (!test_stiff_case(stiff_case_index(names[k]), &c)) continue;
        size_t n = c.rays.count;
        accel_hit *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
        if (a && b) {
            stiff_reference(&c.scene, c.rays.rays, a, n, 2);
            accel_reference_trace(&c.scene, c.rays.rays, b, n, 2);
            CHECKF(!memcmp(a, b, n * sizeof *a), "%s: the moved reference differs", names[k]);
        }
        free(a), free(b);
        stiff_case_free(&c);
    }
}

/* The fields of the CSV line [line, end) into f (RFC 4180 quotes, no ""
 * inside; at most 16 fields, each cut at 127 characters); their count. */
static int csv_split(const char *line, const char *end, char f[16][128])
{
    int nf = 0, quoted = 0;
    size_t len = 0;
    for (const char *q = line; q < end && nf < 16; q++) {
        if (*q == '"') quoted = !quoted;
        else if (*q == ',' && !quoted) f[nf][len] = 0, nf++, len = 0;
        else if (len < 127) f[nf][len++] = *q;
    }
    if (nf < 16) f[nf][len] = 0, nf++;
    return nf;
}

/* Sum of column `col` over the CSV rows whose first field is `part` and
 * third contains `spec`. */
static long csv_sum(const char *text, const char *part, const char *spec, int col, int *rows)
{
    long sum = 0;
    *rows = 0;
    for (const char *line = text; line && *line;) {
        const char *end = strchr(line, '\n');
        char f[16][128];
        int nf = csv_split(line, end ? end : line + strlen(line), f);
        if (nf > col && !strcmp(f[0], part) && strstr(f[2], spec)) sum += atol(f[col]), ++*rows;
        line = end ? end + 1 : NULL;
    }
    return sum;
}

/* The certification row of `spec` on case `name` (part "cert"): 1 and its
 * rays and note, or 0 when there is none. */
static int cert_row(const char *text, const char *name, const char *spec, long *rays, char *note,
                    size_t n)
{
    for (const char *line = text; line && *line;) {
        const char *end = strchr(line, '\n');
        char f[16][128];
        int nf = csv_split(line, end ? end : line + strlen(line), f);
        if (nf >= 15 && !strcmp(f[0], "cert") && !strcmp(f[1], name) && !strcmp(f[2], spec)) {
            *rays = atol(f[3]);
            snprintf(note, n, "%s", f[14]);
            return 1;
        }
        line = end ? end + 1 : NULL;
    }
    return 0;
}

/* exp_stability --quick certifies, on each of its three cases, every
 * configuration it lists: every watertight one of its base-ray table (its
 * "stiff" rows) but brute force, every kind, and every packet and stream
 * mode and wide kernel by name (they once went uncertified as "the same
 * structure" as their kinds). Each has a row with the quick budget's rays,
 * or (not the packet, stream and wide ones) no rays and its reason. */
static void check_every_listed_configuration_certified(const char *text)
{
    static const char *const must[] = {
        "bvh:traverse=packet", "bvh:traverse=packet,frustum=1", "bvh:width=4", "bvh:width=8",
        "bvh:width=4,traverse=packet", "bvh:width=8,traverse=packet", "bvh:width=4,traverse=stream",
        "bvh:width=8,traverse=stream", "grid:traverse=packet", "nested_grid:traverse=packet",
        "instanced:traverse=packet"};
    const int nm = (int)(sizeof must / sizeof must[0]);
    for (int ci = 0; ci < 3; ci++) {
        stiff_case c;
        if (!test_stiff_case(ci, &c)) continue;
        char listed[96][128];
        int nl = 0;
        for (int i = 0; i < nm; i++) snprintf(listed[nl++], sizeof listed[0], "%s", must[i]);
        for (size_t k = 0; k < accel_kind_count; k++)
            if (strcmp(accel_kinds[k]->name, "brute"))
                snprintf(listed[nl++], sizeof listed[0], "%s", accel_kinds[k]->name);
        for (const char *line = text; line && *line && nl < 96;) {
            const char *end = strchr(line, '\n');
            char f[16][128];
            int nf = csv_split(line, end ? end : line + strlen(line), f), dup = 0;
            for (int i = 0; i < nl; i++) dup |= !strcmp(listed[i], f[2]);
            if (nf >= 3 && !strcmp(f[0], "stiff") && !strcmp(f[1], c.name) && !dup &&
                strncmp(f[2], "brute", 5) && !strstr(f[2], "tri=naive"))
                snprintf(listed[nl++], sizeof listed[0], "%s", f[2]);
            line = end ? end + 1 : NULL;
        }
        CHECKF(nl >= nm + 5, "%s: only %d configurations listed", c.name, nl);
        for (int i = 0; i < nl; i++) {
            long rays = 0;
            char note[128] = "";
            int row = cert_row(text, c.name, listed[i], &rays, note, sizeof note);
            CHECKF(row, "%s: `%s` silently not certified (no certification row)", c.name, listed[i]);
            if (!row || rays >= 20000) continue;
            CHECKF(i >= nm, "%s: `%s` (a packet, stream or wide mode) certified on %ld rays, not "
                   "20000", c.name, listed[i], rays);
            CHECKF(!strncmp(note, "not certified: ", 15) && strlen(note) > 20,
                   "%s: `%s` on %ld rays without a reason ('%s')", c.name, listed[i], rays, note);
        }
        stiff_case_free(&c);
    }
}

TEST(stiff_exp_stability_counts_a_planted_leak)
{
    char dir[256], cmd[600], path[300];
    if (!test_temp_dir("stiff", dir, sizeof dir)) return;
    for (int plant = 0; plant < 2; plant++) {
        snprintf(cmd, sizeof cmd, "GRIDBVH_STABILITY_PLANT=%d bin/exp_stability --quick --quiet "
                 "--out %s/out%d", plant, dir, plant);
        CHECKF(test_run(dir, cmd, NULL, NULL) == 0, "%s failed", cmd);
        snprintf(path, sizeof path, "%s/out%d/exp_stability.csv", dir, plant);
        char *text = test_read_file(path, NULL);
        CHECKF(text != NULL, "%s not written", path);
        if (!text) continue;
        int rows = 0, crow = 0;
        /* columns: part,case,spec,rays,leak_rays,shadow_rays,holes,false_hits,
         * disagreements,leaks,shadow_leaks,self_hits,... */
        long leaks = csv_sum(text, "offset", "robust", 9, &rows);
        long sleaks = csv_sum(text, "offset", "robust", 10, &rows);
        long inside = csv_sum(text, "offset", "robust", 4, &rows);
        long cert = csv_sum(text, "cert", "", 9, &crow) + csv_sum(text, "cert", "", 6, &crow);
        CHECKF(rows >= 2 && inside >= 100, "plant %d: %d robust rows, %ld inside rays", plant, rows, inside);
        CHECKF(crow >= 3, "plant %d: %d certification rows", plant, crow);
        CHECKF(cert == 0, "plant %d: the watertight kernels fault %ld times", plant, cert);
        if (plant)
            CHECKF(leaks * 2 > inside && sleaks * 2 > inside, "planted: only %ld and %ld leaks of %ld",
                   leaks, sleaks, inside);
        else
            CHECKF(leaks == 0 && sleaks == 0, "robust offset: %ld and %ld leaks", leaks, sleaks);
        if (!plant) check_every_listed_configuration_certified(text);
        free(text);
    }
    test_remove_dir(dir);
}
