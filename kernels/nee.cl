/* What a walk carries (walk_ctx) and where its next-event estimates go: the direction
 * tables' layout, the vectors of LSQT_VW directions' terms, and one set of sink functions
 * per code path (the CPU's sums per path, the GPU's records, nee_records.cl). Uses
 * common.cl, tally.cl, models.cl and microsurface.cl; bands.cl and walk.cl use it. */
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
/* The most work-items in a group: the CPU path's LSQT_ITEMS, the GPU path's
 * LSQT_GPU_ITEMS (device_layout.h; the host launches no wider groups). */
#define LSQT_GROUP_MAX (LSQT_RECORDS ? LSQT_GPU_ITEMS : LSQT_ITEMS)


/* A band block's work-item keeps per band its path's sums and its low words, and one
 * more row of sums for a vertex's terms before they are spread (bands.cl band_spread);
 * one band keeps its path's sums in that row. */
#define LSQT_SUM_ROWS (LSQT_NB > 1 ? LSQT_NB + 1 : 1)

/* A work-item's work counters, in the order of the LSQT_T_LAYER_EVENTS... tallies. */
#define WORK_LAYER (LSQT_T_LAYER_EVENTS - LSQT_T_LAYER_EVENTS)
#define WORK_MEDIUM (LSQT_T_MEDIUM_EVENTS - LSQT_T_LAYER_EVENTS)
#define WORK_NEE (LSQT_T_NEE_VERTICES - LSQT_T_LAYER_EVENTS)
#define WORK_N (LSQT_T_COUNT - LSQT_T_LAYER_EVENTS)

/* What a walk reads: the stack's tables, a band block's, and the slice's (the same for
 * every path of a launch). */
typedef struct {
    __constant lsqt_dev_scene *scene;
    __global const lsqt_dev_medium *media;
    __global const lsqt_dev_layer *layers;
    __global const real *bw;           /* a band block's table (LSQT_BAND_AT), else unused */
    __global const real *wi;           /* this slice's directions: x[pad], y[pad], z[pad] */
    __global const real *tab;          /* this slice's direction tables (lsqt_prepare) */
} walk_in;

/* Where a walk's tallies go: the code path's sink of next-event terms and the counters. */
typedef struct {
    __local real *sum;                 /* the current vertex's point estimates (CPU path; one
                                          band's: its path's, bsum) */
    __local real *bsum;                /* each band's path sums, LSQT_NWI_PAD apart */
    __local ulong *nee;                /* this work-item's point-estimate sums, low words (CPU path;
                                          a band block's: each band's, LSQT_NWI_PAD apart) */
    __global ulong *nee_g;             /* the tallies of the chunk's batch (nee_word) */
    uint v;                            /* the first state slice of this walk */
    int batch;
    work_t *work;                      /* the work counters (LSQT_T_LAYER_EVENTS ...; work_t) */
    volatile __local acc_word *acc;    /* the work-group's scalar tallies, LSQT_ACC_WORDS each */
    volatile __global uint *flags;
    nee_out *out;                      /* the path's next-event records (GPU path) */
    int count_only;                    /* 1: count the records, tally nothing (GPU path) */
} walk_sink;

/* The walk's context: what it reads, where it adds, what kind of walk it is, and its
 * path's band state. */
typedef struct {
    walk_in in;
    walk_sink sink;
    struct {
        int nee_on;                    /* 0: no point estimates (the RRSS candidate walks) */
        __global real *exit_dir;       /* non-0: the path only writes its exit direction here */
    } mode;
    struct {
        uint *touched;                 /* the bands the path has added to (bits) */
        BAND_MEM real *rows;           /* the path's rows of per-band state and its hero (bands.cl) */
    } band;
} walk_ctx;

/* Direction k's tally of the walk's batch (state slice v + k / LSQT_GROUP_PAD), or 0 for
 * the padding between a grouped session's candidate sets. */
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
        fix1 q = to_fixed(v, c->sink.flags);
        local_add128(c->sink.acc + LSQT_ACC_WORDS * (b * LSQT_T_COUNT + k), q.lo, q.hi, c->sink.flags);
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


/* The next-event terms of one vertex for the vector of LSQT_VW directions at b, the same
 * text for both code paths (the CPU's sums per path, the GPU's records). Lanes with
 * t = 0 add nothing, even where the model is not finite (the zero vectors that pad the
 * directions). A layer's closed-form BSDF (tab: its table, T first; microsurfaces take
 * ms_vertex_walks): */
LSQT_INLINE realv nee_layer_vec(__global const lsqt_dev_layer *l, real3 wo, real w, __global const real *dirs,
                                    __global const real *tab, int b)
{
    const realv t = vloadv(0, tab + b);
    return select((realv)(R(0.0)), (w * bsdf_evalv_closed(l, wo, load_dirv(dirs, b))) * t, t > R(0.0));
}

/* A medium's phase function at optical depths tu above and td below the vertex (a_up,
 * a_down: the slice's media rows). */
