/* pixel_cv.h: control variates for the draws every frame makes per pixel,
 * applied to the running image (clvr_renderer_read). clvr_pixel_cv is the
 * plain-C reference; kernels/render.cl's clvr_pixel_cv_image runs the same
 * arithmetic in the same order with the four channels as one float4.
 *
 * A pixel's running mean M is the mean of its frames' samples. Two of each
 * frame's draws move a sample in a way its neighbours can predict:
 *  - the box filter's jitter d in [-1/2, 1/2)^2, the camera ray's offset
 *    from the pixel centre: where the image varies across the pixel, the
 *    sample is close to its box value plus g.d, g the image's gradient;
 *  - the camera ray's first uniform u (urm's quadrature offset, delta
 *    tracking's first free flight, march's offset): a quadrature over
 *    points k + u errs by about (u - 1/2) (g(end) - g(start)) (the
 *    Euler-Maclaurin term of a shifted rule), which varies smoothly across
 *    the image.
 * Both have known mean 0 (d) and 1/2 (u). With D and U the pixel's means
 * of d and of u - 1/2 over its frames, the image shown is
 *     M - (gx Dx + gy Dy + b U),
 * where (a, gx, gy, b) is the least-squares fit of M_j ~ a + gx X_j + gy Y_j
 * + b U_j over the 8 neighbours j (X_j, Y_j: the mean positions of their
 * rays relative to the pixel's centre), with a ridge CLVR_PIXEL_CV_RIDGE on
 * b. The fit reads other pixels' draws only, independent of the pixel's own
 * (each pixel draws its own sampler stream), so E[fit . (D, U)] = E[fit] .
 * E[(D, U)] = 0: every pixel keeps its expected value, whatever the fit is.
 * That holds for any deterministic choice of the fit: the ridge and the
 * rules below change the noise only.
 *
 * Why on the running means and not frame by frame: the low-discrepancy
 * sampler already spreads a pixel's d and u over their ranges, so D and U
 * shrink as frames accumulate (and so does the noise the fit adds); frame
 * by frame, the jitter term alone cost error from 4 frames on. The ridge
 * keeps b small once the neighbours' U no longer spread enough to measure
 * it (without: error after 4 frames 0.33 -> 0.91% on the PLOT3D post).
 * 256^2, urm, relative error after 1 / 2 / 4 frames without shadows, off ->
 * on: PLOT3D post 3.07 / 1.13 / 0.38 -> 1.57 / 0.79 / 0.32%, combustor
 * 4.55 / 1.98 / 1.01 -> 2.98 / 1.67 / 0.97%, 1M tets 4.11 / 1.65 / 0.81 ->
 * 1.83 / 1.10 / 0.73%; the jitter alone (no u term) gave 2.29% and 3.47%
 * after one frame, a fit over the shadow ray's offset or urm's pick lost
 * (bench/results/render-converge/2026-11-28-s32-pixel-cv.md).
 *
 * With adaptive sampling (render.h settings.adaptive) some pixels also
 * have refine samples, kept in their own sums. A pixel's M and (D, U) then
 * take in all its samples, but the fit still reads its neighbours' frames
 * alone: how many refine samples a neighbour got depends on the values
 * around that neighbour, the pixel's own among them, and a fit that read
 * them would no longer be independent of the pixel's draws. */
#ifndef CLVR_PIXEL_CV_H
#define CLVR_PIXEL_CV_H

#include "clvr_shared.h"

#ifdef __OPENCL_VERSION__
#define CLVR_CV_SQRT(x) sqrt(x)
#define CLVR_CV_FINITE(x) isfinite(x)
#else
#include <math.h>
#define CLVR_CV_SQRT(x) sqrtf(x)
#define CLVR_CV_FINITE(x) isfinite(x)
#endif

#define CLVR_PIXEL_CV_RIDGE 0.1f
/* A gradient the neighbours cannot measure (no neighbour beside the pixel
 * on that axis: a 1-pixel-wide image) is held near 0 by this ridge. */
#define CLVR_PIXEL_CV_PIN 1.0e4f

/* 1 when the 8 neighbours' sums (those inside the image) are all the same,
 * bit for bit: then the fit's gradient and u slope are 0 and the pixel's
 * mean is its value, without the fit (the background, most of many
 * images, where the fit was half the image pass's time). It reads the
 * neighbours only, as the fit does, so the pixel keeps its expected value.
 * A NaN neighbour never compares equal: the fit then decides. */
CLVR_INLINE int clvr_pixel_cv_flat(CLVR_GLOBAL const float *sum, clvr_u32 w, clvr_u32 h, clvr_u32 x, clvr_u32 y)
{
    int n = 0, same = 1;
    clvr_u64 q0 = 0;
    for (int oy = -1; oy <= 1 && same; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
            const int xx = (int)x + ox, yy = (int)y + oy;
            if ((ox == 0 && oy == 0) || xx < 0 || yy < 0 || xx >= (int)w || yy >= (int)h) continue;
            const clvr_u64 q = (clvr_u64)yy * w + (clvr_u64)xx;
            if (n++ == 0) {
                q0 = q;
                continue;
            }
            for (int k = 0; k < 4; ++k) same &= sum[4u * q + (clvr_u64)k] == sum[4u * q0 + (clvr_u64)k];
        }
    return same && n > 0;
}

