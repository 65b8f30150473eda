/* The kernels' own elementary functions, which replace the library's on the hot paths
 * (sampling.cl's neg_log_unit for free paths and azimuth_cs for every sampled azimuth,
 * common.cl's inv_pow15v for the Henyey-Greenstein value and exp2_negv for the media's
 * transmittance), against the C library in
 * double at every 2^-20 step of their arguments and at the small ends of their ranges;
 * and walk.cl's exit-histogram bin, whose phi bin counts bin edges instead of taking
 * atan2, against atan2 in double.
 * The tolerances are a few float roundings: each function is meant to be as good as the
 * library's float functions, not merely close. */
#include <math.h>
#include <stdint.h>

#include "cl_fixture.h"
#include "lsqt/device_layout.h"

#define N (1 << 20)
#define NX (N + 64)

#define PI_D 3.14159265358979323846

/* The reference bin: |cos theta| x atan2(|y|, x) in [0, pi], in double. */
static int ref_bin(double x, double y, double z)
{
    int up = z >= 0, bm = (int)(fabs(z) * LSQT_HIST_NMU), bp = (int)(atan2(fabs(y), x) * (LSQT_HIST_NPHI / PI_D));
    bm = bm < 0 ? 0 : bm > LSQT_HIST_NMU - 1 ? LSQT_HIST_NMU - 1 : bm;
    bp = bp < 0 ? 0 : bp > LSQT_HIST_NPHI - 1 ? LSQT_HIST_NPHI - 1 : bp;
    return ((up ? 0 : 1) * LSQT_HIST_NMU + bm) * LSQT_HIST_NPHI + bp;
}

#define NH (1 << 18)
#define NH_ALL (NH + 6)

/* Directions on a fine grid of phi (every 2^-16 of a turn, so the edges j pi / 16 are
 * on it) and of cos theta, both hemispheres; then the special ones: straight up and down
 * (atan2(0, 0) = 0), y = 0 behind (phi = pi), and a NaN. Away from an edge (more than
 * 1e-6 rad) the bin must be atan2's; on an edge it may be either neighbour. */
static void check_hist_bin(cl_program prog)
{
    static float d[3 * NH_ALL];
    static int out[NH_ALL];
    for (int i = 0; i < NH; i++) {
        double phi = 2 * PI_D * (double)(i % 65536) / 65536, mu = ((i / 65536) * 2 + 1) / 8.0 * 0.999;
        double sz = (i & 1) ? -1 : 1, st = sqrt(1 - mu * mu);
        d[3 * i] = (float)(st * cos(phi)), d[3 * i + 1] = (float)(st * sin(phi)), d[3 * i + 2] = (float)(sz * mu);
    }
    const float special[6][3] = {{0, 0, 1}, {0, 0, -1}, {-1, 0, 0}, {-0.6f, -0.0f, 0.8f}, {1, 0, 0}, {NAN, NAN, NAN}};
    for (int i = 0; i < 6; i++)
        for (int c = 0; c < 3; c++) d[3 * (NH + i) + c] = special[i][c];
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "harness_hist_bin", &e);
    cl_mem bd = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof d, d, &e);
    cl_mem bo = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, sizeof out, NULL, &e);
    clSetKernelArg(k, 0, sizeof bd, &bd);
    clSetKernelArg(k, 1, sizeof bo, &bo);
    size_t global = NH_ALL;
    e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, bo, CL_TRUE, 0, sizeof out, out, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "harness_hist_bin failed: %d", (int)e);
    int wrong = 0, edge = 0, first = -1;
    for (int i = 0; i < NH && e == CL_SUCCESS; i++) {
        double x = d[3 * i], y = d[3 * i + 1], z = d[3 * i + 2], t = atan2(fabs(y), x) * (LSQT_HIST_NPHI / PI_D);
        int r = ref_bin(x, y, z);
        if (fabs(t - round(t)) * (PI_D / LSQT_HIST_NPHI) < 1e-6) {
            edge++;
            if (out[i] != r && out[i] != r - 1 && !(out[i] == r + 1 && (r + 1) % LSQT_HIST_NPHI)) wrong++;
        } else if (out[i] != r) {
            wrong++;
        }
        if (wrong && first < 0) first = i;
    }
    CHECK(wrong == 0, "hist_bin: %d of %d directions in the wrong bin, the first (%.9g, %.9g, %.9g): %d, atan2's %d", wrong,
          NH, first < 0 ? 0 : d[3 * first], first < 0 ? 0 : d[3 * first + 1], first < 0 ? 0 : d[3 * first + 2],
          first < 0 ? 0 : out[first], first < 0 ? 0 : ref_bin(d[3 * first], d[3 * first + 1], d[3 * first + 2]));
    CHECK(edge >= 4 * 2 * 16, "hist_bin: only %d directions on an edge (the grid should hold every edge)", edge);
    const int nphi = LSQT_HIST_NPHI, nmu = LSQT_HIST_NMU, bins = 2 * nmu * nphi;
    const int want[5] = {(nmu - 1) * nphi, (2 * nmu - 1) * nphi, nphi - 1, 25 * nphi + nphi - 1, 0};
    for (int i = 0; i < 5 && e == CL_SUCCESS; i++)
        CHECK(out[NH + i] == want[i], "hist_bin(%g, %g, %g) = %d, atan2's %d", special[i][0], special[i][1], special[i][2],
              out[NH + i], want[i]);
    CHECK(e != CL_SUCCESS || (out[NH + 5] >= 0 && out[NH + 5] < bins), "hist_bin(NaN) = %d, outside the table", out[NH + 5]);
    printf("hist_bin: %d directions (%d on an edge) in atan2's bins\n", NH, edge);
    clReleaseMemObject(bd);
    clReleaseMemObject(bo);
    clReleaseKernel(k);
}

