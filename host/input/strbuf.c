/* The bounded string builder of lsqt_internal.h, for the parser's messages and the
 * canonical writer. */
#include "lsqt_internal.h"

#include <stdarg.h>
#include <stdio.h>

void lsqt_sb_init(lsqt_sb *sb, char *buf, size_t cap)
{
    sb->buf = buf;
    sb->cap = buf ? cap : 0;
    sb->len = 0;
    if (sb->cap)
        buf[0] = '\0';
}

void lsqt_sb_printf(lsqt_sb *sb, const char *fmt, ...)
{
    char *dst = NULL;
    size_t room = 0;
    if (sb->len < sb->cap) {
        dst = sb->buf + sb->len;
        room = sb->cap - sb->len;
    }
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(dst, room, fmt, ap);
    va_end(ap);
    if (n > 0)
        sb->len += (size_t)n;
}
