/* viewer.c: the interactive viewer. One GLFW window with a legacy OpenGL
 * context; each loop turn applies the pending edits through the renderer's
 * set_* calls (which restart the accumulation), renders one more sample per
 * pixel, copies the running mean through the host, maps it with the
 * exposure and tone curve of PNG output (--exposure, --tonemap), encodes it
 * to sRGB with a table and draws it as a texture, with the transfer function as a strip
 * along the bottom. Input is turned into edits by handlers that the GLFW
 * callbacks and the CLVR_VIEW_SCRIPT test hook share, so scripted tests
 * drive the same code as a person does. See viewer.h and docs/viewer.md. */
#include "viewer.h"
#include "message.h"

#include <GLFW/glfw3.h>
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>


/* A modifier bit of our own beside GLFW's: "L is held" turns a left drag
 * into a light rotation. GLFW's modifier bits stop at 0x20. */
#define VIEW_MOD_LIGHT 0x100

#define MAX_MAPS 16
#define STRIP_TEXELS 256
#define ORBIT_DEG_PER_PX 0.4f
#define KEY_ORBIT_DEG 10.0f
#define KEY_LIGHT_DEG 15.0f
#define KEY_PAN_FRACTION 0.05f
#define ZOOM_PER_NOTCH 0.85f
#define WINDOW_MOVE 0.05f
#define WINDOW_SCALE 0.9f
#define DENSITY_STEP 1.25f
#define TITLE_PERIOD_S 0.25

typedef struct viewer {
    const clvr_options *o;
    clvr_tracer *tr;             /* every edit goes through libclvr's public calls */
    const char *device;          /* the device's name, for the status line */
    float data_lo, data_hi;      /* the field's range */
    clvr_tracer_settings ts;     /* the render settings, as edited */
    uint32_t width, height;      /* the tracer's image: the framebuffer's size */
    int resized;
    int shadows;                 /* what the user asked for; march never has shadows */
    char map_name[64];           /* the colour map in use */
    float range_lo, range_hi, density; /* the transfer function's window and density, as edited */
    float ext_scale;             /* table extinction per unit opacity (clvr_tf_info) */
    GLFWwindow *win;
    clvr_message *err;
    clvr_result status;          /* first failure of an edit; ends the loop */
    int quit;

    /* Orbit camera: eye and target move, `pole` (the initial up vector) is
     * the axis of horizontal orbiting and stays fixed so the horizon does. */
    float eye[3], target[3], pole[3], eye0[3], target0[3], fovy;
    float diag;                  /* mesh bounding-box diagonal: zoom limits */

    /* Transfer function. */
    char maps[MAX_MAPS][32];
    int num_maps, map_index, map_changed;
    float range0_lo, range0_hi;  /* initial window (W resets to it) */
    float density_factor;        /* tf->density / what --density means (a --tf file's own density) */
    float *table;
    uint32_t table_n;

    /* Pending edits, applied once per loop turn. */
    int dirty_settings, dirty_camera, dirty_tf;
    int filter_point;          /* A: the point pixel filter (clvr_tracer_set_pixel_filter) instead of box */
    int denoise;               /* D: the window shows clvr_tracer_read_denoised (a biased preview) */
    float adaptive;            /* V: adaptive sampling's threshold (clvr_tracer_set_adaptive), 0: off */
    float adaptive_on;         /* the threshold V turns it back on with (the starting one, else the default) */

    /* Image: the renderer's size is the framebuffer's. */
    uint32_t img_w, img_h;       /* size of rgba / rgba8 contents */
    uint64_t img_spp;            /* accumulated frames in rgba */
    char estimator_used[16];     /* what the frames render with (clvr_render_stats: auto resolved) */
    float *rgba;
    uint8_t *rgba8;
    size_t img_cap;              /* pixels allocated */
    GLuint tex, strip_tex;
    uint32_t tex_w, tex_h;
    clvr_image_settings display; /* what `clvr -o x.png` applies: exposure, tone curve, alpha */

    /* Mouse. */
    int button;                  /* GLFW_MOUSE_BUTTON_* held, -1: none */
    double mx, my;

    /* Status line. */
    double t_title;
    uint32_t frames_since_title;
    uint64_t rays_since_title, rays_last;
    double fps, mrays;
    char title[512];

    /* Script (CLVR_VIEW_SCRIPT). */
    FILE *script;
    const char *script_path;
    int script_line;
    long wait_frames;
} viewer;

static const char *const method_names[] = {"march", "track", "bins", "dda"};
static const char *const estimator_names[] = {"delta", "urm", "walk", "auto"};

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Index of name in names (n of them); 0 when absent. */
static unsigned name_index(const char *const *names, unsigned n, const char *name)
{
    for (unsigned i = 0; i < n; ++i)
        if (!strcmp(names[i], name)) return i;
    return 0;
}

static int is_march(const viewer *v) { return !strcmp(v->ts.method, "march"); }

/* A failed library call ends the viewer with its message. */
static clvr_result lib_fail(viewer *v, const clvr_message *msg)
{
    return clvr_app_fail(v->err, (clvr_result)msg->result, "%s", msg->text);
}

/* --- small vector helpers ---------------------------------------------- */

