/* The analog exits of a microsurface of Lambertian facets that transmit (fT > 0), in single
 * scattering, through a band block (docs/design.md, 3.7; kernels/bands.cl,
 * host/sim/band_blocks.c): every band's exit histogram against the evaluation integrated
 * over its bins.
 *
 * The layer (alpha, fR 0.35, fT 0.6, use_multiple_scattering=false) is the same in every
 * band; a clear absorber of thickness 1 (mus 0, mua = tau per band: 0, 0.3, 1.2) lies
 * below it ("under") or above it ("over"), with nothing else in the stack, so the bands
 * share their paths (one block, LSQT_BAND_BLOCK 16) and differ only by the absorber's
 * transmittance, which the block applies by spectral MIS on the hero band's flights.
 * Light from above (theta_o per case). Every exit has met the layer exactly once, so band
 * b's exits are distributed as the layer's single scattering f(wo -> wi) (cosine
 * included: per unit mu and phi) times
 *   under:  1 (reflection), e^(-tau_b / mu_i) (transmission);
 *   over:   e^(-tau_b / mu_o - tau_b / mu_i) (reflection), e^(-tau_b / mu_o) (transmission).
 * f is the walk's own evaluation: its first vertex's next-event terms (mslambert_firstv,
 * which average the escape after the vertex analytically), by the harness kernel
 * harness_ms_eval, ITEMS independent work-items of `reps` vertices each, at 2 x 2 Gauss
 * nodes in every bin of the exit histogram (walk.cl's hist_bin: 32 equal bins in
 * |cos theta| x 16 in phi folded to [0, pi], per hemisphere; the fold doubles each bin,
 * wo being in the x-z plane). In |cos theta| the two nodes carry product-integration
 * weights, int L_k(mu) a(mu) dmu with a the band's transmittance (exact for f linear
 * across a bin however steep a is). That evaluation is tested against the walk's own
 * analog exits, without bands, by test_ms_models ("Lambertian single").
 *
 * Per (case, slice, band), on the histogram's batch sums (32 batches):
 *  - chi-square on coarse bins (4 x 4 histogram bins, 64 in all; bins expecting fewer than
 *    MIN_EXITS exits pooled per hemisphere): each bin's t = (observed - expected) / (the
 *    batch-means error (+) the evaluation's, from its items) made a standard normal
 *    through Student's t with 31 dof, and the sum of squares against chi-square;
 *  - the albedo of each hemisphere (R, T) alone: t against Student's t with 31 dof.
 * All p-values form one family, Bonferroni corrected to a false-alarm rate of 1e-3
 * (tests/gof.h). Power, kept as a self-check: each band's histogram with every bin's
 * content times 1 + 0.02 x (x the bin's mean direction's; a 2 % skew of the exits) must
 * be rejected wherever its noncentrality says the chi-square can (lambda >= 150);
 * the output prints lambda for all.
 * That the paths were shared: one block, and every band's work counters are the block's.
 *
 *   test_band_exits quick   the release suite's: 2^22 paths a slice; under at alpha 0.3
 *                           (theta_o 0, 60, 85), over at alpha 1 (30, 70); evaluation
 *                           ITEMS x 1000 vertices a slice. About 18 s on 2 cores.
 *   test_band_exits power   power: 2^23 paths a slice; under (0, 60, 85) and over (0, 45,
 *                           70) at alpha 0.05, 0.3, 1 and 2.4; ITEMS x 2000 vertices.
 *                           About 170 CPU-s, two thirds of it the evaluation.
 * `test_band_exits SECTION N` adds N to every seed (to see that the tolerances hold). */
#include <stdint.h>

#include "band_run.h"
#include "family_stats.h"
#include "gof.h"

#include "lsqt/band_blocks.h"
#include "lsqt/state.h"

