/* RRSS (rrss.h): candidates from the slices' own walks, a pilot that estimates the BSDF
 * at all of them, and the redundancy reduction of docs/design.md section 3.5. */
#include "lsqt/rrss.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/directions.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

#define NBR_MAX 256  /* neighbours summed in order of nearness for a redundancy disc */
#define NBR_KEEP 48  /* of those, kept per candidate (a disc holds a few; a larger one is
                        ordered again when it comes: the same sums, 5x less sorting) */
#define KNN 8         /* neighbours behind the candidates' density estimate */
#define FLOOR 0.1     /* share of the uniform density in the target: no region is left bare */

typedef struct {
    double dot;
    int j;
} nbr;

static double dot3f(const float *a, const float *b)
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* Decreasing dot product; equal ones by index, so the order is the same everywhere. */
static int nbr_cmp(const void *x, const void *y)
{
    const nbr *a = x, *b = y;
    if (a->dot != b->dot) return a->dot < b->dot ? 1 : -1;
    return (a->j > b->j) - (a->j < b->j);
}

/* nbr_cmp's order, inline: before = larger dot, or equal dot and smaller index. */
static int nbr_before(const nbr *a, const nbr *b) { return a->dot > b->dot || (a->dot == b->dot && a->j < b->j); }

/* Puts the first k of v[0..n) in nbr_cmp's order into v[0..k), sorted: a quickselect
 * (median of three) and a sort of those k only. The order is total, so the result is the
 * same as sorting all n; the selection made RRSS's choice 30 % of a Substr run. */
