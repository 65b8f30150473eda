#include "lsqt/report.h"

#include <math.h>
#include <stddef.h>

#include "lsqt/util.h"

/* An error for the summary: "n/a" while it cannot be estimated. */
static const char *err_text(double v, char *buf, size_t cap)
{
    if (isnan(v)) snprintf(buf, cap, "n/a");
    else snprintf(buf, cap, "%.2g", v);
    return buf;
}

/* "band 2 (550 nm)" / "band 2 (G)" / "band 2" */
static const char *band_text(const lsqt_state *st, int b, char *buf, size_t cap)
{
    if (st->wavelengths) snprintf(buf, cap, "band %d (%g nm)", b + 1, st->wavelengths[b]);
    else if (st->n_bands == 3) snprintf(buf, cap, "band %d (%c)", b + 1, "RGB"[b]);
    else snprintf(buf, cap, "band %d", b + 1);
    return buf;
}

void lsqt_report_summary(FILE *f, const lsqt_state *st, const lsqt_slice_est *est,
                         const lsqt_run_info *ri)
{
    fprintf(f, "device: %s%s\n", ri->device, st->use_double ? " (double)" : "");
    fprintf(f, "paths: %llu added per slice (%llu per slice in all) in %.3g s: %.4g paths/s\n",
            ri->paths_added, (unsigned long long)st->paths, ri->seconds, ri->paths_per_second);
    const int nbands = lsqt_state_bands(st);
    /* Many bands: one line a band (a spectrum of 32 printed 452 lines); -v, or lsqt-cl
     * info, gives every band's table. */
    const int compact = nbands > LSQT_SUMMARY_BANDS && !ri->all_bands;
    unsigned long long cut = 0;
    int nonfinite = 0, no_err = 0, n_below = 0;
    if (compact)
        fprintf(f, "%d bands, over the slices (every slice's table: -v, or lsqt-cl info FILE.lss):\n"
                   "%-18s %-22s %-22s %s\n", nbands, "band", "R min .. max", "T min .. max", "max rel err");
    double r0 = INFINITY, r1 = -INFINITY, t0 = INFINITY, t1 = -INFINITY, m = 0; /* a band's, compact */
    for (int i = 0; i < nbands * st->n_slices; i++) {
        const int s = i % st->n_slices;
        const lsqt_slice_est *e = &est[i];
        char bt[64], er[32], et[32], em[32];
        const int below = (st->slice_flags[s] & LSQT_SLICE_BELOW) != 0;
        n_below += below && i < st->n_slices;
        if (isnan(e->max_rel_err)) no_err = 1;
        cut += e->cut;
        nonfinite += e->n_nonfinite;
        if (compact) {
            if (s == 0) r0 = t0 = INFINITY, r1 = t1 = -INFINITY, m = 0;
            r0 = fmin(r0, e->R.mean), r1 = fmax(r1, e->R.mean);
            t0 = fmin(t0, e->T.mean), t1 = fmax(t1, e->T.mean);
            m = isnan(e->max_rel_err) || isnan(m) ? NAN : fmax(m, e->max_rel_err);
            if (s == st->n_slices - 1)
                fprintf(f, "%-18s %.6f .. %.6f  %.6f .. %.6f  %s\n", band_text(st, i / st->n_slices, bt, sizeof bt),
                        r0, r1, t0, t1, isnan(m) ? "n/a" : (snprintf(em, sizeof em, "%.3g", m), em));
            continue;
        }
        if (s == 0 && nbands > 1) fprintf(f, "%s:\n", band_text(st, i / st->n_slices, bt, sizeof bt));
        if (s == 0)
            fprintf(f, "%5s %9s  %-21s %-21s %-10s %s\n", "slice", "theta_o", "R +- 1 s.e.", "T +- 1 s.e.",
                    "delta_T", "max rel err");
        fprintf(f, "%5d %8.3fd  %.6f +- %-9s %.6f +- %-9s %-10.4g %s%s\n", s, e->theta_o * 180.0 / LSQT_PI,
                e->R.mean, err_text(e->R.err, er, sizeof er), e->T.mean, err_text(e->T.err, et, sizeof et),
                e->delta_T.mean, isnan(e->max_rel_err) ? "n/a" : (snprintf(em, sizeof em, "%.3g", e->max_rel_err), em),
                below ? "  from below" : "");
    }
    for (int s = 0; s < nbands * st->n_slices; s++)
        if (est[s].delta_T.mean > 0) {
            fprintf(f, "note: unscattered light (delta_T) is a forward delta; it is in T and LSS, not in RAW\n");
            break;
        }
    if (n_below)
        fprintf(f, "note: slices 'from below' are of light entering from the bottom medium, seen with the stack "
                   "upside down (theta_o from -z; R is what goes back down); their RAW is OUT.below.raw\n");
    if (no_err)
        fprintf(f, "note: errors need paths in 2 of the %d batches (more than %d paths per slice): n/a\n",
                LSQT_BATCHES, LSQT_CHUNK);
    if (ri->stopped_by) fprintf(f, "stopped by %s\n", ri->stopped_by);
    if (ri->target_error > 0 && ri->max_rel_err <= ri->target_error)
        fprintf(f, "target error %g: met (largest relative error %.3g)\n", ri->target_error, ri->max_rel_err);
    else if (ri->target_error > 0 && ri->paths_needed)
        fprintf(f, "target error %g: not met (largest relative error %.3g); about %llu paths per slice in all "
                   "would reach it (1/sqrt(paths)): continue with --total-paths %llu\n",
                ri->target_error, ri->max_rel_err, ri->paths_needed, ri->paths_needed);
    else if (ri->target_error > 0)
        fprintf(f, "target error %g: not met (not judged yet: the largest error counts from %llu paths per "
                   "slice on)\n", ri->target_error, (unsigned long long)LSQT_STOP_ERR_PATHS);
    const lsqt_work *w = &ri->work;
    if (w->paths > 0) {
        double ev = w->layer_events + w->medium_events;
        fprintf(f, "work: %.4g events per path (layers %.4g, media %.4g), %.4g events/s, %.4g next-event "
                   "evaluations/s\n", ev / w->paths, w->layer_events / w->paths, w->medium_events / w->paths,
                ri->seconds > 0 ? ev / ri->seconds : 0.0, ri->seconds > 0 ? w->nee_evaluations / ri->seconds : 0.0);
    }
    if (cut) fprintf(f, "warning: %llu paths reached the safety cap of %d events and were stopped\n", cut, LSQT_MAX_EVENTS);
    if (nonfinite) fprintf(f, "warning: %d non-finite estimates were left out of RAW\n", nonfinite);
    if (st->flags & LSQT_FLAG_NONFINITE) fprintf(f, "warning: non-finite path contributions were dropped\n");
}

