/* Trowbridge-Reitz (GGX) microfacets with isotropic roughness alpha, the Smith model with
 * the uniform height distribution of Heitz, Hanika, d'Eon, Dachsbacher 2016: masking
 * Lambda, the microfacet distribution D, and the distribution of visible normals, sampled
 * as in Heitz 2018 ("Sampling the GGX distribution of visible normals"). Directions are
 * unit vectors in the layer frame (z the macro normal), on the side of +z. */

/* Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2, LSQT_VW directions at once (z = cos). */
#define LSQT_GGX_LAMBDA(T, alpha, z)                                                                \
    {                                                                                               \
        const T z2 = fmax(z * z, (T)(R(1e-30)));                                                    \
        const T t2 = fmax(R(1.0) - z2, (T)(R(0.0))) / z2; /* tan^2 */                               \
        return R(0.5) * (sqrt(R(1.0) + alpha * alpha * t2) - R(1.0));                               \
    }
LSQT_INLINE realv ggx_lambdav(real alpha, realv z) LSQT_GGX_LAMBDA(realv, alpha, z)
LSQT_INLINE real ggx_lambda(real alpha, real z) LSQT_GGX_LAMBDA(real, alpha, z)

/* D(h) = alpha^2 / (pi ((alpha^2 - 1) cos^2 + 1)^2) for a unit normal h on the upper side,
 * written as alpha^2 / (pi (alpha^2 hz^2 + hx^2 + hy^2)^2): the same for unit h, but with
 * no cancellation, so a smooth surface (alpha 1e-4, alpha^2 below float's epsilon) keeps
 * its finite peak 1 / (pi alpha^2) instead of dividing by a rounded 0. */
LSQT_INLINE realv ggx_dv(real alpha, realv hx, realv hy, realv hz)
{
    real a2 = alpha * alpha;
    realv k = a2 * hz * hz + hx * hx + hy * hy;
    return select((realv)(R(0.0)), a2 * LSQT_INV_PI / (k * k), hz > R(0.0));
}

/* A visible normal for wo (wo.z > 0), density D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z
 * with G1 = 1 / (1 + Lambda(wo)): stretch to the unit-roughness configuration, sample
 * the projected hemisphere there, unstretch. */
LSQT_INLINE real3 ggx_sample_vndf(real alpha, real3 wo, real u1, real u2)
{
    real3 vh = normalize(make_real3(alpha * wo.x, alpha * wo.y, wo.z));
    real lensq = vh.x * vh.x + vh.y * vh.y;
    real3 t1 = lensq > R(0.0) ? make_real3(-vh.y, vh.x, R(0.0)) * rsqrt(lensq) : make_real3(R(1.0), R(0.0), R(0.0));
    real3 t2 = cross(vh, t1);
    const real r = sqrt(u1);
    const real2 cs = azimuth_cs(u2); /* not cos and sin of 2 pi u2: their reduction of a
                                        radian argument takes 40 VGPRs on gfx90a */
    real p1 = r * cs.x, p2 = r * cs.y;
    real s = R(0.5) * (R(1.0) + vh.z);
    p2 = (R(1.0) - s) * safe_sqrt(R(1.0) - p1 * p1) + s * p2;
    real3 nh = p1 * t1 + p2 * t2 + safe_sqrt(R(1.0) - p1 * p1 - p2 * p2) * vh;
    return normalize(make_real3(alpha * nh.x, alpha * nh.y, fmax(R(1e-9), nh.z)));
}

/* Projected area of the facets visible from v (either hemisphere), per unit macro area:
 * A(v) = (v.z + sqrt(v.z^2 + alpha^2 (1 - v.z^2))) / 2, which is (1 + Lambda) v.z above
 * the surface and Lambda(-v) |v.z| below it. The visible normals' density is
 * D_v(m) = max(0, v.m) D(m) / A(v). */
LSQT_INLINE real ggx_area(real alpha, real vz)
{
    real z2 = vz * vz;
    return R(0.5) * (vz + sqrt(z2 + alpha * alpha * fmax(R(1.0) - z2, R(0.0))));
}

/* Uniform heights (Heitz et al. 2016): h uniform on [-1, 1], so C1(h) = (1 + h) / 2 and
 * the chance that a ray leaving height h along w (w.z > 0) escapes is G1 = C1(h)^Lambda(w).
 * A walk keeps c = C1(h) in the frame of the side the ray is on; the other side sees the
 * mirrored surface, where the same height has C1 = 1 - c. */
#define LSQT_MS_C_MIN R(1e-30)

