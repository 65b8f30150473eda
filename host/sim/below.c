/* Two-sided BSDFs (below.h): the mirrored assembly and states of one side each (a session
 * runs the two sides as lanes: session.c). */
#include "lsqt/below.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/tally.h"
#include "lsqt/util.h"

/* A model's mirror image is itself when it treats light from either side alike: the
 * model list's MIRROR column (include/lsqt/model_list.h says why for each). A model that
 * never transmits is never met from above by light from below: no mirror is needed. */
static int layer_self_mirror(int kind)
{
#define MIRRORS(ID, num, name, alias, prefix, sampler, mirror, ...) || (kind == LSQT_BSDF_##ID && mirror)
    return kind == LSQT_BSDF_NULL LSQT_BSDFS(MIRRORS);
#undef MIRRORS
}

static int phase_self_mirror(int kind)
{
#define MIRRORS(ID, num, name, alias, prefix, sampler, mirror) || (kind == LSQT_PHASE_##ID && mirror)
    return kind == LSQT_PHASE_NONE LSQT_PHASES(MIRRORS);
#undef MIRRORS
}

/* A's stack upside down, without checks. Returns 0, or 2 out of memory. */
static int mirror_one(const lsqt_assembly *a, lsqt_assembly *out)
{
    memset(out, 0, sizeof *out);
    const int n = a->n_layers;
    out->layers = calloc((size_t)(n > 0 ? n : 1), sizeof *out->layers);
    out->media = calloc((size_t)n + 1, sizeof *out->media);
    if (!out->layers || !out->media) {
        lsqt_assembly_free(out);
        return 2;
    }
    out->n_layers = n;
    out->n_pruned_layers = a->n_pruned_layers;
    for (int i = 0; i < n; i++) {
        out->layers[i] = a->layers[n - 1 - i];
        out->layers[i].z = 0.0 - a->layers[n - 1 - i].z; /* 0.0 - 0.0 is +0: no "-0" in the text */
    }
    for (int m = 0; m <= n; m++) out->media[m] = a->media[n - m];
    if (lsqt_phase_tables_copy(a, out)) { /* the media's tables (their numbers stay) */
        lsqt_assembly_free(out);
        return 2;
    }
    return 0;
}

/* Layer i lets light through in some band. */
static int layer_transmits_any(const lsqt_assembly *a, int i)
{
    for (int b = 0; b < lsqt_assembly_bands(a); b++)
        if (lsqt_layer_transmits(&lsqt_assembly_band(a, b)->layers[i])) return 1;
    return 0;
}

int lsqt_assembly_mirror(const lsqt_assembly *a, lsqt_assembly *out, char *err, size_t errcap)
{
    memset(out, 0, sizeof *out);
    const int n = a->n_layers;
    for (int i = 0; i < n; i++)
        if (!layer_transmits_any(a, i)) {
            snprintf(err, errcap, "line %d: %s transmits nothing, so light from below never reaches what lies "
                                  "above it", a->layers[i].line, lsqt_bsdf_name(a->layers[i].kind));
            return 2;
        }
    for (int i = 0; i < n; i++)
        if (!layer_self_mirror(a->layers[i].kind)) {
            snprintf(err, errcap, "line %d: %s has no mirror image (light from below) that lsqt-cl can express",
                     a->layers[i].line, lsqt_bsdf_name(a->layers[i].kind));
            return 2;
        }
    /* a phase model is kept only where the medium scatters (in some band) */
    for (int m = 0; m <= n; m++)
        if (!phase_self_mirror(a->media[m].phase.kind)) {
            snprintf(err, errcap, "line %d: %s has no mirror image (light from below) that lsqt-cl can express",
                     a->media[m].line, lsqt_phase_name(a->media[m].phase.kind));
            return 2;
        }
    const int nb = a->n_bands > 1 ? a->n_bands : 0;
    lsqt_assembly *each = nb ? calloc((size_t)nb, sizeof *each) : NULL;
    int rc = nb && !each ? 2 : 0;
    for (int b = 0; b < nb && !rc; b++) rc = mirror_one(&a->band[b], &each[b]);
    if (!rc) rc = nb ? lsqt_assembly_join(each, nb, a->wavelengths, out) : mirror_one(a, out);
    if (rc) {
        for (int b = 0; each && b < nb; b++) lsqt_assembly_free(&each[b]);
        snprintf(err, errcap, "out of memory");
    }
    free(each);
    return rc;
}

int lsqt_state_below_count(const lsqt_state *st)
{
    int k = 0;
    for (int s = 0; s < st->n_slices; s++) k += (st->slice_flags[s] & LSQT_SLICE_BELOW) != 0;
    return k;
}

