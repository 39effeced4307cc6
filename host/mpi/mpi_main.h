/* mpi_main.h: clvr's data-parallel mode (docs/mpi-compositing.md). */
#ifndef CLVR_MPI_MAIN_H
#define CLVR_MPI_MAIN_H

#include "cli.h"

/* Nonzero when this process was started by mpirun/mpiexec (Open MPI's
 * OMPI_COMM_WORLD_SIZE, or a PMI/PMIx launcher's size), even with -n 1. */
int clvr_mpi_launched(void);

/* Runs the whole program as one rank of MPI_COMM_WORLD: every rank renders
 * its region, rank 0 composites and writes the image, the stats and every
 * message. Returns the process exit code (the same on every rank). */
int clvr_mpi_main(int argc, char **argv, const clvr_options *o);

#endif
