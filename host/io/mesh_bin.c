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

/* What the header says, after validation. */
typedef struct bin_header {
    uint64_t num_vertices;
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];
    uint64_t array_bytes[BIN_ARRAY_COUNT];
    uint64_t file_size; /* what the file size must be */
    char scalar_name[CLVR_SCALAR_NAME_MAX];
} bin_header;

/* Byte sizes of the six arrays and the total file size for given counts;
 * returns nonzero on 64-bit overflow. */
static int bin_sizes(uint64_t num_vertices, const uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                     uint64_t bytes[BIN_ARRAY_COUNT], uint64_t *file_size)
{
    uint64_t total = BIN_HEADER_SIZE;
    if (clvr_mul_u64(num_vertices, 3u * sizeof(float), &bytes[BIN_ARRAY_POSITIONS])) return 1;
    if (clvr_mul_u64(num_vertices, sizeof(float), &bytes[BIN_ARRAY_SCALARS])) return 1;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        if (clvr_mul_u64(num_cells[t], clvr_cell_vertex_count(t) * sizeof(uint32_t), &bytes[BIN_ARRAY_CELLS + t]))
            return 1;
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT; ++a)
        if (clvr_add_u64(total, bytes[a], &total)) return 1;
    *file_size = total;
    return 0;
}

static const char *bin_array_name(uint32_t a)
{
    return a == BIN_ARRAY_POSITIONS ? "positions" : a == BIN_ARRAY_SCALARS ? "scalars"
                                                                           : clvr_cell_type_name(a - BIN_ARRAY_CELLS);
}

/* Validates the first min(have, 256) header bytes against the file size and
 * the requested scalar. Every failure names the file, the field and both
 * values. */
static clvr_status bin_read_header(const uint8_t *h, size_t have, uint64_t file_size, const char *name,
                                   const clvr_load_options *opt, bin_header *out, clvr_error *err)
{
    memset(out, 0, sizeof *out);
    size_t cmp = have < BIN_MAGIC_LEN ? have : BIN_MAGIC_LEN;
    if (memcmp(h, BIN_MAGIC, cmp) != 0)
        return clvr_error_set(err, CLVR_ERR_BAD_MAGIC,
                              "%s: not a clvr .bin file (the first 8 bytes are not \"CLVRMESH\"); "
                              "convert it with clvr-convert", name);
    if (have < BIN_HEADER_SIZE)
        return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                              "%s: truncated: the file has %llu bytes but the .bin header alone is %u bytes", name,
                              (unsigned long long)file_size, BIN_HEADER_SIZE);
    uint32_t version = get_u32(h + BIN_OFF_VERSION);
    if (version != BIN_VERSION)
        return clvr_error_set(err, CLVR_ERR_BAD_VERSION,
                              "%s: .bin version is %u but this clvr reads version %u; re-convert the mesh", name,
                              version, BIN_VERSION);
    uint32_t header_size = get_u32(h + BIN_OFF_HEADER_SIZE);
    if (header_size != BIN_HEADER_SIZE)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: header_size is %u but version 1 requires %u", name,
                              header_size, BIN_HEADER_SIZE);
    uint32_t flags = get_u32(h + BIN_OFF_FLAGS);
    if (flags != 0)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s: flags is 0x%x but version 1 defines none; the file comes from a newer writer",
                              name, flags);
    const char *sname = (const char *)h + BIN_OFF_SCALAR_NAME;
    if (memchr(sname, '\0', CLVR_SCALAR_NAME_MAX) == NULL)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s: scalar_name is not NUL-terminated within its %d bytes", name,
                              CLVR_SCALAR_NAME_MAX);
    memcpy(out->scalar_name, sname, CLVR_SCALAR_NAME_MAX);

    out->num_vertices = get_u64(h + BIN_OFF_NUM_VERTICES);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) out->num_cells[t] = get_u64(h + BIN_OFF_NUM_CELLS + 8 * t);
    if (bin_sizes(out->num_vertices, out->num_cells, out->array_bytes, &out->file_size))
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
    if (file_size < out->file_size)
        return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                              "%s: truncated: the header's counts need %llu bytes but the file has %llu", name,
                              (unsigned long long)out->file_size, (unsigned long long)file_size);
    if (file_size > out->file_size)
        return clvr_error_set(err, CLVR_ERR_FORMAT,
                              "%s: %llu trailing bytes: the header's counts need %llu bytes but the file has %llu",
                              name, (unsigned long long)(file_size - out->file_size),
                              (unsigned long long)out->file_size, (unsigned long long)file_size);
    if (opt && opt->scalar_name && strcmp(opt->scalar_name, out->scalar_name) != 0)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s: no scalar named '%s'; a .bin holds one scalar, here '%s'", name, opt->scalar_name,
                              out->scalar_name);
    return CLVR_OK;
}

static void *bin_array_ptr(clvr_mesh *m, uint32_t a)
{
    return a == BIN_ARRAY_POSITIONS ? (void *)m->positions
         : a == BIN_ARRAY_SCALARS   ? (void *)m->scalars
                                    : (void *)m->indices[a - BIN_ARRAY_CELLS];
}

