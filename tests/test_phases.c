/* The phase functions (Henyey-Greenstein and its two-lobe mixture, Rayleigh with
 * depolarisation, SGGX specular and diffuse microflakes) and the Oren-Nayar BRDF, through
 * the harness kernels (the code the walk runs), and lossless stacks end to end. Release,
 * 2 cores: about 60 s (half of it the stochastic diffuse SGGX evaluations).
 *
 * 1. Goodness of fit of every sampler (harness_sample) against its own evaluation:
 *    HG2 (g0, g1, b) = (0.9, -0.5, 0.3), (0, 0.95, 0.5), (-0.95, 0.95, 1); Rayleigh
 *    rho = -1, 0, 0.5, 1; SGGX specular and diffuse with Apara / Aperp = 0.1, 1, 10 at
 *    0, 60, 89 degrees from the z axis (the flakes' phase depends on absolute
 *    directions); Oren-Nayar (fR 0.7) sigma = 0, 0.3, 0.8 at 0, 60, 85 degrees, and 0.3
 *    at 120 degrees (from below). 10^6 samples each. Bins: a 16 x 16 product grid in
 *    (mu, phi) about an axis (-wo, the forward direction, for HG2 and Rayleigh; z for
 *    SGGX; for Oren-Nayar the normal on wo's side, the grid covering that hemisphere),
 *    with breakpoints at quantiles of 0.4 uniform + 0.6 an independent pilot run's
 *    samples, so bins crowd where the lobe is; forced edges where the value has a kink
 *    (SGGX: the horizon; Oren-Nayar: |cos theta_i| = |cos theta_o| and the azimuths where
 *    wo'.wi' changes sign). Expected content of a bin, E = N x the integral
 *    of the evaluation over it: for the deterministic evaluations (harness_eval) by
 *    adaptive Gauss-Legendre (8 x 8 rules against their quarters', to 2 % of the bin's
 *    sampling sigma; the difference is kept as the quadrature's error); for diffuse SGGX
 *    (one visible normal per vertex: stochastic) by 3 x 3 Gauss nodes per bin of
 *    harness_phase_mc, each node 8 independent work-items of 2000 normals, whose spread
 *    gives the evaluation's variance, added to the denominators (3 x 3 nodes leave a
 *    quadrature bias of about 1e-4 of the total, 2 x 2 left 5e-4: small against a bin's
 *    1.6 % sampling sigma). Observed: the sum of the weights per bin (1 for the exact
 *    phase samplers; f / pdf for Oren-Nayar, whose sampler is cosine weighted). Tests per
 *    case: chi-square on the fine bins, sum (O - E)^2 / (r E + var_E) with
 *    r = sum w^2 / sum w (bins under 25 effective samples pooled; dof = bins, less 1 where
 *    every weight is 1 and the total is fixed), the same on 4 x 4 blocks of bins, and for
 *    Oren-Nayar the total (sum of weights against N x the albedo). The weight equals
 *    f / pdf at every sample (deterministic evaluations; 1 for every phase sampler). All
 *    p-values of the file form one family, Bonferroni corrected: reject below
 *    1e-3 / (number of tests).
 *    Power, kept as a self-check: the samples reweighted by a 2 % tilt along the grid's mu
 *    axis, 1 + 0.02 (2 c - 1) with c the pilot's distribution function at the sample's mu
 *    (about uniform under the sampler, whatever the lobe), renormalised so that the total
 *    stays (a skewed sampler, not a scaled one), must be rejected wherever its
 *    noncentrality on the coarse bins is 100 or more (every case here: about 115-125).
 * 2. Normalisation: every phase integrates to 1 over the sphere within 1e-4 (deterministic
 *    evaluations, by the adaptive rule over the bins, whose error estimate is printed; HG
 *    and HG2 at g = +-0.999 on panels in log q) or 1e-3 (diffuse SGGX, by the stochastic
 *    evaluation, whose standard error must be 2.5e-4 or less: 1e-3 is 4 sigma). Oren-Nayar
 *    integrates to its directional albedo, equal to an independent double-precision
 *    integral of the formula written here (Gauss-Legendre in theta and phi split at the
 *    kinks, 24 and 48 nodes agreeing to 1e-10), within 2e-5 relative. The formula, as
 *    published, is not energy conserving at grazing angles: its albedo at sigma 0.1,
 *    80 degrees is 1.005 (fR = 1), reproduced by the formula and by the kernel.
 * 3. Limits and closed forms: HG2 with b = 0 is HG(g0) exactly (values and samples, bit
 *    for bit); Rayleigh rho = 1 is isotropic 1/(4 pi), rho = 0 is 3 / (16 pi) (1 + cos^2)
 *    (relative 1e-6); SGGX specular with Apara = Aperp is 1/(4 pi) (1e-5); SGGX diffuse
 *    with Apara = Aperp is the diffuse sphere, p = 2 / (3 pi^2) (sin a + (pi - a) cos a), a
 *    the angle between wo and wi, both pointing away from the vertex (a = 0 straight
 *    back), whose closed form is first checked to integrate to 1 (within 4 sigma of the
 *    stochastic evaluation, 64 items of 5000 normals per value, relative sigma < 1 %);
 *    Oren-Nayar with sigma = 0 is Lambertian fR |cos theta_i| / pi, and 0 on the other
 *    side. SGGX specular next to the forward direction wi = -wo (1e-7 .. 1e-2 rad from it,
 *    where h = wo + wi nearly vanishes) stays finite and below its bound
 *    max D / (4 sigma(wo)); at wi = -wo exactly (h = 0, no limit) the value is only printed.
 * 4. Peaks in float, g = +-0.999: HG and HG2 values at the forward and backward peaks and
 *    1e-4 .. pi rad from them against the textbook formula in double (relative 1e-4), and
 *    the samplers' distribution of q = 1 - cos t about each peak axis, binned 4 per decade
 *    down to 1e-9 (about 1000 of the 10^6 samples fall below 1e-9), against the exact CDF
 *    (chi-square): the peak is resolved.
 * 5. Rayleigh sampler: the CDF at the sampled mu is uniform (Kolmogorov-Smirnov, 10^6
 *    samples) for rho = -1, -0.5, 0, 0.5, 1.
 * 6. Reciprocity: Oren-Nayar f(a->b) / |cos b| = f(b->a) / |cos a| (relative 1e-5, 300
 *    pairs above and below); SGGX specular sigma(a) p(a->b) = sigma(b) p(b->a) (= D(h) / 4:
 *    the microflake reciprocity, with the projected area sigma; p(a->b) = p(b->a) only
 *    where sigma is constant, which the test also shows: up to 0.9 apart at Apara / Aperp
 *    0.1 and 10); SGGX diffuse the same with the stochastic evaluation (each value from
 *    its own launch, 64 items of 2500 normals: |z| < 4, and the sum of z^2 in the family).
 * 7. Lossless stacks conserve energy: a slab of HG2 (0.8, -0.3, 0.3) and one of diffuse
 *    SGGX (Apara 0.3) between null layers, 10^5 paths at 0, 45, 80 degrees: R + T = 1
 *    within 4 sigma (exit tallies), and the point estimates agree with the exits: NEE
 *    reflectance = R, NEE transmittance = T - delta_T (the unscattered forward delta is no
 *    point estimate), within 4 sigma (batch means of the difference on the same paths)
 *    plus the quadrature error of the direction rule, bounded by the difference between
 *    1024 and 256 directions on the same paths (required below 2 % of the value).
 * 8. Draine (section draine): the sampler against the value for (g, alpha) = (0, 1),
 *    (0.7, 0.5), (-0.5, 3), (0.95, 20) as in 1 (normalisation to 1e-4 included); the value
 *    against the formula in double; alpha = 0 is HG bit for bit; g = 0, alpha = 1 is
 *    Rayleigh rho = 0; a lossless Draine slab as in 7.
 * 9. TabulatedPhase (section tabulated), tables made here as a Mie code writes them
 *    (cos theta descending from 1 to -1, uniform in theta) and read by the host's parser:
 *    HG g = 0.7 and Rayleigh rho = 0 at 2001 rows evaluate within the interpolation error
 *    of their closed forms (relative 2e-4) and as the host's own interpolation in double
 *    (relative 1e-5, float); the sampler against its own interpolated density (goodness of
 *    fit as in 1, normalisation to 1e-4) for those two and a coarse 6-row table whose
 *    interpolation is far from any closed form (a zero row included); a stack of the HG
 *    table over the Rayleigh one against the same stack with HenyeyGreensteinPhase g = 0.7
 *    over RayleighPhase (the reference: the closed-form models), same seeds, R and T per
 *    slice within 4 sigma of the batch means of the paired difference plus the
 *    interpolation's 2e-4, a test that sees 1 %, in float and in double (--double); the
 *    coarse table in a slab as in 7.
 * usage: test_phases [SECTION...] (all by default; sections: hg2 rayleigh sggx-specular
 * sggx-diffuse oren-nayar peaks rayleigh-ks limits reciprocity stacks draine tabulated). */
#include <stdint.h>

#include "cl_fixture.h"
#include "gof.h"
#include "lsqt/tables.h"
#include "lsqt/util.h"
#include "nee_albedo.h"
#include "quadrature.h"
#include "stats.h"

#define PI 3.14159265358979323846
#ifndef QM
#define QM 3 /* Gauss nodes per bin side, stochastic evaluation */
#endif
#ifndef MC_K
#define MC_K 8 /* independent items per direction, stochastic evaluation */
#endif
#define NS 1000000
#define N_FAMILY 106 /* p-values of a full run: the Bonferroni divisor of every run, full or a section */

static cl_program prog;

/* ---------------------------------------------------------------- kernels */

typedef struct {
    char name[96];
    int use_phase; /* 1: the medium's phase function, 0: the layer's BSDF */
    int mc;        /* evaluation by harness_phase_mc (diffuse SGGX) */
    lsqt_dev_layer L;
    lsqt_dev_medium M;
    float wo[3];
    const float *tab; /* the medium's table (TabulatedPhase), put after it in its buffer */
    size_t tab_reals;
} model_t;

/* The medium's buffer: the medium, then its table as the host lays them out
 * (include/lsqt/tables.h). */
static cl_mem medium_mem(const model_t *m)
{
    const size_t bytes = sizeof m->M + m->tab_reals * sizeof(float);
    unsigned char *buf = malloc(bytes);
    memcpy(buf, &m->M, sizeof m->M);
    if (m->tab_reals) memcpy(buf + sizeof m->M, m->tab, m->tab_reals * sizeof(float));
    cl_mem r = fixture_mem(bytes, buf);
    free(buf);
    return r;
}

/* harness_sample: n samples (x, y, z, weight) for m->wo; harness_eval: (value, pdf) at n
 * directions (x, y, z, 0) for wo. */
static void k_sample(const model_t *m, cl_uint seed, size_t n, float *out)
{
    cl_mem bl = fixture_mem(sizeof m->L, &m->L), bm = medium_mem(m);
    fixture_harness_sample(prog, bl, bm, m->use_phase, m->wo, seed, n, out);
    clReleaseMemObject(bl), clReleaseMemObject(bm);
}

