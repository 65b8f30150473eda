/* Colour from spectra (include/lsqt/colour.h): the CIE tables at their rows against the
 * published numbers, the white points they make, the sRGB matrix, spectra to linear sRGB
 * (grey stays grey, narrow bands land in their channel), the errors, and the bands'
 * labels. References: CIE 015:2004 Tables T.1 (D65) and T.4 (1931 observer), IEC
 * 61966-2-1 (sRGB matrices, D65 white 0.95047 1 1.08883). */
#include "check.h"
#include "lsqt/bands.h"
#include "lsqt/colour.h"
#include "lsqt/util.h"

#include <locale.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N_OF(a) (int)(sizeof(a) / sizeof((a)[0]))

/* The 1931 observer at its 5 nm rows, the published values (CIE 015:2004 Table T.4, the
 * CIE's 1 nm digits) typed here by hand, not copied from colour.c; and between rows. */
static void observer(void)
{
    static const struct {
        double wl, x, y, z;
    } rows[] = {
        {360, 0.0001299, 0.000003917, 0.0006061}, {440, 0.34828, 0.023, 1.74706},
        {450, 0.3362, 0.038, 1.77211},            {505, 0.0024, 0.4073, 0.2123},
        {555, 0.5120501, 1.0, 0.00575},           {600, 1.0622, 0.631, 0.0008},
        {700, 0.01135916, 0.004102, 0},           {830, 0.000001251141, 0.00000045181, 0},
    };
    for (int i = 0; i < N_OF(rows); i++) {
        double c[3];
        lsqt_cie1931(rows[i].wl, c);
        const double want[3] = {rows[i].x, rows[i].y, rows[i].z};
        /* 1e-6: the table keeps the CIE's 1 nm digits (0.5120501 at 555 nm) */
        for (int k = 0; k < 3; k++)
            CHECK(fabs(c[k] - want[k]) <= 1e-6 * want[k] + 1e-15, "%g nm, %c-bar: %.10g, published %.10g",
                  rows[i].wl, "xyz"[k], c[k], want[k]);
    }
    /* halfway between 600 and 605 nm: the mean of the rows (605: 1.0456 0.5668 0.0006) */
    double c[3], a[3], b[3];
    lsqt_cie1931(602.5, c);
    CHECK(fabs(c[0] - (1.0622 + 1.0456) / 2) < 1e-12 && fabs(c[1] - (0.631 + 0.5668) / 2) < 1e-12 &&
              fabs(c[2] - (0.0008 + 0.0006) / 2) < 1e-12, "602.5 nm: %.10g %.10g %.10g", c[0], c[1], c[2]);
    /* a fifth of the way from 445 nm (0.34806 0.0298 1.7826) to 450 nm */
    lsqt_cie1931(446, c);
    CHECK(fabs(c[2] - (1.7826 + 0.2 * (1.77211 - 1.7826))) < 1e-12, "446 nm z-bar %.10g", c[2]);
    /* linear: at any point between two rows, on the chord */
    lsqt_cie1931(515, a), lsqt_cie1931(520, b), lsqt_cie1931(518.75, c);
    for (int k = 0; k < 3; k++)
        CHECK(fabs(c[k] - (a[k] + 0.75 * (b[k] - a[k]))) < 1e-12, "518.75 nm, %c-bar %.10g", "xyz"[k], c[k]);
    /* outside 360-830 nm and NaN: 0 */
    const double outside[] = {359.999, 830.001, 0, -550, 2000, NAN};
    for (int i = 0; i < N_OF(outside); i++) {
        lsqt_cie1931(outside[i], c);
        CHECK(c[0] == 0 && c[1] == 0 && c[2] == 0, "%g nm: %g %g %g", outside[i], c[0], c[1], c[2]);
    }
    /* the functions were normalised so the equal-energy spectrum is white, x = y = 1/3,
     * with the integral of y-bar 106.857 nm (CIE 015:2004, 7.1) */
    double s[3] = {0, 0, 0};
    for (int l = 360; l <= 830; l++) {
        lsqt_cie1931(l, c);
        for (int k = 0; k < 3; k++) s[k] += c[k];
    }
    double sum = s[0] + s[1] + s[2];
    CHECK(fabs(s[0] / sum - 1.0 / 3) < 1e-4 && fabs(s[1] / sum - 1.0 / 3) < 1e-4, "E: x %.6f y %.6f", s[0] / sum,
          s[1] / sum);
    CHECK_REL(s[1], 106.857, 1e-3);
}

