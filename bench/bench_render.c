/* bench_render.c: render throughput in the shape of the paper's Table 5
 * (fps and million rays per second at 1 sample per pixel, primary plus
 * shadow rays) for every integrator: alpha-composited ray marching (no
 * shadows, as in the paper), delta tracking with one global majorant, and
 * the adaptive methods (majorant bins along the ray; macrocell grid with
 * 3D-DDA, --macrocells: the automatic grid and two grid sizes by default,
 * each entry R or auto; the automatic grid's choice is printed); plus samples (point locations) and null
 * collisions per ray. The pipeline is clvr's own (load, Quick Clusters
 * preprocessing, two-level BVH, renderer), with clvr's default transfer
 * function over the mesh's scalar range and its automatic camera framing.
 *
 * Timing: W warm-up frames, then N frames, each timed by the render
 * kernel's OpenCL events (the renderer's counters: last_frame_s, the
 * frame's full pass and its refine pass); the table gives the median.
 * Rays, samples and null collisions are the counters' totals over the N
 * timed frames divided by N. The 1-minute load average is
 * recorded with every row because the machine may be shared.
 *
 * --converge measures time to equal quality instead (bench/render-vs-vtk.sh):
 * a reference with many samples per pixel, then a fresh progressive run with
 * another seed whose RMSE against the reference is checked at growing spp
 * (see the comment at converge_one for the definitions).
 *
 *   bench_render [--device SPEC] [--json FILE] [--mesh FILE ...] [--size WxH] [--frames N] [--warmup W]
 *                [--methods LIST] [--macrocells auto,A,B] [--no-shadows] [--budget S] [--density D|auto] [--quick]
 *                [--sampler ld|independent] [--no-hull] [--pixel-filter box|point]
 *   bench_render --converge [--mesh FILE] [--size WxH] [--method NAME] [--ref-spp R] [--target F]
 *                [--max-spp M] [--sampler ld|independent] [--json FILE] [--denoise] [--no-pixel-cv]
 *                [--adaptive T]
 *                [--repeats K]
 *
 * --repeats (--converge): K measured runs per configuration with seeds 1 ..
 * K (default 3; only the first where it took over CONV_REPEAT_MAX_S device
 * seconds, whose frames average their noise already); the row is the run
 * whose time to the target is the median (runs that miss it rank last), and
 * the table's note and the JSON
 * ("repeats_s") give every run's time. One 20-40 ms frame moved by up to 40%
 * on a 2-core VM between runs (bench/results/render-converge/
 * 2026-11-28-s35-newton-locate.md, section 8); a seed's error moves too.
 *
 * --denoise (--converge): also the error of each checkpoint's image after the
 * optional denoiser (kernels/denoise.h), and its bias (the denoised
 * reference against the reference), in a second table: never in the first,
 * which is the unbiased estimate's.
 * --pixel-filter: the image the frames converge to (render.h; the
 * reference of --converge uses it too), box (default) or point.
 * --adaptive T: adaptive sampling's threshold (render.h settings.adaptive;
 * 0: off; default CLVR_ADAPTIVE_DEFAULT); an estimator variant's @T suffix
 * (walk@0) sets it for that variant alone, for A/B rows in one run. --converge checks the image after
 * each frame and after its refine pass; spp there is samples per pixel.
 * --no-pixel-cv: the images read are the plain means, without the
 * per-pixel control variates (kernels/pixel_cv.h; render.h settings.pixel_cv;
 * for A/B runs). The --converge reference is always made without them; the
 * image pass's device time counts in the measured runs' times.
 * --no-hull: camera rays are not cut to the mesh's boundary crossings
 * (settings.hull off; the same image in expectation, for A/B runs).
 * --sampler: the renderer's frame sampler (default ld, the renderer's
 * default); --converge renders its reference with independent frames always
 * and the measured run with this sampler.
 *
 * Without --mesh: the built-in default scene and tests/data/vtk/notch_stress.vtk. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clock.h"
#include "bench_util.h"
#include "accel.h"
#include "cli.h"
#include "camera.h"
#include "cl_context.h"
#include "denoiser.h"
#include "mesh_io.h"
#include "preprocess.h"
#include "render.h"
#include "scene.h"
#include "tf.h"
#include "tf_auto.h"

#define MAX_MESHES 16
#define MAX_CONFIGS 8

static int parse_method(const char *s, uint32_t *m)
{
    *m = clvr_render_method_from_name(s);
    return *m < CLVR_RENDER_COUNT;
}

typedef struct config {
    uint32_t method, macrocells;
    int shadows;
    char label[32];
    uint32_t sampler;   /* CLVR_SAMPLER_* */
    uint32_t estimator; /* CLVR_ESTIMATOR_* */
    uint32_t urm_steps; /* 0: the renderer's default */
    float urm_kappa;    /* 0: the renderer's default */
    uint32_t light_res; /* 0: the renderer's default (urm with shadows: light grid cells per axis) */
    int no_hull;        /* --no-hull: camera rays keep their whole box interval (render.h settings.hull) */
    uint32_t pixel_filter; /* CLVR_PIXEL_*: --pixel-filter (the reference's too) */
    int guides;         /* --denoise (converge): keep the denoiser's guides, report the denoised error apart */
    int no_pixel_cv;    /* --no-pixel-cv: images read without the per-pixel control variates (render.h) */
    float adaptive;     /* --adaptive T: render.h settings.adaptive (default CLVR_ADAPTIVE_DEFAULT; 0 off) */
} config;

typedef struct row {
    const char *mesh;
    uint64_t elements;
    double preprocess_s;
    config c;
    uint32_t frames;
    double frame_s, frame_min_s, frame_max_s, wall_frame_s; /* median device time, its spread, median wall time */
    double rays_per_frame, samples_per_ray, nulls_per_ray;
    double fps, mrays_s, image_mean;
    double load_before, load_after;
} row;

/* A mesh on the device, ready to render: owns everything it holds. */
typedef struct scene_gpu {
    clvr_clustered clustered;
    clvr_accel accel;
    clvr_tf tf;
    float *table;
    uint32_t table_n;
    float lo[3], hi[3];
    uint64_t elements;
    double preprocess_s;
    int adjacency_told; /* the walk's adjacency reported once */
    int grid_told;      /* the automatic macrocell grid's choice reported once */
} scene_gpu;

static void scene_release(clvr_cl *cl, scene_gpu *g)
{
    clvr_accel_release(cl, &g->accel);
    clvr_clustered_release(cl, &g->clustered);
    clvr_tf_free(&g->tf);
    free(g->table);
    memset(g, 0, sizeof *g);
}

/* clvr_preprocess_options.one_curve of every scene (--one-curve auto|on|off; auto, the default, as clvr's) */
static int g_one_curve = CLVR_ONE_CURVE_AUTO;

/* --like FILE: every scene takes FILE's scalar range (its transfer
 * function), box (the extent the density is scaled by, the camera's framing
 * and the pixels counted as inside) instead of its own, so a graded mesh's
 * uniform twin is rendered at the same optical depth from the same camera
 * (bench/graded.sh). A twin sampled from a solver's mesh (tools/graded_twin.py)
 * covers a little less of the box and misses the field's thinnest extremes. */
typedef struct like_ref {
    int set;
    const char *path; /* FILE (argv's) */
    float lo[3], hi[3], scalar_min, scalar_max;
    float auto_density; /* --density auto: FILE's (clvr_tf_auto_density) */
} like_ref;
static like_ref g_like;

/* --density auto (clvr's default): the factor that gives m's median visible
 * camera ray optical depth CLVR_TF_AUTO_DEPTH under the default ramp over
 * [smin, smax] and box lo..hi (clvr_tf_auto_density). */
static clvr_status auto_density_of(const clvr_mesh *m, float smin, float smax, const float *lo, const float *hi,
                                   float *out, clvr_error *err)
{
    clvr_tf tf;
    memset(&tf, 0, sizeof tf);
    clvr_status s = clvr_tf_from_options(&tf, NULL, NULL, 0, 0.0f, 0.0f, 1.0f, smin, smax, err);
    if (s == CLVR_OK) {
        clvr_tf_set_extent(&tf, lo, hi);
        s = clvr_tf_auto_density(m, &tf, out, err);
    }
    clvr_tf_free(&tf);
    return s;
}

/* The header's density: "auto" (resolved per mesh on stderr, "density auto =")
 * or the factor, and --like's file when given. */
static const char *density_text(float density, const char *like, char *buf, size_t cap)
{
    int n = density > 0.0f ? snprintf(buf, cap, "%g", (double)density) : snprintf(buf, cap, "auto");
    if (like && n >= 0 && (size_t)n < cap) snprintf(buf + n, cap - (size_t)n, ", like %s", like);
    return buf;
}

