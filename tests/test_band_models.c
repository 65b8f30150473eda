/* Every model inside a band block (docs/design.md, 3.7; kernels/bands.cl, the LSQT_NB > 1
 * parts of kernels/walk.cl, host/sim/band_blocks.c), each band against its own one-band
 * run.
 *
 * test_band_blocks checks band blocks against an independent reference, which exists only
 * for HG media over Lambertian floors. Here ONE run of each stack holds its bands in one
 * block (LSQT_BAND_BLOCK 16), and each band is compared with the run of its own stack
 * alone (the same text with that band's values; a one-band program has none of bands.cl)
 * under another seed: a block's band must agree with its own walk within the error bars.
 * The other seed keeps an error both runs would share by drawing the same numbers from
 * hiding. Every stack is lit at theta_o = 0, 60 and 85 degrees and seen at theta_i = 0,
 * 40, 70, 80, 87, 89 at azimuths 0, 90, 180 from wo's (tests/stack_dirs.h), on both sides
 * where it transmits.
 *
 *   phase cases (hg, hg2, rayleigh, sggx-specular, sggx-diffuse, draine): two slabs of
 *               that phase function between null layers. The upper one has one extinction
 *               in every band and albedos 0.95, 0.6, 0.8 (bands.cl's one-extinction
 *               flights: a collision weighs by the albedo only); the lower one extinctions
 *               0.5, 1.5, 1.2 and albedos 0.9, 0.9, 0.6 (spectral MIS over the flights).
 *               Each collision's phase sample and next-event terms are shared.
 *   hg-g, hg-draine  the same with phase functions that differ by band (g from -0.5 to
 *               0.9; Draine's alpha 0, which is HG, beside 1 and 2.5): the hero's phase
 *               sample, each band weighed by its own phase function over the mixture,
 *               and each band's own next-event terms.
 *   lambertian  a transmitting Lambertian (fR 0.3, 0.6, 0.1; fT 0.6, 0.2, 0.85) between
 *               two HG media, lit from above and, by the lower medium's light, from below:
 *               the hero's side, each band's fs or fo in the walk step and the next-event
 *               terms, on both sides of the layer.
 *   oren-nayar  an Oren-Nayar floor (sigma 0.6, fR 0.9, 0.5, 0.2) under an HG medium of
 *               extinction 0.4, 0.5, 0.45: its unit model over the cosine sampler is not 1
 *               (a Lambertian's is), as a walk step and as next-event terms.
 *   metal-ss, metal-ms  a GGX dielectric interface (alpha 0.2, single scattering: its
 *               terms are analytic) into a thin HG medium of index 1.5 (optical thickness
 *               0.15 to 0.22 per band) over a GGX conductor whose n + i k differ per band
 *               (single scattering alpha 0.2; multiple scattering alpha 0.5). The
 *               conductor is hidden (no next-event terms of its own), but the interface
 *               keeps its lobe: a lobe turned about the normal (specular into
 *               retro-reflection) keeps every R and T and shows only direction by
 *               direction, away from theta_o = 0.
 *
 *   test_band_models quick   the release suite's: 2^18 paths a slice per run (23 CPU-s,
 *                            about 35 s on two busy cores). Median relative standard
 *                            errors of a band's difference: 0.2-2.4 % per direction,
 *                            0.15-1.5 % per theta_i, 0.03-0.5 % per side (inverse-variance
 *                            means), R 0.14-0.8 %: one band's terms 0.5 % too large fail
 *                            (z 9), a walk step 1.3 % short fails by its R (z 7.7), a
 *                            conductor's exit tilted 10 % to the normal at grazing
 *                            directions (z 16).
 *   test_band_models power   power (CI): 2^21 paths a slice (172 CPU-s; 90 s on two idle
 *                            cores, up to 300 s on busy ones): about 3 times finer; one
 *                            band's terms 0.5 % too large fail with z 10.
 *   Each prints, per band, the median relative standard error of the differences it
 *   tests: a bias of about ZA times that in one band fails.
 *
 * Checks, per band and slice: per direction z = (a - b) / sqrt(ea^2 + eb^2) within ZD; per
 * (side, theta_i) the mean over the azimuths and per side the mean over every direction
 * (plain, and weighed by each direction's inverse relative variance), of f / (the two
 * runs' mean f there), as ratio estimates with their batch-means errors from each run
 * (tests/family_stats.h), and R, T, delta_T: z within ZA. ZD and ZA: Student t with 31 degrees of freedom (the difference of two runs
 * has more: conservative) for a family-wise false alarm rate of 1e-3 per section. A band's
 * standard errors of R and of the means over every direction are at most ERR_CAP times
 * its own run's: weights that run wild (estimates too noisy for any z to fail) are caught
 * there. That the paths were shared: the bands make one block and every band's work
 * counters are equal (test_band_blocks). `test_band_models SECTION N` adds N to every
 * seed. */
