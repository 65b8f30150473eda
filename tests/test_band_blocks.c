/* Bands that share their paths (band blocks: docs/design.md, 3.7; kernels/bands.cl,
 * host/sim/band_blocks.c), every band against its own independent reference: the
 * adding-doubling method (tests/ref_adding.h), which owes nothing to the program.
 *
 * Bands that differ only in their factors (a Lambertian's fR, an interior medium's mus and
 * mua) walk each path once for the whole block: one band's free flights and layer side
 * for all of them, each band with its own weight along the path, and each vertex's
 * next-event terms spread to every band with its factor and its own extra transmittance.
 * Each band's values must be its own stack's, as if it had walked alone. Here ONE run of
 * each stack holds all its bands in one block (LSQT_BAND_BLOCK is set to 16, the default
 * width), and each band is checked as test_media_stacks checks a one-band run: lit at
 * theta_o = 0, 60 and 85 degrees, the RAW value f at theta_i = 0, 40, 70, 80, 87 and 89
 * degrees, at azimuths 0, 90 and 180 from wo's, on both sides where the stack transmits.
 *
 *   albedo      one HG slab (g 0.6, tau 1, 0.8 thick) between null layers, four bands of
 *               equal extinction and albedo 0, 0.5, 0.9 and 0.999: one extinction, the
 *               bands differ only in what a collision leaves of their weights; the
 *               albedo-0 band shares its paths with one that scatters hundreds of times.
 *   extinction  an HG slab (g 0.6, 1.6 thick) of optical thickness 0.02, 0.2 and 2 (100:1:
 *               a band's flights drawn for another's extinction weigh far off 1), albedo
 *               0.9, 0.6, 0.95, over an opaque Lambertian of fR 0.1, 0.5, 0.8 (the floor's
 *               factor per band).
 *   extinction through  the same slab with nothing below: the bands' transmission, and
 *               each band's own extra transmittance towards the directions below.
 *   dust        tools/bench_bands.py's dusty coat at three bands: HG g 0.6, tau 2.0, 1.6,
 *               1.2, albedo 0.98, 0.8, 0.6, 1 thick, over a Lambertian of fR 0.7, 0.4, 0.1.
 *   metal       a diffuser (Lambertian fR 0, fT 1) over a GGX conductor (alpha 0.3, single
 *               scattering) whose n + i k crosses k = n over four bands: the conductor is
 *               hidden, so the bands share its reflection and each takes its own Fresnel
 *               factor. Its reference is tests/ref_conductor.h's albedo, averaged over
 *               the diffuser's cosine-weighted light (METAL below); 0.05 % per band.
 *   two media up  two HG media over a Lambertian floor, each band's depths ordered
 *               differently in each medium: the floor's terms look up through both media,
 *               the lower medium's through the upper one, each band with its own depths.
 *   three media through  three media, nothing below: a medium vertex's terms look down
 *               through the media below it and up through those above.
 *   near-equal  two media whose bands' extinctions are 0.5 % and 1 % apart (neighbours of
 *               a smooth spectrum): each band keeps its own extinction (at 87 degrees a
 *               depth 1 % off moves the transmission by 10-20 %).
 *   clear in one band  a dye film (mus 0, mua 0 in band 1) over a slab that is empty in
 *               band 1, only absorbs in band 2 and scatters in band 3, over a floor.
 *   Lambertian over media  a transmitting Lambertian (fR, fT per band) over an absorbing
 *               and a scattering medium, nothing below: its terms look down into them.
 *               Its reference composes the Lambertian over the media's
 *               (ad_ref_lambertian_top).
 *
 *   test_band_blocks quick   the release suite's: the ten stacks in float, 2^19 paths a
 *                            slice (15-25 s on two cores with the kernels cached). The
 *                            means over azimuths have a median relative standard error
 *                            of 0.2 % (at most 0.8 %): a 1-2 % bias fails them.
 *   test_band_blocks power   power (CI): the ten at 2^22 paths a slice, and the
 *                            reference's resolution at every band's stack (55-60 s).
 *                            Median 0.08 % (at most 0.3 %): a 0.5 % bias fails.
 *
 * Checks, per band: per direction |f - ref| <= ZD sigma + ref REF_TOL + q, q half a unit
 * of the tallies' fixed point per path (a value within 1000 q of 0, deep behind an
 * absorber at grazing theta_i, is below their resolution: checked, but left out of the
 * means); per (slice, side,
 * theta_i) the mean of f/ref over the azimuths, per (slice, side) its mean over every
 * direction, and per slice the analog R, T and delta_T, within ZA sigma + REF_TOL. ZD, ZA:
 * Student t (31 degrees of freedom) for a family-wise false alarm rate of 1e-3 per
 * section (tests/family_stats.h). REF_TOL bounds the reference's error (test_media_stacks
 * reference checks the reference itself; the power section its resolution here). A band of
 * albedo 0 scatters nothing: its f and R must be exactly 0 and its T exactly its delta_T
 * (a neighbour's coefficient or factor leaking into it shows at once).
 * Each band's standard errors of f/ref over every direction and of R are at most ERR_CAP_F
 * and ERR_CAP_R (scaled to the section's paths): weights that run wild, with estimates too
 * noisy for any z to fail, are caught there.
 * That the paths were shared: the stack's bands make one block (lsqt_band_blocks), and
 * every band's work counters (events and next-event evaluations per path, the block's
 * path's, counted for each of its bands) are equal: bands walked apart would differ.
 * What a section can see: it prints, per band and slice, the median relative standard
 * error of f per direction and of the means; a bias of ZA times that is caught.
 * `test_band_blocks SECTION N` adds N to every seed (to see that the tolerances hold). */