static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static float len3(const float *a) { return sqrtf(dot3(a, a)); }
static void cross3(const float *a, const float *b, float *o)
{
    float t[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(o, t, sizeof t);
}
static int normalize3(float *a)
{
    float l = len3(a);
    if (!(l > 0.0f) || !isfinite(l)) return 0;
    for (int k = 0; k < 3; ++k) a[k] /= l;
    return 1;
}
/* Rotates v about the unit axis by deg degrees (Rodrigues' formula). */
static void rotate3(float *v, const float *axis, float deg)
{
    float a = deg * (float)M_PI / 180.0f, c = cosf(a), s = sinf(a), kxv[3];
    cross3(axis, v, kxv);
    float kv = dot3(axis, v);
    for (int k = 0; k < 3; ++k) v[k] = v[k] * c + kxv[k] * s + axis[k] * kv * (1.0f - c);
}

/* --- camera edits ------------------------------------------------------- */

/* The camera's right and up vectors for the current eye and target. */
static void view_basis(const viewer *v, float *fwd, float *right, float *up)
{
    for (int k = 0; k < 3; ++k) fwd[k] = v->target[k] - v->eye[k];
    normalize3(fwd);
    cross3(fwd, v->pole, right);
    if (!normalize3(right)) { right[0] = 1; right[1] = right[2] = 0; }
    cross3(right, fwd, up);
}

/* Orbits the eye around the target: dx_deg about the pole, dy_deg about the
 * camera's right axis (positive dx: the scene turns right; positive dy: the
 * scene tilts down, as when dragging it). Elevation stops 2 degrees short of
 * the pole, where the camera basis would degenerate. */
static void orbit(viewer *v, float dx_deg, float dy_deg)
{
    float off[3], right[3];
    for (int k = 0; k < 3; ++k) off[k] = v->eye[k] - v->target[k];
    rotate3(off, v->pole, -dx_deg);
    /* right = forward x pole with forward = -off. */
    cross3(v->pole, off, right);
    if (normalize3(right)) {
        float t[3] = {off[0], off[1], off[2]};
        rotate3(t, right, -dy_deg);
        float u[3] = {t[0], t[1], t[2]};
        if (normalize3(u) && fabsf(dot3(u, v->pole)) < cosf(2.0f * (float)M_PI / 180.0f)) memcpy(off, t, sizeof off);
    }
    for (int k = 0; k < 3; ++k) v->eye[k] = v->target[k] + off[k];
    v->dirty_camera = 1;
}

/* Moves eye and target across the view by (dx, dy) framebuffer pixels; the
 * scene follows the pointer at the target's depth. */
static void pan(viewer *v, float dx, float dy)
{
    float fwd[3], right[3], up[3], off[3];
    view_basis(v, fwd, right, up);
    for (int k = 0; k < 3; ++k) off[k] = v->eye[k] - v->target[k];
    float dist = len3(off);
    float per_px = 2.0f * dist * tanf(0.5f * v->fovy * (float)M_PI / 180.0f) / (float)(v->height ? v->height : 1);
    for (int k = 0; k < 3; ++k) {
        float m = -dx * per_px * right[k] + dy * per_px * up[k];
        v->eye[k] += m;
        v->target[k] += m;
    }
    v->dirty_camera = 1;
}

/* notches > 0 moves the eye towards the target. */
static void zoom(viewer *v, float notches)
{
    float off[3];
    for (int k = 0; k < 3; ++k) off[k] = v->eye[k] - v->target[k];
    float dist = len3(off);
    if (!(dist > 0.0f)) return;
    float nd = dist * powf(ZOOM_PER_NOTCH, notches);
    float lo = 1e-4f * (v->diag > 0.0f ? v->diag : 1.0f), hi = 1e3f * (v->diag > 0.0f ? v->diag : 1.0f);
    if (nd < lo) nd = lo;
    if (nd > hi) nd = hi;
    for (int k = 0; k < 3; ++k) v->eye[k] = v->target[k] + off[k] * (nd / dist);
    v->dirty_camera = 1;
}

/* Turns the light direction like the scene under orbit(): about the camera's
 * up axis for dx, its right axis for dy. */
static void rotate_light(viewer *v, float dx_deg, float dy_deg)
{
    float fwd[3], right[3], up[3];
    view_basis(v, fwd, right, up);
    rotate3(v->ts.light_dir, up, dx_deg);
    rotate3(v->ts.light_dir, right, dy_deg);
    if (!normalize3(v->ts.light_dir)) { v->ts.light_dir[0] = 0; v->ts.light_dir[1] = 1; v->ts.light_dir[2] = 0; }
    v->dirty_settings = 1;
}

/* --- transfer-function edits -------------------------------------------- */

static void set_map(viewer *v, int index)
{
    if (v->num_maps == 0) return;
    v->map_index = (index % v->num_maps + v->num_maps) % v->num_maps;
    snprintf(v->map_name, sizeof v->map_name, "%s", v->maps[v->map_index]);
    v->map_changed = 1;
    v->dirty_tf = 1;
}

static void move_window(viewer *v, float fraction)
{
    float w = v->range_hi - v->range_lo;
    v->range_lo += fraction * w;
    v->range_hi += fraction * w;
    v->dirty_tf = 1;
}

static void scale_window(viewer *v, float factor)
{
    float c = 0.5f * (v->range_lo + v->range_hi), w = v->range_hi - v->range_lo;
    float nw = w * factor;
    /* Keep lo < hi representable: no narrower than a few ulps of the centre
     * or a millionth of the data range. */
    float data_w = v->data_hi - v->data_lo;
    float min_w = fmaxf(1e-6f * fmaxf(data_w, fabsf(c)), 64.0f * 1.2e-7f * fabsf(c));
    if (!(min_w > 0.0f)) min_w = 1e-6f;
    if (nw < min_w) nw = min_w;
    v->range_lo = c - 0.5f * nw;
    v->range_hi = c + 0.5f * nw;
    if (!(v->range_hi > v->range_lo)) v->range_hi = nextafterf(v->range_lo, INFINITY);
    v->dirty_tf = 1;
}

static void scale_density(viewer *v, float factor)
{
    float d = v->density;
    d = d > 0.0f ? d * factor : (factor > 1.0f ? 0.05f * v->density_factor : 0.0f);
    if (d > 1e30f) d = 1e30f;
    v->density = d;
    v->dirty_tf = 1;
}

/* --- files -------------------------------------------------------------- */

/* Writes the image shown (the running mean of img_spp frames) to path. */
static void save_image(viewer *v, const char *path)
{
    clvr_message msg;
    if (v->img_spp == 0 || !v->rgba) {
        fprintf(stderr, "clvr: no image to save yet\n");
        return;
    }
    if (clvr_image_save_with(path, v->img_w, v->img_h, v->rgba, &v->display, &msg) != CLVR_RESULT_OK) {
        fprintf(stderr, "clvr: %s\n", msg.text);
        return;
    }
    printf("clvr: saved %s (%ux%u, %llu spp)\n", path, v->img_w, v->img_h, (unsigned long long)v->img_spp);
    fflush(stdout);
}

/* X and P: the first free clvr-view-NNN.<ext> in the working directory. */
static void save_numbered(viewer *v, const char *ext)
{
    char path[64];
    for (int i = 1; i < 1000; ++i) {
        snprintf(path, sizeof path, "clvr-view-%03d.%s", i, ext);
        if (access(path, F_OK) != 0) {
            save_image(v, path);
            return;
        }
    }
    fprintf(stderr, "clvr: clvr-view-001..999.%s all exist; remove some to save more\n", ext);
}

/* Appends s to the buffer, single-quoted for a POSIX shell when needed. */
static void append_quoted(char *buf, size_t cap, const char *s)
{
    size_t n = strlen(buf);
    int plain = *s != 0;
    for (const char *p = s; *p; ++p)
        if (!(isalnum((unsigned char)*p) || strchr("_./,:=+-@%", *p))) plain = 0;
    if (plain) {
        snprintf(buf + n, cap - n, "%s", s);
        return;
    }
    if (n + 1 < cap) buf[n++] = '\'';
    for (const char *p = s; *p && n + 5 < cap; ++p) {
        if (*p == '\'') { memcpy(buf + n, "'\\''", 4); n += 4; }
        else buf[n++] = *p;
    }
    if (n + 1 < cap) buf[n++] = '\'';
    buf[n < cap ? n : cap - 1] = 0;
}

static void appendf(char *buf, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void appendf(char *buf, size_t cap, const char *fmt, ...)
{
    size_t n = strlen(buf);
    if (n >= cap) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + n, cap - n, fmt, ap);
    va_end(ap);
}

/* K: the current view as a clvr command line that renders the same image
 * offline (same size, seed, camera, transfer function, method, light), with
 * %.9g so every float reads back to the same bits. Options still at their
 * defaults are left out, except the view-defining ones the brief asks for. */
static void print_command_line(viewer *v)
{
    const clvr_options *o = v->o;
    clvr_options d;
    clvr_message e;
    char *argv0[] = {"clvr", NULL};
    clvr_cli_parse(1, argv0, &d, &e);
    char line[8192] = "clvr";
    size_t cap = sizeof line;
    if (o->mesh_path) { appendf(line, cap, " "); append_quoted(line, cap, o->mesh_path); }
    if (o->scalar_name) { appendf(line, cap, " --scalar "); append_quoted(line, cap, o->scalar_name); }
    if (o->device) { appendf(line, cap, " --device "); append_quoted(line, cap, o->device); }
    uint64_t spp = v->img_spp > o->spp ? v->img_spp : o->spp;
    clvr_tracer_settings dts; /* the library's defaults: the command line's */
    clvr_tracer_settings_init(&dts);
    appendf(line, cap, " --size %ux%u --spp %llu --seed %llu", v->width, v->height, (unsigned long long)spp,
            (unsigned long long)v->ts.seed);
    appendf(line, cap, " --method %s --shadows %s --estimator %s", v->ts.method, v->shadows ? "on" : "off",
            v->ts.estimator);
    if (v->ts.urm_steps != dts.urm_steps) appendf(line, cap, " --urm-steps %u", v->ts.urm_steps);
    if (strcmp(v->ts.sampler, dts.sampler)) appendf(line, cap, " --sampler %s", v->ts.sampler);
    if (strcmp(clvr_tracer_pixel_filter(v->tr), "box"))
        appendf(line, cap, " --pixel-filter %s", clvr_tracer_pixel_filter(v->tr));
    if (v->adaptive > 0.0f) appendf(line, cap, " --adaptive %g", (double)v->adaptive);
    else appendf(line, cap, " --adaptive off");
    if (v->denoise) appendf(line, cap, " --denoise");
    if (v->ts.step != dts.step) appendf(line, cap, " --step %.9g", (double)v->ts.step);
    if (v->ts.bins != dts.bins) appendf(line, cap, " --bins %u", v->ts.bins);
    if (v->ts.segments != dts.segments) appendf(line, cap, " --segments %u", v->ts.segments);
    if (v->ts.macrocells != dts.macrocells) {
        if (v->ts.macrocells) appendf(line, cap, " --macrocells %u", v->ts.macrocells);
        else appendf(line, cap, " --macrocells auto");
    }
    if (o->leaf_size != d.leaf_size) appendf(line, cap, " --leaf-size %u", o->leaf_size);
    if (o->sampling_size != d.sampling_size) appendf(line, cap, " --sampling-size %u", o->sampling_size);
    appendf(line, cap, " --camera %.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", (double)v->eye[0], (double)v->eye[1],
            (double)v->eye[2], (double)v->target[0], (double)v->target[1], (double)v->target[2], (double)v->pole[0],
            (double)v->pole[1], (double)v->pole[2]);
    if (v->fovy != d.fovy) appendf(line, cap, " --fovy %.9g", (double)v->fovy);
    if (o->tf_file) { appendf(line, cap, " --tf "); append_quoted(line, cap, o->tf_file); }
    appendf(line, cap, " --colormap ");
    append_quoted(line, cap, v->map_changed ? v->maps[v->map_index] : o->colormap);
    if (o->opacity_ramp) appendf(line, cap, " --opacity ramp");
    appendf(line, cap, " --range %.9g %.9g --density %.9g", (double)v->range_lo, (double)v->range_hi,
            (double)(v->density / v->density_factor));
    appendf(line, cap, " --light %.9g,%.9g,%.9g", (double)v->ts.light_dir[0], (double)v->ts.light_dir[1],
            (double)v->ts.light_dir[2]);
    if (v->ts.light_intensity != d.light_intensity)
        appendf(line, cap, " --light-intensity %.9g", (double)v->ts.light_intensity);
    if (v->ts.ambient != d.ambient) appendf(line, cap, " --ambient %.9g", (double)v->ts.ambient);
    if (o->transparent) appendf(line, cap, " --background none");
    else if (memcmp(v->ts.background, d.background, sizeof d.background))
        appendf(line, cap, " --background %.9g,%.9g,%.9g", (double)v->ts.background[0], (double)v->ts.background[1],
                (double)v->ts.background[2]);
    if (o->exposure != d.exposure) appendf(line, cap, " --exposure %.9g", (double)o->exposure);
    if (o->tonemap != d.tonemap) appendf(line, cap, " --tonemap %s", clvr_cli_tonemap_name(o->tonemap));
    /* Clipping and the outline come from the command line unchanged. */
    for (uint32_t i = 0; i < o->num_clip_planes; ++i)
        appendf(line, cap, " --clip %.9g,%.9g,%.9g,%.9g", (double)o->clip_planes[i][0], (double)o->clip_planes[i][1],
                (double)o->clip_planes[i][2], (double)o->clip_planes[i][3]);
    if (o->clip_box_set)
        appendf(line, cap, " --clip-box %.9g,%.9g,%.9g,%.9g,%.9g,%.9g", (double)o->clip_lo[0], (double)o->clip_lo[1],
                (double)o->clip_lo[2], (double)o->clip_hi[0], (double)o->clip_hi[1], (double)o->clip_hi[2]);
    if (o->outline) appendf(line, cap, " --outline");
    printf("%s\n", line);
    fflush(stdout);
    if (o->tf_file && v->map_changed)
        fprintf(stderr, "clvr: note: colours from --tf %s take precedence over --colormap offline\n", o->tf_file);
    FILE *f = fopen("clvr-view.txt", "w");
    if (!f || fprintf(f, "%s\n", line) < 0 || fclose(f) != 0) {
        fprintf(stderr, "clvr: cannot write clvr-view.txt in the working directory\n");
        return;
    }
    printf("clvr: wrote clvr-view.txt\n");
    fflush(stdout);
}

/* H: the "Viewer controls" section of clvr --help, so the two never differ. */
static void print_controls(FILE *out)
{
    char *text = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&text, &len);
    if (!m) return;
    clvr_cli_print_help(m);
    fclose(m);
    const char *a = strstr(text, "Viewer controls"), *b = a ? strstr(a, "\nExit status") : NULL;
    if (a && b) fprintf(out, "%.*s", (int)(b - a), a);
    fflush(out);
    free(text);
}

