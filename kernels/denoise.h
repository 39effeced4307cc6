/* denoise.h: the optional denoiser (clvr --denoise), an edge-avoiding
 * a-trous wavelet filter (Dammertz, Sewtz, Hanika and Lensch, "Edge-Avoiding
 * A-Trous Wavelet Transform for fast Global Illumination Filtering", HPG
 * 2010), with the colour weight scaled by the local noise as in SVGF
 * (Schied et al., HPG 2017). Passes of a 5x5 B3-spline kernel whose taps
 * are 1, 2, 4, ... pixels apart; each tap is weighted by how alike the two
 * pixels are in
 *   colour:  luminance difference against the noise (estimated from the
 *            input's Laplacians, clvr_dn_noise),
 *   albedo:  the mean colour unlit (render.cl's guides), relative difference,
 *   depth:   the mean depth of the medium seen (render.cl's guides), against
 *            the depth's own gradient across the tap.
 * Pixels whose ray never met the medium (depth < 0: background) are neither
 * changed nor used. The result is biased (a smoothed image): never the
 * default, never in the convergence figures (bench_render reports its error
 * and its bias apart). Compiled for the host (reference, tests) and for
 * kernels/denoise.cl, the same arithmetic. */
#ifndef CLVR_DENOISE_H
#define CLVR_DENOISE_H

#include "clvr_shared.h"

#ifdef __OPENCL_VERSION__
#define CLVR_DN_EXP(x) exp(x)
#define CLVR_DN_SQRT(x) sqrt(x)
#define CLVR_DN_ABS(x) fabs(x)
#else
#include <math.h>
#define CLVR_DN_EXP(x) expf(x)
#define CLVR_DN_SQRT(x) sqrtf(x)
#define CLVR_DN_ABS(x) fabsf(x)
#endif

/* At most this many passes (taps 1, 2, 4, ... 2^(passes-1) pixels apart). */
#define CLVR_DN_MAX_PASSES 8u

/* Edge-stopping strengths (larger: smooths across larger differences).
 * The defaults: 256^2, urm, bench_render --converge --denoise, error after
 * 1 frame raw -> denoised without / with shadows (bias: the converged
 * reference denoised, against itself): PLOT3D post 3.07 -> 2.49% / 3.95 ->
 * 3.06% (bias 0.2-0.3%), combustor 4.56 -> 3.80% / 4.88 -> 3.93% (0.6-0.7%),
 * kiefer_tet10 7.09 -> 6.61% / 6.92 -> 6.41% (0.5%). A colour weight of 1,
 * an albedo weight of 0.1-0.2, passes 3 or 5, or guides used unsmoothed gave
 * less or a larger bias; without the albedo or the depth weight the bias
 * reached 5-30% (bench/results/render-converge/2026-11-28-s30-denoise.md).
 * What the first frames' error holds beyond the estimator's noise
 * (sub-pixel coverage at edges, structure at the pixel's scale) no
 * edge-avoiding filter removes; from about 4 frames on the raw image is
 * closer to the converged one. */
typedef struct clvr_dn_params {
    float sigma_l; /* colour: luminance differences in noise standard deviations */
    float sigma_a; /* albedo: relative difference */
    float sigma_d; /* depth: differences in units of the depth's change across the tap */
    clvr_u32 passes; /* 1 .. CLVR_DN_MAX_PASSES */
} clvr_dn_params;

CLVR_INLINE clvr_dn_params clvr_dn_params_default(void)
{
    clvr_dn_params p;
    p.sigma_l = 2.0f;
    p.sigma_a = 0.05f;
    p.sigma_d = 0.5f;
    p.passes = 4u;
    return p;
}

