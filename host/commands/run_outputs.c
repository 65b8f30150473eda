/* The files a run writes (run_cmd.h's outputs): their names, the files the run reads that
 * they must not replace, and the locks; lsqt/outputs.h expands them band by band, checks
 * and writes them. */
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
        o->f.path[LSQT_OUT_RAW_BT] = o->raw_bt;
    } else {
        snprintf(o->raw_b, sizeof o->raw_b, "%s", rb);
    }
    o->f.path[LSQT_OUT_RAW_B] = o->raw_b;
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
        o->f.path[LSQT_OUT_RAW] = o->raw;
        if (transmits) {
            lsqt_raw_hemi_name(raw, "T", o->raw_t, sizeof o->raw_t);
            o->f.path[LSQT_OUT_RAW_T] = o->raw_t;
        }
    } else {
        snprintf(o->raw, sizeof o->raw, "%s", raw);
        o->f.path[LSQT_OUT_RAW] = o->raw;
    }
    return 0;
}

/* The LSS (--lss, or the input's name with .lss; none for stdin), the JSON, and a
 * shard's own LSS. Returns 0 or 2. */
static int state_names(const lsqt_cli *c, int from_stdin, outputs *o, char *err, size_t errcap)
{
    if (c->lss) o->f.path[LSQT_OUT_LSS] = c->lss;
    else if (!from_stdin) {
        snprintf(o->lss, sizeof o->lss, "%s.lss", c->input);
        o->f.path[LSQT_OUT_LSS] = o->lss;
    }
    o->f.path[LSQT_OUT_JSON] = c->json;
    o->base = o->f.path[LSQT_OUT_LSS];
    if (c->shard_n) {
        /* a shard writes its part beside the state it continues; a RAW only when asked */
        if (!o->base || strcmp(o->base, "-") == 0) {
            snprintf(err, errcap, "--shard writes an LSS named from the run's LSS: give a file (--lss PATH)");
            return 2;
        }
        size_t n = strlen(o->base);
        if (n >= 4 && strcmp(o->base + n - 4, ".lss") == 0) n -= 4;
        snprintf(o->shard, sizeof o->shard, "%.*s.shard-%d-of-%d.lss", (int)n, o->base, c->shard_k, c->shard_n);
        o->f.path[LSQT_OUT_LSS] = o->shard;
        if (!c->output) o->f.path[LSQT_OUT_RAW] = o->f.path[LSQT_OUT_RAW_T] = o->f.path[LSQT_OUT_RAW_B] = o->f.path[LSQT_OUT_RAW_BT] = NULL;
    }
    return 0;
}

void run_outputs_free(outputs *o) { lsqt_outputs_free(&o->f); }

/* The plan for a state that transmits or not, with slices from below or not. */
static int plan_outputs(const lsqt_cli *c, int from_stdin, const lsqt_assembly *a, int transmits, int below,
                        outputs *o, char *err, size_t errcap)
{
    memset(o, 0, sizeof *o);
    o->f.n_bands = lsqt_assembly_bands(a), o->f.wl = a->wavelengths, o->f.hemi = c->only_hemispherical;
    if (c->no_raw && (c->output || c->only_hemispherical)) {
        snprintf(err, errcap, "--no-raw writes no RAW file, and %s names one", c->output ? "-o" : "-H");
        return 2;
    }
    char raw[LSQT_PATH_CAP + 16];
    raw_name(c, from_stdin, raw, sizeof raw);
    if (!c->no_raw && below && below_names(c, raw, o, err, errcap)) return 2;
    if (!c->no_raw && raw_names(c, raw, transmits, o, err, errcap)) return 2;
    if (state_names(c, from_stdin, o, err, errcap)) return 2;
    if (c->no_raw && !o->f.path[LSQT_OUT_LSS] && !o->f.path[LSQT_OUT_JSON]) {
        snprintf(err, errcap, "--no-raw: this run would write nothing (its input is stdin, so it has no LSS of "
                              "its own): give --lss PATH or --json PATH");
        return 2;
    }
    /* the files the run reads, which no output may replace */
    const lsqt_assembly *a0 = lsqt_assembly_band(a, 0); /* its phase tables are every band's */
    lsqt_input_file *in = calloc((size_t)a->n_tables + (size_t)a0->n_phase_tables + 3, sizeof *in);
    if (!in) {
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    int n_in = 0;
    if (!from_stdin) in[n_in++] = (lsqt_input_file){c->input, "the input"};
    if (c->wi_file) in[n_in++] = (lsqt_input_file){c->wi_file, "the --wi-file"};
    if (o->base && o->base != o->f.path[LSQT_OUT_LSS]) in[n_in++] = (lsqt_input_file){o->base, "the state this shard continues"};
    for (int t = 0; t < a->n_tables; t++) in[n_in++] = (lsqt_input_file){a->tables[t], "the table"};
    for (int t = 0; t < a0->n_phase_tables; t++)
        if (a0->phase_tables[t].path) in[n_in++] = (lsqt_input_file){a0->phase_tables[t].path, "the phase table"};
    int rc = lsqt_outputs_plan(&o->f, in, n_in,
                               ", or --no-raw to write no RAW (the LSS, --json and lsqt-cl export hold every band)", err,
                               errcap);
    free(in);
    return rc;
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
    const char *paths[2] = {o->f.path[LSQT_OUT_LSS], o->base != o->f.path[LSQT_OUT_LSS] ? o->base : NULL};
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

int run_write_outputs(const outputs *o, const lsqt_cli *c, const lsqt_state *st, const lsqt_state *lss_st,
                      const lsqt_slice_est *est, const lsqt_run_info *ri, FILE *info)
{
    int rc = lsqt_outputs_write(&o->f, st, lss_st, est, ri, "lsqt-cl", NULL, c->quiet, info);
    if (!c->quiet && c->only_hemispherical && !o->f.path[LSQT_OUT_RAW_T])
        fprintf(info, "note: the stack transmits nothing, so -H wrote no T file\n");
    return rc;
}

int run_plan_outputs(const lsqt_cli *c, int from_stdin, const lsqt_assembly *a, const lsqt_state *st, int continued,
                     outputs *o, char *err, size_t errcap)
{
    if (!st) return plan_outputs(c, from_stdin, a, lsqt_assembly_transmits(a), 0, o, err, errcap);
    const int below = lsqt_state_below_count(st) > 0;
    if (!c->quiet && c->from_below && !lsqt_assembly_transmits(a))
        fprintf(stderr, "note: --from-below: the stack transmits nothing, so no light from below reaches it; "
                        "only the slices from above are simulated\n");
    else if (!c->quiet && continued && below && !c->from_below) /* the other case is refused */
        fprintf(stderr, "note: the LSS has slices from below: both sides are continued\n");
    if (!below) return 0; /* the plan made without the state stands */
    run_outputs_free(o);
    return plan_outputs(c, from_stdin, a, st->transmits, 1, o, err, errcap);
}
