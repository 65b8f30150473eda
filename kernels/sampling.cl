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

/* Cosine-weighted direction on the upper (+z) hemisphere; pdf = cos / pi. */
inline real3 sample_cosine_hemisphere(real u1, real u2)
{
    real r = sqrt(u1), phi = R(2.0) * LSQT_PI * u2;
    return make_real3(r * cos(phi), r * sin(phi), safe_sqrt(R(1.0) - u1));
}

/* Direction with cosine mu to the axis n and uniform azimuth. */
inline real3 direction_around(real3 n, real mu, real u)
{
    real3 t, b;
    make_frame(n, &t, &b);
    real s = safe_sqrt(R(1.0) - mu * mu), phi = R(2.0) * LSQT_PI * u;
    return normalize(s * cos(phi) * t + s * sin(phi) * b + mu * n);
}

/* Direction at angle t from the unit axis n, given q = 1 - cos t (accurate near t = 0,
 * where 1 - q would lose it: sin t = sqrt(q (2 - q))), and uniform azimuth. */
inline real3 direction_around_q(real3 n, real q, real u)
{
    real3 t, b;
    make_frame(n, &t, &b);
    real s = safe_sqrt(q * (R(2.0) - q)), phi = R(2.0) * LSQT_PI * u;
    return normalize(s * cos(phi) * t + s * sin(phi) * b + (R(1.0) - q) * n);
}
