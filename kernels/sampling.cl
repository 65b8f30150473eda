/* Direction warps and frames used by several models. */

/* Orthonormal basis around unit n (Duff et al. 2017, branchless). */
inline void make_frame(real3 n, real3 *t, real3 *b)
{
    real s = n.z >= R(0.0) ? R(1.0) : R(-1.0);
    real a = R(-1.0) / (s + n.z);
    real c = n.x * n.y * a;
    *t = make_real3(R(1.0) + s * n.x * n.x * a, s * c, -s * n.x);
    *b = make_real3(c, s + n.y * n.y * a, -n.y);
}

/* (cos, sin) of the azimuth 2 pi u, u in [0, 1): cospi and sinpi of 2u - 1 (|x| <= 1, no
 * costly reduction of a radian argument; the point is the same, rotated by pi, so the
 * signs flip back). Twice as fast as cos and sin of 2 pi u on PoCL. */
inline real2 azimuth_cs(real u)
{
    real x = R(2.0) * u - R(1.0);
    return (real2)(-cospi(x), -sinpi(x));
}

/* Cosine-weighted direction on the upper (+z) hemisphere; pdf = cos / pi. */
inline real3 sample_cosine_hemisphere(real u1, real u2)
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
inline real3 renormalize(real3 v) { return v * (R(1.5) - R(0.5) * dot(v, v)); }

/* Direction with cosine mu to the axis n and uniform azimuth. */
inline real3 direction_around(real3 n, real mu, real u)
{
    real3 t, b;
    make_frame(n, &t, &b);
    real s = safe_sqrt(R(1.0) - mu * mu);
    real2 cs = azimuth_cs(u);
    return renormalize(s * cs.x * t + s * cs.y * b + mu * n);
}

/* Direction at angle t from the unit axis n, given q = 1 - cos t (accurate near t = 0,
 * where 1 - q would lose it: sin t = sqrt(q (2 - q))), and uniform azimuth. */
inline real3 direction_around_q(real3 n, real q, real u)
{
    real3 t, b;
    make_frame(n, &t, &b);
    real s = safe_sqrt(q * (R(2.0) - q));
    real2 cs = azimuth_cs(u);
    return renormalize(s * cs.x * t + s * cs.y * b + (R(1.0) - q) * n);
}
