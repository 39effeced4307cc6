#include "majorant.h"

#include <stdlib.h>
#include <string.h>

struct clvr_majorants {
    clvr_cl *cl;
    const clvr_clustered *mesh;
    cl_program prog;
    cl_kernel k_cluster_maj, k_grid_clear, k_grid_splat_el, k_grid_maj, k_grid_blocks;
    cl_mem cluster_maj;          /* float [num_sampling] */
    cl_mem grid_range;           /* ordered (min, max) per cell, see kernels/majorant.cl */
    cl_mem grid_maj, block_maj;  /* float per cell, per block */
    cl_mem block_sum;            /* float per block: sum of its cells' majorants */
    cl_mem block2_maj;           /* the blocks of the blocks (the coarse grid's blocks) */
    uint32_t grid_res;           /* resolution of the grid buffers (0: no grid) */
    uint32_t use_res;            /* the grid the frames read: grid_res, or its blocks' */
    double fine_mean, coarse_mean; /* the last choice's means (0, 0 when none was made) */
    float grid_lo[3], grid_hi[3]; /* domain the grid was rasterized over */
};

uint32_t clvr_majorant_blocks(uint32_t res) { return (res + CLVR_DDA_BLOCK - 1) / CLVR_DDA_BLOCK; }

clvr_status clvr_majorants_create(clvr_cl *cl, const clvr_clustered *mesh, clvr_majorants **out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_majorants *m = calloc(1, sizeof *m);
    *out = NULL;
    if (!m) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory creating the majorants");
    m->cl = cl;
    m->mesh = mesh;
    CLVR_TRY(clvr_cl_build(cl, "majorant.cl", NULL, &m->prog, err));
    CLVR_TRY(clvr_cl_kernel(m->prog, "clvr_cluster_majorants", &m->k_cluster_maj, err));
    CLVR_TRY(clvr_cl_kernel(m->prog, "clvr_grid_clear", &m->k_grid_clear, err));
    CLVR_TRY(clvr_cl_kernel(m->prog, "clvr_grid_splat_elements", &m->k_grid_splat_el, err));
    CLVR_TRY(clvr_cl_kernel(m->prog, "clvr_grid_majorants", &m->k_grid_maj, err));
    CLVR_TRY(clvr_cl_kernel(m->prog, "clvr_grid_blocks", &m->k_grid_blocks, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)(mesh->num_sampling ? mesh->num_sampling : 1) * sizeof(float),
                            NULL, "cluster majorants", &m->cluster_maj, err));
    *out = m;
    m = NULL;
cleanup:
    clvr_majorants_destroy(m);
    return s;
}

static void release_grid(clvr_majorants *m)
{
    clvr_cl_release(m->cl, &m->grid_range);
    clvr_cl_release(m->cl, &m->grid_maj);
    clvr_cl_release(m->cl, &m->block_maj);
    clvr_cl_release(m->cl, &m->block_sum);
    clvr_cl_release(m->cl, &m->block2_maj);
    m->grid_res = m->use_res = 0;
    m->fine_mean = m->coarse_mean = 0.0;
}

void clvr_majorants_destroy(clvr_majorants *m)
{
    if (!m) return;
    cl_kernel ks[] = {m->k_cluster_maj, m->k_grid_clear, m->k_grid_splat_el, m->k_grid_maj, m->k_grid_blocks};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i)
        if (ks[i]) clReleaseKernel(ks[i]);
    if (m->prog) clReleaseProgram(m->prog);
    release_grid(m);
    clvr_cl_release(m->cl, &m->cluster_maj);
    free(m);
}

