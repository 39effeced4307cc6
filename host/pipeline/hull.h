/* hull.h: the boundary faces of a clustered mesh and the tree over them
 * (kernels/hull.h), built on the device once per mesh beside the other
 * trees (accel.h), or on the host by the plain-C reference with the same
 * result bit for bit. The renderer cuts every camera ray to the part
 * between its first and last crossing of these faces.
 *
 * Device build: a key per face slot (every face of every element), a
 * key-value radix sort of (key, slot), a flag per slot without a twin,
 * a select of the flagged slots (element order, so the faces follow the
 * elements' Hilbert curve), the faces and their boxes, and a 4-wide tree
 * over them. Transient device memory: 24 bytes per face slot (4 to 6
 * slots per element: keys and slots, twice over for the sort); kept: 64
 * bytes per boundary face and the tree's nodes (112 bytes per 3 faces or
 * so). */
#ifndef CLVR_HULL_BUILD_H
#define CLVR_HULL_BUILD_H

#include <stdint.h>

#include "bvh.h"
#include "cl_context.h"
#include "preprocess.h"

typedef struct clvr_hull {
    cl_mem faces;        /* clvr_hull_face [num_faces], or NULL when num_faces is 0 */
    cl_mem nodes;        /* tree over faces, root 0, clvr_bvh_nodes_bound(num_faces) nodes */
    uint32_t num_faces;
    uint32_t num_nodes;
    uint64_t num_slots;  /* faces of all elements */
    double build_s;      /* device seconds of the build's kernels (sort and select included) */
    /* The probe (hull.c): the mean fraction of a ray's chord
     * through the mesh's box that lies outside the mesh (before its first
     * or after its last crossing; a ray that misses the mesh counts 1), over
     * a fixed set of rays from 14 directions. Near 0 for a mesh that fills
     * its box: there the cut saves nothing and costs two tree walks a ray. */
    float empty_fraction;
    /* CLVR_HULL_AUTO's first probe: the same rays through the sampling
     * clusters' boxes, which contain the mesh, so at most empty_fraction
     * (-1 when not run). Under CLVR_HULL_MIN_BOX_EMPTY no hull is built
     * (boxes_only = 1, empty_fraction = box_fraction). */
    float box_fraction;
    int boxes_only;
    int kept;            /* faces and nodes are there for the renderer */
} clvr_hull;

/* Face adjacency, for the walk estimator (kernels/render_volume.h): the
 * same face keys and sort as the hull's build, then per face slot the
 * sorted element id across the face (kernels/hull.h, clvr_hull_twin), or
 * CLVR_BVH_NOT_FOUND on the boundary. 4 bytes per face slot (16 per tet)
 * kept; 24 per face slot while it builds. */
typedef struct clvr_adjacency {
    cl_mem adj;          /* uint [num_slots] */
    cl_mem face_first;   /* uint [num_instances + 1]: first slot of each instance (clvr_hull_face_first) */
    uint32_t num_slots;
    uint64_t bytes;      /* device bytes kept */
    double build_s;      /* device seconds of its kernels */
} clvr_adjacency;

/* How clvr_hull_build treats a mesh: CLVR_HULL_AUTO (the default) first
 * runs the probe's rays through the sampling clusters' boxes and builds
 * nothing when their empty fraction is under CLVR_HULL_MIN_BOX_EMPTY (the boxes
 * contain the mesh, so the hull's fraction is at least theirs; a mesh that
 * fills its box is caught there, for a few thousand tree walks instead of
 * the build, which costs about as much as the rest of the preprocessing);
 * otherwise it builds the hull and keeps it when its own probe finds
 * empty_fraction at least CLVR_HULL_MIN_EMPTY, releasing it otherwise
 * (kept = 0: the renderer cuts nothing and the memory is free again);
 * CLVR_HULL_ON keeps it always (tests, A/B runs); CLVR_HULL_OFF builds
 * nothing. */
#define CLVR_HULL_OFF 0
#define CLVR_HULL_AUTO 1
#define CLVR_HULL_ON 2

/* Below this empty_fraction, CLVR_HULL_AUTO drops the hull: the cut costs
 * two tree walks a ray (6-20% of a frame) and pays only where enough of the
 * box in front of the medium is empty. Measured at 256^2, urm, frames to 2%
 * without / with shadows, no cut -> cut
 * (bench/results/render-converge/2026-11-28-s28-hull.md): combustor (0.56)
 * 8 / 11 -> 3 / 4, kiefer_tet10 (0.77) 7 / 8 -> 4 / 4, post (0.23) 2 / 3 ->
 * 2 / 2, blunt fin (0.13) 2 / 2 -> 2 / 2 at 11% more a frame and a higher
 * two-frame error (its low-discrepancy frames interleave less well); meshes
 * that fill their box (1M tets, fire_ug, the built-in scene: under 0.02)
 * gain nothing. */
