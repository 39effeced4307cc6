/* bvh.c: host reference and device driver of the packed 4-wide BVH build
 * (Hilbert R-tree packing of primitives already in Hilbert order, see
 * kernels/bvh_build.h). Both run the same per-node code, level by level. */
#include "bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../kernels/bvh_build.h"

uint32_t clvr_bvh_nodes_bound(uint32_t num_prims) { return clvr_bvh_tree_size(num_prims); }

uint64_t clvr_bvh_bytes(uint32_t tlas_nodes, uint32_t blas_nodes)
{
    return ((uint64_t)tlas_nodes + blas_nodes) * sizeof(clvr_bvh_node);
}

/* Lays trees out one after another from node `base`; returns the node count
 * or fails when it passes 2^31 - 1 (child references keep the top bit). */
static clvr_status layout_trees(clvr_bvh_tree *trees, uint32_t ntrees, uint32_t base, uint32_t *total, clvr_error *err)
{
    uint64_t at = base;
    for (uint32_t t = 0; t < ntrees; ++t) {
        trees[t].node_base = (uint32_t)at;
        at += clvr_bvh_tree_size(trees[t].num_prims);
        if (at > CLVR_BVH_MAX_PRIMS)
            return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                                  "bvh: %llu nodes exceed the 2^31 - 1 a node reference can address; use larger "
                                  "leaf clusters (--leaf-size)",
                                  (unsigned long long)at);
    }
    *total = (uint32_t)(at - base);
    return CLVR_OK;
}

static uint32_t max_height(const clvr_bvh_tree *trees, uint32_t ntrees)
{
    uint32_t h = 0;
    for (uint32_t t = 0; t < ntrees; ++t) {
        const uint32_t ht = clvr_bvh_height(trees[t].num_prims);
        if (ht > h) h = ht;
    }
    return h;
}

static void build_trees_host(clvr_bvh_node *nodes, const float *prim_boxes, const clvr_bvh_tree *trees,
                             uint32_t ntrees)
{
    const uint32_t h = max_height(trees, ntrees);
    for (uint32_t level = 0; level < h; ++level)
        for (uint32_t t = 0; t < ntrees; ++t) {
            const uint32_t m = clvr_bvh_level_size(trees[t].num_prims, level);
            for (uint32_t i = 0; i < m; ++i) clvr_bvh_build_node(nodes, prim_boxes, trees[t], level, i);
        }
}

clvr_status clvr_bvh_build_boxes(const void *boxes, uint32_t n, clvr_bvh_node *nodes, clvr_error *err)
{
    if (n > CLVR_BVH_MAX_PRIMS)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "bvh: %u boxes exceed the 2^31 - 1 a tree can hold", n);
    clvr_bvh_tree t = {0, 0, n, 0};
    build_trees_host(nodes, (const float *)boxes, &t, 1);
    return CLVR_OK;
}

/* One tree per instance over its leaves; checks the instances' leaf ranges. */
static clvr_status instance_trees(const clvr_instance *inst, uint32_t ninst, uint32_t num_leaves,
                                  clvr_bvh_tree **out, uint32_t *total, clvr_error *err)
{
    clvr_bvh_tree *trees = calloc(ninst ? ninst : 1, sizeof *trees);
    if (!trees) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bvh: no memory for %u tree descriptors", ninst);
    for (uint32_t i = 0; i < ninst; ++i) {
        if ((uint64_t)inst[i].first_leaf + inst[i].num_leaves > num_leaves) {
            free(trees);
            return clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                                  "bvh: instance %u has leaves %u..%u but there are %u leaf boxes; the clustering "
                                  "and its leaf_boxes disagree",
                                  i, inst[i].first_leaf, inst[i].first_leaf + inst[i].num_leaves, num_leaves);
        }
        trees[i].first_prim = inst[i].first_leaf;
        trees[i].num_prims = inst[i].num_leaves;
    }
    clvr_status s = layout_trees(trees, ninst, 0, total, err);
    if (s != CLVR_OK) {
        free(trees);
        return s;
    }
    *out = trees;
    return CLVR_OK;
}

/* The top level over the instances' bounds, in host memory. */
static clvr_status build_tlas_host(const clvr_instance *inst, uint32_t ninst, clvr_bvh_node **out, uint32_t *count,
                                   clvr_error *err)
{
    const uint32_t nn = clvr_bvh_tree_size(ninst);
    clvr_box *boxes = malloc((ninst ? ninst : 1) * sizeof *boxes);
    clvr_bvh_node *nodes = malloc((size_t)nn * sizeof *nodes);
    if (!boxes || !nodes) {
        free(boxes);
        free(nodes);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bvh: no memory for the top level over %u instances", ninst);
    }
    for (uint32_t i = 0; i < ninst; ++i) boxes[i] = inst[i].bounds;
    clvr_status s = clvr_bvh_build_boxes(boxes, ninst, nodes, err);
    free(boxes);
    if (s != CLVR_OK) {
        free(nodes);
        return s;
    }
    *out = nodes;
    *count = nn;
    return CLVR_OK;
}

