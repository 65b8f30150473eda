/* Power tests of media: enough paths to see a 1 % systematic error in two
 * regimes that the other tests reach only weakly.
 *
 *   test_power_media double    media walks in --double (LSQT_DOUBLE kernels) against
 *                              closed forms: a clear absorber's analog transmission
 *                              exp(-tau/muo) (free flights), a clear absorber over a
 *                              Lambertian (exact point estimates, 2 E3 analog R), single
 *                              scattering of thin HG slabs per collision (phase values),
 *                              a semi-infinite isotropic medium against Chandrasekhar's H
 *                              (the medium's next-event transmittance).
 *   test_power_media grazing   point estimates at theta_i = 89, 89.5, 89.9 degrees (above
 *                              and below the horizon, three azimuths) through media, float:
 *                              thin HG slabs' single scattering per collision, clear
 *                              absorbers around a Lambertian (exact), H for a semi-infinite
 *                              isotropic medium.
 *
 * Conventions as tests/test_references.c (whose closed forms these are, here at other
 * precisions and angles): a path enters along -wo, wo = (sin to, 0, cos to); RAW f is the
 * tallied value over |wi.z|. Statistical checks are z-scores with batch-means errors over
 * LSQT_BATCHES = 32 batches (Student t, 31 degrees of freedom); each section is one
 * family: its thresholds are the t quantiles of two-sided tail 5e-4 / (the number of
 * checks of single directions) for those, and 5e-4 / (the number of aggregates) for the
 * aggregates, so an unmodified code fails a section by chance with probability <= 1e-3.
 * Checks of exact identities (float or double rounding only) are not in the family.
 * `test_power_media SECTION N` adds N to every seed (to check that the tolerances hold).
 *
 * Detectable effects (planted in the kernels, tools/mutate/mutations.txt): double: free
 * flights 0.5 % too long, uniforms scaled by 0.998, HG values +-0.25 %, the medium's
 * next-event exponent 1 % high (0.5 % is missed); grazing: a medium next-event error of
 * 0.66 % at 89.9 degrees (0.16 % is missed), any change of the layers' next-event
 * transmittance above float rounding (1e-6). */
#include "family_stats.h"
#include "quadrature.h"
#include "ref_media.h"

/* The grazing set: theta_i = 89, 89.5, 89.9 degrees at azimuths 0, 90, 180 (relative to
 * wo's), above the horizon and (for a transmitting stack) below it, then theta_i = 0 and
 * 60 (at azimuth 45) on each side, as anchors. Returns the count. */
enum { NWI_GRAZE = 22 };
static int grazing_dirs(int transmits, double (*d)[3])
{
    static const double th[] = {89.0, 89.5, 89.9}, ph[] = {0.0, 90.0, 180.0};
    int n = 0;
    for (int side = 0; side < (transmits ? 2 : 1); side++) {
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++, n++) {
                const double t = th[i] * PI / 180.0, p = ph[j] * PI / 180.0;
                d[n][0] = sin(t) * cos(p), d[n][1] = sin(t) * sin(p), d[n][2] = side ? -cos(t) : cos(t);
            }
        for (int i = 0; i < 2; i++, n++) {
            const double t = (i ? 60.0 : 0.0) * PI / 180.0, p = PI / 4;
            d[n][0] = sin(t) * cos(p), d[n][1] = sin(t) * sin(p), d[n][2] = side ? -cos(t) : cos(t);
        }
    }
    return n;
}

/* ------------------------------------------ multiple-scattering bound (thin slab) */

/* ms_grid, ms_integrals (ref_media.h; derived in tests/test_references.c, section 1): a
 * bound on what second and later collisions add to the point estimate at wi of a slab of
 * thickness 1, mut = tau, entered along -wo. */
static ms_grid ms_g;

/* Thin HG slab (thickness 1, mut = tau, albedo om): per direction, the value tallied per
 * collision, C_k = (sum f_k / ref_k) p1 / (paths that collided), where ref_k is the
 * single-scattering closed form and p1 = 1 - exp(-tau/muo). Paths that collided are
 * those not in delta_T (weight exactly 1 each), so the count's noise cancels: C_k checks
 * the phase value, the albedo and the exit transmittance per collision. It lies in
 * [1, 1 + bound_k/ref_k] up to noise. Also the absolute mean over each hemisphere, A
 * (the collision count: free flights), and delta_T = exp(-tau/muo) (analog).
 * count_only: only count the checks (n_dir, n_agg). */
