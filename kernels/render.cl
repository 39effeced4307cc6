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

/* Parameters: the frame, the camera, the arrays (CLVR_VOLUME_PARAM,
 * kernels/render_volume.h), then the outputs (host/pipeline/render.c binds
 * them in this order). */

/* The light grid (with shadows): one work item per column (a, b) of its
 * r x r (clvr_light_column). Same parameters as clvr_render_frame then the
 * grid. */
__kernel void clvr_light_grid(__global const clvr_frame *fp, __global const clvr_camera *cam,
                              CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global float *out)
{
    const clvr_frame f = *fp;
    const int r = (int)f.light_res, a = (int)get_global_id(0), b = (int)get_global_id(1);
    if (a >= r || b >= r) return;
    clvr_volume v;
    v.f = &f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_BIND)
    clvr_light_column(&v, a, b, out);
    (void)cam;
}

/* A frame's sample of pixel into its sums (first: the accumulation's first
 * frame writes them): the sample, its square and its controls c4, and with
 * guides its denoiser guides from guide (colour and depth, w < 0: none),
 * two float4 per pixel: albedo rgb and the frames with a depth, then the
 * sum of those depths (kernels/denoise.h reads their means). */
inline void clvr_frame_add(uint pixel, int first, float4 result, float4 c4, uint with_guides, float4 guide,
                           __global float4 *accum, __global float4 *accum_sq, __global float4 *ctl,
                           __global float4 *guides)
{
    if (with_guides) {
        const int hit = guide.w >= 0.0f;
        const float4 g0 = (float4)(guide.xyz, hit ? 1.0f : 0.0f), g1 = (float4)(hit ? guide.w : 0.0f, 0.0f, 0.0f, 0.0f);
        if (first) { guides[2u * pixel] = g0; guides[2u * pixel + 1u] = g1; }
        else { guides[2u * pixel] += g0; guides[2u * pixel + 1u] += g1; }
    }
    if (first) { accum[pixel] = result; accum_sq[pixel] = result * result; ctl[pixel] = c4; }
    else { accum[pixel] += result; accum_sq[pixel] += result * result; ctl[pixel] += c4; }
}

/* The pixel's counters: rays, samples (extinction lookups), null
 * collisions, summed over frames and refine passes. */
inline void clvr_counters_add(__global uint *counters, uint pixel, int first, uint rays, uint samples, uint nulls)
{
    __global uint *c = counters + 3u * pixel;
    if (first) { c[0] = rays; c[1] = samples; c[2] = nulls; }
    else { c[0] += rays; c[1] += samples; c[2] += nulls; }
}

/* One frame: adds each pixel's sample to accum (and its square to
 * accum_sq), its controls to ctl (the camera ray's offset from the pixel
 * centre and its first uniform minus 1/2, kernels/pixel_cv.h), its counters
 * and, when asked, its denoiser guides. nsamp[pixel] counts the pixel's
 * samples, frames and refine passes alike, and numbers its random streams.
 *
 * A refine pass (f.pass_pixels > 0, adaptive sampling, render.h): one work
 * item per pixel of list[0 .. pass_pixels), its sample and controls added to
 * refine[2 pixel] and refine[2 pixel + 1] instead (written by the pixel's
 * first refine sample: never zeroed, and read only where nsamp exceeds the
 * frames), so that accum, accum_sq and ctl keep the frames' sums alone: the
 * pixel control variates fit those (clvr_pixel_cv_image), whose counts do
 * not depend on the list. No guides. */
