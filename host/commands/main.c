/* lsqt-cl: LSQT text -> assembly -> device simulation -> LSS, RAW, summary. */
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lsqt/assembly.h"
#include "lsqt/below.h"
#include "lsqt/cli.h"
#include "lsqt/device.h"
#include "lsqt/directions.h"
#include "lsqt/export.h"
#include "lsqt/info.h"
#include "lsqt/lss.h"
#include "lsqt/merge.h"
#include "lsqt/raw.h"
#include "lsqt/report.h"
#include "lsqt/rrss.h"
#include "lsqt/simulate.h"
#include "lsqt/stages.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

static volatile sig_atomic_t g_stop = 0;  /* the signal that asked to stop, 0 if none */
static volatile sig_atomic_t g_armed = 0; /* the input is read: Ctrl-C now means "finish" */
static sigset_t g_sigint;

/* Ctrl-C (SIGINT), and the signals a batch system sends at or before a job's time limit
 * (SIGTERM, SIGHUP, SIGUSR1 with sbatch --signal), are taken by this thread alone
 * (sigwait), never by a signal handler: they are blocked in every other thread, PoCL's
 * included, so LLVM's own handler (installed while PoCL compiles a kernel) cannot run
 * and delete the compiler's temporary files, which failed the build. First signal:
 * finish the launch, write LSS and RAW, exit non-zero. Second (or any while the input is
 * still being read): stop at once, exit 128 + the signal. */
static pthread_mutex_t g_watch_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t g_watch_cond = PTHREAD_COND_INITIALIZER;
static int g_watch_started = 0;

static void *sigint_watch(void *arg)
{
    (void)arg;
    pthread_mutex_lock(&g_watch_lock);
    g_watch_started = 1;
    pthread_cond_signal(&g_watch_cond);
    pthread_mutex_unlock(&g_watch_lock);
    for (int count = 0;;) {
        int sig = 0;
        if (sigwait(&g_sigint, &sig) != 0 || !sigismember(&g_sigint, sig)) continue;
        if (++count == 1 && g_armed) {
            g_stop = sig;
            continue;
        }
        static const char msg[] = "\nlsqt-cl: interrupted: stopping now, nothing more written\n";
        if (write(STDERR_FILENO, msg, sizeof msg - 1) < 0) { /* nowhere left to say it */
        }
        _exit(128 + sig);
    }
    return NULL;
}

static void on_sigint(int sig) /* fallback when no thread can be started */
{
    g_stop = sig;
    signal(sig, SIG_DFL);
}

static const int g_stop_signals[] = {SIGINT, SIGTERM, SIGHUP, SIGUSR1};

/* Before any other thread exists, so that every thread inherits the blocked SIGINT. */
static void sigint_setup(void)
{
    sigemptyset(&g_sigint);
    for (size_t i = 0; i < sizeof g_stop_signals / sizeof *g_stop_signals; i++) sigaddset(&g_sigint, g_stop_signals[i]);
    pthread_t t;
    if (pthread_sigmask(SIG_BLOCK, &g_sigint, NULL) == 0 && pthread_create(&t, NULL, sigint_watch, NULL) == 0) {
        pthread_detach(t);
        /* Wait until the thread runs: a process that exits while a thread is still being
         * set up (a bad flag exits at once) leaves the C library's start-up data behind,
         * which LeakSanitizer reports. */
        pthread_mutex_lock(&g_watch_lock);
        while (!g_watch_started) pthread_cond_wait(&g_watch_cond, &g_watch_lock);
        pthread_mutex_unlock(&g_watch_lock);
        return;
    }
    pthread_sigmask(SIG_UNBLOCK, &g_sigint, NULL);
    for (size_t i = 0; i < sizeof g_stop_signals / sizeof *g_stop_signals; i++) signal(g_stop_signals[i], on_sigint);
}

static const char *signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : sig == SIGUSR1 ? "SIGUSR1" : "a signal";
}

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

static int fail(int code, const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "lsqt-cl: error: ");
    fprintf(stderr, fmt, a, b);
    fprintf(stderr, "\n");
    return code;
}

/* A fresh state: slices, incident directions and zero tallies. The directions are the
 * --wi-file ones (wi_file, n_wi_file of them) when given, else the -wi spread; every
 * slice gets the same (its wo is at azimuth 0, so phi is measured from it in each). */
