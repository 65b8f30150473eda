/* RRSS: the incident directions of every slice chosen from the slice's own walks
 * (docs/design.md section 3.5, the original tool's Redundancy-Reduced Sample Set). */
#ifndef LSQT_RRSS_H
#define LSQT_RRSS_H

#include <stdio.h>

#include "lsqt/simulate.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lsqt_rrss_info {
    int candidates;        /* per slice: rx * n_wi */
    int short_slices;      /* slices whose walks gave too few candidates (filled from the spread) */
    int density_fallback;  /* slices whose BSDF integral was unusable (sampling density used) */
    double seconds;        /* candidates, pilot and selection */
    double select_seconds; /* the selection alone */
    int interrupted;       /* the pilot stopped early (*stop, time limit): st->paths tells how far */
} lsqt_rrss_info;

/* Chooses ST's directions (st->n_wi per slice; st is fresh: 0 paths) and runs the pilot:
 *  - candidates: rx * n_wi per slice, the scattered exits of analog walks of that slice
 *    (RNG purpose "candidates", paths in index order), mirrored to y >= 0;
 *  - pilot: pilot_paths paths estimate the BSDF at every candidate (one walk serves all);
 *  - selection: target density q = 0.9 f / Z + 0.1 / |D| (f the BSDF value, Z its integral
 *    over the domain D, importance sampled with the candidates' own density, estimated
 *    from their 8 nearest neighbours; that density itself where Z is not usable), then
 *    the most redundant candidate is disabled until n_wi remain (ties by index):
 *    redundancy = e a q / Q over the other candidates within r = sqrt(1/(pi q m)), e of
 *    them enabled, a in all, Q the sum of their q (0 without neighbours).
 * On return ST holds the kept directions with their pilot tallies (st->paths =
 * pilot_paths, fewer when interrupted), exactly what a run of that many paths with those
 * directions gives.
 * Returns 0, or 1 with err filled. */
int lsqt_rrss(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, int rx, uint64_t pilot_paths,
              const lsqt_sim_opts *o, lsqt_rrss_info *info, char *err, size_t errcap);

/* lsqt_rrss in parts, for a sharded or resumed pilot (LSQT_STAGE_PILOT states):
 *  - lsqt_rrss_pilot makes PS (fresh; free it): ST's slices times rx candidate sets, the
 *    candidates (a pure function of seed and slice, so every shard has the same), and
 *    paths [begin, begin + n_paths) of the pilot of pilot_total paths run on them (PS's
 *    span_end: run_paths, the run's -p; o->checkpoint, if set, gets PS);
 *  - lsqt_rrss_pilot_continue runs paths [begin, begin + n_paths) more of the pilot PS
 *    (a checkpoint, an interrupted pilot or pilot shard);
 *  - lsqt_rrss_choose makes ST (fresh; free it) from a pilot PS: the selection, the kept
 *    directions with their pilot tallies, PS's ranges, pilot_paths = PS's paths;
 *  - lsqt_rrss_choose_using the same from a PS it uses up: each slice's candidate tallies
 *    are zeroed and their pages given back once copied (PS is only to be freed then).
 * A two-sided ST or PS (below.h) runs both sides' candidates and pilot on the same paths.
 * Each returns 0, or 1 with err filled. */
int lsqt_rrss_pilot(lsqt_context *cx, const lsqt_assembly *a, const lsqt_state *st, int rx, uint64_t pilot_total,
                    uint64_t run_paths, uint64_t begin, uint64_t n_paths, const lsqt_sim_opts *o, lsqt_state *ps,
                    lsqt_rrss_info *info, char *err, size_t errcap);
int lsqt_rrss_pilot_continue(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *ps, uint64_t begin,
                             uint64_t n_paths, const lsqt_sim_opts *o, lsqt_rrss_info *info, char *err, size_t errcap);
int lsqt_rrss_choose(const lsqt_state *ps, lsqt_state *st, lsqt_rrss_info *info, char *err, size_t errcap);
int lsqt_rrss_choose_using(lsqt_state *ps, lsqt_state *st, lsqt_rrss_info *info, char *err, size_t errcap);

/* The notes a user needs about INFO (fallbacks), one line each. */
void lsqt_rrss_notes(FILE *f, const lsqt_rrss_info *info);

/* The selection alone (exposed for the tests): keeps n of the m candidates dirs (x, y, z,
 * pad per direction, unit, y >= 0) with BSDF values f (>= 0), over the upper hemisphere
 * or the sphere; keep[i] = 1 for the kept ones. Returns 1 when it fell back to the
 * sampling density, else 0; -1 when out of memory. */
int lsqt_rrss_select(const float *dirs, const double *f, int m, int n, int sphere, unsigned char *keep);

#ifdef __cplusplus
}
#endif
#endif
