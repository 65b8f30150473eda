/* Gauss-Legendre quadrature for the tests' reference integrals: n nodes on [-1, 1] by
 * Newton's method on P_n, accurate to double precision for n up to a few hundred. */
#ifndef LSQT_TESTS_QUADRATURE_H
#define LSQT_TESTS_QUADRATURE_H

#include <math.h>

static inline void gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < n; i++) {
        double t = cos(3.14159265358979323846 * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; k++) {
                double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (t * p1 - p0) / (t * t - 1.0);
            double step = p1 / dp;
            t -= step;
            if (fabs(step) < 1e-15) break;
        }
        x[i] = t;
        w[i] = 2.0 / ((1.0 - t * t) * dp * dp);
    }
}

#endif
