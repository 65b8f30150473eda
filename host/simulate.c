#include "lsqt/simulate.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/tally.h"
#include "lsqt/util.h"

/* Models the kernels can run today; the parser knows them all. */
static int bsdf_supported(const lsqt_layer *l)
{
    return l->kind == LSQT_BSDF_NULL || l->kind == LSQT_BSDF_LAMBERTIAN || l->kind == LSQT_BSDF_MS_LAMBERTIAN ||
           l->kind == LSQT_BSDF_MS_DIELECTRIC || l->kind == LSQT_BSDF_MS_CONDUCTIVE || l->kind == LSQT_BSDF_OREN_NAYAR;
}
static int phase_supported(int kind)
{
    return kind == LSQT_PHASE_NONE || kind == LSQT_PHASE_HG || kind == LSQT_PHASE_HG2 || kind == LSQT_PHASE_RAYLEIGH ||
           kind == LSQT_PHASE_SGGX;
}

const char *lsqt_unsupported_model(const lsqt_assembly *a, int *line)
{
    for (int i = 0; i < a->n_layers; i++)
        if (!bsdf_supported(&a->layers[i])) {
            *line = a->layers[i].line;
            return lsqt_bsdf_name(a->layers[i].kind);
        }
    for (int m = 0; m <= a->n_layers; m++)
        if (a->media[m].mus > 0 && !phase_supported(a->media[m].phase.kind)) {
            *line = a->media[m].line;
            return lsqt_phase_name(a->media[m].phase.kind);
        }
    return NULL;
}

static double medium_thickness(const lsqt_assembly *a, int m)
{
    return (m == 0 || m == a->n_layers) ? 0.0 : a->layers[m - 1].z - a->layers[m].z;
}

static double medium_tau(const lsqt_assembly *a, int m)
{
    return (a->media[m].mua + a->media[m].mus) * medium_thickness(a, m);
}

/* A phase model's parameters as the kernels read them (kernels/phase_*.cl). */
static void phase_params(const lsqt_phase *p, double pp[4])
{
    switch (p->kind) {
    case LSQT_PHASE_HG: pp[0] = p->g; break;
    case LSQT_PHASE_HG2: pp[0] = p->g0, pp[1] = p->g1, pp[2] = p->b; break;
    case LSQT_PHASE_RAYLEIGH: pp[0] = p->rho / (2.0 - p->rho); break; /* gamma, as in the seed */
    case LSQT_PHASE_SGGX: {
        /* S = diag(Apara^2, Apara^2, Aperp^2), scaled to a largest entry of 1 (the phase
         * function does not change with the scale of S, and float keeps its range) */
        double a = p->apara > p->aperp ? p->apara : p->aperp;
        pp[0] = (p->apara / a) * (p->apara / a), pp[1] = (p->aperp / a) * (p->aperp / a);
        pp[2] = p->sggx_diffuse ? 1.0 : 0.0;
        break;
    }
    default: break;
    }
}

