/* The random walk on a microsurface (Heitz, Hanika, d'Eon, Dachsbacher 2016), shared by
 * the three facet models. A ray arrives along d; it meets the microsurface at a random
 * height, scatters off a visible facet (the model's phase function), and goes on until it
 * escapes above (reflection) or below (transmission, after crossing a facet). Its exit
 * is an exact sample of the BSDF, with weight the product of the facet albedos.
 *
 * One walk serves every incident direction: each vertex adds, towards every direction u
 * of the slice, its phase function value times the chance G1(u, h) that light leaving
 * that way escapes. Evaluation and sampling are the same walk, so the same walk's exit
 * continues the path. Where single scattering is analytic (conductor, dielectric) it is
 * added exactly once and the walks add orders >= 2 only: the same expectation, less noise.
 * Work per direction that does not depend on the vertex (Lambda(u), lgamma(1 + Lambda(u)),
 * the media's transmittance) comes from a table made once per launch (lsqt_prepare). */

/* A walk longer than this is cut (absorbed): in the furnace tests no walk comes close. */
#define LSQT_MS_MAX_ORDER 1024

/* Where a vertex's terms go: the slice's directions and this layer's table
 * (transmittance T, 0 where light may not leave that way; Lambda; lgamma(1 + Lambda)),
 * each LSQT_NWI_PAD long; on the CPU path the per-direction sums (sum), on the GPU path
 * the path's records instead (out, for layer `layer`; nee_records.cl). */
typedef struct {
    __local real *sum;
    __global const real *wi;
    __global const real *tab;
    work_t *count; /* vertices evaluated (work counter), or 0 */
    nee_out *out;
    int layer;
} ms_sink;

/* Directions are in `real`: --double is double end to end (the host normalises them). */
LSQT_INLINE dirv load_dirv(__global const real *wi, int k)
{
    dirv d = {vloadv(0, wi + k), vloadv(0, wi + LSQT_NWI_PAD + k), vloadv(0, wi + 2 * LSQT_NWI_PAD + k)};
    return d;
}

/* The terms w * T * EXPR of the vector of LSQT_VW directions at b, into v; u (this
 * side's frame), lam and lg are in scope for EXPR. Lanes with T = 0 (t) add nothing even
 * where EXPR is not finite (the zero vectors that pad the directions). */
#define MS_NEE_VEC(EXPR)                                                       \
    {                                                                            \
        dirv u = load_dirv(wi, b);                                               \
        u.z *= side;                                                             \
        realv lam = vloadv(0, tab + LSQT_NWI_PAD + b);                           \
        realv lg = vloadv(0, tab + 2 * LSQT_NWI_PAD + b);                        \
        (void)lg;                                                                \
        v = select((realv)(R(0.0)), (w * t) * (EXPR), t > R(0.0));               \
    }

/* sum += the terms over every vector of directions that light may leave by. */
#define MS_NEE_LOOP(EXPR)                                                        \
    if (k->count) (*k->count)++;                                                 \
    for (int b = 0; b < LSQT_NWI_PAD; b += LSQT_VW) {                            \
        __global const real *wi = k->wi, *tab = k->tab;                          \
        realv t = vloadv(0, tab + b), v;                                         \
        if (!anyv(t > R(0.0))) continue;                                         \
        MS_NEE_VEC(EXPR)                                                       \
        VEC_AT(realv, k->sum, b) += v;                                           \
    }

/* A walk model's terms (its file's functions, model_list.h), one text for both code
 * paths: a walk vertex's is the facet's phase function times G1 = C1^Lambda(u) to this
 * side, (1 - C1)^Lambda(u) to the other; the first record's is the model's own (its
 * closed-form single scattering, or its walk's first vertex). */
#define MS_G1 exp(lam * select((realv)(x->log_cbar), (realv)(x->log_c), u.z > R(0.0)))
#define MS_VERTEX_TERMS(p) (p##_phasev(l, x, u) * MS_G1)
#define MS_FIRST_TERMS(p) (p##_firstv(l, x, u, lam, lg))

