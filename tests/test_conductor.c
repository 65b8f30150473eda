/* MicrosurfaceConductiveBrdf, single scattering, against an independent double-precision
 * implementation written here from the formulas (not from the kernel):
 *   f |cos i| = F(wo.h) D(h) G2(wo, wi) / (4 cos o),  G2 = 1 / (1 + L(wo) + L(wi)),
 *   D = a^2 / (pi ((a^2 - 1) cos^2 h + 1)^2),  L = (sqrt(1 + a^2 tan^2) - 1) / 2,
 *   F from the Fresnel amplitudes of the complex index n = eta + i k (complex.h):
 *   rs = (c - t)/(c + t), rp = (n^2 c - t)/(n^2 c + t), t = sqrt(n^2 - sin^2).
 * Checks: values at many direction pairs (float kernel to 1e-2 relative, double kernel
 * to 1e-3), reciprocity, the end-to-end albedo R(theta_o) of Silver against quadrature
 * of the reference, the smooth limit R = F(cos theta_o), and finite RAW everywhere. */
#include "cl_fixture.h"
#include "ref_conductor.h"

static cl_program build(int dbl)
{
    return fixture_build("-cl-std=CL1.2 -DLSQT_HAS_BSDF_MS_CONDUCTIVE=1%s", dbl ? " -DLSQT_DOUBLE=1" : "");
}

/* The kernel's f at direction pairs through harness_eval, in float or double. */
static void kernel_f(cl_program prog, int dbl, double a, double eta, double k, const double (*wo)[3],
                     const double (*wi)[3], int n, double *out)
{
    if (!prog) return;
    const lsqt_dev_layer_d L = {.kind = LSQT_BSDF_MS_CONDUCTIVE, .p = {a, eta, k}};
    fixture_eval_pairs(prog, dbl, &L, 0.0, n, wo, wi, out, NULL);
}

static void unit_dir(double theta, double phi, double v[3])
{
    v[0] = sin(theta) * cos(phi), v[1] = sin(theta) * sin(phi), v[2] = cos(theta);
}

/* >= 20 pairs per roughness: values, and reciprocity f(a->b)/cos b = f(b->a)/cos a. */
static void test_values(void)
{
    const double alphas[] = {0.05, 0.3, 1.0, 2.4};
    const double eta = 0.051585, k = 3.9046; /* silver, as in Silver.lsqt */
    enum { NP = 24 };
    double wo[2 * NP][3], wi[2 * NP][3], got[2 * NP], want[2 * NP];
    cl_program progs[2] = {build(0), fixture_cx.dev.has_fp64 ? build(1) : NULL};
    for (int ia = 0; ia < 4; ia++) {
        const double a = alphas[ia];
        for (int i = 0; i < NP; i++) {
            /* pairs from near-specular to far off it, up to grazing */
            double to = (i % 6) * 0.29, ti = ((i * 7) % 11) * 0.14, dphi = PI * (0.97 - (i % 4) * 0.31);
            if (a < 0.1) ti = to + 0.02 * (i % 3), dphi = PI * (1.0 - 0.01 * (i % 5)); /* near the narrow lobe */
            unit_dir(to, 0, wo[i]);
            unit_dir(ti, dphi, wi[i]);
            memcpy(wo[NP + i], wi[i], sizeof wo[i]); /* the reversed pair */
            memcpy(wi[NP + i], wo[i], sizeof wi[i]);
        }
        for (int dbl = 0; dbl < 2; dbl++) {
            if (dbl && !fixture_cx.dev.has_fp64) continue;
            kernel_f(progs[dbl], dbl, a, eta, k, (const double(*)[3])wo, (const double(*)[3])wi, 2 * NP, got);
            double worst = 0;
            for (int i = 0; i < 2 * NP; i++) {
                /* the kernel sees float directions: evaluate the reference at them */
                double o[3], w[3];
                for (int c = 0; c < 3; c++) o[c] = (float)wo[i][c], w[c] = (float)wi[i][c];
                want[i] = ref_f(a, eta + k * I, o, w);
                double rel = fabs(got[i] - want[i]) / fmax(want[i], 1e-300);
                worst = fmax(worst, rel);
                CHECK(want[i] > 0 && rel <= (dbl ? 1e-3 : 1e-2), "alpha %g %s pair %d: f %.9g vs reference %.9g", a,
                      dbl ? "double" : "float", i, got[i], want[i]);
            }
            for (int i = 0; i < NP; i++) {
                double r1 = got[i] / wi[i][2], r2 = got[NP + i] / wi[NP + i][2];
                /* the harness normalises wo (not wi) after its rounding to float, so the two
                 * evaluations see directions that differ by float rounding (6e-8) */
                /* (the narrow lobe of alpha 0.05 turns that into 2e-4 in float, 1e-6 in double) */
                CHECK(fabs(r1 - r2) <= (dbl ? 1e-5 : 1e-3) * fmax(r1, r2), "alpha %g: reciprocity %.9g vs %.9g", a,
                      r1, r2);
            }
            printf("conductor alpha %-4g %s: %d values, worst relative difference %.2g\n", a, dbl ? "double" : "float ",
                   2 * NP, worst);
        }
    }
    /* The peak of a smooth surface, alpha 1e-4, at the mirror direction (normal and 60
     * degrees): 1/(pi alpha^2) = 3.2e7 times F G2 / (4 cos), finite in float too. */
    for (int dbl = 0; dbl < 2; dbl++) {
        if (!progs[dbl]) continue;
        double po[2][3] = {{0, 0, 1}, {sin(PI / 3), 0, cos(PI / 3)}}, pi_[2][3] = {{0, 0, 1}, {-sin(PI / 3), 0, cos(PI / 3)}};
        kernel_f(progs[dbl], dbl, 1e-4, eta, k, (const double(*)[3])po, (const double(*)[3])pi_, 2, got);
        for (int i = 0; i < 2; i++) {
            double o[3], w[3];
            for (int c = 0; c < 3; c++) o[c] = (float)po[i][c], w[c] = (float)pi_[i][c];
            double r = ref_f(1e-4, eta + k * I, o, w);
            /* float: cos of h at the peak is 1 - O(1e-8), which moves D by up to 10 %
             * there; double is exact to 1e-6 */
            CHECK(isfinite(got[i]) && fabs(got[i] - r) <= (dbl ? 1e-6 : 0.1) * r, "alpha 1e-4 peak %s: f %.9g vs %.9g",
                  dbl ? "double" : "float", got[i], r);
        }
    }
    for (int d = 0; d < 2; d++)
        if (progs[d]) clReleaseProgram(progs[d]);
}

