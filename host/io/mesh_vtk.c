/* mesh_vtk.c: reader for legacy VTK files (the "# vtk DataFile Version"
 * format of VTK's vtkUnstructuredGridReader), DATASET UNSTRUCTURED_GRID
 * only, ASCII or BINARY (big-endian).
 *
 * Handled: POINTS of any numeric type; CELLS in the classic layout
 * ("CELLS n size" then per cell a count and its ids) and in the VTK 5.1
 * layout ("CELLS n+1 m" then OFFSETS and CONNECTIVITY arrays); CELL_TYPES;
 * POINT_DATA and CELL_DATA with SCALARS (LOOKUP_TABLE line optional),
 * VECTORS, NORMALS, TENSORS, FIELD arrays and the other attribute kinds
 * (skipped unless chosen); METADATA blocks (skipped); dataset-level FIELD
 * data (skipped). Names are %XX-decoded as VTK writes them.
 *
 * Cells of type 10 (tetra), 14 (pyramid), 13 (wedge) and 12 (hexahedron)
 * are kept in file order, and so are the quadratic versions of those four,
 * reduced to their corners (see vtk_to_clvr_type); polyhedra (type 42)
 * are decomposed into tets and pyramids (poly_decompose, counted in
 * mesh->decomposed_cells); all others (vertices, lines, triangles, quads,
 * Lagrange cells) are skipped; library
 * code prints nothing, so their number goes to mesh->skipped_cells and the
 * CLI warns. Every point is kept so that
 * point data lines up.
 *
 * The scalar is opt->scalar_name, a clvr_field_select spec over the point
 * and cell arrays; by default the first point array (SCALARS or
 * one-component FIELD arrays first), else the first cell array. Arrays with
 * several components give their Euclidean norm or the chosen component;
 * cell arrays are averaged onto the points of the kept cells (points with
 * none get 0). Every array is listed in mesh->fields for --info.
 *
 * Parsing is two passes over the untrusted buffer: the first walks the
 * sections and records where each array starts after checking that it fits
 * (binary) or that enough tokens follow (ASCII); the second decodes only
 * the arrays that are used, straight into the mesh. Tokens are copied into
 * a bounded local buffer before strtod/strtoll, so no parse ever reads past
 * the end of a buffer that is not NUL-terminated. */
#include "mesh_io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define VTK_TOKEN_MAX 256 /* longest keyword, name or number we accept */

/* VTK cell type numbers kept, and their clvr type. */
#define VTK_TETRA 10
#define VTK_HEXAHEDRON 12
#define VTK_WEDGE 13
#define VTK_PYRAMID 14

typedef enum vtype {
    VT_BIT,
    VT_I8,
    VT_U8,
    VT_I16,
    VT_U16,
    VT_I32,
    VT_U32,
    VT_I64,
    VT_U64,
    VT_F32,
    VT_F64
} vtype;

static const struct {
    const char *name;
    vtype type;
} vtk_types[] = {
    {"bit", VT_BIT},           {"char", VT_I8},           {"signed_char", VT_I8},     {"unsigned_char", VT_U8},
    {"short", VT_I16},         {"unsigned_short", VT_U16}, {"int", VT_I32},            {"unsigned_int", VT_U32},
    {"long", VT_I64},          {"unsigned_long", VT_U64},  {"vtkidtype", VT_I64},      {"float", VT_F32},
    {"double", VT_F64},        {"vtktypeint8", VT_I8},     {"vtktypeuint8", VT_U8},    {"vtktypeint16", VT_I16},
    {"vtktypeuint16", VT_U16}, {"vtktypeint32", VT_I32},   {"vtktypeuint32", VT_U32},  {"vtktypeint64", VT_I64},
    {"vtktypeuint64", VT_U64}, {"vtktypefloat32", VT_F32}, {"vtktypefloat64", VT_F64},
};

static uint32_t vtype_size(vtype t)
{
    switch (t) {
    case VT_BIT: return 0; /* packed: see array_bytes */
    case VT_I8: case VT_U8: return 1;
    case VT_I16: case VT_U16: return 2;
    case VT_I32: case VT_U32: case VT_F32: return 4;
    default: return 8;
    }
}

static int vtype_is_int(vtype t) { return t != VT_F32 && t != VT_F64; }

/* Where an array's values are: binary ones are decoded in place, ASCII
 * ones are re-tokenized from `offset`. */
typedef struct varr {
    vtype type;
    uint64_t count; /* values, not tuples */
    uint64_t offset;
} varr;

typedef struct vtk_in {
    const uint8_t *d;
    uint64_t n, pos;
    const char *name;
    int binary;
    clvr_error *err;
} vtk_in;

/* A named array that may become the scalar. */
typedef struct cand {
    char name[VTK_TOKEN_MAX];
    int cell; /* 0: point data, 1: cell data */
    int one_comp_first; /* SCALARS or one-component: preferred by default */
    uint32_t ncomp;
    varr a;
} cand;

typedef struct cand_list {
    cand *v;
    size_t n, cap;
} cand_list;

static int is_space(uint8_t c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

/* Next whitespace-separated token; returns its length, 0 at end of input. */
static size_t next_token(const vtk_in *in, uint64_t *pos, const char **tok)
{
    uint64_t p = *pos;
    while (p < in->n && is_space(in->d[p])) ++p;
    uint64_t s = p;
    while (p < in->n && !is_space(in->d[p])) ++p;
    *tok = (const char *)in->d + s;
    *pos = p;
    return (size_t)(p - s);
}

/* Token copied and NUL-terminated into buf (VTK_TOKEN_MAX); error when it
 * is missing or longer than that. */
static clvr_status read_word(vtk_in *in, const char *what, char *buf)
{
    const char *t;
    uint64_t at = in->pos;
    size_t len = next_token(in, &in->pos, &t);
    if (len == 0)
        return clvr_error_set(in->err, CLVR_ERR_TRUNCATED, "%s: truncated: the file ends where %s was expected",
                              in->name, what);
    if (len >= VTK_TOKEN_MAX)
        return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: %s at byte %llu is %zu characters long", in->name,
                              what, (unsigned long long)at, len);
    memcpy(buf, t, len);
    buf[len] = 0;
    return CLVR_OK;
}

static clvr_status read_count(vtk_in *in, const char *what, uint64_t *out)
{
    char buf[VTK_TOKEN_MAX], *end;
    uint64_t at = in->pos;
    clvr_status s = read_word(in, what, buf);
    if (s != CLVR_OK) return s;
    errno = 0;
    unsigned long long v = strtoull(buf, &end, 10);
    if (*end || end == buf || buf[0] == '-' || buf[0] == '+' || errno == ERANGE)
        return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: %s near byte %llu is '%s', not a count", in->name, what,
                              (unsigned long long)at, buf);
    *out = v;
    return CLVR_OK;
}

static clvr_status read_type(vtk_in *in, const char *what, vtype *out)
{
    char buf[VTK_TOKEN_MAX];
    clvr_status s = read_word(in, what, buf);
    if (s != CLVR_OK) return s;
    for (size_t i = 0; i < sizeof vtk_types / sizeof vtk_types[0]; ++i)
        if (strcasecmp(buf, vtk_types[i].name) == 0) {
            *out = vtk_types[i].type;
            return CLVR_OK;
        }
    return clvr_error_set(in->err, CLVR_ERR_FORMAT, "%s: %s has data type '%s', which clvr does not read", in->name,
                          what, buf);
}

/* Peeks the next token; if it equals kw (case-insensitive) consumes it. */
static int accept_kw(vtk_in *in, const char *kw)
{
    const char *t;
    uint64_t p = in->pos;
    size_t len = next_token(in, &p, &t);
    if (len == strlen(kw) && strncasecmp(t, kw, len) == 0) {
        in->pos = p;
        return 1;
    }
    return 0;
}

