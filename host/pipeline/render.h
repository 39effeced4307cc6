/* render.h: the progressive renderer. Owns the device buffers of one frame
 * (accumulator, counters, transfer-function table) and its majorants
 * (majorant.h: cluster majorants and the macrocell grid, kernels/majorant.cl)
 * and dispatches kernels/render.cl over a clustered mesh and its trees. One call of clvr_renderer_frame adds one
 * sample per pixel; any change of settings, camera or transfer function
 * restarts the accumulation. */
#ifndef CLVR_RENDER_H
#define CLVR_RENDER_H

#include <stdint.h>

#include "cl_context.h"
#include "clvr_shared.h"
#include "preprocess.h"
#include "accel.h"

/* Names of CLVR_RENDER_* and CLVR_ESTIMATOR_* ("?" when out of range), and
 * the value of a name (CLVR_RENDER_COUNT / CLVR_ESTIMATOR_COUNT when none):
 * the one table the CLI, the viewer, the stats and the benches use. */
const char *clvr_render_method_name(uint32_t method);
const char *clvr_render_estimator_name(uint32_t estimator);
uint32_t clvr_render_method_from_name(const char *name);
uint32_t clvr_render_estimator_from_name(const char *name);

/* The default adaptive sampling threshold (settings.adaptive); clvr.h
 * defines the same for the API's users, token for token (a compiler that
 * sees both checks they agree). */
#define CLVR_ADAPTIVE_DEFAULT 0.1f

typedef struct clvr_render_settings {
    uint32_t method;           /* CLVR_RENDER_* */
    uint32_t estimator;        /* CLVR_ESTIMATOR_* (track, bins, dda) */
    uint32_t urm_steps;        /* urm: minimum quadrature points per ray (>= 1) */
    float urm_kappa;           /* urm: largest majorant optical depth between two points (> 0) */
    uint32_t light_res;        /* with shadows: light grid columns per axis (clvr_light_nodes), 1..
                                * CLVR_URM_LIGHT_RES, or 0 (the default): clvr_light_res_for the mesh's
                                * elements; any keeps the image unbiased, a coarser one is noisier */
    uint32_t width, height;
    uint64_t seed;
    uint32_t sampler;          /* CLVR_SAMPLER_*: ld (default) or independent frames */
    uint32_t pixel_filter;     /* CLVR_PIXEL_*: box (default, antialiased) or point (pixel centres) */
    int pixel_cv;              /* nonzero (default): the image read is each pixel's mean minus the control
                                * variates of its jitter and first uniform (kernels/pixel_cv.h; the same
                                * expected image, less noise); 0: the plain means */
    int guides;                /* nonzero: frames also accumulate the denoiser's guides (clvr_renderer_read_guides) */
    /* Adaptive sampling (clvr_renderer_refine): > 0 (default
     * CLVR_ADAPTIVE_DEFAULT): after each frame, one more sample in the
     * pixels whose 8 neighbours' values spread (standard deviation of their
     * luminance, after the accumulation's first frames) by more than
     * `adaptive` times the mean of the other pixels that met the medium; 0:
     * every pixel gets one sample per frame. The choice never reads the
     * pixel's own samples, so every pixel keeps its expected value. */
    float adaptive;
    int shadows;
    /* Nonzero (default): every camera ray is cut to the part between its
     * first and last crossing of the mesh's boundary faces, where the
     * medium can be, when the trees have a hull (accel.h; kept unless the
     * mesh fills its box, hull.h); 0: to the clip box only. The image's
     * expected value is the same; the estimators converge faster when the
     * medium starts inside the box. */
    int hull;
    float step;                /* march step; <= 0: mesh diagonal / 512 */
    uint32_t bins, segments;   /* bins method (bins <= CLVR_RENDER_MAX_BINS) */
    uint32_t macrocells;       /* dda method: grid resolution per axis; 0 (default): automatic,
                                  CLVR_MACROCELLS_FINE or a grid CLVR_DDA_BLOCK times coarser,
                                  chosen per transfer function (clvr_renderer_macrocells) */
    float light_dir[3];        /* toward the light; normalised here */
    float light_intensity;
    float ambient;
    float background[3];
    /* Clip box of the rays and domain of the macrocell grid; lo > hi (the
     * default) means the mesh bounds. The grid domain must cover every
     * element that should be seen (majorants outside it are 0); the clip box
     * may be anything. Kept apart so that a clip box does not coarsen the
     * grid and a partition of a mesh can share one grid domain. */
    float clip_lo[3], clip_hi[3];
    float grid_lo[3], grid_hi[3];
    /* Clip planes (nx, ny, nz, d): the medium where n.p > d is removed
     * (kept: n.p <= d, ParaView's Clip with "Invert" on, its default), for
     * camera and shadow rays alike. n need not be unit length (it is
     * normalised with d); a zero n is a usage error. Default none. */
    uint32_t num_clip_planes;  /* 0..CLVR_MAX_CLIP_PLANES */
    float clip_planes[CLVR_MAX_CLIP_PLANES][4];
    /* Nonzero: a frame traces every pixel, also those whose camera rays
     * cannot meet the clip box (which it otherwise writes as background
     * without tracing, clvr_frame.live). The image is the same bit for bit
     * (test_render checks it); default 0. */
    int trace_all;
} clvr_render_settings;