#define NWI_H 4096 /* the harness program's LSQT_NWI: 2 x 512 histogram bins x 2 x 2 nodes */
#define PAD_H LSQT_PAD(NWI_H, 4)
#define ITEMS 128
#define HMU LSQT_HIST_NMU
#define HPHI LSQT_HIST_NPHI
#define HBINS LSQT_HIST_BINS
#define CMU 4  /* histogram bins per coarse bin in |cos theta| */
#define CPHI 4 /* and in phi */
#define NCB (2 * (HMU / CMU) * (HPHI / CPHI))
#define MIN_EXITS 2000.0 /* a coarse bin's exits (~60 a batch): batch sums near normal */
#define SKEW 0.02
#define MAXB 3
#define MAXS 3

static cl_program prog;

/* ------------------------------------------------------------------ the evaluation */

/* The histogram bin (h, i, j)'s nodes: mu at the 2-point Gauss nodes of [i, i + 1] / HMU,
 * phi at those of [j, j + 1] pi / HPHI; node n = bin * 4 + 2 * a + q (a: mu, q: phi). */
static const double G2 = 0.57735026918962576451;
static double node_mu(int i, int a) { return (i + 0.5 + (a ? G2 : -G2) * 0.5) / HMU; }
static double node_phi(int j, int q) { return (j + 0.5 + (q ? G2 : -G2) * 0.5) * PI / HPHI; }

/* The layer's f (per unit mu and phi) at every node, per item: out[item * PAD_H + node],
 * for light from above at theta_o. */
static void eval_nodes(const lsqt_dev_layer *L, double theta_o, int reps, cl_uint seed, float *out)
{
    static double d[NWI_H][3];
    for (int bin = 0; bin < HBINS; bin++) {
        const int h = bin / (HMU * HPHI), i = bin / HPHI % HMU, j = bin % HPHI;
        for (int a = 0; a < 2; a++)
            for (int q = 0; q < 2; q++) {
                const double mu = node_mu(i, a), ph = node_phi(j, q), st = sqrt(1 - mu * mu);
                double *v = d[bin * 4 + 2 * a + q];
                v[0] = st * cos(ph), v[1] = st * sin(ph), v[2] = h ? -mu : mu;
            }
    }
    cl_mem bl = fixture_mem(sizeof *L, L);
    fixture_dirs md = fixture_dirs_make(prog, bl, (const double(*)[3])d, NWI_H, NWI_H, PAD_H);
    const double wo[3] = {sin(theta_o), 0.0, cos(theta_o)};
    fixture_ms_eval(prog, bl, wo, &md, seed, reps, ITEMS, PAD_H, out);
    fixture_dirs_free(&md);
    clReleaseMemObject(bl);
}

/* ------------------------------------------------------------------ the cases */

typedef struct {
    const char *name;
    int over;            /* the absorber above the layer (else below it) */
    double alpha;
    int ns;
    double deg[MAXS];    /* theta_o of the slices */
    int reps;            /* the evaluation's vertices per item */
} exit_case;

static const double FR = 0.35, FT = 0.6; /* fT > fR: most light crosses the facets */
static const int NBANDS = 3;
static const double TAU[MAXB] = {0.0, 0.3, 1.2};

static void case_text(const exit_case *c, char *text, size_t size)
{
    char layer[200], med[200];
    /* iter_count 1: more walks per vertex serve only the point estimates, not tested here */
    snprintf(layer, sizeof layer,
             "MicrosurfaceLambertianBrdf alpha=%g fR=%g fT=%g use_multiple_scattering=false iter_count=1", c->alpha,
             FR, FT);
    snprintf(med, sizeof med, "Medium mus=0,0,0 mua=%g,%g,%g", TAU[0], TAU[1], TAU[2]);
    if (c->over)
        snprintf(text, size, "Medium\nLayer z=1 NullBsdf\n%s\nLayer z=0 %s\nMedium\n", med, layer);
    else
        snprintf(text, size, "Medium\nLayer z=1 %s\n%s\nLayer z=0 NullBsdf\nMedium\n", layer, med);
}

