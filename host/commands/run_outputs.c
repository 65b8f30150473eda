/* The files a run writes (run_cmd.h's outputs): their names, checked against each other
 * and the input, their locks, and the writing of each, LSS first. */
#include "run_cmd.h"

#include <stdlib.h>
#include <string.h>

#include "lsqt/bands.h"
#include "lsqt/colour.h"
#include "lsqt/below.h"
#include "lsqt/lss.h"
#include "lsqt/raw.h"

/* The RAW name: -o, or the input's name with .raw (Layered.raw for stdin). */
static void raw_name(const lsqt_cli *c, int from_stdin, char *raw, size_t cap)
{
    if (c->output) snprintf(raw, cap, "%s", c->output);
    else if (from_stdin) snprintf(raw, cap, "Layered.raw");
    else snprintf(raw, cap, "%s.raw", c->input);
}

/* The RAW files of the side from below, named from the RAW name. Returns 0 or 2. */
static int below_names(const lsqt_cli *c, const char *raw, outputs *o, char *err, size_t errcap)
{
    const char *what = NULL;
    int t = strcmp(raw, "-") == 0 ? LSQT_PATH_SPECIAL : lsqt_path_type(raw, &what);
    if (t == LSQT_PATH_SPECIAL || t == LSQT_PATH_DIRECTORY) {
        snprintf(err, errcap, "the slices from below go to a second RAW named from the RAW name, and '%s' is "
                 "%s%s: give -o a file name", raw, what ? "a " : "stdout", what ? what : "");
        return 2;
    }
    char rb[LSQT_PATH_CAP + 32];
    lsqt_below_raw_name(raw, rb, sizeof rb);
    if (c->only_hemispherical) {
        lsqt_raw_hemi_name(rb, "R", o->raw_b, sizeof o->raw_b);
        lsqt_raw_hemi_name(rb, "T", o->raw_bt, sizeof o->raw_bt);
        o->path[OUT_RAW_BT] = o->raw_bt;
    } else {
        snprintf(o->raw_b, sizeof o->raw_b, "%s", rb);
    }
    o->path[OUT_RAW_B] = o->raw_b;
    return 0;
}

/* The RAW file, or with -H the R and T files named from it. Returns 0 or 2. */
static int raw_names(const lsqt_cli *c, const char *raw, int transmits, outputs *o, char *err, size_t errcap)
{
    if (c->only_hemispherical) {
        const char *what = NULL;
        int t = strcmp(raw, "-") == 0 ? LSQT_PATH_SPECIAL : lsqt_path_type(raw, &what);
        if (t == LSQT_PATH_SPECIAL || t == LSQT_PATH_DIRECTORY) {
            snprintf(err, errcap, "-H writes two files named from the RAW name, and '%s' is %s%s", raw,
                     what ? "a " : "stdout", what ? what : "");
            return 2;
        }
        lsqt_raw_hemi_name(raw, "R", o->raw, sizeof o->raw);
        o->path[OUT_RAW] = o->raw;
        if (transmits) {
            lsqt_raw_hemi_name(raw, "T", o->raw_t, sizeof o->raw_t);
            o->path[OUT_RAW_T] = o->raw_t;
        }
    } else {
        snprintf(o->raw, sizeof o->raw, "%s", raw);
        o->path[OUT_RAW] = o->raw;
    }
    return 0;
}

/* The LSS (--lss, or the input's name with .lss; none for stdin), the JSON, and a
 * shard's own LSS. Returns 0 or 2. */
static int state_names(const lsqt_cli *c, int from_stdin, outputs *o, char *err, size_t errcap)
{
    if (c->lss) o->path[OUT_LSS] = c->lss;
    else if (!from_stdin) {
        snprintf(o->lss, sizeof o->lss, "%s.lss", c->input);
        o->path[OUT_LSS] = o->lss;
    }
    o->path[OUT_JSON] = c->json;
    o->base = o->path[OUT_LSS];
    if (c->shard_n) {
        /* a shard writes its part beside the state it continues; a RAW only when asked */
        if (!o->base || strcmp(o->base, "-") == 0) {
            snprintf(err, errcap, "--shard writes an LSS named from the run's LSS: give a file (--lss PATH)");
            return 2;
        }
        size_t n = strlen(o->base);
        if (n >= 4 && strcmp(o->base + n - 4, ".lss") == 0) n -= 4;
        snprintf(o->shard, sizeof o->shard, "%.*s.shard-%d-of-%d.lss", (int)n, o->base, c->shard_k, c->shard_n);
        o->path[OUT_LSS] = o->shard;
        if (!c->output) o->path[OUT_RAW] = o->path[OUT_RAW_T] = o->path[OUT_RAW_B] = o->path[OUT_RAW_BT] = NULL;
    }
    return 0;
}