/* Grid g over box (lo, hi) with about `want` cells, cells about cubic over
 * the axes that have an extent (flat, empty or NaN axes get one cell), at
 * most max_res per axis; g->res[3] left 0. */
static void entry_grid_fit(const float *lo, const float *hi, double want, uint32_t max_res, clvr_entry_grid *g)
{
    memset(g, 0, sizeof *g);
    double ext[3], vol = 1.0;
    int axes = 0;
    for (int k = 0; k < 3; ++k) {
        g->lo[k] = lo[k];
        g->res[k] = 1;
        ext[k] = (double)hi[k] - (double)lo[k];
        if (!isfinite(ext[k]) || !(ext[k] > 0.0)) ext[k] = 0.0;
        if (ext[k] > 0.0) {
            vol *= ext[k];
            ++axes;
        }
    }
    const double h = axes ? pow(vol / want, 1.0 / axes) : 0.0;
    for (int k = 0; k < 3; ++k) {
        if (!(ext[k] > 0.0) || !(h > 0.0)) continue;
        const double r = fmin(fmax(ceil(ext[k] / h), 1.0), (double)max_res);
        g->res[k] = (uint32_t)r;
        if (g->res[k] > 1u) g->scale[k] = (float)(r / ext[k]);
    }
}

/* 1 when the instances' global hint words fit (clvr_global_hints_fit). */
static int global_hints_fit(const clvr_instance *instances, uint32_t num_instances)
{
    uint32_t most = 0;
    for (uint32_t i = 0; i < num_instances; ++i)
        if (instances[i].num_leaves > most) most = instances[i].num_leaves;
    return clvr_global_hints_fit(num_instances, most);
}

/* Global hint cells of occupancy grid g at shift sh. */
static uint64_t global_hint_cells(const clvr_entry_grid *g, uint32_t sh)
{
    return (uint64_t)clvr_global_hint_res(g, sh, 0) * clvr_global_hint_res(g, sh, 1) * clvr_global_hint_res(g, sh, 2);
}

clvr_status clvr_entry_grids_layout(const clvr_instance *instances, uint32_t num_instances, uint64_t max_bytes,
                                    clvr_entry_grid *grids, uint32_t *num_words, clvr_error *err)
{
    uint64_t total = 0, elements = 0;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < num_instances; ++i) {
        const clvr_instance *in = &instances[i];
        /* About CLVR_ENTRY_CELLS_PER_LEAF cells per leaf of tets,
         * CLVR_ENTRY_CELLS_PER_LEAF_NEWTON for the other types. */
        const double per_leaf =
            in->type == CLVR_CELL_TET ? CLVR_ENTRY_CELLS_PER_LEAF : CLVR_ENTRY_CELLS_PER_LEAF_NEWTON;
        entry_grid_fit(in->bounds.lo, in->bounds.hi, per_leaf * (in->num_leaves ? in->num_leaves : 1u),
                       CLVR_ENTRY_MAX_RES, &grids[1u + i]);
        grids[1u + i].res[3] = (uint32_t)fmin((double)total, 4294967295.0);
        total += (uint64_t)grids[1u + i].res[0] * grids[1u + i].res[1] * grids[1u + i].res[2];
        elements += in->num_elements;
        for (int k = 0; k < 3; ++k) {
            lo[k] = fminf(lo[k], in->bounds.lo[k]);
            hi[k] = fmaxf(hi[k], in->bounds.hi[k]);
        }
    }
    if (!num_instances)
        for (int k = 0; k < 3; ++k) lo[k] = hi[k] = 0.0f; /* no element: one clear bit */
    entry_grid_fit(lo, hi, (double)CLVR_OCCUPANCY_CELLS_PER_ELEMENT * (double)(elements ? elements : 1u),
                   CLVR_OCCUPANCY_MAX_RES, &grids[0]);
    /* the occupancy bits, then the global hints at the finest shift that
     * keeps them within CLVR_GLOBAL_HINT_MAX_CELLS and the whole array
     * within max_bytes (none when no shift does: they only save time) */
    const uint64_t base = 2u * total + clvr_occupancy_words(&grids[0]);
    uint64_t hints = 0;
    grids[0].lo[3] = 0.0f;
    for (uint32_t sh = 0; sh <= 10u && num_instances && global_hints_fit(instances, num_instances); ++sh) {
        const uint64_t n = global_hint_cells(&grids[0], sh);
        if (n <= CLVR_GLOBAL_HINT_MAX_CELLS && (!max_bytes || (base + n) * sizeof(uint32_t) <= max_bytes)) {
            grids[0].lo[3] = 1.0f + (float)sh;
            hints = n;
            break;
        }
    }
    const uint64_t words = base + hints;
    if (words > 0xffffffffull)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "bvh: the entry grids of %u instances pass 2^32 - 1 words; use a larger --leaf-size",
                              num_instances);
    grids[0].res[3] = (uint32_t)(2u * total);
    *num_words = (uint32_t)words;
    return CLVR_OK;
}