static clvr_status like_load(const char *path, like_ref *out, clvr_error *err)
{
    clvr_mesh m = {0};
    clvr_load_options lo = {0};
    clvr_status s = clvr_mesh_load(path, &lo, &m, err);
    if (s != CLVR_OK) return s;
    memcpy(out->lo, m.bounds_lo, sizeof out->lo);
    memcpy(out->hi, m.bounds_hi, sizeof out->hi);
    out->scalar_min = m.scalar_min;
    out->scalar_max = m.scalar_max;
    s = auto_density_of(&m, m.scalar_min, m.scalar_max, m.bounds_lo, m.bounds_hi, &out->auto_density, err);
    out->set = s == CLVR_OK;
    out->path = path;
    clvr_mesh_free(&m);
    return s;
}

/* Loads path ("default": the built-in scene), preprocesses and builds the
 * trees, and bakes clvr's default transfer function over the data range
 * (or --like's). */
static clvr_status scene_load(clvr_cl *cl, const char *path, float density, scene_gpu *g, clvr_error *err)
{
    clvr_status s;
    clvr_mesh m = {0};
    memset(g, 0, sizeof *g);
    if (!strcmp(path, "default")) s = clvr_scene_default(&m, err);
    else {
        clvr_load_options lo = {0};
        s = clvr_mesh_load(path, &lo, &m, err);
    }
    if (s != CLVR_OK) return s;
    g->elements = clvr_mesh_num_elements(&m);
    memcpy(g->lo, g_like.set ? g_like.lo : m.bounds_lo, sizeof g->lo);
    memcpy(g->hi, g_like.set ? g_like.hi : m.bounds_hi, sizeof g->hi);
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    po.one_curve = g_one_curve;
    double t0 = clvr_clock_monotonic_s();
    s = clvr_preprocess(cl, &m, &po, &g->clustered, err);
    if (s == CLVR_OK) s = clvr_accel_build(cl, &g->clustered, &g->accel, err);
    g->preprocess_s = clvr_clock_monotonic_s() - t0;
    if (s == CLVR_OK) {
        const clvr_hull *hl = &g->accel.hull;
        fprintf(stderr, "bench_render: hull: %u boundary faces of %llu, %.1f MB (faces and tree), %.3f s device, "
                "empty fraction %.3f, of the clusters' boxes %.3f (%s)\n", hl->num_faces, (unsigned long long)hl->num_slots,
                ((double)hl->num_faces * sizeof(clvr_hull_face) + (double)hl->num_nodes * sizeof(clvr_bvh_node)) / 1e6,
                hl->build_s, (double)hl->empty_fraction, (double)hl->box_fraction,
                hl->kept ? "kept" : hl->boxes_only ? "not built: little empty space in the box" : "dropped: little empty space in the box");
    }
    if (s == CLVR_OK && !(density > 0.0f)) { /* auto */
        if (g_like.set) density = g_like.auto_density;
        else s = auto_density_of(&m, m.scalar_min, m.scalar_max, g->lo, g->hi, &density, err);
        if (s == CLVR_OK) fprintf(stderr, "bench_render: %s: density auto = %g\n", path, (double)density);
    }
    if (s == CLVR_OK)
        s = clvr_tf_from_options(&g->tf, NULL, NULL, 0, 0.0f, 0.0f, density,
                                 g_like.set ? g_like.scalar_min : m.scalar_min,
                                 g_like.set ? g_like.scalar_max : m.scalar_max, err);
    if (s == CLVR_OK) {
        clvr_tf_set_extent(&g->tf, g->lo, g->hi);
        g->table_n = clvr_tf_table_size(&g->tf);
        g->table = malloc((size_t)g->table_n * 4 * sizeof(float));
        if (!g->table) s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_render: out of memory for the tf table");
        else clvr_tf_bake(&g->tf, g->table, g->table_n);
    }
    clvr_mesh_free(&m);
    if (s != CLVR_OK) scene_release(cl, g);
    return s;
}

/* A renderer over g with clvr's defaults, method/shadows/size from c. */
static clvr_status renderer_for(clvr_cl *cl, scene_gpu *g, const config *c, uint32_t w, uint32_t h, uint64_t seed,
                                clvr_renderer **out, clvr_camera *cam_out, clvr_error *err)
{
    clvr_render_settings rs;
    clvr_render_settings_default(&rs);
    rs.method = c->method;
    rs.width = w;
    rs.height = h;
    rs.seed = seed;
    rs.sampler = c->sampler;
    rs.estimator = c->estimator;
    if (c->urm_steps) rs.urm_steps = c->urm_steps;
    if (c->urm_kappa > 0.0f) rs.urm_kappa = c->urm_kappa;
    if (c->light_res) rs.light_res = c->light_res;
    rs.hull = !c->no_hull;
    rs.pixel_filter = c->pixel_filter;
    rs.pixel_cv = !c->no_pixel_cv;
    rs.adaptive = c->adaptive;
    rs.guides = c->guides;
    rs.shadows = c->shadows && c->method != CLVR_RENDER_MARCH;
    if (c->macrocells) rs.macrocells = c->macrocells;
    clvr_camera cam;
    clvr_status s = clvr_camera_frame_box(&cam, g->lo, g->hi, 40.0f, w, h, err);
    if (s != CLVR_OK) return s;
    if (cam_out) *cam_out = cam;
    s = clvr_renderer_create(cl, &g->clustered, &g->accel, &rs, out, err);
    if (s == CLVR_OK) s = clvr_renderer_set_camera(*out, &cam, err);
    if (s == CLVR_OK) s = clvr_renderer_set_tf(*out, g->table, g->table_n, g->tf.range_lo, g->tf.range_hi,
                                               g->tf.density, err);
    if (s == CLVR_OK && !g->adjacency_told) {
        /* Once, when the renderer built the walk's adjacency or gave it up. */
        uint64_t bytes;
        double build_s;
        const char *skipped;
        clvr_renderer_adjacency(*out, &bytes, &build_s, &skipped);
        if (*skipped) fprintf(stderr, "bench_render: walk renders as urm: %s\n", skipped);
        else if (bytes)
            fprintf(stderr, "bench_render: face adjacency for walk: %.1f MB (%.1f bytes per element), built in %.3f s "
                    "device\n", (double)bytes / 1e6, g->elements ? (double)bytes / (double)g->elements : 0.0, build_s);
        g->adjacency_told = *skipped || bytes;
    }
    if (s == CLVR_OK && c->method == CLVR_RENDER_DDA && !c->macrocells && !g->grid_told) {
        g->grid_told = 1; /* once per mesh: the choice follows the mesh and transfer function alone */
        double fine, coarse;
        const uint32_t res = clvr_renderer_macrocells(*out, &fine, &coarse);
        fprintf(stderr, "bench_render: macrocells auto: %u^3 (mean majorant %.4g over %u^3 cells, %.4g over %u^3: "
                "ratio %.3f, the fine grid below %.2f)\n", res, fine, CLVR_MACROCELLS_FINE, coarse,
                CLVR_MACROCELLS_FINE / CLVR_DDA_BLOCK, coarse > 0 ? fine / coarse : 0.0, (double)CLVR_MACROCELLS_GAIN);
    }
    if (s != CLVR_OK) {
        clvr_renderer_destroy(*out);
        *out = NULL;
    }
    return s;
}

/* Mean of the finite rgb values; NaN when any value is not finite. */
static double image_mean(const float *rgba, size_t npix)
{
    double sum = 0.0;
    for (size_t i = 0; i < npix; ++i)
        for (int k = 0; k < 3; ++k) {
            float v = rgba[4 * i + k];
            if (!isfinite(v)) return NAN;
            sum += v;
        }
    return npix ? sum / (3.0 * (double)npix) : NAN;
}

