/* The run's memory estimate (memory.h) against the allocations it stands for: a state's
 * tallies (every band's nee, scalars and exit histograms), an RRSS pilot's with its
 * shared histograms, and the peak as the largest of a run's phases; then what a short
 * run of three bands really makes resident (mincore) on a CPU device: its session's
 * tally buffers, and its state once read back, within the estimate for its paths, which
 * is a small part of their size (only the batches a short run reaches are written).
 *   test_memory          all of it
 *   test_memory formula  without the device */
#define _DEFAULT_SOURCE /* mincore */
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include "cl_fixture.h"

#include "lsqt/memory.h"
#include "lsqt/session.h"
#include "lsqt/state.h"

/* The bytes of ST's tallies as state.c allocates them. */
static uint64_t state_bytes(const lsqt_state *st)
{
    return (uint64_t)(lsqt_state_nee_count(st) + lsqt_state_scalar_count(st) + lsqt_state_hist_count(st)) *
           sizeof(lsqt_u128);
}

static void check_tallies(int nb, int ns, int nw, int rx)
{
    lsqt_state st;
    CHECK(lsqt_state_init(&st, "x", 1, 2, ns, nw, 0, nb, NULL) == 0, "state of %d bands", nb);
    CHECK(lsqt_memory_tallies(nb, ns, nw, ns, 0) == state_bytes(&st), "%d bands x %d slices x %d: %llu, state %llu", nb,
          ns, nw, (unsigned long long)lsqt_memory_tallies(nb, ns, nw, ns, 0), (unsigned long long)state_bytes(&st));
    lsqt_state_free(&st);
    /* a pilot: rx candidate sets a slice, one histogram a slice (rrss.c) */
    CHECK(lsqt_state_init(&st, "x", 1, 2, ns * rx, nw, 0, nb, NULL) == 0 && lsqt_state_group_hist(&st, rx) == 0,
          "pilot state");
    CHECK(lsqt_memory_tallies(nb, ns * rx, nw, ns, 0) == state_bytes(&st), "pilot of %d bands, rx %d: %llu, state %llu",
          nb, rx, (unsigned long long)lsqt_memory_tallies(nb, ns * rx, nw, ns, 0), (unsigned long long)state_bytes(&st));
    lsqt_state_free(&st);
}

/* Resident bytes of [p, p + bytes): the pages mincore says are in memory. */
static uint64_t resident(const void *p, size_t bytes)
{
    const uintptr_t pg = (uintptr_t)sysconf(_SC_PAGESIZE), a = (uintptr_t)p / pg * pg;
    const size_t n = ((uintptr_t)p + bytes - a + pg - 1) / pg;
    unsigned char *v = calloc(n, 1);
    uint64_t r = 0;
    if (v && mincore((void *)a, n * pg, v) == 0)
        for (size_t i = 0; i < n; i++) r += (v[i] & 1) ? pg : 0;
    free(v);
    return r;
}

/* The process's resident bytes (/proc/self/statm). */
static uint64_t rss_bytes(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long long size = 0, res = 0;
    if (!f || fscanf(f, "%llu %llu", &size, &res) != 2) res = 0;
    if (f) fclose(f);
    return (uint64_t)res * (uint64_t)sysconf(_SC_PAGESIZE);
}

/* 3 bands (one block), 4 slices x 16 directions, 1000 paths: the first 4 of 32 batches. */
static void check_resident(void)
{
    const char *text = "Medium\nLayer z=0 LambertianBsdf fR=0.2,0.4,0.6 fT=0\nMedium\n";
    enum { NS = 4, NW = 16, NB = 3, PATHS = 1000 };
    lsqt_assembly a;
    lsqt_diag d;
    memset(&d, 0, sizeof d);
    CHECK(lsqt_parse(text, strlen(text), "t", NULL, 0, ".", &a, &d) == 0, "parse: %s", d.error);
    lsqt_state st;
    CHECK(lsqt_state_init(&st, "t", lsqt_assembly_hash(&a), 5, NS, NW, 0, NB, NULL) == 0, "state");
    for (int s = 0; s < NS; s++) {
        st.theta_o[s] = 0.3 * s;
        for (int k = 0; k < NW; k++) {
            float *w = st.wi + ((size_t)s * NW + (size_t)k) * 4;
            const double t = 0.09 * k, ph = 0.4 * k;
            w[0] = (float)(sin(t) * cos(ph)), w[1] = (float)fabs(sin(t) * sin(ph)), w[2] = (float)cos(t);
        }
    }
    lsqt_session s;
    char err[1024];
    CHECK(lsqt_session_open(&s, &fixture_cx, &a, &st, NULL, 0, 0, err, sizeof err) == 0, "session: %s", err);
    CHECK(lsqt_session_launch(&s, 0, PATHS, err, sizeof err) == 0, "launch: %s", err);
    const uint64_t bound = lsqt_memory_tallies(NB, NS, NW, NS, PATHS), dense = lsqt_memory_tallies(NB, NS, NW, NS, 0);
    CHECK(bound < dense / 4, "the estimate for %d paths, %llu, is not a small part of %llu", PATHS,
          (unsigned long long)bound, (unsigned long long)dense);
    if (fixture_cx.dev.is_cpu) {
        uint64_t r = 0;
        for (int i = 0; i < 3; i++) {
            CHECK(s.host[i] != NULL, "a CPU device's tally buffer %d is not the session's zero pages", i);
            if (s.host[i]) r += resident(s.host[i], s.host_bytes[i]);
        }
        CHECK(r > 0 && r <= bound, "the device's tallies: %llu bytes resident, the estimate %llu (all %llu)",
              (unsigned long long)r, (unsigned long long)bound, (unsigned long long)dense);
    }
    /* the state's pages are counted by the process's RSS (mincore counts the shared zero
     * page that a read of a never-written page maps; RSS does not): only the pages of
     * nonzero tallies are written */
    const uint64_t rss0 = rss_bytes();
    CHECK(lsqt_session_read(&s, &st, 1, err, sizeof err) == 0, "read: %s", err);
    const uint64_t grew = rss_bytes() - rss0;
    /* the last read (release) gave the device's tallies back: nothing more to launch */
    CHECK(!s.nee && !s.hist && !s.host[0] && !s.host[2], "the tallies' buffers are kept after the last read");
    CHECK(lsqt_session_launch(&s, PATHS, 2 * PATHS, err, sizeof err) == 1, "a launch after the last read");
    lsqt_session_close(&s);
    CHECK(grew <= bound + 64 * 4096, "the state's tallies: RSS grew by %llu bytes as they were read, the estimate %llu "
          "(all %llu)", (unsigned long long)grew, (unsigned long long)bound, (unsigned long long)dense);
    uint64_t nonzero = 0;
    for (size_t i = 0; i < lsqt_state_hist_count(&st); i++) nonzero += st.hist[i].lo || st.hist[i].hi;
    CHECK(nonzero > 100, "%llu exits tallied", (unsigned long long)nonzero);
    lsqt_state_free(&st);
    lsqt_assembly_free(&a);
}

