/* MAP_ANONYMOUS (mmap of zero pages) is not in POSIX 2008 */
#define _DEFAULT_SOURCE
#include "lsqt/session.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "lsqt/below.h"
#include "lsqt/tables.h"

static cl_mem make_buffer(lsqt_context *cx, cl_mem_flags fl, size_t size, void *host, cl_int *e)
{
    if (*e != CL_SUCCESS) return NULL;
    const cl_mem_flags copy = host && !(fl & CL_MEM_USE_HOST_PTR) ? CL_MEM_COPY_HOST_PTR : 0;
    return clCreateBuffer(cx->ctx, fl | copy, size, host, e);
}

/* The code path: a CPU's (wide vectors, one work-item per work-group, the four-block
 * RNG) or a GPU's (vector width 2, work-groups of 64, a path per work-item in the walk,
 * one RNG block at a time).
 * LSQT_GPU_PATH=1 takes the GPU's on any device, so the tests run it on a CPU;
 * LSQT_GPU_PATH=0 the CPU's. Returns 1 (GPU), 0 (CPU) or -1 (bad value, err set). */
static int gpu_path(const lsqt_context *cx, char *err, size_t errcap)
{
    const char *env = getenv("LSQT_GPU_PATH");
    if (!env || !*env) return !cx->dev.is_cpu;
    if (!strcmp(env, "0") || !strcmp(env, "1")) return atoi(env);
    snprintf(err, errcap, "LSQT_GPU_PATH is '%s': expected 0 or 1", env);
    return -1;
}

/* The next-event loops take vw directions at a time: 16 on a CPU (AVX-512 holds 16
 * floats; at 4, Substr's next-event work took 1.6x the time), 2 on a GPU, where a
 * work-item's vector is sequential work and registers (at 4, lsqt_estimate of the
 * microsurface families takes 135-138 VGPRs on gfx90a, 3 waves per SIMD; at 2, 93-116).
 * Per-direction values do not depend on it; the vector maths of some builtins may round
 * differently per width. */
static int vector_width(int gpu, char *err, size_t errcap)
{
    const char *env = getenv("LSQT_VECTOR_WIDTH"); /* for tuning a device, and the tests */
    if (!env || !*env) return gpu ? LSQT_GPU_VECTOR_WIDTH : LSQT_CPU_VECTOR_WIDTH;
    if (!strcmp(env, "2") || !strcmp(env, "4") || !strcmp(env, "8") || !strcmp(env, "16")) return atoi(env);
    snprintf(err, errcap, "LSQT_VECTOR_WIDTH is '%s': expected 2, 4, 8 or 16", env);
    return 0;
}

/* A grouped session's kernels see each simulated slice's slice_group blocks of n_wi
 * directions as one set of slice_group x PAD(n_wi, vw) (the padding inside is zero). */
int lsqt_kernel_options(const lsqt_assembly *a, int n_wi, int group, int vw, int gpu, int use_double,
                        int int64_atomics, char *opt, size_t cap)
{
    size_t n = lsqt_assembly_build_options(a, opt, cap);
    if (n >= cap) return 1;
    const size_t nwi = group > 1 ? (size_t)group * LSQT_PAD((size_t)n_wi, (size_t)vw) : (size_t)n_wi;
    n += (size_t)snprintf(opt + n, cap - n, " -cl-std=CL1.2 -DLSQT_NWI=%zu -DLSQT_VW=%d", nwi, vw);
    if (group > 1) n += (size_t)snprintf(opt + n, cap - n, " -DLSQT_GROUP_NWI=%d", n_wi);
    if (use_double) n += (size_t)snprintf(opt + n, cap - n, " -DLSQT_DOUBLE=1");
    if (!gpu) n += (size_t)snprintf(opt + n, cap - n, " -DLSQT_RNG_WIDE=1"); /* philox.cl */
    if (gpu) n += (size_t)snprintf(opt + n, cap - n, " -DLSQT_NEE_RECORDS=1"); /* walk.cl */
    if (!int64_atomics) n += (size_t)snprintf(opt + n, cap - n, " -DLSQT_NO_INT64_ATOMICS=1");
    return n >= cap;
}

static int build_options(lsqt_context *cx, const lsqt_assembly *a, const lsqt_state *st, int group, int vw,
                         int gpu, char *opt, size_t cap, char *err, size_t errcap)
{
    if (lsqt_device_check(&cx->dev, st->use_double, err, errcap)) return 1;
    if (lsqt_kernel_options(a, st->n_wi, group, vw, gpu, st->use_double, cx->dev.has_int64_atomics, opt, cap)) {
        snprintf(err, errcap, "kernel build options too long");
        return 1;
    }
    return 0;
}

/* The directions as the kernel reads them: per simulated slice, x, y and z arrays of its
 * blocks (state slices) one after the other, each zero-padded to a multiple of vw, in the
 * kernel's precision (double ones normalised again: float leaves |wi| - 1 at 1e-7). */
static void *directions_of(const lsqt_state *st, int group, int vw, size_t *bytes)
{
    const size_t pad = LSQT_PAD((size_t)st->n_wi, (size_t)vw), n = (size_t)st->n_slices * 3 * pad;
    const size_t sz = st->use_double ? sizeof(double) : sizeof(float);
    void *buf = calloc(n ? n : 1, sz);
    if (!buf) return NULL;
    for (int sl = 0; sl < st->n_slices; sl++)
        for (size_t i = 0; i < (size_t)st->n_wi; i++) {
            const float *d = st->wi + ((size_t)sl * (size_t)st->n_wi + i) * 4;
            double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
            for (size_t j = 0; j < 3; j++) {
                size_t at = (((size_t)(sl / group) * 3 + j) * (size_t)group + (size_t)(sl % group)) * pad + i;
                if (st->use_double) ((double *)buf)[at] = len > 0 ? d[j] / len : d[j];
                else ((float *)buf)[at] = d[j];
            }
        }
    *bytes = n * sz;
    return buf;
}

/* The scene's run-wide fields, and the slices' outgoing directions (wo, and wo_f in float). */
static void scene_and_wo(const lsqt_session *s, const lsqt_state *st, lsqt_dev_scene *scene, double *wo, float *wo_f,
                         size_t n_wo)
{
    scene->n_wi = st->n_wi;
    scene->slice_group = s->slice_group;
    scene->seed_lo = (lsqt_u32)st->seed;
    scene->seed_hi = (lsqt_u32)(st->seed >> 32);
    scene->rng_side = st->n_slices > 0 && (st->slice_flags[0] & LSQT_SLICE_BELOW) ? LSQT_RNG_BELOW : 0u;
    for (int sl = 0; sl < st->n_slices; sl++) {
        wo[4 * sl] = sin(st->theta_o[sl]);
        wo[4 * sl + 2] = cos(st->theta_o[sl]);
    }
    for (size_t i = 0; i < n_wo; i++) wo_f[i] = (float)wo[i];
}

/* The buffers as the kernels' arguments (those of the launches are set per launch). */
static cl_int set_kernel_args(lsqt_session *s)
{
    cl_int e = CL_SUCCESS;
    cl_mem *args[] = {&s->scene, &s->media, &s->layers, &s->wo, &s->wi, &s->tab};
    for (cl_uint i = 0; i < 6; i++) e |= clSetKernelArg(s->walk, i, sizeof(cl_mem), args[i]);
    e |= clSetKernelArg(s->walk, 9, sizeof(cl_mem), &s->nee);
    e |= clSetKernelArg(s->walk, 10, sizeof(cl_mem), &s->scalars);
    e |= clSetKernelArg(s->walk, 11, sizeof(cl_mem), &s->hist);
    e |= clSetKernelArg(s->walk, 12, sizeof(cl_mem), &s->flags);
    /* The CPU path ignores the records' arguments: any buffer will do. */
    cl_int zero = 0;
    e |= clSetKernelArg(s->walk, 13, sizeof(cl_mem), &s->flags);
    e |= clSetKernelArg(s->walk, 14, sizeof(cl_mem), &s->flags);
    e |= clSetKernelArg(s->walk, 15, sizeof zero, &zero);
    e |= clSetKernelArg(s->walk, 16, sizeof(cl_mem), &s->bandw);
    if (s->records) {
        for (cl_uint i = 0; i < 5; i++)
            e |= clSetKernelArg(s->estimate, i, sizeof(cl_mem), args[i == 3 ? 4 : i == 4 ? 5 : i]);
        e |= clSetKernelArg(s->estimate, 10, sizeof(cl_mem), &s->nee);
        e |= clSetKernelArg(s->estimate, 11, sizeof(cl_mem), &s->flags);
    }
    cl_mem *pargs[] = {&s->scene, &s->media, &s->layers, &s->wi, &s->tab};
    for (cl_uint i = 0; i < 5; i++) e |= clSetKernelArg(s->prepare, i, sizeof(cl_mem), pargs[i]);
    return e;
}