clvr_status clvr_majorants_build_grid(clvr_majorants *m, const clvr_frame *f, cl_mem frame, int *rebuilt,
                                      clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = m->cl;
    const uint32_t res = f->grid_res;
    const uint64_t cells = (uint64_t)res * res * res, rc = clvr_majorant_blocks(res),
                   rc2 = clvr_majorant_blocks((uint32_t)rc);
    const cl_uint ncells = (cl_uint)cells;
    if (rebuilt) *rebuilt = 0;
    if (m->grid_res == res && !memcmp(m->grid_lo, f->grid_lo, sizeof m->grid_lo) &&
        !memcmp(m->grid_hi, f->grid_hi, sizeof m->grid_hi))
        return CLVR_OK;
    release_grid(m);
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)cells * 2 * sizeof(cl_uint), NULL, "macrocell ranges",
                            &m->grid_range, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)cells * sizeof(cl_float), NULL, "macrocell majorants",
                            &m->grid_maj, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)(rc * rc * rc) * sizeof(cl_float), NULL,
                            "macrocell block majorants", &m->block_maj, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)(rc * rc * rc) * sizeof(cl_float), NULL,
                            "macrocell block sums", &m->block_sum, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)(rc2 * rc2 * rc2) * sizeof(cl_float), NULL,
                            "coarse macrocell block majorants", &m->block2_maj, err));
    CLVR_TRY(CLVR_CL_ARGS(m->k_grid_clear, err, CLVR_ARG(m->grid_range), CLVR_ARG(ncells)));
    CLVR_TRY(clvr_cl_run1d(cl, m->k_grid_clear, cells, 64, NULL, err));
    /* Per element, not per sampling cluster: tighter cells (majorant.cl). */
    const clvr_clustered *c = m->mesh;
    cl_uint ninst = (cl_uint)c->num_instances, nelem = (cl_uint)c->num_elements;
    clvr_clustered_pieces pc; /* every piece of a split mesh (clvr_instance.piece) */
    clvr_clustered_get_pieces(c, &pc);
    CLVR_TRY(CLVR_CL_ARGS(m->k_grid_splat_el, err, CLVR_ARG(c->instances), CLVR_ARG(ninst), CLVR_ARG(nelem),
                          CLVR_ARG(frame), CLVR_ARG(m->grid_range), CLVR_ARG(pc.vertices[0]), CLVR_ARG(pc.idx16[0]),
                          CLVR_ARG(pc.idx32[0]), CLVR_ARG(pc.vertices[1]), CLVR_ARG(pc.idx16[1]),
                          CLVR_ARG(pc.idx32[1]), CLVR_ARG(pc.vertices[2]), CLVR_ARG(pc.idx16[2]),
                          CLVR_ARG(pc.idx32[2]), CLVR_ARG(pc.vertices[3]), CLVR_ARG(pc.idx16[3]),
                          CLVR_ARG(pc.idx32[3])));
    if (nelem) CLVR_TRY(clvr_cl_run1d(cl, m->k_grid_splat_el, nelem, 64, NULL, err));
    m->grid_res = m->use_res = res;
    memcpy(m->grid_lo, f->grid_lo, sizeof m->grid_lo);
    memcpy(m->grid_hi, f->grid_hi, sizeof m->grid_hi);
    if (rebuilt) *rebuilt = 1;
cleanup:
    if (s != CLVR_OK) release_grid(m);
    return s;
}

