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

/* Where a field's values live. */
#define CLVR_FIELD_POINT 0u /* one tuple per vertex */
#define CLVR_FIELD_CELL 1u  /* one tuple per element, in the order tets, pyramids, wedges, hexes */
#define CLVR_FIELD_COMPONENTS_MAX 16u
#define CLVR_FIELD_COUNT_MAX 4096u /* fields per file (.bin version 2 refuses more) */
#define CLVR_FIELD_MAGNITUDE (-1)   /* component: the Euclidean norm of the tuple */

/* One array a file holds, as --info lists it. The range is of the values
 * (components == 1) or of the magnitudes; has_range is 0 where the loader
 * did not decode the array (legacy .vtk arrays other than the chosen one,
 * unless clvr_load_options.field_ranges). */
typedef struct clvr_field_info {
    char name[CLVR_SCALAR_NAME_MAX]; /* sanitized like scalar_name */
    uint32_t association;            /* CLVR_FIELD_POINT or CLVR_FIELD_CELL */
    uint32_t components;             /* 1..CLVR_FIELD_COMPONENTS_MAX */
    int has_range;
    float min, max;
} clvr_field_info;

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
    /* Every array of the file (NULL/0 for formats with one scalar), and how
     * `scalars` came from the chosen one: its index, the component
     * (CLVR_FIELD_MAGNITUDE or 0..components-1) and, for cell data, that it
     * was averaged onto the vertices. Owned by the mesh (clvr_mesh_free). */
    clvr_field_info *fields;
    uint32_t num_fields;
    uint32_t scalar_field;                         /* index into fields when num_fields > 0 */
    int scalar_component;
    uint64_t decomposed_cells;                     /* polyhedra split into tets and pyramids on load */
    int cell_flat;                                 /* scalars are a cell field made flat (clvr_mesh_flatten_cells) */
    /* Arrays mapped read-only from a .bin (clvr_load_options.map_indices,
     * map_vertices): indices[t], and positions / scalars where mapped, then
     * point into this private mapping of the file (page cache: no second
     * host copy, pages evictable and not anonymous memory), must not be
     * written, and go with the mapping. NULL: every array is malloc'd. */
    void *map_base;
    uint64_t map_bytes;
} clvr_mesh;

/* Allocates arrays for the given counts (zeroed struct first). On failure
 * frees what it got and returns CLVR_ERR_NO_MEMORY or CLVR_ERR_OVERFLOW. */
clvr_status clvr_mesh_alloc(clvr_mesh *m, uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                            clvr_error *err);
/* Frees every array; accepts NULL and half-built meshes; leaves *m zeroed. */
void clvr_mesh_free(clvr_mesh *m);

/* Frees (or unmaps) the index lists only: indices[] NULL, counts kept,
 * vertices and scalars untouched. */
void clvr_mesh_free_indices(clvr_mesh *m);

/* Mapped index lists: gives the whole pages of [p, p + bytes) that lie in
 * m's mapping back to the page cache (MADV_DONTNEED), so that a pass over a
 * mapped mesh does not grow the resident set by the file's size. Always
 * safe: the pages are the file's and fault back in on the next read. No-op
 * for malloc'd lists. */
void clvr_mesh_release_pages(const clvr_mesh *m, const void *p, uint64_t bytes);
/* The same for every mapped page. */
void clvr_mesh_release_all_pages(const clvr_mesh *m);

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

/* Finds the field a --scalar SPEC names among n fields: SPEC is
 * [point:|cell:]NAME[:x|:y|:z|:K]. A name matches exactly first (names may
 * hold ':'); the suffix picks component x/y/z (0/1/2) or K of a vector,
 * otherwise a vector gives its magnitude. Where a point and a cell array
 * share a name without a prefix, the point array wins. NULL or "" spec: the
 * first field. On failure the message names `file`, the spec and every
 * field there is. */
clvr_status clvr_field_select(const clvr_field_info *fields, uint32_t n, const char *spec, const char *file,
                              uint32_t *index, int *component, clvr_error *err);

/* Gives every element its own copies of its vertices, all carrying the
 * element's value from values (one per element, in the order tets,
 * pyramids, wedges, hexes), so that interpolation inside an element is
 * constant: cell data shown flat, as ParaView shows it, with no change to
 * the renderer (majorants bound the values as they bound any vertex
 * scalar). The vertex count becomes the sum of the elements' corner counts
 * (at most 2^32 - 1, else CLVR_ERR_OVERFLOW naming `what`); m->cell_flat
 * is set. On failure m is unchanged. */
clvr_status clvr_mesh_flatten_cells(clvr_mesh *m, const float *values, const char *what, clvr_error *err);

/* Name of a cell type: "tets", "pyramids", "wedges", "hexes". */
const char *clvr_cell_type_name(uint32_t t);

#endif /* CLVR_MESH_H */
