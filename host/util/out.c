/* The output file API of util.h: check, open, commit, abort; named outputs (a library
 * writes the file by name). How a path is written is out_plan.c's. */
#include "util_internal.h"

#include <errno.h>
#include <fcntl.h>
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

int lsqt_out_commit(lsqt_out *o, char *err, size_t errcap)
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
    if (o->how == LSQT_OUT_IN_PLACE) return 0;
    return lsqt_out_replace_target(o, err, errcap);
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
