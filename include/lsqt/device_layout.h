/* Layouts shared by the host and the OpenCL kernels: the device tables of one assembly,
 * the tally buffers and the GPU code path's next-event records. This file is compiled
 * both as C11 and as OpenCL C 1.2 (it is prepended to the kernel sources), so it holds
 * only 4-byte scalar fields, or 8-byte ones in whole pairs of 4-byte fields (the records:
 * whole vectors of 4): the layout is then the same on every device and host without
 * packing pragmas. */
#ifndef LSQT_DEVICE_LAYOUT_H
#define LSQT_DEVICE_LAYOUT_H

#ifdef __OPENCL_C_VERSION__
typedef int lsqt_i32;
typedef uint lsqt_u32;
#else
#include <stdint.h>
typedef int32_t lsqt_i32;
typedef uint32_t lsqt_u32;
#endif

/* Paths are grouped in chunks of LSQT_CHUNK consecutive path indices; chunk c belongs to
 * batch c % LSQT_BATCHES. Both numbers are part of what a result means (the LSS stores
 * them), so that any split of the path range gives the same integer tallies. */
#define LSQT_CHUNK 256
#define LSQT_BATCHES 32

/* The GPU code path's work-group size, at most (the kernels size their local memory for
 * it, walk.cl; the host launches no wider groups, session.c). */
#define LSQT_GPU_ITEMS 64

/* Incident directions go to the device as three coordinate arrays (x, y, z) per slice,
 * each padded to a multiple of 4 with zero vectors, which contribute nothing. */
#define LSQT_PAD(n, w) (((n) + (w) - 1) / (w) * (w))

/* Rows (each padded to the directions' width) of a slice's direction tables
 * (walk.cl's lsqt_prepare): LSQT_MEDIA_TAB_ROWS for the media's transmittance, then
 * LSQT_LAYER_TAB_ROWS per layer. */
#define LSQT_MEDIA_TAB_ROWS 2
#define LSQT_LAYER_TAB_ROWS 3

/* Tallies are 128-bit unsigned fixed point, value * 2^LSQT_FIX_BITS rounded, stored as
 * two 64-bit words, low first: a unit of 2^-40 resolves 1e-12 of a unit weight, and
 * 2^88 holds 1e10 contributions of 1e12 (kernels/tally.cl). */
#define LSQT_FIX_BITS 40
#define LSQT_FIX_SCALE 1099511627776.0
#define LSQT_TALLY_WORDS 2 /* 64-bit words per tally */
#ifndef __OPENCL_C_VERSION__
typedef struct lsqt_u128 {
    uint64_t lo, hi;
} lsqt_u128;
#endif

/* Per-(slice, batch) scalar tallies, after the n_wi point-estimate sums. */
#define LSQT_T_R 0        /* weight leaving upward */
#define LSQT_T_T 1        /* weight leaving downward */
#define LSQT_T_DELTA_T 2  /* part of T that never scattered (forward delta) */
#define LSQT_T_CUT 3      /* paths stopped by the safety cap (count, not fixed point) */
/* Work counters (counts, not fixed point): scattering events on layers (NullBsdf layers
 * are crossed, not counted) and in media, and the vertices whose next-event estimate
 * was evaluated towards all n_wi directions (path vertices and microsurface walk
 * vertices that can see out): n_wi times that is the count of evaluations. */
#define LSQT_T_LAYER_EVENTS 4
#define LSQT_T_MEDIUM_EVENTS 5
#define LSQT_T_NEE_VERTICES 6
#define LSQT_T_COUNT 7

/* Exit histogram: per hemisphere LSQT_HIST_NMU bins in |cos theta| times LSQT_HIST_NPHI in
 * phi folded to [0, pi] (equal solid angle). Upper hemisphere first. Tallied per
 * (simulated slice, batch), as the point estimates, so that every bin has a standard
 * error; a slice group (the RRSS pilot's blocks of a slice) has one, its paths' exits. */
#define LSQT_HIST_NMU 32
#define LSQT_HIST_NPHI 16
#define LSQT_HIST_BINS (2 * LSQT_HIST_NMU * LSQT_HIST_NPHI)

/* Status flags the kernels may raise (bitwise OR into one word). */
#define LSQT_FLAG_OVERFLOW 1u   /* a fixed-point tally would have wrapped */
#define LSQT_FLAG_NONFINITE 2u  /* a non-finite contribution was dropped */

/* Safety cap against infinite loops, not a bias control (Russian roulette ends paths):
 * in a lossless slab of optical thickness tau a path takes ~tau^2 events to cross, so
 * the cap sits far above that for tau = 1e4. Paths it stops are counted and reported. */
#define LSQT_MAX_EVENTS 1000000000

