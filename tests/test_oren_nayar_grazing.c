/* Oren-Nayar with both directions beyond 87 degrees, end to end (the walk's point estimate
 * at the layer, the host's RAW value f / |cos i|), against the published formula and
 * kernels/bsdf_oren_nayar.cl promise, written here in double from the formula:
 *   f |cos i| = fR |cos i| / pi [A + B max(wo'.wi', 0) / max(|cos o|, |cos i|)],
 *   A = 1 - 0.5 s^2 / (s^2 + 0.33), B = 0.45 s^2 / (s^2 + 0.09), wo'.wi' the tangential
 *   part sin o sin i cos(dphi); reflection on wo's side only, nothing clamped.
 * There, max(|cos o|, |cos i|) is 0.002 to 0.05, so the B term is 20 to 500 times A and
 * any guard on that division (a floor, an epsilon) or any loss of the cosines' precision
 * shows at once; the existing tests stop at 85 degrees.
 * A single Oren-Nayar layer under vacuum: every path's only point estimate is the first
 * vertex's, with weight 1, so the estimate is the value itself, without noise (its
 * standard error is 0, the fixed-point tallies are exact sums). The only error is the
 * float arithmetic of the directions (wo and wi are floats on the device: at 89.9 degrees
 * cos i = 1.7e-3 is stored with a relative rounding of 6e-8, as the formula here gets it) and of
 * the kernel (a few roundings of 6e-8 each): the tolerance is 2e-5 relative in float
 * (measured: 2.5e-7), 1e-8 in double (measured: 1.1e-9) (--double end to end; the directions of the state
 * are floats, which the device normalises, as the formula here does; the RAW value divides
 * by the stored |wi.z|). No chance enters, so no family: a correct code always
 * passes. Slices theta_o = 87, 87.5, 88, 89, 89.5, 89.9 degrees; directions theta_i in
 * the same set (equal angles included) at dphi = 0, 20, 45, 70, 89, 100, 180 degrees (the
 * last two: the B term is 0), fR 0.8, sigma 0.3 and 0.8. */
#include "cl_fixture.h"

#define PI 3.14159265358979323846
#define NTH 6
#define NPH 7
#define NWI (NTH * NPH)

static const double th_deg[NTH] = {87, 87.5, 88, 89, 89.5, 89.9};
static const double ph_deg[NPH] = {0, 20, 45, 70, 89, 100, 180};

static double on_ref(double fr, double s, const double o[3], const double i[3])
{
    if (!(o[2] * i[2] > 0)) return 0;
    double A = 1 - 0.5 * s * s / (s * s + 0.33), B = 0.45 * s * s / (s * s + 0.09);
    double t = fmax(o[0] * i[0] + o[1] * i[1], 0.0);
    return fr * fabs(i[2]) / PI * (A + B * t / fmax(fabs(o[2]), fabs(i[2])));
}

/* fixture_run_prec with these directions instead of the spread set */
static lsqt_slice_est *run(const char *text, uint64_t paths, int use_double, lsqt_state *st)
{
    lsqt_assembly a;
    fixture_state(text, NTH, NWI, 7, use_double, &a, st);
    for (int s = 0; s < NTH; s++) {
        st->theta_o[s] = th_deg[s] * PI / 180.0;
        for (int i = 0; i < NTH; i++)
            for (int j = 0; j < NPH; j++) {
                float *w = st->wi + ((size_t)s * NWI + (size_t)(i * NPH + j)) * 4;
                double t = th_deg[i] * PI / 180.0, p = ph_deg[j] * PI / 180.0;
                w[0] = (float)(sin(t) * cos(p)), w[1] = (float)(sin(t) * sin(p)), w[2] = (float)cos(t), w[3] = 0;
            }
    }
    fixture_simulate(&a, st, paths);
    return lsqt_estimates(st);
}

int main(void)
{
    fixture_open();
    const double sig[] = {0.3, 0.8}, fr = 0.8;
    for (int prec = 0; prec < 2; prec++) {
        const double tol = prec ? 1e-8 : 2e-5;
        for (int is = 0; is < 2; is++) {
            char text[256];
            snprintf(text, sizeof text, "Medium\nLayer z=0 OrenNayarDiffuseBrdf fR=%g sigma=%g\nMedium\n", fr, sig[is]);
            lsqt_state st;
            lsqt_slice_est *e = run(text, 4096, prec, &st);
            CHECK(st.flags == 0 && !st.transmits, "flags %u", st.flags);
            double worst = 0, smallest = 1e300, largest = 0;
            for (int s = 0; s < NTH; s++) {
                /* wo as the host makes it (double, then the device's precision) */
                double o[3] = {sin(st.theta_o[s]), 0.0, cos(st.theta_o[s])};
                if (!prec)
                    for (int c = 0; c < 3; c++) o[c] = (float)o[c];
                CHECK(e[s].T.mean == 0.0 && e[s].R.mean > 0.0, "a reflector: R %g T %g", e[s].R.mean, e[s].T.mean);
                for (int k = 0; k < NWI; k++) {
                    const float *w = st.wi + ((size_t)s * NWI + (size_t)k) * 4;
                    double i[3] = {w[0], w[1], w[2]};
                    double nn = sqrt(i[0] * i[0] + i[1] * i[1] + i[2] * i[2]);
                    for (int c = 0; c < 3; c++) i[c] /= nn; /* the device normalises the float wi */
                    double ref = on_ref(fr, sig[is], o, i) / fabs(w[2]);
                    double got = e[s].f[k].mean, rel = fabs(got - ref) / ref;
                    CHECK(rel <= tol && !(e[s].f[k].err > 1e-9 * ref),
                          "%s sigma=%g to=%g ti=%g dphi=%g: f %.9g, formula %.9g (relative %.3g, tolerance %g; "
                          "error %.3g)",
                          prec ? "double" : "float", sig[is], th_deg[s], th_deg[k / NPH], ph_deg[k % NPH], got, ref, rel,
                          tol, e[s].f[k].err);
                    worst = fmax(worst, rel), smallest = fmin(smallest, ref), largest = fmax(largest, ref);
                }
            }
            printf("%s sigma=%g: %d values from %.4g to %.4g 1/sr, largest relative difference %.3g (tolerance %g)\n",
                   prec ? "double" : "float", sig[is], NTH * NWI, smallest, largest, worst, tol);
            lsqt_estimates_free(e, NTH);
            lsqt_state_free(&st);
        }
    }
    lsqt_context_release(&fixture_cx);
    return check_finish("test_oren_nayar_grazing");
}
