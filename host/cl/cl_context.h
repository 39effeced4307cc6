/* cl_context.h: the OpenCL runtime: device listing and selection, program
 * builds from kernel sources embedded at build time (or read from a
 * directory while developing), checked calls and buffer allocation with
 * device-memory limits. Every OpenCL failure is reported with the call's
 * name and the error code's name. */
#ifndef CLVR_CL_CONTEXT_H
#define CLVR_CL_CONTEXT_H

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <stdio.h>

#include "status.h"

typedef struct clvr_cl {
    cl_platform_id platform;
    cl_device_id device;
    cl_context context;
    cl_command_queue queue;      /* in-order, with profiling enabled */
    cl_device_type device_type;
    char platform_name[256];
    char device_name[256];
    char device_version[128];
    char driver_version[128];
    cl_ulong global_mem_bytes;
    cl_ulong max_alloc_bytes;    /* CL_DEVICE_MAX_MEM_ALLOC_SIZE, or CLVR_MAX_ALLOC_BYTES when that is lower */
    cl_ulong device_max_alloc_bytes; /* CL_DEVICE_MAX_MEM_ALLOC_SIZE as the device reports it */
    size_t max_work_group_size;
    cl_uint compute_units;
    /* CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT in CL_DEVICE_SINGLE_FP_CONFIG: the
     * kernels are built with -cl-fp32-correctly-rounded-divide-sqrt, so a
     * division or square root gives the host reference's bits (NVIDIA's
     * default division is within 2.5 ulp, enough to move a quantized
     * element box by a step). */
    int fp32_correct_div_sqrt;
    const char *kernel_dir;      /* NULL: embedded sources; else read kernels from this directory */
    cl_ulong allocated_bytes;    /* sum of live buffers made by clvr_cl_buffer (bookkeeping for --stats) */
    double build_s;              /* seconds spent in clBuildProgram so far (kernel compilation) */
    /* Set by the caller: print "compiling kernels (cached for next time)" to
     * stderr when a build takes longer than CLVR_BUILD_NOTICE_S (a cold
     * driver cache), at most once per context. */
    int build_notice;
    int build_notice_shown;      /* the notice was printed */
} clvr_cl;

/* A build slower than this is a compilation, not a cache hit (PoCL: 1-12 s
 * per program with an empty cache, a few ms from its cache). */
#define CLVR_BUILD_NOTICE_S 0.4

/* Name of an OpenCL error code, e.g. "CL_OUT_OF_RESOURCES". */
const char *clvr_cl_error_name(cl_int code);

/* Prints every platform and device (name, vendor, version, compute units,
 * global memory) to out. Fails with CLVR_ERR_NO_DEVICE when there is none. */
clvr_status clvr_cl_list_devices(FILE *out, clvr_error *err);

/* Picks a device by spec and creates context and queue. spec: NULL or ""
 * (first GPU, else PoCL, else the first device), "pocl", "cpu", "gpu",
 * "P:D" indices, or a case-insensitive substring of a platform or device
 * name. No match: CLVR_ERR_NO_DEVICE with the list of what exists.
 * The environment variable CLVR_KERNEL_DIR, when set, becomes kernel_dir. */
clvr_status clvr_cl_create(const char *spec, clvr_cl *out, clvr_error *err);
/* Releases everything; accepts NULL and half-built contexts. */
void clvr_cl_destroy(clvr_cl *cl);

/* Builds the program whose entry file is kernels/<entry> (e.g. "sort.cl").
 * Local #include "x.h" directives are expanded from the same source set, with
 * #line markers so compiler messages name the right file and line. options
 * are appended to clvr's defaults (-cl-std=CL1.2 -I...). On failure the build
 * log goes into the message (CLVR_ERR_KERNEL_BUILD). The compiler's own
 * output to stderr (PoCL's "1 warning generated.") is captured, never shown
 * to a user: it joins the message on failure, and CLVR_BUILD_LOG=1 in the
 * environment prints it and the build log of every program (developers).
 * Adds the build's wall time to cl->build_s. */
clvr_status clvr_cl_build(clvr_cl *cl, const char *entry, const char *options, cl_program *out, clvr_error *err);

/* A build log with each "<kernel>:LINE:" / "<source>:LINE:" (compilers that
 * ignore #line, NVIDIA's among them) rewritten as "FILE:LINE:" of the kernel
 * file that line of the expanded source `src` came from. Malloc'ed; NULL
 * when out of memory. Used by clvr_cl_build; public for its test. */
char *clvr_cl_map_build_log(const char *src, const char *log);