/* The elements of leaf cluster `leaf` of inst into the cells their boxes
 * meet (clvr_entry_element_hull): cells holds (first, last) leaf per cell
 * of inst's grid g and the bits of the occupancy grid occ. */
static void entry_rasterize_host(const clvr_mesh_view *m, const clvr_instance *inst, const clvr_entry_grid *g,
                                 const clvr_entry_grid *occ, uint32_t leaf, uint32_t *cells)
{
    const clvr_piece_arrays pa = clvr_view_piece(m, inst);
    uint32_t end;
    for (uint32_t e = clvr_leaf_elements(m, inst, leaf, &end); e < end; ++e) {
        float lo[3], hi[3];
        uint32_t a[3], b[3];
        clvr_element_slabs sl;
        clvr_entry_element_hull(&pa, inst, e, lo, hi, &sl);
        clvr_entry_box_cells(g, lo, hi, a, b);
        for (uint32_t z = a[2]; z <= b[2]; ++z)
            for (uint32_t y = a[1]; y <= b[1]; ++y)
                for (uint32_t x = a[0]; x <= b[0]; ++x) {
                    uint32_t *c = cells + 2u * ((size_t)g->res[3] + ((size_t)z * g->res[1] + y) * g->res[0] + x);
                    if (leaf < c[0]) c[0] = leaf;
                    if (leaf > c[1]) c[1] = leaf;
                }
        clvr_entry_box_cells(occ, lo, hi, a, b);
        for (uint32_t z = a[2]; z <= b[2]; ++z)
            for (uint32_t y = a[1]; y <= b[1]; ++y) {
                const uint32_t c0 = (z * occ->res[1] + y) * occ->res[0] + a[0], c1 = c0 + (b[0] - a[0]);
                float blo[2], bhi[2];
                clvr_entry_cell_span(occ, 1, y, &blo[0], &bhi[0]);
                clvr_entry_cell_span(occ, 2, z, &blo[1], &bhi[1]);
                for (uint32_t w = c0 / 32u; w <= c1 / 32u; ++w) {
                    const uint32_t box = clvr_occupancy_mask(w == c0 / 32u ? c0 % 32u : 0u,
                                                             w == c1 / 32u ? c1 % 32u : 31u);
                    uint32_t *word = &cells[occ->res[3] + w];
                    *word |= clvr_occupancy_row_bits(occ, &sl, w, c0, c1, a[0], blo, bhi, box & ~*word);
                }
            }
    }
}

clvr_status clvr_entry_cells_host(const clvr_mesh_view *m, uint32_t num_instances, clvr_entry_grid *grids,
                                  uint32_t num_words, uint32_t *cells, clvr_error *err)
{
    clvr_entry_grid *occ = &grids[0];
    const int hinted = clvr_global_hints_on(occ);
    const uint32_t sh = hinted ? clvr_global_hints_shift(occ) : 0u;
    const uint64_t nh = hinted ? global_hint_cells(occ, sh) : 0u;
    if (occ->res[3] % 2u || occ->res[3] > num_words || clvr_occupancy_words(occ) > num_words - occ->res[3] ||
        nh != num_words - clvr_global_hints_first(occ))
        return clvr_error_set(err, CLVR_ERR_INTERNAL, "bvh: the occupancy grid passes the %u words", num_words);
    const uint32_t num_cells = occ->res[3] / 2u;
    for (uint32_t c = 0; c < num_cells; ++c) {
        cells[2u * (size_t)c] = CLVR_BVH_NOT_FOUND;
        cells[2u * (size_t)c + 1u] = 0;
    }
    for (uint32_t w = occ->res[3]; w < num_words; ++w) cells[w] = 0;
    for (uint32_t i = 0; i < num_instances; ++i) {
        const clvr_instance *inst = &m->instances[i];
        const clvr_entry_grid *g = &grids[1u + i];
        const uint64_t n = (uint64_t)g->res[0] * g->res[1] * g->res[2];
        if (g->res[3] > num_cells || n > num_cells - g->res[3])
            return clvr_error_set(err, CLVR_ERR_INTERNAL, "bvh: instance %u's entry grid passes the %u cells", i,
                                  num_cells);
        for (uint32_t leaf = inst->first_leaf; leaf < inst->first_leaf + inst->num_leaves; ++leaf)
            entry_rasterize_host(m, inst, g, occ, leaf, cells);
        for (uint32_t c = 0; c < (uint32_t)n; ++c) {
            uint32_t *cell = cells + 2u * ((size_t)g->res[3] + c);
            const uint32_t start = cell[0] == CLVR_BVH_NOT_FOUND ? CLVR_BVH_NOT_FOUND : clvr_entry_lca(inst, cell[0], cell[1]);
            cell[0] = start;
            cell[1] = clvr_entry_hint(m, inst, g, start, c % g->res[0], c / g->res[0] % g->res[1],
                                      c / g->res[0] / g->res[1]);
        }
    }
    if (!hinted) return CLVR_OK;
    /* hints off while they are built (clvr_global_hints_on) */
    const float on = occ->lo[3];
    uint32_t *hints = cells + clvr_global_hints_first(occ);
    clvr_mesh_view mg = *m;
    mg.entry_grids = grids;
    mg.entry_cells = cells;
    occ->lo[3] = 0.0f;
    for (uint64_t c = 0; c < nh; ++c) hints[c] = clvr_global_hint(&mg, sh, (uint32_t)c);
    occ->lo[3] = on;
    return CLVR_OK;
}

