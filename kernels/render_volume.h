/* render_volume.h: the volume seen by the renderer (extinction and colour at
 * a point), the majorant segment iterator (track / dda / bins) and the
 * delta-tracking and ray-marching integrators. OpenCL C only. */
#ifndef CLVR_RENDER_VOLUME_H
#define CLVR_RENDER_VOLUME_H

#include "clvr_shared.h"
#include "rng.h"
#include "locate.h"

typedef struct clvr_volume {
    const clvr_frame *f;
    __global const float4 *tf;
    __global const float4 *vertices;
    __global const ushort *idx16;
    __global const uint *idx32;
    __global const clvr_instance *instances;
    __global const clvr_bvh_node *tlas;
    __global const clvr_bvh_node *blas;
    __global const float *grid;
    __global const float *blocks; /* dda: coarse level, see CLVR_DDA_BLOCK */
    __global const clvr_bvh_node *sampling_bvh;
    __global const clvr_sampling_cluster *sampling;
    __global const float *cluster_majorants;
} clvr_volume;

/* Transfer function at scalar s: rgb colour and extinction in w. Points
 * outside the mesh have no medium (all zero). */
inline float4 clvr_volume_tf(const clvr_volume *v, float s)
{
    return clvr_tf_sample4(v->tf, v->f->tf_size, v->f->tf_lo, v->f->tf_hi, v->f->density, s);
}

/* Point location + interpolation + transfer function. */
inline float4 clvr_volume_at(const clvr_volume *v, float3 p)
{
    float s;
    if (!clvr_locate_point((clvr_mesh_view){v->tlas, v->blas, v->instances, v->vertices, v->idx16, v->idx32,
                                            v->f->tlas_root, v->f->leaf_size}, p.x, p.y, p.z, &s))
        return (float4)(0.0f);
    return clvr_volume_tf(v, s);
}

/* Ray vs axis-aligned box, slab test; returns 0 when missed. */
inline int clvr_ray_box(float3 org, float3 dir, float3 lo, float3 hi, float *t0, float *t1)
{
    float3 inv = 1.0f / dir;
    float3 ta = (lo - org) * inv, tb = (hi - org) * inv;
    float3 tn = fmin(ta, tb), tf = fmax(ta, tb);
    float a = fmax(fmax(tn.x, tn.y), fmax(tn.z, *t0));
    float b = fmin(fmin(tf.x, tf.y), fmin(tf.z, *t1));
    *t0 = a;
    *t1 = b;
    return a <= b;
}

/* ------------------------------------------------------------ majorant segments
 * The segment iterator of the `track` and `bins` methods; `dda` walks its
 * grid in its own loop (clvr_delta_track_dda). */

typedef struct clvr_segments {
    uint method;
    float t, tend;   /* next segment starts at t; the ray ends at tend */
    int done;
    /* bins */
    uint seg, nbins, bin;
    float seg_t0, bin_len;
    float bins[32];
} clvr_segments;

inline void clvr_segments_begin(const clvr_volume *v, clvr_segments *it, float t0, float t1)
{
    const clvr_frame *f = v->f;
    it->method = f->method;
    it->t = t0;
    it->tend = t1;
    it->done = !(t0 < t1);
    if (it->method == CLVR_RENDER_BINS) {
        it->seg = 0;
        it->nbins = f->bins;
        it->bin = it->nbins; /* forces a fill of the first segment */
        it->seg_t0 = t0;
        it->bin_len = (t1 - t0) / (float)(f->segments * f->bins);
    }
}

/* Splats the majorants of the sampling clusters hit over [a, b] into bins
 * (paper 3.4.2: "rasterize" clusters into 1D segments along the ray). */
