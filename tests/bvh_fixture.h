/* bvh_fixture.h: test and benchmark helpers of bvh/: generated meshes
 * (jittered grids cut into tets, pyramids, wedges, hexes or a mix) and a
 * plain host clustering into the exact "clustered mesh" format of
 * clvr_shared.h (elements sorted per type along a Morton curve, instances of
 * up to K elements with 16- or 32-bit local indices, leaf clusters, leaf
 * boxes), standing in for the preprocessing kernels. Header-only, static. */
#ifndef CLVR_BVH_FIXTURE_H
#define CLVR_BVH_FIXTURE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "../kernels/clvr_shared.h"
#include "../kernels/locate.h"

/* ------------------------------------------------------------ generated meshes */

/* Cube kinds of fx_grid_mesh. */
#define FX_TETS 0      /* 6 Kuhn tets per cube (conforming) */
#define FX_PYRAMIDS 1  /* 6 pyramids per cube, apex at the cube's centre vertex */
#define FX_WEDGES 2    /* 2 wedges per cube (split along the xy diagonal) */
#define FX_HEXES 3
#define FX_MIXED 4     /* kind of cube (i, j, k) = (i + 2j + 3k) % 4 */

static inline float fx_field(float x, float y, float z) { return sinf(1.3f * x) + 0.7f * y * z - 0.2f * z * z + 2.0f; }

/* Grid of n^3 cubes over [0, n]^3 (scaled by `scale`, offset by `offset`),
 * interior vertices jittered by up to `jitter` cells (non-planar faces),
 * cut into elements of the given kind. Vertices: (n+1)^3 corners, then n^3
 * cube centres. */