void lsqt_json_num(FILE *f, double v)
{
    if (isfinite(v)) fprintf(f, "%.17g", v);
    else fprintf(f, "null");
}
#define json_num lsqt_json_num

/* ", "NAME": mean, "NAME_err": err" */
static void json_est(FILE *f, const char *name, lsqt_est v)
{
    fprintf(f, ", \"%s\": ", name);
    json_num(f, v.mean);
    fprintf(f, ", \"%s_err\": ", name);
    json_num(f, v.err);
}

void lsqt_json_bands(FILE *f, const lsqt_state *st)
{
    fprintf(f, ",\n \"bands\": %d, \"wavelengths\": ", lsqt_state_bands(st));
    if (!st->wavelengths) fprintf(f, "null");
    for (int b = 0; st->wavelengths && b < st->n_bands; b++) fprintf(f, "%s%.17g", b ? ", " : "[", st->wavelengths[b]);
    if (st->wavelengths) fprintf(f, "]");
}

void lsqt_json_slice(FILE *f, const lsqt_state *st, const lsqt_slice_est *e, int s, int detail)
{
    lsqt_json_slice_fields(f, st, e, s, detail);
    fprintf(f, "}");
}

/* ", NAME": a number, or with bands a list of one per band (e[b * stride]); which: 0 mean,
 * 1 err of the lsqt_est at byte offset off; 2 max_rel_err. */
static void json_band_list(FILE *f, const char *name, const lsqt_slice_est *e, int nbands, size_t stride,
                           size_t off, int which)
{
    fprintf(f, ", \"%s\": %s", name, nbands > 1 ? "[" : "");
    for (int b = 0; b < nbands; b++) {
        const lsqt_slice_est *x = e + (size_t)b * stride;
        const lsqt_est *v = (const lsqt_est *)(const void *)((const char *)x + off);
        if (b) fprintf(f, ", ");
        json_num(f, which == 2 ? x->max_rel_err : which ? v->err : v->mean);
    }
    if (nbands > 1) fprintf(f, "]");
}

