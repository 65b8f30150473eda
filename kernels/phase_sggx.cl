/* SGGX microflakes (Heitz, Dupuy, Crassin, Dachsbacher 2015) as a medium's phase function,
 * with S = diag(Apara^2, Apara^2, Aperp^2) in the layer frame; pp = {Apara^2, Aperp^2,
 * type (0 Specular, 1 Diffuse)}. The medium's mus stays direction independent (as in the
 * original tool): only the phase function comes from the flakes.
 *   sigma(w) = sqrt(w^T S w) (projected area), D(m) = 1 / (pi sqrt|S| (m^T S^-1 m)^2),
 *   specular: p(wo -> wi) = D(h) / (4 sigma(wo)), h = normalize(wo + wi);
 *   diffuse:  p(wo -> wi) = E_m[max(0, wi.m)] / pi over normals m visible from wo.
 * Both depend on absolute directions, not only on the scattering angle. S is symmetric
 * under y -> -y (and rotations about z), so the phi = 0 slices and the y-mirroring of RAW
 * stay valid. Flakes are two-sided: D(m) = D(-m). */

LSQT_INLINE real sggx_sigma(real sxx, real szz, real3 w)
{
    return sqrt(sxx * (w.x * w.x + w.y * w.y) + szz * w.z * w.z);
}

LSQT_INLINE realv sggx_dv(real sxx, real szz, realv mx, realv my, realv mz)
{
    realv q = (mx * mx + my * my) / sxx + mz * mz / szz; /* sqrt|S| = sxx sqrt(szz) */
    /* A unit m has q >= min(1/sxx, 1/szz); m = 0 (the half vector of wi = -wo, which has
     * no direction) would divide by 0: it takes the largest D, a finite value. */
    q = fmax(q, (realv)(fmin(R(1.0) / sxx, R(1.0) / szz)));
    return R(1.0) / (((LSQT_PI * sxx) * sqrt(szz)) * q * q);
}

/* A normal visible from w, density max(0, w.m) D(m) / sigma(w). The flakes are the
 * ellipsoid x^T S x = 1, the image of the unit sphere under S^-1/2, whose normal at
 * S^-1/2 y is along S^1/2 y: a uniform point of the unit sphere's disk as seen from
 * S^1/2 w, lifted onto the sphere, maps to a uniform point of the ellipsoid's projection
 * (a linear map has a constant Jacobian), so m = normalize(S^1/2 y). */
LSQT_INLINE real3 sggx_sample_vndf(real sxx, real szz, real3 w, real u1, real u2)
{
    const real sp = sqrt(sxx), sn = sqrt(szz);
    real3 v = normalize(make_real3(sp * w.x, sp * w.y, sn * w.z)), t, b;
    make_frame(v, &t, &b);
    const real r = sqrt(u1);
    const real2 cs = azimuth_cs(u2);
    real x = r * cs.x, y = r * cs.y;
    real3 p = x * t + y * b + safe_sqrt(R(1.0) - x * x - y * y) * v;
    return normalize(make_real3(sp * p.x, sp * p.y, sn * p.z));
}

LSQT_INLINE realv sggx_specular_evalv(__global const lsqt_dev_medium *m, real3 wo, dirv wi)
{
    const real sxx = m->pp[0], szz = m->pp[1];
    realv hx = wo.x + wi.x, hy = wo.y + wi.y, hz = wo.z + wi.z;
    realv inv = rsqrt(fmax(hx * hx + hy * hy + hz * hz, (realv)(R(1e-30))));
    return sggx_dv(sxx, szz, hx * inv, hy * inv, hz * inv) / (R(4.0) * sggx_sigma(sxx, szz, wo));
}

/* Diffuse flakes: the value towards wi given the vertex's visible normal m (one sample
 * serves every direction of the point estimate, and the path's next direction). */
LSQT_INLINE realv sggx_diffuse_evalv(real3 m, dirv wi)
{
    return fmax(wi.x * m.x + wi.y * m.y + wi.z * m.z, (realv)(R(0.0))) * LSQT_INV_PI;
}

/* Specular: reflect wo about a visible normal (weight 1). Diffuse: a cosine lobe about
 * the vertex's normal (weight 1). */
LSQT_INLINE real3 sggx_sample(__global const lsqt_dev_medium *m, real3 wo, real3 normal, real u1, real u2)
{
    if (m->pp[2] > R(0.5)) {
        real3 t, b;
        make_frame(normal, &t, &b);
        real3 c = sample_cosine_hemisphere(u1, u2);
        return normalize(c.x * t + c.y * b + c.z * normal);
    }
    real3 h = sggx_sample_vndf(m->pp[0], m->pp[1], wo, u1, u2);
    return normalize(R(2.0) * dot(wo, h) * h - wo);
}

/* The phase model SggxPhase, pp = {Sxx, Szz, diffuse}: a VERTEX sampler, as diffuse
 * flakes draw one visible normal per vertex for the point estimate and the sample alike. */
LSQT_INLINE void sggx_phase_vertex(__global const lsqt_dev_medium *m, real3 wo, rng_t *rng, phase_vtx *v)
{
    if (m->pp[2] > R(0.5)) {
        real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
        v->m = sggx_sample_vndf(m->pp[0], m->pp[1], wo, u1, u2);
    }
}

LSQT_INLINE realv sggx_phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
    return m->pp[2] > R(0.5) ? sggx_diffuse_evalv(v->m, wi) : sggx_specular_evalv(m, wo, wi);
}

/* The density of sggx_phase_sample: the specular phase function; 0 for diffuse flakes,
 * whose density has no closed form. */
LSQT_INLINE real sggx_phase_pdf(__global const lsqt_dev_medium *m, real3 wo, real3 wi)
{
    if (m->pp[2] > R(0.5)) return R(0.0);
    return sggx_specular_evalv(m, wo, dirv_broadcast(wi)).s0;
}

LSQT_INLINE real sggx_phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real u1, real u2,
                                   rng_t *rng, real3 *wi)
{
    (void)rng;
    *wi = sggx_sample(m, wo, v->m, u1, u2);
    return R(1.0);
}
