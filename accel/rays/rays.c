/*
 * rays.c - deterministic ray sets, FORMATS.md ray/hit files, comparison.
 *
 * Randomness is a pure function of (seed, ray index, dimension): a
 * SplitMix64 finalizer (Steele, Lea, Flood, OOPSLA 2014) over the mixed
 * inputs, so ray i is the same whichever thread or order generates it.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "rays/rays.h"
#include "scene/scene.h"

void rays_free(rays_set *r)
{
    free(r->rays);
    free(r->pixel);
    memset(r, 0, sizeof *r);
}

static int rays_alloc(rays_set *r, size_t n, int with_pixels, accel_error *err)
{
    memset(r, 0, sizeof *r);
    if (n > SIZE_MAX / sizeof(accel_ray))
        return accel_fail(err, ACCEL_ERR_RANGE, "too many rays (%zu)", n);
    r->rays = malloc((n ? n : 1) * sizeof *r->rays);
    r->pixel = with_pixels ? malloc((n ? n : 1) * sizeof *r->pixel) : NULL;
    if (!r->rays || (with_pixels && !r->pixel)) {
        rays_free(r);
        return accel_fail(err, ACCEL_ERR_NOMEM, "out of memory for %zu rays", n);
    }
    r->count = n;
    return 0;
}

static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

float rays_rand(uint64_t seed, uint64_t index, uint32_t dim)
{
    uint64_t h = mix64(seed * 0x9e3779b97f4a7c15ull + index);
    h = mix64(h ^ ((uint64_t)dim * 0xd1b54a32d192ed03ull));
    return (float)(h >> 40) * 0x1p-24f; /* 24 random bits: exactly representable, < 1 */
}

int rays_camera_check(const accel_camera *cam, accel_error *err)
{
    return scene_camera_check(cam, err);
}

int rays_primary(const accel_camera *cam, int width, int height, rays_set *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    int crc = rays_camera_check(cam, err);
    if (crc) return crc;
    if (width < 1 || height < 1 || width > 65536 || height > 65536)
        return accel_fail(err, ACCEL_ERR_RANGE, "image size %dx%d out of range 1..65536", width,
                          height);
    int rc = rays_alloc(out, (size_t)width * height, 1, err);
    if (rc) return rc;
    out->width = width;
    out->height = height;
    vec3 fwd = v3_norm(v3_sub(cam->look_at, cam->eye));
    vec3 right = v3_norm(v3_cross(fwd, cam->up));
    vec3 up = v3_cross(right, fwd);
    float th = tanf(0.5f * cam->fov_deg * 3.14159265358979f / 180.0f);
    float aspect = (float)width / (float)height;
    size_t i = 0;
    /* 8x8 tiles, row-major within and between tiles: a tile is a packet. */
    for (int ty = 0; ty < height; ty += 8)
        for (int tx = 0; tx < width; tx += 8)
            for (int y = ty; y < ty + 8 && y < height; y++)
                for (int x = tx; x < tx + 8 && x < width; x++) {
                    float sx = (2.0f * ((float)x + 0.5f) / (float)width - 1.0f) * aspect * th;
                    float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)height) * th;
                    vec3 d = v3_norm(v3_add(fwd, v3_add(v3_scale(right, sx), v3_scale(up, sy))));
                    accel_ray r = {cam->eye.x, cam->eye.y, cam->eye.z, 0.0f,
                                   d.x,        d.y,        d.z,        INFINITY};
                    out->rays[i] = r;
                    out->pixel[i] = (uint32_t)y * (uint32_t)width + (uint32_t)x;
                    i++;
                }
    return 0;
}

