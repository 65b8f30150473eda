/* Several media separated by null layers, against an independent reference: the
 * adding-doubling method (tests/ref_adding.h), which owes nothing to the program.
 *
 * A point estimate from a lower medium crosses every medium above it on its way up (and
 * every one below on its way down); a path crosses null layers between media in its
 * free flights. Stacks with one medium do not see errors there: these do. Each stack is
 * lit at theta_o = 0, 60 and 85 degrees; the RAW value f is compared at theta_i = 0, 40,
 * 70, 80, 87 and 89 degrees, at azimuths 0, 90 and 180 from wo's, on both sides.
 *
 *   test_media_stacks reference  the reference itself, no device: Chandrasekhar's H
 *                                (semi-infinite isotropic), iadpython's hemispherical R
 *                                and T (tests/data/validation_fixtures.json), exact
 *                                identities of a clear absorber above and below a
 *                                scatterer, energy conservation, reciprocity of
 *                                reflection, and its own quadrature and Fourier
 *                                truncation at the settings the other sections use.
 *   test_media_stacks quick      the release suite's: thin over thick, thick over thin,
 *                                three media, two media over a Lambertian ground, and a
 *                                clear absorbing film over a scatterer, in float, 2^18
 *                                paths a slice.
 *   test_media_stacks float      power (CI): six stacks, 2^21 paths a slice: those five
 *                                and two equal media that must equal one medium of the
 *                                summed optical thickness (its reference is the one
 *                                medium's).
 *   test_media_stacks double     power (CI): five of them in --double, 2^20 paths.
 *
 * Checks: per direction |f - ref| <= ZD sigma + ref REF_TOL; per (slice, side, theta_i)
 * the mean of f/ref over the azimuths, and per slice the analog R, T and delta_T, within
 * ZA sigma + REF_TOL. ZD, ZA: Student t (31 degrees of freedom) for a family-wise false
 * alarm rate of 1e-3 per section (tests/family_stats.h). REF_TOL bounds the reference's
 * error; the reference section checks it. `test_media_stacks SECTION N` adds N to every
 * seed (to see that the tolerances hold). */
#include "family_stats.h"
#include "ref_adding.h"
#include "stack_dirs.h"

/* The reference's error bound (relative), and the settings all value sections use:
 * nodes per panel, Fourier modes, the thickest start of the doubling. Against a reference
 * with 1.5 times the nodes and modes and a start 10 times thinner (FINE_*) they differ
 * by less than 1e-5 on every stack here (checked: the reference and float sections). */
#define REF_TOL 1e-4
#define REF_T0 1e-7
#define FINE_T0 1e-8
enum { REF_PER_PANEL = 4, REF_MODES = 16, FINE_PER_PANEL = 6, FINE_MODES = 24 };

/* ------------------------------------------------------------------ the stacks */

enum { MAX_MEDIA = 4 };

typedef struct {
    const char *name;
    int n; /* interior media, top first */
    /* optical thickness, albedo, HG g and geometric thickness of each */
    double tau[MAX_MEDIA], om[MAX_MEDIA], g[MAX_MEDIA], d[MAX_MEDIA];
    int ref_merged; /* the reference is one medium of the summed tau (equal media) */
    int floor;      /* an opaque Lambertian of reflectance floor_fr at the bottom (else null) */
    double floor_fr;
} stack_case;

/* Thicknesses other than 1, so that a coefficient taken for an optical thickness (or
 * the other way round) is an error the test sees. */
static const stack_case THIN_OVER_THICK = {
    "thin over thick", 2, {0.1, 2.0}, {0.9, 0.95}, {0.3, 0.6}, {0.4, 1.7}, 0, 0, 0.0};
static const stack_case THICK_OVER_THIN = {
    "thick over thin", 2, {2.0, 0.1}, {0.95, 0.8}, {0.5, -0.3}, {1.3, 0.6}, 0, 0, 0.0};
static const stack_case FILM_OVER_PIGMENT = {
    "absorbing film over scatterer", 2, {0.3, 1.0}, {0.0, 0.99}, {0.0, 0.5}, {0.25, 2.0}, 0, 0, 0.0};
static const stack_case THREE_MEDIA = {
    "three media", 3, {0.2, 0.3, 1.0}, {0.9, 0.5, 0.9}, {0.5, 0.0, -0.2}, {0.5, 1.5, 0.8}, 0, 0, 0.0};