static clvr_status bench_one(clvr_cl *cl, scene_gpu *g, const config *c, uint32_t w, uint32_t h, uint32_t warmup,
                             uint32_t frames, double budget_s, row *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_renderer *rd = NULL;
    double *dev = calloc(frames, sizeof *dev), *wall = calloc(frames, sizeof *wall);
    float *img = malloc((size_t)w * h * 4 * sizeof(float));
    clvr_render_counters c0, c1;
    if (!dev || !wall || !img) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_render: out of memory");
        goto done;
    }
    r->c = *c;
    r->load_before = bench_load1();
    s = renderer_for(cl, g, c, w, h, 1, &rd, NULL, err);
    /* Calibration: the first warm-up frame's time caps the timed frames at
     * about budget_s (at least one), so that marching a 10M-element mesh at
     * 1024^2 finishes; the row reports how many frames it took. */
    for (uint32_t i = 0; s == CLVR_OK && i < (warmup ? warmup : 1); ++i) {
        s = clvr_renderer_frame(rd, err);
        if (s != CLVR_OK || i) continue;
        clvr_render_counters cw;
        s = clvr_renderer_read(rd, NULL, &cw, err);
        if (s == CLVR_OK && cw.last_frame_s > 0 && budget_s > 0) {
            double fit = budget_s / cw.last_frame_s;
            if (fit < frames) frames = fit < 1 ? 1 : (uint32_t)fit;
            if (cw.last_frame_s > budget_s / 4) break; /* one warm-up frame is enough for slow configurations */
        }
    }
    if (s == CLVR_OK) s = clvr_renderer_read(rd, NULL, &c0, err);
    for (uint32_t i = 0; s == CLVR_OK && i < frames; ++i) {
        double t0 = clvr_clock_monotonic_s();
        s = clvr_renderer_frame(rd, err);
        wall[i] = clvr_clock_monotonic_s() - t0;
        clvr_render_counters ci;
        if (s == CLVR_OK) s = clvr_renderer_read(rd, NULL, &ci, err);
        dev[i] = ci.last_frame_s;
    }
    if (s == CLVR_OK) s = clvr_renderer_read(rd, img, &c1, err);
    if (s != CLVR_OK) goto done;
    r->frames = frames;
    r->load_after = bench_load1();
    const double rays = (double)(c1.rays - c0.rays), samples = (double)(c1.samples - c0.samples),
                 nulls = (double)(c1.null_collisions - c0.null_collisions);
    r->rays_per_frame = rays / frames;
    r->samples_per_ray = rays > 0 ? samples / rays : 0.0;
    r->nulls_per_ray = rays > 0 ? nulls / rays : 0.0;
    r->wall_frame_s = bench_median(wall, frames);
    r->frame_s = bench_median(dev, frames);
    r->frame_min_s = dev[0];
    r->frame_max_s = dev[frames - 1];
    r->fps = r->frame_s > 0 ? 1.0 / r->frame_s : 0.0;
    r->mrays_s = r->frame_s > 0 ? r->rays_per_frame / r->frame_s / 1e6 : 0.0;
    r->image_mean = image_mean(img, (size_t)w * h);
done:
    clvr_renderer_destroy(rd);
    free(dev);
    free(wall);
    free(img);
    return s;
}

static const char *base_name(const char *p)
{
    const char *b = strrchr(p, '/');
    return b ? b + 1 : p;
}

/* ---------------------------------------------------------------- converge
 * Time to equal quality (issue 14's figure). Per shadow setting, a reference
 * of R spp (seed 0x5eed, independent frames, estimator --ref-estimator,
 * default urm: the least noisy, and the tests prove it has the same mean as
 * delta tracking), then for each estimator a fresh progressive run with
 * seed 1 and the sampler under test. Definitions, over the pixels whose
 * camera ray (through the pixel centre) enters the mesh's bounding box
 * ("inside"; background pixels are exact and would dilute the figure), linear
 * rgb, no clamping:
 *   mse_raw(n) = mean over inside pixels and channels of (img_n - ref)^2
 *   ref_var    = mean over the same of the reference's own variance of the
 *                mean, (sumsq/R - mean^2) / (R - 1), from its per-frame
 *                moments
 *   rmse(n)    = sqrt(max(0, mse_raw(n) - ref_var)): the error against the
 *                converged image, with the reference's own noise removed
 *   rel(n)     = rmse(n) / mean of the reference's rgb over inside pixels
 * The RMSE is taken over inside pixels too (the stricter of the two readings
 * of "RMSE over every pixel": background pixels would lower it). The
 * criterion is rel <= target. Checkpoints at n = 1, 2, ..., 16, then steps of
 * n/16; the time is the summed device time of the n frames (and wall time).
 * A 1/n fit (mse * n is constant for independent frames) gives the
 * interpolated spp and time as well; with the ld sampler the error falls
 * faster than 1/n and the fit is pessimistic. */
typedef struct conv_point {
    uint32_t spp;      /* frames */
    int refined;       /* after the frame's refine pass (adaptive sampling) */
    double spp_mean;   /* samples per pixel, frames and refine passes */
    double dev_s, wall_s, rmse_raw, rmse, rmse_rel;
    double rmse_rel_dn; /* --denoise: the denoised image's (biased; NaN otherwise) */
} conv_point;

#define MAX_POINTS 128
#define MAX_REPEATS 9
#define CONV_REPEAT_MAX_S 2.0
#define MAX_EST 8

/* An estimator of a converge run: name[:urm-steps[:urm-kappa[:light-res]]]
 * (0 or absent: the renderer's default). */
typedef struct est_variant {
    uint32_t estimator, urm_steps;
    float urm_kappa;
    uint32_t light_res;
    float adaptive; /* @T: adaptive sampling's threshold for this variant; < 0: --adaptive's */
} est_variant;

/* An adaptive sampling threshold (render.h settings.adaptive): a whole
 * string that is a finite number >= 0. Returns 0 otherwise. */
static int parse_adaptive(const char *s, float *out)
{
    char *end;
    *out = strtof(s, &end);
    return end != s && !*end && *out >= 0.0f && isfinite(*out);
}

/* name[:urm-steps[:urm-kappa[:light-res]]][@adaptive] */
static int parse_variant(const char *s, est_variant *v)
{
    char name[32];
    v->adaptive = -1.0f;
    const char *at = strchr(s, '@');
    if (at && !parse_adaptive(at + 1, &v->adaptive)) return 0;
    size_t n = strcspn(s, ":@");
    if (n >= sizeof name) return 0;
    memcpy(name, s, n);
    name[n] = 0;
    v->estimator = clvr_render_estimator_from_name(name);
    v->urm_steps = 0;
    v->urm_kappa = 0.0f;
    v->light_res = 0;
    if (s[n] == ':') {
        char *end;
        v->urm_steps = (uint32_t)strtoul(s + n + 1, &end, 10);
        if (*end == ':') v->urm_kappa = strtof(end + 1, &end);
        if (*end == ':') v->light_res = (uint32_t)strtoul(end + 1, &end, 10);
    }
    return v->estimator < CLVR_ESTIMATOR_COUNT;
}

static void variant_label(const est_variant *v, char *buf, size_t cap)
{
    if (v->light_res) snprintf(buf, cap, "%s:%u:%g:%u", clvr_render_estimator_name(v->estimator), v->urm_steps,
                               (double)v->urm_kappa, v->light_res);
    else if (v->urm_steps) snprintf(buf, cap, "%s:%u:%g", clvr_render_estimator_name(v->estimator), v->urm_steps,
                               (double)v->urm_kappa);
    else snprintf(buf, cap, "%s", clvr_render_estimator_name(v->estimator));
    if (v->adaptive >= 0.0f) {
        const size_t l = strlen(buf);
        snprintf(buf + l, cap - l, "@%g", (double)v->adaptive);
    }
}

typedef struct conv_ref {
    int shadows;
    float *img;                     /* reference mean image */
    uint8_t *inside;                /* per pixel: camera ray enters the bounding box */
    size_t ninside;
    double ref_s, ref_mean, ref_var; /* device time, mean inside rgb, its own noise (variance of the mean) */
    double bias_rel;                /* --denoise: rel RMSE of the denoised reference against itself (NaN otherwise) */
} conv_ref;

typedef struct conv_result {
    int shadows;
    uint32_t estimator;
    char label[48];
    double frame_s;                 /* mean device time of one frame (the light grid apart) */
    double light_s;                 /* device time of the light grid (urm with shadows: once, before the first frame) */
    double samples_per_ray, rays_per_pixel; /* rays per pixel: per sample */
    double spp_per_frame;           /* samples per pixel a frame and its refine pass add */
    double refine_fraction;         /* adaptive sampling: pixels a refine pass renders / all pixels */
    double adaptive;                /* its threshold (0: off) */
    uint32_t npoints;
    conv_point pts[MAX_POINTS];
    int reached;
    conv_point at;                  /* first checkpoint at or below the target */
    int reached_dn;                 /* --denoise: the same for the denoised image */
    conv_point at_dn;
    double dn_s;                    /* --denoise: wall seconds of one denoiser run (the last) */
    double fit_spp, fit_s;          /* 1/n fit; NaN where there was nothing to fit */
    double load_before, load_after;
    uint32_t nrep;                  /* --repeats: runs behind the row (the median's) */
    double rep_s[MAX_REPEATS];      /* each run's device seconds to the target, NaN where missed */
    int picked;                     /* auto's pilot ran (clvr_renderer_pick): pick holds it (the last run's) */
    clvr_render_pick pick;
    double pilot_s;
} conv_result;

/* Mean squared error over the inside pixels' rgb of img against the reference. */
static double inside_mse(const float *img, const conv_ref *ref, size_t npix)
{
    double mse = 0.0;
    for (size_t p = 0; p < npix; ++p) {
        if (!ref->inside[p]) continue;
        for (int k = 0; k < 3; ++k) {
            const size_t i = 4 * p + (size_t)k;
            double d = (double)img[i] - (double)ref->img[i];
            mse += d * d;
        }
    }
    return ref->ninside ? mse / (3.0 * (double)ref->ninside) : 0.0;
}

