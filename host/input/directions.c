#include "lsqt/directions.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/cli.h"
#include "lsqt/util.h"

void lsqt_wo_angles(int n, double *theta)
{
    for (int k = 0; k < n; k++) theta[k] = (double)k / n * 0.99 * (LSQT_PI / 2);
}

void lsqt_wi_spread(int n, int sphere, float *out)
{
    const double golden = 0.6180339887498949; /* irrational step: no two azimuths coincide */
    for (int j = 0; j < n; j++) {
        double u = (j + 0.5) / n;
        double z = sphere ? 1.0 - 2.0 * u : 1.0 - u; /* uniform in z: equal area */
        double t = (j + 0.5) * golden;
        double phi = LSQT_PI * (t - floor(t));           /* [0, pi]: y >= 0 */
        double s = sqrt(fmax(0.0, 1.0 - z * z));
        out[4 * j] = (float)(s * cos(phi));
        out[4 * j + 1] = (float)(s * sin(phi));
        out[4 * j + 2] = (float)z;
        out[4 * j + 3] = 0.0f;
    }
}

/* ---- --wi-file ------------------------------------------------------------------------ */

/* sin and cos of an angle in degrees, exact at multiples of 90 (cos 90 is 0, not 6e-17:
 * theta = 90 must be seen as the horizon it is). */
static void sincos_deg(double deg, double *s, double *c)
{
    double r = fmod(deg, 360.0);
    if (r < 0) r += 360.0;
    int q = (int)floor(r / 90.0 + 0.5); /* nearest quadrant, 0 .. 4 */
    double a = (r - 90.0 * q) * (LSQT_PI / 180.0), s0 = sin(a), c0 = cos(a); /* |a| <= 45 deg */
    switch (q & 3) {
    case 0: *s = s0, *c = c0; break;
    case 1: *s = c0, *c = -s0; break;
    case 2: *s = -s0, *c = -c0; break;
    default: *s = -c0, *c = s0; break;
    }
    *s += 0.0; /* no -0 */
    *c += 0.0;
}

/* ---- --grid --------------------------------------------------------------------------- */

double lsqt_grid_cos(int k, int n)
{
    return k == 0 ? LSQT_GRID_HORIZON_COS : (double)k / (n - 1);
}

void lsqt_grid_theta_o(int n, double *theta)
{
    for (int s = 0; s < n; s++) theta[s] = s == 0 ? 0.0 : acos(lsqt_grid_cos(n - 1 - s, n));
}

int lsqt_grid_wi_count(int ni, int nphi, int lower)
{
    return ni * (nphi / 2 + 1) * (lower ? 2 : 1);
}

void lsqt_grid_wi(int ni, int nphi, int lower, float *out)
{
    const int na = nphi / 2 + 1;
    for (int h = 0; h < (lower ? 2 : 1); h++)
        for (int i = 0; i < ni; i++) {
            const double c = lsqt_grid_cos(ni - 1 - i, ni), st = sqrt(fmax(0.0, 1.0 - c * c));
            for (int m = 0; m < na; m++) {
                double sp, cp;
                sincos_deg(360.0 * m / nphi, &sp, &cp); /* exact at multiples of 90 deg */
                float *d = out + 4 * ((size_t)(h * ni + i) * na + m);
                d[0] = (float)(st * cp), d[1] = (float)(st * sp), d[2] = (float)(h ? -c : c), d[3] = 0.0f;
            }
        }
}

void lsqt_rgl_theta_o(int nt, double *theta)
{
    for (int k = 0; k < nt; k++) theta[k] = k == nt - 1 ? acos(LSQT_GRID_HORIZON_COS) : LSQT_PI / 2 * k / (nt - 1);
}

int lsqt_rgl_wi_count(int nu) { return (nu - nu / 2) * nu; }

