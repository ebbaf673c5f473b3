/*
 * svg.c - plots as SVG (see svg.h).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "svg.h"

/* The drawing area inside a 760 x 460 canvas; the legend sits right of it. */
#define W 760
#define H 460
#define LEFT 78
#define RIGHT 230
#define TOP 42
#define BOTTOM 58

static const char *const palette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                      "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

void svg_series_look(int i, int dashed, char colour[8], const char **dash, int *marker)
{
    static const char *const solid_dash[4] = {NULL, "2 3", "9 3 2 3", "1 4"};
    static const char *const dashed_dash[4] = {"6 4", "6 3 2 3 2 3", "12 4", "3 6"};
    int np = (int)(sizeof palette / sizeof palette[0]), round = i / np;
    if (round < 4) {
        snprintf(colour, 8, "%s", palette[i % np]);
    } else { /* past 40 series: hues around the circle by the golden angle (HSV, s 0.65) */
        double h = fmod(i * 137.508, 360.0) / 60.0, fr = h - floor(h);
        double v = 200, p = v * 0.35, q = v * (1 - 0.65 * fr), t = v * (1 - 0.65 * (1 - fr));
        double rgb[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
        const double *c = rgb[(int)h % 6];
        snprintf(colour, 8, "#%02x%02x%02x", (int)c[0], (int)c[1], (int)c[2]);
    }
    *dash = (dashed ? dashed_dash : solid_dash)[round % 4];
    *marker = round % 4;
}

/* A point's marker at (x, y) in colour c (svg_series_look's shapes). */
static void marker_at(FILE *f, double x, double y, int marker, const char *c)
{
    if (marker == 1)
        fprintf(f, "<rect x=\"%.1f\" y=\"%.1f\" width=\"6\" height=\"6\" fill=\"%s\"/>\n",
                x - 3, y - 3, c);
    else if (marker == 2)
        fprintf(f, "<path d=\"M%.1f %.1fl4 4l-4 4l-4 -4z\" fill=\"%s\"/>\n", x, y - 4, c);
    else if (marker == 3)
        fprintf(f, "<path d=\"M%.1f %.1fl4 7h-8z\" fill=\"%s\"/>\n", x, y - 4, c);
    else
        fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\"/>\n", x, y, c);
}

void svg_plot_init(svg_plot *p, const char *title, const char *xlabel, const char *ylabel)
{
    memset(p, 0, sizeof *p);
    snprintf(p->title, sizeof p->title, "%s", title);
    snprintf(p->xlabel, sizeof p->xlabel, "%s", xlabel);
    snprintf(p->ylabel, sizeof p->ylabel, "%s", ylabel);
}

static double *copy(const double *v, int n)
{
    if (!v) return NULL;
    double *c = malloc((size_t)(n > 0 ? n : 1) * sizeof *c);
    if (c && n > 0) memcpy(c, v, (size_t)n * sizeof *c);
    return c;
}

int svg_add(svg_plot *p, const char *name, const double *x, const double *y, const double *lo,
            const double *hi, int n, int style)
{
    if (p->count == SVG_MAX_SERIES) return 0;
    svg_series *s = &p->s[p->count];
    snprintf(s->name, sizeof s->name, "%s", name);
    s->x = copy(x, n), s->y = copy(y, n), s->lo = copy(lo, n), s->hi = copy(hi, n);
    s->n = n, s->style = style;
    if (!s->x || !s->y || (lo && !s->lo) || (hi && !s->hi)) {
        free(s->x), free(s->y), free(s->lo), free(s->hi);
        return -1;
    }
    p->count++;
    return 0;
}

static int add_mark(svg_plot *p, double x, double y, int vertical, const char *label)
{
    if (p->mark_count == SVG_MAX_MARKS) return -1;
    svg_mark_t *m = &p->marks[p->mark_count++];
    m->x = x, m->y = y, m->vertical = vertical;
    snprintf(m->label, sizeof m->label, "%s", label ? label : "");
    return 0;
}

int svg_vline(svg_plot *p, double x, const char *label) { return add_mark(p, x, NAN, 1, label); }

int svg_mark(svg_plot *p, double x, double y, const char *label) { return add_mark(p, x, y, 0, label); }

void svg_free(svg_plot *p)
{
    for (int i = 0; i < p->count; i++)
        free(p->s[i].x), free(p->s[i].y), free(p->s[i].lo), free(p->s[i].hi);
    p->count = 0;
}

