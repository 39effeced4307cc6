/* locate.h: two-level point location in the clustered mesh, the software
 * stand-in for the paper's RT-core query (section 3.1, a ray with
 * tmin = tmax = 0 at the sample point): top-level tree over instance
 * clusters -> the instance's bottom-level tree over its leaf clusters ->
 * the leaf's elements, tested one by one with clvr_element_sample.
 * Compiled for the host (reference, tests) and for kernels. The first
 * element that contains the point wins; on a shared face that may be either
 * neighbour, and both interpolate the same value. */
#ifndef CLVR_LOCATE_H
#define CLVR_LOCATE_H

#include "clvr_shared.h"
#include "elements.h"
#include "bvh_traverse.h"
#include "bvh_build.h"

/* Walk counters for analysis tools (a tool defines it before including
 * this header); nothing in kernels or the library. */
#ifndef CLVR_WALK_STAT
#define CLVR_WALK_STAT(field) ((void)0)
#endif

/* One piece of the arrays that are split at instance boundaries
 * (CLVR_MAX_SPLITS, docs/large-meshes.md): an instance's vertices, local
 * indices and element boxes all live in the piece its `piece` field names. */
typedef struct clvr_piece_arrays {
    CLVR_GLOBAL const clvr_vec4 *vertices;
    CLVR_GLOBAL const clvr_u16 *idx16;
    CLVR_GLOBAL const clvr_u32 *idx32;
    CLVR_GLOBAL const clvr_u8 *ebox;  /* NULL: no element boxes */
} clvr_piece_arrays;

/* The arrays of a clustered mesh and its two-level tree that point location
 * reads, bundled so that the walk takes one argument instead of eight
 * (kernels build it on the stack from their arguments; the host points it
 * at host arrays). tlas_root: root of the top-level tree in tlas (0 for
 * clvr_bvh builds); each instance's bvh_root is its bottom-level root in
 * blas. leaf_size: elements per leaf cluster, as the clustering used.
 * vertices, idx16, idx32 and ebox are piece 0 of the split arrays (the whole
 * arrays of a mesh that is not split); `more` holds pieces 1 .. 3 (unused
 * entries may be anything: no instance names them). */
typedef struct clvr_mesh_view {
    CLVR_GLOBAL const clvr_bvh_node *tlas;
    CLVR_GLOBAL const clvr_bvh_node *blas;
    CLVR_GLOBAL const clvr_instance *instances;
    CLVR_GLOBAL const clvr_vec4 *vertices;
    CLVR_GLOBAL const clvr_u16 *idx16;
    CLVR_GLOBAL const clvr_u32 *idx32;
    clvr_u32 tlas_root;
    clvr_u32 leaf_size;
    /* Quantized element boxes (CLVR_EBOX_BYTES per sorted element, see
     * clvr_ebox_build_leaf), or NULL: leaves are then scanned without them
     * (same results, slower). Pieces 1 .. 3 use element boxes exactly when
     * this (piece 0's) is set. */
    CLVR_GLOBAL const clvr_u8 *ebox;
    clvr_piece_arrays more[CLVR_MAX_SPLITS - 1u];
    /* Entry grids (one per instance) and their cells, or NULL: walks then
     * start at each instance's root (same results, slower). Last, so that
     * an initializer that stops before them leaves them NULL. */
    CLVR_GLOBAL const clvr_entry_grid *entry_grids;
    CLVR_GLOBAL const clvr_u32 *entry_cells;
} clvr_mesh_view;
/* Initializer of `more` for a mesh that is one piece. */
#define CLVR_VIEW_ONE_PIECE {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}}

/* The arrays of instance inst's piece: picked once when a walk enters the
 * instance (a branch per instance visited, never per element). Element e's
 * box is entry e - inst->piece_first_element of the piece's ebox. */
CLVR_INLINE clvr_piece_arrays clvr_view_piece(const clvr_mesh_view *m, const clvr_instance *inst)
{
    clvr_piece_arrays a;
    switch (inst->piece) {
    case 1u: a = m->more[0]; break;
    case 2u: a = m->more[1]; break;
    case 3u: a = m->more[2]; break;
    default:
        a.vertices = m->vertices;
        a.idx16 = m->idx16;
        a.idx32 = m->idx32;
        a.ebox = m->ebox;
        break;
    }
    if (!m->ebox) a.ebox = 0;
    return a;
}

/* Global sorted ids of leaf cluster `leaf`'s elements: first (returned) ..
 * *end - 1; an instance's last leaf may hold fewer than leaf_size. */
CLVR_INLINE clvr_u32 clvr_leaf_elements(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 leaf,
                                        clvr_u32 *end)
{
    const clvr_u32 first = inst->first_element + (leaf - inst->first_leaf) * m->leaf_size;
    const clvr_u32 end_inst = inst->first_element + inst->num_elements;
    *end = end_inst - first < m->leaf_size ? end_inst : first + m->leaf_size;
    return first;
}

/* Loads the vertices of element e (global sorted id, inside instance
 * `inst`, whose piece's arrays are a) into v[0 .. vertex_count(inst->type) - 1]. */
CLVR_INLINE void clvr_load_element_in(const clvr_piece_arrays *a, const clvr_instance *inst, clvr_u32 e,
                                      clvr_vec4 *v)
{
    CLVR_GLOBAL const clvr_vec4 *vertices = a->vertices;
    CLVR_GLOBAL const clvr_u16 *idx16 = a->idx16;
    CLVR_GLOBAL const clvr_u32 *idx32 = a->idx32;
    const clvr_u32 nv = clvr_cell_vertex_count(inst->type);
    const clvr_u64 base = inst->first_index + (clvr_u64)(e - inst->first_element) * nv;
    if (inst->index_bits == 16u) {
        for (clvr_u32 k = 0; k < nv; ++k) v[k] = vertices[inst->first_vertex + (clvr_u32)idx16[base + k]];
    } else {
        for (clvr_u32 k = 0; k < nv; ++k) v[k] = vertices[inst->first_vertex + idx32[base + k]];
    }
}

/* clvr_load_element_in with the piece picked from m (for callers that load
 * one element of an instance, not a walk). */
CLVR_INLINE void clvr_load_element(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 e, clvr_vec4 *v)
{
    const clvr_piece_arrays a = clvr_view_piece(m, inst);
    clvr_load_element_in(&a, inst, e, v);
}

/* Element e of inst as the cell it is: returns its type and loads its
 * vertices into v (VTK order). That is inst's type, except for a hex with
 * repeated corners (the tets, pyramids and wedges of a mesh preprocessed
 * on one curve, clvr_preprocess_options.one_curve, or a file's degenerate
 * HEX8), which is the type it collapses to, v then holding that type's
 * vertices (clvr_hex_collapsed). The renderer's walk and the hull take
 * cells this way, so that such a cell has its own type's faces, exits and
 * linear spans. */
CLVR_INLINE clvr_u32 clvr_load_cell_in(const clvr_piece_arrays *a, const clvr_instance *inst, clvr_u32 e,
                                       clvr_vec4 *v)
{
    clvr_load_element_in(a, inst, e, v);
    if (inst->type != CLVR_CELL_HEX) return inst->type;
    clvr_vec4 c[6];
    const clvr_u32 t = clvr_hex_collapsed(v, c);
    for (clvr_u32 k = 0; t != CLVR_CELL_HEX && k < clvr_cell_vertex_count(t); ++k) v[k] = c[k];
    return t;
}

/* Loads tet e's 4 vertices (one 8-byte index load on the device for
 * 16-bit instances). */
CLVR_INLINE void clvr_load_tet(const clvr_piece_arrays *a, const clvr_instance *inst, clvr_u32 e, clvr_vec4 *v)
{
    CLVR_GLOBAL const clvr_u16 *idx16 = a->idx16;
    CLVR_GLOBAL const clvr_u32 *idx32 = a->idx32;
    const clvr_u64 base = inst->first_index + (clvr_u64)(e - inst->first_element) * 4u;
    CLVR_GLOBAL const clvr_vec4 *vb = a->vertices + inst->first_vertex;
    if (inst->index_bits == 16u) {
#ifdef __OPENCL_VERSION__
        const ushort4 k = vload4(0, idx16 + base);
        v[0] = vb[k.x]; v[1] = vb[k.y]; v[2] = vb[k.z]; v[3] = vb[k.w];
#else
        for (int k = 0; k < 4; ++k) v[k] = vb[idx16[base + k]];
#endif
    } else {
        for (int k = 0; k < 4; ++k) v[k] = vb[idx32[base + k]];
    }
}

/* Prefetches the first line of leaf cluster `leaf`'s index block (instance
 * inst): the line its search, or clvr_prefetch_leaf_vertices, stalls on
 * first. */
CLVR_INLINE void clvr_prefetch_leaf(const clvr_mesh_view *m, const clvr_piece_arrays *a, const clvr_instance *inst,
                                    clvr_u32 leaf)
{
    const clvr_u32 nv = clvr_cell_vertex_count(inst->type);
    const clvr_u64 base = inst->first_index + (clvr_u64)(leaf - inst->first_leaf) * m->leaf_size * nv;
    if (inst->index_bits == 16u) CLVR_PREFETCH(a->idx16 + base);
    else CLVR_PREFETCH(a->idx32 + base);
}

/* Prefetches what the search of leaf cluster `leaf` will load first: for
 * tets, the vertices of all its elements (reading its indices, which the
 * parent's visit prefetched), so that the vertex misses of a leaf overlap
 * instead of waiting one tet, and one mispredicted box test, after another;
 * for other types, its index block. Called for every leaf a node's box test
 * finds, before any of them is searched. Measured on PoCL (1M tets, 1M
 * random points, leaf clusters of 8, interleaved runs): +9% for the
 * vertices of the leaf being searched, +2% to +7% more for those of its hit
 * siblings too. */
CLVR_INLINE void clvr_prefetch_leaf_vertices(const clvr_mesh_view *m, const clvr_piece_arrays *a,
                                             const clvr_instance *inst, clvr_u32 leaf)
{
    if (inst->type != CLVR_CELL_TET) {
        clvr_prefetch_leaf(m, a, inst, leaf);
        return;
    }
    CLVR_GLOBAL const clvr_u16 *idx16 = a->idx16;
    CLVR_GLOBAL const clvr_u32 *idx32 = a->idx32;
    clvr_u32 end;
    const clvr_u32 first = clvr_leaf_elements(m, inst, leaf, &end);
    CLVR_GLOBAL const clvr_vec4 *vb = a->vertices + inst->first_vertex;
    const clvr_u64 base = inst->first_index + (clvr_u64)(first - inst->first_element) * 4u;
    for (clvr_u32 i = 0; i < 4u * (end - first); ++i)
        CLVR_PREFETCH(vb + (inst->index_bits == 16u ? (clvr_u32)idx16[base + i] : idx32[base + i]));
}

