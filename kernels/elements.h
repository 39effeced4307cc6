/* elements.h: point containment and scalar interpolation for the four
 * element types (VTK vertex order), compiled for the host (tests, reference)
 * and for OpenCL kernels: the same code on both sides.
 *
 * Tetrahedra use barycentric coordinates (one 3x3 solve). Pyramids, wedges
 * and hexahedra invert their isoparametric map (bilinear-in-the-base times
 * linear in height for pyramids and wedges, trilinear for hexahedra) with
 * Newton's method, as VTK's EvaluatePosition and Open VKL's non-planar
 * element path do: start at the parametric centre, at most
 * CLVR_NEWTON_MAX_ITER steps, stop when the step or the residual is tiny,
 * give up on divergence or a singular Jacobian. Faces that are not planar
 * are handled exactly: two elements sharing a quad face both see it as the
 * same bilinear patch, so the parametric test agrees between neighbours.
 *
 * Everything runs in coordinates relative to vertex 0 so that meshes far
 * from the origin keep their float precision. NaN anywhere (degenerate or
 * inverted elements, NaN points) makes the point "outside": every
 * comparison is written so that NaN fails it. */
#ifndef CLVR_ELEMENTS_H
#define CLVR_ELEMENTS_H

#include "clvr_shared.h"

#ifndef __OPENCL_VERSION__
#include <math.h>
#endif

/* Newton: iteration bound and convergence threshold on the parametric step
 * (VTK uses 10 and 1e-5); residual threshold relative to the element size.
 * A step below CLVR_NEWTON_STEP_TOL ends the solve at the point it reaches:
 * Newton converges quadratically, so the error left is about the step
 * squared times the map's curvature over its Jacobian (near 1e-8 for a
 * step of 1e-4 in a reasonably shaped cell, under the parametric
 * coordinates' float resolution), and the shape functions are evaluated
 * once more there for the interpolation. The bound was 1e-6 with no
 * re-evaluation, which spent one more full iteration (shape functions,
 * Jacobian, residual) to confirm nearly every solve that starts near its
 * answer, as a ray's next point in the same cell does
 * (clvr_element_sample_near): 256^2 urm frames, notch_stress's hexes 24.6
 * -> 21.5 ms. test_elements checks the coordinates against the exact ones
 * within 1e-5 from near and far starts, on cells distorted by a quarter of
 * their edge. */
#define CLVR_NEWTON_MAX_ITER 16
#define CLVR_NEWTON_STEP_TOL 1e-4f
#define CLVR_NEWTON_RESIDUAL_REL 1e-7f
/* Parametric coordinates beyond this mean Newton diverged. */
#define CLVR_NEWTON_DIVERGED 1e6f

/* ---------------------------------------------------------------- per type
 * Each element type has the same three functions, and a new type adds its
 * own three (and one line in CLVR_CELL_TYPES):
 *   clvr_<name>_shape(u, v, w, N, Nu, Nv, Nw): shape functions N[i] at
 *       parametric (u, v, w) and their derivatives, for its own vertex
 *       slots only (the dispatcher zeroes the rest);
 *   clvr_<name>_inside(u, v, w, eps): 1 when (u, v, w) lies in its
 *       parametric domain grown by eps;
 *   clvr_<name>_invert(vtx, px, py, pz, &u, &v, &w): parametric coordinates
 *       of world point p (see clvr_element_invert); types whose map is not
 *       linear call clvr_newton_invert from a start point of their own.
 * The tet also has a faster containment test (clvr_tet_sample) that
 * clvr_element_sample and point location use.
 * Parametric domains: tet u, v, w >= 0, u + v + w <= 1; pyramid u, v, w in
 * [0, 1] (apex at w = 1); wedge u, v >= 0, u + v <= 1, w in [0, 1]; hex
 * [0, 1]^3. */

/* The shape dispatcher (below, with the others): Newton calls it. */
CLVR_FORCE_INLINE void clvr_element_shape(clvr_u32 type, float u, float v, float w, float *N, float *Nu, float *Nv,
                                          float *Nw);

/* Solves [a b c] x = r by Cramer's rule; returns 0 when the determinant is
 * zero, tiny relative to the columns, or not finite. */
CLVR_FORCE_INLINE int clvr_solve3(float ax, float ay, float az, float bx, float by, float bz, float cx, float cy,
                                  float cz, float rx, float ry, float rz, float *x0, float *x1, float *x2)
{
    /* cofactors of the columns: b x c, c x a, a x b */
    const float bcx = by * cz - bz * cy, bcy = bz * cx - bx * cz, bcz = bx * cy - by * cx;
    const float cax = cy * az - cz * ay, cay = cz * ax - cx * az, caz = cx * ay - cy * ax;
    const float abx = ay * bz - az * by, aby = az * bx - ax * bz, abz = ax * by - ay * bx;
    const float det = ax * bcx + ay * bcy + az * bcz;
    const float la = fabs(ax) + fabs(ay) + fabs(az), lb = fabs(bx) + fabs(by) + fabs(bz);
    const float lc = fabs(cx) + fabs(cy) + fabs(cz);
    /* NaN-safe: !(x > y) is true for NaN. */
    if (!(fabs(det) > 1e-12f * la * lb * lc) || !(fabs(det) < INFINITY)) return 0;
    const float inv = 1.0f / det;
    *x0 = (rx * bcx + ry * bcy + rz * bcz) * inv;
    *x1 = (rx * cax + ry * cay + rz * caz) * inv;
    *x2 = (rx * abx + ry * aby + rz * abz) * inv;
    return 1;
}

