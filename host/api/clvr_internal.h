/* clvr_internal.h: what the library's own drivers outside host/api need
 * beyond clvr.h. Today one: the MPI mode (host/mpi/mpi_main.c, built into
 * the module libclvr_mpi.so with its own copy of the pipeline), which runs
 * the renderer's phase kernels on a tracer and sets render settings the
 * public API does not carry (the macrocell and light grids' domain, agreed
 * by all ranks). The clvr program (host/app) does not include this header
 * (tests/test_app_includes.sh checks). Not installed, not exported from
 * libclvr.so or libclvr_mpi.so. */
#ifndef CLVR_INTERNAL_H
#define CLVR_INTERNAL_H

#include "clvr.h"
#include "mesh.h"
#include "render.h"
#include "status.h"
#include "tf.h"

/* A clvr_result and its message as a clvr_status and clvr_error. */
clvr_status clvr_internal_status(clvr_result r, const clvr_message *msg, clvr_error *err);

/* A dataset that takes over a loaded mesh (m is left zeroed), its one field
 * named after m's scalar. */
clvr_status clvr_internal_dataset_adopt(clvr_mesh *m, clvr_dataset **out, clvr_error *err);

/* The transfer function of options as clvr_tracer_set_tf builds it: density
 * 0 is automatic (*auto_density receives the factor). Fresh tf. */
clvr_status clvr_internal_tf_build(const clvr_mesh *m, const char *colormap, const char *tf_path, int range_set,
                                   float lo, float hi, float density, int ramp, clvr_tf *tf, float *auto_density,
                                   clvr_error *err);

/* A scene of ds (settings ps; its curve quantized over [quantize_lo,
 * quantize_hi], NULL for the mesh's bounds: the MPI ranks share the whole
 * mesh's box, so their shares are pieces of one Hilbert curve) and a tracer
 * on it with render settings rs (rs->width x rs->height) and shadows asked
 * for; *preprocess_s receives the scene's preprocessing time. */
clvr_status clvr_internal_tracer_create(clvr_context *ctx, clvr_dataset *ds, const clvr_preprocess_settings *ps,
                                        const float quantize_lo[3], const float quantize_hi[3],
                                        const clvr_render_settings *rs, int shadows, clvr_tracer **out,
                                        double *preprocess_s, clvr_error *err);

/* The render settings of ts for a width x height image, checked and
 * converted as clvr_tracer_create_on does (*shadows: asked for). */
clvr_status clvr_internal_render_settings(const clvr_tracer_settings *ts, uint32_t width, uint32_t height,
                                          clvr_render_settings *rs, int *shadows, clvr_error *err);

/* The tracer's renderer (borrowed). */
clvr_renderer *clvr_internal_tracer_renderer(clvr_tracer *tr);

#endif /* CLVR_INTERNAL_H */
