/* main.c: the clvr command line: load (or generate) a mesh, preprocess it
 * into Quick Clusters on the OpenCL device, build the two-level BVH, render
 * progressively and write the image and statistics. Only main() exits. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "clock.h"
#include "accel.h"
#include "camera.h"
#include "cl_context.h"
#include "cli.h"
#include "image.h"
#include "info.h"
#include "limits_check.h"
#include "mesh_io.h"
#include "outline.h"
#include "partition.h"
#include "preprocess.h"
#include "render.h"
#include "scene.h"
#include "series.h"
#include "stats.h"
#include "tf.h"
#include "tf_auto.h"
#ifdef CLVR_HAVE_VIEWER
#include "viewer.h"
#endif

/* Set by SIGINT/SIGTERM: the render loop stops after the current frame and
 * the image accumulated so far is written. A signal handler can only talk to
 * the program through a static flag; this is the one piece of global state. */
static volatile sig_atomic_t g_interrupted;

static void on_signal(int sig)
{
    (void)sig;
    g_interrupted = 1;
}

static int fail(const clvr_error *err)
{
    fprintf(stderr, "clvr: %s\n", err->msg);
    return clvr_status_exit_code(err->status);
}

/* Preprocesses a tiny mesh with every element type, so that the driver
 * compiles the preprocessing and BVH kernels now, not inside the timed
 * clustering of the real mesh. */
static clvr_status warm_up_kernels(clvr_cl *cl, const clvr_preprocess_options *po, clvr_error *err)
{
    clvr_scene_box_params bp;
    clvr_scene_box_params_init(&bp);
    bp.nx = bp.ny = bp.nz = 4;
    bp.mix = CLVR_SCENE_MIX_CYCLE;
    clvr_mesh tiny = {0};
    clvr_clustered tc = {0};
    clvr_accel ta = {0};
    clvr_status s = clvr_scene_box(&bp, &tiny, err);
    if (s == CLVR_OK) s = clvr_preprocess(cl, &tiny, po, &tc, err);
    if (s == CLVR_OK) s = clvr_accel_build(cl, &tc, &ta, err);
    clvr_accel_release(cl, &ta);
    clvr_clustered_release(cl, &tc);
    clvr_mesh_free(&tiny);
    return s;
}

/* Elements per preprocessing partition for the memory checks: the mesh
 * over --partitions K, or partition.h's default bound. */
static uint64_t part_elements(const clvr_options *o, uint64_t n)
{
    if (o->partitions) return (n + o->partitions - 1) / o->partitions;
    return n > CLVR_PARTITION_DEFAULT_ELEMENTS ? CLVR_PARTITION_DEFAULT_ELEMENTS : n;
}

/* Loads MESH or builds the default scene. */
static clvr_status load_mesh(const clvr_options *o, clvr_mesh *m, clvr_error *err)
{
    if (!o->mesh_path) return clvr_scene_default(m, err);
    clvr_load_options lo = {0};
    lo.scalar_name = o->scalar_name;
    lo.field_ranges = o->info; /* --info lists every array with its range */
    lo.cell_flat = o->cell_flat;
    return clvr_mesh_load(o->mesh_path, &lo, m, err);
}

