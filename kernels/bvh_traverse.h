/* bvh_traverse.h: iterators over the 4-wide packed BVH of clvr_shared.h,
 * compiled for the host and for OpenCL kernels (no recursion, no callbacks,
 * a fixed stack in the iterator). Usage, the same on both sides:
 *
 *   clvr_bvh_point_iter it;
 *   clvr_bvh_point_begin(&it, root, px, py, pz);
 *   clvr_u32 prim;
 *   while (clvr_bvh_point_next(&it, nodes, &prim)) { ... prim's box holds p ... }
 *
 *   clvr_bvh_ray_iter ri;
 *   clvr_bvh_ray_begin(&ri, nodes, ox, oy, oz, dx, dy, dz, tmin, tmax);   (root: node 0)
 *   while (clvr_bvh_ray_next(&ri, nodes, &prim, &t0, &t1)) { ... box hit over [t0, t1] ... }
 *
 * Every primitive whose (padded) box contains the point, or overlaps the ray
 * over [tmin, tmax], is reported exactly once, in no particular order. */
#ifndef CLVR_BVH_TRAVERSE_H
#define CLVR_BVH_TRAVERSE_H

#include "clvr_shared.h"

#ifndef __OPENCL_VERSION__
#include <math.h>
#endif

/* ------------------------------------------------------------ point queries */

typedef struct clvr_bvh_point_iter {
    float px, py, pz;
    clvr_u32 sp;
    clvr_u32 stack[CLVR_BVH_STACK_SIZE]; /* inner node indices, or LEAF_BIT | primitive */
} clvr_bvh_point_iter;

CLVR_INLINE void clvr_bvh_point_begin(clvr_bvh_point_iter *it, clvr_u32 root, float px, float py, float pz)
{
    it->px = px;
    it->py = py;
    it->pz = pz;
    it->stack[0] = root;
    it->sp = 1;
}

/* Bit c set when child c's box of node n contains the point. Empty slots
 * (lo = +inf) and NaN points fail every test. On the device the four
 * children are tested at once on the node's structure-of-arrays float4
 * lanes (one compare per bound, no per-child branches). */
CLVR_INLINE clvr_u32 clvr_bvh_node_point_mask(CLVR_GLOBAL const clvr_bvh_node *n, float px, float py, float pz)
{
#ifdef __OPENCL_VERSION__
    CLVR_GLOBAL const float4 *q = (CLVR_GLOBAL const float4 *)n; /* lo x y z, hi x y z, child */
    const int4 in = (px >= q[0]) & (py >= q[1]) & (pz >= q[2]) & (px <= q[3]) & (py <= q[4]) & (pz <= q[5]);
    return (clvr_u32)((in.x & 1) | (in.y & 2) | (in.z & 4) | (in.w & 8));
#else
    clvr_u32 mask = 0;
    for (int c = 0; c < 4; ++c)
        mask |= (clvr_u32)(px >= n->lo_x[c] && py >= n->lo_y[c] && pz >= n->lo_z[c] && px <= n->hi_x[c] &&
                           py <= n->hi_y[c] && pz <= n->hi_z[c])
                << c;
    return mask;
#endif
}

/* Next primitive whose box contains the point; 0 when there is none left. */
CLVR_INLINE int clvr_bvh_point_next(clvr_bvh_point_iter *it, CLVR_GLOBAL const clvr_bvh_node *nodes, clvr_u32 *prim)
{
    while (it->sp > 0) {
        const clvr_u32 ref = it->stack[--it->sp];
        if (ref & CLVR_BVH_LEAF_BIT) {
            *prim = ref & CLVR_BVH_MAX_PRIMS;
            return 1;
        }
        CLVR_GLOBAL const clvr_bvh_node *n = nodes + ref;
        const clvr_u32 mask = clvr_bvh_node_point_mask(n, it->px, it->py, it->pz);
        for (int c = 0; c < 4; ++c)
            if (((mask >> c) & 1u) && it->sp < CLVR_BVH_STACK_SIZE) it->stack[it->sp++] = n->child[c];
    }
    return 0;
}

/* ------------------------------------------------------------ ray queries */

