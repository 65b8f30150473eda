/* lsqt-cl export --rgl: an --rgl-grid LSS as an RGL tensor file (host/commands/export_rgl.c). */
#ifndef LSQT_EXPORT_RGL_H
#define LSQT_EXPORT_RGL_H

#include <stddef.h>

#include "lsqt/state.h"
#include "lsqt/tally.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The slices from above of an --rgl-grid state, in order, into slices (n_slices ints):
 * returns their count NT, or -1 with err saying why ST cannot be exported (another
 * sampling, no paths, slices or directions that are not the grid's nodes). */
int lsqt_rgl_slices(const lsqt_state *st, const char *input, int *slices, char *err, size_t errcap);

/* Writes the tensor file at path: field `rgb` (3 equal channels, Mitsuba's RGB variants)
 * or, when spectral, `wavelengths` 360 and 830 nm and `spectra` (Mitsuba's spectral
 * variants, pbrt-v4); `stderr` the standard errors. Returns 0, or -1 with err. */
int lsqt_rgl_write(const char *path, const lsqt_state *st, const lsqt_slice_est *est, const int *slices, int nt,
                   int spectral, char *err, size_t errcap);

#ifdef __cplusplus
}
#endif
#endif
