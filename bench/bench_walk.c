/* bench_walk.c: what a point-location walk does per query, counted on the
 * host with kernels/locate.h's own code (CLVR_WALK_STAT): nodes of the top
 * and bottom trees visited, instances entered, leaf clusters scanned,
 * elements that pass their quantized box, elements given the exact
 * containment test (barycentric; a pyramid's side planes, then Newton;
 * Newton), and how often
 * a ray's hint (clvr_locate_hinted) held the next sample, how often an
 * entry grid's hint held the point (--entry off: walks from the roots), and
 * the share of queries that the occupancy grid answered (no element there). Issue #19 asks
 * where the walk's time goes on graded meshes; counts answer that without
 * hardware counters, which the benchmark VMs do not have. The mesh is
 * clustered by the real preprocessing (on the OpenCL device), then read back
 * with clvr_clustered_download.
 *
 *   bench_walk --mesh FILE [--device SPEC] [--leaf N] [--order rays|random|sorted] [--queries Q] [--entry on|off]
 *   bench_walk --mesh FILE --per-instance [--order ...] [--queries Q]
 *   bench_walk --mesh FILE --classes [--leaf N] [--order ...] [--queries Q]
 *
 * Prints one markdown row per run; queries/s is one host thread, a relative
 * figure between rows of the same machine, not clvr's device speed.
 *
 * --per-instance asks whether a leaf size chosen per instance cluster would
 * beat the best single one (issue #19), without building it: the same
 * queries are timed one by one on builds with leaf clusters of 8, 16 and 32,
 * twice each, and every query's time goes to the chunk of
 * CLVR_WALK_CHUNK consecutive sorted elements that holds the element found
 * (the Hilbert order does not depend on the leaf size, so a chunk is the
 * same part of the mesh in every build, about one instance cluster). An
 * oracle picks the best leaf size per chunk from the first pass and is
 * scored on the second, so that picking the luckiest noise is not counted
 * as a gain. Queries that find no element keep the best single size.
 *
 * --classes asks where the time goes by kind of query: each query is
 * timed alone (clvr_locate_ex, one clock read before and after: the
 * clock's own cost is in every class) and counted in one class by what
 * its walk did: answered by the occupancy bit; found in its global hint's
 * leaf or siblings; found after that hint missed; in an occupied cell but
 * in no element. For the third class it also says how the element found
 * relates to the hint: same instance under another node, another instance
 * of the same type, another type (each type has its own curve and
 * instance clusters), or a cell without a hint. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Counters of the walk, incremented by the CLVR_WALK_STAT hooks of
 * kernels/locate.h, which are empty everywhere else. One thread, so a
 * plain static struct; this program's only mutable global. */
