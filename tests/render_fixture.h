/* render_fixture.h: the moments of a progressive render, for tests that
 * compare two preprocessings of one mesh in distribution (partitions,
 * element boxes, split arrays): per pixel and channel, the mean and the
 * variance of n frames. Header-only, for the test programs. */
#ifndef CLVR_RENDER_FIXTURE_H
#define CLVR_RENDER_FIXTURE_H

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
 * the caller frees them). */
static inline clvr_status fx_render_moments_at(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a,
                                               const clvr_render_settings *set, const float *eye, const float *target,
                                               float density, uint32_t n, float **mean, float **var, clvr_error *err)
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

/* The same at density 2 with the automatic camera. */
static inline clvr_status fx_render_moments(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a,
                                            const clvr_render_settings *set, uint32_t n, float **mean, float **var,
                                            clvr_error *err)
{
    return fx_render_moments_at(cl, m, c, a, set, NULL, NULL, 2.0f, n, mean, var, err);
}

#endif /* CLVR_RENDER_FIXTURE_H */
