/* Trowbridge-Reitz (GGX) microfacets with isotropic roughness alpha, the Smith model with
 * the uniform height distribution of Heitz, Hanika, d'Eon, Dachsbacher 2016: masking
 * Lambda, the microfacet distribution D, and the distribution of visible normals, sampled
 * as in Heitz 2018 ("Sampling the GGX distribution of visible normals"). Directions are
 * unit vectors in the layer frame (z the macro normal), on the side of +z. */

/* Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2, four directions at once (z = cos). */
inline real4 ggx_lambda4(real alpha, real4 z)
{
    real4 z2 = fmax(z * z, (real4)(R(1e-30)));
    real4 t2 = fmax(R(1.0) - z2, (real4)(R(0.0))) / z2; /* tan^2 */
    return R(0.5) * (sqrt(R(1.0) + alpha * alpha * t2) - R(1.0));
}

inline real ggx_lambda(real alpha, real z) { return ggx_lambda4(alpha, (real4)(z)).x; }

/* D(h) = alpha^2 / (pi ((alpha^2 - 1) cos^2 + 1)^2) for a unit normal h on the upper side,
 * written as alpha^2 / (pi (alpha^2 hz^2 + hx^2 + hy^2)^2): the same for unit h, but with
 * no cancellation, so a smooth surface (alpha 1e-4, alpha^2 below float's epsilon) keeps
 * its finite peak 1 / (pi alpha^2) instead of dividing by a rounded 0. */
inline real4 ggx_d4(real alpha, real4 hx, real4 hy, real4 hz)
{
    real a2 = alpha * alpha;
    real4 k = a2 * hz * hz + hx * hx + hy * hy;
    return select((real4)(R(0.0)), a2 * LSQT_INV_PI / (k * k), hz > R(0.0));
}

/* A visible normal for wo (wo.z > 0), density D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z
 * with G1 = 1 / (1 + Lambda(wo)): stretch to the unit-roughness configuration, sample
 * the projected hemisphere there, unstretch. */
inline real3 ggx_sample_vndf(real alpha, real3 wo, real u1, real u2)
{
    real3 vh = normalize(make_real3(alpha * wo.x, alpha * wo.y, wo.z));
    real lensq = vh.x * vh.x + vh.y * vh.y;
    real3 t1 = lensq > R(0.0) ? make_real3(-vh.y, vh.x, R(0.0)) * rsqrt(lensq) : make_real3(R(1.0), R(0.0), R(0.0));
    real3 t2 = cross(vh, t1);
    real r = sqrt(u1), phi = R(2.0) * LSQT_PI * u2;
    real p1 = r * cos(phi), p2 = r * sin(phi);
    real s = R(0.5) * (R(1.0) + vh.z);
    p2 = (R(1.0) - s) * safe_sqrt(R(1.0) - p1 * p1) + s * p2;
    real3 nh = p1 * t1 + p2 * t2 + safe_sqrt(R(1.0) - p1 * p1 - p2 * p2) * vh;
    return normalize(make_real3(alpha * nh.x, alpha * nh.y, fmax(R(1e-9), nh.z)));
}
