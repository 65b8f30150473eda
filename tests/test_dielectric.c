/* MicrosurfaceDielectricBsdf, single scattering (analytic), against an independent
 * double-precision implementation written here from the formulas (tests/ref_dielectric.h,
 * not from the kernel): GGX D, Smith Lambda for uniform heights, unpolarised dielectric
 * Fresnel with total internal reflection,
 *   reflection    f |cos i| = kR F D / (4 cos o) / (1 + Lo + Li),
 *   transmission  f |cos i| = kT (1 - F) D B(1 + Lo, 1 + Li) e^2 |i.h| |o.h| / (cos o (o.h + e i.h)^2),
 * e the relative index across the surface seen from wo's side (eta = n_below / n_above
 * from above, 1 / eta from below).
 * Checks, through harness_eval, for alpha 0.05, 0.3, 1, 2.4 and eta 1.5, 1/1.5, and 1.33
 * with kR 0.7, kT 0.4: per case 24 pairs each of reflection and transmission with the
 * observer above and below, and all of them reversed (192 values), to 1e-2 relative in
 * float and 1e-3 in double (absolute below 1e-6 of the case's largest value); zero where
 * the reference is zero (transmission pairs no microsurface normal refracts); the pdf
 * positive where f is; reflection reciprocity f(a->b)/|cos b| = f(b->a)/|cos a| and the
 * transmission rule n_o^2 f(o->i)/|cos i| = n_i^2 f(i->o)/|cos o| for the kernel (and, to
 * rounding, for the reference); finite non-negative values at alpha 1e-3. The reference
 * is checked on its own: Fresnel identities, the Beta term, and R + T at normal incidence
 * (R = F(1), T = 1 - F(1) in the smooth limit). */
#include <stdint.h>

#include "cl_fixture.h"
#include "ref_dielectric.h"

static cl_program build(int dbl)
{
    return fixture_build("-cl-std=CL1.2 -DLSQT_HAS_BSDF_MS_DIELECTRIC=1%s", dbl ? " -DLSQT_DOUBLE=1" : "");
}

typedef struct {
    double a, eta, kr, kt;
} dcase;

/* The kernel's f (cosine of wi included) and pdf at n pairs through harness_eval, in float
 * or double (fixture_eval_pairs). Returns 0 on success. */
static int kernel_eval(cl_program prog, int dbl, const dcase *c, int n, const double (*wo)[3],
                       const double (*wi)[3], double *f, double *pdf)
{
    if (!prog) return -1;
    const lsqt_dev_layer_d L = {.kind = LSQT_BSDF_MS_DIELECTRIC, .iter_count = 1, .p = {c->a, c->eta, c->kr, c->kt}};
    return fixture_eval_pairs(prog, dbl, &L, 1.0, n, wo, wi, f, pdf);
}

/* A tiny LCG: the pairs are the same on every run. */
static uint32_t lcg = 12345u;
static double urand(void)
{
    lcg = lcg * 1664525u + 1013904223u;
    return (lcg >> 8) * (1.0 / 16777216.0);
}

static void unit_dir(double theta, double phi, double v[3])
{
    v[0] = sin(theta) * cos(phi), v[1] = sin(theta) * sin(phi), v[2] = cos(theta);
}

enum { NP = 24, NZ = 10, MAXN = 8 * NP + 2 * NZ };

/* np pairs in the frame where wo is up, relative index e: wi mirrored (trans = 0) or
 * refracted (trans = 1) about a normal h drawn around the macro normal on the scale of
 * alpha (h exactly normal for every sixth pair), theta_o from normal (0, 0.01 rad) to 72
 * degrees. Every fifth pair takes wi anywhere on its side instead (far
 * off the lobe). |wi.z| >= 0.06 and, for transmission, min(o.h, -i.h) >= 0.02, so that
 * float rounding cannot move a pair across the edge of validity. */
