#include "mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <float.h>
#include <stdio.h>
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

static int in_map(const clvr_mesh *m, const void *p);

void clvr_mesh_free_indices(clvr_mesh *m)
{
    if (!m) return;
    if (m->map_base && (in_map(m, m->positions) || in_map(m, m->scalars))) {
        /* The vertices live in the mapping too: only the lists' pages go. */
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
            if (m->indices[t]) clvr_mesh_release_pages(m, m->indices[t], clvr_mesh_num_indices(m, t) * 4u);
    } else if (m->map_base) {
#ifdef __linux__
        munmap(m->map_base, (size_t)m->map_bytes);
#endif
        m->map_base = NULL;
        m->map_bytes = 0;
    } else {
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) free(m->indices[t]);
    }
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) m->indices[t] = NULL;
}

void clvr_mesh_release_pages(const clvr_mesh *m, const void *p, uint64_t bytes)
{
#ifdef __linux__
    if (!m->map_base || !p || bytes == 0) return;
    const uintptr_t pg = 4096, base = (uintptr_t)m->map_base, end = base + (uintptr_t)m->map_bytes;
    uintptr_t a = (uintptr_t)p, b = a + (uintptr_t)bytes;
    a = a < base ? base : a;
    b = b > end ? end : b;
    a = (a + pg - 1) / pg * pg; /* whole pages only: a page straddling the range may still be read */
    b = b / pg * pg;
    if (b > a) madvise((void *)a, b - a, MADV_DONTNEED);
#else
    (void)m; (void)p; (void)bytes;
#endif
}

void clvr_mesh_release_all_pages(const clvr_mesh *m)
{
    clvr_mesh_release_pages(m, m->map_base, m->map_bytes);
}

/* Whether p points into m's mapping (then it is not malloc'd). */
static int in_map(const clvr_mesh *m, const void *p)
{
    const uintptr_t a = (uintptr_t)p, b = (uintptr_t)m->map_base;
    return m->map_base && a >= b && a < b + (uintptr_t)m->map_bytes;
}

void clvr_mesh_free(clvr_mesh *m)
{
    if (!m) return;
    if (!in_map(m, m->positions)) free(m->positions);
    if (!in_map(m, m->scalars)) free(m->scalars);
    clvr_mesh_free_indices(m);
    free(m->fields);
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
        if ((i & 0xfffff) == 0xfffff) { /* mapped vertices: pages back behind the scan */
            clvr_mesh_release_pages(m, m->positions + 3 * (i - 0xfffff), 0x100000 * 12ull);
            clvr_mesh_release_pages(m, m->scalars + (i - 0xfffff), 0x100000 * 4ull);
        }
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
        if ((i & 0xfffff) == 0xfffff) { /* mapped vertices: pages back behind the scan */
            clvr_mesh_release_pages(m, m->positions + 3 * (i - 0xfffff), 0x100000 * 12ull);
            clvr_mesh_release_pages(m, m->scalars + (i - 0xfffff), 0x100000 * 4ull);
        }
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
        /* Mapped lists are checked in chunks whose pages go back to the page
         * cache behind the scan, so validating a 13 GB file does not make
         * it 13 GB of resident set (clvr_mesh_release_pages). */
        const uint64_t chunk = (uint64_t)8 << 20;
        for (uint64_t j0 = 0; j0 < n; j0 += chunk) {
            const uint64_t j1 = n - j0 < chunk ? n : j0 + chunk;
            const uint32_t *ix = m->indices[t];
            uint32_t bad = 0;
            for (uint64_t j = j0; j < j1; ++j) bad |= ix[j] >= m->num_vertices;
            if (bad)
                for (uint64_t j = j0; j < j1; ++j)
                    if ((uint64_t)ix[j] >= m->num_vertices) {
                        clvr_mesh_release_pages(m, ix + j0, (j1 - j0) * sizeof *ix);
                        return clvr_error_set(err, CLVR_ERR_BAD_INDEX,
                                              "%s: %s[%llu] vertex %u is index %u but the mesh has %llu vertices",
                                              what, clvr_cell_type_name(t), (unsigned long long)(j / nv),
                                              (unsigned)(j % nv), ix[j], (unsigned long long)m->num_vertices);
                    }
            clvr_mesh_release_pages(m, ix + j0, (j1 - j0) * sizeof *ix);
        }
    }
    return CLVR_OK;
}

/* Index of the field called name[0..len) with the given association
 * (2: either, point first), or -1. */
static int64_t field_find(const clvr_field_info *f, uint32_t n, const char *name, size_t len, uint32_t assoc)
{
    for (uint32_t pass = 0; pass < 2; ++pass) {
        uint32_t want = pass == 0 ? CLVR_FIELD_POINT : CLVR_FIELD_CELL;
        if (assoc != 2 && assoc != want) continue;
        for (uint32_t i = 0; i < n; ++i)
            if (f[i].association == want && strlen(f[i].name) == len && memcmp(f[i].name, name, len) == 0)
                return i;
    }
    return -1;
}