inline void clvr_segments_fill_bins(const clvr_volume *v, clvr_segments *it, float3 org, float3 dir, float a, float b)
{
    for (uint k = 0; k < it->nbins; ++k) it->bins[k] = 0.0f;
    clvr_bvh_ray_iter ri;
    clvr_bvh_ray_begin(&ri, v->sampling_bvh, org.x, org.y, org.z, dir.x, dir.y, dir.z, a, b);
    uint prim;
    float c0, c1;
    while (clvr_bvh_ray_next(&ri, v->sampling_bvh, &prim, &c0, &c1)) {
        float m = v->cluster_majorants[prim];
        if (!(m > 0.0f)) continue;
        int k0 = (int)floor((fmax(c0, a) - a) / it->bin_len);
        int k1 = (int)floor((fmin(c1, b) - a) / it->bin_len);
        k0 = clamp(k0, 0, (int)it->nbins - 1);
        k1 = clamp(k1, 0, (int)it->nbins - 1);
        for (int k = k0; k <= k1; ++k) it->bins[k] = fmax(it->bins[k], m);
    }
}

/* Next non-overlapping segment [*a, *b) with majorant *m; 0 at the end. */
inline int clvr_segments_next(const clvr_volume *v, clvr_segments *it, float3 org, float3 dir, float *a, float *b,
                              float *m)
{
    if (it->done) return 0;
    if (it->method == CLVR_RENDER_BINS) {
        if (it->bin == it->nbins) {
            if (it->seg == v->f->segments) { it->done = 1; return 0; }
            float a0 = it->seg_t0 + (float)it->seg * (float)it->nbins * it->bin_len;
            float b0 = it->seg + 1 == v->f->segments ? it->tend : a0 + (float)it->nbins * it->bin_len;
            clvr_segments_fill_bins(v, it, org, dir, a0, b0);
            it->seg++;
            it->bin = 0;
        }
        uint k = it->bin++;
        float base = it->seg_t0 + (float)((it->seg - 1) * it->nbins + k) * it->bin_len;
        *a = base;
        *b = (it->seg == v->f->segments && it->bin == it->nbins) ? it->tend : base + it->bin_len;
        *m = it->bins[k];
        return 1;
    }
    /* track: one segment, the global majorant */
    *a = it->t;
    *b = it->tend;
    *m = v->f->global_majorant;
    it->done = 1;
    return 1;
}

/* ------------------------------------------------------------ integrators */

/* Spends the free flight's remaining optical depth *tau inside one segment
 * [a, b) of majorant m > 0: tentative collisions at tau / m, accepted with
 * probability extinction / m (Woodcock). Returns 1 with the collision, or 0
 * with *tau reduced by the segment's optical depth m * (b - a). */
inline int clvr_track_segment(const clvr_volume *v, float3 org, float3 dir, float a, float b, float m, float *tau,
                              clvr_rng *rng, float *t_hit, float4 *medium, uint *samples, uint *nulls)
{
    float t = a;
    for (;;) {
        const float fly = *tau / m;
        if (t + fly >= b) {
            *tau = fmax(*tau - (b - t) * m, 0.0f);
            return 0;
        }
        t += fly;
        float4 med = clvr_volume_at(v, org + dir * t);
        ++*samples;
        if (clvr_rng_next(rng) * m < med.w) {
            *t_hit = t;
            *medium = med;
            return 1;
        }
        ++*nulls;
        *tau = -log(1.0f - clvr_rng_next(rng));
    }
}

/* Delta tracking (Woodcock) along [t0, t1]: returns 1 and the collision's
 * medium (rgb + extinction) when a real collision happens, 0 when the ray
 * leaves. u in [0, 1) is the uniform of the first free flight (the caller's
 * sampler decides where it comes from, see clvr_frame.sampler); later
 * decisions draw from rng. A free flight is an optical depth tau ~ Exp(1)
 * spent across the piecewise-constant majorant segments (tau / m world
 * units in a segment of majorant m); this equals restarting the flight at
 * every boundary (memorylessness) but needs one logarithm per tentative
 * collision instead of one per segment, which matters for DDA rays crossing
 * many cells. */
