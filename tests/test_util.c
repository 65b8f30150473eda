/* Host utilities without OpenCL: exact seed parsing, the device check behind exit status 3,
 * the --wi-file parser (numbers, normalisation, the mirror in y, errors with line numbers),
 * and the output-file rules of util.h on every kind of target. Everything is made inside
 * a private temporary folder; device nodes are ones this test makes there with mknod
 * (skipped when it may not), never the system's. */
#define _DEFAULT_SOURCE /* mknod, makedev, mkdtemp, symlink */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "lsqt/cli.h"
#include "lsqt/device.h"
#include "lsqt/directions.h"
#include "lsqt/util.h"

static char dir[256];

static const char *at(const char *name)
{
    static char buf[8][512];
    static int k;
    k = (k + 1) % 8;
    snprintf(buf[k], sizeof buf[k], "%s/%s", dir, name);
    return buf[k];
}

static int write_text(const char *path, const char *text, char *err, size_t errcap)
{
    lsqt_out o;
    if (lsqt_out_open(&o, path, err, errcap)) return -1;
    fputs(text, o.f);
    return lsqt_out_commit(&o, err, errcap);
}

static char *slurp(const char *path)
{
    size_t n = 0;
    char err[256];
    return lsqt_read_file(path, &n, err, sizeof err);
}

static int count_temporaries(void)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "ls -a '%s' '%s/other' 2>/dev/null | grep -c '\\.tmp\\.'", dir, dir);
    FILE *p = popen(cmd, "r");
    int n = -1;
    if (p && fscanf(p, "%d", &n) != 1) n = -1;
    if (p) pclose(p);
    return n;
}

static void test_seeds(void)
{
    uint64_t v = 0;
    CHECK(lsqt_parse_u64("0", &v) == 0 && v == 0, "0");
    CHECK(lsqt_parse_u64("9007199254740993", &v) == 0 && v == 9007199254740993ULL, "2^53+1 read as %llu",
          (unsigned long long)v);
    CHECK(lsqt_parse_u64("18446744073709551615", &v) == 0 && v == UINT64_MAX, "2^64-1");
    CHECK(lsqt_parse_u64("18446744073709551616", &v) != 0, "2^64 accepted");
    CHECK(lsqt_parse_u64("99999999999999999999", &v) != 0, "1e20-1 accepted");
    const char *bad[] = {"", "-1", "+1", "1e3", " 1", "1 ", "0x10", "1.0", "abc"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) CHECK(lsqt_parse_u64(bad[i], &v) != 0, "'%s' accepted", bad[i]);
}

/* CRC-32 (IEEE): the standard check value, and the table-driven form against the bitwise
 * definition (written here) at every length and alignment, continued in pieces. */
