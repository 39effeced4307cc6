/* info.h: the human-readable mesh summary of `clvr --info`. */
#ifndef CLVR_INFO_H
#define CLVR_INFO_H

#include <stdio.h>

#include "mesh.h"

/* Prints counts per element type, bounds, scalar range and bytes of m. */
void clvr_info_print(FILE *out, const char *name, const clvr_mesh *m);

#endif