static void k_eval(const model_t *m, const float wo[3], const float *dirs, size_t n, float *out)
{
    cl_mem bl = fixture_mem(sizeof m->L, &m->L), bm = medium_mem(m);
    fixture_harness_eval(prog, bl, bm, m->use_phase, wo, dirs, n, out);
    clReleaseMemObject(bl), clReleaseMemObject(bm);
}

/* harness_phase_mc: out[i] = the mean of reps vertex evaluations towards direction i. */
static void k_mc(const model_t *m, const float wo[3], const float *dirs, size_t n, cl_uint seed, cl_int reps,
                 float *out)
{
    cl_mem bm = medium_mem(m), bd = fixture_mem(n * 16, dirs), bo = fixture_mem(n * 4, NULL);
    cl_kernel k = clCreateKernel(prog, "harness_phase_mc", NULL);
    const size_t sz[] = {sizeof bm, 4, 4, 4, sizeof bd, sizeof seed, sizeof reps, sizeof bo};
    const void *val[] = {&bm, &wo[0], &wo[1], &wo[2], &bd, &seed, &reps, &bo};
    fixture_args(k, 8, sz, val);
    fixture_launch(k, n, 0);
    fixture_read(bo, n * 4, out);
    clReleaseKernel(k);
    clReleaseMemObject(bm), clReleaseMemObject(bd), clReleaseMemObject(bo);
}

static cl_uint mc_seed = 1000;

/* The stochastic evaluation towards nd directions (x, y, z, 0): MC_K independent
 * work-items of reps normals each per direction; the mean and the variance of the mean. */
static void mc_eval_k(const model_t *m, const float wo[3], const float *dirs, size_t nd, int K, int reps,
                      double *mean, double *var)
{
    const size_t n = nd * (size_t)K;
    float *d = malloc(n * 16), *o = malloc(n * 4);
    for (size_t k = 0; k < (size_t)K; k++) memcpy(d + 4 * k * nd, dirs, nd * 16);
    k_mc(m, wo, d, n, mc_seed++, reps, o);
    for (size_t j = 0; j < nd; j++) {
        double s = 0, ss = 0;
        for (size_t k = 0; k < (size_t)K; k++) s += o[k * nd + j];
        s /= K;
        for (size_t k = 0; k < (size_t)K; k++) ss += (o[k * nd + j] - s) * (o[k * nd + j] - s);
        mean[j] = s;
        var[j] = ss / (K - 1) / K;
    }
    free(d), free(o);
}

static void mc_eval(const model_t *m, const float wo[3], const float *dirs, size_t nd, int reps, double *mean,
                    double *var)
{
    mc_eval_k(m, wo, dirs, nd, MC_K, reps, mean, var);
}

/* ---------------------------------------------------------------- models */

static model_t phase_model(const char *name, int kind, double p0, double p1, double p2, const double wo[3])
{
    model_t m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    m.use_phase = 1;
    m.M.eta = 1, m.M.mus = 1, m.M.mut = 1, m.M.phase_kind = kind;
    m.M.pp[0] = (float)p0, m.M.pp[1] = (float)p1, m.M.pp[2] = (float)p2;
    for (int i = 0; i < 3; i++) m.wo[i] = (float)wo[i];
    return m;
}

static model_t hg2_model(double g0, double g1, double b, const double wo[3])
{
    char nm[96];
    snprintf(nm, sizeof nm, "HG2 (%g, %g, %g)", g0, g1, b);
    return phase_model(nm, LSQT_PHASE_HG2, g0, g1, b, wo);
}

static model_t rayleigh_model(double rho, const double wo[3])
{
    char nm[96];
    snprintf(nm, sizeof nm, "Rayleigh rho=%g", rho);
    return phase_model(nm, LSQT_PHASE_RAYLEIGH, rho / (2 - rho), 0, 0, wo); /* gamma, as the host passes it */
}

/* Draine (g, alpha): the table holds {g, alpha, 1 / (1 + alpha (1 + 2 g^2) / 3)}, the
 * normalisation written here from HG's mean cos^2 = (1 + 2 g^2) / 3 (docs/design.md 1.2). */
static model_t draine_model(double g, double alpha, const double wo[3])
{
    char nm[96];
    snprintf(nm, sizeof nm, "Draine (g %g, alpha %g)", g, alpha);
    return phase_model(nm, LSQT_PHASE_DRAINE, g, alpha, 1 / (1 + alpha * (1 + 2 * g * g) / 3), wo);
}

/* Apara / Aperp = ratio; the table holds S / a^2 with a = max(Apara, Aperp), as the host
 * makes it. */
static model_t sggx_model(double ratio, int diffuse, double theta_deg)
{
    double th = theta_deg * PI / 180, wo[3] = {sin(th), 0.0, cos(th)};
    double ap = ratio <= 1 ? ratio : 1, an = ratio <= 1 ? 1 : 1 / ratio;
    char nm[96];
    snprintf(nm, sizeof nm, "SGGX %s Apara/Aperp=%g th=%g", diffuse ? "diffuse" : "specular", ratio, theta_deg);
    model_t m = phase_model(nm, LSQT_PHASE_SGGX, ap * ap, an * an, diffuse ? 1 : 0, wo);
    m.mc = diffuse;
    return m;
}

static model_t oren_nayar_model(double fr, double sigma, double theta_deg)
{
    model_t m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "Oren-Nayar sigma=%g th=%g", sigma, theta_deg);
    m.L.kind = LSQT_BSDF_OREN_NAYAR, m.L.iter_count = 1;
    m.L.p[0] = (float)fr, m.L.p[1] = (float)sigma;
    double th = theta_deg * PI / 180;
    m.wo[0] = (float)sin(th), m.wo[1] = 0, m.wo[2] = (float)cos(th);
    return m;
}

/* The formula of the Oren-Nayar "simpler expression", written here in double (the
 * reference): f = fR |cos i| / pi [A + B max(wo'.wi', 0) / max(|cos o|, |cos i|)], on wo's
 * side only. */
static double oren_nayar_ref(double fr, double s, const double o[3], const double i[3])
{
    if (!(o[2] * i[2] > 0)) return 0;
    double A = 1 - 0.5 * s * s / (s * s + 0.33), B = 0.45 * s * s / (s * s + 0.09);
    double t = fmax(o[0] * i[0] + o[1] * i[1], 0.0);
    return fr * fabs(i[2]) / PI * (A + B * t / fmax(fabs(o[2]), fabs(i[2])));
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* wo as the kernel gets it (float), normalised in double */
static void wo_double(const float *wo, double *o)
{
    double n = sqrt((double)wo[0] * wo[0] + (double)wo[1] * wo[1] + (double)wo[2] * wo[2]);
    for (int i = 0; i < 3; i++) o[i] = wo[i] / n;
}


/* ---------------------------------------------------------------- goodness of fit */

/* A fit (gof.h) of a model's sampler against its evaluation on a grid about axis. */

typedef struct {
    model_t m;
    double axis[3];
    double lo;          /* -1: the sphere; 0: the hemisphere about the axis */
    int nfm, nfp;       /* forced edges in mu and phi */
    double fmu[2], fph[2];
    int reps;           /* normals per item of the stochastic evaluation */
    double integral;    /* what the evaluation integrates to (1; Oren-Nayar: its albedo) */
    double int_tol;     /* allowed |integral - that| */
} gof_case;

/* The stochastic evaluation integrated over every bin: QM x QM Gauss nodes per bin, each
 * node's value the mean of MC_K independent items; I[c] and its variance VI[c] (the
 * nodes are independent: every work-item has its own random stream). */
static void mc_bins(const model_t *m, const gof_bins *b, int reps, double *I, double *VI)
{
    const int nq = QM * QM;
    const size_t n = (size_t)b->n * nq;
    float *dirs = malloc(n * 16);
    double *wt = malloc(n * sizeof *wt), *mean = malloc(n * sizeof *mean), *var = malloc(n * sizeof *var);
    for (int c = 0; c < b->n; c++) {
        double r[4];
        b->rect(b->g, c, r);
        gof_rect_nodes(b, c, r[0], r[1], r[2], r[3], QM, dirs + 4 * (size_t)c * nq, wt + (size_t)c * nq);
    }
    mc_eval(m, m->wo, dirs, n, reps, mean, var);
    for (int c = 0; c < b->n; c++) {
        I[c] = VI[c] = 0;
        for (int k = 0; k < nq; k++) {
            size_t q = (size_t)c * nq + k;
            I[c] += wt[q] * mean[q], VI[c] += wt[q] * wt[q] * var[q];
        }
    }
    free(dirs), free(wt), free(mean), free(var);
}


static void fit_sample(void *ctx, unsigned seed, size_t n, float *out) { k_sample(&((const gof_case *)ctx)->m, seed, n, out); }

static void fit_density(void *ctx, const float *dirs, size_t n, float *out)
{
    const model_t *m = &((const gof_case *)ctx)->m;
    k_eval(m, m->wo, dirs, n, out);
}

static void fit_integrals(void *ctx, const gof_bins *b, double *I, double *VI)
{
    const gof_case *gc = ctx;
    mc_bins(&gc->m, b, gc->reps, I, VI);
}

/* Case `index` (its seeds: the same whichever sections run). */
static void gof(const gof_case *gc, int index)
{
    gof_spec s = {.name = gc->m.name, .ctx = (void *)gc, .sample = fit_sample, .density = gc->m.mc ? NULL : fit_density,
                  .integrals = fit_integrals, .unit_weights = gc->m.use_phase, .lo = gc->lo, .nfm = gc->nfm,
                  .nfp = gc->nfp, .integral = gc->integral, .int_tol = gc->int_tol,
                  .seed_pilot = 977u + 2 * (unsigned)index, .seed = 12345u + 2 * (unsigned)index, .n = NS};
    for (int k = 0; k < 3; k++) s.axis[k] = gc->axis[k];
    for (int k = 0; k < 2; k++) s.fmu[k] = gc->fmu[k], s.fph[k] = gc->fph[k];
    gof_fit(&s);
}

/* ---------------------------------------------------------------- section 1 + 2: the fits */

static int n_case = 0;

static void fits_hg2(void)
{
    const double p[][3] = {{0.9, -0.5, 0.3}, {0.0, 0.95, 0.5}, {-0.95, 0.95, 1.0}}, wo[3] = {0.3, -0.2, 0.9327379};
    for (int i = 0; i < 3; i++) {
        gof_case gc = {.m = hg2_model(p[i][0], p[i][1], p[i][2], wo), .lo = -1, .integral = 1, .int_tol = 1e-4};
        for (int k = 0; k < 3; k++) gc.axis[k] = -wo[k];
        gof(&gc, n_case++);
    }
}

static void fits_rayleigh(void)
{
    const double rho[] = {-1, 0, 0.5, 1}, wo[3] = {-0.48, 0.6, 0.64};
    for (int i = 0; i < 4; i++) {
        gof_case gc = {.m = rayleigh_model(rho[i], wo), .lo = -1, .integral = 1, .int_tol = 1e-4};
        for (int k = 0; k < 3; k++) gc.axis[k] = -wo[k];
        gof(&gc, n_case++);
    }
}

static void fits_sggx(int diffuse)
{
    const double ratio[] = {0.1, 1, 10}, th[] = {0, 60, 89};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            gof_case gc = {.m = sggx_model(ratio[i], diffuse, th[j]), .axis = {0, 0, 1}, .lo = -1, .nfm = 1,
                           .fmu = {0.0}, .reps = 2000, .integral = 1, .int_tol = diffuse ? 1e-3 : 1e-4};
            gof(&gc, n_case++);
        }
}

