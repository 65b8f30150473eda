/* What one lsqt-cl run does with its state (docs/design.md section 3.5; shards: docs/guide.md):
 * a plain run or the rest of one it owes, an RRSS pilot (fresh, resumed, or a shard's part of it), the choice of the
 * directions, a shard's part of the paths (resuming its own file), both sides of a
 * two-sided state. host/commands/run_command.c reads the input and writes the outputs around it. */
#include "lsqt/stages.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/below.h"
#include "lsqt/lss.h"
#include "lsqt/util.h"

/* One run's facts, decided once from its plan and its state. */
typedef struct stage_ctx {
    lsqt_context *cx;
    const lsqt_assembly *a;
    const lsqt_run_plan *p;
    const lsqt_sim_opts *so;
    const char *lss_path;
    int pilot_base; /* the state is a saved RRSS pilot (a checkpoint or an interrupted pilot) */
    int owes;       /* the state is part of a run (a merged RRSS pilot, a partial merge) */
    int fresh_rrss; /* a fresh RRSS state: the pilot is the first rp of this run's -p */
    uint64_t held;  /* the paths the state holds from 0 on (UINT64_MAX: gaps) */
    uint64_t add;   /* the paths to add (UINT64_MAX: until the target error) */
} stage_ctx;

/* The state's work counters before the run, which the report subtracts. */
static lsqt_work work_before(const lsqt_state *st, int pilot_base, int shard)
{
    lsqt_work before = lsqt_work_totals(st);
    if (pilot_base) {
        /* each candidate set holds the same walks' work: one block's work is the pilot's */
        before.paths /= st->rx, before.layer_events /= st->rx, before.medium_events /= st->rx;
        before.nee_evaluations /= st->rx;
    }
    if (shard) memset(&before, 0, sizeof before); /* a shard's file holds only its own work */
    return before;
}

/* A shard run again (after a time limit or a signal) continues its own file when that
 * holds the start of this very part. Returns 1 with *prev read and *resume its end, else 0. */
static int shard_resume(const stage_ctx *k, const lsqt_state *st, const char *own_lss, const lsqt_stages *o,
                        lsqt_state *prev, uint64_t *resume, char *err, size_t errcap)
{
    const lsqt_run_plan *p = k->p;
    const char *sp = own_lss, *kind = NULL;
    if (p->restart || lsqt_path_type(sp, &kind) != LSQT_PATH_REGULAR || lsqt_lss_read(sp, prev, err, errcap) != 0)
        return 0;
    const uint64_t x = prev->n_ranges == 0                                ? o->part_lo
                       : prev->n_ranges == 1 && prev->ranges[0] == o->part_lo ? prev->ranges[1]
                                                                           : UINT64_MAX;
    const int match =
        k->fresh_rrss ? prev->stage == LSQT_STAGE_PILOT && prev->hash == st->hash &&
                            strcmp(prev->canonical, st->canonical) == 0 && prev->seed == st->seed &&
                            prev->use_double == st->use_double && prev->rx == (uint32_t)p->rx &&
                            prev->pilot_paths == o->pilot &&
                            prev->span_end == (p->paths > o->pilot ? p->paths : o->pilot) &&
                            prev->n_slices == st->n_slices * p->rx && prev->n_wi == st->n_wi
                      : !lsqt_state_differs(prev, st) && prev->span_end == o->run_hi;
    if (match && x <= o->part_hi) {
        *resume = x;
        if (!p->quiet)
            fprintf(stderr, "continuing %s: paths [%llu, %llu) of this part are done\n", sp,
                    (unsigned long long)o->part_lo, (unsigned long long)x);
        return 1;
    }
    if (!p->quiet) fprintf(stderr, "note: replacing %s (not a part of this run)\n", sp);
    lsqt_state_free(prev);
    return 0;
}

/* A shard's part of a fresh RRSS pilot, on every slice's candidates (the merge chooses);
 * the shard's state is then the pilot's part. */
static int shard_pilot(const stage_ctx *k, lsqt_state *st, int resumed, lsqt_state *prev, uint64_t resume,
                       lsqt_stages *o, char *err, size_t errcap)
{
    const lsqt_run_plan *p = k->p;
    int rc;
    if (resumed) {
        o->ps = *prev;
        rc = lsqt_rrss_pilot_continue(k->cx, k->a, &o->ps, resume, o->part_hi - resume, k->so, &o->rinfo, err,
                                      errcap);
        if (rc) lsqt_state_free(&o->ps);
    } else {
        rc = lsqt_rrss_pilot(k->cx, k->a, st, p->rx, o->pilot, p->paths, o->part_lo, o->part_hi - o->part_lo, k->so,
                             &o->ps, &o->rinfo, err, errcap);
    }
    if (!rc) {
        lsqt_state_free(st);
        *st = o->ps; /* the shard's state is now the pilot's part */
        memset(&o->ps, 0, sizeof o->ps);
        o->pilot_shard = 1;
        o->stats.paths_added = st->paths;
        o->stats.seconds = o->rinfo.seconds;
        if (o->rinfo.interrupted)
            o->stats.interrupted = 1, o->stats.stop_reason = *k->so->stop ? LSQT_STOP_INTERRUPT : LSQT_STOP_TIME;
    }
    return rc;
}