static int new_state(lsqt_state *st, const lsqt_cli *c, const lsqt_assembly *a, const char *canonical,
                     const float *wi_file, int n_wi_file)
{
    const int grid = c->grid_no > 0, lower = lsqt_assembly_transmits(a);
    int n_slices = grid ? c->grid_no : c->n_wo_angles ? c->n_wo_angles : c->wo_count;
    int n_wi = c->grid_rgl ? lsqt_rgl_wi_count(c->grid_ni)
             : grid        ? lsqt_grid_wi_count(c->grid_ni, c->grid_nphi, lower)
             : wi_file     ? n_wi_file
                           : c->wi_count;
    if (lsqt_state_init(st, canonical, lsqt_assembly_hash(a), c->seed, n_slices, n_wi, lower)) return -1;
    st->use_double = c->use_double;
    if (c->grid_rgl) lsqt_rgl_theta_o(n_slices, st->theta_o);
    else if (grid) lsqt_grid_theta_o(n_slices, st->theta_o);
    else if (c->n_wo_angles) memcpy(st->theta_o, c->wo_angles, (size_t)n_slices * sizeof(double));
    else lsqt_wo_angles(n_slices, st->theta_o);
    /* RRSS directions are chosen once the device is ready (host/sim/stages.c); the spread stands
     * in until then. */
    st->dir_method = c->grid_rgl ? LSQT_DIRS_RGL : grid ? LSQT_DIRS_GRID : wi_file ? LSQT_DIRS_FILE : c->wi_spread ? LSQT_DIRS_SPREAD : LSQT_DIRS_RRSS;
    if (grid) st->grid_ni = (uint32_t)c->grid_ni, st->grid_nphi = (uint32_t)c->grid_nphi;
    for (int s = 0; s < n_slices; s++) {
        float *dst = st->wi + (size_t)s * (size_t)st->n_wi * 4;
        if (c->grid_rgl) lsqt_rgl_wi(st->theta_o[s], c->grid_ni, dst);
        else if (grid) lsqt_grid_wi(c->grid_ni, c->grid_nphi, lower, dst);
        else if (wi_file) memcpy(dst, wi_file, (size_t)st->n_wi * 4 * sizeof *dst);
        else lsqt_wi_spread(st->n_wi, st->transmits, dst);
    }
    /* --from-below: the same slices again, of light entering from below (below.h) */
    if (c->from_below && st->transmits && lsqt_state_add_below(st)) {
        lsqt_state_free(st);
        return -1;
    }
    return 0;
}

/* The files a run writes. RAW is one file, or with -H two (R and T; no T when nothing is
 * transmitted); a two-sided state adds the same for the side from below (below.h). */
enum { OUT_RAW, OUT_RAW_T, OUT_RAW_B, OUT_RAW_BT, OUT_LSS, OUT_JSON, OUT_COUNT };
typedef struct outputs {
    const char *path[OUT_COUNT]; /* NULL: not written */
    const char *base;            /* the LSS continued (a shard writes its own, path[OUT_LSS]) */
    char raw[LSQT_PATH_CAP + 16], raw_t[LSQT_PATH_CAP + 16], lss[LSQT_PATH_CAP + 16], shard[LSQT_PATH_CAP + 40];
    char raw_b[LSQT_PATH_CAP + 32], raw_bt[LSQT_PATH_CAP + 32];
} outputs;

/* Decides every output name and checks them against each other and the input (below: the
 * state has slices from below). Returns 0 or 2 (err filled). */