/* The Oren-Nayar albedo, independently: the formula in double, Gauss-Legendre in theta_i
 * (so that sin theta_i is smooth) and phi on panels split at its kinks (theta_i = theta_o,
 * and the azimuths where wo'.wi' = 0), n nodes per panel side. With fw, also the same
 * rule's nodes (float directions) and weights, for the kernel's integral. */
static double oren_nayar_albedo(double fr, double s, const double o[3], int n, float *fd, double *fw)
{
    double gx[64], gw[64], to = acos(fmin(1.0, o[2]));
    gauss_legendre(n, gx, gw);
    const double tcut[] = {0, to, PI / 2}, pcut[] = {-PI / 2, PI / 2, 3 * PI / 2};
    double sum = 0;
    int k = 0;
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            double t0 = tcut[a], t1 = tcut[a + 1], p0 = pcut[b], p1 = pcut[b + 1];
            if (t1 <= t0 + 1e-12) continue;
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++, k++) {
                    double t = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * gx[i], ph = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * gx[j];
                    double d[3] = {sin(t) * cos(ph), sin(t) * sin(ph), cos(t)};
                    double w = 0.25 * (t1 - t0) * (p1 - p0) * gw[i] * gw[j] * sin(t);
                    sum += w * oren_nayar_ref(fr, s, o, d);
                    if (fw) {
                        for (int c = 0; c < 3; c++) fd[4 * k + c] = (float)d[c];
                        fd[4 * k + 3] = 0, fw[k] = w;
                    }
                }
        }
    return fw ? k : sum;
}

static void fits_oren_nayar(void)
{
    const double sig[] = {0, 0.3, 0.8}, th[] = {0, 60, 85}, fr = 0.7;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            model_t m = oren_nayar_model(fr, sig[i], th[j]);
            double o[3];
            wo_double(m.wo, o);
            double alb = oren_nayar_albedo((float)fr, (float)sig[i], o, 48, NULL, NULL),
                   alb2 = oren_nayar_albedo((float)fr, (float)sig[i], o, 24, NULL, NULL);
            CHECK(fabs(alb - alb2) < 1e-10, "Oren-Nayar albedo quadrature: %.12f vs %.12f", alb, alb2);
            gof_case gc = {.m = m, .axis = {0, 0, 1}, .lo = 0, .integral = alb, .int_tol = 2e-5 * alb};
            gc.nfm = 1, gc.fmu[0] = o[2];
            if (th[j] > 0) gc.nfp = 2, gc.fph[0] = PI / 2, gc.fph[1] = 3 * PI / 2;
            gof(&gc, n_case++);
        }
    {
        /* from below: the layer reflects on wo's side, whichever it is (the albedo is that
         * of wo mirrored up) */
        model_t m = oren_nayar_model(fr, 0.3, 120);
        double o[3];
        wo_double(m.wo, o);
        o[2] = fabs(o[2]);
        double alb = oren_nayar_albedo((float)fr, (float)0.3, o, 48, NULL, NULL);
        gof_case gc = {.m = m, .axis = {0, 0, -1}, .lo = 0, .integral = alb, .int_tol = 2e-5 * alb, .nfm = 1,
                       .fmu = {o[2]}, .nfp = 2, .fph = {PI / 2, 3 * PI / 2}};
        gof(&gc, n_case++);
    }
    /* The published formula gains energy at grazing angles: albedo 1.005 at sigma 0.1, 80
     * degrees (fR = 1); the kernel's values on the same rule integrate to the same. */
    model_t m = oren_nayar_model(1.0, 0.1, 80);
    double o[3];
    wo_double(m.wo, o);
    const int n = 48;
    float *d = malloc(4 * n * n * 4 * sizeof *d), *fp = malloc(2 * n * n * 4 * sizeof *fp);
    double *w = malloc(n * n * 4 * sizeof *w);
    double alb = oren_nayar_albedo(1.0, (float)0.1, o, n, NULL, NULL);
    int k = (int)oren_nayar_albedo(1.0, (float)0.1, o, n, d, w);
    k_eval(&m, m.wo, d, (size_t)k, fp);
    double kern = 0;
    for (int i = 0; i < k; i++) kern += w[i] * fp[2 * i];
    CHECK(alb > 1.004 && alb < 1.006, "Oren-Nayar albedo at sigma 0.1, 80 degrees: %.6f (published formula: ~1.005)",
          alb);
    CHECK(fabs(kern - alb) <= 2e-5 * alb, "Oren-Nayar kernel albedo at sigma 0.1, 80 degrees %.7f, formula %.7f", kern,
          alb);
    printf("Oren-Nayar sigma 0.1 at 80 degrees, fR 1: albedo %.6f (formula), %.6f (kernel): not energy conserving, as"
           " published\n", alb, kern);
    free(d), free(fp), free(w);
}

/* ---------------------------------------------------------------- section 3: limits */

static void rand_dir(uint64_t *s, double d[3])
{
    for (;;) {
        double v[3], n = 0;
        for (int i = 0; i < 3; i++) {
            *s = *s * 6364136223846793005ull + 1442695040888963407ull;
            v[i] = 2.0 * ((*s >> 11) * 0x1.0p-53) - 1.0;
            n += v[i] * v[i];
        }
        if (n > 1e-4 && n <= 1) {
            for (int i = 0; i < 3; i++) d[i] = v[i] / sqrt(n);
            return;
        }
    }
}

/* nd random float directions, and their double normalised copies */
#define NLIM 4096
static void rand_dirs(uint64_t seed, int nd, float *f, double (*d)[3])
{
    uint64_t s = seed;
    for (int i = 0; i < nd; i++) {
        double x[3];
        rand_dir(&s, x);
        for (int c = 0; c < 3; c++) f[4 * i + c] = (float)x[c];
        f[4 * i + 3] = 0;
        double n = 0;
        for (int c = 0; c < 3; c++) n += (double)f[4 * i + c] * f[4 * i + c];
        for (int c = 0; c < 3; c++) d[i][c] = f[4 * i + c] / sqrt(n);
    }
}


/* The diffuse sphere's phase function, a the angle between wo and wi (both away from the
 * vertex; a = 0 is straight back). */
static double sggx_sigma_d(const model_t *m, const double w[3])
{
    return sqrt(m->M.pp[0] * (w[0] * w[0] + w[1] * w[1]) + m->M.pp[1] * w[2] * w[2]);
}

/* Specular SGGX in double, D(h) / (4 sigma(wo)) with h = normalize(wo + wi) and
 * D(m) = 1 / (pi sqrt|S| (m^T S^-1 m)^2), S = diag(sxx, sxx, szz) (Heitz et al. 2015). */
static double sggx_spec_ref(const model_t *m, const double o[3], const double i[3])
{
    const double sxx = m->M.pp[0], szz = m->M.pp[1];
    double h[3] = {o[0] + i[0], o[1] + i[1], o[2] + i[2]}, l = sqrt(dot3(h, h));
    for (int k = 0; k < 3; k++) h[k] /= l;
    double q = (h[0] * h[0] + h[1] * h[1]) / sxx + h[2] * h[2] / szz;
    return 1 / (PI * sxx * sqrt(szz) * q * q) / (4 * sggx_sigma_d(m, o));
}

static double sphere_phase(double a) { return 2 / (3 * PI * PI) * (sin(a) + (PI - a) * cos(a)); }

/* Two models that must be the same, bit for bit: adds to *neq the values and densities at
 * the n directions f that differ, to *nsame the sample coordinates (20000 samples, one seed
 * for both) that differ. */
static void count_differences(const model_t *a, const model_t *b, const float *f, int n, cl_uint seed, int *neq,
                              int *nsame)
{
    static float fp[2 * NLIM], fq[2 * NLIM];
    k_eval(a, a->wo, f, (size_t)n, fp);
    k_eval(b, b->wo, f, (size_t)n, fq);
    for (int k = 0; k < 2 * n; k++) *neq += fp[k] != fq[k];
    enum { NSAMP = 20000 };
    static float sa[4 * NSAMP], sb[4 * NSAMP];
    k_sample(a, seed, NSAMP, sa);
    k_sample(b, seed, NSAMP, sb);
    for (int k = 0; k < 4 * NSAMP; k++) *nsame += sa[k] != sb[k];
}

