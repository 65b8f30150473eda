/* The point estimates users get (RAW f, 1/sr, without the cosine) against closed forms
 * that owe nothing to the program, at every incident direction of several slices.
 *
 * Conventions (walk.cl): a path starts along -wo, wo = (sin to, 0, cos to); a medium
 * vertex reached along d tallies w p(d.wi) exp(-tau_out/|wi.z|) at wi, a layer vertex
 * w bsdf(wi) (cosine included); the host divides by |wi.z|. The first scattering angle
 * has cosine dot(-wo, wi). Every layer here is index matched (no Fresnel).
 *
 * Tolerances are in standard errors (sigma, batch means over LSQT_BATCHES = 32 batches,
 * so a z-score is Student-t with 31 degrees of freedom): 5 sigma per direction (P < 2e-5
 * each; there are about a thousand of them), 4 sigma for aggregates (P < 4e-4; a few
 * dozen), plus, where stated, a bound on the model or quadrature error, added on the side
 * it can err on. */
#include "cl_fixture.h"
#include "quadrature.h"
#include "ref_media.h"

#define PI 3.14159265358979323846
#define NB LSQT_BATCHES
#define Z_DIR 5.0
#define Z_AGG 4.0

/* ---------------------------------------------------------------- helpers */


static void wi_of(const lsqt_state *st, int s, int k, double v[3])
{
    const float *p = st->wi + ((size_t)s * (size_t)st->n_wi + (size_t)k) * 4;
    v[0] = p[0];
    v[1] = p[1];
    v[2] = p[2];
}

/* Batch sums of the RAW point estimate at (s, k): nee / 2^40 / |wi.z|. */
static double batch_f(const lsqt_state *st, int s, int b, int k)
{
    const lsqt_u128 *nee = st->nee + (size_t)s * NB * (size_t)st->n_wi;
    double z = st->wi[((size_t)s * (size_t)st->n_wi + (size_t)k) * 4 + 2];
    return lsqt_u128_to_double(nee[(size_t)b * (size_t)st->n_wi + (size_t)k]) / LSQT_FIX_SCALE / fabs(z);
}

/* Ratio estimate sum(y) / sum(x) over the batches, with its batch-means standard error
 * (linearised: var = B/(B-1) sum (y_b - r x_b)^2 / (sum x)^2), as host/state/tally.c does. */
static lsqt_est batch_ratio(const double *y, const double *x)
{
    double sy = 0.0, sx = 0.0, ss = 0.0;
    for (int b = 0; b < NB; b++) {
        sy += y[b];
        sx += x[b];
    }
    lsqt_est r = {sy / sx, 0.0};
    for (int b = 0; b < NB; b++) ss += (y[b] - r.mean * x[b]) * (y[b] - r.mean * x[b]);
    r.err = sqrt(ss * NB / (NB - 1)) / sx;
    return r;
}

/* Aggregate over a set of directions: A = mean_k f_k / ref_k, from the batch sums, so its
 * error sees the (strong) correlation between directions that share paths. */
static lsqt_est mean_ratio(const lsqt_state *st, int s, const int *ks, int n, const double *ref)
{
    double y[NB], x[NB];
    for (int b = 0; b < NB; b++) {
        y[b] = 0.0;
        for (int i = 0; i < n; i++) y[b] += batch_f(st, s, b, ks[i]) / ref[ks[i]];
        y[b] /= n;
        x[b] = (double)lsqt_batch_paths(st->paths, b);
    }
    return batch_ratio(y, x);
}

/* ------------------------------------------- 1. single scattering, thin slab */

