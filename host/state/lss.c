#include "lsqt/lss.h"
#include "lsqt/bands.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/directions.h"
#include "lsqt/util.h"

static const char magic[8] = {'L', 'S', 'Q', 'T', 'L', 'S', 'S', '\0'};

/* ---- writing: little-endian, streamed to the file through a small buffer with the CRC
 * kept as it goes, so writing needs no second copy of the state (a large LSS after a long
 * run cannot fail for memory) ---- */
#define LSS_WBUF (1u << 16)
typedef struct wbuf {
    unsigned char *p; /* LSS_WBUF bytes; NULL: a sizing pass that only counts */
    size_t n;
    uint32_t crc; /* of every byte flushed */
    FILE *f;
    uint64_t total; /* bytes put so far */
} wbuf;

static void flush_w(wbuf *w)
{
    if (!w->p) return;
    w->crc = lsqt_crc32(w->crc, w->p, w->n);
    if (w->n) fwrite(w->p, 1, w->n, w->f); /* a failure shows at lsqt_out_commit */
    w->n = 0;
}

static void put(wbuf *w, const void *src, size_t n)
{
    w->total += n;
    if (!w->p) return;
    const unsigned char *s = src;
    while (n) {
        size_t k = LSS_WBUF - w->n < n ? LSS_WBUF - w->n : n;
        memcpy(w->p + w->n, s, k);
        w->n += k, s += k, n -= k;
        if (w->n == LSS_WBUF) flush_w(w);
    }
}

static void put_u32(wbuf *w, uint32_t v)
{
    unsigned char b[4];
    for (int i = 0; i < 4; i++) b[i] = (unsigned char)(v >> (8 * i));
    put(w, b, 4);
}

static void put_u64(wbuf *w, uint64_t v)
{
    put_u32(w, (uint32_t)v);
    put_u32(w, (uint32_t)(v >> 32));
}

/* ---- the tallies of a slice, packed (version 6): most 128-bit words are zero (batches
 * not yet reached, bins never hit) or use 5 to 8 bytes (2^-40 units). A token is an
 * unsigned LEB128 varint t: t = 2k (k >= 1) is a run of k zero tallies; t = 2L + 1
 * (1 <= L <= 16) is a nonzero tally in the next L bytes, little-endian, its last byte
 * nonzero. The encoding is canonical (runs are whole, lengths minimal), so a state has
 * exactly one form and equal work still gives byte-identical files. ---- */
typedef struct tally_run {
    lsqt_u128 *part[3]; /* a slice's point-estimate sums, scalars, histogram, in file order */
    size_t n[3];
} tally_run;

/* Slice s of ST (a band's view); packed histograms are unpacked into SCRATCH
 * (LSQT_BATCHES x LSQT_HIST_BINS). */
static tally_run slice_tallies(const lsqt_state *st, size_t s, lsqt_u128 *scratch)
{
    const size_t nw = (size_t)st->n_wi;
    lsqt_u128 *hist = scratch;
    if (st->hist_pk) {
        memset(scratch, 0, (size_t)LSQT_BATCHES * LSQT_HIST_BINS * sizeof *scratch);
        for (int t = 0; t < LSQT_BATCHES; t++)
            lsqt_state_hist_read(st, 0, (int)s, t, scratch + (size_t)t * LSQT_HIST_BINS, 1);
    } else {
        hist = lsqt_state_hist_of(st, (int)s);
    }
    tally_run t = {{st->nee + s * LSQT_BATCHES * nw, st->scalars + s * LSQT_BATCHES * LSQT_T_COUNT, hist},
                   {LSQT_BATCHES * nw, LSQT_BATCHES * LSQT_T_COUNT, LSQT_BATCHES * LSQT_HIST_BINS}};
    return t;
}

static void put_varint(wbuf *w, uint64_t v)
{
    unsigned char b[10];
    put(w, b, lsqt_tally_varint(b, v));
}

