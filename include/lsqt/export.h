/* lsqt-cl export: the BSDF of a grid LSS as NetCDF (host/commands/export.c; no OpenCL). */
#ifndef LSQT_EXPORT_H
#define LSQT_EXPORT_H

#ifdef __cplusplus
extern "C" {
#endif

/* The whole program: argv[1..argc-1] are its arguments (FILE.lss -o OUT.nc [-q]); prog
 * names it in messages. Returns the exit status: 0, 1 (the output could not be written)
 * or 2 (bad flags, or an LSS that is unreadable or not on a grid). */
int lsqt_export_main(const char *prog, int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