/* Multiple scattering in a slab of thickness 1, mut = tau, entered along -wo, is
 * bounded from the chance of each further collision. A path scattered once towards d
 * collides again with chance 1 - exp(-tau l(t, d)), l the distance to the boundary from
 * the first collision at depth t; that is concave in t (l is linear in t), and t is
 * independent of d, so by Jensen its mean is at most m(d) = 1 - exp(-tau l(E[t], d)).
 * From anywhere in the slab, a path going along d' collides with chance at most
 * m2(d') = 1 - exp(-tau/|d'.z|), so a path that scattered along d collides once more with
 * chance at most q(d) = int p(d.d') m2(d') dd' (a function of |d.z|). With p1(d) =
 * p(-wo.d) and P1 the chance of a first collision, the point estimate at wi gets
 *   from 2nd collisions <= om^2 P1 J,  J = int p1(d) m(d) p(d.wi) dd,
 *   from later ones     <= om^3 pmax P1 Q3 / (1 - qsup),  Q3 = int p1(d) m(d) q(d) dd
 * (their weight is <= om^3, their phase value <= pmax, and their expected number is at
 * most P1 Q3 (1 + qsup + qsup^2 + ...), qsup = sup q). The unit sphere is integrated with
 * |d.z| on panels graded towards the horizon (m and m2 have boundary layers there) and
 * the periodic trapezoid rule in azimuth; J, q and Q3 are raised by 10% for that
 * quadrature (doubling every node count changes them by < 1e-5). At tau = 1e-2 the
 * observed excess of f over the single-scattering value stays below these bounds in every
 * case (2.9% against 3.4% for g = 0, om = 1), and the bounds are nearly tight for g <= 0. */

static ms_grid ms_g; /* large: static */