/* ------------------------------------------------------------ element boxes
 * Each element's padded vertex box (the one clvr_element_box_test accepts),
 * quantized to 8 bits per bound relative to its leaf cluster's box as the
 * leaf's parent node stores it: lo x y z, hi x y z, one byte each, rounded
 * outward by one more step. A leaf scan then rejects most candidates with
 * one 6-byte load each instead of loading and boxing their vertices
 * (index load, then dependent vertex loads): perf on tets-1M (leaves of 16,
 * urm frames) put 68% of the frame in that scan. The filter only rejects
 * elements whose padded box misses p, which the exact test after it would
 * reject too, so point location returns the same element bit for bit. */
#define CLVR_EBOX_BYTES 6u

/* Prefetches all of leaf cluster `leaf`'s element boxes and index block:
 * called for a hint's leaf before its parent node is read, so that those
 * misses overlap the node's instead of following it (the element boxes
 * wait for the node's box, the index block for the boxes' pass). PoCL
 * bench_locate, alternating kernels (session 53): the igloo +8% random
 * (10 pairs) and +4% ray-ordered (10 pairs, every one faster), post-tets
 * +11%, the 1M tets +13%, gmsh layers +9%, fire_ug's hexes +7% (random,
 * 6-8 pairs), the blunt fin 0% random and +10% rays. */
CLVR_INLINE void clvr_prefetch_hint_leaf(const clvr_mesh_view *m, const clvr_piece_arrays *a,
                                         const clvr_instance *inst, clvr_u32 leaf)
{
    clvr_u32 end;
    const clvr_u32 first = clvr_leaf_elements(m, inst, leaf, &end);
    if (end <= first) return;
    if (a->ebox) {
        CLVR_GLOBAL const clvr_u8 *eb = a->ebox + (clvr_u64)(first - inst->piece_first_element) * CLVR_EBOX_BYTES;
        CLVR_PREFETCH(eb);
        CLVR_PREFETCH(eb + CLVR_EBOX_BYTES * (end - first) - 1u);
    }
    const clvr_u32 nv = clvr_cell_vertex_count(inst->type);
    const clvr_u64 base = inst->first_index + (clvr_u64)(first - inst->first_element) * nv;
    const clvr_u32 bytes = (end - first) * nv * (inst->index_bits / 8u);
    CLVR_GLOBAL const clvr_u8 *ib = inst->index_bits == 16u ? (CLVR_GLOBAL const clvr_u8 *)(a->idx16 + base)
                                                              : (CLVR_GLOBAL const clvr_u8 *)(a->idx32 + base);
    for (clvr_u32 o = 0; o < bytes; o += CLVR_CACHE_LINE) CLVR_PREFETCH(ib + o);
    CLVR_PREFETCH(ib + bytes - 1u);
}

/* Index of the lowest set bit of x != 0. */
CLVR_INLINE clvr_u32 clvr_ctz32(clvr_u32 x)
{
#ifdef __OPENCL_VERSION__
    return 31u - clz(x & (0u - x));
#else
    return (clvr_u32)__builtin_ctz(x);
#endif
}
#define CLVR_EBOX_STEPS 255.0f

/* Steps per unit length along an axis of extent [lo, hi]; 0 for a flat or
 * tiny extent (every element then spans the whole axis). */
CLVR_INLINE float clvr_ebox_scale(float lo, float hi)
{
    const float d = hi - lo;
    return d > 1e-30f ? CLVR_EBOX_STEPS / d : 0.0f;
}

/* x's position in steps from lo, clamped to [0, CLVR_EBOX_STEPS]: the same
 * expression for building and querying, and monotonic in x, so the one
 * step of margin covers any rounding between the two. */
CLVR_INLINE float clvr_ebox_pos(float x, float lo, float scale)
{
    return fmin(fmax((x - lo) * scale, 0.0f), CLVR_EBOX_STEPS);
}

/* Quantizes the boxes of leaf cluster `leaf`'s elements against the leaf
 * box (lo, hi) into ebox, the element boxes of inst's piece
 * (CLVR_EBOX_BYTES per element, from the piece's first element,
 * inst->piece_first_element). */
CLVR_INLINE void clvr_ebox_build_leaf(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 leaf,
                                      const float *lo, const float *hi, CLVR_GLOBAL clvr_u8 *ebox)
{
    const clvr_piece_arrays pa = clvr_view_piece(m, inst);
    clvr_u32 end;
    const clvr_u32 first = clvr_leaf_elements(m, inst, leaf, &end);
    float scale[3];
    for (int k = 0; k < 3; ++k) scale[k] = clvr_ebox_scale(lo[k], hi[k]);
    clvr_vec4 v[CLVR_CELL_MAX_VERTS];
    for (clvr_u32 e = first; e < end; ++e) {
        clvr_load_element_in(&pa, inst, e, v);
        float elo[3], ehi[3];
        /* Twice clvr_element_box_test's padding: this box must hold every
         * point that test accepts. */
        const float pad = 2.0f * clvr_element_vertex_box(inst->type, v, elo, ehi);
        CLVR_GLOBAL clvr_u8 *out = ebox + (clvr_u64)(e - inst->piece_first_element) * CLVR_EBOX_BYTES;
        for (int k = 0; k < 3; ++k) {
            const float a = floor(clvr_ebox_pos(elo[k] - pad, lo[k], scale[k])) - 1.0f;
            const float b = ceil(clvr_ebox_pos(ehi[k] + pad, lo[k], scale[k])) + 1.0f;
            out[k] = (clvr_u8)fmax(a, 0.0f);
            out[3 + k] = (clvr_u8)fmin(b, CLVR_EBOX_STEPS);
        }
    }
}

/* Tests the elements of leaf cluster `leaf` of instance inst (whose box,
 * as its parent node n stores it in slot c, holds p); returns 1 and the
 * scalar and element id of the first one that contains p. Candidates are
 * first rejected by their quantized box (when m->ebox is set), then by
 * their vertex box (cheaper than a solve; tets skip it behind a quantized
 * box); tets then take the early-out barycentric test (on a CPU device four
 * at a time, clvr_tet_sample4), other types Newton.
 * skip_elem: an element not tested (its caller has just found it outside
 * p), or CLVR_BVH_NOT_FOUND. */
CLVR_INLINE int clvr_locate_in_leaf(const clvr_mesh_view *m, const clvr_piece_arrays *a, const clvr_instance *inst,
                                    clvr_u32 leaf, CLVR_GLOBAL const clvr_bvh_node *n, clvr_u32 c, float px,
                                    float py, float pz, clvr_u32 skip_elem, float *scalar, clvr_u32 *element_id)
{
    clvr_u32 end;
    const clvr_u32 first = clvr_leaf_elements(m, inst, leaf, &end);
    CLVR_GLOBAL const clvr_u8 *eb = a->ebox;
    if (eb && inst->type == CLVR_CELL_TET && inst->index_bits == 16u) {
        /* The index block's lines (the first candidate's load waits on
         * them) are asked for before the pass over the boxes. */
        CLVR_GLOBAL const clvr_u8 *ib =
            (CLVR_GLOBAL const clvr_u8 *)(a->idx16 + inst->first_index + (clvr_u64)(first - inst->first_element) * 4u);
        CLVR_PREFETCH(ib);
        CLVR_PREFETCH(ib + CLVR_CACHE_LINE);
    }
    /* p's step on each axis of the leaf box (floor: a step test that is
     * at least as permissive as the float one). */
    clvr_u32 ix = 0, iy = 0, iz = 0;
    if (eb) {
        ix = (clvr_u32)clvr_ebox_pos(px, n->lo_x[c], clvr_ebox_scale(n->lo_x[c], n->hi_x[c]));
        iy = (clvr_u32)clvr_ebox_pos(py, n->lo_y[c], clvr_ebox_scale(n->lo_y[c], n->hi_y[c]));
        iz = (clvr_u32)clvr_ebox_pos(pz, n->lo_z[c], clvr_ebox_scale(n->lo_z[c], n->hi_z[c]));
    }
#if defined(__OPENCL_VERSION__) && defined(CLVR_DEVICE_SIMD)
    clvr_vec4 v[16 > CLVR_CELL_MAX_VERTS ? 16 : CLVR_CELL_MAX_VERTS]; /* four tets */
#else
    clvr_vec4 v[CLVR_CELL_MAX_VERTS];
#endif
    for (clvr_u32 base = first; base < end; base += 32u) {
        const clvr_u32 cnt = end - base < 32u ? end - base : 32u;
        /* Candidates, 32 at a time: a branch-free pass over their quantized
         * boxes, then only the survivors' vertices are loaded. */
        clvr_u32 mask = cnt == 32u ? 0xffffffffu : (1u << cnt) - 1u;
        if (eb) {
            clvr_u32 pass = 0;
            for (clvr_u32 k = 0; k < cnt; ++k) {
                CLVR_GLOBAL const clvr_u8 *b = eb + (clvr_u64)(base + k - inst->piece_first_element) * CLVR_EBOX_BYTES;
                pass |= (clvr_u32)((ix >= b[0]) & (iy >= b[1]) & (iz >= b[2]) & (ix <= b[3]) & (iy <= b[4]) &
                                   (iz <= b[5]))
                        << k;
            }
            mask = pass;
        }
        if (skip_elem - base < cnt) mask &= ~(1u << (skip_elem - base));
#if defined(__OPENCL_VERSION__) && defined(CLVR_DEVICE_SIMD)
        if (inst->type == CLVR_CELL_TET) {
            /* Candidates four at a time, in order, on SIMD lanes: the first
             * that holds p wins, as one by one. A point passes about 4 tet
             * boxes on tet-cut hexes (their 6 tets share the hex's box),
             * and one by one each failed early-out test was a mispredicted
             * branch: bench_locate random points +10-12% (blunt fin, post,
             * combustor), ray-ordered +9-15%; urm frames 6-7% shorter (post,
             * combustor, 1M tets); eight at a time (float8) was no faster. */
            while (mask) {
                clvr_u32 e4[4], n4 = 0;
                while (mask && n4 < 4u) {
                    const clvr_u32 k = clvr_ctz32(mask);
                    mask &= mask - 1u;
                    e4[n4++] = base + k;
                }
                for (clvr_u32 j = n4; j < 4u; ++j) e4[j] = e4[0];
                for (clvr_u32 j = 0; j < 4u; ++j) clvr_load_tet(a, inst, e4[j], v + 4u * j);
                float4 s4;
                const clvr_u32 hit = clvr_tet_sample4(v, px, py, pz, &s4) & ((1u << n4) - 1u);
                if (hit) {
                    const clvr_u32 j = clvr_ctz32(hit);
                    *scalar = j == 0u ? s4.x : j == 1u ? s4.y : j == 2u ? s4.z : s4.w;
                    *element_id = e4[j];
                    return 1;
                }
            }
            continue;
        }
#endif
        while (mask) {
            const clvr_u32 k = clvr_ctz32(mask);
            mask &= mask - 1u;
            const clvr_u32 e = base + k;
            CLVR_WALK_STAT(ecand);
            if (inst->type == CLVR_CELL_TET) {
                clvr_load_tet(a, inst, e, v);
                /* Past its quantized box, a tet goes straight to the
                 * barycentric test: the float box (padded 1e-4 of the
                 * extent, more than the test's 1e-5 tolerance reaches
                 * outside the tet) rejected 5% of the candidates there and
                 * cost 5% of a urm frame on post-tets. Same answers: that
                 * box holds every point the test accepts. */
                if (!eb && !clvr_element_box_test(CLVR_CELL_TET, v, px, py, pz)) continue;
                CLVR_WALK_STAT(etest);
                if (clvr_tet_sample(v, px, py, pz, scalar)) {
                    *element_id = e;
                    return 1;
                }
                continue;
            }
            clvr_load_element_in(a, inst, e, v);
            if (!clvr_element_box_test(inst->type, v, px, py, pz)) continue;
            CLVR_WALK_STAT(etest);
            if (clvr_element_sample(inst->type, v, px, py, pz, scalar)) {
                *element_id = e;
                return 1;
            }
        }
    }
    return 0;
}