/* Next token on the same line, if any (for optional trailing fields). */
static size_t same_line_token(const vtk_in *in, uint64_t *pos, const char **tok)
{
    uint64_t p = *pos;
    while (p < in->n && (in->d[p] == ' ' || in->d[p] == '\t')) ++p;
    if (p >= in->n || in->d[p] == '\r' || in->d[p] == '\n') {
        *tok = NULL;
        return 0;
    }
    return next_token(in, pos, tok);
}

static void skip_line(vtk_in *in)
{
    while (in->pos < in->n && in->d[in->pos] != '\n') ++in->pos;
    if (in->pos < in->n) ++in->pos;
}

/* VTK writes names with %XX escapes (spaces as %20). */
static void decode_name(const char *src, char *dst, size_t cap)
{
    size_t o = 0;
    for (size_t i = 0; src[i] && o + 1 < cap; ++i) {
        int hi, lo;
        if (src[i] == '%' && src[i + 1] && src[i + 2] && sscanf(src + i + 1, "%1x%1x", &hi, &lo) == 2) {
            dst[o++] = (char)(hi * 16 + lo);
            i += 2;
        } else {
            dst[o++] = src[i];
        }
    }
    dst[o] = 0;
}

/* Records an array of `count` values of type t starting here, after
 * checking that it fits: binary data starts on the line after its header,
 * ASCII data is `count` tokens. */
static clvr_status take_array(vtk_in *in, vtype t, uint64_t count, const char *what, varr *out)
{
    out->type = t;
    out->count = count;
    if (in->binary) {
        uint64_t bytes;
        skip_line(in);
        if (t == VT_BIT) {
            bytes = count / 8 + (count % 8 != 0);
        } else if (clvr_mul_u64(count, vtype_size(t), &bytes)) {
            return clvr_error_set(in->err, CLVR_ERR_OVERFLOW,
                                  "%s: %s: %llu values of %u bytes overflow 64 bits; the file is corrupt", in->name,
                                  what, (unsigned long long)count, vtype_size(t));
        }
        if (bytes > in->n - in->pos)
            return clvr_error_set(in->err, CLVR_ERR_TRUNCATED,
                                  "%s: truncated: %s needs %llu bytes at byte %llu but only %llu remain", in->name, what,
                                  (unsigned long long)bytes, (unsigned long long)in->pos,
                                  (unsigned long long)(in->n - in->pos));
        out->offset = in->pos;
        in->pos += bytes;
        return CLVR_OK;
    }
    out->offset = in->pos;
    for (uint64_t i = 0; i < count; ++i) {
        const char *tok;
        if (next_token(in, &in->pos, &tok) == 0)
            return clvr_error_set(in->err, CLVR_ERR_TRUNCATED,
                                  "%s: truncated: %s has %llu values but the file ends after %llu", in->name, what,
                                  (unsigned long long)count, (unsigned long long)i);
    }
    return CLVR_OK;
}

/* Sequential reader over one recorded array. */
typedef struct vit {
    const vtk_in *in;
    varr a;
    uint64_t i, pos;
    const char *what;
} vit;

static void vit_init(vit *it, const vtk_in *in, const varr *a, const char *what)
{
    it->in = in;
    it->a = *a;
    it->i = 0;
    it->pos = a->offset;
    it->what = what;
}

static uint64_t be_bits(const uint8_t *p, uint32_t n)
{
    uint64_t v = 0;
    for (uint32_t k = 0; k < n; ++k) v = v << 8 | p[k];
    return v;
}

/* Binary value i as double (ints exactly up to 2^53). */
static double bin_f64(const vtk_in *in, const varr *a, uint64_t i)
{
    const uint8_t *base = in->d + a->offset;
    if (a->type == VT_BIT) return (double)((base[i / 8] >> (7 - i % 8)) & 1);
    uint32_t sz = vtype_size(a->type);
    uint64_t u = be_bits(base + i * sz, sz);
    switch (a->type) {
    case VT_I8: return (double)(int8_t)u;
    case VT_U8: return (double)(uint8_t)u;
    case VT_I16: return (double)(int16_t)u;
    case VT_U16: return (double)(uint16_t)u;
    case VT_I32: return (double)(int32_t)(uint32_t)u;
    case VT_U32: return (double)(uint32_t)u;
    case VT_I64: return (double)(int64_t)u;
    case VT_U64: return (double)u;
    case VT_F32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, 4);
        return f;
    }
    default: {
        double d;
        memcpy(&d, &u, 8);
        return d;
    }
    }
}

static int64_t bin_i64(const vtk_in *in, const varr *a, uint64_t i)
{
    if (a->type == VT_BIT || a->type == VT_F32 || a->type == VT_F64) return (int64_t)bin_f64(in, a, i);
    uint32_t sz = vtype_size(a->type);
    uint64_t u = be_bits(in->d + a->offset + i * sz, sz);
    switch (a->type) {
    case VT_I8: return (int8_t)u;
    case VT_I16: return (int16_t)u;
    case VT_I32: return (int32_t)(uint32_t)u;
    case VT_I64: return (int64_t)u;
    case VT_U64: return u > (uint64_t)INT64_MAX ? INT64_MAX : (int64_t)u;
    default: return (int64_t)u;
    }
}

/* Copies the next ASCII token of the array into buf. */
static clvr_status vit_token(vit *it, char *buf, uint64_t *at)
{
    const char *t;
    size_t len = next_token(it->in, &it->pos, &t);
    *at = (uint64_t)(t - (const char *)it->in->d);
    if (len == 0) /* cannot happen: pass 1 counted the tokens */
        return clvr_error_set(it->in->err, CLVR_ERR_INTERNAL, "%s: %s: value %llu missing", it->in->name, it->what,
                              (unsigned long long)it->i);
    if (len >= 64)
        return clvr_error_set(it->in->err, CLVR_ERR_BAD_FIELD, "%s: %s: value %llu at byte %llu is not a number",
                              it->in->name, it->what, (unsigned long long)it->i, (unsigned long long)*at);
    memcpy(buf, t, len);
    buf[len] = 0;
    return CLVR_OK;
}

static clvr_status vit_f64(vit *it, double *out)
{
    if (it->in->binary) {
        *out = bin_f64(it->in, &it->a, it->i++);
        return CLVR_OK;
    }
    char buf[64], *end;
    uint64_t at;
    clvr_status s = vit_token(it, buf, &at);
    if (s != CLVR_OK) return s;
    *out = strtod(buf, &end);
    if (*end)
        return clvr_error_set(it->in->err, CLVR_ERR_BAD_FIELD, "%s: %s: value %llu at byte %llu is '%s', not a number",
                              it->in->name, it->what, (unsigned long long)it->i, (unsigned long long)at, buf);
    it->i++;
    return CLVR_OK;
}

static clvr_status vit_i64(vit *it, int64_t *out)
{
    if (it->in->binary) {
        *out = bin_i64(it->in, &it->a, it->i++);
        return CLVR_OK;
    }
    char buf[64], *end;
    uint64_t at;
    clvr_status s = vit_token(it, buf, &at);
    if (s != CLVR_OK) return s;
    errno = 0;
    long long v = strtoll(buf, &end, 10);
    if (*end || errno == ERANGE)
        return clvr_error_set(it->in->err, CLVR_ERR_BAD_FIELD,
                              "%s: %s: value %llu at byte %llu is '%s', not an integer", it->in->name, it->what,
                              (unsigned long long)it->i, (unsigned long long)at, buf);
    *out = v;
    it->i++;
    return CLVR_OK;
}

