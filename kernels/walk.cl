/* The path loop: the only place that knows about layers and media together.
 *
 * Indexing: media 0..n, layers 0..n-1, layer L lies between media L (above) and L+1
 * (below). Media 0 and n are the clear outside; a path that enters medium 0 going up has
 * left the stack (reflection), one that enters medium n going down has too (transmission).
 * Inside an interior medium the position is the height h above its bottom boundary, so a
 * thin medium far from z = 0 is as exact as one near it. */
/* Work-group accumulators of the tallies (tally.cl's acc_word, 128-bit sums): the
 * LSQT_T_COUNT scalars for the whole chunk, and on the CPU path the directions' sums in
 * tiles of LSQT_ACC_TILE at the chunk's end (16 (LSQT_ACC_TILE + LSQT_T_COUNT) bytes:
 * 4.2 KB). A path's point estimates are summed per direction in floating point (`sum`,
 * in the path's own fixed order) and converted to fixed point once per path; the
 * work-item keeps those in integers of its own (no atomics on the hot path: on the CPU
 * path in the group's local memory, LSQT_ITEMS; on the GPU path in registers,
 * lsqt_estimate), and adds them once into the work-group's or the batch's. Integer sums
 * keep the result independent of order. */
#define LSQT_ACC_TILE (LSQT_NWI < 256 ? LSQT_NWI : 256)

/* The CPU path's work-group size (the host passes -DLSQT_ITEMS when it is not 1). A CPU
 * runs a group's work-items one after another on one thread, so a group of one is the
 * fastest: its work-item keeps the path's sums and the chunk's low words of every
 * direction in the group's local memory, LSQT_ITEMS x LSQT_NWI_PAD x (sizeof(real) + 8)
 * bytes (12 KB at 1024 directions, 96 KB at the pilot's 8192; the host checks the
 * device's limit). The GPU path keeps none (lsqt_estimate). */
#ifndef LSQT_ITEMS
#define LSQT_ITEMS 1
#endif

/* Bands on one path (bands.cl): 1 in a one-band program, which compiles no band code. A
 * block's work-item keeps per band its path's sums and its low words, and one more row
 * of sums for a vertex's terms before they are spread (LSQT_SUM_ROWS). */
#ifndef LSQT_NB
#define LSQT_NB 1
#endif
#define LSQT_SUM_ROWS (LSQT_NB > 1 ? LSQT_NB + 1 : 1)
/* The band count padded to the vector width: a block's per-band arrays and its table's
 * rows are this long, so that bands.cl can take them LSQT_VW at a time. */
#define LSQT_NBP LSQT_PAD(LSQT_NB, LSQT_VW)

/* A work-item's work counters, in the order of the LSQT_T_LAYER_EVENTS... tallies. */
#define WORK_LAYER (LSQT_T_LAYER_EVENTS - LSQT_T_LAYER_EVENTS)
#define WORK_MEDIUM (LSQT_T_MEDIUM_EVENTS - LSQT_T_LAYER_EVENTS)
#define WORK_NEE (LSQT_T_NEE_VERTICES - LSQT_T_LAYER_EVENTS)
#define WORK_N (LSQT_T_COUNT - LSQT_T_LAYER_EVENTS)

typedef struct {
    __constant lsqt_dev_scene *scene;
    __global const lsqt_dev_medium *media;
    __global const lsqt_dev_layer *layers;
    __global const real *wi;           /* this slice's directions: x[pad], y[pad], z[pad] */
    __global const real *tab;          /* this slice's direction tables (lsqt_prepare) */
    __local real *sum;                 /* the current path's point estimates (CPU path; a band
                                          block's: the current vertex's, bands.cl) */
    __local real *bsum;                /* a band block's: each band's path sums, LSQT_NWI_PAD apart */
    __global const real *bw;           /* a band block's table (LSQT_BAND_AT), else unused */
    __local ulong *nee;                /* this work-item's point-estimate sums, low words (CPU path;
                                          a band block's: each band's, LSQT_NWI_PAD apart) */
    work_t *work;                      /* the work counters (LSQT_T_LAYER_EVENTS ...; work_t) */
    volatile __local acc_word *acc;    /* the work-group's scalar tallies, LSQT_ACC_WORDS each */
    __global ulong *nee_g;             /* the tallies of the chunk's batch (nee_word) */
    uint v;                            /* the first state slice of this walk */
    int batch;
    volatile __global uint *flags;
    int nee_on;                        /* 0: no point estimates (the RRSS candidate walks) */
    int hero;                          /* a band block's: the band whose flights the path draws */
    uint *touched;                     /* a band block's: the bands the path has added to (bits) */
    __global real *exit_dir;           /* non-0: the path only writes its exit direction here */
    nee_out *out;                      /* the path's next-event records (GPU path) */
    int count_only;                    /* 1: count the records, tally nothing (GPU path) */
} walk_ctx;

/* Direction k's tally of the walk's batch (state slice v + k / LSQT_GROUP_PAD), or 0 for
 * the padding between a grouped session's blocks. */
LSQT_INLINE __global ulong *nee_word(__global ulong *nee, uint v, int batch, int k)
{
    const uint b = (uint)k / LSQT_GROUP_PAD, j = (uint)k % LSQT_GROUP_PAD;
    if (j >= LSQT_GROUP_NWI) return 0;
    return nee + 2 * (((ulong)(v + b) * LSQT_BATCHES + (ulong)batch) * LSQT_GROUP_NWI + j);
}

/* Adds v to scalar tally k (LSQT_T_R ...) of band b of a block (0 in a one-band program). */
LSQT_INLINE void acc_add_band(const walk_ctx *c, int b, int k, real v)
{
    if (v != R(0.0)) {
        fix1 q = to_fixed(v, c->flags);
        local_add128(c->acc + LSQT_ACC_WORDS * (b * LSQT_T_COUNT + k), q.lo, q.hi, c->flags);
    }
}

LSQT_INLINE void acc_add(const walk_ctx *c, int k, real v) { acc_add_band(c, 0, k, v); }

