/* preprocess.c: drives kernels/preprocess.cl: bounds -> keys -> radix sort
 * -> gather -> sampling clusters -> greedy instance split with local
 * re-indexing -> flagged select of the instance records -> scans of their
 * vertex and leaf counts -> instance table -> clustered vertices -> leaf
 * boxes -> instance bounds. Contracts: preprocess.h (public API) and
 * preprocess_stages.h (the stages). */
#include "preprocess_stages.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void clvr_preprocess_options_default(clvr_preprocess_options *o)
{
    /* Zero: Hilbert order, the default instance cap, order not kept, the
     * mesh bounds as quantization box. */
    memset(o, 0, sizeof *o);
    o->leaf_size = 16;
    o->sampling_size = 16;
    o->index_bits = 16;
}

clvr_status clvr_pp_options_resolve(const clvr_preprocess_options *in, clvr_preprocess_options *out, clvr_error *err)
{
    if (in) *out = *in;
    else clvr_preprocess_options_default(out);
    if (out->leaf_size < 1 || out->leaf_size > 128)
        return clvr_error_set(err, CLVR_ERR_USAGE, "preprocess: leaf_size %u is outside 1..128 (paper: 16)",
                              out->leaf_size);
    if (out->sampling_size < 1)
        return clvr_error_set(err, CLVR_ERR_USAGE, "preprocess: sampling_size must be at least 1 (default 16)");
    if (out->index_bits != 16 && out->index_bits != 32)
        return clvr_error_set(err, CLVR_ERR_USAGE, "preprocess: index_bits is %u; use 16 or 32", out->index_bits);
    if (out->one_curve != CLVR_ONE_CURVE_AUTO && out->one_curve != CLVR_ONE_CURVE_ON &&
        out->one_curve != CLVR_ONE_CURVE_OFF)
        return clvr_error_set(err, CLVR_ERR_USAGE, "preprocess: one_curve is %d; use CLVR_ONE_CURVE_AUTO, _ON or _OFF",
                              out->one_curve);
    if (out->max_instance_elements == 0) out->max_instance_elements = out->index_bits == 16 ? 1u << 20 : 1u << 16;
    for (int k = 0; out->quantize_box && k < 3; ++k)
        if (!(isfinite(out->quantize_box->lo[k]) && isfinite(out->quantize_box->hi[k]) &&
              out->quantize_box->lo[k] <= out->quantize_box->hi[k]))
            return clvr_error_set(err, CLVR_ERR_USAGE,
                                  "preprocess: quantize_box axis %d is [%g, %g]; give finite bounds with lo <= hi", k,
                                  (double)out->quantize_box->lo[k], (double)out->quantize_box->hi[k]);
    return CLVR_OK;
}

const clvr_box *clvr_pp_quantize_box(const clvr_preprocess_options *o, const clvr_box *mesh_bounds)
{
    return o->quantize_box ? o->quantize_box : mesh_bounds;
}

const char *clvr_pp_stage_name(int stage)
{
    static const char *names[CLVR_PP_STAGE_COUNT] = {"upload", "bounds", "keys", "sort", "gather",
                                                     "sampling", "split", "instances", "vertices", "leaves",
                                                     "partition", "extract", "merge"};
    return stage >= 0 && stage < CLVR_PP_STAGE_COUNT ? names[stage] : "?";
}

void clvr_pp_layout_make(clvr_pp_layout *l, const uint64_t count[CLVR_CELL_TYPE_COUNT])
{
    uint64_t e = 0, s = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        l->count[t] = count[t];
        l->first[t] = e;
        l->slot[t] = s;
        e += count[t];
        s += count[t] * clvr_cell_vertex_count(t);
    }
    l->num_elements = e;
    l->num_slots = s;
}

int clvr_pp_sorted_layout(const clvr_preprocess_options *o, const clvr_pp_layout *in, clvr_pp_layout *out)
{
    *out = *in;
    if (!clvr_pp_one_curve(o, in->count)) return 0;
    const uint64_t hexes[CLVR_CELL_TYPE_COUNT] = {0, 0, 0, in->num_elements};
    clvr_pp_layout_make(out, hexes);
    return 1;
}

void clvr_pp_type_layout(const clvr_pp_layout *l, clvr_type_layout *out)
{
    memset(out, 0, sizeof *out);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        out->first[t] = (clvr_u32)l->first[t]; /* < 2^32: clvr_preprocess refuses bigger meshes */
        out->slot[t] = l->slot[t];
    }
}

float clvr_pp_scale(const clvr_box *b)
{
    float ext = 0.0f;
    for (int k = 0; k < 3; ++k) {
        float d = b->hi[k] - b->lo[k];
        if (d > ext) ext = d;
    }
    return ext > 0.0f ? 65536.0f / ext : 0.0f;
}

uint64_t clvr_pp_segment_floor(uint32_t compute_units)
{
    /* One work item walks a segment alone, one element after another: on the
     * H200 (132 compute units) that was 1.6 us an element, so 2^20-element
     * segments made the split 1.65 s at 1M and at 10M elements alike (session
     * 42). Many compute units get segments of 2^17 (about 2 instances of
     * 58k elements and a partial one, which the segment's end closes). */
    return compute_units >= 32 ? 1ull << 17 : 1ull << 20;
}

void clvr_pp_split_plan_make(clvr_pp_split_plan *p, const clvr_pp_layout *l, const clvr_preprocess_options *o,
                             uint32_t compute_units, uint64_t num_vertices)
{
    memset(p, 0, sizeof *p);
    uint32_t cu = compute_units ? compute_units : 1;
    const uint64_t seg_floor = clvr_pp_segment_floor(cu);
    p->max_elems = o->max_instance_elements;
    if (o->index_bits == 16) p->vlimit = CLVR_INSTANCE_MAX_VERTS16 - 1u;
    else {
        uint64_t v = (uint64_t)p->max_elems * CLVR_CELL_MAX_VERTS;
        if (v > num_vertices) v = num_vertices;
        p->vlimit = v < 8 ? 8u : (uint32_t)v;
    }
    /* Load factor at most 1/2 keeps the linear probes short. */
    p->log2cap = 4;
    while ((1ull << p->log2cap) < 2ull * ((uint64_t)p->vlimit + CLVR_CELL_MAX_VERTS)) ++p->log2cap;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        uint64_t n = l->count[t];
        uint64_t seg = (n + 4ull * cu - 1) / (4ull * cu);
        if (seg < seg_floor) seg = seg_floor;
        p->seg_len[t] = (uint32_t)(seg > 0xffffffffull ? 0xffffffffull : seg);
        p->nseg[t] = n ? (uint32_t)((n + p->seg_len[t] - 1) / p->seg_len[t]) : 0;
        uint32_t vpe = clvr_cell_vertex_count(t);
        uint32_t m = (p->vlimit - vpe + 1) / vpe;
        if (m > p->max_elems) m = p->max_elems;
        if (m < 1) m = 1;
        uint64_t seg_elems = n < p->seg_len[t] ? n : p->seg_len[t];
        if (seg_elems / m + 2 > p->rec_max) p->rec_max = (uint32_t)(seg_elems / m + 2);
        p->rec_base[t] = p->total_segments;
        p->total_segments += p->nseg[t];
    }
}

/* ------------------------------------------------------------ program */

