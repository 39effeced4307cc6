/* main.c: the clvr command line: load (or generate) a mesh, preprocess it
 * into Quick Clusters on the OpenCL device, build the two-level BVH, render
 * progressively and write the image and statistics. Only main() exits.
 * Everything goes through libclvr's public API (clvr.h), the code Python
 * and C callers use, so the program and the library cannot drift apart;
 * tests/test_app_includes.sh keeps it that way. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "clvr.h"
#include "cli.h"
#include "info.h"
#include "message.h"
#include "series.h"
#include "stats.h"
#ifdef CLVR_HAVE_VIEWER
#include "viewer.h"
#endif
#ifdef CLVR_HAVE_MPI
#include "clvr_mpi.h"
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

/* A failed library call: its one-line message and the program's exit code. */
static int fail_msg(const clvr_message *msg)
{
    fprintf(stderr, "clvr: %s\n", msg->text);
    return clvr_result_exit_code(msg->result);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define TRY(call)                                                                                                     \
    do {                                                                                                              \
        if ((call) != CLVR_RESULT_OK) {                                                                               \
            rc = fail_msg(&msg);                                                                                      \
            goto cleanup;                                                                                             \
        }                                                                                                             \
    } while (0)

int main(int argc, char **argv)
{
    clvr_options o;
    clvr_message err = {0};
    clvr_context *ctx = NULL;
    clvr_dataset *ds = NULL;
    clvr_scene *scene = NULL;
    clvr_tracer *tracer = NULL;
    clvr_transfer *transfer = NULL;
    clvr_message msg = {0};
    float *table = NULL, *pixels = NULL;
    char *warnings = NULL;
    clvr_stats stats = {0};
    int rc = 0;
    clvr_result s;

    s = clvr_cli_parse(argc, argv, &o, &err);
    if (s != CLVR_RESULT_OK) {
        fprintf(stderr, "clvr: %s\n", err.text);
        return clvr_result_exit_code(s);
    }
    if (o.help) { clvr_cli_print_help(stdout); return 0; }
    if (o.version) { printf("clvr %s\n", clvr_version_string()); return 0; }
    if (o.list_devices) {
        char *list = malloc(1u << 20);
        if (!list) return fail_msg(&(clvr_message){CLVR_RESULT_ERR_NO_MEMORY, "out of memory"});
        clvr_result r = clvr_list_devices(list, 1u << 20, &msg);
        if (r == CLVR_RESULT_OK) fputs(list, stdout);
        free(list);
        return r == CLVR_RESULT_OK ? 0 : fail_msg(&msg);
    }
#ifdef CLVR_HAVE_MPI
    /* Under mpirun (even -n 1): data-parallel rendering (host/mpi). */
    if (clvr_mpi_launched()) return clvr_mpi_main(argc, argv);
#endif
    /* A time series: every step through this main, one range and camera. */
    if (o.mesh_path && clvr_path_is_series(o.mesh_path)) return clvr_series_run(argc, argv, &o, main);
    if (o.kernel_dir) setenv("CLVR_KERNEL_DIR", o.kernel_dir, 1);
    /* Fail on an unwritable output before minutes of work, not after. */
    if (!o.info && !o.view) {
        if (clvr_image_check_path(o.output, &msg) != CLVR_RESULT_OK) return fail_msg(&msg);
        if (o.legend && !clvr_image_path_is_png(o.output)) {
            fprintf(stderr, "clvr: --legend draws into PNG images; -o %s is not one: use -o NAME.png\n", o.output);
            return 2;
        }
    }
    /* --view without a display (or without the viewer) fails now, not after preprocessing. */
    if (o.view && !o.info) {
#ifdef CLVR_HAVE_VIEWER
        s = clvr_viewer_probe(&err);
        if (s != CLVR_RESULT_OK) return fail_msg(&err);
#else
        fprintf(stderr, "clvr: clvr was built without the viewer (GLFW not found); render to a file with -o\n");
        return 1;
#endif
    }

    /* --- mesh. On a CPU device the device's memory is the host's: a mesh
     * that cannot fit is refused from the .bin header, before it is read
     * (not by the OOM killer or an allocation failure inside the driver). */
    if (o.mesh_path && !o.info && clvr_file_check_memory(o.mesh_path, o.width, o.height, o.partitions, &msg))
        return fail_msg(&msg);
    /* The device before the mesh, so that a .bin its memory or allocation
     * limit cannot hold is refused from the header too (a GPU's memory is
     * not the host's), and a bad --device fails before a long read. */
    if (!o.info) {
        TRY(clvr_context_create(o.device, &ctx, &msg));
        TRY(clvr_context_build_info(ctx, !o.quiet, NULL, NULL, &msg));
        if (o.mesh_path) TRY(clvr_context_check_file(ctx, o.mesh_path, o.width, o.height, o.partitions, &msg));
    }
    double t0 = now_s();
    if (!o.quiet && !o.info) fprintf(stderr, "clvr: loading %s\n", o.mesh_path ? o.mesh_path : "the built-in scene");
    if (o.mesh_path) {
        clvr_load_settings ls;
        clvr_load_settings_init(&ls);
        ls.field = o.scalar_name;
        ls.field_ranges = o.info; /* --info lists every array with its range */
        ls.cell_flat = o.cell_flat;
        TRY(clvr_dataset_load_with(o.mesh_path, &ls, &ds, &msg));
    } else {
        TRY(clvr_dataset_create_demo(&ds, &msg));
    }
    stats.load_s = now_s() - t0;
    clvr_dataset_info info;
    info.size = sizeof info;
    TRY(clvr_dataset_get_info(ds, &info, &msg));
    const char *mesh_name = o.mesh_path ? o.mesh_path : "(built-in default scene)";
    if (o.info) {
        if (clvr_info_print(stdout, mesh_name, ds, &msg) != CLVR_RESULT_OK) { rc = fail_msg(&msg); goto cleanup; }
        if (o.stats_json) {
            stats.have_mesh = 1;
            clvr_stats_from_dataset(&stats, &info);
            if (clvr_stats_write_json(o.stats_json, &stats, &msg) != CLVR_RESULT_OK) rc = fail_msg(&msg);
        }
        goto cleanup;
    }

    /* Flaws that render anyway (degenerate, inverted, duplicate elements, a
     * constant field, cells left out) get one line each; clvr-convert said
     * them once per file already, so --quiet silences them on every render. */
    if (!o.quiet) {
        const size_t wsize = 1u << 16;
        warnings = malloc(wsize);
        if (!warnings) { clvr_app_fail(&err, CLVR_RESULT_ERR_NO_MEMORY, "out of memory"); rc = fail_msg(&err); goto cleanup; }
        TRY(clvr_dataset_warnings(ds, mesh_name, warnings, wsize, NULL, &msg));
        fputs(warnings, stderr);
    }

    /* The transfer function needs only the scalar range: build it now, so a
     * typo in --tf FILE fails before minutes of preprocessing. */
    TRY(clvr_transfer_create(ds, NULL, o.colormap, o.tf_file, o.range_set ? o.range_lo : NAN,
                             o.range_set ? o.range_hi : NAN, o.density_auto ? 0.0f : o.density, o.opacity_ramp,
                             &transfer, &msg));
    if (o.density_auto) {
        clvr_tf_info ti;
        ti.size = sizeof ti;
        TRY(clvr_transfer_get_info(transfer, &ti, &msg));
        o.density = ti.auto_density; /* what --density means now (the viewer prints it) */
        if (!o.quiet) fprintf(stderr, "clvr: automatic density %.3g (--density auto)\n", (double)o.density);
    }

    /* Other formats are checked once loaded (their headers do not give
     * every count), .bin files again with what is left now. */
    int boxes = o.element_boxes; /* AUTO resolves here: off only when the run fits only without them */
    TRY(clvr_dataset_check_memory(ds, mesh_name, o.width, o.height, o.partitions, o.element_boxes, &boxes, &msg));
    if (boxes == CLVR_ELEMENT_BOXES_OFF && o.element_boxes == CLVR_ELEMENT_BOXES_AUTO && !o.quiet)
        fprintf(stderr,
                "clvr: %s: point location without its element boxes (6 bytes per element): the run fits in memory "
                "only without them (--element-boxes on insists)\n",
                mesh_name);

    /* --- device (created before the mesh was read) */
    if (!o.quiet) {
        char dev[256], plat[256];
        TRY(clvr_context_describe(ctx, dev, sizeof dev, plat, sizeof plat, &msg));
        fprintf(stderr, "clvr: %s: %llu elements on %s (%s)\n", mesh_name, (unsigned long long)info.num_elements,
                dev, plat);
    }

    /* --- Quick Clusters. A mesh or image the device cannot hold fails
     * first, with the numbers, not minutes into preprocessing. */
    clvr_preprocess_settings pps;
    clvr_preprocess_settings_init(&pps);
    pps.leaf_size = o.leaf_size;
    if (o.sampling_size) pps.sampling_size = o.sampling_size;
    pps.partitions = o.partitions;
    pps.name = mesh_name;
    pps.width = o.width;
    pps.height = o.height;
    /* The program drops the dataset right after: preprocessing may give its
     * element lists back partition by partition (partition.h). */
    pps.consume = 1;
    pps.element_boxes = boxes;
    pps.one_curve = o.one_curve;
    /* Kernel compilation, timed apart from clustering: the programs'
     * builds, and PoCL's code generation at a kernel's first launch, which a
     * preprocessing of a 64-cube mesh of every type triggers (2.0 s of the
     * 2.4 s a cold cache added to the built-in scene's clustering; 0.08 s
     * with a warm cache). */
    double build0, build1, warm_s = now_s();
    TRY(clvr_context_build_info(ctx, !o.quiet, &build0, NULL, &msg));
    TRY(clvr_context_warm_up_with(ctx, &pps, &msg));
    TRY(clvr_context_build_info(ctx, !o.quiet, &build1, NULL, &msg));
    warm_s = now_s() - warm_s - (build1 - build0);

    /* The statistics of the input, before preprocessing takes it apart. */
    stats.have_mesh = 1;
    clvr_stats_from_dataset(&stats, &info);

    TRY(clvr_scene_create(ctx, ds, NULL, &pps, &scene, &msg));
    clvr_scene_stats sst;
    sst.size = sizeof sst;
    TRY(clvr_scene_get_stats(scene, &sst, &msg));
    stats.preprocess_s = sst.preprocess_s;
    stats.partitions = sst.partitions;
    if (!o.quiet)
        fprintf(stderr,
                "clvr: clustered in %.2f s: %llu instance clusters (%llu with 16-bit indices), %llu leaf clusters, "
                "%llu sampling clusters\n",
                stats.preprocess_s, (unsigned long long)sst.instances, (unsigned long long)sst.instances16,
                (unsigned long long)sst.leaves, (unsigned long long)sst.sampling_clusters);
    clvr_stats_from_scene(&stats, &sst);

    /* --- renderer with every setting of the command line */
    clvr_tracer_settings ts;
    clvr_tracer_settings_init(&ts);
    if (clvr_cli_tracer_settings(&o, &ts, &err) != CLVR_RESULT_OK) { rc = fail_msg(&err); goto cleanup; }
    TRY(clvr_tracer_create_on(scene, &ts, o.width, o.height, &tracer, &msg));
    TRY(clvr_tracer_set_pixel_filter(tracer, clvr_setting_name("pixel_filter", o.pixel_filter), &msg));
    if (o.adaptive >= 0.0f) TRY(clvr_tracer_set_adaptive(tracer, o.adaptive, &msg));
    if (o.denoise) TRY(clvr_tracer_set_denoise(tracer, 1, &msg));
    clvr_scene_destroy(scene); /* the tracer holds it */
    scene = NULL;

    TRY(clvr_tracer_set_transfer(tracer, transfer, &msg));
    clvr_tf_info tfi;
    tfi.size = sizeof tfi;
    TRY(clvr_tracer_get_tf(tracer, &tfi, &msg));
    {
        double hf = 0.0, hb = 0.0, he = 0.0, hs = 0.0;
        TRY(clvr_tracer_stat(tracer, "hull_skipped", &hs, &msg));
        if (!o.quiet && hs > 0.0)
            fprintf(stderr, "clvr: the device cannot hold the buffers that find the mesh's boundary faces: rays are not "
                    "cut to the mesh (the same image; it may converge more slowly where the mesh leaves its box "
                    "empty)\n");
        TRY(clvr_tracer_stat(tracer, "hull_faces", &hf, &msg));
        TRY(clvr_tracer_stat(tracer, "hull_bytes", &hb, &msg));
        TRY(clvr_tracer_stat(tracer, "hull_empty_fraction", &he, &msg));
        stats.hull_faces = (uint64_t)hf;
        stats.bytes_hull = (uint64_t)hb;
        stats.hull_empty_fraction = he;
        if (!o.quiet && hf > 0.0)
            fprintf(stderr, "clvr: camera rays cut to the mesh's %.0f boundary faces (%.1f MB): %.0f%% of a ray's way "
                    "through the box is outside the mesh\n", hf, hb / 1e6, 100.0 * he);
    }

    /* --- camera */
    if (o.camera_set)
        TRY(clvr_tracer_set_camera(tracer, o.camera, o.camera + 3, o.camera + 6, o.fovy, &msg));
    else
        TRY(clvr_tracer_frame(tracer, o.up, o.azimuth, o.elevation, o.zoom, o.fovy, &msg));
    /* A turntable turns the eye about the look-at point's vertical: the
     * framing's up axis, or --camera's up vector. */
    const float *orbit_axis = o.camera_set ? o.camera + 6 : o.up;
    float eye0[3], target0[3];
    TRY(clvr_tracer_get_camera(tracer, eye0, target0, NULL, &msg));

    /* The mesh's host copy is no longer needed: the device has it. */
    char legend_name[64];
    snprintf(legend_name, sizeof legend_name, "%s", info.current_name);
    TRY(clvr_tracer_drop_dataset(tracer, &msg));
    clvr_dataset_destroy(ds);
    ds = NULL;
    /* The footprint the run keeps: mesh freed, clustered mesh, trees and
     * renderer in place (on a CPU device all of it host memory). */
    clvr_process_memory(&stats.bytes_resident, NULL);

    /* The legend's colours: the tracer's transfer function, baked. */
    table = malloc((size_t)tfi.table_size * 4 * sizeof(float));
    if (!table) { clvr_app_fail(&err, CLVR_RESULT_ERR_NO_MEMORY, "out of memory for the transfer function"); rc = fail_msg(&err); goto cleanup; }
    TRY(clvr_tracer_get_tf_table(tracer, table, (size_t)tfi.table_size * 4, &msg));
    {
        double build_s;
        int shown;
        TRY(clvr_context_build_info(ctx, !o.quiet, &build_s, &shown, &msg));
        stats.kernel_build_s = build_s + warm_s;
        if (!o.quiet && shown)
            fprintf(stderr, "clvr: kernels compiled in %.2f s; later runs load them from the driver's cache\n",
                    stats.kernel_build_s);
    }

#ifdef CLVR_HAVE_VIEWER
    if (o.view) {
        char dev[256];
        TRY(clvr_context_describe(ctx, dev, sizeof dev, NULL, 0, &msg));
        s = clvr_viewer_run(&o, tracer, dev, &err);
        if (s != CLVR_RESULT_OK) rc = fail_msg(&err);
        goto cleanup;
    }
#endif

    /* --- progressive rendering: one image, or --orbit N turntable images */
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    size_t npix = (size_t)o.width * o.height;
    pixels = malloc(npix * 4 * sizeof(float));
    if (!pixels) { clvr_app_fail(&err, CLVR_RESULT_ERR_NO_MEMORY, "out of memory for the image"); rc = fail_msg(&err); goto cleanup; }
    clvr_image_settings display;
    clvr_image_settings_init(&display);
    display.exposure_ev = o.exposure;
    display.tonemap = clvr_cli_tonemap_name(o.tonemap);
    display.transparent = o.transparent;
    if (o.legend) {
        display.legend_table = table;
        display.legend_entries = tfi.table_size;
        display.legend_lo = tfi.range_lo;
        display.legend_hi = tfi.range_hi;
        display.legend_name = legend_name;
    }
    const uint32_t images = o.orbit ? o.orbit : 1;
    uint32_t frame = 0;
    for (uint32_t img = 0; img < images && !g_interrupted; ++img) {
        char numbered[4096];
        const char *path = o.output;
        if (o.orbit) {
            if (clvr_image_path_numbered(o.output, img, numbered, sizeof numbered, &msg) != CLVR_RESULT_OK) {
                clvr_app_fail(&err, CLVR_RESULT_ERR_USAGE, "-o %s: name too long for numbered --orbit frames; choose a shorter one",
                               o.output);
                rc = fail_msg(&err);
                goto cleanup;
            }
            path = numbered;
            if (img > 0) {
                float eye[3];
                clvr_rotate_about(eye0, target0, orbit_axis, 360.0f * (float)img / (float)o.orbit, eye);
                TRY(clvr_tracer_set_camera(tracer, eye, target0, orbit_axis, o.fovy, &msg));
            }
        }
        double start = now_s(), last_report = start;
        for (frame = 0; frame < o.spp && !g_interrupted; ++frame) {
            TRY(clvr_tracer_render(tracer, 1, &msg));
            double t = now_s();
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
        /* The last image's, as the counters (a camera change resets them):
         * under --orbit a sum over the images made wall seconds a frame N
         * times too long. */
        stats.render_wall_s = now_s() - start;
        if (frame == 0) { /* interrupted before the image's first frame finished */
            fprintf(stderr, "clvr: interrupted before the first frame of %s; not written\n", path);
            rc = 130;
            goto cleanup;
        }
        clvr_render_stats counters;
        counters.size = sizeof counters;
        if (o.denoise) TRY(clvr_tracer_read_denoised(tracer, pixels, npix * 4, &msg));
        else TRY(clvr_tracer_read_image(tracer, pixels, npix * 4, &msg));
        TRY(clvr_tracer_get_render_stats(tracer, &counters, &msg));
        if (o.outline) {
            /* Context for the volume: the mesh's bounds in light grey, the
             * clip box in amber; about one pixel per 400 of image height. */
            const float grey[3] = {0.8f, 0.8f, 0.8f}, amber[3] = {1.0f, 0.55f, 0.1f};
            const float lw = fmaxf(1.0f, (float)o.height / 400.0f);
            TRY(clvr_tracer_draw_box(tracer, pixels, npix * 4, sst.lo, sst.hi, grey, lw, &msg));
            if (o.clip_box_set) TRY(clvr_tracer_draw_box(tracer, pixels, npix * 4, o.clip_lo, o.clip_hi, amber, lw, &msg));
        }
        TRY(clvr_image_save_with(path, o.width, o.height, pixels, &display, &msg));
        stats.have_render = 1;
        clvr_stats_from_render(&stats, &counters);
        /* Read after the image: image_s is the pass that made it (0 with
         * --denoise's read or without the control variates). */
        TRY(clvr_tracer_stat(tracer, "light_s", &stats.light_s, &msg));
        TRY(clvr_tracer_stat(tracer, "image_s", &stats.image_s, &msg));
        TRY(clvr_tracer_stat(tracer, "refine_pixels", &stats.refine_pixels, &msg));
        TRY(clvr_tracer_stat(tracer, "select_s", &stats.select_s, &msg));
        TRY(clvr_tracer_stat(tracer, "pilot_s", &stats.pilot_s, &msg));
        TRY(clvr_tracer_stat(tracer, "pilot_pixels", &stats.pilot_pixels, &msg));
        TRY(clvr_tracer_stat(tracer, "pilot_walk_cells", &stats.pilot_walk_cells, &msg));
        stats.adaptive = clvr_tracer_adaptive(tracer);
        double ab = 0.0, as = 0.0;
        TRY(clvr_tracer_stat(tracer, "adjacency_bytes", &ab, &msg));
        TRY(clvr_tracer_stat(tracer, "adjacency_skipped", &as, &msg));
        stats.bytes_adjacency = (uint64_t)ab;
        if (!o.quiet && as > 0.0)
            fprintf(stderr, "clvr: the device could not hold the walk estimator's face adjacency (4 bytes per cell face): "
                    "urm rendered the rays instead (the same expected image; --estimator urm skips the attempt)\n");
        if (!o.quiet)
            fprintf(stderr, "clvr: wrote %s (%ux%u, %u spp%s)\n", path, o.width, o.height, frame,
                    o.denoise ? ", denoised" : "");
    }
    clvr_process_memory(NULL, &stats.bytes_peak_rss);
    if (o.stats) clvr_stats_print(stdout, &stats);
    if (o.stats_json) {
        TRY(clvr_stats_write_json(o.stats_json, &stats, &msg));
    }
    if (g_interrupted) {
        fprintf(stderr, "clvr: interrupted after %u of %u frames; the image holds what was accumulated\n", frame,
                o.spp);
        rc = 130;
    }

cleanup:
    free(warnings);
    free(pixels);
    free(table);
    clvr_tracer_destroy(tracer);
    clvr_transfer_destroy(transfer);
    clvr_scene_destroy(scene);
    clvr_dataset_destroy(ds);
    clvr_context_destroy(ctx);
    return rc;
}
