/* selftest.cl: the smallest program, used by tests/test_cl_context.c to check
 * embedding, include expansion and that every struct shared by host and
 * kernels has the same size and field offsets on the device (a compiler that
 * pads differently would silently corrupt every buffer). */
#include "clvr_shared.h"
#include "exp_neg.h"

__kernel void clvr_selftest_add(__global const float *a, __global const float *b, __global float *c, uint n)
{
    uint i = get_global_id(0);
    if (i < n) c[i] = a[i] + b[i];
}

/* clvr_exp_neg (exp_neg.h) of n values, for test_cl_context. */
__kernel void clvr_selftest_exp_neg(__global const float *x, __global float *y, uint n)
{
    uint i = get_global_id(0);
    if (i < n) y[i] = clvr_exp_neg(x[i]);
}

/* The order of entries is CLVR_SELFTEST_LAYOUT in tests/test_cl_context.c. */
/* OpenCL C 1.2 has no offsetof: the offset is an address difference inside a
 * private instance, which every compiler accepts. */
#define SIZE_AND(T, field)                                                    \
    {                                                                         \
        T t_;                                                                 \
        out[k++] = (uint)sizeof(T);                                           \
        out[k++] = (uint)((__private char *)&t_.field - (__private char *)&t_); \
    }
__kernel void clvr_selftest_sizes(__global uint *out)
{
    uint k = 0;
    SIZE_AND(clvr_box, hi)
    SIZE_AND(clvr_instance, first_index)
    SIZE_AND(clvr_instance, bvh_root)
    SIZE_AND(clvr_sampling_cluster, hi)
    SIZE_AND(clvr_pp_instance_rec, first_element)
    SIZE_AND(clvr_type_layout, slot)
    SIZE_AND(clvr_bvh_node, child)
    SIZE_AND(clvr_bvh_tree, num_prims)
    SIZE_AND(clvr_camera, fovy)
    SIZE_AND(clvr_camera, height)
    SIZE_AND(clvr_frame, ambient)
    SIZE_AND(clvr_frame, sampler)
    SIZE_AND(clvr_frame, clip_planes)
    out[k++] = clvr_cell_vertex_count(CLVR_CELL_HEX);
}
