/* lsqt-cl merge OUT.lss IN.lss...: the parts of one run (shards, docs/design.md section 4.2) added into one
 * state. Tallies are integers, so the sum is exact: all the shards of a run give the
 * bytes of the run in one process. No OpenCL. */
#include "lsqt/merge.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/bands.h"
#include "lsqt/below.h"
#include "lsqt/lss.h"
#include "lsqt/outputs.h"
#include "lsqt/raw.h"
#include "lsqt/report.h"
#include "lsqt/rrss.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

static void merge_help(FILE *f, const char *prog)
{
    fprintf(f,
            "usage: %s OUT.lss IN.lss... [-o RAW] [-H] [--json PATH] [--partial] [-q]\n"
            "Adds the tallies of parts of one run (lsqt-cl --shard K/N, and the LSS they\n"
            "continued) into OUT.lss, and writes its RAW (OUT with its final .lss replaced by\n"
            ".raw, or -o; -H: R and T files as lsqt-cl -H). OUT may be one of the inputs.\n"
            "The inputs must be of one assembly, seed, precision and set of directions, and\n"
            "hold disjoint path ranges that together make the whole run; the shards of an\n"
            "RRSS pilot, once all merged, choose the directions (then run the shards again\n"
            "with --refine and merge those).\n"
            "  -o, --output PATH   RAW file (- is stdout)\n"
            "  -H                  write OUT.R.raw and OUT.T.raw instead\n"
            "      --json PATH     machine-readable summary\n"
            "      --partial       allow missing shards: OUT holds the ranges it has (lsqt-cl\n"
            "                      info shows them; continuing runs the missing tail, not a gap)\n"
            "  -q, --quiet         print errors only\n"
            "      --version       the version and the commit it was built from\n"
            "Exit status: 0 success, 1 failure, 2 bad input (incompatible, overlapping or\n"
            "missing parts).\n",
            prog);
}

static void add_all(lsqt_u128 *dst, const lsqt_u128 *src, size_t n)
{
    for (size_t i = 0; i < n; i++) dst[i] = lsqt_u128_add(dst[i], src[i]);
}

/* "[a, b), [c, d)": the parts of [0, need) that ranges r (n pairs, sorted) leave out. */
static int missing(const uint64_t *r, int n, uint64_t need, char *buf, size_t cap)
{
    int count = 0;
    size_t len = 0;
    uint64_t at = 0;
    buf[0] = '\0';
    for (int i = 0; i <= n; i++) {
        uint64_t lo = i < n ? r[2 * i] : need;
        if (lo > need) lo = need;
        if (lo > at) {
            if (count < 4 && len < cap)
                len += (size_t)snprintf(buf + len, cap - len, "%s[%llu, %llu)", count ? ", " : "",
                                        (unsigned long long)at, (unsigned long long)lo);
            count++;
        }
        if (i < n && r[2 * i + 1] > at) at = r[2 * i + 1];
    }
    if (count > 4 && len < cap) snprintf(buf + len, cap - len, " and %d more", count - 4);
    return count;
}

/* What the command line asks. */
typedef struct merge_args {
    const char *out_lss, *raw, *json;
    int hemi, partial, quiet, n_in;
    const char **in; /* the inputs, n_in of them */
} merge_args;

/* One merge: its inputs read, their locks, and the sum. */
typedef struct merge_job {
    const char *prog;
    merge_args g;
    lsqt_state *st; /* the inputs read, n_read of them */
    int n_read;
    lsqt_lock *locks;
    int n_locks;
    lsqt_state sum;
    char err[2 * LSQT_PATH_CAP + 512];
} merge_job;