static int plan_outputs(const lsqt_cli *c, int from_stdin, int transmits, int below, outputs *o, char *err,
                        size_t errcap)
{
    memset(o, 0, sizeof *o);
    char raw[LSQT_PATH_CAP + 16];
    if (c->output) snprintf(raw, sizeof raw, "%s", c->output);
    else if (from_stdin) snprintf(raw, sizeof raw, "Layered.raw");
    else snprintf(raw, sizeof raw, "%s.raw", c->input);
    if (below) {
        const char *what = NULL;
        int t = strcmp(raw, "-") == 0 ? LSQT_PATH_SPECIAL : lsqt_path_type(raw, &what);
        if (t == LSQT_PATH_SPECIAL || t == LSQT_PATH_DIRECTORY) {
            snprintf(err, errcap, "the slices from below go to a second RAW named from the RAW name, and '%s' is "
                     "%s%s: give -o a file name", raw, what ? "a " : "stdout", what ? what : "");
            return 2;
        }
        char rb[LSQT_PATH_CAP + 32];
        lsqt_below_raw_name(raw, rb, sizeof rb);
        if (c->only_hemispherical) {
            lsqt_raw_hemi_name(rb, "R", o->raw_b, sizeof o->raw_b);
            lsqt_raw_hemi_name(rb, "T", o->raw_bt, sizeof o->raw_bt);
            o->path[OUT_RAW_BT] = o->raw_bt;
        } else {
            snprintf(o->raw_b, sizeof o->raw_b, "%s", rb);
        }
        o->path[OUT_RAW_B] = o->raw_b;
    }
    if (c->only_hemispherical) {
        const char *what = NULL;
        int t = strcmp(raw, "-") == 0 ? LSQT_PATH_SPECIAL : lsqt_path_type(raw, &what);
        if (t == LSQT_PATH_SPECIAL || t == LSQT_PATH_DIRECTORY) {
            snprintf(err, errcap, "-H writes two files named from the RAW name, and '%s' is %s%s", raw,
                     what ? "a " : "stdout", what ? what : "");
            return 2;
        }
        lsqt_raw_hemi_name(raw, "R", o->raw, sizeof o->raw);
        o->path[OUT_RAW] = o->raw;
        if (transmits) {
            lsqt_raw_hemi_name(raw, "T", o->raw_t, sizeof o->raw_t);
            o->path[OUT_RAW_T] = o->raw_t;
        }
    } else {
        memcpy(o->raw, raw, sizeof raw);
        o->path[OUT_RAW] = o->raw;
    }
    if (c->lss) o->path[OUT_LSS] = c->lss;
    else if (!from_stdin) {
        snprintf(o->lss, sizeof o->lss, "%s.lss", c->input);
        o->path[OUT_LSS] = o->lss;
    }
    o->path[OUT_JSON] = c->json;
    o->base = o->path[OUT_LSS];
    if (c->shard_n) {
        /* a shard writes its part beside the state it continues; a RAW only when asked */
        if (!o->base || strcmp(o->base, "-") == 0) {
            snprintf(err, errcap, "--shard writes an LSS named from the run's LSS: give a file (--lss PATH)");
            return 2;
        }
        size_t n = strlen(o->base);
        if (n >= 4 && strcmp(o->base + n - 4, ".lss") == 0) n -= 4;
        snprintf(o->shard, sizeof o->shard, "%.*s.shard-%d-of-%d.lss", (int)n, o->base, c->shard_k, c->shard_n);
        o->path[OUT_LSS] = o->shard;
        if (!c->output) o->path[OUT_RAW] = o->path[OUT_RAW_T] = o->path[OUT_RAW_B] = o->path[OUT_RAW_BT] = NULL;
    }
    /* No output may land on another one, on stdout twice, or on the input. */
    for (int i = 0; i < OUT_COUNT; i++) {
        if (!o->path[i]) continue;
        for (int j = i + 1; j < OUT_COUNT; j++)
            if (o->path[j] && lsqt_same_file(o->path[i], o->path[j])) {
                snprintf(err, errcap, "two outputs would be written to '%s'%s", o->path[i],
                         strcmp(o->path[i], "-") == 0 ? " (stdout)" : "");
                return 2;
            }
        if (!from_stdin && strcmp(o->path[i], "-") != 0 && lsqt_same_file(o->path[i], c->input)) {
            snprintf(err, errcap, "the output '%s' would replace the input", o->path[i]);
            return 2;
        }
    }
    return 0;
}

static const char *dirs_name(uint32_t m)
{
    return m == LSQT_DIRS_RRSS ? "RRSS" : m == LSQT_DIRS_FILE ? "--wi-file" : m == LSQT_DIRS_GRID ? "--grid"
         : m == LSQT_DIRS_RGL  ? "--rgl-grid" : "--wi-spread";
}

/* A continued run keeps its LSS's sampling. A sampling flag with the LSS's own value is
 * fine; one that contradicts the LSS is an error (exit 2: the user meant another run, and
 * -R starts one); -rp names what the LSS keeps. Returns 0, or 2 with err filled. */
