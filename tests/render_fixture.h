/* render_fixture.h: the moments of a progressive render, for tests that
 * compare two preprocessings of one mesh in distribution (partitions,
 * element boxes, split arrays): per pixel and channel, the mean and the
 * variance of n frames. Header-only, for the test programs. */
#ifndef CLVR_RENDER_FIXTURE_H
#define CLVR_RENDER_FIXTURE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "accel.h"
#include "camera.h"
#include "mesh.h"
#include "preprocess.h"
#include "render.h"
#include "tf.h"

/* Renders n frames of the clustered mesh c (trees a) with the settings set
 * (the caller's size, method, shadows and sampler: CLVR_SAMPLER_INDEPENDENT
 * for per-pixel error bars), the cool-warm transfer function at `density`
 * over m's scalar range, and a camera from eye to target (60 degrees, y up)
 * or, with eye NULL, the automatic camera on m's bounds. *mean and *var
 * receive set->width x set->height x 4 floats (allocated even on failure;
 * the caller frees them); *counters (may be NULL) the renderer's counters
 * after the n frames. */
static inline clvr_status fx_render_moments_counted(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c,
                                                    clvr_accel *a, const clvr_render_settings *set, const float *eye,
                                                    const float *target, float density, uint32_t n, float **mean,
                                                    float **var, clvr_render_counters *counters, clvr_error *err)
{
    const size_t np = (size_t)set->width * set->height * 4;
    *mean = calloc(np, sizeof(float));
    *var = calloc(np, sizeof(float));
    if (!*mean || !*var) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "render moments: out of memory");
    clvr_renderer *r = NULL;
    clvr_tf tf = {0};
    float *table = NULL;
    clvr_status s = clvr_renderer_create(cl, c, a, set, &r, err);
    if (s == CLVR_OK)
        s = clvr_tf_from_options(&tf, "cool-warm", NULL, 0, 0, 0, density, m->scalar_min, m->scalar_max, err);
    if (s == CLVR_OK) {
        clvr_tf_set_extent(&tf, m->bounds_lo, m->bounds_hi);
        const uint32_t nt = clvr_tf_table_size(&tf);
        table = malloc(nt * 4 * sizeof(float));
        if (!table) s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "render moments: out of memory");
        else {
            clvr_tf_bake(&tf, table, nt);
            s = clvr_renderer_set_tf(r, table, nt, tf.range_lo, tf.range_hi, tf.density, err);
        }
    }
    clvr_camera cam;
    const float up[3] = {0.0f, 1.0f, 0.0f};
    if (s == CLVR_OK)
        s = eye ? clvr_camera_look_at(&cam, eye, target, up, 60.0f, set->width, set->height, err)
                : clvr_camera_frame_box(&cam, m->bounds_lo, m->bounds_hi, 40.0f, set->width, set->height, err);
    if (s == CLVR_OK) s = clvr_renderer_set_camera(r, &cam, err);
    for (uint32_t i = 0; i < n && s == CLVR_OK; ++i) s = clvr_renderer_frame(r, err);
    if (s == CLVR_OK) s = clvr_renderer_read_moments(r, *mean, *var, err);
    if (s == CLVR_OK && counters) s = clvr_renderer_read(r, NULL, counters, err);
    if (s == CLVR_OK)
        for (size_t i = 0; i < np; ++i) {
            const double mu = (*mean)[i] / n, v = (*var)[i] / n - mu * mu;
            (*mean)[i] = (float)mu;
            (*var)[i] = (float)(v > 0 ? v : 0);
        }
    free(table);
    clvr_tf_free(&tf);
    clvr_renderer_destroy(r);
    return s;
}

/* fx_render_moments_counted without the counters. */
static inline clvr_status fx_render_moments_at(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a,
                                               const clvr_render_settings *set, const float *eye, const float *target,
                                               float density, uint32_t n, float **mean, float **var, clvr_error *err)
{
    return fx_render_moments_counted(cl, m, c, a, set, eye, target, density, n, mean, var, NULL, err);
}

/* The same at density 2 with the automatic camera. */
static inline clvr_status fx_render_moments(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a,
                                            const clvr_render_settings *set, uint32_t n, float **mean, float **var,
                                            clvr_error *err)
{
    return fx_render_moments_at(cl, m, c, a, set, NULL, NULL, 2.0f, n, mean, var, err);
}

/* Two moment images of n frames each (fx_render_moments) compared in
 * distribution: pixels, 4x4 pixel blocks and the whole image (per channel)
 * whose difference of means exceeds k_sigma standard errors, plus a
 * float-rounding floor of 1e-5 per pixel (a small bias spread over many
 * pixels shows in the blocks, a smaller one spread over all of them in the
 * whole image); the largest block |z|; and the summed opacity (alpha) of
 * a's means, for a test to check that the volume covers part of the image. */
typedef struct fx_moments_diff {
    size_t pixels, blocks, channels; /* channels: of the 4, those whose whole-image sums differ */
    double worst_block_z, opacity;
} fx_moments_diff;

static inline fx_moments_diff fx_compare_moments(const float *ma, const float *va, const float *mb, const float *vb,
                                                 uint32_t W, uint32_t H, uint32_t n, double k_sigma)
{
    fx_moments_diff r = {0, 0, 0, 0.0, 0.0};
    const size_t np = (size_t)W * H * 4;
    double dsum[4] = {0}, vsum[4] = {0};
    for (size_t i = 0; i < np; ++i) {
        const double se = sqrt(va[i] / n + vb[i] / n), d = fabs((double)ma[i] - mb[i]);
        if (d > k_sigma * se + 1e-5) ++r.pixels;
        if (i % 4 == 3) r.opacity += ma[i];
        dsum[i % 4] += (double)ma[i] - mb[i];
        vsum[i % 4] += va[i] / n + vb[i] / n;
    }
    /* The whole image per channel: a bias spread thin over many blocks. */
    for (size_t c = 0; c < 4; ++c)
        if (fabs(dsum[c]) > k_sigma * sqrt(vsum[c]) + 1e-5 * (double)(W * H)) ++r.channels;
    for (uint32_t by = 0; by < H; by += 4)
        for (uint32_t bx = 0; bx < W; bx += 4)
            for (size_t c = 0; c < 4; ++c) {
                double d = 0, v = 0;
                for (uint32_t y = by; y < by + 4 && y < H; ++y)
                    for (uint32_t x = bx; x < bx + 4 && x < W; ++x) {
                        const size_t i = 4 * ((size_t)y * W + x) + c;
                        d += (double)ma[i] - mb[i];
                        v += va[i] / n + vb[i] / n;
                    }
                const double z = v > 0 ? fabs(d) / sqrt(v) : 0.0;
                if (z > r.worst_block_z) r.worst_block_z = z;
                if (fabs(d) > k_sigma * sqrt(v) + 1e-5 * 16) ++r.blocks;
            }
    return r;
}

#endif /* CLVR_RENDER_FIXTURE_H */
