/* The files a run or a merge writes from one state: every band's RAW of each kind and
 * side, the LSS and the JSON, expanded to one entry per file, checked against each other
 * and every file the command reads before any work, and written together: the LSS first,
 * the rest to temporaries published at the end, every file not written named. Run
 * (host/commands/run_outputs.c) and merge (host/commands/merge.c) only choose the names. */
#ifndef LSQT_OUTPUTS_H
#define LSQT_OUTPUTS_H

#include <stdio.h>

#include "lsqt/report.h"
#include "lsqt/state.h"
#include "lsqt/tally.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The kinds: RAW is one file, or with -H two (R and T; no T when nothing is transmitted);
 * a two-sided state adds the same for the side from below (below.h); with bands each RAW
 * kind is one file per band (NAME.550nm.raw). */
enum { LSQT_OUT_RAW, LSQT_OUT_RAW_T, LSQT_OUT_RAW_B, LSQT_OUT_RAW_BT, LSQT_OUT_LSS, LSQT_OUT_JSON, LSQT_OUT_KINDS };

typedef struct lsqt_out_file {
    char *path;
    int kind, band; /* LSQT_OUT_*, and the band of a RAW (0 without bands) */
} lsqt_out_file;

typedef struct lsqt_outputs {
    const char *path[LSQT_OUT_KINDS]; /* NULL: not written; a RAW kind's name before the band labels */
    int hemi;                         /* -H: the RAW kinds hold R only and T only */
    int n_bands;                      /* the state's bands, and their wavelengths (NULL: unnamed) */
    const double *wl;
    int n_files;                      /* every file, in the order written: LSS, RAW kinds band by */
    lsqt_out_file *files;             /* band, JSON (lsqt_outputs_free) */
} lsqt_outputs;

/* A file the command reads, which no output may replace: what names it in a message
 * ("the input", "the table", ...). */
typedef struct lsqt_input_file {
    const char *path, *what;
} lsqt_input_file;

/* Expands O's kinds into its files (with bands one RAW per band: a RAW name that is
 * stdout, a device, a FIFO or a directory is refused then, hint ending the message), and
 * checks that no two land on one file, nor any on a file of IN (n_in of them). Devices
 * and FIFOs may be named twice among the inputs. Returns 0, or 2 (1 out of memory) with
 * err filled and nothing to free. */
int lsqt_outputs_plan(lsqt_outputs *o, const lsqt_input_file *in, int n_in, const char *hint, char *err,
                      size_t errcap);
void lsqt_outputs_free(lsqt_outputs *o);

/* Can every file be written (lsqt_out_check)? Each one that cannot is printed after
 * "PROG: error: " (the first 10, then a count), with " (WHEN)". Returns 0 or 1. */
int lsqt_outputs_check(const lsqt_outputs *o, const char *prog, const char *when);

/* Writes every file; a failed one does not stop the others. The LSS is lss_st (a run's
 * interrupted RRSS pilot's own state), written first; the rest from st (est: lsqt_estimates
 * of st; ri for the JSON), to temporaries published together. Prints "SAID wrote ..." on
 * INFO unless quiet; every file not written is named, and the previous file at its path
 * removed when the LSS moved on (it would pass for this state's). Returns 0 or 1. */
int lsqt_outputs_write(const lsqt_outputs *o, const lsqt_state *st, const lsqt_state *lss_st,
                       const lsqt_slice_est *est, const lsqt_run_info *ri, const char *prog, const char *said,
                       int quiet, FILE *info);

#ifdef __cplusplus
}
#endif
#endif
