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

#define SVG_MAX_MARKS 8
/* A mark that shows the answer on a plot (issue 39): a vertical line at x
 * across the plot (a time budget, a crossing), or a ring at (x, y) (the
 * measured best, a model's pick); each with its label. */
typedef struct {
    double x, y;
    int vertical;
    char label[64];
} svg_mark_t;

typedef struct {
    char title[256], xlabel[128], ylabel[128];
    int log_x, log_y;
    svg_series s[SVG_MAX_SERIES];
    int count;
    svg_mark_t marks[SVG_MAX_MARKS];
    int mark_count;
} svg_plot;

void svg_plot_init(svg_plot *p, const char *title, const char *xlabel, const char *ylabel);
/* Adds a series (the arrays are copied; lo and hi may be NULL). Series
 * beyond SVG_MAX_SERIES and points that a log axis cannot show (<= 0)
 * are left out of the drawing. Returns 0, or -1 when out of memory. */
int svg_add(svg_plot *p, const char *name, const double *x, const double *y, const double *lo,
            const double *hi, int n, int style);
/* A labelled vertical line at x (svg_vline) or ring at (x, y) (svg_mark);
 * marks widen the axes to show themselves. 0, or -1 when full. */
int svg_vline(svg_plot *p, double x, const char *label);
int svg_mark(svg_plot *p, double x, double y, const char *label);
/* No fit is drawn through fewer points than this, nor through a collapsed
 * structure (issue 39): svg_fit_drawable says whether a fit may be. */
#define SVG_MIN_FIT_POINTS 4
static inline int svg_fit_drawable(int points, int collapsed)
{
    return points >= SVG_MIN_FIT_POINTS && !collapsed;
}
/* Writes the plot; 0, or -1 when the file cannot be written. Every tick of
 * an axis has one format: plain numbers, or powers of ten (1e5) when any
 * tick needs them. */
int svg_write(const svg_plot *p, const char *path);
void svg_free(svg_plot *p);

/* How series i is drawn: its colour ("#rrggbb"), its dash pattern (NULL:
 * solid; dashed: the series has SVG_DASHED) and its marker (0 circle, 1
 * square, 2 diamond, 3 triangle). The first 10 series take 10 colours,
 * solid lines and circles; each later round of 10 the same colours with
 * another dash pattern and marker, so that no two of SVG_MAX_SERIES (nor of
 * the first 40) look alike. Exposed for the tests. */
void svg_series_look(int i, int dashed, char colour[8], const char **dash, int *marker);

/* The ticks of an axis from lo to hi: at 1-2-5 steps (linear) or decades
 * with 2 and 5 between them when the range is short (log). Returns the
 * count (at most max). Exposed for the tests. */
int svg_ticks(double lo, double hi, int log_axis, double *ticks, int max);

#endif
