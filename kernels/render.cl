/* render.cl: progressive volume path tracing of the clustered mesh (paper
 * section 3.4). One work item per pixel traces one primary ray per frame
 * through piecewise-constant majorant segments with the frame's estimator:
 * delta tracking (a collision whose colour comes from the transfer function
 * and whose light comes from a delta-tracked shadow ray toward the
 * directional light) or unbiased ray marching (a weighted quadrature with
 * ratio-tracked transmittance; kernels/render_volume.h). Majorant segments
 * come from one of three sources:
 *   track: one global majorant over the whole ray,
 *   dda:   a macrocell grid walked with 3D-DDA (Amanatides & Woo 1987),
 *   bins:  sampling clusters hit by the ray, splatted into N bins per ray
 *          segment, M segments per ray (paper 3.4.2).
 * `march` is the classic alpha-compositing ray marcher at a fixed step. */
#include "clvr_shared.h"
#include "rng.h"
#include "locate.h"
#include "render_volume.h"

/* Parameters: the frame, the camera, the arrays of CLVR_VOLUME_ARRAYS in
 * their order, then the outputs (host/pipeline/render.c binds them in this order). */
#define CLVR_VOLUME_PARAM(T, name) __global const T *name,
#define CLVR_VOLUME_BIND(T, name) v.name = name;

/* The light grid (urm with shadows): one work item per cell, same parameters
 * as clvr_render_frame then the output (the host passes the grid's buffer as
 * both; this kernel never reads the input). */
__kernel void clvr_light_grid(__global const clvr_frame *fp, __global const clvr_camera *cam,
                              CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global float *out)
{
    const clvr_frame f = *fp;
    const int r = (int)f.light_res, x = (int)get_global_id(0), y = (int)get_global_id(1), z = (int)get_global_id(2);
    if (x >= r || y >= r || z >= r) return;
    clvr_volume v;
    v.f = &f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_BIND)
    uint samples = 0, nulls = 0;
    out[clvr_grid_index(x, y, z, r)] = clvr_light_cell(&v, x, y, z, &samples, &nulls);
    (void)cam;
}
__kernel void clvr_render_frame(__global const clvr_frame *fp, __global const clvr_camera *cam,
                                CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global float4 *accum,
                                __global float4 *accum_sq, __global uint *counters)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    const clvr_frame f = *fp;
    if (x >= f.width || y >= f.height) return;
    const uint pixel = y * f.width + x;

    clvr_volume v;
    v.f = &f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_BIND)

    clvr_rng rng = clvr_rng_make(pixel, f.frame_index, f.seed_lo, f.seed_hi);
    float ld[CLVR_LD_DIMS];
    const float *ldp = NULL;
    if (f.sampler == CLVR_SAMPLER_LD) {
        clvr_ld_sample(pixel, f.frame_index, f.seed_lo, f.seed_hi, ld);
        ldp = ld;
    }
    float3 org, dir;
    clvr_render_primary_ray(cam, &f, x, y, &rng, ldp, &org, &dir);

    float4 result;
    uint samples = 0, nulls = 0, rays = 1;
    if (f.method == CLVR_RENDER_MARCH)
        result = clvr_render_march(&v, org, dir, &rng, ldp, &samples);
    else
        result = clvr_render_track(&v, org, dir, &rng, ldp, &samples, &nulls, &rays);

    if (f.frame_index == 0) { accum[pixel] = result; accum_sq[pixel] = result * result; }
    else { accum[pixel] += result; accum_sq[pixel] += result * result; }
    /* Counters: rays, samples (extinction lookups), null collisions, per
     * pixel, summed over frames. */
    __global uint *c = counters + 3u * pixel;
    if (f.frame_index == 0) { c[0] = rays; c[1] = samples; c[2] = nulls; }
    else { c[0] += rays; c[1] += samples; c[2] += nulls; }
}
