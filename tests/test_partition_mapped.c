/* test_partition_mapped: the mapped .bin path and --element-boxes off
 * (issue #15).
 * 1. A .bin loaded with map_indices (+ map_vertices) holds the same arrays
 *    as one read into the heap, and its arrays lie in one read-only mapping.
 * 2. Broken files (truncated, trailing bytes, an index out of range in the
 *    first and in the very last element, a NaN coordinate, no elements)
 *    give the same status and the same message through the mapped reader as
 *    through read(), and leave nothing behind.
 * 3. Validating a mapped mesh does not make it resident: its mapped pages
 *    and the whole resident set each grow by under a quarter of the file
 *    (read into the heap: all of it, so the measurement can fail).
 * 4. A mapped mesh preprocessed in K > 1 partitions with its arrays consumed
 *    (the order-list path of partition.c) against K = 1 of the heap copy:
 *    the same original element and bit-identical values at random points,
 *    every element exactly once; awkward K (K above the element count,
 *    partitions of one element); its lists are released, its vertices kept.
 * 5. Element boxes off: no box buffer; host point location with and without
 *    the boxes finds the same element and value everywhere; the rendered
 *    image matches the one with boxes in distribution (per-pixel and
 *    per-block means within 5 standard errors).
 * 6. --element-boxes auto/on/off against a memory limit between the needs
 *    with and without boxes. */
#include <fcntl.h>
#include <malloc.h>
#include <sys/stat.h>
#include <unistd.h>

#include "accel.h"
#include "bvh.h"
#include "bvh_fixture.h"
#include "camera.h"
#include "limits_check.h"
#include "mesh_io.h"
#include "partition.h"
#include "render.h"
#include "render_fixture.h"
#include "test_util.h"
#include "tf.h"

#define K_SIGMA 5.0

static char g_dir[64];

static void path_of(char *buf, size_t n, const char *name) { snprintf(buf, n, "%s/%s", g_dir, name); }

static clvr_status load(const char *path, int map, clvr_mesh *m, clvr_error *err)
{
    clvr_load_options lo = {0};
    lo.map_indices = lo.map_vertices = map;
    return clvr_mesh_load(path, &lo, m, err);
}

static int in_map(const clvr_mesh *m, const void *p)
{
    return m->map_base && (const uint8_t *)p >= (const uint8_t *)m->map_base &&
           (const uint8_t *)p < (const uint8_t *)m->map_base + m->map_bytes;
}

/* 1. */
static void test_map_same(const char *file, const clvr_mesh *src)
{
    clvr_error err = {0};
    clvr_mesh r = {0}, p = {0}, q = {0};
    TU_CHECK_STATUS(load(file, 0, &r, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(load(file, 1, &p, &err), CLVR_OK, &err);
    clvr_load_options lo = {0};
    lo.map_indices = 1; /* lists only */
    TU_CHECK_STATUS(clvr_mesh_load(file, &lo, &q, &err), CLVR_OK, &err);
    TU_CHECK(r.map_base == NULL && p.map_base != NULL && q.map_base != NULL);
    TU_CHECK(in_map(&p, p.positions) && in_map(&p, p.scalars) && in_map(&p, p.indices[3]));
    TU_CHECK(!in_map(&q, q.positions) && in_map(&q, q.indices[0]));
    const clvr_mesh *ms[3] = {&r, &p, &q};
    for (int i = 0; i < 3; ++i) {
        const clvr_mesh *m = ms[i];
        TU_CHECK_EQ_U64(m->num_vertices, src->num_vertices);
        TU_CHECK(memcmp(m->positions, src->positions, src->num_vertices * 12) == 0);
        TU_CHECK(memcmp(m->scalars, src->scalars, src->num_vertices * 4) == 0);
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            TU_CHECK_EQ_U64(m->num_cells[t], src->num_cells[t]);
            TU_CHECK(memcmp(m->indices[t], src->indices[t], clvr_mesh_num_indices(src, t) * 4) == 0);
        }
        TU_CHECK(memcmp(m->bounds_lo, src->bounds_lo, 12) == 0 && m->scalar_max == src->scalar_max);
    }
    /* Freeing the lists of a mesh whose vertices are mapped keeps the vertices. */
    clvr_mesh_free_indices(&p);
    TU_CHECK(p.indices[0] == NULL && p.map_base != NULL && p.positions[0] == src->positions[0]);
    clvr_mesh_free(&r);
    clvr_mesh_free(&p);
    clvr_mesh_free(&q);
}

static uint8_t *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    *n = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc(*n + 64);
    if (b && fread(b, 1, *n, f) != *n) { free(b); b = NULL; }
    fclose(f);
    return b;
}