/* D65 at its rows (CIE 015:2004 Table T.1), between them, and outside. */
static void illuminant(void)
{
    static const double rows[][2] = {{300, 0.0341}, {360, 46.6383}, {450, 117.008}, {555, 102.023},
                                     {560, 100.0},  {760, 46.4182}, {780, 63.3828}, {830, 60.3125}};
    for (int i = 0; i < N_OF(rows); i++)
        CHECK(fabs(lsqt_d65(rows[i][0]) - rows[i][1]) <= 1e-6 * rows[i][1], "D65(%g) = %.10g, published %g",
              rows[i][0], lsqt_d65(rows[i][0]), rows[i][1]);
    CHECK(lsqt_d65(560) == 100, "D65 is 100 at 560 nm by definition: %.17g", lsqt_d65(560));
    CHECK(fabs(lsqt_d65(557.5) - (102.023 + 100) / 2) < 1e-12, "557.5 nm: %.10g", lsqt_d65(557.5));
    CHECK(lsqt_d65(299.99) == 0 && lsqt_d65(830.01) == 0 && lsqt_d65(NAN) == 0, "outside: not 0");
}

/* D65's white point from the tables, summed here at 1 nm as lsqt_spectrum_to_xyz says it
 * sums; then the module's own sum; and the matrix at the white. */
static void white_point(void)
{
    double s[3] = {0, 0, 0}, c[3];
    for (int l = 360; l <= 830; l++) {
        lsqt_cie1931(l, c);
        for (int k = 0; k < 3; k++) s[k] += lsqt_d65(l) * c[k];
    }
    const double published[3] = {0.95047, 1.0, 1.08883};
    for (int k = 0; k < 3; k++)
        CHECK(fabs(s[k] / s[1] - published[k]) < 1e-3, "D65 %c = %.6f, published %.5f", "XYZ"[k], s[k] / s[1],
              published[k]);
    /* a flat spectrum (one band) through the module: the same sums */
    double xyz[3], one = 1, wl = 550;
    CHECK(lsqt_spectrum_to_xyz(1, &wl, &one, xyz) == 0, "flat spectrum refused");
    for (int k = 0; k < 3; k++)
        CHECK(fabs(xyz[k] - s[k] / s[1]) < 1e-12, "module %c %.15g vs %.15g", "XYZ"[k], xyz[k], s[k] / s[1]);
    /* the tables' white through the matrix is white to 2e-3 without any correction (the
     * correction in lsqt_spectrum_to_srgb is small) */
    double rgb[3];
    lsqt_xyz_to_linear_srgb(xyz, rgb);
    CHECK(fabs(rgb[0] - 1) < 2e-3 && fabs(rgb[1] - 1) < 2e-3 && fabs(rgb[2] - 1) < 2e-3,
          "the tables' white is (%.6f %.6f %.6f) in sRGB", rgb[0], rgb[1], rgb[2]);
}

/* The XYZ -> sRGB matrix against IEC 61966-2-1's sRGB -> XYZ: the primaries and the
 * published white come out as the unit vectors and (1, 1, 1). */