clvr_status clvr_pp_create(clvr_cl *cl, clvr_pp *pp, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    memset(pp, 0, sizeof *pp);
    pp->cl = cl;
    uint32_t cu = cl->compute_units ? cl->compute_units : 1;
    /* A few tiles per compute unit balance the load on a CPU; GPUs want many. */
    pp->max_tiles = cl->device_type & CL_DEVICE_TYPE_GPU ? 4096u : 8u * cu;
    if (pp->max_tiles > 4096u) pp->max_tiles = 4096u;
    /* The bucket phase runs one work-item per bucket: a CPU's shape. Below
     * 2^16 items the whole array fits in cache anyway. */
    pp->sort_hybrid_min = cl->device_type & CL_DEVICE_TYPE_GPU ? UINT64_MAX : 1u << 16;
    CLVR_TRY(clvr_cl_build(cl, "preprocess.cl", NULL, &pp->prog, err));
    struct { cl_kernel *k; const char *name; } ks[] = {
        {&pp->bounds_tiles, "clvr_pp_bounds_tiles"},
#define CLVR_PP_KEYS_KERNEL_(id, name, nv) {&pp->keys_type[id], "clvr_pp_keys_" #name},
        CLVR_CELL_TYPES(CLVR_PP_KEYS_KERNEL_)
#undef CLVR_PP_KEYS_KERNEL_
        {&pp->scan_reduce, "clvr_pp_scan_reduce"},   {&pp->scan_sums, "clvr_pp_scan_sums"},
        {&pp->scan_apply, "clvr_pp_scan_apply"},     {&pp->select_scatter, "clvr_pp_select_scatter"},
        {&pp->radix_andor, "clvr_pp_radix_andor"},   {&pp->radix_hist, "clvr_pp_radix_hist"},
        {&pp->radix_scatter, "clvr_pp_radix_scatter"}, {&pp->gather, "clvr_pp_gather"},
        {&pp->gather_collapse, "clvr_pp_gather_collapse"},
        {&pp->sampling, "clvr_pp_sampling"},         {&pp->leaf_boxes, "clvr_pp_leaf_boxes"},
        {&pp->instance_bounds, "clvr_pp_instance_bounds"}, {&pp->split, "clvr_pp_split"},
        {&pp->rec_flags, "clvr_pp_rec_flags"},       {&pp->inst_counts, "clvr_pp_inst_counts"},
        {&pp->inst_write, "clvr_pp_inst_write"},     {&pp->vertices, "clvr_pp_vertices"},
        {&pp->radix_buckets, "clvr_pp_radix_buckets"}, {&pp->iota, "clvr_pp_iota"},
    };
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i) CLVR_TRY(clvr_cl_kernel(pp->prog, ks[i].name, ks[i].k, err));
cleanup:
    if (s != CLVR_OK) clvr_pp_destroy(pp);
    return s;
}

void clvr_pp_destroy(clvr_pp *pp)
{
    if (!pp) return;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        if (pp->keys_type[t]) { clReleaseKernel(pp->keys_type[t]); pp->keys_type[t] = NULL; }
    cl_kernel *ks[] = {&pp->bounds_tiles, &pp->scan_reduce, &pp->scan_sums, &pp->scan_apply, &pp->select_scatter, &pp->radix_andor, &pp->radix_hist, &pp->radix_scatter, &pp->gather, &pp->gather_collapse,
                       &pp->sampling, &pp->leaf_boxes, &pp->instance_bounds, &pp->split, &pp->rec_flags,
                       &pp->inst_counts, &pp->inst_write, &pp->vertices, &pp->radix_buckets, &pp->iota};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i)
        if (*ks[i]) { clReleaseKernel(*ks[i]); *ks[i] = NULL; }
    if (pp->prog) clReleaseProgram(pp->prog);
    pp->prog = NULL;
}

uint32_t clvr_pp_tiles(const clvr_pp *pp, uint64_t n)
{
    uint64_t t = (n + 4095) / 4096;
    if (t > pp->max_tiles) t = pp->max_tiles;
    return t ? (uint32_t)t : 1u;
}

clvr_status clvr_pp_launch(clvr_pp *pp, cl_kernel k, uint64_t n, size_t local, double *sec, clvr_error *err)
{
    cl_event ev = NULL;
    clvr_status s = clvr_cl_run1d(pp->cl, k, (size_t)n, local, sec ? &ev : NULL, err);
    if (s == CLVR_OK && ev) *sec += clvr_cl_event_seconds(ev);
    if (ev) clReleaseEvent(ev);
    return s;
}

/* ------------------------------------------------------------ stages */

clvr_status clvr_pp_bounds(clvr_pp *pp, cl_mem pos, cl_mem scal, uint64_t n, clvr_box *out, double *sec,
                           clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem part = NULL;
    clvr_box *host = NULL;
    cl_ulong nn = n;
    cl_uint tiles = clvr_pp_tiles(pp, n);
    cl_ulong chunk = (n + tiles - 1) / tiles;
    for (int k = 0; k < 4; ++k) { out->lo[k] = INFINITY; out->hi[k] = -INFINITY; }
    if (n == 0) return CLVR_OK;
    CLVR_TRY(clvr_cl_buffer(pp->cl, CL_MEM_READ_WRITE, tiles * sizeof(clvr_box), NULL, "bounds tiles", &part, err));
    cl_kernel k = pp->bounds_tiles;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(pos), CLVR_ARG(scal), CLVR_ARG(nn), CLVR_ARG(chunk), CLVR_ARG(tiles),
                          CLVR_ARG(part)));
    CLVR_TRY(clvr_pp_launch(pp, k, tiles, 1, sec, err));
    host = malloc(tiles * sizeof *host);
    if (!host) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for bounds"); goto cleanup; }
    CLVR_CL_CHECK(clEnqueueReadBuffer(pp->cl->queue, part, CL_TRUE, 0, tiles * sizeof *host, host, 0, NULL, NULL));
    for (cl_uint t = 0; t < tiles; ++t)
        for (int c = 0; c < 4; ++c) {
            if (host[t].lo[c] < out->lo[c]) out->lo[c] = host[t].lo[c];
            if (host[t].hi[c] > out->hi[c]) out->hi[c] = host[t].hi[c];
        }
cleanup:
    free(host);
    clvr_cl_release(pp->cl, &part);
    return s;
}

clvr_status clvr_pp_keys(clvr_pp *pp, cl_mem pos, cl_mem idx, const clvr_pp_layout *l, const clvr_box *b,
                         int morton, int one_curve, cl_mem keys, cl_mem vals, double *sec, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_float gx = b->lo[0], gy = b->lo[1], gz = b->lo[2], scale = clvr_pp_scale(b);
    cl_int mo = morton, with_vals = vals != NULL;
    for (cl_uint t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        cl_uint count = (cl_uint)l->count[t], first = (cl_uint)l->first[t], kt = one_curve ? CLVR_CELL_HEX : t;
        if (count == 0) continue;
        cl_ulong slot0 = l->slot[t];
        cl_kernel k = pp->keys_type[t];
        cl_mem vbuf = with_vals ? vals : keys; /* a valid buffer either way; unused without values */
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(pos), CLVR_ARG(idx), CLVR_ARG(slot0), CLVR_ARG(count), CLVR_ARG(first),
                              CLVR_ARG(gx), CLVR_ARG(gy), CLVR_ARG(gz), CLVR_ARG(scale), CLVR_ARG(mo), CLVR_ARG(kt),
                              CLVR_ARG(keys), CLVR_ARG(vbuf), CLVR_ARG(with_vals)));
        CLVR_TRY(clvr_pp_launch(pp, k, (count + 1u) / 2u, 64, sec, err)); /* two elements per work-item */
    }
cleanup:
    return s;
}

