#include "render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct clvr_renderer {
    clvr_cl *cl;
    const clvr_clustered *mesh;
    const clvr_accel *bvh;
    clvr_render_settings set;
    clvr_frame frame;
    clvr_camera cam;
    cl_program prog_render, prog_majorant;
    cl_kernel k_render, k_cluster_maj, k_grid_clear, k_grid_splat_el, k_grid_maj, k_grid_blocks;
    cl_mem frame_buf, cam_buf, tf_buf, accum, accum_sq, counters, cluster_maj, grid_range, grid_maj, block_maj;
    uint32_t tf_n;             /* entries in tf_buf (0: no transfer function yet) */
    uint32_t grid_res;         /* resolution of grid_range/grid_maj */
    uint32_t accum_w, accum_h; /* size of accum buffers */
    uint64_t frames;
    double kernel_s, last_frame_s;
    size_t local[2];           /* work-group shape of the render kernel */
};

static const char *const method_names[CLVR_RENDER_COUNT] = {"march", "track", "bins", "dda"};
static const char *const estimator_names[CLVR_ESTIMATOR_COUNT] = {"delta", "urm"};

const char *clvr_render_method_name(uint32_t m) { return m < CLVR_RENDER_COUNT ? method_names[m] : "?"; }
const char *clvr_render_estimator_name(uint32_t e) { return e < CLVR_ESTIMATOR_COUNT ? estimator_names[e] : "?"; }

uint32_t clvr_render_method_from_name(const char *name)
{
    uint32_t m = 0;
    while (m < CLVR_RENDER_COUNT && strcmp(name, method_names[m])) ++m;
    return m;
}

uint32_t clvr_render_estimator_from_name(const char *name)
{
    uint32_t e = 0;
    while (e < CLVR_ESTIMATOR_COUNT && strcmp(name, estimator_names[e])) ++e;
    return e;
}

void clvr_render_settings_default(clvr_render_settings *s)
{
    memset(s, 0, sizeof *s);
    s->method = CLVR_RENDER_DDA;
    /* urm: the estimator that reaches a given relative error first
     * (bench/render-vs-vtk.sh, README "Rendering"). */
    s->estimator = CLVR_ESTIMATOR_URM;
    s->urm_steps = CLVR_URM_DEFAULT_STEPS;
    s->urm_kappa = CLVR_URM_DEFAULT_KAPPA;
    s->width = s->height = 512;
    s->seed = 1;
    /* Low-discrepancy frames: the progressive image reaches a given error
     * in fewer frames (bench_render --converge); tests that need
     * independent frames ask for CLVR_SAMPLER_INDEPENDENT. */
    s->sampler = CLVR_SAMPLER_LD;
    s->shadows = 1;
    s->bins = 32;
    s->segments = 4;
    /* 32^3: measured best or near-best with 16-element sampling clusters on
     * the default scene, amr-1M and post at densities 1 and 8 (finer grids
     * save samples but cost more cell steps; bench/results/render). */
    s->macrocells = 32;
    s->light_dir[0] = 1.0f;
    s->light_dir[1] = 2.0f;
    s->light_dir[2] = 1.5f;
    s->light_intensity = 1.0f;
    s->ambient = 0.3f;
    s->background[0] = 0.05f;
    s->background[1] = 0.05f;
    s->background[2] = 0.07f;
    for (int k = 0; k < 3; ++k) {
        s->clip_lo[k] = s->grid_lo[k] = 1.0f;
        s->clip_hi[k] = s->grid_hi[k] = -1.0f;
    }
}

static clvr_status set_arg(cl_kernel k, cl_uint i, size_t size, const void *v, const char *kname, clvr_error *err)
{
    cl_int rc = clSetKernelArg(k, i, size, v);
    if (rc != CL_SUCCESS)
        return clvr_error_set(err, CLVR_ERR_OPENCL, "clSetKernelArg(%s, %u) failed with %s", kname, i,
                              clvr_cl_error_name(rc));
    return CLVR_OK;
}

#define ARG(k, i, v) CLVR_TRY(set_arg(k, i, sizeof(v), &(v), #k, err))

