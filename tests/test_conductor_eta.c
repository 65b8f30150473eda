/* Power test: MicrosurfaceConductiveBrdf with eta > k (weakly
 * absorbing metals, semiconductors, a metal under a dense medium), where the Fresnel
 * reflectance of the complex index is not that of a good conductor: the real part of
 * n^2 - sin^2 is positive (or changes sign with the angle when eta < 1), so a formula or a
 * branch that is right only for k > eta shows here and nowhere else in the suite.
 *
 * References, written here, double precision:
 *   - fres(): the exact unpolarised Fresnel reflectance of a complex relative index n from
 *     Snell's law with complex angles: n cos t = the root of n^2 - sin^2 i with a
 *     non-negative real part (the wave that decays into the metal),
 *       rs = (cos i - n cos t) / (cos i + n cos t),  rp = (n cos i - cos t) / (n cos i + cos t),
 *     checked against ref_conductor.h's form (n^2 c - t)/(n^2 c + t), normal incidence
 *     |(n - 1)/(n + 1)|^2 and the real-index (dielectric) Fresnel law;
 *   - ref_f() of tests/ref_conductor.h (independent GGX conductor: D, Smith Lambda,
 *     height-correlated G2) for the single-scattering values.
 * Checks:
 *   (a) harness_eval's f at 32 direction pairs (wo from 0 to 89 degrees, specular and off)
 *       for 5 complex indices with eta > k, alpha 0.1, 0.4, 1.2, float and double, against
 *       ref_f: relative tolerance 1e-4 (float), 2e-5 (double): deterministic;
 *   (b) the smooth limit alpha = 1e-4 end to end (LSQT text, host tables, the walk, exit
 *       tallies), single and multiple scattering, 6 assemblies (a medium of index 1.33, 1.5
 *       or 2 above: the relative index changes, down to 0.75 + 0.05i), theta_o 0 to 89
 *       degrees: R(theta_o) = fres(n, cos theta_o) within 4.5 sigma plus (2 alpha^2 tan^2 +
 *       2e-6) F (the roughness left, 3.3e-5 at 89 degrees, and float); Bonferroni over the
 *       checks;
 *   (c) the directional albedo R(theta_o) with multiple scattering on (4 assemblies, theta_o
 *       0, 60, 80 degrees, 1e6 paths a slice) against the independent numpy random walk of
 *       tools/validate/heitz_walk.py (its own complex-sqrt Fresnel; 2e6 walks a slice,
 *       precomputed into tests/data/conductor_eta_heitz.txt by
 *       `python3 tests/data/gen_conductor_eta_heitz.py`, numpy not needed here): within 4.5
 *       sigma of the two errors combined.
 * One family: 72 + 12 statistical checks at 4.5 sigma (6.8e-6 each): 84 x 6.8e-6 < 1e-3. */
#include <complex.h>

#include "cl_fixture.h"
#include "ref_conductor.h"

#ifndef HEITZ_PATHS
#define HEITZ_PATHS 1000000
#endif

/* The exact Fresnel reflectance through complex Snell's law (see above). */
static double fres(double complex n, double c)
{
    double s2 = 1.0 - c * c;
    double complex nct = csqrt(n * n - s2); /* n cos t, principal root: Re >= 0 */
    if (creal(nct) < 0) nct = -nct;
    double complex ct = nct / n;
    double complex rs = (c - nct) / (c + nct), rp = (n * c - ct) / (n * c + ct);
    return 0.5 * (creal(rs * conj(rs)) + creal(rp * conj(rp)));
}

static double fres_dielectric(double eta, double c)
{
    double s2 = (1 - c * c) / (eta * eta);
    if (s2 >= 1) return 1.0;
    double ct = sqrt(1 - s2), rs = (c - eta * ct) / (c + eta * ct), rp = (eta * c - ct) / (eta * c + ct);
    return 0.5 * (rs * rs + rp * rp);
}

