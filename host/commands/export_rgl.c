/* lsqt-cl export --rgl: the reflection of an --rgl-grid LSS as an RGL tensor file, the
 * measured-BSDF format of Dupuy and Jakob 2018 ("An adaptive parameterization for
 * efficient material acquisition and rendering") that Mitsuba 3's and pbrt-v4's
 * `measured` BSDF read.
 *
 * The format stores, per incident elevation theta_i (phi_i one node: isotropic), a table
 * over a unit square (u, v) that the reader maps to a half vector through a warp (the VNDF
 * table) and then to the outgoing direction by reflection. This writer makes the warp the
 * identity (vndf and ndf constant, jacobian 0): the reader's u is then sqrt(theta_m /
 * (pi/2)) and v is (phi_m - phi_i + pi) / (2 pi), the --rgl-grid's nodes (directions.h),
 * so every table entry is a simulated value, f cos theta_o (the reader's eval returns the
 * BSDF times the cosine of its outgoing direction, lsqt-cl's incident one: f is
 * reciprocal). Between nodes the reader interpolates bilinearly, and linearly in theta_i.
 * The luminance table (the reader's sampling density over (u, v)) is the value times the
 * warp's Jacobian, plus a floor so that no direction with a value has density 0.
 *
 * Kept: reflection from above, its standard errors (an extra field `stderr` that renderers
 * ignore; per band with bands) and colour: one band in every channel, R, G, B bands as
 * they are, a spectrum as linear sRGB (rgb) or at its own wavelengths (spectra; the
 * readers interpolate between them and hold the end values). Lost: transmission and the
 * slices from below (the format has no place for them). */
#include "lsqt/export_rgl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/colour.h"
#include "lsqt/directions.h"
#include "lsqt/util.h"

enum { T_UINT8 = 1, T_FLOAT32 = 10 }; /* Mitsuba's Struct::Type codes, as the format uses them */
enum { MAX_FIELDS = 12 };

typedef struct field {
    const char *name;
    int dtype, ndim;
    uint64_t shape[5];
    const void *data;
} field;

static uint64_t field_bytes(const field *f)
{
    uint64_t n = f->dtype == T_FLOAT32 ? 4 : 1;
    for (int d = 0; d < f->ndim; d++) n *= f->shape[d];
    return n;
}

static void put_le(FILE *fp, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++) fputc((int)((v >> (8 * i)) & 0xff), fp);
}

static void put_zeros(FILE *fp, uint64_t n)
{
    while (n--) fputc(0, fp);
}

/* The file: "tensor_file\0", version 1.0, the field count, then per field its name,
 * dimensions, type, data offset and shape; then the data, each field 8-byte aligned,
 * little-endian, C order. */
static int write_fields(const char *path, const field *f, int n, char *err, size_t errcap)
{
    uint64_t header = 12 + 2 + 4;
    for (int i = 0; i < n; i++) header += 2 + strlen(f[i].name) + 2 + 1 + 8 + 8 * (uint64_t)f[i].ndim;
    uint64_t off[MAX_FIELDS], at = (header + 7) / 8 * 8;
    for (int i = 0; i < n; i++) off[i] = at, at = (at + field_bytes(&f[i]) + 7) / 8 * 8;
    FILE *fp = fopen(path, "wb");
    if (!fp) {
        snprintf(err, errcap, "cannot create '%s'", path);
        return -1;
    }
    fwrite("tensor_file", 1, 12, fp); /* with its NUL */
    put_le(fp, 1, 1), put_le(fp, 0, 1), put_le(fp, (uint64_t)n, 4);
    for (int i = 0; i < n; i++) {
        put_le(fp, strlen(f[i].name), 2);
        fputs(f[i].name, fp);
        put_le(fp, (uint64_t)f[i].ndim, 2), put_le(fp, (uint64_t)f[i].dtype, 1), put_le(fp, off[i], 8);
        for (int d = 0; d < f[i].ndim; d++) put_le(fp, f[i].shape[d], 8);
    }
    uint64_t pos = header;
    for (int i = 0; i < n; i++) {
        put_zeros(fp, off[i] - pos);
        const uint64_t b = field_bytes(&f[i]);
        if (f[i].dtype == T_FLOAT32) /* little-endian whatever the host */
            for (uint64_t k = 0; k < b / 4; k++) {
                uint32_t u;
                memcpy(&u, (const float *)f[i].data + k, 4);
                put_le(fp, u, 4);
            }
        else fwrite(f[i].data, 1, (size_t)b, fp);
        pos = off[i] + b;
    }
    put_zeros(fp, at - pos);
    const int bad = ferror(fp) != 0;
    if (fclose(fp) != 0 || bad) {
        snprintf(err, errcap, "cannot write '%s'", path);
        return -1;
    }
    /* Read back what was written (a full disk may pass unseen): its size and header. */
    fp = fopen(path, "rb");
    unsigned char head[18];
    const int ok = fp && fread(head, 1, sizeof head, fp) == sizeof head && memcmp(head, "tensor_file", 12) == 0 &&
                   fseek(fp, 0, SEEK_END) == 0 && (uint64_t)ftell(fp) == at;
    if (fp) fclose(fp);
    if (!ok) {
        snprintf(err, errcap, "'%s' does not read back as written (%llu bytes expected)", path, (unsigned long long)at);
        return -1;
    }
    return 0;
}

