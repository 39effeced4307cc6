/* test_util.h: the small harness every test program uses. Checks print both
 * values and the line; a test with no OpenCL device exits 77 (ctest: skipped,
 * never passed). Tests print "N passed, N failed" as their last line. */
#ifndef CLVR_TEST_UTIL_H
#define CLVR_TEST_UTIL_H

#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cl_context.h"
#include "test_device.h"

static int tu_pass_, tu_fail_;

#define TU_CHECK(cond)                                                                      \
    do {                                                                                    \
        if (cond) ++tu_pass_;                                                               \
        else { ++tu_fail_; fprintf(stderr, "%s:%d: FAILED: %s\n", __FILE__, __LINE__, #cond); } \
    } while (0)

#define TU_CHECK_EQ_U64(a, b)                                                               \
    do {                                                                                    \
        uint64_t tu_a_ = (uint64_t)(a), tu_b_ = (uint64_t)(b);                              \
        if (tu_a_ == tu_b_) ++tu_pass_;                                                     \
        else { ++tu_fail_; fprintf(stderr, "%s:%d: FAILED: %s == %s (%" PRIu64 " vs %" PRIu64 ")\n", \
                                   __FILE__, __LINE__, #a, #b, tu_a_, tu_b_); }             \
    } while (0)

#define TU_CHECK_NEAR(a, b, tol)                                                            \
    do {                                                                                    \
        double tu_a_ = (double)(a), tu_b_ = (double)(b);                                    \
        if (fabs(tu_a_ - tu_b_) <= (double)(tol)) ++tu_pass_;                               \
        else { ++tu_fail_; fprintf(stderr, "%s:%d: FAILED: %s ~ %s (%.9g vs %.9g, tol %g)\n", \
                                   __FILE__, __LINE__, #a, #b, tu_a_, tu_b_, (double)(tol)); } \
    } while (0)

/* Checks a status and, when it is not the expected one, prints the message. */
#define TU_CHECK_STATUS(expr, expected, errp)                                              \
    do {                                                                                    \
        clvr_status tu_s_ = (expr);                                                         \
        if (tu_s_ == (expected)) ++tu_pass_;                                                \
        else { ++tu_fail_; fprintf(stderr, "%s:%d: FAILED: %s gave %s, expected %s: %s\n",  \
                                   __FILE__, __LINE__, #expr, clvr_status_name(tu_s_),      \
                                   clvr_status_name(expected), (errp)->msg); }              \
    } while (0)

/* Prints the closing line ctest logs and returns the exit code. */
static inline int tu_finish(const char *name)
{
    printf("%s: %d passed, %d failed\n", name, tu_pass_, tu_fail_);
    return tu_fail_ ? 1 : 0;
}

/* Opens the test device (tu_device_spec); exits 77 when there is none, so
 * ctest reports the test as skipped. */
static inline void tu_open_device(clvr_cl *cl)
{
    clvr_error err = {0};
    if (clvr_cl_create(tu_device_spec(), cl, &err) != CLVR_OK) {
        fprintf(stderr, "SKIP: no OpenCL device: %s\n", err.msg);
        exit(77);
    }
}

/* Directory of test data files copied from ../shared/data (tests/data). */
static inline const char *tu_data_dir(void)
{
    const char *d = getenv("CLVR_SHARED_DATA");
    return d ? d : CLVR_SOURCE_DIR "/tests/data";
}

/* 1 under CLVR_TEST_BRIEF=1, which the sanitizer build sets (CMakeLists.txt):
 * leave out the runs the plain build's run already covers. The Python tests
 * read it the same way (== "1"). */
static inline int tu_brief(void)
{
    const char *b = getenv("CLVR_TEST_BRIEF");
    return b && strcmp(b, "1") == 0;
}

/* splitmix64: deterministic random numbers for test inputs. */
static inline uint64_t tu_rand(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static inline float tu_randf(uint64_t *state) { return (float)(tu_rand(state) >> 40) * (1.0f / 16777216.0f); }

#endif
