/* lsqt-cl info / lssinfo: prints what an LSS file holds (format, assembly, settings, and
 * per slice the estimates with their errors), as text or as JSON. It reads the file with
 * lsqt_lss_read, which checks everything, and reduces the tallies with lsqt_estimates,
 * the same code a run uses for its summary: no OpenCL anywhere. */
#include "lsqt/info.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/bands.h"
#include "lsqt/colour.h"
#include "lsqt/lss.h"
#include "lsqt/report.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

/* One line of the canonical assembly, each key=number with the number in its shortest
 * form that reads back to the same double (alpha=0.2, not the stored 0.20000000000000001;
 * the stored text, which the assembly's hash is of, is unchanged: --json gives it). */
static void print_shortest(FILE *f, const char *line, size_t n)
{
    char tok[128], num[40];
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && line[j] != ' ') j++;
        const size_t len = j - i;
        const char *eq = memchr(line + i, '=', len);
        int done = 0;
        if (eq && len < sizeof tok) {
            memcpy(tok, line + i, len);
            tok[len] = '\0';
            const char *v = tok + (eq - (line + i)) + 1;
            char *end = NULL;
            const double d = *v ? strtod(v, &end) : 0.0;
            if (end && *end == '\0' && isfinite(d)) {
                for (int prec = 1; prec <= 17; prec++) {
                    snprintf(num, sizeof num, "%.*g", prec, d);
                    if (strtod(num, NULL) == d) break;
                }
                fprintf(f, " %.*s%s", (int)(v - tok), tok, num);
                done = 1;
            }
        }
        if (!done) fprintf(f, " %.*s", (int)len, line + i);
        i = j;
        while (i < n && line[i] == ' ') i++;
    }
}

static void usage(FILE *f, const char *prog)
{
    fprintf(f,
            "usage: %s FILE.lss [--json PATH [--bsdf]]\n"
            "Prints what an LSS file (the progressive state of lsqt-cl) holds: its format version\n"
            "and layout, the canonical assembly and its hash, seed, precision, slices, incident\n"
            "direction count, device flags, the path ranges it holds, and per slice theta_o, paths,\n"
            "R, T and delta_T with one standard error, the largest relative error of the point\n"
            "estimates and the count of non-finite ones. Needs no OpenCL device.\n"
            "\n"
            "      --json PATH   also write it as JSON (- is stdout; the text then goes to stderr)\n"
            "      --bsdf        the JSON gets every slice's incident directions too, each with\n"
            "                    the BSDF value (1/sr, not cosine-weighted) and its standard error:\n"
            "                    \"bsdf\": [[x, y, z, f, f_err], ...] (y >= 0; the BSDF is mirror\n"
            "                    symmetric in y; null for a value or error not known)\n"
            "  -h, --help        this text\n"
            "      --version     the version and the commit it was built from\n"
            "FILE - reads stdin. Exit status: 0 success, 1 an output could not be written,\n"
            "2 bad flags or a file that is not a readable LSS (missing, not a regular file,\n"
            "corrupt, truncated, another version).\n",
            prog);
}

/* The names of the raised device flags, comma separated ("" when none). */
static void flag_names(uint32_t flags, char *buf, size_t cap, const char *quote)
{
    static const struct {
        uint32_t bit;
        const char *name;
    } known[] = {{LSQT_FLAG_OVERFLOW, "overflow"}, {LSQT_FLAG_NONFINITE, "non-finite"}};
    size_t n = 0;
    buf[0] = '\0';
    uint32_t rest = flags;
    for (size_t i = 0; i < sizeof known / sizeof *known; i++)
        if ((flags & known[i].bit) && n < cap) {
            n += (size_t)snprintf(buf + n, n < cap ? cap - n : 0, "%s%s%s%s", n ? ", " : "", quote, known[i].name,
                                  quote);
            rest &= ~known[i].bit;
        }
    if (rest && n < cap) snprintf(buf + n, cap - n, "%s%sunknown 0x%x%s", n ? ", " : "", quote, rest, quote);
}

