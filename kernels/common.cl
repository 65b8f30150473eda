/* Precision and small math shared by every kernel file. `real` is float by default and
 * double when the host builds with -DLSQT_DOUBLE=1 (only on devices with fp64). */
/* LSQT_VW directions at a time in the next-event loops (the host passes -DLSQT_VW: 16 on
 * CPUs, where the vector units are wide and PoCL does not vectorise these loops across
 * work-items; 2 on GPUs, where a work-item's vector is sequential work and registers).
 * `realv` holds LSQT_VW values (one per direction), `maskv` a comparison of two. */
#ifndef LSQT_VW
#define LSQT_VW 4
#endif

/* Every helper is static, so no program depends on the compiler inlining it to link (a
 * C99 plain inline function has no external definition: a GPU compiler at -O0 left 20
 * symbols undefined). One is better compiled on its own on the CPU path: nee_medium,
 * whose loop PoCL optimised worse inside the path loop (the MCX-like slab took a
 * quarter longer); a call per medium vertex costs nothing beside its loop. The GPU
 * path leaves every choice to the GPU's compiler. */
#define LSQT_INLINE static inline
#if !defined(LSQT_NEE_RECORDS) && defined(__clang__)
#define LSQT_NOINLINE_CPU static __attribute__((noinline))
#else
#define LSQT_NOINLINE_CPU static inline
#endif
#define LSQT_CAT_(a, b) a##b
#define LSQT_CAT(a, b) LSQT_CAT_(a, b)
#define vloadv LSQT_CAT(vload, LSQT_VW)
#define vstorev LSQT_CAT(vstore, LSQT_VW)
typedef LSQT_CAT(ulong, LSQT_VW) ulongv;
typedef LSQT_CAT(uint, LSQT_VW) uintv;
/* The vector of LSQT_VW values at p + k (k a multiple of LSQT_VW) of the CPU path's
 * direction sums (local memory declared as vectors, so aligned: one vector load or
 * store). Through vloadv/vstorev, PoCL stores 16 lanes as four 4-lane pieces, and the
 * next load of the vector waits for them (a store-forwarding stall on every next-event
 * vector). */
#define VEC_AT(type, p, k) (*(__local type *)((p) + (k)))
#define as_ulongv LSQT_CAT(as_ulong, LSQT_VW)
#define as_uintv LSQT_CAT(as_uint, LSQT_VW)
#define as_floatv LSQT_CAT(as_float, LSQT_VW)
#define convert_longv LSQT_CAT(convert_long, LSQT_VW)
#define convert_ulongv LSQT_CAT(convert_ulong, LSQT_VW)

#ifdef LSQT_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
typedef double2 real2;
typedef double3 real3;
typedef double4 real4;
typedef LSQT_CAT(double, LSQT_VW) realv;
typedef LSQT_CAT(long, LSQT_VW) maskv;
#define R(x) (x)
#define convert_real convert_double
#else
typedef float real;
typedef float2 real2;
typedef float3 real3;
typedef float4 real4;
typedef LSQT_CAT(float, LSQT_VW) realv;
typedef LSQT_CAT(int, LSQT_VW) maskv;
#define R(x) (x##f)
#define convert_real convert_float
#endif

#define LSQT_PI R(3.14159265358979323846)
#define LSQT_INV_PI R(0.31830988618379067154)
#define LSQT_INV_4PI R(0.07957747154594766788)

/* Russian roulette: a path whose weight falls below this survives with probability
 * weight / LSQT_RR_WEIGHT and then carries exactly LSQT_RR_WEIGHT (unbiased). */
#define LSQT_RR_WEIGHT R(0.25)

LSQT_INLINE real3 make_real3(real x, real y, real z) { return (real3)(x, y, z); }

/* any() and all() of a comparison of LSQT_VW lanes (lanes -1 or 0), by OR / AND of
 * halves: PoCL's builtins test lane after lane with a branch each (a fifth of the path
 * sums' conversion); sumv, the sum of the lanes, by halves (a lane-after-lane sum waits
 * for each add). */