/* No output may land on another one, on stdout twice, or on the input. Returns 0 or 2. */
static int check_clashes(const lsqt_cli *c, int from_stdin, const outputs *o, char *err, size_t errcap)
{
    for (int i = 0; i < OUT_COUNT; i++) {
        if (!o->path[i]) continue;
        for (int j = i + 1; j < OUT_COUNT; j++)
            if (o->path[j] && lsqt_same_file(o->path[i], o->path[j])) {
                snprintf(err, errcap, "two outputs would be written to '%s'%s", o->path[i],
                         strcmp(o->path[i], "-") == 0 ? " (stdout)" : "");
                return 2;
            }
        if (!from_stdin && strcmp(o->path[i], "-") != 0 && lsqt_same_file(o->path[i], c->input)) {
            snprintf(err, errcap, "the output '%s' would replace the input", o->path[i]);
            return 2;
        }
    }
    return 0;
}

int run_plan_outputs(const lsqt_cli *c, int from_stdin, int transmits, int below, outputs *o, char *err,
                     size_t errcap)
{
    memset(o, 0, sizeof *o);
    char raw[LSQT_PATH_CAP + 16];
    raw_name(c, from_stdin, raw, sizeof raw);
    if (below && below_names(c, raw, o, err, errcap)) return 2;
    if (raw_names(c, raw, transmits, o, err, errcap) || state_names(c, from_stdin, o, err, errcap)) return 2;
    return check_clashes(c, from_stdin, o, err, errcap);
}

/* The state files this run owns (lsqt_lock_take), released at exit. */
static lsqt_lock g_locks[2] = {{-1, 0, ""}, {-1, 0, ""}};
static void release_locks(void)
{
    for (int i = 0; i < 2; i++) lsqt_lock_release(&g_locks[i]);
}

int run_lock_states(const outputs *o, int quiet)
{
    char err[3 * LSQT_PATH_CAP];
    atexit(release_locks);
    const char *paths[2] = {o->path[OUT_LSS], o->base != o->path[OUT_LSS] ? o->base : NULL};
    for (int i = 0; i < 2; i++) {
        if (!paths[i]) continue;
        /* -1 (no lock file can be made there): the output checks say why the place cannot
         * be written, before any work. */
        int r = lsqt_lock_take(&g_locks[i], paths[i], i == 0, err, sizeof err);
        if (r == 2 && !quiet) fprintf(stderr, "warning: %s\n", err);
        else if (r == 1) return fail(1, "%s%s", err, ", or give this run another state file (--lss PATH)");
    }
    return 0;
}

/* "X.raw" or, with bands, "X.{450nm,...,650nm}.raw" */
static void raw_shown(const lsqt_state *st, const char *path, char *buf, size_t cap)
{
    if (st->n_bands <= 1) {
        snprintf(buf, cap, "%s", path);
        return;
    }
    char l0[48], l1[48], braces[128];
    lsqt_band_label_one(st->n_bands, st->wavelengths, 0, l0, sizeof l0);
    lsqt_band_label_one(st->n_bands, st->wavelengths, st->n_bands - 1, l1, sizeof l1);
    snprintf(braces, sizeof braces, "{%s,%s%s}", l0, st->n_bands > 2 ? "...," : "", l1);
    lsqt_band_path(path, braces, buf, cap);
}

