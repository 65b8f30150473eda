/* End-to-end physics of the walk on the device, against closed forms. */
#include "cl_fixture.h"
#include "nee_albedo.h"

#define PI 3.14159265358979323846


/* Exact sum of fixed-point tallies over batches (or bins) of one slice. */
static lsqt_u128 sum_u128(const lsqt_u128 *p, size_t n, size_t stride)
{
    lsqt_u128 t = {0, 0};
    for (size_t i = 0; i < n; i++) t = lsqt_u128_add(t, p[i * stride]);
    return t;
}

/* Every scattered exit lands in one histogram bin of its path's batch with the same
 * fixed-point weight as its R or T tally: the integer sums must agree exactly, batch by
 * batch (R + T = binned + delta_T). */
static void check_hist_total(const lsqt_state *st, int s)
{
    for (int b = 0; b < LSQT_BATCHES; b++) {
        const lsqt_u128 *sc = st->scalars + ((size_t)s * LSQT_BATCHES + (size_t)b) * LSQT_T_COUNT;
        const lsqt_u128 *h = st->hist + ((size_t)s * LSQT_BATCHES + (size_t)b) * LSQT_HIST_BINS;
        lsqt_u128 exits = lsqt_u128_add(sc[LSQT_T_R], sc[LSQT_T_T]);
        lsqt_u128 binned = lsqt_u128_add(sum_u128(h, LSQT_HIST_BINS, 1), sc[LSQT_T_DELTA_T]);
        CHECK(exits.lo == binned.lo && exits.hi == binned.hi,
              "slice %d batch %d: histogram + delta_T holds %.17g, exits %.17g", s, b, lsqt_u128_to_double(binned),
              lsqt_u128_to_double(exits));
    }
}

/* The histogram of one slice summed over its batches, bin by bin. */
static void hist_of_slice(const lsqt_state *st, int s, lsqt_u128 *out)
{
    for (int i = 0; i < LSQT_HIST_BINS; i++)
        out[i] = sum_u128(st->hist + (size_t)s * LSQT_BATCHES * LSQT_HIST_BINS + (size_t)i, LSQT_BATCHES,
                          LSQT_HIST_BINS);
}

/* The work counters of one slice, summed over its batches. */
static double work_of(const lsqt_state *st, int s, int which)
{
    return lsqt_u128_to_double(
        sum_u128(st->scalars + (size_t)s * LSQT_BATCHES * LSQT_T_COUNT + (size_t)which, LSQT_BATCHES, LSQT_T_COUNT));
}

/* Work counters where they are exact: a lone Lambertian layer scatters each path once
 * and evaluates its point estimate there; under a clear absorber, only the paths that
 * reach it (and absorption is no event); in a
 * slab between null layers every event is in the medium, the null layers count none,
 * and every medium vertex sees out (optical depth 1 < 60), so each evaluates once. */
static void test_work_counters(void)
{
    const char *texts[] = {"Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n",
                           "Medium\nLayer z=1 NullBsdf\nMedium mua=1\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n",
                           "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0.5\nLayer z=0 NullBsdf\nMedium\n"};
    const double deg[] = {0, 70};
    for (int t = 0; t < 3; t++) {
        lsqt_state st;
        lsqt_slice_est *e = fixture_run(texts[t], 2, deg, 16, 3000, 40 + (uint64_t)t, &st);
        for (int s = 0; s < 2; s++) {
            double n = (double)st.paths, lay = work_of(&st, s, LSQT_T_LAYER_EVENTS);
            double med = work_of(&st, s, LSQT_T_MEDIUM_EVENTS), nee = work_of(&st, s, LSQT_T_NEE_VERTICES);
            if (t == 0) {
                CHECK(lay == n && med == 0 && nee == n, "case %d slice %d: %g paths, layer %g, medium %g, NEE %g", t, s,
                      n, lay, med, nee);
            } else if (t == 1) {
                /* a path reaches the floor with probability exp(-1 / cos), binomially;
                 * absorption in the clear medium is no scattering event */
                double p = exp(-1.0 / cos(deg[s] * PI / 180)), sd = sqrt(n * p * (1 - p));
                CHECK(lay == nee && med == 0 && fabs(lay - n * p) <= 4 * sd,
                      "absorber slice %d: %g paths, layer %g (expected %.1f +- %.1f), medium %g, NEE %g", s, n, lay,
                      n * p, sd, med, nee);
            } else {
                /* mean events per path in a slab of optical depth 1: between 0.5 and 3 */
                CHECK(lay == 0 && nee == med && med > 0.5 * n && med < 3 * n,
                      "slab slice %d: %g paths, layer %g, medium %g, NEE %g", s, n, lay, med, nee);
            }
        }
        lsqt_work w = lsqt_work_totals(&st);
        CHECK(w.paths == 2.0 * st.paths && w.nee_evaluations == 16 * (work_of(&st, 0, LSQT_T_NEE_VERTICES) +
                                                                       work_of(&st, 1, LSQT_T_NEE_VERTICES)),
              "case %d: totals %g paths, %g NEE evaluations", t, w.paths, w.nee_evaluations);
        lsqt_estimates_free(e, 2);
        lsqt_state_free(&st);
    }
}

