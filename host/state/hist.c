/* A state's exit histograms, dense or packed (state.h). Packed, each batch of each
 * histogram of each band is the LSS's form of its tallies (lss.h), so a batch no path
 * reached costs a pointer and a run of 10^4 paths about an eighth of its dense size. */
#include <stdlib.h>
#include <string.h>

#include "lsqt/state.h"

/* A batch of one histogram, packed, is at most this long: a token byte and 16 bytes per
 * tally (the zero runs between them are shorter than the tallies they stand for). */
#define PACK_MAX ((size_t)LSQT_HIST_BINS * 17 + 16)

static size_t bands_of(const lsqt_state *st) { return (size_t)lsqt_state_bands(st); }
static size_t group_of(const lsqt_state *st) { return st->hist_group > 1 ? st->hist_group : 1; }
static size_t hists_of(const lsqt_state *st) { return (size_t)st->n_slices / group_of(st); }

static lsqt_hist_pack *pack_at(const lsqt_state *st, int b, int s, int t)
{
    return st->hist_pk + ((size_t)b * hists_of(st) + (size_t)s / group_of(st)) * LSQT_BATCHES + (size_t)t;
}

static lsqt_u128 *dense_at(const lsqt_state *st, int b, int s, int t)
{
    return st->hist + (((size_t)b * hists_of(st) + (size_t)s / group_of(st)) * LSQT_BATCHES + (size_t)t) * LSQT_HIST_BINS;
}

size_t lsqt_tally_varint(unsigned char *o, uint64_t v)
{
    size_t n = 0;
    do {
        o[n] = (unsigned char)(v & 0x7f);
        v >>= 7;
        if (v) o[n] |= 0x80;
        n++;
    } while (v);
    return n;
}

/* The LSS's tokens (lss.c): 2k a run of k zero tallies, 2L + 1 a nonzero tally in the next
 * L bytes, little-endian. Returns the length; 0 when every tally is zero. */
static size_t encode(const lsqt_u128 *in, size_t stride, unsigned char *o)
{
    size_t n = 0, zeros = 0, nonzero = 0;
    for (size_t i = 0; i < LSQT_HIST_BINS; i++) {
        const lsqt_u128 v = in[i * stride];
        if (!v.lo && !v.hi) {
            zeros++;
            continue;
        }
        if (zeros) n += lsqt_tally_varint(o + n, 2 * zeros);
        zeros = 0, nonzero++;
        size_t len = v.hi ? 8 : 0; /* bytes up to the last nonzero one */
        for (uint64_t w = v.hi ? v.hi : v.lo; w; w >>= 8) len++;
        o[n++] = (unsigned char)(2 * len + 1); /* < 128: one byte */
        for (size_t j = 0; j < len; j++) o[n++] = (unsigned char)(j < 8 ? v.lo >> (8 * j) : v.hi >> (8 * (j - 8)));
    }
    return nonzero ? n : 0;
}

/* Writes the nonzero tallies of P (its own encoding: no checks needed) to OUT[i * stride]. */
static void decode(const unsigned char *p, size_t n, lsqt_u128 *out, size_t stride)
{
    size_t at = 0, i = 0;
    while (at < n) {
        uint64_t tok = 0;
        for (int sh = 0; at < n; sh += 7) {
            const unsigned char c = p[at++];
            tok |= (uint64_t)(c & 0x7f) << sh;
            if (!(c & 0x80)) break;
        }
        if (!(tok & 1)) {
            i += (size_t)(tok / 2);
            continue;
        }
        const size_t len = (size_t)(tok / 2);
        lsqt_u128 v = {0, 0};
        for (size_t j = 0; j < len; j++) {
            const uint64_t byte = p[at + j];
            if (j < 8) v.lo |= byte << (8 * j);
            else v.hi |= byte << (8 * (j - 8));
        }
        at += len;
        out[i++ * stride] = v;
    }
}

int lsqt_state_hist_packs(const lsqt_state *st)
{
    const char *env = getenv("LSQT_PACK_HIST");
    if (env && (!strcmp(env, "0") || !strcmp(env, "1"))) return env[0] == '1';
    return st->n_bands > 1 && lsqt_state_hist_count(st) * sizeof(lsqt_u128) > LSQT_PACK_HIST_BYTES;
}

static void free_packs(lsqt_hist_pack *pk, size_t n)
{
    for (size_t i = 0; pk && i < n; i++) free(pk[i].p);
    free(pk);
}

