/* lsqt-cl: the subcommands (info, merge, export), or a run: LSQT text -> assembly ->
 * device simulation -> LSS, RAW, summary (run_command.c). main only dispatches. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/device.h"
#include "lsqt/export.h"
#include "lsqt/info.h"
#include "lsqt/merge.h"
#include "lsqt/util.h"
#include "run_cmd.h"

/* --list-devices: exit 3 when there is none. */
static int list_devices(void)
{
    lsqt_devices_print(stdout);
    lsqt_device_info *ds = NULL;
    int n = lsqt_devices_list(&ds);
    free(ds);
    return n ? 0 : 3;
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
    if (c.version) {
        printf("lsqt-cl %s\nOpenCL devices (float on every one; --double on those marked fp64):\n", lsqt_version());
        lsqt_devices_print(stdout);
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
    if (c.list_devices) return list_devices();
    if (!c.input) return fail(2, "no input file given (use - for stdin; see --help)%s%s", "", "");
    return c.plan ? plan_command(&c) : run_command(&c);
}