static int check_continuation(const lsqt_cli *c, const lsqt_state *st, const char *lss, int n_wi_file, char *err,
                              size_t errcap)
{
    char why[512] = "", flag[64] = "";
    /* the outgoing angles: the distinct theta_o of the slices from above */
    double th[LSQT_MAX_WO];
    int n_th = 0;
    for (int s = 0; s < st->n_slices; s++) {
        if (st->slice_flags[s] & LSQT_SLICE_BELOW) continue;
        int seen = 0;
        for (int j = 0; j < n_th && !seen; j++) seen = th[j] == st->theta_o[s];
        if (!seen && n_th < LSQT_MAX_WO) th[n_th++] = st->theta_o[s];
    }
    if (c->seed_given && c->seed != st->seed) {
        snprintf(flag, sizeof flag, "-s %llu", (unsigned long long)c->seed);
        snprintf(why, sizeof why, "its paths were drawn with -s %llu", (unsigned long long)st->seed);
    } else if (c->wi_given && c->wi_count != st->n_wi) {
        snprintf(flag, sizeof flag, "-wi %d", c->wi_count);
        snprintf(why, sizeof why, "it holds %d incident directions per slice", st->n_wi);
    } else if (c->wo_given && c->wo_count != n_th) {
        snprintf(flag, sizeof flag, "-wo %d", c->wo_count);
        snprintf(why, sizeof why, "it holds %d outgoing directions", n_th);
    } else if (c->n_wo_angles) {
        int same = c->n_wo_angles == n_th;
        for (int i = 0; i < c->n_wo_angles && same; i++) {
            int found = 0;
            for (int j = 0; j < n_th && !found; j++) found = fabs(c->wo_angles[i] - th[j]) < 1e-9;
            same = found;
        }
        if (!same) {
            snprintf(flag, sizeof flag, "--wo-angles");
            snprintf(why, sizeof why, "its %d outgoing angles are others", n_th);
        }
    }
    const uint32_t want_method = c->grid_rgl ? LSQT_DIRS_RGL : LSQT_DIRS_GRID;
    if (!flag[0] && c->grid_no &&
        (st->dir_method != want_method || (uint32_t)c->grid_ni != st->grid_ni ||
         (uint32_t)c->grid_nphi != st->grid_nphi || c->grid_no != n_th)) {
        if (c->grid_rgl) snprintf(flag, sizeof flag, "--rgl-grid %d,%d", c->grid_no, c->grid_ni);
        else snprintf(flag, sizeof flag, "--grid %d,%d,%d", c->grid_no, c->grid_ni, c->grid_nphi);
        if (st->dir_method == LSQT_DIRS_GRID)
            snprintf(why, sizeof why, "it is on the grid %d,%u,%u", n_th, st->grid_ni, st->grid_nphi);
        else if (st->dir_method == LSQT_DIRS_RGL)
            snprintf(why, sizeof why, "it is on the RGL grid %d,%u", n_th, st->grid_ni);
        else snprintf(why, sizeof why, "its incident directions were chosen by %s", dirs_name(st->dir_method));
    }
    if (!flag[0] && ((c->wi_spread && st->dir_method != LSQT_DIRS_SPREAD) ||
                     (c->wi_file && st->dir_method != LSQT_DIRS_FILE) ||
                     ((c->rx_given || c->rp_given) && st->dir_method != LSQT_DIRS_RRSS))) {
        snprintf(flag, sizeof flag, "%s", c->wi_spread ? "--wi-spread" : c->wi_file ? "--wi-file" : c->rx_given ? "-rx" : "-rp");
        snprintf(why, sizeof why, "its incident directions were chosen by %s", dirs_name(st->dir_method));
    }
    if (!flag[0] && c->wi_file && n_wi_file != st->n_wi) {
        snprintf(flag, sizeof flag, "--wi-file %.40s", c->wi_file);
        snprintf(why, sizeof why, "it holds %d incident directions per slice, the file %d", st->n_wi, n_wi_file);
    }
    if (!flag[0] && c->rx_given && (uint32_t)c->rx != st->rx) {
        snprintf(flag, sizeof flag, "-rx %d", c->rx);
        snprintf(why, sizeof why, "its RRSS pilot drew -rx %u candidates per direction", st->rx);
    }
    if (!flag[0] && c->from_below && lsqt_state_below_count(st) == 0 && st->transmits) {
        snprintf(flag, sizeof flag, "--from-below");
        snprintf(why, sizeof why, "it has no slices from below");
    }
    if (!flag[0] && c->use_double && !st->use_double) {
        snprintf(flag, sizeof flag, "--double");
        snprintf(why, sizeof why, "it is a float state");
    }
    if (flag[0]) {
        snprintf(err, errcap, "%s contradicts '%s' (%s): a continued run keeps what its LSS was made with; drop "
                 "%s, or start over with -R", flag, lss, why, flag);
        return 2;
    }
    if (!c->quiet && c->rp_given)
        fprintf(stderr, "note: -rp %g is not used: '%s' keeps its RRSS pilot (%llu paths per slice)\n", c->rp, lss,
                (unsigned long long)st->pilot_paths);
    if (!c->quiet && c->wi_file)
        fprintf(stderr, "note: --wi-file: '%s' keeps the %d directions it was started with\n", lss, st->n_wi);
    return 0;
}

/* The state files this run owns (lsqt_lock_take), released at exit. */
static lsqt_lock g_locks[2] = {{-1, 0, ""}, {-1, 0, ""}};
static void release_locks(void)
{
    for (int i = 0; i < 2; i++) lsqt_lock_release(&g_locks[i]);
}

/* Locks the LSS the run writes (exclusive) and, for a shard, the state it reads (shared),
 * before that is read. Returns 0, or 1 (printed) when another run holds one. */
static int lock_states(const outputs *o, int quiet)
{
    char err[3 * LSQT_PATH_CAP];
    atexit(release_locks);
    const char *paths[2] = {o->path[OUT_LSS], o->base != o->path[OUT_LSS] ? o->base : NULL};
    for (int i = 0; i < 2; i++) {
        if (!paths[i]) continue;
        /* -1 (no lock file can be made there): the output checks say why the place cannot
         * be written, before any work. */
        int r = lsqt_lock_take(&g_locks[i], paths[i], i == 0, err, sizeof err);
        if (r == 2 && !quiet) fprintf(stderr, "warning: %s\n", err);
        else if (r == 1) return fail(1, "%s%s", err, ", or give this run another state file (--lss PATH)");
    }
    return 0;
}