static void put_tallies(wbuf *w, const tally_run *t)
{
    uint64_t zeros = 0;
    for (int p = 0; p < 3; p++)
        for (size_t i = 0; i < t->n[p]; i++) {
            const lsqt_u128 v = t->part[p][i];
            if (!v.lo && !v.hi) {
                zeros++;
                continue;
            }
            if (zeros) put_varint(w, 2 * zeros);
            zeros = 0;
            unsigned char b[16];
            for (int j = 0; j < 8; j++) b[j] = (unsigned char)(v.lo >> (8 * j)), b[8 + j] = (unsigned char)(v.hi >> (8 * j));
            size_t len = 16;
            while (!b[len - 1]) len--;
            put_varint(w, 2 * len + 1);
            put(w, b, len);
        }
    if (zeros) put_varint(w, 2 * zeros);
}

static void put_f64(wbuf *w, double d)
{
    uint64_t v;
    memcpy(&v, &d, 8);
    put_u64(w, v);
}

static void put_f32(wbuf *w, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    put_u32(w, v);
}

/* The counts an LSS header may hold, for the writer and the reader alike (the writer
 * never writes what the reader refuses): bands says the file is version 7 (bands, or
 * one named band), named that the wavelengths follow the text. */
static int counts_ok(uint64_t n_slices, uint64_t n_wi, uint64_t tl, uint64_t n_ranges, int bands, uint64_t nb,
                     uint64_t named)
{
    return n_slices >= 1 && n_slices <= 4096 * 8 && n_wi >= 1 && n_wi <= 65536 && tl <= (1u << 24) &&
           n_ranges <= (1u << 20) &&
           (!bands || ((nb >= 2 || (nb == 1 && named == 1)) && nb <= LSQT_MAX_BANDS && named <= 1));
}

/* Everything but the CRC; file_bytes is the whole file's size, announced in the header.
 * SCRATCH: a slice's histogram, for packed ones. */
static void put_state(wbuf *w, const lsqt_state *st, uint64_t file_bytes, lsqt_u128 *scratch)
{
    const size_t nw = (size_t)st->n_wi;
    /* one band without a wavelength: version 6, as before bands */
    const int bands = st->n_bands > 1 || st->wavelengths;
    put(w, magic, 8);
    put_u32(w, bands ? LSQT_LSS_VERSION : 6u);
    uint32_t layout[] = {LSQT_CHUNK, LSQT_BATCHES, LSQT_FIX_BITS, LSQT_HIST_NMU, LSQT_HIST_NPHI, LSQT_T_COUNT};
    for (size_t i = 0; i < 6; i++) put_u32(w, layout[i]);
    put_u64(w, st->seed);
    put_u64(w, st->hash);
    put_u32(w, (uint32_t)st->use_double);
    put_u32(w, (uint32_t)st->transmits);
    put_u32(w, st->flags);
    put_u32(w, st->dir_method);
    put_u32(w, st->rx);
    put_u64(w, st->pilot_paths);
    put_u32(w, (uint32_t)st->n_slices);
    put_u32(w, (uint32_t)st->n_wi);
    put_u64(w, st->paths);
    put_u64(w, st->span_end);
    put_u32(w, st->stage);
    put_u32(w, (uint32_t)st->n_ranges);
    size_t tl = strlen(st->canonical);
    put_u32(w, (uint32_t)tl);
    put_u64(w, file_bytes);
    put_u32(w, st->grid_ni);
    put_u32(w, st->grid_nphi);
    if (bands) {
        put_u32(w, (uint32_t)st->n_bands);
        put_u32(w, st->wavelengths != NULL);
    }
    put(w, st->canonical, tl);
    for (int b = 0; bands && st->wavelengths && b < st->n_bands; b++) put_f64(w, st->wavelengths[b]);
    for (int i = 0; i < 2 * st->n_ranges; i++) put_u64(w, st->ranges[i]);
    for (int s = 0; s < st->n_slices; s++) {
        put_f64(w, st->theta_o[s]);
        put_u32(w, st->slice_flags[s]);
        put_u64(w, st->paths);
        for (size_t k = 0; k < nw; k++)
            for (int c = 0; c < 3; c++) put_f32(w, st->wi[((size_t)s * nw + k) * 4 + (size_t)c]);
        for (int b = 0; b < (bands ? st->n_bands : 1); b++) {
            const lsqt_state band = lsqt_state_band(st, b);
            const tally_run t = slice_tallies(&band, (size_t)s, scratch);
            put_tallies(w, &t);
        }
    }
}

