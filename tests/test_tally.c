/* The 128-bit fixed-point tallies (kernels/tally.cl), through a harness kernel that adds
 * values the way the walk does (local 32-bit words, global 64-bit words or the 32-bit
 * fallback), against exact sums computed here in integer arithmetic:
 * - contributions from 1e-12 to 1.7e13 of a unit, each rounded to the nearest 2^-40;
 * - carries through every word: many values just below 2^63 units, and 2^84-unit ones;
 * - a value above the range raises the overflow flag (which fails a run), a NaN the
 *   non-finite flag; values in range raise nothing. */
#include "cl_fixture.h"

/* Exact units of a float: round(v 2^40) to nearest, halves up (none of the values
 * here is a tie). v 2^40 is exact in double; at or above 2^53 it is a whole number
 * m 2^e with e >= 0. */
static lsqt_u128 ref_units(float v)
{
    double x = ldexp((double)v, LSQT_FIX_BITS);
    lsqt_u128 r = {0, 0};
    if (x < 9007199254740992.0) {
        r.lo = (uint64_t)floor(x + 0.5);
        return r;
    }
    int e;
    double m = frexp(x, &e); /* x = m 2^e, m in [0.5, 1) */
    uint64_t mi = (uint64_t)ldexp(m, 53);
    e -= 53;
    r.lo = e >= 64 ? 0 : mi << e;
    r.hi = e == 0 ? 0 : e >= 64 ? mi << (e - 64) : mi >> (64 - e);
    return r;
}

static cl_program build(const char *extra)
{
    return fixture_build("-cl-std=CL1.2 %s", extra);
}

/* Adds v[0..n) on the device; returns the flags, fills the two tallies. */
static unsigned run_tally(cl_program prog, const float *v, size_t n, size_t local, lsqt_u128 out[2])
{
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "harness_tally", &e);
    cl_mem bv = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof *v, (void *)v, &e);
    uint64_t zero[4] = {0, 0, 0, 0};
    cl_uint flags = 0;
    cl_mem bo = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof zero, zero, &e);
    cl_mem bf = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof flags, &flags, &e);
    clSetKernelArg(k, 0, sizeof bv, &bv);
    clSetKernelArg(k, 1, sizeof bo, &bo);
    clSetKernelArg(k, 2, sizeof bf, &bf);
    if (e == CL_SUCCESS) e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &n, &local, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, bo, CL_TRUE, 0, sizeof zero, zero, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, bf, CL_TRUE, 0, sizeof flags, &flags, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "harness_tally: %s (%d)", lsqt_cl_error_name(e), (int)e);
    out[0].lo = zero[0], out[0].hi = zero[1], out[1].lo = zero[2], out[1].hi = zero[3];
    clReleaseMemObject(bv);
    clReleaseMemObject(bo);
    clReleaseMemObject(bf);
    clReleaseKernel(k);
    return flags;
}

static void check_sum(cl_program prog, const char *what, const float *v, size_t n, size_t local)
{
    lsqt_u128 want = {0, 0}, got[2];
    for (size_t i = 0; i < n; i++) want = lsqt_u128_add(want, ref_units(v[i]));
    unsigned flags = run_tally(prog, v, n, local, got);
    CHECK(flags == 0, "%s: flags %u", what, flags);
    for (int t = 0; t < 2; t++)
        CHECK(got[t].lo == want.lo && got[t].hi == want.hi,
              "%s (%s): got %016llx%016llx units, want %016llx%016llx", what, t ? "local words" : "global words",
              (unsigned long long)got[t].hi, (unsigned long long)got[t].lo, (unsigned long long)want.hi,
              (unsigned long long)want.lo);
}

static void test_variant(const char *extra)
{
    cl_program prog = build(extra);
    if (!prog) return;
    printf("tallies %s\n", *extra ? extra : "(64-bit atomics where the device has them)");
    enum { N = 4096 };
    static float v[N];
    /* Contributions across the range, each rounded once: 1e-12 (1.1 units) to 1.7e13;
     * 1.25e7 is between 2^63 and 2^64 units, where a signed conversion overflows. */
    const float span[] = {1e-12f, 3e-9f, 0.1f, 1.0f, 12345.678f, 8388607.5f, 1.25e7f, 1e12f, 1.7e13f, 2.5e-7f, 7e5f};
    for (int i = 0; i < N; i++) v[i] = span[i % 11];
    check_sum(prog, "mixed 1e-12 .. 1.7e13", v, N, 64);
    /* Just below 2^63 units each: the low 64-bit word wraps on every other add, and the
     * local 32-bit words carry at every level. */
    for (int i = 0; i < N; i++) v[i] = 8388607.5f;
    check_sum(prog, "carries out of the low word", v, N, 256);
    /* 2^84 units each: only high words, 4096 of them (2^96). */
    for (int i = 0; i < N; i++) v[i] = 17592186044416.0f;
    check_sum(prog, "high words", v, N, 32);
    /* Tiny values: 1e-12 is 1.1 units, still counted. */
    for (int i = 0; i < N; i++) v[i] = 1e-12f;
    check_sum(prog, "1e-12 each", v, N, 64);
    lsqt_u128 got[2];
    for (int i = 0; i < N; i++) v[i] = 1.0f;
    v[17] = 2e13f;
    CHECK(run_tally(prog, v, N, 64, got) & LSQT_FLAG_OVERFLOW, "2e13 did not raise the overflow flag");
    v[17] = NAN;
    unsigned f = run_tally(prog, v, N, 64, got);
    CHECK((f & LSQT_FLAG_NONFINITE) && !(f & LSQT_FLAG_OVERFLOW), "NaN: flags %u", f);
    CHECK(got[0].lo == (uint64_t)(N - 1) << LSQT_FIX_BITS && got[0].hi == 0, "NaN counted as 0: %llu units",
          (unsigned long long)got[0].lo);
    clReleaseProgram(prog);
}