/* Per-tile sums (flags: counts of nonzero) scanned in place into sums[0..tiles]. */
static clvr_status tile_sums(clvr_pp *pp, cl_mem in, uint64_t n, cl_uint tiles, cl_ulong chunk, int flags,
                             cl_mem sums, double *sec, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_ulong nn = n;
    cl_int f = flags;
    cl_kernel k = pp->scan_reduce;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(in), CLVR_ARG(nn), CLVR_ARG(chunk), CLVR_ARG(tiles), CLVR_ARG(f),
                          CLVR_ARG(sums)));
    CLVR_TRY(clvr_pp_launch(pp, k, tiles, 1, sec, err));
    k = pp->scan_sums;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(sums), CLVR_ARG(tiles)));
    CLVR_TRY(clvr_pp_launch(pp, k, 1, 1, sec, err));
cleanup:
    return s;
}

clvr_status clvr_pp_scan(clvr_pp *pp, cl_mem in, cl_mem out, uint64_t n, uint32_t *total, double *sec,
                         clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem sums = NULL;
    cl_uint tiles = clvr_pp_tiles(pp, n);
    cl_ulong chunk = (n + tiles - 1) / tiles, nn = n;
    if (total) *total = 0;
    if (n == 0) return CLVR_OK;
    CLVR_TRY(clvr_cl_buffer(pp->cl, CL_MEM_READ_WRITE, (tiles + 1) * sizeof(cl_uint), NULL, "scan sums", &sums, err));
    CLVR_TRY(tile_sums(pp, in, n, tiles, chunk, 0, sums, sec, err));
    cl_kernel k = pp->scan_apply;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(in), CLVR_ARG(out), CLVR_ARG(nn), CLVR_ARG(chunk), CLVR_ARG(tiles),
                          CLVR_ARG(sums)));
    CLVR_TRY(clvr_pp_launch(pp, k, tiles, 1, sec, err));
    if (total)
        CLVR_CL_CHECK(clEnqueueReadBuffer(pp->cl->queue, sums, CL_TRUE, tiles * sizeof(cl_uint), sizeof(cl_uint),
                                          total, 0, NULL, NULL));
cleanup:
    clvr_cl_release(pp->cl, &sums);
    return s;
}

clvr_status clvr_pp_select(clvr_pp *pp, cl_mem flags, cl_mem values, cl_mem out, uint64_t n, uint32_t *count,
                           double *sec, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem sums = NULL;
    cl_uint tiles = clvr_pp_tiles(pp, n);
    cl_ulong chunk = (n + tiles - 1) / tiles, nn = n;
    cl_int use_ids = values == NULL;
    *count = 0;
    if (n == 0) return CLVR_OK;
    CLVR_TRY(clvr_cl_buffer(pp->cl, CL_MEM_READ_WRITE, (tiles + 1) * sizeof(cl_uint), NULL, "select sums", &sums, err));
    CLVR_TRY(tile_sums(pp, flags, n, tiles, chunk, 1, sums, sec, err));
    cl_kernel k = pp->select_scatter;
    cl_mem vals = values ? values : flags; /* any valid buffer when ids are selected */
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(flags), CLVR_ARG(vals), CLVR_ARG(use_ids), CLVR_ARG(nn), CLVR_ARG(chunk),
                          CLVR_ARG(tiles), CLVR_ARG(sums), CLVR_ARG(out)));
    CLVR_TRY(clvr_pp_launch(pp, k, tiles, 1, sec, err));
    CLVR_CL_CHECK(clEnqueueReadBuffer(pp->cl->queue, sums, CL_TRUE, tiles * sizeof(cl_uint), sizeof(cl_uint), count, 0,
                                      NULL, NULL));
cleanup:
    clvr_cl_release(pp->cl, &sums);
    return s;
}

/* Digit histograms per tile at `shift`, scanned in place (digit-major), so
 * hist[d * tiles + t] is where tile t's first key of digit d goes. */
static clvr_status radix_count(clvr_pp *pp, cl_mem keys, cl_ulong n, cl_ulong chunk, cl_uint tiles, cl_uint shift,
                               cl_mem hist, cl_mem sums, double *sec, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_ulong hn = (cl_ulong)tiles * CLVR_PP_RADIX;
    cl_uint one = 1;
    cl_int noflags = 0;
    cl_kernel k = pp->radix_hist;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(keys), CLVR_ARG(n), CLVR_ARG(chunk), CLVR_ARG(tiles), CLVR_ARG(shift),
                          CLVR_ARG(hist)));
    CLVR_TRY(clvr_pp_launch(pp, k, tiles, 1, sec, err));
    /* The histogram table is scanned with scan.cl's kernels: one tile is enough for it. */
    k = pp->scan_reduce;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(hist), CLVR_ARG(hn), CLVR_ARG(hn), CLVR_ARG(one), CLVR_ARG(noflags),
                          CLVR_ARG(sums)));
    CLVR_TRY(clvr_pp_launch(pp, k, 1, 1, sec, err));
    k = pp->scan_sums;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(sums), CLVR_ARG(one)));
    CLVR_TRY(clvr_pp_launch(pp, k, 1, 1, sec, err));
    k = pp->scan_apply;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(hist), CLVR_ARG(hist), CLVR_ARG(hn), CLVR_ARG(hn), CLVR_ARG(one),
                          CLVR_ARG(sums)));
    CLVR_TRY(clvr_pp_launch(pp, k, 1, 1, sec, err));
cleanup:
    return s;
}

/* The sort's result moves to the other buffer pair. */
static void swap_pairs(cl_mem *keys, cl_mem *vals, cl_mem *keys_tmp, cl_mem *vals_tmp)
{
    cl_mem t = *keys; *keys = *keys_tmp; *keys_tmp = t;
    t = *vals; *vals = *vals_tmp; *vals_tmp = t;
}

/* Stable scatter by the digit at `shift` from the table of radix_count;
 * swaps the handles so that *keys / *vals hold the result. */
static clvr_status radix_scatter(clvr_pp *pp, cl_mem *keys, cl_mem *vals, cl_mem *keys_tmp, cl_mem *vals_tmp,
                                 cl_ulong n, cl_ulong chunk, cl_uint tiles, cl_uint shift, cl_mem hist, cl_uint iota,
                                 double *sec, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_kernel k = pp->radix_scatter;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(*keys), CLVR_ARG(*vals), CLVR_ARG(n), CLVR_ARG(chunk), CLVR_ARG(tiles),
                          CLVR_ARG(shift), CLVR_ARG(hist), CLVR_ARG(*keys_tmp), CLVR_ARG(*vals_tmp), CLVR_ARG(iota)));
    CLVR_TRY(clvr_pp_launch(pp, k, tiles, 1, sec, err));
    swap_pairs(keys, vals, keys_tmp, vals_tmp);
cleanup:
    return s;
}

/* *varying = the bits that differ between some of the n keys (their AND
 * xor their OR). */
static clvr_status sort_varying(clvr_pp *pp, cl_mem keys, cl_ulong n, cl_ulong chunk, cl_uint tiles,
                                cl_ulong *varying, double *sec, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem andor = NULL;
    cl_ulong *ao = NULL;
    CLVR_TRY(clvr_cl_buffer(pp->cl, CL_MEM_READ_WRITE, 2 * tiles * sizeof(cl_ulong), NULL, "sort and/or", &andor, err));
    cl_kernel k = pp->radix_andor;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(keys), CLVR_ARG(n), CLVR_ARG(chunk), CLVR_ARG(tiles), CLVR_ARG(andor)));
    CLVR_TRY(clvr_pp_launch(pp, k, tiles, 1, sec, err));
    ao = malloc(2 * tiles * sizeof *ao);
    if (!ao) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory in sort"); goto cleanup; }
    CLVR_CL_CHECK(clEnqueueReadBuffer(pp->cl->queue, andor, CL_TRUE, 0, 2 * tiles * sizeof *ao, ao, 0, NULL, NULL));
    cl_ulong all_and = ~0ull, any_or = 0;
    for (cl_uint t = 0; t < tiles; ++t) { all_and &= ao[2 * t]; any_or |= ao[2 * t + 1]; }
    *varying = all_and ^ any_or;
