/* Strict number parsing (cli.h): the flags' values and the --wi-file's numbers. */
#include "lsqt/cli.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int lsqt_parse_double(const char *s, double *out)
{
    if (!s || !*s || isspace((unsigned char)*s)) return -1;
    for (const char *p = s; *p; p++)
        if (!strchr("0123456789+-.eE", *p)) return -1; /* no hex, inf, nan */
    char *end = NULL;
    double v = strtod(s, &end);
    if (*end != '\0' || !isfinite(v)) return -1;
    *out = v;
    return 0;
}

int lsqt_parse_count(const char *s, double lo, double hi, uint64_t *out)
{
    double v;
    if (lsqt_parse_double(s, &v) || v != floor(v) || v < lo || v > hi) return -1;
    *out = (uint64_t)v;
    return 0;
}

int lsqt_parse_u64(const char *s, uint64_t *out)
{
    if (!s || !*s) return -1;
    uint64_t v = 0;
    for (const char *p = s; *p; p++) {
        if (*p < '0' || *p > '9') return -1;
        unsigned d = (unsigned)(*p - '0');
        if (v > (UINT64_MAX - d) / 10) return -1; /* above 2^64 - 1 */
        v = v * 10 + d;
    }
    *out = v;
    return 0;
}