/* --shard K/N: the K-th of N near-equal parts of the run's range, continuing the shard's
 * own LSS when it holds the start of that part. */
static int run_shard(const stage_ctx *k, lsqt_state *st, const char *own_lss, lsqt_stages *o, char *err,
                     size_t errcap)
{
    const lsqt_run_plan *p = k->p;
    if (p->refine && st->paths == 0 && !k->owes) {
        snprintf(err, errcap, "--refine: '%s' holds no merged run yet: run the shards without --refine first, "
                              "then lsqt-cl merge", k->lss_path ? k->lss_path : "the LSS");
        return 2;
    }
    if (k->pilot_base) {
        snprintf(err, errcap, "'%s' holds (part of) an RRSS pilot: merge all of the pilot's shards first "
                              "(lsqt-cl merge OUT.lss SHARDS...)", k->lss_path);
        return 2;
    }
    /* The run's range, then the K-th of N near-equal parts of it. */
    o->run_lo = k->held;
    o->run_hi = k->fresh_rrss ? o->pilot : k->owes ? st->span_end : p->refine ? k->held : k->held + k->add;
    lsqt_shard_part(o->run_lo, o->run_hi, p->shard_k, p->shard_n, &o->part_lo, &o->part_hi);
    lsqt_state prev;
    uint64_t resume = o->part_lo;
    const int resumed = shard_resume(k, st, own_lss, o, &prev, &resume, err, errcap);
    if (k->fresh_rrss) return shard_pilot(k, st, resumed, &prev, resume, o, err, errcap);
    if (resumed) {
        lsqt_state_free(st);
        *st = prev;
    } else {
        lsqt_state_clear_tallies(st);
    }
    int rc = lsqt_simulate_range(k->cx, k->a, st, resume, o->part_hi - resume, k->so, &o->stats, err, errcap);
    st->span_end = o->run_hi;
    return rc;
}

/* A saved RRSS pilot: the same run (no -p, or its -p) finishes the pilot and the run, the
 * bytes of the uninterrupted run; another -p chooses from the pilot so far, then adds -p.
 * The pilot moves from st to o->ps. */
static int resume_pilot(const stage_ctx *k, lsqt_state *st, int *finish_pilot, lsqt_stages *o, char *err,
                        size_t errcap)
{
    const lsqt_run_plan *p = k->p;
    o->ps = *st;
    memset(st, 0, sizeof *st);
    o->have_ps = 1;
    *finish_pilot = !p->paths_given || p->paths == o->ps.span_end;
    if (!p->quiet)
        fprintf(stderr, *finish_pilot ? "note: '%s' holds %llu of the %llu paths of an RRSS pilot: this run "
                                        "finishes it, then the run (%llu paths per slice)\n"
                                      : "note: '%s' holds %llu of the %llu paths of an RRSS pilot: the "
                                        "directions are chosen from them, then -p %llu more paths\n",
                k->lss_path, (unsigned long long)o->ps.paths, (unsigned long long)o->ps.pilot_paths,
                (unsigned long long)(*finish_pilot ? o->ps.span_end : p->paths));
    if (!*finish_pilot) return 0; /* nothing more to run in the pilot */
    if (k->held == UINT64_MAX || k->held > o->ps.pilot_paths) {
        snprintf(err, errcap, "'%s' does not hold one range [0, h) of its RRSS pilot", k->lss_path);
        return 1;
    }
    return lsqt_rrss_pilot_continue(k->cx, k->a, &o->ps, k->held, o->ps.pilot_paths - k->held, k->so, &o->rinfo, err,
                                    errcap);
}

/* The choice of directions from the pilot o->ps into st, and the paths left to add. An
 * interrupted pilot: its LSS is the pilot (continuing finishes it); the RAW and summary
 * show a provisional choice from what it has. */
