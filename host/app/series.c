/* series.c: see series.h. The per-step render is clvr's own main() with a
 * rewritten command line, so a step renders exactly as that mesh alone
 * would with the same options; only range and camera are fixed here. */
#include "series.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "image.h"
#include "json.h"
#include "mesh_io.h"
#include "tf.h"
#include "tf_auto.h"

int clvr_series_is(const char *path)
{
    size_t n = path ? strlen(path) : 0;
    return n > 7 && strcasecmp(path + n - 7, ".series") == 0;
}

void clvr_series_free(char **paths, double *times, uint32_t n)
{
    for (uint32_t i = 0; paths && i < n; ++i) free(paths[i]);
    free(paths);
    free(times);
}

/* The whole file, NUL-terminated; series files are small (1 MiB at most). */
static clvr_status read_text(const char *path, char **out, size_t *len, clvr_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    char *buf = malloc((1u << 20) + 1);
    size_t n = buf ? fread(buf, 1, 1u << 20, f) : 0;
    int more = buf && fgetc(f) != EOF, bad = ferror(f);
    fclose(f);
    if (!buf) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", path);
    if (bad || more) {
        free(buf);
        return clvr_error_set(err, bad ? CLVR_ERR_IO : CLVR_ERR_FORMAT, "%s: %s", path,
                              bad ? "read error" : "longer than 1 MiB; not a series file");
    }
    buf[n] = 0;
    *out = buf;
    *len = n;
    return CLVR_OK;
}

clvr_status clvr_series_read(const char *path, char ***paths_out, double **times_out, uint32_t *n_out, clvr_error *err)
{
    char *text = NULL, **paths = NULL;
    double *times = NULL;
    size_t len = 0;
    uint32_t n = 0;
    clvr_json j = {0};
    *paths_out = NULL;
    *times_out = NULL;
    *n_out = 0;
    clvr_status s = read_text(path, &text, &len, err);
    if (s == CLVR_OK) s = clvr_json_parse(text, len, path, &j, err);
    if (s != CLVR_OK) goto done;
    const clvr_json_node *root = &j.nodes[j.root], *files = NULL;
    if (root->type == CLVR_JSON_OBJECT)
        for (long c = root->child; c >= 0; c = j.nodes[c].next)
            if (clvr_json_key_is(&j, &j.nodes[c], "files")) files = &j.nodes[c];
    if (!files || files->type != CLVR_JSON_ARRAY || files->count == 0) {
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                           "%s: not a series file: expected {\"files\": [{\"name\": \"step.bin\", \"time\": 0}, ...]} "
                           "(clvr-convert writes one for .pvd, .series and Exodus time steps)", path);
        goto done;
    }
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path) + 1 : 0;
    paths = calloc(files->count, sizeof *paths);
    times = calloc(files->count, sizeof *times);
    if (!paths || !times) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", path);
        goto done;
    }
    for (long c = files->child; c >= 0; c = j.nodes[c].next, ++n) {
        const clvr_json_node *e = &j.nodes[c], *name = NULL;
        times[n] = n;
        if (e->type == CLVR_JSON_OBJECT)
            for (long k = e->child; k >= 0; k = j.nodes[k].next) {
                if (clvr_json_key_is(&j, &j.nodes[k], "name")) name = &j.nodes[k];
                if (clvr_json_key_is(&j, &j.nodes[k], "time") && j.nodes[k].type == CLVR_JSON_NUMBER)
                    times[n] = j.nodes[k].num;
            }
        if (!name || name->type != CLVR_JSON_STRING || name->slen == 0 || memchr(j.arena + name->str, 0, name->slen)) {
            s = clvr_json_fail(&j, err, e->line, e->col, "files[%u] needs a \"name\" string", n);
            goto done;
        }
        const char *nm = j.arena + name->str;
        size_t pre = nm[0] == '/' ? 0 : dirlen;
        paths[n] = malloc(pre + name->slen + 1);
        if (!paths[n]) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", path);
            goto done;
        }
        memcpy(paths[n], path, pre);
        memcpy(paths[n] + pre, nm, name->slen + 1);
    }
    *paths_out = paths;
    *times_out = times;
    *n_out = n;
    paths = NULL;
    times = NULL;
done:
    clvr_series_free(paths, times, n);
    clvr_json_free(&j);
    free(text);
    return s;
}

static int is_view_option(const char *a)
{
    return !strcmp(a, "--up") || !strcmp(a, "--azimuth") || !strcmp(a, "--elevation") || !strcmp(a, "--zoom");
}

