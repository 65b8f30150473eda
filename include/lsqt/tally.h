/* Host reduction: integer tallies to estimates with standard errors (batch means). */
#ifndef LSQT_TALLY_H
#define LSQT_TALLY_H

#include "lsqt/state.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Below LSQT_MIN_ERR_PATHS paths (one chunk) a single batch holds them all and the batch means give
 * no standard error: errors are NaN then (printed "n/a", JSON null; they were +-inf).
 * A target error is judged only from LSQT_STOP_ERR_PATHS on, where every batch holds 2
 * chunks: an error from a few batches is too noisy to stop a run on. */
#define LSQT_MIN_ERR_PATHS ((uint64_t)LSQT_CHUNK + 1)
#define LSQT_STOP_ERR_PATHS ((uint64_t)2 * LSQT_CHUNK * LSQT_BATCHES)

typedef struct lsqt_est {
    double mean; /* per path */
    double err;  /* one standard error of the mean; NaN below LSQT_MIN_ERR_PATHS paths */
} lsqt_est;

typedef struct lsqt_slice_est {
    double theta_o;
    uint64_t paths;
    lsqt_est R, T, delta_T;
    uint64_t cut;        /* paths stopped by the safety cap */
    lsqt_est *f;         /* n_wi: non-cosine-weighted BSDF (1/sr) at each wi */
    double max_rel_err;  /* largest err/mean over the finite, positive f (NaN: no errors yet) */
    int n_nonfinite;     /* f values that are not finite (never written to RAW) */
    double layer_events, medium_events; /* scattering events per path (work counters) */
    double nee_evaluations;             /* next-event evaluations in all (vertices x n_wi) */
} lsqt_slice_est;

/* The work counters of a state, summed over slices and batches: paths (per slice times
 * slices), scattering events on layers and in media, and next-event evaluations (vertices
 * evaluated towards all directions, times n_wi). */
typedef struct lsqt_work {
    double paths, layer_events, medium_events, nee_evaluations;
} lsqt_work;
lsqt_work lsqt_work_totals(const lsqt_state *st);

/* Estimates of every slice, band after band (n_bands x n_slices; est[b * n_slices + s]),
 * freed with lsqt_estimates_free. */
lsqt_slice_est *lsqt_estimates(const lsqt_state *st);
void lsqt_estimates_free(lsqt_slice_est *e, int n_slices);

/* Ratio estimator over the LSQT_BATCHES batches: sums[b * stride] holds batch b's
 * fixed-point (or count when scale is 1) sum, nbatch[b] the paths of batch b (over all
 * the ranges a state holds: lsqt_state_batch_counts). */
lsqt_est lsqt_batch_estimate_n(const lsqt_u128 *sums, size_t stride, const uint64_t nbatch[LSQT_BATCHES],
                               double scale);

/* 1 with err filled when the device flags mean the tallies cannot be trusted (a
 * contribution or a sum beyond the 128-bit range): the run must fail. */
int lsqt_tally_flags_error(uint32_t flags, char *err, size_t errcap);

#ifdef __cplusplus
}
#endif
#endif
