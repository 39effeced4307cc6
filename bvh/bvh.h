/* bvh.h: building the two-level BVH of the clustered mesh (bottom level per
 * instance cluster over its leaf clusters, top level over the instances) and
 * single-level BVHs over arbitrary boxes (sampling clusters), on the device
 * (OpenCL, kernels/bvh.cl) or on the host (the C reference, same code).
 * Node layout and sizes: clvr_shared.h, "bvh" section. Traversal:
 * kernels/bvh_traverse.h (iterators), kernels/locate.h (point location),
 * kernels/elements.h (containment and interpolation); all three compile on
 * the host too. */
#ifndef CLVR_BVH_H
#define CLVR_BVH_H

#include <stdint.h>

#include "../kernels/clvr_shared.h"
#include "../kernels/locate.h"
#include "cl_context.h"
#include "status.h"

/* Nodes of a tree over n primitives (n = 0 gives 1: an empty root).
 * Worst case about n / 3 + log4(n) + 1. */
uint32_t clvr_bvh_nodes_bound(uint32_t num_prims);

/* Single-level tree over n boxes given with a 32-byte stride (clvr_box or
 * clvr_sampling_cluster: lo xyz at floats 0..2, hi xyz at 4..6); the ray
 * iterator reports primitive i for box i. nodes must hold
 * clvr_bvh_nodes_bound(n); the root is node 0. */
clvr_status clvr_bvh_build_boxes(const void *boxes, uint32_t n, clvr_bvh_node *nodes, clvr_error *err);

/* The two-level tree in host memory. */
typedef struct clvr_bvh_host {
    clvr_bvh_node *tlas;
    uint32_t tlas_nodes;
    uint32_t tlas_root;   /* always 0 */
    clvr_bvh_node *blas;  /* every instance's tree, instance order */
    uint32_t blas_nodes;
} clvr_bvh_host;

/* Entry grids (kernels/locate.h) of num_instances instances from their
 * bounds and leaf and element counts: grids[0] gets the occupancy grid
 * over all instances, grids[1 + i] instance i's grid (num_instances + 1 in
 * all); each its box, cells per unit length, cells per axis and first cell
 * (instance grids: first cell, 2 words each, in instance order from 0;
 * occupancy grid: first word, after every instance's cells; its global
 * hints follow its bits, at the finest shift (clvr_global_hints_shift,
 * kept as 1 + shift in grids[0].lo[3]) that keeps them within
 * CLVR_GLOBAL_HINT_MAX_CELLS and the whole cell array within max_bytes
 * (0: no limit), or none (lo[3] 0) when no shift does or the mesh is too
 * large for them). *num_words: u32 words of the cell array. Fails with
 * CLVR_ERR_OVERFLOW past 2^32 - 1 words. */
clvr_status clvr_entry_grids_layout(const clvr_instance *instances, uint32_t num_instances, uint64_t max_bytes,
                                    clvr_entry_grid *grids, uint32_t *num_words, clvr_error *err);
/* Host reference of the cells (kernels/locate.h): for cell c of instance
 * i's grid, cells[2 (grids[1 + i].res[3] + c)] its start node and the next
 * word its hint leaf; from word grids[0].res[3] on the occupancy grid's
 * bits, then its global hints (clvr_global_hints_first) when the layout
 * planned them (grids[0].lo[3], which is 0 while they are built and
 * restored after); num_words words in all, as the layout counted them. m
 * holds host arrays (tlas, blas with bvh_root set, instances, vertices,
 * idx16, idx32, leaf_size, ebox or NULL; its entry grids and cells are not
 * read: grids and cells stand in for them). */
clvr_status clvr_entry_cells_host(const clvr_mesh_view *m, uint32_t num_instances, clvr_entry_grid *grids,
                                  uint32_t num_words, uint32_t *cells, clvr_error *err);

/* Host build: instances[i].bvh_root is filled; leaf_boxes has num_leaves
 * boxes (global leaf ids, as instances[].first_leaf count them). Caller frees
 * with clvr_bvh_host_free. Fails with CLVR_ERR_BAD_FIELD when an instance's
 * leaves fall outside leaf_boxes, CLVR_ERR_OVERFLOW past 2^31 - 1 nodes. */
clvr_status clvr_bvh_build_host(clvr_instance *instances, uint32_t num_instances, const clvr_box *leaf_boxes,
                                uint32_t num_leaves, clvr_bvh_host *out, clvr_error *err);
void clvr_bvh_host_free(clvr_bvh_host *b);

/* Compiled kernels/bvh.cl, made once per context. */
typedef struct clvr_bvh_kernels {
    cl_program program;
    cl_kernel build_level;
    cl_kernel locate_points;
    cl_kernel locate_points_split; /* the same over the pieces of a split mesh (clvr_accel_locate) */
    cl_kernel ray_hits;
    cl_kernel ray_span; /* first entry and last exit of a tree's boxes per ray (the hull's first probe) */
    cl_kernel element_boxes;
    cl_kernel entry_rasterize, entry_finish, entry_global; /* entry grids (clvr_bvh_entry_grids_pieces) */
    cl_kernel hull_keys, hull_flags, hull_faces, hull_rays, hull_gap_rays, hull_adjacency; /* host/pipeline/hull.h */
} clvr_bvh_kernels;
clvr_status clvr_bvh_kernels_create(clvr_cl *cl, clvr_bvh_kernels *out, clvr_error *err);
void clvr_bvh_kernels_destroy(clvr_bvh_kernels *k); /* accepts NULL and half-built */