static void thin_slab(const char *what, double g, double om, double tau, int ns, const double *deg, int nwi,
                     const double (*dirs)[3], uint64_t paths, uint64_t seed, int use_double, int count_only)
{
    lsqt_state st;
    lsqt_slice_est *e = NULL;
    char text[256];
    snprintf(text, sizeof text,
             "Medium\nLayer z=1 NullBsdf\nMedium mus=%.17g mua=%.17g HenyeyGreensteinPhase g=%.17g\n"
             "Layer z=0 NullBsdf\nMedium\n",
             om * tau, (1.0 - om) * tau, g);
    if (!count_only) {
        e = run_dirs(text, ns, deg, nwi, dirs, paths, seed, use_double, &st);
        CHECK(st.transmits && st.n_wi == nwi, "%s: expected a transmitting slab", what);
        ms_grid_init(&ms_g, g, tau);
        CHECK(ms_g.qsup < 0.5, "q bound %g", ms_g.qsup);
    }
    const double pmax = hg(fabs(g), 1.0);
    for (int s = 0; s < ns; s++) {
        /* C_k per direction; A and C per hemisphere, C over its grazing directions, delta_T */
        n_dir += nwi, n_agg += 2 + 2 + 2 + 1;
        if (count_only) continue;
        const double muo = cos(st.theta_o[s]), so = sin(st.theta_o[s]);
        const double p1 = -expm1(-tau / muo);
        double wi[128][3], ref[128], bnd[128], J[128], Q3, dcol[NB];
        for (int k = 0; k < nwi; k++) wi_of(&st, s, k, wi[k]);
        ms_integrals(&ms_g, muo, (const double(*)[3])wi, nwi, J, &Q3);
        const double e3b = om * om * om * pmax * p1 * Q3 / (1.0 - ms_g.qsup);
        for (int b = 0; b < NB; b++)
            dcol[b] = (double)lsqt_batch_paths(st.paths, b) - batch_scalar(&st, s, b, LSQT_T_DELTA_T);
        double cmin = 1e9, cmax = -1e9, errmax = 0.0;
        for (int k = 0; k < nwi; k++) {
            const double mui = fabs(wi[k][2]), c = -so * wi[k][0] - muo * wi[k][2];
            double a = wi[k][2] > 0 ? phi1(tau * (1.0 / muo + 1.0 / mui))
                                    : exp(-tau / mui) * phi1(tau * (1.0 / muo - 1.0 / mui));
            ref[k] = om * hg(g, c) * tau / (muo * mui) * a;
            bnd[k] = (om * om * p1 * J[k] + e3b) / mui;
            int one[1] = {k};
            lsqt_est C = ratio_over(&st, s, one, 1, ref, dcol, p1);
            const double rb = bnd[k] / ref[k];
            CHECK(C.err > 0 && C.mean - 1 >= -ZD * C.err && C.mean - 1 <= ZD * C.err + rb,
                  "%s to=%g wi=(%.4f %.4f %.5f): per collision f/ref %.6f +- %.2g (ms bound %.2g), z=%.2f", what,
                  deg[s], wi[k][0], wi[k][1], wi[k][2], C.mean, C.err, rb, (C.mean - 1) / C.err);
            cmin = fmin(cmin, C.mean - 1), cmax = fmax(cmax, C.mean - 1 - rb), errmax = fmax(errmax, C.err);
        }
        for (int up = 0; up <= 1; up++) {
            int ks[128], n = 0;
            double bmean = 0.0;
            for (int k = 0; k < nwi; k++)
                if ((wi[k][2] > 0) == up) ks[n++] = k, bmean += bnd[k] / ref[k];
            if (!n) continue;
            bmean /= n;
            lsqt_est A = ratio_over(&st, s, ks, n, ref, NULL, 1.0), C = ratio_over(&st, s, ks, n, ref, dcol, p1);
            CHECK(A.mean - 1 >= -ZA * A.err && A.mean - 1 <= ZA * A.err + bmean,
                  "%s to=%g %s: mean f/ref %.5f +- %.2g (ms bound %.2g)", what, deg[s], up ? "R" : "T", A.mean,
                  A.err, bmean);
            CHECK(C.mean - 1 >= -ZA * C.err && C.mean - 1 <= ZA * C.err + bmean,
                  "%s to=%g %s: per collision mean f/ref %.5f +- %.2g (ms bound %.2g)", what, deg[s],
                  up ? "R" : "T", C.mean, C.err, bmean);
            printf("  %s to=%4.1f %s: mean f/ref %.5f +- %.5f, per collision %.5f +- %.5f (ms bound %.5f)\n", what,
                   deg[s], up ? "R" : "T", A.mean, A.err, C.mean, C.err, bmean);
            /* the same over the grazing directions (|wi.z| < 0.02) alone */
            int kg[128], ng = 0;
            double bg = 0.0;
            for (int i = 0; i < n; i++)
                if (fabs(wi[ks[i]][2]) < 0.02) kg[ng++] = ks[i], bg += bnd[ks[i]] / ref[ks[i]];
            if (!ng) continue;
            bg /= ng;
            lsqt_est G = ratio_over(&st, s, kg, ng, ref, dcol, p1);
            CHECK(G.mean - 1 >= -ZA * G.err && G.mean - 1 <= ZA * G.err + bg,
                  "%s to=%g %s: per collision mean f/ref over %d grazing directions %.5f +- %.2g (ms bound %.2g)",
                  what, deg[s], up ? "R" : "T", ng, G.mean, G.err, bg);
            printf("  %s to=%4.1f %s: per collision over %d grazing directions %.5f +- %.5f (ms bound %.5f)\n",
                   what, deg[s], up ? "R" : "T", ng, G.mean, G.err, bg);
        }
        CHECK_Z(e[s].delta_T.mean, exp(-tau / muo), e[s].delta_T.err, ZA);
        printf("  %s to=%4.1f: per collision f/ref - 1 in [%.2e, %.2e] beyond the ms bound, largest err %.2e; "
               "delta_T/exp(-tau/muo) %.5f +- %.5f\n",
               what, deg[s], cmin, cmax, errmax, e[s].delta_T.mean / exp(-tau / muo),
               e[s].delta_T.err / exp(-tau / muo));
    }
    if (!count_only) {
        lsqt_estimates_free(e, ns);
        lsqt_state_free(&st);
    }
}

