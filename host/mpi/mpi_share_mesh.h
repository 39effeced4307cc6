/* mpi_share_mesh.h: a rank's share of a mesh every rank holds whole (the
 * built-in scene and the formats that cannot be read in parts). The other
 * producer of a clvr_mpi_share, for .bin files read with offsets, is
 * clvr_mpi_load_share_bin (mpi_load.h). */
#ifndef CLVR_MPI_SHARE_MESH_H
#define CLVR_MPI_SHARE_MESH_H

#include <mpi.h>

#include "mpi_share.h"

/* Collective over comm: every rank passes the same whole mesh. Computes the
 * regions from all element centroids (clvr_mpi_regions, so every rank gets
 * the same boxes) and keeps in out->mesh the elements whose vertex box
 * overlaps this rank's region, with the vertices they use renumbered in
 * their original order (local numbering) and the chosen scalar. Bounds and
 * scalar range are the whole mesh's. The same status on every rank. */
clvr_status clvr_mpi_share_from_mesh(MPI_Comm comm, const clvr_mesh *whole, clvr_mpi_share *out, clvr_error *err);

/* The part of the above without MPI: rank `rank` of `nranks`. */
clvr_status clvr_mpi_share_cut(const clvr_mesh *whole, uint32_t rank, uint32_t nranks, clvr_mpi_share *out,
                               clvr_error *err);

#endif