static int gen_pairs(double a, double e, int trans, int np, double (*o)[3], double (*i)[3])
{
    static const double tos[] = {0.0, 0.01, 0.25, 0.5, 0.8, 1.05, 1.25};
    int n = 0;
    for (int k = 0; n < np && k < 1000000; k++) {
        double ov[3], iv[3], h[3];
        unit_dir(tos[(n + k) % 7], 2 * PI * urand(), ov); /* (k: skips angles with no pair, TIR) */
        int ok;
        if (n % 5 == 4) {
            unit_dir(acos(0.06 + 0.94 * urand()), 2 * PI * urand(), iv);
            if (trans) iv[2] = -iv[2];
            ok = 1;
        } else {
            double u = urand(), th = n % 6 == 0 ? 0.0 : atan(a * 2.5 * u * u);
            unit_dir(th, 2 * PI * urand(), h);
            ok = trans ? refd_refract(ov, h, e, iv) : refd_reflect(ov, h, iv);
        }
        if (!ok || fabs(iv[2]) < 0.06) continue;
        if (trans) {
            double hh[3], oh, ih;
            if (refd_trans_half(ov, iv, e, hh, &oh, &ih) < 0.02) continue;
        }
        memcpy(o[n], ov, sizeof ov), memcpy(i[n], iv, sizeof iv);
        n++;
    }
    return n;
}

/* nz transmission pairs (wo up, wi down) for which no microsurface normal refracts wo
 * into wi, with a margin: min(o.h, -i.h) <= -0.05. */
static int gen_zero_pairs(double e, int nz, double (*o)[3], double (*i)[3])
{
    int n = 0;
    for (int k = 0; n < nz && k < 1000000; k++) {
        double ov[3], iv[3], hh[3], oh, ih;
        unit_dir(acos(0.06 + 0.94 * urand()), 2 * PI * urand(), ov);
        unit_dir(acos(0.06 + 0.94 * urand()), 2 * PI * urand(), iv);
        iv[2] = -iv[2];
        if (refd_trans_half(ov, iv, e, hh, &oh, &ih) > -0.05) continue;
        memcpy(o[n], ov, sizeof ov), memcpy(i[n], iv, sizeof iv);
        n++;
    }
    return n;
}

/* The pairs of one case: for each side of wo, reflection and transmission pairs, each
 * followed by its reverse, then the zero pairs. kind: 0 reflection, 1 transmission, 2
 * zero; rev: index of the reversed pair (forward pairs), -1 otherwise; erel: the relative
 * index n_wi / n_wo. */
typedef struct {
    int n, kind[MAXN], rev[MAXN];
    double wo[MAXN][3], wi[MAXN][3], erel[MAXN];
} pairset;

static void make_pairs(const dcase *c, pairset *ps)
{
    ps->n = 0;
    for (int side = 0; side < 2; side++) {
        const double sg = side ? -1.0 : 1.0, e = side ? 1.0 / c->eta : c->eta;
        for (int trans = 0; trans < 2; trans++) {
            double o[NP][3], i[NP][3];
            int got = gen_pairs(c->a, e, trans, NP, o, i);
            CHECK(got == NP, "alpha %g e %g trans %d: only %d pairs", c->a, e, trans, got);
            for (int k = 0; k < got; k++) {
                int f = ps->n++, r = ps->n++;
                for (int d = 0; d < 3; d++) {
                    double s = d == 2 ? sg : 1.0;
                    ps->wo[f][d] = ps->wi[r][d] = s * o[k][d];
                    ps->wi[f][d] = ps->wo[r][d] = s * i[k][d];
                }
                ps->kind[f] = ps->kind[r] = trans;
                ps->rev[f] = r, ps->rev[r] = -1;
                ps->erel[f] = trans ? e : 1.0, ps->erel[r] = trans ? 1.0 / e : 1.0;
            }
        }
        double o[NZ][3], i[NZ][3];
        int got = gen_zero_pairs(e, NZ, o, i);
        CHECK(got == NZ, "e %g: only %d zero pairs", e, got);
        for (int k = 0; k < got; k++) {
            int z = ps->n++;
            for (int d = 0; d < 3; d++) {
                double s = d == 2 ? sg : 1.0;
                ps->wo[z][d] = s * o[k][d], ps->wi[z][d] = s * i[k][d];
            }
            ps->kind[z] = 2, ps->rev[z] = -1, ps->erel[z] = e;
        }
    }
}

/* The directions as the kernel sees them: rounded to float, wo normalised again. */
static void as_kernel_sees(const double wo[3], const double wi[3], double o[3], double i[3])
{
    for (int d = 0; d < 3; d++) o[d] = (float)wo[d], i[d] = (float)wi[d];
    double l = sqrt(refd_dot(o, o));
    for (int d = 0; d < 3; d++) o[d] /= l;
}

