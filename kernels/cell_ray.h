/* cell_ray.h: where a ray leaves a pyramid, wedge or hexahedron, and the
 * scalar there: the walk estimator's step through cells other than tets
 * (kernels/render_volume.h; tets have their barycentrics). Compiled for the
 * host (tests/test_hull.c checks it against bisection on the cells' own
 * containment test) and for kernels: the same code on both sides.
 *
 * A quad face is the bilinear patch of the cell's map, its corners in the
 * cyclic order of clvr_hull_face_code (q00 q10 q11 q01). The ray meets it
 * where a quadratic in the patch's u has a root in [0, 1] (Reshetov, "Cool
 * Patches", Ray Tracing Gems, 2019, ch. 8), then t and v follow. A
 * triangle face: Moller and Trumbore. The cell's interpolant restricted to
 * a face is the face's own bilinear (on a triangle: linear) interpolation
 * of its corners' scalars, so the scalar where the ray leaves is exact
 * without a Newton solve, and the two cells that share the face compute
 * the same value from the same corners: the walk's scalar is continuous
 * from cell to cell. */
#ifndef CLVR_CELL_RAY_H
#define CLVR_CELL_RAY_H

#include "clvr_shared.h"
#include "hull.h"

#ifndef __OPENCL_VERSION__
#include <math.h>
#endif

/* Parametric slack of the face tests: a ray through an edge shared by two
 * faces hits at least one of them despite rounding (a hit a hair outside
 * a face lies a hair from the true exit). */
#define CLVR_CELL_RAY_EPS 1e-5f

/* 3-vectors: float3 and its built-ins in kernels (PoCL's vector code: the
 * face tests were a third of a frame written on float arrays), a struct on
 * the host. */
