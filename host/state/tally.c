#include "lsqt/tally.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "lsqt/util.h"

lsqt_est lsqt_batch_estimate_n(const lsqt_u128 *sums, size_t stride, const uint64_t nbatch[LSQT_BATCHES], double scale)
{
    lsqt_est r = {0.0, NAN};
    uint64_t total_paths = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) total_paths += nbatch[b];
    if (total_paths == 0) return r;
    double total = 0.0;
    for (int b = 0; b < LSQT_BATCHES; b++) total += lsqt_u128_to_double(sums[(size_t)b * stride]);
    double mean = total / scale / (double)total_paths;
    /* Batches of unequal size: var(mean) = B/(B-1) sum (S_b - n_b mean)^2 / N^2 over the
     * B batches that hold paths. */
    double ss = 0.0;
    int used = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) {
        uint64_t nb = nbatch[b];
        if (nb == 0) continue;
        double dev = lsqt_u128_to_double(sums[(size_t)b * stride]) / scale - (double)nb * mean;
        ss += dev * dev;
        used++;
    }
    r.mean = mean;
    r.err = used > 1 ? sqrt(ss * used / (used - 1)) / (double)total_paths : NAN;
    return r;
}

int lsqt_tally_flags_error(uint32_t flags, char *err, size_t errcap)
{
    if (!(flags & LSQT_FLAG_OVERFLOW)) return 0;
    /* A clamped or wrapped tally would be a silently biased result. */
    snprintf(err, errcap,
             "a path contribution exceeded the tally range (2^44 = 1.8e13 per event, 2^88 per sum): "
             "the result would be biased, so nothing is written");
    return 1;
}

lsqt_work lsqt_work_totals(const lsqt_state *st)
{
    lsqt_work w = {(double)st->paths * st->n_slices, 0.0, 0.0, 0.0};
    for (size_t i = 0; i < lsqt_state_scalar_count(st) / LSQT_T_COUNT; i++) { /* every band's work */
        const lsqt_u128 *sc = st->scalars + i * LSQT_T_COUNT;
        w.layer_events += lsqt_u128_to_double(sc[LSQT_T_LAYER_EVENTS]);
        w.medium_events += lsqt_u128_to_double(sc[LSQT_T_MEDIUM_EVENTS]);
        w.nee_evaluations += lsqt_u128_to_double(sc[LSQT_T_NEE_VERTICES]) * st->n_wi;
    }
    return w;
}

/* Band view's slice estimates into out[0 .. n_slices), their f in fblock. */
static void band_estimates(const lsqt_state *st, lsqt_slice_est *out, lsqt_est *fblock)
{
    const size_t nw = (size_t)st->n_wi;
    uint64_t nb[LSQT_BATCHES];
    lsqt_state_batch_counts(st, nb);
    for (int s = 0; s < st->n_slices; s++) {
        lsqt_slice_est *e = &out[s];
        e->theta_o = st->theta_o[s];
        e->paths = st->paths;
        const lsqt_u128 *sc = st->scalars + (size_t)s * LSQT_BATCHES * LSQT_T_COUNT;
        e->R = lsqt_batch_estimate_n(sc + LSQT_T_R, LSQT_T_COUNT, nb, LSQT_FIX_SCALE);
        e->T = lsqt_batch_estimate_n(sc + LSQT_T_T, LSQT_T_COUNT, nb, LSQT_FIX_SCALE);
        e->delta_T = lsqt_batch_estimate_n(sc + LSQT_T_DELTA_T, LSQT_T_COUNT, nb, LSQT_FIX_SCALE);
        for (int b = 0; b < LSQT_BATCHES; b++) {
            const lsqt_u128 *x = sc + (size_t)b * LSQT_T_COUNT;
            e->cut += x[LSQT_T_CUT].lo;
            e->layer_events += lsqt_u128_to_double(x[LSQT_T_LAYER_EVENTS]);
            e->medium_events += lsqt_u128_to_double(x[LSQT_T_MEDIUM_EVENTS]);
            e->nee_evaluations += lsqt_u128_to_double(x[LSQT_T_NEE_VERTICES]) * (double)nw;
        }
        if (st->paths) e->layer_events /= (double)st->paths, e->medium_events /= (double)st->paths;
        e->f = fblock + (size_t)s * nw;
        const lsqt_u128 *nee = st->nee + (size_t)s * LSQT_BATCHES * nw;
        for (size_t k = 0; k < nw; k++) {
            lsqt_est c = lsqt_batch_estimate_n(nee + k, nw, nb, LSQT_FIX_SCALE);
            double cz = fabs((double)st->wi[((size_t)s * nw + k) * 4 + 2]);
            e->f[k].mean = c.mean / cz; /* RAW wants the BSDF without the cosine */
            e->f[k].err = c.err / cz;
            if (!isfinite(e->f[k].mean)) {
                e->n_nonfinite++;
            } else if (isnan(e->f[k].err)) {
                e->max_rel_err = NAN;
            } else if (e->f[k].mean > 0 && !isnan(e->max_rel_err)) {
                double rel = e->f[k].err / e->f[k].mean;
                if (rel > e->max_rel_err) e->max_rel_err = rel;
            }
        }
    }
}

lsqt_slice_est *lsqt_estimates(const lsqt_state *st)
{
    const size_t nb = (size_t)lsqt_state_bands(st), ns = (size_t)st->n_slices;
    lsqt_slice_est *out = calloc(nb * ns + 1, sizeof *out);
    /* one block holds every f; out[0].f is its start (lsqt_estimates_free) */
    lsqt_est *f = calloc(nb * ns * (size_t)st->n_wi + 1, sizeof *f);
    if (!out || !f) {
        free(out);
        free(f);
        return NULL;
    }
    out[0].f = f;
    for (size_t b = 0; b < nb; b++) {
        const lsqt_state view = lsqt_state_band(st, (int)b);
        band_estimates(&view, out + b * ns, f + b * ns * (size_t)st->n_wi);
    }
    return out;
}

void lsqt_estimates_free(lsqt_slice_est *e, int n_slices)
{
    (void)n_slices;
    if (!e) return;
    free(e[0].f);
    free(e);
}
