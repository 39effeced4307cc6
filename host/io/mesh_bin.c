/* mesh_bin.c: clvr's own .bin mesh format (docs/bin-format.md): parse from
 * memory, load with a few large reads straight into the mesh arrays, save,
 * and a streaming writer for generators that never hold a whole mesh.
 *
 * Header fields are encoded byte by byte so their layout does not depend on
 * the host; the arrays are stored little-endian and copied as they are, which
 * is why non-little-endian hosts are refused at compile time (OpenCL devices
 * clvr targets are little-endian too). */
#include "mesh_io.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "clvr .bin arrays are little-endian and copied verbatim; this host is not little-endian"
#endif

#define BIN_MAGIC "CLVRMESH"
#define BIN_MAGIC_LEN 8u
#define BIN_VERSION 1u
#define BIN_HEADER_SIZE 256u
#define BIN_OFF_VERSION 8u
#define BIN_OFF_HEADER_SIZE 12u
#define BIN_OFF_NUM_VERTICES 16u
#define BIN_OFF_NUM_CELLS 24u /* four u64, in CLVR_CELL_* order */
#define BIN_OFF_BOUNDS_LO 56u
#define BIN_OFF_BOUNDS_HI 68u
#define BIN_OFF_SCALAR_MIN 80u
#define BIN_OFF_SCALAR_MAX 84u
#define BIN_OFF_SCALAR_NAME 88u
#define BIN_OFF_FLAGS 152u

/* Number of arrays in a .bin file: positions, scalars, four index lists. */
#define BIN_ARRAY_COUNT (2u + CLVR_CELL_TYPE_COUNT)
#define BIN_ARRAY_POSITIONS 0u
#define BIN_ARRAY_SCALARS 1u
#define BIN_ARRAY_CELLS 2u /* + cell type */

/* Largest single read()/pwrite() we ask for: Linux transfers at most
 * 0x7ffff000 bytes per call anyway, so bigger requests only mean more
 * partial-transfer loops. */
#define BIN_IO_CHUNK ((size_t)1 << 30)

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t get_u64(const uint8_t *p)
{
    return (uint64_t)get_u32(p) | (uint64_t)get_u32(p + 4) << 32;
}

static void put_u32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; ++i) p[i] = (uint8_t)(v >> (8 * i));
}

static void put_u64(uint8_t *p, uint64_t v)
{
    put_u32(p, (uint32_t)v);
    put_u32(p + 4, (uint32_t)(v >> 32));
}

static void put_f32(uint8_t *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    put_u32(p, u);
}

/* Version 2 (docs/bin-format.md): the field table. */
#define BIN_VERSION_FIELDS 2u
#define BIN_OFF_NUM_FIELDS 156u
#define BIN_OFF_RESERVED2 160u
#define BIN_FIELD_ENTRY 128u
#define BIN_FIELD_OFF_ASSOC 64u
#define BIN_FIELD_OFF_COMPONENTS 68u
#define BIN_FIELD_OFF_MIN 72u
#define BIN_FIELD_OFF_MAX 76u
#define BIN_FIELD_OFF_RESERVED 80u

static float get_f32(const uint8_t *p)
{
    uint32_t u = get_u32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* What the header (and a version 2 field table) says, after validation. */
typedef struct bin_header {
    uint32_t version;
    uint64_t num_vertices;
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];
    uint64_t array_bytes[BIN_ARRAY_COUNT]; /* version 2: array_bytes[BIN_ARRAY_SCALARS] is 0 */
    uint64_t file_size; /* what the file size must be */
    char scalar_name[CLVR_SCALAR_NAME_MAX];
    uint32_t num_fields;
    uint64_t table_offset;
    clvr_field_info *fields;    /* version 2: num_fields entries (malloc) */
    uint64_t *field_offset;     /* byte offset of each field's data */
} bin_header;

static void bin_header_free(bin_header *hd)
{
    free(hd->fields);
    free(hd->field_offset);
    hd->fields = NULL;
    hd->field_offset = NULL;
}

/* Byte sizes of the arrays and the file size up to the end of the last
 * index list (version 2: where the field table starts); nonzero on 64-bit
 * overflow. */
static int bin_sizes_v(uint32_t version, uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                       uint64_t bytes[BIN_ARRAY_COUNT], uint64_t *file_size)
{
    uint64_t total = BIN_HEADER_SIZE;
    if (clvr_mul_u64(num_vertices, 3u * sizeof(float), &bytes[BIN_ARRAY_POSITIONS])) return 1;
    if (version == BIN_VERSION_FIELDS) bytes[BIN_ARRAY_SCALARS] = 0;
    else if (clvr_mul_u64(num_vertices, sizeof(float), &bytes[BIN_ARRAY_SCALARS])) return 1;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        if (clvr_mul_u64(num_cells[t], clvr_cell_vertex_count(t) * sizeof(uint32_t), &bytes[BIN_ARRAY_CELLS + t]))
            return 1;
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT; ++a)
        if (clvr_add_u64(total, bytes[a], &total)) return 1;
    *file_size = total;
    return 0;
}

static int bin_sizes(uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                     uint64_t bytes[BIN_ARRAY_COUNT], uint64_t *file_size)
{
    return bin_sizes_v(BIN_VERSION, num_vertices, num_cells, bytes, file_size);
}

static const char *bin_array_name(uint32_t a)
{
    return a == BIN_ARRAY_POSITIONS ? "positions" : a == BIN_ARRAY_SCALARS ? "scalars"
                                                                           : clvr_cell_type_name(a - BIN_ARRAY_CELLS);
}

/* A file in memory or behind a descriptor: the reader below serves both
 * clvr_mesh_parse_bin (fuzzing) and clvr_mesh_load_bin with one code path. */
typedef struct bin_src {
    const uint8_t *mem; /* NULL: read from fd */
    int fd;
    uint64_t size;
    const char *name;
} bin_src;

