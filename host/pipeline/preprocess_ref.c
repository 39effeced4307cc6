/* preprocess_ref.c: plain-C references of every preprocessing kernel and of
 * the whole pipeline, with the contracts of preprocess.h. The shared helpers
 * (kernels/sfc.h, bounds.h, reindex.h) are the very code the kernels run;
 * the loops around them are written here once more, sequentially, so tests
 * compare the device's results bit for bit. */
#include "preprocess_stages.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bounds.h"
#include "reindex.h"

void clvr_pp_ref_bounds(const float *pos, const float *scal, uint64_t n, clvr_box *out)
{
    float lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < n; ++i) {
        clvr_pp_box_grow(lo, hi, pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
        lo[3] = scal[i] < lo[3] ? scal[i] : lo[3];
        hi[3] = scal[i] > hi[3] ? scal[i] : hi[3];
    }
    memcpy(out->lo, lo, sizeof lo);
    memcpy(out->hi, hi, sizeof hi);
}

void clvr_pp_ref_keys(const float *pos, const uint32_t *idx, const clvr_pp_layout *l, const clvr_box *b, int morton,
                      int one_curve, uint64_t *keys, uint32_t *vals)
{
    const float scale = clvr_pp_scale(b);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t vpe = clvr_cell_vertex_count(t);
        for (uint64_t e = 0; e < l->count[t]; ++e) {
            float lo[3], hi[3];
            clvr_pp_element_box(pos, idx + l->slot[t] + e * vpe, vpe, lo, hi);
            keys[l->first[t] + e] = clvr_pp_element_key(one_curve ? CLVR_CELL_HEX : t, lo, hi, b->lo, scale, morton);
            vals[l->first[t] + e] = (uint32_t)(l->first[t] + e);
        }
    }
}

void clvr_pp_ref_gather_collapse(const uint32_t *order, const uint32_t *idx_in, const clvr_pp_layout *l,
                                 uint64_t n, uint32_t *idx_hex)
{
    for (uint64_t i = 0; i < n; ++i) {
        const uint32_t g = order[i], t = clvr_pp_type_of(g, l->first[1], l->first[2], l->first[3]);
        const uint32_t nv = clvr_cell_vertex_count(t);
        clvr_hex_collapse_ids(t, idx_in + l->slot[t] + (uint64_t)(g - l->first[t]) * nv, idx_hex + 8 * i);
    }
}

uint32_t clvr_pp_ref_scan(const uint32_t *in, uint32_t *out, uint64_t n)
{
    uint32_t acc = 0;
    for (uint64_t i = 0; i < n; ++i) {
        uint32_t v = in[i];
        out[i] = acc;
        acc += v;
    }
    return acc;
}

uint32_t clvr_pp_ref_select(const uint32_t *flags, const uint32_t *values, uint32_t *out, uint64_t n)
{
    uint32_t k = 0;
    for (uint64_t i = 0; i < n; ++i)
        if (flags[i]) out[k++] = values ? values[i] : (uint32_t)i;
    return k;
}

int clvr_pp_ref_sort(uint64_t *keys, uint32_t *vals, uint64_t n)
{
    uint64_t *k2 = malloc((n ? n : 1) * sizeof *k2);
    uint32_t *v2 = malloc((n ? n : 1) * sizeof *v2);
    if (!k2 || !v2) { free(k2); free(v2); return 1; }
    uint64_t *ks = keys, *kd = k2;
    uint32_t *vs = vals, *vd = v2;
    for (uint32_t shift = 0; shift < 64; shift += 8) {
        uint64_t cnt[257] = {0};
        for (uint64_t i = 0; i < n; ++i) ++cnt[((ks[i] >> shift) & 255) + 1];
        if (n && cnt[((ks[0] >> shift) & 255) + 1] == n) continue;
        for (int d = 0; d < 256; ++d) cnt[d + 1] += cnt[d];
        for (uint64_t i = 0; i < n; ++i) {
            uint64_t p = cnt[(ks[i] >> shift) & 255]++;
            kd[p] = ks[i];
            vd[p] = vs[i];
        }
        uint64_t *tk = ks; ks = kd; kd = tk;
        uint32_t *tv = vs; vs = vd; vd = tv;
    }
    if (ks != keys) {
        memcpy(keys, ks, n * sizeof *keys);
        memcpy(vals, vs, n * sizeof *vals);
    }
    free(k2);
    free(v2);
    return 0;
}

