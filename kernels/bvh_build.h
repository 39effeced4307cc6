/* bvh_build.h: the packed 4-wide BVH builder's arithmetic and per-node step,
 * shared by the host reference (bvh/bvh.c) and the build kernel
 * (kernels/bvh.cl). Layout, see clvr_shared.h: a tree over n primitives has
 * levels 0 (nodes over primitives) .. H-1 (the root); level l has
 * ceil(n / 4^(l+1)) nodes (at least 1); nodes are stored root first, so
 * level l starts after the sizes of levels H-1 .. l+1. Node m of level l
 * covers children 4m .. 4m+3 of level l-1 (or primitives at level 0). All
 * nodes of one level are independent: the builder runs level 0 first, then
 * each higher level, one work item per node. */
#ifndef CLVR_BVH_BUILD_H
#define CLVR_BVH_BUILD_H

#include "clvr_shared.h"

#ifndef __OPENCL_VERSION__
#include <math.h>
#endif

/* Nodes of level l of a tree over n primitives (0 when the tree is lower). */
CLVR_INLINE clvr_u32 clvr_bvh_level_size(clvr_u32 n, clvr_u32 level)
{
    clvr_u64 s = n;
    for (clvr_u32 l = 0; l <= level; ++l) {
        if (l > 0 && s <= 1) return 0;
        s = (s + 3u) / 4u;
    }
    return s == 0 ? (level == 0 ? 1u : 0u) : (clvr_u32)s;
}

/* Number of levels (>= 1). */
CLVR_INLINE clvr_u32 clvr_bvh_height(clvr_u32 n)
{
    clvr_u32 h = 1;
    clvr_u64 s = (n + 3ull) / 4u;
    while (s > 1) {
        s = (s + 3u) / 4u;
        ++h;
    }
    return h;
}

/* Total nodes of a tree over n primitives. */
CLVR_INLINE clvr_u32 clvr_bvh_tree_size(clvr_u32 n)
{
    const clvr_u32 h = clvr_bvh_height(n);
    clvr_u32 total = 0;
    for (clvr_u32 l = 0; l < h; ++l) total += clvr_bvh_level_size(n, l);
    return total;
}

/* Offset of level l's first node from the tree's root. */
CLVR_INLINE clvr_u32 clvr_bvh_level_first(clvr_u32 n, clvr_u32 level)
{
    const clvr_u32 h = clvr_bvh_height(n);
    clvr_u32 off = 0;
    for (clvr_u32 l = h; l-- > level + 1;) off += clvr_bvh_level_size(n, l);
    return off;
}

/* Box of lo/hi grown by CLVR_BVH_BOX_PAD_REL of its largest extent plus a few
 * ulps of its coordinates (see clvr_element_box_test). */
CLVR_INLINE void clvr_bvh_pad_box(float *lx, float *ly, float *lz, float *hx, float *hy, float *hz)
{
    const float ext = fmax(fmax(*hx - *lx, *hy - *ly), *hz - *lz);
    const float mag = fmax(fmax(fmax(fabs(*lx), fabs(*hx)), fmax(fabs(*ly), fabs(*hy))), fmax(fabs(*lz), fabs(*hz)));
    const float pad = CLVR_BVH_BOX_PAD_REL * ext + 8.0f * 1.1920929e-7f * mag;
    *lx -= pad; *ly -= pad; *lz -= pad;
    *hx += pad; *hy += pad; *hz += pad;
}

/* Builds node m of level `level` of tree t. prim_boxes: 8 floats per
 * primitive (lo xyz _, hi xyz _: clvr_box and clvr_sampling_cluster both fit),
 * padded here; higher levels read the boxes of their finished child nodes. */
CLVR_INLINE void clvr_bvh_build_node(CLVR_GLOBAL clvr_bvh_node *nodes, CLVR_GLOBAL const float *prim_boxes,
                                     clvr_bvh_tree t, clvr_u32 level, clvr_u32 m)
{
    const clvr_u32 n = t.num_prims;
    CLVR_GLOBAL clvr_bvh_node *out = nodes + t.node_base + clvr_bvh_level_first(n, level) + m;
    const clvr_u32 nchildren = level == 0 ? n : clvr_bvh_level_size(n, level - 1);
    const clvr_u32 child_first = level == 0 ? 0u : t.node_base + clvr_bvh_level_first(n, level - 1);
    for (clvr_u32 c = 0; c < 4; ++c) {
        const clvr_u32 k = 4u * m + c;
        float lx = INFINITY, ly = INFINITY, lz = INFINITY, hx = -INFINITY, hy = -INFINITY, hz = -INFINITY;
        clvr_u32 ref = CLVR_BVH_EMPTY;
        if (k < nchildren) {
            if (level == 0) {
                CLVR_GLOBAL const float *b = prim_boxes + 8u * (clvr_u64)(t.first_prim + k);
                lx = b[0]; ly = b[1]; lz = b[2];
                hx = b[4]; hy = b[5]; hz = b[6];
                /* A primitive with an empty or NaN box stays unreachable. */
                if (lx <= hx && ly <= hy && lz <= hz) {
                    clvr_bvh_pad_box(&lx, &ly, &lz, &hx, &hy, &hz);
                } else {
                    lx = ly = lz = INFINITY;
                    hx = hy = hz = -INFINITY;
                }
                ref = CLVR_BVH_LEAF_BIT | (t.first_prim + k);
            } else {
                ref = child_first + k;
                CLVR_GLOBAL const clvr_bvh_node *ch = nodes + ref;
                for (int j = 0; j < 4; ++j) {
                    if (ch->child[j] == CLVR_BVH_EMPTY) continue;
                    lx = fmin(lx, ch->lo_x[j]); ly = fmin(ly, ch->lo_y[j]); lz = fmin(lz, ch->lo_z[j]);
                    hx = fmax(hx, ch->hi_x[j]); hy = fmax(hy, ch->hi_y[j]); hz = fmax(hz, ch->hi_z[j]);
                }
            }
        }
        out->lo_x[c] = lx; out->lo_y[c] = ly; out->lo_z[c] = lz;
        out->hi_x[c] = hx; out->hi_y[c] = hy; out->hi_z[c] = hz;
        out->child[c] = ref;
    }
}

#endif /* CLVR_BVH_BUILD_H */
