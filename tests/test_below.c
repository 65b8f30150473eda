/* Two-sided BSDFs (below.h).
 *  - mirror: an asymmetric stack turned upside down is the stack written upside down by
 *    hand, twice is the original, stacks that transmit nothing are refused;
 *  - split / join: exact round trips, a mismatch is refused;
 *  - symmetric stack (the same medium above and below, the layers mirror-symmetric about
 *    the slab's middle, here at z = 5 and 3, so turned over they sit at -3 and -5): the
 *    slices from below equal those from above at every direction. With K values,
 *    |z| <= 4.5 each (batch means of 32 batches are t-like with 31 dof: P(|t| > 4.5) is
 *    about 1e-4, times K < 100 values gives a family error below 1 %), and the chi-square
 *    sum of z^2 over K dof has p in [1e-4, 1 - 1e-4]: the upper bound catches sides that
 *    run the same paths (every z would be 0: chi-square 0);
 *  - reciprocity of a lossless asymmetric stack (rough dielectric from eta 1 into a
 *    scattering eta 1.5 slab over eta 1.5): with V the RAW value (BSDF, 1/sr, no cosine)
 *    of light coming from direction a and leaving towards b, and n_a, n_b the indices of
 *    the media a and b lie in, n_a^2 V(a -> b) = n_b^2 V(b -> a) (the radiance L / n^2
 *    is what is conserved; Veach 1997 §5.2 in the form f(a -> b) / n_b^2 = f(b -> a) / n_a^2).
 *    A slice from above at theta_o = t1, transmitted towards wi = (sin t2 cos p,
 *    sin t2 sin p, -cos t2), is light from the top (n 1) into the bottom (n 1.5); the
 *    reverse is the slice from below at theta_o = t2 (its wo is at -z in the stack's
 *    frame) towards the stack's (sin t1 cos p, -sin t1 sin p, cos t1) (turned about z by
 *    -p so its wo lies at azimuth 0), which in the mirrored view the slice from below
 *    keeps is (sin t1 cos p, sin t1 sin p, -cos t1) after the y fold: the same set of
 *    directions serves both sides, and 1^2 V_above(t1 -> (t2, p)) = 1.5^2 V_below(t2 -> (t1, p)).
 *    The same bounds as above on all the pairs;
 *  - the side from above is bit for bit the one-sided run, and the tallies are the same
 *    for work-group sizes 64 and 16. */
#include <stdint.h>

#include "cl_fixture.h"
#include "lsqt/below.h"
#include "lsqt/simulate.h"
#include "stats.h"

#define PI 3.14159265358979323846
#define Z_MAX 4.5

static void parse(const char *text, lsqt_assembly *a)
{
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    if (lsqt_parse(text, strlen(text), "test", NULL, 1, NULL, a, &diag)) {
        fprintf(stderr, "parse failed: %s\n", diag.error);
        exit(1);
    }
}

static char *canonical(const lsqt_assembly *a)
{
    size_t n = lsqt_assembly_canonical(a, NULL, 0);
    char *t = malloc(n + 1);
    lsqt_assembly_canonical(a, t, n + 1);
    return t;
}

