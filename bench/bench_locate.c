/* bench_locate.c: point-location throughput and BVH memory over leaf-cluster
 * sizes N = 1, 4, 8, 16, 32 (the shape of the paper's Table 2) on a
 * generated mesh (jittered grid cut into Kuhn tets, 1M+ elements by
 * default). Clustering: the host fixture of tests/bvh_fixture.h (Morton
 * order, instances of 50K elements); BVH: device build; queries: the
 * clvr_locate_points kernel over random points in the mesh bounds, timed
 * with event profiling after a warm-up.
 *
 *   bench_locate [--device SPEC] [--json FILE] [--cubes N] [--queries Q] [--kind tets|hexes|mixed]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/resource.h>

#include "bvh.h"
#include "cl_context.h"
#include "../tests/bvh_fixture.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct row {
    uint32_t n;
    double qps, bytes_per_elem, build_ms, found;
    uint32_t blas_nodes, tlas_nodes;
} row;

/* CPU seconds of this process (all threads): queries per CPU second stays
 * meaningful on a machine shared with other jobs, where wall time is not. */
static double cpu_s(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static size_t g_local = 64; /* work-group size of the query kernel (--local) */
static uint32_t g_leaf = 0; /* only this leaf size (--leaf), 0: all */

static clvr_status run_one(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_mesh *m, uint32_t leaf, uint32_t nq,
                           row *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    fx_clustered c;
    cl_mem dv = NULL, d16 = NULL, d32 = NULL, dinst = NULL, dleaf = NULL, dpts = NULL, dsc = NULL, deid = NULL;
    clvr_bvh_device db = {0};
    float (*pts)[4] = malloc((size_t)nq * sizeof *pts);
    uint32_t *ids = malloc((size_t)nq * sizeof *ids);
    cl_event evt = NULL;
    if (fx_cluster(m, leaf, 50000, 0, &c) != 0 || !pts || !ids) {
        free(pts);
        free(ids);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_locate: no memory for the clustering");
    }
    uint64_t rs = 42;
    for (uint32_t i = 0; i < nq; ++i) {
        for (int a = 0; a < 3; ++a) {
            rs += 0x9e3779b97f4a7c15ull;
            uint64_t z = rs;
            z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
            z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
            z ^= z >> 31;
            const float r = (float)(z >> 40) * (1.0f / 16777216.0f);
            pts[i][a] = m->bounds_lo[a] + r * (m->bounds_hi[a] - m->bounds_lo[a]);
        }
        pts[i][3] = 0.0f;
    }
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_vertices + 1) * sizeof(clvr_vec4),
                            c.vertices, "vertices", &dv, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_idx16 + 1) * 2, c.idx16, "idx16", &d16, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_idx32 + 1) * 4, c.idx32, "idx32", &d32, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, (c.num_instances + 1) * sizeof(clvr_instance),
                            c.instances, "instances", &dinst, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_leaves + 1) * sizeof(clvr_box),
                            c.leaf_boxes, "leaf boxes", &dleaf, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)nq * sizeof *pts, pts, "points", &dpts, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)nq * 4, NULL, "scalars", &dsc, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)nq * 4, NULL, "ids", &deid, err));
    CLVR_TRY(clvr_bvh_build_device(cl, k, c.instances, c.num_instances, dinst, dleaf, c.num_leaves, &db, err));
    out->n = leaf;
    out->build_ms = db.build_seconds * 1e3;
    out->blas_nodes = db.blas_nodes;
    out->tlas_nodes = db.tlas_nodes;
    out->bytes_per_elem = (double)clvr_bvh_bytes(db.tlas_nodes, db.blas_nodes) / (double)c.num_elements;
    cl_uint n = nq, ls = leaf, root = db.tlas_root;
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 0, sizeof(cl_mem), &dpts));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 1, sizeof(cl_uint), &n));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 2, sizeof(cl_mem), &db.tlas));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 3, sizeof(cl_uint), &root));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 4, sizeof(cl_mem), &db.blas));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 5, sizeof(cl_mem), &dinst));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 6, sizeof(cl_mem), &dv));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 7, sizeof(cl_mem), &d16));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 8, sizeof(cl_mem), &d32));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 9, sizeof(cl_uint), &ls));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 10, sizeof(cl_mem), &dsc));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 11, sizeof(cl_mem), &deid));
    /* warm-up, then the best of 3 timed runs */
    CLVR_TRY(clvr_cl_run1d(cl, k->locate_points, nq, g_local, NULL, err));
    CLVR_CL_CHECK(clFinish(cl->queue));
    double best = 1e30, best_cpu = 1e30;
    for (int r = 0; r < 3; ++r) {
        const double c0 = cpu_s();
        CLVR_TRY(clvr_cl_run1d(cl, k->locate_points, nq, g_local, &evt, err));
        CLVR_CL_CHECK(clWaitForEvents(1, &evt));
        const double ct = cpu_s() - c0;
        const double t = clvr_cl_event_seconds(evt);
        if (t < best) best = t;
        if (ct < best_cpu) best_cpu = ct;
        clReleaseEvent(evt);
        evt = NULL;
    }
    out->qps = nq / best;
    fprintf(stderr, "N=%u: %.3g queries/s wall, %.3g queries per CPU-second\n", leaf, nq / best, nq / best_cpu);
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, deid, CL_TRUE, 0, (size_t)nq * 4, ids, 0, NULL, NULL));
    uint32_t found = 0;
    for (uint32_t i = 0; i < nq; ++i) found += ids[i] != CLVR_BVH_NOT_FOUND;
    out->found = (double)found / nq;