/* A slice's direction tables: for the media's transmittance, up[pad] = log2(e) / z where
 * z > 0, 0 where z < 0, and down[pad] = log2(e) / -z where z < 0, 0 where z > 0 (so a
 * vertex's transmittance towards direction k is 2^-(tau_up up[k] + tau_down down[k]), with
 * no select or division in the loop), both 1e30 where z = 0 (padding: transmittance 0,
 * as light cannot leave horizontally); then each layer's: T[pad] (transmittance of the media
 * light crosses leaving that way, 0 where it may not leave), Lambda[pad] and
 * lgamma(1 + Lambda)[pad] of the layer's microfacets. */
#define LSQT_TAB_STRIDE (LSQT_LAYER_TAB_ROWS * LSQT_NWI_PAD)
#define LSQT_LAYER_TAB(li) (LSQT_MEDIA_TAB_ROWS * LSQT_NWI_PAD + (li) * LSQT_TAB_STRIDE)
#define LSQT_SLICE_TAB(n_layers) LSQT_LAYER_TAB(n_layers)
#define LSQT_LOG2E R(1.44269504088896340736)

/* A contribution below 2^-41 rounds to 0 in fixed point. Weights are at most 1 and
 * values at most 2^44 (a larger one fails the run), so light that must cross more than
 * this optical thickness (exp(-60) < 2^-86) cannot change a tally: skipping it is exact,
 * and saves the work at the deep vertices of optically thick media. */
#define LSQT_NEE_TAU_MAX R(60.0)

LSQT_INLINE int nee_visible(real tau_up, real tau_down, int up, int down)
{
    return (up && tau_up < LSQT_NEE_TAU_MAX) || (down && tau_down < LSQT_NEE_TAU_MAX);
}

/* Transmittance towards directions z (inv_az = 1 / |z|, from the slice's table), 0 where
 * leaving that way is not allowed. */
LSQT_INLINE realv nee_transmittancev(realv z, realv inv_az, real tau_up, real tau_down, int up, int down)
{
    realv t = (realv)(R(1.0));
    if (tau_up > R(0.0) || tau_down > R(0.0))
        t = exp(-select((realv)(tau_down), (realv)(tau_up), z > R(0.0)) * inv_az);
    maskv ok = ((z > R(0.0)) & (maskv)(up && tau_up < LSQT_NEE_TAU_MAX ? -1 : 0)) |
               ((z < R(0.0)) & (maskv)(down && tau_down < LSQT_NEE_TAU_MAX ? -1 : 0));
    return select((realv)(R(0.0)), t, ok);
}

/* Per launch, per slice and layer: the direction table (the work that does not depend on
 * the vertex). Global size (LSQT_NWI_PAD, n_slices). */
__kernel void lsqt_prepare(__constant lsqt_dev_scene *scene, __global const lsqt_dev_medium *media,
                           __global const lsqt_dev_layer *layers, __global const real *wi_dirs,
                           __global real *tab)
{
    const int k = (int)get_global_id(0), slice = (int)get_global_id(1), n = scene->n_layers;
    const real z = wi_dirs[(3 * slice + 2) * LSQT_NWI_PAD + k], inv_az = R(1.0) / fabs(z);
    __global real *st = tab + (size_t)slice * LSQT_SLICE_TAB(n);
    st[k] = z > R(0.0) ? LSQT_LOG2E * inv_az : z < R(0.0) ? R(0.0) : R(1e30);
    st[LSQT_NWI_PAD + k] = z < R(0.0) ? LSQT_LOG2E * inv_az : z > R(0.0) ? R(0.0) : R(1e30);
    for (int li = 0; li < n; li++) {
        __global const lsqt_dev_layer *l = &layers[li];
        __global const lsqt_dev_medium *above = &media[li], *below = &media[li + 1];
        const int up = li == scene->top_nonnull, down = li == scene->bottom_nonnull;
        real tau_up = above->tau_above + above->mut * above->thickness;
        real tau_down = below->tau_below + below->mut * below->thickness;
        int micro = l->kind == LSQT_BSDF_MS_LAMBERTIAN || l->kind == LSQT_BSDF_MS_DIELECTRIC ||
                    l->kind == LSQT_BSDF_MS_CONDUCTIVE;
        real lam = micro ? ggx_lambda(l->p[0], z) : R(0.0);
        __global real *t = st + LSQT_LAYER_TAB(li);
        t[k] = nee_transmittancev((realv)(z), (realv)(inv_az), tau_up, tau_down, up, down).s0;
        t[LSQT_NWI_PAD + k] = lam;
        t[2 * LSQT_NWI_PAD + k] = lgamma_ge1(R(1.0) + lam);
    }
}

/* The next-event terms of one vertex for the block of LSQT_VW directions at b, the same
 * text for both code paths (the CPU's sums per path, the GPU's records). Lanes with
 * t = 0 add nothing, even where the model is not finite (the zero vectors that pad the
 * directions). A layer's closed-form BSDF (tab: its table, T first; microsurfaces take
 * ms_vertex_walks): */
LSQT_INLINE realv nee_layer_block(__global const lsqt_dev_layer *l, real3 wo, real w, __global const real *dirs,
                                    __global const real *tab, int b)
{
    const realv t = vloadv(0, tab + b);
    return select((realv)(R(0.0)), (w * bsdf_evalv_closed(l, wo, load_dirv(dirs, b))) * t, t > R(0.0));
}

/* A medium's phase function at optical depths tu above and td below the vertex (a_up,
 * a_down: the slice's media rows). */
LSQT_INLINE realv nee_medium_block(__global const lsqt_dev_medium *m, const phase_vtx *pv, real3 wo, real w, real tu,
                                     real td, __global const real *dirs, __global const real *a_up,
                                     __global const real *a_down, int b)
{
    const realv t = exp2_negv(-(tu * vloadv(0, a_up + b) + td * vloadv(0, a_down + b)));
    return select((realv)(R(0.0)), (w * phase_evalv(m, pv, wo, load_dirv(dirs, b))) * t, t > R(0.0));
}

/* Converts one path's sums of the block at k to fixed point, adds them to lo, the low
 * 64-bit words of the block's tallies, and returns the new low words. A high word (a sum
 * above 2^63 units, 8e6, or a carry out of the low word) is rare and goes straight to the
 * batch's 128-bit sum in global memory (nee_word of nee, state slice vs, batch), where it counts the same.
 * The common case by one test per block: every lane in [0, 2^15) is below 2^55 units,
 * and at most LSQT_CHUNK (2^8) paths' sums go to the low words before they go to the
 * batch's, so no carry can leave them; the general conversion of such lanes is the same
 * (to_fixedv). A block of zeros takes it too: testing for one cost as much as converting
 * it. */