/* The renderer's image denoised into out (clvr_denoise_renderer; the
 * default parameters, or CLVR_DN=sigma_l,sigma_a,sigma_d,passes for tuning). */
static clvr_status denoised_image(clvr_renderer *rd, clvr_denoiser *dn, uint32_t w, uint32_t h, float *out,
                                  double *wall_s, clvr_error *err)
{
    clvr_dn_params prm = clvr_dn_params_default();
    const char *ev = getenv("CLVR_DN");
    if (ev) sscanf(ev, "%f,%f,%f,%u", &prm.sigma_l, &prm.sigma_a, &prm.sigma_d, &prm.passes);
    const double t0 = clvr_clock_monotonic_s();
    clvr_status s = clvr_denoise_renderer(dn, rd, w, h, prm, out, err);
    if (wall_s) *wall_s = clvr_clock_monotonic_s() - t0;
    return s;
}

static clvr_status converge_reference(clvr_cl *cl, scene_gpu *g, const config *base, int shadows, uint32_t w,
                                      uint32_t h, uint32_t ref_spp, clvr_denoiser *dn, conv_ref *out,
                                      clvr_camera *cam, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_renderer *rd = NULL;
    const size_t npix = (size_t)w * h, nf = npix * 4;
    float *sum = malloc(nf * sizeof(float)), *sq = malloc(nf * sizeof(float));
    memset(out, 0, sizeof *out);
    out->shadows = shadows;
    out->img = malloc(nf * sizeof(float));
    out->inside = malloc(npix);
    config c = *base;
    c.shadows = shadows;
    /* Independent frames: the reference's own noise, subtracted below, is
     * estimated from its per-pixel moments, which needs them. */
    c.sampler = CLVR_SAMPLER_INDEPENDENT;
    /* Plain box samples: the measured runs' control variate is checked
     * against an image made without it. */
    c.no_pixel_cv = 1;
    /* Every pixel the same count of samples: its moments are per frame. */
    c.adaptive = 0.0f;
    if (!sum || !sq || !out->img || !out->inside) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_render: out of memory");
        goto done;
    }
    s = renderer_for(cl, g, &c, w, h, 0x5eed, &rd, cam, err);
    for (uint32_t i = 0; s == CLVR_OK && i < ref_spp; ++i) s = clvr_renderer_frame(rd, err);
    clvr_render_counters rc;
    if (s == CLVR_OK) s = clvr_renderer_read(rd, out->img, &rc, err);
    if (s == CLVR_OK) s = clvr_renderer_read_moments(rd, sum, sq, err);
    if (s != CLVR_OK) goto done;
    out->ref_s = rc.kernel_s;
    double var = 0.0, mean = 0.0;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const size_t p = (size_t)y * w + x;
            float o[3], d[3];
            clvr_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, o, d);
            out->inside[p] = (uint8_t)clvr_ray_hits_box(o, d, g->lo, g->hi);
            if (!out->inside[p]) continue;
            out->ninside++;
            for (int k = 0; k < 3; ++k) {
                const size_t i = 4 * p + (size_t)k;
                double mu = sum[i] / ref_spp, v = (sq[i] / ref_spp - mu * mu) / (ref_spp - 1);
                var += v > 0 ? v : 0;
                mean += out->img[i];
            }
        }
    if (out->ninside) {
        var /= 3.0 * (double)out->ninside;
        mean /= 3.0 * (double)out->ninside;
    }
    out->ref_var = var;
    out->ref_mean = mean;
    out->bias_rel = NAN;
    if (dn) {
        /* The denoiser's bias: what it changes in an image that is already
         * converged (the reference, whose own noise is far below it). */
        s = denoised_image(rd, dn, w, h, sum, NULL, err);
        if (s != CLVR_OK) goto done;
        out->bias_rel = mean > 0 ? sqrt(inside_mse(sum, out, npix)) / mean : 0.0;
    }
done:
    clvr_renderer_destroy(rd);
    free(sum);
    free(sq);
    return s;
}

static clvr_status converge_one(clvr_cl *cl, scene_gpu *g, const config *c, const conv_ref *ref, uint32_t w,
                                uint32_t h, uint32_t max_spp, double target, clvr_denoiser *dn, uint64_t seed,
                                conv_result *out,
                                clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_renderer *rd = NULL;
    const size_t npix = (size_t)w * h;
    float *img = malloc(npix * 4 * sizeof(float)), *dimg = dn ? malloc(npix * 4 * sizeof(float)) : NULL;
    clvr_render_counters rc;
    memset(out, 0, sizeof *out);
    out->at.rmse_rel_dn = out->at_dn.rmse_rel_dn = NAN; /* not measured until a checkpoint says */
    out->shadows = c->shadows;
    out->estimator = c->estimator;
    out->adaptive = c->adaptive;
    out->load_before = bench_load1();
    if (!img || (dn && !dimg)) {
        free(img);
        free(dimg);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_render: out of memory");
    }
    s = renderer_for(cl, g, c, w, h, seed, &rd, NULL, err);
    double wall = 0.0, fit_acc = 0.0;
    uint32_t fit_n = 0, next = 1;
    for (uint32_t n = 1; s == CLVR_OK && n <= max_spp; ++n) {
        const int check = n == next;
        if (check) {
            /* checkpoints every frame up to 16, then in steps of n/16 (about 6%) */
            next = n < 16 ? n + 1 : n + n / 16;
            if (next > max_spp && n < max_spp) next = max_spp;
        }
        /* The frame, then (adaptive sampling) its refine pass: a checkpoint
         * after each, so that the figure sees the image a reader could stop
         * at. */
        for (int half = 0; half < 2 && s == CLVR_OK; ++half) {
            if (half && !(c->adaptive > 0.0f)) break;
            double t0 = clvr_clock_monotonic_s();
            s = half ? clvr_renderer_refine(rd, err) : clvr_renderer_full_frame(rd, err);
            wall += clvr_clock_monotonic_s() - t0;
            if (s != CLVR_OK || !check) continue;
            s = clvr_renderer_read(rd, img, &rc, err);
            if (s != CLVR_OK) break;
            const double mse = inside_mse(img, ref, npix);
            /* The image pass (the control variates), the choice of the
             * refine list and auto's pilot (host seconds, its kernels
             * included) are part of what a reader waits for. */
            conv_point pt = {n, half, n + (double)rc.refine_samples / (double)npix,
                             rc.kernel_s + rc.image_s + rc.select_s + rc.pilot_s, wall + rc.image_s, sqrt(mse),
                             sqrt(mse > ref->ref_var ? mse - ref->ref_var : 0.0), 0.0, NAN};
            pt.rmse_rel = ref->ref_mean > 0 ? pt.rmse / ref->ref_mean : 0.0;
            if (dn) {
                s = denoised_image(rd, dn, w, h, dimg, &out->dn_s, err);
                if (s != CLVR_OK) break;
                const double md = inside_mse(dimg, ref, npix);
                pt.rmse_rel_dn = ref->ref_mean > 0 ? sqrt(md > ref->ref_var ? md - ref->ref_var : 0.0) / ref->ref_mean : 0.0;
                if (!out->reached_dn && pt.rmse_rel_dn <= target) { out->reached_dn = 1; out->at_dn = pt; }
            }
            if (out->npoints < MAX_POINTS) out->pts[out->npoints++] = pt;
            /* Fit mse * samples over the frames' own checkpoints with n >= 4. */
            if (n >= 4 && !half) {
                fit_acc += (pt.rmse_rel * pt.rmse_rel) * pt.spp_mean;
                ++fit_n;
            }
            if (!out->reached && pt.rmse_rel <= target) { out->reached = 1; out->at = pt; }
        }
        if (out->reached && n >= 16) break;
    }
    if (s == CLVR_OK) s = clvr_renderer_read(rd, NULL, &rc, err);
    if (s != CLVR_OK) goto done;
    out->light_s = rc.light_s;
    out->picked = clvr_renderer_pick(rd, &out->pick);
    out->pilot_s = rc.pilot_s;
    out->frame_s = rc.frames ? (rc.kernel_s - rc.light_s) / (double)rc.frames : 0.0;
    out->samples_per_ray = rc.rays ? (double)rc.samples / (double)rc.rays : 0.0;
    {
        /* Per sample: a frame's refine pass adds samples to some pixels. */
        const double samples = (double)rc.frames * (double)npix + (double)rc.refine_samples;
        out->rays_per_pixel = samples > 0 ? (double)rc.rays / samples : 0.0;
        out->spp_per_frame = rc.frames ? samples / ((double)rc.frames * (double)npix) : 1.0;
        out->refine_fraction = rc.refine_passes ? (double)rc.refine_pixels / (double)npix : 0.0;
    }
    /* No error above the reference's own noise at any of the fit's
     * checkpoints (the target met from the first): nothing to fit, NaN (not
     * 0 spp). The fit's seconds count what the measured time to the target
     * counts (conv_point.dev_s): the frames, and once each the light grid,
     * auto's pilot, the refine list and the image pass. */
    out->fit_spp = out->fit_s = NAN;
    if (fit_n && fit_acc > 0.0) {
        out->fit_spp = fit_acc / fit_n / (target * target);
        out->fit_s = out->light_s + rc.pilot_s + rc.select_s + rc.image_s +
                     out->fit_spp / out->spp_per_frame * out->frame_s;
    }
    out->load_after = bench_load1();
done:
    clvr_renderer_destroy(rd);
    free(img);
    free(dimg);
    return s;
}

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; ++s) {
        if (*s == '"' || *s == '\\') fputc('\\', f);
        if ((unsigned char)*s >= 0x20) fputc(*s, f);
    }
    fputc('"', f);
}

