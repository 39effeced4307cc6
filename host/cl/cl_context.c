#define _GNU_SOURCE /* madvise's MADV_HUGEPAGE */
#include "cl_context.h"
#include "kernel_sources.h"

#include <ctype.h>
#include <errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "clock.h"
#ifdef __linux__
#include <sys/mman.h>
#endif

const char *clvr_cl_error_name(cl_int code)
{
    switch (code) {
#define E(x) case x: return #x;
        E(CL_SUCCESS) E(CL_DEVICE_NOT_FOUND) E(CL_DEVICE_NOT_AVAILABLE) E(CL_COMPILER_NOT_AVAILABLE)
        E(CL_MEM_OBJECT_ALLOCATION_FAILURE) E(CL_OUT_OF_RESOURCES) E(CL_OUT_OF_HOST_MEMORY)
        E(CL_PROFILING_INFO_NOT_AVAILABLE) E(CL_MEM_COPY_OVERLAP) E(CL_IMAGE_FORMAT_MISMATCH)
        E(CL_IMAGE_FORMAT_NOT_SUPPORTED) E(CL_BUILD_PROGRAM_FAILURE) E(CL_MAP_FAILURE)
        E(CL_MISALIGNED_SUB_BUFFER_OFFSET) E(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
        E(CL_COMPILE_PROGRAM_FAILURE) E(CL_LINKER_NOT_AVAILABLE) E(CL_LINK_PROGRAM_FAILURE)
        E(CL_DEVICE_PARTITION_FAILED) E(CL_KERNEL_ARG_INFO_NOT_AVAILABLE) E(CL_INVALID_VALUE)
        E(CL_INVALID_DEVICE_TYPE) E(CL_INVALID_PLATFORM) E(CL_INVALID_DEVICE) E(CL_INVALID_CONTEXT)
        E(CL_INVALID_QUEUE_PROPERTIES) E(CL_INVALID_COMMAND_QUEUE) E(CL_INVALID_HOST_PTR)
        E(CL_INVALID_MEM_OBJECT) E(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR) E(CL_INVALID_IMAGE_SIZE)
        E(CL_INVALID_SAMPLER) E(CL_INVALID_BINARY) E(CL_INVALID_BUILD_OPTIONS) E(CL_INVALID_PROGRAM)
        E(CL_INVALID_PROGRAM_EXECUTABLE) E(CL_INVALID_KERNEL_NAME) E(CL_INVALID_KERNEL_DEFINITION)
        E(CL_INVALID_KERNEL) E(CL_INVALID_ARG_INDEX) E(CL_INVALID_ARG_VALUE) E(CL_INVALID_ARG_SIZE)
        E(CL_INVALID_KERNEL_ARGS) E(CL_INVALID_WORK_DIMENSION) E(CL_INVALID_WORK_GROUP_SIZE)
        E(CL_INVALID_WORK_ITEM_SIZE) E(CL_INVALID_GLOBAL_OFFSET) E(CL_INVALID_EVENT_WAIT_LIST)
        E(CL_INVALID_EVENT) E(CL_INVALID_OPERATION) E(CL_INVALID_GL_OBJECT) E(CL_INVALID_BUFFER_SIZE)
        E(CL_INVALID_MIP_LEVEL) E(CL_INVALID_GLOBAL_WORK_SIZE) E(CL_INVALID_PROPERTY)
        E(CL_INVALID_IMAGE_DESCRIPTOR) E(CL_INVALID_COMPILER_OPTIONS) E(CL_INVALID_LINKER_OPTIONS)
        E(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef E
    case -1001: return "CL_PLATFORM_NOT_FOUND_KHR (no OpenCL platform installed)";
    default: return "unknown OpenCL error";
    }
}

clvr_status clvr_cl_fail(clvr_error *err, const char *call, cl_int code, const char *file, int line)
{
    clvr_status st = (code == CL_MEM_OBJECT_ALLOCATION_FAILURE || code == CL_OUT_OF_RESOURCES ||
                      code == CL_INVALID_BUFFER_SIZE)
                         ? CLVR_ERR_DEVICE_MEMORY
                         : CLVR_ERR_OPENCL;
    const char *base = strrchr(file, '/');
    return clvr_error_set(err, st, "OpenCL call %s failed with %s (%d) at %s:%d%s", call, clvr_cl_error_name(code),
                          (int)code, base ? base + 1 : file, line,
                          st == CLVR_ERR_DEVICE_MEMORY
                              ? "; the device ran out of memory: try a smaller image or mesh, or another --device"
                              : "");
}

int clvr_cl_fault(const char *call)
{
    const char *f = getenv("CLVR_FAIL");
    return f && *f && strcmp(f, call) == 0;
}

/* Injected failures look exactly like the driver's: the wrappers below return
 * this code instead of calling the driver. */
#define CLVR_FAULT_CODE(call, code) (clvr_cl_fault(call) ? (code) : CL_SUCCESS)

/* ------------------------------------------------------------ enumeration */

typedef struct device_entry {
    cl_platform_id platform;
    cl_device_id device;
    unsigned p, d;
    char platform_name[256];
    char device_name[256];
    cl_device_type type;
} device_entry;

/* Lists all devices of all platforms into a malloc'ed array. */
static clvr_status enumerate(device_entry **out, unsigned *count, clvr_error *err)
{
    cl_uint np = 0;
    cl_platform_id *plats = NULL;
    device_entry *list = NULL;
    unsigned n = 0, cap = 0;
    clvr_status s = CLVR_OK;
    cl_int rc = CLVR_FAULT_CODE("clGetPlatformIDs", -1001);
    if (rc == CL_SUCCESS) rc = clGetPlatformIDs(0, NULL, &np);
    if (rc == -1001 || (rc == CL_SUCCESS && np == 0)) {
        s = clvr_error_set(err, CLVR_ERR_NO_DEVICE,
                           "no OpenCL platform is installed; install one, e.g. PoCL for the CPU "
                           "(tools/setup-debian.sh, or apt-get install pocl-opencl-icd)");
        goto cleanup;
    }
    CLVR_CL_CHECK(rc);
    plats = calloc(np, sizeof *plats);
    if (!plats) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory listing platforms"); goto cleanup; }
    CLVR_CL_CHECK(clGetPlatformIDs(np, plats, NULL));
    for (cl_uint p = 0; p < np; ++p) {
        cl_uint nd = 0;
        char pname[256] = "";
        clGetPlatformInfo(plats[p], CL_PLATFORM_NAME, sizeof pname, pname, NULL);
        if (clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, 0, NULL, &nd) != CL_SUCCESS || nd == 0) continue;
        cl_device_id *devs = calloc(nd, sizeof *devs);
        if (!devs) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory listing devices"); goto cleanup; }
        if (clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, nd, devs, NULL) != CL_SUCCESS) nd = 0;
        for (cl_uint d = 0; d < nd; ++d) {
            if (n == cap) {
                cap = cap ? 2 * cap : 8;
                device_entry *grown = realloc(list, cap * sizeof *list);
                if (!grown) { free(devs); s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory"); goto cleanup; }
                list = grown;
            }
            device_entry *e = &list[n++];
            memset(e, 0, sizeof *e);
            e->platform = plats[p];
            e->device = devs[d];
            e->p = p;
            e->d = d;
            snprintf(e->platform_name, sizeof e->platform_name, "%s", pname);
            clGetDeviceInfo(devs[d], CL_DEVICE_NAME, sizeof e->device_name, e->device_name, NULL);
            clGetDeviceInfo(devs[d], CL_DEVICE_TYPE, sizeof e->type, &e->type, NULL);
        }
        free(devs);
    }
    if (n == 0)
        s = clvr_error_set(err, CLVR_ERR_NO_DEVICE,
                           "OpenCL platforms exist but none has a device; install a driver, e.g. pocl-opencl-icd");
cleanup:
    free(plats);
    if (s != CLVR_OK) { free(list); list = NULL; n = 0; }
    *out = list;
    *count = n;
    return s;
}

static const char *type_name(cl_device_type t)
{
    if (t & CL_DEVICE_TYPE_GPU) return "GPU";
    if (t & CL_DEVICE_TYPE_CPU) return "CPU";
    if (t & CL_DEVICE_TYPE_ACCELERATOR) return "accelerator";
    return "other";
}

clvr_status clvr_cl_list_devices(FILE *out, clvr_error *err)
{
    device_entry *list;
    unsigned n;
    clvr_status s = enumerate(&list, &n, err);
    if (s != CLVR_OK) return s;
    cl_platform_id last = NULL;
    for (unsigned i = 0; i < n; ++i) {
        const device_entry *e = &list[i];
        if (e->platform != last) {
            char vendor[256] = "", version[256] = "";
            clGetPlatformInfo(e->platform, CL_PLATFORM_VENDOR, sizeof vendor, vendor, NULL);
            clGetPlatformInfo(e->platform, CL_PLATFORM_VERSION, sizeof version, version, NULL);
            fprintf(out, "platform %u: %s (%s, %s)\n", e->p, e->platform_name, vendor, version);
            last = e->platform;
        }
        char vendor[256] = "", version[256] = "", driver[256] = "";
        cl_uint cu = 0;
        cl_ulong mem = 0, alloc = 0;
        clGetDeviceInfo(e->device, CL_DEVICE_VENDOR, sizeof vendor, vendor, NULL);
        clGetDeviceInfo(e->device, CL_DEVICE_VERSION, sizeof version, version, NULL);
        clGetDeviceInfo(e->device, CL_DRIVER_VERSION, sizeof driver, driver, NULL);
        clGetDeviceInfo(e->device, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof cu, &cu, NULL);
        clGetDeviceInfo(e->device, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof mem, &mem, NULL);
        clGetDeviceInfo(e->device, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof alloc, &alloc, NULL);
        fprintf(out,
                "  device %u:%u  %s\n"
                "      type %s, vendor %s, %s, driver %s\n"
                "      %u compute units, %.2f GiB global memory, %.2f GiB max allocation\n",
                e->p, e->d, e->device_name, type_name(e->type), vendor, version, driver, cu,
                (double)mem / (1024.0 * 1024.0 * 1024.0), (double)alloc / (1024.0 * 1024.0 * 1024.0));
    }
    free(list);
    return CLVR_OK;
}

static int contains_nocase(const char *hay, const char *needle)
{
    size_t nl = strlen(needle);
    for (const char *h = hay; *h; ++h) {
        size_t k = 0;
        while (k < nl && h[k] && tolower((unsigned char)h[k]) == tolower((unsigned char)needle[k])) ++k;
        if (k == nl) return 1;
    }
    return nl == 0;
}

static int is_pocl_platform(const char *platform_name)
{
    return contains_nocase(platform_name, "portable computing language") || contains_nocase(platform_name, "pocl");
}

static int is_pocl(const device_entry *e) { return is_pocl_platform(e->platform_name); }

/* Returns the index of the device matching spec, or -1. */
static int pick(const device_entry *list, unsigned n, const char *spec)
{
    if (!spec || !*spec) {
        for (unsigned i = 0; i < n; ++i) if (list[i].type & CL_DEVICE_TYPE_GPU) return (int)i;
        for (unsigned i = 0; i < n; ++i) if (is_pocl(&list[i])) return (int)i;
        return n ? 0 : -1;
    }
    unsigned p, d;
    char tail;
    if (sscanf(spec, "%u:%u%c", &p, &d, &tail) == 2) {
        for (unsigned i = 0; i < n; ++i) if (list[i].p == p && list[i].d == d) return (int)i;
        return -1;
    }
    if (strcmp(spec, "pocl") == 0) {
        for (unsigned i = 0; i < n; ++i) if (is_pocl(&list[i])) return (int)i;
        return -1;
    }
    if (strcmp(spec, "gpu") == 0 || strcmp(spec, "cpu") == 0) {
        cl_device_type want = spec[0] == 'g' ? CL_DEVICE_TYPE_GPU : CL_DEVICE_TYPE_CPU;
        for (unsigned i = 0; i < n; ++i) if (list[i].type & want) return (int)i;
        return -1;
    }
    for (unsigned i = 0; i < n; ++i)
        if (contains_nocase(list[i].device_name, spec) || contains_nocase(list[i].platform_name, spec)) return (int)i;
    return -1;
}

/* CLVR_MAX_ALLOC_BYTES (a testing knob, docs/large-meshes.md): a byte
 * count that can only lower the largest buffer clvr allocates, so that a
 * small mesh is cut into several pieces as a large one is on a device with
 * a small CL_DEVICE_MAX_MEM_ALLOC_SIZE. Unset or empty: the device's. */
static clvr_status max_alloc_override(clvr_cl *cl, clvr_error *err)
{
    const char *env = getenv("CLVR_MAX_ALLOC_BYTES");
    if (!env || !*env) return CLVR_OK;
    char *end = NULL;
    errno = 0;
    const unsigned long long v = strtoull(env, &end, 10);
    if (errno || end == env || *end || v < 16 || env[0] == '-')
        return clvr_error_set(err, CLVR_ERR_USAGE,
                              "CLVR_MAX_ALLOC_BYTES is '%s'; give a byte count of at least 16 (e.g. 1000000000), or "
                              "unset it to use the device's CL_DEVICE_MAX_MEM_ALLOC_SIZE",
                              env);
    if ((cl_ulong)v < cl->max_alloc_bytes) cl->max_alloc_bytes = (cl_ulong)v;
    return CLVR_OK;
}

clvr_status clvr_cl_create(const char *spec, clvr_cl *out, clvr_error *err)
{
    device_entry *list = NULL;
    unsigned n = 0;
    clvr_status s;
    cl_int rc;
    memset(out, 0, sizeof *out);
    out->kernel_dir = getenv("CLVR_KERNEL_DIR");
    if (out->kernel_dir && !*out->kernel_dir) out->kernel_dir = NULL;
    CLVR_TRY(enumerate(&list, &n, err));
    int i = pick(list, n, spec);
    if (i < 0) {
        char avail[768] = "";
        size_t used = 0;
        for (unsigned k = 0; k < n && used < sizeof avail - 1; ++k)
            used += (size_t)snprintf(avail + used, sizeof avail - used, "%s%u:%u %s (%s)", k ? "; " : "", list[k].p,
                                     list[k].d, list[k].device_name, list[k].platform_name);
        s = clvr_error_set(err, CLVR_ERR_NO_DEVICE,
                           "--device %s matches no OpenCL device; available: %s (see clvr --list-devices)", spec,
                           avail);
        goto cleanup;
    }
    out->platform = list[i].platform;
    out->device = list[i].device;
    out->device_type = list[i].type;
    snprintf(out->platform_name, sizeof out->platform_name, "%s", list[i].platform_name);
    snprintf(out->device_name, sizeof out->device_name, "%s", list[i].device_name);
    clGetDeviceInfo(out->device, CL_DEVICE_VERSION, sizeof out->device_version, out->device_version, NULL);
    clGetDeviceInfo(out->device, CL_DRIVER_VERSION, sizeof out->driver_version, out->driver_version, NULL);
    CLVR_CL_CHECK(clGetDeviceInfo(out->device, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof out->global_mem_bytes,
                                  &out->global_mem_bytes, NULL));
    CLVR_CL_CHECK(clGetDeviceInfo(out->device, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof out->max_alloc_bytes,
                                  &out->max_alloc_bytes, NULL));
    out->device_max_alloc_bytes = out->max_alloc_bytes;
    CLVR_TRY(max_alloc_override(out, err));
    CLVR_CL_CHECK(clGetDeviceInfo(out->device, CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof out->max_work_group_size,
                                  &out->max_work_group_size, NULL));
    CLVR_CL_CHECK(clGetDeviceInfo(out->device, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof out->compute_units,
                                  &out->compute_units, NULL));
    cl_device_fp_config fp = 0;
    if (clGetDeviceInfo(out->device, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, NULL) == CL_SUCCESS)
        out->fp32_correct_div_sqrt = (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
    rc = CLVR_FAULT_CODE("clCreateContext", CL_OUT_OF_HOST_MEMORY);
    if (rc == CL_SUCCESS) out->context = clCreateContext(NULL, 1, &out->device, NULL, NULL, &rc);
    CLVR_CL_CHECK(rc);
    out->queue = clCreateCommandQueue(out->context, out->device, CL_QUEUE_PROFILING_ENABLE, &rc);
    CLVR_CL_CHECK(rc);
cleanup:
    free(list);
    if (s != CLVR_OK) clvr_cl_destroy(out);
    return s;
}

void clvr_cl_destroy(clvr_cl *cl)
{
    if (!cl) return;
    if (cl->queue) clReleaseCommandQueue(cl->queue);
    if (cl->context) clReleaseContext(cl->context);
    cl->queue = NULL;
    cl->context = NULL;
}

/* ------------------------------------------------------------ programs */

typedef struct strbuf {
    char *p;
    size_t n, cap;
} strbuf;

static int sb_append(strbuf *b, const char *s, size_t n)
{
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + n + 1) cap *= 2;
        char *q = realloc(b->p, cap);
        if (!q) return 1;
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->n, s, n);
    b->n += n;
    b->p[b->n] = 0;
    return 0;
}

