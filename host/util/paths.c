/* realpath() is an XSI interface. */
#define _GNU_SOURCE

/* What a path is, where its links lead, and whether two paths name one file. */
#include "util_internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The kind of file a stat's mode names, in words. */
const char *lsqt_file_kind(mode_t m)
{
    if (S_ISREG(m)) return "regular file";
    if (S_ISDIR(m)) return "directory";
    if (S_ISCHR(m)) return "character device";
    if (S_ISBLK(m)) return "block device";
    if (S_ISFIFO(m)) return "FIFO";
    if (S_ISSOCK(m)) return "socket";
    return "special file";
}

/* PATH with its symlinks followed link by link; a dangling link names the file to make. */
int lsqt_resolve_links(const char *path, char *out, size_t cap, char *err, size_t errcap)
{
    char cur[LSQT_PATH_CAP], link[LSQT_PATH_CAP], next[LSQT_PATH_CAP];
    snprintf(cur, sizeof cur, "%s", path);
    for (int hops = 0; hops < 40; hops++) {
        struct stat sb;
        if (lstat(cur, &sb) != 0 || !S_ISLNK(sb.st_mode)) {
            if ((size_t)snprintf(out, cap, "%s", cur) >= cap) break;
            return 0;
        }
        ssize_t n = readlink(cur, link, sizeof link - 1);
        if (n < 0) {
            snprintf(err, errcap, "cannot write '%s': cannot read the link '%s': %s", path, cur, strerror(errno));
            return -1;
        }
        link[n] = '\0';
        const char *slash = strrchr(cur, '/');
        size_t w = link[0] == '/' || !slash
                       ? (size_t)snprintf(next, sizeof next, "%s", link)
                       : (size_t)snprintf(next, sizeof next, "%.*s/%s", (int)(slash - cur), cur, link);
        if (w >= sizeof next) break;
        memcpy(cur, next, w + 1);
        if (hops == 39) {
            snprintf(err, errcap, "cannot write '%s': too many levels of symbolic links", path);
            return -1;
        }
    }
    snprintf(err, errcap, "cannot write '%.200s...': path too long", path);
    return -1;
}

int lsqt_path_type(const char *path, const char **what)
{
    struct stat sb;
    *what = "nothing";
    if (stat(path, &sb) != 0) return LSQT_PATH_MISSING;
    *what = lsqt_file_kind(sb.st_mode);
    return S_ISREG(sb.st_mode) ? LSQT_PATH_REGULAR : S_ISDIR(sb.st_mode) ? LSQT_PATH_DIRECTORY : LSQT_PATH_SPECIAL;
}

char *lsqt_path_folder(const char *path, char *dir, size_t cap)
{
    const char *slash = strrchr(path, '/');
    snprintf(dir, cap, "%.*s", slash ? (int)(slash - path) + 1 : 1, slash ? path : ".");
    return dir;
}

/* The folder of PATH made absolute (realpath) with PATH's last name after it. */
static int absolute_name(const char *path, char *out, size_t cap)
{
    char dir[LSQT_PATH_CAP], *real;
    const char *slash = strrchr(path, '/');
    if (!(real = realpath(lsqt_path_folder(path, dir, sizeof dir), NULL))) return -1;
    int w = snprintf(out, cap, "%s/%s", real, slash ? slash + 1 : path);
    free(real);
    return w > 0 && (size_t)w < cap ? 0 : -1;
}

char *lsqt_file_identity(const char *path)
{
    if (strcmp(path, "-") == 0) return strdup("-");
    char t[LSQT_PATH_CAP], e[64], full[2 * LSQT_PATH_CAP + 8];
    if (lsqt_resolve_links(path, t, sizeof t, e, sizeof e)) {
        snprintf(full, sizeof full, "?%s", path); /* a link that cannot be followed: its name */
        return strdup(full);
    }
    struct stat sb;
    if (stat(t, &sb) == 0) {
        if (!S_ISREG(sb.st_mode)) return NULL; /* a device or FIFO may take several outputs */
        snprintf(full, sizeof full, "i%llu:%llu", (unsigned long long)sb.st_dev, (unsigned long long)sb.st_ino);
        return strdup(full);
    }
    full[0] = 'p';
    if (absolute_name(t, full + 1, sizeof full - 1)) snprintf(full, sizeof full, "?%s", t);
    return strdup(full);
}

int lsqt_same_file(const char *a, const char *b)
{
    char *ia = lsqt_file_identity(a), *ib = lsqt_file_identity(b);
    int same = ia && ib && strcmp(ia, ib) == 0;
    free(ia);
    free(ib);
    return same;
}
