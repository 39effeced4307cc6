/* render_volume.h: the volume seen by the renderer (extinction and colour at
 * a point), the majorant iterators (track / bins / dda), the estimators that
 * consume their segments (delta tracking, unbiased ray marching) and the
 * alpha-compositing ray marcher. OpenCL C only. */
#ifndef CLVR_RENDER_VOLUME_H
#define CLVR_RENDER_VOLUME_H

#include "clvr_shared.h"
#include "rng.h"
#include "locate.h"
#include "hull.h"
#include "cell_ray.h"
#include "exp_neg.h"

/* The frame and the device arrays of CLVR_VOLUME_ARRAYS (clvr_shared.h). */
#define CLVR_VOLUME_FIELD(T, name) __global const T *name;
typedef struct clvr_volume {
    const clvr_frame *f;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_FIELD)
} clvr_volume;
#undef CLVR_VOLUME_FIELD
/* A kernel takes the arrays as parameters (CLVR_VOLUME_PARAM, in
 * CLVR_VOLUME_ARRAYS's order, which host/pipeline/render.c binds) and fills
 * its clvr_volume v from them (CLVR_VOLUME_BIND). */
#define CLVR_VOLUME_PARAM(T, name) __global const T *name,
#define CLVR_VOLUME_BIND(T, name) v.name = name;

/* Transfer function at scalar s: rgb colour and extinction in w. Points
 * outside the mesh have no medium (all zero). */
inline float4 clvr_volume_tf(const clvr_volume *v, float s)
{
    return clvr_tf_sample4(v->tf, v->f->tf_size, v->f->tf_lo, v->f->tf_hi, v->f->density, s);
}

/* The volume's point-location view, all pieces of the split arrays. */
inline clvr_mesh_view clvr_volume_view(const clvr_volume *v)
{
    return (clvr_mesh_view){v->tlas,
                            v->blas,
                            v->instances,
                            v->vertices,
                            v->idx16,
                            v->idx32,
                            v->f->tlas_root,
                            v->f->leaf_size,
                            v->ebox,
                            {{v->vertices1, v->idx16_1, v->idx32_1, v->ebox1},
                             {v->vertices2, v->idx16_2, v->idx32_2, v->ebox2},
                             {v->vertices3, v->idx16_3, v->idx32_3, v->ebox3}},
                            v->entry_grids,
                            v->entry_cells};
}

/* Point location + interpolation + transfer function. */
inline float4 clvr_volume_at(const clvr_volume *v, float3 p)
{
    float s;
    if (!clvr_locate_point(clvr_volume_view(v), p.x, p.y, p.z, &s))
        return (float4)(0.0f);
    return clvr_volume_tf(v, s);
}

/* The stretch of a ray inside the tet its last lookup found: [t0, t_end]
 * with the scalar linear in t (s0 at t0, ds/dt dsdt). A ray's lookups go
 * forward in t and, where elements are large against the spacing of its
 * points, often land in the tet the previous one found; those are answered
 * from here without a lookup (the same value up to rounding: the tet's own
 * interpolation). Other cell types are not linear along a ray and keep no
 * span. t_end < t0: none. Share of a chord's 24 points in the tet of the
 * point before (bench_walk --order rays): notch_stress cut into 13k tets
 * 53%, blunt fin 13%, fire_ug 11%, post 6%, combustor 1%. urm frames at
 * 256^2 (interleaved runs, no shadows): the 13k-tet notch 27.5 -> 18.2 ms,
 * kiefer_tet10 87 -> 65 ms, fire_ug 62 -> 57 ms, 1M tets 139 -> 134 ms;
 * post, blunt fin and combustor within 1%, the mixed built-in scene +1.7%
 * (the instance's type read after each lookup). */
typedef struct clvr_span {
    float t0, t_end, s0, dsdt;
    /* The cell of another type the last lookup found (in instance
     * clvr_locate_hint.inst), or CLVR_BVH_NOT_FOUND: the next lookup tests
     * it first (its box, then its map's inverse: the same containment test
     * as a walk's) before any tree walk. 256^2 urm frames (interleaved
     * runs): notch_stress's 2,192 hexes and wedges 34.8 -> 28.9 ms without
     * shadows, 51.5 -> 39.1 ms with; the AMR-like 1M hexes 41.8 -> 37.6 ms;
     * the built-in mixed scene 147 -> 138 ms with shadows; tet meshes
     * within 1%. Newton then starts from the coordinates of the span's
     * last point (pu, pv, pw), not the cell's centre: the notch 31.2 ->
     * 26.6 ms without shadows, 39.8 -> 36.9 ms with; AMR-like and built-in
     * scene -1%. */
    uint elem;
    float pu, pv, pw; /* elem's parametric coordinates at the last point the span answered; pu NaN: none */
    /* ... at ray parameter t_pt, moving by (du, dv, dw) per unit t there
     * (from the two points before; 0 until then): Newton starts where that
     * line predicts, exact for an affine cell. With Newton's last shape
     * functions interpolating (clvr_element_sample_near), 256^2 urm frames
     * (interleaved runs): notch_stress's hexes 27.8 -> 25.7 ms without
     * shadows, 39.8 -> 35.7 ms with; the combustor as 258k curvilinear
     * hexes 132 -> 127 ms; AMR-like 41.4 -> 40.0 ms; built-in scene 154 ->
     * 152 ms with shadows; post as tets unchanged (148.5 -> 149.7). */
    float t_pt, du, dv, dw;
} clvr_span;

