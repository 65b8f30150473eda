/* Wavelength lists and spectral tables (include/lsqt/bands.h): --wavelengths's two forms
 * and their errors, and a table's reading, errors and linear interpolation, against values
 * worked out by hand in the checks. */
#include "check.h"
#include "lsqt/assembly.h"
#include "lsqt/bands.h"
#include "lsqt/model_list.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
               {"nan", "bad wavelength"}, {"2e6", "bad wavelength"},
               /* both ends are included: STOP must be on the grid */
               {"400:455:10", "STEP 10 does not divide STOP - START (55; both ends are included): use a STEP of 11 "
                              "or 9.166666667, or STOP 450 or 460"},
               {"400:401:2", "use a STEP of 1, or STOP 402"}};
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

/* Band b of TEXT; its error (empty when it parsed) into err. */
static int parse_band(const char *text, lsqt_bands *b, int band, lsqt_assembly *a, char err[1024])
{
    lsqt_diag d;
    int rc = lsqt_parse_band(text, strlen(text), "t.lsqt", b, band, a, &d);
    strcpy(err, d.error);
    return rc;
}

/* The parser reads band b's element of a list and band b's table value; every rule holds
 * per band and names the band. */
static void parse_per_band(void)
{
    char dir[] = "/tmp/lsqt-test-bands.XXXXXX", path[256], err[1024];
    CHECK(mkdtemp(dir) != NULL, "mkdtemp");
    snprintf(path, sizeof path, "%s/fr.txt", dir);
    FILE *f = fopen(path, "w");
    CHECK(f != NULL, "%s", path);
    if (!f) return;
    fputs("# fR of a made-up paint\n400 0.1\n500 0.3\n700 0.9\n", f);
    fclose(f);
    const double wl[] = {450, 550, 650};
    lsqt_bands b = {3, wl, dir, 0, NULL, NULL, 0};
    lsqt_assembly a;
    /* a list: element b; a table: interpolated at wl[b] (450: 0.2, 550: 0.45, 650: 0.75) */
    const char *text = "Medium\nLayer z=0 Lambertian fR=@fr.txt fT=0.05,0.1,0.15\nMedium\n";
    const double want_fr[] = {0.2, 0.45, 0.75}, want_ft[] = {0.05, 0.1, 0.15};
    for (int i = 0; i < 3; i++) {
        int rc = parse_band(text, &b, i, &a, err);
        CHECK(rc == 0 && fabs(a.layers[0].v[LSQT_LAMBERTIAN_fR] - want_fr[i]) < 1e-15 &&
                  a.layers[0].v[LSQT_LAMBERTIAN_fT] == want_ft[i],
              "band %d: rc %d fR %g fT %g %s", i, rc, rc ? 0 : a.layers[0].v[LSQT_LAMBERTIAN_fR],
              rc ? 0 : a.layers[0].v[LSQT_LAMBERTIAN_fT], err);
        if (!rc) lsqt_assembly_free(&a);
    }
    CHECK(b.n_tables == 1, "the table is read once: %d", b.n_tables);
    /* media keys and phase keys too */
    text = "Medium\nLayer z=1 Null\nMedium mus=1,2,3 mua=0.5 HenyeyGreenstein g=0.1,0.2,0.3\nLayer z=0 Null\nMedium\n";
    CHECK(parse_band(text, &b, 2, &a, err) == 0 && a.media[1].mus == 3 && a.media[1].phase.v[LSQT_HG_g] == 0.3, "%s", err);
    if (!err[0]) lsqt_assembly_free(&a);
    /* errors: each names the band where it is per band */
    const struct {
        const char *text;
        int band;
        const char *says;
    } bad[] = {
        /* fR + fT > 1 in band 3 only (0.75 + 0.3) */
        {"Medium\nLayer z=0 Lambertian fR=@fr.txt fT=0.1,0.1,0.3\nMedium\n", 2, "band 3 (650 nm): fR + fT = 1.05 exceeds 1"},
        {"Medium\nLayer z=0 Lambertian fR=0.1,0.2\nMedium\n", 0, "wrong number of values at 'fR=0.1,0.2'; expected 3"},
        {"Medium\nLayer z=0 Lambertian fR=0.1,,0.2\nMedium\n", 1, "band 2 (550 nm): empty value in the list"},
        {"Medium\nLayer z=0 Lambertian fR=0.1,1.2,0.2\nMedium\n", 1, "band 2 (550 nm): value out of range"},
        {"Medium\nLayer z=0 Lambertian fR=@missing.txt\nMedium\n", 0, "unreadable table"},
        {"Medium\nLayer z=0,1,2 Lambertian\nMedium\n", 0, "z as a value per band"},
        {"Medium\nLayer z=1 Null\nMedium eta=1.5,0.9,1.5 mus=1 HenyeyGreenstein\nLayer z=0 Null\nMedium\n", 1,
         "band 2 (550 nm): eta below 1"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        int rc = parse_band(bad[i].text, &b, bad[i].band, &a, err);
        CHECK(rc == 2 && strstr(err, bad[i].says), "case %zu: rc %d '%s'", i, rc, err);
    }
    /* a wavelength outside the table */
    const double far[] = {450, 550, 750};
    lsqt_bands b2 = {3, far, dir, 0, NULL, NULL, 0};
    CHECK(parse_band("Medium\nLayer z=0 Lambertian fR=@fr.txt\nMedium\n", &b2, 2, &a, err) == 2 &&
              strstr(err, "band 3 (750 nm): wavelength outside the table") && strstr(err, "400 to 700 nm"),
          "%s", err);
    lsqt_bands_free(&b2);
    /* unnamed bands (lists only): no tables, and the band has no wavelength in messages */
    lsqt_bands rgb = {3, NULL, dir, 0, NULL, NULL, 0};
    CHECK(parse_band("Medium\nLayer z=0 Lambertian fR=@fr.txt\nMedium\n", &rgb, 0, &a, err) == 2 &&
              strstr(err, "a table without wavelengths"), "%s", err);
    CHECK(parse_band("Medium\nLayer z=0 Lambertian fR=0.9,0.9,0.5 fT=0,0,0.6\nMedium\n", &rgb, 2, &a, err) == 2 &&
              strstr(err, "error: band 3: fR + fT"), "%s", err);
    /* one band (lsqt_parse): a list is refused, as before bands */
    lsqt_diag d;
    CHECK(lsqt_parse("Medium\nLayer z=0 Lambertian fR=0.1,0.2\nMedium\n", strlen("Medium\nLayer z=0 Lambertian fR=0.1,0.2\nMedium\n"), "t", NULL, 1, NULL, &a, &d) == 2 &&
              strstr(d.error, "a list of values in a run of one band"), "%s", d.error);
    lsqt_bands_free(&b);
    unlink(path);
    rmdir(dir);
}

/* Canonical text of a run with bands: a list wherever the bands differ (iter_count's too,
 * from auto per band), the '# bands' line, and it reads back to the same text; the band
 * count from the first list, and the shared decisions (pruning where every band stops, a
 * phase model kept where some band scatters). */
static void bands_canonical(void)
{
    const char *text = "Medium\nLayer z=1 NullBsdf\nMedium mus=1,0 mua=0.5 HenyeyGreensteinPhase g=0.5\n"
                       "Layer z=0 MicrosurfaceLambertian alpha=0.05,0.9 fR=0.5 fT=0,0.2\nMedium eta=1.2\n"
                       "Layer z=-1 LambertianBsdf fR=0.3\nMedium\n";
    lsqt_assembly a, b;
    lsqt_diag d;
    CHECK(lsqt_parse(text, strlen(text), "t", NULL, 0, ".", &a, &d) == 0 && a.n_bands == 2 &&
              a.wavelengths == NULL && a.n_layers == 3, "%s", d.error);
    if (a.n_bands != 2) return;
    /* band 1: mus 0 keeps HG (band 0 scatters); the floor is kept (band 1 sees through) */
    CHECK(a.band[1].media[1].phase.kind == LSQT_PHASE_HG && a.band[1].media[1].mus == 0 &&
              a.band[0].media[1].mus == 1 && a.band[0].n_layers == 3 && a.band[0].layers[1].iter_count == 1 &&
              a.band[1].layers[1].iter_count == 6, "band values");
    char buf[2048];
    size_t n = lsqt_assembly_canonical(&a, buf, sizeof buf);
    CHECK(n < sizeof buf && strncmp(buf, "# bands 2\n", 10) == 0 && strstr(buf, " mus=1,0 ") &&
              strstr(buf, " iter_count=1,6 ") && strstr(buf, " fT=0,0.20000000000000001 ") &&
              strstr(buf, " mua=0.5 "), "%s", buf);
    CHECK(lsqt_parse(buf, n, "canonical", NULL, 0, ".", &b, &d) == 0, "reads back: %s", d.error);
    char buf2[2048];
    CHECK(lsqt_assembly_canonical(&b, buf2, sizeof buf2) == n && memcmp(buf, buf2, n) == 0 &&
              lsqt_assembly_hash(&a) == lsqt_assembly_hash(&b), "round trip: %s", buf2);
    lsqt_assembly_free(&b);
    lsqt_assembly_free(&a);
    /* bands alike still say how many they are: the first key is written as a list */
    const char *alike = "Medium\nLayer z=0 LambertianBsdf fR=0.5,0.5\nMedium\n";
    CHECK(lsqt_parse(alike, strlen(alike), "t", NULL, 0, ".", &a, &d) == 0 && a.n_bands == 2, "%s", d.error);
    n = lsqt_assembly_canonical(&a, buf, sizeof buf);
    CHECK(strcmp(buf, "# bands 2\nMedium eta=1,1 mua=0 mus=0\nLayer z=0 LambertianBsdf fR=0.5 fT=0\nMedium eta=1 "
                      "mua=0 mus=0\n") == 0, "%s", buf);
    CHECK(lsqt_parse(buf, n, "canonical", NULL, 0, ".", &b, &d) == 0 && b.n_bands == 2, "%s", d.error);
    lsqt_assembly_free(&b);
    lsqt_assembly_free(&a);
    /* a failure in a later band leaves the assembly empty */
    const char *late = "Medium\nLayer z=0 LambertianBsdf fR=0.5,0.5 fT=0.2,0.6\nMedium\n";
    memset(&a, 0xff, sizeof a);
    CHECK(lsqt_parse(late, strlen(late), "t", NULL, 0, ".", &a, &d) == 2 && a.n_layers == 0 && !a.layers &&
              !a.band && strstr(d.error, "band 2: fR + fT = 1.1 exceeds 1"), "%s", d.error);
    /* a layer opaque in every band still prunes what lies below it */
    const char *opaque = "Medium\nLayer z=0 LambertianBsdf fR=0.2,0.3\nMedium eta=1.5\nLayer z=-1 LambertianBsdf\nMedium\n";
    CHECK(lsqt_parse(opaque, strlen(opaque), "t", NULL, 0, ".", &a, &d) == 0 && a.n_layers == 1 &&
              a.band[1].n_layers == 1 && a.n_pruned_layers == 1, "%s", d.error);
    lsqt_assembly_free(&a);
    /* a whole-number key takes a list, not a table */
    const double wl[] = {500, 600};
    const char *itab = "Medium\nLayer z=0 MicrosurfaceLambertian iter_count=@x.txt\nMedium\n";
    CHECK(lsqt_parse(itab, strlen(itab), "t", wl, 2, ".", &a, &d) == 2 &&
              strstr(d.error, "a table for a whole number at 'iter_count=@x.txt'"), "%s", d.error);
}

int main(void)
{
    wavelengths();
    tables();
    parse_per_band();
    bands_canonical();
    return check_finish("test_bands");
}
