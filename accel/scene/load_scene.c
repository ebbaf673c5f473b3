/*
 * load_scene.c - the `.scene` reader (FORMATS.md): meshes, instances with
 * transforms, camera and light, one statement per line.
 *
 *   mesh     NAME SOURCE                  a mesh file (relative to the scene
 *                                         file's folder) or a built-in spec
 *   instance NAME [TRANSFORM ...]         translate X Y Z | scale S |
 *                                         scale SX SY SZ | rotate AX AY AZ DEG |
 *                                         matrix M00 .. M23 (12 numbers, rows)
 *   camera   eye X Y Z look X Y Z [up X Y Z] [fov DEG]
 *   light    X Y Z
 *
 * Transforms apply left to right as written, each mapping object space
 * toward world space. The meshes and instances go to a scene_compose
 * (compose.c), which flattens them with the primitive ids FORMATS.md
 * defines. Numbers are read in double (the transforms are composed in
 * double): decimal only, no nan, inf or hexadecimal forms.
 *
 * Every error names the file and the line: malformed or missing numbers,
 * trailing words, unknown keywords or transforms, duplicate or unknown mesh
 * names, a mesh that cannot be loaded (its own message follows), singular
 * or non-finite transforms, and a scene whose primitive count would exceed
 * the id limit (checked per instance line, before the flattened scene is
 * allocated). The camera's up defaults to +y and its fov to 40 degrees;
 * without a camera line the default view frames the whole scene.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/compose.h"
#include "scene/load_common.h"

#define SCENE_NAME_MAX 64   /* characters of a mesh name, with the NUL */
#define SCENE_SOURCE_MAX 1024

typedef struct {
    char name[SCENE_NAME_MAX];
    size_t line;
} mesh_entry;

typedef struct {
    load_text t;
    const char *dir;
    const scene_file_options *opt;
    scene_compose c;
    mesh_entry *meshes; /* parallel to c.set.meshes */
    size_t camera_line, light_line;
    accel_camera camera;
    vec3 light;
} parser;

/* ---- tokens ---------------------------------------------------------------- */

/* The next word on the line into buf (at most size-1 characters); 1 if it
 * was longer (buf then holds its start), -1 at the end of the line. */
static int next_word(parser *ps, char *buf, size_t size)
{
    load_text *t = &ps->t;
    load_skip_hspace(t);
    if (load_at_eol(t)) return -1;
    size_t n = 0;
    int longer = 0;
    while (t->p < t->end && !load_is_delim(t, *t->p)) {
        if (n + 1 < size)
            buf[n++] = *t->p;
        else
            longer = 1;
        t->p++;
    }
    buf[n] = 0;
    return longer;
}

static int at_number(parser *ps)
{
    load_skip_hspace(&ps->t);
    if (load_at_eol(&ps->t)) return 0;
    char c = *ps->t.p;
    return (c >= '0' && c <= '9') || c == '.' || c == '+' || c == '-';
}

/* A decimal number [+-] (digits [. digits] | . digits) [e [+-] digits],
 * ending at a delimiter, read in double. */