static clvr_status add_cand(vtk_in *in, cand_list *cl, const char *raw_name, int cell, int preferred, uint32_t ncomp,
                            const varr *a)
{
    if (cl->n == cl->cap) {
        size_t cap = cl->cap ? 2 * cl->cap : 8;
        cand *v = realloc(cl->v, cap * sizeof *v);
        if (!v) return clvr_error_set(in->err, CLVR_ERR_NO_MEMORY, "%s: out of memory listing arrays", in->name);
        cl->v = v;
        cl->cap = cap;
    }
    cand *c = &cl->v[cl->n++];
    decode_name(raw_name, c->name, sizeof c->name);
    c->cell = cell;
    c->one_comp_first = preferred;
    c->ncomp = ncomp;
    c->a = *a;
    return CLVR_OK;
}

/* Everything pass 1 learns. */
typedef struct vtk_doc {
    int have_points, have_cells, have_types, new_layout;
    uint64_t num_points, num_cells, cells_size;
    varr points, cells, offsets, conn, types;
    cand_list cands;
} vtk_doc;

enum { ASSOC_NONE = -1, ASSOC_POINT = 0, ASSOC_CELL = 1 };

/* FIELD name k, then k arrays "name ncomp ntuples type" each with data. */
static clvr_status parse_field(vtk_in *in, vtk_doc *doc, int assoc, uint64_t assoc_count)
{
    char fname[VTK_TOKEN_MAX], aname[VTK_TOKEN_MAX];
    uint64_t k = 0; /* read when the count itself fails to parse */
    clvr_status s = read_word(in, "the FIELD name", fname);
    if (s == CLVR_OK) s = read_count(in, "the FIELD array count", &k);
    for (uint64_t i = 0; i < k && s == CLVR_OK; ++i) {
        uint64_t ncomp, ntuples, total;
        vtype t = VT_F32;
        varr a;
        s = read_word(in, "a FIELD array name", aname);
        if (s != CLVR_OK) break;
        if (strcmp(aname, "NULL_ARRAY") == 0) continue;
        s = read_count(in, "a FIELD array's component count", &ncomp);
        if (s == CLVR_OK) s = read_count(in, "a FIELD array's tuple count", &ntuples);
        if (s == CLVR_OK) s = read_type(in, "a FIELD array", &t);
        if (s != CLVR_OK) break;
        if (clvr_mul_u64(ncomp, ntuples, &total))
            return clvr_error_set(in->err, CLVR_ERR_OVERFLOW,
                                  "%s: FIELD array '%s' has %llu x %llu values, which overflows 64 bits", in->name,
                                  aname, (unsigned long long)ncomp, (unsigned long long)ntuples);
        s = take_array(in, t, total, aname, &a);
        if (s == CLVR_OK && assoc != ASSOC_NONE && ntuples == assoc_count && ncomp > 0 && ncomp <= UINT32_MAX)
            s = add_cand(in, &doc->cands, aname, assoc, ncomp == 1, (uint32_t)ncomp, &a);
    }
    return s;
}

/* METADATA blocks end at the first empty line. */
static void skip_metadata(vtk_in *in)
{
    skip_line(in);
    while (in->pos < in->n) {
        uint64_t p = in->pos;
        int blank = 1;
        while (p < in->n && in->d[p] != '\n') blank &= is_space(in->d[p++]);
        in->pos = p < in->n ? p + 1 : p;
        if (blank) break;
    }
}

/* Attribute arrays with a fixed component count: KEYWORD name type. */
static const struct {
    const char *kw;
    uint32_t ncomp;
} vtk_attrs[] = {{"VECTORS", 3},     {"NORMALS", 3},    {"TENSORS", 9},          {"TENSORS6", 6},
                 {"GLOBAL_IDS", 1},  {"PEDIGREE_IDS", 1}, {"EDGE_FLAGS", 1},      {"RATIONAL_WEIGHTS", 1}};

