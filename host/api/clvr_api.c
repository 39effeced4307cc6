/* clvr_api.c: libclvr's public API (clvr.h) over the pipeline objects: the
 * OpenCL context (cl_context.h), the mesh (mesh.h) seen through a borrowed
 * view of the dataset's arrays, Quick Clusters (preprocess.h), the trees
 * (accel.h), the renderer (render.h), the transfer function (tf.h,
 * tf_auto.h) and the image writers (image.h). Internal statuses map one to
 * one onto clvr_result (checked at compile time below). */
#define CLVR_API_BUILD 1
#include "clvr.h"
#include "clvr_bridge.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"
#include "camera.h"
#include "cl_context.h"
#include "clock.h"
#include "image.h"
#include "limits_check.h"
#include "mesh.h"
#include "mesh_io.h"
#include "partition.h"
#include "preprocess.h"
#include "render.h"
#include "scene.h"
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
};

struct clvr_context {
    clvr_cl cl;
    unsigned tracers; /* live tracers; destroying ctx before them is a bug */
};

struct clvr_tracer {
    clvr_context *ctx;
    clvr_dataset *ds; /* NULL after clvr_tracer_drop_dataset */
    uint32_t field;
    float lo[3], hi[3]; /* the dataset's bounds */
    clvr_tf tf;         /* the transfer function set by options (the viewer edits it) */
    clvr_clustered clustered;
    clvr_accel accel;
    clvr_renderer *renderer;
    clvr_render_settings rs;
    int shadows; /* asked for; march has none */
    clvr_camera cam;
    float up[3];
    float density, range_lo, range_hi;
    uint64_t clustered_points; /* the dataset's points */
    uint64_t frames;
    double preprocess_s;
    uint32_t partitions; /* preprocessing partitions used */
};

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
    if (ctx->tracers)
        fprintf(stderr, "clvr: clvr_context_destroy: %u tracer(s) still alive; destroy them first\n", ctx->tracers);
    clvr_cl_destroy(&ctx->cl);
    free(ctx);
}

clvr_cl *clvr_context_cl(clvr_context *ctx) { return &ctx->cl; }

clvr_status clvr_context_warm_up_setup(clvr_context *ctx, const clvr_preprocess_options *po, clvr_error *err)
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
    return finish(clvr_context_warm_up_setup(ctx, &po, &e), &e, msg);
}

clvr_status clvr_bridge_status(clvr_result r, const clvr_message *msg, clvr_error *err)
{
    if (r == CLVR_RESULT_OK) return CLVR_OK;
    return clvr_error_set(err, (clvr_status)r, "%s", msg->text);
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

clvr_status clvr_dataset_adopt(clvr_mesh *m, clvr_dataset **out, clvr_error *err)
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
    if (s != CLVR_OK) {
        clvr_mesh_free(&ds->loaded);
        free(ds->fields);
        free(ds);
        return s;
    }
    *out = ds;
    return CLVR_OK;
}

