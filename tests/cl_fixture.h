/* Shared by the OpenCL tests: a context on the default device (PoCL's CPU in CI) and
 * a small driver that simulates an LSQT text in memory. */
#ifndef LSQT_TESTS_CL_FIXTURE_H
#define LSQT_TESTS_CL_FIXTURE_H

#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "lsqt/assembly.h"
#include "lsqt/device.h"
#include "lsqt/directions.h"
#include "lsqt/simulate.h"
#include "lsqt/tally.h"

static lsqt_context fixture_cx;

static inline void fixture_open(void)
{
    char err[1024];
    const char *spec = getenv("LSQT_TEST_DEVICE");
    int rc = lsqt_context_create(&fixture_cx, spec, err, sizeof err);
    if (rc) {
        fprintf(stderr, "no OpenCL device for the tests: %s\n", err);
        exit(1);
    }
    printf("device: %s\n", fixture_cx.dev.name);
}

/* Parses text into *a and makes a fresh state of n_slices x n_wi for it in *st (caller
 * frees; slice angles and directions still to be set); ends the test on an error. */
static inline void fixture_state(const char *text, int n_slices, int n_wi, uint64_t seed, int use_double,
                                 lsqt_assembly *a, lsqt_state *st)
{
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    if (lsqt_parse(text, strlen(text), "test", a, &diag)) {
        fprintf(stderr, "parse failed: %s\n", diag.error);
        exit(1);
    }
    size_t n = lsqt_assembly_canonical(a, NULL, 0);
    char *canon = malloc(n + 1);
    lsqt_assembly_canonical(a, canon, n + 1);
    if (lsqt_state_init(st, canon, lsqt_assembly_hash(a), seed, n_slices, n_wi, lsqt_assembly_transmits(a)))
        exit(1);
    free(canon);
    st->use_double = use_double;
}

/* Simulates `paths` per slice of *st (its angles and directions set) for assembly *a,
 * then frees *a; ends the test on an error. */
static inline void fixture_simulate(lsqt_assembly *a, lsqt_state *st, uint64_t paths)
{
    lsqt_sim_opts o = {0, 0.0, 0, NULL, NULL, 0, 0.0, 0.0, NULL, NULL};
    lsqt_sim_stats stats;
    char err[1024];
    if (lsqt_simulate(&fixture_cx, a, st, paths, &o, &stats, err, sizeof err)) {
        fprintf(stderr, "simulate failed: %s\n", err);
        exit(1);
    }
    lsqt_assembly_free(a);
}

/* Parses text and simulates `paths` per slice at the given angles (degrees) with n_wi
 * spread directions, in double precision when use_double; fills *st (caller frees) and
 * returns the estimates. */
static inline lsqt_slice_est *fixture_run_prec(const char *text, int n_slices, const double *deg, int n_wi,
                                               uint64_t paths, uint64_t seed, int use_double, lsqt_state *st)
{
    lsqt_assembly a;
    fixture_state(text, n_slices, n_wi, seed, use_double, &a, st);
    for (int s = 0; s < n_slices; s++) {
        st->theta_o[s] = deg[s] * 3.14159265358979323846 / 180.0;
        lsqt_wi_spread(n_wi, st->transmits, st->wi + (size_t)s * (size_t)n_wi * 4);
    }
    fixture_simulate(&a, st, paths);
    return lsqt_estimates(st);
}

static inline lsqt_slice_est *fixture_run(const char *text, int n_slices, const double *deg, int n_wi,
                                          uint64_t paths, uint64_t seed, lsqt_state *st)
{
    return fixture_run_prec(text, n_slices, deg, n_wi, paths, seed, 0, st);
}

#endif