#include "band_run.h"
#include "family_stats.h"
#include "ref_adding.h"
#include "ref_conductor.h"
#include "stack_dirs.h"

#include "lsqt/band_blocks.h"
#include "lsqt/state.h"

/* The reference's error bound and settings: nodes per panel, Fourier modes, the thickest
 * start of the doubling. Against a reference with 1.5 times the nodes and modes and a
 * start 10 times thinner (FINE_*) they differ by less than 1e-5 at every band's stack,
 * and the last quarter of the modes adds less than 1e-6 (the power section checks both).
 * 24 modes, not test_media_stacks's 16: with g 0.6 in every band, 16 modes' last quarter
 * is 3e-5 (their error against FINE_* is still 3e-6). */
#define REF_TOL 1e-4
/* The metal case's quadrature: against 1.5 times the nodes its E differs by less than
 * REF_TOL / 10 (the power section checks). */
#define METAL_NODES 32
#define REF_T0 1e-7
#define FINE_T0 1e-8
enum { REF_PER_PANEL = 4, REF_MODES = 24, FINE_PER_PANEL = 6, FINE_MODES = 36 };

/* The largest standard error of a band's mean of f/ref over every direction on a side
 * (ERR_CAP_F, relative) and of its R (ERR_CAP_R), at CAP_PATHS paths a slice, scaled by
 * 1/sqrt(paths): the quick section's are at most 1.2 % and 1.1e-3. */
#define ERR_CAP_F 0.03
#define ERR_CAP_R 0.005
#define CAP_PATHS (1u << 19)

/* ------------------------------------------------------------------ the stacks */

enum { MAX_BANDS = 4, MAX_MEDIA = 3 };

/* Media between null layers (top first, each of thickness d and HG g), optionally under
 * a transmitting Lambertian (top: fR, fT per band) and over an opaque Lambertian floor;
 * per band each medium's optical thickness and albedo (tau 0: clear in that band) and the
 * layers' factors. */
typedef struct {
    const char *name;
    int nb, nm;
    double d[MAX_MEDIA], g[MAX_MEDIA];
    double tau[MAX_MEDIA][MAX_BANDS], om[MAX_MEDIA][MAX_BANDS];
    int floor;
    double floor_fr[MAX_BANDS];
    int top;
    double top_fr[MAX_BANDS], top_ft[MAX_BANDS];
    /* or, with metal: a diffuser (LambertianBsdf fR=0 fT=1) over a conductor (GGX METAL_ALPHA,
     * single scattering) of index n + i k per band */
    int metal;
    double n[MAX_BANDS], k[MAX_BANDS];
} band_case;

static const band_case ALBEDO = {
    .name = "albedo", .nb = 4, .nm = 1, .d = {0.8}, .g = {0.6}, .tau = {{1.0, 1.0, 1.0, 1.0}}, .om = {{0.0, 0.5, 0.9, 0.999}}};
static const band_case EXTINCTION = {.name = "extinction",
                                     .nb = 3,
                                     .nm = 1,
                                     .d = {1.6},
                                     .g = {0.6},
                                     .tau = {{0.02, 0.2, 2.0}},
                                     .om = {{0.9, 0.6, 0.95}},
                                     .floor = 1,
                                     .floor_fr = {0.1, 0.5, 0.8}};