/* End to end: R(theta_o) of Silver from the exit tallies equals the reference albedo
 * (every path reflects once, weight F G2/G1), RAW f equals the reference at every
 * direction (one bounce from -wo: the estimate is exact up to float), all finite. */
static void test_silver(void)
{
    const double deg[] = {0, 45, 80};
    lsqt_state st;
    lsqt_slice_est *e = fixture_run("Medium\nLayer z=0 MicrosurfaceConductive alpha=0.2\nMedium eta=0.051585 mua=3.9046\n",
                                    3, deg, 64, 100000, 31, &st);
    CHECK(!st.transmits, "a conductor transmits nothing");
    for (int s = 0; s < 3; s++) {
        double th = deg[s] * PI / 180, alb = ref_albedo(0.2, 0.051585 + 3.9046 * I, th, 32),
               alb2 = ref_albedo(0.2, 0.051585 + 3.9046 * I, th, 64);
        /* converged to 1e-5, far below the noise of R (6e-4) */
        CHECK(fabs(alb - alb2) < 1e-5, "reference albedo not converged: %.9g vs %.9g", alb, alb2);
        CHECK_Z(e[s].R.mean, alb2, e[s].R.err, 4.0);
        double wo[3] = {sin(th), 0, cos(th)}, worst = 0;
        for (int k = 0; k < st.n_wi; k++) {
            const float *w = st.wi + ((size_t)s * 64 + (size_t)k) * 4;
            double wi[3] = {w[0], w[1], w[2]}, wof[3] = {(float)wo[0], 0, (float)wo[2]};
            double want = ref_f(0.2, 0.051585 + 3.9046 * I, wof, wi) / wi[2];
            CHECK(isfinite(e[s].f[k].mean) && e[s].f[k].mean >= 0, "f[%d] = %g", k, e[s].f[k].mean);
            double rel = fabs(e[s].f[k].mean - want) / want;
            worst = fmax(worst, rel);
            CHECK(rel < 1e-4, "theta_o %g wi.z %.3f: RAW f %.9g vs reference %.9g", deg[s], wi[2], e[s].f[k].mean, want);
        }
        printf("Silver theta_o %2.0f: R %.6f +- %.2g, reference albedo %.6f; RAW vs reference worst %.2g\n", deg[s],
               e[s].R.mean, e[s].R.err, alb2, worst);
    }
    lsqt_estimates_free(e, 3);
    lsqt_state_free(&st);
}

