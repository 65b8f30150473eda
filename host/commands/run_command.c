/* lsqt-cl's run of one input: LSQT text -> assembly -> state -> the device's stages ->
 * LSS, RAW, summary. Each step is a function, in the order of a run. */
#include "run_cmd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lsqt/bands.h"
#include "lsqt/device.h"
#include "lsqt/directions.h"
#include "lsqt/lss.h"
#include "lsqt/simulate.h"
#include "lsqt/stages.h"

/* --checkpoint: the LSS, written atomically every so often during the run. */
typedef struct checkpoint_ctx {
    const char *lss;
    int quiet;
} checkpoint_ctx;

static int write_checkpoint(const lsqt_state *st, void *arg)
{
    const checkpoint_ctx *k = arg;
    char err[LSQT_PATH_CAP + 256];
    if (lsqt_lss_write(k->lss, st, err, sizeof err)) {
        fprintf(stderr, "lsqt-cl: warning: checkpoint not written: %s\n", err);
        return 1;
    }
    return 0;
}

/* What a file given as input is when it is one of the files the programs write, not
 * LSQT text, and which command reads it, into msg; 0 when it is none of them. */
static int other_file(const char *text, size_t len, const char *name, char *msg, size_t cap)
{
    if (len >= 8 && memcmp(text, "LSQTLSS", 8) == 0)
        snprintf(msg, cap, "%s is an LSS file (the state of a run), not an LSQT input: 'lsqt-cl info %s' shows "
                 "what it holds; to go on with its run, give the LSQT file it was made from (with --lss %s if "
                 "the LSS is not beside it)", name, name, name);
    else if (len >= 8 && memcmp(text, "RAWB", 4) == 0 && (text[4] == 'S' || text[4] == 'H') &&
             memcmp(text + 5, "10A", 3) == 0)
        snprintf(msg, cap, "%s is a RAW file (a run's BSDF values, for DIRSIG5's raw2sqt), not an LSQT input: "
                 "give the LSQT file of the run", name);
    else if (len >= 4 && (memcmp(text, "CDF\x01", 4) == 0 || memcmp(text, "CDF\x02", 4) == 0 ||
                          memcmp(text, "CDF\x05", 4) == 0 || (len >= 8 && memcmp(text, "\x89HDF\r\n\x1a\n", 8) == 0)))
        snprintf(msg, cap, "%s is a NetCDF file (what 'lsqt-cl export' writes), not an LSQT input: give the "
                 "LSQT file of the run", name);
    else
        return 0;
    return 1;
}

/* Input -> assembly: parsed, its notes printed, a model this version cannot simulate
 * refused. Returns 0, or an exit status (printed; nothing to free). */
static int read_assembly(const lsqt_cli *c, int from_stdin, lsqt_assembly *a)
{
    char err[LSQT_PATH_CAP + 1024];
    size_t len = 0;
    char *text = lsqt_read_text(c->input, LSQT_INPUT_MAX, &len, err, sizeof err);
    if (!text) return fail(2, "%s%s", err, "");
    if (other_file(text, len, from_stdin ? "<stdin>" : c->input, err, sizeof err)) {
        free(text);
        return fail(2, "%s%s", err, "");
    }
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    double *wl = NULL;
    int n_wl = 0;
    if (c->wavelengths && lsqt_parse_wavelengths(c->wavelengths, &wl, &n_wl, err, sizeof err)) {
        free(text);
        return fail(2, "--wavelengths: %s%s", err, "");
    }
    /* a relative @FILE is read from the LSQT file's folder */
    char dir[LSQT_PATH_CAP];
    const char *slash = from_stdin ? NULL : strrchr(c->input, '/');
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - c->input) + (slash == c->input) : 1,
             slash ? c->input : ".");
    int prc = lsqt_parse(text, len, from_stdin ? "<stdin>" : c->input, wl, n_wl, dir, a, &diag);
    free(text);
    free(wl);
    if (!c->quiet)
        for (int i = 0; i < diag.n_notes; i++) fprintf(stderr, "%s\n", diag.notes[i]);
    if (prc) {
        fprintf(stderr, "%s\n", diag.error);
        return 2;
    }
    g_armed = 1;
    int line = 0;
    const char *model = lsqt_unsupported_model(a, &line);
    if (model) {
        fprintf(stderr, "%s:%d: error: %s is parsed but not simulated by this version of lsqt-cl yet\n",
                from_stdin ? "<stdin>" : c->input, line, model);
        lsqt_assembly_free(a);
        return 1;
    }
    return 0;
}

