/* Kernels used only by the tests: they run the same model and RNG code as the walk. */

/* Philox known-answer check: one counter/key/rounds per work-item. */
__kernel void harness_philox(__global const uint *ctr, __global const uint *key,
                             __global const int *rounds, __global uint *out)
{
    int i = (int)get_global_id(0);
    uint4 c = (uint4)(ctr[4 * i], ctr[4 * i + 1], ctr[4 * i + 2], ctr[4 * i + 3]);
    uint2 k = (uint2)(key[2 * i], key[2 * i + 1]);
    uint4 r = philox4x32_rounds(c, k, rounds[i]);
    out[4 * i] = r.x; out[4 * i + 1] = r.y; out[4 * i + 2] = r.z; out[4 * i + 3] = r.w;
}

/* The first n 32-bit draws of one path's stream (rng_init and rng_next_u32, as the walk
 * draws them); one work-item. */
__kernel void harness_rng_stream(uint seed_lo, uint seed_hi, uint slice, ulong path, uint purpose, int n,
                                 __global uint *out)
{
    rng_t rng = rng_init(seed_lo, seed_hi, slice, path, purpose);
    for (int i = 0; i < n; i++) out[i] = rng_next_u32(&rng);
}

/* The kernels' own elementary functions at given arguments, one per work-item:
 * out[5i] = neg_log_unit(xl[i]), out[5i + 1, 2] = azimuth_cs(xa[i]),
 * out[5i + 3] = inv_pow15v(xp[i]), out[5i + 4] = exp2_negv(xe[i]). */
__kernel void harness_fast_math(__global const float *xl, __global const float *xa, __global const float *xp,
                                __global const float *xe, __global float *out)
{
    const int i = (int)get_global_id(0);
    real2 cs = azimuth_cs(xa[i]);
    out[5 * i] = (float)neg_log_unit(xl[i]);
    out[5 * i + 1] = (float)cs.x;
    out[5 * i + 2] = (float)cs.y;
    out[5 * i + 3] = (float)inv_pow15v((realv)(xp[i])).s0;
    out[5 * i + 4] = (float)exp2_negv((realv)(xe[i])).s0;
}

/* The exit histogram's bin (walk.cl's hist_bin) of direction i, leaving upward where
 * its z >= 0. */
__kernel void harness_hist_bin(__global const float *d, __global int *out)
{
    const int i = (int)get_global_id(0);
    real3 v = make_real3(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
    out[i] = hist_bin(v, v.z >= R(0.0));
}

/* Samples one direction per work-item from a layer's BSDF (layer 0 of `layers`) or a
 * medium's phase function (medium 0 of `media`) for fixed wo; out = (x, y, z, weight). */
__kernel void harness_sample(__global const lsqt_dev_layer *layers,
                             __global const lsqt_dev_medium *media, int use_phase,
                             float wox, float woy, float woz, uint seed, __global float *out)
{
    uint i = (uint)get_global_id(0);
    rng_t rng = rng_init(seed, 0u, 0u, i, 7u);
    real3 wo = normalize(make_real3(wox, woy, woz)), wi = make_real3(R(0.0), R(0.0), R(1.0));
    phase_vtx pv = phase_vertex(media, wo, &rng);
    real w = use_phase ? phase_sample(media, &pv, wo, &rng, &wi) : bsdf_sample(layers, wo, &rng, &wi);
    out[4 * i] = (float)wi.x; out[4 * i + 1] = (float)wi.y; out[4 * i + 2] = (float)wi.z;
    out[4 * i + 3] = (float)w;
}

/* Evaluates f (or p) and pdf at given directions for fixed wo: out = (f, pdf). */
__kernel void harness_eval(__global const lsqt_dev_layer *layers,
                           __global const lsqt_dev_medium *media, int use_phase,
                           float wox, float woy, float woz, __global const float *wi,
                           __global float *out)
{
    int i = (int)get_global_id(0);
    real3 wo = normalize(make_real3(wox, woy, woz));
    real3 d = make_real3(wi[4 * i], wi[4 * i + 1], wi[4 * i + 2]);
    phase_vtx pv = {make_real3(R(0.0), R(0.0), R(1.0))}; /* deterministic phases ignore it */
    out[2 * i] = (float)(use_phase ? phase_eval(media, &pv, wo, d) : bsdf_eval(layers, wo, d));
    out[2 * i + 1] = (float)(use_phase ? phase_pdf(media, wo, d) : bsdf_pdf(layers, wo, d));
}

/* The conversion of one vector of LSQT_VW path sums, as the end of a path makes it
 * (to_fixedv): work-item i converts v[i VW .. (i + 1) VW) into out (lo, hi per value),
 * with its own flags word. */
__kernel void harness_tally_block(__global const float *v, __global ulong *out, volatile __global uint *flags)
{
    const int i = (int)get_global_id(0);
    realv x;
    real *xs = (real *)&x;
    for (int j = 0; j < LSQT_VW; j++) xs[j] = (real)v[i * LSQT_VW + j];
    fixv q = to_fixedv(x, flags + i);
    ulong lo[LSQT_VW], hi[LSQT_VW];
    vstorev(q.lo, 0, lo);
    vstorev(q.hi, 0, hi);
    for (int j = 0; j < LSQT_VW; j++) out[2 * (i * LSQT_VW + j)] = lo[j], out[2 * (i * LSQT_VW + j) + 1] = hi[j];
}

/* Tallies: every work-item adds its value into the work-group's 128-bit accumulator (in
 * local memory, as the walk's) and straight into global tally 0; the group's sum then
 * goes to global tally 1. out: two tallies of two 64-bit words. */
__kernel void harness_tally(__global const float *v, __global ulong *out, volatile __global uint *flags)
{
    __local acc_word acc[LSQT_ACC_WORDS];
    const int lid = (int)get_local_id(0);
    if (lid < LSQT_ACC_WORDS) acc[lid] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    fix1 q = to_fixed((real)v[get_global_id(0)], flags);
    local_add128(acc, q.lo, q.hi, flags);
    global_add128(out, q.lo, q.hi, flags);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid == 0) {
        fix1 t = acc_read(acc);
        global_add128(out + 2, t.lo, t.hi, flags);
    }
}

