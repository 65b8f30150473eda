#include "lsqt/device.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/util.h"

extern const char lsqt_kernel_source[];
extern const size_t lsqt_kernel_source_len;
extern const char *const lsqt_kernel_files[];

const char *lsqt_cl_error_name(cl_int e)
{
    switch (e) {
    case CL_SUCCESS: return "CL_SUCCESS";
    case CL_DEVICE_NOT_FOUND: return "CL_DEVICE_NOT_FOUND";
    case CL_OUT_OF_RESOURCES: return "CL_OUT_OF_RESOURCES";
    case CL_OUT_OF_HOST_MEMORY: return "CL_OUT_OF_HOST_MEMORY";
    case CL_MEM_OBJECT_ALLOCATION_FAILURE: return "CL_MEM_OBJECT_ALLOCATION_FAILURE";
    case CL_BUILD_PROGRAM_FAILURE: return "CL_BUILD_PROGRAM_FAILURE";
    case CL_INVALID_VALUE: return "CL_INVALID_VALUE";
    case CL_INVALID_KERNEL_ARGS: return "CL_INVALID_KERNEL_ARGS";
    case CL_INVALID_WORK_GROUP_SIZE: return "CL_INVALID_WORK_GROUP_SIZE";
    case CL_INVALID_BUFFER_SIZE: return "CL_INVALID_BUFFER_SIZE";
    case CL_INVALID_BUILD_OPTIONS: return "CL_INVALID_BUILD_OPTIONS";
    default: return "CL error";
    }
}

static void device_fill(lsqt_device_info *d, cl_platform_id p, cl_device_id id)
{
    memset(d, 0, sizeof *d);
    d->platform = p;
    d->id = id;
    clGetDeviceInfo(id, CL_DEVICE_NAME, sizeof d->name - 1, d->name, NULL);
    clGetPlatformInfo(p, CL_PLATFORM_NAME, sizeof d->platform_name - 1, d->platform_name, NULL);
    clGetDeviceInfo(id, CL_DEVICE_VERSION, sizeof d->version - 1, d->version, NULL);
    cl_device_type type = 0;
    clGetDeviceInfo(id, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    d->is_gpu = (type & CL_DEVICE_TYPE_GPU) != 0;
    d->is_cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
    cl_bool little = CL_TRUE;
    clGetDeviceInfo(id, CL_DEVICE_ENDIAN_LITTLE, sizeof little, &little, NULL);
    d->little_endian = little == CL_TRUE;
    clGetDeviceInfo(id, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof d->compute_units, &d->compute_units, NULL);
    clGetDeviceInfo(id, CL_DEVICE_LOCAL_MEM_SIZE, sizeof d->local_mem, &d->local_mem, NULL);
    size_t n = 0;
    clGetDeviceInfo(id, CL_DEVICE_EXTENSIONS, 0, NULL, &n);
    char *ext = calloc(n + 1, 1);
    if (ext && clGetDeviceInfo(id, CL_DEVICE_EXTENSIONS, n, ext, NULL) == CL_SUCCESS) {
        d->has_fp64 = strstr(ext, "cl_khr_fp64") != NULL;
        d->has_int64_atomics = strstr(ext, "cl_khr_int64_base_atomics") != NULL;
    }
    free(ext);
}

int lsqt_devices_list(lsqt_device_info **out)
{
    *out = NULL;
    cl_uint np = 0;
    if (clGetPlatformIDs(0, NULL, &np) != CL_SUCCESS || np == 0) return 0;
    cl_platform_id *ps = calloc(np, sizeof *ps);
    if (!ps || clGetPlatformIDs(np, ps, NULL) != CL_SUCCESS) {
        free(ps);
        return 0;
    }
    int count = 0;
    for (cl_uint i = 0; i < np; i++) {
        cl_uint nd = 0;
        if (clGetDeviceIDs(ps[i], CL_DEVICE_TYPE_ALL, 0, NULL, &nd) != CL_SUCCESS || nd == 0) continue;
        cl_device_id *ids = calloc(nd, sizeof *ids);
        lsqt_device_info *grown = realloc(*out, (size_t)(count + (int)nd) * sizeof **out);
        if (!ids || !grown) {
            free(ids);
            break;
        }
        *out = grown;
        if (clGetDeviceIDs(ps[i], CL_DEVICE_TYPE_ALL, nd, ids, NULL) == CL_SUCCESS)
            for (cl_uint k = 0; k < nd; k++) device_fill(&(*out)[count++], ps[i], ids[k]);
        free(ids);
    }
    free(ps);
    return count;
}

void lsqt_devices_print(FILE *f)
{
    lsqt_device_info *ds = NULL;
    int n = lsqt_devices_list(&ds);
    if (n == 0) fprintf(f, "no OpenCL device found\n");
    for (int i = 0; i < n; i++)
        fprintf(f, "%d: %s [%s] (%s, %s, %u compute units%s)\n", i, ds[i].name,
                ds[i].platform_name, ds[i].is_gpu ? "gpu" : ds[i].is_cpu ? "cpu" : "other",
                ds[i].version, ds[i].compute_units, ds[i].has_fp64 ? ", fp64" : "");
    free(ds);
}

static int contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (; *hay; hay++) {
        size_t i = 0;
        while (i < n && hay[i] && tolower((unsigned char)hay[i]) == tolower((unsigned char)needle[i])) i++;
        if (i == n) return 1;
    }
    return n == 0;
}

