/* bounds.cl: global bounds of the mesh (a tiled parallel reduction) and the
 * per-element curve keys (element box -> centre -> 16-bit grid -> Hilbert
 * or Morton key), paper sections 3.1 and 3.2.1. */
#include "clvr_shared.h"
#include "bounds.h"

/* Tiled kernels below: work-item t handles the contiguous chunk
 * [t * chunk, min(n, (t + 1) * chunk)). Long contiguous chunks are what a
 * CPU device runs fastest; the host picks a few tiles per compute unit. */

/* Partial bounds of positions (xyz) and scalars (w lanes) per tile. */
__kernel void clvr_pp_bounds_tiles(__global const float *pos, __global const float *scal, ulong n, ulong chunk,
                                   uint ntiles, __global clvr_box *out)
{
    uint t = (uint)get_global_id(0);
    if (t >= ntiles) return;
    ulong b = (ulong)t * chunk, e = min(n, b + chunk);
    float lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
    float hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (ulong i = b; i < e; ++i) {
        clvr_pp_box_grow(lo, hi, pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
        float s = scal[i];
        lo[3] = s < lo[3] ? s : lo[3];
        hi[3] = s > hi[3] ? s : hi[3];
    }
    for (int k = 0; k < 4; ++k) {
        out[t].lo[k] = lo[k];
        out[t].hi[k] = hi[k];
    }
}

/* Sort keys and (with_vals) original global element ids of the elements of one type:
 * work-item i handles elements first + 2i and first + 2i + 1 (the second
 * only when it exists), whose vpe indices start at idx[slot0 + e * vpe].
 * Two elements per work-item (clvr_pp_element_key2) measured faster than
 * one (10M hexes: 0.175 -> 0.118 s). One kernel per type makes vpe a compile-time
 * constant, so the vertex loop unrolls; with the Hilbert loop unrolled and
 * the helpers inlined, the kernel is one straight block. Under PoCL this
 * measured 16% faster (10M hexes: 0.208 -> 0.175 s) than one kernel
 * looking the type up per element. The table-driven Morton and 3-level
 * Hilbert encoders of sfc.h took it from 0.118 to about 0.085 s. */
#define CLVR_PP_KEYS_KERNEL(NAME, VPE)                                                                                \
    __kernel void NAME(__global const float *pos, __global const uint *idx, ulong slot0, uint count, uint first,    \
                       float glo_x, float glo_y, float glo_z, float scale, int morton, uint type,                \
                       __global ulong *keys, __global uint *vals, int with_vals)                                \
    {                                                                                                            \
        uint e0 = 2u * (uint)get_global_id(0);                                                                   \
        if (e0 >= count) return;                                                                                 \
        uint e1 = e0 + 1u < count ? e0 + 1u : e0;                                                                \
        float glo[3] = {glo_x, glo_y, glo_z};                                                                    \
        float lo0[3], hi0[3], lo1[3], hi1[3];                                                                    \
        clvr_pp_element_box(pos, idx + slot0 + (ulong)e0 * VPE, VPE, lo0, hi0);                                  \
        clvr_pp_element_box(pos, idx + slot0 + (ulong)e1 * VPE, VPE, lo1, hi1);                                  \
        ulong k0, k1;                                                                                            \
        clvr_pp_element_key2(type, lo0, hi0, lo1, hi1, glo, scale, morton, &k0, &k1);                            \
        keys[first + e0] = k0;                                                                                   \
        if (with_vals) vals[first + e0] = first + e0;                                                            \
        if (e1 != e0) {                                                                                          \
            keys[first + e1] = k1;                                                                               \
            if (with_vals) vals[first + e1] = first + e1;                                                        \
        }                                                                                                        \
    }
/* clvr_pp_keys_tet, clvr_pp_keys_pyramid, ...: one per CLVR_CELL_TYPES entry. */
#define CLVR_PP_KEYS_OF_TYPE_(id, name, nv) CLVR_PP_KEYS_KERNEL(clvr_pp_keys_##name, nv)
CLVR_CELL_TYPES(CLVR_PP_KEYS_OF_TYPE_)
#undef CLVR_PP_KEYS_OF_TYPE_
