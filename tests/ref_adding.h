/* An independent reference for stacks of homogeneous media between index-matched (null)
 * layers: the adding-doubling method of radiative transfer, in double precision, written
 * for the tests from the textbook equations (van de Hulst, Multiple Light Scattering,
 * ch. 4; Hansen & Travis 1974, Space Sci. Rev. 16, 527, sec. 3.4). It owes nothing to the
 * program: no kernel code, no sampling.
 *
 * What it computes: for a stack of slabs (optical thickness tau, albedo om, Henyey-
 * Greenstein g; top first), optionally over an opaque Lambertian floor, lit from above by
 * a collimated beam travelling down with direction cosine -mu0, the BSDF f (1/sr,
 * without the cosine: the RAW value) of the scattered light at exit direction cosine mu
 * (up: reflection, down: transmission) and azimuth dphi measured from the beam's
 * direction of travel. The unscattered beam (exp(-tau/mu0), a delta) is kept apart and
 * never put on the grid.
 *
 * How:
 *  - Azimuth: f(dphi) = sum_m a_m cos(m dphi), m < nm. Composing two kernels in azimuth
 *    multiplies mode m's coefficients and kappa_m = 2 pi (m = 0) or pi (m > 0).
 *  - Polar cosines: composite Gauss-Legendre nodes on (0, 1), graded towards 0, then
 *    "extra" nodes of weight 0, the directions the test asks about: they take part in no
 *    integral, yet every kernel is computed at them exactly as at the quadrature nodes
 *    (rows and columns of the same equations), so there is no interpolation.
 *  - A kernel K(mu, mu') acts by sum_j K(mu, mu_j) L(mu_j) W_j, W_j = kappa_m mu_j w_j.
 *  - A thin slab (t0 = tau / 2^N) starts as its exact single-scattering kernels,
 *      R0 = om p_m(-mu mu') t0 phi1(t0 (1/mu + 1/mu')) / (mu mu'),
 *      T0 = om p_m(+mu mu') int_0^t0 e^{-s/mu' - (t0 - s)/mu} ds / (mu mu'),
 *    p_m the azimuthal Fourier coefficients of HG by the periodic trapezoid rule (exact
 *    to rounding at 256 points for |g| <= 0.9: the integrand is analytic in a strip).
 *  - Adding a over b (a symmetric, R' = R, T' = T, as a homogeneous slab is), with
 *    Ea, Eb the diagonal direct transmittances e^{-tau/mu}:
 *      D = (I - Ra W Rb W)^{-1} (Ta + Ra W Rb Ea)          diffuse down at the interface
 *      U = Rb Ea + Rb W D                                   diffuse up at the interface
 *      R = Ra + Ea U + Ta W U,   T = Eb D + Tb Ea + Tb W D
 *    (Ea on the right scales columns: the beam reaching the interface; on the left,
 *    rows: light leaving through the slab). Doubling is adding a slab to itself. A
 *    Lambertian floor is a b of R = fR/pi in mode 0, T = 0, tau infinite (E = 0).
 *  - The thin start misses double scattering inside t0, an error of order t0 log(1/t0)
 *    after the doublings (so Richardson's step does little): t0 <= 1e-7.
 *  - Single scattering, which carries all the sharp azimuthal structure, is the closed
 *    form at the exact dphi; only the multiply scattered rest comes from the Fourier sum
 *    (the adding reproduces the single-scattering modes exactly, so they are subtracted
 *    mode by mode), so few modes suffice.
 * The tests check this code against Chandrasekhar's H function, iadpython's hemispherical
 * R and T, energy conservation and its own resolution (tests/test_media_stacks.c). */
#ifndef LSQT_TESTS_REF_ADDING_H
#define LSQT_TESTS_REF_ADDING_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ref_media.h"

enum { AD_PANELS = 14, AD_NPHI = 256, AD_MAX_SLABS = 8 };

typedef struct {
    int n, nq, nm;  /* nodes (nq quadrature nodes, then extras of weight 0), modes */
    double *mu, *w; /* cosines in (0, 1] and quadrature weights on (0, 1) (0: extra) */
} ad_grid;