int lsqt_lss_write(const char *path, const lsqt_state *st, char *err, size_t errcap)
{
    /* Two passes: the first only counts the bytes, so that the header can announce the
     * file's size (a reader tells a truncated file from a damaged one). */
    const int bands = st->n_bands > 1 || st->wavelengths;
    if (st->n_slices < 0 || st->n_wi < 0 || st->n_ranges < 0 || st->n_bands < 1 ||
        !counts_ok((uint64_t)st->n_slices, (uint64_t)st->n_wi, strlen(st->canonical), (uint64_t)st->n_ranges, bands,
                   (uint64_t)st->n_bands, st->wavelengths != NULL)) {
        snprintf(err, errcap, "cannot write '%s': %d bands, %d slices, %d directions, %d ranges or %zu bytes of "
                 "assembly text are more than an LSS may hold (at most %d bands, %d slices, 65536 directions, %u "
                 "ranges, %u bytes)", path, st->n_bands, st->n_slices, st->n_wi, st->n_ranges, strlen(st->canonical),
                 LSQT_MAX_BANDS, 4096 * 8, 1u << 20, 1u << 24);
        return -1;
    }
    lsqt_u128 *scratch = st->hist_pk ? malloc((size_t)LSQT_BATCHES * LSQT_HIST_BINS * sizeof *scratch) : NULL;
    if (st->hist_pk && !scratch) {
        snprintf(err, errcap, "out of memory writing '%s'", path);
        return -1;
    }
    wbuf w = {NULL, 0, 0, NULL, 0};
    put_state(&w, st, 0, scratch);
    const uint64_t file_bytes = w.total + 4;
    w.p = malloc(LSS_WBUF);
    if (!w.p) {
        free(scratch);
        snprintf(err, errcap, "out of memory writing '%s'", path);
        return -1;
    }
    lsqt_out af;
    if (lsqt_out_open(&af, path, err, errcap)) {
        free(w.p), free(scratch);
        return -1;
    }
    w.f = af.f;
    w.total = 0;
    put_state(&w, st, file_bytes, scratch);
    flush_w(&w);
    put_u32(&w, w.crc);
    flush_w(&w);
    free(w.p), free(scratch);
    return lsqt_out_commit(&af, err, errcap);
}

/* ---- reading: a bounds-checked cursor ---- */
typedef struct rbuf {
    const unsigned char *p;
    size_t n, at;
    int bad;
} rbuf;

static const unsigned char *take(rbuf *r, size_t n)
{
    if (r->bad || n > r->n - r->at) {
        r->bad = 1;
        return NULL;
    }
    const unsigned char *q = r->p + r->at;
    r->at += n;
    return q;
}

