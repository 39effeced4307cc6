/* denoiser.h: the optional denoiser (clvr --denoise): kernels/denoise.h's
 * edge-avoiding a-trous passes over an accumulated image, guided by the
 * renderer's albedo and depth guides (clvr_renderer_read_guides), on the
 * device (kernels/denoise.cl) or on the host (the reference the tests
 * compare it with). Biased by design: a separate, labelled mode, never the
 * default and never in a convergence figure. */
#ifndef CLVR_DENOISER_H
#define CLVR_DENOISER_H

#include <stdint.h>

#include "cl_context.h"
#include "denoise.h"

typedef struct clvr_denoiser clvr_denoiser;

/* Builds kernels/denoise.cl. */
clvr_status clvr_denoiser_create(clvr_cl *cl, clvr_denoiser **out, clvr_error *err);
void clvr_denoiser_destroy(clvr_denoiser *d); /* accepts NULL */

/* out = the denoised rgba (w * h * 4 floats), from rgba (the mean image) and
 * guide (w * h * 4: albedo rgb, depth or -1; clvr_renderer_read_guides),
 * with prm (clvr_dn_params_default). out may be
 * rgba. An empty image (w or h 0) is nothing to do. */
clvr_status clvr_denoiser_run(clvr_denoiser *d, uint32_t w, uint32_t h, const float *rgba, const float *guide,
                              clvr_dn_params prm, float *out, clvr_error *err);

/* The same on the host, in plain C (the reference). */
clvr_status clvr_denoise_ref(uint32_t w, uint32_t h, const float *rgba, const float *guide, clvr_dn_params prm,
                             float *out, clvr_error *err);

#endif