inline clvr_span clvr_span_none(void)
{
    return (clvr_span){0.0f, -1.0f, 0.0f, 0.0f, CLVR_BVH_NOT_FOUND, NAN, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
}

/* Tet vtx's barycentric coordinates l[k] at org + t dir and their rates
 * g[k] along dir (the same cofactors as clvr_tet_sample); 0 for a flat
 * tet. */
inline int clvr_tet_bary(const clvr_vec4 *vtx, float3 org, float3 dir, float t, float *l, float *g)
{
    const float3 o = (float3)(vtx[0].x, vtx[0].y, vtx[0].z);
    const float3 a = (float3)(vtx[1].x, vtx[1].y, vtx[1].z) - o, b = (float3)(vtx[2].x, vtx[2].y, vtx[2].z) - o;
    const float3 c = (float3)(vtx[3].x, vtx[3].y, vtx[3].z) - o;
    const float3 bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
    const float det = dot(a, bc);
    if (!(fabs(det) > 0.0f)) return 0;
    const float inv = 1.0f / det;
    const float3 r = org + dir * t - o;
    l[1] = dot(r, bc) * inv; l[2] = dot(r, ca) * inv; l[3] = dot(r, ab) * inv;
    l[0] = 1.0f - l[1] - l[2] - l[3];
    g[1] = dot(dir, bc) * inv; g[2] = dot(dir, ca) * inv; g[3] = dot(dir, ab) * inv;
    g[0] = -(g[1] + g[2] + g[3]);
    return 1;
}

/* Where the ray leaves the tet: the face opposite the first barycentric to
 * reach 0 (index returned, -1 when none falls), *dt the distance to it in
 * t (INFINITY when none). */
inline int clvr_tet_exit(const float *l, const float *g, float *dt)
{
    int kx = -1;
    *dt = INFINITY;
    for (int k = 0; k < 4; ++k)
        if (g[k] < 0.0f && l[k] / -g[k] < *dt) {
            *dt = l[k] / -g[k];
            kx = k;
        }
    return kx;
}

/* The span of tet vtx along the ray org + t dir from t (inside it, scalar
 * s there): exit where the first barycentric reaches 0. */
inline clvr_span clvr_tet_span(const clvr_vec4 *vtx, float3 org, float3 dir, float t, float s)
{
    clvr_span sp = clvr_span_none();
    float l[4], g[4], dt;
    if (!clvr_tet_bary(vtx, org, dir, t, l, g)) return sp;
    clvr_tet_exit(l, g, &dt);
    if (!(dt > 0.0f) || !(dt < INFINITY)) return sp;
    sp.t0 = t;
    sp.t_end = t + dt;
    sp.s0 = s;
    sp.dsdt = g[0] * vtx[0].w + g[1] * vtx[1].w + g[2] * vtx[2].w + g[3] * vtx[3].w;
    return sp;
}

/* clvr_volume_at at org + t dir with the ray's point-location hint
 * (clvr_locate_hinted), answered from the ray's span when t lies in it; a
 * tet found by a lookup becomes the new span. */
inline float4 clvr_volume_at_ray(const clvr_volume *v, float3 org, float3 dir, float t, clvr_locate_hint *h,
                                 clvr_span *sp)
{
    if (t >= sp->t0 && t <= sp->t_end) return clvr_volume_tf(v, sp->s0 + (t - sp->t0) * sp->dsdt);
    const clvr_mesh_view m = clvr_volume_view(v);
    const float3 p = org + dir * t;
    float s;
    /* The kept cell, once it has settled that p is outside it, is not
     * tested again by the walk below (from its centre, Newton's longest
     * solve). Only settled: where Newton gave up from the predicted start,
     * the walk's start may still find p inside. 256^2 urm frames
     * (interleaved runs, two sets): the combustor as hexes 118.6 -> 114.4
     * and 115.6 -> 111.4 ms, notch_stress's hexes 21.8 -> 21.4 and 21.7 ->
     * 21.2 ms; skipping it unsettled too was 1-2% faster still and is not
     * safe. */
    clvr_u32 skip = CLVR_BVH_NOT_FOUND;
    if (sp->elem != CLVR_BVH_NOT_FOUND) {
        const clvr_instance inst = m.instances[h->inst];
        const clvr_piece_arrays pa = clvr_view_piece(&m, &inst);
        clvr_vec4 vtx[CLVR_CELL_MAX_VERTS];
        /* a collapsed hex as the cell it is (its Newton starts from its own coordinates) */
        const uint type = clvr_load_cell_in(&pa, &inst, sp->elem, vtx);
        if (type == CLVR_CELL_TET) {
            /* A tet as a collapsed hex (one curve): its span starts here,
             * at the first point after the lookup that found it (a tet of
             * a tet instance gets it at the lookup; decoding there would
             * cost every hex mesh a load per lookup). */
            if (clvr_tet_sample(vtx, p.x, p.y, p.z, &s)) {
                *sp = clvr_tet_span(vtx, org, dir, t, s);
                return clvr_volume_tf(v, s);
            }
            skip = sp->elem; /* outside, exactly */
        } else {
            const float dt = t - sp->t_pt;
            float u = sp->pu + sp->du * dt, vv = sp->pv + sp->dv * dt, w = sp->pw + sp->dw * dt;
            int settled = 1;
            /* Hexes get their own inlined copy of the solve, the cell type a
             * constant: the shape functions' switch and the loops over the
             * vertices fold (Newton, its shape functions and its 3x3 solve are
             * forced inline; PoCL left them calls). 256^2 urm frames
             * (interleaved runs): notch_stress's hexes 21.3 -> 20.3 ms, the
             * combustor as hexes 109.8 -> 105.7 ms; mixed and AMR-like scenes
             * within 1%; a cold kernel build 5.4 -> 5.7 s. */
            if (clvr_element_box_test(type, vtx, p.x, p.y, p.z) &&
                (type == CLVR_CELL_HEX
                     ? clvr_element_sample_near_settled(CLVR_CELL_HEX, vtx, p.x, p.y, p.z, !isnan(u), &u, &vv, &w, &s,
                                                        &settled)
                     : clvr_element_sample_near_settled(type, vtx, p.x, p.y, p.z, !isnan(u), &u, &vv, &w, &s,
                                                        &settled))) {
                if (!isnan(sp->pu) && dt != 0.0f) {
                    const float inv = 1.0f / dt;
                    sp->du = (u - sp->pu) * inv; sp->dv = (vv - sp->pv) * inv; sp->dw = (w - sp->pw) * inv;
                }
                sp->pu = u; sp->pv = vv; sp->pw = w;
                sp->t_pt = t;
                return clvr_volume_tf(v, s);
            }
            if (settled) skip = sp->elem;
        }
    }
    clvr_u32 e;
    if (!clvr_locate_hinted_skip(&m, p.x, p.y, p.z, h, skip, &s, &e)) {
        sp->elem = CLVR_BVH_NOT_FOUND;
        return (float4)(0.0f);
    }
    const clvr_instance inst = m.instances[h->inst];
    if (inst.type == CLVR_CELL_TET) {
        const clvr_piece_arrays pa = clvr_view_piece(&m, &inst);
        clvr_vec4 vtx[4];
        clvr_load_tet(&pa, &inst, e, vtx);
        *sp = clvr_tet_span(vtx, org, dir, t, s);
        return clvr_volume_tf(v, s);
    }
    *sp = clvr_span_none();
    sp->elem = e;
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

/* Ray vs the frame's clip box (lo, hi) and clip planes: cuts [t0, t1] to the
 * part of the ray inside every kept half-space n.p <= d (clvr_frame);
 * returns 0 when nothing is left. A ray parallel to a plane is kept whole
 * or dropped whole by the side its origin is on. */
inline int clvr_ray_clip(const clvr_frame *f, float3 org, float3 dir, float3 lo, float3 hi, float *t0, float *t1)
{
    if (!clvr_ray_box(org, dir, lo, hi, t0, t1)) return 0;
    for (uint i = 0; i < f->num_clip_planes && i < CLVR_MAX_CLIP_PLANES; ++i) {
        const float3 n = vload3(0, f->clip_planes[i]);
        const float den = dot(n, dir), num = f->clip_planes[i][3] - dot(n, org);
        if (den > 0.0f) *t1 = fmin(*t1, num / den);
        else if (den < 0.0f) *t0 = fmax(*t0, num / den);
        else if (num < 0.0f) return 0;
    }
    return *t0 <= *t1;
}

/* Cuts [t0, t1] to the part of the ray between its first and last crossing
 * of the mesh's boundary faces (kernels/hull.h); 0 when the ray misses the
 * mesh. Camera rays and shadow rays are cut (the light grid's columns,
 * whose segments are short, take the box and clip planes only). Nothing
 * changes without a hull (or with settings.hull off). 256^2, frames to 2%
 * relative RMSE without / with shadows, against no cut: PLOT3D combustor
 * 8 / 11 -> 3 / 4, kiefer_tet10 7 / 8 -> 4 / 4, post 2 / 3 -> 2 / 2, at
 * 8-20% more per frame (two tree walks a ray); meshes with little empty
 * space in their box build or keep no hull (host/pipeline/hull.h) and are
 * unchanged (bench/results/render-converge/2026-11-28-s28-hull.md). */
inline int clvr_volume_hull_clip(const clvr_volume *v, float3 org, float3 dir, float *t0, float *t1)
{
    const clvr_frame *f = v->f;
    if (f->hull_faces == 0u) return 1;
    return clvr_hull_clip(v->hull_bvh, v->hull, org.x, org.y, org.z, dir.x, dir.y, dir.z, t0, t1);
}

/* The part of a ray where the estimators look for medium: the clip box and
 * planes (clvr_ray_clip), then the hull. Every ray the estimators trace
 * goes through it (the MPI record, which keeps the box entry for its
 * compositing order, calls the two apart). */
inline int clvr_volume_clip(const clvr_volume *v, float3 org, float3 dir, float3 lo, float3 hi, float *t0, float *t1)
{
    return clvr_ray_clip(v->f, org, dir, lo, hi, t0, t1) && clvr_volume_hull_clip(v, org, dir, t0, t1);
}

/* The stretches of a camera ray between two hull crossings that lie
 * outside the mesh (kernels/hull.h, clvr_hull_gaps): their extinction is
 * 0, so urm treats them as majorant 0 (it spends no points there, and its
 * control bridges them instead of jumping across the two boundaries). In
 * order, disjoint. 256^2, urm, error after 1 / 2 / 3 / 4 frames without
 * shadows, against the first and last crossing only: kiefer_tet10 7.74 /
 * 3.43 / 2.94 / 1.78% -> 7.14 / 2.82 / 2.61 / 1.17%, PLOT3D combustor 4.60 /
 * 2.03% -> 4.55 / 1.98% (2% in 2 frames instead of 3), post unchanged, at
 * about the same cost per frame (one walk without pruning instead of two
 * pruned ones; bench/results/render-converge/2026-11-28-s29-gaps.md). The
 * shadow rays keep the two walks: gaps there cost the combustor 10% a
 * frame for no lower error. */
typedef struct clvr_gaps {
    int n;
    float lo[CLVR_HULL_MAX_HITS], hi[CLVR_HULL_MAX_HITS];
} clvr_gaps;

/* Candidate gaps shorter than this fraction of the clipped ray are kept as
 * medium without a lookup: most are the slivers between two triangulations
 * of a non-planar quad that meshes cut into tets leave inside (PLOT3D
 * combustor and post: 0.28 and 0.38 candidates per camera ray, 0.003 and
 * 0.002 of them outside the mesh). */
#define CLVR_GAP_MIN 0.01f

/* The hull's cut of [*t0, *t1] and its candidate gaps (clvr_hull_gaps),
 * *n of them (0 without a hull, or past CLVR_HULL_MAX_HITS crossings, where
 * only the cut is made); 0 when the ray misses the mesh. The walk takes
 * them raw (it meets the boundary faces itself). */
inline int clvr_volume_hull_crossings(const clvr_volume *v, float3 org, float3 dir, float *t0, float *t1, float *glo,
                                      float *ghi, int *n)
{
    *n = 0;
    if (v->f->hull_faces == 0u) return 1;
    const int k = clvr_hull_gaps(v->hull_bvh, v->hull, org.x, org.y, org.z, dir.x, dir.y, dir.z, t0, t1, glo, ghi);
    if (k == -1) return 0;
    if (k == -2) return clvr_volume_hull_clip(v, org, dir, t0, t1);
    *n = k;
    return 1;
}

/* The candidates glo/ghi (n of them, clvr_volume_hull_crossings) that lie
 * outside the mesh, cut to [a, b], into *g; candidates shorter than
 * `shortest` are kept as medium without a lookup (CLVR_GAP_MIN). A
 * candidate gap lies wholly inside or outside the mesh; one lookup at its
 * middle tells which (a point within the element tolerance of a face counts
 * inside: the gap is then kept, which costs points, never bias). */
inline void clvr_volume_outside_gaps(const clvr_volume *v, float3 org, float3 dir, float a, float b, float shortest,
                                     const float *glo, const float *ghi, int n, clvr_gaps *g)
{
    g->n = 0;
    for (int i = 0; i < n; ++i) {
        const float lo = fmax(glo[i], a), hi = fmin(ghi[i], b);
        if (!(hi - lo > shortest)) continue;
        const float3 p = org + dir * (0.5f * (glo[i] + ghi[i]));
        float sc;
        if (clvr_locate_point(clvr_volume_view(v), p.x, p.y, p.z, &sc)) continue;
        g->lo[g->n] = lo;
        g->hi[g->n++] = hi;
    }
}

/* clvr_volume_hull_clip for a camera ray, with the gaps that lie outside
 * the mesh in *g (none without a hull, or past CLVR_HULL_MAX_HITS crossings);
 * clvr_volume_clip_gaps: the clip box and planes first, as clvr_volume_clip. */
inline int clvr_volume_hull_gaps(const clvr_volume *v, float3 org, float3 dir, float *t0, float *t1, clvr_gaps *g)
{
    g->n = 0;
    float glo[CLVR_HULL_MAX_HITS], ghi[CLVR_HULL_MAX_HITS];
    int n;
    if (!clvr_volume_hull_crossings(v, org, dir, t0, t1, glo, ghi, &n)) return 0;
    clvr_volume_outside_gaps(v, org, dir, *t0, *t1, CLVR_GAP_MIN * (*t1 - *t0), glo, ghi, n, g);
    return 1;
}

inline int clvr_volume_clip_gaps(const clvr_volume *v, float3 org, float3 dir, float3 lo, float3 hi, float *t0,
                                 float *t1, clvr_gaps *g)
{
    g->n = 0;
    return clvr_ray_clip(v->f, org, dir, lo, hi, t0, t1) && clvr_volume_hull_gaps(v, org, dir, t0, t1, g);
}

/* ------------------------------------------------------------ majorant iterators
 * Each method is an iterator over the ray's majorant segments, in order:
 * next(&a, &b, &m) gives [a, b) with a majorant m >= every extinction on it
 * (m = 0: no medium there), and returns 0 past the end. The estimators below
 * consume segments and never know where they came from (pbrt-v4's
 * `DDAMajorantIterator` / `SampleT_maj` split). */

/* track: one segment, the global majorant. */
typedef struct clvr_global_iter {
    float a, b, m;
    int done;
} clvr_global_iter;

inline void clvr_global_begin(const clvr_volume *v, clvr_global_iter *it, float t0, float t1)
{
    it->a = t0;
    it->b = t1;
    it->m = v->f->global_majorant;
    it->done = !(t0 < t1);
}

inline int clvr_global_next(clvr_global_iter *it, float *a, float *b, float *m)
{
    if (it->done) return 0;
    it->done = 1;
    *a = it->a;
    *b = it->b;
    *m = it->m;
    return 1;
}

/* bins: the ray split into M segments of N bins each; the sampling clusters
 * hit over a segment are splatted into its bins when the segment is reached
 * (paper 3.4.2: "rasterize" clusters into 1D segments along the ray). */
typedef struct clvr_bins_iter {
    float t0, tend, bin_len;
    uint seg, nseg, nbins, bin;
    float bins[CLVR_RENDER_MAX_BINS];
} clvr_bins_iter;

inline void clvr_bins_begin(const clvr_volume *v, clvr_bins_iter *it, float t0, float t1)
{
    it->t0 = t0;
    it->tend = t1;
    it->nseg = t0 < t1 ? v->f->segments : 0u;
    it->nbins = v->f->bins;
    it->seg = 0;
    it->bin = it->nbins; /* forces a fill of the first segment */
    it->bin_len = (t1 - t0) / (float)(v->f->segments * v->f->bins);
}

inline void clvr_bins_fill(const clvr_volume *v, clvr_bins_iter *it, float3 org, float3 dir, float a, float b)
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

inline int clvr_bins_next(const clvr_volume *v, clvr_bins_iter *it, float3 org, float3 dir, float *a, float *b,
                          float *m)
{
    if (it->bin == it->nbins) {
        if (it->seg == it->nseg) return 0;
        float a0 = it->t0 + (float)it->seg * (float)it->nbins * it->bin_len;
        float b0 = it->seg + 1 == it->nseg ? it->tend : a0 + (float)it->nbins * it->bin_len;
        clvr_bins_fill(v, it, org, dir, a0, b0);
        it->seg++;
        it->bin = 0;
    }
    uint k = it->bin++;
    float base = it->t0 + (float)((it->seg - 1) * it->nbins + k) * it->bin_len;
    *a = base;
    *b = (it->seg == it->nseg && it->bin == it->nbins) ? it->tend : base + it->bin_len;
    *m = it->bins[k];
    return 1;
}

/* One level of a 3D-DDA (Amanatides & Woo 1987) over the cells lo_c..hi_c
 * (inclusive) of a grid of row length r, cell size cs, origin lo. The one
 * DDA loop of the renderer: the macrocell iterator below runs one of these
 * over blocks and, inside a dense block, a second one over its cells. */
typedef struct clvr_dda {
    float3 tnext, tdelta;
    int3 left;      /* cells left before the region is left, per axis */
    int idx;        /* clvr_grid_index of the current cell */
    int sx, sy, sz; /* index steps */
} clvr_dda;

inline void clvr_dda_begin(clvr_dda *d, float3 lo, float3 cs, int r, int3 lo_c, int3 hi_c, float3 org, float3 dir,
                           float3 inv, int3 step, float t)
{
    const int3 c = clamp(convert_int3_rtn((org + dir * t - lo) / cs), lo_c, hi_c);
    d->tnext = (lo + convert_float3(c + max(step, (int3)(0))) * cs - org) * inv;
    d->tdelta = fabs(cs * inv);
    if (dir.x == 0.0f) { d->tnext.x = INFINITY; d->tdelta.x = INFINITY; }
    if (dir.y == 0.0f) { d->tnext.y = INFINITY; d->tdelta.y = INFINITY; }
    if (dir.z == 0.0f) { d->tnext.z = INFINITY; d->tdelta.z = INFINITY; }
    d->left = (int3)(step.x > 0 ? hi_c.x - c.x : c.x - lo_c.x, step.y > 0 ? hi_c.y - c.y : c.y - lo_c.y,
                     step.z > 0 ? hi_c.z - c.z : c.z - lo_c.z);
    d->sx = step.x;
    d->sy = step.y * r;
    d->sz = step.z * r * r;
    d->idx = clvr_grid_index(c.x, c.y, c.z, r);
}

/* Where the ray leaves the current cell. */
inline float clvr_dda_exit(const clvr_dda *d) { return fmin(fmin(d->tnext.x, d->tnext.y), d->tnext.z); }

/* Steps into the next cell (tx: clvr_dda_exit, which the caller has); 0
 * when that leaves the region. *axis gets the axis (0, 1, 2) so that a
 * caller can keep cell coordinates. */
inline int clvr_dda_step(clvr_dda *d, float tx, int *axis)
{
    if (d->tnext.x <= tx) {
        *axis = 0;
        if (d->left.x-- == 0) return 0;
        d->idx += d->sx;
        d->tnext.x += d->tdelta.x;
    } else if (d->tnext.y <= tx) {
        *axis = 1;
        if (d->left.y-- == 0) return 0;
        d->idx += d->sy;
        d->tnext.y += d->tdelta.y;
    } else {
        *axis = 2;
        if (d->left.z-- == 0) return 0;
        d->idx += d->sz;
        d->tnext.z += d->tdelta.z;
    }
    return 1;
}

/* dda: the two-level macrocell grid (see CLVR_DDA_BLOCK). Blocks are walked;
 * a block whose majorant optical depth m * chord exceeds CLVR_DDA_DESCEND is
 * walked cell by cell, any other is one segment of the block majorant. The
 * choice depends on the ray alone, so every segmentation is a valid
 * piecewise-constant majorant and the estimators stay unbiased. One clvr_dda
 * stepper serves both levels; the walk is a macro with the consumer inline
 * at the two places a segment is made, rather than an iterator struct with a
 * next(): measured on the built-in scene, 512^2, delta, quiet machine, an
 * iterator was 12% slower (7.4 against 8.4 Mrays/s), its state going through
 * memory per segment. STOP is an expression of (a, b, m), true to end the walk. */
#define CLVR_DDA_WALK(v, org, dir, t0, t1, a, b, m, STOP)                                                              \
    do {                                                                                                               \
        const clvr_frame *f_ = (v)->f;                                                                                 \
        const float3 lo_ = vload3(0, f_->grid_lo), hi_ = vload3(0, f_->grid_hi);                                       \
        const int r_ = (int)f_->grid_res, rc_ = (r_ + CLVR_DDA_BLOCK - 1) / CLVR_DDA_BLOCK;                            \
        const float3 cs_ = (hi_ - lo_) / (float)r_, bs_ = cs_ * (float)CLVR_DDA_BLOCK, inv_ = 1.0f / (dir);            \
        const int3 step_ = (int3)((dir).x >= 0.0f ? 1 : -1, (dir).y >= 0.0f ? 1 : -1, (dir).z >= 0.0f ? 1 : -1);      \
        int3 c_ = clamp(convert_int3_rtn(((org) + (dir) * (t0) - lo_) / bs_), (int3)(0), (int3)(rc_ - 1));            \
        clvr_dda blk_;                                                                                                 \
        clvr_dda_begin(&blk_, lo_, bs_, rc_, (int3)(0), (int3)(rc_ - 1), (org), (dir), inv_, step_, (t0));            \
        float t_ = (t0);                                                                                               \
        int axis_;                                                                                                     \
        for (int more_ = (t0) < (t1); more_;) {                                                                        \
            const float tx_ = clvr_dda_exit(&blk_), bb_ = fmin(tx_, (t1));                                             \
            const float mb_ = (v)->blocks[blk_.idx];                                                                   \
            if (mb_ > 0.0f && mb_ * (bb_ - t_) > CLVR_DDA_DESCEND) {                                                   \
                const int3 clo_ = c_ * CLVR_DDA_BLOCK, chi_ = min(clo_ + CLVR_DDA_BLOCK, (int3)(r_)) - 1;              \
                clvr_dda cel_;                                                                                         \
                clvr_dda_begin(&cel_, lo_, cs_, r_, clo_, chi_, (org), (dir), inv_, step_, t_);                       \
                for (;;) {                                                                                             \
                    const float cx_ = clvr_dda_exit(&cel_);                                                            \
                    a = t_;                                                                                            \
                    b = fmin(cx_, bb_);                                                                                \
                    m = (v)->grid[cel_.idx];                                                                           \
                    if (STOP) { more_ = 0; break; }                                                                    \
                    t_ = b;                                                                                            \
                    if (cx_ >= bb_ || !clvr_dda_step(&cel_, cx_, &axis_)) break;                                       \
                }                                                                                                      \
                if (!more_) break;                                                                                     \
            } else {                                                                                                   \
                a = t_;                                                                                                \
                b = bb_;                                                                                               \
                m = mb_;                                                                                               \
                if (STOP) break;                                                                                       \
            }                                                                                                          \
            t_ = bb_;                                                                                                  \
            if (tx_ >= (t1) || !clvr_dda_step(&blk_, tx_, &axis_)) break;                                              \
            if (axis_ == 0) c_.x += step_.x;                                                                           \
            else if (axis_ == 1) c_.y += step_.y;                                                                      \
            else c_.z += step_.z;                                                                                      \
        }                                                                                                              \
    } while (0)

/* Evaluates STOP, an expression of (a, b, m), for every majorant segment
 * [a, b) of majorant m of the frame's method, in order, until it is true.
 * The one place where the methods are told apart. */
#define CLVR_FOR_EACH_SEGMENT(v, org, dir, t0, t1, a, b, m, STOP)                                                     \
    do {                                                                                                               \
        float a, b, m;                                                                                                 \
        if ((v)->f->method == CLVR_RENDER_DDA) {                                                                       \
            CLVR_DDA_WALK(v, org, dir, t0, t1, a, b, m, STOP);                                                         \
        } else if ((v)->f->method == CLVR_RENDER_BINS) {                                                               \
            clvr_bins_iter it_;                                                                                        \
            clvr_bins_begin((v), &it_, (t0), (t1));                                                                    \
            while (clvr_bins_next((v), &it_, (org), (dir), &a, &b, &m))                                                \
                if (STOP) break;                                                                                       \
        } else {                                                                                                       \
            clvr_global_iter it_;                                                                                      \
            clvr_global_begin((v), &it_, (t0), (t1));                                                                  \
            while (clvr_global_next(&it_, &a, &b, &m))                                                                 \
                if (STOP) break;                                                                                       \
        }                                                                                                              \
    } while (0)

/* ------------------------------------------------------------ estimators
 * Both estimate, per camera ray, the single-scattering integral
 *   L = int T(t) sigma(t) c(t) (ambient + I T_light(t)) dt + T(t1) background
 * (T: transmittance, sigma: extinction, c: colour of the transfer function)
 * and consume majorant segments in order. */

/* delta: Woodcock/delta tracking. A free flight is an optical depth tau ~
 * Exp(1) spent across the piecewise-constant majorant segments (tau / m
 * world units in a segment of majorant m); this equals restarting the flight
 * at every boundary (memorylessness) but needs one logarithm per tentative
 * collision instead of one per segment. A tentative collision is real with
 * probability sigma / m; the estimate is the colour at the first real one
 * (0/1 outcome), the shadow ray a 0/1 visibility. */
typedef struct clvr_delta {
    float tau;
    float t_hit;
    float4 medium;
    int hit;
    clvr_locate_hint hint;
    clvr_span span;
} clvr_delta;

inline void clvr_delta_begin(clvr_delta *d, float u)
{
    d->tau = -log(1.0f - u);
    d->hit = 0;
    d->hint = clvr_locate_hint_none();
    d->span = clvr_span_none();
}

/* Spends the flight inside [a, b) of majorant m; 1 when a real collision
 * happened (then d->t_hit, d->medium). */
inline int clvr_delta_segment(const clvr_volume *v, clvr_delta *d, float3 org, float3 dir, float a, float b, float m,
                              clvr_rng *rng, uint *samples, uint *nulls)
{
    const float depth = m * (b - a);
    if (depth < d->tau) { /* passes the segment: no division */
        d->tau -= depth;
        return 0;
    }
    float t = a;
    for (;;) {
        const float fly = d->tau / m;
        if (t + fly >= b) {
            d->tau = fmax(d->tau - (b - t) * m, 0.0f);
            return 0;
        }
        t += fly;
        float4 med = clvr_volume_at_ray(v, org, dir, t, &d->hint, &d->span);
        ++*samples;
        if (clvr_rng_next(rng) * m < med.w) {
            d->t_hit = t;
            d->medium = med;
            d->hit = 1;
            return 1;
        }
        ++*nulls;
        d->tau = -log(1.0f - clvr_rng_next(rng));
    }
}

/* Delta tracking along [t0, t1]: 1 and the collision, or 0 when the ray leaves. */
inline int clvr_delta_track(const clvr_volume *v, float3 org, float3 dir, float t0, float t1, float u, clvr_rng *rng,
                            float *t_hit, float4 *medium, uint *samples, uint *nulls)
{
    clvr_delta d;
    clvr_delta_begin(&d, u);
    CLVR_FOR_EACH_SEGMENT(v, org, dir, t0, t1, a, b, m,
                          m > 0.0f && clvr_delta_segment(v, &d, org, dir, a, b, m, rng, samples, nulls));
    *t_hit = d.t_hit;
    *medium = d.medium;
    return d.hit;
}

/* urm: unbiased ray marching (after Kettunen et al. 2021, "An unbiased
 * ray-marching transmittance estimator", with the residual ratio tracking of
 * Novak et al. 2014). Position along the ray is measured in a warped
 * coordinate s with density rho(t) = max(m / kappa, rho_0) where the
 * majorant m > 0 (and 0 where m = 0: no medium, nothing to sample), so that
 * one unit of s holds at most kappa of majorant optical depth and a ray gets
 * at least frame.urm_steps units. rho_0 spreads those steps: on camera rays
 * (and MPI regions) in proportion to sqrt(m) times a factor that falls with
 * the majorant optical depth in front (clvr_urm_front, clvr_root_depth), on
 * shadow and light-grid rays evenly over the clipped ray.
 *  - Emission: quadrature points at s = k + u (u: the frame's uniform, from
 *    the low-discrepancy sampler by default) with weight T(t_k) sigma_k /
 *    rho_k. For any fixed u the sum is a quadrature; over u it is unbiased.
 *  - Transmittance between quadrature points: exp(-int sigma/rho ds) over
 *    each unit interval, estimated given u by residual ratio tracking
 *    (Novak et al. 2014): a control density linear between the two
 *    quadrature points' sigma/rho (known given u) is integrated exactly, the
 *    residual r by ratio tracking at the points of a Poisson process drawn
 *    independently of u with the majorant as its rate (mu = m / rho per unit
 *    s, at least kappa / 2): E[exp(-c) prod(1 - r_i / mu_i)] = exp(-int sigma).
 *    The residual is small where sigma is smooth, so T is nearly exact, and
 *    thin media cost few residual points.
 *  - Russian roulette on the running weight below CLVR_URM_RR.
 *  - Direct light, I sum_k g_k T_l(x_k) (g_k: the quadrature terms, T_l:
 *    transmittance toward the light), with a control variate: a light grid
 *    G (transmittance toward the light at the nodes of a coarse grid in
 *    light space, computed on the device whenever the transfer function,
 *    the light or the grid changes, clvr_light_grid) interpolated at every
 *    quadrature point,
 *    plus one shadow ray from a point b picked by weighted reservoir
 *    sampling (weight |T sigma / rho| luminance(c)):
 *      I [sum_k g_k G(x_k) + W g_b / w_b (T_l(b) - G(b))]
 *    is unbiased for any G (the second term corrects the first) and has
 *    little variance where G is close to T_l. One pick alone (I W g_b / w_b
 *    T_l(b)) carries the colour of one point for the whole ray: on tets-1M
 *    it needed 236 spp to 2% with the light fixed at 1, where this needs none.
 *    Where G is flat around b (its 8 interpolated values within
 *    CLVR_URM_SHADOW_RR_SPREAD) the correction is traced with probability
 *    CLVR_URM_SHADOW_RR_Q only and divided by it (Russian roulette).
 * Every value is an unbiased estimate of the same integral as delta tracking
 * (tests/test_render.c compares them per pixel block). */
#ifndef CLVR_URM_RR
#define CLVR_URM_RR 0.05f
#endif
/* Residual points of one interval kept until its end point is known: their
 * count is Poisson with mean at most CLVR_URM_MAX_MU (the residual rate per
 * unit s is capped there, which keeps the estimate unbiased: ratio tracking
 * is, for any rate), so it exceeds 16 with probability below 1e-10; the
 * extra points would be dropped. With the defaults the mean is at most
 * 0.5 on camera rays and 2 on the correction shadow ray. */
#define CLVR_URM_MAX_PTS 16
#define CLVR_URM_MAX_MU 2.0f
/* Russian roulette on urm's correction shadow ray (clvr_render_track):
 * traced with probability CLVR_URM_SHADOW_RR_Q where the light grid's spread
 * at the pick is at most CLVR_URM_SHADOW_RR_SPREAD, always elsewhere.
 * 256^2, shadows, 1M tets / post-tets: shadow rays per pixel 0.45 -> 0.20 /
 * 0.38 -> 0.19, lookups to 2% relative RMSE 91 -> 75 / 63 -> 53 at the same
 * frames (5 / 4). A spread of 0.1 lost a frame on post; 0.02 with q = 0.5
 * hardly triggered (bench/results/render-converge/2026-11-25-levers-*). */
#ifndef CLVR_URM_SHADOW_RR_SPREAD
#define CLVR_URM_SHADOW_RR_SPREAD 0.05f
#endif
#ifndef CLVR_URM_SHADOW_RR_Q
#define CLVR_URM_SHADOW_RR_Q 0.25f
#endif
/* Residual points per unit s, as multiples of the majorant's rate (and of
 * the kappa / 2 floor below): CLVR_URM_RESIDUAL_RATE on camera and
 * light-grid rays, CLVR_URM_SHADOW_RESIDUAL_RATE on the correction shadow
 * ray, whose transmittance error the correction multiplies by the
 * reservoir's weight (and 1/q under roulette). 256^2, Owen-Sobol frames,
 * 1/n fit seconds to 2% against rates 1 and 1: tets-1M 0.313 -> 0.243 s
 * without shadows, 1.24 -> 0.48 s with (2 frames instead of 4); post-tets
 * 0.083 -> 0.071 and 0.41 -> 0.27 s; comb-tets 3.05 -> 1.94 s. A shadow
 * rate of 4 gave 0.51 / 0.28 s, 16 no more than 8; the light grid's rate
 * hardly matters (bench/results/render-converge/2026-11-25-s24-sampler.md). */
#ifndef CLVR_URM_RESIDUAL_RATE
#define CLVR_URM_RESIDUAL_RATE 2.0f
#endif
#ifndef CLVR_URM_SHADOW_RESIDUAL_RATE
#define CLVR_URM_SHADOW_RESIDUAL_RATE 8.0f
#endif

/* What a camera ray's emission points add up to (the walk's and urm's):
 * sum of the weighted colours, with shadows their light-grid terms and a
 * reservoir pick for the correction shadow ray (see urm's comment). */
typedef struct clvr_emit {
    float3 sum;   /* sum of the weighted colours */
    float3 lit;   /* ... times the light grid G at each */
    float3 pick;  /* reservoir: the pick's weighted colour over its reservoir weight */
    float wsum;   /* reservoir: total weight */
    float tsum;   /* sum of weight times distance: wsum's mean depth (the denoiser's depth guide) */
    float pick_t; /* reservoir: where */
    float pick_g; /* reservoir: G there */
    float pick_s; /* reservoir: the spread of G there (clvr_light_at) */
    float pick_u; /* reservoir: the one uniform that decides every pick */
    int shadows;
} clvr_emit;

inline float clvr_urm_lum(float3 c) { return c.x + c.y + c.z; }

/* One step of weighted reservoir sampling driven by a single uniform *u:
 * takes the candidate with probability p, then rescales *u to [0, 1) so
 * that it stays uniform given the decision. So every pick of a ray can come
 * from one low-discrepancy dimension. */
inline int clvr_urm_reservoir(float *u, float p)
{
    const int take = *u < p;
    *u = take ? *u / p : (*u - p) / (1.0f - p);
    *u = fmin(*u, 0x1.fffffep-1f);
    return take;
}

inline void clvr_emit_begin(clvr_emit *a, int shadows, float u_pick)
{
    a->sum = a->lit = a->pick = (float3)(0.0f);
    a->wsum = a->tsum = a->pick_t = a->pick_g = a->pick_s = 0.0f;
    a->pick_u = u_pick;
    a->shadows = shadows;
}

/* Adds colour weight g (rgb, transmittance applied) emitted at org + t dir,
 * with reservoir weight ww (none when ww <= 0); with shadows G and spread
 * are the light grid's value there (any value keeps the estimate unbiased:
 * the walk interpolates it, see CLVR_WALK_LIGHT_STEP). */
inline void clvr_emit_add(clvr_emit *a, float t, float3 g, float ww, float G, float spread)
{
    a->sum += g;
    if (!(ww > 0.0f)) return;
    a->lit += G * g;
    a->wsum += ww;
    a->tsum += ww * t;
    /* The pick serves the correction shadow ray only. */
    if (a->shadows && clvr_urm_reservoir(&a->pick_u, ww / a->wsum)) {
        a->pick = g / ww;
        a->pick_t = t;
        a->pick_g = G;
        a->pick_s = spread;
    }
}

/* With shadows the walk evaluates the light grid (the lit terms' control)
 * at points this many of the grid's smallest spacings apart along the ray
 * and interpolates linearly between them for its emission points: tets
 * are often smaller than the spacing, and the grid is trilinear, nearly
 * linear over that length. Any value of the control keeps the estimate
 * unbiased (the correction shadow ray takes the same value), a closer one
 * lowers its variance. 256^2, shadows, ms per frame and error after 1 / 2
 * frames against the value held from the last evaluation until the points
 * had moved a quarter of a cell (the axis-aligned 24^3 grid of session 39,
 * a step of 1): fire_ug 125 -> 108 ms, 2.79 / 1.83 -> 2.47 / 1.74%; post
 * 273 -> 238 ms, 2.48 / 1.41 -> 2.37 / 1.29%; combustor 199 -> 202 ms,
 * 2.94 / 1.71 -> 2.86 / 1.63%. With the light-space grid, whose columns
 * are about half as far apart, 1 -> 2: fire_ug 116 -> 108 ms, combustor
 * 197 -> 195 ms, errors within 0.06 point
 * (bench/results/render-converge/2026-11-29-s40-light-step.md). */
#ifndef CLVR_WALK_LIGHT_STEP
#define CLVR_WALK_LIGHT_STEP 2.0f
#endif

/* Appends b, which continues a's ray with a's transmittance T in front of
 * it: b's pick replaces a's in proportion to its weight (one draw from
 * rng, only where b has weight). */
inline void clvr_emit_merge(clvr_emit *a, const clvr_emit *b, float T, clvr_rng *rng)
{
    a->sum += T * b->sum;
    a->lit += T * b->lit;
    const float wu = T * b->wsum;
    if (wu > 0.0f && clvr_rng_next(rng) * (a->wsum + wu) < wu) {
        a->pick = b->pick;
        a->pick_t = b->pick_t;
        a->pick_g = b->pick_g;
        a->pick_s = b->pick_s;
    }
    a->wsum += wu;
    a->tsum += T * b->tsum;
}

typedef struct clvr_urm {
    float rho_min, rho_root; /* rho_0 = rho_min + rho_root sqrt(m) clvr_urm_front(...) */
    float front;       /* exp(-CLVR_URM_FRONT tau), tau the majorant optical depth from the ray's entry
                        * to the current segment (clvr_urm_front) */
    float kappa, inv_kappa;
    float to_quad;     /* warped distance to the next quadrature point */
    float tau_pt;      /* residual-process depth to the next residual point, ~ Exp(1) */
    float s_in;        /* warped distance travelled since the last quadrature point */
    float len;         /* warped length of the current interval (u for the first) */
    float sr_prev;     /* sigma / rho at the last quadrature point */
    int first;         /* no quadrature point yet */
    int npts;
    float pt_s[CLVR_URM_MAX_PTS], pt_sr[CLVR_URM_MAX_PTS], pt_mu[CLVR_URM_MAX_PTS];
    float T;           /* transmittance estimate at the last quadrature point */
    int alive;
    int emit;          /* 0: transmittance only (shadow ray) */
    float rate;        /* residual points per unit s over the majorant's rate (CLVR_URM_*RESIDUAL_RATE) */
    clvr_emit acc;     /* the points' T sigma / rho * colour (reservoir weight |T sigma / rho| luminance) */
    clvr_locate_hint hint;
    clvr_span span;
} clvr_urm;

/* span: the clipped ray's length; root: its clvr_root_depth, or 0 to spread
 * the minimum steps evenly over span; share: the part of the ray's minimum
 * points this stretch gets (1, or less where the walk hands urm the rest of
 * a ray; at least one point). */
inline void clvr_urm_begin(const clvr_frame *f, clvr_urm *e, float span, float root, float u, float u_pick, int emit,
                           float rate, float share, clvr_rng *rng)
{
    clvr_emit_begin(&e->acc, emit == 2, u_pick);
    e->hint = clvr_locate_hint_none();
    e->span = clvr_span_none();
    /* A shadow ray needs transmittance only, which the control makes nearly
     * exact between points: half the camera ray's points measured better
     * (tets-1M, 128^2, shadows: 2% in 51 instead of 46 frames, at 74% of the
     * lookups). */
    const float steps = fmax((emit ? (float)f->urm_steps : fmax(0.5f * (float)f->urm_steps, 1.0f)) * share, 1.0f);
    e->rho_min = root > 0.0f ? 0.0f : steps / fmax(span, 1e-30f);
    e->rho_root = root > 0.0f ? steps / root : 0.0f;
    e->front = 1.0f;
    e->kappa = f->urm_kappa;
    e->inv_kappa = 1.0f / f->urm_kappa;
    e->to_quad = u;
    e->len = u;
    e->tau_pt = -log(1.0f - clvr_rng_next(rng));
    e->s_in = 0.0f;
    e->sr_prev = 0.0f;
    e->first = 1;
    e->npts = 0;
    e->T = 1.0f;
    e->alive = 1;
    e->emit = emit;
    e->rate = rate;
}

/* The transmittance factor of the interval just closed (warped length
 * e->len, control density linear from sr0 to sr1 over it). */
inline float clvr_urm_interval(clvr_urm *e, float sr0, float sr1)
{
    const float len = e->len, slope = len > 0.0f ? (sr1 - sr0) / len : 0.0f;
    float F = clvr_exp_neg(0.5f * (sr0 + sr1) * len);
    for (int i = 0; i < e->npts; ++i) F *= 1.0f - (e->pt_sr[i] - (sr0 + slope * e->pt_s[i])) / e->pt_mu[i];
    e->npts = 0;
    return F;
}

/* The light grid G at p: trilinear between its nodes in light space
 * (clvr_light_space), clamped at the faces (any G keeps the estimate
 * unbiased; a close one lowers its variance). *spread: the largest minus
 * the smallest of the 8 values interpolated, a cheap sign of how far G may
 * be from the truth there (0 where the light is uniform around p). */
inline float clvr_light_at(const clvr_volume *v, float3 p, float *spread)
{
    const clvr_frame *f = v->f;
    const int r = (int)f->light_res, n = (int)clvr_light_depth(f->light_res);
    const float4 lu = vload4(0, f->light_space[0]), lv = vload4(0, f->light_space[1]);
    const float4 lw = vload4(0, f->light_space[2]), h = vload4(0, f->light_space[3]);
    const float3 q = clamp((float3)((dot(p, lu.xyz) - lu.w) / h.x - 0.5f, (dot(p, lv.xyz) - lv.w) / h.y - 0.5f,
                                    (lw.w - dot(p, lw.xyz)) / h.z),
                           (float3)(0.0f), (float3)((float)(r - 1), (float)(r - 1), (float)(n - 1)));
    const int3 c0 = min(convert_int3_rtz(q), (int3)(max(r - 2, 0), max(r - 2, 0), max(n - 2, 0)));
    const int3 c1 = min(c0 + 1, (int3)(r - 1, r - 1, n - 1));
    const float3 w = q - convert_float3(c0);
    __global const float *g = v->light;
    const float a0 = g[clvr_light_node(c0.x, c0.y, c0.z, r)], a1 = g[clvr_light_node(c1.x, c0.y, c0.z, r)];
    const float b0 = g[clvr_light_node(c0.x, c1.y, c0.z, r)], b1 = g[clvr_light_node(c1.x, c1.y, c0.z, r)];
    const float d0 = g[clvr_light_node(c0.x, c0.y, c1.z, r)], d1 = g[clvr_light_node(c1.x, c0.y, c1.z, r)];
    const float e0 = g[clvr_light_node(c0.x, c1.y, c1.z, r)], e1 = g[clvr_light_node(c1.x, c1.y, c1.z, r)];
    *spread = fmax(fmax(fmax(a0, a1), fmax(b0, b1)), fmax(fmax(d0, d1), fmax(e0, e1))) -
              fmin(fmin(fmin(a0, a1), fmin(b0, b1)), fmin(fmin(d0, d1), fmin(e0, e1)));
    return mix(mix(mix(a0, a1, w.x), mix(b0, b1, w.x), w.y), mix(mix(d0, d1, w.x), mix(e0, e1, w.x), w.y), w.z);
}

/* The camera ray's minimum points are spread in proportion to sqrt(m)
 * times exp(-CLVR_URM_FRONT tau), tau the majorant optical depth from the
 * ray's entry: fewer of them behind dense medium that the camera hardly
 * sees, more in front of it. tau bounds the true optical depth from above,
 * so exp(-tau) would starve medium behind a loose majorant; the factor 1/2
 * hedges. An MPI rank's region starts tau at its own entry (the medium in
 * front of it is other ranks'): any spread is unbiased, this one only spends
 * a back region's points as if nothing stood in front of it. Per segment
 * [a, a + len) of majorant m entered at depth tau, this
 * returns the factor's mean over the segment, so that the spread stays
 * piecewise constant (one density per segment, as the walk needs) and its
 * integral (clvr_root_depth) exact. 256^2, no shadows, error after 1 / 2
 * frames against the plain sqrt(m) spread: PLOT3D combustor 8.30 / 5.46% ->
 * 7.38 / 4.64% (1/n fit 13.3 -> 9.0 frames to 2%), fire_ug 4.06 / 2.20% ->
 * 3.39 / 1.71% (2% in 2 frames instead of 3), kiefer_tet10 2% in 7 frames
 * instead of 8, post 3.55 / 1.44% -> 3.29 / 1.37%, blunt fin 2.74 / 1.08%
 * -> 2.57 / 1.02%; 1M tets, gmsh point-graded and the dense AMR-like mesh
 * unchanged; OpenFOAM igloo 3.29 / 2.27% -> 3.56 / 2.49% and the thin
 * AMR-like mesh 7.33 / 3.84% -> 7.41 / 4.04% lose, where loose majorants
 * stand in front of what the camera sees. A factor of 1 or 1/4, or a blend
 * with the plain spread, did no better
 * (bench/results/render-converge/2026-11-25-s26-front.md). */
#define CLVR_URM_FRONT 0.5f
/* *front: exp(-CLVR_URM_FRONT tau) at the segment's start, advanced past it
 * by the same exponential that the mean needs (one exp per segment). */
inline float clvr_urm_front(float *front, float m, float len)
{
    const float x = CLVR_URM_FRONT * m * len, ex = clvr_exp_neg(x);
    const float mean = *front * (x > 1e-4f ? (1.0f - ex) / x : 1.0f - 0.5f * x);
    *front *= ex;
    return mean;
}

/* Consumes [a, b) of majorant m; 0 once the walk may stop (terminated).
 * emit 2: also the light grid terms (urm with shadows). */
inline int clvr_urm_segment(const clvr_volume *v, clvr_urm *e, float3 org, float3 dir, float a, float b, float m,
                            clvr_rng *rng, uint *samples, uint *nulls)
{
    if (!(m > 0.0f)) return 1;
    /* Shadow and light-grid rays (rho_root 0) spread evenly: no front. */
    const float rho_spread = e->rho_root > 0.0f ? e->rho_root * sqrt(m) * clvr_urm_front(&e->front, m, b - a) : 0.0f;
    const float rho = fmax(m * e->inv_kappa, e->rho_min + rho_spread), inv_rho = 1.0f / rho;
    /* Residual points per unit s: e->rate times the majorant's rate, but at
     * least kappa/2 before that factor, because the control (interpolated
     * from neighbouring quadrature points, perhaps in denser segments) can
     * exceed this segment's majorant, and a residual r weighs r^2 / mu in
     * the variance; at most CLVR_URM_MAX_MU (the points kept per interval). */
    const float mu = fmin(e->rate * fmax(m, 0.5f * e->kappa * rho) * inv_rho, CLVR_URM_MAX_MU);
    float left = rho * (b - a);   /* warped length of the segment */
    float t = a;
    for (;;) {
        const float to_pt = e->tau_pt / mu;
        const int quad = e->to_quad <= to_pt;
        const float d = quad ? e->to_quad : to_pt;
        if (d >= left) {
            e->to_quad -= left;
            e->tau_pt = fmax(e->tau_pt - left * mu, 0.0f);
            e->s_in += left;
            return 1;
        }
        left -= d;
        t += d * inv_rho;
        e->to_quad -= d;
        e->tau_pt = fmax(e->tau_pt - d * mu, 0.0f);
        e->s_in += d;
        const float4 med = clvr_volume_at_ray(v, org, dir, t, &e->hint, &e->span);
        ++*samples;
        const float sr = med.w * inv_rho;
        if (!quad) { /* residual point of the current interval */
            ++*nulls;
            if (e->npts < CLVR_URM_MAX_PTS) {
                e->pt_s[e->npts] = e->s_in;
                e->pt_sr[e->npts] = sr;
                e->pt_mu[e->npts] = mu;
                ++e->npts;
            }
            e->tau_pt = -log(1.0f - clvr_rng_next(rng));
            continue;
        }
        /* Quadrature point: close the interval, then emit. The first
         * interval [entry, u) has a constant control sr (sr0 = sr1). */
        e->T *= clvr_urm_interval(e, e->first ? sr : e->sr_prev, sr);
        e->first = 0;
        e->sr_prev = sr;
        e->s_in = 0.0f;
        e->len = 1.0f;
        e->to_quad = 1.0f;
        if (e->emit && sr > 0.0f) {
            const float w = e->T * sr;
            const float ww = fabs(w) * clvr_urm_lum(med.xyz);
            float spread = 0.0f;
            const float G = e->emit == 2 && ww > 0.0f ? clvr_light_at(v, org + dir * t, &spread) : 1.0f;
            clvr_emit_add(&e->acc, t, w * med.xyz, ww, G, spread);
        }
        /* Russian roulette on the running transmittance. */
        const float aT = fabs(e->T);
        if (aT < CLVR_URM_RR) {
            if (clvr_rng_next(rng) * CLVR_URM_RR >= aT) {
                e->T = 0.0f;
                e->alive = 0;
                return 0;
            }
            e->T = copysign(CLVR_URM_RR, e->T);
        }
    }
}

/* The next piece [*a, *c) of [*a, b) outside the gaps (*gi: the first gap
 * that may still matter, advanced as the walk goes); 0 when none is left. */
inline int clvr_gaps_next(const clvr_gaps *g, int *gi, float *a, float b, float *c)
{
    while (*a < b) {
        while (*gi < g->n && g->hi[*gi] <= *a) ++*gi;
        if (*gi < g->n && g->lo[*gi] <= *a) {
            *a = fmin(b, g->hi[*gi]);
            continue;
        }
        *c = *gi < g->n ? fmin(b, g->lo[*gi]) : b;
        return 1;
    }
    return 0;
}

/* clvr_urm_segment over [a, b) minus the gaps. */
inline int clvr_urm_segment_gaps(const clvr_volume *v, clvr_urm *e, float3 org, float3 dir, float a, float b, float m,
                                 const clvr_gaps *g, int *gi, clvr_rng *rng, uint *samples, uint *nulls)
{
    float c;
    for (; clvr_gaps_next(g, gi, &a, b, &c); a = c)
        if (!clvr_urm_segment(v, e, org, dir, a, c, m, rng, samples, nulls)) return 0;
    return 1;
}

/* Closes the last interval at the ray's exit; returns T(t1). */
inline float clvr_urm_end(clvr_urm *e)
{
    if (!e->alive) return 0.0f;
    /* The tail [last point, exit) of warped length s_in: constant control
     * sr_prev; a ray that met no quadrature point has the control 0. */
    e->len = e->s_in;
    const float sr0 = e->first ? 0.0f : e->sr_prev;
    return e->T * clvr_urm_interval(e, sr0, sr0);
}

/* Transmittance estimate along [t0, t1] (u: the first quadrature offset). */
inline float clvr_urm_transmittance(const clvr_volume *v, float3 org, float3 dir, float t0, float t1, float u,
                                    float rate, clvr_rng *rng, uint *samples, uint *nulls)
{
    clvr_urm e;
    clvr_urm_begin(v->f, &e, t1 - t0, 0.0f, u, 0.0f, 0, rate, 1.0f, rng);
    CLVR_FOR_EACH_SEGMENT(v, org, dir, t0, t1, a, b, m, !clvr_urm_segment(v, &e, org, dir, a, b, m, rng, samples, nulls));
    return clvr_urm_end(&e);
}

/* Transmittance from p toward the light (urm), counted as one ray. */
inline float clvr_urm_light(const clvr_volume *v, float3 p, float3 ldir, float3 lo, float3 hi, float u, clvr_rng *rng,
                            uint *samples, uint *nulls, uint *rays)
{
    float s0 = 0.0f, s1 = INFINITY;
    ++*rays;
    if (!clvr_volume_clip(v, p, ldir, lo, hi, &s0, &s1)) return 1.0f;
    return clvr_urm_transmittance(v, p, ldir, s0, s1, u, CLVR_URM_SHADOW_RESIDUAL_RATE, rng, samples, nulls);
}

/* ------------------------------------------------------------ light grid
 * r x r columns along the light (clvr_light_space, CLVR_URM_LIGHT_RES in
 * clvr_shared.h for the figures), each integrated from the grid domain's
 * light side away from the light, its optical depth turned into
 * transmittance at every node. The grid is a control variate
 * (clvr_light_at): an error in it costs variance, never bias.
 *
 * Adds the optical depth of [a, b) (majorant m) along org + t dir to *tau:
 * jittered midpoints (offset u), `rate` per unit length and one per
 * CLVR_LIGHT_COLUMN_DEPTH of majorant optical depth; none where m is 0.
 * Returns 0 (CLVR_FOR_EACH_SEGMENT goes on). */
inline int clvr_tau_segment(const clvr_volume *v, float3 org, float3 dir, float a, float b, float m, float rate,
                            float u, clvr_locate_hint *h, clvr_span *sp, float *tau)
{
    if (!(m > 0.0f) || !(b > a)) return 0;
    const float len = b - a;
    const int n = clamp((int)ceil(len * (rate + m * (1.0f / CLVR_LIGHT_COLUMN_DEPTH))), 1, 1024);
    const float ds = len / (float)n;
    for (int j = 0; j < n; ++j) *tau += clvr_volume_at_ray(v, org, dir, a + ((float)j + u) * ds, h, sp).w * ds;
    return 0;
}

/* Column (a, b) of the light grid: transmittance toward the light at each
 * of its nodes. The column is cut to the box and clip planes once (outside
 * the mesh the lookups find no medium, and a hull walk would cost more
 * than it saves), each interval between two nodes to that; the lookup
 * hint and span carry from one interval to the next. */
inline void clvr_light_column(const clvr_volume *v, int a, int b, __global float *grid)
{
    const clvr_frame *f = v->f;
    const int r = (int)f->light_res, n = (int)clvr_light_depth(f->light_res);
    const float4 lu = vload4(0, f->light_space[0]), lv = vload4(0, f->light_space[1]);
    const float4 lw = vload4(0, f->light_space[2]), h = vload4(0, f->light_space[3]);
    const float3 vlo = vload3(0, f->vol_lo), vhi = vload3(0, f->vol_hi);
    const float3 org = (lu.w + ((float)a + 0.5f) * h.x) * lu.xyz + (lv.w + ((float)b + 0.5f) * h.y) * lv.xyz +
                       lw.w * lw.xyz;
    const float3 dir = -lw.xyz;
    clvr_rng rng = clvr_rng_make((uint)(b * r + a), 0x11647u, f->seed_lo, f->seed_hi);
    const float u = clvr_rng_next(&rng), rate = CLVR_LIGHT_COLUMN_POINTS / h.z;
    clvr_locate_hint hint = clvr_locate_hint_none();
    clvr_span span = clvr_span_none();
    float tau = 0.0f, c0 = 0.0f, c1 = INFINITY;
    const int cut = clvr_ray_clip(f, org, dir, vlo, vhi, &c0, &c1);
    grid[clvr_light_node(a, b, 0, r)] = 1.0f;
    for (int j = 1; j < n; ++j) {
        const float s0 = fmax((float)(j - 1) * h.z, c0), s1 = fmin((float)j * h.z, c1);
        if (cut && s0 <= s1)
            CLVR_FOR_EACH_SEGMENT(v, org, dir, s0, s1, sa, sb, sm,
                                  clvr_tau_segment(v, org, dir, sa, sb, sm, rate, u, &hint, &span, &tau));
        grid[clvr_light_node(a, b, j, r)] = exp(-tau);
    }
}

/* ------------------------------------------------------------ camera rays */

/* clvr_root_depth's term of [a, b) of majorant m (front: as clvr_urm.front). */
inline void clvr_root_piece(float a, float b, float m, float *root, float *front)
{
    if (!(m > 0.0f) || !(a < b)) return;
    *root += sqrt(m) * (b - a) * clvr_urm_front(front, m, b - a);
}

/* One segment [a, b) of majorant m minus the gaps (as clvr_urm_segment_gaps). */
inline int clvr_root_segment(float a, float b, float m, const clvr_gaps *g, int *gi, float *root, float *front)
{
    float c;
    for (; clvr_gaps_next(g, gi, &a, b, &c); a = c) clvr_root_piece(a, c, m, root, front);
    return 0;
}

/* The integral of sqrt(m) times the front factor (clvr_urm_front) over
 * [t0, t1) (m: the majorant): a camera ray's minimum urm points are spread
 * in proportion to that. sqrt(m) alone (before the front factor) put them where
 * the medium is (a mesh that fills little of its box gets as many points per
 * ray as one that fills it) and more of them where it is denser, at the
 * same count. One DDA walk without lookups. 256^2, no shadows, error after
 * 1 / 2 frames against points spread evenly over the medium: OpenFOAM igloo
 * 7.26 / 5.10% -> 3.29 / 2.27%, AMR-like density 1 15.9 / 10.6% -> 7.3 /
 * 3.8%, PLOT3D combustor 11.1 / 7.6% -> 8.3 / 5.5%, tets-1M 4.44 / 1.94% ->
 * 4.13 / 1.65%, post and blunt fin unchanged. Spread in proportion to m
 * itself did better on the igloo (2.97%) and worse on tets-1M (2.51% after
 * 2 frames), whose thin parts carry much of the image. The cost: the
 * dense AMR-like mesh (density 8) loses 10-35%, its thin parts giving points
 * to dense ones whose spacing m / kappa already sets
 * (bench/results/render-converge/2026-11-25-s25-root.md). g: the ray's
 * gaps, which hold no depth. */
inline float clvr_root_depth(const clvr_volume *v, float3 org, float3 dir, float t0, float t1, const clvr_gaps *g)
{
    float root = 0.0f, front = 1.0f;
    int gi = 0;
    CLVR_FOR_EACH_SEGMENT(v, org, dir, t0, t1, a, b, m, clvr_root_segment(a, b, m, g, &gi, &root, &front));
    return root;
}

/* The urm walk of a camera ray (or an MPI region of one) over [t0, t1]:
 * its minimum points (share of them, clvr_urm_begin) spread by
 * clvr_root_depth, light-grid terms when the frame has shadows. Returns
 * T(t1); e holds the sums and the pick. */
inline float clvr_urm_camera(const clvr_volume *v, clvr_urm *e, float3 org, float3 dir, float t0, float t1, float share,
                             float u, float u_pick, const clvr_gaps *g, clvr_rng *rng, uint *samples, uint *nulls)
{
    const clvr_frame *f = v->f;
    clvr_urm_begin(f, e, t1 - t0, clvr_root_depth(v, org, dir, t0, t1, g), u, u_pick, f->shadows ? 2 : 1,
                   CLVR_URM_RESIDUAL_RATE, share, rng);
    int gi = 0;
    CLVR_FOR_EACH_SEGMENT(v, org, dir, t0, t1, a, b, m,
                          !clvr_urm_segment_gaps(v, e, org, dir, a, b, m, g, &gi, rng, samples, nulls));
    return clvr_urm_end(e);
}

/* ------------------------------------------------------------ walk
 * Tet meshes with face adjacency (hull.h, clvr_hull_twin): the camera ray
 * walks from tet to tet across shared faces. In a tet the scalar is affine,
 * so along the ray it is linear, and the extinction (the transfer
 * function's, piecewise linear in the scalar) is piecewise linear in t:
 * each tet's optical depth is integrated exactly (a trapezoid inside one
 * bin of the table, the prefix sums clvr_walk_g across bins), so the
 * transmittance is exact; the tet's emission int T sigma c dt is estimated
 * by one point drawn in proportion to sigma and weighted by the
 * transmittance there (tau <= 1/4), or drawn in proportion to T sigma
 * (thicker tets): unbiased either way, its variance only the colour's
 * change inside the tet. Cells of the other types (with --estimator walk;
 * auto hands the ray to urm at the first, clvr_frame.walk_cells) are
 * crossed by their faces too (kernels/cell_ray.h), their field integrated
 * as a tet's plus an unbiased correction (clvr_walk_cell). Where the walk
 * cannot go on (a boundary face with nothing found just past it and no
 * stretch of the hull's outside the mesh after it, a flat tet), urm
 * finishes the ray from that point (clvr_render_track). Measured against
 * urm: bench/results/render-converge/2026-11-29-s36-walk.md (tets),
 * 2026-11-30-s44-cell-walk.md (other cells). */

/* The table's extinction weight (w, before the density) at position p in
 * [0, n - 1], as clvr_tf_lookup interpolates it. */
inline float clvr_walk_w(const clvr_volume *v, float p)
{
    const uint i = clvr_tf_entry(p, v->f->tf_size);
    const float a = v->tf[i].w, b = v->tf[i + 1u].w;
    return a + (p - (float)i) * (b - a);
}

/* G(p): the integral of w from position 0 to p (positions: table entries),
 * w held at its end values beyond the table, as the lookup clamps. */
inline float clvr_walk_g(const clvr_volume *v, float p)
{
    const uint n = v->f->tf_size;
    const float last = (float)(n - 1u);
    if (p <= 0.0f) return v->tf[0].w * p;
    if (p >= last) return v->tf_prefix[n - 1u] + v->tf[n - 1u].w * (p - last);
    const uint i = clvr_tf_entry(p, n);
    const float f = p - (float)i, a = v->tf[i].w, b = v->tf[i + 1u].w;
    return v->tf_prefix[i] + f * (a + 0.5f * f * (b - a));
}

/* A position p with G(p) = g (G is nondecreasing). The search starts from
 * entries [lo, hi] (the caller's bracket: a tet's ends span a few entries of
 * the table, and the search over all of them took a quarter of the walk's
 * time on the combustor); it widens to the whole table where they do not
 * bracket g. */
inline float clvr_walk_g_inverse(const clvr_volume *v, float g, uint lo, uint hi)
{
    const uint n = v->f->tf_size;
    if (g <= 0.0f) {
        const float w0 = v->tf[0].w;
        return w0 > 0.0f ? g / w0 : 0.0f;
    }
    const float pn = v->tf_prefix[n - 1u];
    if (g >= pn) {
        const float wl = v->tf[n - 1u].w;
        return (float)(n - 1u) + (wl > 0.0f ? (g - pn) / wl : 0.0f);
    }
    /* P[lo] <= g < P[hi] */
    hi = min(hi, n - 1u);
    if (!(v->tf_prefix[lo] <= g) || lo >= hi) lo = 0u;
    if (!(g < v->tf_prefix[hi])) hi = n - 1u;
    while (hi - lo > 1u) {
        const uint mid = (lo + hi) / 2u;
        if (v->tf_prefix[mid] <= g) lo = mid;
        else hi = mid;
    }
    const float a = v->tf[lo].w, b = v->tf[lo + 1u].w, r = g - v->tf_prefix[lo];
    const float den = a + sqrt(fmax(a * a + 2.0f * (b - a) * r, 0.0f));
    return (float)lo + (den > 0.0f ? clamp(2.0f * r / den, 0.0f, 1.0f) : 0.0f);
}

/* The first face slot of cell e (its faces' slots follow in
 * clvr_hull_face_code order). */
inline uint clvr_walk_slots(const clvr_volume *v, uint inst_id, const clvr_instance *inst, uint e)
{
    return v->face_first[inst_id] + (e - inst->first_element) * clvr_hull_face_count(inst->type);
}

/* The face slot of tet e's face opposite vertex k. */
inline uint clvr_walk_slot(const clvr_volume *v, uint inst_id, const clvr_instance *inst, uint e, int k)
{
    return clvr_walk_slots(v, inst_id, inst, e) + (k == 0 ? 1u : k == 1 ? 2u : k == 2 ? 0u : 3u);
}

/* Where the walk stands: the cell, its instance and the ray parameter. */
typedef struct clvr_walk {
    clvr_locate_hint h; /* h.inst: the instance of e */
    clvr_instance inst;
    clvr_piece_arrays pa;
    uint e;
    uint type; /* e's own type (clvr_walk_load: a collapsed hex's, the type it collapses to) */
    uint from; /* the cell it came from across a face, or CLVR_BVH_NOT_FOUND */
    int skip;  /* e's face the ray came in by (not a tet): -1 none, -2 the one toward from (not looked up yet) */
    float t;
    float s;   /* the scalar at t where a face gave it, else NaN */
} clvr_walk;

/* Points the walk at cell nb (global sorted id) across a face, finding its
 * instance (instances are sorted by first element). */
inline void clvr_walk_goto(const clvr_volume *v, const clvr_mesh_view *m, clvr_walk *w, uint nb)
{
    if (nb - w->inst.first_element >= w->inst.num_elements) {
        uint lo = 0u, hi = v->f->num_instances;
        while (hi - lo > 1u) {
            const uint mid = (lo + hi) / 2u;
            if (m->instances[mid].first_element <= nb) lo = mid;
            else hi = mid;
        }
        w->inst = m->instances[lo];
        w->pa = clvr_view_piece(m, &w->inst);
        /* The lookup hint moves with it (its node is a node of this
         * instance's tree). */
        w->h.inst = lo;
        w->h.node = clvr_locate_hint_node(&w->inst, w->inst.first_leaf + (nb - w->inst.first_element) / m->leaf_size);
    }
    w->from = w->e;
    w->e = nb;
    w->skip = -2;
}

/* Loads the walk's cell into vtx (its own type's vertices) and sets
 * w->type (clvr_load_cell_in); returns it. */
inline uint clvr_walk_load(clvr_walk *w, clvr_vec4 *vtx)
{
    if (w->inst.type == CLVR_CELL_TET) {
        clvr_load_tet(&w->pa, &w->inst, w->e, vtx);
        w->type = CLVR_CELL_TET;
    } else w->type = clvr_load_cell_in(&w->pa, &w->inst, w->e, vtx);
    return w->type;
}

/* Where the ray org + t dir, inside cell w->e (not a tet) just after t,
 * leaves it (clvr_cell_exit, skipping the face it came in by): the face,
 * -1 when none was found. */
inline int clvr_walk_cell_exit(const clvr_volume *v, clvr_walk *w, const clvr_vec4 *vtx, float3 org, float3 dir, float t,
                               float *tx, float *sx)
{
    const uint nf = clvr_hull_face_count(w->type), base = clvr_walk_slots(v, w->h.inst, &w->inst, w->e);
    if (w->skip == -2) {
        w->skip = -1;
        for (uint k = 0; k < nf; ++k)
            if (v->adj[base + k] == w->from) {
                w->skip = (int)k;
                break;
            }
    }
    const float o[3] = {org.x, org.y, org.z}, d[3] = {dir.x, dir.y, dir.z};
    return clvr_cell_exit(w->type, vtx, o, d, t, w->skip, tx, sx);
}

/* Enters the mesh after t_from: a lookup at t_probe (a little past the
 * crossing, which the hull places conservatively), then back across entry
 * faces to the cell the ray enters first after t_from; w->t = that entry
 * (at least t_from), w->s the scalar there when a face of a cell other
 * than a tet gave it. 1 then; 0 when the lookup finds no cell (the point
 * is outside the mesh); -1 when it found one the walk cannot start from
 * (a type it does not take, a flat tet, no face behind the point in
 * float): the point may be inside, so no gap of the hull may be skipped
 * from there. */
inline int clvr_walk_enter(const clvr_volume *v, const clvr_mesh_view *m, float3 org, float3 dir, float t_from,
                           float t_probe, clvr_walk *w)
{
    const float3 q = org + dir * t_probe;
    float s;
    if (!clvr_locate_hinted(m, q.x, q.y, q.z, &w->h, &s, &w->e)) return 0;
    w->inst = m->instances[w->h.inst];
    w->pa = clvr_view_piece(m, &w->inst);
    w->from = CLVR_BVH_NOT_FOUND;
    w->skip = -1;
    float t = t_probe;
    for (int back = 0; back < 64; ++back) {
        clvr_vec4 vtx[CLVR_CELL_MAX_VERTS];
        float dt;
        uint slot;
        /* (also after each step back: into a cell the walk does not take, urm takes the ray from t_from) */
        if (clvr_walk_load(w, vtx) != CLVR_CELL_TET && !v->f->walk_cells) return -1;
        if (w->type == CLVR_CELL_TET) {
            float l[4], g[4];
            if (!clvr_tet_bary(vtx, org, dir, t, l, g)) return -1;
            /* The face the ray entered by: where the reversed ray leaves. */
            for (int k = 0; k < 4; ++k) g[k] = -g[k];
            const int kx = clvr_tet_exit(l, g, &dt);
            if (kx < 0) return -1;
            slot = clvr_walk_slot(v, w->h.inst, &w->inst, w->e, kx);
            w->s = NAN;
        } else {
            float tx;
            const int fx = clvr_walk_cell_exit(v, w, vtx, org, -dir, -t, &tx, &w->s);
            if (fx < 0) return -1;
            dt = tx + t;
            slot = clvr_walk_slots(v, w->h.inst, &w->inst, w->e) + (uint)fx;
            w->skip = fx;
        }
        t = fmax(t - fmax(dt, 0.0f), t_from);
        if (t <= t_from) break;
        const uint nb = v->adj[slot];
        if (nb == CLVR_BVH_NOT_FOUND) break;
        clvr_walk_goto(v, m, w, nb);
    }
    /* At t_from, not on a face: no scalar; the face behind stays skipped
     * (a hair behind t_from, it would be found again as the exit). */
    if (t <= t_from) w->s = NAN;
    w->t = t;
    return 1;
}

/* The light grid along a walked ray (see CLVR_WALK_LIGHT_STEP): its values
 * at t_A and t_B = t_A + step. */
typedef struct clvr_walk_light {
    float t_A, t_B, G_A, G_B, s_A, s_B, step;
} clvr_walk_light;

/* G at te (linear between the pair, the pair moved on by a step, or
 * started afresh at te, once te leaves it) and *spread. */
inline float clvr_walk_light_at(const clvr_volume *v, clvr_walk_light *L, float3 org, float3 dir, float te,
                                float *spread)
{
    if (!(te >= L->t_A && te <= L->t_B)) {
        if (te > L->t_B && te <= L->t_B + L->step) {
            L->t_A = L->t_B;
            L->G_A = L->G_B;
            L->s_A = L->s_B;
        } else {
            L->t_A = te;
            L->G_A = clvr_light_at(v, org + dir * L->t_A, &L->s_A);
        }
        L->t_B = L->t_A + L->step;
        L->G_B = clvr_light_at(v, org + dir * L->t_B, &L->s_B);
    }
    *spread = fmax(L->s_A, L->s_B);
    return L->step > 0.0f ? mix(L->G_A, L->G_B, (te - L->t_A) / L->step) : L->G_A;
}

/* The walk's extinction over a stretch [0, len] of the ray along which the
 * scalar is linear, sa to sb (in a tet, the field itself; in another cell,
 * the control): the table's extinction, piecewise linear in the scalar,
 * integrated exactly. */
typedef struct clvr_walk_ctl {
    float len, sa, k;  /* the scalar sa + k x */
    float pa, pb;      /* table positions at the ends (unclamped) */
    float sig_a, sig_b, ga, gb, tau;
    int one_bin;       /* one bin of the table (or both ends beyond the same end): linear in x */
} clvr_walk_ctl;

/* k: ds/dt (sb = sa + k len); sig_a: the extinction at sa. This, its
 * inverse and clvr_walk_draw are forced inline: PoCL's compiler called them
 * out of line with the control in memory (a quarter of post-tets' walk
 * frame in the two; the tet walk was 10-15% slower since session 44's
 * refactoring into them than before it), and inlined the frame is 5-10%
 * shorter, the same bits. */
CLVR_FORCE_INLINE void clvr_walk_ctl_make(const clvr_volume *v, float sa, float sb, float k, float len, float sig_a,
                                          clvr_walk_ctl *c)
{
    const clvr_frame *f = v->f;
    const float tf_scale = (float)(f->tf_size - 1u) / (f->tf_hi - f->tf_lo), last = (float)(f->tf_size - 1u);
    c->len = len;
    c->sa = sa;
    c->k = k;
    c->pa = (sa - f->tf_lo) * tf_scale;
    c->pb = (sb - f->tf_lo) * tf_scale;
    const float qa = clamp(c->pa, 0.0f, last), qb = clamp(c->pb, 0.0f, last);
    c->sig_a = sig_a;
    c->sig_b = f->density * clvr_walk_w(v, qb);
    /* One bin of the table (or both ends beyond the same end): the
     * extinction is linear over the stretch, its integral the trapezoid,
     * its inverse a quadratic; else the prefix sums. */
    c->one_bin = (c->pa <= 0.0f && c->pb <= 0.0f) || (c->pa >= last && c->pb >= last) ||
                 (qa == c->pa && qb == c->pb && clvr_tf_entry(qa, f->tf_size) == clvr_tf_entry(qb, f->tf_size));
    c->ga = c->one_bin ? 0.0f : clvr_walk_g(v, c->pa);
    c->gb = c->one_bin ? 0.0f : clvr_walk_g(v, c->pb);
    c->tau = c->one_bin ? 0.5f * len * (c->sig_a + c->sig_b)
                        : f->density * (c->gb - c->ga) / (k * tf_scale);
}

/* x in [0, len] where the control's depth from 0 reaches want (0 <= want
 * <= tau). */
CLVR_FORCE_INLINE float clvr_walk_ctl_inverse(const clvr_volume *v, const clvr_walk_ctl *c, float want)
{
    float xs;
    if (c->one_bin) {
        const float den = c->sig_a + sqrt(fmax(c->sig_a * c->sig_a + 2.0f * (c->sig_b - c->sig_a) / c->len * want, 0.0f));
        xs = den > 0.0f ? 2.0f * want / den : 0.0f;
    } else {
        const clvr_frame *f = v->f;
        const float last = (float)(f->tf_size - 1u);
        const float qa = clamp(c->pa, 0.0f, last), qb = clamp(c->pb, 0.0f, last);
        const float ps = clvr_walk_g_inverse(v, c->ga + want / c->tau * (c->gb - c->ga),
                                             clvr_tf_entry(fmin(qa, qb), f->tf_size),
                                             clvr_tf_entry(fmax(qa, qb), f->tf_size) + 1u);
        xs = c->len * (ps - c->pa) / (c->pb - c->pa);
    }
    return clamp(xs, 0.0f, c->len);
}

/* The control's extinction at x and its depth from 0 to x. */
inline float clvr_walk_ctl_sigma(const clvr_volume *v, const clvr_walk_ctl *c, float x)
{
    const clvr_frame *f = v->f;
    const float p = c->pa + (c->pb - c->pa) * (x / c->len);
    return f->density * clvr_walk_w(v, clamp(p, 0.0f, (float)(f->tf_size - 1u)));
}

inline float clvr_walk_ctl_depth(const clvr_volume *v, const clvr_walk_ctl *c, float x)
{
    if (c->one_bin) return x * (c->sig_a + 0.5f * (c->sig_b - c->sig_a) * (x / c->len));
    if (!(c->tau > 0.0f)) return 0.0f;
    const float p = c->pa + (c->pb - c->pa) * (x / c->len);
    return c->tau * (clvr_walk_g(v, p) - c->ga) / (c->gb - c->ga);
}

/* The emission point of a stretch of control depth tau > 0, from uniform
 * u: *want, the control depth in front of it, and the weight of its value
 * (T sigma c / pdf = wt c where the control is exact): drawn in proportion
 * to the extinction and weighted by the transmittance there (thin
 * stretches), or in proportion to both (tau > 1/4). */
CLVR_FORCE_INLINE float clvr_walk_draw(float tau, float u, float *want)
{
    if (tau <= 0.25f) {
        *want = u * tau;
        return tau * clvr_exp_neg(*want);
    }
    const float wt = -expm1(-tau);
    *want = -log1p(-u * wt);
    return wt;
}

/* Residual points per unit t of a cell other than a tet, as a multiple of
 * the spread of the table's extinction over the cell (see clvr_walk_cell).
 * fire_ug's 10k hexes, 128^2, error after one frame without pieces: rate 1
 * 8.9%, 4 5.5%, 16 4.2%, 64 4.0% (urm 2.6%); the pieces did the rest. */
#ifndef CLVR_WALK_RESIDUAL_RATE
#define CLVR_WALK_RESIDUAL_RATE 4.0f
#endif

/* The scalar of cell vtx (not a tet) at p: Newton from the coordinates of
 * the cell's last solve (*have) or the type's start; where it fails (a
 * degenerate cell), fallback (the control's value). */
inline float clvr_walk_cell_scalar(uint type, const clvr_vec4 *vtx, float3 p, int *have, float *uvw, float fallback)
{
    float a, b, c, N[CLVR_CELL_MAX_VERTS];
    for (int attempt = 0; attempt < 2; ++attempt) {
        if (!*have) clvr_element_start(type, uvw, uvw + 1, uvw + 2);
        const int ok = type == CLVR_CELL_HEX
                           ? clvr_newton_solve(CLVR_CELL_HEX, vtx, p.x, p.y, p.z, uvw[0], uvw[1], uvw[2], &a, &b, &c, N)
                           : clvr_newton_solve(type, vtx, p.x, p.y, p.z, uvw[0], uvw[1], uvw[2], &a, &b, &c, N);
        if (ok) {
            const uint nv = clvr_cell_vertex_count(type);
            float s = 0.0f;
            for (uint i = 0; i < nv; ++i) s += N[i] * vtx[i].w;
            uvw[0] = a; uvw[1] = b; uvw[2] = c;
            *have = 1;
            return s;
        }
        if (!*have) break;
        *have = 0;
    }
    return fallback;
}

/* Pieces of a cell's chord: at most this many, each with a bound on
 * |sigma c - sigma~ c~| times its length of at most CLVR_WALK_PIECE_DEPTH
 * (see clvr_walk_cell). fire_ug's hexes, 128^2, error after one frame at
 * rate 4: 0.05, 3.2% at 20 ms a frame; 0.02, 2.7% at 28 ms (urm: 2.6% at
 * 19-23 ms); a bound on the extinction alone (no colour) at 0.03: 3.5%. */
#ifndef CLVR_WALK_MAX_PIECES
#define CLVR_WALK_MAX_PIECES 8
#endif
#ifndef CLVR_WALK_PIECE_DEPTH
#define CLVR_WALK_PIECE_DEPTH 0.05f
#endif

/* One piece [ta, ta + len] of a cell's chord, the scalar sa and sb at its
 * ends, delta the bound on |sigma - sigma~| (see clvr_walk_cell). */
inline void clvr_walk_piece(const clvr_volume *v, const clvr_vec4 *vtx, uint type, float3 org, float3 dir, float ta,
                            float sa, float sb, float len, float delta, float u, clvr_rng *rng, clvr_emit *acc,
                            float *T, clvr_walk_light *L, int *have, float *uvw, uint *samples, uint *nulls)
{
    const clvr_frame *f = v->f;
    const float last = (float)(f->tf_size - 1u), tf_scale = last / (f->tf_hi - f->tf_lo);
    clvr_walk_ctl c;
    clvr_walk_ctl_make(v, sa, sb, (sb - sa) / len, len,
                       f->density * clvr_walk_w(v, clamp((sa - f->tf_lo) * tf_scale, 0.0f, last)), &c);
    const float dl = delta * len, tot = c.tau + dl;
    if (!(tot > 0.0f)) return;
    /* The emission point x: Gx, the control's depth in front of it. */
    const float e = dl / tot;
    float x, Gx, uu = u;
    if (uu < e) {
        x = len * (uu / e);
        Gx = clvr_walk_ctl_depth(v, &c, x);
    } else {
        uu = fmin((uu - e) / (1.0f - e), 0x1.fffffep-1f);
        clvr_walk_draw(c.tau, uu, &Gx);
        x = clvr_walk_ctl_inverse(v, &c, Gx);
    }
    const float sig_c = clvr_walk_ctl_sigma(v, &c, x);
    const float pdf_c = c.tau > 0.0f ? (c.tau <= 0.25f ? sig_c / c.tau : sig_c * clvr_exp_neg(Gx) / -expm1(-c.tau)) : 0.0f;
    const float pdf = (1.0f - e) * pdf_c + e / len;
    /* The process's points: R over the piece, Rx over those before x. */
    float R = 1.0f, Rx = 1.0f;
    if (delta > 0.0f) {
        const float inv_mu = 1.0f / (CLVR_WALK_RESIDUAL_RATE * delta);
        for (float xi = -log(1.0f - clvr_rng_next(rng)) * inv_mu; xi < len;
             xi += -log(1.0f - clvr_rng_next(rng)) * inv_mu) {
            const float sc = c.sa + c.k * xi;
            const float si = clvr_walk_cell_scalar(type, vtx, org + dir * (ta + xi), have, uvw, sc);
            const float fac = 1.0f - (clvr_volume_tf(v, si).w - clvr_walk_ctl_sigma(v, &c, xi)) * inv_mu;
            R *= fac;
            if (xi < x) Rx *= fac;
            ++*samples;
            ++*nulls;
        }
    }
    const float4 m = clvr_volume_tf(v, clvr_walk_cell_scalar(type, vtx, org + dir * (ta + x), have, uvw, c.sa + c.k * x));
    if (m.w > 0.0f && pdf > 0.0f) {
        const float3 ge = (*T * Rx * clvr_exp_neg(Gx) * m.w / pdf) * m.xyz;
        float spread = 0.0f;
        const float G = acc->shadows ? clvr_walk_light_at(v, L, org, dir, ta + x, &spread) : 1.0f;
        clvr_emit_add(acc, ta + x, ge, fabs(clvr_urm_lum(ge)), G, spread);
    }
    *T *= clvr_exp_neg(c.tau) * R;
}

/* The walk through a cell other than a tet over [ta, ta + len]: the
 * scalar is not linear along the ray there, so the walk integrates a
 * control exactly and corrects it without bias.
 * - Control: the scalar linear from sa to sb, the faces' values where the
 *   ray enters and leaves (exact there, clvr_cell_exit), its extinction
 *   sigma~ (the table's) integrated exactly as in a tet (clvr_walk_ctl),
 *   depth tau.
 * - The cell's extinction lies in [sig_lo, sig_hi], the table's bounds
 *   over its vertices' scalar range (the interpolant is a convex
 *   combination of them), and so does the control's: |sigma - sigma~| <=
 *   delta = sig_hi - sig_lo.
 * - Transmittance: exp(-tau) times, over the points of a Poisson process
 *   of rate mu = CLVR_WALK_RESIDUAL_RATE delta, the product of
 *   1 - (sigma - sigma~) / mu: its mean is exp(-int (sigma - sigma~)) (the
 *   process's generating functional), each factor in [1 - 1/rate,
 *   1 + 1/rate]. A cell with delta 0 has sigma = sigma~: no points, exact,
 *   as a tet.
 * - Emission int T sigma c: one point x, drawn as a tet's from the control
 *   (clvr_walk_draw) with probability 1 - e and uniformly with e = delta
 *   len / (tau + delta len), so that every x where sigma can be positive
 *   can be drawn; its value T(x) sigma(x) c(x) / pdf(x) at the cell's own
 *   scalar there, T(x) from the process's points before x. (Taking the
 *   control's colour at x and adding the difference at the process's
 *   points instead, no solve at x, measured 4-5x the error per frame on
 *   the notch, fire_ug and the built-in scene: rare points with large
 *   weights.)
 * - Pieces: where the bound on |sigma c - sigma~ c~| times the chord
 *   exceeds CLVR_WALK_PIECE_DEPTH, the chord is cut into up to
 *   CLVR_WALK_MAX_PIECES equal pieces at Newton points, each with its own
 *   control (clvr_walk_piece): a field that curves inside a cell gets
 *   more points, as urm's majorant-driven ones.
 * Each point is one Newton solve in the cell (clvr_walk_cell_scalar).
 * Measured (bench/results/render-converge/2026-11-30-s44-cell-walk.md):
 * 2% in half urm's time on the notch's coarse FE hexes, 1.1-1.9x urm's on
 * finer CFD hexes, the built-in scene and the AMR-like mesh, so auto
 * measures which of the two to take per view (its pilot,
 * host/pipeline/render.c pilot_pick). */
inline void clvr_walk_cell(const clvr_volume *v, const clvr_vec4 *vtx, uint type, float3 org, float3 dir, float ta,
                           float sa, float sb, float len, float u, clvr_rng *rng, clvr_emit *acc, float *T,
                           clvr_walk_light *L, uint *samples, uint *nulls)
{
    const clvr_frame *f = v->f;
    const uint nv = clvr_cell_vertex_count(type);
    float lo = vtx[0].w, hi = vtx[0].w;
    for (uint i = 1; i < nv; ++i) {
        lo = fmin(lo, vtx[i].w);
        hi = fmax(hi, vtx[i].w);
    }
    const uint n = f->tf_size, i0 = clvr_tf_entry(clvr_tf_position(lo, f->tf_lo, f->tf_hi, n), n);
    const uint i1 = n < 2u ? 0u : clvr_tf_entry(clvr_tf_position(hi, f->tf_lo, f->tf_hi, n), n) + 1u;
    float4 tlo = v->tf[i0], thi = tlo;
    for (uint i = i0 + 1u; i <= i1; ++i) {
        tlo = fmin(tlo, v->tf[i]);
        thi = fmax(thi, v->tf[i]);
    }
    const float delta = f->density * (thi.w - tlo.w);
    const float3 dc = thi.xyz - tlo.xyz;
    const float spread = delta * fmax(fmax(thi.x, thi.y), thi.z) + f->density * thi.w * fmax(fmax(dc.x, dc.y), dc.z);
    const int K = (int)clamp(ceil(spread * len / CLVR_WALK_PIECE_DEPTH), 1.0f, (float)CLVR_WALK_MAX_PIECES);
    float uvw[3], a = 0.0f, s0 = sa;
    int have = 0;
    for (int k = 1; k <= K; ++k) {
        const float b = k == K ? len : len * (float)k / (float)K;
        const float fb = sa + (sb - sa) * (b / len);
        const float s1 = k == K ? sb : clvr_walk_cell_scalar(type, vtx, org + dir * (ta + b), &have, uvw, fb);
        if (k < K) ++*samples;
        clvr_walk_piece(v, vtx, type, org, dir, ta + a, s0, s1, b - a, delta, u, rng, acc, T, L, &have, uvw, samples,
                        nulls);
        a = b;
        s0 = s1;
    }
}

/* Walks [t0, t1] (raw hull gaps glo/ghi, ng of them, tell where the ray is
 * outside between two crossings): *sum the emission with the
 * transmittance applied, *T the transmittance at the end. Returns 1 when
 * it covered the interval, 0 with *t_stop where it stopped (the caller
 * finishes [*t_stop, t1] another way). */
inline int clvr_walk_ray(const clvr_volume *v, float3 org, float3 dir, float t0, float t1, const float *glo,
                         const float *ghi, int ng, float u, clvr_rng *rng, clvr_emit *acc, float *T, float *t_stop,
                         uint *samples, uint *nulls)
{
    const clvr_frame *f = v->f;
    const clvr_mesh_view m = clvr_volume_view(v);
    const float eps = 1e-6f * (fabs(t0) + fabs(t1)) + 1e-30f, probe = fmin(1e-3f * (t1 - t0), 1e3f * eps);
    const float tf_scale = (float)(f->tf_size - 1u) / (f->tf_hi - f->tf_lo), last = (float)(f->tf_size - 1u);
    clvr_walk w;
    w.h = clvr_locate_hint_none();
    w.e = CLVR_BVH_NOT_FOUND;
    *T = 1.0f;
    *t_stop = t0;
    if (clvr_walk_enter(v, &m, org, dir, t0, fmin(t0 + probe, t1), &w) <= 0) return 0;
    /* sig_a: the extinction at sa, NaN until computed */
    float sa = w.s, sig_a = NAN, G = 1.0f, spread = 0.0f;
    clvr_walk_light L;
    L.t_A = INFINITY;
    L.t_B = -INFINITY;
    L.G_A = L.G_B = 1.0f;
    L.s_A = L.s_B = 0.0f;
    /* The light grid's smallest spacing, in units of t. */
    L.step = CLVR_WALK_LIGHT_STEP * fmin(fmin(f->light_space[3][0], f->light_space[3][1]), f->light_space[3][2]) /
             length(dir);
    int zsteps = 0;
    for (int iter = 0; iter < 65536; ++iter) {
        float tb, sb;
        uint slot;
        int moved;
        clvr_vec4 vtx[CLVR_CELL_MAX_VERTS];
        if (clvr_walk_load(&w, vtx) == CLVR_CELL_TET) {
            float l[4], g[4];
            if (!clvr_tet_bary(vtx, org, dir, w.t, l, g)) return 0;
            float dt;
            const int kx = clvr_tet_exit(l, g, &dt);
            if (kx < 0) return 0;
            slot = clvr_walk_slot(v, w.h.inst, &w.inst, w.e, kx);
            tb = fmin(w.t + fmax(dt, 0.0f), t1);
            const float len = tb - w.t;
            const float k = g[0] * vtx[0].w + g[1] * vtx[1].w + g[2] * vtx[2].w + g[3] * vtx[3].w;
            if (isnan(sa)) sa = l[0] * vtx[0].w + l[1] * vtx[1].w + l[2] * vtx[2].w + l[3] * vtx[3].w;
            if (isnan(sig_a)) sig_a = f->density * clvr_walk_w(v, clamp((sa - f->tf_lo) * tf_scale, 0.0f, last));
            sb = sa + k * fmax(len, 0.0f);
            moved = len > 0.0f;
            if (moved) {
                ++*samples;
                clvr_walk_ctl c;
                clvr_walk_ctl_make(v, sa, sb, k, len, sig_a, &c);
                if (c.tau > 0.0f) {
                    float want;
                    const float wt = clvr_walk_draw(c.tau, u, &want);
                    const float xc = clvr_walk_ctl_inverse(v, &c, want);
                    if (acc->shadows) G = clvr_walk_light_at(v, &L, org, dir, w.t + xc, &spread);
                    const float3 ge = (*T * wt) * clvr_volume_tf(v, sa + k * xc).xyz;
                    clvr_emit_add(acc, w.t + xc, ge, clvr_urm_lum(ge), G, spread);
                    *T *= clvr_exp_neg(c.tau);
                }
                sig_a = c.sig_b;
            }
        } else {
            if (!f->walk_cells) return 0; /* urm finishes the ray from w.t */
            float tx, sx;
            const int fx = clvr_walk_cell_exit(v, &w, vtx, org, dir, w.t, &tx, &sx);
            moved = fx >= 0 && tx > w.t;
            tb = fx >= 0 ? fmin(tx, t1) : w.t;
            slot = fx >= 0 ? clvr_walk_slots(v, w.h.inst, &w.inst, w.e) + (uint)fx : 0u;
            /* Any control keeps the cell's estimate unbiased: where the
             * entry's scalar is not known (the walk entered by a lookup),
             * the exit's, constant. */
            if (isnan(sa)) sa = sx;
            sb = fx >= 0 && tx > t1 ? sa + (sx - sa) * ((t1 - w.t) / (tx - w.t)) : sx;
            if (moved) {
                ++*samples;
                clvr_walk_cell(v, vtx, w.type, org, dir, w.t, sa, sb, tb - w.t, u, rng, acc, T, &L, samples,
                               nulls);
            }
            sig_a = NAN;
            if (fx < 0) moved = -1;
        }
        if (moved > 0) {
            zsteps = 0;
            if (*T < CLVR_URM_RR) {
                if (clvr_rng_next(rng) * CLVR_URM_RR >= *T) {
                    *T = 0.0f;
                    *t_stop = t1;
                    return 1;
                }
                *T = CLVR_URM_RR;
            }
        } else if (moved < 0 || ++zsteps > 4) {
            /* A ray along an edge or through a vertex: the cells around it
             * may hand it back and forth without moving on (or, in a cell
             * other than a tet, no face is hit in float). A lookup a little
             * further on picks one of them. */
            const float tn = fmin(w.t + 8.0f * eps, t1);
            *t_stop = w.t;
            if (tn >= t1) return 1;
            ++*nulls;
            if (clvr_walk_enter(v, &m, org, dir, tn, tn, &w) <= 0) return 0;
            sa = w.s;
            sig_a = NAN;
            zsteps = 0;
            continue;
        }
        w.t = tb;
        sa = sb;
        *t_stop = w.t;
        if (w.t >= t1) return 1;
        const uint nb = v->adj[slot];
        if (nb != CLVR_BVH_NOT_FOUND) {
            clvr_walk_goto(v, &m, &w, nb);
            continue;
        }
        /* A boundary face: the ray leaves the mesh here, or meets a face
         * whose other side does not match (a non-conforming mesh). A
         * lookup just past it; else, where the hull's crossings put a
         * stretch outside the mesh after it, past that stretch. */
        ++*nulls;
        const float tx = w.t;
        const int in = clvr_walk_enter(v, &m, org, dir, tx, fmin(tx + eps, t1), &w);
        if (in < 0) return 0; /* urm finishes from tx */
        if (in > 0) {
            sa = w.s;
            sig_a = NAN;
            continue;
        }
        int i = 0;
        while (i < ng && !(glo[i] <= tx + probe && ghi[i] > tx + probe)) ++i;
        if (i == ng) return 0;
        /* A candidate gap lies wholly inside or outside the mesh (faces
         * that only look like boundary faces, a non-conforming mesh's,
         * bound some): one lookup at its middle says which, as
         * clvr_volume_hull_gaps does; inside, urm finishes from tx. */
        {
            const float3 q = org + dir * (0.5f * (fmax(glo[i], tx) + fmin(ghi[i], t1)));
            float sq;
            if (clvr_locate_point(m, q.x, q.y, q.z, &sq)) return 0;
        }
        if (ghi[i] >= t1) return 1; /* the rest is outside: done */
        w.h = clvr_locate_hint_none();
        if (clvr_walk_enter(v, &m, org, dir, ghi[i], fmin(ghi[i] + probe, t1), &w) <= 0) return 0;
        sa = w.s;
        sig_a = NAN;
    }
    return 0;
}

/* A camera ray's value from its emission sums (walk's or urm's) and its
 * transmittance to the end, T: without shadows every point is fully lit
 * (the whole sum, no pick); with them, the light grid's terms plus the
 * correction shadow ray from the pick (see urm's comment). *guide: the
 * colour unlit and the points' weighted mean depth (the denoiser's). */
inline float4 clvr_emit_shade(const clvr_volume *v, const clvr_emit *a, float T, float3 org, float3 dir, float3 lo,
                              float3 hi, float3 ldir, float3 bg, const float *ld, clvr_rng *rng, uint *samples,
                              uint *nulls, uint *rays, float4 *guide)
{
    const clvr_frame *f = v->f;
    float3 c = (f->ambient + (f->shadows ? 0.0f : f->light_intensity)) * a->sum;
    if (f->shadows && a->wsum > 0.0f) {
        /* Russian roulette on the correction: where the grid is flat
         * around the pick (spread <= CLVR_URM_SHADOW_RR_SPREAD) it is
         * likely right there and the correction small, so the shadow
         * ray is traced with probability CLVR_URM_SHADOW_RR_Q only and
         * its correction divided by that (unbiased for any q > 0). */
        const float q = a->pick_s > CLVR_URM_SHADOW_RR_SPREAD ? 1.0f : CLVR_URM_SHADOW_RR_Q;
        c += f->light_intensity * a->lit;
        if (q >= 1.0f || clvr_rng_next(rng) < q) {
            const float u_s = ld ? ld[3] : clvr_rng_next(rng);
            const float lb = clvr_urm_light(v, org + dir * a->pick_t, ldir, lo, hi, u_s, rng, samples, nulls, rays);
            c += f->light_intensity * (lb - a->pick_g) * a->wsum * a->pick / q;
        }
    }
    *guide = (float4)(a->sum + T * bg, a->wsum > 0.0f ? a->tsum / a->wsum : -1.0f);
    return (float4)(c + T * bg, 1.0f - T);
}

/* One camera ray with the frame's estimator. u_primary (dimension 2 of the
 * low-discrepancy sampler, the caller's draw) drives the camera ray's first
 * free flight (delta) or quadrature offset (urm). ld: the frame's
 * low-discrepancy uniforms (CLVR_LD_DIMS), or NULL for the independent
 * sampler; dimension 3 drives the shadow ray's, 4 the pick of urm's
 * shadow-ray origin. Without ld the draws come from rng. */
inline float4 clvr_render_track(const clvr_volume *v, float3 org, float3 dir, float u_primary, clvr_rng *rng,
                                const float *ld, uint *samples, uint *nulls, uint *rays, float4 *guide)
{
    const clvr_frame *f = v->f;
    const float3 lo = vload3(0, f->vol_lo), hi = vload3(0, f->vol_hi), ldir = vload3(0, f->light_dir);
    const float4 bg = (float4)(vload3(0, f->background), 0.0f);
    float t0 = 0.0f, t1 = INFINITY;
    *guide = (float4)(bg.xyz, -1.0f);

    if (f->estimator == CLVR_ESTIMATOR_WALK) {
        if (!clvr_ray_clip(f, org, dir, lo, hi, &t0, &t1)) return bg;
        float glo[CLVR_HULL_MAX_HITS], ghi[CLVR_HULL_MAX_HITS];
        int ng;
        if (!clvr_volume_hull_crossings(v, org, dir, &t0, &t1, glo, ghi, &ng)) return bg;
        clvr_emit acc;
        clvr_emit_begin(&acc, f->shadows != 0u, ld ? ld[4] : clvr_rng_next(rng));
        float T, ts;
        if (!clvr_walk_ray(v, org, dir, t0, t1, glo, ghi, ng, u_primary, rng, &acc, &T, &ts, samples, nulls) &&
            T > 0.0f) {
            /* urm finishes the ray; its sums join the walk's (its pick
             * replaces the walk's in proportion to its weight). */
            clvr_urm e;
            clvr_gaps g;
            /* The stretches past ts that lie outside the mesh, skipped as
             * plain urm skips them: without them urm spent its points in a
             * mesh's holes (the OpenFOAM igloo's igloo and fridges), and the
             * tet walk + urm took 2.5x plain urm's frames to 2% there
             * (bench/results/graded/2026-12-02-s58-macrocells.md). */
            clvr_volume_outside_gaps(v, org, dir, ts, t1, CLVR_GAP_MIN * (t1 - t0), glo, ghi, ng, &g);
            /* Its minimum points in proportion to what is left of the ray:
             * a ray that leaves the mesh just before the hull's padded end
             * would otherwise spend all of them on lookups that miss. */
            const float Tend = clvr_urm_camera(v, &e, org, dir, ts, t1, (t1 - ts) / fmax(t1 - t0, 1e-30f), u_primary,
                                               clvr_rng_next(rng), &g, rng, samples, nulls);
            clvr_emit_merge(&acc, &e.acc, T, rng);
            T *= Tend;
        }
        return clvr_emit_shade(v, &acc, T, org, dir, lo, hi, ldir, bg.xyz, ld, rng, samples, nulls, rays, guide);
    }
    if (f->estimator != CLVR_ESTIMATOR_DELTA) {
        clvr_gaps g;
        if (!clvr_volume_clip_gaps(v, org, dir, lo, hi, &t0, &t1, &g)) return bg;
        clvr_urm e;
        const float u_pick = ld ? ld[4] : clvr_rng_next(rng);
        const float Tend = clvr_urm_camera(v, &e, org, dir, t0, t1, 1.0f, u_primary, u_pick, &g, rng, samples, nulls);
        return clvr_emit_shade(v, &e.acc, Tend, org, dir, lo, hi, ldir, bg.xyz, ld, rng, samples, nulls, rays, guide);
    }

    float t;
    float4 med;
    if (!clvr_volume_clip(v, org, dir, lo, hi, &t0, &t1)) return bg;
    if (!clvr_delta_track(v, org, dir, t0, t1, u_primary, rng, &t, &med, samples, nulls)) return bg;
    float light = 1.0f;
    if (f->shadows) {
        const float3 p = org + dir * t;
        float s0 = 0.0f, s1 = INFINITY;
        ++*rays;
        if (clvr_volume_clip(v, p, ldir, lo, hi, &s0, &s1)) {
            float ts;
            float4 m2;
            const float u_shadow = ld ? ld[3] : clvr_rng_next(rng);
            if (clvr_delta_track(v, p, ldir, s0, s1, u_shadow, rng, &ts, &m2, samples, nulls)) light = 0.0f;
        }
    }
    const float shade = f->ambient + f->light_intensity * light;
    *guide = (float4)(med.xyz, t); /* the colour and depth of the collision */
    return (float4)(med.xyz * shade, 1.0f);
}

/* MPI mode, phase 1 (docs/mpi-compositing.md): clvr_render_track's urm
 * camera ray restricted to this rank's region (the frame's clip box), with
 * the correction shadow ray left out: its reservoir goes into the record so
 * that rank 0 can pick one shadow point among all ranks. ld and rng are the
 * rank's own streams (dimension 2: quadrature offset, 4: the pick). */
inline void clvr_render_urm_record(const clvr_volume *v, float3 org, float3 dir, clvr_rng *rng, const float *ld,
                                   uint *samples, uint *nulls, __global clvr_mpi_record *rec)
{
    const clvr_frame *f = v->f;
    const float3 lo = vload3(0, f->vol_lo), hi = vload3(0, f->vol_hi);
    float t0 = 0.0f, t1 = INFINITY;
    const float u_primary = ld ? ld[2] : clvr_rng_next(rng);
    const float u_pick = ld ? ld[4] : clvr_rng_next(rng);
    rec->a = INFINITY;
    rec->tau = 1.0f;
    rec->wsum = 0.0f;
    rec->pick_g = 0.0f;
    vstore4((float4)(0.0f), 0, rec->e);
    vstore4((float4)(0.0f), 0, rec->pick);
    if (!clvr_ray_clip(f, org, dir, lo, hi, &t0, &t1)) return;
    const float a = t0;
    clvr_gaps g;
    if (!clvr_volume_hull_gaps(v, org, dir, &t0, &t1, &g)) {
        rec->a = a;
        return;
    }
    clvr_urm e;
    const float Tend = clvr_urm_camera(v, &e, org, dir, t0, t1, 1.0f, u_primary, u_pick, &g, rng, samples, nulls);
    const float3 c = (f->ambient + (f->shadows ? 0.0f : f->light_intensity)) * e.acc.sum +
                     (f->shadows ? f->light_intensity : 0.0f) * e.acc.lit;
    rec->a = a;
    rec->tau = Tend;
    rec->wsum = f->shadows ? e.acc.wsum : 0.0f;
    rec->pick_g = e.acc.pick_g;
    vstore4((float4)(c, 0.0f), 0, rec->e);
    vstore4((float4)(e.acc.pick, e.acc.pick_t), 0, rec->pick);
}

/* Front-to-back alpha compositing at a fixed step with a random offset per
 * frame, u in [0, 1) steps (so frames average to the continuous integral);
 * no shadows. */
inline float4 clvr_render_march(const clvr_volume *v, float3 org, float3 dir, float u, uint *samples)
{
    const clvr_frame *f = v->f;
    float3 lo = vload3(0, f->vol_lo), hi = vload3(0, f->vol_hi);
    float t0 = 0.0f, t1 = INFINITY;
    float4 bg = (float4)(vload3(0, f->background), 0.0f);
    if (!clvr_ray_clip(f, org, dir, lo, hi, &t0, &t1)) return bg;
    float3 c = (float3)(0.0f);
    float T = 1.0f;
    const float shade = f->ambient + f->light_intensity;
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

/* A pixel's random streams for its sample number `index` (its frames and
 * refine passes so far), keyed by (lo, hi): the generator, and with the ld
 * sampler point `index` of the pixel's sequence (CLVR_LD_DIMS uniforms) in
 * ld. Returns ld, or NULL for the independent sampler. */
inline const float *clvr_pixel_streams(const clvr_frame *f, uint pixel, uint index, uint lo, uint hi, clvr_rng *rng,
                                       float *ld)
{
    *rng = clvr_rng_make(pixel, index, lo, hi);
    if (f->sampler != CLVR_SAMPLER_LD) return NULL;
    clvr_ld_sample(pixel, index, lo, hi, ld);
    return ld;
}

/* Primary ray through pixel (x, y) at its sub-pixel position
 * (clvr_pixel_jitter). *jit: the position's offset from the centre, in
 * pixels (a control of kernels/pixel_cv.h). */
inline void clvr_render_primary_ray(__global const clvr_camera *cam, const clvr_frame *f, uint x, uint y,
                                    clvr_rng *rng, const float *ld, float3 *org, float3 *dir, float2 *jit)
{
    float jx, jy;
    clvr_pixel_jitter(ld, rng, f->pixel_filter, &jx, &jy);
    *jit = (float2)(jx - 0.5f, jy - 0.5f);
    clvr_camera c = *cam;
    float o[3], d[3];
    clvr_camera_ray(&c, (float)x + jx, (float)y + jy, o, d);
    *org = vload3(0, o);
    *dir = vload3(0, d);
}

#endif