#define LSQT_FLUSH_FAST_MAX R(32768.0)
#if LSQT_CHUNK > 256
#error "nee_flush_block's carry-free case assumes at most 256 paths per chunk"
#endif
LSQT_INLINE ulongv nee_flush_block(realv v, ulongv lo, __global ulong *nee, uint vs, int batch, int k,
                                     volatile __global uint *flags)
{
    if (allv((v >= R(0.0)) & (v < LSQT_FLUSH_FAST_MAX)))
        return lo + as_ulongv(convert_longv(v * (real)LSQT_FIX_SCALE + R(0.5)));
    fixv q = to_fixedv(v, flags);
    ulongv old = lo, sum = old + q.lo;
    if (anyv((q.hi != 0) | (sum < old))) {
        ulongv h = q.hi + select((ulongv)(0), (ulongv)(1), sum < old);
        ulong hs[LSQT_VW];
        vstorev(h, 0, hs);
        for (int i = 0; i < LSQT_VW; i++) {
            __global ulong *p = hs[i] ? nee_word(nee, vs, batch, k + i) : 0;
            if (p) global_add128(p, 0, hs[i], flags);
        }
    }
    return sum;
}

/* A vertex's next-event estimates, one set of functions per code path with the same
 * names, which the path loop below calls alike: the CPU path adds the terms (above) to the
 * path's sums at once, the GPU path writes the vertex's record (nee_records.cl) for
 * lsqt_estimate (below), which adds the same terms. nee_layer_terms: a layer's, towards
 * wo with weight w (tab: the layer's table); nee_medium_terms: a medium's, at optical
 * depths tu above and td below the vertex; nee_ms_sink: where a microsurface's walks add
 * theirs (ms_vertex_walks; filled through a pointer: a struct returned by value, once
 * inlined, leaves an llvm.experimental.noalias.scope.decl that oclgrind cannot run);
 * nee_counting: 1 in the GPU path's counting walk, which tallies nothing but the
 * records. */
#ifndef LSQT_NEE_RECORDS
LSQT_INLINE void nee_layer_terms(const walk_ctx *c, __global const lsqt_dev_layer *l, int li, real3 wo, real w,
                                 __global const real *tab)
{
    (void)li;
    for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW)
        VBLOCK(realv, c->sum, k) += nee_layer_block(l, wo, w, c->wi, tab, k);
}

LSQT_INLINE void nee_medium_terms(const walk_ctx *c, __global const lsqt_dev_medium *m, int mi, real3 wo, real w,
                                  const phase_vtx *pv, real tu, real td)
{
    /* The pointers in locals: on a CPU, PoCL's local, private and global memory are one
     * address space, so the compiler cannot tell the sums' stores from the context's
     * fields and would load them again at every block. */
    __global const real *dirs = c->wi, *a_up = c->tab, *a_down = c->tab + LSQT_NWI_PAD;
    __local real *sum = c->sum;
    (void)mi;
    for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW)
        VBLOCK(realv, sum, k) += nee_medium_block(m, pv, wo, w, tu, td, dirs, a_up, a_down, k);
}

LSQT_INLINE void nee_ms_sink(const walk_ctx *c, __global const real *tab, int li, ms_sink *k)
{
    k->sum = c->sum, k->wi = c->wi, k->tab = tab, k->count = c->work + WORK_NEE, k->out = 0, k->layer = li;
}

LSQT_INLINE int nee_counting(const walk_ctx *c)
{
    (void)c;
    return 0;
}

/* At the path's end: its sums to the work-item's low words (then cleared). */
LSQT_INLINE void nee_flush(const walk_ctx *c)
{
#if LSQT_NB > 1
    const uint on = *c->touched;
    *c->touched = 0;
    for (int b = 0; b < LSQT_NB; b++) {
        if (!(on >> b & 1u)) continue; /* its sums are 0 */
        __local real *sum = c->bsum + b * LSQT_NWI_PAD;
        __local ulong *lo = c->nee + b * LSQT_NWI_PAD;
        __global ulong *g = c->nee_g + (size_t)b * c->scene->band_nee_words;
        for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW) {
            realv v = VBLOCK(realv, sum, k);
            VBLOCK(realv, sum, k) = (realv)(R(0.0));
            VBLOCK(ulongv, lo, k) = nee_flush_block(v, VBLOCK(ulongv, lo, k), g, c->v, c->batch, k, c->flags);
        }
    }
#else
    for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW) {
        realv v = VBLOCK(realv, c->sum, k);
        VBLOCK(realv, c->sum, k) = (realv)(R(0.0));
        VBLOCK(ulongv, c->nee, k) = nee_flush_block(v, VBLOCK(ulongv, c->nee, k), c->nee_g, c->v, c->batch, k, c->flags);
    }
#endif
}
#else
/* A layer's or a medium's record: wo, and a medium's phase normal m and optical depths
 * tu, td (0 for a layer) where a microsurface vertex keeps m, lam_v and lg_v. */
LSQT_INLINE void nee_put(const walk_ctx *c, int kind, int index, real3 wo, real w, real3 m, real tu, real td)
{
    ms_vtx x;
    x.v = wo, x.m = m, x.inv_area = R(0.0), x.lam_v = tu, x.lg_v = td;
    x.log_c = x.log_cbar = x.e = R(0.0);
    nee_write(c->out, kind, index, w, R(0.0), &x);
}

LSQT_INLINE void nee_layer_terms(const walk_ctx *c, __global const lsqt_dev_layer *l, int li, real3 wo, real w,
                                 __global const real *tab)
{
    (void)l, (void)tab;
    nee_put(c, NEE_LAYER, li, wo, w, (real3)(R(0.0)), R(0.0), R(0.0));
}

LSQT_INLINE void nee_medium_terms(const walk_ctx *c, __global const lsqt_dev_medium *m, int mi, real3 wo, real w,
                                  const phase_vtx *pv, real tu, real td)
{
    (void)m;
    nee_put(c, NEE_MEDIUM, mi, wo, w, pv->m, tu, td);
}

