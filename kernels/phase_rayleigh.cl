/* Rayleigh scattering with depolarisation factor rho (seed): gamma = rho / (2 - rho),
 *   p(cos t) = 3 / (16 pi) [(1 + 3 gamma) + (1 - gamma) cos^2 t] / (1 + 2 gamma),
 * normalised over the sphere for every gamma in [-1/3, 1] (rho in [-1, 1]); gamma = 1 is
 * isotropic, gamma = -1/3 (rho = -1) is pure cos^2. pp = {gamma}. cos t = -dot(wo, wi)
 * as for HG. */
LSQT_INLINE realv rayleigh_phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
    (void)v;
    const real gam = m->pp[0];
    realv c = wo.x * wi.x + wo.y * wi.y + wo.z * wi.z;
    return (R(3.0) / (R(16.0) * LSQT_PI)) * ((R(1.0) + R(3.0) * gam) + (R(1.0) - gam) * c * c) / (R(1.0) + R(2.0) * gam);
}

/* Exact inverse CDF: with a = 1 + 3 gamma, b = 1 - gamma, the CDF in mu = cos t is
 * (a (mu + 1) + b (mu^3 + 1) / 3) / (2 a + 2 b / 3) = u, the cubic
 *   b mu^3 / 3 + a mu + c = 0,  c = (a + b / 3)(1 - 2 u),
 * increasing in mu (a, b >= 0), so it has one real root: by the hyperbolic form of
 * Cardano's solution, mu = -2 sqrt(a / b) sinh(asinh(3 c / (2 a) sqrt(b / a)) / 3), or its
 * limits b -> 0 (mu = -c / a) and a -> 0 (mu = cbrt(-3 c / b)); then two Newton steps on
 * the cubic polish the rounding. */
LSQT_INLINE real rayleigh_cos(real gam, real u)
{
    const real a = R(1.0) + R(3.0) * gam, b = R(1.0) - gam, c = (a + b / R(3.0)) * (R(1.0) - R(2.0) * u);
    real mu;
    if (b < R(1e-6) * a) mu = -c / a;
    else if (a < R(1e-6) * b) mu = cbrt(R(-3.0) * c / b);
    else mu = R(-2.0) * sqrt(a / b) * sinh(asinh(R(1.5) * c / a * sqrt(b / a)) / R(3.0));
    for (int i = 0; i < 2; i++) {
        real f = b * mu * mu * mu / R(3.0) + a * mu + c, df = b * mu * mu + a;
        if (df > R(0.0)) mu -= f / df;
    }
    return clamp(mu, R(-1.0), R(1.0));
}

LSQT_INLINE real rayleigh_phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real u1,
                                       real u2, rng_t *rng, real3 *wi)
{
    (void)v, (void)rng;
    *wi = direction_around(-wo, rayleigh_cos(m->pp[0], u1), u2);
    return R(1.0);
}