int main(int argc, char **argv)
{
    clvr_options o;
    clvr_error err = {0};
    clvr_mesh mesh = {0};
    clvr_cl cl = {0};
    clvr_clustered clustered = {0};
    clvr_accel bvh = {0};
    clvr_renderer *renderer = NULL;
    clvr_tf tf = {0};
    float *table = NULL, *pixels = NULL;
    clvr_stats stats = {0};
    int cl_ready = 0, rc = 0;
    clvr_status s;

    s = clvr_cli_parse(argc, argv, &o, &err);
    if (s != CLVR_OK) {
        fprintf(stderr, "clvr: %s\n", err.msg);
        return clvr_status_exit_code(s);
    }
    if (o.help) { clvr_cli_print_help(stdout); return 0; }
    if (o.version) { printf("clvr %s\n", CLVR_VERSION); return 0; }
    if (o.list_devices) {
        s = clvr_cl_list_devices(stdout, &err);
        return s == CLVR_OK ? 0 : fail(&err);
    }
    /* A time series: every step through this main, one range and camera. */
    if (o.mesh_path && clvr_series_is(o.mesh_path)) return clvr_series_run(argc, argv, &o, main);
    if (o.kernel_dir) setenv("CLVR_KERNEL_DIR", o.kernel_dir, 1);
    /* Fail on an unwritable output before minutes of work, not after. */
    if (!o.info && !o.view) {
        s = clvr_image_check_output(o.output, &err);
        if (s != CLVR_OK) return fail(&err);
        if (o.legend && !clvr_image_is_png(o.output)) {
            fprintf(stderr, "clvr: --legend draws into PNG images; -o %s is not one: use -o NAME.png\n", o.output);
            return 2;
        }
    }
    /* --view without a display (or without the viewer) fails now, not after preprocessing. */
    if (o.view && !o.info) {
#ifdef CLVR_HAVE_VIEWER
        s = clvr_viewer_probe(&err);
        if (s != CLVR_OK) return fail(&err);
#else
        fprintf(stderr, "clvr: clvr was built without the viewer (GLFW not found); render to a file with -o\n");
        return 1;
#endif
    }

    /* --- mesh. On a CPU device the device's memory is the host's: a mesh
     * that cannot fit is refused from the .bin header, before it is read
     * (not by the OOM killer or an allocation failure inside the driver). */
    if (o.mesh_path && !o.info) {
        uint64_t hv = 0, hc[CLVR_CELL_TYPE_COUNT] = {0};
        clvr_error perr = {0};
        if (clvr_mesh_peek_bin(o.mesh_path, &hv, hc, &perr) == CLVR_OK) {
            uint64_t n = 0;
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n += hc[t];
            clvr_mem_limits ml;
            clvr_mem_limits_read(&ml);
            s = clvr_limits_check_host(o.mesh_path, hv, hc, part_elements(&o, n), o.width, o.height, 0, &ml, &err);
            if (s != CLVR_OK) return fail(&err);
        }
    }
    double t0 = clvr_clock_monotonic_s();
    if (!o.quiet && !o.info) fprintf(stderr, "clvr: loading %s\n", o.mesh_path ? o.mesh_path : "the built-in scene");
    s = load_mesh(&o, &mesh, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    stats.load_s = clvr_clock_monotonic_s() - t0;
    const char *mesh_name = o.mesh_path ? o.mesh_path : "(built-in default scene)";
    if (o.info) {
        clvr_info_print(stdout, mesh_name, &mesh);
        if (o.stats_json) {
            stats.have_mesh = 1;
            clvr_stats_from_mesh(&stats, &mesh);
            s = clvr_stats_write_json(o.stats_json, &stats, &err);
            if (s != CLVR_OK) rc = fail(&err);
        }
        goto cleanup;
    }

    /* Flaws that render anyway (degenerate, inverted, duplicate elements, a
     * constant field) get one warning line each; clvr-convert already said
     * them once per file, so --quiet silences them on every render. */
    if (!o.quiet) {
        clvr_limits_report lr;
        clvr_limits_scan(&mesh, &lr);
        clvr_limits_print_warnings(stderr, mesh_name, &lr);
        if (mesh.skipped_cells)
            fprintf(stderr,
                    "clvr: warning: %s: %llu cell%s of other types (surface, line or polyhedron cells) left out; "
                    "clvr renders tetrahedra, pyramids, wedges and hexahedra\n",
                    mesh_name, (unsigned long long)mesh.skipped_cells, mesh.skipped_cells == 1 ? "" : "s");
        if (mesh.decomposed_cells)
            fprintf(stderr, "clvr: %s: %llu polyhedr%s decomposed into tets and pyramids\n", mesh_name,
                    (unsigned long long)mesh.decomposed_cells, mesh.decomposed_cells == 1 ? "on" : "a");
    }

    /* The transfer function needs only the scalar range: load it now, so a
     * typo in --tf FILE fails before minutes of preprocessing. */
    s = clvr_tf_from_options(&tf, o.colormap, o.tf_file, o.range_set, o.range_lo, o.range_hi,
                             o.density_auto ? 1.0f : o.density, mesh.scalar_min, mesh.scalar_max, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    clvr_tf_set_extent(&tf, mesh.bounds_lo, mesh.bounds_hi);
    /* The automatic transfer function (tf_auto.h): opacity from the scalar's
     * volume histogram over the window, unless --opacity ramp or a file's
     * points; density from the optical depth of probe rays. */
    if (!o.opacity_ramp && !tf.opacity_set) {
        double hist[CLVR_TF_AUTO_BINS];
        clvr_tf_auto_histogram(&mesh, tf.range_lo, tf.range_hi, hist, CLVR_TF_AUTO_BINS);
        s = clvr_tf_auto_opacity(&tf, hist, CLVR_TF_AUTO_BINS, &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    }
    if (o.density_auto) {
        s = clvr_tf_auto_density(&mesh, &tf, &o.density, &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
        tf.density *= o.density;
        if (!o.quiet) fprintf(stderr, "clvr: automatic density %.3g (--density auto)\n", (double)o.density);
    }

    /* Other formats are checked once loaded (their headers do not give
     * every count), .bin files again with what is left now. */
    {
        clvr_mem_limits ml;
        clvr_mem_limits_read(&ml);
        s = clvr_limits_check_host(mesh_name, mesh.num_vertices, mesh.num_cells,
                                   part_elements(&o, clvr_mesh_num_elements(&mesh)), o.width, o.height, 1, &ml, &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    }

    /* --- device */
    s = clvr_cl_create(o.device, &cl, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    cl_ready = 1;
    cl.build_notice = !o.quiet;
    if (!o.quiet)
        fprintf(stderr, "clvr: %s: %llu elements on %s (%s)\n", mesh_name,
                (unsigned long long)clvr_mesh_num_elements(&mesh), cl.device_name, cl.platform_name);

    /* --- Quick Clusters */
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    po.leaf_size = o.leaf_size;
    if (o.sampling_size) po.sampling_size = o.sampling_size;
    /* A mesh or image the device cannot hold fails now, with the numbers,
     * not minutes into preprocessing. */
    s = clvr_limits_check_parts(&cl, &mesh, mesh_name, &po, part_elements(&o, clvr_mesh_num_elements(&mesh)), o.width,
                                o.height, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    /* Kernel compilation, timed apart from clustering: the programs'
     * builds, and PoCL's code generation at a kernel's first launch, which a
     * preprocessing of a 64-cube mesh of every type triggers (2.0 s of the
     * 2.4 s a cold cache added to the built-in scene's clustering; 0.08 s
     * with a warm cache). */
    double warm_s = clvr_clock_monotonic_s(), build0 = cl.build_s;
    s = warm_up_kernels(&cl, &po, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    warm_s = clvr_clock_monotonic_s() - warm_s - (cl.build_s - build0);
    t0 = clvr_clock_monotonic_s();
    build0 = cl.build_s;
    /* The statistics of the input, before preprocessing takes it apart. */
    stats.have_mesh = 1;
    clvr_stats_from_mesh(&stats, &mesh);
    /* Consumed: the element lists are given back partition by partition, so
     * the input shrinks while the clustered mesh grows (partition.h). */
    s = clvr_preprocess_partitioned(&cl, &mesh, &po, o.partitions, 0, 1, &clustered, &stats.partitions, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    /* What is left of the mesh (vertices) is not needed by the trees: give it
     * back before they are built. Its bounds and field name are kept. */
    float mesh_lo[3], mesh_hi[3];
    char legend_name[sizeof mesh.scalar_name];
    memcpy(mesh_lo, mesh.bounds_lo, sizeof mesh_lo);
    memcpy(mesh_hi, mesh.bounds_hi, sizeof mesh_hi);
    memcpy(legend_name, mesh.scalar_name, sizeof legend_name);
    clvr_mesh_free(&mesh);
    s = clvr_accel_build(&cl, &clustered, &bvh, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    /* Compiling kernels (seconds on a cold driver cache) is not clustering. */
    stats.preprocess_s = clvr_clock_monotonic_s() - t0 - (cl.build_s - build0);
    if (!o.quiet)
        fprintf(stderr,
                "clvr: clustered in %.2f s: %llu instance clusters (%llu with 16-bit indices), %llu leaf clusters, "
                "%llu sampling clusters\n",
                stats.preprocess_s, (unsigned long long)clustered.num_instances,
                (unsigned long long)clustered.num_instances16, (unsigned long long)clustered.num_leaves,
                (unsigned long long)clustered.num_sampling);
    clvr_stats_from_clusters(&stats, &clustered, &bvh);

    /* --- transfer function and camera */
    clvr_camera cam;
    if (o.camera_set) {
        s = clvr_camera_look_at(&cam, o.camera, o.camera + 3, o.camera + 6, o.fovy, o.width, o.height, &err);
    } else {
        clvr_camera_view view;
        clvr_camera_view_default(&view);
        memcpy(view.up, o.up, sizeof view.up);
        view.azimuth_deg = o.azimuth;
        view.elevation_deg = o.elevation;
        view.zoom = o.zoom;
        s = clvr_camera_frame_view(&cam, mesh_lo, mesh_hi, &view, o.fovy, o.width, o.height, &err);
    }
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    /* A turntable turns the eye about the look-at point's vertical: the
     * framing's up axis, or --camera's up vector. */
    const float *orbit_axis = o.camera_set ? o.camera + 6 : o.up;
    const float eye0[3] = {cam.origin[0], cam.origin[1], cam.origin[2]};
    const float target0[3] = {cam.target[0], cam.target[1], cam.target[2]};


    clvr_render_settings rs;
    clvr_render_settings_default(&rs);
    rs.method = (uint32_t)o.method;
    rs.width = o.width;
    rs.height = o.height;
    rs.seed = o.seed;
    rs.shadows = o.shadows && o.method != CLVR_RENDER_MARCH;
    rs.sampler = o.sampler;
    rs.estimator = o.estimator;
    rs.urm_steps = o.urm_steps;
    rs.step = o.step;
    rs.bins = o.bins;
    rs.segments = o.segments;
    rs.macrocells = o.macrocells;
    memcpy(rs.light_dir, o.light_dir, sizeof rs.light_dir);
    rs.light_intensity = o.light_intensity;
    rs.ambient = o.ambient;
    memcpy(rs.background, o.background, sizeof rs.background);
    if (o.clip_box_set) {
        memcpy(rs.clip_lo, o.clip_lo, sizeof rs.clip_lo);
        memcpy(rs.clip_hi, o.clip_hi, sizeof rs.clip_hi);
    }
    rs.num_clip_planes = o.num_clip_planes;
    memcpy(rs.clip_planes, o.clip_planes, sizeof rs.clip_planes);
    s = clvr_renderer_create(&cl, &clustered, &bvh, &rs, &renderer, &err);
    if (s == CLVR_OK) s = clvr_renderer_set_camera(renderer, &cam, &err);
    if (s == CLVR_OK) {
        uint32_t n = clvr_tf_table_size(&tf);
        table = malloc((size_t)n * 4 * sizeof(float));
        if (!table) s = clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for the transfer function");
        else {
            clvr_tf_bake(&tf, table, n);
            s = clvr_renderer_set_tf(renderer, table, n, tf.range_lo, tf.range_hi, tf.density, &err);
        }
    }
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    /* The footprint the run keeps: mesh freed, clustered mesh, trees and
     * renderer in place (on a CPU device all of it host memory). */
    clvr_mem_rss(&stats.bytes_resident, NULL);
    stats.kernel_build_s = cl.build_s + warm_s;
    if (!o.quiet && cl.build_notice_shown)
        fprintf(stderr, "clvr: kernels compiled in %.2f s; later runs load them from the driver's cache\n",
                stats.kernel_build_s);

#ifdef CLVR_HAVE_VIEWER
    if (o.view) {
        s = clvr_viewer_run(&o, &cl, &clustered, renderer, &rs, &cam, &tf, &err);
        if (s != CLVR_OK) rc = fail(&err);
        goto cleanup;
    }
#endif

    /* --- progressive rendering: one image, or --orbit N turntable images */
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    size_t npix = (size_t)o.width * o.height;
    pixels = malloc(npix * 4 * sizeof(float));
    if (!pixels) { clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for the image"); rc = fail(&err); goto cleanup; }
    clvr_image_legend legend = {table, table ? clvr_tf_table_size(&tf) : 0, tf.range_lo, tf.range_hi, legend_name};
    clvr_image_display display = {o.exposure, (clvr_tonemap)o.tonemap, o.transparent, o.legend ? &legend : NULL};
    const uint32_t images = o.orbit ? o.orbit : 1;
    uint32_t frame = 0;
    for (uint32_t img = 0; img < images && !g_interrupted; ++img) {
        char numbered[4096];
        const char *path = o.output;
        if (o.orbit) {
            if (!clvr_image_numbered_path(o.output, img, numbered, sizeof numbered)) {
                clvr_error_set(&err, CLVR_ERR_USAGE, "-o %s: name too long for numbered --orbit frames; choose a shorter one",
                               o.output);
                rc = fail(&err);
                goto cleanup;
            }
            path = numbered;
            if (img > 0) {
                float eye[3];
                clvr_camera_rotate_about(eye0, target0, orbit_axis, 360.0f * (float)img / (float)o.orbit, eye);
                s = clvr_camera_look_at(&cam, eye, target0, orbit_axis, o.fovy, o.width, o.height, &err);
                if (s == CLVR_OK) s = clvr_renderer_set_camera(renderer, &cam, &err);
                if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
            }
        }
        double start = clvr_clock_monotonic_s(), last_report = start;
        for (frame = 0; frame < o.spp && !g_interrupted; ++frame) {
            s = clvr_renderer_frame(renderer, &err);
            if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
            double t = clvr_clock_monotonic_s();
            if (!o.quiet && (t - last_report > 1.0 || frame + 1 == o.spp)) {
                double per = (t - start) / (frame + 1);
                if (o.orbit)
                    fprintf(stderr, "clvr: image %u/%u, frame %u/%u, %.2f s/frame\n", img + 1, images, frame + 1,
                            o.spp, per);
                else
                    fprintf(stderr, "clvr: frame %u/%u, %.2f s/frame, %.0f s left\n", frame + 1, o.spp, per,
                            per * (o.spp - frame - 1));
                last_report = t;
            }
        }
        stats.render_wall_s += clvr_clock_monotonic_s() - start;
        if (frame == 0) { /* interrupted before the image's first frame finished */
            fprintf(stderr, "clvr: interrupted before the first frame of %s; not written\n", path);
            rc = 130;
            goto cleanup;
        }
        clvr_render_counters counters;
        s = clvr_renderer_read(renderer, pixels, &counters, &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
        if (o.outline) {
            /* Context for the volume: the mesh's bounds in light grey, the
             * clip box in amber; about one pixel per 400 of image height. */
            const float grey[3] = {0.8f, 0.8f, 0.8f}, amber[3] = {1.0f, 0.55f, 0.1f};
            const float lw = fmaxf(1.0f, (float)o.height / 400.0f);
            clvr_outline_draw_box(pixels, &cam, clustered.bounds.lo, clustered.bounds.hi, grey, lw);
            if (o.clip_box_set) clvr_outline_draw_box(pixels, &cam, o.clip_lo, o.clip_hi, amber, lw);
        }
        s = clvr_image_write_display(path, o.width, o.height, pixels, &display, &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
        stats.have_render = 1;
        clvr_stats_from_render(&stats, &counters, (uint32_t)o.method, o.width, o.height);
        if (!o.quiet) fprintf(stderr, "clvr: wrote %s (%ux%u, %u spp)\n", path, o.width, o.height, frame);
    }
    clvr_mem_rss(NULL, &stats.bytes_peak_rss);
    if (o.stats) clvr_stats_print(stdout, &stats);
    if (o.stats_json) {
        s = clvr_stats_write_json(o.stats_json, &stats, &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    }
    if (g_interrupted) {
        fprintf(stderr, "clvr: interrupted after %u of %u frames; the image holds what was accumulated\n", frame,
                o.spp);
        rc = 130;
    }

cleanup:
    free(pixels);
    free(table);
    clvr_renderer_destroy(renderer);
    if (cl_ready) {
        clvr_accel_release(&cl, &bvh);
        clvr_clustered_release(&cl, &clustered);
    }
    clvr_tf_free(&tf);
    clvr_cl_destroy(&cl);
    clvr_mesh_free(&mesh);
    return rc;
}