/* A slab's (or stack's) diffuse kernels: nm matrices of n x n, [m][exit i][incident j];
 * R from above (= from below for a homogeneous slab), T downwards. */
typedef struct {
    double tau;
    double *R, *T;
} ad_slab;

/* Quadrature of per_panel nodes on each panel, then the extra cosines (each in (0, 1]). */
static inline void ad_grid_init(ad_grid *G, int per_panel, int nm, const double *extra, int n_extra)
{
    static const double edges[AD_PANELS + 1] = {0,   1e-5, 1e-4, 1e-3, 5e-3, 0.02, 0.05, 0.1,
                                                0.2, 0.35, 0.5,  0.65, 0.8,  0.92, 1};
    G->nq = AD_PANELS * per_panel;
    G->n = G->nq + n_extra;
    G->nm = nm;
    G->mu = malloc(sizeof(double) * (size_t)G->n);
    G->w = malloc(sizeof(double) * (size_t)G->n);
    composite_gl(edges, AD_PANELS, per_panel, G->mu, G->w);
    for (int i = 0; i < n_extra; i++) G->mu[G->nq + i] = extra[i], G->w[G->nq + i] = 0.0;
}

static inline void ad_grid_free(ad_grid *G)
{
    free(G->mu);
    free(G->w);
}

static inline size_t ad_size(const ad_grid *G) { return (size_t)G->nm * (size_t)G->n * (size_t)G->n; }

static inline void ad_slab_alloc(const ad_grid *G, ad_slab *s)
{
    s->tau = 0.0;
    s->R = calloc(ad_size(G), sizeof(double));
    s->T = calloc(ad_size(G), sizeof(double));
}

static inline void ad_slab_free(ad_slab *s)
{
    free(s->R);
    free(s->T);
}

static inline double ad_kappa(int m) { return m == 0 ? 2.0 * PI : PI; }

/* p_m[m][i][j]: Fourier coefficients in azimuth of HG at cosine sign mu_i mu_j +
 * sin_i sin_j cos(x) (sign -1: reflection, +1: transmission). */
static inline void ad_phase_modes(const ad_grid *G, double g, int sign, double *pm)
{
    const int n = G->n, nm = G->nm;
    double c[AD_NPHI], v[AD_NPHI];
    for (int k = 0; k < AD_NPHI; k++) c[k] = cos(2.0 * PI * k / AD_NPHI);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            const double mi = G->mu[i], mj = G->mu[j];
            const double ss = sqrt(fmax(0.0, 1.0 - mi * mi) * fmax(0.0, 1.0 - mj * mj));
            for (int k = 0; k < AD_NPHI; k++) v[k] = hg(g, sign * mi * mj + ss * c[k]);
            for (int m = 0; m < nm; m++) {
                double s = 0.0;
                for (int k = 0; k < AD_NPHI; k++) s += v[k] * c[(m * k) % AD_NPHI];
                pm[((size_t)m * n + i) * n + j] = s * (m == 0 ? 1.0 : 2.0) / AD_NPHI;
            }
        }
}

/* C = A diag(d) B for n x n matrices (d = NULL: the identity). */
static inline void ad_mul(int n, const double *A, const double *d, const double *B, double *C)
{
    memset(C, 0, sizeof(double) * (size_t)n * (size_t)n);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < n; k++) {
            const double a = A[i * n + k] * (d ? d[k] : 1.0);
            if (a == 0.0) continue;
            const double *b = B + (size_t)k * n;
            double *c = C + (size_t)i * n;
            for (int j = 0; j < n; j++) c[j] += a * b[j];
        }
}

/* Solves M X = B in place (B becomes X) by Gaussian elimination with partial pivoting;
 * M is destroyed. */
