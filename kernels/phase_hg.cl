/* Henyey-Greenstein phase function. Directions point away from the vertex: wo back
 * towards where the path came from, wi where it goes, so the scattering angle has
 * cosine -dot(wo, wi) (the seed's 1 + g^2 + 2 g wo.wi). */

inline real4 hg_eval4(real g, real3 wo, dir4 wi)
{
    real4 cos_t = -(wo.x * wi.x + wo.y * wi.y + wo.z * wi.z);
    real4 denom = R(1.0) + g * g - R(2.0) * g * cos_t;
    return LSQT_INV_4PI * (R(1.0) - g * g) / (denom * sqrt(fmax(denom, R(0.0))));
}

inline real hg_pdf(real g, real3 wo, real3 wi) { return hg_eval4(g, wo, dir4_broadcast(wi)).x; }

/* Samples wi exactly proportional to the phase function: the weight eval/pdf is 1. */
inline real3 hg_sample(real g, real3 wo, real u1, real u2)
{
    real cos_t;
    if (fabs(g) < R(1e-3)) {
        cos_t = R(1.0) - R(2.0) * u1;
    } else {
        real s = (R(1.0) - g * g) / (R(1.0) - g + R(2.0) * g * u1);
        cos_t = (R(1.0) + g * g - s * s) / (R(2.0) * g);
    }
    cos_t = clamp(cos_t, R(-1.0), R(1.0));
    return direction_around(-wo, cos_t, u2);
}
