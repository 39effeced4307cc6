/* image.h: RGBA float images and their files.
 *
 * Pixel convention (what the renderer produces and every writer expects):
 * rows top to bottom, 4 floats per pixel. r, g, b are LINEAR radiance as the
 * camera sees it, the background seen through the volume included (so they
 * are what to display; with a black background they are the volume's light,
 * which is alpha-premultiplied by construction). a is the volume's opacity
 * along the pixel's ray, 1 - transmittance, in [0, 1]: coverage information.
 * Writers never multiply or divide by alpha.
 *
 * Files, chosen by the extension of the path (case-insensitive):
 *   .exr  OpenEXR, 32-bit float R G B A, ZIP compression, written with the
 *         OpenEXR core C API (openexr.h; ImfCRgbaFile.h only does half);
 *         values stored unchanged (linear, alpha as above).
 *   .png  8-bit RGB, opaque; r g b clamped to [0, 1] and encoded with the
 *         sRGB transfer curve (IEC 61966-2-1), sRGB chunk set. Alpha is
 *         dropped: r g b already hold the background (use .exr for alpha).
 *         clvr_image_write_display adds, for PNG only, an exposure, a tone
 *         curve and a transparent mode (8-bit RGBA, straight alpha).
 *   .pfm  portable float map "PF": linear float r g b, little-endian (scale
 *         -1.0), rows bottom to top as the format requires. PFM has no
 *         alpha: it is dropped (r g b already hold the background).
 * Writes are atomic: the data go to "<path>.tmp.<pid>" in the same directory
 * which is renamed onto path only when complete and flushed; on any failure
 * the temporary file is removed, an older file at path is left intact and
 * CLVR_ERR_WRITE names the path and the OS error. */
#ifndef CLVR_IMAGE_H
#define CLVR_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "status.h"

typedef struct clvr_image {
    uint32_t width, height;
    float *rgba; /* width * height * 4, rows top to bottom */
} clvr_image;

/* Largest width or height the readers accept (and writers write). */
#define CLVR_IMAGE_MAX_DIM (1u << 16)

/* Allocates a zeroed image. Errors: CLVR_ERR_USAGE (empty or larger than
 * CLVR_IMAGE_MAX_DIM), CLVR_ERR_NO_MEMORY. */
clvr_status clvr_image_alloc(clvr_image *img, uint32_t width, uint32_t height, clvr_error *err);
/* Frees the pixels; accepts NULL and zeroed images; leaves *img zeroed. */
void clvr_image_free(clvr_image *img);

/* "exr, png, pfm". */
const char *clvr_image_formats(void);

/* Writes width x height pixels (see the convention above) to path, by its
 * extension. Errors: CLVR_ERR_USAGE (unknown extension: the message lists the
 * supported ones; bad size), CLVR_ERR_WRITE (path and OS error). */
clvr_status clvr_image_write(const char *path, uint32_t width, uint32_t height, const float *rgba, clvr_error *err);

/* Display transforms of 8-bit output (PNG). Scene-linear values are scaled
 * by 2^exposure_ev, then mapped by the tone curve to [0, 1], then sRGB-
 * encoded. The curves (clvr_image_tonemap):
 *   none    clamp to [0, 1] (what clvr_image_write does);
 *   aces    Narkowicz's fit of the ACES RRT+ODT (2015), x (2.51 x + 0.03) /
 *           (x (2.43 x + 0.59) + 0.14), of CLVR_TONEMAP_GAIN * x;
 *   filmic  Hable's Uncharted 2 curve (exposure bias 2, white point 11.2)
 *           of CLVR_TONEMAP_GAIN * x.
 * Both curves have a toe (darks stay dark) and a shoulder that reaches 1 at
 * scene value 4.83 (aces) or 3.73 (filmic) instead of 1 (none), so highlights
 * keep their shape; aces has more contrast. */
typedef enum clvr_tonemap {
    CLVR_TONEMAP_NONE = 0,
    CLVR_TONEMAP_ACES = 1,
    CLVR_TONEMAP_FILMIC = 2,
    CLVR_TONEMAP_COUNT
} clvr_tonemap;

/* Scene-linear gain the aces and filmic curves apply before the curve. clvr's
 * default lights put a lit sample of albedo 1 at 1.3 (light 1 + ambient 0.3);
 * with 1.5 it maps to 0.91 (sRGB code 245) under aces, leaving headroom, and
 * the converged built-in scene (brightest pixel 0.71 linear, 99.9th
 * percentile 0.57) spans codes up to 233 with none clipped, where the plain
 * clamp stops at 219 and looks dim. */
#define CLVR_TONEMAP_GAIN 1.5f

