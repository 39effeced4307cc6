/* bench_preprocess: elements/s of every preprocessing stage on a generated
 * hex grid of about N elements and/or on mesh files, against a tuned
 * plain-C 2-thread LSD radix sort (pthreads, 8-bit digits, constant digits
 * skipped) and a memcpy of the same key array; then the paper's Table 3:
 * Hilbert clustering (keys + sort + gather + cluster boxes) against a
 * conventional BVH build over the same element boxes by Embree 3
 * (rtcBuildBVH, quality LOW and MEDIUM), at 16 and 100,000 elements per
 * cluster. Usage:
 *   bench_preprocess [--device SPEC] [--json FILE] [--elements N[,N...]] [--mesh FILE]... [--repeat R]
 * Prints the device, driver and Markdown tables per input; --json writes the
 * same numbers. Stage timings are OpenCL event profiling (device seconds)
 * of the run with the least clustering time after a warm-up run, the runs
 * sharing one workspace (clvr_preprocess_ws) and recycling their results
 * into it, so that, like the C sort's arrays, their scratch and output
 * memory is touched already; a run without a
 * workspace (fresh scratch, as a single `clvr` run) is printed too, beside
 * a C sort that allocates its scratch inside the timing. The C baselines
 * and Embree take the best of R runs. Embree is optional at build time
 * (CLVR_HAVE_EMBREE); without it the Table 3 rows say "not installed". The
 * machine's load average is printed with each table: on a shared machine,
 * rerun when it is above the core count. */
#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"
#include "clock.h"
#include "bounds.h"
#include "mesh_io.h"
#include "preprocess_stages.h"
#ifdef CLVR_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

static double loadavg(void)
{
    double l = -1.0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1) l = -1.0;
        fclose(f);
    }
    return l;
}

/* Structured hex grid n^3 with a smooth scalar. */
static int make_hexes(clvr_mesh *m, uint32_t n, clvr_error *err)
{
    uint64_t cells[4] = {0, 0, 0, (uint64_t)n * n * n};
    uint64_t nv = (uint64_t)(n + 1) * (n + 1) * (n + 1);
    if (clvr_mesh_alloc(m, nv, cells, err) != CLVR_OK) return 1;
    for (uint64_t k = 0, v = 0; k <= n; ++k)
        for (uint64_t j = 0; j <= n; ++j)
            for (uint64_t i = 0; i <= n; ++i, ++v) {
                float x = (float)i / n, y = (float)j / n, z = (float)k / n;
                m->positions[3 * v] = x;
                m->positions[3 * v + 1] = y;
                m->positions[3 * v + 2] = z;
                m->scalars[v] = sinf(6 * x) * cosf(4 * y) + z;
            }
    uint32_t *p = m->indices[3];
    const uint64_t s = n + 1;
    for (uint64_t k = 0; k < n; ++k)
        for (uint64_t j = 0; j < n; ++j)
            for (uint64_t i = 0; i < n; ++i) {
                uint64_t b = (k * s + j) * s + i;
                uint32_t h[8] = {(uint32_t)b, (uint32_t)(b + 1), (uint32_t)(b + s + 1), (uint32_t)(b + s),
                                 (uint32_t)(b + s * s), (uint32_t)(b + s * s + 1), (uint32_t)(b + s * s + s + 1),
                                 (uint32_t)(b + s * s + s)};
                memcpy(p, h, sizeof h);
                p += 8;
            }
    clvr_mesh_update_ranges(m);
    return 0;
}

/* ---- plain-C multi-threaded LSD radix sort (bench_cpu_threads threads):
 * each thread histograms and scatters its share; offsets are combined in
 * thread order so the sort stays stable. */
typedef struct radix_job {
    const uint64_t *ks;
    const uint32_t *vs;
    uint64_t *kd;
    uint32_t *vd;
    uint64_t b, e;
    uint32_t shift;
    uint64_t hist[256];
    uint64_t off[256];
    int phase;
} radix_job;

static void *radix_worker(void *arg)
{
    radix_job *j = arg;
    if (j->phase == 0) {
        memset(j->hist, 0, sizeof j->hist);
        for (uint64_t i = j->b; i < j->e; ++i) ++j->hist[(j->ks[i] >> j->shift) & 255];
    } else {
        uint64_t off[256];
        memcpy(off, j->off, sizeof off);
        for (uint64_t i = j->b; i < j->e; ++i) {
            uint64_t k = j->ks[i];
            uint64_t p = off[(k >> j->shift) & 255]++;
            j->kd[p] = k;
            j->vd[p] = j->vs[i];
        }
    }
    return NULL;
}

