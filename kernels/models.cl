/* Dispatch from a layer or medium table entry to its model. Only the models the assembly
 * uses are compiled in (the host passes -DLSQT_HAS_<MODEL>=1), so a scene pays for
 * nothing it does not contain. */

/* Evaluation takes four directions at once (next-event estimation's inner loop); the
 * single-direction form used by the test harness is lane x of the same code. For the
 * microsurfaces it is the analytic single-scattering term (conductor, dielectric; 0 for
 * Lambertian facets): their full value is the walks' (microsurface.cl), which the path
 * loop runs itself. */
inline real4 bsdf_eval4(__global const lsqt_dev_layer *l, real3 wo, dir4 wi)
{
    switch (l->kind) {
#ifdef LSQT_HAS_BSDF_LAMBERTIAN
    case LSQT_BSDF_LAMBERTIAN: return lambertian_eval4(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_MS_CONDUCTIVE
    case LSQT_BSDF_MS_CONDUCTIVE: return conductor_eval4(l, wo, wi);
#endif
#ifdef LSQT_HAS_BSDF_MS_DIELECTRIC
    case LSQT_BSDF_MS_DIELECTRIC: return dielectric_eval4(l, wo, wi);
#endif
    default: return (real4)(R(0.0));
    }
}

inline real bsdf_eval(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    return bsdf_eval4(l, wo, dir4_broadcast(wi)).x;
}

/* Samples wi given wo; returns the weight f / pdf, 0 when the path is absorbed. */
inline real bsdf_sample(__global const lsqt_dev_layer *l, real3 wo, rng_t *rng, real3 *wi)
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
    default: return R(0.0);
    }
}

inline real bsdf_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
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
    default: return R(0.0);
    }
}

inline real4 phase_eval4(__global const lsqt_dev_medium *m, real3 wo, dir4 wi)
{
    switch (m->phase_kind) {
#ifdef LSQT_HAS_PHASE_HG
    case LSQT_PHASE_HG: return hg_eval4(m->pp[0], wo, wi);
#endif
    default: return (real4)(R(0.0));
    }
}

inline real phase_eval(__global const lsqt_dev_medium *m, real3 wo, real3 wi)
{
    return phase_eval4(m, wo, dir4_broadcast(wi)).x;
}

inline real phase_pdf(__global const lsqt_dev_medium *m, real3 wo, real3 wi)
{
    switch (m->phase_kind) {
#ifdef LSQT_HAS_PHASE_HG
    case LSQT_PHASE_HG: return hg_pdf(m->pp[0], wo, wi);
#endif
    default: return R(0.0);
    }
}

/* Samples wi given wo; returns the weight p / pdf (1 for exact samplers). */
inline real phase_sample(__global const lsqt_dev_medium *m, real3 wo, rng_t *rng, real3 *wi)
{
    real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    switch (m->phase_kind) {
#ifdef LSQT_HAS_PHASE_HG
    case LSQT_PHASE_HG: *wi = hg_sample(m->pp[0], wo, u1, u2); return R(1.0);
#endif
    default: return R(0.0);
    }
}