/* The two-level tree in device memory. */
typedef struct clvr_bvh_device {
    cl_mem tlas, blas;
    uint32_t tlas_nodes, blas_nodes;
    uint32_t tlas_root;   /* always 0 */
    double build_seconds; /* kernel time (event profiling) of the bottom-level build */
    cl_mem ebox;          /* quantized element boxes (clvr_bvh_element_boxes_device), or NULL; piece 0 of
                             a split mesh's (clvr_bvh_element_boxes_pieces) */
    cl_mem ebox_more[CLVR_MAX_SPLITS - 1]; /* pieces 1 .. of a split mesh's element boxes, else NULL */
    uint64_t ebox_bytes;  /* all pieces */
    cl_mem entry_grids;   /* the occupancy grid, then a clvr_entry_grid per instance (kernels/locate.h), or NULL */
    cl_mem entry_cells;   /* the instances' cells (start node, hint leaf), then the occupancy bits */
    uint64_t entry_bytes; /* both */
} clvr_bvh_device;

/* Device build. host_instances (the host copy of the instances buffer) gets
 * bvh_root filled and is written to `instances` (the device buffer of the
 * same num_instances entries). The bottom level is built on the device from
 * leaf_boxes (num_leaves clvr_box); the top level (a few hundred instances at
 * most) on the host, then uploaded. Release with clvr_bvh_device_release. */
clvr_status clvr_bvh_build_device(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_instance *host_instances,
                                  uint32_t num_instances, cl_mem instances, cl_mem leaf_boxes, uint32_t num_leaves,
                                  clvr_bvh_device *out, clvr_error *err);
void clvr_bvh_device_release(clvr_cl *cl, clvr_bvh_device *b);

/* Device build of a single-level tree over n boxes in a device buffer
 * (32-byte stride, as clvr_bvh_build_boxes). *out_nodes receives a new
 * buffer of clvr_bvh_nodes_bound(n) nodes, root 0 (release with
 * clvr_cl_release). */
clvr_status clvr_bvh_build_boxes_device(clvr_cl *cl, const clvr_bvh_kernels *k, cl_mem boxes, uint32_t n,
                                        cl_mem *out_nodes, clvr_error *err);

/* Quantized element boxes (kernels/locate.h: CLVR_EBOX_BYTES per sorted
 * element, each element's padded box relative to its leaf cluster's box in
 * the bottom-level tree), which let a leaf scan skip most candidates
 * without loading their vertices.
 * Host reference: m holds host arrays (blas, instances, vertices, idx16,
 * idx32, leaf_size; tlas and ebox are not read), out has room for
 * num_elements * CLVR_EBOX_BYTES bytes. Fails with CLVR_ERR_INTERNAL when a
 * leaf is not where the tree layout puts it. */
clvr_status clvr_bvh_element_boxes_host(const clvr_mesh_view *m, uint32_t num_instances, uint32_t num_leaves,
                                        uint8_t *out, clvr_error *err);
/* Device build into b->ebox (a new buffer; b->ebox_bytes set), from the
 * clustered mesh's device arrays and b->blas. */
clvr_status clvr_bvh_element_boxes_device(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                          cl_mem instances, uint32_t num_instances, cl_mem vertices, cl_mem idx16,
                                          cl_mem idx32, uint32_t leaf_size, uint32_t num_leaves,
                                          uint64_t num_elements, clvr_error *err);

/* The same for a mesh whose vertices and local indices are cut into
 * num_pieces pieces (clvr_instance.piece; preprocess.h): vertices, idx16
 * and idx32 hold CLVR_MAX_SPLITS buffers each (`dummy`, a small buffer, for
 * pieces past num_pieces), piece_elements the num_pieces + 1 element
 * prefixes. The boxes are cut the same way: b->ebox is piece 0, b->ebox_more
 * pieces 1 .. num_pieces - 1, each of its own elements. */
clvr_status clvr_bvh_element_boxes_pieces(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                          cl_mem instances, uint32_t num_instances, const cl_mem *vertices,
                                          const cl_mem *idx16, const cl_mem *idx32, const uint64_t *piece_elements,
                                          uint32_t num_pieces, cl_mem dummy, uint32_t leaf_size, uint32_t num_leaves,
                                          clvr_error *err);

/* Entry grids (kernels/locate.h) into b->entry_grids and b->entry_cells
 * (new buffers; b->entry_bytes set): their layout from host_instances
 * (bvh_root set) on the host, their cells on the device from b's trees and
 * the mesh's arrays, piece by piece as clvr_bvh_element_boxes_pieces takes
 * them (CLVR_MAX_SPLITS each; b's element boxes, when built, speed it up).
 * Build them after the element boxes. */
clvr_status clvr_bvh_entry_grids_pieces(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                        const clvr_instance *host_instances, cl_mem instances, uint32_t num_instances,
                                        const cl_mem *vertices, const cl_mem *idx16, const cl_mem *idx32,
                                        uint32_t leaf_size, uint32_t num_leaves, clvr_error *err);
/* The same for a mesh whose arrays are one piece. */
clvr_status clvr_bvh_entry_grids_device(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                        const clvr_instance *host_instances, cl_mem instances, uint32_t num_instances,
                                        cl_mem vertices, cl_mem idx16, cl_mem idx32, uint32_t leaf_size,
                                        uint32_t num_leaves, clvr_error *err);

/* Bytes of both levels. */
uint64_t clvr_bvh_bytes(uint32_t tlas_nodes, uint32_t blas_nodes);

#endif /* CLVR_BVH_H */
