/* lsqt-cl merge OUT.lss IN.lss...: the parts of one run (shards, docs/design.md section 4.2) added into one
 * state. Tallies are integers, so the sum is exact: all the shards of a run give the
 * bytes of the run in one process. No OpenCL. */
#include "lsqt/merge.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/below.h"
#include "lsqt/lss.h"
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

int lsqt_merge_main(const char *prog, int argc, char **argv)
{
    const char *out_lss = NULL, *raw = NULL, *json = NULL;
    int hemi = 0, partial = 0, quiet = 0, n_in = 0;
    const char **in = calloc((size_t)(argc > 0 ? argc : 1), sizeof *in);
    char err[2 * LSQT_PATH_CAP + 512];
    if (!in) return lsqt_prog_error(prog, 1, "out of memory");
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *eq = strchr(a, '=');
        size_t nl = eq && a[0] == '-' ? (size_t)(eq - a) : strlen(a);
        int takes = (nl == 2 && strncmp(a, "-o", 2) == 0) || (nl == 8 && strncmp(a, "--output", 8) == 0) ||
                    (nl == 6 && strncmp(a, "--json", 6) == 0);
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            merge_help(stdout, prog);
            free(in);
            return 0;
        } else if (takes) {
            const char *v = eq ? eq + 1 : i + 1 < argc ? argv[++i] : NULL;
            if (!v || !*v) {
                snprintf(err, sizeof err, "%.*s needs a value (see --help)", (int)nl, a);
                free(in);
                return lsqt_prog_error(prog, 2, err);
            }
            if (a[1] == 'o' || a[2] == 'o') raw = v;
            else json = v;
        } else if (strcmp(a, "-H") == 0 || strcmp(a, "--only-hemispherical") == 0) {
            hemi = 1;
        } else if (strcmp(a, "--partial") == 0) {
            partial = 1;
        } else if (strcmp(a, "-q") == 0 || strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (a[0] == '-' && a[1]) {
            snprintf(err, sizeof err, "unknown option '%.64s' (see --help)", a);
            free(in);
            return lsqt_prog_error(prog, 2, err);
        } else if (!out_lss) {
            out_lss = a;
        } else {
            in[n_in++] = a;
        }
    }
    if (!out_lss || n_in == 0) {
        free(in);
        merge_help(stderr, prog);
        return 2;
    }
    if (strcmp(out_lss, "-") == 0) {
        free(in);
        return lsqt_prog_error(prog, 2, "OUT.lss must be a file");
    }

    /* Every input is read and checked before anything is written. The output is locked
     * exclusive and the inputs shared first (lsqt_lock_take): a shard still running, or
     * a run on OUT.lss, makes the merge wait for it rather than lose its paths. */
    lsqt_state *st = calloc((size_t)n_in, sizeof *st), sum;
    lsqt_lock *locks = calloc((size_t)n_in + 1, sizeof *locks);
    memset(&sum, 0, sizeof sum);
    int rc = 0, n_read = 0, n_locks = 0;
    if (!st || !locks) rc = lsqt_prog_error(prog, 1, "out of memory");
    for (int i = -1; i < n_in && !rc; i++) {
        if (i >= 0 && lsqt_same_file(in[i], out_lss)) continue;
        int r = lsqt_lock_take(&locks[n_locks], i < 0 ? out_lss : in[i], i < 0, err, sizeof err);
        if (r == 0) n_locks++;
        else if (r == 2 && !quiet) fprintf(stderr, "warning: %s\n", err);
        else if (r == 1) rc = lsqt_prog_error(prog, 1, err); /* -1: writing OUT.lss fails and says why */
    }
    for (int i = 0; i < n_in && !rc; i++) {
        for (int j = 0; j < i && !rc; j++)
            if (lsqt_same_file(in[i], in[j])) {
                snprintf(err, sizeof err, "'%s' is given twice: the same paths cannot be added twice", in[i]);
                rc = lsqt_prog_error(prog, 2, err);
            }
        if (rc) break;
        if (lsqt_lss_read(in[i], &st[i], err, sizeof err)) {
            rc = lsqt_prog_error(prog, 2, err);
            break;
        }
        n_read++;
        if (rc) break;
        const char *what = i ? lsqt_state_differs(&st[0], &st[i]) : NULL;
        if (what) {
            snprintf(err, sizeof err, "'%s' and '%s' differ in their %s: they are not parts of one run", in[0],
                     in[i], what);
            rc = lsqt_prog_error(prog, 2, err);
        }
    }
    /* Disjoint ranges: a path counted twice would be a silent bias. */
    for (int i = 0; i < n_read && !rc; i++)
        for (int j = 0; j < i && !rc; j++)
            for (int x = 0; x < st[i].n_ranges && !rc; x++)
                for (int y = 0; y < st[j].n_ranges && !rc; y++) {
                    uint64_t lo = st[i].ranges[2 * x] > st[j].ranges[2 * y] ? st[i].ranges[2 * x] : st[j].ranges[2 * y];
                    uint64_t hi = st[i].ranges[2 * x + 1] < st[j].ranges[2 * y + 1] ? st[i].ranges[2 * x + 1]
                                                                                     : st[j].ranges[2 * y + 1];
                    if (lo < hi) {
                        snprintf(err, sizeof err,
                                 "'%s' and '%s' both hold paths [%llu, %llu): overlapping parts (the same shard "
                                 "twice, or shards of different runs)",
                                 in[j], in[i], (unsigned long long)lo, (unsigned long long)hi);
                        rc = lsqt_prog_error(prog, 2, err);
                    }
                }
    int total_ranges = 0;
    for (int i = 0; i < n_read; i++) total_ranges += st[i].n_ranges;
    uint64_t *all = rc ? NULL : malloc(((size_t)total_ranges + 1) * 2 * sizeof *all);
    if (!rc && !all) rc = lsqt_prog_error(prog, 1, "out of memory");
    if (!rc) {
        const lsqt_state *f = &st[0];
        if (lsqt_state_init(&sum, f->canonical, f->hash, f->seed, f->n_slices, f->n_wi, f->transmits)) {
            rc = lsqt_prog_error(prog, 1, "out of memory");
        } else {
            sum.use_double = f->use_double, sum.dir_method = f->dir_method, sum.rx = f->rx;
            sum.pilot_paths = f->pilot_paths, sum.stage = f->stage;
            sum.grid_ni = f->grid_ni, sum.grid_nphi = f->grid_nphi;
            memcpy(sum.theta_o, f->theta_o, (size_t)f->n_slices * sizeof *f->theta_o);
            memcpy(sum.slice_flags, f->slice_flags, (size_t)f->n_slices * sizeof *f->slice_flags);
            memcpy(sum.wi, f->wi, (size_t)f->n_slices * (size_t)f->n_wi * 4 * sizeof *f->wi);
            int k = 0;
            for (int i = 0; i < n_read; i++) {
                add_all(sum.nee, st[i].nee, lsqt_state_nee_count(&sum));
                add_all(sum.scalars, st[i].scalars, lsqt_state_scalar_count(&sum));
                add_all(sum.hist, st[i].hist, lsqt_state_hist_count(&sum));
                sum.flags |= st[i].flags;
                if (st[i].span_end > sum.span_end) sum.span_end = st[i].span_end;
                memcpy(all + 2 * k, st[i].ranges, (size_t)st[i].n_ranges * 2 * sizeof *all);
                k += st[i].n_ranges;
            }
            if (lsqt_state_set_ranges(&sum, all, k)) rc = lsqt_prog_error(prog, 1, "out of memory");
        }
    }
    free(all);
    for (int i = 0; i < n_read; i++) lsqt_state_free(&st[i]);
    free(st);
    if (!rc && lsqt_tally_flags_error(sum.flags, err, sizeof err)) rc = lsqt_prog_error(prog, 1, err);

    /* The whole run, or (--partial) what there is. */
    const int pilot = !rc && sum.stage == LSQT_STAGE_PILOT;
    if (!rc) {
        char gaps[512];
        const uint64_t need = pilot ? sum.pilot_paths : sum.span_end;
        int n_missing = missing(sum.ranges, sum.n_ranges, need, gaps, sizeof gaps);
        if (n_missing && (!partial || pilot)) {
            snprintf(err, sizeof err, "the inputs leave out paths %s of the %s [0, %llu): missing shards%s", gaps,
                     pilot ? "RRSS pilot" : "run", (unsigned long long)need,
                     pilot ? " (an RRSS pilot must be whole to choose directions)" : " (--partial writes them anyway)");
            rc = lsqt_prog_error(prog, 2, err);
        } else if (n_missing && !quiet) {
            fprintf(stderr, "note: partial: %s holds %llu of the run's %llu paths per slice; missing %s\n", out_lss,
                    (unsigned long long)sum.paths, (unsigned long long)need, gaps);
        }
    }
    if (pilot) {
        /* the whole pilot: the directions are chosen here, as lsqt-cl does in one process */
        lsqt_state chosen;
        lsqt_rrss_info ri;
        memset(&ri, 0, sizeof ri);
        if (lsqt_rrss_choose(&sum, &chosen, &ri, err, sizeof err)) {
            rc = lsqt_prog_error(prog, 1, err);
        } else {
            if (!quiet) lsqt_rrss_notes(stderr, &ri);
            if (!quiet)
                fprintf(stderr, "RRSS: directions chosen from a pilot of %llu paths per slice; the run owes %llu "
                                "more (run the shards with --refine, then merge)\n",
                        (unsigned long long)chosen.paths, (unsigned long long)(chosen.span_end - chosen.paths));
            lsqt_state_free(&sum);
            sum = chosen;
        }
    }

    /* Outputs: the LSS, the RAW (named from OUT.lss; -H: R and T), JSON, and for a
     * two-sided state the RAW of the side from below (lsqt-cl's names, below.h). */
    if (!rc) {
        enum { O_LSS, O_RAW, O_RAW_T, O_RAW_B, O_RAW_BT, O_JSON, O_N };
        char raw_name[LSQT_PATH_CAP + 16], names[O_N][LSQT_PATH_CAP + 48], below_name[LSQT_PATH_CAP + 32];
        if (raw) snprintf(raw_name, sizeof raw_name, "%s", raw);
        else {
            size_t n = strlen(out_lss);
            if (n >= 4 && strcmp(out_lss + n - 4, ".lss") == 0) n -= 4;
            snprintf(raw_name, sizeof raw_name, "%.*s.raw", (int)n, out_lss);
        }
        lsqt_below_raw_name(raw_name, below_name, sizeof below_name);
        const int two = lsqt_state_below_count(&sum) > 0;
        const char *outs[O_N] = {out_lss, NULL, NULL, NULL, NULL, json};
        for (int side = 0; side < 1 + two; side++) {
            const char *base = side ? below_name : raw_name;
            char *m = names[side ? O_RAW_B : O_RAW], *t = names[side ? O_RAW_BT : O_RAW_T];
            if (hemi) {
                lsqt_raw_hemi_name(base, "R", m, sizeof names[0]);
                lsqt_raw_hemi_name(base, "T", t, sizeof names[0]);
            } else {
                snprintf(m, sizeof names[0], "%s", base);
            }
            outs[side ? O_RAW_B : O_RAW] = m;
            outs[side ? O_RAW_BT : O_RAW_T] = hemi && sum.transmits ? t : NULL;
        }
        if (two && (!raw_name[0] || strcmp(raw_name, "-") == 0))
            rc = lsqt_prog_error(prog, 2, "a two-sided state has a second RAW named from the first: give -o a file name");
        for (int i = 0; i < O_N && !rc; i++)
            for (int j = i + 1; j < O_N && !rc; j++)
                if (outs[i] && outs[j] && lsqt_same_file(outs[i], outs[j])) {
                    snprintf(err, sizeof err, "two outputs would be written to '%s'", outs[i]);
                    rc = lsqt_prog_error(prog, 2, err);
                }
        /* RAW files hold one side each, as lsqt-cl writes them */
        lsqt_state sides[2];
        memset(sides, 0, sizeof sides);
        lsqt_slice_est *est = rc ? NULL : lsqt_estimates(&sum), *side_est[2] = {NULL, NULL};
        if (!rc && !est) rc = lsqt_prog_error(prog, 1, "out of memory");
        if (!rc && two &&
            (lsqt_state_split_sides(&sum, &sides[0], &sides[1]) || !(side_est[0] = lsqt_estimates(&sides[0])) ||
             !(side_est[1] = lsqt_estimates(&sides[1]))))
            rc = lsqt_prog_error(prog, 1, "out of memory");
        int skipped = 0;
        lsqt_run_info ri = {"(merged: no device)", 0.0, 0.0, 0ULL, NULL, lsqt_work_totals(&sum)};
        for (int i = 0; i < O_N && !rc; i++) {
            if (!outs[i]) continue;
            const int b = i == O_RAW_B || i == O_RAW_BT;
            const lsqt_state *rs = two ? &sides[b] : &sum;
            const lsqt_slice_est *re = two ? side_est[b] : est;
            const int mode = !hemi ? LSQT_RAW_ALL : (i == O_RAW || i == O_RAW_B) ? LSQT_RAW_REFLECT : LSQT_RAW_TRANSMIT;
            int w = i == O_LSS    ? lsqt_lss_write(outs[i], &sum, err, sizeof err)
                    : i == O_JSON ? lsqt_report_json(outs[i], &sum, est, &ri, err, sizeof err)
                                  : lsqt_raw_write(outs[i], rs, re, mode, &skipped, err, sizeof err);
            if (w) rc = lsqt_prog_error(prog, 1, err);
        }
        if (!rc && !quiet) {
            FILE *info = (raw && strcmp(raw, "-") == 0) || (json && strcmp(json, "-") == 0) ? stderr : stdout;
            const uint64_t h = lsqt_state_contiguous(&sum);
            char owed[96] = "";
            if (h == UINT64_MAX) snprintf(owed, sizeof owed, " (partial: with gaps)");
            else if (h < sum.span_end)
                snprintf(owed, sizeof owed, " (the run owes %llu more)", (unsigned long long)(sum.span_end - h));
            fprintf(info, "merged %d file%s: %llu paths per slice%s; wrote %s", n_in, n_in > 1 ? "s" : "",
                    (unsigned long long)sum.paths, owed, out_lss);
            for (int i = 1; i < O_N; i++)
                if (outs[i] && strcmp(outs[i], "-") != 0) fprintf(info, ", %s", outs[i]);
            fprintf(info, "\n");
        }
        lsqt_estimates_free(est, sum.n_slices);
        for (int b = 0; b < 2; b++) {
            lsqt_estimates_free(side_est[b], sides[b].n_slices);
            lsqt_state_free(&sides[b]);
        }
    }
    lsqt_state_free(&sum);
    for (int i = 0; i < n_locks; i++) lsqt_lock_release(&locks[i]);
    free(locks);
    free(in);
    return rc;
}