/* STMT(p) for the walk model of layer l (the others' branches are dead code). */
#define MS_DISPATCH_(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_WALK_##sampler(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) MS_STMT(p))

#ifdef LSQT_NEE_RECORDS
/* The GPU path: the vertex becomes a record (and counts as evaluated). */
LSQT_INLINE void ms_record(const ms_sink *k, int kind, const ms_vtx *x, real side, real w)
{
    if (k->count) (*k->count)++;
    nee_write(k->out, kind, k->layer, w, side, x);
}

LSQT_INLINE void ms_nee_vertex(__global const lsqt_dev_layer *l, const ms_vtx *x, real side, real w, const ms_sink *k)
{
    (void)l;
    ms_record(k, NEE_MS_VERTEX, x, side, w);
}

LSQT_INLINE void ms_nee_first(__global const lsqt_dev_layer *l, const ms_vtx *x, real side, real w, const ms_sink *k)
{
    (void)l;
    ms_record(k, NEE_MS_FIRST, x, side, w);
}

/* A record's terms for the vector of directions at b (the layer's table tab). */
LSQT_INLINE realv ms_nee_vec(__global const lsqt_dev_layer *l, int kind, const ms_vtx *x, real side, real w,
                                 __global const real *wi, __global const real *tab, int b)
{
    realv t = vloadv(0, tab + b), v = (realv)(R(0.0));
    if (!anyv(t > R(0.0))) return v;
    if (kind == NEE_MS_VERTEX) {
#define MS_STMT(p) MS_NEE_VEC(MS_VERTEX_TERMS(p))
        LSQT_BSDFS(MS_DISPATCH_)
#undef MS_STMT
    } else {
#define MS_STMT(p) MS_NEE_VEC(MS_FIRST_TERMS(p))
        LSQT_BSDFS(MS_DISPATCH_)
#undef MS_STMT
    }
    return v;
}
#else
/* The CPU path: the vertex's terms go straight into the per-direction sums. */
LSQT_INLINE void ms_nee_vertex(__global const lsqt_dev_layer *l, const ms_vtx *x, real side, real w, const ms_sink *k)
{
#define MS_STMT(p) { MS_NEE_LOOP(MS_VERTEX_TERMS(p)) }
    LSQT_BSDFS(MS_DISPATCH_)
#undef MS_STMT
}

LSQT_INLINE void ms_nee_first(__global const lsqt_dev_layer *l, const ms_vtx *x, real side, real w, const ms_sink *k)
{
#define MS_STMT(p) { MS_NEE_LOOP(MS_FIRST_TERMS(p)) }
    LSQT_BSDFS(MS_DISPATCH_)
#undef MS_STMT
}
#endif

/* Relative index across the facets from side s (only the dielectric refracts). */
LSQT_INLINE real ms_index(__global const lsqt_dev_layer *l, real s)
{
#define MS_STMT(p) return p##_index(l, s);
    LSQT_BSDFS(MS_DISPATCH_)
#undef MS_STMT
    return R(1.0);
}

/* The walk's step at vertex x: the facet's albedo, the new direction *r and whether it
 * crossed to the other side (*cross). */
LSQT_INLINE real ms_scatter(__global const lsqt_dev_layer *l, const ms_vtx *x, rng_t *rng, real3 *r, int *cross)
{
    *cross = 0;
#define MS_STMT(p) return p##_walk_scatter(l, x, rng, r, cross);
    LSQT_BSDFS(MS_DISPATCH_)
#undef MS_STMT
    return R(0.0);
}

/* Whether layer l is a microsurface walk, and its facets' GGX roughness: p[0], as the
 * model list's ALPHA column says of every walk (host/sim/tables.c checks it; a lookup by
 * kind cost the walk kernels 3 VGPRs on gfx90a). */
