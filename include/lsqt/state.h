/* The state of a simulation: what it is of (assembly text and hash, seed, directions)
 * and the integer tallies so far. It is exactly what the LSS file stores, so a run can
 * be resumed, split or merged without changing a single bit of the result. */
#ifndef LSQT_STATE_H
#define LSQT_STATE_H

#include <stddef.h>
#include <stdint.h>

#include "lsqt/device_layout.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lsqt_state {
    char *canonical;        /* canonical assembly text */
    uint64_t hash;          /* lsqt_assembly_hash */
    uint64_t seed;
    int use_double;         /* precision the tallies were made with */
    int transmits;          /* 1: directions on the sphere, RAW is RAWBS */
    int n_slices, n_wi;
    double *theta_o;        /* n_slices, radians, wo = (sin, 0, cos) */
    float *wi;              /* n_slices * n_wi * 4 (x, y, z, 0), unit, y >= 0 */
    uint64_t paths;         /* paths held per slice (every slice the same): the sum of ranges */
    int n_ranges;           /* the path-index ranges held, [lo, hi) pairs, sorted, disjoint, */
    uint64_t *ranges;       /* not adjacent (one [0, paths) for a plain run; shards hold parts) */
    uint64_t span_end;      /* the run this state belongs to covers [0, span_end) (>= the ranges);
                             * more than the ranges hold: it owes paths (a shard, a pilot) */
    uint32_t stage;         /* LSQT_STAGE_*: a run's state, or a shard of an RRSS pilot */
    uint32_t *slice_flags;  /* n_slices: LSQT_SLICE_* */
    lsqt_u128 *nee;         /* [slice][LSQT_BATCHES][n_wi] fixed point */
    lsqt_u128 *scalars;     /* [slice][LSQT_BATCHES][LSQT_T_COUNT] */
    lsqt_u128 *hist;        /* [slice / hist_group][LSQT_BATCHES][LSQT_HIST_BINS] fixed point */
    uint32_t hist_group;    /* slices that share one histogram (lsqt_state_hist_of; 0 reads as 1):
                             * the RRSS pilot's rx blocks of a slice, whose exits are the same
                             * paths'. An LSS holds every slice's (the group's, repeated). */
    uint32_t flags;         /* LSQT_FLAG_* raised so far */
    uint32_t dir_method;    /* LSQT_DIRS_*: how the directions were chosen */
    uint32_t rx;            /* RRSS: candidates per direction (0 otherwise) */
    uint64_t pilot_paths;   /* RRSS: paths of the pilot, the first of every slice's paths */
    uint32_t grid_ni, grid_nphi; /* LSQT_DIRS_GRID: the grid's NI and NPHI; LSQT_DIRS_RGL: NU and 0
                                  * (directions.h; 0 otherwise) */
    uint32_t lss_version;   /* the LSS format version it was read from (0: not read from a file) */
    int n_bands;            /* wavelength bands (1: one; lsqt_assembly's bands); the tallies
                             * are band after band, each block laid out as a one-band state's */
    double *wavelengths;    /* n_bands nm, or NULL (one band, or unnamed bands) */
    struct lsqt_hist_pack *hist_pk; /* NULL: the histograms are hist; else they are held packed
                                     * (hist NULL): [band][histogram][batch] (lsqt_state_pack_hist) */
} lsqt_state;

/* One batch of one histogram, packed: the LSS's form of its LSQT_HIST_BINS tallies
 * (lss.h: runs of zeros, nonzero tallies in their significant bytes); p NULL: all zero. */
typedef struct lsqt_hist_pack {
    unsigned char *p;
    uint32_t n;
} lsqt_hist_pack;

enum { LSQT_DIRS_SPREAD = 0, LSQT_DIRS_RRSS = 1, LSQT_DIRS_FILE = 2, LSQT_DIRS_GRID = 3, LSQT_DIRS_RGL = 4 };
/* LSQT_STAGE_PILOT: the RRSS pilot of a sharded run (slices are candidate sets: slice
 * s * rx + j is slice s's j-th block of n_wi candidates; pilot_paths its length, span_end
 * the first run's -p). Merging all of its shards chooses the directions. */
enum { LSQT_STAGE_RUN = 0, LSQT_STAGE_PILOT = 1 };
enum { LSQT_SLICE_BELOW = 1u }; /* light enters from the bottom medium */

/* Allocates zeroed tallies for the given shape and n_bands bands (1: one; wl their
 * wavelengths, copied, or NULL); copies canonical. Returns 0 or -1. */
int lsqt_state_init(lsqt_state *st, const char *canonical, uint64_t hash, uint64_t seed, int n_slices, int n_wi,
                    int transmits, int n_bands, const double *wl);
/* ST's band count, at least 1 (n_bands is stored as it is read: an LSS before bands, or
 * a zeroed state, has 0). */
int lsqt_state_bands(const lsqt_state *st);
/* Band b of ST as a one-band state: the same fields, its tallies (and its wavelength, if
 * any) pointing into ST's (not to be freed; valid while ST is). */
lsqt_state lsqt_state_band(const lsqt_state *st, int b);
/* Slices of ST share their histograms in groups of G (hist_group), tallies kept if G
 * divides n_slices and the histograms are zero (a fresh pilot state). Returns 0 or -1. */
int lsqt_state_group_hist(lsqt_state *st, int g);
/* Slice s's histogram in ST (or in a band view of it): [LSQT_BATCHES][LSQT_HIST_BINS]; a
 * state whose histograms are dense only (hist_pk NULL). */
lsqt_u128 *lsqt_state_hist_of(const lsqt_state *st, int s);

