/* partition.h: partitioned Quick Clusters preprocessing (issue #15), so
 * that meshes of hundreds of millions of elements preprocess with scratch
 * memory for one partition instead of the whole mesh.
 *
 * The mesh is cut along the Hilbert curve: one coarse key pass over all
 * elements (the same 48-bit keys clvr_preprocess sorts by, on the same grid
 * over the whole mesh's bounds) and a histogram of their top bits give K
 * contiguous key ranges of bounded element counts. Each range is a
 * clvr_partition: its elements are gathered into a sub-mesh with its own
 * vertex numbering (a flag array over all mesh vertices, reset from the
 * partition's own vertex list, so each partition costs its own size), which
 * clvr_preprocess clusters with the whole mesh's box as quantization box, so
 * every partition's curve is a piece of the one curve. The clustered
 * partitions are appended one by one to the result (ids and offsets
 * shifted), and the partition's scratch is freed before the next one starts.
 * The result is the same kind of clustered mesh as clvr_preprocess's:
 * instance clusters (each in one partition, its vertices duplicated as in
 * the paper) under one top-level BVH.
 *
 * The partition is the unit a distributed (MPI) run will hand to ranks: the
 * plan (key ranges and counts) is small and deterministic, and
 * clvr_partition_extract builds one partition's sub-mesh from the mesh
 * alone. Module prefix clvr_partition_. */
#ifndef CLVR_PARTITION_H
#define CLVR_PARTITION_H

#include <stdint.h>

#include "cl_context.h"
#include "mesh.h"
#include "preprocess.h"
#include "status.h"

/* Bits of the coarse keys (the top bits of the 48-bit Hilbert key): 16, so
 * that the first pass keeps each element's coarse key in the 2-byte slot
 * that then holds its partition (one key computation per element, 2 bytes
 * per element), while a 788M-element mesh still has ~12k elements per bin,
 * fine against partitions of millions. */
#define CLVR_PARTITION_KEY_BITS 16u
/* Default bound on elements per partition. Measured on 10M mixed elements
 * (PoCL, 2 cores): a partition's scratch (its sub-mesh, the sort, the index
 * lists, its result before the append) is about 110 bytes per element, so
 * 4M elements cost ~0.45 GB, under half the result of any mesh big enough
 * to be partitioned. */
#define CLVR_PARTITION_DEFAULT_ELEMENTS (4u << 20)

/* Elements per partition of an n-element mesh in `count` partitions (0:
 * automatic, at most CLVR_PARTITION_DEFAULT_ELEMENTS): what the memory
 * checks budget one partition's scratch for. */
static inline uint64_t clvr_partition_elements(uint64_t n, uint32_t count)
{
    if (count) return (n + count - 1) / count;
    return n > CLVR_PARTITION_DEFAULT_ELEMENTS ? CLVR_PARTITION_DEFAULT_ELEMENTS : n;
}

typedef struct clvr_partition {
    uint32_t id;                                /* 0 .. count - 1, in curve order */
    uint32_t bin_lo, bin_hi;                    /* coarse key bins [bin_lo, bin_hi) */
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];   /* its elements per type */
    uint64_t num_elements;
    uint64_t first_cell[CLVR_CELL_TYPE_COUNT];  /* after clvr_partition_plan_reorder: where its
                                                   elements start in each type's list */
    uint64_t first;                             /* after a reorder of a mapped mesh: where its
                                                   elements start in the plan's `order` */
} clvr_partition;

typedef struct clvr_partition_plan {
    clvr_box box;              /* quantization box shared by every partition: the mesh bounds */
    uint32_t count;            /* K >= 1; partitions may be empty */
    clvr_partition *parts;     /* count entries */
    uint16_t *part_of16;       /* partition of each element, mesh order (types concatenated);
                                  NULL after a reorder */
    uint64_t num_elements;
    int reordered;             /* the mesh's lists are in partition order (clvr_partition_plan_reorder) */
    uint32_t *order;           /* a reorder of a mapped mesh (read-only lists): element ids (types
                                  concatenated) by partition, mesh order inside each; an
                                  anonymous mapping of order_bytes whose consumed pages go back
                                  to the OS as partitions are gathered. NULL otherwise */
    uint64_t order_bytes;
    double seconds;            /* wall seconds of the coarse key pass and the plan */
} clvr_partition_plan;

/* Plans the partitions of mesh m (validated, >= 1 element, < 2^32). With
 * count > 0 exactly `count` partitions of near-equal element counts (cut at
 * coarse-bin boundaries, so some may be empty, and all but one are when
 * count exceeds the element count); with count == 0 as few as keep each
 * partition at most max_elements elements (0: the default): a coarse bin
 * with more elements (a mesh piled into one spot of the grid) is split into
 * partitions of its own in mesh order, as an unbounded partition would
 * need unbounded scratch. At most 65535 partitions. */
