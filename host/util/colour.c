/* Colour from spectra (lsqt/colour.h): the CIE tables, XYZ under D65, linear sRGB, and
 * the bands' labels. */
#include "lsqt/colour.h"

#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* CIE 1931 2-degree standard observer, x-bar y-bar z-bar, 360 to 830 nm every 5 nm: the
 * 5 nm rows of CIE 015:2004 (Colorimetry, 3rd ed.) Table T.4 / ISO 11664-1 = CIE S 014-1,
 * as in the CIE's 1 nm dataset CIE_xyz_1931_2deg.csv (doi:10.25039/CIE.DS.xvudnb9b), whose
 * digits (0.006450001 at 380 nm) are kept. Copied from colour-science's
 * colour/colorimetry/datasets/cmfs.py; checked against pbrt-v4's 1 nm CIE_X/Y/Z (agree
 * to 1e-6 relative, pbrt's are floats) and by eye against a 5 nm copy of CVRL's table. */
#define CMF_LO 360.0
#define CMF_N 95
static const double cmf5[CMF_N][3] = {
    {0.0001299, 0.000003917, 0.0006061}, /* 360 */
    {0.0002321, 0.000006965, 0.001086}, /* 365 */
    {0.0004149, 0.00001239, 0.001946}, /* 370 */
    {0.0007416, 0.00002202, 0.003486}, /* 375 */
    {0.001368, 0.000039, 0.006450001}, /* 380 */
    {0.002236, 0.000064, 0.01054999}, /* 385 */
    {0.004243, 0.00012, 0.02005001}, /* 390 */
    {0.00765, 0.000217, 0.03621}, /* 395 */
    {0.01431, 0.000396, 0.06785001}, /* 400 */
    {0.02319, 0.00064, 0.1102}, /* 405 */
    {0.04351, 0.00121, 0.2074}, /* 410 */
    {0.07763, 0.00218, 0.3713}, /* 415 */
    {0.13438, 0.004, 0.6456}, /* 420 */
    {0.21477, 0.0073, 1.0390501}, /* 425 */
    {0.2839, 0.0116, 1.3856}, /* 430 */
    {0.3285, 0.01684, 1.62296}, /* 435 */
    {0.34828, 0.023, 1.74706}, /* 440 */
    {0.34806, 0.0298, 1.7826}, /* 445 */
    {0.3362, 0.038, 1.77211}, /* 450 */
    {0.3187, 0.048, 1.7441}, /* 455 */
    {0.2908, 0.06, 1.6692}, /* 460 */
    {0.2511, 0.0739, 1.5281}, /* 465 */
    {0.19536, 0.09098, 1.28764}, /* 470 */
    {0.1421, 0.1126, 1.0419}, /* 475 */
    {0.09564, 0.13902, 0.8129501}, /* 480 */
    {0.05795001, 0.1693, 0.6162}, /* 485 */
    {0.03201, 0.20802, 0.46518}, /* 490 */
    {0.0147, 0.2586, 0.3533}, /* 495 */
    {0.0049, 0.323, 0.272}, /* 500 */
    {0.0024, 0.4073, 0.2123}, /* 505 */
    {0.0093, 0.503, 0.1582}, /* 510 */
    {0.0291, 0.6082, 0.1117}, /* 515 */
    {0.06327, 0.71, 0.07824999}, /* 520 */
    {0.1096, 0.7932, 0.05725001}, /* 525 */
    {0.1655, 0.862, 0.04216}, /* 530 */
    {0.2257499, 0.9148501, 0.02984}, /* 535 */
    {0.2904, 0.954, 0.0203}, /* 540 */
    {0.3597, 0.9803, 0.0134}, /* 545 */
    {0.4334499, 0.9949501, 0.008749999}, /* 550 */
    {0.5120501, 1.0, 0.005749999}, /* 555 */
    {0.5945, 0.995, 0.0039}, /* 560 */
    {0.6784, 0.9786, 0.002749999}, /* 565 */
    {0.7621, 0.952, 0.0021}, /* 570 */
    {0.8425, 0.9154, 0.0018}, /* 575 */
    {0.9163, 0.87, 0.001650001}, /* 580 */
    {0.9786, 0.8163, 0.0014}, /* 585 */
    {1.0263, 0.757, 0.0011}, /* 590 */
    {1.0567, 0.6949, 0.001}, /* 595 */
    {1.0622, 0.631, 0.0008}, /* 600 */
    {1.0456, 0.5668, 0.0006}, /* 605 */
    {1.0026, 0.503, 0.00034}, /* 610 */
    {0.9384, 0.4412, 0.00024}, /* 615 */
    {0.8544499, 0.381, 0.00019}, /* 620 */
    {0.7514, 0.321, 0.0001}, /* 625 */
    {0.6424, 0.265, 0.00004999999}, /* 630 */
    {0.5419, 0.217, 0.00003}, /* 635 */
    {0.4479, 0.175, 0.00002}, /* 640 */
    {0.3608, 0.1382, 0.00001}, /* 645 */
    {0.2835, 0.107, 0.0}, /* 650 */
    {0.2187, 0.0816, 0.0}, /* 655 */
    {0.1649, 0.061, 0.0}, /* 660 */
    {0.1212, 0.04458, 0.0}, /* 665 */
    {0.0874, 0.032, 0.0}, /* 670 */
    {0.0636, 0.0232, 0.0}, /* 675 */
    {0.04677, 0.017, 0.0}, /* 680 */
    {0.0329, 0.01192, 0.0}, /* 685 */
    {0.0227, 0.00821, 0.0}, /* 690 */
    {0.01584, 0.005723, 0.0}, /* 695 */
    {0.01135916, 0.004102, 0.0}, /* 700 */
    {0.008110916, 0.002929, 0.0}, /* 705 */
    {0.005790346, 0.002091, 0.0}, /* 710 */
    {0.004109457, 0.001484, 0.0}, /* 715 */
    {0.002899327, 0.001047, 0.0}, /* 720 */
    {0.00204919, 0.00074, 0.0}, /* 725 */
    {0.001439971, 0.00052, 0.0}, /* 730 */
    {0.0009999493, 0.0003611, 0.0}, /* 735 */
    {0.0006900786, 0.0002492, 0.0}, /* 740 */
    {0.0004760213, 0.0001719, 0.0}, /* 745 */
    {0.0003323011, 0.00012, 0.0}, /* 750 */
    {0.0002348261, 0.0000848, 0.0}, /* 755 */
    {0.0001661505, 0.00006, 0.0}, /* 760 */
    {0.000117413, 0.0000424, 0.0}, /* 765 */
    {0.00008307527, 0.00003, 0.0}, /* 770 */
    {0.00005870652, 0.0000212, 0.0}, /* 775 */
    {0.00004150994, 0.00001499, 0.0}, /* 780 */
    {0.00002935326, 0.0000106, 0.0}, /* 785 */
    {0.00002067383, 0.0000074657, 0.0}, /* 790 */
    {0.00001455977, 0.0000052578, 0.0}, /* 795 */
    {0.00001025398, 0.0000037029, 0.0}, /* 800 */
    {0.000007221456, 0.0000026078, 0.0}, /* 805 */
    {0.000005085868, 0.0000018366, 0.0}, /* 810 */
    {0.000003581652, 0.0000012934, 0.0}, /* 815 */
    {0.000002522525, 0.00000091093, 0.0}, /* 820 */
    {0.000001776509, 0.00000064153, 0.0}, /* 825 */
    {0.000001251141, 0.00000045181, 0.0}, /* 830 */
};

