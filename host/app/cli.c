/* cli.c: see cli.h. Only libclvr's public clvr.h: the names of methods,
 * estimators, samplers, tone curves and element box modes, the defaults and
 * the framing all come from the library (tests/test_app_includes.sh). */
#include "cli.h"
#include "message.h"

#include <errno.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void clvr_cli_print_help(FILE *out)
{
    fputs(
        "usage: clvr [options] [MESH]\n"
        "\n"
        "Renders an unstructured volumetric mesh (tets, pyramids, wedges, hexes; one scalar per\n"
        "vertex) with Monte Carlo delta tracking and volumetric shadows, on any OpenCL device.\n"
        "Without MESH, renders the built-in procedural scene. MESH: .bin (clvr), .umesh, legacy .vtk;\n"
        "convert anything else VTK reads with tools/clvr-convert; a .series file (clvr-convert\n"
        "writes one for .pvd, .vtu.series and Exodus time steps) renders every step to -o's name\n"
        "with .0000, .0001, ... before the extension, with one range and one camera.\n"
        "\n"
        "Actions:\n"
        "  --help, -h             this text\n"
        "  --version              print the version\n"
        "  --list-devices         list OpenCL platforms and devices\n"
        "  --info                 print counts per element type, bounds, scalar range, bytes; no render\n"
        "  --stats                print preprocessing and render statistics\n"
        "  --stats-json FILE      write the same statistics as JSON\n"
        "  --view                 open the interactive viewer (needs a display)\n"
        "\n"
        "Input and device:\n"
        "  --device SPEC          pocl | cpu | gpu | P:D | substring of a device or platform name\n"
        "                         (default: the first GPU, else PoCL)\n"
        "  --scalar NAME          which field to render (.bin, .vtk, .umesh; clvr --info lists them):\n"
        "                         NAME, point:NAME or cell:NAME where both exist; a vector gives\n"
        "                         its magnitude, NAME:x|y|z (or NAME:K) one component. Cell data\n"
        "                         is averaged onto the vertices (default: the file's first field)\n"
        "  --cell-data flat|average  a cell field: flat shows each element's own value, constant\n"
        "                         inside it (as ParaView shows cell data; every element gets its\n"
        "                         own vertices); average (default) interpolates the vertex averages\n"
        "  --kernel-dir DIR       load OpenCL sources from DIR instead of the embedded copies\n"
        "\n"
        "Output:\n"
        "  -o FILE, --output FILE  image file: .png (sRGB, tone-mapped), .exr (linear float RGBA),\n"
        "                         .pfm (linear float RGB) (default clvr.png)\n"
        "  --exposure EV          PNG only: scale the linear image by 2^EV before the tone curve\n"
        "                         (default 0)\n"
        "  --tonemap T            PNG only: aces | filmic | none (clamp) (default aces); EXR and PFM\n"
        "                         always hold the linear values\n"
        "  --legend               PNG only: draw the colour map with its range and the field's name\n"
        "                         at the bottom-left corner\n"
        "  --outline              draw the mesh's bounding box (and the --clip-box) over the image\n"
        "                         (PNG, EXR and PFM), projected with the camera\n"
        "  --denoise              write the image after an edge-avoiding filter guided by the colour\n"
        "                         unlit and the depth of the medium (kept by the kernel): smoother,\n"
        "                         and biased (a preview, not the estimate the frames converge to)\n"
        "  --size WxH             image size (default 512x512)\n"
        "  --spp N                samples per pixel = frames accumulated (default 16)\n"
        "  --seed N               random seed (default 1); same seed, same image\n"
        "  --quiet, -q            no progress and no mesh warnings on stderr\n"
        "\n"
        "Rendering:\n"
        "  --method M             march | track | bins | dda (default dda)\n"
        "  --estimator E          auto | walk | urm | delta (track, bins, dda; default auto: walk\n"
        "                         through tets; at other cells walk or urm, whichever a pilot of\n"
        "                         a few hundred pixels before the first frame finds converging\n"
        "                         faster (variance x counted work); --stats says which):\n"
        "                         walk crosses the mesh cell by cell over shared faces: a tet's\n"
        "                         extinction integrated exactly and its emission sampled once;\n"
        "                         other cells as a tet plus a correction at a few Newton\n"
        "                         points: fastest on coarse cells with smooth fields, slower\n"
        "                         than urm on fine CFD hexes (MPI runs get urm);\n"
        "                         urm (unbiased ray marching) weighs jittered quadrature points by\n"
        "                         ratio-tracked transmittance; delta is plain delta tracking (0/1\n"
        "                         collision and shadow); same expected image\n"
        "  --urm-steps N          urm: at least N quadrature points per ray (default 24)\n"
        "  --shadows on|off       volumetric shadow ray toward the light (default on)\n"
        "  --sampler ld|independent  random numbers across frames: ld (default) draws the sub-pixel\n"
        "                         position and first free flights from a per-pixel shifted\n"
        "                         low-discrepancy sequence (faster convergence, frames correlated);\n"
        "                         independent frames give valid per-frame error bars\n"
        "  --adaptive T|off       adaptive sampling: each frame also gives one more sample to the\n"
        "                         pixels whose 8 neighbours differ by more than T times the\n"
        "                         image's mean after the first frame (edges and the noisiest\n"
        "                         parts; default 0.1: a few percent of the pixels); never reads\n"
        "                         a pixel's own samples, so the same expected image, sooner\n"
        "  --pixel-filter box|point  the image frames converge to: box (default) averages each pixel's\n"
        "                         square (rays jittered across it: antialiased); point takes the\n"
        "                         ray through its centre, as VTK and ParaView draw (aliased edges,\n"
        "                         no jitter noise: a clean image in fewer frames)\n"
        "  --step S               march step in world units (default: diagonal / 512)\n"
        "  --bins N               bins per ray segment for --method bins, 1..32 (default 32)\n"
        "  --segments M           ray segments for --method bins (default 4)\n"
        "  --macrocells R|auto    R^3 macrocell grid for --method dda (default auto: 128^3 where its\n"
        "                         majorants average under half of 32^3's, else 32^3)\n"
        "  --leaf-size N          elements per leaf cluster: 1, 4, 8, 16, 32 (default 16)\n"
        "  --sampling-size N      elements per adaptive sampling cluster (default 16)\n"
        "  --clip NX,NY,NZ,D      remove the medium where NX*x + NY*y + NZ*z > D (keeps the side the\n"
        "                         normal points away from, as ParaView's Clip with Invert on);\n"
        "                         shadows see the clipped medium too; up to 6 times\n"
        "  --clip-box X0,Y0,Z0,X1,Y1,Z1  keep only the medium inside this box\n"
        "  --partitions K         preprocess in K pieces of the Hilbert curve (default 0: automatic,\n"
        "                         one per 4.2M elements; less scratch memory, same image)\n"
        "  --element-boxes on|off|auto  quantized element boxes for point location (6 bytes per\n"
        "                         element; faster). auto (default): on unless the mesh fits in\n"
        "                         memory only without them (a notice says so)\n"
        "  --one-curve on|off|auto  cells of several types on one Hilbert curve, each stored as a\n"
        "                         hex with repeated corners (faster point location, up to 8\n"
        "                         indices per cell), or one curve per type. auto (default): one\n"
        "                         curve when that costs at most 1.5x the index slots (--stats\n"
        "                         counts the collapsed cells)\n"
        "\n"
        "Scene:\n"
        "  --camera px,py,pz,lx,ly,lz,ux,uy,uz   eye position, look-at point, up vector\n"
        "                         (default: automatic framing of the mesh)\n"
        "  --fovy DEG             vertical field of view (default 30, as ParaView)\n"
        "  --up AXIS              x | y | z | -x | -y | -z: the world axis shown upwards by the\n"
        "                         automatic framing (default y; no format clvr reads records one)\n"
        "  --azimuth DEG          turn the automatic framing about the up axis (counterclockwise\n"
        "                         seen from above; default 0)\n"
        "  --elevation DEG        raise the automatic framing's camera (default 0; the total stays\n"
        "                         within +-89 degrees of the horizon)\n"
        "  --zoom F               move the automatic framing's camera F times closer (default 1)\n"
        "  --orbit N              render N turntable frames about the up axis (the look-at point's\n"
        "                         vertical), written as -o's name with .0000, .0001, ... before\n"
        "                         the extension\n"
        "  --colormap NAME        cool-warm | viridis | inferno | grayscale | jet (default cool-warm)\n"
        "  --tf FILE              transfer function file (clvr text format or ParaView JSON; a\n"
        "                         JSON map's data-space span is the window unless --range)\n"
        "  --tf FILE:NAME         the ParaView preset NAME from a multi-preset JSON file\n"
        "  --range LO HI          scalar window mapped by the transfer function (default: data range)\n"
        "  --range auto-all       a series: one window over every step's range (the default for a\n"
        "                         series; one mesh: its own range)\n"
        "  --opacity auto|ramp    opacity curve: auto (from the scalar's volume histogram: values\n"
        "                         that fill most of the volume clear, rare ones opaque) or ramp\n"
        "                         (linear, 0 at the window's low end to 1 at its high end)\n"
        "                         (default auto; a --tf file's opacity points win over both)\n"
        "  --density D|auto       extinction scale, 1: optical depth 8 along the mesh diagonal at\n"
        "                         opacity 1; auto (default): the median ray that meets the visible\n"
        "                         medium gets optical depth 0.75\n"
        "  --light X,Y,Z          direction toward the directional light (default 1,2,1.5)\n"
        "  --light-intensity I    (default 1)\n"
        "  --ambient A            ambient light level (default 0.3)\n"
        "  --background R,G,B     linear background colour (default 0.05,0.05,0.07)\n"
        "  --background none      transparent background: PNG gets an alpha channel (the volume's\n"
        "                         opacity), EXR premultiplied colour over black\n"
        "\n"
        "Viewer controls (--view; the window starts at --size, the title shows fps, Mrays/s, spp):\n"
        "  left drag              orbit around the look-at point (arrow keys: 10 degree steps)\n"
        "  middle drag, shift+left drag   pan (shift+arrow keys: pan by 5% of the view)\n"
        "  wheel, PageUp/PageDown zoom in / out\n"
        "  R                      reset the camera to the initial view\n"
        "  C / shift+C            next / previous colour map\n"
        "  [ / ]                  move the scalar window down / up (5% of its width)\n"
        "  { / }                  narrow / widen the scalar window (shift+[ / shift+])\n"
        "  W                      reset the scalar window to the initial one\n"
        "  + / -                  density x1.25 / /1.25\n"
        "  S                      toggle shadows (not with march)\n"
        "  M / shift+M            next / previous method: march, track, bins, dda\n"
        "  E / shift+E            next / previous estimator: delta, urm, walk, auto (not with march)\n"
        "  A                      pixel filter: box (antialiased) / point (pixel centres, as VTK)\n"
        "  V                      adaptive sampling on / off (--adaptive)\n"
        "  D                      show the image denoised (--denoise: a biased preview) / as it is\n"
        "  L+left drag, ctrl+left drag, ctrl+arrows   rotate the light\n"
        "  X / P                  save the accumulated image as clvr-view-NNN.exr / .png (the PNG\n"
        "                         and the window use --exposure and --tonemap, as -o x.png does)\n"
        "  K                      print this view as a clvr command line, also written to clvr-view.txt\n"
        "  H                      print these controls\n"
        "  Q, Escape              quit\n"
        "  The strip at the bottom shows the colour map and opacity over the scalar range, with\n"
        "  the window's ends marked in white. Any change restarts the accumulation.\n"
        "\n"
        "Exit status: 0 success, 2 bad command line, 3 bad input file, 4 OpenCL device problem\n"
        "(or no display for --view), 5 cannot write output, 130 interrupted (the image so far is\n"
        "written), 1 other errors. Messages go to stderr.\n",
        out);
}

