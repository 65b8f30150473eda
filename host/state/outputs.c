/* The files a state is written to (outputs.h): expanded band by band, checked against
 * each other and the files read, and written together. */
#include "lsqt/outputs.h"

#include <stdlib.h>
#include <string.h>

#include "lsqt/bands.h"
#include "lsqt/below.h"
#include "lsqt/colour.h"
#include "lsqt/lss.h"
#include "lsqt/raw.h"
#include "lsqt/util.h"

static int is_raw(int kind) { return kind != LSQT_OUT_LSS && kind != LSQT_OUT_JSON; }

void lsqt_outputs_free(lsqt_outputs *o)
{
    for (int i = 0; i < o->n_files; i++) free(o->files[i].path);
    free(o->files);
    o->files = NULL, o->n_files = 0;
}

/* With bands each RAW kind is one file per band, named from its RAW name: that name must
 * be a plain path then. Returns 0 or 2. */
static int band_base(const lsqt_outputs *o, const char *raw, const char *hint, char *err, size_t errcap)
{
    const char *what = NULL;
    int t = strcmp(raw, "-") == 0 ? LSQT_PATH_SPECIAL : lsqt_path_type(raw, &what);
    if (o->n_bands <= 1 || (t != LSQT_PATH_SPECIAL && t != LSQT_PATH_DIRECTORY)) return 0;
    char example[LSQT_PATH_CAP + 64], label[48];
    lsqt_band_path(strcmp(raw, "-") == 0 ? "OUT" : raw, lsqt_band_label_one(o->n_bands, o->wl, 0, label, sizeof label),
                   example, sizeof example);
    snprintf(err, errcap, "a run with %d bands writes one RAW per band, named from the RAW name (%s, ...), and '%s' is "
             "%s%s: give -o a file name%s", o->n_bands, example, raw, what ? "a " : "stdout", what ? what : "",
             hint ? hint : "");
    return 2;
}

/* Every file, in the order they are written: the LSS, each RAW kind band by band, the
 * JSON. Returns 0, or 1 out of memory. */
static int expand_files(lsqt_outputs *o)
{
    static const int order[LSQT_OUT_KINDS] = {LSQT_OUT_LSS,   LSQT_OUT_RAW,    LSQT_OUT_RAW_T,
                                              LSQT_OUT_RAW_B, LSQT_OUT_RAW_BT, LSQT_OUT_JSON};
    const int nbands = o->n_bands > 1 ? o->n_bands : 1;
    size_t n = 0;
    for (int i = 0; i < LSQT_OUT_KINDS; i++)
        if (o->path[i]) n += is_raw(i) ? (size_t)nbands : 1;
    o->files = calloc(n ? n : 1, sizeof *o->files);
    if (!o->files) return 1;
    lsqt_band_names names; /* --wavelengths and the LSS reader refuse bands that cannot be named apart */
    (void)lsqt_band_names_init(&names, o->n_bands, o->wl, NULL);
    for (int j = 0; j < LSQT_OUT_KINDS; j++) {
        const int k = order[j];
        const int nb = is_raw(k) ? nbands : 1;
        for (int b = 0; o->path[k] && b < nb; b++) {
            char label[48], name[LSQT_PATH_CAP + 96];
            if (nb > 1) lsqt_band_path(o->path[k], lsqt_band_label(&names, b, label, sizeof label), name, sizeof name);
            else snprintf(name, sizeof name, "%s", o->path[k]);
            lsqt_out_file *f = &o->files[o->n_files];
            if (!(f->path = malloc(strlen(name) + 1))) return 1;
            strcpy(f->path, name);
            f->kind = k, f->band = b;
            o->n_files++;
        }
    }
    return 0;
}

/* A file written or read, by lsqt_file_identity (equal keys: one file). */
typedef struct file_id {
    char *key;
    const char *path, *what; /* what: NULL for an output */
    int order;               /* outputs before inputs, then as given */
} file_id;

static int cmp_id(const void *pa, const void *pb)
{
    const file_id *a = pa, *b = pb;
    int k = strcmp(a->key, b->key);
    return k ? k : a->order - b->order;
}

/* No output may land on another one, on stdout twice, or on a file read: every path is
 * keyed by the file it names and the keys sorted, so thousands of band files cost no more
 * than a sort. Returns 0, or 2 (or 1 out of memory) with err filled. */
