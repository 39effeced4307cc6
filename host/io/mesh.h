/* mesh.h: the in-memory unstructured mesh, as the paper keeps it (section
 * 3.1): one float3 per vertex, one float scalar per vertex, and four index
 * lists, one per element type, VTK vertex order. Counts are 64-bit so that
 * meshes with more than 2^31 indices never overflow on the host; vertex
 * indices themselves are 32-bit (at most 2^32 - 1 vertices). */
#ifndef CLVR_MESH_H
#define CLVR_MESH_H

#include <stdint.h>
#include <stddef.h>

#include "clvr_shared.h"
#include "status.h"

#define CLVR_SCALAR_NAME_MAX 64

typedef struct clvr_mesh {
    uint64_t num_vertices;
    float *positions;                              /* 3 * num_vertices, x y z interleaved */
    float *scalars;                                /* num_vertices */
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];      /* per CLVR_CELL_* */
    uint32_t *indices[CLVR_CELL_TYPE_COUNT];       /* num_cells[t] * clvr_cell_vertex_count(t) */
    char scalar_name[CLVR_SCALAR_NAME_MAX];        /* NUL-terminated, may be empty */
    float bounds_lo[3], bounds_hi[3];              /* of all vertices (clvr_mesh_update_ranges) */
    float scalar_min, scalar_max;                  /* of all scalars */
    uint64_t skipped_cells;                        /* cells of other types the loader left out
                                                    * (VTK/umesh surface and line cells) */
} clvr_mesh;

/* Allocates arrays for the given counts (zeroed struct first). On failure
 * frees what it got and returns CLVR_ERR_NO_MEMORY or CLVR_ERR_OVERFLOW. */
clvr_status clvr_mesh_alloc(clvr_mesh *m, uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                            clvr_error *err);
/* Frees every array; accepts NULL and half-built meshes; leaves *m zeroed. */
void clvr_mesh_free(clvr_mesh *m);

/* Total element count over the four types. */
uint64_t clvr_mesh_num_elements(const clvr_mesh *m);
/* Number of uint32 indices of type t (num_cells[t] * vertex count). */
uint64_t clvr_mesh_num_indices(const clvr_mesh *m, uint32_t t);
/* Bytes held by vertices+scalars and by the index lists. */
uint64_t clvr_mesh_vertex_bytes(const clvr_mesh *m);
uint64_t clvr_mesh_index_bytes(const clvr_mesh *m);

/* Recomputes bounds and scalar range from the arrays. */
void clvr_mesh_update_ranges(clvr_mesh *m);

/* Checks what a renderer relies on: at least one element, every index below
 * num_vertices, every coordinate finite. Scalars that are NaN/Inf are an
 * error too. `what` names the source (a file path) in the message, e.g.
 * "mesh.bin: hexes[12] vertex 5 is index 901 but the mesh has 900 vertices". */
clvr_status clvr_mesh_validate(const clvr_mesh *m, const char *what, clvr_error *err);

/* Safe a*b for sizes: returns 0 and sets *out, or 1 on overflow. */
int clvr_mul_u64(uint64_t a, uint64_t b, uint64_t *out);
int clvr_add_u64(uint64_t a, uint64_t b, uint64_t *out);

/* Sets m->scalar_name from len bytes of name (stopping at a NUL), at most
 * CLVR_SCALAR_NAME_MAX - 1 of them. Names come from files and end up in
 * one-line messages, --info and JSON, so control characters, quotes and
 * backslashes become '?'. */
void clvr_mesh_set_scalar_name(clvr_mesh *m, const char *name, size_t len);

/* Name of a cell type: "tets", "pyramids", "wedges", "hexes". */
const char *clvr_cell_type_name(uint32_t t);

#endif /* CLVR_MESH_H */
