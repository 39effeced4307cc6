/* mesh_umesh.c: reader for Ingo Wald's binary .umesh files (github.com/
 * ingowald/umesh, UMesh::writeTo/readFrom). Everything is little-endian and
 * each array is a std::vector written as a u64 count followed by the items.
 *
 *   magic 0x234235566: vertices (vec3f), scalars (f32; count 0 or V),
 *                      triangles (3 x i32), quads (4), tets (4), pyramids (5),
 *                      wedges (6), hexes (8), [vertexTags (u64)]
 *   magic 0x234235567: vertices, u64 numPerVertexAttributes, per attribute
 *                      { i32 name length, name bytes, f32 values },
 *                      u64 numPerElementAttributes (always 0), triangles ...
 *                      hexes, [vertexTags]
 *   magic 0x234235568: as 567, then grids (48-byte bricks) and gridScalars
 *                      (f32) after the hexes, then [vertexTags]
 *   magic 0x234235569: no public writer was found; read as 568, so a file
 *                      that differs fails with a precise message instead of
 *                      being misread.
 *
 * umesh keeps all element types in VTK vertex order (UMesh.h: "all using
 * VTK format for the vertex index ordering"; checked geometrically on
 * tests/data/umesh/all_elements.umesh), so indices are copied unchanged.
 * Triangles and quads are surface elements and are skipped; grid bricks are
 * volume data clvr cannot represent, so a file with any is refused. */
#include "mesh_io.h"

#include <stdio.h>
#include <string.h>

#define UMESH_MAGIC_566 0x234235566ull
#define UMESH_MAGIC_567 0x234235567ull
#define UMESH_MAGIC_568 0x234235568ull
#define UMESH_MAGIC_569 0x234235569ull
#define UMESH_GRID_BYTES 48u /* box4f domain, vec3i numCells, int scalarsOffset */
/* Attributes listed by name in an error message, at most. */
#define UMESH_MAX_LISTED 16

typedef struct cursor {
    const uint8_t *data;
    uint64_t size, pos;
    const char *name;
} cursor;

/* One std::vector in the file: count and where its items start. */
typedef struct span {
    uint64_t count;
    uint64_t offset;
} span;

static uint64_t rd_u64(const uint8_t *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = v << 8 | p[i];
    return v;
}

static clvr_status take_u64(cursor *c, const char *field, uint64_t *out, clvr_error *err)
{
    if (c->size - c->pos < 8)
        return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                              "%s: truncated: the file ends at byte %llu, inside the count of %s", c->name,
                              (unsigned long long)c->size, field);
    *out = rd_u64(c->data + c->pos);
    c->pos += 8;
    return CLVR_OK;
}

/* Reads a vector's count and skips its items after checking that
 * count * item_bytes fits the rest of the file. */
static clvr_status take_span(cursor *c, const char *field, uint64_t item_bytes, span *out, clvr_error *err)
{
    uint64_t bytes;
    uint64_t at = c->pos;
    clvr_status s = take_u64(c, field, &out->count, err);
    if (s != CLVR_OK) return s;
    if (clvr_mul_u64(out->count, item_bytes, &bytes))
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "%s: %s count %llu (at byte %llu) times %llu bytes overflows 64 bits; the file is corrupt",
                              c->name, field, (unsigned long long)out->count, (unsigned long long)at,
                              (unsigned long long)item_bytes);
    if (bytes > c->size - c->pos)
        return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                              "%s: truncated: %s needs %llu bytes at byte %llu but the file has only %llu left", c->name,
                              field, (unsigned long long)bytes, (unsigned long long)c->pos,
                              (unsigned long long)(c->size - c->pos));
    out->offset = c->pos;
    c->pos += bytes;
    return CLVR_OK;
}

/* A per-vertex attribute as stored (name not NUL-terminated in the file). */
typedef struct attribute {
    const char *name;
    uint32_t name_len;
    span values;
} attribute;

static int attr_is(const attribute *a, const char *want)
{
    return strlen(want) == a->name_len && memcmp(a->name, want, a->name_len) == 0;
}