/* The path ranges the state holds, [begin, end) of the path indices of every slice: one
 * [0, paths) for a plain run, parts of it for a shard or a partial merge. */
static void info_ranges(FILE *f, const lsqt_state *st, int json)
{
    if (json) {
        fprintf(f, "[");
        for (int i = 0; i < st->n_ranges; i++)
            fprintf(f, "%s[%llu, %llu]", i ? ", " : "", (unsigned long long)st->ranges[2 * i],
                    (unsigned long long)st->ranges[2 * i + 1]);
        fprintf(f, "]");
        return;
    }
    if (!st->n_ranges) fprintf(f, "none (no paths yet)");
    for (int i = 0; i < st->n_ranges; i++)
        fprintf(f, "%s[%llu, %llu)", i ? ", " : "", (unsigned long long)st->ranges[2 * i],
                (unsigned long long)st->ranges[2 * i + 1]);
    if (st->n_ranges) fprintf(f, " on every slice");
    const uint64_t h = lsqt_state_contiguous(st);
    if (h == UINT64_MAX || h < st->span_end)
        fprintf(f, "; part of a run of [0, %llu) (%s)", (unsigned long long)st->span_end,
                h == UINT64_MAX ? "a shard or a partial merge" : "continuing completes it");
}

#define json_num lsqt_json_num

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
        else if (*p == '\n') fputs("\\n", f);
        else if (*p == '\t') fputs("\\t", f);
        else if (*p < 0x20 || *p == 0x7f) fprintf(f, "\\u%04x", *p);
        else fputc(*p, f);
    }
    fputc('"', f);
}

/* The shortest of %.15g, %.16g, %.17g that reads back as v: exact, and 0.3556 rather
 * than 0.35560000000000003. */
static const char *exact(double v, char buf[32])
{
    for (int prec = 15; prec < 17; prec++) {
        snprintf(buf, 32, "%.*g", prec, v);
        if (strtod(buf, NULL) == v) return buf;
    }
    snprintf(buf, 32, "%.17g", v);
    return buf;
}

/* An error as the summary prints it: n/a while it cannot be estimated. */
static const char *err_str(double v, char buf[32])
{
    if (isnan(v)) snprintf(buf, 32, "n/a");
    else snprintf(buf, 32, "%.3g", v);
    return buf;
}

