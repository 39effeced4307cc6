/* test_bvh.c: the packed BVH and two-level point location against brute
 * force, on the host (reference) and on the OpenCL device:
 * - tree arithmetic and the device's view of the shared structs,
 * - single-level trees over random boxes (sizes 0, 1, primes, non-multiples
 *   of 4 and of the work-group size): point and ray iterators report exactly
 *   the boxes brute force finds; device build equals host build,
 * - two-level trees over generated meshes of each element type and a mix,
 *   leaf sizes 1..32, 16- and 32-bit instances, far from the origin:
 *   random points, points on faces, edges and vertices, points just outside;
 *   host and device point location agree with brute force (same element, or
 *   a neighbour brute force also accepts, with the same scalar), with each
 *   other (same element; the device runs CLVR_LOCATE_INCOHERENT, the host
 *   CLVR_LOCATE_COHERENT; on PoCL the device tests a tet leaf's candidates
 *   four at a time, clvr_tet_sample4, so this compares it with the host's
 *   one-by-one clvr_tet_sample) and across the two query hints on the host
 *   (same element, same scalar bits),
 * - the same on the meshes in tests/data (vtk, umesh) when they load. */
#include "test_util.h"

#include <dirent.h>

#include "bvh.h"
#include "bvh_fixture.h"
#include "mesh_io.h"
#include "../kernels/bvh_build.h"
#include "../kernels/bvh_traverse.h"

/* ------------------------------------------------------------ tree arithmetic */

static void test_arithmetic(void)
{
    /* independent count: sum of ceil(n / 4^k) until 1 */
    const uint32_t ns[] = {0, 1, 2, 3, 4, 5, 15, 16, 17, 63, 64, 65, 1000, 4096, 4097, 123457};
    for (size_t i = 0; i < sizeof ns / sizeof ns[0]; ++i) {
        const uint32_t n = ns[i];
        uint64_t total = 0, s = n, h = 0;
        do {
            s = (s + 3) / 4;
            if (s == 0) s = 1;
            total += s;
            ++h;
        } while (s > 1);
        TU_CHECK_EQ_U64(clvr_bvh_tree_size(n), total);
        TU_CHECK_EQ_U64(clvr_bvh_height(n), h);
        TU_CHECK_EQ_U64(clvr_bvh_level_first(n, clvr_bvh_height(n) - 1), 0); /* root first */
        TU_CHECK_EQ_U64(clvr_bvh_level_first(n, 0) + clvr_bvh_level_size(n, 0), total);
        /* point location's shortcut to the lowest level (its prefetches) */
        clvr_instance inst;
        memset(&inst, 0, sizeof inst);
        inst.num_leaves = n;
        inst.bvh_root = 1000u;
        TU_CHECK_EQ_U64(clvr_locate_level0(&inst), 1000u + clvr_bvh_level_first(n, 0));
    }
}

/* 1 when leaf cluster `leaf` of inst lies under node `node` of its tree
 * (climbing the implicit levels of bvh_build.h from the leaf's
 * lowest-level node). */
static int leaf_under(const clvr_instance *inst, uint32_t leaf, uint32_t node)
{
    uint32_t m = (leaf - inst->first_leaf) / 4u, size = (inst->num_leaves + 3u) / 4u;
    uint32_t first = clvr_locate_level0(inst);
    while (first + m != node && size > 1u) {
        size = (size + 3u) / 4u;
        first -= size;
        m /= 4u;
    }
    return first + m == node;
}

/* Entry grid layouts (locate.h): about CLVR_ENTRY_CELLS_PER_LEAF cells per
 * leaf, cells about cubic, one cell on flat, empty or NaN axes, at most
 * CLVR_ENTRY_MAX_RES per axis, first cells as a running sum; the occupancy
 * grid first, over the instances' union, about
 * CLVR_OCCUPANCY_CELLS_PER_ELEMENT cells per element, at most
 * CLVR_OCCUPANCY_MAX_RES per axis, its bits after every instance's cells;
 * overflow past 2^32 - 1 words reported; one clear word for no instances. */
static void test_entry_layout(void)
{
    clvr_error err = {0};
    clvr_instance in[5];
    clvr_entry_grid g[6];
    memset(in, 0, sizeof in);
    const float box[5][6] = {{0, 0, 0, 1, 1, 1},       /* cube */
                             {0, 0, 0, 8, 1, 1},       /* long in x */
                             {0, 0, 2, 1, 1, 2},       /* flat in z */
                             {0, 0, 0, NAN, 1, 1},     /* NaN */
                             {-1, -1, -1, 1, 1, 1}};   /* huge leaf and element counts */
    const uint32_t leaves[5] = {500, 64, 50, 10, 2000000000u};
    for (int i = 0; i < 5; ++i) {
        for (int a = 0; a < 3; ++a) {
            in[i].bounds.lo[a] = box[i][a];
            in[i].bounds.hi[a] = box[i][3 + a];
        }
        in[i].num_leaves = leaves[i];
        in[i].num_elements = i == 4 ? 4000000000u : 16u * leaves[i];
    }
    uint32_t n = 12345;
    TU_CHECK_STATUS(clvr_entry_grids_layout(in, 0, 0, g, &n, &err), CLVR_OK, &err);
    TU_CHECK(n == 1 && g[0].res[0] * g[0].res[1] * g[0].res[2] == 1 && g[0].res[3] == 0 && g[0].lo[3] == 0.0f);
    TU_CHECK_STATUS(clvr_entry_grids_layout(in, 4, 0, g, &n, &err), CLVR_OK, &err);
    /* 1000 cells for a cube: 10 a side */
    TU_CHECK(g[1].res[0] == 10 && g[1].res[1] == 10 && g[1].res[2] == 10);
    TU_CHECK(fabsf(g[1].scale[0] - 10.0f) < 1e-5f && g[1].res[3] == 0);
    /* 128 cells over 8 x 1 x 1: cubic cells of side about 0.4 */
    TU_CHECK(g[2].res[0] >= 16 && g[2].res[0] <= 24 && g[2].res[1] >= 2 && g[2].res[1] <= 3);
    TU_CHECK(g[2].res[0] * g[2].res[1] * g[2].res[2] >= 128 && g[2].res[3] == 1000);
    /* flat in z: one cell there, scale 0; 100 cells on the square */
    TU_CHECK(g[3].res[2] == 1 && g[3].scale[2] == 0.0f && g[3].res[0] == 10 && g[3].res[1] == 10);
    /* NaN extent: one cell on that axis */
    TU_CHECK(g[4].res[0] == 1 && g[4].scale[0] == 0.0f && g[4].res[1] >= 1);
    uint64_t total = 0;
    for (int i = 0; i < 5; ++i) {
        if (i > 0) {
            TU_CHECK_EQ_U64(g[i].res[3], total);
            total += (uint64_t)g[i].res[0] * g[i].res[1] * g[i].res[2];
        }
        /* a point anywhere maps into the grid, NaN too */
        const float pts[3] = {-1e30f, 0.5f, NAN};
        for (int j = 0; j < 3; ++j)
            for (int a = 0; a < 3; ++a) TU_CHECK(clvr_entry_coord(pts[j], g[i].lo[a], g[i].scale[a], g[i].res[a]) < g[i].res[a]);
    }
    /* occupancy: over (0, 0, 0) - (8, 1, 2) (the NaN bound left out), one
     * cell per element of 16 * 624, cubic cells of side about 0.117 */
    const uint64_t occ = (uint64_t)g[0].res[0] * g[0].res[1] * g[0].res[2];
    TU_CHECK(CLVR_OCCUPANCY_CELLS_PER_ELEMENT == 1u);
    TU_CHECK(g[0].lo[0] == 0.0f && g[0].lo[2] == 0.0f && fabsf(g[0].res[0] / g[0].scale[0] - 8.0f) < 1e-4f &&
             fabsf(g[0].res[2] / g[0].scale[2] - 2.0f) < 1e-4f);
    TU_CHECK(g[0].res[0] == 69 && g[0].res[1] == 9 && g[0].res[2] == 18 && occ >= 16u * 624u);
    /* its bits after the instances' cells */
    TU_CHECK_EQ_U64(g[0].res[3], 2u * total);
    /* then a global hint per occupancy cell (shift 0: lo[3] = 1) */
    const uint64_t base = 2u * total + (occ + 31u) / 32u;
    TU_CHECK(g[0].lo[3] == 1.0f && clvr_global_hints_first(&g[0]) == base);
    TU_CHECK_EQ_U64(n, base + occ);
    /* a byte limit that leaves room for (69 / 2) (9 / 2) (18 / 2) rounded
     * up hints: shift 1; one that leaves room for none: no hints */
    TU_CHECK_STATUS(clvr_entry_grids_layout(in, 4, 4u * (base + 35u * 5u * 9u), g, &n, &err), CLVR_OK, &err);
    TU_CHECK(g[0].lo[3] == 2.0f && clvr_global_hints_shift(&g[0]) == 1u && clvr_global_hint_res(&g[0], 1u, 0) == 35u);
    TU_CHECK_EQ_U64(n, base + 35u * 5u * 9u);
    TU_CHECK_STATUS(clvr_entry_grids_layout(in, 4, 4u * (base + 35u * 5u * 9u) - 1u, g, &n, &err), CLVR_OK, &err);
    TU_CHECK(g[0].lo[3] == 3.0f && n == base + 18u * 3u * 5u);
    TU_CHECK_STATUS(clvr_entry_grids_layout(in, 4, 4u * base, g, &n, &err), CLVR_OK, &err);
    TU_CHECK(g[0].lo[3] == 0.0f && n == base && !clvr_global_hints_on(&g[0]));
    /* 4e9 cells wanted: every axis capped at 1024 (occupancy too), and the
     * sum overflows */
    TU_CHECK_STATUS(clvr_entry_grids_layout(in + 4, 1, 0, g, &n, &err), CLVR_OK, &err);
    TU_CHECK(g[1].res[0] == CLVR_ENTRY_MAX_RES && g[1].res[1] == CLVR_ENTRY_MAX_RES && g[1].res[2] == CLVR_ENTRY_MAX_RES);
    TU_CHECK(g[0].res[0] == CLVR_OCCUPANCY_MAX_RES && g[0].res[1] == CLVR_OCCUPANCY_MAX_RES &&
             g[0].res[2] == CLVR_OCCUPANCY_MAX_RES);
    TU_CHECK_EQ_U64(n, (2ull << 30) + (1ull << 25));
    TU_CHECK(g[0].lo[3] == 0.0f); /* 2e9 leaves in an instance: no global hints */
    /* 60000 leaves: hints at shift 2, 256^3 = CLVR_GLOBAL_HINT_MAX_CELLS */
    clvr_instance big = in[4];
    big.num_leaves = 60000u;
    TU_CHECK_STATUS(clvr_entry_grids_layout(&big, 1, 0, g, &n, &err), CLVR_OK, &err);
    TU_CHECK(g[0].lo[3] == 3.0f && clvr_global_hint_res(&g[0], 2u, 2) == 256u);
    TU_CHECK_EQ_U64(n, 2ull * g[1].res[0] * g[1].res[1] * g[1].res[2] + (1ull << 25) + CLVR_GLOBAL_HINT_MAX_CELLS);
    /* a hex instance: CLVR_ENTRY_CELLS_PER_LEAF_NEWTON cells per leaf (125
     * leaves over the unit cube: 1000 cells, 10 a side); tets keep 2 */
    clvr_instance hx = in[0];
    hx.type = CLVR_CELL_HEX;
    hx.num_leaves = 125;
    TU_CHECK(CLVR_ENTRY_CELLS_PER_LEAF_NEWTON == 8u);
    TU_CHECK_STATUS(clvr_entry_grids_layout(&hx, 1, 0, g, &n, &err), CLVR_OK, &err);
    TU_CHECK(g[1].res[0] == 10 && g[1].res[1] == 10 && g[1].res[2] == 10);
    hx.type = CLVR_CELL_TET;
    TU_CHECK_STATUS(clvr_entry_grids_layout(&hx, 1, 0, g, &n, &err), CLVR_OK, &err);
    TU_CHECK(g[1].res[0] == 7 && g[1].res[1] == 7 && g[1].res[2] == 7);
    clvr_instance many[5];
    for (int i = 0; i < 5; ++i) many[i] = in[4];
    TU_CHECK_STATUS(clvr_entry_grids_layout(many, 5, 0, g, &n, &err), CLVR_ERR_OVERFLOW, &err);
}

