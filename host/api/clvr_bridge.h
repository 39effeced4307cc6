/* clvr_bridge.h: what the clvr program (host/app) uses of libclvr beyond
 * clvr.h. The program builds its pipeline through the same code as the
 * API (a tracer is made by clvr_tracer_create_setup, which
 * clvr_tracer_create calls with the defaults; the transfer function of
 * --colormap/--tf/--range/--density by clvr_api_tf_build, which
 * clvr_tracer_set_tf calls), so the two cannot drift; the bridge only adds
 * the options the public API does not take yet (leaf and sampling cluster
 * sizes, every render setting, the mesh's name in messages) and read access
 * to the pipeline objects for what only the program shows: --stats,
 * --info, the limits warnings, the legend and the viewer. Not installed,
 * not exported from libclvr.so (the program links the static core). */
#ifndef CLVR_BRIDGE_H
#define CLVR_BRIDGE_H

#include "accel.h"
#include "clvr.h"
#include "cl_context.h"
#include "mesh.h"
#include "preprocess.h"
#include "render.h"
#include "status.h"
#include "tf.h"

/* How clvr_tracer_create_setup builds a tracer. */
typedef struct clvr_tracer_setup {
    const char *name;              /* the mesh in messages (a path); NULL: "dataset" */
    clvr_preprocess_options po;    /* Quick Clusters options */
    clvr_render_settings rs;       /* every render setting, width and height included */
    int shadows;                   /* asked for (the march method has none) */
    clvr_tf *tf;                   /* NULL: the API's default (automatic); else moved into the tracer */
    uint32_t partitions;           /* preprocessing partitions (partition.h); 0: automatic */
    int consume;                   /* the caller drops the dataset after creation: a loaded file's element
                                      lists may be given back while preprocessing (partition.h) */
} clvr_tracer_setup;

/* Defaults of clvr_tracer_create for a width x height image. */
void clvr_tracer_setup_default(clvr_tracer_setup *s, uint32_t width, uint32_t height);

/* clvr_tracer_create with a setup: checks the mesh and image against the
 * device (clvr_limits_check_named), preprocesses, builds the trees and the
 * renderer, frames the camera, sets the transfer function. */
clvr_status clvr_tracer_create_setup(clvr_context *ctx, clvr_dataset *ds, const char *field,
                                     clvr_tracer_setup *setup, clvr_tracer **out, clvr_error *err);

/* A dataset that takes over a loaded mesh (m is left zeroed), its one
 * field named after m's scalar. */
clvr_status clvr_dataset_adopt(clvr_mesh *m, clvr_dataset **out, clvr_error *err);

/* The pipeline's mesh over ds's arrays with field `field` (NULL: the
 * first): borrowed pointers, valid while ds lives; never clvr_mesh_free it.
 * Fails (CLVR_ERR_BAD_FIELD) for an unknown field. */
clvr_status clvr_dataset_view(const clvr_dataset *ds, const char *field, clvr_mesh *out, clvr_error *err);

/* The transfer function of the program's options over mesh m, as
 * clvr_tracer_set_tf builds it: built-in colormap, tf_path over it, the
 * window (range_set: [lo, hi]), automatic opacity unless ramp or the file
 * gives it, density (density_auto: the automatic density times the file's;
 * *auto_density receives the automatic factor, 1 otherwise). Fresh tf. */
clvr_status clvr_api_tf_build(const clvr_mesh *m, const char *colormap, const char *tf_path, int range_set,
                              float lo, float hi, float density, int density_auto, int ramp, clvr_tf *tf,
                              float *auto_density, clvr_error *err);

/* Preprocesses a tiny mesh of every element type with po, so that the
 * driver compiles the preprocessing and tree kernels now (PoCL generates
 * code at a kernel's first launch), not inside a timed clustering. */
clvr_status clvr_context_warm_up_setup(clvr_context *ctx, const clvr_preprocess_options *po, clvr_error *err);

/* The context's OpenCL runtime (device names, build time, build notices). */
clvr_cl *clvr_context_cl(clvr_context *ctx);

/* The tracer's pipeline objects (owned by the tracer). */
typedef struct clvr_tracer_parts {
    clvr_clustered *clustered;
    clvr_accel *accel;
    clvr_renderer *renderer;
    clvr_render_settings *rs;
    clvr_camera *cam;
    clvr_tf *tf;                  /* the last transfer function set by options (zeroed after a table) */
    double preprocess_s;          /* wall seconds, kernel compilation excluded */
    uint32_t partitions;          /* preprocessing partitions used */
} clvr_tracer_parts;
void clvr_tracer_parts_of(clvr_tracer *tr, clvr_tracer_parts *out);

/* clvr_result and clvr_message to clvr_status and clvr_error. */
clvr_status clvr_bridge_status(clvr_result r, const clvr_message *msg, clvr_error *err);

#endif /* CLVR_BRIDGE_H */
