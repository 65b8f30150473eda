/* lsqt-cl: LSQT text -> assembly -> device simulation -> LSS, RAW, summary. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lsqt/assembly.h"
#include "lsqt/cli.h"
#include "lsqt/device.h"
#include "lsqt/directions.h"
#include "lsqt/lss.h"
#include "lsqt/raw.h"
#include "lsqt/report.h"
#include "lsqt/simulate.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

static volatile sig_atomic_t g_stop = 0;

/* First Ctrl-C: finish the launch, write LSS and RAW, exit non-zero. Second: die. */
static void on_sigint(int sig)
{
    (void)sig;
    g_stop = 1;
    signal(SIGINT, SIG_DFL);
}

static int fail(int code, const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "lsqt-cl: error: ");
    fprintf(stderr, fmt, a, b);
    fprintf(stderr, "\n");
    return code;
}

/* A fresh state: slices, incident directions and zero tallies. */
static int new_state(lsqt_state *st, const lsqt_cli *c, const lsqt_assembly *a, const char *canonical)
{
    int n_slices = c->n_wo_angles ? c->n_wo_angles : c->wo_count;
    if (lsqt_state_init(st, canonical, lsqt_assembly_hash(a), c->seed, n_slices, c->wi_count,
                        lsqt_assembly_transmits(a)))
        return -1;
    st->use_double = c->use_double;
    if (c->n_wo_angles) memcpy(st->theta_o, c->wo_angles, (size_t)n_slices * sizeof(double));
    else lsqt_wo_angles(n_slices, st->theta_o);
    for (int s = 0; s < n_slices; s++)
        lsqt_wi_spread(st->n_wi, st->transmits, st->wi + (size_t)s * (size_t)st->n_wi * 4);
    return 0;
}

static int write_outputs(const lsqt_cli *c, const char *lss_path, const char *raw_path,
                         const lsqt_state *st, const lsqt_slice_est *est, const lsqt_run_info *ri)
{
    char err[1024];
    if (lss_path && lsqt_lss_write(lss_path, st, err, sizeof err)) return fail(1, "%s%s", err, "");
    int skipped = 0, sk = 0;
    if (c->only_hemispherical) {
        char path[4300];
        snprintf(path, sizeof path, "%s.R.raw", raw_path);
        if (lsqt_raw_write(path, st, est, LSQT_RAW_REFLECT, &sk, err, sizeof err)) return fail(1, "%s%s", err, "");
        snprintf(path, sizeof path, "%s.T.raw", raw_path);
        if (lsqt_raw_write(path, st, est, LSQT_RAW_TRANSMIT, &skipped, err, sizeof err))
            return fail(1, "%s%s", err, "");
    } else if (lsqt_raw_write(raw_path, st, est, LSQT_RAW_ALL, &skipped, err, sizeof err)) {
        return fail(1, "%s%s", err, "");
    }
    if (c->json && lsqt_report_json(c->json, st, est, ri, err, sizeof err)) return fail(1, "%s%s", err, "");
    if (!c->quiet) {
        printf("wrote %s%s%s%s", raw_path, c->only_hemispherical ? ".{R,T}.raw" : "", lss_path ? ", " : "",
               lss_path ? lss_path : "");
        printf("%s%s\n", c->json ? ", " : "", c->json ? c->json : "");
    }
    return 0;
}