/* Sets ranges and runs the validation unless the caller skips it. */
static clvr_status bin_finish(clvr_mesh *m, const char *name, const clvr_load_options *opt, clvr_error *err)
{
    clvr_mesh_update_ranges(m);
    if (opt && opt->skip_validation) return CLVR_OK;
    clvr_status s = clvr_mesh_validate(m, name, err);
    if (s != CLVR_OK) clvr_mesh_free(m);
    return s;
}

clvr_status clvr_mesh_parse_bin(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                clvr_mesh *out, clvr_error *err)
{
    bin_header hd;
    clvr_status s;
    memset(out, 0, sizeof *out);
    if (!data && size) return clvr_error_set(err, CLVR_ERR_INTERNAL, "%s: NULL buffer", name);
    s = bin_read_header((const uint8_t *)data, size, (uint64_t)size, name, opt, &hd, err);
    if (s != CLVR_OK) return s;
    s = clvr_mesh_alloc(out, hd.num_vertices, hd.num_cells, err);
    if (s != CLVR_OK) return s;
    clvr_mesh_set_scalar_name(out, hd.scalar_name, CLVR_SCALAR_NAME_MAX);
    const uint8_t *p = (const uint8_t *)data + BIN_HEADER_SIZE;
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT; ++a) {
        if (hd.array_bytes[a]) memcpy(bin_array_ptr(out, a), p, (size_t)hd.array_bytes[a]);
        p += hd.array_bytes[a];
    }
    return bin_finish(out, name, opt, err);
}

/* Reads exactly n bytes; on short read reports which array was cut. */
static clvr_status read_full(int fd, void *dst, uint64_t n, const char *name, const char *what, clvr_error *err)
{
    uint8_t *p = (uint8_t *)dst;
    while (n > 0) {
        size_t want = n < BIN_IO_CHUNK ? (size_t)n : BIN_IO_CHUNK;
        ssize_t got = read(fd, p, want);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0)
            return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot read %s: %s", name, what, strerror(errno));
        if (got == 0)
            return clvr_error_set(err, CLVR_ERR_TRUNCATED, "%s: truncated while reading %s (the file shrank?)", name,
                                  what);
        p += got;
        n -= (uint64_t)got;
    }
    return CLVR_OK;
}

clvr_status clvr_mesh_load_bin(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err)
{
    uint8_t h[BIN_HEADER_SIZE];
    bin_header hd;
    struct stat st;
    clvr_status s;
    memset(out, 0, sizeof *out);
    int fd = open(path, O_RDONLY);
    if (fd < 0) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0) {
        s = clvr_error_set(err, CLVR_ERR_IO, "%s: cannot stat: %s", path, strerror(errno));
        goto cleanup;
    }
    if (!S_ISREG(st.st_mode)) {
        s = clvr_error_set(err, CLVR_ERR_IO, "%s: is %s, not a mesh file", path,
                           S_ISDIR(st.st_mode) ? "a directory" : "not a regular file");
        goto cleanup;
    }
    uint64_t file_size = (uint64_t)st.st_size;
    uint64_t head = file_size < BIN_HEADER_SIZE ? file_size : BIN_HEADER_SIZE;
    s = read_full(fd, h, head, path, "the header", err);
    if (s != CLVR_OK) goto cleanup;
    s = bin_read_header(h, (size_t)head, file_size, path, opt, &hd, err);
    if (s != CLVR_OK) goto cleanup;
    /* The size matches the header exactly, so allocating is safe now. */
    s = clvr_mesh_alloc(out, hd.num_vertices, hd.num_cells, err);
    if (s != CLVR_OK) goto cleanup;
    clvr_mesh_set_scalar_name(out, hd.scalar_name, CLVR_SCALAR_NAME_MAX);
    for (uint32_t a = 0; a < BIN_ARRAY_COUNT && s == CLVR_OK; ++a)
        s = read_full(fd, bin_array_ptr(out, a), hd.array_bytes[a], path, bin_array_name(a), err);
    if (s != CLVR_OK) {
        clvr_mesh_free(out);
        goto cleanup;
    }
    close(fd);
    fd = -1;
    return bin_finish(out, path, opt, err);
cleanup:
    if (fd >= 0) close(fd);
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
    uint8_t h[BIN_HEADER_SIZE];
    bin_header hd;
    struct stat st;
    clvr_status s;
    int fd = open(path, O_RDONLY);
    if (fd < 0) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        s = clvr_error_set(err, CLVR_ERR_IO, "%s: not a regular file", path);
        goto done;
    }
    uint64_t file_size = (uint64_t)st.st_size, head = file_size < BIN_HEADER_SIZE ? file_size : BIN_HEADER_SIZE;
    s = read_full(fd, h, head, path, "the header", err);
    if (s == CLVR_OK) s = bin_read_header(h, (size_t)head, file_size, path, NULL, &hd, err);
    if (s == CLVR_OK) {
        *num_vertices = hd.num_vertices;
        memcpy(num_cells, hd.num_cells, sizeof hd.num_cells);
    }
done:
    close(fd);
    return s;
}
