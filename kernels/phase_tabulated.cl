/* TabulatedPhase: p(cos t) from a table of n rows (a TABLE key, include/lsqt/model_list.h),
 * mu[0] = -1 < mu[1] < ... < mu[n-1] = 1 and values p[i], normalised by the host so that
 * 2 pi int p dmu = 1 for the linear interpolation between rows, with cdf[i] the
 * probability of cos t < mu[i] (host/input/bands.c). medium_table(m) (common.cl) is mu,
 * then p, then cdf, then the index of n + 1 reals (include/lsqt/tables.h). cos t = -wo.wi, as HG's (phase_hg.cl). A function of the scattering
 * angle alone, so its own mirror image. */

/* The row interval [col[lo], col[lo + 1]] holding x, lo in [lo0, hi0 - 1]: bisection over
 * a sorted column, the last row with col[lo] <= x. */
LSQT_INLINE int tab_interval(__global const real *col, int lo0, int hi0, real x)
{
    int lo = lo0, hi = hi0;
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (col[mid] <= x) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* The interpolated value at cos t = c. */
LSQT_INLINE real tab_value(__global const real *t, int n, real c)
{
    /* the index brackets c by its cell's neighbours (a cell either side: rounding of j) */
    const int j = clamp((int)((c + R(1.0)) * R(0.5) * (real)n), 0, n - 1);
    const int lo = (int)t[3 * n + max(j - 1, 0)], hi = min((int)t[3 * n + min(j + 2, n)] + 1, n - 1);
    const int i = tab_interval(t, lo, hi, c);
    /* rows closer than float tells apart round to one: their interval then has no width */
    const real h = t[i + 1] - t[i], x = h > R(0.0) ? clamp((c - t[i]) / h, R(0.0), R(1.0)) : R(0.0);
    return t[n + i] + x * (t[n + i + 1] - t[n + i]);
}

LSQT_INLINE realv tabulated_phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
    (void)v;
    __global const real *t = medium_table(m);
    const int n = (int)m->pp[2];
    real c[LSQT_VW];
    vstorev(-(wo.x * wi.x + wo.y * wi.y + wo.z * wi.z), 0, c);
    for (int k = 0; k < LSQT_VW; k++) c[k] = tab_value(t, n, clamp(c[k], R(-1.0), R(1.0)));
    return vloadv(0, c);
}

/* Exact: u1 picks the interval by the tabulated CDF, then inverts the interval's own CDF,
 * quadratic for a density linear in mu: with f the fraction of the interval's probability
 * below s (the fraction of its width), s = f (p0 + p1) / (p0 + sqrt(p0^2 + f (p1^2 - p0^2))),
 * the stable root. The weight is 1. */
LSQT_INLINE real tabulated_phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real u1,
                                        real u2, rng_t *rng, real3 *wi)
{
    (void)v, (void)rng;
    __global const real *t = medium_table(m);
    const int n = (int)m->pp[2];
    const int i = tab_interval(t + 2 * n, 0, n - 1, u1);
    const real c0 = t[2 * n + i], c1 = t[2 * n + i + 1], p0 = t[n + i], p1 = t[n + i + 1];
    const real f = clamp((u1 - c0) / (c1 - c0), R(0.0), R(1.0));
    const real den = p0 + sqrt(fmax(p0 * p0 + f * (p1 - p0) * (p1 + p0), R(0.0)));
    const real s = den > R(0.0) ? clamp(f * (p0 + p1) / den, R(0.0), R(1.0)) : R(0.0);
    /* q = 1 - cos t about -wo, from the row's own 1 - mu (no cancellation near the peak) */
    const real q = (R(1.0) - t[i]) - s * (t[i + 1] - t[i]);
    *wi = direction_around_q(-wo, clamp(q, R(0.0), R(2.0)), u2);
    return R(1.0);
}