static clvr_status parse_sections(vtk_in *in, vtk_doc *doc)
{
    char kw[VTK_TOKEN_MAX], name[VTK_TOKEN_MAX];
    int assoc = ASSOC_NONE;
    uint64_t assoc_count = 0;
    clvr_status s = CLVR_OK;
    for (;;) {
        const char *t;
        uint64_t at = in->pos;
        size_t len = next_token(in, &at, &t);
        if (len == 0) return CLVR_OK;
        uint64_t kw_at = (uint64_t)(t - (const char *)in->d);
        s = read_word(in, "a section keyword", kw);
        if (s != CLVR_OK) return s;
        if (strcasecmp(kw, "POINTS") == 0) {
            vtype ty = VT_F32;
            uint64_t n3;
            if (doc->have_points)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: a second POINTS section at byte %llu",
                                      in->name, (unsigned long long)kw_at);
            s = read_count(in, "the POINTS count", &doc->num_points);
            if (s == CLVR_OK) s = read_type(in, "POINTS", &ty);
            if (s != CLVR_OK) return s;
            if (clvr_mul_u64(doc->num_points, 3, &n3))
                return clvr_error_set(in->err, CLVR_ERR_OVERFLOW, "%s: POINTS count %llu overflows 64-bit sizes",
                                      in->name, (unsigned long long)doc->num_points);
            s = take_array(in, ty, n3, "POINTS", &doc->points);
            doc->have_points = 1;
        } else if (strcasecmp(kw, "CELLS") == 0) {
            uint64_t a, b;
            vtype ty = VT_F32;
            if (doc->have_cells)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: a second CELLS section at byte %llu",
                                      in->name, (unsigned long long)kw_at);
            s = read_count(in, "the CELLS count", &a);
            if (s == CLVR_OK) s = read_count(in, "the CELLS size", &b);
            if (s != CLVR_OK) return s;
            doc->have_cells = 1;
            if (accept_kw(in, "OFFSETS")) {
                /* VTK 5.1: a = cells + 1 offsets, b = connectivity length. */
                doc->new_layout = 1;
                doc->num_cells = a ? a - 1 : 0;
                doc->cells_size = b;
                s = read_type(in, "OFFSETS", &ty);
                if (s == CLVR_OK) s = take_array(in, ty, a, "OFFSETS", &doc->offsets);
                if (s == CLVR_OK && !vtype_is_int(ty))
                    s = clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: OFFSETS must be integers", in->name);
                if (s == CLVR_OK && !accept_kw(in, "CONNECTIVITY"))
                    s = clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                       "%s: CONNECTIVITY must follow the OFFSETS array (byte %llu)", in->name,
                                       (unsigned long long)in->pos);
                if (s == CLVR_OK) s = read_type(in, "CONNECTIVITY", &ty);
                if (s == CLVR_OK) s = take_array(in, ty, b, "CONNECTIVITY", &doc->conn);
                if (s == CLVR_OK && !vtype_is_int(ty))
                    s = clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: CONNECTIVITY must be integers", in->name);
            } else {
                doc->num_cells = a;
                doc->cells_size = b;
                s = take_array(in, VT_I32, b, "CELLS", &doc->cells);
            }
        } else if (strcasecmp(kw, "CELL_TYPES") == 0) {
            uint64_t n;
            if (doc->have_types)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: a second CELL_TYPES section at byte %llu",
                                      in->name, (unsigned long long)kw_at);
            s = read_count(in, "the CELL_TYPES count", &n);
            if (s == CLVR_OK) s = take_array(in, VT_I32, n, "CELL_TYPES", &doc->types);
            doc->have_types = 1;
        } else if (strcasecmp(kw, "POINT_DATA") == 0 || strcasecmp(kw, "CELL_DATA") == 0) {
            assoc = strcasecmp(kw, "POINT_DATA") == 0 ? ASSOC_POINT : ASSOC_CELL;
            s = read_count(in, kw, &assoc_count);
        } else if (strcasecmp(kw, "FIELD") == 0) {
            s = parse_field(in, doc, assoc, assoc_count);
        } else if (strcasecmp(kw, "METADATA") == 0) {
            skip_metadata(in);
        } else if (strcasecmp(kw, "SCALARS") == 0) {
            vtype ty = VT_F32;
            uint64_t ncomp = 1, total;
            varr a;
            if (assoc == ASSOC_NONE)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                      "%s: SCALARS at byte %llu comes before POINT_DATA or CELL_DATA", in->name,
                                      (unsigned long long)kw_at);
            s = read_word(in, "the SCALARS name", name);
            if (s == CLVR_OK) s = read_type(in, "SCALARS", &ty);
            if (s != CLVR_OK) return s;
            uint64_t p = in->pos;
            size_t l2 = same_line_token(in, &p, &t);
            if (l2 > 0 && l2 < 20 && t[0] >= '0' && t[0] <= '9') {
                s = read_count(in, "the SCALARS component count", &ncomp);
                if (s != CLVR_OK) return s;
                if (ncomp < 1 || ncomp > 4)
                    return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                          "%s: SCALARS '%s' has %llu components; VTK allows 1 to 4", in->name, name,
                                          (unsigned long long)ncomp);
            }
            if (accept_kw(in, "LOOKUP_TABLE")) {
                char table[VTK_TOKEN_MAX];
                s = read_word(in, "the LOOKUP_TABLE name", table);
                if (s != CLVR_OK) return s;
            }
            if (clvr_mul_u64(assoc_count, ncomp, &total))
                return clvr_error_set(in->err, CLVR_ERR_OVERFLOW, "%s: SCALARS '%s' size overflows 64 bits", in->name,
                                      name);
            s = take_array(in, ty, total, name, &a);
            if (s == CLVR_OK) s = add_cand(in, &doc->cands, name, assoc, 1, (uint32_t)ncomp, &a);
        } else if (strcasecmp(kw, "LOOKUP_TABLE") == 0 || strcasecmp(kw, "COLOR_SCALARS") == 0) {
            /* LOOKUP_TABLE name n: n RGBA entries; COLOR_SCALARS name m:
             * m components per tuple. Bytes in binary files, floats in
             * ASCII ones; never a scalar field. */
            uint64_t m, total;
            varr a;
            int lut = strcasecmp(kw, "LOOKUP_TABLE") == 0;
            s = read_word(in, "the table name", name);
            if (s == CLVR_OK) s = read_count(in, lut ? "the LOOKUP_TABLE size" : "the COLOR_SCALARS count", &m);
            if (s != CLVR_OK) return s;
            if (clvr_mul_u64(lut ? 4 : assoc_count, m, &total))
                return clvr_error_set(in->err, CLVR_ERR_OVERFLOW, "%s: %s '%s' size overflows 64 bits", in->name, kw,
                                      name);
            s = take_array(in, in->binary ? VT_U8 : VT_F32, total, kw, &a);
        } else if (strcasecmp(kw, "TEXTURE_COORDINATES") == 0) {
            uint64_t dim, total;
            vtype ty = VT_F32;
            varr a;
            s = read_word(in, "the TEXTURE_COORDINATES name", name);
            if (s == CLVR_OK) s = read_count(in, "the TEXTURE_COORDINATES dimension", &dim);
            if (s == CLVR_OK) s = read_type(in, "TEXTURE_COORDINATES", &ty);
            if (s != CLVR_OK) return s;
            if (clvr_mul_u64(assoc_count, dim, &total))
                return clvr_error_set(in->err, CLVR_ERR_OVERFLOW, "%s: TEXTURE_COORDINATES size overflows 64 bits",
                                      in->name);
            s = take_array(in, ty, total, name, &a);
        } else {
            size_t k = 0, nk = sizeof vtk_attrs / sizeof vtk_attrs[0];
            while (k < nk && strcasecmp(kw, vtk_attrs[k].kw) != 0) ++k;
            if (k == nk && ((kw[0] >= '0' && kw[0] <= '9') || kw[0] == '-' || kw[0] == '+' || kw[0] == '.'))
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                      "%s: unexpected value '%.40s' at byte %llu where a section keyword should be: "
                                      "the section before it holds more values than its header declares",
                                      in->name, kw, (unsigned long long)kw_at);
            if (k == nk)
                return clvr_error_set(in->err, CLVR_ERR_FORMAT,
                                      "%s: unknown keyword '%.40s' at byte %llu (garbage or an unsupported section)",
                                      in->name, kw, (unsigned long long)kw_at);
            vtype ty = VT_F32;
            uint64_t total;
            varr a;
            if (assoc == ASSOC_NONE)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                      "%s: %s at byte %llu comes before POINT_DATA or CELL_DATA", in->name, kw,
                                      (unsigned long long)kw_at);
            s = read_word(in, "the array name", name);
            if (s == CLVR_OK) s = read_type(in, kw, &ty);
            if (s != CLVR_OK) return s;
            if (clvr_mul_u64(assoc_count, vtk_attrs[k].ncomp, &total))
                return clvr_error_set(in->err, CLVR_ERR_OVERFLOW, "%s: %s '%s' size overflows 64 bits", in->name, kw,
                                      name);
            s = take_array(in, ty, total, name, &a);
            if (s == CLVR_OK) s = add_cand(in, &doc->cands, name, assoc, vtk_attrs[k].ncomp == 1, vtk_attrs[k].ncomp, &a);
        }
        if (s != CLVR_OK) return s;
    }
}

static clvr_status parse_header(vtk_in *in)
{
    static const char sig[] = "# vtk DataFile Version";
    const size_t sl = sizeof sig - 1;
    size_t cmp = in->n < sl ? (size_t)in->n : sl;
    if (strncasecmp((const char *)in->d, sig, cmp) != 0)
        return clvr_error_set(in->err, CLVR_ERR_BAD_MAGIC,
                              "%s: not a legacy VTK file (it does not start with \"# vtk DataFile Version\")",
                              in->name);
    if (in->n <= sl)
        return clvr_error_set(in->err, CLVR_ERR_TRUNCATED, "%s: truncated inside the VTK header line", in->name);
    in->pos = sl;
    const char *t;
    uint64_t p = in->pos;
    size_t len = same_line_token(in, &p, &t);
    char ver[16] = {0};
    if (len == 0 || len >= sizeof ver)
        return clvr_error_set(in->err, len ? CLVR_ERR_BAD_VERSION : CLVR_ERR_TRUNCATED,
                              "%s: the VTK header line has no version number", in->name);
    memcpy(ver, t, len);
    int major = atoi(ver);
    if (major < 1 || major > 5)
        return clvr_error_set(in->err, CLVR_ERR_BAD_VERSION,
                              "%s: VTK file version '%s'; clvr reads legacy versions 1.0 to 5.1", in->name, ver);
    skip_line(in); /* header */
    uint64_t title_at = in->pos;
    skip_line(in); /* title, any text */
    if (in->pos == title_at || in->pos >= in->n)
        return clvr_error_set(in->err, CLVR_ERR_TRUNCATED, "%s: truncated after the VTK header", in->name);
    char word[VTK_TOKEN_MAX];
    clvr_status s = read_word(in, "ASCII or BINARY", word);
    if (s != CLVR_OK) return s;
    if (strcasecmp(word, "ASCII") == 0) in->binary = 0;
    else if (strcasecmp(word, "BINARY") == 0) in->binary = 1;
    else
        return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: third line says '%s' instead of ASCII or BINARY",
                              in->name, word);
    s = read_word(in, "DATASET", word);
    if (s != CLVR_OK) return s;
    if (strcasecmp(word, "DATASET") != 0)
        return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: expected DATASET after %s, found '%s'", in->name,
                              in->binary ? "BINARY" : "ASCII", word);
    s = read_word(in, "the dataset type", word);
    if (s != CLVR_OK) return s;
    if (strcasecmp(word, "UNSTRUCTURED_GRID") != 0)
        return clvr_error_set(in->err, CLVR_ERR_FORMAT,
                              "%s: DATASET %s is not an UNSTRUCTURED_GRID; convert it to an unstructured grid", in->name,
                              word);
    return CLVR_OK;
}

