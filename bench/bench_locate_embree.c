/* bench_locate_embree.c: clvr point location side by side with Embree 3 on
 * the same mesh and the same query points (issue #4). clvr: the real
 * pipeline (clvr_preprocess: Hilbert sort and clusters; clvr_bvh_build_device;
 * the clvr_locate_points kernel). Embree: one user-geometry primitive per
 * element with the element's padded vertex box, and in its callback the very
 * containment test clvr uses (kernels/elements.h compiled for the host), run
 * two ways (rtcIntersect1 with a zero-length ray that a hit cuts short, and
 * rtcPointQuery with radius 0) on `--threads` pthreads over query chunks;
 * the faster way is "Embree". Both report queries/s (median of 5 timed runs
 * after a warm-up, wall seconds of each run, with the 1-minute load average,
 * as the machine may be shared), build time (wall, from the mesh in memory)
 * and memory of tree + indices. A third row is the ceiling of any search on
 * this machine: the same threads load only the element rtcIntersect1 found
 * for each point and run the exact test, with no tree at all (the work every
 * method does for a found point), so that a ratio to Embree reads against
 * what the element tests leave.
 *
 *   bench_locate_embree [--device SPEC] [--json FILE] [--cubes N | --mesh FILE.bin] [--kind tets|hexes|mixed]
 *                       [--queries Q] [--leaf N] [--order random|sorted|rays] [--threads T] [--local L]
 *   defaults: 56^3 cubes cut into 6 Kuhn tets (1,053,696 tets), 1M random points, leaf clusters of 16
 *   (the library's default),
 *   as many threads as online cores (bench_cpu_threads), work-group 64
 *                       [--dump FILE]   (the mesh and points, raw, for bench_vtk_locate)
 *                       [--hint coherent|incoherent]  (clvr's query hint, CLVR_LOCATE_*; default
 *                       coherent, the faster on every order: clvr_shared.h)
 *                       [--ebox on|off]  (quantized element boxes, kernels/locate.h; default on as
 *                       in bench_locate; their bytes count in clvr's tree bytes)
 *                       [--entry on|off]  (entry grids, kernels/locate.h; default on as in the
 *                       renderer; their bytes count in clvr's tree bytes)
 *                       [--one-curve auto|on|off]  (clvr: a mesh of several cell types on one curve, every
 *                       cell a collapsed hex, clvr_preprocess_options.one_curve; default auto as in
 *                       the renderer; Embree gets the mesh's own cells either way)
 *
 * Last line: `point_queries_vs_embree: RATIO` (clvr queries/s over Embree's;
 * "n/a" without Embree). Built without Embree (CLVR_HAVE_EMBREE unset) it
 * measures clvr alone and says "embree: not installed". */
#include <math.h>
#include <pthread.h>
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
#include "../kernels/bvh_build.h"
#include "../kernels/elements.h"
#include "../tests/bvh_fixture.h"
#include "bench_points.h"

#ifdef CLVR_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

#define NRUNS 5

/* ------------------------------------------------------------ clvr */

static cl_uint g_ebox = 1; /* quantized element boxes (--ebox on|off) */
static int g_entry = 1;    /* entry grids (--entry on|off, kernels/locate.h) */
static int g_one_curve = CLVR_ONE_CURVE_AUTO; /* mixed meshes on one curve (--one-curve auto|on|off, preprocess.h) */
static cl_uint g_chain = 1; /* points per work item with one ray's hint (--order rays: a ray's samples, bench_points.h) */

typedef struct result {
    double qps, qps_cpu, load, build_s, sort_s, found;
    uint64_t tree_bytes, index_bytes;
    float *scalars;
    uint32_t *found_flags;
} result;

