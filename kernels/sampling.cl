/* Direction warps and frames used by several models. */

/* Orthonormal basis around unit n (Duff et al. 2017, branchless). */
LSQT_INLINE void make_frame(real3 n, real3 *t, real3 *b)
{
    real s = n.z >= R(0.0) ? R(1.0) : R(-1.0);
    real a = R(-1.0) / (s + n.z);
    real c = n.x * n.y * a;
    *t = make_real3(R(1.0) + s * n.x * n.x * a, s * c, -s * n.x);
    *b = make_real3(c, s + n.y * n.y * a, -n.y);
}

/* (cos, sin) of the azimuth 2 pi u, u in [0, 1). In float: the quarter turn q = floor(4 u)
 * and, within it, the angle pi/4 + b, |b| <= pi/4, whose cosine and sine follow from
 * Taylor polynomials of b (truncation below 2e-9) as (cos b -+ sin b) / sqrt 2: straight-
 * line arithmetic, a third of the cost of PoCL's cospi and sinpi, which reduce their
 * argument with branches and were a fifth of a scattering event. In double: cospi and
 * sinpi of 2u - 1 (|x| <= 1, no costly reduction of a radian argument; the point is the
 * same, rotated by pi, so the signs flip back). */
LSQT_INLINE real2 azimuth_cs(real u)
{
#ifdef LSQT_DOUBLE
    real x = R(2.0) * u - R(1.0);
    return (real2)(-cospi(x), -sinpi(x));
#else
    const real v = R(4.0) * u; /* exact: u has 24 bits */
    const int iq = (int)v;     /* v >= 0: truncation is floor, without its special cases */
    const real b = (v - (real)iq - R(0.5)) * (LSQT_PI / R(2.0)), b2 = b * b;
    const real sb = b * (R(1.0) + b2 * (R(-1.0) / R(6.0) + b2 * (R(1.0) / R(120.0) + b2 * (R(-1.0) / R(5040.0) + b2 * (R(1.0) / R(362880.0))))));
    const real cb = R(1.0) + b2 * (R(-0.5) + b2 * (R(1.0) / R(24.0) + b2 * (R(-1.0) / R(720.0) + b2 * (R(1.0) / R(40320.0) + b2 * (R(-1.0) / R(3628800.0))))));
    const real c = (cb - sb) * R(0.70710678118654752440), s = (cb + sb) * R(0.70710678118654752440);
    /* turn (c, s) by iq quarter turns: (c, s), (-s, c), (-c, -s), (s, -c), by a swap and
     * sign bits (branches here would be mispredicted three times in four) */
    const int odd = iq & 1;
    const uint fx = (uint)((iq + 1) & 2) << 30, fy = (uint)(iq & 2) << 30;
    return (real2)(as_float(as_uint(odd ? s : c) ^ fx), as_float(as_uint(odd ? c : s) ^ fy));
#endif
}

/* -log(x) for x in (0, 1] (a free flight's length in mean free paths from x = 1 - u). In
 * float: x = m 2^e with m in [sqrt(1/2), sqrt(2)), log m = 2 atanh(s), s = (m - 1) / (m + 1),
 * |s| < 0.172, by its series to s^9 (truncation below 3e-9 relative; m - 1 is exact, so
 * x near 1 keeps its relative accuracy), without the library's call and special cases.
 * In double: the library's. */
LSQT_INLINE real neg_log_unit(real x)
{
#ifdef LSQT_DOUBLE
    return -log(x);
#else
    int i = as_int(x);
    int e = ((i >> 23) & 0xff) - 127;
    real m = as_float((i & 0x007fffff) | 0x3f800000);
    if (m > R(1.41421356237309504880)) m *= R(0.5), e += 1;
    const real s = (m - R(1.0)) / (m + R(1.0)), s2 = s * s;
    const real l = R(2.0) * s * (R(1.0) + s2 * (R(1.0) / R(3.0) + s2 * (R(1.0) / R(5.0) + s2 * (R(1.0) / R(7.0) + s2 * (R(1.0) / R(9.0))))));
    return -((real)e * R(0.69314718055994530942) + l);
#endif
}

/* Cosine-weighted direction on the upper (+z) hemisphere; pdf = cos / pi. */
LSQT_INLINE real3 sample_cosine_hemisphere(real u1, real u2)
{
    real r = sqrt(u1);
    real2 cs = azimuth_cs(u2);
    return make_real3(r * cs.x, r * cs.y, safe_sqrt(R(1.0) - u1));
}

/* A vector that is unit up to rounding (|v|^2 = 1 + e, |e| < 1e-4), made unit again by
 * one Newton step for 1/sqrt from 1: the factor 1.5 - |v|^2 / 2 = 1 - e/2 differs from
 * 1/sqrt(1 + e) by 3e^2/8, below float's and double's rounding for the e of a few
 * roundings. No sqrt or division: the library's normalize guards against overflow that
 * cannot happen here, at several times the cost. */
LSQT_INLINE real3 renormalize(real3 v) { return v * (R(1.5) - R(0.5) * dot(v, v)); }

/* Direction with cosine mu to the axis n and uniform azimuth. */
LSQT_INLINE real3 direction_around(real3 n, real mu, real u)
{
    real3 t, b;
    make_frame(n, &t, &b);
    real s = safe_sqrt(R(1.0) - mu * mu);
    real2 cs = azimuth_cs(u);
    return renormalize(s * cs.x * t + s * cs.y * b + mu * n);
}

/* Direction at angle t from the unit axis n, given q = 1 - cos t (accurate near t = 0,
 * where 1 - q would lose it: sin t = sqrt(q (2 - q))), and uniform azimuth. */
LSQT_INLINE real3 direction_around_q(real3 n, real q, real u)
{
    real3 t, b;
    make_frame(n, &t, &b);
    real s = safe_sqrt(q * (R(2.0) - q));
    real2 cs = azimuth_cs(u);
    return renormalize(s * cs.x * t + s * cs.y * b + (R(1.0) - q) * n);
}
