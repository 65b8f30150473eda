/* Band blocks: LSQT_NB bands on one path (docs/design.md, 3.7). Compiled only into a
 * program built with -DLSQT_NB > 1 (the host's band blocks, host/sim/band_blocks.c); a
 * one-band program has none of it.
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
 *   optical depths, into the scratch sums (c->sum), and spread to each band's sums with
 *   the band's factor and, where its media are deeper, its extra transmittance.
 * A block's paths are its own (the hero and the per-band roulette draw numbers a one-band
 * walk does not), so a band of a block agrees with its one-band run within the error
 * bars, not bit for bit. */
#if LSQT_NB > 1

#ifdef LSQT_NEE_RECORDS
#error "band blocks run on the CPU code path only"
#endif

LSQT_INLINE real band_tab(const walk_ctx *c, int at) { return c->bw[at]; }

/* Russian roulette per band, as each band's own walk would play it: a band whose weight
 * is below LSQT_RR_WEIGHT goes on with that weight or stops (0), so a band that absorbs
 * costs no more than on its own paths (band_spread and nee_flush skip it). Returns
 * whether any band goes on. */
LSQT_INLINE int roulette_bands(real *wb, rng_t *rng)
{
    int live = 0;
    for (int b = 0; b < LSQT_NB; b++) {
        if (wb[b] > R(0.0) && wb[b] < LSQT_RR_WEIGHT)
            wb[b] = rng_uniform(rng) * LSQT_RR_WEIGHT < wb[b] ? LSQT_RR_WEIGHT : R(0.0);
        live |= wb[b] > R(0.0);
    }
    return live;
}

/* wb *= f; whether any band still carries weight. */
LSQT_INLINE int band_scale(real *wb, real f)
{
    int live = 0;
    for (int b = 0; b < LSQT_NB; b++) wb[b] *= f, live |= wb[b] > R(0.0);
    return live;
}

/* Spreads the scratch sums of one vertex (c->sum, weight 1, the unit model at the least
 * depths) into each band's sums: lanes on wo's side (z * woz > 0) times cs[b], the others
 * co[b], and each times 2^-(dtu[b] a_up + dtd[b] a_down), the band's transmittance beyond
 * the least depths (skipped where no band has any). Clears the scratch sums. */
LSQT_INLINE void band_spread(const walk_ctx *c, real woz, const real *cs, const real *co, const real *dtu,
                             const real *dtd)
{
    int deeper = 0;
    for (int b = 0; b < LSQT_NB; b++) deeper |= dtu[b] != R(0.0) || dtd[b] != R(0.0);
    __global const real *zs = c->wi + 2 * LSQT_NWI_PAD, *a_up = c->tab, *a_down = c->tab + LSQT_NWI_PAD;
    __local real *u = c->sum, *bs = c->bsum;
    uint on = 0; /* the bands with a term here (the others' weights are 0) */
    for (int b = 0; b < LSQT_NB; b++) on |= (cs[b] != R(0.0) || co[b] != R(0.0)) ? 1u << b : 0u;
    *c->touched |= on;
    for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW) {
        const realv v = VBLOCK(realv, u, k);
        if (!anyv(v != R(0.0))) continue;
        VBLOCK(realv, u, k) = (realv)(R(0.0));
        const maskv same = vloadv(0, zs + k) * woz > R(0.0);
        if (deeper) {
            const realv au = vloadv(0, a_up + k), ad = vloadv(0, a_down + k);
            for (int b = 0; b < LSQT_NB; b++) {
                if (!(on >> b & 1u)) continue;
                const realv t = exp2_negv(-(dtu[b] * au + dtd[b] * ad));
                VBLOCK(realv, bs + b * LSQT_NWI_PAD, k) += select((realv)(co[b]), (realv)(cs[b]), same) * t * v;
            }
        } else {
            for (int b = 0; b < LSQT_NB; b++)
                if (on >> b & 1u) VBLOCK(realv, bs + b * LSQT_NWI_PAD, k) += select((realv)(co[b]), (realv)(cs[b]), same) * v;
        }
    }
}

/* Each band's optical depth beyond the block's least, above (tu) and below (td) a point
 * at height h of interior medium mi or, with mi < 0, beside layer li (all of the media
 * above it, all below). */