/* The histogram buffer's part for the session's histogram k (its slices k * g to k * g +
 * g - 1) and batch t: LSQT_HIST_BINS rows of the block's nb slots (device_layout.h). */
static lsqt_u128 *hist_part(const lsqt_session *s, lsqt_u128 *all, size_t k, int t)
{
    return all + (k * LSQT_BATCHES + (size_t)t) * LSQT_HIST_BINS * (size_t)s->nb;
}

/* Part (k, t) of the histogram buffer ALL between ST's bands and the buffer: from ST
 * (ALL holds zeros there), or with back into ST (every slice of the group, unless ST's
 * groups are these). Returns 0, or -1 out of memory (ST's packed histograms). */
static int hist_batch(const lsqt_session *s, lsqt_state *st, lsqt_u128 *all, size_t k, int t, int back)
{
    const size_t nb = (size_t)s->nb, g = (size_t)s->slice_group, sg = st->hist_group > 1 ? st->hist_group : 1;
    lsqt_u128 *part = hist_part(s, all, k, t);
    for (size_t j = 0; j < nb; j++) {
        if (s->band_of[j] < 0) continue;
        for (size_t m = 0; m < (back ? g : 1); m++) {
            const size_t sl = k * g + m;
            if (m && sl / sg == k * g / sg) break; /* ST's groups are these: written once */
            if (!back) lsqt_state_hist_read(st, s->band_of[j], (int)sl, t, part + j, nb);
            else if (lsqt_state_hist_write(st, s->band_of[j], (int)sl, t, part + j, nb)) return -1;
        }
    }
    return 0;
}

/* A block's tallies between ST and ALL, laid out as its buffers hold them: the path sums
 * and scalars slot after slot, the histogram with the slots innermost (device_layout.h)
 * and one per slice group (its blocks' exits are the same paths'). With back, from ALL
 * into ST; else from ST into ALL (which holds zeros: a padding slot's part stays so).
 * Returns 0, or -1 out of memory. */
static int block_tallies(const lsqt_session *s, lsqt_state *st, int which, lsqt_u128 *all, int back)
{
    const size_t n = which == 0 ? s->n_nee : which == 1 ? s->n_scalars : s->n_hist, nb = (size_t)s->nb;
    if (which != 2) {
        for (size_t j = 0; j < nb; j++) {
            if (s->band_of[j] < 0) continue;
            const lsqt_state v = lsqt_state_band(st, s->band_of[j]);
            lsqt_u128 *band = which == 0 ? v.nee : v.scalars;
            if (back) lsqt_tallies_copy(band, all + j * n, n);
            else lsqt_tallies_copy(all + j * n, band, n);
        }
        return 0;
    }
    /* part by part (a part of 16 slots is 256 KB: every slot's bins stay in cache) */
    for (size_t k = 0; k < n / ((size_t)LSQT_BATCHES * LSQT_HIST_BINS); k++)
        for (int t = 0; t < LSQT_BATCHES; t++)
            if (hist_batch(s, st, all, k, t, back)) return -1;
    return 0;
}

/* Buffer BUF (BYTES) gets ST's tallies WHICH: for a state without paths (a fresh run, a
 * pilot) zeros, filled on the device (no staging copy of what may be a GB of zeros) or
 * already there (a CPU device's mapped zero pages, s->host); else written in place
 * through a map, only the nonzero words into a CPU device's zero pages. */
static cl_int put_tallies(const lsqt_session *s, lsqt_state *st, int which, cl_mem buf, size_t bytes)
{
    if (which == 2 && s->hist_home) return CL_SUCCESS; /* lent launch by launch (stream_hist) */
    cl_command_queue q = s->cx->queue;
    const cl_ulong zero = 0;
    const int zeros = s->host[which] != NULL;
    if (st->paths == 0) return zeros ? CL_SUCCESS : clEnqueueFillBuffer(q, buf, &zero, sizeof zero, 0, bytes, 0, NULL, NULL);
    cl_int e = CL_SUCCESS;
    lsqt_u128 *p = clEnqueueMapBuffer(q, buf, CL_TRUE, zeros ? CL_MAP_WRITE : CL_MAP_WRITE_INVALIDATE_REGION, 0, bytes, 0,
                                      NULL, NULL, &e);
    if (e != CL_SUCCESS) return e;
    if (!zeros) memset(p, 0, bytes); /* a padding slot's part */
    (void)block_tallies(s, st, which, p, 0); /* reads ST only: cannot fail */
    return clEnqueueUnmapMemObject(q, buf, p, 0, NULL, NULL);
}

/* The tables, the directions and the tallies go up; the direction tables (T, Lambda,
 * lgamma(1 + Lambda) per slice, layer and direction) are made on the device, once. A
 * block of bands has its own tables (band_blocks.h). */
