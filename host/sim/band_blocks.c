/* Band blocks: the bands that share their paths, and a block's device tables
 * (include/lsqt/band_blocks.h; the kernels' side is kernels/bands.cl). */
#include "lsqt/band_blocks.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/tables.h"

/* One band's device tables (double), n_layers + 1 media and n_layers layers. */
typedef struct {
    lsqt_dev_scene scene;
    lsqt_dev_medium_d *media;
    lsqt_dev_layer_d *layers;
} band_tables;

static int tables_of(const lsqt_assembly *a, int b, band_tables *t)
{
    const lsqt_assembly *x = lsqt_assembly_band(a, b);
    t->media = calloc((size_t)x->n_layers + 1, sizeof *t->media);
    t->layers = calloc((size_t)x->n_layers + 1, sizeof *t->layers);
    if (!t->media || !t->layers) {
        free(t->media), free(t->layers);
        return 1;
    }
    lsqt_device_tables(x, &t->scene, t->media, t->layers);
    return 0;
}

static void tables_free(band_tables *t) { free(t->media), free(t->layers); }

/* How the bands of a block may differ at a layer: the model list's BANDS, B0, B1 columns
 * (include/lsqt/model_list.h); SAME for a model not in the list (NullBsdf). */
enum { BANDS_SAME, BANDS_FACTORS, BANDS_INDEX };
typedef struct {
    int kind, mode, b0, b1;
} band_rule;

