/* Small host utilities: whole-file reading, CRC-32, output files, clocks. */
#ifndef LSQT_UTIL_H
#define LSQT_UTIL_H

#include <signal.h>
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
/* The same for text a user gives (an LSQT input, a --wi-file): at most max bytes, else an
 * error that says so (a device or an endless pipe read by mistake is refused early). */
char *lsqt_read_text(const char *path, size_t max, size_t *len, char *err, size_t errcap);
#define LSQT_INPUT_MAX ((size_t)64 << 20)

uint32_t lsqt_crc32(uint32_t crc, const void *data, size_t len);

/* Of the n candidates, the one the first len characters of WORD were most likely meant
 * to be (case-insensitive edit distance, a swap of neighbours counting one): at most one
 * edit away for a word of up to 4 characters, two up to 8, three beyond; NULL when none
 * is that close or two different ones are equally close. */
const char *lsqt_closest(const char *word, size_t len, const char *const *cand, int n);
/* "0.1.0 (git 4fbc73c1a2b3)": the version and the commit it was built from ("+changes"
 * after it for a work tree with uncommitted changes, "git unknown" outside a checkout). */
const char *lsqt_version(void);

#define LSQT_PATH_CAP 4096

/* Every output file (RAW, LSS, JSON, and what later tools write) goes through these, so
 * one set of rules holds for all of them:
 * - "-" is stdout;
 * - a new path or an existing regular file is replaced atomically (temporary file beside
 *   it, fsync, rename): a crash or a full disk never leaves a half-written file;
 * - a symlink keeps the link: the file it points to is replaced atomically, the
 *   temporary in that file's folder;
 * - an existing character device, FIFO or socket is written in place, never renamed over
 *   (so -o /dev/null discards, and a FIFO feeds its reader);
 * - a directory or a block device is refused.
 * Errors name the file and the reason. */
enum { LSQT_OUT_REPLACE = 1, LSQT_OUT_IN_PLACE, LSQT_OUT_STDOUT };

typedef struct lsqt_out {
    FILE *f;                   /* writes through o itself: o must stay where it is until commit */
    int fd;                    /* f's descriptor (-1 for stdout) */
    int werr;                  /* the first write's errno (0: none), so commit names the cause */
    int how;                   /* LSQT_OUT_* */
    char path[LSQT_PATH_CAP];  /* as given (for messages) */
    char target[LSQT_PATH_CAP]; /* the file written: symlinks followed */
    char tmp[LSQT_PATH_CAP + 64]; /* LSQT_OUT_REPLACE: the temporary beside target */
} lsqt_out;

/* Can PATH be written? Checked before a long run, so no work is lost at the end: it
 * creates and removes the temporary file, or checks write access to a device. */
int lsqt_out_check(const char *path, char *err, size_t errcap);
int lsqt_out_open(lsqt_out *o, const char *path, char *err, size_t errcap);
/* A FIFO is opened once a process reads it (a note after a second of waiting); while
 * *flag is 0. A program that stops on a signal passes its flag, so the signal ends the
 * wait (the output fails, the others are written). */
void lsqt_out_cancel_flag(volatile sig_atomic_t *flag);
/* Flushes and closes (renames into place when replacing); on any write error, including
 * an earlier one, removes the temporary and fails with the reason (ENOSPC, EPIPE, ...). */
int lsqt_out_commit(lsqt_out *o, char *err, size_t errcap);
void lsqt_out_abort(lsqt_out *o);
/* Outputs published together (one run's RAW files, one per band, and its JSON): each is
 * written and closed as by lsqt_out_commit but left in its temporary (lsqt_out_hold adds
 * it to SET), and lsqt_out_set_publish renames them all at the end, so that a failure or
 * a kill while writing them leaves the previous files, not a mix of old and new. An
 * output written in place (a device, a FIFO, stdout) is finished by lsqt_out_hold. */
