/* Proves the whole preprocessing on meshes built here (hex grid, tet grid,
 * a mixed mesh of all four types, random elements over a large vertex pool,
 * a shuffled hex grid) and on every tests/data mesh clvr loads:
 * - the device result equals the plain-C reference pipeline bit for bit
 *   (every array), for leaf sizes 1, 4, 8, 16, 32, Morton and 32-bit modes;
 * - every element exists exactly once: `order` is a permutation and each
 *   sorted element's fetched vertices (position and scalar) equal its
 *   original's, and the multiset of elements compared by coordinates equals
 *   the input's (without using `order`);
 * - instances tile the sorted elements by type, reference < 2^16 vertices
 *   with 16-bit indices, local indices stay inside their instance, leaf and
 *   sampling clusters cover their elements;
 * - a scalar interpolated at random points inside random elements is
 *   bit-identical before and after re-indexing;
 * - curve order makes leaf boxes far smaller than the input order does.
 * --big: a 216^3 hex grid (10,077,696 elements) end to end. */
#include <time.h>

#include "mesh_io.h"
#include "partition.h"
#include "preprocess_stages.h"
#include "test_util.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------ meshes */

static float field(float x, float y, float z) { return sinf(3.0f * x) * cosf(2.0f * y) + z * z; }

static void set_vertex(clvr_mesh *m, uint64_t v, float x, float y, float z)
{
    m->positions[3 * v] = x;
    m->positions[3 * v + 1] = y;
    m->positions[3 * v + 2] = z;
    m->scalars[v] = field(x, y, z);
}

/* Grid vertices (nx+1)(ny+1)(nz+1); cube (i,j,k) split by `mode`:
 * 0 hex, 1 six tets, 2 two wedges, 3 mixed by x quarter (hex, wedges, pyramids around an extra centre vertex, tets). */
static uint32_t gv(uint32_t i, uint32_t j, uint32_t k, uint32_t nx, uint32_t ny)
{
    return (k * (ny + 1) + j) * (nx + 1) + i;
}

static int cube_kind(int mode, uint32_t i, uint32_t nx)
{
    if (mode != 3) return mode == 0 ? 3 : mode == 1 ? 0 : 2;
    uint32_t q = 4 * i / nx;
    return q == 0 ? 3 : q == 1 ? 2 : q == 2 ? 1 : 0;
}

static clvr_status make_grid(clvr_mesh *m, uint32_t nx, uint32_t ny, uint32_t nz, int mode, clvr_error *err)
{
    uint64_t cells[4] = {0, 0, 0, 0}, gvn = (uint64_t)(nx + 1) * (ny + 1) * (nz + 1), extra = 0;
    for (uint32_t i = 0; i < nx; ++i) {
        int kind = cube_kind(mode, i, nx);
        uint64_t per = (uint64_t)ny * nz;
        if (kind == 3) cells[3] += per;
        else if (kind == 2) cells[2] += 2 * per;
        else if (kind == 1) { cells[1] += 6 * per; extra += per; }
        else cells[0] += 6 * per;
    }
    clvr_status s = clvr_mesh_alloc(m, gvn + extra, cells, err);
    if (s != CLVR_OK) return s;
    for (uint32_t k = 0; k <= nz; ++k)
        for (uint32_t j = 0; j <= ny; ++j)
            for (uint32_t i = 0; i <= nx; ++i)
                set_vertex(m, gv(i, j, k, nx, ny), (float)i / nx, 0.7f * (float)j / ny, 1.3f * (float)k / nz);
    uint64_t c[4] = {0, 0, 0, 0}, ev = gvn;
    static const int tets[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
    static const int faces[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1}, {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}};
    for (uint32_t k = 0; k < nz; ++k)
        for (uint32_t j = 0; j < ny; ++j)
            for (uint32_t i = 0; i < nx; ++i) {
                uint32_t h[8] = {gv(i, j, k, nx, ny),         gv(i + 1, j, k, nx, ny),     gv(i + 1, j + 1, k, nx, ny),
                                 gv(i, j + 1, k, nx, ny),     gv(i, j, k + 1, nx, ny),     gv(i + 1, j, k + 1, nx, ny),
                                 gv(i + 1, j + 1, k + 1, nx, ny), gv(i, j + 1, k + 1, nx, ny)};
                int kind = cube_kind(mode, i, nx);
                if (kind == 3) {
                    memcpy(m->indices[3] + 8 * c[3]++, h, sizeof h);
                } else if (kind == 2) {
                    uint32_t w0[6] = {h[0], h[1], h[2], h[4], h[5], h[6]}, w1[6] = {h[0], h[2], h[3], h[4], h[6], h[7]};
                    memcpy(m->indices[2] + 6 * c[2]++, w0, sizeof w0);
                    memcpy(m->indices[2] + 6 * c[2]++, w1, sizeof w1);
                } else if (kind == 1) {
                    set_vertex(m, ev, ((float)i + 0.5f) / nx, 0.7f * ((float)j + 0.5f) / ny, 1.3f * ((float)k + 0.5f) / nz);
                    for (int f = 0; f < 6; ++f) {
                        uint32_t *p = m->indices[1] + 5 * c[1]++;
                        for (int q = 0; q < 4; ++q) p[q] = h[faces[f][q]];
                        p[4] = (uint32_t)ev;
                    }
                    ++ev;
                } else {
                    for (int t = 0; t < 6; ++t) {
                        uint32_t *p = m->indices[0] + 4 * c[0]++;
                        for (int q = 0; q < 4; ++q) p[q] = h[tets[t][q]];
                    }
                }
            }
    clvr_mesh_update_ranges(m);
    return CLVR_OK;
}