static cl_program build(int dbl)
{
    return fixture_build("-cl-std=CL1.2 -DLSQT_HAS_BSDF_MS_CONDUCTIVE=1%s", dbl ? " -DLSQT_DOUBLE=1" : "");
}

/* The kernel's f (cosine of wi included) at direction pairs through harness_eval. */
static void kernel_f(cl_program prog, int dbl, double a, double eta, double k, const double (*wo)[3],
                     const double (*wi)[3], int n, double *out)
{
    const lsqt_dev_layer_d L = {.kind = LSQT_BSDF_MS_CONDUCTIVE, .p = {a, eta, k}};
    fixture_eval_pairs(prog, dbl, &L, 0.0, n, wo, wi, out, NULL);
}

static void unit_dir(double theta, double phi, double v[3])
{
    v[0] = sin(theta) * cos(phi), v[1] = sin(theta) * sin(phi), v[2] = cos(theta);
}

/* The complex indices relative to the medium above, all with eta > k. */
static const double IDX[][2] = {{3.0, 0.1}, {1.5, 0.01}, {4.0, 2.0}, {0.75, 0.05}, {2.6666667, 1.3333333}};
enum { NIDX = sizeof IDX / sizeof IDX[0] };

static void test_reference(void)
{
    for (int i = 0; i < NIDX; i++) {
        double complex n = IDX[i][0] + IDX[i][1] * I;
        double r0 = cabs((n - 1) / (n + 1));
        CHECK(fabs(fres(n, 1.0) - r0 * r0) < 1e-13, "fres normal incidence");
        for (int j = 0; j <= 100; j++) {
            double c = j / 100.0;
            CHECK(fabs(fres(n, c) - ref_fresnel(n, c)) < 1e-12, "fres vs ref_fresnel at n %g%+gi c %g: %.15g vs %.15g",
                  creal(n), cimag(n), c, fres(n, c), ref_fresnel(n, c));
        }
    }
    for (int j = 0; j <= 100; j++) {
        double c = j / 100.0;
        CHECK(fabs(fres(1.5, c) - fres_dielectric(1.5, c)) < 1e-13 && fabs(fres(0.75, c) - fres_dielectric(0.75, c)) < 1e-13,
              "fres of a real index at c %g", c);
    }
}

/* (a) single-scattering values against ref_f. */
static void test_values(void)
{
    const double alphas[] = {0.1, 0.4, 1.2};
    const double tdeg[] = {0, 30, 50, 65, 75, 82, 87, 89};
    enum { NP = 32 };
    double wo[NP][3], wi[NP][3], got[NP];
    cl_program progs[2] = {build(0), fixture_cx.dev.has_fp64 ? build(1) : NULL};
    for (int ia = 0; ia < 3; ia++) {
        const double a = alphas[ia];
        for (int t = 0; t < 8; t++) {
            double to = tdeg[t] * PI / 180;
            int i = 4 * t;
            unit_dir(to, 0, wo[i]), unit_dir(to, PI, wi[i]);                 /* the mirror direction */
            unit_dir(to, 0, wo[i + 1]), unit_dir(0.5 * to, PI, wi[i + 1]);   /* towards the normal */
            unit_dir(to, 0, wo[i + 2]), unit_dir(PI / 3, 0.5 * PI, wi[i + 2]); /* sideways */
            unit_dir(to, 0, wo[i + 3]), unit_dir(85 * PI / 180, 0.8 * PI, wi[i + 3]); /* grazing out */
        }
        for (int dbl = 0; dbl < 2; dbl++) {
            if (!progs[dbl]) continue;
            for (int c = 0; c < NIDX; c++) {
                const double eta = IDX[c][0], k = IDX[c][1];
                kernel_f(progs[dbl], dbl, a, eta, k, (const double(*)[3])wo, (const double(*)[3])wi, NP, got);
                double worst = 0;
                for (int i = 0; i < NP; i++) {
                    double o[3], w[3];
                    for (int q = 0; q < 3; q++) o[q] = (float)wo[i][q], w[q] = (float)wi[i][q];
                    /* the harness normalises wo after its rounding to float (not wi); at
                     * 87-89 degrees the rounding of the directions tilts the mirror pair's
                     * half vector by ~1e-6 rad, which moves F(wo.h) by up to 4e-6 relative
                     * (seen in float and double alike): hence 2e-5 in double */
                    double lo = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
                    for (int q = 0; q < 3; q++) o[q] /= lo;
                    /* the index as the kernel holds it */
                    double complex n = dbl ? eta + k * I : (double)(float)eta + (double)(float)k * I;
                    double want = ref_f(a, n, o, w), rel = fabs(got[i] - want) / fmax(want, 1e-300);
                    worst = fmax(worst, rel);
                    CHECK(want > 0 && rel <= (dbl ? 2e-5 : 1e-4), "alpha %g n %g%+gi %s pair %d (wo.z %.4f wi.z %.4f): f %.9g vs %.9g (rel %.2g)",
                          a, eta, k, dbl ? "double" : "float", i, o[2], w[2], got[i], want, rel);
                }
                printf("values alpha %-4g n %.4g%+.4gi %s: %d pairs, worst relative difference %.2g\n", a, eta, k,
                       dbl ? "double" : "float ", NP, worst);
            }
        }
    }
    for (int d = 0; d < 2; d++)
        if (progs[d]) clReleaseProgram(progs[d]);
}