#include "band_run.h"
#include "family_stats.h"
#include "ref_adding.h"
#include "stack_dirs.h"

#include "lsqt/band_blocks.h"
#include "lsqt/state.h"

/* A block's band may be noisier than on its own paths (its weight is up to LSQT_NB times
 * its own: docs/design.md, 3.7): the quick section's ratios are at most about 1.9, and
 * two batch-means errors of 31 degrees of freedom each differ by a factor 2.3 once in
 * 1e5. */
#define ERR_CAP 5.0

/* A stack's text with {v1,v2,v3} where a value differs by band: the multi-band text keeps
 * the list, band b's own text takes its b-th value. */
typedef struct {
    const char *name;
    int nb;
    int opaque;
    const char *text;
} model_case;

#define TWO_SLABS(PHASE)                                                                                   \
    "Medium\nLayer z=2 NullBsdf\nMedium mus={0.95,0.6,0.8} mua={0.05,0.4,0.2} " PHASE "\n"                 \
    "Layer z=1 NullBsdf\nMedium mus={0.45,1.35,0.72} mua={0.05,0.15,0.48} " PHASE "\nLayer z=0 NullBsdf\nMedium\n"

static const model_case CASES[] = {
    {"hg", 3, 0, TWO_SLABS("HenyeyGreensteinPhase g=0.7")},
    {"hg2", 3, 0, TWO_SLABS("HenyeyGreenstein2Phase g0=0.8 g1=-0.5 b=0.3")},
    {"rayleigh", 3, 0, TWO_SLABS("RayleighPhase rho=0.3")},
    {"sggx-specular", 3, 0, TWO_SLABS("SggxPhase Apara=1 Aperp=0.2 type=Specular")},
    {"sggx-diffuse", 3, 0, TWO_SLABS("SggxPhase Apara=0.3 Aperp=1 type=Diffuse")},
    {"draine", 3, 0, TWO_SLABS("DrainePhase g=0.4 alpha=2")},
    /* phase functions that differ by band (bands.cl band_phase_sample): g from -0.5 to
     * 0.9 in a slab of one extinction, then in one whose extinctions differ, where band
     * 2 does not scatter (as a hero it samples the block's reference phase function);
     * HG beside Draine (alpha 0 is HG) */
    {"hg-g", 3, 0,
     "Medium\nLayer z=2 NullBsdf\nMedium mus={0.95,0.6,0.8} mua={0.05,0.4,0.2} HenyeyGreensteinPhase g={-0.5,0.3,0.9}\n"
     "Layer z=1 NullBsdf\nMedium mus={0.45,0,0.72} mua={0.05,0.3,0.48} HenyeyGreensteinPhase g={0.9,0.6,-0.3}\n"
     "Layer z=0 NullBsdf\nMedium\n"},
    {"hg-draine", 3, 0, TWO_SLABS("DrainePhase g={0.2,0.5,0.7} alpha={0,1,2.5}")},
    {"lambertian", 3, 0,
     "Medium\nLayer z=2 NullBsdf\nMedium mus={0.5,0.3,0.8} mua={0.1,0.3,0.2} HenyeyGreensteinPhase g=0.5\n"
     "Layer z=1 LambertianBsdf fR={0.3,0.6,0.1} fT={0.6,0.2,0.85}\n"
     "Medium mus={0.8,0.5,0.9} mua={0.2,0.5,0.1} HenyeyGreensteinPhase g=0.3\nLayer z=0 NullBsdf\nMedium\n"},
    {"oren-nayar", 3, 1,
     "Medium\nLayer z=1 NullBsdf\nMedium mus={0.3,0.2,0.4} mua={0.1,0.3,0.05} HenyeyGreensteinPhase g=0.4\n"
     "Layer z=0 OrenNayarDiffuseBrdf fR={0.9,0.5,0.2} sigma=0.6\nMedium\n"},
    {"metal-ss", 3, 1,
     "Medium\nLayer z=1 MicrosurfaceDielectricBsdf alpha=0.2 use_multiple_scattering=false\n"
     "Medium eta=1.5 mus={0.1,0.05,0.2} mua={0.05,0.15,0.02} HenyeyGreensteinPhase g=0.6\n"
     "Layer z=0 MicrosurfaceConductive alpha=0.2 use_multiple_scattering=false\n"
     "Medium eta={0.17,1.3,2.4} mua={3.15,1.3,0.4}\n"},
    {"metal-ms", 3, 1,
     "Medium\nLayer z=1 MicrosurfaceDielectricBsdf alpha=0.2 use_multiple_scattering=false\n"
     "Medium eta=1.5 mus={0.1,0.05,0.2} mua={0.05,0.15,0.02} HenyeyGreensteinPhase g=0.6\n"
     "Layer z=0 MicrosurfaceConductive alpha=0.5 use_multiple_scattering=true\n"
     "Medium eta={0.17,1.3,2.4} mua={3.15,1.3,0.4}\n"},
};
enum { N_CASES = sizeof CASES / sizeof CASES[0] };