/* Sensible defaults (dda, 512x512, shadows on, ...). */
void clvr_render_settings_default(clvr_render_settings *s);

/* The light grid's columns per axis for a mesh of `elements` elements (the
 * whole mesh's, on every MPI rank alike): CLVR_URM_DEFAULT_LIGHT_RES, or
 * fewer where the grid would have more than 2 nodes per element (not below
 * 8). The grid's cost is a fixed cost of the first shadowed frame, about in
 * proportion to its nodes; a grid much finer than the mesh adds nothing it
 * can resolve. */
uint32_t clvr_light_res_for(uint64_t elements);
/* The light grid's frame (clvr_frame.light_space) for r x r columns over
 * the box [lo, hi] and the unit direction toward the light ldir: e1 = the
 * unit vector across ldir from ldir x (the axis least along it), e2 =
 * ldir x e1; the columns tile the box's extent along e1 and e2, the nodes
 * its extent along ldir, the first on its light side. */
void clvr_light_space(const float lo[3], const float hi[3], const float ldir[3], uint32_t r, float out[4][4]);
/* What --estimator auto renders with (CLVR_ESTIMATOR_AUTO's comment): walk,
 * whatever the shadows and the mesh's size (no rule by either fitted the
 * measurements); at cells other than tets, the way its pilot picks
 * (clvr_render_pick). The renderer falls back to urm where the walk cannot
 * run (no room for the adjacency); clvr_renderer_estimator says what it
 * renders with. */
uint32_t clvr_estimator_auto(void);

/* Per-frame figures, summed over the frames accumulated so far. */
typedef struct clvr_render_counters {
    uint64_t frames;
    uint64_t rays;            /* primary + shadow rays; a camera ray a frame knows misses the clip box without
                               * tracing it (clvr_frame.live) counts, as a traced one that misses did */
    uint64_t samples;         /* extinction lookups (point locations) */
    uint64_t null_collisions; /* rejected samples of delta tracking */
    double kernel_s;          /* device time of the render kernel, all frames (the light grid's included) */
    double last_frame_s;      /* device time of the last frame: its full pass and its refine pass (MPI mode:
                               * its record and its shadow pass) */
    double light_s;           /* device time of the light grid's last build (urm with shadows; part of kernel_s) */
    uint64_t refine_passes;   /* adaptive sampling: refine passes so far (clvr_renderer_refine) */
    uint64_t refine_pixels;   /* pixels the refine list holds (0: none, or no list yet) */
    uint64_t refine_samples;  /* samples all refine passes rendered so far, all pixels together (passes x pixels) */
    double select_s;          /* host seconds of making the refine list (once per accumulation; not in kernel_s) */
    double pilot_s;           /* host seconds of auto's pilot (clvr_renderer_pick), its kernels included, when this
                               * accumulation ran one (not in kernel_s) */
    double image_s;           /* device time of the image pass of the last clvr_renderer_read that read the image
                               * (kernels/pixel_cv.h; not part of kernel_s; 0 without the control variates) */
} clvr_render_counters;

typedef struct clvr_renderer clvr_renderer;

/* What a step of the walk through every cell costs, in extinction lookups
 * of urm: the median (1.26) of the ratio of their device time per counted
 * sample on six meshes, shadows off and on, 256x256, this VM's PoCL (the
 * notch, the hexes of fire_ug, the blunt fin and the combustor, the
 * built-in scene, the AMR-like mesh; 0.9-3.3; with post's hexes, measured
 * later, 1.19; bench/results/render-converge/2026-11-30-s45-pilot.md). */
