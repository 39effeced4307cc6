/* cluster.cl: elements reordered along the curve, and the three cluster
 * kinds of the paper built from that order (section 3.2, 3.4.1):
 * leaf clusters (leaf_size consecutive elements inside an instance, a box
 * each), instance bounds (union of their leaves) and adaptive-sampling
 * clusters (sampling_size consecutive elements of one type, a box and the
 * scalar range of their vertices). Element ids are global over the four
 * concatenated type lists; a clvr_type_layout gives where each type's
 * elements and index slots start. */
#include "clvr_shared.h"
#include "bounds.h"

/* Copies the vpe indices of n elements: dst element i = src element order[i]
 * (order relative to the type). One loop per vertex count keeps the copy a
 * fixed-size move the compiler unrolls. */
inline void clvr_pp_gather_run(__global const uint *order, __global const uint *src, __global uint *dst, uint vpe,
                               uint i0, uint i1, uint first)
{
    if (vpe == 8u)
        for (uint i = i0; i < i1; ++i) vstore8(vload8(order[i] - first, src), i, dst);
    else if (vpe == 4u)
        for (uint i = i0; i < i1; ++i) vstore4(vload4(order[i] - first, src), i, dst);
    else
        for (uint i = i0; i < i1; ++i) {
            __global const uint *a = src + (ulong)(order[i] - first) * vpe;
            __global uint *b = dst + (ulong)i * vpe;
            for (uint k = 0; k < vpe; ++k) b[k] = a[k];
        }
}

/* idx_sorted[slot of sorted element i] = idx_in[slot of element order[i]].
 * Tiled: work-item t copies sorted elements [t * chunk, min(n, (t + 1) *
 * chunk)), one run per type; many independent loads in flight per core is
 * what a CPU device needs for this random read. */
__kernel void clvr_pp_gather(__global const uint *order, __global const uint *idx_in, __global uint *idx_sorted,
                             uint n, ulong chunk, uint ntiles, clvr_type_layout L)
{
    uint tile = (uint)get_global_id(0);
    if (tile >= ntiles) return;
    ulong b = (ulong)tile * chunk, e = min((ulong)n, b + chunk);
    for (uint t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint first = L.first[t];
        ulong r0 = max(b, (ulong)first), r1 = min(e, (ulong)clvr_pp_type_end(&L, t, n));
        if (r0 >= r1) continue;
        /* Types are the sort key's top bits: sorted element i and order[i] have the same type. */
        clvr_pp_gather_run(order + first, idx_in + L.slot[t], idx_sorted + L.slot[t], clvr_cell_vertex_count(t),
                           (uint)r0 - first, (uint)r1 - first, first);
    }
}

/* One curve (clvr_preprocess_options.one_curve): idx_hex[8 i .. 8 i + 7] =
 * input element order[i] as its collapsed hex (clvr_hex_collapse_ids),
 * whatever its type; L is the input's type layout. The sort put every type
 * on one curve (one key type), so sorted element i may be of any type.
 * Tiled as clvr_pp_gather. */
__kernel void clvr_pp_gather_collapse(__global const uint *order, __global const uint *idx_in,
                                      __global uint *idx_hex, uint n, ulong chunk, uint ntiles, clvr_type_layout L)
{
    uint tile = (uint)get_global_id(0);
    if (tile >= ntiles) return;
    ulong b = (ulong)tile * chunk, e = min((ulong)n, b + chunk);
    for (ulong i = b; i < e; ++i) {
        const uint g = order[i], t = clvr_pp_type_of(g, L.first[1], L.first[2], L.first[3]);
        const uint nv = clvr_cell_vertex_count(t);
        __global const uint *src = idx_in + L.slot[t] + (ulong)(g - L.first[t]) * nv;
        uint v[CLVR_CELL_MAX_VERTS], h[8];
        for (uint k = 0; k < nv; ++k) v[k] = src[k];
        clvr_hex_collapse_ids(t, v, h);
        for (uint k = 0; k < 8u; ++k) idx_hex[8u * i + k] = h[k];
    }
}

/* Sampling cluster c: cb1..cb3 are the first cluster ids of pyramids,
 * wedges, hexes; L the element layout, en = element count. */
