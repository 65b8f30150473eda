/* Two-sided BSDFs (below.h): the mirrored assembly, states of one side each, and the runs
 * of both sides on the same paths. */
#include "lsqt/below.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/tally.h"
#include "lsqt/util.h"

/* A model's mirror image is itself when it treats light from either side alike (MIRROR in
 * include/lsqt/model_list.h, which says why for each):
 *  - Null, Lambertian (fR back to the side light came from, fT through, either side);
 *  - the microsurfaces: their walks run in the frame of the ray's side (microsurface.cl
 *    ms_walk flips z, and the uniform heights with c -> 1 - c), GGX slopes are symmetric,
 *    and the dielectric takes the relative index seen from that side, which the device
 *    tables make from the media on each side, so reversing the media mirrors it too;
 *  - phase functions of the scattering angle alone (HG, HG2, Rayleigh, Draine), and SGGX,
 *    whose S = diag(Apara^2, Apara^2, Aperp^2) has no xz or yz terms.
 * The conductor and Oren-Nayar never transmit (a stack with them sends nothing down), so
 * light from below never meets them from above: no mirror is needed nor offered. */
static int layer_self_mirror(int kind)
{
#define MIRRORS(ID, num, name, alias, prefix, sampler, mirror, ...) || (kind == LSQT_BSDF_##ID && mirror)
    return kind == LSQT_BSDF_NULL LSQT_BSDFS(MIRRORS);
#undef MIRRORS
}

static int phase_self_mirror(int kind)
{
#define MIRRORS(ID, num, name, alias, prefix, sampler, mirror) || (kind == LSQT_PHASE_##ID && mirror)
    return kind == LSQT_PHASE_NONE LSQT_PHASES(MIRRORS);
#undef MIRRORS
}

/* A's stack upside down, without checks. Returns 0, or 2 out of memory. */
static int mirror_one(const lsqt_assembly *a, lsqt_assembly *out)
{
    memset(out, 0, sizeof *out);
    const int n = a->n_layers;
    out->layers = calloc((size_t)(n > 0 ? n : 1), sizeof *out->layers);
    out->media = calloc((size_t)n + 1, sizeof *out->media);
    if (!out->layers || !out->media) {
        lsqt_assembly_free(out);
        return 2;
    }
    out->n_layers = n;
    out->n_pruned_layers = a->n_pruned_layers;
    for (int i = 0; i < n; i++) {
        out->layers[i] = a->layers[n - 1 - i];
        out->layers[i].z = 0.0 - a->layers[n - 1 - i].z; /* 0.0 - 0.0 is +0: no "-0" in the text */
    }
    for (int m = 0; m <= n; m++) out->media[m] = a->media[n - m];
    if (lsqt_phase_tables_copy(a, out)) { /* the media's tables (their numbers stay) */
        lsqt_assembly_free(out);
        return 2;
    }
    return 0;
}

/* Layer i lets light through in some band. */
static int layer_transmits_any(const lsqt_assembly *a, int i)
{
    for (int b = 0; b < lsqt_assembly_bands(a); b++)
        if (lsqt_layer_transmits(&lsqt_assembly_band(a, b)->layers[i])) return 1;
    return 0;
}

int lsqt_assembly_mirror(const lsqt_assembly *a, lsqt_assembly *out, char *err, size_t errcap)
{
    memset(out, 0, sizeof *out);
    const int n = a->n_layers;
    for (int i = 0; i < n; i++)
        if (!layer_transmits_any(a, i)) {
            snprintf(err, errcap, "line %d: %s transmits nothing, so light from below never reaches what lies "
                                  "above it", a->layers[i].line, lsqt_bsdf_name(a->layers[i].kind));
            return 2;
        }
    for (int i = 0; i < n; i++)
        if (!layer_self_mirror(a->layers[i].kind)) {
            snprintf(err, errcap, "line %d: %s has no mirror image (light from below) that lsqt-cl can express",
                     a->layers[i].line, lsqt_bsdf_name(a->layers[i].kind));
            return 2;
        }
    /* a phase model is kept only where the medium scatters (in some band) */
    for (int m = 0; m <= n; m++)
        if (!phase_self_mirror(a->media[m].phase.kind)) {
            snprintf(err, errcap, "line %d: %s has no mirror image (light from below) that lsqt-cl can express",
                     a->media[m].line, lsqt_phase_name(a->media[m].phase.kind));
            return 2;
        }
    const int nb = a->n_bands > 1 ? a->n_bands : 0;
    lsqt_assembly *each = nb ? calloc((size_t)nb, sizeof *each) : NULL;
    int rc = nb && !each ? 2 : 0;
    for (int b = 0; b < nb && !rc; b++) rc = mirror_one(&a->band[b], &each[b]);
    if (!rc) rc = nb ? lsqt_assembly_join(each, nb, a->wavelengths, out) : mirror_one(a, out);
    if (rc) {
        for (int b = 0; each && b < nb; b++) lsqt_assembly_free(&each[b]);
        snprintf(err, errcap, "out of memory");
    }
    free(each);
    return rc;
}