static const stack_case EQUAL_MEDIA = {
    "two equal media = one", 2, {0.35, 0.65}, {0.9, 0.9}, {0.4, 0.4}, {0.7, 1.3}, 1, 0, 0.0};
/* the layer's point estimates cross both media (the kernels' per-layer tables) */
static const stack_case DUST_HAZE_GROUND = {
    "dust over haze over ground", 2, {0.15, 0.8}, {0.85, 0.97}, {0.6, 0.2}, {0.3, 2.5}, 0, 1, 0.3};

static void stack_text(const stack_case *c, char *text, size_t size)
{
    double z = 0.0;
    for (int k = 0; k < c->n; k++) z += c->d[k];
    int at = snprintf(text, size, "Medium\n");
    for (int k = 0; k < c->n; k++) {
        const double mut = c->tau[k] / c->d[k];
        at += snprintf(text + at, size - (size_t)at, "Layer z=%.17g NullBsdf\n", z);
        if (c->om[k] > 0)
            at += snprintf(text + at, size - (size_t)at, "Medium mus=%.17g mua=%.17g HenyeyGreensteinPhase g=%.17g\n",
                           c->om[k] * mut, (1.0 - c->om[k]) * mut, c->g[k]);
        else
            at += snprintf(text + at, size - (size_t)at, "Medium mua=%.17g\n", mut);
        z -= c->d[k];
    }
    if (c->floor)
        snprintf(text + at, size - (size_t)at, "Layer z=0 LambertianBsdf fR=%.17g fT=0\nMedium\n", c->floor_fr);
    else
        snprintf(text + at, size - (size_t)at, "Layer z=0 NullBsdf\nMedium\n");
}

static void stack_ref(const stack_case *c, int per_panel, int modes, double t0, ad_ref *r)
{
    ad_grid G;
    stack_grid(&G, per_panel, modes);
    ad_stack_desc S = {c->n, {0}, {0}, {0}, c->floor, c->floor_fr};
    for (int k = 0; k < c->n; k++) S.tau[k] = c->tau[k], S.om[k] = c->om[k], S.g[k] = c->g[k];
    if (c->ref_merged) { /* equal media: the reference is one medium */
        S.n = 1;
        S.tau[0] = c->tau[0] + c->tau[1];
    }
    ad_ref_make(r, &G, &S, t0);
}

/* Reference f at state direction d (float components) for slice angle deg. */
static double stack_ref_f(const ad_ref *r, double deg, const double d[3], int modes)
{
    const double mu0 = cos(deg * PI / 180.0);
    return ad_ref_f(r, mu0, d[2], atan2(d[1], d[0]) - PI, modes);
}

static double total_tau(const stack_case *c)
{
    double t = 0.0;
    for (int k = 0; k < c->n; k++) t += c->tau[k];
    return t;
}

