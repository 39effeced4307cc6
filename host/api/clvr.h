/* clvr.h: the stable C API of libclvr (issue 18). Render unstructured volume
 * meshes (tetrahedra, pyramids, wedges, hexahedra) held in memory or read
 * from a file, with the Quick Clusters preprocessing and the progressive
 * path tracer of the clvr program, on an OpenCL device.
 *
 *   clvr_context *ctx; clvr_dataset *ds; clvr_tracer *tr; clvr_message msg;
 *   clvr_context_create("pocl", &ctx, &msg);
 *   clvr_dataset_create(n, xyz, CLVR_COPY, &ds, &msg);
 *   clvr_dataset_add_cells(ds, "tetra", ntets, idx, CLVR_COPY, &msg);
 *   clvr_dataset_add_field(ds, "pressure", p, CLVR_COPY, &msg);
 *   clvr_tracer_create(ctx, ds, NULL, 512, 512, &tr, &msg);   (preprocesses)
 *   clvr_tracer_render(tr, 64, &msg);
 *   clvr_tracer_read_image(tr, rgba, 512 * 512 * 4, &msg);
 *   clvr_tracer_destroy(tr); clvr_dataset_destroy(ds); clvr_context_destroy(ctx);
 *
 * Contract of every function that returns clvr_result: CLVR_RESULT_OK on
 * success; otherwise the code of the failure and, when msg is not NULL, a
 * one-line message in msg->text that names the argument or field and the
 * fix. Out-parameters are written only on success. Arguments are checked
 * (NULL handles and pointers, sizes, NaN) before any device work. Nothing a
 * caller passes in is modified. No function keeps global state; handles of
 * different contexts may be used from different threads, one handle must not
 * be used by two threads at once. Destroy functions accept NULL.
 *
 * Ownership is stated per function: CLVR_COPY copies the caller's array
 * before returning; CLVR_BORROW keeps the caller's pointer, which must stay
 * valid and unchanged until the dataset is destroyed (no copy, no extra
 * memory for large meshes).
 *
 * Pixels: width * height * 4 floats, rows top to bottom, linear r g b (the
 * background seen through the volume included) and a = the volume's opacity
 * along the ray (1 - transmittance). Units of positions are the caller's;
 * angles are degrees.
 *
 * Versioning: CLVR_API_VERSION changes its minor part when functions are
 * added (old programs keep working), its major part, and the shared
 * library's soname (libclvr.so.MAJOR), when anything changes incompatibly.
 * Compare clvr_api_version() with CLVR_API_VERSION to detect a header and
 * library mismatch. */
#ifndef CLVR_H
#define CLVR_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CLVR_API_VERSION_MAJOR 1
#define CLVR_API_VERSION_MINOR 0
/* major * 1000 + minor: 1000 is 1.0. */
#define CLVR_API_VERSION (CLVR_API_VERSION_MAJOR * 1000 + CLVR_API_VERSION_MINOR)

#if defined(CLVR_API_BUILD) && defined(__GNUC__)
#define CLVR_API __attribute__((visibility("default")))
#else
#define CLVR_API
#endif

/* Results, in the order and with the meaning of the clvr program's statuses
 * (the program's exit code in brackets): */
typedef enum clvr_result {
    CLVR_RESULT_OK = 0,
    CLVR_RESULT_ERR_USAGE,          /* [2] bad argument: NULL, out of range, unknown name */
    CLVR_RESULT_ERR_IO,             /* [3] cannot read file */
    CLVR_RESULT_ERR_FORMAT,         /* [3] unknown or unsupported file format */
    CLVR_RESULT_ERR_BAD_MAGIC,      /* [3] bad magic number */
    CLVR_RESULT_ERR_BAD_VERSION,    /* [3] unsupported format version */
    CLVR_RESULT_ERR_TRUNCATED,      /* [3] file is shorter than its header says */
    CLVR_RESULT_ERR_OVERFLOW,       /* [3] counts overflow 64-bit sizes */
    CLVR_RESULT_ERR_BAD_INDEX,      /* [3] vertex index out of range */
    CLVR_RESULT_ERR_BAD_VALUE,      /* [3] NaN or infinite value */
    CLVR_RESULT_ERR_BAD_FIELD,      /* [3] missing or invalid field */
    CLVR_RESULT_ERR_EMPTY,          /* [3] mesh has no elements */
    CLVR_RESULT_ERR_NO_MEMORY,      /* [1] out of host memory */
    CLVR_RESULT_ERR_NO_DEVICE,      /* [4] no matching OpenCL device */
    CLVR_RESULT_ERR_OPENCL,         /* [4] OpenCL call failed */
    CLVR_RESULT_ERR_KERNEL_BUILD,   /* [4] OpenCL kernel build failed */
    CLVR_RESULT_ERR_DEVICE_MEMORY,  /* [4] not enough device memory */
    CLVR_RESULT_ERR_NO_DISPLAY,     /* [4] no display for the viewer */
    CLVR_RESULT_ERR_WRITE,          /* [5] cannot write output file */
    CLVR_RESULT_ERR_INTERRUPTED,    /* [1] interrupted */
    CLVR_RESULT_ERR_INTERNAL,       /* [1] internal error */
    CLVR_RESULT_COUNT
} clvr_result;