/* --- input -------------------------------------------------------------- */

static void handle_key(viewer *v, int key, int mods)
{
    int shift = (mods & GLFW_MOD_SHIFT) != 0, light = (mods & (GLFW_MOD_CONTROL | VIEW_MOD_LIGHT)) != 0;
    switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: v->quit = 1; break;
    case GLFW_KEY_H: print_controls(stdout); break;
    case GLFW_KEY_R:
        memcpy(v->eye, v->eye0, sizeof v->eye);
        memcpy(v->target, v->target0, sizeof v->target);
        v->dirty_camera = 1;
        break;
    case GLFW_KEY_LEFT:
    case GLFW_KEY_RIGHT:
    case GLFW_KEY_UP:
    case GLFW_KEY_DOWN: {
        float sx = key == GLFW_KEY_LEFT ? -1.0f : key == GLFW_KEY_RIGHT ? 1.0f : 0.0f;
        float sy = key == GLFW_KEY_UP ? -1.0f : key == GLFW_KEY_DOWN ? 1.0f : 0.0f;
        if (light) rotate_light(v, sx * KEY_LIGHT_DEG, sy * KEY_LIGHT_DEG);
        else if (shift) pan(v, sx * KEY_PAN_FRACTION * (float)v->height, sy * KEY_PAN_FRACTION * (float)v->height);
        else orbit(v, sx * KEY_ORBIT_DEG, sy * KEY_ORBIT_DEG);
        break;
    }
    case GLFW_KEY_PAGE_UP: zoom(v, 1.0f); break;
    case GLFW_KEY_PAGE_DOWN: zoom(v, -1.0f); break;
    case GLFW_KEY_C: set_map(v, v->map_index + (shift ? -1 : 1)); break;
    case GLFW_KEY_LEFT_BRACKET:
        if (shift) scale_window(v, WINDOW_SCALE);
        else move_window(v, -WINDOW_MOVE);
        break;
    case GLFW_KEY_RIGHT_BRACKET:
        if (shift) scale_window(v, 1.0f / WINDOW_SCALE);
        else move_window(v, WINDOW_MOVE);
        break;
    case GLFW_KEY_W:
        v->range_lo = v->range0_lo;
        v->range_hi = v->range0_hi;
        v->dirty_tf = 1;
        break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD: scale_density(v, DENSITY_STEP); break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT: scale_density(v, 1.0f / DENSITY_STEP); break;
    case GLFW_KEY_S:
        v->shadows = !v->shadows;
        v->dirty_settings = 1;
        break;
    case GLFW_KEY_M: {
        const unsigned n = 4, i = name_index(method_names, n, v->ts.method);
        snprintf(v->ts.method, sizeof v->ts.method, "%s", method_names[(i + (shift ? n - 1u : 1u)) % n]);
        v->dirty_settings = 1;
        break;
    }
    case GLFW_KEY_E: {
        const unsigned n = 4, i = name_index(estimator_names, n, v->ts.estimator);
        snprintf(v->ts.estimator, sizeof v->ts.estimator, "%s", estimator_names[(i + (shift ? n - 1u : 1u)) % n]);
        v->dirty_settings = 1;
        break;
    }
    case GLFW_KEY_A: /* antialiasing: the box filter, or the point filter of VTK's ray casters */
        v->filter_point = !v->filter_point;
        v->dirty_settings = 1;
        break;
    case GLFW_KEY_V: /* adaptive sampling: refine passes on the noisiest pixels, or one sample per pixel a frame */
        v->adaptive = v->adaptive > 0.0f ? 0.0f : v->adaptive_on;
        v->dirty_settings = 1;
        break;
    case GLFW_KEY_D: /* the denoised preview (guides kept by the kernel), or the estimate itself */
        v->denoise = !v->denoise;
        v->dirty_settings = 1;
        break;
    case GLFW_KEY_X: save_numbered(v, "exr"); break;
    case GLFW_KEY_P: save_numbered(v, "png"); break;
    case GLFW_KEY_K: print_command_line(v); break;
    default: break;
    }
}