/* Writes every output; a failed one does not stop the others. Returns 0 or 1. */
/* The LSS is lss_st (an interrupted RRSS pilot's own state), the rest from st. */
static int write_outputs(const outputs *o, const lsqt_cli *c, const lsqt_state *st, const lsqt_state *lss_st,
                         const lsqt_slice_est *est, const lsqt_run_info *ri, FILE *info)
{
    char err[LSQT_PATH_CAP + 512];
    int failed = 0, wrote = 0, skipped = 0, sk = 0;
    char done[OUT_COUNT * (LSQT_PATH_CAP + 2)];
    int written[OUT_COUNT] = {0};
    done[0] = '\0';
    /* RAW files hold one side each: the main one exactly what it is without --from-below */
    lsqt_state sides[2];
    lsqt_slice_est *side_est[2] = {NULL, NULL};
    const int two = lsqt_state_below_count(st) > 0;
    memset(sides, 0, sizeof sides);
    int split_failed = two && (lsqt_state_split_sides(st, &sides[0], &sides[1]) ||
                               !(side_est[0] = lsqt_estimates(&sides[0])) || !(side_est[1] = lsqt_estimates(&sides[1])));
    if (split_failed) fail(1, "out of memory%s%s", "", ""), failed++;
    /* The LSS first: it is what a later run continues, so a RAW that cannot be written
     * (a FIFO nobody reads, a full disk) or a kill during the RAW loses no paths. */
    static const int order[OUT_COUNT] = {OUT_LSS, OUT_RAW, OUT_RAW_T, OUT_RAW_B, OUT_RAW_BT, OUT_JSON};
    for (int j = 0; j < OUT_COUNT && !split_failed; j++) {
        const int i = order[j];
        const char *p = o->path[i];
        if (!p) continue;
        const int b = i == OUT_RAW_B || i == OUT_RAW_BT;
        const lsqt_state *rs = two ? &sides[b] : st;
        const lsqt_slice_est *re = two ? side_est[b] : est;
        int rc = i == OUT_LSS    ? lsqt_lss_write(p, lss_st, err, sizeof err)
                 : i == OUT_JSON ? lsqt_report_json(p, st, est, ri, err, sizeof err)
                 : i == OUT_RAW_T || i == OUT_RAW_BT
                     ? lsqt_raw_write(p, rs, re, LSQT_RAW_TRANSMIT, &sk, err, sizeof err)
                     : lsqt_raw_write(p, rs, re, c->only_hemispherical ? LSQT_RAW_REFLECT : LSQT_RAW_ALL,
                                      &skipped, err, sizeof err);
        if (rc) {
            fail(1, "%s%s", err, "");
            failed++;
            continue;
        }
        written[i] = strcmp(p, "-") != 0;
    }
    for (int i = 0; i < OUT_COUNT; i++) /* in the usual order: RAW files, LSS, JSON */
        if (written[i]) {
            size_t n = strlen(done);
            snprintf(done + n, sizeof done - n, "%s%s", wrote++ ? ", " : "", o->path[i]);
        }
    if (!c->quiet && wrote) fprintf(info, "wrote %s\n", done);
    if (!c->quiet && c->only_hemispherical && !o->path[OUT_RAW_T])
        fprintf(info, "note: the stack transmits nothing, so -H wrote no T file\n");
    if (failed) fprintf(stderr, "lsqt-cl: %d output%s could not be written (see above)\n", failed, failed > 1 ? "s" : "");
    for (int b = 0; b < 2; b++) {
        lsqt_estimates_free(side_est[b], sides[b].n_slices);
        lsqt_state_free(&sides[b]);
    }
    return failed ? 1 : 0;
}

/* --from-below: the sides follow the state (a continued LSS decides); a two-sided state
 * adds the RAW files of the side from below. Returns 0, or an exit status (printed). */
static int plan_sides(const lsqt_cli *c, int from_stdin, const lsqt_assembly *a, lsqt_state *st, int continued,
                      outputs *out, char *err, size_t errcap)
{
    const int below = lsqt_state_below_count(st) > 0;
    if (!c->quiet && c->from_below && !lsqt_assembly_transmits(a))
        fprintf(stderr, "note: --from-below: the stack transmits nothing, so no light from below reaches it; "
                        "only the slices from above are simulated\n");
    else if (!c->quiet && continued && below && !c->from_below) /* the other case is refused */
        fprintf(stderr, "note: the LSS has slices from below: both sides are continued\n");
    int rc = below ? plan_outputs(c, from_stdin, st->transmits, 1, out, err, errcap) : 0;
    if (rc) {
        lsqt_state_free(st);
        fail(rc, "%s%s", err, "");
    }
    return rc;
}

