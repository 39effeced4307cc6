/* clvr_api.c: libclvr's public API (clvr.h) over the pipeline objects: the
 * OpenCL context (cl_context.h), the mesh (mesh.h) seen through a borrowed
 * view of the dataset's arrays, Quick Clusters (preprocess.h), the trees
 * (accel.h), the renderer (render.h), the transfer function (tf.h,
 * tf_auto.h) and the image writers (image.h). Internal statuses map one to
 * one onto clvr_result (checked at compile time below). */
#define CLVR_API_BUILD 1
#include "clvr.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"
#include "camera.h"
#include "cl_context.h"
#include "clock.h"
#include "denoiser.h"
#include "image.h"
#include "limits_check.h"
#include "outline.h"
#include "mesh.h"
#include "mesh_io.h"
#include "partition.h"
#include "preprocess.h"
#include "render.h"
#include "scene.h"
#include "series_file.h"
#include "status.h"
#include "tf.h"
#include "tf_auto.h"

/* Every internal status has a public twin with the same value: a status
 * added to CLVR_STATUS_MAP without one in clvr.h fails to compile here. */
#define CLVR_API_SAME(name, code, text)                                                                               \
    _Static_assert((int)CLVR_RESULT_##name == (int)CLVR_##name, "clvr_result " #name " drifted from clvr_status");
CLVR_STATUS_MAP(CLVR_API_SAME)
#undef CLVR_API_SAME
_Static_assert((int)CLVR_RESULT_COUNT == (int)CLVR_STATUS_COUNT, "clvr_result and clvr_status differ in length");
_Static_assert(sizeof(((clvr_message *)0)->text) == sizeof(((clvr_error *)0)->msg), "message sizes differ");

/* Cell type names of the API, in CLVR_CELL_* order (meshio / VTK names). */
static const char *const cell_names[CLVR_CELL_TYPE_COUNT] = {"tetra", "pyramid", "wedge", "hexahedron"};

typedef struct dataset_field {
    char name[CLVR_SCALAR_NAME_MAX];
    const float *values;
    float *owned; /* == values when copied, else NULL */
    float lo, hi;
    int from_file;       /* a field of the loaded file (its table lists it) */
    uint32_t file_index; /* its index in the file's table */
} dataset_field;

struct clvr_dataset {
    unsigned refs; /* the caller's + one per tracer */
    uint64_t num_points;
    const float *xyz;
    float *xyz_owned;
    uint64_t num_cells[CLVR_CELL_TYPE_COUNT];
    const uint32_t *cells[CLVR_CELL_TYPE_COUNT];
    uint32_t *cells_owned[CLVR_CELL_TYPE_COUNT];
    int has_cells[CLVR_CELL_TYPE_COUNT];
    uint32_t num_fields;
    dataset_field *fields;
    float lo[3], hi[3];
    clvr_mesh loaded; /* a file's mesh, whose arrays the pointers above borrow */
    char *path;       /* the file, for its other fields (loaded when a scene names them) */
    int cell_flat;    /* loaded with cell data shown flat */
    int consumed;     /* a scene took the loaded cell lists apart (clvr_preprocess_settings.consume) */
};

struct clvr_context {
    clvr_cl cl;
    unsigned tracers; /* live scenes (each tracer holds one) */
    int closing;      /* clvr_context_destroy came while scenes lived: the last one frees ctx */
};


static uint32_t table_fields(const clvr_dataset *ds);
static void table_field(const clvr_dataset *ds, uint32_t i, clvr_dataset_field *f);
static void dataset_release(clvr_dataset *ds);

/* --- results -------------------------------------------------------------- */

/* Finishes a call: copies err into msg on failure, clears msg on success. */
static clvr_result finish(clvr_status s, const clvr_error *err, clvr_message *msg)
{
    if (msg) {
        msg->result = (clvr_result)s;
        if (s == CLVR_OK) msg->text[0] = '\0';
        else {
            memcpy(msg->text, err->msg, sizeof msg->text);
            msg->text[sizeof msg->text - 1] = '\0';
            if (!msg->text[0]) snprintf(msg->text, sizeof msg->text, "%s", clvr_status_text(s));
        }
    }
    return (clvr_result)s;
}

#define NULL_ARG(fn, arg) clvr_error_set(&e, CLVR_ERR_USAGE, "%s: %s is NULL", fn, arg)

/* Reads a versioned struct: the caller's size must cover the 1.1 struct
 * (min_size); members it lacks (a caller built against an older header)
 * keep this version's defaults, and bytes past this version's struct are
 * not read. None of the input structs has grown since 1.1 yet, so their
 * callers pass sizeof: a member appended later passes the offset of its
 * first new member instead, as versioned_out's callers do. */
#define VERSIONED_IN_SINCE(fn, p, type, local, min_size)                                                              \
    do {                                                                                                              \
        clvr_##type##_init(&(local));                                                                                 \
        if (p) {                                                                                                      \
            if ((p)->size < (min_size))                                                                               \
                return finish(clvr_error_set(&e, CLVR_ERR_USAGE,                                                      \
                                             "%s: " #type ".size is %u; set it to sizeof(clvr_" #type ") (%zu), "   \
                                             "e.g. with clvr_" #type "_init",                                        \
                                             fn, (unsigned)(p)->size, sizeof(local)),                                 \
                              &e, msg);                                                                               \
            memcpy(&(local), (p), (p)->size < sizeof(local) ? (p)->size : sizeof(local));                             \
            (local).size = (uint32_t)sizeof(local);                                                                   \
        }                                                                                                             \
    } while (0)
#define VERSIONED_IN(fn, p, type, local) VERSIONED_IN_SINCE(fn, p, type, local, sizeof(local))

/* Writes a versioned struct out: local (this version's, local_size bytes)
 * into out, whose size member says how much the caller has. A caller built
 * against an older header has a smaller struct: it gets the members it
 * knows, as long as it has at least the 1.1 struct (min_size: the offset of
 * the first member appended since, or local_size when none was). Before
 * session 55 this asked for this version's full size, so a program built
 * against 1.5 got ERR_USAGE from 1.6's clvr_tracer_get_render_stats and one
 * built against 1.8 from 1.9's clvr_scene_get_stats. */
static clvr_status versioned_out(const char *fn, const char *type, void *out, const void *local, size_t local_size,
                                 size_t min_size, clvr_error *e)
{
    uint32_t size;
    memcpy(&size, out, sizeof size);
    if (size < min_size)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: %s.size is %u; set it to sizeof(%s) (%zu)", fn, type,
                              (unsigned)size, type, local_size);
    memcpy(out, local, size < local_size ? size : local_size);
    memcpy(out, &size, sizeof size);
    return CLVR_OK;
}

static int finite3(const float *v) { return v && isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }


unsigned clvr_api_version(void) { return CLVR_API_VERSION; }
const char *clvr_version_string(void) { return CLVR_VERSION; }
const char *clvr_result_name(clvr_result r) { return clvr_status_name((clvr_status)r); }
const char *clvr_result_text(clvr_result r) { return clvr_status_text((clvr_status)r); }
int clvr_result_exit_code(clvr_result r) { return clvr_status_exit_code((clvr_status)r); }

/* --- context -------------------------------------------------------------- */

clvr_result clvr_context_create(const char *device, clvr_context **out, clvr_message *msg)
{
    clvr_error e = {0};
    clvr_status s;
    if (!out) return finish(NULL_ARG("clvr_context_create", "out"), &e, msg);
    clvr_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "out of memory for a context"), &e, msg);
    s = clvr_cl_create(device, &ctx->cl, &e);
    if (s != CLVR_OK) {
        clvr_cl_destroy(&ctx->cl);
        free(ctx);
        return finish(s, &e, msg);
    }
    *out = ctx;
    return finish(CLVR_OK, &e, msg);
}

void clvr_context_destroy(clvr_context *ctx)
{
    if (!ctx) return;
    /* Scenes and tracers release their device buffers through ctx: freeing
     * it under them corrupted the heap when a program (or Python's garbage
     * collector at exit) destroyed them in the other order. */
    if (ctx->tracers) {
        ctx->closing = 1;
        return;
    }
    clvr_cl_destroy(&ctx->cl);
    free(ctx);
}

static clvr_status warm_up(clvr_context *ctx, const clvr_preprocess_options *po, clvr_error *err)
{
    clvr_scene_box_params bp;
    clvr_scene_box_params_init(&bp);
    bp.nx = bp.ny = bp.nz = 4;
    bp.mix = CLVR_SCENE_MIX_CYCLE;
    clvr_mesh tiny = {0};
    clvr_clustered tc = {0};
    clvr_accel ta = {0};
    clvr_status s = clvr_scene_box(&bp, &tiny, err);
    if (s == CLVR_OK) s = clvr_preprocess(&ctx->cl, &tiny, po, &tc, err);
    if (s == CLVR_OK) s = clvr_accel_build(&ctx->cl, &tc, &ta, err);
    clvr_accel_release(&ctx->cl, &ta);
    clvr_clustered_release(&ctx->cl, &tc);
    clvr_mesh_free(&tiny);
    return s;
}

clvr_result clvr_context_warm_up(clvr_context *ctx, clvr_message *msg)
{
    clvr_error e = {0};
    if (!ctx) return finish(NULL_ARG("clvr_context_warm_up", "ctx"), &e, msg);
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    return finish(warm_up(ctx, &po, &e), &e, msg);
}

static void copy_str(char *dst, size_t size, const char *src)
{
    if (dst && size) snprintf(dst, size, "%s", src);
}

clvr_result clvr_context_describe(const clvr_context *ctx, char *device, size_t device_size, char *platform,
                                  size_t platform_size, clvr_message *msg)
{
    clvr_error e = {0};
    if (!ctx) return finish(NULL_ARG("clvr_context_describe", "ctx"), &e, msg);
    copy_str(device, device_size, ctx->cl.device_name);
    copy_str(platform, platform_size, ctx->cl.platform_name);
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_list_devices(char *buf, size_t size, clvr_message *msg)
{
    clvr_error e = {0};
    if (!buf || !size) return finish(NULL_ARG("clvr_list_devices", "buf (or size 0)"), &e, msg);
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f) return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "out of memory listing devices"), &e, msg);
    clvr_status s = clvr_cl_list_devices(f, &e);
    fclose(f);
    if (s == CLVR_OK) copy_str(buf, size, text ? text : "");
    free(text);
    return finish(s, &e, msg);
}

/* --- dataset -------------------------------------------------------------- */

static void update_bounds(clvr_dataset *ds)
{
    for (int k = 0; k < 3; ++k) {
        ds->lo[k] = INFINITY;
        ds->hi[k] = -INFINITY;
    }
    for (uint64_t i = 0; i < ds->num_points; ++i)
        for (int k = 0; k < 3; ++k) {
            const float v = ds->xyz[3 * i + k];
            if (v < ds->lo[k]) ds->lo[k] = v;
            if (v > ds->hi[k]) ds->hi[k] = v;
        }
}

/* Copies n elements of size sz when own is CLVR_COPY. */
static clvr_status take(const void *src, uint64_t n, size_t sz, clvr_ownership own, const void **view, void **owned,
                        const char *what, clvr_error *e)
{
    *owned = NULL;
    *view = src;
    if (own == CLVR_BORROW) return CLVR_OK;
    uint64_t bytes;
    if (clvr_mul_u64(n, sz, &bytes) || bytes > SIZE_MAX)
        return clvr_error_set(e, CLVR_ERR_OVERFLOW, "%s: %llu elements overflow the address space", what,
                              (unsigned long long)n);
    void *p = malloc(bytes ? (size_t)bytes : 1);
    if (!p) return clvr_error_set(e, CLVR_ERR_NO_MEMORY, "%s: out of memory copying %llu bytes", what,
                                  (unsigned long long)bytes);
    if (bytes) memcpy(p, src, (size_t)bytes);
    *owned = p;
    *view = p;
    return CLVR_OK;
}

static int bad_ownership(clvr_ownership own) { return own != CLVR_COPY && own != CLVR_BORROW; }

clvr_result clvr_dataset_create(uint64_t num_points, const float *xyz, clvr_ownership own, clvr_dataset **out,
                                clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_create";
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    if (!xyz) return finish(NULL_ARG(fn, "xyz"), &e, msg);
    if (bad_ownership(own))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: own is %d; use CLVR_COPY or CLVR_BORROW", fn, (int)own),
                      &e, msg);
    if (num_points == 0 || num_points > 0xffffffffull)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: num_points is %llu; it must be in [1, 2^32 - 1]", fn,
                                     (unsigned long long)num_points),
                      &e, msg);
    for (uint64_t i = 0; i < 3 * num_points; ++i)
        if (!isfinite(xyz[i]))
            return finish(clvr_error_set(&e, CLVR_ERR_BAD_VALUE, "%s: point %llu has a non-finite %c coordinate (%g)",
                                         fn, (unsigned long long)(i / 3), "xyz"[i % 3], (double)xyz[i]),
                          &e, msg);
    clvr_dataset *ds = calloc(1, sizeof *ds);
    if (!ds) return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn), &e, msg);
    const void *view;
    void *owned;
    clvr_status s = take(xyz, 3 * num_points, sizeof(float), own, &view, &owned, "points", &e);
    if (s != CLVR_OK) {
        free(ds);
        return finish(s, &e, msg);
    }
    ds->refs = 1;
    ds->num_points = num_points;
    ds->xyz = view;
    ds->xyz_owned = owned;
    update_bounds(ds);
    *out = ds;
    return finish(CLVR_OK, &e, msg);
}

static int cell_type_of(const char *name)
{
    for (int t = 0; t < (int)CLVR_CELL_TYPE_COUNT; ++t)
        if (!strcmp(name, cell_names[t])) return t;
    return -1;
}

clvr_result clvr_dataset_add_cells(clvr_dataset *ds, const char *type, uint64_t num_cells, const uint32_t *indices,
                                   clvr_ownership own, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_add_cells";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!type) return finish(NULL_ARG(fn, "type"), &e, msg);
    if (!indices && num_cells) return finish(NULL_ARG(fn, "indices"), &e, msg);
    if (bad_ownership(own))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: own is %d; use CLVR_COPY or CLVR_BORROW", fn, (int)own),
                      &e, msg);
    const int t = cell_type_of(type);
    if (t < 0)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE,
                                     "%s: unknown cell type '%.64s'; use tetra, pyramid, wedge or hexahedron", fn, type),
                      &e, msg);
    if (ds->has_cells[t])
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: %s cells were added already; add each type once", fn,
                                     type),
                      &e, msg);
    if (num_cells == 0) return finish(CLVR_OK, &e, msg);
    const uint32_t nv = clvr_cell_vertex_count((uint32_t)t);
    uint64_t n;
    if (clvr_mul_u64(num_cells, nv, &n))
        return finish(clvr_error_set(&e, CLVR_ERR_OVERFLOW, "%s: %llu %s cells overflow", fn,
                                     (unsigned long long)num_cells, type),
                      &e, msg);
    for (uint64_t i = 0; i < n; ++i)
        if (indices[i] >= ds->num_points)
            return finish(clvr_error_set(&e, CLVR_ERR_BAD_INDEX,
                                         "%s: %s cell %llu vertex %u is %u but the dataset has %llu points", fn, type,
                                         (unsigned long long)(i / nv), (unsigned)(i % nv), indices[i],
                                         (unsigned long long)ds->num_points),
                          &e, msg);
    const void *view;
    void *owned;
    clvr_status s = take(indices, n, sizeof(uint32_t), own, &view, &owned, type, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    ds->cells[t] = view;
    ds->cells_owned[t] = owned;
    ds->num_cells[t] = num_cells;
    ds->has_cells[t] = 1;
    return finish(CLVR_OK, &e, msg);
}