/* The direction flags against the stack. Returns 0, or 2 (printed). */
static int check_directions(const lsqt_cli *c, const lsqt_assembly *a)
{
    char err[LSQT_PATH_CAP + 1024];
    /* Over the sphere the equal-area lattice puts its middle direction of an odd count on
     * the horizon, where a BSDF value (tally / |cos|) is 0 / 0. */
    if (!c->wi_file && c->wi_spread && lsqt_assembly_transmits(a) && c->wi_count % 2) {
        snprintf(err, sizeof err, "-wi %d: this stack transmits, so the directions cover the sphere", c->wi_count);
        return fail(2, "%s%s", err, " and their count must be even");
    }
    if (c->grid_no) {
        const int tr = lsqt_assembly_transmits(a), n = lsqt_grid_wi_count(c->grid_ni, c->grid_nphi, tr);
        if (n > LSQT_WI_FILE_MAX) {
            snprintf(err, sizeof err, "--grid %d,%d,%d: %d incident directions per slice (NI x (NPHI/2 + 1)%s), "
                     "more than the %d a slice can have", c->grid_no, c->grid_ni, c->grid_nphi, n,
                     tr ? " x 2: this stack transmits" : "", LSQT_WI_FILE_MAX);
            return fail(2, "%s%s", err, "");
        }
    }
    return 0;
}

/* --wi-file is read (and checked) even when an LSS is continued: bad input is an error
 * whether or not it would be used. Below the horizon is allowed only where light is
 * transmitted; elsewhere the value would be 0 by construction, so it is a mistake.
 * Returns 0, or an exit status (printed). */
static int read_wi_file(const lsqt_cli *c, const lsqt_assembly *a, float **wi_dirs, int *n_wi_dirs, int *n_mirrored)
{
    char err[LSQT_PATH_CAP + 1024];
    if (!c->wi_file) return 0;
    int wrc = lsqt_wi_file_read(c->wi_file, lsqt_assembly_transmits(a), wi_dirs, n_wi_dirs, n_mirrored, err,
                                sizeof err);
    if (wrc == 2) {
        fprintf(stderr, "%s\n", err);
        return 2;
    }
    return wrc ? fail(wrc < 0 ? 1 : 2, "--wi-file: %s%s", err, "") : 0;
}

/* The run plan of the stages (stages.h): what the flags ask of the paths. --total-paths N
 * becomes the -p that brings ST to N: N fresh, N less what it holds continued (0 when it
 * holds N or more, said in a note); an RRSS pilot that N is the run of is finished as the
 * same command without -p would. */
static lsqt_run_plan run_plan(const lsqt_cli *c, const lsqt_state *st, const char *lss)
{
    lsqt_run_plan p;
    memset(&p, 0, sizeof p);
    p.paths = c->paths, p.paths_given = c->paths_given, p.target_error = c->target_error;
    if (c->total_paths) {
        /* a pilot of this very run: finished as without -p (paths_given 0, paths its run) */
        p.paths_given = !(st->stage == LSQT_STAGE_PILOT && c->total_paths == st->span_end);
        p.paths = !p.paths_given ? c->total_paths : c->total_paths > st->paths ? c->total_paths - st->paths : 0;
        if (!p.paths && !c->quiet)
            fprintf(stderr, "note: '%s' holds %llu paths per slice, --total-paths %llu: none to add\n", lss,
                    (unsigned long long)st->paths, (unsigned long long)c->total_paths);
    }
    p.rp = c->rp, p.rx = c->rx;
    p.shard_k = c->shard_k, p.shard_n = c->shard_n, p.refine = c->refine, p.restart = c->restart;
    p.quiet = c->quiet;
    return p;
}

/* A signal stopped the run: exit 1, saying what was written (a calibration run of --plan
 * says nothing: plan.c removes what it wrote and says so). */
static int interrupted(const lsqt_cli *c, const lsqt_sim_stats *stats, int rc)
{
    if (stats->interrupted && g_stop && c->plan == LSQT_PLAN_CALIBRATION) {
        rc = 1; /* --plan's calibration: plan.c says what became of it */
    } else if (stats->interrupted && g_stop) {
        fprintf(stderr, "lsqt-cl: interrupted (%s): %s the paths done so far\n", signal_name(g_stop),
                rc ? "tried to write" : "wrote");
        rc = 1;
    }
    return rc;
}