clvr_status clvr_bvh_build_host(clvr_instance *instances, uint32_t num_instances, const clvr_box *leaf_boxes,
                                uint32_t num_leaves, clvr_bvh_host *out, clvr_error *err)
{
    memset(out, 0, sizeof *out);
    clvr_bvh_tree *trees = NULL;
    uint32_t total = 0;
    clvr_status s = instance_trees(instances, num_instances, num_leaves, &trees, &total, err);
    if (s != CLVR_OK) return s;
    out->blas = malloc((size_t)(total ? total : 1) * sizeof *out->blas);
    if (!out->blas) {
        free(trees);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bvh: no memory for %u bottom-level nodes", total);
    }
    out->blas_nodes = total;
    build_trees_host(out->blas, (const float *)leaf_boxes, trees, num_instances);
    for (uint32_t i = 0; i < num_instances; ++i) instances[i].bvh_root = trees[i].node_base;
    free(trees);
    s = build_tlas_host(instances, num_instances, &out->tlas, &out->tlas_nodes, err);
    if (s != CLVR_OK) {
        clvr_bvh_host_free(out);
        return s;
    }
    out->tlas_root = 0;
    return CLVR_OK;
}

void clvr_bvh_host_free(clvr_bvh_host *b)
{
    if (!b) return;
    free(b->tlas);
    free(b->blas);
    memset(b, 0, sizeof *b);
}

clvr_status clvr_bvh_kernels_create(clvr_cl *cl, clvr_bvh_kernels *out, clvr_error *err)
{
    memset(out, 0, sizeof *out);
    clvr_status s = CLVR_OK;
    CLVR_TRY(clvr_cl_build(cl, "bvh.cl", "", &out->program, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_bvh_build_level", &out->build_level, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_locate_points", &out->locate_points, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_locate_points_split", &out->locate_points_split, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_bvh_ray_hits", &out->ray_hits, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_bvh_ray_span", &out->ray_span, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_element_boxes", &out->element_boxes, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_entry_rasterize", &out->entry_rasterize, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_entry_finish", &out->entry_finish, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_entry_global", &out->entry_global, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_hull_keys", &out->hull_keys, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_hull_flags", &out->hull_flags, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_hull_adjacency", &out->hull_adjacency, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_hull_faces", &out->hull_faces, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_hull_rays", &out->hull_rays, err));
    CLVR_TRY(clvr_cl_kernel(out->program, "clvr_hull_gap_rays", &out->hull_gap_rays, err));
    return CLVR_OK;
cleanup:
    clvr_bvh_kernels_destroy(out);
    return s;
}

void clvr_bvh_kernels_destroy(clvr_bvh_kernels *k)
{
    if (!k) return;
    if (k->build_level) clReleaseKernel(k->build_level);
    if (k->locate_points) clReleaseKernel(k->locate_points);
    if (k->locate_points_split) clReleaseKernel(k->locate_points_split);
    if (k->ray_hits) clReleaseKernel(k->ray_hits);
    if (k->ray_span) clReleaseKernel(k->ray_span);
    if (k->element_boxes) clReleaseKernel(k->element_boxes);
    if (k->entry_rasterize) clReleaseKernel(k->entry_rasterize);
    if (k->entry_finish) clReleaseKernel(k->entry_finish);
    if (k->entry_global) clReleaseKernel(k->entry_global);
    cl_kernel hk[6] = {k->hull_keys, k->hull_flags, k->hull_faces, k->hull_rays, k->hull_gap_rays, k->hull_adjacency};
    for (int i = 0; i < 6; ++i)
        if (hk[i]) clReleaseKernel(hk[i]);
    if (k->program) clReleaseProgram(k->program);
    memset(k, 0, sizeof *k);
}

/* Runs the level kernel bottom-up over all trees into `nodes`. The level
 * prefix is O(trees * levels) host arithmetic; the nodes are built on the
 * device. Adds kernel time to *seconds. */