static int sb_printf(strbuf *b, const char *fmt, ...)
{
    char tmp[1024];
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    return k < 0 ? 1 : sb_append(b, tmp, (size_t)k < sizeof tmp ? (size_t)k : sizeof tmp - 1);
}

/* Reads kernels/<name> from disk (developer mode) or the embedded table.
 * Returns malloc'ed text or NULL. */
static char *read_source(const clvr_cl *cl, const char *name)
{
    if (cl->kernel_dir) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", cl->kernel_dir, name);
        FILE *f = fopen(path, "rb");
        if (!f) return NULL;
        strbuf b = {0};
        char chunk[65536];
        size_t k;
        while ((k = fread(chunk, 1, sizeof chunk, f)) > 0)
            if (sb_append(&b, chunk, k)) { free(b.p); fclose(f); return NULL; }
        fclose(f);
        if (!b.p) sb_append(&b, "", 0);
        return b.p;
    }
    for (unsigned i = 0; i < clvr_kernel_source_count; ++i)
        if (strcmp(clvr_kernel_sources[i].name, name) == 0) {
            char *t = malloc(clvr_kernel_sources[i].size + 1);
            if (t) memcpy(t, clvr_kernel_sources[i].text, clvr_kernel_sources[i].size + 1);
            return t;
        }
    return NULL;
}

