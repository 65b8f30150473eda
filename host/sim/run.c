/* The launch loop (simulate.h): launch sizing, progress, and the stop rules. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/simulate.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

/* Target-error checks fall on multiples of this many paths (whole chunks of every batch). */
#define CHECK_STEP ((uint64_t)LSQT_CHUNK * LSQT_BATCHES)

/* The worst band's: a run with bands stops when every band has reached the target. */
double lsqt_max_rel_err(const lsqt_state *st)
{
    if (st->paths < LSQT_STOP_ERR_PATHS) return NAN;
    double m = 0.0;
    for (int b = 0; b < lsqt_state_bands(st); b++) {
        const lsqt_state view = lsqt_state_band(st, b);
        lsqt_slice_est *est = lsqt_estimates(&view);
        if (!est) return NAN;
        for (int s = 0; s < st->n_slices; s++) {
            if (isnan(est[s].max_rel_err)) m = NAN;
            else if (!isnan(m) && est[s].max_rel_err > m) m = est[s].max_rel_err;
        }
        lsqt_estimates_free(est, st->n_slices);
    }
    return m;
}

/* The next path count at which to check the error: where 1/sqrt(N) predicts the target
 * (5 % beyond), at least 1.1 and at most 4 times the current count, on a CHECK_STEP
 * multiple. A function of the tallies only, so runs stop at the same count anywhere. */
double lsqt_paths_for_error(uint64_t paths, double err, double target)
{
    return (double)paths * (err / target) * (err / target);
}

uint64_t lsqt_next_check(uint64_t paths, double err, double target)
{
    double want = (double)paths * 4.0;
    if (isfinite(err) && err > 0) want = lsqt_paths_for_error(paths, err, target) * 1.05;
    if (want < (double)paths * 1.1) want = (double)paths * 1.1;
    if (want > (double)paths * 4.0) want = (double)paths * 4.0;
    uint64_t n = want > 1e18 ? (uint64_t)1e18 : (uint64_t)want;
    n = (n / CHECK_STEP + 1) * CHECK_STEP;
    if (n < LSQT_STOP_ERR_PATHS) n = LSQT_STOP_ERR_PATHS;
    return n > paths ? n : paths + CHECK_STEP;
}

/* The progress line: the phase, then a bar and ETA, or with a target error the error so
 * far and the time 1/sqrt(paths) predicts to the target (held: the state's paths, which
 * the error is of). */
static void progress_draw(const char *phase, uint64_t done, uint64_t total, uint64_t held, double elapsed,
                          int n_slices, double err, double target)
{
    double rate = elapsed > 0 ? (double)done * n_slices / elapsed : 0.0;
    if (phase) fprintf(stderr, "\r%s: ", phase);
    else fprintf(stderr, "\r");
    if (target > 0) {
        char e[32] = "n/a", eta[48] = "";
        if (isfinite(err)) snprintf(e, sizeof e, "%.3g", err);
        const double need = lsqt_paths_for_error(held, err, target);
        if (need > held && rate > 0)
            snprintf(eta, sizeof eta, ", about %.0f s to it", (need - (double)held) * n_slices / rate);
        fprintf(stderr, "%llu paths per slice  %.3g paths/s  max rel err %s (target %.3g%s)   ",
                (unsigned long long)done, rate, e, target, eta);
        fflush(stderr);
        return;
    }
    double frac = total ? (double)done / (double)total : 1.0;
    double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
    char bar[31];
    int fill = (int)(frac * 30.0);
    for (int i = 0; i < 30; i++) bar[i] = i < fill ? '#' : '.';
    bar[30] = '\0';
    fprintf(stderr, "[%s] %5.1f%%  %.3g paths/s  ETA %.0f s   ", bar, 100.0 * frac, rate, eta);
    fflush(stderr);
}

static uint64_t *base_ranges(const lsqt_state *st, uint64_t begin, int *n, char *err, size_t errcap);

int lsqt_simulate(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t add_paths,
                  const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap)
{
    return lsqt_simulate_range(cx, a, st, lsqt_state_contiguous(st), add_paths, o, stats, err, errcap);
}

