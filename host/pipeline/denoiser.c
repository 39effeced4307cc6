#include "denoiser.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct clvr_denoiser {
    clvr_cl *cl;
    cl_program prog;
    cl_kernel k_guides, k_noise, k_pass;
};

clvr_status clvr_denoiser_create(clvr_cl *cl, clvr_denoiser **out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_denoiser *d = calloc(1, sizeof *d);
    *out = NULL;
    if (!d) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory creating the denoiser");
    d->cl = cl;
    CLVR_TRY(clvr_cl_build(cl, "denoise.cl", NULL, &d->prog, err));
    CLVR_TRY(clvr_cl_kernel(d->prog, "clvr_dn_guides", &d->k_guides, err));
    CLVR_TRY(clvr_cl_kernel(d->prog, "clvr_dn_noise_map", &d->k_noise, err));
    CLVR_TRY(clvr_cl_kernel(d->prog, "clvr_dn_atrous", &d->k_pass, err));
    *out = d;
    d = NULL;
cleanup:
    clvr_denoiser_destroy(d);
    return s;
}

void clvr_denoiser_destroy(clvr_denoiser *d)
{
    if (!d) return;
    if (d->k_guides) clReleaseKernel(d->k_guides);
    if (d->k_noise) clReleaseKernel(d->k_noise);
    if (d->k_pass) clReleaseKernel(d->k_pass);
    if (d->prog) clReleaseProgram(d->prog);
    free(d);
}

clvr_status clvr_denoiser_run(clvr_denoiser *d, uint32_t w, uint32_t h, const float *rgba, const float *guide,
                              const float *var, clvr_dn_params prm, float *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = d->cl;
    cl_mem img[2] = {NULL, NULL}, graw = NULL, gbuf = NULL, noise = NULL, vbuf = NULL;
    const size_t npix = (size_t)w * h, bytes = npix * 4 * sizeof(float);
    if (npix == 0) return CLVR_OK;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, bytes, (void *)rgba, "denoiser image",
                            &img[0], err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, bytes, NULL, "denoiser image", &img[1], err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, (void *)guide, "denoiser guides",
                            &graw, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, bytes, NULL, "denoiser guides", &gbuf, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * sizeof(float), NULL, "denoiser noise map", &noise, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | (var ? CL_MEM_COPY_HOST_PTR : 0), var ? npix * sizeof(float) : 4,
                            (void *)var, "denoiser variances", &vbuf, err));
    {
        const size_t local[2] = {8, 8};
        cl_uint cw = w, ch = h, has_var = var != NULL;
        CLVR_TRY(CLVR_CL_ARGS(d->k_guides, err, CLVR_ARG(graw), CLVR_ARG(cw), CLVR_ARG(ch), CLVR_ARG(gbuf)));
        CLVR_TRY(clvr_cl_run2d(cl, d->k_guides, w, h, local, NULL, err));
        CLVR_TRY(CLVR_CL_ARGS(d->k_noise, err, CLVR_ARG(img[0]), CLVR_ARG(gbuf), CLVR_ARG(vbuf), CLVR_ARG(has_var),
                              CLVR_ARG(cw), CLVR_ARG(ch), CLVR_ARG(noise)));
        CLVR_TRY(clvr_cl_run2d(cl, d->k_noise, w, h, local, NULL, err));
        int cur = 0;
        for (cl_uint pass = 0, step = 1; pass < prm.passes && pass < CLVR_DN_MAX_PASSES; ++pass, step *= 2u) {
            CLVR_TRY(CLVR_CL_ARGS(d->k_pass, err, CLVR_ARG(img[cur]), CLVR_ARG(gbuf), CLVR_ARG(noise), CLVR_ARG(cw),
                                  CLVR_ARG(ch), CLVR_ARG(step), CLVR_ARG(prm.sigma_l), CLVR_ARG(prm.sigma_a),
                                  CLVR_ARG(prm.sigma_d), CLVR_ARG(img[1 - cur])));
            CLVR_TRY(clvr_cl_run2d(cl, d->k_pass, w, h, local, NULL, err));
            cur = 1 - cur;
        }
        CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, img[cur], CL_TRUE, 0, bytes, out, 0, NULL, NULL));
    }
