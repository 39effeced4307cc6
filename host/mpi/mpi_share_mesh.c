/* mpi_share_mesh.c: a rank's share of a mesh held whole (mpi_share_mesh.h). */
#include "mpi_share_mesh.h"

#include "cl_context.h" /* CLVR_TRY */

#include <float.h>
#include <stdlib.h>
#include <string.h>

/* The vertex box of element e of type t. */
static void element_box(const clvr_mesh *m, uint32_t t, uint64_t e, float lo[3], float hi[3])
{
    const uint32_t nv = clvr_cell_vertex_count(t);
    const uint32_t *idx = m->indices[t] + e * nv;
    for (int a = 0; a < 3; ++a) { lo[a] = FLT_MAX; hi[a] = -FLT_MAX; }
    for (uint32_t k = 0; k < nv; ++k) {
        const float *p = m->positions + 3 * (uint64_t)idx[k];
        for (int a = 0; a < 3; ++a) {
            if (p[a] < lo[a]) lo[a] = p[a];
            if (p[a] > hi[a]) hi[a] = p[a];
        }
    }
}

static void element_centroid(const clvr_mesh *m, uint32_t t, uint64_t e, float c[3])
{
    const uint32_t nv = clvr_cell_vertex_count(t);
    const uint32_t *idx = m->indices[t] + e * nv;
    double s[3] = {0, 0, 0};
    for (uint32_t k = 0; k < nv; ++k)
        for (int a = 0; a < 3; ++a) s[a] += m->positions[3 * (uint64_t)idx[k] + a];
    for (int a = 0; a < 3; ++a) c[a] = (float)(s[a] / nv);
}

clvr_status clvr_mpi_share_cut(const clvr_mesh *whole, uint32_t rank, uint32_t nranks, clvr_mpi_share *out,
                               clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const uint64_t n = clvr_mesh_num_elements(whole);
    float *cent = NULL, *regions = NULL;
    uint8_t *keep = NULL;
    uint32_t *vmap = NULL;
    memset(out, 0, sizeof *out);
    if (nranks == 0 || rank >= nranks)
        return clvr_error_set(err, CLVR_ERR_INTERNAL, "rank %u of %u ranks", rank, nranks);
    cent = malloc((size_t)(n ? n : 1) * 3 * sizeof(float));
    regions = malloc((size_t)nranks * 6 * sizeof(float));
    keep = calloc((size_t)(n ? n : 1), 1);
    vmap = malloc((size_t)(whole->num_vertices ? whole->num_vertices : 1) * sizeof(uint32_t));
    if (!cent || !regions || !keep || !vmap) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory cutting the mesh into %u shares", nranks);
        goto cleanup;
    }
    uint64_t i = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        for (uint64_t e = 0; e < whole->num_cells[t]; ++e, ++i) element_centroid(whole, t, e, cent + 3 * i);
    CLVR_TRY(clvr_mpi_regions(cent, n, whole->bounds_lo, whole->bounds_hi, nranks, regions, err));
    const float *rlo = regions + 6u * rank, *rhi = rlo + 3;
    /* Elements kept (vertex box overlaps the closed region), counted per
     * type; owned ones by their centroid (recomputed: cent was reordered). */
    uint64_t cells[CLVR_CELL_TYPE_COUNT] = {0}, owned = 0;
    i = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        for (uint64_t e = 0; e < whole->num_cells[t]; ++e, ++i) {
            float lo[3], hi[3], c[3];
            element_box(whole, t, e, lo, hi);
            if (!clvr_mpi_boxes_overlap(lo, hi, rlo, rhi)) continue;
            keep[i] = 1;
            ++cells[t];
            element_centroid(whole, t, e, c);
            if (clvr_mpi_region_of(regions, nranks, c) == rank) {
                keep[i] = 2;
                ++owned;
            }
        }
    /* Vertices used, numbered in their original order. */
    for (uint64_t v = 0; v < whole->num_vertices; ++v) vmap[v] = UINT32_MAX;
    i = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        for (uint64_t e = 0; e < whole->num_cells[t]; ++e, ++i)
            if (keep[i])
                for (uint32_t k = 0; k < nv; ++k) vmap[whole->indices[t][e * nv + k]] = 0;
    }
    uint64_t nvert = 0;
    for (uint64_t v = 0; v < whole->num_vertices; ++v)
        if (vmap[v] == 0) vmap[v] = (uint32_t)nvert++;
    CLVR_TRY(clvr_mesh_alloc(&out->mesh, nvert, cells, err));
    {
        const uint64_t kept = cells[0] + cells[1] + cells[2] + cells[3];
        out->owned = malloc(kept ? kept : 1);
        if (!out->owned) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory cutting the mesh into %u shares", nranks);
            goto cleanup;
        }
        /* kept elements keep their type order and their order within it */
        uint64_t j = 0, k = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
            for (uint64_t e = 0; e < whole->num_cells[t]; ++e, ++k)
                if (keep[k]) out->owned[j++] = keep[k] == 2;
    }
    for (uint64_t v = 0; v < whole->num_vertices; ++v)
        if (vmap[v] != UINT32_MAX) {
            memcpy(out->mesh.positions + 3 * (uint64_t)vmap[v], whole->positions + 3 * v, 3 * sizeof(float));
            out->mesh.scalars[vmap[v]] = whole->scalars[v];
        }
    i = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        uint64_t j = 0;
        for (uint64_t e = 0; e < whole->num_cells[t]; ++e, ++i)
            if (keep[i]) {
                for (uint32_t k = 0; k < nv; ++k) out->mesh.indices[t][j * nv + k] = vmap[whole->indices[t][e * nv + k]];
                ++j;
            }
    }
    memcpy(out->mesh.scalar_name, whole->scalar_name, sizeof out->mesh.scalar_name);
    out->mesh.cell_flat = whole->cell_flat;
    clvr_mesh_update_ranges(&out->mesh);
    memcpy(out->region_lo, rlo, sizeof out->region_lo);
    memcpy(out->region_hi, rhi, sizeof out->region_hi);
    memcpy(out->bounds_lo, whole->bounds_lo, sizeof out->bounds_lo);
    memcpy(out->bounds_hi, whole->bounds_hi, sizeof out->bounds_hi);
    out->scalar_min = whole->scalar_min;
    out->scalar_max = whole->scalar_max;
    out->global_vertices = whole->num_vertices;
    out->global_elements = n;
    out->owned_elements = owned;
cleanup:
    if (s != CLVR_OK) clvr_mpi_share_free(out);
    free(cent);
    free(regions);
    free(keep);
    free(vmap);
    return s;
}

clvr_status clvr_mpi_share_from_mesh(MPI_Comm comm, const clvr_mesh *whole, clvr_mpi_share *out, clvr_error *err)
{
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    clvr_status s = clvr_mpi_share_cut(whole, (uint32_t)rank, (uint32_t)size, out, err);
    /* Same status everywhere: the first failing rank's. */
    int mine = s == CLVR_OK ? size : rank, first = size;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
    if (first < size && s == CLVR_OK) {
        clvr_mpi_share_free(out);
        s = clvr_error_set(err, CLVR_ERR_INTERNAL, "rank %d failed to cut its share of the mesh", first);
    }
    return s;
}
