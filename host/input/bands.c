/* Wavelength lists and spectral tables (lsqt/bands.h). */
#include "lsqt/bands.h"
#include "lsqt/assembly.h"
#include "lsqt/cli.h"
#include "lsqt/colour.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define WL_MAX 1e6 /* nm: a bound that keeps the numbers sane, far beyond any sensor */

/* One token [p, p + n) as a finite number. */
static int number(const char *p, size_t n, double *v)
{
    char buf[64];
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, p, n);
    buf[n] = '\0';
    return lsqt_parse_double(buf, v);
}

static int range(const char *list, double **out, int *n, char *err, size_t errcap)
{
    const char *c1 = strchr(list, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
    double a, b, s;
    if (!c2 || strchr(c2 + 1, ':') || number(list, (size_t)(c1 - list), &a) ||
        number(c1 + 1, (size_t)(c2 - c1 - 1), &b) || number(c2 + 1, strlen(c2 + 1), &s)) {
        snprintf(err, errcap, "'%s': expected START:STOP:STEP, three numbers in nm", list);
        return 2;
    }
    if (!(s > 0) || !(b >= a) || !(a > 0) || b > WL_MAX) {
        snprintf(err, errcap, "'%s': expected 0 < START <= STOP <= %g and STEP > 0", list, WL_MAX);
        return 2;
    }
    double k = (b - a) / s, whole = floor(k + 1e-9);
    if (k - whole > 1e-9) { /* both ends are included: STEP must divide STOP - START */
        const double up = whole + 1;
        char alt[160];
        if (whole >= 1)
            snprintf(alt, sizeof alt, "a STEP of %.10g or %.10g, or STOP %.10g or %.10g", (b - a) / whole,
                     (b - a) / up, a + whole * s, a + up * s);
        else
            snprintf(alt, sizeof alt, "a STEP of %.10g, or STOP %.10g", (b - a) / up, a + up * s);
        snprintf(err, errcap, "'%s': STEP %g does not divide STOP - START (%g; both ends are included): use %s",
                 list, s, b - a, alt);
        return 2;
    }
    if (whole + 1 > LSQT_MAX_BANDS) {
        snprintf(err, errcap, "'%s': %.0f bands, at most %d", list, whole + 1, LSQT_MAX_BANDS);
        return 2;
    }
    *n = (int)whole + 1;
    *out = malloc((size_t)*n * sizeof **out);
    if (!*out) {
        snprintf(err, errcap, "out of memory");
        return 2;
    }
    for (int i = 0; i < *n; i++) (*out)[i] = a + i * s;
    if (fabs(k - whole) <= 1e-9) (*out)[*n - 1] = b; /* STOP itself, not a rounded sum */
    return 0;
}

static int parse_list(const char *list, double **out, int *n, char *err, size_t errcap)
{
    int cap = 1;
    for (const char *p = list; *p; p++) cap += *p == ',';
    if (cap > LSQT_MAX_BANDS) {
        snprintf(err, errcap, "%d bands, at most %d", cap, LSQT_MAX_BANDS);
        return 2;
    }
    double *w = malloc((size_t)cap * sizeof *w);
    if (!w) {
        snprintf(err, errcap, "out of memory");
        return 2;
    }
    const char *p = list;
    for (int i = 0; i < cap; i++) {
        const char *e = strchr(p, ',');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (number(p, len, &w[i]) || !(w[i] > 0) || w[i] > WL_MAX) {
            snprintf(err, errcap, "bad wavelength '%.*s' (band %d): expected a number of nm in (0, %g]",
                     (int)(len > 40 ? 40 : len), p, i + 1, WL_MAX);
            free(w);
            return 2;
        }
        if (i > 0 && !(w[i] > w[i - 1])) {
            snprintf(err, errcap, "'%.*s' (band %d) is not above the band before it (%g): the "
                     "wavelengths must increase", (int)(len > 40 ? 40 : len), p, i + 1, w[i - 1]);
            free(w);
            return 2;
        }
        p = e ? e + 1 : p + len;
    }
    *out = w, *n = cap;
    return 0;
}

/* v with the fewest digits that read back as v, into buf[32]. */
static const char *shortest(double v, char *buf)
{
    for (int prec = 6; prec <= 17; prec++) {
        snprintf(buf, 32, "%.*g", prec, v);
        if (strtod(buf, NULL) == v) break;
    }
    return buf;
}

int lsqt_parse_wavelengths(const char *list, double **out, int *n, char *err, size_t errcap)
{
    *out = NULL, *n = 0;
    if (strchr(list, ':') ? range(list, out, n, err, errcap) : parse_list(list, out, n, err, errcap)) return 2;
    /* every band needs a file label of its own (lsqt_band_names) */
    lsqt_band_names names;
    int k = 0;
    if (lsqt_band_names_init(&names, *n, *out, &k)) {
        char a[32], b[32];
        snprintf(err, errcap, "bands %d and %d (%s and %s nm) are too close: their file labels (the "
                 "wavelength with at most 9 decimals) are the same; the bands must differ by 1e-9 nm or more",
                 k + 1, k + 2, shortest((*out)[k], a), shortest((*out)[k + 1], b));
        free(*out);
        *out = NULL, *n = 0;
        return 2;
    }
    return 0;
}

/* Splits a row into at most 3 fields at spaces, tabs and commas; returns the count. */
static int fields(const char *p, const char *end, const char *f[3], size_t fn[3])
{
    int k = 0;
    while (p < end) {
        while (p < end && (*p == ' ' || *p == '\t' || *p == ',' || *p == '\r')) p++;
        if (p == end) break;
        const char *s = p;
        while (p < end && *p != ' ' && *p != '\t' && *p != ',' && *p != '\r') p++;
        if (k == 3) return 4;
        f[k] = s, fn[k] = (size_t)(p - s), k++;
    }
    return k;
}

int lsqt_band_table_parse(const char *text, size_t len, const char *name, lsqt_band_table *t, char *err,
                          size_t errcap)
{
    memset(t, 0, sizeof *t);
    int cap = 0, line = 0;
    const char *p = text, *end = text + len;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p)), *le = nl ? nl : end, *hash = memchr(p, '#', (size_t)(le - p));
        line++;
        const char *nul = memchr(p, '\0', (size_t)(le - p));
        if (nul) { /* it would end the number it is in unseen */
            snprintf(err, errcap, "%s:%d: a NUL byte (column %d): a table is text, rows of a wavelength in nm and its "
                     "value", name, line, (int)(nul - p) + 1);
            lsqt_band_table_free(t);
            return 2;
        }
        const char *f[3];
        size_t fn[3];
        int k = fields(p, hash ? hash : le, f, fn);
        p = nl ? nl + 1 : end;
        if (k == 0) continue;
        double wl, v;
        if (k != 2 || number(f[0], fn[0], &wl) || number(f[1], fn[1], &v)) {
            snprintf(err, errcap, "%s:%d: expected two numbers, a wavelength in nm and its value", name, line);
            lsqt_band_table_free(t);
            return 2;
        }
        if (t->n > 0 && !(wl > t->wl[t->n - 1])) {
            snprintf(err, errcap, "%s:%d: wavelength %g is not above the row before it (%g): the table's wavelengths "
                     "must increase", name, line, wl, t->wl[t->n - 1]);
            lsqt_band_table_free(t);
            return 2;
        }
        if (t->n == cap) {
            int nc = cap ? 2 * cap : 64;
            double *a = realloc(t->wl, (size_t)nc * sizeof *a), *b = a ? realloc(t->v, (size_t)nc * sizeof *b) : NULL;
            if (a) t->wl = a;
            if (!b) {
                snprintf(err, errcap, "%s: out of memory", name);
                lsqt_band_table_free(t);
                return 2;
            }
            t->v = b, cap = nc;
        }
        t->wl[t->n] = wl, t->v[t->n] = v, t->n++;
    }
    if (t->n == 0) {
        snprintf(err, errcap, "%s: no rows: expected lines of a wavelength in nm and its value", name);
        return 2;
    }
    return 0;
}