static void test_single_scattering(void)
{
    /* tau = 1e-3: twice-scattered light is O(tau ln(1/tau)) ~ 0.5% of the single for
     * g = 0 (it is ~3% at tau = 0.01, the size of the errors this must see). Paths that
     * pass unscattered cost almost nothing, so 2^22 per slice give ~4000 collisions. */
    const double tau = 1e-3, gs[] = {-0.5, 0.0, 0.8}, omegas[] = {0.5, 1.0};
    const double deg[] = {0, 40, 70};
    enum { NS = 3, NWI = 64 };
    const uint64_t paths = (uint64_t)1 << 22;
    int run = 0;
    for (int ig = 0; ig < 3; ig++) {
        for (int io = 0; io < 2; io++, run++) {
            const double g = gs[ig], om = omegas[io];
            char text[256];
            snprintf(text, sizeof text,
                     "Medium\nLayer z=1 NullBsdf\nMedium mus=%.17g mua=%.17g HenyeyGreensteinPhase g=%g\n"
                     "Layer z=0 NullBsdf\nMedium\n",
                     om * tau, (1.0 - om) * tau, g);
            lsqt_state st;
            lsqt_slice_est *e = fixture_run(text, NS, deg, NWI, paths, 100 + (uint64_t)run, &st);
            CHECK(st.transmits && st.n_wi == NWI, "run %d: expected a transmitting slab", run);
            const double pmax = hg(fabs(g), 1.0);
            if (io == 0) ms_grid_init(&ms_g, g, tau);
            CHECK(ms_g.qsup < 0.5, "q bound %g", ms_g.qsup);
            for (int s = 0; s < NS; s++) {
                const double muo = cos(st.theta_o[s]), so = sin(st.theta_o[s]);
                const double p1 = -expm1(-tau / muo); /* chance of a first collision */
                double wi[NWI][3], ref[NWI], bnd[NWI], J[NWI], Q3;
                for (int k = 0; k < NWI; k++) wi_of(&st, s, k, wi[k]);
                ms_integrals(&ms_g, muo, (const double(*)[3])wi, NWI, J, &Q3);
                const double e3 = om * om * om * pmax * p1 * Q3 / (1.0 - ms_g.qsup);
                double rel_ms = 0.0;
                for (int k = 0; k < NWI; k++) {
                    const double mui = fabs(wi[k][2]), c = -so * wi[k][0] - muo * wi[k][2];
                    /* Collision density (tau/muo) e^{-tau t/muo} over depth t in [0, 1]; albedo
                     * om; exit transmittance e^{-tau t/mui} (up) or e^{-tau (1-t)/mui} (down):
                     *   R: f mui = om p (tau/muo) phi1(tau (1/muo + 1/mui)),
                     *   T: f mui = om p (tau/muo) e^{-tau/mui} phi1(tau (1/muo - 1/mui)),
                     * phi1(x) = (1 - e^-x)/x, i.e. om p (e^{-tau/mui} - e^{-tau/muo})/(mui - muo)
                     * for T, without its 0/0 at mui = muo. */
                    double a = wi[k][2] > 0 ? phi1(tau * (1.0 / muo + 1.0 / mui))
                                            : exp(-tau / mui) * phi1(tau * (1.0 / muo - 1.0 / mui));
                    ref[k] = om * hg(g, c) * tau / (muo * mui) * a;
                    bnd[k] = (om * om * p1 * J[k] + e3) / mui; /* multiple scattering adds, >= 0 */
                    rel_ms = fmax(rel_ms, bnd[k] / ref[k]);
                    double d = e[s].f[k].mean - ref[k], sg = e[s].f[k].err;
                    CHECK(sg > 0 && d >= -Z_DIR * sg && d <= Z_DIR * sg + bnd[k],
                          "single scattering g=%g om=%g to=%g wi.z=%.3f: f %.6g +- %.2g, ref %.6g (+%.2g): z=%.2f",
                          g, om, deg[s], wi[k][2], e[s].f[k].mean, sg, ref[k], bnd[k], d / sg);
                }
                /* Unscattered light: exp(-tau/muo) exactly (an analog estimate). */
                CHECK_Z(e[s].delta_T.mean, exp(-tau / muo), e[s].delta_T.err, Z_AGG);
                /* Aggregates over each hemisphere. Directions share their collisions, so
                 * the noise of f is mostly the common count of first collisions (~1.5%).
                 * (i) A = mean f/ref, absolute; (ii) the same sum times p1, over the
                 * number of paths that collided (those not in delta_T, whose weight is
                 * exactly 1) instead of all paths: the count's noise cancels and what is
                 * left checks the value tallied per collision, om p e^{-tau_out/mui}, to
                 * ~0.1%. Both lie in [1, 1 + mean bound/ref] up to noise. */
                const lsqt_u128 *sc = st.scalars + (size_t)s * NB * LSQT_T_COUNT;
                for (int up = 0; up <= 1; up++) {
                    int ks[NWI], n = 0;
                    double bmean = 0.0;
                    for (int k = 0; k < NWI; k++)
                        if ((wi[k][2] > 0) == up) {
                            ks[n++] = k;
                            bmean += bnd[k] / ref[k];
                        }
                    bmean /= n;
                    lsqt_est A = mean_ratio(&st, s, ks, n, ref);
                    double y[NB], x[NB];
                    for (int b = 0; b < NB; b++) {
                        y[b] = 0.0;
                        for (int i = 0; i < n; i++) y[b] += batch_f(&st, s, b, ks[i]) / ref[ks[i]];
                        y[b] *= p1 / n;
                        x[b] = (double)lsqt_batch_paths(st.paths, b) -
                               lsqt_u128_to_double(sc[(size_t)b * LSQT_T_COUNT + LSQT_T_DELTA_T]) / LSQT_FIX_SCALE;
                    }
                    lsqt_est C = batch_ratio(y, x);
                    const char *h = up ? "R" : "T";
                    CHECK(A.mean - 1 >= -Z_AGG * A.err && A.mean - 1 <= Z_AGG * A.err + bmean,
                          "single scattering g=%g om=%g to=%g %s: mean f/ref = %.5f +- %.2g (ms bound %.2g)", g,
                          om, deg[s], h, A.mean, A.err, bmean);
                    CHECK(C.mean - 1 >= -Z_AGG * C.err && C.mean - 1 <= Z_AGG * C.err + bmean,
                          "single scattering g=%g om=%g to=%g %s: per collision f/ref = %.5f +- %.2g (ms bound "
                          "%.2g)",
                          g, om, deg[s], h, C.mean, C.err, bmean);
                    printf("  single g=%4.1f om=%.1f to=%2.0f %s: mean f/ref %.5f +- %.5f, per collision %.5f "
                           "+- %.5f, ms bound <= %.4f (max %.3f)\n",
                           g, om, deg[s], h, A.mean, A.err, C.mean, C.err, bmean, rel_ms);
                }
            }
            CHECK(st.flags == 0, "flags %u", st.flags);
            lsqt_estimates_free(e, NS);
            lsqt_state_free(&st);
        }
    }
}

