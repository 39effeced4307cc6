/* scene.h: procedural meshes built in memory: the default scene that `clvr`
 * renders when given no mesh, and parametrised boxes that tests of other
 * modules use as inputs with known answers.
 *
 * Every mesh here is a lattice of nx * ny * nz axis-aligned cubes (cells)
 * filling the box [lo, hi]; each cube becomes one hexahedron, two wedges
 * (split by the plane through its x = y diagonal), six pyramids (one per
 * face, apex at an added cube-centre vertex) or six tetrahedra (Kuhn /
 * Freudenthal split along the (0,0,0)-(1,1,1) diagonal). Cube faces are
 * planar, so neighbouring cubes tile the box exactly whatever their
 * decompositions: no gaps, no overlaps (faces need not be conforming; clvr
 * locates points per element). Vertex order is VTK's; every element has
 * positive volume under VTK's conventions, which for the wedge means that the
 * right-hand normal of triangle (0,1,2) points AWAY from triangle (3,4,5)
 * (vtkCellValidator rejects the other order as "faces oriented incorrectly").
 *
 * Vertex numbering (what the streaming functions below rely on):
 *   lattice vertex (i, j, k), 0 <= i <= nx etc., has index
 *     (k * (ny + 1) + j) * (nx + 1) + i;
 *   then one centre vertex per pyramid cube, in cube order (x fastest, then
 *   y, then z), starting at index (nx + 1) * (ny + 1) * (nz + 1).
 */
#ifndef CLVR_SCENE_H
#define CLVR_SCENE_H

#include <stdint.h>

#include "mesh.h"
#include "status.h"

/* How cubes are split into elements. */
typedef enum clvr_scene_mix {
    CLVR_SCENE_MIX_HEX = 0,     /* 1 hexahedron per cube */
    CLVR_SCENE_MIX_TET,         /* 6 tetrahedra per cube (Kuhn split; conforming) */
    CLVR_SCENE_MIX_WEDGE,       /* 2 wedges per cube */
    CLVR_SCENE_MIX_PYRAMID,     /* 6 pyramids per cube + 1 centre vertex */
    CLVR_SCENE_MIX_MIXED,       /* by the blob field at the cube centre (box-relative):
                                   >= 0.35 tets, >= 0.12 pyramids, >= 0.03 wedges, else hexes;
                                   fine elements where the field has features, as a CFD mesh */
    CLVR_SCENE_MIX_CYCLE,       /* type (i + j + k) mod 4 in the order hex, tet, wedge, pyramid:
                                   every type next to every other (small test meshes) */
    CLVR_SCENE_MIX_COUNT
} clvr_scene_mix;

/* The scalar per vertex. */
typedef enum clvr_scene_field {
    CLVR_SCENE_FIELD_CONSTANT = 0, /* params.value everywhere */
    CLVR_SCENE_FIELD_RAMP_X,       /* 0 at lo[0] to 1 at hi[0], linear (every element interpolates it exactly) */
    CLVR_SCENE_FIELD_BLOBS,        /* clvr_scene_blobs of the box-relative position, range [0, 1] */
    CLVR_SCENE_FIELD_COUNT
} clvr_scene_field;

typedef struct clvr_scene_box_params {
    uint32_t nx, ny, nz;       /* cubes per axis, each >= 1 */
    float lo[3], hi[3];        /* the box, lo < hi on every axis */
    clvr_scene_mix mix;
    clvr_scene_field field;
    float value;               /* the scalar of CLVR_SCENE_FIELD_CONSTANT */
    float jitter;              /* interior lattice vertices move by up to jitter * cube size per
                                  axis (uniform, deterministic from seed); boundary vertices stay
                                  on the boundary. Range [0, 0.25] keeps every element positive.
                                  Must be 0 for MIXED and CYCLE: jittered faces are bilinear
                                  patches that a neighbour of another type would not share. */
    uint64_t seed;             /* of the jitter */
} clvr_scene_box_params;

/* Fills p with a 10^3 hex box on [0,1]^3, constant scalar 1, no jitter. */
void clvr_scene_box_params_init(clvr_scene_box_params *p);

/* Builds the box mesh into *out (owned by the caller: clvr_mesh_free).
 * CLVR_ERR_USAGE for invalid parameters, CLVR_ERR_OVERFLOW when the mesh
 * would need more than 2^32 - 1 vertices, CLVR_ERR_NO_MEMORY. Ranges are set. */
clvr_status clvr_scene_box(const clvr_scene_box_params *p, clvr_mesh *out, clvr_error *err);

/* The built-in scene: a 56^3 MIXED box on [-1,1]^3 with the BLOBS field
 * (275,633 elements of all four types: a vortex ring, a rising flame
 * plume and two blobs in tets, wrapped in pyramid and wedge layers, hexes
 * elsewhere). Scalar name "blobs". */
clvr_status clvr_scene_default(clvr_mesh *out, clvr_error *err);

/* The analytic field of the scene at a point of the unit cube (coordinates
 * box-relative, in [0, 1]^3). Range [0, 1]. */
float clvr_scene_blobs(const float u[3]);

/* Signed volume of one element: the sum over its faces of cones from the
 * element's vertex centroid, quadrilateral faces fanned around their own
 * centroid (so the faces of neighbours cancel exactly and volumes of a tiling
 * sum to the volume of the domain, even for non-planar faces). Positive for
 * a valid element in VTK order. positions: the mesh's xyz array; idx: the
 * element's clvr_cell_vertex_count(type) indices. */
double clvr_scene_cell_volume(uint32_t type, const float *positions, const uint32_t *idx);

/* ---- streaming, for generators that cannot hold the mesh (tools/clvr-gen) */

/* Exact counts of the box mesh: vertices and cells per type. */
clvr_status clvr_scene_box_count(const clvr_scene_box_params *p, uint64_t *num_vertices,
                                 uint64_t num_cells[CLVR_CELL_TYPE_COUNT], clvr_error *err);

/* Positions (3 floats each) and scalars of lattice layer k (0 <= k <= nz):
 * (nx + 1) * (ny + 1) vertices, the ones with indices starting at
 * k * (nx + 1) * (ny + 1). */
void clvr_scene_box_layer(const clvr_scene_box_params *p, uint32_t k, float *xyz, float *s);

/* Worst-case sizes of the outputs of one slab: per type, the cells of one
 * layer of nx * ny cubes, and the centre vertices. */
void clvr_scene_box_slab_bound(const clvr_scene_box_params *p, uint64_t max_cells[CLVR_CELL_TYPE_COUNT],
                               uint64_t *max_centres);

/* The elements of cube layer k (0 <= k < nz): appends to cells[t] (room for
 * the bound above) and writes the new centre vertices to centre_xyz /
 * centre_s; first_centre is the index of the first centre vertex of this
 * layer (lattice vertex count + centres of layers below). Counts written
 * are returned in num_cells and *num_centres. */
void clvr_scene_box_slab(const clvr_scene_box_params *p, uint32_t k, uint64_t first_centre,
                         uint32_t *cells[CLVR_CELL_TYPE_COUNT], uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                         float *centre_xyz, float *centre_s, uint64_t *num_centres);

/* Validates p; CLVR_ERR_USAGE with a message naming the field. */
clvr_status clvr_scene_box_check(const clvr_scene_box_params *p, clvr_error *err);

#endif /* CLVR_SCENE_H */
