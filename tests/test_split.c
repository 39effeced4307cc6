/* test_split: arrays of instance clusters cut into pieces below the device's
 * largest allocation (docs/large-meshes.md, "Device buffers above
 * CL_DEVICE_MAX_MEM_ALLOC_SIZE").
 * 1. CLVR_MAX_ALLOC_BYTES only lowers the limit and refuses bad values;
 * 2. the piece planner (clvr_partition_pieces) on a real instance table:
 *    the number of pieces for a limit, every piece at or below it, the
 *    error for a limit below one instance cluster and for more than
 *    CLVR_MAX_SPLITS pieces;
 * 3. the same mixed mesh (tets, pyramids, wedges, hexes), 16- and 32-bit
 *    local indices, preprocessed with the limit forced so that its arrays
 *    take 2, 3 and 4 pieces against the unsplit result: every device
 *    buffer at or below the limit, the arrays read back whole bit for bit
 *    the same (element boxes too), and at random points the same element
 *    ids and bit-identical interpolated values (device point location over
 *    all pieces, full walk and chained hints);
 * 4. renders (dda and bins, shadows on) of 2, 3 and 4 pieces against the
 *    unsplit one, same in distribution (per pixel and per 4x4 block,
 *    difference of means within 5 standard errors, as test_partition);
 * 5. the device check (clvr_limits_check_parts) accepts split arrays that
 *    fit in CLVR_MAX_SPLITS pieces and refuses, with the numbers, more
 *    pieces and a partition whose own buffers exceed the limit.
 * The limit is lowered as CLVR_MAX_ALLOC_BYTES lowers it (clvr_cl's
 * max_alloc_bytes) for preprocessing, trees and renders alike; the mesh is
 * big enough (2M elements) that its pieces exceed the preprocessing's own
 * fixed scratch (split hash maps: 8 MB for 16-bit, 16 MB per table for 32-bit
 * instances) and the renderer's grids. */
#include "accel.h"
#include "bvh_fixture.h"
#include "camera.h"
#include "limits_check.h"
#include "partition.h"
#include "render.h"
#include "render_fixture.h"
#include "test_util.h"
#include "tf.h"

#include <stdlib.h>

#define K_SIGMA 5.0
#define PARTS 12u /* partitions: enough instance clusters to cut between */

/* Preprocesses m in PARTS partitions with the allocation limit lowered to
 * `limit` (0: the device's) and builds its trees; the limit stays lowered
 * (the caller's renders run under it too) until the caller restores it. */
static clvr_status prepare_curve(clvr_cl *cl, const clvr_mesh *m, uint32_t bits, uint64_t limit, int one_curve,
                                 clvr_clustered *c, clvr_accel *a, clvr_error *err)
{
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.index_bits = bits;
    o.one_curve = one_curve;
    clvr_mesh mm = *m; /* not consumed: a shallow copy is enough */
    cl->max_alloc_bytes = limit ? limit : cl->device_max_alloc_bytes;
    clvr_status s = clvr_preprocess_partitioned(cl, &mm, &o, PARTS, 0, 0, c, NULL, err);
    if (s == CLVR_OK) s = clvr_accel_build(cl, c, a, err);
    return s;
}

static clvr_status prepare(clvr_cl *cl, const clvr_mesh *m, uint32_t bits, uint64_t limit, clvr_clustered *c,
                           clvr_accel *a, clvr_error *err)
{
    return prepare_curve(cl, m, bits, limit, CLVR_ONE_CURVE_OFF, c, a, err); /* the types' curves: more instances to cut between */
}

/* 1 when sorted element e of the unsplit host arrays h (ninst instances)
 * holds p, its value in *s (clvr_element_sample). */
