/*
 * csv.h - CSV files as RFC 4180 describes them, one schema per file.
 *
 * Records are written from printf formats whose literal commas separate
 * the fields: csv_row(c, "%s,%d,%.4f\n", spec, n, ms). A field whose text
 * holds a comma, a double quote, CR or LF (a spec such as
 * "bvh:build=binned,bins=16", a scene name) is enclosed in double quotes
 * with its quotes doubled (RFC 4180, 2.6 and 2.7); numbers never need it.
 * The first record is the header; a record with another number of fields
 * is refused and counted, so a file always has one schema. Records end in
 * LF (RFC 4180 names CRLF; Python's csv module, R and gnuplot read both).
 */
#ifndef ACCEL_CSV_H
#define ACCEL_CSV_H

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    FILE *f;
    int columns;    /* fields of the header; 0 until it is written */
    long rows;      /* records written after the header */
    int bad_rows;   /* records refused: wrong field count, format error */
    char first_bad[256];
} csv_file;

/* Formats one record (no line end; a trailing "\n" in fmt is dropped) into
 * buf. Returns the number of fields, or -1 when buf is too small or fmt
 * holds a conversion other than d i u o x X c s f F e E g G a A p %%. */
int csv_vformat(char *buf, size_t n, const char *fmt, va_list ap);
int csv_format(char *buf, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

void csv_open(csv_file *c, FILE *f);
/* Writes one record (the header first) and flushes. Returns 0, or -1 when
 * the record was refused (c->bad_rows, c->first_bad say why). */
int csv_row(csv_file *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
int csv_vrow(csv_file *c, const char *fmt, va_list ap);

#ifdef __cplusplus
}
#endif

#endif