__kernel void clvr_render_frame(__global const clvr_frame *fp, __global const clvr_camera *cam,
                                CLVR_VOLUME_ARRAYS(CLVR_VOLUME_PARAM) __global float4 *accum,
                                __global float4 *accum_sq, __global float4 *ctl, __global uint *counters,
                                __global float4 *guides, __global uint *nsamp, __global float4 *refine,
                                __global const uint *list)
{
    /* A pixel the frame does not trace (clvr_frame.live): its camera rays
     * miss the clip box, so it is written as clvr_render_track and
     * clvr_render_march return a miss (the background, no depth) without
     * its streams, its camera ray or the frame's copy below. Its controls
     * are 0, the centre: its value does not depend on them, and the pixels
     * whose fit reads them (kernels/pixel_cv.h) are those next to a pixel
     * that sees the box, which the live region's margin keeps traced. A
     * third of a frame's time went to such pixels on the notch at
     * 256x256. */
    if (fp->pass_pixels == 0u && fp->pilot == 0u) {
        const uint x = get_global_id(0), y = get_global_id(1), w = fp->width;
        if (x >= w || y >= fp->height) return;
        if (!clvr_frame_traces(fp, x, y)) {
            const uint pixel = y * w + x;
            const int first = fp->frame_index == 0u;
            nsamp[pixel] = first ? 1u : nsamp[pixel] + 1u;
            const float4 bg = (float4)(fp->background[0], fp->background[1], fp->background[2], 0.0f);
            clvr_frame_add(pixel, first, bg, (float4)(0.0f), fp->guides, (float4)(bg.xyz, -1.0f), accum, accum_sq, ctl,
                           guides);
            clvr_counters_add(counters, pixel, first, 1u, 0u, 0u);
            return;
        }
    }
    const clvr_frame f = *fp;
    const int pass = f.pass_pixels > 0u;
    uint x, y, pixel;
    if (pass) {
        const uint i = get_global_id(0);
        if (i >= f.pass_pixels) return;
        pixel = list[i];
        x = pixel % f.width;
        y = pixel / f.width;
    } else {
        x = get_global_id(0);
        y = get_global_id(1);
        if (x >= f.width || y >= f.height) return;
        pixel = y * f.width + x;
    }
    /* auto's pilot (f.pilot = way + 1; host/pipeline/render.c,
     * pilot_pick): list entry i's sample goes to refine[way x pass_pixels +
     * i] and nothing else is touched. A pixel is listed twice in a row, as
     * samples 0 and 1 of streams of its own (the seed's high word
     * flipped), so that the frames' samples do not depend on the pilot. */
    const int pilot = f.pilot > 0u;
    const int first = !pass && f.frame_index == 0; /* overwrites the pixel's sums */
    const uint index = pilot ? (uint)get_global_id(0) & 1u : first ? 0u : nsamp[pixel];
    if (!pilot) nsamp[pixel] = index + 1u;

    clvr_volume v;
    v.f = &f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_BIND)

    clvr_rng rng;
    float ld[CLVR_LD_DIMS];
    const float *ldp = clvr_pixel_streams(&f, pixel, index, f.seed_lo, pilot ? ~f.seed_hi : f.seed_hi, &rng, ld);
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
    if (pilot) { /* rgb and the work (the pilot's cost, counted) */
        refine[(f.pilot - 1u) * f.pass_pixels + get_global_id(0)] = (float4)(result.xyz, (float)samples);
        return;
    }
    const float4 c4 = (float4)(d, u - 0.5f, 0.0f);
    if (pass && index == f.frame_index) { refine[2u * pixel] = result; refine[2u * pixel + 1u] = c4; }
    else if (pass) {
        refine[2u * pixel] += result;
        refine[2u * pixel + 1u] += c4;
    } else {
        clvr_frame_add(pixel, first, result, c4, f.guides, guide, accum, accum_sq, ctl, guides);
    }
    clvr_counters_add(counters, pixel, first, rays, samples, nulls);
}

/* The image so far, its means minus their control variates
 * (kernels/pixel_cv.h): sum and ctl as clvr_render_frame accumulates them,
 * inv_n = 1 / frames; with refine_frames (the frames, or 0 before any
 * refine pass), a pixel with more samples than that (nsamp) also takes its
 * refine sums (clvr_render_frame) into its own mean and controls, while the
 * fit still reads the neighbours' frames alone. live: (x0, y0, x1, y1), the
 * rectangle outside which the frames traced no pixel (clvr_frame.live), or
 * the whole image (render.c reads_live). clvr_pixel_cv's arithmetic in the
 * same order, the four channels as one float4 (a third of the time of the
 * scalar loops on PoCL; test_pixel_cv compares the two). */
