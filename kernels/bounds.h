/* bounds.h: per-element boxes, centroids and curve keys, compiled twice
 * (host reference and kernels), so the host's keys equal the device's bit
 * for bit. Only exact float operations are used (min, max, subtract,
 * multiply, compare; no a*b+c that a compiler could contract into an fma).
 *
 * Sort key layout (64 bits): type << 48 | curve key (48 bits). Sorting all
 * elements at once by this key sorts each type along its own curve and puts
 * the types in CLVR_CELL_* order, which is the contract's concatenation of
 * the four sorted lists. */
#ifndef CLVR_BOUNDS_H
#define CLVR_BOUNDS_H

#include "clvr_shared.h"
#include "sfc.h"

/* Quantizes one coordinate to the 16-bit grid: (c - lo) * scale, clamped
 * to [0, 65535]. scale = 65536 / largest extent of the global box (one
 * scale for the three axes keeps the cells cubic, so curve neighbours are
 * spatial neighbours), 0 when the box is a point. NaN maps to 0. */
CLVR_FORCE_INLINE clvr_u32 clvr_pp_quantize(float c, float lo, float scale)
{
    /* Selects, not branches, in the per-element key kernels. */
    float q = (c - lo) * scale;
    q = q > 0.0f ? q : 0.0f;
    q = q < 65535.0f ? q : 65535.0f;
    return (clvr_u32)q;
}

/* Morton code of the quantized centre of the box (lo, hi). */
CLVR_FORCE_INLINE clvr_u64 clvr_pp_centre_morton(const float *lo, const float *hi, const float *glo, float scale)
{
    clvr_u32 q[3];
    for (int k = 0; k < 3; ++k) {
        float c = (lo[k] + hi[k]) * 0.5f;
        q[k] = clvr_pp_quantize(c, glo[k], scale);
    }
    return clvr_morton3(q[0], q[1], q[2]);
}

/* Sort key of an element whose box is (lo, hi): the curve key of the box
 * centre, with the type in bits 48..49. morton != 0 selects Morton order. */
CLVR_FORCE_INLINE clvr_u64 clvr_pp_element_key(clvr_u32 type, const float *lo, const float *hi, const float *glo,
                                         float scale, int morton)
{
    const clvr_u64 m = clvr_pp_centre_morton(lo, hi, glo, scale);
    /* The Hilbert key is computed from the Morton key anyway; selecting
     * between the two (rather than branching) keeps the code branch-free. */
    const clvr_u64 h = clvr_hilbert3_from_morton(m);
    clvr_u64 code = morton ? m : h;
    return ((clvr_u64)type << 48) | code;
}

/* clvr_pp_element_key of two elements at once (boxes 0 and 1), bit for bit
 * the same keys: the key kernels' form (two elements per work-item). Both
 * Morton codes come before either Hilbert table walk: 3-4% faster under
 * PoCL (10M hexes) than two clvr_pp_element_key calls. */
CLVR_FORCE_INLINE void clvr_pp_element_key2(clvr_u32 type, const float *lo0, const float *hi0, const float *lo1,
                                      const float *hi1, const float *glo, float scale, int morton, clvr_u64 *k0,
                                      clvr_u64 *k1)
{
    const clvr_u64 m0 = clvr_pp_centre_morton(lo0, hi0, glo, scale), m1 = clvr_pp_centre_morton(lo1, hi1, glo, scale);
    const clvr_u64 h0 = clvr_hilbert3_from_morton(m0), h1 = clvr_hilbert3_from_morton(m1);
    *k0 = ((clvr_u64)type << 48) | (morton ? m0 : h0);
    *k1 = ((clvr_u64)type << 48) | (morton ? m1 : h1);
}

/* Type of the element with global id g, given the first ids of pyramids,
 * wedges and hexes (empty types have equal bounds). */
CLVR_INLINE clvr_u32 clvr_pp_type_of(clvr_u64 g, clvr_u64 b1, clvr_u64 b2, clvr_u64 b3)
{
    return (clvr_u32)(g >= b1) + (clvr_u32)(g >= b2) + (clvr_u32)(g >= b3);
}

/* First global id past type t's elements in layout L of n elements. */
CLVR_INLINE clvr_u32 clvr_pp_type_end(const clvr_type_layout *L, clvr_u32 t, clvr_u32 n)
{
    return t + 1u < CLVR_CELL_TYPE_COUNT ? L->first[t + 1u] : n;
}

/* Grows a box (lo, hi) by a point. */
CLVR_FORCE_INLINE void clvr_pp_box_grow(float *lo, float *hi, float x, float y, float z)
{
    lo[0] = x < lo[0] ? x : lo[0];
    lo[1] = y < lo[1] ? y : lo[1];
    lo[2] = z < lo[2] ? z : lo[2];
    hi[0] = x > hi[0] ? x : hi[0];
    hi[1] = y > hi[1] ? y : hi[1];
    hi[2] = z > hi[2] ? z : hi[2];
}

/* Box of the vpe vertices idx[0..vpe-1] of an element; positions are
 * x y z interleaved (the mesh's float3 array). */
CLVR_FORCE_INLINE void clvr_pp_element_box(const CLVR_GLOBAL float *pos, const CLVR_GLOBAL clvr_u32 *idx, clvr_u32 vpe,
                                     float *lo, float *hi)
{
    clvr_u64 v = idx[0];
    lo[0] = hi[0] = pos[3 * v];
    lo[1] = hi[1] = pos[3 * v + 1];
    lo[2] = hi[2] = pos[3 * v + 2];
    CLVR_UNROLL
    for (clvr_u32 k = 1; k < vpe; ++k) {
        v = idx[k];
        clvr_pp_box_grow(lo, hi, pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
    }
}

#endif /* CLVR_BOUNDS_H */
