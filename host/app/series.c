/* series.c: see series.h. The per-step render is clvr's own main() with a
 * rewritten command line, so a step renders exactly as that mesh alone
 * would with the same options; only range, density and camera are fixed
 * here. Through libclvr's public API alone (clvr_series_*, clvr_transfer_*,
 * clvr_frame_box). */
#include "series.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "message.h"

static int fail_msg(const clvr_message *msg)
{
    fprintf(stderr, "clvr: %s\n", msg->text);
    return clvr_result_exit_code(msg->result);
}

/* --density auto once, on the first step with the series' window, as clvr's
 * main computes it (clvr_transfer_create with density 0): every frame gets
 * the same extinction scale. */
static clvr_result first_step_density(const clvr_options *o, const char *path, int range_set, float lo, float hi,
                                      float *density, clvr_message *msg)
{
    clvr_dataset *ds = NULL;
    clvr_transfer *tf = NULL;
    clvr_load_settings ls;
    clvr_load_settings_init(&ls);
    ls.field = o->scalar_name;
    clvr_result r = clvr_dataset_load_with(path, &ls, &ds, msg);
    if (r == CLVR_RESULT_OK)
        r = clvr_transfer_create(ds, NULL, o->colormap, o->tf_file, range_set ? lo : NAN, range_set ? hi : NAN, 0.0f,
                                 o->opacity_ramp, &tf, msg);
    clvr_tf_info ti;
    ti.size = sizeof ti;
    if (r == CLVR_RESULT_OK) r = clvr_transfer_get_info(tf, &ti, msg);
    if (r == CLVR_RESULT_OK) *density = ti.auto_density;
    clvr_transfer_destroy(tf);
    clvr_dataset_destroy(ds);
    return r;
}

static int is_view_option(const char *a)
{
    return !strcmp(a, "--up") || !strcmp(a, "--azimuth") || !strcmp(a, "--elevation") || !strcmp(a, "--zoom");
}

int clvr_series_run(int argc, char **argv, const clvr_options *o, clvr_main_fn run)
{
    char **av = NULL;
    clvr_series *se = NULL;
    clvr_message msg = {0};
    int rc = 0;
    char range_lo[32], range_hi[32], camera[400], numbered[4096], density[32];
    int fix_density = 0;
    if (o->orbit || o->view) {
        fprintf(stderr, "clvr: %s: a series renders one numbered frame per time step; %s does not apply\n",
                o->mesh_path, o->orbit ? "--orbit" : "--view");
        return 2;
    }
    if (clvr_series_open(o->mesh_path, &se, &msg) != CLVR_RESULT_OK) return fail_msg(&msg);
    const uint32_t n = clvr_series_count(se);
    /* One range and one camera for every frame: the field's range and the
     * union of the bounds over all steps. */
    int file_range = 0;
    if (!o->range_set && o->tf_file) {
        /* A --tf file with its own window (`range`, a ParaView map's span)
         * keeps it for every step, as for one mesh; errors surface later. */
        if (clvr_tf_file_window(o->tf_file, &file_range, NULL, NULL, NULL) != CLVR_RESULT_OK) file_range = 0;
    }
    int fix_range = !o->range_set && !file_range && !o->info, fix_camera = !o->camera_set && !o->info;
    float lo = 0, hi = 0, blo[3] = {0, 0, 0}, bhi[3] = {0, 0, 0};
    if ((fix_range || fix_camera) && clvr_series_bounds(se, o->scalar_name, blo, bhi, &lo, &hi, &msg) != CLVR_RESULT_OK) {
        rc = fail_msg(&msg);
        goto done;
    }
    if (fix_range) {
        if (!(hi > lo)) hi = lo + (lo != 0 ? 1e-3f * (lo < 0 ? -lo : lo) : 1.0f); /* a constant field over all steps */
        snprintf(range_lo, sizeof range_lo, "%.9g", lo);
        snprintf(range_hi, sizeof range_hi, "%.9g", hi);
        if (!o->quiet)
            fprintf(stderr, "clvr: %s: %u steps, one range [%g, %g] over all of them (--range auto-all)\n",
                    o->mesh_path, n, lo, hi);
    }
    const char *path0 = NULL, *path_i = NULL;
    double time_i = 0;
    if (clvr_series_step(se, 0, &path0, NULL, &msg) != CLVR_RESULT_OK) {
        rc = fail_msg(&msg);
        goto done;
    }
    if (o->density_auto && !o->info) {
        float d = 1.0f;
        if (first_step_density(o, path0, fix_range || o->range_set, fix_range ? lo : o->range_lo,
                               fix_range ? hi : o->range_hi, &d, &msg) != CLVR_RESULT_OK) {
            rc = fail_msg(&msg);
            goto done;
        }
        snprintf(density, sizeof density, "%.9g", d);
        fix_density = 1;
        if (!o->quiet)
            fprintf(stderr, "clvr: %s: automatic density %.3g from the first step, for every step (--density auto)\n",
                    o->mesh_path, (double)d);
    }
    if (fix_camera) {
        float eye[3], target[3], up[3];
        /* the automatic framing: fix_camera needs no --camera */
        if (clvr_cli_view(o, blo, bhi, eye, target, up, &msg) != CLVR_RESULT_OK) {
            rc = fail_msg(&msg);
            goto done;
        }
        snprintf(camera, sizeof camera, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", eye[0], eye[1], eye[2],
                 target[0], target[1], target[2], up[0], up[1], up[2]);
    }
    av = calloc((size_t)argc + 16, sizeof *av);
    if (!av) {
        fprintf(stderr, "clvr: out of memory\n");
        rc = 1;
        goto done;
    }
    for (uint32_t i = 0; i < n && rc == 0; ++i) {
        int k = 0;
        av[k++] = argv[0];
        for (int a = 1; a < argc; ++a) {
            if (argv[a] == o->mesh_path) continue; /* the step's mesh goes last */
            if (a + 1 < argc && argv[a + 1] == o->output && (!strcmp(argv[a], "-o") || !strcmp(argv[a], "--output"))) {
                ++a;
                continue;
            }
            if (a + 1 < argc && !strcmp(argv[a], "--range") && !strcmp(argv[a + 1], "auto-all")) {
                ++a;
                continue;
            }
            if (fix_density && a + 1 < argc && !strcmp(argv[a], "--density")) {
                ++a;
                continue;
            }
            if (fix_camera && a + 1 < argc && is_view_option(argv[a])) {
                ++a;
                continue;
            }
            av[k++] = argv[a];
        }
        if (fix_range) {
            av[k++] = "--range";
            av[k++] = range_lo;
            av[k++] = range_hi;
        }
        if (fix_density) {
            av[k++] = "--density";
            av[k++] = density;
        }
        if (fix_camera) {
            av[k++] = "--camera";
            av[k++] = camera;
        }
        if (!o->info) {
            if (clvr_image_path_numbered(o->output, i, numbered, sizeof numbered, NULL) != CLVR_RESULT_OK) {
                fprintf(stderr, "clvr: -o %s: name too long for numbered frames; choose a shorter one\n", o->output);
                rc = 2;
                break;
            }
            av[k++] = "-o";
            av[k++] = numbered;
        }
        clvr_series_step(se, i, &path_i, &time_i, NULL); /* i < n */
        av[k++] = (char *)path_i;
        av[k] = NULL;
        if (!o->quiet && !o->info)
            fprintf(stderr, "clvr: step %u/%u (time %g): %s -> %s\n", i + 1, n, time_i, path_i, numbered);
        rc = run(k, av);
    }
done:
    free(av);
    clvr_series_destroy(se);
    return rc;
}