static uint32_t get_u32(rbuf *r)
{
    const unsigned char *b = take(r, 4);
    if (!b) return 0;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static uint64_t get_u64(rbuf *r)
{
    uint64_t lo = get_u32(r);
    return lo | (uint64_t)get_u32(r) << 32;
}

static lsqt_u128 get_u128(rbuf *r)
{
    lsqt_u128 v;
    v.lo = get_u64(r);
    v.hi = get_u64(r);
    return v;
}

static double get_f64(rbuf *r)
{
    uint64_t v = get_u64(r);
    double d;
    memcpy(&d, &v, 8);
    return d;
}

static float get_f32(rbuf *r)
{
    uint32_t v = get_u32(r);
    float f;
    memcpy(&f, &v, 4);
    return f;
}

static int get_varint(rbuf *r, uint64_t *v)
{
    *v = 0;
    for (int i = 0; i < 10; i++) {
        const unsigned char *b = take(r, 1);
        if (!b) return -1;
        if (i == 9 && *b > 1) return -1; /* beyond 64 bits */
        *v |= (uint64_t)(*b & 0x7f) << (7 * i);
        if (!(*b & 0x80)) return i && !*b ? -1 : 0; /* a zero last byte: not the shortest form */
    }
    return -1;
}

/* Reads one slice's packed tallies (see put_tallies) into zeroed arrays; any token that
 * the writer would not have written (a run past the end, two runs in a row, a length out
 * of range or not the shortest) marks r bad. */
static void get_tallies(rbuf *r, const tally_run *t)
{
    int p = 0, after_run = 0;
    size_t at = 0;
    while (p < 3 && !r->bad) {
        uint64_t tok;
        if (get_varint(r, &tok)) {
            r->bad = 1;
            break;
        }
        if (!(tok & 1)) {
            uint64_t k = tok / 2;
            if (!k || after_run) r->bad = 1;
            while (k && p < 3) { /* a run may cross from one part into the next */
                const size_t step = t->n[p] - at < k ? t->n[p] - at : (size_t)k;
                at += step, k -= step;
                if (at == t->n[p]) p++, at = 0;
            }
            if (k) r->bad = 1; /* the run goes past the slice's last tally */
            after_run = 1;
            continue;
        }
        const uint64_t len = tok / 2;
        const unsigned char *b = len >= 1 && len <= 16 ? take(r, (size_t)len) : NULL;
        if (!b || !b[len - 1]) {
            r->bad = 1;
            break;
        }
        lsqt_u128 v = {0, 0};
        for (size_t j = 0; j < len; j++)
            if (j < 8) v.lo |= (uint64_t)b[j] << (8 * j);
            else v.hi |= (uint64_t)b[j] << (8 * (j - 8));
        t->part[p][at++] = v;
        if (at == t->n[p]) p++, at = 0;
        after_run = 0;
    }
}

/* Bytes before the assembly text: magic, version, 6 layout words, seed, hash, 3 u32
 * (double, transmits, flags), direction method, rx, pilot paths, n_slices, n_wi, paths,
 * span end, stage, range count, text length; and from version 6 on the file's size and
 * the grid's NI and NPHI. */
#define LSS_HEADER_V5 (8 + 4 + 6 * 4 + 8 + 8 + 3 * 4 + 4 + 4 + 8 + 2 * 4 + 8 + 8 + 4 + 4 + 4)
#define LSS_HEADER_V6 (LSS_HEADER_V5 + 8 + 4 + 4)
#define LSS_HEADER_V7 (LSS_HEADER_V6 + 4 + 4)

/* Contents a valid CRC cannot vouch for: every slice's theta_o in [0, pi/2) (from its own
 * side's normal), and its incident directions finite unit vectors (those a run used or,
 * during an RRSS pilot, will use). Returns 0, or -1 with err naming the slice. */
static int check_slices(const lsqt_state *st, char *err, size_t errcap)
{
    for (int s = 0; s < st->n_slices; s++) {
        const double t = st->theta_o[s];
        if (!(t >= 0.0 && t < LSQT_PI / 2)) {
            snprintf(err, errcap, "corrupt LSS file (slice %d: theta_o %g rad, outside [0, pi/2))", s, t);
            return -1;
        }
        for (int k = 0; k < st->n_wi; k++) {
            const float *d = st->wi + ((size_t)s * (size_t)st->n_wi + (size_t)k) * 4;
            const double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
            if (!(fabs(len - 1.0) < 1e-3)) {
                snprintf(err, errcap, "corrupt LSS file (slice %d: incident direction %d (%g %g %g) is not a unit "
                         "vector)", s, k, (double)d[0], (double)d[1], (double)d[2]);
                return -1;
            }
        }
    }
    return 0;
}

/* The header's fields, and the file size it announces when its counts are in range. */
typedef struct lss_header {
    uint32_t version;
    int packed;    /* version 6 on: packed tallies; version 5 stores every tally in 16 bytes */
    size_t header; /* its size in bytes */
    uint32_t file_layout[6];
    uint64_t seed, hash;
    uint32_t use_double, transmits, flags, dir_method, rx;
    uint64_t pilot_paths;
    uint32_t n_slices, n_wi;
    uint64_t paths, span_end;
    uint32_t stage, n_ranges, tl;
    uint64_t file_bytes;
    uint32_t grid_ni, grid_nphi;
    uint32_t n_bands, named; /* version 7: bands, and whether their wavelengths follow the text */
    int sane;    /* the counts are in range */
    size_t want; /* the file's size (0: unknown) */
} lss_header;

/* Not an LSS at all, or cut short before its version. */
static int check_start(const unsigned char *data, size_t len, char *err, size_t errcap)
{
    if (len == 0) {
        snprintf(err, errcap, "empty file (not an LSS file)");
        return -1;
    }
    if (memcmp(data, magic, len < 8 ? len : 8) != 0) {
        snprintf(err, errcap, "not an LSS file (bad magic)");
        return -1;
    }
    if (len < 12) {
        snprintf(err, errcap, "truncated at byte %zu (inside the header)", len);
        return -1;
    }
    return 0;
}

/* The size the header announces, when its counts are in range (else unknown: 0):
 * version 5's follows from the counts; version 6 states it, between the sizes of
 * all-zero tallies (one byte a slice) and of the largest (17 bytes each). */
static void announced_size(lss_header *h)
{
    const uint32_t n_slices = h->n_slices, n_wi = h->n_wi, tl = h->tl, n_ranges = h->n_ranges;
    const uint32_t nb = h->version >= 7 ? h->n_bands : 1;
    int sane = counts_ok(n_slices, n_wi, tl, n_ranges, h->version >= 7, nb, h->named);
    const size_t tallies = (size_t)LSQT_BATCHES * (n_wi + LSQT_T_COUNT + LSQT_HIST_BINS) * nb;
    const size_t fixed = sane ? h->header + (size_t)tl + (h->named ? (size_t)nb * 8 : 0) + (size_t)n_ranges * 16 +
                                    (20 + (size_t)n_wi * 12) * n_slices + 4
                              : 0;
    size_t want = sane ? fixed + tallies * 16 * n_slices : 0;
    if (h->packed) {
        sane = sane && h->file_bytes >= fixed + (size_t)n_slices * nb && h->file_bytes <= fixed + tallies * 17 * n_slices;
        want = sane ? (size_t)h->file_bytes : 0;
    }
    h->sane = sane, h->want = want;
}

/* The version, then the header's fields (r->bad when it is cut short). */
static int read_header(rbuf *r, size_t len, lss_header *h, char *err, size_t errcap)
{
    memset(h, 0, sizeof *h);
    uint32_t version = h->version = get_u32(r);
    if (version < 5 || version > LSQT_LSS_VERSION) {
        snprintf(err, errcap, "LSS version %u, this lsqt-cl reads versions 5 to %u", version, LSQT_LSS_VERSION);
        return -1;
    }
    const int packed = h->packed = version >= 6;
    const size_t header = h->header = version >= 7 ? LSS_HEADER_V7 : packed ? LSS_HEADER_V6 : LSS_HEADER_V5;
    if (len < header + 4) {
        snprintf(err, errcap, "truncated at byte %zu (inside the %zu-byte header)", len, header);
        return -1;
    }
    for (size_t i = 0; i < 6; i++) h->file_layout[i] = get_u32(r);
    h->seed = get_u64(r), h->hash = get_u64(r);
    h->use_double = get_u32(r), h->transmits = get_u32(r), h->flags = get_u32(r);
    h->dir_method = get_u32(r), h->rx = get_u32(r);
    h->pilot_paths = get_u64(r);
    h->n_slices = get_u32(r), h->n_wi = get_u32(r);
    h->paths = get_u64(r), h->span_end = get_u64(r);
    h->stage = get_u32(r), h->n_ranges = get_u32(r);
    h->tl = get_u32(r);
    h->file_bytes = packed ? get_u64(r) : 0;
    h->grid_ni = packed ? get_u32(r) : 0;
    h->grid_nphi = packed ? get_u32(r) : 0;
    h->n_bands = version >= 7 ? get_u32(r) : 1;
    h->named = version >= 7 ? get_u32(r) : 0;
    announced_size(h);
    return 0;
}

/* Damaged bytes: the CRC of all but the last 4 bytes, which hold it. */
static int check_crc(const unsigned char *data, size_t len, const lss_header *h, char *err, size_t errcap)
{
    const size_t want = h->want;
    uint32_t crc = (uint32_t)data[len - 4] | (uint32_t)data[len - 3] << 8 |
                   (uint32_t)data[len - 2] << 16 | (uint32_t)data[len - 1] << 24;
#ifndef LSQT_LSS_FUZZING /* the fuzz target skips the CRC to reach the parser behind it */
    if (lsqt_crc32(0, data, len - 4) != crc) {
        if (want && len < want)
            snprintf(err, errcap, "truncated at byte %zu (its header announces %zu bytes; CRC mismatch)", len, want);
        else if (want && len > want)
            snprintf(err, errcap, "corrupt LSS file: %zu bytes where its header announces %zu (CRC mismatch)", len,
                     want);
        else
            snprintf(err, errcap, "corrupt LSS file (CRC mismatch: damaged bytes)");
        return -1;
    }
#else
    (void)crc, (void)want, (void)len, (void)err, (void)errcap;
#endif
    return 0;
}

/* The grid's NI and NPHI fit the direction method and the direction count. */
static int grid_ok(const lss_header *h)
{
    const uint32_t grid_ni = h->grid_ni, grid_nphi = h->grid_nphi, n_wi = h->n_wi;
    return h->dir_method == LSQT_DIRS_GRID
               ? grid_ni >= 2 && grid_ni <= 1024 && grid_nphi >= 2 && grid_nphi <= 2048 && grid_nphi % 2 == 0 &&
                     (uint32_t)lsqt_grid_wi_count((int)grid_ni, (int)grid_nphi, (int)h->transmits) == n_wi
           : h->dir_method == LSQT_DIRS_RGL
               ? grid_ni >= 2 && grid_ni <= 44 && grid_nphi == 0 && (uint32_t)lsqt_rgl_wi_count((int)grid_ni) == n_wi
               : grid_ni == 0 && grid_nphi == 0;
}

/* What a valid CRC vouches for but this build must agree with: the tally layout, the
 * header's values in range, and the file's size. */
static int check_header(const lss_header *h, int bad, size_t len, char *err, size_t errcap)
{
    static const char *const layout_name[] = {"chunk", "batches", "fixed-point bits", "histogram mu bins",
                                              "histogram phi bins", "scalar tallies"};
    const uint32_t layout[] = {LSQT_CHUNK, LSQT_BATCHES, LSQT_FIX_BITS, LSQT_HIST_NMU, LSQT_HIST_NPHI, LSQT_T_COUNT};
    for (size_t i = 0; i < 6; i++)
        if (h->file_layout[i] != layout[i]) {
            snprintf(err, errcap, "LSS tally layout differs from this build's (%s %u, this build %u); cannot read it",
                     layout_name[i], h->file_layout[i], layout[i]);
            return -1;
        }
    const uint32_t rx = h->rx, stage = h->stage;
    if (bad || !h->sane || !grid_ok(h) || h->use_double > 1 || h->transmits > 1 || h->dir_method > LSQT_DIRS_RGL ||
        rx > 8 || stage > LSQT_STAGE_PILOT || (stage == LSQT_STAGE_PILOT && (rx < 2 || h->n_slices % rx)) ||
        (stage == LSQT_STAGE_RUN && h->pilot_paths > h->span_end)) {
        snprintf(err, errcap, "corrupt LSS header (slices %u, wi %u, text %u bytes, double %u, transmits %u)",
                 h->n_slices, h->n_wi, h->tl, h->use_double, h->transmits);
        return -1;
    }
    /* The rest must have exactly the size the header announces. */
    if (len != h->want) {
        snprintf(err, errcap, "corrupt LSS file (%zu bytes, its header announces %zu)", len, h->want);
        return -1;
    }
    return 0;
}

/* The assembly text and a state of the header's shape and settings. */
static int read_state(rbuf *r, const lss_header *h, lsqt_state *st, char *err, size_t errcap)
{
    const uint32_t tl = h->tl, flags = h->flags;
    char *text = malloc((size_t)tl + 1);
    if (!text) {
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    memcpy(text, take(r, tl), tl);
    text[tl] = '\0';
    double *wl = h->named ? malloc((size_t)h->n_bands * sizeof *wl) : NULL;
    int bad_wl = 0;
    for (uint32_t b = 0; wl && b < h->n_bands; b++) {
        wl[b] = get_f64(r);
        bad_wl |= !(wl[b] > 0 && wl[b] <= 1e6) || (b && !(wl[b] > wl[b - 1]));
    }
    int rc = (h->named && !wl) ? -1
                               : lsqt_state_init(st, text, h->hash, h->seed, (int)h->n_slices, (int)h->n_wi,
                                                       (int)h->transmits, (int)h->n_bands, wl);
    free(text);
    free(wl);
    if (!rc && bad_wl) {
        lsqt_state_free(st);
        snprintf(err, errcap, "corrupt LSS file (band wavelengths not increasing positive numbers)");
        return -1;
    }
    if (rc) {
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    st->use_double = (int)h->use_double;
    st->flags = flags;
    st->dir_method = h->dir_method;
    st->rx = h->rx;
    st->pilot_paths = h->pilot_paths;
    st->span_end = h->span_end;
    st->stage = h->stage;
    st->lss_version = h->version;
    st->grid_ni = h->grid_ni, st->grid_nphi = h->grid_nphi;
    return 0;
}

/* The path ranges, stored normalized: sorted, disjoint, not adjacent, not empty, inside
 * the span, and holding the header's path count. */
static int read_ranges(rbuf *r, const lss_header *h, lsqt_state *st, char *err, size_t errcap)
{
    const uint32_t n_ranges = h->n_ranges;
    uint64_t *ranges = malloc(((size_t)n_ranges + 1) * 2 * sizeof *ranges);
    if (!ranges) {
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    for (size_t i = 0; i < 2 * (size_t)n_ranges; i++) ranges[i] = get_u64(r);
    int ranges_ok = 1;
    for (size_t i = 0; i < n_ranges; i++)
        if (ranges[2 * i] >= ranges[2 * i + 1] || (i && ranges[2 * i] <= ranges[2 * i - 1]) ||
            ranges[2 * i + 1] > h->span_end)
            ranges_ok = 0;
    if (ranges_ok && lsqt_state_set_ranges(st, ranges, (int)n_ranges)) ranges_ok = 0;
    free(ranges);
    if (!ranges_ok || st->paths != h->paths) {
        snprintf(err, errcap, "corrupt LSS file (path ranges: %u of them, not a sorted disjoint set holding %llu paths)",
                 n_ranges, (unsigned long long)h->paths);
        return -1;
    }
    return 0;
}

/* Every slice's record: theta_o, flags, path count, directions, tallies; histograms
 * packed as they are read where the state holds them so (lsqt_state_hist_packs: a
 * 200-band state continued held them all dense first). */
static int read_slices(rbuf *r, const lss_header *h, lsqt_state *st, char *err, size_t errcap)
{
    const size_t nw = h->n_wi, nh = (size_t)LSQT_BATCHES * LSQT_HIST_BINS;
    lsqt_u128 *scratch = NULL;
    if (lsqt_state_hist_packs(st) && (!(scratch = calloc(nh, sizeof *scratch)) || lsqt_state_pack_hist(st, 1))) {
        free(scratch);
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    for (size_t s = 0; s < h->n_slices && !r->bad; s++) {
        st->theta_o[s] = get_f64(r);
        st->slice_flags[s] = get_u32(r);
        if (st->slice_flags[s] & ~(uint32_t)LSQT_SLICE_BELOW) r->bad = 1;
        if (get_u64(r) != h->paths) r->bad = 1;
        for (size_t k = 0; k < nw; k++)
            for (size_t c = 0; c < 3; c++) st->wi[(s * nw + k) * 4 + c] = get_f32(r);
        for (int b = 0; b < st->n_bands; b++) {
            lsqt_state band = lsqt_state_band(st, b);
            const tally_run t = slice_tallies(&band, s, scratch); /* packed: scratch, zero */
            if (h->packed) get_tallies(r, &t);
            else
                for (int p = 0; p < 3; p++)
                    for (size_t i = 0; i < t.n[p]; i++) t.part[p][i] = get_u128(r);
            for (int k = 0; scratch && k < LSQT_BATCHES && !r->bad; k++)
                if (lsqt_state_hist_write(&band, 0, (int)s, k, scratch + (size_t)k * LSQT_HIST_BINS, 1)) {
                    free(scratch);
                    snprintf(err, errcap, "out of memory");
                    return -1;
                }
        }
    }
    free(scratch);
    if (r->at != r->n) r->bad = 1; /* packed tallies shorter than the size announced */
    if (r->bad) {
        snprintf(err, errcap, "corrupt LSS file (inconsistent slice records)");
        return -1;
    }
    return 0;
}

int lsqt_lss_parse(const unsigned char *data, size_t len, lsqt_state *st, char *err, size_t errcap)
{
    memset(st, 0, sizeof *st);
    /* The checks go from the first byte on, so each message says what is wrong first: not
     * an LSS at all, another version (whose layout this build cannot know), a file cut
     * short, damaged bytes (CRC), and last what a valid CRC cannot vouch for. */
    if (check_start(data, len, err, errcap)) return -1;
    rbuf r = {data, len, 8, 0};
    lss_header h;
    if (read_header(&r, len, &h, err, errcap) || check_crc(data, len, &h, err, errcap) ||
        check_header(&h, r.bad, len, err, errcap))
        return -1;
    r.n = len - 4;
    if (read_state(&r, &h, st, err, errcap)) return -1;
    if (read_ranges(&r, &h, st, err, errcap) || read_slices(&r, &h, st, err, errcap) ||
        check_slices(st, err, errcap)) {
        lsqt_state_free(st);
        return -1;
    }
    return 0;
}

int lsqt_lss_read(const char *path, lsqt_state *st, char *err, size_t errcap)
{
    /* One input rule for every program: only a regular file (or stdin, "-") is read as an
     * LSS: a FIFO would block, a device holds no state, a directory is no file. */
    const char *what = NULL;
    if (strcmp(path, "-") != 0 && lsqt_path_type(path, &what) > LSQT_PATH_REGULAR) {
        snprintf(err, errcap, "'%s' is a %s, not an LSS file (only regular files are read)", path, what);
        return -1;
    }
    size_t len = 0;
    char *data = lsqt_read_file(path, &len, err, errcap);
    if (!data) return -1;
    char inner[512];
    int rc = lsqt_lss_parse((const unsigned char *)data, len, st, inner, sizeof inner);
    if (rc) snprintf(err, errcap, "'%s': %s", path, inner);
    free(data);
    return rc;
}
