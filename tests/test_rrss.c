/* RRSS (docs/design.md section 3.5): the selection rule, determinism, and that an RRSS state is exactly a run
 * with its directions.
 *  - selection: with the BSDF of a narrow lobe the kept candidates crowd at the lobe;
 *    with a constant BSDF they keep about the candidates' own share everywhere; with a
 *    BSDF that is 0 everywhere it falls back to the sampling density; ties go by index
 *    (the same inputs give the same choice, and a permutation-free input is stable); the
 *    choice equals an independent, plain implementation's where discs hold from one to
 *    several hundred candidates;
 *  - on the device: two RRSS runs, and two work-group sizes, give byte-identical states;
 *    the kept directions' tallies are bit for bit those of a plain run of the pilot's
 *    paths with those directions (so "they keep their pilot tallies" holds exactly), and
 *    continuing both by the same paths keeps them equal; every candidate set of the
 *    pilot state holds the R, T, work and histogram of a plain run of the same paths, also
 *    when the pilot is continued from a state that holds each block's histogram;
 *  - placement: for a smooth dielectric (alpha 0.05) the share of kept directions within
 *    10 degrees of the mirror direction is well above the even spread's (which is about
 *    the cap's solid angle, 0.095 sr of the pi-sr half hemisphere). */
#include <math.h>

#include "cl_fixture.h"
#include "lsqt/rrss.h"

#define PI 3.14159265358979323846

static void unit(float *d, double x, double y, double z)
{
    double l = sqrt(x * x + y * y + z * z);
    d[0] = (float)(x / l), d[1] = (float)(fabs(y) / l), d[2] = (float)(z / l), d[3] = 0;
}

static void test_select(void)
{
    enum { M = 400, N = 100 };
    static float dirs[4 * M];
    static double f[M];
    static unsigned char keep[M], keep2[M];
    /* candidates uniform over the half hemisphere (y >= 0), in random order as exits come */
    uint64_t r = 12345;
    for (int i = 0; i < M; i++) {
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        double u1 = (double)(r >> 11) / 9007199254740992.0;
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        double u2 = (double)(r >> 11) / 9007199254740992.0, z = u1, sn = sqrt(1 - z * z);
        unit(dirs + 4 * i, sn * cos(PI * u2), sn * sin(PI * u2), z);
    }
    /* a narrow lobe around (0.6, 0, 0.8): f = exp(-angle^2 / (2 0.05^2)) */
    int in_lobe_all = 0, in_lobe_kept = 0;
    const double lobe[3] = {0.6, 0, 0.8};
    for (int i = 0; i < M; i++) {
        double c = dirs[4 * i] * lobe[0] + dirs[4 * i + 1] * lobe[1] + dirs[4 * i + 2] * lobe[2];
        double ang = acos(fmin(1, c));
        f[i] = exp(-ang * ang / (2 * 0.05 * 0.05)) * 50;
        in_lobe_all += ang < 0.25;
    }
    CHECK(lsqt_rrss_select(dirs, f, M, N, 0, keep) == 0, "a usable BSDF fell back");
    int kept = 0;
    for (int i = 0; i < M; i++) kept += keep[i], in_lobe_kept += keep[i] && acos(fmin(1, dirs[4 * i] * 0.6 + dirs[4 * i + 2] * 0.8)) < 0.25;
    CHECK(kept == N, "kept %d of %d", kept, M);
    /* all the candidates of the lobe stay (they are few and dense in q); the even share
     * would be N / M of them */
    CHECK(in_lobe_kept == in_lobe_all && in_lobe_all > 0, "lobe: %d of %d candidates kept", in_lobe_kept, in_lobe_all);
    /* the same inputs: the same choice */
    lsqt_rrss_select(dirs, f, M, N, 0, keep2);
    CHECK(memcmp(keep, keep2, M) == 0, "two selections differ");
    /* a constant BSDF over uniform candidates: the kept ones stay spread out (each
     * quarter of the |cos| range keeps between 15 % and 35 % of them) */
    for (int i = 0; i < M; i++) f[i] = 0.3;
    lsqt_rrss_select(dirs, f, M, N, 0, keep);
    int quarter[4] = {0, 0, 0, 0};
    for (int i = 0; i < M; i++)
        if (keep[i]) quarter[(int)fmin(3, dirs[4 * i + 2] * 4)]++;
    for (int k = 0; k < 4; k++) CHECK(quarter[k] >= 15 && quarter[k] <= 35, "constant BSDF: quarter %d keeps %d", k, quarter[k]);
    /* a BSDF that is 0 everywhere: the sampling density */
    for (int i = 0; i < M; i++) f[i] = 0;
    CHECK(lsqt_rrss_select(dirs, f, M, N, 0, keep) == 1, "an all-zero BSDF did not fall back");
    /* identical candidates (ties): the lowest indices go first, the last ones stay */
    for (int i = 0; i < M; i++) unit(dirs + 4 * i, 0.3, 0.1, 0.9), f[i] = 1;
    lsqt_rrss_select(dirs, f, M, N, 0, keep);
    int first_kept = M;
    for (int i = 0; i < M; i++)
        if (keep[i]) { first_kept = i; break; }
    CHECK(first_kept == M - N, "ties: first kept %d, want %d", first_kept, M - N);
}