static void matrix(void)
{
    static const double to_xyz[3][3] = {
        {0.4124, 0.3576, 0.1805}, {0.2126, 0.7152, 0.0722}, {0.0193, 0.1192, 0.9505}};
    for (int p = 0; p < 3; p++) {
        double xyz[3] = {to_xyz[0][p], to_xyz[1][p], to_xyz[2][p]}, rgb[3];
        lsqt_xyz_to_linear_srgb(xyz, rgb);
        for (int k = 0; k < 3; k++)
            CHECK(fabs(rgb[k] - (k == p)) < 1e-3, "primary %c: channel %c %.6f", "RGB"[p], "RGB"[k], rgb[k]);
    }
    double w[3] = {0.95047, 1.0, 1.08883};
    lsqt_xyz_to_linear_srgb(w, w); /* in place, as the header allows */
    CHECK(fabs(w[0] - 1) < 1e-3 && fabs(w[1] - 1) < 1e-3 && fabs(w[2] - 1) < 1e-3, "D65: %.6f %.6f %.6f", w[0],
          w[1], w[2]);
}

static double max_diff(const double a[3], const double b[3])
{
    return fmax(fabs(a[0] - b[0]), fmax(fabs(a[1] - b[1]), fabs(a[2] - b[2])));
}

/* Spectra to linear sRGB: grey, the held ends and the linear segments, linearity. */
static void grey_and_shape(void)
{
    double rgb[3];
    const double wl3[] = {450, 550, 650}, half[] = {0.5, 0.5, 0.5};
    CHECK(lsqt_spectrum_to_srgb(3, wl3, half, rgb) == 0 && fabs(rgb[0] - 0.5) < 1e-9 && fabs(rgb[1] - 0.5) < 1e-9 &&
              fabs(rgb[2] - 0.5) < 1e-9, "v = 0.5: %.12f %.12f %.12f", rgb[0], rgb[1], rgb[2]);
    double wl = 700, one = 1;
    CHECK(lsqt_spectrum_to_srgb(1, &wl, &one, rgb) == 0 && rgb[0] == 1 && rgb[1] == 1 && rgb[2] == 1,
          "v = 1 (one band) is exactly white: %.17g %.17g %.17g", rgb[0], rgb[1], rgb[2]);
    /* the ends held: (400: 0.2, 700: 0.8) is (360: 0.2, 400: 0.2, 700: 0.8, 830: 0.8) */
    const double wa[] = {400, 700}, va[] = {0.2, 0.8}, wb[] = {360, 400, 700, 830}, vb[] = {0.2, 0.2, 0.8, 0.8};
    double ra[3], rb[3];
    CHECK(lsqt_spectrum_to_srgb(2, wa, va, ra) == 0 && lsqt_spectrum_to_srgb(4, wb, vb, rb) == 0 &&
              max_diff(ra, rb) < 1e-12, "held ends: %.3g apart", max_diff(ra, rb));
    /* linear between samples: the ramp's own midpoint added changes nothing */
    const double wc[] = {400, 550, 700}, vc[] = {0.2, 0.5, 0.8};
    CHECK(lsqt_spectrum_to_srgb(3, wc, vc, rb) == 0 && max_diff(ra, rb) < 1e-12, "midpoint: %.3g apart",
          max_diff(ra, rb));
    /* the ramp rises to the red: more red than blue */
    CHECK(ra[0] > ra[2], "a ramp up to the red: R %.4f, B %.4f", ra[0], ra[2]);
    /* linear in v: 2 v1 + 3 v2 from the parts */
    const double w5[] = {420, 480, 530, 610, 690}, v1[] = {0.1, 0.9, 0.3, 0.0, 0.6}, v2[] = {0.5, 0.2, 0.7, 0.4, 0.1};
    double mix[5], r1[3], r2[3], rm[3], want[3];
    for (int i = 0; i < 5; i++) mix[i] = 2 * v1[i] + 3 * v2[i];
    lsqt_spectrum_to_srgb(5, w5, v1, r1), lsqt_spectrum_to_srgb(5, w5, v2, r2), lsqt_spectrum_to_srgb(5, w5, mix, rm);
    for (int k = 0; k < 3; k++) want[k] = 2 * r1[k] + 3 * r2[k];
    CHECK(max_diff(rm, want) < 1e-12, "not linear: %.3g", max_diff(rm, want));
}