/* Random elements over a big random vertex pool: no locality at all, so
 * instances fill up to the 2^16 vertex limit quickly. */
static clvr_status make_random(clvr_mesh *m, uint64_t nv, uint64_t ne, uint64_t *rng, clvr_error *err)
{
    uint64_t cells[4] = {ne / 2, ne / 8, ne / 8, ne - ne / 2 - ne / 4};
    clvr_status s = clvr_mesh_alloc(m, nv, cells, err);
    if (s != CLVR_OK) return s;
    for (uint64_t v = 0; v < nv; ++v) set_vertex(m, v, tu_randf(rng), tu_randf(rng), tu_randf(rng));
    for (uint32_t t = 0; t < 4; ++t)
        for (uint64_t i = 0; i < cells[t] * clvr_cell_vertex_count(t); ++i) m->indices[t][i] = (uint32_t)(tu_rand(rng) % nv);
    clvr_mesh_update_ranges(m);
    return CLVR_OK;
}

/* Shuffles the elements of each type (Fisher-Yates). */
static void shuffle(clvr_mesh *m, uint64_t *rng)
{
    for (uint32_t t = 0; t < 4; ++t) {
        uint32_t vpe = clvr_cell_vertex_count(t), tmp[8];
        for (uint64_t i = m->num_cells[t]; i > 1; --i) {
            uint64_t j = tu_rand(rng) % i;
            memcpy(tmp, m->indices[t] + (i - 1) * vpe, vpe * 4);
            memcpy(m->indices[t] + (i - 1) * vpe, m->indices[t] + j * vpe, vpe * 4);
            memcpy(m->indices[t] + j * vpe, tmp, vpe * 4);
        }
    }
}

/* ------------------------------------------------------------ checks */

/* Original element g (global id over the concatenated lists) and its type/vpe. */
static const uint32_t *orig_element(const clvr_mesh *m, uint64_t g, uint32_t *type)
{
    uint64_t base = 0;
    for (uint32_t t = 0; t < 4; ++t) {
        if (g < base + m->num_cells[t]) { *type = t; return m->indices[t] + (g - base) * clvr_cell_vertex_count(t); }
        base += m->num_cells[t];
    }
    *type = 4;
    return NULL;
}

/* Instance holding sorted element e (binary search). */
static const clvr_instance *find_instance(const clvr_clustered *c, const clvr_clustered_host *h, uint64_t e)
{
    uint64_t a = 0, b = c->num_instances;
    while (b - a > 1) {
        uint64_t mid = (a + b) / 2;
        if (h->instances[mid].first_element <= e) a = mid;
        else b = mid;
    }
    return &h->instances[a];
}

/* Fetches the float4 vertices of sorted element e from the clustered arrays. */
static uint32_t fetch(const clvr_clustered *c, const clvr_clustered_host *h, uint64_t e, float out[8][4])
{
    const clvr_instance *in = find_instance(c, h, e);
    uint32_t vpe = clvr_cell_vertex_count(in->type);
    uint64_t s = in->first_index + (e - in->first_element) * vpe;
    for (uint32_t k = 0; k < vpe; ++k) {
        uint32_t li = in->index_bits == 16 ? h->idx16[s + k] : h->idx32[s + k];
        memcpy(out[k], h->vertices + 4 * ((uint64_t)in->first_vertex + li), 16);
    }
    return vpe;
}

/* Random interpolation weights: trilinear for hexes, normalized random otherwise. */
static void weights(uint32_t vpe, uint64_t *rng, float *w)
{
    if (vpe == 8) {
        float u = tu_randf(rng), v = tu_randf(rng), t = tu_randf(rng);
        float a[2] = {1 - u, u}, b[2] = {1 - v, v}, cz[2] = {1 - t, t};
        static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
        for (int k = 0; k < 8; ++k) w[k] = a[corner[k][0]] * b[corner[k][1]] * cz[corner[k][2]];
        return;
    }
    float sum = 0;
    for (uint32_t k = 0; k < vpe; ++k) sum += w[k] = tu_randf(rng) + 1e-3f;
    for (uint32_t k = 0; k < vpe; ++k) w[k] /= sum;
}

static int cmp_sig(const void *a, const void *b)
{
    return memcmp(a, b, 8 * 4 * 4 + 4);
}

/* Element signature: type then vpe float4 (x y z scalar), zero padded. */
typedef struct sig { uint32_t type; float v[8][4]; } sig;