/* The reference's own transmission rule and reciprocity, at the exact directions. */
static void check_reference_rules(const dcase *c, const pairset *ps)
{
    for (int f = 0; f < ps->n; f++) {
        int r = ps->rev[f];
        if (r < 0) continue;
        double a = ref_dielectric_f(c->a, c->eta, c->kr, c->kt, ps->wo[f], ps->wi[f]);
        double b = ref_dielectric_f(c->a, c->eta, c->kr, c->kt, ps->wo[r], ps->wi[r]);
        double l = a / fabs(ps->wi[f][2]), rr = ps->erel[f] * ps->erel[f] * b / fabs(ps->wo[f][2]);
        /* reflection: erel = 1, the reciprocity; transmission: n_o^2 f/|cos i| = n_i^2 f'/|cos o| */
        CHECK(a > 0 && fabs(l - rr) <= 1e-10 * fmax(l, rr), "reference %s rule, alpha %g eta %g pair %d: %.15g vs %.15g",
              ps->kind[f] ? "transmission" : "reflection", c->a, c->eta, f, l, rr);
    }
    for (int z = 0; z < ps->n; z++)
        if (ps->kind[z] == 2)
            CHECK(ref_dielectric_f(c->a, c->eta, c->kr, c->kt, ps->wo[z], ps->wi[z]) == 0,
                  "reference nonzero at zero pair %d", z);
}

typedef struct {
    double val, tiny, rule[2];
} worsts;

static void check_case(cl_program prog, int dbl, const dcase *c, const pairset *ps, worsts *w)
{
    const double tol = dbl ? 1e-3 : 1e-2;
    double got[MAXN], pdf[MAXN], want[MAXN], fmaxv = 0;
    if (kernel_eval(prog, dbl, c, ps->n, (const double(*)[3])ps->wo, (const double(*)[3])ps->wi, got, pdf)) return;
    for (int k = 0; k < ps->n; k++) {
        double o[3], i[3];
        as_kernel_sees(ps->wo[k], ps->wi[k], o, i);
        want[k] = ref_dielectric_f(c->a, c->eta, c->kr, c->kt, o, i);
        fmaxv = fmax(fmaxv, want[k]);
    }
    const double floor_ = 1e-6 * fmaxv;
    const char *prec = dbl ? "double" : "float";
    for (int k = 0; k < ps->n; k++) {
        const char *what = ps->kind[k] == 0 ? "reflection" : ps->kind[k] == 1 ? "transmission" : "zero";
        CHECK(isfinite(got[k]) && got[k] >= 0 && isfinite(pdf[k]) && pdf[k] >= 0,
              "alpha %g eta %g %s %s pair %d: f %g pdf %g", c->a, c->eta, prec, what, k, got[k], pdf[k]);
        if (ps->kind[k] == 2) {
            CHECK(want[k] == 0 && got[k] == 0,
                  "alpha %g eta %g %s: wo (%.9f %.9f %.9f) wi (%.9f %.9f %.9f): f %.9g, reference %.9g (both must be 0)",
                  c->a, c->eta, prec, ps->wo[k][0], ps->wo[k][1], ps->wo[k][2], ps->wi[k][0], ps->wi[k][1],
                  ps->wi[k][2], got[k], want[k]);
            continue;
        }
        double err = fabs(got[k] - want[k]), rel = err / fmax(want[k], floor_);
        if (want[k] >= floor_)
            w->val = fmax(w->val, rel);
        else
            w->tiny = fmax(w->tiny, rel);
        CHECK(want[k] > 0 && rel <= tol,
              "alpha %g eta %g kR %g kT %g %s %s pair %d: wo (%.9f %.9f %.9f) wi (%.9f %.9f %.9f): f %.9g vs reference "
              "%.9g (relative %.3g)",
              c->a, c->eta, c->kr, c->kt, prec, what, k, ps->wo[k][0], ps->wo[k][1], ps->wo[k][2], ps->wi[k][0],
              ps->wi[k][1], ps->wi[k][2], got[k], want[k], rel);
        if (want[k] > floor_)
            CHECK(pdf[k] > 0, "alpha %g eta %g %s %s pair %d: f %g but pdf %g", c->a, c->eta, prec, what, k, got[k],
                  pdf[k]);
    }
    /* the kernel's reciprocity (reflection) and transmission rule */
    for (int f = 0; f < ps->n; f++) {
        int r = ps->rev[f];
        if (r < 0) continue;
        double o[3], i[3];
        as_kernel_sees(ps->wo[f], ps->wi[f], o, i);
        double l = got[f] / fabs(i[2]), rr = ps->erel[f] * ps->erel[f] * got[r] / fabs(o[2]);
        double fl = ps->erel[f] * ps->erel[f] * floor_ / fmin(fabs(i[2]), fabs(o[2])); /* the same floor */
        double d = fabs(l - rr) / fmax(fmax(l, rr), fl);
        w->rule[ps->kind[f]] = fmax(w->rule[ps->kind[f]], d);
        CHECK(d <= tol, "alpha %g eta %g %s %s rule pair %d: wo (%.9f %.9f %.9f) wi (%.9f %.9f %.9f): %.9g vs %.9g",
              c->a, c->eta, prec, ps->kind[f] ? "transmission" : "reciprocity", f, ps->wo[f][0], ps->wo[f][1],
              ps->wo[f][2], ps->wi[f][0], ps->wi[f][1], ps->wi[f][2], l, rr);
    }
}