inline int clvr_delta_track(const clvr_volume *v, float3 org, float3 dir, float t0, float t1, float u,
                            clvr_rng *rng, float *t_hit, float4 *medium, uint *samples, uint *nulls)
{
    clvr_segments it;
    clvr_segments_begin(v, &it, t0, t1);
    float a, b, m;
    float tau = -log(1.0f - u);
    while (clvr_segments_next(v, &it, org, dir, &a, &b, &m))
        if (m > 0.0f && clvr_track_segment(v, org, dir, a, b, m, &tau, rng, t_hit, medium, samples, nulls)) return 1;
    return 0;
}

/* 3D-DDA (Amanatides & Woo 1987) over the cells of one axis-aligned grid
 * region, cells lo_c..hi_c (inclusive) of size cs from origin lo, along
 * [ta, tb): calls the tracker on each cell's majorant. Returns 1 with a
 * collision, 0 when the ray leaves the region (tau spent accordingly). A
 * dedicated loop with an incremental cell index: a generic segment iterator
 * would cost a call and a large private struct per cell. */
inline int clvr_dda_cells(const clvr_volume *v, __global const float *maj, int r, float3 lo, float3 cs, int3 lo_c,
                          int3 hi_c, float3 org, float3 dir, float3 inv, int3 step, float ta, float tb, float *tau,
                          clvr_rng *rng, float *t_hit, float4 *medium, uint *samples, uint *nulls)
{
    const float3 p0 = org + dir * ta;
    const int3 c = clamp(convert_int3_rtn((p0 - lo) / cs), lo_c, hi_c);
    float3 tnext = (lo + convert_float3(c + max(step, (int3)(0))) * cs - org) * inv;
    float3 tdelta = fabs(cs * inv);
    if (dir.x == 0.0f) { tnext.x = INFINITY; tdelta.x = INFINITY; }
    if (dir.y == 0.0f) { tnext.y = INFINITY; tdelta.y = INFINITY; }
    if (dir.z == 0.0f) { tnext.z = INFINITY; tdelta.z = INFINITY; }
    /* Cells left before the ray leaves the region along each axis. */
    int3 left = (int3)(step.x > 0 ? hi_c.x - c.x : c.x - lo_c.x, step.y > 0 ? hi_c.y - c.y : c.y - lo_c.y,
                       step.z > 0 ? hi_c.z - c.z : c.z - lo_c.z);
    const int sx = step.x, sy = step.y * r, sz = step.z * r * r;
    int idx = (c.z * r + c.y) * r + c.x;
    float t = ta;
    for (;;) {
        const float tx = fmin(fmin(tnext.x, tnext.y), tnext.z);
        const float b = fmin(tx, tb);
        const float m = maj[idx], depth = m * (b - t);
        if (depth < *tau) *tau -= depth; /* passes the cell: as clvr_track_segment, without its division */
        else if (m > 0.0f && clvr_track_segment(v, org, dir, t, b, m, tau, rng, t_hit, medium, samples, nulls))
            return 1;
        if (tx >= tb) return 0;
        t = b;
        if (tnext.x <= tx) {
            if (left.x-- == 0) return 0;
            idx += sx;
            tnext.x += tdelta.x;
        } else if (tnext.y <= tx) {
            if (left.y-- == 0) return 0;
            idx += sy;
            tnext.y += tdelta.y;
        } else {
            if (left.z-- == 0) return 0;
            idx += sz;
            tnext.z += tdelta.z;
        }
    }
}

/* Delta tracking through the two-level macrocell grid: a DDA over the
 * blocks (see CLVR_DDA_BLOCK); a block is skipped when empty, tracked as one
 * segment of the block majorant when its expected tentative collisions
 * m * chord are at most CLVR_DDA_DESCEND, and walked cell by cell otherwise.
 * The segmentation depends on the ray alone, so every choice is a valid
 * piecewise-constant majorant. Same estimator as clvr_delta_track: one
 * optical depth, drawn from u, spent across segments. */