LSQT_INLINE void band_depths(const walk_ctx *c, int b, int mi, real h, int li, real tu, real td, real *dtu, real *dtd)
{
    const int n = c->scene->n_layers;
    if (mi >= 0) {
        const real mut = band_tab(c, LSQT_BAND_MUT(n, LSQT_NBP, b, mi)), th = c->media[mi].thickness;
        *dtu = band_tab(c, LSQT_BAND_TAU_ABOVE(n, LSQT_NBP, b, mi)) + mut * (th - h) - tu;
        *dtd = band_tab(c, LSQT_BAND_TAU_BELOW(n, LSQT_NBP, b, mi)) + mut * h - td;
    } else {
        *dtu = band_tab(c, LSQT_BAND_TAU_ABOVE(n, LSQT_NBP, b, li)) + band_tab(c, LSQT_BAND_MUT(n, LSQT_NBP, b, li)) * c->media[li].thickness - tu;
        *dtd = band_tab(c, LSQT_BAND_TAU_BELOW(n, LSQT_NBP, b, li + 1)) +
               band_tab(c, LSQT_BAND_MUT(n, LSQT_NBP, b, li + 1)) * c->media[li + 1].thickness - td;
    }
    /* Rounding may leave a hair below 0 where the depths are equal. */
    *dtu = fmax(*dtu, R(0.0)), *dtd = fmax(*dtd, R(0.0));
}

/* The probability that band b's sampler leaves layer li on wo's side. */
LSQT_INLINE real side_probability(const walk_ctx *c, int b, int li)
{
    const int n = c->scene->n_layers;
    const real fs = band_tab(c, LSQT_BAND_FS(n, LSQT_NBP, b, li)), fo = band_tab(c, LSQT_BAND_FO(n, LSQT_NBP, b, li));
    return fs + fo > R(0.0) ? fs / (fs + fo) : R(0.5);
}

/* wb *= each band's Fresnel factor at a facet whose cosine with the ray is vm (the
 * conductor li's n and k per band: bw's rows), LSQT_VW bands at a time; bands without
 * weight (and the padding lanes, n = k = 0) stay 0. */
LSQT_INLINE void fresnel_bands(const walk_ctx *c, int li, real vm, real *wb)
{
    const int n = c->scene->n_layers;
    __global const real *etas = c->bw + LSQT_BAND_ETA(n, LSQT_NBP, 0, li), *ks = c->bw + LSQT_BAND_KAPPA(n, LSQT_NBP, 0, li);
    for (int j = 0; j < LSQT_NBP; j += LSQT_VW) {
        const realv w = vloadv(0, wb + j);
        const realv f = fresnel_conductor_lanes(vloadv(0, etas + j), vloadv(0, ks + j), (realv)(vm));
        vstorev(select((realv)(R(0.0)), w * f, w > R(0.0)), 0, wb + j);
    }
}

/* A hidden conductor's vertex (one under another layer that is not null: light leaves
 * it only through that layer, so it has no next-event terms, and the bands' n and k may
 * differ; host/sim/band_blocks.c). The sample of microsurface.cl on the block's unit
 * layer (conductor_sample for single scattering, else ms_walk's walk of reflections),
 * each reflection weighed by each band's Fresnel factor instead of the unit layer's. The
 * walk does not depend on the band, so no band's density of the path changes (rb stays),
 * and it plays no roulette of its own (the factors only shrink; roulette_bands follows
 * the vertex). Returns whether any band still carries weight. */
LSQT_INLINE int conductor_vertex_bands(const walk_ctx *c, __global const lsqt_dev_layer *l, int li, real3 d,
                                       real *wb, rng_t *rng, real3 *wi)
{
    const real alpha = l->p[0];
    if (!(d.z < R(0.0))) return band_scale(wb, R(0.0)); /* light reaches it from above only */
    if (!l->multiple_scattering) {
        const real3 wo = -d;
        (void)rng_uniform(rng); /* conductor_sample's u0, unused */
        const real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
        ms_vtx x = ms_vertex(alpha, wo, R(1.0), R(1.0), u1, u2);
        real vm;
        const real3 r = conductor_reflect(&x, &vm);
        const real lam_v = ggx_lambda(alpha, wo.z);
        if (!(vm > R(0.0)) || !(r.z > R(0.0))) return band_scale(wb, R(0.0));
        fresnel_bands(c, li, vm, wb);
        *wi = r;
        return band_scale(wb, (R(1.0) + lam_v) / (R(1.0) + lam_v + ggx_lambda(alpha, r.z)));
    }
    real3 r = d; /* from above: the ray's side's frame is the world's */
    real h = R(1.0);
    for (int order = 1;; order++) {
        if (!ms_next_height(alpha, r, &h, R(1.0) - rng_uniform(rng))) break;
        if (order > LSQT_MS_MAX_ORDER) return band_scale(wb, R(0.0));
        const real u1 = rng_uniform(rng), u2 = rng_uniform(rng);
        ms_vtx x = ms_vertex(alpha, -r, h, R(1.0), u1, u2);
        real vm;
        r = conductor_reflect(&x, &vm);
        if (!(vm > R(0.0))) return band_scale(wb, R(0.0));
        fresnel_bands(c, li, vm, wb); /* every reflection's, in every band */
    }
    *wi = r;
    return band_scale(wb, R(1.0));
}