/* A pointer move of (dx, dy) framebuffer pixels with `button` held. */
static void handle_drag(viewer *v, int button, int mods, float dx, float dy)
{
    if (button == GLFW_MOUSE_BUTTON_LEFT && (mods & (GLFW_MOD_CONTROL | VIEW_MOD_LIGHT)))
        rotate_light(v, dx * ORBIT_DEG_PER_PX, dy * ORBIT_DEG_PER_PX);
    else if (button == GLFW_MOUSE_BUTTON_MIDDLE || (button == GLFW_MOUSE_BUTTON_LEFT && (mods & GLFW_MOD_SHIFT)))
        pan(v, dx, dy);
    else if (button == GLFW_MOUSE_BUTTON_LEFT)
        orbit(v, dx * ORBIT_DEG_PER_PX, dy * ORBIT_DEG_PER_PX);
    else if (button == GLFW_MOUSE_BUTTON_RIGHT)
        zoom(v, -dy / 40.0f); /* right drag: dolly, 40 pixels a notch */
}

static int held_mods(GLFWwindow *w)
{
    int m = 0;
    if (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS)
        m |= GLFW_MOD_SHIFT;
    if (glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS)
        m |= GLFW_MOD_CONTROL;
    if (glfwGetKey(w, GLFW_KEY_L) == GLFW_PRESS) m |= VIEW_MOD_LIGHT;
    return m;
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode;
    viewer *v = glfwGetWindowUserPointer(w);
    if (action == GLFW_RELEASE || key == GLFW_KEY_L) return;
    /* Saving and printing once per press, not per auto-repeat. */
    if (action == GLFW_REPEAT && (key == GLFW_KEY_X || key == GLFW_KEY_P || key == GLFW_KEY_K || key == GLFW_KEY_H))
        return;
    handle_key(v, key, mods | (held_mods(w) & VIEW_MOD_LIGHT));
}

/* Window coordinates -> framebuffer pixels (they differ on HiDPI screens). */
static void fb_scale(GLFWwindow *w, float *sx, float *sy)
{
    int ww, wh, fw, fh;
    glfwGetWindowSize(w, &ww, &wh);
    glfwGetFramebufferSize(w, &fw, &fh);
    *sx = ww > 0 ? (float)fw / (float)ww : 1.0f;
    *sy = wh > 0 ? (float)fh / (float)wh : 1.0f;
}

/* The pointer position comes from the motion events, not from
 * glfwGetCursorPos: on X11 that asks the server for where the pointer is
 * now, which is ahead of the events still queued. */
static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    (void)mods;
    viewer *v = glfwGetWindowUserPointer(w);
    if (action == GLFW_PRESS) v->button = button;
    else if (button == v->button) v->button = -1;
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    viewer *v = glfwGetWindowUserPointer(w);
    if (v->button >= 0) {
        float sx, sy;
        fb_scale(w, &sx, &sy);
        handle_drag(v, v->button, held_mods(w), (float)(x - v->mx) * sx, (float)(y - v->my) * sy);
    }
    v->mx = x;
    v->my = y;
}

static void draw(viewer *v);

/* The window was uncovered or resized: redraw what we have. */
static void on_refresh(GLFWwindow *w)
{
    viewer *v = glfwGetWindowUserPointer(w);
    draw(v);
    glfwSwapBuffers(w);
}

static void on_scroll(GLFWwindow *w, double xoff, double yoff)
{
    (void)xoff;
    zoom(glfwGetWindowUserPointer(w), (float)yoff);
}

/* --- applying edits ------------------------------------------------------ */

static clvr_result ensure_image(viewer *v, uint32_t w, uint32_t h)
{
    size_t n = (size_t)w * h;
    if (n <= v->img_cap) return CLVR_RESULT_OK;
    float *f = realloc(v->rgba, n * 4 * sizeof(float));
    if (f) v->rgba = f;
    uint8_t *b = f ? realloc(v->rgba8, n * 4) : NULL;
    if (b) v->rgba8 = b;
    if (!f || !b) return clvr_app_fail(v->err, CLVR_RESULT_ERR_NO_MEMORY, "out of memory for a %ux%u viewer image", w, h);
    v->img_cap = n;
    return CLVR_RESULT_OK;
}

/* The strip texture: the colour map over the strip's scalar range (the data
 * range and the window, whichever reaches farther), looked up as the kernels
 * do: clamped at the window's ends. */
