/* libFuzzer target for the --wi-file parser: any bytes parse or fail cleanly (status 2,
 * nothing returned, a message); what parses is 1 to LSQT_WI_FILE_MAX unit directions
 * with y >= 0, none on the horizon, none below it unless allowed; allowing directions
 * below the horizon never changes one that was accepted without; and the directions,
 * written back as x y z, parse again to the same directions. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsqt/directions.h"

static void check_dirs(const float *d, int n, int lower)
{
    if (!d || n < 1 || n > LSQT_WI_FILE_MAX) abort();
    for (int k = 0; k < n; k++) {
        const float *w = d + 4 * k;
        double len = sqrt((double)w[0] * w[0] + (double)w[1] * w[1] + (double)w[2] * w[2]);
        if (!(fabs(len - 1.0) < 1e-6) || !(w[1] >= 0) || w[2] == 0 || (!lower && w[2] < 0) || w[3] != 0) abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    float *d[2] = {NULL, NULL};
    int n[2] = {0, 0}, m[2] = {0, 0};
    char err[512];
    int rc[2];
    for (int lower = 0; lower < 2; lower++) {
        err[0] = '\0';
        rc[lower] = lsqt_wi_parse((const char *)data, size, "fuzz", lower, &d[lower], &n[lower], &m[lower], err, sizeof err);
        if (rc[lower] == 0) check_dirs(d[lower], n[lower], lower);
        else if (rc[lower] != 2 || d[lower] || n[lower] || m[lower] || strncmp(err, "fuzz", 4) != 0) abort();
    }
    if (rc[0] == 0 && (rc[1] != 0 || n[0] != n[1] || m[0] != m[1] || memcmp(d[0], d[1], (size_t)n[0] * 16) != 0)) abort();
    if (rc[1] == 0) {
        char *text = malloc((size_t)n[1] * 64 + 1), *p = text;
        if (!text) abort();
        for (int k = 0; k < n[1]; k++)
            p += sprintf(p, "%.9g %.9g %.9g\n", d[1][4 * k], d[1][4 * k + 1], d[1][4 * k + 2]);
        float *e = NULL;
        int ne = 0, me = 0;
        if (lsqt_wi_parse(text, (size_t)(p - text), "again", 1, &e, &ne, &me, err, sizeof err) != 0 || ne != n[1] || me)
            abort();
        for (int k = 0; k < 4 * ne; k++)
            if (!(fabs(e[k] - d[1][k]) <= 2.5e-7)) abort();
        free(e);
        free(text);
    }
    free(d[0]);
    free(d[1]);
    return 0;
}
