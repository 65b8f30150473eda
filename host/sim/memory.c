#include "lsqt/memory.h"

#include <stdio.h>
#include <string.h>

#include "lsqt/band_blocks.h"
#include "lsqt/device_layout.h"
#include "lsqt/state.h"
#include "lsqt/tally.h"

#define MB ((uint64_t)1 << 20)
/* PoCL with its kernel build and the program's own: a one-band run of the default grid
 * peaks at 96 MB (tools/bench_memory.py). */
#define RUNTIME_BYTES (128 * MB)

#define PAGE ((uint64_t)4096)

/* The resident bytes of ROWS rows of B batches of W tallies each when only the first K
 * batches of a row are written: K W words from each row's start, on at most two pages
 * more than they fill (where they start and end inside one). */
static uint64_t rows_bytes(uint64_t rows, uint64_t w, uint64_t k)
{
    const uint64_t full = LSQT_BATCHES * w * sizeof(lsqt_u128), part = k * w * sizeof(lsqt_u128);
    if (k >= LSQT_BATCHES) return rows * full;
    const uint64_t row = (part + PAGE - 1) / PAGE * PAGE + PAGE;
    return rows * (row < full ? row : full);
}

uint64_t lsqt_memory_tallies(int n_bands, int n_slices, int n_wi, int hist_slices, uint64_t paths)
{
    const uint64_t nb = (uint64_t)n_bands, ns = (uint64_t)n_slices;
    const uint64_t chunks = (paths + LSQT_CHUNK - 1) / LSQT_CHUNK, k = paths && chunks < LSQT_BATCHES ? chunks : LSQT_BATCHES;
    /* state.h: per band [slice][batch][n_wi] nee, [slice][batch][LSQT_T_COUNT] scalars,
     * [histogram][batch][LSQT_HIST_BINS] exit histograms */
    return nb * (rows_bytes(ns, (uint64_t)n_wi, k) + rows_bytes(ns, LSQT_T_COUNT, k) +
                 rows_bytes((uint64_t)hist_slices, LSQT_HIST_BINS, k));
}

/* Packed histograms (state.h: lsqt_state_hist_packs, for the shapes that pack) of
 * n_bands bands with hist_slices histograms each at PATHS per slice (0: unbounded): a
 * path exits once, so a histogram has at most PATHS nonzero bins over its batches, each
 * at most 12 bytes packed, and every batch's block costs about 48 bytes of allocation. */
static int hist_packs(uint64_t nb, uint64_t hist_slices)
{
    return nb > 1 && nb * hist_slices * LSQT_BATCHES * LSQT_HIST_BINS * sizeof(lsqt_u128) > LSQT_PACK_HIST_BYTES;
}

static uint64_t packed_hist(uint64_t nb, uint64_t hist_slices, uint64_t paths)
{
    const uint64_t bins = (uint64_t)LSQT_BATCHES * LSQT_HIST_BINS, nz = paths && paths < bins ? paths : bins;
    return nb * hist_slices * (nz * 12 + LSQT_BATCHES * 48);
}

/* The tallies of a state (its histograms packed where it packs them) and of the device
 * for it (on a CPU device a packed state's histograms are there one band block at a time,
 * session.h). */
static void state_and_device(const lsqt_memory_shape *m, int n_slices, int hist_slices, uint64_t *state,
                             uint64_t *device)
{
    const uint64_t nb = (uint64_t)m->n_bands;
    if (!hist_packs(nb, (uint64_t)hist_slices)) {
        *state = *device = lsqt_memory_tallies(m->n_bands, n_slices, m->n_wi, hist_slices, m->paths);
        return;
    }
    const uint64_t rest = lsqt_memory_tallies(m->n_bands, n_slices, m->n_wi, 0, m->paths);
    const int block = m->n_bands < LSQT_BAND_BLOCK_MAX ? m->n_bands : LSQT_BAND_BLOCK_MAX;
    *state = rest + packed_hist(nb, (uint64_t)hist_slices, m->paths);
    *device = rest + lsqt_memory_tallies(block, 0, m->n_wi, hist_slices, m->paths);
}

/* The device's direction tables and directions of one band block, each band counted as
 * a block of its own (the most there can be; session.c's upload). */
static uint64_t device_tables(const lsqt_memory_shape *m, int n_slices)
{
    const uint64_t nb = (uint64_t)m->n_bands, pad = (uint64_t)m->n_wi + 15;
    const uint64_t dsz = m->use_double ? 8 : 4, rows = (uint64_t)m->n_layers * LSQT_LAYER_TAB_ROWS + LSQT_MEDIA_TAB_ROWS;
    return nb * (uint64_t)n_slices * (rows + 3) * pad * dsz;
}

