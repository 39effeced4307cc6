/* selftest.cl: the smallest program, used by tests/test_cl_context.c to check
 * embedding, include expansion and the layout of shared structs. */
#include "clvr_shared.h"

__kernel void clvr_selftest_add(__global const float *a, __global const float *b, __global float *c, uint n)
{
    uint i = get_global_id(0);
    if (i < n) c[i] = a[i] + b[i];
}

/* Writes sizeof of each shared struct so the host can compare layouts. */
__kernel void clvr_selftest_sizes(__global uint *out)
{
    out[0] = (uint)sizeof(clvr_box);
    out[1] = clvr_cell_vertex_count(CLVR_CELL_HEX);
}
