/* bvh.cl: building the packed 4-wide BVHs on the device (one launch per
 * level, one work item per node, bottom-up) and batch queries used by tests
 * and benchmarks: point location over the two-level tree and ray queries
 * over a single-level tree. */
#include "clvr_shared.h"
#include "bvh_build.h"
#include "bvh_traverse.h"
#include "locate.h"
#include "hull.h"

/* Builds every node of level `level` of all trees. level_prefix[t] is the
 * number of level-`level` nodes in trees 0 .. t-1 (num_trees + 1 entries),
 * so work item i finds its tree by binary search. */
__kernel void clvr_bvh_build_level(__global clvr_bvh_node *nodes, __global const float *prim_boxes,
                                   __global const clvr_bvh_tree *trees, __global const uint *level_prefix,
                                   uint num_trees, uint level)
{
    const uint i = get_global_id(0);
    if (i >= level_prefix[num_trees]) return;
    uint lo = 0, hi = num_trees; /* last t with level_prefix[t] <= i */
    while (hi - lo > 1) {
        const uint mid = (lo + hi) / 2;
        if (level_prefix[mid] <= i) lo = mid;
        else hi = mid;
    }
    clvr_bvh_build_node(nodes, prim_boxes, trees[lo], level, i - level_prefix[lo]);
}

/* The body of the point-location kernels over view m. */
inline void clvr_locate_points_in(const clvr_mesh_view *m, __global const float4 *points, uint n, uint hints,
                                  uint chain, __global float *scalars, __global uint *element_ids)
{
    const uint g = get_global_id(0);
    if (chain <= 1u) {
        if (g >= n) return;
        const float4 p = points[g];
        float s = 0.0f;
        uint e;
        clvr_locate(m, p.x, p.y, p.z, hints, &s, &e);
        scalars[g] = s;
        element_ids[g] = e;
        return;
    }
    const ulong first = (ulong)g * chain;
    if (first >= n) return;
    const uint end = (uint)min((ulong)n, first + chain);
    clvr_locate_hint h = clvr_locate_hint_none();
    for (uint i = (uint)first; i < end; ++i) {
        const float4 p = points[i];
        float s = 0.0f;
        uint e = CLVR_BVH_NOT_FOUND;
        if (!clvr_locate_hinted(m, p.x, p.y, p.z, &h, &s, &e)) e = CLVR_BVH_NOT_FOUND;
        scalars[i] = s;
        element_ids[i] = e;
    }
}

/* Point location for n points (xyz, w ignored): scalar and element id
 * (CLVR_BVH_NOT_FOUND when outside). hints: CLVR_LOCATE_COHERENT or
 * CLVR_LOCATE_INCOHERENT (speed only, same results). chain > 1: each work
 * item takes `chain` consecutive points (the samples of one ray, as a
 * renderer produces them) and carries a ray's hint from one to the next
 * (clvr_locate_hinted): the element found may then differ from the full
 * walk's only where two elements share the point, with the same value.
 * For a mesh whose arrays are one piece; clvr_locate_points_split takes the
 * pieces of a split one. */
__kernel void clvr_locate_points(__global const float4 *points, uint n, __global const clvr_bvh_node *tlas,
                                 uint tlas_root, __global const clvr_bvh_node *blas,
                                 __global const clvr_instance *instances, __global const float4 *vertices,
                                 __global const ushort *idx16, __global const uint *idx32, uint leaf_size,
                                 __global float *scalars, __global uint *element_ids, uint hints,
                                 __global const uchar *ebox, uint use_ebox, uint chain,
                                 __global const clvr_entry_grid *entry_grids, __global const uint *entry_cells)
{
    const clvr_mesh_view m = {tlas,      blas,      instances, vertices, idx16, idx32, tlas_root,
                              leaf_size, use_ebox ? ebox : NULL, CLVR_VIEW_ONE_PIECE, entry_grids, entry_cells};
    clvr_locate_points_in(&m, points, n, hints, chain, scalars, element_ids);
}

