/* realpath() is an XSI interface; fopencookie a GNU one. */
#define _GNU_SOURCE

#include "lsqt/util.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

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

/* CRC-32 (IEEE, reflected 0xEDB88320), four bytes a step through four tables ("slicing
 * by 4"): an LSS is megabytes of histograms, and the bitwise form took 7 % of a short run. */
static uint32_t crc_tab[4][256];

static void crc_tables(void)
{
    for (uint32_t b = 0; b < 256; b++) {
        uint32_t c = b;
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
        crc_tab[0][b] = c;
    }
    for (int t = 1; t < 4; t++)
        for (int b = 0; b < 256; b++) crc_tab[t][b] = (crc_tab[t - 1][b] >> 8) ^ crc_tab[0][crc_tab[t - 1][b] & 0xFFu];
}

uint32_t lsqt_crc32(uint32_t crc, const void *data, size_t len)
{
    if (crc_tab[0][1] == 0) crc_tables(); /* the host calls this from one thread */
    const unsigned char *p = data;
    crc = ~crc;
    for (; len >= 4; len -= 4, p += 4) {
        crc ^= (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
        crc = crc_tab[3][crc & 0xFFu] ^ crc_tab[2][(crc >> 8) & 0xFFu] ^ crc_tab[1][(crc >> 16) & 0xFFu] ^
              crc_tab[0][crc >> 24];
    }
    for (; len > 0; len--, p++) crc = (crc >> 8) ^ crc_tab[0][(crc ^ *p) & 0xFFu];
    return ~crc;
}

/* ---- Output files: one set of rules for every file lsqt-cl and its companions write ----
 * "-" is stdout. A new path or an existing regular file is replaced atomically (a
 * temporary beside it, fsync, rename), so a crash or a full disk leaves the old file
 * whole. A symlink keeps the link: the file it points to is replaced that way, with the
 * temporary in that file's folder. A character device, FIFO or socket is written in
 * place and never renamed over (-o /dev/null throws the output away; a FIFO feeds its
 * reader). A directory or a block device is refused. */

static const char *kind_name(mode_t m)
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
static int resolve_links(const char *path, char *out, size_t cap, char *err, size_t errcap)
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

/* "cannot write 'PATH'" plus the link's target when PATH is a link, then the reason. */
static void out_error(const lsqt_out *o, const char *reason, char *err, size_t errcap)
{
    if (strcmp(o->path, o->target) != 0 && o->target[0])
        snprintf(err, errcap, "cannot write '%s' (a link to '%s'): %s", o->path, o->target, reason);
    else
        snprintf(err, errcap, "cannot write '%s': %s", o->path, reason);
}

/* Decides how PATH is written; *old is its stat when it exists (exists = 1). */
static int out_plan(lsqt_out *o, const char *path, struct stat *old, int *exists, char *err, size_t errcap)
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
    if (resolve_links(path, o->target, sizeof o->target, err, errcap)) return -1;
    o->how = LSQT_OUT_REPLACE;
    if (stat(o->target, old) != 0) {
        if (errno == ENOENT) return 0;
        out_error(o, strerror(errno), err, errcap);
        return -1;
    }
    *exists = 1;
    if (S_ISREG(old->st_mode)) return 0;
    if (S_ISCHR(old->st_mode) || S_ISFIFO(old->st_mode) || S_ISSOCK(old->st_mode)) {
        o->how = LSQT_OUT_IN_PLACE;
        return 0;
    }
    char why[128];
    snprintf(why, sizeof why, "it is a %s%s", kind_name(old->st_mode),
             S_ISBLK(old->st_mode) ? " (lsqt-cl never writes over one)" : "");
    out_error(o, why, err, errcap);
    return -1;
}

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
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - target) + 1 : 1, slash ? target : ".");
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
static int make_temp(lsqt_out *o, const struct stat *old, int exists, const char *suffix, char *err, size_t errcap)
{
    static unsigned serial;
    char host[64];
    host_tag(host, sizeof host);
    remove_stale_temps(o->target, host);
    for (int tries = 0; tries < 1000; tries++) {
        if ((size_t)snprintf(o->tmp, sizeof o->tmp, "%s.tmp.%s.%ld.%u%s", o->target, host, (long)getpid(), serial++,
                             suffix) >= sizeof o->tmp) {
            out_error(o, "path too long", err, errcap);
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
            out_error(o, why, err, errcap);
            return -1;
        }
    }
    o->tmp[0] = '\0';
    out_error(o, "cannot find a free temporary name beside it", err, errcap);
    return -1;
}