static int find_field(const clvr_dataset *ds, const char *name)
{
    if (!name) return ds->num_fields ? 0 : -1;
    for (uint32_t i = 0; i < ds->num_fields; ++i)
        if (!strcmp(ds->fields[i].name, name)) return (int)i;
    return -1;
}

/* "a, b, c" of the dataset's field names into buf. */
static const char *field_list(const clvr_dataset *ds, char *buf, size_t size)
{
    size_t len = 0;
    buf[0] = '\0';
    for (uint32_t i = 0; i < ds->num_fields && len + 1 < size; ++i)
        len += (size_t)snprintf(buf + len, size - len, "%s'%s'", i ? ", " : "", ds->fields[i].name);
    if (!ds->num_fields) snprintf(buf, size, "none");
    return buf;
}

static clvr_status push_field(clvr_dataset *ds, const char *name, const float *values, float *owned, clvr_error *e)
{
    dataset_field *f = realloc(ds->fields, (ds->num_fields + 1) * sizeof *f);
    if (!f) return clvr_error_set(e, CLVR_ERR_NO_MEMORY, "out of memory adding field '%s'", name);
    ds->fields = f;
    dataset_field *nf = &f[ds->num_fields];
    memset(nf, 0, sizeof *nf);
    snprintf(nf->name, sizeof nf->name, "%s", name);
    nf->values = values;
    nf->owned = owned;
    nf->lo = INFINITY;
    nf->hi = -INFINITY;
    for (uint64_t i = 0; i < ds->num_points; ++i) {
        if (values[i] < nf->lo) nf->lo = values[i];
        if (values[i] > nf->hi) nf->hi = values[i];
    }
    ++ds->num_fields;
    return CLVR_OK;
}

clvr_result clvr_dataset_add_field(clvr_dataset *ds, const char *name, const float *values, clvr_ownership own,
                                   clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_add_field";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!name) return finish(NULL_ARG(fn, "name"), &e, msg);
    if (!values) return finish(NULL_ARG(fn, "values"), &e, msg);
    if (bad_ownership(own))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: own is %d; use CLVR_COPY or CLVR_BORROW", fn, (int)own),
                      &e, msg);
    size_t len = strlen(name);
    int printable = len > 0 && len < CLVR_SCALAR_NAME_MAX;
    for (size_t i = 0; printable && i < len; ++i)
        if ((unsigned char)name[i] < 0x20 || name[i] == 0x7f || name[i] == '"' || name[i] == '\\') printable = 0;
    if (!printable)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE,
                                     "%s: field name must be 1 to %d printable characters without quotes or "
                                     "backslashes (got %zu bytes)",
                                     fn, CLVR_SCALAR_NAME_MAX - 1, len),
                      &e, msg);
    if (find_field(ds, name) >= 0)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: the dataset has a field '%s' already", fn, name), &e,
                      msg);
    for (uint64_t i = 0; i < ds->num_points; ++i)
        if (!isfinite(values[i]))
            return finish(clvr_error_set(&e, CLVR_ERR_BAD_VALUE, "%s: field '%s' is %g at point %llu; values must be "
                                         "finite", fn, name, (double)values[i], (unsigned long long)i),
                          &e, msg);
    const void *view;
    void *owned;
    clvr_status s = take(values, ds->num_points, sizeof(float), own, &view, &owned, name, &e);
    if (s == CLVR_OK) {
        s = push_field(ds, name, view, owned, &e);
        if (s != CLVR_OK) free(owned);
    }
    return finish(s, &e, msg);
}

static clvr_status dataset_adopt(clvr_mesh *m, clvr_dataset **out, clvr_error *err)
{
    clvr_dataset *ds = calloc(1, sizeof *ds);
    if (!ds) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for a dataset");
    ds->loaded = *m;
    memset(m, 0, sizeof *m);
    m = &ds->loaded;
    ds->refs = 1;
    ds->num_points = m->num_vertices;
    ds->xyz = m->positions;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        ds->cells[t] = m->indices[t];
        ds->num_cells[t] = m->num_cells[t];
        ds->has_cells[t] = m->num_cells[t] > 0;
    }
    update_bounds(ds);
    clvr_status s = push_field(ds, m->scalar_name[0] ? m->scalar_name : "scalar", m->scalars, NULL, err);
    if (s == CLVR_OK) {
        ds->fields[0].from_file = 1;
        ds->fields[0].file_index = m->scalar_field;
    }
    ds->cell_flat = m->cell_flat;
    if (s != CLVR_OK) {
        clvr_mesh_free(&ds->loaded);
        free(ds->fields);
        free(ds);
        return s;
    }
    *out = ds;
    return CLVR_OK;
}

void clvr_load_settings_init(clvr_load_settings *s)
{
    if (!s) return;
    memset(s, 0, sizeof *s);
    s->size = sizeof *s;
}

static clvr_status dataset_load(const char *path, const clvr_load_settings *ls, clvr_dataset **out, clvr_error *e)
{
    clvr_mesh m = {0};
    clvr_load_options lo = {0};
    lo.scalar_name = ls->field;
    lo.cell_flat = ls->cell_flat;
    lo.field_ranges = ls->field_ranges;
    lo.map_indices = lo.map_vertices = 1; /* a .bin's arrays stay page cache: no second host copy */
    char *copy = strdup(path);
    if (!copy) return clvr_error_set(e, CLVR_ERR_NO_MEMORY, "out of memory");
    clvr_status s = clvr_mesh_load(path, &lo, &m, e);
    if (s == CLVR_OK) {
        if (!m.scalar_name[0] && ls->field) clvr_mesh_set_scalar_name(&m, ls->field, strlen(ls->field));
        s = dataset_adopt(&m, out, e);
    }
    if (s == CLVR_OK) (*out)->path = copy;
    else free(copy);
    clvr_mesh_free(&m);
    return s;
}

