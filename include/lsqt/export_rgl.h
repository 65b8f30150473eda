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

/* 0 when ST's bands can be written (one band; three unnamed, R, G, B, as rgb; bands with
 * wavelengths either way), else -1 with err saying why (no spectrum without wavelengths,
 * no colour from unnamed bands other than three). */
int lsqt_rgl_bands(const lsqt_state *st, const char *input, int spectral, char *err, size_t errcap);

/* Writes the tensor file at path: field `rgb` (Mitsuba's RGB variants: one band in all
 * three channels, R, G, B as they are, or a spectrum's linear sRGB) or, when spectral,
 * `wavelengths` and `spectra` (Mitsuba's spectral variants, pbrt-v4: the run's
 * wavelengths, or for one band 360 and 830 nm holding the same value); `stderr` the
 * standard errors, per band with bands. est: band after band (lsqt_estimates). Returns 0,
 * or -1 with err. */
int lsqt_rgl_write(const char *path, const lsqt_state *st, const lsqt_slice_est *est, const int *slices, int nt,
                   int spectral, char *err, size_t errcap);

#ifdef __cplusplus
}
#endif
#endif