/* Reads n bytes at offset (the caller has checked offset + n <= size). */
static clvr_status src_read(const bin_src *src, uint64_t offset, void *dst, uint64_t n, const char *what,
                            clvr_error *err)
{
    if (n == 0) return CLVR_OK;
    if (src->mem) {
        memcpy(dst, src->mem + offset, (size_t)n);
        return CLVR_OK;
    }
    uint8_t *p = (uint8_t *)dst;
    while (n > 0) {
        size_t want = n < BIN_IO_CHUNK ? (size_t)n : BIN_IO_CHUNK;
        if (offset > (uint64_t)INT64_MAX)
            return clvr_error_set(err, CLVR_ERR_IO, "%s: offset %llu is beyond what the OS can address", src->name,
                                  (unsigned long long)offset);
        ssize_t got = pread(src->fd, p, want, (off_t)offset);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0)
            return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot read %s: %s", src->name, what, strerror(errno));
        if (got == 0)
            return clvr_error_set(err, CLVR_ERR_TRUNCATED, "%s: truncated while reading %s (the file shrank?)",
                                  src->name, what);
        p += got;
        n -= (uint64_t)got;
        offset += (uint64_t)got;
    }
    return CLVR_OK;
}

/* Validates the version 2 field table at hd->table_offset and sets
 * hd->fields, hd->field_offset and hd->file_size. */
static clvr_status bin_read_fields(const bin_src *src, bin_header *hd, clvr_error *err)
{
    const char *name = src->name;
    uint64_t table_bytes = (uint64_t)hd->num_fields * BIN_FIELD_ENTRY, end;
    if (clvr_add_u64(hd->table_offset, table_bytes, &end) || end > src->size)
        return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                              "%s: truncated: the field table of %u fields ends at byte %llu but the file has %llu",
                              name, hd->num_fields, (unsigned long long)(hd->table_offset + table_bytes),
                              (unsigned long long)src->size);
    uint8_t *table = malloc(table_bytes ? (size_t)table_bytes : 1);
    hd->fields = calloc(hd->num_fields ? hd->num_fields : 1, sizeof *hd->fields);
    hd->field_offset = calloc(hd->num_fields ? hd->num_fields : 1, sizeof *hd->field_offset);
    if (!table || !hd->fields || !hd->field_offset) {
        free(table);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the field table", name);
    }
    clvr_status s = src_read(src, hd->table_offset, table, table_bytes, "the field table", err);
    uint64_t num_elements = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) num_elements += hd->num_cells[t]; /* sizes checked: no overflow */
    uint64_t off = end;
    for (uint32_t i = 0; i < hd->num_fields && s == CLVR_OK; ++i) {
        const uint8_t *e = table + (uint64_t)i * BIN_FIELD_ENTRY;
        clvr_field_info *f = &hd->fields[i];
        if (memchr(e, '\0', CLVR_SCALAR_NAME_MAX) == NULL || e[0] == 0) {
            s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: field %u: the name is %s", name, i,
                               e[0] ? "not NUL-terminated within its 64 bytes" : "empty");
            break;
        }
        clvr_mesh tmp; /* reuse the name sanitizer */
        clvr_mesh_set_scalar_name(&tmp, (const char *)e, CLVR_SCALAR_NAME_MAX);
        memcpy(f->name, tmp.scalar_name, CLVR_SCALAR_NAME_MAX);
        f->association = get_u32(e + BIN_FIELD_OFF_ASSOC);
        f->components = get_u32(e + BIN_FIELD_OFF_COMPONENTS);
        f->min = get_f32(e + BIN_FIELD_OFF_MIN);
        f->max = get_f32(e + BIN_FIELD_OFF_MAX);
        f->has_range = 1;
        int reserved = 0;
        for (uint32_t k = BIN_FIELD_OFF_RESERVED; k < BIN_FIELD_ENTRY; ++k) reserved |= e[k];
        if (f->association > CLVR_FIELD_CELL)
            s = clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                               "%s: field %u '%s': association is %u but must be 0 (point) or 1 (cell)", name, i,
                               f->name, f->association);
        else if (f->components < 1 || f->components > CLVR_FIELD_COMPONENTS_MAX)
            s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: field %u '%s': %u components, outside 1..%u", name, i,
                               f->name, f->components, CLVR_FIELD_COMPONENTS_MAX);
        else if (reserved)
            s = clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                               "%s: field %u '%s': reserved bytes are not zero; the file comes from a newer writer",
                               name, i, f->name);
        for (uint32_t j = 0; j < i && s == CLVR_OK; ++j)
            if (hd->fields[j].association == f->association && !strcmp(hd->fields[j].name, f->name))
                s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: fields %u and %u are both %s data named '%s'", name,
                                   j, i, f->association ? "cell" : "point", f->name);
        if (s != CLVR_OK) break;
        uint64_t bytes;
        uint64_t count = f->association == CLVR_FIELD_POINT ? hd->num_vertices : num_elements;
        if (clvr_mul_u64(count, (uint64_t)f->components * sizeof(float), &bytes) || clvr_add_u64(off, bytes, &end)) {
            s = clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: field %u '%s' overflows 64-bit file sizes", name, i, f->name);
            break;
        }
        hd->field_offset[i] = off;
        off = end;
    }
    free(table);
    hd->file_size = off;
    return s;
}

/* Validates the header against the file size (and reads a version 2 field
 * table). Every failure names the file, the field and both values. */
