/* Precision and small math shared by every kernel file. `real` is float by default and
 * double when the host builds with -DLSQT_DOUBLE=1 (only on devices with fp64). */
#ifdef LSQT_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
typedef double2 real2;
typedef double3 real3;
typedef double4 real4;
typedef long4 mask4; /* what comparing two real4 gives */
#define convert_real4 convert_double4
#define R(x) (x)
#define convert_real convert_double
#else
typedef float real;
typedef float2 real2;
typedef float3 real3;
typedef float4 real4;
typedef int4 mask4;
#define convert_real4 convert_float4
#define R(x) (x##f)
#define convert_real convert_float
#endif

#define LSQT_PI R(3.14159265358979323846)
#define LSQT_INV_PI R(0.31830988618379067154)
#define LSQT_INV_4PI R(0.07957747154594766788)

/* Russian roulette: a path whose weight falls below this survives with probability
 * weight / LSQT_RR_WEIGHT and then carries exactly LSQT_RR_WEIGHT (unbiased). */
#define LSQT_RR_WEIGHT R(0.25)

inline real3 make_real3(real x, real y, real z) { return (real3)(x, y, z); }

/* Four directions at once, as three coordinate vectors: next-event estimation evaluates
 * a model at every incident direction, so models evaluate in fours (SIMD on CPUs). */
typedef struct {
    real4 x, y, z;
} dir4;

inline dir4 dir4_broadcast(real3 d)
{
    dir4 r = {(real4)(d.x), (real4)(d.y), (real4)(d.z)};
    return r;
}

inline real sqr(real x) { return x * x; }

/* sqrt that never returns NaN for round-off negatives */
inline real safe_sqrt(real x) { return sqrt(fmax(x, R(0.0))); }
inline real4 safe_sqrt4(real4 x) { return sqrt(fmax(x, (real4)(R(0.0)))); }

/* Point-estimate directions per slice (the host passes -DLSQT_NWI=n), padded to fours. */
#ifndef LSQT_NWI
#define LSQT_NWI 1
#endif
#define LSQT_NWI_PAD LSQT_PAD4(LSQT_NWI)
/* The directions of one block of a grouped session (the RRSS pilot: one walk serves the
 * scene->slice_group candidate blocks of a slice, each LSQT_GROUP_PAD long within the
 * LSQT_NWI = slice_group x LSQT_GROUP_PAD directions); a plain session is one block. */
#ifndef LSQT_GROUP_NWI
#define LSQT_GROUP_NWI LSQT_NWI
#endif
#define LSQT_GROUP_PAD LSQT_PAD4(LSQT_GROUP_NWI)

/* lgamma(x) for x >= 1, four at once, without the library's general (and, on PoCL,
 * scalar) lgamma: the Stirling series to 1/x^7 for x >= 8, error below 3e-11, after
 * lgamma(x) = lgamma(x + 6) - log(x (x+1) ... (x+5)) for smaller x. */
inline real4 lgamma_ge1_4(real4 x)
{
    mask4 small = x < R(8.0);
    real4 p = x * (x + R(1.0)) * (x + R(2.0)) * (x + R(3.0)) * (x + R(4.0)) * (x + R(5.0));
    real4 y = select(x, x + R(6.0), small);
    real4 r = R(1.0) / y, r2 = r * r;
    real4 series = r * (R(1.0) / R(12.0) - r2 * (R(1.0) / R(360.0) - r2 * (R(1.0) / R(1260.0) - r2 * (R(1.0) / R(1680.0)))));
    real4 lg = (y - R(0.5)) * log(y) - y + R(0.91893853320467274178) + series;
    return lg - select((real4)(R(0.0)), log(p), small);
}