int main(void)
{
    static float xl[NX], xa[NX], xp[NX], xe[NX], out[5 * NX];
    for (int i = 0; i < N; i++) {
        xl[i] = 1.0f - (float)i / N;        /* (0, 1]: 1 - u for u on the grid */
        xa[i] = (float)i / N;               /* [0, 1) */
        xp[i] = 4.0f * (float)(i + 1) / N;  /* (0, 4]: 1 + g^2 - 2 g cos t */
        xe[i] = -130.0f * (float)i / N;     /* (-130, 0]: -tau log2(e) / |z| */
    }
    for (int i = 0; i < 64; i++) { /* the small ends: 1 - u down to 2^-24, (1 - |g|)^2 down to 1e-12 */
        xl[N + i] = ldexpf(1.0f + (float)i / 64, -24 + i / 4);
        xa[N + i] = 1.0f - ldexpf(1.0f, -24 + i % 20);
        xp[N + i] = ldexpf(1.0f + (float)i / 64, -40 + i / 2);
        xe[N + i] = -ldexpf(1.0f + (float)i / 64, -30 + i / 2); /* down to -2^-30 */
    }
    fixture_open();
    cl_program prog = fixture_build("-cl-std=CL1.2");
    if (!prog) return check_finish("test_fast_math");
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "harness_fast_math", &e);
    cl_mem_flags ro = CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR;
    cl_mem b[5] = {clCreateBuffer(fixture_cx.ctx, ro, sizeof xl, xl, &e), clCreateBuffer(fixture_cx.ctx, ro, sizeof xa, xa, &e),
                   clCreateBuffer(fixture_cx.ctx, ro, sizeof xp, xp, &e), clCreateBuffer(fixture_cx.ctx, ro, sizeof xe, xe, &e),
                   clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, sizeof out, NULL, &e)};
    for (int i = 0; i < 5; i++) clSetKernelArg(k, (cl_uint)i, sizeof b[i], &b[i]);
    size_t global = NX;
    e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, b[4], CL_TRUE, 0, sizeof out, out, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "harness_fast_math failed: %d", (int)e);
    double worst[4] = {0, 0, 0, 0};
    int at[4] = {0, 0, 0, 0}, exp_nonzero = 0;
    for (int i = 0; i < NX && e == CL_SUCCESS; i++) {
        /* -log x relative to max(-log x, 1e-7): near x = 1 it is u itself and keeps u's
         * relative accuracy only to the float spacing of x */
        const float *o = out + 5 * i;
        double l = -log((double)xl[i]), el = fabs(o[0] - l) / fmax(l, 1e-7);
        double a = 6.283185307179586477 * xa[i], ea = fmax(fabs(o[1] - cos(a)), fabs(o[2] - sin(a)));
        double p = pow((double)xp[i], -1.5), ep = fabs(o[3] - p) / p;
        /* 2^x: relative error down to 2^-125, exactly 0 below (never negative or NaN) */
        double x2 = exp2((double)xe[i]), e2 = xe[i] >= -125.0f ? fabs(o[4] - x2) / x2 : (o[4] != 0.0f) * 1.0;
        exp_nonzero += o[4] != 0.0f;
        double ev[4] = {el, ea, ep, e2};
        for (int f = 0; f < 4; f++)
            if (ev[f] > worst[f]) worst[f] = ev[f], at[f] = i;
    }
    printf("neg_log_unit: largest relative error %.2e at x = %.9g\n", worst[0], xl[at[0]]);
    printf("azimuth_cs: largest error of cos, sin %.2e at u = %.9g\n", worst[1], xa[at[1]]);
    printf("inv_pow15v: largest relative error %.2e at x = %.9g\n", worst[2], xp[at[2]]);
    printf("exp2_negv: largest relative error %.2e at x = %.9g\n", worst[3], xe[at[3]]);
    CHECK(worst[0] < 6e-7, "neg_log_unit: relative error %.3g at x = %.9g (float's library log: about 1.2e-7)", worst[0],
          xl[at[0]]);
    CHECK(worst[1] < 4e-7, "azimuth_cs: error %.3g at u = %.9g (float rounding of cos, sin: 6e-8)", worst[1], xa[at[1]]);
    CHECK(worst[2] < 1e-6, "inv_pow15v: relative error %.3g at x = %.9g", worst[2], xp[at[2]]);
    CHECK(worst[3] < 3e-7, "exp2_negv: relative error %.3g at x = %.9g (or not 0 below -125; float's exp2: 1.2e-7)",
          worst[3], xe[at[3]]);
    CHECK(exp_nonzero > N / 130 * 125, "exp2_negv: only %d arguments gave a value above 0", exp_nonzero);
    for (int i = 0; i < 5; i++) clReleaseMemObject(b[i]);
    clReleaseKernel(k);
    check_hist_bin(prog);
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_fast_math");
}
