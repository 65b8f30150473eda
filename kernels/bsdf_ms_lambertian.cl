/* MicrosurfaceLambertianBrdf: GGX facets that reflect diffusely with fR and transmit
 * diffusely with fT (to the other side of the microsurface, as a dielectric facet
 * refracts). It has no closed-form single scattering: every order comes from the walk
 * (microsurface.cl), the first one too. Parameters p[0] = alpha, p[1] = fR, p[2] = fT. */

/* Phase function of the vertex's facet (normal x->m) towards u: fR max(0, u.m) / pi
 * to this side, fT max(0, -u.m) / pi to the other. */
LSQT_INLINE realv mslambert_phasev(__global const lsqt_dev_layer *l, const ms_vtx *x, dirv u)
{
    realv um = u.x * x->m.x + u.y * x->m.y + u.z * x->m.z;
    return select(l->p[2] * fmax(-um, (realv)(R(0.0))), l->p[1] * fmax(um, (realv)(R(0.0))), u.z > R(0.0)) *
           LSQT_INV_PI;
}

/* Diffuse reflection about m or transmission about -m, in proportion fR : fT; returns
 * the albedo fR + fT. */
LSQT_INLINE real mslambert_scatter(__global const lsqt_dev_layer *l, const ms_vtx *x, real u0, real u1, real u2,
                              real3 *r, int *cross)
{
    real fr = l->p[1], tot = fr + l->p[2];
    if (!(tot > R(0.0))) return R(0.0);
    *cross = u0 * tot >= fr;
    real3 t, b, n = *cross ? -x->m : x->m;
    make_frame(n, &t, &b);
    real3 c = sample_cosine_hemisphere(u1, u2);
    *r = normalize(c.x * t + c.y * b + c.z * n);
    return tot;
}

/* The walk's step (microsurface.cl): three draws (the branch, then the cosine lobe). */
LSQT_INLINE real mslambert_walk_scatter(__global const lsqt_dev_layer *l, const ms_vtx *x, rng_t *rng, real3 *r,
                                        int *cross)
{
    real u0 = rng_uniform(rng), u1 = rng_uniform(rng);
    return mslambert_scatter(l, x, u0, u1, rng_uniform(rng), r, cross);
}

/* The facets do not refract (a transmitted ray keeps its index). */
LSQT_INLINE real mslambert_index(__global const lsqt_dev_layer *l, real side)
{
    (void)l, (void)side;
    return R(1.0);
}

/* The first record of the walk's estimate: the walk's first vertex, whose height is
 * independent of its facet, so the chance of escaping is replaced by its mean over the
 * first hit's height, ms_single_escapev (the same expectation, less noise, most at
 * grazing u). */
LSQT_INLINE realv mslambert_firstv(__global const lsqt_dev_layer *l, const ms_vtx *x, dirv u, realv lam_u, realv lg_u)
{
    return mslambert_phasev(l, x, u) * ms_single_escapev(x, u.z > R(0.0), lam_u, lg_u);
}

/* No closed-form single scattering: next-event estimation and the density come from the
 * walk alone (models.cl evaluates these as 0, as for every order of the walk's own). */
LSQT_INLINE realv mslambert_evalv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    (void)l, (void)wo, (void)wi;
    return (realv)(R(0.0));
}

LSQT_INLINE real mslambert_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    (void)l, (void)wo, (void)wi;
    return R(0.0);
}