/* An independent reading of the selection (docs/design.md section 3.5 and rrss.c's documented order), plain
 * and slow: the candidates' density from the 8 nearest, the target q, then m - n times
 * the most redundant enabled candidate off. A disc's sums run over the others in order
 * of nearness (dot product descending, then index), the first 256 of them; a disc that
 * holds all 256 (of more than 256 others) sums all it holds in index order. */
typedef struct {
    double dot;
    int j;
} ref_nbr;

static int ref_nbr_cmp(const void *x, const void *y)
{
    const ref_nbr *a = x, *b = y;
    if (a->dot != b->dot) return a->dot < b->dot ? 1 : -1;
    return (a->j > b->j) - (a->j < b->j);
}

static double ref_dot(const float *a, const float *b)
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

static void ref_select(const float *dirs, const double *f, int m, int n, int sphere, unsigned char *keep)
{
    ref_nbr *all = malloc((size_t)m * (size_t)(m - 1) * sizeof *all);
    double *q = malloc((size_t)m * sizeof *q), *pe = malloc((size_t)m * sizeof *pe);
    const int k = m - 1 < 8 ? m - 1 : 8, kmax = m - 1 < 256 ? m - 1 : 256;
    for (int i = 0; i < m; i++) {
        ref_nbr *l = all + (size_t)i * (size_t)(m - 1);
        for (int j = 0, c = 0; j < m; j++)
            if (j != i) l[c].dot = ref_dot(dirs + 4 * i, dirs + 4 * j), l[c++].j = j;
        qsort(l, (size_t)(m - 1), sizeof *l, ref_nbr_cmp);
        double cap = fmax(2 * PI * (1 - fmin(l[k - 1].dot, 1.0)), 1e-12);
        pe[i] = k / (m * cap);
    }
    double z = 0;
    for (int i = 0; i < m; i++) z += (isfinite(f[i]) && f[i] > 0 ? f[i] : 0.0) / pe[i] / m;
    const int fb = !(isfinite(z) && z > 0);
    for (int i = 0; i < m; i++)
        q[i] = fb ? pe[i] : 0.9 * (isfinite(f[i]) && f[i] > 0 ? f[i] : 0.0) / z + 0.1 / (sphere ? 2 * PI : PI);
    for (int i = 0; i < m; i++) keep[i] = 1;
    for (int enabled = m; enabled > n; enabled--) {
        int worst = -1;
        double worst_r = -1;
        for (int i = 0; i < m; i++) {
            if (!keep[i]) continue;
            double r = sqrt(1.0 / (PI * q[i] * enabled)), c = r >= PI ? -2.0 : cos(r), e = 0, a = 0, qs = 0;
            const ref_nbr *l = all + (size_t)i * (size_t)(m - 1);
            int t = 0;
            while (t < m - 1 && l[t].dot >= c) t++;
            if (t >= kmax && kmax < m - 1) {
                for (int j = 0; j < m; j++)
                    if (j != i && ref_dot(dirs + 4 * i, dirs + 4 * j) >= c) a += 1, qs += q[j], e += keep[j];
            } else {
                for (int u = 0; u < t; u++) a += 1, qs += q[l[u].j], e += keep[l[u].j];
            }
            double red = a > 0 ? e * a * q[i] / qs : 0.0;
            if (red > worst_r) worst_r = red, worst = i;
        }
        keep[worst] = 0;
    }
    free(all), free(q), free(pe);
}