/* One phase of every job: jobs 1.. on threads, job 0 on the caller's. */
static void radix_phase(radix_job *job, int nt)
{
    pthread_t th[64];
    for (int t = 1; t < nt; ++t) pthread_create(&th[t], NULL, radix_worker, &job[t]);
    radix_worker(&job[0]);
    for (int t = 1; t < nt; ++t) pthread_join(th[t], NULL);
}

static void c_radix2(uint64_t *keys, uint32_t *vals, uint64_t *kt, uint32_t *vt, uint64_t n)
{
    uint64_t a = ~0ull, o = 0;
    for (uint64_t i = 0; i < n; ++i) { a &= keys[i]; o |= keys[i]; }
    uint64_t *ks = keys, *kd = kt;
    uint32_t *vs = vals, *vd = vt;
    const int nt = bench_cpu_threads();
    radix_job job[64];
    for (uint32_t shift = 0; shift < 64; shift += 8) {
        if ((((a ^ o) >> shift) & 255) == 0) continue;
        for (int t = 0; t < nt; ++t) {
            job[t].ks = ks; job[t].vs = vs; job[t].kd = kd; job[t].vd = vd; job[t].shift = shift;
            job[t].b = n * (uint64_t)t / (uint64_t)nt; job[t].e = n * (uint64_t)(t + 1) / (uint64_t)nt; job[t].phase = 0;
        }
        radix_phase(job, nt);
        uint64_t acc = 0;
        for (int d = 0; d < 256; ++d)
            for (int t = 0; t < nt; ++t) { job[t].off[d] = acc; acc += job[t].hist[d]; }
        for (int t = 0; t < nt; ++t) job[t].phase = 1;
        radix_phase(job, nt);
        uint64_t *tk = ks; ks = kd; kd = tk;
        uint32_t *tv = vs; vs = vd; vd = tv;
    }
    if (ks != keys) { memcpy(keys, ks, n * 8); memcpy(vals, vs, n * 4); }
}

/* ---- Embree 3 BVH build over the element boxes (Table 3's "conventional
 * BVH"). Nodes and leaves come from Embree's thread-local allocator; the
 * leaves only count their primitives, as building them is what is timed. */
#ifdef CLVR_HAVE_EMBREE
typedef struct eb_node {
    void *child[2];
    struct RTCBounds bounds[2];
} eb_node;

static void *eb_create_node(RTCThreadLocalAllocator alloc, unsigned int n, void *user)
{
    (void)n; (void)user;
    eb_node *nd = rtcThreadLocalAlloc(alloc, sizeof(eb_node), 16);
    nd->child[0] = nd->child[1] = NULL;
    return nd;
}

static void eb_set_children(void *node, void **children, unsigned int n, void *user)
{
    (void)user;
    for (unsigned int i = 0; i < n && i < 2; ++i) ((eb_node *)node)->child[i] = children[i];
}

static void eb_set_bounds(void *node, const struct RTCBounds **b, unsigned int n, void *user)
{
    (void)user;
    for (unsigned int i = 0; i < n && i < 2; ++i) ((eb_node *)node)->bounds[i] = *b[i];
}

static void *eb_create_leaf(RTCThreadLocalAllocator alloc, const struct RTCBuildPrimitive *prims, size_t n, void *user)
{
    (void)prims; (void)user;
    size_t *leaf = rtcThreadLocalAlloc(alloc, sizeof(size_t), 16);
    *leaf = n;
    return leaf;
}

/* Seconds of the best of `repeat` builds (prims copied back before each,
 * as the builder reorders them); -1 on failure. */