static void limits(void)
{
    static float f[4 * NLIM], fp[2 * NLIM], fq[2 * NLIM];
    static double d[NLIM][3];
    rand_dirs(7, NLIM, f, d);
    const double wos[][3] = {{0, 0, 1}, {0.3, -0.2, 0.9327379}, {0.99, 0.1, -0.0995}};

    /* HG2 with b = 0 is HG(g0), bit for bit: values and samples */
    const double g0s[] = {0.9, -0.5, 0.999, -0.999, 0.0}, g1s[] = {-0.7, 0.95, -0.999, 0.999, 0.5};
    int neq = 0, nsame = 0;
    for (int i = 0; i < 5; i++) {
        model_t a = phase_model("HG", LSQT_PHASE_HG, g0s[i], 0, 0, wos[i % 3]);
        model_t b = phase_model("HG2 b=0", LSQT_PHASE_HG2, g0s[i], g1s[i], 0, wos[i % 3]);
        count_differences(&a, &b, f, NLIM, 99u + (cl_uint)i, &neq, &nsame);
    }
    CHECK(neq == 0, "HG2 with b = 0: %d values differ from HG(g0)", neq);
    CHECK(nsame == 0, "HG2 with b = 0: %d sample coordinates differ from HG(g0)'s", nsame);

    /* Rayleigh: rho = 1 isotropic, rho = 0 is 3 / (16 pi) (1 + cos^2) */
    double worst_iso = 0, worst_r0 = 0;
    for (int w = 0; w < 3; w++) {
        model_t r1 = rayleigh_model(1, wos[w]), r0 = rayleigh_model(0, wos[w]);
        double o[3];
        wo_double(r1.wo, o);
        k_eval(&r1, r1.wo, f, NLIM, fp);
        k_eval(&r0, r0.wo, f, NLIM, fq);
        for (int k = 0; k < NLIM; k++) {
            double c = dot3(o, d[k]), ref = 3 / (16 * PI) * (1 + c * c);
            worst_iso = fmax(worst_iso, fabs(fp[2 * k] * 4 * PI - 1));
            worst_r0 = fmax(worst_r0, fabs(fq[2 * k] / ref - 1));
        }
    }
    CHECK(worst_iso <= 1e-6, "Rayleigh rho = 1: largest relative departure from 1/(4 pi) %.3g", worst_iso);
    CHECK(worst_r0 <= 1e-6, "Rayleigh rho = 0: largest relative departure from 3/(16 pi)(1 + cos^2) %.3g", worst_r0);

    /* SGGX specular with Apara = Aperp (any common scale) is isotropic */
    double worst_sp = 0;
    const double scale[] = {1.0, 0.25};
    for (int w = 0; w < 3; w++)
        for (int s = 0; s < 2; s++) {
            model_t m = phase_model("SGGX", LSQT_PHASE_SGGX, scale[s], scale[s], 0, wos[w]);
            k_eval(&m, m.wo, f, NLIM, fp);
            for (int k = 0; k < NLIM; k++) worst_sp = fmax(worst_sp, fabs(fp[2 * k] * 4 * PI - 1));
        }
    CHECK(worst_sp <= 1e-5, "SGGX specular Apara = Aperp: largest relative departure from 1/(4 pi) %.3g", worst_sp);

    /* SGGX specular at wi = -wo exactly: the half vector is 0 and has no direction; the
     * value must still be finite and non-negative (it was +inf). Axis directions, which the
     * kernel's normalize leaves exact, so that wo + wi is exactly 0 there. */
    int bad_back = 0;
    const double sq[][2] = {{0.01, 1}, {1, 1}, {1, 0.01}}, axes[][3] = {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}};
    for (int w = 0; w < 3; w++)
        for (int r = 0; r < 3; r++) {
            model_t m = phase_model("SGGX", LSQT_PHASE_SGGX, sq[r][0], sq[r][1], 0, axes[w]);
            float back[4] = {-m.wo[0], -m.wo[1], -m.wo[2], 0}, v[2];
            k_eval(&m, m.wo, back, 1, v);
            bad_back += !(isfinite(v[0]) && v[0] >= 0);
        }
    CHECK(bad_back == 0, "SGGX specular at wi = -wo: %d of 9 values not finite and non-negative", bad_back);
    /* ... and close to it, where wo + wi is small (1e-2 and 3e-4 rad from wi = -wo), the
     * float value follows the double formula: h is normalised however short it is */
    double worst_near = 0;
    for (int w = 0; w < 3; w++)
        for (int r = 0; r < 3; r++)
            for (int e = 0; e < 2; e++) {
                const double delta = e ? 3e-4 : 1e-2;
                model_t m = phase_model("SGGX", LSQT_PHASE_SGGX, sq[r][0], sq[r][1], 0, wos[w]);
                double o[3], t[3], i[3];
                wo_double(m.wo, o);
                /* a unit vector normal to o, then wi = -o turned by delta towards it */
                double a[3] = {fabs(o[0]) < 0.9 ? 1 : 0, fabs(o[0]) < 0.9 ? 0 : 1, 0}, c = dot3(a, o), l = 0;
                for (int k = 0; k < 3; k++) t[k] = a[k] - c * o[k], l += t[k] * t[k];
                float fi[4] = {0, 0, 0, 0}, v[2];
                for (int k = 0; k < 3; k++) fi[k] = (float)(-cos(delta) * o[k] + sin(delta) * t[k] / sqrt(l));
                for (int k = 0; k < 3; k++) i[k] = fi[k];
                double n = sqrt(dot3(i, i));
                for (int k = 0; k < 3; k++) i[k] /= n;
                k_eval(&m, m.wo, fi, 1, v);
                double ref = sggx_spec_ref(&m, o, i), rel = fabs(v[0] / ref - 1);
                CHECK(rel < 2e-2, "SGGX specular %g rad from wi = -wo (S %g, %g): %.6g, double %.6g", delta, sq[r][0],
                      sq[r][1], v[0], ref);
                worst_near = fmax(worst_near, rel);
            }
    printf("limits: SGGX specular near wi = -wo, largest relative departure from double %.2g\n", worst_near);

    /* Oren-Nayar with sigma = 0 is Lambertian */
    double worst_on = 0;
    int wrong_side = 0;
    for (int w = 0; w < 3; w++) {
        model_t m = oren_nayar_model(0.7, 0, 0);
        for (int c = 0; c < 3; c++) m.wo[c] = (float)wos[w][c];
        k_eval(&m, m.wo, f, NLIM, fp);
        for (int k = 0; k < NLIM; k++) {
            if (m.wo[2] * d[k][2] > 0) worst_on = fmax(worst_on, fabs(fp[2 * k] / (0.7f * fabs(d[k][2]) / PI) - 1));
            else wrong_side += fp[2 * k] != 0;
        }
    }
    CHECK(worst_on <= 1e-6, "Oren-Nayar sigma = 0: largest relative departure from fR |cos| / pi %.3g", worst_on);
    CHECK(wrong_side == 0, "Oren-Nayar: %d values on the side away from wo are not 0", wrong_side);

    /* SGGX diffuse with Apara = Aperp is the diffuse sphere. Its closed form integrates to 1
     * (Gauss-Legendre in cos a), then the stochastic evaluation at angles a. */
    double gx[64], gw[64], one = 0;
    gauss_legendre(64, gx, gw);
    for (int i = 0; i < 64; i++) one += 2 * PI * gw[i] * sphere_phase(acos(gx[i]));
    CHECK(fabs(one - 1) < 1e-8, "the diffuse sphere's phase function integrates to %.12f", one);
    const double angles[] = {0, 5, 20, 45, 70, 90, 110, 135, 160, 175, 180};
    const int na = 11;
    float dirs[4 * 2 * 11];
    double mean[22], var[22], zmax = 0, relmax = 0;
    int nz = 0;
    for (int w = 0; w < 2; w++) {
        model_t m = phase_model("SGGX diffuse Apara = Aperp", LSQT_PHASE_SGGX, 1, 1, 1, wos[w + 1]);
        m.mc = 1;
        double o[3], u[3], t[3] = {0, 0, 1}, un = 0;
        wo_double(m.wo, o);
        /* u: normal to o */
        double dd = dot3(t, o);
        for (int c = 0; c < 3; c++) u[c] = t[c] - dd * o[c], un += u[c] * u[c];
        for (int c = 0; c < 3; c++) u[c] /= sqrt(un);
        for (int i = 0; i < na; i++) {
            double a = angles[i] * PI / 180;
            for (int c = 0; c < 3; c++) dirs[4 * (w * na + i) + c] = (float)(cos(a) * o[c] + sin(a) * u[c]);
            dirs[4 * (w * na + i) + 3] = 0;
        }
        /* 64 items per value: the variance estimate has 63 dof, so z is close to normal */
        mc_eval_k(&m, m.wo, dirs + 4 * w * na, na, 64, 5000, mean + w * na, var + w * na);
        for (int i = 0; i < na; i++) {
            const float *x = dirs + 4 * (w * na + i);
            double xd[3] = {x[0], x[1], x[2]}, n = sqrt(dot3(xd, xd));
            double a = acos(fmin(1.0, fmax(-1.0, dot3(xd, o) / n))), ref = sphere_phase(a), s = sqrt(var[w * na + i]);
            if (ref < 1e-12 && mean[w * na + i] == 0) continue; /* a = 180: no normal sees both, exactly 0 */
            double zz = (mean[w * na + i] - ref) / s;
            CHECK(s > 0 && fabs(zz) < 4, "SGGX diffuse Apara = Aperp at a = %g degrees: %.6f +- %.2g, sphere %.6f, z = %.2f",
                  angles[i], mean[w * na + i], s, ref, zz);
            zmax = fmax(zmax, fabs(zz)), nz++;
            if (ref > 0.01) relmax = fmax(relmax, s / ref);
        }
    }
    CHECK(relmax < 0.01, "SGGX diffuse sphere: the evaluation's relative sigma %.3g is too large to judge", relmax);

    /* SGGX specular next to the exact forward direction wi = -wo (h = wo + wi vanishes):
     * finite and below max D / (4 sigma(wo)) */
    const double ratio[] = {0.1, 10, 1};
    int n_bad = 0, n_all = 0, n_exact = 0;
    double worst = 0, wv = 0, wb = 0, exact_v = 0;
    float wu[3] = {0, 0, 0}, ww[3] = {0, 0, 0};
    for (int r = 0; r < 3; r++)
        for (int w = 0; w < 3; w++) {
            double ap = ratio[r] <= 1 ? ratio[r] : 1, an = ratio[r] <= 1 ? 1 : 1 / ratio[r];
            model_t m = phase_model("SGGX", LSQT_PHASE_SGGX, ap * ap, an * an, 0, wos[w]);
            double o[3];
            wo_double(m.wo, o);
            double sxx = m.M.pp[0], szz = m.M.pp[1];
            double dmax = fmax(sxx, szz) * fmax(sxx, szz) / (PI * sxx * sqrt(szz));
            double bound = dmax / (4 * sqrt(sxx * (o[0] * o[0] + o[1] * o[1]) + szz * o[2] * o[2]));
            float u[4 * 49];
            int n = 0;
            for (int c = 0; c < 3; c++) u[c] = -m.wo[c];
            u[3] = 0, n = 1;
            double a0[3] = {-o[1], o[0], 0}, an0 = sqrt(a0[0] * a0[0] + a0[1] * a0[1]);
            if (an0 < 1e-6) a0[0] = 1, a0[1] = 0, an0 = 1;
            for (int c = 0; c < 3; c++) a0[c] /= an0;
            double b0[3] = {o[1] * a0[2] - o[2] * a0[1], o[2] * a0[0] - o[0] * a0[2], o[0] * a0[1] - o[1] * a0[0]};
            for (int e = 0; e < 6; e++)
                for (int j = 0; j < 8; j++, n++) {
                    double t = pow(10.0, -7.0 + e), ph = 2 * PI * j / 8, q[3], len = 0;
                    for (int c = 0; c < 3; c++) q[c] = -o[c] + t * (cos(ph) * a0[c] + sin(ph) * b0[c]), len += q[c] * q[c];
                    for (int c = 0; c < 3; c++) u[4 * n + c] = (float)(q[c] / sqrt(len));
                    u[4 * n + 3] = 0;
                }
            float out[2 * 49];
            k_eval(&m, m.wo, u, (size_t)n, out);
            /* u[0] = -wo exactly: h = 0, the value is undefined (its limit depends on the
             * way wi approaches -wo); only reported */
            if (!(isfinite(out[0]) && out[0] <= 1.001 * bound)) n_exact++, exact_v = out[0];
            for (int i = 1; i < n; i++) {
                n_all++;
                double rr = out[2 * i] / bound;
                if (!(rr <= 1.001)) {
                    n_bad++;
                    if (!(rr <= worst)) {
                        worst = isfinite(rr) ? rr : 1e300, wv = out[2 * i], wb = bound;
                        for (int c = 0; c < 3; c++) wu[c] = u[4 * i + c], ww[c] = m.wo[c];
                    }
                }
            }
        }
    CHECK(n_bad == 0,
          "SGGX specular next to wi = -wo: %d of %d values not finite or over max D / (4 sigma(wo)), worst %.6g against"
          " %.6g at wo = (%.9g, %.9g, %.9g), wi = (%.9g, %.9g, %.9g)",
          n_bad, n_all, wv, wb, ww[0], ww[1], ww[2], wu[0], wu[1], wu[2]);
    if (n_exact)
        printf("NOTE: SGGX specular at wi = -wo exactly (h = wo + wi = 0): %d of 9 (wo, S) pairs give %g (not finite or"
               " over the bound), e.g. wo = (0, 0, 1), wi = (0, 0, -1)\n", n_exact, exact_v);
    printf("limits: HG2 b=0 = HG (%d values, samples bit for bit), Rayleigh rho=1 / rho=0 within %.2g / %.2g, SGGX"
           " specular isotropic within %.2g, Oren-Nayar sigma=0 within %.2g, diffuse sphere: closed form integrates to"
           " 1 %+.1e, %d values |z| <= %.2f; SGGX forward bound: %d of %d over\n",
           2 * NLIM * 5, worst_iso, worst_r0, worst_sp, worst_on, one - 1, nz, zmax, n_bad, n_all);
}