static void test_lambertian(void)
{
    const double deg[] = {0, 30, 60, 89.9};
    lsqt_state st;
    lsqt_slice_est *e = fixture_run("Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n", 4, deg, 80, 20000, 1, &st);
    CHECK(!st.transmits, "a Lambertian with fT=0 must not transmit");
    for (int s = 0; s < 4; s++) {
        for (int k = 0; k < st.n_wi; k++) CHECK_REL(e[s].f[k].mean, 0.6 / PI, 1e-5);
        CHECK(fabs(e[s].R.mean - 0.6) <= 3 * e[s].R.err + 1e-7, /* fR is a float on the device */ "slice %d: R = %.9g +- %.3g", s, e[s].R.mean, e[s].R.err);
        CHECK(e[s].T.mean == 0.0, "slice %d: T = %g", s, e[s].T.mean);
        check_hist_total(&st, s);
        /* Exits are cosine distributed: row i of the |cos| grid holds (2i+1)/N^2 of them.
         * Every path weighs exactly fR, so weight / fR counts paths (chi-square). */
        lsqt_u128 h[LSQT_HIST_BINS];
        hist_of_slice(&st, s, h);
        const double unit = 0.6 * LSQT_FIX_SCALE, n = (double)st.paths;
        double chi2 = 0.0;
        for (int i = 0; i < LSQT_HIST_NMU; i++) {
            double got = lsqt_u128_to_double(sum_u128(h + (size_t)i * LSQT_HIST_NPHI, LSQT_HIST_NPHI, 1)) / unit;
            double want = n * (2.0 * i + 1.0) / (LSQT_HIST_NMU * LSQT_HIST_NMU);
            chi2 += (got - want) * (got - want) / want;
        }
        /* 31 dof: P(chi2 > 70) < 1e-4 */
        CHECK(chi2 < 70.0, "slice %d: exit cosines chi2 = %.1f over %d rows", s, chi2, LSQT_HIST_NMU);
    }
    CHECK(st.flags == 0, "flags %u", st.flags);
    lsqt_estimates_free(e, 4);
    lsqt_state_free(&st);
}

/* A path that leaves the stack right after a bounce is never rouletted: a single
 * Lambertian layer reflects exactly fR per path, with no noise at all (roulette there
 * gave 0.0975 +- 0.0013 for fR = 0.1). fR is a float on the device and each path's
 * weight rounds once to the 2^-40 grid, so R is fR to within half a unit + float
 * rounding (fR = 3e-9 is 3299 units: resolved, not 0 +- 0). */
static void test_roulette_exit(void)
{
    const double deg[] = {0, 60};
    const double fr[] = {0.1, 3e-9};
    for (int i = 0; i < 2; i++) {
        char text[128];
        snprintf(text, sizeof text, "Medium\nLayer z=0 LambertianBsdf fR=%g\nMedium\n", fr[i]);
        lsqt_state st;
        lsqt_slice_est *e = fixture_run(text, 2, deg, 16, 20000, 11, &st);
        for (int s = 0; s < 2; s++) {
            CHECK(fabs(e[s].R.mean - fr[i]) <= (0.5 / LSQT_FIX_SCALE) + 1e-7 * fr[i], "fR=%g slice %d: R = %.12g", fr[i], s,
                  e[s].R.mean);
            CHECK(e[s].R.err == 0.0, "fR=%g slice %d: R has an error %.3g (every path carries fR)", fr[i], s,
                  e[s].R.err);
        }
        lsqt_estimates_free(e, 2);
        lsqt_state_free(&st);
    }
}

/* --double is double end to end: the layer's fR = 0.1 reaches the kernel unrounded. Every
 * path reflects exactly fR, rounded once to the 2^-40 grid, so in double R = 0.1 within
 * half a unit (4.5e-13), while the float 0.1f = 0.1 + 1.49e-9 is far further off. */
