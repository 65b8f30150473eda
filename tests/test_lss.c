/* LSS round trip, and refusal of every kind of damage (no OpenCL needed); the packed
 * tallies of version 6 against the format's own rules; version 5 still read; writing
 * needs no copy of the state (malloc is wrapped: -Wl,--wrap=malloc). */
#define _XOPEN_SOURCE 700 /* mkdtemp */
#include <math.h>
#include <stdlib.h>
#include <unistd.h>

#include "check.h"
#include "lsqt/bands.h"
#include "lsqt/lss.h"
#include "lsqt/util.h"

/* The largest single malloc while `watching`: the LSS writer's memory beyond the state. */
void *__real_malloc(size_t n);
void *__wrap_malloc(size_t n);
static int watching;
static size_t largest;
void *__wrap_malloc(size_t n)
{
    if (watching && n > largest) largest = n;
    return __real_malloc(n);
}

static void fill(lsqt_state *st)
{
    lsqt_state_init(st, "Medium eta=1\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium eta=1\n", 0x1234abcdULL, 42, 3,
                    16, 1, 1, NULL);
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
    /* What packing must keep: a run of zeros from slice 0's last batch of sums through all
     * its scalars into its histogram (crossing both boundaries), a run that ends slice 2,
     * and tallies of every length from 1 to 16 bytes (slice 1's scalars). */
    const size_t nb = LSQT_BATCHES * 16, sb = LSQT_BATCHES * LSQT_T_COUNT, hb = LSQT_BATCHES * LSQT_HIST_BINS;
    for (size_t i = nb - 16; i < nb; i++) st->nee[i].lo = st->nee[i].hi = 0;
    for (size_t i = 0; i < sb; i++) st->scalars[i].lo = st->scalars[i].hi = 0;
    for (size_t i = 0; i < 5; i++) st->hist[i].lo = st->hist[i].hi = 0;
    for (size_t i = 3 * hb - 100; i < 3 * hb; i++) st->hist[i].lo = st->hist[i].hi = 0;
    for (size_t j = 0; j < 16; j++) {
        lsqt_u128 *v = &st->scalars[sb + j];
        v->lo = j < 8 ? 0xA5ULL << (8 * j) : 1;
        v->hi = j < 8 ? 0 : 0xA5ULL << (8 * (j - 8));
    }
}

static void le(unsigned char **p, uint64_t v, int n)
{
    for (int i = 0; i < n; i++) *(*p)++ = (unsigned char)(v >> (8 * i));
}

/* A version-5 file of st, from that version's layout (lss.h): 16 bytes a tally, no file size. */
static unsigned char *v5_image(const lsqt_state *st, size_t *len)
{
    const size_t nw = (size_t)st->n_wi, tl = strlen(st->canonical);
    const size_t nt = LSQT_BATCHES * (nw + LSQT_T_COUNT + LSQT_HIST_BINS);
    *len = 116 + tl + 16 * (size_t)st->n_ranges + (size_t)st->n_slices * (20 + 12 * nw + 16 * nt) + 4;
    unsigned char *f = malloc(*len), *p = f;
    memcpy(p, "LSQTLSS", 8), p += 8;
    const uint64_t head[] = {5, LSQT_CHUNK, LSQT_BATCHES, LSQT_FIX_BITS, LSQT_HIST_NMU, LSQT_HIST_NPHI, LSQT_T_COUNT};
    for (int i = 0; i < 7; i++) le(&p, head[i], 4);
    le(&p, st->seed, 8), le(&p, st->hash, 8);
    le(&p, (uint64_t)st->use_double, 4), le(&p, (uint64_t)st->transmits, 4), le(&p, st->flags, 4);
    le(&p, st->dir_method, 4), le(&p, st->rx, 4), le(&p, st->pilot_paths, 8);
    le(&p, (uint64_t)st->n_slices, 4), le(&p, nw, 4), le(&p, st->paths, 8), le(&p, st->span_end, 8);
    le(&p, st->stage, 4), le(&p, (uint64_t)st->n_ranges, 4), le(&p, tl, 4);
    memcpy(p, st->canonical, tl), p += tl;
    for (int i = 0; i < 2 * st->n_ranges; i++) le(&p, st->ranges[i], 8);
    for (size_t s = 0; s < (size_t)st->n_slices; s++) {
        uint64_t th;
        memcpy(&th, &st->theta_o[s], 8);
        le(&p, th, 8), le(&p, st->slice_flags[s], 4), le(&p, st->paths, 8);
        for (size_t k = 0; k < nw; k++)
            for (size_t c = 0; c < 3; c++) {
                uint32_t x;
                memcpy(&x, &st->wi[(s * nw + k) * 4 + c], 4);
                le(&p, x, 4);
            }
        const lsqt_u128 *part[] = {st->nee + s * LSQT_BATCHES * nw, st->scalars + s * LSQT_BATCHES * LSQT_T_COUNT,
                                   st->hist + s * LSQT_BATCHES * LSQT_HIST_BINS};
        const size_t n[] = {LSQT_BATCHES * nw, LSQT_BATCHES * LSQT_T_COUNT, LSQT_BATCHES * LSQT_HIST_BINS};
        for (int q = 0; q < 3; q++)
            for (size_t i = 0; i < n[q]; i++) le(&p, part[q][i].lo, 8), le(&p, part[q][i].hi, 8);
    }
    le(&p, lsqt_crc32(0, f, *len - 4), 4);
    return f;
}

