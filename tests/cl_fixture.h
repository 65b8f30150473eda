/* Shared by the OpenCL tests: a context on the default device (PoCL's CPU in CI), the
 * kernel program's build (fixture_build), small kernel-call helpers (buffers, arguments,
 * launches, reads, each a CHECK), and a small driver that simulates an LSQT text in
 * memory. */
#ifndef LSQT_TESTS_CL_FIXTURE_H
#define LSQT_TESTS_CL_FIXTURE_H

#include <stdarg.h>
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

/* The kernel program (the embedded sources, or $LSQT_KERNEL_DIR's) and, where extra is
 * not NULL, the OpenCL C source extra after them (a test's own kernels), built with the
 * options given as a printf format. A failed build is a failed CHECK that shows the
 * error and the build log; it returns NULL. */
static inline cl_program fixture_build_with(const char *extra, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static inline cl_program fixture_build_with(const char *extra, const char *fmt, ...)
{
    char opt[1024], err[2048] = "", *log = NULL;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(opt, sizeof opt, fmt, ap);
    va_end(ap);
    cl_program prog = NULL;
    if (!extra) {
        prog = lsqt_program_build(&fixture_cx, opt, &log, err, sizeof err);
    } else {
        char *text = lsqt_kernel_text(err, sizeof err);
        cl_int e = CL_SUCCESS;
        if (text) {
            const char *srcs[] = {text, extra};
            prog = clCreateProgramWithSource(fixture_cx.ctx, 2, srcs, NULL, &e);
            free(text);
            if (e != CL_SUCCESS) snprintf(err, sizeof err, "clCreateProgramWithSource: %d", (int)e), prog = NULL;
        }
        if (prog && (e = clBuildProgram(prog, 1, &fixture_cx.dev.id, opt, NULL, NULL)) != CL_SUCCESS) {
            size_t n = 0;
            clGetProgramBuildInfo(prog, fixture_cx.dev.id, CL_PROGRAM_BUILD_LOG, 0, NULL, &n);
            log = calloc(n + 1, 1);
            if (log) clGetProgramBuildInfo(prog, fixture_cx.dev.id, CL_PROGRAM_BUILD_LOG, n, log, NULL);
            snprintf(err, sizeof err, "the kernels and the test's own failed to build: %d with options '%s'", (int)e, opt);
            clReleaseProgram(prog);
            prog = NULL;
        }
    }
    CHECK(prog != NULL, "%s\n%s", err, log ? log : "");
    free(log);
    return prog;
}

/* The kernel program alone: fixture_build_with(NULL, ...). */
#define fixture_build(...) fixture_build_with(NULL, __VA_ARGS__)

/* Kernel calls. Each failure is a failed CHECK. fixture_kernel_s sums the seconds of
 * fixture_launch (kernel time, for a test's timing line). */
static double fixture_kernel_s = 0;

static inline cl_mem fixture_mem(size_t bytes, const void *host)
{
    cl_int e = CL_SUCCESS;
    cl_mem m = clCreateBuffer(fixture_cx.ctx, host ? CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR : CL_MEM_READ_WRITE,
                              bytes, (void *)host, &e);
    CHECK(e == CL_SUCCESS, "clCreateBuffer(%zu): %d", bytes, (int)e);
    return m;
}

/* Sets the kernel's n arguments: sizes sz[i], values val[i]. */
static inline void fixture_args(cl_kernel k, int n, const size_t *sz, const void *const *val)
{
    for (int i = 0; i < n; i++) {
        cl_int e = clSetKernelArg(k, (cl_uint)i, sz[i], val[i]);
        CHECK(e == CL_SUCCESS, "argument %d: %d", i, (int)e);
    }
}

/* Runs n work-items (work-groups of `local`, 0: the implementation's choice) to the end. */
static inline void fixture_launch(cl_kernel k, size_t n, size_t local)
{
    double t0 = check_now();
    cl_int e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &n, local ? &local : NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clFinish(fixture_cx.queue);
    CHECK(e == CL_SUCCESS, "kernel launch of %zu: %d", n, (int)e);
    fixture_kernel_s += check_now() - t0;
}

static inline void fixture_read(cl_mem m, size_t bytes, void *dst)
{
    cl_int e = clEnqueueReadBuffer(fixture_cx.queue, m, CL_TRUE, 0, bytes, dst, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "clEnqueueReadBuffer: %d", (int)e);
}

/* The harness kernels (kernels/harness.cl): the layer's BSDF (use_phase 0) or the medium's
 * phase function (1), buffers layer and medium, for the direction wo. harness_sample:
 * n samples (x, y, z, weight) from seed into out[4 n]; harness_eval: value and pdf
 * towards the n directions dirs (x, y, z, 0) into out[2 n]. Both take these arguments,
 * then their own (its size and value), then the output. */
static inline void fixture_harness(cl_program prog, const char *name, cl_mem layer, cl_mem medium, int use_phase,
                                   const float wo[3], size_t arg_size, const void *arg, size_t n, size_t out_item,
                                   float *out)
{
    cl_mem bo = fixture_mem(n * out_item, NULL);
    cl_kernel k = clCreateKernel(prog, name, NULL);
    cl_int up = use_phase;
    const size_t sz[] = {sizeof layer, sizeof medium, sizeof up, 4, 4, 4, arg_size, sizeof bo};
    const void *val[] = {&layer, &medium, &up, &wo[0], &wo[1], &wo[2], arg, &bo};
    fixture_args(k, 8, sz, val);
    fixture_launch(k, n, 0);
    fixture_read(bo, n * out_item, out);
    clReleaseKernel(k);
    clReleaseMemObject(bo);
}

static inline void fixture_harness_sample(cl_program prog, cl_mem layer, cl_mem medium, int use_phase, const float wo[3],
                                          cl_uint seed, size_t n, float *out)
{
    fixture_harness(prog, "harness_sample", layer, medium, use_phase, wo, sizeof seed, &seed, n, 16, out);
}

static inline void fixture_harness_eval(cl_program prog, cl_mem layer, cl_mem medium, int use_phase, const float wo[3],
                                        const float *dirs, size_t n, float *out)
{
    cl_mem bd = fixture_mem(n * 16, dirs);
    fixture_harness(prog, "harness_eval", layer, medium, use_phase, wo, sizeof bd, &bd, n, 8, out);
    clReleaseMemObject(bd);
}

/* The direction tables a walk model's stochastic evaluation reads (lsqt_prepare for a
 * scene of the one layer `layer`: Lambda and lgamma per direction): the first n of n_wi
 * directions d as x[pad], y[pad], z[pad], zero padded (zero vectors add nothing), and
 * the slice's table. Free with fixture_dirs_free. */
typedef struct {
    cl_mem wi, tab;
} fixture_dirs;

static inline fixture_dirs fixture_dirs_make(cl_program prog, cl_mem layer, const double (*d)[3], int n, int n_wi,
                                             int pad)
{
    float *soa = calloc((size_t)3 * (size_t)pad, sizeof *soa);
    for (int i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) soa[c * pad + i] = (float)d[i][c];
    lsqt_dev_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.n_layers = 1, sc.n_wi = n_wi, sc.top_nonnull = 0, sc.bottom_nonnull = 0;
    lsqt_dev_medium med[2];
    memset(med, 0, sizeof med);
    med[0].eta = med[1].eta = 1;
    cl_mem bs = fixture_mem(sizeof sc, &sc), bm = fixture_mem(sizeof med, med);
    /* walk.cl's LSQT_SLICE_TAB(1) */
    fixture_dirs r = {fixture_mem((size_t)3 * (size_t)pad * sizeof *soa, soa),
                      fixture_mem((size_t)(LSQT_MEDIA_TAB_ROWS + LSQT_LAYER_TAB_ROWS) * (size_t)pad * sizeof(float), NULL)};
    free(soa);
    cl_kernel k = clCreateKernel(prog, "lsqt_prepare", NULL);
    const size_t sz[] = {sizeof bs, sizeof bm, sizeof layer, sizeof r.wi, sizeof r.tab};
    const void *val[] = {&bs, &bm, &layer, &r.wi, &r.tab};
    fixture_args(k, 5, sz, val);
    size_t g[2] = {(size_t)pad, 1};
    cl_int e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 2, NULL, g, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clFinish(fixture_cx.queue);
    CHECK(e == CL_SUCCESS, "lsqt_prepare: %d", (int)e);
    clReleaseKernel(k);
    clReleaseMemObject(bs);
    clReleaseMemObject(bm);
    return r;
}

static inline void fixture_dirs_free(fixture_dirs *d)
{
    clReleaseMemObject(d->wi);
    clReleaseMemObject(d->tab);
}

/* harness_ms_eval: `items` independent means of `reps` vertex evaluations each of the walk
 * model `layer` lit from wo, out[item * pad + k] = f(wo -> wi_k) at the directions d. */
static inline void fixture_ms_eval(cl_program prog, cl_mem layer, const double wo[3], const fixture_dirs *d,
                                   cl_uint seed, cl_int reps, int items, int pad, float *out)
{
    cl_mem bo = fixture_mem((size_t)items * (size_t)pad * sizeof(float), NULL);
    cl_kernel k = clCreateKernel(prog, "harness_ms_eval", NULL);
    float w[3] = {(float)wo[0], (float)wo[1], (float)wo[2]};
    const size_t sz[] = {sizeof layer, 4, 4, 4, sizeof d->wi, sizeof d->tab, sizeof seed, sizeof reps, sizeof bo};
    const void *val[] = {&layer, &w[0], &w[1], &w[2], &d->wi, &d->tab, &seed, &reps, &bo};
    fixture_args(k, 9, sz, val);
    fixture_launch(k, (size_t)items, 1); /* one work-item per group: each holds pad private sums */
    fixture_read(bo, (size_t)items * (size_t)pad * sizeof(float), out);
    clReleaseKernel(k);
    clReleaseMemObject(bo);
}

/* harness_eval of the layer L (as floats, or as doubles in a program built with
 * LSQT_DOUBLE when dbl) between media of index eta, at n direction pairs wo[i] -> wi[i]:
 * f[i] (the cosine of wi included) and, where pdf is not NULL, pdf[i]. One launch a pair
 * (the harness takes wo as scalars), each at its offset in one buffer of wi and one of
 * results. Returns 0, or -1 after a failed CHECK. */
static inline int fixture_eval_pairs(cl_program prog, int dbl, const lsqt_dev_layer_d *L, double eta, int n,
                                     const double (*wo)[3], const double (*wi)[3], double *f, double *pdf)
{
    lsqt_dev_layer lf;
    lsqt_dev_medium mf;
    lsqt_dev_medium_d md;
    memset(&lf, 0, sizeof lf), memset(&mf, 0, sizeof mf), memset(&md, 0, sizeof md);
    lf.kind = L->kind, lf.iter_count = L->iter_count, lf.multiple_scattering = L->multiple_scattering;
    for (int i = 0; i < 8; i++) lf.p[i] = (float)L->p[i];
    mf.eta = (float)eta, md.eta = eta;
    cl_int e = CL_SUCCESS;
    cl_kernel kn = clCreateKernel(prog, "harness_eval", &e);
    if (e != CL_SUCCESS) {
        CHECK(0, "clCreateKernel(harness_eval): %d", (int)e);
        return -1;
    }
    float *dirs = calloc((size_t)n * 4, sizeof *dirs), *res = calloc((size_t)n * 2, sizeof *res);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) dirs[4 * i + k] = (float)wi[i][k];
    cl_mem bl = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, dbl ? sizeof *L : sizeof lf,
                               dbl ? (void *)L : (void *)&lf, &e);
    cl_mem bm = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, dbl ? sizeof md : sizeof mf,
                               dbl ? (void *)&md : (void *)&mf, &e);
    cl_mem bd = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)n * 16, dirs, &e);
    cl_mem br = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, (size_t)n * 8, NULL, &e);
    cl_int zero = 0;
    e |= clSetKernelArg(kn, 0, sizeof bl, &bl);
    e |= clSetKernelArg(kn, 1, sizeof bm, &bm);
    e |= clSetKernelArg(kn, 2, sizeof zero, &zero);
    e |= clSetKernelArg(kn, 6, sizeof bd, &bd);
    e |= clSetKernelArg(kn, 7, sizeof br, &br);
    for (int i = 0; i < n && e == CL_SUCCESS; i++) {
        /* arguments are captured at enqueue, so the launches can queue up */
        float wof[3] = {(float)wo[i][0], (float)wo[i][1], (float)wo[i][2]};
        for (int k = 0; k < 3; k++) e |= clSetKernelArg(kn, (cl_uint)(3 + k), sizeof(float), &wof[k]);
        size_t off = (size_t)i, one = 1;
        if (e == CL_SUCCESS) e = clEnqueueNDRangeKernel(fixture_cx.queue, kn, 1, &off, &one, NULL, 0, NULL, NULL);
    }
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, br, CL_TRUE, 0, (size_t)n * 8, res, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "harness_eval: %d", (int)e);
    for (int i = 0; i < n; i++) {
        f[i] = res[2 * i];
        if (pdf) pdf[i] = res[2 * i + 1];
    }
    clReleaseMemObject(bl), clReleaseMemObject(bm), clReleaseMemObject(bd), clReleaseMemObject(br);
    clReleaseKernel(kn);
    free(dirs);
    free(res);
    return e == CL_SUCCESS ? 0 : -1;
}

/* Parses text into *a and makes a fresh state of n_slices x n_wi for it in *st (caller
 * frees; slice angles and directions still to be set); ends the test on an error. */
static inline void fixture_state(const char *text, int n_slices, int n_wi, uint64_t seed, int use_double,
                                 lsqt_assembly *a, lsqt_state *st)
{
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    if (lsqt_parse(text, strlen(text), "test", NULL, 1, NULL, a, &diag)) {
        fprintf(stderr, "parse failed: %s\n", diag.error);
        exit(1);
    }
    size_t n = lsqt_assembly_canonical(a, NULL, 0);
    char *canon = malloc(n + 1);
    lsqt_assembly_canonical(a, canon, n + 1);
    if (lsqt_state_init(st, canon, lsqt_assembly_hash(a), seed, n_slices, n_wi, lsqt_assembly_transmits(a), 1, NULL))
        exit(1);
    free(canon);
    st->use_double = use_double;
}

/* Simulates `paths` per slice of *st (its angles and directions set) for assembly *a,
 * then frees *a; ends the test on an error. */
static inline void fixture_simulate(lsqt_assembly *a, lsqt_state *st, uint64_t paths)
{
    lsqt_sim_opts o = {0, 0.0, 0, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
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