/* ---------------------------------------------------------------- section 4: peaks */

/* HG in double, the textbook form: (1 - g^2) / (4 pi (1 + g^2 - 2 g cos t)^1.5), cos t =
 * -wo.wi */
static double hg_ref(double g, double cost)
{
    double d = 1 + g * g - 2 * g * cost;
    return (1 - g * g) / (4 * PI * d * sqrt(d));
}

/* P(q <= Q) for q = 1 - cos t (from the forward direction), HG(g): the CDF
 * (1 - g^2) / (2 g) [1 / (1 - g) - 1 / sqrt((1 - g)^2 + 2 g Q)] without its cancellation */
static double hg_cdf_q(double g, double Q)
{
    double a = 1 - g, b = sqrt(a * a + 2 * g * Q);
    return (1 - g * g) * Q / (a * b * (a + b));
}

static void peaks(void)
{
    const float g9 = 0.999f;
    typedef struct {
        const char *name;
        int kind;
        double g0, g1, b;
    } pk;
    const pk cases[] = {{"HG g=0.999", LSQT_PHASE_HG, g9, 0, 0},
                        {"HG g=-0.999", LSQT_PHASE_HG, -g9, 0, 0},
                        {"HG2 (0.999, -0.999, 0.3)", LSQT_PHASE_HG2, g9, -g9, 0.3f}};
    const double wos[][3] = {{0, 0, 1}, {1, 0, 0}, {0, 0, -1}};
    const double ts[] = {0, 1e-4, 1e-3, 3e-3, 1e-2, 0.1, 1, 2, PI}, phs[] = {0, 1, 2.5, 4};
    const int nt = 9;
    double worst[9] = {0};
    for (int c = 0; c < 3; c++)
        for (int w = 0; w < 3; w++) {
            model_t m = phase_model(cases[c].name, cases[c].kind, cases[c].g0, cases[c].g1, cases[c].b, wos[w]);
            const double g0 = m.M.pp[0], g1 = m.M.pp[1], b = m.M.pp[2];
            float dirs[4 * 2 * 9 * 4];
            int n = 0;
            for (int side = 0; side < 2; side++) {
                /* about the forward direction -wo, then the backward one, wo */
                double P[3], U[3] = {0, 0, 0}, V[3];
                for (int k = 0; k < 3; k++) P[k] = side ? wos[w][k] : -wos[w][k];
                U[fabs(P[0]) > 0.5 ? 1 : 0] = 1;
                V[0] = P[1] * U[2] - P[2] * U[1], V[1] = P[2] * U[0] - P[0] * U[2], V[2] = P[0] * U[1] - P[1] * U[0];
                for (int i = 0; i < nt; i++)
                    for (int j = 0; j < 4; j++, n++)
                        for (int k = 0; k < 4; k++)
                            dirs[4 * n + k] = k == 3 ? 0.0f
                                                     : (float)(cos(ts[i]) * P[k] +
                                                               sin(ts[i]) * (cos(phs[j]) * U[k] + sin(phs[j]) * V[k]));
            }
            float out[2 * 2 * 9 * 4];
            k_eval(&m, m.wo, dirs, (size_t)n, out);
            double o[3];
            wo_double(m.wo, o);
            for (int q = 0; q < n; q++) {
                double x[3] = {dirs[4 * q], dirs[4 * q + 1], dirs[4 * q + 2]}, nx = sqrt(dot3(x, x));
                double cost = -dot3(o, x) / nx;
                double ref = cases[c].kind == LSQT_PHASE_HG ? hg_ref(g0, cost)
                                                            : (1 - b) * hg_ref(g0, cost) + b * hg_ref(g1, cost);
                double rel = fabs(out[2 * q] / ref - 1);
                int it = (q % (nt * 4)) / 4;
                if (!(rel <= worst[it])) worst[it] = isfinite(rel) ? rel : 1e300;
                CHECK(rel <= 1e-4, "%s, wo = (%g, %g, %g), %s peak, %g rad off: %.9g, double %.9g (rel %.2g)",
                      m.name, o[0], o[1], o[2], q < nt * 4 ? "forward" : "backward", ts[it], out[2 * q], ref, rel);
            }
        }
    printf("peaks, values against double: largest relative error at 0, 1e-4, 1e-3, 3e-3, 1e-2, 0.1, 1, 2, pi rad:");
    for (int i = 0; i < nt; i++) printf(" %.1e", worst[i]);
    printf("\n");

    /* normalisation at the peaks: the kernel's values integrated over q = 1 - cos t about
     * the forward axis (the value depends on q alone), Gauss-Legendre on panels in log q
     * from 1e-14 (below which the rest is q p(0) < 1e-8) */
    double gxn[16], gwn[16];
    gauss_legendre(16, gxn, gwn);
    for (int c = 0; c < 3; c++) {
        const double wz[3] = {0, 0, 1};
        model_t m = phase_model(cases[c].name, cases[c].kind, cases[c].g0, cases[c].g1, cases[c].b, wz);
        enum { NPAN = 30 };
        static float dq[4 * 2 * NPAN * 16], vq[2 * 2 * NPAN * 16];
        double wq[2 * NPAN * 16];
        int n = 0;
        for (int h = 0; h < 2; h++)
            for (int p = 0; p < NPAN; p++) {
                double l0 = -14 + 14.0 * p / NPAN, l1 = -14 + 14.0 * (p + 1) / NPAN; /* log10 q, q up to 1 */
                for (int i = 0; i < 16; i++, n++) {
                    double l = 0.5 * (l0 + l1) + 0.5 * (l1 - l0) * gxn[i], q = pow(10.0, l);
                    double st = sqrt(q * (2 - q)), ct = 1 - q; /* angle from the axis h ? +z : -z */
                    dq[4 * n] = (float)st, dq[4 * n + 1] = 0, dq[4 * n + 2] = (float)(h ? ct : -ct), dq[4 * n + 3] = 0;
                    wq[n] = 2 * PI * 0.5 * (l1 - l0) * gwn[i] * q * log(10.0);
                }
            }
        k_eval(&m, m.wo, dq, (size_t)n, vq);
        double tot = 0;
        for (int i = 0; i < n; i++) tot += wq[i] * vq[2 * i];
        CHECK(fabs(tot - 1) <= 1e-4, "%s: integrates to %.8f over the sphere", m.name, tot);
        printf("%-28s integral over the sphere %.8f\n", m.name, tot);
    }

    /* the samplers: q = 1 - cos t about each peak axis, 4 bins per decade down to 1e-9 */
    enum { NQ = 37 };
    double qe[NQ + 1];
    qe[0] = 0;
    for (int k = 1; k <= NQ; k++) qe[k] = pow(10.0, -9.0 + 0.25 * (k - 1));
    qe[NQ] = 1; /* the hemisphere's edge, q = 1 */
    const double swo[][3] = {{0, 0, 1}, {0.48, -0.6, 0.64}};
    float *s = malloc((size_t)NS * 16);
    for (int c = 0; c < 3; c++)
        for (int w = 0; w < 2; w++) {
            model_t m = phase_model(cases[c].name, cases[c].kind, cases[c].g0, cases[c].g1, cases[c].b, swo[w]);
            const double g0 = m.M.pp[0], g1 = m.M.pp[1], b = cases[c].kind == LSQT_PHASE_HG ? 0 : m.M.pp[2];
            k_sample(&m, 4321u + 10 * (cl_uint)(c * 2 + w), NS, s);
            double o[3];
            wo_double(m.wo, o);
            static double O[2 * NQ], E[2 * NQ], S2[2 * NQ], V[2 * NQ];
            memset(O, 0, sizeof O), memset(V, 0, sizeof V);
            double qmin = 1;
            for (size_t i = 0; i < NS; i++) {
                double x[3] = {s[4 * i], s[4 * i + 1], s[4 * i + 2]}, nx = sqrt(dot3(x, x)), df[3], db[3];
                for (int k = 0; k < 3; k++) x[k] /= nx, df[k] = x[k] + o[k], db[k] = x[k] - o[k];
                /* forward: 1 - cos t = |wi + wo|^2 / 2; backward: 1 + cos t = |wi - wo|^2 / 2 */
                double qf = 0.5 * dot3(df, df), qb = 0.5 * dot3(db, db);
                int h = qf <= 1 ? 0 : 1;
                double q = h ? qb : qf;
                qmin = fmin(qmin, q);
                O[h * NQ + find_bin(qe, NQ, fmin(q, 1.0))] += 1;
            }
            double tot = 0;
            for (int h = 0; h < 2; h++)
                for (int k = 0; k < NQ; k++) {
                    double e = 0;
                    for (int l = 0; l < 2; l++) {
                        double gl = l ? g1 : g0, wl = l ? b : 1 - b, gs = h ? -gl : gl;
                        if (wl > 0) e += wl * (hg_cdf_q(gs, qe[k + 1]) - hg_cdf_q(gs, qe[k]));
                    }
                    E[h * NQ + k] = NS * e, tot += e;
                }
            memcpy(S2, O, sizeof O);
            int dof;
            double chi2 = gof_chi2(2 * NQ, O, S2, E, V, 1.0, NULL, &dof, NULL);
            dof -= 1;
            double p = chi2_p(chi2, dof);
            char tn[200];
            snprintf(tn, sizeof tn, "%s sampler wo=(%g,%g,%g): q bins", m.name, swo[w][0], swo[w][1], swo[w][2]);
            gof_record(tn, p);
            CHECK(fabs(tot - 1) < 1e-12, "%s: the CDF sums to %.15f", tn, tot);
            printf("%-50s chi2 %6.1f/%2d p=%.3f, expected below q = 1e-9: %.0f, observed %.0f (smallest q %.2g)\n", tn,
                   chi2, dof, p, E[0] + E[NQ], O[0] + O[NQ], qmin);
        }
    free(s);
}

/* ---------------------------------------------------------------- section 5: Rayleigh KS */


