/* Goodness of fit of a sampler against its density: the shared part of the model tests
 * (test_phases, test_ms_models; a new model's test uses it the same way).
 *
 * - The family: every p-value of a test program (gof_record), judged together at the end
 *   (gof_verdict), Bonferroni corrected: reject below GOF_FAMILY_ALPHA / (the family's
 *   size); and the power self-checks (gof_skew): a skewed copy of the samples that the
 *   test must reject wherever its noncentrality says it can.
 * - Bins (gof_bins): a test's grid of bins, each a rectangle in (mu, phi) with a
 *   direction for every point of it; gof_grid is the usual one, GOF_NMU x GOF_NPHI bins
 *   about an axis (mu = cos of the angle to it) with edges at quantiles of
 *   (1 - GOF_MIX) uniform + GOF_MIX a pilot run's samples (quantile_bins.h), so bins
 *   crowd where the lobe is, and edges forced onto the density's kinks.
 * - The expected counts: a deterministic density (gof_density: directions to value and
 *   pdf) integrated over every bin by an adaptive Gauss-Legendre rule (gof_integrate).
 * - The statistic: the pooled chi-square of weighted counts (gof_chi2), the weighted
 *   sampling variance r E (r = sum w^2 / sum w) plus the expectation's own variance.
 * - The driver (gof_fit of a gof_spec): a sampler (gof_sampler) and its density on a gof_grid, 10^6
 *   samples: sanity of every sample (unit vectors, finite weights in the grid, weight =
 *   value / pdf), the density's integral, chi-square on the fine and on 4 x 4 coarse bins
 *   and, where weights vary, the total, each recorded in the family; and a 2 % tilt of
 *   the samples along mu recorded as a skew.
 * p-values from stats.h; a failed expectation is a CHECK (check.h). */
#ifndef LSQT_TESTS_GOF_H
#define LSQT_TESTS_GOF_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "quadrature.h"
#include "quantile_bins.h"
#include "stats.h"

#define GOF_PI 3.14159265358979323846
#define GOF_FAMILY_ALPHA 1e-3 /* the family's false-alarm rate */
#define GOF_MIN_EFF 25.0      /* bins expecting fewer effective samples are pooled */
#define GOF_SKEW 0.02         /* the power self-check's skew */
#define GOF_NMU 16            /* gof_grid: rows in mu */
#define GOF_NPHI 16           /* gof_grid: columns in phi */
#define GOF_NCELL (GOF_NMU * GOF_NPHI)
#define GOF_COARSE 4          /* fine bins per coarse bin side */
#define GOF_NCOARSE (GOF_NCELL / (GOF_COARSE * GOF_COARSE))
#define GOF_NPILOT 40000      /* pilot samples that place the edges */
#define GOF_MIX 0.6           /* the pilot's share of the edges' mixture */
#define GOF_QA 8              /* gof_integrate: Gauss nodes per rectangle side */
#define GOF_MAX_LEVEL 7       /* gof_integrate: the deepest refinement */

/* ---------------------------------------------------------------- the family */

#define GOF_MAX_TESTS 512
#define GOF_MAX_SKEWS 256
static struct {
    char name[200];
    double p;
} gof_tests[GOF_MAX_TESTS];
static int gof_n_tests = 0;
static struct {
    char name[200];
    double p, lambda;
    int required;
} gof_skews[GOF_MAX_SKEWS];
static int gof_n_skews = 0;

/* A p-value of the family. */
static inline void gof_record(const char *name, double p)
{
    if (gof_n_tests < GOF_MAX_TESTS) {
        snprintf(gof_tests[gof_n_tests].name, sizeof gof_tests[gof_n_tests].name, "%s", name);
        gof_tests[gof_n_tests].p = p;
    }
    gof_n_tests++;
}

/* A skewed copy's smallest p-value p, its noncentrality lambda, and whether the test has
 * the power to reject it (then it must). */
static inline void gof_skew(const char *name, double p, double lambda, int required)
{
    if (gof_n_skews < GOF_MAX_SKEWS) {
        snprintf(gof_skews[gof_n_skews].name, sizeof gof_skews[gof_n_skews].name, "%s", name);
        gof_skews[gof_n_skews].p = p, gof_skews[gof_n_skews].lambda = lambda;
        gof_skews[gof_n_skews].required = required;
        gof_n_skews++;
    }
}