/* Quadratic cells list their corners first, in the linear cell's order
 * (VTK's vtkQuadraticTetra etc.), so they are kept as their corner cell:
 * 24 quadratic tetra, 25 quadratic hexahedron, 26 quadratic wedge,
 * 27 quadratic pyramid, 29 triquadratic hexahedron, 32 biquadratic-
 * quadratic wedge, 33 biquadratic-quadratic hexahedron. */
static int vtk_to_clvr_type(int64_t vt)
{
    switch (vt) {
    case VTK_TETRA: case 24: return (int)CLVR_CELL_TET;
    case VTK_PYRAMID: case 27: return (int)CLVR_CELL_PYRAMID;
    case VTK_WEDGE: case 26: case 32: return (int)CLVR_CELL_WEDGE;
    case VTK_HEXAHEDRON: case 25: case 29: case 33: return (int)CLVR_CELL_HEX;
    default: return -1;
    }
}

/* The candidates as a field table (for --scalar and --info). */
static clvr_status cand_fields(vtk_in *in, const vtk_doc *doc, clvr_field_info **out)
{
    const cand_list *cl = &doc->cands;
    *out = calloc(cl->n ? cl->n : 1, sizeof **out);
    if (!*out) return clvr_error_set(in->err, CLVR_ERR_NO_MEMORY, "%s: out of memory listing arrays", in->name);
    for (size_t i = 0; i < cl->n; ++i) {
        clvr_mesh tmp;
        clvr_mesh_set_scalar_name(&tmp, cl->v[i].name, strlen(cl->v[i].name));
        memcpy((*out)[i].name, tmp.scalar_name, CLVR_SCALAR_NAME_MAX);
        (*out)[i].association = cl->v[i].cell ? CLVR_FIELD_CELL : CLVR_FIELD_POINT;
        (*out)[i].components = cl->v[i].ncomp > CLVR_FIELD_COMPONENTS_MAX ? CLVR_FIELD_COMPONENTS_MAX : cl->v[i].ncomp;
    }
    return CLVR_OK;
}

/* Range of one candidate's values, or of its tuples' magnitudes. */
static clvr_status cand_range(vtk_in *in, const cand *c, clvr_field_info *f)
{
    vit it;
    vit_init(&it, in, &c->a, c->name);
    double lo = INFINITY, hi = -INFINITY;
    uint64_t tuples = c->a.count / c->ncomp;
    for (uint64_t i = 0; i < tuples; ++i) {
        double s2 = 0.0, x = 0.0;
        for (uint32_t k = 0; k < c->ncomp; ++k) {
            clvr_status s = vit_f64(&it, &x);
            if (s != CLVR_OK) return s;
            s2 += x * x;
        }
        double v = c->ncomp > 1 ? sqrt(s2) : x;
        if (v < lo) lo = v;
        if (v > hi) hi = v;
    }
    f->has_range = tuples > 0;
    f->min = tuples ? (float)lo : 0.0f;
    f->max = tuples ? (float)hi : 0.0f;
    return CLVR_OK;
}

/* Chooses the scalar array, or explains which ones exist. */
static clvr_status choose_scalar(vtk_in *in, const vtk_doc *doc, const clvr_load_options *opt, const cand **out,
                                 const clvr_field_info *fields, int *comp)
{
    const cand_list *cl = &doc->cands;
    *out = NULL;
    *comp = CLVR_FIELD_MAGNITUDE;
    if (opt && opt->scalar_name && cl->n) {
        uint32_t idx;
        clvr_status s = clvr_field_select(fields, (uint32_t)cl->n, opt->scalar_name, in->name, &idx, comp, in->err);
        if (s == CLVR_OK) *out = &cl->v[idx];
        return s;
    }
    if (opt && opt->scalar_name) {
        for (int cell = 0; cell < 2 && !*out; ++cell)
            for (size_t i = 0; i < cl->n && !*out; ++i)
                if (cl->v[i].cell == cell && strcmp(cl->v[i].name, opt->scalar_name) == 0) *out = &cl->v[i];
        if (*out) return CLVR_OK;
        char list[600];
        size_t len = 0;
        list[0] = 0;
        for (size_t i = 0; i < cl->n && len + 80 < sizeof list; ++i)
            len += (size_t)snprintf(list + len, sizeof list - len, "%s'%.60s' (%s)", i ? ", " : "", cl->v[i].name,
                                    cl->v[i].cell ? "cell" : "point");
        if (cl->n == 0)
            return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: no scalar named '%s': the file has no point or "
                                  "cell data arrays", in->name, opt->scalar_name);
        return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: no scalar named '%s'; the file has %s", in->name,
                              opt->scalar_name, list);
    }
    for (int cell = 0; cell < 2 && !*out; ++cell) {
        for (size_t i = 0; i < cl->n && !*out; ++i)
            if (cl->v[i].cell == cell && cl->v[i].one_comp_first) *out = &cl->v[i];
        for (size_t i = 0; i < cl->n && !*out; ++i)
            if (cl->v[i].cell == cell) *out = &cl->v[i];
    }
    if (*out) return CLVR_OK;
    return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                          "%s: no POINT_DATA or CELL_DATA array to use as the scalar; clvr needs one value per vertex",
                          in->name);
}

/* Polyhedra (VTK type 42, OpenFOAM's foamToVTK -legacy -poly writes them):
 * their ids are a face stream, nfaces then per face a count and its ids.
 * Each is decomposed without new vertices, as a fan from one of its
 * vertices (the apex, the first vertex of the first face): every face that
 * does not hold the apex becomes a pyramid (a quad) or tets (a triangle, or
 * a fan over a larger polygon) with the apex on top, oriented as VTK orders
 * those cells. Exact for convex (and star-shaped about the apex) cells, as
 * OpenFOAM's are; the pieces go to growable lists appended to the mesh at
 * the end. */
#define VTK_POLYHEDRON 42

typedef struct poly_out {
    uint32_t *tets, *pyrs;       /* 4 and 5 ids per piece */
    uint64_t num_tets, num_pyrs, cap_tets, cap_pyrs;
    int64_t *ids;                /* one cell's face stream */
    uint64_t cap_ids;
    uint32_t *uniq;              /* its distinct vertices (cell-data averaging) */
    uint64_t cap_uniq;
    uint64_t cells;              /* polyhedra decomposed */
    float *tv, *pv;              /* --cell-data flat: each piece's cell value */
    uint64_t cap_tv, cap_pv;
} poly_out;

static void poly_free(poly_out *p)
{
    free(p->tets);
    free(p->pyrs);
    free(p->ids);
    free(p->uniq);
    free(p->tv);
    free(p->pv);
}

static int grow(void **buf, uint64_t *cap, uint64_t need, size_t item)
{
    if (need <= *cap) return 0;
    uint64_t n = *cap ? *cap : 64;
    while (n < need) n *= 2;
    if (n > SIZE_MAX / item) return 1;
    void *q = realloc(*buf, (size_t)(n * item));
    if (!q) return 1;
    *buf = q;
    *cap = n;
    return 0;
}

