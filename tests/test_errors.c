/* The error bars are right, not just present (docs/design.md section 5.4: every estimate with its standard
 * error). Two independent checks of the batch-means standard errors of host/state/tally.c:
 *  1. analog fractions with a known distribution: in a lossless slab every path leaves
 *     with weight exactly 1, so R, T and the unscattered delta_T are binomial fractions
 *     and their standard error is sqrt(p (1 - p) / N);
 *  2. point estimates, whose distribution is unknown: over independent seeds the
 *     z-scores of the estimates about their mean must have unit variance;
 *  3. the same for each band of a run whose bands share their paths. */
#include "cl_fixture.h"
#include "lsqt/band_blocks.h"

#define NSLICE 32

static double sqr_d(double x) { return x * x; }

/* 1. Binomial standard errors. A batch-means variance from 32 batches has 31 degrees
 * of freedom: (err / binomial)^2 has mean 1 and sd sqrt(2/31) = 0.254 per slice, so its
 * mean over 32 independent slices has sd 0.045. Allowing 1 +- 0.19 (4.2 sd) checks the
 * errors to within 10 % (sqrt(0.81) = 0.90, sqrt(1.19) = 1.09). */
static void test_binomial(void)
{
    double deg[NSLICE];
    for (int s = 0; s < NSLICE; s++) deg[s] = 85.0 * s / (NSLICE - 1);
    lsqt_state st;
    const uint64_t n = 16384; /* 64 chunks: two per batch */
    lsqt_slice_est *e = fixture_run("Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0.3\n"
                                    "Layer z=0 NullBsdf\nMedium\n",
                                    NSLICE, deg, 16, n, 21, &st);
    double ratio_r = 0, ratio_t = 0, ratio_d = 0;
    int nd = 0;
    for (int s = 0; s < NSLICE; s++) {
        double r = e[s].R.mean, t = e[s].T.mean, d = e[s].delta_T.mean;
        /* Lossless: the integer tallies count paths, so R + T = 1 holds exactly. */
        CHECK(fabs(r + t - 1.0) < 1e-9, "slice %d: R + T = %.12g", s, r + t);
        double br = sqrt(r * (1 - r) / (double)n), bd = sqrt(d * (1 - d) / (double)n);
        ratio_r += sqr_d(e[s].R.err / br) / NSLICE;
        ratio_t += sqr_d(e[s].T.err / br) / NSLICE;
        /* Grazing slices have almost no unscattered paths (exp(-1/cos 85 deg) = 1e-5):
         * the batch variance needs a few per batch. */
        if (d * (double)n > 32 * 8) {
            ratio_d += sqr_d(e[s].delta_T.err / bd);
            nd++;
        }
    }
    ratio_d /= nd;
    printf("binomial: mean (err/expected)^2 over %d slices: R %.3f, T %.3f, delta_T %.3f\n", NSLICE, ratio_r,
           ratio_t, ratio_d);
    CHECK(fabs(ratio_r - 1) < 0.19, "R errors: mean (err/binomial)^2 = %.3f, want 1 +- 0.19", ratio_r);
    CHECK(fabs(ratio_t - 1) < 0.19, "T errors: mean (err/binomial)^2 = %.3f, want 1 +- 0.19", ratio_t);
    /* at least 24 slices: sd 0.254 / sqrt(24) = 0.052, and 0.21 is 4 sd */
    CHECK(nd >= 24 && fabs(ratio_d - 1) < 0.21, "delta_T errors: mean (err/binomial)^2 = %.3f over %d slices, want 1 +- 0.21", ratio_d, nd);
    lsqt_estimates_free(e, NSLICE);
    lsqt_state_free(&st);
}

/* 2. Point estimates over K seeds. With x̄ the mean over seeds, x_j - x̄ has variance
 * sigma^2 (1 - 1/K), so z_j = (x_j - x̄) / (err_j sqrt(1 - 1/K)) has unit variance when
 * the errors are right. err_j itself comes from 31 degrees of freedom, which makes z a
 * Student-t-like variable: E[z^2] = 31/29 = 1.07. The estimates of one run at different
 * directions share their paths and are correlated, so the independent count is between
 * K - 1 = 23 (all directions one variable: sd of mean z^2 = sqrt(2/23) = 0.29) and
 * 23 x 64; the bounds 0.45-1.9 are about 2 sd of the worst case below and 3 above
 * (six sets of 24 seeds gave 0.75-1.16). Errors 5x too large give 0.04, errors half as
 * large 4.3: far outside. */