/* Newton's method on the isoparametric map of an element of `type` (any
 * type whose clvr_<name>_shape is set up), from (u, v, w), in coordinates
 * relative to vertex 0; see clvr_element_invert for the result. N
 * (CLVR_CELL_MAX_VERTS floats) is left holding the shape functions at the
 * coordinates returned, so that interpolation needs no other evaluation
 * (clvr_element_sample_near). */
CLVR_FORCE_INLINE int clvr_hex_newton(const clvr_vec4 *vtx, float px, float py, float pz, float u, float v, float w,
                                      float *pu, float *pv, float *pw, float *N);
CLVR_FORCE_INLINE int clvr_newton_solve(clvr_u32 type, const clvr_vec4 *vtx, float px, float py, float pz, float u,
                                        float v, float w, float *pu, float *pv, float *pw, float *N)
{
    if (type == CLVR_CELL_HEX) return clvr_hex_newton(vtx, px, py, pz, u, v, w, pu, pv, pw, N);
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    /* Relative to vertex 0, for precision far from the origin. */
    const float ox = vtx[0].x, oy = vtx[0].y, oz = vtx[0].z;
    px -= ox; py -= oy; pz -= oz;
    float size = 0.0f;
    for (clvr_u32 i = 1; i < nv; ++i)
        size = fmax(size, fabs(vtx[i].x - ox) + fabs(vtx[i].y - oy) + fabs(vtx[i].z - oz));
    const float res_tol = CLVR_NEWTON_RESIDUAL_REL * size;
    float Nu[CLVR_CELL_MAX_VERTS], Nv[CLVR_CELL_MAX_VERTS], Nw[CLVR_CELL_MAX_VERTS];
    for (int it = 0; it < CLVR_NEWTON_MAX_ITER; ++it) {
        clvr_element_shape(type, u, v, w, N, Nu, Nv, Nw);
        float fx = -px, fy = -py, fz = -pz;
        float jux = 0.0f, juy = 0.0f, juz = 0.0f, jvx = 0.0f, jvy = 0.0f, jvz = 0.0f;
        float jwx = 0.0f, jwy = 0.0f, jwz = 0.0f;
        for (clvr_u32 i = 1; i < nv; ++i) { /* vertex 0 is the origin: contributes nothing */
            const float x = vtx[i].x - ox, y = vtx[i].y - oy, z = vtx[i].z - oz;
            fx += N[i] * x; fy += N[i] * y; fz += N[i] * z;
            jux += Nu[i] * x; juy += Nu[i] * y; juz += Nu[i] * z;
            jvx += Nv[i] * x; jvy += Nv[i] * y; jvz += Nv[i] * z;
            jwx += Nw[i] * x; jwy += Nw[i] * y; jwz += Nw[i] * z;
        }
        /* Residual already at float noise (also what ends the pyramid apex,
         * where the Jacobian is singular). */
        if (fabs(fx) <= res_tol && fabs(fy) <= res_tol && fabs(fz) <= res_tol) {
            *pu = u; *pv = v; *pw = w;
            return 1;
        }
        float du, dv, dw;
        if (!clvr_solve3(jux, juy, juz, jvx, jvy, jvz, jwx, jwy, jwz, fx, fy, fz, &du, &dv, &dw)) return 0;
        u -= du; v -= dv; w -= dw;
        if (!(fabs(u) < CLVR_NEWTON_DIVERGED && fabs(v) < CLVR_NEWTON_DIVERGED && fabs(w) < CLVR_NEWTON_DIVERGED))
            return 0;
        if (fabs(du) < CLVR_NEWTON_STEP_TOL && fabs(dv) < CLVR_NEWTON_STEP_TOL && fabs(dw) < CLVR_NEWTON_STEP_TOL) {
            clvr_element_shape(type, u, v, w, N, Nu, Nv, Nw); /* N where the solve ends */
            *pu = u; *pv = v; *pw = w;
            return 1;
        }
    }
    return 0;
}

/* clvr_newton_solve without the shape functions. */
CLVR_INLINE int clvr_newton_invert(clvr_u32 type, const clvr_vec4 *vtx, float px, float py, float pz, float u,
                                   float v, float w, float *pu, float *pv, float *pw)
{
    float N[CLVR_CELL_MAX_VERTS];
    return clvr_newton_solve(type, vtx, px, py, pz, u, v, w, pu, pv, pw, N);
}

/* ------------------------------------------------ tetrahedron (VTK_TETRA) */

CLVR_INLINE void clvr_tet_shape(float u, float v, float w, float *N, float *Nu, float *Nv, float *Nw)
{
    N[0] = 1.0f - u - v - w; N[1] = u; N[2] = v; N[3] = w;
    Nu[0] = -1.0f; Nu[1] = 1.0f;
    Nv[0] = -1.0f; Nv[2] = 1.0f;
    Nw[0] = -1.0f; Nw[3] = 1.0f;
}

CLVR_INLINE int clvr_tet_inside(float u, float v, float w, float eps)
{
    const float lo = -eps, hi = 1.0f + eps;
    return u >= lo && v >= lo && w >= lo && u + v + w <= hi;
}