clvr_result clvr_dataset_load(const char *path, const char *field, clvr_dataset **out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_load";
    if (!path) return finish(NULL_ARG(fn, "path"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_mesh m = {0};
    clvr_load_options lo = {0};
    lo.scalar_name = field;
    clvr_status s = clvr_mesh_load(path, &lo, &m, &e);
    if (s == CLVR_OK) {
        if (!m.scalar_name[0] && field) clvr_mesh_set_scalar_name(&m, field, strlen(field));
        s = clvr_dataset_adopt(&m, out, &e);
    }
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
    if (num_fields) *num_fields = ds->num_fields;
    return finish(CLVR_OK, &e, msg);
}

clvr_result clvr_dataset_field_name(const clvr_dataset *ds, uint32_t i, char *buf, size_t size, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_field_name";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!buf || !size) return finish(NULL_ARG(fn, "buf (or size 0)"), &e, msg);
    if (i >= ds->num_fields)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: field %u asked but the dataset has %u", fn, i,
                                     ds->num_fields),
                      &e, msg);
    copy_str(buf, size, ds->fields[i].name);
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

clvr_result clvr_dataset_field_range(const clvr_dataset *ds, const char *field, float *min, float *max,
                                     clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_dataset_field_range";
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!min || !max) return finish(NULL_ARG(fn, "min or max"), &e, msg);
    int i;
    clvr_status s = lookup_field(ds, fn, field, &i, &e);
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

clvr_status clvr_dataset_view(const clvr_dataset *ds, const char *field, clvr_mesh *out, clvr_error *err)
{
    int i;
    clvr_status s = lookup_field(ds, "clvr_dataset_view", field, &i, err);
    if (s != CLVR_OK) return s;
    if (ds->loaded.positions && i == 0)
        *out = ds->loaded; /* a file's mesh as its loader left it: its fields, skipped cells, ... */
    else
        mesh_view(ds, (uint32_t)i, out);
    return CLVR_OK;
}

/* --- tracer --------------------------------------------------------------- */

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

/* Uploads tf baked, as the program does, and keeps it (moved: *tf zeroed). */
static clvr_status upload_tf(clvr_tracer *tr, clvr_tf *tf, clvr_error *e)
{
    const uint32_t n = clvr_tf_table_size(tf);
    float *table = malloc((size_t)n * 4 * sizeof(float));
    if (!table) return clvr_error_set(e, CLVR_ERR_NO_MEMORY, "out of memory for the transfer function");
    clvr_tf_bake(tf, table, n);
    clvr_status s = clvr_renderer_set_tf(tr->renderer, table, n, tf->range_lo, tf->range_hi, tf->density, e);
    free(table);
    if (s == CLVR_OK) {
        tr->density = tf->density;
        tr->range_lo = tf->range_lo;
        tr->range_hi = tf->range_hi;
        tr->frames = 0;
        clvr_tf_free(&tr->tf);
        tr->tf = *tf;
        memset(tf, 0, sizeof *tf);
    }
    return s;
}

clvr_status clvr_api_tf_build(const clvr_mesh *m, const char *colormap, const char *tf_path, int range_set,
                              float lo, float hi, float density, int density_auto, int ramp, clvr_tf *tf,
                              float *auto_density, clvr_error *err)
{
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
    clvr_mesh m;
    mesh_view(tr->ds, tr->field, &m);
    clvr_tf tf = {0};
    float auto_density;
    clvr_status s = clvr_api_tf_build(&m, colormap, tf_path, range_set, lo, hi, density, density == 0, ramp, &tf,
                                      &auto_density, e);
    if (s == CLVR_OK) s = upload_tf(tr, &tf, e);
    clvr_tf_free(&tf);
    return s;
}

void clvr_tracer_setup_default(clvr_tracer_setup *s, uint32_t width, uint32_t height)
{
    memset(s, 0, sizeof *s);
    clvr_preprocess_options_default(&s->po);
    clvr_render_settings_default(&s->rs);
    s->rs.width = width;
    s->rs.height = height;
    s->shadows = s->rs.shadows;
}

clvr_status clvr_tracer_create_setup(clvr_context *ctx, clvr_dataset *ds, const char *field,
                                     clvr_tracer_setup *setup, clvr_tracer **out, clvr_error *err)
{
    static const char fn[] = "clvr_tracer_create";
    const uint32_t width = setup->rs.width, height = setup->rs.height;
    if (width < 1 || height < 1 || width > CLVR_IMAGE_MAX_DIM || height > CLVR_IMAGE_MAX_DIM)
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: image %ux%u; width and height must be in [1, %u]", fn, width,
                              height, CLVR_IMAGE_MAX_DIM);
    int fi;
    clvr_status s = lookup_field(ds, fn, field, &fi, err);
    if (s != CLVR_OK) return s;
    clvr_mesh m;
    mesh_view(ds, (uint32_t)fi, &m);
    if (clvr_mesh_num_elements(&m) == 0)
        return clvr_error_set(err, CLVR_ERR_EMPTY, "%s: the dataset has no cells; add some with "
                              "clvr_dataset_add_cells", fn);
    clvr_tracer *tr = calloc(1, sizeof *tr);
    if (!tr) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", fn);
    tr->ctx = ctx;
    tr->ds = ds;
    tr->field = (uint32_t)fi;
    memcpy(tr->lo, ds->lo, sizeof tr->lo);
    memcpy(tr->hi, ds->hi, sizeof tr->hi);
    tr->clustered_points = ds->num_points;
    ++ds->refs;
    ++ctx->tracers;

    /* A mesh or image the device cannot hold fails now, with the numbers,
     * not minutes into preprocessing. */
    const uint64_t n = clvr_mesh_num_elements(&m);
    const uint64_t part = clvr_partition_elements(n, setup->partitions);
    s = clvr_limits_check_parts(&ctx->cl, &m, setup->name ? setup->name : "dataset", &setup->po, part, width, height,
                                err);
    /* Preprocessing in partitions (partition.h). A loaded file's mesh that
     * only this tracer and the caller hold, when the caller drops it after
     * (setup->consume), is consumed: its element lists go back to the OS
     * partition by partition, so the input shrinks while the result grows. */
    clvr_mesh *pm = &m;
    int consume = 0;
    if (setup->consume && ds->refs == 2 && ds->loaded.positions && ds->loaded.positions == ds->xyz &&
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
        s = clvr_preprocess_partitioned(&ctx->cl, pm, &setup->po, setup->partitions, 0, consume, &tr->clustered,
                                        &tr->partitions, err);
    if (consume) /* the lists are gone (counts kept): nothing may read them again */
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) ds->cells[t] = NULL;
    if (s == CLVR_OK) s = clvr_accel_build(&ctx->cl, &tr->clustered, &tr->accel, err);
    /* Compiling kernels (seconds on a cold driver cache) is not clustering. */
    tr->preprocess_s = clvr_clock_monotonic_s() - t0 - (ctx->cl.build_s - build0);
    tr->rs = setup->rs;
    tr->shadows = setup->shadows;
    tr->rs.shadows = tr->shadows && tr->rs.method != CLVR_RENDER_MARCH;
    if (s == CLVR_OK) s = clvr_renderer_create(&ctx->cl, &tr->clustered, &tr->accel, &tr->rs, &tr->renderer, err);
    /* The program's defaults: framing, transfer function. */
    if (s == CLVR_OK) s = frame_view(tr, NULL, 0, 0, 1, 30.0f, err);
    if (s == CLVR_OK) s = setup->tf ? upload_tf(tr, setup->tf, err) : set_tf(tr, NULL, NULL, NAN, NAN, 0, 0, err);
    if (s != CLVR_OK) {
        clvr_tracer_destroy(tr);
        return s;
    }
    *out = tr;
    return CLVR_OK;
}