#define CLVR_PILOT_WALK_STEP 1.25
/* auto's pilot on a mesh with cells other than tets (host/pipeline/render.c,
 * pilot_pick): way 0 walks tets and hands a ray to urm at its first other
 * cell (urm from the start on a mesh without tets), way 1 walks through
 * every cell (walk's clvr_frame.walk_cells). */
typedef struct clvr_render_pick {
    uint32_t pixels;     /* pixels of the pilot, two samples of each way each */
    double var[2];       /* per way: the variance of one sample (clvr_pilot_var), mean over those pixels */
    double work[2];      /* per way: extinction lookups and cell steps per sample (the kernel's sample counter) */
    uint32_t walk_cells; /* the way picked: 1 when var x work (way 1's x CLVR_PILOT_WALK_STEP) was smaller */
} clvr_render_pick;
/* The sum over n pixels of the variance of one sample estimated from two,
 * (a - b)^2 / 2, summed over rgb (the channels the relative RMSE pools);
 * *sumsq (may be NULL): the sum of the squares of those per-pixel values.
 * pairs: 8 floats per pixel, rgba a then rgba b; a non-finite difference
 * counts 0. */
double clvr_pilot_var(const float *pairs, uint32_t n, double *sumsq);
/* Whether a pilot ran since the last settings, and its figures (pick may be
 * NULL). */
int clvr_renderer_pick(const clvr_renderer *r, clvr_render_pick *pick);

/* Creates a renderer over a preprocessed mesh and its trees (not owned: they
 * must outlive the renderer). Builds the render and majorant programs. */
clvr_status clvr_renderer_create(clvr_cl *cl, const clvr_clustered *mesh, const clvr_accel *accel,
                                 const clvr_render_settings *settings, clvr_renderer **out, clvr_error *err);
void clvr_renderer_destroy(clvr_renderer *r); /* accepts NULL */

clvr_status clvr_renderer_set_settings(clvr_renderer *r, const clvr_render_settings *settings, clvr_error *err);
clvr_status clvr_renderer_set_camera(clvr_renderer *r, const clvr_camera *cam, clvr_error *err);
/* Uploads a baked transfer function (n entries of rgb + extinction over the
 * scalar window [lo, hi], scaled by density) and recomputes every majorant on
 * the device. */
clvr_status clvr_renderer_set_tf(clvr_renderer *r, const float *rgba, uint32_t n, float lo, float hi, float density,
                                 clvr_error *err);

/* Renders one more sample per pixel (clvr_renderer_full_frame), then, with
 * settings.adaptive, one more in the pixels that need it
 * (clvr_renderer_refine). */
clvr_status clvr_renderer_frame(clvr_renderer *r, clvr_error *err);
/* The two halves of clvr_renderer_frame, for benches that read the image
 * between them. The first refine pass of an accumulation reads the frames
 * so far and makes the list of pixels (clvr_adaptive_pick), kept until the
 * next change; every refine pass renders one sample in each listed pixel.
 * Without settings.adaptive, refine does nothing. */
clvr_status clvr_renderer_full_frame(clvr_renderer *r, clvr_error *err);
clvr_status clvr_renderer_refine(clvr_renderer *r, clvr_error *err);
/* The choice of adaptive sampling, on the host (it runs once per
 * accumulation): sum, w x h rgba sums of frames, inv_n 1 / frames. Lists in
 * list (room for w * h) the pixels, row by row, whose 8 neighbours'
 * luminance ((r + g + b) / 3 of the means) has a standard deviation above
 * threshold times the mean luminance of the pixels that met the medium
 * (alpha > 0), the pixel itself left out of that mean: nothing the pixel
 * drew decides whether it is listed. *count: how many. Returns nonzero when
 * out of host memory. */
int clvr_adaptive_pick(const float *sum, float inv_n, uint32_t w, uint32_t h, float threshold, uint32_t *list,
                       uint32_t *count);
/* Frames accumulated since the last change (clvr_render_counters.frames,
 * without reading the per-pixel counters). */
uint64_t clvr_renderer_frames(const clvr_renderer *r);

/* Copies the running mean image (width * height * 4 floats, linear rgb and
 * alpha = opacity, rows top to bottom) and the counters; either may be NULL. */