static void nbr_first_k(nbr *v, int n, int k)
{
    int lo = 0, hi = n - 1;
    while (hi - lo > 16 && lo < k) { /* lo <= k <= hi + 1 throughout */
        int mid = lo + (hi - lo) / 2;
        nbr a = v[lo], b = v[mid], c = v[hi], piv;
        if (nbr_before(&a, &b)) piv = nbr_before(&b, &c) ? b : (nbr_before(&a, &c) ? c : a);
        else piv = nbr_before(&a, &c) ? a : (nbr_before(&b, &c) ? c : b);
        int i = lo, j = hi;
        while (i <= j) {
            while (nbr_before(&v[i], &piv)) i++;
            while (nbr_before(&piv, &v[j])) j--;
            if (i <= j) {
                nbr t = v[i];
                v[i] = v[j], v[j] = t;
                i++, j--;
            }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else break; /* v[j+1..i) equal the pivot: the split is at k */
    }
    /* everything in v[0..hi] comes before everything after it, and k <= hi + 1 */
    qsort(v, (size_t)(hi + 1), sizeof *v, nbr_cmp);
}

/* The density of the m candidates (per steradian) at each of them: k of them within the
 * cap out to the k-th nearest other one, k / (m * 2 pi (1 - cos)). It resolves a narrow
 * lobe, where the candidates crowd, as no fixed bin can. */
static void candidate_density(const float *dirs, int m, double *p)
{
    const int k = m - 1 < KNN ? m - 1 : KNN;
    for (int i = 0; i < m; i++) {
        double best[KNN]; /* the k largest dot products, descending */
        int have = 0;
        const float *di = dirs + 4 * i;
        for (int j = 0; j < m; j++) {
            if (j == i) continue;
            const float *dj = dirs + 4 * j;
            double dot = (double)di[0] * dj[0] + (double)di[1] * dj[1] + (double)di[2] * dj[2];
            if (have < k) best[have++] = dot;
            else if (dot > best[k - 1]) best[k - 1] = dot;
            else continue;
            for (int t = have - 1; t > 0 && best[t] > best[t - 1]; t--) {
                double x = best[t];
                best[t] = best[t - 1], best[t - 1] = x;
            }
        }
        double cap = k > 0 ? 2 * LSQT_PI * (1 - fmin(best[k - 1], 1.0)) : 0.0;
        cap = fmax(cap, 1e-12); /* coincident candidates */
        p[i] = k > 0 ? k / (m * cap) : 1.0;
    }
}

/* Candidate i's k nearest others into out[0..k), in nbr_cmp's order. xyz: the candidates'
 * coordinates as doubles, x[m], y[m], z[m] (the dot products of the floats, term for term
 * as dot3f adds them, in a loop the compiler vectorises); dots, row: m scratch. For the
 * kept lists (k <= NBR_KEEP) by insertion into the sorted first k as the others are
 * scanned: after the first few, most fall behind the k-th and cost one comparison (the
 * quickselect over all m was a tenth of a Substr run). Later indices go behind equal
 * dot products, as nbr_cmp orders them. */
static void nearest(const double *xyz, int m, int i, int k, double *dots, nbr *row, nbr *out)
{
    const double *x = xyz, *y = xyz + m, *z = xyz + 2 * (size_t)m, xi = x[i], yi = y[i], zi = z[i];
    for (int j = 0; j < m; j++) dots[j] = xi * x[j] + yi * y[j] + zi * z[j];
    if (k <= NBR_KEEP) {
        int have = 0;
        for (int j = 0; j < m; j++) {
            if (j == i) continue;
            nbr v = {dots[j], j};
            if (have == k && !nbr_before(&v, &out[k - 1])) continue;
            int t = have < k ? have++ : k - 1;
            for (; t > 0 && nbr_before(&v, &out[t - 1]); t--) out[t] = out[t - 1];
            out[t] = v;
        }
        return;
    }
    int c = 0;
    for (int j = 0; j < m; j++)
        if (j != i) row[c].dot = dots[j], row[c++].j = j;
    nbr_first_k(row, c, k);
    memcpy(out, row, (size_t)k * sizeof *row);
}

/* The cosine of the redundancy disc's radius, sqrt(1 / (pi q n)), for n enabled
 * candidates (-2 when the disc is the whole sphere): it falls as n falls. */
static double disc_cos(double q, int enabled)
{
    double r = sqrt(1.0 / (LSQT_PI * q * enabled));
    return r >= LSQT_PI ? -2.0 : cos(r);
}

/* The largest count in [lo, hi] of enabled candidates at which a neighbour at dot product
 * d lies in the disc, or lo - 1 if it does at none (a bisection: d >= disc_cos holds at
 * every count up to it). */
static int enter_count(double d, double q, int lo, int hi)
{
    if (!(d >= disc_cos(q, lo))) return lo - 1;
    while (lo < hi) {
        int mid = lo + (hi - lo + 1) / 2;
        if (d >= disc_cos(q, mid)) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

/* The target density q of every candidate: (1 - FLOOR) f / Z + FLOOR / |D|, Z the integral
 * of f over D by importance sampling with the candidates' density pe; pe itself when Z is
 * not positive (returns 1: the density fallback), else returns 0. */
static int target_density(const float *dirs, const double *f, int m, int sphere, double *q, double *pe)
{
    const double domain = sphere ? 2 * LSQT_PI : LSQT_PI; /* the directions have y >= 0 */
    candidate_density(dirs, m, pe);
    double z = 0.0;
    for (int i = 0; i < m; i++) z += (isfinite(f[i]) && f[i] > 0 ? f[i] : 0.0) / pe[i] / m;
    const int fallback = !(isfinite(z) && z > 0);
    for (int i = 0; i < m; i++) {
        double fi = isfinite(f[i]) && f[i] > 0 ? f[i] : 0.0;
        q[i] = fallback ? pe[i] : (1 - FLOOR) * fi / z + FLOOR / domain;
    }
    return fallback;
}

/* The incremental choice's state: per candidate its ordered neighbours (lst: the kept kn
 * in list, or its own kmax once its disc grows past them), how many lie in its disc
 * (t_in, with their q summed in qs_in), the enabled count at which the next one enters,
 * and whether the disc reaches past kmax (full: then it is scanned in full). */
typedef struct rrss_sel {
    const float *dirs;
    const double *q, *xyz;
    int m, n, kn, kmax;
    double *dots;
    nbr *row, *list, **lst;
    int *t_in, *next;
    double *qs_in;
    unsigned char *full;
} rrss_sel;

/* Candidate i's ordered neighbours that lie in its disc at `enabled` candidates, added.
 * Returns 0, or -1 (out of memory). */
static int grow_disc(rrss_sel *S, int i, int enabled)
{
    const double *q = S->q;
    const int m = S->m, n = S->n, kn = S->kn, kmax = S->kmax;
    nbr **lst = S->lst;
    int *t_in = S->t_in, *next = S->next;
    unsigned char *full = S->full;
    while (!full[i] && next[i] >= enabled) { /* the next ordered neighbour enters */
        S->qs_in[i] += q[lst[i][t_in[i]].j], t_in[i]++;
        if (t_in[i] == kn && kn < kmax) { /* past the kept ones: the first kmax, in order */
            nbr *ext = malloc((size_t)kmax * sizeof *ext);
            if (!ext) return -1;
            nearest(S->xyz, m, i, kmax, S->dots, S->row, ext); /* its first kn are the kept ones */
            lst[i] = ext;
        }
        if (t_in[i] == kmax) {
            full[i] = kmax < m - 1; /* the disc reaches past the ordered ones */
            next[i] = n;
        } else {
            next[i] = enter_count(lst[i][t_in[i]].dot, q[i], n + 1, enabled);
        }
    }
    return 0;
}

/* Candidate i's redundancy at `enabled` candidates: the enabled share of its disc's
 * neighbours times their count, over their density relative to its own. */
static double redundancy(const rrss_sel *S, int i, int enabled, const unsigned char *keep)
{
    const double *q = S->q;
    double e = 0, a = S->t_in[i], qs = S->qs_in[i];
    if (S->full[i]) { /* all of them, in index order */
        const double c = disc_cos(q[i], enabled);
        e = a = qs = 0;
        for (int j = 0; j < S->m; j++)
            if (j != i && dot3f(S->dirs + 4 * i, S->dirs + 4 * j) >= c) a += 1, qs += q[j], e += keep[j];
    } else {
        for (int t = 0; t < S->t_in[i]; t++) e += keep[S->lst[i][t].j];
    }
    /* the neighbours are the other candidates: one with none is not redundant */
    return a > 0 ? e * a * q[i] / qs : 0.0;
}

int lsqt_rrss_select(const float *dirs, const double *f, int m, int n, int sphere, unsigned char *keep)
{
    double *q = calloc((size_t)m, sizeof *q), *pe = calloc((size_t)m, sizeof *pe);
    if (!q || !pe) {
        free(q), free(pe);
        return -1;
    }
    /* Z = integral of f over D, by importance sampling with the candidates' density */
    const int fallback = target_density(dirs, f, m, sphere, q, pe);
    /* Each candidate's nearest others, by decreasing dot product (the first NBR_KEEP; the
     * rare disc that reaches past them is ordered again, up to NBR_MAX, and one past
     * those is scanned in full). */
    const int kmax = m - 1 < NBR_MAX ? m - 1 : NBR_MAX, kn = kmax < NBR_KEEP ? kmax : NBR_KEEP;
    nbr *list = malloc((size_t)m * (size_t)(kn > 0 ? kn : 1) * sizeof *list), *row = malloc((size_t)m * sizeof *row);
    double *xyz = malloc(3 * (size_t)m * sizeof *xyz), *dots = malloc((size_t)m * sizeof *dots);
    if (!list || !row || !xyz || !dots) {
        free(q), free(pe), free(list), free(row), free(xyz), free(dots);
        return -1;
    }
    for (int i = 0; i < m; i++)
        for (int c = 0; c < 3; c++) xyz[(size_t)c * m + i] = dirs[4 * i + c];
    for (int i = 0; i < m; i++) nearest(xyz, m, i, kn, dots, row, list + (size_t)i * kn);
    /* Disable the most redundant candidate until n remain (ties: the lowest index). A disc
     * only grows as candidates are disabled, so each candidate keeps how many of its
     * ordered neighbours lie in it (t_in, with their q sum added in the same order as a
     * fresh scan adds it) and the count of enabled candidates at which the next one
     * enters: no cosine per candidate per step. A candidate's list is its kept kn, or
     * once its disc grows past them, its own kmax (ordered again). */
    int *t_in = calloc((size_t)m, sizeof *t_in), *next = malloc((size_t)m * sizeof *next);
    double *qs_in = calloc((size_t)m, sizeof *qs_in);
    nbr **lst = malloc((size_t)m * sizeof *lst);
    unsigned char *full = calloc((size_t)m, 1); /* 1: the disc reaches past kmax: scanned in full */
    if (!t_in || !next || !qs_in || !lst || !full) {
        free(t_in), free(next), free(qs_in), free(lst), free(full);
        free(q), free(pe), free(list), free(row), free(xyz), free(dots);
        return -1;
    }
    for (int i = 0; i < m; i++) {
        keep[i] = 1;
        lst[i] = list + (size_t)i * kn;
        next[i] = kn > 0 ? enter_count(lst[i][0].dot, q[i], n + 1, m) : n;
    }
    rrss_sel S = {dirs, q, xyz, m, n, kn, kmax, dots, row, list, lst, t_in, next, qs_in, full};
    int status = fallback;
    for (int enabled = m; enabled > n; enabled--) {
        int worst = -1;
        double worst_r = -1.0;
        for (int i = 0; i < m; i++) {
            if (!keep[i]) continue;
            if (grow_disc(&S, i, enabled)) {
                status = -1;
                goto out;
            }
            const double red = redundancy(&S, i, enabled, keep);
            if (red > worst_r) worst_r = red, worst = i;
        }
        keep[worst] = 0;
    }
out:
    for (int i = 0; i < m; i++)
        if (lst[i] != list + (size_t)i * kn) free(lst[i]);
    free(t_in), free(next), free(qs_in), free(lst), free(full);
    free(list), free(row), free(xyz), free(dots);
    free(q), free(pe);
    return status;
}

/* Candidates: the first m scattered exits of each slice's candidate walks, by path index,
 * mirrored to y >= 0 (off the horizon, where a BSDF value is 0/0); a slice whose walks
 * give too few (a BSDF that is zero almost everywhere) is filled from the spread. */
static int candidates(lsqt_session *s, int n_sim, int m, int sphere, float *cand, int *short_slices, char *err,
                      size_t errcap)
{
    int *have = calloc((size_t)n_sim, sizeof *have);
    const uint32_t max_block = (uint32_t)(4 * m > 4096 ? 4 * m : 4096);
    float *out = malloc((size_t)n_sim * max_block * 4 * sizeof *out);
    int rc = 1;
    if (!have || !out) {
        snprintf(err, errcap, "out of memory");
        goto done;
    }
    /* Launches of 2m paths, doubling to max_block: most stacks give m exits in the first
     * (a walk in an optically thick medium costs hundreds of events, so the walks beyond
     * those needed were most of the pilot there). Which walks are candidates does not
     * depend on the launch sizes. */
    uint32_t block = (uint32_t)(2 * m < 64 ? 64 : 2 * m);
    if (block > max_block) block = max_block;
    for (uint64_t begin = 0; begin < (uint64_t)max_block * 64; begin += block, block = block * 2 < max_block ? block * 2 : max_block) {
        if (lsqt_session_exits(s, begin, block, out, err, errcap)) goto done;
        int missing = 0;
        for (int sl = 0; sl < n_sim; sl++) {
            for (uint32_t p = 0; p < block && have[sl] < m; p++) {
                const float *d = out + ((size_t)sl * block + p) * 4;
                if (d[3] != 1.0f || !(fabsf(d[2]) > 1e-6f) || (!sphere && d[2] < 0)) continue;
                float *c = cand + ((size_t)sl * m + (size_t)have[sl]++) * 4;
                double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
                c[0] = (float)(d[0] / len), c[1] = (float)(fabs(d[1]) / len), c[2] = (float)(d[2] / len), c[3] = 0;
            }
            missing += have[sl] < m;
        }
        if (!missing) break;
    }
    *short_slices = 0;
    float *spread = malloc((size_t)m * 4 * sizeof *spread);
    if (!spread) {
        snprintf(err, errcap, "out of memory");
        goto done;
    }
    lsqt_wi_spread(m, sphere, spread);
    for (int sl = 0; sl < n_sim; sl++) {
        if (have[sl] < m) ++*short_slices;
        for (int k = 0; have[sl] < m; k++) memcpy(cand + ((size_t)sl * m + (size_t)have[sl]++) * 4, spread + 4 * k, 16);
    }
    free(spread);
    rc = 0;
done:
    free(have);
    free(out);
    return rc;
}

/* Paths [begin, begin + n_paths) of the pilot PS through SESSION (open on PS). */
static int pilot_run(lsqt_session *sess, lsqt_state *ps, uint64_t begin, uint64_t n_paths, const lsqt_sim_opts *o,
                     lsqt_rrss_info *info, char *err, size_t errcap)
{
    lsqt_sim_opts po = *o;
    po.target_error = 0.0; /* the pilot's length is fixed: the directions depend on it */
    po.phase = "RRSS pilot";
    lsqt_sim_stats stats;
    if (o->verbose)
        fprintf(stderr, "RRSS: %d candidates per slice, pilot paths [%llu, %llu) of [0, %llu)\n",
                (int)ps->rx * ps->n_wi, (unsigned long long)begin, (unsigned long long)(begin + n_paths),
                (unsigned long long)ps->pilot_paths);
    if (lsqt_run_range(sess, ps, begin, n_paths, &po, &stats, err, errcap)) return 1;
    info->interrupted = stats.interrupted;
    return 0;
}

int lsqt_rrss_pilot(lsqt_context *cx, const lsqt_assembly *a, const lsqt_state *st, int rx, uint64_t pilot_total,
                    uint64_t run_paths, uint64_t begin, uint64_t n_paths, const lsqt_sim_opts *o, lsqt_state *ps,
                    lsqt_rrss_info *info, char *err, size_t errcap)
{
    memset(info, 0, sizeof *info);
    const int n = st->n_wi, m = rx * n, ns = st->n_slices;
    info->candidates = m;
    /* slice s's candidate set j is launch slice s * rx + j */
    if (lsqt_state_init(ps, st->canonical, st->hash, st->seed, ns * rx, n, st->transmits, st->n_bands,
                              st->wavelengths)) {
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    /* the blocks of a slice are the same paths: one histogram (a 32-band pilot's were 0.8 GB) */
    if (lsqt_state_group_hist(ps, rx) || lsqt_state_pack_hist(ps, 0)) {
        lsqt_state_free(ps);
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    ps->use_double = st->use_double;
    ps->dir_method = LSQT_DIRS_RRSS;
    ps->rx = (uint32_t)rx;
    ps->stage = LSQT_STAGE_PILOT;
    ps->pilot_paths = pilot_total;
    ps->span_end = run_paths > pilot_total ? run_paths : pilot_total;
    for (int v = 0; v < ns * rx; v++) ps->theta_o[v] = st->theta_o[v / rx], ps->slice_flags[v] = st->slice_flags[v / rx];
    float *cand = calloc((size_t)ns * m * 4, sizeof *cand);
    lsqt_session s;
    memset(&s, 0, sizeof s);
    int rc = 1;
    if (!cand) {
        snprintf(err, errcap, "out of memory");
        goto done;
    }
    if (lsqt_session_open_grouped(&s, cx, a, ps, rx, o->extra_options, o->local_size, o->verbose, err, errcap))
        goto done;
    const double t1 = lsqt_now(); /* the program build is not RRSS's time */
    if (candidates(&s, ns, m, st->transmits, cand, &info->short_slices, err, errcap)) goto done;
    memcpy(ps->wi, cand, (size_t)ns * m * 4 * sizeof *cand); /* block j of slice s is candidates j n ... */
    if (lsqt_session_set_directions(&s, ps, err, errcap)) goto done;
    s.last_read_releases = 1;
    if (pilot_run(&s, ps, begin, n_paths, o, info, err, errcap)) goto done;
    info->seconds = lsqt_now() - t1;
    rc = 0;
done:
    lsqt_session_close(&s);
    if (rc) lsqt_state_free(ps);
    free(cand);
    return rc;
}

int lsqt_rrss_pilot_continue(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *ps, uint64_t begin,
                             uint64_t n_paths, const lsqt_sim_opts *o, lsqt_rrss_info *info, char *err, size_t errcap)
{
    memset(info, 0, sizeof *info);
    info->candidates = (int)ps->rx * ps->n_wi;
    lsqt_session s;
    if (lsqt_session_open_grouped(&s, cx, a, ps, (int)ps->rx, o->extra_options, o->local_size, o->verbose, err, errcap))
        return 1;
    const double t1 = lsqt_now();
    s.last_read_releases = 1;
    int rc = pilot_run(&s, ps, begin, n_paths, o, info, err, errcap);
    info->seconds = lsqt_now() - t1;
    lsqt_session_close(&s);
    return rc;
}

/* The choice; with USED (PS itself, to be freed next) each slice's candidate sets are
 * dropped (lsqt_tallies_drop) once their tallies are copied, so the pilot's pages go back
 * as the chosen state's are written (a 32-band run held both: 447 MB of its 469 MB peak). */
static int choose(const lsqt_state *ps, lsqt_state *used, lsqt_state *st, lsqt_rrss_info *info, char *err,
                  size_t errcap)
{
    const int rx = (int)ps->rx, n = ps->n_wi, m = rx * n, ns = ps->n_slices / rx;
    info->candidates = m;
    if (lsqt_state_init(st, ps->canonical, ps->hash, ps->seed, ns, n, ps->transmits, ps->n_bands,
                              ps->wavelengths)) {
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    if (lsqt_state_pack_hist(st, 0)) {
        lsqt_state_free(st);
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    st->use_double = ps->use_double;
    st->dir_method = LSQT_DIRS_RRSS;
    st->rx = ps->rx;
    st->flags = ps->flags;
    st->span_end = ps->span_end;
    for (int sl = 0; sl < ns; sl++) st->theta_o[sl] = ps->theta_o[sl * rx], st->slice_flags[sl] = ps->slice_flags[sl * rx];
    double *f = calloc((size_t)m, sizeof *f);
    unsigned char *keep = calloc((size_t)m, 1);
    /* With bands, the choice is made on their sum: a direction bright in any band counts. */
    const int nbands = lsqt_state_bands(ps);
    lsqt_slice_est **est = calloc((size_t)nbands, sizeof *est);
    int rc = 1, have_est = est != NULL;
    for (int b = 0; have_est && b < nbands; b++) {
        const lsqt_state view = lsqt_state_band(ps, b);
        have_est = (est[b] = lsqt_estimates(&view)) != NULL;
    }
    if (!f || !keep || !have_est || lsqt_state_set_ranges(st, ps->ranges, ps->n_ranges)) {
        snprintf(err, errcap, "out of memory");
        goto done;
    }
    st->pilot_paths = st->paths;
    if (st->span_end < st->paths) st->span_end = st->paths;
    const size_t B = LSQT_BATCHES;
    const double t_sel = lsqt_now();
    for (int sl = 0; sl < ns; sl++) {
        const float *cand = ps->wi + (size_t)sl * m * 4; /* the blocks of slice sl, in order */
        for (int c = 0; c < m; c++) {
            f[c] = 0.0;
            for (int b = 0; b < nbands; b++) f[c] += est[b][sl * rx + c / n].f[c % n].mean;
        }
        int fb = lsqt_rrss_select(cand, f, m, n, st->transmits, keep);
        if (fb < 0) {
            snprintf(err, errcap, "out of memory");
            goto done;
        }
        info->density_fallback += fb;
        /* the kept candidates, in candidate order, with their pilot tallies */
        int k = 0;
        for (int c = 0; c < m; c++) {
            if (!keep[c]) continue;
            const int v = sl * rx + c / n, kk = c % n;
            memcpy(st->wi + ((size_t)sl * n + (size_t)k) * 4, cand + (size_t)c * 4, 16);
            for (int band = 0; band < nbands; band++) {
                const lsqt_state to = lsqt_state_band(st, band), from = lsqt_state_band(ps, band);
                for (size_t b = 0; b < B; b++)
                    lsqt_tallies_copy(to.nee + ((size_t)sl * B + b) * (size_t)n + (size_t)k,
                                      from.nee + ((size_t)v * B + b) * (size_t)n + (size_t)kk, 1);
            }
            k++;
        }
        /* the paths are those of every block: their scalars and histogram are block 0's */
        for (int band = 0; band < nbands; band++) {
            const lsqt_state to = lsqt_state_band(st, band), from = lsqt_state_band(ps, band);
            lsqt_tallies_copy(to.scalars + (size_t)sl * B * LSQT_T_COUNT, from.scalars + (size_t)sl * rx * B * LSQT_T_COUNT,
                              B * LSQT_T_COUNT);
        }
        if (lsqt_state_copy_hist(st, sl, ps, sl * rx)) {
            snprintf(err, errcap, "out of memory");
            goto done;
        }
        for (int band = 0; used && band < nbands; band++) {
            const lsqt_state from = lsqt_state_band(used, band);
            const size_t v0 = (size_t)sl * rx, nv = (size_t)rx;
            lsqt_tallies_drop(from.nee + v0 * B * n, nv * B * n);
            lsqt_tallies_drop(from.scalars + v0 * B * LSQT_T_COUNT, nv * B * LSQT_T_COUNT);
        }
        if (used) lsqt_state_drop_hist(used, sl * rx, (sl + 1) * rx);
    }
    info->select_seconds = lsqt_now() - t_sel;
    rc = 0;
done:
    for (int b = 0; est && b < nbands; b++) lsqt_estimates_free(est[b], ps->n_slices);
    free(est);
    free(f);
    free(keep);
    if (rc) lsqt_state_free(st);
    return rc;
}

int lsqt_rrss_choose(const lsqt_state *ps, lsqt_state *st, lsqt_rrss_info *info, char *err, size_t errcap)
{
    return choose(ps, NULL, st, info, err, errcap);
}

int lsqt_rrss_choose_using(lsqt_state *ps, lsqt_state *st, lsqt_rrss_info *info, char *err, size_t errcap)
{
    return choose(ps, ps, st, info, err, errcap);
}

int lsqt_rrss(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, int rx, uint64_t pilot_paths,
              const lsqt_sim_opts *o, lsqt_rrss_info *info, char *err, size_t errcap)
{
    lsqt_state ps, chosen;
    lsqt_sim_opts po = *o;
    po.checkpoint = NULL; /* the pilot state is not ST */
    if (lsqt_rrss_pilot(cx, a, st, rx, pilot_paths, pilot_paths, 0, pilot_paths, &po, &ps, info, err, errcap)) return 1;
    const lsqt_rrss_info pilot_info = *info;
    int rc = lsqt_rrss_choose_using(&ps, &chosen, info, err, errcap);
    lsqt_state_free(&ps);
    if (rc) return 1;
    info->short_slices = pilot_info.short_slices;
    info->interrupted = pilot_info.interrupted;
    if (o->verbose)
        fprintf(stderr, "RRSS: candidates and pilot %.3g s, selection %.3g s\n", info->seconds, info->select_seconds);
    info->seconds += info->select_seconds;
    lsqt_state_free(st);
    *st = chosen;
    return 0;
}

void lsqt_rrss_notes(FILE *f, const lsqt_rrss_info *info)
{
    if (info->short_slices)
        fprintf(f, "note: RRSS: in %d slice%s the walks left too few directions to choose from "
                   "(a BSDF that is zero almost everywhere); the even spread filled the rest\n",
                info->short_slices, info->short_slices > 1 ? "s" : "");
    if (info->density_fallback)
        fprintf(f, "note: RRSS: in %d slice%s the pilot's BSDF integral was not usable; directions "
                   "follow the walks' exit density there\n",
                info->density_fallback, info->density_fallback > 1 ? "s" : "");
}