CLVR_INLINE float clvr_dn_lum(CLVR_GLOBAL const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* Luminance of pixel (x, y) when it and its 4 neighbours see the medium
 * (guide depth >= 0) and lie in the image: its Laplacian 4 l - (sum of the
 * 4), in *lap; 0 otherwise. */
CLVR_INLINE int clvr_dn_laplacian(CLVR_GLOBAL const float *rgba, CLVR_GLOBAL const float *guide, clvr_u32 w,
                                  clvr_u32 h, int x, int y, float *lap)
{
    if (x < 1 || y < 1 || x + 1 >= (int)w || y + 1 >= (int)h) return 0;
    const clvr_u64 p = (clvr_u64)y * w + (clvr_u64)x;
    const clvr_u64 q[4] = {p - 1, p + 1, p - w, p + w};
    if (!(guide[4 * p + 3] >= 0.0f)) return 0;
    float l = 4.0f * clvr_dn_lum(rgba + 4 * p);
    for (int k = 0; k < 4; ++k) {
        if (!(guide[4 * q[k] + 3] >= 0.0f)) return 0;
        l -= clvr_dn_lum(rgba + 4 * q[k]);
    }
    *lap = l;
    return 1;
}

/* The noise scale of pixel (x, y) of rgba (w x h, 4 floats per pixel): the
 * standard deviation of its luminance's noise, estimated from the
 * Laplacians over its 3x3 neighbourhood (for white noise of deviation s the
 * Laplacian's is sqrt(20) s, while a smooth ramp's is 0, so unlike the
 * neighbourhood's spread it does not count gradients as noise). A single
 * frame has no per-pixel variance; neighbours see nearly the same medium.
 * 0 where no neighbour has a Laplacian (then only equal colours mix). */
CLVR_INLINE float clvr_dn_noise(CLVR_GLOBAL const float *rgba, CLVR_GLOBAL const float *guide, clvr_u32 w, clvr_u32 h,
                                clvr_u32 x, clvr_u32 y)
{
    float s2 = 0.0f, n = 0.0f;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            float lap;
            if (!clvr_dn_laplacian(rgba, guide, w, h, (int)x + dx, (int)y + dy, &lap)) continue;
            s2 += lap * lap;
            n += 1.0f;
        }
    return n > 0.0f ? CLVR_DN_SQRT(s2 / (20.0f * n)) : 0.0f;
}

/* out[0 .. count-1]: the means of components 0 .. count-1 of a (stride
 * floats per pixel) over pixel (x, y)'s 3x3 neighbours that see the medium
 * (guide depth >= 0; cut at the image's edges). Returns how many there were
 * (out is left alone when none). */
CLVR_INLINE float clvr_dn_mean3x3(CLVR_GLOBAL const float *a, clvr_u32 stride, clvr_u32 count,
                                  CLVR_GLOBAL const float *guide, clvr_u32 w, clvr_u32 h, clvr_u32 x, clvr_u32 y,
                                  float *out)
{
    float sum[4] = {0.0f, 0.0f, 0.0f, 0.0f}, n = 0.0f;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const int qx = (int)x + dx, qy = (int)y + dy;
            if (qx < 0 || qy < 0 || qx >= (int)w || qy >= (int)h) continue;
            const clvr_u64 q = (clvr_u64)qy * w + (clvr_u64)qx;
            if (!(guide[4 * q + 3] >= 0.0f)) continue;
            for (clvr_u32 k = 0; k < count; ++k) sum[k] += a[stride * q + k];
            n += 1.0f;
        }
    if (n > 0.0f)
        for (clvr_u32 k = 0; k < count; ++k) out[k] = sum[k] / n;
    return n;
}

/* The guides of pixel (x, y) averaged over its 3x3 neighbours that see the
 * medium (a background pixel stays as it is): the guides come from the same
 * samples as the colour and carry their noise, which would stop the filter
 * where the image is merely noisy. Writes 4 floats. */
CLVR_INLINE void clvr_dn_guide_smooth(CLVR_GLOBAL const float *guide, clvr_u32 w, clvr_u32 h, clvr_u32 x, clvr_u32 y,
                                      float *out)
{
    const clvr_u64 p = (clvr_u64)y * w + x;
    for (int k = 0; k < 4; ++k) out[k] = guide[4 * p + (clvr_u64)k];
    if (guide[4 * p + 3] >= 0.0f) clvr_dn_mean3x3(guide, 4u, 4u, guide, w, h, x, y, out);
}

/* The noise scale of pixel (x, y) from var, the variance of each pixel's
 * mean luminance over its frames (clvr_dn_moments_variance): the square root
 * of its mean over the 3x3 neighbours that see the medium (one pixel's
 * variance from a few frames is itself noisy). It shrinks as frames
 * accumulate, so a converged image is left nearly as it is, where the
 * Laplacians' estimate would keep smoothing its structure. */
CLVR_INLINE float clvr_dn_noise_var(CLVR_GLOBAL const float *var, CLVR_GLOBAL const float *guide, clvr_u32 w,
                                    clvr_u32 h, clvr_u32 x, clvr_u32 y)
{
    float m = 0.0f;
    return clvr_dn_mean3x3(var, 1u, 1u, guide, w, h, x, y, &m) > 0.0f ? CLVR_DN_SQRT(m) : 0.0f;
}