static int choose(const stage_ctx *k, lsqt_state *st, int finish_pilot, uint64_t *add, lsqt_stages *o, char *err,
                  size_t errcap)
{
    const int pilot_base = k->pilot_base;
    lsqt_state chosen;
    lsqt_rrss_info ci;
    memset(&ci, 0, sizeof ci);
    /* the pilot is freed next unless it was interrupted (its LSS is the pilot's then) */
    int rc = o->rinfo.interrupted ? lsqt_rrss_choose(&o->ps, &chosen, &ci, err, errcap)
                                  : lsqt_rrss_choose_using(&o->ps, &chosen, &ci, err, errcap);
    if (!rc) {
        o->rinfo.density_fallback = ci.density_fallback;
        o->rinfo.seconds += ci.select_seconds;
        lsqt_state_free(st);
        *st = chosen;
        if (o->rinfo.interrupted) *add = 0;
        else if (pilot_base && !finish_pilot) st->span_end = st->paths; /* the rest is abandoned */
        else if (pilot_base) *add = st->span_end - st->paths;
        else if (*add != UINT64_MAX) *add -= st->paths;
    }
    return rc;
}

/* A whole run: RRSS's pilot (fresh, or the rest of a saved one), the choice, the rest of
 * the run. Checkpoints during the pilot save the pilot state, which continues exactly. */
static int run_whole(const stage_ctx *k, lsqt_state *st, lsqt_stages *o, char *err, size_t errcap)
{
    const lsqt_run_plan *p = k->p;
    const uint64_t paths_before = st->paths;
    uint64_t add = k->add;
    int rc = 0, finish_pilot = 1;
    if (k->fresh_rrss) {
        rc = lsqt_rrss_pilot(k->cx, k->a, st, p->rx, o->pilot, add == UINT64_MAX ? o->pilot : p->paths, 0, o->pilot,
                             k->so, &o->ps, &o->rinfo, err, errcap);
        o->have_ps = !rc;
    } else if (k->pilot_base) {
        rc = resume_pilot(k, st, &finish_pilot, o, err, errcap);
    }
    if (o->have_ps && !rc) rc = choose(k, st, finish_pilot, &add, o, err, errcap);
    lsqt_sim_opts ro = *k->so; /* the progress bar says which part of the run it is */
    ro.phase = o->have_ps ? "refining the chosen directions" : NULL;
    /* the pilot's tallies are the chosen state's now: freed before the rest of the run
     * opens its session (they are kept only for an interrupted pilot's LSS) */
    if (o->have_ps && !o->rinfo.interrupted) {
        lsqt_state_free(&o->ps);
        o->have_ps = 0;
    }
    if (!rc && !o->rinfo.interrupted) rc = lsqt_simulate(k->cx, k->a, st, add, &ro, &o->stats, err, errcap);
    o->stats.seconds += o->rinfo.seconds;
    o->stats.paths_added = st->paths - paths_before;
    if (o->rinfo.interrupted)
        o->stats.interrupted = 1, o->stats.stop_reason = *k->so->stop ? LSQT_STOP_INTERRUPT : LSQT_STOP_TIME;
    return rc;
}

int lsqt_run_stages(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, const lsqt_run_plan *p,
                    const char *lss_path, const char *own_lss, const lsqt_sim_opts *so, lsqt_stages *o, char *err,
                    size_t errcap)
{
    memset(o, 0, sizeof *o);
    stage_ctx k = {cx, a, p, so, lss_path, st->stage == LSQT_STAGE_PILOT, 0, 0, 0, 0};
    o->before = work_before(st, k.pilot_base, p->shard_n != 0);
    /* With a target error, -p is a cap when given, else there is none. */
    k.add = p->target_error > 0 && !p->paths_given ? UINT64_MAX : p->paths;
    /* A state that owes paths (a merged RRSS pilot, a partial merge) completes its run. */
    k.held = lsqt_state_contiguous(st);
    k.owes = k.held < st->span_end && !k.pilot_base;
    if (k.owes) {
        k.add = st->span_end - k.held;
        if (!p->quiet)
            fprintf(stderr, "note: '%s' is part of a run of %llu paths per slice: this run does the %llu it owes%s\n",
                    lss_path, (unsigned long long)st->span_end, (unsigned long long)k.add,
                    p->paths_given ? " (-p is not used)" : "");
    }
    k.fresh_rrss = st->dir_method == LSQT_DIRS_RRSS && st->paths == 0 && !k.owes && !k.pilot_base;
    /* A fresh RRSS state: the pilot is the first rp of this run's -p (its tallies stay). */
    if (k.fresh_rrss) {
        o->pilot = (uint64_t)ceil(p->rp * (double)p->paths);
        if (o->pilot < 1) o->pilot = 1;
        if (o->pilot > p->paths) o->pilot = p->paths;
    }
    /* (a state with slices from below runs each side as a lane of the same session, on
     * the same paths: session.h) */
    int rc = p->shard_n ? run_shard(&k, st, own_lss, o, err, errcap) : run_whole(&k, st, o, err, errcap);
    if (!rc && !p->quiet) lsqt_rrss_notes(stderr, &o->rinfo);
    return rc;
}