static double embree_build(RTCDevice dev, const struct RTCBuildPrimitive *src, struct RTCBuildPrimitive *work, size_t n,
                           enum RTCBuildQuality q, unsigned int leaf, int repeat)
{
    double best = -1.0;
    for (int r = 0; r < repeat; ++r) {
        memcpy(work, src, n * sizeof *work);
        RTCBVH bvh = rtcNewBVH(dev);
        struct RTCBuildArguments a = rtcDefaultBuildArguments();
        a.byteSize = sizeof a;
        a.buildFlags = RTC_BUILD_FLAG_NONE;
        a.buildQuality = q;
        a.maxBranchingFactor = 2;
        a.maxDepth = 1024;
        a.sahBlockSize = 1;
        a.minLeafSize = leaf;
        a.maxLeafSize = leaf;
        a.traversalCost = 1.0f;
        a.intersectionCost = 1.0f;
        a.bvh = bvh;
        a.primitives = work;
        a.primitiveCount = n;
        a.primitiveArrayCapacity = n;
        a.createNode = eb_create_node;
        a.setNodeChildren = eb_set_children;
        a.setNodeBounds = eb_set_bounds;
        a.createLeaf = eb_create_leaf;
        a.splitPrimitive = NULL;
        a.buildProgress = NULL;
        a.userPtr = NULL;
        double t0 = clvr_clock_monotonic_s();
        void *root = rtcBuildBVH(&a);
        double t1 = clvr_clock_monotonic_s();
        rtcReleaseBVH(bvh);
        if (!root || rtcGetDeviceError(dev) != RTC_ERROR_NONE) return -1.0;
        if (best < 0 || t1 - t0 < best) best = t1 - t0;
    }
    return best;
}
#endif

/* Seconds, or null where there are none (< 0: a failed or impossible build,
 * or Embree absent), never the -1 that stands for it here. */
static void json_secs(FILE *f, const char *key, double s, const char *sep)
{
    if (s < 0) fprintf(f, "\"%s\": null%s", key, sep);
    else fprintf(f, "\"%s\": %.6f%s", key, s, sep);
}

/* The mesh's index lists concatenated in type order (the layout of clvr_pp_ref_keys). */
static uint32_t *concat_indices(const clvr_mesh *m, const clvr_pp_layout *L)
{
    uint32_t *idx = malloc((L->num_slots ? L->num_slots : 1) * 4);
    if (!idx) return NULL;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        if (L->count[t]) memcpy(idx + L->slot[t], m->indices[t], L->count[t] * clvr_cell_vertex_count(t) * 4);
    return idx;
}

/* Hilbert clustering as the issue counts it: keys + sort + gather + cluster
 * boxes, the boxes being stage `boxes` (leaf boxes, or the sampling
 * clusters' boxes for Table 3's cluster sizes). */
static double clustering_s(const double *stage, int boxes)
{
    return stage[CLVR_PP_STAGE_KEYS] + stage[CLVR_PP_STAGE_SORT] + stage[CLVR_PP_STAGE_GATHER] + stage[boxes];
}

/* Best of `repeat` preprocessing runs that share one workspace
 * (clvr_preprocess_ws), so their scratch memory is already touched, as the
 * C sort's arrays are: *best keeps the result of the run with the least
 * Hilbert clustering time (the figure compared with the C sort, whose
 * best of R is taken too), *best_wall the least wall time of any of them.
 * Before them: a warm-up run (kernel builds, driver caches), then, when
 * cold is not NULL, one run without a workspace, as `clvr` preprocesses:
 * every scratch buffer fresh memory, freed when dead; cold receives its
 * stage times. Then one run fills the workspace (not counted). */
static int best_run(clvr_cl *cl, const clvr_mesh *m, const clvr_preprocess_options *o, int repeat, int boxes,
                    clvr_clustered *best, double *best_wall, double *cold, clvr_error *err)
{
    double best_cl = 1e30;
    clvr_pp_workspace ws = {0};
    memset(best, 0, sizeof *best);
    *best_wall = 1e30;
    for (int r = -2; r <= repeat; ++r) {
        if (r == -1 && !cold) continue;
        clvr_clustered c = {0};
        if (clvr_preprocess_ws(cl, m, o, r < 0 ? NULL : &ws, &c, err) != CLVR_OK) {
            clvr_clustered_release(cl, best);
            clvr_pp_workspace_release(cl, &ws);
            return 1;
        }
        if (r == -1) memcpy(cold, c.stage_s, sizeof c.stage_s);
        if (r > 0 && c.wall_s - c.build_s < *best_wall) *best_wall = c.wall_s - c.build_s;
        /* Results not kept go back to the workspace, so that, like the C
         * sort's, the next run's output arrays are touched memory too. */
        if (r > 0 && clustering_s(c.stage_s, boxes) < best_cl) {
            best_cl = clustering_s(c.stage_s, boxes);
            clvr_pp_workspace_recycle(cl, &ws, best);
            *best = c;
        } else if (r >= 0) clvr_pp_workspace_recycle(cl, &ws, &c);
        else clvr_clustered_release(cl, &c);
    }
    clvr_pp_workspace_release(cl, &ws);
    return 0;
}

