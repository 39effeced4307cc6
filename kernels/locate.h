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

/* The arrays of a clustered mesh and its two-level tree that point location
 * reads, bundled so that the walk takes one argument instead of eight
 * (kernels build it on the stack from their arguments; the host points it
 * at host arrays). tlas_root: root of the top-level tree in tlas (0 for
 * clvr_bvh builds); each instance's bvh_root is its bottom-level root in
 * blas. leaf_size: elements per leaf cluster, as the clustering used. */
typedef struct clvr_mesh_view {
    CLVR_GLOBAL const clvr_bvh_node *tlas;
    CLVR_GLOBAL const clvr_bvh_node *blas;
    CLVR_GLOBAL const clvr_instance *instances;
    CLVR_GLOBAL const clvr_vec4 *vertices;
    CLVR_GLOBAL const clvr_u16 *idx16;
    CLVR_GLOBAL const clvr_u32 *idx32;
    clvr_u32 tlas_root;
    clvr_u32 leaf_size;
} clvr_mesh_view;

/* Loads the vertices of element e (global sorted id, inside instance
 * `inst`) into v[0 .. vertex_count(inst->type) - 1]. */
CLVR_INLINE void clvr_load_element(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 e, clvr_vec4 *v)
{
    CLVR_GLOBAL const clvr_vec4 *vertices = m->vertices;
    CLVR_GLOBAL const clvr_u16 *idx16 = m->idx16;
    CLVR_GLOBAL const clvr_u32 *idx32 = m->idx32;
    const clvr_u32 nv = clvr_cell_vertex_count(inst->type);
    const clvr_u64 base = inst->first_index + (clvr_u64)(e - inst->first_element) * nv;
    if (inst->index_bits == 16u) {
        for (clvr_u32 k = 0; k < nv; ++k) v[k] = vertices[inst->first_vertex + (clvr_u32)idx16[base + k]];
    } else {
        for (clvr_u32 k = 0; k < nv; ++k) v[k] = vertices[inst->first_vertex + idx32[base + k]];
    }
}

/* Loads tet e's 4 vertices (one 8-byte index load on the device for
 * 16-bit instances). */
