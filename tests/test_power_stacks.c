/* Power test: asymmetric stacks of two and three transmitting
 * Lambertian layers, optionally with a clear absorber between them, from above and
 * (lsqt_simulate's lane from below, the host's mirror) from below, with enough paths to see a 1 %
 * error in R or T, whether it comes from the walk (exit tallies) or from the point
 * estimates.
 *
 * Reference (closed form, the adding method for diffuse light). A Lambertian layer i
 * reflects r_i = fR_i and transmits t_i = fT_i of whatever reaches it, from either side
 * and for any direction of arrival, and what it sends on is cosine distributed. So every
 * crossing of an interior medium of optical thickness tau carries cosine-distributed
 * light, of which d = 2 E3(tau) = 2 int_0^1 mu exp(-tau/mu) dmu gets through (whatever
 * its angular shape after that, the next Lambertian layer only sees its total). A stack
 * is then described by (R, R', T): reflectance from above, from below, transmittance
 * (the same both ways). Adding stack a on top of stack b through d:
 *     D  = 1 - R'_a R_b d^2
 *     R  = R_a + T_a^2 d^2 R_b / D
 *     R' = R'_b + T_b^2 d^2 R'_a / D
 *     T  = T_a d T_b / D
 * The light enters through the clear top (bottom) medium and meets a Lambertian layer
 * first, so R, T do not depend on theta_o. For the same reason the emergent BSDF is a
 * constant on each side: every upward exit leaves the top layer last (its point
 * estimate is w fR or w fT |cos|/pi times the same factors for every wi), so
 * f = R/pi at every reflected direction and T/pi at every transmitted one; the
 * directions of lsqt_wi_spread are a midpoint rule in cos theta_i, exact for a constant
 * f cos, so the point estimates' hemispherical integrals (nee_albedo.h) estimate R and
 * T without quadrature error.
 *
 * Checks per stack, side (above, below) and slice (theta_o 0 and 75 degrees): R and T
 * of the exit tallies, R and T integrated from the point estimates (3 x 2 x 2 x 4 = 48);
 * then, per stack and estimator, pooled over the independent slices: R from above (2
 * slices), from below (2), T (all 4, the same number) (3 x 3 x 2 = 18). Batch means over
 * 32 batches give Student-t(31) z-scores (a pooled one has more degrees of freedom);
 * |t| > 5.4 has probability 1.2e-5 each, so a correct code fails with probability
 * < 8e-4 in all 66.
 *
 * Detectable effect (tools/mutate/new-h2.txt, stack-*; z-scores of the seeds here): R and
 * T carry relative standard errors of 0.002-0.1 % per slice (0.002-0.05 % pooled). A
 * layer hit from below inside the stack choosing reflection 0.5 % too often (T moves
 * by 0.15-0.2 %) fails at z 7, 1 % at z 11.5, 2 % at z 20; a vertex of the bottom layer
 * estimating up through the layer above it fails at z > 1000; upward flights in the
 * interior absorber 2 % short fail at z 11.7. */
#include "cl_fixture.h"
#include "lsqt/below.h"
#include "lsqt/simulate.h"
#include "nee_albedo.h"
#include "quadrature.h"

#define PI 3.14159265358979323846
#define Z_TOL 5.4
#define PATHS ((uint64_t)1 << 23)

typedef struct {
    double R, Rb, T; /* from above, from below, transmittance */
} stack3;

/* 2 E3(tau): the fraction of cosine-distributed light that crosses a clear slab. */
static double diffuse_trans(double tau)
{
    if (tau == 0.0) return 1.0;
    double x[64], w[64], sum = 0;
    gauss_legendre(64, x, w);
    /* two panels, mu in (0, 0.2] and [0.2, 1]: mu exp(-tau/mu) is flat near 0 */
    const double e[3] = {0.0, 0.2, 1.0};
    for (int p = 0; p < 2; p++)
        for (int i = 0; i < 64; i++) {
            double h = 0.5 * (e[p + 1] - e[p]), mu = e[p] + h * (x[i] + 1);
            sum += h * w[i] * mu * exp(-tau / mu);
        }
    return 2.0 * sum;
}