clvr_status clvr_pp_ref_preprocess(const clvr_mesh *m, const clvr_preprocess_options *o, uint32_t compute_units,
                                   clvr_clustered *out, clvr_clustered_host *h, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_preprocess_options opt;
    clvr_pp_layout L, LI;
    clvr_pp_split_plan plan;
    uint32_t *idx_in = NULL, *idx_sorted = NULL, *vmap = NULL, *order = NULL;
    uint64_t *keys = NULL, *tk = NULL, *vsrc = NULL;
    clvr_pp_instance_rec *recs = NULL;
    memset(out, 0, sizeof *out);
    memset(h, 0, sizeof *h);
    CLVR_TRY(clvr_pp_options_resolve(o, &opt, err));
    /* LI: the input's layout; L: the sorted one (all hexes with one curve, clvr_preprocess's LS). */
    clvr_pp_layout_make(&LI, m->num_cells);
    const int one_curve = clvr_pp_sorted_layout(&opt, &LI, &L);
    clvr_pp_split_plan_make(&plan, &L, &opt, compute_units, m->num_vertices);
    const uint64_t N = L.num_elements, S = L.num_slots, S_in = LI.num_slots, V = m->num_vertices;
    const int bits32 = opt.index_bits == 32;
    out->leaf_size = opt.leaf_size;
    out->sampling_size = opt.sampling_size;
    out->index_bits = opt.index_bits;
    out->morton = opt.morton;
    out->num_elements = N;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) { out->num_cells[t] = L.count[t]; out->first_cell[t] = L.first[t]; }
    for (uint32_t t = 0; one_curve && t < CLVR_CELL_HEX; ++t) out->collapsed[t] = LI.count[t];

    idx_in = malloc((S_in ? S_in : 1) * 4);
    idx_sorted = malloc((S ? S : 1) * 4);
    vmap = malloc((S ? S : 1) * 4);
    order = malloc((N ? N : 1) * 4);
    keys = malloc((N ? N : 1) * 8);
    if (!idx_in || !idx_sorted || !vmap || !order || !keys) goto oom;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        if (LI.count[t]) memcpy(idx_in + LI.slot[t], m->indices[t], LI.count[t] * clvr_cell_vertex_count(t) * 4);

    clvr_pp_ref_bounds(m->positions, m->scalars, V, &out->bounds);
    out->scalar_min = out->bounds.lo[3];
    out->scalar_max = out->bounds.hi[3];
    clvr_pp_ref_keys(m->positions, idx_in, &LI, clvr_pp_quantize_box(&opt, &out->bounds), opt.morton, one_curve, keys,
                     order);
    if (clvr_pp_ref_sort(keys, order, N)) goto oom;

    /* gather */
    if (one_curve) clvr_pp_ref_gather_collapse(order, idx_in, &LI, N, idx_sorted);
    for (uint64_t i = 0; i < N && !one_curve; ++i) {
        uint32_t t = clvr_pp_type_of(i, L.first[1], L.first[2], L.first[3]);
        uint32_t vpe = clvr_cell_vertex_count(t);
        memcpy(idx_sorted + L.slot[t] + (i - L.first[t]) * vpe, idx_in + L.slot[t] + (order[i] - L.first[t]) * vpe,
               vpe * 4);
    }

    /* sampling clusters */
    {
        uint64_t nc = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) nc += (L.count[t] + opt.sampling_size - 1) / opt.sampling_size;
        out->num_sampling = nc;
        h->sampling = malloc((nc ? nc : 1) * sizeof *h->sampling);
        if (!h->sampling) goto oom;
        uint64_t c = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            uint32_t vpe = clvr_cell_vertex_count(t);
            for (uint64_t e0 = 0; e0 < L.count[t]; e0 += opt.sampling_size, ++c) {
                uint64_t e1 = e0 + opt.sampling_size < L.count[t] ? e0 + opt.sampling_size : L.count[t];
                float lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
                float hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
                for (uint64_t e = e0; e < e1; ++e)
                    for (uint32_t k = 0; k < vpe; ++k) {
                        uint64_t v = idx_sorted[L.slot[t] + e * vpe + k];
                        const float *p = m->positions + 3 * v;
                        clvr_pp_box_grow(lo, hi, p[0], p[1], p[2]);
                        float sc = m->scalars[v];
                        lo[3] = sc < lo[3] ? sc : lo[3];
                        hi[3] = sc > hi[3] ? sc : hi[3];
                    }
                memcpy(h->sampling[c].lo, lo, sizeof lo);
                memcpy(h->sampling[c].hi, hi, sizeof hi);
            }
        }
    }

    /* greedy split, one segment after the other with one table */
    out->num_idx16 = bits32 ? 0 : S;
    out->num_idx32 = bits32 ? S : 0;
    h->idx16 = malloc((out->num_idx16 ? out->num_idx16 : 1) * 2);
    h->idx32 = malloc((out->num_idx32 ? out->num_idx32 : 1) * 4);
    tk = calloc((size_t)1 << plan.log2cap, sizeof *tk); /* the split leaves the map empty again */
    uint64_t nslots = (uint64_t)plan.total_segments * plan.rec_max;
    recs = malloc((nslots ? nslots : 1) * sizeof *recs);
    if (!h->idx16 || !h->idx32 || !tk || !recs) goto oom;
    uint64_t ninst = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        for (uint32_t sg = 0; sg < plan.nseg[t]; ++sg) {
            uint64_t b = (uint64_t)sg * plan.seg_len[t], e = b + plan.seg_len[t] < L.count[t] ? b + plan.seg_len[t] : L.count[t];
            uint32_t nr = clvr_pp_split_segment(idx_sorted, vmap, h->idx16, h->idx32, bits32, t, (uint32_t)L.first[t],
                                                L.slot[t], (uint32_t)b, (uint32_t)e, plan.vlimit, plan.max_elems, tk,
                                                plan.log2cap, recs + ninst, plan.rec_max);
            if (nr > plan.rec_max) {
                s = clvr_error_set(err, CLVR_ERR_INTERNAL, "preprocess reference: %u records exceed the bound %u", nr,
                                   plan.rec_max);
                goto cleanup;
            }
            ninst += nr;
        }
    out->num_instances = ninst;
    h->instances = malloc((ninst ? ninst : 1) * sizeof *h->instances);
    vsrc = malloc((ninst ? ninst : 1) * sizeof *vsrc);
    if (!h->instances || !vsrc) goto oom;
    uint64_t fv = 0, fl = 0;
    for (uint64_t i = 0; i < ninst; ++i) {
        const clvr_pp_instance_rec *r = &recs[i];
        clvr_instance *c = &h->instances[i];
        memset(c, 0, sizeof *c);
        c->type = r->type;
        c->index_bits = bits32 ? 32 : 16;
        c->first_element = r->first_element;
        c->num_elements = r->num_elements;
        c->first_vertex = (uint32_t)fv;
        c->num_vertices = r->num_vertices;
        c->first_index = L.slot[r->type] + (uint64_t)(r->first_element - L.first[r->type]) * clvr_cell_vertex_count(r->type);
        c->first_leaf = (uint32_t)fl;
        c->num_leaves = (r->num_elements + opt.leaf_size - 1) / opt.leaf_size;
        c->bvh_root = CLVR_PP_NO_ROOT;
        vsrc[i] = r->vsrc;
        fv += r->num_vertices;
        fl += c->num_leaves;
    }
    out->num_vertices = fv;
    out->num_leaves = fl;

    /* vertices */
    h->vertices = malloc((fv ? fv : 1) * 16);
    h->leaf_boxes = malloc((fl ? fl : 1) * sizeof *h->leaf_boxes);
    if (!h->vertices || !h->leaf_boxes) goto oom;
    for (uint64_t i = 0; i < ninst; ++i) {
        const clvr_instance *c = &h->instances[i];
        for (uint32_t j = 0; j < c->num_vertices; ++j) {
            uint64_t v = vmap[vsrc[i] + j];
            float *d = h->vertices + 4 * ((uint64_t)c->first_vertex + j);
            d[0] = m->positions[3 * v];
            d[1] = m->positions[3 * v + 1];
            d[2] = m->positions[3 * v + 2];
            d[3] = m->scalars[v];
        }
    }
    /* leaf boxes and instance bounds */
    for (uint64_t i = 0; i < ninst; ++i) {
        clvr_instance *c = &h->instances[i];
        uint32_t vpe = clvr_cell_vertex_count(c->type);
        float ilo[3] = {INFINITY, INFINITY, INFINITY}, ihi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t l = 0; l < c->num_leaves; ++l) {
            uint32_t e0 = c->first_element + l * opt.leaf_size;
            uint32_t e1 = e0 + opt.leaf_size < c->first_element + c->num_elements ? e0 + opt.leaf_size
                                                                                  : c->first_element + c->num_elements;
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            /* Element box first, then the leaf's: the device's order of
             * comparisons (clvr_pp_leaf_boxes), so ties of -0 and +0 resolve
             * alike. */
            for (uint32_t e = e0; e < e1; ++e) {
                uint64_t sl = c->first_index + (uint64_t)(e - c->first_element) * vpe;
                float elo[3] = {INFINITY, INFINITY, INFINITY}, ehi[3] = {-INFINITY, -INFINITY, -INFINITY};
                for (uint32_t k = 0; k < vpe; ++k) {
                    uint32_t li = c->index_bits == 16 ? h->idx16[sl + k] : h->idx32[sl + k];
                    const float *v = h->vertices + 4 * ((uint64_t)c->first_vertex + li);
                    if (k == 0)
                        for (int a = 0; a < 3; ++a) elo[a] = ehi[a] = v[a];
                    else
                        clvr_pp_box_grow(elo, ehi, v[0], v[1], v[2]);
                }
                for (int a = 0; a < 3; ++a) {
                    lo[a] = elo[a] < lo[a] ? elo[a] : lo[a];
                    hi[a] = ehi[a] > hi[a] ? ehi[a] : hi[a];
                }
            }
            clvr_box *bx = &h->leaf_boxes[c->first_leaf + l];
            for (int k = 0; k < 3; ++k) { bx->lo[k] = lo[k]; bx->hi[k] = hi[k]; }
            bx->lo[3] = bx->hi[3] = 0.0f;
            clvr_pp_box_grow(ilo, ihi, lo[0], lo[1], lo[2]);
            clvr_pp_box_grow(ilo, ihi, hi[0], hi[1], hi[2]);
        }
        for (int k = 0; k < 3; ++k) { c->bounds.lo[k] = ilo[k]; c->bounds.hi[k] = ihi[k]; }
        c->bounds.lo[3] = c->bounds.hi[3] = 0.0f;
    }
    out->host_instances = malloc((ninst ? ninst : 1) * sizeof *out->host_instances);
    if (!out->host_instances) goto oom;
    memcpy(out->host_instances, h->instances, ninst * sizeof *h->instances);
    if (opt.keep_order) { h->order = order; order = NULL; }
    goto cleanup;
oom:
    s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "preprocess reference: out of host memory");
cleanup:
    free(idx_in);
    free(idx_sorted);
    free(vmap);
    free(order);
    free(keys);
    free(tk);
    free(vsrc);
    free(recs);
    if (s != CLVR_OK) {
        clvr_clustered_host_free(h);
        free(out->host_instances);
        memset(out, 0, sizeof *out);
    }
    return s;
}