typedef struct clvr_message {
    clvr_result result;
    char text[1024]; /* one line, NUL-terminated; empty on success */
} clvr_message;

/* Ownership of an array passed to a clvr_dataset_* function. */
typedef enum clvr_ownership {
    CLVR_COPY = 0,  /* copied before the call returns; the caller may free it at once */
    CLVR_BORROW = 1 /* kept by pointer; valid and unchanged until clvr_dataset_destroy */
} clvr_ownership;

typedef struct clvr_context clvr_context; /* an OpenCL device, its queue and built kernels */
typedef struct clvr_dataset clvr_dataset; /* points, cells, named point fields on the host */
typedef struct clvr_tracer clvr_tracer;   /* a preprocessed dataset on a device + render state */

/* CLVR_API_VERSION of the library (not of the header you compiled with). */
CLVR_API unsigned clvr_api_version(void);
/* "0.1.0": the clvr release. Static string. */
CLVR_API const char *clvr_version_string(void);
/* "ERR_TRUNCATED" and "file is shorter than its header says"; static
 * strings, "UNKNOWN_STATUS" / "unknown status" out of range. */
CLVR_API const char *clvr_result_name(clvr_result r);
CLVR_API const char *clvr_result_text(clvr_result r);
/* Exit code the clvr program uses for r (see the list above). */
CLVR_API int clvr_result_exit_code(clvr_result r);

/* --- context ------------------------------------------------------------ */

/* Opens a device. device: NULL or "" (first GPU, else PoCL, else the first
 * device), "pocl", "cpu", "gpu", "P:D" (platform and device indices) or a
 * case-insensitive substring of a platform or device name. Kernels are
 * compiled on first use (seconds on a cold driver cache). Errors:
 * ERR_NO_DEVICE (the message lists the devices), ERR_OPENCL. */
CLVR_API clvr_result clvr_context_create(const char *device, clvr_context **out, clvr_message *msg);
/* Destroys ctx. Every tracer of ctx must be destroyed first. */
CLVR_API void clvr_context_destroy(clvr_context *ctx);
/* Compiles the preprocessing and tree kernels now, by preprocessing a tiny
 * mesh of every element type (PoCL generates code at a kernel's first
 * launch), so that a later clvr_tracer_create's "preprocess_s" is
 * clustering, not compilation. Optional. */
CLVR_API clvr_result clvr_context_warm_up(clvr_context *ctx, clvr_message *msg);
/* The device's and its platform's names, NUL-terminated and truncated to
 * the sizes given (either buffer may be NULL). */
CLVR_API clvr_result clvr_context_describe(const clvr_context *ctx, char *device, size_t device_size, char *platform,
                                           size_t platform_size, clvr_message *msg);
/* Writes the platforms and devices, one per line, into buf (NUL-terminated,
 * truncated to size). Does not need a context. Errors: ERR_NO_DEVICE. */
CLVR_API clvr_result clvr_list_devices(char *buf, size_t size, clvr_message *msg);

/* --- dataset ------------------------------------------------------------ */

/* A dataset of num_points points (>= 1, < 2^32) at xyz (3 * num_points
 * floats, x y z interleaved, all finite), copied or borrowed as `own` says.
 * Cells and fields are added next. Errors: ERR_USAGE, ERR_BAD_VALUE (the
 * first non-finite coordinate's point index), ERR_NO_MEMORY. */
CLVR_API clvr_result clvr_dataset_create(uint64_t num_points, const float *xyz, clvr_ownership own,
                                         clvr_dataset **out, clvr_message *msg);
/* Adds num_cells cells of one type: "tetra" (4 indices each), "pyramid"
 * (5), "wedge" (6) or "hexahedron" (8) (the VTK / meshio names; VTK vertex
 * order), indices into the points (each < num_points, checked here).
 * A type may be added once. num_cells may be 0 (nothing is added). Errors:
 * ERR_USAGE (unknown or repeated type), ERR_BAD_INDEX (names the cell, its
 * vertex and the value), ERR_NO_MEMORY. */