int rays_hit_frame(const accel_scene *s, const accel_ray *r, const accel_hit *h, vec3 *point,
                   vec3 *normal)
{
    if (h->prim == ACCEL_MISS || h->prim >= s->prim_count) return 0;
    vec3 d = v3(r->dx, r->dy, r->dz);
    vec3 p, n;
    if (h->prim < s->tri_count) {
        const float *t = s->tris + 9 * (size_t)h->prim;
        vec3 a = v3_load(t), b = v3_load(t + 3), c = v3_load(t + 6);
        /* The barycentric point lies on the triangle up to rounding, unlike o + t*d. */
        float w = 1.0f - h->u - h->v;
        p = v3_add(v3_scale(a, w), v3_add(v3_scale(b, h->u), v3_scale(c, h->v)));
        n = v3_norm(v3_cross(v3_sub(b, a), v3_sub(c, a)));
    } else {
        const float *sp = s->spheres + 4 * (size_t)(h->prim - s->tri_count);
        vec3 c = v3_load(sp);
        vec3 q = v3_add(v3(r->ox, r->oy, r->oz), v3_scale(d, h->t));
        n = v3_norm(v3_sub(q, c));
        p = v3_add(c, v3_scale(n, sp[3]));
    }
    if (v3_dot(n, d) > 0.0f) n = v3_scale(n, -1.0f);
    *point = p;
    *normal = n;
    return 1;
}

/* Waechter & Binder 2019 (Ray Tracing Gems ch. 6): move p along n by a few
 * hundred ULPs (integer arithmetic on the float bits) away from the origin
 * of coordinates, and by a fixed small amount near it where ULPs are tiny. */
static float offset_component(float p, float n)
{
    const float origin = 1.0f / 32.0f, float_scale = 1.0f / 65536.0f, int_scale = 256.0f;
    if (fabsf(p) < origin) return p + float_scale * n;
    int32_t of = (int32_t)(int_scale * n);
    int32_t bits;
    memcpy(&bits, &p, sizeof bits);
    bits += p < 0.0f ? -of : of;
    float q;
    memcpy(&q, &bits, sizeof q);
    return q;
}

vec3 rays_offset_origin(vec3 p, vec3 n)
{
    return v3(offset_component(p.x, n.x), offset_component(p.y, n.y), offset_component(p.z, n.z));
}

/* Orthonormal basis around unit n (Duff et al., "Building an Orthonormal
 * Basis, Revisited", JCGT 6(1), 2017). */
static void onb(vec3 n, vec3 *t, vec3 *b)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float bb = n.x * n.y * a;
    *t = v3(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
    *b = v3(bb, sign + n.y * n.y * a, -n.y);
}

static vec3 cosine_dir(vec3 n, float r1, float r2)
{
    vec3 t, b;
    onb(n, &t, &b);
    float phi = 2.0f * 3.14159265358979f * r1;
    float rr = sqrtf(r2);
    float z = sqrtf(fmaxf(0.0f, 1.0f - r2));
    return v3_norm(v3_add(v3_scale(n, z),
                          v3_add(v3_scale(t, rr * cosf(phi)), v3_scale(b, rr * sinf(phi)))));
}

static size_t count_hits(const accel_hit *hits, size_t n)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++) k += hits[i].prim != ACCEL_MISS;
    return k;
}

/* Shared walk over primary hits: `per_hit` rays each, made by make(). */
typedef int (*make_fn)(const accel_scene *s, vec3 p, vec3 n, uint64_t seed, uint64_t index,
                       float param, accel_ray *out);

static int secondary(const accel_scene *s, const rays_set *prim, const accel_hit *hits,
                     int per_hit, make_fn make, uint64_t seed, float param, rays_set *out,
                     accel_error *err)
{
    size_t n = count_hits(hits, prim->count);
    if (per_hit < 1 || n > SIZE_MAX / (size_t)per_hit / sizeof(accel_ray))
        return accel_fail(err, ACCEL_ERR_RANGE, "too many secondary rays");
    int rc = rays_alloc(out, n * (size_t)per_hit, prim->pixel != NULL, err);
    if (rc) return rc;
    out->width = prim->width;
    out->height = prim->height;
    size_t k = 0;
    for (size_t i = 0; i < prim->count; i++) {
        vec3 p, nn;
        if (!rays_hit_frame(s, &prim->rays[i], &hits[i], &p, &nn)) continue;
        for (int j = 0; j < per_hit; j++) {
            if (!make(s, p, nn, seed, (uint64_t)i * (uint64_t)per_hit + (uint64_t)j, param,
                      &out->rays[k]))
                continue;
            if (out->pixel) out->pixel[k] = prim->pixel ? prim->pixel[i] : (uint32_t)i;
            k++;
        }
    }
    out->count = k;
    return 0;
}