#define KSEEDS 24
#define NWI 32
static void test_seed_zscores(void)
{
    const char *text = "Medium\nLayer z=1 NullBsdf\nMedium mus=2 mua=0.2 HenyeyGreensteinPhase g=0.5\n"
                       "Layer z=0 LambertianBsdf fR=0.5 fT=0.2\nMedium\n";
    const double deg[] = {20, 70};
    static double x[KSEEDS][2][NWI], err[KSEEDS][2][NWI], r[KSEEDS][2], rerr[KSEEDS][2];
    for (int j = 0; j < KSEEDS; j++) {
        lsqt_state st;
        lsqt_slice_est *e = fixture_run(text, 2, deg, NWI, 8192, 1000 + (uint64_t)j, &st);
        for (int s = 0; s < 2; s++) {
            r[j][s] = e[s].R.mean;
            rerr[j][s] = e[s].R.err;
            for (int k = 0; k < NWI; k++) {
                x[j][s][k] = e[s].f[k].mean;
                err[j][s][k] = e[s].f[k].err;
            }
        }
        lsqt_estimates_free(e, 2);
        lsqt_state_free(&st);
    }
    const double shrink = sqrt(1.0 - 1.0 / KSEEDS);
    double z2 = 0, z2r = 0;
    int n = 0, nr = 0, bad = 0;
    for (int s = 0; s < 2; s++) {
        double mr = 0;
        for (int j = 0; j < KSEEDS; j++) mr += r[j][s] / KSEEDS;
        for (int j = 0; j < KSEEDS; j++, nr++) z2r += sqr_d((r[j][s] - mr) / (rerr[j][s] * shrink));
        for (int k = 0; k < NWI; k++) {
            double m = 0;
            for (int j = 0; j < KSEEDS; j++) m += x[j][s][k] / KSEEDS;
            for (int j = 0; j < KSEEDS; j++) {
                if (!(err[j][s][k] > 0)) {
                    bad++;
                    continue;
                }
                z2 += sqr_d((x[j][s][k] - m) / (err[j][s][k] * shrink));
                n++;
            }
        }
    }
    z2 /= n;
    z2r /= nr;
    printf("seeds: mean z^2 of %d point estimates %.3f, of %d R estimates %.3f (expected about 1.07)\n", n, z2, nr,
           z2r);
    CHECK(bad == 0, "%d point estimates without a positive error", bad);
    CHECK(z2 > 0.45 && z2 < 1.9, "point estimates: mean z^2 over seeds = %.3f, want 0.45-1.9", z2);
    /* R: 2 x 24 values, 46 independent: sd of mean z^2 about sqrt(2/46) = 0.21. */
    CHECK(z2r > 0.45 && z2r < 1.9, "R: mean z^2 over seeds = %.3f, want 0.45-1.9", z2r);
}

/* 3. The same over seeds for a run with bands that share their paths (docs/design.md
 * 3.7): each band's errors must be right on its own, though the bands' weights are
 * spectral MIS weights of shared paths. Three bands as unlike as a block may hold
 * (extinction 2.2 to 1.5, albedo 0.91 to 0.4, a floor that transmits in two bands); the
 * bounds as in 2, per band. */