static void json_point(FILE *f, const conv_point *p)
{
    fprintf(f, "{\"spp\": %.4g, \"frames\": %u, \"refined\": %d, \"device_s\": %.6g, \"wall_s\": %.6g, "
               "\"rmse_raw\": %.6g, \"rmse\": %.6g, \"rmse_rel\": %.6g",
            p->spp_mean, p->spp, p->refined, p->dev_s, p->wall_s, p->rmse_raw, p->rmse, p->rmse_rel);
    if (isfinite(p->rmse_rel_dn)) fprintf(f, ", \"rmse_rel_denoised\": %.6g", p->rmse_rel_dn);
    fprintf(f, "}");
}

/* A number, or null where it is NaN (no value, not 0). */
static void json_num(FILE *f, const char *key, double v)
{
    if (isnan(v)) fprintf(f, "\"%s\": null, ", key);
    else fprintf(f, "\"%s\": %.6g, ", key, v);
}

/* Device seconds of a measured run at its last checkpoint. */
static double conv_last_s(const conv_result *r) { return r->pts[r->npoints ? r->npoints - 1 : 0].dev_s; }

/* Order of measured runs: by time to the target; a run that missed it after
 * every run that reached it, by its 1/n fit. (1e30 + fit_s, the key before,
 * is 1e30 in double: missed runs tied, in seed order.) */
static int conv_before(const conv_result *a, const conv_result *b)
{
    if (a->reached != b->reached) return a->reached;
    return a->reached ? a->at.dev_s < b->at.dev_s : a->fit_s < b->fit_s;
}

