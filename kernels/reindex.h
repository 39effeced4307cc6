/* reindex.h: the greedy instance split with per-instance re-indexing
 * (paper 3.2.2 and 3.3), compiled twice: the kernel runs it once per
 * segment, the host reference runs the very same code.
 *
 * Walking one segment of one type's curve-sorted elements, an element
 * joins the open instance unless that would make the instance reference
 * more than vlimit distinct vertices or hold more than max_elems elements;
 * then a new instance starts with it. While walking, every vertex id gets
 * its instance-local number on first use (a hash map vertex id -> local id
 * per worker, emptied when the instance closes),
 * the local index is written in place of the global one, and the vertex id
 * is appended to the instance's vertex list in the scratch map. This is the
 * paper's "flag used vertices, compact, permute" done in one pass: the hash
 * map is the flag array and the old->new permutation restricted to the
 * vertices the instance uses, so the cost is O(indices) instead of
 * O(vertices) per instance, and the vertex list comes out in first-use
 * order, which follows the curve (good locality when rendering).
 * Duplicated vertices across instances are kept, as in the paper.
 *
 * The hash map (linear probing, load factor <= 1/2) stores one 64-bit word
 * per slot, (vertex id + 1) << 32 | local id, 0 when empty, so a probe is
 * one load. Each vertex of an element is looked up once: a hit gives its
 * local id, a miss remembers where the probe stopped so that the insert
 * (when the element joins the instance) continues from there. Closing an
 * instance empties the map by deleting its vertices in reverse insertion
 * order: every slot on a vertex's probe path was filled before it, so the
 * path has no holes yet when the vertex is deleted (O(vertices of the
 * instance), where clearing the whole map would cost O(map size)). */
#ifndef CLVR_REINDEX_H
#define CLVR_REINDEX_H

#include "clvr_shared.h"

/* Home slot of vertex id in a map of 1 << log2cap slots (log2cap >= 4):
 * Fibonacci hashing of id / 8, keeping id % 8 as the low bits, so runs of
 * consecutive ids (an element's vertices along a grid row, a curve-ordered
 * mesh's neighbours) share a cache line of the map instead of taking one
 * miss each. The map (2^17 slots of 8 bytes for 16-bit instances) outgrows
 * the L2 cache, so this measured 2.1x faster on 10M hexes than hashing
 * the id itself; blocks still land at random, so no id pattern piles up. */
CLVR_INLINE clvr_u32 clvr_pp_hash_slot(clvr_u32 id, clvr_u32 log2cap)
{
    return (clvr_u32)(((id >> 3) * 0x9E3779B1u) >> (35u - log2cap)) << 3 | (id & 7u);
}

/* Empties the map of the instance whose vertex ids are vmap[v0 .. v1). */
CLVR_INLINE void clvr_pp_hash_clear(CLVR_GLOBAL clvr_u64 *tab, clvr_u32 log2cap, CLVR_GLOBAL const clvr_u32 *vmap,
                                    clvr_u64 v0, clvr_u64 v1)
{
    const clvr_u32 mask = (1u << log2cap) - 1u;
    for (clvr_u64 p = v1; p > v0; --p) {
        const clvr_u64 want = (clvr_u64)(vmap[p - 1u] + 1u) << 32;
        clvr_u32 h = clvr_pp_hash_slot(vmap[p - 1u], log2cap);
        while ((tab[h] & 0xffffffff00000000ull) != want) h = (h + 1u) & mask;
        tab[h] = 0;
    }
}

/* Closes the instance being grown (elements first_element ..
 * first_element + ne - 1, nv vertices whose ids are vmap[vsrc .. vpos)):
 * writes its record when there is room (every record is counted, so that
 * the caller sees an overflow) and clears its entries from the map. */
CLVR_FORCE_INLINE void clvr_pp_close_instance(CLVR_GLOBAL clvr_pp_instance_rec *recs, clvr_u32 *nrec,
                                              clvr_u32 rec_max, clvr_u64 vsrc, clvr_u32 first_element, clvr_u32 ne,
                                              clvr_u32 nv, clvr_u32 type, CLVR_GLOBAL clvr_u64 *tab,
                                              clvr_u32 log2cap, CLVR_GLOBAL const clvr_u32 *vmap, clvr_u64 vpos)
{
    if (*nrec < rec_max) {
        recs[*nrec].vsrc = vsrc;
        recs[*nrec].first_element = first_element;
        recs[*nrec].num_elements = ne;
        recs[*nrec].num_vertices = nv;
        recs[*nrec].type = type;
    }
    ++*nrec;
    clvr_pp_hash_clear(tab, log2cap, vmap, vsrc, vpos);
}