static stack3 add(stack3 a, stack3 b, double tau)
{
    const double d = diffuse_trans(tau), D = 1.0 - a.Rb * b.R * d * d;
    stack3 s = {a.R + a.T * a.T * d * d * b.R / D, b.Rb + b.T * b.T * d * d * a.Rb / D, a.T * d * b.T / D};
    return s;
}

typedef struct {
    const char *name;
    int n; /* layers */
    double fr[3], ft[3], tau[2]; /* tau[i]: the medium between layers i and i + 1 */
    uint64_t seed;
} stack_case;

static void run_case(const stack_case *c)
{
    /* the LSQT text: layers at z = 2 (n - 1 - i), interior media of thickness 2 */
    char text[1024];
    int len = snprintf(text, sizeof text, "Medium\n");
    for (int i = 0; i < c->n; i++) {
        len += snprintf(text + len, sizeof text - (size_t)len, "Layer z=%d LambertianBsdf fR=%g fT=%g\n",
                        2 * (c->n - 1 - i), c->fr[i], c->ft[i]);
        if (i < c->n - 1) len += snprintf(text + len, sizeof text - (size_t)len, "Medium mua=%g\n", c->tau[i] / 2.0);
        else len += snprintf(text + len, sizeof text - (size_t)len, "Medium\n");
    }
    stack3 ref = {c->fr[0], c->fr[0], c->ft[0]};
    for (int i = 1; i < c->n; i++) {
        stack3 l = {c->fr[i], c->fr[i], c->ft[i]};
        ref = add(ref, l, c->tau[i - 1]);
    }
    printf("%s: R = %.6f, R from below = %.6f, T = %.6f (adding)\n", c->name, ref.R, ref.Rb, ref.T);
    CHECK(fabs(ref.R - ref.Rb) > 0.02, "%s: not asymmetric enough (R %.4f, R' %.4f)", c->name, ref.R, ref.Rb);

    lsqt_assembly a;
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    if (lsqt_parse(text, strlen(text), "test", NULL, 1, NULL, &a, &diag)) {
        fprintf(stderr, "parse failed: %s\n%s", diag.error, text);
        exit(1);
    }
    size_t n = lsqt_assembly_canonical(&a, NULL, 0);
    char *canon = malloc(n + 1);
    lsqt_assembly_canonical(&a, canon, n + 1);
    enum { NS = 2, NWI = 16 };
    const double deg[NS] = {0.0, 75.0};
    lsqt_state st;
    if (lsqt_state_init(&st, canon, lsqt_assembly_hash(&a), c->seed, NS, NWI, lsqt_assembly_transmits(&a), 1, NULL)) exit(1);
    free(canon);
    CHECK(st.transmits, "%s: the stack must transmit", c->name);
    for (int s = 0; s < NS; s++) {
        st.theta_o[s] = deg[s] * PI / 180.0;
        lsqt_wi_spread(NWI, st.transmits, st.wi + (size_t)s * NWI * 4);
    }
    if (lsqt_state_add_below(&st)) exit(1);
    lsqt_sim_opts o = {0, 0.0, 0, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
    lsqt_sim_stats stats;
    char err[1024];
    if (lsqt_simulate(&fixture_cx, &a, &st, PATHS, &o, &stats, err, sizeof err)) {
        fprintf(stderr, "simulate failed: %s\n", err);
        exit(1);
    }
    CHECK(st.n_slices == 2 * NS && st.flags == 0, "%s: %d slices, flags %u", c->name, st.n_slices, st.flags);
    lsqt_slice_est *e = lsqt_estimates(&st);
    /* pooled over independent slices (each slice its own paths): R from above, from
     * below, T (the same for all four), for the exit tallies [0] and point estimates [1] */
    double pool[3][2][2] = {{{0}}}; /* [what][estimator][sum, sum of err^2] */
    int npool[3] = {0, 0, 0};
    for (int s = 0; s < st.n_slices; s++) {
        const int below = s >= NS;
        const double want_r = below ? ref.Rb : ref.R;
        const char *side = below ? "below" : "above";
        lsqt_est rn = nee_albedo_minus(&st, s, 1, 0.0, LSQT_T_R), tn = nee_albedo_minus(&st, s, 0, 0.0, LSQT_T_T);
        printf("  %s from %s to=%2.0f: R %.6f +- %.6f (z %+.2f), T %.6f +- %.6f (z %+.2f); point estimates R %.6f +- "
               "%.6f (z %+.2f), T %.6f +- %.6f (z %+.2f)\n",
               c->name, side, deg[s % NS], e[s].R.mean, e[s].R.err, (e[s].R.mean - want_r) / e[s].R.err, e[s].T.mean,
               e[s].T.err, (e[s].T.mean - ref.T) / e[s].T.err, rn.mean, rn.err, (rn.mean - want_r) / rn.err, tn.mean,
               tn.err, (tn.mean - ref.T) / tn.err);
        CHECK(e[s].paths == PATHS && e[s].cut == 0, "%s from %s: %llu paths, %llu cut", c->name, side,
              (unsigned long long)e[s].paths, (unsigned long long)e[s].cut);
        CHECK_Z(e[s].R.mean, want_r, e[s].R.err, Z_TOL);
        CHECK_Z(e[s].T.mean, ref.T, e[s].T.err, Z_TOL);
        CHECK_Z(rn.mean, want_r, rn.err, Z_TOL);
        CHECK_Z(tn.mean, ref.T, tn.err, Z_TOL);
        const lsqt_est *x[2][2] = {{&e[s].R, &rn}, {&e[s].T, &tn}};
        for (int k = 0; k < 2; k++) {
            const int what = k == 1 ? 2 : below;
            for (int j = 0; j < 2; j++) pool[what][j][0] += x[k][j]->mean, pool[what][j][1] += x[k][j]->err * x[k][j]->err;
            npool[what]++;
        }
    }
    const char *names[3] = {"R from above", "R from below", "T"};
    const double want[3] = {ref.R, ref.Rb, ref.T};
    for (int w = 0; w < 3; w++)
        for (int j = 0; j < 2; j++) {
            const double m = pool[w][j][0] / npool[w], se = sqrt(pool[w][j][1]) / npool[w];
            printf("  %s: %s pooled over %d slices (%s): %.6f +- %.6f, adding %.6f (z %+.2f)\n", c->name, names[w],
                   npool[w], j ? "point estimates" : "exits", m, se, want[w], (m - want[w]) / se);
            CHECK_Z(m, want[w], se, Z_TOL);
        }
    lsqt_estimates_free(e, st.n_slices);
    lsqt_state_free(&st);
    lsqt_assembly_free(&a);
}

int main(void)
{
    fixture_open();
    /* E3 against its series-free special values: 2 E3(0) = 1, E3(1) = 0.10969197 (by a fine midpoint rule) */
    CHECK(fabs(diffuse_trans(1.0) / 2 - 0.10969197) < 1e-7, "2 E3(1) = %.9f", diffuse_trans(1.0));
    /* Asymmetric (R and R' differ by 0.06 to 0.36), and chosen so that the layers hit
     * from below inside the stack (all but the lowest in either view) matter: fR near
     * fT there and a bright layer under them, so a 1 % change of one of their branch
     * probabilities moves T by 0.2-0.35 % (an interior bounce's error is diluted). */
    const stack_case cases[] = {
        {"two layers in vacuum", 2, {0.45, 0.6}, {0.45, 0.35}, {0.0}, 231},
        {"two layers, absorber tau 0.1 between", 2, {0.45, 0.75}, {0.5, 0.2}, {0.1}, 232},
        {"three layers, vacuum then absorber tau 0.3", 3, {0.45, 0.5, 0.3}, {0.5, 0.45, 0.5}, {0.0, 0.3}, 233},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) run_case(&cases[i]);
    lsqt_context_release(&fixture_cx);
    return check_finish("test_power_stacks");
}