/* ------------------------------------------------ clear absorber, analog */

/* A clear absorber (mua only) between null layers: no path scatters, T = delta_T =
 * exp(-tau/muo) exactly (a binomial): the free-flight lengths themselves. */
static void clear_slab(double tau, int ns, const double *deg, uint64_t paths, uint64_t seed, int use_double,
                      int count_only)
{
    if (count_only) {
        n_agg += ns;
        return;
    }
    char text[256];
    snprintf(text, sizeof text, "Medium\nLayer z=1 NullBsdf\nMedium mua=%.17g\nLayer z=0 NullBsdf\nMedium\n", tau);
    lsqt_state st;
    lsqt_slice_est *e = run_dirs(text, ns, deg, 16, NULL, paths, seed, use_double, &st);
    for (int s = 0; s < ns; s++) {
        const double want = exp(-tau / cos(st.theta_o[s]));
        CHECK_Z(e[s].delta_T.mean, want, e[s].delta_T.err, ZA);
        CHECK(e[s].R.mean == 0 && e[s].T.mean == e[s].delta_T.mean, "clear slab: R %g T %g", e[s].R.mean, e[s].T.mean);
        printf("  clear slab tau=%g to=%4.1f: T/exp(-tau/muo) = %.5f +- %.5f\n", tau, deg[s], e[s].delta_T.mean / want,
               e[s].delta_T.err / want);
    }
    lsqt_estimates_free(e, ns);
    lsqt_state_free(&st);
}

/* -------------------------------------- clear absorbers around a Lambertian */

