/* Small host utilities: whole-file reading, CRC-32, atomic file replacement, clocks. */
#ifndef LSQT_UTIL_H
#define LSQT_UTIL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define LSQT_PI 3.14159265358979323846

#ifdef __cplusplus
extern "C" {
#endif

/* Reads a whole file ("-" is stdin) into a NUL-terminated heap buffer. Returns NULL and
 * fills err on failure. */
char *lsqt_read_file(const char *path, size_t *len, char *err, size_t errcap);

uint32_t lsqt_crc32(uint32_t crc, const void *data, size_t len);

/* Atomic replacement: write to PATH.tmp.PID, then fsync and rename over PATH, so a crash
 * or a full disk never leaves a half-written PATH. */
typedef struct lsqt_atomic_file {
    FILE *f;
    char path[4096];
    char tmp[4200];
} lsqt_atomic_file;

int lsqt_atomic_open(lsqt_atomic_file *af, const char *path, char *err, size_t errcap);
/* Closes and renames; on any earlier write error removes the temporary and fails. */
int lsqt_atomic_commit(lsqt_atomic_file *af, char *err, size_t errcap);
void lsqt_atomic_abort(lsqt_atomic_file *af);

double lsqt_now(void); /* monotonic seconds */

int lsqt_file_exists(const char *path);

#ifdef __cplusplus
}
#endif
#endif