/* The mesh view of a kernel that takes the split arrays piece by piece
 * under the parameter names of clvr_locate_points_split (blas, instances,
 * leaf_size, vertices, idx16, idx32, vertices1 .. idx32_3): the top level
 * (tlas, root), the element boxes of pieces 0 .. 3 (eb0 .. eb3, NULL for
 * none) and the entry grids (grids, cells) vary. One initializer for the
 * four kernels that differ only in those. */
#define CLVR_PIECES_VIEW(tlas, root, eb0, eb1, eb2, eb3, grids, cells)                                              \
    {(tlas),                                                                                                     \
     blas,                                                                                                       \
     instances,                                                                                                  \
     vertices,                                                                                                   \
     idx16,                                                                                                      \
     idx32,                                                                                                      \
     (root),                                                                                                     \
     leaf_size,                                                                                                  \
     (eb0),                                                                                                      \
     {{vertices1, idx16_1, idx32_1, (eb1)}, {vertices2, idx16_2, idx32_2, (eb2)}, {vertices3, idx16_3, idx32_3, (eb3)}}, \
     (grids),                                                                                                    \
     (cells)}

/* clvr_locate_points over all CLVR_MAX_SPLITS pieces of the split arrays
 * (vertices, idx16, idx32, ebox: piece 0; then pieces 1 .. 3 of each;
 * unused pieces a small dummy buffer). entry_grids, entry_cells: the
 * tree's entry grids (locate.h), or NULL (walks from the roots). */
__kernel void clvr_locate_points_split(__global const float4 *points, uint n, __global const clvr_bvh_node *tlas,
                                       uint tlas_root, __global const clvr_bvh_node *blas,
                                       __global const clvr_instance *instances, uint leaf_size,
                                       __global float *scalars, __global uint *element_ids, uint hints,
                                       uint use_ebox, uint chain, __global const float4 *vertices,
                                       __global const ushort *idx16, __global const uint *idx32,
                                       __global const uchar *ebox, __global const float4 *vertices1,
                                       __global const ushort *idx16_1, __global const uint *idx32_1,
                                       __global const uchar *ebox1, __global const float4 *vertices2,
                                       __global const ushort *idx16_2, __global const uint *idx32_2,
                                       __global const uchar *ebox2, __global const float4 *vertices3,
                                       __global const ushort *idx16_3, __global const uint *idx32_3,
                                       __global const uchar *ebox3, __global const clvr_entry_grid *entry_grids,
                                       __global const uint *entry_cells)
{
    const clvr_mesh_view m =
        CLVR_PIECES_VIEW(tlas, tlas_root, use_ebox ? ebox : NULL, ebox1, ebox2, ebox3, entry_grids, entry_cells);
    clvr_locate_points_in(&m, points, n, hints, chain, scalars, element_ids);
}

/* The instance that holds leaf cluster `leaf`: the last one whose first
 * leaf is <= leaf (num_instances >= 1). */
