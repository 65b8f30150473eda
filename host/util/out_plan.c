/* Output files: one set of rules for every file lsqt-cl and its companions write.
 * "-" is stdout. A new path or an existing regular file is replaced atomically (a
 * temporary beside it, fsync, rename), so a crash or a full disk leaves the old file
 * whole. A symlink keeps the link: the file it points to is replaced that way, with the
 * temporary in that file's folder. A character device, FIFO or socket is written in
 * place and never renamed over (-o /dev/null throws the output away; a FIFO feeds its
 * reader). A directory or a block device is refused.
 * This file decides how a path is written; out.c writes it. */
#include "util_internal.h"

#include <errno.h>
#include <string.h>
#include <sys/stat.h>

/* "cannot write 'PATH'" plus the link's target when PATH is a link, then the reason. */
void lsqt_out_error(const lsqt_out *o, const char *reason, char *err, size_t errcap)
{
    if (strcmp(o->path, o->target) != 0 && o->target[0])
        snprintf(err, errcap, "cannot write '%s' (a link to '%s'): %s", o->path, o->target, reason);
    else
        snprintf(err, errcap, "cannot write '%s': %s", o->path, reason);
}

/* Decides how PATH is written; *old is its stat when it exists (exists = 1). */
int lsqt_out_plan(lsqt_out *o, const char *path, struct stat *old, int *exists, char *err, size_t errcap)
{
    memset(o, 0, sizeof *o);
    *exists = 0;
    if (!*path) {
        snprintf(err, errcap, "an output file name is empty");
        return -1;
    }
    if (strlen(path) >= sizeof o->path) {
        snprintf(err, errcap, "cannot write '%.200s...': path too long", path);
        return -1;
    }
    strcpy(o->path, path);
    if (strcmp(path, "-") == 0) {
        o->how = LSQT_OUT_STDOUT;
        strcpy(o->target, "-");
        return 0;
    }
    if (lsqt_resolve_links(path, o->target, sizeof o->target, err, errcap)) return -1;
    o->how = LSQT_OUT_REPLACE;
    if (stat(o->target, old) != 0) {
        if (errno == ENOENT) return 0;
        lsqt_out_error(o, strerror(errno), err, errcap);
        return -1;
    }
    *exists = 1;
    if (S_ISREG(old->st_mode)) return 0;
    if (S_ISCHR(old->st_mode) || S_ISFIFO(old->st_mode) || S_ISSOCK(old->st_mode)) {
        o->how = LSQT_OUT_IN_PLACE;
        return 0;
    }
    char why[128];
    snprintf(why, sizeof why, "it is a %s%s", lsqt_file_kind(old->st_mode),
             S_ISBLK(old->st_mode) ? " (lsqt-cl never writes over one)" : "");
    lsqt_out_error(o, why, err, errcap);
    return -1;
}