int lsqt_band_table_at(const lsqt_band_table *t, double wl, double *v)
{
    if (t->n == 0 || !(wl >= t->wl[0]) || !(wl <= t->wl[t->n - 1])) return -1;
    int lo = 0, hi = t->n - 1; /* wl[lo] <= wl <= wl[hi] */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (t->wl[mid] <= wl) lo = mid;
        else hi = mid;
    }
    if (wl == t->wl[lo] || lo == hi) {
        *v = t->v[lo];
        return 0;
    }
    double x = (wl - t->wl[lo]) / (t->wl[hi] - t->wl[lo]);
    *v = t->v[lo] + x * (t->v[hi] - t->v[lo]);
    return 0;
}

void lsqt_band_table_free(lsqt_band_table *t)
{
    free(t->wl);
    free(t->v);
    memset(t, 0, sizeof *t);
}

void lsqt_bands_free(lsqt_bands *b)
{
    for (int i = 0; i < b->n_tables; i++) {
        free(b->table_paths[i]);
        lsqt_band_table_free(&b->tables[i]);
    }
    free(b->table_paths);
    free(b->tables);
    b->n_tables = 0, b->table_paths = NULL, b->tables = NULL;
}

void lsqt_band_path_shown(const char *path, int n_bands, const double *wl, char *dst, size_t cap)
{
    if (n_bands <= 1) {
        snprintf(dst, cap, "%s", path);
        return;
    }
    lsqt_band_names nm;
    lsqt_band_names_init(&nm, n_bands, wl, NULL);
    char l0[48] = "?", l1[48] = "?", braces[128];
    lsqt_band_label(&nm, 0, l0, sizeof l0);
    lsqt_band_label(&nm, n_bands - 1, l1, sizeof l1);
    snprintf(braces, sizeof braces, "{%s,%s%s}", l0, n_bands > 2 ? "...," : "", l1);
    lsqt_band_path(path, braces, dst, cap);
}