/* layer_vertex for a block: the next-event terms of layer li for every band, then the
 * hero's sample, weighed by spectral MIS as flights are (flight_bands). Returns whether
 * any band still carries weight. */
LSQT_INLINE int layer_vertex_bands(const walk_ctx *c, int li, real3 d, real *wb, real *rb, rng_t *rng, real3 *wi)
{
    const int n = c->scene->n_layers;
    const int up = li == c->scene->top_nonnull, down = li == c->scene->bottom_nonnull;
    __global const lsqt_dev_layer *l = &c->layers[li];
    if (LSQT_ON(BSDF_MS_CONDUCTIVE) && l->kind == LSQT_BSDF_MS_CONDUCTIVE && !up) {
        c->work[WORK_LAYER]++;
        return conductor_vertex_bands(c, l, li, d, wb, rng, wi); /* no factors, no terms */
    }
    __global const lsqt_dev_medium *above = &c->media[li], *below = &c->media[li + 1];
    const real tau_up = above->tau_above + above->mut * above->thickness;
    const real tau_down = below->tau_below + below->mut * below->thickness;
    const int visible = c->nee_on && nee_visible(tau_up, tau_down, up, down);
    __global const real *tab = c->tab + LSQT_LAYER_TAB(li);
    real cs[LSQT_NB], co[LSQT_NB], dtu[LSQT_NB], dtd[LSQT_NB];
    for (int b = 0; b < LSQT_NB; b++) {
        cs[b] = wb[b] * band_tab(c, LSQT_BAND_FS(n, LSQT_NBP, b, li));
        co[b] = wb[b] * band_tab(c, LSQT_BAND_FO(n, LSQT_NBP, b, li));
        band_depths(c, b, -1, R(0.0), li, tau_up, tau_down, &dtu[b], &dtd[b]);
    }
    c->work[WORK_LAYER]++;
    if (layer_is_micro(l)) { /* the same in every band (fs = fo = 1) */
        ms_sink k;
        nee_ms_sink(c, tab, li, &k);
        const real f = ms_vertex_walks(l, d, rng, R(1.0), visible, &k, wi);
        if (visible) band_spread(c, -d.z, cs, co, dtu, dtd);
        return band_scale(wb, f);
    }
    if (visible) {
        c->work[WORK_NEE]++;
        nee_layer_terms(c, l, li, -d, R(1.0), tab);
        band_spread(c, -d.z, cs, co, dtu, dtd);
    }
    /* The hero's side, wo's with probability fs / (fs + fo) (1/2 where its band has
     * neither); every band's weight by its own factor over the bands' mixture. */
    const real u0 = rng_uniform(rng), u1 = rng_uniform(rng), u2 = rng_uniform(rng);
    const int same = u0 < side_probability(c, c->hero, li);
    real3 v = sample_cosine_hemisphere(u1, u2);
    v.z *= (-d.z >= R(0.0)) == same ? R(1.0) : R(-1.0);
    /* the unit model over its cosine sampler's density (1 for Lambertian) */
    const real az = fabs(v.z), unit = az > R(0.0) ? bsdf_eval(l, -d, v) * LSQT_PI / az : R(0.0);
    real sum = R(0.0);
    for (int j = 0; j < LSQT_NB; j++) {
        const real p = side_probability(c, j, li);
        rb[j] *= same ? p : R(1.0) - p, sum += rb[j];
    }
    if (!(sum > R(0.0))) return 0;
    const real inv = (real)LSQT_NB / sum;
    int live = 0;
    for (int b = 0; b < LSQT_NB; b++) {
        wb[b] = (same ? cs[b] : co[b]) * unit * inv, rb[b] *= inv;
        live |= wb[b] > R(0.0);
    }
    *wi = v;
    return live;
}