static clvr_status bin_read_header(const bin_src *src, bin_header *out, clvr_error *err)
{
    uint8_t h[BIN_HEADER_SIZE];
    const char *name = src->name;
    uint64_t have = src->size < BIN_HEADER_SIZE ? src->size : BIN_HEADER_SIZE;
    memset(out, 0, sizeof *out);
    clvr_status s = src_read(src, 0, h, have, "the header", err);
    if (s != CLVR_OK) return s;
    size_t cmp = have < BIN_MAGIC_LEN ? (size_t)have : BIN_MAGIC_LEN;
    if (memcmp(h, BIN_MAGIC, cmp) != 0)
        return clvr_error_set(err, CLVR_ERR_BAD_MAGIC,
                              "%s: not a clvr .bin file (the first 8 bytes are not \"CLVRMESH\"); "
                              "convert it with clvr-convert", name);
    if (have < BIN_HEADER_SIZE)
        return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                              "%s: truncated: the file has %llu bytes but the .bin header alone is %u bytes", name,
                              (unsigned long long)src->size, BIN_HEADER_SIZE);
    uint32_t version = get_u32(h + BIN_OFF_VERSION);
    if (version != BIN_VERSION && version != BIN_VERSION_FIELDS)
        return clvr_error_set(err, CLVR_ERR_BAD_VERSION,
                              "%s: .bin version is %u but this clvr reads versions 1 and 2; re-convert the mesh "
                              "with this clvr's clvr-convert", name, version);
    out->version = version;
    uint32_t header_size = get_u32(h + BIN_OFF_HEADER_SIZE);
    if (header_size != BIN_HEADER_SIZE)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: header_size is %u but version %u requires %u", name,
                              header_size, version, BIN_HEADER_SIZE);
    uint32_t flags = get_u32(h + BIN_OFF_FLAGS);
    if (flags != 0)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s: flags is 0x%x but version %u defines none; the file comes from a newer writer",
                              name, flags, version);
    const char *sname = (const char *)h + BIN_OFF_SCALAR_NAME;
    if (memchr(sname, '\0', CLVR_SCALAR_NAME_MAX) == NULL)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s: scalar_name is not NUL-terminated within its %d bytes", name,
                              CLVR_SCALAR_NAME_MAX);
    memcpy(out->scalar_name, sname, CLVR_SCALAR_NAME_MAX);
    if (version == BIN_VERSION_FIELDS) {
        int reserved = 0;
        for (uint32_t k = BIN_OFF_RESERVED2; k < BIN_HEADER_SIZE; ++k) reserved |= h[k];
        out->num_fields = get_u32(h + BIN_OFF_NUM_FIELDS);
        if (out->num_fields > CLVR_FIELD_COUNT_MAX)
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: num_fields is %u; a .bin holds at most %u", name,
                                  out->num_fields, CLVR_FIELD_COUNT_MAX);
        if (reserved)
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                  "%s: reserved header bytes are not zero; the file comes from a newer writer", name);
    }

    out->num_vertices = get_u64(h + BIN_OFF_NUM_VERTICES);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) out->num_cells[t] = get_u64(h + BIN_OFF_NUM_CELLS + 8 * t);
    uint64_t num_elements = 0;
    int over = bin_sizes_v(version, out->num_vertices, out->num_cells, out->array_bytes, &out->file_size);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && !over; ++t)
        over = clvr_add_u64(num_elements, out->num_cells[t], &num_elements);
    if (over)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "%s: header counts (%llu vertices, %llu tets, %llu pyramids, %llu wedges, %llu hexes) "
                              "overflow 64-bit byte sizes; the header is corrupt",
                              name, (unsigned long long)out->num_vertices, (unsigned long long)out->num_cells[0],
                              (unsigned long long)out->num_cells[1], (unsigned long long)out->num_cells[2],
                              (unsigned long long)out->num_cells[3]);
    if (out->num_vertices > UINT32_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "%s: num_vertices is %llu but vertex indices are 32-bit (at most %u vertices)", name,
                              (unsigned long long)out->num_vertices, UINT32_MAX);
    if (version == BIN_VERSION_FIELDS) {
        out->table_offset = out->file_size;
        s = bin_read_fields(src, out, err);
        if (s != CLVR_OK) {
            bin_header_free(out);
            return s;
        }
    }
    if (src->size < out->file_size)
        s = clvr_error_set(err, CLVR_ERR_TRUNCATED,
                           "%s: truncated: the header's counts need %llu bytes but the file has %llu", name,
                           (unsigned long long)out->file_size, (unsigned long long)src->size);
    else if (src->size > out->file_size)
        s = clvr_error_set(err, CLVR_ERR_FORMAT,
                           "%s: %llu trailing bytes: the header's counts need %llu bytes but the file has %llu",
                           name, (unsigned long long)(src->size - out->file_size),
                           (unsigned long long)out->file_size, (unsigned long long)src->size);
    if (s != CLVR_OK) bin_header_free(out);
    return s;
}

static void *bin_array_ptr(clvr_mesh *m, uint32_t a)
{
    return a == BIN_ARRAY_POSITIONS ? (void *)m->positions
         : a == BIN_ARRAY_SCALARS   ? (void *)m->scalars
                                    : (void *)m->indices[a - BIN_ARRAY_CELLS];
}

/* Version 2: the chosen field into m->scalars, one value per vertex: a
 * component or the magnitude of each tuple, and cell data averaged over the
 * elements that use each vertex (vertices no element uses get 0), as
 * docs/bin-format.md says. */
