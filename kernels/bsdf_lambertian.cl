/* Lambertian reflector/transmitter: f = fR |cos(wi)| / pi on the side of wo, fT |cos| / pi
 * on the other (cosine of wi included, docs/design.md section 1.3). Parameters p[0] = fR, p[1] = fT. */

LSQT_INLINE realv lambertian_evalv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    realv k = select((realv)((real)l->p[1]), (realv)((real)l->p[0]), wo.z * wi.z > R(0.0));
    return k * fabs(wi.z) * LSQT_INV_PI;
}

LSQT_INLINE real lambertian_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    real fr = l->p[0], ft = l->p[1];
    real pr = fr / fmax(fr + ft, R(1e-30));
    return ((wo.z * wi.z > R(0.0)) ? pr : R(1.0) - pr) * fabs(wi.z) * LSQT_INV_PI;
}

/* Picks reflection or transmission in proportion to fR : fT; returns the weight
 * f / pdf = fR + fT (0 when the layer absorbs everything). */
LSQT_INLINE real lambertian_sample(__global const lsqt_dev_layer *l, real3 wo, real u0, real u1,
                              real u2, real3 *wi)
{
    real fr = l->p[0], ft = l->p[1];
    real total = fr + ft;
    if (total <= R(0.0)) return R(0.0);
    real3 w = sample_cosine_hemisphere(u1, u2);
    real side = wo.z >= R(0.0) ? R(1.0) : R(-1.0);
    if (u0 * total >= fr) side = -side; /* transmit */
    w.z *= side;
    *wi = w;
    return total;
}