/* A free flight of length t in medium mi, drawn from the hero band's extinction, ended
 * by a collision (collided) or by the medium's boundary. Spectral MIS: each band's
 * weight becomes its own transport over the bands' mixture of densities of the path (the
 * balance heuristic), kept as wb (the weights) and rb (each band's density of the path
 * over the mixture's, mean 1). A band's density of this flight is mut e^-(mut t) for a
 * collision and e^-(mut t) for a boundary; its weight keeps its ratio to rb (its weight
 * on its own paths), times its albedo at a collision. LSQT_VW bands at a time. */
LSQT_INLINE int flight_bands(const walk_ctx *c, int mi, real t, int collided, real *wb, real *rb)
{
    const int n = c->scene->n_layers;
    __global const real *mts = c->bw + LSQT_BAND_MUT(n, LSQT_NBP, 0, mi), *muss = c->bw + LSQT_BAND_MUS(n, LSQT_NBP, 0, mi);
    const real mt_h = mts[c->hero];
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
    real lv[LSQT_NBP];
    realv acc = (realv)(R(0.0));
    for (int j = 0; j < LSQT_NBP; j += LSQT_VW) {
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
        for (int j = 0; j < LSQT_NBP; j += LSQT_VW) {
            const realv mt = vloadv(0, mts + j), dm = mt - mt_h;
            realv v = select(clamp(dm * et, R(-1e4), R(1e4)), (realv)(R(0.0)), dm == R(0.0));
            v += log2(vloadv(0, rb + j));
            if (collided) v += log2(mt);
            vstorev(v, 0, lv + j);
        }
        for (int j = 0; j < LSQT_NB; j++) top = fmax(top, lv[j]);
        if (!(top > -INFINITY)) return 0;
        for (int j = 0; j < LSQT_NBP; j += LSQT_VW) vstorev(exp2(vloadv(0, lv + j) - top), 0, lv + j);
        sum = R(0.0);
        for (int j = 0; j < LSQT_NB; j++) sum += lv[j];
    }
    for (int j = 0; j < LSQT_NBP; j += LSQT_VW) {
        const realv p = vloadv(0, lv + j), r = vloadv(0, rb + j), mt = vloadv(0, mts + j);
        realv own = select((realv)(R(0.0)), vloadv(0, wb + j) / r, r > R(0.0));
        if (collided) own *= select((realv)(R(0.0)), vloadv(0, muss + j) / mt, mt > R(0.0));
        vstorev(p, 0, rb + j);
        vstorev(own * p, 0, wb + j);
    }
    const real inv = (real)LSQT_NB / sum;
    maskv live = (maskv)(0);
    for (int j = 0; j < LSQT_NBP; j += LSQT_VW) {
        const realv w = vloadv(0, wb + j) * inv;
        vstorev(vloadv(0, rb + j) * inv, 0, rb + j);
        vstorev(w, 0, wb + j);
        live |= w > R(0.0);
    }
    return anyv(live);
}

/* nee_medium for a block: the terms once, spread to every band. */
LSQT_NOINLINE_CPU void nee_medium_bands(const walk_ctx *c, int mi, real h, real3 d, const real *wb,
                                        const phase_vtx *pv)
{
    __global const lsqt_dev_medium *m = &c->media[mi];
    const int top = c->scene->top_nonnull, bottom = c->scene->bottom_nonnull;
    const int up = top < 0 || mi <= top, down = bottom < 0 || mi > bottom;
    const real tau_up = m->tau_above + m->mut * (m->thickness - h);
    const real tau_down = m->tau_below + m->mut * h;
    if (!c->nee_on || !nee_visible(tau_up, tau_down, up, down)) return;
    c->work[WORK_NEE]++;
    const real tu = up && tau_up < LSQT_NEE_TAU_MAX ? tau_up : R(1e30);
    const real td = down && tau_down < LSQT_NEE_TAU_MAX ? tau_down : R(1e30);
    nee_medium_terms(c, m, mi, -d, R(1.0), pv, tu, td);
    real dtu[LSQT_NB], dtd[LSQT_NB];
    for (int b = 0; b < LSQT_NB; b++) band_depths(c, b, mi, h, -1, tau_up, tau_down, &dtu[b], &dtd[b]);
    band_spread(c, -d.z, wb, wb, dtu, dtd);
}

#endif
