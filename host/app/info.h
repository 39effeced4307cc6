/* info.h: the human-readable mesh summary of `clvr --info`, from libclvr's
 * dataset information (clvr_dataset_get_info, clvr_dataset_get_field). */
#ifndef CLVR_INFO_H
#define CLVR_INFO_H

#include <stdio.h>

#include "clvr.h"

/* Prints counts per element type, bounds, the fields with their ranges and
 * the bytes of ds. Errors: those of the library calls (msg). */
clvr_result clvr_info_print(FILE *out, const char *name, const clvr_dataset *ds, clvr_message *msg);

#endif
