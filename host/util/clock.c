/* clock_gettime is POSIX (CMakeLists.txt defines _POSIX_C_SOURCE). */
#include "lsqt/util.h"

#include <time.h>

double lsqt_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
