/* Dispatch from a layer or medium table entry to its model. Only the models the assembly
 * uses are compiled in (the host passes -DLSQT_HAS_<MODEL>=1), so a scene pays for
 * nothing it does not contain. */

/* Evaluation takes LSQT_VW directions at once (next-event estimation's inner loop); the
 * single-direction form used by the test harness is lane 0 of the same code. For the
 * microsurfaces it is the analytic single-scattering term (conductor, dielectric; 0 for
 * Lambertian facets): their full value is the walks' (microsurface.cl), which the path
 * loop runs itself. */
LSQT_INLINE realv bsdf_evalv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    switch (l->kind) {
#ifdef LSQT_HAS_BSDF_LAMBERTIAN
    case LSQT_BSDF_LAMBERTIAN: return lambertian_evalv(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_MS_CONDUCTIVE
    case LSQT_BSDF_MS_CONDUCTIVE: return conductor_evalv(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_MS_DIELECTRIC
    case LSQT_BSDF_MS_DIELECTRIC: return dielectric_evalv(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_OREN_NAYAR
    case LSQT_BSDF_OREN_NAYAR: return oren_nayar_evalv(l, wo, wi);
#endif
    default: return (realv)(R(0.0));
    }
}

/* The same for the layers a next-event estimate evaluates this way: every kind but the
 * microsurfaces, whose terms are their walks' (a smaller switch: on a GPU the unused
 * branches' registers would count). */
LSQT_INLINE realv bsdf_evalv_closed(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
    switch (l->kind) {
#ifdef LSQT_HAS_BSDF_LAMBERTIAN
    case LSQT_BSDF_LAMBERTIAN: return lambertian_evalv(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_OREN_NAYAR
    case LSQT_BSDF_OREN_NAYAR: return oren_nayar_evalv(l, wo, wi);
#endif
    default: return (realv)(R(0.0));
    }
}

LSQT_INLINE real bsdf_eval(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    return bsdf_evalv(l, wo, dirv_broadcast(wi)).s0;
}

/* Samples wi given wo; returns the weight f / pdf, 0 when the path is absorbed. */
LSQT_INLINE real bsdf_sample(__global const lsqt_dev_layer *l, real3 wo, rng_t *rng, real3 *wi)
{
#if defined(LSQT_HAS_BSDF_MS_LAMBERTIAN) || defined(LSQT_HAS_BSDF_MS_DIELECTRIC) || defined(LSQT_HAS_BSDF_MS_CONDUCTIVE)
    if (l->kind == LSQT_BSDF_MS_LAMBERTIAN || l->kind == LSQT_BSDF_MS_DIELECTRIC || l->kind == LSQT_BSDF_MS_CONDUCTIVE)
        return ms_sample(l, wo, rng, wi);
#endif
    real u0 = rng_uniform(rng), u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    switch (l->kind) {
#ifdef LSQT_HAS_BSDF_LAMBERTIAN
    case LSQT_BSDF_LAMBERTIAN: return lambertian_sample(l, wo, u0, u1, u2, wi);
#endif
#ifdef LSQT_HAS_BSDF_OREN_NAYAR
    case LSQT_BSDF_OREN_NAYAR: return oren_nayar_sample(l, wo, u1, u2, wi);
#endif
    default: return R(0.0);
    }
}

LSQT_INLINE real bsdf_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    switch (l->kind) {
#ifdef LSQT_HAS_BSDF_LAMBERTIAN
    case LSQT_BSDF_LAMBERTIAN: return lambertian_pdf(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_MS_CONDUCTIVE
    case LSQT_BSDF_MS_CONDUCTIVE: return conductor_pdf(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_MS_DIELECTRIC
    case LSQT_BSDF_MS_DIELECTRIC: return dielectric_pdf(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_OREN_NAYAR
    case LSQT_BSDF_OREN_NAYAR: return oren_nayar_pdf(l, wo, wi);
#endif
    default: return R(0.0);
    }
}

/* What a phase function fixes at a vertex for every direction it is evaluated towards
 * and for the sample that continues the path: for diffuse SGGX flakes one visible normal,
 * so the point estimate's cost does not grow with its stochastic evaluation. */
typedef struct {
    real3 m;
} phase_vtx;

LSQT_INLINE phase_vtx phase_vertex(__global const lsqt_dev_medium *m, real3 wo, rng_t *rng)
{
    phase_vtx v = {make_real3(R(0.0), R(0.0), R(1.0))};
#ifdef LSQT_HAS_PHASE_SGGX
    if (m->phase_kind == LSQT_PHASE_SGGX && m->pp[2] > R(0.5)) {
        real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
        v.m = sggx_sample_vndf(m->pp[0], m->pp[1], wo, u1, u2);
    }
#else
    (void)m, (void)wo, (void)rng;
#endif
    return v;
}

LSQT_INLINE realv phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
    (void)v;
    switch (m->phase_kind) {
#ifdef LSQT_HAS_PHASE_HG
    case LSQT_PHASE_HG: return hg_evalv(m->pp[0], wo, wi);
#endif
#ifdef LSQT_HAS_PHASE_HG2
    case LSQT_PHASE_HG2: return hg2_evalv(m, wo, wi);
#endif
#ifdef LSQT_HAS_PHASE_RAYLEIGH
    case LSQT_PHASE_RAYLEIGH: return rayleigh_evalv(m, wo, wi);
#endif
#ifdef LSQT_HAS_PHASE_SGGX
    case LSQT_PHASE_SGGX: return m->pp[2] > R(0.5) ? sggx_diffuse_evalv(v->m, wi) : sggx_specular_evalv(m, wo, wi);
#endif
    default: return (realv)(R(0.0));
    }
}

LSQT_INLINE real phase_eval(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real3 wi)
{
    return phase_evalv(m, v, wo, dirv_broadcast(wi)).s0;
}

/* Density of phase_sample's directions: the phase function itself for the exact
 * samplers; 0 for diffuse SGGX, whose density has no closed form. */
LSQT_INLINE real phase_pdf(__global const lsqt_dev_medium *m, real3 wo, real3 wi)
{
    phase_vtx none = {make_real3(R(0.0), R(0.0), R(1.0))};
    if (m->phase_kind == LSQT_PHASE_SGGX && m->pp[2] > R(0.5)) return R(0.0);
    return phase_eval(m, &none, wo, wi);
}

/* Samples wi given wo; returns the weight p / pdf (1: every sampler here is exact). */
LSQT_INLINE real phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, rng_t *rng, real3 *wi)
{
    /* Every phase function draws two (HG2 picks its lobe by splitting u1, so with b = 0
     * it is HG sample for sample: test_phases); with the free flight's, a scattering
     * event takes one Philox block of four draws less a quarter. */
    real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    (void)v;
    switch (m->phase_kind) {
#ifdef LSQT_HAS_PHASE_HG
    case LSQT_PHASE_HG: *wi = hg_sample(m->pp[0], wo, u1, u2); return R(1.0);
#endif
#ifdef LSQT_HAS_PHASE_HG2
    case LSQT_PHASE_HG2: *wi = hg2_sample(m, wo, u1, u2); return R(1.0);
#endif
#ifdef LSQT_HAS_PHASE_RAYLEIGH
    case LSQT_PHASE_RAYLEIGH: *wi = rayleigh_sample(m, wo, u1, u2); return R(1.0);
#endif
#ifdef LSQT_HAS_PHASE_SGGX
    case LSQT_PHASE_SGGX: *wi = sggx_sample(m, wo, v->m, u1, u2); return R(1.0);
#endif
    default: return R(0.0);
    }
}
