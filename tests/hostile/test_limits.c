/* test_limits.c: host/cl/limits_check.c. The device-memory estimate against hand
 * computed sums, the check's two refusals (per buffer, global) with a fake
 * device description (no OpenCL needed), and the mesh scan on hand-built
 * degenerate, inverted and duplicate elements and on the real test files
 * (VTK's own element order must count as not inverted). */
#include "../test_util.h"

#include "limits_check.h"
#include "mesh_io.h"

/* A mesh holding only counts: the estimate reads nothing else. */
static clvr_mesh counts_only(uint64_t v, uint64_t tets, uint64_t hexes)
{
    clvr_mesh m;
    memset(&m, 0, sizeof m);
    m.num_vertices = v;
    m.num_cells[CLVR_CELL_TET] = tets;
    m.num_cells[CLVR_CELL_HEX] = hexes;
    return m;
}

static clvr_cl fake_device(uint64_t global, uint64_t max_alloc)
{
    clvr_cl cl;
    memset(&cl, 0, sizeof cl);
    snprintf(cl.device_name, sizeof cl.device_name, "fake device");
    cl.global_mem_bytes = global;
    cl.max_alloc_bytes = max_alloc;
    return cl;
}

static void test_estimate(void)
{
    clvr_limits_estimate e;
    clvr_mesh m = counts_only(1000, 300, 100); /* S = 1200 + 800 = 2000, N = 400 */
    clvr_limits_estimate_bytes(&m, NULL, 64, 32, &e);
    TU_CHECK_EQ_U64(e.num_elements, 400);
    TU_CHECK_EQ_U64(e.num_slots, 2000);
    /* sort phase 16*1000 + 4*2000 + 24*400 = 33600; split 16000 + 10*2000 = 36000 */
    TU_CHECK_EQ_U64(e.preprocess_peak_bytes, 36000);
    /* leaves 25: 2*2000 + 25*32 + (400/16)*32 + (25/3)*node + 6*400 (element boxes) + 24*19 + 72*7 + 400
     * (entry grids over 19 leaves of tets and 7 of hexes, occupancy grid) + 76*64*32 */
    TU_CHECK_EQ_U64(e.image_bytes, 76u * 64u * 32u);
    TU_CHECK_EQ_U64(e.render_bytes,
                    4000u + 800u + 800u + 8u * sizeof(clvr_bvh_node) + 6u * 400u + 24u * 19u + 72u * 7u + 400u + 76u * 64u * 32u);
    TU_CHECK_EQ_U64(e.peak_bytes, e.render_bytes > 36000 ? e.render_bytes : 36000);
    TU_CHECK_EQ_U64(e.largest_buffer_bytes, 16u * 64u * 32u);
    TU_CHECK(strcmp(e.largest_buffer, "image accumulator") == 0);

    clvr_limits_estimate_bytes(&m, NULL, 1, 1, &e);
    TU_CHECK_EQ_U64(e.largest_buffer_bytes, 12000); /* 12 * 1000 vertex positions */
    TU_CHECK(strcmp(e.largest_buffer, "vertex positions") == 0);

    /* 32-bit indices keep 4 bytes per slot resident and 12 in the split. */
    clvr_preprocess_options o;
    memset(&o, 0, sizeof o);
    o.index_bits = 32;
    clvr_limits_estimate_bytes(&m, &o, 1, 1, &e);
    TU_CHECK_EQ_U64(e.preprocess_peak_bytes, 16000u + 12u * 2000u);

    /* Counts whose sizes overflow 64 bits saturate instead of wrapping. */
    clvr_mesh huge = counts_only(UINT64_MAX / 2, UINT64_MAX / 3, UINT64_MAX / 5);
    clvr_limits_estimate_bytes(&huge, NULL, 65536, 65536, &e);
    TU_CHECK_EQ_U64(e.peak_bytes, UINT64_MAX);
    TU_CHECK_EQ_U64(e.largest_buffer_bytes, UINT64_MAX);
}