static uint32_t crc_bitwise(uint32_t crc, const unsigned char *p, size_t n)
{
    crc = ~crc;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

static void test_crc32(void)
{
    CHECK(lsqt_crc32(0, "123456789", 9) == 0xCBF43926u, "CRC-32 check value: %08x", lsqt_crc32(0, "123456789", 9));
    unsigned char b[300];
    for (int i = 0; i < 300; i++) b[i] = (unsigned char)(i * 131u + 7u);
    int bad = 0;
    for (size_t n = 0; n + 3 <= 300; n++)
        for (int o = 0; o < 3; o++) {
            uint32_t whole = lsqt_crc32(0, b + o, n);
            bad += whole != crc_bitwise(0, b + o, n);
            bad += lsqt_crc32(lsqt_crc32(0, b + o, n / 3), b + o + n / 3, n - n / 3) != whole;
        }
    CHECK(bad == 0, "%d CRC-32 values differ from the bitwise definition", bad);
}

static void test_device_check(void)
{
    lsqt_device_info d;
    memset(&d, 0, sizeof d);
    snprintf(d.name, sizeof d.name, "Fake Device 9000");
    snprintf(d.platform_name, sizeof d.platform_name, "Fake Platform");
    d.little_endian = 1;
    char err[512] = "";
    CHECK(lsqt_device_check(&d, 0, err, sizeof err) == 0, "float on a plain device: %s", err);
    CHECK(lsqt_device_check(&d, 1, err, sizeof err) == 3, "--double without fp64 is not exit status 3");
    CHECK(strstr(err, "Fake Device 9000") && strstr(err, "cl_khr_fp64"), "message: %s", err);
    d.has_fp64 = 1;
    CHECK(lsqt_device_check(&d, 1, err, sizeof err) == 0, "double with fp64: %s", err);
    d.little_endian = 0;
    CHECK(lsqt_device_check(&d, 0, err, sizeof err) == 3, "big-endian without 64-bit atomics accepted");
    d.has_int64_atomics = 1;
    CHECK(lsqt_device_check(&d, 0, err, sizeof err) == 0, "big-endian with 64-bit atomics: %s", err);
}

/* lsqt_wi_parse of exactly len bytes (a copy with no terminator, so reading past the end
 * is caught under ASan). Returns its status; *dirs as it gives them. */
static int wi_parse(const char *text, size_t len, int lower, float **dirs, int *n, int *mirrored, char *err,
                    size_t errcap)
{
    char *copy = malloc(len ? len : 1);
    if (!copy) return -1;
    memcpy(copy, text, len);
    int rc = lsqt_wi_parse(copy, len, "w.txt", lower, dirs, n, mirrored, err, errcap);
    free(copy);
    return rc;
}

/* One good text: its count, and each direction (x, y, z) within tol (0: exactly). */
static void wi_good(const char *text, int lower, int want_n, const double *want, double tol, int want_mirrored)
{
    float *d = NULL;
    int n = -1, m = -1;
    char err[512] = "";
    int rc = wi_parse(text, strlen(text), lower, &d, &n, &m, err, sizeof err);
    CHECK(rc == 0 && d && n == want_n && m == want_mirrored, "'%s': rc %d, n %d (want %d), mirrored %d (want %d): %s",
          text, rc, n, want_n, m, want_mirrored, err);
    for (int k = 0; rc == 0 && d && k < n && k < want_n; k++) {
        for (int j = 0; j < 3; j++)
            CHECK(fabs(d[4 * k + j] - want[3 * k + j]) <= tol, "'%s': direction %d coordinate %d is %.9g, want %.9g", text,
                  k, j, d[4 * k + j], want[3 * k + j]);
        CHECK(d[4 * k + 3] == 0.0f && d[4 * k + 1] >= 0 && !signbit(d[4 * k + 1]), "'%s': direction %d: w %g, y %g", text,
              k, d[4 * k + 3], d[4 * k + 1]);
    }
    free(d);
}

/* One bad text: status 2, nothing returned, and a message holding `want`. */
static void wi_bad(const char *text, size_t len, int lower, const char *want)
{
    float *d = (float *)&d;
    int n = -1, m = -1;
    char err[512] = "";
    int rc = wi_parse(text, len, lower, &d, &n, &m, err, sizeof err);
    CHECK(rc == 2 && !d && n == 0 && m == 0 && strstr(err, want), "'%.40s': rc %d, n %d: '%s' lacks '%s'", text, rc, n, err,
          want);
    free(rc == 0 ? d : NULL);
}

static void test_wi_file(void)
{
    const double s3 = 1.0 / sqrt(3.0), s2 = sqrt(0.5), tol = 1.2e-7;
    /* x y z: normalised, exactly where that is exact; scaled first, so neither huge nor
     * subnormal components lose it. */
    wi_good("0 0 2\n", 0, 1, (const double[]){0, 0, 1}, 0, 0);
    wi_good("3 4 12", 0, 1, (const double[]){3.0 / 13, 4.0 / 13, 12.0 / 13}, tol, 0);
    wi_good("1e300 1e300 1e300\n-1e-310 0 1e-310\n", 0, 2, (const double[]){s3, s3, s3, -s2, 0, s2}, tol, 0);
    wi_good("1 -1 -1\n", 1, 1, (const double[]){s3, s3, -s3}, tol, 1);
    /* theta phi in degrees, phi from +x; exact at multiples of 90; phi periodic. */
    wi_good("0 123\n180 7\n", 1, 2, (const double[]){0, 0, 1, 0, 0, -1}, 0, 0);
    wi_good("60 90\n60 0\n60 180\n", 0, 3,
            (const double[]){0, sqrt(0.75), 0.5, sqrt(0.75), 0, 0.5, -sqrt(0.75), 0, 0.5}, tol, 0);
    wi_good("45 -90\n45 270\n30 370\n", 0, 3, (const double[]){0, s2, s2, 0, s2, s2, 0.5 * cos(LSQT_PI / 18),
                                                               0.5 * sin(LSQT_PI / 18), sqrt(0.75)}, tol, 2);
    wi_good("30 -45\n", 0, 1, (const double[]){0.5 * s2, 0.5 * s2, sqrt(0.75)}, tol, 1);
    /* Blank lines, comments (whole lines and after a direction), CRLF, tabs, no final
     * newline. */
    wi_good("\r\n\t# x y z\n  1 0 1 # c\r\n\n#\n0\t0  1", 0, 2, (const double[]){s2, 0, s2, 0, 0, 1}, tol, 0);
    /* Counts up to LSQT_WI_FILE_MAX, one more is an error on its line. */
    char many[8 * (LSQT_WI_FILE_MAX + 1) + 16];
    size_t len = 0;
    for (int k = 0; k < LSQT_WI_FILE_MAX; k++) len += (size_t)snprintf(many + len, sizeof many - len, "0 0 1\n");
    float *d = NULL;
    int n = 0, m = 0;
    char err[512] = "";
    CHECK(wi_parse(many, len, 0, &d, &n, &m, err, sizeof err) == 0 && n == LSQT_WI_FILE_MAX, "%d directions: %s",
          LSQT_WI_FILE_MAX, err);
    free(d);
    snprintf(many + len, sizeof many - len, "0 0 1\n");
    wi_bad(many, strlen(many), 0, "w.txt:1025: error: too many directions at '0 0 1'");

    /* Errors: "w.txt:LINE: error: WHAT at 'TOKEN'". */
    wi_bad("0 0 1\n0 0 0\n", 12, 1, "w.txt:2: error: the zero vector at '0 0 0'");
    wi_bad("0 0 1\n\n1 0 0 # horizon\n", 24, 1, "w.txt:3: error: a direction on the horizon (z = 0");
    wi_bad("90 0\n", 5, 1, "w.txt:1: error: a direction on the horizon");
    wi_bad("1 0 1e-300\n", 11, 1, "w.txt:1: error: a direction on the horizon (z = 0, where the BSDF value tally/|cos| is 0/0) at '1 0 1e-300'");
    wi_bad("# c\n1 0 -1\n", 11, 0, "w.txt:2: error: a direction below the horizon (z < 0)");
    wi_bad("91 0\n", 5, 0, "transmits nothing (its value would be 0) at '91 0'");
    wi_bad("180.5 0\n", 8, 1, "w.txt:1: error: theta out of range at '180.5'");
    wi_bad("-0.5 0\n", 7, 1, "w.txt:1: error: theta out of range at '-0.5'");
    wi_bad("0 0 1\n7\n", 8, 0, "w.txt:2: error: a single number at '7'");
    wi_bad("1 2 3 4 5\n", 10, 0, "w.txt:1: error: trailing text after the direction at '4'");
    wi_bad("1 2 3x\n", 7, 0, "w.txt:1: error: not a finite number at '3x'");
    wi_bad("nan 1 1\n", 8, 0, "w.txt:1: error: not a finite number at 'nan'");
    wi_bad("1 -inf 1\n", 9, 0, "w.txt:1: error: not a finite number at '-inf'");
    wi_bad("1 1e999 1\n", 10, 0, "w.txt:1: error: not a finite number at '1e999'");
    wi_bad("0x1p0 0 1\n", 10, 0, "w.txt:1: error: not a finite number at '0x1p0'");
    wi_bad("1 0 1\0junk\n", 11, 0, "w.txt:1: error: not a finite number at '1?junk'");
    wi_bad("", 0, 0, "w.txt: error: no directions");
    wi_bad("# nothing\n \t\r\n", 14, 0, "w.txt: error: no directions");
    /* A token longer than any number, and a tiny message buffer: cut, never overrun. */
    char longtok[600];
    memset(longtok, '1', sizeof longtok);
    wi_bad(longtok, sizeof longtok, 0, "w.txt:1: error: not a finite number at '1111");
    char tiny[8];
    d = (float *)&d;
    CHECK(wi_parse("0 0 0", 5, 0, &d, &n, &m, tiny, sizeof tiny) == 2 && !d && strlen(tiny) == 7, "tiny buffer: '%s'", tiny);
    /* The file reader: a missing file is status 1, a file of directions parses. */
    CHECK(lsqt_wi_file_read(at("nosuch.txt"), 0, &d, &n, &m, err, sizeof err) == 1 && !d && strstr(err, "cannot open"),
          "missing file: %s", err);
    CHECK(write_text(at("w.txt"), "# two\n0 0 1\n45 -90\n", err, sizeof err) == 0, "%s", err);
    CHECK(lsqt_wi_file_read(at("w.txt"), 0, &d, &n, &m, err, sizeof err) == 0 && n == 2 && m == 1 && d &&
              d[4] == 0.0f && fabs(d[5] - s2) < tol,
          "file: n %d, mirrored %d: %s", n, m, err);
    free(d);
    CHECK(write_text(at("w.txt"), "0 0 1\n\n45 -90 x\n", err, sizeof err) == 0, "%s", err);
    CHECK(lsqt_wi_file_read(at("w.txt"), 0, &d, &n, &m, err, sizeof err) == 2 && !d && strstr(err, "/w.txt:3: error: ") &&
              strstr(err, "at 'x'"),
          "file error: %s", err);
}

static void test_regular_and_links(void)
{
    char err[8192];
    struct stat sb;
    /* New file, then replacement keeps the old file's mode. */
    CHECK(write_text(at("a.txt"), "one\n", err, sizeof err) == 0, "%s", err);
    chmod(at("a.txt"), 0640);
    CHECK(write_text(at("a.txt"), "two\n", err, sizeof err) == 0, "%s", err);
    char *s = slurp(at("a.txt"));
    CHECK(s && strcmp(s, "two\n") == 0, "replaced content: %s", s ? s : "(none)");
    free(s);
    CHECK(stat(at("a.txt"), &sb) == 0 && (sb.st_mode & 0777) == 0640, "mode %o not kept", (unsigned)sb.st_mode & 0777);

    /* An abort leaves the old file whole and no temporary. */
    lsqt_out o;
    CHECK(lsqt_out_open(&o, at("a.txt"), err, sizeof err) == 0, "%s", err);
    fputs("half", o.f);
    lsqt_out_abort(&o);
    s = slurp(at("a.txt"));
    CHECK(s && strcmp(s, "two\n") == 0, "abort changed the file: %s", s ? s : "(none)");
    free(s);

    /* A relative symlink into another folder, and a chain of two: the links stay, the
     * file they point to is replaced. */
    mkdir(at("other"), 0755);
    CHECK(write_text(at("other/real.txt"), "old\n", err, sizeof err) == 0, "%s", err);
    CHECK(symlink("other/real.txt", at("link1")) == 0 && symlink("link1", at("link2")) == 0, "symlink: %s",
          strerror(errno));
    CHECK(lsqt_out_check(at("link2"), err, sizeof err) == 0, "%s", err);
    CHECK(write_text(at("link2"), "new\n", err, sizeof err) == 0, "%s", err);
    CHECK(lstat(at("link1"), &sb) == 0 && S_ISLNK(sb.st_mode), "link1 is no longer a symlink");
    CHECK(lstat(at("link2"), &sb) == 0 && S_ISLNK(sb.st_mode), "link2 is no longer a symlink");
    s = slurp(at("other/real.txt"));
    CHECK(s && strcmp(s, "new\n") == 0, "link target content: %s", s ? s : "(none)");
    free(s);
    /* A dangling link creates the file it names. */
    CHECK(symlink("other/made.txt", at("dangling")) == 0, "symlink");
    CHECK(write_text(at("dangling"), "made\n", err, sizeof err) == 0, "%s", err);
    CHECK(lstat(at("dangling"), &sb) == 0 && S_ISLNK(sb.st_mode), "dangling link replaced");
    CHECK(stat(at("other/made.txt"), &sb) == 0 && S_ISREG(sb.st_mode), "link target not created");
    /* A link loop is an error, not a hang. */
    CHECK(symlink("loopb", at("loopa")) == 0 && symlink("loopa", at("loopb")) == 0, "symlink");
    CHECK(write_text(at("loopa"), "x", err, sizeof err) != 0 && strstr(err, "symbolic links"), "loop: %s", err);
    CHECK(count_temporaries() == 0, "%d temporaries left behind", count_temporaries());

    /* Refused: a directory, a missing folder; the message names the path. */
    CHECK(lsqt_out_check(at("other"), err, sizeof err) != 0 && strstr(err, "is a directory") &&
              strstr(err, at("other")),
          "directory: %s", err);
    CHECK(write_text(at("other"), "x", err, sizeof err) != 0, "wrote over a directory");
    CHECK(lsqt_out_check(at("nodir/x.txt"), err, sizeof err) != 0 && strstr(err, "nodir/x.txt"), "missing folder: %s",
          err);
    CHECK(lsqt_path_type(at("other"), &(const char *){NULL}) == LSQT_PATH_DIRECTORY, "path type of a folder");
    CHECK(lsqt_path_type(at("link2"), &(const char *){NULL}) == LSQT_PATH_REGULAR, "path type through a link");
    CHECK(lsqt_path_type(at("none"), &(const char *){NULL}) == LSQT_PATH_MISSING, "path type of nothing");

    /* Same-file detection: through links and spellings, but devices may be shared. */
    CHECK(lsqt_same_file(at("link2"), at("other/real.txt")), "a link and its target");
    CHECK(lsqt_same_file(at("new.raw"), at("other/../new.raw")), "two spellings of a new file");
    CHECK(!lsqt_same_file(at("a.txt"), at("other/real.txt")), "different files");
    CHECK(lsqt_same_file("-", "-") && !lsqt_same_file("-", at("a.txt")), "stdout");
}

static void test_fifo(void)
{
    char err[8192];
    const char *fifo = at("fifo");
    CHECK(mkfifo(fifo, 0600) == 0, "mkfifo: %s", strerror(errno));
    CHECK(lsqt_out_check(fifo, err, sizeof err) == 0, "check blocks or fails on a FIFO: %s", err);
    pid_t pid = fork();
    if (pid == 0) { /* the reader: copies the FIFO into a file */
        alarm(30);
        FILE *in = fopen(fifo, "rb"), *out = fopen(at("from_fifo"), "wb");
        int c;
        while (in && out && (c = fgetc(in)) != EOF) fputc(c, out);
        _exit(in && out && fclose(out) == 0 ? 0 : 1);
    }
    alarm(30);
    CHECK(write_text(fifo, "through the fifo\n", err, sizeof err) == 0, "%s", err);
    int status = 0;
    waitpid(pid, &status, 0);
    alarm(0);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0, "reader failed");
    char *s = slurp(at("from_fifo"));
    CHECK(s && strcmp(s, "through the fifo\n") == 0, "reader got: %s", s ? s : "(none)");
    free(s);
    struct stat sb;
    CHECK(lstat(fifo, &sb) == 0 && S_ISFIFO(sb.st_mode), "the FIFO was replaced");
    CHECK(lsqt_path_type(fifo, &(const char *){NULL}) == LSQT_PATH_SPECIAL, "path type of a FIFO");
}