static double orient3(const float *pos, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    const float *A = pos + 3 * (uint64_t)a, *B = pos + 3 * (uint64_t)b, *C = pos + 3 * (uint64_t)c,
                *D = pos + 3 * (uint64_t)d;
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
        u[k] = (double)B[k] - A[k];
        v[k] = (double)C[k] - A[k];
        w[k] = (double)D[k] - A[k];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static clvr_status poly_tet(vtk_in *in, poly_out *p, const float *pos, uint32_t a, uint32_t b, uint32_t c, uint32_t apex)
{
    if (grow((void **)&p->tets, &p->cap_tets, p->num_tets + 1, 4 * sizeof(uint32_t)))
        return clvr_error_set(in->err, CLVR_ERR_NO_MEMORY, "%s: out of memory decomposing polyhedra", in->name);
    uint32_t *t = p->tets + 4 * p->num_tets++;
    int flip = orient3(pos, a, b, c, apex) < 0.0;
    t[0] = a;
    t[1] = flip ? c : b;
    t[2] = flip ? b : c;
    t[3] = apex;
    return CLVR_OK;
}

/* Decomposes the face stream p->ids[0..n) of cell c (positions already read). */
static clvr_status poly_decompose(vtk_in *in, poly_out *p, const float *pos, uint64_t num_points, uint64_t c,
                                  uint64_t n)
{
    const int64_t *s = p->ids;
    if (n < 1 || s[0] < 4 || (uint64_t)s[0] > n)
        return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                              "%s: polyhedron cell %llu has %lld faces; a polyhedron needs at least 4 in its %llu ids",
                              in->name, (unsigned long long)c, n ? (long long)s[0] : 0LL, (unsigned long long)n);
    const uint64_t nfaces = (uint64_t)s[0];
    /* Validate the stream and every id first. */
    uint64_t at = 1;
    for (uint64_t f = 0; f < nfaces; ++f) {
        if (at >= n || s[at] < 3 || (uint64_t)s[at] > n - at - 1)
            return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                  "%s: polyhedron cell %llu: face %llu runs past the cell's %llu ids (or has fewer "
                                  "than 3 vertices)", in->name, (unsigned long long)c, (unsigned long long)f,
                                  (unsigned long long)n);
        for (int64_t k = 1; k <= s[at]; ++k)
            if (s[at + k] < 0 || (uint64_t)s[at + k] >= num_points)
                return clvr_error_set(in->err, CLVR_ERR_BAD_INDEX,
                                      "%s: polyhedron cell %llu face %llu vertex is index %lld but the mesh has %llu "
                                      "points", in->name, (unsigned long long)c, (unsigned long long)f,
                                      (long long)s[at + k], (unsigned long long)num_points);
        at += (uint64_t)s[at] + 1;
    }
    const uint32_t apex = (uint32_t)s[2];
    at = 1;
    for (uint64_t f = 0; f < nfaces; ++f) {
        const int64_t nv = s[at];
        const int64_t *v = s + at + 1;
        at += (uint64_t)nv + 1;
        int has_apex = 0;
        for (int64_t k = 0; k < nv; ++k) has_apex |= (uint32_t)v[k] == apex;
        if (has_apex) continue;
        if (nv == 4) {
            if (grow((void **)&p->pyrs, &p->cap_pyrs, p->num_pyrs + 1, 5 * sizeof(uint32_t)))
                return clvr_error_set(in->err, CLVR_ERR_NO_MEMORY, "%s: out of memory decomposing polyhedra",
                                      in->name);
            uint32_t *q = p->pyrs + 5 * p->num_pyrs++;
            /* VTK's pyramid: the base (0,1,2,3) turns counterclockwise seen from the apex. */
            double o = orient3(pos, (uint32_t)v[0], (uint32_t)v[1], (uint32_t)v[2], apex) +
                       orient3(pos, (uint32_t)v[0], (uint32_t)v[2], (uint32_t)v[3], apex);
            for (int k = 0; k < 4; ++k) q[k] = (uint32_t)v[o < 0.0 ? (4 - k) % 4 : k];
            q[4] = apex;
            continue;
        }
        for (int64_t k = 1; k + 1 < nv; ++k) {
            clvr_status st = poly_tet(in, p, pos, (uint32_t)v[0], (uint32_t)v[k], (uint32_t)v[k + 1], apex);
            if (st != CLVR_OK) return st;
        }
    }
    p->cells++;
    return CLVR_OK;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Adds a polyhedron's cell value to each of its distinct vertices. */
static clvr_status poly_accumulate(vtk_in *in, poly_out *p, uint64_t n, double cv, double *acc, uint32_t *cnt)
{
    if (grow((void **)&p->uniq, &p->cap_uniq, n, sizeof(uint32_t)))
        return clvr_error_set(in->err, CLVR_ERR_NO_MEMORY, "%s: out of memory decomposing polyhedra", in->name);
    uint64_t m = 0, at = 1;
    for (int64_t f = 0; f < p->ids[0]; ++f) {
        for (int64_t k = 1; k <= p->ids[at]; ++k) p->uniq[m++] = (uint32_t)p->ids[at + k];
        at += (uint64_t)p->ids[at] + 1;
    }
    qsort(p->uniq, (size_t)m, sizeof *p->uniq, cmp_u32);
    for (uint64_t i = 0; i < m; ++i)
        if (i == 0 || p->uniq[i] != p->uniq[i - 1]) {
            acc[p->uniq[i]] += cv;
            cnt[p->uniq[i]] += 1;
        }
    return CLVR_OK;
}

/* Pass 2: cells. Fills the index lists (counts already allocated) and,
 * for a cell-data scalar, accumulates it onto the cells' points. */