/* A version-6 file of one slice, one direction and no paths whose tallies are the given
 * token stream (file size and CRC made to match): how the reader takes hand-made streams. */
static int parse_stream(const unsigned char *prefix, size_t np, const unsigned char *tok, size_t nt, lsqt_state *out,
                        char *err, size_t errcap)
{
    size_t len = np + nt + 4;
    unsigned char *f = malloc(len), *p = f + 116;
    memcpy(f, prefix, np);
    le(&p, len, 8);
    memcpy(f + np, tok, nt);
    p = f + np + nt;
    le(&p, lsqt_crc32(0, f, len - 4), 4);
    int rc = lsqt_lss_parse(f, len, out, err, errcap);
    free(f);
    return rc;
}

static size_t varint(unsigned char *b, uint64_t v)
{
    size_t n = 0;
    do b[n++] = (unsigned char)((v & 0x7f) | (v >> 7 ? 0x80 : 0)), v >>= 7;
    while (v);
    return n;
}

static int packed_streams(const char *path)
{
    char err[512];
    lsqt_state z, b;
    lsqt_state_init(&z, "Medium eta=1\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium eta=1\n", 1, 2, 1, 1, 0, 1, NULL);
    z.wi[2] = 1.0f;
    CHECK(lsqt_lss_write(path, &z, err, sizeof err) == 0, "%s", err);
    size_t n = 0;
    unsigned char *f = (unsigned char *)lsqt_read_file(path, &n, err, sizeof err);
    /* All 32 x (1 + 7 + 1024) = 33024 tallies zero: one run, the token 2 x 33024 = 66048
     * as LEB128 (0x80 0x84 0x04), after the 132-byte header, the text and the slice's
     * 20 + 12 bytes. */
    const size_t NT = LSQT_BATCHES * (1 + LSQT_T_COUNT + LSQT_HIST_BINS), np = n - 7;
    CHECK(NT == 33024 && n == 132 + strlen(z.canonical) + 32 + 3 + 4 && f[np] == 0x80 && f[np + 1] == 0x84 &&
              f[np + 2] == 0x04,
          "all-zero tallies: %zu bytes, not one run token", n);
    unsigned char t[64];
    size_t k;
    /* Valid: 33023 zeros then 5 (the last histogram bin); a 16-byte tally then the rest. */
    k = varint(t, 2 * (NT - 1)), t[k++] = 3, t[k++] = 5;
    CHECK(parse_stream(f, np, t, k, &b, err, sizeof err) == 0 && b.hist[LSQT_BATCHES * LSQT_HIST_BINS - 1].lo == 5 &&
              b.hist[LSQT_BATCHES * LSQT_HIST_BINS - 2].lo == 0,
          "run then a one-byte tally: %s", err);
    lsqt_state_free(&b);
    t[0] = 33;
    memset(t + 1, 0xFF, 16);
    k = 17 + varint(t + 17, 2 * (NT - 1));
    CHECK(parse_stream(f, np, t, k, &b, err, sizeof err) == 0 && b.nee[0].lo == UINT64_MAX && b.nee[0].hi == UINT64_MAX,
          "16-byte tally then a run: %s", err);
    lsqt_state_free(&b);
    /* What the writer never writes is refused. */
    struct {
        const char *why;
        unsigned char tok[40];
        size_t n;
    } bad[12];
    size_t nb = 0;
    bad[nb].why = "two runs in a row", bad[nb].n = varint(bad[nb].tok, 2 * 24);
    bad[nb].n += varint(bad[nb].tok + bad[nb].n, 2 * (NT - 24)), nb++;
    bad[nb].why = "a run past the end", bad[nb].n = varint(bad[nb].tok, 2 * (NT + 1)), nb++;
    bad[nb].why = "too few tallies", bad[nb].n = varint(bad[nb].tok, 2 * (NT - 1)), nb++;
    bad[nb].why = "bytes after the last tally", bad[nb].n = varint(bad[nb].tok, 2 * NT), bad[nb].tok[bad[nb].n++] = 0,
    nb++;
    bad[nb].why = "an empty run", bad[nb].tok[0] = 0, bad[nb].n = 1 + varint(bad[nb].tok + 1, 2 * NT), nb++;
    bad[nb].why = "a zero tally", bad[nb].n = varint(bad[nb].tok, 2 * (NT - 1));
    bad[nb].tok[bad[nb].n++] = 3, bad[nb].tok[bad[nb].n++] = 0, nb++;
    bad[nb].why = "a tally not in its fewest bytes", bad[nb].n = varint(bad[nb].tok, 2 * (NT - 1));
    bad[nb].tok[bad[nb].n++] = 5, bad[nb].tok[bad[nb].n++] = 7, bad[nb].tok[bad[nb].n++] = 0, nb++;
    bad[nb].why = "a 17-byte tally", bad[nb].tok[0] = 35, memset(bad[nb].tok + 1, 1, 17);
    bad[nb].n = 18 + varint(bad[nb].tok + 18, 2 * (NT - 1)), nb++;
    bad[nb].why = "a zero-length tally", bad[nb].tok[0] = 1, bad[nb].n = 1 + varint(bad[nb].tok + 1, 2 * (NT - 1)), nb++;
    bad[nb].why = "a token not in its fewest bytes", memcpy(bad[nb].tok, "\x80\x84\x84\x00", 4), bad[nb].n = 4, nb++;
    bad[nb].why = "a token beyond 64 bits", memset(bad[nb].tok, 0xFF, 10), bad[nb].n = 10, nb++;
    for (size_t i = 0; i < nb; i++) {
        int rc = parse_stream(f, np, bad[i].tok, bad[i].n, &b, err, sizeof err);
        CHECK(rc != 0 && strstr(err, "corrupt LSS file"), "%s: accepted or wrong message '%s'", bad[i].why,
              rc ? err : "");
        if (!rc) lsqt_state_free(&b);
    }
    free(f);
    lsqt_state_free(&z);
    return 0;
}

