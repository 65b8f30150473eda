/* The microsurface models' samplers (the random walk of Heitz, Hanika, d'Eon, Dachsbacher
 * 2016, kernels/microsurface.cl) against their evaluations, through the harness kernels
 * (the code the path loop runs). `test_ms_models release` (the release suite) runs half of
 * the goodness-of-fit grid of 1. (alphas and angles alternating), `power` (ctest label
 * power) the other half, no argument all of it; 2 and 3 run in the release part; a second
 * argument N adds N to the seeds of 1.'s cases (to see that the tolerances hold). Release,
 * 2 cores: about 105 CPU-s (power 65), nearly all of it kernels.
 *
 * 1. Goodness of fit of harness_sample (weights: the products of the facet albedos)
 *    against the evaluation integrated over bins: Lambertian facets (fR 0.7, fT 0.25),
 *    the conductor (silver) and the lossless dielectric (index ratio 1.5 with wo above,
 *    i.e. 1/1.5 seen from below, and wo below), alpha 0.05, 0.3, 1, 2.4, theta_o 0, 60,
 *    85 degrees, 10^6 exits each; with multiple scattering (the walk; its evaluation is
 *    harness_ms_eval, stochastic) and, for the conductor and the dielectric, without
 *    (single scattering: harness_eval, analytic; for the conductor also weight = f/pdf).
 *    Lambertian facets that transmit (fR 0.35, fT 0.6) also in single scattering, from
 *    above and from below, 4 x 10^6 exits each (from below with other seeds: the model
 *    is mirror-symmetric, so with the same seeds the case from below repeats the one from
 *    above bit for bit): the sampler's exit is the walk's first vertex and then its
 *    chance of escaping (ms_walk, max_order 1: through the facets or not), the
 *    evaluation that vertex's next-event terms, which average the escape analytically
 *    (harness_ms_eval with multiple scattering off).
 *    Bins: per hemisphere (wo's side and the other) a 16 x 16 product grid in
 *    (|cos theta|, phi) with breakpoints at quantiles of 0.4 uniform + 0.6 an independent
 *    pilot run's exits, so bins crowd where the lobe is (an alpha 0.05 lobe gets about
 *    ten of the sixteen rows and columns); the horizon is a bin edge, and so is
 *    |cos theta_i| = cos theta_o / e in the dielectric's transmission, where refraction's
 *    half vector reaches the horizon and f jumps to 0 (GGX's D is finite there).
 *    Expected content of bin i, E_i = N x the integral of f over it: the analytic single
 *    scattering by adaptive Gauss-Legendre (8 x 8 rules against their quarters', to 2 %
 *    of the bin's sigma; the error estimate is kept as a variance); the walks' part
 *    (harness_ms_eval minus the single scattering) by 2 x 2 Gauss nodes per bin, 3 x 3
 *    graded towards the plane of incidence at alpha 0.05, averaged over ITEMS independent
 *    work-items of reps x iter_count walks. Observed O_i: the sum of the exits' weights.
 *    Tests per case: (a) chi-square sum_i (O_i - E_i)^2 / (r_i E_i + var_eval_i), r_i =
 *    sum w^2 / sum w in the bin (so r_i E_i is the weighted sampling variance), var_eval_i
 *    from the items' spread, bins under 25 effective samples pooled, dof = bins (nothing
 *    is fitted: E is absolute); (b) the same on 4 x 4 blocks of bins with the full
 *    covariance (the walks add to all bins at once: their errors are correlated); (c)
 *    the total, sum of all weights against N x the integral of f, variance N var(w) + the
 *    evaluation's (per item) + the quadrature's: the furnace for lossless facets; (d) for
 *    Lambertian facets that transmit, the same per hemisphere (the albedos of reflection
 *    and transmission), since an error that moves light from one to the other can leave
 *    the total nearly as it was.
 *    p-values: the regularized upper incomplete gamma and erfc (stats.h); the family, the
 *    pooled chi-square and the adaptive integration are gof.h's.
 *    Threshold: all p-values of the file form one family, Bonferroni corrected, reject
 *    if p < 1e-3 / (number of tests) (about 2.3e-6 for 442).
 *    Power, kept as a self-check: every case's exits reweighted by 1 + 0.02 wi.x (a 2 %
 *    skew of the sampler) must be rejected wherever the data say the tests can see it
 *    (noncentrality of the skew >= 100 for the total or >= 150 for the coarse test);
 *    where they cannot (mostly theta_o = 0, where the skew averages out over a symmetric
 *    lobe, and the noisiest evaluations) the p-values are printed.
 * 2. The visible-normal sampler, also for directions below the horizon (a walk's vertex
 *    reached going up): ms_vertex's normal, from a kernel of this file built on the
 *    embedded sources, for v.z = 0.87, 0.17, -0.17, -0.71, -0.98 and the four alphas,
 *    4 10^5 normals each, against D_v(m) = max(0, v.m) D(m) / A(v) written here
 *    (integrated per bin exactly in azimuth, by Gauss-Legendre split at the kinks in
 *    slope); and Lambertian facets with fR = 1 at 85 degrees (a furnace: every exit
 *    weighs 1, the evaluation integrates to 1) in 1. The facets' reflection phase
 *    function is bounded, kR D(normal) / (4 A(v)): checked next to u = -v, where v + u
 *    vanishes (the conductor and the dielectric, alpha 0.05 and 0.3).
 * 3. Reciprocity of the stochastic evaluations (multiple scattering on, alpha 0.3 and 1),
 *    20 pairs per group, each value from its own launch (independent z): reflection
 *    f(a->b)/|cos b| = f(b->a)/|cos a| above (all three models) and below (Lambertian
 *    facets, dielectric), the Lambertian facets' transmission likewise, and the
 *    dielectric's transmission n_a^2 f(a->b)/|cos b| = n_b^2 f(b->a)/|cos a|, n the
 *    absolute index on each side (the walk conserves energy: flux normalisation). The
 *    single scattering is exact and cancels; the noise is the walks'. Every |z| < 4.5
 *    (3 sigma would fail one of 370 pairs by chance: 280 pairs here), and each group's
 *    sum of z^2 is a chi-square in the family of 1. */
#include <stdint.h>

#include "cl_fixture.h"
#include "gof.h"
#include "lsqt/util.h"

#define PI 3.14159265358979323846
#define NWI 4896      /* the program's LSQT_NWI: the most walk nodes (512 bins x 9, 32 of them split) */
#define NMU 16        /* bins in |cos theta| per hemisphere */
#define NPHI 16       /* bins in phi */
#define NCELL (2 * NMU * NPHI)
#define ITEMS 128     /* independent evaluations (work-items) per case */

static cl_program prog;

/* harness_sample: n exits (x, y, z, weight) for wo; harness_eval: f and pdf (analytic
 * single scattering) at n directions (x, y, z, 0). The layer in bl, a medium of zeros. */
static void k_sample(cl_mem bl, const double wo[3], cl_uint seed, size_t n, float *out)
{
    static const lsqt_dev_medium med;
    cl_mem bm = fixture_mem(sizeof med, &med);
    const float w[3] = {(float)wo[0], (float)wo[1], (float)wo[2]};
    fixture_harness_sample(prog, bl, bm, 0, w, seed, n, out);
    clReleaseMemObject(bm);
}

static void k_eval(cl_mem bl, const double wo[3], const float *dirs, size_t n, float *out)
{
    static const lsqt_dev_medium med;
    cl_mem bm = fixture_mem(sizeof med, &med);
    const float w[3] = {(float)wo[0], (float)wo[1], (float)wo[2]};
    fixture_harness_eval(prog, bl, bm, 0, w, dirs, n, out);
    clReleaseMemObject(bm);
}

/* Directions of a stochastic evaluation: n (<= NWI) unit vectors as x[pad], y[pad],
 * z[pad] (zero padded, pad = NWI rounded to 4, the kernels' LSQT_VW when the harness does
 * not set it: zero vectors add nothing) and the slice's direction tables from
 * lsqt_prepare for a one-layer scene. */