static int run_converge(clvr_cl *cl, const char *mesh, const config *base, const est_variant *est, uint32_t nest,
                        int sh_lo, int sh_hi, uint32_t w, uint32_t h, uint32_t ref_spp, uint32_t max_spp,
                        double target, float density, uint32_t repeats, const char *json)
{
    static conv_result runs[MAX_REPEATS]; /* large (their checkpoints); one converge per process */
    clvr_error err = {0};
    scene_gpu g;
    conv_ref refs[2] = {{0}, {0}};
    conv_result res[2][MAX_EST];
    clvr_camera cam;
    clvr_denoiser *dn = NULL;
    int rc = 1;
    char dtext[512];
    printf("# bench_render --converge: %s, %s, %ux%u, density %s, reference %u spp (%s, independent frames), "
           "measured runs: %s sampler, target %.3g relative RMSE, %s pixel filter\n", base_name(mesh),
           clvr_render_method_name(base->method), w, h,
           density_text(density, g_like.set ? g_like.path : NULL, dtext, sizeof dtext), ref_spp,
           clvr_render_estimator_name(base->estimator), base->sampler == CLVR_SAMPLER_LD ? "ld" : "independent",
           target, base->pixel_filter == CLVR_PIXEL_POINT ? "point" : "box");
    printf("# device: %s | %s | %s | driver %s\n\n", cl->device_name, cl->platform_name, cl->device_version,
           cl->driver_version);
    fflush(stdout);
    if (scene_load(cl, mesh, density, &g, &err) != CLVR_OK) {
        fprintf(stderr, "bench_render: %s\n", err.msg);
        return 1;
    }
    if (base->guides && clvr_denoiser_create(cl, &dn, &err) != CLVR_OK) goto fail;
    for (int sh = sh_lo; sh <= sh_hi; ++sh) {
        if (converge_reference(cl, &g, base, sh, w, h, ref_spp, dn, &refs[sh], &cam, &err) != CLVR_OK) goto fail;
        fprintf(stderr, "bench_render: reference shadows=%d done (%.1f s device)\n", sh, refs[sh].ref_s);
        for (uint32_t e = 0; e < nest; ++e) {
            config c = *base;
            c.shadows = sh;
            c.estimator = est[e].estimator;
            if (est[e].urm_steps) c.urm_steps = est[e].urm_steps;
            if (est[e].urm_kappa > 0.0f) c.urm_kappa = est[e].urm_kappa;
            if (est[e].light_res) c.light_res = est[e].light_res;
            if (est[e].adaptive >= 0.0f) c.adaptive = est[e].adaptive;
            uint32_t order[MAX_REPEATS], nrun = repeats;
            /* One untimed frame first (its own seed): a device compiles a
             * kernel for each new launch shape at its first launch (PoCL:
             * the pilot's and the refine pass's 1-D ranges; 2.4 s on the
             * notch after a kernel change, once per kernel version), which
             * is not rendering; VTK's median frame leaves out its first. */
            if (converge_one(cl, &g, &c, &refs[sh], w, h, 1, target, dn, 0x9e3779b9u, &runs[0], &err) != CLVR_OK)
                goto fail;
            for (uint32_t k = 0; k < nrun; ++k) {
                if (converge_one(cl, &g, &c, &refs[sh], w, h, max_spp, target, dn, 1 + k, &runs[k], &err) != CLVR_OK)
                    goto fail;
                /* A run of more than CONV_REPEAT_MAX_S device seconds averages
                 * its frames' noise already: one is enough (delta runs to
                 * hundreds of spp would triple the bench's time). */
                if (k == 0 && (runs[0].reached ? runs[0].at.dev_s : conv_last_s(&runs[0])) > CONV_REPEAT_MAX_S)
                    nrun = 1;
                /* insertion by rank: the median run is order[(nrun - 1) / 2] */
                uint32_t j = k;
                for (; j > 0 && conv_before(&runs[k], &runs[order[j - 1]]); --j) order[j] = order[j - 1];
                order[j] = k;
            }
            res[sh][e] = runs[order[(nrun - 1) / 2]];
            res[sh][e].nrep = nrun;
            for (uint32_t k = 0; k < nrun; ++k) res[sh][e].rep_s[k] = runs[k].reached ? runs[k].at.dev_s : NAN;
            variant_label(&est[e], res[sh][e].label, sizeof res[sh][e].label);
            fprintf(stderr, "bench_render: %s shadows=%d done\n", res[sh][e].label, sh);
        }
    }
    printf("| estimator | shadows | elements | frame ms | light grid ms | samples/ray | lookups/pixel to %g%% | "
           "ref mean rgb (inside) | ref own rel RMSE | refined pixels | spp to %g%% rel | s to %g%% rel (device) | "
           "s (wall) | 1/n fit spp | fit s (device) | load |\n",
           target * 100, target * 100, target * 100);
    printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int sh = sh_lo; sh <= sh_hi; ++sh)
        for (uint32_t e = 0; e < nest; ++e) {
            const conv_result *r = &res[sh][e];
            const double last_spp = r->npoints ? r->pts[r->npoints - 1].spp_mean : (double)max_spp;
            char fit_spp[32] = "-", fit_s[32] = "-";
            if (!isnan(r->fit_spp)) {
                /* under one frame: below every checkpoint, the target met at the first */
                snprintf(fit_spp, sizeof fit_spp, r->fit_spp < 1.0 ? "<1" : "%.1f", r->fit_spp);
                snprintf(fit_s, sizeof fit_s, "%.3f", r->fit_s);
            }
            printf("| %s | %s | %" PRIu64 " | %.1f | %.1f | %.2f | %s%.0f | %.4f | %.4f | %.1f%% | %s%.2f | %s%.3f | %.3f | "
                   "%s | %s | %.2f |\n",
                   r->label, sh ? "on" : "off", g.elements, r->frame_s * 1e3, r->light_s * 1e3, r->samples_per_ray,
                   r->reached ? "" : ">", r->samples_per_ray * r->rays_per_pixel * (r->reached ? r->at.spp_mean : last_spp),
                   refs[sh].ref_mean,
                   refs[sh].ref_mean > 0 ? sqrt(refs[sh].ref_var) / refs[sh].ref_mean : 0.0, 100.0 * r->refine_fraction,
                   r->reached ? "" : ">", r->reached ? r->at.spp_mean : last_spp, r->reached ? "" : ">",
                   r->reached ? r->at.dev_s : conv_last_s(r),
                   r->reached ? r->at.wall_s : NAN, fit_spp, fit_s, r->load_after);
        }
    printf("\nrel RMSE: linear rgb, unclamped, over pixels whose camera ray enters the bounding box (%zu of %u), "
           "reference noise subtracted, divided by the reference's mean rgb over the same pixels. 1/n fit: over "
           "the checkpoints from 4 frames on; its seconds count the light grid, pilot, refine list and image pass "
           "once, as the measured seconds do; \"<1\": under one spp, the target met from the first checkpoint; "
           "\"-\": no error above the reference's own noise there, nothing to fit.\n",
           refs[sh_lo].ninside, w * h);
    printf("Each row is the median of up to %u measured runs (seeds 1 .. %u; one where the first took over %.0f s) by "
           "time to %g%%; every run's seconds:", repeats, repeats, CONV_REPEAT_MAX_S, target * 100);
    for (int sh = sh_lo; sh <= sh_hi; ++sh)
        for (uint32_t e = 0; e < nest; ++e) {
            const conv_result *r = &res[sh][e];
            printf("%s %s shadows %s:", sh == sh_lo && e == 0 ? "" : ";", r->label, sh ? "on" : "off");
            for (uint32_t k = 0; k < r->nrep; ++k) printf(" %.3f", r->rep_s[k]);
        }
    printf(".\n");
    if (dn) {
        /* Apart from the table above, which is the unbiased estimate's. */
        printf("\n--denoise (biased, not the convergence figure): the same frames after the edge-avoiding filter "
               "(kernels/denoise.h). bias: rel RMSE of the denoised reference against the reference. spp: samples per "
               "pixel, as above; \">\": not reached by the run's last checkpoint (a run stops once the raw image "
               "reached the target).\n\n");
        printf("| estimator | shadows | bias (rel) | rel RMSE after 1 / 2 / 4 frames | denoised | spp to %g%% "
               "denoised | s to %g%% denoised (frames + one filter) | filter s (wall) |\n",
               target * 100, target * 100);
        printf("|---|---|---:|---|---|---:|---:|---:|\n");
        for (int sh = sh_lo; sh <= sh_hi; ++sh)
            for (uint32_t e = 0; e < nest; ++e) {
                const conv_result *r = &res[sh][e];
                char raw[64] = "", den[64] = "";
                for (uint32_t i = 0; i < r->npoints; ++i) {
                    const conv_point *p = &r->pts[i];
                    if ((p->spp != 1 && p->spp != 2 && p->spp != 4) || p->refined) continue;
                    const size_t lr = strlen(raw), ld = strlen(den);
                    snprintf(raw + lr, sizeof raw - lr, "%s%.2f%%", lr ? " / " : "", p->rmse_rel * 100);
                    snprintf(den + ld, sizeof den - ld, "%s%.2f%%", ld ? " / " : "", p->rmse_rel_dn * 100);
                }
                /* Samples per pixel, as the raw table's column. Missed: ">"
                 * the last checkpoint's, which is max_spp only when the run
                 * went that far (it stops once the raw image reached the
                 * target, and the denoised image was measured no further). */
                const double last_spp = r->npoints ? r->pts[r->npoints - 1].spp_mean : (double)max_spp;
                printf("| %s | %s | %.2f%% | %s | %s | %s%.2f | %s%.3f | %.3f |\n", r->label, sh ? "on" : "off",
                       refs[sh].bias_rel * 100, raw, den, r->reached_dn ? "" : ">",
                       r->reached_dn ? r->at_dn.spp_mean : last_spp, r->reached_dn ? "" : ">",
                       (r->reached_dn ? r->at_dn.dev_s : conv_last_s(r)) + r->dn_s,
                       r->dn_s);
            }
    }
    if (json) {
        FILE *f = fopen(json, "w");
        if (!f) {
            fprintf(stderr, "bench_render: cannot write %s\n", json);
            goto done;
        }
        fprintf(f, "{\"bench\": \"render_converge\", \"device\": ");
        json_str(f, cl->device_name);
        fprintf(f, ", \"driver\": ");
        json_str(f, cl->driver_version);
        fprintf(f, ", \"mesh\": ");
        json_str(f, mesh);
        fprintf(f, ", \"elements\": %" PRIu64 ", \"method\": \"%s\", \"width\": %u, \"height\": %u, \"ref_spp\": %u, "
                   "\"target\": %g, \"criterion\": \"relative RMSE over inside pixels, unclamped\", \"density\": %g, "
                   "\"inside_pixels\": %zu, \"preprocess_s\": %.6g, \"sampler\": \"%s\", \"ref_sampler\": \"independent\", "
                   "\"ref_estimator\": \"%s\", \"pixel_filter\": \"%s\",\n",
                g.elements, clvr_render_method_name(base->method), w, h, ref_spp, target, (double)density,
                refs[sh_lo].ninside, g.preprocess_s, base->sampler == CLVR_SAMPLER_LD ? "ld" : "independent",
                clvr_render_estimator_name(base->estimator), base->pixel_filter == CLVR_PIXEL_POINT ? "point" : "box");
        fprintf(f, " \"camera\": {\"eye\": [%.9g, %.9g, %.9g], \"target\": [%.9g, %.9g, %.9g], \"up\": [%.9g, %.9g, %.9g], "
                   "\"fovy\": %.9g},\n",
                cam.origin[0], cam.origin[1], cam.origin[2], cam.target[0], cam.target[1], cam.target[2], cam.up[0],
                cam.up[1], cam.up[2], cam.fovy);
        fprintf(f, " \"tf\": {\"range\": [%.9g, %.9g], \"density\": %.9g, \"table\": [", g.tf.range_lo, g.tf.range_hi,
                g.tf.density);
        for (uint32_t i = 0; i < g.table_n; ++i)
            fprintf(f, "%s[%.6g, %.6g, %.6g, %.6g]", i ? ", " : "", g.table[4 * i], g.table[4 * i + 1],
                    g.table[4 * i + 2], g.table[4 * i + 3] * g.tf.density);
        fprintf(f, "]},\n \"rows\": [");
        int first = 1;
        for (int sh = sh_lo; sh <= sh_hi; ++sh)
            for (uint32_t e = 0; e < nest; ++e) {
                const conv_result *r = &res[sh][e];
                fprintf(f, "%s\n  {\"estimator\": \"%s\", \"label\": \"%s\", \"shadows\": %d, \"frame_s\": %.6g, \"light_s\": %.6g, \"samples_per_ray\": %.6g, "
                           "\"rays_per_pixel\": %.6g, \"adaptive\": %.6g, \"refine_fraction\": %.6g, "
                           "\"reference_device_s\": %.6g, \"ref_mean\": %.6g, "
                           "\"ref_own_rmse\": %.6g, \"reached\": %d, \"load_before\": %.2f, \"load_after\": %.2f, ",
                        first ? "" : ",", clvr_render_estimator_name(r->estimator), r->label, sh, r->frame_s,
                        r->light_s, r->samples_per_ray, r->rays_per_pixel, r->adaptive, r->refine_fraction,
                        refs[sh].ref_s, refs[sh].ref_mean,
                        sqrt(refs[sh].ref_var), r->reached, r->load_before, r->load_after);
                json_num(f, "fit_spp", r->fit_spp);
                json_num(f, "fit_s", r->fit_s);
                if (dn) {
                    fprintf(f, "\"denoise_bias_rel\": %.6g, \"denoise_s\": %.6g, \"reached_denoised\": %d, ",
                            refs[sh].bias_rel, r->dn_s, r->reached_dn);
                    /* samples per pixel and frames, as "at"; null where it was missed */
                    if (r->reached_dn)
                        fprintf(f, "\"spp_denoised\": %.4g, \"frames_denoised\": %u, ", r->at_dn.spp_mean,
                                r->at_dn.spp);
                    else fprintf(f, "\"spp_denoised\": null, \"frames_denoised\": null, ");
                }
                if (r->picked)
                    fprintf(f, "\"pick\": {\"walk_cells\": %u, \"pixels\": %u, \"var\": [%.6g, %.6g], "
                               "\"work\": [%.6g, %.6g], \"pilot_s\": %.6g}, ",
                            r->pick.walk_cells, r->pick.pixels, r->pick.var[0], r->pick.var[1], r->pick.work[0],
                            r->pick.work[1], r->pilot_s);
                fprintf(f, "\"repeats_s\": [");
                for (uint32_t k = 0; k < r->nrep; ++k) {
                    if (isnan(r->rep_s[k])) fprintf(f, "%snull", k ? ", " : "");
                    else fprintf(f, "%s%.6g", k ? ", " : "", r->rep_s[k]);
                }
                fprintf(f, "], \"at\": ");
                first = 0;
                json_point(f, &r->at);
                fprintf(f, ", \"points\": [");
                for (uint32_t i = 0; i < r->npoints; ++i) {
                    if (i) fprintf(f, ", ");
                    json_point(f, &r->pts[i]);
                }
                fprintf(f, "]}");
            }
        fprintf(f, "\n]}\n");
        fclose(f);
    }
    rc = 0;
    goto done;