static void test_device_sizes(clvr_cl *cl, const clvr_bvh_kernels *k)
{
    clvr_error err = {0};
    clvr_status s = CLVR_OK;
    cl_mem out = NULL;
    cl_kernel kk = NULL;
    cl_uint v[7] = {0};
    TU_CHECK_STATUS(s = clvr_cl_kernel(k->program, "clvr_bvh_sizes", &kk, &err), CLVR_OK, &err);
    if (s != CLVR_OK) return;
    if (clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, sizeof v, NULL, "sizes", &out, &err) == CLVR_OK &&
        clSetKernelArg(kk, 0, sizeof out, &out) == CL_SUCCESS &&
        clvr_cl_run1d(cl, kk, 1, 1, NULL, &err) == CLVR_OK &&
        clEnqueueReadBuffer(cl->queue, out, CL_TRUE, 0, sizeof v, v, 0, NULL, NULL) == CL_SUCCESS) {
        TU_CHECK_EQ_U64(v[0], sizeof(clvr_bvh_node));
        TU_CHECK_EQ_U64(v[1], sizeof(clvr_bvh_tree));
        TU_CHECK_EQ_U64(v[2], sizeof(clvr_instance));
        TU_CHECK_EQ_U64(v[3], sizeof(clvr_vec4));
        TU_CHECK_EQ_U64(v[4], offsetof(clvr_bvh_node, child));
        TU_CHECK_EQ_U64(v[5], offsetof(clvr_instance, first_index));
        TU_CHECK_EQ_U64(v[6], offsetof(clvr_instance, bvh_root));
    } else {
        TU_CHECK(!"clvr_bvh_sizes kernel ran");
    }
    clvr_cl_release(cl, &out);
    clReleaseKernel(kk);
}

/* ------------------------------------------------------------ single level over boxes */

static void random_boxes(uint32_t n, uint64_t *rs, clvr_box *b)
{
    for (uint32_t i = 0; i < n; ++i) {
        memset(&b[i], 0, sizeof b[i]);
        for (int a = 0; a < 3; ++a) {
            const float c = 10.0f * tu_randf(rs), e = 0.05f + 1.5f * tu_randf(rs) * tu_randf(rs);
            b[i].lo[a] = c - e;
            b[i].hi[a] = c + e;
        }
        b[i].lo[3] = (float)i; /* sampling clusters keep scalar ranges here: must be ignored */
        b[i].hi[3] = -(float)i;
    }
}

static int nodes_equal(const clvr_bvh_node *a, const clvr_bvh_node *b, uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i) {
        if (memcmp(a[i].child, b[i].child, sizeof a[i].child) != 0) return 0;
        const float *fa = a[i].lo_x, *fb = b[i].lo_x;
        for (int j = 0; j < 24; ++j)
            if (!(fa[j] == fb[j] || fabsf(fa[j] - fb[j]) <= 1e-6f * fabsf(fb[j]))) return 0;
    }
    return 1;
}