static int upload(lsqt_session *s, const lsqt_assembly *full, const lsqt_band_block *blk, lsqt_state *st,
                  lsqt_state *take, char *err, size_t errcap)
{
    lsqt_context *cx = s->cx;
    const lsqt_assembly *a = lsqt_assembly_band(full, blk->band[0]);
    const int n = a->n_layers;
    lsqt_dev_scene scene;
    /* the reference media, and a block's each band's own after them (band_blocks.h) */
    const int n_media = (n + 1) * (s->nb > 1 ? 1 + s->nb : 1);
    lsqt_dev_medium_d *media = calloc((size_t)n_media, sizeof *media);
    lsqt_dev_layer_d *layers = calloc((size_t)n + 1, sizeof *layers);
    lsqt_dev_medium *media_f = calloc((size_t)n_media, sizeof *media_f);
    lsqt_dev_layer *layers_f = calloc((size_t)n + 1, sizeof *layers_f);
    const int nbp = (int)LSQT_PAD(s->nb, s->vw); /* walk.cl's LSQT_NBP */
    const size_t n_bw = s->nb > 1 ? (size_t)LSQT_BAND_TAB_SIZE(n, nbp) : 1;
    double *bw = calloc(n_bw, sizeof *bw);
    float *bw_f = calloc(n_bw, sizeof *bw_f);
    /* Directions go to the device in the kernel's precision: double for --double. */
    const size_t pad = LSQT_PAD((size_t)st->n_wi, (size_t)s->vw), n_wo = (size_t)st->n_slices * 4;
    double *wo = calloc(n_wo, sizeof *wo);
    float *wo_f = calloc(n_wo, sizeof *wo_f);
    size_t wi_bytes = 0;
    void *wi_up = directions_of(st, s->slice_group, s->vw, &wi_bytes);
    int rc = 1;
    cl_int e = CL_SUCCESS;
    if (!media || !layers || !media_f || !layers_f || !wo || !wo_f || !wi_up || !bw || !bw_f ||
        (s->nb > 1 && lsqt_band_block_tables(full, blk, nbp, st->use_double ? 0.0 : 0x1p-19, &scene, media, layers, bw,
                                             media + n + 1))) {
        snprintf(err, errcap, "out of memory");
        goto done;
    }
    if (s->nb == 1) lsqt_device_tables(a, &scene, media, layers);
    /* a phase table's place: its medium's distance to the end of the media, then its
     * offset in the tables after them (common.cl medium_table) */
    for (int m = 0; m < n_media; m++)
        if (media[m].phase_kind == LSQT_PHASE_TABULATED) media[m].pp[0] = n_media - m;
    lsqt_tables_to_float(media, media_f, n_media, layers, layers_f, n);
    for (size_t i = 0; i < n_bw; i++) bw_f[i] = (float)bw[i];
    /* the strides between the block's bands' tallies (device_layout.h) */
    if (2 * s->n_hist > UINT32_MAX || 2 * s->n_nee > UINT32_MAX || 2 * s->n_scalars > UINT32_MAX) {
        snprintf(err, errcap, "too many directions and slices for a band block (LSQT_BAND_BLOCK=1 runs them)");
        goto done;
    }
    scene.band_nee_words = (lsqt_u32)(2 * s->n_nee);
    scene.band_scalar_words = (lsqt_u32)(2 * s->n_scalars);
    /* The kernel reads the layout it was built for (see device_layout.h). */
    const void *media_up = st->use_double ? (const void *)media : (const void *)media_f;
    const void *layers_up = st->use_double ? (const void *)layers : (const void *)layers_f;
    const size_t media_size = st->use_double ? sizeof *media : sizeof *media_f;
    const size_t layer_size = st->use_double ? sizeof *layers : sizeof *layers_f;
    scene_and_wo(s, st, &scene, wo, wo_f, n_wo);
    const size_t dir_size = st->use_double ? sizeof(double) : sizeof(float);
    void *wo_up = st->use_double ? (void *)wo : (void *)wo_f;
    cl_mem_flags ro = CL_MEM_READ_ONLY, rw = CL_MEM_READ_WRITE;
    cl_uint flags0 = 0;
    s->scene = make_buffer(cx, ro, sizeof scene, &scene, &e);
    /* the phase functions' tables follow the media in their buffer (tables.h) */
    const size_t n_pt = lsqt_device_phase_tables(a, NULL), media_bytes = (size_t)n_media * media_size;
    unsigned char *media_all = malloc(media_bytes + n_pt * dir_size + 1);
    double *pt = malloc(n_pt * sizeof *pt + 1);
    if (!media_all || !pt || n_pt > ((size_t)1 << 24)) { /* pp holds offsets exactly in float up to 2^24 */
        free(media_all), free(pt);
        snprintf(err, errcap, !media_all || !pt ? "out of memory" : "phase tables too long (more than 2^24 reals)");
        goto done;
    }
    lsqt_device_phase_tables(a, pt);
    memcpy(media_all, media_up, media_bytes);
    for (size_t i = 0; i < n_pt; i++) {
        if (st->use_double) memcpy(media_all + media_bytes + i * sizeof(double), &pt[i], sizeof(double));
        else {
            const float f = (float)pt[i];
            memcpy(media_all + media_bytes + i * sizeof f, &f, sizeof f);
        }
    }
    s->media = make_buffer(cx, ro, media_bytes + n_pt * dir_size, media_all, &e);
    free(media_all), free(pt);
    s->layers = make_buffer(cx, ro, (size_t)n * layer_size, (void *)layers_up, &e);
    s->wo = make_buffer(cx, ro, n_wo * dir_size, wo_up, &e);
    s->wi = make_buffer(cx, ro, wi_bytes, wi_up, &e);
    const size_t tab_size = (size_t)st->n_slices * ((size_t)n * LSQT_LAYER_TAB_ROWS + LSQT_MEDIA_TAB_ROWS) * pad * dir_size; /* LSQT_SLICE_TAB */
    s->tab = make_buffer(cx, rw, tab_size, NULL, &e);
    const size_t nb = (size_t)s->nb;
    const size_t tally_bytes[3] = {nb * s->n_nee * sizeof *st->nee, nb * s->n_scalars * sizeof *st->scalars,
                                   nb * s->n_hist * sizeof *st->hist};
    cl_mem *tally_buf[3] = {&s->nee, &s->scalars, &s->hist};
    for (int i = 0; i < 3; i++) {
        if (cx->dev.is_cpu && e == CL_SUCCESS) { /* mapped zero pages, the device's own memory */
            void *m = mmap(NULL, tally_bytes[i], PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
            if (m == MAP_FAILED) e = CL_OUT_OF_HOST_MEMORY;
            else s->host[i] = m, s->host_bytes[i] = tally_bytes[i];
        }
        *tally_buf[i] = make_buffer(cx, rw | (s->host[i] ? CL_MEM_USE_HOST_PTR : 0), tally_bytes[i], s->host[i], &e);
    }
    s->bandw = make_buffer(cx, ro, n_bw * dir_size, st->use_double ? (void *)bw : (void *)bw_f, &e);
    s->flags = make_buffer(cx, rw, sizeof flags0, &flags0, &e);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot allocate device buffers: %s (%d)", lsqt_cl_error_name(e), (int)e);
        goto done;
    }
    /* packed histograms on a CPU device: its buffer holds a batch only while a launch adds to it */
    s->hist_home = st->hist_pk && s->host[2] ? st : NULL;
    for (int i = 0; i < 3 && e == CL_SUCCESS; i++) e = put_tallies(s, st, i, *tally_buf[i], tally_bytes[i]);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot put the tallies on the device: %s (%d)", lsqt_cl_error_name(e), (int)e);
        goto done;
    }
    for (int j = 0; take && j < s->nb; j++) { /* lsqt_session_open_taking: the block's bands are the device's now */
        if (s->band_of[j] < 0) continue;
        lsqt_state v = lsqt_state_band(take, s->band_of[j]);
        lsqt_tallies_drop(v.nee, lsqt_state_nee_count(&v));
        lsqt_tallies_drop(v.scalars, lsqt_state_scalar_count(&v));
        if (v.hist) lsqt_tallies_drop(v.hist, lsqt_state_hist_count(&v)); /* packed ones stay (put_tallies) */
    }
    e = set_kernel_args(s);
    if (e == CL_SUCCESS) {
        size_t pglobal[2] = {pad * (size_t)s->slice_group, (size_t)(st->n_slices / s->slice_group)};
        e = clEnqueueNDRangeKernel(cx->queue, s->prepare, 2, NULL, pglobal, NULL, 0, NULL, NULL);
    }
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot set up the kernels: %s (%d)", lsqt_cl_error_name(e), (int)e);
        goto done;
    }
    rc = 0;
done:
    free(media);
    free(layers);
    free(media_f);
    free(layers_f);
    free(wo);
    free(wo_f);
    free(wi_up);
    free(bw);
    free(bw_f);
    return rc;
}

/* Each kernel's local memory against the device's, so a device that cannot hold it says
 * so here rather than failing a launch with CL_OUT_OF_RESOURCES. The GPU path's kernels
 * need 4.2 KB at most for any direction count (walk.cl's LSQT_ACC_TILE); the CPU path's
 * walk also holds its items' direction sums (walk.cl's LSQT_ITEMS), 96 KB at the largest
 * RRSS pilot, which a CPU device has (PoCL: 2 MB) and a GPU may not. */
static int check_kernel_memory(lsqt_session *s, int verbose, char *err, size_t errcap)
{
    const lsqt_device_info *d = &s->cx->dev;
    const struct {
        cl_kernel k;
        const char *name;
    } ks[] = {{s->walk, "lsqt_walk"}, {s->exits, "lsqt_exits"}, {s->prepare, "lsqt_prepare"}, {s->estimate, "lsqt_estimate"}};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; i++) {
        if (!ks[i].k) continue;
        cl_ulong local = 0, priv = 0;
        clGetKernelWorkGroupInfo(ks[i].k, d->id, CL_KERNEL_LOCAL_MEM_SIZE, sizeof local, &local, NULL);
        clGetKernelWorkGroupInfo(ks[i].k, d->id, CL_KERNEL_PRIVATE_MEM_SIZE, sizeof priv, &priv, NULL);
        if (verbose)
            fprintf(stderr, "kernel %s: %llu bytes of local memory (device: %llu), %llu private per work-item\n",
                    ks[i].name, (unsigned long long)local, (unsigned long long)d->local_mem, (unsigned long long)priv);
        if (d->local_mem && local > d->local_mem) {
            snprintf(err, errcap,
                     "the kernel %s needs %llu bytes of local memory and %s has %llu: this device cannot run it%s",
                     ks[i].name, (unsigned long long)local, d->name, (unsigned long long)d->local_mem,
                     s->records ? "" : " (the GPU code path, LSQT_GPU_PATH=1, needs less)");
            return 1;
        }
    }
    return 0;
}

