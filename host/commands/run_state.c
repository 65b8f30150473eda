/* The state of an lsqt-cl run: a fresh one (slices and directions from the flags), or
 * the LSS it continues, read and checked against the assembly and the flags. */
#include "run_cmd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/below.h"
#include "lsqt/directions.h"
#include "lsqt/lss.h"

/* A fresh state: slices, incident directions and zero tallies. The directions are the
 * --wi-file ones (wi_file, n_wi_file of them) when given, else the -wi spread; every
 * slice gets the same (its wo is at azimuth 0, so phi is measured from it in each). */
int run_new_state(lsqt_state *st, const lsqt_cli *c, const lsqt_assembly *a, const char *canonical,
                  const float *wi_file, int n_wi_file)
{
    const int grid = c->grid_no > 0, lower = lsqt_assembly_transmits(a);
    int n_slices = grid ? c->grid_no : c->n_wo_angles ? c->n_wo_angles : c->wo_count;
    int n_wi = c->grid_rgl ? lsqt_rgl_wi_count(c->grid_ni)
             : grid        ? lsqt_grid_wi_count(c->grid_ni, c->grid_nphi, lower)
             : wi_file     ? n_wi_file
                           : c->wi_count;
    if (lsqt_state_init(st, canonical, lsqt_assembly_hash(a), c->seed, n_slices, n_wi, lower,
                              lsqt_assembly_bands(a), a->wavelengths))
        return -1;
    st->use_double = c->use_double;
    if (c->grid_rgl) lsqt_rgl_theta_o(n_slices, st->theta_o);
    else if (grid) lsqt_grid_theta_o(n_slices, st->theta_o);
    else if (c->n_wo_angles) memcpy(st->theta_o, c->wo_angles, (size_t)n_slices * sizeof(double));
    else lsqt_wo_angles(n_slices, st->theta_o);
    /* RRSS directions are chosen once the device is ready (host/sim/stages.c); the spread stands
     * in until then. */
    st->dir_method = c->grid_rgl ? LSQT_DIRS_RGL : grid ? LSQT_DIRS_GRID : wi_file ? LSQT_DIRS_FILE : c->wi_spread ? LSQT_DIRS_SPREAD : LSQT_DIRS_RRSS;
    if (grid) st->grid_ni = (uint32_t)c->grid_ni, st->grid_nphi = (uint32_t)c->grid_nphi;
    for (int s = 0; s < n_slices; s++) {
        float *dst = st->wi + (size_t)s * (size_t)st->n_wi * 4;
        if (c->grid_rgl) lsqt_rgl_wi(st->theta_o[s], c->grid_ni, dst);
        else if (grid) lsqt_grid_wi(c->grid_ni, c->grid_nphi, lower, dst);
        else if (wi_file) memcpy(dst, wi_file, (size_t)st->n_wi * 4 * sizeof *dst);
        else lsqt_wi_spread(st->n_wi, st->transmits, dst);
    }
    /* --from-below: the same slices again, of light entering from below (below.h) */
    if (c->from_below && st->transmits && lsqt_state_add_below(st)) {
        lsqt_state_free(st);
        return -1;
    }
    return 0;
}

static const char *dirs_name(uint32_t m)
{
    return m == LSQT_DIRS_RRSS ? "RRSS" : m == LSQT_DIRS_FILE ? "--wi-file" : m == LSQT_DIRS_GRID ? "--grid"
         : m == LSQT_DIRS_RGL  ? "--rgl-grid" : "--wi-spread";
}

/* A contradiction between a flag and the LSS continued: the flag as given, and why. */
typedef struct conflict {
    char flag[64], why[512];
} conflict;

/* The outgoing angles: the distinct theta_o of the slices from above. */
static int outgoing_angles(const lsqt_state *st, double th[LSQT_MAX_WO])
{
    int n_th = 0;
    for (int s = 0; s < st->n_slices; s++) {
        if (st->slice_flags[s] & LSQT_SLICE_BELOW) continue;
        int seen = 0;
        for (int j = 0; j < n_th && !seen; j++) seen = th[j] == st->theta_o[s];
        if (!seen && n_th < LSQT_MAX_WO) th[n_th++] = st->theta_o[s];
    }
    return n_th;
}