/* (b) the smooth limit end to end. */
static void test_smooth(void)
{
    static const struct {
        double above, eta, mua;
    } cs[] = {{1.0, 3.0, 0.1}, {1.0, 1.5, 0.01}, {1.0, 4.0, 2.0}, {1.33, 3.0, 0.1}, {2.0, 1.5, 0.1}, {1.5, 4.0, 2.0}};
    const double deg[] = {0, 40, 60, 75, 85, 89};
    double worst = 0, share = 0;
    for (int ms = 0; ms < 2; ms++)
        for (int c = 0; c < 6; c++) {
            char text[256];
            snprintf(text, sizeof text,
                     "Medium eta=%g\nLayer z=0 MicrosurfaceConductive alpha=1e-4 use_multiple_scattering=%s\n"
                     "Medium eta=%g mua=%g\n",
                     cs[c].above, ms ? "true" : "false", cs[c].eta, cs[c].mua);
            double complex n = (cs[c].eta + cs[c].mua * I) / cs[c].above;
            lsqt_state st;
            lsqt_slice_est *e = fixture_run(text, 6, deg, 8, ms ? 400000 : 40000, 700 + 10 * (uint64_t)c + (uint64_t)ms, &st);
            CHECK(!st.transmits && st.flags == 0, "case %d: transmits %d flags %u", c, st.transmits, st.flags);
            for (int s = 0; s < 6; s++) {
                double F = fres(n, cos(deg[s] * PI / 180)), z = (e[s].R.mean - F) / fmax(e[s].R.err, 1e-300);
                worst = fmax(worst, fabs(e[s].R.mean - F) / F);
                /* what alpha 1e-4 leaves: O(alpha^2 tan^2 theta) (3.3e-5 at 89 degrees),
                 * allowed twice, plus float rounding */
                double t2 = pow(1e-4 * tan(deg[s] * PI / 180), 2), allow = 4.5 * e[s].R.err + (2 * t2 + 2e-6) * F;
                share = fmax(share, fabs(e[s].R.mean - F) / allow);
                CHECK(fabs(e[s].R.mean - F) <= allow,
                      "smooth %s n %.5g%+.5gi (above %g) theta_o %g: R %.8f +- %.2g vs Fresnel %.8f (rel %.2g, z %.2f)",
                      ms ? "MS" : "SS", creal(n), cimag(n), cs[c].above, deg[s], e[s].R.mean, e[s].R.err, F,
                      (e[s].R.mean - F) / F, z);
            }
            printf("smooth %s n %.4f%+.4fi: R(0) %.6f +- %.1e vs F %.6f; R(89) %.6f +- %.1e vs F %.6f\n", ms ? "MS" : "SS",
                   creal(n), cimag(n), e[0].R.mean, e[0].R.err, fres(n, 1), e[5].R.mean, e[5].R.err,
                   fres(n, cos(89 * PI / 180)));
            lsqt_estimates_free(e, 6);
            lsqt_state_free(&st);
        }
    printf("smooth limit: worst relative difference %.2g, largest share of the allowance %.2f\n", worst, share);
}

