/* Temporaries beside an output's target: their names, the stale ones of killed processes,
 * and the rename over the target. */
#include "util_internal.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* This machine's name as temporaries carry it (no dots: they separate the fields). */
static void host_tag(char *out, size_t cap)
{
    if (gethostname(out, cap - 1) != 0 || !out[0]) snprintf(out, cap, "host");
    out[cap - 1] = '\0';
    for (char *p = out; *p; p++)
        if (*p == '.' || *p == '/') *p = '_';
}

/* Removes the temporaries of target ("TARGET.tmp.HOST.PID.N") that a process of this
 * machine left when it was killed while writing: its process is gone. Another machine's
 * (a shared folder) are left alone: their process cannot be asked. */
static void remove_stale_temps(const char *target, const char *host)
{
    const char *slash = strrchr(target, '/');
    char dir[LSQT_PATH_CAP], prefix[LSQT_PATH_CAP + 200];
    lsqt_path_folder(target, dir, sizeof dir);
    int n = snprintf(prefix, sizeof prefix, "%s.tmp.%s.", slash ? slash + 1 : target, host);
    if (n <= 0 || (size_t)n >= sizeof prefix) return;
    DIR *d = opendir(dir);
    if (!d) return;
    for (struct dirent *e; (e = readdir(d));) {
        if (strncmp(e->d_name, prefix, (size_t)n) != 0) continue;
        char *end;
        long pid = strtol(e->d_name + n, &end, 10);
        if (pid <= 0 || *end != '.' || pid == (long)getpid()) continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;
        char path[2 * LSQT_PATH_CAP];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        unlink(path);
    }
    closedir(d);
}

/* Creates the temporary beside o->target (mode as the old file's, else 0666 & ~umask),
 * after removing those that killed processes of this machine left there. */
int lsqt_out_make_temp(lsqt_out *o, const struct stat *old, int exists, const char *suffix, char *err, size_t errcap)
{
    static unsigned serial;
    char host[64];
    host_tag(host, sizeof host);
    remove_stale_temps(o->target, host);
    for (int tries = 0; tries < 1000; tries++) {
        if ((size_t)snprintf(o->tmp, sizeof o->tmp, "%s.tmp.%s.%ld.%u%s", o->target, host, (long)getpid(), serial++,
                             suffix) >= sizeof o->tmp) {
            lsqt_out_error(o, "path too long", err, errcap);
            return -1;
        }
        int fd = open(o->tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            if (exists) (void)fchmod(fd, old->st_mode & 07777);
            return fd;
        }
        if (errno != EEXIST) {
            char why[512];
            snprintf(why, sizeof why, "cannot create a file beside it: %s", strerror(errno));
            o->tmp[0] = '\0';
            lsqt_out_error(o, why, err, errcap);
            return -1;
        }
    }
    o->tmp[0] = '\0';
    lsqt_out_error(o, "cannot find a free temporary name beside it", err, errcap);
    return -1;
}

/* Renames the finished temporary over the target, durably. */
int lsqt_out_replace_target(lsqt_out *o, char *err, size_t errcap)
{
    int saved;
    if (rename(o->tmp, o->target) != 0) {
        saved = errno;
        unlink(o->tmp);
        char why[512];
        snprintf(why, sizeof why, "cannot rename the temporary over it: %s", strerror(saved));
        lsqt_out_error(o, why, err, errcap);
        return -1;
    }
    o->tmp[0] = '\0';
    lsqt_sync_folder(o->target);
    return 0;
}

void lsqt_sync_folder(const char *path)
{
    char dir[LSQT_PATH_CAP];
    int dfd = open(lsqt_path_folder(path, dir, sizeof dir), O_RDONLY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)fsync(dfd);
        close(dfd);
    }
}