int lsqt_rgl_slices(const lsqt_state *st, const char *input, int *slices, char *err, size_t errcap)
{
    if (st->dir_method != LSQT_DIRS_RGL) {
        snprintf(err, errcap, "'%s' is not on the nodes of an RGL tensor (its directions were chosen by %s): --rgl "
                 "writes the values a run simulated at them; run with --rgl-grid NT,NU", input,
                 st->dir_method == LSQT_DIRS_GRID ? "--grid" : st->dir_method == LSQT_DIRS_FILE ? "--wi-file"
                 : st->dir_method == LSQT_DIRS_RRSS ? "RRSS" : "--wi-spread");
        return -1;
    }
    if (st->stage != LSQT_STAGE_RUN || st->paths == 0) {
        snprintf(err, errcap, "'%s' holds no finished paths to export", input);
        return -1;
    }
    const int nu = (int)st->grid_ni;
    int nt = 0;
    for (int s = 0; s < st->n_slices; s++)
        if (!(st->slice_flags[s] & LSQT_SLICE_BELOW)) slices[nt++] = s;
    double *theta = malloc(sizeof(double) * (size_t)(nt > 0 ? nt : 1));
    float *wi = malloc(sizeof(float) * 4 * (size_t)st->n_wi);
    if (!theta || !wi) {
        free(theta), free(wi);
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    lsqt_rgl_theta_o(nt, theta);
    int bad = nt < 2 ? 0 : -1;
    for (int k = 0; k < nt && bad < 0; k++) {
        lsqt_rgl_wi(theta[k], nu, wi);
        if (st->theta_o[slices[k]] != theta[k] ||
            memcmp(wi, st->wi + (size_t)slices[k] * (size_t)st->n_wi * 4, sizeof(float) * 4 * (size_t)st->n_wi) != 0)
            bad = k;
    }
    free(theta), free(wi);
    if (bad >= 0) {
        snprintf(err, errcap, "'%s': %d slices from above%s, not the nodes --rgl-grid %d,%d makes", input, nt,
                 nt < 2 ? "" : " whose angles or directions are", nt, nu);
        return -1;
    }
    return nt;
}

int lsqt_rgl_bands(const lsqt_state *st, const char *input, int spectral, char *err, size_t errcap)
{
    if (st->n_bands <= 1) return 0;
    if (spectral && !st->wavelengths) {
        snprintf(err, errcap, "'%s' has %d bands without wavelengths%s: --rgl-spectral writes a spectrum, which needs "
                 "the run's wavelengths (--wavelengths)%s", input, st->n_bands, st->n_bands == 3 ? " (R, G, B)" : "",
                 st->n_bands == 3 ? "; --rgl writes R, G, B as they are" : "");
        return -1;
    }
    if (!spectral && !st->wavelengths && st->n_bands != 3) {
        snprintf(err, errcap, "'%s' has %d bands without wavelengths: --rgl writes colour from three (R, G, B) or from "
                 "a spectrum (a run with --wavelengths)", input, st->n_bands);
        return -1;
    }
    return 0;
}

/* The colour of one node from its bands' values v (nb of them): rgb (linear sRGB) and Y, its
 * luminance (the sampling density's weight). R, G, B are taken as they are, with the Rec.
 * 709 luminance; a spectrum goes through CIE 1931 under D65 (colour.h); one band is grey. */
static void node_colour(const lsqt_state *st, int nb, const double *v, double rgb[3], double *y)
{
    if (nb == 1) {
        rgb[0] = rgb[1] = rgb[2] = *y = v[0];
    } else if (!st->wavelengths) {
        for (int c = 0; c < 3; c++) rgb[c] = v[c];
        *y = 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
    } else {
        double xyz[3] = {0, 0, 0};
        if (lsqt_spectrum_to_srgb(nb, st->wavelengths, v, rgb)) rgb[0] = rgb[1] = rgb[2] = 0;
        lsqt_spectrum_to_xyz(nb, st->wavelengths, v, xyz);
        *y = xyz[1];
    }
}

int lsqt_rgl_write(const char *path, const lsqt_state *st, const lsqt_slice_est *est,
                   const int *slices, int nt, int spectral, char *err, size_t errcap)
{
    if (lsqt_rgl_bands(st, "the state", spectral, err, errcap)) return -1;
    /* nb bands; nch channels of the colour field: rgb 3, spectra the run's wavelengths (one
     * band: 360 and 830 nm, the same value at both); nse bands in stderr */
    const int nu = (int)st->grid_ni, nb = lsqt_state_bands(st);
    const int nch = spectral ? (nb > 1 ? nb : 2) : 3;
    const size_t plane = (size_t)nu * (size_t)nu, cells = (size_t)nt * plane, ns = (size_t)st->n_slices;
    float *theta = malloc(sizeof(float) * (size_t)nt), *vndf = malloc(sizeof(float) * 4 * (size_t)nt);
    float *lum = malloc(sizeof(float) * cells), *sd = malloc(sizeof(float) * cells * (size_t)nb);
    float *val = malloc(sizeof(float) * cells * (size_t)nch), *wl = malloc(sizeof(float) * (size_t)nch);
    double *v = malloc(sizeof(double) * 2 * (size_t)nb);
    const size_t dcap = strlen(st->canonical) + 512 + 40 * (size_t)nb;
    char *desc = malloc(dcap);
    if (!theta || !vndf || !lum || !sd || !val || !wl || !v || !desc) {
        free(theta), free(vndf), free(lum), free(sd), free(val), free(wl), free(v), free(desc);
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    double *s = v + nb; /* the errors beside the values */
    for (int k = 0; k < nt; k++) {
        theta[k] = (float)st->theta_o[slices[k]];
        double lsum = 0;
        for (int j = 0; j < nu; j++)
            for (int l = 0; l < nu; l++) {
                const size_t at = (size_t)k * plane + (size_t)j * nu + (size_t)l;
                const int jj = j >= nu / 2 ? j : nu - 1 - j; /* the simulated mirror image */
                const size_t d = (size_t)(jj - nu / 2) * nu + (size_t)l;
                double w[3], rgb[3], y;
                for (int b = 0; b < nb; b++) v[b] = 0, s[b] = 0;
                if (lsqt_rgl_node(st->theta_o[slices[k]], nu, j, l, w)) {
                    const double cz = st->wi[((size_t)slices[k] * (size_t)st->n_wi + d) * 4 + 2];
                    for (int b = 0; b < nb; b++) {
                        const lsqt_est *f = &est[(size_t)b * ns + (size_t)slices[k]].f[d];
                        v[b] = f->mean * cz, s[b] = f->err * cz;
                    }
                }
                node_colour(st, nb, v, rgb, &y);
                /* the warp's Jacobian: d(omega_o) = 8 pi^2 u sin(theta_m) (wo.m) du dv */
                const double u = (double)l / (nu - 1), tm = u * u * (LSQT_PI / 2);
                const double wm = sin(st->theta_o[slices[k]]) * sin(tm) * cos((2.0 * j / (nu - 1) - 1.0) * LSQT_PI) +
                                  cos(st->theta_o[slices[k]]) * cos(tm);
                /* (one band: its value as it is, the bytes a one-band file always had) */
                lum[at] = (float)((nb > 1 ? fmax(y, 0.0) : y) * 8 * LSQT_PI * LSQT_PI * u * sin(tm) * fmax(wm, 0.0));
                lsum += lum[at];
                for (int b = 0; b < nb; b++) sd[((size_t)k * nb + (size_t)b) * plane + (size_t)j * nu + (size_t)l] = (float)s[b];
                for (int c = 0; c < nch; c++)
                    val[((size_t)k * nch + (size_t)c) * plane + (size_t)j * nu + (size_t)l] =
                        (float)(spectral ? v[nb > 1 ? c : 0] : rgb[c]);
            }
        /* The floor: 1 % of the mean density, so that sampling reaches every value. */
        const float floor_ = (float)(lsum > 0 ? 0.01 * lsum / (double)plane : 1.0);
        for (size_t i = 0; i < plane; i++) lum[(size_t)k * plane + i] += floor_;
    }
    for (int k = 0; k < 4 * nt; k++) vndf[k] = 1.0f;
    size_t at = (size_t)snprintf(desc, dcap,
                                 "lsqt-cl Monte Carlo BSDF (reflection from above, identity warp: values at --rgl-grid "
                                 "%d,%d); seed %llu, %llu paths per slice; ", nt, nu, (unsigned long long)st->seed,
                                 (unsigned long long)st->paths);
    if (nb > 1) { /* what the colour came from, and stderr's bands */
        at += (size_t)snprintf(desc + at, dcap - at, "%s from %d bands (stderr per band):",
                               spectral ? "spectra" : "rgb", nb);
        lsqt_band_names names;
        lsqt_band_names_init(&names, nb, st->wavelengths, NULL);
        for (int b = 0; b < nb; b++) {
            char lab[32];
            at += (size_t)snprintf(desc + at, dcap - at, " %s", lsqt_band_label(&names, b, lab, sizeof lab));
        }
        at += (size_t)snprintf(desc + at, dcap - at, "; ");
    }
    snprintf(desc + at, dcap - at, "assembly:\n%s", st->canonical);
    if (nb > 1 && spectral)
        for (int c = 0; c < nch; c++) wl[c] = (float)st->wavelengths[c];
    else if (spectral)
        wl[0] = 360, wl[1] = 830;
    static const float ones[4] = {1, 1, 1, 1}, quarter[4] = {0.25f, 0.25f, 0.25f, 0.25f}, phi_i[1] = {0};
    static const unsigned char jacobian[1] = {0};
    const uint64_t NT = (uint64_t)nt, NU = (uint64_t)nu, NCH = (uint64_t)nch;
    field f[MAX_FIELDS];
    int n = 0;
    f[n++] = (field){"description", T_UINT8, 1, {strlen(desc)}, desc};
    f[n++] = (field){"theta_i", T_FLOAT32, 1, {NT}, theta};
    f[n++] = (field){"phi_i", T_FLOAT32, 1, {1}, phi_i};
    f[n++] = (field){"ndf", T_FLOAT32, 2, {2, 2}, ones};
    f[n++] = (field){"sigma", T_FLOAT32, 2, {2, 2}, quarter};
    f[n++] = (field){"vndf", T_FLOAT32, 4, {1, NT, 2, 2}, vndf};
    f[n++] = (field){"luminance", T_FLOAT32, 4, {1, NT, NU, NU}, lum};
    if (spectral) {
        f[n++] = (field){"wavelengths", T_FLOAT32, 1, {NCH}, wl};
        f[n++] = (field){"spectra", T_FLOAT32, 5, {1, NT, NCH, NU, NU}, val};
    } else {
        f[n++] = (field){"rgb", T_FLOAT32, 5, {1, NT, 3, NU, NU}, val};
    }
    f[n++] = (field){"jacobian", T_UINT8, 1, {1}, jacobian};
    if (nb > 1) f[n++] = (field){"stderr", T_FLOAT32, 5, {1, NT, (uint64_t)nb, NU, NU}, sd};
    else f[n++] = (field){"stderr", T_FLOAT32, 4, {1, NT, NU, NU}, sd};
    const int rc = write_fields(path, f, n, err, errcap);
    free(theta), free(vndf), free(lum), free(sd), free(val), free(wl), free(v), free(desc);
    return rc;
}