static void test_double_tables(void)
{
    if (!fixture_cx.dev.has_fp64) {
        printf("skip: %s has no fp64, --double is refused there\n", fixture_cx.dev.name);
        return;
    }
    const double deg[] = {0, 45};
    for (int dbl = 0; dbl < 2; dbl++) {
        lsqt_state st;
        lsqt_slice_est *e = fixture_run_prec("Medium\nLayer z=0 LambertianBsdf fR=0.1\nMedium\n", 2, deg, 16, 4096, 12,
                                             dbl, &st);
        const double want = dbl ? 0.1 : (double)0.1f;
        for (int s = 0; s < 2; s++)
            CHECK(fabs(e[s].R.mean - want) <= (0.5 / LSQT_FIX_SCALE), "%s: R = %.15g, want %.15g", dbl ? "double" : "float",
                  e[s].R.mean, want);
        if (dbl) CHECK(fabs(e[0].R.mean - 0.1f) > (0.5 / LSQT_FIX_SCALE), "double run got the float parameter: R = %.15g", e[0].R.mean);
        lsqt_estimates_free(e, 2);
        lsqt_state_free(&st);
    }
}

static void test_slab(void)
{
    const double deg[] = {0, 45, 80};
    lsqt_state st;
    lsqt_slice_est *e = fixture_run("Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0\n"
                                    "Layer z=0 NullBsdf\nMedium\n",
                                    3, deg, 256, 20000, 2, &st);
    lsqt_state coarse;
    lsqt_slice_est *ec_est = fixture_run("Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0\n"
                                         "Layer z=0 NullBsdf\nMedium\n",
                                         3, deg, 64, 20000, 2, &coarse);
    CHECK(st.transmits, "a null slab transmits");
    for (int s = 0; s < 3; s++) {
        double sig = sqrt(e[s].R.err * e[s].R.err + e[s].T.err * e[s].T.err);
        /* iadpython adding-doubling at normal incidence (tools/validate/refs_closed.py, the
         * isotropic slab mus=1 d=1). */
        if (s == 0) CHECK_Z(e[s].R.mean, 0.3413287, e[s].R.err, 3.0);
        CHECK(fabs(e[s].R.mean + e[s].T.mean - 1.0) <= 3 * sig + 1e-9, "slice %d: R + T = %.9g", s,
              e[s].R.mean + e[s].T.mean);
        CHECK(e[s].R.err > 0 && e[s].R.mean > 0.2 && e[s].R.mean < 0.8, "slice %d: R = %g +- %g", s, e[s].R.mean,
              e[s].R.err);
        /* The unscattered part is exactly exp(-tau / cos). */
        double dt = exp(-1.0 / cos(deg[s] * PI / 180));
        CHECK_Z(e[s].delta_T.mean, dt, e[s].delta_T.err, 4.0);
        check_hist_total(&st, s);
        /* Point estimates and the analog exits agree: the integral of f cos over the
         * upper hemisphere is R. The isotropic slab's f depends on wi only through
         * cos theta_i, and the direction set is a midpoint rule in cos theta_i, whose
         * error falls at least as 1/n: the difference between the 256- and the
         * 64-direction rules (same paths, so the noise mostly cancels) bounds the error
         * of the 256 one. */
        lsqt_est diff = nee_albedo_minus(&st, s, 1, 1.0, LSQT_T_R);
        double rn = nee_albedo_minus(&st, s, 1, 0.0, LSQT_T_R).mean, quad = fabs(rn - nee_albedo_minus(&coarse, s, 1, 0.0, LSQT_T_R).mean);
        CHECK(fabs(diff.mean) <= 4 * diff.err + quad, "slice %d: NEE albedo - R = %.3g +- %.2g (quadrature %.2g)", s,
              diff.mean, diff.err, quad);
        CHECK(quad < 0.01 * rn, "slice %d: the 64- and 256-direction rules differ by %.3g", s, quad);
    }
    lsqt_estimates_free(ec_est, 3);
    lsqt_state_free(&coarse);
    lsqt_estimates_free(e, 3);
    lsqt_state_free(&st);

    /* With absorption energy is lost, by far more than the noise. */
    e = fixture_run("Medium\nLayer z=1 NullBsdf\nMedium mua=0.5 mus=1 HenyeyGreensteinPhase g=0.5\n"
                    "Layer z=0 NullBsdf\nMedium\n",
                    1, deg, 32, 20000, 3, &st);
    double sig = sqrt(e[0].R.err * e[0].R.err + e[0].T.err * e[0].T.err);
    CHECK_Z(e[0].R.mean, 0.0771444, e[0].R.err, 3.0); /* iadpython, as above */
    CHECK_Z(e[0].T.mean, 0.4455289, e[0].T.err, 3.0);
    CHECK(e[0].R.mean + e[0].T.mean < 1.0 - 10 * sig, "absorbing slab: R + T = %.6g +- %.2g",
          e[0].R.mean + e[0].T.mean, sig);
    lsqt_estimates_free(e, 1);
    lsqt_state_free(&st);
}