fail:
    fprintf(stderr, "bench_render: %s\n", err.msg);
done:
    for (int sh = 0; sh < 2; ++sh) {
        free(refs[sh].img);
        free(refs[sh].inside);
    }
    clvr_denoiser_destroy(dn);
    scene_release(cl, &g);
    return rc;
}

/* ---------------------------------------------------------------- main */

static int usage(void)
{
    fprintf(stderr,
            "usage: bench_render [--device SPEC] [--json FILE] [--mesh FILE ...] [--size WxH] [--frames N] [--warmup W]\n"
            "                    [--methods march,track,bins,dda] [--macrocells auto,A,B] [--no-shadows] [--budget S] [--density D|auto] [--quick]\n"
            "                    [--sampler ld|independent] [--no-hull] [--pixel-filter box|point]\n"
            "                    [--estimator auto|walk|urm|delta] [--urm-steps N] [--urm-kappa K] [--adaptive T]\n"
            "                    [--one-curve auto|on|off] [--like FILE]\n"
            "       bench_render --converge [--mesh FILE] [--size WxH] [--method dda] [--ref-spp R] [--target F]\n"
            "                    [--max-spp M] [--sampler ld|independent]\n"
            "                    [--estimators auto,walk,urm,delta[:steps[:kappa[:light-res]]]]\n"
            "                    [--ref-estimator urm|delta] [--density D] [--urm-steps N] [--urm-kappa K] [--json FILE]\n"
            "                    [--denoise] [--no-pixel-cv] [--adaptive T] [--repeats K] [--like FILE]\n"
            "  --like FILE: every mesh rendered with FILE's scalar range, box and camera (a uniform twin\n"
            "               at the graded mesh's optical depth); --density auto: clvr's automatic\n"
            "               density (of FILE with --like), else 1 (the default)\n");
    return 2;
}