/* First node of instance inst's lowest level (whose children are leaves):
 * node level0 + m covers leaves 4m .. 4m + 3. Equals bvh_root +
 * clvr_bvh_level_first(num_leaves, 0) of bvh_build.h (test_bvh checks),
 * without its O(height^2) loops: those, run per instance visit, cost
 * sorted points 9%. */
CLVR_INLINE clvr_u32 clvr_locate_level0(const clvr_instance *inst)
{
    clvr_u32 level0 = inst->bvh_root;
    for (clvr_u32 s = (inst->num_leaves + 3u) / 4u; s > 1u;) {
        s = (s + 3u) / 4u;
        level0 += s;
    }
    return level0;
}

/* Node and child slot that hold leaf cluster `leaf` of instance inst: the
 * lowest level's node level0 + m holds leaves 4m .. 4m + 3. */
CLVR_INLINE void clvr_leaf_parent(const clvr_instance *inst, clvr_u32 leaf, clvr_u32 *node, clvr_u32 *slot)
{
    *node = clvr_locate_level0(inst) + (leaf - inst->first_leaf) / 4u;
    *slot = (leaf - inst->first_leaf) % 4u;
}

/* CLVR_LOCATE_INCOHERENT: asks for the lines of every child in mask of node
 * n before any is searched, so that their misses overlap: for a leaf, its
 * tets' vertices (clvr_prefetch_leaf_vertices); for an inner node, its two
 * lines and, on the lowest level, its four leaves' index blocks (random
 * points search about 40% of them: 13.0 nodes, 2.45 leaves, 16.1 tets per
 * query on 1M tets, leaves of 8). One level further (a level-1 node's four
 * children, 7 lines) lost 5% and is not done. */
CLVR_INLINE void clvr_locate_prefetch_children(const clvr_mesh_view *m, const clvr_piece_arrays *a,
                                               const clvr_instance *inst, CLVR_GLOBAL const clvr_bvh_node *n,
                                               clvr_u32 mask, clvr_u32 level0)
{
    CLVR_GLOBAL const clvr_bvh_node *blas = m->blas;
    for (clvr_u32 c = 0; c < 4; ++c) {
        if (!((mask >> c) & 1u)) continue;
        const clvr_u32 ch = n->child[c];
        if (ch & CLVR_BVH_LEAF_BIT) {
            clvr_u32 end;
            if (a->ebox) /* the scan reads its boxes first, then a few survivors */
                CLVR_PREFETCH(a->ebox + (clvr_u64)(clvr_leaf_elements(m, inst, ch & CLVR_BVH_MAX_PRIMS, &end) -
                                                   inst->piece_first_element) *
                                            CLVR_EBOX_BYTES);
            else
                clvr_prefetch_leaf_vertices(m, a, inst, ch & CLVR_BVH_MAX_PRIMS);
            continue;
        }
        CLVR_PREFETCH(blas + ch);
        CLVR_PREFETCH((CLVR_GLOBAL const clvr_u8 *)(blas + ch) + CLVR_CACHE_LINE);
        if (ch >= level0) {
            const clvr_u32 leaf = inst->first_leaf + 4u * (ch - level0);
            for (clvr_u32 j = 0; j < 4u && leaf + j < inst->first_leaf + inst->num_leaves; ++j)
                clvr_prefetch_leaf(m, a, inst, leaf + j);
        }
    }
}

/* Walks instance inst's bottom-level tree: every leaf cluster whose box
 * holds p is searched as soon as its parent's box test finds it (no stack
 * round trip for primitives); inner children go on a private stack.
 * Measured on PoCL (1M tets, bench_locate): this beats the generic
 * iterator by 35% on coherent and 50-80% on random queries; collecting all
 * candidate leaves first to search the deepest-inside first (fewer leaves
 * searched) lost about 10% on coherent queries and gained nothing clear on
 * random ones, so leaves are searched in traversal order. hints: see
 * CLVR_LOCATE_INCOHERENT; results do not depend on them. skip, skip2:
 * inner nodes whose subtrees are not entered (ones already searched), or
 * CLVR_BVH_NOT_FOUND; skip_elem: as clvr_locate_in_leaf's. */
CLVR_INLINE int clvr_locate_in_instance(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 root,
                                        clvr_u32 skip, clvr_u32 skip2, float px, float py, float pz, clvr_u32 hints,
                                        clvr_u32 skip_elem, float *scalar, clvr_u32 *element_id,
                                        clvr_u32 *leaf_found)
{
    CLVR_GLOBAL const clvr_bvh_node *blas = m->blas;
    const clvr_piece_arrays a = clvr_view_piece(m, inst); /* once per instance entered */
    CLVR_WALK_STAT(inst);
    clvr_u32 stack[CLVR_BVH_STACK_SIZE];
    clvr_u32 sp = 0, ref = root;
    const int prefetch = (hints & CLVR_LOCATE_INCOHERENT) != 0u;
    const clvr_u32 level0 = prefetch ? clvr_locate_level0(inst) : 0u;
    for (;;) {
        CLVR_GLOBAL const clvr_bvh_node *n = blas + ref;
        CLVR_WALK_STAT(bnodes);
        const clvr_u32 mask = clvr_bvh_node_point_mask(n, px, py, pz);
        if (prefetch)
            clvr_locate_prefetch_children(m, &a, inst, n, mask, level0);
        for (clvr_u32 c = 0; c < 4; ++c) {
            if (!((mask >> c) & 1u)) continue;
            const clvr_u32 ch = n->child[c];
            if (ch & CLVR_BVH_LEAF_BIT) {
                CLVR_WALK_STAT(leaves);
                if (clvr_locate_in_leaf(m, &a, inst, ch & CLVR_BVH_MAX_PRIMS, n, c, px, py, pz, skip_elem, scalar,
                                        element_id)) {
                    *leaf_found = ch & CLVR_BVH_MAX_PRIMS;
                    return 1;
                }
            } else if (sp < CLVR_BVH_STACK_SIZE && ch != skip && ch != skip2) {
                stack[sp++] = ch;
            }
        }
        if (sp == 0) return 0;
        ref = stack[--sp];
    }
}

/* ------------------------------------------------------------ entry grids
 * A random point's walk from an instance's root tests the nodes on the way
 * down to the leaves near it (7 levels for the blunt fin's 14k leaf
 * clusters) and the siblings whose boxes overlap: 9.5 bottom-level nodes
 * per random query there, 12 on post-tets. Each instance therefore gets a
 * uniform grid over its box, about CLVR_ENTRY_CELLS_PER_LEAF cells per
 * leaf cluster (cells about cubic), and each cell two nodes of the
 * instance's tree:
 *  - start: the lowest common ancestor of every leaf cluster with an
 *    element whose (padded) box meets the cell (CLVR_BVH_NOT_FOUND when
 *    none does: no element there; clvr_entry_element_hull). The box of an
 *    element that holds a point meets the point's cell (a coordinate's
 *    cell is one monotonic map, for points and box corners alike), so a
 *    walk from start finds what a walk from the root finds.
 *  - hint: the leaf cluster holding the element where the cell's centre
 *    lies (or an octant's centre, clvr_entry_hint; CLVR_BVH_NOT_FOUND when
 *    none lies in an element). A query
 *    searches it first, then the other leaves of its lowest-level node
 *    (4 leaf clusters) whose boxes hold the point, then the rest of
 *    start's subtree.
 * Host reference walk, random points, leaves of 16, 2 cells per leaf:
 * bottom-level nodes per query 9.45 -> 2.50 (blunt fin), 12.04 -> 3.61
 * (post-tets), leaves 1.71 -> 1.32 and 2.67 -> 1.85; the hint's node holds
 * the point 77% and 66% of the time. PoCL, bench_locate_embree: the blunt
 * fin 0.92-0.96x -> about 1.47x Embree 3's queries/s (the hint leaf
 * searched before its siblings: +5% of that). The start alone (no hint) halved the host walk's
 * nodes and gained about nothing on PoCL: the levels it skips are the
 * cached ones; 4 or 8 cells per leaf were no faster (more leaves per
 * query). As with a ray's hint, the element found may differ from a walk
 * from the root only where two elements share the point, with the same
 * value. Memory: 8 bytes per cell, 1 byte per element at leaves of 16. */
#define CLVR_ENTRY_CELLS_PER_LEAF 2u
/* Cells per leaf cluster of the types that take Newton's test (hexes,
 * wedges, pyramids): a search of a leaf that does not hold the point costs
 * them Newton solves where tets take a four-lane barycentric test, so a
 * hint that holds more often pays for the larger grid there. Host walk,
 * the OpenFOAM igloo (328k mixed), random points found, 2 / 4 / 8 / 16
 * cells per leaf: bottom nodes 4.70 / 4.12 / 3.27 / 2.93, leaves 2.11 /
 * 1.99 / 1.82 / 1.71. PoCL bench_locate, random points, alternating runs,
 * 8 against 2: the igloo median +8% (10 pairs, 0.93x-1.31x), clvr-gen amr
 * (523k graded hexes) +1% and +6% (8 pairs, twice), while the blunt fin
 * (tets only, so the same grids: this VM's noise) read +2%; clvr-gen mixed
 * (the default scene) unchanged. For tets 8 gained nothing (blunt fin
 * -9%, -3%, 0; post, the igloo cut into tets and gmsh-point within
 * noise). 4 bytes per element at leaves of 16. */