#define MS_IS_(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_WALK_##sampler(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return 1;)
LSQT_INLINE int ms_layer(__global const lsqt_dev_layer *l)
{
    LSQT_BSDFS(MS_IS_)
    (void)l;
    return 0;
}

LSQT_INLINE real ms_alpha(__global const lsqt_dev_layer *l) { return l->p[0]; }

/* A band block's walk at a layer whose facets' albedo differs by band (the list's BANDS
 * INDEX; kernels/bands.cl): the walk runs with albedo 1 and each of its reflections weighs
 * every band's weight wb by that band's albedo (p_albedo_bands, from the rows n and k of
 * the block's table). Null in every other walk. */
typedef struct {
    __global const real *n, *k;
    BAND_MEM real *wb;
} ms_bands;

#define MS_INDEX_(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_INDEX_##bands(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return p##_albedo_bands(x, mb->n, mb->k, mb->wb);)

/* Weighs the bands by their albedos at vertex x; 0 where the step is lost. */
LSQT_INLINE int ms_albedo_bands(__global const lsqt_dev_layer *l, const ms_vtx *x, const ms_bands *mb)
{
    LSQT_BSDFS(MS_INDEX_)
    (void)l, (void)x, (void)mb;
    return 0;
}

/* One walk from direction d (world frame). Vertices of order >= nee_from add their terms,
 * weighted w, to the sink. With max_order 1 (single scattering only) the walk stops after
 * its first vertex and the weight takes the chance of escaping from there. Returns the
 * exit weight (product of the albedos) and sets *out to the exit direction (world). With
 * mb, the albedos are the bands' (ms_bands) and the walk's weight stays 1, so it plays no
 * roulette. */
LSQT_INLINE real ms_walk(__global const lsqt_dev_layer *l, real3 d, rng_t *rng, int max_order, int nee_from, real w,
                    const ms_sink *k, const ms_bands *mb, real3 *out)
{
    const real alpha = ms_alpha(l);
    real s = d.z < R(0.0) ? R(1.0) : R(-1.0); /* the side the ray is on */
    real3 r = make_real3(d.x, d.y, s * d.z);  /* its direction, in that side's frame */
    real c = R(1.0), weight = R(1.0);
    for (int order = 1;; order++) {
        if (!ms_next_height(alpha, r, &c, R(1.0) - rng_uniform(rng))) break;
        if (order > LSQT_MS_MAX_ORDER) return R(0.0);
        real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
        ms_vtx x = ms_vertex(alpha, -r, c, ms_index(l, s), u1, u2);
        if (order == 1 && nee_from == 1) {
            x.lam_v = ggx_lambda(alpha, x.v.z);
            x.lg_v = lgamma_ge1(R(1.0) + x.lam_v);
            ms_nee_first(l, &x, s, w, k);
        } else if (order >= nee_from) {
            ms_nee_vertex(l, &x, s, w * weight, k);
        }
        int cross;
        weight *= ms_scatter(l, &x, rng, &r, &cross);
        if (mb) weight = ms_albedo_bands(l, &x, mb) ? R(1.0) : R(0.0);
        if (!(weight > R(0.0))) return R(0.0);
        if (cross) s = -s, r.z = -r.z, c = R(1.0) - c;
        if (max_order == 1) {
            /* single scattering: only light that escapes now counts */
            if (!(r.z > R(0.0))) return R(0.0);
            weight *= exp(ggx_lambda(alpha, r.z) * log(fmax(c, LSQT_MS_C_MIN)));
            break;
        }
        if (weight < LSQT_RR_WEIGHT) { /* roulette inside the walk, unbiased */
            if (rng_uniform(rng) * LSQT_RR_WEIGHT >= weight) return R(0.0);
            weight = LSQT_RR_WEIGHT;
        }
    }
    *out = make_real3(r.x, r.y, s * r.z);
    return weight;
}

/* The models with closed-form single scattering: whether layer l is one, and its sampler
 * (use_multiple_scattering=false). */
#define MS_SINGLE_(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_SINGLE_##sampler(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) MS_STMT(p))