/* the same slab with nothing below: its bands' transmission, and each band's extra
 * transmittance towards the directions below */
static const band_case EXTINCTION_THROUGH = {.name = "extinction through",
                                             .nb = 3,
                                             .nm = 1,
                                             .d = {1.6},
                                             .g = {0.6},
                                             .tau = {{0.02, 0.2, 2.0}},
                                             .om = {{0.9, 0.6, 0.95}}};
static const band_case DUST = {.name = "dust",
                               .nb = 3,
                               .nm = 1,
                               .d = {1.0},
                               .g = {0.6},
                               .tau = {{2.0, 1.6, 1.2}},
                               .om = {{0.98, 0.8, 0.6}},
                               .floor = 1,
                               .floor_fr = {0.7, 0.4, 0.1}};
/* Two media over a floor whose bands' depths are ordered differently in each (the block's
 * least depth above the floor is no band's own): the floor's terms look up through both,
 * the lower medium's through the upper one, each band with its own depth of each. */
static const band_case TWO_UP = {.name = "two media up",
                                 .nb = 3,
                                 .nm = 2,
                                 .d = {0.5, 1.0},
                                 .g = {0.3, 0.7},
                                 .tau = {{0.1, 0.8, 0.4}, {1.2, 0.3, 0.9}},
                                 .om = {{0.9, 0.5, 0.95}, {0.95, 0.8, 0.6}},
                                 .floor = 1,
                                 .floor_fr = {0.6, 0.3, 0.9}};
/* Three media, nothing below: a medium vertex's terms look down through the media below
 * it (and up through those above), each band with its own depths. */
static const band_case THREE_THROUGH = {.name = "three media through",
                                        .nb = 3,
                                        .nm = 3,
                                        .d = {0.4, 0.6, 0.5},
                                        .g = {0.5, 0.0, 0.6},
                                        .tau = {{0.3, 0.05, 0.6}, {0.2, 0.9, 0.4}, {0.8, 0.3, 0.1}},
                                        .om = {{0.8, 0.95, 0.5}, {0.9, 0.6, 0.99}, {0.7, 0.9, 0.85}}};
/* Neighbouring bands of a smooth spectrum: extinctions 0.5 % and 1 % apart (and albedos
 * close), nothing below: each band keeps its own extinction; at theta_i = 87 degrees a
 * depth 1 % off changes the transmission by 10-20 %. */
static const band_case NEAR = {.name = "near-equal",
                               .nb = 3,
                               .nm = 2,
                               .d = {0.7, 0.5},
                               .g = {0.6, 0.2},
                               .tau = {{1.0, 1.005, 1.01}, {0.5, 0.5025, 0.495}},
                               .om = {{0.9, 0.9, 0.905}, {0.7, 0.7035, 0.7}}};
/* A dye film (clear: mus 0) over a scattering slab over a floor. Band 1 sees through both
 * (the film's mua 0, the slab empty); band 2's film absorbs and its slab only absorbs;
 * band 3's film absorbs and its slab scatters: a band's flights may be drawn for a band
 * whose medium is clear (no collision at all) or for one that scatters there. Band 2's
 * depth (0.5) keeps its R at theta_o = 85 degrees (through 2 x 5.7 optical depths) a
 * few thousand exits: deeper, its analog R is a rare event whose batch-means error
 * cannot be trusted. */
static const band_case CLEAR = {.name = "clear in one band",
                                .nb = 3,
                                .nm = 2,
                                .d = {0.3, 1.0},
                                .g = {0.0, 0.6},
                                .tau = {{0.0, 0.2, 0.15}, {0.0, 0.3, 1.5}},
                                .om = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.9}},
                                .floor = 1,
                                .floor_fr = {0.5, 0.8, 0.3}};
/* A transmitting Lambertian over two media, nothing below: its terms look down into an
 * absorbing (and scattering) medium and through the one below it, each band with its
 * own depths and its own fR and fT. */
static const band_case TOP = {.name = "Lambertian over media",
                              .nb = 3,
                              .nm = 2,
                              .d = {0.6, 0.4},
                              .g = {0.5, 0.0},
                              .tau = {{0.3, 1.5, 0.8}, {0.6, 0.1, 0.3}},
                              .om = {{0.0, 0.6, 0.9}, {0.5, 0.0, 0.8}},
                              .top = 1,
                              .top_fr = {0.2, 0.5, 0.1},
                              .top_ft = {0.7, 0.3, 0.85}};