int lsqt_session_open(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                      const char *extra_options, size_t local_size, int verbose, char *err, size_t errcap)
{
    return lsqt_session_open_grouped(s, cx, a, st, 1, extra_options, local_size, verbose, err, errcap);
}

/* The state's counts, and whether this session can run it: whole slice groups, one side,
 * models the kernels have. Returns 0, or 1 with err filled. */
static int session_shape(lsqt_session *s, const lsqt_assembly *a, const lsqt_state *st, char *err, size_t errcap)
{
    if (st->n_slices % s->slice_group) {
        snprintf(err, errcap, "%d slices are not groups of %d", st->n_slices, s->slice_group);
        return 1;
    }
    s->use_double = st->use_double;
    s->n_slices = st->n_slices;
    s->n_wi = st->n_wi;
    s->n_nee = lsqt_state_nee_count(st);
    s->n_scalars = lsqt_state_scalar_count(st);
    s->n_hist = (size_t)(st->n_slices / s->slice_group) * LSQT_BATCHES * LSQT_HIST_BINS; /* one a slice group */
    /* One program serves one side: the slices from below are another lane (open_lanes). */
    for (int sl = 1; sl < st->n_slices; sl++)
        if ((st->slice_flags[sl] ^ st->slice_flags[0]) & LSQT_SLICE_BELOW) {
            snprintf(err, errcap, "a lane has slices from above and from below");
            return 1;
        }
    int line = 0;
    const char *model = lsqt_unsupported_model(a, &line);
    if (model) {
        snprintf(err, errcap, "line %d: the model %s is not implemented in the kernels yet", line, model);
        return 1;
    }
    return 0;
}

/* The program's kernels (lsqt_estimate on the GPU path only). Returns 0, or 1 with err filled. */
static int make_kernels(lsqt_session *s, const lsqt_state *st, int gpu, char *err, size_t errcap)
{
    cl_int e = CL_SUCCESS, e2 = CL_SUCCESS;
    s->walk = clCreateKernel(s->prog, "lsqt_walk", &e);
    s->prepare = clCreateKernel(s->prog, "lsqt_prepare", &e2);
    cl_int e3 = CL_SUCCESS;
    s->exits = clCreateKernel(s->prog, "lsqt_exits", &e3);
    s->records = gpu;
    s->rec_size = st->use_double ? sizeof(lsqt_nee_rec_d) : sizeof(lsqt_nee_rec); /* device_layout.h */
    if (gpu && e3 == CL_SUCCESS) s->estimate = clCreateKernel(s->prog, "lsqt_estimate", &e3);
    if (e != CL_SUCCESS || e2 != CL_SUCCESS || e3 != CL_SUCCESS) {
        if (e == CL_SUCCESS) e = e2 != CL_SUCCESS ? e2 : e3;
        snprintf(err, errcap, "clCreateKernel: %s (%d)", lsqt_cl_error_name(e), (int)e);
        return 1;
    }
    return 0;
}

/* One block's session (band_blocks.h; a one-band run's is one block of one band): the
 * program built (or PROG, another block's of the same width, shared), its kernels, tables
 * and tallies. A and ST are the run's (every band). */
static int open_block(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                      const lsqt_band_block *blk, int slice_group, const char *extra_options, size_t local_size,
                      int verbose, cl_program prog, lsqt_state *take, char *err, size_t errcap)
{
    memset(s, 0, sizeof *s);
    s->cx = cx;
    s->slice_group = slice_group > 0 ? slice_group : 1;
    s->nb = blk->nb;
    memcpy(s->band_of, blk->band, sizeof s->band_of);
    const lsqt_assembly *a0 = lsqt_assembly_band(a, blk->band[0]);
    const lsqt_state v0 = lsqt_state_band(st, blk->band[0]);
    if (session_shape(s, a0, &v0, err, errcap)) return 1;
    char opt[1024];
    const int gpu = gpu_path(cx, err, errcap);
    if (gpu < 0) return 1;
    s->vw = vector_width(gpu, err, errcap);
    if (!s->vw) return 1;
    if (build_options(cx, a0, &v0, s->slice_group, s->vw, gpu, opt, sizeof opt, err, errcap)) return 1;
    /* A CPU device runs a work-group's items one after another on one thread, so one
     * item does the chunk's 256 paths and the end-of-chunk sums (items x directions, a
     * locked add each) are made once: Slab 5 % and Substr 4 % less CPU than with 8 items
     * (12 % less with 8 than with 64); a GPU wants wide groups. The CPU path's items keep
     * their direction sums in the group's local memory, sized for the group (walk.cl's
     * LSQT_ITEMS). */
    size_t ls = local_size ? local_size : gpu ? LSQT_GPU_ITEMS : 1, kmax = 0;
    if (gpu && ls > LSQT_GPU_ITEMS) ls = LSQT_GPU_ITEMS; /* the kernels' local memory is sized for it */
    if (!gpu && ls > 1 && strlen(opt) + 32 < sizeof opt)
        snprintf(opt + strlen(opt), sizeof opt - strlen(opt), " -DLSQT_ITEMS=%zu", ls);
    if (s->nb > 1 && strlen(opt) + 32 < sizeof opt)
        snprintf(opt + strlen(opt), sizeof opt - strlen(opt), " -DLSQT_NB=%d", s->nb);
    if (extra_options && strlen(opt) + strlen(extra_options) + 2 < sizeof opt) {
        strcat(opt, " ");
        strcat(opt, extra_options);
    }
    if (verbose && !prog) fprintf(stderr, "kernel build options: %s\n", opt);
    char *log = NULL;
    if (prog) clRetainProgram(prog);
    s->prog = prog ? prog : lsqt_program_build(cx, opt, &log, err, errcap);
    if (!s->prog) {
        if (log) fprintf(stderr, "OpenCL build log:\n%s\n", log);
        free(log);
        return 1;
    }
    if (make_kernels(s, &v0, gpu, err, errcap)) {
        lsqt_session_close(s);
        return 1;
    }
    clGetKernelWorkGroupInfo(s->walk, cx->dev.id, CL_KERNEL_WORK_GROUP_SIZE, sizeof kmax, &kmax, NULL);
    if (kmax && ls > kmax) ls = kmax;
    if (gpu) { /* the walk's groups divide a chunk (run_chunks): a power of two up to LSQT_CHUNK */
        size_t p = LSQT_CHUNK;
        while (p > ls) p /= 2;
        ls = p;
    }
    s->local_size = ls;
    if (check_kernel_memory(s, verbose && !prog, err, errcap)) {
        lsqt_session_close(s);
        return 1;
    }
    if (upload(s, a, blk, st, take, err, errcap)) {
        lsqt_session_close(s);
        return 1;
    }
    return 0;
}

/* The widest band block this device and direction count allow: the CPU path keeps per
 * band, per work-item and per direction a sum and a low word (12 bytes in float, 16 in
 * double) in local memory (walk.cl); the GPU path's blocks are at most
 * LSQT_GPU_BAND_BLOCK_MAX wide. */
