/* status.h: recoverable failures. Every fallible function returns a
 * clvr_status and, when it fails, fills a clvr_error with a one-line message
 * that names the file, the field and the fix. Only main() exits. */
#ifndef CLVR_STATUS_H
#define CLVR_STATUS_H

#include <stddef.h>

/* X(name, exit code, short description). The exit code is what `clvr`
 * returns when this status reaches main(): 2 usage, 3 input data,
 * 4 OpenCL device, 5 output, 1 anything else. */
#define CLVR_STATUS_MAP(X)                                                   \
    X(OK, 0, "success")                                                      \
    X(ERR_USAGE, 2, "invalid command line")                                  \
    X(ERR_IO, 3, "cannot read file")                                         \
    X(ERR_FORMAT, 3, "unknown or unsupported file format")                   \
    X(ERR_BAD_MAGIC, 3, "bad magic number")                                  \
    X(ERR_BAD_VERSION, 3, "unsupported format version")                      \
    X(ERR_TRUNCATED, 3, "file is shorter than its header says")             \
    X(ERR_OVERFLOW, 3, "counts overflow 64-bit sizes")                       \
    X(ERR_BAD_INDEX, 3, "vertex index out of range")                         \
    X(ERR_BAD_VALUE, 3, "NaN or infinite value")                             \
    X(ERR_BAD_FIELD, 3, "missing or invalid field")                          \
    X(ERR_EMPTY, 3, "mesh has no elements")                                  \
    X(ERR_NO_MEMORY, 1, "out of host memory")                                \
    X(ERR_NO_DEVICE, 4, "no matching OpenCL device")                         \
    X(ERR_OPENCL, 4, "OpenCL call failed")                                   \
    X(ERR_KERNEL_BUILD, 4, "OpenCL kernel build failed")                     \
    X(ERR_DEVICE_MEMORY, 4, "not enough device memory")                      \
    X(ERR_NO_DISPLAY, 4, "no display for the viewer")                        \
    X(ERR_WRITE, 5, "cannot write output file")                              \
    X(ERR_INTERRUPTED, 1, "interrupted")                                     \
    X(ERR_INTERNAL, 1, "internal error")

typedef enum clvr_status {
#define CLVR_STATUS_ENUM(name, code, text) CLVR_##name,
    CLVR_STATUS_MAP(CLVR_STATUS_ENUM)
#undef CLVR_STATUS_ENUM
    CLVR_STATUS_COUNT
} clvr_status;

/* The message that goes with a failed status. msg is always NUL-terminated. */
typedef struct clvr_error {
    clvr_status status;
    char msg[1024];
} clvr_error;

/* Short name, e.g. "ERR_TRUNCATED", and description of a status. */
const char *clvr_status_name(clvr_status s);
const char *clvr_status_text(clvr_status s);
/* Process exit code for a status (see CLVR_STATUS_MAP). */
int clvr_status_exit_code(clvr_status s);

/* Records status s and a printf-style message in err (err may be NULL) and
 * returns s, so callers write `return clvr_error_set(err, CLVR_ERR_IO, ...)`.
 * The message is one line: control characters (from quoted file contents)
 * become '?', except newlines and tabs of CLVR_ERR_KERNEL_BUILD messages,
 * which carry the compiler's log. */
clvr_status clvr_error_set(clvr_error *err, clvr_status s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#endif /* CLVR_STATUS_H */
