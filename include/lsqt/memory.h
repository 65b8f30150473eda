/* What a run will hold in memory at its peak, before it allocates: the host state, the
 * RRSS pilot's state, the device's buffers (on a CPU device such as PoCL, host memory too;
 * on a GPU they are counted all the same) and the copies made around them, from the run's
 * shape and its paths. Tallies cost only the pages of the ones that can be nonzero
 * (state.h's lsqt_tallies_copy, session.h's host): a run of P paths per slice reaches the
 * first ceil(P / LSQT_CHUNK) of the LSQT_BATCHES batches of every slice, and only their
 * pages are counted. One function serves the run's refusal (--max-memory) and --plan. */
#ifndef LSQT_MEMORY_H
#define LSQT_MEMORY_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lsqt_memory_shape {
    int n_bands;    /* wavelength bands (1 or more: lsqt_state_bands) */
    int n_slices;   /* slices of the state (both sides for --from-below) */
    int n_wi;       /* incident directions per slice */
    int pilot_rx;   /* a fresh RRSS pilot: its candidates per direction (-rx); 0: no pilot */
    int sides;      /* 2: slices from above and from below (--from-below), else 1 */
    int use_double; /* --double: directions and tables in double */
    int n_layers;   /* layers of the stack (the device's direction tables) */
    uint64_t paths; /* paths per slice the state holds at the end (0: not bounded, as a
                     * --target-error run without -p: every batch counted) */
} lsqt_memory_shape;

typedef struct lsqt_memory {
    uint64_t state;   /* the run's state: every band's tallies (nee, scalars, exit histograms) */
    uint64_t pilot;   /* the RRSS pilot's state (0 without a pilot) */
    uint64_t device;  /* the device's tallies and tables for the state (every band block at once) */
    uint64_t extra;   /* the sides' copies (--from-below), the estimates for the outputs */
    uint64_t runtime; /* the OpenCL runtime and the kernel build (a constant) */
    uint64_t peak;    /* runtime + the largest of: pilot + its device buffers, pilot + state,
                       * state + device + extra */
} lsqt_memory;

/* Bytes of the tallies of a state of this many bands (1 or more), slices and directions,
 * with hist_slices exit histograms per band (n_slices; a pilot's slices share theirs), that
 * can be resident when it holds PATHS per slice (0: every batch; then all of them, the
 * allocation's size). */
uint64_t lsqt_memory_tallies(int n_bands, int n_slices, int n_wi, int hist_slices, uint64_t paths);
/* The estimate for SHAPE. */
lsqt_memory lsqt_memory_estimate(const lsqt_memory_shape *shape);
/* The memory this process may use: MemAvailable (/proc/meminfo), less where a cgroup's
 * limit leaves less; 0 when neither can be read. */
uint64_t lsqt_memory_available(void);
/* "1.23 GB", "456 MB" into buf. */
const char *lsqt_memory_format(uint64_t bytes, char *buf, int cap);

#ifdef __cplusplus
}
#endif
#endif