/* Where line n (1-based) of the expanded source came from, read off its
 * #line markers: the file into f and its line into *line. 0 when line n is
 * a marker or past the end. */
static int source_origin(const char *src, unsigned long n, char *f, size_t fsz, unsigned long *line)
{
    unsigned long at = 1;
    f[0] = 0;
    const char *p = src;
    for (unsigned long i = 1; *p; ++i) {
        const char *eol = strchr(p, '\n');
        unsigned long l;
        char name[256];
        if (strncmp(p, "#line ", 6) == 0 && sscanf(p, "#line %lu \"%255[^\"\n]\"", &l, name) == 2) {
            if (i == n) return 0;
            snprintf(f, fsz, "%s", name);
            at = l;
        } else {
            if (i == n) {
                *line = at;
                return f[0] != 0;
            }
            ++at;
        }
        if (!eol) break;
        p = eol + 1;
    }
    return 0;
}

/* See cl_context.h: FILE:LINE as PoCL, which honours #line, writes it. */
char *clvr_cl_map_build_log(const char *src, const char *log)
{
    static const char *const tags[] = {"<kernel>:", "<source>:"};
    strbuf out = {0};
    const char *p = log;
    int oom = sb_append(&out, "", 0);
    while (*p && !oom) {
        size_t tl = 0;
        for (size_t t = 0; t < sizeof tags / sizeof tags[0]; ++t)
            if (strncmp(p, tags[t], strlen(tags[t])) == 0) tl = strlen(tags[t]);
        char *end = NULL;
        unsigned long n = tl && isdigit((unsigned char)p[tl]) ? strtoul(p + tl, &end, 10) : 0;
        char f[256];
        unsigned long line = 0;
        if (n && *end == ':' && source_origin(src, n, f, sizeof f, &line)) {
            oom = sb_printf(&out, "%s:%lu", f, line);
            p = end;
        } else {
            oom = sb_append(&out, p, 1);
            ++p;
        }
    }
    if (oom) {
        free(out.p);
        return NULL;
    }
    return out.p;
}