cleanup:
    clvr_cl_release(cl, &img[0]);
    clvr_cl_release(cl, &img[1]);
    clvr_cl_release(cl, &graw);
    clvr_cl_release(cl, &gbuf);
    clvr_cl_release(cl, &noise);
    clvr_cl_release(cl, &vbuf);
    return s;
}

clvr_status clvr_denoise_ref(uint32_t w, uint32_t h, const float *rgba, const float *guide, const float *var,
                             clvr_dn_params prm, float *out, clvr_error *err)
{
    const size_t npix = (size_t)w * h;
    if (npix == 0) return CLVR_OK;
    float *a = malloc(npix * 4 * sizeof(float)), *b = malloc(npix * 4 * sizeof(float));
    float *noise = malloc(npix * sizeof(float)), *g = malloc(npix * 4 * sizeof(float));
    if (!a || !b || !noise || !g) {
        free(a);
        free(b);
        free(noise);
        free(g);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory denoising a %ux%u image", w, h);
    }
    memcpy(a, rgba, npix * 4 * sizeof(float));
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) clvr_dn_guide_smooth(guide, w, h, x, y, g + 4 * ((size_t)y * w + x));
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            noise[(size_t)y * w + x] = var ? fminf(clvr_dn_noise(a, g, w, h, x, y), clvr_dn_noise_var(var, g, w, h, x, y))
                                           : clvr_dn_noise(a, g, w, h, x, y);
    for (uint32_t pass = 0, step = 1; pass < prm.passes && pass < CLVR_DN_MAX_PASSES; ++pass, step *= 2u) {
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x) clvr_dn_pass(a, g, noise, w, h, x, y, step, prm, b + 4 * ((size_t)y * w + x));
        float *t = a;
        a = b;
        b = t;
    }
    memcpy(out, a, npix * 4 * sizeof(float));
    free(a);
    free(b);
    free(noise);
    free(g);
    return CLVR_OK;
}

void clvr_dn_moments_variance(size_t npix, uint64_t frames, const float *sum, const float *sumsq, float *var)
{
    static const float lum[3] = {0.2126f, 0.7152f, 0.0722f};
    const double n = (double)frames;
    for (size_t p = 0; p < npix; ++p) {
        double sd = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double m = sum[4 * p + (size_t)k] / n, v = (sumsq[4 * p + (size_t)k] / n - m * m) / (n - 1.0);
            sd += lum[k] * sqrt(v > 0.0 ? v : 0.0);
        }
        var[p] = (float)(sd * sd);
    }
}

clvr_status clvr_denoise_renderer(clvr_denoiser *d, clvr_renderer *r, uint32_t w, uint32_t h, clvr_dn_params prm,
                                  float *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const size_t npix = (size_t)w * h;
    const uint64_t frames = clvr_renderer_frames(r);
    float *guide = malloc(npix * 4 * sizeof(float)), *sq = NULL, *var = NULL;
    if (!guide) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory denoising a %ux%u image", w, h);
    CLVR_TRY(clvr_renderer_read_guides(r, guide, err));
    if (frames >= 2) {
        /* The moments give the variance. */
        sq = malloc(npix * 4 * sizeof(float));
        var = malloc(npix * sizeof(float));
        if (!sq || !var) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory denoising a %ux%u image", w, h);
            goto cleanup;
        }
        CLVR_TRY(clvr_renderer_read_moments(r, out, sq, err));
        clvr_dn_moments_variance(npix, frames, out, sq, var);
    }
    /* The image as clvr_renderer_read shows it (with its control variates). */
    CLVR_TRY(clvr_renderer_read(r, out, NULL, err));
    CLVR_TRY(clvr_denoiser_run(d, w, h, out, guide, var, prm, out, err));
cleanup:
    free(guide);
    free(sq);
    free(var);
    return s;
}