#define PAD LSQT_PAD(NWI, 4)
/* walk models' evaluations at PAD directions (cl_fixture.h) */
static fixture_dirs ms_dirs_make(cl_mem bl, const double (*d)[3], int n) { return fixture_dirs_make(prog, bl, d, n, NWI, PAD); }

/* harness_ms_eval: ITEMS independent means of `reps` vertex evaluations each, out[item *
 * PAD + k] = f(wo -> wi_k). */
static void k_ms_eval(cl_mem bl, const double wo[3], const fixture_dirs *d, cl_uint seed, cl_int reps, float *out)
{
    fixture_ms_eval(prog, bl, wo, d, seed, reps, ITEMS, PAD, out);
}

/* ---------------------------------------------------------------- bins */

/* Bins: hemisphere h (0: wo's side, 1: the other), |cos theta| in mu[h][], phi in ph[h][]. */
typedef struct {
    int nh;
    double side; /* +1 when wo is above, -1 below */
    double mu[2][NMU + 1], ph[2][NPHI + 1];
} grid_t;

static void coords(const grid_t *g, const float *d, int *h, double *mu, double *phi)
{
    double z = g->side * d[2];
    *h = z > 0 ? 0 : 1;
    *mu = fabs(z);
    if (*mu > 1) *mu = 1;
    double p = atan2(d[1], d[0]);
    *phi = p < 0 ? p + 2 * PI : p;
}

/* The bin of a direction, -1 for a hemisphere the grid does not cover. */
static int cell_of(const grid_t *g, const float *d)
{
    int h;
    double mu, phi;
    coords(g, d, &h, &mu, &phi);
    if (h >= g->nh) return -1;
    return (h * NMU + find_bin(g->mu[h], NMU, mu)) * NPHI + find_bin(g->ph[h], NPHI, phi);
}

static void grid_from_pilot(grid_t *g, const float *s, int n)
{
    xw *v = malloc((size_t)n * sizeof *v);
    for (int h = 0; h < g->nh; h++) {
        int m = 0;
        for (int i = 0; i < n; i++) {
            int hh;
            double mu, phi;
            coords(g, s + 4 * i, &hh, &mu, &phi);
            if (hh == h && s[4 * i + 3] > 0) v[m].x = mu, v[m++].w = s[4 * i + 3];
        }
        breakpoints(v, m, 0.0, 1.0, NMU, GOF_MIX, g->mu[h]);
        m = 0;
        for (int i = 0; i < n; i++) {
            int hh;
            double mu, phi;
            coords(g, s + 4 * i, &hh, &mu, &phi);
            if (hh == h && s[4 * i + 3] > 0) v[m].x = phi, v[m++].w = s[4 * i + 3];
        }
        breakpoints(v, m, 0.0, 2 * PI, NPHI, GOF_MIX, g->ph[h]);
    }
    free(v);
}

/* The grid as gof.h's bins: bin c the rectangle of its hemisphere h, directions (sin t
 * cos phi, sin t sin phi, side (h ? -mu : mu)). */
static void grid_rect(const void *gv, int c, double r[4])
{
    const grid_t *g = gv;
    int h = c / (NMU * NPHI), i = c / NPHI % NMU, j = c % NPHI;
    r[0] = g->mu[h][i], r[1] = g->mu[h][i + 1], r[2] = g->ph[h][j], r[3] = g->ph[h][j + 1];
}

static void grid_dir(const void *gv, int c, double mu, double phi, double d[3])
{
    const grid_t *g = gv;
    double st = sqrt(fmax(0.0, 1 - mu * mu));
    d[0] = st * cos(phi), d[1] = st * sin(phi), d[2] = g->side * (c >= NMU * NPHI ? -mu : mu);
}

/* Nodes for the walks' part of bin c: q x q Gauss nodes in |cos theta| and phi or, with
 * `graded`, in s = asinh(|phi - pi| / beta) (the bin split at pi when it holds it), so the
 * nodes crowd towards the plane of incidence: at small alpha the conductor's and the
 * dielectric's orders >= 2 form a ridge there a few hundredths of a radian wide (plain
 * Gauss nodes in phi, even 4 x 4 per bin, missed 0.1 % of the conductor's energy at alpha
 * 0.05 and 85 degrees). For broad functions the grading only costs accuracy (the
 * cosh(s) weight over a wide central bin), so it is used at alpha 0.05 only (3 x 3
 * nodes). Returns the count, q^2 or 2 q^2. */
#define MS_BETA 0.02
static int ms_bin_nodes(const grid_t *g, int c, int q, int graded, double (*d)[3], double *w)
{
    double gx[16], gw[16];
    gauss_legendre(q, gx, gw);
    int h = c / (NMU * NPHI), i = c / NPHI % NMU, j = c % NPHI, n = 0;
    double m0 = g->mu[h][i], m1 = g->mu[h][i + 1], p0 = g->ph[h][j], p1 = g->ph[h][j + 1];
    double piece[2][2] = {{p0, p1}, {0, 0}};
    int np = 1;
    if (!graded) {
        for (int a = 0; a < q; a++)
            for (int b = 0; b < q; b++, n++) {
                double mu = 0.5 * (m0 + m1) + 0.5 * (m1 - m0) * gx[a], phi = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * gx[b];
                double st = sqrt(fmax(0.0, 1 - mu * mu));
                d[n][0] = st * cos(phi), d[n][1] = st * sin(phi), d[n][2] = g->side * (h ? -mu : mu);
                w[n] = 0.25 * (m1 - m0) * (p1 - p0) * gw[a] * gw[b];
            }
        return n;
    }
    if (p0 < PI && p1 > PI) piece[0][1] = PI, piece[1][0] = PI, piece[1][1] = p1, np = 2;
    for (int k = 0; k < np; k++) {
        double sgn = piece[k][0] >= PI ? 1 : -1; /* phi = pi + sgn psi */
        double ps0 = fabs(piece[k][0] - PI), ps1 = fabs(piece[k][1] - PI);
        if (ps0 > ps1) {
            double tmp = ps0;
            ps0 = ps1, ps1 = tmp;
        }
        double s0 = asinh(ps0 / MS_BETA), s1 = asinh(ps1 / MS_BETA);
        for (int a = 0; a < q; a++)
            for (int b = 0; b < q; b++, n++) {
                double mu = 0.5 * (m0 + m1) + 0.5 * (m1 - m0) * gx[a], sv = 0.5 * (s0 + s1) + 0.5 * (s1 - s0) * gx[b];
                double phi = PI + sgn * MS_BETA * sinh(sv), st = sqrt(fmax(0.0, 1 - mu * mu));
                d[n][0] = st * cos(phi), d[n][1] = st * sin(phi), d[n][2] = g->side * (h ? -mu : mu);
                w[n] = 0.25 * (m1 - m0) * (s1 - s0) * gw[a] * gw[b] * MS_BETA * cosh(sv);
            }
    }
    return n;
}

/* The analytic single scattering (harness_eval) towards n directions, for gof_integrate. */
typedef struct {
    cl_mem bl;
    const double *wo;
} eval_ctx;

static void eval_density(void *ctx, const float *dirs, size_t n, float *out)
{
    const eval_ctx *e = ctx;
    k_eval(e->bl, e->wo, dirs, n, out);
}

/* ---------------------------------------------------------------- goodness of fit */

typedef struct {
    const char *name;
    int kind;
    double alpha, p1, p2, p3; /* the layer's p[1..3] */
    int ms;                   /* multiple_scattering */
    double theta;             /* degrees; wo = (sin, 0, side cos) */
    double side;
    int nh;        /* hemispheres with light: 1 (conductor, opaque Lambertian facets) or 2 */
    size_t n;      /* samples */
    int reps;      /* vertex evaluations per evaluation item */
    int ic;        /* walks per vertex evaluation (iter_count) */
    int qm;        /* Gauss nodes per bin side for the walks' part */
} gof_case;

/* Bins per side of a coarse bin (a block of fine ones): smooth departures spread over
 * few bins weigh more against fewer degrees of freedom. */
#define COARSE 4
#define NCOARSE (NCELL / (COARSE * COARSE))

static int coarse_of(int c)
{
    int h = c / (NMU * NPHI), i = c / NPHI % NMU, j = c % NPHI;
    return (h * (NMU / COARSE) + i / COARSE) * (NPHI / COARSE) + j / COARSE;
}