#define CLVR_HULL_MIN_EMPTY 0.15f
/* Below this box_fraction, CLVR_HULL_AUTO builds no hull. Half the above:
 * the clusters' boxes stick out of the mesh, so their fraction is lower
 * than the hull's: 0.70-0.85 of it on the real tet meshes measured (post
 * 0.169 / 0.230, blunt fin 0.094 / 0.132, combustor 0.489 / 0.563,
 * kiefer_tet10 0.574 / 0.766), 0.45 on the coarse legacy-VTK post (8750
 * hexes), near 0 on lattices with a hole of mixed cells (clusters of one
 * type span several cells). */
#define CLVR_HULL_MIN_BOX_EMPTY 0.075f

/* face_first[i] = the first face slot of instance i (num_instances + 1
 * entries; the last is the slot count). Fails with CLVR_ERR_OVERFLOW when
 * the mesh has 2^31 or more faces. */
clvr_status clvr_hull_face_first(const clvr_instance *instances, uint64_t num_instances, uint32_t *face_first,
                                 clvr_error *err);

/* Device build from c's device arrays (c->host_instances for the slot
 * layout), with its probe. cluster_tree: the tree over c's sampling
 * clusters (accel.h), for CLVR_HULL_AUTO's first probe; NULL skips that
 * probe. A mesh without elements gets an empty hull (num_faces 0). */
clvr_status clvr_hull_build(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_clustered *c, cl_mem cluster_tree,
                            int mode, clvr_hull *out, clvr_error *err);
/* Runs n rays (origin, direction: 4 floats each, w unused) through the
 * hull on the device: per ray t0, t1 (clvr_hull_clip's cut of [0, inf)),
 * hit (1 or 0) and 0 in out (4 floats each). */
clvr_status clvr_hull_rays(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_hull *h, const float *org,
                           const float *dir, uint32_t n, float *out, clvr_error *err);

/* The same rays through clvr_hull_gaps (kernels/hull.h) on the device:
 * CLVR_HULL_GAP_STRIDE floats per ray into out (see clvr_hull_gap_rays in
 * kernels/bvh.cl). Needs a hull with faces. */
clvr_status clvr_hull_gap_rays(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_hull *h, const float *org,
                               const float *dir, uint32_t n, float *out, clvr_error *err);

void clvr_hull_release(clvr_cl *cl, clvr_hull *h); /* accepts NULL and half-built */

/* Builds c's face adjacency on the device. A mesh without elements gets
 * none (NULL buffers). Errors: CLVR_ERR_OVERFLOW past 2^31 - 1 faces,
 * device memory and OpenCL errors. */
clvr_status clvr_adjacency_build(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_clustered *c, clvr_adjacency *out,
                                 clvr_error *err);
void clvr_adjacency_release(clvr_cl *cl, clvr_adjacency *a); /* accepts NULL and half-built */
/* Device bytes the renderer keeps for the hull: faces and tree, 0 when
 * none are kept. */
uint64_t clvr_hull_bytes(const clvr_hull *h);

/* The reference's first steps: every face slot's key cut to its top
 * key_bits bits (32: the whole key, as the device's build) with the slot,
 * sorted by key then slot (the device's stable sort's order): *keys and
 * *slots (*n entries, malloc'd), face_first num_instances + 1 entries
 * (clvr_hull_face_first). Fewer bits make keys collide (tests). */
clvr_status clvr_hull_sorted_slots_ref(const clvr_clustered_host *h, uint64_t num_instances, uint32_t key_bits,
                                      uint32_t *face_first, uint64_t **keys, uint32_t **slots, uint32_t *n,
                                      clvr_error *err);
/* The reference: the same faces and boxes (8 floats each) on the host from
 * the host copy of a mesh that is one piece (clvr_clustered_download).
 * *faces and *boxes are malloc'd (NULL when there are none). */
clvr_status clvr_hull_build_ref(const clvr_clustered_host *h, uint64_t num_instances, clvr_hull_face **faces,
                                float **boxes, uint32_t *num_faces, clvr_error *err);

#endif
