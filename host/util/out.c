/* The output file API of util.h: check, open, commit, abort; named outputs (a library
 * writes the file by name). How a path is written is out_plan.c's. */
#include "util_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int lsqt_out_check(const char *path, char *err, size_t errcap)
{
    lsqt_out o;
    struct stat old;
    int exists = 0;
    if (lsqt_out_plan(&o, path, &old, &exists, err, errcap)) return -1;
    if (o.how == LSQT_OUT_STDOUT) return 0;
    if (o.how == LSQT_OUT_IN_PLACE) {
        if (access(o.target, W_OK) == 0) return 0;
        lsqt_out_error(&o, strerror(errno), err, errcap);
        return -1;
    }
    /* Creating the temporary is the only honest test (permissions, read-only mounts). */
    int fd = lsqt_out_make_temp(&o, &old, exists, "", err, errcap);
    if (fd < 0) return -1;
    close(fd);
    unlink(o.tmp);
    return 0;
}

int lsqt_out_open(lsqt_out *o, const char *path, char *err, size_t errcap)
{
    struct stat old;
    int exists = 0;
    if (lsqt_out_plan(o, path, &old, &exists, err, errcap)) return -1;
    o->fd = -1;
    if (o->how == LSQT_OUT_STDOUT) {
        o->f = stdout;
        return 0;
    }
    int fd;
    if (o->how == LSQT_OUT_REPLACE) fd = lsqt_out_make_temp(o, &old, exists, "", err, errcap);
    else if (S_ISSOCK(old.st_mode)) fd = lsqt_out_open_socket(o, err, errcap);
    else if (S_ISFIFO(old.st_mode)) fd = lsqt_out_open_fifo(o, err, errcap);
    else {
        fd = open(o->target, O_WRONLY | O_NOCTTY | O_CLOEXEC);
        if (fd < 0) lsqt_out_error(o, strerror(errno), err, errcap);
    }
    if (fd < 0) return -1;
    o->f = lsqt_out_stream(o, fd);
    if (!o->f) {
        lsqt_out_error(o, strerror(errno), err, errcap);
        close(fd);
        if (o->how == LSQT_OUT_REPLACE) unlink(o->tmp);
        return -1;
    }
    return 0;
}

/* Flushes, syncs and closes o; a replaced output keeps its temporary. Returns 0, or -1
 * with err filled and the temporary removed. */
static int out_finish(lsqt_out *o, char *err, size_t errcap)
{
    errno = 0;
    int bad = fflush(o->f) != 0 || ferror(o->f);
    if (!bad && o->how == LSQT_OUT_REPLACE && fsync(o->fd) != 0) bad = 1;
    int saved = o->werr ? o->werr : errno ? errno : EIO;
    if (o->how == LSQT_OUT_STDOUT) {
        o->f = NULL;
        if (bad) snprintf(err, errcap, "cannot write to stdout: %s", strerror(saved));
        return bad ? -1 : 0;
    }
    if (fclose(o->f) != 0 && !bad) {
        bad = 1;
        saved = o->werr ? o->werr : errno;
    }
    o->f = NULL;
    if (bad) {
        if (o->how == LSQT_OUT_REPLACE) unlink(o->tmp);
        lsqt_out_error(o, strerror(saved), err, errcap);
        return -1;
    }
    return 0;
}

int lsqt_out_commit(lsqt_out *o, char *err, size_t errcap)
{
    const int how = o->how;
    if (out_finish(o, err, errcap)) return -1;
    return how == LSQT_OUT_REPLACE ? lsqt_out_replace_target(o, err, errcap) : 0;
}

static char *dup_string(const char *s)
{
    char *d = malloc(strlen(s) + 1);
    if (d) strcpy(d, s);
    return d;
}

int lsqt_out_hold(lsqt_out *o, lsqt_out_set *set, char *err, size_t errcap)
{
    const int how = o->how;
    if (out_finish(o, err, errcap)) return -1;
    if (how != LSQT_OUT_REPLACE) return 0;
    if (set->n == set->cap) {
        int nc = set->cap ? 2 * set->cap : 16;
        char **t = realloc(set->tmp, (size_t)nc * sizeof *t);
        if (t) set->tmp = t;
        char **g = t ? realloc(set->target, (size_t)nc * sizeof *g) : NULL;
        if (g) set->target = g;
        char **p = g ? realloc(set->path, (size_t)nc * sizeof *p) : NULL;
        if (p) set->path = p, set->cap = nc;
    }
    char *tmp = set->n < set->cap ? dup_string(o->tmp) : NULL, *target = tmp ? dup_string(o->target) : NULL;
    char *path = target ? dup_string(o->path) : NULL;
    if (!path) {
        free(tmp), free(target);
        unlink(o->tmp);
        lsqt_out_error(o, "out of memory", err, errcap);
        return -1;
    }
    set->tmp[set->n] = tmp, set->target[set->n] = target, set->path[set->n] = path, set->n++;
    return 0;
}