static void test_boxes(clvr_cl *cl, const clvr_bvh_kernels *k, uint32_t n)
{
    uint64_t rs = 1000 + n;
    clvr_error err = {0};
    clvr_box *boxes = calloc(n + 1, sizeof *boxes), *padded = calloc(n + 1, sizeof *padded);
    const uint32_t nn = clvr_bvh_nodes_bound(n);
    clvr_bvh_node *nodes = calloc(nn, sizeof *nodes), *dnodes = calloc(nn, sizeof *dnodes);
    uint32_t *seen = calloc(n + 1, sizeof *seen);
    random_boxes(n, &rs, boxes);
    for (uint32_t i = 0; i < n; ++i) {
        padded[i] = boxes[i];
        clvr_bvh_pad_box(&padded[i].lo[0], &padded[i].lo[1], &padded[i].lo[2], &padded[i].hi[0], &padded[i].hi[1],
                         &padded[i].hi[2]);
    }
    TU_CHECK_STATUS(clvr_bvh_build_boxes(boxes, n, nodes, &err), CLVR_OK, &err);

    /* point queries: exactly the padded boxes that contain the point, once each */
    int wrong_points = 0;
    for (int q = 0; q < 300; ++q) {
        const float p[3] = {12.0f * tu_randf(&rs) - 1.0f, 12.0f * tu_randf(&rs) - 1.0f, 12.0f * tu_randf(&rs) - 1.0f};
        clvr_bvh_point_iter it;
        clvr_bvh_point_begin(&it, 0, p[0], p[1], p[2]);
        uint32_t prim, got = 0, want = 0;
        int bad = 0;
        while (clvr_bvh_point_next(&it, nodes, &prim)) {
            if (prim >= n || seen[prim] == (uint32_t)q + 1) bad = 1;
            else seen[prim] = (uint32_t)q + 1;
            ++got;
        }
        for (uint32_t i = 0; i < n; ++i) {
            const int in = p[0] >= padded[i].lo[0] && p[0] <= padded[i].hi[0] && p[1] >= padded[i].lo[1] &&
                           p[1] <= padded[i].hi[1] && p[2] >= padded[i].lo[2] && p[2] <= padded[i].hi[2];
            want += in;
            if (in && seen[i] != (uint32_t)q + 1) bad = 1;
        }
        if (bad || got != want) ++wrong_points;
    }
    TU_CHECK_EQ_U64(wrong_points, 0);

    /* ray queries: same set and intervals as the slab test per box */
    enum { NR = 211 };
    float org[NR][4], dir[NR][4];
    uint32_t hcount[NR];
    uint64_t hsum[NR];
    float hlen[NR];
    int wrong_rays = 0;
    for (int r = 0; r < NR; ++r) {
        for (int a = 0; a < 3; ++a) {
            org[r][a] = 14.0f * tu_randf(&rs) - 2.0f;
            dir[r][a] = 2.0f * tu_randf(&rs) - 1.0f;
        }
        if (r % 7 == 0) dir[r][r % 3] = 0.0f; /* axis-parallel components */
        org[r][3] = r % 5 == 0 ? 0.0f : 0.5f * tu_randf(&rs); /* tmin */
        dir[r][3] = r % 3 == 0 ? INFINITY : 3.0f + 10.0f * tu_randf(&rs); /* tmax */
        clvr_bvh_ray_iter it;
        clvr_bvh_ray_begin(&it, nodes, org[r][0], org[r][1], org[r][2], dir[r][0], dir[r][1], dir[r][2], org[r][3],
                           dir[r][3]);
        uint32_t prim, got = 0, want = 0;
        float t0, t1;
        int bad = 0;
        hsum[r] = 0;
        hlen[r] = 0.0f;
        while (clvr_bvh_ray_next(&it, nodes, &prim, &t0, &t1)) {
            if (prim >= n || seen[prim] == 100000u + (uint32_t)r) { bad = 1; continue; }
            seen[prim] = 100000u + (uint32_t)r;
            ++got;
            hsum[r] += prim + 1u;
            hlen[r] += t1 - t0;
            /* the interval must be the slab interval of the padded box */
            float a = org[r][3], b = dir[r][3];
            for (int ax = 0; ax < 3; ++ax) {
                const float inv = clvr_bvh_safe_inv(dir[r][ax]);
                const float ta = (padded[prim].lo[ax] - org[r][ax]) * inv, tb = (padded[prim].hi[ax] - org[r][ax]) * inv;
                a = fmaxf(a, fminf(ta, tb));
                b = fminf(b, fmaxf(ta, tb));
            }
            if (fabsf(a - t0) > 1e-5f * (1.0f + fabsf(a)) || fabsf(b - t1) > 1e-5f * (1.0f + fabsf(b))) bad = 1;
        }
        for (uint32_t i = 0; i < n; ++i) {
            float a = org[r][3], b = dir[r][3];
            for (int ax = 0; ax < 3; ++ax) {
                const float inv = clvr_bvh_safe_inv(dir[r][ax]);
                const float ta = (padded[i].lo[ax] - org[r][ax]) * inv, tb = (padded[i].hi[ax] - org[r][ax]) * inv;
                a = fmaxf(a, fminf(ta, tb));
                b = fminf(b, fmaxf(ta, tb));
            }
            if (a <= b) {
                ++want;
                if (seen[i] != 100000u + (uint32_t)r) bad = 1;
            }
        }
        hcount[r] = got;
        if (bad || got != want) ++wrong_rays;
    }
    TU_CHECK_EQ_U64(wrong_rays, 0);

    /* device: build equals host build, ray kernel equals host iterator */
    clvr_status s = CLVR_OK;
    cl_mem dboxes = NULL, dn = NULL, dorg = NULL, ddir = NULL, dcount = NULL, dsum = NULL, dlen = NULL;
    uint32_t dcnt[NR];
    uint64_t dsm[NR];
    float dln[NR];
    cl_uint nr = NR;
    TU_CHECK_STATUS(s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (n + 1) * sizeof *boxes, boxes,
                                       "boxes", &dboxes, &err), CLVR_OK, &err);
    if (s == CLVR_OK) TU_CHECK_STATUS(s = clvr_bvh_build_boxes_device(cl, k, dboxes, n, &dn, &err), CLVR_OK, &err);
    if (s == CLVR_OK && clEnqueueReadBuffer(cl->queue, dn, CL_TRUE, 0, nn * sizeof *dnodes, dnodes, 0, NULL, NULL) == CL_SUCCESS) {
        TU_CHECK(nodes_equal(dnodes, nodes, nn));
    }
    if (s == CLVR_OK &&
        clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof org, org, "org", &dorg, &err) == CLVR_OK &&
        clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof dir, dir, "dir", &ddir, &err) == CLVR_OK &&
        clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, sizeof dcnt, NULL, "count", &dcount, &err) == CLVR_OK &&
        clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, sizeof dsm, NULL, "sum", &dsum, &err) == CLVR_OK &&
        clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, sizeof dln, NULL, "len", &dlen, &err) == CLVR_OK) {
        clSetKernelArg(k->ray_hits, 0, sizeof(cl_mem), &dorg);
        clSetKernelArg(k->ray_hits, 1, sizeof(cl_mem), &ddir);
        clSetKernelArg(k->ray_hits, 2, sizeof(cl_uint), &nr);
        clSetKernelArg(k->ray_hits, 3, sizeof(cl_mem), &dn);
        clSetKernelArg(k->ray_hits, 4, sizeof(cl_mem), &dcount);
        clSetKernelArg(k->ray_hits, 5, sizeof(cl_mem), &dsum);
        clSetKernelArg(k->ray_hits, 6, sizeof(cl_mem), &dlen);
        TU_CHECK_STATUS(clvr_cl_run1d(cl, k->ray_hits, NR, 64, NULL, &err), CLVR_OK, &err);
        clEnqueueReadBuffer(cl->queue, dcount, CL_TRUE, 0, sizeof dcnt, dcnt, 0, NULL, NULL);
        clEnqueueReadBuffer(cl->queue, dsum, CL_TRUE, 0, sizeof dsm, dsm, 0, NULL, NULL);
        clEnqueueReadBuffer(cl->queue, dlen, CL_TRUE, 0, sizeof dln, dln, 0, NULL, NULL);
        int diff = 0;
        for (int r = 0; r < NR; ++r)
            if (dcnt[r] != hcount[r] || dsm[r] != hsum[r] ||
                (isfinite(hlen[r]) && fabsf(dln[r] - hlen[r]) > 1e-4f * (1.0f + fabsf(hlen[r]))))
                ++diff;
        TU_CHECK_EQ_U64(diff, 0);
    } else {
        TU_CHECK(!"ray kernel buffers");
    }
    clvr_cl_release(cl, &dboxes);
    clvr_cl_release(cl, &dn);
    clvr_cl_release(cl, &dorg);
    clvr_cl_release(cl, &ddir);
    clvr_cl_release(cl, &dcount);
    clvr_cl_release(cl, &dsum);
    clvr_cl_release(cl, &dlen);
    free(boxes);
    free(padded);
    free(nodes);
    free(dnodes);
    free(seen);
}

/* ------------------------------------------------------------ two-level point location */

typedef struct query_set {
    float (*p)[4];
    uint32_t n;
} query_set;

/* Random points in the bounds (grown 5%), points on element faces, edges
 * and vertices (forward map at boundary parameters) and points nudged just
 * outside the mesh bounds. */
static void make_queries(const fx_clustered *c, const clvr_mesh *m, uint32_t n, uint64_t *rs, query_set *q)
{
    q->p = calloc(n + 1, sizeof *q->p);
    q->n = n;
    float lo[3], hi[3], ext = 0.0f;
    for (int a = 0; a < 3; ++a) {
        lo[a] = m->bounds_lo[a];
        hi[a] = m->bounds_hi[a];
        ext = fmaxf(ext, hi[a] - lo[a]);
    }
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t kind = i % 4;
        float *p = q->p[i];
        if (kind == 0 || c->num_elements == 0) {
            for (int a = 0; a < 3; ++a) p[a] = lo[a] - 0.05f * ext + (hi[a] - lo[a] + 0.1f * ext) * tu_randf(rs);
        } else {
            const uint32_t e = (uint32_t)(tu_rand(rs) % c->num_elements);
            clvr_vec4 v[8];
            const uint32_t t = fx_element(c, e, v);
            if (kind == 1) { /* a vertex */
                const clvr_vec4 vv = v[tu_rand(rs) % clvr_cell_vertex_count(t)];
                p[0] = vv.x; p[1] = vv.y; p[2] = vv.z;
            } else { /* a face (kind 2) or an edge (kind 3) */
                float u = tu_randf(rs), w1 = tu_randf(rs), w2 = tu_randf(rs);
                if (t == CLVR_CELL_TET || t == CLVR_CELL_WEDGE) {
                    if (u + w1 > 1.0f) { u = 1.0f - u; w1 = 1.0f - w1; }
                    if (t == CLVR_CELL_TET && u + w1 + w2 > 1.0f) w2 = 1.0f - u - w1;
                }
                float *pc[3] = {&u, &w1, &w2};
                *pc[tu_rand(rs) % 3] = (t == CLVR_CELL_TET) ? 0.0f : (float)(tu_rand(rs) & 1) * ((t == CLVR_CELL_WEDGE) ? 0.0f : 1.0f);
                if (kind == 3) *pc[tu_rand(rs) % 3] = 0.0f;
                clvr_element_forward(t, v, u, w1, w2, &p[0], &p[1], &p[2]);
            }
            /* a quarter of these go just outside along a random axis: outside
             * the mesh when they were on its boundary */
            if (tu_rand(rs) % 4 == 0) {
                const int a = (int)(tu_rand(rs) % 3);
                if (p[a] <= lo[a] + 1e-6f * ext) p[a] = lo[a] - 1e-3f * ext;
                else if (p[a] >= hi[a] - 1e-6f * ext) p[a] = hi[a] + 1e-3f * ext;
            }
        }
        p[3] = 0.0f;
    }
}

/* Judges one answer against brute force: same found/not found; the same
 * element, or one that brute force also accepts, with the same scalar. */
static int judge(const fx_clustered *c, const float *p, uint32_t got_e, float got_s, uint32_t want_e, float want_s)
{
    if ((got_e == CLVR_BVH_NOT_FOUND) != (want_e == CLVR_BVH_NOT_FOUND)) return 0;
    if (got_e == CLVR_BVH_NOT_FOUND) return 1;
    if (got_e >= c->num_elements) return 0;
    float ref = want_s;
    if (got_e != want_e && !fx_element_sample(c, got_e, p[0], p[1], p[2], &ref)) return 0;
    return fabsf(got_s - ref) <= 1e-5f * fmaxf(1.0f, fabsf(ref));
}

