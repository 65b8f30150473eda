/* A run's ownership of its LSS: an fcntl lock on NAME.lss.lock. */
#include "util_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The holder of a lock that conflicts with ours on fd, in words: an exclusive holder
 * wrote its process id and host into the file (F_GETLK's pid means nothing across NFS). */
static void lock_holder(int fd, const char *lock_path, char *out, size_t cap)
{
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    const int known = fcntl(fd, F_GETLK, &fl) == 0 && fl.l_type != F_UNLCK;
    char text[256] = "";
    int in = open(lock_path, O_RDONLY | O_CLOEXEC);
    if (in >= 0) {
        ssize_t n = read(in, text, sizeof text - 1);
        text[n > 0 ? n : 0] = '\0';
        close(in);
    }
    long pid = 0;
    char host[128] = "";
    if (known && fl.l_type == F_WRLCK && sscanf(text, "%ld %127s", &pid, host) == 2 && pid > 0)
        snprintf(out, cap, "process %ld on %s", pid, host);
    else if (known && fl.l_pid > 0)
        snprintf(out, cap, "process %ld%s", (long)fl.l_pid, fl.l_type == F_RDLCK ? ", a shard reading it" : "");
    else
        snprintf(out, cap, "another process");
}

int lsqt_lock_take(lsqt_lock *l, const char *state, int exclusive, char *err, size_t errcap)
{
    memset(l, 0, sizeof *l);
    l->fd = -1;
    if (strcmp(state, "-") == 0) return 0;
    char target[LSQT_PATH_CAP];
    if (lsqt_resolve_links(state, target, sizeof target, err, errcap)) return -1;
    struct stat sb;
    if (stat(target, &sb) == 0 && !S_ISREG(sb.st_mode)) return 0;
    if ((size_t)snprintf(l->path, sizeof l->path, "%s.lock", target) >= sizeof l->path) {
        snprintf(err, errcap, "cannot lock '%.200s...': path too long", state);
        return -1;
    }
    for (int tries = 0; tries < 100; tries++) {
        int fd = open(l->path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
        if (fd < 0) {
            snprintf(err, errcap, "cannot lock '%s': cannot create '%s': %s", state, l->path, strerror(errno));
            return -1;
        }
        struct flock fl;
        memset(&fl, 0, sizeof fl);
        fl.l_type = (short)(exclusive ? F_WRLCK : F_RDLCK);
        fl.l_whence = SEEK_SET;
        if (fcntl(fd, F_SETLK, &fl) != 0) {
            const int e = errno;
            if (e == EACCES || e == EAGAIN) {
                char who[300];
                lock_holder(fd, l->path, who, sizeof who);
                snprintf(err, errcap,
                         "'%s' is in use by another run (%s; lock '%s'): let it finish first",
                         state, who, l->path);
                close(fd);
                return 1;
            }
            close(fd);
            snprintf(err, errcap, "cannot lock '%s' (%s): runs on it are not protected from each other", state,
                     strerror(e));
            return e == ENOLCK || e == EOPNOTSUPP || e == ENOSYS ? 2 : -1;
        }
        /* The holder before us may have removed the file between our open and our lock:
         * then the lock is on a file nobody else will open; take the one now there. */
        struct stat a, b;
        if (fstat(fd, &a) == 0 && stat(l->path, &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino) {
            l->fd = fd;
            l->exclusive = exclusive;
            if (exclusive && ftruncate(fd, 0) == 0) {
                char host[128] = "?", line[200];
                gethostname(host, sizeof host - 1);
                host[sizeof host - 1] = '\0';
                int n = snprintf(line, sizeof line, "%ld %s\n", (long)getpid(), host);
                if (n > 0 && write(fd, line, (size_t)n) < 0) { /* the lock holds without it */
                }
            }
            return 0;
        }
        close(fd);
    }
    snprintf(err, errcap, "cannot lock '%s': its lock file '%s' keeps changing", state, l->path);
    return -1;
}

void lsqt_lock_release(lsqt_lock *l)
{
    if (l->fd < 0) return;
    /* The last holder removes the file: exclusive, or a shared lock that can become one. */
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    if (l->exclusive || fcntl(l->fd, F_SETLK, &fl) == 0) unlink(l->path);
    close(l->fd);
    l->fd = -1;
}