/* The map is linear: one 3x3 solve, no iteration. */
CLVR_INLINE int clvr_tet_invert(const clvr_vec4 *vtx, float px, float py, float pz, float *pu, float *pv, float *pw)
{
    const float ox = vtx[0].x, oy = vtx[0].y, oz = vtx[0].z;
    px -= ox; py -= oy; pz -= oz;
    return clvr_solve3(vtx[1].x - ox, vtx[1].y - oy, vtx[1].z - oz, vtx[2].x - ox, vtx[2].y - oy, vtx[2].z - oz,
                       vtx[3].x - ox, vtx[3].y - oy, vtx[3].z - oz, px, py, pz, pu, pv, pw);
}

/* Tet containment and interpolation: the same arithmetic as
 * clvr_tet_invert + clvr_tet_inside + the shape-function sum (bit for bit:
 * clvr_solve3's formulas, in its order), but each barycentric is computed
 * only when the previous ones passed, so the many tets a point is not in
 * (point location tests several per query) cost about a third of the full
 * solve. Forced inline: PoCL kept it a call, with the four vertices
 * stored to the stack for it (interleaved medians of 3, 2-core AMD EPYC:
 * bench_locate random points +2-4%, urm frames 1-3% shorter; bit-identical
 * images). */
CLVR_FORCE_INLINE int clvr_tet_sample(const clvr_vec4 *vtx, float px, float py, float pz, float *scalar)
{
    const float ox = vtx[0].x, oy = vtx[0].y, oz = vtx[0].z;
    const float rx = px - ox, ry = py - oy, rz = pz - oz;
    const float ax = vtx[1].x - ox, ay = vtx[1].y - oy, az = vtx[1].z - oz;
    const float bx = vtx[2].x - ox, by = vtx[2].y - oy, bz = vtx[2].z - oz;
    const float cx = vtx[3].x - ox, cy = vtx[3].y - oy, cz = vtx[3].z - oz;
    const float bcx = by * cz - bz * cy, bcy = bz * cx - bx * cz, bcz = bx * cy - by * cx;
    const float det = ax * bcx + ay * bcy + az * bcz;
    const float la = fabs(ax) + fabs(ay) + fabs(az), lb = fabs(bx) + fabs(by) + fabs(bz);
    const float lc = fabs(cx) + fabs(cy) + fabs(cz);
    if (!(fabs(det) > 1e-12f * la * lb * lc) || !(fabs(det) < INFINITY)) return 0;
    const float inv = 1.0f / det, lo = -CLVR_ELEMENT_EPS;
    const float u = (rx * bcx + ry * bcy + rz * bcz) * inv;
    if (!(u >= lo)) return 0;
    const float cax = cy * az - cz * ay, cay = cz * ax - cx * az, caz = cx * ay - cy * ax;
    const float v = (rx * cax + ry * cay + rz * caz) * inv;
    if (!(v >= lo)) return 0;
    const float abx = ay * bz - az * by, aby = az * bx - ax * bz, abz = ax * by - ay * bx;
    const float w = (rx * abx + ry * aby + rz * abz) * inv;
    if (!(w >= lo && u + v + w <= 1.0f + CLVR_ELEMENT_EPS)) return 0;
    float s = 0.0f;
    s += (1.0f - u - v - w) * vtx[0].w;
    s += u * vtx[1].w;
    s += v * vtx[2].w;
    s += w * vtx[3].w;
    *scalar = s;
    return 1;
}

#if defined(__OPENCL_VERSION__) && defined(CLVR_DEVICE_SIMD)
/* clvr_tet_sample on four tets at once (v: tet j's vertex i at v[4j + i]),
 * one float4 lane per tet and no early outs: bit j of the result is set
 * when tet j holds the point, with its scalar in lane j of *scalar. The
 * same expressions as clvr_tet_sample, lane by lane. Only where a
 * work-item's float4 arithmetic runs on SIMD lanes (CLVR_DEVICE_SIMD: a CPU
 * device); a GPU would do four tets' work per thread. */