cleanup:
    free(ao);
    clvr_cl_release(pp->cl, &andor);
    return s;
}

clvr_status clvr_pp_sort(clvr_pp *pp, cl_mem *keys, cl_mem *vals, cl_mem *keys_tmp, cl_mem *vals_tmp, uint64_t n,
                         int iota_vals, uint64_t varying_hint, double *sec, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem hist = NULL, sums = NULL;
    cl_uint *table = NULL;
    if (n > 0xffffffffull)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "radix sort of %llu items: at most 2^32 - 1 are supported",
                              (unsigned long long)n);
    cl_uint iota = iota_vals != 0; /* values still to make: the first scatter makes them */
    if (n < 2) goto done;
    cl_uint tiles = clvr_pp_tiles(pp, n);
    cl_ulong chunk = (n + tiles - 1) / tiles, nn = n;
    cl_uint hn = tiles * CLVR_PP_RADIX;
    CLVR_TRY(clvr_cl_buffer(pp->cl, CL_MEM_READ_WRITE, hn * sizeof(cl_uint), NULL, "sort histograms", &hist, err));
    CLVR_TRY(clvr_cl_buffer(pp->cl, CL_MEM_READ_WRITE, 2 * sizeof(cl_uint), NULL, "sort scan sums", &sums, err));
    /* The caller's hint (a superset of the varying bits) spares the pass
     * that finds them, unless the hybrid sort below falls back to LSD,
     * which skips constant digits and so needs them exactly. */
    cl_ulong varying = varying_hint;
    int exact = varying == 0;
    if (exact) {
        CLVR_TRY(sort_varying(pp, *keys, nn, chunk, tiles, &varying, sec, err));
        if (varying == 0) goto done; /* all keys equal: the input order is the stable order */
    }

    /* Hybrid: the top digit is the 8 bits ending at the highest varying bit;
     * the digits below it that vary are left to the bucket kernel. */
    cl_uint top = 63;
    while (!((varying >> top) & 1u)) --top;
    const cl_uint msd = top + 1 > CLVR_PP_RADIX_BITS ? top + 1 - CLVR_PP_RADIX_BITS : 0;
    cl_uint digits = 0, passes = 0;
    for (cl_uint j = 0; j * CLVR_PP_RADIX_BITS < msd; ++j) {
        cl_uint shift = j * CLVR_PP_RADIX_BITS;
        cl_ulong below = msd - shift < CLVR_PP_RADIX_BITS ? (1ull << (msd - shift)) - 1 : CLVR_PP_RADIX - 1;
        if ((varying >> shift) & below) { digits |= 1u << j; ++passes; }
    }
    if (n >= pp->sort_hybrid_min && passes > 0) {
        CLVR_TRY(radix_count(pp, *keys, nn, chunk, tiles, msd, hist, sums, sec, err));
        table = malloc(hn * sizeof *table);
        if (!table) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory in sort"); goto cleanup; }
        CLVR_CL_CHECK(clEnqueueReadBuffer(pp->cl->queue, hist, CL_TRUE, 0, hn * sizeof *table, table, 0, NULL, NULL));
        uint64_t largest = 0;
        for (cl_uint d = 0; d < CLVR_PP_RADIX; ++d) {
            uint64_t end = d + 1 < CLVR_PP_RADIX ? table[(d + 1) * tiles] : n, size = end - table[d * tiles];
            if (size > largest) largest = size;
        }
        /* Keys piled into a few top digits (a tiny dense region of a big
         * box, or a hint wider than the keys) would leave one work-item
         * sorting most of the array: then the plain LSD sort below, which
         * spreads every pass over all tiles. */
        if (largest <= n / 16) {
            CLVR_TRY(radix_scatter(pp, keys, vals, keys_tmp, vals_tmp, nn, chunk, tiles, msd, hist, iota, sec, err));
            iota = 0;
            cl_kernel k = pp->radix_buckets;
            CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(*keys), CLVR_ARG(*vals), CLVR_ARG(*keys_tmp), CLVR_ARG(*vals_tmp),
                                  CLVR_ARG(hist), CLVR_ARG(tiles), CLVR_ARG(nn), CLVR_ARG(digits)));
            CLVR_TRY(clvr_pp_launch(pp, k, CLVR_PP_RADIX, 1, sec, err));
            if (passes & 1u) swap_pairs(keys, vals, keys_tmp, vals_tmp);
            goto cleanup;
        }
    }
    if (!exact) {
        CLVR_TRY(sort_varying(pp, *keys, nn, chunk, tiles, &varying, sec, err));
        if (varying == 0) goto done;
    }
    for (cl_uint shift = 0; shift < 64; shift += CLVR_PP_RADIX_BITS) {
        if (((varying >> shift) & (CLVR_PP_RADIX - 1)) == 0) continue; /* digit constant: order kept */
        CLVR_TRY(radix_count(pp, *keys, nn, chunk, tiles, shift, hist, sums, sec, err));
        CLVR_TRY(radix_scatter(pp, keys, vals, keys_tmp, vals_tmp, nn, chunk, tiles, shift, hist, iota, sec, err));
        iota = 0;
    }
done:
    if (iota && n > 0) { /* no pass ran: the values are still to make */
        cl_uint n32 = (cl_uint)n;
        cl_kernel ki = pp->iota;
        CLVR_TRY(CLVR_CL_ARGS(ki, err, CLVR_ARG(*vals), CLVR_ARG(n32)));
        CLVR_TRY(clvr_pp_launch(pp, ki, n, 64, sec, err));
    }
cleanup:
    free(table);
    clvr_cl_release(pp->cl, &hist);
    clvr_cl_release(pp->cl, &sums);
    return s;
}

/* ------------------------------------------------------------ pipeline */

void clvr_clustered_release(clvr_cl *cl, clvr_clustered *c)
{
    if (!c) return;
    clvr_cl_release(cl, &c->vertices);
    clvr_cl_release(cl, &c->idx16);
    clvr_cl_release(cl, &c->idx32);
    for (uint32_t p = 0; p + 1 < CLVR_MAX_SPLITS; ++p) {
        clvr_cl_release(cl, &c->vertices_more[p]);
        clvr_cl_release(cl, &c->idx16_more[p]);
        clvr_cl_release(cl, &c->idx32_more[p]);
    }
    clvr_cl_release(cl, &c->piece_dummy);
    clvr_cl_release(cl, &c->instances);
    clvr_cl_release(cl, &c->leaf_boxes);
    clvr_cl_release(cl, &c->sampling);
    clvr_cl_release(cl, &c->order);
    /* After the buffers: a finished command may still read them until released. */
    for (size_t i = 0; i < sizeof c->host_arrays / sizeof c->host_arrays[0]; ++i)
        if (c->host_arrays[i]) munmap(c->host_arrays[i], (size_t)c->host_array_bytes[i]);
    free(c->host_instances);
    memset(c, 0, sizeof *c);
}

void clvr_clustered_fill_stats(clvr_clustered *c, const clvr_mesh *m)
{
    c->bytes_vertices_before = m->num_vertices * 16ull;
    c->bytes_vertices_after = c->num_vertices * 16ull;
    c->bytes_indices_before = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        c->bytes_indices_before += m->num_cells[t] * clvr_cell_vertex_count(t) * 4ull;
    c->bytes_indices_after = c->num_idx16 * 2ull + c->num_idx32 * 4ull;
    c->bytes_leaf_boxes = c->num_leaves * sizeof(clvr_box);
    c->bytes_instances = c->num_instances * sizeof(clvr_instance);
    c->bytes_sampling = c->num_sampling * sizeof(clvr_sampling_cluster);
    c->num_instances16 = 0;
    for (uint64_t i = 0; i < c->num_instances; ++i) c->num_instances16 += c->host_instances[i].index_bits == 16;
    c->avg_instance_elements = c->num_instances ? (double)c->num_elements / (double)c->num_instances : 0.0;
    c->avg_instance_vertices = c->num_instances ? (double)c->num_vertices / (double)c->num_instances : 0.0;
    c->avg_leaf_elements = c->num_leaves ? (double)c->num_elements / (double)c->num_leaves : 0.0;
}