#define CLVR_ENTRY_CELLS_PER_LEAF_NEWTON 8u
/* At most this many cells per axis. */
#define CLVR_ENTRY_MAX_RES 1024u

/* Cell of coordinate x on an axis of grid (lo, scale, res): monotonic in x
 * (a subtraction and a product by scale >= 0 round monotonically), clamped
 * to the grid, so a point outside it (or NaN, which fmax turns into 0)
 * still gets a cell; a box [a, b] meets cells coord(a) .. coord(b). */
CLVR_INLINE clvr_u32 clvr_entry_coord(float x, float lo, float scale, clvr_u32 res)
{
    return (clvr_u32)fmin(fmax((x - lo) * scale, 0.0f), (float)(res - 1u));
}

/* Cells a[k] .. b[k] (per axis) that box lo .. hi meets in grid g. */
CLVR_INLINE void clvr_entry_box_cells(const clvr_entry_grid *g, const float *lo, const float *hi, clvr_u32 *a,
                                      clvr_u32 *b)
{
    for (int k = 0; k < 3; ++k) {
        a[k] = clvr_entry_coord(lo[k], g->lo[k], g->scale[k], g->res[k]);
        b[k] = clvr_entry_coord(hi[k], g->lo[k], g->scale[k], g->res[k]);
    }
}

/* Element hulls for the occupancy grid: a cell that an element's padded
 * box meets may still lie wholly outside the element, as cells past a
 * curved wall do for the elements along it (their boxes reach into the
 * body). Slabs along the element's face normals cut those off: every point
 * of an element of any type lies in the convex hull of its vertices (its
 * map is a blend of them with non-negative weights), so for any direction
 * n, n . x over the element lies between the least and the greatest
 * n . v over its vertices. The slabs are therefore sound whatever normals
 * they take; face normals make them tight. Each is widened by twice the
 * box's padding times |n|_1 (>= |n|) so that it holds every point the
 * containment tests accept, as the box does; the cells' own 1/64-cell
 * margin (clvr_entry_cell_span) already covers that reach for elements
 * under about a thousand cells, so test_bvh cannot tell the two apart.
 * A triangle repeats its last vertex: (c - a) x (d - b) is then its
 * normal too; rows past a type's face count (clvr_element_slabs.faces)
 * are never read.
 * Measured (session 53, 2-core Xeon VM, PoCL): random points whose bit is
 * clear on the igloo 44.6% -> 46.2%, those left in an occupied cell but in
 * no element 4.7% -> 3.2% (their 13.7% of a host walk's time -> 10.6%);
 * post-tets and the blunt fin +0.2-0.3% clear. bench_locate on the igloo,
 * alternating kernels: random +5% (median of 30 pairs, 19 faster), rays
 * +3% (38 pairs, 22 faster). Whole preprocessing of the 1M tets unchanged
 * (0.71 against 0.70-0.75 s) since only cells not set yet are tested. */
#ifdef __OPENCL_VERSION__
#define CLVR_FACE_TABLE __constant
#else
#define CLVR_FACE_TABLE static const
#endif
#define CLVR_ELEMENT_MAX_FACES 6u
CLVR_FACE_TABLE clvr_u8 clvr_element_faces[CLVR_CELL_TYPE_COUNT][CLVR_ELEMENT_MAX_FACES][4] = {
    {{0, 1, 3, 3}, {1, 2, 3, 3}, {2, 0, 3, 3}, {0, 2, 1, 1}, {0, 1, 3, 3}, {0, 1, 3, 3}},
    {{0, 3, 2, 1}, {0, 1, 4, 4}, {1, 2, 4, 4}, {2, 3, 4, 4}, {3, 0, 4, 4}, {3, 0, 4, 4}},
    {{0, 1, 2, 2}, {3, 5, 4, 4}, {0, 3, 4, 1}, {1, 4, 5, 2}, {2, 5, 3, 0}, {2, 5, 3, 0}},
    {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}};

typedef struct clvr_element_slabs {
    float o[3];                             /* vertex 0: the slabs are about it */
    float n[CLVR_ELEMENT_MAX_FACES][3];     /* face normals (not unit) */
    float lo[CLVR_ELEMENT_MAX_FACES];       /* n . (x - o) of every accepted x lies in [lo, hi] */
    float hi[CLVR_ELEMENT_MAX_FACES];
    clvr_u32 faces;                         /* 4 (tet), 5 (pyramid, wedge) or 6 (hex) */
} clvr_element_slabs;

/* The slabs of an element of the given type with vertices v, pad being
 * clvr_element_vertex_box's padding of it. */
CLVR_INLINE void clvr_element_slabs_of(clvr_u32 type, const clvr_vec4 *v, float pad, clvr_element_slabs *s)
{
#ifdef __OPENCL_VERSION__
    /* No fused multiply-add: the device's bits equal the host's (test_bvh
     * compares the occupancy words). */
#pragma OPENCL FP_CONTRACT OFF
#endif
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    s->faces = type == CLVR_CELL_TET ? 4u : type == CLVR_CELL_HEX ? 6u : 5u;
    s->o[0] = v[0].x;
    s->o[1] = v[0].y;
    s->o[2] = v[0].z;
    float r[CLVR_CELL_MAX_VERTS][3];
    for (clvr_u32 i = 0; i < nv; ++i) {
        r[i][0] = v[i].x - s->o[0];
        r[i][1] = v[i].y - s->o[1];
        r[i][2] = v[i].z - s->o[2];
    }
    for (clvr_u32 f = 0; f < s->faces; ++f) {
        const clvr_u32 a = clvr_element_faces[type][f][0], b = clvr_element_faces[type][f][1],
                       c = clvr_element_faces[type][f][2], d = clvr_element_faces[type][f][3];
        const float ux = r[c][0] - r[a][0], uy = r[c][1] - r[a][1], uz = r[c][2] - r[a][2];
        const float wx = r[d][0] - r[b][0], wy = r[d][1] - r[b][1], wz = r[d][2] - r[b][2];
        const float nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
        float lo = 0.0f, hi = 0.0f; /* vertex 0 is at the origin */
        for (clvr_u32 i = 1; i < nv; ++i) {
            const float t = nx * r[i][0] + ny * r[i][1] + nz * r[i][2];
            lo = fmin(lo, t);
            hi = fmax(hi, t);
        }
        const float m = 2.0f * pad * (fabs(nx) + fabs(ny) + fabs(nz));
        s->n[f][0] = nx;
        s->n[f][1] = ny;
        s->n[f][2] = nz;
        s->lo[f] = lo - m;
        s->hi[f] = hi + m;
    }
}

/* Bounds of cell c along axis k of grid g, as a box that holds every
 * coordinate clvr_entry_coord maps to c: widened by 1/64 of a cell and by
 * a few ulps of the grid's coordinates (the subtraction of lo rounds at
 * their scale), and open towards the outside at the grid's ends, where
 * the clamp sends every coordinate beyond them. */
CLVR_INLINE void clvr_entry_cell_span(const clvr_entry_grid *g, int k, clvr_u32 c, float *lo, float *hi)
{
#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#endif
    if (!(g->scale[k] > 0.0f)) {
        *lo = -INFINITY;
        *hi = INFINITY;
        return;
    }
    const float w = 1.0f / g->scale[k];
    const float slop = w * (1.0f / 64.0f) + 8.0f * 1.1920929e-7f * (fabs(g->lo[k]) + (float)g->res[k] * w);
    *lo = c == 0u ? -INFINITY : g->lo[k] + (float)c * w - slop;
    *hi = c + 1u >= g->res[k] ? INFINITY : g->lo[k] + (float)(c + 1u) * w + slop;
}

/* n * (x - o) at the ends of span [lo, hi] (lo may be -inf, hi +inf):
 * the least in *tl, the greatest in *th; 0 for n = 0 (no 0 * inf). */
CLVR_INLINE void clvr_slab_terms(float n, float o, float lo, float hi, float *tl, float *th)
{
#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#endif
    *tl = n > 0.0f ? n * (lo - o) : n < 0.0f ? n * (hi - o) : 0.0f;
    *th = n > 0.0f ? n * (hi - o) : n < 0.0f ? n * (lo - o) : 0.0f;
}

/* Bits of word w of occupancy grid g for cells c0 .. c1 (one row: x runs
 * from x0 at cell c0; the row's y and z spans blo_yz .. bhi_yz, from
 * clvr_entry_cell_span) whose box meets every slab of s, among the bits of
 * todo (the others are not tested: the rasterization passes those not set
 * yet, since an element's cells are mostly set by its neighbours). A cell
 * is ruled out only by more than 8 ulps of the sum's terms (its rounding):
 * a cell far larger than the element (1e3 times its size) could otherwise
 * lose it. The y and z terms are summed once per row, the x term per cell. */
CLVR_INLINE clvr_u32 clvr_occupancy_row_bits(const clvr_entry_grid *g, const clvr_element_slabs *s, clvr_u32 w,
                                             clvr_u32 c0, clvr_u32 c1, clvr_u32 x0, const float *blo_yz,
                                             const float *bhi_yz, clvr_u32 todo)
{
#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#endif
    const float tol = 1e-6f;
    if (!todo) return 0;
    float mn[CLVR_ELEMENT_MAX_FACES], mx[CLVR_ELEMENT_MAX_FACES], an[CLVR_ELEMENT_MAX_FACES],
        ax[CLVR_ELEMENT_MAX_FACES];
    for (clvr_u32 f = 0; f < s->faces; ++f) {
        float yl, yh, zl, zh;
        clvr_slab_terms(s->n[f][1], s->o[1], blo_yz[0], bhi_yz[0], &yl, &yh);
        clvr_slab_terms(s->n[f][2], s->o[2], blo_yz[1], bhi_yz[1], &zl, &zh);
        mn[f] = yl + zl;
        mx[f] = yh + zh;
        an[f] = fabs(yl) + fabs(zl);
        ax[f] = fabs(yh) + fabs(zh);
    }
    const clvr_u32 first = w * 32u > c0 ? w * 32u : c0, last = w * 32u + 31u < c1 ? w * 32u + 31u : c1;
    clvr_u32 bits = 0;
    for (clvr_u32 c = first; c <= last; ++c) {
        if (!((todo >> (c % 32u)) & 1u)) continue;
        float xl, xh;
        clvr_entry_cell_span(g, 0, x0 + (c - c0), &xl, &xh);
        int meets = 1;
        for (clvr_u32 f = 0; meets && f < s->faces; ++f) {
            float tl, th;
            clvr_slab_terms(s->n[f][0], s->o[0], xl, xh, &tl, &th);
            if (mn[f] + tl > s->hi[f] + tol * (an[f] + fabs(tl)) ||
                mx[f] + th < s->lo[f] - tol * (ax[f] + fabs(th)))
                meets = 0;
        }
        bits |= (clvr_u32)meets << (c % 32u);
    }
    return bits;
}