static void check_clustered(const char *name, const clvr_mesh *m, const clvr_clustered *c, const clvr_clustered_host *h,
                            int full_multiset)
{
    const uint64_t N = clvr_mesh_num_elements(m);
    uint64_t fails = 0;
    TU_CHECK_EQ_U64(c->num_elements, N);
    /* instances tile the sorted elements, one type each, offsets are prefix sums */
    uint64_t e = 0, fv = 0, fl = 0, bad_inst = 0, over16 = 0, bad_local = 0;
    for (uint64_t i = 0; i < c->num_instances; ++i) {
        const clvr_instance *in = &h->instances[i];
        uint32_t t = in->type;
        bad_inst += in->first_element != e || in->num_elements == 0 || t > 3 || in->first_vertex != fv ||
                    in->first_leaf != fl || in->num_leaves != (in->num_elements + c->leaf_size - 1) / c->leaf_size;
        if (t <= 3)
            bad_inst += in->first_element < c->first_cell[t] ||
                        in->first_element + in->num_elements > c->first_cell[t] + c->num_cells[t];
        if (in->index_bits == 16) over16 += in->num_vertices >= CLVR_INSTANCE_MAX_VERTS16;
        else bad_inst += in->index_bits != 32;
        uint64_t nidx = (uint64_t)in->num_elements * clvr_cell_vertex_count(t < 4 ? t : 0);
        for (uint64_t k = 0; k < nidx; ++k) {
            uint32_t li = in->index_bits == 16 ? h->idx16[in->first_index + k] : h->idx32[in->first_index + k];
            bad_local += li >= in->num_vertices;
        }
        e += in->num_elements;
        fv += in->num_vertices;
        fl += in->num_leaves;
    }
    TU_CHECK_EQ_U64(bad_inst, 0);
    TU_CHECK_EQ_U64(over16, 0);
    TU_CHECK_EQ_U64(bad_local, 0);
    TU_CHECK_EQ_U64(e, N);
    TU_CHECK_EQ_U64(fv, c->num_vertices);
    TU_CHECK_EQ_U64(fl, c->num_leaves);
    uint64_t slots = 0; /* of m: the hex view's with one curve */
    for (uint32_t t = 0; t < 4; ++t) slots += m->num_cells[t] * clvr_cell_vertex_count(t);
    if (c->index_bits == 16 && c->bytes_indices_before) /* 0: a reference result, no stats */
        TU_CHECK_EQ_U64(c->bytes_indices_after * 2, slots * 4);

    /* order is a permutation; sorted elements equal their originals, vertex by vertex */
    if (h->order) {
        unsigned char *seen = calloc(N ? N : 1, 1);
        uint64_t bad_perm = 0, bad_elem = 0, bad_type = 0;
        for (uint64_t i = 0; i < N; ++i) {
            uint32_t g = h->order[i];
            if (g >= N || seen[g]++) { ++bad_perm; continue; }
            uint32_t t;
            const uint32_t *oi = orig_element(m, g, &t);
            float v[8][4];
            uint32_t vpe = fetch(c, h, i, v);
            bad_type += find_instance(c, h, i)->type != t;
            for (uint32_t k = 0; k < vpe; ++k) {
                float o[4] = {m->positions[3 * (uint64_t)oi[k]], m->positions[3 * (uint64_t)oi[k] + 1],
                              m->positions[3 * (uint64_t)oi[k] + 2], m->scalars[oi[k]]};
                bad_elem += memcmp(o, v[k], 16) != 0;
            }
        }
        TU_CHECK_EQ_U64(bad_perm, 0);
        TU_CHECK_EQ_U64(bad_type, 0);
        TU_CHECK_EQ_U64(bad_elem, 0);
        free(seen);

        /* interpolation at random points inside random elements: bit-identical */
        uint64_t rng = 99, bad_interp = 0;
        for (int r = 0; r < 20000 && N; ++r) {
            uint64_t i = tu_rand(&rng) % N;
            uint32_t t;
            const uint32_t *oi = orig_element(m, h->order[i], &t);
            float v[8][4], w[8];
            uint32_t vpe = fetch(c, h, i, v);
            weights(vpe, &rng, w);
            float p0[4] = {0, 0, 0, 0}, p1[4] = {0, 0, 0, 0};
            for (uint32_t k = 0; k < vpe; ++k) {
                const float *op = m->positions + 3 * (uint64_t)oi[k];
                p0[0] += w[k] * op[0]; p0[1] += w[k] * op[1]; p0[2] += w[k] * op[2]; p0[3] += w[k] * m->scalars[oi[k]];
                p1[0] += w[k] * v[k][0]; p1[1] += w[k] * v[k][1]; p1[2] += w[k] * v[k][2]; p1[3] += w[k] * v[k][3];
            }
            bad_interp += memcmp(p0, p1, sizeof p0) != 0;
        }
        TU_CHECK_EQ_U64(bad_interp, 0);
    }

    /* multiset of elements by coordinates, independent of `order` */
    if (full_multiset && N) {
        sig *a = calloc(N, sizeof *a), *b = calloc(N, sizeof *b);
        uint64_t g = 0;
        for (uint32_t t = 0; t < 4; ++t)
            for (uint64_t i = 0; i < m->num_cells[t]; ++i, ++g) {
                a[g].type = t;
                for (uint32_t k = 0; k < clvr_cell_vertex_count(t); ++k) {
                    uint64_t v = m->indices[t][i * clvr_cell_vertex_count(t) + k];
                    memcpy(a[g].v[k], m->positions + 3 * v, 12);
                    a[g].v[k][3] = m->scalars[v];
                }
            }
        for (uint64_t i = 0; i < N; ++i) {
            b[i].type = find_instance(c, h, i)->type;
            fetch(c, h, i, b[i].v);
        }
        qsort(a, N, sizeof *a, cmp_sig);
        qsort(b, N, sizeof *b, cmp_sig);
        TU_CHECK_EQ_U64(memcmp(a, b, N * sizeof *a), 0);
        free(a);
        free(b);
    }

    /* leaf boxes hold their elements; instance bounds hold their leaves; sampling ranges hold their scalars */
    uint64_t bad_box = 0;
    for (uint64_t i = 0; i < c->num_instances; ++i) {
        const clvr_instance *in = &h->instances[i];
        for (uint32_t l = 0; l < in->num_leaves; ++l) {
            const clvr_box *bx = &h->leaf_boxes[in->first_leaf + l];
            for (int k = 0; k < 3; ++k) bad_box += bx->lo[k] < in->bounds.lo[k] || bx->hi[k] > in->bounds.hi[k];
            for (uint32_t q = 0; q < c->leaf_size; ++q) {
                uint64_t el = in->first_element + (uint64_t)l * c->leaf_size + q;
                if (el >= (uint64_t)in->first_element + in->num_elements) break;
                float v[8][4];
                uint32_t vpe = fetch(c, h, el, v);
                for (uint32_t k = 0; k < vpe; ++k)
                    for (int d = 0; d < 3; ++d) bad_box += v[k][d] < bx->lo[d] || v[k][d] > bx->hi[d];
            }
        }
    }
    TU_CHECK_EQ_U64(bad_box, 0);
    uint64_t bad_samp = 0, sc = 0;
    for (uint32_t t = 0; t < 4; ++t)
        for (uint64_t e0 = 0; e0 < c->num_cells[t]; e0 += c->sampling_size, ++sc) {
            const clvr_sampling_cluster *sm = &h->sampling[sc];
            for (uint64_t q = e0; q < e0 + c->sampling_size && q < c->num_cells[t]; ++q) {
                float v[8][4];
                uint32_t vpe = fetch(c, h, c->first_cell[t] + q, v);
                for (uint32_t k = 0; k < vpe; ++k)
                    for (int d = 0; d < 4; ++d) bad_samp += v[k][d] < sm->lo[d] || v[k][d] > sm->hi[d];
            }
        }
    TU_CHECK_EQ_U64(sc, c->num_sampling);
    TU_CHECK_EQ_U64(bad_samp, 0);
    fails = (uint64_t)tu_fail_;
    (void)fails;
    (void)name;
}