/* Expands local `#include "x"` lines recursively (each file once, like
 * #pragma once), framing every file with #line markers. */
static clvr_status expand(const clvr_cl *cl, const char *name, strbuf *out, strbuf *seen, int depth, clvr_error *err)
{
    if (depth > 16) return clvr_error_set(err, CLVR_ERR_KERNEL_BUILD, "kernels/%s: includes nest too deeply", name);
    char key[300];
    snprintf(key, sizeof key, "|%s|", name);
    if (seen->p && strstr(seen->p, key)) return CLVR_OK;
    if (sb_append(seen, key, strlen(key))) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory");
    char *text = read_source(cl, name);
    if (!text)
        return clvr_error_set(err, CLVR_ERR_KERNEL_BUILD, "kernel source kernels/%s not found%s%s", name,
                              cl->kernel_dir ? " in CLVR_KERNEL_DIR=" : " among the embedded sources",
                              cl->kernel_dir ? cl->kernel_dir : "");
    clvr_status s = CLVR_OK;
    int line = 1;
    sb_printf(out, "#line 1 \"%s\"\n", name);
    for (char *p = text; *p && s == CLVR_OK;) {
        char *eol = strchr(p, '\n');
        size_t len = eol ? (size_t)(eol - p) : strlen(p);
        const char *q = p;
        while (q < p + len && (*q == ' ' || *q == '\t')) ++q;
        char inc[256];
        if (sscanf(q, "#include \"%255[^\"]\"", inc) == 1) {
            s = expand(cl, inc, out, seen, depth + 1, err);
            sb_printf(out, "#line %d \"%s\"\n", line + 1, name);
        } else {
            if (sb_append(out, p, len) || sb_append(out, "\n", 1))
                s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory");
        }
        ++line;
        p = eol ? eol + 1 : p + len;
    }
    free(text);
    return s;
}