/* The index of a default setting name; the library's tables hold them. */
static uint32_t index_of(const char *setting, const char *name)
{
    uint32_t i = 0;
    clvr_setting_index(setting, name, &i, NULL);
    return i;
}

static void defaults(clvr_options *o)
{
    /* Rendering defaults live in one place, the library's (a new tracer's). */
    clvr_tracer_settings ts;
    clvr_tracer_settings_init(&ts);
    memset(o, 0, sizeof *o);
    o->output = "clvr.png";
    clvr_default_size(&o->width, &o->height);
    /* urm reaches about 2% relative RMSE in 8-12 frames on the built-in scene
     * and the 1M-tet bench mesh (bench/converge-all.sh): 16 is a clean image. */
    o->spp = 16;
    o->seed = ts.seed;
    o->method = index_of("method", ts.method);
    o->estimator = index_of("estimator", ts.estimator);
    o->urm_steps = ts.urm_steps;
    o->bins = ts.bins;
    o->segments = ts.segments;
    o->macrocells = ts.macrocells;
    o->shadows = ts.shadows;
    o->sampler = index_of("sampler", ts.sampler);
    o->pixel_filter = index_of("pixel_filter", "box");
    o->adaptive = -1.0f; /* the library's default */
    o->leaf_size = 16;
    o->fovy = 30.0f; /* ParaView's default view angle */
    o->up[1] = 1.0f;
    o->zoom = 1.0f;
    o->tonemap = (int)index_of("tonemap", "aces");
    o->colormap = "cool-warm";
    o->density = 1.0f;
    o->density_auto = 1;
    memcpy(o->light_dir, ts.light_dir, sizeof o->light_dir);
    o->light_intensity = ts.light_intensity;
    o->ambient = ts.ambient;
    memcpy(o->background, ts.background, sizeof o->background);
}

