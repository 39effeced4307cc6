/* preprocess_stages.h: the stages of clvr_preprocess one by one (the
 * kernels of kernels/preprocess.cl, one call per stage), the element layout
 * and split plan they share, and a plain-C reference of every stage and of
 * the whole pipeline (host/pipeline/preprocess_ref.c) with the same contract, so that
 * tests compare device and reference bit for bit. Module prefix clvr_pp_.
 * Callers that only preprocess a mesh need preprocess.h alone. */
#ifndef CLVR_PREPROCESS_STAGES_H
#define CLVR_PREPROCESS_STAGES_H

#include <stdint.h>

#include "cl_context.h"
#include "preprocess.h"

/* ------------------------------------------------------------ stages
 * Tiled kernels split n items into `tiles` contiguous chunks, one
 * work-item each. */
typedef struct clvr_pp {
    clvr_cl *cl;
    cl_program prog;
    cl_kernel bounds_tiles, keys_type[CLVR_CELL_TYPE_COUNT], scan_reduce, scan_sums, scan_apply, select_scatter, radix_andor,
        radix_hist, radix_scatter, gather, gather_collapse, sampling, leaf_boxes, instance_bounds, split, rec_flags, inst_counts,
        inst_write, vertices, radix_buckets, iota;
    uint32_t max_tiles;       /* tiles per tiled launch: a few per compute unit */
    uint64_t sort_hybrid_min; /* sorts of at least this many items go hybrid (top digit, then buckets
                                 from cache; kernels/sort.cl); UINT64_MAX on GPUs; tests lower it */
} clvr_pp;

clvr_status clvr_pp_create(clvr_cl *cl, clvr_pp *pp, clvr_error *err);
void clvr_pp_destroy(clvr_pp *pp); /* accepts half-built */

/* Tiles for n items: at most max_tiles, chunks of at least 4096 items. */
uint32_t clvr_pp_tiles(const clvr_pp *pp, uint64_t n);

/* Each stage adds its device seconds to *sec when sec is not NULL. */

/* Bounds of positions (float3 [n]) and scalars [n]: box lo/hi, w = scalar. */
clvr_status clvr_pp_bounds(clvr_pp *pp, cl_mem pos, cl_mem scal, uint64_t n, clvr_box *out, double *sec,
                           clvr_error *err);
/* Per-type element layout used by the element stages: first global element
 * id and first index slot of each type, and the total element count. */
typedef struct clvr_pp_layout {
    uint64_t count[CLVR_CELL_TYPE_COUNT];
    uint64_t first[CLVR_CELL_TYPE_COUNT];
    uint64_t slot[CLVR_CELL_TYPE_COUNT];
    uint64_t num_elements, num_slots;
} clvr_pp_layout;
void clvr_pp_layout_make(clvr_pp_layout *l, const uint64_t count[CLVR_CELL_TYPE_COUNT]);
/* out = the layout of the clustered mesh from the gather on: in itself, or
 * with one curve (clvr_pp_one_curve) every element a hex; returns 1 then. */
int clvr_pp_sorted_layout(const clvr_preprocess_options *o, const clvr_pp_layout *in, clvr_pp_layout *out);
/* The part of l the element kernels take (by value): first ids and slots. */
void clvr_pp_type_layout(const clvr_pp_layout *l, clvr_type_layout *out);
/* The quantization scale of clvr_pp_quantize for a box. */
float clvr_pp_scale(const clvr_box *b);
/* keys[g], vals[g] = sort key and g for every element g; vals may be NULL
 * (not written: clvr_pp_sort can make them, iota_vals). The key is the
 * element's type << 48 | its curve key, so that the sort keeps the types'
 * lists apart; one_curve: CLVR_CELL_HEX << 48 for every type, so that it
 * merges them into one curve (clvr_preprocess_options.one_curve). */
clvr_status clvr_pp_keys(clvr_pp *pp, cl_mem pos, cl_mem idx, const clvr_pp_layout *l, const clvr_box *b,
                         int morton, int one_curve, cl_mem keys, cl_mem vals, double *sec, clvr_error *err);
/* Runs k over n items (local size `local`), adding its device time to
 * *sec (NULL: not timed). */
clvr_status clvr_pp_launch(clvr_pp *pp, cl_kernel k, uint64_t n, size_t local, double *sec, clvr_error *err);
/* Exclusive scan of n uints (in may equal out); *total = sum (may be NULL). */
clvr_status clvr_pp_scan(clvr_pp *pp, cl_mem in, cl_mem out, uint64_t n, uint32_t *total, double *sec,
                         clvr_error *err);