static void rayleigh_ks(void)
{
    const double rho[] = {-1, -0.5, 0, 0.5, 1}, wo[3] = {0.48, -0.6, 0.64};
    const size_t n = 1000000;
    float *s = malloc(n * 16);
    double *u = malloc(n * sizeof *u);
    for (int r = 0; r < 5; r++) {
        model_t m = rayleigh_model(rho[r], wo);
        const double gam = m.M.pp[0], a = 1 + 3 * gam, b = 1 - gam;
        k_sample(&m, 777u + (cl_uint)r, n, s);
        double o[3];
        wo_double(m.wo, o);
        for (size_t i = 0; i < n; i++) {
            double x[3] = {s[4 * i], s[4 * i + 1], s[4 * i + 2]}, nx = sqrt(dot3(x, x));
            double mu = -dot3(o, x) / nx;
            mu = fmin(1.0, fmax(-1.0, mu));
            u[i] = (a * (mu + 1) + b * (mu * mu * mu + 1) / 3) / (2 * a + 2 * b / 3);
        }
        qsort(u, n, sizeof *u, gof_dbl_cmp);
        double d = 0;
        for (size_t i = 0; i < n; i++) d = fmax(d, fmax((i + 1.0) / n - u[i], u[i] - (double)i / n));
        double p = ks_p(d, (double)n);
        char tn[200];
        snprintf(tn, sizeof tn, "Rayleigh rho=%g sampler: KS of the CDF at mu", rho[r]);
        gof_record(tn, p);
        printf("%-50s D = %.5f (sqrt(n) D = %.3f) p = %.3f\n", tn, d, sqrt((double)n) * d, p);
    }
    free(s), free(u);
}

/* ---------------------------------------------------------------- section 6: reciprocity */

static void reciprocity(void)
{
    enum { NP = 400 };
    static float fa[4 * NP], fb[4 * NP], out_ab[2], out_ba[2];
    static double a[NP][3], b[NP][3];
    /* Oren-Nayar: pairs on one side (above, and below), f(a->b)/|cos b| = f(b->a)/|cos a| */
    rand_dirs(11, NP, fa, a);
    rand_dirs(12, NP, fb, b);
    const double sig[] = {0.1, 0.3, 0.8};
    double worst_on = 0;
    int n_on = 0;
    for (int si = 0; si < 3; si++) {
        model_t m = oren_nayar_model(0.6, sig[si], 0);
        for (int i = 0; i < 100; i++) {
            float wa[3] = {fa[4 * i], fa[4 * i + 1], fa[4 * i + 2]}, wb[4] = {fb[4 * i], fb[4 * i + 1], fb[4 * i + 2], 0};
            if (wa[2] * wb[2] < 0) wb[2] = -wb[2]; /* same side */
            float wa4[4] = {wa[0], wa[1], wa[2], 0};
            k_eval(&m, wa, wb, 1, out_ab);
            k_eval(&m, wb, wa4, 1, out_ba);
            double x = out_ab[0] / fabs(wb[2]), y = out_ba[0] / fabs(wa[2]), rel = fabs(x - y) / fmax(fabs(x), fabs(y));
            CHECK(x > 0 && rel <= 1e-5, "Oren-Nayar sigma %g: f(a->b)/|cos b| = %.8g, f(b->a)/|cos a| = %.8g at a = (%.7f,"
                  " %.7f, %.7f), b = (%.7f, %.7f, %.7f)", sig[si], x, y, wa[0], wa[1], wa[2], wb[0], wb[1], wb[2]);
            worst_on = fmax(worst_on, rel), n_on++;
        }
    }
    /* SGGX specular: sigma(a) p(a->b) = sigma(b) p(b->a) = D(h) / 4 */
    const double ratio[] = {0.1, 1, 10};
    double worst_sp = 0, asym[3] = {0, 0, 0};
    int n_sp = 0;
    for (int r = 0; r < 3; r++) {
        const double zero[3] = {0, 0, 1};
        double ap = ratio[r] <= 1 ? ratio[r] : 1, an = ratio[r] <= 1 ? 1 : 1 / ratio[r];
        model_t m = phase_model("SGGX", LSQT_PHASE_SGGX, ap * ap, an * an, 0, zero);
        for (int i = 0; i < 100; i++) {
            float wa[3] = {fa[4 * i], fa[4 * i + 1], fa[4 * i + 2]}, wb[3] = {fb[4 * i], fb[4 * i + 1], fb[4 * i + 2]};
            k_eval(&m, wa, fb + 4 * i, 1, out_ab);
            k_eval(&m, wb, fa + 4 * i, 1, out_ba);
            double x = sggx_sigma_d(&m, a[i]) * out_ab[0], y = sggx_sigma_d(&m, b[i]) * out_ba[0];
            double rel = fabs(x - y) / fmax(fabs(x), fabs(y));
            CHECK(x > 0 && rel <= 1e-5, "SGGX specular Apara/Aperp %g: sigma(a) p(a->b) = %.8g, sigma(b) p(b->a) = %.8g at"
                  " a = (%.7f, %.7f, %.7f), b = (%.7f, %.7f, %.7f)", ratio[r], x, y, wa[0], wa[1], wa[2], wb[0], wb[1],
                  wb[2]);
            worst_sp = fmax(worst_sp, rel), n_sp++;
            asym[r] = fmax(asym[r], fabs(out_ab[0] - out_ba[0]) / fmax(out_ab[0], out_ba[0]));
        }
    }
    /* p itself is not symmetric unless sigma is constant */
    CHECK(asym[0] > 0.1 && asym[2] > 0.1 && asym[1] < 1e-5,
          "SGGX specular: p(a->b) vs p(b->a) differ by up to %.3g, %.3g, %.3g (ratios 0.1, 1, 10)", asym[0], asym[1],
          asym[2]);
    /* SGGX diffuse, stochastic: each value its own launch */
    double zmax = 0, chi2 = 0;
    int n_df = 0;
    for (int r = 0; r < 3; r++) {
        const double zero[3] = {0, 0, 1};
        double ap = ratio[r] <= 1 ? ratio[r] : 1, an = ratio[r] <= 1 ? 1 : 1 / ratio[r];
        model_t m = phase_model("SGGX diffuse", LSQT_PHASE_SGGX, ap * ap, an * an, 1, zero);
        m.mc = 1;
        for (int i = 0; i < 20; i++) {
            float wa[3] = {fa[4 * i], fa[4 * i + 1], fa[4 * i + 2]}, wb[3] = {fb[4 * i], fb[4 * i + 1], fb[4 * i + 2]};
            double mab, vab, mba, vba;
            mc_eval_k(&m, wa, fb + 4 * i, 1, 64, 2500, &mab, &vab);
            mc_eval_k(&m, wb, fa + 4 * i, 1, 64, 2500, &mba, &vba);
            double sa = sggx_sigma_d(&m, a[i]), sb = sggx_sigma_d(&m, b[i]);
            double x = sa * mab, y = sb * mba, s = sqrt(sa * sa * vab + sb * sb * vba), z = s > 0 ? (x - y) / s : 0;
            if (x == 0 && y == 0) continue; /* no normal sees both (a flake distribution this sharp): 0 = 0 */
            CHECK(s > 0 && fabs(z) < 4, "SGGX diffuse Apara/Aperp %g: sigma(a) p(a->b) = %.6g, sigma(b) p(b->a) = %.6g,"
                  " z = %.2f at a = (%.7f, %.7f, %.7f), b = (%.7f, %.7f, %.7f)", ratio[r], x, y, z, wa[0], wa[1], wa[2],
                  wb[0], wb[1], wb[2]);
            zmax = fmax(zmax, fabs(z)), chi2 += z * z, n_df++;
        }
    }
    double p = chi2_p(chi2, n_df);
    gof_record("SGGX diffuse reciprocity: sum z^2", p);
    printf("reciprocity: Oren-Nayar %d pairs, worst rel %.2g; SGGX specular %d pairs (sigma-weighted), worst rel %.2g;"
           " unweighted p(a->b)/p(b->a) asymmetry up to %.2g, %.2g, %.2g (ratios 0.1, 1, 10); SGGX diffuse %d pairs, "
           "largest |z| %.2f, sum z^2 %.1f p=%.3f\n",
           n_on, worst_on, n_sp, worst_sp, asym[0], asym[1], asym[2], n_df, zmax, chi2, p);
}

/* ---------------------------------------------------------------- section 7: stacks */

/* NEE transmittance (lower hemisphere) minus the scattered transmission T - delta_T, per
 * batch from the same paths (as nee_albedo_minus), with its batch-means error. */
static lsqt_est nee_t_minus_scattered(const lsqt_state *st, int s)
{
    const size_t nw = (size_t)st->n_wi;
    const double w = 4.0 * PI / st->n_wi, n = (double)st->paths;
    double d[LSQT_BATCHES], total = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) {
        const lsqt_u128 *nee = st->nee + ((size_t)s * LSQT_BATCHES + (size_t)b) * nw;
        double a = 0;
        for (size_t k = 0; k < nw; k++)
            if (!(st->wi[((size_t)s * nw + k) * 4 + 2] > 0)) a += w * lsqt_u128_to_double(nee[k]);
        const lsqt_u128 *sc = st->scalars + ((size_t)s * LSQT_BATCHES + (size_t)b) * LSQT_T_COUNT;
        d[b] = (a - lsqt_u128_to_double(sc[LSQT_T_T]) + lsqt_u128_to_double(sc[LSQT_T_DELTA_T])) / LSQT_FIX_SCALE;
        total += d[b];
    }
    lsqt_est e = {total / n, 0};
    double ss = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) ss += nee_sqr(d[b] - (double)lsqt_batch_paths(st->paths, b) * e.mean);
    e.err = sqrt(ss * LSQT_BATCHES / (LSQT_BATCHES - 1)) / n;
    return e;
}

static double nee_t(const lsqt_state *st, int s)
{
    /* the NEE transmittance alone: the same sum without the tallies */
    const size_t nw = (size_t)st->n_wi;
    double a = 0;
    for (int b = 0; b < LSQT_BATCHES; b++) {
        const lsqt_u128 *nee = st->nee + ((size_t)s * LSQT_BATCHES + (size_t)b) * nw;
        for (size_t k = 0; k < nw; k++)
            if (!(st->wi[((size_t)s * nw + k) * 4 + 2] > 0)) a += 4.0 * PI / st->n_wi * lsqt_u128_to_double(nee[k]);
    }
    return a / LSQT_FIX_SCALE / (double)st->paths;
}