/* Clear absorbers (optical thickness tau1 above, tau2 below) around a Lambertian layer
 * (fR, fT): every surviving path reaches the layer with weight 1, so
 *   f(wi) = fR/pi e^{-tau1/muo} e^{-tau1/mui} above, fT/pi e^{-tau1/muo} e^{-tau2/|mui|} below,
 * and f e^{tau/|mui|} (tau of the side) / f_side is one number for all wi of a side, to the
 * rounding of the device's precision (eps per operation) and of the fixed point. Plus,
 * statistically, that number against fR/pi e^{-tau1/muo} (the analog way in) and the
 * analog R against fR e^{-tau1/muo} 2 E3(tau1) (the analog way out). */
static void absorber_lambertian(const char *what, double tau1, double tau2, double fr, double ft, int ns,
                               const double *deg, int nwi, const double (*dirs)[3], uint64_t paths, uint64_t seed,
                               int use_double, int count_only)
{
    const int transmits = ft > 0;
    if (count_only) {
        n_agg += ns * (transmits ? 4 : 2);
        return;
    }
    char text[512];
    if (transmits)
        snprintf(text, sizeof text,
                 "Medium\nLayer z=2 NullBsdf\nMedium mua=%.17g\nLayer z=1 LambertianBsdf fR=%.17g fT=%.17g\n"
                 "Medium mua=%.17g\nLayer z=0 NullBsdf\nMedium\n",
                 tau1, fr, ft, tau2);
    else
        snprintf(text, sizeof text, "Medium\nLayer z=1 NullBsdf\nMedium mua=%.17g\nLayer z=0 LambertianBsdf fR=%.17g\nMedium\n",
                 tau1, fr);
    lsqt_state st;
    lsqt_slice_est *e = run_dirs(text, ns, deg, nwi, dirs, paths, seed, use_double, &st);
    CHECK(st.transmits == transmits, "%s: transmits %d", what, st.transmits);
    const double eps = use_double ? ldexp(1.0, -53) : ldexp(1.0, -24);
    for (int s = 0; s < ns; s++) {
        const double muo = cos(st.theta_o[s]);
        for (int up = 1; up >= (transmits ? 0 : 1); up--) {
            const double tau = up ? tau1 : tau2, fx = up ? fr : ft;
            int kb = -1, used = 0;
            double scaled[128], tol[128], spread = 0.0, spread_graze = 0.0;
            for (int k = 0; k < nwi; k++) {
                double wi[3];
                wi_of(&st, s, k, wi);
                tol[k] = -1.0;
                if ((wi[2] > 0) != up) continue;
                const double mui = fabs(wi[2]), x = tau / mui, v = fx * mui / PI * exp(-x);
                scaled[k] = e[s].f[k].mean * host_az(&st, s, k) / mui * exp(x);
                /* per arrival: round(v 2^40) (<= 0.5 units relative to v 2^40) and a few
                 * roundings: fx mui/pi (3), 1/mui (1, times x), exp (<= 3 ulp), f*t (1),
                 * the host's division (1); allowed twice that */
                tol[k] = v * LSQT_FIX_SCALE >= 64.0 ? 2.0 * ((0.5 / LSQT_FIX_SCALE) / v + (9.0 + x) * eps) : -1.0;
                if (tol[k] > 0 && (kb < 0 || mui > host_az(&st, s, kb))) kb = k;
            }
            CHECK(kb >= 0, "%s: no usable direction", what);
            if (kb < 0) continue;
            for (int k = 0; k < nwi; k++) {
                if (tol[k] < 0) continue;
                used++;
                const double r = scaled[k] / scaled[kb] - 1.0, z = st.wi[((size_t)s * nwi + (size_t)k) * 4 + 2];
                spread = fmax(spread, fabs(r));
                if (fabs(z) < 0.02) spread_graze = fmax(spread_graze, fabs(r));
                CHECK(fabs(r) <= tol[k] + tol[kb], "%s to=%g wi.z=%.5f: f e^{tau/mui} differs by %.3g (allowed %.2g)",
                      what, deg[s], z, r, tol[k] + tol[kb]);
            }
            const double mub = host_az(&st, s, kb);
            const double want = fx / PI * exp(-tau1 / muo);
            CHECK_Z(scaled[kb], want, e[s].f[kb].err * exp(tau / mub), ZA);
            /* analog exit: R or T = fx e^{-tau1/muo} 2 E3(tau) */
            const lsqt_est *an = up ? &e[s].R : &e[s].T;
            const double want_an = fx * exp(-tau1 / muo) * 2.0 * e3(tau);
            CHECK_Z(an->mean, want_an, an->err, ZA);
            printf("  %s to=%4.1f %s: f e^{tau/mui} spread %.2g over %d directions (%.2g where |wi.z| < 0.02), "
                   "%.6f vs %.6f (+- %.2g); %s %.6f vs %.6f +- %.2g\n",
                   what, deg[s], up ? "up" : "down", spread, used, spread_graze, scaled[kb], want,
                   e[s].f[kb].err * exp(tau / mub), up ? "R" : "T", an->mean, want_an, an->err);
        }
    }
    lsqt_estimates_free(e, ns);
    lsqt_state_free(&st);
}