/* clCreateKernel with error reporting. */
clvr_status clvr_cl_kernel(cl_program prog, const char *name, cl_kernel *out, clvr_error *err);

/* One kernel argument: its size in bytes and the address of its value (of
 * the cl_mem handle for a buffer; NULL with a size for __local memory). */
typedef struct clvr_cl_arg {
    size_t size;
    const void *value;
} clvr_cl_arg;
/* The argument whose value is the lvalue v: a cl_mem, a cl_uint, a struct
 * of kernels/clvr_shared.h passed by value... Its type must be the kernel
 * parameter's (cl_uint for uint, cl_ulong for ulong): the size is sizeof(v). */
#define CLVR_ARG(v) ((clvr_cl_arg){sizeof(v), &(v)})

/* Sets arguments 0 .. n - 1 of kernel k from args, in order. On the first
 * failure reports the kernel's name, the argument's index and size and the
 * error's name (CLVR_ERR_OPENCL); CLVR_FAIL=clSetKernelArg injects one. */
clvr_status clvr_cl_set_args(cl_kernel k, const clvr_cl_arg *args, size_t n, clvr_error *err);
/* Every argument of k in one call, the list written out in kernel order:
 *   CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(in), CLVR_ARG(n), CLVR_ARG(out)));
 * (the list is a compound literal; its length is counted, not written). */
#define CLVR_CL_ARGS(k, err, ...)                                                                     \
    clvr_cl_set_args((k), (const clvr_cl_arg[]){__VA_ARGS__},                                        \
                     sizeof((const clvr_cl_arg[]){__VA_ARGS__}) / sizeof(clvr_cl_arg), (err))

/* Creates a buffer of bytes (>= 1 byte is always allocated, so empty inputs
 * work) after checking it against CL_DEVICE_MAX_MEM_ALLOC_SIZE and global
 * memory; `what` names the buffer in messages ("vertices: 1.2 GB needed but
 * the device allows 1 GB per buffer; use smaller clusters or another device"). */
clvr_status clvr_cl_buffer(clvr_cl *cl, cl_mem_flags flags, size_t bytes, void *host_ptr, const char *what,
                           cl_mem *out, clvr_error *err);
/* Releases a buffer made by clvr_cl_buffer and updates allocated_bytes. Accepts NULL. */
void clvr_cl_release(clvr_cl *cl, cl_mem *buf);

/* Enqueues a 1D kernel over n work items (rounded up to the local size; the
 * kernel must check its global id against n). n == 0 enqueues nothing.
 * evt may be NULL; when not, it receives the event (for profiling). */
clvr_status clvr_cl_run1d(clvr_cl *cl, cl_kernel k, size_t n, size_t local, cl_event *evt, clvr_error *err);
/* The same over a w x h grid of work items in local[0] x local[1] groups
 * (each axis rounded up; the kernel must check its ids against w and h):
 * images. */
clvr_status clvr_cl_run2d(clvr_cl *cl, cl_kernel k, size_t w, size_t h, const size_t local[2], cl_event *evt,
                          clvr_error *err);

/* Seconds between start and end of a profiled event. */
double clvr_cl_event_seconds(cl_event e);

/* Reports a failed OpenCL call: sets err and returns CLVR_ERR_OPENCL (or
 * CLVR_ERR_DEVICE_MEMORY for allocation failures). */
clvr_status clvr_cl_fail(clvr_error *err, const char *call, cl_int code, const char *file, int line);

/* Checks an OpenCL return code inside a function that has `clvr_status s`,
 * `clvr_error *err` and a `cleanup:` label. */
#define CLVR_CL_CHECK(expr)                                                       \
    do {                                                                          \
        cl_int clvr_rc_ = (expr);                                                 \
        if (clvr_rc_ != CL_SUCCESS) {                                             \
            s = clvr_cl_fail(err, #expr, clvr_rc_, __FILE__, __LINE__);           \
            goto cleanup;                                                         \
        }                                                                         \
    } while (0)

/* Checks a clvr_status-returning call in the same setting. */
#define CLVR_TRY(expr)                                                            \
    do {                                                                          \
        s = (expr);                                                               \
        if (s != CLVR_OK) goto cleanup;                                           \
    } while (0)

/* Fault injection for tests: when the environment variable CLVR_FAIL names
 * an OpenCL entry point (e.g. "clBuildProgram" or "clCreateBuffer"), clvr's
 * wrappers report that call as failed. Returns nonzero when `call` must fail. */
int clvr_cl_fault(const char *call);

#endif /* CLVR_CL_CONTEXT_H */