static void spit(const char *path, const uint8_t *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f) { ++tu_fail_; return; }
    if (fwrite(b, 1, n, f) != n) ++tu_fail_;
    fclose(f);
}

/* Both readers refuse with `want` and the same message. */
static void both_fail(const char *what, const char *path, clvr_status want)
{
    clvr_error e1 = {0}, e2 = {0};
    clvr_mesh a, b;
    const clvr_status s1 = load(path, 0, &a, &e1), s2 = load(path, 1, &b, &e2);
    if (s1 != want || s2 != want || strcmp(e1.msg, e2.msg) != 0)
        fprintf(stderr, "%s: read %d '%s', mapped %d '%s', want %d\n", what, s1, e1.msg, s2, e2.msg, want);
    TU_CHECK(s1 == want && s2 == want);
    TU_CHECK(strcmp(e1.msg, e2.msg) == 0);
    TU_CHECK(strstr(e2.msg, path) != NULL); /* names the file */
    TU_CHECK(b.map_base == NULL && b.positions == NULL && b.indices[3] == NULL); /* nothing left */
}

/* 2. */
static void test_broken(const char *file, const clvr_mesh *src)
{
    size_t n = 0;
    uint8_t *b = slurp(file, &n);
    TU_CHECK(b != NULL);
    if (!b) return;
    char p[128];
    const uint64_t V = src->num_vertices, pos = 256, idx0 = 256 + 16 * V;
    path_of(p, sizeof p, "truncated.bin");
    spit(p, b, n - 100);
    both_fail("truncated", p, CLVR_ERR_TRUNCATED);
    path_of(p, sizeof p, "trailing.bin");
    memset(b + n, 0, 64);
    spit(p, b, n + 8);
    both_fail("trailing", p, CLVR_ERR_FORMAT);
    /* first index of the first list, then the very last index of the file */
    uint32_t bad = (uint32_t)V + 5, keep;
    path_of(p, sizeof p, "badfirst.bin");
    memcpy(&keep, b + idx0, 4);
    memcpy(b + idx0, &bad, 4);
    spit(p, b, n);
    both_fail("bad first index", p, CLVR_ERR_BAD_INDEX);
    memcpy(b + idx0, &keep, 4);
    path_of(p, sizeof p, "badlast.bin");
    memcpy(&keep, b + n - 4, 4);
    bad = UINT32_MAX;
    memcpy(b + n - 4, &bad, 4);
    spit(p, b, n);
    both_fail("bad last index", p, CLVR_ERR_BAD_INDEX);
    memcpy(b + n - 4, &keep, 4);
    path_of(p, sizeof p, "nan.bin");
    const float nan = NAN;
    memcpy(b + pos + 12 * (V / 2) + 4, &nan, 4);
    spit(p, b, n);
    both_fail("NaN coordinate", p, CLVR_ERR_BAD_VALUE);
    free(b);
    /* No elements at all. */
    clvr_error err = {0};
    clvr_mesh e = {0};
    const uint64_t none[4] = {0};
    TU_CHECK_STATUS(clvr_mesh_alloc(&e, 3, none, &err), CLVR_OK, &err);
    memset(e.positions, 0, 36);
    memset(e.scalars, 0, 12);
    path_of(p, sizeof p, "empty.bin");
    TU_CHECK_STATUS(clvr_mesh_save_bin(p, &e, &err), CLVR_OK, &err);
    both_fail("no elements", p, CLVR_ERR_EMPTY);
    clvr_mesh_free(&e);
}

/* Whether VmRSS after malloc_trim measures the live heap: not under ASan,
 * which keeps freed blocks in quarantine and adds its shadow (the mapped
 * load measured 28.7 MB there, 0.0 in the plain build). */
#if defined(__SANITIZE_ADDRESS__)
#define HEAP_MEASURED 0
#else
#define HEAP_MEASURED 1
#endif

/* Pages of files mapped into this process (RssFile of /proc/self/status), bytes. */
static uint64_t rss_file(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    unsigned long long kb = 0;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "RssFile: %llu", &kb) == 1) break;
    if (f) fclose(f);
    return (uint64_t)kb * 1024u;
}