/* The flags and files. Returns -1 to go on, else the exit status (printed; g->in freed). */
static int parse_args(const char *prog, int argc, char **argv, merge_args *g)
{
    char err[2 * LSQT_PATH_CAP + 512];
    memset(g, 0, sizeof *g);
    g->in = calloc((size_t)(argc > 0 ? argc : 1), sizeof *g->in);
    if (!g->in) return lsqt_prog_error(prog, 1, "out of memory");
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *eq = strchr(a, '=');
        size_t nl = eq && a[0] == '-' ? (size_t)(eq - a) : strlen(a);
        int takes = (nl == 2 && strncmp(a, "-o", 2) == 0) || (nl == 8 && strncmp(a, "--output", 8) == 0) ||
                    (nl == 6 && strncmp(a, "--json", 6) == 0);
        if (strcmp(a, "--version") == 0) {
            printf("%s %s\n", prog, lsqt_version());
            free(g->in);
            return 0;
        }
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            merge_help(stdout, prog);
            free(g->in);
            return 0;
        } else if (takes) {
            const char *v = eq ? eq + 1 : i + 1 < argc ? argv[++i] : NULL;
            if (!v || !*v) {
                snprintf(err, sizeof err, "%.*s needs a value (see --help)", (int)nl, a);
                free(g->in);
                return lsqt_prog_error(prog, 2, err);
            }
            if (a[1] == 'o' || a[2] == 'o') g->raw = v;
            else g->json = v;
        } else if (strcmp(a, "-H") == 0 || strcmp(a, "--only-hemispherical") == 0) {
            g->hemi = 1;
        } else if (strcmp(a, "--partial") == 0) {
            g->partial = 1;
        } else if (strcmp(a, "-q") == 0 || strcmp(a, "--quiet") == 0) {
            g->quiet = 1;
        } else if (a[0] == '-' && a[1]) {
            snprintf(err, sizeof err, "unknown option '%.64s' (see --help)", a);
            free(g->in);
            return lsqt_prog_error(prog, 2, err);
        } else if (!g->out_lss) {
            g->out_lss = a;
        } else {
            g->in[g->n_in++] = a;
        }
    }
    if (!g->out_lss || g->n_in == 0) {
        free(g->in);
        merge_help(stderr, prog);
        return 2;
    }
    if (strcmp(g->out_lss, "-") == 0) {
        free(g->in);
        return lsqt_prog_error(prog, 2, "OUT.lss must be a file");
    }
    return -1;
}

/* The output exclusive and the inputs shared (lsqt_lock_take): a shard still running, or
 * a run on OUT.lss, makes the merge wait for it rather than lose its paths. */
static int lock_files(merge_job *j)
{
    const merge_args *g = &j->g;
    int rc = 0;
    for (int i = -1; i < g->n_in && !rc; i++) {
        if (i >= 0 && lsqt_same_file(g->in[i], g->out_lss)) continue;
        int r = lsqt_lock_take(&j->locks[j->n_locks], i < 0 ? g->out_lss : g->in[i], i < 0, j->err, sizeof j->err);
        if (r == 0) j->n_locks++;
        else if (r == 2 && !g->quiet) fprintf(stderr, "warning: %s\n", j->err);
        else if (r == 1) rc = lsqt_prog_error(j->prog, 1, j->err); /* -1: writing OUT.lss fails and says why */
    }
    return rc;
}

/* Every input read and checked against the first before anything is written. */
static int read_inputs(merge_job *j)
{
    const merge_args *g = &j->g;
    int rc = 0;
    for (int i = 0; i < g->n_in && !rc; i++) {
        for (int k = 0; k < i && !rc; k++)
            if (lsqt_same_file(g->in[i], g->in[k])) {
                snprintf(j->err, sizeof j->err, "'%s' is given twice: the same paths cannot be added twice", g->in[i]);
                rc = lsqt_prog_error(j->prog, 2, j->err);
            }
        if (rc) break;
        if (lsqt_lss_read(g->in[i], &j->st[i], j->err, sizeof j->err)) {
            rc = lsqt_prog_error(j->prog, 2, j->err);
            break;
        }
        j->n_read++;
        const char *what = i ? lsqt_state_differs(&j->st[0], &j->st[i]) : NULL;
        if (what) {
            snprintf(j->err, sizeof j->err, "'%s' and '%s' differ in their %s: they are not parts of one run",
                     g->in[0], g->in[i], what);
            rc = lsqt_prog_error(j->prog, 2, j->err);
        }
    }
    return rc;
}