static clvr_status fill_cells(vtk_in *in, const vtk_doc *doc, const uint8_t *types, clvr_mesh *m, const cand *cell_sc,
                              int comp, double *acc, uint32_t *cnt, poly_out *poly, float *const cellv[CLVR_CELL_TYPE_COUNT])
{
    vit stream, offs, conn, sc;
    uint64_t used = 0, fill[CLVR_CELL_TYPE_COUNT] = {0, 0, 0, 0};
    int64_t prev = 0, v;
    clvr_status s = CLVR_OK;
    if (doc->new_layout) {
        vit_init(&offs, in, &doc->offsets, "OFFSETS");
        vit_init(&conn, in, &doc->conn, "CONNECTIVITY");
        if (doc->offsets.count > 0) {
            if ((s = vit_i64(&offs, &prev)) != CLVR_OK) return s;
            if (prev != 0)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD, "%s: OFFSETS[0] is %lld but must be 0", in->name,
                                      (long long)prev);
        }
    } else {
        vit_init(&stream, in, &doc->cells, "CELLS");
    }
    if (cell_sc) vit_init(&sc, in, &cell_sc->a, cell_sc->name);
    for (uint64_t c = 0; c < doc->num_cells; ++c) {
        int64_t npts;
        vit *ids = doc->new_layout ? &conn : &stream;
        if (doc->new_layout) {
            if ((s = vit_i64(&offs, &v)) != CLVR_OK) return s;
            if (v < prev || (uint64_t)v > doc->cells_size)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                      "%s: OFFSETS[%llu] is %lld, outside %lld..%llu (offsets must not decrease)",
                                      in->name, (unsigned long long)(c + 1), (long long)v, (long long)prev,
                                      (unsigned long long)doc->cells_size);
            npts = v - prev;
            prev = v;
        } else {
            if (used >= doc->cells_size)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                      "%s: CELLS size %llu is used up before cell %llu of %llu", in->name,
                                      (unsigned long long)doc->cells_size, (unsigned long long)c,
                                      (unsigned long long)doc->num_cells);
            if ((s = vit_i64(&stream, &npts)) != CLVR_OK) return s;
            ++used;
            if (npts < 0 || (uint64_t)npts > doc->cells_size - used)
                return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                      "%s: cell %llu claims %lld points, more than the CELLS list has left", in->name,
                                      (unsigned long long)c, (long long)npts);
            used += (uint64_t)npts;
        }
        int t = vtk_to_clvr_type(types[c]);
        double cv = 0.0;
        if (cell_sc) {
            double sum2 = 0.0;
            for (uint32_t k = 0; k < cell_sc->ncomp; ++k) {
                double x;
                if ((s = vit_f64(&sc, &x)) != CLVR_OK) return s;
                sum2 += x * x;
                if (comp < 0 || (uint32_t)comp == k) cv = x;
            }
            if (cell_sc->ncomp > 1 && comp < 0) cv = sqrt(sum2);
        }
        if (types[c] == VTK_POLYHEDRON) {
            if (grow((void **)&poly->ids, &poly->cap_ids, (uint64_t)npts ? (uint64_t)npts : 1, sizeof(int64_t)))
                return clvr_error_set(in->err, CLVR_ERR_NO_MEMORY, "%s: out of memory reading polyhedron %llu",
                                      in->name, (unsigned long long)c);
            for (int64_t k = 0; k < npts; ++k)
                if ((s = vit_i64(ids, &poly->ids[k])) != CLVR_OK) return s;
            const uint64_t t0 = poly->num_tets, p0 = poly->num_pyrs;
            s = poly_decompose(in, poly, m->positions, doc->num_points, c, (uint64_t)npts);
            if (s == CLVR_OK && acc && !cellv[0]) s = poly_accumulate(in, poly, (uint64_t)npts, cv, acc, cnt);
            if (s == CLVR_OK && cellv[0]) { /* --cell-data flat: every piece carries the polyhedron's value */
                if (grow((void **)&poly->tv, &poly->cap_tv, poly->num_tets ? poly->num_tets : 1, sizeof(float)) ||
                    grow((void **)&poly->pv, &poly->cap_pv, poly->num_pyrs ? poly->num_pyrs : 1, sizeof(float)))
                    return clvr_error_set(in->err, CLVR_ERR_NO_MEMORY, "%s: out of memory decomposing polyhedra",
                                          in->name);
                for (uint64_t k = t0; k < poly->num_tets; ++k) poly->tv[k] = (float)cv;
                for (uint64_t k = p0; k < poly->num_pyrs; ++k) poly->pv[k] = (float)cv;
            }
            if (s != CLVR_OK) return s;
            continue;
        }
        if (t < 0) {
            /* Skipped cell: step over its ids (binary: in place). */
            if (in->binary) ids->i += (uint64_t)npts;
            else
                for (int64_t k = 0; k < npts; ++k)
                    if ((s = vit_i64(ids, &v)) != CLVR_OK) return s;
            continue;
        }
        /* Fewer points than corners is an error; more (a higher-order cell
         * labelled linear, as in VTK's own notch_stress.vtk, which VTK
         * accepts) keeps the corners, which come first. */
        uint32_t nv = clvr_cell_vertex_count((uint32_t)t);
        if ((uint64_t)npts < nv)
            return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                                  "%s: cell %llu has VTK type %d (%s) but only %lld points, fewer than its %u corners",
                                  in->name, (unsigned long long)c, (int)types[c], clvr_cell_type_name((uint32_t)t),
                                  (long long)npts, nv);
        if (cellv[0]) cellv[t][fill[t]] = (float)cv;
        uint32_t *dst = m->indices[t] + fill[t]++ * nv;
        for (uint32_t k = 0; k < nv; ++k) {
            if ((s = vit_i64(ids, &v)) != CLVR_OK) return s;
            if (v < 0)
                return clvr_error_set(in->err, CLVR_ERR_BAD_INDEX, "%s: cell %llu vertex %u has negative index %lld",
                                      in->name, (unsigned long long)c, k, (long long)v);
            if ((uint64_t)v > UINT32_MAX || (acc && (uint64_t)v >= doc->num_points))
                return clvr_error_set(in->err, CLVR_ERR_BAD_INDEX,
                                      "%s: cell %llu vertex %u is index %lld but the mesh has %llu points", in->name,
                                      (unsigned long long)c, k, (long long)v, (unsigned long long)doc->num_points);
            dst[k] = (uint32_t)v;
            if (acc && !cellv[0]) {
                acc[v] += cv;
                cnt[v] += 1;
            }
        }
        if (in->binary) ids->i += (uint64_t)npts - nv;
        else
            for (int64_t k = nv; k < npts; ++k)
                if ((s = vit_i64(ids, &v)) != CLVR_OK) return s;
    }
    if (doc->new_layout ? (uint64_t)prev != doc->cells_size : used != doc->cells_size)
        return clvr_error_set(in->err, CLVR_ERR_BAD_FIELD,
                              "%s: the cells use %llu connectivity entries but CELLS declares %llu", in->name,
                              (unsigned long long)(doc->new_layout ? (uint64_t)prev : used),
                              (unsigned long long)doc->cells_size);
    return CLVR_OK;
}