static int read_number(parser *ps, const char *what, double *out)
{
    load_text *t = &ps->t;
    load_skip_hspace(t);
    const char *s = t->p, *p = s, *e = t->end;
    if (p < e && (*p == '+' || *p == '-')) p++;
    size_t digits = 0;
    while (p < e && *p >= '0' && *p <= '9') p++, digits++;
    if (p < e && *p == '.') {
        p++;
        while (p < e && *p >= '0' && *p <= '9') p++, digits++;
    }
    if (digits && p < e && (*p == 'e' || *p == 'E')) {
        const char *q = p + 1;
        if (q < e && (*q == '+' || *q == '-')) q++;
        const char *d0 = q;
        while (q < e && *q >= '0' && *q <= '9') q++;
        if (q > d0) p = q;
    }
    if (!digits || (p < e && !load_is_delim(t, *p))) {
        const char *w = s;
        if (w < e && (*w == '+' || *w == '-')) w++;
        size_t left = (size_t)(e - w);
        if ((left >= 3 && !strncasecmp(w, "nan", 3)) || (left >= 3 && !strncasecmp(w, "inf", 3)))
            return load_fail(t, ACCEL_ERR_PARSE, "%s is not a finite number", what);
        return load_fail_expected(t, what);
    }
    char buf[128];
    size_t len = (size_t)(p - s);
    if (len >= sizeof buf)
        return load_fail(t, ACCEL_ERR_PARSE, "%s: number longer than %zu characters", what,
                         sizeof buf - 1);
    memcpy(buf, s, len);
    buf[len] = 0;
    double v = strtod(buf, NULL);
    if (!isfinite(v)) return load_fail(t, ACCEL_ERR_RANGE, "%s %s is out of range", what, buf);
    t->p = p;
    *out = v;
    return 0;
}

static int read_numbers(parser *ps, const char *what, double *out, int n)
{
    for (int i = 0; i < n; i++) {
        int rc = read_number(ps, what, &out[i]);
        if (rc) return rc;
    }
    return 0;
}

static int read_vec3f(parser *ps, const char *what, vec3 *out)
{
    double d[3];
    int rc = read_numbers(ps, what, d, 3);
    if (rc) return rc;
    *out = v3((float)d[0], (float)d[1], (float)d[2]);
    if (!isfinite(out->x) || !isfinite(out->y) || !isfinite(out->z))
        return load_fail(&ps->t, ACCEL_ERR_RANGE, "%s (%g, %g, %g) is beyond the float range",
                         what, d[0], d[1], d[2]);
    return 0;
}

/* Nothing but blanks or a comment may follow a statement. */
static int expect_end(parser *ps, const char *after)
{
    load_skip_hspace(&ps->t);
    if (load_at_eol(&ps->t)) return 0;
    char tok[200];
    load_token_text(ps->t.p, ps->t.end, tok, sizeof tok);
    return load_fail(&ps->t, ACCEL_ERR_PARSE, "unexpected '%s' after %s", tok, after);
}

/* ---- statements ------------------------------------------------------------ */

static int find_mesh(const parser *ps, const char *name)
{
    for (uint32_t i = 0; i < ps->c.set.mesh_count; i++)
        if (!strcmp(ps->meshes[i].name, name)) return (int)i;
    return -1;
}

static int parse_mesh(parser *ps)
{
    load_text *t = &ps->t;
    char name[SCENE_NAME_MAX], source[SCENE_SOURCE_MAX];
    int w = next_word(ps, name, sizeof name);
    if (w < 0) return load_fail_expected(t, "a mesh name");
    if (w > 0)
        return load_fail(t, ACCEL_ERR_PARSE, "mesh name '%s...' is longer than %d characters",
                         name, SCENE_NAME_MAX - 1);
    int prev = find_mesh(ps, name);
    if (prev >= 0)
        return load_fail(t, ACCEL_ERR_PARSE, "mesh '%s' is already declared at line %zu", name,
                         ps->meshes[prev].line);
    w = next_word(ps, source, sizeof source);
    if (w < 0) return load_fail_expected(t, "a mesh source (a mesh file or a built-in scene)");
    if (w > 0)
        return load_fail(t, ACCEL_ERR_PARSE, "mesh source longer than %d characters",
                         SCENE_SOURCE_MAX - 1);
    int rc = expect_end(ps, "the mesh source");
    if (rc) return rc;
    uint32_t count = ps->c.set.mesh_count;
    mesh_entry *m = realloc(ps->meshes, ((size_t)count + 1) * sizeof *m);
    if (!m) return load_fail(t, ACCEL_ERR_NOMEM, "out of memory");
    ps->meshes = m;
    accel_scene mesh;
    memset(&mesh, 0, sizeof mesh);
    rc = ps->opt->load_mesh(ps->opt->ctx, source, ps->dir, &mesh, t->err);
    uint32_t index;
    if (rc == 0) {
        rc = scene_compose_add_mesh(&ps->c, &mesh, &index, t->err);
        if (rc) scene_free(&mesh);
    }
    if (rc) return load_prefix(t->err, rc, "%s:%zu: mesh %s", t->name, t->line, name);
    memcpy(ps->meshes[index].name, name, sizeof name);
    ps->meshes[index].line = t->line;
    return 0;
}