/* (c) the directional albedo with multiple scattering against the independent numpy
 * random walk (tools/validate/heitz_walk.py, 2e6 walks a slice, kept in
 * tests/data/conductor_eta_heitz.txt by tests/data/gen_conductor_eta_heitz.py):
 * |R - R_walk| <= 4.5 sqrt(err^2 + err_walk^2). */
static void test_heitz(void)
{
    char path[512];
    snprintf(path, sizeof path, "%s/conductor_eta_heitz.txt", LSQT_TEST_DATA);
    FILE *f = fopen(path, "r");
    CHECK(f != NULL, "cannot open %s", path);
    if (!f) return;
    char line[256];
    int rows = 0;
    double worst = 0;
    struct {
        double above, eta, mua, alpha, deg, R, err;
    } r[3];
    int nr = 0, ncase = 0;
    for (;;) {
        int ok = fgets(line, sizeof line, f) != NULL;
        if (ok && line[0] == '#') continue;
        if (ok) {
            CHECK(sscanf(line, "%lf %lf %lf %lf %lf %lf %lf", &r[nr].above, &r[nr].eta, &r[nr].mua, &r[nr].alpha,
                         &r[nr].deg, &r[nr].R, &r[nr].err) == 7,
                  "bad line: %s", line);
            nr++, rows++;
        }
        if (nr < 3 && ok) continue;
        if (nr == 0) break;
        /* one assembly, its three angles in one run */
        char text[256];
        snprintf(text, sizeof text,
                 "Medium eta=%g\nLayer z=0 MicrosurfaceConductive alpha=%g use_multiple_scattering=true\n"
                 "Medium eta=%g mua=%g\n",
                 r[0].above, r[0].alpha, r[0].eta, r[0].mua);
        double deg[3];
        for (int i = 0; i < nr; i++) deg[i] = r[i].deg;
        lsqt_state st;
        lsqt_slice_est *e = fixture_run(text, nr, deg, 8, HEITZ_PATHS, 900 + (uint64_t)ncase, &st);
        CHECK(st.flags == 0, "flags %u", st.flags);
        for (int i = 0; i < nr; i++) {
            double sig = sqrt(e[i].R.err * e[i].R.err + r[i].err * r[i].err), d = e[i].R.mean - r[i].R;
            worst = fmax(worst, fabs(d) / r[i].R);
            CHECK(fabs(d) <= 4.5 * sig, "MS n %.4g%+.4gi alpha %g theta_o %g: R %.6f +- %.1e vs walk %.6f +- %.1e (rel %.2g, z %.2f)",
                  r[i].eta / r[i].above, r[i].mua / r[i].above, r[i].alpha, r[i].deg, e[i].R.mean, e[i].R.err, r[i].R,
                  r[i].err, d / r[i].R, d / sig);
            printf("MS n %.4g%+.4gi alpha %g theta_o %2g: R %.6f +- %.1e vs walk %.6f +- %.1e (z %+.2f)\n",
                   r[i].eta / r[i].above, r[i].mua / r[i].above, r[i].alpha, r[i].deg, e[i].R.mean, e[i].R.err, r[i].R,
                   r[i].err, d / sig);
        }
        lsqt_estimates_free(e, nr);
        lsqt_state_free(&st);
        nr = 0, ncase++;
        if (!ok) break;
    }
    fclose(f);
    CHECK(rows == 12, "%d reference rows", rows);
    printf("multiple scattering vs the walk: worst relative difference %.2g\n", worst);
}

int main(void)
{
    fixture_open();
    test_reference();
    test_values();
    test_smooth();
    test_heitz();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_conductor_eta");
}
