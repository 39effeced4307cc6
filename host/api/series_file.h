/* series_file.h: reading a time series file (a ParaView .series file, as
 * tools/clvr-convert writes for .pvd, .vtu.series and Exodus time steps):
 * the list of the steps' mesh paths and times. Behind clvr.h's
 * clvr_series_* (and used by the MPI mode to refuse a series). */
#ifndef CLVR_SERIES_FILE_H
#define CLVR_SERIES_FILE_H

#include <stdint.h>

#include "status.h"

/* Nonzero when path names a series file (ends in .series). */
int clvr_series_is(const char *path);

/* Reads a .series file: {"files": [{"name": N, "time": T}, ...]} with names
 * relative to the file's folder. On success *paths (n strings) and *times
 * are malloc'd (clvr_series_free). */
clvr_status clvr_series_read(const char *path, char ***paths, double **times, uint32_t *n, clvr_error *err);
void clvr_series_free(char **paths, double *times, uint32_t n);

#endif