void clvr_pp_workspace_release(clvr_cl *cl, clvr_pp_workspace *ws)
{
    if (!ws) return;
    for (int i = 0; i < CLVR_PP_WS_COUNT; ++i) clvr_cl_release(cl, &ws->buf[i]);
    memset(ws, 0, sizeof *ws);
}

/* A read-write scratch buffer of at least `bytes`: workspace slot `slot`
 * (grown when too small), or a buffer of its own without a workspace. The
 * caller owns one reference either way and gives it back with ws_drop. */
static clvr_status ws_get(clvr_cl *cl, clvr_pp_workspace *ws, int slot, uint64_t bytes, const char *what, cl_mem *out,
                          clvr_error *err)
{
    if (!ws) return clvr_cl_buffer(cl, CL_MEM_READ_WRITE, bytes, NULL, what, out, err);
    if (!ws->buf[slot] || ws->bytes[slot] < bytes) {
        clvr_cl_release(cl, &ws->buf[slot]);
        ws->bytes[slot] = 0;
        clvr_status s = clvr_cl_buffer(cl, CL_MEM_READ_WRITE, bytes, NULL, what, &ws->buf[slot], err);
        if (s != CLVR_OK) return s;
        ws->bytes[slot] = bytes;
    }
    clRetainMemObject(ws->buf[slot]);
    *out = ws->buf[slot];
    return CLVR_OK;
}

/* The workspace slot holding buffer m, or -1. */
static int ws_slot_of(const clvr_pp_workspace *ws, cl_mem m)
{
    for (int i = 0; ws && m && i < CLVR_PP_WS_COUNT; ++i)
        if (ws->buf[i] == m) return i;
    return -1;
}

/* Gives back the caller's reference to a buffer from ws_get (or any
 * buffer): the workspace keeps its own, so its memory stays counted. */
static void ws_drop(clvr_cl *cl, clvr_pp_workspace *ws, cl_mem *m)
{
    if (*m && ws_slot_of(ws, *m) >= 0) {
        clReleaseMemObject(*m);
        *m = NULL;
    } else clvr_cl_release(cl, m);
}

/* A result buffer of at least `bytes`: a recycled one from workspace slot
 * `slot` (it leaves the workspace), or a new one. */
static clvr_status ws_take(clvr_cl *cl, clvr_pp_workspace *ws, int slot, uint64_t bytes, const char *what,
                           cl_mem *out, clvr_error *err)
{
    if (ws && bytes > 0 && ws->buf[slot] && ws->bytes[slot] >= bytes) {
        *out = ws->buf[slot];
        ws->buf[slot] = NULL;
        ws->bytes[slot] = 0;
        return CLVR_OK;
    }
    return clvr_cl_buffer(cl, CL_MEM_READ_WRITE, bytes, NULL, what, out, err);
}

void clvr_pp_workspace_recycle(clvr_cl *cl, clvr_pp_workspace *ws, clvr_clustered *c)
{
    if (!c) return;
    /* A result assembled on the host (partitions, pieces) has its buffers
     * over host mappings that clvr_clustered_release unmaps: none of them
     * may outlive it in the workspace. */
    int host_assembled = 0;
    for (size_t i = 0; i < sizeof c->host_arrays / sizeof c->host_arrays[0]; ++i)
        host_assembled |= c->host_arrays[i] != NULL;
    if (host_assembled) ws = NULL;
    struct { cl_mem *m; int slot; } give[] = {
        {&c->vertices, CLVR_PP_WS_OUT_VERTICES}, {&c->idx16, CLVR_PP_WS_OUT_IDX16},
        {&c->idx32, CLVR_PP_WS_OUT_IDX32}, {&c->leaf_boxes, CLVR_PP_WS_OUT_LEAF_BOXES},
        {&c->sampling, CLVR_PP_WS_OUT_SAMPLING},
    };
    for (size_t i = 0; ws && i < sizeof give / sizeof give[0]; ++i) {
        size_t n = 0;
        if (!*give[i].m || clGetMemObjectInfo(*give[i].m, CL_MEM_SIZE, sizeof n, &n, NULL) != CL_SUCCESS) continue;
        if (ws->buf[give[i].slot] && ws->bytes[give[i].slot] >= n) continue; /* keep the bigger one */
        clvr_cl_release(cl, &ws->buf[give[i].slot]);
        ws->buf[give[i].slot] = *give[i].m;
        ws->bytes[give[i].slot] = n;
        *give[i].m = NULL;
    }
    clvr_clustered_release(cl, c);
}

/* The buffer leaves the workspace (it becomes part of a result). */
static void ws_detach(clvr_pp_workspace *ws, cl_mem m)
{
    const int i = ws_slot_of(ws, m);
    if (i < 0) return;
    clReleaseMemObject(ws->buf[i]);
    ws->buf[i] = NULL;
    ws->bytes[i] = 0;
}

clvr_status clvr_preprocess(clvr_cl *cl, const clvr_mesh *m, const clvr_preprocess_options *o, clvr_clustered *out,
                            clvr_error *err)
{
    return clvr_preprocess_ws(cl, m, o, NULL, out, err);
}