/* The verdict: every p-value recorded at least GOF_FAMILY_ALPHA / size (size: the family
 * of a full run, or 0 for the number recorded), every skew with the power for it below
 * that; prints the summary (skew: what the skew was). Returns the threshold. */
static inline double gof_verdict(int size, const char *skew)
{
    const double thr = GOF_FAMILY_ALPHA / (size > 0 ? size : gof_n_tests);
    double pmin = 1;
    int imin = 0, failed = 0, below01 = 0, below05 = 0;
    for (int i = 0; i < gof_n_tests && i < GOF_MAX_TESTS; i++) {
        CHECK(gof_tests[i].p >= thr, "%s: p = %.3g below %.3g", gof_tests[i].name, gof_tests[i].p, thr);
        failed += gof_tests[i].p < thr;
        below01 += gof_tests[i].p < 0.01, below05 += gof_tests[i].p < 0.05;
        if (gof_tests[i].p < pmin) pmin = gof_tests[i].p, imin = i;
    }
    CHECK(gof_n_tests <= GOF_MAX_TESTS, "%d tests", gof_n_tests);
    int req = 0, caught = 0, other = 0, other_caught = 0;
    double pmax = 0;
    for (int i = 0; i < gof_n_skews; i++) {
        if (gof_skews[i].required) {
            req++, caught += gof_skews[i].p < thr, pmax = fmax(pmax, gof_skews[i].p);
            CHECK(gof_skews[i].p < thr, "the 2 %% skewed sampler passed: %s, smallest p = %.3g (lambda %.0f)",
                  gof_skews[i].name, gof_skews[i].p, gof_skews[i].lambda);
        } else {
            other++, other_caught += gof_skews[i].p < thr;
            printf("skew without the power for it (lambda %.0f): %s, p = %.3g\n", gof_skews[i].lambda,
                   gof_skews[i].name, gof_skews[i].p);
        }
    }
    printf("%d tests, reject below p = %.3g (family %g): smallest p %.3g (%s), %d rejected; p < 0.05: %d, p < 0.01:"
           " %d (uniform: %.1f, %.1f)\n",
           gof_n_tests, thr, GOF_FAMILY_ALPHA, pmin, gof_n_tests ? gof_tests[imin].name : "", failed, below05, below01,
           0.05 * gof_n_tests, 0.01 * gof_n_tests);
    if (gof_n_skews)
        printf("2 %% skew (%s): rejected in %d of %d cases with the power for it (largest p %.2g), %d of %d others\n",
               skew, caught, req, pmax, other_caught, other);
    return thr;
}

/* ---------------------------------------------------------------- bins */

/* A test's bins: n of them, bin c the rectangle r = [m0, m1] x [p0, p1] in (mu, phi) of
 * its grid g, dir the direction at (mu, phi) of bin c. */
typedef struct {
    int n;
    const void *g;
    void (*rect)(const void *g, int c, double r[4]);
    void (*dir)(const void *g, int c, double mu, double phi, double d[3]);
} gof_bins;

/* q x q Gauss nodes of the rectangle [m0, m1] x [p0, p1] of bin c: directions d (x, y, z,
 * 0 as floats, the kernels' form) and weights w (solid angle). Returns q^2. */
static inline int gof_rect_nodes(const gof_bins *b, int c, double m0, double m1, double p0, double p1, int q, float *d,
                                 double *w)
{
    static double gx[16], gw[16];
    static int gq = 0;
    if (gq != q) gauss_legendre(q, gx, gw), gq = q;
    int n = 0;
    for (int i = 0; i < q; i++)
        for (int j = 0; j < q; j++, n++) {
            double mu = 0.5 * (m0 + m1) + 0.5 * (m1 - m0) * gx[i], phi = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * gx[j], x[3];
            b->dir(b->g, c, mu, phi, x);
            d[4 * n] = (float)x[0], d[4 * n + 1] = (float)x[1], d[4 * n + 2] = (float)x[2], d[4 * n + 3] = 0;
            w[n] = 0.25 * (m1 - m0) * (p1 - p0) * gw[i] * gw[j];
        }
    return n;
}

