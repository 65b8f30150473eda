/* madvise, MADV_DONTNEED (Linux) are not in POSIX 2008 */
#define _DEFAULT_SOURCE
#include "lsqt/state.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/mman.h>
#endif

static size_t bands_of(const lsqt_state *st) { return (size_t)lsqt_state_bands(st); }

/* A zeroed state (0) and a one-band state (1) both have one band's tallies. */
int lsqt_state_bands(const lsqt_state *st) { return st->n_bands > 1 ? st->n_bands : 1; }

/* One band's counts. */
static size_t nee_per_band(const lsqt_state *st) { return (size_t)st->n_slices * LSQT_BATCHES * (size_t)st->n_wi; }
static size_t scalars_per_band(const lsqt_state *st) { return (size_t)st->n_slices * LSQT_BATCHES * LSQT_T_COUNT; }
static size_t hist_group(const lsqt_state *st) { return st->hist_group > 1 ? st->hist_group : 1; }
static size_t hist_per_band(const lsqt_state *st)
{
    return (size_t)st->n_slices / hist_group(st) * LSQT_BATCHES * LSQT_HIST_BINS;
}

size_t lsqt_state_nee_count(const lsqt_state *st) { return bands_of(st) * nee_per_band(st); }
size_t lsqt_state_scalar_count(const lsqt_state *st) { return bands_of(st) * scalars_per_band(st); }
size_t lsqt_state_hist_count(const lsqt_state *st) { return bands_of(st) * hist_per_band(st); }

lsqt_state lsqt_state_band(const lsqt_state *st, int b)
{
    lsqt_state v = *st;
    v.n_bands = 1;
    v.wavelengths = st->wavelengths ? st->wavelengths + b : NULL; /* its own, for its RAW's header */
    v.nee = st->nee + (size_t)b * nee_per_band(st);
    v.scalars = st->scalars + (size_t)b * scalars_per_band(st);
    v.hist = st->hist ? st->hist + (size_t)b * hist_per_band(st) : NULL;
    v.hist_pk = st->hist_pk ? st->hist_pk + (size_t)b * (hist_per_band(st) / LSQT_HIST_BINS) : NULL;
    return v;
}

lsqt_u128 *lsqt_state_hist_of(const lsqt_state *st, int s)
{
    return st->hist + (size_t)s / hist_group(st) * LSQT_BATCHES * LSQT_HIST_BINS;
}

int lsqt_state_group_hist(lsqt_state *st, int g)
{
    if (g < 1 || st->n_slices % g || hist_group(st) != 1 || st->hist_pk) return -1;
    /* calloc's untouched pages cost nothing: the full-size one is dropped before it is used */
    st->hist_group = (uint32_t)g;
    lsqt_u128 *h = calloc(lsqt_state_hist_count(st), sizeof *h);
    if (!h) {
        st->hist_group = 1;
        return -1;
    }
    free(st->hist);
    st->hist = h;
    return 0;
}

void lsqt_tallies_copy(lsqt_u128 *dst, const lsqt_u128 *src, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (dst[i].lo != src[i].lo || dst[i].hi != src[i].hi) dst[i] = src[i];
}

int lsqt_state_copy_slice_tallies(lsqt_state *dst, int ds, const lsqt_state *src, int ss)
{
    const size_t B = LSQT_BATCHES, nw = (size_t)src->n_wi;
    for (size_t b = 0; b < bands_of(src); b++) {
        lsqt_state d = lsqt_state_band(dst, (int)b), s = lsqt_state_band(src, (int)b);
        lsqt_tallies_copy(d.nee + (size_t)ds * B * nw, s.nee + (size_t)ss * B * nw, B * nw);
        lsqt_tallies_copy(d.scalars + (size_t)ds * B * LSQT_T_COUNT, s.scalars + (size_t)ss * B * LSQT_T_COUNT,
                          B * LSQT_T_COUNT);
    }
    return lsqt_state_copy_hist(dst, ds, src, ss);
}