/* The text of band b (b < 0: every band's lists) */
static void case_text(const model_case *c, int b, char *out, size_t size)
{
    size_t at = 0;
    for (const char *p = c->text; *p && at + 1 < size; p++) {
        if (*p != '{') {
            out[at++] = *p;
            continue;
        }
        const char *end = strchr(p, '}');
        if (b < 0) {
            for (const char *q = p + 1; q < end && at + 1 < size; q++) out[at++] = *q;
        } else {
            const char *q = p + 1;
            for (int i = 0; i < b; i++) q = strchr(q, ',') + 1;
            for (; q < end && *q != ',' && at + 1 < size; q++) out[at++] = *q;
        }
        p = end;
    }
    out[at] = '\0';
}

/* z of two independent estimates; 0 where both are exactly equal without errors (a
 * direction neither run reaches) */
static double z_of(lsqt_est a, lsqt_est b)
{
    const double s = sqrt(a.err * a.err + b.err * b.err);
    return s > 0 ? (a.mean - b.mean) / s : a.mean == b.mean ? 0.0 : INFINITY;
}

/* sum over the directions ks of c[k] f_k, per path, with its batch-means error */
static lsqt_est weighted_over(const lsqt_state *st, int s, const int *ks, int n, const double *c)
{
    double y[NB], x[NB];
    for (int b = 0; b < NB; b++) {
        y[b] = 0.0;
        for (int i = 0; i < n; i++) y[b] += c[ks[i]] * batch_f(st, s, b, ks[i]);
        x[b] = (double)lsqt_batch_paths(st->paths, b);
    }
    return batch_ratio(y, x);
}

/* The z and relative standard error of one aggregate check; CHECK within ZA. */
static double agg_check(const char *who, double deg, const char *what, lsqt_est a, lsqt_est b, double *rel)
{
    const double z = z_of(a, b);
    *rel = sqrt(a.err * a.err + b.err * b.err) / fabs(b.mean);
    CHECK(fabs(z) <= ZA, "%s to=%g %s: block %.6g +- %.2g, own run %.6g +- %.2g: %+.2f %%, z = %.2f", who, deg, what,
          a.mean, a.err, b.mean, b.err, 100 * (a.mean / b.mean - 1), z);
    return fabs(z);
}