static void test_socket(void)
{
    char err[8192];
    const char *path = at("sock");
    int srv = socket(AF_UNIX, SOCK_STREAM, 0);
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    snprintf(sa.sun_path, sizeof sa.sun_path, "%s", path);
    if (srv < 0 || bind(srv, (struct sockaddr *)&sa, sizeof sa) != 0 || listen(srv, 1) != 0) {
        printf("skip: cannot make a Unix socket here: %s\n", strerror(errno));
        if (srv >= 0) close(srv);
        return;
    }
    CHECK(write_text(path, "over a socket\n", err, sizeof err) == 0, "%s", err);
    int c = accept(srv, NULL, NULL);
    char buf[64] = "";
    ssize_t n = c >= 0 ? read(c, buf, sizeof buf - 1) : -1;
    if (n > 0) buf[n] = '\0';
    CHECK(strcmp(buf, "over a socket\n") == 0, "socket got: %s", buf);
    struct stat sb;
    CHECK(lstat(path, &sb) == 0 && S_ISSOCK(sb.st_mode), "the socket was replaced");
    if (c >= 0) close(c);
    close(srv);
}

/* Device nodes made here (null 1:3, full 1:7), and a block node of the experimental
 * major 240, which nothing drives: refused before any open. */
static void test_devices(void)
{
    char err[8192];
    struct stat sb;
    if (mknod(at("null"), S_IFCHR | 0666, makedev(1, 3)) != 0) {
        printf("skip: cannot mknod here (%s): device-node checks left to test_outputs.sh\n", strerror(errno));
        return;
    }
    CHECK(lsqt_out_check(at("null"), err, sizeof err) == 0, "%s", err);
    CHECK(write_text(at("null"), "discarded\n", err, sizeof err) == 0, "null: %s", err);
    CHECK(lstat(at("null"), &sb) == 0 && S_ISCHR(sb.st_mode), "the null device was replaced");
    CHECK(mknod(at("full"), S_IFCHR | 0666, makedev(1, 7)) == 0, "mknod full: %s", strerror(errno));
    CHECK(lsqt_out_check(at("full"), err, sizeof err) == 0, "%s", err);
    CHECK(write_text(at("full"), "no room\n", err, sizeof err) != 0 && strstr(err, at("full")) &&
              strstr(err, strerror(ENOSPC)),
          "full device: '%s'", err);
    /* A failed write that is the last one (more than stdio's buffer, nothing after it):
     * the flush at commit has nothing left to write, so only the write kept the cause. */
    {
        static char big[1 << 20];
        memset(big, 'x', sizeof big);
        lsqt_out o;
        CHECK(lsqt_out_open(&o, at("full"), err, sizeof err) == 0, "%s", err);
        if (o.f) {
            fwrite(big, 1, sizeof big, o.f);
            CHECK(lsqt_out_commit(&o, err, sizeof err) != 0 && strstr(err, strerror(ENOSPC)),
                  "full device, a 1 MB write: '%s'", err);
        }
    }
    CHECK(lstat(at("full"), &sb) == 0 && S_ISCHR(sb.st_mode), "the full device was replaced");
    CHECK(mknod(at("blk"), S_IFBLK | 0600, makedev(240, 0)) == 0, "mknod blk: %s", strerror(errno));
    CHECK(lsqt_out_check(at("blk"), err, sizeof err) != 0 && strstr(err, "block device"), "block: %s", err);
    CHECK(write_text(at("blk"), "x", err, sizeof err) != 0, "wrote to a block device");
    CHECK(lstat(at("blk"), &sb) == 0 && S_ISBLK(sb.st_mode), "the block node was replaced");
    CHECK(count_temporaries() == 0, "%d temporaries left behind", count_temporaries());
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    snprintf(dir, sizeof dir, "%s/lsqt_test_util.XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_seeds();
    test_crc32();
    test_device_check();
    test_wi_file();
    test_regular_and_links();
    test_fifo();
    test_socket();
    test_devices();
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
    return check_finish("test_util");
}