/* "'a', 'b'" for error messages. */
static void list_names(const attribute *attrs, uint64_t n, char *buf, size_t cap)
{
    size_t len = 0;
    buf[0] = 0;
    for (uint64_t i = 0; i < n && i < UMESH_MAX_LISTED && len + 1 < cap; ++i) {
        int w = snprintf(buf + len, cap - len, "%s'%.*s'", i ? ", " : "", (int)(attrs[i].name_len > 40 ? 40 : attrs[i].name_len),
                         attrs[i].name);
        if (w < 0) break;
        len += (size_t)w;
    }
    if (n > UMESH_MAX_LISTED && len + 1 < cap) snprintf(buf + len, cap - len, ", ...");
}

clvr_status clvr_mesh_parse_umesh(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                  clvr_mesh *out, clvr_error *err)
{
    cursor c = {(const uint8_t *)data, (uint64_t)size, 0, name};
    attribute attrs[UMESH_MAX_LISTED];
    uint64_t num_attrs = 0, magic;
    span verts, tris, quads, cells[CLVR_CELL_TYPE_COUNT];
    const attribute *chosen = NULL;
    attribute first = {0};
    clvr_status s;
    char names[512];
    memset(out, 0, sizeof *out);

    if (size < 8) {
        /* A cut-off magic is a truncated file if what is there matches. */
        static const uint8_t m56x[8] = {0x66, 0x55, 0x23, 0x34, 0x02, 0, 0, 0};
        const uint8_t *d = (const uint8_t *)data;
        if (size == 0 || (d[0] >= 0x66 && d[0] <= 0x69 && memcmp(d + 1, m56x + 1, size - 1) == 0))
            return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                                  "%s: truncated: %zu bytes, shorter than the 8-byte umesh magic", name, size);
        return clvr_error_set(err, CLVR_ERR_BAD_MAGIC, "%s: not a umesh file (%zu bytes, no 8-byte magic)", name,
                              size);
    }
    magic = rd_u64(c.data);
    c.pos = 8;
    if ((magic >> 8) != (UMESH_MAGIC_566 >> 8) || (magic & 0xff) < 0x66 || (magic & 0xff) > 0x69) {
        if ((magic >> 8) == (UMESH_MAGIC_566 >> 8))
            return clvr_error_set(err, CLVR_ERR_BAD_VERSION,
                                  "%s: umesh magic 0x%llx is not a version clvr reads (0x234235566 to 0x234235569)",
                                  name, (unsigned long long)magic);
        return clvr_error_set(err, CLVR_ERR_BAD_MAGIC,
                              "%s: bad umesh magic 0x%llx (expected 0x234235566 to 0x234235569)", name,
                              (unsigned long long)magic);
    }

    s = take_span(&c, "vertices", 12, &verts, err);
    if (s != CLVR_OK) return s;
    if (verts.count > UINT32_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: %llu vertices but clvr indices are 32-bit (at most %u)",
                              name, (unsigned long long)verts.count, UINT32_MAX);

    if (magic == UMESH_MAGIC_566) {
        first.name = "";
        s = take_span(&c, "scalars", 4, &first.values, err);
        if (s != CLVR_OK) return s;
        if (first.values.count) attrs[num_attrs++] = first;
    } else {
        uint64_t n_attr = 0, n_elem_attr = 0;
        s = take_u64(&c, "per-vertex attributes", &n_attr, err);
        if (s != CLVR_OK) return s;
        for (uint64_t i = 0; i < n_attr; ++i) {
            attribute a;
            char field[64];
            if (c.size - c.pos < 4)
                return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                                      "%s: truncated inside the name length of attribute %llu of %llu", name,
                                      (unsigned long long)i, (unsigned long long)n_attr);
            int32_t len;
            memcpy(&len, c.data + c.pos, 4);
            c.pos += 4;
            if (len < 0)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: attribute %llu has a negative name length %d",
                                      name, (unsigned long long)i, (int)len);
            if ((uint64_t)len > c.size - c.pos)
                return clvr_error_set(err, CLVR_ERR_TRUNCATED,
                                      "%s: truncated: attribute %llu's name of %d bytes runs past the end", name,
                                      (unsigned long long)i, (int)len);
            a.name = (const char *)c.data + c.pos;
            a.name_len = (uint32_t)len;
            c.pos += (uint64_t)len;
            snprintf(field, sizeof field, "attribute %llu's values", (unsigned long long)i);
            s = take_span(&c, field, 4, &a.values, err);
            if (s != CLVR_OK) return s;
            if (i < UMESH_MAX_LISTED) attrs[i] = a;
            if (opt && opt->scalar_name && !chosen && attr_is(&a, opt->scalar_name)) {
                first = a;
                chosen = &first;
            }
        }
        num_attrs = n_attr;
        s = take_u64(&c, "per-element attributes", &n_elem_attr, err);
        if (s != CLVR_OK) return s;
        if (n_elem_attr != 0)
            return clvr_error_set(err, CLVR_ERR_FORMAT,
                                  "%s: %llu per-element attributes; umesh never writes any and clvr cannot read them",
                                  name, (unsigned long long)n_elem_attr);
    }

    static const char *const cell_fields[CLVR_CELL_TYPE_COUNT] = {"tets", "pyramids", "wedges", "hexes"};
    s = take_span(&c, "triangles", 12, &tris, err);
    if (s == CLVR_OK) s = take_span(&c, "quads", 16, &quads, err);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t)
        s = take_span(&c, cell_fields[t], 4u * clvr_cell_vertex_count(t), &cells[t], err);
    if (s != CLVR_OK) return s;
    if (magic >= UMESH_MAGIC_568) {
        span grids, grid_scalars;
        s = take_span(&c, "grids", UMESH_GRID_BYTES, &grids, err);
        if (s == CLVR_OK) s = take_span(&c, "gridScalars", 4, &grid_scalars, err);
        if (s != CLVR_OK) return s;
        if (grids.count)
            return clvr_error_set(err, CLVR_ERR_FORMAT,
                                  "%s: holds %llu structured grid bricks, which clvr cannot render; "
                                  "convert them to hexes first",
                                  name, (unsigned long long)grids.count);
    }
    if (c.pos < c.size) {
        /* Optional trailing vertexTags (u64 each); anything else is junk. */
        span tags = {0, 0};
        if (c.size - c.pos >= 8) {
            s = take_span(&c, "vertexTags", 8, &tags, err);
            if (s != CLVR_OK) return s;
        }
        if (c.pos != c.size)
            return clvr_error_set(err, CLVR_ERR_FORMAT,
                                  "%s: %llu trailing bytes after the last umesh array (byte %llu of %llu)", name,
                                  (unsigned long long)(c.size - c.pos), (unsigned long long)c.pos,
                                  (unsigned long long)c.size);
    }

    /* Pick the scalar: by name, else the first attribute. */
    if (opt && opt->scalar_name) {
        if (!chosen) {
            if (num_attrs == 0)
                return clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: no scalar named '%s': the file has no per-vertex "
                                      "attributes", name, opt->scalar_name);
            list_names(attrs, num_attrs, names, sizeof names);
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                  "%s: no scalar named '%s'; the file's per-vertex attributes are %s%s", name,
                                  opt->scalar_name, names,
                                  magic == UMESH_MAGIC_566 ? " (version 566 stores no names: omit the scalar name)" : "");
        }
    } else if (num_attrs > 0) {
        first = attrs[0];
        chosen = &first;
    }
    if (!chosen)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s: has no per-vertex scalar field; clvr needs one value per vertex", name);
    if (chosen->values.count != verts.count)
        return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                              "%s: scalar '%.*s' has %llu values but the mesh has %llu vertices", name,
                              (int)(chosen->name_len > 60 ? 60 : chosen->name_len), chosen->name,
                              (unsigned long long)chosen->values.count, (unsigned long long)verts.count);

    uint64_t counts[CLVR_CELL_TYPE_COUNT];
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) counts[t] = cells[t].count;
    s = clvr_mesh_alloc(out, verts.count, counts, err);
    if (s != CLVR_OK) return s;
    out->skipped_cells = tris.count + quads.count;
    if (verts.count) {
        memcpy(out->positions, c.data + verts.offset, (size_t)(verts.count * 12));
        memcpy(out->scalars, c.data + chosen->values.offset, (size_t)(verts.count * 4));
    }
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        if (counts[t])
            memcpy(out->indices[t], c.data + cells[t].offset, (size_t)(clvr_mesh_num_indices(out, t) * 4));
    clvr_mesh_set_scalar_name(out, chosen->name, chosen->name_len);

    clvr_mesh_update_ranges(out);
    if (opt && opt->skip_validation) return CLVR_OK;
    s = clvr_mesh_validate(out, name, err);
    if (s != CLVR_OK) clvr_mesh_free(out);
    return s;
}
