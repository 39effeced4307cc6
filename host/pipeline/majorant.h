/* majorant.h: the majorants of the renderer's free-flight sampling (paper
 * 3.4.1 and 3.4.3) and the device buffers that hold them: one per sampling
 * cluster (track's global majorant is their largest, bins reads them per
 * cluster) and the two-level macrocell grid of dda (a range of scalars per
 * cell rasterized from the elements, a majorant per cell and per block of
 * CLVR_DDA_BLOCK^3 cells). Dispatches kernels/majorant.cl.
 *
 * The kernels read the grid domain and resolution (grid_lo, grid_hi,
 * grid_res) and the transfer-function window (tf_size, tf_lo, tf_hi,
 * density) from the caller's device copy of its clvr_frame, so every call
 * that takes `frame` expects that buffer to hold the current values. */
#ifndef CLVR_MAJORANT_H
#define CLVR_MAJORANT_H

#include <stdint.h>

#include "cl_context.h"
#include "clvr_shared.h"
#include "preprocess.h"

typedef struct clvr_majorants clvr_majorants;

/* The device arrays the render kernel reads (CLVR_VOLUME_ARRAYS'
 * cluster_majorants, grid and blocks): the grid the last
 * clvr_majorants_set_tf chose. Valid until the next clvr_majorants_build_grid
 * that rebuilds, or clvr_majorants_destroy. */
typedef struct clvr_majorant_arrays {
    cl_mem clusters; /* float [mesh->num_sampling] */
    cl_mem cells;    /* float [res^3], index clvr_grid_index (res: clvr_majorants_grid) */
    cl_mem blocks;   /* float [clvr_majorant_blocks(res)^3] */
} clvr_majorant_arrays;

/* Blocks per axis of a grid of res cells per axis: ceil(res / CLVR_DDA_BLOCK). */
uint32_t clvr_majorant_blocks(uint32_t res);

/* Builds kernels/majorant.cl and allocates the cluster majorants of mesh
 * (not owned: it must outlive the object). No grid yet: call
 * clvr_majorants_build_grid, then clvr_majorants_set_tf. */
clvr_status clvr_majorants_create(clvr_cl *cl, const clvr_clustered *mesh, clvr_majorants **out, clvr_error *err);
void clvr_majorants_destroy(clvr_majorants *m); /* accepts NULL */

/* Makes the macrocell grid match f->grid_res cells per axis over
 * [f->grid_lo, f->grid_hi]: allocates it and rasterizes the elements'
 * scalar ranges into it, once per mesh, resolution and domain (nothing to do
 * when those are unchanged). *rebuilt (may be NULL) tells whether it did;
 * a rebuilt grid has no majorants until the next clvr_majorants_set_tf. On
 * failure the grid is left empty and the next call builds it again. */
clvr_status clvr_majorants_build_grid(clvr_majorants *m, const clvr_frame *f, cl_mem frame, int *rebuilt,
                                      clvr_error *err);

/* Maps every cluster, cell and block range through the transfer function
 * tf (f->tf_size entries of rgb + extinction, the window and density of f)
 * and returns the largest cluster majorant (the global majorant of track;
 * 0 for a mesh without clusters) in *global_majorant. Call after
 * clvr_majorants_build_grid, and again whenever the transfer function or
 * the grid changes. choose (the automatic grid, see CLVR_MACROCELLS_FINE;
 * a resolution that is a multiple of CLVR_DDA_BLOCK): the frames get the
 * rasterized grid or, where its cells' mean majorant is not below
 * CLVR_MACROCELLS_GAIN times its blocks', the grid of its blocks
 * (clvr_majorants_grid tells which). */
clvr_status clvr_majorants_set_tf(clvr_majorants *m, cl_mem tf, cl_mem frame, int choose, float *global_majorant,
                                  clvr_error *err);

/* Cells per axis of the grid the frames read (clvr_majorants_arrays; the
 * frame's grid_res must say the same), and the mean majorant of the
 * rasterized grid's cells and of its blocks' at the last choice (0 and 0
 * when set_tf did not choose). */
uint32_t clvr_majorants_grid(const clvr_majorants *m, double *fine_mean, double *coarse_mean);

clvr_majorant_arrays clvr_majorants_arrays(const clvr_majorants *m);

/* Copies the majorants of every sampling cluster (mesh->num_sampling),
 * macrocell and block of the grid the frames read (res^3 and
 * clvr_majorant_blocks(res)^3, res from clvr_majorants_grid) to the host;
 * any may be NULL. */
clvr_status clvr_majorants_read(clvr_majorants *m, float *clusters, float *cells, float *blocks, clvr_error *err);

#endif
