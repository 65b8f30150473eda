/* Band blocks: LSQT_NB bands on one path (docs/design.md, 3.7; the host's side is
 * host/sim/band_blocks.c). One band is a block of width 1: every function here is then
 * the one-band walk's step (its weight, its roulette, its flight), and the block's code
 * is dead. Uses nee.cl; walk.cl uses it.
 *
 * The bands of a block differ only where a factor per band says how: a closed layer's
 * reflection and transmission factors (fs, fo: its model is fs or fo times a unit model
 * the bands share), a medium's scattering and extinction. The path is sampled once for
 * all of them and each band carries its own weight wb[b]:
 * - what depends on the band is drawn from one band, the path's hero (path index mod
 *   LSQT_NB, so every band leads as many paths): a medium's free flights from its
 *   extinction, a closed layer's side (wo's or the other) from its fs : fo; the
 *   direction from the unit model's cosine sampler, shared;
 * - each band's weight is its own transport over the mixture of the bands' densities of
 *   the whole path (spectral MIS with the balance heuristic: Wilkie et al. 2014, West et
 *   al. 2020), kept as wb and, per band, rb: its density of the path over the mixture's
 *   (mean 1). A band's weight is at most LSQT_NB times its weight on its own paths, so no
 *   weight grows without bound, and where another band would have gone elsewhere (its
 *   extinction or its fs : fo far from the hero's) a band keeps its path;
 * - a vertex's next-event terms are evaluated once, for the unit model and the least
 *   optical depths, into the scratch sums (c->sink.sum), and spread to each band's sums with
 *   the band's factor and, where its media are deeper, its extra transmittance.
 * A block's paths are its own (the hero and the per-band roulette draw numbers a one-band
 * walk does not), so a band of a block agrees with its one-band run within the error
 * bars, not bit for bit. */
LSQT_INLINE real band_tab(const walk_ctx *c, int at) { return c->in.bw[at]; }

/* A path's per-band state, a row of LSQT_NBW each (BAND_MEM, common.cl): each band's
 * weight wb and density ratio rb, and a flight's densities lv (flight_weights). A GPU
 * keeps the rows in the group's local memory, 13 reals a work-item at 4 bands (3.3 KB a
 * group of 64), within the 16 KB a SIMD may have for 4 waves of 64 on gfx90a. */
#define BAND_WB 0
#define BAND_RB 1
#define BAND_LV 2
#define BAND_ROWS 3
LSQT_INLINE BAND_MEM real *band_row(const walk_ctx *c, int row) { return c->band.rows + row * LSQT_NBW; }

/* The band whose flights path p draws, its hero: path index mod LSQT_NB, so that every
 * band leads as many paths (0 for one band). It is kept after the rows, with them, not in
 * a register through the walk. */
#define BAND_STATE (BAND_ROWS * LSQT_NBW + 1) /* a kernel's BAND_ARRAY(real, rows, BAND_STATE) */
LSQT_INLINE void band_set_hero(const walk_ctx *c, ulong p)
{
    if (LSQT_NB > 1) c->band.rows[BAND_ROWS * LSQT_NBW] = (real)(int)(p % LSQT_NB);
}

LSQT_INLINE int band_hero(const walk_ctx *c) { return LSQT_NB > 1 ? (int)c->band.rows[BAND_ROWS * LSQT_NBW] : 0; }

/* Whether layer l's bands differ by factors of a unit model, or by the index of its
 * facets (the model list's BANDS column). */
#define BAND_FACTORS_(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_FACTORS_##bands(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return 1;)
#define BAND_INDEX_(ID, num, name, alias, p, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_INDEX_##bands(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return 1;)
LSQT_INLINE int layer_bands_factored(__global const lsqt_dev_layer *l)
{
    LSQT_BSDFS(BAND_FACTORS_)
    (void)l;
    return 0;
}