int main(int argc, char **argv)
{
    const char *device = NULL, *json = NULL, *meshes[MAX_MESHES];
    const char *methods = "march,track,bins,dda", *macro = NULL;
    uint32_t sampler = CLVR_SAMPLER_LD, pixel_filter = CLVR_PIXEL_BOX;
    uint32_t nmesh = 0, w = 1024, h = 1024, frames = 5, warmup = 2, ref_spp = 256, max_spp = 1024, repeats = 3;
    uint32_t conv_method = CLVR_RENDER_DDA;
    clvr_render_settings defaults;
    clvr_render_settings_default(&defaults);
    uint32_t estimator = defaults.estimator, ref_estimator = CLVR_ESTIMATOR_URM, urm_steps = 0;
    est_variant conv_est[MAX_EST] = {{CLVR_ESTIMATOR_DELTA, 0, 0.0f, 0, -1.0f}, {CLVR_ESTIMATOR_URM, 0, 0.0f, 0, -1.0f}};
    uint32_t nconv_est = 2;
    int shadow_lo = 0, shadow_hi = 1;
    float urm_kappa = 0.0f;
    int quick = 0, shadows = 1, converge = 0, size_set = 0, frames_set = 0, no_hull = 0, denoise = 0, no_cv = 0;
    float adaptive = CLVR_ADAPTIVE_DEFAULT;
    double target = 0.02, budget = 30.0;
    float density = 1.0f;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--device") && v) device = argv[++i];
        else if (!strcmp(a, "--json") && v) json = argv[++i];
        else if (!strcmp(a, "--mesh") && v) {
            if (nmesh == MAX_MESHES) return usage();
            meshes[nmesh++] = argv[++i];
        } else if (!strcmp(a, "--size") && v) {
            if (sscanf(argv[++i], "%ux%u", &w, &h) != 2 || !w || !h || w > 16384 || h > 16384) return usage();
            size_set = 1;
        } else if (!strcmp(a, "--frames") && v) {
            frames = (uint32_t)atoi(argv[++i]);
            frames_set = 1;
        } else if (!strcmp(a, "--warmup") && v) warmup = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--methods") && v) methods = argv[++i];
        else if (!strcmp(a, "--macrocells") && v) macro = argv[++i];
        else if (!strcmp(a, "--budget") && v) budget = atof(argv[++i]);
        else if (!strcmp(a, "--density") && v) { /* auto: 0 */
            const char *dv = argv[++i];
            density = !strcmp(dv, "auto") ? 0.0f : (float)atof(dv);
            if (!(density >= 0.0f) || (density == 0.0f && strcmp(dv, "auto"))) return usage();
        }
        else if (!strcmp(a, "--no-shadows")) { shadows = 0; shadow_hi = 0; }
        else if (!strcmp(a, "--only-shadows")) shadow_lo = 1;
        else if (!strcmp(a, "--no-hull")) no_hull = 1;
        else if (!strcmp(a, "--like") && v) {
            clvr_error lerr = {0};
            const char *lp = argv[++i];
            if (like_load(lp, &g_like, &lerr) != CLVR_OK) {
                fprintf(stderr, "bench_render: --like %s: %s\n", lp, lerr.msg);
                return 1;
            }
        }
        else if (!strcmp(a, "--one-curve") && v) {
            const char *ov = argv[++i];
            if (!strcmp(ov, "auto")) g_one_curve = CLVR_ONE_CURVE_AUTO;
            else if (!strcmp(ov, "on")) g_one_curve = CLVR_ONE_CURVE_ON;
            else if (!strcmp(ov, "off")) g_one_curve = CLVR_ONE_CURVE_OFF;
            else return usage();
        }
        else if (!strcmp(a, "--denoise")) denoise = 1;
        else if (!strcmp(a, "--no-pixel-cv")) no_cv = 1;
        else if (!strcmp(a, "--adaptive") && v) {
            if (!parse_adaptive(argv[++i], &adaptive)) return usage();
        }
        else if (!strcmp(a, "--sampler") && v) {
            const char *sv = argv[++i];
            if (!strcmp(sv, "ld")) sampler = CLVR_SAMPLER_LD;
            else if (!strcmp(sv, "independent")) sampler = CLVR_SAMPLER_INDEPENDENT;
            else return usage();
        }
        else if (!strcmp(a, "--pixel-filter") && v) {
            const char *fv = argv[++i];
            if (!strcmp(fv, "box")) pixel_filter = CLVR_PIXEL_BOX;
            else if (!strcmp(fv, "point")) pixel_filter = CLVR_PIXEL_POINT;
            else return usage();
        }
        else if (!strcmp(a, "--quick")) quick = 1;
        else if (!strcmp(a, "--converge")) converge = 1;
        else if (!strcmp(a, "--method") && v) {
            if (!parse_method(argv[++i], &conv_method)) return usage();
        } else if (!strcmp(a, "--ref-spp") && v) ref_spp = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--max-spp") && v) max_spp = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--repeats") && v) {
            repeats = (uint32_t)atoi(argv[++i]);
            if (repeats < 1 || repeats > MAX_REPEATS) return usage();
        }
        else if (!strcmp(a, "--target") && v) target = atof(argv[++i]);
        else if (!strcmp(a, "--estimator") && v) {
            if ((estimator = clvr_render_estimator_from_name(argv[++i])) == CLVR_ESTIMATOR_COUNT) return usage();
        } else if (!strcmp(a, "--ref-estimator") && v) {
            if ((ref_estimator = clvr_render_estimator_from_name(argv[++i])) == CLVR_ESTIMATOR_COUNT) return usage();
        } else if (!strcmp(a, "--estimators") && v) {
            char buf[128];
            snprintf(buf, sizeof buf, "%s", argv[++i]);
            nconv_est = 0;
            for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
                if (nconv_est == MAX_EST || !parse_variant(t, &conv_est[nconv_est++])) return usage();
            }
            if (!nconv_est) return usage();
        } else if (!strcmp(a, "--urm-steps") && v) urm_steps = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--urm-kappa") && v) urm_kappa = (float)atof(argv[++i]);
        else return usage();
    }
    if (quick) {
        if (!size_set) w = h = 256;
        if (!frames_set) frames = 3;
        warmup = 1;
    }
    if (frames < 1 || !(density >= 0) || ref_spp < 2 || max_spp < 1 || !(target > 0)) return usage();
    static char notch[1024];
    if (!nmesh) {
        snprintf(notch, sizeof notch, "%s/tests/data/vtk/notch_stress.vtk", CLVR_SOURCE_DIR);
        meshes[nmesh++] = "default";
        meshes[nmesh++] = notch;
    }

    /* configurations: each method; dda once per grid size */
    config cfg[MAX_CONFIGS];
    uint32_t ncfg = 0;
    {
        char buf[256];
        snprintf(buf, sizeof buf, "%s", methods);
        for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
            uint32_t m;
            if (!parse_method(tok, &m)) return usage();
            if (m == CLVR_RENDER_DDA) {
                char mb[128];
                snprintf(mb, sizeof mb, "%s", macro ? macro : "auto,32,128");
                for (char *save = NULL, *t = strtok_r(mb, ",", &save); t && ncfg < MAX_CONFIGS;
                     t = strtok_r(NULL, ",", &save)) {
                    const int automatic = !strcmp(t, "auto");
                    config c = {m, automatic ? 0 : (uint32_t)atoi(t), shadows, "", sampler, estimator, urm_steps, urm_kappa, 0, no_hull,
                                pixel_filter, 0, no_cv, adaptive};
                    if (!automatic && (c.macrocells < 1 || c.macrocells > 1024)) return usage();
                    if (c.macrocells) snprintf(c.label, sizeof c.label, "dda %u^3", c.macrocells);
                    else snprintf(c.label, sizeof c.label, "dda auto");
                    cfg[ncfg++] = c;
                }
            } else if (ncfg < MAX_CONFIGS) {
                config c = {m, 0, shadows && m != CLVR_RENDER_MARCH, "", sampler, estimator, urm_steps, urm_kappa, 0,
                            no_hull, pixel_filter, 0, no_cv, adaptive};
                snprintf(c.label, sizeof c.label, "%s", clvr_render_method_name(m));
                cfg[ncfg++] = c;
            }
        }
    }

    clvr_cl cl;
    clvr_error err = {0};
    if (clvr_cl_create(device, &cl, &err) != CLVR_OK) {
        fprintf(stderr, "bench_render: %s\n", err.msg);
        return 77; /* no OpenCL device: ctest counts the smoke test as skipped */
    }
    if (converge) {
        const config base = {conv_method, macro && strcmp(macro, "auto") ? (uint32_t)atoi(macro) : 0, 1, "", sampler, ref_estimator, urm_steps, urm_kappa, 0,
                             no_hull, pixel_filter, denoise, no_cv, adaptive};
        int rc = run_converge(&cl, meshes[0], &base, conv_est, nconv_est, shadow_lo, shadow_hi, size_set ? w : 512, size_set ? h : 512,
                              ref_spp, max_spp, target, density, repeats, json);
        clvr_cl_destroy(&cl);
        return rc;
    }

    char dtext[512];
    printf("# bench_render: %ux%u, 1 spp per frame, %u warm-up + median of %u frames (fewer past %g s), shadows %s, "
           "default transfer function, density %s%s\n",
           w, h, warmup, frames, budget, shadows ? "on (march: off)" : "off",
           density_text(density, g_like.set ? g_like.path : NULL, dtext, sizeof dtext), quick ? " (quick)" : "");
    printf("# device: %s | %s | %s | driver %s | %u compute units\n\n", cl.device_name, cl.platform_name,
           cl.device_version, cl.driver_version, cl.compute_units);
    printf("| mesh | elements | method | shadows | fps | Mrays/s | ms/frame (min-max) | frames | rays/frame | samples/ray | "
           "null collisions/ray | load |\n");
    printf("|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    fflush(stdout);

    row *rows = calloc((size_t)nmesh * ncfg, sizeof *rows);
    uint32_t nrows = 0;
    int rc = 0;
    for (uint32_t mi = 0; mi < nmesh && !rc; ++mi) {
        scene_gpu g;
        fprintf(stderr, "bench_render: loading %s\n", meshes[mi]);
        if (scene_load(&cl, meshes[mi], density, &g, &err) != CLVR_OK) {
            fprintf(stderr, "bench_render: %s\n", err.msg);
            rc = 1;
            break;
        }
        fprintf(stderr, "bench_render: %s: %" PRIu64 " elements, preprocessing %.2f s\n", meshes[mi], g.elements,
                g.preprocess_s);
        const uint32_t first = nrows;
        for (uint32_t ci = 0; ci < ncfg; ++ci) {
            row *r = &rows[nrows];
            r->mesh = strcmp(meshes[mi], "default") ? base_name(meshes[mi]) : "default scene";
            r->elements = g.elements;
            r->preprocess_s = g.preprocess_s;
            if (bench_one(&cl, &g, &cfg[ci], w, h, warmup, frames, budget, r, &err) != CLVR_OK) {
                fprintf(stderr, "bench_render: %s, %s: %s\n", meshes[mi], cfg[ci].label, err.msg);
                rc = 1;
                break;
            }
            /* The smoke contract: finite, positive numbers (not timings). */
            if (!(r->fps > 0) || !isfinite(r->fps) || !(r->mrays_s > 0) || !isfinite(r->mrays_s) ||
                !(r->rays_per_frame >= (double)w * h * 0.5) || !isfinite(r->image_mean) || !(r->image_mean > 0) ||
                !(r->samples_per_ray >= 0) || !isfinite(r->samples_per_ray)) {
                fprintf(stderr,
                        "bench_render: %s, %s: implausible result: fps %g, Mrays/s %g, rays/frame %g (pixels %u), "
                        "image mean %g, samples/ray %g\n",
                        r->mesh, cfg[ci].label, r->fps, r->mrays_s, r->rays_per_frame, w * h, r->image_mean,
                        r->samples_per_ray);
                rc = 1;
            }
            printf("| %s | %" PRIu64 " | %s | %s | %.3g | %.3g | %.1f (%.1f-%.1f) | %u | %.0f | %.2f | %.2f | %.2f |\n",
                   r->mesh, r->elements, r->c.label, r->c.shadows ? "on" : "off", r->fps, r->mrays_s, r->frame_s * 1e3,
                   r->frame_min_s * 1e3, r->frame_max_s * 1e3, r->frames, r->rays_per_frame, r->samples_per_ray,
                   r->nulls_per_ray, r->load_after);
            fflush(stdout);
            ++nrows;
        }
        /* dda vs track on this mesh, the adaptive sampling's gain */
        const row *tr = NULL, *best = NULL;
        for (uint32_t i = first; i < nrows; ++i) {
            if (rows[i].c.method == CLVR_RENDER_TRACK) tr = &rows[i];
            if (rows[i].c.method == CLVR_RENDER_DDA && (!best || rows[i].fps > best->fps)) best = &rows[i];
        }
        if (tr && best)
            printf("| %s | | %s / track | | **%.2fx** | | | | | | | |\n", tr->mesh, best->c.label, best->fps / tr->fps);
        scene_release(&cl, &g);
    }

    if (json && nrows) {
        FILE *f = fopen(json, "w");
        if (!f) {
            fprintf(stderr, "bench_render: cannot write %s\n", json);
            rc = 1;
        } else {
            fprintf(f, "{\"bench\": \"render\", \"device\": ");
            json_str(f, cl.device_name);
            fprintf(f, ", \"platform\": ");
            json_str(f, cl.platform_name);
            fprintf(f, ", \"driver\": ");
            json_str(f, cl.driver_version);
            fprintf(f, ", \"width\": %u, \"height\": %u, \"warmup\": %u, \"frames\": %u, \"budget_s\": %g, \"density\": %g, \"quick\": %d, \"rows\": [",
                    w, h, warmup, frames, budget, density, quick);
            for (uint32_t i = 0; i < nrows; ++i) {
                const row *r = &rows[i];
                fprintf(f, "%s\n  {\"mesh\": ", i ? "," : "");
                json_str(f, r->mesh);
                fprintf(f, ", \"elements\": %" PRIu64 ", \"preprocess_s\": %.6g, \"method\": \"%s\", \"macrocells\": %u, "
                           "\"label\": \"%s\", \"shadows\": %d, \"frames\": %u, \"fps\": %.6g, \"mrays_per_s\": %.6g, \"frame_s\": %.6g, "
                           "\"frame_min_s\": %.6g, \"frame_max_s\": %.6g, \"wall_frame_s\": %.6g, \"rays_per_frame\": %.6g, "
                           "\"samples_per_ray\": %.6g, \"null_collisions_per_ray\": %.6g, \"image_mean\": %.6g, "
                           "\"load_before\": %.2f, \"load_after\": %.2f}",
                        r->elements, r->preprocess_s, clvr_render_method_name(r->c.method), r->c.macrocells, r->c.label,
                        r->c.shadows, r->frames, r->fps, r->mrays_s, r->frame_s, r->frame_min_s, r->frame_max_s, r->wall_frame_s,
                        r->rays_per_frame, r->samples_per_ray, r->nulls_per_ray, r->image_mean, r->load_before,
                        r->load_after);
            }
            fprintf(f, "\n]}\n");
            fclose(f);
        }
    }
    free(rows);
    clvr_cl_destroy(&cl);
    return rc;
}