static void check_locate(clvr_cl *cl, const clvr_bvh_kernels *k, const clvr_mesh *m, const char *name,
                         uint32_t leaf_size, uint32_t inst_elems, int force32, uint32_t nq)
{
    clvr_error errv = {0}, *err = &errv;
    fx_clustered c;
    if (fx_cluster(m, leaf_size, inst_elems, force32, &c) != 0) {
        TU_CHECK(!"fx_cluster out of memory");
        return;
    }
    clvr_bvh_host hb;
    TU_CHECK_STATUS(clvr_bvh_build_host(c.instances, c.num_instances, c.leaf_boxes, c.num_leaves, &hb, err), CLVR_OK,
                    err);
    uint64_t rs = 77 + leaf_size * 13 + inst_elems;
    query_set q;
    make_queries(&c, m, nq, &rs, &q);
    uint32_t *want_e = malloc(nq * sizeof *want_e);
    float *want_s = malloc(nq * sizeof *want_s);
    uint32_t *host_e = malloc(nq * sizeof *host_e);
    int host_bad = 0, found = 0, hint_diff = 0;
    for (uint32_t i = 0; i < nq; ++i) {
        const float *p = q.p[i];
        want_s[i] = 0.0f;
        want_e[i] = fx_brute_locate(&c, p[0], p[1], p[2], &want_s[i]);
        float s = 0.0f;
        uint32_t e = 0;
        const clvr_mesh_view mv = {hb.tlas, hb.blas, c.instances, c.vertices, c.idx16, c.idx32, hb.tlas_root,
                                   leaf_size, NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
        const int ok = clvr_locate(&mv, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &s, &e);
        found += ok;
        host_e[i] = e;
        /* the query hint changes speed only: same element, same bits */
        float s2 = 0.0f;
        uint32_t e2 = 0;
        const int ok2 = clvr_locate(&mv, p[0], p[1], p[2], CLVR_LOCATE_INCOHERENT, &s2, &e2);
        if (ok2 != ok || e2 != e || memcmp(&s2, &s, sizeof s) != 0) ++hint_diff;
        if (ok != (e != CLVR_BVH_NOT_FOUND) || !judge(&c, p, e, s, want_e[i], want_s[i])) {
            if (host_bad < 5)
                fprintf(stderr, "%s N=%u: host point (%.9g %.9g %.9g): got %u (%g), brute force %u (%g)\n", name,
                        leaf_size, p[0], p[1], p[2], e, s, want_e[i], want_s[i]);
            ++host_bad;
        }
    }
    TU_CHECK_EQ_U64(host_bad, 0);
    TU_CHECK_EQ_U64(hint_diff, 0);
    TU_CHECK(found > (int)nq / 3); /* the queries do hit the mesh */

    /* Quantized element boxes: a filter, so the same element and the same
     * bits with and without them; and the comparison is live: boxes that
     * reject everything (all zero: [0, 0] steps) change the answers. */
    uint8_t *ebox = malloc((size_t)c.num_elements * CLVR_EBOX_BYTES + 1);
    {
        const clvr_mesh_view mv = {hb.tlas, hb.blas, c.instances, c.vertices, c.idx16, c.idx32, hb.tlas_root,
                                   leaf_size, NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
        TU_CHECK_STATUS(clvr_bvh_element_boxes_host(&mv, c.num_instances, c.num_leaves, ebox, err), CLVR_OK, err);
        clvr_mesh_view mve = mv;
        mve.ebox = ebox;
        int ebox_diff = 0, rejected = 0;
        for (uint32_t i = 0; i < nq; ++i) {
            const float *p = q.p[i];
            float s1 = 0.0f, s2 = 0.0f;
            uint32_t e1 = 0, e2 = 0;
            const int ok1 = clvr_locate(&mv, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &s1, &e1);
            const int ok2 = clvr_locate(&mve, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &s2, &e2);
            if (ok1 != ok2 || e1 != e2 || memcmp(&s1, &s2, sizeof s1) != 0) ++ebox_diff;
        }
        TU_CHECK_EQ_U64(ebox_diff, 0);
        uint8_t *zero = calloc((size_t)c.num_elements * CLVR_EBOX_BYTES + 1, 1);
        mve.ebox = zero;
        for (uint32_t i = 0; i < nq; ++i) {
            float s2 = 0.0f;
            uint32_t e2 = 0;
            rejected += clvr_locate(&mve, q.p[i][0], q.p[i][1], q.p[i][2], CLVR_LOCATE_COHERENT, &s2, &e2) !=
                        (host_e[i] != CLVR_BVH_NOT_FOUND);
        }
        TU_CHECK(rejected > 0);
        free(zero);

        /* A ray's hint (clvr_locate_hinted): walks of 24 points from one
         * query point to the next, as a renderer's samples go; same found
         * flag as the full walk, and an element that contains the point
         * with its value (judge(): where elements overlap, as curved faces
         * of mixed meshes do, either one). */
        mve.ebox = ebox;
        /* The same walks skipping an element (clvr_locate_hinted_skip, the
         * renderer's kept cell once it is settled outside): skipping one
         * that does not hold the point changes nothing; skipping the one
         * the full walk found leaves no element, or another that holds the
         * point (a shared face). */
        int hint_bad = 0, walked = 0, skip_bad = 0, skip_gone = 0;
        for (uint32_t i = 0; i + 1 < nq; i += 2) {
            clvr_locate_hint h = clvr_locate_hint_none(), ha = h, hb2 = h;
            for (int step = 0; step <= 24; ++step) {
                const float w = (float)step / 24.0f;
                float p[3];
                for (int a = 0; a < 3; ++a) p[a] = q.p[i][a] + w * (q.p[i + 1][a] - q.p[i][a]);
                float s1 = 0.0f, s2 = 0.0f;
                uint32_t e1 = 0, e2 = 0;
                const int ok1 = clvr_locate(&mve, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &s1, &e1);
                const int ok2 = clvr_locate_hinted(&mve, p[0], p[1], p[2], &h, &s2, &e2);
                walked += ok2;
                if (ok1 != ok2 || (ok1 && !judge(&c, p, e2, s2, e1, s1))) {
                    if (hint_bad < 5)
                        fprintf(stderr, "%s N=%u: hinted (%.9g %.9g %.9g): %d %g, full walk %d %g\n", name, leaf_size,
                                p[0], p[1], p[2], ok2, s2, ok1, s1);
                    ++hint_bad;
                }
                /* a), an element away from the point (step by step through the mesh) */
                float sa = 0.0f, sb = 0.0f, dummy;
                uint32_t ea = 0, eb = 0, other = (uint32_t)(((uint64_t)i * 7919u + (uint64_t)step) % c.num_elements);
                if (!fx_element_sample(&c, other, p[0], p[1], p[2], &dummy)) {
                    const int oka = clvr_locate_hinted_skip(&mve, p[0], p[1], p[2], &ha, other, &sa, &ea);
                    if (oka != ok1 || (ok1 && !judge(&c, p, ea, sa, e1, s1))) ++skip_bad;
                }
                /* b), the element found */
                if (ok1) {
                    const int okb = clvr_locate_hinted_skip(&mve, p[0], p[1], p[2], &hb2, e1, &sb, &eb);
                    if (okb && (eb == e1 || !judge(&c, p, eb, sb, e1, s1))) ++skip_bad;
                    skip_gone += !okb;
                }
            }
        }
        TU_CHECK_EQ_U64(hint_bad, 0);
        TU_CHECK(walked > 0 || nq < 2);
        if (skip_bad) fprintf(stderr, "%s N=%u: %d lookups that skip an element went wrong\n", name, leaf_size, skip_bad);
        TU_CHECK_EQ_U64(skip_bad, 0);
        TU_CHECK(skip_gone > 0 || walked == 0);
    }

    /* Entry grids (locate.h): every leaf cluster whose box holds a point
     * lies under its cell's start node (checked for the leaf each query's
     * full walk ends in, by climbing the implicit levels), a hint is a leaf
     * cluster of its instance under its start, and a walk through the grid finds
     * what the full walk finds (the same found flag; an element that holds
     * the point, with its value). Live: starts moved to a wrong node change
     * answers. */
    clvr_entry_grid *grids = malloc((c.num_instances + 1) * sizeof *grids);
    uint32_t nwords = 0, *cells = NULL;
    TU_CHECK_STATUS(clvr_entry_grids_layout(c.instances, c.num_instances, 0, grids, &nwords, err), CLVR_OK, err);
    const uint32_t ncells = grids[0].res[3] / 2u; /* the instances' cells; the occupancy bits follow */
    cells = malloc(((size_t)nwords + 1) * sizeof *cells);
    clvr_mesh_view mvg = {hb.tlas, hb.blas, c.instances, c.vertices, c.idx16, c.idx32, hb.tlas_root,
                          leaf_size, ebox, CLVR_VIEW_ONE_PIECE, NULL, NULL};
    TU_CHECK_STATUS(clvr_entry_cells_host(&mvg, c.num_instances, grids, nwords, cells, err), CLVR_OK, err);
    uint32_t *grid_e = malloc(nq * sizeof *grid_e);
    {
        int under_bad = 0, hint_bad = 0, entry_bad = 0, same = 0, wrong = 0, centre_bad = 0;
        uint32_t octants = 0;
        for (uint32_t i = 0; i < c.num_instances; ++i) {
            const clvr_entry_grid *g = &grids[1 + i];
            const uint64_t nc = (uint64_t)g->res[0] * g->res[1] * g->res[2];
            TU_CHECK(g->res[0] >= 1 && g->res[1] >= 1 && g->res[2] >= 1 && g->res[3] + nc <= ncells);
            TU_CHECK(i + 1 == c.num_instances ? g->res[3] + nc == ncells : grids[2 + i].res[3] == g->res[3] + nc);
            const clvr_instance *in = &c.instances[i];
            for (uint64_t k2 = 0; k2 < nc; ++k2) {
                const uint32_t st = cells[2 * (g->res[3] + k2)], hn = clvr_entry_hint_leaf(cells[2 * (g->res[3] + k2) + 1]);
                if (hn == CLVR_BVH_NOT_FOUND) continue;
                if (st == CLVR_BVH_NOT_FOUND || hn < in->first_leaf || hn - in->first_leaf >= in->num_leaves) {
                    ++hint_bad;
                    continue;
                }
                hint_bad += !leaf_under(in, hn, st); /* the hint leaf lies under the start node */
                /* without CLVR_ENTRY_HINT_OCTANT an element of the hint leaf
                 * holds the cell's centre; with it (a few cells checked per
                 * instance) none of the instance's elements does */
                const int oct = (cells[2 * (g->res[3] + k2) + 1] & CLVR_ENTRY_HINT_OCTANT) != 0;
                if (oct && ++octants > 200u * (i + 1)) continue;
                const uint32_t cc[3] = {(uint32_t)(k2 % g->res[0]), (uint32_t)(k2 / g->res[0] % g->res[1]),
                                        (uint32_t)(k2 / g->res[0] / g->res[1])};
                float ctr[3], sv;
                for (int a = 0; a < 3; ++a)
                    ctr[a] = g->scale[a] > 0.0f ? g->lo[a] + ((float)cc[a] + 0.5f) / g->scale[a]
                                                : 0.5f * (in->bounds.lo[a] + in->bounds.hi[a]);
                uint32_t end, held = 0;
                const uint32_t first = oct ? in->first_element : clvr_leaf_elements(&mvg, in, hn, &end);
                if (oct) end = in->first_element + in->num_elements;
                for (uint32_t e = first; e < end && !held; ++e) held = fx_element_sample(&c, e, ctr[0], ctr[1], ctr[2], &sv);
                centre_bad += oct ? held != 0 : held == 0;
            }
        }
        for (uint32_t i = 0; i < nq; ++i) {
            const float *p = q.p[i];
            float s1 = 0.0f, s2 = 0.0f;
            uint32_t e1 = 0, e2 = 0, inst = 0, leaf = 0;
            const int ok1 = clvr_locate_ex(&mvg, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, CLVR_BVH_NOT_FOUND,
                                           CLVR_BVH_NOT_FOUND, &s1, &e1, &inst, &leaf);
            mvg.entry_grids = grids;
            mvg.entry_cells = cells;
            const int ok2 = clvr_locate(&mvg, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &s2, &e2);
            mvg.entry_grids = NULL;
            mvg.entry_cells = NULL;
            grid_e[i] = e2;
            if (ok1 != ok2 || (ok1 && !judge(&c, p, e2, s2, e1, s1))) ++entry_bad;
            same += ok1 && e1 == e2;
            if (!ok1) continue;
            const clvr_instance *in = &c.instances[inst];
            const clvr_entry_grid *g = &grids[1 + inst];
            uint32_t cc[3];
            for (int a = 0; a < 3; ++a) cc[a] = clvr_entry_coord(p[a], g->lo[a], g->scale[a], g->res[a]);
            const uint32_t st = cells[2 * (g->res[3] + (cc[2] * g->res[1] + cc[1]) * g->res[0] + cc[0])];
            under_bad += !leaf_under(in, leaf, st);
        }
        /* occupancy: every element's vertices (on its boundary, where
         * rounding is closest) have their cell's bit set */
        int occ_bad = 0;
        mvg.entry_grids = grids;
        mvg.entry_cells = cells;
        for (uint32_t i = 0; i < c.num_instances; ++i) {
            const clvr_instance *in = &c.instances[i];
            const clvr_piece_arrays pa = clvr_view_piece(&mvg, in);
            for (uint32_t e = in->first_element; e < in->first_element + in->num_elements; ++e) {
                clvr_vec4 v[CLVR_CELL_MAX_VERTS];
                clvr_load_element_in(&pa, in, e, v);
                for (uint32_t j = 0; j < clvr_cell_vertex_count(in->type); ++j)
                    occ_bad += !clvr_occupied(&mvg, v[j].x, v[j].y, v[j].z);
            }
        }
        mvg.entry_grids = NULL;
        mvg.entry_cells = NULL;
        TU_CHECK_EQ_U64(occ_bad, 0);
        TU_CHECK_EQ_U64(centre_bad, 0);
        /* global hints (locate.h): on, after the occupancy bits; a hint
         * names a leaf cluster of its instance, one of whose elements
         * holds the centre of the cells it spans or one of their octants'
         * centres; a cell without one has none of the nine points in an
         * element (brute force, a sample of cells) */
        {
            const clvr_entry_grid *og = &grids[0];
            TU_CHECK(clvr_global_hints_on(og) && clvr_global_hints_shift(og) == 0u);
            const uint32_t sh = clvr_global_hints_shift(og);
            const uint32_t hr[3] = {clvr_global_hint_res(og, sh, 0), clvr_global_hint_res(og, sh, 1),
                                    clvr_global_hint_res(og, sh, 2)};
            const uint64_t nh = (uint64_t)hr[0] * hr[1] * hr[2];
            TU_CHECK_EQ_U64(clvr_global_hints_first(og) + nh, nwords);
            const uint32_t *gh = cells + clvr_global_hints_first(og);
            int ghint_bad = 0, ghints = 0;
            for (uint64_t h = 0; h < nh; ++h) {
                const uint32_t w = gh[h], gi = w >> CLVR_GLOBAL_HINT_LEAF_BITS;
                if (w != CLVR_BVH_NOT_FOUND && (gi >= c.num_instances ||
                                                (w & CLVR_GLOBAL_HINT_LEAF_MASK) >= c.instances[gi].num_leaves)) {
                    ++ghint_bad;
                    continue;
                }
                if (h % 7u) continue; /* the sample of cells checked by brute force */
                const uint32_t hc[3] = {(uint32_t)(h % hr[0]), (uint32_t)(h / hr[0] % hr[1]), (uint32_t)(h / hr[0] / hr[1])};
                uint32_t e0 = 0, e1 = c.num_elements;
                if (w != CLVR_BVH_NOT_FOUND)
                    e0 = clvr_leaf_elements(&mvg, &c.instances[gi], c.instances[gi].first_leaf + (w & CLVR_GLOBAL_HINT_LEAF_MASK), &e1);
                int held = 0;
                for (uint32_t o = 0; o < 9u && !held; ++o) {
                    float pt[3], sv;
                    for (int a = 0; a < 3; ++a)
                        pt[a] = og->scale[a] > 0.0f
                                    ? og->lo[a] + ((float)hc[a] + (o == 0u ? 0.5f : ((o - 1u) >> a) & 1u ? 0.75f : 0.25f)) /
                                                      og->scale[a]
                                    : og->lo[a];
                    for (uint32_t e = e0; e < e1 && !held; ++e) held = fx_element_sample(&c, e, pt[0], pt[1], pt[2], &sv);
                }
                ghint_bad += w == CLVR_BVH_NOT_FOUND ? held : !held;
                ghints += w != CLVR_BVH_NOT_FOUND;
            }
            if (ghint_bad) fprintf(stderr, "%s N=%u: %d global hints wrong\n", name, leaf_size, ghint_bad);
            TU_CHECK_EQ_U64(ghint_bad, 0);
            TU_CHECK(ghints > 0 || found == 0);
        }
        TU_CHECK_EQ_U64(under_bad, 0);
        TU_CHECK_EQ_U64(hint_bad, 0);
        TU_CHECK_EQ_U64(entry_bad, 0);
        TU_CHECK(same > 0 || found == 0);
        /* each instance's start moved to its last lowest-level node: a
         * node of its own tree, wrong for most points where it has more
         * than 4 leaf clusters */
        uint32_t *bad = malloc(((size_t)nwords + 1) * sizeof *bad);
        memcpy(bad, cells, (size_t)nwords * sizeof *bad); /* the occupancy bits kept */
        for (uint32_t i = 0; i < c.num_instances; ++i) {
            const clvr_instance *in = &c.instances[i];
            const uint64_t nc = (uint64_t)grids[1 + i].res[0] * grids[1 + i].res[1] * grids[1 + i].res[2];
            for (uint64_t k2 = grids[1 + i].res[3]; k2 < grids[1 + i].res[3] + nc; ++k2) {
                bad[2 * k2] = cells[2 * k2] == CLVR_BVH_NOT_FOUND ? CLVR_BVH_NOT_FOUND
                                                                  : clvr_locate_level0(in) + (in->num_leaves + 3u) / 4u - 1u;
                bad[2 * k2 + 1] = CLVR_BVH_NOT_FOUND;
            }
        }
        mvg.entry_grids = grids;
        mvg.entry_cells = bad;
        for (uint32_t i = 0; i < nq; ++i) {
            float s2 = 0.0f;
            uint32_t e2 = 0;
            wrong += clvr_locate(&mvg, q.p[i][0], q.p[i][1], q.p[i][2], CLVR_LOCATE_COHERENT, &s2, &e2) !=
                     (host_e[i] != CLVR_BVH_NOT_FOUND);
        }
        int big = 0; /* an instance with more than one lowest-level node */
        for (uint32_t i = 0; i < c.num_instances; ++i) big |= c.instances[i].num_leaves > 4u;
        TU_CHECK(wrong > 0 || !big || found == 0);
        /* the right cells, every occupancy bit cleared: nothing is found */
        memcpy(bad, cells, (size_t)nwords * sizeof *bad);
        memset(bad + grids[0].res[3], 0, (size_t)(nwords - grids[0].res[3]) * sizeof *bad);
        int cleared_found = 0;
        for (uint32_t i = 0; i < nq; ++i) {
            float s2 = 0.0f;
            uint32_t e2 = 0;
            cleared_found += clvr_locate(&mvg, q.p[i][0], q.p[i][1], q.p[i][2], CLVR_LOCATE_COHERENT, &s2, &e2);
        }
        TU_CHECK_EQ_U64(cleared_found, 0);
        mvg.entry_cells = cells;
        free(bad);
    }

    /* device build and device point location */
    clvr_status s = CLVR_OK;
    cl_mem dv = NULL, d16 = NULL, d32 = NULL, dinst = NULL, dleaf = NULL, dpts = NULL, dsc = NULL, deid = NULL;
    clvr_bvh_device db = {0};
    clvr_instance *dev_inst = malloc((c.num_instances + 1) * sizeof *dev_inst);
    memcpy(dev_inst, c.instances, c.num_instances * sizeof *dev_inst);
    for (uint32_t i = 0; i < c.num_instances; ++i) dev_inst[i].bvh_root = 12345; /* must be overwritten */
    float *dscal = malloc(nq * sizeof *dscal);
    uint32_t *delem = malloc(nq * sizeof *delem);
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_vertices + 1) * sizeof(clvr_vec4),
                            c.vertices, "vertices", &dv, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_idx16 + 1) * 2, c.idx16, "idx16", &d16, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_idx32 + 1) * 4, c.idx32, "idx32", &d32, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_instances + 1) * sizeof(clvr_instance),
                            dev_inst, "instances", &dinst, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (c.num_leaves + 1) * sizeof(clvr_box),
                            c.leaf_boxes, "leaf boxes", &dleaf, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (nq + 1) * sizeof *q.p, q.p, "points", &dpts, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (nq + 1) * sizeof(float), NULL, "scalars", &dsc, err));
    CLVR_TRY(clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, (nq + 1) * sizeof(uint32_t), NULL, "ids", &deid, err));
    CLVR_TRY(clvr_bvh_build_device(cl, k, dev_inst, c.num_instances, dinst, dleaf, c.num_leaves, &db, err));
    {
        /* same trees as the host build */
        int roots = 1;
        for (uint32_t i = 0; i < c.num_instances; ++i) roots &= dev_inst[i].bvh_root == c.instances[i].bvh_root;
        TU_CHECK(roots);
        TU_CHECK_EQ_U64(db.blas_nodes, hb.blas_nodes);
        TU_CHECK_EQ_U64(db.tlas_nodes, hb.tlas_nodes);
        clvr_bvh_node *tmp = malloc((size_t)db.blas_nodes * sizeof *tmp);
        CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, db.blas, CL_TRUE, 0, (size_t)db.blas_nodes * sizeof *tmp, tmp, 0,
                                          NULL, NULL));
        TU_CHECK(nodes_equal(tmp, hb.blas, hb.blas_nodes));
        free(tmp);
    }
    {
        /* device element boxes: the host reference's bytes */
        CLVR_TRY(clvr_bvh_element_boxes_device(cl, k, &db, dinst, c.num_instances, dv, d16, d32, leaf_size,
                                               c.num_leaves, c.num_elements, err));
        TU_CHECK_EQ_U64(db.ebox_bytes, (uint64_t)c.num_elements * CLVR_EBOX_BYTES);
        uint8_t *tmp = malloc((size_t)db.ebox_bytes + 1);
        if (db.ebox_bytes)
            CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, db.ebox, CL_TRUE, 0, (size_t)db.ebox_bytes, tmp, 0, NULL, NULL));
        TU_CHECK(memcmp(tmp, ebox, (size_t)db.ebox_bytes) == 0);
        free(tmp);
    }
    {
        /* device entry grids: the host reference's cells */
        CLVR_TRY(clvr_bvh_entry_grids_device(cl, k, &db, dev_inst, dinst, c.num_instances, dv, d16, d32, leaf_size,
                                             c.num_leaves, err));
        TU_CHECK_EQ_U64(db.entry_bytes, ((uint64_t)c.num_instances + 1) * sizeof *grids + (uint64_t)nwords * 4u);
        uint32_t *tmp = malloc(((size_t)nwords + 1) * 4u);
        if (nwords)
            CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, db.entry_cells, CL_TRUE, 0, (size_t)nwords * 4u, tmp, 0, NULL,
                                              NULL));
        TU_CHECK(memcmp(tmp, cells, (size_t)nwords * 4u) == 0);
        free(tmp);
    }
    cl_uint n = nq, ls = leaf_size, root = db.tlas_root, hints = CLVR_LOCATE_INCOHERENT, use_ebox = 1;
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
    /* incoherent on the device, coherent on the host: the element ids must
     * still agree (checked below) */
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 12, sizeof(cl_uint), &hints));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 13, sizeof(cl_mem), &db.ebox));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 14, sizeof(cl_uint), &use_ebox));
    cl_uint chain = 1;
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 15, sizeof(cl_uint), &chain));
    /* without entry grids (NULL), then with them (the chains below too) */
    for (int with_grids = 0; with_grids < 2; ++with_grids) {
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 16, sizeof(cl_mem), with_grids ? &db.entry_grids : NULL));
    CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 17, sizeof(cl_mem), with_grids ? &db.entry_cells : NULL));
    CLVR_TRY(clvr_cl_run1d(cl, k->locate_points, nq, 64, NULL, err));
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, dsc, CL_TRUE, 0, nq * sizeof(float), dscal, 0, NULL, NULL));
    CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, deid, CL_TRUE, 0, nq * sizeof(uint32_t), delem, 0, NULL, NULL));
    {
        int dev_bad = 0;
        for (uint32_t i = 0; i < nq; ++i)
            if (!judge(&c, q.p[i], delem[i], dscal[i], want_e[i], want_s[i])) {
                if (dev_bad < 5)
                    fprintf(stderr, "%s N=%u: device point (%.9g %.9g %.9g): got %u (%g), brute force %u (%g)\n",
                            name, leaf_size, q.p[i][0], q.p[i][1], q.p[i][2], delem[i], dscal[i], want_e[i],
                            want_s[i]);
                ++dev_bad;
            }
        TU_CHECK_EQ_U64(dev_bad, 0);
        int host_dev_diff = 0;
        for (uint32_t i = 0; i < nq; ++i) host_dev_diff += delem[i] != (with_grids ? grid_e : host_e)[i];
        TU_CHECK_EQ_U64(host_dev_diff, 0);
    }
    }
    /* Chains (a ray's hint carried from point to point inside a work item)
     * against the same kernel without hints (chain 1, checked against brute
     * force above; the same device arithmetic, since the host's may round
     * differently at element borders): 7 random points per item (mostly
     * misses of the hinted subtree; nq is not a multiple of 7 in the
     * fixtures), then walks of 25 points between pairs of query points, as
     * a renderer's samples go. Same found flag; the same element with the
     * same bits, or another element that holds the point with its value. */
    for (int pass = 0; pass < 2; ++pass) {
        const cl_uint len = pass == 0 ? 7u : 25u;
        const uint32_t np = pass == 0 ? nq : (nq / 2) * 25u;
        float (*walk)[4] = malloc(((size_t)np + 1) * sizeof *walk);
        float *ws = malloc(((size_t)np + 1) * 2 * sizeof *ws);
        uint32_t *we = malloc(((size_t)np + 1) * 2 * sizeof *we);
        cl_mem dw = NULL, dws = NULL, dwe = NULL;
        if (!walk || !ws || !we) s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "chain points");
        if (s == CLVR_OK && pass == 0) memcpy(walk, q.p, (size_t)nq * sizeof *walk);
        for (uint32_t j = 0; s == CLVR_OK && pass == 1 && j < nq / 2; ++j)
            for (uint32_t st = 0; st < 25u; ++st) {
                const float w = (float)st / 24.0f;
                for (int a = 0; a < 3; ++a)
                    walk[25u * j + st][a] = q.p[2 * j][a] + w * (q.p[2 * j + 1][a] - q.p[2 * j][a]);
                walk[25u * j + st][3] = 0.0f;
            }
        cl_uint nn = np;
        if (s == CLVR_OK)
            s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, ((size_t)np + 1) * sizeof *walk, walk,
                               "chain points", &dw, err);
        if (s == CLVR_OK)
            s = clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, ((size_t)np + 1) * sizeof(float), NULL, "chain scalars", &dws, err);
        if (s == CLVR_OK)
            s = clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, ((size_t)np + 1) * sizeof(uint32_t), NULL, "chain ids", &dwe, err);
        for (int run = 0; s == CLVR_OK && run < 2; ++run) {
            const cl_uint cl_len = run == 0 ? 1u : len;
            CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 0, sizeof(cl_mem), &dw));
            CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 1, sizeof(cl_uint), &nn));
            CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 10, sizeof(cl_mem), &dws));
            CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 11, sizeof(cl_mem), &dwe));
            CLVR_CL_CHECK(clSetKernelArg(k->locate_points, 15, sizeof(cl_uint), &cl_len));
            s = clvr_cl_run1d(cl, k->locate_points, (np + cl_len - 1) / cl_len, 64, NULL, err);
            if (s != CLVR_OK) break;
            CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, dws, CL_TRUE, 0, (size_t)np * sizeof(float), ws + run * (np + 1),
                                              0, NULL, NULL));
            CLVR_CL_CHECK(clEnqueueReadBuffer(cl->queue, dwe, CL_TRUE, 0, (size_t)np * sizeof(uint32_t),
                                              we + run * (np + 1), 0, NULL, NULL));
        }
        if (s == CLVR_OK) {
            int chain_bad = 0, same = 0;
            const float *s1 = ws, *s2 = ws + np + 1;
            const uint32_t *e1 = we, *e2 = we + np + 1;
            for (uint32_t i = 0; i < np; ++i) {
                int ok = (e1[i] == CLVR_BVH_NOT_FOUND) == (e2[i] == CLVR_BVH_NOT_FOUND);
                if (ok && e1[i] != CLVR_BVH_NOT_FOUND) {
                    if (e1[i] == e2[i]) ok = memcmp(&s1[i], &s2[i], sizeof(float)) == 0, ++same;
                    else /* a neighbour on a shared face, or an overlapping element (curved faces of mixed
                          * meshes) that contains the point by the host's test (judge) */
                        ok = e2[i] < c.num_elements && (fabsf(s1[i] - s2[i]) <= 1e-5f * fmaxf(1.0f, fabsf(s1[i])) ||
                                                        judge(&c, walk[i], e2[i], s2[i], e1[i], s1[i]));
                }
                if (!ok) {
                    if (chain_bad < 5)
                        fprintf(stderr, "%s N=%u chain %u: point (%.9g %.9g %.9g): got %u (%.9g), without hint %u (%.9g)\n",
                                name, leaf_size, len, walk[i][0], walk[i][1], walk[i][2], e2[i], s2[i], e1[i], s1[i]);
                    ++chain_bad;
                }
            }
            TU_CHECK_EQ_U64(chain_bad, 0);
            TU_CHECK(same > 0 || np == 0 || nq < 4);
        }
        clvr_cl_release(cl, &dw);
        clvr_cl_release(cl, &dws);
        clvr_cl_release(cl, &dwe);
        free(walk);
        free(ws);
        free(we);
        if (s != CLVR_OK) goto cleanup;
    }