lsqt_memory lsqt_memory_estimate(const lsqt_memory_shape *m)
{
    lsqt_memory r;
    memset(&r, 0, sizeof r);
    const uint64_t nb = (uint64_t)m->n_bands, ns = (uint64_t)m->n_slices;
    uint64_t st_tallies, dev_tallies;
    state_and_device(m, m->n_slices, m->n_slices, &st_tallies, &dev_tallies);
    r.state = st_tallies + ns * (uint64_t)m->n_wi * 16;
    r.device = dev_tallies + device_tables(m, m->n_slices);
    /* the sides of a state from below are copies of its slices (below.h); the estimates
     * of every band for the outputs */
    r.extra = (m->sides > 1 ? r.state : 0) + nb * ns * (sizeof(lsqt_slice_est) + (uint64_t)m->n_wi * sizeof(lsqt_est));
    r.runtime = RUNTIME_BYTES;
    uint64_t top = r.state + r.device + r.extra;
    if (m->pilot_rx > 0) { /* a slice's rx candidate sets share one histogram (rrss.c) */
        const int ps = m->n_slices * m->pilot_rx;
        uint64_t p_tallies, p_device;
        state_and_device(m, ps, m->n_slices, &p_tallies, &p_device);
        r.pilot = p_tallies + (uint64_t)ps * (uint64_t)m->n_wi * 16;
        const uint64_t pilot_run = r.pilot + p_device + device_tables(m, ps), choose = r.pilot + r.state;
        if (pilot_run > top) top = pilot_run;
        if (choose > top) top = choose;
    }
    r.peak = r.runtime + top;
    return r;
}

/* A number from the first line of FILE ("max" reads as none: 0). */
static uint64_t read_number(const char *path)
{
    FILE *f = fopen(path, "r");
    unsigned long long v = 0;
    if (!f) return 0;
    if (fscanf(f, "%llu", &v) != 1) v = 0;
    fclose(f);
    return (uint64_t)v;
}

uint64_t lsqt_memory_available(void)
{
    uint64_t avail = 0;
    FILE *f = fopen("/proc/meminfo", "r");
    char line[256];
    while (f && fgets(line, sizeof line, f)) {
        unsigned long long kb = 0;
        if (sscanf(line, "MemAvailable: %llu kB", &kb) == 1) avail = (uint64_t)kb * 1024;
    }
    if (f) fclose(f);
    /* the cgroup this process is in (v2: "0::/path"; v1: the memory controller's) */
    char cg[256] = "", cg1[256] = "", path[700];
    f = fopen("/proc/self/cgroup", "r");
    while (f && fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = 0;
        const char *v1 = strstr(line, ":memory:");
        if (strncmp(line, "0::", 3) == 0) snprintf(cg, sizeof cg, "%s", line + 3);
        else if (v1) snprintf(cg1, sizeof cg1, "%s", v1 + 8);
    }
    if (f) fclose(f);
    uint64_t limit = 0, used = 0;
    for (int k = 0; k < 2 && !limit && cg[0]; k++) {
        snprintf(path, sizeof path, "/sys/fs/cgroup%s/memory.max", k ? "" : cg);
        limit = read_number(path);
        snprintf(path, sizeof path, "/sys/fs/cgroup%s/memory.current", k ? "" : cg);
        used = read_number(path);
    }
    if (!limit) {
        /* (in a container the controller's root is the process's own cgroup) */
        for (int k = 0; k < 2 && !limit; k++) {
            snprintf(path, sizeof path, "/sys/fs/cgroup/memory%s/memory.limit_in_bytes", k ? "" : cg1);
            limit = read_number(path);
            snprintf(path, sizeof path, "/sys/fs/cgroup/memory%s/memory.usage_in_bytes", k ? "" : cg1);
            used = read_number(path);
        }
        if (limit >= ((uint64_t)1 << 60)) limit = 0; /* v1's "no limit" */
    }
    if (limit) {
        const uint64_t left = limit > used ? limit - used : 0;
        if (!avail || left < avail) avail = left;
    }
    return avail;
}

const char *lsqt_memory_format(uint64_t bytes, char *buf, int cap)
{
    if (bytes >= ((uint64_t)1 << 30)) snprintf(buf, (size_t)cap, "%.3g GB", (double)bytes / (double)((uint64_t)1 << 30));
    else snprintf(buf, (size_t)cap, "%.3g MB", (double)bytes / (double)MB);
    return buf;
}