#define LSQT_OR_HALVES(m) ((m).lo | (m).hi)
#define LSQT_AND_HALVES(m) ((m).lo & (m).hi)
#define LSQT_ADD_HALVES(m) ((m).lo + (m).hi)
#if LSQT_VW == 16
#define sumv(v) LSQT_ADD_HALVES(LSQT_ADD_HALVES(LSQT_ADD_HALVES(LSQT_ADD_HALVES(v))))
#define anyv(m) (LSQT_OR_HALVES(LSQT_OR_HALVES(LSQT_OR_HALVES(LSQT_OR_HALVES(m)))) < 0)
#define allv(m) (LSQT_AND_HALVES(LSQT_AND_HALVES(LSQT_AND_HALVES(LSQT_AND_HALVES(m)))) < 0)
#elif LSQT_VW == 8
#define sumv(v) LSQT_ADD_HALVES(LSQT_ADD_HALVES(LSQT_ADD_HALVES(v)))
#define anyv(m) (LSQT_OR_HALVES(LSQT_OR_HALVES(LSQT_OR_HALVES(m))) < 0)
#define allv(m) (LSQT_AND_HALVES(LSQT_AND_HALVES(LSQT_AND_HALVES(m))) < 0)
#elif LSQT_VW == 4
#define sumv(v) LSQT_ADD_HALVES(LSQT_ADD_HALVES(v))
#define anyv(m) (LSQT_OR_HALVES(LSQT_OR_HALVES(m)) < 0)
#define allv(m) (LSQT_AND_HALVES(LSQT_AND_HALVES(m)) < 0)
#elif LSQT_VW == 2
#define sumv(v) LSQT_ADD_HALVES(v)
#define anyv(m) (LSQT_OR_HALVES(m) < 0)
#define allv(m) (LSQT_AND_HALVES(m) < 0)
#else
#error "LSQT_VW must be 2, 4, 8 or 16"
#endif

/* 1/sqrt(x) for 0 < x < 2^126, LSQT_VW at once. In float: the exponent-halving integer
 * guess (Lomont's constant, error below 3.5 %) and three Newton steps, which square the
 * error (1.8e-3, 4.6e-6, 3e-11: below float's own rounding; test_fast_math), without
 * the CPU's divider (10 to 12 cycles per 16 lanes): PoCL's rsqrt and native_rsqrt are
 * 1 / sqrt. (Used where the divider bounds the loop, the medium's next-event loop; in
 * the microfacet models' loops it and a Newton reciprocal measured no faster.) In
 * double: the library's. */
LSQT_INLINE realv rsqrt_fastv(realv x)
{
#ifdef LSQT_DOUBLE
    return rsqrt(x);
#else
    const realv hx = R(0.5) * x;
    realv r = as_floatv((uintv)(0x5f375a86u) - (as_uintv(x) >> 1));
    r = r * (R(1.5) - hx * r * r);
    r = r * (R(1.5) - hx * r * r);
    r = r * (R(1.5) - hx * r * r);
    return r;
#endif
}

/* x^(-3/2) for 0 < x < 2^84: the Henyey-Greenstein value without a division or square
 * root, which were most of a medium vertex's next-event loop. */
LSQT_INLINE realv inv_pow15v(realv x)
{
    realv r = rsqrt_fastv(x);
    return r * r * r;
}

/* 2^x for x <= 0, LSQT_VW at once, exactly 0 below 2^-125 (any contribution that small
 * is 0 in the fixed-point tallies, LSQT_NEE_TAU_MAX). In float: x = n + f with n an
 * integer (by the round-to-nearest of adding 1.5 2^23) and |f| <= 1/2, 2^f by a degree-5
 * polynomial fitted for relative error (7.5e-8, 2.3e-7 with float's roundings;
 * test_fast_math), and n added to the exponent bits. PoCL's exp is longer (range checks
 * for both signs). In double: the library's. */