static int same_arrays(const clvr_clustered *a, const clvr_clustered_host *ha, const clvr_clustered *b,
                       const clvr_clustered_host *hb)
{
    int bad = 0;
    bad |= a->num_vertices != b->num_vertices || a->num_instances != b->num_instances ||
           a->num_leaves != b->num_leaves || a->num_sampling != b->num_sampling || a->num_idx16 != b->num_idx16 ||
           a->num_idx32 != b->num_idx32;
    if (bad) return 0;
    bad |= memcmp(&a->bounds, &b->bounds, sizeof a->bounds) != 0;
    bad |= memcmp(ha->vertices, hb->vertices, a->num_vertices * 16) != 0;
    bad |= memcmp(ha->idx16, hb->idx16, a->num_idx16 * 2) != 0;
    bad |= memcmp(ha->idx32, hb->idx32, a->num_idx32 * 4) != 0;
    bad |= memcmp(ha->instances, hb->instances, a->num_instances * sizeof(clvr_instance)) != 0;
    bad |= memcmp(ha->leaf_boxes, hb->leaf_boxes, a->num_leaves * sizeof(clvr_box)) != 0;
    bad |= memcmp(ha->sampling, hb->sampling, a->num_sampling * sizeof(clvr_sampling_cluster)) != 0;
    if (ha->order && hb->order) bad |= memcmp(ha->order, hb->order, a->num_elements * 4) != 0;
    return !bad;
}

/* Mean leaf box volume (relative to the mesh box) in curve order vs. in input order. */
static void check_locality(const clvr_mesh *m, const clvr_clustered *c, const clvr_clustered_host *h)
{
    double curve = 0, input = 0, ext = 1;
    for (int k = 0; k < 3; ++k) ext *= (double)(m->bounds_hi[k] - m->bounds_lo[k]);
    for (uint64_t l = 0; l < c->num_leaves; ++l) {
        double v = 1;
        for (int k = 0; k < 3; ++k) v *= (double)(h->leaf_boxes[l].hi[k] - h->leaf_boxes[l].lo[k]);
        curve += v / ext;
    }
    uint64_t nl = 0;
    for (uint32_t t = 0; t < 4; ++t) {
        uint32_t vpe = clvr_cell_vertex_count(t);
        for (uint64_t e0 = 0; e0 < m->num_cells[t]; e0 += c->leaf_size, ++nl) {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (uint64_t e = e0; e < e0 + c->leaf_size && e < m->num_cells[t]; ++e)
                for (uint32_t k = 0; k < vpe; ++k)
                    for (int d = 0; d < 3; ++d) {
                        float x = m->positions[3 * (uint64_t)m->indices[t][e * vpe + k] + d];
                        lo[d] = x < lo[d] ? x : lo[d];
                        hi[d] = x > hi[d] ? x : hi[d];
                    }
            input += (double)(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) / ext;
        }
    }
    printf("  leaf volume: curve order %.3g, input order %.3g (mean fraction of the mesh box)\n",
           curve / (double)c->num_leaves, input / (double)nl);
    TU_CHECK(curve / (double)c->num_leaves * 20 < input / (double)nl);
}

/* m with every cell written as its collapsed hex (clvr_hex_collapse_ids),
 * in m's element order: what preprocessing with one curve must hold. */
static clvr_status hex_view(const clvr_mesh *m, clvr_mesh *out, clvr_error *err)
{
    const uint64_t n = clvr_mesh_num_elements(m), hexes[4] = {0, 0, 0, n};
    clvr_status s = clvr_mesh_alloc(out, m->num_vertices, hexes, err);
    if (s != CLVR_OK) return s;
    memcpy(out->positions, m->positions, m->num_vertices * 12);
    memcpy(out->scalars, m->scalars, m->num_vertices * 4);
    out->scalar_min = m->scalar_min;
    out->scalar_max = m->scalar_max;
    memcpy(out->bounds_lo, m->bounds_lo, sizeof out->bounds_lo);
    memcpy(out->bounds_hi, m->bounds_hi, sizeof out->bounds_hi);
    uint64_t g = 0;
    for (uint32_t t = 0; t < 4; ++t)
        for (uint64_t i = 0; i < m->num_cells[t]; ++i, ++g)
            clvr_hex_collapse_ids(t, m->indices[t] + i * clvr_cell_vertex_count(t), out->indices[3] + 8 * g);
    return CLVR_OK;
}

