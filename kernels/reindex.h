/* reindex.h: the greedy instance split with per-instance re-indexing
 * (paper 3.2.2 and 3.3), compiled twice: the kernel runs it once per
 * segment, the host reference runs the very same code.
 *
 * Walking one segment of one type's curve-sorted elements, an element
 * joins the open instance unless that would make the instance reference
 * more than vlimit distinct vertices or hold more than max_elems elements;
 * then a new instance starts with it. While walking, every vertex id gets
 * its instance-local number on first use (a hash map vertex id -> local id
 * per worker, reset per instance by bumping an epoch instead of clearing),
 * the local index is written in place of the global one, and the vertex id
 * is appended to the instance's vertex list in the scratch map. This is the
 * paper's "flag used vertices, compact, permute" done in one pass: the hash
 * map is the flag array and the old->new permutation restricted to the
 * vertices the instance uses, so the cost is O(indices) instead of
 * O(vertices) per instance, and the vertex list comes out in first-use
 * order, which follows the curve (good locality when rendering).
 * Duplicated vertices across instances are kept, as in the paper. */
#ifndef CLVR_REINDEX_H
#define CLVR_REINDEX_H

#include "clvr_shared.h"

/* Hash table slots hold (epoch << 32 | vertex id); a slot whose epoch is
 * not the current one is empty. */
CLVR_INLINE clvr_u32 clvr_pp_hash_slot(clvr_u32 id, clvr_u32 log2cap)
{
    return (clvr_u32)((id * 0x9E3779B1u) >> (32u - log2cap));
}

/* Local id of vertex id in the current instance, or 0xffffffff when absent. */
CLVR_INLINE clvr_u32 clvr_pp_hash_find(CLVR_GLOBAL const clvr_u64 *tk, CLVR_GLOBAL const clvr_u32 *tv,
                                       clvr_u32 log2cap, clvr_u64 epoch, clvr_u32 id)
{
    const clvr_u32 mask = (1u << log2cap) - 1u;
    for (clvr_u32 h = clvr_pp_hash_slot(id, log2cap);; h = (h + 1u) & mask) {
        clvr_u64 s = tk[h];
        if ((s >> 32) != epoch) return 0xffffffffu;
        if ((clvr_u32)s == id) return tv[h];
    }
}

/* Greedy split and re-index of elements [e_begin, e_end) of one type
 * (indices relative to that type: element e's global sorted indices are
 * idx_sorted[slot0 + e * vpe ...]). Writes local indices to idx16 or idx32
 * at the same slots, vertex ids to vmap from slot0 + e_begin * vpe on
 * (each instance uses at most as many entries as it has index slots), and
 * at most rec_max records. epoch0 + 1 .. epoch0 + rec_max are the epochs
 * this call may use (unique per worker table over the whole run). Returns
 * the number of records. */
CLVR_INLINE clvr_u32 clvr_pp_split_segment(CLVR_GLOBAL const clvr_u32 *idx_sorted, CLVR_GLOBAL clvr_u32 *vmap,
                                           CLVR_GLOBAL clvr_u16 *idx16, CLVR_GLOBAL clvr_u32 *idx32, int bits32,
                                           clvr_u32 type, clvr_u32 type_first, clvr_u64 slot0, clvr_u32 e_begin,
                                           clvr_u32 e_end, clvr_u32 vlimit, clvr_u32 max_elems,
                                           CLVR_GLOBAL clvr_u64 *tk, CLVR_GLOBAL clvr_u32 *tv, clvr_u32 log2cap,
                                           clvr_u64 epoch0, CLVR_GLOBAL clvr_pp_instance_rec *recs,
                                           clvr_u32 rec_max)
{
    const clvr_u32 vpe = clvr_cell_vertex_count(type);
    const clvr_u32 mask = (1u << log2cap) - 1u;
    clvr_u64 epoch = epoch0 + 1u;
    clvr_u64 vpos = slot0 + (clvr_u64)e_begin * vpe, vsrc = vpos;
    clvr_u32 nv = 0, ne = 0, first = e_begin, nrec = 0;
    for (clvr_u32 e = e_begin; e < e_end; ++e) {
        const clvr_u64 s = slot0 + (clvr_u64)e * vpe;
        clvr_u32 ids[CLVR_CELL_MAX_VERTS];
        for (clvr_u32 k = 0; k < vpe; ++k) ids[k] = idx_sorted[s + k];
        if (ne > 0u) {
            clvr_u32 fresh = 0;
            for (clvr_u32 k = 0; k < vpe; ++k) {
                if (clvr_pp_hash_find(tk, tv, log2cap, epoch, ids[k]) != 0xffffffffu) continue;
                clvr_u32 dup = 0;
                for (clvr_u32 j = 0; j < k; ++j) dup |= ids[j] == ids[k];
                fresh += dup ? 0u : 1u;
            }
            if (nv + fresh > vlimit || ne >= max_elems) {
                if (nrec < rec_max) {
                    recs[nrec].vsrc = vsrc;
                    recs[nrec].first_element = type_first + first;
                    recs[nrec].num_elements = ne;
                    recs[nrec].num_vertices = nv;
                    recs[nrec].type = type;
                }
                ++nrec;
                ++epoch;
                nv = 0;
                ne = 0;
                first = e;
                vsrc = vpos;
            }
        }
        for (clvr_u32 k = 0; k < vpe; ++k) {
            const clvr_u32 id = ids[k];
            clvr_u32 lid = 0xffffffffu;
            for (clvr_u32 h = clvr_pp_hash_slot(id, log2cap);; h = (h + 1u) & mask) {
                clvr_u64 t = tk[h];
                if ((t >> 32) != epoch) {
                    tk[h] = (epoch << 32) | id;
                    tv[h] = lid = nv++;
                    vmap[vpos++] = id;
                    break;
                }
                if ((clvr_u32)t == id) { lid = tv[h]; break; }
            }
            if (bits32) idx32[s + k] = lid;
            else idx16[s + k] = (clvr_u16)lid;
        }
        ++ne;
    }
    if (ne > 0u) {
        if (nrec < rec_max) {
            recs[nrec].vsrc = vsrc;
            recs[nrec].first_element = type_first + first;
            recs[nrec].num_elements = ne;
            recs[nrec].num_vertices = nv;
            recs[nrec].type = type;
        }
        ++nrec;
    }
    return nrec;
}

#endif /* CLVR_REINDEX_H */