/* Writes the frame parameters to the device (blocking: the host copy may
 * change right after). */
static clvr_status upload_frame(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->frame_buf, CL_TRUE, 0, sizeof r->frame, &r->frame, 0, NULL,
                                       NULL));
cleanup:
    return s;
}

/* Rasterizes the elements' scalar ranges into an R^3 grid and allocates its
 * coarse level of blocks (once per mesh and resolution; majorants follow in
 * update_majorants). */
static clvr_status build_grid(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = r->cl;
    uint32_t res = r->set.macrocells;
    uint64_t cells = (uint64_t)res * res * res;
    cl_uint ncells = (cl_uint)cells;
    if (r->grid_res == res) return CLVR_OK;
    clvr_cl_release(cl, &r->grid_range);
    clvr_cl_release(cl, &r->grid_maj);
    clvr_cl_release(cl, &r->block_maj);
    r->grid_res = 0;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)cells * 2 * sizeof(cl_uint), NULL, "macrocell ranges",
                            &r->grid_range, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)cells * sizeof(cl_float), NULL, "macrocell majorants",
                            &r->grid_maj, err));
    {
        uint64_t rc = (res + CLVR_DDA_BLOCK - 1) / CLVR_DDA_BLOCK;
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)(rc * rc * rc) * sizeof(cl_float), NULL,
                                "macrocell block majorants", &r->block_maj, err));
    }
    CLVR_TRY(upload_frame(r, err));
    ARG(r->k_grid_clear, 0, r->grid_range);
    ARG(r->k_grid_clear, 1, ncells);
    CLVR_TRY(clvr_cl_run1d(cl, r->k_grid_clear, cells, 64, NULL, err));
    /* Per element, not per sampling cluster: tighter cells (majorant.cl). */
    const clvr_clustered *m = r->mesh;
    cl_uint ninst = (cl_uint)m->num_instances, nelem = (cl_uint)m->num_elements;
    ARG(r->k_grid_splat_el, 0, m->instances);
    ARG(r->k_grid_splat_el, 1, ninst);
    ARG(r->k_grid_splat_el, 2, m->vertices);
    ARG(r->k_grid_splat_el, 3, m->idx16);
    ARG(r->k_grid_splat_el, 4, m->idx32);
    ARG(r->k_grid_splat_el, 5, nelem);
    ARG(r->k_grid_splat_el, 6, r->frame_buf);
    ARG(r->k_grid_splat_el, 7, r->grid_range);
    if (nelem) CLVR_TRY(clvr_cl_run1d(cl, r->k_grid_splat_el, nelem, 64, NULL, err));
    r->grid_res = res;
cleanup:
    return s;
}

/* Recomputes cluster, cell and global majorants for the current transfer
 * function (paper 3.4.1: whenever the transfer function changes). */
static clvr_status update_majorants(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = r->cl;
    float *maj = NULL;
    cl_uint nclusters = (cl_uint)r->mesh->num_sampling;
    cl_uint ncells = r->grid_res * r->grid_res * r->grid_res;
    if (!r->tf_n) return CLVR_OK;
    CLVR_TRY(upload_frame(r, err));
    ARG(r->k_cluster_maj, 0, r->mesh->sampling);
    ARG(r->k_cluster_maj, 1, nclusters);
    ARG(r->k_cluster_maj, 2, r->tf_buf);
    ARG(r->k_cluster_maj, 3, r->frame_buf);
    ARG(r->k_cluster_maj, 4, r->cluster_maj);
    CLVR_TRY(clvr_cl_run1d(cl, r->k_cluster_maj, nclusters, 64, NULL, err));
    ARG(r->k_grid_maj, 0, r->grid_range);
    ARG(r->k_grid_maj, 1, ncells);
    ARG(r->k_grid_maj, 2, r->tf_buf);
    ARG(r->k_grid_maj, 3, r->frame_buf);
    ARG(r->k_grid_maj, 4, r->grid_maj);
    CLVR_TRY(clvr_cl_run1d(cl, r->k_grid_maj, ncells, 64, NULL, err));
    {
        cl_uint res = r->grid_res, rc = (res + CLVR_DDA_BLOCK - 1) / CLVR_DDA_BLOCK;
        ARG(r->k_grid_blocks, 0, r->grid_maj);
        ARG(r->k_grid_blocks, 1, res);
        ARG(r->k_grid_blocks, 2, r->block_maj);
        ARG(r->k_grid_blocks, 3, rc);
        CLVR_TRY(clvr_cl_run1d(cl, r->k_grid_blocks, (size_t)rc * rc * rc, 64, NULL, err));
    }
    /* The global majorant of `track` is the largest cluster majorant. */
    maj = malloc((size_t)(nclusters ? nclusters : 1) * sizeof(float));
    if (!maj) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading majorants"); goto cleanup; }
    if (nclusters)
        CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, r->cluster_maj, CL_TRUE, 0, nclusters * sizeof(float), maj, 0,
                                          NULL, NULL));
    float g = 0.0f;
    for (cl_uint i = 0; i < nclusters; ++i) g = maj[i] > g ? maj[i] : g;
    r->frame.global_majorant = g;
