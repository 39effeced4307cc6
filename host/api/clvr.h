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
#define CLVR_API_VERSION_MINOR 11
/* major * 1000 + minor: 1000 is 1.0, 1001 is 1.1 (scenes, settings,
 * statistics and dataset information as versioned structs, multi-field
 * files), 1002 is 1.2 (name tables, framing a box, time series, a transfer
 * function file's window: what the clvr program needs beyond 1.1, so that it
 * uses this header alone), 1003 is 1.3 (the pixel filter), 1004 is 1.4 (the
 * denoiser), 1005 is 1.5 (the walk estimator, and auto, the default: two more
 * estimator names), 1006 is 1.6 (clvr_render_stats.estimator: what auto
 * resolved to), 1007 is 1.7 (adaptive sampling: clvr_tracer_set_adaptive), 1008
 * is 1.8 (auto's pilot on meshes with cells other than tets, and its
 * statistics "pilot_s", "pilot_pixels", "pilot_walk_cells"), 1009 is 1.9
 * (clvr_scene_stats.bytes_entry_grids), 1010 is 1.10 (mixed cells on one
 * curve: clvr_preprocess_settings.one_curve, clvr_scene_stats.collapsed_cells,
 * setting name "one_curve"), 1011 is 1.11 (the automatic macrocell grid:
 * clvr_tracer_settings.macrocells 0, the default, and
 * clvr_render_stats.macrocells).
 *
 * Versioned structs (a first member `size`, set with their _init function or
 * to sizeof) grow only at their end. The library reads and fills a struct
 * down to its 1.1 size: a program built against an older 1.x header keeps
 * working, the members its header lacks taking their defaults (since 1.10;
 * before, the getters of a struct that had grown refused older sizes). */
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
/* Destroys ctx. Destroy its tracers and scenes first; where some still
 * live, ctx is released with the last of them. */
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
/* Smallest and largest value of a field (NULL: the first); a file's field
 * not read yet: the range of its table when decoded (clvr_dataset_field). */
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
 * program's --method; NULL keeps it) and estimator ("delta", "urm" or, since 1.5,
 * "walk" and "auto", --estimator; NULL
 * keeps the current one). Unknown names: ERR_USAGE listing the names. */
CLVR_API clvr_result clvr_tracer_set_method(clvr_tracer *tr, const char *method, const char *estimator,
                                            clvr_message *msg);
/* Random seed (same seed, same settings, same device: same image). */
CLVR_API clvr_result clvr_tracer_set_seed(clvr_tracer *tr, uint64_t seed, clvr_message *msg);

/* Adds `frames` samples per pixel (>= 1) to the running image. */
CLVR_API clvr_result clvr_tracer_render(clvr_tracer *tr, uint32_t frames, clvr_message *msg);
/* Image size in pixels. */
CLVR_API clvr_result clvr_tracer_size(const clvr_tracer *tr, uint32_t *width, uint32_t *height, clvr_message *msg);
/* Copies the running image into rgba, which holds `count` floats
 * (>= width * height * 4; else ERR_USAGE with the size needed): each
 * pixel's mean over the frames less its control variates (a fit
 * over its neighbours of what its sub-pixel offset and first uniform added,
 * kernels/pixel_cv.h; the same expected image, less noise). Before any
 * frame: ERR_USAGE. */
CLVR_API clvr_result clvr_tracer_read_image(clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg);
/* One figure by name: "frames", "rays", "samples", "null_collisions",
 * "kernel_s" (device seconds of all frames), "last_frame_s" (of the last
 * frame: its full pass and, with adaptive sampling, its refine pass),
 * "preprocess_s" (wall, kernel compilation excluded), "kernel_build_s",
 * "elements", "points", "instances", "leaves", "sampling_clusters",
 * "device_bytes" (clustered mesh + trees), "density" (the density in use),
 * "range_lo", "range_hi" (the scalar window), "hull_faces" (the mesh's
 * boundary faces that camera rays are cut to; 0 when the mesh fills its box
 * and none are kept), "hull_bytes" (their device memory, faces and tree),
 * "hull_empty_fraction" (the share of a ray's path through the box that
 * lies outside the mesh, measured on a fixed set of rays: the saving the
 * cut is for), "hull_skipped" (1 when there was too little memory to build
 * them: the image is the same, it converges as without the cut),
 * "light_s" (device seconds of the light grid's last build: urm with
 * shadows, already part of kernel_s), "image_s" (device seconds of the
 * image pass of the last clvr_tracer_read_image, the control variates'
 * fit: not part of kernel_s; 0 before one), since 1.5 "adjacency_bytes"
 * (device memory of the walk estimator's face adjacency, 4 bytes per face
 * of each cell, 16 per tet:
 * 0 until a frame asks for walk) and "adjacency_skipped" (1 when there was
 * too little memory to build it: walk then renders as urm, the same
 * image), "refine_pixels", "refine_passes" and "select_s" (adaptive
 * sampling: pixels refined, passes, host seconds of the choice), since
 * 1.8 "pilot_s" (host seconds, kernels included, of auto's pilot before
 * this accumulation's first frame: on a mesh with cells other than tets,
 * once per change of settings or transfer function; 0 without one, not
 * part of kernel_s), "pilot_pixels" (its pixels) and "pilot_walk_cells"
 * (1: it picked the walk through every cell; 0: urm at the cells other
 * than tets; -1: no pilot since the last settings). Unknown name:
 * ERR_USAGE listing the names. */
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