static void test_check(void)
{
    clvr_error err = {0};
    const uint64_t GB = 1000000000ull;
    clvr_cl dev = fake_device(GB, GB / 4);
    clvr_mesh small = counts_only(1000, 5000, 0);
    TU_CHECK_STATUS(clvr_limits_check(&dev, &small, NULL, 512, 512, &err), CLVR_OK, &err);

    /* 80M hexes: the element indices (2.56 GB) exceed the per-buffer limit. */
    clvr_mesh big = counts_only(1000, 0, 80000000);
    clvr_status s = clvr_limits_check_named(&dev, &big, "big.bin", NULL, 64, 64, &err);
    TU_CHECK_STATUS(s, CLVR_ERR_DEVICE_MEMORY, &err);
    TU_CHECK(strstr(err.msg, "big.bin: 80000000 elements") != NULL);
    TU_CHECK(strstr(err.msg, "element indices") != NULL);
    TU_CHECK(strstr(err.msg, "2.560 GB") != NULL);
    TU_CHECK(strstr(err.msg, "0.250 GB per buffer") != NULL);
    TU_CHECK(strstr(err.msg, "smaller (cropped or decimated) mesh") != NULL);
    if (tu_fail_) fprintf(stderr, "message: %s\n", err.msg);

    /* A 16384^2 image: the accumulator alone is 4.3 GB; the advice is --size. */
    s = clvr_limits_check(&dev, &small, NULL, 16384, 16384, &err);
    TU_CHECK_STATUS(s, CLVR_ERR_DEVICE_MEMORY, &err);
    TU_CHECK(strstr(err.msg, "image accumulator") != NULL);
    TU_CHECK(strstr(err.msg, "--size") != NULL);

    /* Buffers that fit one by one but not together: the global limit. */
    clvr_cl roomy = fake_device(GB, GB);
    clvr_mesh mid = counts_only(10000000, 0, 10000000); /* split phase 0.16 + 0.8 GB */
    TU_CHECK_STATUS(clvr_limits_check_named(&roomy, &mid, "mid.bin", NULL, 64, 64, &err), CLVR_OK, &err);
    clvr_cl tight = fake_device(GB / 2, GB / 2);
    s = clvr_limits_check_named(&tight, &mid, "mid.bin", NULL, 64, 64, &err);
    TU_CHECK_STATUS(s, CLVR_ERR_DEVICE_MEMORY, &err);
    TU_CHECK(strstr(err.msg, "need at least 0.960 GB") != NULL);
    TU_CHECK(strstr(err.msg, "preprocessing is the peak") != NULL);
    TU_CHECK(strstr(err.msg, "has 0.500 GB") != NULL);
    if (tu_fail_) fprintf(stderr, "message: %s\n", err.msg);
}

/* Builds a mesh from arrays (copied). */
static void make_mesh(clvr_mesh *m, const float *pos, uint32_t nv, uint32_t type, const uint32_t *idx, uint32_t nc)
{
    uint64_t counts[CLVR_CELL_TYPE_COUNT] = {0, 0, 0, 0};
    clvr_error err = {0};
    counts[type] = nc;
    if (clvr_mesh_alloc(m, nv, counts, &err) != CLVR_OK) { fprintf(stderr, "%s\n", err.msg); exit(1); }
    memcpy(m->positions, pos, 3 * sizeof(float) * nv);
    for (uint32_t i = 0; i < nv; ++i) m->scalars[i] = (float)i;
    memcpy(m->indices[type], idx, sizeof(uint32_t) * nc * clvr_cell_vertex_count(type));
    clvr_mesh_update_ranges(m);
}

static void test_scan_tets(void)
{
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 0};
    /* 0 fine, 1 inverted (1 and 2 swapped), 2 flat (0 1 2 4 in z = 0),
     * 3 an even permutation of 0 (a duplicate, not inverted), 4 all four
     * at one point. */
    const uint32_t idx[] = {0, 1, 2, 3, 0, 2, 1, 3, 0, 1, 2, 4, 3, 2, 1, 0, 4, 4, 4, 4};
    clvr_mesh m;
    clvr_limits_report r;
    make_mesh(&m, pos, 5, CLVR_CELL_TET, idx, 5);
    clvr_limits_scan(&m, &r);
    TU_CHECK_EQ_U64(r.degenerate, 2);
    TU_CHECK_EQ_U64(r.first_degenerate, 2);
    TU_CHECK_EQ_U64(r.inverted, 1);
    TU_CHECK_EQ_U64(r.first_inverted, 1);
    TU_CHECK(r.duplicates_checked);
    TU_CHECK_EQ_U64(r.duplicates, 2); /* 1 and 3 both repeat tet 0's vertex set */
    TU_CHECK_EQ_U64(r.first_duplicate, 1);
    TU_CHECK_EQ_U64(r.duplicate_of, 0);
    TU_CHECK(!r.constant_scalar);
    TU_CHECK_EQ_U64(r.unused_vertices, 0);

    char buf[4096] = "";
    FILE *f = tmpfile();
    int n = clvr_limits_print_warnings(f, "t.bin", &r);
    rewind(f);
    size_t got = fread(buf, 1, sizeof buf - 1, f);
    buf[got] = 0;
    fclose(f);
    TU_CHECK_EQ_U64(n, 3);
    TU_CHECK(strstr(buf, "clvr: warning: t.bin: 2 degenerate elements (zero volume), the first is tets[2]") != NULL);
    TU_CHECK(strstr(buf, "t.bin: 1 inverted element (vertex order mirrored against VTK's), the first is tets[1]") !=
             NULL);
    TU_CHECK(strstr(buf, "t.bin: 2 duplicate elements, the first is tets[1] (the same vertices as tets[0])") != NULL);
    if (tu_fail_) fprintf(stderr, "%s", buf);
    clvr_mesh_free(&m);

    /* A clean tet with a constant scalar and an unused vertex. */
    make_mesh(&m, pos, 5, CLVR_CELL_TET, idx, 1);
    for (int i = 0; i < 5; ++i) m.scalars[i] = 2.5f;
    clvr_mesh_update_ranges(&m);
    clvr_limits_scan(&m, &r);
    TU_CHECK_EQ_U64(r.degenerate + r.inverted + r.duplicates, 0);
    TU_CHECK(r.constant_scalar && r.constant_value == 2.5f);
    TU_CHECK_EQ_U64(r.unused_vertices, 1);
    clvr_mesh_free(&m);
}

