#include "render.h"

#include "camera.h"
#include "hull.h"
#include "majorant.h"
#include "clock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The frame fields the urm light grid depends on (besides the transfer
 * function), compared byte for byte. */
typedef struct light_key {
    float vol[6], grid[6], light_dir[3], urm_kappa;
    uint32_t u[8];
    float planes[CLVR_MAX_CLIP_PLANES * 4]; /* the shadow rays are clipped too */
} light_key;

struct clvr_renderer {
    clvr_cl *cl;
    const clvr_clustered *mesh;
    const clvr_accel *bvh;
    clvr_render_settings set;
    clvr_frame frame;
    int maj_chose;                /* the majorants were last set with the automatic grid's choice */
    int fine_skipped;             /* the automatic grid's fine level did not fit: its coarse grid alone */
    clvr_camera cam;
    clvr_majorants *maj;       /* cluster majorants and the macrocell grid */
    cl_program prog_render;
    cl_kernel k_render, k_light;
    cl_program prog_mpi;                  /* kernels/render_mpi.cl, built at the first MPI frame */
    cl_kernel k_mpi_record, k_mpi_shadow; /* MPI mode's two phases */
    cl_mem mpi_rec, mpi_pick, mpi_tau, mpi_counters;
    size_t mpi_npix;           /* pixels the MPI buffers hold */
    cl_mem frame_buf, cam_buf, tf_buf, accum, accum_sq, counters;
    cl_mem tf_prefix;          /* walk: prefix sums of the table's extinction (kernels/render_volume.h) */
    clvr_adjacency adj;        /* walk: face adjacency, built at the first frame settings that ask for walk */
    char adj_skipped[1024];    /* why its build did not fit (walk then renders as urm), or "" */
    cl_mem ctl;                /* per pixel, the sums of its controls (float4, kernels/pixel_cv.h) */
    cl_mem image;              /* the image clvr_renderer_read reads: means minus their control variates */
    cl_kernel k_cv;            /* kernels/render.cl: clvr_pixel_cv_image */
    cl_mem guides;             /* settings.guides: 8 floats per pixel (kernels/render.cl); else 8 floats in all,
                                * never written, so that no buffer is bound to two of the kernel's parameters */
    int guides_full;           /* guides holds a whole image's */
    int refine_full;           /* refine holds a whole image's */
    cl_mem light_buf;          /* with shadows: the light grid (clvr_light_nodes(frame.light_res)) */
    uint32_t light_nodes;      /* floats light_buf holds */
    int light_valid;           /* light_buf matches the frame and transfer function */
    light_key light_key;       /* the frame fields light_buf was made for */
    uint32_t tf_n;             /* entries in tf_buf (0: no transfer function yet) */
    uint32_t accum_w, accum_h; /* size of accum buffers */
    uint64_t frames;
    /* Adaptive sampling (settings.adaptive, clvr_renderer_refine). */
    cl_mem nsamp;              /* per pixel, its samples (frames and refine passes): numbers its random streams */
    cl_mem refine;             /* settings.adaptive: per pixel the refine passes' sums of samples and controls
                                * (2 float4); else 2 float4 in all, never written (no buffer is bound to two of
                                * the kernel's parameters) */
    cl_mem list;               /* the refine list, pixel indices row by row (at least one entry) */
    uint32_t list_n;           /* pixels in the list */
    int list_made;             /* the list belongs to this accumulation (reset with it): refine holds sums
                                * where nsamp > frames */
    uint64_t refine_passes;    /* each renders the list_n pixels of the one list */
    double select_s;           /* host seconds of making the list (read, choice, upload) */
    double kernel_s, last_frame_s, light_s;
    double image_s;            /* device time of the last clvr_renderer_read's image pass (clvr_pixel_cv_image) */
    size_t local[2];           /* work-group shape of the render kernel */
    /* auto on a mesh with cells other than tets (pilot_pick): which of its
     * two ways renders them, chosen by a pilot before the first frame after
     * a change of settings or transfer function (not of the camera). */
    int pick_on;               /* the settings ask for the pick (auto, a mesh with other cells, the adjacency) */
    int pick_pending;          /* the next first frame runs the pilot */
    uint32_t pick_base;        /* the estimator of the first way: walk (urm at other cells), urm without tets */
    int pick_ran;              /* a pilot ran since the last settings */
    clvr_render_pick pick;     /* its figures */
    double pilot_s;            /* host seconds of this accumulation's pilot (kernels included; not in kernel_s) */
    cl_mem pilot_list, pilot_out; /* its pixels and their two samples each */
    uint32_t pilot_n;          /* pixels they have room for */
};

static const char *const method_names[CLVR_RENDER_COUNT] = {"march", "track", "bins", "dda"};
static const char *const estimator_names[CLVR_ESTIMATOR_COUNT] = {"delta", "urm", "walk", "auto"};

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
    /* auto: walk (clvr_estimator_auto, docs/rendering.md); a mesh without
     * tets renders with urm. */
    s->estimator = CLVR_ESTIMATOR_AUTO;
    s->urm_steps = CLVR_URM_DEFAULT_STEPS;
    s->urm_kappa = CLVR_URM_DEFAULT_KAPPA;
    s->light_res = 0; /* clvr_light_res_for the mesh */
    s->width = s->height = 512;
    s->seed = 1;
    /* Low-discrepancy frames: the progressive image reaches a given error
     * in fewer frames (bench_render --converge); tests that need
     * independent frames ask for CLVR_SAMPLER_INDEPENDENT. */
    s->sampler = CLVR_SAMPLER_LD;
    s->pixel_cv = 1;
    s->adaptive = CLVR_ADAPTIVE_DEFAULT;
    s->shadows = 1;
    s->hull = 1;
    s->bins = 32;
    s->segments = 4;
    /* Automatic: 128^3 where its majorants are tighter than 32^3's by a
     * margin, else 32^3 (CLVR_MACROCELLS_FINE). 32^3 was measured best or
     * near-best on the default scene, amr-1M and post at densities 1 and 8
     * (bench/results/render), 128^3 on graded meshes (issue #19). */
    s->macrocells = 0;
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

/* The grid the elements are rasterized into: the settings' macrocells, or
 * for the automatic grid (0) the fine one it chooses from (its coarse one
 * where the fine one did not fit the device). */
static uint32_t grid_raster_res(const clvr_renderer *r, const clvr_render_settings *set)
{
    if (set->macrocells) return set->macrocells;
    return r->fine_skipped ? CLVR_MACROCELLS_FINE / CLVR_DDA_BLOCK : CLVR_MACROCELLS_FINE;
}

/* Brings the majorants up to date with the frame (host/pipeline/majorant.h):
 * the macrocell grid for the settings' resolution and the frame's domain,
 * then, once there is a transfer function, every majorant when it changed
 * (tf_changed), the grid was rebuilt or the automatic grid was switched on
 * or off. Keeps frame.global_majorant and sets frame.grid_res to the grid
 * in use. */