/* One transform word and its numbers, as a matrix in *m. */
static int parse_transform(parser *ps, const char *word, double m[12])
{
    load_text *t = &ps->t;
    double v[12];
    int rc;
    if (!strcmp(word, "translate")) {
        rc = read_numbers(ps, "a translate offset (3 numbers)", v, 3);
        if (rc == 0) scene_xform_translate(m, v[0], v[1], v[2]);
    } else if (!strcmp(word, "scale")) {
        rc = read_number(ps, "a scale factor", v);
        if (rc) return rc;
        if (at_number(ps)) {
            rc = read_numbers(ps, "a third scale factor (scale takes 1 or 3 numbers)", v + 1, 2);
            if (rc == 0) scene_xform_scale(m, v[0], v[1], v[2]);
        } else {
            scene_xform_scale(m, v[0], v[0], v[0]);
        }
    } else if (!strcmp(word, "rotate")) {
        rc = read_numbers(ps, "a rotation axis and angle (4 numbers)", v, 4);
        if (rc == 0 && scene_xform_rotate(m, v[0], v[1], v[2], v[3]))
            rc = load_fail(t, ACCEL_ERR_RANGE, "rotation axis (%g, %g, %g) has no direction", v[0],
                           v[1], v[2]);
    } else if (!strcmp(word, "matrix")) {
        rc = read_numbers(ps, "a matrix entry (12 numbers, 3 rows of 4)", v, 12);
        if (rc == 0) memcpy(m, v, sizeof v);
    } else {
        rc = load_fail(t, ACCEL_ERR_PARSE,
                       "unknown transform '%s' (expected translate, scale, rotate or matrix)",
                       word);
    }
    return rc;
}

static int parse_instance(parser *ps)
{
    load_text *t = &ps->t;
    char name[SCENE_NAME_MAX], word[32];
    int w = next_word(ps, name, sizeof name);
    if (w < 0) return load_fail_expected(t, "the name of a mesh to place");
    int mi = w > 0 ? -1 : find_mesh(ps, name);
    if (mi < 0)
        return load_fail(t, ACCEL_ERR_PARSE, "unknown mesh '%s%s' (declare it with a mesh line first)",
                         name, w > 0 ? "..." : "");
    double m[12], step[12];
    scene_xform_identity(m);
    while ((w = next_word(ps, word, sizeof word)) >= 0) {
        if (w > 0)
            return load_fail(t, ACCEL_ERR_PARSE,
                             "unknown transform '%s...' (expected translate, scale, rotate or matrix)",
                             word);
        int rc = parse_transform(ps, word, step);
        if (rc) return rc;
        scene_xform_then(m, step);
    }
    int rc = scene_compose_add_instance(&ps->c, (uint32_t)mi, m, t->err);
    if (rc) return load_prefix(t->err, rc, "%s:%zu: instance %s", t->name, t->line, name);
    return 0;
}

