/* Shared by the tests of band blocks (test_band_blocks, test_band_models, test_band_exits;
 * docs/design.md 3.7): one run of a text whose bands must share their paths, and the
 * GPU path's skip. Include after family_stats.h (seed_offset). */
#ifndef LSQT_TESTS_BAND_RUN_H
#define LSQT_TESTS_BAND_RUN_H

#include "family_stats.h"

#include "lsqt/band_blocks.h"
#include "lsqt/state.h"

/* Parses TEXT (who names it in messages), checks that its nb bands make one block, and
 * simulates them in one run (and checks that they shared its paths) (float) at the n_slices angles deg (degrees) and the n_wi
 * directions dirs, seed + seed_offset; fills *st (every band) and returns the estimates
 * (band after band), or NULL after a failed run (a failed check). */
static inline lsqt_slice_est *band_block_run(const char *who, const char *text, int nb, int n_slices,
                                             const double *deg, int n_wi, const double (*dirs)[3], uint64_t paths,
                                             uint64_t seed, lsqt_state *st)
{
    lsqt_assembly a;
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    if (lsqt_parse(text, strlen(text), "test", NULL, 0, ".", &a, &diag)) {
        fprintf(stderr, "%s: parse failed: %s\n", who, diag.error);
        exit(1);
    }
    CHECK(lsqt_assembly_bands(&a) == nb, "%s: %d bands, not %d", who, lsqt_assembly_bands(&a), nb);
    lsqt_band_block *blocks = NULL;
    const int n_blocks = lsqt_band_blocks(&a, LSQT_BAND_BLOCK_MAX, INFINITY, &blocks);
    CHECK(n_blocks == 1 && blocks[0].nb == nb, "%s: %d bands in %d blocks (the first of %d): they do not share", who,
          nb, n_blocks, n_blocks > 0 ? blocks[0].nb : 0);
    free(blocks);
    const size_t n = lsqt_assembly_canonical(&a, NULL, 0);
    char *canon = malloc(n + 1);
    lsqt_assembly_canonical(&a, canon, n + 1);
    if (lsqt_state_init(st, canon, lsqt_assembly_hash(&a), seed + seed_offset, n_slices, n_wi,
                              lsqt_assembly_transmits(&a), lsqt_assembly_bands(&a), NULL))
        exit(1);
    free(canon);
    st->use_double = 0;
    for (int s = 0; s < n_slices; s++) {
        st->theta_o[s] = deg[s] * PI / 180.0;
        float *w = st->wi + (size_t)s * (size_t)n_wi * 4;
        for (int k = 0; k < n_wi; k++) {
            w[4 * k] = (float)dirs[k][0], w[4 * k + 1] = (float)dirs[k][1], w[4 * k + 2] = (float)dirs[k][2];
            w[4 * k + 3] = 0.0f;
        }
    }
    lsqt_sim_opts o = {0, 0.0, 0, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
    lsqt_sim_stats stats;
    char err[1024];
    const int rc = lsqt_simulate(&fixture_cx, &a, st, paths, &o, &stats, err, sizeof err);
    lsqt_assembly_free(&a);
    CHECK(rc == 0, "%s: the run failed: %s", who, err);
    if (rc) return NULL;
    CHECK(st->flags == 0, "%s: flags %u", who, st->flags);
    lsqt_slice_est *e = lsqt_estimates(st);
    /* the paths were shared: every band's work counters (events and next-event
     * evaluations per path, counted for each band of the block) are the block's */
    for (int b = 1; b < nb; b++)
        for (int s = 0; s < n_slices; s++) {
            const lsqt_slice_est *x = &e[s], *y = &e[b * n_slices + s];
            CHECK(x->layer_events == y->layer_events && x->medium_events == y->medium_events &&
                      x->nee_evaluations == y->nee_evaluations,
                  "%s to=%g: band %d's work (%.6g layer, %.6g medium events, %.6g evaluations) is not band 1's "
                  "(%.6g, %.6g, %.6g): the bands did not share their paths",
                  who, deg[s], b + 1, y->layer_events, y->medium_events, y->nee_evaluations, x->layer_events,
                  x->medium_events, x->nee_evaluations);
        }
    return e;
}

/* Whether this run takes the GPU code path, whose blocks are at most 4 wide (band_blocks.h):
 * a band-block test's blocks of up to 16 are not made there (it says so; test_gpu_path
 * compares the GPU path's blocks with the CPU path's). */
static inline int band_blocks_absent(void)
{
    const char *gp = getenv("LSQT_GPU_PATH");
    if (gp && *gp ? strcmp(gp, "0") != 0 : !fixture_cx.dev.is_cpu) {
        printf("the GPU path's blocks are at most 4 wide: skipped\n");
        return 1;
    }
    return 0;
}

/* main() of a band test of two sections, quick and power, each a function that counts
 * its checks (count_only) or runs them: `name quick|power [SEED_OFFSET]`. Sets the default
 * block width whatever the caller's environment says, the family's thresholds from the
 * counted checks (tests/family_stats.h), and skips on the GPU path. */
static inline int band_sections_main(const char *name, int argc, char **argv, void (*quick)(int), void (*power)(int))
{
    static const char *names[] = {"quick", "power"};
    void (*const run[])(int) = {quick, power};
    int sec = -1;
    for (int i = 0; argc >= 2 && i < 2; i++)
        if (!strcmp(argv[1], names[i])) sec = i;
    if (sec < 0 || argc > 3) {
        fprintf(stderr, "usage: %s quick|power [SEED_OFFSET]\n", name);
        return 2;
    }
    if (argc == 3) seed_offset = strtoull(argv[2], NULL, 10);
    setenv("LSQT_BAND_BLOCK", "16", 1);
    setenv("LSQT_BAND_DIVERGENCE", "inf", 1); /* the cases' bands differ on purpose */
    family_plan(names[sec], run[sec]);
    fixture_open();
    if (band_blocks_absent()) {
        lsqt_context_release(&fixture_cx);
        return 77;
    }
    run[sec](0);
    lsqt_context_release(&fixture_cx);
    char what[64];
    snprintf(what, sizeof what, "%s %s", name, names[sec]);
    return check_finish(what);
}

/* Median of n values (sorted in place). */
static inline double band_median(double *v, int n)
{
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
            const double t = v[j];
            v[j] = v[j - 1], v[j - 1] = t;
        }
    return n ? (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2])) : 0.0;
}

#endif