/* -s, -wi, -wo, --wo-angles: the first that contradicts the LSS. */
static void counts_conflict(const lsqt_cli *c, const lsqt_state *st, const double *th, int n_th, conflict *k)
{
    if (c->seed_given && c->seed != st->seed) {
        snprintf(k->flag, sizeof k->flag, "-s %llu", (unsigned long long)c->seed);
        snprintf(k->why, sizeof k->why, "its paths were drawn with -s %llu", (unsigned long long)st->seed);
    } else if (c->wi_given && c->wi_count != st->n_wi) {
        snprintf(k->flag, sizeof k->flag, "-wi %d", c->wi_count);
        snprintf(k->why, sizeof k->why, "it holds %d incident directions per slice", st->n_wi);
    } else if (c->wo_given && c->wo_count != n_th) {
        snprintf(k->flag, sizeof k->flag, "-wo %d", c->wo_count);
        snprintf(k->why, sizeof k->why, "it holds %d outgoing directions", n_th);
    } else if (c->n_wo_angles) {
        int same = c->n_wo_angles == n_th;
        for (int i = 0; i < c->n_wo_angles && same; i++) {
            int found = 0;
            for (int j = 0; j < n_th && !found; j++) found = fabs(c->wo_angles[i] - th[j]) < 1e-9;
            same = found;
        }
        if (!same) {
            snprintf(k->flag, sizeof k->flag, "--wo-angles");
            snprintf(k->why, sizeof k->why, "its %d outgoing angles are others", n_th);
        }
    }
}

/* --grid, --rgl-grid: another grid, or none in the LSS. */
static void grid_conflict(const lsqt_cli *c, const lsqt_state *st, int n_th, conflict *k)
{
    const uint32_t want_method = c->grid_rgl ? LSQT_DIRS_RGL : LSQT_DIRS_GRID;
    if (!k->flag[0] && c->grid_no &&
        (st->dir_method != want_method || (uint32_t)c->grid_ni != st->grid_ni ||
         (uint32_t)c->grid_nphi != st->grid_nphi || c->grid_no != n_th)) {
        if (c->grid_rgl) snprintf(k->flag, sizeof k->flag, "--rgl-grid %d,%d", c->grid_no, c->grid_ni);
        else snprintf(k->flag, sizeof k->flag, "--grid %d,%d,%d", c->grid_no, c->grid_ni, c->grid_nphi);
        if (st->dir_method == LSQT_DIRS_GRID)
            snprintf(k->why, sizeof k->why, "it is on the grid %d,%u,%u", n_th, st->grid_ni, st->grid_nphi);
        else if (st->dir_method == LSQT_DIRS_RGL)
            snprintf(k->why, sizeof k->why, "it is on the RGL grid %d,%u", n_th, st->grid_ni);
        else snprintf(k->why, sizeof k->why, "its incident directions were chosen by %s", dirs_name(st->dir_method));
    }
}

/* How the directions were chosen, --wi-file's count, -rx, --from-below, --double. */
static void method_conflict(const lsqt_cli *c, const lsqt_state *st, int n_wi_file, conflict *k)
{
    if (!k->flag[0] && ((c->wi_spread && st->dir_method != LSQT_DIRS_SPREAD) ||
                        (c->wi_file && st->dir_method != LSQT_DIRS_FILE) ||
                        ((c->rx_given || c->rp_given) && st->dir_method != LSQT_DIRS_RRSS))) {
        snprintf(k->flag, sizeof k->flag, "%s",
                 c->wi_spread ? "--wi-spread" : c->wi_file ? "--wi-file" : c->rx_given ? "-rx" : "-rp");
        snprintf(k->why, sizeof k->why, "its incident directions were chosen by %s", dirs_name(st->dir_method));
    }
    if (!k->flag[0] && c->wi_file && n_wi_file != st->n_wi) {
        snprintf(k->flag, sizeof k->flag, "--wi-file %.40s", c->wi_file);
        snprintf(k->why, sizeof k->why, "it holds %d incident directions per slice, the file %d", st->n_wi,
                 n_wi_file);
    }
    if (!k->flag[0] && c->rx_given && (uint32_t)c->rx != st->rx) {
        snprintf(k->flag, sizeof k->flag, "-rx %d", c->rx);
        snprintf(k->why, sizeof k->why, "its RRSS pilot drew -rx %u candidates per direction", st->rx);
    }
    if (!k->flag[0] && c->from_below && lsqt_state_below_count(st) == 0 && st->transmits) {
        snprintf(k->flag, sizeof k->flag, "--from-below");
        snprintf(k->why, sizeof k->why, "it has no slices from below");
    }
    if (!k->flag[0] && c->use_double && !st->use_double) {
        snprintf(k->flag, sizeof k->flag, "--double");
        snprintf(k->why, sizeof k->why, "it is a float state");
    }
}

