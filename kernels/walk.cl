/* The path loop: the only place that knows about layers and media together.
 *
 * Indexing: media 0..n, layers 0..n-1, layer L lies between media L (above) and L+1
 * (below). Media 0 and n are the clear outside; a path that enters medium 0 going up has
 * left the stack (reflection), one that enters medium n going down has too (transmission).
 * Inside an interior medium the position is the height h above its bottom boundary, so a
 * thin medium far from z = 0 is as exact as one near it. */

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
        real lam = ms_layer(l) ? ggx_lambda(ms_alpha(l), z) : R(0.0);
        __global real *t = st + LSQT_LAYER_TAB(li);
        t[k] = nee_transmittancev((realv)(z), (realv)(inv_az), tau_up, tau_down, up, down).s0;
        t[LSQT_NWI_PAD + k] = lam;
        t[2 * LSQT_NWI_PAD + k] = lgamma_ge1(R(1.0) + lam);
    }
}

/* A vertex on layer li reached along d with each band's weight wb: next-event estimates
 * towards upward directions if it is the topmost non-null layer, downward if the
 * bottommost, then the sample that continues the path (rb: bands.cl). One band's terms
 * carry its weight; a block's are evaluated at weight 1 and spread to each band with its
 * factors (band_spread). Returns the factor of every band's weight (1 where the sample
 * weighed each band itself, 0 where the path ends) and sets *wi. */
LSQT_INLINE real layer_vertex(const walk_ctx *c, int li, real3 d, BAND_MEM real *wb, BAND_MEM real *rb, rng_t *rng,
                              real3 *wi)
{
    const int n = c->in.scene->n_layers;
    const int up = li == c->in.scene->top_nonnull, down = li == c->in.scene->bottom_nonnull;
    __global const lsqt_dev_layer *l = &c->in.layers[li];
    if (LSQT_NB > 1 && !up && layer_bands_index(l)) {
        /* under another layer: no term leaves it, and each band's index weighs its walk
         * (light reaches it from above only) */
        c->sink.work[WORK_LAYER]++;
        if (!(d.z < R(0.0))) return R(0.0);
        ms_bands mb = {c->in.bw + LSQT_BAND_ETA(n, LSQT_NBP, 0, li), c->in.bw + LSQT_BAND_KAPPA(n, LSQT_NBP, 0, li), wb};
        ms_sink none = {0, 0, 0};
        return ms_vertex_walks(l, d, rng, R(0.0), 0, &none, &mb, wi);
    }
    real tau_up, tau_down;
    layer_depths(c, li, &tau_up, &tau_down);
    const int visible = c->mode.nee_on && nee_visible(tau_up, tau_down, up, down);
    __global const real *tab = c->in.tab + LSQT_LAYER_TAB(li);
    const band_vertex bx = {li, -1, R(0.0), -1};
    const real vw = LSQT_NB > 1 ? R(1.0) : wb[0];
    c->sink.work[WORK_LAYER]++;
    if (ms_layer(l)) { /* constant 0, and the walk dead code, in a scene without one */
        ms_sink k;
        nee_ms_sink(c, tab, li, &k);
        const real f = ms_vertex_walks(l, d, rng, vw, visible, &k, 0, wi);
        if (visible) band_spread(c, -d.z, &bx, wb);
        return f;
    }
    if (visible) {
        c->sink.work[WORK_NEE]++;
        nee_layer_terms(c, l, li, -d, vw, tab);
        band_spread(c, -d.z, &bx, wb);
    }
    if (LSQT_NB == 1 || !layer_bands_factored(l)) return bsdf_sample(l, -d, rng, wi);
    return band_side_sample(c, l, li, d, wb, rb, rng, wi) ? R(1.0) : R(0.0);
}

/* Next-event estimates from a scattering vertex at height h in interior medium mi: one
 * band's with its weight w, a block's (wb) at weight 1, spread to each band with its
 * extra transmittance where its medium is deeper. */