/* CIE standard illuminant D65, relative spectral power, 300 to 830 nm every 5 nm: CIE
 * 015:2004 Table T.1 / ISO 11664-2 = CIE S 014-2. 300-780 nm copied from colour-science's
 * colour/colorimetry/datasets/illuminants/sds.py, 785-830 nm from pbrt-v4's
 * CIE_Illum_D6500 (floats, rounded to the table's 4 decimals; two other public copies
 * give the same digits). The two agree on 300-780 nm to 1e-7 relative. */
#define D65_LO 300.0
#define D65_N 107
static const double d655[D65_N] = {
    0.0341, 1.6643, 3.2945, 11.7652, 20.236, 28.6447, 37.0535, 38.5011,  /* 300 */
    39.9488, 42.4302, 44.9117, 45.775, 46.6383, 49.3637, 52.0891, 51.0323,  /* 340 */
    49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589,  /* 380 */
    93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41,  /* 420 */
    117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082,  /* 460 */
    109.354, 108.578, 107.802, 106.296, 104.79, 106.239, 107.689, 106.047,  /* 500 */
    104.405, 104.225, 104.046, 102.023, 100.0, 98.1671, 96.3342, 96.0611,  /* 540 */
    95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489,  /* 580 */
    87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207,  /* 620 */
    80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652,  /* 660 */
    71.6091, 72.979, 74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863,  /* 700 */
    75.087, 69.3398, 63.5927, 55.0054, 46.4182, 56.6118, 66.8054, 65.0941,  /* 740 */
    63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054, 51.959, 54.6998,  /* 780 */
    57.4406, 58.8765, 60.3125,  /* 820 */
};

