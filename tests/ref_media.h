/* Closed-form references for media shared by test_references and test_power_media:
 * composite Gauss-Legendre panels, the HG phase function, (1 - e^-x)/x, E3, the bound on
 * multiple scattering in an optically thin slab (test_references.c, section 1, derives
 * it), and Chandrasekhar's H function of a semi-infinite isotropic medium. */
#ifndef LSQT_TESTS_REF_MEDIA_H
#define LSQT_TESTS_REF_MEDIA_H

#include <math.h>

#include "quadrature.h"

#ifndef PI
#define PI 3.14159265358979323846
#endif

/* Composite Gauss-Legendre with n nodes on each panel [e[i], e[i+1]]; returns the count. */
static inline int composite_gl(const double *edges, int n_panels, int n, double *x, double *w)
{
    double gx[64], gw[64];
    gauss_legendre(n, gx, gw);
    int m = 0;
    for (int p = 0; p < n_panels; p++) {
        double a = edges[p], b = edges[p + 1];
        for (int i = 0; i < n; i++, m++) {
            x[m] = 0.5 * (a + b) + 0.5 * (b - a) * gx[i];
            w[m] = 0.5 * (b - a) * gw[i];
        }
    }
    return m;
}

/* Henyey-Greenstein, normalised over the sphere, c = cosine of the scattering angle. */
static inline double hg(double g, double c)
{
    double d = 1.0 + g * g - 2.0 * g * c;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

/* (1 - e^-x) / x, also for x near 0 and x < 0 */
static inline double phi1(double x) { return fabs(x) < 1e-300 ? 1.0 : -expm1(-x) / x; }

/* 2 E3(tau) is the share of diffuse light a clear slab of optical thickness tau passes. */
static inline double e3(double tau)
{
    double x[128], w[128], sum = 0;
    gauss_legendre(128, x, w);
    for (int i = 0; i < 128; i++) {
        double mu = 0.5 * (x[i] + 1);
        sum += 0.5 * w[i] * mu * exp(-tau / mu);
    }
    return sum;
}

enum { MS_NP = 15, MS_NG = 8, MS_NMU = MS_NP * MS_NG, MS_NPHI = 128 };
typedef struct {
    double g, tau;
    double mu[MS_NMU], w[MS_NMU]; /* |d.z| nodes in (0, 1) and weights */
    double cphi[MS_NPHI], sphi[MS_NPHI];
    double q[MS_NMU];             /* q(|d.z| = mu[i]) */
    double qsup;
} ms_grid;

static inline void ms_grid_init(ms_grid *G, double g, double tau)
{
    static const double edges[MS_NP + 1] = {0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.04, 0.1, 0.2, 0.35,
                                            0.5, 0.65, 0.8, 0.9, 0.97, 1};
    G->g = g;
    G->tau = tau;
    composite_gl(edges, MS_NP, MS_NG, G->mu, G->w);
    for (int j = 0; j < MS_NPHI; j++) {
        G->cphi[j] = cos(2.0 * PI * (j + 0.5) / MS_NPHI);
        G->sphi[j] = sin(2.0 * PI * (j + 0.5) / MS_NPHI);
    }
    /* q(d) for d = (sqrt(1 - mu^2), 0, mu); m2 is even in d'.z, so q is even in mu. */
    G->qsup = 0.0;
    for (int a = 0; a < MS_NMU; a++) {
        const double mu = G->mu[a], s = sqrt(1.0 - mu * mu);
        double q = 0.0;
        for (int side = -1; side <= 1; side += 2)
            for (int i = 0; i < MS_NMU; i++) {
                const double mu2 = side * G->mu[i], s2 = sqrt(1.0 - mu2 * mu2);
                const double m2 = -expm1(-tau / G->mu[i]) * G->w[i] * (2.0 * PI / MS_NPHI);
                for (int j = 0; j < MS_NPHI; j++) q += m2 * hg(g, s * s2 * G->cphi[j] + mu * mu2);
            }
        G->q[a] = 1.1 * q;
        G->qsup = fmax(G->qsup, G->q[a]);
    }
}

/* J[k] for the directions wi[k] and Q3 (above) for a slice with cos(theta_o) = muo. */
static inline void ms_integrals(const ms_grid *G, double muo, const double (*wi)[3], int nwi, double *J, double *Q3)
{
    const double g = G->g, tau = G->tau;
    const double lam = muo / tau, tbar = lam - 1.0 / expm1(1.0 / lam); /* E[t], t in [0, 1] */
    const double so = sqrt(1.0 - muo * muo);
    for (int k = 0; k < nwi; k++) J[k] = 0.0;
    *Q3 = 0.0;
    for (int side = -1; side <= 1; side += 2) {
        for (int i = 0; i < MS_NMU; i++) {
            const double mu = side * G->mu[i], st = sqrt(1.0 - mu * mu);
            const double m = -expm1(-tau * (mu > 0 ? tbar : 1.0 - tbar) / G->mu[i]);
            for (int j = 0; j < MS_NPHI; j++) {
                const double d[3] = {st * G->cphi[j], st * G->sphi[j], mu};
                const double a = hg(g, -so * d[0] - muo * d[2]) * m * G->w[i] * (2.0 * PI / MS_NPHI);
                *Q3 += a * G->q[i];
                for (int k = 0; k < nwi; k++) J[k] += a * hg(g, d[0] * wi[k][0] + d[1] * wi[k][1] + d[2] * wi[k][2]);
            }
        }
    }
    for (int k = 0; k < nwi; k++) J[k] *= 1.1;
    *Q3 *= 1.1;
}

enum { H_PANELS = 8, H_MAX = H_PANELS * 32 };
typedef struct {
    double omega;
    int n;
    double x[H_MAX], w[H_MAX], h[H_MAX];
} hfun;

/* 1/H(mu) = sqrt(1 - om) + (om/2) int_0^1 mu' H(mu') / (mu + mu') dmu' (Chandrasekhar,
 * Radiative Transfer, ch. V), iterated on composite Gauss-Legendre nodes graded towards
 * mu = 0 (the kernel mu'/(mu + mu') has a layer of width mu there) until it stops
 * changing; H anywhere else is the same formula at that mu (Nystrom). */
static inline int h_solve(hfun *H, double omega, int per_panel)
{
    static const double edges[H_PANELS + 1] = {0, 1e-4, 1e-3, 1e-2, 0.05, 0.15, 0.35, 0.65, 1};
    H->omega = omega;
    H->n = composite_gl(edges, H_PANELS, per_panel, H->x, H->w);
    const double s = sqrt(1.0 - omega);
    double wx[H_MAX];
    for (int i = 0; i < H->n; i++) {
        H->h[i] = 1.0;
        wx[i] = H->w[i] * H->x[i];
    }
    for (int it = 1; it <= 20000; it++) {
        double change = 0.0;
        for (int j = 0; j < H->n; j++) {
            double sum = 0.0;
            for (int i = 0; i < H->n; i++) sum += wx[i] * H->h[i] / (H->x[j] + H->x[i]);
            double v = 1.0 / (s + 0.5 * omega * sum);
            change = fmax(change, fabs(v - H->h[j]));
            H->h[j] = v; /* Gauss-Seidel */
        }
        if (change < 1e-13) return it;
    }
    return -1;
}

static inline double h_eval(const hfun *H, double mu)
{
    double sum = 0.0;
    for (int i = 0; i < H->n; i++) sum += H->w[i] * H->x[i] * H->h[i] / (mu + H->x[i]);
    return 1.0 / (sqrt(1.0 - H->omega) + 0.5 * H->omega * sum);
}

#endif