int lsqt_device_select(const char *spec, lsqt_device_info *out, char *err, size_t errcap)
{
    lsqt_device_info *ds = NULL;
    int n = lsqt_devices_list(&ds);
    if (n == 0) {
        snprintf(err, errcap,
                 "no OpenCL device found. For the CPU, install PoCL: "
                 "apt-get install pocl-opencl-icd ocl-icd-libopencl1 (then check with clinfo -l)");
        return 3;
    }
    int pick = -1;
    if (!spec || !*spec) {
        for (int i = 0; i < n && pick < 0; i++)
            if (ds[i].is_gpu) pick = i;
        if (pick < 0) pick = 0;
    } else {
        char *end = NULL;
        long idx = strtol(spec, &end, 10);
        int numeric = end != spec && *end == '\0';
        for (int i = 0; i < n && pick < 0; i++) {
            if (numeric ? idx == i
                        : strcmp(spec, "gpu") == 0   ? ds[i].is_gpu
                          : strcmp(spec, "cpu") == 0 ? ds[i].is_cpu
                                                     : contains_nocase(ds[i].name, spec) ||
                                                           contains_nocase(ds[i].platform_name, spec))
                pick = i;
        }
    }
    if (pick < 0) {
        int w = snprintf(err, errcap, "no OpenCL device matches '%s'; devices:", spec);
        for (int i = 0; i < n && w > 0 && (size_t)w < errcap; i++)
            w += snprintf(err + w, errcap - (size_t)w, " %d: %s [%s];", i, ds[i].name, ds[i].platform_name);
        free(ds);
        return 2;
    }
    *out = ds[pick];
    free(ds);
    return 0;
}

#ifdef LSQT_LSAN_EARLY
/* Sanitizer builds: LeakSanitizer's exit-time check stops every thread to scan it, and
 * twice in CI its tracer crashed ("Tracer caught signal 11 ... LeakSanitizer has
 * encountered a fatal error") after a test had passed, with PoCL's worker threads about
 * to be torn down. A handler registered after the OpenCL platform is up runs before that
 * teardown (exit handlers run last-registered first), while the workers wait idle; the
 * check is the same one, and it disables the one at exit. */
void __lsan_do_leak_check(void);
static void leak_check_early(void)
{
    fflush(NULL); /* a leak report ends the process without the stdio flush of exit */
    __lsan_do_leak_check();
}
#endif

