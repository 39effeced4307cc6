/* bench_walk.c: what a point-location walk does per query, counted on the
 * host with kernels/locate.h's own code (CLVR_WALK_STAT): nodes of the top
 * and bottom trees visited, instances entered, leaf clusters scanned,
 * elements that pass their quantized box, elements given the exact
 * containment test (barycentric or Newton), and how often
 * a ray's hint (clvr_locate_hinted) held the next sample. Issue #19 asks
 * where the walk's time goes on graded meshes; counts answer that without
 * hardware counters, which the benchmark VMs do not have. The mesh is
 * clustered by the real preprocessing (on the OpenCL device), then read back
 * with clvr_clustered_download.
 *
 *   bench_walk --mesh FILE [--device SPEC] [--leaf N] [--order rays|random|sorted] [--queries Q]
 *
 * Prints one markdown row per run; queries/s is one host thread, a relative
 * figure between rows of the same machine, not clvr's device speed. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Counters of the walk, incremented by the CLVR_WALK_STAT hooks of
 * kernels/locate.h, which are empty everywhere else. One thread, so a
 * plain static struct; this program's only mutable global. */
typedef struct walk_counts {
    unsigned long long tnodes, bnodes, inst, leaves, ecand, etest, hint_try, hint_hit;
} walk_counts;
static walk_counts g_walk;
#define CLVR_WALK_STAT(field) (g_walk.field++)

#include "bench_points.h"
#include "bench_util.h"
#include "bvh.h"
#include "cl_context.h"
#include "clock.h"
#include "mesh_io.h"
#include "preprocess.h"
#include "../kernels/locate.h"

int main(int argc, char **argv)
{
    const char *mesh_path = NULL, *device = NULL, *order_name = "rays";
    uint32_t leaf = 8, nq = 480000;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--mesh") && i + 1 < argc) mesh_path = argv[++i];
        else if (!strcmp(argv[i], "--device") && i + 1 < argc) device = argv[++i];
        else if (!strcmp(argv[i], "--leaf") && i + 1 < argc) leaf = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--order") && i + 1 < argc) order_name = argv[++i];
        else if (!strcmp(argv[i], "--queries") && i + 1 < argc) nq = (uint32_t)strtoul(argv[++i], NULL, 10);
        else {
            fprintf(stderr, "usage: bench_walk --mesh FILE [--device SPEC] [--leaf N] [--order rays|random|sorted] "
                            "[--queries Q]\n");
            return 2;
        }
    }
    const int order = bench_order_from_name(order_name);
    if (!mesh_path || order < 0 || leaf < 1 || leaf > 128 || nq < 1) {
        fprintf(stderr, "bench_walk: needs --mesh FILE; --order random, sorted or rays; --leaf 1..128; "
                        "--queries >= 1\n");
        return 2;
    }
    clvr_error err = {0};
    clvr_mesh m;
    if (clvr_mesh_load(mesh_path, NULL, &m, &err) != CLVR_OK) {
        fprintf(stderr, "bench_walk: %s\n", err.msg);
        return 1;
    }
    clvr_cl cl;
    if (clvr_cl_create(device, &cl, &err) != CLVR_OK) {
        fprintf(stderr, "bench_walk: %s\n", err.msg);
        return 4;
    }
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.leaf_size = leaf;
    clvr_clustered c;
    clvr_clustered_host arrays;
    memset(&arrays, 0, sizeof arrays);
    clvr_bvh_host hb;
    memset(&hb, 0, sizeof hb);
    uint8_t *ebox = NULL;
    float(*pts)[4] = NULL;
    /* The host copies of the clustered arrays (a split mesh comes back whole,
     * its instances' offsets global), under a host-built tree. */
    clvr_status s = clvr_preprocess(&cl, &m, &o, &c, &err);
    if (s == CLVR_OK) s = clvr_clustered_download(&cl, &c, &arrays, &err);
    if (s == CLVR_OK)
        s = clvr_bvh_build_host(arrays.instances, (uint32_t)c.num_instances, arrays.leaf_boxes,
                                (uint32_t)c.num_leaves, &hb, &err);
    clvr_mesh_view mv = {hb.tlas, hb.blas, arrays.instances, (const clvr_vec4 *)arrays.vertices,
                         arrays.idx16, arrays.idx32, hb.tlas_root, leaf, NULL, CLVR_VIEW_ONE_PIECE};
    if (s == CLVR_OK && !(ebox = malloc((size_t)c.num_elements * CLVR_EBOX_BYTES + 1)))
        s = clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "bench_walk: no memory for element boxes");
    if (s == CLVR_OK)
        s = clvr_bvh_element_boxes_host(&mv, (uint32_t)c.num_instances, (uint32_t)c.num_leaves, ebox, &err);
    if (s == CLVR_OK && !(pts = bench_make_points(&m, nq, order)))
        s = clvr_error_set(&err, CLVR_ERR_NO_MEMORY, "bench_walk: no memory for %u points", nq);
    if (s != CLVR_OK) {
        fprintf(stderr, "bench_walk: %s\n", err.msg);
        return 1;
    }
    mv.ebox = ebox;
    const unsigned chain = bench_order_chain(order);
    const double load = bench_load1(), t0 = clvr_clock_monotonic_s();
    uint32_t found = 0;
    for (uint32_t i = 0; i < nq; i += chain) {
        clvr_locate_hint h = clvr_locate_hint_none();
        for (uint32_t j = i; j < i + chain && j < nq; ++j) {
            float sc;
            uint32_t e;
            found += (uint32_t)clvr_locate_hinted(&mv, pts[j][0], pts[j][1], pts[j][2], &h, &sc, &e);
        }
    }
    const double t = clvr_clock_monotonic_s() - t0;
    const double q = (double)nq;
    printf("# bench_walk: %s, %llu elements, leaf clusters of %u, %u %s queries (hint per ray of %u), host reference "
           "walk, 1 thread\n",
           mesh_path, (unsigned long long)c.num_elements, leaf, nq, order_name, chain);
    printf("| mesh | order | leaf | found | top nodes | bottom nodes | instances | leaves | box-pass elements | "
           "exact tests | hint held | q/s (host, 1 thread) | load |\n");
    printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    const char *base = strrchr(mesh_path, '/');
    printf("| %s | %s | %u | %.3f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.3f | %.3g | %.2f |\n",
           base ? base + 1 : mesh_path, order_name, leaf, found / q, g_walk.tnodes / q, g_walk.bnodes / q,
           g_walk.inst / q, g_walk.leaves / q, g_walk.ecand / q, g_walk.etest / q,
           g_walk.hint_try ? (double)g_walk.hint_hit / (double)g_walk.hint_try : 0.0, q / t, load);
    free(pts);
    free(ebox);
    clvr_bvh_host_free(&hb);
    clvr_clustered_host_free(&arrays);
    clvr_clustered_release(&cl, &c);
    clvr_cl_destroy(&cl);
    clvr_mesh_free(&m);
    return 0;
}