static inline clvr_status fx_grid_mesh(uint32_t n, uint32_t kind, float jitter, float scale, float offset, uint64_t seed,
                                clvr_mesh *m, clvr_error *err)
{
    const uint64_t nc = (uint64_t)n * n * n, n1 = n + 1u, ncorner = n1 * n1 * n1;
    uint64_t counts[4] = {0, 0, 0, 0};
    for (uint32_t k = 0; k < n; ++k)
        for (uint32_t j = 0; j < n; ++j)
            for (uint32_t i = 0; i < n; ++i) {
                const uint32_t kk = kind == FX_MIXED ? (i + 2u * j + 3u * k) % 4u : kind;
                counts[kk] += kk == FX_TETS ? 6 : kk == FX_PYRAMIDS ? 6 : kk == FX_WEDGES ? 2 : 1;
            }
    clvr_status s = clvr_mesh_alloc(m, ncorner + nc, counts, err);
    if (s != CLVR_OK) return s;
    uint64_t rs = seed;
    for (uint64_t k = 0; k < n1; ++k)
        for (uint64_t j = 0; j < n1; ++j)
            for (uint64_t i = 0; i < n1; ++i) {
                const uint64_t v = (k * n1 + j) * n1 + i;
                float p[3] = {(float)i, (float)j, (float)k};
                const uint64_t ijk[3] = {i, j, k};
                for (int a = 0; a < 3; ++a) {
                    rs += 0x9e3779b97f4a7c15ull;
                    uint64_t z = rs;
                    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
                    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
                    z ^= z >> 31;
                    const float r = (float)(z >> 40) * (1.0f / 16777216.0f) * 2.0f - 1.0f;
                    if (ijk[a] > 0 && ijk[a] < n) p[a] += jitter * r;
                }
                for (int a = 0; a < 3; ++a) m->positions[3 * v + a] = p[a] * scale + offset;
            }
    for (uint64_t k = 0; k < n; ++k)
        for (uint64_t j = 0; j < n; ++j)
            for (uint64_t i = 0; i < n; ++i) {
                const uint64_t v = ncorner + (k * n + j) * n + i;
                /* centre: average of the 8 corners (keeps pyramids valid) */
                for (int a = 0; a < 3; ++a) {
                    float sum = 0.0f;
                    for (int c = 0; c < 8; ++c) {
                        const uint64_t ci = ((k + (c >> 2 & 1)) * n1 + (j + (c >> 1 & 1))) * n1 + (i + (c & 1));
                        sum += m->positions[3 * ci + a];
                    }
                    m->positions[3 * v + a] = sum / 8.0f;
                }
            }
    for (uint64_t v = 0; v < m->num_vertices; ++v)
        m->scalars[v] = fx_field(m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]);
    uint64_t at[4] = {0, 0, 0, 0};
    for (uint32_t k = 0; k < n; ++k)
        for (uint32_t j = 0; j < n; ++j)
            for (uint32_t i = 0; i < n; ++i) {
                const uint32_t kk = kind == FX_MIXED ? (i + 2u * j + 3u * k) % 4u : kind;
                uint32_t c[8]; /* VTK hex order */
                static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                              {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
                for (int q = 0; q < 8; ++q)
                    c[q] = (uint32_t)(((k + off[q][2]) * n1 + (j + off[q][1])) * n1 + (i + off[q][0]));
                const uint32_t ctr = (uint32_t)(ncorner + ((uint64_t)k * n + j) * n + i);
                uint32_t *out = m->indices[kk] + at[kk] * clvr_cell_vertex_count(kk);
                if (kk == FX_HEXES) {
                    memcpy(out, c, sizeof c);
                    at[kk] += 1;
                } else if (kk == FX_WEDGES) {
                    const uint32_t w[12] = {c[0], c[1], c[2], c[4], c[5], c[6], c[0], c[2], c[3], c[4], c[6], c[7]};
                    memcpy(out, w, sizeof w);
                    at[kk] += 2;
                } else if (kk == FX_PYRAMIDS) {
                    static const int faces[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1},
                                                    {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}};
                    for (int f = 0; f < 6; ++f) {
                        for (int q = 0; q < 4; ++q) out[5 * f + q] = c[faces[f][q]];
                        out[5 * f + 4] = ctr;
                    }
                    at[kk] += 6;
                } else {
                    /* Kuhn: paths from corner 0 to corner 6 in the 6 axis orders. */
                    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
                    for (int t = 0; t < 6; ++t) {
                        int b[3] = {0, 0, 0};
                        out[4 * t] = c[0];
                        for (int s2 = 0; s2 < 3; ++s2) {
                            b[perm[t][s2]] = 1;
                            int q = 0;
                            for (; q < 8; ++q)
                                if (off[q][0] == b[0] && off[q][1] == b[1] && off[q][2] == b[2]) break;
                            out[4 * t + 1 + s2] = c[q];
                        }
                    }
                    at[kk] += 6;
                }
            }
    clvr_mesh_update_ranges(m);
    return CLVR_OK;
}

/* ------------------------------------------------------------ host clustering */

typedef struct fx_clustered {
    clvr_vec4 *vertices;
    uint64_t num_vertices;
    uint16_t *idx16;
    uint64_t num_idx16;
    uint32_t *idx32;
    uint64_t num_idx32;
    clvr_instance *instances;
    uint32_t num_instances;
    clvr_box *leaf_boxes;
    uint32_t num_leaves;
    uint32_t leaf_size;
    uint32_t num_elements;
    uint32_t *elem_instance; /* instance of each global sorted element id */
} fx_clustered;

static inline void fx_clustered_free(fx_clustered *c)
{
    free(c->vertices);
    free(c->idx16);
    free(c->idx32);
    free(c->instances);
    free(c->leaf_boxes);
    free(c->elem_instance);
    memset(c, 0, sizeof *c);
}

typedef struct fx_key {
    uint64_t key;
    uint32_t id;
} fx_key;

static inline int fx_key_cmp(const void *a, const void *b)
{
    const fx_key *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key ? 1 : (x->id > y->id) - (x->id < y->id);
}

static inline uint64_t fx_spread(uint64_t v)
{
    v &= 0xffff;
    v = (v | v << 16) & 0x0000ff0000ffull;
    v = (v | v << 8) & 0x00f00f00f00full;
    v = (v | v << 4) & 0x0c30c30c30c3ull;
    v = (v | v << 2) & 0x249249249249ull;
    return v;
}