clvr_result clvr_dataset_load(const char *path, const char *field, clvr_dataset **out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_load";
    if (!path) return finish(NULL_ARG(fn, "path"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_load_settings ls;
    clvr_load_settings_init(&ls);
    ls.field = field;
    return finish(dataset_load(path, &ls, out, &e), &e, msg);
}

clvr_result clvr_dataset_load_with(const char *path, const clvr_load_settings *s, clvr_dataset **out,
                                   clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_load_with";
    if (!path) return finish(NULL_ARG(fn, "path"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_load_settings ls;
    VERSIONED_IN(fn, s, load_settings, ls);
    return finish(dataset_load(path, &ls, out, &e), &e, msg);
}

clvr_result clvr_dataset_create_demo(clvr_dataset **out, clvr_message *msg)
{
    clvr_error e = {0};
    if (!out) return finish(NULL_ARG("clvr_dataset_create_demo", "out"), &e, msg);
    clvr_mesh m = {0};
    clvr_status s = clvr_scene_default(&m, &e);
    if (s == CLVR_OK) s = dataset_adopt(&m, out, &e);
    clvr_mesh_free(&m);
    return finish(s, &e, msg);
}

static void dataset_release(clvr_dataset *ds)
{
    if (!ds || --ds->refs > 0) return;
    free(ds->xyz_owned);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) free(ds->cells_owned[t]);
    for (uint32_t i = 0; i < ds->num_fields; ++i) free(ds->fields[i].owned);
    free(ds->fields);
    clvr_mesh_free(&ds->loaded);
    free(ds->path);
    free(ds);
}

void clvr_dataset_destroy(clvr_dataset *ds) { dataset_release(ds); }

clvr_result clvr_dataset_counts(const clvr_dataset *ds, uint64_t *num_points, uint64_t num_cells[4],
                                uint32_t *num_fields, clvr_message *msg)
{
    clvr_error e = {0};
    if (!ds) return finish(NULL_ARG("clvr_dataset_counts", "ds"), &e, msg);
    if (num_points) *num_points = ds->num_points;
    if (num_cells) memcpy(num_cells, ds->num_cells, sizeof ds->num_cells);
    if (num_fields) *num_fields = table_fields(ds);
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_dataset_field_name(const clvr_dataset *ds, uint32_t i, char *buf, size_t size, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_field_name";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!buf || !size) return finish(NULL_ARG(fn, "buf (or size 0)"), &e, msg);
    if (i >= table_fields(ds))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: field %u asked but the dataset has %u", fn, i,
                                     table_fields(ds)),
                      &e, msg);
    clvr_dataset_field f;
    table_field(ds, i, &f);
    copy_str(buf, size, f.name);
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_dataset_bounds(const clvr_dataset *ds, float lo[3], float hi[3], clvr_message *msg)
{
    clvr_error e = {0};
    if (!ds) return finish(NULL_ARG("clvr_dataset_bounds", "ds"), &e, msg);
    if (!lo || !hi) return finish(NULL_ARG("clvr_dataset_bounds", "lo or hi"), &e, msg);
    memcpy(lo, ds->lo, sizeof ds->lo);
    memcpy(hi, ds->hi, sizeof ds->hi);
    return finish(CLVR_OK, &e, msg);
}

static clvr_status lookup_field(const clvr_dataset *ds, const char *fn, const char *field, int *out, clvr_error *e)
{
    char names[512];
    *out = find_field(ds, field);
    if (*out >= 0) return CLVR_OK;
    if (!field)
        return clvr_error_set(e, CLVR_ERR_BAD_FIELD, "%s: the dataset has no field; add one with clvr_dataset_add_field",
                              fn);
    return clvr_error_set(e, CLVR_ERR_BAD_FIELD, "%s: no field '%.64s'; the dataset has %s", fn, field,
                          field_list(ds, names, sizeof names));
}

/* lookup_field, and for a loaded file's field not in memory yet: reads it
 * (the file's field table names it; the loader picks the array and the
 * component, as for the program's --scalar) and keeps it under `field`. */
static clvr_status resolve_field(clvr_dataset *ds, const char *fn, const char *field, int *out, clvr_error *e)
{
    if (!field || !ds->path || !ds->loaded.num_fields) return lookup_field(ds, fn, field, out, e);
    if ((*out = find_field(ds, field)) >= 0) return CLVR_OK;
    uint32_t index;
    int component;
    clvr_status s = clvr_field_select(ds->loaded.fields, ds->loaded.num_fields, field, ds->path, &index, &component, e);
    if (s != CLVR_OK) return s;
    if (index == ds->loaded.scalar_field && component == ds->loaded.scalar_component) {
        *out = 0; /* the field loaded first, by another spelling */
        return CLVR_OK;
    }
    if (ds->consumed)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: field '%.64s': the dataset's cells were consumed by an earlier "
                              "scene; load %s again", fn, field, ds->path);
    clvr_mesh m = {0};
    clvr_load_options lo = {0};
    lo.scalar_name = field;
    lo.cell_flat = ds->cell_flat;
    lo.map_indices = lo.map_vertices = 1;
    s = clvr_mesh_load(ds->path, &lo, &m, e);
    if (s == CLVR_OK && (m.num_vertices != ds->num_points || m.cell_flat != ds->cell_flat))
        s = clvr_error_set(e, CLVR_ERR_BAD_FIELD,
                           "%s: field '%.64s' of %s gives the mesh other points (%llu, not %llu: cell data shown "
                           "flat); load the file with this field (clvr_load_settings.field)",
                           fn, field, ds->path, (unsigned long long)m.num_vertices,
                           (unsigned long long)ds->num_points);
    if (s == CLVR_OK) s = push_field(ds, field, m.scalars, m.scalars, e);
    if (s == CLVR_OK) {
        m.scalars = NULL; /* the dataset owns it now */
        ds->fields[ds->num_fields - 1].from_file = 1;
        ds->fields[ds->num_fields - 1].file_index = index;
        if (m.num_fields == ds->loaded.num_fields) /* the file's range of the array, now decoded */
            for (uint32_t i = 0; i < m.num_fields; ++i)
                if (m.fields[i].has_range && !ds->loaded.fields[i].has_range) ds->loaded.fields[i] = m.fields[i];
        *out = (int)ds->num_fields - 1;
    }
    clvr_mesh_free(&m);
    return s;
}

/* The fields a caller sees: a loaded file's table (every array, in memory
 * or not), then the fields added with clvr_dataset_add_field. */
static uint32_t table_fields(const clvr_dataset *ds)
{
    uint32_t n = ds->loaded.num_fields;
    for (uint32_t i = 0; i < ds->num_fields; ++i) n += !(ds->fields[i].from_file && ds->loaded.num_fields);
    return n;
}

/* Field i of the table into f. */
static void table_field(const clvr_dataset *ds, uint32_t i, clvr_dataset_field *f)
{
    memset(f, 0, sizeof *f);
    f->size = sizeof *f;
    if (i < ds->loaded.num_fields) {
        const clvr_field_info *fi = &ds->loaded.fields[i];
        snprintf(f->name, sizeof f->name, "%s", fi->name);
        f->is_cell = fi->association == CLVR_FIELD_CELL;
        f->components = fi->components;
        f->has_range = fi->has_range;
        f->min = fi->min;
        f->max = fi->max;
        for (uint32_t k = 0; k < ds->num_fields; ++k) f->loaded |= ds->fields[k].from_file && ds->fields[k].file_index == i;
        return;
    }
    i -= ds->loaded.num_fields;
    for (uint32_t k = 0; k < ds->num_fields; ++k) {
        if (ds->fields[k].from_file && ds->loaded.num_fields) continue;
        if (i-- == 0) {
            snprintf(f->name, sizeof f->name, "%s", ds->fields[k].name);
            f->components = 1;
            f->has_range = 1;
            f->min = ds->fields[k].lo;
            f->max = ds->fields[k].hi;
            f->loaded = 1;
            return;
        }
    }
}

clvr_result clvr_dataset_field_range(const clvr_dataset *ds, const char *field, float *min, float *max,
                                     clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_field_range";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!min || !max) return finish(NULL_ARG(fn, "min or max"), &e, msg);
    int i;
    clvr_status s = lookup_field(ds, fn, field, &i, &e);
    if (s != CLVR_OK && field) /* a file's field not in memory yet: the range its table has */
        for (uint32_t k = 0; k < ds->loaded.num_fields; ++k)
            if (!strcmp(ds->loaded.fields[k].name, field) && ds->loaded.fields[k].has_range) {
                *min = ds->loaded.fields[k].min;
                *max = ds->loaded.fields[k].max;
                return finish(CLVR_OK, &e, msg);
            }
    if (s != CLVR_OK) return finish(s, &e, msg);
    *min = ds->fields[i].lo;
    *max = ds->fields[i].hi;
    return finish(CLVR_OK, &e, msg);
}

/* The pipeline's mesh over the dataset's arrays and field i: borrowed
 * pointers, never freed (clvr_mesh_free must not see it). */
static void mesh_view(const clvr_dataset *ds, uint32_t field, clvr_mesh *m)
{
    memset(m, 0, sizeof *m);
    m->num_vertices = ds->num_points;
    m->positions = (float *)ds->xyz;
    m->scalars = (float *)ds->fields[field].values;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        m->num_cells[t] = ds->num_cells[t];
        m->indices[t] = (uint32_t *)ds->cells[t];
    }
    clvr_mesh_set_scalar_name(m, ds->fields[field].name, strlen(ds->fields[field].name));
    memcpy(m->bounds_lo, ds->lo, sizeof m->bounds_lo);
    memcpy(m->bounds_hi, ds->hi, sizeof m->bounds_hi);
    m->scalar_min = ds->fields[field].lo;
    m->scalar_max = ds->fields[field].hi;
}


/* --- scenes and tracers --------------------------------------------------- */

/* A preprocessed dataset: what every tracer on it shares. */
struct clvr_scene {
    unsigned refs; /* the caller's + one per tracer */
    clvr_context *ctx;
    clvr_dataset *ds; /* NULL after clvr_scene_drop_dataset */
    uint32_t field;
    char field_name[CLVR_SCALAR_NAME_MAX];
    float lo[3], hi[3];       /* the dataset's bounds */
    float scalar_lo, scalar_hi;
    uint64_t points;          /* the dataset's points */
    uint64_t bytes_points_before, bytes_indices_before;
    clvr_clustered clustered;
    clvr_accel accel;
    double preprocess_s;
    uint32_t partitions; /* preprocessing partitions used */
};

struct clvr_tracer {
    clvr_context *ctx;
    clvr_scene *sc;
    clvr_dataset *ds; /* the scene's, held too; NULL after clvr_tracer_drop_dataset */
    uint32_t field;
    float lo[3], hi[3]; /* the dataset's bounds */
    clvr_tf tf;         /* the transfer function set by options (clvr_tracer_edit_tf edits it) */
    int tf_state;       /* 0: none yet (the automatic one at first use), 1: options (tf), 2: a table */
    float auto_density; /* the automatic density factor of the last options */
    float ext_scale;    /* the table's extinction per unit opacity */
    float *table;       /* the baked table in use */
    uint32_t table_n;
    clvr_renderer *renderer;
    clvr_render_settings rs;
    int shadows; /* asked for; march has none */
    clvr_camera cam;
    float up[3];
    float density, range_lo, range_hi;
    uint64_t frames;
    clvr_denoiser *denoiser; /* made at the first clvr_tracer_read_denoised */
};

static void scene_release(clvr_scene *sc)
{
    if (!sc || --sc->refs > 0) return;
    clvr_context *ctx = sc->ctx;
    clvr_accel_release(&ctx->cl, &sc->accel);
    clvr_clustered_release(&ctx->cl, &sc->clustered);
    --ctx->tracers;
    dataset_release(sc->ds);
    free(sc);
    if (ctx->closing && ctx->tracers == 0) clvr_context_destroy(ctx);
}

static clvr_status apply_settings(clvr_tracer *tr, clvr_error *e)
{
    tr->rs.shadows = tr->shadows && tr->rs.method != CLVR_RENDER_MARCH;
    tr->frames = 0;
    return clvr_renderer_set_settings(tr->renderer, &tr->rs, e);
}

static clvr_status set_camera(clvr_tracer *tr, const float eye[3], const float target[3], const float up[3],
                              float fovy, clvr_error *e)
{
    clvr_camera cam;
    clvr_status s = clvr_camera_look_at(&cam, eye, target, up, fovy, tr->rs.width, tr->rs.height, e);
    if (s == CLVR_OK) s = clvr_renderer_set_camera(tr->renderer, &cam, e);
    if (s == CLVR_OK) {
        tr->cam = cam;
        memcpy(tr->up, up, sizeof tr->up);
        tr->frames = 0;
    }
    return s;
}

static clvr_status frame_view(clvr_tracer *tr, const float up[3], float az, float el, float zoom, float fovy,
                              clvr_error *e)
{
    static const float y_up[3] = {0, 1, 0};
    clvr_camera_view view;
    clvr_camera_view_default(&view);
    memcpy(view.up, up ? up : y_up, sizeof view.up);
    view.azimuth_deg = az;
    view.elevation_deg = el;
    view.zoom = zoom;
    clvr_camera cam;
    clvr_status s = clvr_camera_frame_view(&cam, tr->lo, tr->hi, &view, fovy, tr->rs.width, tr->rs.height, e);
    if (s == CLVR_OK) s = clvr_renderer_set_camera(tr->renderer, &cam, e);
    if (s == CLVR_OK) {
        tr->cam = cam;
        memcpy(tr->up, view.up, sizeof tr->up);
        tr->frames = 0;
    }
    return s;
}

/* Uploads a baked table and keeps it for clvr_tracer_get_tf_table (moved). */
static clvr_status upload_table(clvr_tracer *tr, float **table, uint32_t n, float lo, float hi, float density,
                                clvr_error *e)
{
    clvr_status s = clvr_renderer_set_tf(tr->renderer, *table, n, lo, hi, density, e);
    if (s != CLVR_OK) return s;
    free(tr->table);
    tr->table = *table;
    *table = NULL;
    tr->table_n = n;
    tr->density = density;
    tr->range_lo = lo;
    tr->range_hi = hi;
    tr->frames = 0;
    return CLVR_OK;
}

/* Uploads tf baked, as the program does, and keeps it (moved: *tf zeroed). */
static clvr_status upload_tf(clvr_tracer *tr, clvr_tf *tf, clvr_error *e)
{
    const uint32_t n = clvr_tf_table_size(tf);
    float *table = malloc((size_t)n * 4 * sizeof(float));
    if (!table) return clvr_error_set(e, CLVR_ERR_NO_MEMORY, "out of memory for the transfer function");
    clvr_tf_bake(tf, table, n);
    clvr_status s = upload_table(tr, &table, n, tf->range_lo, tf->range_hi, tf->density, e);
    free(table);
    if (s == CLVR_OK && &tr->tf != tf) {
        clvr_tf_free(&tr->tf);
        tr->tf = *tf;
        memset(tf, 0, sizeof *tf);
    }
    if (s == CLVR_OK) {
        tr->tf_state = 1;
        tr->ext_scale = clvr_tf_extinction_scale(&tr->tf);
    }
    return s;
}

/* The transfer function of the program's options over mesh m: built-in
 * colormap, tf_path over it, the window (range_set: [lo, hi]), automatic
 * opacity unless ramp or the file gives it, density (density 0: the
 * automatic density times the file's; *auto_density receives the automatic
 * factor, 1 otherwise). Fresh tf. */
static clvr_status tf_build(const clvr_mesh *m, const char *colormap, const char *tf_path, int range_set, float lo,
                            float hi, float density, int ramp, clvr_tf *tf, float *auto_density, clvr_error *err)
{
    const int density_auto = density == 0;
    *auto_density = 1;
    clvr_status s = clvr_tf_from_options(tf, colormap ? colormap : "cool-warm", tf_path, range_set, lo, hi,
                                         density_auto ? 1.0f : density, m->scalar_min, m->scalar_max, err);
    if (s != CLVR_OK) return s;
    clvr_tf_set_extent(tf, m->bounds_lo, m->bounds_hi);
    /* The automatic transfer function (tf_auto.h): opacity from the scalar's
     * volume histogram over the window, unless a ramp or a file's points;
     * density from the optical depth of probe rays. */
    if (!ramp && !tf->opacity_set) {
        double hist[CLVR_TF_AUTO_BINS];
        clvr_tf_auto_histogram(m, tf->range_lo, tf->range_hi, hist, CLVR_TF_AUTO_BINS);
        s = clvr_tf_auto_opacity(tf, hist, CLVR_TF_AUTO_BINS, err);
        if (s != CLVR_OK) return s;
    }
    if (density_auto) {
        s = clvr_tf_auto_density(m, tf, auto_density, err);
        if (s != CLVR_OK) return s;
        tf->density *= *auto_density;
    }
    return CLVR_OK;
}

static clvr_status set_tf(clvr_tracer *tr, const char *colormap, const char *tf_path, float lo, float hi,
                          float density, int ramp, clvr_error *e)
{
    const int range_set = !(isnan(lo) && isnan(hi));
    if (range_set && !(isfinite(lo) && isfinite(hi) && lo < hi))
        return clvr_error_set(e, CLVR_ERR_USAGE,
                              "clvr_tracer_set_tf: range [%g, %g] must be finite with lo < hi, or both NaN for the "
                              "data range", (double)lo, (double)hi);
    if (!(density >= 0) || !isfinite(density))
        return clvr_error_set(e, CLVR_ERR_USAGE,
                              "clvr_tracer_set_tf: density is %g; use a value > 0, or 0 for automatic", (double)density);
    if (!tr->ds)
        return clvr_error_set(e, CLVR_ERR_USAGE, "clvr_tracer_set_tf: the tracer's dataset was dropped "
                              "(clvr_tracer_drop_dataset); use clvr_tracer_set_tf_table");
    if (tr->ds->consumed)
        return clvr_error_set(e, CLVR_ERR_USAGE, "clvr_tracer_set_tf: the dataset's cells were consumed by the "
                              "scene (clvr_preprocess_settings.consume); use clvr_tracer_set_tf_table, or a scene "
                              "made without consume");
    clvr_mesh m;
    mesh_view(tr->ds, tr->field, &m);
    clvr_tf tf = {0};
    float auto_density;
    clvr_status s = tf_build(&m, colormap, tf_path, range_set, lo, hi, density, ramp, &tf, &auto_density, e);
    if (s == CLVR_OK) s = upload_tf(tr, &tf, e);
    if (s == CLVR_OK) tr->auto_density = auto_density;
    clvr_tf_free(&tf);
    return s;
}

/* The automatic transfer function of a new tracer, made at its first use
 * (so that a caller who sets its own never pays for the automatic one's
 * histogram and probe rays). Without the dataset: a linear ramp over the
 * field's range. */
static clvr_status ensure_tf(clvr_tracer *tr, clvr_error *e)
{
    if (tr->tf_state) return CLVR_OK;
    /* A dataset whose cells a scene consumed has no cells left to measure:
     * the ramp, as without one. */
    if (tr->ds && !tr->ds->consumed) return set_tf(tr, NULL, NULL, NAN, NAN, 0, 0, e);
    clvr_tf tf = {0};
    clvr_status s = clvr_tf_from_options(&tf, "cool-warm", NULL, 0, 0, 0, 1.0f, tr->sc->scalar_lo, tr->sc->scalar_hi,
                                         e);
    if (s == CLVR_OK) {
        clvr_tf_set_extent(&tf, tr->lo, tr->hi);
        s = upload_tf(tr, &tf, e);
    }
    clvr_tf_free(&tf);
    return s;
}

void clvr_preprocess_settings_init(clvr_preprocess_settings *s)
{
    if (!s) return;
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    memset(s, 0, sizeof *s);
    s->size = sizeof *s;
    s->leaf_size = po.leaf_size;
    s->sampling_size = po.sampling_size;
}

static clvr_status check_preprocess(const char *fn, const clvr_preprocess_settings *ps, clvr_preprocess_options *po,
                                    clvr_error *e)
{
    clvr_preprocess_options_default(po);
    if (ps->leaf_size < 1 || ps->leaf_size > 128)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: leaf_size is %u; use 1 to 128 (the paper's 16 is the default)",
                              fn, ps->leaf_size);
    if (ps->sampling_size < 1)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: sampling_size is 0; use >= 1 (default 16)", fn);
    po->leaf_size = ps->leaf_size;
    po->sampling_size = ps->sampling_size;
    if (ps->element_boxes != CLVR_EBOX_AUTO && ps->element_boxes != CLVR_EBOX_ON &&
        ps->element_boxes != CLVR_EBOX_OFF)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: element_boxes is %d; use CLVR_ELEMENT_BOXES_AUTO, _ON or _OFF",
                              fn, ps->element_boxes);
    po->no_element_boxes = ps->element_boxes == CLVR_EBOX_OFF;
    if (ps->one_curve != CLVR_ONE_CURVE_AUTO && ps->one_curve != CLVR_ONE_CURVE_ON &&
        ps->one_curve != CLVR_ONE_CURVE_OFF)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: one_curve is %d; use CLVR_ONE_CURVE_AUTO, _ON or _OFF", fn,
                              ps->one_curve);
    po->one_curve = ps->one_curve;
    return CLVR_OK;
}

/* qbox: the curve's quantization box (NULL: the mesh's bounds; the MPI
 * driver gives every rank the whole mesh's, clvr_internal.h). */