/* A continued run keeps its LSS's sampling. A sampling flag with the LSS's own value is
 * fine; one that contradicts the LSS is an error (exit 2: the user meant another run, and
 * -R starts one); -rp names what the LSS keeps. Returns 0, or 2 with err filled. */
static int check_continuation(const lsqt_cli *c, const lsqt_state *st, const char *lss, int n_wi_file, char *err,
                              size_t errcap)
{
    conflict k = {"", ""};
    double th[LSQT_MAX_WO];
    const int n_th = outgoing_angles(st, th);
    counts_conflict(c, st, th, n_th, &k);
    grid_conflict(c, st, n_th, &k);
    method_conflict(c, st, n_wi_file, &k);
    if (k.flag[0]) {
        snprintf(err, errcap, "%s contradicts '%s' (%s): a continued run keeps what its LSS was made with; drop "
                 "%s, or start over with -R", k.flag, lss, k.why, k.flag);
        return 2;
    }
    if (!c->quiet && c->rp_given)
        fprintf(stderr, "note: -rp %g is not used: '%s' keeps its RRSS pilot (%llu paths per slice)\n", c->rp, lss,
                (unsigned long long)st->pilot_paths);
    if (!c->quiet && c->wi_file)
        fprintf(stderr, "note: --wi-file: '%s' keeps the %d directions it was started with\n", lss, st->n_wi);
    return 0;
}

/* n bands (wl: their wavelengths or NULL) in words: "3 bands at 450 to 650 nm". */
static void bands_words(int n, const double *wl, char *buf, size_t cap)
{
    if (wl && n > 1) snprintf(buf, cap, "%d bands at %.10g to %.10g nm", n, wl[0], wl[n - 1]);
    else if (wl) snprintf(buf, cap, "one band at %.10g nm", wl[0]);
    else if (n > 1) snprintf(buf, cap, "%d bands without wavelengths (lists)", n);
    else snprintf(buf, cap, "one band without a wavelength");
}

/* How the LSS's bands differ from the run's, into buf ("" when they agree), and what to
 * do: a state of its own, or -R, which discards the LSS's. */
static void bands_differ(const lsqt_state *st, const lsqt_assembly *a, const char *lss_path, char *buf, size_t cap)
{
    const int nb = lsqt_assembly_bands(a);
    char was[128], now[128], first[160] = "";
    bands_words(st->n_bands, st->wavelengths, was, sizeof was);
    bands_words(nb, a->wavelengths, now, sizeof now);
    int same = st->n_bands == nb && (st->wavelengths != NULL) == (a->wavelengths != NULL);
    if (st->wavelengths && a->wavelengths) { /* the first band whose wavelength differs */
        const int n = st->n_bands < nb ? st->n_bands : nb;
        for (int b = 0; b < n; b++)
            if (st->wavelengths[b] != a->wavelengths[b]) {
                snprintf(first, sizeof first, " (band %d: %.10g nm there, %.10g nm here)", b + 1, st->wavelengths[b],
                         a->wavelengths[b]);
                same = 0;
                break;
            }
    }
    int at = same ? snprintf(buf, cap, ": its layers or values differ")
                  : snprintf(buf, cap, ": it holds %s, this run has %s%s", was, now, first);
    if (at < 0 || (size_t)at >= cap) return;
    snprintf(buf + at, cap - (size_t)at, "; to keep it, give this run a state of its own (--lss OTHER.lss); -R "
             "would discard the state of %s in '%s' and start over", was, lss_path);
}

/* The LSS at lss_path, read and checked: it must be whole, of this assembly, and agree
 * with the flags. Returns 0, or an exit status (printed; st freed). */