static int make_shadow(const accel_scene *s, vec3 p, vec3 n, uint64_t seed, uint64_t index,
                       float param, accel_ray *out)
{
    (void)seed, (void)index, (void)param;
    vec3 to_light = v3_sub(s->light, p);
    if (v3_dot(to_light, n) <= 0.0f) return 0; /* facing away: a renderer casts no ray */
    vec3 o = rays_offset_origin(p, n);
    vec3 d = v3_sub(s->light, o);
    accel_ray r = {o.x, o.y, o.z, 0.0f, d.x, d.y, d.z, 1.0f - 0x1p-12f};
    *out = r;
    return 1;
}

static int make_diffuse(const accel_scene *s, vec3 p, vec3 n, uint64_t seed, uint64_t index,
                        float t_far, accel_ray *out)
{
    (void)s;
    vec3 o = rays_offset_origin(p, n);
    vec3 d = cosine_dir(n, rays_rand(seed, index, 0), rays_rand(seed, index, 1));
    accel_ray r = {o.x, o.y, o.z, 0.0f, d.x, d.y, d.z, t_far};
    *out = r;
    return 1;
}

int rays_shadow(const accel_scene *s, const rays_set *prim, const accel_hit *hits, rays_set *out,
                accel_error *err)
{
    return secondary(s, prim, hits, 1, make_shadow, 0, 0.0f, out, err);
}

int rays_diffuse(const accel_scene *s, const rays_set *prim, const accel_hit *hits, uint64_t seed,
                 rays_set *out, accel_error *err)
{
    return secondary(s, prim, hits, 1, make_diffuse, seed, INFINITY, out, err);
}

int rays_ao(const accel_scene *s, const rays_set *prim, const accel_hit *hits, int samples,
            float ao_radius, uint64_t seed, rays_set *out, accel_error *err)
{
    if (samples < 1 || samples > 4096)
        return accel_fail(err, ACCEL_ERR_RANGE, "ao samples %d out of range 1..4096", samples);
    if (!(ao_radius > 0.0f))
        return accel_fail(err, ACCEL_ERR_RANGE, "ao radius must be positive");
    return secondary(s, prim, hits, samples, make_diffuse, seed ^ 0xa0a0a0a0ull, ao_radius, out,
                     err);
}

int rays_ending_at_hit(const rays_set *prim, const accel_hit *hits, rays_set *out,
                       accel_error *err)
{
    memset(out, 0, sizeof *out);
    size_t n = 0;
    for (size_t i = 0; i < prim->count; i++) n += hits[i].prim != ACCEL_MISS;
    out->rays = malloc((n ? n : 1) * sizeof *out->rays);
    if (!out->rays) return accel_fail(err, ACCEL_ERR_NOMEM, "rays: out of memory for %zu rays", n);
    for (size_t i = 0; i < prim->count; i++) {
        if (hits[i].prim == ACCEL_MISS) continue;
        out->rays[out->count] = prim->rays[i];
        out->rays[out->count++].t_far = hits[i].t;
    }
    return 0;
}

/* ---- files ---------------------------------------------------------------- */

static int write_file(const char *path, const char magic[4], const void *data, size_t elem,
                      size_t count, accel_error *err)
{
    FILE *f = fopen(path, "wb");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open for writing: %s", path,
                              strerror(errno));
    unsigned char head[16];
    uint32_t version = 1;
    uint64_t n = count;
    memcpy(head, magic, 4);
    for (int i = 0; i < 4; i++) head[4 + i] = (unsigned char)(version >> (8 * i));
    for (int i = 0; i < 8; i++) head[8 + i] = (unsigned char)(n >> (8 * i));
    /* Records are written as they lie in memory: the project requires a
     * little-endian host (checked in rays_read / hits_read as well). */
    int ok = fwrite(head, 1, 16, f) == 16 && fwrite(data, elem, count, f) == count;
    if (fclose(f) != 0) ok = 0;
    if (!ok) return accel_fail(err, ACCEL_ERR_IO, "%s: write failed", path);
    return 0;
}