static int block_width(lsqt_context *cx, const lsqt_state *st, int slice_group, size_t local_size, char *err,
                       size_t errcap)
{
    int width = lsqt_band_block_width(err, errcap);
    const int gpu = gpu_path(cx, err, errcap);
    if (!width || gpu < 0) return 0;
    if (gpu) return width < LSQT_GPU_BAND_BLOCK_MAX ? width : LSQT_GPU_BAND_BLOCK_MAX;
    const int vw = vector_width(gpu, err, errcap);
    if (!vw) return 0;
    size_t nwi = slice_group > 1 ? (size_t)slice_group * LSQT_PAD((size_t)st->n_wi, (size_t)vw) : (size_t)st->n_wi;
    const size_t pad = LSQT_PAD(nwi, (size_t)vw), items = local_size ? local_size : 1;
    const size_t real_size = st->use_double ? 8 : 4, per_band = items * pad * (8 + real_size);
    const size_t local = cx->dev.local_mem ? (size_t)cx->dev.local_mem : (size_t)32768, spare = 16384 + items * pad * real_size;
    const size_t fit = local > spare && per_band ? (local - spare) / per_band : 1;
    if ((size_t)width > fit) width = fit > 1 ? (int)fit : 1;
    return width;
}

static int open_grouped(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                        int slice_group, const char *extra_options, size_t local_size, int verbose, lsqt_state *take,
                        char *err, size_t errcap);

int lsqt_session_open_grouped(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                              int slice_group, const char *extra_options, size_t local_size, int verbose,
                              char *err, size_t errcap)
{
    return open_grouped(s, cx, a, st, slice_group, extra_options, local_size, verbose, NULL, err, errcap);
}

int lsqt_session_open_taking(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                             const char *extra_options, size_t local_size, int verbose, char *err, size_t errcap)
{
    return open_grouped(s, cx, a, st, 1, extra_options, local_size, verbose, st, err, errcap);
}

static int open_lane(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, int slice_group,
                     const char *extra_options, size_t local_size, int verbose, lsqt_state *take, char *err,
                     size_t errcap);

/* A two-sided state's lanes: each side's part of the state, the state's slice of each of
 * the side's slices (in order), and the mirrored assembly of the lane from below. */
typedef struct lsqt_lanes {
    lsqt_state side[2];
    int *at[2];
    lsqt_assembly mirror;
} lsqt_lanes;

/* at[] for ST's slices (0 done, -1 out of memory). */
static int lanes_index(lsqt_lanes *sd, const lsqt_state *st)
{
    int k[2] = {0, 0};
    for (int i = 0; i < 2; i++) {
        free(sd->at[i]);
        sd->at[i] = malloc(((size_t)st->n_slices + 1) * sizeof *sd->at[i]);
        if (!sd->at[i]) return -1;
    }
    for (int sl = 0; sl < st->n_slices; sl++) {
        const int d = (st->slice_flags[sl] & LSQT_SLICE_BELOW) != 0;
        sd->at[d][k[d]++] = sl;
    }
    return 0;
}

static void lanes_free(lsqt_lanes *sd)
{
    if (!sd) return;
    for (int i = 0; i < 2; i++) lsqt_state_free(&sd->side[i]), free(sd->at[i]);
    lsqt_assembly_free(&sd->mirror);
    free(sd);
}

/* A two-sided ST's session: S the lane from above on A, s->below the lane from below on
 * A mirrored, each on its side of ST (split off: lsqt_state_split_by_side). With TAKE, ST's
 * tallies are given back (the sides hold them) and each lane takes its side's. */