static clvr_status build_trees_device(clvr_cl *cl, const clvr_bvh_kernels *k, cl_mem nodes, cl_mem prim_boxes,
                                      const clvr_bvh_tree *trees, uint32_t ntrees, double *seconds, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem trees_mem = NULL, prefix_mem = NULL;
    uint32_t *prefix = calloc((size_t)ntrees + 1, sizeof *prefix);
    cl_event evt = NULL;
    if (!prefix) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bvh: no memory for %u tree prefixes", ntrees);
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)ntrees * sizeof *trees,
                            (void *)trees, "bvh tree descriptors", &trees_mem, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, ((size_t)ntrees + 1) * sizeof *prefix, NULL, "bvh level prefix",
                            &prefix_mem, err));
    const uint32_t h = max_height(trees, ntrees);
    for (uint32_t level = 0; level < h; ++level) {
        for (uint32_t t = 0; t < ntrees; ++t) prefix[t + 1] = prefix[t] + clvr_bvh_level_size(trees[t].num_prims, level);
        /* Blocking: prefix[] is rewritten for the next level. */
        CLVR_CL_CHECK(clEnqueueWriteBuffer(cl->queue, prefix_mem, CL_TRUE, 0, ((size_t)ntrees + 1) * sizeof *prefix,
                                           prefix, 0, NULL, NULL));
        CLVR_TRY(CLVR_CL_ARGS(k->build_level, err, CLVR_ARG(nodes), CLVR_ARG(prim_boxes), CLVR_ARG(trees_mem),
                              CLVR_ARG(prefix_mem), CLVR_ARG(ntrees), CLVR_ARG(level)));
        CLVR_TRY(clvr_cl_run1d(cl, k->build_level, prefix[ntrees], 64, &evt, err));
        if (evt) {
            CLVR_CL_CHECK(clWaitForEvents(1, &evt));
            *seconds += clvr_cl_event_seconds(evt);
            clReleaseEvent(evt);
            evt = NULL;
        }
    }
    CLVR_CL_CHECK(clFinish(cl->queue));
cleanup:
    if (evt) clReleaseEvent(evt);
    clvr_cl_release(cl, &trees_mem);
    clvr_cl_release(cl, &prefix_mem);
    free(prefix);
    return s;
}

clvr_status clvr_bvh_build_device(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_instance *host_instances,
                                  uint32_t num_instances, cl_mem instances, cl_mem leaf_boxes, uint32_t num_leaves,
                                  clvr_bvh_device *out, clvr_error *err)
{
    memset(out, 0, sizeof *out);
    clvr_status s = CLVR_OK;
    clvr_bvh_tree *trees = NULL;
    clvr_bvh_node *tlas = NULL;
    uint32_t total = 0;
    CLVR_TRY(instance_trees(host_instances, num_instances, num_leaves, &trees, &total, err));
    out->blas_nodes = total;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)total * sizeof(clvr_bvh_node), NULL,
                            "bottom-level BVH nodes", &out->blas, err));
    CLVR_TRY(build_trees_device(cl, k, out->blas, leaf_boxes, trees, num_instances, &out->build_seconds, err));
    for (uint32_t i = 0; i < num_instances; ++i) host_instances[i].bvh_root = trees[i].node_base;
    if (num_instances)
        CLVR_CL_CHECK(clEnqueueWriteBuffer(cl->queue, instances, CL_TRUE, 0, (size_t)num_instances * sizeof *host_instances,
                                           host_instances, 0, NULL, NULL));
    CLVR_TRY(build_tlas_host(host_instances, num_instances, &tlas, &out->tlas_nodes, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)out->tlas_nodes * sizeof *tlas, tlas,
                            "top-level BVH nodes", &out->tlas, err));
    out->tlas_root = 0;
cleanup:
    free(trees);
    free(tlas);
    if (s != CLVR_OK) clvr_bvh_device_release(cl, out);
    return s;
}

void clvr_bvh_device_release(clvr_cl *cl, clvr_bvh_device *b)
{
    if (!b) return;
    clvr_cl_release(cl, &b->tlas);
    clvr_cl_release(cl, &b->blas);
    clvr_cl_release(cl, &b->ebox);
    for (uint32_t p = 0; p + 1 < CLVR_MAX_SPLITS; ++p) clvr_cl_release(cl, &b->ebox_more[p]);
    clvr_cl_release(cl, &b->entry_grids);
    clvr_cl_release(cl, &b->entry_cells);
    memset(b, 0, sizeof *b);
}

clvr_status clvr_bvh_build_boxes_device(clvr_cl *cl, const clvr_bvh_kernels *k, cl_mem boxes, uint32_t n,
                                        cl_mem *out_nodes, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    *out_nodes = NULL;
    double secs = 0.0;
    if (n > CLVR_BVH_MAX_PRIMS)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "bvh: %u boxes exceed the 2^31 - 1 a tree can hold", n);
    clvr_bvh_tree t = {0, 0, n, 0};
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)clvr_bvh_tree_size(n) * sizeof(clvr_bvh_node), NULL,
                            "sampling-cluster BVH nodes", out_nodes, err));
    CLVR_TRY(build_trees_device(cl, k, *out_nodes, boxes, &t, 1, &secs, err));
    return CLVR_OK;
