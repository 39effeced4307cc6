/* limits_check.h: what a mesh asks of the device and of the renderer, checked
 * before any long work starts.
 *
 * clvr_limits_check estimates the device memory of the whole run from the
 * mesh counts alone (no OpenCL call) and refuses, with the numbers, a mesh
 * or image the device cannot hold, instead of failing minutes later in the
 * middle of preprocessing. clvr_limits_scan looks for elements the renderer
 * tolerates but the user should hear about: degenerate (zero-volume),
 * inverted and duplicate elements, and a constant scalar field.
 *
 * Where main() calls them: clvr_limits_scan right after the mesh is loaded
 * (it needs a validated mesh), clvr_limits_check right after clvr_cl_create
 * and before clvr_preprocess. Errors and warnings name the file. */
#ifndef CLVR_LIMITS_CHECK_H
#define CLVR_LIMITS_CHECK_H

#include <stdint.h>
#include <stdio.h>

#include "cl_context.h"
#include "mesh.h"
#include "preprocess.h"
#include "status.h"

/* Device bytes of a run, from counts only. The preprocessing peak is the
 * figure clvr_preprocess documents (40 bytes per index slot + 36 per element
 * + 16 per vertex), which covers its sort (keys and values twice), the
 * gathered index list and the split tables alive at the same time. What
 * stays for rendering: clustered vertices (float4, at least one per mesh
 * vertex), 16-bit local indices (2 per slot), leaf boxes (32 bytes per
 * leaf), instances and sampling clusters, the BVH (about one 112-byte node
 * per 3 leaves), and the image buffers (accumulator, second moments,
 * controls, the image read, counters: 76 bytes per pixel). Every figure is a lower bound on what the
 * pipeline allocates, so a refusal is never a false alarm. */
typedef struct clvr_limits_estimate {
    uint64_t num_elements, num_slots, num_vertices;
    uint64_t preprocess_peak_bytes;  /* device bytes at the peak of clvr_preprocess */
    uint64_t render_bytes;           /* clustered mesh + BVH + image buffers while rendering */
    uint64_t image_bytes;            /* of render_bytes: the per-pixel buffers */
    uint64_t peak_bytes;             /* max of the two phases */
    uint64_t largest_buffer_bytes;   /* the largest array of the run (split or not) */
    const char *largest_buffer;      /* its name, as clvr_cl_buffer reports it */
    /* The arrays of instance clusters (local indices, element boxes) of a
     * mesh preprocessed in more than one partition are cut into pieces at
     * instance boundaries (docs/large-meshes.md); of one partition they are
     * single buffers. The largest buffer that is not cut: */
    uint64_t whole_buffer_bytes;
    const char *whole_buffer;
    int whole_per_partition;         /* it is one partition's (more partitions make it smaller) */
    /* and the cut arrays' largest total (0 in one partition): */
    uint64_t split_bytes;
    const char *split_array;
} clvr_limits_estimate;

/* Fills *out for mesh m (only its counts are read), options o (NULL:
 * defaults) and a width x height image. Sizes saturate at UINT64_MAX. */
void clvr_limits_estimate_bytes(const clvr_mesh *m, const clvr_preprocess_options *o, uint32_t width,
                                uint32_t height, clvr_limits_estimate *out);

/* The same for preprocessing in partitions of at most part_elements
 * elements (0: one, the whole mesh; partition.h): the preprocessing buffers
 * are one partition's; the result's local indices are a candidate for the
 * largest buffer too. */
void clvr_limits_estimate_parts(const clvr_mesh *m, const clvr_preprocess_options *o, uint64_t part_elements,
                                uint32_t width, uint32_t height, clvr_limits_estimate *out);