/* IEC 61966-2-1 (sRGB), XYZ to linear RGB, D65 white at Y = 1. */
static const double xyz_to_srgb[3][3] = {
    {3.2406, -1.5372, -0.4986},
    {-0.9689, 1.8758, 0.0415},
    {0.0557, -0.2040, 1.0570},
};

/* Row i of a 5 nm table of n rows from lo, and the fraction t in [0, 1) of the way to row
 * i + 1 (the last row itself: i = n - 1, t = 0). -1 outside the table or for NaN. */
static int row(double wl, double lo, int n, double *t)
{
    if (!(wl >= lo && wl <= lo + 5.0 * (n - 1))) return -1;
    double x = (wl - lo) / 5.0;
    int i = (int)x;
    if (i >= n - 1) i = n - 1, x = i; /* wl at the last row */
    *t = x - i;
    return i;
}

/* a + t (b - a) with t == 0 read as a alone, so a row's value comes back exactly. */
static double lerp(double a, double b, double t)
{
    return t == 0 ? a : a + t * (b - a);
}

void lsqt_cie1931(double wl_nm, double xyz[3])
{
    double t;
    int i = row(wl_nm, CMF_LO, CMF_N, &t);
    for (int k = 0; k < 3; k++) xyz[k] = i < 0 ? 0 : lerp(cmf5[i][k], t == 0 ? 0 : cmf5[i + 1][k], t);
}

double lsqt_d65(double wl_nm)
{
    double t;
    int i = row(wl_nm, D65_LO, D65_N, &t);
    return i < 0 ? 0 : lerp(d655[i], t == 0 ? 0 : d655[i + 1], t);
}

void lsqt_xyz_to_linear_srgb(const double xyz[3], double rgb[3])
{
    double in[3] = {xyz[0], xyz[1], xyz[2]}; /* xyz may be rgb */
    for (int r = 0; r < 3; r++)
        rgb[r] = xyz_to_srgb[r][0] * in[0] + xyz_to_srgb[r][1] * in[1] + xyz_to_srgb[r][2] * in[2];
}

/* The spectrum's XYZ and the white's (v == 1), both over the white's Y. The weights
 * D65 * cmf at 1 nm are worked out per call, so nothing is shared between threads: 8 to
 * 10 us a call with 31 bands (a 512 x 512 preview, 2 to 3 s of one core; one with many
 * pixels may want the weights worked out once). */
static int spectrum_xyz(int n, const double *wl, const double *v, double xyz[3], double white[3])
{
    if (n < 1 || !wl || !v) return -1;
    for (int i = 0; i < n; i++)
        if (!isfinite(wl[i]) || (i > 0 && !(wl[i] > wl[i - 1]))) return -1;
    double s[3] = {0, 0, 0}, w[3] = {0, 0, 0};
    int j = 0; /* past wl[0]: wl[j] <= lambda, and lambda < wl[j + 1] unless j is the last */
    for (int k = 0; k <= 470; k++) {
        double l = 360 + k, c[3], e = lsqt_d65(l), vl;
        lsqt_cie1931(l, c);
        while (j + 1 < n && wl[j + 1] <= l) j++;
        if (l <= wl[0] || j == n - 1)
            vl = l <= wl[0] ? v[0] : v[n - 1]; /* the end values held */
        else
            vl = lerp(v[j], v[j + 1], (l - wl[j]) / (wl[j + 1] - wl[j]));
        for (int q = 0; q < 3; q++) {
            s[q] += vl * e * c[q];
            w[q] += e * c[q];
        }
    }
    for (int q = 0; q < 3; q++) xyz[q] = s[q] / w[1], white[q] = w[q] / w[1];
    return 0;
}

int lsqt_spectrum_to_xyz(int n, const double *wl_nm, const double *v, double xyz[3])
{
    double out[3], white[3];
    if (!xyz || spectrum_xyz(n, wl_nm, v, out, white)) return -1;
    for (int q = 0; q < 3; q++) xyz[q] = out[q];
    return 0;
}