CLVR_FORCE_INLINE clvr_u32 clvr_tet_sample4(const clvr_vec4 *v, float px, float py, float pz, float4 *scalar)
{
    const float4 ox = (float4)(v[0].x, v[4].x, v[8].x, v[12].x), oy = (float4)(v[0].y, v[4].y, v[8].y, v[12].y),
                 oz = (float4)(v[0].z, v[4].z, v[8].z, v[12].z);
    const float4 ax = (float4)(v[1].x, v[5].x, v[9].x, v[13].x) - ox, ay = (float4)(v[1].y, v[5].y, v[9].y, v[13].y) - oy,
                 az = (float4)(v[1].z, v[5].z, v[9].z, v[13].z) - oz;
    const float4 bx = (float4)(v[2].x, v[6].x, v[10].x, v[14].x) - ox, by = (float4)(v[2].y, v[6].y, v[10].y, v[14].y) - oy,
                 bz = (float4)(v[2].z, v[6].z, v[10].z, v[14].z) - oz;
    const float4 cx = (float4)(v[3].x, v[7].x, v[11].x, v[15].x) - ox, cy = (float4)(v[3].y, v[7].y, v[11].y, v[15].y) - oy,
                 cz = (float4)(v[3].z, v[7].z, v[11].z, v[15].z) - oz;
    const float4 rx = px - ox, ry = py - oy, rz = pz - oz;
    const float4 bcx = by * cz - bz * cy, bcy = bz * cx - bx * cz, bcz = bx * cy - by * cx;
    const float4 det = ax * bcx + ay * bcy + az * bcz;
    const float4 la = fabs(ax) + fabs(ay) + fabs(az), lb = fabs(bx) + fabs(by) + fabs(bz);
    const float4 lc = fabs(cx) + fabs(cy) + fabs(cz);
    const float4 inv = 1.0f / det;
    const float4 u = (rx * bcx + ry * bcy + rz * bcz) * inv;
    const float4 cax = cy * az - cz * ay, cay = cz * ax - cx * az, caz = cx * ay - cy * ax;
    const float4 vv = (rx * cax + ry * cay + rz * caz) * inv;
    const float4 abx = ay * bz - az * by, aby = az * bx - ax * bz, abz = ax * by - ay * bx;
    const float4 w = (rx * abx + ry * aby + rz * abz) * inv;
    const float lo = -CLVR_ELEMENT_EPS;
    const int4 in = (fabs(det) > 1e-12f * la * lb * lc) & (fabs(det) < INFINITY) & (u >= lo) & (vv >= lo) &
                    (w >= lo) & (u + vv + w <= 1.0f + CLVR_ELEMENT_EPS);
    const float4 w0 = (float4)(v[0].w, v[4].w, v[8].w, v[12].w), w1 = (float4)(v[1].w, v[5].w, v[9].w, v[13].w),
                 w2 = (float4)(v[2].w, v[6].w, v[10].w, v[14].w), w3 = (float4)(v[3].w, v[7].w, v[11].w, v[15].w);
    float4 s = 0.0f;
    s += (1.0f - u - vv - w) * w0;
    s += u * w1;
    s += vv * w2;
    s += w * w3;
    *scalar = s;
    return (clvr_u32)((in.x & 1) | (in.y & 2) | (in.z & 4) | (in.w & 8));
}
#endif

/* ------------------------------------------------ pyramid (VTK_PYRAMID) */

/* base 0 (0,0) 1 (1,0) 2 (1,1) 3 (0,1) scaled by (1 - w), apex 4 */
CLVR_INLINE void clvr_pyramid_shape(float u, float v, float w, float *N, float *Nu, float *Nv, float *Nw)
{
    const float iu = 1.0f - u, iv = 1.0f - v, iw = 1.0f - w;
    N[0] = iu * iv * iw; N[1] = u * iv * iw; N[2] = u * v * iw; N[3] = iu * v * iw; N[4] = w;
    Nu[0] = -iv * iw; Nu[1] = iv * iw; Nu[2] = v * iw; Nu[3] = -v * iw;
    Nv[0] = -iu * iw; Nv[1] = -u * iw; Nv[2] = u * iw; Nv[3] = iu * iw;
    Nw[0] = -iu * iv; Nw[1] = -u * iv; Nw[2] = -u * v; Nw[3] = -iu * v; Nw[4] = 1.0f;
}

CLVR_INLINE int clvr_pyramid_inside(float u, float v, float w, float eps)
{
    /* In the collapsed coordinates a = u (1 - w), b = v (1 - w) the domain
     * is the pyramid itself; u and v lose their meaning at the apex (their
     * error grows like 1 / (1 - w)), a and b do not. */
    const float lo = -eps, hi = 1.0f + eps;
    const float iw = 1.0f - w, a = u * iw, b = v * iw;
    return w >= lo && w <= hi && a >= lo && a <= iw + eps && b >= lo && b <= iw + eps;
}

/* Newton from below the singular apex. Each type's start is a macro that
 * clvr_element_sample_near uses too. */
#define CLVR_PYRAMID_START 0.5f, 0.5f, 0.25f
CLVR_INLINE int clvr_pyramid_invert(const clvr_vec4 *vtx, float px, float py, float pz, float *pu, float *pv,
                                    float *pw)
{
    return clvr_newton_invert(CLVR_CELL_PYRAMID, vtx, px, py, pz, CLVR_PYRAMID_START, pu, pv, pw);
}

/* ------------------------------------------------ wedge (VTK_WEDGE) */

/* triangle 0 1 2 at w = 0, triangle 3 4 5 above it at w = 1 */
CLVR_INLINE void clvr_wedge_shape(float u, float v, float w, float *N, float *Nu, float *Nv, float *Nw)
{
    const float iw = 1.0f - w, t = 1.0f - u - v;
    N[0] = t * iw; N[1] = u * iw; N[2] = v * iw; N[3] = t * w; N[4] = u * w; N[5] = v * w;
    Nu[0] = -iw; Nu[1] = iw; Nu[3] = -w; Nu[4] = w;
    Nv[0] = -iw; Nv[2] = iw; Nv[3] = -w; Nv[5] = w;
    Nw[0] = -t; Nw[1] = -u; Nw[2] = -v; Nw[3] = t; Nw[4] = u; Nw[5] = v;
}

CLVR_INLINE int clvr_wedge_inside(float u, float v, float w, float eps)
{
    const float lo = -eps, hi = 1.0f + eps;
    return u >= lo && v >= lo && u + v <= hi && w >= lo && w <= hi;
}