LSQT_INLINE int ms_analytic(__global const lsqt_dev_layer *l)
{
#define MS_STMT(p) return 1;
    LSQT_BSDFS(MS_SINGLE_)
#undef MS_STMT
    return 0;
}

LSQT_INLINE real ms_single_sample(__global const lsqt_dev_layer *l, real3 wo, rng_t *rng, real3 *wi)
{
    real u0 = rng_uniform(rng), u1 = rng_uniform(rng), u2 = rng_uniform(rng);
#define MS_STMT(p) return p##_sample(l, wo, u0, u1, u2, wi);
    LSQT_BSDFS(MS_SINGLE_)
#undef MS_STMT
    (void)u0, (void)u1, (void)u2, (void)wo, (void)wi;
    return R(0.0);
}

/* Single scattering with the bands' albedos (mb): the model's own sample, drawn as it
 * draws (u0 unused by a reflecting model), with each band's albedo at the facet, times
 * the chance that the reflection escapes, (1 + Lambda(wo)) / (1 + Lambda(wo) + Lambda(wi)). */
LSQT_INLINE real ms_single_bands(__global const lsqt_dev_layer *l, real3 wo, rng_t *rng, const ms_bands *mb,
                                 real3 *wi)
{
    const real alpha = ms_alpha(l);
    (void)rng_uniform(rng);
    const real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    ms_vtx x = ms_vertex(alpha, wo, R(1.0), ms_index(l, R(1.0)), u1, u2);
    real3 r;
    int cross;
    (void)ms_scatter(l, &x, rng, &r, &cross);
    if (!(r.z > R(0.0)) || !ms_albedo_bands(l, &x, mb)) return R(0.0);
    const real lam_v = ggx_lambda(alpha, wo.z);
    *wi = r;
    return (R(1.0) + lam_v) / (R(1.0) + lam_v + ggx_lambda(alpha, r.z));
}

/* A microsurface vertex reached along d with weight w: iter_count walks each add their
 * terms (weighted w / iter_count) to every direction of the sink, after the analytic
 * single scattering where there is one; walk 0's exit continues the path. Returns the
 * factor for the path's weight and sets *out. With nee 0 only the sample is made; with
 * mb (a band block's, no next-event terms) the bands' albedos weigh it. */
LSQT_INLINE real ms_vertex_walks(__global const lsqt_dev_layer *l, real3 d, rng_t *rng, real w, int nee,
                            const ms_sink *k, const ms_bands *mb, real3 *out)
{
    const int ms = l->multiple_scattering, analytic = ms_analytic(l);
    const int n = nee ? l->iter_count : 1, max_order = ms ? LSQT_MS_MAX_ORDER : 1;
    if (analytic) {
        const real side = d.z < R(0.0) ? R(1.0) : R(-1.0);
        if (nee) {
            ms_vtx x = ms_vertex_single(ms_alpha(l), make_real3(-d.x, -d.y, side * -d.z), ms_index(l, side));
            ms_nee_first(l, &x, side, w, k);
        }
        if (!ms) return mb ? ms_single_bands(l, -d, rng, mb, out) : ms_single_sample(l, -d, rng, out);
    }
    const int nee_from = nee ? (analytic ? 2 : 1) : LSQT_MS_MAX_ORDER + 1;
    real weight = R(0.0), wn = w / (real)n;
    for (int it = 0; it < n; it++) {
        real3 o = make_real3(R(0.0), R(0.0), R(1.0));
        real wt = ms_walk(l, d, rng, max_order, nee_from, wn, k, mb, &o);
        if (it == 0) weight = wt, *out = o;
    }
    return weight;
}

/* Sampling alone (a vertex with no point estimate, and the test harness). */
LSQT_INLINE real ms_sample(__global const lsqt_dev_layer *l, real3 wo, rng_t *rng, real3 *wi)
{
    ms_sink none = {0, 0, 0};
    return ms_vertex_walks(l, -wo, rng, R(0.0), 0, &none, 0, wi);
}
