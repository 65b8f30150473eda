/* The files a run writes (run_cmd.h's outputs): their names (with bands one RAW per band
 * and side), checked against each other and every file the run reads before any work,
 * their locks, and the writing: the LSS first, then the rest published together. */
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

/* With bands each RAW kind is one file per band, named from the RAW name: that name must
 * be a plain path then. Returns 0 or 2. */
static int band_base(const char *raw, int n_bands, const double *wl, char *err, size_t errcap)
{
    const char *what = NULL;
    int t = strcmp(raw, "-") == 0 ? LSQT_PATH_SPECIAL : lsqt_path_type(raw, &what);
    if (n_bands <= 1 || (t != LSQT_PATH_SPECIAL && t != LSQT_PATH_DIRECTORY)) return 0;
    char example[LSQT_PATH_CAP + 64], label[48];
    lsqt_band_path(strcmp(raw, "-") == 0 ? "OUT" : raw, lsqt_band_label_one(n_bands, wl, 0, label, sizeof label), example,
                   sizeof example);
    snprintf(err, errcap, "a run with %d bands writes one RAW per band, named from the RAW name (%s, ...), and '%s' is "
             "%s%s: give -o a file name, or --no-raw to write no RAW (the LSS, --json and lsqt-cl export hold "
             "every band)", n_bands, example, raw, what ? "a " : "stdout", what ? what : "");
    return 2;
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
        if (band_base(raw, o->n_bands, o->wl, err, errcap)) return 2;
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

static int is_raw(int kind) { return kind != OUT_LSS && kind != OUT_JSON; }

void run_outputs_free(outputs *o)
{
    for (int i = 0; i < o->n_files; i++) free(o->files[i].path);
    free(o->files);
    o->files = NULL, o->n_files = 0;
}

/* Every file of the run, in the order they are written: the LSS, each RAW kind band by
 * band, the JSON. Returns 0, or 1 out of memory. */
static int expand_files(outputs *o)
{
    static const int order[OUT_COUNT] = {OUT_LSS, OUT_RAW, OUT_RAW_T, OUT_RAW_B, OUT_RAW_BT, OUT_JSON};
    size_t n = 0;
    for (int i = 0; i < OUT_COUNT; i++)
        if (o->path[i]) n += is_raw(i) ? (size_t)o->n_bands : 1;
    o->files = calloc(n ? n : 1, sizeof *o->files);
    if (!o->files) return 1;
    lsqt_band_names names; /* --wavelengths has refused bands it cannot name apart */
    (void)lsqt_band_names_init(&names, o->n_bands, o->wl, NULL);
    for (int j = 0; j < OUT_COUNT; j++) {
        const int k = order[j];
        const int nb = is_raw(k) ? o->n_bands : 1;
        for (int b = 0; o->path[k] && b < nb; b++) {
            char label[48], name[LSQT_PATH_CAP + 96];
            if (nb > 1) lsqt_band_path(o->path[k], lsqt_band_label(&names, b, label, sizeof label), name, sizeof name);
            else snprintf(name, sizeof name, "%s", o->path[k]);
            out_file *f = &o->files[o->n_files];
            if (!(f->path = malloc(strlen(name) + 1))) return 1;
            strcpy(f->path, name);
            f->kind = k, f->band = b;
            o->n_files++;
        }
    }
    return 0;
}

/* A file the run writes or reads, by lsqt_file_identity (equal keys: one file). */
typedef struct file_id {
    char *key;
    const char *path;
    int role; /* 0: an output; else an input, ROLE_* */
} file_id;
enum { ROLE_OUTPUT, ROLE_INPUT, ROLE_TABLE, ROLE_WI_FILE, ROLE_STATE };

static int cmp_id(const void *pa, const void *pb)
{
    const file_id *a = pa, *b = pb;
    int k = strcmp(a->key, b->key);
    return k ? k : a->role - b->role;
}

/* No output may land on another one, on stdout twice, or on a file the run reads (the
 * input, its @FILE tables, --wi-file, the state a shard continues): every path is keyed
 * by the file it names and the keys sorted, so thousands of band files cost no more than
 * a sort. Returns 0, or 2 (or 1 out of memory) with err filled. */
static int check_clashes(const lsqt_cli *c, int from_stdin, const lsqt_assembly *a, const outputs *o, char *err,
                         size_t errcap)
{
    const int n_in = 3 + a->n_tables;
    file_id *ids = calloc((size_t)(o->n_files + n_in), sizeof *ids);
    if (!ids) {
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    int n = 0;
    for (int i = 0; i < o->n_files; i++) ids[n++] = (file_id){NULL, o->files[i].path, ROLE_OUTPUT};
    if (!from_stdin) ids[n++] = (file_id){NULL, c->input, ROLE_INPUT};
    if (c->wi_file) ids[n++] = (file_id){NULL, c->wi_file, ROLE_WI_FILE};
    if (o->base && o->base != o->path[OUT_LSS]) ids[n++] = (file_id){NULL, o->base, ROLE_STATE};
    for (int t = 0; t < a->n_tables; t++) ids[n++] = (file_id){NULL, a->tables[t], ROLE_TABLE};
    int m = 0; /* devices and FIFOs (no key) may be shared */
    for (int i = 0; i < n; i++)
        if ((ids[i].key = lsqt_file_identity(ids[i].path)) != NULL) ids[m++] = ids[i];
    qsort(ids, (size_t)m, sizeof *ids, cmp_id);
    static const char *const what[] = {"", "the input", "the table", "the --wi-file", "the state this shard continues"};
    int rc = 0;
    for (int i = 0; i + 1 < m && !rc; i++) {
        const file_id *x = &ids[i], *y = &ids[i + 1];
        if (strcmp(x->key, y->key) != 0 || (x->role && y->role)) continue;
        rc = 2;
        if (y->role) /* sorted: an output before the inputs */
            snprintf(err, errcap, "the output '%s' would replace %s '%s'", x->path, what[y->role], y->path);
        else if (strcmp(x->path, y->path) == 0)
            snprintf(err, errcap, "two outputs would be written to '%s'%s", x->path,
                     strcmp(x->path, "-") == 0 ? " (stdout)" : "");
        else
            snprintf(err, errcap, "two outputs would be written to '%s' (also named '%s')", x->path, y->path);
    }
    for (int i = 0; i < m; i++) free(ids[i].key);
    free(ids);
    return rc;
}

int run_plan_outputs(const lsqt_cli *c, int from_stdin, const lsqt_assembly *a, int transmits, int below,
                     outputs *o, char *err, size_t errcap)
{
    memset(o, 0, sizeof *o);
    o->n_bands = lsqt_assembly_bands(a), o->wl = a->wavelengths;
    if (c->no_raw && (c->output || c->only_hemispherical)) {
        snprintf(err, errcap, "--no-raw writes no RAW file, and %s names one", c->output ? "-o" : "-H");
        return 2;
    }
    char raw[LSQT_PATH_CAP + 16];
    raw_name(c, from_stdin, raw, sizeof raw);
    if (!c->no_raw && below && below_names(c, raw, o, err, errcap)) return 2;
    if (!c->no_raw && raw_names(c, raw, transmits, o, err, errcap)) return 2;
    if (state_names(c, from_stdin, o, err, errcap)) return 2;
    if (c->no_raw && !o->path[OUT_LSS] && !o->path[OUT_JSON]) {
        snprintf(err, errcap, "--no-raw: this run would write nothing (its input is stdin, so it has no LSS of "
                              "its own): give --lss PATH or --json PATH");
        return 2;
    }
    if (expand_files(o)) {
        run_outputs_free(o);
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    int rc = check_clashes(c, from_stdin, a, o, err, errcap);
    if (rc) run_outputs_free(o);
    return rc;
}

int run_check_outputs(const outputs *o)
{
    char err[LSQT_PATH_CAP + 1024];
    int bad = 0;
    for (int i = 0; i < o->n_files; i++)
        if (lsqt_out_check(o->files[i].path, err, sizeof err) && ++bad <= 10)
            fail(1, "%s (nothing simulated)", err, "");
    if (bad > 10) fprintf(stderr, "lsqt-cl: error: %d more outputs cannot be written (nothing simulated)\n", bad - 10);
    return bad ? 1 : 0;
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

/* A growing line of names ("a, b, c"), for the messages that list files. */
typedef struct name_list {
    char *s;
    size_t n, cap;
    int count;
} name_list;

static void list_add(name_list *l, const char *name)
{
    size_t need = l->n + strlen(name) + 3;
    if (need > l->cap) {
        size_t nc = need * 2;
        char *t = realloc(l->s, nc);
        if (!t) return;
        l->s = t, l->cap = nc;
    }
    l->n += (size_t)snprintf(l->s + l->n, l->cap - l->n, "%s%s", l->count++ ? ", " : "", name);
}

/* The previous file at PATH, when a failed write leaves it behind a newer LSS: removed,
 * so that no output looks current that is not. */
static int remove_stale(const char *path) { return lsqt_out_remove_old(path) == 1; }

/* Writes file F of the run (not the LSS): a RAW of one side and band, or the JSON, held
 * in SET. Returns 0 or -1 (err filled). */
static int write_held(const out_file *f, const outputs *o, const lsqt_cli *c, const lsqt_state *st,
                      const lsqt_slice_est *est, const lsqt_state sides[2], lsqt_slice_est *const side_est[2],
                      const lsqt_run_info *ri, lsqt_out_set *set, char *err, size_t errcap)
{
    if (f->kind == OUT_JSON) return lsqt_report_json(f->path, st, est, ri, set, err, errcap);
    const int b = f->kind == OUT_RAW_B || f->kind == OUT_RAW_BT, two = lsqt_state_below_count(st) > 0;
    const lsqt_state *rs = two ? &sides[b] : st;
    const lsqt_slice_est *re = (two ? side_est[b] : est) + (size_t)f->band * (size_t)rs->n_slices;
    const lsqt_state view = o->n_bands > 1 ? lsqt_state_band(rs, f->band) : *rs;
    const int mode = f->kind == OUT_RAW_T || f->kind == OUT_RAW_BT ? LSQT_RAW_TRANSMIT
                   : c->only_hemispherical                        ? LSQT_RAW_REFLECT
                                                                  : LSQT_RAW_ALL;
    int skipped = 0;
    return lsqt_raw_write(f->path, &view, re, mode, &skipped, set, err, errcap);
}

int run_write_outputs(const outputs *o, const lsqt_cli *c, const lsqt_state *st, const lsqt_state *lss_st,
                      const lsqt_slice_est *est, const lsqt_run_info *ri, FILE *info)
{
    char err[LSQT_PATH_CAP + 512];
    /* RAW files hold one side each: the main one exactly what it is without --from-below */
    lsqt_state sides[2];
    lsqt_slice_est *side_est[2] = {NULL, NULL};
    const int two = lsqt_state_below_count(st) > 0;
    memset(sides, 0, sizeof sides);
    char *done = calloc((size_t)o->n_files + 1, 1); /* per file: 1 written, 2 failed */
    if (!done || (two && (lsqt_state_split_sides(st, &sides[0], &sides[1]) || !(side_est[0] = lsqt_estimates(&sides[0])) ||
                          !(side_est[1] = lsqt_estimates(&sides[1]))))) {
        for (int b = 0; b < 2; b++) {
            lsqt_estimates_free(side_est[b], sides[b].n_slices);
            lsqt_state_free(&sides[b]);
        }
        free(done);
        return fail(1, "out of memory: no output written%s%s", "", "");
    }
    /* The LSS first and on its own: it is what a later run continues, so a RAW that
     * cannot be written (a FIFO nobody reads, a full disk) or a kill during the RAW files
     * loses no paths. The others are written to temporaries and published together. */
    lsqt_out_set set = {0, 0, NULL, NULL};
    int failed = 0, lss_failed = 0;
    for (int i = 0; i < o->n_files; i++) {
        const out_file *f = &o->files[i];
        int rc = f->kind == OUT_LSS ? lsqt_lss_write(f->path, lss_st, err, sizeof err)
                                    : write_held(f, o, c, st, est, sides, side_est, ri, &set, err, sizeof err);
        done[i] = rc ? 2 : 1;
        if (rc && ++failed <= 10) fail(1, "%s%s", err, "");
        if (rc && f->kind == OUT_LSS) lss_failed = 1;
    }
    failed += lsqt_out_set_publish(&set);
    /* What was written, in the usual order (RAW files, LSS, JSON); what was not. */
    name_list wrote = {NULL, 0, 0, 0}, missing = {NULL, 0, 0, 0}, removed = {NULL, 0, 0, 0};
    for (int k = 0; k < OUT_COUNT; k++) {
        int n = 0, ok = 0, first = -1;
        for (int i = 0; i < o->n_files; i++)
            if (o->files[i].kind == k) {
                n++, ok += done[i] == 1;
                if (first < 0) first = i;
            }
        if (!n || strcmp(o->path[k], "-") == 0) continue;
        char shown[LSQT_PATH_CAP + 200];
        if (ok == n) lsqt_band_path_shown(o->path[k], is_raw(k) ? o->n_bands : 1, o->wl, shown, sizeof shown);
        else if (ok) snprintf(shown, sizeof shown, "%d of the %d band files of %s", ok, n, o->path[k]);
        if (ok) list_add(&wrote, shown);
    }
    for (int i = 0; i < o->n_files; i++)
        if (done[i] == 2) {
            list_add(&missing, o->files[i].path);
            /* an old RAW or JSON beside a new LSS would pass for this run's */
            if (o->files[i].kind != OUT_LSS && !lss_failed && remove_stale(o->files[i].path))
                list_add(&removed, o->files[i].path);
        }
    if (!c->quiet && wrote.count) fprintf(info, "wrote %s\n", wrote.s);
    if (!c->quiet && c->only_hemispherical && !o->path[OUT_RAW_T])
        fprintf(info, "note: the stack transmits nothing, so -H wrote no T file\n");
    if (failed) {
        fflush(info);
        if (failed > 10) fprintf(stderr, "lsqt-cl: error: %d more outputs could not be written\n", failed - 10);
        fprintf(stderr, "lsqt-cl: %d output%s could not be written: %s\n", failed, failed > 1 ? "s" : "",
                missing.s ? missing.s : "(a rename, see above)");
        if (removed.count)
            fprintf(stderr, "lsqt-cl: removed the previous %s: %s older than the LSS this run wrote\n", removed.s,
                    removed.count > 1 ? "they were" : "it was");
        else if (lss_failed)
            fprintf(stderr, "lsqt-cl: the LSS was not written: it still holds the previous state, and the files "
                            "not written are as that state left them\n");
    }
    free(wrote.s), free(missing.s), free(removed.s), free(done);
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
    if (below) run_outputs_free(out);
    int rc = below ? run_plan_outputs(c, from_stdin, a, st->transmits, 1, out, err, errcap) : 0;
    if (rc) {
        lsqt_state_free(st);
        fail(rc, "%s%s", err, "");
    }
    return rc;
}
