/* Order-independent tallies: values become 128-bit unsigned fixed point (2^-LSQT_FIX_BITS
 * units, two 64-bit words, low first) and are added with integer atomics, so the sums do
 * not depend on thread scheduling, work-group size or how the path range was split. A
 * contribution may be up to LSQT_FIX_MAX_VALUE (above 1e13) and as small as 1e-12; 2^128
 * units hold 1e10 of the largest. Adds propagate carries word by word and raise a flag
 * instead of wrapping. Without cl_khr_int64_base_atomics a 64-bit word is two 32-bit
 * words (little-endian device, checked by the host). */
#if defined(cl_khr_int64_base_atomics) && !defined(LSQT_NO_INT64_ATOMICS)
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#define LSQT_INT64_ATOMICS 1
#endif

/* Largest value accepted per contribution (2^44 = 1.76e13): anything larger raises
 * LSQT_FLAG_OVERFLOW, which fails the run (the host never reports a clamped result). */
#define LSQT_FIX_MAX_VALUE R(17592186044416.0)
#define LSQT_TWO64 R(18446744073709551616.0)

typedef struct {
    ulongv lo, hi;
} fixv;

typedef struct {
    ulong lo, hi;
} fix1;

/* Values rounded to the nearest unit (a float sum x + 0.5 that ties may round up once
 * more: at most one unit, 1e-7 relative, and the same every time); non-finite or
 * negative ones raise a flag and count as 0. One body for LSQT_VW values (fixv, to_fixedv)
 * and for one (fix1, to_fixed; common.cl's scalar twins): FIX the result's type, T the
 * value's, M a comparison's, ALL and ANY of a condition, LONG_BITS(x) x converted to a
 * long and its bits taken as a ulong, ULONG(x) x converted to a ulong. */
#define LSQT_TO_FIXED(FIX, T, M, ALL, ANY, LONG_BITS, ULONG)                                         \
    {                                                                                                \
        FIX r;                                                                                       \
        /* The common case first, by two comparisons (NaN fails both): every value         \
         * non-negative and below 2^63 units (8.4e6), where the general form below does the \
         * same. The path sums' conversion was a fifth of a slab run. */                   \
        if (ALL((v >= R(0.0)) & (v < R(0.5) * LSQT_TWO64 / (real)LSQT_FIX_SCALE))) {                  \
            r.lo = LONG_BITS(v * (real)LSQT_FIX_SCALE + R(0.5));                                      \
            r.hi = 0;                                                                                \
            return r;                                                                                \
        }                                                                                            \
        const M bad = isnan(v) | isinf(v) | (v < R(0.0));                                            \
        if (ANY(bad)) {                                                                              \
            atomic_or(flags, LSQT_FLAG_NONFINITE);                                                   \
            v = bad ? (T)(R(0.0)) : v;                                                               \
        }                                                                                            \
        if (ANY(v > LSQT_FIX_MAX_VALUE)) {                                                           \
            atomic_or(flags, LSQT_FLAG_OVERFLOW);                                                    \
            v = fmin(v, LSQT_FIX_MAX_VALUE);                                                         \
        }                                                                                            \
        const T x = v * (real)LSQT_FIX_SCALE;                                                        \
        /* Almost every value is below 2^63 units (8e6): one signed conversion each (on x86 \
         * the unsigned one branches). Larger ones are whole numbers of units and split into \
         * words exactly: the scalings are powers of two and the remainder holds only low   \
         * bits of x. */                                                                      \
        if (ALL(x < R(0.5) * LSQT_TWO64)) {                                                          \
            r.lo = LONG_BITS(x + R(0.5)); /* to nearest (rte costs 20 % here) */                    \
            r.hi = 0;                                                                                \
        } else {                                                                                     \
            const T h = floor(x / LSQT_TWO64);                                                       \
            r.hi = ULONG(h);                                                                         \
            r.lo = ULONG(x - h * LSQT_TWO64);                                                        \
        }                                                                                            \
        return r;                                                                                    \
    }