typedef struct bench_ctx {
    clvr_cl *cl;
    int repeat;
    FILE *jf;
    int first_run;
#ifdef CLVR_HAVE_EMBREE
    RTCDevice embree;
#endif
} bench_ctx;

static int run_case(bench_ctx *bc, const char *name, const clvr_mesh *m)
{
    clvr_cl *cl = bc->cl;
    clvr_error err = {0};
    const int repeat = bc->repeat;
    const uint64_t N = clvr_mesh_num_elements(m);
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    clvr_clustered keep = {0};
    double load0 = loadavg();
    double cold[CLVR_PP_STAGE_COUNT], best_wall = 0;
    if (best_run(cl, m, &o, repeat, CLVR_PP_STAGE_LEAVES, &keep, &best_wall, cold, &err)) { fprintf(stderr, "bench_preprocess: %s\n", err.msg); return 1; }
    double stage[CLVR_PP_STAGE_COUNT];
    memcpy(stage, keep.stage_s, sizeof stage);
    /* C baselines on the same keys (the host reference computes them bit-identically). */
    clvr_pp_layout L;
    clvr_pp_layout_make(&L, m->num_cells);
    clvr_box b;
    clvr_pp_ref_bounds(m->positions, m->scalars, m->num_vertices, &b);
    uint32_t *idx = concat_indices(m, &L);
    uint64_t *keys = malloc(N * 8), *k2 = malloc(N * 8), *kt = malloc(N * 8);
    uint32_t *vals = malloc(N * 4), *v2 = malloc(N * 4), *vt = malloc(N * 4);
    if (!idx || !keys || !k2 || !kt || !vals || !v2 || !vt) {
        fprintf(stderr, "bench_preprocess: out of host memory for the C baselines\n");
        free(idx); free(keys); free(k2); free(kt); free(vals); free(v2); free(vt);
        clvr_clustered_release(cl, &keep);
        return 1;
    }
    clvr_pp_ref_keys(m->positions, idx, &L, &b, 0, 0, keys, vals);
    double t_radix = 1e30, t_memcpy = 1e30, t_radix_cold = 1e30;
    for (int r = 0; r < repeat; ++r) {
        memcpy(k2, keys, N * 8);
        memcpy(v2, vals, N * 4);
        double t0 = clvr_clock_monotonic_s();
        c_radix2(k2, v2, kt, vt, N);
        double t1 = clvr_clock_monotonic_s();
        if (t1 - t0 < t_radix) t_radix = t1 - t0;
        /* A baseline is a figure only when it sorts: keys in order, and
         * stable (ties keep their element order, which vals hold). */
        for (uint64_t i = 1; i < N; ++i)
            if (k2[i - 1] > k2[i] || (k2[i - 1] == k2[i] && v2[i - 1] > v2[i])) {
                fprintf(stderr, "bench_preprocess: the C radix sort's output is out of order at %" PRIu64 "\n", i);
                free(idx); free(keys); free(k2); free(kt); free(vals); free(v2); free(vt);
                clvr_clustered_release(cl, &keep);
                return 1;
            }
        t0 = clvr_clock_monotonic_s();
        memcpy(kt, keys, N * 8);
        t1 = clvr_clock_monotonic_s();
        if (t1 - t0 < t_memcpy) t_memcpy = t1 - t0;
        /* The same sort with its scratch allocated inside the timing: fresh
         * pages (glibc maps blocks this big anew), the counterpart of the
         * device's cold run. */
        memcpy(k2, keys, N * 8);
        memcpy(v2, vals, N * 4);
        t0 = clvr_clock_monotonic_s();
        uint64_t *fk = malloc(N * 8);
        uint32_t *fv = malloc(N * 4);
        if (fk && fv) c_radix2(k2, v2, fk, fv, N);
        t1 = clvr_clock_monotonic_s();
        free(fk);
        free(fv);
        if (fk && fv && t1 - t0 < t_radix_cold) t_radix_cold = t1 - t0;
    }
    const double hilbert = clustering_s(stage, CLVR_PP_STAGE_LEAVES);
    const double hilbert_cold = clustering_s(cold, CLVR_PP_STAGE_LEAVES);
    double dev_total = 0;
    for (int s = 0; s < CLVR_PP_STAGE_COUNT; ++s) dev_total += stage[s];
    printf("\n### %s: %" PRIu64 " elements (%" PRIu64 " tets, %" PRIu64 " pyramids, %" PRIu64 " wedges, %" PRIu64
           " hexes), %" PRIu64 " vertices; load average %.2f\n\n| stage | seconds | Melements/s |\n|---|---:|---:|\n",
           name, N, m->num_cells[0], m->num_cells[1], m->num_cells[2], m->num_cells[3], m->num_vertices, load0);
    for (int s = 0; s < CLVR_PP_STAGE_COUNT; ++s)
        printf("| %s | %.4f | %.1f |\n", clvr_pp_stage_name(s), stage[s], stage[s] > 0 ? N / stage[s] / 1e6 : 0.0);
    printf("| **device total** | %.4f | %.1f |\n", dev_total, N / dev_total / 1e6);
    printf("| **wall (no build)** | %.4f | %.1f |\n", best_wall, N / best_wall / 1e6);
    printf("| kernel build (not in wall) | %.4f | |\n", keep.build_s);
    printf("| Hilbert clustering (keys+sort+gather+leaves) | %.4f | %.1f |\n", hilbert, N / hilbert / 1e6);
    printf("| C radix sort, %d threads | %.4f | %.1f |\n", bench_cpu_threads(), t_radix, N / t_radix / 1e6);
    printf("| memcpy of the keys | %.4f | %.1f |\n", t_memcpy, N / t_memcpy / 1e6);
    printf("| fresh scratch (a single clvr run): Hilbert clustering | %.4f | %.1f |\n", hilbert_cold,
           N / hilbert_cold / 1e6);
    printf("| fresh scratch (allocated inside the timing): C radix sort | %.4f | %.1f |\n", t_radix_cold,
           N / t_radix_cold / 1e6);
    printf("\nratios: device sort / C radix = %.2f; Hilbert clustering / C radix = %.2f (goal <= 2); "
           "C radix / memcpy = %.1f; wall %.2f s (goal < 2 s at 10M)\n"
           "fresh scratch on both sides (allocated and first touched inside the timing): Hilbert clustering / C "
           "radix = %.2f\n",
           stage[CLVR_PP_STAGE_SORT] / t_radix, hilbert / t_radix, t_radix / t_memcpy, best_wall,
           hilbert_cold / t_radix_cold);
    printf("memory: vertices %.1f MB -> %.1f MB, indices %.1f MB -> %.1f MB (%.2f), %" PRIu64
           " instances (avg %.0f elements), %" PRIu64 " leaves\n",
           keep.bytes_vertices_before / 1e6, keep.bytes_vertices_after / 1e6, keep.bytes_indices_before / 1e6,
           keep.bytes_indices_after / 1e6, (double)keep.bytes_indices_after / (double)keep.bytes_indices_before,
           keep.num_instances, keep.avg_instance_elements, keep.num_leaves);
    clvr_clustered_release(cl, &keep);

    /* ---- Table 3: Hilbert clustering at 16 and 100k elements per cluster
     * (keys + sort + gather + boxes of consecutive runs of that many sorted
     * elements, i.e. the sampling-cluster kernel with that size) against
     * Embree's builder over the same element boxes. */
    const uint32_t csize[2] = {16, 100000};
    double hil[2] = {-1, -1}, emb[2][2] = {{-1, -1}, {-1, -1}}, t_boxes = -1;
    for (int c = 0; c < 2; ++c) {
        clvr_preprocess_options oc = o;
        oc.sampling_size = csize[c];
        clvr_clustered r = {0};
        double wall_c = 0;
        if (best_run(cl, m, &oc, repeat, CLVR_PP_STAGE_SAMPLING, &r, &wall_c, NULL, &err) == 0) {
            hil[c] = clustering_s(r.stage_s, CLVR_PP_STAGE_SAMPLING);
            clvr_clustered_release(cl, &r);
        } else fprintf(stderr, "bench_preprocess: %s\n", err.msg);
    }
#ifdef CLVR_HAVE_EMBREE
    struct RTCBuildPrimitive *prims = malloc(N * sizeof *prims), *work = malloc(N * sizeof *work);
    if (bc->embree && prims && work) {
        double t0 = clvr_clock_monotonic_s();
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            const uint32_t vpe = clvr_cell_vertex_count(t);
            for (uint64_t e = 0; e < L.count[t]; ++e) {
                float lo[3], hi[3];
                clvr_pp_element_box(m->positions, idx + L.slot[t] + e * vpe, vpe, lo, hi);
                struct RTCBuildPrimitive *p = &prims[L.first[t] + e];
                p->lower_x = lo[0]; p->lower_y = lo[1]; p->lower_z = lo[2]; p->geomID = 0;
                p->upper_x = hi[0]; p->upper_y = hi[1]; p->upper_z = hi[2];
                p->primID = (unsigned int)(L.first[t] + e);
            }
        }
        t_boxes = clvr_clock_monotonic_s() - t0;
        /* rtcBuildBVH accepts leaves of at most RTC_BUILD_MAX_PRIMITIVES_PER_LEAF
         * (32) primitives (larger ones crash Embree 3.13), so the 100k column
         * cannot be built with it and stays "n/a". */
        for (int c = 0; c < 2; ++c) {
            if (csize[c] > RTC_BUILD_MAX_PRIMITIVES_PER_LEAF) continue;
            emb[c][0] = embree_build(bc->embree, prims, work, N, RTC_BUILD_QUALITY_LOW, csize[c], repeat);
            emb[c][1] = embree_build(bc->embree, prims, work, N, RTC_BUILD_QUALITY_MEDIUM, csize[c], repeat);
        }
    }
    free(prims);
    free(work);