/* The selection against the reference on candidates whose discs hold from one to several
 * hundred others: an even spread of 300 and a dense cluster of 300 away from a narrow
 * lobe (the cluster's target density is the floor, so its discs are wide). */
static void test_select_reference(void)
{
    enum { M = 600, N = 150 };
    static float dirs[4 * M];
    static double f[M];
    static unsigned char keep[M], ref[M];
    uint64_t r = 987654321;
    for (int i = 0; i < M; i++) {
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        double u1 = (double)(r >> 11) / 9007199254740992.0;
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        double u2 = (double)(r >> 11) / 9007199254740992.0;
        if (i % 2) { /* the cluster: within 0.15 rad of (-0.5, 0, 0.866) */
            double t = 0.15 * sqrt(u1), p = 2 * PI * u2;
            unit(dirs + 4 * i, -0.5 + t * cos(p) * 0.866, t * sin(p), 0.866 + t * cos(p) * 0.5);
        } else {
            double z = u1, sn = sqrt(1 - z * z);
            unit(dirs + 4 * i, sn * cos(PI * u2), sn * sin(PI * u2), z);
        }
        double c = dirs[4 * i] * 0.6 + dirs[4 * i + 2] * 0.8, ang = acos(fmin(1, c));
        f[i] = 50 * exp(-ang * ang / (2 * 0.05 * 0.05));
    }
    lsqt_rrss_select(dirs, f, M, N, 0, keep);
    ref_select(dirs, f, M, N, 0, ref);
    int diff = 0, kept = 0;
    for (int i = 0; i < M; i++) diff += keep[i] != ref[i], kept += keep[i];
    CHECK(diff == 0 && kept == N, "selection differs from the reference in %d of %d candidates (kept %d)", diff, M, kept);
    /* and a BSDF that is 0 everywhere: the density fallback, the same way */
    for (int i = 0; i < M; i++) f[i] = 0;
    lsqt_rrss_select(dirs, f, M, N, 0, keep);
    ref_select(dirs, f, M, N, 0, ref);
    diff = 0;
    for (int i = 0; i < M; i++) diff += keep[i] != ref[i];
    CHECK(diff == 0, "fallback selection differs from the reference in %d of %d candidates", diff, M);
}

typedef struct {
    lsqt_assembly a;
    lsqt_state st;
} run_t;

static void fresh(run_t *r, const char *text, int n_slices, const double *deg, int n_wi, uint64_t seed)
{
    lsqt_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(lsqt_parse(text, strlen(text), "test", NULL, 1, NULL, &r->a, &diag) == 0, "%s", diag.error);
    size_t n = lsqt_assembly_canonical(&r->a, NULL, 0);
    char *canon = malloc(n + 1);
    lsqt_assembly_canonical(&r->a, canon, n + 1);
    CHECK(lsqt_state_init(&r->st, canon, lsqt_assembly_hash(&r->a), seed, n_slices, n_wi,
                          lsqt_assembly_transmits(&r->a), 1, NULL) == 0, "state");
    free(canon);
    for (int s = 0; s < n_slices; s++) {
        r->st.theta_o[s] = deg[s] * PI / 180;
        lsqt_wi_spread(n_wi, r->st.transmits, r->st.wi + (size_t)s * (size_t)n_wi * 4);
    }
}

