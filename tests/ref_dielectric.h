/* An independent double-precision model of the single-scattering GGX rough dielectric
 * (MicrosurfaceDielectricBsdf with multiple_scattering = 0), written from the formulas
 * (Walter et al. 2007 D, Jacobian and Fresnel; Smith Lambda for GGX; Heitz 2014/2016
 * height-correlated masking-shadowing for uniform heights), for the tests. Not from the
 * kernel code.
 *
 * Directions are unit vectors in the layer frame, z the macro normal pointing up; wo
 * points towards the observer. The layer's eta = n_below / n_above. Everything is done in
 * the frame where wo's side is up: when wo.z < 0 the z of wo and wi are flipped and the
 * relative index is e = 1/eta, else e = eta. co = |wo.z|, ci = |wi.z|.
 *   D(h)     = a^2 / (pi ((a^2 - 1) h.z^2 + 1)^2) for h.z > 0, else 0
 *   Lambda(w)= (sqrt(1 + a^2 tan^2 theta_w) - 1) / 2 with |w.z|;  Lo, Li
 *   F(c, e)  = 0.5 ((g-c)/(g+c))^2 (1 + ((c(g+c)-1)/(c(g-c)+1))^2), g^2 = e^2 - 1 + c^2,
 *              F = 1 when g^2 < 0 (total internal reflection); c = wo.h
 * Reflection (wi.z > 0 after the flip): h = normalize(wo + wi),
 *   f |cos i| = kR F(wo.h, e) D(h) / (4 co) / (1 + Lo + Li)       (0 if wo.h <= 0)
 * Transmission (wi.z < 0 after the flip): h = -normalize(wo + e wi), negated if h.z < 0;
 *   0 unless wo.h > 0 and wi.h < 0, else
 *   f |cos i| = kT (1 - F(wo.h, e)) D(h) G2T e^2 |wi.h| |wo.h| / (co (wo.h + e wi.h)^2),
 *   G2T = B(1 + Lo, 1 + Li) = Gamma(1 + Lo) Gamma(1 + Li) / Gamma(2 + Lo + Li).
 * This is the flux normalisation: for kR = kT = 1 the integral of f |cos i| over wi is the
 * fraction of the energy from wo that leaves (R + T = 1 up to the single-scattering loss).
 * Consequences checked by the tests: with n_o, n_i the absolute indices on the sides of
 * wo and wi, n_o^2 f(wo->wi) / |cos i| = n_i^2 f(wi->wo) / |cos o| (transmission), and
 * f(a->b) / |cos b| = f(b->a) / |cos a| (reflection). */
#ifndef LSQT_TESTS_REF_DIELECTRIC_H
#define LSQT_TESTS_REF_DIELECTRIC_H

#include <math.h>

#include "quadrature.h"

#ifndef PI
#define PI 3.14159265358979323846
#endif