static clvr_status update_majorants(clvr_renderer *r, int tf_changed, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    int rebuilt = 0;
    r->frame.grid_res = grid_raster_res(r, &r->set); /* what the rasterizing kernel reads */
    CLVR_TRY(upload_frame(r, err));
    s = clvr_majorants_build_grid(r->maj, &r->frame, r->frame_buf, &rebuilt, err);
    if (!r->set.macrocells && !r->fine_skipped && (s == CLVR_ERR_DEVICE_MEMORY || s == CLVR_ERR_OVERFLOW)) {
        /* The automatic grid's fine level (25 MB at 128^3, 17 MB of it in
         * one buffer) does not fit this device: its coarse grid, which it
         * would choose on most meshes anyway (clvr_renderer_macrocells
         * says 32, its means 0). */
        r->fine_skipped = 1;
        *err = (clvr_error){0};
        r->frame.grid_res = grid_raster_res(r, &r->set);
        CLVR_TRY(upload_frame(r, err));
        s = clvr_majorants_build_grid(r->maj, &r->frame, r->frame_buf, &rebuilt, err);
    }
    if (s != CLVR_OK) goto cleanup;
    const int choose = !r->set.macrocells && !r->fine_skipped;
    if (r->tf_n && (tf_changed || rebuilt || choose != r->maj_chose)) {
        CLVR_TRY(clvr_majorants_set_tf(r->maj, r->tf_buf, r->frame_buf, choose, &r->frame.global_majorant, err));
        r->maj_chose = choose;
    }
    r->frame.grid_res = clvr_majorants_grid(r->maj, NULL, NULL);
    CLVR_TRY(upload_frame(r, err));
cleanup:
    return s;
}

/* A change of settings, camera or transfer function: the accumulation
 * starts again, and so does the refine list. */
static void restart(clvr_renderer *r)
{
    r->frames = 0;
    r->kernel_s = 0.0;
    r->image_s = 0.0;
    r->list_made = 0;
    r->list_n = 0;
    r->refine_passes = 0;
    r->select_s = 0.0;
    r->pilot_s = 0.0;
}

static clvr_status alloc_image(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = r->cl;
    size_t npix = (size_t)r->set.width * r->set.height;
    const int refine_full = r->set.adaptive > 0.0f;
    if (r->accum && r->accum_w == r->set.width && r->accum_h == r->set.height && r->guides &&
        r->guides_full == !!r->set.guides && r->refine_full == refine_full)
        return CLVR_OK;
    clvr_cl_release(cl, &r->guides);
    clvr_cl_release(cl, &r->accum);
    clvr_cl_release(cl, &r->accum_sq);
    clvr_cl_release(cl, &r->counters);
    clvr_cl_release(cl, &r->ctl);
    clvr_cl_release(cl, &r->image);
    clvr_cl_release(cl, &r->nsamp);
    clvr_cl_release(cl, &r->refine);
    clvr_cl_release(cl, &r->list);
    r->accum_w = r->accum_h = 0;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 4 * sizeof(float), NULL, "image accumulator", &r->accum, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 4 * sizeof(float), NULL, "image second moments",
                            &r->accum_sq, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 3 * sizeof(cl_uint), NULL, "ray counters", &r->counters,
                            err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 4 * sizeof(float), NULL, "pixel controls", &r->ctl, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * 4 * sizeof(float), NULL, "image", &r->image, err));
    r->guides_full = !!r->set.guides;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (r->guides_full ? npix : 1) * 8 * sizeof(float), NULL,
                            "denoiser guides", &r->guides, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, npix * sizeof(cl_uint), NULL, "pixel sample counts", &r->nsamp,
                            err));
    r->refine_full = refine_full;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (refine_full ? npix : 1) * 8 * sizeof(float), NULL,
                            "adaptive sampling sums", &r->refine, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, sizeof(cl_uint), NULL, "adaptive sampling list", &r->list, err));
    r->accum_w = r->set.width;
    r->accum_h = r->set.height;
cleanup:
    return s;
}

uint32_t clvr_estimator_auto(void) { return CLVR_ESTIMATOR_WALK; }

uint32_t clvr_light_res_for(uint64_t elements)
{
    uint32_t r = CLVR_URM_DEFAULT_LIGHT_RES;
    while (r > 8u && (uint64_t)clvr_light_nodes(r) > 2u * elements) --r;
    return r;
}

void clvr_light_space(const float lo[3], const float hi[3], const float ldir[3], uint32_t r, float out[4][4])
{
    const double L[3] = {ldir[0], ldir[1], ldir[2]};
    int k = 0;
    for (int i = 1; i < 3; ++i)
        if (fabs(L[i]) < fabs(L[k])) k = i;
    const double ax[3] = {k == 0, k == 1, k == 2};
    double e1[3] = {L[1] * ax[2] - L[2] * ax[1], L[2] * ax[0] - L[0] * ax[2], L[0] * ax[1] - L[1] * ax[0]};
    const double n1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int i = 0; i < 3; ++i) e1[i] /= n1;
    const double e2[3] = {L[1] * e1[2] - L[2] * e1[1], L[2] * e1[0] - L[0] * e1[2], L[0] * e1[1] - L[1] * e1[0]};
    const double *axes[3] = {e1, e2, L};
    double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; ++c) {
        const double p[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
        for (int a = 0; a < 3; ++a) {
            const double d = p[0] * axes[a][0] + p[1] * axes[a][1] + p[2] * axes[a][2];
            mn[a] = fmin(mn[a], d);
            mx[a] = fmax(mx[a], d);
        }
    }
    for (int a = 0; a < 3; ++a)
        for (int i = 0; i < 3; ++i) out[a][i] = (float)axes[a][i];
    out[0][3] = (float)mn[0];
    out[1][3] = (float)mn[1];
    out[2][3] = (float)mx[2];
    /* A flat extent (a flat box seen edge-on) must not divide by 0. */
    const uint32_t n = clvr_light_depth(r);
    out[3][0] = (float)fmax((mx[0] - mn[0]) / r, 1e-30);
    out[3][1] = (float)fmax((mx[1] - mn[1]) / r, 1e-30);
    out[3][2] = (float)fmax((mx[2] - mn[2]) / (n > 1u ? n - 1u : 1u), 1e-30);
    out[3][3] = 0.0f;
}