/* One step of the walk's height: a ray at c travelling along r (in its side's frame)
 * either escapes (returns 0) or hits the microsurface at a new c (returns 1). Going down
 * it always hits: C1(h') = C1(h) u^(1/(1 + Lambda)); going up it escapes with G1, else
 * C1(h') = C1(h) u^(-1/Lambda) for u in (G1, 1] (inverting the Smith masking in height). */
LSQT_INLINE int ms_next_height(real alpha, real3 r, real *c, real u)
{
    real lam = ggx_lambda(alpha, r.z), lu = log(u);
    if (r.z > R(0.0)) {
        if (lu <= lam * log(*c)) return 0;
        *c = fmin(R(1.0), *c * exp(-lu / lam));
    } else if (r.z < R(0.0)) {
        *c = fmax(LSQT_MS_C_MIN, *c * exp(lu / (R(1.0) + lam)));
    }
    return 1;
}

/* What a facet interaction needs to know about the ray that arrives, fixed for every
 * direction it is evaluated towards. Frame: the side the ray is on, z up. */
typedef struct {
    real3 v;          /* towards where the ray came from (v.z < 0 when it arrived going up) */
    real3 m;          /* a visible normal sampled for this vertex (D_v) */
    real inv_area;    /* 1 / A(v) */
    real lam_v;       /* Lambda(v) and lgamma(1 + Lambda(v)): analytic single */
    real lg_v;        /* scattering only (ms_vertex_single; v.z > 0 there) */
    real log_c;       /* log C1(h): escape to this side is exp(Lambda(u) log_c) */
    real log_cbar;    /* log (1 - C1(h)): escape to the other side */
    real e;           /* relative index across the facets seen from this side */
} ms_vtx;

LSQT_INLINE ms_vtx ms_vertex(real alpha, real3 v, real c, real e, real u1, real u2)
{
    ms_vtx x;
    x.v = v;
    x.m = ggx_sample_vndf(alpha, v, u1, u2);
    x.inv_area = R(1.0) / fmax(ggx_area(alpha, v.z), R(1e-30));
    x.lam_v = x.lg_v = R(0.0);
    x.log_c = log(fmax(c, LSQT_MS_C_MIN));
    x.log_cbar = log(fmax(R(1.0) - c, LSQT_MS_C_MIN));
    x.e = e;
    return x;
}

/* The first hit of light arriving along -v from above (c = 1), for the analytic single
 * scattering terms. */
LSQT_INLINE ms_vtx ms_vertex_single(real alpha, real3 v, real e)
{
    ms_vtx x = ms_vertex(alpha, v, R(1.0), e, R(0.5), R(0.5));
    x.lam_v = ggx_lambda(alpha, v.z);
    x.lg_v = lgamma_ge1(R(1.0) + x.lam_v);
    return x;
}

/* Escape of the single-scattered light, averaged over the first hit's height:
 * (1 + Lv) / (1 + Lv + Lu) to this side, (1 + Lv) B(1 + Lv, 1 + Lu) to the other
 * (lg_u = lgamma(1 + Lu), from the per-direction table). */
#define LSQT_MS_SINGLE_ESCAPE(T, ALL, LGAMMA)                                                        \
    {                                                                                               \
        const T a = R(1.0) + x->lam_v;                                                              \
        T r = a / (a + lam_u);                                                                      \
        if (!ALL(up)) /* the Beta function only where some light goes through */                   \
            r = up ? r : a * exp(x->lg_v + lg_u - LGAMMA(R(2.0) + x->lam_v + lam_u));               \
        return r;                                                                                   \
    }
LSQT_INLINE realv ms_single_escapev(const ms_vtx *x, maskv up, realv lam_u, realv lg_u)
    LSQT_MS_SINGLE_ESCAPE(realv, allv, lgamma_ge1_v)
LSQT_INLINE real ms_single_escape(const ms_vtx *x, int up, real lam_u, real lg_u)
    LSQT_MS_SINGLE_ESCAPE(real, LSQT_ALL1, lgamma_ge1)

/* Half vector of wo and u for reflection (k = 1) or refraction (k = relative index),
 * oriented up: q = v + k u, m = q / |q|; returns |q|^2. LSQT_VW directions at once. */
LSQT_INLINE realv ms_halfv(real3 v, dirv u, realv k, dirv *m)
{
    realv qx = v.x + k * u.x, qy = v.y + k * u.y, qz = v.z + k * u.z;
    realv n2 = fmax(qx * qx + qy * qy + qz * qz, (realv)(R(1e-30)));
    realv inv = rsqrt(n2) * select((realv)(R(1.0)), (realv)(R(-1.0)), qz < R(0.0));
    m->x = qx * inv, m->y = qy * inv, m->z = qz * inv;
    return n2;
}