static clvr_status run_clvr(clvr_cl *cl, const clvr_mesh *m, uint32_t leaf, float (*pts)[4], uint32_t nq, size_t local,
                            cl_uint hints, result *r, clvr_error *err)
{
    clvr_status s = CLVR_OK;
    clvr_bvh_kernels k;
    clvr_clustered c;
    clvr_bvh_device db;
    memset(&k, 0, sizeof k);
    memset(&c, 0, sizeof c);
    memset(&db, 0, sizeof db);
    cl_mem dpts = NULL, dsc = NULL, deid = NULL;
    cl_event evt = NULL;
    uint32_t *ids = malloc((size_t)(nq ? nq : 1) * sizeof *ids);
    r->scalars = malloc((size_t)(nq ? nq : 1) * sizeof *r->scalars);
    if (!ids || !r->scalars) {
        free(ids);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "bench_locate_embree: no memory for %u results", nq);
    }
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.leaf_size = leaf;
    o.one_curve = g_one_curve;
    CLVR_TRY(clvr_bvh_kernels_create(cl, &k, err));
    /* build_s: wall seconds from the mesh in host memory to a structure the
     * queries can run on (upload, every preprocessing stage: the sort, the
     * clusters' vertices and 16-bit indices the queries read, the trees, the
     * top-level tree on the host, the element boxes), as Embree's is from
     * its arrays to a committed scene. Until session 46 it was the bottom
     * trees' device seconds alone (the element boxes were added after it was
     * read), plus the sort's stages in the comparison line: about a third of
     * the work. */
    const double t_build = clvr_clock_monotonic_s();
    CLVR_TRY(clvr_preprocess(cl, m, &o, &c, err));
    CLVR_TRY(clvr_bvh_build_device(cl, &k, c.host_instances, (uint32_t)c.num_instances, c.instances, c.leaf_boxes,
                                   (uint32_t)c.num_leaves, &db, err));
    if (g_ebox)
        CLVR_TRY(clvr_bvh_element_boxes_device(cl, &k, &db, c.instances, (uint32_t)c.num_instances, c.vertices, c.idx16,
                                               c.idx32, c.leaf_size, (uint32_t)c.num_leaves, c.num_elements, err));
    if (g_entry)
        CLVR_TRY(clvr_bvh_entry_grids_device(cl, &k, &db, c.host_instances, c.instances, (uint32_t)c.num_instances,
                                             c.vertices, c.idx16, c.idx32, c.leaf_size, (uint32_t)c.num_leaves, err));
    CLVR_CL_CHECK(clFinish(cl->queue));
    r->build_s = clvr_clock_monotonic_s() - t_build;
    /* The BVH's sort, for the record: bounds, curve keys, radix sort, leaf boxes (device seconds). */
    r->sort_s = c.stage_s[CLVR_PP_STAGE_BOUNDS] + c.stage_s[CLVR_PP_STAGE_KEYS] + c.stage_s[CLVR_PP_STAGE_SORT] +
                c.stage_s[CLVR_PP_STAGE_LEAVES];
    /* Tree bytes include the quantized element boxes and the entry grids: they are part of clvr's acceleration
     * structure. */
    r->tree_bytes = clvr_bvh_bytes(db.tlas_nodes, db.blas_nodes) + c.num_instances * sizeof(clvr_instance) +
                    (g_ebox ? db.ebox_bytes : 0) + (g_entry ? db.entry_bytes : 0);
    /* Indices, and the vertices the clusters duplicate (each instance keeps
     * its own copy of a vertex shared across its border): the price of the
     * 16-bit indices, which Embree, indexing the mesh's own vertices, does
     * not pay (left out until session 46: 5-10% of clvr's figure). */
    const uint64_t dup = c.bytes_vertices_after > c.bytes_vertices_before
                             ? c.bytes_vertices_after - c.bytes_vertices_before
                             : 0;
    r->index_bytes = c.num_idx16 * 2 + c.num_idx32 * 4 + dup;
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)(nq ? nq : 1) * sizeof *pts, pts,
                            "points", &dpts, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)(nq ? nq : 1) * 4, NULL, "scalars", &dsc, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (size_t)(nq ? nq : 1) * 4, NULL, "ids", &deid, err));
    cl_uint n = nq, ls = leaf, root = db.tlas_root;
    const cl_mem args[] = {dpts, db.tlas, db.blas, c.instances, c.vertices, c.idx16, c.idx32, dsc, deid};
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 0, sizeof(cl_mem), &args[0]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 1, sizeof(cl_uint), &n));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 2, sizeof(cl_mem), &args[1]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 3, sizeof(cl_uint), &root));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 4, sizeof(cl_mem), &args[2]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 5, sizeof(cl_mem), &args[3]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 6, sizeof(cl_mem), &args[4]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 7, sizeof(cl_mem), &args[5]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 8, sizeof(cl_mem), &args[6]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 9, sizeof(cl_uint), &ls));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 10, sizeof(cl_mem), &args[7]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 11, sizeof(cl_mem), &args[8]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 12, sizeof(cl_uint), &hints));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 13, sizeof(cl_mem), g_ebox ? &db.ebox : &args[4]));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 14, sizeof(cl_uint), &g_ebox));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 15, sizeof(cl_uint), &g_chain));
    /* --entry off: NULL grids, every walk from its instance's root */
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 16, sizeof(cl_mem), g_entry ? &db.entry_grids : NULL));
    CLVR_CL_CHECK(clSetKernelArg(k.locate_points, 17, sizeof(cl_mem), g_entry ? &db.entry_cells : NULL));
    const size_t items = (nq + g_chain - 1) / g_chain;
    CLVR_TRY(clvr_cl_run1d(cl, k.locate_points, items, local, NULL, err)); /* warm-up */
    CLVR_CL_CHECK(clFinish(cl->queue));
    double t[NRUNS], tc[NRUNS], ld[NRUNS];
    for (int i = 0; i < NRUNS; ++i) {
        /* Wall seconds from the launch to its end, as Embree's (which count
         * its threads' start and join); the kernel's event seconds leave out
         * the launch (until session 46 they were the figure). */
        const double c0 = clvr_clock_cpu_s(), w0 = clvr_clock_monotonic_s();
        CLVR_TRY(clvr_cl_run1d(cl, k.locate_points, items, local, &evt, err));
        CLVR_CL_CHECK(clWaitForEvents(1, &evt));
        t[i] = clvr_clock_monotonic_s() - w0;
        tc[i] = clvr_clock_cpu_s() - c0;
        ld[i] = bench_load1();
        clReleaseEvent(evt);
        evt = NULL;
    }
    r->qps = nq / bench_median(t, NRUNS);
    r->qps_cpu = nq / bench_median(tc, NRUNS);
    r->load = bench_median(ld, NRUNS);
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, deid, CL_TRUE, 0, (size_t)nq * 4, ids, 0, NULL, NULL));
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, dsc, CL_TRUE, 0, (size_t)nq * 4, r->scalars, 0, NULL, NULL));
    uint32_t found = 0;
    for (uint32_t i = 0; i < nq; ++i) {
        const int f = ids[i] != CLVR_BVH_NOT_FOUND;
        found += (uint32_t)f;
        if (!f) r->scalars[i] = NAN;
    }
    r->found = nq ? (double)found / nq : 0.0;