clvr_status clvr_renderer_set_settings(clvr_renderer *r, const clvr_render_settings *set, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (set->method >= CLVR_RENDER_COUNT || set->estimator >= CLVR_ESTIMATOR_COUNT || set->sampler > CLVR_SAMPLER_LD ||
        set->pixel_filter > CLVR_PIXEL_POINT ||
        set->width == 0 || set->height == 0 || set->bins == 0 || set->bins > CLVR_RENDER_MAX_BINS ||
        set->segments == 0 || set->urm_steps == 0 || !(set->urm_kappa > 0.0f) ||
        set->light_res > CLVR_URM_LIGHT_RES)
        return clvr_error_set(err, CLVR_ERR_USAGE, "invalid render settings (method %u, estimator %u, sampler %u, "
                              "pixel filter %u, %ux%u, %u bins, %u segments, urm steps %u, kappa %g, "
                              "light grid %u: 0..%u)", set->method,
                              set->estimator, set->sampler, set->pixel_filter, set->width, set->height, set->bins,
                              set->segments, set->urm_steps, (double)set->urm_kappa, set->light_res,
                              CLVR_URM_LIGHT_RES);
    if (!(set->adaptive >= 0.0f) || !isfinite(set->adaptive))
        return clvr_error_set(err, CLVR_ERR_USAGE, "adaptive sampling threshold %g: expected 0 (off) or a finite "
                              "number > 0 (default %g)", (double)set->adaptive, (double)CLVR_ADAPTIVE_DEFAULT);
    uint64_t cells = (uint64_t)set->macrocells * set->macrocells * set->macrocells; /* 0: automatic */
    if (cells > (1ull << 31))
        return clvr_error_set(err, CLVR_ERR_USAGE, "--macrocells %u gives %llu cells; use at most 1290",
                              set->macrocells, (unsigned long long)cells);
    r->set = *set;
    const clvr_clustered *m = r->mesh;
    clvr_frame *f = &r->frame;
    const int clip = set->clip_lo[0] <= set->clip_hi[0], grid = set->grid_lo[0] <= set->grid_hi[0];
    for (int k = 0; k < 3; ++k) {
        f->vol_lo[k] = clip ? set->clip_lo[k] : m->bounds.lo[k];
        f->vol_hi[k] = clip ? set->clip_hi[k] : m->bounds.hi[k];
        f->grid_lo[k] = grid ? set->grid_lo[k] : m->bounds.lo[k];
        f->grid_hi[k] = grid ? set->grid_hi[k] : m->bounds.hi[k];
        f->background[k] = set->background[k];
    }
    if (set->num_clip_planes > CLVR_MAX_CLIP_PLANES)
        return clvr_error_set(err, CLVR_ERR_USAGE, "%u clip planes; at most %u", set->num_clip_planes,
                              CLVR_MAX_CLIP_PLANES);
    memset(f->clip_planes, 0, sizeof f->clip_planes);
    f->num_clip_planes = set->num_clip_planes;
    for (uint32_t i = 0; i < set->num_clip_planes; ++i) {
        const float *q = set->clip_planes[i];
        float n = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (!(n > 0.0f) || !isfinite(n) || !isfinite(q[3]))
            return clvr_error_set(err, CLVR_ERR_USAGE, "clip plane %u (%g, %g, %g, %g): expected a finite, nonzero "
                                  "normal", i + 1, (double)q[0], (double)q[1], (double)q[2], (double)q[3]);
        for (int k = 0; k < 4; ++k) f->clip_planes[i][k] = q[k] / n;
    }
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
    f->estimator =
        set->estimator == CLVR_ESTIMATOR_AUTO ? clvr_estimator_auto() : set->estimator;
    if (f->estimator == CLVR_ESTIMATOR_WALK) {
        /* The walk needs the face adjacency; auto walks tets only (the
         * walk through other cells, clvr_walk_cell, reached 2% sooner than
         * urm on the notch's coarse hexes and later on finer CFD hexes:
         * bench/results/render-converge/2026-11-30-s44-cell-walk.md), so
         * a mesh without tets renders with urm then. */
        /* (one curve: tets as collapsed hexes are walked as tets, kernels/render_volume.h clvr_walk_load) */
        int tets = m->collapsed[CLVR_CELL_TET] > 0, others = 0;
        for (uint64_t i = 0; i < m->num_instances; ++i) {
            tets |= m->host_instances[i].type == CLVR_CELL_TET;
            others |= m->host_instances[i].type != CLVR_CELL_TET;
        }
        f->walk_cells = set->estimator == CLVR_ESTIMATOR_WALK;
        /* auto on a mesh with other cells: a pilot before the first frame
         * picks the walk through them or urm there (pilot_pick), so it needs
         * the adjacency whatever the pick. */
        const int pick = set->estimator == CLVR_ESTIMATOR_AUTO && others && set->method != CLVR_RENDER_MARCH;
        const int walked = f->walk_cells || tets || pick;
        if (walked && !r->adj.adj && !r->adj_skipped[0]) {
            /* Like the hull, the adjacency only speeds convergence: where
             * its buffers do not fit (a mesh split into pieces below the
             * device's largest allocation, docs/large-meshes.md) the frames
             * are urm's, the same image. */
            s = clvr_adjacency_build(r->cl, &r->bvh->kernels, m, &r->adj, err);
            if (s == CLVR_ERR_DEVICE_MEMORY || s == CLVR_ERR_OVERFLOW) {
                snprintf(r->adj_skipped, sizeof r->adj_skipped, "%s", err->msg[0] ? err->msg : "no room");
                *err = (clvr_error){0};
                s = CLVR_OK;
            }
            if (s != CLVR_OK) goto cleanup;
        }
        if (!walked || !r->adj.adj) f->estimator = CLVR_ESTIMATOR_URM;
        r->pick_on = r->pick_pending = pick && r->adj.adj;
        if (r->pick_on && !tets) f->estimator = CLVR_ESTIMATOR_URM;
        r->pick_base = f->estimator;
    } else {
        r->pick_on = r->pick_pending = 0;
    }
    r->pick_ran = 0;
    f->num_instances = (clvr_u32)m->num_instances;
    f->urm_steps = set->urm_steps;
    f->urm_kappa = set->urm_kappa;
    f->seed_lo = (clvr_u32)set->seed;
    f->seed_hi = (clvr_u32)(set->seed >> 32);
    f->shadows = set->shadows ? 1u : 0u;
    f->sampler = set->sampler;
    f->pixel_filter = set->pixel_filter;
    f->guides = set->guides ? 1u : 0u;
    f->bins = set->bins;
    f->segments = set->segments;
    f->leaf_size = m->leaf_size;
    f->tlas_root = r->bvh->tlas_root;
    {
        const clvr_hull *hl = &r->bvh->hull;
        f->hull_faces = set->hull && hl->kept ? hl->num_faces : 0u;
    }
    f->light_res = set->light_res ? set->light_res : clvr_light_res_for(m->num_elements);
    clvr_light_space(f->grid_lo, f->grid_hi, f->light_dir, f->light_res, f->light_space);
    {
        /* The light grid depends on these fields only (and on the transfer
         * function): a new image size, exposure, sampler or a shadows toggle
         * keeps it, so the viewer does not pay for it again. */
        light_key k;
        memset(&k, 0, sizeof k);
        memcpy(k.vol, f->vol_lo, sizeof f->vol_lo);
        memcpy(k.vol + 3, f->vol_hi, sizeof f->vol_hi);
        memcpy(k.grid, f->grid_lo, sizeof f->grid_lo);
        memcpy(k.grid + 3, f->grid_hi, sizeof f->grid_hi);
        memcpy(k.light_dir, f->light_dir, sizeof f->light_dir);
        k.urm_kappa = f->urm_kappa;
        k.u[0] = f->urm_steps; k.u[1] = f->seed_lo; k.u[2] = f->seed_hi; k.u[3] = f->method;
        k.u[4] = set->macrocells; k.u[5] = f->bins; k.u[6] = f->segments; k.u[7] = f->light_res;
        memcpy(k.planes, f->clip_planes, sizeof k.planes);
        if (memcmp(&k, &r->light_key, sizeof k) != 0) r->light_valid = 0;
        r->light_key = k;
    }
    if (r->light_nodes != clvr_light_nodes(f->light_res)) {
        /* Sized to the grid in use (1.8 MB at the default 96 x 96 x 48 on
         * meshes of 221k elements or more, 98 KB on 13k tets): bound to
         * every frame, with shadows or not. A new size means a new grid
         * (light_res is in the key). */
        clvr_cl_release(r->cl, &r->light_buf);
        r->light_nodes = 0;
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_WRITE, (size_t)clvr_light_nodes(f->light_res) * sizeof(float),
                                NULL, "light grid", &r->light_buf, err));
        r->light_nodes = clvr_light_nodes(f->light_res);
    }
    CLVR_TRY(alloc_image(r, err));
    /* A new grid resolution or domain needs the elements rasterized again. */
    CLVR_TRY(update_majorants(r, 0, err));
    restart(r);
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
    CLVR_TRY(clvr_majorants_create(cl, mesh, &r->maj, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_render, "clvr_render_frame", &r->k_render, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_render, "clvr_light_grid", &r->k_light, err));
    CLVR_TRY(clvr_cl_kernel(r->prog_render, "clvr_pixel_cv_image", &r->k_cv, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, sizeof(clvr_frame), NULL, "frame parameters", &r->frame_buf, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, sizeof(clvr_camera), NULL, "camera", &r->cam_buf, err));
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
    if (r->k_render) clReleaseKernel(r->k_render);
    if (r->k_light) clReleaseKernel(r->k_light);
    if (r->k_cv) clReleaseKernel(r->k_cv);
    if (r->k_mpi_record) clReleaseKernel(r->k_mpi_record);
    if (r->k_mpi_shadow) clReleaseKernel(r->k_mpi_shadow);
    clvr_cl_release(r->cl, &r->mpi_rec);
    clvr_cl_release(r->cl, &r->mpi_pick);
    clvr_cl_release(r->cl, &r->mpi_tau);
    clvr_cl_release(r->cl, &r->mpi_counters);
    clvr_cl_release(r->cl, &r->light_buf);
    clvr_adjacency_release(r->cl, &r->adj);
    if (r->prog_render) clReleaseProgram(r->prog_render);
    if (r->prog_mpi) clReleaseProgram(r->prog_mpi);
    clvr_majorants_destroy(r->maj);
    cl_mem *bufs[] = {&r->frame_buf, &r->cam_buf, &r->tf_buf, &r->accum,  &r->accum_sq, &r->counters, &r->guides,
                      &r->ctl,       &r->image,   &r->tf_prefix, &r->nsamp, &r->refine, &r->list,
                      &r->pilot_list, &r->pilot_out};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; ++i) clvr_cl_release(r->cl, bufs[i]);
    free(r);
}