LSQT_INLINE int layer_bands_index(__global const lsqt_dev_layer *l)
{
    LSQT_BSDFS(BAND_INDEX_)
    (void)l;
    return 0;
}

/* Medium mi's extinction in the band whose flights the path draws (the hero), and its
 * largest over the block (0: clear in every band). */
LSQT_INLINE real band_hero_mut(const walk_ctx *c, int mi)
{
    if (LSQT_NB == 1) return c->in.media[mi].mut;
    return band_tab(c, LSQT_BAND_MUT(c->in.scene->n_layers, LSQT_NBP, band_hero(c), mi));
}

LSQT_INLINE real band_most_mut(const walk_ctx *c, int mi)
{
    return LSQT_NB == 1 ? c->in.media[mi].mut : band_tab(c, mi);
}

/* Band b's own medium mi (its phase function, extinction and depths), after the block's
 * reference media in their buffer (device_layout.h), and whether medium mi's phase
 * functions differ between the block's bands. */
LSQT_INLINE __global const lsqt_dev_medium *band_medium(const walk_ctx *c, int b, int mi)
{
    const int n = c->in.scene->n_layers;
    return c->in.media + (1 + b) * (n + 1) + mi;
}

LSQT_INLINE int band_phases_differ(const walk_ctx *c, int mi)
{
    return LSQT_NB > 1 && band_tab(c, LSQT_BAND_PHASES(c->in.scene->n_layers, LSQT_NBP, 0, mi)) != R(0.0);
}

/* Russian roulette per band, as each band's own walk would play it: a band whose weight
 * is below LSQT_RR_WEIGHT goes on with that weight or stops (0), so a band that absorbs
 * costs no more than on its own paths (band_spread and nee_flush skip it). Returns
 * whether any band goes on. */
LSQT_INLINE int roulette(BAND_MEM real *wb, rng_t *rng)
{
    if (LSQT_NB == 1) {
        if (wb[0] >= LSQT_RR_WEIGHT) return 1;
        if (rng_uniform(rng) * LSQT_RR_WEIGHT >= wb[0]) return 0;
        wb[0] = LSQT_RR_WEIGHT;
        return 1;
    }
    int live = 0;
    BAND_LOOP
    for (int b = 0; b < LSQT_NB; b++) {
        if (wb[b] > R(0.0) && wb[b] < LSQT_RR_WEIGHT)
            wb[b] = rng_uniform(rng) * LSQT_RR_WEIGHT < wb[b] ? LSQT_RR_WEIGHT : R(0.0);
        live |= wb[b] > R(0.0);
    }
    return live;
}

/* wb *= f; whether any band still carries weight. (One band's in the one-band walk's
 * words: a loop over one band, even unrolled, costs it 7 VGPRs on gfx90a.) */
LSQT_INLINE int band_scale(BAND_MEM real *wb, real f)
{
    if (LSQT_NB == 1) {
        wb[0] *= f;
        return wb[0] > R(0.0);
    }
    int live = 0;
    BAND_LOOP
    for (int b = 0; b < LSQT_NB; b++) wb[b] *= f, live |= wb[b] > R(0.0);
    return live;
}

/* A band's sums s for a vector of directions plus its share of a vertex's terms v (the
 * unit model at the least depths, weight 1): on wo's side (same) times cs, the others co,
 * and where some band of the block is deeper (deeper) times 2^-(dtu a_up + dtd a_down),
 * the band's transmittance beyond the least depths (float's 2^-0 is a hair above 1). One
 * expression, s + f v, so that every compiler fuses it alike. The walk's sums
 * (band_spread) and lsqt_estimate's (walk.cl) take it alike. */
LSQT_INLINE realv band_add(realv s, realv v, maskv same, real cs, real co, real dtu, real dtd, int deeper, realv au,
                           realv ad)
{
    realv f = select((realv)(co), (realv)(cs), same);
    if (deeper) f *= exp2_negv(-(dtu * au + dtd * ad));
    return s + f * v;
}

