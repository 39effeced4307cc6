/* tf.h: the transfer function: a colour map (control points interpolated in
 * RGB, CIELAB, Moreland's diverging Msh space, HSV or as steps), an opacity
 * curve (piecewise-linear points with ParaView's midpoint/sharpness), a
 * scalar window [range_lo, range_hi] and a density scale. It is baked into a
 * table of n entries (linear rgb + extinction) that the kernels look up with
 * the shared functions of kernels/clvr_shared.h (clvr_tf_lookup,
 * clvr_tf_majorant). Conventions, file formats and units:
 * docs/transfer-function.md. */
#ifndef CLVR_TF_H
#define CLVR_TF_H

#include <stddef.h>
#include <stdint.h>

#include "clvr_shared.h"
#include "status.h"

/* Optical depth along the mesh's bounding-box diagonal of a medium with
 * opacity 1 at density 1: extinction = density * opacity(s) * K / diagonal,
 * i.e. the mean free path at full opacity is 1/K of the diagonal. */
#define CLVR_TF_DIAGONAL_DEPTH 8.0f

/* Largest table and transfer-function file the loaders accept. */
#define CLVR_TF_MAX_TABLE 65536u
#define CLVR_TF_MAX_FILE_BYTES (16u << 20)

typedef enum clvr_tf_space {
    CLVR_TF_SPACE_RGB = 0,       /* linear in the (sRGB-encoded) values, ParaView "RGB" */
    CLVR_TF_SPACE_LAB = 1,       /* CIELAB, ParaView "Lab" (and "Lab/CIEDE2000", approximated) */
    CLVR_TF_SPACE_DIVERGING = 2, /* Moreland's Msh with a white midpoint, ParaView "Diverging" */
    CLVR_TF_SPACE_HSV = 3,       /* HSV along the shorter hue arc, ParaView "HSV" */
    CLVR_TF_SPACE_STEP = 4,      /* constant from each point to the next, ParaView "Step" */
    CLVR_TF_SPACE_COUNT
} clvr_tf_space;

/* Control-point positions x are normalised: 0 is range_lo, 1 is range_hi.
 * Colours are sRGB-encoded display values in [0, 1] as colour maps are
 * published; baking decodes them to linear rgb. */
typedef struct clvr_tf {
    char name[64];            /* colour map name, for messages and --stats */
    uint32_t space;           /* clvr_tf_space */
    uint32_t num_colors;      /* >= 1 */
    float *colors;            /* 4 per point: x, r, g, b; x non-decreasing */
    uint32_t num_opacity;     /* >= 1 */
    float *opacity;           /* 4 per point: x, opacity, midpoint, sharpness (ParaView) */
    int opacity_set;          /* nonzero when a file gave the opacity points */
    float range_lo, range_hi; /* scalar window, range_lo < range_hi */
    int range_set;            /* nonzero when a file or the caller chose the window */
    float density;            /* dimensionless scale, >= 0 (1: see CLVR_TF_DIAGONAL_DEPTH) */
    float extent;             /* world length the density is relative to (the mesh diagonal); <= 0: 1 */
    uint32_t table_size;      /* entries of the baked table, 2..CLVR_TF_MAX_TABLE */
} clvr_tf;

/* "cool-warm, viridis, inferno, grayscale, jet". */
const char *clvr_tf_colormap_names(void);

/* Resets tf (freeing what it held) to the built-in colour map `colormap`
 * (NULL: "cool-warm"), opacity ramp 0 -> 1, window [0, 1] (not set),
 * density 1, extent 0, table CLVR_TF_DEFAULT_SIZE. tf must be zeroed or
 * valid. Unknown name: CLVR_ERR_USAGE listing the names. */
clvr_status clvr_tf_init(clvr_tf *tf, const char *colormap, clvr_error *err);

/* Replaces the colour points with a built-in colour map. */
clvr_status clvr_tf_set_colormap(clvr_tf *tf, const char *colormap, clvr_error *err);

/* Loads a transfer-function file into tf (already initialised): the simple
 * text format or a ParaView colour-map JSON export, told apart by the first
 * non-blank character ('[' or '{': JSON). `path` may be FILE:PRESET (when
 * `path` itself does not open) to pick the JSON map whose "Name" is PRESET
 * from a multi-preset file. ParaView JSON sets the window to the span of
 * its data-space positions. What the file sets replaces what
 * tf held; what it leaves out stays. A file `density d` multiplies
 * tf->density. Errors: CLVR_ERR_IO (cannot read, too large),
 * CLVR_ERR_BAD_FIELD with "path:line[:column]: what was expected"; on error
 * tf is unchanged. */
clvr_status clvr_tf_load(clvr_tf *tf, const char *path, clvr_error *err);

/* The same from memory (len bytes, need not be NUL-terminated); `name`
 * prefixes the messages. This is what the fuzz target drives. */
clvr_status clvr_tf_parse(clvr_tf *tf, const char *text, size_t len, const char *name, clvr_error *err);
/* The same, picking the JSON colour map named `preset` (NULL: the first);
 * an unknown name is CLVR_ERR_BAD_FIELD listing the file's names. */
clvr_status clvr_tf_parse_preset(clvr_tf *tf, const char *text, size_t len, const char *name, const char *preset,
                                 clvr_error *err);

/* What the command line asks for: built-in colormap (NULL: cool-warm), then
 * tf_file (NULL: none) over it, then the window: [range_lo, range_hi] when
 * range_set, else the file's `range`, else the data range
 * [scalar_min, scalar_max] (widened when it is a single value); density
 * multiplies the file's. Fresh tf (zeroed or freed). */
clvr_status clvr_tf_from_options(clvr_tf *tf, const char *colormap, const char *tf_file, int range_set,
                                 float range_lo, float range_hi, float density, float scalar_min, float scalar_max,
                                 clvr_error *err);

/* Sets extent to the diagonal of the box [lo, hi] (the mesh bounds), which
 * makes density relative to the mesh size (see CLVR_TF_DIAGONAL_DEPTH). */
void clvr_tf_set_extent(clvr_tf *tf, const float lo[3], const float hi[3]);

/* Extinction per unit density at opacity 1, 1/world length:
 * CLVR_TF_DIAGONAL_DEPTH / extent (extent <= 0 counts as 1). */
float clvr_tf_extinction_scale(const clvr_tf *tf);

/* tf->table_size. */
uint32_t clvr_tf_table_size(const clvr_tf *tf);

/* Bakes n >= 2 entries into rgba (4n floats): entry i is the transfer
 * function at x = i / (n - 1): linear r, g, b (sRGB-decoded colour map) and
 * opacity(x) * clvr_tf_extinction_scale(tf); the kernels multiply by the
 * density (clvr_tf_lookup). */
void clvr_tf_bake(const clvr_tf *tf, float *rgba, uint32_t n);

/* The colour map at normalised position x (clamped to [0, 1]), as
 * sRGB-encoded values in [0, 1]. */
void clvr_tf_color(const clvr_tf *tf, float x, float srgb[3]);
/* The opacity curve at normalised position x (clamped), in [0, 1]. */
float clvr_tf_opacity(const clvr_tf *tf, float x);

/* Frees the point arrays; accepts NULL and zeroed structs; leaves *tf zeroed. */
void clvr_tf_free(clvr_tf *tf);

#endif /* CLVR_TF_H */