static void strip_range(const viewer *v, float *lo, float *hi)
{
    *lo = fminf(v->data_lo, v->range_lo);
    *hi = fmaxf(v->data_hi, v->range_hi);
    if (!(*hi > *lo)) *hi = *lo + 1.0f;
}

/* The table entry at x in [0, 1] of the window, clamped as the kernels do. */
static const float *table_at(const viewer *v, float x)
{
    if (!(x > 0.0f)) x = 0.0f;
    if (x > 1.0f) x = 1.0f;
    uint32_t i = (uint32_t)lrintf(x * (float)(v->table_n - 1));
    return v->table + 4 * (size_t)i;
}

static void update_strip(viewer *v)
{
    float lin[STRIP_TEXELS * 4];
    uint8_t px[STRIP_TEXELS * 4];
    float lo, hi;
    strip_range(v, &lo, &hi);
    if (!v->table_n) return;
    for (int i = 0; i < STRIP_TEXELS; ++i) {
        float s = lo + ((float)i + 0.5f) / STRIP_TEXELS * (hi - lo);
        const float *c = table_at(v, (s - v->range_lo) / (v->range_hi - v->range_lo));
        memcpy(lin + 4 * i, c, 3 * sizeof(float));
        lin[4 * i + 3] = 1.0f;
    }
    /* The colours as the legend shows them: sRGB, no exposure or tone curve. */
    clvr_message msg;
    if (clvr_image_to_srgb8(lin, STRIP_TEXELS, 1, 0.0f, "none", px, &msg) != CLVR_RESULT_OK) return;
    glBindTexture(GL_TEXTURE_2D, v->strip_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, STRIP_TEXELS, 1, 0, GL_RGBA, GL_UNSIGNED_BYTE, px);
}

/* The tracer's transfer function and its baked table, after a change. */
static clvr_result read_tf(viewer *v)
{
    clvr_message msg;
    clvr_tf_info ti;
    ti.size = sizeof ti;
    if (clvr_tracer_get_tf(v->tr, &ti, &msg) != CLVR_RESULT_OK) return lib_fail(v, &msg);
    if (ti.table_size != v->table_n) {
        float *t = realloc(v->table, (size_t)ti.table_size * 4 * sizeof(float));
        if (!t) return clvr_app_fail(v->err, CLVR_RESULT_ERR_NO_MEMORY, "out of memory for the transfer function");
        v->table = t;
        v->table_n = ti.table_size;
    }
    if (clvr_tracer_get_tf_table(v->tr, v->table, (size_t)v->table_n * 4, &msg) != CLVR_RESULT_OK)
        return lib_fail(v, &msg);
    snprintf(v->map_name, sizeof v->map_name, "%s", ti.colormap);
    v->range_lo = ti.range_lo;
    v->range_hi = ti.range_hi;
    v->density = ti.density;
    v->ext_scale = ti.extinction_scale > 0.0f ? ti.extinction_scale : 1.0f;
    return CLVR_RESULT_OK;
}

static clvr_result apply_edits(viewer *v)
{
    clvr_result s = CLVR_RESULT_OK;
    clvr_message msg;
    if (v->resized) {
        if (clvr_tracer_set_size(v->tr, v->width, v->height, &msg) != CLVR_RESULT_OK) return lib_fail(v, &msg);
        v->resized = 0;
    }
    if (v->dirty_settings) {
        v->ts.shadows = v->shadows;
        if (clvr_tracer_set_settings(v->tr, &v->ts, &msg) != CLVR_RESULT_OK) return lib_fail(v, &msg);
        if (clvr_tracer_set_pixel_filter(v->tr, v->filter_point ? "point" : "box", &msg) != CLVR_RESULT_OK)
            return lib_fail(v, &msg);
        if (clvr_tracer_set_denoise(v->tr, v->denoise, &msg) != CLVR_RESULT_OK) return lib_fail(v, &msg);
        if (clvr_tracer_set_adaptive(v->tr, v->adaptive, &msg) != CLVR_RESULT_OK) return lib_fail(v, &msg);
        v->dirty_settings = 0;
    }
    if (v->dirty_camera) {
        /* A degenerate view cannot happen with the clamps above; keep the old one rather than stop. */
        if (clvr_tracer_set_camera(v->tr, v->eye, v->target, v->pole, v->fovy, &msg) != CLVR_RESULT_OK)
            fprintf(stderr, "clvr: %s\n", msg.text);
        v->dirty_camera = 0;
    }
    if (v->dirty_tf) {
        if (clvr_tracer_edit_tf(v->tr, v->map_changed ? v->map_name : NULL, v->range_lo, v->range_hi, v->density,
                                &msg) != CLVR_RESULT_OK)
            return lib_fail(v, &msg);
        if ((s = read_tf(v)) != CLVR_RESULT_OK) return s;
        update_strip(v);
        v->dirty_tf = 0;
    }
    v->rays_last = 0;
    return s;
}

/* Renders one frame and copies it into the texture. */
static clvr_result render_frame(viewer *v)
{
    clvr_result s = CLVR_RESULT_OK;
    clvr_message msg;
    clvr_render_stats c;
    c.size = sizeof c;
    if (clvr_tracer_render(v->tr, 1, &msg) != CLVR_RESULT_OK) return lib_fail(v, &msg);
    if ((s = ensure_image(v, v->width, v->height)) != CLVR_RESULT_OK) return s;
    const size_t count = (size_t)v->width * v->height * 4;
    if ((v->denoise ? clvr_tracer_read_denoised(v->tr, v->rgba, count, &msg)
                    : clvr_tracer_read_image(v->tr, v->rgba, count, &msg)) != CLVR_RESULT_OK ||
        clvr_tracer_get_render_stats(v->tr, &c, &msg) != CLVR_RESULT_OK)
        return lib_fail(v, &msg);
    v->img_w = v->width;
    v->img_h = v->height;
    v->img_spp = c.frames;
    snprintf(v->estimator_used, sizeof v->estimator_used, "%s", c.estimator);
    /* Counters restart with the accumulation. */
    uint64_t rays = c.frames <= 1 || c.rays < v->rays_last ? c.rays : c.rays - v->rays_last;
    v->rays_last = c.rays;
    v->rays_since_title += rays;
    v->frames_since_title++;
    /* As the PNG writer maps an opaque image: 2^exposure, tone curve, sRGB. */
    if (clvr_image_to_srgb8(v->rgba, v->img_w, v->img_h, v->display.exposure_ev, v->display.tonemap, v->rgba8,
                            &msg) != CLVR_RESULT_OK)
        return lib_fail(v, &msg);
    glBindTexture(GL_TEXTURE_2D, v->tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (v->tex_w != v->img_w || v->tex_h != v->img_h) {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, (GLsizei)v->img_w, (GLsizei)v->img_h, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                     v->rgba8);
        v->tex_w = v->img_w;
        v->tex_h = v->img_h;
    } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)v->img_w, (GLsizei)v->img_h, GL_RGBA, GL_UNSIGNED_BYTE,
                        v->rgba8);
    }
    return s;
}

/* --- drawing ------------------------------------------------------------- */