static clvr_status scene_create(clvr_context *ctx, clvr_dataset *ds, const char *field,
                                const clvr_preprocess_settings *ps, const clvr_box *qbox, clvr_scene **out,
                                clvr_error *err)
{
    static const char fn[] = "clvr_scene_create";
    clvr_preprocess_options po;
    clvr_status s = check_preprocess(fn, ps, &po, err);
    if (s != CLVR_OK) return s;
    po.quantize_box = qbox;
    int fi;
    s = resolve_field(ds, fn, field, &fi, err);
    if (s != CLVR_OK) return s;
    clvr_mesh m;
    mesh_view(ds, (uint32_t)fi, &m);
    if (clvr_mesh_num_elements(&m) == 0)
        return clvr_error_set(err, CLVR_ERR_EMPTY, "%s: the dataset has no cells; add some with "
                              "clvr_dataset_add_cells", fn);
    if (ds->consumed)
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: the dataset's cells were consumed by an earlier scene "
                              "(clvr_preprocess_settings.consume); load it again", fn);
    clvr_scene *sc = calloc(1, sizeof *sc);
    if (!sc) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn);
    sc->refs = 1;
    sc->ctx = ctx;
    sc->ds = ds;
    sc->field = (uint32_t)fi;
    snprintf(sc->field_name, sizeof sc->field_name, "%s", ds->fields[fi].name);
    memcpy(sc->lo, ds->lo, sizeof sc->lo);
    memcpy(sc->hi, ds->hi, sizeof sc->hi);
    sc->scalar_lo = ds->fields[fi].lo;
    sc->scalar_hi = ds->fields[fi].hi;
    sc->points = ds->num_points;
    sc->bytes_points_before = clvr_mesh_vertex_bytes(&m);
    sc->bytes_indices_before = clvr_mesh_index_bytes(&m);
    ++ds->refs;
    ++ctx->tracers;

    /* A mesh the device cannot hold fails now, with the numbers, not
     * minutes into preprocessing (the image is checked by the tracer). */
    const uint64_t n = clvr_mesh_num_elements(&m);
    const uint64_t part = clvr_partition_elements(n, ps->partitions);
    if (ps->element_boxes == CLVR_EBOX_AUTO) {
        /* AUTO: off only when the host check says the run fits only
         * without the boxes (clvr_dataset_check_memory); a run that does not
         * fit either way is left to the checks that report it. */
        clvr_mem_limits ml;
        clvr_mem_limits_read(&ml);
        clvr_error ignored = {0};
        int boxes = CLVR_EBOX_AUTO;
        if (clvr_limits_check_host_boxes("dataset", m.num_vertices, m.num_cells, part, ps->width ? ps->width : 1,
                                         ps->height ? ps->height : 1, 1, ds->loaded.map_base != NULL, &boxes, &ml,
                                         NULL, &ignored) == CLVR_OK)
            po.no_element_boxes = boxes == CLVR_EBOX_OFF;
    }
    s = clvr_limits_check_parts(&ctx->cl, &m, ps->name ? ps->name : "dataset", &po, part,
                                ps->width ? ps->width : 1, ps->height ? ps->height : 1, err);
    /* Preprocessing in partitions (partition.h). A loaded file's mesh that
     * only this scene and the caller hold, when the caller drops it after
     * (consume), is consumed: its element lists go back to the OS partition
     * by partition, so the input shrinks while the result grows. */
    clvr_mesh *pm = &m;
    int consume = 0;
    if (ps->consume && ds->refs == 2 && ds->loaded.positions && ds->loaded.positions == ds->xyz &&
        ds->fields[fi].values == ds->loaded.scalars) {
        int borrowed_all = 1;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
            borrowed_all &= ds->cells_owned[t] == NULL && ds->cells[t] == ds->loaded.indices[t];
        if (borrowed_all) {
            pm = &ds->loaded;
            consume = 1;
        }
    }
    const double build0 = ctx->cl.build_s, t0 = clvr_clock_monotonic_s();
    if (s == CLVR_OK)
        s = clvr_preprocess_partitioned(&ctx->cl, pm, &po, ps->partitions, 0, consume, &sc->clustered,
                                        &sc->partitions, err);
    if (consume) { /* the lists are gone (counts kept): nothing may read them again */
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) ds->cells[t] = NULL;
        ds->consumed = 1;
    }
    if (s == CLVR_OK) s = clvr_accel_build(&ctx->cl, &sc->clustered, &sc->accel, err);
    /* Compiling kernels (seconds on a cold driver cache) is not clustering. */
    sc->preprocess_s = clvr_clock_monotonic_s() - t0 - (ctx->cl.build_s - build0);
    if (s != CLVR_OK) {
        scene_release(sc);
        return s;
    }
    *out = sc;
    return CLVR_OK;
}

clvr_result clvr_scene_create(clvr_context *ctx, clvr_dataset *ds, const char *field,
                              const clvr_preprocess_settings *s, clvr_scene **out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_scene_create";
    if (!ctx) return finish(NULL_ARG(fn, "ctx"), &e, msg);
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_preprocess_settings ps;
    VERSIONED_IN_SINCE(fn, s, preprocess_settings, ps, offsetof(clvr_preprocess_settings, one_curve));
    return finish(scene_create(ctx, ds, field, &ps, NULL, out, &e), &e, msg);
}

void clvr_scene_destroy(clvr_scene *sc) { scene_release(sc); }

clvr_result clvr_scene_drop_dataset(clvr_scene *sc, clvr_message *msg)
{
    clvr_error e = {0};
    if (!sc) return finish(NULL_ARG("clvr_scene_drop_dataset", "sc"), &e, msg);
    dataset_release(sc->ds);
    sc->ds = NULL;
    return finish(CLVR_OK, &e, msg);
}

clvr_scene *clvr_tracer_scene(clvr_tracer *tr) { return tr ? tr->sc : NULL; }

static void settings_from_render(const clvr_render_settings *rs, int shadows, clvr_tracer_settings *s);

/* The renderer's defaults, through the one conversion the tracer's getter
 * uses too. */
void clvr_tracer_settings_init(clvr_tracer_settings *s)
{
    if (!s) return;
    clvr_render_settings rs;
    clvr_render_settings_default(&rs);
    settings_from_render(&rs, rs.shadows, s);
}

/* The public settings onto render settings rs (width, height, grid kept):
 * every member checked, rs written only when all are good. */
static clvr_status settings_to_render(const char *fn, const clvr_tracer_settings *s, clvr_render_settings *rs,
                                      int *shadows, clvr_error *e)
{
    clvr_render_settings r = *rs;
    r.method = clvr_render_method_from_name(s->method);
    if (r.method >= CLVR_RENDER_COUNT)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: method '%.16s'; use march, track, bins or dda", fn, s->method);
    r.estimator = clvr_render_estimator_from_name(s->estimator);
    if (r.estimator >= CLVR_ESTIMATOR_COUNT)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: estimator '%.16s'; use auto, walk, urm or delta", fn,
                              s->estimator);
    if (!strcmp(s->sampler, "ld")) r.sampler = CLVR_SAMPLER_LD;
    else if (!strcmp(s->sampler, "independent")) r.sampler = CLVR_SAMPLER_INDEPENDENT;
    else return clvr_error_set(e, CLVR_ERR_USAGE, "%s: sampler '%.16s'; use ld or independent", fn, s->sampler);
    if (s->urm_steps < 1) return clvr_error_set(e, CLVR_ERR_USAGE, "%s: urm_steps is 0; use >= 1", fn);
    if (!(s->step >= 0) || !isfinite(s->step))
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: step is %g; use > 0, or 0 for automatic", fn, (double)s->step);
    if (s->bins < 1 || s->bins > CLVR_RENDER_MAX_BINS || s->segments < 1)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: bins %u and segments %u; use 1 to %u bins and >= 1 segments",
                              fn, s->bins, s->segments, CLVR_RENDER_MAX_BINS);
    if (s->macrocells > 1024)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: macrocells is %u; use 1 to 1024, or 0 for automatic", fn,
                              s->macrocells);
    if (!finite3(s->light_dir) || (s->light_dir[0] == 0 && s->light_dir[1] == 0 && s->light_dir[2] == 0))
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: light_dir must be 3 finite numbers, not all 0", fn);
    if (!(s->light_intensity >= 0) || !isfinite(s->light_intensity) || !(s->ambient >= 0) || !isfinite(s->ambient))
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: light_intensity %g and ambient %g must be finite and >= 0", fn,
                              (double)s->light_intensity, (double)s->ambient);
    if (!finite3(s->background) || s->background[0] < 0 || s->background[1] < 0 || s->background[2] < 0)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: background must be 3 finite numbers >= 0", fn);
    if (s->clip_box) {
        if (!finite3(s->clip_lo) || !finite3(s->clip_hi) || !(s->clip_lo[0] <= s->clip_hi[0]) ||
            !(s->clip_lo[1] <= s->clip_hi[1]) || !(s->clip_lo[2] <= s->clip_hi[2]))
            return clvr_error_set(e, CLVR_ERR_USAGE, "%s: clip_lo and clip_hi must be finite with lo <= hi on "
                                  "every axis", fn);
    }
    if (s->num_clip_planes > CLVR_MAX_CLIP_PLANES)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: num_clip_planes is %u; at most %u", fn, s->num_clip_planes,
                              CLVR_MAX_CLIP_PLANES);
    for (uint32_t i = 0; i < s->num_clip_planes; ++i) {
        const float *p = s->clip_planes[i];
        if (!finite3(p) || !isfinite(p[3]) || (p[0] == 0 && p[1] == 0 && p[2] == 0))
            return clvr_error_set(e, CLVR_ERR_USAGE, "%s: clip plane %u needs a finite, non-zero normal and a finite "
                                  "d", fn, i);
    }
    r.seed = s->seed;
    r.urm_steps = s->urm_steps;
    r.step = s->step;
    r.bins = s->bins;
    r.segments = s->segments;
    r.macrocells = s->macrocells;
    memcpy(r.light_dir, s->light_dir, sizeof r.light_dir);
    r.light_intensity = s->light_intensity;
    r.ambient = s->ambient;
    memcpy(r.background, s->background, sizeof r.background);
    if (s->clip_box) {
        memcpy(r.clip_lo, s->clip_lo, sizeof r.clip_lo);
        memcpy(r.clip_hi, s->clip_hi, sizeof r.clip_hi);
    } else {
        clvr_render_settings d;
        clvr_render_settings_default(&d);
        memcpy(r.clip_lo, d.clip_lo, sizeof r.clip_lo);
        memcpy(r.clip_hi, d.clip_hi, sizeof r.clip_hi);
    }
    r.num_clip_planes = s->num_clip_planes;
    memcpy(r.clip_planes, s->clip_planes, sizeof r.clip_planes);
    *shadows = s->shadows != 0;
    r.shadows = *shadows && r.method != CLVR_RENDER_MARCH;
    *rs = r;
    return CLVR_OK;
}

static void settings_from_render(const clvr_render_settings *rs, int shadows, clvr_tracer_settings *s)
{
    memset(s, 0, sizeof *s);
    s->size = sizeof *s;
    snprintf(s->method, sizeof s->method, "%s", clvr_render_method_name(rs->method));
    snprintf(s->estimator, sizeof s->estimator, "%s", clvr_render_estimator_name(rs->estimator));
    snprintf(s->sampler, sizeof s->sampler, "%s", rs->sampler == CLVR_SAMPLER_LD ? "ld" : "independent");
    s->seed = rs->seed;
    s->urm_steps = rs->urm_steps;
    s->step = rs->step > 0 ? rs->step : 0;
    s->bins = rs->bins;
    s->segments = rs->segments;
    s->macrocells = rs->macrocells;
    memcpy(s->light_dir, rs->light_dir, sizeof s->light_dir);
    s->light_intensity = rs->light_intensity;
    s->ambient = rs->ambient;
    s->shadows = shadows;
    memcpy(s->background, rs->background, sizeof s->background);
    s->clip_box = rs->clip_lo[0] <= rs->clip_hi[0] && rs->clip_lo[1] <= rs->clip_hi[1] &&
                  rs->clip_lo[2] <= rs->clip_hi[2];
    if (s->clip_box) {
        memcpy(s->clip_lo, rs->clip_lo, sizeof s->clip_lo);
        memcpy(s->clip_hi, rs->clip_hi, sizeof s->clip_hi);
    }
    s->num_clip_planes = rs->num_clip_planes;
    memcpy(s->clip_planes, rs->clip_planes, sizeof s->clip_planes);
}

static clvr_status tracer_create(clvr_scene *sc, const clvr_tracer_settings *ts, uint32_t width, uint32_t height,
                                 clvr_tracer **out, clvr_error *err)
{
    static const char fn[] = "clvr_tracer_create";
    if (width < 1 || height < 1 || width > CLVR_IMAGE_MAX_DIM || height > CLVR_IMAGE_MAX_DIM)
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: image %ux%u; width and height must be in [1, %u]", fn, width,
                              height, CLVR_IMAGE_MAX_DIM);
    clvr_render_settings rs;
    clvr_render_settings_default(&rs);
    rs.width = width;
    rs.height = height;
    int shadows = rs.shadows;
    clvr_status s = settings_to_render(fn, ts, &rs, &shadows, err);
    if (s != CLVR_OK) return s;
    clvr_context *ctx = sc->ctx;
    /* An image the device cannot hold fails here, with the numbers (the
     * estimate counts the mesh too: it is the run's total). */
    if (sc->ds && !sc->ds->consumed) {
        clvr_mesh m;
        mesh_view(sc->ds, sc->field, &m);
        clvr_preprocess_options po;
        clvr_preprocess_options_default(&po);
        po.leaf_size = sc->clustered.leaf_size;
        po.sampling_size = sc->clustered.sampling_size;
        const uint64_t part = clvr_partition_elements(clvr_mesh_num_elements(&m), sc->partitions);
        s = clvr_limits_check_parts(&ctx->cl, &m, "dataset", &po, part, width, height, err);
        if (s != CLVR_OK) return s;
    }
    clvr_tracer *tr = calloc(1, sizeof *tr);
    if (!tr) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn);
    tr->ctx = ctx;
    tr->sc = sc;
    ++sc->refs;
    tr->ds = sc->ds;
    if (tr->ds) ++tr->ds->refs;
    tr->field = sc->field;
    memcpy(tr->lo, sc->lo, sizeof tr->lo);
    memcpy(tr->hi, sc->hi, sizeof tr->hi);
    tr->auto_density = 1;
    tr->rs = rs;
    tr->shadows = shadows;
    s = clvr_renderer_create(&ctx->cl, &sc->clustered, &sc->accel, &tr->rs, &tr->renderer, err);
    /* The program's default framing; the transfer function at first use. */
    if (s == CLVR_OK) s = frame_view(tr, NULL, 0, 0, 1, 30.0f, err);
    if (s != CLVR_OK) {
        clvr_tracer_destroy(tr);
        return s;
    }
    *out = tr;
    return CLVR_OK;
}

clvr_result clvr_tracer_create_on(clvr_scene *sc, const clvr_tracer_settings *s, uint32_t width, uint32_t height,
                                  clvr_tracer **out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_create_on";
    if (!sc) return finish(NULL_ARG(fn, "sc"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_tracer_settings ts;
    VERSIONED_IN(fn, s, tracer_settings, ts);
    return finish(tracer_create(sc, &ts, width, height, out, &e), &e, msg);
}

clvr_result clvr_tracer_create(clvr_context *ctx, clvr_dataset *ds, const char *field, uint32_t width,
                               uint32_t height, clvr_tracer **out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_create";
    if (!ctx) return finish(NULL_ARG(fn, "ctx"), &e, msg);
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    if (width < 1 || height < 1 || width > CLVR_IMAGE_MAX_DIM || height > CLVR_IMAGE_MAX_DIM)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: image %ux%u; width and height must be in [1, %u]", fn,
                                     width, height, CLVR_IMAGE_MAX_DIM),
                      &e, msg);
    clvr_preprocess_settings ps;
    clvr_preprocess_settings_init(&ps);
    clvr_tracer_settings ts;
    clvr_tracer_settings_init(&ts);
    clvr_scene *sc = NULL;
    clvr_status s = scene_create(ctx, ds, field, &ps, NULL, &sc, &e);
    if (s == CLVR_OK) s = tracer_create(sc, &ts, width, height, out, &e);
    scene_release(sc); /* the tracer holds it */
    return finish(s, &e, msg);
}

