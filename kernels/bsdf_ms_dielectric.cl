/* MicrosurfaceDielectricBsdf: GGX facets that are Fresnel mirrors between the medium
 * above (index n_a) and the one below (n_b). Light from above meets relative index
 * e = n_b / n_a, light from below 1 / e; kR and kT scale the facets' reflection and
 * transmission (values below 1 absorb). Parameters p[0] = alpha, p[1] = n_b / n_a,
 * p[2] = kR, p[3] = kT.
 *
 * Normalisation: the walk conserves energy, so f (cosine of wi included) integrates over
 * wi to the fraction of the light that leaves each way, and a lossless stack has
 * R + T = 1. This is the flux form of the BSDF; it obeys, with n_o and n_i the indices on
 * the sides of wo and wi,  n_o^2 f(wo -> wi) / |cos i| = n_i^2 f(wi -> wo) / |cos o|
 * (for reflection plain reciprocity). Single scattering, in the frame of wo's side:
 *   reflection   f = kR F(wo.h) D(h) / (4 cos o) / (1 + Lo + Li),  h = normalize(wo + wi)
 *   transmission f = kT (1 - F(wo.h)) D(h) e^2 |wi.h| wo.h / (cos o (wo.h + e wi.h)^2)
 *                    * B(1 + Lo, 1 + Li),  h = -normalize(wo + e wi) turned up,
 * B the Beta function: uniform heights make the height-correlated G2 of transmission
 * E[(1 - C1(h))^Li] over the first hit's height, (1 + Lo) B(1 + Lo, 1 + Li) / (1 + Lo). */

/* Unpolarised Fresnel reflectance of a dielectric interface for cos(incidence) c >= 0 on
 * the incident side and relative index e = n2 / n1; 1 under total internal reflection. */
#define LSQT_FRESNEL_DIELECTRIC(T)                                                                   \
    {                                                                                               \
        c = clamp(c, (T)(R(0.0)), (T)(R(1.0)));                                                     \
        const T g2 = e * e - R(1.0) + c * c;                                                        \
        const T g = sqrt(fmax(g2, (T)(R(0.0))));                                                    \
        const T a = (g - c) / (g + c);                                                              \
        const T b = (c * (g + c) - R(1.0)) / (c * (g - c) + R(1.0));                                \
        return g2 <= R(0.0) ? (T)(R(1.0)) : R(0.5) * a * a * (R(1.0) + b * b);                      \
    }
LSQT_INLINE realv fresnel_dielectricv(real e, realv c) LSQT_FRESNEL_DIELECTRIC(realv)
LSQT_INLINE real fresnel_dielectric(real e, real c) LSQT_FRESNEL_DIELECTRIC(real)

/* The facets' phase function towards u, in the frame of the ray's side (z up): towards
 * this side reflection kR F D_v(m) / (4 v.m), towards the other side refraction
 * kT (1 - F) D_v(m) e^2 |u.m| / (v.m + e u.m)^2, m the half vector of each. */
LSQT_INLINE realv dielectric_phasev(__global const lsqt_dev_layer *l, const ms_vtx *x, dirv u)
{
    const real e = x->e;
    maskv up = u.z > R(0.0);
    dirv m;
    realv n2 = ms_halfv(x->v, u, select((realv)(e), (realv)(R(1.0)), up), &m);
    realv vm = x->v.x * m.x + x->v.y * m.y + x->v.z * m.z;
    realv um = u.x * m.x + u.y * m.y + u.z * m.z;
    realv fr = fresnel_dielectricv(e, vm);
    /* reflection: vm^2 / |q|^2 is 1/4 exactly, so no division by |q|^2, which rounding
     * spoils where u is near -v (|q| -> 0); refraction has |q| >= |e - 1| */
    realv k = select((realv)(l->p[3]) * (R(1.0) - fr) * (e * e) * fabs(um) * vm / n2, (realv)(R(0.25) * l->p[2]) * fr, up);
    realv f = ggx_dv(l->p[0], m.x, m.y, m.z) * k * x->inv_area;
    return select((realv)(R(0.0)), f, (vm > R(0.0)) & (up | (um < R(0.0))));
}

/* Reflects or refracts at the vertex's visible normal, in proportion kR F : kT (1 - F);
 * returns the albedo kR F + kT (1 - F) and sets *cross when the ray went through. */
LSQT_INLINE real dielectric_scatter(__global const lsqt_dev_layer *l, const ms_vtx *x, real u, real3 *r, int *cross)
{
    const real e = x->e, vm = dot(x->v, x->m);
    if (!(vm > R(0.0))) return R(0.0);
    real fr = fresnel_dielectric(e, vm);
    real pr = l->p[2] * fr, tot = pr + l->p[3] * (R(1.0) - fr);
    if (u * tot < pr) {
        *r = normalize(R(2.0) * vm * x->m - x->v);
        *cross = 0;
    } else {
        real ct = safe_sqrt(R(1.0) - (R(1.0) - vm * vm) / (e * e));
        *r = normalize(-x->v / e + (vm / e - ct) * x->m);
        *cross = 1;
    }
    return tot;
}

