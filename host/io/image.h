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
 *   .pfm  portable float map "PF": linear float r g b, little-endian (scale
 *         -1.0), rows bottom to top as the format requires. PFM has no
 *         alpha: it is dropped (r g b already hold the background).
 * Writes are atomic: the data go to "<path>.tmp.<pid>" in the same directory
 * which is renamed onto path only when complete and flushed; on any failure
 * the temporary file is removed, an older file at path is left intact and
 * CLVR_ERR_WRITE names the path and the OS error. */
#ifndef CLVR_IMAGE_H
#define CLVR_IMAGE_H

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
