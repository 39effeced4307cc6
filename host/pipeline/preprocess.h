/* preprocess.h: Quick Clusters preprocessing on the OpenCL device (paper
 * sections 3.2-3.4.1): element keys along a Hilbert (or Morton) curve, a
 * key-value radix sort, the gather of the index lists in curve order, leaf
 * clusters, instance clusters re-indexed to 16-bit local indices, and
 * adaptive-sampling clusters. The result is the "clustered mesh" of
 * kernels/clvr_shared.h; bvh/ builds trees over its instances and leaf
 * boxes and the renderer reads all of it.
 *
 * This is the public API (clvr_preprocess, clvr_clustered, the workspace).
 * The stages one by one, their plain-C references (host/pipeline/preprocess_ref.c,
 * bit for bit the same results) and the split plan are in
 * preprocess_stages.h, for the pipeline itself, tests and benchmarks. */
#ifndef CLVR_PREPROCESS_H
#define CLVR_PREPROCESS_H

#include <stdint.h>

#include "cl_context.h"
#include "mesh.h"
#include "status.h"

typedef struct clvr_preprocess_options {
    uint32_t leaf_size;       /* elements per leaf cluster, 1..128 (paper: 16; default 16) */
    uint32_t sampling_size;   /* elements per adaptive-sampling cluster, >= 1. Default 16, like a
                                 leaf cluster: measured on the default scene (dda, 64^3 cells),
                                 16 gives 0.14 samples and 0.10 null collisions per ray against
                                 0.26 and 0.22 with 256, and twice the rays/s; the bins method is
                                 about as fast with 16 as with 256. Costs 2 bytes per element. */
    int morton;               /* 0: Hilbert curve (paper); 1: Morton order (for comparison) */
    uint32_t index_bits;      /* 16 (default): instances grow greedily until they would reference
                                 more than 65535 vertices, 16-bit local indices (paper 3.3);
                                 32: no compression, instances of max_instance_elements elements
                                 with 32-bit local indices (the "before" of Table 1) */
    uint32_t max_instance_elements; /* cap on elements per instance; 0: 1<<20 for 16-bit (the paper's
                                       1M of 3.2.2; the vertex limit binds first, giving the
                                       paper's 30k-60k hexes), 65536 for 32-bit */
    int keep_order;           /* nonzero: keep `order` (original element id per sorted element) */
    const clvr_box *quantize_box; /* NULL (default): the curve keys quantize element centres on a 2^16
                                     grid over the mesh bounds. Else over this box (xyz of lo and hi,
                                     finite, lo <= hi; w ignored; the caller keeps it alive during the
                                     call): partitions of one mesh preprocessed one by one with the
                                     whole mesh's box share one Hilbert grid, so their curves are
                                     pieces of one curve. Centres outside the box clamp to its faces. */
    int no_element_boxes;     /* nonzero: the result carries no quantized element boxes (6 bytes per
                                 element, kernels/locate.h): clvr_accel_build skips them and point
                                 location tests every element of a leaf exactly (same elements
                                 found, slower). 0 (default): boxes on */
    int one_curve;            /* CLVR_ONE_CURVE_AUTO (0, default), _ON, _OFF. On: a mesh of two or more
                                 cell types is sorted along one curve, every cell stored as an
                                 8-index hex with repeated corners (tet a b c c d d d d, pyramid
                                 a b c d e e e e, wedge a b c c d e f f), which point location and
                                 the renderer read back as its own type (kernels/elements.h
                                 clvr_hex_collapsed, kernels/locate.h clvr_load_cell_in), so that
                                 instance and leaf clusters hold every type of their region. Off:
                                 one curve per type, the result's cells typed as the mesh's. Auto:
                                 on when the mesh has two or more types and the collapsed hexes
                                 take at most 1.5x the index slots of the types' own lists
                                 (clvr_pp_one_curve; a mesh mostly of tets keeps its 4-index tets).
                                 The OpenFOAM igloo (mixed, 1.37x the slots): the same image bit
                                 for bit, frames 28% faster, point location +15-20% */
} clvr_preprocess_options;
#define CLVR_ONE_CURVE_AUTO 0
#define CLVR_ONE_CURVE_ON 1
#define CLVR_ONE_CURVE_OFF 2