static void test_scan_other_types(void)
{
    /* Unit hex, VTK order, and its mirror (top and bottom faces swapped). */
    const float hp[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
    const uint32_t hi[] = {0, 1, 2, 3, 4, 5, 6, 7, 4, 5, 6, 7, 0, 1, 2, 3};
    clvr_mesh m;
    clvr_limits_report r;
    make_mesh(&m, hp, 8, CLVR_CELL_HEX, hi, 2);
    clvr_limits_scan(&m, &r);
    TU_CHECK_EQ_U64(r.inverted, 1);
    TU_CHECK_EQ_U64(r.first_inverted_type, CLVR_CELL_HEX);
    TU_CHECK_EQ_U64(r.first_inverted, 1);
    TU_CHECK_EQ_U64(r.duplicates, 1); /* same vertex set */
    TU_CHECK_EQ_U64(r.degenerate, 0);
    clvr_mesh_free(&m);

    /* Wedge in VTK's order: (0, 1, 2)'s normal points away from (3, 4, 5). */
    const float wp[] = {0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 1, 1, 1, 0, 1};
    const uint32_t wi[] = {0, 1, 2, 3, 4, 5, 0, 2, 1, 3, 5, 4};
    make_mesh(&m, wp, 6, CLVR_CELL_WEDGE, wi, 2);
    clvr_limits_scan(&m, &r);
    TU_CHECK_EQ_U64(r.inverted, 1);
    TU_CHECK_EQ_U64(r.first_inverted, 1);
    clvr_mesh_free(&m);

    /* Pyramid: base normal toward the apex; a flattened one is degenerate. */
    const float pp[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5f, 0.5f, 1, 0.5f, 0.5f, 0};
    const uint32_t pi[] = {0, 1, 2, 3, 4, 0, 1, 2, 3, 5, 0, 3, 2, 1, 4};
    make_mesh(&m, pp, 6, CLVR_CELL_PYRAMID, pi, 3);
    clvr_limits_scan(&m, &r);
    TU_CHECK_EQ_U64(r.degenerate, 1);
    TU_CHECK_EQ_U64(r.first_degenerate, 1);
    TU_CHECK_EQ_U64(r.inverted, 1);
    TU_CHECK_EQ_U64(r.first_inverted, 2);
    clvr_mesh_free(&m);
}

/* Files written by VTK and umesh: their element order is the convention,
 * so nothing may count as inverted. */
static void test_scan_files(void)
{
    const char *dir = getenv("CLVR_SHARED_DATA");
    const char *files[] = {"vtk/uGridEx.vtk", "vtk/post.vtk", "vtk/notch_stress.vtk", "umesh/all_elements.umesh"};
    if (!dir) { fprintf(stderr, "CLVR_SHARED_DATA not set: skipping the file scans\n"); return; }
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[4096];
        clvr_mesh m;
        clvr_error err = {0};
        clvr_limits_report r;
        snprintf(path, sizeof path, "%s/%s", dir, files[i]);
        clvr_status s = clvr_mesh_load(path, NULL, &m, &err);
        TU_CHECK_STATUS(s, CLVR_OK, &err);
        if (s != CLVR_OK) continue;
        clvr_limits_scan(&m, &r);
        printf("%s: %llu elements, %llu degenerate, %llu inverted, %llu duplicates, %llu unused vertices\n",
               files[i], (unsigned long long)clvr_mesh_num_elements(&m), (unsigned long long)r.degenerate,
               (unsigned long long)r.inverted, (unsigned long long)r.duplicates,
               (unsigned long long)r.unused_vertices);
        TU_CHECK_EQ_U64(r.inverted, 0);
        TU_CHECK_EQ_U64(r.degenerate, 0);
        TU_CHECK_EQ_U64(r.duplicates, 0);
        TU_CHECK(r.duplicates_checked);
        clvr_mesh_free(&m);
    }
}