cleanup:
    if (evt) clReleaseEvent(evt);
    clvr_cl_release(cl, &dpts);
    clvr_cl_release(cl, &dsc);
    clvr_cl_release(cl, &deid);
    clvr_bvh_device_release(cl, &db);
    clvr_clustered_release(cl, &c);
    clvr_bvh_kernels_destroy(&k);
    free(ids);
    return s;
}

/* ------------------------------------------------------------ Embree */

#ifdef CLVR_HAVE_EMBREE
typedef struct emb_mem {
    ssize_t now, peak;
    pthread_mutex_t lock;
} emb_mem;

static bool emb_monitor(void *user, ssize_t bytes, bool post)
{
    (void)post;
    emb_mem *mm = user;
    pthread_mutex_lock(&mm->lock);
    mm->now += bytes;
    if (mm->now > mm->peak) mm->peak = mm->now;
    pthread_mutex_unlock(&mm->lock);
    return true;
}

/* The mesh as Embree's callbacks read it: original element order, vertices
 * packed as x y z scalar (one 16-byte load each, as clvr's clustered
 * vertices; the same bytes as positions + scalars). */
typedef struct emb_mesh {
    const clvr_mesh *m;
    clvr_vec4 *v4;
} emb_mesh;

static uint32_t emb_element(const emb_mesh *em, uint64_t g, clvr_vec4 *v)
{
    const clvr_mesh *m = em->m;
    uint32_t t = 0;
    while (t + 1 < CLVR_CELL_TYPE_COUNT && g >= m->num_cells[t]) g -= m->num_cells[t++];
    const uint32_t nv = clvr_cell_vertex_count(t);
    const uint32_t *ix = m->indices[t] + g * nv;
    for (uint32_t k = 0; k < nv; ++k) v[k] = em->v4[ix[k]];
    return t;
}

