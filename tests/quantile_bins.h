/* Adaptive bins for the chi-square tests of samplers (test_ms_models, test_phases): bin
 * edges at the quantiles of a mixture of the uniform distribution and weighted pilot
 * values, so that a narrow lobe gets bins of its own, and the bin of a value. */
#ifndef LSQT_TEST_QUANTILE_BINS_H
#define LSQT_TEST_QUANTILE_BINS_H

#include <stdlib.h>

/* The bin k of x for edges[0..n]: edges[k] <= x < edges[k + 1] (0 or n - 1 outside). */
static int find_bin(const double *edges, int n, double x)
{
    int lo = 0, hi = n; /* edges[lo] <= x < edges[hi] */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (x >= edges[mid]) lo = mid;
        else hi = mid;
    }
    return lo;
}

typedef struct {
    double x, w;
} xw;

static int xw_cmp(const void *a, const void *b)
{
    double d = ((const xw *)a)->x - ((const xw *)b)->x;
    return d < 0 ? -1 : d > 0;
}

/* edges[0..nb] on [lo, hi] at the quantiles k / nb of (1 - mix) uniform + mix the pilot
 * values v[0..n) with their weights (uniform alone when there are none); sorts v. */
static void breakpoints(xw *v, int n, double lo, double hi, int nb, double mix, double *edges)
{
    double tot = 0;
    for (int i = 0; i < n; i++) tot += v[i].w;
    qsort(v, (size_t)n, sizeof *v, xw_cmp);
    double *cum = malloc(((size_t)n + 1) * sizeof *cum);
    cum[0] = 0;
    for (int i = 0; i < n; i++) cum[i + 1] = cum[i] + v[i].w;
    if (!(tot > 0)) mix = 0;
    edges[0] = lo, edges[nb] = hi;
    for (int k = 1; k < nb; k++) {
        double target = (double)k / nb, a = lo, b = hi;
        for (int it = 0; it < 60; it++) {
            double x = 0.5 * (a + b);
            int l = 0, r = n; /* values below x: v[0..l) */
            while (l < r) {
                int m = (l + r) / 2;
                if (v[m].x < x) l = m + 1;
                else r = m;
            }
            double g = (1 - mix) * (x - lo) / (hi - lo) + (tot > 0 ? mix * cum[l] / tot : 0);
            if (g < target) a = x;
            else b = x;
        }
        edges[k] = 0.5 * (a + b);
    }
    free(cum);
}

#endif