/* ======================================================================== *
 * API 1.1. Every struct below is plain data whose first member is `size`:
 * set it to sizeof the struct (the clvr_*_init functions do, with the
 * defaults). A library with a longer struct (a later minor version) then
 * reads and writes only the members your header knows, so programs built
 * against 1.1 keep working when members are appended. size smaller than
 * the 1.1 struct: ERR_USAGE.
 * ======================================================================== */

/* --- files and datasets (1.1) -------------------------------------------- */

typedef struct clvr_tracer_settings clvr_tracer_settings; /* below */

typedef struct clvr_load_settings {
    uint32_t size;
    /* The field to load first: "NAME", "point:NAME", "cell:NAME", a
     * component "NAME:x" / "NAME:y" / "NAME:z" / "NAME:0"..; a vector named
     * plainly gives its magnitude; NULL: the file's first. Other fields load
     * when a scene asks for them by name (clvr_scene_create). */
    const char *field;
    int cell_flat;    /* nonzero: a cell field is shown flat, each element its own value (its own copies
                         of its vertices); 0: averaged onto the vertices (default) */
    int field_ranges; /* nonzero: decode every field of the file now for its range (clvr_dataset_field) */
} clvr_load_settings;
CLVR_API void clvr_load_settings_init(clvr_load_settings *s);

/* clvr_dataset_load with settings (s NULL: the defaults). A file with
 * several fields (.bin version 2, legacy VTK with several arrays) lists them
 * all (clvr_dataset_field); any may be named in clvr_scene_create /
 * clvr_tracer_create, and is read from the file then (the file must still
 * be there, unchanged). */
CLVR_API clvr_result clvr_dataset_load_with(const char *path, const clvr_load_settings *s, clvr_dataset **out,
                                            clvr_message *msg);
/* The clvr program's built-in scene (a box of mixed element types with a
 * smooth field), for examples and tests. */
CLVR_API clvr_result clvr_dataset_create_demo(clvr_dataset **out, clvr_message *msg);

typedef struct clvr_dataset_info {
    uint32_t size;
    uint64_t num_points;
    uint64_t num_cells[4];      /* tetra, pyramid, wedge, hexahedron */
    uint64_t num_elements;
    uint32_t num_fields;        /* as clvr_dataset_counts */
    uint32_t current_field;     /* the field loaded first (a file's rendered field) */
    float lo[3], hi[3];         /* bounds of the points */
    float scalar_min, scalar_max; /* range of the current field */
    uint64_t bytes_points;      /* host bytes of positions + one scalar per point */
    uint64_t bytes_indices;     /* host bytes of the cells' indices */
    uint64_t skipped_cells;     /* a file's cells of other types (surface, line, polyhedron) left out */
    uint64_t decomposed_cells;  /* a file's polyhedra split into tets and pyramids */
    int cell_flat;              /* the current field is a cell field shown flat */
    int current_is_cell;        /* the current field is cell data (averaged, or flat) */
    char current_name[64];      /* name of the current field ("" when unnamed) */
    uint32_t file_fields;       /* fields listed from the file's own table (the first ones; 0: none) */
} clvr_dataset_info;
CLVR_API clvr_result clvr_dataset_get_info(const clvr_dataset *ds, clvr_dataset_info *info, clvr_message *msg);

/* Field i (< num_fields) of a dataset: a file's arrays as the file has them,
 * or the fields added with clvr_dataset_add_field. */
