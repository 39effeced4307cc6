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
#include "pixel_cv.h"

/* Parameters: the frame, the camera, the arrays of CLVR_VOLUME_ARRAYS in
 * their order, then the outputs (host/pipeline/render.c binds them in this order). */
#define CLVR_VOLUME_PARAM(T, name) __global const T *name,
#define CLVR_VOLUME_BIND(T, name) v.name = name;

/* The light grid (urm with shadows): step `step` of its sweep
 * (clvr_light_sweep), one work item per lateral cell, same parameters as
 * clvr_render_frame then the grid (the host passes the grid's buffer as
 * both; this kernel reads and writes it through `out` only). */
__kernel void clvr_light_grid(__global const clvr_frame *fp, __global const clvr_camera *cam,
                              CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global float *out, uint step)
{
    const clvr_frame f = *fp;
    const int r = (int)f.light_res, a = (int)get_global_id(0), b = (int)get_global_id(1);
    if (a >= r || b >= r) return;
    clvr_volume v;
    v.f = &f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_BIND)
    clvr_light_sweep(&v, a, b, (int)step, out);
    (void)cam;
}
/* One frame: adds each pixel's sample to accum (and its square to
 * accum_sq), its controls to ctl (the camera ray's offset from the pixel
 * centre and its first uniform minus 1/2, kernels/pixel_cv.h), its counters
 * and, when asked, its denoiser guides. */
__kernel void clvr_render_frame(__global const clvr_frame *fp, __global const clvr_camera *cam,
                                CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global float4 *accum,
                                __global float4 *accum_sq, __global float4 *ctl, __global uint *counters,
                                __global float4 *guides)
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
    float2 d;
    clvr_render_primary_ray(cam, &f, x, y, &rng, ldp, &org, &dir, &d);
    const float u = ldp ? ldp[2] : clvr_rng_next(&rng);

    float4 result, guide;
    uint samples = 0, nulls = 0, rays = 1;
    if (f.method == CLVR_RENDER_MARCH) {
        result = clvr_render_march(&v, org, dir, u, &samples);
        guide = (float4)(result.xyz, result.w > 0.0f ? 0.0f : -1.0f); /* no depth: one flat layer */
    } else {
        result = clvr_render_track(&v, org, dir, u, &rng, ldp, &samples, &nulls, &rays, &guide);
    }
    if (f.guides) {
        /* Two float4 per pixel: albedo rgb and the frames with a depth, then
         * the sum of those depths (kernels/denoise.h reads their means). */
        const int hit = guide.w >= 0.0f;
        const float4 g0 = (float4)(guide.xyz, hit ? 1.0f : 0.0f), g1 = (float4)(hit ? guide.w : 0.0f, 0.0f, 0.0f, 0.0f);
        if (f.frame_index == 0) { guides[2u * pixel] = g0; guides[2u * pixel + 1u] = g1; }
        else { guides[2u * pixel] += g0; guides[2u * pixel + 1u] += g1; }
    }
    const float4 c4 = (float4)(d, u - 0.5f, 0.0f);
    if (f.frame_index == 0) { accum[pixel] = result; accum_sq[pixel] = result * result; ctl[pixel] = c4; }
    else { accum[pixel] += result; accum_sq[pixel] += result * result; ctl[pixel] += c4; }
    /* Counters: rays, samples (extinction lookups), null collisions, per
     * pixel, summed over frames. */
    __global uint *c = counters + 3u * pixel;
    if (f.frame_index == 0) { c[0] = rays; c[1] = samples; c[2] = nulls; }
    else { c[0] += rays; c[1] += samples; c[2] += nulls; }
}

/* The image so far, its means minus their control variates
 * (kernels/pixel_cv.h): sum and ctl as clvr_render_frame accumulates them,
 * inv_n = 1 / frames. */
__kernel void clvr_pixel_cv_image(__global const float *sum, __global const float *ctl, float inv_n, uint w, uint h,
                                  __global float4 *out)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    if (x >= w || y >= h) return;
    float o[4];
    clvr_pixel_cv(sum, ctl, inv_n, w, h, x, y, o);
    out[(ulong)y * w + x] = (float4)(o[0], o[1], o[2], o[3]);
}