/* The box of an element of the given type with vertices v in lo, hi, padded as
 * clvr_ebox_build_leaf pads it: it holds every point the containment tests
 * accept. The entry grids' cells take elements' boxes, not their leaf
 * clusters': a leaf of 16 graded or curved-boundary cells has a box far
 * larger than its elements, and a cell that only its box meets sends every
 * point there into a search that finds nothing (OpenFOAM igloo, random
 * points, host walk: queries that miss without entering a tree 12% -> 25%
 * of all, bottom nodes per miss 4.9 -> 2.6; PoCL bench_locate +13-20%,
 * the tet meshes unchanged).
 * Its slabs (clvr_element_slabs_of) in s: the occupancy grid's cells take
 * those too (element hulls, above). Also test_bvh's reference. */
CLVR_INLINE void clvr_element_hull(clvr_u32 type, const clvr_vec4 *v, float *lo, float *hi, clvr_element_slabs *s)
{
    const float pad = clvr_element_vertex_box(type, v, lo, hi);
    for (int k = 0; k < 3; ++k) {
        lo[k] -= 2.0f * pad;
        hi[k] += 2.0f * pad;
    }
    clvr_element_slabs_of(type, v, pad, s);
}

/* clvr_element_hull of element e of inst (in its piece pa). */
CLVR_INLINE void clvr_entry_element_hull(const clvr_piece_arrays *pa, const clvr_instance *inst, clvr_u32 e,
                                         float *lo, float *hi, clvr_element_slabs *s)
{
    clvr_vec4 v[CLVR_CELL_MAX_VERTS];
    clvr_load_element_in(pa, inst, e, v);
    clvr_element_hull(inst->type, v, lo, hi, s);
}

/* ------------------------------------------------------------ occupancy
 * Random points in a mesh's box often lie in no element: half of them in
 * the OpenFOAM igloo (a dome), 12-22% in the PLOT3D sets. Without help
 * such a point costs the top-level walk and, near a curved boundary where
 * leaf and instance boxes reach out of the mesh, searches of whole
 * subtrees (the igloo: a quarter of all queries). With entry grids a view
 * also has one occupancy grid over the whole mesh (entry_grids[0]; the
 * instances' grids follow it), one bit per cell, about
 * CLVR_OCCUPANCY_CELLS_PER_ELEMENT cells per element (0.125 bytes per
 * element), the bit set where some element's box and all its slabs
 * (clvr_entry_element_hull; element hulls, above) meet the cell. A point
 * whose bit is clear is in no element, for the same reason as for an entry
 * grid's start: clvr_locate_ex returns at once. Host walk, random points: the bit answers 44.5% of all queries on
 * the igloo (the entry grids alone let 25% miss without a tree), 9.7% on
 * the blunt fin, 18.4% on post-tets. 8 cells per element answered 46%,
 * 10.5% and 19%, and made the 1M tets' whole preprocessing 0.88 s instead
 * of 0.52 s on PoCL (before the rasterization's one OR per word; with it,
 * one cell per element: 0.29-0.33 s against 0.27-0.30 s without the
 * grid). PoCL bench_locate on the igloo, alternating runs with the commit
 * before: +10-24% (element boxes included). */
#define CLVR_OCCUPANCY_CELLS_PER_ELEMENT 1u
/* At most this many cells per axis (a 128 MB grid). */
#define CLVR_OCCUPANCY_MAX_RES 1024u

/* u32 words of occupancy grid g's bits (res[3]: its first word in the
 * cell array, after the entry grids' cells). */
CLVR_INLINE clvr_u32 clvr_occupancy_words(const clvr_entry_grid *g)
{
    return (clvr_u32)(((clvr_u64)g->res[0] * g->res[1] * g->res[2] + 31u) / 32u);
}

/* Mask of bits lo .. hi (lo <= hi < 32) of a word. Rasterizing a box
 * sets a row of cells (consecutive along x) with one OR per word it
 * touches, instead of one per cell. */
CLVR_INLINE clvr_u32 clvr_occupancy_mask(clvr_u32 lo, clvr_u32 hi)
{
    return (0xffffffffu >> (31u - hi)) & (0xffffffffu << lo);
}

/* p's cell in occupancy grid g: its coordinates c[0 .. 2] and its index
 * (returned, x fastest). */
CLVR_INLINE clvr_u32 clvr_occupancy_cell(const clvr_entry_grid *g, float px, float py, float pz, clvr_u32 *c)
{
    c[0] = clvr_entry_coord(px, g->lo[0], g->scale[0], g->res[0]);
    c[1] = clvr_entry_coord(py, g->lo[1], g->scale[1], g->res[1]);
    c[2] = clvr_entry_coord(pz, g->lo[2], g->scale[2], g->res[2]);
    return (c[2] * g->res[1] + c[1]) * g->res[0] + c[0];
}

/* 1 when cell oc of m's occupancy grid g has its bit set: 0 means no
 * element holds a point there. */
CLVR_INLINE int clvr_occupancy_bit(const clvr_mesh_view *m, const clvr_entry_grid *g, clvr_u32 oc)
{
    return (int)((m->entry_cells[g->res[3] + oc / 32u] >> (oc % 32u)) & 1u);
}

/* 1 when p's cell of the occupancy grid has its bit set. */
CLVR_INLINE int clvr_occupied(const clvr_mesh_view *m, float px, float py, float pz)
{
    const clvr_entry_grid g = m->entry_grids[0];
    clvr_u32 c[3];
    return clvr_occupancy_bit(m, &g, clvr_occupancy_cell(&g, px, py, pz, c));
}

/* ---------------------------------------------------------- global hints
 * The entry grids are per instance, so a query first walks the top level
 * to learn which instances' boxes hold it, then reads each one's cell. In
 * a mesh of mixed types every type has its own curve and instance
 * clusters, and they overlap: on the OpenFOAM igloo a found point passed
 * the boxes of 2.5 instances and tried 1.31 hints. So each cell of the
 * occupancy grid also names, in one word, the instance and leaf cluster
 * where the search for its points starts (clvr_global_hint: the leaf of
 * the element holding the cell's centre, else an octant's centre, as for
 * an instance's hint). A query reads that word right after its occupancy
 * bit and searches that leaf and its siblings (clvr_locate_hint_leaf)
 * before any top-level walk; only when they miss does it take the path
 * above. The word is instance << CLVR_GLOBAL_HINT_LEAF_BITS | the leaf's
 * index in its instance, CLVR_BVH_NOT_FOUND for none; a mesh whose
 * instances or leaves per instance do not fit (clvr_global_hints_fit:
 * 65535 instances or more, about two billion elements) has none and keeps
 * the path above.
 *
 * Measured on PoCL, 2-core Xeon VM (bench/results/graded/
 * 2026-11-30-s51-global-hints.md): the hint held for 76% of the igloo's
 * tries (host walk, random points); queries per CPU-second against the
 * same build without hints, alternating runs: the igloo +14% random and
 * ray-ordered (10 and 8 pairs), the blunt fin +5% and +18%, post-tets +7%
 * (5 pairs each). A hint per 8 occupancy cells (shift 1) instead of one
 * per cell: the igloo -3% (12 pairs), the blunt fin -13% random and -12%
 * rays, the 1M tets -11% (5-6 pairs each); a quarter of a cell per
 * element for the occupancy grid and hints: -7%, four: -2%. Skipping, after
 * a miss, the leaf the hint had searched: +2% (8 pairs, noise); skipping
 * its whole node, as clvr_locate_entry_pass now does
 * (clvr_locate_hint_unsearched): +4-6% (session 52); searching the 16
 * leaves under the hint's grandparent after a miss: +1% (noise).
 * Costs: 4 bytes per occupancy cell (about 4 per element: the igloo's tree
 * and indices 0.27 -> 0.31 of Embree's) and one point location per cell
 * at build time (the 1M tets: 0.29 s, so the whole preprocessing 0.25-0.33
 * -> 0.60-0.62 s, slower than Embree's 0.43-0.47 s build). Building them
 * instead by rasterizing (each element tests the cell centres in its box,
 * the smallest word per cell winning; locates only for the octants of
 * cells whose centre no element holds) was slower: 0.71 s on the 1M tets,
 * 0.12 + 0.08 s on the igloo (beside a CI run, so slowed, but not 2.4x);
 * 4^3-cell tiles per work-group instead of rows: 0.30 -> 0.29 s. */
#define CLVR_GLOBAL_HINT_LEAF_BITS 16u
#define CLVR_GLOBAL_HINT_LEAF_MASK ((1u << CLVR_GLOBAL_HINT_LEAF_BITS) - 1u)
/* At most this many global hint cells (64 MB); a larger occupancy grid
 * (meshes of more than 2^24 elements) shares a hint among 2^3, 4^3, ...
 * of its cells (clvr_global_hints_shift). */
#define CLVR_GLOBAL_HINT_MAX_CELLS (1u << 24)

/* 1 when a mesh of num_instances instances, none with more than max_leaves
 * leaf clusters, can have global hints. */
CLVR_INLINE int clvr_global_hints_fit(clvr_u32 num_instances, clvr_u32 max_leaves)
{
    return num_instances < (1u << (32u - CLVR_GLOBAL_HINT_LEAF_BITS)) - 1u &&
           max_leaves <= (1u << CLVR_GLOBAL_HINT_LEAF_BITS);
}

/* 1 when occupancy grid g's cells have global hints to read: its lo[3]
 * (otherwise unused) is 1 + clvr_global_hints_shift, 0 when there are
 * none (they do not fit) or while they are built: clvr_locate_ex then
 * does not read them, which keeps their build, a point location per
 * cell, deterministic. */
CLVR_INLINE int clvr_global_hints_on(const clvr_entry_grid *g)
{
    return g->lo[3] >= 1.0f;
}

/* A global hint cell spans 2^s occupancy cells per axis, s this shift. */
CLVR_INLINE clvr_u32 clvr_global_hints_shift(const clvr_entry_grid *g)
{
    return (clvr_u32)g->lo[3] - 1u;
}