static clvr_status bin_read_field(const bin_src *src, const bin_header *hd, uint32_t fi, int comp, clvr_mesh *m,
                                  float *cellv, clvr_error *err)
{
    const clvr_field_info *f = &hd->fields[fi];
    const uint32_t nc = f->components;
    uint64_t count = f->association == CLVR_FIELD_POINT ? m->num_vertices : clvr_mesh_num_elements(m);
    if (f->association == CLVR_FIELD_POINT && nc == 1)
        return src_read(src, hd->field_offset[fi], m->scalars, count * sizeof(float), f->name, err);
    /* A chunk of tuples at a time keeps the scratch small on huge meshes. */
    const uint64_t chunk = 1u << 16;
    float *buf = malloc((size_t)(chunk * nc * sizeof(float)));
    double *acc = NULL;
    uint32_t *cnt = NULL;
    if (f->association == CLVR_FIELD_CELL && !cellv) {
        size_t nv = m->num_vertices ? (size_t)m->num_vertices : 1;
        acc = calloc(nv, sizeof *acc);
        cnt = calloc(nv, sizeof *cnt);
    }
    clvr_status s = CLVR_OK;
    if (!buf || (f->association == CLVR_FIELD_CELL && !cellv && (!acc || !cnt)))
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate scratch to read field '%s'", src->name,
                           f->name);
    uint32_t t = 0;
    uint64_t in_type = 0; /* element within type t */
    for (uint64_t i0 = 0; i0 < count && s == CLVR_OK; i0 += chunk) {
        uint64_t n = count - i0 < chunk ? count - i0 : chunk;
        s = src_read(src, hd->field_offset[fi] + i0 * nc * sizeof(float), buf, n * nc * sizeof(float), f->name, err);
        for (uint64_t j = 0; j < n && s == CLVR_OK; ++j) {
            const float *tup = buf + j * nc;
            double v;
            if (comp >= 0) v = tup[comp];
            else if (nc == 1) v = tup[0];
            else {
                double s2 = 0.0;
                for (uint32_t k = 0; k < nc; ++k) s2 += (double)tup[k] * tup[k];
                v = sqrt(s2);
            }
            if (f->association == CLVR_FIELD_POINT) {
                m->scalars[i0 + j] = (float)v;
                continue;
            }
            if (cellv) { /* --cell-data flat: the element's own value */
                cellv[i0 + j] = (float)v;
                continue;
            }
            while (in_type >= m->num_cells[t]) {
                ++t;
                in_type = 0;
            }
            const uint32_t nv = clvr_cell_vertex_count(t);
            const uint32_t *idx = m->indices[t] + in_type * nv;
            for (uint32_t k = 0; k < nv; ++k)
                if (idx[k] < m->num_vertices) { /* bad indices are reported by validation */
                    acc[idx[k]] += v;
                    cnt[idx[k]] += 1;
                }
            ++in_type;
        }
    }
    if (s == CLVR_OK && f->association == CLVR_FIELD_CELL && !cellv)
        for (uint64_t i = 0; i < m->num_vertices; ++i) m->scalars[i] = cnt[i] ? (float)(acc[i] / cnt[i]) : 0.0f;
    free(buf);
    free(acc);
    free(cnt);
    return s;
}

/* Sets ranges and runs the validation unless the caller skips it. */
static clvr_status bin_finish(clvr_mesh *m, const char *name, const clvr_load_options *opt, clvr_error *err)
{
    clvr_mesh_update_ranges(m);
    if (m->num_fields) {
        clvr_field_info *f = &m->fields[m->scalar_field];
        if (f->components == 1 || m->scalar_component == CLVR_FIELD_MAGNITUDE) {
            if (f->association == CLVR_FIELD_POINT) { /* the table's range is informative: use the values' */
                f->min = m->scalar_min;
                f->max = m->scalar_max;
            }
        }
    }
    if (opt && opt->skip_validation) return CLVR_OK;
    clvr_status s = clvr_mesh_validate(m, name, err);
    if (s != CLVR_OK) clvr_mesh_free(m);
    return s;
}

/* Maps the file's arrays up to the end of the last index list (one
 * read-only private mapping from the file's start) and points m->indices,
 * and with map_vertices m->positions (and a version 1 file's m->scalars),
 * into it (m->map_base). With map_vertices, m comes without vertex arrays
 * (clvr_mesh_alloc of 0 vertices): the counts are set here, and the
 * scalars of a version 2 file, which are read from its fields, allocated.
 * The header has been checked against the file's
 * size, so every array lies inside the file. A file truncated by someone
 * else while mapped would fault (SIGBUS) on access: clvr's own files are
 * written under a temporary name and renamed when complete, so they are
 * never shortened in place. */
static clvr_status bin_map_arrays(const bin_src *src, const bin_header *hd, int map_vertices, clvr_mesh *m,
                                  clvr_error *err)
{
    uint64_t end = BIN_HEADER_SIZE;
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT; ++a) end += hd->array_bytes[a];
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) m->num_cells[t] = hd->num_cells[t];
    if (end > (uint64_t)SIZE_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: %.3f GB of arrays exceed the address space", src->name,
                              (double)end / 1e9);
    void *p = mmap(NULL, (size_t)end, PROT_READ, MAP_PRIVATE, src->fd, 0);
    if (p == MAP_FAILED)
        return clvr_error_set(err, errno == ENOMEM ? CLVR_ERR_NO_MEMORY : CLVR_ERR_IO,
                              "%s: cannot map its %.3f GB of arrays: %s (raise ulimit -v, or free address space)",
                              src->name, (double)end / 1e9, strerror(errno));
    /* Read ahead in big steps: the passes over the lists are sequential. */
    madvise(p, (size_t)end, MADV_SEQUENTIAL);
    m->map_base = p;
    m->map_bytes = end;
    uint64_t off = BIN_HEADER_SIZE;
    if (map_vertices) {
        m->num_vertices = hd->num_vertices;
        m->positions = hd->num_vertices ? (float *)((uint8_t *)p + off) : NULL;
        if (hd->array_bytes[BIN_ARRAY_SCALARS])
            m->scalars = (float *)((uint8_t *)p + off + hd->array_bytes[BIN_ARRAY_POSITIONS]);
        else if (hd->num_vertices && !(m->scalars = malloc((size_t)hd->num_vertices * sizeof(float))))
            /* (no overflow: the positions, 3 floats a vertex, fit in the mapping) */
            return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %.3f GB of scalars", src->name,
                                  (double)hd->num_vertices * sizeof(float) / 1e9);
    }
    off += hd->array_bytes[BIN_ARRAY_POSITIONS] + hd->array_bytes[BIN_ARRAY_SCALARS];
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        m->indices[t] = hd->num_cells[t] ? (uint32_t *)((uint8_t *)p + off) : NULL;
        off += hd->array_bytes[BIN_ARRAY_CELLS + t];
    }
    return CLVR_OK;
}