__kernel void clvr_pp_sampling(__global const float *pos, __global const float *scal, __global const uint *idx_sorted,
                               uint nclusters, uint size, uint cb1, uint cb2, uint cb3, clvr_type_layout L, uint en,
                               __global clvr_sampling_cluster *out)
{
    uint c = (uint)get_global_id(0);
    if (c >= nclusters) return;
    uint t = clvr_pp_type_of(c, cb1, cb2, cb3);
    uint cfirst = t == 0u ? 0u : t == 1u ? cb1 : t == 2u ? cb2 : cb3;
    uint first = L.first[t];
    uint end = clvr_pp_type_end(&L, t, en);
    ulong slot0 = L.slot[t];
    uint vpe = clvr_cell_vertex_count(t);
    uint e0 = first + (c - cfirst) * size, e1 = min(end, e0 + size);
    float lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
    float hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (uint e = e0; e < e1; ++e) {
        __global const uint *ix = idx_sorted + slot0 + (ulong)(e - first) * vpe;
        for (uint k = 0; k < vpe; ++k) {
            ulong v = ix[k];
            clvr_pp_box_grow(lo, hi, pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
            float s = scal[v];
            lo[3] = s < lo[3] ? s : lo[3];
            hi[3] = s > hi[3] ? s : hi[3];
        }
    }
    for (int k = 0; k < 4; ++k) {
        out[c].lo[k] = lo[k];
        out[c].hi[k] = hi[k];
    }
}

/* Index of the instance that holds leaf l (largest c with first_leaf <= l). */
inline uint clvr_pp_find_leaf(__global const clvr_instance *inst, uint ninst, uint l)
{
    uint a = 0, b = ninst;
    while (b - a > 1u) {
        uint m = (a + b) / 2u;
        if (inst[m].first_leaf <= l) a = m;
        else b = m;
    }
    return a;
}

/* Grows (lo, hi) by the vertices of elements [e0, e1) of instance c, whose
 * local indices are IDX (idx16 or idx32), VPE per element: a macro so that
 * every (index width, vertex count) pair becomes a loop with constant
 * bounds and no per-vertex test. Each element's box is found first and
 * then merged: the elements' comparison chains are independent, where one
 * running box made every vertex wait for the previous one's min/max
 * (profiled: 78% of the kernel's time on the two compares). The host
 * reference compares in the same order, so ties of -0 and +0 resolve
 * alike. Only xyz matter; the w lanes carry the scalar. */
#define CLVR_PP_LEAF_GROW(IDX, VPE)                                                                   \
    for (uint e = e0; e < e1; ++e) {                                                                 \
        ulong s = c.first_index + (ulong)(e - c.first_element) * (VPE);                               \
        float4 elo = verts[c.first_vertex + (uint)IDX[s]], ehi = elo;                                \
        for (uint k = 1; k < (VPE); ++k) {                                                           \
            float4 v = verts[c.first_vertex + (uint)IDX[s + k]];                                     \
            elo = select(elo, v, v < elo);                                                           \
            ehi = select(ehi, v, v > ehi);                                                           \
        }                                                                                            \
        lo = select(lo, elo, elo < lo);                                                              \
        hi = select(hi, ehi, ehi > hi);                                                              \
    }
#define CLVR_PP_LEAF_CASE_16(id, name, nv) case id: CLVR_PP_LEAF_GROW(idx16, nv) break;
#define CLVR_PP_LEAF_CASE_32(id, name, nv) case id: CLVR_PP_LEAF_GROW(idx32, nv) break;
#define CLVR_PP_LEAF_CASES(BITS)                   \
    switch (c.type) {                              \
        CLVR_CELL_TYPES(CLVR_PP_LEAF_CASE_##BITS)  \
    default: break;                                \
    }

/* Box of leaf cluster l from the clustered arrays (local indices into the
 * instance's own vertices), so the boxes describe exactly what is rendered.
 * 10M hexes: 0.028 -> 0.022-0.026 s, from the per-element boxes (the
 * specialised loops alone measured no faster). */
__kernel void clvr_pp_leaf_boxes(__global const float4 *verts, __global const ushort *idx16,
                                 __global const uint *idx32, __global const clvr_instance *inst, uint ninst,
                                 uint nleaves, uint leaf_size, __global clvr_box *out)
{
    uint l = (uint)get_global_id(0);
    if (l >= nleaves) return;
    clvr_instance c = inst[clvr_pp_find_leaf(inst, ninst, l)];
    uint e0 = c.first_element + (l - c.first_leaf) * leaf_size;
    uint e1 = min(c.first_element + c.num_elements, e0 + leaf_size);
    float4 lo = (float4)(INFINITY), hi = (float4)(-INFINITY);
    if (c.index_bits == 16u) {
        CLVR_PP_LEAF_CASES(16)
    } else {
        CLVR_PP_LEAF_CASES(32)
    }
    out[l].lo[0] = lo.x; out[l].lo[1] = lo.y; out[l].lo[2] = lo.z; out[l].lo[3] = 0.0f;
    out[l].hi[0] = hi.x; out[l].hi[1] = hi.y; out[l].hi[2] = hi.z; out[l].hi[3] = 0.0f;
}

/* Instance bounds: the union of its leaf boxes. */
__kernel void clvr_pp_instance_bounds(__global clvr_instance *inst, uint ninst, __global const clvr_box *leaves)
{
    uint i = (uint)get_global_id(0);
    if (i >= ninst) return;
    uint l0 = inst[i].first_leaf, l1 = l0 + inst[i].num_leaves;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint l = l0; l < l1; ++l) {
        clvr_pp_box_grow(lo, hi, leaves[l].lo[0], leaves[l].lo[1], leaves[l].lo[2]);
        clvr_pp_box_grow(lo, hi, leaves[l].hi[0], leaves[l].hi[1], leaves[l].hi[2]);
    }
    for (int k = 0; k < 3; ++k) {
        inst[i].bounds.lo[k] = lo[k];
        inst[i].bounds.hi[k] = hi[k];
    }
    inst[i].bounds.lo[3] = 0.0f;
    inst[i].bounds.hi[3] = 0.0f;
}