static void print_text(FILE *f, const char *path, const lsqt_state *st, const lsqt_slice_est *est)
{
    char flags[128];
    flag_names(st->flags, flags, sizeof flags, "");
    fprintf(f, "file: %s\n", path);
    fprintf(f, "format: LSS version %u; chunk %d paths, %d batches, %d fixed-point bits, "
               "histogram 2 x %d x %d = %d bins, %d scalar tallies\n",
            st->lss_version, LSQT_CHUNK, LSQT_BATCHES, LSQT_FIX_BITS, LSQT_HIST_NMU, LSQT_HIST_NPHI, LSQT_HIST_BINS,
            LSQT_T_COUNT);
    fprintf(f, "assembly hash: %016llx\n", (unsigned long long)st->hash);
    fprintf(f, "seed: %llu\n", (unsigned long long)st->seed);
    fprintf(f, "precision: %s\n", st->use_double ? "double" : "float");
    fprintf(f, "transmits: %s\n", st->transmits ? "yes (incident directions over the sphere)"
                                                : "no (incident directions over the upper hemisphere)");
    int n_below = 0;
    for (int s = 0; s < st->n_slices; s++) n_below += (st->slice_flags[s] & LSQT_SLICE_BELOW) != 0;
    if (n_below)
        fprintf(f, "slices: %d (%d from above, %d from below: the stack upside down, theta_o from -z), wi per "
                   "slice: %d\n", st->n_slices, st->n_slices - n_below, n_below, st->n_wi);
    else fprintf(f, "slices: %d, wi per slice: %d\n", st->n_slices, st->n_wi);
    if (st->dir_method == LSQT_DIRS_RRSS)
        fprintf(f, "directions: RRSS (%u candidates per direction, pilot of %llu paths)\n", st->rx,
                (unsigned long long)st->pilot_paths);
    else if (st->dir_method == LSQT_DIRS_GRID)
        fprintf(f, "directions: grid (--grid: NI %u, NPHI %u)\n", st->grid_ni, st->grid_nphi);
    else if (st->dir_method == LSQT_DIRS_RGL)
        fprintf(f, "directions: RGL tensor nodes (--rgl-grid: NU %u)\n", st->grid_ni);
    else fprintf(f, "directions: %s\n", st->dir_method == LSQT_DIRS_FILE ? "from a file (--wi-file)" : "even spread");
    if (st->stage == LSQT_STAGE_PILOT)
        fprintf(f, "stage: RRSS pilot (%d slices x %u candidate sets of %d; %llu of its %llu paths; the run: %llu)\n",
                st->n_slices / (int)st->rx, st->rx, st->n_wi, (unsigned long long)st->paths,
                (unsigned long long)st->pilot_paths, (unsigned long long)st->span_end);
    else fprintf(f, "stage: run\n");
    fprintf(f, "paths: %llu per slice\n", (unsigned long long)st->paths);
    const int nb = lsqt_state_bands(st);
    if (nb > 1) {
        fprintf(f, "bands: %d", nb);
        for (int b = 0; st->wavelengths && b < nb; b++) fprintf(f, "%s%.10g", b ? ", " : " at ", st->wavelengths[b]);
        fprintf(f, "%s\n", st->wavelengths ? " nm" : nb == 3 ? " (R, G, B)" : " (unnamed)");
    } else if (st->wavelengths) {
        fprintf(f, "band: one, at %.10g nm\n", st->wavelengths[0]);
    }
    if (st->flags) fprintf(f, "flags: 0x%x (%s)\n", st->flags, flags);
    else fprintf(f, "flags: none\n");
    fprintf(f, "ranges: ");
    info_ranges(f, st, 0);
    fprintf(f, "\nassembly:\n");
    for (const char *p = st->canonical; *p;) {
        const char *nl = strchr(p, '\n');
        size_t n = nl ? (size_t)(nl - p) : strlen(p);
        fputs(" ", f);
        print_shortest(f, p, n);
        fputs("\n", f);
        p += n + (nl ? 1 : 0);
    }
    lsqt_band_names names;
    lsqt_band_names_init(&names, nb, st->wavelengths, NULL);
    for (int s = 0; s < st->n_slices; s++) {
        const lsqt_slice_est *e = &est[s];
        char b[32];
        fprintf(f, "slice %d%s: theta_o %.6g deg (%s rad), %llu paths\n", s,
                st->slice_flags[s] & LSQT_SLICE_BELOW ? " (from below)" : "", e->theta_o * 180.0 / LSQT_PI,
                exact(e->theta_o, b), (unsigned long long)e->paths);
        char u[32];
        for (int k = 0; k < nb; k++) { /* band k's estimates of slice s: est[k * n_slices + s] */
            const lsqt_slice_est *x = e + (size_t)k * (size_t)st->n_slices;
            char lab[48];
            if (nb > 1) fprintf(f, "  band %s\n", lsqt_band_label(&names, k, lab, sizeof lab));
            const char *ind = nb > 1 ? "  " : "";
            fprintf(f, "%s  R       %s +- %s\n", ind, exact(x->R.mean, b), err_str(x->R.err, u));
            fprintf(f, "%s  T       %s +- %s\n", ind, exact(x->T.mean, b), err_str(x->T.err, u));
            fprintf(f, "%s  delta_T %s +- %s\n", ind, exact(x->delta_T.mean, b), err_str(x->delta_T.err, u));
            fprintf(f, "%s  max rel err %s, non-finite %d, paths cut %llu\n", ind, err_str(x->max_rel_err, u),
                    x->n_nonfinite, (unsigned long long)x->cut);
            fprintf(f, "%s  events per path: layers %.6g, media %.6g; next-event evaluations %.17g\n", ind,
                    x->layer_events, x->medium_events, x->nee_evaluations);
        }
    }
}