int clvr_series_run(int argc, char **argv, const clvr_options *o, clvr_main_fn run)
{
    char **paths = NULL, **av = NULL;
    double *times = NULL;
    uint32_t n = 0;
    clvr_error err = {0};
    clvr_mesh m = {0};
    int rc = 0;
    char range_lo[32], range_hi[32], camera[400], numbered[4096], density[32];
    int fix_density = 0;
    if (o->orbit || o->view) {
        fprintf(stderr, "clvr: %s: a series renders one numbered frame per time step; %s does not apply\n",
                o->mesh_path, o->orbit ? "--orbit" : "--view");
        return 2;
    }
    clvr_status s = clvr_series_read(o->mesh_path, &paths, &times, &n, &err);
    if (s != CLVR_OK) {
        fprintf(stderr, "clvr: %s\n", err.msg);
        return clvr_status_exit_code(s);
    }
    /* One range and one camera for every frame: the field's range and the
     * union of the bounds over all steps. */
    int file_range = 0;
    if (!o->range_set && o->tf_file) {
        /* A --tf file with its own window (`range`, a ParaView map's span)
         * keeps it for every step, as for one mesh; errors surface later. */
        clvr_tf t = {0};
        clvr_error e2 = {0};
        if (clvr_tf_init(&t, NULL, &e2) == CLVR_OK && clvr_tf_load(&t, o->tf_file, &e2) == CLVR_OK)
            file_range = t.range_set;
        clvr_tf_free(&t);
    }
    int fix_range = !o->range_set && !file_range && !o->info, fix_camera = !o->camera_set && !o->info;
    float lo = 0, hi = 0, blo[3] = {0, 0, 0}, bhi[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n && (fix_range || fix_camera); ++i) {
        clvr_load_options lo_opt = {0};
        lo_opt.scalar_name = o->scalar_name;
        s = clvr_mesh_load(paths[i], &lo_opt, &m, &err);
        if (s != CLVR_OK) {
            fprintf(stderr, "clvr: %s (step %u of %s)\n", err.msg, i, o->mesh_path);
            rc = clvr_status_exit_code(s);
            goto done;
        }
        for (int k = 0; k < 3; ++k) {
            blo[k] = i == 0 || m.bounds_lo[k] < blo[k] ? m.bounds_lo[k] : blo[k];
            bhi[k] = i == 0 || m.bounds_hi[k] > bhi[k] ? m.bounds_hi[k] : bhi[k];
        }
        lo = i == 0 || m.scalar_min < lo ? m.scalar_min : lo;
        hi = i == 0 || m.scalar_max > hi ? m.scalar_max : hi;
        clvr_mesh_free(&m);
    }
    if (fix_range) {
        if (!(hi > lo)) hi = lo + (lo != 0 ? 1e-3f * (lo < 0 ? -lo : lo) : 1.0f); /* a constant field over all steps */
        snprintf(range_lo, sizeof range_lo, "%.9g", lo);
        snprintf(range_hi, sizeof range_hi, "%.9g", hi);
        if (!o->quiet)
            fprintf(stderr, "clvr: %s: %u steps, one range [%g, %g] over all of them (--range auto-all)\n",
                    o->mesh_path, n, lo, hi);
    }
    /* --density auto once, on the first step with the common range, as
     * clvr's main computes it: every frame gets the same extinction scale. */
    if (o->density_auto && !o->info) {
        clvr_load_options lo_opt = {0};
        clvr_tf tf = {0};
        float d = 1.0f;
        lo_opt.scalar_name = o->scalar_name;
        s = clvr_mesh_load(paths[0], &lo_opt, &m, &err);
        if (s == CLVR_OK)
            s = clvr_tf_from_options(&tf, o->colormap, o->tf_file, fix_range || o->range_set,
                                     fix_range ? lo : o->range_lo, fix_range ? hi : o->range_hi, 1.0f, m.scalar_min,
                                     m.scalar_max, &err);
        if (s == CLVR_OK) {
            clvr_tf_set_extent(&tf, m.bounds_lo, m.bounds_hi);
            if (!o->opacity_ramp && !tf.opacity_set) {
                double hist[CLVR_TF_AUTO_BINS];
                clvr_tf_auto_histogram(&m, tf.range_lo, tf.range_hi, hist, CLVR_TF_AUTO_BINS);
                s = clvr_tf_auto_opacity(&tf, hist, CLVR_TF_AUTO_BINS, &err);
            }
        }
        if (s == CLVR_OK) s = clvr_tf_auto_density(&m, &tf, &d, &err);
        clvr_tf_free(&tf);
        clvr_mesh_free(&m);
        if (s != CLVR_OK) {
            fprintf(stderr, "clvr: %s\n", err.msg);
            rc = clvr_status_exit_code(s);
            goto done;
        }
        snprintf(density, sizeof density, "%.9g", d);
        fix_density = 1;
        if (!o->quiet)
            fprintf(stderr, "clvr: %s: automatic density %.3g from the first step, for every step (--density auto)\n",
                    o->mesh_path, (double)d);
    }
    if (fix_camera) {
        clvr_camera cam;
        s = clvr_cli_camera(o, blo, bhi, &cam, &err); /* the automatic framing: fix_camera needs no --camera */
        if (s != CLVR_OK) {
            fprintf(stderr, "clvr: %s\n", err.msg);
            rc = clvr_status_exit_code(s);
            goto done;
        }
        snprintf(camera, sizeof camera, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", cam.origin[0], cam.origin[1],
                 cam.origin[2], cam.target[0], cam.target[1], cam.target[2], o->up[0], o->up[1], o->up[2]);
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
            if (!clvr_image_numbered_path(o->output, i, numbered, sizeof numbered)) {
                fprintf(stderr, "clvr: -o %s: name too long for numbered frames; choose a shorter one\n", o->output);
                rc = 2;
                break;
            }
            av[k++] = "-o";
            av[k++] = numbered;
        }
        av[k++] = paths[i];
        av[k] = NULL;
        if (!o->quiet && !o->info)
            fprintf(stderr, "clvr: step %u/%u (time %g): %s -> %s\n", i + 1, n, times[i], paths[i], numbered);
        rc = run(k, av);
    }
done:
    free(av);
    clvr_mesh_free(&m);
    clvr_series_free(paths, times, n);
    return rc;
}