/* The coarse bins' chi-square with the full covariance: the walks add to every bin at
 * once (a walk that scatters more adds more everywhere), so the evaluation's errors of
 * different bins are correlated, and for a sum of many fine bins that matters. Covariance:
 * the sampling's (r E on the diagonal) + the items' sample covariance of the bins' walk
 * integrals / ITEMS (ci, NULL when the evaluation is analytic) + the quadrature's error
 * and the float floor on the diagonal. Bins with fewer than GOF_MIN_EFF effective samples are
 * pooled into one (their items summed too). Statistic d^T C^-1 d by Cholesky. With
 * shifted, also lambda: the noncentrality of the shift (shifted - O) in the same metric. */
static double coarse_chi2(int ncc, const double *O, const double *S2, const double *E, const double *Q,
                          double (*ci)[NCOARSE], double N, double rg, int *dof, double *lambda, const double *shifted)
{
    int grp[NCOARSE], ng = 0, pool = -1;
    for (int c = 0; c < ncc; c++) {
        if (E[c] / rg >= GOF_MIN_EFF) grp[c] = ng++;
        else grp[c] = -1;
    }
    for (int c = 0; c < ncc; c++)
        if (grp[c] < 0 && (O[c] > 0 || E[c] > 0)) {
            if (pool < 0) pool = ng++;
            grp[c] = pool;
        }
    double go[NCOARSE + 1] = {0}, gs[NCOARSE + 1] = {0}, ge[NCOARSE + 1] = {0}, gq[NCOARSE + 1] = {0},
           gd[NCOARSE + 1] = {0};
    static double C[NCOARSE + 1][NCOARSE + 1], gi[ITEMS][NCOARSE + 1];
    memset(C, 0, sizeof C), memset(gi, 0, sizeof gi);
    for (int c = 0; c < ncc; c++) {
        int g = grp[c];
        if (g < 0) continue;
        go[g] += O[c], gs[g] += S2[c], ge[g] += E[c], gq[g] += Q[c];
        if (shifted) gd[g] += shifted[c] - O[c];
        if (ci)
            for (int it = 0; it < ITEMS; it++) gi[it][g] += ci[it][c];
    }
    for (int a = 0; a < ng; a++) {
        double r = go[a] > 0 ? gs[a] / go[a] : rg;
        C[a][a] = r * fmax(ge[a], rg) + gq[a] * gq[a] + 1e-12 * ge[a] * ge[a];
    }
    if (ci) {
        double m[NCOARSE + 1] = {0};
        for (int it = 0; it < ITEMS; it++)
            for (int a = 0; a < ng; a++) m[a] += gi[it][a] / ITEMS;
        for (int it = 0; it < ITEMS; it++)
            for (int a = 0; a < ng; a++)
                for (int b = 0; b < ng; b++)
                    C[a][b] += N * N * (gi[it][a] - m[a]) * (gi[it][b] - m[b]) / ((double)ITEMS * (ITEMS - 1));
    }
    /* Cholesky C = L L^T in place (lower triangle) */
    for (int j = 0; j < ng; j++) {
        double v = C[j][j];
        for (int k = 0; k < j; k++) v -= C[j][k] * C[j][k];
        C[j][j] = sqrt(fmax(v, 1e-300));
        for (int i = j + 1; i < ng; i++) {
            double u = C[i][j];
            for (int k = 0; k < j; k++) u -= C[i][k] * C[j][k];
            C[i][j] = u / C[j][j];
        }
    }
    double chi2 = 0, lam = 0, y[NCOARSE + 1], yl[NCOARSE + 1];
    for (int i = 0; i < ng; i++) {
        double u = go[i] - ge[i], ul = gd[i];
        for (int k = 0; k < i; k++) u -= C[i][k] * y[k], ul -= C[i][k] * yl[k];
        y[i] = u / C[i][i], yl[i] = ul / C[i][i];
        chi2 += y[i] * y[i], lam += yl[i] * yl[i];
    }
    *dof = ng;
    if (lambda) *lambda = lam;
    return chi2;
}

typedef struct {
    double O[NCELL], S2[NCELL];
} tally_t;

/* Added to the seeds of a case (the pilot's, the samples', the evaluation's). Lambertian
 * facets are mirror-symmetric: from below with the same seeds a case repeats its twin
 * from above bit for bit, so the cases from below take other seeds (independent data). */
static cl_uint seed_shift = 0;
static cl_uint seed_off = 0; /* argv[2]: added to every case's seeds (to see that the tolerances hold) */

