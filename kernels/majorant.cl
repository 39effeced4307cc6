/* majorant.cl: maximum extinction (majorants) for adaptive delta tracking
 * (paper 3.4.1 and 3.4.3). Cluster scalar ranges are mapped through the
 * transfer function whenever it changes; for the dda method the elements'
 * scalar ranges are first rasterized into a macrocell grid with atomics
 * (once per mesh and grid size), then each cell's range is mapped the same
 * way, and each block of cells takes the largest of its cells (the coarse
 * level, see CLVR_DDA_BLOCK). Cells that no element touches keep an empty
 * range and get majorant 0 (skipped). */
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

/* Rasterizes each element's vertex scalar range into every cell its own box
 * overlaps, grown by a hundredth of a cell so that points a rounding error
 * outside a cell boundary (or found in the element within its tolerance)
 * are still covered by the DDA's cell. Tighter than the
 * sampling clusters' boxes: a cluster of 16 elements along the Hilbert curve
 * can mix a large coarse element with small ones near a feature, and its
 * box then carries the feature's scalars over cells the feature never
 * reaches (AMR meshes). Interpolation inside an element stays within its
 * vertices' scalar range, so every cell still bounds every point in it.
 * Instances are sorted by first_element (preprocessing emits them in global
 * element order); each work item finds its own by binary search. */
__kernel void clvr_grid_splat_elements(__global const clvr_instance *inst, uint ninst, uint nelem,
                                       __global const clvr_frame *fp, __global uint *grid,
                                       __global const float4 *vertices0, __global const ushort *idx16_0,
                                       __global const uint *idx32_0, __global const float4 *vertices1,
                                       __global const ushort *idx16_1, __global const uint *idx32_1,
                                       __global const float4 *vertices2, __global const ushort *idx16_2,
                                       __global const uint *idx32_2, __global const float4 *vertices3,
                                       __global const ushort *idx16_3, __global const uint *idx32_3)
{
    uint e = get_global_id(0);
    if (e >= nelem || ninst == 0) return;
    uint a = 0, b = ninst; /* inst[a].first_element <= e < inst[b].first_element */
    while (b - a > 1) {
        uint m = (a + b) / 2;
        if (inst[m].first_element <= e) a = m;
        else b = m;
    }
    const uint type = inst[a].type, nv = clvr_cell_vertex_count(type), first_vertex = inst[a].first_vertex;
    const ulong base = inst[a].first_index + (ulong)(e - inst[a].first_element) * nv;
    const int wide = inst[a].index_bits == 32u;
    /* The element's piece of the split arrays (docs/large-meshes.md). */
    const uint piece = inst[a].piece;
    __global const float4 *vertices = piece == 1u ? vertices1 : piece == 2u ? vertices2 : piece == 3u ? vertices3 : vertices0;
    __global const ushort *idx16 = piece == 1u ? idx16_1 : piece == 2u ? idx16_2 : piece == 3u ? idx16_3 : idx16_0;
    __global const uint *idx32 = piece == 1u ? idx32_1 : piece == 2u ? idx32_2 : piece == 3u ? idx32_3 : idx32_0;
    float3 blo = (float3)(INFINITY), bhi = (float3)(-INFINITY);
    float smin = INFINITY, smax = -INFINITY;
    for (uint k = 0; k < nv; ++k) {
        uint li = wide ? idx32[base + k] : (uint)idx16[base + k];
        float4 p = vertices[first_vertex + li];
        blo = fmin(blo, p.xyz);
        bhi = fmax(bhi, p.xyz);
        smin = fmin(smin, p.w);
        smax = fmax(smax, p.w);
    }
    const clvr_frame f = *fp;
    const int r = (int)f.grid_res;
    float3 lo = vload3(0, f.grid_lo), hi = vload3(0, f.grid_hi);
    float3 cs = (hi - lo) / (float)r;
    int3 c0 = clamp(convert_int3_rtn((blo - lo) / cs - 0.01f), (int3)(0), (int3)(r - 1));
    int3 c1 = clamp(convert_int3_rtn((bhi - lo) / cs + 0.01f), (int3)(0), (int3)(r - 1));
    uint omin = clvr_ordered_from_float(smin), omax = clvr_ordered_from_float(smax);
    for (int z = c0.z; z <= c1.z; ++z)
        for (int y = c0.y; y <= c1.y; ++y)
            for (int x = c0.x; x <= c1.x; ++x) {
                uint c = (uint)clvr_grid_index(x, y, z, r);
                atomic_min(&grid[2 * c], omin);
                atomic_max(&grid[2 * c + 1], omax);
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

/* Coarse level of the grid: the largest majorant of each block's cells
 * (CLVR_DDA_BLOCK^3, fewer at the far faces when the block count does not
 * divide r), and, where sums is not NULL, their sum (for the automatic
 * grid's choice, see host/pipeline/majorant.h). rc = ceil(r / CLVR_DDA_BLOCK) blocks per axis.
 * Run on the blocks again it makes the level above: with r = 128 and
 * blocks of 4, the blocks of the 128^3 grid are a 32^3 grid whose cells
 * bound theirs. */
__kernel void clvr_grid_blocks(__global const float *cells, uint r, __global float *blocks, __global float *sums,
                               uint rc)
{
    uint i = get_global_id(0);
    if (i >= rc * rc * rc) return;
    const uint bx = i % rc, by = (i / rc) % rc, bz = i / (rc * rc), B = (uint)CLVR_DDA_BLOCK;
    float m = 0.0f, sum = 0.0f;
    for (uint z = bz * B; z < min(bz * B + B, r); ++z)
        for (uint y = by * B; y < min(by * B + B, r); ++y)
            for (uint x = bx * B; x < min(bx * B + B, r); ++x) {
                const float c = cells[clvr_grid_index((int)x, (int)y, (int)z, (int)r)];
                m = fmax(m, c);
                sum += c;
            }
    blocks[i] = m;
    if (sums) sums[i] = sum;
}