static int holds(const clvr_clustered_host *h, uint64_t ninst, uint32_t e, const float *p, float *s)
{
    uint64_t lo = 0, hi = ninst; /* the last instance whose first element is <= e */
    while (hi - lo > 1) {
        const uint64_t mid = (lo + hi) / 2;
        if (h->instances[mid].first_element <= e) lo = mid;
        else hi = mid;
    }
    const clvr_instance *in = &h->instances[lo];
    if (!ninst || e - in->first_element >= in->num_elements) return 0;
    const clvr_mesh_view mv = {NULL, NULL, h->instances, (const clvr_vec4 *)h->vertices, h->idx16, h->idx32, 0, 0,
                               NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
    clvr_vec4 v[CLVR_CELL_MAX_VERTS];
    clvr_load_element(&mv, in, e, v);
    return clvr_element_sample(in->type, v, p[0], p[1], p[2], s);
}

static uint64_t mem_size(cl_mem b)
{
    size_t n = 0;
    if (b && clGetMemObjectInfo(b, CL_MEM_SIZE, sizeof n, &n, NULL) != CL_SUCCESS) return UINT64_MAX;
    return n;
}

/* Pieces clvr_partition_pieces makes of instance table `inst` for `limit`
 * (0 on an error), on a copy. */
static uint32_t pieces_for(const clvr_clustered *c, const clvr_instance *inst, uint64_t limit)
{
    clvr_instance *t = malloc(c->num_instances * sizeof *t);
    memcpy(t, inst, c->num_instances * sizeof *t);
    clvr_clustered cc = *c;
    clvr_error err = {0};
    clvr_status s = clvr_partition_pieces(t, c->num_instances, limit, 1, NULL, &cc, &err);
    free(t);
    return s == CLVR_OK ? cc.num_pieces : 0;
}

/* Smallest limit that gives at most k pieces (bisection: fewer pieces never
 * need a smaller limit). */
static uint64_t limit_for(const clvr_clustered *c, const clvr_instance *inst, uint32_t k)
{
    uint64_t lo = 16, hi = 1ull << 40;
    while (lo < hi) {
        const uint64_t mid = lo + (hi - lo) / 2, p = pieces_for(c, inst, mid);
        if (p != 0 && p <= k) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

static void test_env(void)
{
    clvr_cl cl;
    clvr_error err = {0};
    setenv("CLVR_MAX_ALLOC_BYTES", "123456", 1);
    TU_CHECK_STATUS(clvr_cl_create(NULL, &cl, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(cl.max_alloc_bytes, 123456);
    TU_CHECK(cl.device_max_alloc_bytes > 123456);
    clvr_cl_destroy(&cl);
    setenv("CLVR_MAX_ALLOC_BYTES", "99999999999999999", 1); /* above the device's: only lowers */
    TU_CHECK_STATUS(clvr_cl_create(NULL, &cl, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(cl.max_alloc_bytes, cl.device_max_alloc_bytes);
    clvr_cl_destroy(&cl);
    const char *bad[] = {"12abc", "-5", "0", "lots"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        setenv("CLVR_MAX_ALLOC_BYTES", bad[i], 1);
        TU_CHECK_STATUS(clvr_cl_create(NULL, &cl, &err), CLVR_ERR_USAGE, &err);
        TU_CHECK(strstr(err.msg, "CLVR_MAX_ALLOC_BYTES") && strstr(err.msg, bad[i]));
    }
    unsetenv("CLVR_MAX_ALLOC_BYTES");
}

/* Element boxes read back whole (pieces concatenated). */
static uint8_t *read_ebox(clvr_cl *cl, const clvr_clustered *c, const clvr_accel *a)
{
    cl_mem eb[CLVR_MAX_SPLITS];
    clvr_accel_get_ebox_pieces(c, a, eb);
    uint8_t *out = malloc(c->num_elements * CLVR_EBOX_BYTES + 1);
    const uint32_t np = c->num_pieces > 1 ? c->num_pieces : 1;
    for (uint32_t p = 0; p < np; ++p) {
        const uint64_t e0 = np > 1 ? c->piece_elements[p] : 0, e1 = np > 1 ? c->piece_elements[p + 1] : c->num_elements;
        if (e1 > e0)
            clEnqueueReadBuffer(cl->queue, eb[p], CL_TRUE, 0, (e1 - e0) * CLVR_EBOX_BYTES, out + e0 * CLVR_EBOX_BYTES,
                                0, NULL, NULL);
    }
    return out;
}

/* Mean and variance per pixel and channel over n frames of c (dda or
 * bins, shadows on). */
static int render_moments_counted(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a,
                                  uint32_t method, uint32_t estimator, uint32_t W, uint32_t H, uint32_t n, float **mean,
                                  float **var, clvr_render_counters *counters)
{
    clvr_error err = {0};
    clvr_render_settings set;
    clvr_render_settings_default(&set);
    if (estimator != CLVR_ESTIMATOR_COUNT) set.estimator = estimator;
    set.width = W;
    set.height = H;
    set.method = method;
    set.shadows = 1;
    set.sampler = CLVR_SAMPLER_INDEPENDENT; /* per-pixel error bars need independent frames */
    clvr_status s = fx_render_moments_counted(cl, m, c, a, &set, NULL, NULL, 2.0f, n, mean, var, counters, &err);
    if (s != CLVR_OK) fprintf(stderr, "render, %u pieces: %s\n", c->num_pieces, err.msg);
    return s != CLVR_OK;
}

static int render_moments_est(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a, uint32_t method,
                              uint32_t estimator, uint32_t W, uint32_t H, uint32_t n, float **mean, float **var)
{
    return render_moments_counted(cl, m, c, a, method, estimator, W, H, n, mean, var, NULL);
}

static int render_moments(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a, uint32_t method,
                          uint32_t W, uint32_t H, uint32_t n, float **mean, float **var)
{
    return render_moments_est(cl, m, c, a, method, CLVR_ESTIMATOR_COUNT, W, H, n, mean, var);
}

/* 4. Renders of c (dda and bins, shadows on) against the unsplit one's
 * moments base_m, base_v (computed first, with c the unsplit mesh and
 * base_m[0] NULL). */
enum { NM = 2, RW = 32, RH = 32, RN = 64 };
static const uint32_t methods[NM] = {CLVR_RENDER_DDA, CLVR_RENDER_BINS};
static void compare_renders(clvr_cl *cl, const clvr_mesh *m, clvr_clustered *c, clvr_accel *a, float **base_m,
                            float **base_v)
{
    const uint32_t W = RW, H = RH, n = RN;
    for (int mi = 0; mi < NM; ++mi) {
        if (!base_m[mi]) {
            TU_CHECK(!render_moments(cl, m, c, a, methods[mi], W, H, n, &base_m[mi], &base_v[mi]));
            double signal = 0;
            for (size_t i = 3; i < (size_t)W * H * 4; i += 4) signal += base_m[mi][i];
            TU_CHECK(signal > 0.05 * W * H); /* the volume covers part of the image: the test can fail */
            continue;
        }
        float *mk, *vk;
        TU_CHECK(!render_moments(cl, m, c, a, methods[mi], W, H, n, &mk, &vk));
        const float *m1 = base_m[mi], *v1 = base_v[mi];
        const size_t np = (size_t)W * H * 4;
        size_t same = 0;
        for (size_t i = 0; i < np; ++i) same += m1[i] == mk[i];
        const fx_moments_diff r = fx_compare_moments(m1, v1, mk, vk, W, H, n, K_SIGMA);
        /* The same seeds and the same walk: the images are in fact equal
         * bit for bit (printed); the test asks for the distribution only. */
        printf("%s with shadows, %u pieces: %zu pixels and %zu blocks beyond %.0f sigma, largest block |z| %.2f, "
               "%zu of %zu values identical\n",
               clvr_render_method_name(methods[mi]), c->num_pieces, r.pixels, r.blocks, K_SIGMA, r.worst_block_z, same,
               np);
        TU_CHECK_EQ_U64(r.pixels, 0);
        TU_CHECK_EQ_U64(r.blocks, 0);
        TU_CHECK_EQ_U64(r.channels, 0);
        free(mk);
        free(vk);
    }
}

/* Sections 2 and 3 (and 4 when render != 0) for one index width; returns
 * the limits of 2, 3 and 4 pieces in lim[2..4]. */
static void test_pieces(clvr_cl *cl, const clvr_mesh *m, uint32_t bits, int render, uint64_t lim[5])
{
    float *base_m[NM] = {NULL}, *base_v[NM] = {NULL};
    clvr_error err = {0};
    clvr_clustered c1 = {0};
    clvr_accel a1 = {0};
    clvr_clustered_host h1 = {0};
    TU_CHECK_STATUS(prepare(cl, m, bits, 0, &c1, &a1, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(c1.num_pieces, 1);
    if (render) compare_renders(cl, m, &c1, &a1, base_m, base_v);
    TU_CHECK_STATUS(clvr_clustered_download(cl, &c1, &h1, &err), CLVR_OK, &err);
    TU_CHECK(c1.num_instances >= 16);
    uint64_t n16 = 0, n32 = 0, largest = 0;
    for (uint64_t i = 0; i < c1.num_instances; ++i) {
        n16 += h1.instances[i].index_bits == 16;
        n32 += h1.instances[i].index_bits == 32;
        const uint64_t nv = clvr_cell_vertex_count(h1.instances[i].type), ne = h1.instances[i].num_elements;
        const uint64_t b[4] = {h1.instances[i].num_vertices * 16ull, ne * nv * (bits / 8), ne * 6};
        for (int k = 0; k < 3; ++k) largest = b[k] > largest ? b[k] : largest;
    }
    TU_CHECK_EQ_U64(bits == 16 ? n16 : n32, c1.num_instances);
    uint32_t types = 0;
    for (uint64_t i = 0; i < c1.num_instances; ++i) types |= 1u << h1.instances[i].type;
    TU_CHECK_EQ_U64(types, 15); /* all four element types */

    /* 2. The planner: limits for 2, 3, 4 pieces; below one instance and
     * more than CLVR_MAX_SPLITS pieces fail with their messages. */
    for (uint32_t k = 2; k <= 4; ++k) {
        lim[k] = limit_for(&c1, h1.instances, k);
        TU_CHECK_EQ_U64(pieces_for(&c1, h1.instances, lim[k]), k);
        TU_CHECK(lim[k] >= largest);
    }
    TU_CHECK(lim[4] < lim[3] && lim[3] < lim[2]);
    {
        clvr_instance *t = malloc(c1.num_instances * sizeof *t);
        clvr_clustered cc = c1;
        memcpy(t, h1.instances, c1.num_instances * sizeof *t);
        TU_CHECK_STATUS(clvr_partition_pieces(t, c1.num_instances, largest - 1, 1, "split.bin", &cc, &err),
                        CLVR_ERR_DEVICE_MEMORY, &err);
        TU_CHECK(strstr(err.msg, "split.bin") && strstr(err.msg, "alone needs") && strstr(err.msg, "per buffer"));
        printf("one instance above the limit: %s\n", err.msg);
        memcpy(t, h1.instances, c1.num_instances * sizeof *t);
        if (lim[4] - 1 >= largest) {
            TU_CHECK_STATUS(clvr_partition_pieces(t, c1.num_instances, lim[4] - 1, 1, "split.bin", &cc, &err),
                            CLVR_ERR_DEVICE_MEMORY, &err);
            TU_CHECK(strstr(err.msg, "more than 4 pieces") && strstr(err.msg, "split.bin"));
        }
        free(t);
    }

    /* 3. Preprocessed with the limit lowered: k pieces, each at or below
     * the limit, the same arrays and the same point location. */
    enum { NPTS = 20000 };
    float *pts = malloc(NPTS * 4 * sizeof(float)), *s1 = malloc(NPTS * 4), *sk = malloc(NPTS * 4);
    uint32_t *e1 = malloc(NPTS * 4), *ek = malloc(NPTS * 4);
    uint64_t rng = 0x5eed0000u + bits;
    for (int i = 0; i < NPTS; ++i) {
        for (int k = 0; k < 3; ++k)
            pts[4 * i + k] = m->bounds_lo[k] + tu_randf(&rng) * (m->bounds_hi[k] - m->bounds_lo[k]);
        pts[4 * i + 3] = 0.0f;
    }
    uint8_t *ebox1 = read_ebox(cl, &c1, &a1);
    /* CLVR_TEST_BRIEF (the sanitizer build, CMakeLists.txt): 4 pieces
     * only, the most and the same code as 2 and 3, which the plain build
     * checks; with all three the whole test took 280 s under ASan of a
     * 31-minute CI run. */
    const int brief = tu_brief();
    for (uint32_t k = brief ? 4 : 2; k <= 4; ++k) {
        clvr_clustered ck = {0};
        clvr_accel ak = {0};
        clvr_clustered_host hk = {0};
        TU_CHECK_STATUS(prepare(cl, m, bits, lim[k], &ck, &ak, &err), CLVR_OK, &err);
        TU_CHECK_EQ_U64(ck.num_pieces, k);
        clvr_clustered_pieces pc;
        cl_mem eb[CLVR_MAX_SPLITS];
        clvr_clustered_get_pieces(&ck, &pc);
        clvr_accel_get_ebox_pieces(&ck, &ak, eb);
        uint64_t over = 0, pieces_used[3] = {0};
        for (uint32_t p = 0; p < ck.num_pieces; ++p) {
            over += mem_size(pc.vertices[p]) > lim[k];
            over += mem_size(pc.idx16[p]) > lim[k];
            over += mem_size(pc.idx32[p]) > lim[k];
            over += mem_size(eb[p]) > lim[k];
        }
        TU_CHECK_EQ_U64(over, 0);
        for (uint64_t i = 0; i < ck.num_instances; ++i) { /* pieces in order, each used */
            const uint32_t p = ck.host_instances[i].piece;
            pieces_used[0] |= 1u << p;
            if (i) pieces_used[1] += p < ck.host_instances[i - 1].piece;
        }
        TU_CHECK_EQ_U64(pieces_used[0], (1u << k) - 1);
        TU_CHECK_EQ_U64(pieces_used[1], 0);
        TU_CHECK_STATUS(clvr_clustered_download(cl, &ck, &hk, &err), CLVR_OK, &err);
        TU_CHECK_EQ_U64(ck.num_vertices, c1.num_vertices);
        TU_CHECK_EQ_U64(ck.num_instances, c1.num_instances);
        if (ck.num_vertices == c1.num_vertices && ck.num_instances == c1.num_instances) {
            TU_CHECK(!memcmp(hk.vertices, h1.vertices, c1.num_vertices * 16));
            TU_CHECK(!memcmp(hk.idx16, h1.idx16, c1.num_idx16 * 2));
            TU_CHECK(!memcmp(hk.idx32, h1.idx32, c1.num_idx32 * 4));
            TU_CHECK(!memcmp(hk.instances, h1.instances, c1.num_instances * sizeof(clvr_instance)));
            uint8_t *eboxk = read_ebox(cl, &ck, &ak);
            TU_CHECK(!memcmp(eboxk, ebox1, c1.num_elements * CLVR_EBOX_BYTES));
            free(eboxk);
        }
        const struct { uint32_t hints, chain; } modes[] = {
            {CLVR_LOCATE_COHERENT, 1}, {CLVR_LOCATE_INCOHERENT, 1}, {CLVR_LOCATE_COHERENT, 24}};
        for (size_t q = 0; q < sizeof modes / sizeof modes[0]; ++q) {
            TU_CHECK_STATUS(clvr_accel_locate(cl, &c1, &a1, pts, NPTS, modes[q].hints, modes[q].chain, s1, e1, &err),
                            CLVR_OK, &err);
            TU_CHECK_STATUS(clvr_accel_locate(cl, &ck, &ak, pts, NPTS, modes[q].hints, modes[q].chain, sk, ek, &err),
                            CLVR_OK, &err);
            /* The same element and value bit for bit, except where the
             * lowered limit gave the entry cells coarser global hints
             * (clvr_entry_grids_layout) and a search starting elsewhere
             * found another element that also holds the point (on a face
             * both share): both must hold it, the value must be its
             * element's, and such points must be rare. */
            uint64_t found = 0, diff_e = 0, diff_s = 0, shared = 0;
            for (int i = 0; i < NPTS; ++i) {
                found += e1[i] != CLVR_BVH_NOT_FOUND;
                if (e1[i] != ek[i]) {
                    float a = 0.0f, b = 0.0f;
                    const int both = e1[i] != CLVR_BVH_NOT_FOUND && ek[i] != CLVR_BVH_NOT_FOUND &&
                                     holds(&h1, c1.num_instances, e1[i], pts + 4 * i, &a) &&
                                     holds(&h1, c1.num_instances, ek[i], pts + 4 * i, &b) &&
                                     fabsf(b - sk[i]) <= 1e-5f * fmaxf(1.0f, fabsf(b));
                    shared += both;
                    diff_e += !both;
                    continue;
                }
                diff_s += e1[i] != CLVR_BVH_NOT_FOUND && memcmp(&s1[i], &sk[i], sizeof(float)) != 0;
            }
            if (diff_e || diff_s || shared)
                fprintf(stderr,
                        "%u-bit, %u pieces, hints %u chain %u: %llu of %d element ids wrong, %llu values differ, "
                        "%llu points on a face found in the other element\n",
                        bits, k, modes[q].hints, modes[q].chain, (unsigned long long)diff_e, NPTS,
                        (unsigned long long)diff_s, (unsigned long long)shared);
            TU_CHECK(found > NPTS / 2); /* the points are mostly inside: the comparison can fail */
            TU_CHECK_EQ_U64(diff_e, 0);
            TU_CHECK_EQ_U64(diff_s, 0);
            TU_CHECK(shared <= NPTS / 1000u);
        }
        if (render) compare_renders(cl, m, &ck, &ak, base_m, base_v);
        clvr_clustered_host_free(&hk);
        clvr_accel_release(cl, &ak);
        clvr_clustered_release(cl, &ck);
    }
    /* More pieces than CLVR_MAX_SPLITS through the whole preprocessing: the
     * planner's message, nothing left allocated. */
    if (lim[4] - 1 >= largest) {
        clvr_clustered ck = {0};
        clvr_accel ak = {0};
        const cl_ulong before = cl->allocated_bytes;
        TU_CHECK_STATUS(prepare(cl, m, bits, lim[4] - 1, &ck, &ak, &err), CLVR_ERR_DEVICE_MEMORY, &err);
        TU_CHECK(strstr(err.msg, "more than 4 pieces") != NULL);
        TU_CHECK_EQ_U64(cl->allocated_bytes, before);
        clvr_accel_release(cl, &ak);
        clvr_clustered_release(cl, &ck);
    }
    for (int mi = 0; mi < NM; ++mi) {
        free(base_m[mi]);
        free(base_v[mi]);
    }
    free(ebox1);
    free(pts);
    free(s1);
    free(sk);
    free(e1);
    free(ek);
    clvr_clustered_host_free(&h1);
    clvr_accel_release(cl, &a1);
    clvr_clustered_release(cl, &c1);
}

/* 5. The device check from counts. */
/* 5. One curve (clvr_preprocess_options.one_curve), in PARTS partitions:
 * every clustered cell of the mixed mesh a collapsed hex, fewer instances
 * (each holds every type of its region), the same point location as one
 * curve per type (the same points found, the same values: bit for bit where
 * the same element holds the point, its collapsed hex taking the type's own
 * test; within rounding where a point on a face both share was found in
 * the other one) and renders with the same distribution. */
static void test_one_curve(clvr_cl *cl, const clvr_mesh *m)
{
    float *base_m[NM] = {NULL}, *base_v[NM] = {NULL};
    clvr_error err = {0};
    clvr_clustered c1 = {0}, c2 = {0};
    clvr_accel a1 = {0}, a2 = {0};
    TU_CHECK_STATUS(prepare_curve(cl, m, 16, 0, CLVR_ONE_CURVE_OFF, &c1, &a1, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(prepare_curve(cl, m, 16, 0, CLVR_ONE_CURVE_ON, &c2, &a2, &err), CLVR_OK, &err);
    if (!c1.instances || !c2.instances) return;
    TU_CHECK_EQ_U64(c2.num_cells[CLVR_CELL_HEX], c2.num_elements);
    TU_CHECK(c1.num_cells[CLVR_CELL_HEX] < c1.num_elements); /* the mesh is mixed: the test can fail */
    uint64_t hexes = 0;
    for (uint64_t i = 0; i < c2.num_instances; ++i) hexes += c2.host_instances[i].type == CLVR_CELL_HEX;
    TU_CHECK_EQ_U64(hexes, c2.num_instances);
    printf("one curve: %llu instances (one curve per type: %llu)\n", (unsigned long long)c2.num_instances,
           (unsigned long long)c1.num_instances);
    TU_CHECK(c2.num_instances < c1.num_instances);
    enum { NPTS = 20000 };
    float *pts = malloc(NPTS * 4 * sizeof(float)), *s1 = malloc(NPTS * 4), *s2 = malloc(NPTS * 4);
    uint32_t *e1 = malloc(NPTS * 4), *e2 = malloc(NPTS * 4);
    uint64_t rng = 0x0ce0c0u;
    for (int i = 0; i < NPTS; ++i) {
        for (int k = 0; k < 3; ++k)
            pts[4 * i + k] = m->bounds_lo[k] + tu_randf(&rng) * (m->bounds_hi[k] - m->bounds_lo[k]);
        pts[4 * i + 3] = 0.0f;
    }
    TU_CHECK_STATUS(clvr_accel_locate(cl, &c1, &a1, pts, NPTS, CLVR_LOCATE_COHERENT, 1, s1, e1, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_accel_locate(cl, &c2, &a2, pts, NPTS, CLVR_LOCATE_COHERENT, 1, s2, e2, &err), CLVR_OK, &err);
    uint64_t found = 0, diff_found = 0, same = 0, close = 0, far = 0;
    float worst = 0.0f;
    for (int i = 0; i < NPTS; ++i) {
        const int f1 = e1[i] != CLVR_BVH_NOT_FOUND, f2 = e2[i] != CLVR_BVH_NOT_FOUND;
        found += f1;
        diff_found += f1 != f2;
        if (!f1 || !f2) continue;
        const float d = fabsf(s1[i] - s2[i]);
        worst = fmaxf(worst, d);
        if (memcmp(&s1[i], &s2[i], sizeof(float)) == 0) ++same;
        else if (d <= 1e-5f * fmaxf(1.0f, fabsf(s1[i]))) ++close;
        else ++far;
    }
    printf("one curve: %llu of %d points found, %llu found by one side only; values: %llu identical, %llu within "
           "1e-5, %llu further (largest difference %g)\n",
           (unsigned long long)found, NPTS, (unsigned long long)diff_found, (unsigned long long)same,
           (unsigned long long)close, (unsigned long long)far, (double)worst);
    TU_CHECK(found > NPTS / 2);
    TU_CHECK_EQ_U64(diff_found, 0);
    TU_CHECK_EQ_U64(far, 0);
    TU_CHECK(same > found * 9 / 10);
    compare_renders(cl, m, &c1, &a1, base_m, base_v);
    compare_renders(cl, m, &c2, &a2, base_m, base_v);
    for (int mi = 0; mi < NM; ++mi) { free(base_m[mi]); free(base_v[mi]); }
    /* The hull takes a collapsed hex as the cell it is: the same boundary
     * faces (a collapsed tet's extra slots hold none), and the walk crosses
     * the same shared faces, through every cell type (walk) and through tets
     * with urm elsewhere (auto), to the same image. */
    clvr_hull hl1 = {0}, hl2 = {0};
    TU_CHECK_STATUS(clvr_hull_build(cl, &a1.kernels, &c1, a1.sampling_nodes, CLVR_HULL_ON, &hl1, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_hull_build(cl, &a2.kernels, &c2, a2.sampling_nodes, CLVR_HULL_ON, &hl2, &err), CLVR_OK, &err);
    printf("one curve: %u boundary faces (one curve per type: %u)\n", hl2.num_faces, hl1.num_faces);
    TU_CHECK_EQ_U64(hl2.num_faces, hl1.num_faces);
    TU_CHECK(hl1.num_faces > 0);
    clvr_hull_release(cl, &hl1);
    clvr_hull_release(cl, &hl2);
    const uint32_t ests[2] = {CLVR_ESTIMATOR_WALK, CLVR_ESTIMATOR_AUTO};
    for (int k = 0; k < 2; ++k) {
        float *m1 = NULL, *v1 = NULL, *mk = NULL, *vk = NULL;
        clvr_render_counters n1 = {0}, n2 = {0};
        TU_CHECK(!render_moments_counted(cl, m, &c1, &a1, CLVR_RENDER_DDA, ests[k], RW, RH, RN, &m1, &v1, &n1));
        TU_CHECK(!render_moments_counted(cl, m, &c2, &a2, CLVR_RENDER_DDA, ests[k], RW, RH, RN, &mk, &vk, &n2));
        if (!m1 || !mk) continue;
        /* The same walk through the same cells, so the same work per ray
         * (equal to three decimals here). A walk that took a collapsed tet
         * for a hex fails at its faces and falls back to urm's lookups:
         * the image stays right, so only this count shows it (session 55,
         * clvr_walk_load without the decode: walk 24.34 samples per ray
         * against 25.63; auto moved 0.2% only, under the tolerance). */
        const double w1 = (double)n1.samples / (double)(n1.rays ? n1.rays : 1);
        const double w2 = (double)n2.samples / (double)(n2.rays ? n2.rays : 1);
        printf("one curve, dda %s: %.3f samples per ray (one curve per type: %.3f; rays %llu, %llu)\n",
               k ? "auto" : "walk", w2, w1, (unsigned long long)n2.rays, (unsigned long long)n1.rays);
        TU_CHECK(n1.rays > 0 && fabs((double)n2.rays - (double)n1.rays) <= 0.01 * (double)n1.rays);
        TU_CHECK(fabs(w2 - w1) <= 0.02 * w1);
        const fx_moments_diff r = fx_compare_moments(m1, v1, mk, vk, RW, RH, RN, K_SIGMA);
        printf("one curve, dda %s with shadows: %zu pixels and %zu blocks beyond %.0f sigma, largest block |z| %.2f\n",
               k ? "auto" : "walk", r.pixels, r.blocks, K_SIGMA, r.worst_block_z);
        TU_CHECK_EQ_U64(r.pixels, 0);
        TU_CHECK_EQ_U64(r.blocks, 0);
        TU_CHECK_EQ_U64(r.channels, 0);
        free(m1); free(v1); free(mk); free(vk);
    }
    free(pts); free(s1); free(s2); free(e1); free(e2);
    clvr_accel_release(cl, &a1);
    clvr_accel_release(cl, &a2);
    clvr_clustered_release(cl, &c1);
    clvr_clustered_release(cl, &c2);
}

static void test_check(void)
{
    clvr_error err = {0};
    clvr_mesh m = {0};
    m.num_vertices = 250000000;
    m.num_cells[CLVR_CELL_HEX] = 250000000; /* 4 GB of 16-bit indices, 0.5 GB of leaf boxes */
    clvr_cl cl = {0};
    snprintf(cl.device_name, sizeof cl.device_name, "test device");
    cl.global_mem_bytes = 1ull << 50;
    cl.device_max_alloc_bytes = 1ull << 40;
    const uint64_t part = 4u << 20;
    cl.max_alloc_bytes = 1050000000; /* 4 pieces of 1.05 GB hold 4 GB */
    TU_CHECK_STATUS(clvr_limits_check_parts(&cl, &m, "big.bin", NULL, part, 256, 256, &err), CLVR_OK, &err);
    cl.max_alloc_bytes = 950000000; /* 5 pieces: refused with the numbers */
    TU_CHECK_STATUS(clvr_limits_check_parts(&cl, &m, "big.bin", NULL, part, 256, 256, &err), CLVR_ERR_DEVICE_MEMORY,
                    &err);
    TU_CHECK(strstr(err.msg, "big.bin") && strstr(err.msg, "16-bit indices") && strstr(err.msg, "4.000 GB") &&
             strstr(err.msg, "5 pieces") && strstr(err.msg, "0.950 GB") && strstr(err.msg, "CLVR_MAX_SPLITS") &&
             strstr(err.msg, "CLVR_MAX_ALLOC_BYTES"));
    /* One partition: the arrays are single buffers, and more partitions are the fix. */
    cl.max_alloc_bytes = 1050000000;
    TU_CHECK_STATUS(clvr_limits_check_parts(&cl, &m, "big.bin", NULL, 0, 256, 256, &err), CLVR_ERR_DEVICE_MEMORY,
                    &err);
    TU_CHECK(strstr(err.msg, "--partitions") != NULL);
    /* A partition's own buffers above the limit: the partition count that fits. */
    cl.max_alloc_bytes = 100000000;
    TU_CHECK_STATUS(clvr_limits_check_parts(&cl, &m, "big.bin", NULL, 200u << 20, 256, 256, &err),
                    CLVR_ERR_DEVICE_MEMORY, &err);
    TU_CHECK(strstr(err.msg, "--partitions") && strstr(err.msg, "element indices"));
}

int main(void)
{
    test_env();
    test_check();
    clvr_cl cl;
    tu_open_device(&cl);
    clvr_error err = {0};
    clvr_mesh m = {0};
    /* Conforming mixed mesh (unjittered: see test_partition). */
    TU_CHECK_STATUS(fx_grid_mesh(80, FX_MIXED, 0.0f, 1.0f, 0.0f, 7, &m, &err), CLVR_OK, &err);
    clvr_mesh_update_ranges(&m);
    uint64_t lim16[5] = {0}, lim32[5] = {0};
    test_pieces(&cl, &m, 16, 1, lim16);
    test_pieces(&cl, &m, 32, 0, lim32);
    printf("mixed 80^3 (%llu elements), %u partitions: limits of 2/3/4 pieces %llu/%llu/%llu bytes (16-bit), "
           "%llu/%llu/%llu (32-bit)\n",
           (unsigned long long)clvr_mesh_num_elements(&m), PARTS, (unsigned long long)lim16[2],
           (unsigned long long)lim16[3], (unsigned long long)lim16[4], (unsigned long long)lim32[2],
           (unsigned long long)lim32[3], (unsigned long long)lim32[4]);
    clvr_mesh_free(&m);
    /* smaller: the point is the types on one curve, not the pieces */
    TU_CHECK_STATUS(fx_grid_mesh(40, FX_MIXED, 0.0f, 1.0f, 0.0f, 7, &m, &err), CLVR_OK, &err);
    clvr_mesh_update_ranges(&m);
    test_one_curve(&cl, &m);
    clvr_mesh_free(&m);
    clvr_cl_destroy(&cl);
    return tu_finish("test_split");
}