typedef struct clvr_dataset_field {
    uint32_t size;
    char name[64];
    int is_cell;          /* 0: point data, 1: cell data */
    uint32_t components;  /* 1 (scalar) .. 16; a component is picked as NAME:x or NAME:0.., the magnitude as NAME */
    int has_range;        /* 0: not decoded yet (clvr_load_settings.field_ranges) */
    float min, max;       /* range (the magnitude's for vectors) when has_range */
    int loaded;           /* its values are in memory now */
} clvr_dataset_field;
CLVR_API clvr_result clvr_dataset_get_field(const clvr_dataset *ds, uint32_t i, clvr_dataset_field *out,
                                            clvr_message *msg);
/* The array the dataset reads for `name` ("points", a cell type name or a
 * field's name) and whether it is the caller's own (borrowed, 1) or the
 * dataset's copy (0): lets a caller check that CLVR_BORROW kept its array. */
CLVR_API clvr_result clvr_dataset_get_array(const clvr_dataset *ds, const char *name, const void **data,
                                            int *borrowed, clvr_message *msg);
/* Warnings about flaws that render anyway (degenerate, inverted or
 * duplicate elements, a constant field, cells left out), one line each,
 * "clvr: warning: NAME: ..." into buf (NUL-terminated, truncated; "" when
 * none); *count receives the number of lines (may be NULL). name: the
 * dataset in messages (NULL: "dataset"). */
CLVR_API clvr_result clvr_dataset_warnings(const clvr_dataset *ds, const char *name, char *buf, size_t size,
                                           uint32_t *count, clvr_message *msg);
/* Host memory check before reading a mesh file: a clvr .bin whose header
 * says it cannot fit with a width x height image (and partitions, 0:
 * automatic) fails with the numbers (ERR_NO_MEMORY). Other formats, whose
 * headers do not give the counts: OK (checked by clvr_dataset_check_memory
 * once loaded). */
CLVR_API clvr_result clvr_file_check_memory(const char *path, uint32_t width, uint32_t height, uint32_t partitions,
                                            clvr_message *msg);
/* element_boxes: CLVR_ELEMENT_BOXES_* asked for; *resolved (may be NULL)
 * receives ON or OFF: AUTO becomes OFF when the run fits only without the
 * boxes (pass it on in clvr_preprocess_settings.element_boxes). */
CLVR_API clvr_result clvr_dataset_check_memory(const clvr_dataset *ds, const char *name, uint32_t width,
                                               uint32_t height, uint32_t partitions, int element_boxes,
                                               int *resolved, clvr_message *msg);
/* Device check before reading a mesh file (1.2): a clvr .bin whose header
 * says its mesh cannot fit ctx's device even in its smallest configuration
 * (element boxes off; partitions as given, 0: automatic) with a width x
 * height image fails with the numbers and what to do (ERR_DEVICE_MEMORY):
 * a buffer that is never split above CL_DEVICE_MAX_MEM_ALLOC_SIZE, arrays
 * that would need more than 4 pieces, or more than the device's global
 * memory. On a GPU that is device memory, which clvr_file_check_memory
 * (host memory) does not see. Other formats: OK (checked again when the
 * scene is made). */
CLVR_API clvr_result clvr_context_check_file(clvr_context *ctx, const char *path, uint32_t width, uint32_t height,
                                             uint32_t partitions, clvr_message *msg);

/* --- preprocessing as its own step (1.1) --------------------------------- */

typedef struct clvr_scene clvr_scene; /* a preprocessed dataset (clusters and trees) on a device */

typedef struct clvr_preprocess_settings {
    uint32_t size;
    uint32_t leaf_size;      /* elements per leaf cluster, 1..128 (paper: 16; default 16) */
    uint32_t sampling_size;  /* elements per adaptive-sampling cluster (default 16) */
    uint32_t partitions;     /* preprocess in this many pieces to bound peak memory; 0: automatic */
    int consume;             /* nonzero: the caller destroys the dataset right after; a loaded file's cell
                                lists may then be freed piece by piece while preprocessing */
    const char *name;        /* the dataset in messages (a path); NULL: "dataset" */
    uint32_t width, height;  /* the image the tracers will render, for the device memory check before
                                preprocessing (0: checked by clvr_tracer_create_on only) */
    int element_boxes;       /* point location's quantized element boxes (6 bytes per element, about twice
                                the lookup speed): CLVR_ELEMENT_BOXES_AUTO (default: on unless the host memory
                                check finds the run fits only without them), _ON, _OFF */
    int one_curve;           /* (1.10) a mesh of two or more cell types on one Hilbert curve, every cell
                                stored as a hex with repeated corners (clusters then hold every type of their
                                region; faster point location on mixed meshes, up to 8 indices per cell):
                                CLVR_ONE_CURVE_AUTO (default: when that costs at most 1.5x the index slots
                                of one curve per type), _ON, _OFF (one curve per type) */
} clvr_preprocess_settings;
#define CLVR_ELEMENT_BOXES_AUTO 0
#define CLVR_ELEMENT_BOXES_ON 1
#define CLVR_ELEMENT_BOXES_OFF 2
#define CLVR_ONE_CURVE_AUTO 0
#define CLVR_ONE_CURVE_ON 1
#define CLVR_ONE_CURVE_OFF 2
CLVR_API void clvr_preprocess_settings_init(clvr_preprocess_settings *s);