/* Runs device and reference with these options and checks everything. */
static void run_case(clvr_cl *cl, const char *name, const clvr_mesh *m, const clvr_preprocess_options *o, int ref,
                     int multiset)
{
    clvr_error err = {0};
    clvr_clustered c = {0}, rc = {0};
    clvr_clustered_host h = {0}, rh = {0};
    double t0 = now_s();
    TU_CHECK_STATUS(clvr_preprocess(cl, m, o, &c, &err), CLVR_OK, &err);
    double t1 = now_s();
    if (!c.instances) return;
    TU_CHECK_STATUS(clvr_clustered_download(cl, &c, &h, &err), CLVR_OK, &err);
    printf("%s: leaf %u%s%s: %llu elements -> %llu instances (avg %.0f elements, %.0f vertices), %llu leaves, "
           "%llu sampling; vertices %llu -> %llu; indices %.2f MB -> %.2f MB; %.3f s (build %.3f)\n",
           name, c.leaf_size, c.morton ? " morton" : "", c.index_bits == 32 ? " 32-bit" : "",
           (unsigned long long)c.num_elements, (unsigned long long)c.num_instances, c.avg_instance_elements,
           c.avg_instance_vertices, (unsigned long long)c.num_leaves, (unsigned long long)c.num_sampling,
           (unsigned long long)m->num_vertices, (unsigned long long)c.num_vertices, c.bytes_indices_before / 1e6,
           c.bytes_indices_after / 1e6, t1 - t0, c.build_s);
    if (ref) {
        TU_CHECK_STATUS(clvr_pp_ref_preprocess(m, o, cl->compute_units, &rc, &rh, &err), CLVR_OK, &err);
        int same = same_arrays(&c, &h, &rc, &rh);
        if (!same) fprintf(stderr, "%s: device and reference differ\n", name);
        TU_CHECK(same);
    }
    uint64_t slots = 0;
    for (uint32_t t = 0; t < 4; ++t) slots += m->num_cells[t] * clvr_cell_vertex_count(t);
    clvr_preprocess_options defaults;
    clvr_preprocess_options_default(&defaults);
    TU_CHECK_EQ_U64(c.bytes_indices_before, slots * 4);
    if (clvr_pp_one_curve(o ? o : &defaults, m->num_cells)) {
        /* one curve: the same clustered mesh as the hex view's, whatever the types */
        clvr_mesh mh = {0};
        TU_CHECK_STATUS(hex_view(m, &mh, &err), CLVR_OK, &err);
        TU_CHECK_EQ_U64(c.num_cells[3], c.num_elements);
        check_clustered(name, &mh, &c, &h, multiset);
        clvr_mesh_free(&mh);
    } else {
        for (uint32_t t = 0; t < 4; ++t) TU_CHECK_EQ_U64(c.num_cells[t], m->num_cells[t]);
        check_clustered(name, m, &c, &h, multiset);
    }
    if (o && o->leaf_size == 16 && !o->morton && strstr(name, "shuffled")) check_locality(m, &c, &h);
    clvr_clustered_host_free(&h);
    clvr_clustered_host_free(&rh);
    free(rc.host_instances);
    clvr_clustered_release(cl, &c);
    TU_CHECK_EQ_U64(c.vertices == NULL && c.host_instances == NULL, 1);
}

static void run_all_options(clvr_cl *cl, const char *name, const clvr_mesh *m, int multiset)
{
    clvr_preprocess_options o;
    const uint32_t leaves[] = {16, 1, 4, 8, 32};
    for (size_t i = 0; i < sizeof leaves / sizeof leaves[0]; ++i) {
        clvr_preprocess_options_default(&o);
        o.keep_order = 1;
        o.one_curve = CLVR_ONE_CURVE_OFF; /* one curve per type; one curve below */
        o.leaf_size = leaves[i];
        run_case(cl, name, m, &o, 1, multiset && i == 0);
    }
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    o.one_curve = CLVR_ONE_CURVE_OFF;
    o.morton = 1;
    o.sampling_size = 7;
    run_case(cl, name, m, &o, 1, 0);
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    o.one_curve = CLVR_ONE_CURVE_OFF;
    o.index_bits = 32;
    o.max_instance_elements = 1000;
    run_case(cl, name, m, &o, 1, 0);
    /* tight limits: many small instances */
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    o.one_curve = CLVR_ONE_CURVE_OFF;
    o.max_instance_elements = 37;
    run_case(cl, name, m, &o, 1, 0);
    /* one curve (whatever the types' slots), with leaves of 16 and of 5, 32-bit
     * indices, and tight limits; and the default (auto) */
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    o.one_curve = CLVR_ONE_CURVE_ON;
    run_case(cl, name, m, &o, 1, multiset);
    o.leaf_size = 5;
    o.max_instance_elements = 37;
    run_case(cl, name, m, &o, 1, 0);
    o.leaf_size = 16;
    o.index_bits = 32;
    o.max_instance_elements = 1000;
    run_case(cl, name, m, &o, 1, 0);
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    run_case(cl, name, m, &o, 1, 0);
}

/* clvr_pp_one_curve: auto puts two or more types on one curve while the
 * collapsed hexes take at most 1.5x the types' own index slots; on and off
 * force it; one type never needs it; bad values are refused. */