static void draw(viewer *v)
{
    int fw, fh;
    glfwGetFramebufferSize(v->win, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glOrtho(0.0, (double)fw, 0.0, (double)fh, -1.0, 1.0); /* pixel units, y up */
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glColor3f(1.0f, 1.0f, 1.0f);
    glEnable(GL_TEXTURE_2D);
    if (v->tex_w) {
        /* Texture row 0 is the image's top row. */
        glBindTexture(GL_TEXTURE_2D, v->tex);
        glBegin(GL_QUADS);
        glTexCoord2f(0, 1); glVertex2f(0, 0);
        glTexCoord2f(1, 1); glVertex2f((float)fw, 0);
        glTexCoord2f(1, 0); glVertex2f((float)fw, (float)fh);
        glTexCoord2f(0, 0); glVertex2f(0, (float)fh);
        glEnd();
    }
    /* The transfer-function strip: colours, the opacity curve, the window. */
    float sh = (float)fh / 14.0f;
    sh = sh < 6.0f ? 6.0f : sh > 24.0f ? 24.0f : sh;
    glBindTexture(GL_TEXTURE_2D, v->strip_tex);
    glBegin(GL_QUADS);
    glTexCoord2f(0, 0); glVertex2f(0, 0);
    glTexCoord2f(1, 0); glVertex2f((float)fw, 0);
    glTexCoord2f(1, 1); glVertex2f((float)fw, sh);
    glTexCoord2f(0, 1); glVertex2f(0, sh);
    glEnd();
    glDisable(GL_TEXTURE_2D);
    float lo, hi;
    strip_range(v, &lo, &hi);
    glColor3f(0.0f, 0.0f, 0.0f);
    glBegin(GL_LINE_STRIP);
    for (int i = 0; i <= 64; ++i) {
        float s = lo + (float)i / 64.0f * (hi - lo);
        float x = (s - v->range_lo) / (v->range_hi - v->range_lo);
        float opacity = v->table_n ? table_at(v, x)[3] / v->ext_scale : 0.0f;
        glVertex2f((float)i / 64.0f * (float)fw, 1.0f + fminf(fmaxf(opacity, 0.0f), 1.0f) * (sh - 2.0f));
    }
    glEnd();
    float xs[2] = {(v->range_lo - lo) / (hi - lo) * (float)fw, (v->range_hi - lo) / (hi - lo) * (float)fw};
    for (int pass = 0; pass < 2; ++pass) {
        glLineWidth(pass == 0 ? 3.0f : 1.0f);
        if (pass == 0) glColor3f(0.0f, 0.0f, 0.0f);
        else glColor3f(1.0f, 1.0f, 1.0f);
        glBegin(GL_LINES);
        for (int i = 0; i < 2; ++i) {
            float x = fminf(fmaxf(xs[i], 1.0f), (float)fw - 1.0f);
            glVertex2f(x, 0.0f);
            glVertex2f(x, sh + 4.0f);
        }
        glEnd();
    }
    glLineWidth(1.0f);
}

/* Writes what the window shows (the back buffer just drawn) to path. */
static void screenshot(viewer *v, const char *path)
{
    int fw, fh;
    glfwGetFramebufferSize(v->win, &fw, &fh);
    if (fw <= 0 || fh <= 0) return;
    draw(v);
    glFinish();
    size_t n = (size_t)fw * fh;
    uint8_t *px = malloc(n * 4), *img = malloc(n * 4);
    clvr_message msg;
    if (!px || !img) {
        fprintf(stderr, "clvr: out of memory for a screenshot\n");
    } else {
        glReadBuffer(GL_BACK);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, px);
        for (int y = 0; y < fh; ++y) /* GL rows are bottom to top */
            memcpy(img + (size_t)y * fw * 4, px + (size_t)(fh - 1 - y) * fw * 4, (size_t)fw * 4);
        if (clvr_image_save_srgb8(path, (uint32_t)fw, (uint32_t)fh, img, &msg) != CLVR_RESULT_OK)
            fprintf(stderr, "clvr: %s\n", msg.text);
        else printf("clvr: screenshot %s (%dx%d)\n", path, fw, fh);
        fflush(stdout);
    }
    free(px);
    free(img);
}

static void update_title(viewer *v, int force)
{
    double t = now_s();
    if (!force && t - v->t_title < TITLE_PERIOD_S) return;
    double dt = t - v->t_title;
    if (dt > 0.0 && v->frames_since_title > 0) {
        v->fps = v->frames_since_title / dt;
        v->mrays = (double)v->rays_since_title / dt * 1e-6;
    } else if (v->img_spp >= CLVR_VIEWER_MAX_SPP) {
        v->fps = v->mrays = 0.0;
    }
    v->t_title = t;
    v->frames_since_title = 0;
    v->rays_since_title = 0;
    const char *mesh = v->o->mesh_path ? strrchr(v->o->mesh_path, '/') : NULL;
    mesh = mesh ? mesh + 1 : v->o->mesh_path ? v->o->mesh_path : "default scene";
    char method[64];
    if (is_march(v)) snprintf(method, sizeof method, "march");
    else if (v->estimator_used[0] && strcmp(v->estimator_used, v->ts.estimator))
        snprintf(method, sizeof method, "%s %s (%s)", v->ts.method, v->ts.estimator, v->estimator_used);
    else snprintf(method, sizeof method, "%s %s", v->ts.method, v->ts.estimator);
    snprintf(v->title, sizeof v->title,
             "clvr | %s | %s | %llu spp%s | %.1f fps | %.2f Mrays/s | %s [%.4g, %.4g] density %.3g | shadows %s | %s",
             mesh, method, (unsigned long long)v->img_spp, v->adaptive > 0.0f ? " + adaptive" : "", v->fps, v->mrays,
             v->map_name, (double)v->range_lo, (double)v->range_hi,
             (double)(v->density / v->density_factor),
             is_march(v) ? "n/a" : v->shadows ? "on" : "off", v->device);
    glfwSetWindowTitle(v->win, v->title);
}

/* --- script ---------------------------------------------------------------- */

static int parse_mods(char **tok, int n, int *mods)
{
    *mods = 0;
    for (int i = 0; i < n; ++i) {
        if (!strcmp(tok[i], "shift")) *mods |= GLFW_MOD_SHIFT;
        else if (!strcmp(tok[i], "ctrl")) *mods |= GLFW_MOD_CONTROL;
        else if (!strcmp(tok[i], "light")) *mods |= VIEW_MOD_LIGHT;
        else return 0;
    }
    return 1;
}