static int write_json(const char *out, const char *path, const lsqt_state *st, const lsqt_slice_est *est,
                      int bsdf, char *err, size_t errcap)
{
    lsqt_out af;
    if (lsqt_out_open(&af, out, err, errcap)) return -1;
    FILE *f = af.f;
    char flags[160];
    flag_names(st->flags, flags, sizeof flags, "\"");
    fprintf(f, "{\"file\": ");
    json_str(f, path);
    fprintf(f, ", \"version\": %u,\n \"layout\": {\"chunk\": %d, \"batches\": %d, \"fix_bits\": %d, "
               "\"hist_nmu\": %d, \"hist_nphi\": %d, \"hist_bins\": %d, \"t_count\": %d},\n",
            st->lss_version, LSQT_CHUNK, LSQT_BATCHES, LSQT_FIX_BITS, LSQT_HIST_NMU, LSQT_HIST_NPHI, LSQT_HIST_BINS,
            LSQT_T_COUNT);
    fprintf(f, " \"hash\": \"%016llx\", \"seed\": %llu, \"double\": %s, \"transmits\": %s, \"n_slices\": %d, "
               "\"n_wi\": %d, \"paths\": %llu,\n \"directions\": {\"method\": \"%s\", \"rx\": %u, \"pilot_paths\": %llu, "
               "\"grid_ni\": %u, \"grid_nphi\": %u},\n"
               " \"flags\": %u, \"flag_names\": [%s], \"ranges\": ",
            (unsigned long long)st->hash, (unsigned long long)st->seed, st->use_double ? "true" : "false",
            st->transmits ? "true" : "false", st->n_slices, st->n_wi, (unsigned long long)st->paths,
            st->dir_method == LSQT_DIRS_RRSS   ? "rrss"
            : st->dir_method == LSQT_DIRS_FILE ? "file"
            : st->dir_method == LSQT_DIRS_GRID ? "grid"
            : st->dir_method == LSQT_DIRS_RGL  ? "rgl_grid"
                                               : "spread",
            st->rx, (unsigned long long)st->pilot_paths, st->grid_ni, st->grid_nphi, st->flags, flags);
    info_ranges(f, st, 1);
    fprintf(f, ", \"span_end\": %llu, \"stage\": \"%s\"", (unsigned long long)st->span_end,
            st->stage == LSQT_STAGE_PILOT ? "rrss-pilot" : "run");
    lsqt_json_bands(f, st);
    fprintf(f, ",\n \"assembly\": ");
    json_str(f, st->canonical);
    fprintf(f, ",\n \"slices\": [");
    for (int s = 0; s < st->n_slices; s++) {
        fprintf(f, "%s\n  ", s ? "," : "");
        lsqt_json_slice_fields(f, st, &est[s], s, 1);
        if (!bsdf) {
            fprintf(f, "}");
            continue;
        }
        fprintf(f, ",\n   \"bsdf\": [");
        for (int k = 0; k < st->n_wi; k++) {
            const float *w = st->wi + ((size_t)s * (size_t)st->n_wi + (size_t)k) * 4;
            fprintf(f, "%s[%.9g, %.9g, %.9g", k ? ", " : "", w[0], w[1], w[2]);
            /* with bands: [x, y, z, [value per band], [error per band]] */
            const int nb = lsqt_state_bands(st);
            for (int part = 0; part < 2; part++) {
                fprintf(f, ", %s", nb > 1 ? "[" : "");
                for (int b = 0; b < nb; b++) {
                    const lsqt_est *v = &est[(size_t)b * (size_t)st->n_slices + (size_t)s].f[k];
                    if (b) fprintf(f, ", ");
                    json_num(f, part ? v->err : v->mean);
                }
                if (nb > 1) fprintf(f, "]");
            }
            fprintf(f, "]");
        }
        fprintf(f, "]}");
    }
    fprintf(f, "\n ]}\n");
    return lsqt_out_commit(&af, err, errcap);
}

