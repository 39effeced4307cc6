/* cli.h: clvr's command line, parsed into plain options. Parsing is separate
 * from running so that tests can check every option and every error. The
 * command-line contract is documented in `clvr --help` and the README. Like
 * the rest of the program it uses libclvr's public clvr.h alone: settings
 * with a fixed set of names are kept as their index in clvr_setting_name's
 * tables. Compiled into the program and into the MPI module
 * (libclvr_mpi.so), which parses the same command line. */
#ifndef CLVR_CLI_H
#define CLVR_CLI_H

#include <stdint.h>
#include <stdio.h>

#include "clvr.h"

typedef struct clvr_options {
    /* actions */
    int help, version, list_devices, info, stats, quiet, view;
    /* input */
    const char *mesh_path;       /* NULL: the built-in default scene */
    const char *scalar_name;     /* --scalar */
    int cell_flat;               /* --cell-data flat: a cell field shown per element; 0 (average): at the vertices */
    const char *device;          /* --device SPEC, NULL: default */
    const char *kernel_dir;      /* --kernel-dir: load kernels from disk (developers) */
    /* output */
    const char *output;          /* -o FILE; default "clvr.png" */
    const char *stats_json;      /* --stats-json FILE */
    uint32_t width, height;      /* --size WxH */
    uint32_t spp;                /* --spp N: frames of 1 sample per pixel */
    uint64_t seed;               /* --seed N */
    /* renderer */
    uint32_t method;             /* --method: index in clvr_setting_name("method", i) */
    uint32_t estimator;          /* --estimator: index in clvr_setting_name("estimator", i) */
    uint32_t urm_steps;          /* --urm-steps N (urm estimator) */
    int method_set;              /* nonzero when --method was given */
    float step;                  /* --step (march), world units; 0: automatic */
    uint32_t bins, segments;     /* --bins N (<= 32), --segments M */
    uint32_t macrocells;         /* --macrocells R */
    int shadows;                 /* --shadows on|off */
    uint32_t sampler;            /* --sampler: index in clvr_setting_name("sampler", i) */
    uint32_t pixel_filter;       /* --pixel-filter: index in clvr_setting_name("pixel_filter", i)
                                  * (clvr_tracer_set_pixel_filter, not in the settings struct) */
    float adaptive;              /* --adaptive T|off: clvr_tracer_set_adaptive's threshold (off: 0); < 0: the
                                  * library's default */
    /* clustering */
    uint32_t leaf_size;          /* --leaf-size N: 1, 4, 8, 16, 32 */
    uint32_t sampling_size;      /* --sampling-size N: elements per sampling cluster, 0: default */
    uint32_t partitions;         /* --partitions K: preprocessing partitions, 0: automatic */
    int element_boxes;           /* --element-boxes: CLVR_ELEMENT_BOXES_AUTO (default), _ON, _OFF */
    int one_curve;               /* --one-curve: CLVR_ONE_CURVE_AUTO (default), _ON, _OFF */
    /* scene */
    int camera_set;
    float camera[9];             /* --camera px,py,pz,lx,ly,lz,ux,uy,uz */
    float fovy;                  /* --fovy degrees (default 30, as ParaView) */
    float up[3];                 /* --up: axis of the automatic framing (default +y) */
    int view_set;                /* nonzero when --up, --azimuth, --elevation or --zoom was given */
    float azimuth, elevation;    /* --azimuth, --elevation: degrees added to the automatic framing's */
    float zoom;                  /* --zoom F: the framing distance divided by F (default 1) */
    uint32_t orbit;              /* --orbit N: N turntable frames to numbered files; 0: one image */
    const char *colormap;        /* --colormap NAME */
    const char *tf_file;         /* --tf FILE */
    int range_set;
    float range_lo, range_hi;    /* --range lo hi */
    int range_auto_all;          /* --range auto-all: one range over every step of a series */
    float density;               /* --density D (after clvr's main: the automatic one when density_auto) */
    int density_auto;            /* --density auto (the default): from the mesh's optical depth */
    int opacity_ramp;            /* --opacity ramp: the linear ramp; auto (default): from the histogram */
    float light_dir[3];          /* --light x,y,z (direction towards the light) */
    float light_intensity;       /* --light-intensity I */
    float ambient;               /* --ambient A */
    float background[3];         /* --background r,g,b */
    int transparent;             /* --background none: PNG alpha from the volume, background black */
    /* display (PNG only; EXR and PFM stay linear) */
    float exposure;              /* --exposure EV */
    int tonemap;                 /* --tonemap: index in clvr_setting_name("tonemap", i), default aces */
    int legend;                  /* --legend: colour bar, range and field name drawn into the PNG */
    int denoise;                 /* --denoise: the image written is clvr_tracer_read_denoised's */
    int outline;                 /* --outline: the mesh's bounding box (and the clip box) drawn over the image */
    /* clipping (the medium is kept where n.p <= d) */
    uint32_t num_clip_planes;    /* --clip nx,ny,nz,d, repeatable up to CLVR_MAX_CLIP */
    float clip_planes[CLVR_MAX_CLIP][4];
    int clip_box_set;
    float clip_lo[3], clip_hi[3]; /* --clip-box x0,y0,z0,x1,y1,z1 */
} clvr_options;

/* Fills defaults, then parses argv. On a bad command line returns
 * CLVR_RESULT_ERR_USAGE with a message naming the option and what it
 * expects. */
clvr_result clvr_cli_parse(int argc, char **argv, clvr_options *o, clvr_message *msg);

/* The render settings of the command line (--method, --estimator,
 * --sampler, --seed, --urm-steps, --step, --bins, --segments, --macrocells,
 * --light, --light-intensity, --ambient, --shadows, --background, --clip,
 * --clip-box) as libclvr's settings (s initialised by the caller). */
clvr_result clvr_cli_tracer_settings(const clvr_options *o, clvr_tracer_settings *s, clvr_message *msg);

/* The camera the options ask for over the mesh bounds [lo, hi], as eye,
 * look-at point and up vector (with --fovy: clvr_tracer_set_camera's
 * arguments): --camera as given, else the automatic framing
 * (clvr_frame_box) moved by --up, --azimuth, --elevation and --zoom. The
 * time-series driver and the MPI mode frame one shared box. */
clvr_result clvr_cli_view(const clvr_options *o, const float lo[3], const float hi[3], float eye[3], float target[3],
                          float up[3], clvr_message *msg);

/* The name of --tonemap's value, as clvr_image_settings.tonemap takes it. */
const char *clvr_cli_tonemap_name(int tonemap);

/* The --help text. */
void clvr_cli_print_help(FILE *out);

#endif