clvr_status clvr_renderer_set_camera(clvr_renderer *r, const clvr_camera *cam, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    r->cam = *cam;
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->cam_buf, CL_TRUE, 0, sizeof r->cam, &r->cam, 0, NULL, NULL));
    restart(r);
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
        clvr_cl_release(r->cl, &r->tf_prefix);
        r->tf_n = 0;
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_ONLY, (size_t)n * 4 * sizeof(float), NULL, "transfer function",
                                &r->tf_buf, err));
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_ONLY, (size_t)n * sizeof(float), NULL,
                                "transfer function prefix sums", &r->tf_prefix, err));
    }
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->tf_buf, CL_TRUE, 0, (size_t)n * 4 * sizeof(float), rgba, 0,
                                       NULL, NULL));
    {
        /* P[i]: the integral of the table's extinction (w, before the
         * density) from entry 0 to entry i, in entries (the trapezoids of
         * the linear interpolation), summed in double. */
        float *pre = malloc((size_t)n * sizeof *pre);
        if (!pre) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of host memory for the transfer function");
            goto cleanup;
        }
        double acc = 0.0;
        pre[0] = 0.0f;
        for (uint32_t i = 1; i < n; ++i) {
            acc += 0.5 * ((double)rgba[4 * (i - 1) + 3] + (double)rgba[4 * i + 3]);
            pre[i] = (float)acc;
        }
        cl_int rc = clEnqueueWriteBuffer(r->cl->queue, r->tf_prefix, CL_TRUE, 0, (size_t)n * sizeof(float), pre, 0,
                                         NULL, NULL);
        free(pre);
        CLVR_CL_CHECK(rc);
    }
    r->tf_n = n;
    r->frame.tf_size = n;
    r->frame.tf_lo = lo;
    r->frame.tf_hi = hi;
    r->frame.density = density;
    CLVR_TRY(update_majorants(r, 1, err));
    r->light_valid = 0;
    r->pick_pending = r->pick_on; /* new majorants, new costs */
    restart(r);
cleanup:
    return s;
}

/* The device arrays of CLVR_VOLUME_ARRAYS, in its order. */
typedef struct volume_bufs {
#define CLVR_VOLUME_HOST(T, name) cl_mem name;
    CLVR_VOLUME_ARRAYS(CLVR_VOLUME_HOST)
#undef CLVR_VOLUME_HOST
} volume_bufs;

static volume_bufs volume_of(const clvr_renderer *r)
{
    const clvr_clustered *m = r->mesh;
    const clvr_accel *b = r->bvh;
    const clvr_majorant_arrays maj = clvr_majorants_arrays(r->maj);
    clvr_clustered_pieces pc; /* the split arrays piece by piece (clvr_instance.piece) */
    cl_mem eb[CLVR_MAX_SPLITS];
    clvr_clustered_get_pieces(m, &pc);
    clvr_accel_get_ebox_pieces(m, b, eb);
    return (volume_bufs){.tf = r->tf_buf, .tf_prefix = r->tf_prefix, .vertices = pc.vertices[0], .idx16 = pc.idx16[0], .idx32 = pc.idx32[0],
                         .instances = m->instances, .tlas = b->two_level.tlas, .blas = b->two_level.blas,
                         .grid = maj.cells, .blocks = maj.blocks, .sampling_bvh = b->sampling_nodes,
                         .sampling = m->sampling, .cluster_majorants = maj.clusters, .light = r->light_buf,
                         .ebox = eb[0], .entry_grids = b->two_level.entry_grids,
                         .entry_cells = b->two_level.entry_cells, .hull_bvh = b->hull.nodes ? b->hull.nodes : r->tf_buf,
                         .hull = b->hull.faces ? b->hull.faces : r->tf_buf,
                         .face_first = r->adj.face_first ? r->adj.face_first : r->tf_buf,
                         .adj = r->adj.adj ? r->adj.adj : r->tf_buf, .vertices1 = pc.vertices[1], .vertices2 = pc.vertices[2],
                         .vertices3 = pc.vertices[3], .idx16_1 = pc.idx16[1], .idx16_2 = pc.idx16[2],
                         .idx16_3 = pc.idx16[3], .idx32_1 = pc.idx32[1], .idx32_2 = pc.idx32[2],
                         .idx32_3 = pc.idx32[3], .ebox1 = eb[1], .ebox2 = eb[2], .ebox3 = eb[3]};
}
#define CLVR_VOLUME_ARG(T, name) CLVR_ARG(vol.name),

/* The light grid, once per transfer function, light and settings (urm with
 * shadows); its time counts as render time (part of the first frame's cost).
 * Expects the frame uploaded. */
static clvr_status ensure_light(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_event evt = NULL;
    volume_bufs vol = volume_of(r);
    if (!r->light_valid && r->frame.shadows && r->frame.estimator != CLVR_ESTIMATOR_DELTA &&
        r->frame.method != CLVR_RENDER_MARCH) {
        /* One work item per column (kernels/render_volume.h,
         * clvr_light_column): 9216 at the default 96 x 96, enough lanes for
         * a GPU; a CPU's work-groups take 64 columns each. */
        const cl_uint n = r->frame.light_res;
        const size_t local[2] = {8, 8};
        CLVR_TRY(CLVR_CL_ARGS(r->k_light, err, CLVR_ARG(r->frame_buf), CLVR_ARG(r->cam_buf),
                              CLVR_VOLUME_ARRAYS(CLVR_VOLUME_ARG) CLVR_ARG(r->light_buf)));
        CLVR_TRY(clvr_cl_run2d(r->cl, r->k_light, n, n, local, &evt, err));
        CLVR_CL_CHECK(clWaitForEvents(1, &evt));
        r->light_s = clvr_cl_event_seconds(evt);
        r->kernel_s += r->light_s;
        clReleaseEvent(evt);
        evt = NULL;
        r->light_valid = 1;
    }
cleanup:
    if (evt) clReleaseEvent(evt);
    return s;
}

uint64_t clvr_renderer_frames(const clvr_renderer *r) { return r->frames; }