static void emb_bounds(const struct RTCBoundsFunctionArguments *a)
{
    const emb_mesh *m = a->geometryUserPtr;
    clvr_vec4 v[8];
    const uint32_t t = emb_element(m, a->primID, v);
    const uint32_t nv = clvr_cell_vertex_count(t);
    float lx = v[0].x, ly = v[0].y, lz = v[0].z, hx = lx, hy = ly, hz = lz;
    for (uint32_t i = 1; i < nv; ++i) {
        lx = fminf(lx, v[i].x); ly = fminf(ly, v[i].y); lz = fminf(lz, v[i].z);
        hx = fmaxf(hx, v[i].x); hy = fmaxf(hy, v[i].y); hz = fmaxf(hz, v[i].z);
    }
    /* the padding of clvr's boxes (bvh_build.h), so boundary points pass */
    clvr_bvh_pad_box(&lx, &ly, &lz, &hx, &hy, &hz);
    a->bounds_o->lower_x = lx; a->bounds_o->lower_y = ly; a->bounds_o->lower_z = lz;
    a->bounds_o->upper_x = hx; a->bounds_o->upper_y = hy; a->bounds_o->upper_z = hz;
}

/* Per-query state rides behind Embree's context (the documented way). */
typedef struct emb_ctx {
    struct RTCIntersectContext ctx;
    const emb_mesh *m;
    float px, py, pz, scalar;
    int found;
} emb_ctx;

static void emb_intersect(const struct RTCIntersectFunctionNArguments *a)
{
    if (!a->valid[0]) return;
    emb_ctx *q = (emb_ctx *)a->context;
    clvr_vec4 v[8];
    const uint32_t t = emb_element(q->m, a->primID, v);
    float s;
    if (!clvr_element_sample(t, v, q->px, q->py, q->pz, &s)) return;
    q->found = 1;
    q->scalar = s;
    /* Cut the (zero-length) ray off: every remaining box test fails. */
    struct RTCRayHit *rh = (struct RTCRayHit *)a->rayhit;
    rh->ray.tfar = -INFINITY;
    rh->hit.geomID = a->geomID;
    rh->hit.primID = a->primID;
}

typedef struct emb_pq {
    const emb_mesh *m;
    float scalar;
    int found;
} emb_pq;

static bool emb_point(struct RTCPointQueryFunctionArguments *a)
{
    emb_pq *q = a->userPtr;
    if (q->found) return false; /* rtcPointQuery has no early exit; later candidates cost one branch */
    clvr_vec4 v[8];
    const uint32_t t = emb_element(q->m, a->primID, v);
    float s;
    if (clvr_element_sample(t, v, a->query->x, a->query->y, a->query->z, &s)) {
        q->found = 1;
        q->scalar = s;
    }
    return false;
}

/* What emb_worker runs per point. */
enum { EMB_INTERSECT1, EMB_POINT_QUERY, EMB_FOUND_ONLY };

typedef struct emb_job {
    RTCScene scene;
    const emb_mesh *m;
    float (*pts)[4];
    uint32_t begin, end;
    int api;          /* EMB_* */
    float *scalars;
    uint32_t *prims;  /* EMB_INTERSECT1 writes the element found (UINT32_MAX: none), EMB_FOUND_ONLY reads it */
} emb_job;