cleanup:
    if (evt) clReleaseEvent(evt);
    clvr_bvh_device_release(cl, &db);
    clvr_cl_release(cl, &dv);
    clvr_cl_release(cl, &d16);
    clvr_cl_release(cl, &d32);
    clvr_cl_release(cl, &dinst);
    clvr_cl_release(cl, &dleaf);
    clvr_cl_release(cl, &dpts);
    clvr_cl_release(cl, &dsc);
    clvr_cl_release(cl, &deid);
    free(pts);
    free(ids);
    fx_clustered_free(&c);
    return s;
}

int main(int argc, char **argv)
{
    const char *device = NULL, *json = NULL, *kind_name = "tets";
    uint32_t cubes = 56, nq = 1u << 20;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--device") && i + 1 < argc) device = argv[++i];
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--cubes") && i + 1 < argc) cubes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--queries") && i + 1 < argc) nq = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--kind") && i + 1 < argc) kind_name = argv[++i];
        else if (!strcmp(argv[i], "--local") && i + 1 < argc) g_local = (size_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--leaf") && i + 1 < argc) g_leaf = (uint32_t)atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: %s [--device SPEC] [--json FILE] [--cubes N] [--queries Q] [--kind tets|hexes|mixed]\n",
                    argv[0]);
            return 2;
        }
    }
    const uint32_t kind = !strcmp(kind_name, "hexes") ? FX_HEXES : !strcmp(kind_name, "mixed") ? FX_MIXED : FX_TETS;
    clvr_cl cl;
    clvr_error err = {0};
    clvr_bvh_kernels k;
    clvr_mesh m;
    memset(&m, 0, sizeof m);
    if (clvr_cl_create(device, &cl, &err) != CLVR_OK) {
        fprintf(stderr, "bench_locate: %s\n", err.msg);
        return 4;
    }
    if (clvr_bvh_kernels_create(&cl, &k, &err) != CLVR_OK) {
        fprintf(stderr, "bench_locate: %s\n", err.msg);
        clvr_cl_destroy(&cl);
        return 4;
    }
    double t0 = now_s();
    if (fx_grid_mesh(cubes, kind, 0.2f, 1.0f, 0.0f, 1, &m, &err) != CLVR_OK) {
        fprintf(stderr, "bench_locate: %s\n", err.msg);
        return 1;
    }
    const uint64_t ne = clvr_mesh_num_elements(&m);
    printf("# bench_locate: %s, %llu elements (%s), %u queries\n", cl.device_name, (unsigned long long)ne, kind_name,
           nq);
    printf("# device: %s | %s | driver %s | compute units %u | mesh generated in %.1f s\n", cl.platform_name,
           cl.device_version, cl.driver_version, cl.compute_units, now_s() - t0);
    printf("\n| N | point queries/s | BVH bytes/element | BLAS nodes | TLAS nodes | build ms | found |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|\n");
    const uint32_t ns[5] = {1, 4, 8, 16, 32};
    row rows[5];
    int nrows = 0, rc = 0;
    for (int i = 0; i < 5; ++i) {
        if (g_leaf && ns[i] != g_leaf) continue;
        if (run_one(&cl, &k, &m, ns[i], nq, &rows[nrows], &err) != CLVR_OK) {
            fprintf(stderr, "bench_locate: N=%u: %s\n", ns[i], err.msg);
            rc = 1;
            break;
        }
        const row *r = &rows[nrows++];
        printf("| %u | %.3g | %.2f | %u | %u | %.1f | %.3f |\n", r->n, r->qps, r->bytes_per_elem, r->blas_nodes,
               r->tlas_nodes, r->build_ms, r->found);
        fflush(stdout);
    }
    if (json) {
        FILE *f = fopen(json, "w");
        if (!f) {
            fprintf(stderr, "bench_locate: cannot write %s\n", json);
            rc = 5;
        } else {
            fprintf(f, "{\"bench\": \"locate\", \"device\": \"%s\", \"elements\": %llu, \"kind\": \"%s\", \"queries\": %u, \"rows\": [",
                    cl.device_name, (unsigned long long)ne, kind_name, nq);
            for (int i = 0; i < nrows; ++i)
                fprintf(f, "%s{\"N\": %u, \"queries_per_s\": %.6g, \"bvh_bytes_per_element\": %.4f, \"blas_nodes\": %u, "
                           "\"tlas_nodes\": %u, \"build_ms\": %.3f, \"found\": %.4f}",
                        i ? ", " : "", rows[i].n, rows[i].qps, rows[i].bytes_per_elem, rows[i].blas_nodes,
                        rows[i].tlas_nodes, rows[i].build_ms, rows[i].found);
            fprintf(f, "]}\n");
            fclose(f);
        }
    }
    clvr_mesh_free(&m);
    clvr_bvh_kernels_destroy(&k);
    clvr_cl_destroy(&cl);
    return rc;
}
