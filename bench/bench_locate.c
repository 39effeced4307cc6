/* bench_locate.c: point-location throughput and BVH memory over leaf-cluster
 * sizes N = 1, 4, 8, 16, 32 (the shape of the paper's Table 2), on a
 * generated mesh (jittered grid cut into Kuhn tets, hexes or a mix; 1M+
 * elements by default) or a .bin file (--mesh, e.g. /tmp/clvr-data/
 * mixed-10M.bin). Clustering: the real preprocessing (clvr_preprocess:
 * Hilbert order, 16-bit instances); BVH: clvr_bvh_build_device; queries:
 * the clvr_locate_points kernel over uniform random points in the mesh
 * bounds (--order sorted: the same points along a Morton curve, as
 * neighbouring rays' samples), timed with event profiling after a warm-up,
 * median of 5. The machine may be shared: each row carries the 1-minute
 * load average and queries per CPU-second of this process (less sensitive
 * to other jobs than wall time).
 *
 *   bench_locate [--device SPEC] [--json FILE] [--cubes N | --mesh FILE.bin] [--kind tets|hexes|mixed]
 *                [--queries Q] [--leaf N] [--order random|sorted|rays] [--local L] [--hint coherent|incoherent]
 *                [--ebox on|off] [--entry on|off] [--one-curve auto|on|off]
 *
 * --ebox: quantized element boxes (kernels/locate.h), on by default as in
 * the renderer; off measures the leaf scan without them.
 * --entry: entry grids (kernels/locate.h), on by default as in the
 * renderer; off starts every walk at its instance's root. Their bytes count
 * in the BVH's bytes per element.
 * --one-curve: a mesh of several cell types sorted along one curve, every
 * cell a collapsed hex (clvr_preprocess_options.one_curve); default auto, as
 * in the renderer.
 * --hint: the query hint passed to the kernel (CLVR_LOCATE_*, clvr_shared.h);
 * default coherent (the faster on every order, clvr_shared.h).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clock.h"
#include "bench_util.h"
#include "bvh.h"
#include "cl_context.h"
#include "mesh_io.h"
#include "preprocess.h"
#include "../tests/bvh_fixture.h"
#include "bench_points.h"

typedef struct row {
    uint32_t n;
    double qps, qps_cpu, load, bytes_per_elem, ebox_bytes_per_elem, index_bytes_per_elem, build_ms, found;
    uint32_t blas_nodes, tlas_nodes;
} row;

static size_t g_local = 64; /* work-group size of the query kernel (--local) */
static uint32_t g_leaf = 0; /* only this leaf size (--leaf), 0: all */
static cl_uint g_ebox = 1; /* quantized element boxes (--ebox on|off) */
static int g_entry = 1;    /* entry grids (--entry on|off, kernels/locate.h) */
static int g_one_curve = CLVR_ONE_CURVE_AUTO; /* mixed meshes on one curve (--one-curve auto|on|off, preprocess.h) */
static cl_uint g_hints = CLVR_LOCATE_INCOHERENT; /* query hint of the kernel (--order, --hint) */
static cl_uint g_chain = 1; /* points per work item with one ray's hint (--order rays: a ray's samples) */
#define NRUNS 5