int main(int argc, char **argv)
{
    lsqt_cli c;
    char err[2048];
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
        char n[32];
        snprintf(n, sizeof n, "%d", c.threads);
        setenv("POCL_CPU_MAX_CU_NUM", n, 1); /* must precede the first OpenCL call */
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
    char *text = lsqt_read_file(c.input, &len, err, sizeof err);
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
    int line = 0;
    const char *model = lsqt_unsupported_model(&a, &line);
    if (model) {
        fprintf(stderr, "%s:%d: error: %s is parsed but not simulated by this version of lsqt-cl yet\n",
                from_stdin ? "<stdin>" : c.input, line, model);
        lsqt_assembly_free(&a);
        return 1;
    }

    /* Output names. */
    char raw_path[4200], lss_buf[4200];
    snprintf(raw_path, sizeof raw_path, "%s", c.output ? c.output : from_stdin ? "Layered.raw" : "");
    if (!c.output && !from_stdin) snprintf(raw_path, sizeof raw_path, "%s.raw", c.input);
    const char *lss_path = c.lss;
    if (!lss_path && !from_stdin) {
        snprintf(lss_buf, sizeof lss_buf, "%s.lss", c.input);
        lss_path = lss_buf;
    }

    /* State: continue the LSS when there is one, else start fresh. */
    size_t clen = lsqt_assembly_canonical(&a, NULL, 0);
    char *canonical = malloc(clen + 1);
    if (!canonical) return fail(1, "out of memory%s%s", "", "");
    lsqt_assembly_canonical(&a, canonical, clen + 1);
    lsqt_state st;
    int rc = 0;
    if (lss_path && !c.restart && lsqt_file_exists(lss_path)) {
        if (lsqt_lss_read(lss_path, &st, err, sizeof err)) {
            rc = fail(2, "%s (use -R to start over and replace it)%s", err, "");
        } else if (st.hash != lsqt_assembly_hash(&a) || strcmp(st.canonical, canonical) != 0) {
            lsqt_state_free(&st);
            rc = fail(2, "'%s' was made for a different assembly; use -R to start over and replace it%s",
                      lss_path, "");
        } else if (!c.quiet) {
            fprintf(stderr, "continuing %s (%llu paths per slice so far)%s\n", lss_path,
                    (unsigned long long)st.paths,
                    c.sampling_given ? "; sampling flags (-wo, -wi, -s, ...) are taken from it" : "");
            if (st.use_double != c.use_double)
                fprintf(stderr, "note: precision follows the LSS (%s)\n", st.use_double ? "double" : "float");
        }
    } else if (new_state(&st, &c, &a, canonical)) {
        rc = fail(1, "out of memory%s%s", "", "");
    }
    free(canonical);
    if (rc) {
        lsqt_assembly_free(&a);
        return rc;
    }

    lsqt_context cx;
    rc = lsqt_context_create(&cx, c.device, err, sizeof err);
    if (rc) {
        lsqt_state_free(&st);
        lsqt_assembly_free(&a);
        return fail(rc, "%s%s", err, "");
    }
    if (c.verbose) fprintf(stderr, "device: %s [%s]\n", cx.dev.name, cx.dev.platform_name);

    signal(SIGINT, on_sigint);
    lsqt_sim_opts so = {isatty(STDERR_FILENO) && !c.quiet, c.time_limit, 0, &g_stop, NULL};
    lsqt_sim_stats stats;
    rc = lsqt_simulate(&cx, &a, &st, c.paths, &so, &stats, err, sizeof err);
    if (rc) {
        fail(1, "%s%s", err, "");
    } else {
        lsqt_slice_est *est = lsqt_estimates(&st);
        char devname[600];
        snprintf(devname, sizeof devname, "%s [%s]", cx.dev.name, cx.dev.platform_name);
        lsqt_run_info ri = {devname, stats.seconds,
                            stats.seconds > 0 ? (double)stats.paths_added * st.n_slices / stats.seconds : 0.0,
                            (unsigned long long)stats.paths_added};
        if (!est) rc = fail(1, "out of memory%s%s", "", "");
        else rc = write_outputs(&c, lss_path, raw_path, &st, est, &ri);
        if (!rc && !c.quiet) lsqt_report_summary(stdout, &st, est, &ri);
        lsqt_estimates_free(est, st.n_slices);
        if (!rc && stats.interrupted && g_stop) {
            fprintf(stderr, "lsqt-cl: interrupted: wrote the paths done so far\n");
            rc = 1;
        }
    }
    lsqt_context_release(&cx);
    lsqt_state_free(&st);
    lsqt_assembly_free(&a);
    return rc;
}