#endif
    printf("\nTable 3 (paper): cluster/BVH build over %" PRIu64 " elements, seconds (Melements/s)\n\n"
           "| method | 16 elements per cluster | 100k elements per cluster |\n|---|---:|---:|\n", N);
    char hcol[2][64];
    for (int c = 0; c < 2; ++c) {
        if (hil[c] < 0) snprintf(hcol[c], sizeof hcol[c], "failed");
        else snprintf(hcol[c], sizeof hcol[c], "%.4f (%.1f)", hil[c], N / hil[c] / 1e6);
    }
    printf("| Hilbert clustering (keys+sort+gather+cluster boxes), OpenCL | %s | %s |\n", hcol[0], hcol[1]);
    const char *qn[2] = {"LOW", "MEDIUM"};
    for (int q = 0; q < 2; ++q) {
#ifdef CLVR_HAVE_EMBREE
        if (bc->embree && emb[0][q] >= 0)
            printf("| Embree 3 rtcBuildBVH %s, %d threads (element boxes given; filling them took %.4f s) | %.4f (%.1f) "
                   "| n/a: leaves hold at most %d primitives |\n",
                   qn[q], bench_cpu_threads(), t_boxes, emb[0][q], N / emb[0][q] / 1e6, (int)RTC_BUILD_MAX_PRIMITIVES_PER_LEAF);
        else
            printf("| Embree 3 rtcBuildBVH %s | embree: %s | n/a |\n", qn[q],
                   bc->embree ? "build failed" : "rtcNewDevice failed");
#else
        printf("| Embree 3 rtcBuildBVH %s | embree: not installed | embree: not installed |\n", qn[q]);
#endif
    }
    if (bc->jf) {
        FILE *jf = bc->jf;
        fprintf(jf, "%s    {\"name\": \"%s\", \"elements\": %" PRIu64 ", \"vertices\": %" PRIu64 ", \"load_average\": %.2f, \"stages_s\": {",
                bc->first_run ? "" : ",\n", name, N, m->num_vertices, load0);
        for (int s = 0; s < CLVR_PP_STAGE_COUNT; ++s) fprintf(jf, "%s\"%s\": %.6f", s ? ", " : "", clvr_pp_stage_name(s), stage[s]);
        fprintf(jf, "}, \"device_total_s\": %.6f, \"wall_s\": %.6f, \"hilbert_clustering_s\": %.6f, \"c_radix2_s\": %.6f, "
                    "\"memcpy_s\": %.6f, \"hilbert_clustering_cold_s\": %.6f, \"c_radix2_cold_s\": %.6f, \"table3\": {",
                dev_total, best_wall, hilbert, t_radix, t_memcpy, hilbert_cold, t_radix_cold);
        json_secs(jf, "hilbert16_s", hil[0], ", ");
        json_secs(jf, "hilbert100k_s", hil[1], ", ");
        json_secs(jf, "embree_low16_s", emb[0][0], ", ");
        json_secs(jf, "embree_medium16_s", emb[0][1], ", ");
        json_secs(jf, "embree_low100k_s", emb[1][0], ", ");
        json_secs(jf, "embree_medium100k_s", emb[1][1], ", ");
        json_secs(jf, "embree_boxes_s", t_boxes, "}}");
        bc->first_run = 0;
    }
    free(idx); free(keys); free(k2); free(kt); free(vals); free(v2); free(vt);
    return 0;
}

