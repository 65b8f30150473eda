/* The human summary and the machine-readable JSON summary of a run. */
#ifndef LSQT_REPORT_H
#define LSQT_REPORT_H

#include <stdio.h>

#include "lsqt/state.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lsqt_run_info {
    const char *device;
    double seconds;          /* this run */
    double paths_per_second; /* this run, all slices together */
    unsigned long long paths_added;
    const char *stopped_by;  /* what ended the run (NULL: not said) */
    lsqt_work work;          /* the work of this run (the state's counters after minus before) */
    /* --target-error (0: not given): the largest relative error reached (NaN: not known
     * yet) and the paths per slice in all the 1/sqrt(paths) law says the target needs */
    double target_error, max_rel_err;
    unsigned long long paths_needed;
    int all_bands; /* every band's table even when there are many (-v) */
} lsqt_run_info;
/* Above this many bands the summary gives one line a band (all_bands: every table). */
#define LSQT_SUMMARY_BANDS 4

void lsqt_report_summary(FILE *f, const lsqt_state *st, const lsqt_slice_est *est,
                         const lsqt_run_info *ri);

/* Returns 0 or -1 (err filled). Written through lsqt_out (util.h): committed, or with
 * HOLD left for lsqt_out_set_publish. */
int lsqt_report_json(const char *path, const lsqt_state *st, const lsqt_slice_est *est,
                     const lsqt_run_info *ri, lsqt_out_set *hold, char *err, size_t errcap);

/* JSON pieces shared by the run's and lsqt-cl info's JSON: a number (null when not
 * finite), and slice s's object (detail: non-finite count and work counters too). */
void lsqt_json_num(FILE *f, double v);
/* ",\n "bands": N, "wavelengths": [...] or null" */
void lsqt_json_bands(FILE *f, const lsqt_state *st);
void lsqt_json_slice(FILE *f, const lsqt_state *st, const lsqt_slice_est *e, int s, int detail);
/* The same object's fields without its closing brace (more fields may follow). With bands,
 * e is est + s of lsqt_estimates (e[b * n_slices] is band b's) and R, T, delta_T, their
 * errors and max_rel_err are lists of one value per band. */
void lsqt_json_slice_fields(FILE *f, const lsqt_state *st, const lsqt_slice_est *e, int s, int detail);

#ifdef __cplusplus
}
#endif
#endif