clvr_status clvr_renderer_read(clvr_renderer *r, float *rgba, clvr_render_counters *counters, clvr_error *err);

/* The sum of per-frame samples (not the mean), for tests that need per-pixel
 * variances: rgba_sum, rgba_sumsq (width * height * 4 each; may be NULL).
 * The frames' only: refine passes' samples are kept apart. */
clvr_status clvr_renderer_read_moments(clvr_renderer *r, float *rgba_sum, float *rgba_sumsq, clvr_error *err);

/* The denoiser's guides (kernels/denoise.h) of the frames so far: per pixel
 * the mean albedo (colour unlit) rgb and the mean depth of the frames whose
 * ray met the medium, or -1 where none did (width * height * 4 floats). An
 * error unless the settings asked for guides. */
clvr_status clvr_renderer_read_guides(clvr_renderer *r, float *guide, clvr_error *err);

/* The light grid (transmittance toward the light at the nodes of
 * frame light_res^2 columns, clvr_light_node order, clvr_light_space's
 * frame) as last built by a frame with urm or walk and shadows; *res gets
 * light_res. out: clvr_light_nodes(light_res) floats, or NULL for *res
 * only. An error before such a frame. */
clvr_status clvr_renderer_read_light(clvr_renderer *r, float *out, uint32_t *res, clvr_error *err);

/* The walk's face adjacency (built at the first settings that ask for
 * walk): device bytes kept and the device seconds of its build, 0 and 0
 * when none; *skipped: why walk renders as urm on this mesh ("" when it
 * does not), valid while r lives. */
void clvr_renderer_adjacency(const clvr_renderer *r, uint64_t *bytes, double *build_s, const char **skipped);
/* The estimator the frames render with (CLVR_ESTIMATOR_*, never AUTO): the
 * settings' as resolved by the last settings (auto, and urm where the walk
 * cannot run). */
uint32_t clvr_renderer_estimator(const clvr_renderer *r);

/* Cells per axis of the macrocell grid the frames read (the settings'
 * macrocells, or what the automatic grid chose), and the automatic grid's
 * mean majorants of its fine cells and of its blocks at its last choice (0
 * and 0 with macrocells set). */
uint32_t clvr_renderer_macrocells(const clvr_renderer *r, double *fine_mean, double *coarse_mean);

/* The majorant of every sampling cluster / macrocell / macrocell block of
 * the grid in use (clvr_renderer_macrocells per axis, and
 * ceil(that / CLVR_DDA_BLOCK) blocks per axis, see clvr_shared.h) (tests);
 * any may be NULL. */
clvr_status clvr_renderer_read_majorants(clvr_renderer *r, float *clusters, float *cells, float *blocks,
                                         float *global_majorant, clvr_error *err);


/* MPI mode (host/mpi, docs/mpi-compositing.md): the urm estimator split
 * into the two phases that rank 0 composites. Each runs one kernel over the
 * image with frame index `frame` and the frame's random streams mixed with
 * rank_key, and reads its result back (blocking). counters, when not NULL,
 * receives the extinction lookups of the call. */
/* Phase 1: one record per pixel (width * height). */
clvr_status clvr_renderer_mpi_record(clvr_renderer *r, uint32_t frame, uint32_t rank_key, clvr_mpi_record *rec,
                                     uint64_t *samples, clvr_error *err);
/* Phase 2: the transmittance inside this rank's region along the shadow ray
 * from distance pick_t[p] on pixel p's camera ray (< 0: no ray, tau 1). */
clvr_status clvr_renderer_mpi_shadow(clvr_renderer *r, uint32_t frame, uint32_t rank_key, const float *pick_t,
                                     float *tau, uint64_t *samples, clvr_error *err);
/* The light grid (*res = light_res columns per axis,
 * clvr_light_nodes(res) floats, at most clvr_light_nodes(CLVR_URM_LIGHT_RES)): computed for the current frame and transfer
 * function when out of date, then copied out (clvr_renderer_read_light);
 * and replaced by a given one of the same size (the product over ranks),
 * kept until the settings or transfer function change. */
clvr_status clvr_renderer_light_grid(clvr_renderer *r, float *grid, uint32_t *res, clvr_error *err);
clvr_status clvr_renderer_set_light_grid(clvr_renderer *r, const float *grid, clvr_error *err);

#endif