LSQT_INLINE void nee_ms_sink(const walk_ctx *c, __global const real *tab, int li, ms_sink *k)
{
    k->sum = 0, k->wi = c->wi, k->tab = tab, k->count = c->work + WORK_NEE, k->out = c->out, k->layer = li;
}

LSQT_INLINE int nee_counting(const walk_ctx *c) { return c->count_only; }
#endif

/* Whether layer l is a microsurface, which its random walk samples and estimates. */
LSQT_INLINE int layer_is_micro(__global const lsqt_dev_layer *l)
{
#define X(ID, num, name, alias, p, sampler, mirror, transmits) \
    LSQT_IF_WALK_##sampler(if (LSQT_ON(BSDF_##ID) && l->kind == LSQT_BSDF_##ID) return 1;)
    LSQT_BSDFS(X)
#undef X
    (void)l;
    return 0;
}

/* A vertex on layer li reached along d with weight w: next-event estimates towards upward
 * directions if it is the topmost non-null layer, downward if the bottommost, then the
 * sample that continues the path. Returns the weight factor and sets *wi. */
LSQT_INLINE real layer_vertex(const walk_ctx *c, int li, real3 d, real w, rng_t *rng, real3 *wi)
{
    const int up = li == c->scene->top_nonnull, down = li == c->scene->bottom_nonnull;
    __global const lsqt_dev_layer *l = &c->layers[li];
    __global const lsqt_dev_medium *above = &c->media[li], *below = &c->media[li + 1];
    real tau_up = above->tau_above + above->mut * above->thickness;
    real tau_down = below->tau_below + below->mut * below->thickness;
    const int visible = c->nee_on && nee_visible(tau_up, tau_down, up, down);
    __global const real *tab = c->tab + LSQT_LAYER_TAB(li);
    c->work[WORK_LAYER]++;
    if (layer_is_micro(l)) { /* constant 0, and the walk dead code, in a scene without one */
        ms_sink k;
        nee_ms_sink(c, tab, li, &k);
        return ms_vertex_walks(l, d, rng, w, visible, &k, wi);
    }
    if (visible) {
        c->work[WORK_NEE]++;
        nee_layer_terms(c, l, li, -d, w, tab);
    }
    return bsdf_sample(l, -d, rng, wi);
}

/* Next-event estimates from a scattering vertex at height h in interior medium mi. */
LSQT_NOINLINE_CPU void nee_medium(const walk_ctx *c, int mi, real h, real3 d, real w, const phase_vtx *pv)
{
    __global const lsqt_dev_medium *m = &c->media[mi];
    const int top = c->scene->top_nonnull, bottom = c->scene->bottom_nonnull;
    const int up = top < 0 || mi <= top, down = bottom < 0 || mi > bottom;
    real tau_up = m->tau_above + m->mut * (m->thickness - h);
    real tau_down = m->tau_below + m->mut * h;
    if (!c->nee_on || !nee_visible(tau_up, tau_down, up, down)) return;
    c->work[WORK_NEE]++;
    /* A side light may not leave by, or too deep to count, is as good as infinitely deep
     * (2^-huge is 0; 1e30 times a 0 of the tables is still 0, never NaN). */
    const real tu = up && tau_up < LSQT_NEE_TAU_MAX ? tau_up : R(1e30);
    const real td = down && tau_down < LSQT_NEE_TAU_MAX ? tau_down : R(1e30);
    nee_medium_terms(c, m, mi, -d, w, pv, tu, td);
}

/* The phi bin of (x, |y|), phi = atan2(|y|, x) in [0, pi], without atan2 (a tenth of a
 * slab run): phi > j pi / 16 exactly where sin(phi - j pi / 16) > 0, i.e.
 * |y| cos(j pi / 16) - x sin(j pi / 16) > 0, so the bin counts the edges j = 1 ... 15
 * below phi (lane 0 is 0 > 0, never). x = y = 0 falls in bin 0, as atan2(0, 0) = 0. */
#if LSQT_HIST_NPHI != 16
#error "hist_phi_bin assumes 16 phi bins"
#endif
LSQT_INLINE int hist_phi_bin(real x, real ay)
{
    const float16 c = (float16)(
        0.000000000f, 0.980785280f, 0.923879533f, 0.831469612f,
        0.707106781f, 0.555570233f, 0.382683432f, 0.195090322f,
        0.000000000f, -0.195090322f, -0.382683432f, -0.555570233f,
        -0.707106781f, -0.831469612f, -0.923879533f, -0.980785280f);
    const float16 s = (float16)(
        0.000000000f, 0.195090322f, 0.382683432f, 0.555570233f,
        0.707106781f, 0.831469612f, 0.923879533f, 0.980785280f,
        1.000000000f, 0.980785280f, 0.923879533f, 0.831469612f,
        0.707106781f, 0.555570233f, 0.382683432f, 0.195090322f);
    int16 m = (float16)((float)ay) * c - (float16)((float)x) * s > 0.0f;
    int8 m8 = m.lo + m.hi;
    int4 m4 = m8.lo + m8.hi;
    int2 m2 = m4.lo + m4.hi;
    return -(m2.x + m2.y);
}

/* Equal-solid-angle bin of an exit direction: |cos theta| x phi folded to [0, pi]. The
 * hemisphere is the side the path left by (d.z may round to 0); the clamps keep even a
 * NaN direction inside the table. */
LSQT_INLINE int hist_bin(real3 d, int up)
{
    real mu = fabs(d.z);
    int bm = clamp((int)(mu * LSQT_HIST_NMU), 0, LSQT_HIST_NMU - 1);
    int bp = hist_phi_bin(d.x, fabs(d.y));
    return ((up ? 0 : 1) * LSQT_HIST_NMU + bm) * LSQT_HIST_NPHI + bp;
}

/* Russian roulette; returns 0 when the path ends. */
LSQT_INLINE int roulette(real *w, rng_t *rng)
{
    if (*w >= LSQT_RR_WEIGHT) return 1;
    if (rng_uniform(rng) * LSQT_RR_WEIGHT >= *w) return 0;
    *w = LSQT_RR_WEIGHT;
    return 1;
}

