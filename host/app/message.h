/* message.h: the program's own failures (a bad option, out of memory, a
 * file the program writes itself) in libclvr's form, a clvr_result and a
 * clvr_message, so that they print and exit like the library's. */
#ifndef CLVR_APP_MESSAGE_H
#define CLVR_APP_MESSAGE_H

#include "clvr.h"

/* Records r and a printf-style one-line message in msg (may be NULL) and
 * returns r: `return clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, ...)`.
 * Control characters (from quoted user input) become '?', as in the
 * library's messages (a kernel build's log keeps its lines). */
clvr_result clvr_app_fail(clvr_message *msg, clvr_result r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#endif