/* Packed histograms (host/state/hist.c), for the checks below: P's batch t of band b,
 * slice sp, is K times D's of slice sd (a sum of K copies). */
static int hist_batch_is(const lsqt_state *p, int sp, const lsqt_state *d, int sd, int b, int t, int k)
{
    lsqt_u128 got[LSQT_HIST_BINS], want[LSQT_HIST_BINS];
    memset(got, 0, sizeof got), memset(want, 0, sizeof want);
    lsqt_state_hist_read(p, b, sp, t, got, 1);
    lsqt_state_hist_read(d, b, sd, t, want, 1);
    for (int i = 0; i < LSQT_HIST_BINS; i++) {
        lsqt_u128 w = {0, 0};
        for (int j = 0; j < k; j++) w = lsqt_u128_add(w, want[i]);
        if (w.lo != got[i].lo || w.hi != got[i].hi) return 0;
    }
    return 1;
}

/* A 3-band state of 2 slices whose histograms are sparse, with tallies of every length
 * (1 to 16 bytes, the high word too) and runs of zeros, written to PATH. */
static void sparse_bands(lsqt_state *d, const char *path)
{
    const double wl[3] = {450, 550, 650};
    lsqt_state_init(d, "Medium eta=1\nLayer z=0 LambertianBsdf fR=0.6,0.5,0.4 fT=0\nMedium eta=1\n", 9, 3, 2, 4,
                          1, 3, wl);
    const uint64_t r[] = {0, 5000};
    lsqt_state_set_ranges(d, r, 1);
    d->span_end = 5000;
    for (size_t i = 0; i < (size_t)2 * 4; i++) d->wi[4 * i + 2] = 1.0f;
    uint64_t x = 88172645463325252ULL;
    for (size_t i = 0; i < lsqt_state_hist_count(d); i++) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        if (x % 5) continue;
        d->hist[i].lo = x >> (x % 61);
        d->hist[i].hi = i % 7 == 0 ? x >> (x % 64) : 0;
    }
    for (size_t i = 0; i < lsqt_state_nee_count(d); i++) d->nee[i].lo = i * 3;
    char err[256];
    CHECK(lsqt_lss_write(path, d, err, sizeof err) == 0, "%s", err);
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
              strstr(err, "truncated at byte 50 (inside the 132-byte header)"),
          "truncated header: %s", err);
    f1[n1 / 2] ^= 0x10;
    CHECK(lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) != 0 && strstr(err, "CRC mismatch"),
          "flipped: %s", err);
    f1[n1 / 2] ^= 0x10;
    f1[8] = 1;
    char want_v[64];
    snprintf(want_v, sizeof want_v, "LSS version 1, this lsqt-cl reads versions 5 to %u", LSQT_LSS_VERSION);
    CHECK(lsqt_lss_parse((const unsigned char *)f1, n1, &b, err, sizeof err) != 0 && strstr(err, want_v),
          "version: %s", err);
    f1[8] = 6; /* a one-band state is written as version 6 */
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

    /* Packed tallies: an all-zero state's exact size, and hand-made token streams. */
    packed_streams(path);

    /* A grid state keeps its NI and NPHI; ones that do not give its direction count are
     * refused (16 directions on a transmitting stack: NI 2 x (NPHI/2 + 1 = 4) x 2). */
    {
        lsqt_state g;
        fill(&g);
        g.dir_method = LSQT_DIRS_GRID, g.grid_ni = 2, g.grid_nphi = 6;
        CHECK(lsqt_lss_write(path, &g, err, sizeof err) == 0, "%s", err);
        const int rc = lsqt_lss_read(path, &b, err, sizeof err);
        CHECK(rc == 0 && b.dir_method == LSQT_DIRS_GRID && b.grid_ni == 2 && b.grid_nphi == 6, "grid state: %s",
              rc ? err : "other grid sizes");
        if (rc == 0) lsqt_state_free(&b);
        g.grid_nphi = 8;
        CHECK(lsqt_lss_write(path, &g, err, sizeof err) == 0, "%s", err);
        CHECK(lsqt_lss_read(path, &b, err, sizeof err) != 0 && strstr(err, "corrupt LSS header"),
              "a grid of 20 directions holding 16 accepted: '%s'", err);
        g.dir_method = LSQT_DIRS_FILE, g.grid_nphi = 6;
        CHECK(lsqt_lss_write(path, &g, err, sizeof err) == 0, "%s", err);
        CHECK(lsqt_lss_read(path, &b, err, sizeof err) != 0 && strstr(err, "corrupt LSS header"),
              "grid sizes on a --wi-file state accepted: '%s'", err);
        /* --rgl-grid: NU 4 gives (4 - 2) x 4 = 8 directions, not 16 */
        g.dir_method = LSQT_DIRS_RGL, g.grid_ni = 4, g.grid_nphi = 0;
        CHECK(lsqt_lss_write(path, &g, err, sizeof err) == 0, "%s", err);
        CHECK(lsqt_lss_read(path, &b, err, sizeof err) != 0 && strstr(err, "corrupt LSS header"),
              "an RGL grid of 8 directions holding 16 accepted: '%s'", err);
        lsqt_state_free(&g);
    }

    /* The band limit: a state of LSQT_MAX_BANDS bands (one slice of one direction, the
     * tallies zero but one in the first and one in the last band) round-trips, and the
     * writer refuses one band more (the reader would), writing nothing. */
    {
        static double wl[LSQT_MAX_BANDS + 1];
        for (int k = 0; k <= LSQT_MAX_BANDS; k++) wl[k] = 400 + 0.5 * k;
        for (int extra = 0; extra <= 1; extra++) {
            const int nb = LSQT_MAX_BANDS + extra;
            char far[80];
            snprintf(far, sizeof far, "%s/limit%d.lss", dir, nb);
            lsqt_state m;
            CHECK(lsqt_state_init(&m, "# limit\nMedium eta=1\n", 9, 3, 1, 1, 0, nb, wl) == 0, "init %d", nb);
            m.wi[2] = 1.0f;
            const size_t per = lsqt_state_nee_count(&m) / (size_t)nb;
            m.nee[0].lo = 5, m.nee[(size_t)(nb - 1) * per].lo = 7;
            const int wrc = lsqt_lss_write(far, &m, err, sizeof err);
            if (extra) {
                CHECK(wrc != 0 && strstr(err, "4097 bands") && strstr(err, "at most 4096 bands") && access(far, F_OK) != 0,
                      "4097 bands written: '%s'", err);
            } else {
                const int rc = wrc ? -1 : lsqt_lss_read(far, &b, err, sizeof err);
                CHECK(rc == 0 && b.n_bands == nb && b.wavelengths && b.wavelengths[nb - 1] == wl[nb - 1] &&
                          b.nee[0].lo == 5 && b.nee[(size_t)(nb - 1) * per].lo == 7 && b.nee[per].lo == 0,
                      "%d bands do not round-trip: %s", nb, rc ? err : "values");
                if (rc == 0) lsqt_state_free(&b);
                unlink(far);
            }
            lsqt_state_free(&m);
        }
    }

    /* Bands (version 7): every band's tallies and the wavelengths round-trip; bands without
     * wavelengths too; wavelengths that do not increase (under a valid CRC) are refused;
     * one band is still version 6. */
    {
        const double wl[3] = {450, 550.5, 650};
        for (int named = 1; named >= 0; named--) {
            lsqt_state m;
            lsqt_state_init(&m, "# bands 3\nMedium eta=1\n", 9, 3, 2, 16, 0, 3, named ? wl : NULL);
            for (size_t i = 0; i < (size_t)2 * 16; i++) m.wi[4 * i + 2] = 1.0f;
            for (size_t i = 0; i < lsqt_state_nee_count(&m); i++) m.nee[i].lo = 3 * i + 1;
            for (size_t i = 0; i < lsqt_state_scalar_count(&m); i++) m.scalars[i].hi = i;
            for (size_t i = 0; i < lsqt_state_hist_count(&m); i++) m.hist[i].lo = i % 7;
            CHECK(lsqt_lss_write(path, &m, err, sizeof err) == 0, "%s", err);
            const int rc = lsqt_lss_read(path, &b, err, sizeof err);
            CHECK(rc == 0 && b.lss_version == 7 && b.n_bands == 3 && (named ? b.wavelengths != NULL : !b.wavelengths),
                  "bands: %s", rc ? err : "header");
            if (rc == 0) {
                CHECK(!named || memcmp(b.wavelengths, wl, sizeof wl) == 0, "wavelengths differ");
                CHECK(lsqt_state_nee_count(&b) == lsqt_state_nee_count(&m) &&
                          memcmp(b.nee, m.nee, lsqt_state_nee_count(&m) * sizeof *m.nee) == 0 &&
                          memcmp(b.scalars, m.scalars, lsqt_state_scalar_count(&m) * sizeof *m.scalars) == 0 &&
                          memcmp(b.hist, m.hist, lsqt_state_hist_count(&m) * sizeof *m.hist) == 0,
                      "the bands' tallies differ");
                /* band 2 is the third block */
                const lsqt_state v = lsqt_state_band(&b, 2);
                CHECK(v.n_bands == 1 && v.nee == b.nee + 2 * (lsqt_state_nee_count(&b) / 3) &&
                          (!named || v.wavelengths[0] == 650),
                      "band view");
                lsqt_state_free(&b);
            }
            if (named) {
                m.wavelengths[2] = 500; /* 450, 550.5, 500 */
                CHECK(lsqt_lss_write(path, &m, err, sizeof err) == 0, "%s", err);
                CHECK(lsqt_lss_read(path, &b, err, sizeof err) != 0 && strstr(err, "band wavelengths not increasing"),
                      "decreasing wavelengths accepted: '%s'", err);
            }
            lsqt_state_free(&m);
        }
        CHECK(lsqt_lss_write(path, &a, err, sizeof err) == 0 && lsqt_lss_read(path, &b, err, sizeof err) == 0 &&
                  b.lss_version == 6 && b.n_bands == 1 && !b.wavelengths,
              "one band: version %u", b.lss_version);
        lsqt_state_free(&b);
    }

    /* Version 5, written from its layout, is read to the same state (and says so). */
    size_t n5 = 0;
    unsigned char *f5 = v5_image(&a, &n5);
    CHECK(lsqt_lss_parse(f5, n5, &b, err, sizeof err) == 0, "version 5 refused: %s", err);
    if (!check_failures) {
        CHECK(b.lss_version == 5 && a.paths == b.paths && b.n_ranges == 2 && b.span_end == 200000, "v5 header differs");
        CHECK(memcmp(a.wi, b.wi, (size_t)3 * 16 * 4 * sizeof(float)) == 0 &&
                  memcmp(a.nee, b.nee, lsqt_state_nee_count(&a) * sizeof *a.nee) == 0 &&
                  memcmp(a.scalars, b.scalars, lsqt_state_scalar_count(&a) * sizeof *a.scalars) == 0 &&
                  memcmp(a.hist, b.hist, lsqt_state_hist_count(&a) * sizeof *a.hist) == 0,
              "version 5 tallies differ");
        lsqt_state_free(&b);
    }
    CHECK(lsqt_lss_parse(f5, 60, &b, err, sizeof err) != 0 && strstr(err, "inside the 116-byte header"),
          "truncated version 5: %s", err);
    CHECK(lsqt_lss_parse(f5, n5 - 16, &b, err, sizeof err) != 0 && strstr(err, "truncated at byte"),
          "short version 5: %s", err);
    free(f5);

    /* Packed histograms: an LSS read packed (LSQT_PACK_HIST=1, as a run of many bands
     * reads it) holds every batch as the dense state does and writes the same bytes; a
     * dense state packed too; sums (packed with packed, dense with packed), copies and
     * drops of slices agree with the u128 sums of the dense batches. */
    {
        lsqt_state d, p, q, e;
        sparse_bands(&d, path);
        size_t na = 0, nb2 = 0, nc = 0;
        char *fa = lsqt_read_file(path, &na, err, sizeof err);
        setenv("LSQT_PACK_HIST", "1", 1);
        CHECK(lsqt_lss_read(path, &p, err, sizeof err) == 0 && p.hist_pk && !p.hist, "read packed: %s", err);
        setenv("LSQT_PACK_HIST", "0", 1);
        CHECK(lsqt_lss_read(path, &q, err, sizeof err) == 0 && !q.hist_pk, "read dense: %s", err);
        CHECK(lsqt_lss_read(path, &e, err, sizeof err) == 0, "read dense: %s", err);
        unsetenv("LSQT_PACK_HIST");
        int same = 1;
        for (int bd = 0; bd < 3; bd++)
            for (int sl = 0; sl < 2; sl++)
                for (int t = 0; t < LSQT_BATCHES; t++) same &= hist_batch_is(&p, sl, &d, sl, bd, t, 1);
        CHECK(same, "a packed histogram batch differs from the dense one");
        CHECK(lsqt_lss_write(path, &p, err, sizeof err) == 0, "%s", err);
        char *fb = lsqt_read_file(path, &nb2, err, sizeof err);
        CHECK(fa && fb && na == nb2 && memcmp(fa, fb, na) == 0, "the packed state's LSS differs (%zu, %zu bytes)", na, nb2);
        CHECK(lsqt_state_pack_hist(&q, 1) == 0 && q.hist_pk && lsqt_lss_write(path, &q, err, sizeof err) == 0, "%s", err);
        char *fc = lsqt_read_file(path, &nc, err, sizeof err);
        CHECK(fc && na == nc && memcmp(fa, fc, na) == 0, "the dense state packed writes another LSS");
        CHECK(lsqt_state_add_hist(&p, &q) == 0 && lsqt_state_add_hist(&e, &q) == 0, "adding histograms");
        same = 1;
        for (int bd = 0; bd < 3; bd++)
            for (int sl = 0; sl < 2; sl++)
                for (int t = 0; t < LSQT_BATCHES; t++)
                    same &= hist_batch_is(&p, sl, &d, sl, bd, t, 2) && hist_batch_is(&e, sl, &d, sl, bd, t, 2);
        CHECK(same, "a sum of histograms differs from the sum of the dense batches");
        CHECK(lsqt_state_copy_hist(&q, 0, &p, 1) == 0, "copy");
        lsqt_state_drop_hist(&p, 0, 1);
        same = 1;
        for (int bd = 0; bd < 3; bd++)
            for (int t = 0; t < LSQT_BATCHES; t++)
                same &= hist_batch_is(&q, 0, &d, 1, bd, t, 2) && hist_batch_is(&q, 1, &d, 1, bd, t, 1) &&
                        hist_batch_is(&p, 0, &d, 0, bd, t, 0) && hist_batch_is(&p, 1, &d, 1, bd, t, 2);
        CHECK(same, "a copied or dropped slice's histograms are wrong");
        free(fa), free(fb), free(fc);
        lsqt_state_free(&d), lsqt_state_free(&p), lsqt_state_free(&q), lsqt_state_free(&e);
    }

    /* Writing streams through a small buffer: no allocation near the state's size (a large
     * LSS after a long run cannot fail for memory). 4 slices of 1024 directions, dense:
     * 8 MB of tallies. */
    lsqt_state big;
    lsqt_state_init(&big, "Medium eta=1\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium eta=1\n", 7, 1, 4, 1024, 1, 1, NULL);
    for (size_t i = 0; i < (size_t)4 * 1024; i++) big.wi[4 * i + 2] = 1.0f;
    for (size_t i = 0; i < lsqt_state_nee_count(&big); i++) big.nee[i].lo = i * 0x9E3779B97F4A7C15ULL;
    for (size_t i = 0; i < lsqt_state_hist_count(&big); i++) big.hist[i].lo = ~i;
    watching = 1, largest = 0;
    CHECK(lsqt_lss_write(path, &big, err, sizeof err) == 0, "%s", err);
    watching = 0;
    CHECK(largest > 0 && largest <= 256 * 1024, "writing 8 MB of tallies allocated %zu bytes at once", largest);
    lsqt_state_free(&big);

    free(f1);
    free(f2);
    remove(path);
    rmdir(dir);
    lsqt_state_free(&a);
    return check_finish("test_lss");
}