/* Checks the estimate against cl's CL_DEVICE_GLOBAL_MEM_SIZE and
 * CL_DEVICE_MAX_MEM_ALLOC_SIZE (cl->max_alloc_bytes: lowered by
 * CLVR_MAX_ALLOC_BYTES when set). The split arrays pass when they fit in
 * CLVR_MAX_SPLITS pieces of the limit (the cut at instance boundaries, in
 * partition.c, refuses the rare mesh that still needs more, or whose one
 * instance cluster alone exceeds it); a buffer of one partition's scratch
 * above the limit is refused with the partition count that fits. CLVR_ERR_DEVICE_MEMORY names the mesh size,
 * the bytes needed, what the device has, and what to change: a smaller
 * image, a smaller or cropped mesh, 16-bit instance clusters (index_bits 16,
 * which halve the resident indices) or another --device. `what` names the
 * mesh in the message (a path), may be NULL. */
clvr_status clvr_limits_check(const clvr_cl *cl, const clvr_mesh *m, const clvr_preprocess_options *o,
                              uint32_t width, uint32_t height, clvr_error *err);
/* The same with a name for the mesh. */
clvr_status clvr_limits_check_named(const clvr_cl *cl, const clvr_mesh *m, const char *what,
                                    const clvr_preprocess_options *o, uint32_t width, uint32_t height,
                                    clvr_error *err);
/* The same for partitions of at most part_elements elements (0: one). */
clvr_status clvr_limits_check_parts(const clvr_cl *cl, const clvr_mesh *m, const char *what,
                                    const clvr_preprocess_options *o, uint64_t part_elements, uint32_t width,
                                    uint32_t height, clvr_error *err);

/* ------------------------------------------------------------ host memory
 * On a CPU device (PoCL) device buffers are host memory, so a run that does
 * not fit ends in the OOM killer or in an allocation failure inside the
 * driver (PoCL asserts: SIGABRT) unless it is refused first. These read the
 * limits that apply to this process and check a run's host bytes against
 * them from the mesh's counts alone, so that the check can run from a
 * file's header before the mesh is read. */
typedef struct clvr_mem_limits {
    uint64_t mem_available;   /* MemAvailable of /proc/meminfo; UINT64_MAX when unknown */
    uint64_t cgroup_left;     /* cgroup v2 memory.max - memory.current (v1: limit - usage); UINT64_MAX: none */
    uint64_t as_left;         /* RLIMIT_AS (ulimit -v) - VmSize; UINT64_MAX: unlimited */
    uint64_t limit;           /* the smallest of the three */
    const char *binding;      /* which one it is, as a user would name it */
} clvr_mem_limits;
void clvr_mem_limits_read(clvr_mem_limits *out);
/* Resident set now (VmRSS) and its peak so far (VmHWM) in bytes; 0 when unknown. */
void clvr_mem_rss(uint64_t *current, uint64_t *peak);

/* Host bytes of a run on a CPU device, from counts: the loaded mesh
 * (16 V + 4 S, exact), the clustered result with its BVH (16 V + 2 S +
 * about 6 bytes per element: measured 100M mixed elements needed 10% more,
 * as vertices are duplicated across instance clusters; a mesh with many
 * unreferenced vertices needs less), the scratch of one preprocessing
 * partition of at most part_elements elements (0: the whole mesh) and the
 * image; in partitions the mesh shrinks as the result grows, so the two
 * count as the larger of mesh and vertices + result. Address space (RLIMIT_AS) also pays the driver's reservations
 * (CLVR_LIMITS_DRIVER_VM_BYTES). */
#define CLVR_LIMITS_DRIVER_VM_BYTES (1ull << 30)
typedef struct clvr_host_estimate {
    uint64_t mesh_bytes, result_bytes, scratch_bytes, image_bytes, total_bytes;
} clvr_host_estimate;
void clvr_limits_host_estimate(uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                               uint64_t part_elements, uint32_t width, uint32_t height, clvr_host_estimate *out);
/* Refuses (CLVR_ERR_NO_MEMORY) a run whose estimate exceeds what l allows,
 * naming the mesh, its size, the need, the binding limit and what to do.
 * mesh_loaded: the mesh's bytes are resident already (then they are not
 * needed again from the limits). */
