/* Whole files into memory: the LSQT input, --wi-file, an LSS. */
#include "lsqt/util.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

char *lsqt_read_file(const char *path, size_t *len, char *err, size_t errcap)
{
    return lsqt_read_text(path, SIZE_MAX, len, err, errcap);
}

char *lsqt_read_text(const char *path, size_t max, size_t *len, char *err, size_t errcap)
{
    if (errcap) err[0] = '\0';
    int is_stdin = strcmp(path, "-") == 0;
    FILE *f = is_stdin ? stdin : fopen(path, "rb");
    if (!f) {
        snprintf(err, errcap, "cannot open '%s': %s", path, strerror(errno));
        return NULL;
    }
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    while (buf) {
        size_t got = fread(buf + n, 1, cap - n - 1, f);
        n += got;
        if (n > max) {
            snprintf(err, errcap, "%s%s%s is larger than %zu MiB, the most an input may be (is it the right file?)",
                     is_stdin ? "" : "'", is_stdin ? "standard input" : path, is_stdin ? "" : "'", max >> 20);
            free(buf);
            buf = NULL;
            break;
        }
        if (n + 1 < cap) {
            if (ferror(f)) {
                snprintf(err, errcap, "cannot read '%s': %s", path, strerror(errno));
                free(buf);
                buf = NULL;
            }
            break;
        }
        char *bigger = realloc(buf, cap * 2);
        if (!bigger) free(buf);
        buf = bigger;
        cap *= 2;
    }
    if (!is_stdin) fclose(f);
    if (!buf) {
        if (!err[0]) snprintf(err, errcap, "out of memory reading '%s'", path);
        return NULL;
    }
    buf[n] = '\0';
    *len = n;
    return buf;
}
