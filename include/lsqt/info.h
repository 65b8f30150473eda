/* lsqt-cl info / lssinfo: what an LSS file holds, as text or JSON (no OpenCL). */
#ifndef LSQT_INFO_H
#define LSQT_INFO_H

#ifdef __cplusplus
extern "C" {
#endif

/* The whole program: argv[1..argc-1] are its arguments (FILE.lss [--json PATH]); prog
 * names it in messages ("lssinfo", "lsqt-cl info"). Returns the exit status: 0, 1 (an
 * output could not be written) or 2 (bad flags, or a file that is not a readable LSS). */
int lsqt_info_main(const char *prog, int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