/* The walk's step (microsurface.cl): one draw picks reflection or refraction. */
LSQT_INLINE real dielectric_walk_scatter(__global const lsqt_dev_layer *l, const ms_vtx *x, rng_t *rng, real3 *r,
                                         int *cross)
{
    return dielectric_scatter(l, x, rng_uniform(rng), r, cross);
}

/* Single scattering (the first record of the walk's estimate): the phase function times
 * the escape averaged over the first hit's height. */
LSQT_INLINE realv dielectric_firstv(__global const lsqt_dev_layer *l, const ms_vtx *x, dirv u, realv lam_u, realv lg_u)
{
    return dielectric_phasev(l, x, u) * ms_single_escapev(x, u.z > R(0.0), lam_u, lg_u);
}

/* The frame of wo's side: z flipped below, and the relative index seen from there. */
LSQT_INLINE real ms_side(real3 wo) { return wo.z >= R(0.0) ? R(1.0) : R(-1.0); }
LSQT_INLINE real dielectric_index(__global const lsqt_dev_layer *l, real side)
{
    return side > R(0.0) ? l->p[1] : R(1.0) / l->p[1];
}

LSQT_INLINE realv dielectric_evalv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    const real s = ms_side(wo), alpha = l->p[0];
    ms_vtx x = ms_vertex_single(alpha, make_real3(wo.x, wo.y, s * wo.z), dielectric_index(l, s));
    wi.z *= s;
    realv lam = ggx_lambdav(alpha, wi.z);
    return dielectric_firstv(l, &x, wi, lam, lgamma_ge1_v(R(1.0) + lam));
}

/* Density of dielectric_sample's directions: both branches (a reflection may point into
 * the surface and a refraction out of it; those carry weight 0), each D_v(m) times its
 * Jacobian times the chance of choosing it. */
LSQT_INLINE real dielectric_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    const real s = ms_side(wo), alpha = l->p[0], e = dielectric_index(l, s);
    real3 v = make_real3(wo.x, wo.y, s * wo.z), u = make_real3(wi.x, wi.y, s * wi.z);
    real inv_area = R(1.0) / fmax(ggx_area(alpha, v.z), R(1e-30)), pdf = R(0.0);
    for (int branch = 0; branch < 2; branch++) {
        real k = branch ? e : R(1.0);
        real3 q = v + k * u;
        real n2 = dot(q, q);
        if (!(n2 > R(1e-30))) continue;
        real3 m = q * (rsqrt(n2) * (q.z < R(0.0) ? R(-1.0) : R(1.0)));
        real vm = dot(v, m), um = dot(u, m);
        if (!(vm > R(0.0)) || (branch && !(um < R(0.0)))) continue;
        real fr = fresnel_dielectric(e, vm);
        real pr = l->p[2] * fr, pt = l->p[3] * (R(1.0) - fr);
        if (!(pr + pt > R(0.0))) continue;
        real d = ggx_dv(alpha, (realv)(m.x), (realv)(m.y), (realv)(m.z)).s0 * vm * inv_area;
        pdf += branch ? pt / (pr + pt) * d * e * e * fabs(um) / n2 : pr / (pr + pt) * d * R(0.25) / vm;
    }
    return pdf;
}

/* Single scattering: a visible normal, reflection or refraction by kR F : kT (1 - F), and
 * the escape averaged over heights; 0 when the direction points the wrong way. */
LSQT_INLINE real dielectric_sample(__global const lsqt_dev_layer *l, real3 wo, real u0, real u1, real u2, real3 *wi)
{
    const real s = ms_side(wo), alpha = l->p[0];
    ms_vtx x = ms_vertex(alpha, make_real3(wo.x, wo.y, s * wo.z), R(1.0), dielectric_index(l, s), u1, u2);
    x.lam_v = ggx_lambda(alpha, x.v.z);
    x.lg_v = lgamma_ge1(R(1.0) + x.lam_v);
    real3 r;
    int cross;
    real w = dielectric_scatter(l, &x, u0, &r, &cross);
    *wi = make_real3(r.x, r.y, s * r.z);
    if (!(w > R(0.0)) || (cross ? !(r.z < R(0.0)) : !(r.z > R(0.0)))) return R(0.0);
    real lam = ggx_lambda(alpha, r.z);
    return w * ms_single_escape(&x, !cross, lam, lgamma_ge1(R(1.0) + lam));
}
