/* Two-sided BSDFs (--from-below): light entering from the bottom medium.
 *
 * Light from below through a stack A is light from above through A turned upside down
 * (z -> -z): the media in reverse order, the layers reversed with z negated, and every
 * model mirrored. Every model lsqt-cl has that can transmit is its own mirror image
 * (lsqt_assembly_mirror says why), so the same kernels serve both sides.
 *
 * A two-sided state holds n slices from above, then n from below (the same theta_o,
 * slice_flags LSQT_SLICE_BELOW). A slice from below is the mirrored view: its theta_o is
 * measured from -z, and its incident directions and RAW lines are those of the stack
 * turned upside down; negate z (of wo and of every wi) for the stack's own frame. Its
 * paths have their own RNG stream (LSQT_RNG_BELOW), so the two sides are independent. */
#ifndef LSQT_BELOW_H
#define LSQT_BELOW_H

#include <stddef.h>

#include "lsqt/assembly.h"
#include "lsqt/rrss.h"
#include "lsqt/simulate.h"
#include "lsqt/state.h"

#ifdef __cplusplus
extern "C" {
#endif

/* OUT is A turned upside down (free it with lsqt_assembly_free). Returns 0, or 2 with err
 * naming the model (and line) that has no mirror lsqt-cl can express, or saying that the
 * stack transmits nothing (then no light from below reaches what lies above). */
int lsqt_assembly_mirror(const lsqt_assembly *a, lsqt_assembly *out, char *err, size_t errcap);

/* The slices of ST flagged LSQT_SLICE_BELOW. */
int lsqt_state_below_count(const lsqt_state *st);

/* ST (fresh, one-sided) gets a slice from below for each of its slices, with the same
 * theta_o and directions. Returns 0 or -1 (out of memory; ST unchanged). */
int lsqt_state_add_below(lsqt_state *st);

/* The slices from above and those from below, each a state of its own (sharing nothing
 * with ST; free both), with ST's ranges, span, stage, flags and settings. Returns 0 or -1. */
int lsqt_state_split_sides(const lsqt_state *st, lsqt_state *above, lsqt_state *below);

/* The two-sided state of ABOVE's slices then BELOW's (OUT fresh; free it). Both must hold
 * the same paths and settings (err says which differs, returns 1); -1 out of memory. */
int lsqt_state_join_sides(const lsqt_state *above, const lsqt_state *below, lsqt_state *out, char *err,
                          size_t errcap);

/* lsqt_simulate(_range) for a state that may have slices from below: a one-sided state
 * goes straight through; a two-sided one runs each side with its own assembly (A, and A
 * mirrored for below) on the same paths, in segments of both sides (about a second each):
 * a stop (interrupt, time limit) ends the side from above, and the side from below then
 * does the same paths; --target-error is checked on both sides at the counts
 * lsqt_simulate uses; checkpoints get the joined state between segments.
 * Same returns and stats as the functions they wrap. */
int lsqt_simulate_sides(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t add_paths,
                        const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err, size_t errcap);
int lsqt_simulate_range_sides(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *st, uint64_t begin,
                              uint64_t add_paths, const lsqt_sim_opts *o, lsqt_sim_stats *stats, char *err,
                              size_t errcap);

/* lsqt_rrss_pilot and lsqt_rrss_pilot_continue (rrss.h) for both sides: a two-sided
 * pilot state holds the candidate blocks of the slices from above, then those from below,
 * on the same paths (the side from below runs as many as the side from above did, not
 * stopped early; no checkpoints). One-sided states go straight through. */
int lsqt_rrss_pilot_sides(lsqt_context *cx, const lsqt_assembly *a, const lsqt_state *st, int rx, uint64_t pilot_total,
                          uint64_t run_paths, uint64_t begin, uint64_t n_paths, const lsqt_sim_opts *o, lsqt_state *ps,
                          lsqt_rrss_info *info, char *err, size_t errcap);
int lsqt_rrss_pilot_continue_sides(lsqt_context *cx, const lsqt_assembly *a, lsqt_state *ps, uint64_t begin,
                                   uint64_t n_paths, const lsqt_sim_opts *o, lsqt_rrss_info *info, char *err,
                                   size_t errcap);

/* The RAW name of the side from below: RAW with its final ".raw" replaced by ".below.raw"
 * (appended when RAW does not end in ".raw"). */
void lsqt_below_raw_name(const char *raw, char *dst, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