static int open_lanes(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, int slice_group,
                      const char *extra_options, size_t local_size, int verbose, lsqt_state *take, char *err,
                      size_t errcap)
{
    memset(s, 0, sizeof *s);
    lsqt_lanes *sd = calloc(1, sizeof *sd);
    lsqt_session *dn = calloc(1, sizeof *dn);
    if (!sd || !dn) {
        free(sd), free(dn);
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    if (lsqt_assembly_mirror(a, &sd->mirror, err, errcap)) {
        free(sd), free(dn);
        return 1;
    }
    int rc = 0;
    if (lsqt_state_split_by_side(st, &sd->side[0], &sd->side[1])) {
        lsqt_assembly_free(&sd->mirror);
        free(sd), free(dn);
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    if (lanes_index(sd, st)) {
        snprintf(err, errcap, "out of memory");
        rc = 1;
    }
    if (!rc && take) lsqt_state_drop_tallies(st);
    if (!rc)
        rc = open_lane(s, cx, a, &sd->side[0], slice_group, extra_options, local_size, verbose,
                       take ? &sd->side[0] : NULL, err, errcap);
    if (!rc && open_lane(dn, cx, &sd->mirror, &sd->side[1], slice_group, extra_options, local_size, verbose,
                         take ? &sd->side[1] : NULL, err, errcap)) {
        lsqt_session_close(s);
        rc = 1;
    }
    if (rc) {
        free(dn);
        lanes_free(sd);
        return 1;
    }
    s->below = dn, s->lanes = sd;
    return 0;
}

static int open_grouped(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st,
                        int slice_group, const char *extra_options, size_t local_size, int verbose, lsqt_state *take,
                        char *err, size_t errcap)
{
    if (lsqt_state_below_count(st))
        return open_lanes(s, cx, a, st, slice_group, extra_options, local_size, verbose, take, err, errcap);
    return open_lane(s, cx, a, st, slice_group, extra_options, local_size, verbose, take, err, errcap);
}

/* -v: each block's bands (runs of neighbours as FIRST-LAST), the largest divergence of
 * two of its bands' paths, and where a band's next runs in another block, theirs: why
 * the bands were grouped so. */
static void describe_blocks(const lsqt_assembly *a, const lsqt_state *st, const lsqt_band_block *blocks,
                            int n_blocks, double most)
{
    fprintf(stderr, "blocks (the largest divergence of two bands' paths in a block, and [the next band's from them] where it runs in another):");
    for (int i = 0; i < n_blocks; i++) {
        const lsqt_band_block *k = &blocks[i];
        for (int j = 0; j < k->nb && k->band[j] >= 0;) {
            int e = j;
            while (e + 1 < k->nb && k->band[e + 1] == k->band[e] + 1) e++;
            for (int x = 0; x < 2 && (x == 0 || e > j); x++) {
                const int b = k->band[x ? e : j];
                if (st->wavelengths) fprintf(stderr, "%s%g%s", x ? "-" : j ? "," : " ", st->wavelengths[b], x || e == j ? "nm" : "");
                else fprintf(stderr, "%s%d", x ? "-" : j ? "," : " ", b + 1);
            }
            j = e + 1;
        }
        double inside = 0.0;
        int last = 0;
        for (int j = 0; j < k->nb && k->band[j] >= 0; j++) {
            last = k->band[j];
            for (int x = 0; x < j; x++) inside = fmax(inside, lsqt_bands_divergence(a, k->band[x], k->band[j]));
        }
        if (k->nb > 1 && k->band[1] >= 0) fprintf(stderr, " (%.2g)", inside);
        if (last + 1 < lsqt_assembly_bands(a)) { /* the next band, when not in this block */
            double next = 0.0;
            int apart = 1;
            for (int j = 0; j < k->nb && k->band[j] >= 0; j++)
                apart &= k->band[j] != last + 1, next = fmax(next, lsqt_bands_divergence(a, k->band[j], last + 1));
            if (apart) fprintf(stderr, " [%.2g]", next);
        }
        fprintf(stderr, "%s", i + 1 < n_blocks ? ";" : "\n");
    }
    if (most >= 0.0)
        fprintf(stderr, "blocks: bands share where their values differ only as a block allows (docs/design.md 3.7) and "
                        "their paths differ by at most %g (LSQT_BAND_DIVERGENCE)\n", most);
    else
        fprintf(stderr, "blocks: bands share where their values differ only as a block allows (docs/design.md 3.7) and "
                        "their paths differ by at most %.2g in a block of 2, %.2g of 16 (sharing must pay every band "
                        "%g times, by a model of what it costs; LSQT_BAND_DIVERGENCE=D sets D)\n",
                lsqt_band_divergence_allowed(2), lsqt_band_divergence_allowed(16), LSQT_BAND_GAIN_MIN);
}

/* One side's session: its band blocks. */
static int open_lane(lsqt_session *s, lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, int slice_group,
                     const char *extra_options, size_t local_size, int verbose, lsqt_state *take, char *err,
                     size_t errcap)
{
    const int nb = lsqt_assembly_bands(a);
    if (nb != lsqt_state_bands(st)) {
        snprintf(err, errcap, "the assembly has %d bands and the state %d", nb, st->n_bands);
        return 1;
    }
    lsqt_band_block one = {1, {0}}, *blocks = &one;
    int n_blocks = 1;
    if (nb > 1) {
        const int width = block_width(cx, st, slice_group, local_size, err, errcap);
        if (!width) return 1;
        const double most = lsqt_band_divergence_max(err, errcap);
        if (most < -1.0) return 1;
        n_blocks = lsqt_band_blocks(a, width, most, &blocks);
        if (n_blocks < 0) {
            snprintf(err, errcap, "out of memory");
            return 1;
        }
        if (verbose) {
            int widest = 0;
            for (int i = 0; i < n_blocks; i++) widest = blocks[i].nb > widest ? blocks[i].nb : widest;
            fprintf(stderr, "%d bands in %d block%s of up to %d sharing their paths\n", nb, n_blocks,
                    n_blocks == 1 ? "" : "s", widest);
            describe_blocks(a, st, blocks, n_blocks, most);
        }
    }
    int rc = open_block(s, cx, a, st, &blocks[0], slice_group, extra_options, local_size, verbose, NULL, take, err,
                        errcap);
    if (!rc && n_blocks > 1) {
        s->blocks = calloc((size_t)n_blocks - 1, sizeof *s->blocks);
        if (!s->blocks) {
            snprintf(err, errcap, "out of memory");
            rc = 1;
        }
    }
    for (int i = 1; !rc && i < n_blocks; i++) {
        /* blocks of one width share a program (the same models in every band) */
        cl_program prog = NULL;
        for (int j = 0; j < i && !prog; j++)
            if (blocks[j].nb == blocks[i].nb) prog = j ? s->blocks[j - 1].prog : s->prog;
        rc = open_block(&s->blocks[i - 1], cx, a, st, &blocks[i], slice_group, extra_options, local_size, verbose,
                        prog, take, err, errcap);
        if (!rc) s->n_blocks = i + 1;
    }
    if (blocks != &one) free(blocks);
    if (rc && s->prog) lsqt_session_close(s);
    return rc;
}

/* Enqueues kernel k over the chunks of paths [begin, end) of every simulated slice
 * (arguments 6, 7, 8 of lsqt_walk; 5, 6, 7 of lsqt_estimate) and waits for it: items
 * work-items per chunk, a work-group's (s->local_size) where a group runs a chunk,
 * LSQT_CHUNK for the GPU path's walk (a path each, in groups that divide the chunk). */
static cl_int run_chunks(lsqt_session *s, cl_kernel k, cl_uint arg0, uint64_t begin, uint64_t end, size_t items)
{
    cl_ulong b = begin, en = end, chunk0 = begin / LSQT_CHUNK;
    cl_ulong nchunks = (end - 1) / LSQT_CHUNK - chunk0 + 1;
    cl_int e = clSetKernelArg(k, arg0, sizeof b, &b);
    e |= clSetKernelArg(k, arg0 + 1, sizeof en, &en);
    e |= clSetKernelArg(k, arg0 + 2, sizeof chunk0, &chunk0);
    size_t global[2] = {(size_t)nchunks * items, (size_t)(s->n_slices / s->slice_group)}, local[2] = {s->local_size, 1};
    if (e == CL_SUCCESS) e = clEnqueueNDRangeKernel(s->cx->queue, k, 2, NULL, global, local, 0, NULL, NULL);
    if (e == CL_SUCCESS) e = clFinish(s->cx->queue);
    return e;
}

/* A buffer of at least n elements of size sz (grown, contents dropped). */
static cl_int ensure_buffer(lsqt_session *s, cl_mem *m, size_t *cap, size_t n, size_t sz)
{
    if (*m && *cap >= n) return CL_SUCCESS;
    if (*m) clReleaseMemObject(*m);
    cl_int e = CL_SUCCESS;
    *cap = n + n / 4 + 1024;
    *m = clCreateBuffer(s->cx->ctx, CL_MEM_READ_WRITE, *cap * sz, NULL, &e);
    if (e != CL_SUCCESS) *m = NULL, *cap = 0;
    return e;
}

/* The records' budget: LSQT_NEE_RECORD_CAP records (the tests make it small to split
 * launches), else a quarter of the device's largest buffer, at most 512 MB; below 2^31
 * records either way (the walk counts a launch's records in 32 bits, nee_records.cl). */
static size_t record_budget(const lsqt_session *s)
{
    const char *env = getenv("LSQT_NEE_RECORD_CAP");
    if (env && *env && atol(env) > 0) return atol(env) < INT32_MAX ? (size_t)atol(env) : (size_t)INT32_MAX;
    cl_ulong max_alloc = 0;
    clGetDeviceInfo(s->cx->dev.id, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof max_alloc, &max_alloc, NULL);
    size_t bytes = max_alloc ? (size_t)(max_alloc / 4) : (size_t)64 << 20;
    if (bytes > ((size_t)512 << 20)) bytes = (size_t)512 << 20;
    return bytes / s->rec_size;
}

/* The GPU path: for each part of [begin, end) the walk counts each path's next-event
 * records, the host turns the counts into offsets and parts the paths so their records
 * fit the budget, then per part the walk writes the records (and tallies the rest) and
 * lsqt_estimate evaluates them. Counting walks the paths twice; the same random numbers
 * make the same paths. */
static cl_int launch_records(lsqt_session *s, uint64_t begin, uint64_t end, int *no_memory)
{
    const size_t n_sim = (size_t)(s->n_slices / s->slice_group), budget = record_budget(s);
    const uint64_t span = (uint64_t)((((size_t)1 << 20) / n_sim) > LSQT_CHUNK ? ((size_t)1 << 20) / n_sim : LSQT_CHUNK);
    cl_int e = CL_SUCCESS;
    cl_ulong *counts = NULL, *off = NULL, *per_path = NULL;
    for (uint64_t pos = begin; pos < end && e == CL_SUCCESS;) {
        const uint64_t stop = end - pos > span ? pos + span : end;
        const size_t n = (size_t)(stop - pos);
        cl_ulong *c2 = realloc(counts, n * n_sim * sizeof *counts), *o2 = c2 ? realloc(off, (n * n_sim + 1) * sizeof *off) : NULL;
        cl_ulong *p2 = o2 ? realloc(per_path, n * sizeof *per_path) : NULL;
        counts = c2 ? c2 : counts, off = o2 ? o2 : off, per_path = p2 ? p2 : per_path;
        if (!p2) {
            *no_memory = 1;
            e = CL_OUT_OF_HOST_MEMORY;
            break;
        }
        e = ensure_buffer(s, &s->rec_off, &s->off_cap, n * n_sim + 1, sizeof(cl_ulong));
        if (e == CL_SUCCESS) e = ensure_buffer(s, &s->rec, &s->rec_cap, 1, s->rec_size);
        if (e == CL_SUCCESS) {
            cl_int one = 1;
            e = clSetKernelArg(s->walk, 13, sizeof(cl_mem), &s->rec);
            e |= clSetKernelArg(s->walk, 14, sizeof(cl_mem), &s->rec_off);
            e |= clSetKernelArg(s->walk, 15, sizeof one, &one);
        }
        if (e == CL_SUCCESS) e = run_chunks(s, s->walk, 6, pos, stop, LSQT_CHUNK);
        if (e == CL_SUCCESS)
            e = clEnqueueReadBuffer(s->cx->queue, s->rec_off, CL_TRUE, 0, n * n_sim * sizeof *counts, counts, 0, NULL, NULL);
        for (size_t i = 0; i < n; i++) {
            per_path[i] = 0;
            for (size_t j = 0; j < n_sim; j++) per_path[i] += counts[j * n + i];
        }
        /* Parts of consecutive paths whose records fit the budget (one path at least). */
        for (size_t p0 = 0; p0 < n && e == CL_SUCCESS;) {
            size_t p1 = p0 + 1;
            cl_ulong total = per_path[p0];
            while (p1 < n && total + per_path[p1] <= budget) total += per_path[p1++];
            const size_t m = p1 - p0;
            cl_ulong at = 0;
            for (size_t j = 0; j < n_sim; j++)
                for (size_t i = p0; i < p1; i++) off[j * m + (i - p0)] = at, at += counts[j * n + i];
            off[m * n_sim] = at;
            e = ensure_buffer(s, &s->rec, &s->rec_cap, at ? (size_t)at : 1, s->rec_size);
            if (e == CL_SUCCESS)
                e = clEnqueueWriteBuffer(s->cx->queue, s->rec_off, CL_TRUE, 0, (m * n_sim + 1) * sizeof *off, off, 0, NULL, NULL);
            if (e == CL_SUCCESS) {
                cl_int zero = 0;
                e = clSetKernelArg(s->walk, 13, sizeof(cl_mem), &s->rec);
                e |= clSetKernelArg(s->walk, 14, sizeof(cl_mem), &s->rec_off);
                e |= clSetKernelArg(s->walk, 15, sizeof zero, &zero);
                e |= clSetKernelArg(s->estimate, 8, sizeof(cl_mem), &s->rec);
                e |= clSetKernelArg(s->estimate, 9, sizeof(cl_mem), &s->rec_off);
            }
            if (e == CL_SUCCESS) e = run_chunks(s, s->walk, 6, pos + p0, pos + p1, LSQT_CHUNK);
            if (e == CL_SUCCESS) e = run_chunks(s, s->estimate, 5, pos + p0, pos + p1, s->local_size);
            p0 = p1;
        }
        pos = stop;
    }
    free(counts);
    free(off);
    free(per_path);
    return e;
}

/* The bands run one after another, so they lend each other band 0's record buffers (the
 * GPU path's; up to 512 MB each) rather than holding one each. */
static void swap_records(lsqt_session *a, lsqt_session *b)
{
    cl_mem rec = a->rec, off = a->rec_off;
    size_t rc = a->rec_cap, oc = a->off_cap;
    a->rec = b->rec, a->rec_off = b->rec_off, a->rec_cap = b->rec_cap, a->off_cap = b->off_cap;
    b->rec = rec, b->rec_off = off, b->rec_cap = rc, b->off_cap = oc;
}

/* A launch of paths [begin, end) on a session that borrows its packed histograms
 * (hist_home): before it (in 0), the batches its chunks fall in are unpacked into the
 * buffer's zero pages; after it, packed back into the state and the pages given back. So
 * the buffer holds at most the batches of one launch (a 200-band run's histograms were
 * 1.3 GB in the buffers). Returns 0, or 1 with err filled. */
static int stream_hist(lsqt_session *s, uint64_t begin, uint64_t end, int in, char *err, size_t errcap)
{
    const uint64_t c0 = begin / LSQT_CHUNK, c1 = (end - 1) / LSQT_CHUNK + 1;
    const size_t parts = s->n_hist / ((size_t)LSQT_BATCHES * LSQT_HIST_BINS), nb = (size_t)s->nb;
    const size_t bytes = nb * s->n_hist * sizeof(lsqt_u128);
    cl_int e = CL_SUCCESS;
    lsqt_u128 *all = clEnqueueMapBuffer(s->cx->queue, s->hist, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, bytes, 0, NULL,
                                        NULL, &e);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot map the histograms: %s (%d)", lsqt_cl_error_name(e), (int)e);
        return 1;
    }
    int rc = 0;
    for (uint64_t c = c0; c < c1 && c < c0 + LSQT_BATCHES && !rc; c++) {
        const int t = (int)(c % LSQT_BATCHES);
        for (size_t k = 0; k < parts && !rc; k++) {
            rc = hist_batch(s, s->hist_home, all, k, t, !in);
            if (!in) lsqt_tallies_drop(hist_part(s, all, k, t), (size_t)LSQT_HIST_BINS * nb);
        }
    }
    e = clEnqueueUnmapMemObject(s->cx->queue, s->hist, all, 0, NULL, NULL);
    if (rc) snprintf(err, errcap, "out of memory for the packed histograms");
    else if (e != CL_SUCCESS) snprintf(err, errcap, "cannot unmap the histograms: %s (%d)", lsqt_cl_error_name(e), (int)e);
    return rc || e != CL_SUCCESS;
}

/* Paths [begin, end) of one lane (every band block of one side). */
static int launch_lane(lsqt_session *s, uint64_t begin, uint64_t end, char *err, size_t errcap)
{
    for (int b = 1; b < s->n_blocks; b++) {
        swap_records(s, &s->blocks[b - 1]);
        const int rc = launch_lane(&s->blocks[b - 1], begin, end, err, errcap);
        swap_records(s, &s->blocks[b - 1]);
        if (rc) return 1;
    }
    if (end <= begin) return 0;
    if (!s->nee) {
        snprintf(err, errcap, "the session's tallies were released by its last read");
        return 1;
    }
    if (s->hist_home && stream_hist(s, begin, end, 1, err, errcap)) return 1;
    int no_memory = 0;
    cl_int e = s->records ? launch_records(s, begin, end, &no_memory) : run_chunks(s, s->walk, 6, begin, end, s->local_size);
    if (e != CL_SUCCESS) {
        if (no_memory) snprintf(err, errcap, "out of memory for the next-event records' offsets");
        else snprintf(err, errcap, "kernel launch failed: %s (%d)", lsqt_cl_error_name(e), (int)e);
        return 1;
    }
    return s->hist_home && stream_hist(s, begin, end, 0, err, errcap);
}

int lsqt_session_launch(lsqt_session *s, uint64_t begin, uint64_t end, char *err, size_t errcap)
{
    return launch_lane(s, begin, end, err, errcap) || (s->below && launch_lane(s->below, begin, end, err, errcap));
}

static int read_block(lsqt_session *s, lsqt_state *st, int release, char *err, size_t errcap);

/* A block's tally buffer I released (and a CPU device's pages unmapped). */
static void release_tally(lsqt_session *s, int i)
{
    cl_mem *bufs[3] = {&s->nee, &s->scalars, &s->hist};
    if (*bufs[i]) clReleaseMemObject(*bufs[i]);
    *bufs[i] = NULL;
    clFinish(s->cx->queue); /* (nothing uses the pages now) */
    if (s->host[i]) munmap(s->host[i], s->host_bytes[i]);
    s->host[i] = NULL;
}

static int read_lane(lsqt_session *s, lsqt_state *st, int release, char *err, size_t errcap)
{
    for (int b = 0; b < (s->n_blocks > 1 ? s->n_blocks : 1); b++) {
        lsqt_session *blk = b ? &s->blocks[b - 1] : s;
        if (!blk->nee) {
            snprintf(err, errcap, "the session's tallies were released by its last read");
            return 1;
        }
        if (read_block(blk, st, release, err, errcap)) return 1;
    }
    return 0;
}

/* Each lane into its side, the sides joined into ST (which is then in the join's order:
 * above's slices first). */
int lsqt_session_read(lsqt_session *s, lsqt_state *st, int release, char *err, size_t errcap)
{
    lsqt_lanes *sd = s->lanes;
    if (!sd) return read_lane(s, st, release, err, errcap);
    lsqt_state both;
    if (read_lane(s, &sd->side[0], release, err, errcap) || read_lane(s->below, &sd->side[1], release, err, errcap) ||
        lsqt_state_join_by_side(&sd->side[0], &sd->side[1], &both, err, errcap))
        return 1;
    lsqt_state_free(st);
    *st = both;
    if (lanes_index(sd, st)) {
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    return 0;
}

/* A block's tallies into its bands' parts of ST; with release, each buffer released once
 * it is read (the host's copy grows as the device's goes). */
static int read_block(lsqt_session *s, lsqt_state *st, int release, char *err, size_t errcap)
{
    cl_command_queue q = s->cx->queue;
    cl_uint fl = 0;
    const size_t nb = (size_t)s->nb, counts[3] = {s->n_nee, s->n_scalars, s->n_hist};
    cl_mem bufs[3] = {s->nee, s->scalars, s->hist};
    cl_int e = CL_SUCCESS;
    for (int i = 0; i < 3 && e == CL_SUCCESS; i++) { /* in place, through a map: no staging copy */
        lsqt_u128 *t = clEnqueueMapBuffer(q, bufs[i], CL_TRUE, CL_MAP_READ, 0, nb * counts[i] * sizeof *t, 0, NULL,
                                          NULL, &e);
        if (e != CL_SUCCESS) break;
        /* a borrowed histogram is the state's already (stream_hist) */
        const int bad = i == 2 && s->hist_home ? s->hist_home != st : block_tallies(s, st, i, t, 1);
        e = clEnqueueUnmapMemObject(q, bufs[i], t, 0, NULL, NULL);
        if (bad) {
            snprintf(err, errcap, s->hist_home && s->hist_home != st ? "the session's histograms are another state's"
                                                                       : "out of memory for the packed histograms");
            return 1;
        }
        if (e == CL_SUCCESS && release) release_tally(s, i);
    }
    if (e == CL_SUCCESS) e = clEnqueueReadBuffer(q, s->flags, CL_TRUE, 0, sizeof fl, &fl, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot read the tallies back: %s (%d)", lsqt_cl_error_name(e), (int)e);
        return 1;
    }
    st->flags |= fl;
    return 0;
}

static int set_lane_directions(lsqt_session *s, const lsqt_state *st, char *err, size_t errcap)
{
    for (int b = 1; b < s->n_blocks; b++)
        if (set_lane_directions(&s->blocks[b - 1], st, err, errcap)) return 1;
    size_t bytes = 0;
    void *dirs = directions_of(st, s->slice_group, s->vw, &bytes);
    if (!dirs) {
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    cl_int e = clEnqueueWriteBuffer(s->cx->queue, s->wi, CL_TRUE, 0, bytes, dirs, 0, NULL, NULL);
    free(dirs);
    if (e == CL_SUCCESS) {
        size_t pglobal[2] = {LSQT_PAD((size_t)st->n_wi, (size_t)s->vw) * (size_t)s->slice_group, (size_t)(st->n_slices / s->slice_group)};
        e = clEnqueueNDRangeKernel(s->cx->queue, s->prepare, 2, NULL, pglobal, NULL, 0, NULL, NULL);
    }
    if (e == CL_SUCCESS) e = clFinish(s->cx->queue);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot upload the directions: %s (%d)", lsqt_cl_error_name(e), (int)e);
        return 1;
    }
    return 0;
}

/* Each side's directions from ST's (they are joined from the sides at a read). */
int lsqt_session_set_directions(lsqt_session *s, const lsqt_state *st, char *err, size_t errcap)
{
    lsqt_lanes *sd = s->lanes;
    if (!sd) return set_lane_directions(s, st, err, errcap);
    const size_t nw = (size_t)st->n_wi * 4;
    for (int d = 0; d < 2; d++)
        for (int i = 0; i < sd->side[d].n_slices; i++)
            memcpy(sd->side[d].wi + (size_t)i * nw, st->wi + (size_t)sd->at[d][i] * nw, nw * sizeof *st->wi);
    return set_lane_directions(s, &sd->side[0], err, errcap) || set_lane_directions(s->below, &sd->side[1], err, errcap);
}

static int lane_exits(lsqt_session *s, uint64_t begin, uint32_t n, float *out, char *err, size_t errcap);

/* Each lane's exits, put at its simulated slices' places among ST's. */
int lsqt_session_exits(lsqt_session *s, uint64_t begin, uint32_t n, float *out, char *err, size_t errcap)
{
    lsqt_lanes *sd = s->lanes;
    if (!sd) return lane_exits(s, begin, n, out, err, errcap);
    const size_t per = (size_t)n * 4, g = (size_t)s->slice_group;
    for (int d = 0; d < 2; d++) {
        lsqt_session *lane = d ? s->below : s;
        const size_t n_sim = (size_t)(lane->n_slices / lane->slice_group);
        float *part = malloc((n_sim ? n_sim : 1) * per * sizeof *part);
        if (!part) {
            snprintf(err, errcap, "out of memory");
            return 1;
        }
        const int rc = lane_exits(lane, begin, n, part, err, errcap);
        for (size_t i = 0; !rc && i < n_sim; i++)
            memcpy(out + (size_t)sd->at[d][i * g] / g * per, part + i * per, per * sizeof *part);
        free(part);
        if (rc) return 1;
    }
    return 0;
}

static int lane_exits(lsqt_session *s, uint64_t begin, uint32_t n, float *out, char *err, size_t errcap)
{
    const size_t n_sim = (size_t)(s->n_slices / s->slice_group), count = n_sim * n * 4;
    const size_t sz = s->use_double ? sizeof(double) : sizeof(float);
    cl_int e = CL_SUCCESS;
    cl_mem buf = clCreateBuffer(s->cx->ctx, CL_MEM_WRITE_ONLY, count * sz, NULL, &e);
    void *host = malloc(count * sz);
    cl_ulong b = begin;
    cl_uint nn = n;
    if (e == CL_SUCCESS && host) {
        cl_mem args[] = {s->scene, s->media, s->layers, s->wo, s->wi, s->tab};
        for (cl_uint i = 0; i < 6; i++) e |= clSetKernelArg(s->exits, i, sizeof(cl_mem), &args[i]);
        e |= clSetKernelArg(s->exits, 6, sizeof b, &b);
        e |= clSetKernelArg(s->exits, 7, sizeof nn, &nn);
        e |= clSetKernelArg(s->exits, 8, sizeof(cl_mem), &buf);
        e |= clSetKernelArg(s->exits, 9, sizeof(cl_mem), &s->flags);
        e |= clSetKernelArg(s->exits, 10, sizeof(cl_mem), &s->bandw);
        /* groups of the session's size, for which the kernels' local memory is sized */
        size_t global[2] = {LSQT_PAD((size_t)n, s->local_size), n_sim}, local[2] = {s->local_size, 1};
        if (e == CL_SUCCESS) e = clEnqueueNDRangeKernel(s->cx->queue, s->exits, 2, NULL, global, local, 0, NULL, NULL);
        if (e == CL_SUCCESS) e = clEnqueueReadBuffer(s->cx->queue, buf, CL_TRUE, 0, count * sz, host, 0, NULL, NULL);
    }
    int rc = 0;
    if (!host) {
        snprintf(err, errcap, "out of memory");
        rc = 1;
    } else if (e != CL_SUCCESS) {
        snprintf(err, errcap, "the RRSS candidate walks failed: %s (%d)", lsqt_cl_error_name(e), (int)e);
        rc = 1;
    } else {
        for (size_t i = 0; i < count; i++) out[i] = s->use_double ? (float)((double *)host)[i] : ((float *)host)[i];
    }
    free(host);
    if (buf) clReleaseMemObject(buf);
    return rc;
}

void lsqt_session_close(lsqt_session *s)
{
    lsqt_session *below = s->below;
    lsqt_lanes *lanes = s->lanes; /* freed after the lanes: their packed histograms' home */
    s->below = NULL, s->lanes = NULL;
    if (below) lsqt_session_close(below);
    free(below);
    for (int b = 1; b < s->n_blocks; b++) lsqt_session_close(&s->blocks[b - 1]);
    free(s->blocks);
    cl_mem *all[] = {&s->scene, &s->media, &s->layers, &s->wo, &s->wi, &s->tab,  &s->nee,
                     &s->scalars, &s->hist, &s->flags, &s->rec, &s->rec_off, &s->bandw};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++)
        if (*all[i]) clReleaseMemObject(*all[i]);
    if (s->walk) clReleaseKernel(s->walk);
    if (s->prepare) clReleaseKernel(s->prepare);
    if (s->exits) clReleaseKernel(s->exits);
    if (s->estimate) clReleaseKernel(s->estimate);
    if (s->prog) clReleaseProgram(s->prog);
    for (int i = 0; i < 3; i++) /* (every command that used them has finished) */
        if (s->host[i]) munmap(s->host[i], s->host_bytes[i]);
    memset(s, 0, sizeof *s);
    lanes_free(lanes);
}