int lsqt_context_create(lsqt_context *cx, const char *spec, char *err, size_t errcap)
{
    memset(cx, 0, sizeof *cx);
    int rc = lsqt_device_select(spec, &cx->dev, err, errcap);
    if (rc) return rc;
    cl_int e = CL_SUCCESS;
    cl_context_properties props[] = {CL_CONTEXT_PLATFORM, (cl_context_properties)cx->dev.platform, 0};
    cx->ctx = clCreateContext(props, 1, &cx->dev.id, NULL, NULL, &e);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot create an OpenCL context on %s: %s (%d)", cx->dev.name,
                 lsqt_cl_error_name(e), (int)e);
        return 3;
    }
    cx->queue = clCreateCommandQueue(cx->ctx, cx->dev.id, 0, &e);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot create a command queue on %s: %s (%d)", cx->dev.name,
                 lsqt_cl_error_name(e), (int)e);
        clReleaseContext(cx->ctx);
        cx->ctx = NULL;
        return 3;
    }
#ifdef LSQT_LSAN_EARLY
    static int registered = 0;
    if (!registered) registered = atexit(leak_check_early) == 0;
#endif
    return 0;
}

int lsqt_device_check(const lsqt_device_info *d, int use_double, char *err, size_t errcap)
{
    if (use_double && !d->has_fp64) {
        snprintf(err, errcap,
                 "no usable OpenCL device for this request: double precision needs cl_khr_fp64, which "
                 "%s [%s] lacks (drop --double, or pick another device with -d; see --list-devices)",
                 d->name, d->platform_name);
        return 3;
    }
    if (!d->has_int64_atomics && !d->little_endian) {
        snprintf(err, errcap,
                 "no usable OpenCL device for this request: %s [%s] has neither 64-bit atomics nor "
                 "little-endian words, which the tallies need",
                 d->name, d->platform_name);
        return 3;
    }
    return 0;
}

void lsqt_context_release(lsqt_context *cx)
{
    if (cx->queue) clReleaseCommandQueue(cx->queue);
    if (cx->ctx) clReleaseContext(cx->ctx);
    cx->queue = NULL;
    cx->ctx = NULL;
}

/* The kernel text: embedded, or re-read from $LSQT_KERNEL_DIR (the repository root) so a
 * kernel can be edited without rebuilding the host. */
char *lsqt_kernel_text(char *err, size_t errcap)
{
    const char *dir = getenv("LSQT_KERNEL_DIR");
    if (!dir || !*dir) {
        char *s = malloc(lsqt_kernel_source_len + 1);
        if (s) memcpy(s, lsqt_kernel_source, lsqt_kernel_source_len + 1);
        return s;
    }
    size_t total = 0;
    char *all = calloc(1, 1);
    for (int i = 0; all && lsqt_kernel_files[i]; i++) {
        char path[4096];
        size_t len = 0;
        snprintf(path, sizeof path, "%s/%s", dir, lsqt_kernel_files[i]);
        char *part = lsqt_read_file(path, &len, err, errcap);
        char *grown = part ? realloc(all, total + len + 2) : NULL;
        if (!grown) {
            free(part);
            free(all);
            return NULL;
        }
        all = grown;
        memcpy(all + total, part, len);
        total += len;
        all[total++] = '\n';
        all[total] = '\0';
        free(part);
    }
    return all;
}

cl_program lsqt_program_build(lsqt_context *cx, const char *options, char **log, char *err,
                              size_t errcap)
{
    *log = NULL;
    char *src = lsqt_kernel_text(err, errcap);
    if (!src) return NULL;
    cl_int e = CL_SUCCESS;
    const char *srcs[] = {src};
    cl_program prog = clCreateProgramWithSource(cx->ctx, 1, srcs, NULL, &e);
    free(src);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "clCreateProgramWithSource: %s (%d)", lsqt_cl_error_name(e), (int)e);
        return NULL;
    }
    e = clBuildProgram(prog, 1, &cx->dev.id, options, NULL, NULL);
    if (e != CL_SUCCESS) {
        size_t n = 0;
        clGetProgramBuildInfo(prog, cx->dev.id, CL_PROGRAM_BUILD_LOG, 0, NULL, &n);
        *log = calloc(n + 1, 1);
        if (*log) clGetProgramBuildInfo(prog, cx->dev.id, CL_PROGRAM_BUILD_LOG, n, *log, NULL);
        snprintf(err, errcap, "the OpenCL kernels failed to build on %s: %s (%d) with options '%s'",
                 cx->dev.name, lsqt_cl_error_name(e), (int)e, options);
        clReleaseProgram(prog);
        return NULL;
    }
    return prog;
}