cleanup:
    free(maj);
    return s;
}

static clvr_status alloc_image(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = r->cl;
    size_t npix = (size_t)r->set.width * r->set.height;
    if (r->accum && r->accum_w == r->set.width && r->accum_h == r->set.height) return CLVR_OK;
    clvr_cl_release(cl, &r->accum);
    clvr_cl_release(cl, &r->accum_sq);
    clvr_cl_release(cl, &r->counters);
    r->accum_w = r->accum_h = 0;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 4 * sizeof(float), NULL, "image accumulator", &r->accum, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 4 * sizeof(float), NULL, "image second moments",
                            &r->accum_sq, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 3 * sizeof(cl_uint), NULL, "ray counters", &r->counters,
                            err));
    r->accum_w = r->set.width;
    r->accum_h = r->set.height;
cleanup:
    return s;
}

clvr_status clvr_renderer_set_settings(clvr_renderer *r, const clvr_render_settings *set, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (set->method >= CLVR_RENDER_COUNT || set->estimator >= CLVR_ESTIMATOR_COUNT || set->sampler > CLVR_SAMPLER_LD ||
        set->width == 0 || set->height == 0 || set->bins == 0 || set->bins > CLVR_RENDER_MAX_BINS ||
        set->segments == 0 || set->macrocells == 0 || set->urm_steps == 0 || !(set->urm_kappa > 0.0f))
        return clvr_error_set(err, CLVR_ERR_USAGE, "invalid render settings (method %u, estimator %u, sampler %u, "
                              "%ux%u, %u bins, %u segments, %u macrocells, urm steps %u, kappa %g)", set->method,
                              set->estimator, set->sampler, set->width, set->height, set->bins, set->segments,
                              set->macrocells, set->urm_steps, (double)set->urm_kappa);
    uint64_t cells = (uint64_t)set->macrocells * set->macrocells * set->macrocells;
    if (cells > (1ull << 31))
        return clvr_error_set(err, CLVR_ERR_USAGE, "--macrocells %u gives %llu cells; use at most 1290",
                              set->macrocells, (unsigned long long)cells);
    r->set = *set;
    const clvr_clustered *m = r->mesh;
    clvr_frame *f = &r->frame;
    const int clip = set->clip_lo[0] <= set->clip_hi[0], grid = set->grid_lo[0] <= set->grid_hi[0];
    const float old_grid[6] = {f->grid_lo[0], f->grid_lo[1], f->grid_lo[2], f->grid_hi[0], f->grid_hi[1], f->grid_hi[2]};
    for (int k = 0; k < 3; ++k) {
        f->vol_lo[k] = clip ? set->clip_lo[k] : m->bounds.lo[k];
        f->vol_hi[k] = clip ? set->clip_hi[k] : m->bounds.hi[k];
        f->grid_lo[k] = grid ? set->grid_lo[k] : m->bounds.lo[k];
        f->grid_hi[k] = grid ? set->grid_hi[k] : m->bounds.hi[k];
        f->background[k] = set->background[k];
    }
    /* A new grid domain needs the elements rasterized again. */
    if (memcmp(old_grid, f->grid_lo, 3 * sizeof(float)) || memcmp(old_grid + 3, f->grid_hi, 3 * sizeof(float)))
        r->grid_res = 0;
    float len = sqrtf(set->light_dir[0] * set->light_dir[0] + set->light_dir[1] * set->light_dir[1] +
                      set->light_dir[2] * set->light_dir[2]);
    if (!(len > 0.0f)) return clvr_error_set(err, CLVR_ERR_USAGE, "the light direction must not be zero");
    for (int k = 0; k < 3; ++k) f->light_dir[k] = set->light_dir[k] / len;
    float dx = f->vol_hi[0] - f->vol_lo[0], dy = f->vol_hi[1] - f->vol_lo[1], dz = f->vol_hi[2] - f->vol_lo[2];
    float diag = sqrtf(dx * dx + dy * dy + dz * dz);
    f->ambient = set->ambient;
    f->light_intensity = set->light_intensity;
    f->step = set->step > 0.0f ? set->step : (diag > 0.0f ? diag / 512.0f : 1.0f);
    f->width = set->width;
    f->height = set->height;
    f->method = set->method;
    f->estimator = set->estimator;
    f->urm_steps = set->urm_steps;
    f->urm_kappa = set->urm_kappa;
    f->seed_lo = (clvr_u32)set->seed;
    f->seed_hi = (clvr_u32)(set->seed >> 32);
    f->shadows = set->shadows ? 1u : 0u;
    f->sampler = set->sampler;
    f->bins = set->bins;
    f->segments = set->segments;
    f->grid_res = set->macrocells;
    f->leaf_size = m->leaf_size;
    f->tlas_root = r->bvh->tlas_root;
    CLVR_TRY(alloc_image(r, err));
    if (r->grid_res != set->macrocells) {
        CLVR_TRY(build_grid(r, err));
        CLVR_TRY(update_majorants(r, err));
    }
    r->frames = 0;
    r->kernel_s = 0.0;
cleanup:
    return s;
}