/* ---- duplicates on big random meshes against a sort-based reference:
 * elements ordered by (type, sorted vertex set, id); every element that is
 * not first in its group is a duplicate of the group's first. Sizes run
 * past the scan's one-partition case (32k elements). */
typedef struct dup_ref_item {
    uint32_t type, key[8];
    uint64_t id; /* within the type */
} dup_ref_item;

static int dup_ref_cmp(const void *a, const void *b)
{
    const dup_ref_item *x = a, *y = b;
    if (x->type != y->type) return x->type < y->type ? -1 : 1;
    int c = memcmp(x->key, y->key, sizeof x->key);
    if (c) return c;
    return x->id < y->id ? -1 : x->id > y->id;
}

static void sort8(uint32_t *k, uint32_t n)
{
    for (uint32_t i = 1; i < n; ++i)
        for (uint32_t j = i; j > 0 && k[j - 1] > k[j]; --j) {
            uint32_t t = k[j];
            k[j] = k[j - 1];
            k[j - 1] = t;
        }
}

static void test_scan_duplicates_random(void)
{
    const uint64_t sizes[] = {0, 1, 2, 40000, 100003, 300007};
    uint64_t rng = 12345;
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si) {
        const uint64_t n = sizes[si];
        clvr_mesh m;
        memset(&m, 0, sizeof m);
        /* Few vertices, so random vertex sets also repeat by chance. */
        m.num_vertices = 64;
        m.num_cells[CLVR_CELL_TET] = n - n / 3;
        m.num_cells[CLVR_CELL_HEX] = n / 3;
        m.positions = calloc(3 * m.num_vertices, sizeof(float));
        m.scalars = calloc(m.num_vertices, sizeof(float));
        for (uint32_t v = 0; v < m.num_vertices; ++v) m.positions[3 * v] = (float)v; /* geometry unused here */
        dup_ref_item *items = malloc((n ? n : 1) * sizeof *items);
        uint64_t k = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            const uint32_t nv = clvr_cell_vertex_count(t);
            m.indices[t] = malloc((m.num_cells[t] ? m.num_cells[t] : 1) * nv * sizeof(uint32_t));
            for (uint64_t e = 0; e < m.num_cells[t]; ++e) {
                uint32_t *ix = m.indices[t] + e * nv;
                rng = rng * 6364136223846793005ull + 1442695040888963407ull;
                if (e > 0 && (rng >> 60) == 0) {
                    /* A planted duplicate: an earlier element, vertices rotated. */
                    uint64_t o = (rng >> 20) % e;
                    for (uint32_t i = 0; i < nv; ++i) ix[i] = m.indices[t][o * nv + (i + 1) % nv];
                } else {
                    /* Distinct ids from 64 vertices: tets repeat by chance now and then. */
                    uint64_t used = 0;
                    for (uint32_t i = 0; i < nv; ++i) {
                        uint32_t v;
                        do {
                            rng = rng * 6364136223846793005ull + 1442695040888963407ull;
                            v = (uint32_t)(rng >> 58);
                        } while (used >> v & 1);
                        used |= 1ull << v;
                        ix[i] = v;
                    }
                }
                dup_ref_item *it = &items[k++];
                memset(it, 0, sizeof *it);
                it->type = t;
                it->id = e;
                memcpy(it->key, ix, nv * sizeof *ix);
                sort8(it->key, nv);
            }
        }
        qsort(items, n, sizeof *items, dup_ref_cmp);
        uint64_t dups = 0, first_g = UINT64_MAX, first_t = 0, first_e = 0, of = 0;
        for (uint64_t i = 0, g0 = 0; i < n; ++i) {
            if (i > 0 && items[i].type == items[i - 1].type && !memcmp(items[i].key, items[i - 1].key, sizeof items[i].key)) {
                ++dups;
                uint64_t g = items[i].type == CLVR_CELL_TET ? items[i].id : m.num_cells[0] + items[i].id;
                if (g < first_g) {
                    first_g = g;
                    first_t = items[i].type;
                    first_e = items[i].id;
                    of = items[g0].id;
                }
            } else
                g0 = i;
        }
        clvr_limits_report r;
        clvr_limits_scan(&m, &r);
        TU_CHECK(r.duplicates_checked);
        TU_CHECK_EQ_U64(r.duplicates, dups);
        if (dups) {
            TU_CHECK_EQ_U64(r.first_duplicate_type, first_t);
            TU_CHECK_EQ_U64(r.first_duplicate, first_e);
            TU_CHECK_EQ_U64(r.duplicate_of, of);
        }
        if (n > 1000) TU_CHECK(dups > 100); /* the test plants enough to mean something */
        free(items);
        clvr_mesh_free(&m);
    }
}

int main(void)
{
    test_estimate();
    test_check();
    test_scan_tets();
    test_scan_other_types();
    test_scan_files();
    test_scan_duplicates_random();
    return tu_finish("test_limits");
}