static void *emb_worker(void *arg)
{
    emb_job *j = arg;
    for (uint32_t i = j->begin; i < j->end; ++i) {
        const float *p = j->pts[i];
        if (j->api == EMB_FOUND_ONLY) {
            /* The ceiling of any search: no tree, only the work every
             * method does for a found point, the element's load and the
             * exact test (the callback's own). */
            float s = NAN;
            if (j->prims[i] != UINT32_MAX) {
                clvr_vec4 v[8];
                const uint32_t t = emb_element(j->m, j->prims[i], v);
                if (!clvr_element_sample(t, v, p[0], p[1], p[2], &s)) s = NAN;
            }
            j->scalars[i] = s;
        } else if (j->api == EMB_POINT_QUERY) {
            struct RTCPointQuery pq = {p[0], p[1], p[2], 0.0f, 0.0f};
            struct RTCPointQueryContext pc;
            rtcInitPointQueryContext(&pc);
            emb_pq q = {j->m, NAN, 0};
            rtcPointQuery(j->scene, &pq, &pc, emb_point, &q);
            j->scalars[i] = q.found ? q.scalar : NAN;
        } else {
            emb_ctx q;
            rtcInitIntersectContext(&q.ctx);
            q.m = j->m;
            q.px = p[0]; q.py = p[1]; q.pz = p[2];
            q.found = 0;
            q.scalar = NAN;
            struct RTCRayHit rh;
            memset(&rh, 0, sizeof rh);
            rh.ray.org_x = p[0]; rh.ray.org_y = p[1]; rh.ray.org_z = p[2];
            rh.ray.dir_x = 0.57735f; rh.ray.dir_y = 0.57735f; rh.ray.dir_z = 0.57735f;
            rh.ray.tnear = 0.0f;
            rh.ray.tfar = 0.0f;
            rh.ray.mask = 0xffffffffu;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(j->scene, &q.ctx, &rh);
            j->scalars[i] = q.found ? q.scalar : NAN;
            j->prims[i] = q.found ? rh.hit.primID : UINT32_MAX;
        }
    }
    return NULL;
}

/* Queries all points on `threads` pthreads; returns wall seconds. */
static double emb_query(RTCScene scene, const emb_mesh *m, float (*pts)[4], uint32_t nq, int threads, int api,
                        float *scalars, uint32_t *prims)
{
    pthread_t th[64];
    int started[64];
    emb_job jobs[64];
    const double t0 = clvr_clock_monotonic_s();
    for (int i = 0; i < threads; ++i) {
        jobs[i] = (emb_job){scene, m, pts, (uint32_t)((uint64_t)nq * i / threads),
                            (uint32_t)((uint64_t)nq * (i + 1) / threads), api, scalars, prims};
        started[i] = pthread_create(&th[i], NULL, emb_worker, &jobs[i]) == 0;
        if (!started[i]) emb_worker(&jobs[i]);
    }
    for (int i = 0; i < threads; ++i)
        if (started[i]) pthread_join(th[i], NULL);
    return clvr_clock_monotonic_s() - t0;
}

/* r[EMB_*]: Embree's two query APIs, then the found elements alone (the
 * elements rtcIntersect1 found). */