int lsqt_info_main(const char *prog, int argc, char **argv)
{
    /* A closed pipe is a write error to report, not a silent death. */
    signal(SIGPIPE, SIG_IGN);
    const char *input = NULL, *json = NULL;
    int bsdf = 0;
    char msg[LSQT_PATH_CAP + 1024];
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout, prog);
            return 0;
        }
        if (strcmp(a, "--version") == 0) {
            printf("%s %s\n", prog, lsqt_version());
            return 0;
        }
        if (strcmp(a, "--json") == 0 || strncmp(a, "--json=", 7) == 0) {
            const char *v = a[6] == '=' ? a + 7 : i + 1 < argc ? argv[++i] : NULL;
            if (!v) snprintf(msg, sizeof msg, "--json needs a value");
            else if (!*v) snprintf(msg, sizeof msg, "bad value '' for --json: expected a file name");
            else if (json) snprintf(msg, sizeof msg, "--json given twice");
            else {
                json = v;
                continue;
            }
        } else if (strcmp(a, "--bsdf") == 0) {
            bsdf = 1;
            continue;
        } else if (a[0] == '-' && a[1] != '\0') {
            snprintf(msg, sizeof msg, "unknown option '%.64s'", a);
        } else if (input) {
            snprintf(msg, sizeof msg, "more than one file: '%.200s' and '%.200s'", input, a);
        } else {
            input = a;
            continue;
        }
        fprintf(stderr, "%s: error: %s\n", prog, msg);
        usage(stderr, prog);
        return 2;
    }
    if (bsdf && !json) {
        fprintf(stderr, "%s: error: --bsdf adds to the JSON: give --json PATH too\n", prog);
        return 2;
    }
    if (!input) {
        fprintf(stderr, "%s: error: no LSS file given\n", prog);
        usage(stderr, prog);
        return 2;
    }

    /* Only a regular file (or stdin, "-") is read: lsqt_lss_read's rule for every program. */
    const int from_stdin = strcmp(input, "-") == 0;
    if (json && !from_stdin && strcmp(json, "-") != 0 && lsqt_same_file(json, input)) {
        snprintf(msg, sizeof msg, "the JSON output '%s' would replace the input", json);
        return lsqt_prog_error(prog, 2, msg);
    }
    lsqt_state st;
    if (lsqt_lss_read(input, &st, msg, sizeof msg)) return lsqt_prog_error(prog, 2, msg);
    lsqt_slice_est *est = lsqt_estimates(&st);
    if (!est) {
        lsqt_state_free(&st);
        return lsqt_prog_error(prog, 1, "out of memory");
    }
    const char *name = from_stdin ? "<stdin>" : input;
    FILE *text = json && strcmp(json, "-") == 0 ? stderr : stdout;
    print_text(text, name, &st, est);
    int rc = 0;
    if (fflush(text) != 0 || ferror(text)) {
        snprintf(msg, sizeof msg, "cannot write to %s: %s", text == stdout ? "stdout" : "stderr", strerror(errno));
        rc = lsqt_prog_error(prog, 1, msg);
    }
    if (json && write_json(json, name, &st, est, bsdf, msg, sizeof msg)) rc = lsqt_prog_error(prog, 1, msg);
    lsqt_estimates_free(est, st.n_slices);
    lsqt_state_free(&st);
    return rc;
}