/* Each band's optical depth beyond the block's least, above (tu) and below (td) a point
 * at height h of interior medium mi or, with mi < 0, beside layer li (all of the media
 * above it, all below). */
LSQT_INLINE void band_depths(const walk_ctx *c, int b, int mi, real h, int li, real tu, real td, real *dtu, real *dtd)
{
    const int n = c->in.scene->n_layers;
    if (mi >= 0) {
        const real mut = band_tab(c, LSQT_BAND_MUT(n, LSQT_NBP, b, mi)), th = c->in.media[mi].thickness;
        *dtu = band_tab(c, LSQT_BAND_TAU_ABOVE(n, LSQT_NBP, b, mi)) + mut * (th - h) - tu;
        *dtd = band_tab(c, LSQT_BAND_TAU_BELOW(n, LSQT_NBP, b, mi)) + mut * h - td;
    } else {
        *dtu = band_tab(c, LSQT_BAND_TAU_ABOVE(n, LSQT_NBP, b, li)) + band_tab(c, LSQT_BAND_MUT(n, LSQT_NBP, b, li)) * c->in.media[li].thickness - tu;
        *dtd = band_tab(c, LSQT_BAND_TAU_BELOW(n, LSQT_NBP, b, li + 1)) +
               band_tab(c, LSQT_BAND_MUT(n, LSQT_NBP, b, li + 1)) * c->in.media[li + 1].thickness - td;
    }
    /* Rounding may leave a hair below 0 where the depths are equal. */
    *dtu = fmax(*dtu, R(0.0)), *dtd = fmax(*dtd, R(0.0));
}

/* The optical depths of the media above layer li (tu) and below it (td), at the block's
 * least extinction (one band's own). */
LSQT_INLINE void layer_depths(const walk_ctx *c, int li, real *tu, real *td)
{
    __global const lsqt_dev_medium *above = &c->in.media[li], *below = &c->in.media[li + 1];
    *tu = above->tau_above + above->mut * above->thickness;
    *td = below->tau_below + below->mut * below->thickness;
}

/* The optical depths above (tu) and below (td) a point at height h of interior medium m,
 * at the block's least extinction. */
LSQT_INLINE void medium_depths(__global const lsqt_dev_medium *m, real h, real *tu, real *td)
{
    *tu = m->tau_above + m->mut * (m->thickness - h);
    *td = m->tau_below + m->mut * h;
}

/* A next-event vertex, for its bands' factors: on layer li (mi < 0), or at height h in
 * interior medium mi; with only >= 0, terms of band `only`'s own phase function at its
 * own depths (nee_medium), which go to that band alone. */
typedef struct {
    int li, mi;
    real h;
    int only;
} band_vertex;

/* Band b's factors at vertex x (tu, td: the least depths there), as (cs, co, dtu, dtd):
 * its weight times its fs on wo's side and its fo on the other (a medium's: its weight on
 * both), and its optical depths beyond the least. */
LSQT_INLINE real4 band_factors(const walk_ctx *c, const band_vertex *x, int b, const BAND_MEM real *wb, real tu,
                               real td)
{
    const int n = c->in.scene->n_layers;
    if (x->only >= 0) return b == x->only ? (real4)(wb[b], wb[b], R(0.0), R(0.0)) : (real4)(R(0.0));
    real dtu, dtd;
    band_depths(c, b, x->mi, x->h, x->li, tu, td, &dtu, &dtd);
    if (x->mi >= 0) return (real4)(wb[b], wb[b], dtu, dtd);
    return (real4)(wb[b] * band_tab(c, LSQT_BAND_FS(n, LSQT_NBP, b, x->li)),
                   wb[b] * band_tab(c, LSQT_BAND_FO(n, LSQT_NBP, b, x->li)), dtu, dtd);
}

