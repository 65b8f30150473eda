/* Private to lsqt-cl's run command (host/commands/): main.c dispatches to run_command.c,
 * which calls the others in the order of a run: signals.c (the stop signals), run_state.c
 * (a fresh state, or the LSS continued and its checks), run_outputs.c (the files a run
 * writes, their locks, the writing). No file here calls run_command.c or main.c. */
#ifndef LSQT_RUN_CMD_H
#define LSQT_RUN_CMD_H

#include <signal.h>
#include <stdio.h>

#include "lsqt/assembly.h"
#include "lsqt/cli.h"
#include "lsqt/memory.h"
#include "lsqt/outputs.h"
#include "lsqt/state.h"
#include "lsqt/tally.h"
#include "lsqt/report.h"
#include "lsqt/util.h"

/* "lsqt-cl: error: " FMT (with a and b) on stderr; returns code. */
static inline int fail(int code, const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "lsqt-cl: error: ");
    fprintf(stderr, fmt, a, b);
    fprintf(stderr, "\n");
    return code;
}

/* signals.c */
extern volatile sig_atomic_t g_stop;  /* the signal that asked to stop, 0 if none */
extern volatile sig_atomic_t g_armed; /* the input is read: Ctrl-C now means "finish" */
/* Before any other thread exists, so that every thread inherits the blocked signals. */
void sigint_setup(void);
const char *signal_name(int sig);
/* FN runs (on the signals' thread) before a stop at once exits: what must not be left
 * behind (--plan's folder). NULL: nothing. */
void sigint_at_stop(void (*fn)(void));

/* run_command.c: everything lsqt-cl does with an input once its flags are read; returns
 * the exit status. */
int run_command(const lsqt_cli *c);
/* The shape of the last run_command's memory estimate (memory.h; n_bands 0 before one),
 * which --plan estimates again for the paths of the run it plans. */
extern lsqt_memory_shape g_run_shape;
/* plan.c: --plan (two calibration runs through run_command, then the prediction). */
int plan_command(const lsqt_cli *c);

/* run_outputs.c: the names of the files a run writes (lsqt/outputs.h does the rest). */
typedef struct outputs {
    lsqt_outputs f;              /* every file; f.path[LSQT_OUT_*] the names before band labels */
    const char *base;            /* the LSS continued (a shard writes its own, f.path[LSQT_OUT_LSS]) */
    char raw[LSQT_PATH_CAP + 16], raw_t[LSQT_PATH_CAP + 16], lss[LSQT_PATH_CAP + 16], shard[LSQT_PATH_CAP + 40];
    char raw_b[LSQT_PATH_CAP + 32], raw_bt[LSQT_PATH_CAP + 32];
} outputs;

/* Decides every output name (every band's) and checks them against each other and every
 * file the run reads (the input, its tables, --wi-file). ST NULL: before the state is
 * read (the names to lock). ST given (continued: read from an LSS): the sides follow the
 * state, so --from-below notes are printed and a two-sided state plans again with the
 * RAW files of the side from below (O freed first). Returns 0, or 2 (1 out of memory)
 * with err filled and nothing to free. */
int run_plan_outputs(const lsqt_cli *c, int from_stdin, const lsqt_assembly *a, const lsqt_state *st, int continued,
                     outputs *o, char *err, size_t errcap);
void run_outputs_free(outputs *o);
/* Locks the LSS the run writes (exclusive) and, for a shard, the state it reads (shared),
 * before that is read. Returns 0, or 1 (printed) when another run holds one. */
int run_lock_states(const outputs *o, int quiet);
/* Writes every output (lsqt_outputs_write): the LSS is lss_st (an interrupted RRSS
 * pilot's own state), the rest from st. Returns 0 or 1. */
int run_write_outputs(const outputs *o, const lsqt_cli *c, const lsqt_state *st, const lsqt_state *lss_st,
                      const lsqt_slice_est *est, const lsqt_run_info *ri, FILE *info);

/* run_state.c */
/* A fresh state: slices, incident directions and zero tallies (wi_file: the --wi-file
 * directions, n_wi_file of them, or NULL). Returns 0 or -1 (out of memory). */
int run_new_state(lsqt_state *st, const lsqt_cli *c, const lsqt_assembly *a, const char *canonical,
                  const float *wi_file, int n_wi_file);
/* The state of this run: the LSS at lss_path continued (checked against the assembly and
 * the flags), or a fresh one. Returns 0, or an exit status (printed; nothing to free);
 * *continued: the LSS was read. */
int run_open_state(lsqt_state *st, const lsqt_cli *c, const lsqt_assembly *a, const char *lss_path,
                   const float *wi_dirs, int n_wi_dirs, int n_mirrored, int *continued);

#endif