static void set_clear(lsqt_out_set *set, int unlink_temps)
{
    for (int i = 0; i < set->n; i++) {
        if (unlink_temps && set->tmp[i]) unlink(set->tmp[i]);
        free(set->tmp[i]);
        free(set->target[i]);
        free(set->path[i]);
    }
    free(set->tmp);
    free(set->target);
    free(set->path);
    memset(set, 0, sizeof *set);
}

int lsqt_out_set_publish(lsqt_out_set *set, const char *prog, void (*failed)(void *ctx, const char *path), void *ctx)
{
    int n_failed = 0;
    for (int i = 0; i < set->n; i++) {
        if (rename(set->tmp[i], set->target[i]) == 0) {
            free(set->tmp[i]);
            set->tmp[i] = NULL;
            continue;
        }
        fprintf(stderr, "%s: error: cannot write '%s': cannot rename the temporary over it: %s\n", prog,
                set->target[i], strerror(errno));
        if (failed) failed(ctx, set->path[i]);
        n_failed++;
    }
    /* each folder once: a run's RAW files are usually all in one */
    char last[LSQT_PATH_CAP] = "";
    for (int i = 0; i < set->n; i++) {
        char dir[LSQT_PATH_CAP];
        if (strcmp(lsqt_path_folder(set->target[i], dir, sizeof dir), last) == 0) continue;
        snprintf(last, sizeof last, "%s", dir);
        lsqt_sync_folder(set->target[i]);
    }
    set_clear(set, 1);
    return n_failed;
}

void lsqt_out_set_abort(lsqt_out_set *set) { set_clear(set, 1); }

int lsqt_out_remove_old(const char *path)
{
    lsqt_out o;
    struct stat old;
    int exists = 0;
    char err[64];
    return lsqt_out_plan(&o, path, &old, &exists, err, sizeof err) == 0 && exists && o.how == LSQT_OUT_REPLACE &&
           S_ISREG(old.st_mode) && unlink(o.target) == 0;
}

int lsqt_out_open_named(lsqt_out *o, const char *path, char *err, size_t errcap)
{
    struct stat old;
    int exists = 0;
    if (lsqt_out_plan(o, path, &old, &exists, err, errcap)) return -1;
    o->fd = -1;
    o->f = NULL;
    if (o->how == LSQT_OUT_STDOUT) {
        snprintf(err, errcap, "cannot write to stdout ('-') here: give a file name");
        return -1;
    }
    if (o->how == LSQT_OUT_IN_PLACE) return 0;
    const char *base = strrchr(o->target, '/'), *dot = strrchr(base ? base : o->target, '.');
    int fd = lsqt_out_make_temp(o, &old, exists, dot ? dot : "", err, errcap);
    if (fd < 0) return -1;
    close(fd);
    return 0;
}

const char *lsqt_out_name(const lsqt_out *o) { return o->how == LSQT_OUT_REPLACE ? o->tmp : o->target; }

int lsqt_out_commit_named(lsqt_out *o, char *err, size_t errcap)
{
    if (o->how != LSQT_OUT_REPLACE) return 0;
    int fd = open(o->tmp, O_RDONLY | O_CLOEXEC);
    if (fd < 0 || fsync(fd) != 0) {
        const int e = errno;
        if (fd >= 0) close(fd);
        unlink(o->tmp);
        lsqt_out_error(o, strerror(e), err, errcap);
        return -1;
    }
    close(fd);
    return lsqt_out_replace_target(o, err, errcap);
}

void lsqt_out_abort(lsqt_out *o)
{
    if (!o->f && o->how == LSQT_OUT_REPLACE && o->tmp[0]) { /* a named output */
        unlink(o->tmp);
        o->tmp[0] = '\0';
        return;
    }
    if (o->f && o->how != LSQT_OUT_STDOUT) fclose(o->f);
    if (o->f && o->how == LSQT_OUT_REPLACE && o->tmp[0]) unlink(o->tmp);
    o->f = NULL;
}