inline uint clvr_instance_of_leaf(__global const clvr_instance *instances, uint num_instances, uint leaf)
{
    uint lo = 0, hi = num_instances;
    while (hi - lo > 1) {
        const uint mid = (lo + hi) / 2;
        if (instances[mid].first_leaf <= leaf) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* Quantized element boxes (locate.h), one work item per leaf cluster, into
 * the element boxes of the leaf's piece (ebox0 .. ebox3; pieces the mesh
 * does not have are never written). status[0] becomes nonzero when a leaf
 * is not in the slot of the node clvr_leaf_parent names (a tree layout this
 * code does not expect). */
__kernel void clvr_element_boxes(__global const clvr_bvh_node *blas, __global const clvr_instance *instances,
                                 uint num_instances, uint leaf_size, uint num_leaves, __global uint *status,
                                 __global const float4 *vertices, __global const ushort *idx16,
                                 __global const uint *idx32, __global uchar *ebox, __global const float4 *vertices1,
                                 __global const ushort *idx16_1, __global const uint *idx32_1, __global uchar *ebox1,
                                 __global const float4 *vertices2, __global const ushort *idx16_2,
                                 __global const uint *idx32_2, __global uchar *ebox2,
                                 __global const float4 *vertices3, __global const ushort *idx16_3,
                                 __global const uint *idx32_3, __global uchar *ebox3)
{
    const uint leaf = get_global_id(0);
    if (leaf >= num_leaves || num_instances == 0) return;
    const uint lo = clvr_instance_of_leaf(instances, num_instances, leaf);
    const clvr_instance inst = instances[lo];
    uint node, slot;
    clvr_leaf_parent(&inst, leaf, &node, &slot);
    if (leaf - inst.first_leaf >= inst.num_leaves || blas[node].child[slot] != (CLVR_BVH_LEAF_BIT | leaf)) {
        status[0] = 1u;
        return;
    }
    __global const clvr_bvh_node *n = blas + node;
    const float L[3] = {n->lo_x[slot], n->lo_y[slot], n->lo_z[slot]};
    const float H[3] = {n->hi_x[slot], n->hi_y[slot], n->hi_z[slot]};
    const clvr_mesh_view m = CLVR_PIECES_VIEW(NULL, 0u, NULL, NULL, NULL, NULL, NULL, NULL);
    __global uchar *out = inst.piece == 1u ? ebox1 : inst.piece == 2u ? ebox2 : inst.piece == 3u ? ebox3 : ebox;
    clvr_ebox_build_leaf(&m, &inst, leaf, L, H, out);
}

/* Entry grids (locate.h), first pass: one work item per leaf cluster
 * marks the cells its elements' boxes meet (clvr_entry_element_hull):
 * atomic min / max of its id in its instance's grid (cells hold (first,
 * last) leaf pairs, filled with (NOT_FOUND, 0) before), atomic or of the
 * bits of the occupancy grid's cells that the box and the element's slabs
 * both meet (cleared before). The arrays come piece by piece as
 * clvr_locate_points_split takes them. */
__kernel void clvr_entry_rasterize(__global const clvr_bvh_node *blas, __global const clvr_instance *instances,
                                   __global const clvr_entry_grid *grids, uint num_instances, uint num_leaves,
                                   __global uint *cells, uint leaf_size, __global const float4 *vertices,
                                   __global const ushort *idx16, __global const uint *idx32,
                                   __global const float4 *vertices1, __global const ushort *idx16_1,
                                   __global const uint *idx32_1, __global const float4 *vertices2,
                                   __global const ushort *idx16_2, __global const uint *idx32_2,
                                   __global const float4 *vertices3, __global const ushort *idx16_3,
                                   __global const uint *idx32_3)
{
    const uint leaf = get_global_id(0);
    if (leaf >= num_leaves || num_instances == 0) return;
    const uint lo = clvr_instance_of_leaf(instances, num_instances, leaf);
    const clvr_instance inst = instances[lo];
    if (leaf - inst.first_leaf >= inst.num_leaves) return;
    const clvr_entry_grid g = grids[1u + lo], occ = grids[0]; /* [0]: the occupancy grid */
    const clvr_mesh_view m = CLVR_PIECES_VIEW(NULL, 0u, NULL, NULL, NULL, NULL, NULL, NULL);
    const clvr_piece_arrays pa = clvr_view_piece(&m, &inst);
    uint end;
    for (uint e = clvr_leaf_elements(&m, &inst, leaf, &end); e < end; ++e) {
        float L[3], H[3];
        uint a[3], b[3];
        clvr_element_slabs sl;
        clvr_entry_element_hull(&pa, &inst, e, L, H, &sl);
        clvr_entry_box_cells(&g, L, H, a, b);
        for (uint z = a[2]; z <= b[2]; ++z)
            for (uint y = a[1]; y <= b[1]; ++y)
                for (uint x = a[0]; x <= b[0]; ++x) {
                    __global uint *c = cells + 2ul * (g.res[3] + (z * g.res[1] + y) * g.res[0] + x);
                    if (c[0] > leaf) atomic_min(c, leaf);
                    if (c[1] < leaf) atomic_max(c + 1, leaf);
                }
        /* A word's bits only go from 0 to 1 (a cell's first leaf only
         * down, its last only up), so a read that finds the change made
         * skips the atomic: the elements of a leaf share most cells, and
         * the atomics were most of this pass's time. */
        clvr_entry_box_cells(&occ, L, H, a, b);
        for (uint z = a[2]; z <= b[2]; ++z)
            for (uint y = a[1]; y <= b[1]; ++y) {
                const uint c0 = (z * occ.res[1] + y) * occ.res[0] + a[0], c1 = c0 + (b[0] - a[0]);
                float blo[2], bhi[2];
                clvr_entry_cell_span(&occ, 1, y, &blo[0], &bhi[0]);
                clvr_entry_cell_span(&occ, 2, z, &blo[1], &bhi[1]);
                for (uint w = c0 / 32u; w <= c1 / 32u; ++w) {
                    const uint box = clvr_occupancy_mask(w == c0 / 32u ? c0 % 32u : 0u, w == c1 / 32u ? c1 % 32u : 31u);
                    __global uint *word = cells + occ.res[3] + w;
                    const uint mask = clvr_occupancy_row_bits(&occ, &sl, w, c0, c1, a[0], blo, bhi, box & ~*word);
                    if (mask) atomic_or(word, mask);
                }
            }
    }
}

/* The split arrays and element boxes of pieces 0 .. 3 as kernel
 * parameters, under the names CLVR_PIECES_VIEW takes. */
#define CLVR_EBOX_PIECE_PARAMS                                                                                         \
    __global const float4 *vertices, __global const ushort *idx16, __global const uint *idx32,                       \
        __global const uchar *ebox, __global const float4 *vertices1, __global const ushort *idx16_1,                \
        __global const uint *idx32_1, __global const uchar *ebox1, __global const float4 *vertices2,                 \
        __global const ushort *idx16_2, __global const uint *idx32_2, __global const uchar *ebox2,                   \
        __global const float4 *vertices3, __global const ushort *idx16_3, __global const uint *idx32_3,              \
        __global const uchar *ebox3

/* Entry grids, second pass: one work item per cell of all instances' grids
 * (grids[1 + i].res[3]: instance i's first cell, increasing; every grid
 * has a cell) turns its (first, last) leaf pair into (start, hint) nodes. The
 * arrays come piece by piece as clvr_locate_points_split takes them. */
__kernel void clvr_entry_finish(__global const clvr_bvh_node *blas, __global const clvr_instance *instances,
                                __global const clvr_entry_grid *grids, uint num_instances, uint num_cells,
                                __global uint *cells, uint leaf_size, uint use_ebox, CLVR_EBOX_PIECE_PARAMS)
{
    const uint i = get_global_id(0);
    if (i >= num_cells || num_instances == 0) return;
    uint lo = 0, hi = num_instances; /* last instance whose first cell is <= i */
    while (hi - lo > 1) {
        const uint mid = (lo + hi) / 2;
        if (grids[1u + mid].res[3] <= i) lo = mid;
        else hi = mid;
    }
    const clvr_entry_grid g = grids[1u + lo]; /* [0]: the occupancy grid */
    const clvr_instance inst = instances[lo];
    const clvr_mesh_view m = CLVR_PIECES_VIEW(NULL, 0u, use_ebox ? ebox : NULL, ebox1, ebox2, ebox3, NULL, NULL);
    const uint c = i - g.res[3]; /* the cell within its grid */
    __global uint *cell = cells + 2ul * i;
    const uint start = cell[0] == CLVR_BVH_NOT_FOUND ? CLVR_BVH_NOT_FOUND : clvr_entry_lca(&inst, cell[0], cell[1]);
    cell[0] = start;
    cell[1] = clvr_entry_hint(&m, &inst, &g, start, c % g.res[0], c / g.res[0] % g.res[1], c / g.res[0] / g.res[1]);
}

/* cells[first_word + i] = clvr_global_hint of hint cell i at shift sh,
 * for i < num_cells, through the finished entry grids (their global hints
 * off: grids[0].lo[3] is 0 until the host sets it after this kernel). */
__kernel void clvr_entry_global(__global const clvr_bvh_node *tlas, __global const clvr_bvh_node *blas,
                                __global const clvr_instance *instances, __global const clvr_entry_grid *grids,
                                uint sh, uint num_cells, uint first_word, __global uint *cells, uint leaf_size,
                                uint use_ebox, CLVR_EBOX_PIECE_PARAMS)
{
    const uint i = get_global_id(0);
    if (i >= num_cells) return;
    const clvr_mesh_view m = CLVR_PIECES_VIEW(tlas, 0u, use_ebox ? ebox : NULL, ebox1, ebox2, ebox3, grids, cells);
    cells[first_word + i] = clvr_global_hint(&m, sh, i);
}

/* Ray queries over a single-level tree (root 0): rays as origin (w = tmin)
 * and direction (w = tmax). Per ray: number of boxes hit, sum of
 * (primitive + 1) and sum of t1 - t0 (tests compare with brute force). */
__kernel void clvr_bvh_ray_hits(__global const float4 *org, __global const float4 *dir, uint n,
                                __global const clvr_bvh_node *nodes, __global uint *count, __global ulong *prim_sum,
                                __global float *len_sum)
{
    const uint i = get_global_id(0);
    if (i >= n) return;
    const float4 o = org[i], d = dir[i];
    clvr_bvh_ray_iter it;
    clvr_bvh_ray_begin(&it, nodes, o.x, o.y, o.z, d.x, d.y, d.z, o.w, d.w);
    uint prim, c = 0;
    ulong ps = 0;
    float t0, t1, len = 0.0f;
    while (clvr_bvh_ray_next(&it, nodes, &prim, &t0, &t1)) {
        ++c;
        ps += (ulong)prim + 1u;
        len += t1 - t0;
    }
    count[i] = c;
    prim_sum[i] = ps;
    len_sum[i] = len;
}

/* Per ray (origin, direction; w unused): the first entry into and the last
 * exit from the boxes under a single-level tree (root 0) along [0, inf),
 * as (t0, t1, 1, 0), or (0, inf, 0, 0) when no box is hit: the layout of
 * clvr_hull_rays. The hull's first probe runs it over the sampling
 * clusters' boxes (host/pipeline/hull.c). */
__kernel void clvr_bvh_ray_span(__global const float4 *org, __global const float4 *dir, uint n,
                                __global const clvr_bvh_node *nodes, __global float4 *t01)
{
    const uint i = get_global_id(0);
    if (i >= n) return;
    const float4 o = org[i], d = dir[i];
    clvr_bvh_ray_iter it;
    clvr_bvh_ray_begin(&it, nodes, o.x, o.y, o.z, d.x, d.y, d.z, 0.0f, INFINITY);
    uint prim;
    float t0, t1, first = INFINITY, last = -INFINITY;
    while (clvr_bvh_ray_next(&it, nodes, &prim, &t0, &t1)) {
        first = fmin(first, t0);
        last = fmax(last, t1);
    }
    t01[i] = first <= last ? (float4)(first, last, 1.0f, 0.0f) : (float4)(0.0f, INFINITY, 0.0f, 0.0f);
}

/* ------------------------------------------------------------ hull
 * The boundary faces of a clustered mesh (kernels/hull.h), in three
 * passes over face slots (face_first: the first slot of each instance,
 * num_instances + 1 entries; see clvr_hull_slot_face): keys, then, after a
 * sort of (key, slot) pairs, a flag per slot that has no twin, then, after
 * a select of the flagged slots, the faces and their boxes. The mesh's
 * pieces as in clvr_element_boxes. */
#define CLVR_HULL_PIECE_PARAMS                                                                                         \
    __global const float4 *vertices, __global const ushort *idx16, __global const uint *idx32,                       \
        __global const float4 *vertices1, __global const ushort *idx16_1, __global const uint *idx32_1,              \
        __global const float4 *vertices2, __global const ushort *idx16_2, __global const uint *idx32_2,              \
        __global const float4 *vertices3, __global const ushort *idx16_3, __global const uint *idx32_3
#define CLVR_HULL_VIEW(instances)                                                                                      \
    {NULL,                                                                                                             \
     NULL,                                                                                                             \
     instances,                                                                                                        \
     vertices,                                                                                                         \
     idx16,                                                                                                            \
     idx32,                                                                                                            \
     0u,                                                                                                               \
     0u,                                                                                                               \
     NULL,                                                                                                             \
     {{vertices1, idx16_1, idx32_1, NULL}, {vertices2, idx16_2, idx32_2, NULL}, {vertices3, idx16_3, idx32_3, NULL}}, \
     NULL,                                                                                                             \
     NULL}

/* keys[slot] = clvr_hull_face_key of the face in that slot. */
__kernel void clvr_hull_keys(__global const clvr_instance *instances, uint num_instances,
                             __global const uint *face_first, uint num_slots, __global ulong *keys,
                             CLVR_HULL_PIECE_PARAMS)
{
    const uint slot = get_global_id(0);
    if (slot >= num_slots) return;
    const clvr_mesh_view m = CLVR_HULL_VIEW(instances);
    uint i, e, f;
    clvr_hull_slot_face(instances, face_first, num_instances, slot, &i, &e, &f);
    const clvr_instance inst = instances[i];
    clvr_hull_face h;
    clvr_hull_face_load(&m, &inst, e, f, &h);
    keys[slot] = clvr_hull_face_key(&h);
}

/* keys, slots: sorted pairs. flags[slot] = clvr_hull_boundary, with the
 * two common cases short-cut (the same flags; test_hull compares them with
 * the reference): a key that no other slot has is a boundary face without
 * loading it, and a key that exactly two slots share (an interior face
 * seen from both sides) is decided once, by the first of the two, which
 * loads each face once instead of each work-item loading both (the flags
 * pass was half of the hull's build on 1M tets). */
__kernel void clvr_hull_flags(__global const clvr_instance *instances, uint num_instances,
                              __global const uint *face_first, uint num_slots, __global const ulong *keys,
                              __global const uint *slots, __global uint *flags, CLVR_HULL_PIECE_PARAMS)
{
    const uint i = get_global_id(0);
    if (i >= num_slots) return;
    const ulong key = keys[i];
    const int prev = i > 0u && keys[i - 1u] == key, next = i + 1u < num_slots && keys[i + 1u] == key;
    /* (the key of slots with no face takes the general path, which loads the face) */
    if (!prev && !next && key != CLVR_HULL_NO_FACE_KEY) {
        flags[slots[i]] = 1u;
        return;
    }
    const int prev2 = prev && i > 1u && keys[i - 2u] == key, next2 = next && i + 2u < num_slots && keys[i + 2u] == key;
    if (prev && !next && !prev2) return; /* the second of a pair: the first decides both */
    const clvr_mesh_view m = CLVR_HULL_VIEW(instances);
    if (!prev && next && !next2 && key != CLVR_HULL_NO_FACE_KEY) {
        clvr_hull_face a, b;
        clvr_hull_slot_load(&m, instances, face_first, num_instances, slots[i], &a);
        clvr_hull_slot_load(&m, instances, face_first, num_instances, slots[i + 1u], &b);
        const uint boundary = clvr_hull_opposite(&a, &b) ? 0u : 1u;
        flags[slots[i]] = boundary;
        flags[slots[i + 1u]] = boundary;
        return;
    }
    flags[slots[i]] = clvr_hull_boundary(&m, instances, face_first, num_instances, num_slots, keys, slots, i);
}

/* keys, slots: sorted pairs. adj[slot] = the sorted element id across the
 * face in that slot (clvr_hull_twin), CLVR_BVH_NOT_FOUND on the boundary. */
__kernel void clvr_hull_adjacency(__global const clvr_instance *instances, uint num_instances,
                                  __global const uint *face_first, uint num_slots, __global const ulong *keys,
                                  __global const uint *slots, __global uint *adj, CLVR_HULL_PIECE_PARAMS)
{
    const uint i = get_global_id(0);
    if (i >= num_slots) return;
    const ulong key = keys[i];
    const int prev = i > 0u && keys[i - 1u] == key, next = i + 1u < num_slots && keys[i + 1u] == key;
    if (!prev && !next) {
        adj[slots[i]] = CLVR_BVH_NOT_FOUND;
        return;
    }
    const clvr_mesh_view m = CLVR_HULL_VIEW(instances);
    adj[slots[i]] = clvr_hull_twin(&m, instances, face_first, num_instances, num_slots, keys, slots, i);
}

/* Face k of the hull from boundary slot slots[k]: out[k] and its box. */
__kernel void clvr_hull_faces(__global const clvr_instance *instances, uint num_instances,
                              __global const uint *face_first, __global const uint *slots, uint num_faces,
                              __global clvr_hull_face *out, __global float *boxes, CLVR_HULL_PIECE_PARAMS)
{
    const uint k = get_global_id(0);
    if (k >= num_faces) return;
    const clvr_mesh_view m = CLVR_HULL_VIEW(instances);
    clvr_hull_face h;
    clvr_hull_face_at(&m, instances, face_first, num_instances, slots[k], &h, boxes + 8u * (ulong)k);
    out[k] = h;
}

/* Ray queries over a hull (tests compare with brute force): per ray
 * (origin, direction; w unused), clvr_hull_clip's interval starting from
 * [0, inf) in t01 (x, y) and its result in z. */
__kernel void clvr_hull_rays(__global const float4 *org, __global const float4 *dir, uint n,
                             __global const clvr_bvh_node *nodes, __global const clvr_hull_face *faces,
                             __global float4 *t01)
{
    const uint i = get_global_id(0);
    if (i >= n) return;
    const float4 o = org[i], d = dir[i];
    float t0 = 0.0f, t1 = INFINITY;
    const int hit = clvr_hull_clip(nodes, faces, o.x, o.y, o.z, d.x, d.y, d.z, &t0, &t1);
    t01[i] = (float4)(t0, t1, (float)hit, 0.0f);
}

/* clvr_hull_gaps per ray (tests compare with brute force): CLVR_HULL_GAP_STRIDE
 * floats per ray into out: the cut of [0, inf) (t0, t1), the result (gaps,
 * -1 miss, -2 too many crossings), 0, then the gaps' ends. */
__kernel void clvr_hull_gap_rays(__global const float4 *org, __global const float4 *dir, uint n,
                                 __global const clvr_bvh_node *nodes, __global const clvr_hull_face *faces,
                                 __global float *out)
{
    const uint i = get_global_id(0);
    if (i >= n) return;
    const float4 o = org[i], d = dir[i];
    float t0 = 0.0f, t1 = INFINITY, glo[CLVR_HULL_MAX_HITS], ghi[CLVR_HULL_MAX_HITS];
    const int r = clvr_hull_gaps(nodes, faces, o.x, o.y, o.z, d.x, d.y, d.z, &t0, &t1, glo, ghi);
    __global float *w = out + (ulong)i * CLVR_HULL_GAP_STRIDE;
    w[0] = t0;
    w[1] = t1;
    w[2] = (float)r;
    w[3] = 0.0f;
    for (int k = 0; k < r; ++k) {
        w[4 + 2 * k] = glo[k];
        w[5 + 2 * k] = ghi[k];
    }
}

/* Layout of the shared bvh structs as the device sees them (the host
 * compares with its own sizeof/offsetof). */
__kernel void clvr_bvh_sizes(__global uint *out)
{
    out[0] = (uint)sizeof(clvr_bvh_node);
    out[1] = (uint)sizeof(clvr_bvh_tree);
    out[2] = (uint)sizeof(clvr_instance);
    out[3] = (uint)sizeof(clvr_vec4);
    /* OpenCL C 1.2 has no offsetof: measure on private objects */
    clvr_bvh_node nd;
    clvr_instance in;
    out[4] = (uint)((char *)&nd.child[0] - (char *)&nd);
    out[5] = (uint)((char *)&in.first_index - (char *)&in);
    out[6] = (uint)((char *)&in.bvh_root - (char *)&in);
}