#if LSQT_NB > 1
/* A band block's steps (bands.cl, which follows this file). */
LSQT_INLINE int roulette_bands(real *wb, rng_t *rng);
LSQT_INLINE int layer_vertex_bands(const walk_ctx *c, int li, real3 d, real *wb, real *rb, rng_t *rng, real3 *wi);
LSQT_INLINE int flight_bands(const walk_ctx *c, int mi, real t, int collided, real *wb, real *rb);
LSQT_NOINLINE_CPU void nee_medium_bands(const walk_ctx *c, int mi, real h, real3 d, const real *wb,
                                        const phase_vtx *pv);
#endif

/* A path's exit: R or T, the unscattered part of T, and the exit histogram, each of
 * band b (0 in a one-band program) with weight w. */
LSQT_INLINE void tally_exit(const walk_ctx *c, int b, real3 d, int up, int scattered, real w, __global ulong *hist)
{
    if (LSQT_NB > 1 && w == R(0.0)) return; /* a block's band that stopped earlier */
    acc_add_band(c, b, up ? LSQT_T_R : LSQT_T_T, w);
    if (nee_counting(c)) return;
    if (scattered) {
        /* one histogram a simulated slice: a grouped session's blocks are the same paths */
        fix1 q = to_fixed(w, c->flags);
        const int bin = hist_bin(d, up);
        /* A block's bands are the innermost index: one exit's adds share cache lines (one
         * band's histograms after another's were a sixth of a 32-band run, in misses). */
        if (LSQT_NB == 1 || q.lo || q.hi) /* a block's bands without weight add nothing */
            global_add128(hist + 2 * ((size_t)bin * LSQT_NB + b), q.lo, q.hi, c->flags);
    } else {
        acc_add_band(c, b, LSQT_T_DELTA_T, w);
    }
}

LSQT_INLINE void run_path(const walk_ctx *c, real3 wo, rng_t *rng, __global ulong *hist)
{
    const int n = c->scene->n_layers;
    real3 d = -wo;
    real w = R(1.0), h = R(0.0);
#if LSQT_NB > 1
    /* each band's weight, and its density of the path over the bands' mixture (bands.cl) */
    real wb[LSQT_NBP], rb[LSQT_NBP];
    for (int b = 0; b < LSQT_NBP; b++) wb[b] = rb[b] = b < LSQT_NB ? R(1.0) : R(0.0);
    (void)w;
#endif
    int scattered = 0, at_layer = 1, layer = 0, medium = 0;
    for (int events = 0;; events++) {
        if (events >= LSQT_MAX_EVENTS) {
            for (int b = 0; b < LSQT_NB; b++) local_add128(c->acc + LSQT_ACC_WORDS * (b * LSQT_T_COUNT + LSQT_T_CUT), 1, 0, c->flags);
            return;
        }
        if (at_layer) {
            __global const lsqt_dev_layer *l = &c->layers[layer];
            const int bounced = l->kind != LSQT_BSDF_NULL;
            if (bounced) {
                real3 wi;
#if LSQT_NB > 1
                scattered = 1;
                if (!layer_vertex_bands(c, layer, d, wb, rb, rng, &wi)) return;
#else
                w *= layer_vertex(c, layer, d, w, rng, &wi);
                scattered = 1;
                if (!(w > R(0.0))) return;
#endif
                d = wi;
            }
            at_layer = 0;
            if (d.z < R(0.0)) {
                medium = layer + 1;
                h = c->media[medium].thickness;
            } else {
                medium = layer;
                h = R(0.0);
            }
            /* Medium 0 is entered only going up and medium n only going down ("down" is
             * d.z < 0 everywhere, so even a direction that rounds to horizontal, or a NaN,
             * moves consistently and leaves). */
            if (medium == 0 || medium == n) {
                int up = medium == 0;
                if (c->exit_dir) { /* a candidate walk: its scattered exit, (0, 0, 0) if none */
                    vstore4(scattered ? (real4)(d.x, d.y, d.z, R(1.0)) : (real4)(R(0.0)), 0, c->exit_dir);
                    return;
                }
#if LSQT_NB > 1
                for (int b = 0; b < LSQT_NB; b++) tally_exit(c, b, d, up, scattered, wb[b], hist);
#else
                tally_exit(c, 0, d, up, scattered, w, hist);
#endif
                return;
            }
            /* Roulette only for paths that go on inside the stack: on one that leaves it
             * would add noise and save no work. */
#if LSQT_NB > 1
            if (bounced && !roulette_bands(wb, rng)) return;
#else
            if (bounced && !roulette(&w, rng)) return;
#endif
            continue;
        }
        /* Inside interior medium `medium` at height h, travelling along d. */
        __global const lsqt_dev_medium *m = &c->media[medium];
#if LSQT_NB > 1
        /* The hero band's flight, every band's weight by spectral MIS (bands.cl); a
         * medium clear in every band is crossed as it is without bands. */
        if (c->bw[medium] > R(0.0)) {
            const real mt_h = c->bw[LSQT_BAND_MUT(n, LSQT_NBP, c->hero, medium)];
            const real s = mt_h > R(0.0) ? neg_log_unit(R(1.0) - rng_uniform(rng)) / mt_h : (real)INFINITY;
            if (d.z < R(0.0) ? s * -d.z < h : s * d.z < m->thickness - h) {
                h = clamp(h + s * d.z, R(0.0), (real)m->thickness);
                if (!flight_bands(c, medium, s, 1, wb, rb)) return;
                scattered = 1;
                c->work[WORK_MEDIUM]++;
                phase_vtx pv = phase_vertex(m, -d, rng);
                nee_medium_bands(c, medium, h, d, wb, &pv);
                real3 wi;
                const real f = phase_sample(m, &pv, -d, rng, &wi);
                if (!(f > R(0.0))) return;
                for (int b = 0; b < LSQT_NB; b++) wb[b] *= f;
                if (!roulette_bands(wb, rng)) return;
                d = wi;
                continue;
            }
            /* to the boundary ahead (a horizontal d never reaches one: it is clear in the
             * hero's band, and crosses nothing) */
            const real t = d.z < R(0.0) ? h / -d.z : d.z > R(0.0) ? (m->thickness - h) / d.z : R(0.0);
            if (!flight_bands(c, medium, t, 0, wb, rb)) return;
        }
#else
        if (m->mut > R(0.0)) {
            real s = neg_log_unit(R(1.0) - rng_uniform(rng)) / (real)m->mut;
            /* s < the distance to the boundary ahead, without dividing by d.z (a
             * horizontal d scatters below the top; a NaN one goes on to a layer and
             * leaves) */
            if (d.z < R(0.0) ? s * -d.z < h : s * d.z < m->thickness - h) {
                h = clamp(h + s * d.z, R(0.0), (real)m->thickness);
                w *= (real)m->mus / (real)m->mut;
                scattered = 1;
                if (!(w > R(0.0))) return; /* absorbed (mus = 0): no scattering event */
                c->work[WORK_MEDIUM]++;
                phase_vtx pv = phase_vertex(m, -d, rng);
                nee_medium(c, medium, h, d, w, &pv);
                real3 wi;
                w *= phase_sample(m, &pv, -d, rng, &wi);
                if (!(w > R(0.0)) || !roulette(&w, rng)) return;
                d = wi;
                continue;
            }
        }
#endif
        at_layer = 1;
        layer = d.z < R(0.0) ? medium : medium - 1;
    }
}