static void test_one_curve_rule(void)
{
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    TU_CHECK_EQ_U64(o.one_curve, CLVR_ONE_CURVE_AUTO);
    const uint64_t igloo[4] = {60436, 157582, 916, 109470}; /* the OpenFOAM igloo: 1.37x */
    const uint64_t tets_wedges[4] = {900, 0, 100, 0};       /* boundary-layer prisms and tets: 1.90x */
    const uint64_t edge[4] = {1, 0, 0, 1};                  /* 16 slots against 12: 1.33x */
    const uint64_t edge2[4] = {1, 1, 0, 0};                 /* 16 against 9: 1.78x */
    const uint64_t tets[4] = {1000, 0, 0, 0}, none[4] = {0, 0, 0, 0};
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, igloo), 1);
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, tets_wedges), 0);
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, edge), 1);
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, edge2), 0);
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, tets), 0);
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, none), 0);
    o.one_curve = CLVR_ONE_CURVE_ON;
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, tets_wedges), 1);
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, tets), 0);
    o.one_curve = CLVR_ONE_CURVE_OFF;
    TU_CHECK_EQ_U64(clvr_pp_one_curve(&o, igloo), 0);
    clvr_preprocess_options r;
    clvr_error err = {0};
    o.one_curve = 7;
    TU_CHECK_STATUS(clvr_pp_options_resolve(&o, &r, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "one_curve") != NULL);
}

/* A caller-given quantization box (partitions of one mesh sharing one
 * Hilbert grid): the mesh's own bounds give exactly the default result; a
 * larger, off-centre box still gives a valid clustering, the same on the
 * device as in the reference; a box that is not finite is refused. */
