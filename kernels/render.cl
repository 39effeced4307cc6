/* render.cl: progressive volume path tracing of the clustered mesh (paper
 * section 3.4). One work item per pixel traces one primary ray per frame:
 * delta tracking (Woodcock tracking) through piecewise-constant majorant
 * segments finds a collision, whose colour comes from the transfer function
 * and whose light comes from a delta-tracked shadow ray toward the
 * directional light. Majorant segments come from one of three sources:
 *   track: one global majorant over the whole ray,
 *   dda:   a macrocell grid walked with 3D-DDA (Amanatides & Woo 1987),
 *   bins:  sampling clusters hit by the ray, splatted into N bins per ray
 *          segment, M segments per ray (paper 3.4.2).
 * `march` is the classic alpha-compositing ray marcher at a fixed step. */
#include "clvr_shared.h"
#include "rng.h"
#include "locate.h"
#include "render_volume.h"

__kernel void clvr_render_frame(__global const clvr_frame *fp, __global const clvr_camera *cam,
                                __global const float4 *tf_table, __global const float4 *vertices,
                                __global const ushort *idx16, __global const uint *idx32,
                                __global const clvr_instance *instances, __global const clvr_bvh_node *tlas,
                                __global const clvr_bvh_node *blas, __global const float *grid_majorants,
                                __global const float *block_majorants,
                                __global const clvr_bvh_node *sampling_bvh, __global const clvr_sampling_cluster *sampling,
                                __global const float *cluster_majorants, __global float4 *accum, __global float4 *accum_sq,
                                __global uint *counters)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    const clvr_frame f = *fp;
    if (x >= f.width || y >= f.height) return;
    const uint pixel = y * f.width + x;

    clvr_volume v;
    v.f = &f;
    v.tf = tf_table;
    v.vertices = vertices;
    v.idx16 = idx16;
    v.idx32 = idx32;
    v.instances = instances;
    v.tlas = tlas;
    v.blas = blas;
    v.grid = grid_majorants;
    v.blocks = block_majorants;
    v.sampling_bvh = sampling_bvh;
    v.sampling = sampling;
    v.cluster_majorants = cluster_majorants;

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