void lsqt_band_path(const char *path, const char *label, char *dst, size_t cap)
{
    size_t n = strlen(path);
    const int raw = n >= 4 && strcmp(path + n - 4, ".raw") == 0;
    snprintf(dst, cap, "%.*s.%s%s", (int)(raw ? n - 4 : n), path, label, raw ? ".raw" : "");
}

/* ---- A phase function's table (a TABLE key, KEY=@FILE; lsqt/assembly.h) --------------- */

void lsqt_phase_table_free(lsqt_phase_table *t)
{
    free(t->mu), free(t->p), free(t->cdf), free(t->path);
    memset(t, 0, sizeof *t);
}

/* The token f (n bytes) for a message: at most 40 bytes. */
static const char *token(const char *f, size_t n, char out[48])
{
    size_t k = n < 40 ? n : 40;
    for (size_t i = 0; i < k; i++) out[i] = f[i] >= 0x20 && f[i] < 0x7f ? f[i] : '?';
    out[k] = '\0';
    return out;
}

#define PT_FAIL(...) \
    do { snprintf(err, errcap, __VA_ARGS__); lsqt_phase_table_free(t); return 2; } while (0)

int lsqt_phase_table_parse(const char *text, size_t len, const char *name, lsqt_phase_table *t, char *err,
                           size_t errcap)
{
    memset(t, 0, sizeof *t);
    int cap = 0, line = 0, dir = 0;
    char tk[48];
    const char *p = text, *end = text + len;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p)), *le = nl ? nl : end, *hash = memchr(p, '#', (size_t)(le - p));
        line++;
        const char *nul = memchr(p, '\0', (size_t)(le - p));
        if (nul)
            PT_FAIL("%s:%d: a NUL byte (column %d): a phase table is text, rows of cos theta and its value", name, line,
                    (int)(nul - p) + 1);
        const char *f[3];
        size_t fn[3];
        int k = fields(p, hash ? hash : le, f, fn);
        p = nl ? nl + 1 : end;
        if (k == 0) continue;
        double mu, v;
        if (k != 2)
            PT_FAIL("%s:%d: %s at '%s': expected two numbers, cos theta and the phase function's value "
                    "(a phase table, not a wavelength table)", name, line, k == 1 ? "one column" : "more than two columns",
                    token(f[0], fn[0], tk));
        if (number(f[0], fn[0], &mu)) PT_FAIL("%s:%d: '%s' is not a number: expected cos theta", name, line, token(f[0], fn[0], tk));
        if (number(f[1], fn[1], &v)) PT_FAIL("%s:%d: '%s' is not a number: expected the phase function's value", name, line,
                                             token(f[1], fn[1], tk));
        if (!(fabs(mu) <= 1 + 1e-9))
            PT_FAIL("%s:%d: cos theta '%s' outside [-1, 1] (a phase table's first column is cos theta, not an angle "
                    "or a wavelength)", name, line, token(f[0], fn[0], tk));
        if (!(v >= 0) || !isfinite(v))
            PT_FAIL("%s:%d: value '%s' is negative: a phase function is >= 0", name, line, token(f[1], fn[1], tk));
        mu = mu > 1 ? 1 : mu < -1 ? -1 : mu;
        if (t->n > 0) {
            const double prev = t->mu[t->n - 1];
            const int d = mu > prev ? 1 : mu < prev ? -1 : 0;
            if (d == 0 || (dir && d != dir))
                PT_FAIL("%s:%d: cos theta '%s' after %.17g: the rows must go one way in cos theta, increasing or "
                        "decreasing, with no repeats", name, line, token(f[0], fn[0], tk), prev);
            dir = d;
        }
        if (t->n == cap) {
            int nc = cap ? 2 * cap : 256;
            double *a = realloc(t->mu, (size_t)nc * sizeof *a);
            if (a) t->mu = a;
            double *b = a ? realloc(t->p, (size_t)nc * sizeof *b) : NULL;
            if (b) t->p = b;
            if (!b) PT_FAIL("%s: out of memory", name);
            cap = nc;
        }
        t->mu[t->n] = mu, t->p[t->n] = v, t->n++;
    }
    if (t->n < 2)
        PT_FAIL("%s: too few rows (%d): a phase table needs at least 2 rows of cos theta and value, from -1 to 1", name,
                t->n);
    if (dir < 0) /* descending (theta from 0 to pi, as Mie codes write it): turn it round */
        for (int i = 0, j = t->n - 1; i < j; i++, j--) {
            double a = t->mu[i], b = t->p[i];
            t->mu[i] = t->mu[j], t->p[i] = t->p[j], t->mu[j] = a, t->p[j] = b;
        }
    if (t->mu[0] > -1 + 1e-6 || t->mu[t->n - 1] < 1 - 1e-6)
        PT_FAIL("%s: cos theta covers [%.9g, %.9g]: a phase table must cover [-1, 1] (its first and last rows at -1 "
                "and 1)", name, t->mu[0], t->mu[t->n - 1]);
    t->mu[0] = -1, t->mu[t->n - 1] = 1;
    if (!(t->cdf = malloc((size_t)t->n * sizeof *t->cdf))) PT_FAIL("%s: out of memory", name);
    /* the trapezoid rule is the integral of the linear interpolation; 2 pi for the azimuth */
    t->cdf[0] = 0;
    for (int i = 1; i < t->n; i++)
        t->cdf[i] = t->cdf[i - 1] + 0.5 * (t->p[i - 1] + t->p[i]) * (t->mu[i] - t->mu[i - 1]);
    const double total = 2 * 3.14159265358979323846 * t->cdf[t->n - 1];
    if (!(total > 0) || !isfinite(total))
        PT_FAIL("%s: the phase function integrates to %g: it must be positive somewhere (and finite)", name, total);
    for (int i = 0; i < t->n; i++) t->p[i] /= total, t->cdf[i] /= t->cdf[t->n - 1];
    t->cdf[t->n - 1] = 1;
    /* the phase function's identity: its rows normalised (a table and its multiple are one) */
    uint64_t h = 14695981039346656037ULL;
    for (int i = 0; i < t->n; i++) {
        const double row[2] = {t->mu[i], t->p[i]};
        const unsigned char *b = (const unsigned char *)row;
        for (size_t k = 0; k < sizeof row; k++) h = (h ^ b[k]) * 1099511628211ULL;
    }
    t->hash = h;
    return 0;
}