/* Exit histograms dense or packed (host/state/hist.c). A band's histograms at the default
 * grid are 6 MB dense, and a run of 10^4 paths touches every page of them while its LSS
 * packs them to an eighth: a run of many bands holds them packed, batch by batch, and a
 * CPU device's buffers hold a batch only while a launch adds to it (session.h). */
/* Whether ST's histograms should be held packed: LSQT_PACK_HIST=1 or 0 says; else when
 * there are bands and the dense histograms would take more than LSQT_PACK_HIST_BYTES. */
#define LSQT_PACK_HIST_BYTES ((size_t)256 << 20)
int lsqt_state_hist_packs(const lsqt_state *st);
/* The packed form's token V as an unsigned LEB128 varint into O (at most 10 bytes);
 * returns its length. The LSS writer and the packed histograms share it. */
size_t lsqt_tally_varint(unsigned char *o, uint64_t v);
/* Packs ST's histograms (their dense memory freed), if lsqt_state_hist_packs says so or
 * FORCE. Returns 0, or -1 out of memory (ST unchanged). */
int lsqt_state_pack_hist(lsqt_state *st, int force);
/* Batch t of slice s's histogram of band b (s / hist_group is the histogram) into OUT[i *
 * stride] for its LSQT_HIST_BINS bins: only the nonzero ones are written, so OUT must hold
 * zeros (a page of zeros stays unmapped). */
void lsqt_state_hist_read(const lsqt_state *st, int b, int s, int t, lsqt_u128 *out, size_t stride);
/* The same batch set from IN[i * stride]. Returns 0, or -1 out of memory (unchanged). */
int lsqt_state_hist_write(lsqt_state *st, int b, int s, int t, const lsqt_u128 *in, size_t stride);
/* Every band's histogram of slice ss of SRC into slice ds of DST (dense or packed, either). */
int lsqt_state_copy_hist(lsqt_state *dst, int ds, const lsqt_state *src, int ss);
/* SRC's histograms added to DST's (the same shape; dense or packed, either). Returns 0, or
 * -1 out of memory. */
int lsqt_state_add_hist(lsqt_state *dst, const lsqt_state *src);
/* The histograms of slices [s0, s1) of every band zeroed, their memory given back. */
void lsqt_state_drop_hist(lsqt_state *st, int s0, int s1);
/* DST gets SRC's n tallies, a word written only where it differs: the zero words of a
 * fresh (calloc'd) DST are never written, so their pages stay unmapped and a state costs
 * the memory of the pages its nonzero tallies are on (the exit histograms of a short run
 * are mostly zero: its batches not yet reached, bins never hit). */
void lsqt_tallies_copy(lsqt_u128 *dst, const lsqt_u128 *src, size_t n);
/* Slice ss's tallies of SRC, in every band, into slice ds of DST (same bands, n_wi).
 * Returns 0, or -1 out of memory (DST's packed histograms). */
int lsqt_state_copy_slice_tallies(lsqt_state *dst, int ds, const lsqt_state *src, int ss);
void lsqt_state_free(lsqt_state *st);

/* Tally counts (each one lsqt_u128), all bands together. */
size_t lsqt_state_nee_count(const lsqt_state *st);
size_t lsqt_state_scalar_count(const lsqt_state *st);
size_t lsqt_state_hist_count(const lsqt_state *st);

/* Paths of [0, total) that fall in batch b (chunk c belongs to batch c % LSQT_BATCHES). */
uint64_t lsqt_batch_paths(uint64_t total, int b);
/* Paths held in each batch (over all ranges). */
void lsqt_state_batch_counts(const lsqt_state *st, uint64_t nb[LSQT_BATCHES]);

/* Sets the held ranges (n pairs lo, hi; empty ones dropped), sorted and joined, and paths
 * to their total. Returns 0, -1 out of memory, or 1 when two of them overlap (nothing
 * changed then). */
int lsqt_state_set_ranges(lsqt_state *st, const uint64_t *r, int n);
/* Adds [lo, hi) to the held ranges; returns as lsqt_state_set_ranges. */
int lsqt_state_add_range(lsqt_state *st, uint64_t lo, uint64_t hi);
/* h when the state holds exactly [0, h) (0: nothing), UINT64_MAX when it has gaps. */
uint64_t lsqt_state_contiguous(const lsqt_state *st);
/* The K-th of N near-equal parts [lo, hi) of [begin, end) (the first (end-begin) % N
 * parts one path longer); the parts of all K tile the range. */
void lsqt_shard_part(uint64_t begin, uint64_t end, int k, int n, uint64_t *lo, uint64_t *hi);
/* What differs between A and B that parts of one run must share (assembly, seed,
 * precision, stage, shape, direction method, angles, slice kinds, directions), as a
 * phrase; NULL when nothing does. */
const char *lsqt_state_differs(const lsqt_state *a, const lsqt_state *b);
/* Zero tallies, no ranges, no flags: the same directions, ready for another part of a run. */
void lsqt_state_clear_tallies(lsqt_state *st);
/* Zero tallies, nothing else changed, their whole pages given back to the system (on
 * Linux: madvise MADV_DONTNEED, which leaves zero pages; elsewhere a memset). For a state
 * whose tallies a session's device buffers hold until its next read, which restores every
 * word (lsqt_run_range): the host's copy then costs nothing in between. Packed
 * histograms are kept (a CPU device borrows them launch by launch: session.h). */
void lsqt_state_drop_tallies(lsqt_state *st);
/* The same for N tallies at T (a part of a state's). */
void lsqt_tallies_drop(lsqt_u128 *t, size_t n);

/* A tally as a number: units (fixed point divides by LSQT_FIX_SCALE), and exact sums. */
double lsqt_u128_to_double(lsqt_u128 v);
lsqt_u128 lsqt_u128_add(lsqt_u128 a, lsqt_u128 b);

#ifdef __cplusplus
}
#endif
#endif