static inline void ad_solve(int n, double *M, double *B)
{
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(M[i * n + k]) > fabs(M[p * n + k])) p = i;
        if (p != k)
            for (int j = 0; j < n; j++) {
                double t = M[k * n + j];
                M[k * n + j] = M[p * n + j], M[p * n + j] = t;
                t = B[k * n + j];
                B[k * n + j] = B[p * n + j], B[p * n + j] = t;
            }
        const double inv = 1.0 / M[k * n + k];
        for (int i = k + 1; i < n; i++) {
            const double f = M[i * n + k] * inv;
            if (f == 0.0) continue;
            for (int j = k; j < n; j++) M[i * n + j] -= f * M[k * n + j];
            for (int j = 0; j < n; j++) B[i * n + j] -= f * B[k * n + j];
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        const double inv = 1.0 / M[k * n + k];
        for (int j = 0; j < n; j++) {
            double s = B[k * n + j];
            for (int i = k + 1; i < n; i++) s -= M[k * n + i] * B[i * n + j];
            B[k * n + j] = s * inv;
        }
    }
}

/* out = a over b (out may be a or b). */
static inline void ad_add(const ad_grid *G, const ad_slab *a, const ad_slab *b, ad_slab *out)
{
    const int n = G->n;
    const size_t nn = (size_t)n * n;
    double *W = malloc(sizeof(double) * n), *Ea = malloc(sizeof(double) * n), *Eb = malloc(sizeof(double) * n);
    double *X = malloc(sizeof(double) * nn), *Q = malloc(sizeof(double) * nn), *D = malloc(sizeof(double) * nn);
    double *U = malloc(sizeof(double) * nn), *Y = malloc(sizeof(double) * nn);
    for (int j = 0; j < n; j++) Ea[j] = exp(-a->tau / G->mu[j]), Eb[j] = exp(-b->tau / G->mu[j]);
    for (int m = 0; m < G->nm; m++) {
        const double *Ra = a->R + m * nn, *Ta = a->T + m * nn, *Rb = b->R + m * nn, *Tb = b->T + m * nn;
        for (int j = 0; j < n; j++) W[j] = ad_kappa(m) * G->mu[j] * G->w[j];
        ad_mul(n, Ra, W, Rb, Q); /* Q = Ra W Rb */
        /* X = I - Q W;  D = Ta + Q Ea (Ea scaling columns) */
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                X[i * n + j] = (i == j) - Q[i * n + j] * W[j];
                D[i * n + j] = Ta[i * n + j] + Q[i * n + j] * Ea[j];
            }
        ad_solve(n, X, D);
        ad_mul(n, Rb, W, D, U); /* U = Rb Ea + Rb W D */
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) U[i * n + j] += Rb[i * n + j] * Ea[j];
        ad_mul(n, Ta, W, U, Y); /* R = Ra + Ea U + Ta W U */
        double *Ro = out->R + m * nn, *To = out->T + m * nn;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) Y[i * n + j] += Ra[i * n + j] + Ea[i] * U[i * n + j];
        ad_mul(n, Tb, W, D, U); /* T = Eb D + Tb Ea + Tb W D (U is free now) */
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) U[i * n + j] += Eb[i] * D[i * n + j] + Tb[i * n + j] * Ea[j];
        memcpy(Ro, Y, sizeof(double) * nn);
        memcpy(To, U, sizeof(double) * nn);
    }
    out->tau = a->tau + b->tau;
    free(W), free(Ea), free(Eb), free(X), free(Q), free(D), free(U), free(Y);
}

/* int_0^t e^{-s b - (t - s) a} ds: in at rate b, out at rate a, without the 0 * inf
 * of e^{-t a} t phi1(t (b - a)) when a is huge. */
static inline double ad_cross(double t, double b, double a) { return exp(-t * fmin(a, b)) * t * phi1(t * fabs(a - b)); }

/* The exact single-scattering kernels of a slab of thickness t, from the phase modes. */
static inline void ad_thin(const ad_grid *G, double om, double t, const double *pR, const double *pT, ad_slab *s)
{
    const int n = G->n;
    for (int m = 0; m < G->nm; m++)
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                const double mi = G->mu[i], mj = G->mu[j];
                const size_t at = ((size_t)m * n + i) * n + j;
                s->R[at] = om * pR[at] * t * phi1(t * (1.0 / mi + 1.0 / mj)) / (mi * mj);
                s->T[at] = om * pT[at] * ad_cross(t, 1.0 / mj, 1.0 / mi) / (mi * mj);
            }
    s->tau = t;
}

