/* p-values for the tests' goodness-of-fit statistics: chi-square by the regularized upper
 * incomplete gamma function, and the Kolmogorov-Smirnov statistic by its asymptotic
 * distribution. test_phases checks them against closed forms before it uses them. */
#ifndef LSQT_TESTS_STATS_H
#define LSQT_TESTS_STATS_H

#include <math.h>

/* Regularized upper incomplete gamma Q(a, x) (series below a + 1, continued fraction
 * above, as in Numerical Recipes' gammq). */
static inline double gamma_q(double a, double x)
{
    if (x <= 0) return 1.0;
    double gln = lgamma(a);
    if (x < a + 1) {
        double ap = a, sum = 1.0 / a, del = sum;
        for (int n = 0; n < 100000; n++) {
            ap += 1;
            del *= x / ap;
            sum += del;
            if (fabs(del) < fabs(sum) * 1e-15) break;
        }
        double p = sum * exp(-x + a * log(x) - gln);
        return p >= 1 ? 0.0 : 1.0 - p;
    }
    double b = x + 1 - a, c = 1e300, d = 1 / b, h = d;
    for (int i = 1; i < 100000; i++) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (fabs(c) < 1e-300) c = 1e-300;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1) < 1e-15) break;
    }
    return exp(-x + a * log(x) - gln) * h;
}

/* P(chi-square with dof degrees of freedom >= chi2). */
static inline double chi2_p(double chi2, int dof) { return dof > 0 ? gamma_q(0.5 * dof, 0.5 * chi2) : 1.0; }

/* P(D_n >= d) for the one-sample Kolmogorov-Smirnov statistic of n points: the
 * asymptotic series with Stephens' small-sample correction (Numerical Recipes' probks). */
static inline double ks_p(double d, double n)
{
    double en = sqrt(n), lam = (en + 0.12 + 0.11 / en) * d;
    if (lam < 0.2) return 1.0;
    double sum = 0, sign = 1, prev = 0;
    for (int k = 1; k <= 200; k++) {
        double term = 2 * sign * exp(-2 * lam * lam * k * k);
        sum += term;
        if (fabs(term) <= 1e-12 * fabs(prev) || fabs(term) <= 1e-300) break;
        sign = -sign;
        prev = term;
    }
    return sum < 0 ? 0 : sum > 1 ? 1 : sum;
}

#endif