/* Band b's transmittance for an exit at |cos theta| mu in hemisphere h (0 up). */
static double band_a(const exit_case *c, int b, double mu_o, int h, double mu)
{
    const double t = TAU[b];
    if (c->over) return h ? exp(-t / mu_o) : exp(-t / mu_o - t / mu);
    return h ? exp(-t / mu) : 1.0;
}

/* The product-integration weights of a bin [i, i + 1] / HMU: W[a] = int L_a(mu) a(mu) dmu,
 * L_a the linear interpolant that is 1 at node a and 0 at the other (16-point Gauss). */
static void mu_weights(const exit_case *c, int b, double mu_o, int h, int i, double W[2])
{
    static double gx[16], gw[16];
    static int init = 0;
    if (!init) gauss_legendre(16, gx, gw), init = 1;
    const double m0 = (double)i / HMU, m1 = (double)(i + 1) / HMU, n0 = node_mu(i, 0), n1 = node_mu(i, 1);
    W[0] = W[1] = 0;
    for (int k = 0; k < 16; k++) {
        const double mu = 0.5 * (m0 + m1) + 0.5 * (m1 - m0) * gx[k], wk = 0.5 * (m1 - m0) * gw[k];
        const double av = mu > 0 ? band_a(c, b, mu_o, h, mu) : 0.0;
        W[0] += wk * av * (mu - n1) / (n0 - n1), W[1] += wk * av * (mu - n0) / (n1 - n0);
    }
}

static int coarse_of(int bin)
{
    const int h = bin / (HMU * HPHI), i = bin / HPHI % HMU, j = bin % HPHI;
    return (h * (HMU / CMU) + i / CMU) * (HPHI / CPHI) + j / CPHI;
}

