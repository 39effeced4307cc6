/* tf_auto.h: the automatic transfer function (issue 17): an opacity curve
 * from the scalar's volume-weighted histogram and a density from the mesh's
 * optical depth. docs/transfer-function.md ("Automatic opacity and
 * density") gives the definitions and the measured figures. */
#ifndef CLVR_TF_AUTO_H
#define CLVR_TF_AUTO_H

#include <stdint.h>

#include "mesh.h"
#include "status.h"
#include "tf.h"

/* Bins of the histogram behind the automatic opacity. */
#define CLVR_TF_AUTO_BINS 64u
/* A bin holding this many times the uniform share (1 / bins) of the volume
 * or more gets opacity 0; one holding 1 / this many times or less gets 1;
 * log-linear in between (the uniform share gets 0.5). */
#define CLVR_TF_AUTO_SHARE 8.0f
/* Exponent of the side-distribution factor (see clvr_tf_auto_opacity). */
#ifndef CLVR_TF_AUTO_GAMMA
#define CLVR_TF_AUTO_GAMMA 1.0f
#endif
/* The automatic density puts the median optical depth of the probe rays
 * that meet the visible medium at this value (transmittance e^-0.75 = 47%). */
#define CLVR_TF_AUTO_DEPTH 0.75f

/* Volume-weighted histogram of the vertex scalar over [lo, hi] (lo < hi):
 * each element's volume (clvr_scene_cell_volume, absolute) is shared equally
 * by its vertices, whose scalar falls into one of `bins` equal bins (clamped
 * to the ends, as the transfer function clamps; NaN ignored). hist receives
 * the volumes. */
void clvr_tf_auto_histogram(const clvr_mesh *m, float lo, float hi, double *hist, uint32_t bins);

/* Replaces tf's opacity points with the histogram's curve: bin b with share
 * p_b of the total gets a = clamp(1/2 - log(p_b * bins) / (2 log SHARE), 0, 1),
 * after smoothing the shares with a [1 2 1] / 4 filter; points at the bins'
 * centres plus the two ends. A histogram with fewer than 2 non-empty bins
 * (empty, or a constant field) leaves tf unchanged.
 * Errors: CLVR_ERR_NO_MEMORY. */
clvr_status clvr_tf_auto_opacity(clvr_tf *tf, const double *hist, uint32_t bins, clvr_error *err);

/* Optical depth statistics of tf at its current density over the mesh
 * (tf's extent must be set): the mesh is binned into a grid of about 48^3
 * cells (each element's extinction, from the mean opacity of its vertices,
 * times its volume spread over the cells its bounding box overlaps, divided
 * by the cell's volume or, where overlapping or duplicated elements add up
 * to more, by theirs), then
 * 48 x 48 parallel probe rays cross the box along each of the 3 axes and
 * the 4 diagonals. median_depth: the median optical depth of the rays
 * whose depth exceeds 1e-3 x the largest (those that meet the visible
 * medium); 0 when none does. Errors: CLVR_ERR_NO_MEMORY. */
clvr_status clvr_tf_auto_probe(const clvr_mesh *m, const clvr_tf *tf, float *median_depth, clvr_error *err);

/* The density that puts the probe median at CLVR_TF_AUTO_DEPTH for tf with
 * density 1 (tf->density is ignored), clamped to [1e-3, 1e4]; 1 when the
 * medium is invisible everywhere. */
clvr_status clvr_tf_auto_density(const clvr_mesh *m, const clvr_tf *tf, float *density, clvr_error *err);

/* The same figures from sums that several processes can add up (MPI mode:
 * each rank sums the elements it owns, keep[e] != 0 for element e counted
 * across the types in order, NULL for all; the ranks add the arrays; every
 * rank then finishes the same way). clvr_tf_auto_histogram is
 * clvr_tf_auto_histogram_kept with keep NULL, and clvr_tf_auto_probe is
 * grid_create over m's bounds, grid_add, grid_median. */
void clvr_tf_auto_histogram_kept(const clvr_mesh *m, const uint8_t *keep, float lo, float hi, double *hist,
                                  uint32_t bins);

typedef struct clvr_tf_auto_grid {
    int n[3];
    size_t cells;           /* n[0] n[1] n[2]; 0 for empty or degenerate bounds (median 0) */
    double lo[3], ext[3], cell_h[3];
    double *sigma, *covered; /* per cell: extinction x volume, elements' volume (one allocation) */
} clvr_tf_auto_grid;

/* Cells over [bounds_lo, bounds_hi], zeroed. Errors: CLVR_ERR_NO_MEMORY. */
clvr_status clvr_tf_auto_grid_create(const float bounds_lo[3], const float bounds_hi[3], clvr_tf_auto_grid *g,
                                     clvr_error *err);
/* Adds the kept elements of m with tf's opacity and density. */
clvr_status clvr_tf_auto_grid_add(clvr_tf_auto_grid *g, const clvr_mesh *m, const uint8_t *keep, const clvr_tf *tf,
                                  clvr_error *err);
/* The probe rays' median optical depth through the summed grid. */
clvr_status clvr_tf_auto_grid_median(const clvr_tf_auto_grid *g, float *median_depth, clvr_error *err);
void clvr_tf_auto_grid_free(clvr_tf_auto_grid *g);
/* The automatic density for a probe median at density 1 (clvr_tf_auto_density). */
float clvr_tf_auto_density_of_median(float median_depth);

#endif /* CLVR_TF_AUTO_H */