/* A band of 1 between lo and hi nm (samples every 5 nm from lo - 10 to hi + 10, 0 outside
 * the band) to linear sRGB. */
static void spike(int lo, int hi, double rgb[3])
{
    double wl[64], v[64];
    int n = 0;
    for (int l = lo - 10; l <= hi + 10; l += 5, n++) wl[n] = l, v[n] = l >= lo && l <= hi;
    CHECK(lsqt_spectrum_to_srgb(n, wl, v, rgb) == 0, "spike %d-%d refused", lo, hi);
}

/* Narrow bands land in their channel; the others stay small. Spectral greens lie outside
 * the sRGB gamut, so a green band's red is negative: it is not clamped. */
static void spikes(void)
{
    double r[3];
    spike(610, 620, r); /* orange-red: R 0.29, G -0.009, B -0.005 */
    CHECK(r[0] > 0.1 && r[0] > r[1] && r[0] > r[2] && fabs(r[1]) < 0.1 * r[0] && fabs(r[2]) < 0.1 * r[0],
          "610-620 nm: %.4f %.4f %.4f", r[0], r[1], r[2]);
    spike(520, 540, r); /* green: R -0.19, G 0.36, B -0.03 */
    CHECK(r[1] > 0.1 && r[1] > r[0] && r[1] > r[2] && fabs(r[2]) < 0.1 * r[1] && r[0] < 0,
          "520-540 nm: %.4f %.4f %.4f", r[0], r[1], r[2]);
    spike(440, 460, r); /* blue: R 0.035, G -0.045, B 0.49 */
    CHECK(r[2] > 0.1 && r[2] > r[0] && r[2] > r[1] && fabs(r[0]) < 0.1 * r[2] && fabs(r[1]) < 0.1 * r[2],
          "440-460 nm: %.4f %.4f %.4f", r[0], r[1], r[2]);
    /* beyond the eye: nothing */
    const double ir[] = {900, 1000}, v[] = {1, 1}, zero[] = {0, 0};
    double a[3], b[3];
    CHECK(lsqt_spectrum_to_srgb(2, ir, v, a) == 0 && a[0] == 1 && a[1] == 1 && a[2] == 1,
          "bands all in the infrared hold their value over the visible: %g %g %g", a[0], a[1], a[2]);
    const double wl[] = {300, 350, 850, 900}, vv[] = {1, 0, 0, 1};
    CHECK(lsqt_spectrum_to_srgb(4, wl, vv, b) == 0 && b[0] == 0 && b[1] == 0 && b[2] == 0 &&
              lsqt_spectrum_to_srgb(2, ir, zero, a) == 0 && a[0] == 0,
          "light only outside 360-830 nm is black: %g %g %g", b[0], b[1], b[2]);
}

static void errors(void)
{
    const double ok[] = {450, 550}, down[] = {550, 450}, same[] = {450, 450}, nan_wl[] = {450, NAN},
                 inf_wl[] = {INFINITY}, v[] = {0.5, 0.5};
    double rgb[3] = {-7, -7, -7}, xyz[3] = {-7, -7, -7};
    CHECK(lsqt_spectrum_to_srgb(0, ok, v, rgb) == -1, "n = 0");
    CHECK(lsqt_spectrum_to_srgb(-1, ok, v, rgb) == -1, "n = -1");
    CHECK(lsqt_spectrum_to_srgb(2, down, v, rgb) == -1, "decreasing");
    CHECK(lsqt_spectrum_to_srgb(2, same, v, rgb) == -1, "equal wavelengths");
    CHECK(lsqt_spectrum_to_srgb(2, nan_wl, v, rgb) == -1, "NaN wavelength");
    CHECK(lsqt_spectrum_to_srgb(1, inf_wl, v, rgb) == -1, "infinite wavelength");
    CHECK(lsqt_spectrum_to_srgb(2, NULL, v, rgb) == -1 && lsqt_spectrum_to_srgb(2, ok, NULL, rgb) == -1 &&
              lsqt_spectrum_to_srgb(2, ok, v, NULL) == -1, "NULL");
    CHECK(rgb[0] == -7 && rgb[1] == -7 && rgb[2] == -7, "rgb written on an error");
    CHECK(lsqt_spectrum_to_xyz(0, ok, v, xyz) == -1 && lsqt_spectrum_to_xyz(2, down, v, xyz) == -1 &&
              xyz[0] == -7 && xyz[1] == -7 && xyz[2] == -7, "xyz: errors");
}