LSQT_INLINE realv exp2_negv(realv x)
{
#ifdef LSQT_DOUBLE
    return exp2(x);
#else
    const maskv tiny = x < R(-125.0);
    const realv xc = fmax(x, R(-125.0)), big = (realv)(R(12582912.0)); /* 1.5 2^23 */
    const realv t = xc + big, f = xc - (t - big);
    realv p = R(0.00132764715);
    p = p * f + R(0.00967554133);
    p = p * f + R(0.0555071327);
    p = p * f + R(0.240221197);
    p = p * f + R(0.693146967);
    p = p * f + R(1.00000007);
    const uintv scaled = as_uintv(p) + ((as_uintv(t) - as_uintv(big)) << 23);
    return select(as_floatv(scaled), (realv)(R(0.0)), tiny);
#endif
}

/* LSQT_VW directions at once, as three coordinate vectors: next-event estimation evaluates
 * a model at every incident direction, so models evaluate LSQT_VW at a time (SIMD on CPUs). */
typedef struct {
    realv x, y, z;
} dirv;

LSQT_INLINE dirv dirv_broadcast(real3 d)
{
    dirv r = {(realv)(d.x), (realv)(d.y), (realv)(d.z)};
    return r;
}

LSQT_INLINE real sqr(real x) { return x * x; }

/* Scalar twins. A model's formula serves both the LSQT_VW directions of next-event
 * estimation (realv) and the one direction a path samples (real): one macro body over a
 * type T, instantiated twice, whose selections are ?: (componentwise for a vector
 * condition). Lane 0 of a broadcast vector would do, but clang keeps every lane of such
 * a call through selects and divisions: on gfx90a that was four lanes of Fresnel terms
 * live in the walk, some 20 VGPRs. */
#define LSQT_ALL1(m) (m)
#define LSQT_ANY1(m) (m)

/* sqrt that never returns NaN for round-off negatives */
LSQT_INLINE real safe_sqrt(real x) { return sqrt(fmax(x, R(0.0))); }
LSQT_INLINE realv safe_sqrtv(realv x) { return sqrt(fmax(x, (realv)(R(0.0)))); }

/* Point-estimate directions per slice (the host passes -DLSQT_NWI=n), padded to a
 * multiple of LSQT_VW. */
#ifndef LSQT_NWI
#define LSQT_NWI 1
#endif
#define LSQT_NWI_PAD LSQT_PAD(LSQT_NWI, LSQT_VW)
/* The directions of one candidate set of a grouped session (the RRSS pilot: one walk serves the
 * scene->slice_group candidate sets of a slice, each LSQT_GROUP_PAD long within the
 * LSQT_NWI = slice_group x LSQT_GROUP_PAD directions); a plain session is one set. */
#ifndef LSQT_GROUP_NWI
#define LSQT_GROUP_NWI LSQT_NWI
#endif
#define LSQT_GROUP_PAD LSQT_PAD(LSQT_GROUP_NWI, LSQT_VW)

/* The bands on one path (kernels/bands.cl): a block of LSQT_NB (the host passes -DLSQT_NB
 * when it is not 1; one band is a block of width 1). LSQT_NBP: the width padded to the
 * vector width (the rows of a block's table, taken LSQT_VW bands at a time); LSQT_NBW: a
 * path's per-band arrays (1 for one band, whose code takes no vectors of bands);
 * LSQT_NBV: the bound of the loops that take them a vector at a time (none for one band). */
#ifndef LSQT_NB
#define LSQT_NB 1
#endif
#define LSQT_NBP LSQT_PAD(LSQT_NB, LSQT_VW)
#define LSQT_NBW (LSQT_NB > 1 ? LSQT_NBP : 1)
#define LSQT_NBV (LSQT_NB > 1 ? LSQT_NBP : 0)