int main(int argc, char **argv)
{
#ifdef M_MMAP_THRESHOLD
    mallopt(M_MMAP_THRESHOLD, 128 * 1024); /* the state's tallies in pages of their own, fresh */
#endif
    check_tallies(1, 12, 80, 4);
    check_tallies(32, 12, 80, 4);
    check_tallies(3, 5, 1024, 2);

    /* the default grid, 32 bands: a histogram is 512 KB a slice and band, nee 40 KB */
    lsqt_memory_shape m = {32, 12, 80, 0, 1, 0, 1, 0};
    const uint64_t t = lsqt_memory_tallies(32, 12, 80, 12, 0);
    CHECK(t == 32ull * 12 * 32 * (80 + 7 + 1024) * 16, "32-band tallies %llu", (unsigned long long)t);
    lsqt_memory e = lsqt_memory_estimate(&m);
    CHECK(e.state >= t && e.state < t + t / 50, "state %llu against tallies %llu", (unsigned long long)e.state,
          (unsigned long long)t);
    CHECK(e.device >= t && e.device < t + t / 10, "device %llu against tallies %llu", (unsigned long long)e.device,
          (unsigned long long)t);
    CHECK(e.pilot == 0, "no pilot");
    CHECK(e.peak == e.runtime + e.state + e.device + e.extra, "peak of a run without a pilot");
    /* with a pilot of rx 4: its nee four times the state's, the histograms the same */
    m.pilot_rx = 4;
    lsqt_memory p = lsqt_memory_estimate(&m);
    CHECK(p.pilot >= lsqt_memory_tallies(32, 48, 80, 12, 0) && p.pilot > e.state, "pilot %llu", (unsigned long long)p.pilot);
    CHECK(p.peak >= p.runtime + 2 * p.pilot && p.peak >= p.runtime + p.pilot + p.state && p.peak >= e.peak,
          "peak with a pilot %llu", (unsigned long long)p.peak);
    /* from below: the sides' copies of the state */
    m.pilot_rx = 0, m.sides = 2;
    lsqt_memory s = lsqt_memory_estimate(&m);
    CHECK(s.extra >= e.extra + e.state, "sides' copies %llu", (unsigned long long)s.extra);
    /* 4096 bands of the default grid: 24 GB of histograms dense, so they are packed
     * (state.h): the state holds its sums and scalars dense and at most 12 bytes a bin
     * (32768 a histogram: unbounded paths) and 48 a batch of them; the device the sums and
     * scalars, one block's (16 bands') histograms and every band's direction tables */
    m.sides = 1, m.n_bands = 4096;
    const lsqt_memory b4 = lsqt_memory_estimate(&m);
    const uint64_t rest = lsqt_memory_tallies(4096, 12, 80, 0, 0), pk = 4096ull * 12 * (32768 * 12 + 32 * 48);
    CHECK(rest == 4096ull * 12 * 32 * (80 + 7) * 16, "sums and scalars %llu", (unsigned long long)rest);
    CHECK(b4.state >= rest + pk && b4.state < rest + pk + rest / 50, "4096 bands: state %llu",
          (unsigned long long)b4.state);
    CHECK(b4.device >= rest + lsqt_memory_tallies(16, 0, 80, 12, 0) &&
              b4.device < rest + lsqt_memory_tallies(16, 0, 80, 12, 0) + 4096ull * 12 * 8 * 96 * 4 + rest / 50,
          "4096 bands: device %llu", (unsigned long long)b4.device);
    CHECK(b4.peak == b4.runtime + b4.state + b4.device + b4.extra, "4096 bands: peak");
    char b[32];
    CHECK(strcmp(lsqt_memory_format((uint64_t)3 << 29, b, 32), "1.5 GB") == 0, "format %s", b);
    CHECK(strcmp(lsqt_memory_format((uint64_t)500 << 20, b, 32), "500 MB") == 0, "format %s", b);
    if (argc < 2 || strcmp(argv[1], "formula") != 0) {
        fixture_open();
        check_resident();
        lsqt_context_release(&fixture_cx);
    }
    return check_finish("test_memory");
}