/* Global hint cells along axis k of occupancy grid g at shift s. */
CLVR_INLINE clvr_u32 clvr_global_hint_res(const clvr_entry_grid *g, clvr_u32 s, int k)
{
    return ((g->res[k] - 1u) >> s) + 1u;
}

/* Index of the global hint cell at shift s that holds occupancy cell
 * c[0 .. 2] of grid g (x fastest). */
CLVR_INLINE clvr_u32 clvr_global_hint_cell(const clvr_entry_grid *g, clvr_u32 s, const clvr_u32 *c)
{
    return ((c[2] >> s) * clvr_global_hint_res(g, s, 1) + (c[1] >> s)) * clvr_global_hint_res(g, s, 0) + (c[0] >> s);
}

/* First word of occupancy grid g's global hints in the cell array: right
 * after its bits, one word per hint cell. */
CLVR_INLINE clvr_u64 clvr_global_hints_first(const clvr_entry_grid *g)
{
    return (clvr_u64)g->res[3] + clvr_occupancy_words(g);
}

/* Lowest common ancestor of leaf clusters first_hit <= last_hit of inst:
 * climbs the implicit levels (bvh_build.h, levels stored root first, node
 * i of a level the parent of nodes 4i .. 4i + 3 below) from their
 * lowest-level nodes until the two meet. */
CLVR_INLINE clvr_u32 clvr_entry_lca(const clvr_instance *inst, clvr_u32 first_hit, clvr_u32 last_hit)
{
    if (first_hit > last_hit || first_hit < inst->first_leaf || last_hit - inst->first_leaf >= inst->num_leaves)
        return inst->bvh_root; /* not the instance's leaves (never from the builders): the root is always right */
    clvr_u32 a = (first_hit - inst->first_leaf) / 4u, b = (last_hit - inst->first_leaf) / 4u;
    clvr_u32 size = (inst->num_leaves + 3u) / 4u, first = clvr_locate_level0(inst);
    while (a != b) {
        size = (size + 3u) / 4u;
        first -= size;
        a /= 4u;
        b /= 4u;
    }
    return first + a;
}

/* Coordinate on axis k of probe point o of grid cells first .. first +
 * span - 1 on an axis (lo, scale > 0): o = 0 their centre, 1 .. 8 their
 * octants' centres (bit k of o - 1 set: the upper half on axis k). Where
 * a cell's hint looks for its element (clvr_entry_hint, clvr_global_hint). */
CLVR_INLINE float clvr_entry_probe(float lo, float scale, clvr_u32 first, clvr_u32 span, clvr_u32 o, int k)
{
    const float f = o == 0u ? 0.5f : ((o - 1u) >> k) & 1u ? 0.75f : 0.25f;
    return lo + ((float)first + (float)span * f) / scale;
}

/* Set in a cell's hint when it came from an octant's centre, not the
 * cell's (leaf ids stay below 2^31, CLVR_BVH_MAX_PRIMS). Among instances
 * of mixed types only the type whose element holds a cell's centre has a
 * hint without it, so clvr_locate_entry_pass tries those hints first: on
 * the OpenFOAM igloo (host walk, random points) a point found in a pyramid
 * searched 3.38 leaf clusters instead of 3.80, and hints tried per found
 * point 1.52 -> 1.41; PoCL bench_locate, alternating with the kernels
 * before: +5%, -5%, +5% (and +34% on a first pair). */
#define CLVR_ENTRY_HINT_OCTANT 0x80000000u

/* The hint leaf of a cell's hint word h (CLVR_BVH_NOT_FOUND for none). */
CLVR_INLINE clvr_u32 clvr_entry_hint_leaf(clvr_u32 h)
{
    return h == CLVR_BVH_NOT_FOUND ? h : h & CLVR_BVH_MAX_PRIMS;
}

/* The hint of cell (cx, cy, cz) of inst's grid g, whose start node is
 * start: the leaf cluster holding the element where the cell's centre
 * lies; where no element of inst holds the centre, the one where the first
 * of the centres of the cell's eight octants lies that one holds (a cell
 * on the mesh's boundary, or, in a mesh of mixed cells, one whose centre
 * is in another type's element); else CLVR_BVH_NOT_FOUND. The octants:
 * host walk on the OpenFOAM igloo, random points, bottom-level nodes per
 * query 3.62 -> 3.07; PoCL bench_locate, alternating runs: igloo +1-9%
 * (4 pairs), post-tets +12% and +22%, blunt fin +6%, +11%, -10%. */
CLVR_INLINE clvr_u32 clvr_entry_hint(const clvr_mesh_view *m, const clvr_instance *inst, const clvr_entry_grid *g,
                                     clvr_u32 start, clvr_u32 cx, clvr_u32 cy, clvr_u32 cz)
{
    if (start == CLVR_BVH_NOT_FOUND) return CLVR_BVH_NOT_FOUND;
    const clvr_u32 c[3] = {cx, cy, cz};
    for (clvr_u32 o = 0; o < 9u; ++o) {
        float p[3];
        for (int k = 0; k < 3; ++k) /* an axis of one cell has scale 0: its centre is the box's */
            p[k] = g->scale[k] > 0.0f ? clvr_entry_probe(g->lo[k], g->scale[k], c[k], 1u, o, k)
                                      : 0.5f * (inst->bounds.lo[k] + inst->bounds.hi[k]);
        float s;
        clvr_u32 e, leaf;
        if (clvr_locate_in_instance(m, inst, start, CLVR_BVH_NOT_FOUND, CLVR_BVH_NOT_FOUND, p[0], p[1], p[2],
                                    CLVR_LOCATE_COHERENT, CLVR_BVH_NOT_FOUND, &s, &e, &leaf))
            return o == 0u ? leaf : leaf | CLVR_ENTRY_HINT_OCTANT;
    }
    return CLVR_BVH_NOT_FOUND;
}

/* Start node and hint word (its leaf: clvr_entry_hint_leaf) of p's cell in
 * instance inst_id's entry grid. */
CLVR_INLINE void clvr_entry_cell(const clvr_mesh_view *m, clvr_u32 inst_id, float px, float py, float pz,
                                 clvr_u32 *start, clvr_u32 *hint)
{
    const clvr_entry_grid g = m->entry_grids[1u + inst_id]; /* [0]: the occupancy grid */
    const clvr_u32 cx = clvr_entry_coord(px, g.lo[0], g.scale[0], g.res[0]);
    const clvr_u32 cy = clvr_entry_coord(py, g.lo[1], g.scale[1], g.res[1]);
    const clvr_u32 cz = clvr_entry_coord(pz, g.lo[2], g.scale[2], g.res[2]);
    CLVR_GLOBAL const clvr_u32 *cell = m->entry_cells + 2u * ((clvr_u64)g.res[3] + (cz * g.res[1] + cy) * g.res[0] + cx);
    *start = cell[0];
    *hint = cell[1];
}

/* Searches hint leaf `hint` of inst, then its siblings (the lowest level's
 * children are all leaves; empty slots fail the box test) from its slot
 * on; *node: their node. Arguments and result as clvr_locate_in_instance's. */
CLVR_INLINE int clvr_locate_hint_leaf(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 hint, float px,
                                      float py, float pz, clvr_u32 skip_elem, float *scalar, clvr_u32 *element_id,
                                      clvr_u32 *leaf_found, clvr_u32 *node)
{
    clvr_u32 slot;
    clvr_leaf_parent(inst, hint, node, &slot);
    CLVR_GLOBAL const clvr_bvh_node *n = m->blas + *node;
    const clvr_piece_arrays a = clvr_view_piece(m, inst);
    clvr_prefetch_hint_leaf(m, &a, inst, hint);
    const clvr_u32 mask = clvr_bvh_node_point_mask(n, px, py, pz);
    CLVR_WALK_STAT(entry_try);
    CLVR_WALK_STAT(bnodes);
    for (clvr_u32 k = 0; k < 4u; ++k) {
        const clvr_u32 c = (slot + k) & 3u;
        if (!((mask >> c) & 1u)) continue;
        const clvr_u32 leaf = n->child[c] & CLVR_BVH_MAX_PRIMS;
        CLVR_WALK_STAT(leaves);
        if (clvr_locate_in_leaf(m, &a, inst, leaf, n, c, px, py, pz, skip_elem, scalar, element_id)) {
            CLVR_WALK_STAT(entry_hit);
            *leaf_found = leaf;
            return 1;
        }
    }
    return 0;
}

/* Searches instance inst_id (inst) for p the way its entry grid says:
 * the cell's hint, then the rest of its start node's subtree (the whole
 * tree from the root without entry grids). Arguments and result as
 * clvr_locate_in_instance's. */
CLVR_INLINE int clvr_locate_entered(const clvr_mesh_view *m, clvr_u32 inst_id, const clvr_instance *inst, float px,
                                    float py, float pz, clvr_u32 hints, clvr_u32 skip_elem, float *scalar,
                                    clvr_u32 *element_id, clvr_u32 *leaf_found)
{
    if (!m->entry_grids)
        return clvr_locate_in_instance(m, inst, inst->bvh_root, CLVR_BVH_NOT_FOUND, CLVR_BVH_NOT_FOUND, px, py, pz,
                                       hints, skip_elem, scalar, element_id, leaf_found);
    clvr_u32 start, hint, skip = CLVR_BVH_NOT_FOUND;
    clvr_entry_cell(m, inst_id, px, py, pz, &start, &hint);
    if (start == CLVR_BVH_NOT_FOUND) return 0;
    hint = clvr_entry_hint_leaf(hint);
    if (hint != CLVR_BVH_NOT_FOUND) {
        if (clvr_locate_hint_leaf(m, inst, hint, px, py, pz, skip_elem, scalar, element_id, leaf_found, &skip))
            return 1;
        if (skip == start) return 0; /* the hint's node was the whole of start's subtree */
    }
    return clvr_locate_in_instance(m, inst, start, skip, CLVR_BVH_NOT_FOUND, px, py, pz, hints, skip_elem, scalar,
                                   element_id, leaf_found);
}

/* clvr_locate_hint_leaf, unless hint leaf `hint` of inst lies under node
 * `searched` (the global hint's node, whose leaves clvr_locate_ex has just
 * searched for the point; CLVR_BVH_NOT_FOUND for none): then it returns 0
 * with *node set, searching nothing, and clvr_locate_entry_pass does not
 * enter that node in a start subtree either. On the tet meshes nearly
 * every miss of the global hint is in its own instance, and the entry
 * cell's hint is often in the same node: host walk, random points found
 * after a miss, exact tests 7.94 -> 6.58 (post-tets), 5.60 -> 4.92 (blunt
 * fin), 3.01 -> 2.61 (igloo). PoCL bench_locate, queries per CPU-second,
 * medians of 8 alternating pairs: igloo +5.1%, post-tets +4.7%, gmsh
 * boundary layers +5.6% (random points), blunt fin +3.6% (rays); a first
 * version that did not skip an octant hint or a start node under the
 * searched node: +1.7% to +2.9% on five meshes, 30 of 40 pairs faster. */