/* A slab of optical thickness tau and albedo om (phase modes pR, pT), doubled from a
 * start 2^-halvings as thick. */
static inline void ad_slab_make(const ad_grid *G, double tau, double om, const double *pR, const double *pT,
                                int halvings, ad_slab *s)
{
    ad_thin(G, om, ldexp(tau, -halvings), pR, pT, s);
    for (int k = 0; k < halvings; k++) ad_add(G, s, s, s);
}

/* A stack: its slabs, top first, and optionally an opaque Lambertian floor under them
 * (floor = 1, reflectance floor_fr). */
typedef struct {
    int n;
    double tau[AD_MAX_SLABS], om[AD_MAX_SLABS], g[AD_MAX_SLABS];
    int floor;
    double floor_fr;
} ad_stack_desc;

/* The single-scattering BSDF of the stack, lit along -mu0 (down), exit cosine mu
 * (up > 0: reflection), with phase value p_k for slab k, HG at cosine c of the
 * scattering angle (pm = NULL), or mode m's coefficient from pm[k] at (i, j). */
static inline double ad_single(const ad_stack_desc *S, double mu0, double mu, double c, double *const *pm_R,
                               double *const *pm_T, size_t at)
{
    double total = 0.0, above = 0.0, sum = 0.0;
    for (int k = 0; k < S->n; k++) total += S->tau[k];
    const double a = fabs(mu);
    for (int k = 0; k < S->n; k++) {
        const double t = S->tau[k];
        double p, v;
        if (mu > 0) {
            p = pm_R ? pm_R[k][at] : hg(S->g[k], c);
            v = exp(-above * (1.0 / mu0 + 1.0 / a)) * t * phi1(t * (1.0 / mu0 + 1.0 / a));
        } else {
            p = pm_T ? pm_T[k][at] : hg(S->g[k], c);
            const double below = total - above - t;
            v = exp(-above / mu0 - below / a) * ad_cross(t, 1.0 / mu0, 1.0 / a);
        }
        sum += S->om[k] * p * v / (mu0 * a);
        above += t;
    }
    return sum;
}

/* The reference for a whole stack: its kernels (adding the slabs top to bottom) and the
 * phase modes of each slab for the single-scattering split. */
typedef struct {
    ad_grid G;
    ad_stack_desc S;
    ad_slab all;
    double *pR[AD_MAX_SLABS], *pT[AD_MAX_SLABS];
    int diffuse_top; /* a Lambertian layer over the slabs (ad_ref_lambertian_top) */
} ad_ref;

/* Builds the reference of stack S on grid G (taken over: freed by ad_ref_free), each slab
 * doubled from a start no thicker than t0. The
 * slabs are added from the bottom up, so the upper operand of every adding is one
 * homogeneous slab (R' = R, T' = T, as ad_add assumes) and the lower one the stack below
 * it, whose R from above and T downwards are all that ad_add uses of it. */
static inline void ad_ref_make(ad_ref *r, const ad_grid *G, const ad_stack_desc *S, double t0)
{
    r->G = *G;
    r->S = *S;
    r->diffuse_top = 0;
    ad_slab_alloc(G, &r->all);
    if (S->floor) { /* f = fR / pi in mode 0, nothing through: tau infinite */
        const size_t nn = (size_t)G->n * (size_t)G->n;
        for (size_t i = 0; i < nn; i++) r->all.R[i] = S->floor_fr / PI;
        r->all.tau = INFINITY;
    }
    for (int k = S->n - 1; k >= 0; k--) {
        r->pR[k] = malloc(sizeof(double) * ad_size(G));
        r->pT[k] = malloc(sizeof(double) * ad_size(G));
        ad_phase_modes(G, S->g[k], -1, r->pR[k]);
        ad_phase_modes(G, S->g[k], +1, r->pT[k]);
        /* a start no thicker than t0 */
        int h = 0;
        while (ldexp(S->tau[k], -h) > t0) h++;
        ad_slab s;
        ad_slab_alloc(G, &s);
        ad_slab_make(G, S->tau[k], S->om[k], r->pR[k], r->pT[k], h, &s);
        if (k == S->n - 1 && !S->floor) {
            memcpy(r->all.R, s.R, sizeof(double) * ad_size(G));
            memcpy(r->all.T, s.T, sizeof(double) * ad_size(G));
            r->all.tau = s.tau;
        } else {
            ad_add(G, &s, &r->all, &r->all);
        }
        ad_slab_free(&s);
    }
}