/* A hidden conductor (under the diffuser: its n and k weigh its walk, and each band's own
 * Fresnel factors must be taken at every reflection) whose index crosses k = n over the
 * bands: gold at 650 nm (n 0.17, k 3.15), k = 2 n, k = n, k = n / 6. The diffuser
 * transmits everything, spread as cos theta: the stack's R is the conductor's albedo
 * averaged over cosine-weighted incidence, E = 2 int A(mu) mu dmu (A: tests/ref_conductor.h,
 * an independent model), the same from every wo, and f = E / pi. */
#define METAL_ALPHA 0.3
static const band_case METAL = {
    .name = "metal", .nb = 4, .floor = 1, .metal = 1, .n = {0.17, 0.8, 1.3, 2.4}, .k = {3.15, 1.6, 1.3, 0.4}};

/* The stack's total optical thickness in band b */
static double total_tau(const band_case *c, int b)
{
    double t = 0.0;
    for (int m = 0; m < c->nm; m++) t += c->tau[m][b];
    return t;
}

/* Light leaves the stack downwards */
static int transmits(const band_case *c) { return !c->floor; }

/* A band that can scatter nothing: no scattering in any medium, no layer that is not null */
static int dark_band(const band_case *c, int b)
{
    int any = c->floor || c->top;
    for (int m = 0; m < c->nm; m++) any |= c->om[m][b] > 0.0 && c->tau[m][b] > 0.0;
    return !any;
}

/* "k=v1,v2,..." for the bands' values */
static int put_list(char *text, size_t size, const char *key, const double *v, int n)
{
    int at = snprintf(text, size, " %s=", key);
    for (int b = 0; b < n; b++) at += snprintf(text + at, size - (size_t)at, b ? ",%.17g" : "%.17g", v[b]);
    return at;
}

static void case_text(const band_case *c, char *text, size_t size)
{
    if (c->metal) {
        int at = snprintf(text, size, "Medium\nLayer z=1 LambertianBsdf fR=0 fT=1\nMedium\n"
                                      "Layer z=0 MicrosurfaceConductive alpha=%g use_multiple_scattering=false\nMedium",
                          METAL_ALPHA);
        at += put_list(text + at, size - (size_t)at, "eta", c->n, c->nb);
        at += put_list(text + at, size - (size_t)at, "mua", c->k, c->nb);
        snprintf(text + at, size - (size_t)at, "\n");
        return;
    }
    double z = 0.0;
    for (int m = 0; m < c->nm; m++) z += c->d[m];
    int at = snprintf(text, size, "Medium\nLayer z=%.17g", z);
    if (c->top) {
        at += snprintf(text + at, size - (size_t)at, " LambertianBsdf");
        at += put_list(text + at, size - (size_t)at, "fR", c->top_fr, c->nb);
        at += put_list(text + at, size - (size_t)at, "fT", c->top_ft, c->nb);
        at += snprintf(text + at, size - (size_t)at, "\n");
    } else {
        at += snprintf(text + at, size - (size_t)at, " NullBsdf\n");
    }
    for (int m = 0; m < c->nm; m++) {
        double mus[MAX_BANDS], mua[MAX_BANDS];
        for (int b = 0; b < c->nb; b++) {
            const double mut = c->tau[m][b] / c->d[m];
            mus[b] = c->om[m][b] * mut, mua[b] = mut - mus[b];
        }
        z -= c->d[m];
        at += snprintf(text + at, size - (size_t)at, "Medium");
        at += put_list(text + at, size - (size_t)at, "mus", mus, c->nb);
        at += put_list(text + at, size - (size_t)at, "mua", mua, c->nb);
        at += snprintf(text + at, size - (size_t)at, " HenyeyGreensteinPhase g=%.17g\n", c->g[m]);
        if (m < c->nm - 1) {
            at += snprintf(text + at, size - (size_t)at, "Layer z=%.17g NullBsdf\n", z);
        } else if (c->floor) {
            at += snprintf(text + at, size - (size_t)at, "Layer z=0 LambertianBsdf");
            at += put_list(text + at, size - (size_t)at, "fR", c->floor_fr, c->nb);
            snprintf(text + at, size - (size_t)at, " fT=0\nMedium\n");
        } else {
            snprintf(text + at, size - (size_t)at, "Layer z=0 NullBsdf\nMedium\n");
        }
    }
}

/* The metal case's R: E = 2 int_0^1 A(mu) mu dmu by Gauss-Legendre over mu (nodes), A
 * by ref_albedo with nodes per panel. */