/* Newton from the parametric centre. */
#define CLVR_WEDGE_START 1.0f / 3.0f, 1.0f / 3.0f, 0.5f
CLVR_INLINE int clvr_wedge_invert(const clvr_vec4 *vtx, float px, float py, float pz, float *pu, float *pv, float *pw)
{
    return clvr_newton_invert(CLVR_CELL_WEDGE, vtx, px, py, pz, CLVR_WEDGE_START, pu, pv, pw);
}

/* ------------------------------------------------ hexahedron (VTK_HEXAHEDRON) */

/* 0 (0,0,0) 1 (1,0,0) 2 (1,1,0) 3 (0,1,0), 4..7 the same at w = 1 */
CLVR_INLINE void clvr_hex_shape(float u, float v, float w, float *N, float *Nu, float *Nv, float *Nw)
{
    const float iu = 1.0f - u, iv = 1.0f - v, iw = 1.0f - w;
    N[0] = iu * iv * iw; N[1] = u * iv * iw; N[2] = u * v * iw; N[3] = iu * v * iw;
    N[4] = iu * iv * w;  N[5] = u * iv * w;  N[6] = u * v * w;  N[7] = iu * v * w;
    Nu[0] = -iv * iw; Nu[1] = iv * iw; Nu[2] = v * iw; Nu[3] = -v * iw;
    Nu[4] = -iv * w;  Nu[5] = iv * w;  Nu[6] = v * w;  Nu[7] = -v * w;
    Nv[0] = -iu * iw; Nv[1] = -u * iw; Nv[2] = u * iw; Nv[3] = iu * iw;
    Nv[4] = -iu * w;  Nv[5] = -u * w;  Nv[6] = u * w;  Nv[7] = iu * w;
    Nw[0] = -iu * iv; Nw[1] = -u * iv; Nw[2] = -u * v; Nw[3] = -iu * v;
    Nw[4] = iu * iv;  Nw[5] = u * iv;  Nw[6] = u * v;  Nw[7] = iu * v;
}

CLVR_INLINE int clvr_hex_inside(float u, float v, float w, float eps)
{
    const float lo = -eps, hi = 1.0f + eps;
    return u >= lo && u <= hi && v >= lo && v <= hi && w >= lo && w <= hi;
}

/* clvr_newton_solve for a hex, the same steps and stopping rules, with the
 * trilinear map in monomial form, x(u,v,w) = c1 u + c2 v + c3 w + c4 uv +
 * c5 vw + c6 uw + c7 uvw (relative to vertex 0): its value and Jacobian
 * take about 50 flops a step instead of the 8 shape functions, their 24
 * derivatives and 84 products with the vertices. */
CLVR_FORCE_INLINE int clvr_hex_newton(const clvr_vec4 *vtx, float px, float py, float pz, float u, float v, float w,
                                      float *pu, float *pv, float *pw, float *N)
{
    const float ox = vtx[0].x, oy = vtx[0].y, oz = vtx[0].z;
    px -= ox; py -= oy; pz -= oz;
    float size = 0.0f;
    for (int i = 1; i < 8; ++i) size = fmax(size, fabs(vtx[i].x - ox) + fabs(vtx[i].y - oy) + fabs(vtx[i].z - oz));
    const float res_tol = CLVR_NEWTON_RESIDUAL_REL * size;
    float x[8][3];
    for (int i = 0; i < 8; ++i) {
        x[i][0] = vtx[i].x - ox; x[i][1] = vtx[i].y - oy; x[i][2] = vtx[i].z - oz;
    }
    float c1[3], c2[3], c3[3], c4[3], c5[3], c6[3], c7[3];
    for (int k = 0; k < 3; ++k) { /* x[0][k] is 0 */
        c1[k] = x[1][k];
        c2[k] = x[3][k];
        c3[k] = x[4][k];
        c4[k] = x[2][k] - x[1][k] - x[3][k];
        c5[k] = x[7][k] - x[3][k] - x[4][k];
        c6[k] = x[5][k] - x[1][k] - x[4][k];
        c7[k] = x[1][k] - x[2][k] + x[3][k] + x[4][k] - x[5][k] + x[6][k] - x[7][k];
    }
    for (int it = 0; it < CLVR_NEWTON_MAX_ITER; ++it) {
        const float uv = u * v, vw = v * w, uw = u * w, uvw = uv * w;
        float f[3], ju[3], jv[3], jw[3];
        const float p[3] = {px, py, pz};
        for (int k = 0; k < 3; ++k) {
            f[k] = c1[k] * u + c2[k] * v + c3[k] * w + c4[k] * uv + c5[k] * vw + c6[k] * uw + c7[k] * uvw - p[k];
            ju[k] = c1[k] + c4[k] * v + c6[k] * w + c7[k] * vw;
            jv[k] = c2[k] + c4[k] * u + c5[k] * w + c7[k] * uw;
            jw[k] = c3[k] + c5[k] * v + c6[k] * u + c7[k] * uv;
        }
        if (fabs(f[0]) <= res_tol && fabs(f[1]) <= res_tol && fabs(f[2]) <= res_tol) {
            float Nu[8], Nv[8], Nw[8];
            clvr_hex_shape(u, v, w, N, Nu, Nv, Nw);
            *pu = u; *pv = v; *pw = w;
            return 1;
        }
        float du, dv, dw;
        if (!clvr_solve3(ju[0], ju[1], ju[2], jv[0], jv[1], jv[2], jw[0], jw[1], jw[2], f[0], f[1], f[2], &du, &dv,
                         &dw))
            return 0;
        u -= du; v -= dv; w -= dw;
        if (!(fabs(u) < CLVR_NEWTON_DIVERGED && fabs(v) < CLVR_NEWTON_DIVERGED && fabs(w) < CLVR_NEWTON_DIVERGED))
            return 0;
        if (fabs(du) < CLVR_NEWTON_STEP_TOL && fabs(dv) < CLVR_NEWTON_STEP_TOL && fabs(dw) < CLVR_NEWTON_STEP_TOL) {
            float Nu[8], Nv[8], Nw[8];
            clvr_hex_shape(u, v, w, N, Nu, Nv, Nw); /* N where the solve ends */
            *pu = u; *pv = v; *pw = w;
            return 1;
        }
    }
    return 0;
}

