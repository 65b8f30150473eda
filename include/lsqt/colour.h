/* Colour from spectra: a value per wavelength band (a BSDF, an albedo) as CIE XYZ and
 * linear sRGB, for RGB exports and previews, and the bands' names in file names. Host
 * only; no state, so any thread may call any of these. */
#ifndef LSQT_COLOUR_H
#define LSQT_COLOUR_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The CIE 1931 2-degree standard observer's colour-matching functions x-bar, y-bar,
 * z-bar at wl_nm: the 5 nm table from 360 to 830 nm, linear between rows (exact at a
 * row), 0 outside (and for NaN). */
void lsqt_cie1931(double wl_nm, double xyz[3]);

/* CIE standard illuminant D65's relative spectral power (100 at 560 nm): the 5 nm table
 * from 300 to 830 nm, linear between rows, 0 outside. */
double lsqt_d65(double wl_nm);

/* XYZ to LINEAR sRGB with the IEC 61966-2-1 matrix (D65 white, Y = 1 is white), no
 * transfer curve, no clamping. */
void lsqt_xyz_to_linear_srgb(const double xyz[3], double rgb[3]);

/* A reflectance-like spectrum v sampled at n strictly increasing, finite wavelengths wl_nm
 * as XYZ under D65: v(lambda) is linear between samples and holds its end values outside
 * [wl[0], wl[n-1]] (one band is a flat spectrum); v * D65 * cmf is summed at 1 nm steps
 * from 360 to 830 nm and divided by the same sum of D65 * y-bar, so v == 1 gives Y = 1
 * and D65's white point in X and Z. Returns 0, or -1 (xyz untouched) for n < 1, a NULL
 * pointer, or wavelengths that do not increase. */
int lsqt_spectrum_to_xyz(int n, const double *wl_nm, const double *v, double xyz[3]);

/* The same spectrum as LINEAR sRGB: lsqt_spectrum_to_xyz, the matrix above, then a
 * diagonal white correction so that v == c gives exactly (c, c, c) (the tables' white
 * is off the matrix's by at most 4e-4 a channel; colour.c says why it is corrected).
 * No clamping: a saturated spectrum (a narrow band) has negative channels, and a
 * value above 1 stays above 1; a caller clamps and encodes for display. Returns 0 or -1
 * as lsqt_spectrum_to_xyz. */
int lsqt_spectrum_to_srgb(int n, const double *wl_nm, const double *v, double rgb[3]);

/* The label of band b in file names, into buf: with wavelengths (wl_or_null[b] nm) the
 * number in "%.10g" and "nm", "550nm", "412.5nm" (10 digits: wavelengths up to 1e6 nm
 * that differ by 0.001 nm or more get distinct labels); without, "R", "G", "B" for three
 * bands, else the index, "0", "1", ... Returns buf, or NULL when b is not a band, buf is
 * NULL or the label does not fit in cap bytes. */
const char *lsqt_band_label(int n_bands, const double *wl_or_null, int b, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif

#endif
