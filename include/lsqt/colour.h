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

/* How the bands of a run are named in file names, computed once from all of them (O(n)):
 * with wavelengths, one format for every band: the integer part zero-padded to the width
 * of the largest wavelength's, and the same number of decimals for every band, the least
 * in 0..9 that makes all labels distinct and shows every wavelength to 1e-9 nm (9 where
 * none does): "450nm", "0400nm".."2500nm", "400.0nm" "400.5nm", so that the labels are unique and `ls` sorts them in wavelength order
 * (the wavelengths increase). Without wavelengths: "R", "G", "B" for three bands, else
 * the index zero-padded to the width of n - 1 ("00".."11" for 12 bands). */
typedef struct lsqt_band_names {
    int n_bands;
    const double *wl; /* NULL: unnamed bands; not copied, must outlive the names */
    int width;        /* digits of the integer part (wavelengths) or of the index */
    int decimals;     /* wavelengths: decimals of every label */
} lsqt_band_names;

/* Fills *nm for n_bands bands (wl_or_null: their wavelengths, increasing). Returns 0, or
 * -1 when no number of decimals up to 9 tells two adjacent wavelengths apart: then
 * *clash (when not NULL) is the first band b whose label equals band b + 1's, and the
 * names use 9 decimals. */
int lsqt_band_names_init(lsqt_band_names *nm, int n_bands, const double *wl_or_null, int *clash);

/* The label of band b in file names, into buf (see lsqt_band_names). Returns buf, or NULL
 * when b is not a band, buf is NULL or the label does not fit in cap bytes. */
const char *lsqt_band_label(const lsqt_band_names *nm, int b, char *buf, size_t cap);

/* The label of band b of a run of n_bands bands (wl_or_null: their wavelengths), for a
 * caller that names one or two bands: computes the names (O(n)) each call; a caller that
 * labels every band computes lsqt_band_names once instead. */
const char *lsqt_band_label_one(int n_bands, const double *wl_or_null, int b, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif

#endif
