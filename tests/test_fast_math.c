/* The kernels' own elementary functions, which replace the library's on the hot paths
 * (sampling.cl's neg_log_unit for free paths and azimuth_cs for every sampled azimuth,
 * common.cl's inv_pow15v for the Henyey-Greenstein value), against the C library in
 * double at every 2^-20 step of their arguments and at the small ends of their ranges.
 * The tolerances are a few float roundings: each function is meant to be as good as the
 * library's float functions, not merely close. */
#include <math.h>

#include "cl_fixture.h"

#define N (1 << 20)
#define NX (N + 64)

int main(void)
{
    static float xl[NX], xa[NX], xp[NX], out[4 * NX];
    for (int i = 0; i < N; i++) {
        xl[i] = 1.0f - (float)i / N;        /* (0, 1]: 1 - u for u on the grid */
        xa[i] = (float)i / N;               /* [0, 1) */
        xp[i] = 4.0f * (float)(i + 1) / N;  /* (0, 4]: 1 + g^2 - 2 g cos t */
    }
    for (int i = 0; i < 64; i++) { /* the small ends: 1 - u down to 2^-24, (1 - |g|)^2 down to 1e-12 */
        xl[N + i] = ldexpf(1.0f + (float)i / 64, -24 + i / 4);
        xa[N + i] = 1.0f - ldexpf(1.0f, -24 + i % 20);
        xp[N + i] = ldexpf(1.0f + (float)i / 64, -40 + i / 2);
    }
    fixture_open();
    char err[512], *build_log = NULL;
    cl_program prog = lsqt_program_build(&fixture_cx, "-cl-std=CL1.2", &build_log, err, sizeof err);
    CHECK(prog != NULL, "%s\n%s", err, build_log ? build_log : "");
    free(build_log);
    if (!prog) return check_finish("test_fast_math");
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "harness_fast_math", &e);
    cl_mem_flags ro = CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR;
    cl_mem b[4] = {clCreateBuffer(fixture_cx.ctx, ro, sizeof xl, xl, &e), clCreateBuffer(fixture_cx.ctx, ro, sizeof xa, xa, &e),
                   clCreateBuffer(fixture_cx.ctx, ro, sizeof xp, xp, &e),
                   clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, sizeof out, NULL, &e)};
    for (int i = 0; i < 4; i++) clSetKernelArg(k, (cl_uint)i, sizeof b[i], &b[i]);
    size_t global = NX;
    e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, b[3], CL_TRUE, 0, sizeof out, out, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "harness_fast_math failed: %d", (int)e);
    double worst[3] = {0, 0, 0};
    int at[3] = {0, 0, 0};
    for (int i = 0; i < NX && e == CL_SUCCESS; i++) {
        /* -log x relative to max(-log x, 1e-7): near x = 1 it is u itself and keeps u's
         * relative accuracy only to the float spacing of x */
        double l = -log((double)xl[i]), el = fabs(out[4 * i] - l) / fmax(l, 1e-7);
        double a = 6.283185307179586477 * xa[i], ea = fmax(fabs(out[4 * i + 1] - cos(a)), fabs(out[4 * i + 2] - sin(a)));
        double p = pow((double)xp[i], -1.5), ep = fabs(out[4 * i + 3] - p) / p;
        double ev[3] = {el, ea, ep};
        for (int f = 0; f < 3; f++)
            if (ev[f] > worst[f]) worst[f] = ev[f], at[f] = i;
    }
    printf("neg_log_unit: largest relative error %.2e at x = %.9g\n", worst[0], xl[at[0]]);
    printf("azimuth_cs: largest error of cos, sin %.2e at u = %.9g\n", worst[1], xa[at[1]]);
    printf("inv_pow15v: largest relative error %.2e at x = %.9g\n", worst[2], xp[at[2]]);
    CHECK(worst[0] < 6e-7, "neg_log_unit: relative error %.3g at x = %.9g (float's library log: about 1.2e-7)", worst[0],
          xl[at[0]]);
    CHECK(worst[1] < 4e-7, "azimuth_cs: error %.3g at u = %.9g (float rounding of cos, sin: 6e-8)", worst[1], xa[at[1]]);
    CHECK(worst[2] < 1e-6, "inv_pow15v: relative error %.3g at x = %.9g", worst[2], xp[at[2]]);
    for (int i = 0; i < 4; i++) clReleaseMemObject(b[i]);
    clReleaseKernel(k);
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_fast_math");
}