static int read_file(const char *path, const char magic[4], size_t elem, void **data,
                     size_t *count, accel_error *err)
{
    *data = NULL;
    *count = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fileno(f), &st) == 0 && !S_ISREG(st.st_mode)) { /* sizes below need a file */
        fclose(f);
        return accel_fail(err, ACCEL_ERR_IO, "%s: not a regular file (a %s)", path,
                          S_ISDIR(st.st_mode) ? "directory" : S_ISFIFO(st.st_mode) ? "pipe" : "device");
    }
    unsigned char head[16];
    if (fread(head, 1, 16, f) != 16) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_PARSE, "%s: byte 0: truncated header (16 bytes expected)",
                          path);
    }
    if (memcmp(head, magic, 4) != 0) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_PARSE, "%s: byte 0: bad magic (expected '%.4s')", path,
                          magic);
    }
    uint32_t version = 0;
    uint64_t n = 0;
    for (int i = 0; i < 4; i++) version |= (uint32_t)head[4 + i] << (8 * i);
    for (int i = 0; i < 8; i++) n |= (uint64_t)head[8 + i] << (8 * i);
    if (version != 1) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_PARSE, "%s: byte 4: unsupported version %u (expected 1)",
                          path, version);
    }
    /* The count must match the bytes present before anything is allocated. */
    if (fseek(f, 0, SEEK_END) != 0) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_IO, "%s: cannot seek", path);
    }
    long size = ftell(f);
    uint64_t body = size > 16 ? (uint64_t)size - 16 : 0;
    if (n > body / elem || body != n * elem) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_PARSE,
                          "%s: byte 8: record count %llu does not match the file size (%ld bytes "
                          "= %llu records of %zu bytes)",
                          path, (unsigned long long)n, size, (unsigned long long)(body / elem),
                          elem);
    }
    void *buf = malloc(n ? (size_t)n * elem : 1);
    if (!buf) {
        fclose(f);
        return accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory for %llu records", path,
                          (unsigned long long)n);
    }
    if (fseek(f, 16, SEEK_SET) != 0 || fread(buf, elem, (size_t)n, f) != (size_t)n) {
        free(buf);
        fclose(f);
        return accel_fail(err, ACCEL_ERR_IO, "%s: read failed", path);
    }
    fclose(f);
    *data = buf;
    *count = (size_t)n;
    return 0;
}

int rays_write(const char *path, const accel_ray *rays, size_t count, accel_error *err)
{
    return write_file(path, "RAYS", rays, sizeof *rays, count, err);
}

int rays_read(const char *path, rays_set *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    void *data;
    int rc = read_file(path, "RAYS", sizeof(accel_ray), &data, &out->count, err);
    out->rays = data;
    return rc;
}

/* The fault of a ray that can hit nothing, or NULL for a traceable one. */
static const char *ray_fault(const accel_ray *r)
{
    float o[3] = {r->ox, r->oy, r->oz}, d[3] = {r->dx, r->dy, r->dz};
    for (int k = 0; k < 3; k++)
        if (!isfinite(o[k])) return "a NaN or infinite origin";
    for (int k = 0; k < 3; k++)
        if (!isfinite(d[k])) return "a NaN or infinite direction";
    if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) return "a zero direction";
    if (isnan(r->t_near) || isnan(r->t_far)) return "a NaN tnear or tfar";
    if (r->t_near > r->t_far) return "tnear > tfar";
    return NULL;
}

size_t rays_invalid_count(const accel_ray *rays, size_t count, size_t *first, const char **why)
{
    size_t n = 0;
    *first = SIZE_MAX;
    *why = NULL;
    for (size_t i = 0; i < count; i++) {
        const char *f = ray_fault(&rays[i]);
        if (!f) continue;
        if (!n++) *first = i, *why = f;
    }
    return n;
}

int hits_write(const char *path, const accel_hit *hits, size_t count, accel_error *err)
{
    return write_file(path, "HITS", hits, sizeof *hits, count, err);
}