void lsqt_json_slice_fields(FILE *f, const lsqt_state *st, const lsqt_slice_est *e, int s, int detail)
{
    /* with bands, e[b * n_slices] is band b's estimate of this slice */
    const int nb = lsqt_state_bands(st);
    const size_t ns = (size_t)st->n_slices;
    fprintf(f, "{\"theta_o\": %.17g, \"paths\": %llu", e->theta_o, (unsigned long long)e->paths);
    if (nb == 1) {
        json_est(f, "R", e->R);
        json_est(f, "T", e->T);
        json_est(f, "delta_T", e->delta_T);
    } else {
        static const char *const names[] = {"R", "R_err", "T", "T_err", "delta_T", "delta_T_err"};
        const size_t offs[] = {offsetof(lsqt_slice_est, R), offsetof(lsqt_slice_est, T),
                               offsetof(lsqt_slice_est, delta_T)};
        for (int i = 0; i < 6; i++) json_band_list(f, names[i], e, nb, ns, offs[i / 2], i % 2);
    }
    json_band_list(f, "max_rel_err", e, nb, ns, 0, 2);
    lsqt_slice_est sum = *e; /* the counters of every band's walks */
    for (int b = 1; b < nb; b++) {
        const lsqt_slice_est *x = e + (size_t)b * ns;
        sum.n_nonfinite += x->n_nonfinite, sum.cut += x->cut, sum.layer_events += x->layer_events;
        sum.medium_events += x->medium_events, sum.nee_evaluations += x->nee_evaluations;
    }
    if (detail) fprintf(f, ", \"n_nonfinite\": %d", sum.n_nonfinite);
    fprintf(f, ", \"cut_paths\": %llu", (unsigned long long)sum.cut);
    if (detail) {
        fprintf(f, ", \"layer_events_per_path\": ");
        json_num(f, sum.layer_events);
        fprintf(f, ", \"medium_events_per_path\": ");
        json_num(f, sum.medium_events);
        fprintf(f, ", \"nee_evaluations\": %.17g", sum.nee_evaluations);
    }
    fprintf(f, ", \"from_below\": %s", st->slice_flags[s] & LSQT_SLICE_BELOW ? "true" : "false");
}

int lsqt_report_json(const char *path, const lsqt_state *st, const lsqt_slice_est *est,
                     const lsqt_run_info *ri, lsqt_out_set *hold, char *err, size_t errcap)
{
    lsqt_out af;
    if (lsqt_out_open(&af, path, err, errcap)) return -1;
    FILE *f = af.f;
    fprintf(f, "{\"device\": \"");
    for (const char *p = ri->device; *p; p++) {
        if (*p == '"' || *p == '\\') fputc('\\', f);
        if ((unsigned char)*p >= 0x20) fputc(*p, f);
    }
    fprintf(f, "\", \"double\": %s, \"seed\": %llu, \"seconds\": ", st->use_double ? "true" : "false",
            (unsigned long long)st->seed);
    json_num(f, ri->seconds);
    fprintf(f, ", \"paths_per_second\": ");
    json_num(f, ri->paths_per_second);
    fprintf(f, ", \"assembly_hash\": \"%016llx\", \"flags\": %u, \"paths_added\": %llu, \"stopped_by\": ",
            (unsigned long long)st->hash, st->flags, ri->paths_added);
    if (ri->stopped_by) fprintf(f, "\"%s\"", ri->stopped_by);
    else fprintf(f, "null");
    fprintf(f, ", \"target_error\": ");
    json_num(f, ri->target_error > 0 ? ri->target_error : NAN);
    fprintf(f, ", \"target_met\": %s, \"paths_needed\": ",
            !(ri->target_error > 0) ? "null" : ri->max_rel_err <= ri->target_error ? "true" : "false");
    if (ri->target_error > 0 && ri->paths_needed) fprintf(f, "%llu", ri->paths_needed);
    else fprintf(f, "null");
    const lsqt_work *w = &ri->work;
    const double ev = w->layer_events + w->medium_events, np = w->paths > 0 ? w->paths : NAN;
    const double sec = ri->seconds > 0 ? ri->seconds : NAN;
    fprintf(f, ",\n \"events_per_path\": ");
    json_num(f, ev / np);
    fprintf(f, ", \"layer_events_per_path\": ");
    json_num(f, w->layer_events / np);
    fprintf(f, ", \"medium_events_per_path\": ");
    json_num(f, w->medium_events / np);
    fprintf(f, ", \"events_per_second\": ");
    json_num(f, ev / sec);
    fprintf(f, ", \"nee_evaluations\": %.17g, \"nee_evaluations_per_second\": ", w->nee_evaluations);
    json_num(f, w->nee_evaluations / sec);
    lsqt_json_bands(f, st);
    fprintf(f, ",\n \"slices\": [");
    for (int s = 0; s < st->n_slices; s++) {
        fprintf(f, "%s\n  ", s ? "," : "");
        lsqt_json_slice(f, st, &est[s], s, 0);
    }
    fprintf(f, "\n ]}\n");
    return hold ? lsqt_out_hold(&af, hold, err, errcap) : lsqt_out_commit(&af, err, errcap);
}
