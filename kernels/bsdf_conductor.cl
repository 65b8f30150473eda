/* MicrosurfaceConductiveBrdf: GGX facets with the exact unpolarised Fresnel reflectance
 * of a conductor of complex relative index eta + i k (the metal below over the medium
 * above). Single scattering (with the cosine of wi, docs/design.md section 1.3) with the
 * height-correlated Smith masking-shadowing that uniform heights imply:
 *   f = F(wo.h) D(h) G2(wo, wi) / (4 wo.z),  G2 = 1 / (1 + Lambda(wo) + Lambda(wi)),
 * h = normalize(wo + wi), both above; multiple scattering adds the walk's orders >= 2
 * (microsurface.cl). Parameters p[0] = alpha, p[1] = eta, p[2] = k (relative to the medium
 * above). Light reaches it only from above. */

/* Unpolarised Fresnel reflectance of a conductor for cos(incidence) c, LSQT_VW at once:
 * with a^2 + b^2 = sqrt((eta^2 - k^2 - s^2)^2 + 4 eta^2 k^2), s = sin, (the standard
 * closed form of the complex-index Fresnel equations)
 *   Rs = (a2b2 - 2 a c + c^2) / (a2b2 + 2 a c + c^2),
 *   Rp = Rs (a2b2 c^2 - 2 a c s^2 + s^4) / (a2b2 c^2 + 2 a c s^2 + s^4). */
#define LSQT_FRESNEL_CONDUCTOR(T)                                                                    \
    {                                                                                               \
        c = clamp(c, (T)(R(0.0)), (T)(R(1.0)));                                                     \
        const T c2 = c * c, s2 = R(1.0) - c2;                                                       \
        const T t = eta * eta - k * k - s2;                                                         \
        const T a2b2 = sqrt(t * t + R(4.0) * eta * eta * k * k);                                    \
        const T a = sqrt(fmax(R(0.5) * (a2b2 + t), (T)(R(0.0))));                                   \
        const T rs = (a2b2 - R(2.0) * a * c + c2) / (a2b2 + R(2.0) * a * c + c2);                   \
        const T rp = rs * (a2b2 * c2 - R(2.0) * a * c * s2 + s2 * s2) / (a2b2 * c2 + R(2.0) * a * c * s2 + s2 * s2); \
        return R(0.5) * (rs + rp);                                                                  \
    }
LSQT_INLINE realv fresnel_conductor_lanes(realv eta, realv k, realv c) LSQT_FRESNEL_CONDUCTOR(realv)
LSQT_INLINE real fresnel_conductor(real eta, real k, real c) LSQT_FRESNEL_CONDUCTOR(real)

/* One index, LSQT_VW cosines (a band block's walk takes LSQT_VW indices at one cosine). */
LSQT_INLINE realv fresnel_conductorv(real eta, real k, realv c)
{
    return fresnel_conductor_lanes((realv)(eta), (realv)(k), c);
}

/* The facets' phase function towards u (the ray's side's frame): F D_v(m) / (4 v.m) =
 * F D(m) / (4 A(v)), m = normalize(v + u); 0 towards the other side (a reflection that
 * points into the surface hits it again). */
LSQT_INLINE realv conductor_phasev(__global const lsqt_dev_layer *l, const ms_vtx *x, dirv u)
{
    dirv m;
    ms_halfv(x->v, u, (realv)(R(1.0)), &m);
    realv vm = x->v.x * m.x + x->v.y * m.y + x->v.z * m.z;
    realv f = fresnel_conductorv(l->p[1], l->p[2], vm) * ggx_dv(l->p[0], m.x, m.y, m.z) * (R(0.25) * x->inv_area);
    return select((realv)(R(0.0)), f, (vm > R(0.0)) & (u.z > R(0.0)));
}

/* The ray's reflection about the vertex's visible normal; *vm, the cosine between them. */
LSQT_INLINE real3 conductor_reflect(const ms_vtx *x, real *vm)
{
    *vm = dot(x->v, x->m);
    return normalize(R(2.0) * *vm * x->m - x->v);
}

/* A band block's albedos (the list's BANDS INDEX, microsurface.cl ms_bands): each band's
 * Fresnel factor at the vertex's facet, from its n and k (rows n, k of the block's table),
 * weighs its weight wb, LSQT_VW bands at a time; bands without weight (and the padding,
 * n = k = 0) stay 0. Returns 0 where the ray meets the facet from behind (lost). */