int svg_ticks(double lo, double hi, int log_axis, double *t, int max)
{
    int n = 0;
    if (!(hi > lo)) {
        if (max > 0) t[n++] = lo;
        return n;
    }
    if (log_axis) {
        int d0 = (int)floor(log10(lo) + 1e-9), d1 = (int)ceil(log10(hi) - 1e-9);
        int fine = d1 - d0 <= 2;
        for (int d = d0; d <= d1 && n < max; d++) {
            static const double steps[3] = {1, 2, 5};
            for (int k = 0; k < (fine ? 3 : 1) && n < max; k++) {
                double v = steps[k] * pow(10, d);
                if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) t[n++] = v;
            }
        }
        return n;
    }
    double raw = (hi - lo) / 6, mag = pow(10, floor(log10(raw))), step = mag;
    if (raw / mag > 5) step = 10 * mag;
    else if (raw / mag > 2) step = 5 * mag;
    else if (raw / mag > 1) step = 2 * mag;
    for (double v = ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step && n < max; v += step)
        t[n++] = fabs(v) < step * 1e-9 ? 0 : v;
    return n;
}

typedef struct {
    double lo, hi;
    int log;
    double px0, px1; /* pixel ends */
} axis;

static double map(const axis *a, double v)
{
    double f = a->log ? (log10(v) - log10(a->lo)) / (log10(a->hi) - log10(a->lo))
                      : (v - a->lo) / (a->hi - a->lo);
    return a->px0 + f * (a->px1 - a->px0);
}

static int shown(const axis *a, double v) { return isfinite(v) && (!a->log || v > 0); }

/* The data range of an axis, widened a little (linear) or to decades (log). */
static void range(const svg_plot *p, int y, axis *a)
{
    a->lo = INFINITY, a->hi = -INFINITY;
    for (int i = 0; i < p->count; i++)
        for (int k = 0; k < p->s[i].n; k++) {
            const svg_series *s = &p->s[i];
            double v[3] = {y ? s->y[k] : s->x[k], y && s->lo ? s->lo[k] : NAN,
                           y && s->hi ? s->hi[k] : NAN};
            for (int j = 0; j < 3; j++)
                if (shown(a, v[j])) a->lo = fmin(a->lo, v[j]), a->hi = fmax(a->hi, v[j]);
        }
    for (int i = 0; i < p->mark_count; i++) {
        double v = y ? p->marks[i].y : p->marks[i].x;
        if (shown(a, v)) a->lo = fmin(a->lo, v), a->hi = fmax(a->hi, v);
    }
    if (!(a->hi >= a->lo)) a->lo = a->log ? 1 : 0, a->hi = a->log ? 10 : 1;
    if (a->log) {
        if (a->hi <= a->lo * 1.0001) a->lo /= 2, a->hi *= 2;
        a->lo = pow(10, floor(log10(a->lo) * 4) / 4), a->hi = pow(10, ceil(log10(a->hi) * 4) / 4);
    } else {
        double pad = (a->hi - a->lo) * 0.05;
        if (pad == 0) pad = a->hi != 0 ? fabs(a->hi) * 0.1 : 1;
        a->lo -= pad, a->hi += pad;
    }
}

static void text(FILE *f, const char *s)
{
    for (; *s; s++) {
        if (*s == '&') fputs("&amp;", f);
        else if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else fputc(*s, f);
    }
}

/* Whether an axis's ticks need powers of ten (then all of them get it). */
static int needs_exp(const double *t, int n)
{
    for (int i = 0; i < n; i++)
        if (fabs(t[i]) >= 1e5 || (fabs(t[i]) < 1e-3 && t[i] != 0)) return 1;
    return 0;
}

static void label(char *buf, size_t n, double v, int exp_form)
{
    if (exp_form && v != 0) {
        int e = (int)floor(log10(fabs(v)) + 1e-9);
        double m = v / pow(10, e);
        if (fabs(m - 1) < 1e-9) snprintf(buf, n, "1e%d", e);
        else snprintf(buf, n, "%.3ge%d", m, e);
    } else {
        snprintf(buf, n, "%g", v);
    }
}

/* The marks: dashed vertical lines and rings, labelled. */
static void draw_marks(FILE *f, const svg_plot *p, const axis *ax, const axis *ay)
{
    for (int i = 0; i < p->mark_count; i++) {
        const svg_mark_t *m = &p->marks[i];
        if (!shown(ax, m->x) || (!m->vertical && !shown(ay, m->y))) continue;
        double x = map(ax, m->x), y = m->vertical ? TOP + 12 + 14 * i : map(ay, m->y);
        if (m->vertical)
            fprintf(f, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#444\" "
                       "stroke-width=\"1.4\" stroke-dasharray=\"3 3\"/>\n", x, TOP, x, H - BOTTOM);
        else
            fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"7\" fill=\"none\" stroke=\"#000\" "
                       "stroke-width=\"1.6\"/>\n", x, y);
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\">", x + 5, m->vertical ? y : y - 9);
        text(f, m->label);
        fprintf(f, "</text>\n");
    }
}

