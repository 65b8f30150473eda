/* The run's memory estimate (memory.h) against the allocations it stands for: a state's
 * tallies (every band's nee, scalars and exit histograms), an RRSS pilot's with its
 * shared histograms, and the peak as the largest of a run's phases. */
#include "check.h"

#include "lsqt/memory.h"
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
    CHECK(lsqt_state_init_bands(&st, "x", 1, 2, ns, nw, 0, nb, NULL) == 0, "state of %d bands", nb);
    CHECK(lsqt_memory_tallies(nb, ns, nw, ns) == state_bytes(&st), "%d bands x %d slices x %d: %llu, state %llu", nb,
          ns, nw, (unsigned long long)lsqt_memory_tallies(nb, ns, nw, ns), (unsigned long long)state_bytes(&st));
    lsqt_state_free(&st);
    /* a pilot: rx candidate blocks a slice, one histogram a slice (rrss.c) */
    CHECK(lsqt_state_init_bands(&st, "x", 1, 2, ns * rx, nw, 0, nb, NULL) == 0 && lsqt_state_group_hist(&st, rx) == 0,
          "pilot state");
    CHECK(lsqt_memory_tallies(nb, ns * rx, nw, ns) == state_bytes(&st), "pilot of %d bands, rx %d: %llu, state %llu",
          nb, rx, (unsigned long long)lsqt_memory_tallies(nb, ns * rx, nw, ns), (unsigned long long)state_bytes(&st));
    lsqt_state_free(&st);
}

int main(void)
{
    check_tallies(1, 12, 80, 4);
    check_tallies(32, 12, 80, 4);
    check_tallies(3, 5, 1024, 2);

    /* the default grid, 32 bands: a histogram is 512 KB a slice and band, nee 40 KB */
    lsqt_memory_shape m = {32, 12, 80, 0, 1, 0, 1};
    const uint64_t t = lsqt_memory_tallies(32, 12, 80, 12);
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
    CHECK(p.pilot >= lsqt_memory_tallies(32, 48, 80, 12) && p.pilot > e.state, "pilot %llu", (unsigned long long)p.pilot);
    CHECK(p.peak >= p.runtime + 2 * p.pilot && p.peak >= p.runtime + p.pilot + p.state && p.peak >= e.peak,
          "peak with a pilot %llu", (unsigned long long)p.peak);
    /* from below: the sides' copies of the state */
    m.pilot_rx = 0, m.sides = 2;
    lsqt_memory s = lsqt_memory_estimate(&m);
    CHECK(s.extra >= e.extra + e.state, "sides' copies %llu", (unsigned long long)s.extra);
    /* bands scale it: 4096 bands of the default grid are 27 GB of tallies at least */
    m.sides = 1, m.n_bands = 4096;
    CHECK(lsqt_memory_estimate(&m).peak > 2 * 128 * t, "4096 bands");
    char b[32];
    CHECK(strcmp(lsqt_memory_format((uint64_t)3 << 29, b, 32), "1.5 GB") == 0, "format %s", b);
    CHECK(strcmp(lsqt_memory_format((uint64_t)500 << 20, b, 32), "500 MB") == 0, "format %s", b);
    return check_finish("test_memory");
}