#define LSQT_LONG_BITSV(x) as_ulongv(convert_longv(x))
#define LSQT_LONG_BITS1(x) ((ulong)(long)(x))
#define LSQT_ULONG1(x) ((ulong)(x))
LSQT_INLINE fixv to_fixedv(realv v, volatile __global uint *flags)
    LSQT_TO_FIXED(fixv, realv, maskv, allv, anyv, LSQT_LONG_BITSV, convert_ulongv)
LSQT_INLINE fix1 to_fixed(real v, volatile __global uint *flags)
    LSQT_TO_FIXED(fix1, real, int, LSQT_ALL1, LSQT_ANY1, LSQT_LONG_BITS1, LSQT_ULONG1)

/* 128-bit add into four 32-bit words w[0..3] (low first) with atomics on each word: a
 * word that wraps carries one into the next, counted by the add that wrapped it, so the
 * total is exact whatever the order. Zero words cost nothing. */
#define LSQT_ADD128_WORDS(w, lo, hi, flags)                                          \
    do {                                                                             \
        uint v_[4] = {(uint)(lo), (uint)((lo) >> 32), (uint)(hi), (uint)((hi) >> 32)}; \
        uint carry_ = 0;                                                             \
        for (int i_ = 0; i_ < 4; i_++) {                                             \
            uint add_ = v_[i_] + carry_;                                             \
            carry_ = add_ < carry_;                                                  \
            if (add_ == 0) continue;                                                 \
            uint old_ = atomic_add(&(w)[i_], add_);                                  \
            carry_ += old_ + add_ < old_;                                            \
        }                                                                            \
        if (carry_) atomic_or(flags, LSQT_FLAG_OVERFLOW);                            \
    } while (0)

/* The work-group accumulators: 64-bit words where the device has 64-bit atomics (one
 * atomic per add as a rule: the high word only takes carries), else 32-bit words. */
#ifdef LSQT_INT64_ATOMICS
typedef ulong acc_word;
#define LSQT_ACC_WORDS 2
#else
typedef uint acc_word;
#define LSQT_ACC_WORDS 4
#endif

LSQT_INLINE void local_add128(volatile __local acc_word *w, ulong lo, ulong hi, volatile __global uint *flags)
{
#ifdef LSQT_INT64_ATOMICS
    if (lo) {
        ulong old = atom_add(&w[0], lo);
        hi += old + lo < old ? 1ul : 0ul;
    }
    if (hi) {
        ulong oh = atom_add(&w[1], hi);
        if (oh + hi < oh) atomic_or(flags, LSQT_FLAG_OVERFLOW);
    }
#else
    LSQT_ADD128_WORDS(w, lo, hi, flags);
#endif
}

/* The 128-bit value of accumulator w (LSQT_ACC_WORDS words). */
LSQT_INLINE fix1 acc_read(volatile __local acc_word *w)
{
#ifdef LSQT_INT64_ATOMICS
    fix1 r = {w[0], w[1]};
#else
    fix1 r = {((ulong)w[1] << 32) | (ulong)w[0], ((ulong)w[3] << 32) | (ulong)w[2]};
#endif
    return r;
}

/* p: two 64-bit words (low first). */
LSQT_INLINE void global_add128(__global ulong *p, ulong lo, ulong hi, volatile __global uint *flags)
{
    if (lo == 0 && hi == 0) return;
#ifdef LSQT_INT64_ATOMICS
    ulong old = atom_add((volatile __global ulong *)p, lo);
    ulong h = hi + (old + lo < old ? 1ul : 0ul);
    if (h) {
        ulong oh = atom_add((volatile __global ulong *)(p + 1), h);
        if (oh + h < oh) atomic_or(flags, LSQT_FLAG_OVERFLOW);
    }
#else
    volatile __global uint *w = (volatile __global uint *)p;
    LSQT_ADD128_WORDS(w, lo, hi, flags);
#endif
}
