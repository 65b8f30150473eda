/* A statistical test's family of checks over the batch means of a run (shared by
 * test_power_media and test_media_stacks): Student-t thresholds for a family-wise error
 * rate, the batch sums of the RAW values, ratio estimates with their batch-means errors,
 * and a run at chosen incident directions.
 *
 * A section counts its checks in a dry pass (count_only), sets ZD and ZA from the counts
 * (z_family), then runs for real. Batch-means errors over LSQT_BATCHES = 32 batches make
 * each z-score Student t with 31 degrees of freedom. */
#ifndef LSQT_TESTS_FAMILY_STATS_H
#define LSQT_TESTS_FAMILY_STATS_H

#include "cl_fixture.h"

#ifndef PI
#define PI 3.14159265358979323846
#endif
#define NB LSQT_BATCHES

/* ------------------------------------------------------------ statistics */

/* Two-sided tail of Student's t with nu degrees of freedom beyond |t|, by Simpson's rule
 * on the density in u = 1/x (the density has a polynomial tail). */
static inline double t_tail2(double t, int nu)
{
    const double c = exp(lgamma((nu + 1) / 2.0) - lgamma(nu / 2.0)) / sqrt(nu * PI);
    /* int_t^inf c (1 + x^2/nu)^(-(nu+1)/2) dx = int_0^{1/t} c (1 + 1/(u^2 nu))^(-(nu+1)/2) / u^2 du */
    const int n = 4000;
    const double h = (1.0 / t) / n;
    double s = 0.0;
    for (int i = 1; i <= n; i++) {
        const double u = i * h;
        const double f = c * pow(1.0 + 1.0 / (u * u * nu), -(nu + 1) / 2.0) / (u * u);
        s += f * (i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return 2.0 * s * h / 3.0;
}

/* |t| whose two-sided tail (31 degrees of freedom) is alpha / n_checks */
static inline double z_family(int n_checks, double alpha)
{
    double lo = 1.0, hi = 40.0, p = alpha / n_checks;
    for (int i = 0; i < 60; i++) {
        double mid = 0.5 * (lo + hi);
        if (t_tail2(mid, NB - 1) > p)
            lo = mid;
        else
            hi = mid;
    }
    return hi;
}

/* The section's thresholds: half the family's 1e-3 for the checks of single directions,
 * half for the aggregates (means over directions, R, T, delta_T), each Bonferroni over
 * its count (counted by a dry pass of the section). */
static double ZD, ZA;
static int n_dir, n_agg;
static uint64_t seed_offset; /* argv[2]: other seeds, to check that the tolerances hold */

/* The dry pass of SECTION (its argument 1: count the checks, run nothing), then ZD and ZA
 * from the counts, printed under NAME. */
static inline void family_plan(const char *name, void (*section)(int))
{
    section(1);
    ZD = z_family(n_dir, 5e-4), ZA = z_family(n_agg, 5e-4);
    printf("%s: %d checks of single directions, |z| <= %.2f; %d aggregates, |z| <= %.2f (Student t, 31 dof, "
           "family 1e-3)\n",
           name, n_dir, ZD, n_agg, ZA);
}

/* ---------------------------------------------------------------- helpers */

/* The direction the device uses: the state's float one, normalised again in double for a
 * double kernel (host/sim/session.c), as the RAW divides by the float |z|. */
static inline void wi_of(const lsqt_state *st, int s, int k, double v[3])
{
    const float *p = st->wi + ((size_t)s * (size_t)st->n_wi + (size_t)k) * 4;
    v[0] = p[0], v[1] = p[1], v[2] = p[2];
    if (st->use_double) {
        const double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        v[0] /= len, v[1] /= len, v[2] /= len;
    }
}

/* |z| of direction k as the host divides by it (the state's float) */
static inline double host_az(const lsqt_state *st, int s, int k)
{
    return fabs((double)st->wi[((size_t)s * (size_t)st->n_wi + (size_t)k) * 4 + 2]);
}

/* Batch b's sum of the RAW value at (s, k) */
static inline double batch_f(const lsqt_state *st, int s, int b, int k)
{
    const lsqt_u128 *nee = st->nee + (size_t)s * NB * (size_t)st->n_wi;
    double z = st->wi[((size_t)s * (size_t)st->n_wi + (size_t)k) * 4 + 2];
    return lsqt_u128_to_double(nee[(size_t)b * (size_t)st->n_wi + (size_t)k]) / LSQT_FIX_SCALE / fabs(z);
}

static inline double batch_scalar(const lsqt_state *st, int s, int b, int q)
{
    return lsqt_u128_to_double(st->scalars[((size_t)s * NB + (size_t)b) * LSQT_T_COUNT + (size_t)q]) / LSQT_FIX_SCALE;
}

/* sum(y) / sum(x) over the batches with its linearised batch-means error */
static inline lsqt_est batch_ratio(const double *y, const double *x)
{
    double sy = 0.0, sx = 0.0, ss = 0.0;
    for (int b = 0; b < NB; b++) sy += y[b], sx += x[b];
    lsqt_est r = {sy / sx, 0.0};
    for (int b = 0; b < NB; b++) ss += (y[b] - r.mean * x[b]) * (y[b] - r.mean * x[b]);
    r.err = sqrt(ss * NB / (NB - 1)) / sx;
    return r;
}

/* Mean over the directions ks of f/ref, per path (x = paths) or per unit of *den */
static inline lsqt_est ratio_over(const lsqt_state *st, int s, const int *ks, int n, const double *ref,
                                  const double *den, double scale)
{
    double y[NB], x[NB];
    for (int b = 0; b < NB; b++) {
        y[b] = 0.0;
        for (int i = 0; i < n; i++) y[b] += batch_f(st, s, b, ks[i]) / ref[ks[i]];
        y[b] *= scale / n;
        x[b] = den ? den[b] : (double)lsqt_batch_paths(st->paths, b);
    }
    return batch_ratio(y, x);
}

/* Simulates text at the slices deg with the given directions (float x, y, z per row), or
 * n_wi spread ones when dirs is NULL. */
static inline lsqt_slice_est *run_dirs(const char *text, int n_slices, const double *deg, int n_wi,
                                       const double (*dirs)[3], uint64_t paths, uint64_t seed, int use_double,
                                       lsqt_state *st)
{
    lsqt_assembly a;
    fixture_state(text, n_slices, n_wi, seed, use_double, &a, st);
    for (int s = 0; s < n_slices; s++) {
        st->theta_o[s] = deg[s] * PI / 180.0;
        float *w = st->wi + (size_t)s * (size_t)n_wi * 4;
        if (!dirs) {
            lsqt_wi_spread(n_wi, st->transmits, w);
            continue;
        }
        for (int k = 0; k < n_wi; k++) {
            w[4 * k] = (float)dirs[k][0], w[4 * k + 1] = (float)dirs[k][1], w[4 * k + 2] = (float)dirs[k][2];
            w[4 * k + 3] = 0.0f;
        }
    }
    st->seed += seed_offset;
    fixture_simulate(&a, st, paths);
    CHECK(st->flags == 0, "flags %u", st->flags);
    return lsqt_estimates(st);
}

#endif
