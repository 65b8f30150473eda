/* A simulation session on one device: the program, the device tables and the tallies of
 * one state, kept across launches (and the stages of a run: pilot, refinement, stop
 * rules). The launch loop itself is in run.c (simulate.h). */
#ifndef LSQT_SESSION_H
#define LSQT_SESSION_H

#include <stdint.h>

#include "lsqt/assembly.h"
#include "lsqt/band_blocks.h"
#include "lsqt/device.h"
#include "lsqt/state.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lsqt_session {
    lsqt_context *cx;
    cl_program prog;
    cl_kernel walk, prepare, exits, estimate;
    cl_mem scene, media, layers, wo, wi, tab, nee, scalars, hist, flags;
    /* The GPU path's next-event records (walk.cl, LSQT_NEE_RECORDS): the records of a
     * launch's paths and their offsets, grown as launches need. */
    int records;
    cl_mem rec, rec_off;
    size_t rec_cap, off_cap;  /* records, offsets the buffers hold */
    size_t rec_size;          /* bytes per record */
    size_t local_size; /* work-group size of the walk */
    int n_slices, n_wi;
    int slice_group;   /* launch slices per simulated slice (1; rx for the RRSS pilot) */
    int vw;            /* directions per vector in the next-event loops (LSQT_VW; pads n_wi) */
    int use_double;
    size_t n_nee, n_scalars, n_hist; /* tally counts (lsqt_u128 each) of one band */
    /* The bands on this session's paths: nb (its program's LSQT_NB; 1 for a one-band
     * program) and the run's band in each slot, -1 for padding (band_blocks.h); bandw the
     * block's table (kernels/bands.cl). Its tallies hold its nb bands one after another. */
    int nb;
    int band_of[LSQT_BAND_BLOCK_MAX];
    cl_mem bandw;
    /* On a CPU device the tally buffers (nee, scalars, hist) are this memory, mapped zero
     * pages (CL_MEM_USE_HOST_PTR; host_bytes each): only the pages that come to hold a
     * nonzero tally are ever resident (a fill with zeros would make every page so). NULL
     * on a GPU, whose buffers are filled on the device. */
    void *host[3];
    size_t host_bytes[3];
    /* ST's histograms packed (lsqt_state_pack_hist) on a CPU device: the session borrows
     * them launch by launch (session.c's stream_hist), so its histogram buffer holds only
     * the batches of the launch running; its reads then read them from this state, which
     * must be the one read into and outlive the session. NULL: the buffer holds them. */
    struct lsqt_state *hist_home;
    /* 1: the caller runs one range on this session (lsqt_simulate_range, the RRSS pilot),
     * so lsqt_run_range's last read releases each block's tallies as it reads them */
    int last_read_releases;
    /* A run with bands: this session is the first block's (band 0's), and blocks[i - 1]
     * block i's, each with its own tables and tallies; blocks of one width share one
     * program. A launch runs every block over the same path indices. */
    int n_blocks;
    struct lsqt_session *blocks;
    /* A two-sided state (below.h): this session is the lane of its slices from above and
     * *below the lane of those from below, on the mirrored assembly; each lane runs its
     * side of the state (held in lanes, session.c), and a launch, read, exits or new
     * directions serve both lanes, on the same paths. NULL for a one-sided state. */
    struct lsqt_session *below;
    struct lsqt_lanes *lanes;
} lsqt_session;

/* The vector widths (LSQT_VW) of the two code paths by default (session.c says why). */
#define LSQT_CPU_VECTOR_WIDTH 16
#define LSQT_GPU_VECTOR_WIDTH 2

/* The OpenCL build options of A's program for n_wi directions per slice in groups of
 * GROUP (1; rx for the RRSS pilot), vw directions per vector, the GPU code path or the
 * CPU's, the precision, and whether the device has 64-bit atomics (the kernels' text is
 * lsqt_kernel_text). Returns 0, or 1 when cap is too small. */
int lsqt_kernel_options(const lsqt_assembly *a, int n_wi, int group, int vw, int gpu, int use_double,
                        int int64_atomics, char *opt, size_t cap);

/* Builds the program for assembly A and state ST (its precision and direction count),
 * uploads the tables, directions and ST's tallies, and fills the direction tables. A
 * state with slices from below gets a lane per side (A mirrored for below); its reads
 * then give ST both sides joined (lsqt_state_join_by_side: above's slices first).
 * extra_options: appended to the build options (tests, tuning); local_size 0 = automatic.
 * Returns 0, or 1 with err filled (a build log, if any, already printed to stderr). */
int lsqt_session_open(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                      const char *extra_options, size_t local_size, int verbose, char *err, size_t errcap);

/* The same, where every slice_group consecutive slices of ST are one simulated slice
 * whose walks serve all their direction sets at once (the RRSS pilot: the kernels are
 * built for slice_group x PAD(n_wi, vw) directions; each slice gets the walks' R, T, work
 * and histogram). */
int lsqt_session_open_grouped(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                              int slice_group, const char *extra_options, size_t local_size, int verbose,
                              char *err, size_t errcap);

/* lsqt_session_open, where the session takes ST's tallies: each band block's are given
 * back on the host (lsqt_tallies_drop) once they are on the device, until a read copies
 * them all back (lsqt_run_range's). For a caller that reads none of ST's tallies before
 * then; on an error they are undefined. */
int lsqt_session_open_taking(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                             const char *extra_options, size_t local_size, int verbose, char *err, size_t errcap);

/* Uploads ST's directions again (same count) and remakes their tables. Returns 0 or 1. */
int lsqt_session_set_directions(lsqt_session *s, const lsqt_state *st, char *err, size_t errcap);

/* RRSS candidate walks: paths [begin, begin + n) of every simulated slice; out gets
 * n_slices / slice_group x n x 4 floats (x, y, z, 1 for a scattered exit, else all 0).
 * Returns 0 or 1. */
int lsqt_session_exits(lsqt_session *s, uint64_t begin, uint32_t n, float *out, char *err, size_t errcap);

/* Runs paths [begin, end) of every slice (the chunks they touch) and waits for them.
 * Returns 0, or 1 with err filled. */
int lsqt_session_launch(lsqt_session *s, uint64_t begin, uint64_t end, char *err, size_t errcap);

/* Copies the device tallies into ST and ORs the device flags into ST's (paths are the
 * caller's to count). With release, the session's last read: each block's tally buffers
 * are released once read, so the state and the device hold a block's tallies twice one
 * block at a time, not every block's at once (the session cannot launch again). Returns
 * 0, or 1 with err filled. */
int lsqt_session_read(lsqt_session *s, lsqt_state *st, int release, char *err, size_t errcap);

void lsqt_session_close(lsqt_session *s);

#ifdef __cplusplus
}
#endif
#endif
