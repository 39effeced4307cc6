/* main.c: the clvr command line: load (or generate) a mesh, preprocess it
 * into Quick Clusters on the OpenCL device, build the two-level BVH, render
 * progressively and write the image and statistics. Only main() exits.
 * The pipeline goes through libclvr's API (clvr.h; clvr_bridge.h for the
 * options and objects only the program shows), the code Python and C
 * callers use, so the program and the library cannot drift apart. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "clock.h"
#include "accel.h"
#include "clvr.h"
#include "clvr_bridge.h"
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

/* Loads MESH or builds the default scene. */
static clvr_status load_mesh(const clvr_options *o, clvr_mesh *m, clvr_error *err)
{
    if (!o->mesh_path) return clvr_scene_default(m, err);
    clvr_load_options lo = {0};
    lo.scalar_name = o->scalar_name;
    lo.field_ranges = o->info; /* --info lists every array with its range */
    lo.cell_flat = o->cell_flat;
    lo.map_indices = lo.map_vertices = 1; /* a .bin's arrays stay page cache: no second host copy */
    return clvr_mesh_load(o->mesh_path, &lo, m, err);
}

/* Elements per preprocessing partition for the memory checks: the mesh
 * over --partitions K, or partition.h's default bound. */
static uint64_t part_elements(const clvr_options *o, uint64_t n)
{
    return clvr_partition_elements(n, o->partitions);
}