cleanup:
    if (s != CLVR_OK) {
        fprintf(stderr, "%s: device part failed: %s\n", name, err->msg);
        TU_CHECK(s == CLVR_OK);
    }
    clvr_bvh_device_release(cl, &db);
    clvr_cl_release(cl, &dv);
    clvr_cl_release(cl, &d16);
    clvr_cl_release(cl, &d32);
    clvr_cl_release(cl, &dinst);
    clvr_cl_release(cl, &dleaf);
    clvr_cl_release(cl, &dpts);
    clvr_cl_release(cl, &dsc);
    clvr_cl_release(cl, &deid);
    free(dev_inst);
    free(dscal);
    free(delem);
    free(want_e);
    free(want_s);
    free(host_e);
    free(ebox);
    free(grids);
    free(cells);
    free(grid_e);
    free(q.p);
    clvr_bvh_host_free(&hb);
    fx_clustered_free(&c);
}

/* More instances hold a point than clvr_locate_ex collects
 * (CLVR_LOCATE_MAX_CANDIDATES): 300 random tets around the origin, each
 * holding a small ball about it, in instance clusters of 10, so that every
 * instance box holds the centre; the lookups there go one instance after
 * another past the array. Answers through the entry grids: an element that
 * holds the point, with its value, or none where brute force finds none. */