/* Fills the defaults above. */
void clvr_preprocess_options_default(clvr_preprocess_options *o);
/* 1 when o puts a mesh of these cell counts on one curve (one_curve): on,
 * or auto with two or more types whose collapsed hexes take at most 1.5x
 * their own index slots. Inline, as is clvr_pp_sorted_slots: the memory
 * estimates (limits_check.c) use them in builds without the pipeline. */
static inline int clvr_pp_one_curve(const clvr_preprocess_options *o, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT])
{
    uint64_t n = 0, slots = 0;
    int types = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        n += num_cells[t];
        slots += num_cells[t] * clvr_cell_vertex_count(t);
        types += num_cells[t] > 0;
    }
    if (types < 2 || o->one_curve == CLVR_ONE_CURVE_OFF) return 0;
    /* Auto: the collapsed hexes' 8 slots per cell against the types' own,
     * at most 1.5x (the igloo's 1.37x: its tree and indices 33.0 against
     * 34.6 bytes per element, fewer instances making up the extra slots). */
    return o->one_curve == CLVR_ONE_CURVE_ON || 16 * n <= 3 * slots;
}

/* Index slots of the clustered mesh: 8 per cell on one curve, else the
 * cells' own (the device and host memory estimates, limits_check.h). */
static inline uint64_t clvr_pp_sorted_slots(const clvr_preprocess_options *o,
                                            const uint64_t num_cells[CLVR_CELL_TYPE_COUNT])
{
    uint64_t n = 0, slots = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        n += num_cells[t];
        slots += num_cells[t] * clvr_cell_vertex_count(t);
    }
    return clvr_pp_one_curve(o, num_cells) ? 8 * n : slots;
}

/* Names of the timed stages, in the order of clvr_clustered.stage_s. */
enum {
    CLVR_PP_STAGE_UPLOAD,     /* host -> device copies of the mesh */
    CLVR_PP_STAGE_BOUNDS,     /* global bounds reduction */
    CLVR_PP_STAGE_KEYS,       /* element boxes, centroids, curve keys */
    CLVR_PP_STAGE_SORT,       /* radix sort */
    CLVR_PP_STAGE_GATHER,     /* index lists in curve order */
    CLVR_PP_STAGE_SAMPLING,   /* sampling clusters */
    CLVR_PP_STAGE_SPLIT,      /* instance split + local re-indexing */
    CLVR_PP_STAGE_INSTANCES,  /* flagged select, scans, instance table */
    CLVR_PP_STAGE_VERTICES,   /* copy of the per-instance vertices */
    CLVR_PP_STAGE_LEAVES,     /* leaf boxes and instance bounds */
    CLVR_PP_STAGE_PARTITION,  /* partitioned runs only (partition.h): coarse keys, plan, reorder (wall) */
    CLVR_PP_STAGE_EXTRACT,    /* partitioned runs only: the partitions' sub-mesh gathers on the host (wall) */
    CLVR_PP_STAGE_MERGE,      /* partitioned runs only: appending the partitions' results (wall) */
    CLVR_PP_STAGE_COUNT
};
/* "upload", "bounds", ... */
const char *clvr_pp_stage_name(int stage);

/* The clustered mesh. Device buffers are made with clvr_cl_buffer and
 * released by clvr_clustered_release; counts are 64-bit on the host. */