static void gof(const gof_case *gc)
{
    const double th = gc->theta * PI / 180, wo[3] = {sin(th), 0.0, gc->side * cos(th)};
    lsqt_dev_layer L;
    memset(&L, 0, sizeof L);
    L.kind = gc->kind, L.iter_count = 1, L.multiple_scattering = gc->ms;
    L.p[0] = (float)gc->alpha, L.p[1] = (float)gc->p1, L.p[2] = (float)gc->p2, L.p[3] = (float)gc->p3;
    cl_mem bl = fixture_mem(sizeof L, &L);
    const int analytic = gc->kind != LSQT_BSDF_MS_LAMBERTIAN;
    /* Lambertian facets have no analytic part: even in single scattering the evaluation
     * is the walk's (its first vertex's next-event terms, harness_ms_eval) */
    const int walked = gc->ms || !analytic;
    const double N = (double)gc->n;
    char name[80];
    snprintf(name, sizeof name, "%s%s a=%.2g th=%g%s", gc->name, gc->ms ? "" : " single", gc->alpha, gc->theta,
             gc->side < 0 ? " below" : "");
    const double t_case = check_now();

    /* The bins, from an independent pilot run. */
    grid_t g;
    memset(&g, 0, sizeof g);
    g.nh = gc->nh, g.side = gc->side;
    float *smp = malloc((gc->n > GOF_NPILOT ? gc->n : GOF_NPILOT) * 16);
    k_sample(bl, wo, 977u + seed_off + seed_shift, GOF_NPILOT, smp);
    grid_from_pilot(&g, smp, GOF_NPILOT);
    if (gc->kind == LSQT_BSDF_MS_DIELECTRIC) {
        /* Refraction's half vector is horizontal where |cos theta_i| = cos theta_o / e (e the
         * relative index seen from wo): beyond it no visible facet refracts, and as GGX's
         * D stays finite at the horizon f jumps to 0 there; a bin edge goes on it. */
        double e = gc->side > 0 ? gc->p1 : 1 / gc->p1, mc = cos(th) / e;
        if (mc > 0 && mc < 1) {
            int k = 1;
            for (int i = 2; i < NMU; i++)
                if (fabs(g.mu[1][i] - mc) < fabs(g.mu[1][k] - mc)) k = i;
            g.mu[1][k] = mc;
        }
    }
    const int nc = g.nh * NMU * NPHI, ncc = nc / (COARSE * COARSE);

    /* The samples, and their skewed copy. */
    k_sample(bl, wo, 12345u + seed_off + seed_shift, gc->n, smp);
    static tally_t t[2]; /* plain, skewed */
    memset(t, 0, sizeof t);
    double sw[2] = {0, 0}, sw2[2] = {0, 0};
    int bad_dir = 0, bad_w = 0, outside = 0;
    for (size_t i = 0; i < gc->n; i++) {
        const float *s = smp + 4 * i;
        double w = s[3];
        if (!(w >= 0 && w <= 1 + 1e-6)) bad_w++;
        if (!(w > 0)) continue;
        double len = sqrt((double)s[0] * s[0] + (double)s[1] * s[1] + (double)s[2] * s[2]);
        if (!(fabs(len - 1) < 1e-4)) bad_dir++;
        int c = cell_of(&g, s);
        if (c < 0) outside++;
        for (int k = 0; k < 2; k++) {
            double v = k ? w * (1 + GOF_SKEW * s[0]) : w;
            sw[k] += v, sw2[k] += v * v;
            if (c >= 0) t[k].O[c] += v, t[k].S2[c] += v * v;
        }
    }
    CHECK(bad_dir == 0, "%s: %d exits are not unit vectors", name, bad_dir);
    CHECK(bad_w == 0, "%s: %d weights outside [0, 1]", name, bad_w);
    CHECK(outside == 0, "%s: %d exits on a side with no light", name, outside);

    /* Expected: the analytic single scattering, adaptively per bin. */
    static double E[NCELL], VE[NCELL], EQ[NCELL], CI[ITEMS][NCOARSE];
    memset(E, 0, sizeof E), memset(VE, 0, sizeof VE), memset(EQ, 0, sizeof EQ), memset(CI, 0, sizeof CI);
    const double rg = sw[0] > 0 ? sw2[0] / sw[0] : 1;
    if (analytic) {
        const gof_bins bins = {nc, &g, grid_rect, grid_dir};
        eval_ctx ec = {bl, wo};
        gof_integrate(&bins, eval_density, &ec, N, rg, E, EQ);
        for (int c = 0; c < nc; c++) E[c] *= N, EQ[c] *= N;
    }
    /* The conductor's single scattering: the samples' weights are f / pdf (the
     * dielectric's are f / pdf of the branch sampled, reflection or refraction). */
    if (!gc->ms && gc->kind == LSQT_BSDF_MS_CONDUCTIVE) {
        float *fp = malloc(gc->n * 8);
        k_eval(bl, wo, smp, gc->n, fp);
        int bad = 0;
        for (size_t i = 0; i < gc->n; i++) {
            double ratio = fp[2 * i + 1] > 0 ? fp[2 * i] / fp[2 * i + 1] : 0, w = smp[4 * i + 3];
            if (!(fabs(w - ratio) <= 1e-4 * ratio + 1e-6)) bad++;
        }
        CHECK(bad == 0, "%s: %d sample weights differ from f/pdf", name, bad);
        free(fp);
    }
    /* The walks' part: harness_ms_eval minus the single scattering, qm x qm nodes per bin,
     * per item (the spread of the items' bin integrals is the evaluation's noise; per
     * coarse bin and for the total from the items too, so correlations count). The
     * evaluation's layer runs ic walks per vertex (iter_count): the analytic single
     * scattering, the same for all, is then computed once per ic walks. */
    double tot_var_e = 0;
    if (walked) {
        const int most = 2 * nc * gc->qm * gc->qm;
        double(*d)[3] = malloc((size_t)most * sizeof *d), *wt = malloc((size_t)most * sizeof *wt);
        static int off[NCELL + 1];
        off[0] = 0;
        for (int c = 0; c < nc; c++) off[c + 1] = off[c] + ms_bin_nodes(&g, c, gc->qm, analytic && gc->alpha < 0.1, d + off[c], wt + off[c]);
        const int nn = off[nc];
        CHECK(nn <= NWI, "%s: %d nodes", name, nn);
        float *single = calloc((size_t)nn * 2, sizeof *single);
        if (analytic) {
            float *dirs = malloc((size_t)nn * 16);
            for (int q = 0; q < nn; q++)
                dirs[4 * q] = (float)d[q][0], dirs[4 * q + 1] = (float)d[q][1], dirs[4 * q + 2] = (float)d[q][2],
                dirs[4 * q + 3] = 0;
            k_eval(bl, wo, dirs, (size_t)nn, single);
            free(dirs);
        }
        lsqt_dev_layer Le = L;
        Le.iter_count = gc->ic;
        cl_mem ble = fixture_mem(sizeof Le, &Le);
        fixture_dirs md = ms_dirs_make(ble, (const double(*)[3])d, nn);
        float *out = malloc((size_t)ITEMS * PAD * sizeof *out);
        k_ms_eval(ble, wo, &md, 4242u + seed_off + seed_shift, gc->reps, out);
        static double a1[NCELL], a2[NCELL];
        memset(a1, 0, sizeof a1), memset(a2, 0, sizeof a2);
        double t1 = 0, t2 = 0;
        int nonfinite = 0;
        for (int it = 0; it < ITEMS; it++) {
            double tot = 0, *cc = CI[it];
            for (int c = 0; c < nc; c++) {
                double v = 0;
                for (int q = off[c]; q < off[c + 1]; q++) {
                    double f = out[(size_t)it * PAD + q];
                    if (!isfinite(f)) nonfinite++;
                    v += wt[q] * (f - single[2 * q]);
                }
                a1[c] += v, a2[c] += v * v, tot += v, cc[coarse_of(c)] += v;
            }
            t1 += tot, t2 += tot * tot;
        }
        CHECK(nonfinite == 0, "%s: %d non-finite evaluations", name, nonfinite);
        /* mean and variance of the mean over the items, scaled to N samples */
#define MEAN_VAR(s1, s2, m, v)                                                   \
    do {                                                                         \
        double mu_ = (s1) / ITEMS;                                               \
        (m) += N * mu_;                                                          \
        (v) = N * N * fmax(((s2) / ITEMS - mu_ * mu_) / (ITEMS - 1), 0.0);       \
    } while (0)
        double unused = 0;
        for (int c = 0; c < nc; c++) MEAN_VAR(a1[c], a2[c], E[c], VE[c]);
        MEAN_VAR(t1, t2, unused, tot_var_e);
        fixture_dirs_free(&md);
        clReleaseMemObject(ble);
        free(out), free(single), free(d), free(wt);
    }

    /* Chi-squares (fine, coarse) and totals, for the data and the skewed copy. The
     * evaluation's variance: the walks' spread, the quadrature's error estimate, and
     * 1e-6 relative for float (all as variances; the quadrature's errors added up with
     * their signs unknown, i.e. in absolute value, for coarse bins and the total). */
    double et = 0, ratio = 0, qt = 0, VEF[NCELL], QC[NCOARSE] = {0}, EC[NCOARSE] = {0};
    for (int c = 0; c < nc; c++) {
        et += E[c], qt += EQ[c], QC[coarse_of(c)] += EQ[c], EC[coarse_of(c)] += E[c];
        ratio = fmax(ratio, VE[c] / fmax(rg * E[c], rg * GOF_MIN_EFF));
        VEF[c] = VE[c] + EQ[c] * EQ[c] + 1e-12 * E[c] * E[c];
    }
    const double var_et = tot_var_e + qt * qt + 1e-12 * et * et;
    double pmin[2] = {1, 1}, chi[2], chic[2], z[2], pf[2], pc[2], pz[2], lam_c = 0;
    int dof[2], dofc[2];
    double OC[2][NCOARSE] = {{0}}, SC[2][NCOARSE] = {{0}};
    for (int k = 0; k < 2; k++)
        for (int c = 0; c < nc; c++) OC[k][coarse_of(c)] += t[k].O[c], SC[k][coarse_of(c)] += t[k].S2[c];
    for (int k = 0; k < 2; k++) {
        chi[k] = gof_chi2(nc, t[k].O, t[k].S2, E, VEF, rg, NULL, &dof[k], NULL);
        chic[k] = coarse_chi2(ncc, OC[k], SC[k], EC, QC, walked ? CI : NULL, N, rg, &dofc[k], k ? NULL : &lam_c,
                              OC[1]);
        double var_t = fmax(sw2[k] - sw[k] * sw[k] / N, 0.0) + var_et;
        z[k] = var_t > 0 ? (sw[k] - et) / sqrt(var_t) : (fabs(sw[k] - et) <= 1e-9 * N ? 0 : 1e9);
        pf[k] = chi2_p(chi[k], dof[k]), pc[k] = chi2_p(chic[k], dofc[k]), pz[k] = erfc(fabs(z[k]) / sqrt(2.0));
        pmin[k] = fmin(pf[k], fmin(pc[k], pz[k]));
    }
    /* Lambertian facets that transmit: the albedo of each hemisphere on its own (the sum
     * of the exits' weights there against N x the integral of f over it), since an error
     * that moves light between reflection and transmission (the fR : fT branch, the
     * escape after a crossing) can leave the total nearly as it was. Variance: the
     * sampling's (N var of w 1{h}) + the items' spread of the hemisphere's integral. */
    double za[2][2] = {{0, 0}, {0, 0}}, ea[2] = {0, 0}, oa[2] = {0, 0};
    const int albedo = !analytic && g.nh == 2;
    if (albedo) {
        double vea[2] = {0, 0};
        for (int h = 0; h < 2; h++) {
            double m1 = 0, m2 = 0;
            for (int it = 0; it < ITEMS; it++) {
                double v = 0;
                for (int cc = h * NCOARSE / 2; cc < (h + 1) * NCOARSE / 2; cc++) v += CI[it][cc];
                m1 += v / ITEMS, m2 += v * v / ITEMS;
            }
            vea[h] = N * N * fmax(m2 - m1 * m1, 0.0) / (ITEMS - 1);
            for (int c = h * NMU * NPHI; c < (h + 1) * NMU * NPHI; c++) ea[h] += E[c];
        }
        for (int k = 0; k < 2; k++)
            for (int h = 0; h < 2; h++) {
                double o = 0, o2 = 0;
                for (int c = h * NMU * NPHI; c < (h + 1) * NMU * NPHI; c++) o += t[k].O[c], o2 += t[k].S2[c];
                const double var = fmax(o2 - o * o / N, 0.0) + vea[h] + 1e-12 * ea[h] * ea[h];
                za[k][h] = var > 0 ? (o - ea[h]) / sqrt(var) : 0;
                if (!k) oa[h] = o;
                pmin[k] = fmin(pmin[k], erfc(fabs(za[k][h]) / sqrt(2.0)));
            }
    }
    char tn[112];
    snprintf(tn, sizeof tn, "%s: chi2 (%d bins)", name, dof[0]);
    gof_record(tn, pf[0]);
    snprintf(tn, sizeof tn, "%s: coarse chi2 (%d bins)", name, dofc[0]);
    gof_record(tn, pc[0]);
    snprintf(tn, sizeof tn, "%s: total", name);
    gof_record(tn, pz[0]);
    for (int h = 0; albedo && h < 2; h++) {
        snprintf(tn, sizeof tn, "%s: albedo %s", name, h ? "T" : "R");
        gof_record(tn, erfc(fabs(za[0][h]) / sqrt(2.0)));
        printf("%-32s albedo %s: mean w %.5f int f %.5f z=%+.2f | skewed z=%+.2f\n", name, h ? "T" : "R", oa[h] / N,
               ea[h] / N, za[0][h], za[1][h]);
    }
    /* The skew's expected effect, from the data: its shift of each coarse bin and of the
     * total against their sigmas (noncentralities). Where either is large the skewed copy
     * must be rejected: a total shifted by 10 sigma, or a coarse chi-square by 150 on about
     * 32 dof, falls below the threshold always. */
    const double lam_t = (sw[1] - sw[0]) * (sw[1] - sw[0]) / (fmax(sw2[0] - sw[0] * sw[0] / N, 0.0) + var_et);
    gof_skew(name, pmin[1], lam_c, lam_t >= 100 || lam_c >= 150);
    printf("%-32s chi2 %6.1f/%3d p=%.3f coarse %5.1f/%2d p=%.3f | mean w %.5f int f %.5f z=%+.2f | eval var/sample"
           " var <= %.2f | skewed: p %.1e (lambda %.0f, %.0f) | %.2f s\n",
           name, chi[0], dof[0], pf[0], chic[0], dofc[0], pc[0], sw[0] / N, et / N, z[0], ratio, pmin[1], lam_c,
           lam_t, check_now() - t_case);
    clReleaseMemObject(bl);
    free(smp);
}

