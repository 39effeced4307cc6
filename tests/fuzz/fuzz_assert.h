/* fuzz_assert.h: FUZZ_ASSERT aborts (so libFuzzer records the input) when a
 * parser breaks its contract, printing the condition and a message. */
#ifndef CLVR_FUZZ_ASSERT_H
#define CLVR_FUZZ_ASSERT_H

#include <stdio.h>
#include <stdlib.h>

#define FUZZ_ASSERT(cond, ...)                                                          \
    do {                                                                                \
        if (!(cond)) {                                                                  \
            fprintf(stderr, "fuzz contract broken at %s:%d: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                               \
            fputc('\n', stderr);                                                        \
            abort();                                                                    \
        }                                                                               \
    } while (0)

#endif