/* Preprocesses ds's field `field` (NULL: the current one; a file's other
 * field by name or spec as in clvr_load_settings) on ctx's device: Quick
 * Clusters and both trees. s NULL: defaults. The mesh is checked against
 * the device's memory first (ERR_DEVICE_MEMORY with the numbers). The scene
 * keeps ds alive until clvr_scene_drop_dataset or destroy. Its wall time,
 * kernel compilation excluded, is clvr_scene_stats' preprocess_s. */
CLVR_API clvr_result clvr_scene_create(clvr_context *ctx, clvr_dataset *ds, const char *field,
                                       const clvr_preprocess_settings *s, clvr_scene **out, clvr_message *msg);
/* Tracers made on the scene keep it alive. */
CLVR_API void clvr_scene_destroy(clvr_scene *sc);
/* Lets go of the scene's dataset (see clvr_tracer_drop_dataset). */
CLVR_API clvr_result clvr_scene_drop_dataset(clvr_scene *sc, clvr_message *msg);
/* A tracer of width x height pixels on a preprocessed scene with settings s
 * (NULL: the defaults; see clvr_tracer_settings) and, until one is set, the
 * automatic transfer function of clvr_tracer_create. Several tracers may
 * share a scene. */
CLVR_API clvr_result clvr_tracer_create_on(clvr_scene *sc, const clvr_tracer_settings *s, uint32_t width,
                                           uint32_t height, clvr_tracer **out, clvr_message *msg);
/* clvr_context_warm_up with the cluster sizes of s. */
CLVR_API clvr_result clvr_context_warm_up_with(clvr_context *ctx, const clvr_preprocess_settings *s,
                                               clvr_message *msg);
/* Kernel compilation so far on ctx (wall seconds in the driver's compiler)
 * and whether to print a one-line notice on stderr when a compilation takes
 * long (default off); *notice_shown: one was printed. Pointers may be NULL. */
CLVR_API clvr_result clvr_context_build_info(clvr_context *ctx, int notices, double *build_s, int *notice_shown,
                                             clvr_message *msg);

#define CLVR_STATS_MAX_STAGES 16
typedef struct clvr_scene_stats {
    uint32_t size;
    uint64_t elements, points;
    uint64_t instances, instances16, leaves, sampling_clusters;
    uint32_t leaf_size, sampling_size, partitions;
    float lo[3], hi[3];             /* bounds of the mesh */
    /* device bytes (the paper's Table 1) */
    uint64_t bytes_points_before;   /* float3 + float per mesh point */
    uint64_t bytes_points_after;    /* float4 per clustered (duplicated) point */
    uint64_t bytes_indices_before;  /* 32-bit indices */
    uint64_t bytes_indices_after;   /* 16/32-bit per instance cluster */
    uint64_t bytes_bvh;             /* the two-level tree */
    uint64_t bytes_bvh_one_per_leaf;/* the same tree with one element per leaf (Table 1 "pre") */
    uint64_t bytes_sampling;        /* sampling clusters and their tree */
    uint64_t bytes_element_boxes;   /* quantized element boxes of point location */
    uint64_t device_bytes;          /* all device allocations of the context now */
    double preprocess_s;            /* wall: upload + clustering + trees, kernel compilation excluded */
    uint32_t num_stages;
    char stage_name[CLVR_STATS_MAX_STAGES][16];
    double stage_s[CLVR_STATS_MAX_STAGES]; /* device seconds per stage, then the trees ("bvh") and the
                                              boundary faces ("hull", 0 when none were built) */
    float scalar_min, scalar_max;   /* range of the scene's field */
    uint64_t bytes_entry_grids;     /* (1.9) point location's entry grids (where a query's walk starts),
                                     * occupancy grid (where no element is) and its global hints (the
                                     * leaf where a query starts, since session 51) */
    uint64_t collapsed_cells[4];    /* (1.10) tets, pyramids, wedges stored as hexes with repeated corners
                                     * (one curve; [3] is 0), all 0 on one curve per type */
} clvr_scene_stats;
CLVR_API clvr_result clvr_scene_get_stats(const clvr_scene *sc, clvr_scene_stats *out, clvr_message *msg);
/* The scene a tracer renders (borrowed: valid while the tracer lives). */
CLVR_API clvr_scene *clvr_tracer_scene(clvr_tracer *tr);