/* MPI mode (docs/mpi-compositing.md). The sub-pixel position comes from the
 * frame's seed, the same on every rank, so that all ranks trace the same
 * camera ray; the estimator's draws come from the seed mixed with
 * f.mpi_rank_key (phase 1) or with it and a second constant (phase 2), so
 * that ranks, and a rank's two phases, draw independently. */
inline void clvr_mpi_streams(const clvr_frame *f, uint pixel, uint phase, clvr_rng *rng, float *ld, const float **ldp)
{
    const uint lo = f->seed_lo ^ (f->mpi_rank_key * 0x9E3779B9u), hi = f->seed_hi ^ (0x632BE5ABu * (phase + 1u));
    *rng = clvr_rng_make(pixel, f->frame_index, lo, hi);
    *ldp = NULL;
    if (f->sampler == CLVR_SAMPLER_LD) {
        clvr_ld_sample(pixel, f->frame_index, lo, hi, ld);
        *ldp = ld;
    }
}

inline void clvr_mpi_camera_ray(__global const clvr_camera *cam, const clvr_frame *f, uint x, uint y, float3 *org,
                                float3 *dir)
{
    const uint pixel = y * f->width + x;
    clvr_rng rng = clvr_rng_make(pixel, f->frame_index, f->seed_lo, f->seed_hi);
    float ld[CLVR_LD_DIMS];
    const float *ldp = NULL;
    if (f->sampler == CLVR_SAMPLER_LD) {
        clvr_ld_sample(pixel, f->frame_index, f->seed_lo, f->seed_hi, ld);
        ldp = ld;
    }
    float2 jit; /* MPI frames are composited on the host without the jitter's control variate */
    clvr_render_primary_ray(cam, f, x, y, &rng, ldp, org, dir, &jit);
}

/* Phase 1: one clvr_mpi_record per pixel. */
__kernel void clvr_render_mpi_record(__global const clvr_frame *fp, __global const clvr_camera *cam,
                                     CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global clvr_mpi_record *rec,
                                     __global uint *counters)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    const clvr_frame f = *fp;
    if (x >= f.width || y >= f.height) return;
    const uint pixel = y * f.width + x;
    clvr_volume v;
    v.f = &f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_BIND)
    float3 org, dir;
    clvr_mpi_camera_ray(cam, &f, x, y, &org, &dir);
    clvr_rng rng;
    float ld[CLVR_LD_DIMS];
    const float *ldp;
    clvr_mpi_streams(&f, pixel, 0u, &rng, ld, &ldp);
    uint samples = 0, nulls = 0;
    clvr_render_urm_record(&v, org, dir, &rng, ldp, &samples, &nulls, rec + pixel);
    counters[2u * pixel] = samples;
    counters[2u * pixel + 1u] = nulls;
}

/* Phase 2: this rank's transmittance estimate along the shadow ray from the
 * point at distance pick_t[pixel] on the pixel's camera ray (< 0: none),
 * inside its region (1 where the ray misses it). */
__kernel void clvr_render_mpi_shadow(__global const clvr_frame *fp, __global const clvr_camera *cam,
                                     CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global const float *pick_t,
                                     __global float *tau, __global uint *counters)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    const clvr_frame f = *fp;
    if (x >= f.width || y >= f.height) return;
    const uint pixel = y * f.width + x;
    const float t = pick_t[pixel];
    if (!(t >= 0.0f)) { tau[pixel] = 1.0f; return; }
    clvr_volume v;
    v.f = &f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_BIND)
    float3 org, dir;
    clvr_mpi_camera_ray(cam, &f, x, y, &org, &dir);
    clvr_rng rng;
    float ld[CLVR_LD_DIMS];
    const float *ldp;
    clvr_mpi_streams(&f, pixel, 1u, &rng, ld, &ldp);
    const float u_s = ldp ? ldp[3] : clvr_rng_next(&rng);
    uint samples = 0, nulls = 0, rays = 0;
    tau[pixel] = clvr_urm_light(&v, org + dir * t, vload3(0, f.light_dir), vload3(0, f.vol_lo), vload3(0, f.vol_hi),
                                u_s, &rng, &samples, &nulls, &rays);
    counters[2u * pixel] += samples;
    counters[2u * pixel + 1u] += nulls;
}