int main(int argc, char **argv)
{
    const char *device = NULL, *json = NULL, *sizes = NULL;
    const char *meshes[16];
    int nmesh = 0, repeat = 3;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--device") && i + 1 < argc) device = argv[++i];
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--elements") && i + 1 < argc) sizes = argv[++i];
        else if (!strcmp(argv[i], "--mesh") && i + 1 < argc && nmesh < 16) meshes[nmesh++] = argv[++i];
        else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_preprocess [--device SPEC] [--json FILE] [--elements N[,N...]] "
                            "[--mesh FILE]... [--repeat R]\n");
            return 2;
        }
    }
    if (repeat < 1) repeat = 1;
    if (!sizes && nmesh == 0) sizes = "1000000,10000000";
    clvr_cl cl;
    clvr_error err = {0};
    if (clvr_cl_create(device, &cl, &err) != CLVR_OK) { fprintf(stderr, "bench_preprocess: %s\n", err.msg); return 4; }
    printf("device: %s (%s), %s, driver %s, %u compute units, %.2f GB device memory\n", cl.device_name,
           cl.platform_name, cl.device_version, cl.driver_version, cl.compute_units, (double)cl.global_mem_bytes / 1e9);
#ifdef CLVR_HAVE_EMBREE
    char emb_cfg[32]; /* as many threads as the C radix sort */
    snprintf(emb_cfg, sizeof emb_cfg, "threads=%d", bench_cpu_threads());