/* ---------------------------------- 2. semi-infinite isotropic (Chandrasekhar) */

/* H by h_solve / h_eval (ref_media.h) */
static double h_moment(const hfun *H, int k)
{
    double m = 0.0;
    for (int i = 0; i < H->n; i++) m += H->w[i] * pow(H->x[i], k) * H->h[i];
    return m;
}

static hfun hf_a, hf_b; /* large: static */

static void test_h_function(void)
{
    /* Conservative scattering, against Chandrasekhar's tabulated H(1) = 2.90781 and the
     * moments int H = 2 and int H mu = 2/sqrt(3) that hold for om = 1 (Radiative
     * Transfer, ch. V). A check of the method, not of the program. */
    int it = h_solve(&hf_a, 1.0, 16);
    CHECK(it > 0, "H(om=1) did not converge");
    CHECK(fabs(h_eval(&hf_a, 1.0) - 2.90781) < 2e-5, "H(1) = %.7f for om = 1", h_eval(&hf_a, 1.0));
    CHECK(fabs(h_moment(&hf_a, 0) - 2.0) < 1e-5, "int H = %.8f for om = 1", h_moment(&hf_a, 0));
    CHECK(fabs(h_moment(&hf_a, 1) - 2.0 / sqrt(3.0)) < 1e-5, "int H mu = %.8f for om = 1", h_moment(&hf_a, 1));
    printf("  H(om=1): %d iterations, H(1) = %.6f, int H = %.8f, int H mu = %.8f\n", it, h_eval(&hf_a, 1.0),
           h_moment(&hf_a, 0), h_moment(&hf_a, 1));
}

