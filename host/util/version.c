/* The version string every program's --version prints (util.h). */
#include "lsqt/util.h"
#include "lsqt_git.h" /* LSQT_GIT_HASH: tools/git_hash.cmake writes it at every build */

#ifndef LSQT_VERSION_STRING
#define LSQT_VERSION_STRING "unknown"
#endif

const char *lsqt_version(void) { return LSQT_VERSION_STRING " (git " LSQT_GIT_HASH ")"; }