/* Clusters m: per type Morton-sorted, instances of at most inst_elems
 * elements (16-bit indices when they reference < 2^16 vertices and force32
 * is 0), leaf clusters of leaf_size. Returns 0 on success, -1 out of memory. */
static inline int fx_cluster(const clvr_mesh *m, uint32_t leaf_size, uint32_t inst_elems, int force32, fx_clustered *c)
{
    memset(c, 0, sizeof *c);
    c->leaf_size = leaf_size;
    const uint64_t ne = clvr_mesh_num_elements(m);
    c->num_elements = (uint32_t)ne;
    uint64_t ninst_max = 0, nleaf_max = 0, nidx = 0;
    for (uint32_t t = 0; t < 4; ++t) {
        ninst_max += (m->num_cells[t] + inst_elems - 1) / inst_elems;
        nleaf_max += (m->num_cells[t] + leaf_size - 1) / leaf_size + (m->num_cells[t] + inst_elems - 1) / inst_elems;
        nidx += clvr_mesh_num_indices(m, t);
    }
    c->instances = calloc(ninst_max + 1, sizeof *c->instances);
    c->leaf_boxes = calloc(nleaf_max + 1, sizeof *c->leaf_boxes);
    c->vertices = malloc((nidx + 1) * sizeof *c->vertices);
    c->idx16 = malloc((nidx + 1) * sizeof *c->idx16);
    c->idx32 = malloc((nidx + 1) * sizeof *c->idx32);
    c->elem_instance = malloc((ne + 1) * sizeof *c->elem_instance);
    uint32_t *stamp = malloc((m->num_vertices + 1) * sizeof *stamp);
    uint32_t *local = malloc((m->num_vertices + 1) * sizeof *local);
    fx_key *keys = malloc((ne + 1) * sizeof *keys);
    if (!c->instances || !c->leaf_boxes || !c->vertices || !c->idx16 || !c->idx32 || !c->elem_instance || !stamp ||
        !local || !keys) {
        free(stamp);
        free(local);
        free(keys);
        fx_clustered_free(c);
        return -1;
    }
    memset(stamp, 0xff, (m->num_vertices + 1) * sizeof *stamp);
    const float *lo = m->bounds_lo, *hi = m->bounds_hi;
    uint32_t global = 0;
    for (uint32_t t = 0; t < 4; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        const uint64_t n = m->num_cells[t];
        for (uint64_t e = 0; e < n; ++e) {
            float cx = 0, cy = 0, cz = 0;
            for (uint32_t k = 0; k < nv; ++k) {
                const float *p = m->positions + 3 * (uint64_t)m->indices[t][e * nv + k];
                cx += p[0]; cy += p[1]; cz += p[2];
            }
            uint64_t q[3];
            const float cc[3] = {cx / nv, cy / nv, cz / nv};
            for (int a = 0; a < 3; ++a) {
                const float ext = hi[a] - lo[a];
                float f = ext > 0 ? (cc[a] - lo[a]) / ext : 0.0f;
                f = f < 0 ? 0 : f > 1 ? 1 : f;
                q[a] = (uint64_t)(f * 65535.0f);
            }
            keys[e].key = fx_spread(q[0]) | fx_spread(q[1]) << 1 | fx_spread(q[2]) << 2;
            keys[e].id = (uint32_t)e;
        }
        qsort(keys, n, sizeof *keys, fx_key_cmp);
        for (uint64_t first = 0; first < n; first += inst_elems) {
            const uint64_t cnt = n - first < inst_elems ? n - first : inst_elems;
            clvr_instance *in = &c->instances[c->num_instances];
            const uint32_t id = c->num_instances++;
            /* count distinct vertices first to pick the index width */
            uint32_t nvert = 0;
            for (uint64_t e = first; e < first + cnt; ++e)
                for (uint32_t k = 0; k < nv; ++k) {
                    const uint32_t g = m->indices[t][(uint64_t)keys[e].id * nv + k];
                    if (stamp[g] != id) { stamp[g] = id; local[g] = nvert++; }
                }
            in->type = t;
            in->index_bits = (!force32 && nvert < CLVR_INSTANCE_MAX_VERTS16) ? 16u : 32u;
            in->first_element = global;
            in->num_elements = (uint32_t)cnt;
            in->first_vertex = (uint32_t)c->num_vertices;
            in->num_vertices = nvert;
            in->first_index = in->index_bits == 16 ? c->num_idx16 : c->num_idx32;
            in->first_leaf = c->num_leaves;
            in->num_leaves = (uint32_t)((cnt + leaf_size - 1) / leaf_size);
            for (int a = 0; a < 3; ++a) { in->bounds.lo[a] = INFINITY; in->bounds.hi[a] = -INFINITY; }
            for (uint64_t e = first; e < first + cnt; ++e)
                for (uint32_t k = 0; k < nv; ++k) {
                    const uint32_t g = m->indices[t][(uint64_t)keys[e].id * nv + k];
                    const float *p = m->positions + 3 * (uint64_t)g;
                    clvr_vec4 vv = {p[0], p[1], p[2], m->scalars[g]};
                    c->vertices[in->first_vertex + local[g]] = vv;
                    if (in->index_bits == 16) c->idx16[c->num_idx16++] = (uint16_t)local[g];
                    else c->idx32[c->num_idx32++] = local[g];
                }
            c->num_vertices += nvert;
            for (uint32_t l = 0; l < in->num_leaves; ++l) {
                clvr_box *b = &c->leaf_boxes[in->first_leaf + l];
                memset(b, 0, sizeof *b);
                for (int a = 0; a < 3; ++a) { b->lo[a] = INFINITY; b->hi[a] = -INFINITY; }
                const uint64_t e0 = first + (uint64_t)l * leaf_size;
                const uint64_t e1 = e0 + leaf_size < first + cnt ? e0 + leaf_size : first + cnt;
                for (uint64_t e = e0; e < e1; ++e)
                    for (uint32_t k = 0; k < nv; ++k) {
                        const float *p = m->positions + 3 * (uint64_t)m->indices[t][(uint64_t)keys[e].id * nv + k];
                        for (int a = 0; a < 3; ++a) {
                            b->lo[a] = fminf(b->lo[a], p[a]);
                            b->hi[a] = fmaxf(b->hi[a], p[a]);
                        }
                    }
                for (int a = 0; a < 3; ++a) {
                    in->bounds.lo[a] = fminf(in->bounds.lo[a], b->lo[a]);
                    in->bounds.hi[a] = fmaxf(in->bounds.hi[a], b->hi[a]);
                }
            }
            c->num_leaves += in->num_leaves;
            for (uint64_t e = 0; e < cnt; ++e) c->elem_instance[global + e] = id;
            global += (uint32_t)cnt;
        }
    }
    free(stamp);
    free(local);
    free(keys);
    return 0;
}