/* The tables of media and layers. Their parameters are of type T: float, or double in a
 * kernel built with -DLSQT_DOUBLE, so --double is double end to end (a float table would
 * cut every parameter to 1e-7 relative). The host knows both layouts: lsqt_dev_medium /
 * lsqt_dev_layer (float) and lsqt_dev_medium_d / lsqt_dev_layer_d (double). Integer
 * fields come in pairs, so the double layout has no padding either. */
#define LSQT_DEV_TABLES(T, SUFFIX)                                                          \
    typedef struct lsqt_dev_medium##SUFFIX {                                                \
        T eta, mua, mus, mut; /* mut = mua + mus */                                         \
        T thickness;          /* 0 for the top and bottom media */                          \
        T tau_above;          /* optical thickness of interior media above this one */      \
        T tau_below;          /* ... and below it */                                        \
        T pp[4];              /* phase parameters: HG {g} */                                \
        lsqt_i32 phase_kind;  /* enum lsqt_phase_kind, NONE when mus == 0 */                \
        lsqt_i32 pad;                                                                       \
    } lsqt_dev_medium##SUFFIX;                                                              \
    typedef struct lsqt_dev_layer##SUFFIX {                                                 \
        lsqt_i32 kind;        /* enum lsqt_bsdf_kind */                                     \
        lsqt_i32 iter_count;                                                                \
        lsqt_i32 multiple_scattering;                                                       \
        lsqt_i32 pad;                                                                       \
        T p[8];               /* BSDF parameters: Lambertian {fR, fT} */                    \
    } lsqt_dev_layer##SUFFIX;

#if defined(__OPENCL_C_VERSION__) && defined(LSQT_DOUBLE)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
LSQT_DEV_TABLES(double, )
#else
LSQT_DEV_TABLES(float, )
#endif
#ifndef __OPENCL_C_VERSION__
LSQT_DEV_TABLES(double, _d)
#endif

typedef struct lsqt_dev_scene {
    lsqt_i32 n_layers;
    lsqt_i32 n_wi;            /* point-estimate directions per slice */
    lsqt_i32 top_nonnull;     /* index of the topmost non-null layer, -1 if none */
    lsqt_i32 bottom_nonnull;  /* index of the bottommost non-null layer, -1 if none */
    lsqt_u32 seed_lo, seed_hi;
    lsqt_i32 slice_group;     /* state slices per simulated slice (the RRSS pilot: one walk
                                 serves a slice's candidate sets, one state slice each) */
    lsqt_u32 rng_side;        /* OR'ed into every RNG purpose: 0, or LSQT_RNG_BELOW for a state
                                 of light entering from below, so its paths are not those of
                                 the slices from above */
    /* A band block (walk.cl, -DLSQT_NB > 1): the path sums and scalars hold the block's
     * bands one after another, each laid out as a one-band session's; these are the
     * strides between them, in 64-bit words (0 in a one-band program). Its histogram has
     * the bands innermost: a one-band session's bin i of band b is entry i NB + b. */
    lsqt_u32 band_nee_words, band_scalar_words, band_hist_unused;
    lsqt_u32 band_pad;
} lsqt_dev_scene;

/* A band block's table (walk.cl, -DLSQT_NB > 1), in reals: first the largest extinction
 * of each medium over the block's bands (0: clear in every band), then rows of nbp reals
 * (the block's bands, then zeros up to nbp, the band count padded to the kernels' vector
 * width, so a row loads as vectors): per layer the factors for light leaving on wo's side
 * (fs), then per layer those for the other side (fo), per medium its mus, its mut, and
 * its optical thickness above and below it, then per layer a conductor's index n and k
 * (0 for the other layers), then per medium 1 in every band where the bands' phase
 * functions differ (0 where they are one). The block's layer table holds each layer's
 * unit model (fs = fo = 1) and its medium table the least of each medium's extinction
 * and depths (host/sim/band_blocks.c); after it in the same buffer come each band's own
 * media, n_layers + 1 a band (its phase function, extinction and depths: bands.cl
 * band_medium), and then the phase functions' tables. */
