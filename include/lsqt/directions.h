/* Where the BSDF is estimated: outgoing slices and the incident directions per slice. */
#ifndef LSQT_DIRECTIONS_H
#define LSQT_DIRECTIONS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define LSQT_WI_FILE_MAX 1024 /* directions a --wi-file may give */

/* theta_k = k / n * 0.99 * pi / 2, k = 0 .. n-1 (as the original tool). */
void lsqt_wo_angles(int n, double *theta);

/* n directions spread evenly (Fibonacci lattice, equal area) over the half of the upper
 * hemisphere with y >= 0, or of the whole sphere when `sphere` is set; 4 floats each
 * (x, y, z, 0). The BSDF is mirror symmetric in y, so y < 0 is the same. */
void lsqt_wi_spread(int n, int sphere, float *out);

/* --grid NO,NI,NPHI: a regular grid, the one Eradiate's tabulated BSDF takes (cos theta
 * on linspace(0, 1, N), azimuth on 2 pi k / NPHI). Node k of n is cos theta = k / (n - 1),
 * but node 0, the horizon, where no direction can be simulated, is simulated at
 * LSQT_GRID_HORIZON_COS (theta = 89.94 deg): a continuous BSDF differs there from its
 * horizon limit by far less than any Monte Carlo error. */
#define LSQT_GRID_HORIZON_COS 0.001
double lsqt_grid_cos(int k, int n);
/* Slice s (of n) at the node n-1-s: theta_o ascending from 0, as -wo's. */
void lsqt_grid_theta_o(int n, double *theta);
/* Simulated azimuths: 2 pi m / nphi for m = 0 .. nphi/2 (the rest, in (pi, 2 pi), are
 * mirror images); directions ni * (nphi/2 + 1), twice that when `lower`. */
int lsqt_grid_wi_count(int ni, int nphi, int lower);
/* The directions, 4 floats each, direction ((h * ni + i) * (nphi/2 + 1) + m): h 0 above,
 * 1 below (z = -cos), i over theta ascending (node ni-1-i), m over the azimuths. */
void lsqt_grid_wi(int ni, int nphi, int lower, float *out);

/* --rgl-grid NT,NU: the nodes of an RGL tensor file (Dupuy and Jakob 2018, as Mitsuba 3's
 * and pbrt-v4's `measured` BSDF read it), so that export --rgl writes simulated values
 * only. Slice k of nt is at theta = k / (nt - 1) * 90 deg (the last, the horizon, at
 * acos LSQT_GRID_HORIZON_COS). Its directions are reflections of wo about the half
 * vectors of an nu x nu grid: node (j, l) has theta_m = (l / (nu - 1))^2 * 90 deg and
 * phi_m = (2 j / (nu - 1) - 1) * 180 deg from wo's azimuth; j < nu / 2 mirrors
 * nu - 1 - j, so only j >= nu / 2 is simulated: direction (j - nu / 2) * nu + l. */
#define LSQT_RGL_MIN_COS 1e-4 /* a node's direction nearer the horizon holds 0 */
void lsqt_rgl_theta_o(int nt, double *theta);
int lsqt_rgl_wi_count(int nu);
/* Node (j, l) of the slice at theta_o: 1 and wi (unit) when the reflection is at least
 * LSQT_RGL_MIN_COS above the horizon, else 0 (the tensor holds 0 there). */
int lsqt_rgl_node(double theta_o, int nu, int j, int l, double wi[3]);
/* The slice's directions, 4 floats each; a node without one (lsqt_rgl_node 0) gets the
 * mirror direction of wo, so that every direction is a valid one. */
void lsqt_rgl_wi(double theta_o, int nu, float *out);

/* Incident directions given by the user (--wi-file), from text[0 .. len) (NUL bytes are
 * just bad characters). One direction per line, either `x y z` (any length but 0; it is
 * normalised) or `theta_deg phi_deg` (theta from +z, in [0, 180]; phi from +x, the
 * azimuth of every slice's wo, any finite value): (sin t cos p, sin t sin p, cos t).
 * Numbers are finite decimals; tokens are separated by blanks (spaces, tabs, CR); '#'
 * starts a comment to the end of the line; blank lines are skipped. 1 to
 * LSQT_WI_FILE_MAX directions. A direction on the horizon (z = 0 in float, where a BSDF
 * value tally / |cos| is 0 / 0) is refused, and so is one below it (z < 0) unless
 * `lower` (the stack transmits). The BSDF is mirror symmetric about the xz-plane (the
 * plane of wo), so a direction with y < 0 is kept as (x, -y, z), as the state keeps them
 * (RAW writes both mirror images).
 * On success: 0, *dirs a malloc'd array of *n directions, 4 floats each (x, y, z, 0),
 * unit, y >= 0, in the order given; *n_mirrored (may be NULL) how many had y < 0.
 * On failure: 2, *dirs NULL, *n 0, and err "NAME:LINE: error: WHAT at 'TOKEN'; expected
 * ..." (no LINE when the error is not on one line, as for a file without directions);
 * -1 when out of memory. */
int lsqt_wi_parse(const char *text, size_t len, const char *name, int lower, float **dirs, int *n,
                  int *n_mirrored, char *err, size_t errcap);

/* lsqt_wi_parse of the file at PATH ("-" is stdin), named PATH in messages. Returns 0,
 * 2 (a content error, as lsqt_wi_parse), 1 when it cannot be read (err "cannot open
 * 'PATH': ..."), or -1 when out of memory. */
int lsqt_wi_file_read(const char *path, int lower, float **dirs, int *n, int *n_mirrored, char *err,
                      size_t errcap);

#ifdef __cplusplus
}
#endif
#endif