static int run_embree(const clvr_mesh *mesh, float (*pts)[4], uint32_t nq, int threads, result r[3])
{
    emb_mesh em = {mesh, malloc((size_t)(mesh->num_vertices ? mesh->num_vertices : 1) * sizeof(clvr_vec4))};
    const emb_mesh *m = &em;
    uint32_t *prims = malloc((size_t)(nq ? nq : 1) * sizeof *prims);
    if (!em.v4 || !prims) {
        free(em.v4);
        free(prims);
        return -1;
    }
    for (uint64_t i = 0; i < mesh->num_vertices; ++i) {
        em.v4[i].x = mesh->positions[3 * i];
        em.v4[i].y = mesh->positions[3 * i + 1];
        em.v4[i].z = mesh->positions[3 * i + 2];
        em.v4[i].w = mesh->scalars[i];
    }
    char cfg[64];
    snprintf(cfg, sizeof cfg, "threads=%d", threads);
    RTCDevice dev = rtcNewDevice(cfg);
    if (!dev) {
        fprintf(stderr, "bench_locate_embree: rtcNewDevice failed (%d)\n", (int)rtcGetDeviceError(NULL));
        free(em.v4);
        free(prims);
        return -1;
    }
    emb_mem mm = {0, 0, PTHREAD_MUTEX_INITIALIZER};
    rtcSetDeviceMemoryMonitorFunction(dev, emb_monitor, &mm);
    const uint64_t ne = clvr_mesh_num_elements(mesh);
    const double t0 = clvr_clock_monotonic_s();
    RTCScene scene = rtcNewScene(dev);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, (unsigned)ne);
    rtcSetGeometryUserData(g, (void *)m);
    rtcSetGeometryBoundsFunction(g, emb_bounds, (void *)m);
    rtcSetGeometryIntersectFunction(g, emb_intersect);
    rtcSetGeometryPointQueryFunction(g, emb_point);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    const double build = clvr_clock_monotonic_s() - t0;
    for (int api = EMB_INTERSECT1; api <= EMB_FOUND_ONLY; ++api) { /* EMB_FOUND_ONLY reads EMB_INTERSECT1's prims */
        result *o = &r[api];
        o->build_s = build;
        o->sort_s = 0.0;
        o->tree_bytes = (uint64_t)(mm.now > 0 ? mm.now : 0);
        o->index_bytes = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) o->index_bytes += clvr_mesh_num_indices(mesh, t) * 4u;
        o->scalars = malloc((size_t)(nq ? nq : 1) * sizeof *o->scalars);
        if (!o->scalars) {
            free(em.v4);
            free(prims);
            return -1;
        }
        emb_query(scene, m, pts, nq < 1000 ? nq : 1000, threads, api, o->scalars, prims); /* warm-up */
        double t[NRUNS], tc[NRUNS], ld[NRUNS];
        for (int i = 0; i < NRUNS; ++i) {
            const double c0 = clvr_clock_cpu_s();
            t[i] = emb_query(scene, m, pts, nq, threads, api, o->scalars, prims);
            tc[i] = clvr_clock_cpu_s() - c0;
            ld[i] = bench_load1();
        }
        o->qps = nq / bench_median(t, NRUNS);
        o->qps_cpu = nq / bench_median(tc, NRUNS);
        o->load = bench_median(ld, NRUNS);
        uint32_t found = 0;
        for (uint32_t i = 0; i < nq; ++i) found += o->scalars[i] == o->scalars[i];
        o->found = nq ? (double)found / nq : 0.0;
    }
    fprintf(stderr, "# embree: peak memory during the build %.1f MB\n", (double)mm.peak / 1e6);
    rtcReleaseScene(scene);
    rtcReleaseDevice(dev);
    free(em.v4);
    free(prims);
    return 0;
}
#endif

/* ------------------------------------------------------------ VTK dump */

/* Raw file for bench_vtk_locate: "CLVRLOC1", u64 num_vertices, u64
 * num_cells[4], u64 num_points; float xyz[num_vertices]; float
 * scalars[num_vertices]; per type u32 indices; float xyz[num_points]. */
static int dump_raw(const char *path, const clvr_mesh *m, float (*pts)[4], uint32_t nq)
{
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    const uint64_t hdr[6] = {m->num_vertices, m->num_cells[0], m->num_cells[1], m->num_cells[2], m->num_cells[3], nq};
    int ok = fwrite("CLVRLOC1", 1, 8, f) == 8 && fwrite(hdr, sizeof hdr, 1, f) == 1;
    ok = ok && fwrite(m->positions, 12, m->num_vertices, f) == m->num_vertices;
    ok = ok && fwrite(m->scalars, 4, m->num_vertices, f) == m->num_vertices;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && ok; ++t) {
        const uint64_t n = clvr_mesh_num_indices(m, t);
        ok = fwrite(m->indices[t], 4, n, f) == n;
    }
    for (uint32_t i = 0; i < nq && ok; ++i) ok = fwrite(pts[i], 12, 1, f) == 1;
    return (fclose(f) == 0 && ok) ? 0 : -1;
}

/* ------------------------------------------------------------ main */

static void print_row(const char *name, const result *r, uint64_t ne)
{
    printf("| %s | %.3g | %.3g | %.2f | %.3f | %.3f | %.2f | %.2f | %.4f |\n", name, r->qps, r->qps_cpu, r->load,
           r->build_s, r->sort_s, (double)r->tree_bytes / (double)ne, (double)r->index_bytes / (double)ne, r->found);
}

/* Fraction of points where both found an element and the scalars agree
 * (shared faces may pick either neighbour: same value up to rounding), or
 * neither found one. */
static double agreement(const float *a, const float *b, uint32_t nq, float tol)
{
    uint32_t ok = 0;
    for (uint32_t i = 0; i < nq; ++i) {
        const int fa = a[i] == a[i], fb = b[i] == b[i];
        ok += (uint32_t)((!fa && !fb) || (fa && fb && fabsf(a[i] - b[i]) <= tol));
    }
    return nq ? (double)ok / nq : 1.0;
}