int lsqt_state_pack_hist(lsqt_state *st, int force)
{
    if (st->hist_pk || !(force || lsqt_state_hist_packs(st))) return 0;
    const size_t n = bands_of(st) * hists_of(st) * LSQT_BATCHES;
    lsqt_hist_pack *pk = calloc(n ? n : 1, sizeof *pk);
    unsigned char *buf = malloc(PACK_MAX);
    for (size_t i = 0; pk && buf && i < n; i++) {
        const size_t len = encode(st->hist + i * LSQT_HIST_BINS, 1, buf);
        if (!len) continue;
        if (!(pk[i].p = malloc(len))) {
            free_packs(pk, n);
            pk = NULL;
            break;
        }
        memcpy(pk[i].p, buf, len);
        pk[i].n = (uint32_t)len;
    }
    free(buf);
    if (!pk) return -1;
    free(st->hist);
    st->hist = NULL;
    st->hist_pk = pk;
    return 0;
}

void lsqt_state_hist_read(const lsqt_state *st, int b, int s, int t, lsqt_u128 *out, size_t stride)
{
    if (st->hist_pk) {
        const lsqt_hist_pack *p = pack_at(st, b, s, t);
        if (p->p) decode(p->p, p->n, out, stride);
        return;
    }
    const lsqt_u128 *h = dense_at(st, b, s, t);
    for (size_t i = 0; i < LSQT_HIST_BINS; i++)
        if (h[i].lo || h[i].hi) out[i * stride] = h[i];
}

int lsqt_state_hist_write(lsqt_state *st, int b, int s, int t, const lsqt_u128 *in, size_t stride)
{
    if (!st->hist_pk) {
        lsqt_u128 *h = dense_at(st, b, s, t);
        for (size_t i = 0; i < LSQT_HIST_BINS; i++) /* a word written only where it differs */
            if (h[i].lo != in[i * stride].lo || h[i].hi != in[i * stride].hi) h[i] = in[i * stride];
        return 0;
    }
    unsigned char buf[PACK_MAX];
    const size_t len = encode(in, stride, buf);
    unsigned char *p = len ? malloc(len) : NULL;
    if (len && !p) return -1;
    if (len) memcpy(p, buf, len);
    lsqt_hist_pack *pk = pack_at(st, b, s, t);
    free(pk->p);
    pk->p = p, pk->n = (uint32_t)len;
    return 0;
}

int lsqt_state_copy_hist(lsqt_state *dst, int ds, const lsqt_state *src, int ss)
{
    lsqt_u128 *tmp = calloc(LSQT_HIST_BINS, sizeof *tmp);
    int rc = tmp ? 0 : -1;
    for (int b = 0; !rc && b < (int)bands_of(src); b++)
        for (int t = 0; !rc && t < LSQT_BATCHES; t++) {
            lsqt_state_hist_read(src, b, ss, t, tmp, 1);
            rc = lsqt_state_hist_write(dst, b, ds, t, tmp, 1);
            memset(tmp, 0, LSQT_HIST_BINS * sizeof *tmp);
        }
    free(tmp);
    return rc;
}

void lsqt_state_drop_hist(lsqt_state *st, int s0, int s1)
{
    if (s1 <= s0) return;
    const size_t g = group_of(st), h0 = (size_t)s0 / g, h1 = ((size_t)s1 - 1) / g + 1;
    for (size_t b = 0; b < bands_of(st); b++) {
        if (!st->hist_pk) {
            lsqt_tallies_drop(dense_at(st, (int)b, (int)(h0 * g), 0), (h1 - h0) * LSQT_BATCHES * LSQT_HIST_BINS);
            continue;
        }
        for (size_t h = h0; h < h1; h++)
            for (int t = 0; t < LSQT_BATCHES; t++) {
                lsqt_hist_pack *p = pack_at(st, (int)b, (int)(h * g), t);
                free(p->p);
                p->p = NULL, p->n = 0;
            }
    }
}

int lsqt_state_add_hist(lsqt_state *dst, const lsqt_state *src)
{
    lsqt_u128 *a = malloc(2 * LSQT_HIST_BINS * sizeof *a), *b = a + LSQT_HIST_BINS;
    int rc = a ? 0 : -1;
    for (int band = 0; !rc && band < (int)bands_of(dst); band++)
        for (size_t h = 0; !rc && h < hists_of(dst); h++)
            for (int t = 0; !rc && t < LSQT_BATCHES; t++) {
                const int sl = (int)(h * group_of(dst));
                memset(a, 0, 2 * LSQT_HIST_BINS * sizeof *a);
                lsqt_state_hist_read(dst, band, sl, t, a, 1);
                lsqt_state_hist_read(src, band, sl, t, b, 1);
                for (size_t i = 0; i < LSQT_HIST_BINS; i++) a[i] = lsqt_u128_add(a[i], b[i]);
                rc = lsqt_state_hist_write(dst, band, sl, t, a, 1);
            }
    free(a);
    return rc;
}