static double metal_e(const band_case *c, int b, int nodes)
{
    double x[64], w[64], e = 0.0;
    gauss_legendre(nodes, x, w);
    for (int i = 0; i < nodes; i++) {
        const double mu = 0.5 + 0.5 * x[i];
        e += w[i] * mu * ref_albedo(METAL_ALPHA, c->n[b] + I * c->k[b], acos(mu), nodes);
    }
    return e; /* 2 * (1/2) sum w mu A */
}

/* Band b's own stack's reference: its media (those clear in band b left out), its floor,
 * and its Lambertian on top. */
static void band_ref(const band_case *c, int b, int per_panel, int modes, double t0, ad_ref *r)
{
    ad_grid G;
    stack_grid(&G, per_panel, modes);
    ad_stack_desc S = {0, {0}, {0}, {0}, c->floor, c->floor ? c->floor_fr[b] : 0.0};
    for (int m = 0; m < c->nm; m++)
        if (c->tau[m][b] > 0.0) S.tau[S.n] = c->tau[m][b], S.om[S.n] = c->om[m][b], S.g[S.n++] = c->g[m];
    ad_ref_make(r, &G, &S, t0);
    if (c->top) ad_ref_lambertian_top(r, c->top_fr[b], c->top_ft[b]);
}

/* Reference f at state direction d (float components) for slice angle deg. */
static double slab_f(const ad_ref *r, double deg, const double d[3], int modes)
{
    const double mu0 = cos(deg * PI / 180.0);
    return ad_ref_f(r, mu0, d[2], atan2(d[1], d[0]) - PI, modes);
}

/* Every scattered exit of a band lands in one bin of that band's histogram, in its path's
 * batch, with the same fixed-point weight as its R or T tally (the block's histogram has
 * the bands innermost: this reads each band's part back): hist + delta_T = R + T, exactly,
 * batch by batch. Returns the number of batches where they differ. */
static int hist_mismatches(const lsqt_state *v, int s)
{
    int bad = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) {
        const lsqt_u128 *sc = v->scalars + ((size_t)s * LSQT_BATCHES + (size_t)b) * LSQT_T_COUNT;
        const lsqt_u128 *h = v->hist + ((size_t)s * LSQT_BATCHES + (size_t)b) * LSQT_HIST_BINS;
        lsqt_u128 exits = lsqt_u128_add(sc[LSQT_T_R], sc[LSQT_T_T]), binned = sc[LSQT_T_DELTA_T];
        for (int i = 0; i < LSQT_HIST_BINS; i++) binned = lsqt_u128_add(binned, h[i]);
        bad += exits.lo != binned.lo || exits.hi != binned.hi;
    }
    return bad;
}


/* "NAME band B (tau .. albedo .., ...)": band b's values, for the messages */
static void describe(const band_case *c, int b, char *who, size_t size)
{
    int at = snprintf(who, size, "%s band %d (", c->name, b + 1);
    if (c->metal) {
        snprintf(who + at, size - (size_t)at, "n %g, k %g)", c->n[b], c->k[b]);
        return;
    }
    if (c->top) at += snprintf(who + at, size - (size_t)at, "fR %g fT %g; ", c->top_fr[b], c->top_ft[b]);
    for (int m = 0; m < c->nm; m++)
        at += snprintf(who + at, size - (size_t)at, "%stau %g om %g", m ? "; " : "", c->tau[m][b], c->om[m][b]);
    if (c->floor) at += snprintf(who + at, size - (size_t)at, "; fR %g", c->floor_fr[b]);
    snprintf(who + at, size - (size_t)at, ")");
}

/* Simulates the stack's bands in one run and checks each band (count_only: only counts
 * the checks). */