#ifndef LSQT_NEE_RECORDS /* the CPU code path's sums (the tests build it) */
/* Stochastic evaluation of a microsurface (layer 0) for fixed wo towards the LSQT_NWI
 * directions wi (x[pad], y[pad], z[pad]), with the slice's direction tables tab that
 * lsqt_prepare makes for a one-layer scene (its layer's after the media's rows): each
 * work-item averages `reps` vertex evaluations (each iter_count walks plus the analytic
 * single scattering, exactly as the path loop does) and writes its means,
 * out[item * LSQT_NWI_PAD + k]; the spread across work-items gives the noise. */
__kernel __attribute__((reqd_work_group_size(1, 1, 1))) void
harness_ms_eval(__global const lsqt_dev_layer *layers, float wox, float woy, float woz, __global const real *wi,
                __global const real *tab, uint seed, int reps, __global float *out)
{
    uint i = (uint)get_global_id(0);
    rng_t rng = rng_init(seed, 0u, 1u, i, 7u);
    real3 wo = normalize(make_real3(wox, woy, woz));
    __local realv sum_v[LSQT_NWI_PAD / LSQT_VW]; /* the group's (one work-item's) sums */
    __local real *sum = (__local real *)sum_v;
    for (int k = 0; k < LSQT_NWI_PAD; k++) sum[k] = R(0.0);
    ms_sink sink = {sum, wi, tab + LSQT_LAYER_TAB(0)};
    for (int r = 0; r < reps; r++) {
        real3 o;
        ms_vertex_walks(layers, -wo, &rng, R(1.0) / (real)reps, 1, &sink, 0, &o);
    }
    for (int k = 0; k < LSQT_NWI_PAD; k++) out[(size_t)i * LSQT_NWI_PAD + k] = (float)sum[k];
}
#endif

/* Stochastic phase evaluation (diffuse SGGX): work-item i averages `reps` vertices (each
 * one visible normal, as the path loop draws) towards direction i; out[i] = the mean. */
__kernel void harness_phase_mc(__global const lsqt_dev_medium *media, float wox, float woy, float woz,
                               __global const float *wi, uint seed, int reps, __global float *out)
{
    int i = (int)get_global_id(0);
    rng_t rng = rng_init(seed, 0u, 2u, (ulong)i, 7u);
    real3 wo = normalize(make_real3(wox, woy, woz));
    real3 d = make_real3(wi[4 * i], wi[4 * i + 1], wi[4 * i + 2]);
    real sum = R(0.0);
    for (int r = 0; r < reps; r++) {
        phase_vtx pv = phase_vertex(media, wo, &rng);
        sum += phase_eval(media, &pv, wo, d);
    }
    out[i] = (float)(sum / (real)reps);
}
