/* The launch loop: runs paths of a state on the device in launches over (chunks of paths,
 * slices) through a session (session.h), with progress and the stop rules (path count,
 * time limit, interrupt, target error), and reads the tallies back into the state. */
#ifndef LSQT_SIMULATE_H
#define LSQT_SIMULATE_H

#include <signal.h>
#include <stdint.h>

#include "lsqt/assembly.h"
#include "lsqt/device.h"
#include "lsqt/session.h"
#include "lsqt/state.h"
#include "lsqt/tables.h"

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
    double target_error;          /* > 0: stop once every slice's largest relative standard
                                     error of the point estimates is at most this (checked at
                                     path counts that depend only on the tallies, so the stop
                                     is reproducible); add_paths is then a cap */
    double checkpoint_every;      /* > 0: call checkpoint with the state this often (seconds) */
    int (*checkpoint)(const lsqt_state *st, void *ctx); /* e.g. writes the LSS; 0 = ok */
    void *checkpoint_ctx;
    const char *phase;            /* the progress bar's label ("RRSS pilot", ...), NULL: none */
} lsqt_sim_opts;

enum {
    LSQT_STOP_PATHS = 0,  /* the requested paths are done (with a target error: the cap) */
    LSQT_STOP_TARGET,     /* the target error is reached */
    LSQT_STOP_TIME,       /* the time limit */
    LSQT_STOP_INTERRUPT   /* *stop was set */
};

typedef struct lsqt_sim_stats {
    uint64_t paths_added;         /* per slice */
    double seconds;
    int interrupted;              /* stopped early by *stop or the time limit */
    int stop_reason;              /* LSQT_STOP_* */
    int launches;
} lsqt_sim_stats;

/* Returns 0, or 1 with err filled (build log, if any, already printed to stderr). Models
 * the kernels do not implement yet are refused before anything runs. A two-sided ST
 * (below.h) runs both sides on the same paths, A mirrored for below (the session's lanes),
 * and comes back with its slices from above first. */
int lsqt_simulate(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t add_paths,
                  const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap);

/* The same for paths [begin, begin + add_paths) (a shard: ST may hold none of [0, begin)).
 * ST's ranges get the paths done; its span_end grows to cover them. */
int lsqt_simulate_range(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t begin, uint64_t add_paths,
                        const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap);

/* The launch loop of lsqt_simulate on an open session (whose tallies are ST's), paths
 * [begin, begin + add_paths). While it launches, ST's tallies are only the session's
 * (the host's pages given back) until a read copies them all back; on an error (1) they
 * are undefined and ST is not to be used further. */
int lsqt_run_range(lsqt_session *s, lsqt_state *st, uint64_t begin, uint64_t add_paths, const lsqt_sim_opts *o,
                   lsqt_sim_stats *stats, char *err, size_t errcap);

/* The largest over the slices of the largest relative standard error of the point
 * estimates; NaN while a run may not stop on it (fewer than LSQT_STOP_ERR_PATHS paths). */
double lsqt_max_rel_err(const lsqt_state *st);

/* With --target-error: the path count at which to check the error next, after PATHS with
 * error ERR (NaN: unknown); a function of the tallies only, so a stop is reproducible. */
uint64_t lsqt_next_check(uint64_t paths, double err, double target);
/* The paths at which an error err at `paths` paths falls to target, by 1/sqrt(paths):
 * paths (err / target)^2; NaN when err is (no error bars yet). The stop rule, the
 * progress line, the summary and --plan all predict with it. */
double lsqt_paths_for_error(uint64_t paths, double err, double target);

#ifdef __cplusplus
}
#endif
#endif