/* --up's axis: x, y or z with an optional sign (+x, -z) as a unit vector;
 * -1 for anything else. */
static int parse_axis(const char *text, float out[3])
{
    float sign = 1.0f;
    if (*text == '-' || *text == '+') sign = *text++ == '-' ? -1.0f : 1.0f;
    if (!text[0] || text[1] || text[0] < 'x' || text[0] > 'z') return -1;
    out[0] = out[1] = out[2] = 0.0f;
    out[text[0] - 'x'] = sign;
    return 0;
}

/* A setting with a fixed set of names (clvr_setting_name) by its index. */
static clvr_result parse_named(const char *opt, const char *setting, const char *v, const char *expects,
                               uint32_t *out, clvr_message *msg)
{
    uint32_t i;
    if (clvr_setting_index(setting, v, &i, NULL) != CLVR_RESULT_OK)
        return clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "%s expects %s, got '%s'", opt, expects, v);
    *out = i;
    return CLVR_RESULT_OK;
}

static clvr_result parse_u64(const char *opt, const char *v, uint64_t lo, uint64_t hi, uint64_t *out, clvr_message *msg)
{
    char *end;
    errno = 0;
    if (!v || !*v || *v == '-')
        return clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "%s expects a whole number in [%llu, %llu], got '%s'", opt,
                              (unsigned long long)lo, (unsigned long long)hi, v ? v : "");
    unsigned long long x = strtoull(v, &end, 10);
    if (errno || *end || x < lo || x > hi)
        return clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "%s expects a whole number in [%llu, %llu], got '%s'", opt,
                              (unsigned long long)lo, (unsigned long long)hi, v);
    *out = x;
    return CLVR_RESULT_OK;
}