/* Where a path's per-band state lives (bands.cl: each band's weight, its density ratio;
 * lsqt_estimate's low words): on the GPU path a block's in the work-group's local memory,
 * so that it takes no registers (in registers, 4 bands took the walk from 82 to 132
 * VGPRs on gfx90a); otherwise in private memory (on a CPU, in local memory beside the
 * path's sums, it cost a 32-band run 2 %). BAND_ARRAY declares a work-item's n elements
 * of type T there, at a kernel's outermost scope (local memory is declared nowhere else),
 * for groups of at most LSQT_GROUP_MAX work-items (nee.cl). */
#if LSQT_NB > 1 && defined(LSQT_NEE_RECORDS)
#define BAND_MEM __local
#define BAND_ARRAY(T, name, n) \
    __local T name##_all[LSQT_GROUP_MAX * (n)]; \
    __local T *name = name##_all + get_local_id(0) * (n)
#else
#define BAND_MEM
#define BAND_ARRAY(T, name, n) T name[n]
#endif
/* Before a loop over a block's bands: on the GPU path, not unrolled (unrolled, every
 * band's loads and terms are in flight at once and the walk needs more than 128 VGPRs on
 * gfx90a, test_gpu_build; the CPU path's loops are the compiler's to unroll). */
#if LSQT_NB > 1 && defined(LSQT_NEE_RECORDS)
#define BAND_LOOP _Pragma("unroll 1")
#else
#define BAND_LOOP
#endif
/* The GPU path's occupancy target on AMD: 4 waves per SIMD, at most 128 VGPRs on gfx90a
 * (without it the compiler settles on 3 waves for a band block's walk, whose registers
 * then grow to some 140). Other devices choose their own. */
#if defined(__AMDGCN__) && defined(LSQT_NEE_RECORDS)
#define LSQT_GPU_KERNEL __kernel __attribute__((amdgpu_waves_per_eu(4)))
#else
#define LSQT_GPU_KERNEL __kernel
#endif

/* lgamma(x) for x >= 1 without the library's general lgamma (scalar on PoCL, some 40
 * VGPRs on gfx90a): the Stirling series to 1/x^7 for x >= 8, error below 3e-11, after
 * lgamma(x) = lgamma(x + 6) - log(x (x+1) ... (x+5)) for smaller x. One text for the
 * LSQT_VW-wide form and the scalar one (the scalar twins above). */
#define LSQT_LGAMMA_GE1(T)                                                                                    \
    {                                                                                                         \
        const T p = x * (x + R(1.0)) * (x + R(2.0)) * (x + R(3.0)) * (x + R(4.0)) * (x + R(5.0));               \
        const T y = x < R(8.0) ? x + R(6.0) : x;                                                              \
        const T r = R(1.0) / y, r2 = r * r;                                                                   \
        const T series = r * (R(1.0) / R(12.0) - r2 * (R(1.0) / R(360.0) - r2 * (R(1.0) / R(1260.0) - r2 * (R(1.0) / R(1680.0))))); \
        const T lg = (y - R(0.5)) * log(y) - y + R(0.91893853320467274178) + series;                          \
        return lg - (x < R(8.0) ? log(p) : (T)(R(0.0)));                                                      \
    }
LSQT_INLINE realv lgamma_ge1_v(realv x) LSQT_LGAMMA_GE1(realv)
LSQT_INLINE real lgamma_ge1(real x) LSQT_LGAMMA_GE1(real)

/* What a phase function fixes at a vertex for every direction it is evaluated towards and
 * for its sample (models.cl phase_vertex): a diffuse SGGX flake's visible normal. */
typedef struct {
    real3 m;
} phase_vtx;

/* A model's table (a TABLE key, include/lsqt/model_list.h): the host puts the tables after
 * the media in the media's buffer (host/sim/tables.c), and a medium with one holds in
 * pp[0] the media from it to their end and in pp[1] its table's offset in reals from
 * there (pp[2]: its row count), so the address is the medium's own plus those: no kernel
 * argument, and the same on every device. */
LSQT_INLINE __global const real *medium_table(__global const lsqt_dev_medium *m)
{
    return (__global const real *)(m + (int)m->pp[0]) + (int)m->pp[1];
}