#define LSQT_BAND_AT(n_layers, nbp, row, b) ((n_layers) + 1 + (row) * (nbp) + (b))
#define LSQT_BAND_FS(n_layers, nbp, b, li) LSQT_BAND_AT(n_layers, nbp, li, b)
#define LSQT_BAND_FO(n_layers, nbp, b, li) LSQT_BAND_AT(n_layers, nbp, (n_layers) + (li), b)
#define LSQT_BAND_MUS(n_layers, nbp, b, m) LSQT_BAND_AT(n_layers, nbp, 2 * (n_layers) + (m), b)
#define LSQT_BAND_MUT(n_layers, nbp, b, m) LSQT_BAND_AT(n_layers, nbp, 3 * (n_layers) + 1 + (m), b)
#define LSQT_BAND_TAU_ABOVE(n_layers, nbp, b, m) LSQT_BAND_AT(n_layers, nbp, 4 * (n_layers) + 2 + (m), b)
#define LSQT_BAND_TAU_BELOW(n_layers, nbp, b, m) LSQT_BAND_AT(n_layers, nbp, 5 * (n_layers) + 3 + (m), b)
#define LSQT_BAND_ETA(n_layers, nbp, b, li) LSQT_BAND_AT(n_layers, nbp, 6 * (n_layers) + 4 + (li), b)
#define LSQT_BAND_KAPPA(n_layers, nbp, b, li) LSQT_BAND_AT(n_layers, nbp, 7 * (n_layers) + 4 + (li), b)
#define LSQT_BAND_PHASES(n_layers, nbp, b, m) LSQT_BAND_AT(n_layers, nbp, 8 * (n_layers) + 4 + (m), b)
#define LSQT_BAND_TAB_SIZE(n_layers, nbp) LSQT_BAND_AT(n_layers, nbp, 9 * (n_layers) + 5, 0)

/* The GPU code path's next-event record (kernels/walk.cl, -DLSQT_NEE_RECORDS): what a
 * path's vertex leaves for lsqt_estimate, its state that does not depend on the incident
 * direction, in LSQT_NEE_REC_VECS vectors of 4 reals (float, or double with --double),
 * which the kernels move whole. Every kind keeps a microsurface vertex's fields (ms_vtx);
 * a layer's record uses v only, a medium's also m (its phase_vtx's normal) and the
 * optical depths above and below the vertex in lam_v and lg_v. The kernels write
 * (kernels/nee_records.cl: nee_write) and read (walk.cl: nee_rec_vec) records through
 * the field macros below; the host sizes their buffer with lsqt_nee_rec. */
#define LSQT_NEE_REC_VECS 4
#define LSQT_NEE_RECORD(T4, SUFFIX)              \
    typedef struct lsqt_nee_rec##SUFFIX {        \
        T4 q[LSQT_NEE_REC_VECS];                 \
    } lsqt_nee_rec##SUFFIX;
#ifdef __OPENCL_C_VERSION__
#ifdef LSQT_DOUBLE
LSQT_NEE_RECORD(double4, )
#else
LSQT_NEE_RECORD(float4, )
#endif
/* Where each field is (r an lsqt_nee_rec): */
#define LSQT_NEE_V(r) (r).q[0].xyz        /* wo: the direction light leaves the vertex by */
#define LSQT_NEE_INV_AREA(r) (r).q[0].w   /* the rest as ms_vtx names them */
#define LSQT_NEE_M(r) (r).q[1].xyz
#define LSQT_NEE_LAM_V(r) (r).q[1].w
#define LSQT_NEE_TAU_UP(r) (r).q[1].w     /* a medium's: the optical depth above, in lam_v */
#define LSQT_NEE_LG_V(r) (r).q[2].x
#define LSQT_NEE_TAU_DOWN(r) (r).q[2].x   /* a medium's: the optical depth below, in lg_v */
#define LSQT_NEE_LOG_C(r) (r).q[2].y
#define LSQT_NEE_LOG_CBAR(r) (r).q[2].z
#define LSQT_NEE_E(r) (r).q[2].w
#define LSQT_NEE_W(r) (r).q[3].x          /* the weight */
#define LSQT_NEE_SIDE(r) (r).q[3].y       /* a microsurface's side (+-1), else 0 */
#define LSQT_NEE_KIND(r) (r).q[3].z       /* NEE_LAYER ... (nee_records.cl) */
#define LSQT_NEE_INDEX(r) (r).q[3].w      /* the layer's or the medium's index */
/* A band block's spread record (NEE_SPREAD) after a vertex's records: bands j ... j + 2
 * of the block, band j + i's (cs, co, dtu, dtd) in q[i] (bands.cl band_spread), and the
 * vertex's wo.z; kind in LSQT_NEE_KIND. */
#define LSQT_NEE_SPREAD_BANDS 3
#define LSQT_NEE_SPREAD(r, i) (r).q[i]
#define LSQT_NEE_WOZ(r) (r).q[3].x
#else
typedef float lsqt_nee_float4[4];
typedef double lsqt_nee_double4[4];
LSQT_NEE_RECORD(lsqt_nee_float4, )
LSQT_NEE_RECORD(lsqt_nee_double4, _d)
#endif

/* The RNG purpose bit of the paths from below (kernels/philox.cl: counter word 2 holds
 * purpose << 16). */
#define LSQT_RNG_BELOW 2u

#endif