void clvr_tracer_destroy(clvr_tracer *tr)
{
    if (!tr) return;
    clvr_denoiser_destroy(tr->denoiser);
    clvr_renderer_destroy(tr->renderer);
    dataset_release(tr->ds);
    scene_release(tr->sc);
    clvr_tf_free(&tr->tf);
    free(tr->table);
    free(tr);
}

clvr_result clvr_tracer_drop_dataset(clvr_tracer *tr, clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_drop_dataset", "tr"), &e, msg);
    dataset_release(tr->ds);
    tr->ds = NULL;
    if (tr->sc->refs == 1) { /* the scene is this tracer's alone */
        dataset_release(tr->sc->ds);
        tr->sc->ds = NULL;
    }
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_tracer_set_camera(clvr_tracer *tr, const float eye[3], const float target[3], const float up[3],
                                   float fovy_deg, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_camera";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!eye || !target || !up) return finish(NULL_ARG(fn, "eye, target or up"), &e, msg);
    return finish(set_camera(tr, eye, target, up, fovy_deg, &e), &e, msg);
}

clvr_result clvr_tracer_frame(clvr_tracer *tr, const float up[3], float azimuth_deg, float elevation_deg, float zoom,
                              float fovy_deg, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_frame";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!isfinite(azimuth_deg) || !isfinite(elevation_deg) || !(zoom > 0) || !isfinite(zoom))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: azimuth %g, elevation %g must be finite and zoom %g > 0",
                                     fn, (double)azimuth_deg, (double)elevation_deg, (double)zoom),
                      &e, msg);
    return finish(frame_view(tr, up, azimuth_deg, elevation_deg, zoom, fovy_deg, &e), &e, msg);
}

clvr_result clvr_tracer_get_camera(const clvr_tracer *tr, float eye[3], float target[3], float up[3],
                                   clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_get_camera", "tr"), &e, msg);
    if (eye) memcpy(eye, tr->cam.origin, 3 * sizeof(float));
    if (target) memcpy(target, tr->cam.target, 3 * sizeof(float));
    if (up) memcpy(up, tr->up, 3 * sizeof(float));
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_tracer_set_tf(clvr_tracer *tr, const char *colormap, const char *tf_path, float range_lo,
                               float range_hi, float density, int ramp, clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_set_tf", "tr"), &e, msg);
    return finish(set_tf(tr, colormap, tf_path, range_lo, range_hi, density, ramp, &e), &e, msg);
}

clvr_result clvr_tracer_set_tf_table(clvr_tracer *tr, const float *rgba, uint32_t n, float range_lo, float range_hi,
                                     float density, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_tf_table";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!rgba) return finish(NULL_ARG(fn, "rgba"), &e, msg);
    if (n < 2 || n > CLVR_TF_MAX_TABLE)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: %u entries; the table needs 2 to %u", fn, n,
                                     CLVR_TF_MAX_TABLE),
                      &e, msg);
    if (!(isfinite(range_lo) && isfinite(range_hi) && range_lo < range_hi))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: range [%g, %g] must be finite with lo < hi", fn,
                                     (double)range_lo, (double)range_hi),
                      &e, msg);
    if (!(density >= 0) || !isfinite(density))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: density %g must be finite and >= 0", fn,
                                     (double)density),
                      &e, msg);
    for (uint64_t i = 0; i < 4ull * n; ++i)
        if (!(rgba[i] >= 0 && rgba[i] <= 1))
            return finish(clvr_error_set(&e, CLVR_ERR_BAD_VALUE, "%s: entry %llu %s is %g; values must be in [0, 1]",
                                         fn, (unsigned long long)(i / 4),
                                         (const char *[]){"r", "g", "b", "opacity"}[i % 4], (double)rgba[i]),
                          &e, msg);
    float *table = malloc((size_t)n * 4 * sizeof(float));
    if (!table) return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn), &e, msg);
    /* Opacity to extinction as clvr_tf_bake: relative to the mesh diagonal. */
    clvr_tf scale = {0};
    clvr_tf_set_extent(&scale, tr->lo, tr->hi);
    const float k = clvr_tf_extinction_scale(&scale);
    for (uint32_t i = 0; i < n; ++i) {
        memcpy(table + 4 * i, rgba + 4 * i, 3 * sizeof(float));
        table[4 * i + 3] = rgba[4 * i + 3] * k;
    }
    clvr_status s = upload_table(tr, &table, n, range_lo, range_hi, density, &e);
    free(table);
    if (s == CLVR_OK) {
        clvr_tf_free(&tr->tf);
        tr->tf_state = 2;
        tr->ext_scale = k;
        tr->auto_density = 1;
    }
    return finish(s, &e, msg);
}

clvr_result clvr_tracer_set_light(clvr_tracer *tr, const float dir[3], float intensity, float ambient, int shadows,
                                  clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_light";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!finite3(dir) || (dir[0] == 0 && dir[1] == 0 && dir[2] == 0))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: dir must be 3 finite numbers, not all 0", fn), &e, msg);
    if (!(intensity >= 0) || !isfinite(intensity) || !(ambient >= 0) || !isfinite(ambient))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: intensity %g and ambient %g must be finite and >= 0", fn,
                                     (double)intensity, (double)ambient),
                      &e, msg);
    memcpy(tr->rs.light_dir, dir, sizeof tr->rs.light_dir);
    tr->rs.light_intensity = intensity;
    tr->rs.ambient = ambient;
    tr->shadows = shadows != 0;
    return finish(apply_settings(tr, &e), &e, msg);
}

clvr_result clvr_tracer_set_background(clvr_tracer *tr, const float rgb[3], clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_background";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!finite3(rgb) || rgb[0] < 0 || rgb[1] < 0 || rgb[2] < 0)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: rgb must be 3 finite numbers >= 0", fn), &e, msg);
    memcpy(tr->rs.background, rgb, sizeof tr->rs.background);
    return finish(apply_settings(tr, &e), &e, msg);
}

clvr_result clvr_tracer_set_method(clvr_tracer *tr, const char *method, const char *estimator, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_method";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (method) {
        uint32_t m = clvr_render_method_from_name(method);
        if (m >= CLVR_RENDER_COUNT)
            return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown method '%.64s'; use march, track, bins or dda",
                                         fn, method),
                          &e, msg);
        tr->rs.method = m;
    }
    if (estimator) {
        uint32_t x = clvr_render_estimator_from_name(estimator);
        if (x >= CLVR_ESTIMATOR_COUNT)
            return finish(clvr_error_set(&e, CLVR_ERR_USAGE,
                                         "%s: unknown estimator '%.64s'; use auto, walk, urm or delta", fn, estimator),
                          &e, msg);
        tr->rs.estimator = x;
    }
    return finish(apply_settings(tr, &e), &e, msg);
}

clvr_result clvr_tracer_set_seed(clvr_tracer *tr, uint64_t seed, clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_set_seed", "tr"), &e, msg);
    tr->rs.seed = seed;
    return finish(apply_settings(tr, &e), &e, msg);
}

clvr_result clvr_tracer_render(clvr_tracer *tr, uint32_t frames, clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_render", "tr"), &e, msg);
    if (frames < 1)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "clvr_tracer_render: frames is 0; render at least 1"), &e,
                      msg);
    clvr_status s = ensure_tf(tr, &e);
    for (uint32_t i = 0; i < frames && s == CLVR_OK; ++i) {
        s = clvr_renderer_frame(tr->renderer, &e);
        if (s == CLVR_OK) ++tr->frames;
    }
    return finish(s, &e, msg);
}

clvr_result clvr_tracer_size(const clvr_tracer *tr, uint32_t *width, uint32_t *height, clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_size", "tr"), &e, msg);
    if (width) *width = tr->rs.width;
    if (height) *height = tr->rs.height;
    return finish(CLVR_OK, &e, msg);
}

/* What reading an image (fn) needs: rgba, room for the tracer's image in
 * count floats, and a frame since the last change. */
static clvr_status image_read_usage(const clvr_tracer *tr, const char *fn, const float *rgba, size_t count,
                                    clvr_error *e)
{
    if (!rgba) return clvr_error_set(e, CLVR_ERR_USAGE, "%s: %s is NULL", fn, "rgba");
    const size_t need = (size_t)tr->rs.width * tr->rs.height * 4;
    if (count < need)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: rgba holds %zu floats; a %ux%u image needs %zu", fn, count,
                              tr->rs.width, tr->rs.height, need);
    if (tr->frames == 0)
        return clvr_error_set(e, CLVR_ERR_USAGE, "%s: no frame rendered since the last change; call "
                              "clvr_tracer_render first", fn);
    return CLVR_OK;
}

clvr_result clvr_tracer_read_image(clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_read_image";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    clvr_status s = image_read_usage(tr, fn, rgba, count, &e);
    if (s == CLVR_OK) s = clvr_renderer_read(tr->renderer, rgba, NULL, &e);
    return finish(s, &e, msg);
}

static const char *const stat_names =
    "frames, rays, samples, null_collisions, kernel_s, last_frame_s, preprocess_s, kernel_build_s, elements, points, "
    "instances, leaves, sampling_clusters, device_bytes, density, range_lo, range_hi, hull_faces, hull_bytes, "
    "hull_empty_fraction, hull_skipped, light_s, image_s, adjacency_bytes, adjacency_skipped, refine_pixels, "
    "refine_passes, select_s, pilot_s, pilot_pixels, pilot_walk_cells";

clvr_result clvr_tracer_stat(clvr_tracer *tr, const char *name, double *value, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_stat";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!name || !value) return finish(NULL_ARG(fn, "name or value"), &e, msg);
    clvr_render_counters c = {0};
    clvr_status s = ensure_tf(tr, &e);
    if (s == CLVR_OK && tr->frames) s = clvr_renderer_read(tr->renderer, NULL, &c, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    const clvr_clustered *k = &tr->sc->clustered;
    double v;
    if (!strcmp(name, "frames")) v = (double)tr->frames;
    else if (!strcmp(name, "rays")) v = (double)c.rays;
    else if (!strcmp(name, "samples")) v = (double)c.samples;
    else if (!strcmp(name, "null_collisions")) v = (double)c.null_collisions;
    else if (!strcmp(name, "kernel_s")) v = c.kernel_s;
    else if (!strcmp(name, "last_frame_s")) v = c.last_frame_s;
    else if (!strcmp(name, "preprocess_s")) v = tr->sc->preprocess_s;
    else if (!strcmp(name, "kernel_build_s")) v = tr->ctx->cl.build_s;
    else if (!strcmp(name, "elements")) v = (double)k->num_elements;
    else if (!strcmp(name, "points")) v = (double)tr->sc->points;
    else if (!strcmp(name, "instances")) v = (double)k->num_instances;
    else if (!strcmp(name, "leaves")) v = (double)k->num_leaves;
    else if (!strcmp(name, "sampling_clusters")) v = (double)k->num_sampling;
    else if (!strcmp(name, "device_bytes")) v = (double)tr->ctx->cl.allocated_bytes;
    else if (!strcmp(name, "density")) v = tr->density;
    else if (!strcmp(name, "range_lo")) v = tr->range_lo;
    else if (!strcmp(name, "range_hi")) v = tr->range_hi;
    else if (!strcmp(name, "hull_faces")) v = tr->sc->accel.hull.kept ? (double)tr->sc->accel.hull.num_faces : 0.0;
    else if (!strcmp(name, "hull_bytes")) v = (double)clvr_hull_bytes(&tr->sc->accel.hull);
    else if (!strcmp(name, "hull_empty_fraction")) v = tr->sc->accel.hull.empty_fraction;
    else if (!strcmp(name, "hull_skipped")) v = tr->sc->accel.hull_skipped[0] ? 1.0 : 0.0;
    else if (!strcmp(name, "light_s")) v = c.light_s;
    else if (!strcmp(name, "image_s")) v = c.image_s;
    else if (!strcmp(name, "refine_pixels")) v = (double)c.refine_pixels;
    else if (!strcmp(name, "refine_passes")) v = (double)c.refine_passes;
    else if (!strcmp(name, "select_s")) v = c.select_s;
    else if (!strcmp(name, "pilot_s")) v = c.pilot_s;
    else if (!strcmp(name, "pilot_pixels") || !strcmp(name, "pilot_walk_cells")) {
        clvr_render_pick pk;
        const int ran = clvr_renderer_pick(tr->renderer, &pk);
        v = !strcmp(name, "pilot_pixels") ? (ran ? (double)pk.pixels : 0.0) : ran ? (double)pk.walk_cells : -1.0;
    }
    else if (!strcmp(name, "adjacency_bytes") || !strcmp(name, "adjacency_skipped")) {
        uint64_t bytes;
        double build_s;
        const char *skipped;
        clvr_renderer_adjacency(tr->renderer, &bytes, &build_s, &skipped);
        v = !strcmp(name, "adjacency_bytes") ? (double)bytes : *skipped ? 1.0 : 0.0;
    } else
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown figure '%.64s'; use one of %s", fn, name,
                                     stat_names),
                      &e, msg);
    *value = v;
    return finish(CLVR_OK, &e, msg);
}

/* --- API 1.1: dataset information ------------------------------------------ */

clvr_result clvr_dataset_get_info(const clvr_dataset *ds, clvr_dataset_info *info, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_get_info";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!info) return finish(NULL_ARG(fn, "info"), &e, msg);
    clvr_dataset_info d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.num_points = ds->num_points;
    memcpy(d.num_cells, ds->num_cells, sizeof d.num_cells);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) d.num_elements += ds->num_cells[t];
    d.num_fields = table_fields(ds);
    memcpy(d.lo, ds->lo, sizeof d.lo);
    memcpy(d.hi, ds->hi, sizeof d.hi);
    if (ds->num_fields) {
        clvr_mesh m;
        mesh_view(ds, 0, &m);
        d.bytes_points = clvr_mesh_vertex_bytes(&m);
        d.bytes_indices = clvr_mesh_index_bytes(&m);
        d.scalar_min = ds->fields[0].lo;
        d.scalar_max = ds->fields[0].hi;
        snprintf(d.current_name, sizeof d.current_name, "%s", ds->loaded.positions ? ds->loaded.scalar_name
                                                                                    : ds->fields[0].name);
    }
    d.current_field = ds->loaded.num_fields ? ds->loaded.scalar_field : 0;
    d.skipped_cells = ds->loaded.skipped_cells;
    d.file_fields = ds->loaded.num_fields;
    d.decomposed_cells = ds->loaded.decomposed_cells;
    d.cell_flat = ds->loaded.cell_flat;
    d.current_is_cell = ds->loaded.num_fields && ds->loaded.fields[ds->loaded.scalar_field].association ==
                                                     CLVR_FIELD_CELL;
    return finish(versioned_out(fn, "clvr_dataset_info", info, &d, sizeof d, sizeof d, &e), &e, msg);
}