static void case_check(const band_case *c, uint64_t paths, uint64_t seed, int count_only)
{
    /* an opaque stack: the upward directions only (the first NWI) */
    const int nwi = transmits(c) ? NWI_T : NWI, ngrp = transmits(c) ? 2 * NTH : NTH, nsides = transmits(c) ? 2 : 1;
    for (int b = 0; b < c->nb; b++) {
        if (dark_band(c, b)) {
            n_agg += NS; /* delta_T; the rest is exact */
            continue;
        }
        n_dir += NS * nwi, n_agg += NS * (ngrp + nsides + 3);
    }
    if (count_only) return;
    char text[2048];
    case_text(c, text, sizeof text);
    double dirs[NWI_T][3];
    int grp[NWI_T];
    stack_dirs(dirs, grp);
    lsqt_state st;
    const double t0 = check_now();
    lsqt_slice_est *e = band_block_run(c->name, text, c->nb, NS, DEG_O, nwi, (const double(*)[3])dirs, paths, seed, &st);
    const double secs = check_now() - t0;
    if (!e) {
        lsqt_state_free(&st);
        return;
    }
    CHECK(st.n_bands == c->nb && st.transmits == transmits(c) && st.n_wi == nwi,
          "%s: %d bands, transmits %d, %d directions", c->name, st.n_bands, st.transmits, st.n_wi);
    printf("  %s: %d bands in one run, %.1f s; %.2f medium events per path at to=0 (every band's)\n", c->name, c->nb,
           secs, e[0].medium_events);
    for (int b = 0; b < c->nb; b++) {
        const lsqt_state v = lsqt_state_band(&st, b);
        const lsqt_slice_est *eb = e + (size_t)b * NS;
        for (int s = 0; s < NS; s++) {
            const int bad = hist_mismatches(&v, s);
            CHECK(bad == 0, "%s band %d to=%g: the histogram + delta_T is not R + T in %d of %d batches", c->name, b + 1,
                  DEG_O[s], bad, LSQT_BATCHES);
        }
        char who[160];
        describe(c, b, who, sizeof who);
        if (dark_band(c, b)) {
            for (int s = 0; s < NS; s++) {
                const double mu0 = cos(DEG_O[s] * PI / 180.0), dT = exp(-total_tau(c, b) / mu0);
                int nonzero = 0;
                double most = 0.0;
                for (int k = 0; k < nwi; k++)
                    nonzero += eb[s].f[k].mean != 0.0, most = fmax(most, fabs(eb[s].f[k].mean));
                CHECK(nonzero == 0, "%s to=%g: f is not 0 at %d directions (up to %.3g)", who, DEG_O[s], nonzero,
                      most);
                CHECK(eb[s].R.mean == 0.0 && eb[s].T.mean == eb[s].delta_T.mean,
                      "%s to=%g: R %.6g (must be 0), T %.8g (must be delta_T %.8g)", who, DEG_O[s], eb[s].R.mean,
                      eb[s].T.mean, eb[s].delta_T.mean);
                const double sd_dT = fmax(eb[s].delta_T.err, sqrt(dT * (1.0 - dT) / (double)paths));
                CHECK(fabs(eb[s].delta_T.mean - dT) <= ZA * sd_dT + 1e-6 * dT, "%s to=%g: delta_T %.6g +- %.2g vs %.6g",
                      who, DEG_O[s], eb[s].delta_T.mean, sd_dT, dT);
                printf("  %-44s to=%2.0f: f and R exactly 0, T = delta_T %.5f (ref %.5f, z = %.2f)\n", who, DEG_O[s],
                       eb[s].delta_T.mean, dT, (eb[s].delta_T.mean - dT) / sd_dT);
            }
            continue;
        }
        ad_ref r;
        const double metal_r = c->metal ? metal_e(c, b, METAL_NODES) : 0.0;
        if (!c->metal) band_ref(c, b, REF_PER_PANEL, REF_MODES, REF_T0, &r);
        for (int s = 0; s < NS; s++) {
            const double mu0 = cos(DEG_O[s] * PI / 180.0);
            double ref[NWI_T], rel_d[NWI_T], rel_a[2 * NTH], zmax = 0.0, amax = 0.0, pool[2] = {0, 0};
            int resolved[NWI_T];
            for (int k = 0; k < nwi; k++) {
                ref[k] = c->metal ? metal_r / PI : slab_f(&r, DEG_O[s], dirs[k], REF_MODES);
                /* A path's sum at a direction is rounded to the tallies' fixed point once:
                 * at most half a unit, f |cos theta_i| per path (light that crosses a
                 * depth of 25/|cos| rounds to nothing). A value within 1000 such units of
                 * 0 is checked against them alone, and left out of the means. */
                const double quantum = 0.5 / (LSQT_FIX_SCALE * fabs(dirs[k][2]));
                resolved[k] = ref[k] > 1000.0 * quantum;
                const double f = eb[s].f[k].mean, sg = eb[s].f[k].err, dev = fabs(f - ref[k]);
                const double z = (dev - REF_TOL * ref[k] - quantum) / sg;
                zmax = fmax(zmax, dev / sg);
                rel_d[k] = sg / ref[k];
                CHECK((sg > 0 || dev <= REF_TOL * ref[k] + quantum) && z <= ZD,
                      "%s to=%g wi=(%.4f %.4f %.4f): f %.6g +- %.2g vs reference %.6g: %+.2f %%, z = %.2f", who,
                      DEG_O[s], dirs[k][0], dirs[k][1], dirs[k][2], f, sg, ref[k], 100 * (f / ref[k] - 1),
                      (f - ref[k]) / sg);
            }
            /* per (side, theta_i): the mean of f/ref over the azimuths */
            for (int g = 0; g < ngrp; g++) {
                int ks[3], n = 0;
                for (int k = 0; k < nwi; k++)
                    if (grp[k] == g && resolved[k]) ks[n++] = k;
                rel_a[g] = 0.0;
                if (!n) continue;
                const lsqt_est A = ratio_over(&v, s, ks, n, ref, NULL, 1.0);
                amax = fmax(amax, fabs(A.mean - 1.0) / A.err);
                rel_a[g] = A.err;
                CHECK((A.err > 0 || fabs(A.mean - 1.0) <= REF_TOL) && fabs(A.mean - 1.0) <= ZA * A.err + REF_TOL,
                      "%s to=%g %s theta_i=%g: mean f/ref %.5f +- %.2g (%+.2f %%, z = %.2f)", who, DEG_O[s],
                      g < NTH ? "up" : "down", TH_I[g % NTH], A.mean, A.err, 100 * (A.mean - 1), (A.mean - 1) / A.err);
            }
            /* per side: the mean of f/ref over every direction */
            for (int side = 0; side < nsides; side++) {
                int ks[NWI], n = 0;
                for (int k = 0; k < nwi; k++)
                    if (grp[k] / NTH == side && resolved[k]) ks[n++] = k;
                if (!n) continue;
                const lsqt_est A = ratio_over(&v, s, ks, n, ref, NULL, 1.0);
                amax = fmax(amax, fabs(A.mean - 1.0) / A.err);
                pool[side] = A.err;
                CHECK((A.err > 0 || fabs(A.mean - 1.0) <= REF_TOL) && fabs(A.mean - 1.0) <= ZA * A.err + REF_TOL,
                      "%s to=%g %s, every direction: mean f/ref %.5f +- %.2g (%+.2f %%, z = %.2f)", who, DEG_O[s],
                      side ? "down" : "up", A.mean, A.err, 100 * (A.mean - 1), (A.mean - 1) / A.err);
            }
            /* analog: R, T (with the unscattered beam) and delta_T */
            double Rr = metal_r, Tr = 0.0;
            if (!c->metal) ad_ref_hemi(&r, mu0, &Rr, &Tr);
            const double dT = c->floor || c->top ? 0.0 : exp(-total_tau(c, b) / mu0);
            Tr += dT;
            CHECK(fabs(eb[s].R.mean - Rr) <= ZA * eb[s].R.err + REF_TOL * Rr,
                  "%s to=%g: R %.6f +- %.2g vs %.6f (z = %.2f)", who, DEG_O[s], eb[s].R.mean, eb[s].R.err, Rr,
                  (eb[s].R.mean - Rr) / eb[s].R.err);
            CHECK(fabs(eb[s].T.mean - Tr) <= ZA * eb[s].T.err + REF_TOL * Tr,
                  "%s to=%g: T %.6f +- %.2g vs %.6f (z = %.2f)", who, DEG_O[s], eb[s].T.mean, eb[s].T.err, Tr,
                  (eb[s].T.mean - Tr) / eb[s].T.err);
            /* delta_T: binomial; its batch-means error is 0 where no path came through */
            const double sd_dT = fmax(eb[s].delta_T.err, sqrt(dT * (1.0 - dT) / (double)paths));
            CHECK(fabs(eb[s].delta_T.mean - dT) <= ZA * sd_dT + 1e-6 * dT, "%s to=%g: delta_T %.6g +- %.2g vs %.6g",
                  who, DEG_O[s], eb[s].delta_T.mean, sd_dT, dT);
            /* the precision the section needs: weights that run wild give estimates too
             * noisy for any z to fail */
            const double scale = sqrt((double)CAP_PATHS / (double)paths);
            CHECK(pool[0] <= ERR_CAP_F * scale && pool[1] <= ERR_CAP_F * scale && eb[s].R.err <= ERR_CAP_R * scale,
                  "%s to=%g: standard errors %.3g (f/ref up), %.3g (down), R %.3g: more than %.3g, %.3g", who,
                  DEG_O[s], pool[0], pool[1], eb[s].R.err, ERR_CAP_F * scale, ERR_CAP_R * scale);
            /* what the section can see: the typical relative standard error of f, of the
             * means over azimuths and over every direction, and of R */
            const double md = band_median(rel_d, nwi), ma = band_median(rel_a, ngrp);
            printf("  %-44s to=%2.0f: max |z| %.2f per direction, %.2f per mean; R %.5f (ref %.5f), T %.5f (ref %.5f); "
                   "rel. s.e. %.2f %% per direction, %.2f %% per theta_i, %.2f %% all up, R %.2f %%\n",
                   who, DEG_O[s], zmax, amax, eb[s].R.mean, Rr, eb[s].T.mean, Tr, 100 * md, 100 * ma, 100 * pool[0],
                   100 * eb[s].R.err / Rr);
        }
        if (!c->metal) ad_ref_free(&r);
    }
    lsqt_estimates_free(e, NS);
    lsqt_state_free(&st);
}