cleanup:
    clvr_cl_release(cl, out_nodes);
    return s;
}

clvr_status clvr_bvh_element_boxes_host(const clvr_mesh_view *m, uint32_t num_instances, uint32_t num_leaves,
                                        uint8_t *out, clvr_error *err)
{
    for (uint32_t i = 0; i < num_instances; ++i) {
        const clvr_instance *inst = &m->instances[i];
        if (inst->num_leaves > num_leaves || inst->first_leaf > num_leaves - inst->num_leaves)
            return clvr_error_set(err, CLVR_ERR_INTERNAL, "bvh: instance %u's leaves pass the %u leaf clusters", i,
                                  num_leaves);
        for (uint32_t leaf = inst->first_leaf; leaf < inst->first_leaf + inst->num_leaves; ++leaf) {
            uint32_t node, slot;
            clvr_leaf_parent(inst, leaf, &node, &slot);
            const clvr_bvh_node *n = &m->blas[node];
            if (n->child[slot] != (CLVR_BVH_LEAF_BIT | leaf))
                return clvr_error_set(err, CLVR_ERR_INTERNAL,
                                      "bvh: leaf cluster %u is not in slot %u of node %u; the element boxes "
                                      "expect the packed layout of bvh_build.h", leaf, slot, node);
            const float lo[3] = {n->lo_x[slot], n->lo_y[slot], n->lo_z[slot]};
            const float hi[3] = {n->hi_x[slot], n->hi_y[slot], n->hi_z[slot]};
            clvr_ebox_build_leaf(m, inst, leaf, lo, hi, out);
        }
    }
    return CLVR_OK;
}

static void ebox_release(clvr_cl *cl, clvr_bvh_device *b)
{
    clvr_cl_release(cl, &b->ebox);
    for (uint32_t p = 0; p + 1 < CLVR_MAX_SPLITS; ++p) clvr_cl_release(cl, &b->ebox_more[p]);
    b->ebox_bytes = 0;
}

clvr_status clvr_bvh_element_boxes_pieces(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                          cl_mem instances, uint32_t num_instances, const cl_mem *vertices,
                                          const cl_mem *idx16, const cl_mem *idx32, const uint64_t *piece_elements,
                                          uint32_t num_pieces, cl_mem dummy, uint32_t leaf_size, uint32_t num_leaves,
                                          clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_mem status_mem = NULL;
    cl_event evt = NULL;
    cl_uint status = 0;
    cl_mem out[CLVR_MAX_SPLITS];
    ebox_release(cl, b);
    if (num_pieces < 1 || num_pieces > CLVR_MAX_SPLITS)
        return clvr_error_set(err, CLVR_ERR_INTERNAL, "bvh: %u pieces (1 .. %u)", num_pieces, CLVR_MAX_SPLITS);
    for (uint32_t p = 0; p < CLVR_MAX_SPLITS; ++p) {
        if (p >= num_pieces) {
            out[p] = dummy; /* no leaf names it */
            continue;
        }
        const uint64_t bytes = (piece_elements[p + 1] - piece_elements[p]) * CLVR_EBOX_BYTES;
        CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)bytes, NULL, "element boxes",
                                p ? &b->ebox_more[p - 1] : &b->ebox, err));
        out[p] = p ? b->ebox_more[p - 1] : b->ebox;
        b->ebox_bytes += bytes;
    }
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof status, &status,
                            "element box status", &status_mem, err));
    if (num_leaves > 0 && num_instances > 0) {
        CLVR_TRY(CLVR_CL_ARGS(k->element_boxes, err, CLVR_ARG(b->blas), CLVR_ARG(instances), CLVR_ARG(num_instances),
                              CLVR_ARG(leaf_size), CLVR_ARG(num_leaves), CLVR_ARG(status_mem), CLVR_ARG(vertices[0]),
                              CLVR_ARG(idx16[0]), CLVR_ARG(idx32[0]), CLVR_ARG(out[0]), CLVR_ARG(vertices[1]),
                              CLVR_ARG(idx16[1]), CLVR_ARG(idx32[1]), CLVR_ARG(out[1]), CLVR_ARG(vertices[2]),
                              CLVR_ARG(idx16[2]), CLVR_ARG(idx32[2]), CLVR_ARG(out[2]), CLVR_ARG(vertices[3]),
                              CLVR_ARG(idx16[3]), CLVR_ARG(idx32[3]), CLVR_ARG(out[3])));
        CLVR_TRY(clvr_cl_run1d(cl, k->element_boxes, num_leaves, 64, &evt, err));
        if (evt) {
            CLVR_CL_CHECK(clWaitForEvents(1, &evt));
            b->build_seconds += clvr_cl_event_seconds(evt);
        }
        CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, status_mem, CL_TRUE, 0, sizeof status, &status, 0, NULL, NULL));
        if (status)
            s = clvr_error_set(err, CLVR_ERR_INTERNAL,
                               "bvh: a leaf cluster is not where the packed layout of bvh_build.h puts it; the "
                               "element boxes cannot be built (a bug: please report it)");
    }