CLVR_INLINE void clvr_load_tet(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 e, clvr_vec4 *v)
{
    CLVR_GLOBAL const clvr_u16 *idx16 = m->idx16;
    CLVR_GLOBAL const clvr_u32 *idx32 = m->idx32;
    const clvr_u64 base = inst->first_index + (clvr_u64)(e - inst->first_element) * 4u;
    CLVR_GLOBAL const clvr_vec4 *vb = m->vertices + inst->first_vertex;
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
CLVR_INLINE void clvr_prefetch_leaf(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 leaf)
{
    const clvr_u32 nv = clvr_cell_vertex_count(inst->type);
    const clvr_u64 base = inst->first_index + (clvr_u64)(leaf - inst->first_leaf) * m->leaf_size * nv;
    if (inst->index_bits == 16u) CLVR_PREFETCH(m->idx16 + base);
    else CLVR_PREFETCH(m->idx32 + base);
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
CLVR_INLINE void clvr_prefetch_leaf_vertices(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 leaf)
{
    if (inst->type != CLVR_CELL_TET) {
        clvr_prefetch_leaf(m, inst, leaf);
        return;
    }
    const clvr_u32 leaf_size = m->leaf_size;
    CLVR_GLOBAL const clvr_u16 *idx16 = m->idx16;
    CLVR_GLOBAL const clvr_u32 *idx32 = m->idx32;
    const clvr_u32 first = inst->first_element + (leaf - inst->first_leaf) * leaf_size;
    const clvr_u32 end_inst = inst->first_element + inst->num_elements;
    const clvr_u32 end = end_inst - first < leaf_size ? end_inst : first + leaf_size;
    CLVR_GLOBAL const clvr_vec4 *vb = m->vertices + inst->first_vertex;
    const clvr_u64 base = inst->first_index + (clvr_u64)(first - inst->first_element) * 4u;
    for (clvr_u32 i = 0; i < 4u * (end - first); ++i)
        CLVR_PREFETCH(vb + (inst->index_bits == 16u ? (clvr_u32)idx16[base + i] : idx32[base + i]));
}

/* Tests the elements of leaf cluster `leaf` of instance inst; returns 1 and
 * the scalar and element id of the first one that contains p. Each
 * candidate is first rejected by its vertex box (most of a leaf's elements
 * are not near p, and the box test is cheaper than a solve); tets then take
 * the early-out barycentric test, other types Newton. */
CLVR_INLINE int clvr_locate_in_leaf(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 leaf, float px,
                                    float py, float pz, float *scalar, clvr_u32 *element_id)
{
    const clvr_u32 leaf_size = m->leaf_size;
    const clvr_u32 first = inst->first_element + (leaf - inst->first_leaf) * leaf_size;
    const clvr_u32 end_inst = inst->first_element + inst->num_elements;
    const clvr_u32 end = end_inst - first < leaf_size ? end_inst : first + leaf_size;
    clvr_vec4 v[CLVR_CELL_MAX_VERTS];
    if (inst->type == CLVR_CELL_TET) {
        for (clvr_u32 e = first; e < end; ++e) {
            clvr_load_tet(m, inst, e, v);
            if (!clvr_element_box_test(CLVR_CELL_TET, v, px, py, pz)) continue;
            if (clvr_tet_sample(v, px, py, pz, scalar)) {
                *element_id = e;
                return 1;
            }
        }
        return 0;
    }
    for (clvr_u32 e = first; e < end; ++e) {
        clvr_load_element(m, inst, e, v);
        if (!clvr_element_box_test(inst->type, v, px, py, pz)) continue;
        if (clvr_element_sample(inst->type, v, px, py, pz, scalar)) {
            *element_id = e;
            return 1;
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

/* CLVR_LOCATE_INCOHERENT: asks for the lines of every child in mask of node
 * n before any is searched, so that their misses overlap: for a leaf, its
 * tets' vertices (clvr_prefetch_leaf_vertices); for an inner node, its two
 * lines and, on the lowest level, its four leaves' index blocks (random
 * points search about 40% of them: 13.0 nodes, 2.45 leaves, 16.1 tets per
 * query on 1M tets, leaves of 8). One level further (a level-1 node's four
 * children, 7 lines) lost 5% and is not done. */
CLVR_INLINE void clvr_locate_prefetch_children(const clvr_mesh_view *m, const clvr_instance *inst,
                                               CLVR_GLOBAL const clvr_bvh_node *n, clvr_u32 mask, clvr_u32 level0)
{
    CLVR_GLOBAL const clvr_bvh_node *blas = m->blas;
    for (clvr_u32 c = 0; c < 4; ++c) {
        if (!((mask >> c) & 1u)) continue;
        const clvr_u32 ch = n->child[c];
        if (ch & CLVR_BVH_LEAF_BIT) {
            clvr_prefetch_leaf_vertices(m, inst, ch & CLVR_BVH_MAX_PRIMS);
            continue;
        }
        CLVR_PREFETCH(blas + ch);
        CLVR_PREFETCH((CLVR_GLOBAL const clvr_u8 *)(blas + ch) + CLVR_CACHE_LINE);
        if (ch >= level0) {
            const clvr_u32 leaf = inst->first_leaf + 4u * (ch - level0);
            for (clvr_u32 j = 0; j < 4u && leaf + j < inst->first_leaf + inst->num_leaves; ++j)
                clvr_prefetch_leaf(m, inst, leaf + j);
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
 * CLVR_LOCATE_INCOHERENT; results do not depend on them. */
CLVR_INLINE int clvr_locate_in_instance(const clvr_mesh_view *m, const clvr_instance *inst, float px, float py,
                                        float pz, clvr_u32 hints, float *scalar, clvr_u32 *element_id)
{
    CLVR_GLOBAL const clvr_bvh_node *blas = m->blas;
    clvr_u32 stack[CLVR_BVH_STACK_SIZE];
    clvr_u32 sp = 0, ref = inst->bvh_root;
    const int prefetch = (hints & CLVR_LOCATE_INCOHERENT) != 0u;
    const clvr_u32 level0 = prefetch ? clvr_locate_level0(inst) : 0u;
    for (;;) {
        CLVR_GLOBAL const clvr_bvh_node *n = blas + ref;
        const clvr_u32 mask = clvr_bvh_node_point_mask(n, px, py, pz);
        if (prefetch)
            clvr_locate_prefetch_children(m, inst, n, mask, level0);
        for (clvr_u32 c = 0; c < 4; ++c) {
            if (!((mask >> c) & 1u)) continue;
            const clvr_u32 ch = n->child[c];
            if (ch & CLVR_BVH_LEAF_BIT) {
                if (clvr_locate_in_leaf(m, inst, ch & CLVR_BVH_MAX_PRIMS, px, py, pz, scalar, element_id))
                    return 1;
            } else if (sp < CLVR_BVH_STACK_SIZE) {
                stack[sp++] = ch;
            }
        }
        if (sp == 0) return 0;
        ref = stack[--sp];
    }
}

/* Point location in mesh m: returns 1 when an element contains
 * (px, py, pz) and writes its interpolated scalar and global sorted element
 * id; 0 (and element id CLVR_BVH_NOT_FOUND) otherwise. hints:
 * CLVR_LOCATE_COHERENT or CLVR_LOCATE_INCOHERENT (a speed hint only: the
 * result is the same bit for bit). */
CLVR_INLINE int clvr_locate(const clvr_mesh_view *m, float px, float py, float pz, clvr_u32 hints, float *scalar,
                            clvr_u32 *element_id)
{
    *element_id = CLVR_BVH_NOT_FOUND;
    clvr_u32 stack[CLVR_BVH_STACK_SIZE];
    clvr_u32 sp = 0, ref = m->tlas_root;
    for (;;) {
        CLVR_GLOBAL const clvr_bvh_node *n = m->tlas + ref;
        const clvr_u32 mask = clvr_bvh_node_point_mask(n, px, py, pz);
        for (clvr_u32 c = 0; c < 4; ++c) {
            if (!((mask >> c) & 1u)) continue;
            const clvr_u32 ch = n->child[c];
            if (ch & CLVR_BVH_LEAF_BIT) {
                const clvr_instance inst = m->instances[ch & CLVR_BVH_MAX_PRIMS];
                if (clvr_locate_in_instance(m, &inst, px, py, pz, hints, scalar, element_id))
                    return 1;
            } else if (sp < CLVR_BVH_STACK_SIZE) {
                stack[sp++] = ch;
            }
        }
        if (sp == 0) return 0;
        ref = stack[--sp];
    }
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