clvr_status clvr_mesh_parse_vtk(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                clvr_mesh *out, clvr_error *err)
{
    vtk_in in = {(const uint8_t *)data, (uint64_t)size, 0, name, 0, err};
    vtk_doc doc;
    uint8_t *types = NULL;
    double *acc = NULL;
    uint32_t *cnt = NULL;
    const cand *sc = NULL;
    clvr_field_info *fields = NULL;
    int comp = CLVR_FIELD_MAGNITUDE;
    poly_out poly;
    memset(&poly, 0, sizeof poly);
    float *cellv[CLVR_CELL_TYPE_COUNT] = {NULL, NULL, NULL, NULL};
    int flat = 0;
    clvr_status s;
    memset(&doc, 0, sizeof doc);
    memset(out, 0, sizeof *out);

    s = parse_header(&in);
    if (s == CLVR_OK) s = parse_sections(&in, &doc);
    if (s != CLVR_OK) goto done;
    if (!doc.have_points || !doc.have_cells || !doc.have_types) {
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: the unstructured grid has no %s section", name,
                           !doc.have_points ? "POINTS" : !doc.have_cells ? "CELLS" : "CELL_TYPES");
        goto done;
    }
    if (doc.types.count != doc.num_cells) {
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: CELLS has %llu cells but CELL_TYPES has %llu", name,
                           (unsigned long long)doc.num_cells, (unsigned long long)doc.types.count);
        goto done;
    }
    if (doc.num_points > UINT32_MAX) {
        s = clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: %llu points but clvr indices are 32-bit (at most %u)", name,
                           (unsigned long long)doc.num_points, UINT32_MAX);
        goto done;
    }
    s = cand_fields(&in, &doc, &fields);
    if (s == CLVR_OK) s = choose_scalar(&in, &doc, opt, &sc, fields, &comp);
    if (s != CLVR_OK) goto done;

    /* Cell types: count the kept ones to size the index lists. */
    uint64_t counts[CLVR_CELL_TYPE_COUNT] = {0, 0, 0, 0}, skipped = 0, polyhedra = 0;
    if (doc.num_cells > SIZE_MAX || !(types = malloc(doc.num_cells ? (size_t)doc.num_cells : 1))) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %llu cell types", name,
                           (unsigned long long)doc.num_cells);
        goto done;
    }
    {
        vit it;
        vit_init(&it, &in, &doc.types, "CELL_TYPES");
        for (uint64_t c = 0; c < doc.num_cells; ++c) {
            int64_t v;
            if ((s = vit_i64(&it, &v)) != CLVR_OK) goto done;
            types[c] = v >= 0 && v < 255 ? (uint8_t)v : 255;
            int t = vtk_to_clvr_type(types[c]);
            if (t >= 0) ++counts[t];
            else if (types[c] == VTK_POLYHEDRON) ++polyhedra;
            else ++skipped;
        }
    }
    if (counts[0] + counts[1] + counts[2] + counts[3] + polyhedra == 0 && !(opt && opt->skip_validation)) {
        s = clvr_error_set(err, CLVR_ERR_EMPTY,
                           "%s: no tetra, pyramid, wedge or hexahedron cells (%llu cells of other types skipped)", name,
                           (unsigned long long)skipped);
        goto done;
    }
    if (sc->cell && doc.num_cells != sc->a.count / sc->ncomp) {
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: CELL_DATA array '%s' has %llu tuples for %llu cells", name,
                           sc->name, (unsigned long long)(sc->a.count / sc->ncomp), (unsigned long long)doc.num_cells);
        goto done;
    }
    if (!sc->cell && doc.num_points != sc->a.count / sc->ncomp) {
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD, "%s: POINT_DATA array '%s' has %llu tuples for %llu points", name,
                           sc->name, (unsigned long long)(sc->a.count / sc->ncomp),
                           (unsigned long long)doc.num_points);
        goto done;
    }
    s = clvr_mesh_alloc(out, doc.num_points, counts, err);
    if (s != CLVR_OK) goto done;
    out->skipped_cells = skipped;
    clvr_mesh_set_scalar_name(out, sc->name, strlen(sc->name));

    {
        vit it;
        vit_init(&it, &in, &doc.points, "POINTS");
        for (uint64_t i = 0; i < 3 * doc.num_points; ++i) {
            double x;
            if ((s = vit_f64(&it, &x)) != CLVR_OK) goto done;
            out->positions[i] = (float)x;
        }
    }
    flat = opt && opt->cell_flat && sc->cell;
    if (sc->cell) {
        acc = calloc(doc.num_points ? (size_t)doc.num_points : 1, sizeof *acc);
        cnt = calloc(doc.num_points ? (size_t)doc.num_points : 1, sizeof *cnt);
        if (!acc || !cnt) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the cell-to-point averaging buffers", name);
            goto done;
        }
    }
    if (flat) {
        /* --cell-data flat: each element's own value, per type; polyhedron pieces in poly.tv/pv. */
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t)
            if (!(cellv[t] = malloc(counts[t] ? (size_t)counts[t] * sizeof(float) : sizeof(float))))
                s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the cell values", name);
        if (s != CLVR_OK) goto done;
    }
    s = fill_cells(&in, &doc, types, out, sc->cell ? sc : NULL, comp, acc, cnt, &poly, cellv);
    if (s != CLVR_OK) goto done;
    if (poly.num_tets || poly.num_pyrs) {
        /* The pieces go after the file's own tets and pyramids. */
        const uint64_t add[2] = {poly.num_tets, poly.num_pyrs};
        const uint32_t *src[2] = {poly.tets, poly.pyrs};
        for (uint32_t t = 0; t < 2; ++t) {
            uint64_t total, bytes;
            const uint32_t nv = clvr_cell_vertex_count(t);
            if (!add[t]) continue;
            if (clvr_add_u64(out->num_cells[t], add[t], &total) || clvr_mul_u64(total, nv * sizeof(uint32_t), &bytes) ||
                bytes > SIZE_MAX) {
                s = clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: decomposed polyhedra overflow the %s list", name,
                                   clvr_cell_type_name(t));
                goto done;
            }
            uint32_t *q = realloc(out->indices[t], (size_t)bytes);
            if (!q) {
                s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory for decomposed polyhedra", name);
                goto done;
            }
            memcpy(q + out->num_cells[t] * nv, src[t], (size_t)(add[t] * nv * sizeof(uint32_t)));
            out->indices[t] = q;
            out->num_cells[t] = total;
        }
    }
    out->decomposed_cells = poly.cells;
    if (flat) {
        /* One value per element in mesh order: each type's file cells, then its polyhedron pieces. */
        uint64_t ne = clvr_mesh_num_elements(out), e = 0;
        float *all = ne <= SIZE_MAX / sizeof(float) ? malloc(ne ? (size_t)ne * sizeof(float) : 1) : NULL;
        if (!all) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the cell values", name);
            goto done;
        }
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            memcpy(all + e, cellv[t], (size_t)counts[t] * sizeof(float));
            e += counts[t];
            const float *extra = t == 0 ? poly.tv : t == 1 ? poly.pv : NULL;
            const uint64_t n_extra = t == 0 ? poly.num_tets : t == 1 ? poly.num_pyrs : 0;
            if (n_extra) memcpy(all + e, extra, (size_t)n_extra * sizeof(float));
            e += n_extra;
        }
        s = clvr_mesh_flatten_cells(out, all, name, err);
        free(all);
        if (s != CLVR_OK) goto done;
    }
    if (flat) {
        /* scalars set by clvr_mesh_flatten_cells */
    } else if (sc->cell) {
        for (uint64_t i = 0; i < doc.num_points; ++i) out->scalars[i] = cnt[i] ? (float)(acc[i] / cnt[i]) : 0.0f;
    } else {
        vit it;
        vit_init(&it, &in, &sc->a, sc->name);
        for (uint64_t i = 0; i < doc.num_points; ++i) {
            double sum2 = 0.0, x = 0.0, pick = 0.0;
            for (uint32_t k = 0; k < sc->ncomp; ++k) {
                if ((s = vit_f64(&it, &x)) != CLVR_OK) goto done;
                sum2 += x * x;
                if (comp < 0 || (uint32_t)comp == k) pick = x;
            }
            out->scalars[i] = (float)(sc->ncomp > 1 && comp < 0 ? sqrt(sum2) : pick);
        }
    }
    clvr_mesh_update_ranges(out);
    /* The field table for --info: ranges of every array on request, the
     * chosen point array's from the scalars. */
    for (size_t i = 0; i < doc.cands.n && s == CLVR_OK && opt && opt->field_ranges; ++i)
        s = cand_range(&in, &doc.cands.v[i], &fields[i]);
    if (s != CLVR_OK) goto done;
    {
        uint32_t fi = (uint32_t)(sc - doc.cands.v);
        if (!sc->cell && (comp < 0 || sc->ncomp == 1)) {
            fields[fi].has_range = 1;
            fields[fi].min = out->scalar_min;
            fields[fi].max = out->scalar_max;
        }
        if (comp >= 0 && sc->ncomp > 1) {
            char label[CLVR_SCALAR_NAME_MAX + 16];
            if (comp < 3) snprintf(label, sizeof label, "%s:%c", fields[fi].name, "xyz"[comp]);
            else snprintf(label, sizeof label, "%s:%d", fields[fi].name, comp);
            clvr_mesh_set_scalar_name(out, label, strlen(label));
        }
        out->fields = fields;
        out->num_fields = (uint32_t)doc.cands.n;
        out->scalar_field = fi;
        out->scalar_component = comp;
        fields = NULL;
    }
    if (!(opt && opt->skip_validation)) s = clvr_mesh_validate(out, name, err);
done:
    if (s != CLVR_OK) clvr_mesh_free(out);
    free(types);
    free(acc);
    free(cnt);
    free(fields);
    poly_free(&poly);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) free(cellv[t]);
    free(doc.cands.v);
    return s;
}
