/* majorant.cl: maximum extinction (majorants) for adaptive delta tracking
 * (paper 3.4.1 and 3.4.3). Cluster scalar ranges are mapped through the
 * transfer function whenever it changes; for the dda method the clusters'
 * scalar ranges are first rasterized into a macrocell grid with atomics
 * (once per mesh), then each cell's range is mapped the same way. Cells that
 * no cluster touches keep an empty range and get majorant 0 (skipped). */
#include "clvr_shared.h"

/* Float <-> uint mapping that preserves order, so atomic_min/atomic_max on
 * uints act as min/max on floats of any sign. */
inline uint clvr_ordered_from_float(float f)
{
    uint u = as_uint(f);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
inline float clvr_float_from_ordered(uint u)
{
    return as_float((u & 0x80000000u) ? (u & 0x7fffffffu) : ~u);
}

/* One majorant per sampling cluster: max extinction over the TF entries its
 * scalar range covers, times density. */
__kernel void clvr_cluster_majorants(__global const clvr_sampling_cluster *clusters, uint n,
                                     __global const float4 *tf, __global const clvr_frame *fp,
                                     __global float *out)
{
    uint i = get_global_id(0);
    if (i >= n) return;
    const clvr_frame f = *fp;
    out[i] = clvr_tf_max_extinction(tf, f.tf_size, f.tf_lo, f.tf_hi, f.density, clusters[i].lo[3], clusters[i].hi[3]);
}

/* grid[2*c] = ordered min, grid[2*c+1] = ordered max; empty = (max, min). */
__kernel void clvr_grid_clear(__global uint *grid, uint cells)
{
    uint i = get_global_id(0);
    if (i >= cells) return;
    grid[2 * i] = 0xffffffffu;
    grid[2 * i + 1] = 0u;
}

/* Rasterizes each cluster's scalar range into every cell its box overlaps.
 * The box is grown by a hundredth of a cell so that points a rounding error
 * outside a cell boundary are still covered by the DDA's cell. */
__kernel void clvr_grid_splat(__global const clvr_sampling_cluster *clusters, uint n, __global const clvr_frame *fp,
                              __global uint *grid)
{
    uint i = get_global_id(0);
    if (i >= n) return;
    const clvr_frame f = *fp;
    const int r = (int)f.grid_res;
    float3 lo = vload3(0, f.vol_lo), hi = vload3(0, f.vol_hi);
    float3 cs = (hi - lo) / (float)r;
    float3 blo = vload3(0, clusters[i].lo), bhi = vload3(0, clusters[i].hi);
    int3 c0 = clamp(convert_int3_rtn((blo - lo) / cs - 0.01f), (int3)(0), (int3)(r - 1));
    int3 c1 = clamp(convert_int3_rtn((bhi - lo) / cs + 0.01f), (int3)(0), (int3)(r - 1));
    uint smin = clvr_ordered_from_float(clusters[i].lo[3]);
    uint smax = clvr_ordered_from_float(clusters[i].hi[3]);
    for (int z = c0.z; z <= c1.z; ++z)
        for (int y = c0.y; y <= c1.y; ++y)
            for (int x = c0.x; x <= c1.x; ++x) {
                uint c = ((uint)z * (uint)r + (uint)y) * (uint)r + (uint)x;
                atomic_min(&grid[2 * c], smin);
                atomic_max(&grid[2 * c + 1], smax);
            }
}

/* Majorant per cell from its scalar range; 0 for untouched cells. */
__kernel void clvr_grid_majorants(__global const uint *grid, uint cells, __global const float4 *tf,
                                  __global const clvr_frame *fp, __global float *out)
{
    uint i = get_global_id(0);
    if (i >= cells) return;
    const clvr_frame f = *fp;
    uint a = grid[2 * i], b = grid[2 * i + 1];
    if (a > b) { out[i] = 0.0f; return; }
    out[i] = clvr_tf_max_extinction(tf, f.tf_size, f.tf_lo, f.tf_hi, f.density, clvr_float_from_ordered(a),
                                    clvr_float_from_ordered(b));
}