/* A pilot shard holds candidate sets, not a BSDF yet: its LSS is all there is. */
static int report_pilot_shard(const lsqt_cli *c, const outputs *out, const lsqt_state *st, const lsqt_stages *sg,
                              FILE *info)
{
    char err[LSQT_PATH_CAP + 1024];
    int rc = 0;
    const lsqt_sim_stats stats = sg->stats;
    const char *ls = out->f.path[LSQT_OUT_LSS];
    if (lsqt_lss_write(ls, st, err, sizeof err)) rc = fail(1, "%s%s", err, "");
    else if (!c->quiet)
        fprintf(info, "shard %d/%d of the RRSS pilot: paths [%llu, %llu) of [0, %llu) in %.3g s; wrote %s\n"
                      "(merge all %d pilot shards, then run the shards with --refine)\n",
                c->shard_k, c->shard_n, (unsigned long long)sg->part_lo, (unsigned long long)sg->part_hi,
                (unsigned long long)sg->pilot, stats.seconds, ls, c->shard_n);
    if (!c->quiet && c->output) fprintf(stderr, "note: a pilot shard writes no RAW (-o is not used)\n");
    return interrupted(c, &stats, rc);
}

/* What the summary and the JSON say of this run: the device, its speed, its work (less
 * what the state held before), and what stopped it. */
static lsqt_run_info run_info(const lsqt_cli *c, const lsqt_state *st, const lsqt_stages *sg, const char *devname)
{
    const lsqt_sim_stats stats = sg->stats;
    const lsqt_work before = sg->before;
    lsqt_run_info ri = {devname, stats.seconds,
                        stats.seconds > 0 ? (double)stats.paths_added * st->n_slices / stats.seconds : 0.0,
                        (unsigned long long)stats.paths_added, NULL, lsqt_work_totals(st), 0.0, NAN, 0ULL, c->verbose};
    ri.work.paths -= before.paths, ri.work.layer_events -= before.layer_events;
    ri.work.medium_events -= before.medium_events, ri.work.nee_evaluations -= before.nee_evaluations;
    static const char *const why[] = {"the path count (-p)", "the target error (--target-error)",
                                      "the time limit (--time-limit)", "an interrupt"};
    if (c->target_error > 0 || c->time_limit > 0)
        ri.stopped_by = stats.stop_reason == 0 && c->total_paths ? "the path count (--total-paths)" : why[stats.stop_reason];
    if (c->target_error > 0) {
        ri.target_error = c->target_error;
        ri.max_rel_err = lsqt_max_rel_err(st);
        const double need = lsqt_paths_for_error(st->paths, ri.max_rel_err, c->target_error);
        if (need > st->paths && need < 9e15) ri.paths_needed = (unsigned long long)ceil(need);
        else if (need <= st->paths) ri.paths_needed = st->paths; /* NaN (no error bars yet): not known */
    }
    return ri;
}

/* The outputs of a run, the summary, and the notes on what it leaves to do. */
static int report_run(const lsqt_cli *c, const outputs *out, const lsqt_state *st, const lsqt_stages *sg,
                      const lsqt_context *cx, FILE *info)
{
    int rc;
    lsqt_slice_est *est = lsqt_estimates(st);
    char devname[600];
    snprintf(devname, sizeof devname, "%s [%s]", cx->dev.name, cx->dev.platform_name);
    const lsqt_run_info ri = run_info(c, st, sg, devname);
    if (!est) rc = fail(1, "out of memory%s%s", "", "");
    else rc = run_write_outputs(out, c, st, sg->have_ps ? &sg->ps : st, est, &ri, info);
    if (est && !c->quiet) lsqt_report_summary(info, st, est, &ri);
    if (sg->have_ps && !c->quiet && out->f.path[LSQT_OUT_LSS] && fflush(info) == 0)
        fprintf(stderr,
                "note: the run stopped in its RRSS pilot: '%s' holds %llu of the pilot's %llu paths per slice, "
                "and the RAW's directions are a provisional choice from them. Continuing without -p finishes "
                "the pilot and then this run (%llu paths per slice in all); continuing with -p N chooses the "
                "directions from the pilot as it is and adds N paths per slice.\n",
                out->f.path[LSQT_OUT_LSS], (unsigned long long)sg->ps.paths, (unsigned long long)sg->ps.pilot_paths,
                (unsigned long long)sg->ps.span_end);
    if (!c->quiet && c->shard_n)
        fprintf(info, "shard %d/%d: paths [%llu, %llu) of this run's [%llu, %llu)%s\n", c->shard_k, c->shard_n,
                (unsigned long long)sg->part_lo, (unsigned long long)sg->part_hi, (unsigned long long)sg->run_lo,
                (unsigned long long)sg->run_hi, sg->part_lo == sg->part_hi ? " (nothing to do: an empty part)" : "");
    lsqt_estimates_free(est, st->n_slices);
    return interrupted(c, &sg->stats, rc);
}

