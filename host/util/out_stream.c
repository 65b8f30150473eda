/* fopencookie is a GNU interface. */
#define _GNU_SOURCE

/* Outputs written in place (a socket, a FIFO once it has a reader) and the stream over
 * an output's descriptor. */
#include "util_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

/* A connected stream to the Unix socket at o->target. */
int lsqt_out_open_socket(lsqt_out *o, char *err, size_t errcap)
{
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    if (strlen(o->target) >= sizeof sa.sun_path) {
        lsqt_out_error(o, "socket path too long", err, errcap);
        return -1;
    }
    strcpy(sa.sun_path, o->target);
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    if (fd >= 0 && connect(fd, (struct sockaddr *)&sa, sizeof sa) == 0) return fd;
    char why[512];
    snprintf(why, sizeof why, "cannot connect to the socket: %s", strerror(errno));
    if (fd >= 0) close(fd);
    lsqt_out_error(o, why, err, errcap);
    return -1;
}

static volatile sig_atomic_t *g_cancel; /* lsqt_out_cancel_flag */

void lsqt_out_cancel_flag(volatile sig_atomic_t *flag) { g_cancel = flag; }

/* A FIFO for writing once a reader has it open (O_NONBLOCK fails with ENXIO until then),
 * then blocking as any output. */
int lsqt_out_open_fifo(lsqt_out *o, char *err, size_t errcap)
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
            lsqt_out_error(o, strerror(errno), err, errcap);
            return -1;
        }
        if (g_cancel && *g_cancel) {
            lsqt_out_error(o, "no process read the FIFO before the interrupt", err, errcap);
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
FILE *lsqt_out_stream(lsqt_out *o, int fd)
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
