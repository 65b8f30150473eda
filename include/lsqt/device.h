/* OpenCL discovery, device choice, and program builds from the embedded kernel sources. */
#ifndef LSQT_DEVICE_H
#define LSQT_DEVICE_H

#include <CL/cl.h>
#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lsqt_device_info {
    cl_platform_id platform;
    cl_device_id id;
    char name[256];
    char platform_name[256];
    char version[128];
    int is_gpu, is_cpu;
    int has_fp64;
    int has_int64_atomics;
    int little_endian;
    cl_uint compute_units;
    cl_ulong local_mem; /* CL_DEVICE_LOCAL_MEM_SIZE, bytes */
} lsqt_device_info;

/* All devices of all platforms, in a stable order (platform, then device). Returns the
 * count (0 when there is none); *out is heap allocated. */
int lsqt_devices_list(lsqt_device_info **out);

/* Picks a device by spec (the -d value): NULL (first GPU, else first device), an index of the list, a
 * case-insensitive name substring, "cpu" or "gpu". Returns 0, or 3 when no device
 * exists at all, or 2 when spec matches none (err says which exist). */
int lsqt_device_select(const char *spec, lsqt_device_info *out, char *err, size_t errcap);

void lsqt_devices_print(FILE *f);

typedef struct lsqt_context {
    lsqt_device_info dev;
    cl_context ctx;
    cl_command_queue queue;
} lsqt_context;

int lsqt_context_create(lsqt_context *cx, const char *spec, char *err, size_t errcap);
void lsqt_context_release(lsqt_context *cx);

/* Can device D run a simulation (in double precision when use_double)? Returns 0, or 3
 * (exit status "no usable OpenCL device") with err naming the device and what it lacks. */
int lsqt_device_check(const lsqt_device_info *d, int use_double, char *err, size_t errcap);

/* The kernel text (heap, caller frees; NULL on error, with err set): the embedded
 * sources, or the files under $LSQT_KERNEL_DIR (the repository root) when it is set. */
char *lsqt_kernel_text(char *err, size_t errcap);

/* Builds the kernel program (embedded sources, or the files under $LSQT_KERNEL_DIR for
 * development) with OPTIONS. On a compile failure the build log goes into *log (heap,
 * caller frees) and NULL is returned. */
cl_program lsqt_program_build(lsqt_context *cx, const char *options, char **log, char *err,
                              size_t errcap);

const char *lsqt_cl_error_name(cl_int e);

#ifdef __cplusplus
}
#endif
#endif