/* 3. */
static void test_resident(const char *file)
{
    clvr_error err = {0};
    struct stat st;
    if (stat(file, &st) != 0) { ++tu_fail_; return; }
    /* Mapped: the file's pages mapped in (RssFile) after the loader's
     * validation and the warnings' scan over every element (as clvr runs
     * them); read: the heap it took (VmRSS), so the measure can fail. */
    for (int map = 1; map >= 0; --map) {
        clvr_mesh m = {0};
        uint64_t before = 0, after = 0, vm_before = 0, vm_after = 0;
        /* malloc_trim: heap pages freed but kept by the allocator (the
         * fixture's 55 MB mesh, buffers the loader frees) leave the count,
         * so VmRSS measures what is live. */
        malloc_trim(0);
        if (map) before = rss_file();
        clvr_mem_rss(&vm_before, NULL);
        TU_CHECK_STATUS(load(file, map, &m, &err), CLVR_OK, &err);
        clvr_limits_report r;
        clvr_limits_scan(&m, &r);
        malloc_trim(0);
        if (map) after = rss_file();
        clvr_mem_rss(&vm_after, NULL);
        const double grew = map ? (double)after - (double)before : (double)vm_after - (double)vm_before;
        const double vm_grew = (double)vm_after - (double)vm_before;
        fprintf(stderr, "%s: %s grew by %.1f MB (VmRSS by %.1f MB) for a %.1f MB file\n", map ? "mapped" : "read",
                map ? "RssFile" : "VmRSS", grew / 1e6, vm_grew / 1e6, (double)st.st_size / 1e6);
        /* Mapped: neither the file's pages nor the heap (a copy of the
         * arrays made while validating would show in VmRSS, not RssFile). */
        if (map) TU_CHECK(grew < 0.25 * (double)st.st_size && (!HEAP_MEASURED || vm_grew < 0.25 * (double)st.st_size));
        else TU_CHECK(grew > 0.75 * (double)st.st_size);
        clvr_mesh_free(&m);
    }
}

/* Host point location over a downloaded clustered mesh (as test_partition). */
typedef struct located {
    clvr_clustered_host h;
    clvr_bvh_host b;
    clvr_instance *inst;
    clvr_mesh_view mv;
    uint8_t *ebox;
} located;