/* The labels of n bands (wl: NULL or their wavelengths) equal want[]. */
static void labels_are(int n, const double *wl, const char *const *want, const char *what)
{
    lsqt_band_names nm;
    char buf[64];
    CHECK(lsqt_band_names_init(&nm, n, wl, NULL) == 0, "%s: names", what);
    for (int b = 0; b < n; b++) {
        const char *s = lsqt_band_label(&nm, b, buf, sizeof buf);
        CHECK(s == buf && strcmp(s, want[b]) == 0, "%s, band %d: '%s', want '%s'", what, b, s ? s : "(null)", want[b]);
    }
}

static void labels(void)
{
    char buf[64];
    const char *rgb[] = {"R", "G", "B"}, *five[] = {"0", "1", "2", "3", "4"};
    labels_are(3, NULL, rgb, "3 unnamed bands");
    labels_are(5, NULL, five, "5 unnamed bands");
    /* unnamed: the index padded to the width of n - 1, so that ls sorts them */
    const char *eleven[] = {"00", "01", "02", "03", "04", "05", "06", "07", "08", "09", "10"};
    labels_are(11, NULL, eleven, "11 unnamed bands");
    lsqt_band_names nm;
    lsqt_band_names_init(&nm, 101, NULL, NULL);
    CHECK(lsqt_band_label(&nm, 7, buf, sizeof buf) && strcmp(buf, "007") == 0, "101 unnamed bands, band 7: '%s'", buf);
    /* whole wavelengths of one width stay as they were */
    const double vis[] = {450, 550, 650};
    const char *vis_want[] = {"450nm", "550nm", "650nm"};
    labels_are(3, vis, vis_want, "450,550,650");
    /* one format for all: the integer part padded, the same decimals */
    const double wide[] = {400, 412.5, 1000, 2500};
    const char *wide_want[] = {"0400.0nm", "0412.5nm", "1000.0nm", "2500.0nm"};
    labels_are(4, wide, wide_want, "400,412.5,1000,2500");
    /* the least decimals that separate every pair: 8 here (500.5 and 500.50000001) */
    const double close[] = {500, 500.0001, 500.5, 500.50000001};
    const char *close_want[] = {"500.00000000nm", "500.00010000nm", "500.50000000nm", "500.50000001nm"};
    labels_are(4, close, close_want, "500,500.0001,500.5,500.50000001");
    /* rounding to the decimals can widen the integer part: 999.96 and 1000 need 2 */
    const double carry[] = {999.96, 1000};
    const char *carry_want[] = {"0999.96nm", "1000.00nm"};
    labels_are(2, carry, carry_want, "999.96,1000");
    const double big[] = {2, 1e6};
    const char *big_want[] = {"0000002nm", "1000000nm"};
    labels_are(2, big, big_want, "2,1e6");
    /* no decimals up to 9 separate them: refused, naming the first of the two */
    const double twins[] = {400, 500, 500.0000000001};
    int clash = -1;
    CHECK(lsqt_band_names_init(&nm, 3, twins, &clash) == -1 && clash == 1, "500 and 500.0000000001: clash %d", clash);
    double *w = NULL;
    int n = 0;
    char err[512];
    CHECK(lsqt_parse_wavelengths("400,500,500.0000000001", &w, &n, err, sizeof err) == 2 && !w && n == 0 &&
              strstr(err, "bands 2 and 3"), "twins refused: %s", err);
    CHECK(lsqt_parse_wavelengths("500,500.000000001", &w, &n, err, sizeof err) == 0 && n == 2, "1e-9 apart: %s", err);
    lsqt_band_names_init(&nm, n, w, NULL);
    CHECK(lsqt_band_label(&nm, 1, buf, sizeof buf) && strcmp(buf, "500.000000001nm") == 0, "1e-9 apart: '%s'", buf);
    free(w);
    /* a range: padded to the widest */
    CHECK(lsqt_parse_wavelengths("400:2500:10", &w, &n, err, sizeof err) == 0 && n == 211, "400:2500:10: %s", err);
    lsqt_band_names_init(&nm, n, w, NULL);
    CHECK(lsqt_band_label(&nm, 0, buf, sizeof buf) && strcmp(buf, "0400nm") == 0, "400:2500:10, first: '%s'", buf);
    CHECK(lsqt_band_label(&nm, n - 1, buf, sizeof buf) && strcmp(buf, "2500nm") == 0, "400:2500:10, last: '%s'", buf);
    CHECK(lsqt_band_label_one(n, w, 60, buf, sizeof buf) && strcmp(buf, "1000nm") == 0, "label_one: '%s'", buf);
    free(w);
    /* not a band, no room */
    lsqt_band_names_init(&nm, 3, NULL, NULL);
    CHECK(lsqt_band_label(&nm, 3, buf, sizeof buf) == NULL && lsqt_band_label(&nm, -1, buf, sizeof buf) == NULL &&
              lsqt_band_label(&nm, 0, NULL, 8) == NULL && lsqt_band_label(NULL, 0, buf, sizeof buf) == NULL,
          "band out of range");
    lsqt_band_names_init(&nm, 3, vis, NULL);
    CHECK(lsqt_band_label(&nm, 0, buf, 5) == NULL && lsqt_band_label(&nm, 0, buf, 6) == buf,
          "cap: '450nm' needs 6 bytes");
    lsqt_band_names_init(&nm, 11, NULL, NULL);
    CHECK(lsqt_band_label(&nm, 10, buf, 2) == NULL && lsqt_band_label(&nm, 10, buf, 3) == buf, "cap: '10' needs 3");
    /* every band of 0.001 nm steps, as --wavelengths makes them (start + i step): each
     * label sorts after the one before (so distinct, and ls lists them in order) */
    const char *lists[] = {"400:404:0.001", "999996:1000000:0.001", "1:4096:1"};
    const int counts[] = {4001, 4001, 4096};
    for (int i = 0; i < N_OF(lists); i++) {
        char prev[64] = "";
        CHECK(lsqt_parse_wavelengths(lists[i], &w, &n, err, sizeof err) == 0 && n == counts[i], "%s: %s", lists[i], err);
        lsqt_band_names_init(&nm, n, w, NULL);
        int order = 0;
        for (int b = 0; b < n; b++) {
            if (!lsqt_band_label(&nm, b, buf, sizeof buf) || (b && strcmp(buf, prev) <= 0)) order++;
            strcpy(prev, buf);
        }
        CHECK(order == 0, "%s: %d labels do not sort after the one before", lists[i], order);
        free(w);
    }
    /* a caller's comma locale does not reach the file name, where such a locale exists */
    if (setlocale(LC_NUMERIC, "de_DE.UTF-8") || setlocale(LC_NUMERIC, "fr_FR.UTF-8")) {
        const char *wide_c[] = {"0400.0nm", "0412.5nm", "1000.0nm", "2500.0nm"};
        labels_are(4, wide, wide_c, "under a comma locale");
        setlocale(LC_NUMERIC, "C");
    } else {
        printf("no comma locale here: the locale check did not run\n");
    }
}

