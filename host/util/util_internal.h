/* Private to host/util/: the steps of writing an output (util.h's lsqt_out_*) and the
 * path helpers they share with the locks. Calls go one way: out.c -> out_plan.c,
 * out_temp.c, out_stream.c -> paths.c; lock.c -> paths.c. */
#ifndef LSQT_UTIL_INTERNAL_H
#define LSQT_UTIL_INTERNAL_H

#include <sys/types.h>

#include "lsqt/util.h"

/* paths.c: the kind of file a stat's mode names ("regular file", "FIFO", ...). */
const char *lsqt_file_kind(mode_t m);
/* paths.c: PATH with its symlinks followed link by link into out; a dangling link names
 * the file to make. Returns 0, or -1 with err filled. */
int lsqt_resolve_links(const char *path, char *out, size_t cap, char *err, size_t errcap);

struct stat;
/* out_plan.c: "cannot write 'PATH'" (with the link's target when PATH is a link): reason. */
void lsqt_out_error(const lsqt_out *o, const char *reason, char *err, size_t errcap);
/* out_plan.c: how PATH is written (o->how, o->target); *old is its stat when it exists. */
int lsqt_out_plan(lsqt_out *o, const char *path, struct stat *old, int *exists, char *err, size_t errcap);

/* out_temp.c: the temporary beside o->target (o->tmp, its name ending in suffix); returns
 * its descriptor, or -1 with err filled. */
int lsqt_out_make_temp(lsqt_out *o, const struct stat *old, int exists, const char *suffix, char *err, size_t errcap);
/* out_temp.c: renames the finished temporary over the target, durably. */
int lsqt_out_replace_target(lsqt_out *o, char *err, size_t errcap);
/* out_temp.c: makes a rename in PATH's folder durable (best effort: not every file system
 * allows the folder's fsync). */
void lsqt_sync_folder(const char *path);

/* out_stream.c: descriptors of outputs written in place, and the stream over one. */
int lsqt_out_open_socket(lsqt_out *o, char *err, size_t errcap);
int lsqt_out_open_fifo(lsqt_out *o, char *err, size_t errcap);
FILE *lsqt_out_stream(lsqt_out *o, int fd);

#endif