static void stack(const char *name, const char *text, uint64_t paths)
{
    const double deg[] = {0, 45, 80};
    lsqt_state st, coarse;
    lsqt_slice_est *e = fixture_run(text, 3, deg, 1024, paths, 21, &st);
    lsqt_slice_est *ec = fixture_run(text, 3, deg, 256, paths, 21, &coarse);
    CHECK(st.transmits, "%s transmits", name);
    for (int s = 0; s < 3; s++) {
        double sig = sqrt(e[s].R.err * e[s].R.err + e[s].T.err * e[s].T.err), rt = e[s].R.mean + e[s].T.mean;
        CHECK(fabs(rt - 1) <= 4 * sig + 1e-9, "%s, %g degrees: R + T = %.9f +- %.2g", name, deg[s], rt, sig);
        CHECK(e[s].n_nonfinite == 0 && e[s].cut == 0, "%s: %d non-finite, %llu cut", name, e[s].n_nonfinite,
              (unsigned long long)e[s].cut);
        lsqt_est dr = nee_albedo_minus(&st, s, 1, 1.0, LSQT_T_R), dt = nee_t_minus_scattered(&st, s);
        double rn = nee_albedo_minus(&st, s, 1, 0.0, LSQT_T_R).mean;
        double qr = fabs(rn - nee_albedo_minus(&coarse, s, 1, 0.0, LSQT_T_R).mean);
        double tn = nee_t(&st, s), qt = fabs(tn - nee_t(&coarse, s));
        CHECK(fabs(dr.mean) <= 4 * dr.err + qr, "%s, %g degrees: NEE R - R = %.3g +- %.2g (quadrature %.2g)", name,
              deg[s], dr.mean, dr.err, qr);
        CHECK(fabs(dt.mean) <= 4 * dt.err + qt, "%s, %g degrees: NEE T - (T - delta_T) = %.3g +- %.2g (quadrature %.2g)",
              name, deg[s], dt.mean, dt.err, qt);
        CHECK(qr < 0.02 * rn && qt < 0.02 * tn, "%s, %g degrees: the 256- and 1024-direction rules differ by %.3g (R)"
              " and %.3g (T): the quadrature does not allow the comparison", name, deg[s], qr, qt);
        printf("%-28s %2g deg: R %.5f T %.5f (delta_T %.5f) R+T-1 %+.1e +- %.1e | NEE R-R %+.1e +- %.1e (quad %.1e)"
               " NEE T-(T-dT) %+.1e +- %.1e (quad %.1e)\n",
               name, deg[s], e[s].R.mean, e[s].T.mean, e[s].delta_T.mean, rt - 1, sig, dr.mean, dr.err, qr, dt.mean,
               dt.err, qt);
    }
    CHECK(st.flags == 0, "%s: flags %u", name, st.flags);
    lsqt_estimates_free(e, 3), lsqt_estimates_free(ec, 3);
    lsqt_state_free(&st), lsqt_state_free(&coarse);
}

static void stacks(void)
{
    stack("HG2 (0.8, -0.3, 0.3) slab",
          "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreenstein2Phase g0=0.8 g1=-0.3 b=0.3\n"
          "Layer z=0 NullBsdf\nMedium\n",
          100000);
    stack("SGGX diffuse Apara=0.3 slab",
          "Medium\nLayer z=1 NullBsdf\nMedium mus=1 SggxPhase Apara=0.3 type=Diffuse\nLayer z=0 NullBsdf\nMedium\n",
          100000);
}

/* ---------------------------------------------------------------- section 11: draine */

/* Draine's phase function in double, from its definition (Draine 2003, eq. 4):
 * (1 - g^2) (1 + alpha cos^2 t) / (4 pi (1 + alpha (1 + 2 g^2) / 3) (1 + g^2 - 2 g cos t)^1.5),
 * cos t = -wo.wi. */
static double draine_ref(double g, double alpha, double cost)
{
    return (1 - g * g) * (1 + alpha * cost * cost) /
           (4 * PI * (1 + alpha * (1 + 2 * g * g) / 3) * pow(1 + g * g - 2 * g * cost, 1.5));
}

/* DrainePhase: the sampler against the value (goodness of fit, as section 1, with the
 * normalisation to 1e-4 in it) for four (g, alpha) from Rayleigh-like to a sharp forward
 * peak with a strong cos^2 term; the value against the formula in double (relative 2e-5,
 * float); alpha = 0 is HG(g) bit for bit, values and samples (the sampler then draws as
 * HG's); g = 0, alpha = 1 is Rayleigh rho = 0, 3 / (16 pi) (1 + cos^2) (relative 1e-6);
 * and a lossless Draine slab end to end (as section 7). */
static void draine(void)
{
    const double gs[] = {0.0, 0.7, -0.5, 0.95}, as[] = {1.0, 0.5, 3.0, 20.0};
    const double wos[][3] = {{0, 0, 1}, {0.3, -0.2, 0.9327379}, {-0.48, 0.6, 0.64}, {0.99, 0.1, -0.0995}};
    for (int i = 0; i < 4; i++) {
        gof_case gc = {.m = draine_model(gs[i], as[i], wos[i]), .lo = -1, .integral = 1, .int_tol = 1e-4};
        for (int k = 0; k < 3; k++) gc.axis[k] = -wos[i][k];
        gof(&gc, 100 + i); /* seeds of their own, whichever sections run */
    }

    static float f[4 * NLIM], fp[2 * NLIM];
    static double d[NLIM][3];
    rand_dirs(11, NLIM, f, d);
    double worst = 0;
    for (int i = 0; i < 4; i++) {
        model_t m = draine_model(gs[i], as[i], wos[i]);
        double o[3];
        wo_double(m.wo, o);
        k_eval(&m, m.wo, f, NLIM, fp);
        for (int k = 0; k < NLIM; k++) {
            double ref = draine_ref(m.M.pp[0], m.M.pp[1], -dot3(o, d[k]));
            worst = fmax(worst, fabs(fp[2 * k] / ref - 1));
            worst = fmax(worst, fabs(fp[2 * k + 1] / ref - 1)); /* the density: exact sampler */
        }
    }
    CHECK(worst <= 2e-5, "Draine: largest relative departure from the formula %.3g", worst);

    int neq = 0, nsame = 0;
    for (int i = 0; i < 4; i++) {
        const double g = i == 3 ? -0.999 : gs[i] + 0.1;
        model_t a = phase_model("HG", LSQT_PHASE_HG, g, 0, 0, wos[i]), b = draine_model(g, 0, wos[i]);
        count_differences(&a, &b, f, NLIM, 199u + (cl_uint)i, &neq, &nsame);
    }
    CHECK(neq == 0, "Draine with alpha = 0: %d values differ from HG(g)", neq);
    CHECK(nsame == 0, "Draine with alpha = 0: %d sample coordinates differ from HG(g)'s", nsame);

    double worst_r = 0;
    for (int w = 0; w < 4; w++) {
        model_t m = draine_model(0, 1, wos[w]);
        double o[3];
        wo_double(m.wo, o);
        k_eval(&m, m.wo, f, NLIM, fp);
        for (int k = 0; k < NLIM; k++) {
            double c = dot3(o, d[k]);
            worst_r = fmax(worst_r, fabs(fp[2 * k] / (3 / (16 * PI) * (1 + c * c)) - 1));
        }
    }
    CHECK(worst_r <= 1e-6, "Draine g = 0, alpha = 1: largest relative departure from Rayleigh rho = 0 %.3g", worst_r);
    printf("draine: formula within %.2g, alpha = 0 is HG (%d values, samples bit for bit), g = 0 alpha = 1 is"
           " Rayleigh within %.2g\n", worst, 2 * NLIM * 4, worst_r);

    stack("Draine (0.6, 2) slab",
          "Medium\nLayer z=1 NullBsdf\nMedium mus=1 DrainePhase g=0.6 alpha=2\nLayer z=0 NullBsdf\nMedium\n", 100000);
}

/* ---------------------------------------------------------------- section 12: tabulated */

static char tab_dir[] = "/tmp/test_phases_tab.XXXXXX";

/* A table file of n rows of f(cos t), cos theta descending from 1 to -1 uniformly in theta
 * (as miepython writes one), or the rows given (mu, p: n of them); its path. */
static const char *tab_write(const char *name, double (*f)(double), int n, const double *mu, const double *p)
{
    static char path[256];
    snprintf(path, sizeof path, "%s/%s", tab_dir, name);
    FILE *fp = fopen(path, "w");
    CHECK(fp != NULL, "cannot write %s", path);
    if (!fp) return path;
    fprintf(fp, "# cos(theta) p\n");
    for (int i = 0; i < n; i++) {
        const double c = mu ? mu[i] : cos(PI * i / (n - 1));
        fprintf(fp, "%.17g %.17g\n", c, mu ? p[i] : f(c));
    }
    fclose(fp);
    return path;
}

/* The table as the host reads it, and the model with it (pp as the host packs them: one
 * medium to its end, then offset 0, the rows); *t stays for the references. */
static model_t tab_model(const char *name, const char *path, const double wo[3], lsqt_phase_table *t, float **store)
{
    size_t len = 0;
    char err[512];
    char *text = lsqt_read_text(path, 1 << 26, &len, err, sizeof err);
    CHECK(text && lsqt_phase_table_parse(text, len, path, t, err, sizeof err) == 0, "%s: %s", path, err);
    free(text);
    lsqt_assembly a;
    memset(&a, 0, sizeof a);
    a.n_phase_tables = 1, a.phase_tables = t;
    const size_t n = lsqt_device_phase_tables(&a, NULL);
    double *d = malloc(n * sizeof *d);
    *store = malloc(n * sizeof **store);
    lsqt_device_phase_tables(&a, d);
    for (size_t i = 0; i < n; i++) (*store)[i] = (float)d[i];
    free(d);
    model_t m = phase_model(name, LSQT_PHASE_TABULATED, 1, 0, t->n, wo);
    m.tab = *store, m.tab_reals = n;
    return m;
}

/* The table's linear interpolation at cos t = c, in double. */
static double tab_interp(const lsqt_phase_table *t, double c)
{
    int i = 0;
    while (i + 2 < t->n && t->mu[i + 1] <= c) i++;
    const double x = (c - t->mu[i]) / (t->mu[i + 1] - t->mu[i]);
    return t->p[i] + x * (t->p[i + 1] - t->p[i]);
}

static double hg07(double c) { return hg_ref(0.7, c); }
static double rayleigh0(double c) { return 3 / (16 * PI) * (1 + c * c); }

/* Per slice, R or T (which) of a minus b on the same paths, with its batch-means error. */
static lsqt_est paired(const lsqt_state *a, const lsqt_state *b, int s, int which)
{
    double d[LSQT_BATCHES], total = 0;
    for (int k = 0; k < LSQT_BATCHES; k++) {
        const size_t at = ((size_t)s * LSQT_BATCHES + (size_t)k) * LSQT_T_COUNT + (size_t)which;
        d[k] = (lsqt_u128_to_double(a->scalars[at]) - lsqt_u128_to_double(b->scalars[at])) / LSQT_FIX_SCALE;
        total += d[k];
    }
    const double n = (double)a->paths;
    lsqt_est e = {total / n, 0};
    double ss = 0;
    for (int k = 0; k < LSQT_BATCHES; k++) ss += nee_sqr(d[k] - (double)lsqt_batch_paths(a->paths, k) * e.mean);
    e.err = sqrt(ss * LSQT_BATCHES / (LSQT_BATCHES - 1)) / n;
    return e;
}

