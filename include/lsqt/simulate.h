/* The launch loop: uploads an assembly's device tables and a state's tallies, runs paths
 * on the device in launches over (chunks of paths, slices), and reads the tallies back. */
#ifndef LSQT_SIMULATE_H
#define LSQT_SIMULATE_H

#include <signal.h>
#include <stdint.h>

#include "lsqt/assembly.h"
#include "lsqt/device.h"
#include "lsqt/state.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lsqt_sim_opts {
    int progress;                 /* draw a progress bar on stderr */
    double time_limit;            /* seconds, 0 = none */
    size_t local_size;            /* work-group size, 0 = automatic */
    volatile sig_atomic_t *stop;  /* set asynchronously (Ctrl-C): stop after this launch */
    const char *extra_options;    /* appended to the kernel build options (tests, tuning) */
    int verbose;                  /* print the kernel build options and launches on stderr */
} lsqt_sim_opts;

typedef struct lsqt_sim_stats {
    uint64_t paths_added;         /* per slice */
    double seconds;
    int interrupted;              /* stopped early by *stop or the time limit */
} lsqt_sim_stats;

/* Returns 0, or 1 with err filled (build log, if any, already printed to stderr). Models
 * the kernels do not implement yet are refused before anything runs. */
int lsqt_simulate(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t add_paths,
                  const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap);

/* Fills the device tables of an assembly in double precision (exposed for the tests;
 * a float kernel gets them rounded). */
void lsqt_device_tables(const lsqt_assembly *a, lsqt_dev_scene *scene, lsqt_dev_medium_d *media,
                        lsqt_dev_layer_d *layers);

/* NULL when the kernels support every model of the assembly, else the first model name. */
const char *lsqt_unsupported_model(const lsqt_assembly *a, int *line);

#ifdef __cplusplus
}
#endif
#endif