static void test_values(void)
{
    const double alphas[] = {0.05, 0.3, 1.0, 2.4};
    const dcase idx[] = {{0, 1.5, 1, 1}, {0, 1.0 / 1.5, 1, 1}, {0, 1.33, 0.7, 0.4}};
    cl_program progs[2] = {build(0), fixture_cx.dev.has_fp64 ? build(1) : NULL};
    static pairset ps;
    for (int ix = 0; ix < 3; ix++)
        for (int ia = 0; ia < 4; ia++) {
            dcase c = idx[ix];
            c.a = alphas[ia];
            make_pairs(&c, &ps);
            check_reference_rules(&c, &ps);
            for (int dbl = 0; dbl < 2; dbl++) {
                if (!progs[dbl]) continue; /* (no double on the device, or the build failed: checked) */
                worsts w = {0, 0, {0, 0}};
                check_case(progs[dbl], dbl, &c, &ps, &w);
                printf("dielectric alpha %-4g eta %.4f kR %.1f kT %.1f %s: %d pairs, worst relative %.2g (tiny %.2g), "
                       "reciprocity %.2g, transmission rule %.2g\n",
                       c.a, c.eta, c.kr, c.kt, dbl ? "double" : "float ", ps.n, w.val, w.tiny, w.rule[0], w.rule[1]);
            }
        }
    /* alpha 1e-3: peaks of 1/(pi alpha^2) = 3e5 and h within 1e-3 of the normal, where
     * cancellation would show; every value finite and non-negative. */
    for (int ix = 0; ix < 3; ix++) {
        dcase c = idx[ix];
        c.a = 1e-3;
        make_pairs(&c, &ps);
        for (int dbl = 0; dbl < 2; dbl++) {
            if (!progs[dbl]) continue;
            double got[MAXN], pdf[MAXN], big = 0;
            if (kernel_eval(progs[dbl], dbl, &c, ps.n, (const double(*)[3])ps.wo, (const double(*)[3])ps.wi, got, pdf))
                continue;
            int bad = 0;
            double want[MAXN], wmax = 0, worst = 0;
            for (int k = 0; k < ps.n; k++) {
                double o[3], i[3];
                as_kernel_sees(ps.wo[k], ps.wi[k], o, i);
                want[k] = ref_dielectric_f(c.a, c.eta, c.kr, c.kt, o, i);
                wmax = fmax(wmax, want[k]);
            }
            for (int k = 0; k < ps.n; k++) {
                bad += !(isfinite(got[k]) && got[k] >= 0 && isfinite(pdf[k]) && pdf[k] >= 0);
                big = fmax(big, got[k]);
                double rel = fabs(got[k] - want[k]) / fmax(want[k], 1e-6 * wmax);
                if (ps.kind[k] != 2) worst = fmax(worst, rel);
                /* double: the same values as the rougher cases (float is only required finite:
                 * 1 - h.z is 1e-6 here) */
                if (dbl)
                    CHECK(rel <= 1e-3, "alpha 1e-3 eta %g double pair %d: wo (%.9f %.9f %.9f) wi (%.9f %.9f %.9f): "
                          "f %.9g vs reference %.9g", c.eta, k, ps.wo[k][0], ps.wo[k][1], ps.wo[k][2], ps.wi[k][0],
                          ps.wi[k][1], ps.wi[k][2], got[k], want[k]);
            }
            CHECK(bad == 0 && big > 0, "alpha 1e-3 eta %g %s: %d of %d values not finite and non-negative, largest %g",
                  c.eta, dbl ? "double" : "float", bad, ps.n, big);
            printf("dielectric alpha 1e-3 eta %.4f %s: %d pairs finite, largest f %.3g (reference %.3g), worst "
                   "relative %.2g\n", c.eta, dbl ? "double" : "float ", ps.n, big, wmax, worst);
        }
    }
    for (int d = 0; d < 2; d++)
        if (progs[d]) clReleaseProgram(progs[d]);
}

