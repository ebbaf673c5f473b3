/*
 * svg.h - the report's plots, drawn by the project itself as SVG: text
 * files (diffable, no gnuplot needed) that every Markdown viewer shows
 * inline. A plot has axes (linear or logarithmic, with ticks at 1-2-5
 * steps or at decades), a title, axis labels, a legend and several series,
 * each a line, points, or a dashed line, optionally with an interval
 * (error bar) at every point.
 */
#ifndef EXP_SVG_H
#define EXP_SVG_H

#include <stddef.h>

enum { SVG_LINE = 1, SVG_POINTS = 2, SVG_DASHED = 4 };

#define SVG_MAX_SERIES 16

typedef struct {
    char name[160];
    double *x, *y, *lo, *hi; /* lo/hi: NULL without intervals */
    int n, style;
} svg_series;

typedef struct {
    char title[256], xlabel[128], ylabel[128];
    int log_x, log_y;
    svg_series s[SVG_MAX_SERIES];
    int count;
} svg_plot;

void svg_plot_init(svg_plot *p, const char *title, const char *xlabel, const char *ylabel);
/* Adds a series (the arrays are copied; lo and hi may be NULL). Series
 * beyond SVG_MAX_SERIES and points that a log axis cannot show (<= 0)
 * are left out of the drawing. Returns 0, or -1 when out of memory. */
int svg_add(svg_plot *p, const char *name, const double *x, const double *y, const double *lo,
            const double *hi, int n, int style);
/* Writes the plot; 0, or -1 when the file cannot be written. */
int svg_write(const svg_plot *p, const char *path);
void svg_free(svg_plot *p);

/* The ticks of an axis from lo to hi: at 1-2-5 steps (linear) or decades
 * with 2 and 5 between them when the range is short (log). Returns the
 * count (at most max). Exposed for the tests. */
int svg_ticks(double lo, double hi, int log_axis, double *ticks, int max);

#endif