/* ---------------------------------------------------------------- visible normals */

static const char *vndf_src =
    "__kernel void test_vndf(float alpha, float vx, float vy, float vz, uint seed, __global float *out)\n"
    "{\n"
    "    uint i = (uint)get_global_id(0);\n"
    "    rng_t rng = rng_init(seed, 0u, 3u, i, 9u);\n"
    "    real u1 = rng_uniform(&rng), u2 = rng_uniform(&rng);\n"
    "    real3 v = normalize(make_real3(vx, vy, vz));\n"
    "    ms_vtx x = ms_vertex((real)alpha, v, R(0.5), R(1.0), u1, u2);\n"
    "    out[4 * i] = (float)x.m.x; out[4 * i + 1] = (float)x.m.y; out[4 * i + 2] = (float)x.m.z;\n"
    "    out[4 * i + 3] = (float)dot(v, x.m);\n"
    "}\n"
    "__kernel void test_phase(__global const lsqt_dev_layer *l, float vx, float vy, float vz,\n"
    "                         __global const float *u, __global float *out)\n"
    "{\n"
    "    int i = (int)get_global_id(0);\n"
    "    ms_vtx x = ms_vertex(l->p[0], make_real3(vx, vy, vz), R(0.5), ms_index(l, R(1.0)), R(0.5), R(0.5));\n"
    "    dirv d = dirv_broadcast(make_real3(u[3 * i], u[3 * i + 1], u[3 * i + 2]));\n"
    "    realv f = l->kind == LSQT_BSDF_MS_DIELECTRIC ? dielectric_phasev(l, &x, d) : conductor_phasev(l, &x, d);\n"
    "    out[2 * i] = (float)f.x;\n"
    "    out[2 * i + 1] = (float)x.inv_area;\n"
    "}\n";

/* The facets' reflection phase function (a walk vertex's point estimate) is
 * kR F D(m) / (4 A(v)) <= kR D(normal) / (4 A(v)) = kR / (4 pi alpha^2 A(v)) for every u on
 * the ray's side: bounded. Checked where it is hardest to compute, u next to -v (a vertex
 * reached going up, v.z < 0, evaluated towards the way the ray was going): there v + u is
 * tiny and a form that divides by |v + u|^2 loses everything to rounding. v from a walk
 * that hit it (alpha 0.05, wo at 85 degrees: the first reflection blocked on its way out),
 * and others; u = -v and -v turned by 1e-7 .. 1e-2. */