typedef struct lsqt_out_set {
    int n, cap;
    char **tmp, **target, **path; /* heap strings, n of each (path: as given) */
} lsqt_out_set;
/* Returns 0, or -1 with err filled (the temporary removed, as lsqt_out_commit). */
int lsqt_out_hold(lsqt_out *o, lsqt_out_set *set, char *err, size_t errcap);
/* Renames every held temporary over its target and makes the renames durable (each
 * folder synced once). Returns the number that failed: each is printed to stderr as
 * "PROG: error: cannot write ...", and FAILED (unless NULL) is called with its path as
 * given. The set is empty afterwards. */
int lsqt_out_set_publish(lsqt_out_set *set, const char *prog, void (*failed)(void *ctx, const char *path), void *ctx);
/* Removes every held temporary (nothing is published); the set is empty afterwards. */
void lsqt_out_set_abort(lsqt_out_set *set);
/* Removes the regular file that writing PATH would replace (symlinks followed; a device,
 * FIFO or "-" holds nothing to remove). Returns 1 when one was removed, else 0. */
int lsqt_out_remove_old(const char *path);
/* For a writer that opens the file itself by name (OpenImageIO): the same rules, through
 * a temporary beside PATH that ends as PATH does (so the format follows the extension).
 * Write to lsqt_out_name(o), then lsqt_out_commit_named (fsync, rename over PATH) or
 * lsqt_out_abort. A device or FIFO is written in place; "-" is refused. */
int lsqt_out_open_named(lsqt_out *o, const char *path, char *err, size_t errcap);
const char *lsqt_out_name(const lsqt_out *o);
int lsqt_out_commit_named(lsqt_out *o, char *err, size_t errcap);

double lsqt_now(void); /* monotonic seconds */

/* What is at PATH, symlinks followed: LSQT_PATH_*; *what names it ("FIFO", ...). */
enum { LSQT_PATH_MISSING, LSQT_PATH_REGULAR, LSQT_PATH_DIRECTORY, LSQT_PATH_SPECIAL };
int lsqt_path_type(const char *path, const char **what);
/* The folder PATH is in, into dir: its part up to the last '/' (kept), or "." when it has
 * none. Returns dir. */
char *lsqt_path_folder(const char *path, char *dir, size_t cap);

/* Would writes to A and B land on the same regular file (or both on stdout, "-")? Devices
 * and FIFOs may be shared (two outputs to /dev/null are fine). */
int lsqt_same_file(const char *a, const char *b);
/* What lsqt_same_file compares, as a string (heap): equal strings name one file. An
 * existing regular file is its device and inode, a path to be made its absolute name, and
 * "-" stdout; NULL for an existing device, FIFO or socket (several outputs may share one)
 * or out of memory. Sorting these finds the clashes among thousands of paths. */
char *lsqt_file_identity(const char *path);

/* A run owns the state it writes: an advisory lock (fcntl, whole file) on "STATE.lock"
 * beside the state file (symlinks followed), taken before the state is read and held to
 * the end. Exclusive for the file a run, a shard or a merge writes; shared for the state
 * shards read (they run together; a plain run or a merge on it waits for them). fcntl
 * locks are the ones NFS carries (NFSv4, or v3 with its lock manager), so runs on two
 * cluster nodes exclude each other too; where the file system has no locks, take says
 * so (returns 2) and the caller goes on unprotected. A lock dies with its process (even
 * by SIGKILL); the holder removes the lock file when it is the last one. "-", devices and
 * FIFOs hold no state and take no lock. */
typedef struct lsqt_lock {
    int fd; /* -1: none held */
    int exclusive;
    char path[LSQT_PATH_CAP + 8];
} lsqt_lock;
/* 0: held (or nothing to lock); 1: another process holds it (err names it, and how to go
 * on); 2: the file system cannot lock (err says so); -1: another error (err). */
int lsqt_lock_take(lsqt_lock *l, const char *state, int exclusive, char *err, size_t errcap);
void lsqt_lock_release(lsqt_lock *l);

/* "PROG: error: MSG" on stderr; returns code (the exit status of the subcommands). */
int lsqt_prog_error(const char *prog, int code, const char *msg);

#ifdef __cplusplus
}
#endif
#endif