CLVR_INLINE int clvr_locate_hint_unsearched(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 hint,
                                            clvr_u32 searched, float px, float py, float pz, clvr_u32 skip_elem,
                                            float *scalar, clvr_u32 *element_id, clvr_u32 *leaf_found,
                                            clvr_u32 *node)
{
    if (searched != CLVR_BVH_NOT_FOUND) {
        clvr_u32 slot;
        clvr_leaf_parent(inst, hint, node, &slot);
        if (*node == searched) return 0;
    }
    return clvr_locate_hint_leaf(m, inst, hint, px, py, pz, skip_elem, scalar, element_id, leaf_found, node);
}

/* Instances whose boxes hold a point that clvr_locate_ex searches hints
 * first across (more: one instance after another). */
#define CLVR_ENTRY_MAX_CANDIDATES 8u

/* clvr_locate_ex with entry grids: the instances whose boxes hold p (at
 * most CLVR_ENTRY_MAX_CANDIDATES; 0 when there are more, so that the caller
 * searches them one by one); when they are of more than one type, every
 * one's hint first (those from a cell's centre before those from an
 * octant's, CLVR_ENTRY_HINT_OCTANT), then the rest of every one's start
 * subtree. Where
 * each element type has its own instance clusters (one curve per type),
 * they overlap: on the OpenFOAM igloo (328k mixed cells) a found point's
 * box test passes 2.5 instances, and searching them one after another
 * searched the whole start subtree of the wrong types before the right
 * one's hint (hints first: +7-18% queries/s there). searched_inst,
 * searched_node: the instance and lowest-level node whose leaves the caller
 * has already searched (the global hint's; clvr_locate_hint_unsearched), or
 * CLVR_BVH_NOT_FOUND. *done: 1 when the search was made (its result
 * returned), 0 when there were too many candidates. */
CLVR_INLINE int clvr_locate_entry_pass(const clvr_mesh_view *m, float px, float py, float pz, clvr_u32 hints,
                                       clvr_u32 skip_inst, clvr_u32 skip_elem, clvr_u32 searched_inst,
                                       clvr_u32 searched_node, float *scalar, clvr_u32 *element_id,
                                       clvr_u32 *inst_found, clvr_u32 *leaf_found, int *done)
{
    clvr_u32 cand[CLVR_ENTRY_MAX_CANDIDATES], start[CLVR_ENTRY_MAX_CANDIDATES], skip[CLVR_ENTRY_MAX_CANDIDATES];
    clvr_u32 nc = 0;
    *done = 0;
    /* Its own top-level walk, like clvr_locate_ex's: one walk for both that
     * collects candidates and searches those past the array as it meets them
     * measured 2-10% slower on post-tets and the igloo (3 pairs each). */
    {
        clvr_u32 stack[CLVR_BVH_STACK_SIZE];
        clvr_u32 sp = 0, ref = m->tlas_root;
        for (;;) {
            CLVR_GLOBAL const clvr_bvh_node *n = m->tlas + ref;
            CLVR_WALK_STAT(tnodes);
            const clvr_u32 mask = clvr_bvh_node_point_mask(n, px, py, pz);
            for (clvr_u32 c = 0; c < 4; ++c) {
                if (!((mask >> c) & 1u)) continue;
                const clvr_u32 ch = n->child[c];
                if (ch & CLVR_BVH_LEAF_BIT) {
                    if ((ch & CLVR_BVH_MAX_PRIMS) == skip_inst) continue;
                    if (nc == CLVR_ENTRY_MAX_CANDIDATES) return 0;
                    cand[nc++] = ch & CLVR_BVH_MAX_PRIMS;
                } else if (sp < CLVR_BVH_STACK_SIZE) {
                    stack[sp++] = ch;
                }
            }
            if (sp == 0) break;
            ref = stack[--sp];
        }
    }
    *done = 1;
    /* Candidates of one type (a tet mesh's neighbouring clusters) are
     * searched one after another, each hint then its start subtree: there
     * the next instance's hint is the worse bet (hints first across them
     * cost post-tets and the igloo cut into tets 2-11%). This is
     * clvr_locate_entered's search written out: calling it measured 3-4%
     * slower (4 pairs each on post-tets, the igloo and its tets). */
    int mixed = 0;
    for (clvr_u32 i = 1; i < nc; ++i) mixed |= m->instances[cand[i]].type != m->instances[cand[0]].type;
    clvr_u32 octant[CLVR_ENTRY_MAX_CANDIDATES];
    for (clvr_u32 i = 0; i < nc; ++i) {
        clvr_u32 word;
        clvr_entry_cell(m, cand[i], px, py, pz, &start[i], &word);
        const clvr_u32 hint = clvr_entry_hint_leaf(word);
        const clvr_u32 searched = cand[i] == searched_inst ? searched_node : CLVR_BVH_NOT_FOUND;
        skip[i] = CLVR_BVH_NOT_FOUND;
        octant[i] = CLVR_BVH_NOT_FOUND;
        if (start[i] == CLVR_BVH_NOT_FOUND || start[i] == searched) { /* nothing there not searched yet */
            start[i] = CLVR_BVH_NOT_FOUND;
            continue;
        }
        const clvr_instance inst = m->instances[cand[i]];
        if (mixed && hint != CLVR_BVH_NOT_FOUND && (word & CLVR_ENTRY_HINT_OCTANT)) {
            octant[i] = hint; /* after every hint from a cell's centre */
            continue;
        }
        if (hint != CLVR_BVH_NOT_FOUND) {
            if (clvr_locate_hint_unsearched(m, &inst, hint, searched, px, py, pz, skip_elem, scalar, element_id,
                                            leaf_found, &skip[i])) {
                *inst_found = cand[i];
                return 1;
            }
            if (skip[i] == start[i]) start[i] = CLVR_BVH_NOT_FOUND; /* its node was the whole start subtree */
        }
        if (mixed || start[i] == CLVR_BVH_NOT_FOUND) continue;
        CLVR_WALK_STAT(inst);
        if (clvr_locate_in_instance(m, &inst, start[i], skip[i], searched, px, py, pz, hints, skip_elem, scalar,
                                    element_id, leaf_found)) {
            *inst_found = cand[i];
            return 1;
        }
        start[i] = CLVR_BVH_NOT_FOUND;
    }
    for (clvr_u32 i = 0; i < nc; ++i) {
        if (octant[i] == CLVR_BVH_NOT_FOUND) continue;
        const clvr_instance inst = m->instances[cand[i]];
        const clvr_u32 searched = cand[i] == searched_inst ? searched_node : CLVR_BVH_NOT_FOUND;
        if (clvr_locate_hint_unsearched(m, &inst, octant[i], searched, px, py, pz, skip_elem, scalar, element_id,
                                        leaf_found, &skip[i])) {
            *inst_found = cand[i];
            return 1;
        }
        if (skip[i] == start[i]) start[i] = CLVR_BVH_NOT_FOUND;
    }
    for (clvr_u32 i = 0; i < nc; ++i) {
        if (start[i] == CLVR_BVH_NOT_FOUND) continue;
        const clvr_instance inst = m->instances[cand[i]];
        const clvr_u32 searched = cand[i] == searched_inst ? searched_node : CLVR_BVH_NOT_FOUND;
        CLVR_WALK_STAT(inst);
        if (clvr_locate_in_instance(m, &inst, start[i], skip[i], searched, px, py, pz, hints, skip_elem, scalar,
                                    element_id, leaf_found)) {
            *inst_found = cand[i];
            return 1;
        }
    }
    *element_id = CLVR_BVH_NOT_FOUND;
    return 0;
}

/* Point location in mesh m: returns 1 when an element contains
 * (px, py, pz) and writes its interpolated scalar and global sorted element
 * id; 0 (and element id CLVR_BVH_NOT_FOUND) otherwise. hints:
 * CLVR_LOCATE_COHERENT or CLVR_LOCATE_INCOHERENT (a speed hint only: the
 * result is the same bit for bit). skip_inst: an instance not entered
 * (one already searched), or CLVR_BVH_NOT_FOUND; skip_elem: an element not
 * tested (clvr_locate_in_leaf). inst_found, leaf_found: the instance index
 * and leaf cluster of the element found. */
CLVR_INLINE int clvr_locate_ex(const clvr_mesh_view *m, float px, float py, float pz, clvr_u32 hints,
                               clvr_u32 skip_inst, clvr_u32 skip_elem, float *scalar, clvr_u32 *element_id,
                               clvr_u32 *inst_found, clvr_u32 *leaf_found)
{
    *element_id = CLVR_BVH_NOT_FOUND;
    if (m->entry_grids) {
        const clvr_entry_grid og = m->entry_grids[0];
        clvr_u32 c[3];
        const clvr_u32 oc = clvr_occupancy_cell(&og, px, py, pz, c);
        if (!clvr_occupancy_bit(m, &og, oc)) {
            CLVR_WALK_STAT(occ_clear);
            return 0;
        }
        clvr_u32 searched_inst = CLVR_BVH_NOT_FOUND, searched_node = CLVR_BVH_NOT_FOUND;
        if (clvr_global_hints_on(&og)) {
            const clvr_u32 sh = clvr_global_hints_shift(&og);
            const clvr_u32 w = m->entry_cells[clvr_global_hints_first(&og) + clvr_global_hint_cell(&og, sh, c)];
            const clvr_u32 gi = w >> CLVR_GLOBAL_HINT_LEAF_BITS;
            if (w != CLVR_BVH_NOT_FOUND && gi != skip_inst) {
                const clvr_instance inst = m->instances[gi];
                clvr_u32 node;
                CLVR_WALK_STAT(global_try);
                if (clvr_locate_hint_leaf(m, &inst, inst.first_leaf + (w & CLVR_GLOBAL_HINT_LEAF_MASK),
                                          px, py, pz, skip_elem, scalar, element_id, leaf_found, &node)) {
                    CLVR_WALK_STAT(global_hit);
                    *inst_found = gi;
                    return 1;
                }
                searched_inst = gi;
                searched_node = node;
            }
        }
        int done;
        const int found = clvr_locate_entry_pass(m, px, py, pz, hints, skip_inst, skip_elem, searched_inst,
                                                 searched_node, scalar, element_id, inst_found, leaf_found, &done);
        if (done) return found;
    }
    clvr_u32 stack[CLVR_BVH_STACK_SIZE];
    clvr_u32 sp = 0, ref = m->tlas_root;
    for (;;) {
        CLVR_GLOBAL const clvr_bvh_node *n = m->tlas + ref;
        CLVR_WALK_STAT(tnodes);
        const clvr_u32 mask = clvr_bvh_node_point_mask(n, px, py, pz);
        for (clvr_u32 c = 0; c < 4; ++c) {
            if (!((mask >> c) & 1u)) continue;
            const clvr_u32 ch = n->child[c];
            if (ch & CLVR_BVH_LEAF_BIT) {
                if ((ch & CLVR_BVH_MAX_PRIMS) == skip_inst) continue;
                const clvr_instance inst = m->instances[ch & CLVR_BVH_MAX_PRIMS];
                if (clvr_locate_entered(m, ch & CLVR_BVH_MAX_PRIMS, &inst, px, py, pz, hints, skip_elem, scalar,
                                        element_id, leaf_found)) {
                    *inst_found = ch & CLVR_BVH_MAX_PRIMS;
                    return 1;
                }
            } else if (sp < CLVR_BVH_STACK_SIZE) {
                stack[sp++] = ch;
            }
        }
        if (sp == 0) return 0;
        ref = stack[--sp];
    }
}