typedef struct walk_counts {
    unsigned long long tnodes, bnodes, inst, leaves, ecand, etest, hint_try, hint_hit, entry_try, entry_hit, global_try,
        global_hit, occ_clear;
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

/* One build of the mesh with leaf clusters of `leaf`: the host copies of the
 * clustered arrays (a split mesh comes back whole, its instances' offsets
 * global) under a host-built tree, with element boxes. */
typedef struct walk_build {
    clvr_clustered c;
    clvr_clustered_host arrays;
    clvr_bvh_host hb;
    uint8_t *ebox;
    clvr_entry_grid *grids; /* entry grids (kernels/locate.h), NULL with --entry off */
    uint32_t *cells;
    clvr_mesh_view mv;
} walk_build;


static void walk_build_free(clvr_cl *cl, walk_build *b)
{
    free(b->ebox);
    free(b->grids);
    free(b->cells);
    clvr_bvh_host_free(&b->hb);
    clvr_clustered_host_free(&b->arrays);
    clvr_clustered_release(cl, &b->c);
    memset(b, 0, sizeof *b);
}

static clvr_status walk_build_make(clvr_cl *cl, const clvr_mesh *m, uint32_t leaf, int entry, walk_build *b,
                                   clvr_error *err)
{
    memset(b, 0, sizeof *b);
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.leaf_size = leaf;
    clvr_status s = clvr_preprocess(cl, m, &o, &b->c, err);
    if (s == CLVR_OK) s = clvr_clustered_download(cl, &b->c, &b->arrays, err);
    if (s == CLVR_OK)
        s = clvr_bvh_build_host(b->arrays.instances, (uint32_t)b->c.num_instances, b->arrays.leaf_boxes,
                                (uint32_t)b->c.num_leaves, &b->hb, err);
    const clvr_mesh_view mv = {b->hb.tlas, b->hb.blas, b->arrays.instances, (const clvr_vec4 *)b->arrays.vertices,
                               b->arrays.idx16, b->arrays.idx32, b->hb.tlas_root, leaf, NULL, CLVR_VIEW_ONE_PIECE,
                               NULL, NULL};
    b->mv = mv;
    if (s == CLVR_OK && !(b->ebox = malloc((size_t)b->c.num_elements * CLVR_EBOX_BYTES + 1)))
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_walk: no memory for element boxes");
    if (s == CLVR_OK)
        s = clvr_bvh_element_boxes_host(&b->mv, (uint32_t)b->c.num_instances, (uint32_t)b->c.num_leaves, b->ebox,
                                        err);
    b->mv.ebox = b->ebox;
    const uint32_t ninst = (uint32_t)b->c.num_instances;
    uint32_t nwords = 0;
    if (s == CLVR_OK && entry && !(b->grids = malloc(((size_t)ninst + 1u) * sizeof *b->grids)))
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_walk: no memory for entry grids");
    if (s == CLVR_OK && entry) s = clvr_entry_grids_layout(b->arrays.instances, ninst, 0, b->grids, &nwords, err);
    if (s == CLVR_OK && entry && !(b->cells = malloc((size_t)nwords * sizeof *b->cells)))
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_walk: no memory for %u entry grid words", nwords);
    if (s == CLVR_OK && entry) s = clvr_entry_cells_host(&b->mv, ninst, b->grids, nwords, b->cells, err);
    b->mv.entry_grids = b->grids;
    b->mv.entry_cells = b->cells;
    if (s != CLVR_OK) walk_build_free(cl, b);
    return s;
}

/* Sorted elements per chunk of --per-instance: the middle of the 30k-60k
 * elements of an instance cluster. */
#define CLVR_WALK_CHUNK 32768u
#define WALK_SIZES 3

/* --per-instance: per-chunk times of the same queries on builds with leaf
 * clusters of 8, 16 and 32 (see the file's comment). */
static int per_instance(clvr_cl *cl, const clvr_mesh *m, const char *mesh_path, float (*pts)[4], uint32_t nq,
                        const char *order_name, unsigned chain, int entry)
{
    static const uint32_t sizes[WALK_SIZES] = {8u, 16u, 32u};
    const uint32_t nchunk = (uint32_t)((clvr_mesh_num_elements(m) + CLVR_WALK_CHUNK - 1) / CLVR_WALK_CHUNK) + 1u; /* last: not found */
    double *t = calloc((size_t)WALK_SIZES * 2u * nchunk, sizeof *t);
    uint32_t *hits = calloc(nchunk, sizeof *hits);
    if (!t || !hits) {
        free(t);
        free(hits);
        fprintf(stderr, "bench_walk: out of memory\n");
        return 1;
    }
    const double load = bench_load1();
    for (int k = 0; k < WALK_SIZES; ++k) {
        walk_build b;
        clvr_error err = {0};
        if (walk_build_make(cl, m, sizes[k], entry, &b, &err) != CLVR_OK) {
            fprintf(stderr, "bench_walk: %s\n", err.msg);
            free(t);
            free(hits);
            return 1;
        }
        for (int pass = 0; pass < 2; ++pass) {
            double *tk = t + ((size_t)k * 2u + (size_t)pass) * nchunk;
            for (uint32_t i = 0; i < nq; i += chain) {
                clvr_locate_hint h = clvr_locate_hint_none();
                for (uint32_t j = i; j < i + chain && j < nq; ++j) {
                    float sc;
                    uint32_t e;
                    const double q0 = clvr_clock_monotonic_s();
                    const int ok = clvr_locate_hinted(&b.mv, pts[j][0], pts[j][1], pts[j][2], &h, &sc, &e);
                    const double dt = clvr_clock_monotonic_s() - q0;
                    const uint32_t ch = ok ? e / CLVR_WALK_CHUNK : nchunk - 1u;
                    tk[ch] += dt;
                    if (k == 0 && pass == 0) hits[ch]++;
                }
            }
        }
        walk_build_free(cl, &b);
    }
    /* Totals per size (second pass), and the oracle: per chunk, the size
     * that was fastest in the first pass, timed by the second. */
    double total[WALK_SIZES] = {0}, oracle = 0.0;
    int best = 0;
    for (int k = 0; k < WALK_SIZES; ++k) {
        for (uint32_t ch = 0; ch < nchunk; ++ch) total[k] += t[((size_t)k * 2u + 1u) * nchunk + ch];
        if (total[k] < total[best]) best = k;
    }
    uint32_t picks[WALK_SIZES] = {0}, used = 0;
    for (uint32_t ch = 0; ch < nchunk; ++ch) {
        int pick = best;
        if (ch + 1u < nchunk && hits[ch]) {
            for (int k = 0; k < WALK_SIZES; ++k)
                if (t[(size_t)k * 2u * nchunk + ch] < t[(size_t)pick * 2u * nchunk + ch]) pick = k;
            picks[pick]++;
            used++;
        }
        oracle += t[((size_t)pick * 2u + 1u) * nchunk + ch];
    }
    /* Bookkeeping the smoke test checks: every query counted once, every
     * total a positive time, the oracle between the chunks' best and worst. */
    uint64_t counted = 0;
    double lo = 0.0, hi = 0.0;
    for (uint32_t ch = 0; ch < nchunk; ++ch) {
        counted += hits[ch];
        double a = INFINITY, z = 0.0;
        for (int k = 0; k < WALK_SIZES; ++k) {
            const double v = t[((size_t)k * 2u + 1u) * nchunk + ch];
            a = v < a ? v : a;
            z = v > z ? v : z;
        }
        lo += a;
        hi += z;
    }
    int bad = counted != nq || !(oracle >= lo * (1 - 1e-9) && oracle <= hi * (1 + 1e-9));
    for (int k = 0; k < WALK_SIZES; ++k) bad |= !(total[k] > 0.0 && isfinite(total[k]));
    if (bad) {
        fprintf(stderr, "bench_walk: per-instance bookkeeping is wrong: %llu of %u queries counted, oracle %g outside "
                        "[%g, %g] or a total not positive\n",
                (unsigned long long)counted, nq, oracle, lo, hi);
        free(t);
        free(hits);
        return 3;
    }
    const char *base = strrchr(mesh_path, '/');
    printf("# bench_walk --per-instance: %s, %llu elements, %u %s queries (hint per ray of %u), chunks of %u sorted "
           "elements, host reference walk, 1 thread, each query timed\n",
           mesh_path, (unsigned long long)clvr_mesh_num_elements(m), nq, order_name, chain, CLVR_WALK_CHUNK);
    printf("| mesh | order | s, leaf 8 | s, leaf 16 | s, leaf 32 | best single | oracle per chunk | oracle / best | "
           "chunks picking 8 / 16 / 32 | load |\n");
    printf("|---|---|---:|---:|---:|---:|---:|---:|---|---:|\n");
    printf("| %s | %s | %.3f | %.3f | %.3f | %u | %.3f | %.3f | %u / %u / %u of %u | %.2f |\n", base ? base + 1 : mesh_path,
           order_name, total[0], total[1], total[2], sizes[best], oracle, oracle / total[best], picks[0], picks[1],
           picks[2], used, load);
    free(t);
    free(hits);
    return 0;
}

/* --classes (see the file's comment): one row per class. Returns 0, or 3
 * when the bookkeeping is wrong (the smoke test's check). */
enum { WALK_CLEAR, WALK_HINT_HELD, WALK_AFTER_MISS, WALK_EMPTY, WALK_CLASSES };
enum { WALK_MISS_OTHER_NODE, WALK_MISS_OTHER_INSTANCE, WALK_MISS_OTHER_TYPE, WALK_MISS_NO_HINT, WALK_MISSES };
static int walk_classes(const walk_build *b, const char *mesh_path, float (*pts)[4], uint32_t nq,
                        const char *order_name, uint32_t leaf)
{
    static const char *names[WALK_CLASSES] = {"occupancy bit clear", "global hint held", "found after the hint missed",
                                              "occupied, in no element"};
    double t[WALK_CLASSES] = {0};
    unsigned long long n[WALK_CLASSES] = {0}, tn[WALK_CLASSES] = {0}, bn[WALK_CLASSES] = {0}, lv[WALK_CLASSES] = {0},
                       et[WALK_CLASSES] = {0}, miss[WALK_MISSES] = {0};
    const clvr_mesh_view *mv = &b->mv;
    const clvr_entry_grid og = mv->entry_grids[0];
    const int hinted = clvr_global_hints_on(&og);
    const double load = bench_load1();
    for (uint32_t j = 0; j < nq; ++j) {
        const walk_counts before = g_walk;
        float sc;
        uint32_t e, inst, leaf_found;
        const double t0 = clvr_clock_monotonic_s();
        const int found = clvr_locate_ex(mv, pts[j][0], pts[j][1], pts[j][2], CLVR_LOCATE_COHERENT, CLVR_BVH_NOT_FOUND,
                                         CLVR_BVH_NOT_FOUND, &sc, &e, &inst, &leaf_found);
        const double dt = clvr_clock_monotonic_s() - t0;
        const int k = g_walk.occ_clear > before.occ_clear ? WALK_CLEAR
                      : g_walk.global_hit > before.global_hit ? WALK_HINT_HELD
                      : found ? WALK_AFTER_MISS
                              : WALK_EMPTY;
        t[k] += dt;
        ++n[k];
        tn[k] += g_walk.tnodes - before.tnodes;
        bn[k] += g_walk.bnodes - before.bnodes;
        lv[k] += g_walk.leaves - before.leaves;
        et[k] += g_walk.etest - before.etest;
        if (k != WALK_AFTER_MISS) continue;
        /* the hint word of the point's cell, as clvr_locate_ex reads it */
        uint32_t c[3], w = CLVR_BVH_NOT_FOUND;
        clvr_occupancy_cell(&og, pts[j][0], pts[j][1], pts[j][2], c);
        if (hinted)
            w = mv->entry_cells[clvr_global_hints_first(&og) +
                                clvr_global_hint_cell(&og, clvr_global_hints_shift(&og), c)];
        if (w == CLVR_BVH_NOT_FOUND) {
            ++miss[WALK_MISS_NO_HINT];
            continue;
        }
        const uint32_t gi = w >> CLVR_GLOBAL_HINT_LEAF_BITS;
        const int where = gi == inst ? WALK_MISS_OTHER_NODE
                          : mv->instances[gi].type == mv->instances[inst].type ? WALK_MISS_OTHER_INSTANCE
                                                                               : WALK_MISS_OTHER_TYPE;
        ++miss[where];
    }
    double total = 0.0;
    unsigned long long counted = 0, misses = 0;
    for (int k = 0; k < WALK_CLASSES; ++k) {
        total += t[k];
        counted += n[k];
    }
    for (int k = 0; k < WALK_MISSES; ++k) misses += miss[k];
    if (counted != nq || misses != n[WALK_AFTER_MISS] || !(total > 0.0)) {
        fprintf(stderr, "bench_walk: classes bookkeeping is wrong: %llu of %u queries counted, %llu of %llu misses "
                        "placed, total %g s\n",
                counted, nq, misses, n[WALK_AFTER_MISS], total);
        return 3;
    }
    const char *base = strrchr(mesh_path, '/');
    printf("# bench_walk --classes: %s, %llu elements, leaf clusters of %u, %u %s queries, host reference walk, 1 "
           "thread, each query timed (global hints %s)\n",
           mesh_path, (unsigned long long)b->c.num_elements, leaf, nq, order_name, hinted ? "on" : "off");
    printf("| mesh | order | class | share of queries | share of time | ns per query | top nodes | bottom nodes | "
           "leaves | exact tests | load |\n");
    printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int k = 0; k < WALK_CLASSES; ++k) {
        const double q = n[k] ? (double)n[k] : 1.0;
        printf("| %s | %s | %s | %.3f | %.3f | %.0f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", base ? base + 1 : mesh_path,
               order_name, names[k], n[k] / (double)nq, t[k] / total, 1e9 * t[k] / q, tn[k] / q, bn[k] / q, lv[k] / q,
               et[k] / q, load);
    }
    const double mq = misses ? (double)misses : 1.0;
    printf("\nfound after the hint missed (%llu): the element in the hint's instance under another node %.3f, in "
           "another instance of the same type %.3f, of another type %.3f; no hint in the cell %.3f\n",
           misses, miss[WALK_MISS_OTHER_NODE] / mq, miss[WALK_MISS_OTHER_INSTANCE] / mq,
           miss[WALK_MISS_OTHER_TYPE] / mq, miss[WALK_MISS_NO_HINT] / mq);
    return 0;
}

