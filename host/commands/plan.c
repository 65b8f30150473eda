/* lsqt-cl --plan: what a run of these flags will cost before it is paid for. Two short
 * runs of the same command (4096 paths per slice, then 16384 or as many more as make its
 * extra time about half a second; in a temporary folder) give the time per path (their
 * difference: start-up drops out) and every slice's largest relative error at the longer
 * one, n; Monte Carlo error falls as 1/sqrt(paths), so a target error E needs
 * n (e / E)^2 paths (docs/speed-accuracy.md measures that law). */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "lsqt/lss.h"
#include "lsqt/simulate.h"
#include "lsqt/util.h"
#include "run_cmd.h"

#define PLAN_SHORT 4096u
#define PLAN_LONG 16384u /* at least: error bars from every batch, as --target-error judges them */

static double cpu_seconds(void)
{
    struct rusage r;
    getrusage(RUSAGE_SELF, &r);
    return (double)r.ru_utime.tv_sec + r.ru_utime.tv_usec * 1e-6 + (double)r.ru_stime.tv_sec + r.ru_stime.tv_usec * 1e-6;
}

/* One calibration run: the command's sampling flags, N paths, outputs in DIR. */
static int calibrate(const lsqt_cli *c, const char *dir, uint64_t n, double *wall, double *cpu)
{
    lsqt_cli k = *c;
    char raw[LSQT_PATH_CAP + 16], lss[LSQT_PATH_CAP + 16];
    snprintf(raw, sizeof raw, "%s/c.raw", dir);
    snprintf(lss, sizeof lss, "%s/c.lss", dir);
    k.plan = LSQT_PLAN_CALIBRATION, k.paths = n, k.paths_given = 1, k.total_paths = 0, k.restart = 1, k.quiet = 1, k.verbose = 0;
    k.output = c->no_raw ? NULL : raw, k.lss = lss, k.json = NULL, k.target_error = 0, k.time_limit = 0, k.checkpoint = 0;
    const double w0 = lsqt_now(), c0 = cpu_seconds();
    const int rc = run_command(&k);
    *wall = lsqt_now() - w0, *cpu = cpu_seconds() - c0;
    return rc;
}

/* Removes DIR, the calibration's own folder, and the files the runs wrote in it (one
 * RAW per band with bands, the sides from below, -H's R and T files, the LSS). */
static void remove_dir(const char *dir)
{
    DIR *d = opendir(dir);
    char p[LSQT_PATH_CAP + 300];
    for (struct dirent *e; d && (e = readdir(d));) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        unlink(p);
    }
    if (d) closedir(d);
    if (rmdir(dir)) fprintf(stderr, "note: --plan left its folder %s (%s)\n", dir, strerror(errno));
}

/* The calibration folder of this process, removed by a stop at once (signals.c) too. */
static char g_dir[LSQT_PATH_CAP];
static void remove_own_dir(void)
{
    if (g_dir[0]) remove_dir(g_dir);
}

/* Folders TMP/lsqt-plan.PID.* of earlier --plan runs that were killed (SIGKILL, or a
 * stop at once before this version removed them): PID no longer runs, the folder is ours. */
static void remove_stale_dirs(const char *tmp)
{
    DIR *d = opendir(tmp);
    char p[LSQT_PATH_CAP + 300];
    for (struct dirent *e; d && (e = readdir(d));) {
        char *end = NULL;
        if (strncmp(e->d_name, "lsqt-plan.", 10) != 0) continue;
        const long pid = strtol(e->d_name + 10, &end, 10);
        struct stat sb;
        snprintf(p, sizeof p, "%s/%s", tmp, e->d_name);
        if (end == e->d_name + 10 || *end != '.' || pid <= 0 || pid == (long)getpid()) continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue; /* it runs (or is not ours to ask) */
        if (lstat(p, &sb) == 0 && S_ISDIR(sb.st_mode) && sb.st_uid == getuid()) remove_dir(p);
    }
    if (d) closedir(d);
}

static void print_time(FILE *f, double s)
{
    if (s < 120) fprintf(f, "%.3g s", s);
    else if (s < 7200) fprintf(f, "%.3g min", s / 60);
    else if (s < 172800) fprintf(f, "%.3g h", s / 3600);
    else fprintf(f, "%.3g days", s / 86400);
}