static int continue_lss(lsqt_state *st, const lsqt_cli *c, const lsqt_assembly *a, const char *canonical,
                        const char *lss_path, int n_wi_dirs)
{
    char err[LSQT_PATH_CAP + 1024];
    int rc = 0;
    if (lsqt_lss_read(lss_path, st, err, sizeof err)) {
        rc = fail(2, "%s (use -R to start over and replace it)%s", err, "");
    } else if (st->hash != lsqt_assembly_hash(a) || strcmp(st->canonical, canonical) != 0) {
        bands_differ(st, a, lss_path, err, sizeof err);
        lsqt_state_free(st);
        rc = fail(2, "'%s' was made for a different assembly%s", lss_path, err);
    } else if ((st->wavelengths != NULL) != (a->wavelengths != NULL) ||
               (st->wavelengths && st->n_bands == lsqt_assembly_bands(a) &&
                memcmp(st->wavelengths, a->wavelengths, (size_t)st->n_bands * sizeof *st->wavelengths))) {
        /* one band's wavelength is not in the assembly's text (bands' are) */
        bands_differ(st, a, lss_path, err, sizeof err);
        lsqt_state_free(st);
        rc = fail(2, "'%s' was made for other wavelengths%s", lss_path, err);
    } else if (st->stage == LSQT_STAGE_PILOT && lsqt_state_contiguous(st) == UINT64_MAX) {
        lsqt_state_free(st);
        rc = fail(2, "'%s' is one shard of an RRSS pilot: merge all of the pilot's shards first "
                     "(lsqt-cl merge OUT.lss SHARDS...)%s", lss_path, "");
    } else if (lsqt_state_contiguous(st) == UINT64_MAX) {
        lsqt_state_free(st);
        rc = fail(2, "'%s' holds paths with gaps between them (a partial merge): merge the missing shards "
                     "into it first (see lsqt-cl info)%s", lss_path, "");
    } else if (check_continuation(c, st, lss_path, n_wi_dirs, err, sizeof err)) {
        lsqt_state_free(st);
        rc = fail(2, "%s%s", err, "");
    } else if (!c->quiet) {
        fprintf(stderr, "continuing %s (%llu paths per slice so far)\n", lss_path, (unsigned long long)st->paths);
        if (st->use_double != c->use_double)
            fprintf(stderr, "note: precision follows the LSS (%s)\n", st->use_double ? "double" : "float");
    }
    return rc;
}

/* State: continue the LSS when there is one, else start fresh. Only a regular file is
 * ever read as an LSS: a FIFO would block and a device holds no state. */
int run_open_state(lsqt_state *st, const lsqt_cli *c, const lsqt_assembly *a, const char *lss_path,
                   const float *wi_dirs, int n_wi_dirs, int n_mirrored, int *continued)
{
    size_t clen = lsqt_assembly_canonical(a, NULL, 0);
    char *canonical = malloc(clen + 1);
    if (!canonical) return fail(1, "out of memory%s%s", "", "");
    lsqt_assembly_canonical(a, canonical, clen + 1);
    int rc = 0;
    const char *what = NULL;
    int lss_type = lss_path && !c->restart && strcmp(lss_path, "-") != 0 ? lsqt_path_type(lss_path, &what)
                                                                         : LSQT_PATH_MISSING;
    *continued = lss_type == LSQT_PATH_REGULAR;
    if (lss_type == LSQT_PATH_SPECIAL) {
        rc = fail(2, "cannot continue from '%s': it is a %s, not an LSS file (add -R to write a fresh state into it)",
                  lss_path, what);
    } else if (lss_type == LSQT_PATH_REGULAR) {
        rc = continue_lss(st, c, a, canonical, lss_path, n_wi_dirs);
    } else if (run_new_state(st, c, a, canonical, wi_dirs, n_wi_dirs)) {
        rc = fail(1, "out of memory%s%s", "", "");
    } else if (n_mirrored && !c->quiet) {
        fprintf(stderr, "note: %d direction%s of %s with y < 0 %s simulated at (x, -y, z) (the BSDF is symmetric "
                        "about the plane of wo); the RAW holds both mirror images\n",
                n_mirrored, n_mirrored > 1 ? "s" : "", c->wi_file, n_mirrored > 1 ? "are" : "is");
    }
    free(canonical);
    return rc;
}