/* Simulates the case's bands in one block and each band alone, and compares them band
 * by band (count_only: only counts the checks). */
static void case_check(const model_case *c, uint64_t paths, uint64_t seed, int count_only)
{
    const int nwi = c->opaque ? NWI : NWI_T, ngrp = c->opaque ? NTH : 2 * NTH, nsides = c->opaque ? 1 : 2;
    n_dir += c->nb * NS * nwi, n_agg += c->nb * NS * (ngrp + 2 * nsides + 3);
    if (count_only) return;
    char text[2048];
    double dirs[NWI_T][3];
    int grp[NWI_T];
    stack_dirs(dirs, grp);
    case_text(c, -1, text, sizeof text);
    lsqt_state st;
    double t0 = check_now();
    lsqt_slice_est *e = band_block_run(c->name, text, c->nb, NS, DEG_O, nwi, (const double(*)[3])dirs, paths, seed, &st);
    const double t_block = check_now() - t0;
    if (!e) {
        lsqt_state_free(&st);
        return;
    }
    CHECK(st.n_bands == c->nb && st.transmits == !c->opaque && st.n_wi == nwi, "%s: %d bands, transmits %d, %d directions",
          c->name, st.n_bands, st.transmits, st.n_wi);
    double t_own = 0.0;
    for (int b = 0; b < c->nb; b++) {
        char who[64], own[1024];
        snprintf(who, sizeof who, "%s band %d", c->name, b + 1);
        case_text(c, b, own, sizeof own);
        lsqt_state so;
        t0 = check_now();
        /* another seed than the block's (and than the other bands') */
        lsqt_slice_est *o = band_block_run(who, own, 1, NS, DEG_O, nwi, (const double(*)[3])dirs, paths, seed + 1000 + (uint64_t)b, &so);
        t_own += check_now() - t0;
        if (!o) {
            lsqt_state_free(&so);
            continue;
        }
        const lsqt_state v = lsqt_state_band(&st, b);
        const lsqt_slice_est *eb = e + (size_t)b * NS;
        double r_dir[NS * NWI_T], r_th[NS * 2 * NTH], r_side[NS * 2], r_iv[NS * 2], r_R[NS], r_T[NS], zd = 0.0, za = 0.0, cap = 0.0;
        int n_d = 0, n_th = 0, n_side = 0, n_iv = 0;
        for (int s = 0; s < NS; s++) {
            /* per direction */
            double mean_f[NWI_T], rel_f[NWI_T];
            for (int k = 0; k < nwi; k++) {
                const lsqt_est a = eb[s].f[k], r = o[s].f[k];
                const double z = z_of(a, r);
                zd = fmax(zd, fabs(z));
                mean_f[k] = 0.5 * (a.mean + r.mean);
                rel_f[k] = sqrt(a.err * a.err + r.err * r.err) / mean_f[k];
                if (mean_f[k] > 0) r_dir[n_d++] = rel_f[k];
                CHECK(fabs(z) <= ZD,
                      "%s to=%g wi=(%.4f %.4f %.4f): block %.6g +- %.2g, own run %.6g +- %.2g: %+.2f %%, z = %.2f", who,
                      DEG_O[s], dirs[k][0], dirs[k][1], dirs[k][2], a.mean, a.err, r.mean, r.err,
                      100 * (a.mean / r.mean - 1), z);
            }
            /* per (side, theta_i) the mean over the azimuths, then per side over every
             * direction, of f / mean_f, the same weights for both runs: equal, and by the
             * inverse of each direction's relative variance (grazing directions, noisier,
             * weigh less: a bias of the whole band shows with less noise). Directions
             * where neither run has a value or an error weigh 0. */
            for (int g = 0; g < ngrp + 2 * nsides; g++) {
                const int inv_var = g >= ngrp + nsides, side = g < ngrp ? -1 : (g - ngrp) % nsides;
                int ks[NWI_T], n = 0;
                double wt[NWI_T], sum = 0.0;
                for (int k = 0; k < nwi; k++) {
                    if (!(g < ngrp ? grp[k] == g : grp[k] / NTH == side)) continue;
                    ks[n++] = k;
                    wt[k] = !(mean_f[k] > 0 && rel_f[k] > 0) ? 0.0 : inv_var ? 1.0 / (rel_f[k] * rel_f[k]) : 1.0;
                    sum += wt[k];
                }
                for (int i = 0; i < n; i++) wt[ks[i]] = sum > 0 ? wt[ks[i]] / sum / mean_f[ks[i]] : 0.0;
                const lsqt_est A = weighted_over(&v, s, ks, n, wt), B = weighted_over(&so, s, ks, n, wt);
                char what[80];
                if (g < ngrp)
                    snprintf(what, sizeof what, "%s theta_i=%g, mean over azimuths", g < NTH ? "up" : "down",
                             TH_I[g % NTH]);
                else
                    snprintf(what, sizeof what, "%s, %s mean over every direction", side ? "down" : "up",
                             inv_var ? "inverse-variance" : "plain");
                double rel;
                za = fmax(za, agg_check(who, DEG_O[s], what, A, B, &rel));
                if (g < ngrp) r_th[n_th++] = rel;
                else if (!inv_var) {
                    r_side[n_side++] = rel;
                    cap = fmax(cap, A.err / B.err);
                } else
                    r_iv[n_iv++] = rel;
            }
            za = fmax(za, agg_check(who, DEG_O[s], "R", eb[s].R, o[s].R, &r_R[s]));
            za = fmax(za, agg_check(who, DEG_O[s], "T", eb[s].T, o[s].T, &r_T[s]));
            /* delta_T: its batch-means error is 0 where no path came through */
            lsqt_est da = eb[s].delta_T, db = o[s].delta_T;
            const double p = 0.5 * (da.mean + db.mean), sd = sqrt(p * (1.0 - p) / (double)paths);
            da.err = fmax(da.err, sd), db.err = fmax(db.err, sd);
            double rel;
            za = fmax(za, agg_check(who, DEG_O[s], "delta_T", da, db, &rel));
            if (eb[s].R.err > 0 && o[s].R.err > 0) cap = fmax(cap, eb[s].R.err / o[s].R.err);
        }
        CHECK(cap <= ERR_CAP, "%s: a standard error %.2f times its own run's (at most %g)", who, cap, ERR_CAP);
        char t_rel[32] = "-";
        if (!c->opaque) snprintf(t_rel, sizeof t_rel, "%.2f %%", 100 * band_median(r_T, NS));
        printf("  %-20s max |z| %.2f per direction, %.2f per aggregate; R %.5f (own %.5f) at to=0; median rel. s.e. "
               "%.2f %% per direction, %.2f %% per theta_i, %.2f %% per side (%.2f %% inverse-variance), R %.2f %%, T %s; "
               "s.e. up to %.2f x own\n",
               who, zd, za, eb[0].R.mean, o[0].R.mean, 100 * band_median(r_dir, n_d), 100 * band_median(r_th, n_th),
               100 * band_median(r_side, n_side), 100 * band_median(r_iv, n_iv), 100 * band_median(r_R, NS), t_rel, cap);
        lsqt_estimates_free(o, NS);
        lsqt_state_free(&so);
    }
    printf("  %s: %d bands in one run %.1f s, their own runs %.1f s; %.2f layer, %.2f medium events per path at to=0\n",
           c->name, c->nb, t_block, t_own, e[0].layer_events, e[0].medium_events);
    lsqt_estimates_free(e, NS);
    lsqt_state_free(&st);
}

static void section_quick(int count_only)
{
    for (int i = 0; i < N_CASES; i++) case_check(&CASES[i], (uint64_t)1 << 18, 6001 + (uint64_t)i, count_only);
}

static void section_power(int count_only)
{
    for (int i = 0; i < N_CASES; i++) case_check(&CASES[i], (uint64_t)1 << 21, 6101 + (uint64_t)i, count_only);
}

int main(int argc, char **argv)
{
    (void)stack_grid; /* stack_dirs.h's reference grid: no reference here */
    return band_sections_main("test_band_models", argc, argv, section_quick, section_power);
}