int svg_write(const svg_plot *p, const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    axis ax = {0, 0, p->log_x, LEFT, W - RIGHT}, ay = {0, 0, p->log_y, H - BOTTOM, TOP};
    range(p, 0, &ax);
    range(p, 1, &ay);
    fprintf(f, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
               "viewBox=\"0 0 %d %d\" font-family=\"sans-serif\" font-size=\"12\">\n"
               "<rect width=\"%d\" height=\"%d\" fill=\"white\"/>\n", W, H, W, H, W, H);
    fprintf(f, "<text x=\"%d\" y=\"22\" font-size=\"14\" font-weight=\"bold\">", LEFT);
    text(f, p->title);
    fprintf(f, "</text>\n");
    double t[64];
    char buf[32];
    int n = svg_ticks(ax.lo, ax.hi, ax.log, t, 64), ex = needs_exp(t, n);
    for (int i = 0; i < n; i++) {
        double x = map(&ax, t[i]);
        label(buf, sizeof buf, t[i], ex);
        fprintf(f, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#e4e4e4\"/>\n"
                   "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%s</text>\n",
                x, TOP, x, H - BOTTOM, x, H - BOTTOM + 16, buf);
    }
    n = svg_ticks(ay.lo, ay.hi, ay.log, t, 64), ex = needs_exp(t, n);
    for (int i = 0; i < n; i++) {
        double y = map(&ay, t[i]);
        label(buf, sizeof buf, t[i], ex);
        fprintf(f, "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"#e4e4e4\"/>\n"
                   "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n",
                LEFT, y, W - RIGHT, y, LEFT - 6, y + 4, buf);
    }
    fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"#333\"/>\n",
            LEFT, TOP, W - RIGHT - LEFT, H - BOTTOM - TOP);
    fprintf(f, "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">", (LEFT + W - RIGHT) / 2, H - 18);
    text(f, p->xlabel);
    fprintf(f, "%s</text>\n<text transform=\"translate(18,%d) rotate(-90)\" text-anchor=\"middle\">",
            ax.log ? " (log scale)" : "", (TOP + H - BOTTOM) / 2);
    text(f, p->ylabel);
    fprintf(f, "%s</text>\n", ay.log ? " (log scale)" : "");
    for (int i = 0; i < p->count; i++) {
        const svg_series *s = &p->s[i];
        char c[8], dash_attr[48] = "";
        const char *dash;
        int marker;
        svg_series_look(i, s->style & SVG_DASHED, c, &dash, &marker);
        if (dash) snprintf(dash_attr, sizeof dash_attr, " stroke-dasharray=\"%s\"", dash);
        if (s->style & (SVG_LINE | SVG_DASHED)) {
            fprintf(f, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.6\"%s points=\"", c,
                    dash_attr);
            for (int k = 0; k < s->n; k++)
                if (shown(&ax, s->x[k]) && shown(&ay, s->y[k]))
                    fprintf(f, "%.1f,%.1f ", map(&ax, s->x[k]), map(&ay, s->y[k]));
            fprintf(f, "\"/>\n");
        }
        for (int k = 0; k < s->n; k++) {
            if (!shown(&ax, s->x[k]) || !shown(&ay, s->y[k])) continue;
            double x = map(&ax, s->x[k]), y = map(&ay, s->y[k]);
            if (s->lo && s->hi && shown(&ay, s->lo[k]) && shown(&ay, s->hi[k])) {
                double y0 = map(&ay, s->lo[k]), y1 = map(&ay, s->hi[k]);
                fprintf(f, "<path d=\"M%.1f %.1fV%.1fM%.1f %.1fh6M%.1f %.1fh6\" stroke=\"%s\"/>\n",
                        x, y0, y1, x - 3, y0, x - 3, y1, c);
            }
            if (s->style & SVG_POINTS) marker_at(f, x, y, marker, c);
        }
        int ly = TOP + 8 + 18 * i;
        if (s->style & (SVG_LINE | SVG_DASHED))
            fprintf(f, "<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"%s\" "
                       "stroke-width=\"2\"%s/>\n", W - RIGHT + 12, ly, W - RIGHT + 36, ly, c,
                    dash_attr);
        if (s->style & SVG_POINTS) marker_at(f, W - RIGHT + 24, ly, marker, c);
        fprintf(f, "<text x=\"%d\" y=\"%d\" font-size=\"11\">", W - RIGHT + 42, ly + 4);
        char name[40];
        /* The legend has room for about 30 characters; the full name is in the section. */
        snprintf(name, sizeof name, "%.29s%s", s->name, strlen(s->name) > 29 ? "..." : "");
        text(f, name);
        fprintf(f, "</text>\n");
    }
    draw_marks(f, p, &ax, &ay);
    fprintf(f, "</svg>\n");
    return fclose(f) == 0 ? 0 : -1;
}