clvr_status clvr_preprocess_ws(clvr_cl *cl, const clvr_mesh *m, const clvr_preprocess_options *o,
                               clvr_pp_workspace *ws, clvr_clustered *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_pp pp = {0};
    clvr_preprocess_options opt;
    clvr_pp_layout L, LS;
    clvr_pp_split_plan plan;
    cl_mem pos = NULL, scal = NULL, idx_in = NULL, vmap = NULL, keys = NULL, vals = NULL, keys_tmp = NULL, vals_tmp = NULL,
           idx_sorted = NULL, tk = NULL, segbuf = NULL, recs = NULL, rec_counts = NULL, flags = NULL, sel = NULL,
           nverts = NULL, nleaves = NULL, vsrc = NULL;
    cl_uint4 *segs = NULL;
    double t_start = wall_now();
    double *st;
    memset(out, 0, sizeof *out);
    st = out->stage_s;
    CLVR_TRY(clvr_pp_options_resolve(o, &opt, err));
    clvr_pp_layout_make(&L, m->num_cells);
    if (L.num_elements == 0) { s = clvr_error_set(err, CLVR_ERR_EMPTY, "preprocess: the mesh has no elements"); goto cleanup; }
    if (L.num_elements > 0xffffffffull || m->num_vertices > 0xffffffffull) {
        s = clvr_error_set(err, CLVR_ERR_OVERFLOW,
                           "preprocess: %llu elements and %llu vertices; the clustered mesh addresses at most "
                           "2^32 - 1 of each (clvr_instance.first_element)",
                           (unsigned long long)L.num_elements, (unsigned long long)m->num_vertices);
        goto cleanup;
    }
    const int bits32 = opt.index_bits == 32;
    int types_used = 0, only_type = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        if (L.count[t]) { ++types_used; only_type = (int)t; }
    /* LS: the layout from the gather on. With one curve, every element is
     * a collapsed hex (8 index slots). */
    const int one_curve = clvr_pp_sorted_layout(&opt, &L, &LS);
    out->leaf_size = opt.leaf_size;
    out->no_element_boxes = opt.no_element_boxes;
    out->sampling_size = opt.sampling_size;
    out->index_bits = opt.index_bits;
    out->morton = opt.morton;
    out->num_elements = L.num_elements;
    out->num_partitions = 1;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) { out->num_cells[t] = LS.count[t]; out->first_cell[t] = LS.first[t]; }
    for (uint32_t t = 0; one_curve && t < CLVR_CELL_HEX; ++t) out->collapsed[t] = L.count[t];

    double tb = wall_now();
    CLVR_TRY(clvr_pp_create(cl, &pp, err));
    out->build_s = wall_now() - tb;
    clvr_pp_split_plan_make(&plan, &LS, &opt, cl->compute_units, m->num_vertices);

    /* --- upload */
    const uint64_t V = m->num_vertices, N = L.num_elements, S_in = L.num_slots, S = LS.num_slots;
    /* On a CPU device the kernels can read the mesh where it lies: buffers
     * made with CL_MEM_USE_HOST_PTR are the host arrays themselves (PoCL
     * maps them without a copy), which saves the write of every byte and the
     * page faults of fresh device memory (the upload was ~0.3 s of 10M
     * hexes). They are read-only, so the const mesh is never written. The
     * element indices can be borrowed only when one type holds them all,
     * as the kernels read the types' lists concatenated. Other devices get
     * copies. */
    const int zero_copy = (cl->device_type & CL_DEVICE_TYPE_CPU) != 0;
    const int borrow_idx = zero_copy && types_used == 1;
    {
        const cl_mem_flags ro = CL_MEM_READ_ONLY | (zero_copy ? CL_MEM_USE_HOST_PTR : 0);
        double tu = wall_now();
        CLVR_TRY(clvr_cl_buffer(cl, ro, V * 12, zero_copy ? (void *)m->positions : NULL, "vertex positions", &pos, err));
        CLVR_TRY(clvr_cl_buffer(cl, ro, V * 4, zero_copy ? (void *)m->scalars : NULL, "vertex scalars", &scal, err));
        if (borrow_idx)
            CLVR_TRY(clvr_cl_buffer(cl, ro, S_in * 4, (void *)m->indices[only_type], "element indices", &idx_in, err));
        else
            CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_IDX_IN, S_in * 4, "element indices", &idx_in, err));
        if (zero_copy) st[CLVR_PP_STAGE_UPLOAD] += wall_now() - tu;
    }
    {
        cl_event ev[2 + CLVR_CELL_TYPE_COUNT] = {0};
        int ne = 0;
        if (!zero_copy) {
            CLVR_CL_CHECK(clEnqueueWriteBuffer(cl->queue, pos, CL_FALSE, 0, V * 12, m->positions, 0, NULL, &ev[ne++]));
            CLVR_CL_CHECK(clEnqueueWriteBuffer(cl->queue, scal, CL_FALSE, 0, V * 4, m->scalars, 0, NULL, &ev[ne++]));
        }
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && !borrow_idx; ++t)
            if (L.count[t])
                CLVR_CL_CHECK(clEnqueueWriteBuffer(cl->queue, idx_in, CL_FALSE, L.slot[t] * 4,
                                                   L.count[t] * clvr_cell_vertex_count(t) * 4, m->indices[t], 0,
                                                   NULL, &ev[ne++]));
        for (int i = 0; i < ne; ++i) { st[CLVR_PP_STAGE_UPLOAD] += clvr_cl_event_seconds(ev[i]); clReleaseEvent(ev[i]); }
    }

    /* --- bounds, keys, sort */
    CLVR_TRY(clvr_pp_bounds(&pp, pos, scal, V, &out->bounds, &st[CLVR_PP_STAGE_BOUNDS], err));
    out->scalar_min = out->bounds.lo[3];
    out->scalar_max = out->bounds.hi[3];
    CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_KEYS, N * 8, "sort keys", &keys, err));
    CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_VALS, N * 4, "sort values", &vals, err));
    /* The values (element ids) are made by the sort's first pass. */
    CLVR_TRY(clvr_pp_keys(&pp, pos, idx_in, &L, clvr_pp_quantize_box(&opt, &out->bounds), opt.morton, one_curve, keys,
                          NULL, &st[CLVR_PP_STAGE_KEYS], err));
    CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_KEYS_TMP, N * 8, "sort keys (scratch)", &keys_tmp, err));
    CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_VALS_TMP, N * 4, "sort values (scratch)", &vals_tmp, err));
    {
        /* The keys are type << 48 | 48-bit curve key: the host knows which
         * type bits can differ, so the sort need not find out (a pass over
         * the keys) unless it falls back to plain LSD. */
        uint64_t type_and = ~0ull, type_or = 0; /* every type id, not only 2 bits */
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
            if (LS.count[t]) { type_and &= t; type_or |= t; }
        const uint64_t hint = ((type_and ^ type_or) << 48) | ((1ull << 48) - 1);
        CLVR_TRY(clvr_pp_sort(&pp, &keys, &vals, &keys_tmp, &vals_tmp, N, 1, hint, &st[CLVR_PP_STAGE_SORT], err));
    }
    ws_drop(cl, ws, &keys);
    ws_drop(cl, ws, &keys_tmp);
    ws_drop(cl, ws, &vals_tmp);

    /* --- gather in curve order */
    cl_uint n32 = (cl_uint)N;
    clvr_type_layout tl, tl_in;
    clvr_pp_type_layout(&L, &tl_in);
    clvr_pp_type_layout(&LS, &tl);
    CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_IDX_SORTED, S * 4, "sorted element indices", &idx_sorted, err));
    {
        cl_kernel k = one_curve ? pp.gather_collapse : pp.gather;
        cl_uint tiles = clvr_pp_tiles(&pp, N);
        cl_ulong chunk = (N + tiles - 1) / tiles;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(vals), CLVR_ARG(idx_in), CLVR_ARG(idx_sorted), CLVR_ARG(n32),
                              CLVR_ARG(chunk), CLVR_ARG(tiles), CLVR_ARG(tl_in)));
        CLVR_TRY(clvr_pp_launch(&pp, k, tiles, 1, &st[CLVR_PP_STAGE_GATHER], err));
    }
    if (opt.keep_order) {
        ws_detach(ws, vals);
        out->order = vals;
        vals = NULL;
    } else ws_drop(cl, ws, &vals);

    /* --- sampling clusters (from the sorted lists and the mesh's own vertices) */
    {
        uint64_t cfirst[CLVR_CELL_TYPE_COUNT], nc = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            cfirst[t] = nc;
            nc += (LS.count[t] + opt.sampling_size - 1) / opt.sampling_size;
        }
        out->num_sampling = nc;
        CLVR_TRY(ws_take(cl, ws, CLVR_PP_WS_OUT_SAMPLING, nc * sizeof(clvr_sampling_cluster), "sampling clusters",
                         &out->sampling, err));
        cl_uint ncl = (cl_uint)nc, size = opt.sampling_size, c1 = (cl_uint)cfirst[1], c2 = (cl_uint)cfirst[2],
                c3 = (cl_uint)cfirst[3];
        cl_kernel k = pp.sampling;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(pos), CLVR_ARG(scal), CLVR_ARG(idx_sorted), CLVR_ARG(ncl),
                              CLVR_ARG(size), CLVR_ARG(c1), CLVR_ARG(c2), CLVR_ARG(c3), CLVR_ARG(tl), CLVR_ARG(n32),
                              CLVR_ARG(out->sampling)));
        CLVR_TRY(clvr_pp_launch(&pp, k, nc, 64, &st[CLVR_PP_STAGE_SAMPLING], err));
    }

    /* --- greedy instance split with local re-indexing. The scratch vertex
     * map takes idx_in's place (same size; idx_in is not read any more),
     * or a buffer of its own when idx_in is the borrowed mesh array or
     * (one curve) smaller than the collapsed hexes' slots. */
    if (borrow_idx || S_in < S) {
        ws_drop(cl, ws, &idx_in);
        CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_VMAP, S * 4, "scratch vertex map", &vmap, err));
    } else {
        vmap = idx_in;
        idx_in = NULL;
    }
    out->num_idx16 = bits32 ? 0 : S;
    out->num_idx32 = bits32 ? S : 0;
    CLVR_TRY(ws_take(cl, ws, CLVR_PP_WS_OUT_IDX16, out->num_idx16 * 2, "16-bit indices", &out->idx16, err));
    CLVR_TRY(ws_take(cl, ws, CLVR_PP_WS_OUT_IDX32, out->num_idx32 * 4, "32-bit indices", &out->idx32, err));
    {
        const uint64_t cap = 1ull << plan.log2cap, tables = plan.total_segments;
        CLVR_TRY(ws_get(cl, ws, CLVR_PP_WS_HASH, tables * cap * 8, "split hash maps", &tk, err));
        cl_ulong zero = 0;
        cl_event ev = NULL;
        CLVR_CL_CHECK(clEnqueueFillBuffer(cl->queue, tk, &zero, sizeof zero, 0, tables * cap * 8, 0, NULL, &ev));
        st[CLVR_PP_STAGE_SPLIT] += clvr_cl_event_seconds(ev);
        clReleaseEvent(ev);
        /* Segment table: (type, first, end, 0) per segment, types in order. */
        segs = malloc(plan.total_segments * sizeof *segs);
        if (!segs) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the split plan"); goto cleanup; }
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
            for (uint32_t g = 0; g < plan.nseg[t]; ++g) {
                cl_uint4 *d = &segs[plan.rec_base[t] + g];
                uint64_t b = (uint64_t)g * plan.seg_len[t], e = b + plan.seg_len[t];
                d->s[0] = t;
                d->s[1] = (cl_uint)b;
                d->s[2] = (cl_uint)(e < LS.count[t] ? e : LS.count[t]);
                d->s[3] = 0;
            }
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, plan.total_segments * sizeof *segs, segs,
                                "split segments", &segbuf, err));
        /* Record slots: rec_max per segment. */
        cl_uint rec_max = plan.rec_max;
        uint64_t nslots = (uint64_t)plan.total_segments * rec_max;
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, nslots * sizeof(clvr_pp_instance_rec), NULL, "instance records",
                                &recs, err));
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, plan.total_segments * 4, NULL, "instance record counts",
                                &rec_counts, err));
        {
            cl_kernel k = pp.split;
            cl_int b32 = bits32;
            cl_uint nseg = plan.total_segments, vl = plan.vlimit, me = plan.max_elems, lc = plan.log2cap;
            CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(idx_sorted), CLVR_ARG(vmap), CLVR_ARG(out->idx16),
                                  CLVR_ARG(out->idx32), CLVR_ARG(b32), CLVR_ARG(segbuf), CLVR_ARG(nseg), CLVR_ARG(tl),
                                  CLVR_ARG(vl), CLVR_ARG(me), CLVR_ARG(tk), CLVR_ARG(lc), CLVR_ARG(rec_max),
                                  CLVR_ARG(recs), CLVR_ARG(rec_counts)));
            CLVR_TRY(clvr_pp_launch(&pp, k, nseg, 1, &st[CLVR_PP_STAGE_SPLIT], err));
        }
        ws_drop(cl, ws, &tk);
        clvr_cl_release(cl, &segbuf);
        ws_drop(cl, ws, &idx_sorted);

        /* --- instance table: flagged select of the used record slots, scans of the counts */
        double *si = &st[CLVR_PP_STAGE_INSTANCES];
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, nslots * 4, NULL, "record flags", &flags, err));
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, nslots * 4, NULL, "selected records", &sel, err));
        cl_uint ns = (cl_uint)nslots;
        cl_kernel k = pp.rec_flags;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(rec_counts), CLVR_ARG(ns), CLVR_ARG(rec_max), CLVR_ARG(flags)));
        CLVR_TRY(clvr_pp_launch(&pp, k, nslots, 64, si, err));
        uint32_t ninst = 0;
        CLVR_TRY(clvr_pp_select(&pp, flags, NULL, sel, nslots, &ninst, si, err));
        out->num_instances = ninst;
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (uint64_t)ninst * 4, NULL, "instance vertex counts", &nverts, err));
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (uint64_t)ninst * 4, NULL, "instance leaf counts", &nleaves, err));
        cl_uint ni = ninst, leaf = opt.leaf_size;
        k = pp.inst_counts;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(recs), CLVR_ARG(sel), CLVR_ARG(ni), CLVR_ARG(leaf), CLVR_ARG(nverts),
                              CLVR_ARG(nleaves)));
        CLVR_TRY(clvr_pp_launch(&pp, k, ninst, 64, si, err));
        uint32_t total_v = 0, total_l = 0;
        CLVR_TRY(clvr_pp_scan(&pp, nverts, nverts, ninst, &total_v, si, err));
        CLVR_TRY(clvr_pp_scan(&pp, nleaves, nleaves, ninst, &total_l, si, err));
        /* The scans are 32-bit: check that the true sums fit (they count vertices and leaves). */
        out->num_vertices = total_v;
        out->num_leaves = total_l;
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (uint64_t)ninst * sizeof(clvr_instance), NULL, "instances",
                                &out->instances, err));
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (uint64_t)ninst * 8, NULL, "instance vertex sources", &vsrc, err));
        k = pp.inst_write;
        cl_int b32 = bits32;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(recs), CLVR_ARG(sel), CLVR_ARG(ni), CLVR_ARG(nverts), CLVR_ARG(nleaves),
                              CLVR_ARG(leaf), CLVR_ARG(b32), CLVR_ARG(tl), CLVR_ARG(out->instances), CLVR_ARG(vsrc)));
        CLVR_TRY(clvr_pp_launch(&pp, k, ninst, 64, si, err));
    }

    /* --- clustered vertices */
    CLVR_TRY(ws_take(cl, ws, CLVR_PP_WS_OUT_VERTICES, out->num_vertices * 16, "clustered vertices", &out->vertices,
                            err));
    {
        cl_uint ni = (cl_uint)out->num_instances, nv = (cl_uint)out->num_vertices;
        cl_kernel k = pp.vertices;
        cl_uint tiles = clvr_pp_tiles(&pp, nv);
        cl_ulong chunk = ((cl_ulong)nv + tiles - 1) / tiles;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(pos), CLVR_ARG(scal), CLVR_ARG(vmap), CLVR_ARG(out->instances),
                              CLVR_ARG(vsrc), CLVR_ARG(ni), CLVR_ARG(nv), CLVR_ARG(chunk), CLVR_ARG(tiles),
                              CLVR_ARG(out->vertices)));
        CLVR_TRY(clvr_pp_launch(&pp, k, tiles, 1, &st[CLVR_PP_STAGE_VERTICES], err));
    }
    ws_drop(cl, ws, &vmap);
    clvr_cl_release(cl, &pos);
    clvr_cl_release(cl, &scal);

    /* --- leaf boxes, then instance bounds from them */
    CLVR_TRY(ws_take(cl, ws, CLVR_PP_WS_OUT_LEAF_BOXES, out->num_leaves * sizeof(clvr_box), "leaf boxes",
                            &out->leaf_boxes, err));
    {
        cl_uint ni = (cl_uint)out->num_instances, nl = (cl_uint)out->num_leaves, leaf = opt.leaf_size;
        cl_kernel k = pp.leaf_boxes;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(out->vertices), CLVR_ARG(out->idx16), CLVR_ARG(out->idx32),
                              CLVR_ARG(out->instances), CLVR_ARG(ni), CLVR_ARG(nl), CLVR_ARG(leaf),
                              CLVR_ARG(out->leaf_boxes)));
        CLVR_TRY(clvr_pp_launch(&pp, k, nl, 64, &st[CLVR_PP_STAGE_LEAVES], err));
        k = pp.instance_bounds;
        CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(out->instances), CLVR_ARG(ni), CLVR_ARG(out->leaf_boxes)));
        CLVR_TRY(clvr_pp_launch(&pp, k, ni, 64, &st[CLVR_PP_STAGE_LEAVES], err));
    }
    out->host_instances = malloc(out->num_instances * sizeof(clvr_instance));
    if (!out->host_instances) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the instance table"); goto cleanup; }
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, out->instances, CL_TRUE, 0, out->num_instances * sizeof(clvr_instance),
                                      out->host_instances, 0, NULL, NULL));
    {
        /* The device scans count in 32 bits: a wrapped total shows up here. */
        uint64_t sum_v = 0;
        for (uint64_t i = 0; i < out->num_instances; ++i) sum_v += out->host_instances[i].num_vertices;
        if (sum_v != out->num_vertices) {
            s = clvr_error_set(err, CLVR_ERR_OVERFLOW,
                               "preprocess: the clustered mesh would hold %llu vertices; at most 2^32 - 1 are "
                               "addressable (clvr_instance.first_vertex)", (unsigned long long)sum_v);
            goto cleanup;
        }
    }
    clvr_clustered_fill_stats(out, m);
    /* One piece: the whole arrays (partition.c splits an assembled result). */
    out->num_pieces = 1;
    out->piece_vertices[1] = out->num_vertices;
    out->piece_idx16[1] = out->num_idx16;
    out->piece_idx32[1] = out->num_idx32;
    out->piece_elements[1] = out->num_elements;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, 16, NULL, "piece placeholder", &out->piece_dummy, err));