/* Simulates the stack and checks it (count_only: only counts the checks). */
static void stack_check(const stack_case *c, uint64_t paths, uint64_t seed, int use_double, int count_only)
{
    /* an opaque stack: the upward directions only (the first NWI) */
    const int nwi = c->floor ? NWI : NWI_T, nb = c->floor ? NTH : 2 * NTH;
    n_dir += NS * nwi, n_agg += NS * (nb + 3);
    if (count_only) return;
    char text[1024];
    stack_text(c, text, sizeof text);
    double dirs[NWI_T][3];
    int band[NWI_T];
    stack_dirs(dirs, band);
    ad_ref r;
    stack_ref(c, REF_PER_PANEL, REF_MODES, REF_T0, &r);
    lsqt_state st;
    lsqt_slice_est *e = run_dirs(text, NS, DEG_O, nwi, (const double(*)[3])dirs, paths, seed, use_double, &st);
    CHECK(st.transmits == !c->floor && st.n_wi == nwi, "%s: transmits %d, %d directions", c->name, st.transmits,
          st.n_wi);
    const char *prec = use_double ? "double" : "float";
    for (int s = 0; s < NS; s++) {
        const double mu0 = cos(DEG_O[s] * PI / 180.0);
        double ref[NWI_T], zmax = 0.0, amax = 0.0;
        for (int k = 0; k < nwi; k++) {
            ref[k] = stack_ref_f(&r, DEG_O[s], dirs[k], REF_MODES);
            const double f = e[s].f[k].mean, sg = e[s].f[k].err, dev = fabs(f - ref[k]);
            const double z = (dev - REF_TOL * ref[k]) / sg;
            zmax = fmax(zmax, dev / sg);
            CHECK(sg > 0 && z <= ZD,
                  "%s (%s) to=%g wi=(%.4f %.4f %.4f): f %.6g +- %.2g vs reference %.6g: %+.2f %%, z = %.2f", c->name,
                  prec, DEG_O[s], dirs[k][0], dirs[k][1], dirs[k][2], f, sg, ref[k], 100 * (f / ref[k] - 1),
                  (f - ref[k]) / sg);
        }
        /* per (side, theta_i): the mean of f/ref over the azimuths */
        for (int b = 0; b < nb; b++) {
            int ks[3], n = 0;
            for (int k = 0; k < nwi; k++)
                if (band[k] == b) ks[n++] = k;
            lsqt_est A = ratio_over(&st, s, ks, n, ref, NULL, 1.0);
            amax = fmax(amax, fabs(A.mean - 1.0) / A.err);
            CHECK(A.err > 0 && fabs(A.mean - 1.0) <= ZA * A.err + REF_TOL,
                  "%s (%s) to=%g %s theta_i=%g: mean f/ref %.5f +- %.2g (%+.2f %%, z = %.2f)", c->name, prec, DEG_O[s],
                  b < NTH ? "up" : "down", TH_I[b % NTH], A.mean, A.err, 100 * (A.mean - 1), (A.mean - 1) / A.err);
        }
        /* analog: R, T (with the unscattered beam) and delta_T */
        double Rr, Tr;
        ad_ref_hemi(&r, mu0, &Rr, &Tr);
        const double dT = c->floor ? 0.0 : exp(-total_tau(c) / mu0);
        Tr += dT;
        CHECK(fabs(e[s].R.mean - Rr) <= ZA * e[s].R.err + REF_TOL * Rr, "%s (%s) to=%g: R %.6f +- %.2g vs %.6f",
              c->name, prec, DEG_O[s], e[s].R.mean, e[s].R.err, Rr);
        CHECK(fabs(e[s].T.mean - Tr) <= ZA * e[s].T.err + REF_TOL * Tr, "%s (%s) to=%g: T %.6f +- %.2g vs %.6f",
              c->name, prec, DEG_O[s], e[s].T.mean, e[s].T.err, Tr);
        /* delta_T: binomial; its batch-means error is 0 where no path came through */
        const double sd_dT = fmax(e[s].delta_T.err, sqrt(dT * (1.0 - dT) / (double)paths));
        CHECK(fabs(e[s].delta_T.mean - dT) <= ZA * sd_dT + 1e-6 * dT, "%s (%s) to=%g: delta_T %.6g +- %.2g vs %.6g",
              c->name, prec, DEG_O[s], e[s].delta_T.mean, sd_dT, dT);
        printf("  %-30s %-6s to=%2.0f: max |z| %.2f per direction, %.2f per theta_i; R %.5f (ref %.5f), T %.5f (ref "
               "%.5f)\n",
               c->name, prec, DEG_O[s], zmax, amax, e[s].R.mean, Rr, e[s].T.mean, Tr);
    }
    lsqt_estimates_free(e, NS);
    lsqt_state_free(&st);
    ad_ref_free(&r);
}

/* -------------------------------------------------------- the reference itself */

static hfun hf;

/* Largest relative difference of two references (with their first ma, mb modes) at every
 * direction and slice of the test. */
static double ref_diff(const ad_ref *a, int ma, const ad_ref *b, int mb)
{
    double d[NWI_T][3], worst = 0.0;
    int band[NWI_T];
    stack_dirs(d, band);
    for (int s = 0; s < NS; s++)
        for (int k = 0; k < NWI_T; k++) {
            const double x = stack_ref_f(a, DEG_O[s], d[k], ma), y = stack_ref_f(b, DEG_O[s], d[k], mb);
            worst = fmax(worst, fabs(x / y - 1.0));
        }
    return worst;
}

/* The reference at the value sections' settings against a finer one (FINE_*: 1.5 times
 * the nodes and modes, a start 10 times thinner) and against its own first 3/4 of the
 * modes, at every direction and slice of the test: each must be below REF_TOL / 10. */
static void check_resolution(const stack_case *c)
{
    ad_ref a, b;
    stack_ref(c, REF_PER_PANEL, REF_MODES, REF_T0, &a);
    stack_ref(c, FINE_PER_PANEL, FINE_MODES, FINE_T0, &b);
    const double dq = ref_diff(&a, REF_MODES, &b, FINE_MODES), dm = ref_diff(&a, REF_MODES * 3 / 4, &a, REF_MODES);
    CHECK(dq < REF_TOL / 10 && dm < REF_TOL / 10, "reference %s: %.3g from the finer one, truncation %.3g (>= %g)",
          c->name, dq, dm, REF_TOL / 10);
    printf("  reference %-30s: %.2g from the finer one, %.2g from 3/4 of its modes (largest relative difference)\n",
           c->name, dq, dm);
    ad_ref_free(&a), ad_ref_free(&b);
}

