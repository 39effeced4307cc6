/* denoise.cl: the optional denoiser's passes over a w x h rgba image
 * (kernels/denoise.h, which the host reference runs too). One work item
 * per pixel. */
#include "clvr_shared.h"
#include "denoise.h"

/* noise[p]: clvr_dn_noise_var of var when has_var, else clvr_dn_noise of
 * the input image. */
__kernel void clvr_dn_noise_map(__global const float *rgba, __global const float *guide, __global const float *var,
                                uint has_var, uint w, uint h, __global float *noise)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    if (x >= w || y >= h) return;
    const float lap = clvr_dn_noise(rgba, guide, w, h, x, y);
    noise[(ulong)y * w + x] = has_var ? fmin(lap, clvr_dn_noise_var(var, guide, w, h, x, y)) : lap;
}

/* smooth[p]: clvr_dn_guide_smooth of the guides. */
__kernel void clvr_dn_guides(__global const float *guide, uint w, uint h, __global float *smooth)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    if (x >= w || y >= h) return;
    float o[4];
    clvr_dn_guide_smooth(guide, w, h, x, y, o);
    vstore4((float4)(o[0], o[1], o[2], o[3]), (ulong)y * w + x, smooth);
}

/* One a-trous pass with taps `step` pixels apart, in -> out. */
__kernel void clvr_dn_atrous(__global const float *in, __global const float *guide, __global const float *noise,
                             uint w, uint h, uint step, float sigma_l, float sigma_a, float sigma_d,
                             __global float *out)
{
    const uint x = get_global_id(0), y = get_global_id(1);
    if (x >= w || y >= h) return;
    clvr_dn_params prm;
    prm.sigma_l = sigma_l;
    prm.sigma_a = sigma_a;
    prm.sigma_d = sigma_d;
    float o[4];
    clvr_dn_pass(in, guide, noise, w, h, x, y, step, prm, o);
    vstore4((float4)(o[0], o[1], o[2], o[3]), (ulong)y * w + x, out);
}