static clvr_status run_one(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_mesh *m, uint32_t leaf,
                           float (*pts)[4], uint32_t nq, row *out, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_clustered c;
    memset(&c, 0, sizeof c);
    cl_mem dpts = NULL, dsc = NULL, deid = NULL;
    clvr_bvh_device db;
    memset(&db, 0, sizeof db);
    uint32_t *ids = malloc((size_t)(nq ? nq : 1) * sizeof *ids);
    cl_event evt = NULL;
    if (!ids) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_locate: no memory for %u results", nq);
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.leaf_size = leaf;
    o.one_curve = g_one_curve;
    CLVR_TRY(clvr_preprocess(cl, m, &o, &c, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)(nq ? nq : 1) * sizeof *pts, pts,
                            "points", &dpts, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)(nq ? nq : 1) * 4, NULL, "scalars", &dsc, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)(nq ? nq : 1) * 4, NULL, "ids", &deid, err));
    CLVR_TRY(clvr_bvh_build_device(cl, k, c.host_instances, (uint32_t)c.num_instances, c.instances, c.leaf_boxes,
                                   (uint32_t)c.num_leaves, &db, err));
    out->n = leaf;
    out->build_ms = db.build_seconds * 1e3;
    out->blas_nodes = db.blas_nodes;
    out->tlas_nodes = db.tlas_nodes;
    if (g_ebox)
        CLVR_TRY(clvr_bvh_element_boxes_device(cl, k, &db, c.instances, (uint32_t)c.num_instances, c.vertices, c.idx16,
                                               c.idx32, c.leaf_size, (uint32_t)c.num_leaves, c.num_elements, err));
    if (g_entry)
        CLVR_TRY(clvr_bvh_entry_grids_device(cl, k, &db, c.host_instances, c.instances, (uint32_t)c.num_instances,
                                             c.vertices, c.idx16, c.idx32, c.leaf_size, (uint32_t)c.num_leaves, err));
    out->bytes_per_elem =
        (double)(clvr_bvh_bytes(db.tlas_nodes, db.blas_nodes) + (g_entry ? db.entry_bytes : 0)) / (double)c.num_elements;
    out->ebox_bytes_per_elem = (double)db.ebox_bytes / (double)c.num_elements;
    out->index_bytes_per_elem = (double)(c.num_idx16 * 2 + c.num_idx32 * 4) / (double)c.num_elements;
    cl_uint n = nq, ls = leaf, root = db.tlas_root;
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 0, sizeof(cl_mem), &dpts));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 1, sizeof(cl_uint), &n));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 2, sizeof(cl_mem), &db.tlas));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 3, sizeof(cl_uint), &root));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 4, sizeof(cl_mem), &db.blas));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 5, sizeof(cl_mem), &c.instances));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 6, sizeof(cl_mem), &c.vertices));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 7, sizeof(cl_mem), &c.idx16));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 8, sizeof(cl_mem), &c.idx32));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 9, sizeof(cl_uint), &ls));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 10, sizeof(cl_mem), &dsc));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 11, sizeof(cl_mem), &deid));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 12, sizeof(cl_uint), &g_hints));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 13, sizeof(cl_mem), g_ebox ? &db.ebox : &c.vertices));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 14, sizeof(cl_uint), &g_ebox));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 15, sizeof(cl_uint), &g_chain));
    /* --entry off: NULL grids, every walk from its instance's root */
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 16, sizeof(cl_mem), g_entry ? &db.entry_grids : NULL));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 17, sizeof(cl_mem), g_entry ? &db.entry_cells : NULL));
    const size_t items = (nq + g_chain - 1) / g_chain;
    /* warm-up, then the median of NRUNS timed runs */
    CLVR_TRY(clvr_cl_run1d(cl, k->locate_points, items, g_local, NULL, err));
    CLVR_CL_CHECK(clFinish(cl->queue));
    double t[NRUNS], tc[NRUNS], ld[NRUNS];
    for (int r = 0; r < NRUNS; ++r) {
        const double c0 = clvr_clock_cpu_s();
        CLVR_TRY(clvr_cl_run1d(cl, k->locate_points, items, g_local, &evt, err));
        CLVR_CL_CHECK(clWaitForEvents(1, &evt));
        tc[r] = clvr_clock_cpu_s() - c0;
        t[r] = clvr_cl_event_seconds(evt);
        ld[r] = bench_load1();
        clReleaseEvent(evt);
        evt = NULL;
    }
    out->qps = nq / bench_median(t, NRUNS);
    out->qps_cpu = nq / bench_median(tc, NRUNS);
    out->load = bench_median(ld, NRUNS);
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, deid, CL_TRUE, 0, (size_t)nq * 4, ids, 0, NULL, NULL));
    uint32_t found = 0;
    for (uint32_t i = 0; i < nq; ++i) found += ids[i] != CLVR_BVH_NOT_FOUND;
    out->found = nq ? (double)found / nq : 0.0;
cleanup:
    if (evt) clReleaseEvent(evt);
    clvr_bvh_device_release(cl, &db);
    clvr_cl_release(cl, &dpts);
    clvr_cl_release(cl, &dsc);
    clvr_cl_release(cl, &deid);
    clvr_clustered_release(cl, &c);
    free(ids);
    return s;
}