/* Disjoint ranges: a path counted twice would be a silent bias. */
static int check_disjoint(merge_job *j)
{
    const lsqt_state *st = j->st;
    const char **in = j->g.in;
    int rc = 0;
    for (int i = 0; i < j->n_read && !rc; i++)
        for (int k = 0; k < i && !rc; k++)
            for (int x = 0; x < st[i].n_ranges && !rc; x++)
                for (int y = 0; y < st[k].n_ranges && !rc; y++) {
                    uint64_t lo = st[i].ranges[2 * x] > st[k].ranges[2 * y] ? st[i].ranges[2 * x] : st[k].ranges[2 * y];
                    uint64_t hi = st[i].ranges[2 * x + 1] < st[k].ranges[2 * y + 1] ? st[i].ranges[2 * x + 1]
                                                                                     : st[k].ranges[2 * y + 1];
                    if (lo < hi) {
                        snprintf(j->err, sizeof j->err,
                                 "'%s' and '%s' both hold paths [%llu, %llu): overlapping parts (the same shard "
                                 "twice, or shards of different runs)",
                                 in[k], in[i], (unsigned long long)lo, (unsigned long long)hi);
                        rc = lsqt_prog_error(j->prog, 2, j->err);
                    }
                }
    return rc;
}

/* The sum: the first input's settings, every input's tallies, flags and ranges (all: room
 * for every range). Returns 0 or 1 (out of memory). */
static int add_inputs(merge_job *j, uint64_t *all)
{
    lsqt_state *st = j->st;
    const lsqt_state *f = &st[0];
    lsqt_state *sum = &j->sum;
    if (lsqt_state_init(sum, f->canonical, f->hash, f->seed, f->n_slices, f->n_wi, f->transmits, f->n_bands,
                              f->wavelengths) ||
        lsqt_state_pack_hist(sum, 0)) /* many bands: packed, as the inputs were read */
        return 1;
    sum->use_double = f->use_double, sum->dir_method = f->dir_method, sum->rx = f->rx;
    sum->pilot_paths = f->pilot_paths, sum->stage = f->stage;
    sum->grid_ni = f->grid_ni, sum->grid_nphi = f->grid_nphi;
    memcpy(sum->theta_o, f->theta_o, (size_t)f->n_slices * sizeof *f->theta_o);
    memcpy(sum->slice_flags, f->slice_flags, (size_t)f->n_slices * sizeof *f->slice_flags);
    memcpy(sum->wi, f->wi, (size_t)f->n_slices * (size_t)f->n_wi * 4 * sizeof *f->wi);
    int k = 0;
    for (int i = 0; i < j->n_read; i++) {
        add_all(sum->nee, st[i].nee, lsqt_state_nee_count(sum));
        add_all(sum->scalars, st[i].scalars, lsqt_state_scalar_count(sum));
        if (lsqt_state_add_hist(sum, &st[i])) return 1;
        sum->flags |= st[i].flags;
        if (st[i].span_end > sum->span_end) sum->span_end = st[i].span_end;
        memcpy(all + 2 * k, st[i].ranges, (size_t)st[i].n_ranges * 2 * sizeof *all);
        k += st[i].n_ranges;
    }
    return lsqt_state_set_ranges(sum, all, k) ? 1 : 0;
}

/* Reads, checks and adds the inputs into j->sum; the inputs are freed. */
static int merge_inputs(merge_job *j)
{
    int rc = lock_files(j);
    if (!rc) rc = read_inputs(j);
    if (!rc) rc = check_disjoint(j);
    int total_ranges = 0;
    for (int i = 0; i < j->n_read; i++) total_ranges += j->st[i].n_ranges;
    uint64_t *all = rc ? NULL : malloc(((size_t)total_ranges + 1) * 2 * sizeof *all);
    if (!rc && !all) rc = lsqt_prog_error(j->prog, 1, "out of memory");
    if (!rc && add_inputs(j, all)) rc = lsqt_prog_error(j->prog, 1, "out of memory");
    free(all);
    for (int i = 0; i < j->n_read; i++) lsqt_state_free(&j->st[i]);
    if (!rc && lsqt_tally_flags_error(j->sum.flags, j->err, sizeof j->err)) rc = lsqt_prog_error(j->prog, 1, j->err);
    return rc;
}