clvr_status clvr_field_select(const clvr_field_info *fields, uint32_t n, const char *spec, const char *file,
                              uint32_t *index, int *component, clvr_error *err)
{
    *index = 0;
    *component = CLVR_FIELD_MAGNITUDE;
    if (!spec || !spec[0]) {
        if (n == 0)
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: the file holds no fields", file);
        return CLVR_OK;
    }
    const char *name = spec;
    uint32_t assoc = 2;
    if (strncmp(spec, "point:", 6) == 0) {
        assoc = CLVR_FIELD_POINT;
        name = spec + 6;
    } else if (strncmp(spec, "cell:", 5) == 0) {
        assoc = CLVR_FIELD_CELL;
        name = spec + 5;
    }
    size_t len = strlen(name);
    int64_t i = field_find(fields, n, name, len, assoc);
    /* A name that does not match whole may end in a component. */
    if (i < 0 && assoc != 2) i = field_find(fields, n, spec, strlen(spec), 2); /* "cell:x" may be a whole name */
    if (i >= 0) {
        *index = (uint32_t)i;
        return CLVR_OK;
    }
    const char *colon = strrchr(name, ':');
    if (colon && colon > name) {
        const char *c = colon + 1;
        int comp = -1;
        if (!strcmp(c, "x") || !strcmp(c, "X")) comp = 0;
        else if (!strcmp(c, "y") || !strcmp(c, "Y")) comp = 1;
        else if (!strcmp(c, "z") || !strcmp(c, "Z")) comp = 2;
        else if (c[0] >= '0' && c[0] <= '9' && strlen(c) <= 2) {
            char *end;
            long v = strtol(c, &end, 10);
            if (!*end && v >= 0 && v < (long)CLVR_FIELD_COMPONENTS_MAX) comp = (int)v;
        }
        if (comp >= 0) {
            i = field_find(fields, n, name, (size_t)(colon - name), assoc);
            if (i >= 0) {
                if ((uint32_t)comp >= fields[i].components || fields[i].components == 1)
                    return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                          "%s: --scalar %s: %s field '%s' has %u component%s; use %s (magnitude)%s",
                                          file, spec, fields[i].association ? "cell" : "point", fields[i].name,
                                          fields[i].components, fields[i].components == 1 ? "" : "s",
                                          fields[i].name, fields[i].components >= 3 ? " or NAME:x|y|z" : "");
                *index = (uint32_t)i;
                *component = comp;
                return CLVR_OK;
            }
        }
    }
    char list[700];
    size_t l = 0;
    list[0] = 0;
    for (uint32_t k = 0; k < n && l + 100 < sizeof list; ++k)
        l += (size_t)snprintf(list + l, sizeof list - l, "%s%s:%s%s", k ? ", " : "",
                              fields[k].association ? "cell" : "point", fields[k].name,
                              fields[k].components > 1 ? " (vector)" : "");
    if (n == 0)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: no field named '%s': the file holds no fields", file, spec);
    return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: no field named '%s'; the file has %s%s (clvr --info %s lists them)",
                          file, spec, list, l + 100 >= sizeof list ? ", ..." : "", file);
}

clvr_status clvr_mesh_flatten_cells(clvr_mesh *m, const float *values, const char *what, clvr_error *err)
{
    uint64_t total = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) total += clvr_mesh_num_indices(m, t);
    if (total > UINT32_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "%s: --cell-data flat gives every element its own vertices: %llu corners, more than the "
                              "%u vertices clvr indexes; render the averaged field (--cell-data average)",
                              what, (unsigned long long)total, UINT32_MAX);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint64_t n = clvr_mesh_num_indices(m, t);
        for (uint64_t j = 0; j < n; ++j)
            if ((uint64_t)m->indices[t][j] >= m->num_vertices)
                return clvr_error_set(err, CLVR_ERR_BAD_INDEX,
                                      "%s: %s[%llu] vertex %u is index %u but the mesh has %llu vertices", what,
                                      clvr_cell_type_name(t), (unsigned long long)(j / clvr_cell_vertex_count(t)),
                                      (unsigned)(j % clvr_cell_vertex_count(t)), m->indices[t][j],
                                      (unsigned long long)m->num_vertices);
    }
    float *pos = NULL, *sc = NULL;
    clvr_status s = alloc_array((void **)&pos, total, 3 * sizeof(float), what, err);
    if (s == CLVR_OK) s = alloc_array((void **)&sc, total, sizeof(float), what, err);
    if (s != CLVR_OK) {
        free(pos);
        return s;
    }
    uint64_t k = 0, e = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        for (uint64_t c = 0; c < m->num_cells[t]; ++c, ++e)
            for (uint32_t j = 0; j < nv; ++j, ++k) {
                uint32_t *ix = &m->indices[t][c * nv + j];
                memcpy(pos + 3 * k, m->positions + 3 * (uint64_t)*ix, 3 * sizeof(float));
                sc[k] = values[e];
                *ix = (uint32_t)k;
            }
    }
    free(m->positions);
    free(m->scalars);
    m->positions = pos;
    m->scalars = sc;
    m->num_vertices = total;
    m->cell_flat = 1;
    clvr_mesh_update_ranges(m);
    return CLVR_OK;
}
