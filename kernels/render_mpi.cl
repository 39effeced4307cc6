/* render_mpi.cl: MPI mode's two kernels (docs/mpi-compositing.md), a program
 * of their own beside render.cl. host/pipeline/render.c builds it at the first
 * MPI frame, so a render without MPI never compiles them: on NVIDIA's driver
 * their code cost 28 s of the render program's 211 s cold build (ptxas, H200,
 * session 42). */
#include "clvr_shared.h"
#include "rng.h"
#include "locate.h"
#include "render_volume.h"

/* MPI mode (docs/mpi-compositing.md). The sub-pixel position comes from the
 * frame's seed, the same on every rank, so that all ranks trace the same
 * camera ray; the estimator's draws come from the seed mixed with
 * f.mpi_rank_key (phase 1) or with it and a second constant (phase 2), so
 * that ranks, and a rank's two phases, draw independently. */
inline void clvr_mpi_streams(const clvr_frame *f, uint pixel, uint phase, clvr_rng *rng, float *ld, const float **ldp)
{
    const uint lo = f->seed_lo ^ (f->mpi_rank_key * 0x9E3779B9u), hi = f->seed_hi ^ (0x632BE5ABu * (phase + 1u));
    *ldp = clvr_pixel_streams(f, pixel, f->frame_index, lo, hi, rng, ld);
}

inline void clvr_mpi_camera_ray(__global const clvr_camera *cam, const clvr_frame *f, uint x, uint y, float3 *org,
                                float3 *dir)
{
    const uint pixel = y * f->width + x;
    clvr_rng rng;
    float ld[CLVR_LD_DIMS];
    const float *ldp = clvr_pixel_streams(f, pixel, f->frame_index, f->seed_lo, f->seed_hi, &rng, ld);
    float2 jit; /* rank 0 draws it again on the host (host/mpi/mpi_main.c, add_jitters) */
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