void lsqt_device_tables(const lsqt_assembly *a, lsqt_dev_scene *scene, lsqt_dev_medium_d *media,
                        lsqt_dev_layer_d *layers)
{
    const int n = a->n_layers;
    memset(scene, 0, sizeof *scene);
    scene->n_layers = n;
    scene->top_nonnull = scene->bottom_nonnull = -1;
    for (int i = 0; i < n; i++) {
        const lsqt_layer *l = &a->layers[i];
        memset(&layers[i], 0, sizeof layers[i]);
        layers[i].kind = l->kind;
        layers[i].iter_count = l->iter_count;
        layers[i].multiple_scattering = l->multiple_scattering;
        const lsqt_medium *up = &a->media[i], *down = &a->media[i + 1];
        if (l->kind == LSQT_BSDF_MS_CONDUCTIVE) {
            /* alpha, and the metal's complex index relative to the medium above */
            layers[i].p[0] = l->alpha;
            layers[i].p[1] = down->eta / up->eta;
            layers[i].p[2] = down->mua / up->eta;
        } else if (l->kind == LSQT_BSDF_MS_DIELECTRIC) {
            /* alpha, the index below relative to the one above, the Fresnel scales */
            layers[i].p[0] = l->alpha;
            layers[i].p[1] = down->eta / up->eta;
            layers[i].p[2] = l->kR;
            layers[i].p[3] = l->kT;
        } else if (l->kind == LSQT_BSDF_MS_LAMBERTIAN) {
            layers[i].p[0] = l->alpha;
            layers[i].p[1] = l->fR;
            layers[i].p[2] = l->fT;
        } else if (l->kind == LSQT_BSDF_OREN_NAYAR) {
            layers[i].p[0] = l->fR;
            layers[i].p[1] = l->sigma;
        } else {
            layers[i].p[0] = l->fR;
            layers[i].p[1] = l->fT;
        }
        if (l->kind != LSQT_BSDF_NULL) {
            if (scene->top_nonnull < 0) scene->top_nonnull = i;
            scene->bottom_nonnull = i;
        }
    }
    for (int m = 0; m <= n; m++) {
        const lsqt_medium *src = &a->media[m];
        lsqt_dev_medium_d *d = &media[m];
        memset(d, 0, sizeof *d);
        d->eta = src->eta;
        d->mua = src->mua;
        d->mus = src->mus;
        d->mut = src->mua + src->mus;
        d->thickness = medium_thickness(a, m);
        d->phase_kind = src->mus > 0 ? src->phase.kind : LSQT_PHASE_NONE;
        phase_params(&src->phase, d->pp);
    }
    /* Optical thickness of the interior media strictly above / below each medium. */
    double acc = 0.0;
    for (int m = 0; m <= n; m++) {
        media[m].tau_above = acc;
        acc += medium_tau(a, m);
    }
    acc = 0.0;
    for (int m = n; m >= 0; m--) {
        media[m].tau_below = acc;
        acc += medium_tau(a, m);
    }
}

/* The float tables of a kernel built without -DLSQT_DOUBLE (same fields, rounded). */
static void tables_to_float(const lsqt_dev_medium_d *md, lsqt_dev_medium *mf, int n_media,
                            const lsqt_dev_layer_d *ld, lsqt_dev_layer *lf, int n_layers)
{
    for (int m = 0; m < n_media; m++) {
        const lsqt_dev_medium_d *d = &md[m];
        lsqt_dev_medium *f = &mf[m];
        memset(f, 0, sizeof *f);
        f->eta = (float)d->eta, f->mua = (float)d->mua, f->mus = (float)d->mus, f->mut = (float)d->mut;
        f->thickness = (float)d->thickness, f->tau_above = (float)d->tau_above, f->tau_below = (float)d->tau_below;
        for (int i = 0; i < 4; i++) f->pp[i] = (float)d->pp[i];
        f->phase_kind = d->phase_kind;
    }
    for (int l = 0; l < n_layers; l++) {
        memset(&lf[l], 0, sizeof lf[l]);
        lf[l].kind = ld[l].kind, lf[l].iter_count = ld[l].iter_count;
        lf[l].multiple_scattering = ld[l].multiple_scattering;
        for (int i = 0; i < 8; i++) lf[l].p[i] = (float)ld[l].p[i];
    }
}

/* Device buffers of one simulation. */
typedef struct sim_buffers {
    cl_mem scene, media, layers, wo, wi, tab, nee, scalars, hist, flags;
} sim_buffers;

static void buffers_release(sim_buffers *b)
{
    cl_mem *all[] = {&b->scene, &b->media, &b->layers, &b->wo, &b->wi, &b->tab,
                     &b->nee, &b->scalars, &b->hist, &b->flags};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++)
        if (*all[i]) clReleaseMemObject(*all[i]);
}

static cl_mem make_buffer(lsqt_context *cx, cl_mem_flags fl, size_t size, void *host, cl_int *e)
{
    if (*e != CL_SUCCESS) return NULL;
    return clCreateBuffer(cx->ctx, fl | (host ? CL_MEM_COPY_HOST_PTR : 0), size, host, e);
}

static int build_options(lsqt_context *cx, const lsqt_assembly *a, const lsqt_state *st,
                         char *opt, size_t cap, char *err, size_t errcap)
{
    size_t n = lsqt_assembly_build_options(a, opt, cap);
    if (n >= cap) {
        snprintf(err, errcap, "kernel build options too long");
        return 1;
    }
    n += (size_t)snprintf(opt + n, cap - n, " -cl-std=CL1.2 -DLSQT_NWI=%d", st->n_wi);
    if (lsqt_device_check(&cx->dev, st->use_double, err, errcap)) return 1;
    if (st->use_double) n += (size_t)snprintf(opt + n, cap - n, " -DLSQT_DOUBLE=1");
    if (!cx->dev.has_int64_atomics) snprintf(opt + n, cap - n, " -DLSQT_NO_INT64_ATOMICS=1");
    return 0;
}