__kernel void clvr_pixel_cv_image(__global const float4 *sum, __global const float4 *ctl, float inv_n, uint w, uint h,
                                  __global const float4 *refine, __global const uint *nsamp, uint refine_frames,
                                  uint4 live, __global float4 *out)
{
    /* The reference's bits: no fused multiply-add (NVIDIA's compiler fuses
     * by default, and the fit's pinned weights magnify an ulp to 1e-4). */
#pragma OPENCL FP_CONTRACT OFF
    const uint x = get_global_id(0), y = get_global_id(1);
    if (x >= w || y >= h) return;
    const ulong p = (ulong)y * w + x;
    float4 mean = sum[p] * inv_n, cp = ctl[p] * inv_n;
    if (refine_frames && nsamp[p] > refine_frames) {
        const float inv = 1.0f / (float)nsamp[p];
        mean = (sum[p] + refine[2u * p]) * inv;
        cp = (ctl[p] + refine[2u * p + 1u]) * inv;
    }
    /* Outside live, the frames' live rectangle (clvr_frame.live; the
     * whole image where they traced every pixel), the pixel and its
     * neighbours were the background in every frame: flat, as
     * clvr_pixel_cv_flat finds, without reading them (80% of the notch's
     * pixels at 256x256, most of this pass's time). */
    if (x < live.x || x >= live.z || y < live.y || y >= live.w ||
        clvr_pixel_cv_flat((__global const float *)sum, w, h, x, y)) { /* the neighbours all the same: no fit */
        out[p] = mean;
        return;
    }
    float a00 = 0.0f, a10 = 0.0f, a11 = 0.0f, a20 = 0.0f, a21 = 0.0f, a22 = 0.0f, a30 = 0.0f, a31 = 0.0f, a32 = 0.0f,
          a33 = 0.0f;
    float4 b0 = (float4)(0.0f), b1 = b0, b2 = b0, b3 = b0;
    int beside_x = 0, beside_y = 0;
    for (int oy = -1; oy <= 1; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
            const int xx = (int)x + ox, yy = (int)y + oy;
            if ((ox == 0 && oy == 0) || xx < 0 || yy < 0 || xx >= (int)w || yy >= (int)h) continue;
            const ulong q = (ulong)yy * w + (ulong)xx;
            const float4 m = sum[q] * inv_n;
            if (!all(isfinite(m))) continue;
            beside_x |= ox != 0;
            beside_y |= oy != 0;
            const float4 c = ctl[q] * inv_n;
            const float r1 = (float)ox + c.x, r2 = (float)oy + c.y, r3 = c.z;
            a00 += 1.0f;
            a10 += r1; a11 += r1 * r1;
            a20 += r2; a21 += r2 * r1; a22 += r2 * r2;
            a30 += r3; a31 += r3 * r1; a32 += r3 * r2; a33 += r3 * r3;
            b0 += m; b1 += r1 * m; b2 += r2 * m; b3 += r3 * m;
        }
    a11 += beside_x ? 0.0f : CLVR_PIXEL_CV_PIN;
    a22 += beside_y ? 0.0f : CLVR_PIXEL_CV_PIN;
    a33 += CLVR_PIXEL_CV_RIDGE;
    /* Cholesky, as clvr_pixel_cv: l_ij below the diagonal, d_j on it. */
    float d = a00;
    if (!(d > 1e-4f * a00 && d > 1e-12f)) { out[p] = mean; return; }
    const float l00 = sqrt(d), l10 = a10 / l00, l20 = a20 / l00, l30 = a30 / l00;
    d = a11 - l10 * l10;
    if (!(d > 1e-4f * a11 && d > 1e-12f)) { out[p] = mean; return; }
    const float l11 = sqrt(d), l21 = (a21 - l20 * l10) / l11, l31 = (a31 - l30 * l10) / l11;
    d = a22 - l20 * l20 - l21 * l21;
    if (!(d > 1e-4f * a22 && d > 1e-12f)) { out[p] = mean; return; }
    const float l22 = sqrt(d), l32 = (a32 - l30 * l20 - l31 * l21) / l22;
    d = a33 - l30 * l30 - l31 * l31 - l32 * l32;
    if (!(d > 1e-4f * a33 && d > 1e-12f)) { out[p] = mean; return; }
    const float l33 = sqrt(d);
    const float4 z0 = b0 / l00, z1 = (b1 - l10 * z0) / l11, z2 = (b2 - l20 * z0 - l21 * z1) / l22,
                 z3 = (b3 - l30 * z0 - l31 * z1 - l32 * z2) / l33;
    const float4 c3 = z3 / l33, c2 = (z2 - l32 * c3) / l22, c1 = (z1 - l21 * c2 - l31 * c3) / l11;
    out[p] = mean - (c1 * cp.x + c2 * cp.y + c3 * cp.z);
}