/* The reference at the sections' settings against a finer one (FINE_*: 1.5 times the
 * nodes and modes, a start 10 times thinner) and against its own first 3/4 of the modes,
 * at every direction and slice of the test, for every band's stack: each below
 * REF_TOL / 10. */
static void check_resolution(const band_case *c)
{
    if (c->metal) {
        for (int b = 0; b < c->nb; b++) {
            const double e = metal_e(c, b, METAL_NODES), f = metal_e(c, b, METAL_NODES * 3 / 2);
            CHECK(fabs(e / f - 1.0) < REF_TOL / 10, "reference %s band %d: E %.9f, with 1.5 times the nodes %.9f",
                  c->name, b + 1, e, f);
            printf("  reference %s band %d: E %.6f, %.2g from 1.5 times the nodes\n", c->name, b + 1, e, fabs(e / f - 1.0));
        }
        return;
    }
    double d[NWI_T][3];
    int grp[NWI_T];
    stack_dirs(d, grp);
    const int nwi = transmits(c) ? NWI_T : NWI;
    for (int b = 0; b < c->nb; b++) {
        if (dark_band(c, b)) continue;
        ad_ref a, f;
        band_ref(c, b, REF_PER_PANEL, REF_MODES, REF_T0, &a);
        band_ref(c, b, FINE_PER_PANEL, FINE_MODES, FINE_T0, &f);
        double dq = 0.0, dm = 0.0;
        for (int s = 0; s < NS; s++)
            for (int k = 0; k < nwi; k++) {
                const double x = slab_f(&a, DEG_O[s], d[k], REF_MODES);
                dq = fmax(dq, fabs(x / slab_f(&f, DEG_O[s], d[k], FINE_MODES) - 1.0));
                dm = fmax(dm, fabs(slab_f(&a, DEG_O[s], d[k], REF_MODES * 3 / 4) / x - 1.0));
            }
        CHECK(dq < REF_TOL / 10 && dm < REF_TOL / 10,
              "reference %s band %d: %.3g from the finer one, truncation %.3g (>= %g)", c->name, b + 1, dq, dm,
              REF_TOL / 10);
        printf("  reference %s band %d: %.2g from the finer one, %.2g from 3/4 of its modes (largest relative "
               "difference)\n",
               c->name, b + 1, dq, dm);
        ad_ref_free(&a), ad_ref_free(&f);
    }
}

/* ---------------------------------------------------------------- sections */

/* Every stack, in the order of the comment at the top, with its seed (the section's
 * base + its index). */
static const band_case *const CASES[] = {&ALBEDO, &EXTINCTION, &EXTINCTION_THROUGH, &DUST, &METAL,
                                         &TWO_UP, &THREE_THROUGH, &NEAR, &CLEAR, &TOP};
enum { N_CASES = sizeof CASES / sizeof CASES[0] };

static void section_quick(int count_only)
{
    for (int i = 0; i < N_CASES; i++) case_check(CASES[i], (uint64_t)1 << 19, 4001 + (uint64_t)i, count_only);
}

static void section_power(int count_only)
{
    for (int i = 0; i < N_CASES && !count_only; i++) check_resolution(CASES[i]);
    for (int i = 0; i < N_CASES; i++) case_check(CASES[i], (uint64_t)1 << 22, 4101 + (uint64_t)i, count_only);
}

int main(int argc, char **argv)
{
    return band_sections_main("test_band_blocks", argc, argv, section_quick, section_power);
}