LSQT_INLINE realv nee_medium_vec(__global const lsqt_dev_medium *m, const phase_vtx *pv, real3 wo, real w, real tu,
                                     real td, __global const real *dirs, __global const real *a_up,
                                     __global const real *a_down, int b)
{
    const realv t = exp2_negv(-(tu * vloadv(0, a_up + b) + td * vloadv(0, a_down + b)));
    return select((realv)(R(0.0)), (w * phase_evalv(m, pv, wo, load_dirv(dirs, b))) * t, t > R(0.0));
}

/* Converts one path's sums of the vector at k to fixed point, adds them to lo, the low
 * 64-bit words of the block's tallies, and returns the new low words. A high word (a sum
 * above 2^63 units, 8e6, or a carry out of the low word) is rare and goes straight to the
 * batch's 128-bit sum in global memory (nee_word of nee, state slice vs, batch), where it counts the same.
 * The common case by one test per vector: every lane in [0, 2^15) is below 2^55 units,
 * and at most LSQT_CHUNK (2^8) paths' sums go to the low words before they go to the
 * batch's, so no carry can leave them; the general conversion of such lanes is the same
 * (to_fixedv). A vector of zeros takes it too: testing for one cost as much as converting
 * it. */
#define LSQT_FLUSH_FAST_MAX R(32768.0)
#if LSQT_CHUNK > 256
#error "nee_flush_vec's carry-free case assumes at most 256 paths per chunk"
#endif
LSQT_INLINE ulongv nee_flush_vec(realv v, ulongv lo, __global ulong *nee, uint vs, int batch, int k,
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
        VEC_AT(realv, c->sink.sum, k) += nee_layer_vec(l, wo, w, c->in.wi, tab, k);
}

LSQT_INLINE void nee_medium_terms(const walk_ctx *c, __global const lsqt_dev_medium *m, int mi, real3 wo, real w,
                                  const phase_vtx *pv, real tu, real td)
{
    /* The pointers in locals: on a CPU, PoCL's local, private and global memory are one
     * address space, so the compiler cannot tell the sums' stores from the context's
     * fields and would load them again at every vector. */
    __global const real *dirs = c->in.wi, *a_up = c->in.tab, *a_down = c->in.tab + LSQT_NWI_PAD;
    __local real *sum = c->sink.sum;
    (void)mi;
    for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW)
        VEC_AT(realv, sum, k) += nee_medium_vec(m, pv, wo, w, tu, td, dirs, a_up, a_down, k);
}

LSQT_INLINE void nee_ms_sink(const walk_ctx *c, __global const real *tab, int li, ms_sink *k)
{
    k->sum = c->sink.sum, k->wi = c->in.wi, k->tab = tab, k->count = c->sink.work + WORK_NEE, k->out = 0, k->layer = li;
}

LSQT_INLINE int nee_counting(const walk_ctx *c)
{
    (void)c;
    return 0;
}

/* At the path's end: its sums to the work-item's low words (then cleared), band by band
 * (a block's bands without a term on the path have sums of 0, and are skipped). */
LSQT_INLINE void nee_flush(const walk_ctx *c)
{
    const uint on = LSQT_NB > 1 ? *c->band.touched : 1u;
    if (LSQT_NB > 1) *c->band.touched = 0;
    BAND_LOOP
    for (int b = 0; b < LSQT_NB; b++) {
        if (!(on >> b & 1u)) continue;
        __local real *sum = c->sink.bsum + b * LSQT_NWI_PAD;
        __local ulong *lo = c->sink.nee + b * LSQT_NWI_PAD;
        __global ulong *g = c->sink.nee_g + (size_t)b * c->in.scene->band_nee_words;
        for (int k = 0; k < LSQT_NWI_PAD; k += LSQT_VW) {
            realv v = VEC_AT(realv, sum, k);
            VEC_AT(realv, sum, k) = (realv)(R(0.0));
            VEC_AT(ulongv, lo, k) = nee_flush_vec(v, VEC_AT(ulongv, lo, k), g, c->sink.v, c->sink.batch, k, c->sink.flags);
        }
    }
}
#else
/* A layer's or a medium's record: wo, and a medium's phase normal m and optical depths
 * tu, td (0 for a layer) where a microsurface vertex keeps m, lam_v and lg_v. */
LSQT_INLINE void nee_put(const walk_ctx *c, int kind, int index, real3 wo, real w, real3 m, real tu, real td)
{
    ms_vtx x;
    x.v = wo, x.m = m, x.inv_area = R(0.0), x.lam_v = tu, x.lg_v = td;
    x.log_c = x.log_cbar = x.e = R(0.0);
    nee_write(c->sink.out, kind, index, w, R(0.0), &x);
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
    k->sum = 0, k->wi = c->in.wi, k->tab = tab, k->count = c->sink.work + WORK_NEE, k->out = c->sink.out, k->layer = li;
}

LSQT_INLINE int nee_counting(const walk_ctx *c) { return c->sink.count_only; }
#endif