typedef struct clvr_bvh_ray_iter {
    float ox, oy, oz;
    float ix, iy, iz;       /* 1 / direction, zero components replaced by a tiny value */
    float tmin, tmax;
    clvr_u32 sp;
    clvr_u32 npend;         /* primitives hit by the last node, not yet returned */
    clvr_u32 pend[4];
    float pend_t0[4], pend_t1[4];
    clvr_u32 stack[CLVR_BVH_STACK_SIZE];
} clvr_bvh_ray_iter;

/* 1 / d, with d = 0 replaced by +-1e-30 so that slabs give +-huge instead of
 * NaN (0 * inf) for rays that start on a box face. */
CLVR_INLINE float clvr_bvh_safe_inv(float d)
{
    return 1.0f / (fabs(d) < 1e-30f ? (d < 0.0f ? -1e-30f : 1e-30f) : d);
}

/* Starts a ray query over [tmin, tmax] at root node 0 of nodes (the layout
 * of clvr_bvh_build_boxes). */
CLVR_INLINE void clvr_bvh_ray_begin_at(clvr_bvh_ray_iter *it, clvr_u32 root, float ox, float oy, float oz, float dx,
                                       float dy, float dz, float tmin, float tmax)
{
    it->ox = ox; it->oy = oy; it->oz = oz;
    it->ix = clvr_bvh_safe_inv(dx);
    it->iy = clvr_bvh_safe_inv(dy);
    it->iz = clvr_bvh_safe_inv(dz);
    it->tmin = tmin;
    it->tmax = tmax;
    it->npend = 0;
    it->stack[0] = root;
    it->sp = 1;
}

CLVR_INLINE void clvr_bvh_ray_begin(clvr_bvh_ray_iter *it, CLVR_GLOBAL const clvr_bvh_node *nodes, float ox, float oy,
                                    float oz, float dx, float dy, float dz, float tmin, float tmax)
{
    (void)nodes;
    clvr_bvh_ray_begin_at(it, 0u, ox, oy, oz, dx, dy, dz, tmin, tmax);
}

/* Next primitive whose box the ray overlaps; [*t0, *t1] is the overlap
 * clipped to [tmin, tmax]. 0 when there is none left. */
CLVR_INLINE int clvr_bvh_ray_next(clvr_bvh_ray_iter *it, CLVR_GLOBAL const clvr_bvh_node *nodes, clvr_u32 *prim,
                                  float *t0, float *t1)
{
    for (;;) {
        if (it->npend > 0) {
            const clvr_u32 k = --it->npend;
            *prim = it->pend[k];
            *t0 = it->pend_t0[k];
            *t1 = it->pend_t1[k];
            return 1;
        }
        if (it->sp == 0) return 0;
        CLVR_GLOBAL const clvr_bvh_node *n = nodes + it->stack[--it->sp];
        for (int c = 0; c < 4; ++c) {
            const clvr_u32 ch = n->child[c];
            /* Empty slots (and primitives whose box was empty or NaN) have
             * lo > hi; the slab test alone would accept them. */
            if (!(n->lo_x[c] <= n->hi_x[c])) continue;
            const float ax = (n->lo_x[c] - it->ox) * it->ix, bx = (n->hi_x[c] - it->ox) * it->ix;
            const float ay = (n->lo_y[c] - it->oy) * it->iy, by = (n->hi_y[c] - it->oy) * it->iy;
            const float az = (n->lo_z[c] - it->oz) * it->iz, bz = (n->hi_z[c] - it->oz) * it->iz;
            const float a = fmax(fmax(fmin(ax, bx), fmin(ay, by)), fmax(fmin(az, bz), it->tmin));
            const float b = fmin(fmin(fmax(ax, bx), fmax(ay, by)), fmin(fmax(az, bz), it->tmax));
            if (!(a <= b)) continue;
            if (ch & CLVR_BVH_LEAF_BIT) {
                const clvr_u32 k = it->npend++;
                it->pend[k] = ch & CLVR_BVH_MAX_PRIMS;
                it->pend_t0[k] = a;
                it->pend_t1[k] = b;
            } else if (it->sp < CLVR_BVH_STACK_SIZE) {
                it->stack[it->sp++] = ch;
            }
        }
    }
}

#endif /* CLVR_BVH_TRAVERSE_H */
