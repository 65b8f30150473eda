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

/* Philox4x32 written from the paper (Salmon et al. 2011), independent of the kernel's:
 * checked against the same known answers, then the reference for the draw stream. */
static void philox_ref(const uint32_t in[4], const uint32_t key[2], int rounds, uint32_t out[4])
{
    uint32_t c[4] = {in[0], in[1], in[2], in[3]}, k0 = key[0], k1 = key[1];
    for (int r = 0; r < rounds; r++) {
        uint64_t p0 = (uint64_t)0xD2511F53u * c[0], p1 = (uint64_t)0xCD9E8D57u * c[2];
        uint32_t n[4] = {(uint32_t)(p1 >> 32) ^ c[1] ^ k0, (uint32_t)p1, (uint32_t)(p0 >> 32) ^ c[3] ^ k1,
                         (uint32_t)p0};
        memcpy(c, n, sizeof c);
        k0 += 0x9E3779B9u, k1 += 0xBB67AE85u;
    }
    memcpy(out, c, sizeof c);
}

/* docs/design.md section 4.1: draw j of a path is word j mod 4 of Philox4x32-10 with key = seed and
 * counter = (j / 4, path index low 32 bits, high 16 bits | purpose << 16, slice), so a
 * path is a pure function of (seed, slice, path index, purpose). Both forms of the
 * stream: one block at a time (GPUs) and the CPUs' four at a time (LSQT_RNG_WIDE), whose
 * first four blocks come alone, the next four too, and later ones made ahead: 71 draws
 * are 18 blocks, the last one in part. */
static void check_stream(cl_program prog, const char *form)
{
    enum { N = 71 };
    const uint32_t seed[2] = {0x12345678u, 0x9abcdef0u}, slice = 7u, purpose = 1u;
    const uint64_t path = 0x0000beef00c0ffeeull;
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "harness_rng_stream", &e);
    cl_mem bo = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, N * sizeof(uint32_t), NULL, &e);
    cl_ulong p = path;
    cl_int n = N;
    clSetKernelArg(k, 0, sizeof seed[0], &seed[0]);
    clSetKernelArg(k, 1, sizeof seed[1], &seed[1]);
    clSetKernelArg(k, 2, sizeof slice, &slice);
    clSetKernelArg(k, 3, sizeof p, &p);
    clSetKernelArg(k, 4, sizeof purpose, &purpose);
    clSetKernelArg(k, 5, sizeof n, &n);
    clSetKernelArg(k, 6, sizeof bo, &bo);
    uint32_t got[N];
    size_t one = 1;
    e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &one, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, bo, CL_TRUE, 0, sizeof got, got, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "harness_rng_stream failed: %d", (int)e);
    for (int j = 0; j < N && e == CL_SUCCESS; j++) {
        const uint32_t ctr[4] = {(uint32_t)(j / 4), (uint32_t)path, (uint32_t)(path >> 32 & 0xFFFFu) | purpose << 16,
                                 slice};
        uint32_t block[4];
        philox_ref(ctr, seed, 10, block);
        CHECK(got[j] == block[j % 4], "%s: draw %d: %08x, expected %08x (block %d word %d)", form, j, got[j],
              block[j % 4], j / 4, j % 4);
    }
    clReleaseMemObject(bo);
    clReleaseKernel(k);
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
    cl_program prog = fixture_build("-cl-std=CL1.2");
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
    for (int i = 0; i < n; i++) {
        uint32_t ref[4];
        philox_ref(ctr + 4 * i, key + 2 * i, rounds[i], ref);
        CHECK(memcmp(ref, expect + 4 * i, sizeof ref) == 0, "the test's own Philox misses vector %d", i);
    }
    check_stream(prog, "one block at a time");
    cl_program wide = fixture_build("-cl-std=CL1.2 -DLSQT_RNG_WIDE=1");
    if (wide) check_stream(wide, "four blocks at a time"), clReleaseProgram(wide);
    clReleaseMemObject(bc);
    clReleaseMemObject(bk);
    clReleaseMemObject(br);
    clReleaseMemObject(bo);
    clReleaseKernel(k);
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_philox");
}