int lsqt_state_init(lsqt_state *st, const char *canonical, uint64_t hash, uint64_t seed, int n_slices, int n_wi,
                    int transmits, int n_bands, const double *wl)
{
    memset(st, 0, sizeof *st);
    st->n_bands = n_bands > 1 ? n_bands : 1;
    if (wl) { /* one band keeps its wavelength too (its RAW header, the JSON, a version 7 LSS) */
        st->wavelengths = malloc((size_t)st->n_bands * sizeof *wl);
        if (!st->wavelengths) return -1;
        memcpy(st->wavelengths, wl, (size_t)st->n_bands * sizeof *wl);
    }
    st->hash = hash;
    st->seed = seed;
    st->n_slices = n_slices;
    st->n_wi = n_wi;
    st->transmits = transmits;
    st->canonical = malloc(strlen(canonical) + 1);
    st->theta_o = calloc((size_t)n_slices, sizeof *st->theta_o);
    st->wi = calloc((size_t)n_slices * (size_t)n_wi * 4, sizeof *st->wi);
    st->nee = calloc(lsqt_state_nee_count(st), sizeof *st->nee);
    st->scalars = calloc(lsqt_state_scalar_count(st), sizeof *st->scalars);
    st->hist = calloc(lsqt_state_hist_count(st), sizeof *st->hist);
    st->slice_flags = calloc((size_t)n_slices, sizeof *st->slice_flags);
    if (!st->canonical || !st->theta_o || !st->wi || !st->nee || !st->scalars || !st->hist || !st->slice_flags) {
        lsqt_state_free(st);
        return -1;
    }
    strcpy(st->canonical, canonical);
    return 0;
}

void lsqt_state_free(lsqt_state *st)
{
    free(st->canonical);
    free(st->theta_o);
    free(st->wi);
    free(st->nee);
    free(st->scalars);
    free(st->hist);
    if (st->hist_pk) {
        lsqt_state_drop_hist(st, 0, st->n_slices);
        free(st->hist_pk);
    }
    free(st->ranges);
    free(st->slice_flags);
    free(st->wavelengths);
    memset(st, 0, sizeof *st);
}

uint64_t lsqt_batch_paths(uint64_t total, int b)
{
    uint64_t full = total / LSQT_CHUNK, rest = total % LSQT_CHUNK;
    uint64_t chunks = full / LSQT_BATCHES + ((uint64_t)b < full % LSQT_BATCHES ? 1u : 0u);
    return chunks * LSQT_CHUNK + (full % LSQT_BATCHES == (uint64_t)b ? rest : 0u);
}

double lsqt_u128_to_double(lsqt_u128 v) { return ldexp((double)v.hi, 64) + (double)v.lo; }

lsqt_u128 lsqt_u128_add(lsqt_u128 a, lsqt_u128 b)
{
    lsqt_u128 r = {a.lo + b.lo, a.hi + b.hi};
    r.hi += r.lo < a.lo;
    return r;
}

void lsqt_state_batch_counts(const lsqt_state *st, uint64_t nb[LSQT_BATCHES])
{
    for (int b = 0; b < LSQT_BATCHES; b++) {
        nb[b] = 0;
        for (int i = 0; i < st->n_ranges; i++)
            nb[b] += lsqt_batch_paths(st->ranges[2 * i + 1], b) - lsqt_batch_paths(st->ranges[2 * i], b);
    }
}

static int range_cmp(const void *x, const void *y)
{
    const uint64_t *a = x, *b = y;
    return (a[0] > b[0]) - (a[0] < b[0]);
}

int lsqt_state_set_ranges(lsqt_state *st, const uint64_t *r, int n)
{
    uint64_t *t = malloc((size_t)(n > 0 ? n : 1) * 2 * sizeof *t);
    if (!t) return -1;
    int m = 0;
    for (int i = 0; i < n; i++)
        if (r[2 * i] < r[2 * i + 1]) t[2 * m] = r[2 * i], t[2 * m + 1] = r[2 * i + 1], m++;
    qsort(t, (size_t)m, 2 * sizeof *t, range_cmp);
    int k = 0;
    uint64_t total = 0;
    for (int i = 0; i < m; i++) {
        if (k > 0 && t[2 * i] < t[2 * k - 1]) {
            free(t);
            return 1;
        }
        if (k > 0 && t[2 * i] == t[2 * k - 1]) t[2 * k - 1] = t[2 * i + 1];
        else t[2 * k] = t[2 * i], t[2 * k + 1] = t[2 * i + 1], k++;
        total += t[2 * i + 1] - t[2 * i];
    }
    free(st->ranges);
    st->ranges = t;
    st->n_ranges = k;
    st->paths = total;
    return 0;
}

int lsqt_state_add_range(lsqt_state *st, uint64_t lo, uint64_t hi)
{
    uint64_t *t = malloc(((size_t)st->n_ranges + 1) * 2 * sizeof *t);
    if (!t) return -1;
    if (st->n_ranges) memcpy(t, st->ranges, (size_t)st->n_ranges * 2 * sizeof *t);
    t[2 * st->n_ranges] = lo, t[2 * st->n_ranges + 1] = hi;
    int rc = lsqt_state_set_ranges(st, t, st->n_ranges + 1);
    free(t);
    return rc;
}