/* A connected stream to the Unix socket at o->target. */
static int open_socket(lsqt_out *o, char *err, size_t errcap)
{
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    if (strlen(o->target) >= sizeof sa.sun_path) {
        out_error(o, "socket path too long", err, errcap);
        return -1;
    }
    strcpy(sa.sun_path, o->target);
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    if (fd >= 0 && connect(fd, (struct sockaddr *)&sa, sizeof sa) == 0) return fd;
    char why[512];
    snprintf(why, sizeof why, "cannot connect to the socket: %s", strerror(errno));
    if (fd >= 0) close(fd);
    out_error(o, why, err, errcap);
    return -1;
}

static volatile sig_atomic_t *g_cancel; /* lsqt_out_cancel_flag */

void lsqt_out_cancel_flag(volatile sig_atomic_t *flag) { g_cancel = flag; }

/* A FIFO for writing once a reader has it open (O_NONBLOCK fails with ENXIO until then),
 * then blocking as any output. */
static int open_fifo(lsqt_out *o, char *err, size_t errcap)
{
    const double t0 = lsqt_now();
    int said = 0;
    for (;;) {
        int fd = open(o->target, O_WRONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
        if (fd >= 0) {
            int fl = fcntl(fd, F_GETFL);
            if (fl >= 0) (void)fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
            return fd;
        }
        if (errno != ENXIO && errno != EINTR) {
            out_error(o, strerror(errno), err, errcap);
            return -1;
        }
        if (g_cancel && *g_cancel) {
            out_error(o, "no process read the FIFO before the interrupt", err, errcap);
            return -1;
        }
        if (!said && lsqt_now() - t0 > 1.0) {
            fprintf(stderr, "note: waiting for a process to read the FIFO '%s'%s\n", o->path,
                    g_cancel ? " (an interrupt gives up on it)" : "");
            said = 1;
        }
        struct timespec ts = {0, 20000000};
        nanosleep(&ts, NULL);
    }
}

#ifdef __GLIBC__
/* The stream's writes keep their errno (commit reports the first failure's cause: stdio
 * keeps only a flag, and a later successful flush leaves errno 0). */
static ssize_t out_cookie_write(void *cookie, const char *buf, size_t n)
{
    lsqt_out *o = cookie;
    size_t done = 0;
    while (done < n) {
        ssize_t w = write(o->fd, buf + done, n - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            if (!o->werr) o->werr = w < 0 ? errno : EIO;
            break;
        }
        done += (size_t)w;
    }
    return (ssize_t)done; /* short: the stream sets its error flag */
}

static int out_cookie_close(void *cookie)
{
    lsqt_out *o = cookie;
    int r = close(o->fd);
    if (r != 0 && !o->werr) o->werr = errno;
    o->fd = -1;
    return r;
}
#endif

/* The stream over fd (o->fd). */
static FILE *out_stream(lsqt_out *o, int fd)
{
    o->fd = fd;
    o->werr = 0;
#ifdef __GLIBC__
    cookie_io_functions_t io = {NULL, out_cookie_write, NULL, out_cookie_close};
    return fopencookie(o, "wb", io);
#else
    return fdopen(fd, "wb");
#endif
}

int lsqt_out_check(const char *path, char *err, size_t errcap)
{
    lsqt_out o;
    struct stat old;
    int exists = 0;
    if (out_plan(&o, path, &old, &exists, err, errcap)) return -1;
    if (o.how == LSQT_OUT_STDOUT) return 0;
    if (o.how == LSQT_OUT_IN_PLACE) {
        if (access(o.target, W_OK) == 0) return 0;
        out_error(&o, strerror(errno), err, errcap);
        return -1;
    }
    /* Creating the temporary is the only honest test (permissions, read-only mounts). */
    int fd = make_temp(&o, &old, exists, "", err, errcap);
    if (fd < 0) return -1;
    close(fd);
    unlink(o.tmp);
    return 0;
}

int lsqt_out_open(lsqt_out *o, const char *path, char *err, size_t errcap)
{
    struct stat old;
    int exists = 0;
    if (out_plan(o, path, &old, &exists, err, errcap)) return -1;
    o->fd = -1;
    if (o->how == LSQT_OUT_STDOUT) {
        o->f = stdout;
        return 0;
    }
    int fd;
    if (o->how == LSQT_OUT_REPLACE) fd = make_temp(o, &old, exists, "", err, errcap);
    else if (S_ISSOCK(old.st_mode)) fd = open_socket(o, err, errcap);
    else if (S_ISFIFO(old.st_mode)) fd = open_fifo(o, err, errcap);
    else {
        fd = open(o->target, O_WRONLY | O_NOCTTY | O_CLOEXEC);
        if (fd < 0) out_error(o, strerror(errno), err, errcap);
    }
    if (fd < 0) return -1;
    o->f = out_stream(o, fd);
    if (!o->f) {
        out_error(o, strerror(errno), err, errcap);
        close(fd);
        if (o->how == LSQT_OUT_REPLACE) unlink(o->tmp);
        return -1;
    }
    return 0;
}

static int replace_target(lsqt_out *o, char *err, size_t errcap);

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
        out_error(o, strerror(saved), err, errcap);
        return -1;
    }
    if (o->how == LSQT_OUT_IN_PLACE) return 0;
    return replace_target(o, err, errcap);
}