int main(int argc, char **argv)
{
    const char *device = NULL, *json = NULL, *mesh_path = NULL, *dump = NULL, *kind_name = "tets", *order = "random",
               *hint = NULL;
    /* The leaf-cluster size users get (clvr_preprocess_options_default: 16);
     * issue #19's figures before session 31 used 8, which is 4-15% slower
     * on the graded and PLOT3D meshes
     * (bench/results/graded/2026-11-28-s31-leaf.md). */
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    uint32_t cubes = 56, nq = 1000000, leaf = po.leaf_size;
    int threads = bench_cpu_threads();
    size_t local = 64;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--device") && i + 1 < argc) device = argv[++i];
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--mesh") && i + 1 < argc) mesh_path = argv[++i];
        else if (!strcmp(argv[i], "--cubes") && i + 1 < argc) cubes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--kind") && i + 1 < argc) kind_name = argv[++i];
        else if (!strcmp(argv[i], "--queries") && i + 1 < argc) nq = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--leaf") && i + 1 < argc) leaf = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--order") && i + 1 < argc) order = argv[++i];
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--local") && i + 1 < argc) local = (size_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--dump") && i + 1 < argc) dump = argv[++i];
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
                    "[--queries Q] [--leaf N] [--order random|sorted|rays] [--threads T] [--local L] [--dump FILE] "
                    "[--hint coherent|incoherent] [--ebox on|off] [--entry on|off] [--one-curve auto|on|off]\n",
                    argv[0]);
            return 2;
        }
    }
    cl_uint hints;
    const int order_id = bench_order_from_name(order);
    if (order_id < 0) {
        fprintf(stderr, "bench_locate_embree: --order must be random, sorted or rays\n");
        return 2;
    }
    g_chain = bench_order_chain(order_id);
    if (bench_query_hint(hint, &hint, &hints)) {
        fprintf(stderr, "bench_locate_embree: --hint must be coherent or incoherent\n");
        return 2;
    }
    if (threads < 1 || threads > 64 || leaf < 1 || leaf > 128) {
        fprintf(stderr, "bench_locate_embree: --threads must be 1..64 and --leaf 1..128\n");
        return 2;
    }
    clvr_error err = {0};
    clvr_mesh m;
    memset(&m, 0, sizeof m);
    clvr_status st;
    if (mesh_path) {
        st = clvr_mesh_load(mesh_path, NULL, &m, &err);
    } else {
        const uint32_t kind = !strcmp(kind_name, "hexes") ? FX_HEXES : !strcmp(kind_name, "mixed") ? FX_MIXED : FX_TETS;
        st = fx_grid_mesh(cubes, kind, 0.2f, 1.0f, 0.0f, 1, &m, &err);
    }
    if (st != CLVR_OK) {
        fprintf(stderr, "bench_locate_embree: %s\n", err.msg);
        return 1;
    }
    const uint64_t ne = clvr_mesh_num_elements(&m);
    float (*pts)[4] = bench_make_points(&m, nq, order_id);
    if (!pts) {
        fprintf(stderr, "bench_locate_embree: no memory for %u points\n", nq);
        return 1;
    }
    if (dump) {
        if (dump_raw(dump, &m, pts, nq) != 0) {
            fprintf(stderr, "bench_locate_embree: cannot write %s\n", dump);
            return 5;
        }
        printf("# wrote %s\n", dump);
        clvr_mesh_free(&m);
        free(pts);
        return 0;
    }
    clvr_cl cl;
    if (clvr_cl_create(device, &cl, &err) != CLVR_OK) {
        fprintf(stderr, "bench_locate_embree: %s\n", err.msg);
        return 4;
    }
    printf("# bench_locate_embree: %s, %llu elements (%s), %u %s queries, leaf clusters of %u, %d threads\n",
           mesh_path ? mesh_path : "generated grid", (unsigned long long)ne, mesh_path ? "file" : kind_name, nq, order,
           leaf, threads);
    printf("# device: %s | %s | driver %s | compute units %u | clvr work-group %zu, hint %s\n", cl.device_name,
           cl.device_version, cl.driver_version, cl.compute_units, local, hint);
    result rc;
    memset(&rc, 0, sizeof rc);
    if (run_clvr(&cl, &m, leaf, pts, nq, local, hints, &rc, &err) != CLVR_OK) {
        fprintf(stderr, "bench_locate_embree: clvr: %s\n", err.msg);
        return 1;
    }
    printf("\n| method | point queries/s | queries per CPU-second | load (1 min) | build s | sort s | tree bytes/element "
           "| index bytes/element | found |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    print_row("clvr (OpenCL)", &rc, ne);
    int have_embree = 0;
    result re[3];
    memset(re, 0, sizeof re);
#ifdef CLVR_HAVE_EMBREE
    if (run_embree(&m, pts, nq, threads, re) == 0) {
        have_embree = 1;
        print_row("Embree 3, rtcIntersect1", &re[0], ne);
        print_row("Embree 3, rtcPointQuery", &re[1], ne);
        printf("| found element only (no search) | %.3g | %.3g | %.2f | | | | | %.4f |\n", re[2].qps, re[2].qps_cpu,
               re[2].load, re[2].found);
    }
#endif
    const result *best = re[1].qps > re[0].qps ? &re[1] : &re[0];
    const float tol = 1e-4f * fmaxf(1.0f, fabsf(m.scalar_max) + fabsf(m.scalar_min));
    if (have_embree) {
        printf("\nsame answers as Embree (found/not found, scalar within %.2g): %.5f\n", tol,
               agreement(rc.scalars, best->scalars, nq, tol));
        printf("build (mesh in memory to queries: clvr's whole preprocessing) vs Embree: %.3f s vs %.3f s\n",
               rc.build_s, best->build_s);
        printf("tree + index memory vs Embree: %.1f vs %.1f bytes/element (%.2f of Embree's)\n",
               (double)(rc.tree_bytes + rc.index_bytes) / ne, (double)(best->tree_bytes + best->index_bytes) / ne,
               (double)(rc.tree_bytes + rc.index_bytes) / (double)(best->tree_bytes + best->index_bytes));
        /* Every method loads the element that holds a point and runs its
         * exact test; a search costing nothing would leave that. */
        printf("ceiling (found element only: load + exact test, no search, %d threads): %.3g queries/s; clvr at "
               "%.2f of it, Embree at %.2f; the most any search could reach over Embree: %.2fx\n",
               threads, re[2].qps, rc.qps / re[2].qps, best->qps / re[2].qps, re[2].qps / best->qps);
    } else {
        printf("\nembree: not installed (rebuild with libembree-dev)\n");
    }
    if (json) {
        FILE *f = fopen(json, "w");
        if (f) {
            fprintf(f, "{\"bench\": \"locate_embree\", \"device\": \"%s\", \"elements\": %llu, \"queries\": %u, "
                       "\"order\": \"%s\", \"hint\": \"%s\", \"leaf\": %u, \"threads\": %d, \"rows\": [",
                    cl.device_name, (unsigned long long)ne, nq, order, hint, leaf, threads);
            const result *rows[4] = {&rc, &re[0], &re[1], &re[2]};
            const char *names[4] = {"clvr", "embree_intersect1", "embree_point_query", "found_element_only"};
            for (int i = 0; i < (have_embree ? 4 : 1); ++i)
                fprintf(f, "%s{\"method\": \"%s\", \"queries_per_s\": %.6g, \"queries_per_cpu_s\": %.6g, \"load\": %.2f, "
                           "\"build_s\": %.6f, \"sort_s\": %.6f, \"tree_bytes\": %llu, \"index_bytes\": %llu, "
                           "\"found\": %.5f}",
                        i ? ", " : "", names[i], rows[i]->qps, rows[i]->qps_cpu, rows[i]->load, rows[i]->build_s,
                        rows[i]->sort_s, (unsigned long long)rows[i]->tree_bytes,
                        (unsigned long long)rows[i]->index_bytes, rows[i]->found);
            fprintf(f, "]}\n");
            fclose(f);
        }
    }
    if (have_embree)
        printf("point_queries_vs_embree: %.3f\n", rc.qps / best->qps);
    else
        printf("point_queries_vs_embree: n/a\n");
    free(rc.scalars);
    free(re[0].scalars);
    free(re[1].scalars);
    free(re[2].scalars);
    free(pts);
    clvr_mesh_free(&m);
    clvr_cl_destroy(&cl);
    return 0;
}