cleanup:
    if (evt) clReleaseEvent(evt);
    clvr_cl_release(cl, &status_mem);
    if (s != CLVR_OK) ebox_release(cl, b);
    return s;
}

clvr_status clvr_bvh_element_boxes_device(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                          cl_mem instances, uint32_t num_instances, cl_mem vertices, cl_mem idx16,
                                          cl_mem idx32, uint32_t leaf_size, uint32_t num_leaves,
                                          uint64_t num_elements, clvr_error *err)
{
    /* One piece; the instance table stands in for the pieces it lacks (never read). */
    const cl_mem v[CLVR_MAX_SPLITS] = {vertices, instances, instances, instances};
    const cl_mem i16[CLVR_MAX_SPLITS] = {idx16, instances, instances, instances};
    const cl_mem i32[CLVR_MAX_SPLITS] = {idx32, instances, instances, instances};
    const uint64_t pe[2] = {0, num_elements};
    return clvr_bvh_element_boxes_pieces(cl, k, b, instances, num_instances, v, i16, i32, pe, 1, instances,
                                         leaf_size, num_leaves, err);
}

static void entry_release(clvr_cl *cl, clvr_bvh_device *b)
{
    clvr_cl_release(cl, &b->entry_grids);
    clvr_cl_release(cl, &b->entry_cells);
    b->entry_bytes = 0;
}