/* Puts a Lambertian layer over the stack of r: reflection fR / pi and transmission
 * fT / pi, the same from either side (a symmetric operand, as ad_add needs), nothing
 * unscattered through it (tau infinite), mode 0 only. Light reaches the slabs only
 * diffusely then, so f has no sharp single-scattering part and no azimuthal modes: it is
 * the composed kernels' mode 0, read as is (ad_ref_f skips the single-scattering split). */
static inline void ad_ref_lambertian_top(ad_ref *r, double fr, double ft)
{
    const ad_grid *G = &r->G;
    const size_t nn = (size_t)G->n * (size_t)G->n;
    ad_slab L;
    ad_slab_alloc(G, &L);
    for (size_t i = 0; i < nn; i++) L.R[i] = fr / PI, L.T[i] = ft / PI;
    L.tau = INFINITY;
    ad_add(G, &L, &r->all, &r->all);
    ad_slab_free(&L);
    r->diffuse_top = 1;
}

static inline void ad_ref_free(ad_ref *r)
{
    ad_slab_free(&r->all);
    for (int k = 0; k < r->S.n; k++) free(r->pR[k]), free(r->pT[k]);
    ad_grid_free(&r->G);
}

/* The node of cosine a (an extra node or a quadrature node), or -1. */
static inline int ad_node(const ad_grid *G, double a)
{
    for (int i = 0; i < G->n; i++)
        if (G->mu[i] == a) return i;
    return -1;
}

/* f at exit direction cosine mu (signed) and azimuth dphi from the beam's direction of
 * travel, for the beam at cosine mu0; both |cosines| must be nodes of the grid. With
 * nm_used < the grid's modes, only the first nm_used (to see the truncation). */
static inline double ad_ref_f(const ad_ref *r, double mu0, double mu, double dphi, int nm_used)
{
    const ad_grid *G = &r->G;
    const int i = ad_node(G, fabs(mu)), j = ad_node(G, mu0), n = G->n;
    if (i < 0 || j < 0) return NAN;
    const double *K = mu > 0 ? r->all.R : r->all.T;
    if (r->diffuse_top) return K[(size_t)i * n + j]; /* mode 0 is all there is */
    double ms = 0.0;
    for (int m = 0; m < nm_used && m < G->nm; m++) {
        const size_t at = ((size_t)m * n + i) * n + j;
        ms += (K[at] - ad_single(&r->S, mu0, mu, 0.0, r->pR, r->pT, at)) * cos(m * dphi);
    }
    const double s0 = sqrt(fmax(0.0, 1.0 - mu0 * mu0)), s = sqrt(fmax(0.0, 1.0 - mu * mu));
    const double c = -mu0 * mu + s0 * s * cos(dphi); /* travel (-mu0) against exit (mu) */
    return ms + ad_single(&r->S, mu0, mu, c, NULL, NULL, 0);
}

/* Hemispherical integrals of the diffuse light, mode 0 over the quadrature nodes: R
 * (up) and the scattered part of T (down) for the beam at node cosine mu0. */
static inline void ad_ref_hemi(const ad_ref *r, double mu0, double *R, double *T)
{
    const ad_grid *G = &r->G;
    const int j = ad_node(G, mu0), n = G->n;
    *R = *T = 0.0;
    for (int i = 0; i < G->nq; i++) {
        *R += 2.0 * PI * r->all.R[(size_t)i * n + j] * G->mu[i] * G->w[i];
        *T += 2.0 * PI * r->all.T[(size_t)i * n + j] * G->mu[i] * G->w[i];
    }
}

#endif