/* The driver's compiler may write to the process's stderr (PoCL's clang
 * prints "N warnings generated." there, outside the build log). A build
 * runs with fd 2 pointed at a temporary file, so nothing of it reaches the
 * user; the text is kept for the error message and CLVR_BUILD_LOG. */
typedef struct stderr_capture {
    int saved;  /* dup of the real stderr, -1 when not capturing */
    FILE *file; /* where fd 2 points meanwhile */
} stderr_capture;

static void capture_begin(stderr_capture *c)
{
    c->saved = -1;
    c->file = tmpfile();
    if (!c->file) return; /* cannot capture: the compiler may speak */
    fflush(stderr);
    c->saved = dup(2);
    if (c->saved < 0 || dup2(fileno(c->file), 2) < 0) {
        if (c->saved >= 0) close(c->saved);
        c->saved = -1;
        fclose(c->file);
        c->file = NULL;
    }
}

/* Restores stderr; returns what was written meanwhile (caller frees), or NULL. */
static char *capture_end(stderr_capture *c)
{
    char *text = NULL;
    if (c->saved < 0) return NULL;
    fflush(stderr);
    dup2(c->saved, 2);
    close(c->saved);
    c->saved = -1;
    long n = ftell(c->file);
    if (n > 0 && fseek(c->file, 0, SEEK_SET) == 0 && (text = malloc((size_t)n + 1))) {
        size_t got = fread(text, 1, (size_t)n, c->file);
        text[got] = 0;
    }
    fclose(c->file);
    c->file = NULL;
    return text;
}

/* Prints the compiling notice from a helper thread when the build outlasts
 * CLVR_BUILD_NOTICE_S: only then is it a compilation the user waits for;
 * once per context (`quiet` after that), and then every
 * CLVR_BUILD_PROGRESS_S while this build lasts, naming it: NVIDIA's driver
 * takes minutes on a cold cache. It writes to the real stderr (fd 2 is
 * captured meanwhile). */
#define CLVR_BUILD_PROGRESS_S 20
typedef struct build_notice {
    pthread_mutex_t lock;
    pthread_cond_t done_cv;
    int done, shown, fd, quiet;
    const char *entry;
} build_notice;

static void *notice_main(void *arg)
{
    build_notice *n = arg;
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    long ns = until.tv_nsec + (long)(CLVR_BUILD_NOTICE_S * 1e9);
    until.tv_sec += ns / 1000000000L;
    until.tv_nsec = ns % 1000000000L;
    pthread_mutex_lock(&n->lock);
    for (long waited = 0;; waited += CLVR_BUILD_PROGRESS_S, until.tv_sec += CLVR_BUILD_PROGRESS_S) {
        while (!n->done && pthread_cond_timedwait(&n->done_cv, &n->lock, &until) != ETIMEDOUT) {}
        if (n->done) break;
        char msg[160];
        const int len = !waited ? snprintf(msg, sizeof msg, "clvr: compiling kernels (cached for next time)\n")
                                : snprintf(msg, sizeof msg, "clvr: still compiling kernels/%s (%ld s)\n", n->entry,
                                           waited);
        if ((waited || !n->quiet) && write(n->fd, msg, (size_t)len) > 0 && !waited) n->shown = 1;
    }
    pthread_mutex_unlock(&n->lock);
    return NULL;
}