#ifdef __OPENCL_VERSION__
typedef float3 clvr_v3;
CLVR_INLINE clvr_v3 clvr_v3_make(float x, float y, float z) { return (float3)(x, y, z); }
CLVR_INLINE clvr_v3 clvr_v3_sub(clvr_v3 a, clvr_v3 b) { return a - b; }
CLVR_INLINE clvr_v3 clvr_v3_lerp(clvr_v3 a, clvr_v3 b, float u) { return a + u * (b - a); }
CLVR_INLINE clvr_v3 clvr_v3_cross(clvr_v3 a, clvr_v3 b) { return cross(a, b); }
CLVR_INLINE float clvr_v3_dot(clvr_v3 a, clvr_v3 b) { return dot(a, b); }
#else
typedef struct clvr_v3 {
    float x, y, z;
} clvr_v3;
CLVR_INLINE clvr_v3 clvr_v3_make(float x, float y, float z) { return (clvr_v3){x, y, z}; }
CLVR_INLINE clvr_v3 clvr_v3_sub(clvr_v3 a, clvr_v3 b) { return (clvr_v3){a.x - b.x, a.y - b.y, a.z - b.z}; }
CLVR_INLINE clvr_v3 clvr_v3_lerp(clvr_v3 a, clvr_v3 b, float u)
{
    return (clvr_v3){a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z)};
}
CLVR_INLINE clvr_v3 clvr_v3_cross(clvr_v3 a, clvr_v3 b)
{
    return (clvr_v3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
CLVR_INLINE float clvr_v3_dot(clvr_v3 a, clvr_v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
#endif

CLVR_INLINE clvr_v3 clvr_v3_of(clvr_vec4 p) { return clvr_v3_make(p.x, p.y, p.z); }

/* The hit of the ray t d (from the origin the corners are relative to)
 * with the bilinear patch p00 p10 (p01 = p00 + e00, p11 = p10 + e11) at its
 * root u, if any: *t and *v. */
CLVR_FORCE_INLINE int clvr_cell_ray_patch_at(clvr_v3 d, clvr_v3 p00, clvr_v3 p10, clvr_v3 e00, clvr_v3 e11, float u,
                                             float *t, float *v)
{
    if (!(u >= -CLVR_CELL_RAY_EPS && u <= 1.0f + CLVR_CELL_RAY_EPS)) return 0;
    const clvr_v3 pa = clvr_v3_lerp(p00, p10, u); /* the point on edge q00 q10 */
    const clvr_v3 pb = clvr_v3_lerp(e00, e11, u); /* from it to the point on edge q01 q11 */
    /* t d = pa + v pb: crossed with pb and with d. */
    const clvr_v3 n = clvr_v3_cross(d, pb);
    const float den = clvr_v3_dot(n, n);
    if (!(den > 0.0f)) return 0;
    const clvr_v3 n2 = clvr_v3_cross(n, pa);
    const float vv = clvr_v3_dot(n2, d);
    if (!(vv >= -CLVR_CELL_RAY_EPS * den && vv <= (1.0f + CLVR_CELL_RAY_EPS) * den)) return 0;
    *t = clvr_v3_dot(n2, pb) / den;
    *v = vv / den;
    return 1;
}

/* Ray (from o, direction d) against the patch q00 q10 q11 q01: every hit
 * with t in (t_lo, *t_best) lowers *t_best and sets *s_best (the corners'
 * w, bilinear at the hit). Returns 1 when one did. */
CLVR_FORCE_INLINE int clvr_cell_ray_patch(clvr_v3 o, clvr_v3 d, clvr_vec4 q00, clvr_vec4 q10, clvr_vec4 q11,
                                          clvr_vec4 q01, float t_lo, float *t_best, float *s_best)
{
    const clvr_v3 c00 = clvr_v3_of(q00), c10 = clvr_v3_of(q10), c11 = clvr_v3_of(q11), c01 = clvr_v3_of(q01);
    const clvr_v3 p00 = clvr_v3_sub(c00, o), p10 = clvr_v3_sub(c10, o);
    const clvr_v3 e00 = clvr_v3_sub(c01, c00), e11 = clvr_v3_sub(c11, c10);
    const clvr_v3 qn = clvr_v3_cross(clvr_v3_sub(c10, c00), clvr_v3_sub(c01, c11));
    /* a + b u + c u^2 = 0: the ray meets the segment of the patch at u. */
    const float a = clvr_v3_dot(clvr_v3_cross(p00, d), e00), c = clvr_v3_dot(qn, d);
    const float b = clvr_v3_dot(clvr_v3_cross(p10, d), e11) - (a + c);
    float u1, u2;
    if (fabs(c) <= 1e-7f * (fabs(a) + fabs(b))) { /* a planar patch (or nearly): one root */
        if (!(b != 0.0f)) return 0;
        u1 = -a / b;
        u2 = -1.0f;
    } else {
        const float disc = b * b - 4.0f * a * c;
        if (!(disc >= 0.0f)) return 0;
        const float q = -0.5f * (b + copysign(sqrt(disc), b)); /* no cancellation */
        u1 = q / c;
        u2 = q != 0.0f ? a / q : -1.0f;
    }
    int hit = 0;
    for (int r = 0; r < 2; ++r) {
        const float u = r ? u2 : u1;
        float t, v;
        if (!clvr_cell_ray_patch_at(d, p00, p10, e00, e11, u, &t, &v) || !(t > t_lo && t < *t_best)) continue;
        const float uc = fmin(fmax(u, 0.0f), 1.0f), vc = fmin(fmax(v, 0.0f), 1.0f);
        const float sa = q00.w + uc * (q10.w - q00.w), sb = q01.w + uc * (q11.w - q01.w);
        *t_best = t;
        *s_best = sa + vc * (sb - sa);
        hit = 1;
    }
    return hit;
}

/* Ray (from o, direction d) against triangle a b c, as clvr_cell_ray_patch. */
CLVR_FORCE_INLINE int clvr_cell_ray_tri(clvr_v3 o, clvr_v3 d, clvr_vec4 a, clvr_vec4 b, clvr_vec4 c, float t_lo,
                                        float *t_best, float *s_best)
{
    const clvr_v3 pa = clvr_v3_of(a);
    const clvr_v3 e1 = clvr_v3_sub(clvr_v3_of(b), pa), e2 = clvr_v3_sub(clvr_v3_of(c), pa), tv = clvr_v3_sub(o, pa);
    const clvr_v3 p = clvr_v3_cross(d, e2);
    const float det = clvr_v3_dot(e1, p);
    if (!(fabs(det) > 0.0f)) return 0;
    const float inv = 1.0f / det;
    const float u = clvr_v3_dot(tv, p) * inv;
    const clvr_v3 q = clvr_v3_cross(tv, e1);
    const float v = clvr_v3_dot(d, q) * inv;
    const float lo = -CLVR_CELL_RAY_EPS, hi = 1.0f + CLVR_CELL_RAY_EPS;
    if (!(u >= lo && v >= lo && u + v <= hi)) return 0;
    const float t = clvr_v3_dot(e2, q) * inv;
    if (!(t > t_lo && t < *t_best)) return 0;
    const float uc = fmin(fmax(u, 0.0f), 1.0f), vc = fmin(fmax(v, 0.0f), 1.0f - uc);
    *t_best = t;
    *s_best = a.w + uc * (b.w - a.w) + vc * (c.w - a.w);
    return 1;
}

/* The ray org + t dir, inside cell vtx (of the type: not a tet) just after
 * t_in: the face it leaves by (clvr_hull_face_code order), with *t_out
 * and the scalar there, *s_out. skip: the face it came in by (not tested),
 * or -1. Hits up to a hair before t_in count as leaving at t_in (a ray
 * through an edge of the cell). -1 when no face is hit: a ray along a face
 * or through an edge, in float; the caller looks further on. */
CLVR_INLINE int clvr_cell_exit(clvr_u32 type, const clvr_vec4 *vtx, const float *org, const float *dir, float t_in,
                               int skip, float *t_out, float *s_out)
{
    /* From the ray's point at t_in: the hits' t are then small numbers
     * with their own precision, and the slack below is relative to the
     * cell's size along the ray. */
    const clvr_v3 o = clvr_v3_make(org[0] + dir[0] * t_in, org[1] + dir[1] * t_in, org[2] + dir[2] * t_in);
    const clvr_v3 d = clvr_v3_make(dir[0], dir[1], dir[2]);
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    float ext = 0.0f;
    for (clvr_u32 i = 1; i < nv; ++i)
        ext = fmax(ext, fabs(vtx[i].x - vtx[0].x) + fabs(vtx[i].y - vtx[0].y) + fabs(vtx[i].z - vtx[0].z));
    const float dl = fabs(dir[0]) + fabs(dir[1]) + fabs(dir[2]);
    const float t_lo = dl > 0.0f ? -1e-5f * ext / dl : 0.0f;
    const clvr_u32 nf = clvr_hull_face_count(type);
    float tb = INFINITY, sb = 0.0f;
    int face = -1;
    for (clvr_u32 f = 0; f < nf; ++f) {
        if ((int)f == skip) continue;
        const clvr_u32 code = clvr_hull_face_code(type, f);
        const clvr_vec4 c0 = vtx[code & 0xFu], c1 = vtx[(code >> 4) & 0xFu], c2 = vtx[(code >> 8) & 0xFu];
        const int hit = (code >> 12) == 0xFu ? clvr_cell_ray_tri(o, d, c0, c1, c2, t_lo, &tb, &sb)
                                             : clvr_cell_ray_patch(o, d, c0, c1, c2, vtx[code >> 12], t_lo, &tb, &sb);
        if (hit) face = (int)f;
    }
    if (face < 0) return -1;
    *t_out = t_in + fmax(tb, 0.0f);
    *s_out = sb;
    return face;
}

#endif
