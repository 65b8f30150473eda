/* What one lsqt-cl run does with its state (docs/design.md section 3.5; shards: docs/guide.md):
 * a plain run or the rest of one it owes, an RRSS pilot (fresh, resumed, or a shard's part of it), the choice of the
 * directions, a shard's part of the paths (resuming its own file), both sides of a
 * two-sided state. main.c reads the input and writes the outputs around it. */
#include "lsqt/stages.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/below.h"
#include "lsqt/lss.h"
#include "lsqt/util.h"

int lsqt_run_stages(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, const lsqt_cli *c, const char *lss_path,
                    const char *own_lss, const lsqt_sim_opts *so, lsqt_stages *o, char *err, size_t errcap)
{
    memset(o, 0, sizeof *o);
    int rc = 0;
    const int pilot_base = st->stage == LSQT_STAGE_PILOT; /* a checkpoint or an interrupted pilot */
    o->before = lsqt_work_totals(st);
    if (pilot_base) {
        /* each candidate block holds the same walks' work: one block's work is the pilot's */
        o->before.paths /= st->rx, o->before.layer_events /= st->rx, o->before.medium_events /= st->rx;
        o->before.nee_evaluations /= st->rx;
    }
    if (c->shard_n) memset(&o->before, 0, sizeof o->before); /* a shard's file holds only its own work */
    const uint64_t paths_before = st->paths;
    /* With a target error, -p is a cap when given, else there is none. */
    uint64_t add = c->target_error > 0 && !c->paths_given ? UINT64_MAX : c->paths;
    /* A state that owes paths (a merged RRSS pilot, a partial merge) completes its run. */
    const uint64_t held = lsqt_state_contiguous(st);
    const int owes = held < st->span_end && !pilot_base;
    if (owes) {
        add = st->span_end - held;
        if (!c->quiet)
            fprintf(stderr, "note: '%s' is part of a run of %llu paths per slice: this run does the %llu it owes%s\n",
                    lss_path, (unsigned long long)st->span_end, (unsigned long long)add,
                    c->paths_given ? " (-p is not used)" : "");
    }
    const int fresh_rrss = st->dir_method == LSQT_DIRS_RRSS && st->paths == 0 && !owes && !pilot_base;
    /* A fresh RRSS state: the pilot is the first rp of this run's -p (its tallies stay). */
    if (fresh_rrss) {
        o->pilot = (uint64_t)ceil(c->rp * (double)c->paths);
        if (o->pilot < 1) o->pilot = 1;
        if (o->pilot > c->paths) o->pilot = c->paths;
    }
    int finish_pilot = 1;
    /* (every run below goes through the _sides functions: a state with slices from below
     * runs each side with its own assembly on the same paths, below.h) */
    if (c->shard_n) {
        if (c->refine && st->paths == 0 && !owes) {
            snprintf(err, errcap, "--refine: '%s' holds no merged run yet: run the shards without --refine first, "
                                  "then lsqt-cl merge", lss_path ? lss_path : "the LSS");
            rc = 2;
        } else if (pilot_base) {
            snprintf(err, errcap, "'%s' holds (part of) an RRSS pilot: merge all of the pilot's shards first "
                                  "(lsqt-cl merge OUT.lss SHARDS...)", lss_path);
            rc = 2;
        } else {
            /* The run's range, then the K-th of N near-equal parts of it. */
            o->run_lo = held;
            o->run_hi = fresh_rrss ? o->pilot : owes ? st->span_end : c->refine ? held : held + add;
            lsqt_shard_part(o->run_lo, o->run_hi, c->shard_k, c->shard_n, &o->part_lo, &o->part_hi);
            /* A shard run again (after a time limit or a signal) continues its own file when
             * that holds the start of this very part. */
            lsqt_state prev;
            uint64_t resume = o->part_lo;
            int resumed = 0;
            const char *sp = own_lss, *kind = NULL;
            if (!c->restart && lsqt_path_type(sp, &kind) == LSQT_PATH_REGULAR &&
                lsqt_lss_read(sp, &prev, err, errcap) == 0) {
                const uint64_t x = prev.n_ranges == 0                              ? o->part_lo
                                   : prev.n_ranges == 1 && prev.ranges[0] == o->part_lo ? prev.ranges[1]
                                                                                     : UINT64_MAX;
                const int match =
                    fresh_rrss ? prev.stage == LSQT_STAGE_PILOT && prev.hash == st->hash &&
                                     strcmp(prev.canonical, st->canonical) == 0 && prev.seed == st->seed &&
                                     prev.use_double == st->use_double && prev.rx == (uint32_t)c->rx &&
                                     prev.pilot_paths == o->pilot && prev.span_end == (c->paths > o->pilot ? c->paths : o->pilot) &&
                                     prev.n_slices == st->n_slices * c->rx && prev.n_wi == st->n_wi
                               : !lsqt_state_differs(&prev, st) && prev.span_end == o->run_hi;
                if (match && x <= o->part_hi) {
                    resumed = 1, resume = x;
                    if (!c->quiet)
                        fprintf(stderr, "continuing %s: paths [%llu, %llu) of this part are done\n", sp,
                                (unsigned long long)o->part_lo, (unsigned long long)x);
                } else {
                    if (!c->quiet) fprintf(stderr, "note: replacing %s (not a part of this run)\n", sp);
                    lsqt_state_free(&prev);
                }
            }
            if (fresh_rrss && resumed) {
                o->ps = prev;
                rc = lsqt_rrss_pilot_continue_sides(cx, a, &o->ps, resume, o->part_hi - resume, so, &o->rinfo, err, errcap);
                if (rc) lsqt_state_free(&o->ps);
            } else if (fresh_rrss) {
                /* the pilot's part, on every slice's candidates; the merge chooses */
                rc = lsqt_rrss_pilot_sides(cx, a, st, c->rx, o->pilot, c->paths, o->part_lo, o->part_hi - o->part_lo, so, &o->ps, &o->rinfo,
                                     err, errcap);
            }
            if (fresh_rrss) {
                if (!rc) {
                    lsqt_state_free(st);
                    *st = o->ps; /* the shard's state is now the pilot's part */
                    memset(&o->ps, 0, sizeof o->ps);
                    o->pilot_shard = 1;
                    o->stats.paths_added = st->paths;
                    o->stats.seconds = o->rinfo.seconds;
                    if (o->rinfo.interrupted) o->stats.interrupted = 1, o->stats.stop_reason = *so->stop ? LSQT_STOP_INTERRUPT : LSQT_STOP_TIME;
                }
            } else {
                if (resumed) {
                    lsqt_state_free(st);
                    *st = prev;
                } else {
                    lsqt_state_clear_tallies(st);
                }
                rc = lsqt_simulate_range_sides(cx, a, st, resume, o->part_hi - resume, so, &o->stats, err, errcap);
                st->span_end = o->run_hi;
            }
        }
    } else {
        /* RRSS: the pilot (fresh, or the rest of a saved one), the choice, the rest of the
         * run. Checkpoints during the pilot save the pilot state, which continues exactly. */
        if (fresh_rrss) {
            rc = lsqt_rrss_pilot_sides(cx, a, st, c->rx, o->pilot, add == UINT64_MAX ? o->pilot : c->paths, 0, o->pilot, so, &o->ps,
                                 &o->rinfo, err, errcap);
            o->have_ps = !rc;
        } else if (pilot_base) {
            o->ps = *st;
            memset(st, 0, sizeof *st);
            o->have_ps = 1;
            /* the same run (no -p, or its -p): finish the pilot and the run, the bytes of the
             * uninterrupted run; another -p: choose from the pilot so far, then add -p */
            finish_pilot = !c->paths_given || c->paths == o->ps.span_end;
            if (!c->quiet)
                fprintf(stderr, finish_pilot ? "note: '%s' holds %llu of the %llu paths of an RRSS pilot: this run "
                                               "finishes it, then the run (%llu paths per slice)\n"
                                             : "note: '%s' holds %llu of the %llu paths of an RRSS pilot: the "
                                               "directions are chosen from them, then -p %llu more paths\n",
                        lss_path, (unsigned long long)o->ps.paths, (unsigned long long)o->ps.pilot_paths,
                        (unsigned long long)(finish_pilot ? o->ps.span_end : c->paths));
            if (!finish_pilot) {
                /* nothing more to run in the pilot */
            } else if (held == UINT64_MAX || held > o->ps.pilot_paths) {
                snprintf(err, errcap, "'%s' does not hold one range [0, h) of its RRSS pilot", lss_path);
                rc = 1;
            } else {
                rc = lsqt_rrss_pilot_continue_sides(cx, a, &o->ps, held, o->ps.pilot_paths - held, so, &o->rinfo, err, errcap);
            }
        }
        if (o->have_ps && !rc) {
            /* an interrupted pilot: its LSS is the pilot (continuing finishes it); the RAW
             * and summary show a provisional choice from what it has */
            lsqt_state chosen;
            lsqt_rrss_info ci;
            memset(&ci, 0, sizeof ci);
            rc = lsqt_rrss_choose(&o->ps, &chosen, &ci, err, errcap);
            if (!rc) {
                o->rinfo.density_fallback = ci.density_fallback;
                o->rinfo.seconds += ci.select_seconds;
                lsqt_state_free(st);
                *st = chosen;
                if (o->rinfo.interrupted) add = 0;
                else if (pilot_base && !finish_pilot) st->span_end = st->paths; /* the rest is abandoned */
                else if (pilot_base) add = st->span_end - st->paths;
                else if (add != UINT64_MAX) add -= st->paths;
            }
        }
        if (!rc && !o->rinfo.interrupted) rc = lsqt_simulate_sides(cx, a, st, add, so, &o->stats, err, errcap);
        o->stats.seconds += o->rinfo.seconds;
        o->stats.paths_added = st->paths - paths_before;
        if (o->rinfo.interrupted) o->stats.interrupted = 1, o->stats.stop_reason = *so->stop ? LSQT_STOP_INTERRUPT : LSQT_STOP_TIME;
        if (o->have_ps && !o->rinfo.interrupted) {
            lsqt_state_free(&o->ps);
            o->have_ps = 0;
        }
    }
    if (!rc && !c->quiet) lsqt_rrss_notes(stderr, &o->rinfo);
    return rc;
}
