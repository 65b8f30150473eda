/* LSS round trip, and refusal of every kind of damage (no OpenCL needed). */
#define _XOPEN_SOURCE 700 /* mkdtemp */
#include <math.h>
#include <stdlib.h>
#include <unistd.h>

#include "check.h"
#include "lsqt/lss.h"
#include "lsqt/util.h"

static void fill(lsqt_state *st)
{
    lsqt_state_init(st, "Medium eta=1\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium eta=1\n", 0x1234abcdULL, 42, 3,
                    16, 1);
    const uint64_t r[] = {0, 100000, 100256, 123712}; /* 123456 paths, a gap between */
    lsqt_state_set_ranges(st, r, 2);
    st->span_end = 200000;
    st->flags = 2;
    for (int s = 0; s < 3; s++) st->theta_o[s] = 0.1 * s;
    for (size_t i = 0; i < (size_t)3 * 16; i++) { /* distinct unit vectors */
        const double a = 0.37 * (double)i, z = cos(0.05 * (double)i);
        st->wi[4 * i] = (float)(sqrt(1 - z * z) * cos(a));
        st->wi[4 * i + 1] = (float)(sqrt(1 - z * z) * sin(a));
        st->wi[4 * i + 2] = (float)z;
        st->wi[4 * i + 3] = 0.0f;
    }
    for (size_t i = 0; i < lsqt_state_nee_count(st); i++) {
        st->nee[i].lo = i * 0x9E3779B97F4A7C15ULL;
        st->nee[i].hi = i * 0x5851F42D4C957F2DULL; /* both words must round-trip */
    }
    for (size_t i = 0; i < lsqt_state_scalar_count(st); i++) st->scalars[i].lo = i * 77, st->scalars[i].hi = i;
    for (size_t i = 0; i < lsqt_state_hist_count(st); i++) st->hist[i].lo = i ^ 0xFFFF, st->hist[i].hi = ~i;
    st->slice_flags[1] = LSQT_SLICE_BELOW;
}

