/* RAW text for DIRSIG5's raw2sqt, as the original layered-sqt writes it (docs/design.md section 6.2; docs/formats.md). */
#ifndef LSQT_RAW_H
#define LSQT_RAW_H

#include <stddef.h>

#include "lsqt/state.h"
#include "lsqt/tally.h"
#include "lsqt/util.h"

#ifdef __cplusplus
extern "C" {
#endif

enum lsqt_raw_mode {
    LSQT_RAW_ALL = 0,      /* RAWBS with transmission, else RAWBH */
    LSQT_RAW_REFLECT = 1,  /* upper hemisphere only, RAWBH */
    LSQT_RAW_TRANSMIT = 2  /* lower hemisphere mirrored up (z -> -z), RAWBH */
};

/* Written through lsqt_out (util.h): committed, or with HOLD left in its temporary for
 * lsqt_out_set_publish. *skipped counts non-finite estimates left out. Returns 0 or -1. */
int lsqt_raw_write(const char *path, const lsqt_state *st, const lsqt_slice_est *est, int mode,
                   int *skipped, lsqt_out_set *hold, char *err, size_t errcap);

/* -H names: OUT with its final ".raw" replaced by ".R.raw" / ".T.raw" (part "R", "T";
 * appended when OUT does not end in ".raw"). */
void lsqt_raw_hemi_name(const char *out, const char *part, char *dst, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
