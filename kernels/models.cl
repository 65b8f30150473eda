/* Dispatch from a layer or medium table entry to its model, expanded from the model list
 * (include/lsqt/model_list.h). Only the models the assembly uses are compiled in: the host
 * passes -DLSQT_HAS_<CLASS>_<ID>=1 for each, and LSQT_ON(<CLASS>_<ID>) (model_list.h) is 1
 * for those and 0 for the rest, whose branches are dead code, so a scene pays for nothing
 * it does not contain (on a GPU, not even registers). The microsurfaces' walk dispatches
 * the same way (microsurface.cl). */

/* Evaluation takes LSQT_VW directions at once (next-event estimation's inner loop); the
 * single-direction form used by the test harness is lane 0 of the same code. For the
 * microsurfaces it is the analytic single-scattering term (conductor, dielectric; 0 for
 * Lambertian facets): their full value is the walks' (microsurface.cl), which the path
 * loop runs itself. */
LSQT_INLINE realv bsdf_evalv(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
#define X(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return p##_evalv(l, wo, wi);
    LSQT_BSDFS(X)
#undef X
    return (realv)(R(0.0));
}

/* The same for the layers a next-event estimate evaluates this way: every kind but the
 * microsurfaces, whose terms are their walks' (fewer branches: on a GPU the unused
 * branches' registers would count). */
LSQT_INLINE realv bsdf_evalv_closed(__global const lsqt_dev_layer *l, real3 wo, dirv wi)
{
#define X(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_CLOSED_##sampler(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return p##_evalv(l, wo, wi);)
    LSQT_BSDFS(X)
#undef X
    return (realv)(R(0.0));
}

LSQT_INLINE real bsdf_eval(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
    return bsdf_evalv(l, wo, dirv_broadcast(wi)).s0;
}

/* Samples wi given wo; returns the weight f / pdf, 0 when the path is absorbed. The
 * microsurfaces sample by their walk; the others take three draws (u0 picks a lobe). */
LSQT_INLINE real bsdf_sample(__global const lsqt_dev_layer *l, real3 wo, rng_t *rng, real3 *wi)
{
#define X(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_WALK_##sampler(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return ms_sample(l, wo, rng, wi);)
    LSQT_BSDFS(X)
#undef X
    real u0 = rng_uniform(rng), u1 = rng_uniform(rng), u2 = rng_uniform(rng);
#define X(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha)                                     \
    LSQT_IF_CLOSED_##sampler(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) \
                                 return p##_sample(l, wo, u0, u1, u2, wi);)
    LSQT_BSDFS(X)
#undef X
    return R(0.0);
}

LSQT_INLINE real bsdf_pdf(__global const lsqt_dev_layer *l, real3 wo, real3 wi)
{
#define X(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return p##_pdf(l, wo, wi);
    LSQT_BSDFS(X)
#undef X
    return R(0.0);
}

/* What a phase function fixes at a vertex for every direction it is evaluated towards
 * and for the sample that continues the path (phase_vtx, common.cl): for diffuse SGGX
 * flakes one visible normal, so the point estimate's cost does not grow with its
 * stochastic evaluation. The EXACT samplers fix nothing. */
LSQT_INLINE phase_vtx phase_vertex(__global const lsqt_dev_medium *m, real3 wo, rng_t *rng)
{
    phase_vtx v = {make_real3(R(0.0), R(0.0), R(1.0))};
#define X(ID, num, name, alias, p, sampler, mirror) \
    LSQT_IF_VERTEX_##sampler(if (LSQT_ON(PHASE_##ID) && m->phase_kind == LSQT_PHASE_##ID) p##_phase_vertex(m, wo, rng, &v);)
    LSQT_PHASES(X)
#undef X
    (void)m, (void)wo, (void)rng;
    return v;
}

LSQT_INLINE realv phase_evalv(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, dirv wi)
{
#define X(ID, num, name, alias, p, sampler, mirror) \
    if (LSQT_ON(PHASE_##ID) && m->phase_kind == LSQT_PHASE_##ID) return p##_phase_evalv(m, v, wo, wi);
    LSQT_PHASES(X)
#undef X
    (void)v, (void)wo, (void)wi;
    return (realv)(R(0.0));
}

LSQT_INLINE real phase_eval(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, real3 wi)
{
    return phase_evalv(m, v, wo, dirv_broadcast(wi)).s0;
}

/* Density of phase_sample's directions: the phase function itself for the EXACT
 * samplers; the VERTEX ones say (0 for diffuse SGGX, whose density has no closed form). */
LSQT_INLINE real phase_pdf(__global const lsqt_dev_medium *m, real3 wo, real3 wi)
{
#define X(ID, num, name, alias, p, sampler, mirror) \
    LSQT_IF_VERTEX_##sampler(if (LSQT_ON(PHASE_##ID) && m->phase_kind == LSQT_PHASE_##ID) return p##_phase_pdf(m, wo, wi);)
    LSQT_PHASES(X)
#undef X
    phase_vtx none = {make_real3(R(0.0), R(0.0), R(1.0))};
    return phase_eval(m, &none, wo, wi);
}

/* Samples wi given wo; returns the weight p / pdf (1 for the exact samplers). */
LSQT_INLINE real phase_sample(__global const lsqt_dev_medium *m, const phase_vtx *v, real3 wo, rng_t *rng, real3 *wi)
{
    /* Every phase function draws two (HG2 picks its lobe by splitting u1, so with b = 0
     * it is HG sample for sample: test_phases); with the free flight's, a scattering
     * event takes one Philox block of four draws less a quarter. */
    real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
#define X(ID, num, name, alias, p, sampler, mirror) \
    if (LSQT_ON(PHASE_##ID) && m->phase_kind == LSQT_PHASE_##ID) return p##_phase_sample(m, v, wo, u1, u2, rng, wi);
    LSQT_PHASES(X)
#undef X
    (void)v, (void)wo, (void)wi;
    return R(0.0);
}