static void test_many_candidates(void)
{
    clvr_error err = {0};
    clvr_mesh m;
    memset(&m, 0, sizeof m);
    const uint32_t nt = 300;
    uint64_t counts[CLVR_CELL_TYPE_COUNT] = {0};
    counts[CLVR_CELL_TET] = nt;
    TU_CHECK_STATUS(clvr_mesh_alloc(&m, 4u * nt, counts, &err), CLVR_OK, &err);
    if (!m.positions) return;
    uint64_t rs = 4242;
    for (uint32_t t = 0; t < nt; ++t) {
        /* a regular tet's corners (which hold the origin), scaled and turned a little at random */
        static const float c[4][3] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
        const float sc = 0.5f + tu_randf(&rs);
        for (int v = 0; v < 4; ++v) {
            for (int a = 0; a < 3; ++a)
                m.positions[3u * (4u * t + v) + a] = sc * c[v][a] + 0.2f * (tu_randf(&rs) - 0.5f);
            m.scalars[4u * t + v] = fx_field(m.positions[3u * (4u * t + v)], m.positions[3u * (4u * t + v) + 1],
                                             m.positions[3u * (4u * t + v) + 2]);
            m.indices[CLVR_CELL_TET][4u * t + v] = 4u * t + v;
        }
    }
    clvr_mesh_update_ranges(&m);
    fx_clustered c;
    if (fx_cluster(&m, 1, 10, 0, &c) != 0) {
        TU_CHECK(!"fx_cluster out of memory");
        clvr_mesh_free(&m);
        return;
    }
    clvr_bvh_host hb;
    TU_CHECK_STATUS(clvr_bvh_build_host(c.instances, c.num_instances, c.leaf_boxes, c.num_leaves, &hb, &err), CLVR_OK,
                    &err);
    clvr_entry_grid *grids = malloc((c.num_instances + 1) * sizeof *grids);
    uint32_t nwords = 0;
    TU_CHECK_STATUS(clvr_entry_grids_layout(c.instances, c.num_instances, 0, grids, &nwords, &err), CLVR_OK, &err);
    uint32_t *cells = malloc(((size_t)nwords + 1) * sizeof *cells);
    clvr_mesh_view mv = {hb.tlas, hb.blas, c.instances, c.vertices, c.idx16, c.idx32, hb.tlas_root, 1, NULL,
                         CLVR_VIEW_ONE_PIECE, NULL, NULL};
    TU_CHECK_STATUS(clvr_entry_cells_host(&mv, c.num_instances, grids, nwords, cells, &err), CLVR_OK, &err);
    mv.entry_grids = grids;
    mv.entry_cells = cells;
    int bad = 0, crowded = 0, found = 0;
    for (int i = 0; i < 2000; ++i) {
        const float p[3] = {0.3f * (tu_randf(&rs) - 0.5f), 0.3f * (tu_randf(&rs) - 0.5f), 0.3f * (tu_randf(&rs) - 0.5f)};
        uint32_t inside = 0; /* instance boxes that hold p */
        for (uint32_t j = 0; j < c.num_instances; ++j) {
            const clvr_box *b = &c.instances[j].bounds;
            inside += p[0] >= b->lo[0] && p[0] <= b->hi[0] && p[1] >= b->lo[1] && p[1] <= b->hi[1] &&
                      p[2] >= b->lo[2] && p[2] <= b->hi[2];
        }
        crowded += inside > CLVR_ENTRY_MAX_CANDIDATES;
        float want_s = 0.0f, s = 0.0f;
        uint32_t e = 0;
        const uint32_t want_e = fx_brute_locate(&c, p[0], p[1], p[2], &want_s);
        found += clvr_locate(&mv, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &s, &e);
        bad += !judge(&c, p, e, s, want_e, want_s);
    }
    TU_CHECK_EQ_U64(bad, 0);
    TU_CHECK(crowded > 1000 && found > 1000); /* the path under test is taken, and finds elements */
    free(grids);
    free(cells);
    clvr_bvh_host_free(&hb);
    fx_clustered_free(&c);
    clvr_mesh_free(&m);
}

