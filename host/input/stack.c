/* The parsed stack itself: freeing it, and whether light can cross a layer or the whole
 * stack (the parser prunes with it; the runs decide on transmission with it). */
#include "lsqt/assembly.h"

#include <stdlib.h>
#include <string.h>

void lsqt_assembly_free(lsqt_assembly *a)
{
    if (!a)
        return;
    for (int b = 0; a->band && b < a->n_bands; b++)
        lsqt_assembly_free(&a->band[b]);
    free(a->band);
    free(a->wavelengths);
    for (int i = 0; i < a->n_tables; i++)
        free(a->tables[i]);
    free(a->tables);
    for (int i = 0; i < a->n_phase_tables; i++)
        lsqt_phase_table_free(&a->phase_tables[i]);
    free(a->phase_tables);
    free(a->layers);
    free(a->media);
    memset(a, 0, sizeof *a);
}

int lsqt_phase_tables_copy(const lsqt_assembly *from, lsqt_assembly *to)
{
    to->n_phase_tables = 0;
    to->phase_tables = from->n_phase_tables ? calloc((size_t)from->n_phase_tables, sizeof *to->phase_tables) : NULL;
    if (from->n_phase_tables && !to->phase_tables) return 2;
    for (int t = 0; t < from->n_phase_tables; t++) {
        const lsqt_phase_table *f = &from->phase_tables[t];
        lsqt_phase_table *c = &to->phase_tables[t];
        const size_t bytes = (size_t)f->n * sizeof(double);
        c->n = f->n, c->hash = f->hash;
        c->mu = malloc(bytes), c->p = malloc(bytes), c->cdf = malloc(bytes);
        c->path = f->path ? strdup(f->path) : NULL;
        to->n_phase_tables = t + 1; /* freed with it whatever happens */
        if (!c->mu || !c->p || !c->cdf || (f->path && !c->path)) return 2;
        memcpy(c->mu, f->mu, bytes), memcpy(c->p, f->p, bytes), memcpy(c->cdf, f->cdf, bytes);
    }
    return 0;
}

int lsqt_assembly_join(lsqt_assembly *each, int n, const double *wl, lsqt_assembly *out)
{
    memset(out, 0, sizeof *out);
    const int nl = each[0].n_layers;
    out->band = malloc((size_t)n * sizeof *out->band);
    out->wavelengths = wl ? malloc((size_t)n * sizeof *wl) : NULL;
    out->layers = malloc((size_t)nl * sizeof *out->layers);
    out->media = malloc(((size_t)nl + 1) * sizeof *out->media);
    if (!out->band || (wl && !out->wavelengths) || !out->layers || !out->media) {
        free(out->band), free(out->wavelengths), free(out->layers), free(out->media);
        memset(out, 0, sizeof *out);
        return 2;
    }
    memcpy(out->layers, each[0].layers, (size_t)nl * sizeof *out->layers);
    memcpy(out->media, each[0].media, ((size_t)nl + 1) * sizeof *out->media);
    out->n_layers = nl;
    out->n_pruned_layers = each[0].n_pruned_layers;
    memcpy(out->band, each, (size_t)n * sizeof *each);
    if (wl)
        memcpy(out->wavelengths, wl, (size_t)n * sizeof *wl);
    out->n_bands = n;
    return 0;
}

int lsqt_assembly_bands(const lsqt_assembly *a) { return a->n_bands > 1 ? a->n_bands : 1; }

const lsqt_assembly *lsqt_assembly_band(const lsqt_assembly *a, int b)
{
    return a->n_bands > 1 ? &a->band[b] : a;
}

int lsqt_layer_transmits(const lsqt_layer *l)
{
#define TRANSMITS(ID, num, name, alias, prefix, sampler, mirror, transmits, ...) \
    if (l->kind == LSQT_BSDF_##ID)                                          \
        return LSQT_TRANSMITS_##transmits(ID, l->v);
    LSQT_BSDFS(TRANSMITS)
#undef TRANSMITS
    return 1; /* NullBsdf */
}

int lsqt_assembly_transmits(const lsqt_assembly *a)
{
    if (a->n_bands > 1) {
        for (int b = 0; b < a->n_bands; b++)
            if (lsqt_assembly_transmits(&a->band[b]))
                return 1;
        return 0;
    }
    for (int i = 0; i < a->n_layers; i++)
        if (!lsqt_layer_transmits(&a->layers[i]))
            return 0;
    return a->n_layers > 0;
}