clvr_status clvr_cl_build(clvr_cl *cl, const char *entry, const char *options, cl_program *out, clvr_error *err)
{
    strbuf src = {0}, seen = {0}, opts = {0};
    cl_program prog = NULL;
    clvr_status s = CLVR_OK;
    cl_int rc;
    *out = NULL;
    CLVR_TRY(expand(cl, entry, &src, &seen, 0, err));
    const char *text = src.p;
    prog = clCreateProgramWithSource(cl->context, 1, &text, NULL, &rc);
    CLVR_CL_CHECK(rc);
    /* CLVR_DEVICE_PREFETCH: the kernels' CLVR_PREFETCH is a real prefetch
     * (kernels/clvr_shared.h) on PoCL's CPU devices alone. CLVR_DEVICE_SIMD
     * there too: a work-item's float4 arithmetic runs on SIMD lanes, so
     * point location tests four tets at once (kernels/locate.h). */
    const int pocl_cpu = (cl->device_type & CL_DEVICE_TYPE_CPU) && is_pocl_platform(cl->platform_name);
    /* CLVR_BUILD_OPTIONS (developers): more options for every program, e.g.
     * NVIDIA's -cl-nv-verbose, whose registers and spills CLVR_BUILD_LOG=1
     * then prints. */
    const char *extra = getenv("CLVR_BUILD_OPTIONS");
    sb_printf(&opts, "-cl-std=CL1.2 -DCLVR_WG=%u%s%s %s %s", (unsigned)(cl->max_work_group_size < 256 ? cl->max_work_group_size : 256),
              pocl_cpu ? " -DCLVR_DEVICE_PREFETCH -DCLVR_DEVICE_SIMD" : "",
              cl->fp32_correct_div_sqrt ? " -cl-fp32-correctly-rounded-divide-sqrt" : "", options ? options : "",
              extra ? extra : "");
    rc = CLVR_FAULT_CODE("clBuildProgram", CL_BUILD_PROGRAM_FAILURE);
    char *compiler_said = NULL;
    if (rc == CL_SUCCESS) {
        const int debug = getenv("CLVR_BUILD_LOG") && strcmp(getenv("CLVR_BUILD_LOG"), "0") != 0;
        stderr_capture cap;
        build_notice notice = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, 0, 0, 2, 0, entry};
        pthread_t notice_thread;
        int notice_running = 0;
        double t0 = clvr_clock_monotonic_s();
        capture_begin(&cap);
        if (cl->build_notice) {
            notice.fd = cap.saved >= 0 ? cap.saved : 2;
            notice.quiet = cl->build_notice_shown;
            notice_running = pthread_create(&notice_thread, NULL, notice_main, &notice) == 0;
        }
        rc = clBuildProgram(prog, 1, &cl->device, opts.p, NULL, NULL);
        if (notice_running) {
            pthread_mutex_lock(&notice.lock);
            notice.done = 1;
            pthread_cond_signal(&notice.done_cv);
            pthread_mutex_unlock(&notice.lock);
            pthread_join(notice_thread, NULL);
            cl->build_notice_shown |= notice.shown;
        }
        compiler_said = capture_end(&cap);
        cl->build_s += clvr_clock_monotonic_s() - t0;
        if (debug && rc == CL_SUCCESS) {
            size_t ls = 0;
            clGetProgramBuildInfo(prog, cl->device, CL_PROGRAM_BUILD_LOG, 0, NULL, &ls);
            char *blog = malloc(ls + 1);
            if (blog) {
                blog[0] = 0;
                clGetProgramBuildInfo(prog, cl->device, CL_PROGRAM_BUILD_LOG, ls, blog, NULL);
                blog[ls] = 0;
            }
            fprintf(stderr, "clvr: CLVR_BUILD_LOG: kernels/%s built in %.2f s; build log:\n%s\n%s%s", entry,
                    clvr_clock_monotonic_s() - t0, blog ? blog : "", compiler_said ? "compiler stderr:\n" : "",
                    compiler_said ? compiler_said : "");
            free(blog);
        }
    }
    if (rc != CL_SUCCESS) {
        size_t logsize = 0;
        clGetProgramBuildInfo(prog, cl->device, CL_PROGRAM_BUILD_LOG, 0, NULL, &logsize);
        char *log = malloc(logsize + 64); /* room for the injected-failure note */
        if (log) {
            log[0] = 0;
            clGetProgramBuildInfo(prog, cl->device, CL_PROGRAM_BUILD_LOG, logsize, log, NULL);
            log[logsize] = 0;
        }
        if (clvr_cl_fault("clBuildProgram") && log) snprintf(log, logsize + 64, "%s", "(injected by CLVR_FAIL)");
        char *mapped = log ? clvr_cl_map_build_log(src.p, log) : NULL;
        if (mapped) {
            free(log);
            log = mapped;
        }
        s = clvr_error_set(err, CLVR_ERR_KERNEL_BUILD, "building kernels/%s for %s failed (%s):\n%s%s", entry,
                           cl->device_name, clvr_cl_error_name(rc), log && *log ? log : "(empty build log)",
                           compiler_said && !(log && *log) ? compiler_said : "");
        free(log);
        free(compiler_said);
        goto cleanup;
    }
    free(compiler_said);
    *out = prog;
    prog = NULL;