/* Spreads the terms of vertex x (wo.z = woz), made at weight 1 for the unit model at the
 * least depths, to each band with its factors (band_factors): on the CPU path from the
 * scratch sums (c->sink.sum, then cleared) into each band's path sums at once, on the GPU
 * path as spread records after the vertex's (nee_records.cl), which lsqt_estimate spreads
 * the same way (walk.cl). A band without a term here (cs = co = 0: its weight is 0) is
 * skipped. One band's terms are its path's sums already. The factors are made here, where
 * they are used: made before a microsurface's walk, they cost the GPU path's walk
 * registers through it. */
LSQT_INLINE void band_spread(const walk_ctx *c, real woz, const band_vertex *x, const BAND_MEM real *wb)
{
    if (LSQT_NB == 1) return;
    real tu, td;
    if (x->mi >= 0)
        medium_depths(&c->in.media[x->mi], x->h, &tu, &td);
    else
        layer_depths(c, x->li, &tu, &td);
    if (LSQT_RECORDS) {
        BAND_LOOP
        for (int j = 0; j < NEE_SPREAD_RECORDS; j++) {
            nee_out *out = c->sink.out;
            if (out->rec) {
                __global lsqt_nee_rec *r = out->rec + out->n;
                for (int i = 0; i < LSQT_NEE_SPREAD_BANDS; i++) {
                    const int b = j * LSQT_NEE_SPREAD_BANDS + i;
                    LSQT_NEE_SPREAD(*r, i) = b < LSQT_NB ? band_factors(c, x, b, wb, tu, td) : (real4)(R(0.0));
                }
                LSQT_NEE_WOZ(*r) = woz, LSQT_NEE_KIND(*r) = (real)NEE_SPREAD;
            }
            out->n++;
        }
        return;
    }
    /* In private memory: in local memory, beside the sums the loop below writes, the
     * compiler would load them again at every vector (5 % of a 32-band run). */
    real cs[LSQT_NBW], co[LSQT_NBW], dtu[LSQT_NBW], dtd[LSQT_NBW];
    uint on = 0; /* the bands with a term here */
    int deeper = 0;
    BAND_LOOP
    for (int b = 0; b < LSQT_NB; b++) {
        const real4 f = band_factors(c, x, b, wb, tu, td);
        cs[b] = f.x, co[b] = f.y, dtu[b] = f.z, dtd[b] = f.w;
        on |= (f.x != R(0.0) || f.y != R(0.0)) ? 1u << b : 0u;
        deeper |= f.z != R(0.0) || f.w != R(0.0);
    }
    *c->band.touched |= on;
    __global const real *zs = c->in.wi + 2 * LSQT_NWI_PAD, *a_up = c->in.tab, *a_down = c->in.tab + LSQT_NWI_PAD;
    __local real *u = c->sink.sum, *bs = c->sink.bsum;
    for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW) {
        const realv v = VEC_AT(realv, u, k);
        if (!anyv(v != R(0.0))) continue;
        VEC_AT(realv, u, k) = (realv)(R(0.0));
        const maskv same = vloadv(0, zs + k) * woz > R(0.0);
        const realv au = vloadv(0, a_up + k), ad = vloadv(0, a_down + k);
        BAND_LOOP
        for (int b = 0; b < LSQT_NB; b++)
            if (on >> b & 1u) {
                __local real *s = bs + b * LSQT_NWI_PAD;
                VEC_AT(realv, s, k) = band_add(VEC_AT(realv, s, k), v, same, cs[b], co[b], dtu[b], dtd[b], deeper, au, ad);
            }
    }
}

/* The probability that band b's sampler leaves layer li on wo's side. */
LSQT_INLINE real side_probability(const walk_ctx *c, int b, int li)
{
    const int n = c->in.scene->n_layers;
    const real fs = band_tab(c, LSQT_BAND_FS(n, LSQT_NBP, b, li)), fo = band_tab(c, LSQT_BAND_FO(n, LSQT_NBP, b, li));
    return fs + fo > R(0.0) ? fs / (fs + fo) : R(0.5);
}