/* The block conversion at the end of every path (to_fixedv, LSQT_VW values at once, 4 as
 * on a GPU and 16 as on a CPU): one lane special, every other 0.5, for each lane. Each
 * lane must be converted on its own: a NaN or a negative one is 0 and raises the
 * non-finite flag, one above 2^63 units takes the exact general path, one above the range
 * is clamped and raises the overflow flag; the other lanes stay exact. */
static void test_blocks(int vw)
{
    char opt[64];
    snprintf(opt, sizeof opt, "-DLSQT_VW=%d", vw);
    cl_program prog = build(opt);
    if (!prog) return;
    const float special[] = {NAN, -1.0f, 1.25e7f, 1e12f, 2e13f};
    const unsigned want_flag[] = {LSQT_FLAG_NONFINITE, LSQT_FLAG_NONFINITE, 0, 0, LSQT_FLAG_OVERFLOW};
    const float want_value[] = {0.0f, 0.0f, 1.25e7f, 1e12f, 17592186044416.0f};
    enum { NS = 5, MAXW = 16 };
    const size_t items = (size_t)NS * (size_t)vw;
    float v[NS * MAXW * MAXW];
    uint64_t out[2 * NS * MAXW * MAXW];
    cl_uint flags[NS * MAXW];
    for (size_t i = 0; i < items; i++)
        for (int j = 0; j < vw; j++) v[i * (size_t)vw + (size_t)j] = j == (int)(i % (size_t)vw) ? special[i / (size_t)vw] : 0.5f;
    memset(flags, 0, sizeof flags);
    cl_int e = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "harness_tally_block", &e);
    cl_mem bv = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, items * (size_t)vw * sizeof *v, v, &e);
    cl_mem bo = clCreateBuffer(fixture_cx.ctx, CL_MEM_WRITE_ONLY, items * (size_t)vw * 2 * sizeof *out, NULL, &e);
    cl_mem bf = clCreateBuffer(fixture_cx.ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, items * sizeof *flags, flags, &e);
    clSetKernelArg(k, 0, sizeof bv, &bv);
    clSetKernelArg(k, 1, sizeof bo, &bo);
    clSetKernelArg(k, 2, sizeof bf, &bf);
    if (e == CL_SUCCESS) e = clEnqueueNDRangeKernel(fixture_cx.queue, k, 1, NULL, &items, NULL, 0, NULL, NULL);
    if (e == CL_SUCCESS)
        e = clEnqueueReadBuffer(fixture_cx.queue, bo, CL_TRUE, 0, items * (size_t)vw * 2 * sizeof *out, out, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(fixture_cx.queue, bf, CL_TRUE, 0, items * sizeof *flags, flags, 0, NULL, NULL);
    CHECK(e == CL_SUCCESS, "harness_tally_block: %s (%d)", lsqt_cl_error_name(e), (int)e);
    int bad = 0;
    for (size_t i = 0; i < items && e == CL_SUCCESS; i++) {
        const int s = (int)(i / (size_t)vw), lane = (int)(i % (size_t)vw);
        int ok = flags[i] == want_flag[s];
        bad += !ok;
        CHECK(ok, "width %d, %g in lane %d: flags %u, want %u", vw, special[s], lane, flags[i], want_flag[s]);
        for (int j = 0; j < vw; j++) {
            lsqt_u128 want = ref_units(j == lane ? want_value[s] : 0.5f);
            const uint64_t *g = out + 2 * (i * (size_t)vw + (size_t)j);
            ok = g[0] == want.lo && g[1] == want.hi;
            bad += !ok;
            CHECK(ok, "width %d, %g in lane %d: lane %d is %016llx%016llx units", vw, special[s], lane, j,
                  (unsigned long long)g[1], (unsigned long long)g[0]);
        }
    }
    printf("block conversion, width %d: %d lanes x %d special values, %d wrong\n", vw, vw, NS, bad);
    clReleaseMemObject(bv);
    clReleaseMemObject(bo);
    clReleaseMemObject(bf);
    clReleaseKernel(k);
    clReleaseProgram(prog);
}