static void test_semi_infinite(void)
{
    const double omegas[] = {0.5, 0.9, 0.99}, deg[] = {0, 40, 70};
    /* omega = 0.99 paths scatter ~100 times: fewer of them */
    const uint64_t paths[] = {(uint64_t)1 << 16, (uint64_t)1 << 16, (uint64_t)1 << 15};
    enum { NS = 3, NWI = 48 };
    for (int io = 0; io < 3; io++) {
        const double om = omegas[io];
        /* H to quadrature precision: 16 and 32 nodes per panel agree to < 1e-9 relative,
         * and int H = (2/om)(1 - sqrt(1 - om)) (the zeroth moment of the H equation). */
        CHECK(h_solve(&hf_a, om, 16) > 0 && h_solve(&hf_b, om, 32) > 0, "H(om=%g) did not converge", om);
        double hdiff = 0.0;
        for (int i = 0; i <= 100; i++) {
            double mu = i / 100.0;
            hdiff = fmax(hdiff, fabs(h_eval(&hf_a, mu) / h_eval(&hf_b, mu) - 1.0));
        }
        CHECK(hdiff < 1e-9, "H(om=%g): quadratures differ by %.3g", om, hdiff);
        double m0 = 2.0 / om * (1.0 - sqrt(1.0 - om));
        CHECK(fabs(h_moment(&hf_b, 0) - m0) < 1e-9, "int H = %.10f, expected %.10f (om=%g)", h_moment(&hf_b, 0), m0,
              om);

        /* tau = 100 of a medium with mut = 1: "semi-infinite" (checked below: T ~ 0). */
        char text[256];
        snprintf(text, sizeof text,
                 "Medium\nLayer z=100 NullBsdf\nMedium mus=%.17g mua=%.17g HenyeyGreensteinPhase g=0\n"
                 "Layer z=0 NullBsdf\nMedium\n",
                 om, 1.0 - om);
        lsqt_state st;
        lsqt_slice_est *e = fixture_run(text, NS, deg, NWI, paths[io], 200 + (uint64_t)io, &st);
        for (int s = 0; s < NS; s++) {
            const double muo = cos(st.theta_o[s]), ho = h_eval(&hf_b, muo);
            /* Light that reaches the bottom (T) is all that the finite slab misses of a
             * half space; what a half space would return of it is less: T/R bounds the
             * relative model error (here it is 0 to double precision). */
            CHECK(e[s].T.mean < 1e-4, "om=%g slice %d: T = %.3g, not semi-infinite", om, s, e[s].T.mean);
            const double model = (e[s].T.mean + 3 * e[s].T.err) / e[s].R.mean + 1e-6; /* + H */
            double ref[NWI];
            int ks[NWI], n = 0;
            double zmax = 0.0;
            for (int k = 0; k < NWI; k++) {
                double wi[3];
                wi_of(&st, s, k, wi);
                if (wi[2] <= 0) {
                    ref[k] = 1.0;
                    continue;
                }
                /* f = om/(4 pi) H(muo) H(mui) / (muo + mui): Chandrasekhar's reflected
                 * intensity I = F om/4 muo/(muo + mui) H H for incident flux pi F per unit
                 * area normal to the beam, over the irradiance pi F muo. With H = 1 it is
                 * the single-scattering limit om p/(muo + mui) of section 1. */
                ref[k] = om / (4.0 * PI) * ho * h_eval(&hf_b, wi[2]) / (muo + wi[2]);
                ks[n++] = k;
                double d = e[s].f[k].mean - ref[k], sg = e[s].f[k].err;
                zmax = fmax(zmax, fabs(d) / sg);
                CHECK(sg > 0 && fabs(d) <= Z_DIR * sg + model * ref[k],
                      "semi-infinite om=%g to=%g wi.z=%.3f: f %.6g +- %.2g vs %.6g: z = %.2f", om, deg[s], wi[2],
                      e[s].f[k].mean, sg, ref[k], d / sg);
            }
            lsqt_est A = mean_ratio(&st, s, ks, n, ref);
            CHECK(fabs(A.mean - 1.0) <= Z_AGG * A.err + model, "semi-infinite om=%g to=%g: mean f/ref %.5f +- %.2g",
                  om, deg[s], A.mean, A.err);
            printf("  semi-infinite om=%.2f to=%2.0f: mean f/ref %.5f +- %.5f, max |z| %.2f, R %.5f, T %.2g\n", om,
                   deg[s], A.mean, A.err, zmax, e[s].R.mean, e[s].T.mean);
        }
        CHECK(st.flags == 0, "flags %u", st.flags);
        lsqt_estimates_free(e, NS);
        lsqt_state_free(&st);
    }
}

/* ------------------------------------- 3. clear absorber over a Lambertian */