static int parse_key(const char *name, int *key, int *mods)
{
    static const struct { const char *name; int key, mods; } named[] = {
        {"LEFT", GLFW_KEY_LEFT, 0}, {"RIGHT", GLFW_KEY_RIGHT, 0}, {"UP", GLFW_KEY_UP, 0},
        {"DOWN", GLFW_KEY_DOWN, 0}, {"PAGE_UP", GLFW_KEY_PAGE_UP, 0}, {"PAGE_DOWN", GLFW_KEY_PAGE_DOWN, 0},
        {"HOME", GLFW_KEY_HOME, 0}, {"ESCAPE", GLFW_KEY_ESCAPE, 0}, {"[", GLFW_KEY_LEFT_BRACKET, 0},
        {"]", GLFW_KEY_RIGHT_BRACKET, 0}, {"{", GLFW_KEY_LEFT_BRACKET, GLFW_MOD_SHIFT},
        {"}", GLFW_KEY_RIGHT_BRACKET, GLFW_MOD_SHIFT}, {"+", GLFW_KEY_EQUAL, GLFW_MOD_SHIFT},
        {"=", GLFW_KEY_EQUAL, 0}, {"-", GLFW_KEY_MINUS, 0},
    };
    for (size_t i = 0; i < sizeof named / sizeof named[0]; ++i)
        if (!strcasecmp(name, named[i].name)) {
            *key = named[i].key;
            *mods |= named[i].mods;
            return 1;
        }
    if (name[0] && !name[1] && isalnum((unsigned char)name[0])) {
        char c = (char)toupper((unsigned char)name[0]);
        *key = isdigit((unsigned char)c) ? GLFW_KEY_0 + (c - '0') : GLFW_KEY_A + (c - 'A');
        return 1;
    }
    return 0;
}

/* Waits (processing window events) until the framebuffer is w x h. */
static int resize_window(viewer *v, int w, int h)
{
    glfwSetWindowSize(v->win, w, h);
    double t0 = now_s();
    int fw = 0, fh = 0;
    while (now_s() - t0 < 5.0) {
        glfwPollEvents();
        glfwGetFramebufferSize(v->win, &fw, &fh);
        if (fw == w && fh == h) return 1;
        usleep(2000);
    }
    return 0;
}

/* `run CMD`: runs a shell command (tests send real X input with xdotool)
 * and then reads the window events it caused, so that they are handled
 * before the next script command. */
static void run_command(viewer *v, char *cmd)
{
    cmd[strcspn(cmd, "\r\n")] = 0;
    fflush(stdout);
    int rc = system(cmd);
    if (rc != 0) {
        v->status = clvr_app_fail(v->err, CLVR_RESULT_ERR_INTERNAL, "%s:%d: '%s' failed (status %d)", v->script_path,
                                   v->script_line, cmd, rc);
        return;
    }
    /* The X server has queued the events before the command returned; a
     * short pump reads all of them. */
    double t0 = now_s();
    while (now_s() - t0 < 0.2) {
        glfwPollEvents();
        usleep(5000);
    }
}

/* Runs script commands until one asks for frames, the script ends or a
 * command fails (v->status). */
static void run_script(viewer *v)
{
    char line[1024];
    while (v->script && v->wait_frames <= 0 && !v->quit && v->status == CLVR_RESULT_OK) {
        if (!fgets(line, sizeof line, v->script)) {
            fclose(v->script);
            v->script = NULL;
            return;
        }
        v->script_line++;
        char *hash = strchr(line, '#');
        if (hash) *hash = 0;
        char *cmd = line + strspn(line, " \t");
        if (!strncmp(cmd, "run ", 4)) {
            run_command(v, cmd + 4);
            continue;
        }
        char *tok[8];
        int n = 0;
        for (char *p = strtok(line, " \t\r\n"); p && n < 8; p = strtok(NULL, " \t\r\n")) tok[n++] = p;
        if (n == 0) continue;
        int ok = 1, mods = 0, key = 0;
        char *end = NULL;
        if (!strcmp(tok[0], "frames") && n == 2) {
            v->wait_frames = strtol(tok[1], &end, 10);
            ok = *end == 0 && v->wait_frames >= 0;
        } else if (!strcmp(tok[0], "key") && n >= 2) {
            ok = parse_mods(tok + 2, n - 2, &mods) && parse_key(tok[1], &key, &mods);
            if (ok) handle_key(v, key, mods);
        } else if (!strcmp(tok[0], "drag") && n >= 4) {
            int button = !strcmp(tok[1], "left") ? GLFW_MOUSE_BUTTON_LEFT
                         : !strcmp(tok[1], "middle") ? GLFW_MOUSE_BUTTON_MIDDLE
                         : !strcmp(tok[1], "right") ? GLFW_MOUSE_BUTTON_RIGHT : -1;
            char *e1, *e2;
            float dx = strtof(tok[2], &e1), dy = strtof(tok[3], &e2);
            ok = button >= 0 && !*e1 && !*e2 && parse_mods(tok + 4, n - 4, &mods);
            if (ok) handle_drag(v, button, mods, dx, dy);
        } else if (!strcmp(tok[0], "scroll") && n == 2) {
            float dy = strtof(tok[1], &end);
            ok = *end == 0;
            if (ok) zoom(v, dy);
        } else if (!strcmp(tok[0], "resize") && n == 3) {
            long w = strtol(tok[1], &end, 10), h = 0;
            ok = *end == 0 && w > 0 && w <= 16384;
            if (ok) h = strtol(tok[2], &end, 10);
            ok = ok && *end == 0 && h > 0 && h <= 16384;
            if (ok && !resize_window(v, (int)w, (int)h))
                fprintf(stderr, "clvr: %s:%d: the window did not become %ldx%ld\n", v->script_path, v->script_line, w, h);
        } else if (!strcmp(tok[0], "shot") && n == 2) {
            screenshot(v, tok[1]);
        } else if (!strcmp(tok[0], "save") && n == 2) {
            save_image(v, tok[1]);
        } else if (!strcmp(tok[0], "title") && n == 1) {
            update_title(v, 1);
            printf("title: %s\n", v->title);
            fflush(stdout);
        } else if (!strcmp(tok[0], "quit") && n == 1) {
            v->quit = 1;
        } else {
            ok = 0;
        }
        if (!ok)
            v->status = clvr_app_fail(v->err, CLVR_RESULT_ERR_USAGE,
                                       "%s:%d: unknown script command '%s' (see host/app/viewer.h: frames N, key K, "
                                       "drag B DX DY, scroll D, resize W H, shot F, save F, title, quit)",
                                       v->script_path, v->script_line, tok[0]);
    }
}

/* --- entry points ---------------------------------------------------------- */

static clvr_result no_display(clvr_message *err)
{
    const char *desc = NULL;
    glfwGetError(&desc);
    return clvr_app_fail(err, CLVR_RESULT_ERR_NO_DISPLAY,
                          "--view cannot open a window (%s); run it on a display (or under xvfb-run), or "
                          "render to a file instead: clvr MESH -o image.png",
                          desc ? desc : "no display");
}

clvr_result clvr_viewer_probe(clvr_message *err)
{
    if (!glfwInit()) return no_display(err);
    glfwTerminate();
    return CLVR_RESULT_OK;
}