static void test_phase_bound(cl_program vp)
{
    const double vs[][3] = {{0.997667551, -0.00477453042, -0.0680937693}, {0.9848078, 0.0, -0.1736482},
                            {0.7071068, 0.3, -0.6403124}, {0.2, -0.1, -0.9746794}};
    const int kinds[] = {LSQT_BSDF_MS_DIELECTRIC, LSQT_BSDF_MS_CONDUCTIVE};
    const double as[] = {0.05, 0.3}, eta[] = {1.5, 1 / 1.5};
    enum { NU = 1 + 6 * 8 };
    cl_kernel k = clCreateKernel(vp, "test_phase", NULL);
    float u[NU * 3], out[NU * 2];
    int n_bad_all = 0;
    double worst = 0;
    for (int ik = 0; ik < 2; ik++)
        for (int ia = 0; ia < 2; ia++)
            for (int ie = 0; ie < (ik ? 1 : 2); ie++)
            {
                int n_bad = 0, n_all = 0;
                double cw = 0, cv[3] = {0, 0, 0}, cu[3] = {0, 0, 0}, cf = 0, cb = 0;
                for (int iv = 0; iv < 4; iv++) {
                    lsqt_dev_layer L;
                    memset(&L, 0, sizeof L);
                    L.kind = kinds[ik], L.iter_count = 1, L.multiple_scattering = 1, L.p[0] = (float)as[ia];
                    if (ik) L.p[1] = 0.051585f, L.p[2] = 3.9046f;
                    else L.p[1] = (float)eta[ie], L.p[2] = 1, L.p[3] = 1;
                    float v[3] = {(float)vs[iv][0], (float)vs[iv][1], (float)vs[iv][2]};
                    int n = 0;
                    for (int c = 0; c < 3; c++) u[c] = -v[c];
                    n = 1;
                    for (int e = 0; e < 6; e++)
                        for (int j = 0; j < 8; j++, n++) {
                            double t = pow(10.0, -7.0 + e), ph = 2 * PI * j / 8, p[3], q[3], len = 0;
                            /* p: a unit vector normal to v, at azimuth ph */
                            double a0[3] = {-vs[iv][1], vs[iv][0], 0}, an = hypot(a0[0], a0[1]);
                            for (int c = 0; c < 3; c++) a0[c] /= an;
                            double b0[3] = {vs[iv][1] * a0[2] - vs[iv][2] * a0[1], vs[iv][2] * a0[0] - vs[iv][0] * a0[2],
                                            vs[iv][0] * a0[1] - vs[iv][1] * a0[0]};
                            for (int c = 0; c < 3; c++) p[c] = cos(ph) * a0[c] + sin(ph) * b0[c];
                            for (int c = 0; c < 3; c++) q[c] = -vs[iv][c] + t * p[c], len += q[c] * q[c];
                            for (int c = 0; c < 3; c++) u[3 * n + c] = (float)(q[c] / sqrt(len));
                        }
                    cl_mem bl = fixture_mem(sizeof L, &L), bu = fixture_mem(sizeof u, u), bo = fixture_mem(sizeof out, NULL);
                    const size_t sz[] = {sizeof bl, 4, 4, 4, sizeof bu, sizeof bo};
                    const void *val[] = {&bl, &v[0], &v[1], &v[2], &bu, &bo};
                    fixture_args(k, 6, sz, val);
                    fixture_launch(k, NU, 0);
                    fixture_read(bo, sizeof out, out);
                    for (int i = 0; i < NU; i++) {
                        if (!(u[3 * i + 2] > 0)) continue;
                        double bound = out[2 * i + 1] / (4 * PI * as[ia] * as[ia]), r = out[2 * i] / bound;
                        n_all++;
                        if (!(r <= 1.001)) {
                            n_bad++;
                            if (!(r <= cw)) {
                                cw = isfinite(r) ? r : 1e300, cf = out[2 * i], cb = bound;
                                for (int c = 0; c < 3; c++) cv[c] = v[c], cu[c] = u[3 * i + c];
                            }
                        }
                    }
                    clReleaseMemObject(bl), clReleaseMemObject(bu), clReleaseMemObject(bo);
                }
                CHECK(n_bad == 0,
                      "%s facets, alpha %.2g%s%.3g: the reflection phase function next to u = -v exceeds its bound "
                      "kR D(normal) / (4 A(v)) in %d of %d directions, worst %.6g against %.6g (%.3g times) at "
                      "v = (%.9f, %.9f, %.9f), u = (%.9f, %.9f, %.9f)",
                      ik ? "conductor" : "dielectric", as[ia], ik ? "" : ", e ", ik ? 0.0 : eta[ie], n_bad, n_all, cf,
                      cb, cw, cv[0], cv[1], cv[2], cu[0], cu[1], cu[2]);
                n_bad_all += n_bad;
                worst = fmax(worst, cw);
            }
    printf("reflection phase bound next to u = -v: %s (%d directions over it, largest ratio %.3g)\n",
           n_bad_all ? "VIOLATED" : "holds", n_bad_all, worst);
    clReleaseKernel(k);
}

/* Integral over phi in [p0, p1] of max(0, vz + b cos phi). */
static double phi_integral(double vz, double b, double p0, double p1)
{
    double lo[2], hi[2];
    int n = 0;
    if (b <= 0 || -vz / b <= -1) {
        lo[0] = p0, hi[0] = p1, n = 1;
    } else if (-vz / b < 1) {
        double psi = acos(-vz / b); /* positive on [0, psi) and (2 pi - psi, 2 pi] */
        lo[0] = fmax(p0, 0.0), hi[0] = fmin(p1, psi);
        lo[1] = fmax(p0, 2 * PI - psi), hi[1] = fmin(p1, 2 * PI);
        n = 2;
    }
    double s = 0;
    for (int i = 0; i < n; i++)
        if (hi[i] > lo[i]) s += vz * (hi[i] - lo[i]) + b * (sin(hi[i]) - sin(lo[i]));
    return s;
}

/* D_v over the bin [x0, x1] x [p0, p1], x = t / (1 + t), t = tan(theta_m) / alpha,
 * v = (vx, 0, vz), vx > 0: D(m) cos(theta_m) dw = t / (pi (1 + t^2)^2) dt dphi, and
 * v.m / m.z = vz + alpha t vx cos(phi). Split where the visible region's edge meets the
 * bin's (kinks), 12 Gauss nodes per piece. */
static double vndf_bin(double alpha, double vx, double vz, double x0, double x1, double p0, double p1)
{
    double gx[12], gw[12], cut[8];
    gauss_legendre(12, gx, gw);
    int nc = 0;
    cut[nc++] = x0;
    double tk[3] = {fabs(vz) / (alpha * vx), -vz / (alpha * vx * cos(p0)), -vz / (alpha * vx * cos(p1))};
    for (int i = 0; i < 3; i++) {
        if (!(tk[i] > 0) || !isfinite(tk[i])) continue;
        double xk = tk[i] / (1 + tk[i]);
        if (xk > x0 && xk < x1) cut[nc++] = xk;
    }
    cut[nc++] = x1;
    for (int i = 1; i < nc; i++) /* sort the few cuts */
        for (int j = i; j > 0 && cut[j] < cut[j - 1]; j--) {
            double tmp = cut[j];
            cut[j] = cut[j - 1], cut[j - 1] = tmp;
        }
    const double area = 0.5 * (vz + sqrt(vz * vz + alpha * alpha * (1 - vz * vz)));
    double s = 0;
    for (int k = 0; k + 1 < nc; k++) {
        double a = cut[k], b = cut[k + 1];
        for (int q = 0; q < 12; q++) {
            double x = 0.5 * (a + b) + 0.5 * (b - a) * gx[q], t = x / (1 - x), dtdx = 1 / ((1 - x) * (1 - x));
            double dens = t / (PI * (1 + t * t) * (1 + t * t));
            s += 0.5 * (b - a) * gw[q] * dtdx * dens * phi_integral(vz, alpha * t * vx, p0, p1);
        }
    }
    return s / area;
}

static int n_silhouette = 0;
static double max_silhouette = 0;