/* Flagged select: out[k] = values[i] (ids i when values is NULL) for the
 * k-th nonzero flags[i]; *count = how many. out holds n entries. */
clvr_status clvr_pp_select(clvr_pp *pp, cl_mem flags, cl_mem values, cl_mem out, uint64_t n, uint32_t *count,
                           double *sec, clvr_error *err);
/* Stable sort of n (ulong key, uint value) pairs, n < 2^32. *keys and *vals
 * hold the input; tmp buffers are the same sizes; on return the handles
 * may have been swapped so that *keys / *vals hold the result. iota_vals:
 * the values are 0..n-1 and *vals holds nothing yet (the first pass makes
 * them, which saves writing and reading n values). varying_hint: 0, or a
 * mask with every key bit that may differ between keys set (a superset is
 * fine, a missing bit is not): spares the hybrid sort a pass over the keys. */
clvr_status clvr_pp_sort(clvr_pp *pp, cl_mem *keys, cl_mem *vals, cl_mem *keys_tmp, cl_mem *vals_tmp, uint64_t n,
                         int iota_vals, uint64_t varying_hint, double *sec, clvr_error *err);

/* ------------------------------------------------------------ references
 * Plain C, same contracts on host arrays (host/pipeline/preprocess_ref.c). */
void clvr_pp_ref_bounds(const float *pos, const float *scal, uint64_t n, clvr_box *out);
void clvr_pp_ref_keys(const float *pos, const uint32_t *idx, const clvr_pp_layout *l, const clvr_box *b,
                      int morton, int one_curve, uint64_t *keys, uint32_t *vals);
/* clvr_pp_gather_collapse: idx_hex[8 i ..] = input element order[i] (l: the
 * input's layout) as its collapsed hex. */
void clvr_pp_ref_gather_collapse(const uint32_t *order, const uint32_t *idx_in, const clvr_pp_layout *l,
                                 uint64_t n, uint32_t *idx_hex);
uint32_t clvr_pp_ref_scan(const uint32_t *in, uint32_t *out, uint64_t n);
uint32_t clvr_pp_ref_select(const uint32_t *flags, const uint32_t *values, uint32_t *out, uint64_t n);
/* Stable LSD radix sort, single thread; returns nonzero when out of memory. */
int clvr_pp_ref_sort(uint64_t *keys, uint32_t *vals, uint64_t n);

/* The whole pipeline on the host, bit-identical to clvr_preprocess with the
 * same options and tiles (the split's segment length depends on the device's
 * compute units, given here). Fills a clustered description (counts, bounds,
 * host_instances; no device buffers) and host arrays. */
clvr_status clvr_pp_ref_preprocess(const clvr_mesh *m, const clvr_preprocess_options *o, uint32_t compute_units,
                                   clvr_clustered *out, clvr_clustered_host *arrays, clvr_error *err);

/* Split plan shared by device and reference: segment length per type and
 * the hash map size. Segments are numbered over the types in order (type
 * t's are rec_base[t] .. rec_base[t] + nseg[t] - 1); segment s keeps its
 * records at s * rec_max. */
typedef struct clvr_pp_split_plan {
    uint32_t vlimit, max_elems, log2cap;
    uint32_t seg_len[CLVR_CELL_TYPE_COUNT], nseg[CLVR_CELL_TYPE_COUNT];
    uint32_t rec_max;         /* records per segment at most (the stride of the record table) */
    uint32_t rec_base[CLVR_CELL_TYPE_COUNT], total_segments;
} clvr_pp_split_plan;
/* o must be resolved. Segments are long (clvr_pp_segment_floor elements at
 * least) so that the greedy split, which closes an instance at every segment
 * end, loses little. */
uint64_t clvr_pp_segment_floor(uint32_t compute_units);
void clvr_pp_split_plan_make(clvr_pp_split_plan *p, const clvr_pp_layout *l, const clvr_preprocess_options *o,
                             uint32_t compute_units, uint64_t num_vertices);
/* Resolved options (defaults applied, checked): CLVR_ERR_USAGE when invalid. */
clvr_status clvr_pp_options_resolve(const clvr_preprocess_options *in, clvr_preprocess_options *out,
                                    clvr_error *err);
/* The box the curve keys quantize over: o->quantize_box, else the mesh bounds. */
const clvr_box *clvr_pp_quantize_box(const clvr_preprocess_options *o, const clvr_box *mesh_bounds);

#endif /* CLVR_PREPROCESS_STAGES_H */