clvr_result clvr_viewer_run(const clvr_options *o, clvr_tracer *tr, const char *device, clvr_message *err)
{
    clvr_result s = CLVR_RESULT_OK;
    int glfw_up = 0;
    clvr_message msg;
    viewer *v = calloc(1, sizeof *v);
    if (!v) return clvr_app_fail(err, CLVR_RESULT_ERR_NO_MEMORY, "out of memory for the viewer");
    v->o = o;
    v->tr = tr;
    v->filter_point = !strcmp(clvr_tracer_pixel_filter(tr), "point");
    v->denoise = clvr_tracer_denoise(tr);
    v->adaptive = clvr_tracer_adaptive(tr);
    v->adaptive_on = v->adaptive > 0.0f ? v->adaptive : CLVR_ADAPTIVE_DEFAULT; /* started with --adaptive off */
    v->device = device ? device : "";
    v->shadows = o->shadows;
    v->err = err;
    v->button = -1;
    v->ts.size = sizeof v->ts;
    clvr_scene_stats st;
    st.size = sizeof st;
    if (clvr_tracer_get_settings(tr, &v->ts, &msg) != CLVR_RESULT_OK ||
        clvr_tracer_size(tr, &v->width, &v->height, &msg) != CLVR_RESULT_OK ||
        clvr_tracer_get_view(tr, v->eye0, v->target0, NULL, &v->fovy, &msg) != CLVR_RESULT_OK ||
        clvr_scene_get_stats(clvr_tracer_scene(tr), &st, &msg) != CLVR_RESULT_OK) {
        s = lib_fail(v, &msg);
        goto cleanup;
    }
    if ((s = read_tf(v)) != CLVR_RESULT_OK) goto cleanup;
    if (!strcmp(v->map_name, "table")) {
        s = clvr_app_fail(err, CLVR_RESULT_ERR_USAGE, "the viewer edits a transfer function set by options, not a table");
        goto cleanup;
    }
    v->data_lo = st.scalar_min;
    v->data_hi = st.scalar_max;
    for (int k = 0; k < 3; ++k) {
        v->eye[k] = v->eye0[k];
        v->target[k] = v->target0[k];
        v->pole[k] = o->camera_set ? o->camera[6 + k] : o->up[k]; /* --up: the framing's axis */
    }
    if (!normalize3(v->pole)) v->pole[1] = 1.0f;
    float ext[3] = {st.hi[0] - st.lo[0], st.hi[1] - st.lo[1], st.hi[2] - st.lo[2]};
    v->diag = len3(ext);
    v->range0_lo = v->range_lo;
    v->range0_hi = v->range_hi;
    v->density_factor = o->density > 0.0f && v->density > 0.0f ? v->density / o->density : 1.0f;
    clvr_image_settings_init(&v->display);
    v->display.exposure_ev = o->exposure;
    v->display.tonemap = clvr_cli_tonemap_name(o->tonemap);
    v->display.transparent = o->transparent;

    /* The colour maps to cycle through, from libclvr's list. */
    const char *names = clvr_colormap_names();
    v->map_index = -1;
    while (*names && v->num_maps < MAX_MAPS) {
        size_t len = strcspn(names, ", ");
        if (len > 0 && len < sizeof v->maps[0]) {
            memcpy(v->maps[v->num_maps], names, len);
            v->maps[v->num_maps][len] = 0;
            if (!strcasecmp(v->maps[v->num_maps], v->map_name)) v->map_index = v->num_maps;
            v->num_maps++;
        }
        names += len;
        names += strspn(names, ", ");
    }

    const char *script = getenv("CLVR_VIEW_SCRIPT");
    if (script && *script) {
        v->script_path = script;
        v->script = fopen(script, "r");
        if (!v->script) {
            s = clvr_app_fail(err, CLVR_RESULT_ERR_IO, "CLVR_VIEW_SCRIPT %s: cannot open it", script);
            goto cleanup;
        }
    }

    if (!glfwInit()) { s = no_display(err); goto cleanup; }
    glfw_up = 1;
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_FALSE);
    v->win = glfwCreateWindow((int)o->width, (int)o->height, "clvr", NULL, NULL);
    if (!v->win) {
        const char *desc = NULL;
        glfwGetError(&desc);
        s = clvr_app_fail(err, CLVR_RESULT_ERR_NO_DISPLAY,
                           "--view cannot create an OpenGL window (%s); render to a file instead with -o image.png",
                           desc ? desc : "unknown GLFW error");
        goto cleanup;
    }
    glfwSetWindowUserPointer(v->win, v);
    glfwMakeContextCurrent(v->win);
    glfwSwapInterval(0); /* the renderer paces the loop, not the display */
    glfwSetKeyCallback(v->win, on_key);
    glfwSetMouseButtonCallback(v->win, on_button);
    glfwSetCursorPosCallback(v->win, on_cursor);
    glfwSetScrollCallback(v->win, on_scroll);
    glfwSetWindowRefreshCallback(v->win, on_refresh);
    glfwGetCursorPos(v->win, &v->mx, &v->my);
    glGenTextures(1, &v->tex);
    glGenTextures(1, &v->strip_tex);
    GLuint texs[2] = {v->tex, v->strip_tex};
    for (int i = 0; i < 2; ++i) {
        glBindTexture(GL_TEXTURE_2D, texs[i]);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, i == 0 ? GL_NEAREST : GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, i == 0 ? GL_NEAREST : GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    update_strip(v);
    if (!o->quiet) fprintf(stderr, "clvr: viewer open; press H for the controls, Q to quit\n");
    v->t_title = now_s();

    while (!v->quit && v->status == CLVR_RESULT_OK && !glfwWindowShouldClose(v->win)) {
        int fw, fh;
        glfwGetFramebufferSize(v->win, &fw, &fh);
        int busy = v->resized || v->dirty_settings || v->dirty_camera || v->dirty_tf || v->wait_frames > 0 ||
                   (v->script && v->wait_frames <= 0) || (v->img_spp < CLVR_VIEWER_MAX_SPP && fw > 0 && fh > 0);
        if (busy) glfwPollEvents();
        else glfwWaitEventsTimeout(0.5);
        if (v->status != CLVR_RESULT_OK || v->quit) break;
        run_script(v);
        if (v->status != CLVR_RESULT_OK || v->quit) break;
        glfwGetFramebufferSize(v->win, &fw, &fh);
        if (fw > 0 && fh > 0 && ((uint32_t)fw != v->width || (uint32_t)fh != v->height)) {
            v->width = (uint32_t)fw;
            v->height = (uint32_t)fh;
            v->resized = v->dirty_camera = 1;
        }
        int changed = v->resized || v->dirty_settings || v->dirty_camera || v->dirty_tf;
        if (changed) {
            v->status = apply_edits(v);
            if (v->status != CLVR_RESULT_OK) break;
            v->img_spp = 0;
        }
        int rendered = 0;
        if (fw > 0 && fh > 0 && (changed || v->img_spp < CLVR_VIEWER_MAX_SPP)) {
            v->status = render_frame(v);
            if (v->status != CLVR_RESULT_OK) break;
            rendered = 1;
        }
        if (v->wait_frames > 0) v->wait_frames--;
        if (rendered || changed) {
            draw(v);
            glfwSwapBuffers(v->win);
        }
        update_title(v, 0);
    }
    s = v->status;

cleanup:
    if (v->win) {
        if (v->tex) glDeleteTextures(1, &v->tex);
        if (v->strip_tex) glDeleteTextures(1, &v->strip_tex);
        glfwDestroyWindow(v->win);
    }
    if (glfw_up) glfwTerminate();
    if (v->script) fclose(v->script);
    free(v->table);
    free(v->rgba);
    free(v->rgba8);
    free(v);
    return s;
}
