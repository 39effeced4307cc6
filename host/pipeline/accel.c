#include "clock.h"
#include "accel.h"

#include <string.h>
#include <time.h>

clvr_status clvr_accel_build(clvr_cl *cl, clvr_clustered *c, clvr_accel *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    double t0 = clvr_clock_monotonic_s();
    memset(out, 0, sizeof *out);
    if (c->num_instances > 0xffffffffull || c->num_leaves > CLVR_BVH_MAX_PRIMS || c->num_sampling > CLVR_BVH_MAX_PRIMS)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "%llu leaf clusters exceed the BVH's 2^31 - 1 primitives; use a larger --leaf-size",
                              (unsigned long long)c->num_leaves);
    CLVR_TRY(clvr_bvh_kernels_create(cl, &out->kernels, err));
    CLVR_TRY(clvr_bvh_build_device(cl, &out->kernels, c->host_instances, (uint32_t)c->num_instances, c->instances,
                                   c->leaf_boxes, (uint32_t)c->num_leaves, &out->two_level, err));
    if (!c->no_element_boxes) /* --element-boxes off: the kernels get a NULL ebox and skip the test */
        CLVR_TRY(clvr_bvh_element_boxes_device(cl, &out->kernels, &out->two_level, c->instances,
                                               (uint32_t)c->num_instances, c->vertices, c->idx16, c->idx32,
                                               c->leaf_size, (uint32_t)c->num_leaves, c->num_elements, err));
    CLVR_TRY(clvr_bvh_build_boxes_device(cl, &out->kernels, c->sampling, (uint32_t)c->num_sampling,
                                         &out->sampling_nodes, err));
    out->sampling_node_count = clvr_bvh_nodes_bound((uint32_t)c->num_sampling);
    out->tlas_root = out->two_level.tlas_root;
    out->build_s = clvr_clock_monotonic_s() - t0;
cleanup:
    if (s != CLVR_OK) clvr_accel_release(cl, out);
    return s;
}

void clvr_accel_release(clvr_cl *cl, clvr_accel *a)
{
    if (!a) return;
    clvr_bvh_device_release(cl, &a->two_level);
    clvr_cl_release(cl, &a->sampling_nodes);
    clvr_bvh_kernels_destroy(&a->kernels);
    memset(a, 0, sizeof *a);
}

uint64_t clvr_accel_bvh_bytes(const clvr_accel *a)
{
    return clvr_bvh_bytes(a->two_level.tlas_nodes, a->two_level.blas_nodes);
}