CLVR_INLINE int clvr_locate(const clvr_mesh_view *m, float px, float py, float pz, clvr_u32 hints, float *scalar,
                            clvr_u32 *element_id)
{
    clvr_u32 inst, leaf;
    return clvr_locate_ex(m, px, py, pz, hints, CLVR_BVH_NOT_FOUND, CLVR_BVH_NOT_FOUND, scalar, element_id, &inst,
                          &leaf);
}

/* The global hint word of hint cell c of m's occupancy grid at shift sh
 * (the global hints section above): where the centre of the occupancy
 * cells it spans lies, else the first of their octants' centres that lies
 * in an element (the order clvr_entry_hint takes), found by clvr_locate_ex
 * through m's entry grids, whose global hints must be off
 * (clvr_global_hints_on) while this runs; CLVR_BVH_NOT_FOUND when no
 * element holds any of the nine points. */
CLVR_INLINE clvr_u32 clvr_global_hint(const clvr_mesh_view *m, clvr_u32 sh, clvr_u32 c)
{
    const clvr_entry_grid g = m->entry_grids[0];
    const clvr_u32 hx = clvr_global_hint_res(&g, sh, 0), hy = clvr_global_hint_res(&g, sh, 1);
    const clvr_u32 cc[3] = {c % hx, c / hx % hy, c / hx / hy};
    for (clvr_u32 o = 0; o < 9u; ++o) {
        float p[3];
        for (int k = 0; k < 3; ++k) {
            /* the occupancy cells first .. first + span - 1 on this axis
             * (fewer at the grid's end); an axis of one cell (scale 0):
             * its low corner, a flat mesh's plane */
            const clvr_u32 first = cc[k] << sh, span = g.res[k] - first < (1u << sh) ? g.res[k] - first : 1u << sh;
            p[k] = g.scale[k] > 0.0f ? clvr_entry_probe(g.lo[k], g.scale[k], first, span, o, k) : g.lo[k];
        }
        float s;
        clvr_u32 e, inst, leaf;
        if (clvr_locate_ex(m, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, CLVR_BVH_NOT_FOUND, CLVR_BVH_NOT_FOUND, &s, &e,
                           &inst, &leaf))
            return inst << CLVR_GLOBAL_HINT_LEAF_BITS | (leaf - m->instances[inst].first_leaf);
    }
    return CLVR_BVH_NOT_FOUND;
}

/* Without entry grids (a view whose entry_grids is NULL; with them, a
 * lookup starts from its point's cell instead, see clvr_locate_hinted_skip):
 * a ray's next sample is usually near its last one (urm's quadrature
 * points are a few elements apart), so a ray keeps where its last lookup
 * ended: the instance and the node two levels above that leaf (16 leaf
 * clusters). The next lookup searches that subtree first, then the rest of
 * that instance, then the other instances, so no subtree is searched twice.
 * Walking the whole tree after a miss in the subtree instead (which
 * searched it again) cost 3.6% more per urm frame on post-tets and 7% more
 * on tets-1M (256^2, interleaved runs; the hinted subtree holds the next
 * sample for 53% and 25% of the lookups). inst CLVR_BVH_NOT_FOUND: no hint
 * yet. The element found may differ from clvr_locate's only where two
 * elements share the point (a shared face), with the same value. */
typedef struct clvr_locate_hint {
    clvr_u32 inst, node;
} clvr_locate_hint;

CLVR_INLINE clvr_locate_hint clvr_locate_hint_none(void)
{
    clvr_locate_hint h;
    h.inst = CLVR_BVH_NOT_FOUND;
    h.node = 0u;
    return h;
}

/* The node two levels above leaf cluster `leaf` of inst (its root when the
 * tree is lower). Levels are stored root first, so level 1 sits just before
 * level 0. */
CLVR_INLINE clvr_u32 clvr_locate_hint_node(const clvr_instance *inst, clvr_u32 leaf)
{
    const clvr_u32 level0 = clvr_locate_level0(inst);
    const clvr_u32 s1 = clvr_bvh_level_size(inst->num_leaves, 1u);
    return s1 == 0u ? level0 : level0 - s1 + (leaf - inst->first_leaf) / 16u;
}

/* clvr_locate_hinted without testing element skip_elem (one the caller has
 * just found outside the point, or CLVR_BVH_NOT_FOUND). */
CLVR_INLINE int clvr_locate_hinted_skip(const clvr_mesh_view *m, float px, float py, float pz, clvr_locate_hint *h,
                                        clvr_u32 skip_elem, float *scalar, clvr_u32 *element_id)
{
    clvr_u32 leaf, inst_id, skip_inst = CLVR_BVH_NOT_FOUND;
    /* With entry grids the point's own cell is the better hint: on
     * ray-ordered points (bench_locate --order rays, leaves of 16, PoCL,
     * alternating runs) blunt fin 5.7 -> 6.2-7.3M queries/s, post-tets 4.0 ->
     * 4.4M, combustor 5.6-6.3 -> 6.2-6.5M, 1M tets the same; host walk:
     * bottom nodes per lookup 4.09 -> 2.48 (blunt fin), 5.03 -> 3.62 (post),
     * the cell's hint holding 78% and 66% against the ray's 70% and 60%.
     * The ray's hint is then not searched; its instance is kept up to date
     * (callers read it), its node is not read. */
    if (m->entry_grids) {
        if (!clvr_locate_ex(m, px, py, pz, CLVR_LOCATE_COHERENT, CLVR_BVH_NOT_FOUND, skip_elem, scalar, element_id,
                            &inst_id, &leaf))
            return 0;
        h->inst = inst_id;
        return 1;
    }
    if (h->inst != CLVR_BVH_NOT_FOUND) {
        const clvr_instance inst = m->instances[h->inst];
        CLVR_WALK_STAT(hint_try);
        if (clvr_locate_in_instance(m, &inst, h->node, CLVR_BVH_NOT_FOUND, CLVR_BVH_NOT_FOUND, px, py, pz,
                                    CLVR_LOCATE_COHERENT, skip_elem, scalar, element_id, &leaf)) {
            CLVR_WALK_STAT(hint_hit);
            h->node = clvr_locate_hint_node(&inst, leaf);
            return 1;
        }
        /* The rest of the hinted instance next (a ray's next sample is most
         * often still inside it), from the hinted node upward: its parent's
         * other children, then its grandparent's, and so on to the root, so
         * that a sample a few elements away is found in a neighbouring
         * subtree before a descent from the root; then the other instances.
         * No subtree is searched twice. The tree is implicit (bvh_build.h):
         * levels stored root first, node i of a level the parent of nodes
         * 4i .. 4i + 3 of the level below. Against a descent from the root
         * (skipping the hinted node): bottom-tree nodes per lookup on
         * ray-ordered points 20.9 -> 14.4 on the 1M tets, 8.7 -> 7.2 on
         * post-tets (bench_walk --order rays); on PoCL a urm frame of the 1M
         * tets -5%, bench_locate --order rays +6%, post and the PLOT3D
         * meshes within noise (their hints hold 53% and a miss is mostly in
         * another instance). */
        clvr_u32 node = h->node;
        clvr_u32 size = (inst.num_leaves + 3u) / 4u, first = clvr_locate_level0(&inst);
        if (node < first) { /* the hint is on level 1 */
            size = (size + 3u) / 4u;
            first -= size;
        }
        while (size > 1u) {
            const clvr_u32 up = (size + 3u) / 4u, up_first = first - up;
            const clvr_u32 parent = up_first + (node - first) / 4u;
            if (clvr_locate_in_instance(m, &inst, parent, node, CLVR_BVH_NOT_FOUND, px, py, pz, CLVR_LOCATE_COHERENT,
                                        skip_elem, scalar, element_id, &leaf)) {
                h->node = clvr_locate_hint_node(&inst, leaf);
                return 1;
            }
            node = parent;
            size = up;
            first = up_first;
        }
        skip_inst = h->inst;
    }
    if (!clvr_locate_ex(m, px, py, pz, CLVR_LOCATE_COHERENT, skip_inst, skip_elem, scalar, element_id, &inst_id,
                        &leaf))
        return 0;
    const clvr_instance inst = m->instances[inst_id];
    h->inst = inst_id;
    h->node = clvr_locate_hint_node(&inst, leaf);
    return 1;
}

CLVR_INLINE int clvr_locate_hinted(const clvr_mesh_view *m, float px, float py, float pz, clvr_locate_hint *h,
                                   float *scalar, clvr_u32 *element_id)
{
    return clvr_locate_hinted_skip(m, px, py, pz, h, CLVR_BVH_NOT_FOUND, scalar, element_id);
}

/* The renderer's entry point: clvr_locate without the element id. The
 * samples of one ray, and of neighbouring rays, are close to each other, so
 * coherent: the prefetches of CLVR_LOCATE_INCOHERENT would only cost there.
 * The view comes by value, so that a caller can build it in the call (the
 * address of a compound literal is not private memory in OpenCL C). */
CLVR_INLINE int clvr_locate_point(clvr_mesh_view m, float px, float py, float pz, float *scalar)
{
    clvr_u32 e;
    return clvr_locate(&m, px, py, pz, CLVR_LOCATE_COHERENT, scalar, &e);
}

#endif /* CLVR_LOCATE_H */