/* Newton from the parametric centre. */
#define CLVR_HEX_START 0.5f, 0.5f, 0.5f
CLVR_INLINE int clvr_hex_invert(const clvr_vec4 *vtx, float px, float py, float pz, float *pu, float *pv, float *pw)
{
    return clvr_newton_invert(CLVR_CELL_HEX, vtx, px, py, pz, CLVR_HEX_START, pu, pv, pw);
}

/* ---------------------------------------------------------------- dispatch
 * One switch per operation, generated from CLVR_CELL_TYPES (Open VKL's
 * shape: per-type functions, one dispatcher). The type is uniform over an
 * instance cluster, so the branch is taken the same way by a leaf's
 * elements. */

/* Shape functions N[i] of the element type at parametric (u, v, w) and
 * their derivatives (domains above). Slots past the vertex count are
 * zero. */
CLVR_FORCE_INLINE void clvr_element_shape(clvr_u32 type, float u, float v, float w, float *N, float *Nu, float *Nv,
                                          float *Nw)
{
    for (clvr_u32 i = 0; i < CLVR_CELL_MAX_VERTS; ++i) { N[i] = 0.0f; Nu[i] = 0.0f; Nv[i] = 0.0f; Nw[i] = 0.0f; }
    switch (type) {
#define CLVR_ELEMENT_CASE_(id, name, nv) \
    case id: clvr_##name##_shape(u, v, w, N, Nu, Nv, Nw); break;
        CLVR_CELL_TYPES(CLVR_ELEMENT_CASE_)
#undef CLVR_ELEMENT_CASE_
    default: break;
    }
}

/* 1 when (u, v, w) lies in the type's parametric domain grown by eps (0
 * for an unknown type). */
CLVR_INLINE int clvr_element_param_inside(clvr_u32 type, float u, float v, float w, float eps)
{
    switch (type) {
#define CLVR_ELEMENT_CASE_(id, name, nv) \
    case id: return clvr_##name##_inside(u, v, w, eps);
        CLVR_CELL_TYPES(CLVR_ELEMENT_CASE_)
#undef CLVR_ELEMENT_CASE_
    default: return 0;
    }
}

/* Parametric coordinates of world point p in the element (vertices vtx[0..n-1],
 * VTK order). Returns 1 when they were found (Newton converged, or the tet's
 * solve succeeded), 0 on divergence, singular maps, NaN or an unknown type;
 * a 1 says nothing about inside: use clvr_element_param_inside. */
CLVR_INLINE int clvr_element_invert(clvr_u32 type, const clvr_vec4 *vtx, float px, float py, float pz, float *pu,
                                    float *pv, float *pw)
{
    switch (type) {
#define CLVR_ELEMENT_CASE_(id, name, nv) \
    case id: return clvr_##name##_invert(vtx, px, py, pz, pu, pv, pw);
        CLVR_CELL_TYPES(CLVR_ELEMENT_CASE_)
#undef CLVR_ELEMENT_CASE_
    default: return 0;
    }
}

/* Forward map: world position of parametric (u, v, w) (tests build points on
 * faces, edges and inside elements with it). */
CLVR_INLINE void clvr_element_forward(clvr_u32 type, const clvr_vec4 *vtx, float u, float v, float w, float *x,
                                      float *y, float *z)
{
    float N[CLVR_CELL_MAX_VERTS], Nu[CLVR_CELL_MAX_VERTS], Nv[CLVR_CELL_MAX_VERTS], Nw[CLVR_CELL_MAX_VERTS];
    clvr_element_shape(type, u, v, w, N, Nu, Nv, Nw);
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
    for (clvr_u32 i = 0; i < nv; ++i) {
        sx += N[i] * vtx[i].x;
        sy += N[i] * vtx[i].y;
        sz += N[i] * vtx[i].z;
    }
    *x = sx; *y = sy; *z = sz;
}

/* Newton's start in a cell of the type: its clvr_<name>_invert's (a tet's
 * map is linear: any). */
CLVR_INLINE void clvr_element_start(clvr_u32 type, float *u, float *v, float *w)
{
    const float sp[3] = {CLVR_PYRAMID_START}, sw[3] = {CLVR_WEDGE_START}, sh[3] = {CLVR_HEX_START};
    const float *s0 = type == CLVR_CELL_PYRAMID ? sp : type == CLVR_CELL_WEDGE ? sw : sh;
    *u = s0[0];
    *v = s0[1];
    *w = s0[2];
}