clvr_status clvr_majorants_set_tf(clvr_majorants *m, cl_mem tf, cl_mem frame, int choose, float *global_majorant,
                                  clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_cl *cl = m->cl;
    float *maj = NULL, *sums = NULL;
    cl_uint nclusters = (cl_uint)m->mesh->num_sampling;
    cl_uint res = m->grid_res, ncells = res * res * res, rc = clvr_majorant_blocks(res), rc2 = clvr_majorant_blocks(rc);
    if (!res) return clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr_majorants_set_tf before a macrocell grid");
    m->use_res = res;
    m->fine_mean = m->coarse_mean = 0.0;
    CLVR_TRY(CLVR_CL_ARGS(m->k_cluster_maj, err, CLVR_ARG(m->mesh->sampling), CLVR_ARG(nclusters), CLVR_ARG(tf),
                          CLVR_ARG(frame), CLVR_ARG(m->cluster_maj)));
    CLVR_TRY(clvr_cl_run1d(cl, m->k_cluster_maj, nclusters, 64, NULL, err));
    CLVR_TRY(CLVR_CL_ARGS(m->k_grid_maj, err, CLVR_ARG(m->grid_range), CLVR_ARG(ncells), CLVR_ARG(tf),
                          CLVR_ARG(frame), CLVR_ARG(m->grid_maj)));
    CLVR_TRY(clvr_cl_run1d(cl, m->k_grid_maj, ncells, 64, NULL, err));
    CLVR_TRY(CLVR_CL_ARGS(m->k_grid_blocks, err, CLVR_ARG(m->grid_maj), CLVR_ARG(res), CLVR_ARG(m->block_maj),
                          CLVR_ARG(m->block_sum), CLVR_ARG(rc)));
    CLVR_TRY(clvr_cl_run1d(cl, m->k_grid_blocks, (size_t)rc * rc * rc, 64, NULL, err));
    if (choose && rc < res && res % CLVR_DDA_BLOCK == 0) {
        /* The mean majorant of the fine cells against the blocks' (see
         * CLVR_MACROCELLS_FINE): rc^3 maxima and sums, 32^3 of each at 128.
         * Whole blocks only (res a multiple of the block), so that both
         * means are over the same box. */
        const size_t nb = (size_t)rc * rc * rc;
        maj = malloc(nb * sizeof(float));
        sums = malloc(nb * sizeof(float));
        if (!maj || !sums) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading majorants"); goto cleanup; }
        CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, m->block_maj, CL_TRUE, 0, nb * sizeof(float), maj, 0, NULL, NULL));
        CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, m->block_sum, CL_TRUE, 0, nb * sizeof(float), sums, 0, NULL, NULL));
        double fine = 0.0, coarse = 0.0;
        for (size_t i = 0; i < nb; ++i) {
            fine += sums[i];
            coarse += maj[i];
        }
        m->fine_mean = fine / ((double)res * res * res);
        m->coarse_mean = coarse / (double)nb;
        if (!(m->fine_mean < (double)CLVR_MACROCELLS_GAIN * m->coarse_mean)) {
            /* The coarse grid: its cells are the blocks, its blocks theirs. */
            const cl_mem no_sums = NULL;
            CLVR_TRY(CLVR_CL_ARGS(m->k_grid_blocks, err, CLVR_ARG(m->block_maj), CLVR_ARG(rc), CLVR_ARG(m->block2_maj),
                                  CLVR_ARG(no_sums), CLVR_ARG(rc2)));
            CLVR_TRY(clvr_cl_run1d(cl, m->k_grid_blocks, (size_t)rc2 * rc2 * rc2, 64, NULL, err));
            m->use_res = rc;
        }
        free(maj);
        maj = NULL;
    }
    /* The global majorant of `track` is the largest cluster majorant. */
    maj = malloc((size_t)(nclusters ? nclusters : 1) * sizeof(float));
    if (!maj) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading majorants"); goto cleanup; }
    if (nclusters)
        CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, m->cluster_maj, CL_TRUE, 0, nclusters * sizeof(float), maj, 0,
                                          NULL, NULL));
    float g = 0.0f;
    for (cl_uint i = 0; i < nclusters; ++i) g = maj[i] > g ? maj[i] : g;
    *global_majorant = g;
cleanup:
    free(maj);
    free(sums);
    if (s != CLVR_OK) m->use_res = res;
    return s;
}

uint32_t clvr_majorants_grid(const clvr_majorants *m, double *fine_mean, double *coarse_mean)
{
    if (fine_mean) *fine_mean = m->fine_mean;
    if (coarse_mean) *coarse_mean = m->coarse_mean;
    return m->use_res;
}

clvr_majorant_arrays clvr_majorants_arrays(const clvr_majorants *m)
{
    const int coarse = m->use_res != m->grid_res;
    return (clvr_majorant_arrays){.clusters = m->cluster_maj,
                                  .cells = coarse ? m->block_maj : m->grid_maj,
                                  .blocks = coarse ? m->block2_maj : m->block_maj};
}

clvr_status clvr_majorants_read(clvr_majorants *m, float *clusters, float *cells, float *blocks, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    cl_command_queue q = m->cl->queue;
    const clvr_majorant_arrays a = clvr_majorants_arrays(m);
    const size_t res = m->use_res, rc = clvr_majorant_blocks(m->use_res);
    if ((cells || blocks) && !res)
        return clvr_error_set(err, CLVR_ERR_INTERNAL, "clvr_majorants_read before a macrocell grid");
    if (blocks)
        CLVR_CL_CHECK(clEnqueueReadBuffer(q, a.blocks, CL_TRUE, 0, rc * rc * rc * sizeof(float), blocks, 0, NULL, NULL));
    if (clusters && m->mesh->num_sampling)
        CLVR_CL_CHECK(clEnqueueReadBuffer(q, m->cluster_maj, CL_TRUE, 0, (size_t)m->mesh->num_sampling * sizeof(float),
                                          clusters, 0, NULL, NULL));
    if (cells)
        CLVR_CL_CHECK(clEnqueueReadBuffer(q, a.cells, CL_TRUE, 0, res * res * res * sizeof(float), cells, 0, NULL, NULL));
cleanup:
    return s;
}