static void test_mirror(void)
{
    lsqt_assembly a, m, mm, want;
    char err[512];
    parse("Medium eta=1\nLayer z=1 MicrosurfaceDielectricBsdf alpha=0.3 kR=0.9\n"
          "Medium eta=1.5 mus=1 HenyeyGreensteinPhase g=0.6\nLayer z=0 LambertianBsdf fR=0.2 fT=0.7\n"
          "Medium eta=1.2 mua=0 mus=0\n", &a);
    parse("Medium eta=1.2\nLayer z=0 LambertianBsdf fR=0.2 fT=0.7\n"
          "Medium eta=1.5 mus=1 HenyeyGreensteinPhase g=0.6\nLayer z=-1 MicrosurfaceDielectricBsdf alpha=0.3 kR=0.9\n"
          "Medium eta=1\n", &want);
    CHECK(lsqt_assembly_mirror(&a, &m, err, sizeof err) == 0, "%s", err);
    char *ca = canonical(&a), *cm = canonical(&m), *cw = canonical(&want);
    CHECK(strcmp(cm, cw) == 0, "mirror:\n%s\nexpected:\n%s", cm, cw);
    CHECK(lsqt_assembly_mirror(&m, &mm, err, sizeof err) == 0, "%s", err);
    char *cmm = canonical(&mm);
    CHECK(strcmp(cmm, ca) == 0, "mirror twice:\n%s\nexpected:\n%s", cmm, ca);
    free(ca), free(cm), free(cw), free(cmm);
    lsqt_assembly_free(&a), lsqt_assembly_free(&m), lsqt_assembly_free(&mm), lsqt_assembly_free(&want);

    const char *opaque[] = {"Medium\nLayer z=0 MicrosurfaceConductiveBrdf\nMedium eta=0.2 mua=3\n",
                            "Medium\nLayer z=1 LambertianBsdf fR=0.5 fT=0.5\nMedium\nLayer z=0 OrenNayarDiffuseBrdf\nMedium\n",
                            "Medium\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n"};
    for (int i = 0; i < 3; i++) {
        parse(opaque[i], &a);
        err[0] = '\0';
        CHECK(lsqt_assembly_mirror(&a, &m, err, sizeof err) == 2 && strstr(err, "transmits nothing") &&
                  m.layers == NULL,
              "opaque stack %d: '%s'", i, err);
        lsqt_assembly_free(&a);
    }
}

/* A state of A: slices at deg (ns), directions wi (nwi), both sides when two. */
static void make_state(lsqt_state *st, const lsqt_assembly *a, const double *deg, int ns, const float *wi, int nwi,
                       uint64_t seed, int two)
{
    char *c = canonical(a);
    if (lsqt_state_init(st, c, lsqt_assembly_hash(a), seed, ns, nwi, lsqt_assembly_transmits(a), 1, NULL)) exit(1);
    free(c);
    st->dir_method = LSQT_DIRS_FILE;
    for (int s = 0; s < ns; s++) {
        st->theta_o[s] = deg[s] * PI / 180.0;
        memcpy(st->wi + (size_t)s * nwi * 4, wi, (size_t)nwi * 4 * sizeof *wi);
    }
    if (two && lsqt_state_add_below(st)) exit(1);
}