/* The reader behind clvr_mesh_parse_bin and clvr_mesh_load_bin. */
static clvr_status bin_load(const bin_src *src, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err)
{
    bin_header hd;
    const char *name = src->name;
    const char *spec = opt ? opt->scalar_name : NULL;
    uint32_t fi = 0;
    int comp = CLVR_FIELD_MAGNITUDE;
    clvr_status s = bin_read_header(src, &hd, err);
    if (s != CLVR_OK) return s;
    if (hd.version == BIN_VERSION) {
        /* Version 1 holds one point scalar: a table of one for the selection. */
        clvr_field_info one;
        memset(&one, 0, sizeof one);
        clvr_mesh tmp;
        clvr_mesh_set_scalar_name(&tmp, hd.scalar_name, CLVR_SCALAR_NAME_MAX);
        memcpy(one.name, tmp.scalar_name, sizeof one.name);
        one.components = 1;
        if (spec && spec[0] && strcmp(spec, hd.scalar_name) != 0) {
            s = clvr_field_select(&one, 1, spec, name, &fi, &comp, err);
            if (s == CLVR_OK && comp >= 1) /* "name:0" is the scalar itself */
                s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: no scalar named '%s'", name, spec);
            if (s != CLVR_OK) {
                /* The old message said what a version 1 file holds. */
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                      "%s: no scalar named '%s'; a version 1 .bin holds one scalar, here '%s' "
                                      "(re-convert with clvr-convert to keep every field)",
                                      name, spec, hd.scalar_name);
            }
        }
    } else {
        s = clvr_field_select(hd.fields, hd.num_fields, spec, name, &fi, &comp, err);
        if (s != CLVR_OK && hd.num_fields == 0 && !(spec && spec[0])) s = CLVR_OK; /* no field: scalars 0 */
        if (s != CLVR_OK) {
            bin_header_free(&hd);
            return s;
        }
    }
    /* Mapped index lists (opt->map_indices): a file, not --cell-data flat
     * of a cell field (which rewrites the lists). */
    const int flat_cells = opt && opt->cell_flat && hd.version == BIN_VERSION_FIELDS && hd.num_fields &&
                           hd.fields[fi].association == CLVR_FIELD_CELL;
    const int map = opt && opt->map_indices && src->fd >= 0 && !flat_cells;
    if (map) {
        /* Mapped vertices are not allocated (bin_map_arrays sets them):
         * allocating them to free them at once cost a transient copy of
         * their size. */
        const uint64_t none[CLVR_CELL_TYPE_COUNT] = {0};
        s = clvr_mesh_alloc(out, opt->map_vertices ? 0 : hd.num_vertices, none, err);
        if (s == CLVR_OK) s = bin_map_arrays(src, &hd, opt->map_vertices, out, err);
    } else {
        s = clvr_mesh_alloc(out, hd.num_vertices, hd.num_cells, err);
    }
    uint64_t off = BIN_HEADER_SIZE;
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT && s == CLVR_OK; ++a) {
        if (!(map && (a >= BIN_ARRAY_CELLS || (opt->map_vertices && a <= BIN_ARRAY_SCALARS))))
            s = src_read(src, off, bin_array_ptr(out, a), hd.array_bytes[a], bin_array_name(a), err);
        off += hd.array_bytes[a];
    }
    if (s == CLVR_OK && hd.version == BIN_VERSION) {
        clvr_mesh_set_scalar_name(out, hd.scalar_name, CLVR_SCALAR_NAME_MAX);
    } else if (s == CLVR_OK && hd.num_fields == 0) {
        if (out->num_vertices) memset(out->scalars, 0, (size_t)out->num_vertices * sizeof(float));
    } else if (s == CLVR_OK) {
        float *cellv = NULL;
        const int flat = opt && opt->cell_flat && hd.fields[fi].association == CLVR_FIELD_CELL;
        uint64_t ne = clvr_mesh_num_elements(out);
        if (flat && (ne > SIZE_MAX / sizeof(float) || !(cellv = malloc(ne ? (size_t)ne * sizeof(float) : 1))))
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %llu cell values", name,
                               (unsigned long long)ne);
        if (s == CLVR_OK) s = bin_read_field(src, &hd, fi, comp, out, cellv, err);
        if (s == CLVR_OK && flat) s = clvr_mesh_flatten_cells(out, cellv, name, err);
        free(cellv);
        if (s == CLVR_OK) {
            const clvr_field_info *f = &hd.fields[fi];
            char label[CLVR_SCALAR_NAME_MAX + 16];
            static const char xyz[] = "xyz";
            if (comp >= 0 && f->components > 1) {
                if (comp < 3) snprintf(label, sizeof label, "%s:%c", f->name, xyz[comp]);
                else snprintf(label, sizeof label, "%s:%d", f->name, comp);
            } else {
                snprintf(label, sizeof label, "%s", f->name);
            }
            clvr_mesh_set_scalar_name(out, label, strlen(label));
            out->fields = hd.fields;
            hd.fields = NULL;
            out->num_fields = hd.num_fields;
            out->scalar_field = fi;
            out->scalar_component = comp;
        }
    }
    bin_header_free(&hd);
    if (s != CLVR_OK) {
        clvr_mesh_free(out);
        return s;
    }
    return bin_finish(out, name, opt, err);
}

clvr_status clvr_mesh_parse_bin(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                clvr_mesh *out, clvr_error *err)
{
    memset(out, 0, sizeof *out);
    if (!data && size) return clvr_error_set(err, CLVR_ERR_INTERNAL, "%s: NULL buffer", name);
    static const uint8_t empty[1] = {0};
    bin_src src = {data ? (const uint8_t *)data : empty, -1, (uint64_t)size, name};
    return bin_load(&src, opt, out, err);
}