int lsqt_state_below_count(const lsqt_state *st)
{
    int k = 0;
    for (int s = 0; s < st->n_slices; s++) k += (st->slice_flags[s] & LSQT_SLICE_BELOW) != 0;
    return k;
}

/* OUT: N slices (zero), every setting and the ranges of ST. */
static int init_like(lsqt_state *out, const lsqt_state *st, int n)
{
    if (lsqt_state_init_bands(out, st->canonical, st->hash, st->seed, n, st->n_wi, st->transmits, st->n_bands,
                              st->wavelengths))
        return -1;
    if (st->hist_pk && lsqt_state_pack_hist(out, 1)) { /* as ST holds them */
        lsqt_state_free(out);
        return -1;
    }
    out->use_double = st->use_double;
    out->span_end = st->span_end;
    out->stage = st->stage;
    out->flags = st->flags;
    out->dir_method = st->dir_method;
    out->grid_ni = st->grid_ni, out->grid_nphi = st->grid_nphi;
    out->rx = st->rx;
    out->pilot_paths = st->pilot_paths;
    if (lsqt_state_set_ranges(out, st->ranges, st->n_ranges)) {
        lsqt_state_free(out);
        return -1;
    }
    return 0;
}

/* Slice ss of SRC (direction, flags, tallies) as slice ds of DST (same n_wi). Returns 0
 * or -1 (out of memory). */
static int copy_slice(lsqt_state *dst, int ds, const lsqt_state *src, int ss)
{
    const size_t nw = (size_t)src->n_wi;
    dst->theta_o[ds] = src->theta_o[ss];
    dst->slice_flags[ds] = src->slice_flags[ss];
    memcpy(dst->wi + (size_t)ds * nw * 4, src->wi + (size_t)ss * nw * 4, nw * 4 * sizeof *src->wi);
    return lsqt_state_copy_slice_tallies(dst, ds, src, ss);
}

int lsqt_state_split_sides(const lsqt_state *st, lsqt_state *above, lsqt_state *below)
{
    const int nb = lsqt_state_below_count(st), na = st->n_slices - nb;
    if (init_like(above, st, na)) return -1;
    if (init_like(below, st, nb)) {
        lsqt_state_free(above);
        return -1;
    }
    int ia = 0, ib = 0, rc = 0;
    for (int s = 0; s < st->n_slices && !rc; s++) {
        if (st->slice_flags[s] & LSQT_SLICE_BELOW) rc = copy_slice(below, ib++, st, s);
        else rc = copy_slice(above, ia++, st, s);
    }
    if (rc) {
        lsqt_state_free(above);
        lsqt_state_free(below);
    }
    return rc;
}

