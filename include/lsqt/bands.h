/* Wavelength bands: the run's wavelengths (--wavelengths) and the two-column tables a
 * model parameter may be read from (KEY=@FILE), interpolated at those wavelengths. Host
 * only; nothing here touches the kernels. */
#ifndef LSQT_BANDS_H
#define LSQT_BANDS_H

#include <stddef.h>

/* Most bands a run may have (400:2500:1 is 2101). */
#define LSQT_MAX_BANDS 4096

/* Parses LIST, "450,550,650" or "START:STOP:STEP" (both ends included: STOP must be
 * START plus a whole number of steps, to 1e-9 of a step, else refused with the steps and
 * stops that work), into *out (heap, *n values, at most LSQT_MAX_BANDS, strictly
 * increasing, each in (0, 1e6] nm, every two far enough apart for distinct file labels,
 * lsqt_band_names). Returns 0, or 2 with a message that names the token in err (without
 * a "--wavelengths" prefix: the caller adds it). */
int lsqt_parse_wavelengths(const char *list, double **out, int *n, char *err, size_t errcap);

/* A table of (wavelength nm, value) rows, wavelengths strictly increasing. */
typedef struct lsqt_band_table {
    int n;
    double *wl, *v;
} lsqt_band_table;

/* Reads TEXT (len bytes; NAME for messages): one row per line, two numbers separated by
 * spaces, tabs or a comma; '#' starts a comment; blank lines are skipped. Returns 0, or 2
 * with "NAME:LINE: ..." in err. At least one row. */
int lsqt_band_table_parse(const char *text, size_t len, const char *name, lsqt_band_table *t, char *err,
                          size_t errcap);

/* The table's value at wavelength wl, linear between rows (exact at a row). Returns 0,
 * or -1 when wl is outside [first, last] row. */
int lsqt_band_table_at(const lsqt_band_table *t, double wl, double *v);

void lsqt_band_table_free(lsqt_band_table *t);

/* What the parser needs to read band b of a key written as a list or a table: the run's
 * band count and wavelengths (NULL when the bands are unnamed: lists only), and the folder
 * a relative @FILE is read from. Tables read once are kept (tables, n_tables), so a parse
 * per band reads each file once; lsqt_bands_free releases them. */
typedef struct lsqt_bands {
    int n;              /* 0: not known yet (no --wavelengths): the first list sets it */
    const double *wl;
    const char *dir;
    int n_tables;
    char **table_paths;
    lsqt_band_table *tables;
    int count_line;     /* the line of the list that set n (0: --wavelengths did) */
} lsqt_bands;

void lsqt_bands_free(lsqt_bands *b);

/* PATH with ".LABEL" (lsqt_band_label, lsqt/colour.h) before its final ".raw" (or at its end): panel.lsqt.raw ->
 * panel.lsqt.550nm.raw. */
void lsqt_band_path(const char *path, const char *label, char *dst, size_t cap);

/* What a RAW PATH of n_bands bands (wl: their wavelengths or NULL) is written as, for
 * messages: PATH itself for one band, else the first and last band's labels in braces:
 * panel.lsqt.{450nm,...,650nm}.raw, panel.lsqt.{450nm,650nm}.raw for two bands. */
void lsqt_band_path_shown(const char *path, int n_bands, const double *wl, char *dst, size_t cap);

#endif
