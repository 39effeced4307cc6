/* series.h: rendering a time series (a ParaView .series file, as
 * tools/clvr-convert writes for .pvd, .vtu.series and Exodus time steps):
 * every step to a numbered frame (-o NAME.png gives NAME.0000.png, ...)
 * with one transfer-function range (--range auto-all, the default for a
 * series: the chosen field's range over all steps) and one camera (framing
 * the union of the steps' bounds), so that frames compare. clvr.h's
 * clvr_path_is_series tells a series file. */
#ifndef CLVR_SERIES_H
#define CLVR_SERIES_H

#include "cli.h"

/* Runs `run` (clvr's main) once per step with argv rewritten: the series
 * replaced by the step's mesh, -o numbered, --range LO HI over all steps and
 * --camera for the union bounds unless given. Returns the first non-zero
 * exit status, else 0. */
typedef int (*clvr_main_fn)(int argc, char **argv);
int clvr_series_run(int argc, char **argv, const clvr_options *o, clvr_main_fn run);

#endif