/* A factored layer's sample for a block (the list's BANDS FACTORS): the hero's side, then
 * the unit model's cosine sample there, weighed by spectral MIS as flights are
 * (flight_weights): each band's weight times its factor on the side taken. Returns
 * whether any band still carries weight. */
LSQT_INLINE int band_side_sample(const walk_ctx *c, __global const lsqt_dev_layer *l, int li, real3 d,
                                 BAND_MEM real *wb, BAND_MEM real *rb, rng_t *rng, real3 *wi)
{
    /* The hero's side, wo's with probability fs / (fs + fo) (1/2 where its band has
     * neither); every band's weight by its own factor over the bands' mixture. */
    const real u0 = rng_uniform(rng), u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    const int same = u0 < side_probability(c, band_hero(c), li);
    real3 v = sample_cosine_hemisphere(u1, u2);
    v.z *= (-d.z >= R(0.0)) == same ? R(1.0) : R(-1.0);
    /* the unit model over its cosine sampler's density (1 for Lambertian) */
    const real az = fabs(v.z), unit = az > R(0.0) ? bsdf_eval(l, -d, v) * LSQT_PI / az : R(0.0);
    real sum = R(0.0);
    BAND_LOOP
    for (int j = 0; j < LSQT_NB; j++) {
        const real p = side_probability(c, j, li);
        rb[j] *= same ? p : R(1.0) - p, sum += rb[j];
    }
    if (!(sum > R(0.0))) return 0;
    const real inv = (real)LSQT_NB / sum;
    const int n = c->in.scene->n_layers;
    __global const real *f = c->in.bw + (same ? LSQT_BAND_FS(n, LSQT_NBP, 0, li) : LSQT_BAND_FO(n, LSQT_NBP, 0, li));
    int live = 0;
    BAND_LOOP
    for (int b = 0; b < LSQT_NB; b++) {
        wb[b] = (wb[b] * f[b]) * unit * inv, rb[b] *= inv;
        live |= wb[b] > R(0.0);
    }
    *wi = v;
    return live;
}

/* A collision's direction in medium mi where the bands' phase functions differ: the
 * hero's sample (exact: its density is its phase function), and each band's weight
 * times its own phase function over the bands' mixture of densities, as flights are
 * (flight_weights). pv: the vertex's (phase_vertex; nothing for the exact samplers).
 * Returns whether any band still carries weight. */
LSQT_INLINE int band_phase_sample(const walk_ctx *c, int mi, const phase_vtx *pv, real3 wo, BAND_MEM real *wb,
                                  BAND_MEM real *rb, rng_t *rng, real3 *wi)
{
    if (!(phase_sample(band_medium(c, band_hero(c), mi), pv, wo, rng, wi) > R(0.0))) return 0;
    BAND_MEM real *lv = band_row(c, BAND_LV);
    real sum = R(0.0);
    BAND_LOOP
    for (int j = 0; j < LSQT_NB; j++) {
        lv[j] = phase_eval(band_medium(c, j, mi), pv, wo, *wi);
        rb[j] *= lv[j], sum += rb[j];
    }
    if (!(sum > R(0.0))) return 0;
    const real inv = (real)LSQT_NB / sum;
    int live = 0;
    BAND_LOOP
    for (int b = 0; b < LSQT_NB; b++) {
        wb[b] = (wb[b] * lv[b]) * inv, rb[b] *= inv;
        live |= wb[b] > R(0.0);
    }
    return live;
}

/* A free flight of length t in medium mi, drawn from the hero band's extinction, ended
 * by a collision (collided) or by the medium's boundary. Spectral MIS: each band's
 * weight becomes its own transport over the bands' mixture of densities of the path (the
 * balance heuristic), kept as wb (the weights) and rb (each band's density of the path
 * over the mixture's, mean 1). A band's density of this flight is mut e^-(mut t) for a
 * collision and e^-(mut t) for a boundary; its weight keeps its ratio to rb (its weight
 * on its own paths), times its albedo at a collision. LSQT_VW bands at a time. */