/* The RRSS candidates: analog walks (purpose RNG_PURPOSE_CANDIDATES, no point estimates)
 * of paths [path_begin, path_begin + n) of every simulated slice; out[slice][path] is the
 * direction of its scattered exit, w = 1, or all 0 (absorbed, unscattered, cut). Global
 * size (n rounded up, simulated slices); simulated slice s is the state's slices
 * s * slice_group ... (their outgoing direction is the same). */
__kernel void lsqt_exits(__constant lsqt_dev_scene *scene, __global const lsqt_dev_medium *media,
                         __global const lsqt_dev_layer *layers, __global const real *wo_dirs,
                         __global const real *wi_dirs, __global const real *tab, ulong path_begin, uint n,
                         __global real *out, volatile __global uint *flags, __global const real *bandw)
{
    __local acc_word acc[LSQT_ACC_WORDS * LSQT_T_COUNT * LSQT_NB]; /* the safety cap's count, unused */
    const uint i = (uint)get_global_id(0), slice = (uint)get_global_id(1);
    const uint v = slice * (uint)max(scene->slice_group, 1);
    /* no point estimates, so no sums (they would fill a CPU worker's stack: a work-group
     * of 256 at the pilot's 4 x 300 directions is 3.7 MB) */
    work_t work[WORK_N] = {0, 0, 0};
    walk_ctx c;
    c.scene = scene, c.media = media, c.layers = layers, c.wi = wi_dirs + 3 * LSQT_NWI_PAD * slice;
    c.tab = tab + (size_t)slice * LSQT_SLICE_TAB(scene->n_layers);
    c.sum = 0, c.bsum = 0, c.bw = bandw, c.nee = 0, c.work = work, c.acc = acc, c.nee_g = 0, c.v = 0, c.batch = 0;
    c.flags = flags, c.nee_on = 0, c.exit_dir = out + 4 * ((size_t)slice * n + i), c.out = 0, c.count_only = 0;
    uint touched = 0;
    c.hero = (int)((path_begin + i) % LSQT_NB), c.touched = &touched;
    if (i >= n) return;
    real3 wo = make_real3(wo_dirs[4 * v], wo_dirs[4 * v + 1], wo_dirs[4 * v + 2]);
    rng_t rng = rng_init(scene->seed_lo, scene->seed_hi, slice, path_begin + i, RNG_PURPOSE_CANDIDATES | scene->rng_side);
    vstore4((real4)(R(0.0)), 0, c.exit_dir);
    run_path(&c, wo, &rng, 0);
}

/* A work-group's share of a launch: one work-group per (chunk of LSQT_CHUNK paths,
 * simulated slice), global size (n_chunks * local size, n_slices / slice_group). Its
 * work-item lid of lsz, the simulated slice, the paths [begin, end) of chunk chunk_first
 * + the group's index that fall in [path_begin, path_end), and the chunk's batch. */
typedef struct {
    int lid, lsz;
    uint slice;
    ulong begin, end;
    int batch;
} chunk_span;

LSQT_INLINE chunk_span chunk_of(ulong chunk_first, ulong path_begin, ulong path_end)
{
    chunk_span s;
#ifdef LSQT_NEE_RECORDS
    const ulong chunk = chunk_first + get_group_id(0);
#else
    /* A CPU runs the groups in the order of their index, so the index goes batch by batch
     * (chunk_first + r, r + 32, r + 64, ... for r = 0, 1, ...): consecutive groups add to
     * one batch's histogram, which stays in cache (a chunk's exits spread over its batch's
     * 16 KB of bins, a new batch's every time: a tenth of a Lambertian run went to those
     * misses). Which group runs a chunk changes no tally. */
    const ulong g = get_group_id(0), n = get_num_groups(0), q = n / LSQT_BATCHES, big = (n % LSQT_BATCHES) * (q + 1);
    const ulong r = g < big ? g / (q + 1) : n % LSQT_BATCHES + (g - big) / q;
    const ulong chunk = chunk_first + r + LSQT_BATCHES * (g < big ? g % (q + 1) : (g - big) % q);
#endif
    s.lid = (int)get_local_id(0), s.lsz = (int)get_local_size(0);
    s.slice = (uint)get_global_id(1);
    s.begin = max(chunk * LSQT_CHUNK, path_begin);
    s.end = min((chunk + 1) * LSQT_CHUNK, path_end);
    s.batch = (int)(chunk % LSQT_BATCHES);
    return s;
}

#ifdef LSQT_NEE_RECORDS
/* The GPU path's walk: a path per work-item, LSQT_CHUNK work-items per chunk, in groups
 * that divide it (the host sees to it), so that a group's paths are of one chunk and one
 * batch; begin = the work-item's path and end = begin + 1, or end = begin where it falls
 * outside [path_begin, path_end). A loop over several paths kept the state of a path's
 * start and end live through the walk: some 10 VGPRs on gfx90a. */
LSQT_INLINE chunk_span path_span(ulong chunk_first, ulong path_begin, ulong path_end)
{
    chunk_span s;
    const ulong p = chunk_first * LSQT_CHUNK + get_global_id(0);
    s.lid = (int)get_local_id(0), s.lsz = (int)get_local_size(0);
    s.slice = (uint)get_global_id(1);
    s.begin = p;
    s.end = p >= path_begin && p < path_end ? p + 1 : p;
    s.batch = (int)(p / LSQT_CHUNK % LSQT_BATCHES);
    return s;
}
#endif

