/* mesh_io.h: reading meshes from files and writing clvr's own .bin.
 * Files are untrusted: every reader checks magic, version, counts and
 * offset + count * size <= file size before reading, and reports a distinct
 * status with a message naming the file, the field and the fix.
 * The .bin layout is specified in docs/bin-format.md. */
#ifndef CLVR_MESH_IO_H
#define CLVR_MESH_IO_H

#include "mesh.h"

typedef struct clvr_load_options {
    const char *scalar_name;  /* attribute to use as the scalar; NULL: the file's first/only one */
    int skip_validation;      /* nonzero: do not run clvr_mesh_validate (fuzzing, --info of broken files) */
    int field_ranges;         /* nonzero: also decode every other array for its range (--info) */
    int cell_flat;            /* nonzero: a cell field is rendered flat, each element its own value:
                               * every element gets its own copies of its vertices carrying that
                               * value (clvr_mesh_flatten_cells); 0: averaged onto the vertices */
    int map_indices;          /* nonzero, .bin files: map the element index lists read-only
                               * (MAP_PRIVATE) instead of reading them into the heap, so the
                               * mesh's biggest arrays stay page cache, never a second host
                               * copy (clvr_mesh.map_base); validation as for a read file.
                               * Not for --cell-data flat, which rewrites the lists. */
    int map_vertices;         /* with map_indices: the positions (and a version 1 file's scalars)
                               * too, so the loaded mesh holds no anonymous memory at all; its
                               * arrays must then never be written */
} clvr_load_options;

/* Loads any supported file, chosen by content (magic) and then extension:
 * .bin (clvr), .umesh (magics 0x234235566..0x234235569), legacy VTK .vtk
 * unstructured grids (ASCII and binary; cell types 10, 12, 13, 14).
 * On success *out owns its arrays (clvr_mesh_free), ranges are set and the
 * mesh has been validated unless opt->skip_validation. opt may be NULL. */
clvr_status clvr_mesh_load(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err);

clvr_status clvr_mesh_load_bin(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err);
clvr_status clvr_mesh_load_umesh(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err);
clvr_status clvr_mesh_load_vtk(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err);

/* Counts from a .bin file's header alone (validated against the file size),
 * so that memory can be checked before the mesh is read. Not a .bin:
 * CLVR_ERR_BAD_MAGIC. */
clvr_status clvr_mesh_peek_bin(const char *path, uint64_t *num_vertices, uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                               clvr_error *err);

/* Parsers over a memory buffer (what the fuzz targets call); `name` is used
 * in messages only. Same contracts as the file loaders. */
clvr_status clvr_mesh_parse_bin(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                clvr_mesh *out, clvr_error *err);
clvr_status clvr_mesh_parse_umesh(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                  clvr_mesh *out, clvr_error *err);
clvr_status clvr_mesh_parse_vtk(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                clvr_mesh *out, clvr_error *err);

/* Writes m as .bin: to "path.tmp.<pid>" first, renamed onto path only when
 * complete, so a failure never leaves a partial file or harms an older one. */
clvr_status clvr_mesh_save_bin(const char *path, const clvr_mesh *m, clvr_error *err);

/* Streaming .bin writer for generators that cannot hold the mesh: counts are
 * fixed at open; the arrays may be appended in chunks, each array's chunks in
 * order, arrays in any order (each has a known offset). close() checks that
 * every array is complete, patches bounds and scalar range into the header,
 * and renames the temporary file onto path. abort() removes it. */
typedef struct clvr_bin_writer clvr_bin_writer;
clvr_status clvr_bin_writer_open(const char *path, uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                                 const char *scalar_name, clvr_bin_writer **out, clvr_error *err);
clvr_status clvr_bin_writer_positions(clvr_bin_writer *w, const float *xyz, uint64_t num_vertices, clvr_error *err);
clvr_status clvr_bin_writer_scalars(clvr_bin_writer *w, const float *s, uint64_t num_vertices, clvr_error *err);
clvr_status clvr_bin_writer_cells(clvr_bin_writer *w, uint32_t type, const uint32_t *idx, uint64_t num_cells,
                                  clvr_error *err);
clvr_status clvr_bin_writer_close(clvr_bin_writer *w, clvr_error *err); /* frees w in all cases */
void clvr_bin_writer_abort(clvr_bin_writer *w);                          /* accepts NULL */

/* Where a .bin file's arrays lie, from its header (and version 2 field
 * table) validated against the file size exactly as clvr_mesh_load_bin
 * does, with the --scalar selection resolved: for readers that take a file
 * in parts with offsets (MPI mode: host/mpi/mpi_load.c). The arrays'
 * contents are not read or checked. */
typedef struct clvr_bin_layout {
    uint32_t version;                                /* 1 or 2 */
    uint64_t file_size;
    uint64_t num_vertices;
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];
    uint64_t positions_offset;                       /* 3 f32 per vertex */
    uint64_t cells_offset[CLVR_CELL_TYPE_COUNT];     /* u32 indices, clvr_cell_vertex_count(t) per cell */
    int has_scalar;                                  /* 0: version 2 without fields (scalars are 0) */
    uint64_t scalar_offset;                          /* the chosen array: count x components f32 */
    uint32_t scalar_association;                     /* CLVR_FIELD_POINT or CLVR_FIELD_CELL */
    uint32_t scalar_components;
    int scalar_component;                            /* CLVR_FIELD_MAGNITUDE or a component */
    char scalar_label[CLVR_SCALAR_NAME_MAX];         /* what clvr_mesh.scalar_name becomes, sanitized */
} clvr_bin_layout;

/* Reads and validates the header of the open file fd (`name` in messages)
 * and resolves scalar_spec (clvr_load_options.scalar_name; NULL: the
 * first). Same statuses and messages as clvr_mesh_load_bin. */
clvr_status clvr_mesh_bin_layout(int fd, const char *name, const char *scalar_spec, clvr_bin_layout *out,
                                 clvr_error *err);

/* One tuple of the chosen field as the loader turns it into a vertex
 * scalar: the component, or the Euclidean norm for CLVR_FIELD_MAGNITUDE. */
float clvr_bin_tuple_value(const float *tuple, uint32_t components, int component);

#endif /* CLVR_MESH_IO_H */
