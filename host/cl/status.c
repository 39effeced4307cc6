#include "status.h"

#include <stdarg.h>
#include <stdio.h>

const char *clvr_status_name(clvr_status s)
{
    switch (s) {
#define CLVR_STATUS_CASE(name, code, text) case CLVR_##name: return #name;
        CLVR_STATUS_MAP(CLVR_STATUS_CASE)
#undef CLVR_STATUS_CASE
    default: return "UNKNOWN_STATUS";
    }
}

const char *clvr_status_text(clvr_status s)
{
    switch (s) {
#define CLVR_STATUS_CASE(name, code, text) case CLVR_##name: return text;
        CLVR_STATUS_MAP(CLVR_STATUS_CASE)
#undef CLVR_STATUS_CASE
    default: return "unknown status";
    }
}

int clvr_status_exit_code(clvr_status s)
{
    switch (s) {
#define CLVR_STATUS_CASE(name, code, text) case CLVR_##name: return code;
        CLVR_STATUS_MAP(CLVR_STATUS_CASE)
#undef CLVR_STATUS_CASE
    default: return 1;
    }
}

clvr_status clvr_error_set(clvr_error *err, clvr_status s, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->status = s;
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        /* Messages quote names and text from untrusted files: control
         * characters become '?' so a message stays one line and cannot drive
         * the terminal. Kernel build failures keep the compiler log's lines. */
        const int keep_lines = s == CLVR_ERR_KERNEL_BUILD;
        for (char *c = err->msg; *c; ++c) {
            unsigned char u = (unsigned char)*c;
            if ((u < 0x20 || u == 0x7f) && !(keep_lines && (u == '\n' || u == '\t'))) *c = '?';
        }
    }
    return s;
}