/* "none", "aces", "filmic"; "?" for other values. */
const char *clvr_tonemap_name(clvr_tonemap t);
/* Parses a curve name; returns CLVR_TONEMAP_COUNT for an unknown one. */
clvr_tonemap clvr_tonemap_parse(const char *name);
/* The curve of t at an exposed scene-linear value x >= 0: a display-linear
 * value in [0, 1] (NaN and negative x give 0). */
float clvr_image_tonemap(clvr_tonemap t, float x);

/* A colour legend drawn into 8-bit output: the transfer function's colours
 * from lo (left) to hi (right) as a bar, the field's name above it and the
 * two ends' values below it, white text (a built-in 5x7 font; lower case is
 * drawn as upper case, characters it lacks as '?') on a panel that darkens
 * the image by 60%, at the bottom-left corner. Everything scales by
 * max(1, min(width, height) / 256) pixels per font pixel. The bar shows the
 * colour map sRGB-encoded, without the image's exposure or tone curve. */
typedef struct clvr_image_legend {
    const float *table;   /* entries x (r, g, b, extinction), linear, as clvr_tf_bake writes */
    uint32_t entries;     /* >= 1 */
    float lo, hi;         /* the scalar window the table spans */
    const char *name;     /* the field's name; NULL or "": "scalar" */
} clvr_image_legend;

/* Where clvr_image_draw_legend draws in a width x height image: rectangles
 * as x0, y0, x1, y1 (x1, y1 exclusive; may be clipped by the image), the
 * title's and the labels' top-left corners, the font scale. */
typedef struct clvr_image_legend_layout {
    uint32_t scale;
    int32_t panel[4], bar[4];
    int32_t title_x, title_y, labels_y;
    uint32_t title_chars; /* characters of the name that fit */
} clvr_image_legend_layout;

void clvr_image_legend_layout_of(uint32_t width, uint32_t height, const clvr_image_legend *legend,
                                 clvr_image_legend_layout *out);

/* Draws the legend into px: width x height pixels of channels (3: RGB, 4:
 * RGBA with straight alpha, which the panel makes at least 60% opaque) 8-bit
 * sRGB samples, rows top to bottom. Pixels outside the image are skipped. */
void clvr_image_draw_legend(uint8_t *px, uint32_t channels, uint32_t width, uint32_t height,
                            const clvr_image_legend *legend);

/* The 5x7 glyph of c (7 rows, bit 4 = leftmost column), or NULL for a space. */
const uint8_t *clvr_image_glyph(char c);

typedef struct clvr_image_display {
    float exposure_ev;    /* stops: scene values are scaled by 2^exposure_ev */
    clvr_tonemap tonemap;
    /* Nonzero: write PNG as RGBA with alpha = the pixel's a, and r g b
     * divided by a (PNG's alpha is straight, the renderer's colour is
     * premultiplied: render over a black background for this). */
    int transparent;
    const clvr_image_legend *legend; /* NULL: none */
} clvr_image_display;

/* As clvr_image_write, with display transforms for PNG (display may be NULL:
 * none, 0 EV, opaque). EXR and PFM ignore display: they stay scene-linear. */
clvr_status clvr_image_write_display(const char *path, uint32_t width, uint32_t height, const float *rgba,
                                     const clvr_image_display *display, clvr_error *err);

/* path with ".NNNN" (index, at least 4 digits) inserted before its extension
 * (or appended when it has none): "out/a.png" -> "out/a.0007.png". Returns 0
 * when out (size bytes) is too small. */
int clvr_image_numbered_path(const char *path, uint32_t index, char *out, size_t size);

/* Nonzero when path's extension is .png (case-insensitive). */
int clvr_image_is_png(const char *path);

/* Checks, before any long work, that path has a supported extension
 * (CLVR_ERR_USAGE) and that its directory exists and is writable
 * (CLVR_ERR_WRITE naming the directory and the OS error). */
clvr_status clvr_image_check_output(const char *path, clvr_error *err);

/* Reads a .exr (single-part scanline file with R G B [A] channels, half or
 * float; missing A reads as 1), .pfm (PF or grey Pf; A = 1) or .png (decoded
 * from sRGB to linear) into a fresh image (caller frees). Errors:
 * CLVR_ERR_USAGE (extension), CLVR_ERR_IO, CLVR_ERR_FORMAT / CLVR_ERR_TRUNCATED
 * (bad file). */
clvr_status clvr_image_read(const char *path, clvr_image *out, clvr_error *err);

/* sRGB transfer curve (IEC 61966-2-1) of one component: encode maps linear
 * to display values (no clamping), decode the inverse. */
float clvr_image_srgb_encode(float linear);
float clvr_image_srgb_decode(float srgb);
/* Linear value -> 8-bit sRGB code: clamp to [0, 1] (NaN -> 0), encode, round. */
uint8_t clvr_image_srgb_to_u8(float linear);

#endif /* CLVR_IMAGE_H */