/* Every output location is checked before any work, so a long run never ends in an
 * unwritable path; then the device. Returns 0, or an exit status (printed). */
static int open_device(const lsqt_cli *c, const lsqt_state *st, const outputs *out, lsqt_context *cx)
{
    char err[LSQT_PATH_CAP + 1024];
    int rc = lsqt_outputs_check(&out->f, "lsqt-cl", "nothing simulated");
    memset(cx, 0, sizeof *cx);
    if (!rc) {
        rc = lsqt_context_create(cx, c->device, err, sizeof err);
        if (!rc) rc = lsqt_device_check(&cx->dev, st->use_double, err, sizeof err);
        if (rc) fail(rc, "%s%s", err, "");
    }
    if (rc) lsqt_context_release(cx);
    else if (c->verbose) fprintf(stderr, "device: %s [%s]\n", cx->dev.name, cx->dev.platform_name);
    return rc;
}

lsqt_memory_shape g_run_shape;

/* The run's peak memory against --max-memory (default: 80 % of what this machine, or
 * its cgroup, has available), before the device or the tallies are touched. Returns 0,
 * or 2 (printed) when it does not fit. */
static int check_memory(const lsqt_cli *c, const lsqt_assembly *a, const lsqt_state *st)
{
    const int pilot = st->stage == LSQT_STAGE_PILOT, rx = pilot ? (int)st->rx : c->rx;
    lsqt_memory_shape m = {lsqt_state_bands(st), pilot && rx ? st->n_slices / rx : st->n_slices, st->n_wi, 0, 1,
                           st->use_double, a->n_layers, 0};
    /* the paths per slice it holds at the end (0: a target error without -p, unbounded) */
    if (c->total_paths) m.paths = c->total_paths;
    else if (!(c->target_error > 0 && !c->paths_given)) m.paths = st->paths + c->paths;
    if (m.paths && m.paths < st->span_end) m.paths = st->span_end;
    if (pilot || (st->dir_method == LSQT_DIRS_RRSS && st->paths == 0)) m.pilot_rx = rx;
    for (int s = 1; s < st->n_slices; s++)
        if ((st->slice_flags[s] ^ st->slice_flags[0]) & LSQT_SLICE_BELOW) m.sides = 2;
    g_run_shape = m;
    const lsqt_memory est = lsqt_memory_estimate(&m), *e = &est;
    const uint64_t avail = c->max_memory_given ? 0 : lsqt_memory_available();
    const uint64_t limit = c->max_memory_given ? c->max_memory : avail / 10 * 8;
    char b[5][32];
    if (c->verbose)
        fprintf(stderr, "memory: about %s at the peak (state %s, device %s, RRSS pilot %s); limit %s\n",
                lsqt_memory_format(e->peak, b[0], 32), lsqt_memory_format(e->state, b[1], 32),
                lsqt_memory_format(e->device, b[2], 32), lsqt_memory_format(e->pilot, b[3], 32),
                limit ? lsqt_memory_format(limit, b[4], 32) : "none");
    if (!limit || e->peak <= limit) return 0;
    char why[64];
    if (c->max_memory_given) snprintf(why, sizeof why, "--max-memory");
    else snprintf(why, sizeof why, "80 %% of the %s available", lsqt_memory_format(avail, b[4], 32));
    fprintf(stderr,
            "lsqt-cl: error: this run would need about %s of memory at its peak, more than the %s allowed (%s): "
            "%d band%s x %d slices x %d directions hold %s of tallies on the host and %s on the device%s%s%s. "
            "Nothing was simulated. Fewer bands per run (split --wavelengths into several runs, each with its "
            "own --lss), fewer slices or directions (-wo, -wi, --grid) or no --from-below need less; "
            "--max-memory SIZE (0: no limit) sets the limit\n",
            lsqt_memory_format(e->peak, b[0], 32), lsqt_memory_format(limit, b[1], 32), why, m.n_bands,
            m.n_bands == 1 ? "" : "s", st->n_slices, st->n_wi, lsqt_memory_format(e->state, b[2], 32),
            lsqt_memory_format(e->device, b[3], 32), e->pilot ? ", and the RRSS pilot " : "",
            e->pilot ? lsqt_memory_format(e->pilot, b[4], 32) : "", e->pilot ? " (-rx sets its size)" : "");
    return 2;
}

