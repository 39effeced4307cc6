/* clvr_mpi.h: the MPI module of libclvr (libclvr_mpi.so, built when MPI is
 * found), clvr's data-parallel mode (docs/mpi-compositing.md): under
 * `mpirun -n N`, every rank loads and clusters its share of the mesh and
 * renders the medium inside its region, and rank 0 composites the ranks'
 * images and writes the result. The module takes the clvr program's command
 * line (`clvr --help`) and carries its own private copy of the pipeline
 * (the ranks run the renderer's phase kernels, which clvr.h does not
 * expose); it exports only the two functions below. Link it with
 * `pkg-config --cflags --libs clvr_mpi` (or -lclvr_mpi: the library sits
 * beside libclvr). */
#ifndef CLVR_MPI_H
#define CLVR_MPI_H

#ifdef __cplusplus
extern "C" {
#endif

#if defined(CLVR_MPI_BUILD) && defined(__GNUC__)
#define CLVR_MPI_API __attribute__((visibility("default")))
#else
#define CLVR_MPI_API
#endif

/* Nonzero when this process was started by mpirun/mpiexec (Open MPI's
 * OMPI_COMM_WORLD_SIZE, or a PMI/PMIx launcher's size), even with -n 1. */
CLVR_MPI_API int clvr_mpi_launched(void);

/* Runs the clvr program's command line argv[0..argc) as one rank of
 * MPI_COMM_WORLD (MPI is initialised and finalised here unless the caller
 * initialised it): every rank renders its region, rank 0 composites, writes
 * the image and the statistics, and prints every message on stderr.
 * Installs handlers for SIGINT and SIGTERM for its frames: a signal on any
 * rank stops all of them after the same frame, and rank 0 writes the image
 * accumulated so far (exit code 130).
 * Returns the process exit code (the clvr program's codes; the same on
 * every rank). */
CLVR_MPI_API int clvr_mpi_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif

#endif /* CLVR_MPI_H */