static void section_reference(void)
{
    double d[NWI_T][3];
    int band[NWI_T];
    stack_dirs(d, band);
    /* 1. Semi-infinite isotropic media (tau = 40): f = om/(4 pi) H(mu0) H(mu)/(mu0 + mu),
     *    Chandrasekhar's H (ref_media.h; itself checked in test_references). */
    for (int io = 0; io < 2; io++) {
        const double om = io ? 0.99 : 0.7;
        CHECK(h_solve(&hf, om, 32) > 0, "H(om=%g) did not converge", om);
        const stack_case c = {"semi-infinite", 1, {40.0}, {om}, {0.0}, {1.0}, 0, 0, 0.0};
        ad_ref r;
        stack_ref(&c, REF_PER_PANEL, 2, REF_T0, &r);
        double worst = 0.0;
        for (int s = 0; s < NS; s++) {
            const double mu0 = cos(DEG_O[s] * PI / 180.0);
            for (int k = 0; k < NWI; k++) {
                const double f = stack_ref_f(&r, DEG_O[s], d[k], 2);
                const double h = om / (4 * PI) * h_eval(&hf, mu0) * h_eval(&hf, d[k][2]) / (mu0 + d[k][2]);
                worst = fmax(worst, fabs(f / h - 1.0));
            }
        }
        CHECK(worst < 2e-5, "reference vs H (om=%g): %.3g relative", om, worst);
        printf("  semi-infinite om=%.2f: largest relative difference from H %.2g\n", om, worst);
        ad_ref_free(&r);
    }
    /* 2. iadpython (adding-doubling, Prahl), hemispherical R and T with the unscattered
     *    beam, at normal incidence and 60 degrees: the index-matched slabs of the
     *    validation fixtures with |g| <= 0.8 (its values' error: 2e-5; ours grows with
     *    the number of doublings to 4e-5 at tau = 100), on the finer grid (the value
     *    sections' is enough for their |g| <= 0.6, not for g = 0.8's hemispherical
     *    integrals: 4e-4). */
    static const struct {
        double om, tau, g, R0, T0, R60, T60;
    } iad[] = {
        {0.5, 0.1, 0.0, 0.021732965500357845, 0.926465072823318, 0.04149864092831941, 0.8598285906241168},
        {0.9, 1.0, 0.5, 0.12979327969419416, 0.7390911209814004, 0.273591763316513, 0.5275249296314383},
        {0.99, 1.0, -0.5, 0.4378355537524171, 0.5471333009672162, 0.5765089935352867, 0.40107495543518656},
        {0.99, 3.0, 0.8, 0.17900295819850492, 0.7748837211458826, 0.38676062120332566, 0.5481583780847613},
        {0.7, 30.0, -0.3, 0.26502584224677156, 4.38777991425118e-12, 0.31501811557971665, 8.181664808833416e-13},
        {0.999, 100.0, 0.5, 0.8778792095017616, 0.004887833701109756, 0.9140331447632611, 0.003349925009273248},
    };
    for (size_t i = 0; i < sizeof iad / sizeof iad[0]; i++) {
        const stack_case c = {"iadpython", 1, {iad[i].tau}, {iad[i].om}, {iad[i].g}, {1.0}, 0, 0, 0.0};
        ad_ref r;
        stack_ref(&c, FINE_PER_PANEL, 1, REF_T0, &r);
        double R[2], T[2], worst = 0.0;
        for (int s = 0; s < 2; s++) {
            const double mu0 = s ? cos(DEG_O[1] * PI / 180.0) : 1.0;
            ad_ref_hemi(&r, mu0, &R[s], &T[s]);
            T[s] += exp(-iad[i].tau / mu0);
        }
        const double want[4] = {iad[i].R0, iad[i].T0, iad[i].R60, iad[i].T60}, got[4] = {R[0], T[0], R[1], T[1]};
        for (int q = 0; q < 4; q++) worst = fmax(worst, fabs(got[q] - want[q]));
        CHECK(worst < 5e-5,
              "reference vs iadpython om=%g tau=%g g=%g: R %.7f %.7f, T %.7f %.7f (iad %.7f %.7f, %.7f %.7f)",
              iad[i].om, iad[i].tau, iad[i].g, R[0], R[1], T[0], T[1], iad[i].R0, iad[i].R60, iad[i].T0, iad[i].T60);
        printf("  iadpython om=%.3f tau=%5.1f g=%+.1f: largest difference in R, T %.2g\n", iad[i].om, iad[i].tau,
               iad[i].g, worst);
        ad_ref_free(&r);
    }
    /* 3. A clear absorber (tau_a) above a scatterer B multiplies B's reflection by
     *    e^{-tau_a (1/mu0 + 1/mu)} and its transmission by e^{-tau_a/mu0}; below it, it
     *    leaves R alone and multiplies T by e^{-tau_a/|mu|}: exact, so the adding of
     *    unlike slabs is checked term by term. */
    {
        const double ta = 0.3;
        const stack_case B = {"B", 1, {1.0}, {0.95}, {0.5}, {1.0}, 0, 0, 0.0};
        const stack_case AB = {"A/B", 2, {ta, 1.0}, {0.0, 0.95}, {0.0, 0.5}, {1.0, 1.0}, 0, 0, 0.0};
        const stack_case BA = {"B/A", 2, {1.0, ta}, {0.95, 0.0}, {0.5, 0.0}, {1.0, 1.0}, 0, 0, 0.0};
        ad_ref rb, rab, rba;
        stack_ref(&B, REF_PER_PANEL, REF_MODES, REF_T0, &rb);
        stack_ref(&AB, REF_PER_PANEL, REF_MODES, REF_T0, &rab);
        stack_ref(&BA, REF_PER_PANEL, REF_MODES, REF_T0, &rba);
        double worst = 0.0;
        for (int s = 0; s < NS; s++) {
            const double mu0 = cos(DEG_O[s] * PI / 180.0);
            for (int k = 0; k < NWI_T; k++) {
                const double mu = d[k][2], fb = stack_ref_f(&rb, DEG_O[s], d[k], REF_MODES);
                const double above = mu > 0 ? exp(-ta * (1 / mu0 + 1 / mu)) : exp(-ta / mu0);
                const double below = mu > 0 ? 1.0 : exp(-ta / -mu);
                worst = fmax(worst, fabs(stack_ref_f(&rab, DEG_O[s], d[k], REF_MODES) / (above * fb) - 1));
                worst = fmax(worst, fabs(stack_ref_f(&rba, DEG_O[s], d[k], REF_MODES) / (below * fb) - 1));
            }
        }
        /* and over a Lambertian floor: f = fR/pi e^{-tau_a (1/mu0 + 1/mu)} */
        const stack_case AL = {"A/floor", 1, {ta}, {0.0}, {0.0}, {1.0}, 0, 1, 0.4};
        ad_ref ral;
        stack_ref(&AL, REF_PER_PANEL, REF_MODES, REF_T0, &ral);
        for (int s = 0; s < NS; s++) {
            const double mu0 = cos(DEG_O[s] * PI / 180.0);
            for (int k = 0; k < NWI; k++) {
                const double want = 0.4 / PI * exp(-ta * (1 / mu0 + 1 / d[k][2]));
                worst = fmax(worst, fabs(stack_ref_f(&ral, DEG_O[s], d[k], REF_MODES) / want - 1));
            }
        }
        CHECK(worst < 1e-9, "reference: absorber above/below a scatterer or over a floor off by %.3g relative", worst);
        printf("  absorber above and below a scatterer, over a floor: largest relative difference from the exact "
               "%.2g\n",
               worst);
        ad_ref_free(&rb), ad_ref_free(&rab), ad_ref_free(&rba), ad_ref_free(&ral);
    }
    /* 4. Unlike conservative slabs (om = 1): R + T + the unscattered beam = 1. 5. Their
     *    reflection is reciprocal, f(mu0 -> mu, dphi) = f(mu -> mu0, dphi), though the
     *    stack is not symmetric (a wrong term of the adding breaks that). */
    {
        const stack_case c = {
            "conservative", 3, {0.2, 1.5, 0.4}, {1.0, 1.0, 1.0}, {0.6, -0.4, 0.2}, {1, 1, 1}, 0, 0, 0.0};
        ad_ref r;
        stack_ref(&c, REF_PER_PANEL, REF_MODES, REF_T0, &r);
        double worst_e = 0.0, worst_r = 0.0;
        for (int s = 0; s < NS; s++) {
            const double mu0 = cos(DEG_O[s] * PI / 180.0);
            double R, T;
            ad_ref_hemi(&r, mu0, &R, &T);
            worst_e = fmax(worst_e, fabs(R + T + exp(-total_tau(&c) / mu0) - 1.0));
            for (int k = 0; k < NWI; k++) {
                const double dphi = atan2(d[k][1], d[k][0]) - PI;
                const double a = ad_ref_f(&r, mu0, d[k][2], dphi, REF_MODES);
                const double b = ad_ref_f(&r, d[k][2], mu0, dphi, REF_MODES);
                worst_r = fmax(worst_r, fabs(a / b - 1));
            }
        }
        CHECK(worst_e < 1e-5, "reference: energy not conserved by %.3g", worst_e);
        CHECK(worst_r < 1e-9, "reference: reflection not reciprocal by %.3g", worst_r);
        printf("  three conservative slabs: energy conserved to %.2g, reflection reciprocal to %.2g\n", worst_e,
               worst_r);
        ad_ref_free(&r);
    }
    /* 6. Its resolution, on the stack with the most slabs (the float section checks
     *    every stack's). */
    check_resolution(&THREE_MEDIA);
}