/* Vertices of global sorted element e. Returns its type. */
static inline uint32_t fx_element(const fx_clustered *c, uint32_t e, clvr_vec4 *v)
{
    const clvr_instance *in = &c->instances[c->elem_instance[e]];
    const clvr_mesh_view mv = {NULL, NULL, c->instances, c->vertices, c->idx16, c->idx32, 0, 0, NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
    clvr_load_element(&mv, in, e, v);
    return in->type;
}

/* Brute force: does element e contain p (and its scalar)? */
static inline int fx_element_sample(const fx_clustered *c, uint32_t e, float px, float py, float pz, float *s)
{
    clvr_vec4 v[CLVR_CELL_MAX_VERTS];
    const uint32_t t = fx_element(c, e, v);
    return clvr_element_sample(t, v, px, py, pz, s);
}

/* Brute force over all elements: first element that contains p, or
 * CLVR_BVH_NOT_FOUND. */
static inline uint32_t fx_brute_locate(const fx_clustered *c, float px, float py, float pz, float *s)
{
    for (uint32_t e = 0; e < c->num_elements; ++e) {
        clvr_vec4 v[8];
        const uint32_t t = fx_element(c, e, v);
        if (!clvr_element_box_test(t, v, px, py, pz)) continue;
        if (clvr_element_sample(t, v, px, py, pz, s)) return e;
    }
    return CLVR_BVH_NOT_FOUND;
}

#endif /* CLVR_BVH_FIXTURE_H */