static void test_vndf(cl_program vp)
{
    const double alphas[] = {0.05, 0.3, 1.0, 2.4}, thv[] = {30, 80, 100, 135, 170};
    const size_t n = 400000;
    float *s = malloc(n * 16);
    cl_mem bo = fixture_mem(n * 16, NULL);
    cl_kernel k = clCreateKernel(vp, "test_vndf", NULL);
    for (int ia = 0; ia < 4; ia++)
        for (int iv = 0; iv < 5; iv++) {
            const double th = thv[iv] * PI / 180, vx = sin(th), vz = cos(th);
            float a = (float)alphas[ia], v[3] = {(float)vx, 0.0f, (float)vz};
            double xs[NMU + 1], ps[NPHI + 1];
            /* the float direction the kernel gets, for the reference */
            double vxf = v[0], vzf = v[2], vn = sqrt(vxf * vxf + vzf * vzf);
            vxf /= vn, vzf /= vn;
            for (int pass = 0; pass < 2; pass++) {
                cl_uint seed = pass ? 31337u + 10 * (cl_uint)(ia * 5 + iv) : 555u;
                size_t m = pass ? n : GOF_NPILOT;
                const size_t sz[] = {4, 4, 4, 4, sizeof seed, sizeof bo};
                const void *val[] = {&a, &v[0], &v[1], &v[2], &seed, &bo};
                fixture_args(k, 6, sz, val);
                fixture_launch(k, m, 0);
                fixture_read(bo, m * 16, s);
                if (!pass) {
                    xw *p = malloc(m * sizeof *p);
                    for (size_t i = 0; i < m; i++) {
                        double t = sqrt((double)s[4 * i] * s[4 * i] + (double)s[4 * i + 1] * s[4 * i + 1]) /
                                   (alphas[ia] * s[4 * i + 2]);
                        p[i].x = t / (1 + t), p[i].w = 1;
                    }
                    breakpoints(p, (int)m, 0.0, 1.0, NMU, GOF_MIX, xs);
                    for (size_t i = 0; i < m; i++) {
                        double ph = atan2(s[4 * i + 1], s[4 * i]);
                        p[i].x = ph < 0 ? ph + 2 * PI : ph, p[i].w = 1;
                    }
                    breakpoints(p, (int)m, 0.0, 2 * PI, NPHI, GOF_MIX, ps);
                    free(p);
                }
            }
            static double O[NMU * NPHI], S2[NMU * NPHI], E[NMU * NPHI], VE[NMU * NPHI];
            memset(O, 0, sizeof O), memset(VE, 0, sizeof VE);
            int invisible = 0, behind = 0, below = 0;
            for (size_t i = 0; i < n; i++) {
                const float *m = s + 4 * i;
                if (!(m[3] > 0)) invisible++;
                if (!(m[3] > -1e-6)) behind++;
                if (!(m[2] > 0)) below++;
                double t = sqrt((double)m[0] * m[0] + (double)m[1] * m[1]) / (alphas[ia] * m[2]);
                double ph = atan2(m[1], m[0]);
                if (ph < 0) ph += 2 * PI;
                O[find_bin(xs, NMU, t / (1 + t)) * NPHI + find_bin(ps, NPHI, ph)] += 1;
            }
            double tot = 0;
            for (int i = 0; i < NMU; i++)
                for (int j = 0; j < NPHI; j++) {
                    E[i * NPHI + j] = n * vndf_bin(alphas[ia], vxf, vzf, xs[i], xs[i + 1], ps[j], ps[j + 1]);
                    tot += E[i * NPHI + j];
                }
            memcpy(S2, O, sizeof O);
            int dof;
            double chi2 = gof_chi2(NMU * NPHI, O, S2, E, VE, 1.0, NULL, &dof, NULL);
            dof -= 1; /* the counts sum to n */
            double p = chi2_p(chi2, dof);
            char tn[112];
            snprintf(tn, sizeof tn, "visible normals a=%.2g v.z=%.3f", alphas[ia], vz);
            gof_record(tn, p);
            CHECK(fabs(tot / n - 1) < 1e-6, "%s: D_v integrates to %.9f", tn, tot / n);
            /* Normals exactly on the silhouette (v.m = 0 to rounding) come out of the float
             * sampler for v far below the horizon (the sliver it samples is then thin); a
             * walk that draws one is absorbed (a loss, of order the count / n). */
            CHECK(behind == 0 && below == 0 && invisible <= (int)(n / 1000),
                  "%s: %d normals with v.m <= 0 (%d below -1e-6), %d with m.z <= 0", tn, invisible, behind, below);
            n_silhouette += invisible;
            max_silhouette = fmax(max_silhouette, (double)invisible / n);
            printf("%-36s chi2 %6.1f/%3d p=%.3f  (D_v sums to %.8f; v.m <= 0: %d)\n", tn, chi2, dof, p, tot / n,
                   invisible);
        }
    clReleaseKernel(k);
    clReleaseMemObject(bo);
    free(s);
}

/* ---------------------------------------------------------------- reciprocity */

static void unit(double th_deg, double ph_deg, double z_sign, double d[3])
{
    double th = th_deg * PI / 180, ph = ph_deg * PI / 180;
    d[0] = sin(th) * cos(ph), d[1] = sin(th) * sin(ph), d[2] = z_sign * cos(th);
}

/* f(wo -> wi) by harness_ms_eval with wi alone: the mean and the variance of the mean. */
static void ms_value(cl_mem bl, const double wo[3], const double wi[3], cl_uint seed, int reps, double *m, double *v)
{
    fixture_dirs md = ms_dirs_make(bl, (const double(*)[3])wi, 1);
    static float out[ITEMS * PAD];
    k_ms_eval(bl, wo, &md, seed, reps, out);
    double s1 = 0, s2 = 0;
    for (int i = 0; i < ITEMS; i++) s1 += out[(size_t)i * PAD], s2 += (double)out[(size_t)i * PAD] * out[(size_t)i * PAD];
    *m = s1 / ITEMS;
    *v = fmax((s2 / ITEMS - *m * *m) / (ITEMS - 1), 0.0);
    fixture_dirs_free(&md);
}

#define NPAIR 20
#define Z_PAIR 4.5
static int n_pairs = 0, n_over3 = 0;
static double z_max = 0;

/* NPAIR pairs (a, b), a on side sa and b on side sb (+1 above, -1 below), each value from
 * its own launch (independent z): na^2 f(a->b)/|cos b| against nb^2 f(b->a)/|cos a|. */
static void reciprocity(const char *name, const lsqt_dev_layer *L, double sa, double sb, double na, double nb,
                        int reps, int ic, cl_uint seed)
{
    lsqt_dev_layer LL = *L;
    LL.iter_count = ic;
    cl_mem bl = fixture_mem(sizeof LL, &LL);
    double chi2 = 0, rel = 0;
    int over3 = 0;
    for (int i = 0; i < NPAIR; i++) {
        /* spread over the hemispheres: theta 8..86 degrees, golden-angle azimuths */
        double a[3], b[3];
        unit(8 + 78 * fmod(0.618034 * (i + 1), 1.0), 137.50776 * i, sa, a);
        unit(8 + 78 * fmod(0.414214 * (i + 1) + 0.3, 1.0), 137.50776 * i + 73, sb, b);
        double fab, vab, fba, vba;
        ms_value(bl, a, b, seed + 2 * (cl_uint)i, reps, &fab, &vab);
        ms_value(bl, b, a, seed + 2 * (cl_uint)i + 1, reps, &fba, &vba);
        double x = na * na * fab / fabs(b[2]), y = nb * nb * fba / fabs(a[2]);
        double sx = na * na * sqrt(vab) / fabs(b[2]), sy = nb * nb * sqrt(vba) / fabs(a[2]);
        double s = sqrt(sx * sx + sy * sy), z = s > 0 ? (x - y) / s : 0;
        CHECK(s > 0 && fabs(z) < Z_PAIR, "%s pair %d: a = (%.6f, %.6f, %.6f), b = (%.6f, %.6f, %.6f): %.6g vs %.6g, z = %.2f",
              name, i, a[0], a[1], a[2], b[0], b[1], b[2], x, y, z);
        chi2 += z * z;
        rel += s / (0.5 * (x + y)) / NPAIR;
        if (fabs(z) > 3) over3++;
        z_max = fmax(z_max, fabs(z));
    }
    n_pairs += NPAIR, n_over3 += over3;
    double p = chi2_p(chi2, NPAIR);
    char tn[112];
    snprintf(tn, sizeof tn, "reciprocity %s: sum z^2", name);
    gof_record(tn, p);
    printf("%-44s sum z^2 %5.1f/%d p=%.3f, %d over 3 sigma, mean sigma/value %.2g\n", name, chi2, NPAIR, p, over3, rel);
    clReleaseMemObject(bl);
}

/* ---------------------------------------------------------------- main */

static lsqt_dev_layer layer(int kind, double alpha, double p1, double p2, double p3)
{
    lsqt_dev_layer L;
    memset(&L, 0, sizeof L);
    L.kind = kind, L.iter_count = 1, L.multiple_scattering = 1;
    L.p[0] = (float)alpha, L.p[1] = (float)p1, L.p[2] = (float)p2, L.p[3] = (float)p3;
    return L;
}

/* Roulette inside a walk: a walk whose weight falls below LSQT_RR_WEIGHT (0.25) survives
 * with probability weight / 0.25 and then carries exactly 0.25. On Lambertian facets with
 * fR = 0.5 (fT = 0) a walk's weight is 0.5 after one bounce, 0.25 after two, and every
 * later bounce takes it below 0.25 and back to exactly 0.25 by roulette: every exit
 * weight is 0.5 or 0.25, never less (a survivor left at its small weight is biased). */
static void test_walk_roulette(void)
{
    lsqt_dev_layer L = layer(LSQT_BSDF_MS_LAMBERTIAN, 2.4, 0.5, 0.0, 0.0);
    cl_mem bl = fixture_mem(sizeof L, &L);
    const size_t n = 200000;
    float *s = malloc(n * 16);
    const double wo[3] = {sin(1.0), 0.0, cos(1.0)};
    k_sample(bl, wo, 77u, n, s);
    size_t below = 0, at_half = 0, at_quarter = 0, zero = 0;
    for (size_t i = 0; i < n; i++) {
        float w = s[4 * i + 3];
        if (w == 0.0f) zero++;
        else if (w == 0.5f) at_half++;
        else if (w == 0.25f) at_quarter++;
        else below++;
    }
    CHECK(below == 0, "walk roulette: %zu of %zu exits weigh neither 0.5 nor 0.25 (nor 0)", below, n);
    CHECK(at_half > n / 10 && at_quarter > n / 20 && zero > 0,
          "walk roulette: %zu exits of weight 0.5, %zu of 0.25, %zu absorbed: all kinds expected", at_half,
          at_quarter, zero);
    free(s);
    clReleaseMemObject(bl);
}

