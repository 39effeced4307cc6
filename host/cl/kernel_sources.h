/* kernel_sources.h: the OpenCL sources of kernels/, embedded at build time
 * by tools/embed_kernels.cmake (see CLVR_KERNEL_FILES in CMakeLists.txt). */
#ifndef CLVR_KERNEL_SOURCES_H
#define CLVR_KERNEL_SOURCES_H

#include <stddef.h>

typedef struct clvr_source_file {
    const char *name;  /* file name relative to kernels/, e.g. "sort.cl" */
    const char *text;  /* NUL-terminated contents */
    size_t size;       /* bytes, without the terminator */
} clvr_source_file;

extern const clvr_source_file clvr_kernel_sources[]; /* terminated by {0,0,0} */
extern const unsigned clvr_kernel_source_count;

#endif