/* Greedy split and re-index of elements [e_begin, e_end) of one type
 * (indices relative to that type: element e's global sorted indices are
 * idx_sorted[slot0 + e * vpe ...]). Writes local indices to idx16 or idx32
 * at the same slots, vertex ids to vmap from slot0 + e_begin * vpe on
 * (each instance uses at most as many entries as it has index slots), and
 * at most rec_max records. tab is this worker's map of 1 << log2cap slots,
 * all zero on entry and on return. Returns the number of records. */
CLVR_INLINE clvr_u32 clvr_pp_split_segment(CLVR_GLOBAL const clvr_u32 *idx_sorted, CLVR_GLOBAL clvr_u32 *vmap,
                                           CLVR_GLOBAL clvr_u16 *idx16, CLVR_GLOBAL clvr_u32 *idx32, int bits32,
                                           clvr_u32 type, clvr_u32 type_first, clvr_u64 slot0, clvr_u32 e_begin,
                                           clvr_u32 e_end, clvr_u32 vlimit, clvr_u32 max_elems,
                                           CLVR_GLOBAL clvr_u64 *tab, clvr_u32 log2cap,
                                           CLVR_GLOBAL clvr_pp_instance_rec *recs, clvr_u32 rec_max)
{
    const clvr_u32 vpe = clvr_cell_vertex_count(type);
    const clvr_u32 mask = (1u << log2cap) - 1u;
    const clvr_u32 none = 0xffffffffu;
    clvr_u64 vpos = slot0 + (clvr_u64)e_begin * vpe, vsrc = vpos;
    clvr_u32 nv = 0, ne = 0, first = e_begin, nrec = 0;
    for (clvr_u32 e = e_begin; e < e_end; ++e) {
        const clvr_u64 s = slot0 + (clvr_u64)e * vpe;
        clvr_u32 ids[CLVR_CELL_MAX_VERTS], lid[CLVR_CELL_MAX_VERTS], at[CLVR_CELL_MAX_VERTS];
        clvr_u32 fresh = 0;
        for (clvr_u32 k = 0; k < vpe; ++k) {
            const clvr_u32 id = idx_sorted[s + k];
            const clvr_u64 want = (clvr_u64)(id + 1u) << 32;
            clvr_u32 h = clvr_pp_hash_slot(id, log2cap);
            clvr_u64 t;
            while ((t = tab[h]) != 0u && (t & 0xffffffff00000000ull) != want) h = (h + 1u) & mask;
            ids[k] = id;
            at[k] = h;
            lid[k] = t != 0u ? (clvr_u32)t : none;
            if (t == 0u) {
                clvr_u32 dup = 0;
                for (clvr_u32 j = 0; j < k; ++j) dup |= ids[j] == id;
                fresh += dup ? 0u : 1u;
            }
        }
        if (ne > 0u && (nv + fresh > vlimit || ne >= max_elems)) {
            clvr_pp_close_instance(recs, &nrec, rec_max, vsrc, type_first + first, ne, nv, type, tab, log2cap, vmap,
                                   vpos);
            nv = 0;
            ne = 0;
            first = e;
            vsrc = vpos;
            /* The map is empty: every vertex is new, probes restart at home. */
            for (clvr_u32 k = 0; k < vpe; ++k) {
                lid[k] = none;
                at[k] = clvr_pp_hash_slot(ids[k], log2cap);
            }
        }
        for (clvr_u32 k = 0; k < vpe; ++k) {
            clvr_u32 l = lid[k];
            if (l == none) {
                /* Continue the probe: an earlier vertex of this element may
                 * have taken the slot, or be this very vertex (repeated id). */
                const clvr_u64 want = (clvr_u64)(ids[k] + 1u) << 32;
                clvr_u32 h = at[k];
                clvr_u64 t;
                while ((t = tab[h]) != 0u && (t & 0xffffffff00000000ull) != want) h = (h + 1u) & mask;
                if (t != 0u) l = (clvr_u32)t;
                else {
                    l = nv++;
                    tab[h] = want | l;
                    vmap[vpos++] = ids[k];
                }
            }
            if (bits32) idx32[s + k] = l;
            else idx16[s + k] = (clvr_u16)l;
        }
        ++ne;
    }
    if (ne > 0u)
        clvr_pp_close_instance(recs, &nrec, rec_max, vsrc, type_first + first, ne, nv, type, tab, log2cap, vmap, vpos);
    return nrec;
}

#endif /* CLVR_REINDEX_H */
