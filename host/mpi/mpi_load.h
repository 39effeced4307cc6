/* mpi_load.h: every rank of an MPI job reads about 1/N of a .bin mesh with
 * offsets and ends with its share (mpi_share.h): the elements whose vertex
 * box overlaps its region, owned and ghosts (docs/mpi-loading.md). */
#ifndef CLVR_MPI_LOAD_H
#define CLVR_MPI_LOAD_H

#include <mpi.h>
#include <stdint.h>

#include "mesh_io.h"
#include "mpi_share.h"
#include "status.h"

/* Collective. Turns per-rank outcomes into one: CLVR_OK on every rank when
 * `local` is CLVR_OK on every rank; otherwise every rank returns the status
 * of the lowest failing rank with its message prefixed by "rank R of N"
 * (and how many ranks failed), so each rank can stop before the next
 * collective instead of leaving the others waiting in it. `err` holds the
 * failing rank's message on entry (may be NULL: the status text is used). */
clvr_status clvr_mpi_agree(MPI_Comm comm, clvr_status local, clvr_error *err);

/* What one rank's load did (for benchmarks and tests). */
typedef struct clvr_mpi_load_stats {
    uint64_t bytes_read;       /* from the mesh file by this rank, header included, re-reads counted */
    uint64_t slice_bytes;      /* of the file regions this rank reads: header, its vertex slice (positions
                                * and the chosen field) and its element slice; the element slice is read
                                * twice (count, then send) and the sample's elements a third time */
    uint64_t slice_vertices;   /* vertices of this rank's 1/N slice of the file */
    uint64_t slice_elements;   /* elements of this rank's 1/N slice */
    uint64_t share_elements;   /* elements of the share: owned + ghosts */
    uint64_t ghost_elements;   /* share elements whose centroid another rank owns */
    uint64_t sample;           /* centroids all ranks bisected for the regions */
    uint64_t exchange_rounds;  /* MPI_Alltoallv rounds over all exchanges (chunking) */
} clvr_mpi_load_stats;

/* Collective over comm: reads the .bin file at path (versions 1 and 2, see
 * docs/bin-format.md) in parts and fills *out with this rank's share:
 *   - rank r reads a contiguous 1/N of the vertex array (positions and the
 *     chosen point scalar, lo->scalar_name as --scalar) and of the
 *     elements (across the four type arrays), never the whole file;
 *   - bounds and scalar range are reduced over the slices (bit for bit what
 *     clvr_mesh_load gives);
 *   - regions come from a deterministic sample of element centroids (at
 *     most 65536, every ceil(E / 65536)-th element) that every rank
 *     bisects identically (clvr_mpi_regions);
 *   - each element goes to every rank whose closed region its vertex box
 *     overlaps (its vertices fetched from their slice owners to find it),
 *     streamed in pieces: the element slice is read twice (find the
 *     destinations, then send), so no rank holds more than its share, its
 *     vertex slice and one piece's buffers.
 * The centroid of an element is the float mean of its vertex coordinates
 * in vertex order, clamped into its vertex box.
 * The share's mesh numbers its vertices by ascending global id and keeps
 * each type's elements in file order. Cell fields are refused (the fix
 * is in the message): averaging them onto vertices needs the elements of
 * every rank. The file is validated as clvr_mesh_load does (indices,
 * finite coordinates and scalars; lo->skip_validation is ignored, since a
 * bad index would address another rank's memory).
 * Every rank returns the same status and message (clvr_mpi_agree); on
 * failure *out is zeroed. lo may be NULL. */
clvr_status clvr_mpi_load_share_bin(MPI_Comm comm, const char *path, const clvr_load_options *lo,
                                    clvr_mpi_share *out, clvr_error *err);

/* The same with the round size and stats (may be NULL). chunk_bytes: 0
 * gives pieces of about 16 MiB of element records over all peers and
 * exchanges straight on the buffers while MPI's int counts allow; nonzero
 * sets the piece size (chunk_bytes / (36 N) elements, at least one) and
 * sends every exchange through scratch of at most that many bytes per
 * round (tests use 40 bytes to run hundreds of rounds). */
clvr_status clvr_mpi_load_share_bin_ex(MPI_Comm comm, const char *path, const clvr_load_options *lo,
                                       uint64_t chunk_bytes, clvr_mpi_share *out, clvr_mpi_load_stats *stats,
                                       clvr_error *err);

#endif