CLVR_API clvr_result clvr_dataset_add_cells(clvr_dataset *ds, const char *type, uint64_t num_cells,
                                            const uint32_t *indices, clvr_ownership own, clvr_message *msg);
/* Adds a scalar per point named `name` (1..63 printable characters, unique
 * in the dataset), num_points finite floats. Errors: ERR_USAGE (name),
 * ERR_BAD_VALUE (the first NaN or infinity), ERR_NO_MEMORY. */
CLVR_API clvr_result clvr_dataset_add_field(clvr_dataset *ds, const char *name, const float *values,
                                            clvr_ownership own, clvr_message *msg);
/* Loads a mesh file (clvr .bin, .umesh, legacy .vtk; see the program's
 * docs) with its scalar `field` (NULL: the file's first). The dataset owns
 * its arrays. Errors: those of the file readers (ERR_IO, ERR_FORMAT, ...). */
CLVR_API clvr_result clvr_dataset_load(const char *path, const char *field, clvr_dataset **out, clvr_message *msg);
/* Destroys ds. A tracer made from ds keeps it alive: the memory (and the
 * borrowed arrays' use) ends when the last of them is destroyed. */
CLVR_API void clvr_dataset_destroy(clvr_dataset *ds);
/* Counts: points, cells per type in the order tetra, pyramid, wedge,
 * hexahedron, fields. Any pointer may be NULL. */
CLVR_API clvr_result clvr_dataset_counts(const clvr_dataset *ds, uint64_t *num_points, uint64_t num_cells[4],
                                         uint32_t *num_fields, clvr_message *msg);
/* Name of field i (< num_fields) into buf (NUL-terminated, truncated). */
CLVR_API clvr_result clvr_dataset_field_name(const clvr_dataset *ds, uint32_t i, char *buf, size_t size,
                                             clvr_message *msg);
/* Bounding box of the points (lo, hi: 3 floats each). */
CLVR_API clvr_result clvr_dataset_bounds(const clvr_dataset *ds, float lo[3], float hi[3], clvr_message *msg);
/* Smallest and largest value of a field (NULL: the first). */
CLVR_API clvr_result clvr_dataset_field_range(const clvr_dataset *ds, const char *field, float *min, float *max,
                                              clvr_message *msg);

/* --- tracer ------------------------------------------------------------- */

/* Preprocesses ds (Quick Clusters, paper sections 3.2-3.4) with its scalar
 * `field` (NULL: the first) on ctx's device, builds the trees and a
 * renderer of width x height pixels (1..65536) with the clvr program's
 * defaults: automatic framing, cool-warm colour map with automatic opacity
 * and density, method dda, shadows on. ds needs >= 1 cell and >= 1 field;
 * the tracer keeps ds alive (see clvr_dataset_destroy). A mesh or image the
 * device cannot hold fails here with the numbers (ERR_DEVICE_MEMORY). */
CLVR_API clvr_result clvr_tracer_create(clvr_context *ctx, clvr_dataset *ds, const char *field, uint32_t width,
                                        uint32_t height, clvr_tracer **out, clvr_message *msg);
CLVR_API void clvr_tracer_destroy(clvr_tracer *tr);
/* Lets go of the tracer's dataset (its host memory is freed when nothing
 * else holds it: a big mesh's arrays once on the device). Afterwards
 * clvr_tracer_set_tf, which reads the field for the automatic opacity and
 * density, fails with ERR_USAGE; clvr_tracer_set_tf_table still works. */
CLVR_API clvr_result clvr_tracer_drop_dataset(clvr_tracer *tr, clvr_message *msg);

/* Every setter below restarts the accumulation (the next render starts a
 * new image). */

/* Pinhole camera at eye looking at target; up must not be parallel to the
 * view direction; fovy_deg in (0, 180). */
CLVR_API clvr_result clvr_tracer_set_camera(clvr_tracer *tr, const float eye[3], const float target[3],
                                            const float up[3], float fovy_deg, clvr_message *msg);
/* Automatic framing of the dataset's bounding box, as the program's
 * --up/--azimuth/--elevation/--zoom/--fovy: up NULL is +y; zoom > 0. */
CLVR_API clvr_result clvr_tracer_frame(clvr_tracer *tr, const float up[3], float azimuth_deg, float elevation_deg,
                                       float zoom, float fovy_deg, clvr_message *msg);