#endif
    bench_ctx bc = {&cl, repeat, NULL, 1
#ifdef CLVR_HAVE_EMBREE
                    , rtcNewDevice(emb_cfg)
#endif
    };
#ifdef CLVR_HAVE_EMBREE
    printf("embree: %s\n", bc.embree ? "Embree 3 (rtcBuildBVH)" : "embree: rtcNewDevice failed");
#else
    printf("embree: not installed\n");
#endif
    bc.jf = json ? fopen(json, "w") : NULL;
    if (bc.jf) fprintf(bc.jf, "{\n  \"device\": \"%s\",\n  \"driver\": \"%s\",\n  \"runs\": [\n", cl.device_name, cl.driver_version);
    int rc = 0;
    for (int i = 0; i < nmesh && !rc; ++i) {
        clvr_mesh m = {0};
        if (clvr_mesh_load(meshes[i], NULL, &m, &err) != CLVR_OK) { fprintf(stderr, "bench_preprocess: %s\n", err.msg); rc = 1; break; }
        rc = run_case(&bc, meshes[i], &m);
        clvr_mesh_free(&m);
    }
    for (const char *p = sizes; p && *p && !rc;) {
        /* N, or N with a K/M/G suffix (10M = 10,000,000), comma separated. */
        char *end;
        uint64_t want = strtoull(p, &end, 10);
        if (*end == 'K' || *end == 'k') want *= 1000ull, ++end;
        else if (*end == 'M' || *end == 'm') want *= 1000000ull, ++end;
        else if (*end == 'G' || *end == 'g') want *= 1000000000ull, ++end;
        if (end == p || (*end && *end != ',') || want == 0 || want > 4000000000ull) {
            fprintf(stderr, "bench_preprocess: --elements '%s': expected counts such as 1000000,10M (1 .. 4G)\n", sizes);
            rc = 2;
            break;
        }
        p = *end == ',' ? end + 1 : end;
        uint32_t n = (uint32_t)llround(cbrt((double)want));
        if (n < 1) n = 1;
        clvr_mesh m = {0};
        if (make_hexes(&m, n, &err)) { fprintf(stderr, "bench_preprocess: %s\n", err.msg); rc = 1; break; }
        char name[64];
        snprintf(name, sizeof name, "hex grid %u^3", n);
        rc = run_case(&bc, name, &m);
        clvr_mesh_free(&m);
    }
    if (bc.jf) { fprintf(bc.jf, "\n  ]\n}\n"); fclose(bc.jf); }
#ifdef CLVR_HAVE_EMBREE
    if (bc.embree) rtcReleaseDevice(bc.embree);
#endif
    clvr_cl_destroy(&cl);
    return rc;
}