int main(int argc, char **argv)
{
    /* lsqt-cl info FILE.lss: reads an LSS, no OpenCL (host/commands/info.c; lssinfo is the same). */
    if (argc >= 2 && strcmp(argv[1], "info") == 0) return lsqt_info_main("lsqt-cl info", argc - 1, argv + 1);
    /* lsqt-cl merge OUT.lss IN.lss...: adds shards (host/commands/merge.c), no OpenCL. */
    if (argc >= 2 && strcmp(argv[1], "merge") == 0) return lsqt_merge_main("lsqt-cl merge", argc - 1, argv + 1);
    /* lsqt-cl export FILE.lss -o OUT.nc: a grid LSS as NetCDF (host/commands/export.c). */
    if (argc >= 2 && strcmp(argv[1], "export") == 0) return lsqt_export_main("lsqt-cl export", argc - 1, argv + 1);
    /* Signals first: a Ctrl-C during device setup or the kernel build must not be lost,
     * and a closed pipe is a write error to report (other outputs still get written). */
    sigint_setup();
    signal(SIGPIPE, SIG_IGN);
    lsqt_out_cancel_flag(&g_stop); /* a signal ends a wait for a FIFO's reader */

    lsqt_cli c;
    char err[LSQT_PATH_CAP + 1024];
    if (argc < 2) {
        lsqt_cli_help(stdout);
        return 0;
    }
    if (lsqt_cli_parse(argc, argv, &c, err, sizeof err)) return fail(2, "%s%s", err, "");
    if (c.help) {
        lsqt_cli_help(stdout);
        return 0;
    }
    if (c.threads) {
        /* PoCL's CPU devices read these when the first OpenCL call loads them: the
         * pthread device of PoCL 3.x (Debian 12's) POCL_MAX_PTHREAD_COUNT, other
         * versions and devices POCL_CPU_MAX_CU_NUM. Other OpenCL drivers read neither. */
        char n[32];
        snprintf(n, sizeof n, "%d", c.threads);
        setenv("POCL_CPU_MAX_CU_NUM", n, 1);
        setenv("POCL_MAX_PTHREAD_COUNT", n, 1);
    }
    if (c.list_devices) {
        lsqt_devices_print(stdout);
        lsqt_device_info *ds = NULL;
        int n = lsqt_devices_list(&ds);
        free(ds);
        return n ? 0 : 3;
    }
    if (!c.input) return fail(2, "no input file given (use - for stdin; see --help)%s%s", "", "");

    /* Input -> assembly. */
    const int from_stdin = strcmp(c.input, "-") == 0;
    size_t len = 0;
    char *text = lsqt_read_text(c.input, LSQT_INPUT_MAX, &len, err, sizeof err);
    if (!text) return fail(2, "%s%s", err, "");
    lsqt_assembly a;
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    int prc = lsqt_parse(text, len, from_stdin ? "<stdin>" : c.input, &a, &diag);
    free(text);
    if (!c.quiet)
        for (int i = 0; i < diag.n_notes; i++) fprintf(stderr, "%s\n", diag.notes[i]);
    if (prc) {
        fprintf(stderr, "%s\n", diag.error);
        return 2;
    }
    g_armed = 1;
    int line = 0;
    const char *model = lsqt_unsupported_model(&a, &line);
    if (model) {
        fprintf(stderr, "%s:%d: error: %s is parsed but not simulated by this version of lsqt-cl yet\n",
                from_stdin ? "<stdin>" : c.input, line, model);
        lsqt_assembly_free(&a);
        return 1;
    }

    /* Over the sphere the equal-area lattice puts its middle direction of an odd count on
     * the horizon, where a BSDF value (tally / |cos|) is 0 / 0. */
    if (!c.wi_file && c.wi_spread && lsqt_assembly_transmits(&a) && c.wi_count % 2) {
        lsqt_assembly_free(&a);
        snprintf(err, sizeof err, "-wi %d: this stack transmits, so the directions cover the sphere", c.wi_count);
        return fail(2, "%s%s", err, " and their count must be even");
    }
    if (c.grid_no) {
        const int tr = lsqt_assembly_transmits(&a), n = lsqt_grid_wi_count(c.grid_ni, c.grid_nphi, tr);
        if (n > LSQT_WI_FILE_MAX) {
            lsqt_assembly_free(&a);
            snprintf(err, sizeof err, "--grid %d,%d,%d: %d incident directions per slice (NI x (NPHI/2 + 1)%s), more than "
                     "the %d a slice can have", c.grid_no, c.grid_ni, c.grid_nphi, n, tr ? " x 2: this stack transmits" : "",
                     LSQT_WI_FILE_MAX);
            return fail(2, "%s%s", err, "");
        }
    }
    /* --wi-file is read (and checked) even when an LSS is continued: bad input is an error
     * whether or not it would be used. Below the horizon is allowed only where light is
     * transmitted; elsewhere the value would be 0 by construction, so it is a mistake. */
    float *wi_dirs = NULL;
    int n_wi_dirs = 0, n_mirrored = 0;
    if (c.wi_file) {
        int wrc = lsqt_wi_file_read(c.wi_file, lsqt_assembly_transmits(&a), &wi_dirs, &n_wi_dirs, &n_mirrored,
                                    err, sizeof err);
        if (wrc) {
            lsqt_assembly_free(&a);
            if (wrc == 2) {
                fprintf(stderr, "%s\n", err);
                return 2;
            }
            return fail(wrc < 0 ? 1 : 2, "--wi-file: %s%s", err, "");
        }
    }
    outputs out;
    int rc = plan_outputs(&c, from_stdin, lsqt_assembly_transmits(&a), 0, &out, err, sizeof err);
    if (rc) {
        free(wi_dirs);
        lsqt_assembly_free(&a);
        return fail(rc, "%s%s", err, "");
    }
    if (lock_states(&out, c.quiet)) {
        free(wi_dirs);
        lsqt_assembly_free(&a);
        return 1;
    }
    const char *lss_path = out.base; /* the state continued */
    /* With an output on stdout, everything else we print goes to stderr. */
    int to_stdout = 0;
    for (int i = 0; i < OUT_COUNT; i++) to_stdout |= out.path[i] && strcmp(out.path[i], "-") == 0;
    FILE *info = to_stdout ? stderr : stdout;

    /* State: continue the LSS when there is one, else start fresh. Only a regular file is
     * ever read as an LSS: a FIFO would block and a device holds no state. */
    size_t clen = lsqt_assembly_canonical(&a, NULL, 0);
    char *canonical = malloc(clen + 1);
    if (!canonical) {
        free(wi_dirs);
        lsqt_assembly_free(&a);
        return fail(1, "out of memory%s%s", "", "");
    }
    lsqt_assembly_canonical(&a, canonical, clen + 1);
    lsqt_state st;
    const char *what = NULL;
    int lss_type = lss_path && !c.restart && strcmp(lss_path, "-") != 0 ? lsqt_path_type(lss_path, &what)
                                                                        : LSQT_PATH_MISSING;
    if (lss_type == LSQT_PATH_SPECIAL) {
        rc = fail(2, "cannot continue from '%s': it is a %s, not an LSS file (add -R to write a fresh state into it)",
                  lss_path, what);
    } else if (lss_type == LSQT_PATH_REGULAR) {
        if (lsqt_lss_read(lss_path, &st, err, sizeof err)) {
            rc = fail(2, "%s (use -R to start over and replace it)%s", err, "");
        } else if (st.hash != lsqt_assembly_hash(&a) || strcmp(st.canonical, canonical) != 0) {
            lsqt_state_free(&st);
            rc = fail(2, "'%s' was made for a different assembly; use -R to start over and replace it%s",
                      lss_path, "");
        } else if (st.stage == LSQT_STAGE_PILOT && lsqt_state_contiguous(&st) == UINT64_MAX) {
            lsqt_state_free(&st);
            rc = fail(2, "'%s' is one shard of an RRSS pilot: merge all of the pilot's shards first "
                         "(lsqt-cl merge OUT.lss SHARDS...)%s", lss_path, "");
        } else if (lsqt_state_contiguous(&st) == UINT64_MAX) {
            lsqt_state_free(&st);
            rc = fail(2, "'%s' holds paths with gaps between them (a partial merge): merge the missing shards "
                         "into it first (see lsqt-cl info)%s", lss_path, "");
        } else if (check_continuation(&c, &st, lss_path, n_wi_dirs, err, sizeof err)) {
            lsqt_state_free(&st);
            rc = fail(2, "%s%s", err, "");
        } else if (!c.quiet) {
            fprintf(stderr, "continuing %s (%llu paths per slice so far)\n", lss_path, (unsigned long long)st.paths);
            if (st.use_double != c.use_double)
                fprintf(stderr, "note: precision follows the LSS (%s)\n", st.use_double ? "double" : "float");
        }
    } else if (new_state(&st, &c, &a, canonical, wi_dirs, n_wi_dirs)) {
        rc = fail(1, "out of memory%s%s", "", "");
    } else if (n_mirrored && !c.quiet) {
        fprintf(stderr, "note: %d direction%s of %s with y < 0 %s simulated at (x, -y, z) (the BSDF is symmetric "
                        "about the plane of wo); the RAW holds both mirror images\n",
                n_mirrored, n_mirrored > 1 ? "s" : "", c.wi_file, n_mirrored > 1 ? "are" : "is");
    }
    free(wi_dirs);
    free(canonical);
    if (!rc) rc = plan_sides(&c, from_stdin, &a, &st, lss_type == LSQT_PATH_REGULAR, &out, err, sizeof err);
    if (rc) {
        lsqt_assembly_free(&a);
        return rc;
    }

    /* Every output location is checked before any work, so a long run never ends in an
     * unwritable path. */
    for (int i = 0; i < OUT_COUNT && !rc; i++)
        if (out.path[i] && lsqt_out_check(out.path[i], err, sizeof err)) rc = fail(1, "%s (nothing simulated)", err, "");

    lsqt_context cx;
    memset(&cx, 0, sizeof cx);
    if (!rc) {
        rc = lsqt_context_create(&cx, c.device, err, sizeof err);
        if (!rc) rc = lsqt_device_check(&cx.dev, st.use_double, err, sizeof err);
        if (rc) fail(rc, "%s%s", err, "");
    }
    if (rc) {
        lsqt_context_release(&cx);
        lsqt_state_free(&st);
        lsqt_assembly_free(&a);
        return rc;
    }
    if (c.verbose) fprintf(stderr, "device: %s [%s]\n", cx.dev.name, cx.dev.platform_name);

    checkpoint_ctx ck = {out.path[OUT_LSS], c.quiet}; /* a shard checkpoints its own file */
    const int can_checkpoint = ck.lss && strcmp(ck.lss, "-") != 0 && c.checkpoint > 0;
    lsqt_sim_opts so = {isatty(STDERR_FILENO) && !c.quiet, c.time_limit, 0, &g_stop, NULL, c.verbose, c.target_error,
                        can_checkpoint ? c.checkpoint : 0.0, can_checkpoint ? write_checkpoint : NULL, &ck};
    lsqt_stages sg;
    rc = lsqt_run_stages(&cx, &a, &st, &c, lss_path, out.path[OUT_LSS], &so, &sg, err, sizeof err);
    lsqt_sim_stats stats = sg.stats;
    const lsqt_work before = sg.before;
    if (rc) {
        fail(rc, "%s%s", err, "");
    } else if (sg.pilot_shard) {
        /* a pilot shard holds candidate blocks, not a BSDF yet: its LSS is all there is */
        const char *ls = out.path[OUT_LSS];
        if (lsqt_lss_write(ls, &st, err, sizeof err)) rc = fail(1, "%s%s", err, "");
        else if (!c.quiet)
            fprintf(info, "shard %d/%d of the RRSS pilot: paths [%llu, %llu) of [0, %llu) in %.3g s; wrote %s\n"
                          "(merge all %d pilot shards, then run the shards with --refine)\n",
                    c.shard_k, c.shard_n, (unsigned long long)sg.part_lo, (unsigned long long)sg.part_hi,
                    (unsigned long long)sg.pilot, stats.seconds, ls, c.shard_n);
        if (!c.quiet && c.output) fprintf(stderr, "note: a pilot shard writes no RAW (-o is not used)\n");
        if (stats.interrupted && g_stop) {
            fprintf(stderr, "lsqt-cl: interrupted (%s): %s the paths done so far\n", signal_name(g_stop),
                    rc ? "tried to write" : "wrote");
            rc = 1;
        }
    } else {
        lsqt_slice_est *est = lsqt_estimates(&st);
        char devname[600];
        snprintf(devname, sizeof devname, "%s [%s]", cx.dev.name, cx.dev.platform_name);
        lsqt_run_info ri = {devname, stats.seconds,
                            stats.seconds > 0 ? (double)stats.paths_added * st.n_slices / stats.seconds : 0.0,
                            (unsigned long long)stats.paths_added, NULL, lsqt_work_totals(&st)};
        ri.work.paths -= before.paths, ri.work.layer_events -= before.layer_events;
        ri.work.medium_events -= before.medium_events, ri.work.nee_evaluations -= before.nee_evaluations;
        static const char *const why[] = {"the path count (-p)", "the target error (--target-error)",
                                          "the time limit (--time-limit)", "an interrupt"};
        if (c.target_error > 0 || c.time_limit > 0) ri.stopped_by = why[stats.stop_reason];
        if (!est) rc = fail(1, "out of memory%s%s", "", "");
        else rc = write_outputs(&out, &c, &st, sg.have_ps ? &sg.ps : &st, est, &ri, info);
        if (est && !c.quiet) lsqt_report_summary(info, &st, est, &ri);
        if (sg.have_ps && !c.quiet && out.path[OUT_LSS] && fflush(info) == 0)
            fprintf(stderr,
                    "note: the run stopped in its RRSS pilot: '%s' holds %llu of the pilot's %llu paths per slice, "
                    "and the RAW's directions are a provisional choice from them. Continuing without -p finishes "
                    "the pilot and then this run (%llu paths per slice in all); continuing with -p N chooses the "
                    "directions from the pilot as it is and adds N paths per slice.\n",
                    out.path[OUT_LSS], (unsigned long long)sg.ps.paths, (unsigned long long)sg.ps.pilot_paths,
                    (unsigned long long)sg.ps.span_end);
        if (!c.quiet && c.shard_n)
            fprintf(info, "shard %d/%d: paths [%llu, %llu) of this run's [%llu, %llu)%s\n", c.shard_k, c.shard_n,
                    (unsigned long long)sg.part_lo, (unsigned long long)sg.part_hi, (unsigned long long)sg.run_lo,
                    (unsigned long long)sg.run_hi, sg.part_lo == sg.part_hi ? " (nothing to do: an empty part)" : "");
        lsqt_estimates_free(est, st.n_slices);
        if (stats.interrupted && g_stop) {
            fprintf(stderr, "lsqt-cl: interrupted (%s): %s the paths done so far\n", signal_name(g_stop),
                    rc ? "tried to write" : "wrote");
            rc = 1;
        }
    }
    if (sg.have_ps) lsqt_state_free(&sg.ps);
    lsqt_context_release(&cx);
    lsqt_state_free(&st);
    lsqt_assembly_free(&a);
    return rc;
}