static void tabulated(void)
{
    CHECK(mkdtemp(tab_dir) != NULL, "mkdtemp");
    const double wos[][3] = {{0, 0, 1}, {0.3, -0.2, 0.9327379}, {0.99, 0.1, -0.0995}};
    lsqt_phase_table t[3];
    float *store[3];
    char hg_path[256];
    snprintf(hg_path, sizeof hg_path, "%s", tab_write("hg07.txt", hg07, 2001, NULL, NULL));
    model_t m[3];
    m[0] = tab_model("Tabulated HG g=0.7 (2001 rows)", hg_path, wos[0], &t[0], &store[0]);
    m[1] = tab_model("Tabulated Rayleigh (2001 rows)", tab_write("rayleigh.txt", rayleigh0, 2001, NULL, NULL), wos[1],
                     &t[1], &store[1]);
    /* coarse, ascending, uneven, a zero row: its interpolation is no closed form */
    const double cmu[] = {-1, -0.6, 0.1, 0.5, 0.9, 1}, cp[] = {0.3, 0, 0.2, 1.5, 4, 9};
    m[2] = tab_model("Tabulated coarse (6 rows)", tab_write("coarse.txt", NULL, 6, cmu, cp), wos[2], &t[2], &store[2]);

    /* the value: the host's interpolation (float), and the closed forms within the
     * interpolation's error */
    static float f[4 * NLIM], fp[2 * NLIM];
    static double d[NLIM][3];
    rand_dirs(13, NLIM, f, d);
    double worst_i = 0, worst_c[2] = {0, 0};
    for (int i = 0; i < 3; i++) {
        double o[3];
        wo_double(m[i].wo, o);
        k_eval(&m[i], m[i].wo, f, NLIM, fp);
        for (int k = 0; k < NLIM; k++) {
            const double c = -dot3(o, d[k]), ref = tab_interp(&t[i], c);
            worst_i = fmax(worst_i, fabs(fp[2 * k] - ref) / fmax(ref, 1e-3));
            worst_i = fmax(worst_i, fabs(fp[2 * k + 1] - ref) / fmax(ref, 1e-3)); /* the density: exact sampler */
            if (i < 2) worst_c[i] = fmax(worst_c[i], fabs(fp[2 * k] / (i ? rayleigh0(c) : hg07(c)) - 1));
        }
    }
    CHECK(worst_i <= 1e-5, "Tabulated: largest relative departure from the table's interpolation %.3g", worst_i);
    CHECK(worst_c[0] <= 2e-4, "Tabulated HG 0.7: largest relative departure from the closed form %.3g", worst_c[0]);
    CHECK(worst_c[1] <= 2e-4, "Tabulated Rayleigh: largest relative departure from the closed form %.3g", worst_c[1]);
    printf("tabulated: the interpolation within %.2g, HG within %.2g, Rayleigh within %.2g\n", worst_i, worst_c[0],
           worst_c[1]);

    /* the sampler against its own interpolated density, normalisation included */
    for (int i = 0; i < 3; i++) {
        gof_case gc = {.m = m[i], .lo = -1, .integral = 1, .int_tol = 1e-4};
        for (int k = 0; k < 3; k++) gc.axis[k] = -wos[i][k];
        gof(&gc, 110 + i);
    }

    /* a stack of two tables (each medium finds its own) against the closed forms they
     * tabulate, on the same paths */
    const double deg[] = {0, 45, 80};
    char text[1024], rayleigh_path[256];
    snprintf(rayleigh_path, sizeof rayleigh_path, "%s/rayleigh.txt", tab_dir);
    snprintf(text, sizeof text, "Medium\nLayer z=2 NullBsdf\nMedium mus=1 TabulatedPhase table=@%s\nLayer z=1 NullBsdf\n"
             "Medium mus=0.5 TabulatedPhase table=@%s\nLayer z=0 NullBsdf\nMedium\n", hg_path, rayleigh_path);
    for (int dbl = 0; dbl < 2; dbl++) { /* float and --double: the tables in each precision */
        lsqt_state sa, sb;
        lsqt_slice_est *ea = fixture_run_prec(text, 3, deg, 64, 40000, 23, dbl, &sa);
        lsqt_slice_est *eb = fixture_run_prec("Medium\nLayer z=2 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0.7\n"
                                              "Layer z=1 NullBsdf\nMedium mus=0.5 RayleighPhase\nLayer z=0 NullBsdf\n"
                                              "Medium\n", 3, deg, 64, 40000, 23, dbl, &sb);
        const char *prec = dbl ? "double" : "float";
        for (int s = 0; s < 3; s++) {
            const lsqt_est dr = paired(&sa, &sb, s, LSQT_T_R), dt = paired(&sa, &sb, s, LSQT_T_T);
            const double r = eb[s].R.mean, tt = eb[s].T.mean;
            CHECK(fabs(dr.mean) <= 4 * dr.err + 2e-4 * r, "Tabulated HG over Rayleigh (%s), %g degrees: R - R(closed "
                  "forms) = %.3g +- %.2g (R %.4f)", prec, deg[s], dr.mean, dr.err, r);
            CHECK(fabs(dt.mean) <= 4 * dt.err + 2e-4 * tt, "Tabulated HG over Rayleigh (%s), %g degrees: T - T(closed "
                  "forms) = %.3g +- %.2g (T %.4f)", prec, deg[s], dt.mean, dt.err, tt);
            CHECK(4 * dr.err + 2e-4 * r < 0.01 * r && 4 * dt.err + 2e-4 * tt < 0.01 * tt,
                  "Tabulated HG over Rayleigh (%s), %g degrees: the test cannot see 1 %% (R +- %.2g, T +- %.2g)", prec,
                  deg[s], dr.err, dt.err);
            printf("Tabulated HG over Rayleigh (%s) %2g deg: R %.5f - closed %+.2e +- %.1e, T %.5f - closed %+.2e +- "
                   "%.1e\n", prec, deg[s], ea[s].R.mean, dr.mean, dr.err, ea[s].T.mean, dt.mean, dt.err);
        }
        lsqt_estimates_free(ea, 3), lsqt_estimates_free(eb, 3);
        lsqt_state_free(&sa), lsqt_state_free(&sb);
    }
    /* the coarse table in a lossless slab: R + T = 1, next-event estimates = exits (7) */
    char coarse_path[256];
    snprintf(coarse_path, sizeof coarse_path, "%s/coarse.txt", tab_dir);
    snprintf(text, sizeof text, "Medium\nLayer z=1 NullBsdf\nMedium mus=1 TabulatedPhase table=@%s\nLayer z=0 NullBsdf\n"
             "Medium\n", coarse_path);
    stack("Tabulated coarse slab", text, 100000);
    for (int i = 0; i < 3; i++) lsqt_phase_table_free(&t[i]), free(store[i]);
    const char *names[] = {"hg07.txt", "rayleigh.txt", "coarse.txt"};
    for (int i = 0; i < 3; i++) {
        char path[256];
        snprintf(path, sizeof path, "%s/%s", tab_dir, names[i]);
        remove(path);
    }
    remove(tab_dir);
}

/* ---------------------------------------------------------------- main */

static int want(int argc, char **argv, const char *sec)
{
    if (argc < 2) return 1;
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], sec)) return 1;
    return 0;
}

int main(int argc, char **argv)
{
    const double t_start = check_now();
    /* the p-values against closed forms: Q(1, x/2) = e^(-x/2), Q(2, x/2) = e^(-x/2)(1 + x/2),
     * chi-square with 1 dof erfc(sqrt(x/2)), both sides of the series/fraction switch;
     * Kolmogorov's 5 % point 1.3581 (large n) */
    for (double x = 0.5; x < 60; x *= 1.7) {
        CHECK(fabs(chi2_p(x, 2) / exp(-x / 2) - 1) < 1e-10, "chi2_p(%g, 2) = %.15g", x, chi2_p(x, 2));
        CHECK(fabs(chi2_p(x, 4) / (exp(-x / 2) * (1 + x / 2)) - 1) < 1e-10, "chi2_p(%g, 4) = %.15g", x, chi2_p(x, 4));
        CHECK(fabs(chi2_p(x, 1) / erfc(sqrt(x / 2)) - 1) < 1e-9, "chi2_p(%g, 1) = %.15g", x, chi2_p(x, 1));
    }
    CHECK(fabs(ks_p(1.3581 / 1e6, 1e12) - 0.05) < 1e-4, "ks_p at Kolmogorov's 5 %% point: %.6f", ks_p(1.3581 / 1e6, 1e12));
    fixture_open();
    prog = fixture_build("-cl-std=CL1.2 -DLSQT_HAS_PHASE_HG=1 -DLSQT_HAS_PHASE_HG2=1 -DLSQT_HAS_PHASE_RAYLEIGH=1 "
                         "-DLSQT_HAS_PHASE_SGGX=1 -DLSQT_HAS_PHASE_DRAINE=1 -DLSQT_HAS_PHASE_TABULATED=1 "
                         "-DLSQT_HAS_BSDF_OREN_NAYAR=1");
    if (!prog) return check_finish("test_phases");
    printf("build %.1f s\n", check_now() - t_start);
    const char *secs[] = {"hg2", "rayleigh", "sggx-specular", "sggx-diffuse", "oren-nayar", "peaks", "rayleigh-ks",
                          "limits", "reciprocity", "stacks", "draine", "tabulated"};
    enum { NSEC = 12 };
    static const int n_pvalues[NSEC] = {6, 8, 18, 18, 30, 6, 5, 0, 1, 0, 8, 6}; /* per section; they sum to N_FAMILY */
    int sum = 0;
    for (int k = 0; k < NSEC; k++) sum += n_pvalues[k];
    CHECK(sum == N_FAMILY, "n_pvalues sum to %d, N_FAMILY is %d", sum, N_FAMILY);
    for (int i = 1; i < argc; i++) {
        int ok = 0;
        for (int k = 0; k < NSEC; k++) ok |= !strcmp(argv[i], secs[k]);
        CHECK(ok, "unknown section '%s'", argv[i]);
    }
    for (int k = 0; k < NSEC; k++) {
        if (!want(argc, argv, secs[k])) {
            if (k < 5) n_case += k == 0 ? 3 : k == 1 ? 4 : k == 4 ? 10 : 9; /* the same seeds whatever runs */
            continue;
        }
        double t0 = check_now();
        switch (k) {
        case 0: fits_hg2(); break;
        case 1: fits_rayleigh(); break;
        case 2: fits_sggx(0); break;
        case 3: fits_sggx(1); break;
        case 4: fits_oren_nayar(); break;
        case 5: peaks(); break;
        case 6: rayleigh_ks(); break;
        case 7: limits(); break;
        case 8: reciprocity(); break;
        case 9: stacks(); break;
        case 10: draine(); break;
        case 11: tabulated(); break;
        }
        printf("[%s: %.1f s]\n", secs[k], check_now() - t0);
    }

    /* the family: Bonferroni over every p-value of a full run, so that a section alone
     * (ctest runs each as its own test) rejects exactly what the full run rejects */
    int expect = 0;
    for (int k = 0; k < NSEC; k++) expect += want(argc, argv, secs[k]) ? n_pvalues[k] : 0;
    CHECK(gof_n_tests == expect, "%d p-values recorded, %d expected: update n_pvalues and N_FAMILY", gof_n_tests,
          expect);
    gof_verdict(N_FAMILY, "tilt along mu");
    printf("total %.1f s, kernels %.1f s\n", check_now() - t_start, fixture_kernel_s);
    clReleaseProgram(prog);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_phases");
}