clvr_result clvr_tracer_create(clvr_context *ctx, clvr_dataset *ds, const char *field, uint32_t width,
                               uint32_t height, clvr_tracer **out, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_create";
    if (!ctx) return finish(NULL_ARG(fn, "ctx"), &e, msg);
    if (!ds) return finish(NULL_ARG(fn, "ds"), &e, msg);
    if (!out) return finish(NULL_ARG(fn, "out"), &e, msg);
    clvr_tracer_setup setup;
    clvr_tracer_setup_default(&setup, width, height);
    return finish(clvr_tracer_create_setup(ctx, ds, field, &setup, out, &e), &e, msg);
}

void clvr_tracer_destroy(clvr_tracer *tr)
{
    if (!tr) return;
    clvr_renderer_destroy(tr->renderer);
    clvr_accel_release(&tr->ctx->cl, &tr->accel);
    clvr_clustered_release(&tr->ctx->cl, &tr->clustered);
    --tr->ctx->tracers;
    dataset_release(tr->ds);
    clvr_tf_free(&tr->tf);
    free(tr);
}

clvr_result clvr_tracer_drop_dataset(clvr_tracer *tr, clvr_message *msg)
{
    clvr_error e = {0};
    if (!tr) return finish(NULL_ARG("clvr_tracer_drop_dataset", "tr"), &e, msg);
    dataset_release(tr->ds);
    tr->ds = NULL;
    return finish(CLVR_OK, &e, msg);
}