/* --- every render setting (1.1) ------------------------------------------ */

#define CLVR_MAX_CLIP 6
struct clvr_tracer_settings {
    uint32_t size;
    char method[16];          /* "march", "track", "bins", "dda" */
    char estimator[16];       /* "delta", "urm", "walk", "auto" (since 1.5; the default) (track, bins, dda) */
    char sampler[16];         /* "ld" (low discrepancy across frames), "independent" */
    uint64_t seed;
    uint32_t urm_steps;       /* urm: minimum quadrature points per ray, >= 1 */
    float step;               /* march step in world units; 0: automatic */
    uint32_t bins, segments;  /* bins method: bins <= 32, segments >= 1 */
    uint32_t macrocells;      /* dda: grid cells per axis, 1..1024; 0 (since 1.11, the default):
                                 automatic, 128 or 32 per transfer function (docs/rendering.md) */
    float light_dir[3];       /* toward the light, not all 0 */
    float light_intensity, ambient;
    int shadows;
    float background[3];      /* linear, >= 0 */
    int clip_box;             /* nonzero: rays see only [clip_lo, clip_hi] */
    float clip_lo[3], clip_hi[3];
    uint32_t num_clip_planes; /* 0..CLVR_MAX_CLIP: medium kept where n.p <= d */
    float clip_planes[CLVR_MAX_CLIP][4];
};
/* The defaults of a new tracer. */
CLVR_API void clvr_tracer_settings_init(clvr_tracer_settings *s);
CLVR_API clvr_result clvr_tracer_get_settings(const clvr_tracer *tr, clvr_tracer_settings *out, clvr_message *msg);
/* Checks every member (ERR_USAGE naming it) and applies them all, or none. */
CLVR_API clvr_result clvr_tracer_set_settings(clvr_tracer *tr, const clvr_tracer_settings *s, clvr_message *msg);
/* Resizes the image (1..65536 each way); the camera keeps its eye, target
 * and vertical field of view. */
CLVR_API clvr_result clvr_tracer_set_size(clvr_tracer *tr, uint32_t width, uint32_t height, clvr_message *msg);

/* Figures of the frames accumulated since the last change. */
typedef struct clvr_render_stats {
    uint32_t size;
    uint64_t frames, rays, samples, null_collisions;
    double kernel_s, last_frame_s; /* device seconds: all frames, the last one (its full and refine pass) */
    uint32_t width, height;
    char method[16];
    char estimator[16]; /* since 1.6: what the frames render with ("delta", "urm", "walk"): "auto" resolved,
                         * and "urm" where the walk cannot run (under "auto" a mesh without tets, no
                         * room for its face adjacency, an MPI run) */
    uint32_t macrocells; /* (1.11) dda: cells per axis of the macrocell grid in use (the automatic grid's
                          * choice); 0 for the other methods */
} clvr_render_stats;
CLVR_API clvr_result clvr_tracer_get_render_stats(clvr_tracer *tr, clvr_render_stats *out, clvr_message *msg);

/* The camera in full: eye, target, up and the vertical field of view. */
CLVR_API clvr_result clvr_tracer_get_view(const clvr_tracer *tr, float eye[3], float target[3], float up[3],
                                          float *fovy_deg, clvr_message *msg);
/* Rotates point p about the line through centre along axis by deg (right
 * hand): a turntable's eye. Pure arithmetic. */
CLVR_API void clvr_rotate_about(const float p[3], const float centre[3], const float axis[3], float deg, float out[3]);
/* Draws the edges of the box [lo, hi], as the current camera sees it, into
 * rgba (the tracer's size, the pixel convention above) in linear colour rgb,
 * line_width pixels wide: an outline of the mesh or a clip box. */
CLVR_API clvr_result clvr_tracer_draw_box(const clvr_tracer *tr, float *rgba, size_t count, const float lo[3],
                                          const float hi[3], const float rgb[3], float line_width, clvr_message *msg);

/* --- the transfer function in use (1.1) ---------------------------------- */