/* One pass at pixel (x, y): taps `step` pixels apart over in (w x h rgba),
 * with the guides and the noise scale of every pixel; writes 4 floats. */
CLVR_INLINE void clvr_dn_pass(CLVR_GLOBAL const float *in, CLVR_GLOBAL const float *guide,
                              CLVR_GLOBAL const float *noise, clvr_u32 w, clvr_u32 h, clvr_u32 x, clvr_u32 y,
                              clvr_u32 step, clvr_dn_params prm, float *out)
{
    const clvr_u64 p = (clvr_u64)y * w + x;
    CLVR_GLOBAL const float *gp = guide + 4 * p;
    const float dp = gp[3];
    for (int k = 0; k < 4; ++k) out[k] = in[4 * p + (clvr_u64)k];
    if (!(dp >= 0.0f)) return; /* background: exact, left alone */
    /* The depth's change per pixel (central differences where both
     * neighbours see the medium, else one-sided, else none). */
    float grad[2] = {0.0f, 0.0f};
    for (int axis = 0; axis < 2; ++axis) {
        const int ax = axis == 0, ay = axis == 1;
        const int x0 = (int)x - ax, y0 = (int)y - ay, x1 = (int)x + ax, y1 = (int)y + ay;
        const int ok0 = x0 >= 0 && y0 >= 0 && guide[4 * ((clvr_u64)y0 * w + (clvr_u64)x0) + 3] >= 0.0f;
        const int ok1 = x1 < (int)w && y1 < (int)h && guide[4 * ((clvr_u64)y1 * w + (clvr_u64)x1) + 3] >= 0.0f;
        const float d0 = ok0 ? guide[4 * ((clvr_u64)y0 * w + (clvr_u64)x0) + 3] : dp;
        const float d1 = ok1 ? guide[4 * ((clvr_u64)y1 * w + (clvr_u64)x1) + 3] : dp;
        grad[axis] = (ok0 && ok1) ? 0.5f * (d1 - d0) : (d1 - d0);
    }
    const float lp = clvr_dn_lum(in + 4 * p);
    const float lscale = prm.sigma_l * noise[p] + 1e-6f;
    const float ap = gp[0] + gp[1] + gp[2];
    /* B3 spline taps: 3/8 at the centre, 1/4 at 1, 1/16 at 2. */
    const float kern[3] = {0.375f, 0.25f, 0.0625f};
    float sum[4] = {0.0f, 0.0f, 0.0f, 0.0f}, wsum = 0.0f;
    for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
            const int qx = (int)x + dx * (int)step, qy = (int)y + dy * (int)step;
            if (qx < 0 || qy < 0 || qx >= (int)w || qy >= (int)h) continue;
            const clvr_u64 q = (clvr_u64)qy * w + (clvr_u64)qx;
            CLVR_GLOBAL const float *gq = guide + 4 * q;
            const float dq = gq[3];
            if (!(dq >= 0.0f)) continue;
            const float hk = kern[dx < 0 ? -dx : dx] * kern[dy < 0 ? -dy : dy];
            const float dl = clvr_dn_lum(in + 4 * q) - lp;
            const float da = CLVR_DN_ABS(gq[0] - gp[0]) + CLVR_DN_ABS(gq[1] - gp[1]) + CLVR_DN_ABS(gq[2] - gp[2]);
            const float aq = gq[0] + gq[1] + gq[2];
            const float dd = dq - dp;
            const float dexp = CLVR_DN_ABS(grad[0] * (float)(dx * (int)step) + grad[1] * (float)(dy * (int)step));
            const float e = CLVR_DN_ABS(dl) / lscale + da / (prm.sigma_a * 0.5f * (ap + aq) + 1e-6f) +
                            CLVR_DN_ABS(dd) / (prm.sigma_d * dexp + 1e-3f * dp + 1e-6f);
            const float wq = hk * CLVR_DN_EXP(-e);
            for (int k = 0; k < 4; ++k) sum[k] += wq * in[4 * q + (clvr_u64)k];
            wsum += wq;
        }
    /* The centre tap always counts (e = 0 there), so wsum > 0. */
    for (int k = 0; k < 4; ++k) out[k] = sum[k] / wsum;
}

#endif /* CLVR_DENOISE_H */