typedef struct clvr_clustered {
    cl_mem vertices;          /* float4 (x, y, z, scalar) [num_vertices], per instance, duplicates kept */
    cl_mem idx16;             /* ushort [num_idx16]: local indices of 16-bit instances, at first_index */
    cl_mem idx32;             /* uint [num_idx32]: local indices of 32-bit instances, at first_index */
    cl_mem instances;         /* clvr_instance [num_instances] */
    cl_mem leaf_boxes;        /* clvr_box [num_leaves] (w lanes zero) */
    cl_mem sampling;          /* clvr_sampling_cluster [num_sampling] */
    cl_mem order;             /* uint [num_elements] original global element id per sorted element;
                                 NULL unless options.keep_order */
    clvr_instance *host_instances; /* host copy of `instances` (malloc'ed; bounds filled) */
    void *host_arrays[8];     /* page-aligned anonymous mappings the buffers above live in
                                 (CL_MEM_USE_HOST_PTR) when the result was assembled on the host
                                 (partition.h); unmapped by clvr_clustered_release after the
                                 buffers; NULL otherwise */
    uint64_t host_array_bytes[8]; /* their mapped sizes */
    /* The arrays whose entries belong to instance clusters are cut at
     * instance boundaries into num_pieces buffers (docs/large-meshes.md) so
     * that none exceeds the device's largest allocation: vertices, idx16 and
     * idx32 above are piece 0 (the whole arrays when num_pieces is 1), the
     * *_more buffers pieces 1 .. num_pieces - 1 (NULL past them). Piece p
     * holds the vertices [piece_vertices[p], piece_vertices[p + 1]), the
     * local indices [piece_idx16[p], ...) and [piece_idx32[p], ...) and the
     * elements [piece_elements[p], ...) of the whole arrays; instances hold
     * offsets inside their piece (clvr_instance.piece). num_pieces 0 (a
     * result made by hand) counts as 1. piece_dummy: a 16-byte buffer the
     * kernels get for the pieces a mesh does not have. */
    uint32_t num_pieces;
    cl_mem vertices_more[CLVR_MAX_SPLITS - 1], idx16_more[CLVR_MAX_SPLITS - 1], idx32_more[CLVR_MAX_SPLITS - 1];
    cl_mem piece_dummy;
    uint64_t piece_vertices[CLVR_MAX_SPLITS + 1], piece_idx16[CLVR_MAX_SPLITS + 1],
        piece_idx32[CLVR_MAX_SPLITS + 1], piece_elements[CLVR_MAX_SPLITS + 1];
    uint32_t num_partitions;  /* partitions it was preprocessed in (1 for clvr_preprocess) */
    uint64_t num_elements, num_vertices, num_idx16, num_idx32, num_instances, num_instances16, num_leaves,
        num_sampling;
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];   /* elements per type (sorted lists in this order) */
    uint64_t first_cell[CLVR_CELL_TYPE_COUNT];  /* global sorted id of each type's first element */
    uint64_t collapsed[CLVR_CELL_TYPE_COUNT];   /* one curve (options.one_curve): the tets, pyramids and
                                                   wedges stored as collapsed hexes (counted as hexes in
                                                   num_cells); [CLVR_CELL_HEX] 0 */
    clvr_box bounds;          /* of all mesh vertices; lo[3] / hi[3] = scalar range */
    float scalar_min, scalar_max;
    uint32_t leaf_size, sampling_size, index_bits;
    int morton;
    int no_element_boxes;     /* from the options: clvr_accel_build makes no element boxes */
    /* stats */
    double stage_s[CLVR_PP_STAGE_COUNT]; /* device seconds per stage (OpenCL event profiling) */
    double build_s;           /* wall seconds to build the kernels (cached by the driver after the first run) */
    double wall_s;            /* wall seconds of clvr_preprocess, build included */
    uint64_t bytes_vertices_before;  /* float3 + float per mesh vertex */
    uint64_t bytes_vertices_after;   /* float4 per clustered vertex */
    uint64_t bytes_indices_before;   /* 4 bytes per index */
    uint64_t bytes_indices_after;    /* 2 or 4 bytes per index */
    uint64_t bytes_leaf_boxes, bytes_instances, bytes_sampling;
    double avg_instance_elements, avg_instance_vertices, avg_leaf_elements;
} clvr_clustered;

/* Preprocesses m (validated, >= 1 element, < 2^32 elements, < 2^32
 * clustered vertices) into *out (zeroed first). o may be NULL (defaults).
 * On failure *out holds nothing (everything released). Needs roughly
 * 40 bytes per index slot + 36 per element + 16 per vertex of device memory
 * at its peak; each buffer is checked against the device limits. */
clvr_status clvr_preprocess(clvr_cl *cl, const clvr_mesh *m, const clvr_preprocess_options *o, clvr_clustered *out,
                            clvr_error *err);
/* Fills c's byte and average figures (bytes_*, avg_*, num_instances16)
 * from its counts and those of the input mesh m. */
void clvr_clustered_fill_stats(clvr_clustered *c, const clvr_mesh *m);
/* Releases every buffer and the host copy; accepts NULL and half-built results; leaves *c zeroed. */
void clvr_clustered_release(clvr_cl *cl, clvr_clustered *c);

