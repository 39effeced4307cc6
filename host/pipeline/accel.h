/* accel.h: every acceleration structure the renderer traverses, built once
 * per clustered mesh: the two-level BVH for point location (bvh/) and the
 * single-level BVH over the adaptive-sampling clusters for the `bins`
 * method's ray-vs-cluster queries, and the tree over the mesh's boundary
 * faces that tells a camera ray where the medium can begin and end (hull.h). */
#ifndef CLVR_ACCEL_H
#define CLVR_ACCEL_H

#include "bvh.h"
#include "hull.h"
#include "cl_context.h"
#include "preprocess.h"

typedef struct clvr_accel {
    clvr_bvh_kernels kernels;
    clvr_bvh_device two_level;   /* tlas, blas */
    cl_mem sampling_nodes;       /* BVH over clustered->sampling */
    uint32_t sampling_node_count;
    uint32_t tlas_root;
    clvr_hull hull;              /* boundary faces and their tree (hull.h) */
    char hull_skipped[1024];     /* why CLVR_HULL_AUTO built none (device memory, size), or "" */
    double build_s;              /* wall seconds of clvr_accel_build */
} clvr_accel;

/* Builds every tree; fills c->host_instances[].bvh_root and the device
 * copy. The hull as CLVR_HULL_AUTO (hull.h). */
clvr_status clvr_accel_build(clvr_cl *cl, clvr_clustered *c, clvr_accel *out, clvr_error *err);
/* The same with the hull's mode given (CLVR_HULL_OFF, _AUTO, _ON). */
clvr_status clvr_accel_build_hull(clvr_cl *cl, clvr_clustered *c, int hull_mode, clvr_accel *out, clvr_error *err);
/* Releases everything; accepts NULL and half-built. */
void clvr_accel_release(clvr_cl *cl, clvr_accel *a);
/* The element boxes' buffers piece by piece, as the kernels take them:
 * out[0] NULL when there are none, pieces c lacks a placeholder. */
void clvr_accel_get_ebox_pieces(const clvr_clustered *c, const clvr_accel *a, cl_mem out[CLVR_MAX_SPLITS]);
/* Point location on the device (the clvr_locate_points_split kernel, every
 * piece of a split mesh): n points as float4 (x, y, z, unused) in, the
 * interpolated scalar and global sorted element id (CLVR_BVH_NOT_FOUND
 * outside) per point out. hints, chain: as the kernel (chain 0 or 1: one
 * point per work item, the full walk). */
clvr_status clvr_accel_locate(clvr_cl *cl, const clvr_clustered *c, const clvr_accel *a, const float *points,
                              uint32_t n, uint32_t hints, uint32_t chain, float *scalars, uint32_t *element_ids,
                              clvr_error *err);
/* Device bytes of the two-level BVH (the paper's "BVH size"). */
uint64_t clvr_accel_bvh_bytes(const clvr_accel *a);

#endif
