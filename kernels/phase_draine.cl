/* DrainePhase (Draine 2003, ApJ 598, eq. 4): Henyey-Greenstein times (1 + alpha cos^2 t),
 * normalised,
 *   p(t) = HG_g(t) (1 + alpha cos^2 t) / (1 + alpha (1 + 2 g^2) / 3),
 * since HG's mean of cos^2 t is (1 + 2 g^2) / 3. alpha = 0 is HG; g = 0, alpha = 1 is
 * Rayleigh's shape, 3 (1 + cos^2 t) / (16 pi). pp = {g, alpha, 1 / (1 + alpha (1 + 2 g^2) / 3)}
 * (the normalisation in double, from the host). */

/* Rejections at most before the sampler keeps its last proposal: each proposal is accepted
 * with probability >= 1/3, so (2/3)^63 < 1e-11 is the chance of a sample not drawn
 * exactly from p. */
#define LSQT_DRAINE_TRIES 64

LSQT_INLINE realv draine_phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
    (void)v;
    realv c = wo.x * wi.x + wo.y * wi.y + wo.z * wi.z; /* -cos t; only its square is used */
    return hg_evalv(m->pp[0], wo, wi) * (R(1.0) + m->pp[1] * c * c) * m->pp[2];
}

/* HG's exact sample, kept with probability (1 + alpha cos^2 t) / (1 + alpha) (at least
 * 1 / (1 + alpha (1 - (1 + 2 g^2) / 3)) on average, so at least 1/3): the kept ones are
 * distributed as p, and the weight is 1. Only cos t is redrawn: the acceptance does not
 * depend on the azimuth, so u2 serves every proposal. With alpha = 0 it is hg_sample, draw
 * for draw. */
LSQT_INLINE real draine_phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real u1,
                                     real u2, rng_t *rng, real3 *wi)
{
    (void)v;
    const real g = m->pp[0], a = m->pp[1];
    real3 w = hg_sample(g, wo, u1, u2);
    for (int i = 1; i < LSQT_DRAINE_TRIES && a > R(0.0); i++) {
        const real c = dot(wo, w);
        if (rng_uniform(rng) * (R(1.0) + a) <= R(1.0) + a * c * c) break;
        w = hg_sample(g, wo, rng_uniform(rng), u2);
    }
    *wi = w;
    return R(1.0);
}
