/* The program a GPU would build, for test_gpu_build's offline compiles:
 *   gpu_program --source OUT.cl                  the kernels' text, as the host builds it
 *   gpu_program FILE.lsqt N_WI GROUP DOUBLE      the build options of FILE's program on
 *                                                the GPU code path (its vector width,
 *                                                one RNG block, 64-bit atomics), N_WI
 *                                                directions in groups of GROUP (the RRSS
 *                                                pilot's rx; 1 for the main run)
 * Both come from the host's own functions, so the test compiles what a GPU gets. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/assembly.h"
#include "lsqt/device.h"
#include "lsqt/session.h"
#include "lsqt/util.h"

int main(int argc, char **argv)
{
    char err[1024] = "";
    if (argc == 3 && !strcmp(argv[1], "--source")) {
        char *src = lsqt_kernel_text(err, sizeof err);
        FILE *f = src ? fopen(argv[2], "w") : NULL;
        if (!f || fputs(src, f) < 0 || fclose(f)) {
            fprintf(stderr, "gpu_program: cannot write %s %s\n", argv[2], err);
            return 1;
        }
        free(src);
        return 0;
    }
    if (argc != 5) {
        fprintf(stderr, "usage: gpu_program --source OUT.cl | FILE.lsqt N_WI GROUP DOUBLE\n");
        return 2;
    }
    size_t len = 0;
    char *text = lsqt_read_file(argv[1], &len, err, sizeof err);
    lsqt_assembly a;
    lsqt_diag d;
    /* its tables (KEY=@FILE, TabulatedPhase table=@FILE) read from FILE's folder, as lsqt-cl does */
    char dir[LSQT_PATH_CAP];
    const char *slash = strrchr(argv[1], '/');
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - argv[1]) + (slash == argv[1]) : 1, slash ? argv[1] : ".");
    if (!text || lsqt_parse(text, len, argv[1], NULL, 0, dir, &a, &d)) {
        fprintf(stderr, "gpu_program: %s%s\n", err, text ? d.error : "");
        free(text);
        return 2;
    }
    free(text);
    char opt[1024];
    int rc = lsqt_kernel_options(&a, atoi(argv[2]), atoi(argv[3]), LSQT_GPU_VECTOR_WIDTH, 1, atoi(argv[4]), 1, opt, sizeof opt);
    if (!rc) printf("%s\n", opt);
    lsqt_assembly_free(&a);
    return rc;
}
