/* api_check.h: the checks of the tests that use the public API (clvr.h)
 * alone: test_api, test_api_scene, test_api_program. Header-only; it
 * defines the test's failure count, and the macros read the caller's
 * `msg` (a clvr_message), which each test keeps where its calls write it. */
#ifndef CLVR_API_CHECK_H
#define CLVR_API_CHECK_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clvr.h"
#include "test_device.h"

static int failures;

#define CHECK(cond)                                                                                                   \
    do {                                                                                                              \
        if (!(cond)) {                                                                                                \
            fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond);                                 \
            ++failures;                                                                                               \
        }                                                                                                             \
    } while (0)
/* A call that must fail with result `want` (returned and in msg) and a
 * message containing `part`. */
#define CHECK_FAILS(call, want, part)                                                                                 \
    do {                                                                                                              \
        clvr_result r_ = (call);                                                                                      \
        if (r_ != (want) || msg.result != (want) || !strstr(msg.text, (part))) {                                      \
            fprintf(stderr, "%s:%d: %s gave %s '%s'; expected %s with '%s'\n", __FILE__, __LINE__, #call,           \
                    clvr_result_name(r_), msg.text, clvr_result_name(want), part);                                   \
            ++failures;                                                                                               \
        }                                                                                                             \
    } while (0)
/* A call that must succeed; the test stops at the first that does not
 * (what follows needs what it made). */
#define OK(call)                                                                                                      \
    do {                                                                                                              \
        clvr_result r_ = (call);                                                                                      \
        if (r_ != CLVR_RESULT_OK) {                                                                                   \
            fprintf(stderr, "%s:%d: %s failed: %s: %s\n", __FILE__, __LINE__, #call, clvr_result_name(r_), msg.text); \
            exit(1);                                                                                                  \
        }                                                                                                             \
    } while (0)

#endif