cleanup:
    if (prog) clReleaseProgram(prog);
    free(src.p);
    free(seen.p);
    free(opts.p);
    return s;
}

clvr_status clvr_cl_kernel(cl_program prog, const char *name, cl_kernel *out, clvr_error *err)
{
    cl_int rc;
    *out = clCreateKernel(prog, name, &rc);
    if (rc != CL_SUCCESS) {
        *out = NULL;
        return clvr_error_set(err, CLVR_ERR_OPENCL, "clCreateKernel(%s) failed with %s", name, clvr_cl_error_name(rc));
    }
    return CLVR_OK;
}

clvr_status clvr_cl_set_args(cl_kernel k, const clvr_cl_arg *args, size_t n, clvr_error *err)
{
    for (size_t i = 0; i < n; ++i) {
        cl_int rc = CLVR_FAULT_CODE("clSetKernelArg", CL_INVALID_ARG_VALUE);
        if (rc == CL_SUCCESS) rc = clSetKernelArg(k, (cl_uint)i, args[i].size, args[i].value);
        if (rc != CL_SUCCESS) {
            /* The name is looked up only now: a failure is a bug to find. */
            char name[128] = "?";
            if (clGetKernelInfo(k, CL_KERNEL_FUNCTION_NAME, sizeof name, name, NULL) != CL_SUCCESS)
                snprintf(name, sizeof name, "?");
            return clvr_error_set(err, CLVR_ERR_OPENCL, "clSetKernelArg(%s, argument %zu of %zu, %zu bytes) failed with %s",
                                  name, i, n, args[i].size, clvr_cl_error_name(rc));
        }
    }
    return CLVR_OK;
}

/* ------------------------------------------------------------ buffers */

#if defined(__linux__) && defined(MADV_HUGEPAGE)
#define CLVR_HUGE_PAGE ((size_t)2 << 20)
static void CL_CALLBACK free_host_memory(cl_mem mem, void *p)
{
    (void)mem;
    free(p);
}

/* On a CPU device a buffer is host memory, and a fresh buffer of 4 KiB
 * pages faults into the kernel on the first touch of every page: profiling
 * the preprocessing of 10M hexes under PoCL put ~19% of its time in page
 * faults (70% of the gather kernel's). So on CPU devices clvr allocates big
 * buffers itself, asks Linux for transparent huge pages (512x fewer faults),
 * hands the memory to the driver with CL_MEM_USE_HOST_PTR, and frees it in
 * the buffer's destructor callback. Returns NULL (the caller falls back to
 * the driver's allocation) when that does not apply or fails. */
static cl_mem huge_page_buffer(clvr_cl *cl, cl_mem_flags flags, size_t bytes, void *host_ptr, cl_int *rc)
{
    if (!(cl->device_type & CL_DEVICE_TYPE_CPU) || bytes < CLVR_HUGE_PAGE ||
        (flags & (CL_MEM_USE_HOST_PTR | CL_MEM_ALLOC_HOST_PTR)))
        return NULL;
    /* CLVR_HUGE_PAGES=0 leaves every buffer to the driver (for comparisons,
     * or where huge pages are unwelcome). */
    const char *env = getenv("CLVR_HUGE_PAGES");
    if (env && !strcmp(env, "0")) return NULL;
    size_t rounded = (bytes + CLVR_HUGE_PAGE - 1) / CLVR_HUGE_PAGE * CLVR_HUGE_PAGE;
    void *p = aligned_alloc(CLVR_HUGE_PAGE, rounded);
    if (!p) return NULL;
    madvise(p, rounded, MADV_HUGEPAGE); /* advice only: 4 KiB pages still work */
    if (flags & CL_MEM_COPY_HOST_PTR) memcpy(p, host_ptr, bytes);
    flags = (flags & ~(cl_mem_flags)CL_MEM_COPY_HOST_PTR) | CL_MEM_USE_HOST_PTR;
    cl_mem m = clCreateBuffer(cl->context, flags, bytes, p, rc);
    if (*rc != CL_SUCCESS) { free(p); return NULL; }
    if (clSetMemObjectDestructorCallback(m, free_host_memory, p) != CL_SUCCESS) {
        /* Without the callback the memory could not be freed safely. */
        clReleaseMemObject(m);
        free(p);
        return NULL;
    }
    return m;
}
#else
static cl_mem huge_page_buffer(clvr_cl *cl, cl_mem_flags flags, size_t bytes, void *host_ptr, cl_int *rc)
{
    (void)cl, (void)flags, (void)bytes, (void)host_ptr, (void)rc;
    return NULL;
}
#endif