#define NBANDS 3
static void test_band_zscores(void)
{
    const char *text = "Medium\nLayer z=1 NullBsdf\nMedium mus=2,1.2,0.6 mua=0.2,0.5,0.9 HenyeyGreensteinPhase g=0.5\n"
                       "Layer z=0 LambertianBsdf fR=0.5,0.3,0.1 fT=0.2,0.1,0\nMedium\n";
    const double deg[] = {20, 70};
    static double x[KSEEDS][NBANDS][2][NWI], err[KSEEDS][NBANDS][2][NWI], r[KSEEDS][NBANDS][2], rerr[KSEEDS][NBANDS][2];
    for (int j = 0; j < KSEEDS; j++) {
        lsqt_assembly a;
        lsqt_diag diag;
        memset(&diag, 0, sizeof diag);
        if (lsqt_parse(text, strlen(text), "test", NULL, 0, ".", &a, &diag)) {
            fprintf(stderr, "parse failed: %s\n", diag.error);
            exit(1);
        }
        lsqt_band_block *blocks = NULL;
        const int n_blocks = lsqt_band_blocks(&a, LSQT_BAND_BLOCK_MAX, INFINITY, &blocks);
        if (j == 0) CHECK(n_blocks == 1 && blocks[0].nb == NBANDS, "the bands do not share their paths (%d blocks)", n_blocks);
        free(blocks);
        const size_t n = lsqt_assembly_canonical(&a, NULL, 0);
        char *canon = malloc(n + 1);
        lsqt_assembly_canonical(&a, canon, n + 1);
        lsqt_state st;
        if (lsqt_state_init(&st, canon, lsqt_assembly_hash(&a), 2000 + (uint64_t)j, 2, NWI,
                                  lsqt_assembly_transmits(&a), NBANDS, NULL))
            exit(1);
        free(canon);
        for (int s = 0; s < 2; s++) {
            st.theta_o[s] = deg[s] * 3.14159265358979323846 / 180.0;
            lsqt_wi_spread(NWI, st.transmits, st.wi + (size_t)s * NWI * 4);
        }
        fixture_simulate(&a, &st, 8192);
        lsqt_slice_est *e = lsqt_estimates(&st);
        for (int b = 0; b < NBANDS; b++)
            for (int s = 0; s < 2; s++) {
                const lsqt_slice_est *q = &e[b * 2 + s];
                r[j][b][s] = q->R.mean, rerr[j][b][s] = q->R.err;
                for (int k = 0; k < NWI; k++) x[j][b][s][k] = q->f[k].mean, err[j][b][s][k] = q->f[k].err;
            }
        lsqt_estimates_free(e, NBANDS * 2);
        lsqt_state_free(&st);
    }
    const double shrink = sqrt(1.0 - 1.0 / KSEEDS);
    for (int b = 0; b < NBANDS; b++) {
        double z2 = 0, z2r = 0;
        int n = 0, nr = 0, bad = 0;
        for (int s = 0; s < 2; s++) {
            double mr = 0;
            for (int j = 0; j < KSEEDS; j++) mr += r[j][b][s] / KSEEDS;
            for (int j = 0; j < KSEEDS; j++, nr++) z2r += sqr_d((r[j][b][s] - mr) / (rerr[j][b][s] * shrink));
            for (int k = 0; k < NWI; k++) {
                double m = 0;
                for (int j = 0; j < KSEEDS; j++) m += x[j][b][s][k] / KSEEDS;
                for (int j = 0; j < KSEEDS; j++) {
                    if (!(err[j][b][s][k] > 0)) { /* a value of exactly 0 (band 2 transmits nothing) has none */
                        bad += x[j][b][s][k] != 0;
                        continue;
                    }
                    z2 += sqr_d((x[j][b][s][k] - m) / (err[j][b][s][k] * shrink));
                    n++;
                }
            }
        }
        z2 /= n, z2r /= nr;
        printf("band %d, shared paths: mean z^2 of %d point estimates %.3f, of %d R estimates %.3f\n", b, n, z2, nr, z2r);
        CHECK(bad == 0, "band %d: %d point estimates without a positive error", b, bad);
        CHECK(z2 > 0.45 && z2 < 1.9, "band %d: point estimates: mean z^2 over seeds = %.3f, want 0.45-1.9", b, z2);
        CHECK(z2r > 0.45 && z2r < 1.9, "band %d: R: mean z^2 over seeds = %.3f, want 0.45-1.9", b, z2r);
    }
}

int main(void)
{
    fixture_open();
    test_binomial();
    test_seed_zscores();
    test_band_zscores();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_errors");
}