/* Containment and interpolation for a type other than tets: Newton started
 * from *u, *v, *w (a point nearby found inside the element) when start is
 * set, from the type's own start otherwise (clvr_element_invert); as
 * clvr_element_sample, and writes the coordinates found. *settled: 1 when
 * the answer does not hang on the start (found inside, or Newton converged
 * to coordinates outside), 0 when Newton gave up (no convergence, a
 * singular Jacobian), where another start might still find the point
 * inside; a caller that tests the element again elsewhere may skip it only
 * when settled. */
CLVR_FORCE_INLINE int clvr_element_sample_near_settled(clvr_u32 type, const clvr_vec4 *vtx, float px, float py,
                                                       float pz, int start, float *u, float *v, float *w,
                                                       float *scalar, int *settled)
{
    float a, b, c, N[CLVR_CELL_MAX_VERTS];
    if (!start) clvr_element_start(type, u, v, w);
    *settled = 0;
    /* Newton's last shape functions interpolate: one evaluation fewer. */
    if (!clvr_newton_solve(type, vtx, px, py, pz, *u, *v, *w, &a, &b, &c, N)) return 0;
    *settled = 1;
    if (!clvr_element_param_inside(type, a, b, c, CLVR_ELEMENT_EPS)) return 0;
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    float s = 0.0f;
    for (clvr_u32 i = 0; i < nv; ++i) s += N[i] * vtx[i].w;
    *scalar = s;
    *u = a; *v = b; *w = c;
    return 1;
}

CLVR_INLINE int clvr_element_sample_near(clvr_u32 type, const clvr_vec4 *vtx, float px, float py, float pz, int start,
                                         float *u, float *v, float *w, float *scalar)
{
    int settled;
    return clvr_element_sample_near_settled(type, vtx, px, py, pz, start, u, v, w, scalar, &settled);
}

/* Quick reject for pyramids, before Newton: 0 when p lies outside one of
 * the four side faces' planes by more than 1e-3 of the element's extent
 * (those faces, a base edge and the apex, are flat triangles). A plane is
 * used only when both base vertices off it lie on the pyramid's side of it:
 * then the whole pyramid does (a point of it is (1 - t) times a bilinear
 * blend of the base vertices plus t times the apex, so its distance to the
 * plane is a non-negative blend of theirs), and a point Newton accepts
 * (CLVR_ELEMENT_EPS, 1e-5, outside the parametric domain) is within about
 * 2e-5 of the extent: the margin is 50 times that. Where a polyhedral cell
 * was split into pyramids around its centre (OpenFOAM's foamToVTK), a
 * point inside it passes about 3 of their boxes, and the shared side faces
 * tell them apart without Newton. */
CLVR_INLINE int clvr_pyramid_sides_hold(const clvr_vec4 *vtx, float px, float py, float pz)
{
    const float ax = vtx[4].x, ay = vtx[4].y, az = vtx[4].z;
    float ext = 0.0f;
    for (int i = 0; i < 4; ++i)
        ext = fmax(ext, fmax(fmax(fabs(vtx[i].x - ax), fabs(vtx[i].y - ay)), fabs(vtx[i].z - az)));
    const float tol = 1e-3f * ext;
    const float qx = px - ax, qy = py - ay, qz = pz - az;
    for (int i = 0; i < 4; ++i) {
        const clvr_vec4 b0 = vtx[i], b1 = vtx[(i + 1) & 3], c0 = vtx[(i + 2) & 3], c1 = vtx[(i + 3) & 3];
        const float ux = b0.x - ax, uy = b0.y - ay, uz = b0.z - az;
        const float vx = b1.x - ax, vy = b1.y - ay, vz = b1.z - az;
        const float nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        const float r0 = (c0.x - ax) * nx + (c0.y - ay) * ny + (c0.z - az) * nz;
        const float r1 = (c1.x - ax) * nx + (c1.y - ay) * ny + (c1.z - az) * nz;
        if (!((r0 > 0.0f && r1 > 0.0f) || (r0 < 0.0f && r1 < 0.0f))) continue; /* warped: no bound */
        const float d = (qx * nx + qy * ny + qz * nz) * (r0 > 0.0f ? 1.0f : -1.0f);
        if (d < 0.0f && d * d > tol * tol * (nx * nx + ny * ny + nz * nz)) return 0;
    }
    return 1;
}

/* The type an 8-node hex with repeated corners collapses to, in the forms
 * FE codes write other types in (Exodus II's and Patran's degenerate
 * HEX8): tet (a b c c d d d d), pyramid (a b c d e e e e), wedge
 * (a b c c d e f f); CLVR_CELL_HEX for any other hex. out: that type's
 * vertices in VTK order (untouched for CLVR_CELL_HEX). Repeated means the
 * same position bit for bit, which a repeated vertex index gives. Newton
 * on a collapsed hex finds the same containment and value as the type's
 * own test (the collapsed trilinear map is a reparametrization of the
 * tet's barycentrics, the pyramid's and the wedge's shape functions:
 * tests/test_elements.c), but costs a solve where a tet takes a
 * barycentric test, and a pyramid loses its side planes. */