clvr_status clvr_mesh_load_bin(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err)
{
    struct stat st;
    clvr_status s;
    memset(out, 0, sizeof *out);
    int fd = open(path, O_RDONLY);
    if (fd < 0) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0) {
        s = clvr_error_set(err, CLVR_ERR_IO, "%s: cannot stat: %s", path, strerror(errno));
    } else if (!S_ISREG(st.st_mode)) {
        s = clvr_error_set(err, CLVR_ERR_IO, "%s: is %s, not a mesh file", path,
                           S_ISDIR(st.st_mode) ? "a directory" : "not a regular file");
    } else {
        bin_src src = {NULL, fd, (uint64_t)st.st_size, path};
        s = bin_load(&src, opt, out, err);
    }
    close(fd);
    return s;
}

/* ------------------------------------------------------------ writer */

struct clvr_bin_writer {
    int fd;
    char *path;     /* target */
    char *tmp_path; /* "<path>.tmp.<pid>" */
    uint64_t num_vertices;
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];
    uint64_t array_bytes[BIN_ARRAY_COUNT];
    uint64_t array_offset[BIN_ARRAY_COUNT];
    uint64_t written[BIN_ARRAY_COUNT]; /* bytes of each array written so far */
    float lo[3], hi[3], smin, smax;    /* running ranges, patched into the header at close */
    uint8_t header[BIN_HEADER_SIZE];
};

static clvr_status pwrite_full(clvr_bin_writer *w, const void *src, uint64_t n, uint64_t offset, const char *what,
                               clvr_error *err)
{
    const uint8_t *p = (const uint8_t *)src;
    while (n > 0) {
        size_t want = n < BIN_IO_CHUNK ? (size_t)n : BIN_IO_CHUNK;
        if (offset > (uint64_t)INT64_MAX)
            return clvr_error_set(err, CLVR_ERR_WRITE, "%s: offset %llu is beyond what the OS can address",
                                  w->tmp_path, (unsigned long long)offset);
        ssize_t put = pwrite(w->fd, p, want, (off_t)offset);
        if (put < 0 && errno == EINTR) continue;
        if (put <= 0)
            return clvr_error_set(err, CLVR_ERR_WRITE, "%s: cannot write %s: %s", w->tmp_path, what,
                                  put < 0 ? strerror(errno) : "no progress");
        p += put;
        n -= (uint64_t)put;
        offset += (uint64_t)put;
    }
    return CLVR_OK;
}

void clvr_bin_writer_abort(clvr_bin_writer *w)
{
    if (!w) return;
    if (w->fd >= 0) close(w->fd);
    if (w->tmp_path) unlink(w->tmp_path);
    free(w->path);
    free(w->tmp_path);
    free(w);
}

clvr_status clvr_bin_writer_open(const char *path, uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                                 const char *scalar_name, clvr_bin_writer **out, clvr_error *err)
{
    clvr_status s;
    uint64_t file_size;
    *out = NULL;
    if (!scalar_name) scalar_name = "";
    if (strlen(scalar_name) >= CLVR_SCALAR_NAME_MAX)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: scalar name '%s' is longer than %d characters", path,
                              scalar_name, CLVR_SCALAR_NAME_MAX - 1);
    if (num_vertices > UINT32_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: %llu vertices but indices are 32-bit (at most %u)", path,
                              (unsigned long long)num_vertices, UINT32_MAX);
    clvr_bin_writer *w = calloc(1, sizeof *w);
    if (!w) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the .bin writer", path);
    w->fd = -1;
    if (bin_sizes(num_vertices, num_cells, w->array_bytes, &file_size)) {
        s = clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: the mesh counts overflow 64-bit file sizes", path);
        goto fail;
    }
    w->num_vertices = num_vertices;
    memcpy(w->num_cells, num_cells, sizeof w->num_cells);
    uint64_t off = BIN_HEADER_SIZE;
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT; ++a) {
        w->array_offset[a] = off;
        off += w->array_bytes[a];
    }
    for (int k = 0; k < 3; ++k) {
        w->lo[k] = INFINITY;
        w->hi[k] = -INFINITY;
    }
    w->smin = INFINITY;
    w->smax = -INFINITY;

    size_t plen = strlen(path);
    w->path = malloc(plen + 1);
    w->tmp_path = malloc(plen + 32);
    if (!w->path || !w->tmp_path) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the .bin writer", path);
        goto fail;
    }
    memcpy(w->path, path, plen + 1);
    snprintf(w->tmp_path, plen + 32, "%s.tmp.%ld", path, (long)getpid());
    w->fd = open(w->tmp_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (w->fd < 0) {
        s = clvr_error_set(err, CLVR_ERR_WRITE, "%s: cannot create: %s", w->tmp_path, strerror(errno));
        free(w->tmp_path); /* nothing to remove */
        w->tmp_path = NULL;
        goto fail;
    }
    uint8_t *h = w->header;
    memcpy(h, BIN_MAGIC, BIN_MAGIC_LEN);
    put_u32(h + BIN_OFF_VERSION, BIN_VERSION);
    put_u32(h + BIN_OFF_HEADER_SIZE, BIN_HEADER_SIZE);
    put_u64(h + BIN_OFF_NUM_VERTICES, num_vertices);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) put_u64(h + BIN_OFF_NUM_CELLS + 8 * t, num_cells[t]);
    memcpy(h + BIN_OFF_SCALAR_NAME, scalar_name, strlen(scalar_name));
    s = pwrite_full(w, h, BIN_HEADER_SIZE, 0, "the header", err);
    if (s != CLVR_OK) goto fail;
    /* Sizing the file now makes out-of-order array writes cheap and reports
     * a full disk here rather than after hours of generating (where the file
     * system refuses sparse files, writes will still report it). */
    if (ftruncate(w->fd, (off_t)file_size) != 0) {
        s = clvr_error_set(err, CLVR_ERR_WRITE, "%s: cannot size the file to %llu bytes: %s", w->tmp_path,
                           (unsigned long long)file_size, strerror(errno));
        goto fail;
    }
    *out = w;
    return CLVR_OK;
fail:
    clvr_bin_writer_abort(w);
    return s;
}

