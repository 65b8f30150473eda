/* The stages of one lsqt-cl run on a state (host/sim/stages.c): which paths it runs and how
 * (the RRSS pilot and choice, docs/design.md section 3.5; shards), between reading the input and writing the
 * outputs (host/commands/run_command.c). */
#ifndef LSQT_STAGES_H
#define LSQT_STAGES_H

#include "lsqt/rrss.h"
#include "lsqt/simulate.h"
#include "lsqt/tally.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a run asks of the paths (lsqt-cl fills it from its flags). */
typedef struct lsqt_run_plan {
    uint64_t paths;      /* -p: paths per slice to add */
    int paths_given;     /* -p was given (with a target error it is then a cap) */
    double target_error; /* --target-error, 0 = none */
    double rp;           /* -rp: a fresh RRSS run's pilot is ceil(rp paths) */
    int rx;              /* -rx: RRSS candidates per direction */
    int shard_k, shard_n; /* --shard K/N (shard_n 0: not sharded) */
    int refine;          /* --refine: a shard does only what its state owes */
    int restart;         /* -R: a shard does not continue its own LSS */
    int quiet;           /* -q: no notes on stderr */
} lsqt_run_plan;

typedef struct lsqt_stages {
    lsqt_sim_stats stats;   /* this run: paths added, seconds, why it stopped */
    lsqt_rrss_info rinfo;   /* the RRSS pilot and choice, when there was one */
    lsqt_work before;       /* the state's work counters before the run (a shard: none) */
    uint64_t pilot;         /* a fresh RRSS run's pilot length */
    int pilot_shard;        /* the state is now a shard of an RRSS pilot (write only its LSS) */
    uint64_t part_lo, part_hi, run_lo, run_hi; /* a shard's part [lo, hi) of the run's [lo, hi) */
    int have_ps;            /* an RRSS pilot was interrupted: ps is its state, to be the LSS */
    lsqt_state ps;          /* (free it when have_ps) */
} lsqt_stages;

/* Runs what the plan P asks of ST (read from lss_path, or fresh; a shard's own LSS is own_lss):
 *  - a state that owes paths (a merged RRSS pilot, a partial merge) runs what it owes;
 *  - a fresh RRSS state: the pilot of ceil(rp p) paths, the choice, the rest; a saved
 *    pilot (stage pilot) is finished (no -p, or its run's -p) or chosen from (another -p);
 *  - --shard K/N: the K-th part of the run's paths (of the pilot, for a fresh RRSS state),
 *    continuing own_lss when it holds the start of that part; ST then holds the part only;
 *  - a state with slices from below runs both sides (below.h).
 * Returns 0; 1 with err filled (a run failed); 2 with err filled (bad input or flags). */
int lsqt_run_stages(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, const lsqt_run_plan *p,
                    const char *lss_path, const char *own_lss, const lsqt_sim_opts *so, lsqt_stages *o, char *err,
                    size_t errcap);

#ifdef __cplusplus
}
#endif
#endif