static void progress_draw(uint64_t done, uint64_t total, double elapsed, int n_slices)
{
    double frac = total ? (double)done / (double)total : 1.0;
    double rate = elapsed > 0 ? (double)done * n_slices / elapsed : 0.0;
    double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
    char bar[31];
    int fill = (int)(frac * 30.0);
    for (int i = 0; i < 30; i++) bar[i] = i < fill ? '#' : '.';
    bar[30] = '\0';
    fprintf(stderr, "\r[%s] %5.1f%%  %.3g paths/s  ETA %.0f s   ", bar, 100.0 * frac, rate, eta);
    fflush(stderr);
}

int lsqt_simulate(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t add_paths,
                  const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap)
{
    memset(stats, 0, sizeof *stats);
    int line = 0;
    const char *model = lsqt_unsupported_model(a, &line);
    if (model) {
        snprintf(err, errcap, "line %d: the model %s is not implemented in the kernels yet", line, model);
        return 1;
    }
    char opt[1024];
    if (build_options(cx, a, st, opt, sizeof opt, err, errcap)) return 1;
    if (o->extra_options && strlen(opt) + strlen(o->extra_options) + 2 < sizeof opt) {
        strcat(opt, " ");
        strcat(opt, o->extra_options);
    }
    if (o->verbose) fprintf(stderr, "kernel build options: %s\n", opt);
    char *log = NULL;
    cl_program prog = lsqt_program_build(cx, opt, &log, err, errcap);
    if (!prog) {
        if (log) fprintf(stderr, "OpenCL build log:\n%s\n", log);
        free(log);
        return 1;
    }
    cl_int e = CL_SUCCESS, e2 = CL_SUCCESS;
    cl_kernel k = clCreateKernel(prog, "lsqt_walk", &e);
    cl_kernel kp = clCreateKernel(prog, "lsqt_prepare", &e2);
    if (e != CL_SUCCESS || e2 != CL_SUCCESS) {
        if (e == CL_SUCCESS) e = e2;
        snprintf(err, errcap, "clCreateKernel: %s (%d)", lsqt_cl_error_name(e), (int)e);
        if (k) clReleaseKernel(k);
        if (kp) clReleaseKernel(kp);
        clReleaseProgram(prog);
        return 1;
    }

    /* Tables and tallies (the state's tallies go up, so a run continues where it was). */
    const int n = a->n_layers;
    lsqt_dev_scene scene;
    lsqt_dev_medium_d *media = calloc((size_t)n + 1, sizeof *media);
    lsqt_dev_layer_d *layers = calloc((size_t)n, sizeof *layers);
    lsqt_dev_medium *media_f = calloc((size_t)n + 1, sizeof *media_f);
    lsqt_dev_layer *layers_f = calloc((size_t)n, sizeof *layers_f);
    /* Directions go to the device in the kernel's precision: double for --double. */
    const size_t pad = LSQT_PAD4((size_t)st->n_wi), n_wo = (size_t)st->n_slices * 4, n_wi = (size_t)st->n_slices * 3 * pad;
    double *wo = calloc(n_wo, sizeof *wo), *wi = calloc(n_wi, sizeof *wi);
    float *wo_f = calloc(n_wo, sizeof *wo_f), *wi_f = calloc(n_wi, sizeof *wi_f);
    sim_buffers b;
    memset(&b, 0, sizeof b);
    int rc = 1;
    if (!media || !layers || !media_f || !layers_f || !wo || !wi || !wo_f || !wi_f) {
        snprintf(err, errcap, "out of memory");
        goto done;
    }
    lsqt_device_tables(a, &scene, media, layers);
    tables_to_float(media, media_f, n + 1, layers, layers_f, n);
    /* The kernel reads the layout it was built for (see device_layout.h). */
    const void *media_up = st->use_double ? (const void *)media : (const void *)media_f;
    const void *layers_up = st->use_double ? (const void *)layers : (const void *)layers_f;
    const size_t media_size = st->use_double ? sizeof *media : sizeof *media_f;
    const size_t layer_size = st->use_double ? sizeof *layers : sizeof *layers_f;
    scene.n_wi = st->n_wi;
    scene.seed_lo = (lsqt_u32)st->seed;
    scene.seed_hi = (lsqt_u32)(st->seed >> 32);
    for (int s = 0; s < st->n_slices; s++) {
        wo[4 * s] = sin(st->theta_o[s]);
        wo[4 * s + 2] = cos(st->theta_o[s]);
        /* Incident directions as coordinate arrays, zero-padded to fours. The state holds
         * them in float; in double they are normalised again (float leaves |wi| - 1 at
         * 1e-7), in float they go as they are. */
        for (size_t i = 0; i < (size_t)st->n_wi; i++) {
            const float *d = st->wi + ((size_t)s * (size_t)st->n_wi + i) * 4;
            double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
            for (size_t j = 0; j < 3; j++) {
                wi[((size_t)s * 3 + j) * pad + i] = st->use_double && len > 0 ? d[j] / len : d[j];
                wi_f[((size_t)s * 3 + j) * pad + i] = d[j];
            }
        }
    }
    for (size_t i = 0; i < n_wo; i++) wo_f[i] = (float)wo[i];
    const size_t dir_size = st->use_double ? sizeof(double) : sizeof(float);
    void *wo_up = st->use_double ? (void *)wo : (void *)wo_f, *wi_up = st->use_double ? (void *)wi : (void *)wi_f;
    cl_mem_flags ro = CL_MEM_READ_ONLY, rw = CL_MEM_READ_WRITE;
    cl_uint flags0 = 0;
    b.scene = make_buffer(cx, ro, sizeof scene, &scene, &e);
    b.media = make_buffer(cx, ro, ((size_t)n + 1) * media_size, (void *)media_up, &e);
    b.layers = make_buffer(cx, ro, (size_t)n * layer_size, (void *)layers_up, &e);
    b.wo = make_buffer(cx, ro, n_wo * dir_size, wo_up, &e);
    b.wi = make_buffer(cx, ro, n_wi * dir_size, wi_up, &e);
    /* per slice and layer: T, Lambda, lgamma(1 + Lambda) of every direction */
    const size_t tab_size = (size_t)st->n_slices * (size_t)n * 3 * pad * (st->use_double ? sizeof(double) : sizeof(float));
    b.tab = make_buffer(cx, rw, tab_size, NULL, &e);
    b.nee = make_buffer(cx, rw, lsqt_state_nee_count(st) * sizeof *st->nee, st->nee, &e);
    b.scalars = make_buffer(cx, rw, lsqt_state_scalar_count(st) * sizeof *st->scalars, st->scalars, &e);
    b.hist = make_buffer(cx, rw, lsqt_state_hist_count(st) * sizeof *st->hist, st->hist, &e);
    b.flags = make_buffer(cx, rw, sizeof flags0, &flags0, &e);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot allocate device buffers: %s (%d)", lsqt_cl_error_name(e), (int)e);
        goto done;
    }
    cl_mem *args[] = {&b.scene, &b.media, &b.layers, &b.wo, &b.wi, &b.tab};
    for (cl_uint i = 0; i < 6; i++) e |= clSetKernelArg(k, i, sizeof(cl_mem), args[i]);
    e |= clSetKernelArg(k, 9, sizeof(cl_mem), &b.nee);
    e |= clSetKernelArg(k, 10, sizeof(cl_mem), &b.scalars);
    e |= clSetKernelArg(k, 11, sizeof(cl_mem), &b.hist);
    e |= clSetKernelArg(k, 12, sizeof(cl_mem), &b.flags);
    /* The direction tables, once for the whole run. */
    cl_mem *pargs[] = {&b.scene, &b.media, &b.layers, &b.wi, &b.tab};
    for (cl_uint i = 0; i < 5; i++) e |= clSetKernelArg(kp, i, sizeof(cl_mem), pargs[i]);
    if (e == CL_SUCCESS) {
        size_t pglobal[2] = {pad, (size_t)st->n_slices};
        e = clEnqueueNDRangeKernel(cx->queue, kp, 2, NULL, pglobal, NULL, 0, NULL, NULL);
    }

    size_t ls = o->local_size ? o->local_size : 64, kmax = 0;
    clGetKernelWorkGroupInfo(k, cx->dev.id, CL_KERNEL_WORK_GROUP_SIZE, sizeof kmax, &kmax, NULL);
    if (kmax && ls > kmax) ls = kmax;

    /* Launches cover whole chunks; their size adapts so each takes about 0.3 s, which
     * keeps the progress bar and Ctrl-C responsive without starving the device. */
    const uint64_t first = st->paths, target = st->paths + add_paths;
    uint64_t pos = first, chunks_per_launch = 8;
    const double t0 = lsqt_now();
    int launches = 0;
    if (o->verbose)
        fprintf(stderr, "simulating %llu paths per slice x %d slices (work-group size %zu)\n",
                (unsigned long long)add_paths, st->n_slices, ls);
    while (pos < target && e == CL_SUCCESS) {
        cl_ulong chunk0 = pos / LSQT_CHUNK;
        cl_ulong end = (chunk0 + chunks_per_launch) * LSQT_CHUNK;
        if (end > target) end = target;
        cl_ulong nchunks = (end - 1) / LSQT_CHUNK - chunk0 + 1, begin = pos;
        e |= clSetKernelArg(k, 6, sizeof begin, &begin);
        e |= clSetKernelArg(k, 7, sizeof end, &end);
        e |= clSetKernelArg(k, 8, sizeof chunk0, &chunk0);
        size_t global[2] = {(size_t)nchunks * ls, (size_t)st->n_slices}, local[2] = {ls, 1};
        double t = lsqt_now();
        if (e == CL_SUCCESS) e = clEnqueueNDRangeKernel(cx->queue, k, 2, NULL, global, local, 0, NULL, NULL);
        if (e == CL_SUCCESS) e = clFinish(cx->queue);
        if (e != CL_SUCCESS) break;
        double dt = lsqt_now() - t;
        pos = end;
        launches++;
        double grow = dt > 0 ? 0.3 / dt : 4.0;
        grow = grow > 4.0 ? 4.0 : grow < 0.5 ? 0.5 : grow;
        chunks_per_launch = (uint64_t)((double)chunks_per_launch * grow);
        if (chunks_per_launch < 1) chunks_per_launch = 1;
        if (o->progress) progress_draw(pos - first, add_paths, lsqt_now() - t0, st->n_slices);
        if ((o->stop && *o->stop) || (o->time_limit > 0 && lsqt_now() - t0 >= o->time_limit)) {
            stats->interrupted = 1;
            break;
        }
    }
    if (o->progress) fprintf(stderr, "\n");
    if (o->verbose) fprintf(stderr, "%d launches in %.3g s\n", launches, lsqt_now() - t0);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "kernel launch failed: %s (%d)", lsqt_cl_error_name(e), (int)e);
        goto done;
    }
    e |= clEnqueueReadBuffer(cx->queue, b.nee, CL_TRUE, 0, lsqt_state_nee_count(st) * sizeof *st->nee, st->nee, 0, NULL, NULL);
    e |= clEnqueueReadBuffer(cx->queue, b.scalars, CL_TRUE, 0, lsqt_state_scalar_count(st) * sizeof *st->scalars, st->scalars, 0, NULL, NULL);
    e |= clEnqueueReadBuffer(cx->queue, b.hist, CL_TRUE, 0, lsqt_state_hist_count(st) * sizeof *st->hist, st->hist, 0, NULL, NULL);
    e |= clEnqueueReadBuffer(cx->queue, b.flags, CL_TRUE, 0, sizeof flags0, &flags0, 0, NULL, NULL);
    if (e != CL_SUCCESS) {
        snprintf(err, errcap, "cannot read the tallies back: %s (%d)", lsqt_cl_error_name(e), (int)e);
        goto done;
    }
    stats->paths_added = pos - first;
    stats->seconds = lsqt_now() - t0;
    st->paths = pos;
    st->flags |= flags0;
    if (lsqt_tally_flags_error(flags0, err, errcap)) goto done;
    rc = 0;
done:
    buffers_release(&b);
    free(media);
    free(layers);
    free(media_f);
    free(layers_f);
    free(wo);
    free(wi);
    free(wo_f);
    free(wi_f);
    clReleaseKernel(k);
    clReleaseKernel(kp);
    clReleaseProgram(prog);
    return rc;
}
