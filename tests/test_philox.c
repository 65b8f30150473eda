/* Philox4x32 in the kernel against the published Random123 known-answer vectors
 * (tests/data/philox4x32_kat.json, copied from the project's shared data). */
#include <stdint.h>

#include "cl_fixture.h"
#include "lsqt/util.h"

#define MAXV 16

/* Reads the n quoted hex words of the array that follows `key` in obj. */
static int words_after(const char *obj, const char *key, uint32_t *out, int n)
{
    const char *p = strstr(obj, key);
    p = p ? strchr(p, '[') : NULL;
    for (int i = 0; i < n; i++) {
        p = p ? strchr(p, '"') : NULL;
        if (!p) return -1;
        char *end = NULL;
        out[i] = (uint32_t)strtoul(p + 1, &end, 16);
        if (end != p + 9 || *end != '"') return -1;
        p = end + 1;
    }
    return 0;
}

int main(void)
{
    size_t len = 0;
    char err[512];
    char *json = lsqt_read_file(LSQT_TEST_DATA "/philox4x32_kat.json", &len, err, sizeof err);
    CHECK(json != NULL, "%s", err);
    if (!json) return check_finish("test_philox");
    uint32_t ctr[4 * MAXV], key[2 * MAXV], expect[4 * MAXV], got[4 * MAXV];
    int rounds[MAXV], n = 0;
    for (const char *v = strstr(json, "\"rounds\""); v && n < MAXV; v = strstr(v + 1, "\"rounds\"")) {
        rounds[n] = atoi(strchr(v, ':') + 1);
        int bad = words_after(v, "\"counter\"", ctr + 4 * n, 4) || words_after(v, "\"key\"", key + 2 * n, 2) ||
                  words_after(v, "\"output\"", expect + 4 * n, 4);
        CHECK(!bad, "cannot read vector %d", n);
        n++;
    }
    free(json);
    CHECK(n == 6, "expected 6 vectors, read %d", n);
    CHECK(expect[0] == 0x5f6fb709u && rounds[0] == 7, "first vector parsed as %08x", expect[0]);

    fixture_open();
    char *log = NULL;
    cl_program prog = lsqt_program_build(&fixture_cx, "-cl-std=CL1.2", &log, err, sizeof err);
    CHECK(prog != NULL, "%s\n%s", err, log ? log : "");
    free(log);
    if (!prog) return check_finish("test_philox");
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "harness_philox", &e);
    cl_mem bc = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof ctr, ctr, &e);
    cl_mem bk = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof key, key, &e);
    cl_mem br = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof rounds, rounds, &e);
    cl_mem bo = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, sizeof got, NULL, &e);
    clSetKernelArg(k, 0, sizeof bc, &bc);
    clSetKernelArg(k, 1, sizeof bk, &bk);
    clSetKernelArg(k, 2, sizeof br, &br);
    clSetKernelArg(k, 3, sizeof bo, &bo);
    size_t global = (size_t)n;
    e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, bo, CL_TRUE, 0, sizeof got, got, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "kernel run failed: %d", (int)e);
    for (int i = 0; i < n; i++)
        for (int w = 0; w < 4; w++)
            CHECK(got[4 * i + w] == expect[4 * i + w], "vector %d (%d rounds) word %d: %08x, expected %08x", i,
                  rounds[i], w, got[4 * i + w], expect[4 * i + w]);
    clReleaseMemObject(bc);
    clReleaseMemObject(bk);
    clReleaseMemObject(br);
    clReleaseMemObject(bo);
    clReleaseKernel(k);
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_philox");
}
