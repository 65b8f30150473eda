/* Wavelength lists and spectral tables (include/lsqt/bands.h): --wavelengths's two forms
 * and their errors, and a table's reading, errors and linear interpolation, against values
 * worked out by hand in the checks. */
#include "check.h"
#include "lsqt/bands.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void wavelengths(void)
{
    double *w;
    int n;
    char err[256];
    CHECK(lsqt_parse_wavelengths("450,550,650", &w, &n, err, sizeof err) == 0 && n == 3 && w[0] == 450 &&
              w[1] == 550 && w[2] == 650, "list: %s", err);
    free(w);
    /* both ends included: 400, 410, ..., 2500 is 211 bands */
    CHECK(lsqt_parse_wavelengths("400:2500:10", &w, &n, err, sizeof err) == 0 && n == 211 && w[0] == 400 &&
              w[210] == 2500 && w[1] == 410, "range: n %d, %s", n, err);
    free(w);
    /* STOP not on the grid: the last band is the last step below it */
    CHECK(lsqt_parse_wavelengths("400:455:10", &w, &n, err, sizeof err) == 0 && n == 6 && w[5] == 450, "n %d", n);
    free(w);
    /* a step that does not divide exactly in binary still ends on STOP */
    CHECK(lsqt_parse_wavelengths("400:700:0.1", &w, &n, err, sizeof err) == 0 && n == 3001 && w[3000] == 700,
          "n %d last %.17g", n, n ? w[n - 1] : 0.0);
    free(w);
    CHECK(lsqt_parse_wavelengths("550", &w, &n, err, sizeof err) == 0 && n == 1 && w[0] == 550, "one band");
    free(w);
    const struct {
        const char *in, *says;
    } bad[] = {{"450,450", "must increase"}, {"650,550", "(band 2)"}, {"450,,550", "bad wavelength ''"},
               {"450,x", "bad wavelength 'x'"}, {"-1", "bad wavelength '-1'"}, {"0,1", "bad wavelength '0'"},
               {"400:300:10", "START <= STOP"}, {"400:500:0", "STEP > 0"}, {"400:500", "START:STOP:STEP"},
               {"400:500:10:1", "START:STOP:STEP"}, {"1:100000:1", "at most 4096"}, {"450,", "bad wavelength ''"},
               {"nan", "bad wavelength"}, {"2e6", "bad wavelength"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = '\0';
        int rc = lsqt_parse_wavelengths(bad[i].in, &w, &n, err, sizeof err);
        CHECK(rc == 2 && w == NULL && strstr(err, bad[i].says), "'%s': rc %d, '%s'", bad[i].in, rc, err);
    }
}

static void tables(void)
{
    lsqt_band_table t;
    char err[256];
    const char *text = "# gold, n\n400 1.658\n\n500\t0.97 # a comment\n600,0.25\r\n  700 0.13\n";
    CHECK(lsqt_band_table_parse(text, strlen(text), "au.txt", &t, err, sizeof err) == 0 && t.n == 4, "%s", err);
    double v = -1;
    /* at a row: the row's value exactly; between rows: linear; outside: refused */
    CHECK(lsqt_band_table_at(&t, 500, &v) == 0 && v == 0.97, "at 500: %g", v);
    CHECK(lsqt_band_table_at(&t, 400, &v) == 0 && v == 1.658, "at 400: %g", v);
    CHECK(lsqt_band_table_at(&t, 700, &v) == 0 && v == 0.13, "at 700: %g", v);
    CHECK(lsqt_band_table_at(&t, 550, &v) == 0 && fabs(v - 0.61) < 1e-15, "at 550: %.17g (0.61)", v);
    CHECK(lsqt_band_table_at(&t, 425, &v) == 0 && fabs(v - (1.658 + 0.25 * (0.97 - 1.658))) < 1e-15, "at 425: %g", v);
    CHECK(lsqt_band_table_at(&t, 399.999, &v) == -1 && lsqt_band_table_at(&t, 700.001, &v) == -1, "outside");
    lsqt_band_table_free(&t);
    /* one row: only its own wavelength */
    CHECK(lsqt_band_table_parse("550 0.5\n", 8, "one", &t, err, sizeof err) == 0 && t.n == 1, "%s", err);
    CHECK(lsqt_band_table_at(&t, 550, &v) == 0 && v == 0.5 && lsqt_band_table_at(&t, 551, &v) == -1, "one row");
    lsqt_band_table_free(&t);
    const struct {
        const char *in, *says;
    } bad[] = {{"400 1\n400 2\n", "t.txt:2: wavelength 400 is not above"}, {"400 1\n300 2\n", "t.txt:2:"},
               {"400 1 2\n", "t.txt:1: expected two numbers"}, {"400\n", "t.txt:1: expected two numbers"},
               {"# nothing\n\n", "no rows"}, {"400 x\n", "t.txt:1:"}, {"1 2\n2 3\nfoo bar\n", "t.txt:3:"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err[0] = '\0';
        int rc = lsqt_band_table_parse(bad[i].in, strlen(bad[i].in), "t.txt", &t, err, sizeof err);
        CHECK(rc == 2 && t.n == 0 && t.wl == NULL && strstr(err, bad[i].says), "'%s': rc %d, '%s'", bad[i].in, rc, err);
    }
}

int main(void)
{
    wavelengths();
    tables();
    return check_finish("test_bands");
}
