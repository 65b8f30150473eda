/* OrenNayarDiffuseBrdf, the "simpler expression" of the later user's guide (section
 * 3.2.5), with the cosine of wi included:
 *   f = fR |cos i| / pi [A + B max(wo'.wi', 0) / max(|cos o|, |cos i|)],
 * wo'.wi' = wo.x wi.x + wo.y wi.y (the tangential parts), A = 1 - 0.5 s^2 / (s^2 + 0.33),
 * B = 0.45 s^2 / (s^2 + 0.09), s = sigma (radians). It reflects only. The formula is
 * reproduced as published: it is not energy conserving at grazing angles (albedo about
 * 1.005 at sigma 0.1, 80 degrees), and nothing is clamped. p[0] = fR, p[1] = sigma. */

LSQT_INLINE real oren_nayar_a(real s) { return R(1.0) - R(0.5) * s * s / (s * s + R(0.33)); }
LSQT_INLINE real oren_nayar_b(real s) { return R(0.45) * s * s / (s * s + R(0.09)); }

/* The bracket [A + B ...] for LSQT_VW directions on wo's side. */
LSQT_INLINE realv oren_nayar_bracketv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    const real s = l->p[1];
    realv t = fmax(wo.x * wi.x + wo.y * wi.y, (realv)(R(0.0)));
    realv mx = fmax(fabs(wi.z), (realv)(fabs(wo.z)));
    return oren_nayar_a(s) + oren_nayar_b(s) * t / fmax(mx, (realv)(R(1e-30)));
}

LSQT_INLINE realv oren_nayar_evalv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    realv f = l->p[0] * fabs(wi.z) * LSQT_INV_PI * oren_nayar_bracketv(l, wo, wi);
    return select((realv)(R(0.0)), f, wo.z * wi.z > R(0.0));
}

LSQT_INLINE real oren_nayar_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    (void)l;
    return wo.z * wi.z > R(0.0) ? fabs(wi.z) * LSQT_INV_PI : R(0.0);
}

/* Cosine-weighted on wo's side; the weight f / pdf = fR [A + B ...]. */
LSQT_INLINE real oren_nayar_sample(__global const lsqt_dev_layer *l, real3 wo, real u0, real u1, real u2, real3 *wi)
{
    (void)u0;
    real3 w = sample_cosine_hemisphere(u1, u2);
    w.z *= wo.z >= R(0.0) ? R(1.0) : R(-1.0);
    *wi = w;
    return l->p[0] * oren_nayar_bracketv(l, wo, dirv_broadcast(w)).s0;
}