/* Scratch device buffers kept from one clvr_preprocess_ws call to the next
 * (sort keys and values, the sorted and the uploaded index lists, the
 * split's vertex map and hash tables), so that preprocessing again (a time
 * series, a benchmark's repeats) reuses device memory instead of
 * allocating it again. On a CPU device a fresh buffer is fresh pages that
 * the OS zeroes on first touch: on the 2-core VM, touching 580 MB the
 * first time took 0.30 s (4 KiB pages) or 0.07 s (huge pages), again
 * 0.02 s. A buffer grows when a call needs more; the workspace holds the
 * memory until clvr_pp_workspace_release, so peak device memory is the sum
 * of the scratch instead of its largest stage. Zero-initialize it. */
enum {
    CLVR_PP_WS_KEYS,
    CLVR_PP_WS_VALS,
    CLVR_PP_WS_KEYS_TMP,
    CLVR_PP_WS_VALS_TMP,
    CLVR_PP_WS_IDX_IN,
    CLVR_PP_WS_IDX_SORTED,
    CLVR_PP_WS_VMAP,
    CLVR_PP_WS_HASH,
    /* result buffers handed back by clvr_pp_workspace_recycle */
    CLVR_PP_WS_OUT_VERTICES,
    CLVR_PP_WS_OUT_IDX16,
    CLVR_PP_WS_OUT_IDX32,
    CLVR_PP_WS_OUT_LEAF_BOXES,
    CLVR_PP_WS_OUT_SAMPLING,
    CLVR_PP_WS_COUNT
};
typedef struct clvr_pp_workspace {
    cl_mem buf[CLVR_PP_WS_COUNT];
    uint64_t bytes[CLVR_PP_WS_COUNT];
} clvr_pp_workspace;
/* Releases the workspace's buffers; leaves it zeroed (ready for reuse). */
void clvr_pp_workspace_release(clvr_cl *cl, clvr_pp_workspace *ws);
/* Releases a result that is no longer needed, handing its big arrays
 * (vertices, indices, leaf boxes, sampling clusters) to ws, whose next
 * clvr_preprocess_ws writes its result into them where they are big
 * enough (the previous time step's buffers, say). *c is left zeroed. */
void clvr_pp_workspace_recycle(clvr_cl *cl, clvr_pp_workspace *ws, clvr_clustered *c);
/* clvr_preprocess with scratch from (and kept in) ws; ws == NULL is
 * clvr_preprocess, which frees each scratch buffer as soon as it is dead. */
clvr_status clvr_preprocess_ws(clvr_cl *cl, const clvr_mesh *m, const clvr_preprocess_options *o,
                               clvr_pp_workspace *ws, clvr_clustered *out, clvr_error *err);

/* The split arrays' device buffers piece by piece (index 0 .. CLVR_MAX_SPLITS
 * - 1), c->piece_dummy (or, for a result without one, c->instances) for
 * the pieces c does not have: what the kernels' piece arguments get. */
typedef struct clvr_clustered_pieces {
    cl_mem vertices[CLVR_MAX_SPLITS], idx16[CLVR_MAX_SPLITS], idx32[CLVR_MAX_SPLITS];
} clvr_clustered_pieces;
void clvr_clustered_get_pieces(const clvr_clustered *c, clvr_clustered_pieces *out);

/* Host copies of every array of a clustered mesh (tests, tools). A split
 * mesh is read back whole: its pieces concatenated and its instances'
 * offsets made global again (piece 0, piece_first_element 0), the same
 * arrays as the mesh unsplit. */
typedef struct clvr_clustered_host {
    float *vertices;          /* 4 * num_vertices */
    uint16_t *idx16;          /* num_idx16 */
    uint32_t *idx32;          /* num_idx32 */
    clvr_instance *instances; /* num_instances */
    clvr_box *leaf_boxes;     /* num_leaves */
    clvr_sampling_cluster *sampling; /* num_sampling */
    uint32_t *order;          /* num_elements, or NULL when not kept */
} clvr_clustered_host;
clvr_status clvr_clustered_download(clvr_cl *cl, const clvr_clustered *c, clvr_clustered_host *out, clvr_error *err);
void clvr_clustered_host_free(clvr_clustered_host *h);

#endif /* CLVR_PREPROCESS_H */