int plan_command(const lsqt_cli *c)
{
    if (strcmp(c->input, "-") == 0) {
        fprintf(stderr, "lsqt-cl: error: --plan runs the input twice: give a file, not stdin\n");
        return 2;
    }
    const double t_start = lsqt_now();
    const char *tmp = getenv("TMPDIR");
    char dir[LSQT_PATH_CAP];
    remove_stale_dirs(tmp && *tmp ? tmp : "/tmp");
    snprintf(dir, sizeof dir, "%s/lsqt-plan.%ld.XXXXXX", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    if (!mkdtemp(dir)) {
        fprintf(stderr, "lsqt-cl: error: --plan: cannot make a temporary folder %s: %s\n", dir, strerror(errno));
        return 1;
    }
    snprintf(g_dir, sizeof g_dir, "%s", dir);
    sigint_at_stop(remove_own_dir);
    if (!c->quiet) fprintf(stderr, "plan: calibrating (two short runs of the same command)...\n");
    double w1 = 0, c1 = 0, w2 = 0, c2 = 0;
    uint64_t n = PLAN_LONG;
    int rc = calibrate(c, dir, PLAN_SHORT, &w1, &c1);
    if (!rc) rc = calibrate(c, dir, n, &w2, &c2);
    if (!rc && w2 - w1 < 0.25) { /* too short to time: again, with about half a second more */
        const double more = ceil(0.5 / fmax(w2 - w1, 1.0 / 128));
        n = (uint64_t)(PLAN_LONG * (more < 64 ? more : 64));
        if (n > PLAN_LONG) rc = calibrate(c, dir, n, &w2, &c2);
    }
    lsqt_state st;
    memset(&st, 0, sizeof st);
    char err[LSQT_PATH_CAP + 1024], lss[LSQT_PATH_CAP + 16];
    snprintf(lss, sizeof lss, "%s/c.lss", dir);
    if (g_stop) /* an interrupted calibration run has rc 1 and has said nothing */
        rc = fprintf(stderr, "lsqt-cl: --plan interrupted (%s): no plan; its calibration runs are removed, "
                             "nothing was written\n", signal_name(g_stop)) > 0;
    if (!rc && lsqt_lss_read(lss, &st, err, sizeof err)) rc = fprintf(stderr, "lsqt-cl: error: %s\n", err) > 0;
    remove_dir(dir);
    sigint_at_stop(NULL);
    g_dir[0] = 0;
    if (rc) return rc;
    /* per path: the difference of the two runs (start-up, tables, the RRSS choice drop out) */
    const double dn = (double)(n - PLAN_SHORT);
    const double wall_pp = fmax(w2 - w1, 1e-9) / dn, cpu_pp = fmax(c2 - c1, 1e-9) / dn;
    const double start = fmax(w1 - PLAN_SHORT * wall_pp, 0.0);
    const int nb = lsqt_state_bands(&st);
    double worst = 0;
    FILE *f = stdout;
    fprintf(f, "plan for %s: %d slices x %d directions", c->input, st.n_slices, st.n_wi);
    if (nb > 1) fprintf(f, ", %d bands", nb);
    fprintf(f, "; calibrated in %.3g s (wall)\n", lsqt_now() - t_start);
    fprintf(f, "time per 1e6 paths per slice: %.3g s wall, %.3g CPU-s; start-up about %.2g s\n", wall_pp * 1e6,
            cpu_pp * 1e6, start);
    if (g_run_shape.n_bands) { /* the calibration's shape is the run's; its paths are the run's -p */
        const uint64_t asked_paths = c->total_paths ? c->total_paths : c->paths_given ? c->paths : 0;
        lsqt_memory_shape m = g_run_shape;
        m.paths = asked_paths;
        const lsqt_memory e = lsqt_memory_estimate(&m);
        char b[4][32], what[64] = "of 8192 paths per slice or more";
        if (asked_paths) snprintf(what, sizeof what, "of %llu paths per slice", (unsigned long long)asked_paths);
        fprintf(f, "peak memory of a run %s: about %s (tallies: %s on the host, %s on the device; RRSS pilot %s)\n",
                what, lsqt_memory_format(e.peak, b[0], 32), lsqt_memory_format(e.state, b[1], 32),
                lsqt_memory_format(e.device, b[2], 32), lsqt_memory_format(e.pilot, b[3], 32));
    }
    fprintf(f, "largest relative error of a slice's BSDF values at %llu paths (error ~ 1/sqrt(paths)):\n",
            (unsigned long long)n);
    fprintf(f, "  slice  theta_o  max_rel_err  paths for 1%%  paths for 0.1%%\n");
    double *err_s = calloc((size_t)st.n_slices, sizeof *err_s); /* the largest over the bands */
    for (int b = 0; err_s && b < nb; b++) {
        const lsqt_state v = lsqt_state_band(&st, b);
        lsqt_slice_est *est = lsqt_estimates(&v);
        for (int s = 0; est && s < st.n_slices; s++) err_s[s] = fmax(err_s[s], est[s].max_rel_err);
        if (est) lsqt_estimates_free(est, st.n_slices);
        else free(err_s), err_s = NULL;
    }
    if (!err_s) {
        lsqt_state_free(&st);
        fprintf(stderr, "lsqt-cl: error: out of memory\n");
        return 1;
    }
    for (int s = 0; s < st.n_slices; s++) {
        const double e = err_s[s];
        worst = fmax(worst, e);
        fprintf(f, "  %5d  %6.2fd  %11.3g  %12.3g  %14.3g\n", s, st.theta_o[s] * 180 / LSQT_PI, e,
                ceil(lsqt_paths_for_error(n, e, 0.01)), ceil(lsqt_paths_for_error(n, e, 0.001)));
    }
    free(err_s);
    const double targets[] = {c->target_error, 0.01, 0.003, 0.001};
    fprintf(f, "for the worst slice (what --target-error E waits for):\n");
    for (int i = 0; i < 4; i++) {
        const double E = targets[i];
        if (!(E > 0) || (i > 0 && E == c->target_error)) continue;
        const double need = ceil(lsqt_paths_for_error(n, worst, E));
        fprintf(f, "  target %-6g %10.3g paths per slice: about ", E, need);
        print_time(f, start + need * wall_pp);
        fprintf(f, " wall, ");
        print_time(f, need * cpu_pp);
        fprintf(f, " CPU%s\n", i == 0 ? " (your --target-error)" : "");
    }
    const uint64_t asked = c->total_paths ? c->total_paths : c->paths_given ? c->paths : 0;
    if (asked) {
        fprintf(f, "your %s %llu: largest relative error about %.3g, ", c->total_paths ? "--total-paths" : "-p",
                (unsigned long long)asked, worst * sqrt((double)n / (double)asked));
        print_time(f, start + (double)asked * wall_pp);
        fprintf(f, " wall, ");
        print_time(f, (double)asked * cpu_pp);
        fprintf(f, " CPU (a fresh run)\n");
    }
    if (!c->quiet)
        fprintf(f, "(a run of --total-paths N, or --target-error E, does it; the calibration wrote nothing here)\n");
    lsqt_state_free(&st);
    return 0;
}
