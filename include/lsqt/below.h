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
 * paths have their own RNG stream (LSQT_RNG_BELOW), so the two sides are independent.
 * A session on a two-sided state runs each side as a lane of its own (session.h), so
 * lsqt_simulate and the RRSS pilot take such states as they take one-sided ones. */
#ifndef LSQT_BELOW_H
#define LSQT_BELOW_H

#include <stddef.h>

#include "lsqt/assembly.h"
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
int lsqt_state_split_by_side(const lsqt_state *st, lsqt_state *above, lsqt_state *below);

/* The two-sided state of ABOVE's slices then BELOW's (OUT fresh; free it). Both must hold
 * the same paths and settings (err says which differs, returns 1); -1 out of memory. */
int lsqt_state_join_by_side(const lsqt_state *above, const lsqt_state *below, lsqt_state *out, char *err,
                          size_t errcap);

/* The RAW name of the side from below: RAW with its final ".raw" replaced by ".below.raw"
 * (appended when RAW does not end in ".raw"). */
void lsqt_below_raw_name(const char *raw, char *dst, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