typedef struct clvr_tf_info {
    uint32_t size;
    char colormap[64];   /* the colour map's name (a file's name for --tf files; "table" for a table) */
    float range_lo, range_hi;
    float density;       /* in use (the automatic factor included) */
    float auto_density;  /* the automatic factor of the last clvr_tracer_set_tf with density 0; else 1 */
    uint32_t table_size; /* entries of the baked table */
    float extinction_scale; /* the table's 4th column is opacity times this (the mesh diagonal's scale) */
} clvr_tf_info;
CLVR_API clvr_result clvr_tracer_get_tf(const clvr_tracer *tr, clvr_tf_info *out, clvr_message *msg);
/* The baked table in use: table_size entries of linear r, g, b and
 * extinction (opacity times the density scale), rgba holding count floats
 * (>= 4 * table_size). */
CLVR_API clvr_result clvr_tracer_get_tf_table(const clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg);
/* Edits the transfer function set by clvr_tracer_set_tf, keeping its
 * opacity: colormap (NULL: keep; a built-in name), the window [lo, hi]
 * (both NaN: keep) and the density (>= 0; NaN: keep). ERR_USAGE after a
 * table (clvr_tracer_set_tf_table). */
CLVR_API clvr_result clvr_tracer_edit_tf(clvr_tracer *tr, const char *colormap, float range_lo, float range_hi,
                                         float density, clvr_message *msg);
/* A transfer function built apart from a tracer, from a dataset's field
 * (NULL: the current one), with the arguments of clvr_tracer_set_tf: it
 * can be made (and a bad file or name reported) before the device work,
 * and set on tracers later, after the dataset is gone. */
typedef struct clvr_transfer clvr_transfer;
CLVR_API clvr_result clvr_transfer_create(const clvr_dataset *ds, const char *field, const char *colormap,
                                          const char *tf_path, float range_lo, float range_hi, float density,
                                          int ramp, clvr_transfer **out, clvr_message *msg);
CLVR_API void clvr_transfer_destroy(clvr_transfer *tf);
/* Its colour map, window, density and automatic density factor
 * (table_size: entries of its baked table). */
CLVR_API clvr_result clvr_transfer_get_info(const clvr_transfer *tf, clvr_tf_info *out, clvr_message *msg);
/* Sets tf on tr (copied: tf may be destroyed afterwards), as
 * clvr_tracer_set_tf would have. */
CLVR_API clvr_result clvr_tracer_set_transfer(clvr_tracer *tr, const clvr_transfer *tf, clvr_message *msg);

/* "cool-warm, viridis, ...": the built-in colour maps. Static string. */
CLVR_API const char *clvr_colormap_names(void);

/* --- images and process (1.1) -------------------------------------------- */

typedef struct clvr_image_settings {
    uint32_t size;
    float exposure_ev;       /* PNG: scene values times 2^exposure_ev */
    const char *tonemap;     /* PNG: "none", "aces" (default), "filmic" */
    int transparent;         /* PNG: RGBA with straight alpha */
    /* A colour bar drawn into a PNG: legend_table (legend_entries x 4
     * floats as clvr_tracer_get_tf_table gives), the window it spans and
     * the field's name. NULL: none. */
    const float *legend_table;
    uint32_t legend_entries;
    float legend_lo, legend_hi;
    const char *legend_name;
} clvr_image_settings;
CLVR_API void clvr_image_settings_init(clvr_image_settings *s);
/* clvr_image_save with settings (s NULL: the defaults). */
CLVR_API clvr_result clvr_image_save_with(const char *path, uint32_t width, uint32_t height, const float *rgba,
                                          const clvr_image_settings *s, clvr_message *msg);
/* Checks before long work that path has an image extension (ERR_USAGE) and
 * that its directory is writable (ERR_WRITE). */
CLVR_API clvr_result clvr_image_check_path(const char *path, clvr_message *msg);
/* Nonzero when path ends in .png (any case). */
CLVR_API int clvr_image_path_is_png(const char *path);
/* path with ".NNNN" inserted before its extension ("a.png", 7 ->
 * "a.0007.png"); ERR_USAGE when out (size bytes) is too small. */
CLVR_API clvr_result clvr_image_path_numbered(const char *path, uint32_t index, char *out, size_t size,
                                              clvr_message *msg);
/* 8-bit sRGB pixels of an image (the pixel convention above) as the PNG
 * writer makes an opaque one: scaled by 2^exposure_ev, tone curve
 * ("none", "aces", "filmic"; NULL: "aces"), sRGB; rgba8 receives
 * width * height * 4 bytes, alpha 255. For displays (the viewer). */