clvr_result clvr_dataset_get_field(const clvr_dataset *ds, uint32_t i, clvr_dataset_field *out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_get_field";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    if (i >= table_fields(ds))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: field %u asked but the dataset has %u", fn, i,
                                     table_fields(ds)),
                      &e, msg);
    clvr_dataset_field f;
    table_field(ds, i, &f);
    return finish(versioned_out(fn, "clvr_dataset_field", out, &f, sizeof f, sizeof f, &e), &e, msg);
}

clvr_result clvr_dataset_get_array(const clvr_dataset *ds, const char *name, const void **data, int *borrowed,
                                   clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_get_array";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!name || !data || !borrowed) return finish(NULL_ARG(fn, "name, data or borrowed"), &e, msg);
    if (!strcmp(name, "points")) {
        *data = ds->xyz;
        *borrowed = ds->xyz_owned == NULL && !ds->loaded.positions;
        return finish(CLVR_OK, &e, msg);
    }
    const int t = cell_type_of(name);
    if (t >= 0) {
        *data = ds->cells[t];
        *borrowed = ds->cells[t] && ds->cells_owned[t] == NULL && !ds->loaded.positions;
        return finish(CLVR_OK, &e, msg);
    }
    int i;
    clvr_status s = lookup_field(ds, fn, name, &i, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    *data = ds->fields[i].values;
    *borrowed = ds->fields[i].owned == NULL && !ds->fields[i].from_file;
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_dataset_warnings(const clvr_dataset *ds, const char *name, char *buf, size_t size, uint32_t *count,
                                  clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_warnings";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!buf || !size) return finish(NULL_ARG(fn, "buf (or size 0)"), &e, msg);
    if (!name) name = "dataset";
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f) return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn), &e, msg);
    int lines = 0;
    if (ds->num_fields && !ds->consumed) {
        clvr_mesh m;
        mesh_view(ds, 0, &m);
        clvr_limits_report lr;
        clvr_limits_scan(&m, &lr);
        lines += clvr_limits_print_warnings(f, name, &lr);
    }
    const uint64_t sk = ds->loaded.skipped_cells, dc = ds->loaded.decomposed_cells;
    if (sk) {
        fprintf(f, "clvr: warning: %s: %llu cell%s of other types (surface, line or polyhedron cells) left out; "
                   "clvr renders tetrahedra, pyramids, wedges and hexahedra\n",
                name, (unsigned long long)sk, sk == 1 ? "" : "s");
        ++lines;
    }
    if (dc) {
        fprintf(f, "clvr: %s: %llu polyhedr%s decomposed into tets and pyramids\n", name, (unsigned long long)dc,
                dc == 1 ? "on" : "a");
        ++lines;
    }
    fclose(f);
    copy_str(buf, size, text ? text : "");
    free(text);
    if (count) *count = (uint32_t)lines;
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_file_check_memory(const char *path, uint32_t width, uint32_t height, uint32_t partitions,
                                   clvr_message *msg)
{
    clvr_error e = {0};
    if (!path) return finish(NULL_ARG("clvr_file_check_memory", "path"), &e, msg);
    uint64_t hv = 0, hc[CLVR_CELL_TYPE_COUNT] = {0};
    clvr_error perr = {0};
    if (clvr_mesh_peek_bin(path, &hv, hc, &perr) != CLVR_OK) return finish(CLVR_OK, &e, msg); /* read will say */
    uint64_t n = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n += hc[t];
    clvr_mem_limits ml;
    clvr_mem_limits_read(&ml);
    /* The library maps a .bin's arrays (read, not mapped, for cell data
     * shown flat: checked again once loaded); boxes as AUTO resolves them. */
    int boxes = CLVR_EBOX_AUTO;
    return finish(clvr_limits_check_host_boxes(path, hv, hc, clvr_partition_elements(n, partitions), width, height, 0,
                                               1, &boxes, &ml, NULL, &e),
                  &e, msg);
}

clvr_result clvr_context_check_file(clvr_context *ctx, const char *path, uint32_t width, uint32_t height,
                                    uint32_t partitions, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_context_check_file";
    if (!ctx) return finish(NULL_ARG(fn, "ctx"), &e, msg);
    if (!path) return finish(NULL_ARG(fn, "path"), &e, msg);
    clvr_mesh m;
    memset(&m, 0, sizeof m);
    clvr_error perr = {0};
    if (clvr_mesh_peek_bin(path, &m.num_vertices, m.num_cells, &perr) != CLVR_OK)
        return finish(CLVR_OK, &e, msg); /* not a .bin, or unreadable: the read will say */
    /* The smallest run: without the element boxes (AUTO may drop them). */
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    po.no_element_boxes = 1;
    return finish(clvr_limits_check_parts(&ctx->cl, &m, path, &po,
                                          clvr_partition_elements(clvr_mesh_num_elements(&m), partitions),
                                          width ? width : 1, height ? height : 1, &e),
                  &e, msg);
}

clvr_result clvr_dataset_check_memory(const clvr_dataset *ds, const char *name, uint32_t width, uint32_t height,
                                      uint32_t partitions, int element_boxes, int *resolved, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_check_memory";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (element_boxes != CLVR_EBOX_AUTO && element_boxes != CLVR_EBOX_ON && element_boxes != CLVR_EBOX_OFF)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: element_boxes is %d; use CLVR_ELEMENT_BOXES_AUTO, _ON "
                                     "or _OFF", fn, element_boxes),
                      &e, msg);
    uint64_t n = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n += ds->num_cells[t];
    clvr_mem_limits ml;
    clvr_mem_limits_read(&ml);
    int boxes = element_boxes;
    clvr_status s = clvr_limits_check_host_boxes(name ? name : "dataset", ds->num_points, ds->num_cells,
                                                 clvr_partition_elements(n, partitions), width, height, 1,
                                                 ds->loaded.map_base != NULL, &boxes, &ml, NULL, &e);
    if (s == CLVR_OK && resolved) *resolved = boxes;
    return finish(s, &e, msg);
}

/* --- API 1.1: context and scene -------------------------------------------- */

clvr_result clvr_context_warm_up_with(clvr_context *ctx, const clvr_preprocess_settings *s, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_context_warm_up_with";
    if (!ctx) return finish(NULL_ARG(fn, "ctx"), &e, msg);
    clvr_preprocess_settings ps;
    VERSIONED_IN_SINCE(fn, s, preprocess_settings, ps, offsetof(clvr_preprocess_settings, one_curve));
    clvr_preprocess_options po;
    clvr_status st = check_preprocess(fn, &ps, &po, &e);
    if (st == CLVR_OK) st = warm_up(ctx, &po, &e);
    return finish(st, &e, msg);
}

clvr_result clvr_context_build_info(clvr_context *ctx, int notices, double *build_s, int *notice_shown,
                                    clvr_message *msg)
{
    clvr_error e = {0};
    if (!ctx) return finish(NULL_ARG("clvr_context_build_info", "ctx"), &e, msg);
    ctx->cl.build_notice = notices != 0;
    if (build_s) *build_s = ctx->cl.build_s;
    if (notice_shown) *notice_shown = ctx->cl.build_notice_shown;
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_scene_get_stats(const clvr_scene *sc, clvr_scene_stats *out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_scene_get_stats";
    if (!sc) return finish(NULL_ARG(fn, "sc"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    const clvr_clustered *c = &sc->clustered;
    const clvr_accel *a = &sc->accel;
    clvr_scene_stats d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.elements = c->num_elements;
    d.points = sc->points;
    d.instances = c->num_instances;
    d.instances16 = c->num_instances16;
    d.leaves = c->num_leaves;
    d.sampling_clusters = c->num_sampling;
    d.leaf_size = c->leaf_size;
    d.sampling_size = c->sampling_size;
    d.partitions = sc->partitions;
    memcpy(d.lo, sc->lo, sizeof d.lo);
    memcpy(d.hi, sc->hi, sizeof d.hi);
    d.bytes_points_before = sc->bytes_points_before;
    d.bytes_points_after = c->bytes_vertices_after;
    d.bytes_indices_before = c->bytes_indices_before ? c->bytes_indices_before : sc->bytes_indices_before;
    d.bytes_indices_after = c->bytes_indices_after;
    d.bytes_bvh = clvr_accel_bvh_bytes(a);
    d.bytes_element_boxes = a->two_level.ebox_bytes;
    d.bytes_entry_grids = a->two_level.entry_bytes;
    for (int t = 0; t < 4; ++t) d.collapsed_cells[t] = c->collapsed[t];
    /* Table 1's "pre" column: the same packed 4-wide tree with one element
     * per leaf, i.e. over num_elements primitives. */
    d.bytes_bvh_one_per_leaf =
        (uint64_t)clvr_bvh_nodes_bound(c->num_elements > 0x7fffffffull ? 0x7fffffffu : (uint32_t)c->num_elements) *
        sizeof(clvr_bvh_node);
    d.bytes_sampling = c->bytes_sampling + (uint64_t)a->sampling_node_count * sizeof(clvr_bvh_node);
    d.device_bytes = sc->ctx->cl.allocated_bytes;
    d.preprocess_s = sc->preprocess_s;
    for (int i = 0; i < CLVR_PP_STAGE_COUNT && d.num_stages < CLVR_STATS_MAX_STAGES - 2; ++i) {
        snprintf(d.stage_name[d.num_stages], sizeof d.stage_name[0], "%s", clvr_pp_stage_name(i));
        d.stage_s[d.num_stages++] = c->stage_s[i];
    }
    d.scalar_min = sc->scalar_lo;
    d.scalar_max = sc->scalar_hi;
    snprintf(d.stage_name[d.num_stages], sizeof d.stage_name[0], "bvh");
    d.stage_s[d.num_stages++] = a->two_level.build_seconds;
    snprintf(d.stage_name[d.num_stages], sizeof d.stage_name[0], "hull");
    d.stage_s[d.num_stages++] = a->hull.build_s;
    return finish(versioned_out(fn, "clvr_scene_stats", out, &d, sizeof d,
                                    offsetof(clvr_scene_stats, bytes_entry_grids), &e), &e, msg);
}

/* --- API 1.1: settings, size, statistics, camera ---------------------------- */

clvr_result clvr_tracer_get_settings(const clvr_tracer *tr, clvr_tracer_settings *out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_get_settings";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_tracer_settings d;
    settings_from_render(&tr->rs, tr->shadows, &d);
    return finish(versioned_out(fn, "clvr_tracer_settings", out, &d, sizeof d, sizeof d, &e), &e, msg);
}

clvr_result clvr_tracer_set_settings(clvr_tracer *tr, const clvr_tracer_settings *s, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_settings";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!s) return finish(NULL_ARG(fn, "s"), &e, msg);
    clvr_tracer_settings ts;
    VERSIONED_IN(fn, s, tracer_settings, ts);
    clvr_render_settings rs = tr->rs;
    int shadows;
    clvr_status st = settings_to_render(fn, &ts, &rs, &shadows, &e);
    if (st != CLVR_OK) return finish(st, &e, msg);
    const clvr_render_settings old = tr->rs;
    const int old_shadows = tr->shadows;
    tr->rs = rs;
    tr->shadows = shadows;
    st = apply_settings(tr, &e);
    if (st != CLVR_OK) { /* all or nothing */
        tr->rs = old;
        tr->shadows = old_shadows;
    }
    return finish(st, &e, msg);
}

clvr_result clvr_tracer_set_pixel_filter(clvr_tracer *tr, const char *filter, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_pixel_filter";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!filter) return finish(NULL_ARG(fn, "filter"), &e, msg);
    uint32_t f;
    if (!strcmp(filter, "box")) f = CLVR_PIXEL_BOX;
    else if (!strcmp(filter, "point")) f = CLVR_PIXEL_POINT;
    else return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: pixel filter '%s'; use box or point", fn, filter), &e,
                       msg);
    const uint32_t old = tr->rs.pixel_filter;
    tr->rs.pixel_filter = f;
    const clvr_status s = apply_settings(tr, &e);
    if (s != CLVR_OK) tr->rs.pixel_filter = old;
    return finish(s, &e, msg);
}

const char *clvr_tracer_pixel_filter(const clvr_tracer *tr)
{
    return tr ? clvr_setting_name("pixel_filter", tr->rs.pixel_filter) : NULL;
}

clvr_result clvr_tracer_set_adaptive(clvr_tracer *tr, float threshold, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_adaptive";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!(threshold >= 0.0f) || !isfinite(threshold))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: threshold %g; use 0 (off) or a finite number > 0 "
                                     "(default %g)", fn, (double)threshold, (double)CLVR_ADAPTIVE_DEFAULT),
                      &e, msg);
    const float old = tr->rs.adaptive;
    tr->rs.adaptive = threshold;
    const clvr_status s = apply_settings(tr, &e);
    if (s != CLVR_OK) tr->rs.adaptive = old;
    return finish(s, &e, msg);
}

float clvr_tracer_adaptive(const clvr_tracer *tr) { return tr ? tr->rs.adaptive : 0.0f; }

clvr_result clvr_tracer_set_denoise(clvr_tracer *tr, int on, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_denoise";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    const int old = tr->rs.guides;
    if (!old == !on) return finish(CLVR_OK, &e, msg);
    tr->rs.guides = on ? 1 : 0;
    const clvr_status s = apply_settings(tr, &e);
    if (s != CLVR_OK) tr->rs.guides = old;
    return finish(s, &e, msg);
}

int clvr_tracer_denoise(const clvr_tracer *tr) { return tr && tr->rs.guides ? 1 : 0; }

clvr_result clvr_tracer_read_denoised(clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_read_denoised";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!tr->rs.guides)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: the tracer keeps no guides; call "
                                     "clvr_tracer_set_denoise(tr, 1) before rendering", fn),
                      &e, msg);
    clvr_status s = image_read_usage(tr, fn, rgba, count, &e);
    if (s == CLVR_OK && !tr->denoiser) s = clvr_denoiser_create(&tr->ctx->cl, &tr->denoiser, &e);
    if (s == CLVR_OK)
        s = clvr_denoise_renderer(tr->denoiser, tr->renderer, tr->rs.width, tr->rs.height, clvr_dn_params_default(),
                                  rgba, &e);
    return finish(s, &e, msg);
}