/* sum: the frames' summed rgba samples per pixel; ctl: per pixel the summed
 * controls (dx, dy, u - 1/2, unused); inv_n: 1 / frames; w x h row by row.
 * refine (NULL: none): per pixel the refine passes' summed samples and
 * controls (8 floats), read where nsamp, its count of samples, exceeds
 * frames (frames = 1 / inv_n).
 * out: pixel (x, y)'s mean rgba minus its control variate. */
CLVR_INLINE void clvr_pixel_cv(CLVR_GLOBAL const float *sum, CLVR_GLOBAL const float *ctl, float inv_n,
                               CLVR_GLOBAL const float *refine, CLVR_GLOBAL const clvr_u32 *nsamp, clvr_u32 frames,
                               clvr_u32 w,
                               clvr_u32 h, clvr_u32 x, clvr_u32 y, float *out)
{
    /* Normal equations A c = B of the fit: A symmetric 4x4 (lower half
     * used), B one column per channel. */
    float A[4][4] = {{0.0f}}, B[4][4] = {{0.0f}};
    int beside_x = 0, beside_y = 0;
    const clvr_u64 p = (clvr_u64)y * w + (clvr_u64)x;
    /* The pixel's own mean and mean controls (c[0] unused). */
    float c[4] = {0.0f, ctl[4u * p] * inv_n, ctl[4u * p + 1u] * inv_n, ctl[4u * p + 2u] * inv_n};
    for (int k = 0; k < 4; ++k) out[k] = sum[4u * p + (clvr_u64)k] * inv_n;
    if (refine && nsamp[p] > frames) {
        const float inv = 1.0f / (float)nsamp[p];
        for (int k = 0; k < 4; ++k) out[k] = (sum[4u * p + (clvr_u64)k] + refine[8u * p + (clvr_u64)k]) * inv;
        for (int k = 0; k < 3; ++k) c[k + 1] = (ctl[4u * p + (clvr_u64)k] + refine[8u * p + 4u + (clvr_u64)k]) * inv;
    }
    if (clvr_pixel_cv_flat(sum, w, h, x, y)) return;
    for (int oy = -1; oy <= 1; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
            const int xx = (int)x + ox, yy = (int)y + oy;
            if ((ox == 0 && oy == 0) || xx < 0 || yy < 0 || xx >= (int)w || yy >= (int)h) continue;
            const clvr_u64 q = (clvr_u64)yy * w + (clvr_u64)xx;
            float m[4];
            int finite = 1;
            for (int k = 0; k < 4; ++k) {
                m[k] = sum[4u * q + (clvr_u64)k] * inv_n;
                finite &= CLVR_CV_FINITE(m[k]) ? 1 : 0;
            }
            if (!finite) continue;
            beside_x |= ox != 0;
            beside_y |= oy != 0;
            const float r[4] = {1.0f, (float)ox + ctl[4u * q] * inv_n, (float)oy + ctl[4u * q + 1u] * inv_n,
                                ctl[4u * q + 2u] * inv_n};
            for (int i = 0; i < 4; ++i) {
                for (int j = 0; j <= i; ++j) A[i][j] += r[i] * r[j];
                for (int k = 0; k < 4; ++k) B[k][i] += r[i] * m[k];
            }
        }
    A[1][1] += beside_x ? 0.0f : CLVR_PIXEL_CV_PIN;
    A[2][2] += beside_y ? 0.0f : CLVR_PIXEL_CV_PIN;
    A[3][3] += CLVR_PIXEL_CV_RIDGE;
    /* Cholesky A = L L^T in place; a pivot that is not clearly positive
     * (fewer neighbours than unknowns) leaves the mean as it is. */
    for (int j = 0; j < 4; ++j) {
        float d = A[j][j];
        for (int k = 0; k < j; ++k) d -= A[j][k] * A[j][k];
        if (!(d > 1e-4f * A[j][j] && d > 1e-12f)) return;
        A[j][j] = CLVR_CV_SQRT(d);
        for (int i = j + 1; i < 4; ++i) {
            float s = A[i][j];
            for (int k = 0; k < j; ++k) s -= A[i][k] * A[j][k];
            A[i][j] = s / A[j][j];
        }
    }
    for (int k = 0; k < 4; ++k) {
        float z[4], coef[4];
        for (int i = 0; i < 4; ++i) { /* L z = B */
            float s = B[k][i];
            for (int j = 0; j < i; ++j) s -= A[i][j] * z[j];
            z[i] = s / A[i][i];
        }
        for (int i = 3; i >= 0; --i) { /* L^T coef = z */
            float s = z[i];
            for (int j = i + 1; j < 4; ++j) s -= A[j][i] * coef[j];
            coef[i] = s / A[i][i];
        }
        out[k] -= coef[1] * c[1] + coef[2] * c[2] + coef[3] * c[3];
    }
}

#endif