static void test_generated(clvr_cl *cl, const clvr_bvh_kernels *k)
{
    static const char *names[5] = {"tets", "pyramids", "wedges", "hexes", "mixed"};
    for (uint32_t kind = 0; kind <= FX_MIXED; ++kind) {
        clvr_mesh m;
        clvr_error err = {0};
        memset(&m, 0, sizeof m);
        const uint32_t n = kind == FX_HEXES ? 11 : 7;
        TU_CHECK_STATUS(fx_grid_mesh(n, kind, 0.2f, 1.0f, 0.0f, 11 + kind, &m, &err), CLVR_OK, &err);
        check_locate(cl, k, &m, names[kind], 1, 97, 0, 1500);
        check_locate(cl, k, &m, names[kind], 8, 500, 0, 1500);
        check_locate(cl, k, &m, names[kind], 32, 1000000, 1, 1500);
        clvr_mesh_free(&m);
    }
    /* far from the origin, small elements */
    clvr_mesh m;
    clvr_error err = {0};
    memset(&m, 0, sizeof m);
    TU_CHECK_STATUS(fx_grid_mesh(6, FX_MIXED, 0.2f, 0.01f, 500.0f, 5, &m, &err), CLVR_OK, &err);
    check_locate(cl, k, &m, "mixed-offset", 4, 300, 0, 1500);
    clvr_mesh_free(&m);
    /* graded by 10^4 per axis towards one corner, 100 units from the
     * origin: the smallest elements are 1e-4 of an occupancy cell, where
     * the occupancy grid's slab test (locate.h, element hulls) must still
     * keep every cell they reach (its rounding margin); the queries on
     * their vertices, edges and faces find what the full walk finds. The
     * mixed mesh is not jittered: jitter graded this steeply makes hexes
     * whose Newton solve ends 1e-5 apart on the host and the device */
    for (uint32_t kind = FX_TETS; kind <= FX_MIXED; kind += FX_MIXED - FX_TETS) {
        memset(&m, 0, sizeof m);
        TU_CHECK_STATUS(fx_grid_mesh(7, kind, kind == FX_TETS ? 0.2f : 0.0f, 1.0f, 0.0f, 23 + kind, &m, &err), CLVR_OK,
                        &err);
        for (uint64_t i = 0; i < 3 * m.num_vertices; ++i) {
            const float t = m.positions[i] / 7.0f;
            m.positions[i] = 100.0f + 7.0f * t * t * t * t * t * t;
        }
        clvr_mesh_update_ranges(&m);
        check_locate(cl, k, &m, kind == FX_TETS ? "tets-graded" : "mixed-graded", 4, 300, 0, 1500);
        clvr_mesh_free(&m);
    }
}

/* Inconsistent input is reported, not trusted. */
static void test_bad_input(void)
{
    clvr_error err = {0};
    clvr_instance in;
    memset(&in, 0, sizeof in);
    in.first_leaf = 3;
    in.num_leaves = 5;
    clvr_box boxes[4];
    memset(boxes, 0, sizeof boxes);
    clvr_bvh_host hb;
    TU_CHECK_STATUS(clvr_bvh_build_host(&in, 1, boxes, 4, &hb, &err), CLVR_ERR_BAD_FIELD, &err);
    TU_CHECK(strstr(err.msg, "leaf") != NULL);
}

