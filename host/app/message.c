#include "message.h"

#include <stdarg.h>
#include <stdio.h>

clvr_result clvr_app_fail(clvr_message *msg, clvr_result r, const char *fmt, ...)
{
    if (!msg) return r;
    msg->result = r;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg->text, sizeof msg->text, fmt, ap);
    va_end(ap);
    /* As the library's messages: one line that cannot drive the terminal,
     * except a kernel build's compiler log, which keeps its lines. */
    const int keep_lines = r == CLVR_RESULT_ERR_KERNEL_BUILD;
    for (char *c = msg->text; *c; ++c) {
        unsigned char u = (unsigned char)*c;
        if ((u < 0x20 || u == 0x7f) && !(keep_lines && (u == '\n' || u == '\t'))) *c = '?';
    }
    return r;
}