static int parse_camera(parser *ps)
{
    load_text *t = &ps->t;
    if (ps->camera_line)
        return load_fail(t, ACCEL_ERR_PARSE, "second camera (the first is at line %zu)",
                         ps->camera_line);
    vec3 val[3] = {{0, 0, 0}, {0, 0, 0}, {0, 1, 0}};
    double fov = 40.0;
    int given[4] = {0, 0, 0, 0};
    static const char *const keys[4] = {"eye", "look", "up", "fov"};
    char word[16];
    int w;
    while ((w = next_word(ps, word, sizeof word)) >= 0) {
        int k = 0;
        while (k < 4 && (w > 0 || strcmp(word, keys[k]))) k++;
        if (k == 4)
            return load_fail(t, ACCEL_ERR_PARSE,
                             "unknown camera word '%s%s' (expected eye, look, up or fov)", word,
                             w > 0 ? "..." : "");
        if (given[k]) return load_fail(t, ACCEL_ERR_PARSE, "camera %s given twice", keys[k]);
        given[k] = 1;
        char what[48];
        snprintf(what, sizeof what, "camera %s (%s)", keys[k], k == 3 ? "degrees" : "3 numbers");
        int rc = k == 3 ? read_number(ps, what, &fov) : read_vec3f(ps, what, &val[k]);
        if (rc) return rc;
    }
    if (!given[0] || !given[1])
        return load_fail(t, ACCEL_ERR_PARSE, "camera needs eye and look");
    if (!(fov > 0.0 && fov < 180.0))
        return load_fail(t, ACCEL_ERR_RANGE, "camera fov %g is not in (0, 180) degrees", fov);
    /* The ray generators' own check (in double: a far eye or a tiny view
     * vector is fine, an up within 0.006 degrees of the view is not), here
     * where the line is known. */
    ps->camera = (accel_camera){val[0], val[1], val[2], (float)fov};
    int crc = scene_camera_check(&ps->camera, t->err);
    if (crc) return load_prefix(t->err, crc, "%s:%zu", t->name, t->line);
    ps->camera_line = t->line;
    return 0;
}

static int parse_light(parser *ps)
{
    if (ps->light_line)
        return load_fail(&ps->t, ACCEL_ERR_PARSE, "second light (the first is at line %zu)",
                         ps->light_line);
    int rc = read_vec3f(ps, "a light position (3 numbers)", &ps->light);
    if (rc == 0) rc = expect_end(ps, "the light position");
    if (rc == 0) ps->light_line = ps->t.line;
    return rc;
}

static int parse_lines(parser *ps)
{
    load_text *t = &ps->t;
    char word[32];
    while (t->p < t->end) {
        int w = next_word(ps, word, sizeof word);
        if (w < 0) {
            load_next_line(t);
            continue;
        }
        int rc;
        if (w > 0)
            rc = load_fail(t, ACCEL_ERR_PARSE,
                           "unknown keyword '%s...' (expected mesh, instance, camera or light)",
                           word);
        else if (!strcmp(word, "mesh"))
            rc = parse_mesh(ps);
        else if (!strcmp(word, "instance"))
            rc = parse_instance(ps);
        else if (!strcmp(word, "camera"))
            rc = parse_camera(ps);
        else if (!strcmp(word, "light"))
            rc = parse_light(ps);
        else
            rc = load_fail(t, ACCEL_ERR_PARSE,
                           "unknown keyword '%s' (expected mesh, instance, camera or light)", word);
        if (rc) return rc;
        load_next_line(t);
    }
    return 0;
}

int load_scene_parse(const char *name, const char *dir, const char *data, size_t size,
                     const scene_file_options *opt, accel_scene *s, accel_error *err)
{
    memset(s, 0, sizeof *s);
    parser ps;
    memset(&ps, 0, sizeof ps);
    int rc = load_text_begin(&ps.t, name, data, size, size, '#', err);
    if (rc) return rc;
    ps.dir = dir ? dir : "";
    ps.opt = opt;
    ps.c.max_prims = opt->max_prims;
    rc = parse_lines(&ps);
    const char *base = strrchr(name, '/');
    if (rc == 0) rc = scene_compose_finish(&ps.c, base ? base + 1 : name, s, err);
    if (rc == 0) {
        if (ps.camera_line) s->camera = ps.camera;
        if (ps.light_line) s->light = ps.light;
    }
    scene_compose_free(&ps.c);
    free(ps.meshes);
    return rc;
}