LSQT_INLINE int flight_weights(const walk_ctx *c, int mi, real t, int collided, BAND_MEM real *wb, BAND_MEM real *rb)
{
    if (LSQT_NB == 1) { /* the band's own density: its albedo at a collision */
        if (!collided) return 1;
        wb[0] *= (real)c->in.media[mi].mus / (real)c->in.media[mi].mut;
        return wb[0] > R(0.0);
    }
    const int n = c->in.scene->n_layers;
    __global const real *mts = c->in.bw + LSQT_BAND_MUT(n, LSQT_NBP, 0, mi), *muss = c->in.bw + LSQT_BAND_MUS(n, LSQT_NBP, 0, mi);
    const real mt_h = mts[band_hero(c)];
    /* One extinction in every band: every band's density is the hero's (rb stays), and a
     * collision weighs each band by its albedo. */
    int alike = 1;
    real mt_min = mt_h;
    for (int j = 0; j < LSQT_NB; j++) alike &= mts[j] == mt_h, mt_min = fmin(mt_min, mts[j]);
    if (alike) {
        if (!collided) return 1;
        int live = 0;
        for (int j = 0; j < LSQT_NB; j++) wb[j] *= muss[j] / mt_h, live |= wb[j] > R(0.0);
        return live;
    }
    /* The densities relative to the least extinct band's e^-(mut t): each factor at most
     * 1, so no overflow; the padding lanes (mut 0, rb 0) stay 0. */
    const real et = -t * LSQT_LOG2E;
    BAND_MEM real *lv = band_row(c, BAND_LV);
    realv acc = (realv)(R(0.0));
    for (int j = 0; j < LSQT_NBV; j += LSQT_VW) {
        const realv mt = vloadv(0, mts + j), r = vloadv(0, rb + j);
        realv p = r * exp2_negv(fmin((mt - mt_min) * et, R(0.0)));
        if (collided) p *= mt;
        vstorev(p, 0, lv + j);
        acc += p;
    }
    real sum = sumv(acc);
    /* Where every band's density is below float's normal range (a band far less extinct
     * than the others, with little rb), the same products in log2, relative to the
     * largest (e held within +-1e4: a flight whose depths differ by more, e^-7000, weighs
     * the same as at 1e4). */
    if (!(sum > R(1e-30))) {
        real top = -INFINITY;
        for (int j = 0; j < LSQT_NB; j++) {
            const real dm = mts[j] - mt_h;
            real v = (dm == R(0.0) ? R(0.0) : clamp(dm * et, R(-1e4), R(1e4))) + log2(rb[j]);
            if (collided) v += log2(mts[j]);
            lv[j] = v, top = fmax(top, v);
        }
        if (!(top > -INFINITY)) return 0;
        sum = R(0.0);
        for (int j = 0; j < LSQT_NB; j++) lv[j] = exp2(lv[j] - top), sum += lv[j];
    }
    const real inv = (real)LSQT_NB / sum;
    maskv live = (maskv)(0);
    for (int j = 0; j < LSQT_NBV; j += LSQT_VW) {
        const realv p = vloadv(0, lv + j), r = vloadv(0, rb + j), mt = vloadv(0, mts + j);
        realv own = select((realv)(R(0.0)), vloadv(0, wb + j) / r, r > R(0.0));
        if (collided) own *= select((realv)(R(0.0)), vloadv(0, muss + j) / mt, mt > R(0.0));
        const realv w = (own * p) * inv;
        vstorev(p * inv, 0, rb + j);
        vstorev(w, 0, wb + j);
        live |= w > R(0.0);
    }
    return anyv(live);
}