/* Renames the finished temporary over the target, durably. */
static int replace_target(lsqt_out *o, char *err, size_t errcap)
{
    int saved;
    if (rename(o->tmp, o->target) != 0) {
        saved = errno;
        unlink(o->tmp);
        char why[512];
        snprintf(why, sizeof why, "cannot rename the temporary over it: %s", strerror(saved));
        out_error(o, why, err, errcap);
        return -1;
    }
    o->tmp[0] = '\0';
    /* Make the rename itself durable (best effort: not every file system allows it). */
    char dir[LSQT_PATH_CAP];
    const char *slash = strrchr(o->target, '/');
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - o->target) + 1 : 1, slash ? o->target : ".");
    int dfd = open(dir, O_RDONLY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)fsync(dfd);
        close(dfd);
    }
    return 0;
}

int lsqt_out_open_named(lsqt_out *o, const char *path, char *err, size_t errcap)
{
    struct stat old;
    int exists = 0;
    if (out_plan(o, path, &old, &exists, err, errcap)) return -1;
    o->fd = -1;
    o->f = NULL;
    if (o->how == LSQT_OUT_STDOUT) {
        snprintf(err, errcap, "cannot write to stdout ('-') here: give a file name");
        return -1;
    }
    if (o->how == LSQT_OUT_IN_PLACE) return 0;
    const char *base = strrchr(o->target, '/'), *dot = strrchr(base ? base : o->target, '.');
    int fd = make_temp(o, &old, exists, dot ? dot : "", err, errcap);
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
        out_error(o, strerror(e), err, errcap);
        return -1;
    }
    close(fd);
    return replace_target(o, err, errcap);
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

double lsqt_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int lsqt_path_type(const char *path, const char **what)
{
    struct stat sb;
    *what = "nothing";
    if (stat(path, &sb) != 0) return LSQT_PATH_MISSING;
    *what = kind_name(sb.st_mode);
    return S_ISREG(sb.st_mode) ? LSQT_PATH_REGULAR : S_ISDIR(sb.st_mode) ? LSQT_PATH_DIRECTORY : LSQT_PATH_SPECIAL;
}

/* The folder of PATH made absolute (realpath) with PATH's last name after it. */
static int absolute_name(const char *path, char *out, size_t cap)
{
    char dir[LSQT_PATH_CAP], *real;
    const char *slash = strrchr(path, '/');
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) + 1 : 1, slash ? path : ".");
    if (!(real = realpath(dir, NULL))) return -1;
    int w = snprintf(out, cap, "%s/%s", real, slash ? slash + 1 : path);
    free(real);
    return w > 0 && (size_t)w < cap ? 0 : -1;
}

int lsqt_same_file(const char *a, const char *b)
{
    if (strcmp(a, "-") == 0 || strcmp(b, "-") == 0) return strcmp(a, b) == 0;
    char ta[LSQT_PATH_CAP], tb[LSQT_PATH_CAP], e[64];
    if (resolve_links(a, ta, sizeof ta, e, sizeof e) || resolve_links(b, tb, sizeof tb, e, sizeof e))
        return strcmp(a, b) == 0;
    struct stat sa, sb;
    int ha = stat(ta, &sa) == 0, hb = stat(tb, &sb) == 0;
    if (ha && hb) return S_ISREG(sa.st_mode) && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    if (ha || hb) return 0;
    char fa[2 * LSQT_PATH_CAP], fb[2 * LSQT_PATH_CAP];
    if (absolute_name(ta, fa, sizeof fa) || absolute_name(tb, fb, sizeof fb)) return strcmp(ta, tb) == 0;
    return strcmp(fa, fb) == 0;
}

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
    if (resolve_links(state, target, sizeof target, err, errcap)) return -1;
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

int lsqt_prog_error(const char *prog, int code, const char *msg)
{
    fprintf(stderr, "%s: error: %s\n", prog, msg);
    return code;
}
