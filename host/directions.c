#include "lsqt/directions.h"

#include <math.h>

#include "lsqt/util.h"

void lsqt_wo_angles(int n, double *theta)
{
    for (int k = 0; k < n; k++) theta[k] = (double)k / n * 0.99 * (LSQT_PI / 2);
}

void lsqt_wi_spread(int n, int sphere, float *out)
{
    const double golden = 0.6180339887498949; /* irrational step: no two azimuths coincide */
    for (int j = 0; j < n; j++) {
        double u = (j + 0.5) / n;
        double z = sphere ? 1.0 - 2.0 * u : 1.0 - u; /* uniform in z: equal area */
        double t = (j + 0.5) * golden;
        double phi = LSQT_PI * (t - floor(t));           /* [0, pi]: y >= 0 */
        double s = sqrt(fmax(0.0, 1.0 - z * z));
        out[4 * j] = (float)(s * cos(phi));
        out[4 * j + 1] = (float)(s * sin(phi));
        out[4 * j + 2] = (float)z;
        out[4 * j + 3] = 0.0f;
    }
}
