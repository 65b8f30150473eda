/* An independent double-precision model of the single-scattering GGX conductor, written
 * from the formulas (Walter et al. 2007 D and Smith Lambda for GGX, Heitz 2014 height-
 * correlated G2, the Fresnel amplitudes of a complex index), for the tests:
 *   f |cos i| = F(wo.h) D(h) G2(wo, wi) / (4 cos o),  G2 = 1 / (1 + L(wo) + L(wi)),
 *   D = a^2 / (pi ((a^2 - 1) cos^2 h + 1)^2),  L = (sqrt(1 + a^2 tan^2) - 1) / 2,
 *   rs = (c - t)/(c + t), rp = (n^2 c - t)/(n^2 c + t), t = sqrt(n^2 - sin^2). */
#ifndef LSQT_TESTS_REF_CONDUCTOR_H
#define LSQT_TESTS_REF_CONDUCTOR_H

#include <complex.h>
#include <math.h>

#include "quadrature.h"

#ifndef PI
#define PI 3.14159265358979323846
#endif

static inline double ref_fresnel(double complex n, double c)
{
    double complex t = csqrt(n * n - (1.0 - c * c));
    double complex rs = (c - t) / (c + t), rp = (n * n * c - t) / (n * n * c + t);
    return 0.5 * (cabs(rs) * cabs(rs) + cabs(rp) * cabs(rp));
}

static inline double ref_lambda(double a, double z) { return 0.5 * (sqrt(1.0 + a * a * (1.0 - z * z) / (z * z)) - 1.0); }

static inline double ref_d(double a, double hz)
{
    double k = (a * a - 1.0) * hz * hz + 1.0;
    return hz > 0 ? a * a / (PI * k * k) : 0.0;
}

/* f with the cosine of wi included, as the kernels tally it. */
static inline double ref_f(double a, double complex n, const double wo[3], const double wi[3])
{
    if (wo[2] <= 0 || wi[2] <= 0) return 0.0;
    double h[3] = {wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]};
    double l = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int i = 0; i < 3; i++) h[i] /= l;
    double oh = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
    return ref_fresnel(n, oh) * ref_d(a, h[2]) / (1.0 + ref_lambda(a, wo[2]) + ref_lambda(a, wi[2])) / (4.0 * wo[2]);
}

/* Directional albedo by Gauss-Legendre in cos theta_i (on panels graded towards the
 * specular peak's cosine) times an even rule in phi (checked by doubling the nodes). */
static inline double ref_albedo(double a, double complex n, double theta_o, int nodes)
{
    double wo[3] = {sin(theta_o), 0, cos(theta_o)}, gx[64], gw[64], sum = 0;
    gauss_legendre(nodes, gx, gw);
    /* panel edges around the peak at mu = cos theta_o */
    const double mp = cos(theta_o), cand[] = {mp - 0.2, mp - 0.06, mp - 0.02, mp, mp + 0.02, mp + 0.06, mp + 0.2};
    double edges[10];
    int np = 0;
    edges[0] = 0.0;
    for (int i = 0; i < 7; i++)
        if (cand[i] > edges[np] + 1e-3 && cand[i] < 1.0 - 1e-3) edges[++np] = cand[i];
    edges[++np] = 1.0;
    const int nphi = 4 * nodes;
    for (int p = 0; p < np; p++)
        for (int i = 0; i < nodes; i++) {
            double mu = 0.5 * (edges[p] + edges[p + 1]) + 0.5 * (edges[p + 1] - edges[p]) * gx[i];
            double wmu = 0.5 * (edges[p + 1] - edges[p]) * gw[i], s = sqrt(1 - mu * mu);
            for (int j = 0; j < nphi; j++) {
                double phi = PI * (j + 0.5) / nphi; /* symmetric in y: [0, pi], twice */
                double wi[3] = {s * cos(phi), s * sin(phi), mu};
                sum += 2.0 * wmu * (PI / nphi) * ref_f(a, n, wo, wi);
            }
        }
    return sum;
}

#endif