cleanup:
    clvr_cl_release(cl, &pos);
    clvr_cl_release(cl, &scal);
    ws_drop(cl, ws, &idx_in);
    ws_drop(cl, ws, &vmap);
    ws_drop(cl, ws, &keys);
    ws_drop(cl, ws, &vals);
    ws_drop(cl, ws, &keys_tmp);
    ws_drop(cl, ws, &vals_tmp);
    ws_drop(cl, ws, &idx_sorted);
    ws_drop(cl, ws, &tk);
    clvr_cl_release(cl, &segbuf);
    free(segs);
    clvr_cl_release(cl, &recs);
    clvr_cl_release(cl, &rec_counts);
    clvr_cl_release(cl, &flags);
    clvr_cl_release(cl, &sel);
    clvr_cl_release(cl, &nverts);
    clvr_cl_release(cl, &nleaves);
    clvr_cl_release(cl, &vsrc);
    clvr_pp_destroy(&pp);
    if (s != CLVR_OK) clvr_clustered_release(cl, out);
    else out->wall_s = wall_now() - t_start;
    return s;
}

/* ------------------------------------------------------------ download */

void clvr_clustered_host_free(clvr_clustered_host *h)
{
    if (!h) return;
    free(h->vertices);
    free(h->idx16);
    free(h->idx32);
    free(h->instances);
    free(h->leaf_boxes);
    free(h->sampling);
    free(h->order);
    memset(h, 0, sizeof *h);
}

