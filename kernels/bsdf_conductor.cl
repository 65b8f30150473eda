/* MicrosurfaceConductiveBrdf, single scattering (use_multiple_scattering=false): GGX
 * facets with the exact unpolarised Fresnel reflectance of a conductor of complex
 * relative index eta + i k (the metal below over the medium above), and the
 * height-correlated Smith masking-shadowing that uniform heights imply,
 * G2 = 1 / (1 + Lambda(wo) + Lambda(wi)). With the cosine of wi included (SPEC section 4):
 *   f = F(wo.h) D(h) G2(wo, wi) / (4 wo.z),  h = normalize(wo + wi),  both above.
 * Parameters p[0] = alpha, p[1] = eta, p[2] = k (relative to the medium above). Light
 * reaches it only from above; what the single-scattering term does not reflect is lost. */

/* Unpolarised Fresnel reflectance of a conductor for cos(incidence) c, four at once:
 * with a^2 + b^2 = sqrt((eta^2 - k^2 - s^2)^2 + 4 eta^2 k^2), s = sin, (the standard
 * closed form of the complex-index Fresnel equations)
 *   Rs = (a2b2 - 2 a c + c^2) / (a2b2 + 2 a c + c^2),
 *   Rp = Rs (a2b2 c^2 - 2 a c s^2 + s^4) / (a2b2 c^2 + 2 a c s^2 + s^4). */
inline real4 fresnel_conductor4(real eta, real k, real4 c)
{
    c = clamp(c, (real4)(R(0.0)), (real4)(R(1.0)));
    real4 c2 = c * c, s2 = R(1.0) - c2;
    real4 t = eta * eta - k * k - s2;
    real4 a2b2 = sqrt(t * t + R(4.0) * eta * eta * k * k);
    real4 a = safe_sqrt4(R(0.5) * (a2b2 + t));
    real4 rs = (a2b2 - R(2.0) * a * c + c2) / (a2b2 + R(2.0) * a * c + c2);
    real4 rp = rs * (a2b2 * c2 - R(2.0) * a * c * s2 + s2 * s2) / (a2b2 * c2 + R(2.0) * a * c * s2 + s2 * s2);
    return R(0.5) * (rs + rp);
}

inline real4 conductor_eval4(__global const lsqt_dev_layer *l, real3 wo, dir4 wi)
{
    const real alpha = l->p[0];
    if (!(wo.z > R(0.0))) return (real4)(R(0.0));
    real4 hx = wo.x + wi.x, hy = wo.y + wi.y, hz = wo.z + wi.z;
    real4 inv = rsqrt(fmax(hx * hx + hy * hy + hz * hz, (real4)(R(1e-30))));
    hx *= inv, hy *= inv, hz *= inv;
    real4 oh = wo.x * hx + wo.y * hy + wo.z * hz;
    real4 g2 = R(1.0) / (R(1.0) + ggx_lambda(alpha, wo.z) + ggx_lambda4(alpha, wi.z));
    real4 f = fresnel_conductor4(l->p[1], l->p[2], oh) * ggx_d4(alpha, hx, hy, hz) * g2 / (R(4.0) * wo.z);
    return select((real4)(R(0.0)), f, wi.z > R(0.0));
}

/* Density of conductor_sample's directions (reflections of visible normals, also those
 * that point below the surface, which carry weight 0): G1(wo) D(h) / (4 wo.z). */
inline real conductor_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    const real alpha = l->p[0];
    if (!(wo.z > R(0.0))) return R(0.0);
    real3 h = wo + wi;
    real n = length(h);
    if (!(n > R(1e-12))) return R(0.0);
    h /= n;
    if (!(dot(wo, h) > R(0.0))) return R(0.0);
    return ggx_d4(alpha, (real4)(h.x), (real4)(h.y), (real4)(h.z)).x / ((R(1.0) + ggx_lambda(alpha, wo.z)) * R(4.0) * wo.z);
}

/* Reflects wo about a visible normal; the weight f/pdf is F (1 + Lo) / (1 + Lo + Li),
 * 0 when the reflection points below the surface (single scattering only). */
inline real conductor_sample(__global const lsqt_dev_layer *l, real3 wo, real u1, real u2, real3 *wi)
{
    const real alpha = l->p[0];
    if (!(wo.z > R(0.0))) return R(0.0);
    real3 h = ggx_sample_vndf(alpha, wo, u1, u2);
    real oh = dot(wo, h);
    *wi = normalize(R(2.0) * oh * h - wo);
    if (!(wi->z > R(0.0))) return R(0.0);
    real lo = ggx_lambda(alpha, wo.z), li = ggx_lambda(alpha, wi->z);
    return fresnel_conductor4(l->p[1], l->p[2], (real4)(oh)).x * (R(1.0) + lo) / (R(1.0) + lo + li);
}
