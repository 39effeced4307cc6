#include "mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <float.h>
#ifdef __linux__
#include <sys/mman.h>
#endif

int clvr_mul_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (a != 0 && b > UINT64_MAX / a) return 1;
    *out = a * b;
    return 0;
}

int clvr_add_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (b > UINT64_MAX - a) return 1;
    *out = a + b;
    return 0;
}

void clvr_mesh_set_scalar_name(clvr_mesh *m, const char *name, size_t len)
{
    size_t n = 0;
    for (; n < len && n < CLVR_SCALAR_NAME_MAX - 1 && name[n]; ++n) {
        unsigned char c = (unsigned char)name[n];
        m->scalar_name[n] = (c < 0x20 || c == 0x7f || c == '"' || c == '\\') ? '?' : (char)c;
    }
    m->scalar_name[n] = 0;
}

const char *clvr_cell_type_name(uint32_t t)
{
    static const char *names[CLVR_CELL_TYPE_COUNT] = {"tets", "pyramids", "wedges", "hexes"};
    return t < CLVR_CELL_TYPE_COUNT ? names[t] : "?";
}

/* malloc of count*size bytes with overflow and size_t checks. */
static clvr_status alloc_array(void **p, uint64_t count, uint64_t size, const char *what, clvr_error *err)
{
    uint64_t bytes;
    *p = NULL;
    if (clvr_mul_u64(count, size, &bytes) || bytes > (uint64_t)SIZE_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: %llu entries of %llu bytes overflow the address space",
                              what, (unsigned long long)count, (unsigned long long)size);
    if (bytes == 0) return CLVR_OK;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    /* Big arrays on transparent huge pages: filling 4 KiB pages one fault at
     * a time was half of loading a 3.7 GB .bin (perf: page faults and
     * clearing, 5.1 s for 100M mixed elements). free() takes them as any. */
    const size_t huge = (size_t)2 << 20;
    if (bytes >= 16 * huge && bytes <= SIZE_MAX - huge) {
        *p = aligned_alloc(huge, ((size_t)bytes + huge - 1) / huge * huge);
        if (*p) {
            madvise(*p, ((size_t)bytes + huge - 1) / huge * huge, MADV_HUGEPAGE);
            return CLVR_OK;
        }
    }
#endif
    *p = malloc((size_t)bytes);
    if (!*p)
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %.3f GB of host memory", what,
                              (double)bytes / 1e9);
    return CLVR_OK;
}

clvr_status clvr_mesh_alloc(clvr_mesh *m, uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                            clvr_error *err)
{
    clvr_status s;
    memset(m, 0, sizeof *m);
    m->num_vertices = num_vertices;
    s = alloc_array((void **)&m->positions, num_vertices, 3 * sizeof(float), "vertices", err);
    if (s == CLVR_OK) s = alloc_array((void **)&m->scalars, num_vertices, sizeof(float), "scalars", err);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t) {
        m->num_cells[t] = num_cells[t];
        s = alloc_array((void **)&m->indices[t], num_cells[t], clvr_cell_vertex_count(t) * sizeof(uint32_t),
                        clvr_cell_type_name(t), err);
    }
    if (s != CLVR_OK) clvr_mesh_free(m);
    return s;
}

void clvr_mesh_free(clvr_mesh *m)
{
    if (!m) return;
    free(m->positions);
    free(m->scalars);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) free(m->indices[t]);
    memset(m, 0, sizeof *m);
}

uint64_t clvr_mesh_num_elements(const clvr_mesh *m)
{
    uint64_t n = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n += m->num_cells[t];
    return n;
}

uint64_t clvr_mesh_num_indices(const clvr_mesh *m, uint32_t t)
{
    return m->num_cells[t] * clvr_cell_vertex_count(t);
}

uint64_t clvr_mesh_vertex_bytes(const clvr_mesh *m)
{
    return m->num_vertices * 4u * sizeof(float);
}

uint64_t clvr_mesh_index_bytes(const clvr_mesh *m)
{
    uint64_t n = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n += clvr_mesh_num_indices(m, t) * sizeof(uint32_t);
    return n;
}

void clvr_mesh_update_ranges(clvr_mesh *m)
{
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    float smin = FLT_MAX, smax = -FLT_MAX;
    for (uint64_t i = 0; i < m->num_vertices; ++i) {
        for (int k = 0; k < 3; ++k) {
            float v = m->positions[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
        smin = m->scalars[i] < smin ? m->scalars[i] : smin;
        smax = m->scalars[i] > smax ? m->scalars[i] : smax;
    }
    if (m->num_vertices == 0) {
        for (int k = 0; k < 3; ++k) lo[k] = hi[k] = 0.0f;
        smin = smax = 0.0f;
    }
    memcpy(m->bounds_lo, lo, sizeof lo);
    memcpy(m->bounds_hi, hi, sizeof hi);
    m->scalar_min = smin;
    m->scalar_max = smax;
}

clvr_status clvr_mesh_validate(const clvr_mesh *m, const char *what, clvr_error *err)
{
    if (clvr_mesh_num_elements(m) == 0)
        return clvr_error_set(err, CLVR_ERR_EMPTY, "%s: the mesh has no elements (0 tets, pyramids, wedges, hexes)",
                              what);
    for (uint64_t i = 0; i < m->num_vertices; ++i) {
        const float *p = m->positions + 3 * i;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
            return clvr_error_set(err, CLVR_ERR_BAD_VALUE,
                                  "%s: vertex %llu has a non-finite coordinate (%g, %g, %g); fix or remove it",
                                  what, (unsigned long long)i, p[0], p[1], p[2]);
        if (!isfinite(m->scalars[i]))
            return clvr_error_set(err, CLVR_ERR_BAD_VALUE,
                                  "%s: scalar '%s' at vertex %llu is %g; replace NaN/Inf values before rendering",
                                  what, m->scalar_name, (unsigned long long)i, m->scalars[i]);
    }
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        const uint64_t n = clvr_mesh_num_indices(m, t);
        for (uint64_t j = 0; j < n; ++j) {
            if ((uint64_t)m->indices[t][j] >= m->num_vertices)
                return clvr_error_set(err, CLVR_ERR_BAD_INDEX,
                                      "%s: %s[%llu] vertex %u is index %u but the mesh has %llu vertices", what,
                                      clvr_cell_type_name(t), (unsigned long long)(j / nv), (unsigned)(j % nv),
                                      m->indices[t][j], (unsigned long long)m->num_vertices);
        }
    }
    return CLVR_OK;
}