CLVR_INLINE clvr_u32 clvr_hex_collapsed(const clvr_vec4 *h, clvr_vec4 *out)
{
#define CLVR_SAME_(i, j) (h[i].x == h[j].x && h[i].y == h[j].y && h[i].z == h[j].z)
    const int top = CLVR_SAME_(4, 5) && CLVR_SAME_(5, 6) && CLVR_SAME_(6, 7), base = CLVR_SAME_(2, 3);
    const int wedge = base && CLVR_SAME_(6, 7) && !top;
#undef CLVR_SAME_
    if (!top && !wedge) return CLVR_CELL_HEX;
    out[0] = h[0];
    out[1] = h[1];
    out[2] = h[2];
    if (top && base) {
        out[3] = h[4];
        return CLVR_CELL_TET;
    }
    if (top) {
        out[3] = h[3];
        out[4] = h[4];
        return CLVR_CELL_PYRAMID;
    }
    out[3] = h[4];
    out[4] = h[5];
    out[5] = h[6];
    return CLVR_CELL_WEDGE;
}

/* Point containment and interpolation: returns 1 when (px, py, pz) lies in
 * the element (within CLVR_ELEMENT_EPS in parametric coordinates) and writes
 * the interpolated scalar (the vertices' w) to *scalar; 0 otherwise (also
 * for degenerate elements and NaN input). vtx holds the element's
 * clvr_cell_vertex_count(type) vertices in VTK order. Tets take their
 * early-out test (clvr_tet_sample); pyramids their side planes
 * (clvr_pyramid_sides_hold), then Newton; wedges and hexes invert their
 * map; a collapsed hex (clvr_hex_collapsed) takes its own type's test. */
CLVR_INLINE int clvr_element_sample(clvr_u32 type, const clvr_vec4 *vtx, float px, float py, float pz, float *scalar)
{
    clvr_vec4 c[6];
    if (type == CLVR_CELL_HEX) { /* a collapsed hex takes its own type's test */
        type = clvr_hex_collapsed(vtx, c);
        if (type != CLVR_CELL_HEX) vtx = c;
    }
    if (type == CLVR_CELL_TET) return clvr_tet_sample(vtx, px, py, pz, scalar);
    if (type == CLVR_CELL_PYRAMID && !clvr_pyramid_sides_hold(vtx, px, py, pz)) return 0;
    float u, v, w;
    return clvr_element_sample_near(type, vtx, px, py, pz, 0, &u, &v, &w, scalar);
}

/* The element's vertex box (lo, hi) and the padding clvr_element_box_test
 * grows it by: CLVR_BVH_BOX_PAD_REL of its largest extent plus a few ulps of
 * its coordinates. */
CLVR_INLINE float clvr_element_vertex_box(clvr_u32 type, const clvr_vec4 *vtx, float *lo, float *hi)
{
#ifdef __OPENCL_VERSION__
    /* No fused multiply-add in the padding: the device's boxes (and the
     * quantized element boxes built from them) keep the host's bits. */
#pragma OPENCL FP_CONTRACT OFF
#endif
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    lo[0] = hi[0] = vtx[0].x;
    lo[1] = hi[1] = vtx[0].y;
    lo[2] = hi[2] = vtx[0].z;
    for (clvr_u32 i = 1; i < nv; ++i) {
        lo[0] = fmin(lo[0], vtx[i].x); lo[1] = fmin(lo[1], vtx[i].y); lo[2] = fmin(lo[2], vtx[i].z);
        hi[0] = fmax(hi[0], vtx[i].x); hi[1] = fmax(hi[1], vtx[i].y); hi[2] = fmax(hi[2], vtx[i].z);
    }
    const float ext = fmax(fmax(hi[0] - lo[0], hi[1] - lo[1]), hi[2] - lo[2]);
    const float mag = fmax(fmax(fmax(fabs(lo[0]), fabs(hi[0])), fmax(fabs(lo[1]), fabs(hi[1]))),
                           fmax(fabs(lo[2]), fabs(hi[2])));
    return CLVR_BVH_BOX_PAD_REL * ext + 4.0f * 1.1920929e-7f * mag;
}

/* Quick reject: 1 when p is inside the element's vertex box padded like the
 * BVH's boxes (clvr_element_vertex_box). */
CLVR_INLINE int clvr_element_box_test(clvr_u32 type, const clvr_vec4 *vtx, float px, float py, float pz)
{
#ifdef __OPENCL_VERSION__
    /* The same test on float3 lanes: a third of the instructions (point
     * location runs it on every candidate element). */
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    float3 lo = vtx[0].xyz, hi = lo;
    for (clvr_u32 i = 1; i < nv; ++i) {
        lo = fmin(lo, vtx[i].xyz);
        hi = fmax(hi, vtx[i].xyz);
    }
    const float3 d = hi - lo, a = fmax(fabs(lo), fabs(hi));
    const float pad4 = CLVR_BVH_BOX_PAD_REL * fmax(fmax(d.x, d.y), d.z) + 4.0f * 1.1920929e-7f * fmax(fmax(a.x, a.y), a.z);
    const float3 p3 = (float3)(px, py, pz);
    const int3 in = (p3 >= lo - pad4) & (p3 <= hi + pad4);
    return in.x & in.y & in.z & 1;
#else
    float lo[3], hi[3];
    const float pad = clvr_element_vertex_box(type, vtx, lo, hi);
    return px >= lo[0] - pad && px <= hi[0] + pad && py >= lo[1] - pad && py <= hi[1] + pad && pz >= lo[2] - pad &&
           pz <= hi[2] + pad;
#endif
}

#endif /* CLVR_ELEMENTS_H */