static band_rule rule_of(int kind)
{
#define RULE(ID, num, name, alias, prefix, sampler, mirror, transmits, bands, b0, b1, alpha) \
    {LSQT_BSDF_##ID, BANDS_##bands, b0, b1},
    static const band_rule rules[] = {LSQT_BSDFS(RULE)};
#undef RULE
    for (size_t i = 0; i < sizeof rules / sizeof rules[0]; i++)
        if (rules[i].kind == kind) return rules[i];
    band_rule same = {kind, BANDS_SAME, -1, -1};
    return same;
}

/* A layer's factors fs and fo (FACTORS: its value is fs or fo times a unit model the bands
 * share); 1 and 1 where the bands' models are the same, 0 for NullBsdf. */
static void layer_factors(const lsqt_dev_layer_d *l, double *fs, double *fo)
{
    const band_rule r = rule_of(l->kind);
    if (r.mode == BANDS_FACTORS) *fs = l->p[r.b0], *fo = r.b1 >= 0 ? l->p[r.b1] : 0.0;
    else if (l->kind == LSQT_BSDF_NULL) *fs = *fo = 0.0;
    else *fs = *fo = 1.0;
}

/* A layer of INDEX under another layer that is not null (microsurface.cl ms_bands): light
 * leaves it only through that layer, so its index weighs its walk and no next-event term;
 * the index may differ between the bands. */
static int hidden_index(const band_tables *t, int i)
{
    return rule_of(t->layers[i].kind).mode == BANDS_INDEX && t->scene.top_nonnull != i;
}

/* Whether the bands of a block may have different phase functions of this kind: one
 * whose sampler draws its own density exactly (EXACT), so that a band's density of the
 * hero's sample is its phase function's value (bands.cl band_phase_sample); a VERTEX
 * sampler's density (SGGX's) has no closed form. */
static int phase_mixes(int kind)
{
#define X(ID, num, name, alias, p, sampler, mirror) \
    LSQT_IF_EXACT_##sampler(if (kind == LSQT_PHASE_##ID) return 1;)
    LSQT_PHASES(X)
#undef X
    return 0;
}

static int tables_share(const band_tables *x, const band_tables *y, int n)
{
    if (x->scene.top_nonnull != y->scene.top_nonnull) return 0;
    for (int i = 0; i < n; i++) {
        const lsqt_dev_layer_d *p = &x->layers[i], *q = &y->layers[i];
        if (p->kind != q->kind || p->iter_count != q->iter_count || p->multiple_scattering != q->multiple_scattering)
            return 0;
        const band_rule r = rule_of(p->kind);
        const int free_slots = r.mode == BANDS_FACTORS || (r.mode == BANDS_INDEX && hidden_index(x, i));
        for (int k = 0; k < 8; k++)
            if (!(free_slots && (k == r.b0 || k == r.b1)) && p->p[k] != q->p[k]) return 0;
    }
    for (int m = 0; m <= n; m++) {
        const lsqt_dev_medium_d *p = &x->media[m], *q = &y->media[m];
        /* the medium under an INDEX layer is its index (compared there) */
        const int metal = m == n && n > 0 && p->mus == 0 && rule_of(x->layers[n - 1].kind).mode == BANDS_INDEX;
        if ((!metal && p->eta != q->eta) || p->thickness != q->thickness) return 0;
        /* a phase function matters only where both bands scatter, and its parameters
         * only where its sampler is not exact */
        if (p->mus > 0 && q->mus > 0 &&
            (p->phase_kind != q->phase_kind ||
             (memcmp(p->pp, q->pp, sizeof p->pp) && !phase_mixes(p->phase_kind))))
            return 0;
    }
    return 1;
}

/* A phase function's mean cosine (the g of HG, its lobes' mean for HG2, Draine's
 * (2003, eq. 6); 0 for the rest: Rayleigh's, and those the bands of a block share). */
static double phase_mean_cosine(const lsqt_dev_medium_d *m)
{
    const double *p = m->pp;
    if (m->phase_kind == LSQT_PHASE_HG) return p[0];
    if (m->phase_kind == LSQT_PHASE_HG2) return (1.0 - p[2]) * p[0] + p[2] * p[1];
    if (m->phase_kind == LSQT_PHASE_DRAINE)
        return p[0] * (1.0 + p[1] * (3.0 + 2.0 * p[0] * p[0]) / 5.0) / (1.0 + p[1] * (1.0 + 2.0 * p[0] * p[0]) / 3.0);
    return 0.0;
}

static double hg(double g, double mu) { return (1.0 - g * g) / (2.0 * pow(1.0 + g * g - 2.0 * g * mu, 1.5)); }

/* KL(HG_g || HG_h) over cos t (midpoint rule, 256 cells: ample for |g| <= 0.95; g is held
 * there, as sharper lobes only make the bands more different). */
static double hg_divergence(double g, double h)
{
    if (g == h) return 0.0;
    g = fmax(-0.95, fmin(0.95, g)), h = fmax(-0.95, fmin(0.95, h));
    double kl = 0.0;
    for (int i = 0; i < 256; i++) {
        const double mu = -1.0 + (i + 0.5) / 128.0, p = hg(g, mu);
        kl += p * log(p / hg(h, mu)) / 128.0;
    }
    return fmax(kl, 0.0);
}

/* Medium m's expected collisions on a path: tau_s (1 + tau'), its scattering depth times
 * one plus its reduced depth (a diffusing path in a thick medium meets ~tau' reduced
 * mean free paths), at most a / (1 - a), the mean before absorption ends it. */
static double collisions(const lsqt_dev_medium_d *m)
{
    if (!(m->mut > 0.0)) return 0.0;
    const double tau = m->mut * m->thickness, a = m->mus / m->mut, g = phase_mean_cosine(m);
    const double n = a * tau * (1.0 + tau * (1.0 - a * g));
    return a < 1.0 ? fmin(n, a / (1.0 - a)) : n;
}

/* How far apart two sharing bands' paths are: the sum over the interior media of the
 * expected collisions (the larger band's) times the Kullback-Leibler divergence per
 * collision of the flights' and the phase functions' densities; where a band is clear,
 * the other's optical depth. A block's band then has about e^-D of its own paths among
 * another band's (docs/design.md 3.7): where D is small, sharing costs it nothing. */
static double path_divergence(const band_tables *x, const band_tables *y, int n)
{
    double d = 0.0;
    for (int m = 1; m < n; m++) {
        const lsqt_dev_medium_d *p = &x->media[m], *q = &y->media[m];
        if (p->mut == q->mut && p->phase_kind == q->phase_kind && !memcmp(p->pp, q->pp, sizeof p->pp)) continue;
        if (!(p->mut > 0.0) || !(q->mut > 0.0)) {
            d += fmax(p->mut, q->mut) * p->thickness;
            continue;
        }
        const double r = q->mut / p->mut, flight = r - 1.0 - log(r); /* KL of Exp(p) || Exp(q) */
        const double phase = p->mus > 0.0 && q->mus > 0.0 ? hg_divergence(phase_mean_cosine(p), phase_mean_cosine(q)) : 0.0;
        d += fmax(collisions(p), collisions(q)) * (flight + phase);
    }
    return d;
}

/* Whether bands b and c can share, and the divergence of their paths (*d). */
static int pair_of(const lsqt_assembly *a, int b, int c, double *d)
{
    band_tables x, y;
    const int n = lsqt_assembly_band(a, b)->n_layers;
    *d = INFINITY;
    if (n != lsqt_assembly_band(a, c)->n_layers) return 0;
    if (tables_of(a, b, &x)) return 0;
    if (tables_of(a, c, &y)) {
        tables_free(&x);
        return 0;
    }
    const int r = tables_share(&x, &y, n);
    if (r) *d = path_divergence(&x, &y, n);
    tables_free(&x);
    tables_free(&y);
    return r;
}

int lsqt_bands_share(const lsqt_assembly *a, int b, int c)
{
    double d;
    return pair_of(a, b, c, &d);
}

double lsqt_bands_divergence(const lsqt_assembly *a, int b, int c)
{
    double d;
    pair_of(a, b, c, &d);
    return d;
}

int lsqt_band_block_width(char *err, size_t errcap)
{
    const char *env = getenv("LSQT_BAND_BLOCK");
    if (!env || !*env) return LSQT_BAND_BLOCK_MAX;
    char *end = NULL;
    const long w = strtol(env, &end, 10);
    if (*end || w < 1 || w > LSQT_BAND_BLOCK_MAX) {
        snprintf(err, errcap, "LSQT_BAND_BLOCK is '%s': expected 1 to %d", env, LSQT_BAND_BLOCK_MAX);
        return 0;
    }
    return (int)w;
}

double lsqt_band_divergence_max(char *err, size_t errcap)
{
    const char *env = getenv("LSQT_BAND_DIVERGENCE");
    if (!env || !*env) return -1.0;
    char *end = NULL;
    const double d = strtod(env, &end);
    if (*end || !(d >= 0.0)) {
        snprintf(err, errcap, "LSQT_BAND_DIVERGENCE is '%s': expected a number >= 0 or inf", env);
        return -2.0;
    }
    return d;
}

double lsqt_band_divergence_allowed(int k)
{
    if (k <= 1) return INFINITY;
    const double rho = (LSQT_BAND_GAIN_MIN * (1.0 + LSQT_BAND_COST * (k - 1)) - 1.0) / (k - 1);
    return rho <= 0.0 ? INFINITY : rho >= 1.0 ? 0.0 : -log(rho);
}

int lsqt_band_blocks(const lsqt_assembly *a, int width, double max_divergence, lsqt_band_block **out)
{
    const int nb = lsqt_assembly_bands(a), n = a->n_layers;
    if (width < 1) width = 1;
    if (width > LSQT_BAND_BLOCK_MAX) width = LSQT_BAND_BLOCK_MAX;
    int *group = malloc((size_t)nb * sizeof *group), n_groups = 0;
    band_tables *t = calloc((size_t)nb, sizeof *t);
    lsqt_band_block *blocks = calloc((size_t)nb, sizeof *blocks);
    int ok = group && t && blocks, count = 0;
    for (int b = 0; ok && b < nb; b++) ok = !tables_of(a, b, &t[b]);
    /* Groups: a band joins the first group every member of which it shares with and
     * whose paths are within max_divergence of its own (path_divergence; < 0: what the
     * model allows in a block as large as the group would be, or a full one). */
    for (int b = 0; ok && b < nb; b++) {
        group[b] = -1;
        for (int g = 0; g < n_groups && group[b] < 0 && width > 1; g++) {
            int all = 1, size = 1;
            for (int c = 0; c < b; c++) size += group[c] == g;
            const double most = max_divergence >= 0.0 ? max_divergence
                                                      : lsqt_band_divergence_allowed(size < width ? size : width);
            for (int c = 0; c < b && all; c++)
                if (group[c] == g) all = tables_share(&t[b], &t[c], n) && path_divergence(&t[b], &t[c], n) <= most;
            if (all) group[b] = g;
        }
        if (group[b] < 0) group[b] = n_groups++;
    }
    /* Each group in as few blocks as the width allows, evenly filled. */
    for (int g = 0; ok && g < n_groups; g++) {
        int size = 0;
        for (int b = 0; b < nb; b++) size += group[b] == g;
        const int n_blk = (size + width - 1) / width, k = (size + n_blk - 1) / n_blk;
        int slot = k;
        for (int b = 0; b < nb; b++) {
            if (group[b] != g) continue;
            if (slot == k) {
                lsqt_band_block *blk = &blocks[count++];
                blk->nb = k, slot = 0;
                for (int j = 0; j < LSQT_BAND_BLOCK_MAX; j++) blk->band[j] = -1;
            }
            blocks[count - 1].band[slot++] = b;
        }
    }
    for (int b = 0; t && b < nb; b++) tables_free(&t[b]);
    free(t);
    free(group);
    if (!ok) {
        free(blocks);
        return -1;
    }
    *out = blocks;
    return count;
}

int lsqt_band_block_tables(const lsqt_assembly *a, const lsqt_band_block *blk, int nbp, double same_mut,
                           lsqt_dev_scene *scene, lsqt_dev_medium_d *media, lsqt_dev_layer_d *layers, double *bw,
                           lsqt_dev_medium_d *band_media)
{
    const int n = a->n_layers, first = blk->band[0];
    lsqt_device_tables(lsqt_assembly_band(a, first), scene, media, layers);
    band_tables t[LSQT_BAND_BLOCK_MAX];
    int have = 0;
    for (int j = 0; j < blk->nb; j++) {
        t[j].media = NULL, t[j].layers = NULL;
        if (blk->band[j] >= 0 && tables_of(a, blk->band[j], &t[j])) {
            for (int i = 0; i < have; i++) tables_free(&t[i]);
            return 1;
        }
        have = j + 1;
    }
    /* Extinctions within same_mut (relative) of a medium's least are the least (a band's
     * mus + mua written as decimals to 6 digits may miss the others' sum by 1e-6): the
     * kernels then see one extinction and take the flights' short way (bands.cl).
     * Each band's depths are summed again as tables.c sums them, so equal extinctions
     * give equal depths. */
    for (int m = 1; m < n; m++) {
        double least = INFINITY;
        for (int j = 0; j < have; j++)
            if (blk->band[j] >= 0 && t[j].media[m].mut < least) least = t[j].media[m].mut;
        for (int j = 0; j < have; j++) {
            lsqt_dev_medium_d *q = blk->band[j] >= 0 ? &t[j].media[m] : NULL;
            if (q && q->mut != least && fabs(q->mut - least) <= same_mut * least)
                q->mus *= least / q->mut, q->mut = least, q->mua = least - q->mus;
        }
    }
    for (int j = 0; j < have; j++) {
        if (blk->band[j] < 0) continue;
        double acc = 0.0;
        for (int m = 0; m <= n; m++) t[j].media[m].tau_above = acc, acc += t[j].media[m].mut * t[j].media[m].thickness;
        acc = 0.0;
        for (int m = n; m >= 0; m--) t[j].media[m].tau_below = acc, acc += t[j].media[m].mut * t[j].media[m].thickness;
    }
    /* The reference media: the least extinction and depths, a phase function from a band
     * that scatters; each medium's largest extinction (0: clear in every band). */
    for (int m = 0; m <= n; m++) {
        const int interior = m > 0 && m < n;
        double most = 0.0;
        for (int j = 0; j < have; j++) {
            if (blk->band[j] < 0) continue;
            const lsqt_dev_medium_d *q = &t[j].media[m];
            lsqt_dev_medium_d *r = &media[m];
            if (q->mut < r->mut) r->mut = q->mut;
            if (q->tau_above < r->tau_above) r->tau_above = q->tau_above;
            if (q->tau_below < r->tau_below) r->tau_below = q->tau_below;
            if (q->mus > 0 && r->phase_kind == LSQT_PHASE_NONE) {
                r->phase_kind = q->phase_kind, r->mus = q->mus;
                memcpy(r->pp, q->pp, sizeof r->pp);
            }
            if (interior && q->mut > most) most = q->mut;
        }
        media[m].mus = media[m].mus < media[m].mut ? media[m].mus : media[m].mut;
        media[m].mua = media[m].mut - media[m].mus;
        bw[m] = most;
    }
    /* Unit models: the factors are the bands'. */
    for (int i = 0; i < n; i++) {
        const band_rule r = rule_of(layers[i].kind);
        if (r.mode != BANDS_FACTORS) continue;
        layers[i].p[r.b0] = 1.0;
        if (r.b1 >= 0) layers[i].p[r.b1] = 1.0;
    }
    /* Per slot, its band's factors; a padding slot repeats the block's last band (its
     * tallies are dropped; as a hero it draws that band's flights). */
    int last = 0;
    for (int j = 0; j < blk->nb; j++) {
        if (blk->band[j] >= 0) last = j;
        const band_tables *q = &t[blk->band[j] >= 0 ? j : last];
        for (int i = 0; i < n; i++) {
            double fs = 0.0, fo = 0.0;
            layer_factors(&q->layers[i], &fs, &fo);
            bw[LSQT_BAND_FS(n, nbp, j, i)] = fs, bw[LSQT_BAND_FO(n, nbp, j, i)] = fo;
            const band_rule r = rule_of(q->layers[i].kind);
            if (r.mode == BANDS_INDEX)
                bw[LSQT_BAND_ETA(n, nbp, j, i)] = q->layers[i].p[r.b0], bw[LSQT_BAND_KAPPA(n, nbp, j, i)] = q->layers[i].p[r.b1];
        }
        for (int m = 0; m <= n; m++) {
            const int interior = m > 0 && m < n;
            bw[LSQT_BAND_MUS(n, nbp, j, m)] = interior ? q->media[m].mus : 0.0;
            bw[LSQT_BAND_MUT(n, nbp, j, m)] = interior ? q->media[m].mut : 0.0;
            bw[LSQT_BAND_TAU_ABOVE(n, nbp, j, m)] = q->media[m].tau_above;
            bw[LSQT_BAND_TAU_BELOW(n, nbp, j, m)] = q->media[m].tau_below;
        }
    }
    /* Each slot's own media (a padding slot's: the last band's), a band that does not
     * scatter in a medium with the reference's phase function: it weighs nothing there,
     * but as a hero it samples it, so that its paths go on for the other bands (with none,
     * they would end there: still unbiased, as its density of what follows is then 0,
     * but wasted); per medium, whether the phase functions differ. */
    for (int j = 0; j < blk->nb; j++) {
        if (blk->band[j] >= 0) last = j;
        const band_tables *q = &t[blk->band[j] >= 0 ? j : last];
        for (int m = 0; m <= n; m++) {
            lsqt_dev_medium_d *d = &band_media[(size_t)j * (size_t)(n + 1) + (size_t)m];
            *d = q->media[m];
            if (d->phase_kind == LSQT_PHASE_NONE) d->phase_kind = media[m].phase_kind, memcpy(d->pp, media[m].pp, sizeof d->pp);
        }
    }
    for (int m = 0; m <= n; m++) {
        int differ = 0;
        for (int j = 1; j < blk->nb; j++) {
            const lsqt_dev_medium_d *p = &band_media[m], *q = &band_media[(size_t)j * (size_t)(n + 1) + (size_t)m];
            differ |= p->phase_kind != q->phase_kind || memcmp(p->pp, q->pp, sizeof p->pp) != 0;
        }
        for (int j = 0; j < blk->nb; j++) bw[LSQT_BAND_PHASES(n, nbp, j, m)] = differ;
    }
    for (int j = 0; j < have; j++) tables_free(&t[j]);
    return 0;
}