static void test_absorber_lambertian(void)
{
    /* The way in is analog (a path survives tau/muo with chance e^{-tau/muo}) and the same
     * for every wi; the way out is the next-event transmittance. So
     * f(wi) = fR/pi e^{-tau/muo} e^{-tau/mui}, and f e^{tau/mui} is one number for all wi:
     * every surviving path arrives with weight 1 and adds round(v 2^40) to direction k,
     * v = fR mui/pi e^{-tau/mui} in float. Its relative error is at most 2^-41/v (fixed
     * point) plus a few float roundings: fR mui/pi (3), 1/mui (1, times the exponent
     * x = tau/mui), exp (<= 3 ulp by OpenCL), f*t (1); allowed: twice that. */
    const double deg[] = {0, 45, 75}, fr = 0.5, tau = 1.0;
    enum { NS = 3, NWI = 64 };
    lsqt_state st;
    lsqt_slice_est *e = fixture_run("Medium\nLayer z=1 NullBsdf\nMedium mua=1\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n",
                                    NS, deg, NWI, (uint64_t)1 << 16, 300, &st);
    CHECK(!st.transmits, "an opaque floor does not transmit");
    const double eps = ldexp(1.0, -24);
    for (int s = 0; s < NS; s++) {
        const double muo = cos(st.theta_o[s]);
        int kb = 0; /* the most precise direction: largest mui */
        double scaled[NWI], tol[NWI];
        for (int k = 0; k < NWI; k++) {
            double wi[3];
            wi_of(&st, s, k, wi);
            const double x = tau / wi[2], v = fr * wi[2] / PI * exp(-x);
            scaled[k] = e[s].f[k].mean * exp(x);
            tol[k] = v * LSQT_FIX_SCALE >= 1.0 ? 2.0 * ((0.5 / LSQT_FIX_SCALE) / v + (8.0 + x) * eps) : -1.0;
            if (wi[2] > st.wi[((size_t)s * NWI + (size_t)kb) * 4 + 2]) kb = k;
        }
        int used = 0;
        double spread = 0.0, spread_fine = 0.0; /* all, and where tol < 1e-5 */
        for (int k = 0; k < NWI; k++) {
            if (tol[k] < 0) continue; /* below one fixed-point unit: rounds to nothing */
            used++;
            double r = scaled[k] / scaled[kb] - 1.0;
            spread = fmax(spread, fabs(r));
            if (tol[k] < 1e-5) spread_fine = fmax(spread_fine, fabs(r));
            CHECK(fabs(r) <= tol[k] + tol[kb], "absorber to=%g wi.z=%.3f: f e^{tau/mui} differs by %.3g (allowed %.2g)",
                  deg[s], st.wi[((size_t)s * NWI + (size_t)k) * 4 + 2], r, tol[k] + tol[kb]);
        }
        CHECK(used >= NWI / 2, "only %d directions above the fixed-point floor", used);
        const double want = fr / PI * exp(-tau / muo);
        CHECK_Z(scaled[kb], want, e[s].f[kb].err * exp(tau / st.wi[((size_t)s * NWI + (size_t)kb) * 4 + 2]), Z_AGG);
        printf("  absorber to=%2.0f: f e^{tau/mui} spread %.2g over %d directions (%.2g where float-limited), %.6f vs "
               "fR/pi e^{-tau/muo} %.6f\n",
               deg[s], spread, used, spread_fine, scaled[kb], want);
    }
    lsqt_estimates_free(e, NS);
    lsqt_state_free(&st);
}

/* ------------------------------- 4. which vertices may see the outside */

/* A Lambertian that every exit on one side crosses last makes f there a constant: the
 * point estimates on that side come only from that layer, w fT |cos|/pi per arrival, and
 * every weight here is 1 (no absorption, fR + fT = 1), so f = (arrivals/N) fT/pi in every
 * direction, to fixed-point and float rounding: 2^-41 pi/mui + a few 2^-24 < 1e-6 for
 * mui >= 1/64. A next-event estimate from the medium on the wrong side of the layer would
 * add light with the phase function's shape. */
/* E3(tau) = integral over mu in (0, 1] of mu exp(-tau / mu): the cosine-weighted
 * hemispherical transmittance of a clear layer of optical thickness tau, over 2 pi. */

/* Light leaves on one side only through a Lambertian layer and then, optionally, a clear
 * absorber of optical thickness tau (so there are media on both sides of the layer). The
 * exact RAW on that side is then C exp(-tau / mu_i): f exp(tau / mu_i) is the same at
 * every direction, and its hemispherical integral 2 pi E3(tau) C is the analog R or T. */