int main(void)
{
    lsqt_state a, b;
    char err[512];
    fill(&a);
    /* A private temporary folder: tests write nowhere else. */
    char dir[] = "/tmp/lsqt_test_lss.XXXXXX", path[64];
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(path, sizeof path, "%s/state.lss", dir);
    CHECK(lsqt_lss_write(path, &a, err, sizeof err) == 0, "%s", err);
    CHECK(lsqt_lss_read(path, &b, err, sizeof err) == 0, "%s", err);
    CHECK(strcmp(a.canonical, b.canonical) == 0, "canonical text differs");
    CHECK(a.hash == b.hash && a.seed == b.seed && a.paths == b.paths && a.flags == b.flags, "header differs");
    CHECK(a.n_slices == b.n_slices && a.n_wi == b.n_wi && a.transmits == b.transmits, "shape differs");
    CHECK(b.n_ranges == 2 && memcmp(a.ranges, b.ranges, 4 * sizeof *a.ranges) == 0 && b.span_end == 200000 &&
              b.paths == 123456,
          "path ranges differ (%d ranges, span %llu)", b.n_ranges, (unsigned long long)b.span_end);
    CHECK(memcmp(a.slice_flags, b.slice_flags, 3 * sizeof *a.slice_flags) == 0, "slice flags differ");
    CHECK(memcmp(a.theta_o, b.theta_o, 3 * sizeof(double)) == 0, "theta_o differs");
    CHECK(memcmp(a.wi, b.wi, (size_t)3 * 16 * 4 * sizeof(float)) == 0, "wi differs");
    CHECK(memcmp(a.nee, b.nee, lsqt_state_nee_count(&a) * sizeof *a.nee) == 0, "nee differs");
    CHECK(memcmp(a.scalars, b.scalars, lsqt_state_scalar_count(&a) * sizeof *a.scalars) == 0, "scalars differ");
    CHECK(memcmp(a.hist, b.hist, lsqt_state_hist_count(&a) * sizeof *a.hist) == 0, "hist differs");
    lsqt_state_free(&b);

    /* Writing the same state twice gives the same bytes. */
    size_t n1 = 0, n2 = 0;
    char *f1 = lsqt_read_file(path, &n1, err, sizeof err);
    CHECK(lsqt_lss_write(path, &a, err, sizeof err) == 0, "%s", err);
    char *f2 = lsqt_read_file(path, &n2, err, sizeof err);
    CHECK(f1 && f2 && n1 == n2 && memcmp(f1, f2, n1) == 0, "two writes differ");

    /* Every truncation and every single-bit flip (sampled: all in the header, then about
     * 150 more spread over the tallies, each parse checking the whole CRC) is refused. */
    int accepted = 0;
    const size_t cut_step = n1 / 150 | 1, flip_step = n1 / 150 | 1;
    for (size_t cut = 0; cut < n1; cut += (cut < 256 ? 1 : cut_step)) {
        if (lsqt_lss_parse((const unsigned char *)f1, cut, &b, err, sizeof err) == 0) {
            accepted++;
            lsqt_state_free(&b);
        }
    }
    CHECK(accepted == 0, "%d truncations accepted", accepted);
    for (size_t i = 0; i < n1; i += (i < 512 ? 1 : flip_step)) {
        f1[i] ^= (char)(1 << (i % 8));
        if (lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) == 0) {
            accepted++;
            lsqt_state_free(&b);
        }
        f1[i] ^= (char)(1 << (i % 8));
    }
    CHECK(accepted == 0, "%d bit flips accepted", accepted);
    CHECK(lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) == 0, "intact copy refused: %s", err);
    lsqt_state_free(&b);

    /* The messages say what is wrong. */
    CHECK(lsqt_lss_parse((const unsigned char *)f1, 0, &b, err, sizeof err) != 0 && strstr(err, "empty file"),
          "empty: %s", err);
    CHECK(lsqt_lss_parse((const unsigned char *)f1, 1000, &b, err, sizeof err) != 0 &&
              strstr(err, "truncated at byte 1000 ("),
          "truncated: %s", err);
    CHECK(lsqt_lss_parse((const unsigned char *)f1, 50, &b, err, sizeof err) != 0 &&
              strstr(err, "truncated at byte 50 (inside the 116-byte header)"),
          "truncated header: %s", err);
    f1[n1 / 2] ^= 0x10;
    CHECK(lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) != 0 && strstr(err, "CRC mismatch"),
          "flipped: %s", err);
    f1[n1 / 2] ^= 0x10;
    f1[8] = 1;
    char want_v[64];
    snprintf(want_v, sizeof want_v, "LSS version 1, this lsqt-cl reads version %u", LSQT_LSS_VERSION);
    CHECK(lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) != 0 && strstr(err, want_v),
          "version: %s", err);
    f1[8] = (char)LSQT_LSS_VERSION;
    f1[0] = 'X';
    CHECK(lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) != 0 && strstr(err, "bad magic"),
          "magic: %s", err);
    f1[0] = 'L';
    CHECK(lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) == 0, "restored copy refused: %s", err);
    lsqt_state_free(&b);
    CHECK(lsqt_lss_read("no-such-file.lss", &b, err, sizeof err) != 0 && strstr(err, "no-such-file.lss"),
          "missing file: %s", err);
    /* Impossible contents under a valid CRC (written by the writer itself): refused, naming
     * the slice, never continued. */
    const struct {
        int slice, k;
        double theta;
        float d[3];
        const char *want;
    } bad[] = {
        {1, -1, NAN, {0}, "slice 1: theta_o nan rad, outside [0, pi/2)"},
        {2, -1, -1.0, {0}, "slice 2: theta_o -1 rad"},
        {0, -1, LSQT_PI / 2, {0}, "slice 0: theta_o 1.5708 rad"},
        {1, 3, 0.2, {NAN, 0, 1}, "slice 1: incident direction 3 (nan 0 1) is not a unit vector"},
        {0, 0, 0.0, {2, 0, 0}, "slice 0: incident direction 0 (2 0 0) is not a unit vector"},
        {2, 15, 0.2, {0, 0, 0}, "incident direction 15 (0 0 0)"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        lsqt_state c;
        fill(&c);
        if (bad[i].k < 0) c.theta_o[bad[i].slice] = bad[i].theta;
        else memcpy(c.wi + ((size_t)bad[i].slice * 16 + (size_t)bad[i].k) * 4, bad[i].d, sizeof bad[i].d);
        CHECK(lsqt_lss_write(path, &c, err, sizeof err) == 0, "%s", err);
        CHECK(lsqt_lss_read(path, &b, err, sizeof err) != 0 && strstr(err, "corrupt LSS file") &&
                  strstr(err, bad[i].want),
              "impossible state %zu: '%s'", i, err);
        lsqt_state_free(&c);
    }
    free(f1);
    free(f2);
    remove(path);
    rmdir(dir);
    lsqt_state_free(&a);
    return check_finish("test_lss");
}