static clvr_status read_array(clvr_cl *cl, cl_mem b, uint64_t bytes, void **out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    *out = malloc(bytes ? bytes : 1);
    if (!*out) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory downloading %llu bytes",
                                     (unsigned long long)bytes);
    if (bytes && b) CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, b, CL_TRUE, 0, bytes, *out, 0, NULL, NULL));
cleanup:
    return s;
}

void clvr_clustered_get_pieces(const clvr_clustered *c, clvr_clustered_pieces *out)
{
    const cl_mem dummy = c->piece_dummy ? c->piece_dummy : c->instances;
    out->vertices[0] = c->vertices;
    out->idx16[0] = c->idx16;
    out->idx32[0] = c->idx32;
    for (uint32_t p = 1; p < CLVR_MAX_SPLITS; ++p) {
        out->vertices[p] = c->vertices_more[p - 1] ? c->vertices_more[p - 1] : dummy;
        out->idx16[p] = c->idx16_more[p - 1] ? c->idx16_more[p - 1] : dummy;
        out->idx32[p] = c->idx32_more[p - 1] ? c->idx32_more[p - 1] : dummy;
    }
}

/* Reads a split array back whole: piece p's `prefix[p + 1] - prefix[p]`
 * entries of `size` bytes from bufs[p] into their place. */
static clvr_status read_pieces(clvr_cl *cl, const cl_mem *bufs, const uint64_t *prefix, uint32_t pieces,
                               uint64_t size, void **out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const uint64_t bytes = prefix[pieces] * size;
    *out = malloc(bytes ? bytes : 1);
    if (!*out) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory downloading %llu bytes",
                                     (unsigned long long)bytes);
    for (uint32_t p = 0; p < pieces; ++p) {
        const uint64_t n = (prefix[p + 1] - prefix[p]) * size;
        if (n) CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, bufs[p], CL_TRUE, 0, n, (char *)*out + prefix[p] * size,
                                                 0, NULL, NULL));
    }
cleanup:
    return s;
}

clvr_status clvr_clustered_download(clvr_cl *cl, const clvr_clustered *c, clvr_clustered_host *h, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    memset(h, 0, sizeof *h);
    if (c->num_pieces > 1) {
        clvr_clustered_pieces pc;
        clvr_clustered_get_pieces(c, &pc);
        CLVR_TRY(read_pieces(cl, pc.vertices, c->piece_vertices, c->num_pieces, 16, (void **)&h->vertices, err));
        CLVR_TRY(read_pieces(cl, pc.idx16, c->piece_idx16, c->num_pieces, 2, (void **)&h->idx16, err));
        CLVR_TRY(read_pieces(cl, pc.idx32, c->piece_idx32, c->num_pieces, 4, (void **)&h->idx32, err));
    } else {
        CLVR_TRY(read_array(cl, c->vertices, c->num_vertices * 16, (void **)&h->vertices, err));
        CLVR_TRY(read_array(cl, c->idx16, c->num_idx16 * 2, (void **)&h->idx16, err));
        CLVR_TRY(read_array(cl, c->idx32, c->num_idx32 * 4, (void **)&h->idx32, err));
    }
    CLVR_TRY(read_array(cl, c->instances, c->num_instances * sizeof(clvr_instance), (void **)&h->instances, err));
    for (uint64_t i = 0; c->num_pieces > 1 && i < c->num_instances; ++i) { /* offsets in the whole arrays */
        clvr_instance *in = &h->instances[i];
        const uint32_t p = in->piece < c->num_pieces ? in->piece : 0;
        in->first_vertex += (uint32_t)c->piece_vertices[p];
        in->first_index += in->index_bits == 16 ? c->piece_idx16[p] : c->piece_idx32[p];
        in->piece = 0;
        in->piece_first_element = 0;
    }
    CLVR_TRY(read_array(cl, c->leaf_boxes, c->num_leaves * sizeof(clvr_box), (void **)&h->leaf_boxes, err));
    CLVR_TRY(read_array(cl, c->sampling, c->num_sampling * sizeof(clvr_sampling_cluster), (void **)&h->sampling, err));
    if (c->order) CLVR_TRY(read_array(cl, c->order, c->num_elements * 4, (void **)&h->order, err));
cleanup:
    if (s != CLVR_OK) clvr_clustered_host_free(h);
    return s;
}
