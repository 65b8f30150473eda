/* Minimal test helpers: every CHECK that fails prints where and why; a test program
 * returns check_finish(), non-zero when anything failed. With LSQT_CHECK_FAIL_FAST=1 in
 * the environment (the mutation check sets it) the first failed CHECK ends the program
 * with status 1: a planted error is known to be caught at its first sign, and the rest
 * of a long test would only say so again. */
#ifndef LSQT_TESTS_CHECK_H
#define LSQT_TESTS_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int check_failures = 0;
static int check_count = 0;

static inline void check_failed_now(void)
{
    static int fast = -1;
    if (fast < 0) {
        const char *e = getenv("LSQT_CHECK_FAIL_FAST");
        fast = e && *e && strcmp(e, "0") != 0;
    }
    if (fast) {
        fprintf(stderr, "stopping at the first failed check (LSQT_CHECK_FAIL_FAST)\n");
        fflush(NULL);
        exit(1);
    }
}

#define CHECK(cond, ...)                                                         \
    do {                                                                         \
        check_count++;                                                           \
        if (!(cond)) {                                                           \
            check_failures++;                                                    \
            fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                        \
            fprintf(stderr, "\n");                                               \
            check_failed_now();                                                  \
        }                                                                        \
    } while (0)

/* |a - b| <= tol * |b| */
#define CHECK_REL(a, b, tol)                                                     \
    CHECK(fabs((double)(a) - (double)(b)) <= (tol) * fabs((double)(b)),          \
          "%.10g vs %.10g (rel tol %g)", (double)(a), (double)(b), (double)(tol))

/* |estimate - expected| <= k * sigma, with sigma > 0 required */
#define CHECK_Z(est, expected, sigma, k)                                         \
    CHECK((sigma) > 0 && fabs((double)(est) - (double)(expected)) <= (k) * (sigma), \
          "%.8g vs %.8g: z = %.3f (sigma %.3g, allowed %g)", (double)(est),       \
          (double)(expected), ((double)(est) - (double)(expected)) / (double)(sigma), \
          (double)(sigma), (double)(k))

/* Seconds on a monotonic clock, for the tests' timing lines. */
static inline double check_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int check_finish(const char *name)
{
    printf("%s: %d checks, %d failed\n", name, check_count, check_failures);
    return check_failures ? 1 : 0;
}

#endif