static void test_adding(void)
{
    /* Two Lambertian layers in vacuum: R = R1 + T1^2 R2 / (1 - R1 R2) for any incidence. */
    const double deg[] = {0, 50, 85};
    const double R1 = 0.3, T1 = 0.5, R2 = 0.6, expect = R1 + T1 * T1 * R2 / (1 - R1 * R2);
    lsqt_state st;
    lsqt_slice_est *e = fixture_run("Medium\nLayer z=1 LambertianBsdf fR=0.3 fT=0.5\nMedium\n"
                                    "Layer z=0 LambertianBsdf fR=0.6\nMedium\n",
                                    3, deg, 48, 20000, 4, &st);
    for (int s = 0; s < 3; s++) {
        CHECK_Z(e[s].R.mean, expect, e[s].R.err, 3.0);
        CHECK(e[s].T.mean == 0.0, "T = %g", e[s].T.mean);
        /* f is constant here and the directions are a midpoint rule in cos theta_i, exact
         * for f cos: only the noise is left. */
        lsqt_est rn = nee_albedo_minus(&st, s, 1, 0.0, LSQT_T_R);
        CHECK_Z(rn.mean, expect, rn.err, 4.0);
    }
    lsqt_estimates_free(e, 3);
    lsqt_state_free(&st);
}