static clvr_result parse_u32(const char *opt, const char *v, uint32_t lo, uint32_t hi, uint32_t *out, clvr_message *msg)
{
    uint64_t x;
    clvr_result s = parse_u64(opt, v, lo, hi, &x, msg);
    if (s == CLVR_RESULT_OK) *out = (uint32_t)x;
    return s;
}

static clvr_result parse_float(const char *opt, const char *v, float lo, float hi, float *out, clvr_message *msg)
{
    char *end;
    errno = 0;
    float x = v ? strtof(v, &end) : 0.0f;
    if (!v || !*v || errno || *end || !isfinite(x) || x < lo || x > hi)
        return clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "%s expects a number in [%g, %g], got '%s'", opt, lo, hi,
                              v ? v : "");
    *out = x;
    return CLVR_RESULT_OK;
}

/* Parses "a,b,c,..." with exactly n finite numbers. */
static clvr_result parse_floats(const char *opt, const char *v, int n, float *out, clvr_message *msg)
{
    const char *p = v ? v : "";
    for (int i = 0; i < n; ++i) {
        char *end;
        errno = 0;
        float x = strtof(p, &end);
        if (end == p || errno || !isfinite(x) || (i + 1 < n ? *end != ',' : *end != 0))
            return clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "%s expects %d comma-separated numbers, got '%s'", opt, n,
                                  v ? v : "");
        out[i] = x;
        p = end + 1;
    }
    return CLVR_RESULT_OK;
}

