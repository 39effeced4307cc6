#include "clock.h"
#include "accel.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

clvr_status clvr_accel_build(clvr_cl *cl, clvr_clustered *c, clvr_accel *out, clvr_error *err)
{
    return clvr_accel_build_hull(cl, c, CLVR_HULL_AUTO, out, err);
}

clvr_status clvr_accel_build_hull(clvr_cl *cl, clvr_clustered *c, int hull_mode, clvr_accel *out, clvr_error *err)
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
    clvr_clustered_pieces pc;
    clvr_clustered_get_pieces(c, &pc);
    if (!c->no_element_boxes) { /* --element-boxes off: the kernels get a NULL ebox and skip the test */
        const uint64_t one[2] = {0, c->num_elements};
        const int split = c->num_pieces > 1;
        CLVR_TRY(clvr_bvh_element_boxes_pieces(cl, &out->kernels, &out->two_level, c->instances,
                                               (uint32_t)c->num_instances, pc.vertices, pc.idx16, pc.idx32,
                                               split ? c->piece_elements : one, split ? c->num_pieces : 1,
                                               pc.vertices[CLVR_MAX_SPLITS - 1], c->leaf_size,
                                               (uint32_t)c->num_leaves, err));
    }
    /* after the element boxes, which speed up its cells' point location */
    CLVR_TRY(clvr_bvh_entry_grids_pieces(cl, &out->kernels, &out->two_level, c->host_instances, c->instances,
                                         (uint32_t)c->num_instances, pc.vertices, pc.idx16, pc.idx32, c->leaf_size,
                                         (uint32_t)c->num_leaves, err));
    CLVR_TRY(clvr_bvh_build_boxes_device(cl, &out->kernels, c->sampling, (uint32_t)c->num_sampling,
                                         &out->sampling_nodes, err));
    out->sampling_node_count = clvr_bvh_nodes_bound((uint32_t)c->num_sampling);
    s = clvr_hull_build(cl, &out->kernels, c, out->sampling_nodes, hull_mode, &out->hull, err);
    /* The hull only speeds convergence: a mesh too large for its transient
     * buffers (or past 2^31 - 1 faces) renders without it, the same image. */
    if (hull_mode == CLVR_HULL_AUTO && (s == CLVR_ERR_DEVICE_MEMORY || s == CLVR_ERR_OVERFLOW)) {
        snprintf(out->hull_skipped, sizeof out->hull_skipped, "%s", err->msg);
        *err = (clvr_error){0};
        s = CLVR_OK;
    }
    if (s != CLVR_OK) goto cleanup;
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
    clvr_hull_release(cl, &a->hull);
    clvr_bvh_kernels_destroy(&a->kernels);
    memset(a, 0, sizeof *a);
}

uint64_t clvr_accel_bvh_bytes(const clvr_accel *a)
{
    return clvr_bvh_bytes(a->two_level.tlas_nodes, a->two_level.blas_nodes);
}

void clvr_accel_get_ebox_pieces(const clvr_clustered *c, const clvr_accel *a, cl_mem out[CLVR_MAX_SPLITS])
{
    clvr_clustered_pieces pc;
    clvr_clustered_get_pieces(c, &pc);
    out[0] = a->two_level.ebox; /* NULL: no element boxes (the kernels skip them) */
    for (uint32_t p = 1; p < CLVR_MAX_SPLITS; ++p)
        out[p] = a->two_level.ebox_more[p - 1] ? a->two_level.ebox_more[p - 1] : pc.vertices[CLVR_MAX_SPLITS - 1];
}

clvr_status clvr_accel_locate(clvr_cl *cl, const clvr_clustered *c, const clvr_accel *a, const float *points,
                              uint32_t n, uint32_t hints, uint32_t chain, float *scalars, uint32_t *element_ids,
                              clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem pts = NULL, sc = NULL, ids = NULL;
    clvr_clustered_pieces pc;
    cl_mem eb[CLVR_MAX_SPLITS];
    clvr_clustered_get_pieces(c, &pc);
    clvr_accel_get_ebox_pieces(c, a, eb);
    /* A NULL element-box piece 0 means none: the kernel gets a placeholder and use_ebox 0. */
    const cl_uint use_ebox = eb[0] != NULL, root = a->tlas_root, leaf = c->leaf_size, nn = n, h = hints,
                  ch = chain ? chain : 1;
    if (!eb[0]) eb[0] = pc.vertices[CLVR_MAX_SPLITS - 1];
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)n * 16, n ? (void *)points : NULL,
                            "query points", &pts, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)n * 4, NULL, "query scalars", &sc, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)n * 4, NULL, "query element ids", &ids, err));
    if (n == 0) goto cleanup;
    cl_kernel k = a->kernels.locate_points_split;
    CLVR_TRY(CLVR_CL_ARGS(k, err, CLVR_ARG(pts), CLVR_ARG(nn), CLVR_ARG(a->two_level.tlas), CLVR_ARG(root),
                          CLVR_ARG(a->two_level.blas), CLVR_ARG(c->instances), CLVR_ARG(leaf), CLVR_ARG(sc),
                          CLVR_ARG(ids), CLVR_ARG(h), CLVR_ARG(use_ebox), CLVR_ARG(ch), CLVR_ARG(pc.vertices[0]),
                          CLVR_ARG(pc.idx16[0]), CLVR_ARG(pc.idx32[0]), CLVR_ARG(eb[0]), CLVR_ARG(pc.vertices[1]),
                          CLVR_ARG(pc.idx16[1]), CLVR_ARG(pc.idx32[1]), CLVR_ARG(eb[1]), CLVR_ARG(pc.vertices[2]),
                          CLVR_ARG(pc.idx16[2]), CLVR_ARG(pc.idx32[2]), CLVR_ARG(eb[2]), CLVR_ARG(pc.vertices[3]),
                          CLVR_ARG(pc.idx16[3]), CLVR_ARG(pc.idx32[3]), CLVR_ARG(eb[3]),
                          CLVR_ARG(a->two_level.entry_grids), CLVR_ARG(a->two_level.entry_cells)));
    CLVR_TRY(clvr_cl_run1d(cl, k, (n + ch - 1) / ch, 64, NULL, err));
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, sc, CL_TRUE, 0, (size_t)n * 4, scalars, 0, NULL, NULL));
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, ids, CL_TRUE, 0, (size_t)n * 4, element_ids, 0, NULL, NULL));
cleanup:
    clvr_cl_release(cl, &pts);
    clvr_cl_release(cl, &sc);
    clvr_cl_release(cl, &ids);
    return s;
}