clvr_status clvr_limits_check_host(const char *what, uint64_t num_vertices,
                                   const uint64_t num_cells[CLVR_CELL_TYPE_COUNT], uint64_t part_elements,
                                   uint32_t width, uint32_t height, int mesh_loaded, const clvr_mem_limits *l,
                                   clvr_error *err);

/* --element-boxes (clvr_preprocess_options.no_element_boxes). */
#define CLVR_EBOX_AUTO 0
#define CLVR_EBOX_ON 1
#define CLVR_EBOX_OFF 2

/* How the run holds the mesh and what it builds, for the host estimate. */
typedef struct clvr_host_layout {
    int mapped;          /* the .bin's arrays are mapped (clvr_load_options.map_indices and
                            map_vertices): the loaded mesh is page cache, not process memory;
                            a partitioned run's element order list (4 bytes per element) and
                            the plan (2) are, at its start */
    int element_boxes;   /* CLVR_EBOX_ON or CLVR_EBOX_OFF: 6 bytes per element or none */
} clvr_host_layout;
void clvr_limits_host_estimate_layout(uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                                      uint64_t part_elements, uint32_t width, uint32_t height,
                                      const clvr_host_layout *lay, clvr_host_estimate *out);
/* clvr_limits_check_host for a layout, resolving *element_boxes: AUTO
 * becomes ON when the run fits with the boxes, else OFF when it fits
 * without them (one "clvr: ..." notice line to `notice` unless NULL), else
 * the error (for the run without boxes: the smallest). ON or OFF are
 * checked as they are; an ON that would fit only as OFF says so. */
clvr_status clvr_limits_check_host_boxes(const char *what, uint64_t num_vertices,
                                         const uint64_t num_cells[CLVR_CELL_TYPE_COUNT], uint64_t part_elements,
                                         uint32_t width, uint32_t height, int mesh_loaded, int mapped,
                                         int *element_boxes, const clvr_mem_limits *l, FILE *notice,
                                         clvr_error *err);

/* What clvr_limits_scan found. Element ids are per type (tets[i] etc.). */
typedef struct clvr_limits_report {
    uint64_t degenerate;        /* |Jacobian| at the parametric centre ~ 0 relative to the element size */
    uint64_t inverted;          /* negative Jacobian: vertex order mirrored against VTK's */
    uint64_t duplicates;        /* elements with the same type and vertex set as an earlier one */
    uint32_t first_degenerate_type, first_inverted_type, first_duplicate_type;
    uint64_t first_degenerate, first_inverted, first_duplicate;
    uint64_t duplicate_of;      /* the earlier element first_duplicate repeats (same type) */
    int duplicates_checked;     /* 0 when the check was skipped (no memory, >= 2^32 elements) */
    int constant_scalar;        /* every scalar is the same value (scalar_min == scalar_max) */
    float constant_value;
    uint64_t unused_vertices;   /* vertices no element references (informational) */
} clvr_limits_report;

/* Scans a validated mesh (every index < num_vertices, finite values): one
 * pass over the elements plus a hash of their vertex sets, at most about
 * 256 MB of host memory, freed before return. */
void clvr_limits_scan(const clvr_mesh *m, clvr_limits_report *out);
/* The same with the duplicate search's scratch bounded by about scan_bytes
 * (clvr_limits_scan: 256 MB; 12 bytes per element in one go would be 9.5 GB
 * at 788M elements): its hash partitions are taken in groups, one pass
 * over the elements per group. Same report for any budget. */
void clvr_limits_scan_budget(const clvr_mesh *m, uint64_t scan_bytes, clvr_limits_report *out);

/* Prints one "clvr: warning: ..." line per finding to out (stderr in
 * clvr) and returns how many it printed. `what` names the mesh. The lines
 * say what the renderer does about it (degenerate elements cover no volume
 * and are never hit; inverted ones render as their mirror image, which is
 * the same element; duplicates are found first-come and render once; a
 * constant field gets a window around its value). */
int clvr_limits_print_warnings(FILE *out, const char *what, const clvr_limits_report *r);

#endif /* CLVR_LIMITS_CHECK_H */