/* A deterministic density: out[2 i], out[2 i + 1] = its value and pdf towards the n
 * directions dirs[4 i .. 4 i + 2]. */
typedef void (*gof_density)(void *ctx, const float *dirs, size_t n, float *out);

/* The density integrated over every bin, adaptively: a rectangle's GOF_QA x GOF_QA rule
 * against its four quarters', accepted when they agree to 2 % of the bin's sampling sigma
 * for N samples of mean weight-square-over-weight rg (sqrt(rg N I) / N, scaled by the
 * square root of the rectangle's share of the bin, so that the errors add up to at most
 * that) or to 1e-6 relative (float), else the quarters are refined, down to
 * GOF_MAX_LEVEL. I[c] = the accepted quarters' sums, IQ[c] = their |differences| (the
 * error estimate; conservative, it is the coarser rule's). Probability units. A
 * non-finite value counts as 1e30 (the fit fails, loudly), and a refinement past 200000
 * rectangles stops (a broken density: the fit fails anyway). */
static inline void gof_integrate(const gof_bins *bins, gof_density f, void *ctx, double N, double rg, double *I,
                                 double *IQ)
{
    typedef struct {
        int c, level;
        double m0, m1, p0, p1;
    } rect_t;
    const int nq = GOF_QA * GOF_QA, per = 5 * nq;
    int np = bins->n;
    rect_t *pend = malloc((size_t)np * sizeof *pend);
    double *sig = malloc((size_t)bins->n * sizeof *sig);
    for (int c = 0; c < bins->n; c++) {
        double r[4];
        bins->rect(bins->g, c, r);
        rect_t x = {c, 0, r[0], r[1], r[2], r[3]};
        pend[c] = x, sig[c] = -1, I[c] = IQ[c] = 0;
    }
    while (np > 0) {
        float *dirs = malloc((size_t)np * per * 16), *fp = malloc((size_t)np * per * 8);
        double *wt = malloc((size_t)np * per * sizeof *wt);
        for (int r = 0; r < np; r++) {
            const rect_t *x = &pend[r];
            double mm = 0.5 * (x->m0 + x->m1), pm = 0.5 * (x->p0 + x->p1);
            const double box[5][4] = {{x->m0, x->m1, x->p0, x->p1}, {x->m0, mm, x->p0, pm}, {mm, x->m1, x->p0, pm},
                                      {x->m0, mm, pm, x->p1}, {mm, x->m1, pm, x->p1}};
            for (int b = 0; b < 5; b++) {
                size_t o = (size_t)r * per + (size_t)b * nq;
                gof_rect_nodes(bins, x->c, box[b][0], box[b][1], box[b][2], box[b][3], GOF_QA, dirs + 4 * o, wt + o);
            }
        }
        f(ctx, dirs, (size_t)np * per, fp);
        /* the bins' sigma, from the first (whole-bin) pass */
        for (int r = 0; r < np; r++)
            if (sig[pend[r].c] < 0) {
                double v = 0;
                for (int k = 0; k < nq; k++) v += wt[(size_t)r * per + k] * fp[2 * ((size_t)r * per + k)];
                sig[pend[r].c] = sqrt(rg * fmax(N * v, 1.0)) / N;
            }
        int nn = 0;
        rect_t *next = malloc((size_t)np * 4 * sizeof *next);
        for (int r = 0; r < np; r++) {
            const rect_t *x = &pend[r];
            double br[4];
            bins->rect(bins->g, x->c, br);
            double share = (x->m1 - x->m0) * (x->p1 - x->p0) / ((br[1] - br[0]) * (br[3] - br[2]));
            double ip = 0, sum = 0;
            int bad = 0;
            for (int b = 0; b < 5; b++)
                for (int k = 0; k < nq; k++) {
                    size_t q = (size_t)r * per + (size_t)b * nq + k;
                    double v = wt[q] * fp[2 * q];
                    if (!isfinite(v)) v = 1e30, bad = 1;
                    if (b) sum += v;
                    else ip += v;
                }
            double diff = fabs(sum - ip);
            if (diff <= 0.02 * sig[x->c] * sqrt(share) || diff <= 1e-6 * fabs(sum) || x->level >= GOF_MAX_LEVEL || bad ||
                np > 200000) {
                I[x->c] += sum, IQ[x->c] += diff;
                continue;
            }
            double mm = 0.5 * (x->m0 + x->m1), pm = 0.5 * (x->p0 + x->p1);
            rect_t q0 = {x->c, x->level + 1, x->m0, mm, x->p0, pm}, q1 = {x->c, x->level + 1, mm, x->m1, x->p0, pm};
            rect_t q2 = {x->c, x->level + 1, x->m0, mm, pm, x->p1}, q3 = {x->c, x->level + 1, mm, x->m1, pm, x->p1};
            next[nn++] = q0, next[nn++] = q1, next[nn++] = q2, next[nn++] = q3;
        }
        free(dirs), free(fp), free(wt), free(pend);
        pend = next, np = nn;
    }
    free(pend), free(sig);
}