int lsqt_simulate_range(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t begin, uint64_t add_paths,
                        const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap)
{
    memset(stats, 0, sizeof *stats);
    lsqt_session s;
    /* Without a target error nothing reads ST's tallies before the run's first read: the
     * session takes them as it uploads them (a 32-band run held both copies meanwhile),
     * unless lsqt_run_range is to refuse the range (ST is kept as it is then). */
    char e2[256];
    int n_base = 0;
    uint64_t *base = o->target_error > 0 ? NULL : base_ranges(st, begin, &n_base, e2, sizeof e2);
    const int take = base != NULL;
    free(base);
    if (take ? lsqt_session_open_taking(&s, cx, a, st, o->extra_options, o->local_size, o->verbose, err, errcap)
             : lsqt_session_open(&s, cx, a, st, o->extra_options, o->local_size, o->verbose, err, errcap))
        return 1;
    s.last_read_releases = 1;
    int rc = lsqt_run_range(&s, st, begin, add_paths, o, stats, err, errcap);
    lsqt_session_close(&s);
    return rc;
}

/* ST's tallies hold its base ranges and [first, pos) now. */
static int hold(lsqt_state *st, const uint64_t *base, int n_base, uint64_t first, uint64_t pos, char *err,
                size_t errcap)
{
    if (lsqt_state_set_ranges(st, base, n_base) || lsqt_state_add_range(st, first, pos)) {
        snprintf(err, errcap, "out of memory (or paths [%llu, %llu) already held)", (unsigned long long)first,
                 (unsigned long long)pos);
        return 1;
    }
    if (st->span_end < pos) st->span_end = pos;
    return 0;
}

/* The ranges ST holds before the run (a copy), when [begin, ...) is free of them; NULL
 * with err filled when it is not, or begin is UINT64_MAX (gaps), or out of memory. */
static uint64_t *base_ranges(const lsqt_state *st, uint64_t begin, int *n, char *err, size_t errcap)
{
    if (begin == UINT64_MAX) {
        snprintf(err, errcap, "the state holds paths with gaps between them (a partial merge): it cannot be continued");
        return NULL;
    }
    uint64_t *base = malloc(((size_t)st->n_ranges + 1) * 2 * sizeof *base);
    if (!base) {
        snprintf(err, errcap, "out of memory");
        return NULL;
    }
    const int n_base = *n = st->n_ranges;
    if (n_base) memcpy(base, st->ranges, (size_t)n_base * 2 * sizeof *base);
    for (int i = 0; i < n_base; i++)
        if (base[2 * i + 1] > begin) {
            snprintf(err, errcap, "paths from %llu on are already held", (unsigned long long)begin);
            free(base);
            return NULL;
        }
    return base;
}

/* The next launch's size in chunks: each should take about goal seconds (dt: the last
 * one's). */
static uint64_t next_launch_chunks(uint64_t chunks_per_launch, double dt, double goal)
{
    double grow = dt > 0 ? goal / dt : 4.0;
    grow = grow > 4.0 ? 4.0 : grow < 0.5 ? 0.5 : grow;
    chunks_per_launch = (uint64_t)((double)chunks_per_launch * grow);
    return chunks_per_launch < 1 ? 1 : chunks_per_launch;
}

/* A signal, or the time limit with paths still to do: 1 (stats say which), else 0. */
static int stop_asked(const lsqt_sim_opts *o, lsqt_sim_stats *stats, double t0, uint64_t pos, uint64_t target)
{
    if (o->stop && *o->stop) {
        stats->stop_reason = LSQT_STOP_INTERRUPT;
        stats->interrupted = 1;
        return 1;
    }
    if (o->time_limit > 0 && lsqt_now() - t0 >= o->time_limit && pos < target) {
        stats->stop_reason = LSQT_STOP_TIME;
        stats->interrupted = 1;
        return 1;
    }
    return 0;
}