static int located_open(clvr_cl *cl, const clvr_clustered *c, int boxes, located *L)
{
    clvr_error err = {0};
    memset(L, 0, sizeof *L);
    if (clvr_clustered_download(cl, c, &L->h, &err) != CLVR_OK) goto fail;
    L->inst = malloc((c->num_instances + 1) * sizeof *L->inst);
    memcpy(L->inst, c->host_instances, c->num_instances * sizeof *L->inst);
    if (clvr_bvh_build_host(L->inst, (uint32_t)c->num_instances, L->h.leaf_boxes, (uint32_t)c->num_leaves, &L->b,
                            &err) != CLVR_OK)
        goto fail;
    clvr_mesh_view mv = {L->b.tlas, L->b.blas, L->inst, (const clvr_vec4 *)L->h.vertices, L->h.idx16, L->h.idx32,
                         L->b.tlas_root, c->leaf_size, NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
    L->mv = mv;
    if (boxes) {
        L->ebox = malloc(c->num_elements * CLVR_EBOX_BYTES + 1);
        if (clvr_bvh_element_boxes_host(&L->mv, (uint32_t)c->num_instances, (uint32_t)c->num_leaves, L->ebox, &err) !=
            CLVR_OK)
            goto fail;
        L->mv.ebox = L->ebox;
    }
    return 0;
fail:
    fprintf(stderr, "located_open: %s\n", err.msg);
    ++tu_fail_;
    return 1;
}

static void located_close(located *L)
{
    clvr_clustered_host_free(&L->h);
    clvr_bvh_host_free(&L->b);
    free(L->inst);
    free(L->ebox);
}

/* Same element (original id through order, when both have one) and
 * bit-identical value at nq random points. */
static void same_points(const char *name, const located *a, const located *b, const float lo[3], const float hi[3],
                        uint64_t seed)
{
    uint64_t rs = seed, found = 0, differ = 0;
    const uint32_t nq = 4000;
    for (uint32_t i = 0; i < nq; ++i) {
        float p[3];
        for (int k = 0; k < 3; ++k) p[k] = lo[k] + (hi[k] - lo[k]) * (0.02f + 0.96f * tu_randf(&rs));
        float sa = 0, sb = 0;
        uint32_t ea = 0, eb = 0;
        int oa = clvr_locate(&a->mv, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &sa, &ea);
        int ob = clvr_locate(&b->mv, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &sb, &eb);
        found += oa;
        const uint32_t ia = a->h.order ? a->h.order[ea] : ea, ib = b->h.order ? b->h.order[eb] : eb;
        int same = oa == ob && (!oa || (ia == ib && memcmp(&sa, &sb, sizeof sa) == 0));
        if (!same && differ++ < 5)
            fprintf(stderr, "%s: point (%.9g %.9g %.9g): %d elem %u %.9g against %d elem %u %.9g\n", name, p[0], p[1],
                    p[2], oa, oa ? ia : 0, sa, ob, ob ? ib : 0, sb);
    }
    TU_CHECK_EQ_U64(differ, 0);
    TU_CHECK(found > nq / 2); /* the points do hit the mesh */
}

/* 4. */
static void test_mapped_partitions(clvr_cl *cl, const char *file, uint32_t K)
{
    clvr_error err = {0};
    clvr_mesh r = {0}, p = {0};
    TU_CHECK_STATUS(load(file, 0, &r, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(load(file, 1, &p, &err), CLVR_OK, &err);
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.keep_order = 1; /* allowed when consuming a mapped mesh: its lists never move */
    clvr_clustered c1 = {0}, ck = {0};
    uint32_t nk = 0;
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, &r, &o, 1, 0, 0, &c1, NULL, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, &p, &o, K, 0, 1, &ck, &nk, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(nk, K);
    TU_CHECK_EQ_U64(ck.num_elements, c1.num_elements);
    TU_CHECK_EQ_U64(ck.num_idx16 + ck.num_idx32, c1.num_idx16 + c1.num_idx32);
    TU_CHECK(ck.num_vertices >= c1.num_vertices);
    /* consumed: lists gone (counts kept), vertices still there */
    TU_CHECK(p.indices[0] == NULL && p.indices[3] == NULL && p.num_cells[3] == r.num_cells[3]);
    TU_CHECK(p.positions != NULL && p.positions[5] == r.positions[5]);
    located a, b;
    if (located_open(cl, &c1, 0, &a) == 0 && located_open(cl, &ck, 0, &b) == 0) {
        uint8_t *seen = calloc(ck.num_elements, 1);
        uint64_t dup = 0;
        for (uint64_t i = 0; i < ck.num_elements; ++i) dup += seen[b.h.order[i]]++ != 0;
        TU_CHECK_EQ_U64(dup, 0);
        free(seen);
        char name[64];
        snprintf(name, sizeof name, "mapped, consumed, K=%u", K);
        same_points(name, &a, &b, r.bounds_lo, r.bounds_hi, 17 + K);
    }
    located_close(&a);
    located_close(&b);
    clvr_clustered_release(cl, &c1);
    clvr_clustered_release(cl, &ck);
    clvr_mesh_free(&r);
    clvr_mesh_free(&p);
}

/* Renders n independent frames; per-pixel mean and variance. */
static int render_moments(clvr_cl *cl, const clvr_mesh *m, int no_boxes, uint32_t W, uint32_t H, uint32_t n,
                          float **mean, float **var, uint64_t *ebox_bytes)
{
    clvr_error err = {0};
    clvr_clustered c = {0};
    clvr_accel a = {0};
    clvr_render_settings set;
    clvr_render_settings_default(&set);
    set.width = W;
    set.height = H;
    set.sampler = CLVR_SAMPLER_INDEPENDENT;
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.no_element_boxes = no_boxes;
    clvr_status s = clvr_preprocess(cl, m, &o, &c, &err);
    if (s == CLVR_OK) s = clvr_accel_build(cl, &c, &a, &err);
    *ebox_bytes = a.two_level.ebox_bytes + (a.two_level.ebox != NULL);
    if (s == CLVR_OK) s = fx_render_moments(cl, m, &c, &a, &set, n, mean, var, &err);
    else {
        *mean = calloc((size_t)W * H * 4, sizeof(float));
        *var = calloc((size_t)W * H * 4, sizeof(float));
    }
    if (s != CLVR_OK) fprintf(stderr, "render (boxes %s): %s\n", no_boxes ? "off" : "on", err.msg);
    clvr_accel_release(cl, &a);
    clvr_clustered_release(cl, &c);
    return s != CLVR_OK;
}

/* 5. */
static void test_boxes_off(clvr_cl *cl)
{
    clvr_error err = {0};
    clvr_mesh m = {0};
    /* jittered tets: conforming, and boxes that matter (elements of varied shape) */
    TU_CHECK_STATUS(fx_grid_mesh(11, FX_TETS, 0.3f, 1.0f, 0.0f, 23, &m, &err), CLVR_OK, &err);
    clvr_mesh_update_ranges(&m);
    {
        clvr_clustered c = {0};
        TU_CHECK_STATUS(clvr_preprocess(cl, &m, NULL, &c, &err), CLVR_OK, &err);
        located with, without;
        if (located_open(cl, &c, 1, &with) == 0 && located_open(cl, &c, 0, &without) == 0)
            same_points("element boxes on against off", &with, &without, m.bounds_lo, m.bounds_hi, 5);
        located_close(&with);
        located_close(&without);
        clvr_clustered_release(cl, &c);
    }
    const uint32_t W = 32, H = 32, n = 96;
    float *m1, *v1, *m0, *v0;
    uint64_t eb_on = 0, eb_off = 0;
    int bad1 = render_moments(cl, &m, 0, W, H, n, &m1, &v1, &eb_on),
        bad0 = render_moments(cl, &m, 1, W, H, n, &m0, &v0, &eb_off);
    TU_CHECK(!bad1 && !bad0);
    TU_CHECK_EQ_U64(eb_off, 0);                                   /* off: no buffer at all */
    TU_CHECK_EQ_U64(eb_on, clvr_mesh_num_elements(&m) * CLVR_EBOX_BYTES + 1); /* on: 6 bytes per element */
    if (!bad1 && !bad0) {
        const fx_moments_diff r = fx_compare_moments(m1, v1, m0, v0, W, H, n, K_SIGMA);
        TU_CHECK_EQ_U64(r.pixels, 0);
        TU_CHECK(r.opacity > 0.05 * W * H);
        TU_CHECK_EQ_U64(r.blocks, 0);
        TU_CHECK_EQ_U64(r.channels, 0);
    }
    free(m1);
    free(v1);
    free(m0);
    free(v0);
    clvr_mesh_free(&m);
}

/* 6. */
static void test_boxes_check(void)
{
    clvr_error err = {0};
    const uint64_t cells[4] = {300000000ull, 0, 0, 0}, V = 50000000ull;
    clvr_host_estimate on, off;
    const clvr_host_layout lon = {1, CLVR_EBOX_ON}, loff = {1, CLVR_EBOX_OFF};
    clvr_limits_host_estimate_layout(V, cells, 4u << 20, 512, 512, &lon, &on);
    clvr_limits_host_estimate_layout(V, cells, 4u << 20, 512, 512, &loff, &off);
    TU_CHECK_EQ_U64(on.total_bytes - off.total_bytes, 300000000ull * 6); /* 6 bytes per element */
    TU_CHECK_EQ_U64(on.mesh_bytes, 0);                                    /* mapped: page cache */
    /* A limit between the two (checks allow 90% of it). */
    clvr_mem_limits l = {0};
    l.limit = l.mem_available = (on.total_bytes + off.total_bytes) / 2 / 9 * 10;
    l.cgroup_left = l.as_left = UINT64_MAX;
    l.binding = "available memory";
    FILE *note = tmpfile();
    int mode = CLVR_EBOX_AUTO;
    TU_CHECK_STATUS(clvr_limits_check_host_boxes("tets.bin", V, cells, 4u << 20, 512, 512, 0, 1, &mode, &l, note, &err),
                    CLVR_OK, &err);
    TU_CHECK_EQ_U64(mode, CLVR_EBOX_OFF);
    char line[512] = {0};
    rewind(note);
    TU_CHECK(fgets(line, sizeof line, note) != NULL && strstr(line, "tets.bin") && strstr(line, "element boxes"));
    fclose(note);
    mode = CLVR_EBOX_ON;
    TU_CHECK_STATUS(clvr_limits_check_host_boxes("tets.bin", V, cells, 4u << 20, 512, 512, 0, 1, &mode, &l, NULL, &err),
                    CLVR_ERR_NO_MEMORY, &err);
    TU_CHECK(strstr(err.msg, "--element-boxes off") != NULL && strstr(err.msg, "tets.bin") != NULL);
    mode = CLVR_EBOX_OFF;
    TU_CHECK_STATUS(clvr_limits_check_host_boxes("tets.bin", V, cells, 4u << 20, 512, 512, 0, 1, &mode, &l, NULL, &err),
                    CLVR_OK, &err);
    /* Plenty: auto keeps them; too little: refused even without. */
    l.limit = l.mem_available = on.total_bytes * 2;
    mode = CLVR_EBOX_AUTO;
    TU_CHECK_STATUS(clvr_limits_check_host_boxes("tets.bin", V, cells, 4u << 20, 512, 512, 0, 1, &mode, &l, NULL, &err),
                    CLVR_OK, &err);
    TU_CHECK_EQ_U64(mode, CLVR_EBOX_ON);
    l.limit = l.mem_available = off.total_bytes / 2;
    mode = CLVR_EBOX_AUTO;
    TU_CHECK_STATUS(clvr_limits_check_host_boxes("tets.bin", V, cells, 4u << 20, 512, 512, 0, 1, &mode, &l, NULL, &err),
                    CLVR_ERR_NO_MEMORY, &err);
    /* The device estimate counts the boxes as a buffer, and not when off. */
    clvr_mesh counts = {0};
    counts.num_vertices = V;
    counts.num_cells[0] = cells[0];
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    clvr_limits_estimate d1, d0;
    clvr_limits_estimate_parts(&counts, &o, 4u << 20, 64, 64, &d1);
    o.no_element_boxes = 1;
    clvr_limits_estimate_parts(&counts, &o, 4u << 20, 64, 64, &d0);
    TU_CHECK_EQ_U64(d1.render_bytes - d0.render_bytes, cells[0] * 6);
}

int main(void)
{
    snprintf(g_dir, sizeof g_dir, "/tmp/clvr-test-mapped-XXXXXX");
    if (!mkdtemp(g_dir)) {
        fprintf(stderr, "cannot make a temporary folder\n");
        return 1;
    }
    clvr_error err = {0};
    char file[128], big[128];
    path_of(file, sizeof file, "mixed.bin");
    path_of(big, sizeof big, "big.bin");
    clvr_mesh m = {0};
    TU_CHECK_STATUS(fx_grid_mesh(12, FX_MIXED, 0.0f, 1.0f, 0.0f, 7, &m, &err), CLVR_OK, &err);
    clvr_mesh_update_ranges(&m);
    TU_CHECK_STATUS(clvr_mesh_save_bin(file, &m, &err), CLVR_OK, &err);
    test_map_same(file, &m);
    test_broken(file, &m);
    test_boxes_check();
    {
        clvr_mesh b = {0}; /* 80^3 cubes: a 55 MB file */
        TU_CHECK_STATUS(fx_grid_mesh(80, FX_MIXED, 0.0f, 1.0f, 0.0f, 3, &b, &err), CLVR_OK, &err);
        clvr_mesh_update_ranges(&b);
        TU_CHECK_STATUS(clvr_mesh_save_bin(big, &b, &err), CLVR_OK, &err);
        clvr_mesh_free(&b);
        test_resident(big);
    }
    clvr_cl cl;
    tu_open_device(&cl);
    test_mapped_partitions(&cl, file, 2);
    test_mapped_partitions(&cl, file, 9);
    {
        /* K above the element count: empty partitions and partitions of one element. */
        char tiny[128];
        clvr_mesh t = {0};
        path_of(tiny, sizeof tiny, "tiny.bin");
        TU_CHECK_STATUS(fx_grid_mesh(3, FX_MIXED, 0.0f, 1.0f, 0.0f, 9, &t, &err), CLVR_OK, &err);
        clvr_mesh_update_ranges(&t);
        TU_CHECK_STATUS(clvr_mesh_save_bin(tiny, &t, &err), CLVR_OK, &err);
        test_mapped_partitions(&cl, tiny, (uint32_t)clvr_mesh_num_elements(&t) + 13);
        clvr_mesh_free(&t);
        unlink(tiny);
    }
    test_boxes_off(&cl);
    clvr_cl_destroy(&cl);
    clvr_mesh_free(&m);
    const char *names[] = {"mixed.bin", "big.bin", "truncated.bin", "trailing.bin", "badfirst.bin", "badlast.bin",
                           "nan.bin", "empty.bin"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        char p[128];
        path_of(p, sizeof p, names[i]);
        unlink(p);
    }
    rmdir(g_dir);
    return tu_finish("test_partition_mapped");
}