clvr_status clvr_renderer_create(clvr_cl *cl, const clvr_clustered *mesh, const clvr_accel *bvh,
                                 const clvr_render_settings *settings, clvr_renderer **out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_renderer *r = calloc(1, sizeof *r);
    *out = NULL;
    if (!r) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory creating the renderer");
    r->cl = cl;
    r->mesh = mesh;
    /* Work-group shape: 8x8 tiles keep neighbouring rays (and their memory
     * accesses) together; on PoCL 8x8, 4x4 and 16x1 measured alike and 1x1
     * a third slower. CLVR_RENDER_LOCAL=WxH overrides, for benchmarks. */
    r->local[0] = r->local[1] = 8;
    {
        const char *e = getenv("CLVR_RENDER_LOCAL");
        unsigned lw, lh;
        if (e && sscanf(e, "%ux%u", &lw, &lh) == 2 && lw >= 1 && lh >= 1 && lw * lh <= cl->max_work_group_size) {
            r->local[0] = lw;
            r->local[1] = lh;
        }
    }
    r->bvh = bvh;
    CLVR_TRY(clvr_cl_build(cl, "render.cl", NULL, &r->prog_render, err));
    CLVR_TRY(clvr_cl_build(cl, "majorant.cl", NULL, &r->prog_majorant, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_render, "clvr_render_frame", &r->k_render, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_majorant, "clvr_cluster_majorants", &r->k_cluster_maj, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_majorant, "clvr_grid_clear", &r->k_grid_clear, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_majorant, "clvr_grid_splat_elements", &r->k_grid_splat_el, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_majorant, "clvr_grid_majorants", &r->k_grid_maj, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_majorant, "clvr_grid_blocks", &r->k_grid_blocks, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, sizeof(clvr_frame), NULL, "frame parameters", &r->frame_buf, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, sizeof(clvr_camera), NULL, "camera", &r->cam_buf, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)(mesh->num_sampling ? mesh->num_sampling : 1) * sizeof(float),
                            NULL, "cluster majorants", &r->cluster_maj, err));
    CLVR_TRY(clvr_renderer_set_settings(r, settings, err));
    *out = r;
    r = NULL;