clvr_status clvr_partition_plan_make(const clvr_mesh *m, uint32_t count, uint64_t max_elements,
                                     clvr_partition_plan *out, clvr_error *err);
void clvr_partition_plan_free(clvr_partition_plan *p); /* accepts zeroed and half-built */

/* Permutes each type's element list of m in place (a cycle-leader
 * counting sort by partition, O(elements)) so that every partition's
 * elements are one range per type (parts[].first_cell), and frees
 * part_of16: afterwards membership is by range. The order inside a
 * partition changes (swaps); the partition's own sort orders it anyway.
 * A mapped mesh (m->map_base: read-only lists) is not written: a counting
 * sort of the element ids instead gives p->order, where each partition is
 * one range (parts[].first), 4 bytes per element in place of the 2 of
 * part_of16. */
void clvr_partition_plan_reorder(clvr_mesh *m, clvr_partition_plan *p);

/* The partition of element g (mesh order; not after a reorder). */
uint32_t clvr_partition_of(const clvr_partition_plan *p, uint64_t g);

/* Sub-mesh of partition `part`: its elements in mesh order per type, the
 * vertices they reference in first-use order, indices renumbered. ids (may
 * be NULL) receives, per sub-mesh element (types concatenated), the mesh's
 * element id (types concatenated). vmap is scratch of m->num_vertices
 * entries, all UINT32_MAX on entry and on return. */
clvr_status clvr_partition_extract(const clvr_mesh *m, const clvr_partition_plan *p, uint32_t part, uint32_t *vmap,
                                   clvr_mesh *sub, uint32_t **ids, clvr_error *err);

/* Partitioned preprocessing: clvr_preprocess of every partition of the plan
 * (made here with `count` / max_elements as above), appended into *out.
 * consume != 0 lets it take the mesh apart to keep the peak near the
 * result's size: the element lists are reordered by partition and the pages
 * of each partition's indices are given back to the OS as soon as it is
 * gathered, so the input's indices shrink while the result grows; on return
 * (success or not) m's index lists are freed (NULL, counts kept), its
 * vertices untouched. consume == 0 leaves m as it was (m is not written).
 * keep_order needs consume == 0, except for a mapped mesh (m->map_base),
 * whose lists are never moved (the ids stay those of the file).
 * o->quantize_box is ignored (the plan's box is used). The result's device
 * buffers are made once at the end from host arrays the result owns (on a
 * CPU device with CL_MEM_USE_HOST_PTR, so the device reads them where they
 * are: no second copy). Stages: the partitions' stage_s summed, plus the
 * plan and reorder time under CLVR_PP_STAGE_PARTITION, the sub-mesh gathers
 * under CLVR_PP_STAGE_EXTRACT and the appends under CLVR_PP_STAGE_MERGE. num_cells are the totals; first_cell is the
 * first partition's (each partition has its own type lists). With
 * o->keep_order, order holds mesh element ids (types concatenated). */
clvr_status clvr_preprocess_partitioned(clvr_cl *cl, clvr_mesh *m, const clvr_preprocess_options *o,
                                        uint32_t count, uint64_t max_elements, int consume, clvr_clustered *out,
                                        uint32_t *num_partitions, clvr_error *err);

/* Cuts a clustered mesh's split arrays (clustered vertices, 16- and 32-bit
 * local indices, and the element boxes when element_boxes != 0) into
 * pieces of at most `limit` bytes each at instance boundaries
 * (docs/large-meshes.md): a new piece starts at the instance whose arrays
 * would push any of them past the limit. inst: c's n instances, in global
 * element order, with offsets into the whole arrays (c's num_vertices,
 * num_idx16, num_idx32, num_elements give the totals); rewritten to
 * piece-relative offsets (first_vertex, first_index), piece and
 * piece_first_element. Sets c->num_pieces and the piece_* prefixes (the
 * buffers are not touched). Fails with CLVR_ERR_DEVICE_MEMORY, naming the
 * array, the sizes, the limit and what to do, when one instance alone
 * exceeds the limit or more than CLVR_MAX_SPLITS pieces would be needed;
 * `what` names the mesh in the messages (NULL: "mesh"). */
clvr_status clvr_partition_pieces(clvr_instance *inst, uint64_t n, uint64_t limit, int element_boxes,
                                  const char *what, clvr_clustered *c, clvr_error *err);

#endif /* CLVR_PARTITION_H */