/* Unpolarised Fresnel reflectance for cos c > 0 on the side of the incident ray, e = n2/n1. */
static inline double refd_fresnel(double c, double e)
{
    double g2 = e * e - 1.0 + c * c;
    if (g2 < 0) return 1.0;
    double g = sqrt(g2), a = (g - c) / (g + c), b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

static inline double refd_lambda(double a, double z)
{
    z = fabs(z);
    return 0.5 * (sqrt(1.0 + a * a * (1.0 - z * z) / (z * z)) - 1.0);
}

static inline double refd_d(double a, double hz)
{
    double k = (a * a - 1.0) * hz * hz + 1.0;
    return hz > 0 ? a * a / (PI * k * k) : 0.0;
}

/* Height-correlated transmission term for uniform heights: the Beta function B(1+lo, 1+li). */
static inline double refd_g2t(double lo, double li)
{
    return exp(lgamma(1.0 + lo) + lgamma(1.0 + li) - lgamma(2.0 + lo + li));
}

static inline double refd_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* The microsurface normal and the two cosines of a transmission pair in the flipped frame
 * (o.z > 0 > i.z); returns min(o.h, -i.h), positive exactly when the pair is valid. */
static inline double refd_trans_half(const double o[3], const double i[3], double e, double h[3], double *oh,
                                     double *ih)
{
    double v[3] = {-(o[0] + e * i[0]), -(o[1] + e * i[1]), -(o[2] + e * i[2])};
    double l = sqrt(refd_dot(v, v));
    if (!(l > 0)) return -1.0;
    double s = v[2] < 0 ? -1.0 / l : 1.0 / l;
    for (int k = 0; k < 3; k++) h[k] = v[k] * s;
    *oh = refd_dot(o, h), *ih = refd_dot(i, h);
    return fmin(*oh, -*ih);
}

/* f(wo -> wi) with |cos wi| included, as harness_eval returns it. eta = n_below / n_above. */
static inline double ref_dielectric_f(double a, double eta, double kr, double kt, const double wo[3],
                                      const double wi[3])
{
    if (wo[2] == 0 || wi[2] == 0) return 0.0;
    const double s = wo[2] < 0 ? -1.0 : 1.0, e = wo[2] < 0 ? 1.0 / eta : eta;
    const double o[3] = {wo[0], wo[1], s * wo[2]}, i[3] = {wi[0], wi[1], s * wi[2]};
    const double co = o[2], lo = refd_lambda(a, o[2]), li = refd_lambda(a, i[2]);
    if (i[2] > 0) { /* reflection */
        double h[3] = {o[0] + i[0], o[1] + i[1], o[2] + i[2]}, l = sqrt(refd_dot(h, h));
        for (int k = 0; k < 3; k++) h[k] /= l;
        double oh = refd_dot(o, h);
        if (oh <= 0) return 0.0;
        return kr * refd_fresnel(oh, e) * refd_d(a, h[2]) / (4.0 * co) / (1.0 + lo + li);
    }
    double h[3], oh, ih;
    if (!(refd_trans_half(o, i, e, h, &oh, &ih) > 0)) return 0.0;
    double den = oh + e * ih;
    return kt * (1.0 - refd_fresnel(oh, e)) * refd_d(a, h[2]) * refd_g2t(lo, li) * e * e * fabs(ih) * fabs(oh) /
           (co * den * den);
}

/* Directions built from a chosen microsurface normal h (h.z > 0), in the frame where wo
 * is up (o.z > 0): the mirror direction, and the refracted one for relative index e;
 * return 0 when there is none (wrong side, or total internal reflection). */
static inline int refd_reflect(const double o[3], const double h[3], double out[3])
{
    double c = refd_dot(o, h);
    for (int k = 0; k < 3; k++) out[k] = 2.0 * c * h[k] - o[k];
    return c > 0 && out[2] > 0;
}

static inline int refd_refract(const double o[3], const double h[3], double e, double out[3])
{
    double c = refd_dot(o, h), r = 1.0 / e, t2 = 1.0 - r * r * (1.0 - c * c);
    if (c <= 0 || t2 <= 0) return 0;
    double ct = sqrt(t2);
    for (int k = 0; k < 3; k++) out[k] = -r * o[k] + (r * c - ct) * h[k];
    return out[2] < 0;
}

/* Reflected and transmitted fractions at normal incidence (f is then symmetric about z):
 * integrals over theta_i of f |cos i| sin theta_i 2 pi by Gauss-Legendre on panels graded
 * towards the two lobes (widths ~ alpha around theta 0 and pi), with edges at the kinks:
 * the end of the transmitted cone (a microsurface normal at the critical angle sends the
 * light out at pi/2 - asin(min(e, 1/e)) from -z) and, from the denser side, the onset of
 * total internal reflection (reflected at 2 asin(e)); theta measured from +z for R and
 * from -z for T. */
static inline void refd_normal_rt(double a, double e, int nodes, double *r, double *t)
{
    double gx[64], gw[64], edges[48];
    int ne = 0;
    gauss_legendre(nodes, gx, gw);
    edges[ne++] = 0.0;
    for (double w = 0.25 * a; w < 0.5 * PI - 1e-3 && ne < 40; w *= 2.0) edges[ne++] = w;
    for (int k = 1; k <= 4; k++) edges[ne++] = k * 0.1 * PI; /* no panel wider than 0.1 pi */
    edges[ne++] = 0.5 * PI - asin(fmin(e, 1.0 / e));
    if (e < 1 && 2 * asin(e) < 0.5 * PI) edges[ne++] = 2 * asin(e);
    edges[ne++] = 0.5 * PI;
    for (int p = 1; p < ne; p++) /* sort (insertion) and drop near-duplicates */
        for (int q = p; q > 0 && edges[q] < edges[q - 1]; q--) {
            double x = edges[q];
            edges[q] = edges[q - 1], edges[q - 1] = x;
        }
    int m = 1;
    for (int p = 1; p < ne; p++)
        if (edges[p] > edges[m - 1] + 1e-9) edges[m++] = edges[p];
    ne = m;
    const double o[3] = {0, 0, 1};
    *r = *t = 0;
    for (int p = 0; p + 1 < ne; p++)
        for (int k = 0; k < nodes; k++) {
            double th = 0.5 * (edges[p] + edges[p + 1]) + 0.5 * (edges[p + 1] - edges[p]) * gx[k];
            double w = 0.5 * (edges[p + 1] - edges[p]) * gw[k] * 2.0 * PI * sin(th);
            double up[3] = {sin(th), 0, cos(th)}, dn[3] = {sin(th), 0, -cos(th)};
            *r += w * ref_dielectric_f(a, e, 1.0, 1.0, o, up);
            *t += w * ref_dielectric_f(a, e, 1.0, 1.0, o, dn);
        }
}

#endif
