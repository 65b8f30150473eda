/* "Did you mean": the known word a mistyped one was most likely meant to be. */
#include <ctype.h>
#include <string.h>

#include "lsqt/util.h"

#define SUGGEST_MAX 64 /* longer words are not slips of a known one */

/* Edit distance, case-insensitive, a swap of two neighbours counting one (optimal string
 * alignment): "LambertianBdsf" is one from "LambertianBsdf", "fr" none from "fR". */
static int distance(const char *a, size_t n, const char *b, size_t m)
{
    int d[SUGGEST_MAX + 1][SUGGEST_MAX + 1]; /* 17 KB of stack */
    for (size_t i = 0; i <= n; i++) d[i][0] = (int)i;
    for (size_t j = 0; j <= m; j++) d[0][j] = (int)j;
    for (size_t i = 1; i <= n; i++)
        for (size_t j = 1; j <= m; j++) {
            const int same = tolower((unsigned char)a[i - 1]) == tolower((unsigned char)b[j - 1]);
            int v = d[i - 1][j - 1] + !same;
            if (d[i - 1][j] + 1 < v) v = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < v) v = d[i][j - 1] + 1;
            if (i > 1 && j > 1 && tolower((unsigned char)a[i - 1]) == tolower((unsigned char)b[j - 2]) &&
                tolower((unsigned char)a[i - 2]) == tolower((unsigned char)b[j - 1]) && d[i - 2][j - 2] + 1 < v)
                v = d[i - 2][j - 2] + 1;
            d[i][j] = v;
        }
    return d[n][m];
}

const char *lsqt_closest(const char *word, size_t len, const char *const *cand, int n)
{
    if (len == 0 || len > SUGGEST_MAX) return NULL;
    /* a slip: one edit in a word of up to 4 characters, two up to 8, three beyond */
    const int most = len <= 4 ? 1 : len <= 8 ? 2 : 3;
    const char *best = NULL;
    int best_d = most + 1, tie = 0;
    for (int i = 0; i < n; i++) {
        if (!cand[i] || strlen(cand[i]) > SUGGEST_MAX) continue;
        const int dd = distance(word, len, cand[i], strlen(cand[i]));
        if (dd < best_d) best = cand[i], best_d = dd, tie = 0;
        else if (dd == best_d && best && strcmp(best, cand[i]) != 0) tie = 1;
    }
    return best && !tie ? best : NULL;
}