int lsqt_run_range(lsqt_session *sp, lsqt_state *st, uint64_t begin, uint64_t add_paths, const lsqt_sim_opts *o,
                   lsqt_sim_stats *stats, char *err, size_t errcap)
{
    memset(stats, 0, sizeof *stats);
    /* the ranges held before, and whether [begin, ...) is free */
    int n_base = 0;
    uint64_t *base = base_ranges(st, begin, &n_base, err, errcap);
    if (!base) return 1;

    /* Launches cover whole chunks; their size adapts so each takes about 0.3 s, which
     * keeps the progress bar and Ctrl-C responsive without starving the device; 5 s where
     * the session borrows packed histograms, whose batches each launch unpacks and packs
     * again (a 200-band run at 1e5 paths took 1.5 times the CPU at 0.3 s). */
    const double launch_goal = sp->hist_home ? 5.0 : 0.3;
    const uint64_t first = begin;
    const uint64_t target = add_paths > UINT64_MAX - first ? UINT64_MAX : first + add_paths;
    const double goal = o->target_error;
    uint64_t pos = first, chunks_per_launch = 8, check = UINT64_MAX;
    double cur_err = NAN;
    int rc = 1;
    if (goal > 0) {
        /* a continued state may already be good enough */
        cur_err = lsqt_max_rel_err(st);
        if (!isnan(cur_err) && cur_err <= goal) {
            stats->stop_reason = LSQT_STOP_TARGET;
            rc = 0;
            goto done;
        }
        check = first < LSQT_STOP_ERR_PATHS ? LSQT_STOP_ERR_PATHS : lsqt_next_check(first, cur_err, goal);
    }
    const double t0 = lsqt_now();
    double last_ck = t0;
    if (o->verbose)
        fprintf(stderr, "simulating %llu paths per slice x %d slices (work-group size %zu)%s\n",
                (unsigned long long)(target - first), st->n_slices, sp->local_size,
                goal > 0 ? ", or fewer if the target error is reached" : "");
    stats->stop_reason = LSQT_STOP_PATHS;
    /* The device's buffers hold ST's tallies until the next read, which copies every word
     * back: in between, the host's copy is given back (a 32-band run's held both), dropped
     * again after each read the loop goes on from. Nothing reads ST's tallies before the
     * read (an error leaves them undefined: lsqt_run_range). */
    int on_host = sp->nee != NULL;
    while (pos < target) {
        if (on_host) {
            lsqt_state_drop_tallies(st);
            on_host = 0;
        }
        uint64_t end = (pos / LSQT_CHUNK + chunks_per_launch) * LSQT_CHUNK;
        if (end > target) end = target;
        if (end > check) end = check;
        double t = lsqt_now();
        if (lsqt_session_launch(sp, pos, end, err, errcap)) goto done;
        double dt = lsqt_now() - t;
        pos = end;
        stats->launches++;
        chunks_per_launch = next_launch_chunks(chunks_per_launch, dt, launch_goal);
        if (pos == check) {
            if (lsqt_session_read(sp, st, 0, err, errcap) || hold(st, base, n_base, first, pos, err, errcap)) goto done;
            on_host = 1;
            cur_err = lsqt_max_rel_err(st);
            if (!isnan(cur_err) && cur_err <= goal) {
                stats->stop_reason = LSQT_STOP_TARGET;
                break;
            }
            check = lsqt_next_check(pos, cur_err, goal);
        }
        if (o->checkpoint && o->checkpoint_every > 0 && lsqt_now() - last_ck >= o->checkpoint_every && pos < target) {
            /* the state so far, exactly as a run of pos paths leaves it */
            if (lsqt_session_read(sp, st, 0, err, errcap) || hold(st, base, n_base, first, pos, err, errcap)) goto done;
            on_host = 1;
            o->checkpoint(st, o->checkpoint_ctx);
            last_ck = lsqt_now();
        }
        if (o->progress)
            progress_draw(o->phase, pos - first, target - first, pos, lsqt_now() - t0, st->n_slices, cur_err, goal);
        if (stop_asked(o, stats, t0, pos, target)) break;
    }
    if (o->progress) fprintf(stderr, "\n");
    if (o->verbose) fprintf(stderr, "%d launches in %.3g s\n", stats->launches, lsqt_now() - t0);
    if (lsqt_session_read(sp, st, sp->last_read_releases, err, errcap) || hold(st, base, n_base, first, pos, err, errcap))
        goto done;
    stats->paths_added = pos - first;
    stats->seconds = lsqt_now() - t0;
    if (lsqt_tally_flags_error(st->flags, err, errcap)) goto done;
    rc = 0;
done:
    free(base);
    return rc;
}