/* The whole run, or (--partial) what there is; an RRSS pilot must be whole. */
static int check_whole(merge_job *j, int pilot)
{
    const merge_args *g = &j->g;
    const lsqt_state *sum = &j->sum;
    const int partial = g->partial;
    char gaps[512];
    const uint64_t need = pilot ? sum->pilot_paths : sum->span_end;
    int n_missing = missing(sum->ranges, sum->n_ranges, need, gaps, sizeof gaps);
    if (n_missing && (!partial || pilot)) {
        snprintf(j->err, sizeof j->err, "the inputs leave out paths %s of the %s [0, %llu): missing shards%s", gaps,
                 pilot ? "RRSS pilot" : "run", (unsigned long long)need,
                 pilot ? " (an RRSS pilot must be whole to choose directions)" : " (--partial writes them anyway)");
        return lsqt_prog_error(j->prog, 2, j->err);
    }
    if (n_missing && !g->quiet)
        fprintf(stderr, "note: partial: %s holds %llu of the run's %llu paths per slice; missing %s\n", g->out_lss,
                (unsigned long long)sum->paths, (unsigned long long)need, gaps);
    return 0;
}

/* The whole pilot: the directions are chosen here, as lsqt-cl does in one process. */
static int choose_pilot(merge_job *j)
{
    lsqt_state chosen;
    lsqt_rrss_info ri;
    memset(&ri, 0, sizeof ri);
    if (lsqt_rrss_choose_using(&j->sum, &chosen, &ri, j->err, sizeof j->err)) return lsqt_prog_error(j->prog, 1, j->err);
    if (!j->g.quiet) lsqt_rrss_notes(stderr, &ri);
    if (!j->g.quiet)
        fprintf(stderr, "RRSS: directions chosen from a pilot of %llu paths per slice; the run owes %llu "
                        "more (run the shards with --refine, then merge)\n",
                (unsigned long long)chosen.paths, (unsigned long long)(chosen.span_end - chosen.paths));
    lsqt_state_free(&j->sum);
    j->sum = chosen;
    return 0;
}

/* Outputs: the LSS, the RAW (named from OUT.lss; -H: R and T), JSON, and for a two-sided
 * state the RAW of the side from below (lsqt-cl's names, below.h); with bands each RAW
 * one file per band. */
typedef struct merge_outs {
    lsqt_outputs f;
    char names[4][LSQT_PATH_CAP + 48]; /* the RAW kinds' names */
} merge_outs;

/* Names every output, every band's, and checks them against each other and the inputs
 * (OUT.lss may be one of them). Returns 0 or 2 (1 out of memory), printed. */
static int name_outputs(merge_job *j, merge_outs *o)
{
    const merge_args *g = &j->g;
    const char *raw = g->raw, *out_lss = g->out_lss;
    char raw_name[LSQT_PATH_CAP + 16], below_name[LSQT_PATH_CAP + 32];
    if (raw) snprintf(raw_name, sizeof raw_name, "%s", raw);
    else {
        size_t n = strlen(out_lss);
        if (n >= 4 && strcmp(out_lss + n - 4, ".lss") == 0) n -= 4;
        snprintf(raw_name, sizeof raw_name, "%.*s.raw", (int)n, out_lss);
    }
    lsqt_below_raw_name(raw_name, below_name, sizeof below_name);
    const int two = lsqt_state_below_count(&j->sum) > 0;
    o->f.path[LSQT_OUT_LSS] = out_lss;
    o->f.path[LSQT_OUT_JSON] = g->json;
    o->f.hemi = g->hemi;
    o->f.n_bands = j->sum.n_bands, o->f.wl = j->sum.wavelengths;
    for (int side = 0; side < 1 + two; side++) {
        const char *base = side ? below_name : raw_name;
        const int km = side ? LSQT_OUT_RAW_B : LSQT_OUT_RAW, kt = side ? LSQT_OUT_RAW_BT : LSQT_OUT_RAW_T;
        char *m = o->names[km], *t = o->names[kt];
        if (g->hemi) {
            lsqt_raw_hemi_name(base, "R", m, sizeof o->names[0]);
            lsqt_raw_hemi_name(base, "T", t, sizeof o->names[0]);
        } else {
            snprintf(m, sizeof o->names[0], "%s", base);
        }
        o->f.path[km] = m;
        o->f.path[kt] = g->hemi && j->sum.transmits ? t : NULL;
    }
    if (two && (!raw_name[0] || strcmp(raw_name, "-") == 0))
        return lsqt_prog_error(j->prog, 2,
                               "a two-sided state has a second RAW named from the first: give -o a file name");
    lsqt_input_file *in = calloc((size_t)g->n_in + 1, sizeof *in);
    if (!in) return lsqt_prog_error(j->prog, 1, "out of memory");
    int n_in = 0;
    for (int i = 0; i < g->n_in; i++) /* the sum may replace an input, no other output */
        if (!lsqt_same_file(g->in[i], out_lss)) in[n_in++] = (lsqt_input_file){g->in[i], "the input"};
    int rc = lsqt_outputs_plan(&o->f, in, n_in, "", j->err, sizeof j->err);
    free(in);
    return rc ? lsqt_prog_error(j->prog, rc, j->err) : 0;
}

