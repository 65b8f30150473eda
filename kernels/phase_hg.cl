/* Henyey-Greenstein phase function, and its two-lobe mixture. Directions point away from
 * the vertex: wo back towards where the path came from, wi where it goes, so the
 * scattering angle has cosine cos t = -dot(wo, wi) (the seed's 1 + g^2 + 2 g wo.wi).
 *
 * Float at the extremes (g = +-0.999, a peak 1e-3 wide): 1 + g^2 - 2 g cos t cancels to
 * nothing at the peak, so it is written (1 - |g|)^2 + 2 |g| q with q = 1 -+ cos t taken
 * from the vectors, q = |wo +- wi|^2 / 2, exact to rounding near the peak. */

LSQT_INLINE realv hg_evalv(real g, real3 wo, dirv wi)
{
    const real ag = fabs(g), s = g >= R(0.0) ? R(1.0) : R(-1.0);
    realv qx = wo.x + s * wi.x, qy = wo.y + s * wi.y, qz = wo.z + s * wi.z;
    /* 2 |g| q with q = 1 - cos t towards the peak, |wo +- wi|^2 / 2: the halving and
     * doubling are exact, so they are left out (one multiply fewer per 16 directions) */
    realv denom = (R(1.0) - ag) * (R(1.0) - ag) + ag * (qx * qx + qy * qy + qz * qz);
    return LSQT_INV_4PI * ((R(1.0) - ag) * (R(1.0) + ag)) * inv_pow15v(denom);
}

LSQT_INLINE real hg_pdf(real g, real3 wo, real3 wi) { return hg_evalv(g, wo, dirv_broadcast(wi)).s0; }

/* Samples wi exactly proportional to the phase function (weight 1): the inverse CDF of
 * the standard form, cos t = (1 + g^2 - s^2) / (2 g), s = (1 - g^2) / (1 - g + 2 g u),
 * rewritten for q = 1 - cos t about the peak, q = (1 - g)(1 - u)(s + 1 - g) / (1 - g + 2 g u)
 * (|g| in place of g, the peak axis reversed for g < 0), which keeps angles down to
 * (1 - g) 2^-12 rad in float. */
LSQT_INLINE real3 hg_sample(real g, real3 wo, real u1, real u2)
{
    const real ag = fabs(g);
    real3 axis = g >= R(0.0) ? -wo : wo;
    real q;
    if (ag < R(1e-3)) {
        q = R(2.0) * u1; /* isotropic: cos t uniform */
    } else {
        real it = R(1.0) / (R(1.0) - ag + R(2.0) * ag * u1);
        real s = (R(1.0) - ag) * (R(1.0) + ag) * it;
        q = (R(1.0) - ag) * (R(1.0) - u1) * (s + R(1.0) - ag) * it;
    }
    return direction_around_q(axis, clamp(q, R(0.0), R(2.0)), u2);
}

/* The phase model HenyeyGreensteinPhase, pp = {g}. */
LSQT_INLINE realv hg_phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
    (void)v;
    return hg_evalv(m->pp[0], wo, wi);
}

LSQT_INLINE real hg_phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real u1, real u2,
                                 rng_t *rng, real3 *wi)
{
    (void)v, (void)rng;
    *wi = hg_sample(m->pp[0], wo, u1, u2);
    return R(1.0);
}

/* Two lobes: (1 - b) HG(g0) + b HG(g1); pp = {g0, g1, b}. The sampler picks lobe 1 with
 * probability b, so the weight is exactly 1: lobe 1 when u1 < b, and u1 rescaled to the
 * chosen part of [0, 1) is again uniform, for the lobe's own sample. */
LSQT_INLINE realv hg2_phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
    (void)v;
    const real b = m->pp[2];
    return (R(1.0) - b) * hg_evalv(m->pp[0], wo, wi) + b * hg_evalv(m->pp[1], wo, wi);
}

LSQT_INLINE real hg2_phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real u1, real u2,
                                  rng_t *rng, real3 *wi)
{
    (void)v, (void)rng;
    const real b = m->pp[2];
    if (u1 < b) *wi = hg_sample(m->pp[1], wo, u1 / b, u2);
    else *wi = hg_sample(m->pp[0], wo, fmin((u1 - b) / (R(1.0) - b), R(1.0)), u2);
    return R(1.0);
}