CLVR_API clvr_result clvr_image_to_srgb8(const float *rgba, uint32_t width, uint32_t height, float exposure_ev,
                                         const char *tonemap, uint8_t *rgba8, clvr_message *msg);
/* Writes 8-bit sRGB pixels (width * height * 4 bytes, rows top to bottom,
 * alpha ignored) to path by its extension: a .png gets them as they are,
 * .exr and .pfm decoded to linear. Atomic as clvr_image_save. */
CLVR_API clvr_result clvr_image_save_srgb8(const char *path, uint32_t width, uint32_t height, const uint8_t *rgba8,
                                           clvr_message *msg);
/* The process's resident and peak resident memory in bytes (Linux; 0
 * where unknown). Either pointer may be NULL. */
CLVR_API void clvr_process_memory(uint64_t *resident, uint64_t *peak);


/* ======================================================================== *
 * API 1.2: what a command line or a GUI around the library needs besides
 * rendering (the clvr program uses only this header). No new structs.
 * ======================================================================== */

/* --- names of settings (1.2) --------------------------------------------- */

/* The names a setting takes, by index: setting "method" (march, track,
 * bins, dda), "estimator" (delta, urm, walk and auto since 1.5), "sampler" (independent, ld),
 * "tonemap" (none, aces, filmic), "element_boxes" (auto, on, off: index =
 * CLVR_ELEMENT_BOXES_*), since 1.3, "pixel_filter" (box, point), or, since 1.10, "one_curve" (auto, on,
 * off: index = CLVR_ONE_CURVE_*). Static string; NULL for an index past the end or an
 * unknown setting. Indices are stable within a major version (new names
 * are appended), so a program may keep a setting as its index. */
CLVR_API const char *clvr_setting_name(const char *setting, uint32_t index);
/* The index of name in setting's table (exact match). ERR_USAGE for an
 * unknown setting, or an unknown name (the message lists the names). */
CLVR_API clvr_result clvr_setting_index(const char *setting, const char *name, uint32_t *index, clvr_message *msg);
/* The image size a tracer of the clvr program gets by default (512 x 512).
 * Either pointer may be NULL. */
CLVR_API void clvr_default_size(uint32_t *width, uint32_t *height);

/* --- framing without a tracer (1.2) -------------------------------------- */

/* The automatic framing of clvr_tracer_frame for the box [lo, hi] (lo <= hi,
 * finite) and a width x height image: the eye and the look-at point (the
 * box's centre). up NULL is +y; zoom > 0; fovy_deg in (0, 180). A camera set
 * with clvr_tracer_set_camera(eye, target, up, fovy_deg) is then exactly the
 * framing: several datasets (a time series, the shares of a distributed
 * mesh) can be framed as one box. Pure arithmetic. ERR_BAD_VALUE (bounds),
 * ERR_USAGE (the rest). */
CLVR_API clvr_result clvr_frame_box(const float lo[3], const float hi[3], const float up[3], float azimuth_deg,
                                    float elevation_deg, float zoom, float fovy_deg, uint32_t width, uint32_t height,
                                    float eye[3], float target[3], clvr_message *msg);

/* --- transfer function files (1.2) --------------------------------------- */

/* Whether the transfer function file tf_path (docs/transfer-function.md;
 * "FILE:NAME" for a ParaView preset) fixes its own scalar window (a `range`
 * line, or a ParaView map's data-space span): *has_window 1 and the window
 * in *lo, *hi (may be NULL), else 0. Errors: the file's (ERR_IO,
 * ERR_BAD_FIELD, ...). */
CLVR_API clvr_result clvr_tf_file_window(const char *tf_path, int *has_window, float *lo, float *hi,
                                         clvr_message *msg);

/* --- time series (1.2) --------------------------------------------------- */

/* A time series: a ParaView .series file ({"files": [{"name": "step.bin",
 * "time": 0}, ...]}, as tools/clvr-convert writes for .pvd, .vtu.series and
 * Exodus time steps), names relative to the file's folder. */
typedef struct clvr_series clvr_series;
/* Nonzero when path names a series file (ends in .series, any case). */
CLVR_API int clvr_path_is_series(const char *path);
/* Reads the list of steps (not the meshes). Errors: ERR_IO, ERR_FORMAT
 * (over 1 MiB), ERR_BAD_FIELD (not a series file; a step without a name:
 * "FILE:LINE:COL: ..."), ERR_NO_MEMORY. */