/* -------------------------------- semi-infinite isotropic medium (Chandrasekhar) */

/* H by h_solve / h_eval (ref_media.h) */
static hfun hf_a, hf_b;

/* A slab of optical thickness 100 (mut = 1) as a half space: f = om/(4 pi) H(muo) H(mui) /
 * (muo + mui) above. Per direction, and the mean of f/ref over the upper directions that
 * are checked (`sel`: all, or only |wi.z| < 0.02, the grazing ones). */
static void semi_infinite(const char *what, double om, int ns, const double *deg, int nwi, const double (*dirs)[3],
                         uint64_t paths, uint64_t seed, int use_double, int count_only)
{
    if (count_only) {
        int n_up = 0;
        if (dirs)
            for (int k = 0; k < nwi; k++) n_up += dirs[k][2] > 0;
        else
            n_up = nwi / 2; /* lsqt_wi_spread on the sphere: half above */
        n_dir += ns * n_up, n_agg += ns;
        return;
    }
    CHECK(h_solve(&hf_a, om, 16) > 0 && h_solve(&hf_b, om, 32) > 0, "H(om=%g) did not converge", om);
    double hdiff = 0.0;
    for (int i = 0; i <= 1000; i++)
        hdiff = fmax(hdiff, fabs(h_eval(&hf_a, i / 1000.0) / h_eval(&hf_b, i / 1000.0) - 1.0));
    CHECK(hdiff < 1e-9, "H(om=%g): quadratures differ by %.3g", om, hdiff);
    char text[256];
    snprintf(text, sizeof text,
             "Medium\nLayer z=100 NullBsdf\nMedium mus=%.17g mua=%.17g HenyeyGreensteinPhase g=0\n"
             "Layer z=0 NullBsdf\nMedium\n",
             om, 1.0 - om);
    lsqt_state st;
    lsqt_slice_est *e = run_dirs(text, ns, deg, nwi, dirs, paths, seed, use_double, &st);
    for (int s = 0; s < ns; s++) {
        const double muo = cos(st.theta_o[s]), ho = h_eval(&hf_b, muo);
        CHECK(e[s].T.mean < 1e-4, "%s slice %d: T = %.3g, not semi-infinite", what, s, e[s].T.mean);
        const double model = (e[s].T.mean + 3 * e[s].T.err) / e[s].R.mean + 1e-6;
        double ref[128];
        int ks[128], n = 0;
        double zmax = 0.0;
        for (int k = 0; k < nwi; k++) {
            double wi[3];
            wi_of(&st, s, k, wi);
            ref[k] = 1.0;
            if (wi[2] <= 0) continue;
            ref[k] = om / (4.0 * PI) * ho * h_eval(&hf_b, wi[2]) / (muo + wi[2]);
            ks[n++] = k;
            const double d = e[s].f[k].mean - ref[k], sg = e[s].f[k].err;
            zmax = fmax(zmax, fabs(d) / sg);
            CHECK(sg > 0 && fabs(d) <= ZD * sg + model * ref[k], "%s om=%g to=%g wi.z=%.5f: f %.6g +- %.2g vs %.6g: z = %.2f",
                  what, om, deg[s], wi[2], e[s].f[k].mean, sg, ref[k], d / sg);
        }
        lsqt_est A = ratio_over(&st, s, ks, n, ref, NULL, 1.0);
        CHECK(fabs(A.mean - 1.0) <= ZA * A.err + model, "%s om=%g to=%g: mean f/ref %.5f +- %.2g", what, om, deg[s],
              A.mean, A.err);
        printf("  %s om=%.2f to=%4.1f: mean f/ref %.5f +- %.5f over %d directions, max |z| %.2f\n", what, om, deg[s],
               A.mean, A.err, n, zmax);
    }
    lsqt_estimates_free(e, ns);
    lsqt_state_free(&st);
}