/* Binds kernels/render.cl's parameters (frame, camera, the arrays, the
 * outputs; refine and list as given) and enqueues one pass: a frame over
 * every pixel (pass_pixels 0) or one work item per list entry. Expects the
 * frame on the device. */
static clvr_status enqueue_pass(clvr_renderer *r, uint32_t pass_pixels, cl_mem refine, cl_mem list, cl_event *evt,
                                clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_kernel k = r->k_render;
    volume_bufs vol = volume_of(r);
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(r->frame_buf), CLVR_ARG(r->cam_buf), CLVR_VOLUME_ARRAYS(CLVR_VOLUME_ARG)
                          CLVR_ARG(r->accum), CLVR_ARG(r->accum_sq), CLVR_ARG(r->ctl), CLVR_ARG(r->counters),
                          CLVR_ARG(r->guides), CLVR_ARG(r->nsamp), CLVR_ARG(refine), CLVR_ARG(list)));
    if (pass_pixels) {
        const size_t wg = r->local[0] * r->local[1];
        const size_t global = (pass_pixels + wg - 1) / wg * wg;
        CLVR_CL_CHECK(clEnqueueNDRangeKernel(r->cl->queue, k, 1, NULL, &global, &wg, 0, NULL, evt));
    } else {
        CLVR_TRY(clvr_cl_run2d(r->cl, k, r->set.width, r->set.height, r->local, evt, err));
    }
cleanup:
    return s;
}

/* One pass of the render kernel: a frame over every pixel (pass_pixels 0)
 * or a refine pass over the list. */
static clvr_status render_pass(clvr_renderer *r, uint32_t pass_pixels, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_event evt = NULL;
    if (!r->tf_n) return clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr_renderer_frame before a transfer function");
    r->frame.frame_index = (clvr_u32)r->frames;
    r->frame.pass_pixels = pass_pixels;
    /* The pixels the frame traces: a margin of 3 around those whose rays
     * can meet the clip box, 2 for the pixel control variates' neighbours
     * (kernels/render.cl) and 1 for rounding, so that the image is the one
     * every pixel traced would give, bit for bit. */
    clvr_camera_live(&r->cam, r->frame.vol_lo, r->frame.vol_hi, 3u, r->frame.live, r->frame.live_edges);
    if (r->set.trace_all) r->frame.live[2] = 0u;
    CLVR_TRY(upload_frame(r, err));
    CLVR_TRY(ensure_light(r, err));
    CLVR_TRY(enqueue_pass(r, pass_pixels, r->refine, r->list, &evt, err));
    CLVR_CL_CHECK(clWaitForEvents(1, &evt));
    /* A frame is its full pass and its refine pass (adaptive sampling): a
     * refine pass adds to the frame's time. (Until session 46 it replaced
     * it, and bench_render's table timed only the refine pass, the few
     * pixels adaptive sampling picked: 0.8 against 34 ms a frame on the
     * notch.) */
    const double t = clvr_cl_event_seconds(evt);
    r->last_frame_s = pass_pixels ? r->last_frame_s + t : t;
    r->kernel_s += t;
cleanup:
    if (evt) clReleaseEvent(evt);
    r->frame.pass_pixels = 0;
    return s;
}

double clvr_pilot_var(const float *pairs, uint32_t n, double *sumsq)
{
    double v = 0.0, v2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double p = 0.0;
        for (size_t k = 0; k < 3; ++k) {
            const double d = (double)pairs[8 * i + k] - (double)pairs[8 * i + 4 + k];
            p += isfinite(d) ? 0.5 * d * d : 0.0;
        }
        v += p;
        v2 += p * p;
    }
    if (sumsq) *sumsq = v2;
    return v;
}

/* The pilot's pixels: up to n whose centre's ray meets the frame's volume
 * box (the others cost either way next to nothing and draw no variance),
 * spread over the image: row-major positions of the golden-ratio sequence
 * from *next on (advanced past the candidates used; 64 n candidates at
 * most, so a volume on less than 1/64 of the image gets fewer), each
 * listed twice in a row (its two samples). Returns how many pixels. */
static uint32_t pilot_pixels(const clvr_camera *cam, const clvr_frame *f, uint32_t n, uint64_t *next, uint32_t *list)
{
    const uint64_t npix = (uint64_t)f->width * f->height, end = *next + 64u * (uint64_t)n;
    const double phi = 0.6180339887498949;
    uint32_t k = 0;
    for (; *next < end && k < n; ++*next) {
        uint64_t p = (uint64_t)(fmod(0.5 + phi * (double)*next, 1.0) * (double)npix);
        if (p >= npix) p = npix - 1;
        float o[3], d[3];
        clvr_camera_ray(cam, (float)(p % f->width) + 0.5f, (float)(p / f->width) + 0.5f, o, d);
        if (clvr_ray_hits_box(o, d, f->vol_lo, f->vol_hi)) list[2 * k] = list[2 * k + 1] = (uint32_t)p, ++k;
    }
    return k;
}

/* The frame of the pilot's way c (0: the tet walk and urm at other cells,
 * or urm on a mesh without tets; 1: the walk through every cell). */
static void pilot_way(const clvr_renderer *r, int c, clvr_frame *f)
{
    f->estimator = c ? CLVR_ESTIMATOR_WALK : r->pick_base;
    f->walk_cells = (clvr_u32)c;
}

/* One round of the pilot: two samples of each way in the n pixels of list
 * (each listed twice), one launch per way, both queued before waiting (the
 * in-order queue writes each way's frame after the previous launch has
 * read its own). Adds to var[way] and var2[way] the sums of clvr_pilot_var and to
 * work[way] the extinction lookups and cell steps of the way's samples
 * (the kernel's sample counter, in each sample's w). */
static clvr_status pilot_round(clvr_renderer *r, const uint32_t *list, uint32_t n, float *out, double var[2],
                               double var2[2], double work[2], clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_frame fw[2];
    if (n > r->pilot_n) {
        clvr_cl_release(r->cl, &r->pilot_list);
        clvr_cl_release(r->cl, &r->pilot_out);
        r->pilot_n = 0;
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_ONLY, (size_t)n * 2 * sizeof(cl_uint), NULL,
                                "estimator pilot pixels", &r->pilot_list, err));
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_WRITE, (size_t)n * 16 * sizeof(float), NULL,
                                "estimator pilot samples", &r->pilot_out, err));
        r->pilot_n = n;
    }
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->pilot_list, CL_FALSE, 0, (size_t)n * 2 * sizeof(cl_uint), list,
                                       0, NULL, NULL));
    for (int c = 0; c < 2; ++c) {
        fw[c] = r->frame;
        pilot_way(r, c, &fw[c]);
        fw[c].pass_pixels = 2 * n;
        fw[c].pilot = (clvr_u32)c + 1u;
        CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->frame_buf, CL_FALSE, 0, sizeof fw[c], &fw[c], 0, NULL,
                                           NULL));
        CLVR_TRY(enqueue_pass(r, 2 * n, r->pilot_out, r->pilot_list, NULL, err));
    }
    CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->pilot_out, CL_TRUE, 0, (size_t)n * 16 * sizeof(float), out, 0,
                                      NULL, NULL));
    for (int c = 0; c < 2; ++c) {
        const float *o = out + (size_t)c * n * 8;
        double sq;
        var[c] += clvr_pilot_var(o, n, &sq);
        var2[c] += sq;
        for (size_t i = 0; i < 2 * (size_t)n; ++i) work[c] += o[4 * i + 3];
    }