/* The device's work on the state (stages.h), then the outputs. Returns the exit status. */
static int simulate(const lsqt_cli *c, const lsqt_assembly *a, lsqt_state *st, const outputs *out)
{
    lsqt_context cx;
    int rc = open_device(c, st, out, &cx);
    if (rc) return rc;
    /* With an output on stdout, everything else we print goes to stderr. */
    int to_stdout = 0;
    for (int i = 0; i < LSQT_OUT_KINDS; i++) to_stdout |= out->f.path[i] && strcmp(out->f.path[i], "-") == 0;
    FILE *info = to_stdout ? stderr : stdout;
    checkpoint_ctx ck = {out->f.path[LSQT_OUT_LSS], c->quiet}; /* a shard checkpoints its own file */
    const int can_checkpoint = ck.lss && strcmp(ck.lss, "-") != 0 && c->checkpoint > 0;
    lsqt_sim_opts so = {isatty(STDERR_FILENO) && !c->quiet, c->time_limit, 0, &g_stop, NULL, c->verbose,
                        c->target_error, can_checkpoint ? c->checkpoint : 0.0,
                        can_checkpoint ? write_checkpoint : NULL, &ck, NULL};
    const lsqt_run_plan plan = run_plan(c, st, out->base);
    lsqt_stages sg;
    char err[LSQT_PATH_CAP + 1024];
    rc = lsqt_run_stages(&cx, a, st, &plan, out->base, out->f.path[LSQT_OUT_LSS], &so, &sg, err, sizeof err);
    if (rc) fail(rc, "%s%s", err, "");
    else if (sg.pilot_shard) rc = report_pilot_shard(c, out, st, &sg, info);
    else rc = report_run(c, out, st, &sg, &cx, info);
    if (sg.have_ps) lsqt_state_free(&sg.ps);
    lsqt_context_release(&cx);
    return rc;
}

int run_command(const lsqt_cli *c)
{
    char err[LSQT_PATH_CAP + 1024];
    const int from_stdin = strcmp(c->input, "-") == 0;
    lsqt_assembly a;
    int rc = read_assembly(c, from_stdin, &a);
    if (rc) return rc;
    float *wi_dirs = NULL;
    int n_wi_dirs = 0, n_mirrored = 0;
    rc = check_directions(c, &a);
    if (!rc) rc = read_wi_file(c, &a, &wi_dirs, &n_wi_dirs, &n_mirrored);
    outputs out;
    memset(&out, 0, sizeof out);
    if (!rc && (rc = run_plan_outputs(c, from_stdin, &a, NULL, 0, &out, err, sizeof err)))
        fail(rc, "%s%s", err, "");
    if (!rc) rc = run_lock_states(&out, c->quiet) ? 1 : 0;
    lsqt_state st;
    int continued = 0;
    /* out.base: the state continued (a shard writes its own, out.f.path[LSQT_OUT_LSS]) */
    if (!rc) rc = run_open_state(&st, c, &a, out.base, wi_dirs, n_wi_dirs, n_mirrored, &continued);
    free(wi_dirs);
    if (!rc && (rc = run_plan_outputs(c, from_stdin, &a, &st, continued, &out, err, sizeof err))) {
        lsqt_state_free(&st);
        fail(rc, "%s%s", err, "");
    }
    if (!rc && (rc = check_memory(c, &a, &st))) lsqt_state_free(&st);
    else if (!rc && lsqt_state_pack_hist(&st, 0)) { /* many bands: histograms packed (state.h) */
        rc = fail(1, "out of memory packing the histograms%s%s", "", "");
        lsqt_state_free(&st);
    } else if (!rc) {
        rc = simulate(c, &a, &st, &out);
        lsqt_state_free(&st);
    }
    run_outputs_free(&out);
    lsqt_assembly_free(&a);
    return rc;
}