/* Appends n items of `item` bytes to array a, after checking they fit. */
static clvr_status writer_append(clvr_bin_writer *w, uint32_t a, const void *src, uint64_t n, uint64_t item,
                                 clvr_error *err)
{
    uint64_t bytes, end;
    if (!w) return clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr_bin_writer: NULL writer");
    if (clvr_mul_u64(n, item, &bytes) || clvr_add_u64(w->written[a], bytes, &end) || end > w->array_bytes[a])
        return clvr_error_set(err, CLVR_ERR_INTERNAL,
                              "%s: %s: appending %llu items exceeds the %llu the writer was opened with", w->path,
                              bin_array_name(a), (unsigned long long)n,
                              (unsigned long long)(w->array_bytes[a] / item));
    if (bytes && !src) return clvr_error_set(err, CLVR_ERR_INTERNAL, "%s: %s: NULL data", w->path, bin_array_name(a));
    clvr_status s = pwrite_full(w, src, bytes, w->array_offset[a] + w->written[a], bin_array_name(a), err);
    if (s == CLVR_OK) w->written[a] = end;
    return s;
}

clvr_status clvr_bin_writer_positions(clvr_bin_writer *w, const float *xyz, uint64_t num_vertices, clvr_error *err)
{
    clvr_status s = writer_append(w, BIN_ARRAY_POSITIONS, xyz, num_vertices, 3 * sizeof(float), err);
    if (s != CLVR_OK) return s;
    for (uint64_t i = 0; i < num_vertices; ++i)
        for (int k = 0; k < 3; ++k) {
            float v = xyz[3 * i + k];
            w->lo[k] = v < w->lo[k] ? v : w->lo[k];
            w->hi[k] = v > w->hi[k] ? v : w->hi[k];
        }
    return CLVR_OK;
}

clvr_status clvr_bin_writer_scalars(clvr_bin_writer *w, const float *sc, uint64_t num_vertices, clvr_error *err)
{
    clvr_status s = writer_append(w, BIN_ARRAY_SCALARS, sc, num_vertices, sizeof(float), err);
    if (s != CLVR_OK) return s;
    for (uint64_t i = 0; i < num_vertices; ++i) {
        w->smin = sc[i] < w->smin ? sc[i] : w->smin;
        w->smax = sc[i] > w->smax ? sc[i] : w->smax;
    }
    return CLVR_OK;
}

clvr_status clvr_bin_writer_cells(clvr_bin_writer *w, uint32_t type, const uint32_t *idx, uint64_t num_cells,
                                  clvr_error *err)
{
    if (type >= CLVR_CELL_TYPE_COUNT)
        return clvr_error_set(err, CLVR_ERR_INTERNAL, "%s: cell type %u is not one of the four", w ? w->path : "?",
                              type);
    return writer_append(w, BIN_ARRAY_CELLS + type, idx, num_cells, clvr_cell_vertex_count(type) * sizeof(uint32_t),
                         err);
}

clvr_status clvr_bin_writer_close(clvr_bin_writer *w, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (!w) return clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr_bin_writer_close: NULL writer");
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT; ++a)
        if (w->written[a] != w->array_bytes[a]) {
            s = clvr_error_set(err, CLVR_ERR_INTERNAL, "%s: %s incomplete: %llu of %llu bytes written", w->path,
                               bin_array_name(a), (unsigned long long)w->written[a],
                               (unsigned long long)w->array_bytes[a]);
            goto fail;
        }
    /* Same ranges as clvr_mesh_update_ranges gives, zeros for no vertices. */
    uint8_t *h = w->header;
    for (int k = 0; k < 3; ++k) {
        put_f32(h + BIN_OFF_BOUNDS_LO + 4 * k, w->num_vertices ? w->lo[k] : 0.0f);
        put_f32(h + BIN_OFF_BOUNDS_HI + 4 * k, w->num_vertices ? w->hi[k] : 0.0f);
    }
    put_f32(h + BIN_OFF_SCALAR_MIN, w->num_vertices ? w->smin : 0.0f);
    put_f32(h + BIN_OFF_SCALAR_MAX, w->num_vertices ? w->smax : 0.0f);
    s = pwrite_full(w, h + BIN_OFF_BOUNDS_LO, BIN_OFF_SCALAR_NAME - BIN_OFF_BOUNDS_LO, BIN_OFF_BOUNDS_LO,
                    "the header ranges", err);
    if (s != CLVR_OK) goto fail;
    /* Data must be on disk before the rename makes it the file at `path`. */
    if (fsync(w->fd) != 0) {
        s = clvr_error_set(err, CLVR_ERR_WRITE, "%s: fsync failed: %s", w->tmp_path, strerror(errno));
        goto fail;
    }
    int rc = close(w->fd);
    w->fd = -1;
    if (rc != 0) {
        s = clvr_error_set(err, CLVR_ERR_WRITE, "%s: close failed: %s", w->tmp_path, strerror(errno));
        goto fail;
    }
    if (rename(w->tmp_path, w->path) != 0) {
        s = clvr_error_set(err, CLVR_ERR_WRITE, "%s: cannot rename %s onto it: %s", w->path, w->tmp_path,
                           strerror(errno));
        goto fail;
    }
    free(w->tmp_path);
    w->tmp_path = NULL; /* renamed: nothing left to remove */
fail:
    clvr_bin_writer_abort(w);
    return s;
}

clvr_status clvr_mesh_save_bin(const char *path, const clvr_mesh *m, clvr_error *err)
{
    clvr_bin_writer *w = NULL;
    clvr_status s = clvr_bin_writer_open(path, m->num_vertices, m->num_cells, m->scalar_name, &w, err);
    if (s == CLVR_OK) s = clvr_bin_writer_positions(w, m->positions, m->num_vertices, err);
    if (s == CLVR_OK) s = clvr_bin_writer_scalars(w, m->scalars, m->num_vertices, err);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t)
        s = clvr_bin_writer_cells(w, t, m->indices[t], m->num_cells[t], err);
    if (s != CLVR_OK) {
        clvr_bin_writer_abort(w);
        return s;
    }
    return clvr_bin_writer_close(w, err);
}