inline int clvr_delta_track_dda(const clvr_volume *v, float3 org, float3 dir, float t0, float t1, float u,
                                clvr_rng *rng, float *t_hit, float4 *medium, uint *samples, uint *nulls)
{
    const clvr_frame *f = v->f;
    const float3 lo = vload3(0, f->vol_lo), hi = vload3(0, f->vol_hi);
    const int r = (int)f->grid_res, B = CLVR_DDA_BLOCK, rc = (r + B - 1) / B;
    const float3 cs = (hi - lo) / (float)r, bs = cs * (float)B;
    const float3 p0 = org + dir * t0;
    int3 c = clamp(convert_int3_rtn((p0 - lo) / bs), (int3)(0), (int3)(rc - 1));
    const int3 step = (int3)(dir.x >= 0.0f ? 1 : -1, dir.y >= 0.0f ? 1 : -1, dir.z >= 0.0f ? 1 : -1);
    const float3 inv = 1.0f / dir;
    float3 tnext = (lo + convert_float3(c + max(step, (int3)(0))) * bs - org) * inv;
    float3 tdelta = fabs(bs * inv);
    if (dir.x == 0.0f) { tnext.x = INFINITY; tdelta.x = INFINITY; }
    if (dir.y == 0.0f) { tnext.y = INFINITY; tdelta.y = INFINITY; }
    if (dir.z == 0.0f) { tnext.z = INFINITY; tdelta.z = INFINITY; }
    int3 left = (int3)(step.x > 0 ? rc - 1 - c.x : c.x, step.y > 0 ? rc - 1 - c.y : c.y,
                       step.z > 0 ? rc - 1 - c.z : c.z);
    const int sx = step.x, sy = step.y * rc, sz = step.z * rc * rc;
    int idx = (c.z * rc + c.y) * rc + c.x;
    float t = t0;
    float tau = -log(1.0f - u);
    for (;;) {
        const float tx = fmin(fmin(tnext.x, tnext.y), tnext.z);
        const float b = fmin(tx, t1);
        const float m = v->blocks[idx];
        const float depth = m * (b - t);
        if (m > 0.0f) {
            /* The choice between the block and its cells must not look at
             * tau (that would bias the flight); only the block's own
             * segment may skip the division when the flight passes it. */
            if (depth > CLVR_DDA_DESCEND) {
                if (clvr_dda_cells(v, v->grid, r, lo, cs, c * B, min(c * B + B, (int3)(r)) - 1, org, dir, inv, step, t,
                                   b, &tau, rng, t_hit, medium, samples, nulls))
                    return 1;
            } else if (depth < tau) {
                tau -= depth;
            } else if (clvr_track_segment(v, org, dir, t, b, m, &tau, rng, t_hit, medium, samples, nulls)) {
                return 1;
            }
        }
        if (tx >= t1) return 0;
        t = b;
        if (tnext.x <= tx) {
            if (left.x-- == 0) return 0;
            idx += sx;
            c.x += step.x;
            tnext.x += tdelta.x;
        } else if (tnext.y <= tx) {
            if (left.y-- == 0) return 0;
            idx += sy;
            c.y += step.y;
            tnext.y += tdelta.y;
        } else {
            if (left.z-- == 0) return 0;
            idx += sz;
            c.z += step.z;
            tnext.z += tdelta.z;
        }
    }
}

/* The tracker of the frame's method. */
inline int clvr_track(const clvr_volume *v, float3 org, float3 dir, float t0, float t1, float u, clvr_rng *rng,
                      float *t_hit, float4 *medium, uint *samples, uint *nulls)
{
    if (v->f->method == CLVR_RENDER_DDA)
        return clvr_delta_track_dda(v, org, dir, t0, t1, u, rng, t_hit, medium, samples, nulls);
    return clvr_delta_track(v, org, dir, t0, t1, u, rng, t_hit, medium, samples, nulls);
}