/* The white correction: the tables' D65 (X, Z = 0.950471, 1.088678 summed at 1 nm) is not
 * quite the white the 4-digit matrix was made for (0.9505, 1.0890), so v == 1 would come
 * out (1.00008, 1.00007, 0.99967). Each channel is divided by the white's, so a flat
 * spectrum, the commonest (one band, a grey material), is exactly grey in an export and
 * in a preview; a change of 4e-4 at most, below what 8-bit output shows. */
int lsqt_spectrum_to_srgb(int n, const double *wl_nm, const double *v, double rgb[3])
{
    double xyz[3], white[3];
    if (!rgb || spectrum_xyz(n, wl_nm, v, xyz, white)) return -1;
    lsqt_xyz_to_linear_srgb(xyz, xyz);
    lsqt_xyz_to_linear_srgb(white, white);
    for (int q = 0; q < 3; q++) rgb[q] = xyz[q] / white[q];
    return 0;
}

/* "%.10g": up to 1e6 nm (the parser's bound) 10 digits keep 0.001 nm steps apart. A
 * caller's setlocale may make printf's point ','; a file name keeps '.'. */
/* Band b's wavelength with d decimals, the integer part zero-padded to w digits, '.' as
 * the decimal point whatever the locale; no "nm". Returns the length, or -1. */
static int wl_label(double wl, int w, int d, char *buf, size_t cap)
{
    int len = snprintf(buf, cap, "%0*.*f", d ? w + 1 + d : w, d, wl);
    if (len < 0 || (size_t)len >= cap) return -1;
    const char *point = localeconv()->decimal_point;
    size_t pl = strlen(point);
    char *p = d && pl && strcmp(point, ".") ? strstr(buf, point) : NULL;
    if (p) { /* the label only gets shorter */
        *p = '.';
        memmove(p + 1, p + pl, strlen(p + pl) + 1);
        len -= (int)pl - 1;
    }
    return len;
}

int lsqt_band_names_init(lsqt_band_names *nm, int n_bands, const double *wl_or_null, int *clash)
{
    nm->n_bands = n_bands, nm->wl = wl_or_null, nm->width = 1, nm->decimals = 0;
    if (!wl_or_null) {
        for (int m = n_bands - 1; m >= 10; m /= 10) nm->width++;
        return 0;
    }
    if (n_bands < 1) return 0;
    char a[64], b[64];
    for (int d = 0; d <= 9; d++) {
        /* the largest wavelength has the widest integer part (after rounding, too) */
        int len = wl_label(wl_or_null[n_bands - 1], 1, d, a, sizeof a);
        if (len < 0) break;
        nm->width = d ? len - 1 - d : len, nm->decimals = d;
        int k = 0, exact = 1;
        const double scale = pow(10.0, d);
        wl_label(wl_or_null[0], 1, d, a, sizeof a);
        for (; k < n_bands; k++) {
            /* every label shows its wavelength (to 1e-9 nm: 412.5 is not "412") */
            exact = exact && fabs(wl_or_null[k] - round(wl_or_null[k] * scale) / scale) <= 1e-9;
            if (k + 1 == n_bands) break;
            /* increasing: only neighbours can share a label */
            wl_label(wl_or_null[k + 1], 1, d, b, sizeof b);
            if (strcmp(a, b) == 0) break;
            memcpy(a, b, sizeof a);
        }
        if (k + 1 == n_bands && (exact || d == 9)) return 0;
        if (d == 9 && k + 1 < n_bands) {
            if (clash) *clash = k;
            return -1;
        }
    }
    if (clash) *clash = 0;
    return -1;
}

const char *lsqt_band_label(const lsqt_band_names *nm, int b, char *buf, size_t cap)
{
    if (!buf || !nm || b < 0 || b >= nm->n_bands) return NULL;
    int len;
    if (nm->wl) {
        len = wl_label(nm->wl[b], nm->width, nm->decimals, buf, cap);
        if (len < 0 || (size_t)len + 2 >= cap) return NULL;
        memcpy(buf + len, "nm", 3);
        return buf;
    }
    if (nm->n_bands == 3)
        len = snprintf(buf, cap, "%c", "RGB"[b]);
    else
        len = snprintf(buf, cap, "%0*d", nm->width, b);
    return len < 0 || (size_t)len >= cap ? NULL : buf;
}

const char *lsqt_band_label_one(int n_bands, const double *wl_or_null, int b, char *buf, size_t cap)
{
    lsqt_band_names nm;
    lsqt_band_names_init(&nm, n_bands, wl_or_null, NULL);
    return lsqt_band_label(&nm, b, buf, cap);
}