/* OUT: N slices (zero), every setting and the ranges of ST. */
static int init_like(lsqt_state *out, const lsqt_state *st, int n)
{
    if (lsqt_state_init(out, st->canonical, st->hash, st->seed, n, st->n_wi, st->transmits, st->n_bands,
                              st->wavelengths))
        return -1;
    if (st->hist_pk && lsqt_state_pack_hist(out, 1)) { /* as ST holds them */
        lsqt_state_free(out);
        return -1;
    }
    out->use_double = st->use_double;
    out->span_end = st->span_end;
    out->stage = st->stage;
    out->flags = st->flags;
    out->dir_method = st->dir_method;
    out->grid_ni = st->grid_ni, out->grid_nphi = st->grid_nphi;
    out->rx = st->rx;
    out->pilot_paths = st->pilot_paths;
    if (lsqt_state_set_ranges(out, st->ranges, st->n_ranges)) {
        lsqt_state_free(out);
        return -1;
    }
    return 0;
}

/* Slice ss of SRC (direction, flags, tallies) as slice ds of DST (same n_wi). Returns 0
 * or -1 (out of memory). */
static int copy_slice(lsqt_state *dst, int ds, const lsqt_state *src, int ss)
{
    const size_t nw = (size_t)src->n_wi;
    dst->theta_o[ds] = src->theta_o[ss];
    dst->slice_flags[ds] = src->slice_flags[ss];
    memcpy(dst->wi + (size_t)ds * nw * 4, src->wi + (size_t)ss * nw * 4, nw * 4 * sizeof *src->wi);
    return lsqt_state_copy_slice_tallies(dst, ds, src, ss);
}

int lsqt_state_split_by_side(const lsqt_state *st, lsqt_state *above, lsqt_state *below)
{
    const int nb = lsqt_state_below_count(st), na = st->n_slices - nb;
    if (init_like(above, st, na)) return -1;
    if (init_like(below, st, nb)) {
        lsqt_state_free(above);
        return -1;
    }
    int ia = 0, ib = 0, rc = 0;
    for (int s = 0; s < st->n_slices && !rc; s++) {
        if (st->slice_flags[s] & LSQT_SLICE_BELOW) rc = copy_slice(below, ib++, st, s);
        else rc = copy_slice(above, ia++, st, s);
    }
    if (rc) {
        lsqt_state_free(above);
        lsqt_state_free(below);
    }
    return rc;
}

int lsqt_state_join_by_side(const lsqt_state *above, const lsqt_state *below, lsqt_state *out, char *err,
                          size_t errcap)
{
    const char *diff = NULL;
    if (above->hash != below->hash || strcmp(above->canonical, below->canonical) != 0) diff = "assembly";
    else if (above->seed != below->seed) diff = "seed";
    else if (above->n_wi != below->n_wi || above->transmits != below->transmits) diff = "direction count";
    else if (above->use_double != below->use_double) diff = "precision";
    else if (above->n_ranges != below->n_ranges ||
             (above->n_ranges &&
              memcmp(above->ranges, below->ranges, (size_t)above->n_ranges * 2 * sizeof *above->ranges) != 0) ||
             above->span_end != below->span_end || above->stage != below->stage)
        diff = "paths";
    else if (above->dir_method != below->dir_method || above->rx != below->rx ||
             above->pilot_paths != below->pilot_paths || above->grid_ni != below->grid_ni ||
             above->grid_nphi != below->grid_nphi)
        diff = "direction method";
    if (diff) {
        snprintf(err, errcap, "the sides from above and from below differ in their %s", diff);
        return 1;
    }
    if (init_like(out, above, above->n_slices + below->n_slices)) {
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    out->flags |= below->flags;
    int rc = 0;
    for (int s = 0; s < above->n_slices && !rc; s++) rc = copy_slice(out, s, above, s);
    for (int s = 0; s < below->n_slices && !rc; s++) rc = copy_slice(out, above->n_slices + s, below, s);
    if (rc) {
        lsqt_state_free(out);
        snprintf(err, errcap, "out of memory");
    }
    return rc;
}

int lsqt_state_add_below(lsqt_state *st)
{
    lsqt_state dn, both;
    char err[128];
    if (init_like(&dn, st, st->n_slices)) return -1;
    for (int s = 0; s < st->n_slices; s++) {
        if (copy_slice(&dn, s, st, s)) {
            lsqt_state_free(&dn);
            return -1;
        }
        dn.slice_flags[s] |= LSQT_SLICE_BELOW;
    }
    int rc = lsqt_state_join_by_side(st, &dn, &both, err, sizeof err);
    lsqt_state_free(&dn);
    if (rc) return -1;
    lsqt_state_free(st);
    *st = both;
    return 0;
}

void lsqt_below_raw_name(const char *raw, char *dst, size_t cap)
{
    size_t n = strlen(raw);
    if (n >= 4 && strcmp(raw + n - 4, ".raw") == 0) n -= 4;
    snprintf(dst, cap, "%.*s.below.raw", (int)n, raw);
}
