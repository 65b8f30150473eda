/* lsqt-cl's stop signals: one thread takes them (sigwait), no handler runs in PoCL or LLVM. */
#include "run_cmd.h"

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

volatile sig_atomic_t g_stop = 0;  /* the signal that asked to stop, 0 if none */
volatile sig_atomic_t g_armed = 0; /* the input is read: Ctrl-C now means "finish" */
static sigset_t g_sigint;

/* Ctrl-C (SIGINT), and the signals a batch system sends at or before a job's time limit
 * (SIGTERM, SIGHUP, SIGUSR1 with sbatch --signal), are taken by this thread alone
 * (sigwait), never by a signal handler: they are blocked in every other thread, PoCL's
 * included, so LLVM's own handler (installed while PoCL compiles a kernel) cannot run
 * and delete the compiler's temporary files, which failed the build. First signal:
 * finish the launch, write LSS and RAW, exit non-zero. Second (or any while the input is
 * still being read): stop at once, exit 128 + the signal. */
static pthread_mutex_t g_watch_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t g_watch_cond = PTHREAD_COND_INITIALIZER;
static int g_watch_started = 0;
static void (*volatile g_at_stop)(void) = NULL; /* sigint_at_stop's */

void sigint_at_stop(void (*fn)(void)) { g_at_stop = fn; }

static void *sigint_watch(void *arg)
{
    (void)arg;
    pthread_mutex_lock(&g_watch_lock);
    g_watch_started = 1;
    pthread_cond_signal(&g_watch_cond);
    pthread_mutex_unlock(&g_watch_lock);
    for (int count = 0;;) {
        int sig = 0;
        if (sigwait(&g_sigint, &sig) != 0 || !sigismember(&g_sigint, sig)) continue;
        if (++count == 1 && g_armed) {
            g_stop = sig;
            continue;
        }
        void (*at_stop)(void) = g_at_stop;
        if (at_stop) at_stop();
        static const char msg[] = "\nlsqt-cl: interrupted: stopping now, nothing more written\n";
        if (write(STDERR_FILENO, msg, sizeof msg - 1) < 0) { /* nowhere left to say it */
        }
        _exit(128 + sig);
    }
    return NULL;
}

static void on_sigint(int sig) /* fallback when no thread can be started */
{
    g_stop = sig;
    signal(sig, SIG_DFL);
}

static const int g_stop_signals[] = {SIGINT, SIGTERM, SIGHUP, SIGUSR1};

/* Before any other thread exists, so that every thread inherits the blocked SIGINT. */
void sigint_setup(void)
{
    sigemptyset(&g_sigint);
    for (size_t i = 0; i < sizeof g_stop_signals / sizeof *g_stop_signals; i++) sigaddset(&g_sigint, g_stop_signals[i]);
    pthread_t t;
    if (pthread_sigmask(SIG_BLOCK, &g_sigint, NULL) == 0 && pthread_create(&t, NULL, sigint_watch, NULL) == 0) {
        pthread_detach(t);
        /* Wait until the thread runs: a process that exits while a thread is still being
         * set up (a bad flag exits at once) leaves the C library's start-up data behind,
         * which LeakSanitizer reports. */
        pthread_mutex_lock(&g_watch_lock);
        while (!g_watch_started) pthread_cond_wait(&g_watch_cond, &g_watch_lock);
        pthread_mutex_unlock(&g_watch_lock);
        return;
    }
    pthread_sigmask(SIG_UNBLOCK, &g_sigint, NULL);
    for (size_t i = 0; i < sizeof g_stop_signals / sizeof *g_stop_signals; i++) signal(g_stop_signals[i], on_sigint);
}

const char *signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : sig == SIGUSR1 ? "SIGUSR1" : "a signal";
}
