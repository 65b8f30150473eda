/* The one form of a companion program's error message. */
#include "lsqt/util.h"

int lsqt_prog_error(const char *prog, int code, const char *msg)
{
    fprintf(stderr, "%s: error: %s\n", prog, msg);
    return code;
}
