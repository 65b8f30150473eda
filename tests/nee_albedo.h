/* Albedo from the point estimates of a simulated state (shared by the end-to-end tests). */
#ifndef LSQT_TESTS_NEE_ALBEDO_H
#define LSQT_TESTS_NEE_ALBEDO_H

#include <math.h>

#include "lsqt/state.h"
#include "lsqt/tally.h"

/* The NEE albedo A = integral of f cos over one hemisphere by the direction rule (each
 * direction stands for 2 pi / n sr of the upper hemisphere, 4 pi / n when the set covers
 * the sphere), minus c times the analog tally `which` (LSQT_T_R or LSQT_T_T; c = 0 or 1), with its batch-means standard
 * error: per batch, A_b - c R_b from the same paths, so the covariance of the two
 * estimators is in the error (they share paths, and the difference is far less noisy
 * than either). */
static inline double nee_sqr(double x) { return x * x; }

static inline lsqt_est nee_albedo_minus(const lsqt_state *st, int s, int upper, double c, int which)
{
    const size_t nw = (size_t)st->n_wi;
    const double w = (st->transmits ? 4.0 : 2.0) * 3.14159265358979323846 / st->n_wi, n = (double)st->paths;
    double d[LSQT_BATCHES], total = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) {
        const lsqt_u128 *nee = st->nee + ((size_t)s * LSQT_BATCHES + (size_t)b) * nw;
        double a = 0;
        for (size_t k = 0; k < nw; k++)
            if ((st->wi[((size_t)s * nw + k) * 4 + 2] > 0) == upper)
                a += w * lsqt_u128_to_double(nee[k]); /* cosine included */
        double r = lsqt_u128_to_double(st->scalars[((size_t)s * LSQT_BATCHES + (size_t)b) * LSQT_T_COUNT + which]);
        d[b] = (a - c * r) / LSQT_FIX_SCALE;
        total += d[b];
    }
    lsqt_est e = {total / n, 0};
    double ss = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) ss += nee_sqr(d[b] - (double)lsqt_batch_paths(st->paths, b) * e.mean);
    e.err = sqrt(ss * LSQT_BATCHES / (LSQT_BATCHES - 1)) / n;
    return e;
}

#endif