cleanup:
    return s;
}

/* The two ways' efficiencies (lower is better) after n pilot pixels:
 * the mean variance of a sample times the work of a sample (a walk step
 * weighted CLVR_PILOT_WALK_STEP). A pixel's variance from two samples is
 * heavy-tailed (one pixel in 64 held most of the walk's sum on the notch),
 * so the two means count as one, their pooled mean, unless they differ by
 * more than 2 standard errors of the difference: then work alone decides. */
static void pilot_efficiency(const double var[2], const double var2[2], const double work[2], uint32_t n,
                             double e[2])
{
    double m[2], se2 = 0.0;
    for (int c = 0; c < 2; ++c) {
        m[c] = var[c] / n;
        const double s2 = n > 1 ? (var2[c] - n * m[c] * m[c]) / (n - 1) : 0.0;
        se2 += (s2 > 0.0 ? s2 : 0.0) / n;
    }
    if ((m[0] - m[1]) * (m[0] - m[1]) <= 4.0 * se2) m[0] = m[1] = 0.5 * (m[0] + m[1]);
    e[0] = m[0] * work[0];
    e[1] = m[1] * work[1] * CLVR_PILOT_WALK_STEP;
}

/* auto on a mesh with cells other than tets: the walk through those cells
 * (clvr_walk_cell) reached 2% relative RMSE sooner than urm on the notch's
 * coarse hexes and later on finer CFD hexes, by up to 2x either way
 * (bench/results/render-converge/2026-11-30-s44-cell-walk.md), and no rule
 * by mesh size fitted both. So the frame itself is measured, before the
 * first: two samples of each way (streams the frames never draw) in pixels
 * that see the volume, and the way with the smaller variance x cost per
 * sample renders the frames (efficiency, Veach 1997 section 2.5.2: after a
 * time T the error is about sqrt(var x cost per sample / T);
 * pilot_efficiency). The cost is counted, not timed, so that the same
 * settings give the same image on every run: the samples' extinction
 * lookups and cell steps, a walk's weighted by CLVR_PILOT_WALK_STEP.
 * Rounds of 64, 64, 128, ... pixels
 * until one way is 1.3x the other's efficiency or 1/256 of the image is
 * spent (at least 256 pixels, at most 65536). Both ways are unbiased and
 * the choice does not depend on the frames' samples, so the image's
 * expected value does not depend on it either. Once per change of
 * settings or transfer function. */
static clvr_status pilot_pick(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const double t0 = clvr_clock_monotonic_s();
    const uint64_t npix = (uint64_t)r->set.width * r->set.height;
    uint64_t most = npix / 256u, next = 0;
    if (most < 256u) most = 256u;
    if (most > 65536u) most = 65536u;
    uint32_t *list = malloc((size_t)most * 2 * sizeof *list);
    float *out = malloc((size_t)most * 16 * sizeof(float));
    double var[2] = {0.0, 0.0}, var2[2] = {0.0, 0.0}, work[2] = {0.0, 0.0}, e[2] = {0.0, 0.0};
    uint32_t done = 0, round = 64;
    r->pick_pending = 0;
    if (!list || !out) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of host memory for the estimator pilot (%u pixels)",
                           (unsigned)most);
        goto cleanup;
    }
    for (;;) {
        const uint32_t n = pilot_pixels(&r->cam, &r->frame, round, &next, list);
        if (n == 0) break; /* no more of the volume in view */
        CLVR_TRY(pilot_round(r, list, n, out, var, var2, work, err));
        done += n;
        pilot_efficiency(var, var2, work, done, e);
        if (done >= most || e[0] > 1.3 * e[1] || e[1] > 1.3 * e[0]) break;
        round = done < most - done ? done : (uint32_t)(most - done);
    }
    if (done) {
        const int c = e[1] < e[0];
        r->pick = (clvr_render_pick){.pixels = done, .var = {var[0] / done, var[1] / done},
                                     .work = {work[0] / (2.0 * done), work[1] / (2.0 * done)},
                                     .walk_cells = (uint32_t)c};
        pilot_way(r, c, &r->frame);
        r->pick_ran = 1;
    }
cleanup:
    /* The host's frame goes back up with the next pass (upload_frame). */
    free(list);
    free(out);
    r->pilot_s += clvr_clock_monotonic_s() - t0;
    return s;
}

clvr_status clvr_renderer_full_frame(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (r->frames == 0 && r->pick_pending) {
        /* The light grid first: the frames need it whatever the pick, and
         * kernel_s counts it. */
        CLVR_TRY(upload_frame(r, err));
        CLVR_TRY(ensure_light(r, err));
        CLVR_TRY(pilot_pick(r, err));
    }
    CLVR_TRY(render_pass(r, 0, err));
    r->frames++;
cleanup:
    return s;
}

int clvr_adaptive_pick(const float *sum, float inv_n, uint32_t w, uint32_t h, float threshold, uint32_t *list,
                       uint32_t *count)
{
    const size_t npix = (size_t)w * h;
    double *lum = malloc(npix * sizeof *lum);
    if (!lum) return 1;
    /* S and K: the luminance summed over the pixels whose rays met the
     * medium (alpha > 0), and their number. */
    double S = 0.0, K = 0.0;
    for (size_t i = 0; i < npix; ++i) {
        const float *q = sum + 4 * i;
        lum[i] = ((double)q[0] + (double)q[1] + (double)q[2]) * (double)inv_n / 3.0;
        if (q[3] > 0.0f && isfinite(lum[i])) {
            S += lum[i];
            K += 1.0;
        }
    }
    uint32_t n = 0;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const size_t p = (size_t)y * w + x;
            /* The scale without the pixel's own value: the mean over the
             * other pixels that met the medium. */
            const int own = sum[4 * p + 3] > 0.0f && isfinite(lum[p]);
            const double k = K - own, scale = k > 0.0 ? (S - (own ? lum[p] : 0.0)) / k : 0.0;
            if (!(scale > 0.0)) continue;
            double m = 0.0, m2 = 0.0;
            int c = 0;
            for (int oy = -1; oy <= 1; ++oy)
                for (int ox = -1; ox <= 1; ++ox) {
                    const int xx = (int)x + ox, yy = (int)y + oy;
                    if ((ox == 0 && oy == 0) || xx < 0 || yy < 0 || xx >= (int)w || yy >= (int)h) continue;
                    const double v = lum[(size_t)yy * w + (size_t)xx];
                    if (!isfinite(v)) continue;
                    m += v;
                    m2 += v * v;
                    ++c;
                }
            if (c < 2) continue;
            m /= c;
            const double var = m2 / c - m * m;
            if (var > (double)threshold * threshold * scale * scale) list[n++] = (uint32_t)p;
        }
    free(lum);
    *count = n;
    return 0;
}

/* The refine list from the frames so far (once per accumulation). */
static clvr_status make_list(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const double t0 = clvr_clock_monotonic_s();
    const uint32_t w = r->set.width, h = r->set.height;
    const size_t npix = (size_t)w * h;
    float *sum = malloc(npix * 4 * sizeof(float));
    uint32_t *list = malloc(npix * sizeof(uint32_t)), n = 0;
    if (!sum || !list) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of host memory for the adaptive sampling list (%ux%u)", w, h);
        goto cleanup;
    }
    CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->accum, CL_TRUE, 0, npix * 4 * sizeof(float), sum, 0, NULL,
                                      NULL));
    if (clvr_adaptive_pick(sum, 1.0f / (float)r->frames, w, h, r->set.adaptive, list, &n)) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of host memory for the adaptive sampling list (%ux%u)", w, h);
        goto cleanup;
    }
    clvr_cl_release(r->cl, &r->list);
    CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_ONLY, (n ? n : 1) * sizeof(cl_uint), NULL, "adaptive sampling list",
                            &r->list, err));
    if (n)
        CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->list, CL_TRUE, 0, n * sizeof(cl_uint), list, 0, NULL,
                                           NULL));
    /* No fill: a pixel's first refine sample overwrites its sums
     * (clvr_render_frame), and only pixels with more samples than frames
     * are read (a 2048^2 image's 134 MB, first touched by a fill, took
     * 0.25 s on PoCL). */
    r->list_n = n;
    r->list_made = 1;
