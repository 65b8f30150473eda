/* Order-independent tallies: values become 64-bit unsigned fixed point and are added with
 * integer atomics, so the sums do not depend on thread scheduling, work-group size or how
 * the path range was split. Every add detects a carry out of 64 bits and raises a flag
 * instead of wrapping silently. Without cl_khr_int64_base_atomics a 64-bit word is two
 * 32-bit words (little-endian device, checked by the host) with an explicit carry. */
#if defined(cl_khr_int64_base_atomics) && !defined(LSQT_NO_INT64_ATOMICS)
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#define LSQT_INT64_ATOMICS 1
#endif

/* Largest value accepted per contribution; beyond it the flag is raised (keeps per-chunk
 * local sums far from 2^64). */
#define LSQT_FIX_MAX_VALUE R(1048576.0)

/* Four values at once; non-finite or negative lanes raise a flag and count as 0. */
inline ulong4 to_fixed4(real4 v, volatile __global uint *flags)
{
    mask4 bad = isnan(v) | isinf(v) | (v < R(0.0));
    if (any(bad)) {
        atomic_or(flags, LSQT_FLAG_NONFINITE);
        v = select(v, (real4)(R(0.0)), bad);
    }
    if (any(v > LSQT_FIX_MAX_VALUE)) {
        atomic_or(flags, LSQT_FLAG_OVERFLOW);
        v = fmin(v, LSQT_FIX_MAX_VALUE);
    }
    /* Values are below 2^51, so the signed conversion (one instruction per lane on x86,
     * where the unsigned one branches) is exact. */
#ifdef LSQT_DOUBLE
    return as_ulong4(convert_long4(v * LSQT_FIX_SCALE + 0.5));
#else
    return as_ulong4(convert_long4(v * (float)LSQT_FIX_SCALE + 0.5f));
#endif
}

/* One value: lane x of the same conversion. */
inline ulong to_fixed(real v, volatile __global uint *flags)
{
    return to_fixed4((real4)(v), flags).x;
}

/* Adds v to a 64-bit word held as two 32-bit local words (lo, hi). */
inline void local_add64(volatile __local uint *lo, volatile __local uint *hi, ulong v,
                        volatile __global uint *flags)
{
    uint vlo = (uint)v, vhi = (uint)(v >> 32);
    uint old = atomic_add(lo, vlo);
    if (old + vlo < old) vhi++;
    if (vhi) {
        uint oh = atomic_add(hi, vhi);
        if (oh + vhi < oh) atomic_or(flags, LSQT_FLAG_OVERFLOW);
    }
}

inline void global_add64(__global ulong *p, ulong v, volatile __global uint *flags)
{
    if (v == 0) return;
#ifdef LSQT_INT64_ATOMICS
    ulong old = atom_add((volatile __global ulong *)p, v);
    if (old + v < old) atomic_or(flags, LSQT_FLAG_OVERFLOW);
#else
    volatile __global uint *w = (volatile __global uint *)p;
    uint vlo = (uint)v, vhi = (uint)(v >> 32);
    uint old = atomic_add(&w[0], vlo);
    if (old + vlo < old) vhi++;
    if (vhi) {
        uint oh = atomic_add(&w[1], vhi);
        if (oh + vhi < oh) atomic_or(flags, LSQT_FLAG_OVERFLOW);
    }
#endif
}