static void run(const lsqt_assembly *a, lsqt_state *st, uint64_t paths, size_t local)
{
    lsqt_sim_opts o = {0, 0.0, local, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
    lsqt_sim_stats stats;
    char err[1024];
    if (lsqt_simulate(&fixture_cx, a, st, paths, &o, &stats, err, sizeof err)) {
        fprintf(stderr, "simulate failed: %s\n", err);
        exit(1);
    }
}

static int same_tallies(const lsqt_state *x, const lsqt_state *y)
{
    return x->n_slices == y->n_slices && x->paths == y->paths &&
           memcmp(x->nee, y->nee, lsqt_state_nee_count(x) * sizeof *x->nee) == 0 &&
           memcmp(x->scalars, y->scalars, lsqt_state_scalar_count(x) * sizeof *x->scalars) == 0 &&
           memcmp(x->hist, y->hist, lsqt_state_hist_count(x) * sizeof *x->hist) == 0 &&
           memcmp(x->slice_flags, y->slice_flags, (size_t)x->n_slices * sizeof *x->slice_flags) == 0 &&
           memcmp(x->wi, y->wi, (size_t)x->n_slices * x->n_wi * 4 * sizeof *x->wi) == 0;
}

static void test_split_join(void)
{
    lsqt_assembly a;
    parse("Medium\nLayer z=0 LambertianBsdf fR=0.3 fT=0.6\nMedium\n", &a);
    const double deg[] = {0, 40, 70};
    float wi[8] = {0.6f, 0, 0.8f, 0, 0, 0.6f, -0.8f, 0};
    lsqt_state st, up, dn, back;
    make_state(&st, &a, deg, 3, wi, 2, 7, 1);
    CHECK(st.n_slices == 6 && lsqt_state_below_count(&st) == 3, "add_below: %d slices, %d below", st.n_slices,
          lsqt_state_below_count(&st));
    run(&a, &st, 3000, 0);
    char err[256];
    CHECK(lsqt_state_split_by_side(&st, &up, &dn) == 0, "split");
    CHECK(up.n_slices == 3 && dn.n_slices == 3 && lsqt_state_below_count(&up) == 0 &&
              lsqt_state_below_count(&dn) == 3 && up.paths == 3000 && dn.paths == 3000 && up.n_ranges == 1 &&
              dn.ranges[1] == 3000 && dn.span_end == st.span_end,
          "split sides");
    CHECK(lsqt_state_join_by_side(&up, &dn, &back, err, sizeof err) == 0 && same_tallies(&st, &back), "join: %s", err);
    lsqt_state_free(&back);
    dn.pilot_paths = 5;
    CHECK(lsqt_state_join_by_side(&up, &dn, &back, err, sizeof err) == 1 && strstr(err, "direction method"),
          "a mismatch is refused: %s", err);
    dn.pilot_paths = up.pilot_paths;
    lsqt_state_add_range(&dn, 3000, 3256);
    CHECK(lsqt_state_join_by_side(&up, &dn, &back, err, sizeof err) == 1 && strstr(err, "paths"),
          "sides with other paths are refused: %s", err);
    lsqt_state_free(&up), lsqt_state_free(&dn), lsqt_state_free(&st);
    lsqt_assembly_free(&a);
}

/* |z| of every pair and their chi-square against the bounds; returns the chi-square. */
typedef struct {
    int k;
    double chi2, zmax;
} zsum;

static void z_add(zsum *zs, double x, double sx, double y, double sy)
{
    double s = sqrt(sx * sx + sy * sy);
    CHECK(s > 0 && isfinite(x) && isfinite(y), "value %g +- %g vs %g +- %g", x, sx, y, sy);
    if (!(s > 0)) return;
    double z = (x - y) / s;
    zs->k++, zs->chi2 += z * z;
    if (fabs(z) > zs->zmax) zs->zmax = fabs(z);
    CHECK(fabs(z) <= Z_MAX, "%.6g +- %.3g vs %.6g +- %.3g: z = %.2f", x, sx, y, sy, z);
}

static void z_report(const char *what, const zsum *zs)
{
    double p = chi2_p(zs->chi2, zs->k);
    printf("%s: %d values, max |z| %.2f, chi-square %.1f / %d dof, p = %.3g\n", what, zs->k, zs->zmax, zs->chi2, zs->k, p);
    CHECK(p >= 1e-4 && p <= 1 - 1e-4, "%s: chi-square %.2f over %d dof, p = %.3g", what, zs->chi2, zs->k, p);
}

/* Directions (sin t cos p, sin t sin p, c cos t) for t in ts, p in ps (one p at t = 0). */
static int dirs(const double *ts, int nt, const double *ps, int np, double c, float *out)
{
    int n = 0;
    for (int i = 0; i < nt; i++)
        for (int j = 0; j < (ts[i] == 0 ? 1 : np); j++) {
            double t = ts[i] * PI / 180, p = ps[j] * PI / 180;
            float *d = out + 4 * n++;
            d[0] = (float)(sin(t) * cos(p)), d[1] = (float)(sin(t) * sin(p)), d[2] = (float)(c * cos(t)), d[3] = 0;
        }
    return n;
}

static void test_symmetric(void)
{
    /* Rough interfaces between eta 1 outside and a scattering eta 1.33 slab, the top at
     * z = 5 and the bottom at z = 3. */
    lsqt_assembly a;
    parse("Medium\nLayer z=5 MicrosurfaceDielectricBsdf alpha=0.4 use_multiple_scattering=false\n"
          "Medium eta=1.33 mus=0.8 HenyeyGreensteinPhase g=0.5\n"
          "Layer z=3 MicrosurfaceDielectricBsdf alpha=0.4 use_multiple_scattering=false\nMedium\n", &a);
    const double deg[] = {0, 35, 65}, ts[] = {0, 30, 60, 80}, ps[] = {0, 90, 180};
    float wi[4 * 32];
    int n = dirs(ts, 4, ps, 3, 1, wi);
    n += dirs(ts, 4, ps, 3, -1, wi + 4 * n);
    lsqt_state st, one, up, dn;
    make_state(&st, &a, deg, 3, wi, n, 11, 1);
    run(&a, &st, 60000, 0);
    lsqt_slice_est *est = lsqt_estimates(&st);
    zsum zs = {0, 0, 0};
    for (int s = 0; s < 3; s++) {
        CHECK(!(st.slice_flags[s] & LSQT_SLICE_BELOW) && (st.slice_flags[3 + s] & LSQT_SLICE_BELOW), "flags");
        for (int k = 0; k < n; k++) z_add(&zs, est[s].f[k].mean, est[s].f[k].err, est[3 + s].f[k].mean, est[3 + s].f[k].err);
        z_add(&zs, est[s].R.mean, est[s].R.err, est[3 + s].R.mean, est[3 + s].R.err);
    }
    z_report("symmetric stack, below vs above", &zs);
    lsqt_estimates_free(est, st.n_slices);

    /* the side from above is the one-sided run; work-group size 16 gives the same bits */
    make_state(&one, &a, deg, 3, wi, n, 11, 0);
    run(&a, &one, 60000, 0);
    CHECK(lsqt_state_split_by_side(&st, &up, &dn) == 0 && same_tallies(&up, &one),
          "the side from above differs from the one-sided run");
    lsqt_state_free(&up), lsqt_state_free(&dn), lsqt_state_free(&one);
    lsqt_state w16;
    make_state(&w16, &a, deg, 3, wi, n, 11, 1);
    run(&a, &w16, 20000, 16);
    run(&a, &w16, 40000, 16); /* and in two runs */
    CHECK(same_tallies(&st, &w16), "work-group size 16 in two runs differs from 64 in one");
    lsqt_state_free(&w16), lsqt_state_free(&st);
    lsqt_assembly_free(&a);
}

static void test_reciprocity(void)
{
    const double nt = 1.0, nb = 1.5;
    lsqt_assembly a;
    parse("Medium eta=1\nLayer z=1 MicrosurfaceDielectricBsdf alpha=0.3\n"
          "Medium eta=1.5 mus=0.7 HenyeyGreensteinPhase g=0.6\nLayer z=0 NullBsdf\nMedium eta=1.5\n", &a);
    const double ts[] = {10, 35, 60}, ps[] = {0, 60, 120, 180};
    float wi[4 * 12];
    const int n = dirs(ts, 3, ps, 4, -1, wi); /* 12, in the order (t, p) */
    lsqt_state st;
    make_state(&st, &a, ts, 3, wi, n, 5, 1);
    run(&a, &st, 100000, 0);
    lsqt_slice_est *est = lsqt_estimates(&st);
    zsum zs = {0, 0, 0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            for (int p = 0; p < 4; p++) {
                const lsqt_est *ab = &est[i].f[4 * j + p], *ba = &est[3 + j].f[4 * i + p];
                z_add(&zs, nt * nt * ab->mean, nt * nt * ab->err, nb * nb * ba->mean, nb * nb * ba->err);
            }
    z_report("reciprocity of transmission, n_a^2 V(a->b) = n_b^2 V(b->a)", &zs);
    /* lossless: R + T = 1 on both sides */
    for (int s = 0; s < 6; s++) CHECK_Z(est[s].R.mean + est[s].T.mean, 1.0, est[s].R.err + 1e-9, 4.0);
    lsqt_estimates_free(est, st.n_slices);
    lsqt_state_free(&st);
    lsqt_assembly_free(&a);
}

int main(int argc, char **argv)
{
    const char *only = argc > 1 ? argv[1] : NULL;
    test_mirror();
    fixture_open();
    if (!only || strcmp(only, "split") == 0) test_split_join();
    if (!only || strcmp(only, "symmetric") == 0) test_symmetric();
    if (!only || strcmp(only, "reciprocity") == 0) test_reciprocity();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_below");
}