clvr_result clvr_cli_parse(int argc, char **argv, clvr_options *o, clvr_message *msg)
{
    clvr_result s = CLVR_RESULT_OK;
    defaults(o);
    for (int i = 1; i < argc && s == CLVR_RESULT_OK; ++i) {
        const char *a = argv[i];
        /* value of an option that takes one argument */
#define NEXT()                                                                                         \
    (i + 1 < argc ? argv[++i]                                                                          \
                  : (s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "%s needs a value (see clvr --help)", a), \
                     (const char *)NULL))
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) o->help = 1;
        else if (!strcmp(a, "--version")) o->version = 1;
        else if (!strcmp(a, "--list-devices")) o->list_devices = 1;
        else if (!strcmp(a, "--info")) o->info = 1;
        else if (!strcmp(a, "--stats")) o->stats = 1;
        else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) o->quiet = 1;
        else if (!strcmp(a, "--view")) o->view = 1;
        else if (!strcmp(a, "--device")) { const char *v = NEXT(); if (v) o->device = v; }
        else if (!strcmp(a, "--scalar")) { const char *v = NEXT(); if (v) o->scalar_name = v; }
        else if (!strcmp(a, "--cell-data")) {
            const char *v = NEXT();
            if (v) {
                if (!strcmp(v, "flat")) o->cell_flat = 1;
                else if (!strcmp(v, "average")) o->cell_flat = 0;
                else s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--cell-data expects flat or average, got '%s'", v);
            }
        }
        else if (!strcmp(a, "--kernel-dir")) { const char *v = NEXT(); if (v) o->kernel_dir = v; }
        else if (!strcmp(a, "-o") || !strcmp(a, "--output")) { const char *v = NEXT(); if (v) o->output = v; }
        else if (!strcmp(a, "--stats-json")) { const char *v = NEXT(); if (v) o->stats_json = v; }
        else if (!strcmp(a, "--size")) {
            const char *v = NEXT();
            if (v) {
                unsigned w = 0, h = 0;
                char tail;
                if (sscanf(v, "%ux%u%c", &w, &h, &tail) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--size expects WxH with 1 <= W, H <= 16384, got '%s'", v);
                o->width = w;
                o->height = h;
            }
        }
        else if (!strcmp(a, "--spp")) { const char *v = NEXT(); if (v) s = parse_u32(a, v, 1, 1u << 24, &o->spp, msg); }
        else if (!strcmp(a, "--seed")) { const char *v = NEXT(); if (v) s = parse_u64(a, v, 0, UINT64_MAX, &o->seed, msg); }
        else if (!strcmp(a, "--method")) {
            const char *v = NEXT();
            if (v) {
                s = parse_named(a, "method", v, "march, track, bins or dda", &o->method, msg);
                if (s == CLVR_RESULT_OK) o->method_set = 1;
            }
        }
        else if (!strcmp(a, "--estimator")) {
            const char *v = NEXT();
            if (v) {
                s = parse_named(a, "estimator", v, "auto, walk, urm or delta", &o->estimator, msg);
            }
        }
        else if (!strcmp(a, "--urm-steps")) { const char *v = NEXT(); if (v) s = parse_u32(a, v, 1, 4096, &o->urm_steps, msg); }
        else if (!strcmp(a, "--step")) { const char *v = NEXT(); if (v) s = parse_float(a, v, 1e-9f, 1e30f, &o->step, msg); }
        else if (!strcmp(a, "--bins")) { const char *v = NEXT(); if (v) s = parse_u32(a, v, 1, 32, &o->bins, msg); }
        else if (!strcmp(a, "--segments")) { const char *v = NEXT(); if (v) s = parse_u32(a, v, 1, 1024, &o->segments, msg); }
        else if (!strcmp(a, "--macrocells")) {
            const char *v = NEXT();
            if (v && !strcmp(v, "auto")) o->macrocells = 0;
            else if (v) s = parse_u32(a, v, 1, 1024, &o->macrocells, msg);
        }
        else if (!strcmp(a, "--shadows")) {
            const char *v = NEXT();
            if (v) {
                if (!strcmp(v, "on")) o->shadows = 1;
                else if (!strcmp(v, "off")) o->shadows = 0;
                else s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--shadows expects on or off, got '%s'", v);
            }
        }
        else if (!strcmp(a, "--sampler")) {
            const char *v = NEXT();
            if (v) s = parse_named(a, "sampler", v, "ld or independent", &o->sampler, msg);
        }
        else if (!strcmp(a, "--adaptive")) {
            const char *v = NEXT();
            if (v) {
                if (!strcmp(v, "off")) o->adaptive = 0.0f;
                else s = parse_float(a, v, 0.0f, 1e30f, &o->adaptive, msg);
            }
        }
        else if (!strcmp(a, "--pixel-filter")) {
            const char *v = NEXT();
            if (v) s = parse_named(a, "pixel_filter", v, "box or point", &o->pixel_filter, msg);
        }
        else if (!strcmp(a, "--leaf-size")) {
            const char *v = NEXT();
            if (v) {
                s = parse_u32(a, v, 1, 32, &o->leaf_size, msg);
                if (s == CLVR_RESULT_OK && (o->leaf_size & (o->leaf_size - 1)) != 0 && o->leaf_size != 1)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--leaf-size expects 1, 4, 8, 16 or 32, got '%s'", v);
                if (s == CLVR_RESULT_OK && o->leaf_size == 2)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--leaf-size expects 1, 4, 8, 16 or 32, got '%s'", v);
            }
        }
        else if (!strcmp(a, "--sampling-size")) { const char *v = NEXT(); if (v) s = parse_u32(a, v, 1, 1u << 20, &o->sampling_size, msg); }
        else if (!strcmp(a, "--element-boxes")) {
            const char *v = NEXT();
            uint32_t b;
            if (v) s = parse_named(a, "element_boxes", v, "on, off or auto", &b, msg);
            if (v && s == CLVR_RESULT_OK) o->element_boxes = (int)b;
        }
        else if (!strcmp(a, "--one-curve")) {
            const char *v = NEXT();
            uint32_t b;
            if (v) s = parse_named(a, "one_curve", v, "on, off or auto", &b, msg);
            if (v && s == CLVR_RESULT_OK) o->one_curve = (int)b;
        }
        else if (!strcmp(a, "--partitions")) { const char *v = NEXT(); if (v) s = parse_u32(a, v, 0, 65535u, &o->partitions, msg); }
        else if (!strcmp(a, "--camera")) { const char *v = NEXT(); if (v) { s = parse_floats(a, v, 9, o->camera, msg); o->camera_set = 1; } }
        else if (!strcmp(a, "--fovy")) { const char *v = NEXT(); if (v) s = parse_float(a, v, 0.1f, 179.0f, &o->fovy, msg); }
        else if (!strcmp(a, "--colormap")) { const char *v = NEXT(); if (v) o->colormap = v; }
        else if (!strcmp(a, "--tf")) { const char *v = NEXT(); if (v) o->tf_file = v; }
        else if (!strcmp(a, "--range")) {
            const char *lo = NEXT();
            const char *hi = lo && strcmp(lo, "auto-all") != 0 ? NEXT() : NULL;
            if (lo && !strcmp(lo, "auto-all")) {
                o->range_auto_all = 1; /* a series' range over all steps; one mesh: its own range */
                o->range_set = 0;
            } else if (lo && hi) {
                s = parse_float("--range LO", lo, -3e38f, 3e38f, &o->range_lo, msg);
                if (s == CLVR_RESULT_OK) s = parse_float("--range HI", hi, -3e38f, 3e38f, &o->range_hi, msg);
                if (s == CLVR_RESULT_OK && !(o->range_hi > o->range_lo))
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--range expects LO < HI, got %s %s", lo, hi);
                o->range_set = 1;
            }
        }
        else if (!strcmp(a, "--density")) {
            const char *v = NEXT();
            if (v && !strcmp(v, "auto")) o->density_auto = 1;
            else if (v) {
                s = parse_float(a, v, 0.0f, 1e30f, &o->density, msg);
                if (s != CLVR_RESULT_OK)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--density expects auto or a number in [0, 1e+30], got '%s'", v);
                o->density_auto = 0;
            }
        }
        else if (!strcmp(a, "--opacity")) {
            const char *v = NEXT();
            if (v) {
                if (!strcmp(v, "auto")) o->opacity_ramp = 0;
                else if (!strcmp(v, "ramp")) o->opacity_ramp = 1;
                else s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--opacity expects auto or ramp, got '%s'", v);
            }
        }
        else if (!strcmp(a, "--light")) {
            const char *v = NEXT();
            if (v) {
                s = parse_floats(a, v, 3, o->light_dir, msg);
                if (s == CLVR_RESULT_OK && o->light_dir[0] == 0 && o->light_dir[1] == 0 && o->light_dir[2] == 0)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--light expects a non-zero direction, got '%s'", v);
            }
        }
        else if (!strcmp(a, "--light-intensity")) { const char *v = NEXT(); if (v) s = parse_float(a, v, 0.0f, 1e30f, &o->light_intensity, msg); }
        else if (!strcmp(a, "--ambient")) { const char *v = NEXT(); if (v) s = parse_float(a, v, 0.0f, 1e30f, &o->ambient, msg); }
        else if (!strcmp(a, "--background")) {
            const char *v = NEXT();
            if (v && !strcmp(v, "none")) {
                /* Rendered over black, the colour is premultiplied by the opacity. */
                o->transparent = 1;
                memset(o->background, 0, sizeof o->background);
            } else if (v) {
                o->transparent = 0;
                s = parse_floats(a, v, 3, o->background, msg);
                if (s != CLVR_RESULT_OK)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--background expects R,G,B (3 numbers) or none, got '%s'", v);
            }
        }
        else if (!strcmp(a, "--legend")) o->legend = 1;
        else if (!strcmp(a, "--outline")) o->outline = 1;
        else if (!strcmp(a, "--denoise")) o->denoise = 1;
        else if (!strcmp(a, "--clip")) {
            const char *v = NEXT();
            if (v) {
                float q[4];
                s = parse_floats(a, v, 4, q, msg);
                if (s == CLVR_RESULT_OK && o->num_clip_planes == CLVR_MAX_CLIP)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--clip given more than %u times", CLVR_MAX_CLIP);
                else if (s == CLVR_RESULT_OK && q[0] == 0.0f && q[1] == 0.0f && q[2] == 0.0f)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--clip expects a nonzero normal nx,ny,nz, got '%s'", v);
                else if (s == CLVR_RESULT_OK)
                    memcpy(o->clip_planes[o->num_clip_planes++], q, sizeof q);
            }
        }
        else if (!strcmp(a, "--clip-box")) {
            const char *v = NEXT();
            if (v) {
                float b[6];
                s = parse_floats(a, v, 6, b, msg);
                if (s == CLVR_RESULT_OK && !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--clip-box expects x0 < x1, y0 < y1, z0 < z1, got '%s'",
                                       v);
                else if (s == CLVR_RESULT_OK) {
                    memcpy(o->clip_lo, b, sizeof o->clip_lo);
                    memcpy(o->clip_hi, b + 3, sizeof o->clip_hi);
                    o->clip_box_set = 1;
                }
            }
        }
        else if (!strcmp(a, "--exposure")) { const char *v = NEXT(); if (v) s = parse_float(a, v, -30.0f, 30.0f, &o->exposure, msg); }
        else if (!strcmp(a, "--tonemap")) {
            const char *v = NEXT();
            if (v) {
                uint32_t t;
                s = parse_named(a, "tonemap", v, "aces, filmic or none", &t, msg);
                if (s == CLVR_RESULT_OK) o->tonemap = (int)t;
            }
        }
        else if (!strcmp(a, "--up")) {
            const char *v = NEXT();
            if (v) {
                if (parse_axis(v, o->up) != 0)
                    s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--up expects x, y, z, -x, -y or -z, got '%s'", v);
                o->view_set = 1;
            }
        }
        else if (!strcmp(a, "--azimuth")) { const char *v = NEXT(); if (v) { s = parse_float(a, v, -3600.0f, 3600.0f, &o->azimuth, msg); o->view_set = 1; } }
        else if (!strcmp(a, "--elevation")) { const char *v = NEXT(); if (v) { s = parse_float(a, v, -180.0f, 180.0f, &o->elevation, msg); o->view_set = 1; } }
        else if (!strcmp(a, "--zoom")) { const char *v = NEXT(); if (v) { s = parse_float(a, v, 1e-3f, 1e3f, &o->zoom, msg); o->view_set = 1; } }
        else if (!strcmp(a, "--orbit")) { const char *v = NEXT(); if (v) s = parse_u32(a, v, 1, 100000, &o->orbit, msg); }
        else if (a[0] == '-' && a[1] != 0) s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "unknown option '%s' (see clvr --help)", a);
        else if (o->mesh_path) s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "more than one mesh given: '%s' and '%s'", o->mesh_path, a);
        else o->mesh_path = a;
