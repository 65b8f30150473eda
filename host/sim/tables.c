/* Device tables: an assembly as the kernels read it (layouts in device_layout.h). */
#include "lsqt/tables.h"

#include <string.h>

/* Models the kernels can run: every model of include/lsqt/model_list.h (the parser knows
 * no other, but a hand-made assembly might hold any number). */
static int bsdf_supported(const lsqt_layer *l)
{
#define KNOWN(ID, ...) || l->kind == LSQT_BSDF_##ID
    return l->kind == LSQT_BSDF_NULL LSQT_BSDFS(KNOWN);
#undef KNOWN
}
static int phase_supported(int kind)
{
#define KNOWN(ID, ...) || kind == LSQT_PHASE_##ID
    return kind == LSQT_PHASE_NONE LSQT_PHASES(KNOWN);
#undef KNOWN
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

/* A phase model's parameters as the kernels read them (kernels/phase_*.cl): the packing
 * of include/lsqt/model_list.h. */
static void phase_params(const lsqt_phase *p, double pp[4])
{
    const double *v = p->v;
#define PACK(ID, ...) \
    if (p->kind == LSQT_PHASE_##ID) LSQT_PACK_##ID(v, pp)
    LSQT_PHASES(PACK)
#undef PACK
}

/* The walk (kernels/microsurface.cl ms_alpha) reads a microsurface's roughness at p[0]:
 * the model list's ALPHA column must say so of every walk. */
#define ALPHA_AT_0(ID, num, name, alias, prefix, sampler, mirror, transmits, bands, b0, b1, alpha) \
    LSQT_IF_WALK_##sampler(_Static_assert(alpha == 0, "the walk reads " #ID "'s alpha at p[0]");)
LSQT_BSDFS(ALPHA_AT_0)
#undef ALPHA_AT_0

/* A layer's parameters as the kernels read them (kernels/bsdf_*.cl), from the layer and
 * the media on each side of it. */
static void layer_params(const lsqt_layer *l, const lsqt_medium *up, const lsqt_medium *down, double p[8])
{
    const double *v = l->v;
#define PACK(ID, ...) \
    if (l->kind == LSQT_BSDF_##ID) LSQT_PACK_##ID(v, up, down, p)
    LSQT_BSDFS(PACK)
#undef PACK
    (void)up, (void)down;
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
        layer_params(l, &a->media[i], &a->media[i + 1], layers[i].p);
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
        const int t = src->phase.table;
        if (t >= 1 && t <= a->n_phase_tables) { /* where its table is (model_list.h) */
            size_t off = 0;
            for (int u = 0; u < t - 1; u++) off += LSQT_PHASE_TABLE_REALS(a->phase_tables[u].n);
            d->pp[0] = n + 1 - m, d->pp[1] = (double)off, d->pp[2] = a->phase_tables[t - 1].n;
        }
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

size_t lsqt_device_phase_tables(const lsqt_assembly *a, double *out)
{
    size_t k = 0;
    for (int t = 0; t < a->n_phase_tables; t++) {
        const lsqt_phase_table *p = &a->phase_tables[t];
        if (out) {
            const size_t n = (size_t)p->n;
            memcpy(out + k, p->mu, n * sizeof *out);
            memcpy(out + k + n, p->p, n * sizeof *out);
            memcpy(out + k + 2 * n, p->cdf, n * sizeof *out);
            /* the index: per cell j of n equal cells in mu, the row interval holding its
             * lower edge -1 + 2 j / n (j = n: the last interval) */
            int i = 0;
            for (size_t j = 0; j <= n; j++) {
                const double x = -1.0 + 2.0 * (double)j / (double)n;
                while (i + 2 < p->n && p->mu[i + 1] <= x) i++;
                out[k + 3 * n + j] = i;
            }
        }
        k += LSQT_PHASE_TABLE_REALS(p->n);
    }
    return k;
}

void lsqt_tables_to_float(const lsqt_dev_medium_d *md, lsqt_dev_medium *mf, int n_media,
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