static int check_clashes(const lsqt_outputs *o, const lsqt_input_file *in, int n_in, char *err, size_t errcap)
{
    file_id *ids = calloc((size_t)(o->n_files + n_in) + 1, sizeof *ids);
    if (!ids) {
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    int n = 0;
    for (int i = 0; i < o->n_files; i++) ids[n] = (file_id){NULL, o->files[i].path, NULL, n}, n++;
    for (int i = 0; i < n_in; i++) ids[n] = (file_id){NULL, in[i].path, in[i].what, n}, n++;
    int m = 0; /* devices and FIFOs (no key) may be shared */
    for (int i = 0; i < n; i++)
        if ((ids[i].key = lsqt_file_identity(ids[i].path)) != NULL) ids[m++] = ids[i];
    qsort(ids, (size_t)m, sizeof *ids, cmp_id);
    int rc = 0;
    for (int i = 0; i + 1 < m && !rc; i++) {
        const file_id *x = &ids[i], *y = &ids[i + 1];
        if (strcmp(x->key, y->key) != 0 || (x->what && y->what)) continue;
        rc = 2;
        if (y->what) /* sorted: an output before the inputs */
            snprintf(err, errcap, "the output '%s' would replace %s '%s'", x->path, y->what, y->path);
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

int lsqt_outputs_plan(lsqt_outputs *o, const lsqt_input_file *in, int n_in, const char *hint, char *err,
                      size_t errcap)
{
    o->files = NULL, o->n_files = 0;
    for (int k = 0; k < LSQT_OUT_KINDS; k++)
        if (o->path[k] && is_raw(k) && band_base(o, o->path[k], hint, err, errcap)) return 2;
    if (expand_files(o)) {
        lsqt_outputs_free(o);
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    int rc = check_clashes(o, in, n_in, err, errcap);
    if (rc) lsqt_outputs_free(o);
    return rc;
}

int lsqt_outputs_check(const lsqt_outputs *o, const char *prog, const char *when)
{
    char err[LSQT_PATH_CAP + 1024];
    int bad = 0;
    for (int i = 0; i < o->n_files; i++)
        if (lsqt_out_check(o->files[i].path, err, sizeof err) && ++bad <= 10)
            fprintf(stderr, "%s: error: %s (%s)\n", prog, err, when);
    if (bad > 10) fprintf(stderr, "%s: error: %d more outputs cannot be written (%s)\n", prog, bad - 10, when);
    return bad ? 1 : 0;
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

/* Writes file F (not the LSS): a RAW of one side and band, or the JSON, held in SET.
 * Returns 0 or -1 (err filled). */
static int write_held(const lsqt_out_file *f, const lsqt_outputs *o, const lsqt_state *st, const lsqt_slice_est *est,
                      const lsqt_state sides[2], lsqt_slice_est *const side_est[2], const lsqt_run_info *ri,
                      lsqt_out_set *set, char *err, size_t errcap)
{
    if (f->kind == LSQT_OUT_JSON) return lsqt_report_json(f->path, st, est, ri, set, err, errcap);
    const int b = f->kind == LSQT_OUT_RAW_B || f->kind == LSQT_OUT_RAW_BT, two = lsqt_state_below_count(st) > 0;
    const lsqt_state *rs = two ? &sides[b] : st;
    const lsqt_slice_est *re = (two ? side_est[b] : est) + (size_t)f->band * (size_t)rs->n_slices;
    const lsqt_state view = lsqt_state_bands(rs) > 1 ? lsqt_state_band(rs, f->band) : *rs;
    const int mode = f->kind == LSQT_OUT_RAW_T || f->kind == LSQT_OUT_RAW_BT ? LSQT_RAW_TRANSMIT
                   : o->hemi                                                ? LSQT_RAW_REFLECT
                                                                            : LSQT_RAW_ALL;
    int skipped = 0;
    return lsqt_raw_write(f->path, &view, re, mode, &skipped, set, err, errcap);
}

/* A held file whose rename failed (lsqt_out_set_publish): marked failed in DONE. */
typedef struct publish_ctx {
    const lsqt_outputs *o;
    char *done;
} publish_ctx;

static void publish_failed(void *ctx, const char *path)
{
    publish_ctx *p = ctx;
    for (int i = 0; i < p->o->n_files; i++)
        if (p->done[i] == 1 && strcmp(p->o->files[i].path, path) == 0) {
            p->done[i] = 2;
            return;
        }
}

static void free_sides(lsqt_state sides[2], lsqt_slice_est *side_est[2])
{
    for (int b = 0; b < 2; b++) {
        lsqt_estimates_free(side_est[b], sides[b].n_slices);
        lsqt_state_free(&sides[b]);
    }
}

int lsqt_outputs_write(const lsqt_outputs *o, const lsqt_state *st, const lsqt_state *lss_st,
                       const lsqt_slice_est *est, const lsqt_run_info *ri, const char *prog, const char *said,
                       int quiet, FILE *info)
{
    char err[LSQT_PATH_CAP + 512];
    /* RAW files hold one side each: the main one exactly what it is without --from-below */
    lsqt_state sides[2];
    lsqt_slice_est *side_est[2] = {NULL, NULL};
    const int two = lsqt_state_below_count(st) > 0;
    memset(sides, 0, sizeof sides);
    char *done = calloc((size_t)o->n_files + 1, 1); /* per file: 1 written, 2 failed */
    if (!done || (two && (lsqt_state_split_by_side(st, &sides[0], &sides[1]) || !(side_est[0] = lsqt_estimates(&sides[0])) ||
                          !(side_est[1] = lsqt_estimates(&sides[1]))))) {
        free_sides(sides, side_est);
        free(done);
        fprintf(stderr, "%s: error: out of memory: no output written\n", prog);
        return 1;
    }
    /* The LSS first and on its own: it is what a later run continues, so a RAW that
     * cannot be written (a FIFO nobody reads, a full disk) or a kill during the RAW files
     * loses no paths. The others are written to temporaries and published together. */
    lsqt_out_set set = {0, 0, NULL, NULL, NULL};
    int failed = 0, lss_failed = 0;
    for (int i = 0; i < o->n_files; i++) {
        const lsqt_out_file *f = &o->files[i];
        int rc = f->kind == LSQT_OUT_LSS ? lsqt_lss_write(f->path, lss_st, err, sizeof err)
                                         : write_held(f, o, st, est, sides, side_est, ri, &set, err, sizeof err);
        done[i] = rc ? 2 : 1;
        if (rc && ++failed <= 10) fprintf(stderr, "%s: error: %s\n", prog, err);
        if (rc && f->kind == LSQT_OUT_LSS) lss_failed = 1;
    }
    publish_ctx pc = {o, done};
    failed += lsqt_out_set_publish(&set, prog, publish_failed, &pc);
    /* What was written, in the usual order (RAW files, LSS, JSON); what was not. */
    name_list wrote = {NULL, 0, 0, 0}, missing = {NULL, 0, 0, 0}, removed = {NULL, 0, 0, 0};
    for (int k = 0; k < LSQT_OUT_KINDS; k++) {
        int n = 0, ok = 0;
        for (int i = 0; i < o->n_files; i++)
            if (o->files[i].kind == k) n++, ok += done[i] == 1;
        if (!n || strcmp(o->path[k], "-") == 0) continue;
        char shown[LSQT_PATH_CAP + 200];
        if (ok == n) lsqt_band_path_shown(o->path[k], is_raw(k) ? o->n_bands : 1, o->wl, shown, sizeof shown);
        else if (ok) snprintf(shown, sizeof shown, "%d of the %d band files of %s", ok, n, o->path[k]);
        if (ok) list_add(&wrote, shown);
    }
    for (int i = 0; i < o->n_files; i++)
        if (done[i] == 2) {
            list_add(&missing, o->files[i].path);
            /* an old RAW or JSON beside a new LSS would pass for this state's */
            if (o->files[i].kind != LSQT_OUT_LSS && !lss_failed && lsqt_out_remove_old(o->files[i].path) == 1)
                list_add(&removed, o->files[i].path);
        }
    if (!quiet && wrote.count) fprintf(info, "%swrote %s\n", said ? said : "", wrote.s);
    if (failed) {
        fflush(info);
        if (failed > 10) fprintf(stderr, "%s: error: %d more outputs could not be written\n", prog, failed - 10);
        fprintf(stderr, "%s: %d output%s could not be written: %s\n", prog, failed, failed > 1 ? "s" : "",
                missing.s ? missing.s : "(see above)");
        if (removed.count)
            fprintf(stderr, "%s: removed the previous %s: %s older than the LSS written now\n", prog, removed.s,
                    removed.count > 1 ? "they were" : "it was");
        else if (lss_failed)
            fprintf(stderr, "%s: the LSS was not written: it still holds the previous state, and the files "
                            "not written are as that state left them\n", prog);
    }
    free(wrote.s), free(missing.s), free(removed.s), free(done);
    free_sides(sides, side_est);
    return failed ? 1 : 0;
}