/* Writes every output (lsqt_outputs_write), after "merged N files: P paths per slice". */
static int write_outputs(merge_job *j, const merge_outs *o)
{
    const merge_args *g = &j->g;
    const lsqt_state *sum = &j->sum;
    lsqt_slice_est *est = lsqt_estimates(sum);
    if (!est) return lsqt_prog_error(j->prog, 1, "out of memory");
    lsqt_run_info ri = {"(merged: no device)", 0.0, 0.0, 0ULL, NULL, lsqt_work_totals(sum), 0.0, 0.0, 0ULL, 0};
    FILE *info = (g->raw && strcmp(g->raw, "-") == 0) || (g->json && strcmp(g->json, "-") == 0) ? stderr : stdout;
    const uint64_t h = lsqt_state_contiguous(sum);
    char said[256], owed[96] = "";
    if (h == UINT64_MAX) snprintf(owed, sizeof owed, " (partial: with gaps)");
    else if (h < sum->span_end)
        snprintf(owed, sizeof owed, " (the run owes %llu more)", (unsigned long long)(sum->span_end - h));
    snprintf(said, sizeof said, "merged %d file%s: %llu paths per slice%s; ", g->n_in, g->n_in > 1 ? "s" : "",
             (unsigned long long)sum->paths, owed);
    int rc = lsqt_outputs_write(&o->f, sum, sum, est, &ri, j->prog, said, g->quiet, info);
    lsqt_estimates_free(est, sum->n_slices);
    return rc;
}

int lsqt_merge_main(const char *prog, int argc, char **argv)
{
    merge_job j;
    memset(&j, 0, sizeof j);
    j.prog = prog;
    int rc = parse_args(prog, argc, argv, &j.g);
    if (rc >= 0) return rc;
    rc = 0;
    /* Every input is read and checked before anything is written. */
    j.st = calloc((size_t)j.g.n_in, sizeof *j.st);
    j.locks = calloc((size_t)j.g.n_in + 1, sizeof *j.locks);
    if (!j.st || !j.locks) rc = lsqt_prog_error(prog, 1, "out of memory");
    if (!rc) rc = merge_inputs(&j);
    free(j.st);
    const int pilot = !rc && j.sum.stage == LSQT_STAGE_PILOT;
    if (!rc) rc = check_whole(&j, pilot);
    /* A pilot's directions are chosen even when check_whole refused it for its gaps, as
     * merge always did: the same messages and status (a failed choice's then wins). */
    if (pilot) {
        const int crc = choose_pilot(&j);
        if (crc) rc = crc;
    }
    merge_outs o;
    memset(&o, 0, sizeof o);
    if (!rc) rc = name_outputs(&j, &o);
    if (!rc) rc = lsqt_outputs_check(&o.f, prog, "nothing written");
    if (!rc) rc = write_outputs(&j, &o);
    lsqt_outputs_free(&o.f);
    lsqt_state_free(&j.sum);
    for (int i = 0; i < j.n_locks; i++) lsqt_lock_release(&j.locks[i]);
    free(j.locks);
    free(j.g.in);
    return rc;
}
