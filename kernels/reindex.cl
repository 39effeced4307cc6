/* reindex.cl: instance clusters and mesh compression (paper 3.2.2, 3.3):
 * the greedy split + local re-indexing per segment (reindex.h), the flags
 * that the flagged select (scan.cl) compacts into the instance table, the
 * instance table itself, and the copy of every instance's vertices into the
 * clustered float4 (x, y, z, scalar) array. */
#include "clvr_shared.h"
#include "bounds.h"
#include "reindex.h"

/* One work-item per segment, all types in one launch (so that the segments
 * of small types run beside those of big ones): seg[s] = (type, first
 * element, end element, 0) with elements counted within the type; L gives
 * the first global element id and index slot of each type. Worker s uses
 * map s (1 << log2cap slots, zero) and writes its records at
 * recs[s * rec_max ...] and their number at counts[s]. */
__kernel void clvr_pp_split(__global const uint *idx_sorted, __global uint *vmap, __global ushort *idx16,
                            __global uint *idx32, int bits32, __global const uint4 *seg, uint nseg,
                            clvr_type_layout L, uint vlimit, uint max_elems,
                            __global ulong *tab, uint log2cap, uint rec_max, __global clvr_pp_instance_rec *recs,
                            __global uint *counts)
{
    uint s = (uint)get_global_id(0);
    if (s >= nseg) return;
    uint4 g = seg[s];
    uint t = g.x;
    uint first = L.first[t];
    ulong slot0 = L.slot[t];
    counts[s] = clvr_pp_split_segment(idx_sorted, vmap, idx16, idx32, bits32, t, first, slot0, g.y, g.z, vlimit,
                                      max_elems, tab + ((ulong)s << log2cap), log2cap, recs + (ulong)s * rec_max,
                                      rec_max);
}

/* flags[i] = 1 when record slot i holds a record (i % rec_max < its count). */
__kernel void clvr_pp_rec_flags(__global const uint *counts, uint nslots, uint rec_max, __global uint *flags)
{
    uint i = (uint)get_global_id(0);
    if (i >= nslots) return;
    flags[i] = (i % rec_max) < counts[i / rec_max] ? 1u : 0u;
}

/* Per instance i (record recs[sel[i]]): vertex and leaf counts, to scan. */
__kernel void clvr_pp_inst_counts(__global const clvr_pp_instance_rec *recs, __global const uint *sel, uint ninst,
                                  uint leaf_size, __global uint *nverts, __global uint *nleaves)
{
    uint i = (uint)get_global_id(0);
    if (i >= ninst) return;
    clvr_pp_instance_rec r = recs[sel[i]];
    nverts[i] = r.num_vertices;
    nleaves[i] = (r.num_elements + leaf_size - 1u) / leaf_size;
}

/* The instance table (bounds come later from the leaves); vsrc[i] keeps
 * where instance i's vertex ids are in the scratch map. nverts and nleaves
 * hold the exclusive scans of the counts. */
__kernel void clvr_pp_inst_write(__global const clvr_pp_instance_rec *recs, __global const uint *sel, uint ninst,
                                 __global const uint *first_vertex, __global const uint *first_leaf, uint leaf_size,
                                 int bits32, clvr_type_layout L, __global clvr_instance *inst, __global ulong *vsrc)
{
    uint i = (uint)get_global_id(0);
    if (i >= ninst) return;
    clvr_pp_instance_rec r = recs[sel[i]];
    uint t = r.type;
    uint first = L.first[t];
    ulong slot0 = L.slot[t];
    clvr_instance c;
    for (int k = 0; k < 4; ++k) { c.bounds.lo[k] = 0.0f; c.bounds.hi[k] = 0.0f; }
    c.type = t;
    c.index_bits = bits32 ? 32u : 16u;
    c.first_element = r.first_element;
    c.num_elements = r.num_elements;
    c.first_vertex = first_vertex[i];
    c.num_vertices = r.num_vertices;
    c.first_index = slot0 + (ulong)(r.first_element - first) * clvr_cell_vertex_count(t);
    c.first_leaf = first_leaf[i];
    c.num_leaves = (r.num_elements + leaf_size - 1u) / leaf_size;
    c.bvh_root = CLVR_PP_NO_ROOT;
    c.piece = 0u; /* one piece: host/pipeline/partition.c splits assembled results */
    c.piece_first_element = 0u;
    inst[i] = c;
    vsrc[i] = r.vsrc;
}

/* Clustered vertex j = (position, scalar) of the mesh vertex that instance
 * c's j - first_vertex'th local id stands for. Tiled: work-item t fills
 * vertices [t * chunk, min(nv, (t + 1) * chunk)), finding its first
 * instance by binary search once and then walking the instances in order. */
__kernel void clvr_pp_vertices(__global const float *pos, __global const float *scal, __global const uint *vmap,
                               __global const clvr_instance *inst, __global const ulong *vsrc, uint ninst, uint nv,
                               ulong chunk, uint ntiles, __global float4 *out)
{
    uint tile = (uint)get_global_id(0);
    if (tile >= ntiles) return;
    ulong jb = (ulong)tile * chunk, je = min((ulong)nv, jb + chunk);
    if (jb >= je) return;
    uint a = 0, b = ninst;
    while (b - a > 1u) {
        uint m = (a + b) / 2u;
        if (inst[m].first_vertex <= jb) a = m;
        else b = m;
    }
    for (ulong j = jb; j < je;) {
        uint f = inst[a].first_vertex;
        ulong end = a + 1u < ninst ? (ulong)inst[a + 1u].first_vertex : (ulong)nv;
        end = min(end, je);
        __global const uint *src = vmap + vsrc[a] + (j - f);
        for (; j < end; ++j) {
            ulong v = *src++;
            out[j] = (float4)(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2], scal[v]);
        }
        ++a;
    }
}