int lsqt_rgl_node(double theta_o, int nu, int j, int l, double wi[3])
{
    const double u = (double)l / (nu - 1), tm = u * u * (LSQT_PI / 2), pm = (2.0 * j / (nu - 1) - 1.0) * LSQT_PI;
    const double m[3] = {sin(tm) * cos(pm), sin(tm) * sin(pm), cos(tm)}, wo[3] = {sin(theta_o), 0.0, cos(theta_o)};
    const double c = wo[0] * m[0] + wo[2] * m[2];
    for (int i = 0; i < 3; i++) wi[i] = 2.0 * c * m[i] - wo[i];
    return c > 0 && wi[2] >= LSQT_RGL_MIN_COS;
}

void lsqt_rgl_wi(double theta_o, int nu, float *out)
{
    for (int j = nu / 2; j < nu; j++)
        for (int l = 0; l < nu; l++) {
            double w[3];
            if (!lsqt_rgl_node(theta_o, nu, j, l, w)) w[0] = -sin(theta_o), w[1] = 0.0, w[2] = cos(theta_o);
            float *d = out + 4 * ((size_t)(j - nu / 2) * nu + l);
            d[0] = (float)w[0], d[1] = (float)fabs(w[1]), d[2] = (float)w[2], d[3] = 0.0f;
        }
}

typedef struct wi_span {
    const char *p;
    size_t n;
} wi_span;

static int is_blank(char ch) { return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f'; }

/* Up to 40 characters of s, unprintable ones as '?'. */
static const char *wi_show(wi_span s, char out[48])
{
    size_t n = s.n > 40 ? 40 : s.n, i;
    for (i = 0; i < n; i++) out[i] = (s.p[i] >= 0x20 && s.p[i] < 0x7f) ? s.p[i] : '?';
    strcpy(out + i, s.n > n ? "..." : "");
    return out;
}

static int wi_fail(char *err, size_t errcap, const char *name, long line, wi_span tok, const char *what,
                   const char *expected)
{
    char shown[48], at[64] = "";
    if (tok.p) snprintf(at, sizeof at, " at '%s'", wi_show(tok, shown));
    if (line > 0) snprintf(err, errcap, "%s:%ld: error: %s%s; expected %s", name, line, what, at, expected);
    else snprintf(err, errcap, "%s: error: %s%s; expected %s", name, what, at, expected);
    return 2;
}

static int wi_number(wi_span t, double *v)
{
    char buf[256];
    if (t.n >= sizeof buf || memchr(t.p, '\0', t.n)) return -1;
    memcpy(buf, t.p, t.n);
    buf[t.n] = '\0';
    return lsqt_parse_double(buf, v);
}

#define WI_STR(x) #x
#define WI_XSTR(x) WI_STR(x)
#define WI_FORMS "a direction per line, 'x y z' or 'theta_deg phi_deg'"

/* One line's direction in d[3] (unit, double) and its text in *all. Returns 0, 1 (no
 * direction: blank or a comment) or 2 (err filled). */
static int wi_line(const char *p, const char *end, const char *name, long line, double d[3], wi_span *all,
                   char *err, size_t errcap)
{
    const char *hash = memchr(p, '#', (size_t)(end - p));
    if (hash) end = hash;
    wi_span tok[4];
    int nt = 0;
    while (p < end) {
        while (p < end && is_blank(*p)) p++;
        if (p == end) break;
        const char *s = p;
        while (p < end && !is_blank(*p)) p++;
        if (nt == 4) break;
        tok[nt].p = s;
        tok[nt++].n = (size_t)(p - s);
    }
    if (nt == 0) return 1;
    all->p = tok[0].p;
    all->n = (size_t)(tok[nt - 1].p + tok[nt - 1].n - tok[0].p);
    if (nt == 4) return wi_fail(err, errcap, name, line, tok[3], "trailing text after the direction", WI_FORMS);
    double v[3];
    for (int i = 0; i < nt; i++)
        if (wi_number(tok[i], &v[i]))
            return wi_fail(err, errcap, name, line, tok[i], "not a finite number", WI_FORMS);
    if (nt == 1) return wi_fail(err, errcap, name, line, tok[0], "a single number", WI_FORMS);
    if (nt == 2) {
        if (!(v[0] >= 0 && v[0] <= 180))
            return wi_fail(err, errcap, name, line, tok[0], "theta out of range",
                           "theta_deg in [0, 180] (the angle from +z)");
        double st, ct, sp, cp;
        sincos_deg(v[0], &st, &ct);
        sincos_deg(v[1], &sp, &cp);
        d[0] = st * cp;
        d[1] = st * sp;
        d[2] = ct;
    } else {
        double m = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2]))); /* scaled first: no overflow */
        if (!(m > 0)) return wi_fail(err, errcap, name, line, *all, "the zero vector", "a direction of non-zero length");
        for (int i = 0; i < 3; i++) v[i] /= m;
        double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int i = 0; i < 3; i++) d[i] = v[i] / len;
    }
    if ((float)d[2] == 0.0f)
        return wi_fail(err, errcap, name, line, *all,
                       "a direction on the horizon (z = 0, where the BSDF value tally/|cos| is 0/0)", "z != 0");
    return 0;
}