clvr_status clvr_bvh_entry_grids_pieces(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                        const clvr_instance *host_instances, cl_mem instances, uint32_t num_instances,
                                        const cl_mem *vertices, const cl_mem *idx16, const cl_mem *idx32,
                                        uint32_t leaf_size, uint32_t num_leaves, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_entry_grid *grids = NULL;
    cl_event evt = NULL;
    uint32_t nwords = 0;
    entry_release(cl, b);
    /* The element boxes speed up the centres' point location; the
     * placeholders of absent pieces are never read. */
    cl_mem eb[CLVR_MAX_SPLITS];
    for (uint32_t p = 0; p < CLVR_MAX_SPLITS; ++p)
        eb[p] = p == 0 ? b->ebox : b->ebox_more[p - 1] ? b->ebox_more[p - 1] : vertices[p];
    const cl_uint use_ebox = b->ebox != NULL, ni = num_instances, nl = num_leaves, ls = leaf_size;
    if (!eb[0]) eb[0] = vertices[0];
    if (!(grids = malloc(((size_t)num_instances + 1u) * sizeof *grids)))
        CLVR_TRY(clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bvh: no memory for %u entry grids", num_instances));
    CLVR_TRY(clvr_entry_grids_layout(host_instances, num_instances, cl->max_alloc_bytes, grids, &nwords, err));
    const float hints_on = grids[0].lo[3]; /* uploaded off, switched on once they are built */
    grids[0].lo[3] = 0.0f;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, ((size_t)num_instances + 1u) * sizeof *grids,
                            grids, "entry grids", &b->entry_grids, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)nwords * sizeof(cl_uint), NULL, "entry grid cells",
                            &b->entry_cells, err));
    b->entry_bytes = ((uint64_t)num_instances + 1u) * sizeof *grids + (uint64_t)nwords * sizeof(cl_uint);
    const cl_uint nc = grids[0].res[3] / 2u, zero = 0u, fill[2] = {CLVR_BVH_NOT_FOUND, 0u}; /* (first, last) leaf */
    if (nc)
        CLVR_CL_CHECK(clEnqueueFillBuffer(cl->queue, b->entry_cells, fill, sizeof fill, 0, (size_t)nc * sizeof fill,
                                          0, NULL, NULL));
    CLVR_CL_CHECK(clEnqueueFillBuffer(cl->queue, b->entry_cells, &zero, sizeof zero, (size_t)nc * sizeof fill,
                                      (size_t)(nwords - 2u * nc) * sizeof zero, 0, NULL, NULL));
    if (num_leaves && num_instances) {
        CLVR_TRY(CLVR_CL_ARGS(k->entry_rasterize, err, CLVR_ARG(b->blas), CLVR_ARG(instances),
                              CLVR_ARG(b->entry_grids), CLVR_ARG(ni), CLVR_ARG(nl), CLVR_ARG(b->entry_cells),
                              CLVR_ARG(ls), CLVR_ARG(vertices[0]), CLVR_ARG(idx16[0]), CLVR_ARG(idx32[0]),
                              CLVR_ARG(vertices[1]), CLVR_ARG(idx16[1]), CLVR_ARG(idx32[1]), CLVR_ARG(vertices[2]),
                              CLVR_ARG(idx16[2]), CLVR_ARG(idx32[2]), CLVR_ARG(vertices[3]), CLVR_ARG(idx16[3]),
                              CLVR_ARG(idx32[3])));
        CLVR_TRY(clvr_cl_run1d(cl, k->entry_rasterize, num_leaves, 64, &evt, err));
        if (evt) {
            CLVR_CL_CHECK(clWaitForEvents(1, &evt));
            b->build_seconds += clvr_cl_event_seconds(evt);
            clReleaseEvent(evt);
            evt = NULL;
        }
    }
    if (nc && num_instances) {
        CLVR_TRY(CLVR_CL_ARGS(k->entry_finish, err, CLVR_ARG(b->blas), CLVR_ARG(instances), CLVR_ARG(b->entry_grids),
                              CLVR_ARG(ni), CLVR_ARG(nc), CLVR_ARG(b->entry_cells), CLVR_ARG(ls), CLVR_ARG(use_ebox),
                              CLVR_ARG(vertices[0]), CLVR_ARG(idx16[0]), CLVR_ARG(idx32[0]), CLVR_ARG(eb[0]),
                              CLVR_ARG(vertices[1]), CLVR_ARG(idx16[1]), CLVR_ARG(idx32[1]), CLVR_ARG(eb[1]),
                              CLVR_ARG(vertices[2]), CLVR_ARG(idx16[2]), CLVR_ARG(idx32[2]), CLVR_ARG(eb[2]),
                              CLVR_ARG(vertices[3]), CLVR_ARG(idx16[3]), CLVR_ARG(idx32[3]), CLVR_ARG(eb[3])));
        CLVR_TRY(clvr_cl_run1d(cl, k->entry_finish, nc, 64, &evt, err));
        if (evt) {
            CLVR_CL_CHECK(clWaitForEvents(1, &evt));
            b->build_seconds += clvr_cl_event_seconds(evt);
            clReleaseEvent(evt);
            evt = NULL;
        }
    }
    /* The global hints: a point location per hint cell through the
     * finished entry grids, hints still off (grids[0].lo[3] 0 on the
     * device), then switched on (clvr_entry_cells_host's order). */
    const uint64_t hfirst = clvr_global_hints_first(&grids[0]), ncells = (uint64_t)nwords - hfirst;
    if (ncells) {
        const cl_uint first = (cl_uint)hfirst, n = (cl_uint)ncells, sh = (cl_uint)hints_on - 1u;
        CLVR_TRY(CLVR_CL_ARGS(k->entry_global, err, CLVR_ARG(b->tlas), CLVR_ARG(b->blas), CLVR_ARG(instances),
                              CLVR_ARG(b->entry_grids), CLVR_ARG(sh), CLVR_ARG(n), CLVR_ARG(first),
                              CLVR_ARG(b->entry_cells), CLVR_ARG(ls), CLVR_ARG(use_ebox), CLVR_ARG(vertices[0]),
                              CLVR_ARG(idx16[0]), CLVR_ARG(idx32[0]), CLVR_ARG(eb[0]), CLVR_ARG(vertices[1]),
                              CLVR_ARG(idx16[1]), CLVR_ARG(idx32[1]), CLVR_ARG(eb[1]), CLVR_ARG(vertices[2]),
                              CLVR_ARG(idx16[2]), CLVR_ARG(idx32[2]), CLVR_ARG(eb[2]), CLVR_ARG(vertices[3]),
                              CLVR_ARG(idx16[3]), CLVR_ARG(idx32[3]), CLVR_ARG(eb[3])));
        CLVR_TRY(clvr_cl_run1d(cl, k->entry_global, n, 64, &evt, err));
        if (evt) {
            CLVR_CL_CHECK(clWaitForEvents(1, &evt));
            b->build_seconds += clvr_cl_event_seconds(evt);
        }
        grids[0].lo[3] = hints_on;
        CLVR_CL_CHECK(clEnqueueWriteBuffer(cl->queue, b->entry_grids, CL_TRUE, 0, sizeof grids[0], &grids[0], 0, NULL,
                                           NULL));
    }
cleanup:
    if (evt) clReleaseEvent(evt);
    free(grids);
    if (s != CLVR_OK) entry_release(cl, b);
    return s;
}

clvr_status clvr_bvh_entry_grids_device(clvr_cl *cl, const clvr_bvh_kernels *k, clvr_bvh_device *b,
                                        const clvr_instance *host_instances, cl_mem instances, uint32_t num_instances,
                                        cl_mem vertices, cl_mem idx16, cl_mem idx32, uint32_t leaf_size,
                                        uint32_t num_leaves, clvr_error *err)
{
    /* One piece; the instance table stands in for the pieces it lacks (never read). */
    const cl_mem v[CLVR_MAX_SPLITS] = {vertices, instances, instances, instances};
    const cl_mem i16[CLVR_MAX_SPLITS] = {idx16, instances, instances, instances};
    const cl_mem i32[CLVR_MAX_SPLITS] = {idx32, instances, instances, instances};
    return clvr_bvh_entry_grids_pieces(cl, k, b, host_instances, instances, num_instances, v, i16, i32, leaf_size,
                                       num_leaves, err);
}