cleanup:
    free(sum);
    free(list);
    r->select_s += clvr_clock_monotonic_s() - t0;
    return s;
}

clvr_status clvr_renderer_refine(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (!(r->set.adaptive > 0.0f)) return CLVR_OK;
    if (r->frames == 0) return clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr_renderer_refine before a frame");
    if (!r->list_made) CLVR_TRY(make_list(r, err));
    if (r->list_n) CLVR_TRY(render_pass(r, r->list_n, err));
    r->refine_passes++;
cleanup:
    return s;
}

clvr_status clvr_renderer_frame(clvr_renderer *r, clvr_error *err)
{
    clvr_status s = clvr_renderer_full_frame(r, err);
    if (s == CLVR_OK) s = clvr_renderer_refine(r, err);
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

clvr_status clvr_renderer_read_guides(clvr_renderer *r, float *guide, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const size_t npix = (size_t)r->set.width * r->set.height;
    float *g = NULL;
    if (!r->guides_full) return clvr_error_set(err, CLVR_ERR_INTERNAL, "the renderer keeps no denoiser guides");
    if (r->frames == 0) return clvr_error_set(err, CLVR_ERR_INTERNAL, "no frame rendered yet");
    g = malloc(npix * 8 * sizeof(float));
    if (!g) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading the denoiser guides");
    CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->guides, CL_TRUE, 0, npix * 8 * sizeof(float), g, 0, NULL,
                                      NULL));
    {
        const float inv = 1.0f / (float)r->frames;
        for (size_t i = 0; i < npix; ++i) {
            const float *q = g + 8 * i;
            for (int k = 0; k < 3; ++k) guide[4 * i + (size_t)k] = q[k] * inv;
            guide[4 * i + 3] = q[3] > 0.0f ? q[4] / q[3] : -1.0f;
        }
    }
cleanup:
    free(g);
    return s;
}

/* The rectangle outside which the frames since the last change traced no
 * pixel: the one render_pass gave them (a change of camera or clip box
 * restarts them, and a read needs a frame), or the whole image where they
 * traced every pixel (clvr_frame.live[2] == 0, settings.trace_all). */
static cl_uint4 reads_live(const clvr_renderer *r)
{
    const clvr_u32 *l = r->frame.live;
    const cl_uint4 all = {{0u, 0u, r->set.width, r->set.height}}, rect = {{l[0], l[1], l[2], l[3]}};
    return l[2] == 0u ? all : rect;
}

clvr_status clvr_renderer_read(clvr_renderer *r, float *rgba, clvr_render_counters *counters, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_uint *cnt = NULL;
    float *ref = NULL;
    cl_event evt = NULL;
    size_t npix = (size_t)r->set.width * r->set.height;
    if (rgba && r->set.pixel_cv) {
        /* The means minus their control variates (kernels/pixel_cv.h), on
         * the device: a least-squares fit per pixel. */
        if (r->frames == 0) return clvr_error_set(err, CLVR_ERR_INTERNAL, "no frame rendered yet");
        const cl_float inv_n = 1.0f / (float)r->frames;
        /* refine_frames: 0, no refine sums; else the frames, below which a
         * pixel's count means no refine sample of its own. */
        const cl_uint w = r->set.width, h = r->set.height, refine_frames = r->list_made ? (cl_uint)r->frames : 0u;
        const cl_uint4 live = reads_live(r);
        CLVR_TRY(CLVR_CL_ARGS(r->k_cv, err, CLVR_ARG(r->accum), CLVR_ARG(r->ctl), CLVR_ARG(inv_n), CLVR_ARG(w),
                              CLVR_ARG(h), CLVR_ARG(r->refine), CLVR_ARG(r->nsamp), CLVR_ARG(refine_frames),
                              CLVR_ARG(live), CLVR_ARG(r->image)));
        CLVR_TRY(clvr_cl_run2d(r->cl, r->k_cv, w, h, r->local, &evt, err));
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->image, CL_TRUE, 0, npix * 4 * sizeof(float), rgba, 0,
                                          NULL, NULL));
        r->image_s = clvr_cl_event_seconds(evt);
    } else if (rgba && r->list_made) {
        /* Each pixel's mean over its own count of samples. */
        CLVR_TRY(clvr_renderer_read_moments(r, rgba, NULL, err));
        ref = malloc(npix * 8 * sizeof(float));
        cnt = malloc(npix * sizeof(cl_uint));
        if (!ref || !cnt) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading the image"); goto cleanup; }
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->refine, CL_TRUE, 0, npix * 8 * sizeof(float), ref, 0, NULL,
                                          NULL));
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->nsamp, CL_TRUE, 0, npix * sizeof(cl_uint), cnt, 0, NULL,
                                          NULL));
        for (size_t i = 0; i < npix; ++i) {
            const int own = cnt[i] > r->frames; /* refine samples of its own: its sums are written */
            for (size_t k = 0; k < 4; ++k)
                rgba[4 * i + k] = (rgba[4 * i + k] + (own ? ref[8 * i + k] : 0.0f)) / (float)cnt[i];
        }
        free(cnt);
        cnt = NULL;
    } else if (rgba) {
        CLVR_TRY(clvr_renderer_read_moments(r, rgba, NULL, err));
        float inv = 1.0f / (float)r->frames;
        for (size_t i = 0; i < npix * 4; ++i) rgba[i] *= inv;
    }
    if (counters) {
        memset(counters, 0, sizeof *counters);
        counters->frames = r->frames;
        counters->kernel_s = r->kernel_s;
        counters->light_s = r->light_s;
        counters->image_s = r->image_s;
        counters->last_frame_s = r->last_frame_s;
        counters->refine_passes = r->refine_passes;
        counters->refine_pixels = r->list_n;
        counters->refine_samples = r->refine_passes * r->list_n;
        counters->select_s = r->select_s;
        counters->pilot_s = r->pilot_s;
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
    if (evt) clReleaseEvent(evt);
    free(cnt);
    free(ref);
    return s;
}

void clvr_renderer_adjacency(const clvr_renderer *r, uint64_t *bytes, double *build_s, const char **skipped)
{
    *bytes = r->adj.bytes;
    *build_s = r->adj.build_s;
    *skipped = r->adj_skipped;
}

uint32_t clvr_renderer_estimator(const clvr_renderer *r) { return r->frame.estimator; }

int clvr_renderer_pick(const clvr_renderer *r, clvr_render_pick *pick)
{
    if (pick) *pick = r->pick;
    return r->pick_ran;
}

uint32_t clvr_renderer_macrocells(const clvr_renderer *r, double *fine_mean, double *coarse_mean)
{
    return clvr_majorants_grid(r->maj, fine_mean, coarse_mean);
}