clvr_result clvr_tracer_set_size(clvr_tracer *tr, uint32_t width, uint32_t height, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_size";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (width < 1 || height < 1 || width > CLVR_IMAGE_MAX_DIM || height > CLVR_IMAGE_MAX_DIM)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: image %ux%u; width and height must be in [1, %u]", fn,
                                     width, height, CLVR_IMAGE_MAX_DIM),
                      &e, msg);
    const uint32_t w0 = tr->rs.width, h0 = tr->rs.height;
    tr->rs.width = width;
    tr->rs.height = height;
    clvr_status s = apply_settings(tr, &e);
    if (s == CLVR_OK) {
        float eye[3], target[3], up[3];
        memcpy(eye, tr->cam.origin, sizeof eye);
        memcpy(target, tr->cam.target, sizeof target);
        memcpy(up, tr->up, sizeof up);
        s = set_camera(tr, eye, target, up, tr->cam.fovy, &e);
    }
    if (s != CLVR_OK) {
        tr->rs.width = w0;
        tr->rs.height = h0;
    }
    return finish(s, &e, msg);
}

clvr_result clvr_tracer_get_render_stats(clvr_tracer *tr, clvr_render_stats *out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_get_render_stats";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_render_counters c = {0};
    clvr_status s = CLVR_OK;
    if (tr->frames) s = clvr_renderer_read(tr->renderer, NULL, &c, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    clvr_render_stats d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    d.frames = tr->frames ? c.frames : 0;
    d.rays = c.rays;
    d.samples = c.samples;
    d.null_collisions = c.null_collisions;
    d.kernel_s = c.kernel_s;
    d.last_frame_s = c.last_frame_s;
    d.width = tr->rs.width;
    d.height = tr->rs.height;
    snprintf(d.method, sizeof d.method, "%s", clvr_render_method_name(tr->rs.method));
    snprintf(d.estimator, sizeof d.estimator, "%s", clvr_render_estimator_name(clvr_renderer_estimator(tr->renderer)));
    d.macrocells = tr->rs.method == CLVR_RENDER_DDA ? clvr_renderer_macrocells(tr->renderer, NULL, NULL) : 0;
    return finish(versioned_out(fn, "clvr_render_stats", out, &d, sizeof d,
                                    offsetof(clvr_render_stats, estimator), &e), &e, msg);
}

clvr_result clvr_tracer_get_view(const clvr_tracer *tr, float eye[3], float target[3], float up[3], float *fovy_deg,
                                 clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_get_view", "tr"), &e, msg);
    if (eye) memcpy(eye, tr->cam.origin, 3 * sizeof(float));
    if (target) memcpy(target, tr->cam.target, 3 * sizeof(float));
    if (up) memcpy(up, tr->up, 3 * sizeof(float));
    if (fovy_deg) *fovy_deg = tr->cam.fovy;
    return finish(CLVR_OK, &e, msg);
}

void clvr_rotate_about(const float p[3], const float centre[3], const float axis[3], float deg, float out[3])
{
    clvr_camera_rotate_about(p, centre, axis, deg, out);
}

clvr_result clvr_tracer_draw_box(const clvr_tracer *tr, float *rgba, size_t count, const float lo[3],
                                 const float hi[3], const float rgb[3], float line_width, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_draw_box";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!rgba || !lo || !hi || !rgb) return finish(NULL_ARG(fn, "rgba, lo, hi or rgb"), &e, msg);
    const size_t need = (size_t)tr->rs.width * tr->rs.height * 4;
    if (count < need)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: rgba holds %zu floats; a %ux%u image needs %zu", fn,
                                     count, tr->rs.width, tr->rs.height, need),
                      &e, msg);
    if (!finite3(lo) || !finite3(hi) || !finite3(rgb) || !(line_width > 0) || !isfinite(line_width))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: lo, hi and rgb must be finite and line_width > 0", fn),
                      &e, msg);
    clvr_outline_draw_box(rgba, &tr->cam, lo, hi, rgb, line_width);
    return finish(CLVR_OK, &e, msg);
}

/* --- API 1.1: the transfer function in use --------------------------------- */

clvr_result clvr_tracer_get_tf(const clvr_tracer *tr, clvr_tf_info *out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_get_tf";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_status s = ensure_tf((clvr_tracer *)tr, &e); /* the automatic one, made at first use */
    if (s != CLVR_OK) return finish(s, &e, msg);
    clvr_tf_info d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    snprintf(d.colormap, sizeof d.colormap, "%s", tr->tf_state == 1 ? tr->tf.name : "table");
    d.range_lo = tr->range_lo;
    d.range_hi = tr->range_hi;
    d.density = tr->density;
    d.auto_density = tr->auto_density;
    d.table_size = tr->table_n;
    d.extinction_scale = tr->ext_scale;
    return finish(versioned_out(fn, "clvr_tf_info", out, &d, sizeof d, sizeof d, &e), &e, msg);
}

clvr_result clvr_tracer_get_tf_table(const clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_get_tf_table";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!rgba) return finish(NULL_ARG(fn, "rgba"), &e, msg);
    clvr_status s = ensure_tf((clvr_tracer *)tr, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    if (count < 4 * (size_t)tr->table_n)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: rgba holds %zu floats; the table needs %zu", fn, count,
                                     4 * (size_t)tr->table_n),
                      &e, msg);
    memcpy(rgba, tr->table, 4 * (size_t)tr->table_n * sizeof(float));
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_tracer_edit_tf(clvr_tracer *tr, const char *colormap, float range_lo, float range_hi, float density,
                                clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_edit_tf";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    clvr_status s = ensure_tf(tr, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    if (tr->tf_state != 1)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: the transfer function is a table "
                                     "(clvr_tracer_set_tf_table); set it again instead", fn),
                      &e, msg);
    const int keep_range = isnan(range_lo) && isnan(range_hi);
    if (!keep_range && !(isfinite(range_lo) && isfinite(range_hi) && range_lo < range_hi))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: range [%g, %g] must be finite with lo < hi, or both "
                                     "NaN to keep it", fn, (double)range_lo, (double)range_hi),
                      &e, msg);
    if (!isnan(density) && (!(density >= 0) || !isfinite(density)))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: density %g; use a finite value >= 0, or NaN to keep it",
                                     fn, (double)density),
                      &e, msg);
    clvr_tf old = tr->tf; /* the colour points are replaced by a colormap change: keep the old ones until it works */
    clvr_tf edit = tr->tf;
    edit.colors = NULL;
    edit.num_colors = 0;
    if (colormap) s = clvr_tf_set_colormap(&edit, colormap, &e);
    else {
        edit.colors = malloc((size_t)old.num_colors * 4 * sizeof(float));
        if (!edit.colors) s = clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn);
        else {
            memcpy(edit.colors, old.colors, (size_t)old.num_colors * 4 * sizeof(float));
            edit.num_colors = old.num_colors;
        }
    }
    if (s != CLVR_OK) {
        free(edit.colors);
        return finish(s, &e, msg);
    }
    if (!keep_range) {
        edit.range_lo = range_lo;
        edit.range_hi = range_hi;
        edit.range_set = 1;
    }
    if (!isnan(density)) edit.density = density;
    tr->tf = edit; /* upload_tf keeps tr->tf when given it */
    s = upload_tf(tr, &tr->tf, &e);
    if (s == CLVR_OK) free(old.colors);
    else {
        free(edit.colors);
        tr->tf = old;
    }
    return finish(s, &e, msg);
}

const char *clvr_colormap_names(void) { return clvr_tf_colormap_names(); }


struct clvr_transfer {
    clvr_tf tf;
    float auto_density;
};

/* A deep copy of src into *dst (zeroed or freed first by the caller). */
static clvr_status tf_copy(const clvr_tf *src, clvr_tf *dst, clvr_error *e)
{
    *dst = *src;
    dst->colors = malloc((size_t)(src->num_colors ? src->num_colors : 1) * 4 * sizeof(float));
    dst->opacity = malloc((size_t)(src->num_opacity ? src->num_opacity : 1) * 4 * sizeof(float));
    if (!dst->colors || !dst->opacity) {
        free(dst->colors);
        free(dst->opacity);
        memset(dst, 0, sizeof *dst);
        return clvr_error_set(e, CLVR_ERR_NO_MEMORY, "out of memory copying a transfer function");
    }
    if (src->num_colors) memcpy(dst->colors, src->colors, (size_t)src->num_colors * 4 * sizeof(float));
    if (src->num_opacity) memcpy(dst->opacity, src->opacity, (size_t)src->num_opacity * 4 * sizeof(float));
    return CLVR_OK;
}

clvr_result clvr_transfer_create(const clvr_dataset *ds, const char *field, const char *colormap, const char *tf_path,
                                 float range_lo, float range_hi, float density, int ramp, clvr_transfer **out,
                                 clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_transfer_create";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    const int range_set = !(isnan(range_lo) && isnan(range_hi));
    if (range_set && !(isfinite(range_lo) && isfinite(range_hi) && range_lo < range_hi))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: range [%g, %g] must be finite with lo < hi, or both "
                                     "NaN for the data range", fn, (double)range_lo, (double)range_hi),
                      &e, msg);
    if (!(density >= 0) || !isfinite(density))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: density is %g; use a value > 0, or 0 for automatic",
                                     fn, (double)density),
                      &e, msg);
    if (ds->consumed)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: the dataset's cells were consumed by a scene; make "
                                     "the transfer function before clvr_scene_create", fn),
                      &e, msg);
    int fi;
    clvr_status s = lookup_field(ds, fn, field, &fi, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    clvr_transfer *t = calloc(1, sizeof *t);
    if (!t) return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn), &e, msg);
    clvr_mesh m;
    mesh_view(ds, (uint32_t)fi, &m);
    s = tf_build(&m, colormap, tf_path, range_set, range_lo, range_hi, density, ramp, &t->tf, &t->auto_density, &e);
    if (s != CLVR_OK) {
        clvr_transfer_destroy(t);
        return finish(s, &e, msg);
    }
    *out = t;
    return finish(CLVR_OK, &e, msg);
}

void clvr_transfer_destroy(clvr_transfer *tf)
{
    if (!tf) return;
    clvr_tf_free(&tf->tf);
    free(tf);
}

clvr_result clvr_transfer_get_info(const clvr_transfer *tf, clvr_tf_info *out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_transfer_get_info";
    if (!tf) return finish(NULL_ARG(fn, "tf"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_tf_info d;
    memset(&d, 0, sizeof d);
    d.size = sizeof d;
    snprintf(d.colormap, sizeof d.colormap, "%s", tf->tf.name);
    d.range_lo = tf->tf.range_lo;
    d.range_hi = tf->tf.range_hi;
    d.density = tf->tf.density;
    d.auto_density = tf->auto_density;
    d.table_size = clvr_tf_table_size(&tf->tf);
    d.extinction_scale = clvr_tf_extinction_scale(&tf->tf);
    return finish(versioned_out(fn, "clvr_tf_info", out, &d, sizeof d, sizeof d, &e), &e, msg);
}

clvr_result clvr_tracer_set_transfer(clvr_tracer *tr, const clvr_transfer *tf, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_set_transfer";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!tf) return finish(NULL_ARG(fn, "tf"), &e, msg);
    clvr_tf copy;
    clvr_status s = tf_copy(&tf->tf, &copy, &e);
    if (s == CLVR_OK) s = upload_tf(tr, &copy, &e);
    if (s == CLVR_OK) tr->auto_density = tf->auto_density;
    clvr_tf_free(&copy);
    return finish(s, &e, msg);
}

/* --- API 1.1: images and process ------------------------------------------- */

void clvr_image_settings_init(clvr_image_settings *s)
{
    if (!s) return;
    memset(s, 0, sizeof *s);
    s->size = sizeof *s;
    s->tonemap = "aces";
}

clvr_result clvr_image_save_with(const char *path, uint32_t width, uint32_t height, const float *rgba,
                                 const clvr_image_settings *s, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_image_save_with";
    if (!path) return finish(NULL_ARG(fn, "path"), &e, msg);
    if (!rgba) return finish(NULL_ARG(fn, "rgba"), &e, msg);
    clvr_image_settings is;
    VERSIONED_IN(fn, s, image_settings, is);
    if (!isfinite(is.exposure_ev))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: exposure_ev must be finite", fn), &e, msg);
    clvr_tonemap tm = clvr_tonemap_parse(is.tonemap ? is.tonemap : "aces");
    if (tm >= CLVR_TONEMAP_COUNT)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown tone curve '%.64s'; use none, aces or filmic",
                                     fn, is.tonemap),
                      &e, msg);
    if (is.legend_table && (is.legend_entries < 1 || !(is.legend_lo < is.legend_hi)))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: a legend needs legend_entries >= 1 and legend_lo < "
                                     "legend_hi", fn),
                      &e, msg);
    clvr_image_legend legend = {is.legend_table, is.legend_entries, is.legend_lo, is.legend_hi, is.legend_name};
    clvr_image_display d = {is.exposure_ev, tm, is.transparent != 0, is.legend_table ? &legend : NULL};
    return finish(clvr_image_write_display(path, width, height, rgba, &d, &e), &e, msg);
}

clvr_result clvr_image_check_path(const char *path, clvr_message *msg)
{
    clvr_error e = {0};
    if (!path) return finish(NULL_ARG("clvr_image_check_path", "path"), &e, msg);
    return finish(clvr_image_check_output(path, &e), &e, msg);
}

int clvr_image_path_is_png(const char *path) { return path && clvr_image_is_png(path); }

clvr_result clvr_image_path_numbered(const char *path, uint32_t index, char *out, size_t size, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_image_path_numbered";
    if (!path || !out) return finish(NULL_ARG(fn, "path or out"), &e, msg);
    if (!clvr_image_numbered_path(path, index, out, size))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: %s with a frame number does not fit %zu bytes", fn,
                                     path, size),
                      &e, msg);
    return finish(CLVR_OK, &e, msg);
}

void clvr_process_memory(uint64_t *resident, uint64_t *peak) { clvr_mem_rss(resident, peak); }