LSQT_INLINE int conductor_albedo_bands(const ms_vtx *x, __global const real *n, __global const real *k, BAND_MEM real *wb)
{
    const real vm = dot(x->v, x->m);
    if (!(vm > R(0.0))) return 0;
    BAND_LOOP
    for (int j = 0; j < LSQT_NBV; j += LSQT_VW) {
        const realv w = vloadv(0, wb + j);
        const realv f = fresnel_conductor_lanes(vloadv(0, n + j), vloadv(0, k + j), (realv)(vm));
        vstorev(select((realv)(R(0.0)), w * f, w > R(0.0)), 0, wb + j);
    }
    return 1;
}

/* Reflects about the vertex's visible normal; returns the facet albedo F. */
LSQT_INLINE real conductor_scatter(__global const lsqt_dev_layer *l, const ms_vtx *x, real3 *r)
{
    real vm;
    *r = conductor_reflect(x, &vm);
    return vm > R(0.0) ? fresnel_conductor(l->p[1], l->p[2], vm) : R(0.0);
}

/* The walk's step (microsurface.cl): no draw, never crosses. */
LSQT_INLINE real conductor_walk_scatter(__global const lsqt_dev_layer *l, const ms_vtx *x, rng_t *rng, real3 *r,
                                        int *cross)
{
    (void)rng;
    *cross = 0;
    return conductor_scatter(l, x, r);
}

/* The facets do not refract. */
LSQT_INLINE real conductor_index(__global const lsqt_dev_layer *l, real side)
{
    (void)l, (void)side;
    return R(1.0);
}

/* Single scattering (the first record of the walk's estimate): the phase function times
 * the chance the reflected light escapes, averaged over the first hit's height:
 * (1 + Lambda(v)) / (1 + Lambda(v) + Lambda(u)). */
LSQT_INLINE realv conductor_firstv(__global const lsqt_dev_layer *l, const ms_vtx *x, dirv u, realv lam_u, realv lg_u)
{
    (void)lg_u;
    return conductor_phasev(l, x, u) * ((R(1.0) + x->lam_v) / (R(1.0) + x->lam_v + lam_u));
}

LSQT_INLINE realv conductor_evalv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    if (!(wo.z > R(0.0))) return (realv)(R(0.0));
    ms_vtx x = ms_vertex_single(l->p[0], wo, R(1.0));
    return conductor_firstv(l, &x, wi, ggx_lambdav(l->p[0], wi.z), (realv)(R(0.0)));
}

/* Density of conductor_sample's directions (reflections of visible normals, also those
 * that point below the surface, which carry weight 0): G1(wo) D(h) / (4 wo.z). */
LSQT_INLINE real conductor_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    const real alpha = l->p[0];
    if (!(wo.z > R(0.0))) return R(0.0);
    real3 h = wo + wi;
    real n = length(h);
    if (!(n > R(1e-12))) return R(0.0);
    h /= n;
    if (!(dot(wo, h) > R(0.0))) return R(0.0);
    return ggx_dv(alpha, (realv)(h.x), (realv)(h.y), (realv)(h.z)).s0 / ((R(1.0) + ggx_lambda(alpha, wo.z)) * R(4.0) * wo.z);
}

/* Single scattering: reflects wo about a visible normal; the weight f/pdf is
 * F (1 + Lo) / (1 + Lo + Li), 0 when the reflection points below the surface. */
LSQT_INLINE real conductor_sample(__global const lsqt_dev_layer *l, real3 wo, real u0, real u1, real u2, real3 *wi)
{
    (void)u0;
    const real alpha = l->p[0];
    if (!(wo.z > R(0.0))) return R(0.0);
    ms_vtx x = ms_vertex(alpha, wo, R(1.0), R(1.0), u1, u2);
    x.lam_v = ggx_lambda(alpha, wo.z);
    real f = conductor_scatter(l, &x, wi);
    if (!(wi->z > R(0.0))) return R(0.0);
    return f * (R(1.0) + x.lam_v) / (R(1.0) + x.lam_v + ggx_lambda(alpha, wi->z));
}