clvr_status clvr_mesh_peek_bin(const char *path, uint64_t *num_vertices, uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                               clvr_error *err)
{
    bin_header hd;
    struct stat st;
    clvr_status s;
    int fd = open(path, O_RDONLY);
    if (fd < 0) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        s = clvr_error_set(err, CLVR_ERR_IO, "%s: not a regular file", path);
        goto done;
    }
    {
        const bin_src src = {NULL, fd, (uint64_t)st.st_size, path};
        s = bin_read_header(&src, &hd, err);
    }
    if (s == CLVR_OK) {
        *num_vertices = hd.num_vertices;
        memcpy(num_cells, hd.num_cells, sizeof hd.num_cells);
        bin_header_free(&hd); /* version 2: the field table */
    }
done:
    close(fd);
    return s;
}

/* ------------------------------------------------------------ layout */

/* The field selection of bin_load, for clvr_mesh_bin_layout: the same
 * rules and messages (kept beside it rather than shared so that this
 * addition leaves bin_load untouched). */
static clvr_status layout_select(const bin_header *hd, const char *name, const char *spec, uint32_t *fi, int *comp,
                                 clvr_error *err)
{
    *fi = 0;
    *comp = CLVR_FIELD_MAGNITUDE;
    if (hd->version == BIN_VERSION) {
        if (!(spec && spec[0] && strcmp(spec, hd->scalar_name) != 0)) return CLVR_OK;
        clvr_field_info one;
        memset(&one, 0, sizeof one);
        clvr_mesh tmp;
        clvr_mesh_set_scalar_name(&tmp, hd->scalar_name, CLVR_SCALAR_NAME_MAX);
        memcpy(one.name, tmp.scalar_name, sizeof one.name);
        one.components = 1;
        clvr_status s = clvr_field_select(&one, 1, spec, name, fi, comp, err);
        if (s == CLVR_OK && *comp >= 1) s = CLVR_ERR_BAD_FIELD;
        if (s != CLVR_OK)
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                  "%s: no scalar named '%s'; a version 1 .bin holds one scalar, here '%s' "
                                  "(re-convert with clvr-convert to keep every field)",
                                  name, spec, hd->scalar_name);
        return CLVR_OK;
    }
    if (hd->num_fields == 0 && !(spec && spec[0])) return CLVR_OK;
    return clvr_field_select(hd->fields, hd->num_fields, spec, name, fi, comp, err);
}

clvr_status clvr_mesh_bin_layout(int fd, const char *name, const char *scalar_spec, clvr_bin_layout *out,
                                 clvr_error *err)
{
    struct stat st;
    bin_header hd;
    memset(out, 0, sizeof *out);
    if (fstat(fd, &st) != 0) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot stat: %s", name, strerror(errno));
    if (!S_ISREG(st.st_mode))
        return clvr_error_set(err, CLVR_ERR_IO, "%s: is %s, not a mesh file", name,
                              S_ISDIR(st.st_mode) ? "a directory" : "not a regular file");
    const bin_src src = {NULL, fd, (uint64_t)st.st_size, name};
    clvr_status s = bin_read_header(&src, &hd, err);
    if (s != CLVR_OK) return s;
    uint32_t fi = 0;
    int comp = CLVR_FIELD_MAGNITUDE;
    s = layout_select(&hd, name, scalar_spec, &fi, &comp, err);
    if (s == CLVR_OK) {
        out->version = hd.version;
        out->file_size = hd.file_size;
        out->num_vertices = hd.num_vertices;
        memcpy(out->num_cells, hd.num_cells, sizeof out->num_cells);
        uint64_t off = BIN_HEADER_SIZE; /* sizes were checked against the file: no overflow below */
        out->positions_offset = off;
        off += hd.array_bytes[BIN_ARRAY_POSITIONS];
        const uint64_t scalars_v1 = off;
        off += hd.array_bytes[BIN_ARRAY_SCALARS];
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            out->cells_offset[t] = off;
            off += hd.array_bytes[BIN_ARRAY_CELLS + t];
        }
        out->scalar_component = comp;
        if (hd.version == BIN_VERSION) {
            out->has_scalar = 1;
            out->scalar_offset = scalars_v1;
            out->scalar_association = CLVR_FIELD_POINT;
            out->scalar_components = 1;
            clvr_mesh tmp;
            clvr_mesh_set_scalar_name(&tmp, hd.scalar_name, CLVR_SCALAR_NAME_MAX);
            memcpy(out->scalar_label, tmp.scalar_name, sizeof out->scalar_label);
        } else if (hd.num_fields > 0) {
            const clvr_field_info *f = &hd.fields[fi];
            out->has_scalar = 1;
            out->scalar_offset = hd.field_offset[fi];
            out->scalar_association = f->association;
            out->scalar_components = f->components;
            static const char xyz[] = "xyz";
            char label[CLVR_SCALAR_NAME_MAX + 16];
            if (comp >= 0 && f->components > 1) {
                if (comp < 3) snprintf(label, sizeof label, "%s:%c", f->name, xyz[comp]);
                else snprintf(label, sizeof label, "%s:%d", f->name, comp);
            } else {
                snprintf(label, sizeof label, "%s", f->name);
            }
            clvr_mesh tmp;
            clvr_mesh_set_scalar_name(&tmp, label, strlen(label));
            memcpy(out->scalar_label, tmp.scalar_name, sizeof out->scalar_label);
        }
    }
    bin_header_free(&hd);
    return s;
}

float clvr_bin_tuple_value(const float *tuple, uint32_t components, int component)
{
    /* The same arithmetic as bin_read_field, so values match it bit for bit. */
    double v;
    if (component >= 0) v = tuple[component];
    else if (components == 1) v = tuple[0];
    else {
        double s2 = 0.0;
        for (uint32_t k = 0; k < components; ++k) s2 += (double)tuple[k] * tuple[k];
        v = sqrt(s2);
    }
    return (float)v;
}