int lsqt_state_join_sides(const lsqt_state *above, const lsqt_state *below, lsqt_state *out, char *err,
                          size_t errcap)
{
    const char *diff = NULL;
    if (above->hash != below->hash || strcmp(above->canonical, below->canonical) != 0) diff = "assembly";
    else if (above->seed != below->seed) diff = "seed";
    else if (above->n_wi != below->n_wi || above->transmits != below->transmits) diff = "direction count";
    else if (above->use_double != below->use_double) diff = "precision";
    else if (above->n_ranges != below->n_ranges ||
             (above->n_ranges &&
              memcmp(above->ranges, below->ranges, (size_t)above->n_ranges * 2 * sizeof *above->ranges) != 0) ||
             above->span_end != below->span_end || above->stage != below->stage)
        diff = "paths";
    else if (above->dir_method != below->dir_method || above->rx != below->rx ||
             above->pilot_paths != below->pilot_paths || above->grid_ni != below->grid_ni ||
             above->grid_nphi != below->grid_nphi)
        diff = "direction method";
    if (diff) {
        snprintf(err, errcap, "the sides from above and from below differ in their %s", diff);
        return 1;
    }
    if (init_like(out, above, above->n_slices + below->n_slices)) {
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    out->flags |= below->flags;
    int rc = 0;
    for (int s = 0; s < above->n_slices && !rc; s++) rc = copy_slice(out, s, above, s);
    for (int s = 0; s < below->n_slices && !rc; s++) rc = copy_slice(out, above->n_slices + s, below, s);
    if (rc) {
        lsqt_state_free(out);
        snprintf(err, errcap, "out of memory");
    }
    return rc;
}

int lsqt_state_add_below(lsqt_state *st)
{
    lsqt_state dn, both;
    char err[128];
    if (init_like(&dn, st, st->n_slices)) return -1;
    for (int s = 0; s < st->n_slices; s++) {
        if (copy_slice(&dn, s, st, s)) {
            lsqt_state_free(&dn);
            return -1;
        }
        dn.slice_flags[s] |= LSQT_SLICE_BELOW;
    }
    int rc = lsqt_state_join_sides(st, &dn, &both, err, sizeof err);
    lsqt_state_free(&dn);
    if (rc) return -1;
    lsqt_state_free(st);
    *st = both;
    return 0;
}

void lsqt_below_raw_name(const char *raw, char *dst, size_t cap)
{
    size_t n = strlen(raw);
    if (n >= 4 && strcmp(raw + n - 4, ".raw") == 0) n -= 4;
    snprintf(dst, cap, "%.*s.below.raw", (int)n, raw);
}

/* The two sides of ST and the mirrored assembly (for a two-sided ST; 0 done, else err). */
typedef struct sides {
    lsqt_state up, dn;
    lsqt_assembly mirror;
} sides;

static int sides_open(sides *sd, const lsqt_assembly *a, const lsqt_state *st, char *err, size_t errcap)
{
    memset(sd, 0, sizeof *sd);
    if (lsqt_assembly_mirror(a, &sd->mirror, err, errcap)) return 1;
    if (lsqt_state_split_sides(st, &sd->up, &sd->dn)) {
        lsqt_assembly_free(&sd->mirror);
        snprintf(err, errcap, "out of memory");
        return 1;
    }
    return 0;
}

/* Joins the sides into ST (on success) and frees them. */
static int sides_close(sides *sd, lsqt_state *st, int ok, char *err, size_t errcap)
{
    int rc = ok ? 0 : 1;
    if (ok) {
        lsqt_state both;
        if (lsqt_state_join_sides(&sd->up, &sd->dn, &both, err, errcap)) rc = 1;
        else {
            lsqt_state_free(st);
            *st = both;
        }
    }
    lsqt_state_free(&sd->up);
    lsqt_state_free(&sd->dn);
    lsqt_assembly_free(&sd->mirror);
    return rc;
}

/* Both sides of a pilot state PS (or of the fresh ST) on the same paths: the side from
 * above may be stopped; the side from below then runs as many, unstopped. Checkpoints
 * are off (one side's pilot is not the state); an interrupt saves the joined pilot. */
static int pilot_sides(lsqt_context *cx, const lsqt_assembly *a, const lsqt_state *st, lsqt_state *ps, int rx,
                       uint64_t pilot_total, uint64_t run_paths, uint64_t begin, uint64_t n_paths,
                       const lsqt_sim_opts *o, lsqt_rrss_info *info, char *err, size_t errcap)
{
    const int fresh = st != NULL;
    sides sd;
    if (sides_open(&sd, a, fresh ? st : ps, err, errcap)) return 1;
    lsqt_sim_opts po = *o;
    po.checkpoint = NULL;
    lsqt_sim_opts ob = po;
    ob.stop = NULL, ob.time_limit = 0.0;
    lsqt_state pu, pd;
    memset(&pu, 0, sizeof pu), memset(&pd, 0, sizeof pd);
    lsqt_rrss_info ib;
    int ok;
    if (fresh) {
        ok = !lsqt_rrss_pilot(cx, a, &sd.up, rx, pilot_total, run_paths, begin, n_paths, &po, &pu, info, err, errcap);
        ok = ok && !lsqt_rrss_pilot(cx, &sd.mirror, &sd.dn, rx, pilot_total, run_paths, begin, pu.paths, &ob, &pd,
                                    &ib, err, errcap);
    } else {
        const uint64_t had = sd.up.paths;
        ok = !lsqt_rrss_pilot_continue(cx, a, &sd.up, begin, n_paths, &po, info, err, errcap);
        ok = ok && !lsqt_rrss_pilot_continue(cx, &sd.mirror, &sd.dn, begin, sd.up.paths - had, &ob, &ib, err, errcap);
    }
    if (ok) info->short_slices += ib.short_slices, info->seconds += ib.seconds;
    lsqt_state both;
    if (ok && lsqt_state_join_sides(fresh ? &pu : &sd.up, fresh ? &pd : &sd.dn, &both, err, errcap)) ok = 0;
    if (ok) {
        if (!fresh) lsqt_state_free(ps);
        *ps = both;
    }
    lsqt_state_free(&pu), lsqt_state_free(&pd);
    lsqt_state_free(&sd.up), lsqt_state_free(&sd.dn);
    lsqt_assembly_free(&sd.mirror);
    return ok ? 0 : 1;
}

int lsqt_rrss_pilot_sides(lsqt_context *cx, const lsqt_assembly *a, const lsqt_state *st, int rx, uint64_t pilot_total,
                          uint64_t run_paths, uint64_t begin, uint64_t n_paths, const lsqt_sim_opts *o, lsqt_state *ps,
                          lsqt_rrss_info *info, char *err, size_t errcap)
{
    if (!lsqt_state_below_count(st))
        return lsqt_rrss_pilot(cx, a, st, rx, pilot_total, run_paths, begin, n_paths, o, ps, info, err, errcap);
    memset(info, 0, sizeof *info);
    memset(ps, 0, sizeof *ps);
    return pilot_sides(cx, a, st, ps, rx, pilot_total, run_paths, begin, n_paths, o, info, err, errcap);
}

int lsqt_rrss_pilot_continue_sides(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *ps, uint64_t begin,
                                   uint64_t n_paths, const lsqt_sim_opts *o, lsqt_rrss_info *info, char *err,
                                   size_t errcap)
{
    if (!lsqt_state_below_count(ps)) return lsqt_rrss_pilot_continue(cx, a, ps, begin, n_paths, o, info, err, errcap);
    memset(info, 0, sizeof *info);
    return pilot_sides(cx, a, NULL, ps, (int)ps->rx, ps->pilot_paths, ps->span_end, begin, n_paths, o, info, err,
                       errcap);
}

int lsqt_simulate_sides(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t add_paths,
                        const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap)
{
    return lsqt_simulate_range_sides(cx, a, st, lsqt_state_contiguous(st), add_paths, o, stats, err, errcap);
}

/* The largest relative error over both sides (NaN if either is NaN). */
static double sides_err(const sides *sd)
{
    double x = lsqt_max_rel_err(&sd->up), y = lsqt_max_rel_err(&sd->dn);
    return isnan(x) || isnan(y) ? NAN : x > y ? x : y;
}

static int sides_checkpoint(const sides *sd, const lsqt_sim_opts *o)
{
    lsqt_state both;
    char e[128];
    if (lsqt_state_join_sides(&sd->up, &sd->dn, &both, e, sizeof e)) return 1;
    int rc = o->checkpoint(&both, o->checkpoint_ctx);
    lsqt_state_free(&both);
    return rc;
}

/* The options of each side's launches: the stop rules, progress and checkpoints are
 * applied between segments (lsqt_simulate_range_sides), and only the side from above
 * (oa) may be cut short by a signal; the side from below (ob) runs the same paths. */
static void side_opts(const lsqt_sim_opts *o, lsqt_sim_opts *oa, lsqt_sim_opts *ob)
{
    *oa = *o;
    oa->progress = 0, oa->time_limit = 0.0, oa->target_error = 0.0, oa->checkpoint = NULL, oa->verbose = 0;
    *ob = *oa;
    ob->stop = NULL;
}

/* The next segment's paths per slice, after one that took dt seconds. */
static uint64_t next_segment(uint64_t seg, double dt)
{
    double grow = dt > 0 ? 1.0 / dt : 4.0; /* segments of about a second */
    grow = grow > 4.0 ? 4.0 : grow < 0.5 ? 0.5 : grow;
    seg = (uint64_t)((double)seg * grow);
    return seg < LSQT_CHUNK ? LSQT_CHUNK : seg;
}

/* The paths [pos, end) of the side from above (a stop may cut them short: s1 says), then
 * the same paths from below; their launches are added to stats. Returns 0, or 1 with err. */
static int run_segment(lsqt_session *sa, lsqt_session *sb, sides *sd, uint64_t pos, uint64_t end,
                       const lsqt_sim_opts *oa, const lsqt_sim_opts *ob, lsqt_sim_stats *s1, lsqt_sim_stats *stats,
                       char *err, size_t errcap)
{
    lsqt_sim_stats s2;
    if (lsqt_run_range(sa, &sd->up, pos, end - pos, oa, s1, err, errcap)) return 1;
    if (lsqt_run_range(sb, &sd->dn, pos, s1->paths_added, ob, &s2, err, errcap)) return 1;
    stats->launches += s1->launches + s2.launches;
    return 0;
}

int lsqt_simulate_range_sides(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t begin,
                              uint64_t add_paths, const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err,
                              size_t errcap)
{
    if (!lsqt_state_below_count(st))
        return lsqt_simulate_range(cx, a, st, begin, add_paths, o, stats, err, errcap);
    memset(stats, 0, sizeof *stats);
    if (begin == UINT64_MAX) {
        snprintf(err, errcap, "the state holds paths with gaps between them (a partial merge): it cannot be continued");
        return 1;
    }
    sides sd;
    if (sides_open(&sd, a, st, err, errcap)) return 1;
    lsqt_session sa, sb;
    memset(&sa, 0, sizeof sa), memset(&sb, 0, sizeof sb);
    int ok = 0;
    if (lsqt_session_open(&sa, cx, a, &sd.up, o->extra_options, o->local_size, o->verbose, err, errcap) ||
        lsqt_session_open(&sb, cx, &sd.mirror, &sd.dn, o->extra_options, o->local_size, o->verbose, err, errcap))
        goto done;
    /* Each segment runs the side from above (which a stop may cut short), then the same
     * paths from below; the stop rules are applied here, between segments. */
    lsqt_sim_opts oa, ob;
    side_opts(o, &oa, &ob);
    const uint64_t target = add_paths > UINT64_MAX - begin ? UINT64_MAX : begin + add_paths;
    const double goal = o->target_error, t0 = lsqt_now();
    double last_ck = t0, cur_err = NAN;
    uint64_t pos = begin, seg = 8 * LSQT_CHUNK, check = UINT64_MAX;
    stats->stop_reason = LSQT_STOP_PATHS;
    if (goal > 0) {
        cur_err = sides_err(&sd);
        if (!isnan(cur_err) && cur_err <= goal) {
            stats->stop_reason = LSQT_STOP_TARGET;
            ok = 1;
            goto done;
        }
        check = begin < LSQT_STOP_ERR_PATHS ? LSQT_STOP_ERR_PATHS : lsqt_next_check(begin, cur_err, goal);
    }
    if (o->verbose)
        fprintf(stderr, "simulating %llu paths per slice x %d slices from above and %d from below\n",
                (unsigned long long)(target - begin), sd.up.n_slices, sd.dn.n_slices);
    while (pos < target) {
        uint64_t end = target - pos > seg ? pos + seg : target;
        if (end > check) end = check;
        lsqt_sim_stats s1;
        const double t = lsqt_now();
        if (run_segment(&sa, &sb, &sd, pos, end, &oa, &ob, &s1, stats, err, errcap)) goto done;
        pos += s1.paths_added;
        seg = next_segment(seg, lsqt_now() - t);
        if (o->progress)
            fprintf(stderr, "\r%s%s%llu of %llu paths per slice, both sides (from above and below)   ",
                    o->phase ? o->phase : "", o->phase ? ": " : "", (unsigned long long)(pos - begin),
                    (unsigned long long)(target - begin));
        if (s1.interrupted) {
            stats->stop_reason = LSQT_STOP_INTERRUPT, stats->interrupted = 1;
            break;
        }
        if (pos == check) {
            cur_err = sides_err(&sd);
            if (!isnan(cur_err) && cur_err <= goal) {
                stats->stop_reason = LSQT_STOP_TARGET;
                break;
            }
            check = lsqt_next_check(pos, cur_err, goal);
        }
        if (o->time_limit > 0 && lsqt_now() - t0 >= o->time_limit && pos < target) {
            stats->stop_reason = LSQT_STOP_TIME, stats->interrupted = 1;
            break;
        }
        if (o->checkpoint && o->checkpoint_every > 0 && lsqt_now() - last_ck >= o->checkpoint_every && pos < target) {
            sides_checkpoint(&sd, o);
            last_ck = lsqt_now();
        }
    }
    if (o->progress) fprintf(stderr, "\n");
    stats->paths_added = pos - begin;
    stats->seconds = lsqt_now() - t0;
    ok = 1;
done:
    lsqt_session_close(&sa);
    lsqt_session_close(&sb);
    return sides_close(&sd, st, ok, err, errcap);
}