int main(int argc, char **argv)
{
    clvr_options o;
    clvr_error err = {0};
    clvr_mesh mesh = {0};
    clvr_context *ctx = NULL;
    clvr_dataset *ds = NULL;
    clvr_tracer *tracer = NULL;
    clvr_message msg = {0};
    clvr_tf tf = {0};
    float *table = NULL, *pixels = NULL;
    clvr_stats stats = {0};
    int rc = 0;
    clvr_status s;

    s = clvr_cli_parse(argc, argv, &o, &err);
    if (s != CLVR_OK) {
        fprintf(stderr, "clvr: %s\n", err.msg);
        return clvr_status_exit_code(s);
    }
    if (o.help) { clvr_cli_print_help(stdout); return 0; }
    if (o.version) { printf("clvr %s\n", CLVR_VERSION); return 0; }
    if (o.list_devices) {
        char *list = malloc(1u << 20);
        if (!list) return fail(&(clvr_error){CLVR_ERR_NO_MEMORY, "out of memory"});
        s = clvr_bridge_status(clvr_list_devices(list, 1u << 20, &msg), &msg, &err);
        if (s == CLVR_OK) fputs(list, stdout);
        free(list);
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
    int mapped = 0; /* a .bin: load_mesh maps its arrays */
    if (o.mesh_path && !o.info) {
        uint64_t hv = 0, hc[CLVR_CELL_TYPE_COUNT] = {0};
        clvr_error perr = {0};
        if (clvr_mesh_peek_bin(o.mesh_path, &hv, hc, &perr) == CLVR_OK) {
            uint64_t n = 0;
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n += hc[t];
            clvr_mem_limits ml;
            clvr_mem_limits_read(&ml);
            mapped = !o.cell_flat; /* --cell-data flat rewrites the lists: read, not mapped */
            int boxes = o.element_boxes; /* resolved (with its notice) once loaded, below */
            s = clvr_limits_check_host_boxes(o.mesh_path, hv, hc, part_elements(&o, n), o.width, o.height, 0, mapped,
                                             &boxes, &ml, NULL, &err);
            if (s != CLVR_OK) return fail(&err);
        }
    }
    double t0 = clvr_clock_monotonic_s();
    if (!o.quiet && !o.info) fprintf(stderr, "clvr: loading %s\n", o.mesh_path ? o.mesh_path : "the built-in scene");
    s = load_mesh(&o, &mesh, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    stats.load_s = clvr_clock_monotonic_s() - t0;
    /* From here the mesh is libclvr's dataset; `view` borrows its arrays. */
    clvr_mesh view;
    s = clvr_dataset_adopt(&mesh, &ds, &err);
    if (s == CLVR_OK) s = clvr_dataset_view(ds, NULL, &view, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    const char *mesh_name = o.mesh_path ? o.mesh_path : "(built-in default scene)";
    if (o.info) {
        clvr_info_print(stdout, mesh_name, &view);
        if (o.stats_json) {
            stats.have_mesh = 1;
            clvr_stats_from_mesh(&stats, &view);
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
        clvr_limits_scan(&view, &lr);
        clvr_limits_print_warnings(stderr, mesh_name, &lr);
        if (view.skipped_cells)
            fprintf(stderr,
                    "clvr: warning: %s: %llu cell%s of other types (surface, line or polyhedron cells) left out; "
                    "clvr renders tetrahedra, pyramids, wedges and hexahedra\n",
                    mesh_name, (unsigned long long)view.skipped_cells, view.skipped_cells == 1 ? "" : "s");
        if (view.decomposed_cells)
            fprintf(stderr, "clvr: %s: %llu polyhedr%s decomposed into tets and pyramids\n", mesh_name,
                    (unsigned long long)view.decomposed_cells, view.decomposed_cells == 1 ? "on" : "a");
    }

    /* The transfer function needs only the scalar range: load it now, so a
     * typo in --tf FILE fails before minutes of preprocessing. */
    s = clvr_api_tf_build(&view, o.colormap, o.tf_file, o.range_set, o.range_lo, o.range_hi, o.density,
                          o.density_auto, o.opacity_ramp, &tf, &o.density, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    if (o.density_auto && !o.quiet)
        fprintf(stderr, "clvr: automatic density %.3g (--density auto)\n", (double)o.density);

    /* Other formats are checked once loaded (their headers do not give
     * every count), .bin files again with what is left now. */
    {
        clvr_mem_limits ml;
        clvr_mem_limits_read(&ml);
        s = clvr_limits_check_host_boxes(mesh_name, view.num_vertices, view.num_cells,
                                         part_elements(&o, clvr_mesh_num_elements(&view)), o.width, o.height, 1,
                                         view.map_base != NULL, &o.element_boxes, &ml, o.quiet ? NULL : stderr,
                                         &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    }

    /* --- device */
    s = clvr_bridge_status(clvr_context_create(o.device, &ctx, &msg), &msg, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    clvr_cl *cl = clvr_context_cl(ctx);
    cl->build_notice = !o.quiet;
    if (!o.quiet)
        fprintf(stderr, "clvr: %s: %llu elements on %s (%s)\n", mesh_name,
                (unsigned long long)clvr_mesh_num_elements(&view), cl->device_name, cl->platform_name);

    /* --- Quick Clusters */
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    po.leaf_size = o.leaf_size;
    if (o.sampling_size) po.sampling_size = o.sampling_size;
    po.no_element_boxes = o.element_boxes == CLVR_EBOX_OFF;
    /* A mesh or image the device cannot hold fails now, with the numbers,
     * not minutes into preprocessing. */
    s = clvr_limits_check_parts(cl, &view, mesh_name, &po, part_elements(&o, clvr_mesh_num_elements(&view)), o.width,
                                o.height, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    /* Kernel compilation, timed apart from clustering: the programs'
     * builds, and PoCL's code generation at a kernel's first launch, which a
     * preprocessing of a 64-cube mesh of every type triggers (2.0 s of the
     * 2.4 s a cold cache added to the built-in scene's clustering; 0.08 s
     * with a warm cache). */
    double warm_s = clvr_clock_monotonic_s(), build0 = cl->build_s;
    s = clvr_context_warm_up_setup(ctx, &po, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    warm_s = clvr_clock_monotonic_s() - warm_s - (cl->build_s - build0);

    /* The statistics of the input, before preprocessing takes it apart. */
    stats.have_mesh = 1;
    clvr_stats_from_mesh(&stats, &view);

    /* --- Quick Clusters, trees, renderer and transfer function: one tracer */
    clvr_tracer_setup setup;
    clvr_tracer_setup_default(&setup, o.width, o.height);
    setup.name = mesh_name;
    setup.po = po;
    clvr_render_settings *rsp = &setup.rs;
    rsp->method = (uint32_t)o.method;
    rsp->seed = o.seed;
    rsp->sampler = o.sampler;
    rsp->estimator = o.estimator;
    rsp->urm_steps = o.urm_steps;
    rsp->step = o.step;
    rsp->bins = o.bins;
    rsp->segments = o.segments;
    rsp->macrocells = o.macrocells;
    memcpy(rsp->light_dir, o.light_dir, sizeof rsp->light_dir);
    rsp->light_intensity = o.light_intensity;
    rsp->ambient = o.ambient;
    memcpy(rsp->background, o.background, sizeof rsp->background);
    if (o.clip_box_set) {
        memcpy(rsp->clip_lo, o.clip_lo, sizeof rsp->clip_lo);
        memcpy(rsp->clip_hi, o.clip_hi, sizeof rsp->clip_hi);
    }
    rsp->num_clip_planes = o.num_clip_planes;
    memcpy(rsp->clip_planes, o.clip_planes, sizeof rsp->clip_planes);
    setup.shadows = o.shadows;
    setup.partitions = o.partitions;
    /* The program drops the dataset right after: preprocessing may give its
     * element lists back partition by partition (partition.h). */
    setup.consume = 1;
    setup.tf = &tf; /* moved into the tracer */
    s = clvr_tracer_create_setup(ctx, ds, NULL, &setup, &tracer, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    clvr_tracer_parts parts;
    clvr_tracer_parts_of(tracer, &parts);
    const clvr_clustered *clustered = parts.clustered;
    stats.preprocess_s = parts.preprocess_s;
    stats.partitions = parts.partitions;
    if (!o.quiet)
        fprintf(stderr,
                "clvr: clustered in %.2f s: %llu instance clusters (%llu with 16-bit indices), %llu leaf clusters, "
                "%llu sampling clusters\n",
                stats.preprocess_s, (unsigned long long)clustered->num_instances,
                (unsigned long long)clustered->num_instances16, (unsigned long long)clustered->num_leaves,
                (unsigned long long)clustered->num_sampling);
    clvr_stats_from_clusters(&stats, clustered, parts.accel);

    /* --- camera */
    clvr_result r;
    if (o.camera_set)
        r = clvr_tracer_set_camera(tracer, o.camera, o.camera + 3, o.camera + 6, o.fovy, &msg);
    else
        r = clvr_tracer_frame(tracer, o.up, o.azimuth, o.elevation, o.zoom, o.fovy, &msg);
    s = clvr_bridge_status(r, &msg, &err);
    if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
    /* A turntable turns the eye about the look-at point's vertical: the
     * framing's up axis, or --camera's up vector. */
    const float *orbit_axis = o.camera_set ? o.camera + 6 : o.up;
    float eye0[3], target0[3];
    clvr_tracer_get_camera(tracer, eye0, target0, NULL, &msg);

    /* The mesh's host copy is no longer needed: the device has it. */
    char legend_name[sizeof view.scalar_name];
    memcpy(legend_name, view.scalar_name, sizeof legend_name);
    clvr_tracer_drop_dataset(tracer, &msg);
    clvr_dataset_destroy(ds);
    ds = NULL;
    /* The footprint the run keeps: mesh freed, clustered mesh, trees and
     * renderer in place (on a CPU device all of it host memory). */
    clvr_mem_rss(&stats.bytes_resident, NULL);

    /* The legend's colours: the tracer's transfer function, baked. */
    const clvr_tf *ttf = parts.tf;
    {
        uint32_t n = clvr_tf_table_size(ttf);
        table = malloc((size_t)n * 4 * sizeof(float));
        if (!table) { clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "out of memory for the transfer function"); rc = fail(&err); goto cleanup; }
        clvr_tf_bake(ttf, table, n);
    }
    stats.kernel_build_s = cl->build_s + warm_s;
    if (!o.quiet && cl->build_notice_shown)
        fprintf(stderr, "clvr: kernels compiled in %.2f s; later runs load them from the driver's cache\n",
                stats.kernel_build_s);

#ifdef CLVR_HAVE_VIEWER
    if (o.view) {
        s = clvr_viewer_run(&o, cl, clustered, parts.renderer, parts.rs, parts.cam, parts.tf, &err);
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
    clvr_image_legend legend = {table, table ? clvr_tf_table_size(ttf) : 0, ttf->range_lo, ttf->range_hi, legend_name};
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
                s = clvr_bridge_status(clvr_tracer_set_camera(tracer, eye, target0, orbit_axis, o.fovy, &msg), &msg,
                                       &err);
                if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
            }
        }
        double start = clvr_clock_monotonic_s(), last_report = start;
        for (frame = 0; frame < o.spp && !g_interrupted; ++frame) {
            s = clvr_bridge_status(clvr_tracer_render(tracer, 1, &msg), &msg, &err);
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
        s = clvr_bridge_status(clvr_tracer_read_image(tracer, pixels, npix * 4, &msg), &msg, &err);
        if (s == CLVR_OK) s = clvr_renderer_read(parts.renderer, NULL, &counters, &err);
        if (s != CLVR_OK) { rc = fail(&err); goto cleanup; }
        if (o.outline) {
            /* Context for the volume: the mesh's bounds in light grey, the
             * clip box in amber; about one pixel per 400 of image height. */
            const float grey[3] = {0.8f, 0.8f, 0.8f}, amber[3] = {1.0f, 0.55f, 0.1f};
            const float lw = fmaxf(1.0f, (float)o.height / 400.0f);
            clvr_outline_draw_box(pixels, parts.cam, clustered->bounds.lo, clustered->bounds.hi, grey, lw);
            if (o.clip_box_set) clvr_outline_draw_box(pixels, parts.cam, o.clip_lo, o.clip_hi, amber, lw);
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
    clvr_tracer_destroy(tracer);
    clvr_dataset_destroy(ds);
    clvr_tf_free(&tf);
    clvr_context_destroy(ctx);
    clvr_mesh_free(&mesh);
    return rc;
}