/* Standard normal z with the same two-sided tail as Student's t (31 dof) at t. */
static double z_of_t(double t)
{
    const double a = fabs(t);
    if (a < 1e-9) return 0.0;
    const double p = fmax(t_tail2(a, NB - 1), 1e-300);
    double lo = 0.0, hi = 40.0;
    for (int k = 0; k < 80; k++) {
        const double mid = 0.5 * (lo + hi);
        if (erfc(mid / sqrt(2.0)) > p)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

static double smallest_lambda = 1e300; /* the weakest required skew (printed) */

/* Parses the case's bands, checks they make one block, simulates them in one run. */
static lsqt_slice_est *run_block(const exit_case *c, uint64_t paths, uint64_t seed, lsqt_state *st)
{
    char text[1024];
    case_text(c, text, sizeof text);
    /* two directions for the point estimates (the exits are what is tested) */
    static const double dw[2][3] = {{0.5, 0.0, 0.8660254}, {0.5, 0.0, -0.8660254}};
    return band_block_run(c->name, text, NBANDS, c->ns, c->deg, 2, dw, paths, seed, st);
}

static void case_check(const exit_case *c, uint64_t paths, uint64_t seed)
{
    const double t0 = check_now();
    lsqt_state st;
    lsqt_slice_est *e = run_block(c, paths, seed, &st);
    const double t_run = check_now() - t0;
    if (!e) {
        lsqt_state_free(&st);
        return;
    }
    lsqt_dev_layer L;
    memset(&L, 0, sizeof L);
    L.kind = LSQT_BSDF_MS_LAMBERTIAN, L.iter_count = 1, L.multiple_scattering = 0;
    L.p[0] = (float)c->alpha, L.p[1] = (float)FR, L.p[2] = (float)FT;
    float *f = malloc((size_t)ITEMS * PAD_H * sizeof *f);
    double t_eval = 0, eratio = 0;
    for (int s = 0; s < c->ns; s++) {
        const double th = c->deg[s] * PI / 180.0, mu_o = cos(th);
        const double te = check_now();
        eval_nodes(&L, th, c->reps, (cl_uint)(seed + seed_offset) * 7u + (cl_uint)s, f);
        t_eval += check_now() - te;
        int nonfinite = 0;
        for (size_t k = 0; k < (size_t)ITEMS * PAD_H; k++) nonfinite += !isfinite(f[k]);
        CHECK(nonfinite == 0, "%s to=%g: %d non-finite evaluations", c->name, c->deg[s], nonfinite);
        uint64_t np[NB];
        lsqt_state_batch_counts(&st, np);
        /* expected per path, per band, coarse bin and item; the bin's mean x for the skew */
        static double cia[MAXB][ITEMS][NCB], exa[MAXB][NCB], vxa[MAXB][NCB], xba[MAXB][NCB];
        memset(cia, 0, sizeof cia), memset(xba, 0, sizeof xba);
        for (int b = 0; b < NBANDS; b++) {
            double (*ci)[NCB] = cia[b], *ex = exa[b], *vx = vxa[b], *xb = xba[b], xwt[NCB] = {0};
            for (int bin = 0; bin < HBINS; bin++) {
                const int h = bin / (HMU * HPHI), i = bin / HPHI % HMU, j = bin % HPHI, cb = coarse_of(bin);
                double W[2];
                mu_weights(c, b, mu_o, h, i, W);
                const double wphi = 0.5 * PI / HPHI * 2; /* half the width, times 2 for the fold */
                for (int it = 0; it < ITEMS; it++) {
                    const float *fi = f + (size_t)it * PAD_H + (size_t)bin * 4;
                    ci[it][cb] += wphi * (W[0] * (fi[0] + fi[1]) + W[1] * (fi[2] + fi[3]));
                }
                const double mu = (i + 0.5) / HMU, ph = (j + 0.5) * PI / HPHI;
                xb[cb] += (W[0] + W[1]) * sqrt(1 - mu * mu) * cos(ph), xwt[cb] += W[0] + W[1];
            }
            for (int cb = 0; cb < NCB; cb++) {
                double m1 = 0, m2 = 0;
                for (int it = 0; it < ITEMS; it++) m1 += ci[it][cb] / ITEMS, m2 += ci[it][cb] * ci[it][cb] / ITEMS;
                ex[cb] = m1, vx[cb] = fmax(m2 - m1 * m1, 0.0) / (ITEMS - 1);
                xb[cb] = xwt[cb] > 0 ? xb[cb] / xwt[cb] : 0;
            }
        }
        /* Pooling, the same for every band: per hemisphere the coarse bins expecting fewer
         * than MIN_EXITS exits. The bands share their exits (a path's exit is tallied in
         * every band, with the band's weight), so their count is about the bands' mean
         * weight over the facets' albedo. */
        int grp[NCB], ng = 0, pool[2] = {-1, -1};
        double gcnt[NCB + 2] = {0};
        for (int cb = 0; cb < NCB; cb++) {
            double cnt = 0;
            for (int b = 0; b < NBANDS; b++) cnt += exa[b][cb] * (double)paths / (NBANDS * (FR + FT));
            const int h = cb >= NCB / 2;
            if (cnt >= MIN_EXITS) {
                grp[cb] = ng++;
            } else {
                if (pool[h] < 0) pool[h] = ng++;
                grp[cb] = pool[h];
            }
            gcnt[grp[cb]] += cnt;
        }
        for (int b = 0; b < NBANDS; b++) {
            double (*ci)[NCB] = cia[b], *ex = exa[b], *vx = vxa[b], *xb = xba[b];
            /* observed: each coarse bin's batch sums (plain and skewed) */
            const lsqt_state v = lsqt_state_band(&st, b);
            const lsqt_u128 *hist = lsqt_state_hist_of(&v, s);
            static double y[2][NCB][NB];
            memset(y, 0, sizeof y);
            for (int bt = 0; bt < NB; bt++)
                for (int bin = 0; bin < HBINS; bin++) {
                    const double w = lsqt_u128_to_double(hist[(size_t)bt * HBINS + bin]) / LSQT_FIX_SCALE;
                    const int cb = coarse_of(bin);
                    y[0][cb][bt] += w, y[1][cb][bt] += w * (1 + SKEW * xb[cb]);
                }
            double x[NB];
            for (int bt = 0; bt < NB; bt++) x[bt] = (double)np[bt];
            double gex[NCB + 2] = {0}, gvx[NCB + 2] = {0};
            for (int cb = 0; cb < NCB; cb++) gex[grp[cb]] += ex[cb], gvx[grp[cb]] += vx[cb];
            double chi[2] = {0, 0}, lam = 0, tmax = 0;
            int dof = 0;
            for (int g = 0; g < ng; g++) {
                if (gcnt[g] < MIN_EXITS) continue; /* a pool too small to test */
                double yg[2][NB];
                for (int k = 0; k < 2; k++)
                    for (int bt = 0; bt < NB; bt++) {
                        yg[k][bt] = 0;
                        for (int cb = 0; cb < NCB; cb++)
                            if (grp[cb] == g) yg[k][bt] += y[k][cb][bt];
                    }
                dof++;
                for (int k = 0; k < 2; k++) {
                    const lsqt_est r = batch_ratio(yg[k], x);
                    const double sd = sqrt(r.err * r.err + gvx[g]), t = (r.mean - gex[g]) / sd;
                    const double z = z_of_t(t);
                    chi[k] += z * z;
                    if (!k) {
                        tmax = fmax(tmax, fabs(t)), eratio = fmax(eratio, gvx[g] / (r.err * r.err));
                        const lsqt_est r1 = batch_ratio(yg[1], x);
                        lam += (r1.mean - r.mean) * (r1.mean - r.mean) / (sd * sd);
                    }
                }
            }
            char tn[160];
            snprintf(tn, sizeof tn, "%s to=%g band %d (tau %g): exits chi2 (%d bins)", c->name, c->deg[s], b + 1,
                     TAU[b], dof);
            const double p = chi2_p(chi[0], dof), ps = chi2_p(chi[1], dof);
            gof_record(tn, p);
            /* each hemisphere's albedo */
            double alb[2], alb_e[2], alb_t[2], psk = ps;
            for (int h = 0; h < 2; h++) {
                double yh[2][NB], eh = 0, vh = 0;
                for (int k = 0; k < 2; k++)
                    for (int bt = 0; bt < NB; bt++) {
                        yh[k][bt] = 0;
                        for (int cb = h * NCB / 2; cb < (h + 1) * NCB / 2; cb++) yh[k][bt] += y[k][cb][bt];
                    }
                /* the items' spread of the hemisphere's integral */
                double m1 = 0, m2 = 0;
                for (int it = 0; it < ITEMS; it++) {
                    double u = 0;
                    for (int cb = h * NCB / 2; cb < (h + 1) * NCB / 2; cb++) u += ci[it][cb];
                    m1 += u / ITEMS, m2 += u * u / ITEMS;
                }
                eh = m1, vh = fmax(m2 - m1 * m1, 0.0) / (ITEMS - 1);
                for (int k = 0; k < 2; k++) {
                    const lsqt_est r = batch_ratio(yh[k], x);
                    const double t = (r.mean - eh) / sqrt(r.err * r.err + vh + 1e-14 * eh * eh);
                    const double pt = t_tail2(fmax(fabs(t), 1e-9), NB - 1);
                    if (k) {
                        psk = fmin(psk, pt);
                        continue;
                    }
                    alb[h] = r.mean, alb_e[h] = eh, alb_t[h] = t;
                    snprintf(tn, sizeof tn, "%s to=%g band %d (tau %g): albedo %s", c->name, c->deg[s], b + 1, TAU[b],
                             h ? "T" : "R");
                    gof_record(tn, pt);
                }
            }
            snprintf(tn, sizeof tn, "%s to=%g band %d", c->name, c->deg[s], b + 1);
            gof_skew(tn, psk, lam, lam >= 150);
            if (lam >= 150) smallest_lambda = fmin(smallest_lambda, lam);
            printf("  %-26s to=%2g band %d (tau %.1f): chi2 %6.1f/%2d p=%.3f (max |t| %.2f) | R %.5f (eval %.5f, "
                   "t=%+.2f) T %.5f (eval %.5f, t=%+.2f) | 2 %% skew: lambda %.0f, p %.1e\n",
                   c->name, c->deg[s], b + 1, TAU[b], chi[0], dof, p, tmax, alb[0], alb_e[0], alb_t[0], alb[1],
                   alb_e[1], alb_t[1], lam, psk);
        }
    }
    printf("  %s: run %.1f s, evaluation %.1f s (its variance / the exits' <= %.2f per bin)\n", c->name, t_run,
           t_eval, eratio);
    free(f);
    lsqt_estimates_free(e, c->ns);
    lsqt_state_free(&st);
}

/* ---------------------------------------------------------------- sections */

static void section_quick(void)
{
    const uint64_t n = (uint64_t)1 << 22;
    const exit_case under = {"under a=0.3", 0, 0.3, 3, {0, 60, 85}, 1000};
    const exit_case over = {"over a=1", 1, 1.0, 2, {30, 70, 0}, 1000};
    case_check(&under, n, 5001);
    case_check(&over, n, 5002);
}

static void section_power(void)
{
    const uint64_t n = (uint64_t)1 << 23;
    const double alphas[] = {0.05, 0.3, 1.0, 2.4};
    for (int ia = 0; ia < 4; ia++) {
        char nu[32], no[32];
        snprintf(nu, sizeof nu, "under a=%g", alphas[ia]);
        snprintf(no, sizeof no, "over a=%g", alphas[ia]);
        const exit_case under = {nu, 0, alphas[ia], 3, {0, 60, 85}, 2000};
        const exit_case over = {no, 1, alphas[ia], 3, {0, 45, 70}, 2000};
        case_check(&under, n, 5101 + 2 * (uint64_t)ia);
        case_check(&over, n, 5102 + 2 * (uint64_t)ia);
    }
}

int main(int argc, char **argv)
{
    static const char *names[] = {"quick", "power"};
    static void (*const run[])(void) = {section_quick, section_power};
    int sec = -1;
    for (int i = 0; argc >= 2 && i < 2; i++)
        if (!strcmp(argv[1], names[i])) sec = i;
    if (sec < 0 || argc > 3) {
        fprintf(stderr, "usage: test_band_exits quick|power [SEED_OFFSET]\n");
        return 2;
    }
    if (argc == 3) seed_offset = strtoull(argv[2], NULL, 10);
    (void)ZD, (void)ZA, (void)n_dir, (void)n_agg; /* family_stats.h's per-direction family: this one is gof.h's */
    const double t_start = check_now();
    /* the default width, whatever the caller's environment says */
    setenv("LSQT_BAND_BLOCK", "16", 1);
    setenv("LSQT_BAND_DIVERGENCE", "inf", 1); /* the cases' bands differ on purpose */
    fixture_open();
    if (band_blocks_absent()) {
        lsqt_context_release(&fixture_cx);
        return 77;
    }
    prog = fixture_build("-cl-std=CL1.2 -DLSQT_HAS_BSDF_MS_LAMBERTIAN=1 -DLSQT_NWI=%d", NWI_H);
    if (!prog) return check_finish("test_band_exits");
    run[sec]();
    gof_verdict(0, "every bin times 1 + 0.02 x");
    if (smallest_lambda < 1e300) printf("the weakest skew that had to be rejected: lambda %.0f\n", smallest_lambda);
    printf("total %.1f s, kernels %.1f s\n", check_now() - t_start, fixture_kernel_s);
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    char what[64];
    snprintf(what, sizeof what, "test_band_exits %s", names[sec]);
    return check_finish(what);
}