/* ---------------------------------------------------------------- sections */

/* Each section runs its cases twice: first counting the family's checks (no simulation),
 * then for real with ZD and ZA from those counts. */
static void section_double(int count_only)
{
    const double deg3[] = {0, 50, 80}, deg2[] = {0, 60};
    /* free flights: T = exp(-tau/muo) to ~5e-4 relative */
    clear_slab(1.0, 3, deg3, (uint64_t)1 << 22, 1001, 1, count_only);
    /* the way out of an absorber (layer next-event transmittance, exp in double) and 2 E3 */
    absorber_lambertian("double absorber/Lambertian", 1.0, 0.5, 0.5, 0.3, 2, deg2, 64, NULL, (uint64_t)1 << 20, 1002, 1,
                        count_only);
    /* phase values per collision (om small: second collisions weigh om^2) */
    thin_slab("double thin g=0.6", 0.6, 0.1, 1e-3, 2, deg2, 64, NULL, (uint64_t)1 << 22, 1003, 1, count_only);
    thin_slab("double thin g=-0.3", -0.3, 0.1, 1e-3, 2, deg2, 64, NULL, (uint64_t)1 << 22, 1004, 1, count_only);
    /* the medium's next-event transmittance, to all orders */
    semi_infinite("double semi-infinite", 0.5, 2, deg2, 64, NULL, (uint64_t)1 << 19, 1005, 1, count_only);
}

static void section_grazing(int count_only)
{
    double dirs[NWI_GRAZE][3], up_only[NWI_GRAZE][3];
    const int nt = grazing_dirs(1, dirs), nr = grazing_dirs(0, up_only);
    const double(*dt)[3] = (const double(*)[3])dirs, (*dr)[3] = (const double(*)[3])up_only;
    const double deg3[] = {0, 60, 85};
    /* exact: the layer's next-event transmittance at grazing, both sides */
    absorber_lambertian("grazing absorbers/Lambertian", 1e-3, 2e-3, 0.5, 0.3, 3, deg3, nt, dt, (uint64_t)1 << 18, 2001,
                        0, count_only);
    absorber_lambertian("grazing absorber/opaque Lambertian", 3e-3, 0.0, 0.7, 0.0, 3, deg3, nr, dr, (uint64_t)1 << 18,
                        2002, 0, count_only);
    /* the medium's: single scattering per collision, tau/|mu_i| up to 0.57 */
    thin_slab("grazing thin g=0", 0.0, 0.1, 1e-3, 3, deg3, nt, dt, (uint64_t)1 << 23, 2003, 0, count_only);
    thin_slab("grazing thin g=0.7", 0.7, 0.1, 1e-3, 3, deg3, nt, dt, (uint64_t)1 << 23, 2004, 0, count_only);
    /* all orders: H(mu_i) near mu_i = 0 */
    semi_infinite("grazing semi-infinite", 0.9, 2, deg3, nr, dr, (uint64_t)1 << 17, 2005, 0, count_only);
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3 || (strcmp(argv[1], "double") && strcmp(argv[1], "grazing"))) {
        fprintf(stderr, "usage: test_power_media double|grazing [SEED_OFFSET]\n");
        return 2;
    }
    if (argc == 3) seed_offset = strtoull(argv[2], NULL, 10);
    const int dbl = !strcmp(argv[1], "double");
    family_plan(argv[1], dbl ? section_double : section_grazing);
    fixture_open();
    if (dbl && !fixture_cx.dev.has_fp64) {
        printf("no fp64 on this device: skipped\n");
        lsqt_context_release(&fixture_cx);
        return 77;
    }
    if (dbl) section_double(0);
    else section_grazing(0);
    lsqt_context_release(&fixture_cx);
    return check_finish(dbl ? "test_power_media double" : "test_power_media grazing");
}