/* The reference on its own. */
static void test_reference(void)
{
    /* Fresnel: normal incidence ((e - 1)/(e + 1))^2 from either side, TIR past the
     * critical angle, and the same F for both directions of a refracted pair (Stokes). */
    const double es[] = {1.5, 1.0 / 1.5, 1.33, 1.0 / 1.33};
    for (int k = 0; k < 4; k++) {
        double e = es[k];
        CHECK(fabs(refd_fresnel(1.0, e) - (e - 1) * (e - 1) / ((e + 1) * (e + 1))) < 1e-14, "F(1, %g)", e);
        for (double c = 0.05; c < 1.0; c += 0.1) {
            double s2 = (1 - c * c) / (e * e);
            if (s2 >= 1) {
                CHECK(refd_fresnel(c, e) == 1.0, "TIR at cos %g, e %g: %g", c, e, refd_fresnel(c, e));
                continue;
            }
            double ct = sqrt(1 - s2);
            CHECK(fabs(refd_fresnel(c, e) - refd_fresnel(ct, 1 / e)) < 1e-13, "Stokes at cos %g e %g: %.15g vs %.15g",
                  c, e, refd_fresnel(c, e), refd_fresnel(ct, 1 / e));
        }
    }
    /* Beta term: B(1, 1) = 1, B(2, 2) = 1/6, symmetric, B(1 + L, 1) = 1/(1 + L) */
    CHECK(fabs(refd_g2t(0, 0) - 1) < 1e-14 && fabs(refd_g2t(1, 1) - 1.0 / 6) < 1e-14, "B(1,1) %g B(2,2) %g",
          refd_g2t(0, 0), refd_g2t(1, 1));
    CHECK(fabs(refd_g2t(0.3, 2.1) - refd_g2t(2.1, 0.3)) < 1e-15, "B symmetric");
    CHECK(fabs(refd_g2t(0.5, 0) - 1 / 1.5) < 1e-14, "B(1 + L, 1) = 1 / (1 + L)");
    /* R + T at normal incidence, lossless: the smooth limit R = F(1), T = 1 - F(1), and
     * never more than 1 for rougher surfaces (converged: 32 and 48 nodes per panel). */
    const double as[] = {0.02, 0.3, 1.0};
    for (int k = 0; k < 2; k++)
        for (int ia = 0; ia < 3; ia++) {
            double e = es[k], r, t, r2, t2, f1 = refd_fresnel(1.0, e);
            refd_normal_rt(as[ia], e, 32, &r, &t);
            refd_normal_rt(as[ia], e, 48, &r2, &t2);
            CHECK(fabs(r - r2) < 1e-6 && fabs(t - t2) < 1e-6, "quadrature not converged: %.9g %.9g vs %.9g %.9g", r, t,
                  r2, t2);
            CHECK(r2 + t2 <= 1 + 1e-5, "alpha %g e %g: R + T = %.9g", as[ia], e, r2 + t2);
            if (ia == 0)
                CHECK(fabs(r2 - f1) < 2e-3 && fabs(t2 - (1 - f1)) < 2e-3, "smooth limit e %g: R %.6f T %.6f vs F %.6f",
                      e, r2, t2, f1);
            printf("reference, normal incidence, alpha %-4g e %.4f: R %.6f T %.6f R+T %.6f (F(1) %.6f)\n", as[ia], e, r2,
                   t2, r2 + t2, f1);
        }
}

int main(void)
{
    fixture_open();
    test_reference();
    test_values();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_dielectric");
}