clvr_result clvr_image_to_srgb8(const float *rgba, uint32_t width, uint32_t height, float exposure_ev,
                                const char *tonemap, uint8_t *rgba8, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_image_to_srgb8";
    if (!rgba || !rgba8) return finish(NULL_ARG(fn, "rgba or rgba8"), &e, msg);
    if (!isfinite(exposure_ev))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: exposure_ev must be finite", fn), &e, msg);
    const clvr_tonemap tm = clvr_tonemap_parse(tonemap ? tonemap : "aces");
    if (tm >= CLVR_TONEMAP_COUNT)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown tone curve '%.64s'; use none, aces or filmic",
                                     fn, tonemap),
                      &e, msg);
    const float gain = exp2f(exposure_ev);
    const size_t n = (size_t)width * height * 4;
    for (size_t i = 0; i < n; i += 4) {
        for (int k = 0; k < 3; ++k) rgba8[i + k] = clvr_image_srgb_to_u8(clvr_image_tonemap(tm, rgba[i + k] * gain));
        rgba8[i + 3] = 255;
    }
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_image_save_srgb8(const char *path, uint32_t width, uint32_t height, const uint8_t *rgba8,
                                  clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_image_save_srgb8";
    if (!path || !rgba8) return finish(NULL_ARG(fn, "path or rgba8"), &e, msg);
    const size_t n = (size_t)width * height;
    float *img = malloc((n ? n : 1) * 4 * sizeof(float));
    if (!img) return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn), &e, msg);
    float dec[256];
    for (int i = 0; i < 256; ++i) dec[i] = clvr_image_srgb_decode((float)i / 255.0f);
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) img[4 * i + k] = dec[rgba8[4 * i + k]];
        img[4 * i + 3] = 1.0f;
    }
    clvr_status s = clvr_image_write(path, width, height, img, &e);
    free(img);
    return finish(s, &e, msg);
}

/* --- images --------------------------------------------------------------- */

clvr_result clvr_image_save(const char *path, uint32_t width, uint32_t height, const float *rgba, float exposure_ev,
                            const char *tonemap, int transparent, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_image_save";
    if (!path) return finish(NULL_ARG(fn, "path"), &e, msg);
    if (!rgba) return finish(NULL_ARG(fn, "rgba"), &e, msg);
    if (!isfinite(exposure_ev))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: exposure_ev must be finite", fn), &e, msg);
    clvr_tonemap tm = clvr_tonemap_parse(tonemap ? tonemap : "aces");
    if (tm >= CLVR_TONEMAP_COUNT)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown tone curve '%.64s'; use none, aces or filmic",
                                     fn, tonemap),
                      &e, msg);
    clvr_image_display d = {exposure_ev, tm, transparent != 0, NULL};
    return finish(clvr_image_write_display(path, width, height, rgba, &d, &e), &e, msg);
}

/* --- internal: the library's own drivers (clvr_internal.h) --------------- */

clvr_status clvr_internal_status(clvr_result r, const clvr_message *msg, clvr_error *err)
{
    if (r == CLVR_RESULT_OK) return CLVR_OK;
    return clvr_error_set(err, (clvr_status)r, "%s", msg && msg->text[0] ? msg->text : clvr_result_text(r));
}

clvr_status clvr_internal_dataset_adopt(clvr_mesh *m, clvr_dataset **out, clvr_error *err)
{
    return dataset_adopt(m, out, err);
}

clvr_status clvr_internal_tf_build(const clvr_mesh *m, const char *colormap, const char *tf_path, int range_set,
                                   float lo, float hi, float density, int ramp, clvr_tf *tf, float *auto_density,
                                   clvr_error *err)
{
    return tf_build(m, colormap, tf_path, range_set, lo, hi, density, ramp, tf, auto_density, err);
}

clvr_status clvr_internal_tracer_create(clvr_context *ctx, clvr_dataset *ds, const clvr_preprocess_settings *ps,
                                        const float quantize_lo[3], const float quantize_hi[3],
                                        const clvr_render_settings *rs, int shadows, clvr_tracer **out,
                                        double *preprocess_s, clvr_error *err)
{
    clvr_scene *sc = NULL;
    clvr_tracer *tr = NULL;
    clvr_box qbox;
    memset(&qbox, 0, sizeof qbox);
    for (int k = 0; k < 3 && quantize_lo && quantize_hi; ++k) {
        qbox.lo[k] = quantize_lo[k];
        qbox.hi[k] = quantize_hi[k];
    }
    clvr_status s = scene_create(ctx, ds, NULL, ps, quantize_lo && quantize_hi ? &qbox : NULL, &sc, err);
    if (s == CLVR_OK) {
        clvr_tracer_settings ts;
        clvr_tracer_settings_init(&ts);
        s = tracer_create(sc, &ts, rs->width, rs->height, &tr, err);
    }
    if (s == CLVR_OK) {
        tr->rs = *rs;
        tr->shadows = shadows;
        s = apply_settings(tr, err);
    }
    if (s == CLVR_OK && preprocess_s) *preprocess_s = sc->preprocess_s;
    scene_release(sc); /* the tracer holds it */
    if (s != CLVR_OK) {
        clvr_tracer_destroy(tr);
        return s;
    }
    *out = tr;
    return CLVR_OK;
}

clvr_status clvr_internal_render_settings(const clvr_tracer_settings *ts, uint32_t width, uint32_t height,
                                          clvr_render_settings *rs, int *shadows, clvr_error *err)
{
    clvr_render_settings_default(rs);
    rs->width = width;
    rs->height = height;
    return settings_to_render("clvr", ts, rs, shadows, err);
}

clvr_renderer *clvr_internal_tracer_renderer(clvr_tracer *tr) { return tr ? tr->renderer : NULL; }

/* --- API 1.2: names, framing, transfer function files, time series ------ */

/* The tables are the pipeline's own names in the order of its constants
 * (clvr_shared.h, image.h, limits_check.h), so that a program keeping a
 * setting as its index holds the pipeline's value; the asserts catch a
 * renumbering. */
_Static_assert(CLVR_SAMPLER_INDEPENDENT == 0 && CLVR_SAMPLER_LD == 1, "sampler names out of order");
_Static_assert(CLVR_PIXEL_BOX == 0 && CLVR_PIXEL_POINT == 1, "pixel filter names out of order");
_Static_assert(CLVR_TONEMAP_NONE == 0 && CLVR_TONEMAP_ACES == 1 && CLVR_TONEMAP_FILMIC == 2, "tone curves out of order");
_Static_assert(CLVR_ELEMENT_BOXES_AUTO == CLVR_EBOX_AUTO && CLVR_ELEMENT_BOXES_ON == CLVR_EBOX_ON &&
                   CLVR_ELEMENT_BOXES_OFF == CLVR_EBOX_OFF, "element box modes drifted");
_Static_assert(CLVR_ONE_CURVE_AUTO == 0 && CLVR_ONE_CURVE_ON == 1 && CLVR_ONE_CURVE_OFF == 2,
               "one_curve names out of order");
_Static_assert(CLVR_MAX_CLIP == CLVR_MAX_CLIP_PLANES, "clip plane limits differ");

const char *clvr_setting_name(const char *setting, uint32_t index)
{
    static const char *samplers[] = {"independent", "ld"};
    static const char *boxes[] = {"auto", "on", "off"}; /* also one_curve's */
    static const char *filters[] = {"box", "point"}; /* CLVR_PIXEL_* */
    if (!setting) return NULL;
    if (!strcmp(setting, "method")) return index < CLVR_RENDER_COUNT ? clvr_render_method_name(index) : NULL;
    if (!strcmp(setting, "estimator"))
        return index < CLVR_ESTIMATOR_COUNT ? clvr_render_estimator_name(index) : NULL;
    if (!strcmp(setting, "sampler")) return index < 2 ? samplers[index] : NULL;
    if (!strcmp(setting, "tonemap")) return index < CLVR_TONEMAP_COUNT ? clvr_tonemap_name((clvr_tonemap)index) : NULL;
    if (!strcmp(setting, "element_boxes")) return index < 3 ? boxes[index] : NULL;
    if (!strcmp(setting, "one_curve")) return index < 3 ? boxes[index] : NULL;
    if (!strcmp(setting, "pixel_filter")) return index < 2 ? filters[index] : NULL;
    return NULL;
}

clvr_result clvr_setting_index(const char *setting, const char *name, uint32_t *index, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_setting_index";
    if (!setting) return finish(NULL_ARG(fn, "setting"), &e, msg);
    if (!name) return finish(NULL_ARG(fn, "name"), &e, msg);
    if (!index) return finish(NULL_ARG(fn, "index"), &e, msg);
    if (!clvr_setting_name(setting, 0))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown setting '%s'; use method, estimator, sampler, "
                                     "tonemap, element_boxes or pixel_filter", fn, setting),
                      &e, msg);
    char list[256] = "";
    size_t len = 0;
    for (uint32_t i = 0; clvr_setting_name(setting, i); ++i) {
        const char *n = clvr_setting_name(setting, i);
        if (!strcmp(n, name)) {
            *index = i;
            return finish(CLVR_OK, &e, msg);
        }
        len += (size_t)snprintf(list + len, len < sizeof list ? sizeof list - len : 0, "%s%s", i ? ", " : "", n);
        if (len >= sizeof list) len = sizeof list - 1;
    }
    return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown %s '%s'; use one of %s", fn, setting, name, list),
                  &e, msg);
}

void clvr_default_size(uint32_t *width, uint32_t *height)
{
    clvr_render_settings rs;
    clvr_render_settings_default(&rs);
    if (width) *width = rs.width;
    if (height) *height = rs.height;
}

clvr_result clvr_frame_box(const float lo[3], const float hi[3], const float up[3], float azimuth_deg,
                           float elevation_deg, float zoom, float fovy_deg, uint32_t width, uint32_t height,
                           float eye[3], float target[3], clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_frame_box";
    static const float y_up[3] = {0, 1, 0};
    if (!lo) return finish(NULL_ARG(fn, "lo"), &e, msg);
    if (!hi) return finish(NULL_ARG(fn, "hi"), &e, msg);
    if (!eye) return finish(NULL_ARG(fn, "eye"), &e, msg);
    if (!target) return finish(NULL_ARG(fn, "target"), &e, msg);
    if (!isfinite(azimuth_deg) || !isfinite(elevation_deg) || (up && !finite3(up)))
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: azimuth %g, elevation %g and the up axis must be finite",
                                     fn, (double)azimuth_deg, (double)elevation_deg),
                      &e, msg);
    /* The framing of clvr_tracer_frame (frame_view above), on a box. */
    clvr_camera_view view;
    clvr_camera_view_default(&view);
    memcpy(view.up, up ? up : y_up, sizeof view.up);
    view.azimuth_deg = azimuth_deg;
    view.elevation_deg = elevation_deg;
    view.zoom = zoom;
    clvr_camera cam;
    clvr_status s = clvr_camera_frame_view(&cam, lo, hi, &view, fovy_deg, width, height, &e);
    if (s == CLVR_OK) {
        memcpy(eye, cam.origin, 3 * sizeof(float));
        memcpy(target, cam.target, 3 * sizeof(float));
    }
    return finish(s, &e, msg);
}

clvr_result clvr_tf_file_window(const char *tf_path, int *has_window, float *lo, float *hi, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tf_file_window";
    if (!tf_path) return finish(NULL_ARG(fn, "tf_path"), &e, msg);
    if (!has_window) return finish(NULL_ARG(fn, "has_window"), &e, msg);
    clvr_tf t = {0};
    clvr_status s = clvr_tf_init(&t, NULL, &e);
    if (s == CLVR_OK) s = clvr_tf_load(&t, tf_path, &e);
    if (s == CLVR_OK) {
        *has_window = t.range_set != 0;
        if (lo) *lo = t.range_set ? t.range_lo : 0.0f;
        if (hi) *hi = t.range_set ? t.range_hi : 0.0f;
    }
    clvr_tf_free(&t);
    return finish(s, &e, msg);
}

struct clvr_series {
    char *path; /* the .series file, for messages */
    char **paths;
    double *times;
    uint32_t n;
};

int clvr_path_is_series(const char *path) { return clvr_series_is(path); }

clvr_result clvr_series_open(const char *path, clvr_series **out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_series_open";
    if (!path) return finish(NULL_ARG(fn, "path"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_series *se = calloc(1, sizeof *se);
    char *copy = strdup(path);
    if (!se || !copy) {
        free(se);
        free(copy);
        return finish(clvr_error_set(&e, CLVR_ERR_NO_MEMORY, "%s: out of memory", path), &e, msg);
    }
    se->path = copy;
    clvr_status s = clvr_series_read(path, &se->paths, &se->times, &se->n, &e);
    if (s != CLVR_OK) {
        clvr_series_destroy(se);
        return finish(s, &e, msg);
    }
    *out = se;
    return finish(CLVR_OK, &e, msg);
}

void clvr_series_destroy(clvr_series *se)
{
    if (!se) return;
    clvr_series_free(se->paths, se->times, se->n);
    free(se->path);
    free(se);
}

uint32_t clvr_series_count(const clvr_series *se) { return se ? se->n : 0; }

clvr_result clvr_series_step(const clvr_series *se, uint32_t i, const char **path, double *time, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_series_step";
    if (!se) return finish(NULL_ARG(fn, "se"), &e, msg);
    if (i >= se->n)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: step %u of %s, which has %u", fn, i, se->path, se->n),
                      &e, msg);
    if (path) *path = se->paths[i];
    if (time) *time = se->times[i];
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_series_bounds(const clvr_series *se, const char *field, float lo[3], float hi[3], float *min,
                               float *max, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_series_bounds";
    if (!se) return finish(NULL_ARG(fn, "se"), &e, msg);
    float blo[3] = {0, 0, 0}, bhi[3] = {0, 0, 0}, vlo = 0, vhi = 0;
    for (uint32_t i = 0; i < se->n; ++i) {
        clvr_mesh m = {0};
        clvr_load_options opt = {0};
        opt.scalar_name = field;
        opt.map_indices = opt.map_vertices = 1; /* only bounds and range are needed: no copy of a .bin */
        clvr_status s = clvr_mesh_load(se->paths[i], &opt, &m, &e);
        if (s != CLVR_OK) {
            clvr_mesh_free(&m);
            char first[sizeof e.msg];
            memcpy(first, e.msg, sizeof first);
            first[sizeof first - 64] = '\0'; /* room for the step */
            return finish(clvr_error_set(&e, s, "%s (step %u of %s)", first, i, se->path), &e, msg);
        }
        for (int k = 0; k < 3; ++k) {
            blo[k] = i == 0 || m.bounds_lo[k] < blo[k] ? m.bounds_lo[k] : blo[k];
            bhi[k] = i == 0 || m.bounds_hi[k] > bhi[k] ? m.bounds_hi[k] : bhi[k];
        }
        vlo = i == 0 || m.scalar_min < vlo ? m.scalar_min : vlo;
        vhi = i == 0 || m.scalar_max > vhi ? m.scalar_max : vhi;
        clvr_mesh_free(&m);
    }
    if (lo) memcpy(lo, blo, sizeof blo);
    if (hi) memcpy(hi, bhi, sizeof bhi);
    if (min) *min = vlo;
    if (max) *max = vhi;
    return finish(CLVR_OK, &e, msg);
}