static void test_files(clvr_cl *cl, const clvr_bvh_kernels *k)
{
    char path[1024];
    const char *files[16];
    char names[16][256];
    int nf = 0;
    snprintf(path, sizeof path, "%s/vtk", tu_data_dir());
    DIR *d = opendir(path);
    if (d) {
        struct dirent *de;
        while ((de = readdir(d)) && nf < 15) {
            const size_t l = strlen(de->d_name);
            if (l > 4 && strcmp(de->d_name + l - 4, ".vtk") == 0) {
                snprintf(names[nf], sizeof names[nf], "vtk/%s", de->d_name);
                files[nf] = names[nf];
                ++nf;
            }
        }
        closedir(d);
    }
    files[nf++] = "umesh/all_elements.umesh";
    TU_CHECK(nf >= 4); /* notch_stress, post, uGridEx and the umesh at least */
    for (int i = 0; i < nf; ++i) {
        snprintf(path, sizeof path, "%s/%s", tu_data_dir(), files[i]);
        clvr_mesh m;
        clvr_error err = {0};
        memset(&m, 0, sizeof m);
        const clvr_status st = clvr_mesh_load(path, NULL, &m, &err);
        TU_CHECK_STATUS(st, CLVR_OK, &err); /* every .vtk and .umesh of tests/data loads */
        if (st != CLVR_OK) continue;
        printf("%s: %llu elements\n", files[i], (unsigned long long)clvr_mesh_num_elements(&m));
        const uint32_t nq = clvr_mesh_num_elements(&m) > 20000 ? 400 : 1500;
        check_locate(cl, k, &m, files[i], 8, 2000, 0, nq);
        clvr_mesh_free(&m);
    }
}

/* The occupancy grid's slabs (locate.h, element hulls), on the host
 * functions the rasterization calls. Exact: on a grid of 10^3 cells whose
 * inner 8^3 cover the unit cube (the outer ones reach to infinity), the
 * corner tet x, y, z >= 0, x + y + z <= 1 meets inner cell (i, j, k),
 * i, j, k in 1 .. 8, iff (i - 1) + (j - 1) + (k - 1) <= 8 (the cell's low
 * corner on the tet's side of the slanted face): 162 of the 512 its box
 * keeps. Sound: random
 * elements of every type (jittered, non-planar faces), in grids of random
 * resolution, 1e3 units from the origin: the cell of every point
 * clvr_element_forward gives for random parameters (interior, faces,
 * edges, corners) keeps its bit. */
static uint32_t occ_bits_of(const clvr_entry_grid *g, uint32_t type, const clvr_vec4 *v, uint32_t *words)
{
    float lo[3], hi[3];
    clvr_element_slabs sl;
    clvr_element_hull(type, v, lo, hi, &sl);
    uint32_t a[3], b[3], set = 0;
    clvr_entry_box_cells(g, lo, hi, a, b);
    for (uint32_t z = a[2]; z <= b[2]; ++z)
        for (uint32_t y = a[1]; y <= b[1]; ++y) {
            const uint32_t c0 = (z * g->res[1] + y) * g->res[0] + a[0], c1 = c0 + (b[0] - a[0]);
            float blo[2], bhi[2];
            clvr_entry_cell_span(g, 1, y, &blo[0], &bhi[0]);
            clvr_entry_cell_span(g, 2, z, &blo[1], &bhi[1]);
            for (uint32_t w = c0 / 32u; w <= c1 / 32u; ++w) {
                const uint32_t bits = clvr_occupancy_row_bits(g, &sl, w, c0, c1, a[0], blo, bhi, 0xffffffffu);
                TU_CHECK((bits & ~clvr_occupancy_mask(w == c0 / 32u ? c0 % 32u : 0u, w == c1 / 32u ? c1 % 32u : 31u)) == 0u);
                words[w] |= bits;
                set += (uint32_t)__builtin_popcount(bits);
            }
        }
    return set;
}

static void test_occupancy_slabs(void)
{
    clvr_entry_grid g;
    memset(&g, 0, sizeof g);
    for (int a = 0; a < 3; ++a) { /* cells 1 .. 8 of 10 over the unit cube; 0 and 9 reach out to infinity */
        g.lo[a] = -0.125f;
        g.scale[a] = 8.0f;
        g.res[a] = 10u;
    }
    uint32_t words[4096];
    memset(words, 0, 32 * sizeof *words);
    const clvr_vec4 tet[4] = {{0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
    occ_bits_of(&g, CLVR_CELL_TET, tet, words);
    int wrong = 0, inner = 0;
    for (uint32_t c = 0; c < 1000u; ++c) {
        const uint32_t i = c % 10u, j = c / 10u % 10u, k = c / 100u;
        if (i < 1u || i > 8u || j < 1u || j > 8u || k < 1u || k > 8u) continue;
        const int bit = (int)((words[c / 32u] >> (c % 32u)) & 1u);
        inner += bit;
        wrong += bit != (i + j + k - 3u <= 8u);
    }
    TU_CHECK_EQ_U64(wrong, 0);
    TU_CHECK_EQ_U64(inner, 162u); /* of the 512 the box keeps */

    uint64_t rs = 77;
    int lost = 0;
    uint32_t kept = 0, boxed = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const uint32_t type = (uint32_t)trial % CLVR_CELL_TYPE_COUNT;
        /* a unit cube's corners (or a tet's, pyramid's, wedge's in it),
         * jittered, scaled and moved; grid res 3 .. 15 over the box */
        static const float hexc[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
        static const float tetc[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.3f, 0.2f, 1}};
        static const float pyrc[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.4f, 1}};
        static const float wedc[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
        const float(*cn)[3] = type == CLVR_CELL_TET ? tetc : type == CLVR_CELL_PYRAMID ? pyrc
                              : type == CLVR_CELL_WEDGE ? wedc : hexc;
        const float sc = 0.01f + 10.0f * tu_randf(&rs);
        clvr_vec4 v[8];
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) {
            float p[3];
            for (int a = 0; a < 3; ++a) {
                p[a] = 1000.0f + sc * (cn[i][a] + 0.3f * (tu_randf(&rs) - 0.5f));
                lo[a] = fminf(lo[a], p[a]);
                hi[a] = fmaxf(hi[a], p[a]);
            }
            v[i].x = p[0];
            v[i].y = p[1];
            v[i].z = p[2];
            v[i].w = 0.0f;
        }
        /* the grid: over the element's box grown by up to a third, a
         * random rotation of the axes' resolutions */
        uint64_t cells = 1;
        for (int a = 0; a < 3; ++a) {
            const float ext = hi[a] - lo[a], grow = ext * 0.33f * tu_randf(&rs);
            g.res[a] = 3u + (uint32_t)(tu_rand(&rs) % 13u);
            g.lo[a] = lo[a] - grow;
            g.scale[a] = (float)g.res[a] / (ext + 2.0f * grow);
            cells *= g.res[a];
        }
        memset(words, 0, (size_t)((cells + 31u) / 32u) * sizeof *words);
        kept += occ_bits_of(&g, type, v, words);
        float blo[3], bhi[3];
        clvr_element_slabs sl;
        uint32_t a[3], b[3];
        clvr_element_hull(type, v, blo, bhi, &sl);
        clvr_entry_box_cells(&g, blo, bhi, a, b);
        boxed += (b[0] - a[0] + 1u) * (b[1] - a[1] + 1u) * (b[2] - a[2] + 1u);
        for (int q = 0; q < 300; ++q) {
            float u = tu_randf(&rs), w1 = tu_randf(&rs), w2 = tu_randf(&rs);
            if (q % 3 == 1) u = (float)(tu_rand(&rs) & 1u); /* on a face (or an edge, a corner) */
            if (q % 3 == 2) u = w1 = (float)(tu_rand(&rs) & 1u);
            if (type == CLVR_CELL_TET || type == CLVR_CELL_WEDGE) {
                if (u + w1 > 1.0f) {
                    const float t = u + w1;
                    u /= t;
                    w1 /= t;
                }
                if (type == CLVR_CELL_TET && u + w1 + w2 > 1.0f) w2 = 1.0f - u - w1;
            }
            float p[3];
            clvr_element_forward(type, v, u, w1, w2, &p[0], &p[1], &p[2]);
            uint32_t cc[3];
            const uint32_t oc = clvr_occupancy_cell(&g, p[0], p[1], p[2], cc);
            lost += !((words[oc / 32u] >> (oc % 32u)) & 1u);
        }
    }
    TU_CHECK_EQ_U64(lost, 0);
    /* the slabs cut something off the boxes (about a quarter here) */
    printf("occupancy slabs: %u of %u cells of the element boxes kept\n", kept, boxed);
    TU_CHECK(kept < boxed * 0.9);
}

int main(void)
{
    test_arithmetic();
    test_entry_layout();
    test_occupancy_slabs();
    test_many_candidates();
    test_bad_input();
    clvr_cl cl;
    tu_open_device(&cl);
    clvr_bvh_kernels k;
    clvr_error err = {0};
    if (clvr_bvh_kernels_create(&cl, &k, &err) != CLVR_OK) {
        fprintf(stderr, "bvh.cl: %s\n", err.msg);
        TU_CHECK(!"bvh.cl builds");
        clvr_cl_destroy(&cl);
        return tu_finish("test_bvh");
    }
    test_device_sizes(&cl, &k);
    const uint32_t sizes[] = {0, 1, 2, 4, 5, 17, 63, 64, 65, 257, 1031};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) test_boxes(&cl, &k, sizes[i]);
    test_generated(&cl, &k);
    test_files(&cl, &k);
    clvr_bvh_kernels_destroy(&k);
    clvr_cl_destroy(&cl);
    return tu_finish("test_bvh");
}