CLVR_API clvr_result clvr_series_open(const char *path, clvr_series **out, clvr_message *msg);
CLVR_API void clvr_series_destroy(clvr_series *se);
/* Number of steps (>= 1); 0 for NULL. */
CLVR_API uint32_t clvr_series_count(const clvr_series *se);
/* Step i's mesh path (static while se lives) and time (its index when the
 * file gives none). ERR_USAGE for i >= count. Either pointer may be NULL. */
CLVR_API clvr_result clvr_series_step(const clvr_series *se, uint32_t i, const char **path, double *time,
                                      clvr_message *msg);
/* Loads every step in turn (one in memory at a time) with field `field`
 * (NULL: each file's first; as clvr_load_settings.field): the union of the
 * steps' bounds (lo, hi; may be NULL) and the field's range over all steps
 * (*min, *max; may be NULL), what one camera and one colour window for the
 * whole series need. A step that fails to load: its error, naming the step
 * ("(step I of FILE)"). */
CLVR_API clvr_result clvr_series_bounds(const clvr_series *se, const char *field, float lo[3], float hi[3],
                                        float *min, float *max, clvr_message *msg);

/* ======================================================================== *
 * API 1.3. A call, not a member appended to clvr_tracer_settings: a program
 * built against 1.1 or 1.2 passes the shorter struct to
 * clvr_tracer_settings_init, which must not write past it.
 * ======================================================================== */

/* Which image the frames converge to: "box" (the default) gives each pixel
 * the mean over its square, camera rays jittered across it (antialiased
 * edges; the jitter is part of each frame's noise); "point" gives it the
 * value of the ray through its centre, as VTK's and ParaView's ray casters
 * draw (aliased edges that no number of frames removes, and no jitter
 * noise: on smooth meshes a clean image in about half the frames). A
 * change restarts the accumulation. ERR_USAGE for another name. */
CLVR_API clvr_result clvr_tracer_set_pixel_filter(clvr_tracer *tr, const char *filter, clvr_message *msg);
/* "box" or "point"; NULL for a NULL tracer. */
CLVR_API const char *clvr_tracer_pixel_filter(const clvr_tracer *tr);

/* ======================================================================== *
 * API 1.4: the optional denoiser.
 * ======================================================================== */

/* on nonzero: the frames from now on also keep the denoiser's guides (per
 * pixel the colour unlit and the mean depth of the medium seen, 32 bytes
 * per pixel on the device), so that clvr_tracer_read_denoised can filter
 * the image; 0 (the default) drops them. A change restarts the
 * accumulation. */
CLVR_API clvr_result clvr_tracer_set_denoise(clvr_tracer *tr, int on, clvr_message *msg);
/* 1 when the tracer keeps the guides; 0 otherwise or for a NULL tracer. */
CLVR_API int clvr_tracer_denoise(const clvr_tracer *tr);
/* The accumulated image (as clvr_tracer_read_image) after an edge-avoiding
 * a-trous filter guided by the colour's local noise, the albedo and the
 * depth (kernels/denoise.h). Smoother, and biased: it is not the estimate
 * the frames converge to, and no convergence figure of clvr uses it. Pixels
 * whose rays never met the medium stay as they are. ERR_USAGE before a
 * frame, or unless clvr_tracer_set_denoise(tr, 1) came before the frames. */
CLVR_API clvr_result clvr_tracer_read_denoised(clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg);

/* ======================================================================== *
 * API 1.7: adaptive sampling.
 * ======================================================================== */

/* threshold > 0 (the default, 0.1): each frame is followed by one more
 * sample in the pixels whose 8 neighbours' luminance, after the first frame
 * of the accumulation, has a standard deviation above threshold times the
 * mean of the other pixels that met the medium (edges of the medium, the
 * noisiest regions; a few percent of the pixels at the default). The choice
 * never reads a pixel's own samples, so the expected image is the same; it
 * converges faster per second. 0 turns it off (one sample per pixel per
 * frame). The statistic "refine_pixels" says how many pixels are refined.
 * A change restarts the accumulation. ERR_USAGE for a negative or
 * non-finite threshold. */
CLVR_API clvr_result clvr_tracer_set_adaptive(clvr_tracer *tr, float threshold, clvr_message *msg);
/* A new tracer's threshold (render.h defines the same, token for token). */
#define CLVR_ADAPTIVE_DEFAULT 0.1f
/* The threshold in use; 0 for off or a NULL tracer. */
CLVR_API float clvr_tracer_adaptive(const clvr_tracer *tr);

#ifdef __cplusplus
}
#endif

#endif /* CLVR_H */