cleanup:
    clvr_renderer_destroy(r);
    return s;
}

void clvr_renderer_destroy(clvr_renderer *r)
{
    if (!r) return;
    cl_kernel ks[] = {r->k_render, r->k_cluster_maj, r->k_grid_clear, r->k_grid_splat_el, r->k_grid_maj,
                      r->k_grid_blocks};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i)
        if (ks[i]) clReleaseKernel(ks[i]);
    if (r->prog_render) clReleaseProgram(r->prog_render);
    if (r->prog_majorant) clReleaseProgram(r->prog_majorant);
    cl_mem *bufs[] = {&r->frame_buf, &r->cam_buf, &r->tf_buf, &r->accum, &r->accum_sq, &r->counters,
                      &r->cluster_maj, &r->grid_range, &r->grid_maj, &r->block_maj};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; ++i) clvr_cl_release(r->cl, bufs[i]);
    free(r);
}

clvr_status clvr_renderer_set_camera(clvr_renderer *r, const clvr_camera *cam, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    r->cam = *cam;
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->cam_buf, CL_TRUE, 0, sizeof r->cam, &r->cam, 0, NULL, NULL));
    r->frames = 0;
    r->kernel_s = 0.0;
cleanup:
    return s;
}

clvr_status clvr_renderer_set_tf(clvr_renderer *r, const float *rgba, uint32_t n, float lo, float hi, float density,
                                 clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (n < 2 || !(hi > lo) || !(density >= 0.0f))
        return clvr_error_set(err, CLVR_ERR_USAGE, "invalid transfer function (%u entries, range [%g, %g], density %g)",
                              n, lo, hi, density);
    if (n != r->tf_n) {
        clvr_cl_release(r->cl, &r->tf_buf);
        r->tf_n = 0;
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_ONLY, (size_t)n * 4 * sizeof(float), NULL, "transfer function",
                                &r->tf_buf, err));
    }
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->tf_buf, CL_TRUE, 0, (size_t)n * 4 * sizeof(float), rgba, 0,
                                       NULL, NULL));
    r->tf_n = n;
    r->frame.tf_size = n;
    r->frame.tf_lo = lo;
    r->frame.tf_hi = hi;
    r->frame.density = density;
    CLVR_TRY(update_majorants(r, err));
    r->frames = 0;
    r->kernel_s = 0.0;
cleanup:
    return s;
}

clvr_status clvr_renderer_frame(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = r->cl;
    cl_event evt = NULL;
    if (!r->tf_n) return clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr_renderer_frame before a transfer function");
    r->frame.frame_index = (clvr_u32)r->frames;
    CLVR_TRY(upload_frame(r, err));
    const clvr_clustered *m = r->mesh;
    const clvr_accel *b = r->bvh;
    cl_kernel k = r->k_render;
    /* The device arrays of CLVR_VOLUME_ARRAYS, in its order. */
    const struct {
#define CLVR_VOLUME_HOST(T, name) cl_mem name;
        CLVR_VOLUME_ARRAYS(CLVR_VOLUME_HOST)
#undef CLVR_VOLUME_HOST
    } vol = {.tf = r->tf_buf, .vertices = m->vertices, .idx16 = m->idx16, .idx32 = m->idx32,
             .instances = m->instances, .tlas = b->two_level.tlas, .blas = b->two_level.blas, .grid = r->grid_maj,
             .blocks = r->block_maj, .sampling_bvh = b->sampling_nodes, .sampling = m->sampling,
             .cluster_majorants = r->cluster_maj};
    cl_uint i = 0;
    ARG(k, i++, r->frame_buf);
    ARG(k, i++, r->cam_buf);
#define CLVR_VOLUME_ARG(T, name) ARG(k, i++, vol.name);
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_ARG)
#undef CLVR_VOLUME_ARG
    ARG(k, i++, r->accum);
    ARG(k, i++, r->accum_sq);
    ARG(k, i++, r->counters);
    size_t local[2] = {r->local[0], r->local[1]};
    size_t global[2] = {(r->set.width + local[0] - 1) / local[0] * local[0],
                        (r->set.height + local[1] - 1) / local[1] * local[1]};
    cl_int rc = clvr_cl_fault("clEnqueueNDRangeKernel") ? CL_OUT_OF_RESOURCES : CL_SUCCESS;
    if (rc == CL_SUCCESS) rc = clEnqueueNDRangeKernel(cl->queue, k, 2, NULL, global, local, 0, NULL, &evt);
    if (rc != CL_SUCCESS) {
        char call[96];
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(clvr_render_frame, %ux%u)", r->set.width, r->set.height);
        s = clvr_cl_fail(err, call, rc, __FILE__, __LINE__);
        goto cleanup;
    }
    CLVR_CL_CHECK(clWaitForEvents(1, &evt));
    r->last_frame_s = clvr_cl_event_seconds(evt);
    r->kernel_s += r->last_frame_s;
    r->frames++;