/* alpha = 1e-3 is a mirror: R(theta_o) = F(cos theta_o) of the complex index. What the
 * roughness leaves is O(alpha^2 tan^2) < 1e-4 at 80 degrees. */
static void test_smooth_limit(void)
{
    const double deg[] = {0, 45, 80};
    const double complex n = 0.2 + 3.0 * I; /* relative to eta 1.5 above: 0.3 + 4.5 i */
    lsqt_state st;
    lsqt_slice_est *e = fixture_run("Medium eta=1.5\nLayer z=0 MicrosurfaceConductive alpha=1e-3\nMedium eta=0.3 mua=4.5\n",
                                    3, deg, 16, 20000, 32, &st);
    for (int s = 0; s < 3; s++) {
        double want = ref_fresnel(n, cos(deg[s] * PI / 180));
        CHECK(fabs(e[s].R.mean - want) <= 3 * e[s].R.err + 1e-4, "theta_o %g: R %.7f +- %.2g vs F %.7f", deg[s],
              e[s].R.mean, e[s].R.err, want);
    }
    lsqt_estimates_free(e, 3);
    lsqt_state_free(&st);
}

/* Extremes: alpha 1e-4 (a peak of 1/(pi alpha^2) = 3e7 in the point
 * estimates) and 10, theta_o up to 89.9 degrees, metal index ratios from a dielectric
 * above, float and double: every value finite and non-negative, no flag (nothing
 * dropped, nothing out of the tally range), R <= 1 within 3 sigma. */
static void test_extremes(void)
{
    const char *cases[] = {
        "Medium\nLayer z=0 MicrosurfaceConductive alpha=1e-4\nMedium eta=0.051585 mua=3.9046\n",
        "Medium\nLayer z=0 MicrosurfaceConductive alpha=10\nMedium eta=0.051585 mua=3.9046\n",
        "Medium eta=4\nLayer z=0 MicrosurfaceConductive alpha=1e-4\nMedium eta=1 mua=0.01\n",
        "Medium\nLayer z=0 MicrosurfaceConductive alpha=0.5\nMedium eta=4 mua=1e3\n",
    };
    const double deg[] = {0, 60, 89.9};
    for (int dbl = 0; dbl < 2; dbl++) {
        if (dbl && !fixture_cx.dev.has_fp64) continue;
        for (int c = 0; c < 4; c++) {
            lsqt_state st;
            lsqt_slice_est *e = fixture_run_prec(cases[c], 3, deg, 64, 4096, 40 + (uint64_t)c, dbl, &st);
            int bad = 0;
            double fmax_seen = 0;
            for (int s = 0; s < 3; s++) {
                CHECK(isfinite(e[s].R.mean) && e[s].R.mean >= 0 && e[s].R.mean <= 1 + 3 * e[s].R.err + 1e-9,
                      "case %d %s slice %d: R = %.9g +- %.2g", c, dbl ? "double" : "float", s, e[s].R.mean, e[s].R.err);
                for (int k = 0; k < st.n_wi; k++) {
                    bad += !(isfinite(e[s].f[k].mean) && e[s].f[k].mean >= 0);
                    fmax_seen = fmax(fmax_seen, e[s].f[k].mean);
                }
            }
            CHECK(bad == 0 && st.flags == 0, "case %d %s: %d bad values, flags %u", c, dbl ? "double" : "float", bad,
                  st.flags);
            printf("extreme case %d %s: R %.4f %.4f %.4f, largest f %.3g\n", c, dbl ? "double" : "float ", e[0].R.mean,
                   e[1].R.mean, e[2].R.mean, fmax_seen);
            lsqt_estimates_free(e, 3);
            lsqt_state_free(&st);
        }
    }
}

int main(void)
{
    fixture_open();
    /* the reference itself: normal incidence F = |(n - 1)/(n + 1)|^2 */
    double complex n = 0.051585 + 3.9046 * I;
    CHECK(fabs(ref_fresnel(n, 1.0) - cabs((n - 1) / (n + 1)) * cabs((n - 1) / (n + 1))) < 1e-12, "ref F(0)");
    test_values();
    test_silver();
    test_smooth_limit();
    test_extremes();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_conductor");
}