/* One primary ray with delta tracking and, with shadows, a delta-tracked
 * shadow ray. ld: the frame's low-discrepancy uniforms (CLVR_LD_DIMS), or
 * NULL for the independent sampler; dimension 2 drives the primary ray's
 * first free flight and 3 the shadow ray's. Without ld the draws come from
 * rng in the order of the original sampler (primary flight right away,
 * shadow flight after the primary ray's draws). */
inline float4 clvr_render_track(const clvr_volume *v, float3 org, float3 dir, clvr_rng *rng, const float *ld,
                                 uint *samples, uint *nulls, uint *rays)
{
    const clvr_frame *f = v->f;
    float3 lo = vload3(0, f->vol_lo), hi = vload3(0, f->vol_hi);
    float t0 = 0.0f, t1 = INFINITY;
    float4 bg = (float4)(vload3(0, f->background), 0.0f);
    if (!clvr_ray_box(org, dir, lo, hi, &t0, &t1)) return bg;
    float t;
    float4 med;
    const float u_primary = ld ? ld[2] : clvr_rng_next(rng);
    if (!clvr_track(v, org, dir, t0, t1, u_primary, rng, &t, &med, samples, nulls)) return bg;
    float light = 1.0f;
    if (f->shadows) {
        float3 p = org + dir * t, ldir = vload3(0, f->light_dir);
        float s0 = 0.0f, s1 = INFINITY;
        ++*rays;
        if (clvr_ray_box(p, ldir, lo, hi, &s0, &s1)) {
            float ts;
            float4 m2;
            const float u_shadow = ld ? ld[3] : clvr_rng_next(rng);
            if (clvr_track(v, p, ldir, s0, s1, u_shadow, rng, &ts, &m2, samples, nulls)) light = 0.0f;
        }
    }
    float shade = f->ambient + f->light_intensity * light;
    return (float4)(med.xyz * shade, 1.0f);
}

/* Front-to-back alpha compositing at a fixed step with a random offset per
 * frame (so frames average to the continuous integral); no shadows. ld as in
 * clvr_render_track: dimension 2 gives the offset. */
inline float4 clvr_render_march(const clvr_volume *v, float3 org, float3 dir, clvr_rng *rng, const float *ld,
                                uint *samples)
{
    const clvr_frame *f = v->f;
    float3 lo = vload3(0, f->vol_lo), hi = vload3(0, f->vol_hi);
    float t0 = 0.0f, t1 = INFINITY;
    float4 bg = (float4)(vload3(0, f->background), 0.0f);
    if (!clvr_ray_box(org, dir, lo, hi, &t0, &t1)) return bg;
    float3 c = (float3)(0.0f);
    float T = 1.0f;
    const float shade = f->ambient + f->light_intensity;
    const float u = ld ? ld[2] : clvr_rng_next(rng);
    for (float t = t0 + u * f->step; t < t1 && T > 1e-6f; t += f->step) {
        float4 med = clvr_volume_at(v, org + dir * t);
        ++*samples;
        float dt = fmin(f->step, t1 - t);
        float alpha = 1.0f - exp(-med.w * dt);
        c += T * alpha * med.xyz * shade;
        T *= 1.0f - alpha;
    }
    return (float4)(c + T * bg.xyz, 1.0f - T);
}

/* Primary ray through pixel (x, y) with a random sub-pixel position
 * (dimensions 0 and 1 of ld, or two draws of rng when ld is NULL). */
inline void clvr_render_primary_ray(__global const clvr_camera *cam, const clvr_frame *f, uint x, uint y,
                                    clvr_rng *rng, const float *ld, float3 *org, float3 *dir)
{
    float jx = ld ? ld[0] : clvr_rng_next(rng), jy = ld ? ld[1] : clvr_rng_next(rng);
    clvr_camera c = *cam;
    float o[3], d[3];
    clvr_camera_ray(&c, (float)x + jx, (float)y + jy, o, d);
    *org = vload3(0, o);
    *dir = vload3(0, d);
    (void)f;
}

#endif
