/* mpi_composite.h: rank 0's front-to-back compositing of the ranks' phase-1
 * records of one pixel (docs/mpi-compositing.md). Plain C, no MPI: the same
 * function is the reference the tests call. */
#ifndef CLVR_MPI_COMPOSITE_H
#define CLVR_MPI_COMPOSITE_H

#include <stddef.h>
#include <stdint.h>

#include "clvr_shared.h"

/* Test hooks (CLVR_MPI_TEST_BREAK, docs/mpi-compositing.md): compositings
 * that are wrong on purpose, so that the tests can show they would notice. */
#define CLVR_MPI_BREAK_NONE 0
#define CLVR_MPI_BREAK_RANK0 1 /* rank 0's record only, the others dropped */
#define CLVR_MPI_BREAK_ORDER 2 /* rank order instead of depth order */

typedef struct clvr_mpi_composite_params {
    float background[3];
    float light_intensity;
    int shadows;
    uint64_t seed;   /* the pick of the shadow point among ranks: keyed by (seed, frame, pixel) */
    uint32_t frame;
    int broken;      /* CLVR_MPI_BREAK_* */
} clvr_mpi_composite_params;

/* What one pixel's composite leaves for the shadow phase. */
typedef struct clvr_mpi_shadow_pick {
    float t;         /* distance of the shadow ray's origin on the camera ray; < 0: no shadow ray */
    float g;         /* light grid G there */
    float factor[3]; /* the correction is factor * (T_light - g) */
} clvr_mpi_shadow_pick;

/* rec[r * stride] is rank r's record (r < nranks, at most 4096). Writes the
 * pixel's rgba without the shadow correction (alpha: 1 - transmittance) and
 * the pick. */
void clvr_mpi_composite_pixel(const clvr_mpi_record *rec, size_t stride, uint32_t nranks,
                              const clvr_mpi_composite_params *p, uint32_t pixel, float rgba[4],
                              clvr_mpi_shadow_pick *pick);

#endif