void clvr_tracer_parts_of(clvr_tracer *tr, clvr_tracer_parts *out)
{
    out->clustered = &tr->clustered;
    out->accel = &tr->accel;
    out->renderer = tr->renderer;
    out->rs = &tr->rs;
    out->cam = &tr->cam;
    out->tf = &tr->tf;
    out->preprocess_s = tr->preprocess_s;
    out->partitions = tr->partitions;
}

static int finite3(const float *v) { return v && isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

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
    clvr_status s = clvr_renderer_set_tf(tr->renderer, table, n, range_lo, range_hi, density, &e);
    free(table);
    if (s == CLVR_OK) {
        clvr_tf_free(&tr->tf);
        tr->density = density;
        tr->range_lo = range_lo;
        tr->range_hi = range_hi;
        tr->frames = 0;
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
            return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown estimator '%.64s'; use delta or urm", fn,
                                         estimator),
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
    clvr_status s = CLVR_OK;
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

clvr_result clvr_tracer_read_image(clvr_tracer *tr, float *rgba, size_t count, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_read_image";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!rgba) return finish(NULL_ARG(fn, "rgba"), &e, msg);
    const size_t need = (size_t)tr->rs.width * tr->rs.height * 4;
    if (count < need)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: rgba holds %zu floats; a %ux%u image needs %zu", fn,
                                     count, tr->rs.width, tr->rs.height, need),
                      &e, msg);
    if (tr->frames == 0)
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: no frame rendered since the last change; call "
                                     "clvr_tracer_render first", fn),
                      &e, msg);
    return finish(clvr_renderer_read(tr->renderer, rgba, NULL, &e), &e, msg);
}

static const char *const stat_names =
    "frames, rays, samples, null_collisions, kernel_s, last_frame_s, preprocess_s, kernel_build_s, elements, points, "
    "instances, leaves, sampling_clusters, device_bytes, density, range_lo, range_hi";

clvr_result clvr_tracer_stat(clvr_tracer *tr, const char *name, double *value, clvr_message *msg)
{
    clvr_error e = {0};
    static const char fn[] = "clvr_tracer_stat";
    if (!tr) return finish(NULL_ARG(fn, "tr"), &e, msg);
    if (!name || !value) return finish(NULL_ARG(fn, "name or value"), &e, msg);
    clvr_render_counters c = {0};
    clvr_status s = CLVR_OK;
    if (tr->frames) s = clvr_renderer_read(tr->renderer, NULL, &c, &e);
    if (s != CLVR_OK) return finish(s, &e, msg);
    const clvr_clustered *k = &tr->clustered;
    double v;
    if (!strcmp(name, "frames")) v = (double)tr->frames;
    else if (!strcmp(name, "rays")) v = (double)c.rays;
    else if (!strcmp(name, "samples")) v = (double)c.samples;
    else if (!strcmp(name, "null_collisions")) v = (double)c.null_collisions;
    else if (!strcmp(name, "kernel_s")) v = c.kernel_s;
    else if (!strcmp(name, "last_frame_s")) v = c.last_frame_s;
    else if (!strcmp(name, "preprocess_s")) v = tr->preprocess_s;
    else if (!strcmp(name, "kernel_build_s")) v = tr->ctx->cl.build_s;
    else if (!strcmp(name, "elements")) v = (double)k->num_elements;
    else if (!strcmp(name, "points")) v = (double)tr->clustered_points;
    else if (!strcmp(name, "instances")) v = (double)k->num_instances;
    else if (!strcmp(name, "leaves")) v = (double)k->num_leaves;
    else if (!strcmp(name, "sampling_clusters")) v = (double)k->num_sampling;
    else if (!strcmp(name, "device_bytes")) v = (double)tr->ctx->cl.allocated_bytes;
    else if (!strcmp(name, "density")) v = tr->density;
    else if (!strcmp(name, "range_lo")) v = tr->range_lo;
    else if (!strcmp(name, "range_hi")) v = tr->range_hi;
    else
        return finish(clvr_error_set(&e, CLVR_ERR_USAGE, "%s: unknown figure '%.64s'; use one of %s", fn, name,
                                     stat_names),
                      &e, msg);
    *value = v;
    return finish(CLVR_OK, &e, msg);
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