int main(int argc, char **argv)
{
    const char *device = NULL, *json = NULL, *kind_name = "tets", *mesh_path = NULL, *order = "random", *hint = NULL;
    uint32_t cubes = 56, nq = 1u << 20;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--device") && i + 1 < argc) device = argv[++i];
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--cubes") && i + 1 < argc) cubes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--mesh") && i + 1 < argc) mesh_path = argv[++i];
        else if (!strcmp(argv[i], "--queries") && i + 1 < argc) nq = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--kind") && i + 1 < argc) kind_name = argv[++i];
        else if (!strcmp(argv[i], "--order") && i + 1 < argc) order = argv[++i];
        else if (!strcmp(argv[i], "--local") && i + 1 < argc) g_local = (size_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--leaf") && i + 1 < argc) g_leaf = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--hint") && i + 1 < argc) hint = argv[++i];
        else if (!strcmp(argv[i], "--ebox") && i + 1 < argc && (!strcmp(argv[i + 1], "on") || !strcmp(argv[i + 1], "off")))
            g_ebox = !strcmp(argv[++i], "on");
        else if (!strcmp(argv[i], "--entry") && i + 1 < argc &&
                 (!strcmp(argv[i + 1], "on") || !strcmp(argv[i + 1], "off")))
            g_entry = !strcmp(argv[++i], "on");
        else if (!strcmp(argv[i], "--one-curve") && i + 1 < argc &&
                 (!strcmp(argv[i + 1], "auto") || !strcmp(argv[i + 1], "on") || !strcmp(argv[i + 1], "off"))) {
            ++i;
            g_one_curve = !strcmp(argv[i], "on") ? CLVR_ONE_CURVE_ON : !strcmp(argv[i], "off") ? CLVR_ONE_CURVE_OFF
                                                                                             : CLVR_ONE_CURVE_AUTO;
        }
        else {
            fprintf(stderr,
                    "usage: %s [--device SPEC] [--json FILE] [--cubes N | --mesh FILE.bin] [--kind tets|hexes|mixed] "
                    "[--queries Q] [--leaf N] [--order random|sorted|rays] [--local L] [--hint coherent|incoherent] [--ebox on|off] [--entry on|off] [--one-curve auto|on|off]\n",
                    argv[0]);
            return 2;
        }
    }
    const int order_id = bench_order_from_name(order);
    if (order_id < 0) {
        fprintf(stderr, "bench_locate: --order must be random, sorted or rays\n");
        return 2;
    }
    g_chain = bench_order_chain(order_id);
    if (bench_query_hint(hint, &hint, &g_hints)) {
        fprintf(stderr, "bench_locate: --hint must be coherent or incoherent\n");
        return 2;
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
    double t0 = clvr_clock_monotonic_s();
    const clvr_status ms = mesh_path ? clvr_mesh_load(mesh_path, NULL, &m, &err)
                                     : fx_grid_mesh(cubes, kind, 0.2f, 1.0f, 0.0f, 1, &m, &err);
    if (ms != CLVR_OK) {
        fprintf(stderr, "bench_locate: %s\n", err.msg);
        return 1;
    }
    const uint64_t ne = clvr_mesh_num_elements(&m);
    float (*pts)[4] = bench_make_points(&m, nq, order_id);
    if (!pts) {
        fprintf(stderr, "bench_locate: no memory for %u points\n", nq);
        return 1;
    }
    const char *what = mesh_path ? mesh_path : kind_name;
    printf("# bench_locate: %s, %llu elements (%s), %u %s queries, work-group %zu, hint %s\n", cl.device_name,
           (unsigned long long)ne, what, nq, order, g_local, hint);
    printf("# device: %s | %s | driver %s | compute units %u | mesh %s in %.1f s\n", cl.platform_name,
           cl.device_version, cl.driver_version, cl.compute_units, mesh_path ? "loaded" : "generated", clvr_clock_monotonic_s() - t0);
    printf("\n| N | point queries/s | queries per CPU-second | load (1 min) | BVH bytes/element | element box bytes/element "
           "| index bytes/element | BLAS nodes | TLAS nodes | build ms | found |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    const uint32_t ns[5] = {1, 4, 8, 16, 32};
    row rows[5];
    int nrows = 0, rc = 0;
    for (int i = 0; i < 5; ++i) {
        if (g_leaf && ns[i] != g_leaf) continue;
        if (run_one(&cl, &k, &m, ns[i], pts, nq, &rows[nrows], &err) != CLVR_OK) {
            fprintf(stderr, "bench_locate: N=%u: %s\n", ns[i], err.msg);
            rc = 1;
            break;
        }
        const row *r = &rows[nrows++];
        printf("| %u | %.3g | %.3g | %.2f | %.2f | %.2f | %.2f | %u | %u | %.1f | %.3f |\n", r->n, r->qps, r->qps_cpu,
               r->load, r->bytes_per_elem, r->ebox_bytes_per_elem, r->index_bytes_per_elem, r->blas_nodes, r->tlas_nodes, r->build_ms, r->found);
        fflush(stdout);
    }
    if (json) {
        FILE *f = fopen(json, "w");
        if (!f) {
            fprintf(stderr, "bench_locate: cannot write %s\n", json);
            rc = 5;
        } else {
            fprintf(f, "{\"bench\": \"locate\", \"device\": \"%s\", \"elements\": %llu, \"mesh\": \"%s\", "
                       "\"queries\": %u, \"order\": \"%s\", \"local\": %zu, \"hint\": \"%s\", \"rows\": [",
                    cl.device_name, (unsigned long long)ne, what, nq, order, g_local, hint);
            for (int i = 0; i < nrows; ++i)
                fprintf(f, "%s{\"N\": %u, \"queries_per_s\": %.6g, \"queries_per_cpu_s\": %.6g, \"load\": %.2f, "
                           "\"bvh_bytes_per_element\": %.4f, \"ebox_bytes_per_element\": %.4f, \"index_bytes_per_element\": %.4f, \"blas_nodes\": %u, "
                           "\"tlas_nodes\": %u, \"build_ms\": %.3f, \"found\": %.4f}",
                        i ? ", " : "", rows[i].n, rows[i].qps, rows[i].qps_cpu, rows[i].load, rows[i].bytes_per_elem,
                        rows[i].ebox_bytes_per_elem, rows[i].index_bytes_per_elem, rows[i].blas_nodes, rows[i].tlas_nodes, rows[i].build_ms,
                        rows[i].found);
            fprintf(f, "]}\n");
            fclose(f);
        }
    }
    free(pts);
    clvr_mesh_free(&m);
    clvr_bvh_kernels_destroy(&k);
    clvr_cl_destroy(&cl);
    return rc;
}