/* ---------------------------------------------------------------- the statistic */

/* Pooled chi-square of observed O (sum of the weights in each of nc bins), S2 (sum of
 * their squares) against expected E with the expectation's variance V: sum (O - E)^2 /
 * (r E + V), r = S2 / O (rg, the mean of w^2 / w, in an empty bin), so r E is the
 * weighted sampling variance; bins with fewer than GOF_MIN_EFF effective samples (E / rg)
 * go into one pool (with almost nothing expected, a few observations there must not
 * divide by 0). Returns the statistic, sets *dof (the bins used). With shift (another
 * observation, e.g. a skewed copy), also *lambda: the noncentrality of shift - O in the
 * same metric. */
static inline double gof_chi2(int nc, const double *O, const double *S2, const double *E, const double *V, double rg,
                              const double *shift, int *dof, double *lambda)
{
    double chi2 = 0, lam = 0, po = 0, pe = 0, ps = 0, pv = 0, pd = 0;
    int k = 0;
    for (int c = 0; c < nc; c++) {
        double d = shift ? shift[c] - O[c] : 0;
        if (E[c] / rg < GOF_MIN_EFF) {
            po += O[c], pe += E[c], ps += S2[c], pv += V[c], pd += d;
            continue;
        }
        double r = O[c] > 0 ? S2[c] / O[c] : rg, v = r * E[c] + V[c];
        chi2 += (O[c] - E[c]) * (O[c] - E[c]) / v, lam += d * d / v;
        k++;
    }
    if (pe / rg >= 1.0 || po > 0) {
        double r = po > 0 ? ps / po : rg, v = r * fmax(pe, rg) + pv;
        chi2 += (po - pe) * (po - pe) / v, lam += pd * pd / v;
        k++;
    }
    *dof = k;
    if (lambda) *lambda = lam;
    return chi2;
}

/* ---------------------------------------------------------------- gof_grid */

/* GOF_NMU x GOF_NPHI bins about an axis: mu = cos(angle to the axis) in lo .. 1 (edges
 * mu[]), phi the azimuth from u towards v (edges ph[]); bin c = row * GOF_NPHI + column. */
typedef struct {
    double axis[3], u[3], v[3], lo, hi;
    double mu[GOF_NMU + 1], ph[GOF_NPHI + 1];
} gof_grid;