int lsqt_wi_parse(const char *text, size_t len, const char *name, int lower, float **dirs, int *n,
                  int *n_mirrored, char *err, size_t errcap)
{
    *dirs = NULL;
    *n = 0;
    if (n_mirrored) *n_mirrored = 0;
    if (errcap) err[0] = '\0';
    float *out = malloc((size_t)LSQT_WI_FILE_MAX * 4 * sizeof *out);
    if (!out) {
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    int count = 0, mirrored = 0;
    long line = 0;
    const char *p = text, *end = text + len;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        const char *line_end = nl ? nl : end;
        line++;
        double d[3] = {0.0, 0.0, 0.0};
        wi_span all = {NULL, 0};
        int rc = wi_line(p, line_end, name, line, d, &all, err, errcap);
        if (rc == 0 && d[2] < 0 && !lower)
            rc = wi_fail(err, errcap, name, line, all,
                         "a direction below the horizon (z < 0), but the stack transmits nothing (its value would be 0)",
                         "z > 0 for a stack that only reflects");
        else if (rc == 0 && count == LSQT_WI_FILE_MAX)
            rc = wi_fail(err, errcap, name, line, all, "too many directions",
                         "at most " WI_XSTR(LSQT_WI_FILE_MAX) " directions");
        if (rc == 2) {
            free(out);
            return 2;
        }
        if (rc == 0) {
            float *w = out + 4 * count++;
            mirrored += d[1] < 0;
            w[0] = (float)(d[0] + 0.0);
            w[1] = (float)fabs(d[1]); /* mirror image: the BSDF is symmetric in y */
            w[2] = (float)d[2];
            w[3] = 0.0f;
        }
        p = nl ? nl + 1 : end;
    }
    if (count == 0) {
        free(out);
        wi_span none = {NULL, 0};
        return wi_fail(err, errcap, name, 0, none, "no directions (every line is blank or a comment)",
                       "1 to " WI_XSTR(LSQT_WI_FILE_MAX) " directions, " WI_FORMS);
    }
    *dirs = out;
    *n = count;
    if (n_mirrored) *n_mirrored = mirrored;
    return 0;
}

int lsqt_wi_file_read(const char *path, int lower, float **dirs, int *n, int *n_mirrored, char *err,
                      size_t errcap)
{
    *dirs = NULL;
    *n = 0;
    if (n_mirrored) *n_mirrored = 0;
    size_t len = 0;
    char *text = lsqt_read_text(path, LSQT_INPUT_MAX, &len, err, errcap);
    if (!text) return strncmp(err, "out of memory", 13) == 0 ? -1 : 1;
    int rc = lsqt_wi_parse(text, len, strcmp(path, "-") == 0 ? "<stdin>" : path, lower, dirs, n, n_mirrored, err, errcap);
    free(text);
    return rc;
}