#undef NEXT
    }
    /* The view options move the automatic framing; an explicit --camera has
     * its own eye and up, and silently ignoring them would surprise. */
    if (s == CLVR_RESULT_OK && o->camera_set && o->view_set)
        s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE,
                           "--up, --azimuth, --elevation and --zoom adjust the automatic framing; drop them or drop "
                           "--camera");
    if (s == CLVR_RESULT_OK && o->orbit && o->view)
        s = clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "--orbit renders numbered files; it does not apply to --view");
    return s;
}

clvr_result clvr_cli_tracer_settings(const clvr_options *o, clvr_tracer_settings *s, clvr_message *msg)
{
    const char *method = clvr_setting_name("method", o->method), *estimator = clvr_setting_name("estimator", o->estimator),
               *sampler = clvr_setting_name("sampler", o->sampler);
    if (!method || !estimator || !sampler)
        return clvr_app_fail(msg, CLVR_RESULT_ERR_USAGE, "render settings: method %u, estimator %u or sampler %u "
                             "is not an index of clvr_setting_name", o->method, o->estimator, o->sampler);
    snprintf(s->method, sizeof s->method, "%s", method);
    snprintf(s->estimator, sizeof s->estimator, "%s", estimator);
    snprintf(s->sampler, sizeof s->sampler, "%s", sampler);
    s->seed = o->seed;
    s->urm_steps = o->urm_steps;
    s->step = o->step > 0 ? o->step : 0;
    s->bins = o->bins;
    s->segments = o->segments;
    s->macrocells = o->macrocells;
    memcpy(s->light_dir, o->light_dir, sizeof s->light_dir);
    s->light_intensity = o->light_intensity;
    s->ambient = o->ambient;
    s->shadows = o->shadows;
    memcpy(s->background, o->background, sizeof s->background);
    s->clip_box = o->clip_box_set;
    if (o->clip_box_set) {
        memcpy(s->clip_lo, o->clip_lo, sizeof s->clip_lo);
        memcpy(s->clip_hi, o->clip_hi, sizeof s->clip_hi);
    }
    s->num_clip_planes = o->num_clip_planes;
    memcpy(s->clip_planes, o->clip_planes, sizeof s->clip_planes);
    return CLVR_RESULT_OK;
}

const char *clvr_cli_tonemap_name(int tonemap)
{
    const char *n = tonemap >= 0 ? clvr_setting_name("tonemap", (uint32_t)tonemap) : NULL;
    return n ? n : "?";
}

clvr_result clvr_cli_view(const clvr_options *o, const float lo[3], const float hi[3], float eye[3], float target[3],
                          float up[3], clvr_message *msg)
{
    if (o->camera_set) {
        memcpy(eye, o->camera, 3 * sizeof(float));
        memcpy(target, o->camera + 3, 3 * sizeof(float));
        memcpy(up, o->camera + 6, 3 * sizeof(float));
        return CLVR_RESULT_OK;
    }
    clvr_result r = clvr_frame_box(lo, hi, o->up, o->azimuth, o->elevation, o->zoom, o->fovy, o->width, o->height, eye,
                                   target, msg);
    if (r == CLVR_RESULT_OK) memcpy(up, o->up, 3 * sizeof(float));
    return r;
}
