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

/* Sort key and original global element id of every element. Elements are
 * numbered over the concatenated type lists (tets first); eb = first element
 * id of pyramids, wedges, hexes; sb = first index slot of each. Work-item i
 * handles elements [i * per, min(n, (i + 1) * per)): contiguous runs are
 * what a CPU device streams fastest. */
__kernel void clvr_pp_element_keys(__global const float *pos, __global const uint *idx, uint n, uint per, uint eb1,
                                   uint eb2, uint eb3, ulong sb1, ulong sb2, ulong sb3, float glo_x, float glo_y,
                                   float glo_z, float scale, int morton, __global ulong *keys, __global uint *vals)
{
    uint g0 = (uint)get_global_id(0) * per;
    if (g0 >= n) return;
    uint g1 = min(n, g0 + per);
    float glo[3] = {glo_x, glo_y, glo_z};
    for (uint g = g0; g < g1; ++g) {
        uint t = clvr_pp_type_of(g, eb1, eb2, eb3);
        uint first = t == 0u ? 0u : t == 1u ? eb1 : t == 2u ? eb2 : eb3;
        ulong slot0 = t == 0u ? 0ul : t == 1u ? sb1 : t == 2u ? sb2 : sb3;
        uint vpe = clvr_cell_vertex_count(t);
        float lo[3], hi[3];
        clvr_pp_element_box(pos, idx + slot0 + (ulong)(g - first) * vpe, vpe, lo, hi);
        keys[g] = clvr_pp_element_key(t, lo, hi, glo, scale, morton);
        vals[g] = g;
    }
}