/* ---------------------------------------------------------------- sections */

static void section_quick(int count_only)
{
    stack_check(&THIN_OVER_THICK, (uint64_t)1 << 18, 3001, 0, count_only);
    stack_check(&THICK_OVER_THIN, (uint64_t)1 << 18, 3002, 0, count_only);
    stack_check(&THREE_MEDIA, (uint64_t)1 << 18, 3003, 0, count_only);
    stack_check(&DUST_HAZE_GROUND, (uint64_t)1 << 18, 3004, 0, count_only);
    stack_check(&FILM_OVER_PIGMENT, (uint64_t)1 << 18, 3005, 0, count_only);
}

static void section_float(int count_only)
{
    if (!count_only) {
        check_resolution(&THIN_OVER_THICK);
        check_resolution(&THICK_OVER_THIN);
        check_resolution(&FILM_OVER_PIGMENT);
    }
    stack_check(&THIN_OVER_THICK, (uint64_t)1 << 21, 3101, 0, count_only);
    stack_check(&THICK_OVER_THIN, (uint64_t)1 << 21, 3102, 0, count_only);
    stack_check(&FILM_OVER_PIGMENT, (uint64_t)1 << 21, 3103, 0, count_only);
    stack_check(&THREE_MEDIA, (uint64_t)1 << 21, 3104, 0, count_only);
    stack_check(&EQUAL_MEDIA, (uint64_t)1 << 21, 3105, 0, count_only);
    stack_check(&DUST_HAZE_GROUND, (uint64_t)1 << 21, 3106, 0, count_only);
}