static void test_quantize_box(clvr_cl *cl)
{
    clvr_error err = {0};
    clvr_mesh m = {0};
    TU_CHECK_STATUS(make_grid(&m, 24, 10, 10, 3, &err), CLVR_OK, &err);
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    clvr_clustered a = {0}, b = {0};
    clvr_clustered_host ha = {0}, hb = {0};
    TU_CHECK_STATUS(clvr_preprocess(cl, &m, &o, &a, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_clustered_download(cl, &a, &ha, &err), CLVR_OK, &err);
    const clvr_box own = a.bounds;
    o.quantize_box = &own;
    TU_CHECK_STATUS(clvr_preprocess(cl, &m, &o, &b, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_clustered_download(cl, &b, &hb, &err), CLVR_OK, &err);
    TU_CHECK(same_arrays(&a, &ha, &b, &hb));
    clvr_box big = own;
    for (int k = 0; k < 3; ++k) {
        const float ext = own.hi[k] - own.lo[k];
        big.lo[k] = own.lo[k] - 1.7f * ext - 0.25f;
        big.hi[k] = own.hi[k] + 0.9f * ext + 0.5f;
    }
    o.quantize_box = &big;
    run_case(cl, "mixed 24x10x10, larger quantization box", &m, &o, 1, 1);
    clvr_box bad = own;
    bad.lo[1] = NAN;
    o.quantize_box = &bad;
    clvr_clustered c = {0};
    TU_CHECK_STATUS(clvr_preprocess(cl, &m, &o, &c, &err), CLVR_ERR_USAGE, &err);
    clvr_clustered_host_free(&ha);
    clvr_clustered_host_free(&hb);
    clvr_clustered_release(cl, &a);
    clvr_clustered_release(cl, &b);
    clvr_mesh_free(&m);
}

/* A workspace reused across calls (growing, then shrinking meshes; one
 * index list uploaded, one borrowed; results recycled into it) gives
 * exactly what fresh buffers give, and a kept result (its `order` came from
 * the workspace) survives the calls after it. */
static void test_workspace(clvr_cl *cl)
{
    clvr_error err = {0};
    uint64_t rng = 11;
    clvr_mesh ms[3] = {{0}};
    TU_CHECK_STATUS(make_grid(&ms[0], 24, 10, 10, 3, &err), CLVR_OK, &err);  /* mixed: indices uploaded */
    TU_CHECK_STATUS(make_grid(&ms[1], 17, 13, 11, 0, &err), CLVR_OK, &err);  /* hexes only: borrowed */
    TU_CHECK_STATUS(make_random(&ms[2], 300007, 65537, &rng, &err), CLVR_OK, &err);
    const int seq[] = {0, 1, 2, 0, 1};
    const int n = (int)(sizeof seq / sizeof seq[0]);
    const cl_ulong before = cl->allocated_bytes;
    clvr_pp_workspace ws = {0};
    clvr_clustered kept = {0};
    clvr_clustered_host kept_ref = {0};
    for (int i = 0; i < n; ++i) {
        const clvr_mesh *m = &ms[seq[i]];
        clvr_preprocess_options o;
        clvr_preprocess_options_default(&o);
        o.keep_order = i != 2;
        clvr_clustered c = {0}, r = {0};
        clvr_clustered_host h = {0}, rh = {0};
        TU_CHECK_STATUS(clvr_preprocess_ws(cl, m, &o, &ws, &c, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_preprocess(cl, m, &o, &r, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_clustered_download(cl, &c, &h, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_clustered_download(cl, &r, &rh, &err), CLVR_OK, &err);
        TU_CHECK(same_arrays(&c, &h, &r, &rh));
        TU_CHECK((c.order != NULL) == (o.keep_order != 0));
        clvr_clustered_host_free(&h);
        clvr_clustered_release(cl, &r);
        if (i == 0) {
            kept = c;
            kept_ref = rh;
        } else {
            /* Its arrays become the next call's (stale contents: every
             * element must be written again). */
            clvr_pp_workspace_recycle(cl, &ws, &c);
            TU_CHECK(c.vertices == NULL && c.leaf_boxes == NULL && c.instances == NULL);
            clvr_clustered_host_free(&rh);
        }
    }
    /* A result assembled on the host (partitions) lives over host mappings
     * its release unmaps: recycling it must leave the workspace as it was
     * (a buffer kept there would be written over freed memory next call),
     * and the next call still gives fresh buffers' result. */
    {
        clvr_clustered p = {0}, q = {0}, r = {0};
        clvr_clustered_host qh = {0}, rh = {0};
        clvr_mesh mm = ms[0]; /* not consumed: a shallow copy is enough */
        TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, &mm, NULL, 3, 0, 0, &p, NULL, &err), CLVR_OK, &err);
        /* Over host mappings on a CPU device; a GPU's result is in device
         * buffers (partition.c), which the workspace may keep. */
        const int mapped = p.host_arrays[0] != NULL;
        TU_CHECK(mapped == ((cl->device_type & CL_DEVICE_TYPE_CPU) != 0));
        clvr_pp_workspace ws2 = {0}; /* empty: it would take any buffer offered */
        clvr_pp_workspace_recycle(cl, &ws2, &p);
        TU_CHECK(p.vertices == NULL && p.idx16 == NULL && p.leaf_boxes == NULL);
        int kept_any = 0;
        for (int k = 0; k < CLVR_PP_WS_COUNT; ++k) kept_any |= ws2.buf[k] != NULL;
        if (mapped) TU_CHECK(!kept_any);
        if (!(mapped && kept_any)) /* (with a buffer over unmapped memory kept, this call would crash) */
            TU_CHECK_STATUS(clvr_preprocess_ws(cl, &ms[0], NULL, &ws2, &q, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_preprocess(cl, &ms[0], NULL, &r, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_clustered_download(cl, &q, &qh, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_clustered_download(cl, &r, &rh, &err), CLVR_OK, &err);
        TU_CHECK(same_arrays(&q, &qh, &r, &rh));
        clvr_clustered_host_free(&qh);
        clvr_clustered_host_free(&rh);
        clvr_clustered_release(cl, &q);
        clvr_clustered_release(cl, &r);
        clvr_pp_workspace_release(cl, &ws2);
    }
    clvr_clustered_host kh = {0};
    TU_CHECK_STATUS(clvr_clustered_download(cl, &kept, &kh, &err), CLVR_OK, &err);
    TU_CHECK(kh.order != NULL && same_arrays(&kept, &kh, &kept, &kept_ref));
    clvr_clustered_host_free(&kh);
    clvr_clustered_host_free(&kept_ref);
    clvr_clustered_release(cl, &kept);
    clvr_pp_workspace_release(cl, &ws);
    TU_CHECK_EQ_U64(cl->allocated_bytes, before);
    for (int i = 0; i < 3; ++i) clvr_mesh_free(&ms[i]);
}

static void test_errors(clvr_cl *cl)
{
    clvr_error err = {0};
    clvr_mesh m = {0};
    clvr_clustered c = {0};
    uint64_t cells[4] = {0, 0, 0, 0};
    TU_CHECK_STATUS(clvr_mesh_alloc(&m, 4, cells, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_preprocess(cl, &m, NULL, &c, &err), CLVR_ERR_EMPTY, &err);
    clvr_mesh_free(&m);
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.leaf_size = 0;
    make_grid(&m, 2, 2, 2, 0, &err);
    TU_CHECK_STATUS(clvr_preprocess(cl, &m, &o, &c, &err), CLVR_ERR_USAGE, &err);
    o.leaf_size = 16;
    o.index_bits = 8;
    TU_CHECK_STATUS(clvr_preprocess(cl, &m, &o, &c, &err), CLVR_ERR_USAGE, &err);
    /* a failing allocation leaves nothing behind */
    setenv("CLVR_FAIL", "clCreateBuffer", 1);
    cl_ulong before = cl->allocated_bytes;
    TU_CHECK_STATUS(clvr_preprocess(cl, &m, NULL, &c, &err), CLVR_ERR_DEVICE_MEMORY, &err);
    unsetenv("CLVR_FAIL");
    TU_CHECK_EQ_U64(cl->allocated_bytes, before);
    TU_CHECK(c.vertices == NULL && c.host_instances == NULL);
    clvr_clustered_release(cl, &c); /* on an empty result: a no-op */
    clvr_clustered_release(cl, NULL);
    clvr_mesh_free(&m);
}

/* Every file of tests/data that clvr reads natively (the .vtu files need
 * tools/clvr-convert: clvr_mesh_load refuses them), through every option. */
static void test_data_meshes(clvr_cl *cl)
{
    const char *files[] = {"vtk/notch_stress.vtk", "vtk/post.vtk", "vtk/uGridEx.vtk", "umesh/all_elements.umesh"};
    uint64_t loaded = 0;
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", tu_data_dir(), files[i]);
        clvr_mesh m = {0};
        clvr_error err = {0};
        const clvr_status st = clvr_mesh_load(path, NULL, &m, &err);
        TU_CHECK_STATUS(st, CLVR_OK, &err);
        if (st != CLVR_OK) continue;
        ++loaded;
        run_all_options(cl, files[i], &m, 1);
        clvr_mesh_free(&m);
    }
    TU_CHECK_EQ_U64(loaded, sizeof files / sizeof files[0]);
}

/* The split's segments: 2^20 elements at least on a few compute units, 2^17
 * on many (a GPU's, where one work item walks a segment alone). The
 * reference split with 132 compute units over 64 x 64 x 40 hexes (163,840
 * elements: two segments) is a valid clustering, with one instance more than
 * with 2 compute units at most (the one that the first segment's end closes). */
static void test_split_segments(void)
{
    clvr_error err = {0};
    TU_CHECK_EQ_U64(clvr_pp_segment_floor(2), 1ull << 20);
    TU_CHECK_EQ_U64(clvr_pp_segment_floor(31), 1ull << 20);
    TU_CHECK_EQ_U64(clvr_pp_segment_floor(32), 1ull << 17);
    TU_CHECK_EQ_U64(clvr_pp_segment_floor(132), 1ull << 17);
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    clvr_preprocess_options r;
    TU_CHECK_STATUS(clvr_pp_options_resolve(&o, &r, &err), CLVR_OK, &err);
    const uint64_t tens[CLVR_CELL_TYPE_COUNT] = {10000000, 0, 0, 0};
    clvr_pp_layout L;
    clvr_pp_layout_make(&L, tens);
    clvr_pp_split_plan few, many;
    clvr_pp_split_plan_make(&few, &L, &r, 2, 2000000);
    clvr_pp_split_plan_make(&many, &L, &r, 132, 2000000);
    TU_CHECK_EQ_U64(few.seg_len[0], 1250000);
    TU_CHECK_EQ_U64(few.nseg[0], 8);
    TU_CHECK_EQ_U64(many.seg_len[0], 1u << 17);
    TU_CHECK_EQ_U64(many.nseg[0], (10000000 + (1u << 17) - 1) >> 17);

    clvr_mesh m = {0};
    TU_CHECK_STATUS(make_grid(&m, 64, 64, 40, 0, &err), CLVR_OK, &err);
    clvr_clustered a = {0}, b = {0};
    clvr_clustered_host ha = {0}, hb = {0};
    TU_CHECK_STATUS(clvr_pp_ref_preprocess(&m, &o, 2, &a, &ha, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_pp_ref_preprocess(&m, &o, 132, &b, &hb, &err), CLVR_OK, &err);
    printf("split segments: 163840 hexes -> %llu instances with 2 compute units, %llu with 132\n",
           (unsigned long long)a.num_instances, (unsigned long long)b.num_instances);
    TU_CHECK(b.num_instances >= a.num_instances && b.num_instances <= a.num_instances + 1);
    check_clustered("hex 64x64x40, reference with 132 compute units", &m, &b, &hb, 0);
    clvr_clustered_host_free(&ha);
    clvr_clustered_host_free(&hb);
    free(a.host_instances);
    free(b.host_instances);
    clvr_mesh_free(&m);
}

int main(int argc, char **argv)
{
    int big = argc > 1 && strcmp(argv[1], "--big") == 0;
    clvr_cl cl;
    clvr_error err = {0};
    tu_open_device(&cl);
    uint64_t rng = 5;
    if (big) {
        clvr_mesh m = {0};
        double t0 = now_s();
        TU_CHECK_STATUS(make_grid(&m, 216, 216, 216, 0, &err), CLVR_OK, &err);
        printf("generated 216^3 hexes in %.2f s\n", now_s() - t0);
        clvr_preprocess_options o;
        clvr_preprocess_options_default(&o);
        o.keep_order = 1;
        run_case(&cl, "hex 216^3", &m, &o, 1, 0);
        clvr_mesh_free(&m);
        clvr_cl_destroy(&cl);
        return tu_finish("test_preprocess --big");
    }
    test_split_segments();
    test_one_curve_rule();
    test_errors(&cl);
    test_workspace(&cl);
    test_quantize_box(&cl);
    struct { const char *name; uint32_t nx, ny, nz; int mode; } grids[] = {
        {"hex 1x1x1", 1, 1, 1, 0}, {"hex 2x1x1", 2, 1, 1, 0}, {"hex 17x13x11", 17, 13, 11, 0},
        {"tets 9x10x11", 9, 10, 11, 1}, {"wedges 5x7x3", 5, 7, 3, 2}, {"mixed 24x10x10", 24, 10, 10, 3},
        {"hex 64x64x40", 64, 64, 40, 0},
    };
    for (size_t i = 0; i < sizeof grids / sizeof grids[0]; ++i) {
        clvr_mesh m = {0};
        TU_CHECK_STATUS(make_grid(&m, grids[i].nx, grids[i].ny, grids[i].nz, grids[i].mode, &err), CLVR_OK, &err);
        run_all_options(&cl, grids[i].name, &m, m.num_cells[3] < 100000);
        clvr_mesh_free(&m);
    }
    {
        clvr_mesh m = {0};
        TU_CHECK_STATUS(make_grid(&m, 40, 30, 20, 3, &err), CLVR_OK, &err);
        shuffle(&m, &rng);
        clvr_preprocess_options o;
        clvr_preprocess_options_default(&o);
        o.keep_order = 1;
        run_case(&cl, "mixed 40x30x20 shuffled", &m, &o, 1, 1);
        clvr_mesh_free(&m);
    }
    {
        clvr_mesh m = {0};
        TU_CHECK_STATUS(make_random(&m, 300007, 65537, &rng, &err), CLVR_OK, &err);
        run_all_options(&cl, "random 65537 elements", &m, 1);
        clvr_mesh_free(&m);
    }
    test_data_meshes(&cl);
    clvr_cl_destroy(&cl);
    return tu_finish("test_preprocess");
}