cleanup:
    if (evt) clReleaseEvent(evt);
    return s;
}

clvr_status clvr_renderer_read_moments(clvr_renderer *r, float *sum, float *sumsq, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    size_t bytes = (size_t)r->set.width * r->set.height * 4 * sizeof(float);
    if (r->frames == 0) return clvr_error_set(err, CLVR_ERR_INTERNAL, "no frame rendered yet");
    if (sum) CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->accum, CL_TRUE, 0, bytes, sum, 0, NULL, NULL));
    if (sumsq) CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->accum_sq, CL_TRUE, 0, bytes, sumsq, 0, NULL, NULL));
cleanup:
    return s;
}

clvr_status clvr_renderer_read(clvr_renderer *r, float *rgba, clvr_render_counters *counters, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_uint *cnt = NULL;
    size_t npix = (size_t)r->set.width * r->set.height;
    if (rgba) {
        CLVR_TRY(clvr_renderer_read_moments(r, rgba, NULL, err));
        float inv = 1.0f / (float)r->frames;
        for (size_t i = 0; i < npix * 4; ++i) rgba[i] *= inv;
    }
    if (counters) {
        memset(counters, 0, sizeof *counters);
        counters->frames = r->frames;
        counters->kernel_s = r->kernel_s;
        counters->last_frame_s = r->last_frame_s;
        if (r->frames) {
            cnt = malloc(npix * 3 * sizeof(cl_uint));
            if (!cnt) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading counters"); goto cleanup; }
            CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->counters, CL_TRUE, 0, npix * 3 * sizeof(cl_uint), cnt,
                                              0, NULL, NULL));
            for (size_t i = 0; i < npix; ++i) {
                counters->rays += cnt[3 * i];
                counters->samples += cnt[3 * i + 1];
                counters->null_collisions += cnt[3 * i + 2];
            }
        }
    }
cleanup:
    free(cnt);
    return s;
}

clvr_status clvr_renderer_read_majorants(clvr_renderer *r, float *clusters, float *cells, float *blocks,
                                         float *global_majorant, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const size_t rc = (r->grid_res + CLVR_DDA_BLOCK - 1) / CLVR_DDA_BLOCK;
    if (blocks)
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->block_maj, CL_TRUE, 0, rc * rc * rc * sizeof(float), blocks,
                                          0, NULL, NULL));
    if (clusters && r->mesh->num_sampling)
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->cluster_maj, CL_TRUE, 0,
                                          (size_t)r->mesh->num_sampling * sizeof(float), clusters, 0, NULL, NULL));
    if (cells)
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->grid_maj, CL_TRUE, 0,
                                          (size_t)r->grid_res * r->grid_res * r->grid_res * sizeof(float), cells, 0,
                                          NULL, NULL));
    if (global_majorant) *global_majorant = r->frame.global_majorant;
cleanup:
    return s;
}
