#include "lsqt/raw.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lsqt/util.h"

int lsqt_raw_write(const char *path, const lsqt_state *st, const lsqt_slice_est *est, int mode,
                   int *skipped, lsqt_out_set *hold, char *err, size_t errcap)
{
    lsqt_out af;
    *skipped = 0;
    if (lsqt_out_open(&af, path, err, errcap)) return -1;
    FILE *f = af.f;
    int spherical = mode == LSQT_RAW_ALL && st->transmits;
    /* one band; its wavelength in um when the run has them (0.5, as the original tool writes, else) */
    if (st->wavelengths) fprintf(f, "RAWB%c10A Layered-SQT\n1 %.9g\n%d", spherical ? 'S' : 'H', st->wavelengths[0] / 1000.0, st->n_slices);
    else fprintf(f, "RAWB%c10A Layered-SQT\n1 0.5\n%d", spherical ? 'S' : 'H', st->n_slices);
    for (int s = 0; s < st->n_slices; s++) fprintf(f, " %.9g", st->theta_o[s]);
    fprintf(f, "\n");
    for (int s = 0; s < st->n_slices; s++) {
        for (int k = 0; k < st->n_wi; k++) {
            const float *w = st->wi + ((size_t)s * (size_t)st->n_wi + (size_t)k) * 4;
            double x = w[0], y = w[1], z = w[2], v = est[s].f[k].mean;
            if ((mode == LSQT_RAW_REFLECT && z < 0) || (mode == LSQT_RAW_TRANSMIT && z > 0)) continue;
            if (!isfinite(v)) {
                (*skipped)++;
                continue;
            }
            if (mode == LSQT_RAW_TRANSMIT) z = -z;
            /* Each estimate twice, at y and -y: the BSDF is mirror symmetric about the
             * plane of wo, and raw2sqt covers the sphere better with both. */
            fprintf(f, "%d %.9g %.9g %.9g %.9g\n", s, x, y, z, v);
            fprintf(f, "%d %.9g %.9g %.9g %.9g\n", s, x, 0.0 - y, z, v); /* y = 0: "0", not "-0" */
        }
    }
    return hold ? lsqt_out_hold(&af, hold, err, errcap) : lsqt_out_commit(&af, err, errcap);
}

void lsqt_raw_hemi_name(const char *out, const char *part, char *dst, size_t cap)
{
    size_t n = strlen(out);
    if (n >= 4 && strcmp(out + n - 4, ".raw") == 0) n -= 4;
    snprintf(dst, cap, "%.*s.%s.raw", (int)n, out, part);
}