/* Eye, target and up of the current camera (any may be NULL). */
CLVR_API clvr_result clvr_tracer_get_camera(const clvr_tracer *tr, float eye[3], float target[3], float up[3],
                                            clvr_message *msg);
/* Transfer function as the program's --colormap/--tf/--range/--density:
 * colormap NULL is "cool-warm"; tf_path NULL is none (a text or ParaView
 * JSON file, docs/transfer-function.md); [range_lo, range_hi] the scalar
 * window, both NaN for the file's or the field's range; density > 0 a
 * multiplier, 0 automatic (the program's default). Opacity is automatic
 * (from the field's histogram) unless the file gives it or ramp is nonzero
 * (linear ramp 0 -> 1 over the window). */
CLVR_API clvr_result clvr_tracer_set_tf(clvr_tracer *tr, const char *colormap, const char *tf_path, float range_lo,
                                        float range_hi, float density, int ramp, clvr_message *msg);
/* Transfer function from a table of n >= 2 entries (4 floats each: linear
 * r, g, b in [0, 1] and opacity in [0, 1], evenly spaced over the window
 * [range_lo, range_hi], lo < hi) and density >= 0 (1: the mesh diagonal is
 * 8 mean free paths at opacity 1). The table is copied. */
CLVR_API clvr_result clvr_tracer_set_tf_table(clvr_tracer *tr, const float *rgba, uint32_t n, float range_lo,
                                              float range_hi, float density, clvr_message *msg);
/* Directional light (dir toward the light, non-zero), intensity >= 0,
 * ambient >= 0, shadows 0/1. */
CLVR_API clvr_result clvr_tracer_set_light(clvr_tracer *tr, const float dir[3], float intensity, float ambient,
                                           int shadows, clvr_message *msg);
/* Linear background colour (3 finite floats >= 0). */
CLVR_API clvr_result clvr_tracer_set_background(clvr_tracer *tr, const float rgb[3], clvr_message *msg);
/* Method by name ("march", "track", "bins" or "dda", as the
 * program's --method; NULL keeps it) and estimator ("delta" or "urm", --estimator; NULL
 * keeps the current one). Unknown names: ERR_USAGE listing the names. */
CLVR_API clvr_result clvr_tracer_set_method(clvr_tracer *tr, const char *method, const char *estimator,
                                            clvr_message *msg);
/* Random seed (same seed, same settings, same device: same image). */
CLVR_API clvr_result clvr_tracer_set_seed(clvr_tracer *tr, uint64_t seed, clvr_message *msg);

/* Adds `frames` samples per pixel (>= 1) to the running image. */
CLVR_API clvr_result clvr_tracer_render(clvr_tracer *tr, uint32_t frames, clvr_message *msg);
/* Image size in pixels. */
CLVR_API clvr_result clvr_tracer_size(const clvr_tracer *tr, uint32_t *width, uint32_t *height, clvr_message *msg);
/* Copies the running mean image into rgba, which holds `count` floats
 * (>= width * height * 4; else ERR_USAGE with the size needed). Before any
 * frame: ERR_USAGE. */
CLVR_API clvr_result clvr_tracer_read_image(clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg);
/* One figure by name: "frames", "rays", "samples", "null_collisions",
 * "kernel_s" (device seconds of all frames), "last_frame_s",
 * "preprocess_s" (wall, kernel compilation excluded), "kernel_build_s",
 * "elements", "points", "instances", "leaves", "sampling_clusters",
 * "device_bytes" (clustered mesh + trees), "density" (the density in use),
 * "range_lo", "range_hi" (the scalar window). Unknown name: ERR_USAGE
 * listing the names. */
CLVR_API clvr_result clvr_tracer_stat(clvr_tracer *tr, const char *name, double *value, clvr_message *msg);

/* --- images ------------------------------------------------------------- */

/* Writes pixels (the convention above) to path by its extension, with the
 * program's writers: .exr (float RGBA, unchanged), .png (8-bit sRGB after
 * 2^exposure_ev and the tone curve "none", "aces" (the program's default)
 * or "filmic"; transparent != 0: RGBA with straight alpha), .pfm (float
 * RGB). Atomic: an older file at path survives a failed write. Errors:
 * ERR_USAGE (extension, size, tone curve), ERR_WRITE. */
CLVR_API clvr_result clvr_image_save(const char *path, uint32_t width, uint32_t height, const float *rgba,
                                     float exposure_ev, const char *tonemap, int transparent, clvr_message *msg);

#ifdef __cplusplus
}
#endif

#endif /* CLVR_H */