int hits_read(const char *path, accel_hit **hits, size_t *count, accel_error *err)
{
    void *data;
    int rc = read_file(path, "HITS", sizeof(accel_hit), &data, count, err);
    *hits = data;
    if (rc) return rc;
    /* FORMATS.md: a miss has t = +infinity; a hit has a distance. A NaN
     * would agree with anything in a comparison (no |t1 - t2| is > 1e-4 of
     * it), and a miss with a distance is a record from a broken writer. */
    for (size_t i = 0; i < *count; i++) {
        const accel_hit *h = &(*hits)[i];
        const char *bad = NULL;
        if (h->prim == ACCEL_MISS)
            bad = h->t == INFINITY ? NULL : "a miss (prim 0xFFFFFFFF) whose t is not +infinity";
        else if (isnan(h->t))
            bad = "a hit whose t is NaN";
        else if (isnan(h->u) || isnan(h->v))
            bad = "a hit whose u or v is NaN";
        if (!bad) continue;
        accel_fail(err, ACCEL_ERR_PARSE, "%s: byte %llu: hit record %zu is %s (t %g, prim %u)", path,
                   16ull + 16ull * i, i, bad, (double)h->t, h->prim);
        free(*hits);
        *hits = NULL;
        *count = 0;
        return ACCEL_ERR_PARSE;
    }
    return 0;
}

/* ---- ray orders ------------------------------------------------------------- */

int rays_order_parse(const char *name, rays_order *out)
{
    static const char *const names[] = {"tiles8", "scanline", "shuffle"};
    for (int i = 0; i < 3; i++)
        if (!strcmp(name, names[i])) return *out = (rays_order)i, 0;
    return -1;
}

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* The sort key of pixel p in order `order` (the ray index below it keeps
 * the sort stable). */
static uint64_t pixel_key(uint32_t p, int width, rays_order order)
{
    if (order == RAYS_ORDER_SCANLINE) return p;
    const uint64_t x = p % (uint32_t)width, y = p / (uint32_t)width;
    const uint64_t tiles_x = ((uint64_t)width + 7) / 8;
    return ((y / 8) * tiles_x + x / 8) * 64 + (y % 8) * 8 + x % 8;
}

int rays_reorder(rays_set *r, rays_order order, uint64_t seed, accel_error *err)
{
    const size_t n = r->count;
    if (order != RAYS_ORDER_SHUFFLE && (!r->pixel || r->width < 1))
        return accel_fail(err, ACCEL_ERR_SPEC, "ray order tiles8/scanline needs rays made from a "
                          "camera (a .rays file has no pixels)");
    if (n > UINT32_MAX) return accel_fail(err, ACCEL_ERR_RANGE, "%zu rays: too many to reorder", n);
    uint64_t *perm = malloc((n ? n : 1) * sizeof *perm);
    accel_ray *rays = malloc((n ? n : 1) * sizeof *rays);
    uint32_t *pix = r->pixel ? malloc((n ? n : 1) * sizeof *pix) : NULL;
    if (!perm || !rays || (r->pixel && !pix)) {
        free(perm), free(rays), free(pix);
        return accel_fail(err, ACCEL_ERR_NOMEM, "no memory to reorder %zu rays", n);
    }
    for (size_t i = 0; i < n; i++) perm[i] = i;
    if (order == RAYS_ORDER_SHUFFLE) { /* Fisher-Yates, one hashed draw per step */
        for (size_t i = n; i > 1; i--) {
            size_t j = (size_t)(rays_rand(seed, i, 0) * (float)i);
            if (j >= i) j = i - 1;
            uint64_t t = perm[i - 1]; perm[i - 1] = perm[j], perm[j] = t;
        }
    } else {
        /* key in the high bits, ray index in the low 32 */
        for (size_t i = 0; i < n; i++) perm[i] |= pixel_key(r->pixel[i], r->width, order) << 32;
        qsort(perm, n, sizeof *perm, cmp_u64);
    }
    for (size_t i = 0; i < n; i++) {
        const size_t k = (size_t)(perm[i] & 0xFFFFFFFFu);
        rays[i] = r->rays[k];
        if (pix) pix[i] = r->pixel[k];
    }
    free(perm);
    free(r->rays), r->rays = rays;
    if (pix) free(r->pixel), r->pixel = pix;
    return 0;
}