/* One of examples/tables/ read with the parser a run uses. */
static int example_table(const char *name, lsqt_band_table *t)
{
    char path[1024], err[256];
    size_t len;
    snprintf(path, sizeof path, "%s/tables/%s", LSQT_EXAMPLES, name);
    char *text = lsqt_read_file(path, &len, err, sizeof err);
    CHECK(text != NULL, "%s", err);
    if (!text) return -1;
    int rc = lsqt_band_table_parse(text, len, name, t, err, sizeof err);
    free(text);
    CHECK(rc == 0, "%s", err);
    return rc ? -1 : 0;
}

/* The example tables parse, cover the visible, and look like what they say: Johnson &
 * Christy's gold (n 0.97 k 1.87 at 500 nm, n 0.13 k 4.10 at 704 nm) is yellow at normal
 * incidence, the red paint is red. */
static void example_colours(lsqt_band_table n, lsqt_band_table k, lsqt_band_table paint)
{
    CHECK(n.n == 49 && k.n == 49 && n.wl[0] < 400 && n.wl[n.n - 1] > 800, "gold: %d and %d rows, %g-%g nm", n.n, k.n,
          n.wl[0], n.wl[n.n - 1]);
    double vn = 0, vk = 0;
    lsqt_band_table_at(&n, 500, &vn), lsqt_band_table_at(&k, 500, &vk);
    CHECK(fabs(vn - 0.97) < 0.01 && fabs(vk - 1.87) < 0.01, "gold at 500 nm: n %g k %g", vn, vk);
    lsqt_band_table_at(&n, 704.46, &vn), lsqt_band_table_at(&k, 704.46, &vk);
    CHECK(vn == 0.13 && vk == 4.103, "gold at 704.46 nm (1.76 eV): n %g k %g", vn, vk);
    /* normal-incidence reflectance ((n-1)^2 + k^2) / ((n+1)^2 + k^2) on the rows near the
     * visible: R > G > B (measured 1.035 0.727 0.365; R above 1 is a saturated colour,
     * not clamped) */
    double wl[64], r[64], rgb[3];
    int m = 0;
    for (int i = 0; i < n.n && m < 64; i++) {
        if (n.wl[i] < 350 || n.wl[i] > 850) continue;
        double a = n.v[i], b = 0;
        CHECK(fabs(k.wl[i] - n.wl[i]) < 1e-9 && lsqt_band_table_at(&k, n.wl[i], &b) == 0, "k row %d", i);
        wl[m] = n.wl[i], r[m++] = ((a - 1) * (a - 1) + b * b) / ((a + 1) * (a + 1) + b * b);
    }
    CHECK(lsqt_spectrum_to_srgb(m, wl, r, rgb) == 0 && rgb[0] > rgb[1] && rgb[1] > rgb[2] && rgb[2] > 0,
          "gold: %.3f %.3f %.3f", rgb[0], rgb[1], rgb[2]);
    CHECK(paint.n == 41 && paint.wl[0] == 380 && paint.wl[40] == 780, "paint: %d rows", paint.n);
    for (int i = 0; i < paint.n; i++) {
        double want = 0.05 + 0.7 / (1 + exp(-(paint.wl[i] - 590) / 15)); /* its header's formula */
        CHECK(fabs(paint.v[i] - want) <= 5e-7, "paint at %g nm: %g, the formula %.8f", paint.wl[i], paint.v[i], want);
    }
    CHECK(lsqt_spectrum_to_srgb(paint.n, paint.wl, paint.v, rgb) == 0 && rgb[0] > 3 * rgb[1] && rgb[0] > 3 * rgb[2],
          "paint: %.3f %.3f %.3f", rgb[0], rgb[1], rgb[2]);
}

static void example_tables(void)
{
    lsqt_band_table n = {0, NULL, NULL}, k = n, paint = n;
    int bad = example_table("gold_n.txt", &n);
    bad |= example_table("gold_k.txt", &k);
    bad |= example_table("red_paint_albedo.txt", &paint);
    if (!bad) example_colours(n, k, paint);
    lsqt_band_table_free(&n), lsqt_band_table_free(&k), lsqt_band_table_free(&paint);
}

int main(void)
{
    observer();
    illuminant();
    white_point();
    matrix();
    grey_and_shape();
    spikes();
    errors();
    labels();
    example_tables();
    return check_finish("test_colour");
}