/* Host side: a tally as a number, and the flags that fail a run. */
static void test_host(void)
{
    lsqt_u128 one_high = {0, 1}, mixed = {12345, 3};
    CHECK(lsqt_u128_to_double(one_high) == 18446744073709551616.0, "2^64 units read as %.17g",
          lsqt_u128_to_double(one_high));
    CHECK(lsqt_u128_to_double(mixed) == 3 * 18446744073709551616.0 + 12345, "%.17g", lsqt_u128_to_double(mixed));
    lsqt_u128 a = {~0ull, 5}, b = {1, 0}, c = lsqt_u128_add(a, b);
    CHECK(c.lo == 0 && c.hi == 6, "carry of lsqt_u128_add");
    char err[256] = "";
    CHECK(lsqt_tally_flags_error(0, err, sizeof err) == 0, "no flags: %s", err);
    CHECK(lsqt_tally_flags_error(LSQT_FLAG_NONFINITE, err, sizeof err) == 0, "a dropped NaN is reported, not fatal");
    CHECK(lsqt_tally_flags_error(LSQT_FLAG_OVERFLOW, err, sizeof err) != 0 && strstr(err, "tally range"),
          "an overflow must fail the run: '%s'", err);
}

/* Path ranges (shards, partial merges): each batch's path count over several ranges, and
 * the range set's rules, against counting path indices one by one (chunk p / CHUNK is in
 * batch chunk % BATCHES). */
static void test_ranges(void)
{
    lsqt_state st;
    CHECK(lsqt_state_init(&st, "x", 1, 2, 1, 16, 0, 1, NULL) == 0, "state");
    const uint64_t r[] = {9000, 9001, 0, 1000, 5000, 7000, 1000, 1300, 7100, 7100};
    CHECK(lsqt_state_set_ranges(&st, r, 5) == 0, "set ranges");
    CHECK(st.n_ranges == 3 && st.ranges[0] == 0 && st.ranges[1] == 1300 && st.ranges[2] == 5000 &&
              st.ranges[5] == 9001 && st.paths == 1300 + 2000 + 1,
          "ranges not sorted, joined and summed: %d ranges, %llu paths", st.n_ranges, (unsigned long long)st.paths);
    uint64_t nb[LSQT_BATCHES], want[LSQT_BATCHES] = {0};
    lsqt_state_batch_counts(&st, nb);
    for (int i = 0; i < st.n_ranges; i++)
        for (uint64_t p = st.ranges[2 * i]; p < st.ranges[2 * i + 1]; p++) want[(p / LSQT_CHUNK) % LSQT_BATCHES]++;
    int bad = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) bad += nb[b] != want[b];
    CHECK(bad == 0, "%d batches hold the wrong path count over the ranges", bad);
    CHECK(lsqt_state_contiguous(&st) == UINT64_MAX, "a state with gaps taken for one range");
    CHECK(lsqt_state_add_range(&st, 6000, 6100) == 1 && st.paths == 3301, "an overlapping range accepted");
    CHECK(lsqt_state_add_range(&st, 1300, 5000) == 0 && lsqt_state_add_range(&st, 7000, 9000) == 0 &&
              lsqt_state_contiguous(&st) == 9001,
          "filling the gaps does not give [0, 9001)");
    /* the parts of a shard split tile the range and differ by at most one path */
    uint64_t at = 123, lo, hi, lo0, hi0;
    lsqt_shard_part(123, 1000, 0, 7, &lo0, &hi0);
    for (int k = 0; k < 7; k++) {
        lsqt_shard_part(123, 1000, k, 7, &lo, &hi);
        CHECK(lo == at && hi - lo + 1 >= hi0 - lo0 && hi - lo <= hi0 - lo0, "shard %d/7 is [%llu, %llu)", k,
              (unsigned long long)lo, (unsigned long long)hi);
        at = hi;
    }
    CHECK(at == 1000, "the shards end at %llu, not 1000", (unsigned long long)at);
    lsqt_state_free(&st);
}

int main(void)
{
    test_host();
    test_ranges();
    fixture_open();
    /* the reference itself: 1.5 units rounds to 2, 2^84 units is one high bit */
    CHECK(ref_units(ldexpf(1.5f, -40)).lo == 2 && ref_units(17592186044416.0f).hi == (1ull << 20), "ref_units");
    test_variant("");
    test_variant("-DLSQT_NO_INT64_ATOMICS=1");
    test_blocks(4);
    test_blocks(16);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_tally");
}
