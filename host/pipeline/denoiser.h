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
#include "render.h"

typedef struct clvr_denoiser clvr_denoiser;

/* Builds kernels/denoise.cl. */
clvr_status clvr_denoiser_create(clvr_cl *cl, clvr_denoiser **out, clvr_error *err);
void clvr_denoiser_destroy(clvr_denoiser *d); /* accepts NULL */

/* out = the denoised rgba (w * h * 4 floats), from rgba (the mean image),
 * guide (w * h * 4: albedo rgb, depth or -1; clvr_renderer_read_guides) and
 * var (w * h: the variance of each pixel's mean luminance,
 * clvr_dn_moments_variance; NULL for one frame: the noise is then estimated
 * from the image's Laplacians), with prm (clvr_dn_params_default). out may
 * be rgba. An empty image (w or h 0) is nothing to do. */
clvr_status clvr_denoiser_run(clvr_denoiser *d, uint32_t w, uint32_t h, const float *rgba, const float *guide,
                              const float *var, clvr_dn_params prm, float *out, clvr_error *err);

/* The same on the host, in plain C (the reference). */
clvr_status clvr_denoise_ref(uint32_t w, uint32_t h, const float *rgba, const float *guide, const float *var,
                             clvr_dn_params prm, float *out, clvr_error *err);

/* var[p] = the variance of pixel p's mean luminance after `frames` frames
 * (>= 2) whose rgba sums and sums of squares are sum and sumsq
 * (clvr_renderer_read_moments), the frames taken as independent (for the
 * low-discrepancy sampler an overestimate) and the channels as fully
 * correlated (the deviations add). */
void clvr_dn_moments_variance(size_t npix, uint64_t frames, const float *sum, const float *sumsq, float *var);

/* The renderer's accumulated image denoised with prm into out (width *
 * height * 4 floats): its mean, guides and (from 2 frames) moments. The
 * renderer must keep guides (settings.guides) and hold a frame. */
clvr_status clvr_denoise_renderer(clvr_denoiser *d, clvr_renderer *r, uint32_t w, uint32_t h, clvr_dn_params prm,
                                  float *out, clvr_error *err);

#endif