int main(int argc, char **argv)
{
    const char *mesh_path = NULL, *device = NULL, *order_name = "rays";
    uint32_t leaf = 8, nq = 480000;
    int per_inst = 0, entry = 1, by_class = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--mesh") && i + 1 < argc) mesh_path = argv[++i];
        else if (!strcmp(argv[i], "--device") && i + 1 < argc) device = argv[++i];
        else if (!strcmp(argv[i], "--leaf") && i + 1 < argc) leaf = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--order") && i + 1 < argc) order_name = argv[++i];
        else if (!strcmp(argv[i], "--queries") && i + 1 < argc) nq = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--per-instance")) per_inst = 1;
        else if (!strcmp(argv[i], "--classes")) by_class = 1;
        else if (!strcmp(argv[i], "--entry") && i + 1 < argc &&
                 (!strcmp(argv[i + 1], "on") || !strcmp(argv[i + 1], "off")))
            entry = !strcmp(argv[++i], "on");
        else {
            fprintf(stderr, "usage: bench_walk --mesh FILE [--device SPEC] [--leaf N] [--order rays|random|sorted] "
                            "[--queries Q] [--per-instance | --classes] [--entry on|off]\n");
            return 2;
        }
    }
    const int order = bench_order_from_name(order_name);
    if (!mesh_path || order < 0 || leaf < 1 || leaf > 128 || nq < 1 || (by_class && (per_inst || !entry))) {
        fprintf(stderr, "bench_walk: needs --mesh FILE; --order random, sorted or rays; --leaf 1..128; "
                        "--queries >= 1; --classes with the entry grids and without --per-instance\n");
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
        clvr_mesh_free(&m);
        return 4;
    }
    const unsigned chain = bench_order_chain(order);
    float(*pts)[4] = bench_make_points(&m, nq, order);
    if (!pts) {
        fprintf(stderr, "bench_walk: no memory for %u points\n", nq);
        clvr_cl_destroy(&cl);
        clvr_mesh_free(&m);
        return 1;
    }
    int rc = 0;
    if (per_inst) {
        rc = per_instance(&cl, &m, mesh_path, pts, nq, order_name, chain, entry);
    } else {
        walk_build b;
        if (walk_build_make(&cl, &m, leaf, entry, &b, &err) != CLVR_OK) {
            fprintf(stderr, "bench_walk: %s\n", err.msg);
            rc = 1;
        } else if (by_class) {
            rc = walk_classes(&b, mesh_path, pts, nq, order_name, leaf);
            walk_build_free(&cl, &b);
        } else {
            const double load = bench_load1(), t0 = clvr_clock_monotonic_s();
            uint32_t found = 0;
            for (uint32_t i = 0; i < nq; i += chain) {
                clvr_locate_hint h = clvr_locate_hint_none();
                for (uint32_t j = i; j < i + chain && j < nq; ++j) {
                    float sc;
                    uint32_t e;
                    found += (uint32_t)clvr_locate_hinted(&b.mv, pts[j][0], pts[j][1], pts[j][2], &h, &sc, &e);
                }
            }
            const double t = clvr_clock_monotonic_s() - t0;
            const double q = (double)nq;
            printf("# bench_walk: %s, %llu elements, leaf clusters of %u, %u %s queries (hint per ray of %u), host "
                   "reference walk, 1 thread\n",
                   mesh_path, (unsigned long long)b.c.num_elements, leaf, nq, order_name, chain);
            printf("| mesh | order | leaf | found | top nodes | bottom nodes | instances | leaves | box-pass elements | "
                   "exact tests | hint held | entry hint held | global hint held | occupancy clear | q/s (host, 1 thread) | "
                   "load |\n");
            printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
            const char *base = strrchr(mesh_path, '/');
            printf("| %s | %s | %u | %.3f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.3f | %.3f | %.3f | %.3f | %.3g | "
                   "%.2f |\n",
                   base ? base + 1 : mesh_path, order_name, leaf, found / q, g_walk.tnodes / q, g_walk.bnodes / q,
                   g_walk.inst / q, g_walk.leaves / q, g_walk.ecand / q, g_walk.etest / q,
                   g_walk.hint_try ? (double)g_walk.hint_hit / (double)g_walk.hint_try : 0.0,
                   g_walk.entry_try ? (double)g_walk.entry_hit / (double)g_walk.entry_try : 0.0,
                   g_walk.global_try ? (double)g_walk.global_hit / (double)g_walk.global_try : 0.0, g_walk.occ_clear / q,
                   q / t, load);
            walk_build_free(&cl, &b);
        }
    }
    free(pts);
    clvr_cl_destroy(&cl);
    clvr_mesh_free(&m);
    return rc;
}