/* The paths: a work-group runs those of its chunk (chunk_span; on the GPU path a part of
 * a chunk, a path each, path_span) and adds its tallies once to the batch's. In a grouped
 * session (the RRSS pilot) one walk serves every block of the slice: block b's directions
 * are [b LSQT_GROUP_PAD, + LSQT_GROUP_NWI), and its tallies are state slice
 * slice * slice_group + b, whose R and T and work are the walk's; the histogram is one a
 * simulated slice (the host gives it to every block). The CPU path sums the next-event
 * estimates in local memory and ignores rec,
 * rec_off and count_only. The GPU path (LSQT_NEE_RECORDS) makes none: path p's records
 * go to rec from rec_off[slice * (path_end - path_begin) + p - path_begin] on, and
 * lsqt_estimate evaluates them; with count_only it only writes each path's record count
 * there (the host turns the counts into offsets) and tallies nothing. */
__kernel void lsqt_walk(__constant lsqt_dev_scene *scene,
                        __global const lsqt_dev_medium *media,
                        __global const lsqt_dev_layer *layers,
                        __global const real *wo_dirs,
                        __global const real *wi_dirs, __global const real *tab,
                        ulong path_begin, ulong path_end, ulong chunk_first,
                        __global ulong *nee, __global ulong *scalars, __global ulong *hist,
                        volatile __global uint *flags, __global lsqt_nee_rec *rec, __global ulong *rec_off,
                        int count_only, __global const real *bandw)
{
    __local acc_word acc[LSQT_ACC_WORDS * LSQT_T_COUNT * LSQT_NB];
#ifdef LSQT_NEE_RECORDS
    const chunk_span s = path_span(chunk_first, path_begin, path_end);
#else
    const chunk_span s = chunk_of(chunk_first, path_begin, path_end);
#endif

    for (int k = s.lid; k < LSQT_ACC_WORDS * LSQT_T_COUNT * LSQT_NB; k += s.lsz) acc[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);

    work_t work[WORK_N] = {0, 0, 0};
    const uint g = (uint)max(scene->slice_group, 1), v = s.slice * g; /* v: the first state slice */
    walk_ctx c;
    c.scene = scene, c.media = media, c.layers = layers, c.wi = wi_dirs + 3 * LSQT_NWI_PAD * s.slice;
    c.tab = tab + (size_t)s.slice * LSQT_SLICE_TAB(scene->n_layers);
    c.work = work, c.acc = acc, c.nee_g = nee, c.v = v, c.batch = s.batch, c.flags = flags;
    uint touched = 0;
    c.nee_on = 1, c.exit_dir = 0, c.hero = 0, c.touched = &touched;
    c.sum = 0, c.bsum = 0, c.nee = 0, c.bw = bandw;
    real3 wo = make_real3(wo_dirs[4 * v], wo_dirs[4 * v + 1], wo_dirs[4 * v + 2]);
    __global ulong *hist_b = hist + 2 * ((ulong)s.slice * LSQT_BATCHES + (ulong)s.batch) * LSQT_HIST_BINS * LSQT_NB;
    /* The paths, one body per code path. The CPU path's local memory can only be declared
     * in the kernel; the GPU path's path stays here too (in a function of its own,
     * clang-15 inlines the walk in another order, and lsqt_walk and lsqt_exits take a VGPR
     * more on gfx90a). */
#ifdef LSQT_NEE_RECORDS
    nee_out out;
    c.out = &out, c.count_only = count_only;
    if (s.begin < s.end) {
        const ulong p = s.begin, at = (ulong)s.slice * (path_end - path_begin) + (p - path_begin);
        out.rec = count_only ? 0 : rec + rec_off[at];
        out.n = 0;
        rng_t rng = rng_init(scene->seed_lo, scene->seed_hi, s.slice, p, RNG_PURPOSE_WALK | scene->rng_side);
        run_path(&c, wo, &rng, hist_b);
        if (count_only) rec_off[at] = out.n;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (count_only) return;
#else
    (void)rec, (void)rec_off, (void)count_only;
    const int lid = s.lid, lsz = s.lsz;
    __local acc_word acc_t[LSQT_ACC_WORDS * LSQT_ACC_TILE];
    /* The directions' sums of each of the group's LSQT_ITEMS work-items (declared as
     * vectors, for aligned blocks: VBLOCK): LSQT_NB rows of low words, LSQT_SUM_ROWS of
     * sums. */
    __local ulongv nee_v[LSQT_ITEMS * LSQT_NB * (LSQT_NWI_PAD / LSQT_VW)];
    __local realv sum_v[LSQT_ITEMS * LSQT_SUM_ROWS * (LSQT_NWI_PAD / LSQT_VW)];
    __local ulong *nee_priv = (__local ulong *)(nee_v + lid * LSQT_NB * (LSQT_NWI_PAD / LSQT_VW));
    __local real *path_sum = (__local real *)(sum_v + lid * LSQT_SUM_ROWS * (LSQT_NWI_PAD / LSQT_VW));
    for (int k = 0; k < LSQT_NB * LSQT_NWI_PAD; k++) nee_priv[k] = 0;
    for (int k = 0; k < LSQT_SUM_ROWS * LSQT_NWI_PAD; k++) path_sum[k] = R(0.0);
    c.sum = path_sum, c.nee = nee_priv, c.out = 0, c.count_only = 0;
    c.bsum = path_sum + LSQT_NWI_PAD; /* a band block's: after the vertex's row */
#ifdef LSQT_RNG_WIDE
    rng_t ahead; /* the next path's stream, made with this one's (rng_init_pair) */
    int have_ahead = 0;
#endif
    for (ulong p = s.begin + (ulong)lid; p < s.end; p += (ulong)lsz) {
        c.hero = (int)(p % LSQT_NB); /* every band leads as many paths */
        const uint purpose = RNG_PURPOSE_WALK | scene->rng_side;
        rng_t rng;
#ifdef LSQT_RNG_WIDE
        if (have_ahead)
            rng = ahead, have_ahead = 0;
        else if (p + (ulong)lsz < s.end)
            rng_init_pair(scene->seed_lo, scene->seed_hi, s.slice, p, p + (ulong)lsz, purpose, &rng, &ahead), have_ahead = 1;
        else
#endif
            rng = rng_init(scene->seed_lo, scene->seed_hi, s.slice, p, purpose);
        run_path(&c, wo, &rng, hist_b);
        nee_flush(&c);
    }
    /* The directions' sums, band by band (one in a one-band program), a tile at a time. */
    for (int band = 0; band < LSQT_NB; band++) {
        __local ulong *lo = nee_priv + band * LSQT_NWI_PAD;
        __global ulong *nee_b = nee + (size_t)band * scene->band_nee_words;
        for (int t0 = 0; t0 < LSQT_NWI; t0 += LSQT_ACC_TILE) {
            const int tn = min(LSQT_ACC_TILE, LSQT_NWI - t0);
            for (int k = lid; k < LSQT_ACC_WORDS * tn; k += lsz) acc_t[k] = 0;
            barrier(CLK_LOCAL_MEM_FENCE);
            for (int k = 0; k < tn; k++)
                if (lo[t0 + k]) local_add128(acc_t + LSQT_ACC_WORDS * k, lo[t0 + k], 0, flags);
            barrier(CLK_LOCAL_MEM_FENCE);
            for (int k = lid; k < tn; k += lsz) {
                fix1 a = acc_read(acc_t + LSQT_ACC_WORDS * k);
                __global ulong *p = nee_word(nee_b, v, s.batch, t0 + k);
                if (p) global_add128(p, a.lo, a.hi, flags);
            }
            barrier(CLK_LOCAL_MEM_FENCE);
        }
    }
#endif
    /* The work counters are every band's. */
    for (int band = 0; band < LSQT_NB; band++)
        for (int k = 0; k < WORK_N; k++)
            if (work[k]) local_add128(acc + LSQT_ACC_WORDS * (band * LSQT_T_COUNT + LSQT_T_LAYER_EVENTS + k), work[k], 0, flags);
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int k = s.lid; k < LSQT_T_COUNT * LSQT_NB; k += s.lsz) {
        fix1 a = acc_read(acc + LSQT_ACC_WORDS * k);
#if LSQT_NB > 1
        const int band = k / LSQT_T_COUNT, t = k % LSQT_T_COUNT;
#else
        const int band = 0, t = k;
#endif
        __global ulong *sc = scalars + (size_t)band * scene->band_scalar_words;
        for (uint b = 0; b < g; b++) {
            const ulong base = (ulong)(v + b) * LSQT_BATCHES + (ulong)s.batch;
            global_add128(sc + 2 * (base * LSQT_T_COUNT + t), a.lo, a.hi, flags);
        }
    }
}