clvr_status clvr_cl_buffer(clvr_cl *cl, cl_mem_flags flags, size_t bytes, void *host_ptr, const char *what,
                           cl_mem *out, clvr_error *err)
{
    cl_int rc;
    size_t n = bytes ? bytes : 16;
    *out = NULL;
    if ((cl_ulong)n > cl->max_alloc_bytes)
        return clvr_error_set(err, CLVR_ERR_DEVICE_MEMORY,
                              "%s needs %.3f GB in one buffer but %s allows at most %.3f GB per buffer "
                              "(CL_DEVICE_MAX_MEM_ALLOC_SIZE%s); use a smaller mesh or image, or another --device",
                              what, (double)n / 1e9, cl->device_name, (double)cl->max_alloc_bytes / 1e9,
                              cl->device_max_alloc_bytes > cl->max_alloc_bytes ? ", lowered by CLVR_MAX_ALLOC_BYTES"
                                                                               : "");
    if ((cl_ulong)n + cl->allocated_bytes > cl->global_mem_bytes)
        return clvr_error_set(err, CLVR_ERR_DEVICE_MEMORY,
                              "%s needs %.3f GB more device memory but %s has %.3f GB and %.3f GB is in use; "
                              "use a smaller mesh or image, or another --device",
                              what, (double)n / 1e9, cl->device_name, (double)cl->global_mem_bytes / 1e9,
                              (double)cl->allocated_bytes / 1e9);
    /* An empty input has nothing to copy: a 16-byte placeholder without the
     * host-pointer flags (which require a non-NULL pointer). */
    if (bytes == 0) flags &= ~(cl_mem_flags)(CL_MEM_COPY_HOST_PTR | CL_MEM_USE_HOST_PTR);
    rc = CLVR_FAULT_CODE("clCreateBuffer", CL_MEM_OBJECT_ALLOCATION_FAILURE);
    if (rc == CL_SUCCESS && !(*out = huge_page_buffer(cl, flags, bytes, host_ptr, &rc)))
        *out = clCreateBuffer(cl->context, flags, n, bytes ? host_ptr : NULL, &rc);
    if (rc != CL_SUCCESS) {
        *out = NULL;
        return clvr_error_set(err, CLVR_ERR_DEVICE_MEMORY, "clCreateBuffer for %s (%.3f GB) failed with %s on %s",
                              what, (double)n / 1e9, clvr_cl_error_name(rc), cl->device_name);
    }
    cl->allocated_bytes += n;
    return CLVR_OK;
}

void clvr_cl_release(clvr_cl *cl, cl_mem *buf)
{
    if (!buf || !*buf) return;
    size_t n = 0;
    if (clGetMemObjectInfo(*buf, CL_MEM_SIZE, sizeof n, &n, NULL) == CL_SUCCESS && cl && cl->allocated_bytes >= n)
        cl->allocated_bytes -= n;
    clReleaseMemObject(*buf);
    *buf = NULL;
}

clvr_status clvr_cl_run1d(clvr_cl *cl, cl_kernel k, size_t n, size_t local, cl_event *evt, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (evt) *evt = NULL;
    if (n == 0) return CLVR_OK;
    if (local == 0) local = 64;
    size_t global = (n + local - 1) / local * local;
    cl_int rc = CLVR_FAULT_CODE("clEnqueueNDRangeKernel", CL_OUT_OF_RESOURCES);
    if (rc == CL_SUCCESS) rc = clEnqueueNDRangeKernel(cl->queue, k, 1, NULL, &global, &local, 0, NULL, evt);
    if (rc != CL_SUCCESS) {
        /* Name the kernel: "clEnqueueNDRangeKernel(clvr_sort_scatter, 1031 work items)". */
        char name[128] = "?", call[192];
        clGetKernelInfo(k, CL_KERNEL_FUNCTION_NAME, sizeof name, name, NULL);
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(%s, %zu work items)", name, n);
        s = clvr_cl_fail(err, call, rc, __FILE__, __LINE__);
    }
    return s;
}

clvr_status clvr_cl_run2d(clvr_cl *cl, cl_kernel k, size_t w, size_t h, const size_t local[2], cl_event *evt,
                          clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (evt) *evt = NULL;
    if (w == 0 || h == 0) return CLVR_OK;
    size_t global[2] = {(w + local[0] - 1) / local[0] * local[0], (h + local[1] - 1) / local[1] * local[1]};
    cl_int rc = CLVR_FAULT_CODE("clEnqueueNDRangeKernel", CL_OUT_OF_RESOURCES);
    if (rc == CL_SUCCESS) rc = clEnqueueNDRangeKernel(cl->queue, k, 2, NULL, global, local, 0, NULL, evt);
    if (rc != CL_SUCCESS) {
        /* "clEnqueueNDRangeKernel(clvr_render_frame, 512x512)". */
        char name[128] = "?", call[192];
        clGetKernelInfo(k, CL_KERNEL_FUNCTION_NAME, sizeof name, name, NULL);
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(%s, %zux%zu)", name, w, h);
        s = clvr_cl_fail(err, call, rc, __FILE__, __LINE__);
    }
    return s;
}

double clvr_cl_event_seconds(cl_event e)
{
    cl_ulong t0 = 0, t1 = 0;
    if (!e) return 0.0;
    clWaitForEvents(1, &e);
    clGetEventProfilingInfo(e, CL_PROFILING_COMMAND_START, sizeof t0, &t0, NULL);
    clGetEventProfilingInfo(e, CL_PROFILING_COMMAND_END, sizeof t1, &t1, NULL);
    return t1 > t0 ? (double)(t1 - t0) * 1e-9 : 0.0;
}