static void rrss_run(run_t *r, int rx, uint64_t pilot, uint64_t rest, size_t local_size)
{
    char err[1024];
    lsqt_sim_opts o = {0, 0.0, local_size, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
    lsqt_rrss_info info;
    lsqt_sim_stats stats;
    CHECK(lsqt_rrss(&fixture_cx, &r->a, &r->st, rx, pilot, &o, &info, err, sizeof err) == 0, "%s", err);
    CHECK(r->st.paths == pilot && info.candidates == rx * r->st.n_wi, "pilot %llu paths, %d candidates",
          (unsigned long long)r->st.paths, info.candidates);
    CHECK(lsqt_simulate(&fixture_cx, &r->a, &r->st, rest, &o, &stats, err, sizeof err) == 0, "%s", err);
}

static int same_state(const lsqt_state *x, const lsqt_state *y)
{
    return x->paths == y->paths && x->n_wi == y->n_wi && x->n_slices == y->n_slices &&
           !memcmp(x->wi, y->wi, (size_t)x->n_slices * x->n_wi * 4 * sizeof *x->wi) &&
           !memcmp(x->nee, y->nee, lsqt_state_nee_count(x) * sizeof *x->nee) &&
           !memcmp(x->scalars, y->scalars, lsqt_state_scalar_count(x) * sizeof *x->scalars) &&
           !memcmp(x->hist, y->hist, lsqt_state_hist_count(x) * sizeof *x->hist);
}

static void free_run(run_t *r)
{
    lsqt_state_free(&r->st);
    lsqt_assembly_free(&r->a);
}

static const char *const SMOOTH = "Medium\nLayer z=0 MicrosurfaceDielectricBsdf alpha=0.05\nMedium eta=1.5\n";
static const char *const DUSTY =
    "Medium\nLayer z=1 NullBsdf\nMedium mus=2 HenyeyGreensteinPhase g=0.6\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n";

static void test_device(void)
{
    const double deg[] = {0, 40, 75};
    for (int t = 0; t < 2; t++) {
        const char *text = t ? DUSTY : SMOOTH;
        run_t a, b, c, plain;
        fresh(&a, text, 3, deg, 24, 5);
        fresh(&b, text, 3, deg, 24, 5);
        fresh(&c, text, 3, deg, 24, 5);
        rrss_run(&a, 4, 3000, 1000, 0);
        rrss_run(&b, 4, 3000, 1000, 0);
        rrss_run(&c, 4, 3000, 1000, 16);
        CHECK(same_state(&a.st, &b.st), "%s: two RRSS runs differ", t ? "dusty" : "smooth");
        CHECK(same_state(&a.st, &c.st), "%s: work-group sizes 64 and 16 differ", t ? "dusty" : "smooth");
        /* a plain run with the kept directions: the same tallies, bit for bit */
        fresh(&plain, text, 3, deg, 24, 5);
        memcpy(plain.st.wi, a.st.wi, (size_t)3 * 24 * 4 * sizeof *a.st.wi);
        char err[1024];
        lsqt_sim_opts o = {0, 0.0, 0, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
        lsqt_sim_stats stats;
        CHECK(lsqt_simulate(&fixture_cx, &plain.a, &plain.st, 4000, &o, &stats, err, sizeof err) == 0, "%s", err);
        CHECK(same_state(&a.st, &plain.st), "%s: RRSS state != a plain run with its directions", t ? "dusty" : "smooth");
        if (!t) {
            /* the smooth dielectric: kept directions near the mirror direction of each
             * slice, against the spread's */
            int all_r = 0, all_e = 0;
            for (int s = 0; s < 3; s++) {
                /* the two specular peaks: the mirror direction and the refracted one */
                const double th = deg[s] * PI / 180, tt = asin(sin(th) / 1.5);
                const double peak[2][3] = {{-sin(th), 0, cos(th)}, {-sin(tt), 0, -cos(tt)}};
                int near_r = 0, near_e = 0;
                float spread[4 * 24];
                lsqt_wi_spread(24, 1, spread);
                for (int k = 0; k < 24; k++) {
                    const float *d = a.st.wi + ((size_t)s * 24 + k) * 4, *e = spread + 4 * k;
                    int nr = 0, ne = 0;
                    for (int j = 0; j < 2; j++) {
                        nr |= acos(fmin(1, d[0] * peak[j][0] + d[2] * peak[j][2])) < 10 * PI / 180;
                        ne |= acos(fmin(1, e[0] * peak[j][0] + e[2] * peak[j][2])) < 10 * PI / 180;
                    }
                    near_r += nr, near_e += ne;
                }
                printf("smooth dielectric slice %g deg: %d of 24 RRSS directions within 10 deg of a specular peak "
                       "(mirror or refracted), %d of the spread's\n", deg[s], near_r, near_e);
                CHECK(near_r >= 4 && near_r >= 2 * near_e + 3, "slice %g: %d near the peaks (spread %d)", deg[s],
                      near_r, near_e);
                all_r += near_r, all_e += near_e;
            }
            printf("smooth dielectric: %d of 72 RRSS directions near a peak, %d of the spread's\n", all_r, all_e);
        }
        free_run(&a), free_run(&b), free_run(&c), free_run(&plain);
    }
}

/* The pilot state itself: one walk serves a slice's rx candidate sets, so every block
 * holds the same R, T, work counters and histogram, and those are a plain run's of the
 * same paths (its directions do not change them). */
static void test_pilot_blocks(void)
{
    const double deg[] = {0, 60};
    enum { RX = 3, NWI = 18 }; /* 18: blocks padded inside the kernel's direction set */
    run_t r, plain;
    fresh(&r, DUSTY, 2, deg, NWI, 9);
    fresh(&plain, DUSTY, 2, deg, NWI, 9);
    char err[1024];
    lsqt_sim_opts o = {0, 0.0, 0, NULL, NULL, 0, 0.0, 0.0, NULL, NULL, NULL};
    lsqt_state ps;
    lsqt_rrss_info info;
    lsqt_sim_stats stats;
    memset(&ps, 0, sizeof ps);
    CHECK(lsqt_rrss_pilot(&fixture_cx, &r.a, &r.st, RX, 2000, 2000, 0, 2000, &o, &ps, &info, err, sizeof err) == 0, "%s",
          err);
    CHECK(lsqt_simulate(&fixture_cx, &plain.a, &plain.st, 2000, &o, &stats, err, sizeof err) == 0, "%s", err);
    CHECK(ps.n_slices == 2 * RX, "pilot slices %d", ps.n_slices);
    const size_t ns = (size_t)LSQT_BATCHES * LSQT_T_COUNT, nh = (size_t)LSQT_BATCHES * LSQT_HIST_BINS;
    for (int s = 0; s < 2 && ps.n_slices == 2 * RX; s++)
        for (int b = 0; b < RX; b++) {
            const size_t v = (size_t)s * RX + (size_t)b;
            CHECK(!memcmp(ps.scalars + v * ns, plain.st.scalars + (size_t)s * ns, ns * sizeof *ps.scalars),
                  "pilot slice %d block %d: R, T or work differ from a plain run of the same paths", s, b);
            CHECK(!memcmp(lsqt_state_hist_of(&ps, (int)v), plain.st.hist + (size_t)s * nh, nh * sizeof *ps.hist),
                  "pilot slice %d block %d: the exit histogram differs from a plain run's", s, b);
        }
    /* A pilot stopped after 1000 paths and continued from a state that holds every block's
     * histogram (as one read from its LSS does) ends with every block's histogram that of
     * the plain run of all 2000 paths. */
    lsqt_state half, q;
    memset(&half, 0, sizeof half);
    CHECK(lsqt_rrss_pilot(&fixture_cx, &r.a, &r.st, RX, 2000, 2000, 0, 1000, &o, &half, &info, err, sizeof err) == 0,
          "%s", err);
    CHECK(half.hist_group == RX, "the pilot state's histograms are one a slice (group %u)", half.hist_group);
    CHECK(lsqt_state_init(&q, half.canonical, half.hash, half.seed, half.n_slices, half.n_wi, half.transmits, 1,
                                NULL) == 0 && lsqt_state_set_ranges(&q, half.ranges, half.n_ranges) == 0,
          "out of memory");
    q.use_double = half.use_double, q.dir_method = half.dir_method, q.rx = half.rx, q.stage = half.stage;
    q.pilot_paths = half.pilot_paths, q.span_end = half.span_end, q.flags = half.flags;
    memcpy(q.theta_o, half.theta_o, (size_t)q.n_slices * sizeof *q.theta_o);
    memcpy(q.slice_flags, half.slice_flags, (size_t)q.n_slices * sizeof *q.slice_flags);
    memcpy(q.wi, half.wi, (size_t)q.n_slices * (size_t)q.n_wi * 4 * sizeof *q.wi);
    for (int v = 0; v < q.n_slices; v++) lsqt_state_copy_slice_tallies(&q, v, &half, v);
    CHECK(lsqt_rrss_pilot_continue(&fixture_cx, &r.a, &q, 1000, 1000, &o, &info, err, sizeof err) == 0, "%s", err);
    for (int v = 0; v < q.n_slices && q.n_slices == 2 * RX; v++)
        CHECK(!memcmp(lsqt_state_hist_of(&q, v), plain.st.hist + (size_t)(v / RX) * nh, nh * sizeof *q.hist),
              "pilot continued from every block's histograms: block %d of slice %d differs from a plain run's", v % RX,
              v / RX);
    lsqt_state_free(&q), lsqt_state_free(&half);
    lsqt_state_free(&ps);
    free_run(&r), free_run(&plain);
}

int main(void)
{
    test_select();
    test_select_reference();
    fixture_open();
    test_device();
    test_pilot_blocks();
    lsqt_context_release(&fixture_cx);
    return check_finish("test_rrss");
}
