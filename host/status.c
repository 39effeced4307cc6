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
    }
    return s;
}
