/* Where the BSDF is estimated: outgoing slices and the incident directions per slice. */
#ifndef LSQT_DIRECTIONS_H
#define LSQT_DIRECTIONS_H

#ifdef __cplusplus
extern "C" {
#endif

/* theta_k = k / n * 0.99 * pi / 2, k = 0 .. n-1 (as the original tool). */
void lsqt_wo_angles(int n, double *theta);

/* n directions spread evenly (Fibonacci lattice, equal area) over the half of the upper
 * hemisphere with y >= 0, or of the whole sphere when `sphere` is set; 4 floats each
 * (x, y, z, 0). The BSDF is mirror symmetric in y, so y < 0 is the same. */
void lsqt_wi_spread(int n, int sphere, float *out);

#ifdef __cplusplus
}
#endif
#endif