int run_write_outputs(const outputs *o, const lsqt_cli *c, const lsqt_state *st, const lsqt_state *lss_st,
                      const lsqt_slice_est *est, const lsqt_run_info *ri, FILE *info)
{
    char err[LSQT_PATH_CAP + 512];
    int failed = 0, wrote = 0, skipped = 0, sk = 0;
    char done[OUT_COUNT * (LSQT_PATH_CAP + 164)];
    int written[OUT_COUNT] = {0};
    done[0] = '\0';
    /* RAW files hold one side each: the main one exactly what it is without --from-below */
    lsqt_state sides[2];
    lsqt_slice_est *side_est[2] = {NULL, NULL};
    const int two = lsqt_state_below_count(st) > 0;
    memset(sides, 0, sizeof sides);
    int split_failed = two && (lsqt_state_split_sides(st, &sides[0], &sides[1]) ||
                               !(side_est[0] = lsqt_estimates(&sides[0])) || !(side_est[1] = lsqt_estimates(&sides[1])));
    if (split_failed) fail(1, "out of memory%s%s", "", ""), failed++;
    /* The LSS first: it is what a later run continues, so a RAW that cannot be written
     * (a FIFO nobody reads, a full disk) or a kill during the RAW loses no paths. */
    static const int order[OUT_COUNT] = {OUT_LSS, OUT_RAW, OUT_RAW_T, OUT_RAW_B, OUT_RAW_BT, OUT_JSON};
    for (int j = 0; j < OUT_COUNT && !split_failed; j++) {
        const int i = order[j];
        const char *p = o->path[i];
        if (!p) continue;
        const int b = i == OUT_RAW_B || i == OUT_RAW_BT;
        const lsqt_state *rs = two ? &sides[b] : st;
        const lsqt_slice_est *re = two ? side_est[b] : est;
        int rc = i == OUT_LSS    ? lsqt_lss_write(p, lss_st, err, sizeof err)
                 : i == OUT_JSON ? lsqt_report_json(p, st, est, ri, err, sizeof err)
                 : i == OUT_RAW_T || i == OUT_RAW_BT
                     ? lsqt_raw_write_bands(p, rs, re, LSQT_RAW_TRANSMIT, &sk, err, sizeof err)
                     : lsqt_raw_write_bands(p, rs, re, c->only_hemispherical ? LSQT_RAW_REFLECT : LSQT_RAW_ALL,
                                     &skipped, err, sizeof err);
        if (rc) {
            fail(1, "%s%s", err, "");
            failed++;
            continue;
        }
        written[i] = strcmp(p, "-") != 0;
    }
    for (int i = 0; i < OUT_COUNT; i++) /* in the usual order: RAW files, LSS, JSON */
        if (written[i]) {
            char shown[LSQT_PATH_CAP + 160];
            if (i == OUT_LSS || i == OUT_JSON) snprintf(shown, sizeof shown, "%s", o->path[i]);
            else raw_shown(st, o->path[i], shown, sizeof shown);
            size_t n = strlen(done);
            snprintf(done + n, sizeof done - n, "%s%s", wrote++ ? ", " : "", shown);
        }
    if (!c->quiet && wrote) fprintf(info, "wrote %s\n", done);
    if (!c->quiet && c->only_hemispherical && !o->path[OUT_RAW_T])
        fprintf(info, "note: the stack transmits nothing, so -H wrote no T file\n");
    if (failed) fprintf(stderr, "lsqt-cl: %d output%s could not be written (see above)\n", failed, failed > 1 ? "s" : "");
    for (int b = 0; b < 2; b++) {
        lsqt_estimates_free(side_est[b], sides[b].n_slices);
        lsqt_state_free(&sides[b]);
    }
    return failed ? 1 : 0;
}

int run_plan_sides(const lsqt_cli *c, int from_stdin, const lsqt_assembly *a, lsqt_state *st, int continued,
                   outputs *out, char *err, size_t errcap)
{
    const int below = lsqt_state_below_count(st) > 0;
    if (!c->quiet && c->from_below && !lsqt_assembly_transmits(a))
        fprintf(stderr, "note: --from-below: the stack transmits nothing, so no light from below reaches it; "
                        "only the slices from above are simulated\n");
    else if (!c->quiet && continued && below && !c->from_below) /* the other case is refused */
        fprintf(stderr, "note: the LSS has slices from below: both sides are continued\n");
    int rc = below ? run_plan_outputs(c, from_stdin, st->transmits, 1, out, err, errcap) : 0;
    if (rc) {
        lsqt_state_free(st);
        fail(rc, "%s%s", err, "");
    }
    return rc;
}