clvr_status clvr_renderer_read_majorants(clvr_renderer *r, float *clusters, float *cells, float *blocks,
                                         float *global_majorant, clvr_error *err)
{
    if (global_majorant) *global_majorant = r->frame.global_majorant;
    return clvr_majorants_read(r->maj, clusters, cells, blocks, err);
}

/* ------------------------------------------------------------ MPI mode */

/* The MPI kernels and buffers for the current image size. */
static clvr_status mpi_prepare(clvr_renderer *r, uint32_t frame, uint32_t rank_key, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const size_t npix = (size_t)r->set.width * r->set.height;
    if (!r->tf_n) return clvr_error_set(err, CLVR_ERR_INTERNAL, "MPI phase before a transfer function");
    if (r->frame.estimator != CLVR_ESTIMATOR_URM || r->frame.method == CLVR_RENDER_MARCH)
        return clvr_error_set(err, CLVR_ERR_USAGE, "MPI mode composites the urm estimator only");
    if (!r->prog_mpi) CLVR_TRY(clvr_cl_build(r->cl, "render_mpi.cl", NULL, &r->prog_mpi, err));
    if (!r->k_mpi_record) CLVR_TRY(clvr_cl_kernel(r->prog_mpi, "clvr_render_mpi_record", &r->k_mpi_record, err));
    if (!r->k_mpi_shadow) CLVR_TRY(clvr_cl_kernel(r->prog_mpi, "clvr_render_mpi_shadow", &r->k_mpi_shadow, err));
    if (r->mpi_npix != npix) {
        clvr_cl_release(r->cl, &r->mpi_rec);
        clvr_cl_release(r->cl, &r->mpi_pick);
        clvr_cl_release(r->cl, &r->mpi_tau);
        clvr_cl_release(r->cl, &r->mpi_counters);
        r->mpi_npix = 0;
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_WRITE, npix * sizeof(clvr_mpi_record), NULL, "MPI records",
                                &r->mpi_rec, err));
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_ONLY, npix * sizeof(float), NULL, "MPI shadow points",
                                &r->mpi_pick, err));
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_WRITE, npix * sizeof(float), NULL, "MPI shadow transmittance",
                                &r->mpi_tau, err));
        CLVR_TRY(clvr_cl_buffer(r->cl, CL_MEM_READ_WRITE, npix * 2 * sizeof(cl_uint), NULL, "MPI counters",
                                &r->mpi_counters, err));
        r->mpi_npix = npix;
    }
    r->frame.frame_index = frame;
    r->frame.mpi_rank_key = rank_key;
    CLVR_TRY(upload_frame(r, err));
cleanup:
    return s;
}

/* first: the call starts a frame (phase 1). An MPI frame is its record
 * and its shadow pass, as a frame is its full and its refine pass: the
 * shadow pass adds to last_frame_s (it replaced it, so the figure was the
 * last kernel's alone). */
static clvr_status mpi_run(clvr_renderer *r, cl_kernel k, int first, uint64_t *samples, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_event evt = NULL;
    cl_uint *cnt = NULL;
    CLVR_TRY(clvr_cl_run2d(r->cl, k, r->set.width, r->set.height, r->local, &evt, err));
    CLVR_CL_CHECK(clWaitForEvents(1, &evt));
    const double t = clvr_cl_event_seconds(evt);
    r->last_frame_s = first ? t : r->last_frame_s + t;
    r->kernel_s += t;
    if (samples) {
        cnt = malloc(r->mpi_npix * 2 * sizeof(cl_uint));
        if (!cnt) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading counters"); goto cleanup; }
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->mpi_counters, CL_TRUE, 0, r->mpi_npix * 2 * sizeof(cl_uint),
                                          cnt, 0, NULL, NULL));
        uint64_t n = 0;
        for (size_t i = 0; i < r->mpi_npix; ++i) n += cnt[2 * i];
        *samples = n;
    }
cleanup:
    free(cnt);
    if (evt) clReleaseEvent(evt);
    return s;
}

clvr_status clvr_renderer_mpi_record(clvr_renderer *r, uint32_t frame, uint32_t rank_key, clvr_mpi_record *rec,
                                     uint64_t *samples, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    CLVR_TRY(mpi_prepare(r, frame, rank_key, err));
    CLVR_TRY(ensure_light(r, err));
    volume_bufs vol = volume_of(r);
    CLVR_TRY(CLVR_CL_ARGS(r->k_mpi_record, err, CLVR_ARG(r->frame_buf), CLVR_ARG(r->cam_buf),
                          CLVR_VOLUME_ARRAYS(CLVR_VOLUME_ARG) CLVR_ARG(r->mpi_rec), CLVR_ARG(r->mpi_counters)));
    CLVR_TRY(mpi_run(r, r->k_mpi_record, 1, samples, err));
    CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->mpi_rec, CL_TRUE, 0, r->mpi_npix * sizeof(clvr_mpi_record), rec,
                                      0, NULL, NULL));
cleanup:
    return s;
}

clvr_status clvr_renderer_mpi_shadow(clvr_renderer *r, uint32_t frame, uint32_t rank_key, const float *pick_t,
                                     float *tau, uint64_t *samples, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    CLVR_TRY(mpi_prepare(r, frame, rank_key, err));
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->mpi_pick, CL_TRUE, 0, r->mpi_npix * sizeof(float), pick_t, 0,
                                       NULL, NULL));
    volume_bufs vol = volume_of(r);
    CLVR_TRY(CLVR_CL_ARGS(r->k_mpi_shadow, err, CLVR_ARG(r->frame_buf), CLVR_ARG(r->cam_buf),
                          CLVR_VOLUME_ARRAYS(CLVR_VOLUME_ARG) CLVR_ARG(r->mpi_pick), CLVR_ARG(r->mpi_tau),
                          CLVR_ARG(r->mpi_counters)));
    CLVR_TRY(mpi_run(r, r->k_mpi_shadow, 0, samples, err));
    CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->mpi_tau, CL_TRUE, 0, r->mpi_npix * sizeof(float), tau, 0, NULL,
                                      NULL));
cleanup:
    return s;
}

clvr_status clvr_renderer_light_grid(clvr_renderer *r, float *grid, uint32_t *res, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    if (!r->tf_n) return clvr_error_set(err, CLVR_ERR_INTERNAL, "light grid before a transfer function");
    CLVR_TRY(upload_frame(r, err));
    CLVR_TRY(ensure_light(r, err));
    if (!r->light_valid) return clvr_error_set(err, CLVR_ERR_INTERNAL, "no light grid: urm with shadows only");
    s = clvr_renderer_read_light(r, grid, res, err);
cleanup:
    return s;
}

clvr_status clvr_renderer_set_light_grid(clvr_renderer *r, const float *grid, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const size_t n = clvr_light_nodes(r->frame.light_res);
    CLVR_CL_CHECK(clEnqueueWriteBuffer(r->cl->queue, r->light_buf, CL_TRUE, 0, n * sizeof(float), grid, 0, NULL,
                                       NULL));
    r->light_valid = 1;
cleanup:
    return s;
}

clvr_status clvr_renderer_read_light(clvr_renderer *r, float *out, uint32_t *res, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    const uint32_t n = r->frame.light_res;
    *res = n;
    if (!r->light_valid)
        return clvr_error_set(err, CLVR_ERR_INTERNAL, "no light grid yet (it is made by a urm frame with shadows)");
    if (out)
        CLVR_CL_CHECK(clEnqueueReadBuffer(r->cl->queue, r->light_buf, CL_TRUE, 0, (size_t)clvr_light_nodes(n) * sizeof(float),
                                          out, 0, NULL, NULL));
cleanup:
    return s;
}
