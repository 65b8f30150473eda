#include "lsqt/util.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

char *lsqt_read_file(const char *path, size_t *len, char *err, size_t errcap)
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

uint32_t lsqt_crc32(uint32_t crc, const void *data, size_t len)
{
    const unsigned char *p = data;
    crc = ~crc;
    for (size_t i = 0; i < len; i++) {
        crc ^= p[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

int lsqt_atomic_open(lsqt_atomic_file *af, const char *path, char *err, size_t errcap)
{
    memset(af, 0, sizeof *af);
    if (strlen(path) >= sizeof af->path) {
        snprintf(err, errcap, "path too long: '%.64s...'", path);
        return -1;
    }
    strcpy(af->path, path);
    snprintf(af->tmp, sizeof af->tmp, "%s.tmp.%ld", path, (long)getpid());
    af->f = fopen(af->tmp, "wb");
    if (!af->f) {
        snprintf(err, errcap, "cannot write '%s': %s", af->tmp, strerror(errno));
        return -1;
    }
    return 0;
}

int lsqt_atomic_commit(lsqt_atomic_file *af, char *err, size_t errcap)
{
    int bad = ferror(af->f) || fflush(af->f) != 0 || fsync(fileno(af->f)) != 0;
    int saved = errno;
    if (fclose(af->f) != 0 && !bad) {
        bad = 1;
        saved = errno;
    }
    af->f = NULL;
    if (bad) {
        remove(af->tmp);
        snprintf(err, errcap, "cannot write '%s': %s", af->path, strerror(saved));
        return -1;
    }
    if (rename(af->tmp, af->path) != 0) {
        saved = errno;
        remove(af->tmp);
        snprintf(err, errcap, "cannot replace '%s': %s", af->path, strerror(saved));
        return -1;
    }
    return 0;
}

void lsqt_atomic_abort(lsqt_atomic_file *af)
{
    if (af->f) fclose(af->f);
    af->f = NULL;
    if (af->tmp[0]) remove(af->tmp);
}

double lsqt_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int lsqt_file_exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}