static void check_constant_side(const char *what, const char *text, int upper, double fT, double tau, uint64_t seed)
{
    const double deg[] = {0, 50, 80};
    enum { NS = 3, NWI = 64 };
    lsqt_state st;
    lsqt_slice_est *e = fixture_run(text, NS, deg, NWI, (uint64_t)1 << 16, seed, &st);
    CHECK(st.transmits, "%s: expected a transmitting stack", what);
    for (int s = 0; s < NS; s++) {
        int k0 = -1, n = 0;
        double spread = 0.0, c0 = 0.0;
        for (int k = 0; k < NWI; k++) {
            double wi[3];
            wi_of(&st, s, k, wi);
            if ((wi[2] > 0) != upper) continue;
            /* A contribution is at least 0.25 fT |mu| exp(-tau/mu) / pi (roulette keeps
             * weights >= 0.25): where that is below 1e-3, fixed-point rounding (2^-41
             * each) could exceed 5e-7 relative, so such grazing directions are left out. */
            double mu = fabs(wi[2]), vmin = 0.25 * fT * mu * exp(-tau / mu) / PI;
            if (vmin < 1e-3) continue;
            double c = e[s].f[k].mean * exp(tau / mu);
            n++;
            if (k0 < 0) k0 = k, c0 = c;
            double r = c / c0 - 1.0;
            spread = fmax(spread, fabs(r));
            /* float rounding of the value and of exp(-tau/mu) on the device, and the
             * fixed-point rounding bound */
            double tol = 1e-6 + (8.0 + tau / mu) * ldexp(1.0, -24) + (0.5 / LSQT_FIX_SCALE) / vmin;
            CHECK(fabs(r) <= tol, "%s to=%g wi.z=%.3f: f exp(tau/mu) %.9g differs from %.9g by %.3g", what, deg[s],
                  wi[2], c, c0, r);
        }
        CHECK(n >= 16, "%s: only %d directions checked", what, n);
        /* The layer passes fT of what arrives; what passes is the analog R or T (for
         * fT = 1 exactly the same paths, else a binomial split of them): 2 pi E3(tau) C
         * = R or T within the sum of the two errors (they are positively correlated). */
        const lsqt_est *x = upper ? &e[s].R : &e[s].T;
        const double k_int = 2 * PI * e3(tau), c_err = e[s].f[k0].err * c0 / e[s].f[k0].mean;
        CHECK_Z(c0 * k_int, x->mean, x->err + k_int * c_err, Z_AGG);
        printf("  %s to=%2.0f: f exp(tau/mu) spread %.2g over %d directions, 2 pi E3 C %.6f vs %s %.6f +- %.2g\n",
               what, deg[s], spread, n, c0 * k_int, upper ? "R" : "T", x->mean, x->err);
    }
    lsqt_estimates_free(e, NS);
    lsqt_state_free(&st);
}

static void test_visibility(void)
{
    CHECK(fabs(e3(0) - 0.5) < 1e-12 && fabs(e3(1) - 0.1096) < 1e-4, "E3: %.6f %.6f", e3(0), e3(1));
    /* Upward exits all cross the top Lambertian (fT = 1) last: the medium below it must
     * not estimate upwards. */
    check_constant_side("top Lambertian",
                        "Medium\nLayer z=1 LambertianBsdf fR=0 fT=1\nMedium mus=2 HenyeyGreensteinPhase g=0.5\n"
                        "Layer z=0 NullBsdf\nMedium\n",
                        1, 1.0, 0.0, 400);
    /* Downward exits all cross the bottom Lambertian last: the medium above it must not
     * estimate downwards. */
    check_constant_side("bottom Lambertian",
                        "Medium\nLayer z=1 NullBsdf\nMedium mus=2 HenyeyGreensteinPhase g=0.5\n"
                        "Layer z=0 LambertianBsdf fR=0.3 fT=0.7\nMedium\n",
                        0, 0.7, 0.0, 401);
    /* Media on both sides of the Lambertian: a scatterer on the far side, a clear
     * absorber (tau 0.5) on the exit side, which may estimate outwards (nothing to
     * estimate: it does not scatter) while the scatterer must not. */
    check_constant_side("top Lambertian, media both sides",
                        "Medium\nLayer z=2 NullBsdf\nMedium mua=0.5\nLayer z=1 LambertianBsdf fR=0 fT=1\n"
                        "Medium mus=2 HenyeyGreensteinPhase g=0.5\nLayer z=0 NullBsdf\nMedium\n",
                        1, 1.0, 0.5, 402);
    check_constant_side("bottom Lambertian, media both sides",
                        "Medium\nLayer z=2 NullBsdf\nMedium mus=2 HenyeyGreensteinPhase g=0.5\n"
                        "Layer z=1 LambertianBsdf fR=0.3 fT=0.7\nMedium mua=0.5\nLayer z=0 NullBsdf\nMedium\n",
                        0, 0.7, 0.5, 403);
}

int main(void)
{
    fixture_open();
    test_h_function();
    test_single_scattering();
    test_semi_infinite();
    test_absorber_lambertian();
    test_visibility();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_references");
}