#ifdef LSQT_NEE_RECORDS
/* A record's terms for the block of directions at b (dirs, st: the slice's directions
 * and tables). */
LSQT_INLINE realv nee_rec_block(__global const lsqt_nee_rec *r, __global const lsqt_dev_medium *media,
                                  __global const lsqt_dev_layer *layers, __global const real *dirs,
                                  __global const real *st, int b)
{
    const lsqt_nee_rec q = *r;
    const int kind = (int)LSQT_NEE_KIND(q), i = (int)LSQT_NEE_INDEX(q);
    const real w = LSQT_NEE_W(q);
    if (kind == NEE_LAYER) return nee_layer_block(&layers[i], LSQT_NEE_V(q), w, dirs, st + LSQT_LAYER_TAB(i), b);
    if (kind == NEE_MEDIUM) {
        phase_vtx pv = {LSQT_NEE_M(q)};
        return nee_medium_block(&media[i], &pv, LSQT_NEE_V(q), w, LSQT_NEE_TAU_UP(q), LSQT_NEE_TAU_DOWN(q), dirs, st,
                                st + LSQT_NWI_PAD, b);
    }
    ms_vtx x = nee_ms_vtx(&q);
    return ms_nee_block(&layers[i], kind, &x, LSQT_NEE_SIDE(q), w, dirs, st + LSQT_LAYER_TAB(i), b);
}

/* The GPU path's next-event estimates: one work-group per (chunk, simulated slice), as
 * lsqt_walk's, sharing the slice's directions: work-item i owns the blocks of LSQT_VW
 * directions at i LSQT_VW, (i + size) LSQT_VW, ... For each block it sums every path's
 * records in the path's order (the CPU path's order, so the same sums), converts each
 * path's sum to fixed point and adds it to the block's tallies: a sum and a 64-bit word
 * per lane in registers, whatever the direction count. Every work-item reads the same
 * record at once. */
__kernel void lsqt_estimate(__constant lsqt_dev_scene *scene, __global const lsqt_dev_medium *media,
                            __global const lsqt_dev_layer *layers, __global const real *wi_dirs,
                            __global const real *tab, ulong path_begin, ulong path_end, ulong chunk_first,
                            __global const lsqt_nee_rec *rec, __global const ulong *rec_off, __global ulong *nee,
                            volatile __global uint *flags)
{
    const chunk_span s = chunk_of(chunk_first, path_begin, path_end);
    const uint v = s.slice * (uint)max(scene->slice_group, 1);
    __global const real *dirs = wi_dirs + 3 * LSQT_NWI_PAD * s.slice;
    __global const real *st = tab + (size_t)s.slice * LSQT_SLICE_TAB(scene->n_layers);
    const ulong first = (ulong)s.slice * (path_end - path_begin) - path_begin;
    for (int b = s.lid * LSQT_VW; b < LSQT_NWI_PAD; b += s.lsz * LSQT_VW) {
        ulongv lo = (ulongv)(0);
        for (ulong p = s.begin; p < s.end; p++) {
            realv sum = (realv)(R(0.0));
            const ulong r1 = rec_off[first + p + 1];
            for (ulong r = rec_off[first + p]; r < r1; r++) sum += nee_rec_block(rec + r, media, layers, dirs, st, b);
            lo = nee_flush_block(sum, lo, nee, v, s.batch, b, flags);
        }
        ulong ls[LSQT_VW];
        vstorev(lo, 0, ls);
        for (int i = 0; i < LSQT_VW; i++) {
            __global ulong *p = ls[i] ? nee_word(nee, v, s.batch, b + i) : 0;
            if (p) global_add128(p, ls[i], 0, flags);
        }
    }
}
#endif