LSQT_NOINLINE_CPU void nee_medium(const walk_ctx *c, int mi, real h, real3 d, real w, const BAND_MEM real *wb,
                                  const phase_vtx *pv)
{
    __global const lsqt_dev_medium *m = &c->in.media[mi];
    const int top = c->in.scene->top_nonnull, bottom = c->in.scene->bottom_nonnull;
    const int up = top < 0 || mi <= top, down = bottom < 0 || mi > bottom;
    real tau_up, tau_down;
    medium_depths(m, h, &tau_up, &tau_down);
    if (!c->mode.nee_on || !nee_visible(tau_up, tau_down, up, down)) return;
    c->sink.work[WORK_NEE]++;
    /* A side light may not leave by, or too deep to count, is as good as infinitely deep
     * (2^-huge is 0; 1e30 times a 0 of the tables is still 0, never NaN). */
    if (band_phases_differ(c, mi)) {
        /* each band's own phase function at its own depths, to that band alone */
        BAND_LOOP
        for (int b = 0; b < LSQT_NB; b++) {
            if (!(wb[b] > R(0.0))) continue;
            __global const lsqt_dev_medium *bm = band_medium(c, b, mi);
            medium_depths(bm, h, &tau_up, &tau_down);
            if (!nee_visible(tau_up, tau_down, up, down)) continue;
            nee_medium_terms(c, bm, (int)(bm - c->in.media), -d, R(1.0), pv,
                             up && tau_up < LSQT_NEE_TAU_MAX ? tau_up : R(1e30),
                             down && tau_down < LSQT_NEE_TAU_MAX ? tau_down : R(1e30));
            const band_vertex bx = {-1, mi, h, b};
            band_spread(c, -d.z, &bx, wb);
        }
        return;
    }
    const real tu = up && tau_up < LSQT_NEE_TAU_MAX ? tau_up : R(1e30);
    const real td = down && tau_down < LSQT_NEE_TAU_MAX ? tau_down : R(1e30);
    nee_medium_terms(c, m, mi, -d, LSQT_NB > 1 ? R(1.0) : w, pv, tu, td);
    const band_vertex bx = {-1, mi, h, -1};
    band_spread(c, -d.z, &bx, wb);
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

/* A path's exit along d: each band's R or T, the unscattered part of T, and the exit
 * histogram, with the band's weight wb (one bin for all of them). */
LSQT_INLINE void tally_exit(const walk_ctx *c, real3 d, int up, int scattered, const BAND_MEM real *wb,
                            __global ulong *hist)
{
    /* one histogram a simulated slice: a grouped session's blocks are the same paths */
    const int bin = scattered ? hist_bin(d, up) : 0;
    BAND_LOOP
    for (int b = 0; b < LSQT_NB; b++) {
        const real w = wb[b];
        if (LSQT_NB > 1 && w == R(0.0)) continue; /* a block's band that stopped earlier */
        acc_add_band(c, b, up ? LSQT_T_R : LSQT_T_T, w);
        if (nee_counting(c)) continue;
        if (scattered) {
            fix1 q = to_fixed(w, c->sink.flags);
            /* A block's bands are the innermost index: one exit's adds share cache lines
             * (one band's histograms after another's were a sixth of a 32-band run, in
             * misses). A block's bands without weight add nothing. */
            if (LSQT_NB == 1 || q.lo || q.hi)
                global_add128(hist + 2 * ((size_t)bin * LSQT_NB + b), q.lo, q.hi, c->sink.flags);
        } else {
            acc_add_band(c, b, LSQT_T_DELTA_T, w);
        }
    }
}

/* One path from wo, for every band of its block: each band's weight (wb) and its density
 * of the path over the bands' mixture (rb; bands.cl). One band's code is the same text at
 * width 1, where the mixture is the band itself. */
LSQT_INLINE void run_path(const walk_ctx *c, real3 wo, rng_t *rng, __global ulong *hist)
{
    const int n = c->in.scene->n_layers;
    real3 d = -wo;
    real h = R(0.0);
    BAND_MEM real *wb = band_row(c, BAND_WB), *rb = band_row(c, BAND_RB);
    for (int b = 0; b < LSQT_NBW; b++) wb[b] = rb[b] = b < LSQT_NB ? R(1.0) : R(0.0);
    int scattered = 0, at_layer = 1, layer = 0, medium = 0;
    for (int events = 0;; events++) {
        if (events >= LSQT_MAX_EVENTS) {
            BAND_LOOP
            for (int b = 0; b < LSQT_NB; b++) local_add128(c->sink.acc + LSQT_ACC_WORDS * (b * LSQT_T_COUNT + LSQT_T_CUT), 1, 0, c->sink.flags);
            return;
        }
        if (at_layer) {
            __global const lsqt_dev_layer *l = &c->in.layers[layer];
            const int bounced = l->kind != LSQT_BSDF_NULL;
            if (bounced) {
                real3 wi;
                scattered = 1;
                if (!band_scale(wb, layer_vertex(c, layer, d, wb, rb, rng, &wi))) return;
                d = wi;
            }
            at_layer = 0;
            if (d.z < R(0.0)) {
                medium = layer + 1;
                h = c->in.media[medium].thickness;
            } else {
                medium = layer;
                h = R(0.0);
            }
            /* Medium 0 is entered only going up and medium n only going down ("down" is
             * d.z < 0 everywhere, so even a direction that rounds to horizontal, or a NaN,
             * moves consistently and leaves). */
            if (medium == 0 || medium == n) {
                int up = medium == 0;
                if (c->mode.exit_dir) { /* a candidate walk: its scattered exit, (0, 0, 0) if none */
                    vstore4(scattered ? (real4)(d.x, d.y, d.z, R(1.0)) : (real4)(R(0.0)), 0, c->mode.exit_dir);
                    return;
                }
                tally_exit(c, d, up, scattered, wb, hist);
                return;
            }
            /* Roulette only for paths that go on inside the stack: on one that leaves it
             * would add noise and save no work. */
            if (bounced && !roulette(wb, rng)) return;
            continue;
        }
        /* Inside interior medium `medium` at height h, travelling along d: the hero band's
         * free flight (bands.cl), unless the medium is clear in every band. */
        __global const lsqt_dev_medium *m = &c->in.media[medium];
        if (band_most_mut(c, medium) > R(0.0)) {
            const real mt_h = band_hero_mut(c, medium);
            const real s = mt_h > R(0.0) ? neg_log_unit(R(1.0) - rng_uniform(rng)) / mt_h : (real)INFINITY;
            /* s < the distance to the boundary ahead, without dividing by d.z (a
             * horizontal d scatters below the top; a NaN one goes on to a layer and
             * leaves) */
            if (d.z < R(0.0) ? s * -d.z < h : s * d.z < m->thickness - h) {
                h = clamp(h + s * d.z, R(0.0), (real)m->thickness);
                /* every band's albedo, and its density of the flight (absorbed in every
                 * band, mus = 0: no scattering event) */
                if (!flight_weights(c, medium, s, 1, wb, rb)) return;
                scattered = 1;
                c->sink.work[WORK_MEDIUM]++;
                phase_vtx pv = phase_vertex(m, -d, rng);
                nee_medium(c, medium, h, d, wb[0], LSQT_NB > 1 ? wb : 0, &pv);
                real3 wi;
                if (band_phases_differ(c, medium)) {
                    if (!band_phase_sample(c, medium, &pv, -d, wb, rb, rng, &wi) || !roulette(wb, rng)) return;
                } else {
                    const real f = phase_sample(m, &pv, -d, rng, &wi);
                    if (!(f > R(0.0)) || !band_scale(wb, f) || !roulette(wb, rng)) return;
                }
                d = wi;
                continue;
            }
            /* to the boundary ahead (a horizontal d never reaches one: it is clear in the
             * hero's band, and crosses nothing) */
            const real t = d.z < R(0.0) ? h / -d.z : d.z > R(0.0) ? (m->thickness - h) / d.z : R(0.0);
            if (!flight_weights(c, medium, t, 0, wb, rb)) return;
        }
        at_layer = 1;
        layer = d.z < R(0.0) ? medium : medium - 1;
    }
}

/* The RRSS candidates: analog walks (purpose RNG_PURPOSE_CANDIDATES, no point estimates)
 * of paths [path_begin, path_begin + n) of every simulated slice; out[slice][path] is the
 * direction of its scattered exit, w = 1, or all 0 (absorbed, unscattered, cut). Global
 * size (n rounded up, simulated slices); simulated slice s is the state's slices
 * s * slice_group ... (their outgoing direction is the same). */
LSQT_GPU_KERNEL void lsqt_exits(__constant lsqt_dev_scene *scene, __global const lsqt_dev_medium *media,
                         __global const lsqt_dev_layer *layers, __global const real *wo_dirs,
                         __global const real *wi_dirs, __global const real *tab, ulong path_begin, uint n,
                         __global real *out, volatile __global uint *flags, __global const real *bandw)
{
    __local acc_word acc[LSQT_ACC_WORDS * LSQT_T_COUNT * LSQT_NB]; /* the safety cap's count, unused */
    BAND_ARRAY(real, rows, BAND_STATE);
    const uint i = (uint)get_global_id(0), slice = (uint)get_global_id(1);
    const uint v = slice * (uint)max(scene->slice_group, 1);
    /* no point estimates, so no sums (they would fill a CPU worker's stack: a work-group
     * of 256 at the pilot's 4 x 300 directions is 3.7 MB) */
    work_t work[WORK_N] = {0, 0, 0};
    walk_ctx c;
    c.in.scene = scene, c.in.media = media, c.in.layers = layers, c.in.wi = wi_dirs + 3 * LSQT_NWI_PAD * slice;
    c.in.tab = tab + (size_t)slice * LSQT_SLICE_TAB(scene->n_layers);
    c.sink.sum = 0, c.sink.bsum = 0, c.in.bw = bandw, c.sink.nee = 0, c.sink.work = work, c.sink.acc = acc, c.sink.nee_g = 0, c.sink.v = 0, c.sink.batch = 0;
    c.sink.flags = flags, c.mode.nee_on = 0, c.mode.exit_dir = out + 4 * ((size_t)slice * n + i), c.sink.out = 0, c.sink.count_only = 0;
    uint touched = 0;
    c.band.touched = &touched, c.band.rows = rows;
    band_set_hero(&c, path_begin + i);
    if (i >= n) return;
    real3 wo = make_real3(wo_dirs[4 * v], wo_dirs[4 * v + 1], wo_dirs[4 * v + 2]);
    rng_t rng = rng_init(scene->seed_lo, scene->seed_hi, slice, path_begin + i, RNG_PURPOSE_CANDIDATES | scene->rng_side);
    vstore4((real4)(R(0.0)), 0, c.mode.exit_dir);
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
    /* A CPU runs the groups in the order of their index, so the index goes batch by batch
     * (chunk_first + r, r + 32, r + 64, ... for r = 0, 1, ...): consecutive groups add to
     * one batch's histogram, which stays in cache (a chunk's exits spread over its batch's
     * 16 KB of bins, a new batch's every time: a tenth of a Lambertian run went to those
     * misses). Which group runs a chunk changes no tally; a GPU's groups take the chunks
     * in order. */
    const ulong g = get_group_id(0), n = get_num_groups(0), q = n / LSQT_BATCHES, big = (n % LSQT_BATCHES) * (q + 1);
    const ulong r = g < big ? g / (q + 1) : n % LSQT_BATCHES + (g - big) / q;
    const ulong chunk = LSQT_RECORDS ? chunk_first + g : chunk_first + r + LSQT_BATCHES * (g < big ? g % (q + 1) : (g - big) % q);
    s.lid = (int)get_local_id(0), s.lsz = (int)get_local_size(0);
    s.slice = (uint)get_global_id(1);
    s.begin = max(chunk * LSQT_CHUNK, path_begin);
    s.end = min((chunk + 1) * LSQT_CHUNK, path_end);
    s.batch = (int)(chunk % LSQT_BATCHES);
    return s;
}

/* The GPU path's walk: a path per work-item, LSQT_CHUNK work-items per chunk, in groups
 * that divide it (the host sees to it), so that a group's paths are of one chunk and one
 * batch; begin = the work-item's path and end = begin + 1, or end = begin where it falls
 * outside [path_begin, path_end). A loop over several paths kept the state of a path's
 * start and end live through the walk: some 10 VGPRs on gfx90a. The slice and the batch
 * are the group's (a group is of one chunk, and one slice: local size 1 in dimension 1),
 * taken from its index so that the compiler sees them the same in every work-item: the
 * pointers made from them take no VGPRs (3 to 4 fewer on gfx90a). */
LSQT_INLINE chunk_span path_span(ulong chunk_first, ulong path_begin, ulong path_end)
{
    chunk_span s;
    const ulong p = chunk_first * LSQT_CHUNK + get_global_id(0);
    s.lid = (int)get_local_id(0), s.lsz = (int)get_local_size(0);
    s.slice = (uint)get_group_id(1);
    s.begin = p;
    s.end = p >= path_begin && p < path_end ? p + 1 : p;
    s.batch = (int)((chunk_first + get_group_id(0) * get_local_size(0) / LSQT_CHUNK) % LSQT_BATCHES);
    return s;
}

/* The paths: a work-group runs those of its chunk (chunk_span; on the GPU path a part of
 * a chunk, a path each, path_span) and adds its tallies once to the batch's. In a grouped
 * session (the RRSS pilot) one walk serves every candidate set of the slice: set b's directions
 * are [b LSQT_GROUP_PAD, + LSQT_GROUP_NWI), and its tallies are state slice
 * slice * slice_group + b, whose R and T and work are the walk's; the histogram is one a
 * simulated slice (the host gives it to every set). The CPU path sums the next-event
 * estimates in local memory and ignores rec,
 * rec_off and count_only. The GPU path (LSQT_NEE_RECORDS) makes none: path p's records
 * go to rec from rec_off[slice * (path_end - path_begin) + p - path_begin] on, and
 * lsqt_estimate evaluates them; with count_only it only writes each path's record count
 * there (the host turns the counts into offsets) and tallies nothing. */
LSQT_GPU_KERNEL void lsqt_walk(__constant lsqt_dev_scene *scene,
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
    BAND_ARRAY(real, rows, BAND_STATE);
    const chunk_span s = LSQT_RECORDS ? path_span(chunk_first, path_begin, path_end)
                                      : chunk_of(chunk_first, path_begin, path_end);

    for (int k = s.lid; k < LSQT_ACC_WORDS * LSQT_T_COUNT * LSQT_NB; k += s.lsz) acc[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);

    work_t work[WORK_N] = {0, 0, 0};
    const uint g = (uint)max(scene->slice_group, 1), v = s.slice * g; /* v: the first state slice */
    walk_ctx c;
    c.in.scene = scene, c.in.media = media, c.in.layers = layers, c.in.wi = wi_dirs + 3 * LSQT_NWI_PAD * s.slice;
    c.in.tab = tab + (size_t)s.slice * LSQT_SLICE_TAB(scene->n_layers);
    c.sink.work = work, c.sink.acc = acc, c.sink.nee_g = nee, c.sink.v = v, c.sink.batch = s.batch, c.sink.flags = flags;
    uint touched = 0;
    c.mode.nee_on = 1, c.mode.exit_dir = 0, c.band.touched = &touched, c.band.rows = rows;
    c.sink.sum = 0, c.sink.bsum = 0, c.sink.nee = 0, c.in.bw = bandw;
    real3 wo = make_real3(wo_dirs[4 * v], wo_dirs[4 * v + 1], wo_dirs[4 * v + 2]);
    __global ulong *hist_b = hist + 2 * ((ulong)s.slice * LSQT_BATCHES + (ulong)s.batch) * LSQT_HIST_BINS * LSQT_NB;
    /* The paths, one body per code path. The CPU path's local memory can only be declared
     * in the kernel; the GPU path's path stays here too (in a function of its own,
     * clang-15 inlines the walk in another order, and lsqt_walk and lsqt_exits take a VGPR
     * more on gfx90a). */
#ifdef LSQT_NEE_RECORDS
    nee_out out;
    c.sink.out = &out, c.sink.count_only = count_only;
    if (s.begin < s.end) {
        const ulong p = s.begin, at = (ulong)s.slice * (path_end - path_begin) + (p - path_begin);
        out.rec = count_only ? 0 : rec;
        out.n = count_only ? 0 : (uint)rec_off[at];
        band_set_hero(&c, p);
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
     * vectors, for aligned blocks: VEC_AT): LSQT_NB rows of low words, LSQT_SUM_ROWS of
     * sums. */
    __local ulongv nee_v[LSQT_ITEMS * LSQT_NB * (LSQT_NWI_PAD / LSQT_VW)];
    __local realv sum_v[LSQT_ITEMS * LSQT_SUM_ROWS * (LSQT_NWI_PAD / LSQT_VW)];
    __local ulong *nee_priv = (__local ulong *)(nee_v + lid * LSQT_NB * (LSQT_NWI_PAD / LSQT_VW));
    __local real *path_sum = (__local real *)(sum_v + lid * LSQT_SUM_ROWS * (LSQT_NWI_PAD / LSQT_VW));
    for (int k = 0; k < LSQT_NB * LSQT_NWI_PAD; k++) nee_priv[k] = 0;
    for (int k = 0; k < LSQT_SUM_ROWS * LSQT_NWI_PAD; k++) path_sum[k] = R(0.0);
    c.sink.sum = path_sum, c.sink.nee = nee_priv, c.sink.out = 0, c.sink.count_only = 0;
    c.sink.bsum = LSQT_NB > 1 ? path_sum + LSQT_NWI_PAD : path_sum; /* one band's: the vertex's row */
#ifdef LSQT_RNG_WIDE
    rng_t ahead; /* the next path's stream, made with this one's (rng_init_pair) */
    int have_ahead = 0;
#endif
    for (ulong p = s.begin + (ulong)lid; p < s.end; p += (ulong)lsz) {
        band_set_hero(&c, p);
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
        const int band = k / LSQT_T_COUNT, t = k % LSQT_T_COUNT;
        __global ulong *sc = scalars + (size_t)band * scene->band_scalar_words;
        for (uint b = 0; b < g; b++) {
            const ulong base = (ulong)(v + b) * LSQT_BATCHES + (ulong)s.batch;
            global_add128(sc + 2 * (base * LSQT_T_COUNT + t), a.lo, a.hi, flags);
        }
    }
}

#ifdef LSQT_NEE_RECORDS
/* A record's terms for the vector of directions at b (dirs, st: the slice's directions
 * and tables). */
LSQT_INLINE realv nee_rec_vec(__global const lsqt_nee_rec *r, __global const lsqt_dev_medium *media,
                                  __global const lsqt_dev_layer *layers, __global const real *dirs,
                                  __global const real *st, int b)
{
    const lsqt_nee_rec q = *r;
    const int kind = (int)LSQT_NEE_KIND(q), i = (int)LSQT_NEE_INDEX(q);
    const real w = LSQT_NEE_W(q);
    if (kind == NEE_LAYER) return nee_layer_vec(&layers[i], LSQT_NEE_V(q), w, dirs, st + LSQT_LAYER_TAB(i), b);
    if (kind == NEE_MEDIUM) {
        phase_vtx pv = {LSQT_NEE_M(q)};
        return nee_medium_vec(&media[i], &pv, LSQT_NEE_V(q), w, LSQT_NEE_TAU_UP(q), LSQT_NEE_TAU_DOWN(q), dirs, st,
                                st + LSQT_NWI_PAD, b);
    }
    ms_vtx x = nee_ms_vtx(&q);
    return ms_nee_vec(&layers[i], kind, &x, LSQT_NEE_SIDE(q), w, dirs, st + LSQT_LAYER_TAB(i), b);
}

/* A spread of a path's records (NEE_SPREAD_RECORDS from r, bands.cl band_spread) for
 * the vector of directions at b: the vertex's terms u to each band's path sums bs. */
LSQT_INLINE void nee_rec_spread(__global const lsqt_nee_rec *r, realv u, __global const real *dirs,
                                __global const real *st, int b, realv *bs)
{
    const maskv same = vloadv(0, dirs + 2 * LSQT_NWI_PAD + b) * LSQT_NEE_WOZ(*r) > R(0.0);
    const realv au = vloadv(0, st + b), ad = vloadv(0, st + LSQT_NWI_PAD + b);
    int deeper = 0;
    for (int j = 0; j < LSQT_NB; j++) {
        const real4 f = LSQT_NEE_SPREAD(r[j / LSQT_NEE_SPREAD_BANDS], j % LSQT_NEE_SPREAD_BANDS);
        deeper |= f.z != R(0.0) || f.w != R(0.0);
    }
    for (int j = 0; j < LSQT_NB; j++) {
        const real4 f = LSQT_NEE_SPREAD(r[j / LSQT_NEE_SPREAD_BANDS], j % LSQT_NEE_SPREAD_BANDS);
        if (f.x != R(0.0) || f.y != R(0.0)) bs[j] = band_add(bs[j], u, same, f.x, f.y, f.z, f.w, deeper, au, ad);
    }
}

/* The GPU path's next-event estimates: one work-group per (chunk, simulated slice), as
 * lsqt_walk's, sharing the slice's directions: work-item i owns the vectors of LSQT_VW
 * directions at i LSQT_VW, (i + size) LSQT_VW, ... For each vector it sums every path's
 * records in the path's order (the CPU path's order, so the same sums), converts each
 * path's sum to fixed point and adds it to the block's tallies: a sum and a 64-bit word
 * per lane and band in registers, whatever the direction count. A band block's records
 * are at weight 1 and each vertex's are followed by its spread records, which add them to
 * each band's sums (as the CPU path's band_spread). Every work-item reads the same record
 * at once. */
LSQT_GPU_KERNEL void lsqt_estimate(__constant lsqt_dev_scene *scene, __global const lsqt_dev_medium *media,
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
    const size_t band_words = scene->band_nee_words;
    /* A block's low words in local memory (LSQT_NB x 16 bytes a work-item: 4 KB a group of
     * 64 at 4 bands), its path sums in registers (these loops over the bands are unrolled):
     * both in registers took more than 128 VGPRs on gfx90a at 4 bands. */
    BAND_ARRAY(ulongv, lo, LSQT_NB);
    for (int b = s.lid * LSQT_VW; b < LSQT_NWI_PAD; b += s.lsz * LSQT_VW) {
        for (int j = 0; j < LSQT_NB; j++) lo[j] = (ulongv)(0);
        for (ulong p = s.begin; p < s.end; p++) {
            realv u = (realv)(R(0.0)), bs[LSQT_NB];
            for (int j = 0; j < LSQT_NB; j++) bs[j] = (realv)(R(0.0));
            const ulong r1 = rec_off[first + p + 1];
            for (ulong r = rec_off[first + p]; r < r1; r++) {
                if (LSQT_NB > 1 && (int)LSQT_NEE_KIND(rec[r]) == NEE_SPREAD) {
                    nee_rec_spread(rec + r, u, dirs, st, b, bs);
                    u = (realv)(R(0.0)), r += NEE_SPREAD_RECORDS - 1;
                } else
                    u += nee_rec_vec(rec + r, media, layers, dirs, st, b);
            }
            if (LSQT_NB == 1) bs[0] = u; /* one band's terms carry its weight */
            for (int j = 0; j < LSQT_NB; j++) lo[j] = nee_flush_vec(bs[j], lo[j], nee + j * band_words, v, s.batch, b, flags);
        }
        for (int j = 0; j < LSQT_NB; j++) {
            ulong ls[LSQT_VW];
            vstorev(lo[j], 0, ls);
            for (int i = 0; i < LSQT_VW; i++) {
                __global ulong *p = ls[i] ? nee_word(nee + j * band_words, v, s.batch, b + i) : 0;
                if (p) global_add128(p, ls[i], 0, flags);
            }
        }
    }
}
#endif