static inline void gof_grid_frame(gof_grid *g, const double a[3])
{
    double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int i = 0; i < 3; i++) g->axis[i] = a[i] / n;
    double t[3] = {fabs(g->axis[0]) < 0.9 ? 1.0 : 0.0, fabs(g->axis[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    double d = t[0] * g->axis[0] + t[1] * g->axis[1] + t[2] * g->axis[2], un = 0;
    for (int i = 0; i < 3; i++) g->u[i] = t[i] - d * g->axis[i], un += g->u[i] * g->u[i];
    for (int i = 0; i < 3; i++) g->u[i] /= sqrt(un);
    const double *x = g->axis, *y = g->u;
    g->v[0] = x[1] * y[2] - x[2] * y[1], g->v[1] = x[2] * y[0] - x[0] * y[2], g->v[2] = x[0] * y[1] - x[1] * y[0];
}

static inline void gof_grid_coords(const gof_grid *g, const float *d, double *mu, double *phi)
{
    double x = d[0], y = d[1], z = d[2], n = sqrt(x * x + y * y + z * z);
    x /= n, y /= n, z /= n;
    double m = x * g->axis[0] + y * g->axis[1] + z * g->axis[2];
    *mu = m > 1 ? 1 : m < -1 ? -1 : m;
    double p = atan2(x * g->v[0] + y * g->v[1] + z * g->v[2], x * g->u[0] + y * g->u[1] + z * g->u[2]);
    *phi = p < 0 ? p + 2 * GOF_PI : p;
}

static inline void gof_grid_dir(const void *gv, int c, double mu, double phi, double d[3])
{
    const gof_grid *g = gv;
    (void)c;
    double s = sqrt(fmax(0.0, 1 - mu * mu)), cp = cos(phi), sp = sin(phi);
    for (int i = 0; i < 3; i++) d[i] = mu * g->axis[i] + s * (cp * g->u[i] + sp * g->v[i]);
}

static inline void gof_grid_rect(const void *gv, int c, double r[4])
{
    const gof_grid *g = gv;
    int i = c / GOF_NPHI, j = c % GOF_NPHI;
    r[0] = g->mu[i], r[1] = g->mu[i + 1], r[2] = g->ph[j], r[3] = g->ph[j + 1];
}

static inline gof_bins gof_grid_bins(const gof_grid *g)
{
    gof_bins b = {GOF_NCELL, g, gof_grid_rect, gof_grid_dir};
    return b;
}

/* The bin of a direction, -1 outside the grid's mu range. */
static inline int gof_grid_cell(const gof_grid *g, const float *d)
{
    double mu, phi;
    gof_grid_coords(g, d, &mu, &phi);
    if (mu < g->lo - 1e-6 || mu > g->hi + 1e-6) return -1;
    mu = fmin(fmax(mu, g->lo), g->hi);
    int i = find_bin(g->mu, GOF_NMU, mu), j = find_bin(g->ph, GOF_NPHI, phi);
    return i * GOF_NPHI + j;
}

/* The coarse bin (GOF_COARSE x GOF_COARSE fine ones) of fine bin c. */
static inline int gof_grid_coarse(int c)
{
    return (c / GOF_NPHI / GOF_COARSE) * (GOF_NPHI / GOF_COARSE) + (c % GOF_NPHI) / GOF_COARSE;
}

static inline int gof_dbl_cmp(const void *a, const void *b)
{
    double d = *(const double *)a - *(const double *)b;
    return d < 0 ? -1 : d > 0;
}

/* Moves the interior edge nearest to x onto it (where x is inside the range). */
static inline void gof_force_edge(double *edges, int nb, double x)
{
    if (!(x > edges[0] + 1e-3 && x < edges[nb] - 1e-3)) return;
    int k = 1;
    for (int i = 2; i < nb; i++)
        if (fabs(edges[i] - x) < fabs(edges[k] - x)) k = i;
    edges[k] = x;
    qsort(edges + 1, (size_t)nb - 1, sizeof *edges, gof_dbl_cmp);
}

/* The grid about axis for mu in lo .. 1, its edges from the n pilot samples s (x, y, z,
 * weight) and forced onto fmu[0..nfm) and fph[0..nfp). */
static inline void gof_grid_make(gof_grid *g, const double axis[3], double lo, const float *s, int n, int nfm,
                                 const double *fmu, int nfp, const double *fph)
{
    gof_grid_frame(g, axis);
    g->lo = lo, g->hi = 1;
    xw *v = malloc((size_t)n * sizeof *v);
    int k = 0;
    for (int i = 0; i < n; i++) {
        double mu, phi;
        gof_grid_coords(g, s + 4 * i, &mu, &phi);
        if (s[4 * i + 3] > 0 && mu >= g->lo) v[k].x = mu, v[k++].w = s[4 * i + 3];
    }
    breakpoints(v, k, g->lo, g->hi, GOF_NMU, GOF_MIX, g->mu);
    k = 0;
    for (int i = 0; i < n; i++) {
        double mu, phi;
        gof_grid_coords(g, s + 4 * i, &mu, &phi);
        if (s[4 * i + 3] > 0 && mu >= g->lo) v[k].x = phi, v[k++].w = s[4 * i + 3];
    }
    breakpoints(v, k, 0.0, 2 * GOF_PI, GOF_NPHI, GOF_MIX, g->ph);
    for (int i = 0; i < nfm; i++) gof_force_edge(g->mu, GOF_NMU, fmu[i]);
    for (int i = 0; i < nfp; i++) gof_force_edge(g->ph, GOF_NPHI, fph[i]);
    free(v);
}

/* The fraction of the (sorted) pilot values mu below the direction's: about uniform on
 * 0 .. 1 under the sampler, whatever the lobe's shape. */
static inline double gof_skew_c(const gof_grid *g, const double *pmu, int n, const float *d)
{
    double mu, phi;
    gof_grid_coords(g, d, &mu, &phi);
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (pmu[mid] < mu) lo = mid + 1;
        else hi = mid;
    }
    return n > 0 ? (double)lo / n : 0.5;
}

/* ---------------------------------------------------------------- the driver */

/* A sampler: n samples (x, y, z, weight) into out[4 n], from the seed. */
typedef void (*gof_sampler)(void *ctx, unsigned seed, size_t n, float *out);

/* A stochastic density integrated over the bins by the test: I[c] and its variance VI[c]. */
typedef void (*gof_bin_integrals)(void *ctx, const gof_bins *b, double *I, double *VI);

typedef struct {
    const char *name;
    void *ctx;                      /* the callbacks' */
    gof_sampler sample;
    gof_density density;            /* deterministic; or NULL and: */
    gof_bin_integrals integrals;    /* a stochastic density's bin integrals */
    int unit_weights;               /* every weight is 1 (a phase function): the counts sum to n */
    double axis[3], lo;             /* the gof_grid: about axis, mu in lo .. 1 */
    int nfm, nfp;                   /* edges forced onto fmu[], fph[] (the density's kinks) */
    double fmu[2], fph[2];
    double integral, int_tol;       /* what the density integrates to over the grid, and how closely */
    unsigned seed_pilot, seed;      /* the pilot run's (GOF_NPILOT samples) and the fit's */
    size_t n;                       /* samples of the fit */
} gof_spec;

/* Fits the sampler to its density on a gof_grid made from a pilot run: checks every
 * sample (a unit vector of finite non-negative weight in the grid's range; weight 1 with
 * unit_weights; weight = value / pdf for a deterministic density, to 1e-4) and the
 * density's integral, records the chi-squares of the fine and the coarse bins (dof = the
 * bins used, less 1 with unit_weights) and, without unit_weights, the total's z, and a
 * skewed copy's smallest p-value (the weights times 1 + GOF_SKEW (2 c - 1), c the pilot's
 * distribution function at the sample's mu, renormalised: a skewed sampler, not a scaled
 * one), required to be rejected where its noncentrality on the coarse bins is >= 100. */
static inline void gof_fit(const gof_spec *gc)
{
    const double t_case = check_now(), N = (double)gc->n;
    float *smp = malloc((gc->n > GOF_NPILOT ? gc->n : GOF_NPILOT) * 16);
    gof_grid g;
    gc->sample(gc->ctx, gc->seed_pilot, GOF_NPILOT, smp);
    gof_grid_make(&g, gc->axis, gc->lo, smp, GOF_NPILOT, gc->nfm, gc->fmu, gc->nfp, gc->fph);
    const gof_bins bins = gof_grid_bins(&g);
    /* the skew's coordinate: the pilot's distribution function in mu */
    static double pmu[GOF_NPILOT];
    int npm = 0;
    for (int i = 0; i < GOF_NPILOT; i++) {
        double mu, phi;
        gof_grid_coords(&g, smp + 4 * i, &mu, &phi);
        if (smp[4 * i + 3] > 0) pmu[npm++] = mu;
    }
    qsort(pmu, (size_t)npm, sizeof *pmu, gof_dbl_cmp);
    gc->sample(gc->ctx, gc->seed, gc->n, smp);

    /* the samples: checks, the skew's normalisation, then the tallies */
    int bad_dir = 0, bad_w = 0, outside = 0, not_one = 0;
    double sw = 0, sw2 = 0, sws = 0;
    for (size_t i = 0; i < gc->n; i++) {
        const float *s = smp + 4 * i;
        double w = s[3], len = sqrt((double)s[0] * s[0] + (double)s[1] * s[1] + (double)s[2] * s[2]), c = 0;
        if (!(fabs(len - 1) < 1e-4)) bad_dir++;
        if (!(w >= 0 && w < 1e6)) {
            bad_w++;
            continue;
        }
        if (gc->unit_weights && w != 1) not_one++;
        if (gof_grid_cell(&g, s) < 0) outside++;
        c = gof_skew_c(&g, pmu, npm, s);
        sw += w, sw2 += w * w, sws += w * (1 + GOF_SKEW * (2 * c - 1));
    }
    CHECK(bad_dir == 0, "%s: %d samples are not unit vectors", gc->name, bad_dir);
    CHECK(bad_w == 0, "%s: %d weights negative or not finite", gc->name, bad_w);
    CHECK(not_one == 0, "%s: %d phase sample weights are not 1", gc->name, not_one);
    CHECK(outside == 0, "%s: %d samples outside the model's hemisphere", gc->name, outside);
    const double norm = sw / sws, rg = sw > 0 ? sw2 / sw : 1;
    static double O[2][GOF_NCELL], S2[2][GOF_NCELL];
    memset(O, 0, sizeof O), memset(S2, 0, sizeof S2);
    for (size_t i = 0; i < gc->n; i++) {
        const float *s = smp + 4 * i;
        double w = s[3], c = 0;
        if (!(w >= 0 && w < 1e6)) continue;
        int cell = gof_grid_cell(&g, s);
        if (cell < 0) continue;
        c = gof_skew_c(&g, pmu, npm, s);
        double ws = w * (1 + GOF_SKEW * (2 * c - 1)) * norm;
        O[0][cell] += w, S2[0][cell] += w * w, O[1][cell] += ws, S2[1][cell] += ws * ws;
    }
    /* the weight is f / pdf at every sample (deterministic densities) */
    if (gc->density) {
        float *fp = malloc(gc->n * 8);
        gc->density(gc->ctx, smp, gc->n, fp);
        int bad = 0;
        for (size_t i = 0; i < gc->n; i++) {
            double ratio = fp[2 * i + 1] > 0 ? fp[2 * i] / fp[2 * i + 1] : 0, w = smp[4 * i + 3];
            if (!(fabs(w - ratio) <= 1e-4 * ratio + 1e-6)) bad++;
        }
        CHECK(bad == 0, "%s: %d sample weights differ from f / pdf", gc->name, bad);
        free(fp);
    }

    /* expected */
    static double I[GOF_NCELL], IQ[GOF_NCELL], E[GOF_NCELL], V[GOF_NCELL];
    double itot = 0, iq = 0, ivar = 0;
    const int mc = !gc->density;
    if (mc) {
        gc->integrals(gc->ctx, &bins, I, IQ);
        for (int c = 0; c < GOF_NCELL; c++) E[c] = N * I[c], V[c] = N * N * IQ[c], itot += I[c], ivar += IQ[c];
    } else {
        gof_integrate(&bins, gc->density, gc->ctx, N, rg, I, IQ);
        for (int c = 0; c < GOF_NCELL; c++) {
            E[c] = N * I[c], V[c] = N * N * IQ[c] * IQ[c] + 1e-12 * E[c] * E[c];
            itot += I[c], iq += IQ[c];
        }
    }
    /* normalisation */
    if (mc)
        CHECK(fabs(itot - gc->integral) <= gc->int_tol && sqrt(ivar) <= 0.25 * gc->int_tol,
              "%s: the evaluation integrates to %.6f +- %.2g over the sphere, not %.6f (allowed %.2g)", gc->name, itot,
              sqrt(ivar), gc->integral, gc->int_tol);
    else
        CHECK(fabs(itot - gc->integral) <= gc->int_tol, "%s: the evaluation integrates to %.8f (quadrature error <= %.2g),"
              " not %.8f (allowed %.2g)", gc->name, itot, iq, gc->integral, gc->int_tol);

    /* coarse bins: sums of blocks (quadrature errors add with unknown signs) */
    static double OC[2][GOF_NCOARSE], SC[2][GOF_NCOARSE], EC[GOF_NCOARSE], VC[GOF_NCOARSE], QC[GOF_NCOARSE];
    memset(OC, 0, sizeof OC), memset(SC, 0, sizeof SC), memset(EC, 0, sizeof EC), memset(VC, 0, sizeof VC);
    memset(QC, 0, sizeof QC);
    for (int c = 0; c < GOF_NCELL; c++) {
        int k = gof_grid_coarse(c);
        for (int s = 0; s < 2; s++) OC[s][k] += O[s][c], SC[s][k] += S2[s][c];
        EC[k] += E[c];
        if (mc) VC[k] += V[c];
        else QC[k] += N * IQ[c];
    }
    for (int k = 0; k < GOF_NCOARSE; k++)
        if (!mc) VC[k] = QC[k] * QC[k] + 1e-12 * EC[k] * EC[k];
    const int fixed = gc->unit_weights; /* every weight 1: the counts sum to N */
    double chi[2], chic[2], lam_c = 0, pf[2], pc[2], pz[2] = {1, 1}, z[2] = {0, 0};
    int dof[2], dofc[2];
    for (int s = 0; s < 2; s++) {
        chi[s] = gof_chi2(GOF_NCELL, O[s], S2[s], E, V, rg, NULL, &dof[s], NULL);
        chic[s] = gof_chi2(GOF_NCOARSE, OC[s], SC[s], EC, VC, rg, s ? NULL : OC[1], &dofc[s], s ? NULL : &lam_c);
        dof[s] -= fixed, dofc[s] -= fixed;
        pf[s] = chi2_p(chi[s], dof[s]), pc[s] = chi2_p(chic[s], dofc[s]);
    }
    char tn[200];
    snprintf(tn, sizeof tn, "%s: chi2 (%d dof)", gc->name, dof[0]);
    gof_record(tn, pf[0]);
    snprintf(tn, sizeof tn, "%s: coarse chi2 (%d dof)", gc->name, dofc[0]);
    gof_record(tn, pc[0]);
    if (!gc->unit_weights) {
        /* the total: the mean weight is the albedo */
        double et = N * itot, var_e = (N * iq) * (N * iq) + 1e-12 * et * et;
        for (int s = 0; s < 2; s++) {
            double tw = 0, tw2 = 0;
            for (int c = 0; c < GOF_NCELL; c++) tw += O[s][c], tw2 += S2[s][c];
            double var = fmax(tw2 - tw * tw / N, 0.0) + var_e;
            z[s] = (tw - et) / sqrt(var), pz[s] = erfc(fabs(z[s]) / sqrt(2.0));
        }
        snprintf(tn, sizeof tn, "%s: total", gc->name);
        gof_record(tn, pz[0]);
    }
    double ps = fmin(fmin(pf[1], pc[1]), pz[1]);
    gof_skew(gc->name, ps, lam_c, lam_c >= 100);
    printf("%-36s chi2 %6.1f/%3d p=%.3f coarse %5.1f/%2d p=%.3f | integral %.7f (%s %.1e) | skewed p %.1e (lambda %.0f)"
           " | %.2f s\n",
           gc->name, chi[0], dof[0], pf[0], chic[0], dofc[0], pc[0], itot, mc ? "sigma" : "quad", mc ? sqrt(ivar) : iq,
           ps, lam_c, check_now() - t_case);
    if (!gc->unit_weights)
        printf("%36s total z = %+.2f (mean weight %.6f, albedo %.6f)\n", "", z[0], sw / N, gc->integral);
    free(smp);
}

#endif