static void section_double(int count_only)
{
    stack_check(&THIN_OVER_THICK, (uint64_t)1 << 20, 3201, 1, count_only);
    stack_check(&THICK_OVER_THIN, (uint64_t)1 << 20, 3202, 1, count_only);
    stack_check(&FILM_OVER_PIGMENT, (uint64_t)1 << 20, 3203, 1, count_only);
    stack_check(&THREE_MEDIA, (uint64_t)1 << 20, 3204, 1, count_only);
    stack_check(&DUST_HAZE_GROUND, (uint64_t)1 << 20, 3205, 1, count_only);
}

int main(int argc, char **argv)
{
    static const char *names[] = {"reference", "quick", "float", "double"};
    static void (*const run[])(int) = {NULL, section_quick, section_float, section_double};
    int sec = -1;
    for (int i = 0; argc >= 2 && i < 4; i++)
        if (!strcmp(argv[1], names[i])) sec = i;
    if (sec < 0 || argc > 3) {
        fprintf(stderr, "usage: test_media_stacks reference|quick|float|double [SEED_OFFSET]\n");
        return 2;
    }
    if (argc == 3) seed_offset = strtoull(argv[2], NULL, 10);
    if (sec == 0) {
        section_reference();
        return check_finish("test_media_stacks reference");
    }
    family_plan(names[sec], run[sec]);
    fixture_open();
    if (sec == 3 && !fixture_cx.dev.has_fp64) {
        printf("no fp64 on this device: skipped\n");
        lsqt_context_release(&fixture_cx);
        return 77;
    }
    run[sec](0);
    lsqt_context_release(&fixture_cx);
    char what[64];
    snprintf(what, sizeof what, "test_media_stacks %s", names[sec]);
    return check_finish(what);
}