/* Which goodness-of-fit cases run: the release suite takes half of the grid (alphas and
 * angles alternating, so every alpha and every angle is in it), the power tier (ctest label
 * "power") the other half; no argument runs them all. */
static int part_release = 1, part_power = 1;
static int case_runs(int ia, int it) { return (ia + it) % 2 == 0 ? part_release : part_power; }

int main(int argc, char **argv)
{
    double t_start = check_now();
    if (argc > 1) {
        part_release = strcmp(argv[1], "release") == 0;
        part_power = strcmp(argv[1], "power") == 0;
        if ((!part_release && !part_power) || argc > 3) {
            fprintf(stderr, "usage: test_ms_models [release|power [SEED_OFFSET]]\n");
            return 2;
        }
        if (argc == 3) seed_off = (cl_uint)strtoul(argv[2], NULL, 10);
    }
    fixture_open();
    prog = fixture_build("-cl-std=CL1.2 -DLSQT_HAS_BSDF_MS_LAMBERTIAN=1 -DLSQT_HAS_BSDF_MS_DIELECTRIC=1 "
                         "-DLSQT_HAS_BSDF_MS_CONDUCTIVE=1 -DLSQT_NWI=%d",
                         NWI);
    if (!prog) return check_finish("test_ms_models");
    /* The visible-normal sampler alone: the kernel sources plus one kernel of this test's
     * (ms_vertex, as the walk calls it). */
    cl_program vp =
        fixture_build_with(vndf_src, "-cl-std=CL1.2 -DLSQT_HAS_BSDF_MS_DIELECTRIC=1 -DLSQT_HAS_BSDF_MS_CONDUCTIVE=1");
    printf("builds %.1f s\n", check_now() - t_start);
    if (part_release) test_walk_roulette();

    /* The cases. Walks for the evaluations: Lambertian facets have no analytic part, so
     * every vertex of every walk evaluates (ITEMS x 500 walks); for the conductor and the
     * dielectric only orders >= 2 do, and at alpha 0.05 those are rare and sharp (a spike
     * of width alpha around each second vertex's mirror direction), so it takes many walks
     * (ITEMS x 320 x 32) and 3 x 3 nodes per bin; 20 x 32 per item at alpha >= 1. */
    const double alphas[] = {0.05, 0.3, 1.0, 2.4}, thetas[] = {0, 60, 85};
    const size_t NS = 1000000;
    double t0 = check_now();
    for (int ia = 0; ia < 4; ia++)
        for (int it = 0; it < 3; it++) {
            if (!case_runs(ia, it)) continue;
            const double a = alphas[ia], th = thetas[it];
            const int reps = a < 0.1 ? 320 : a < 0.5 ? 40 : 20, qm = a < 0.1 ? 3 : 2;
            gof_case lam = {"Lambertian", LSQT_BSDF_MS_LAMBERTIAN, a, 0.7, 0.25, 0, 1, th, 1, 2, NS, 500, 1, 2};
            gof(&lam);
            gof_case con = {"Conductor", LSQT_BSDF_MS_CONDUCTIVE, a, 0.051585, 3.9046, 0, 1, th, 1, 1, NS, reps, 32, qm};
            gof(&con);
            con.ms = 0;
            gof(&con);
            for (int side = 1; side >= -1; side -= 2) {
                gof_case die = {"Dielectric", LSQT_BSDF_MS_DIELECTRIC, a, 1.5, 1, 1, 1, th, side, 2, NS, reps, 32, qm};
                gof(&die);
                die.ms = 0;
                gof(&die);
            }
            /* Lambertian facets that transmit, in single scattering: the exit is the walk's
             * analog escape after its first vertex (through the facets or not), the
             * evaluation its next-event terms, which average that escape analytically
             * (mslambert_firstv); fT > fR so that most light crosses. From both sides.
             * Single-vertex walks are cheap: 4 x 10^6 exits, so that a 2 % change of the
             * lobe's shape (not only of an albedo) is seen. */
            for (int side = 1; side >= -1; side -= 2) {
                gof_case ls = {"Lambertian", LSQT_BSDF_MS_LAMBERTIAN, a, 0.35, 0.6, 0, 0, th, side, 2, 4 * NS, 500, 1, 2};
                seed_shift = side < 0 ? 7919u : 0u;
                gof(&ls);
                seed_shift = 0;
            }
        }
    /* Lambertian facets that only reflect, fR = 1: a furnace (every weight is 1, the
     * evaluation must integrate to 1), at 85 degrees. */
    for (int ia = 0; ia < 4; ia++) {
        if (!case_runs(ia, 1)) continue;
        gof_case lam = {"Lambertian fR=1", LSQT_BSDF_MS_LAMBERTIAN, alphas[ia], 1.0, 0.0, 0, 1, 85, 1, 1, NS, 500, 1, 2};
        gof(&lam);
    }
    printf("goodness of fit %.1f s\n", check_now() - t0);
    t0 = check_now();
    if (vp && part_release) test_vndf(vp), test_phase_bound(vp);
    if (vp) clReleaseProgram(vp);
    printf("visible normals %.1f s\n", check_now() - t0);
    t0 = check_now();
    /* walks per value: ITEMS x reps x iter_count (the dielectric's values are noisier) */
    for (int ia = 1; ia <= 2 && part_release; ia++) {
        const double a = alphas[ia];
        char nm[64];
        lsqt_dev_layer lam = layer(LSQT_BSDF_MS_LAMBERTIAN, a, 0.7, 0.25, 0);
        lsqt_dev_layer con = layer(LSQT_BSDF_MS_CONDUCTIVE, a, 0.051585, 3.9046, 0);
        lsqt_dev_layer die = layer(LSQT_BSDF_MS_DIELECTRIC, a, 1.5, 1, 1);
        /* model, what, sides of a and b, indices there, normals per item, walks per vertex, seed */
        const struct {
            const lsqt_dev_layer *L;
            const char *what;
            double sa, sb, na, nb;
            int reps, ic;
            cl_uint seed;
        } rc[] = {{&lam, "Lambertian a=%.1f R above", 1, 1, 1, 1, 200, 1, 1},
                  {&lam, "Lambertian a=%.1f R below", -1, -1, 1, 1, 200, 1, 101},
                  {&lam, "Lambertian a=%.1f T", 1, -1, 1, 1, 200, 1, 201},
                  {&con, "Conductor a=%.1f R", 1, 1, 1, 1, 200, 1, 301},
                  {&die, "Dielectric a=%.1f R above", 1, 1, 1, 1, 150, 4, 401},
                  {&die, "Dielectric a=%.1f R below", -1, -1, 1.5, 1.5, 150, 4, 501},
                  {&die, "Dielectric a=%.1f T (n^2 f)", 1, -1, 1, 1.5, 150, 4, 601}};
        for (int r = 0; r < 7; r++) {
            snprintf(nm, sizeof nm, rc[r].what, a);
            reciprocity(nm, rc[r].L, rc[r].sa, rc[r].sb, rc[r].na, rc[r].nb, rc[r].reps, rc[r].ic, 1000u * ia + rc[r].seed);
        }
    }
    printf("reciprocity %.1f s: %d pairs, %d over 3 sigma (%.1f expected by chance), largest |z| %.2f\n", check_now() - t0,
           n_pairs, n_over3, 0.0027 * n_pairs, z_max);

    /* The family: Bonferroni over every p-value recorded. */
    gof_verdict(0, "weights times 1 + 0.02 x");
    printf("visible normals on the silhouette (v.m <= 0): %d in all, at most a fraction %.2g\n", n_silhouette,
           max_silhouette);
    printf("total %.1f s, kernels %.1f s\n", check_now() - t_start, fixture_kernel_s);
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_ms_models");
}
