/* mpi_share.h: a rank's share of a mesh in data-parallel (MPI) mode, and the
 * convex regions that decide it (docs/mpi-compositing.md).
 *
 * The medium is cut into N axis-aligned boxes (regions) that tile the mesh's
 * bounds: recursive bisection of element centroids at the count median along
 * the longest axis. Rank r keeps every element whose vertex box overlaps its
 * closed region (its own elements and the ghosts that straddle a face) and
 * renders the medium inside the region only, so each point of space belongs
 * to one rank (faces shared by two regions have measure zero) and a ray meets
 * each rank in one interval: that is what makes front-to-back compositing of
 * per-rank estimates exact.
 *
 * Two producers fill a clvr_mpi_share, and every rank of a job uses the
 * same one: clvr_mpi_load_share_bin (mpi_load.c: a .bin file read with
 * offsets, each rank about 1/N of it) and clvr_mpi_share_from_mesh (the
 * built-in scene and formats that cannot be read in parts: every rank holds
 * the whole mesh for a moment and keeps its share). The regions function
 * below has no MPI in it, so it is tested without mpirun. */
#ifndef CLVR_MPI_SHARE_H
#define CLVR_MPI_SHARE_H

#include <stdint.h>

#include "mesh.h"
#include "status.h"

typedef struct clvr_mpi_share {
    clvr_mesh mesh;                   /* owned + ghost elements, local vertex numbering, the chosen point scalar */
    float region_lo[3], region_hi[3]; /* this rank's closed box; the regions of all ranks tile [bounds_lo, bounds_hi] */
    float bounds_lo[3], bounds_hi[3]; /* of the whole mesh, the same on every rank */
    float scalar_min, scalar_max;     /* of the whole mesh's chosen scalar, the same on every rank */
    uint64_t global_vertices, global_elements;
    uint64_t owned_elements;          /* elements whose centroid this rank owns (clvr_mpi_region_of); sums to
                                       * global_elements over the ranks */
    uint8_t *owned;                   /* per element of `mesh` (tets, pyramids, wedges, hexes in order): 1 where
                                       * this rank owns it; sums over the job count every element once (the
                                       * automatic transfer function's histogram and density grid) */
} clvr_mpi_share;

/* Regions for `nranks` ranks from `n` centroids (3 floats each, may be a
 * sample of the mesh's): `regions` receives nranks boxes of 6 floats
 * (lo x y z, hi x y z) that tile [lo, hi] exactly, rank r's box at 6r. A
 * split puts floor(k/2) of k ranks on the low side with about that share of
 * the centroids. Deterministic: the same input gives the same boxes on every
 * rank. `centroids` is reordered (partial sorts). n = 0 is allowed (equal
 * splits of the box). */
clvr_status clvr_mpi_regions(float *centroids, uint64_t n, const float lo[3], const float hi[3], uint32_t nranks,
                             float *regions, clvr_error *err);

/* The one region that owns point p: the first r whose box holds p with the
 * upper faces open, except where a face is the bounds' own upper face (so
 * every point of [lo, hi] has exactly one owner). Points outside every box
 * give the nearest by clamping. */
uint32_t clvr_mpi_region_of(const float *regions, uint32_t nranks, const float p[3]);

/* Nonzero when the closed boxes [alo, ahi] and [blo, bhi] overlap (touching
 * counts: an element on a face is a ghost of both sides). */
int clvr_mpi_boxes_overlap(const float alo[3], const float ahi[3], const float blo[3], const float bhi[3]);

void clvr_mpi_share_free(clvr_mpi_share *s); /* accepts NULL and half-built shares; leaves *s zeroed */

#endif