uint64_t lsqt_state_contiguous(const lsqt_state *st)
{
    if (st->n_ranges == 0) return 0;
    return st->n_ranges == 1 && st->ranges[0] == 0 ? st->ranges[1] : UINT64_MAX;
}

void lsqt_state_clear_tallies(lsqt_state *st)
{
    memset(st->nee, 0, lsqt_state_nee_count(st) * sizeof *st->nee);
    memset(st->scalars, 0, lsqt_state_scalar_count(st) * sizeof *st->scalars);
    if (st->hist) memset(st->hist, 0, lsqt_state_hist_count(st) * sizeof *st->hist);
    else lsqt_state_drop_hist(st, 0, st->n_slices);
    free(st->ranges);
    st->ranges = NULL;
    st->n_ranges = 0;
    st->paths = 0;
    st->flags = 0;
}

/* BYTES at P zeroed: the whole pages inside given back (they read as zeros again, as an
 * anonymous private mapping's do, whether malloc made it by mmap or on its heap; a chunk's
 * own bytes hold none of malloc's bookkeeping), the partial ones at the ends memset. */
static void zero_pages(void *p, size_t bytes)
{
    char *c = p, *lo = c, *hi = c;
#ifdef __linux__
    const long pg = sysconf(_SC_PAGESIZE);
    if (pg > 0 && bytes >= 2 * (size_t)pg) {
        const uintptr_t a = (uintptr_t)c, m = (uintptr_t)pg - 1;
        lo = (char *)((a + m) & ~m);
        hi = (char *)((a + bytes) & ~m);
        if (hi <= lo || madvise(lo, (size_t)(hi - lo), MADV_DONTNEED) != 0) lo = hi = c;
    }
#endif
    if (lo == hi) {
        memset(c, 0, bytes);
        return;
    }
    memset(c, 0, (size_t)(lo - c));
    memset(hi, 0, (size_t)(c + bytes - hi));
}

void lsqt_tallies_drop(lsqt_u128 *t, size_t n) { zero_pages(t, n * sizeof *t); }

void lsqt_state_drop_tallies(lsqt_state *st)
{
    lsqt_tallies_drop(st->nee, lsqt_state_nee_count(st));
    lsqt_tallies_drop(st->scalars, lsqt_state_scalar_count(st));
    if (st->hist) lsqt_tallies_drop(st->hist, lsqt_state_hist_count(st)); /* packed ones are not the device's */
}

void lsqt_shard_part(uint64_t begin, uint64_t end, int k, int n, uint64_t *lo, uint64_t *hi)
{
    const uint64_t len = end > begin ? end - begin : 0, q = len / (uint64_t)n, r = len % (uint64_t)n;
    const uint64_t kk = (uint64_t)k;
    *lo = begin + kk * q + (kk < r ? kk : r);
    *hi = *lo + q + (kk < r ? 1u : 0u);
}

/* What must be equal for two states to be parts of one run; NULL when they are. */
const char *lsqt_state_differs(const lsqt_state *a, const lsqt_state *b)
{
    if (a->hash != b->hash || strcmp(a->canonical, b->canonical) != 0) return "assembly";
    if (a->seed != b->seed) return "seed";
    if (a->n_bands != b->n_bands || (a->wavelengths != NULL) != (b->wavelengths != NULL) ||
        (a->wavelengths && memcmp(a->wavelengths, b->wavelengths, (size_t)a->n_bands * sizeof *a->wavelengths)))
        return "bands";
    if (a->use_double != b->use_double) return "precision";
    if (a->stage != b->stage) return "stage (an RRSS pilot shard and a run's state)";
    if (a->n_slices != b->n_slices || a->n_wi != b->n_wi || a->transmits != b->transmits)
        return "shape (slices, directions)";
    if (a->dir_method != b->dir_method || a->rx != b->rx || a->pilot_paths != b->pilot_paths ||
        a->grid_ni != b->grid_ni || a->grid_nphi != b->grid_nphi)
        return "direction method (RRSS pilot, grid)";
    if (memcmp(a->theta_o, b->theta_o, (size_t)a->n_slices * sizeof *a->theta_o) != 0) return "outgoing angles";
    if (memcmp(a->slice_flags, b->slice_flags, (size_t)a->n_slices * sizeof *a->slice_flags) != 0)
        return "slice kinds (from above, from below)";
    if (memcmp(a->wi, b->wi, (size_t)a->n_slices * (size_t)a->n_wi * 4 * sizeof *a->wi) != 0)
        return "incident directions";
    return NULL;
}