/* The same paths whatever the split into runs and the work-group size. */
static void test_reproducible(void)
{
    const char *text = "Medium\nLayer z=1 NullBsdf\nMedium mus=2 mua=0.1 HenyeyGreensteinPhase g=0.3\n"
                       "Layer z=0 LambertianBsdf fR=0.5 fT=0.2\nMedium\n";
    const double deg[] = {10, 70};
    lsqt_state one, split;
    lsqt_slice_est *e1 = fixture_run(text, 2, deg, 16, 5000, 9, &one);
    lsqt_slice_est *e2 = fixture_run(text, 2, deg, 16, 1234, 9, &split);
    lsqt_assembly a;
    lsqt_diag d;
    memset(&d, 0, sizeof d);
    lsqt_parse(text, strlen(text), "t", NULL, 1, NULL, &a, &d);
    lsqt_sim_opts o = {0, 0.0, 32, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
    lsqt_sim_stats stats;
    char err[512];
    CHECK(lsqt_simulate(&fixture_cx, &a, &split, 5000 - 1234, &o, &stats, err, sizeof err) == 0, "%s", err);
    CHECK(split.paths == one.paths, "%llu paths", (unsigned long long)split.paths);
    CHECK(memcmp(one.nee, split.nee, lsqt_state_nee_count(&one) * sizeof *one.nee) == 0, "point-estimate tallies differ");
    CHECK(memcmp(one.scalars, split.scalars, lsqt_state_scalar_count(&one) * sizeof *one.scalars) == 0, "R/T tallies differ");
    CHECK(memcmp(one.hist, split.hist, lsqt_state_hist_count(&one) * sizeof *one.hist) == 0, "histograms differ");
    /* The 32-bit-atomics fallback (devices without cl_khr_int64_base_atomics) sums the
     * same integers. */
    lsqt_state st32;
    lsqt_state_init(&st32, one.canonical, one.hash, one.seed, 2, 16, one.transmits, 1, NULL);
    memcpy(st32.theta_o, one.theta_o, sizeof(double) * 2);
    memcpy(st32.wi, one.wi, sizeof(float) * 2 * 16 * 4);
    lsqt_sim_opts o32 = {0, 0.0, 0, NULL, "-DLSQT_NO_INT64_ATOMICS=1", 0, 0.0, 0.0, NULL, NULL, NULL};
    CHECK(lsqt_simulate(&fixture_cx, &a, &st32, 5000, &o32, &stats, err, sizeof err) == 0, "%s", err);
    CHECK(memcmp(one.nee, st32.nee, lsqt_state_nee_count(&one) * sizeof *one.nee) == 0, "32-bit atomics: tallies differ");
    CHECK(memcmp(one.scalars, st32.scalars, lsqt_state_scalar_count(&one) * sizeof *one.scalars) == 0, "32-bit atomics: R/T differ");
    CHECK(memcmp(one.hist, st32.hist, lsqt_state_hist_count(&one) * sizeof *one.hist) == 0, "32-bit atomics: histograms differ");
    lsqt_state_free(&st32);
    /* ... and another seed gives other paths. */
    lsqt_state other;
    lsqt_slice_est *e3 = fixture_run(text, 2, deg, 16, 5000, 10, &other);
    CHECK(memcmp(one.scalars, other.scalars, lsqt_state_scalar_count(&one) * sizeof *one.scalars) != 0, "seed has no effect");
    lsqt_assembly_free(&a);
    lsqt_estimates_free(e1, 2);
    lsqt_estimates_free(e2, 2);
    lsqt_estimates_free(e3, 2);
    lsqt_state_free(&one);
    lsqt_state_free(&split);
    lsqt_state_free(&other);
}

/* Extremes: grazing theta_o, thin and thick layers far from z = 0,
 * g near +-1, optically thick media: never NaN, Inf or negative, never more than 1, and
 * no path cut by the safety cap. (Optical thickness 1e4 is in tools/validate: its
 * lossless paths need ~1e4 events on average, too slow for a unit test.) */
static void test_extremes(void)
{
    const char *cases[] = {
        "Medium\nLayer z=1000001 NullBsdf\nMedium mus=1e-4 HenyeyGreensteinPhase g=0.999\nLayer z=1 NullBsdf\n"
        "Medium\nLayer z=0 LambertianBsdf fR=1\nMedium\n",
        "Medium\nLayer z=1000000.000001 NullBsdf\nMedium mus=1e4 mua=1e3 HenyeyGreensteinPhase g=-0.999\n"
        "Layer z=1e6 LambertianBsdf fR=0 fT=1\nMedium\n",
        "Medium\nLayer z=1 NullBsdf\nMedium mus=1e3 HenyeyGreensteinPhase g=0.9\nLayer z=0 NullBsdf\nMedium\n",
        "Medium\nLayer z=0 LambertianBsdf fR=0 fT=0\nMedium\n",
    };
    const double deg[] = {0, 89.9};
    for (int i = 0; i < 4; i++) {
        lsqt_state st;
        lsqt_slice_est *e = fixture_run(cases[i], 2, deg, 16, 1000, 5, &st);
        for (int s = 0; s < 2; s++) {
            double sig = sqrt(e[s].R.err * e[s].R.err + e[s].T.err * e[s].T.err);
            CHECK(isfinite(e[s].R.mean) && isfinite(e[s].T.mean) && e[s].R.mean >= 0 && e[s].T.mean >= 0,
                  "case %d slice %d: R %g T %g", i, s, e[s].R.mean, e[s].T.mean);
            CHECK(e[s].R.mean + e[s].T.mean <= 1.0 + 3 * sig + 1e-7, "case %d slice %d: R + T = %.9g", i, s,
                  e[s].R.mean + e[s].T.mean);
            CHECK(e[s].n_nonfinite == 0, "case %d: %d non-finite estimates", i, e[s].n_nonfinite);
            CHECK(e[s].cut == 0, "case %d: %llu paths cut", i, (unsigned long long)e[s].cut);
            for (int k = 0; k < st.n_wi; k++)
                CHECK(e[s].f[k].mean >= 0 && isfinite(e[s].f[k].mean), "case %d: f[%d] = %g", i, k, e[s].f[k].mean);
        }
        CHECK(st.flags == 0, "case %d: flags %u", i, st.flags);
        if (i == 3) CHECK(e[0].R.mean == 0 && e[0].T.mean == 0, "black layer: R %g T %g", e[0].R.mean, e[0].T.mean);
        lsqt_estimates_free(e, 2);
        lsqt_state_free(&st);
    }
    /* mus -> 0 is a clear medium: everything passes as the forward delta. */
    lsqt_state st;
    lsqt_slice_est *e = fixture_run("Medium\nLayer z=1 NullBsdf\nMedium mus=1e-9 HenyeyGreensteinPhase\n"
                                    "Layer z=0 NullBsdf\nMedium\n",
                                    2, deg, 16, 1000, 6, &st);
    CHECK(fabs(e[0].delta_T.mean - 1.0) < 1e-6 && fabs(e[1].T.mean - 1.0) < 1e-6, "delta_T %.9g, T %.9g",
          e[0].delta_T.mean, e[1].T.mean);
    lsqt_estimates_free(e, 2);
    lsqt_state_free(&st);
}

int main(void)
{
    fixture_open();
    test_lambertian();
    test_work_counters();
    test_roulette_exit();
    test_double_tables();
    test_slab();
    test_adding();
    test_reproducible();
    test_extremes();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_simulate");
}
