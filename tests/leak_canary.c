/* Built only in the sanitizer build, for test_leak_check.sh: shows that the LSan
 * suppressions (tests/lsan.supp) hide the OpenCL implementation's leaks and nothing of
 * ours. It compiles and runs a kernel whose options carry a fresh nonce (so PoCL and LLVM
 * really compile, whatever the kernel cache holds), then leaks two blocks of its own: one
 * from a plain malloc, one through the project library (a state never freed). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "lsqt/device.h"
#include "lsqt/state.h"

static void *volatile sink;

__attribute__((noinline)) static void canary_leak(void)
{
    char *p = malloc(4242);
    if (p) memset(p, 0x5a, 4242);
    sink = p;
    sink = NULL; /* the last reference is gone: a true leak */
}

__attribute__((noinline)) static void canary_leak_state(void)
{
    lsqt_state *st = malloc(sizeof *st);
    if (st && lsqt_state_init(st, "canary", 1, 2, 4, 16, 0, 1, NULL) == 0) sink = st;
    sink = NULL;
}

int main(void)
{
    lsqt_context cx;
    char err[1024];
    if (lsqt_context_create(&cx, getenv("LSQT_TEST_DEVICE"), err, sizeof err)) {
        fprintf(stderr, "leak_canary: %s\n", err);
        return 2;
    }
    const char *src = "kernel void canary(global int *x) { x[get_global_id(0)] = NONCE; }";
    char opt[64];
    snprintf(opt, sizeof opt, "-DNONCE=%ld", (long)time(NULL) * 100000L + (long)getpid() % 100000L);
    cl_int e = CL_SUCCESS;
    cl_program prog = clCreateProgramWithSource(cx.ctx, 1, &src, NULL, &e);
    if (e == CL_SUCCESS) e = clBuildProgram(prog, 1, &cx.dev.id, opt, NULL, NULL);
    cl_kernel k = e == CL_SUCCESS ? clCreateKernel(prog, "canary", &e) : NULL;
    cl_mem m = e == CL_SUCCESS ? clCreateBuffer(cx.ctx, CL_MEM_READ_WRITE, 64 * sizeof(cl_int), NULL, &e) : NULL;
    if (e == CL_SUCCESS) e = clSetKernelArg(k, 0, sizeof m, &m);
    size_t global = 64;
    if (e == CL_SUCCESS) e = clEnqueueNDRangeKernel(cx.queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clFinish(cx.queue);
    if (m) clReleaseMemObject(m);
    if (k) clReleaseKernel(k);
    if (prog) clReleaseProgram(prog);
    lsqt_context_release(&cx);
    if (e != CL_SUCCESS) {
        fprintf(stderr, "leak_canary: OpenCL failed: %s (%d)\n", lsqt_cl_error_name(e), (int)e);
        return 2;
    }
    canary_leak();
    canary_leak_state();
    printf("leak_canary: compiled and ran a kernel (%s), leaked 4242 bytes and a state\n", opt);
    return 0;
}
