/* test_partition: partitioned preprocessing (host/pipeline/partition.h).
 * 1. plans: every element in exactly one partition, partitions contiguous
 *    and increasing along the curve (coarse keys), exactly K with `count`,
 *    bounded sizes without; awkward sizes: K above the element count (empty
 *    partitions), partitions of one element, one element in all;
 * 2. the in-place reorder keeps every partition's elements (multiset);
 * 3. K > 1 against K = 1 on a mixed mesh: same element counts, and at
 *    random points the same element (original id) and bit-identical
 *    interpolated values (host point location on both clustered meshes);
 *    the consumed mode gives the same counts and frees the index lists;
 * 4. K > 1 renders the same image in distribution as K = 1 (per-pixel and
 *    per-block difference of means within 5 standard errors);
 * 5. the host-memory check refuses with the numbers and accepts when it fits. */
#include "accel.h"
#include "bvh.h"
#include "bvh_fixture.h"
#include "camera.h"
#include "limits_check.h"
#include "partition.h"
#include "preprocess_stages.h"
#include "render.h"
#include "render_fixture.h"
#include "test_util.h"
#include "tf.h"

#include "../kernels/bounds.h"

#define K_SIGMA 5.0

static uint32_t coarse(const clvr_mesh *m, const clvr_box *b, uint32_t t, uint64_t e)
{
    const uint32_t vpe = clvr_cell_vertex_count(t);
    float lo[3], hi[3];
    clvr_pp_element_box(m->positions, m->indices[t] + e * vpe, vpe, lo, hi);
    uint64_t k = clvr_pp_element_key(t, lo, hi, b->lo, clvr_pp_scale(b), 0) & ((1ull << 48) - 1);
    return (uint32_t)(k >> (48 - CLVR_PARTITION_KEY_BITS));
}

/* Plan invariants: counts add up, membership matches the bin ranges,
 * ranges increase with the partition id. */
static void check_plan(const char *name, const clvr_mesh *m, const clvr_partition_plan *p)
{
    uint64_t total = 0, first = 0, bad = 0;
    for (uint32_t k = 0; k < p->count; ++k) {
        total += p->parts[k].num_elements;
        /* increasing along the curve; pieces of one split bin share it */
        const clvr_partition *c = &p->parts[k], *b = k ? &p->parts[k - 1] : NULL;
        if (b && c->num_elements && b->num_elements && c->bin_lo < b->bin_hi &&
            !(c->bin_lo == b->bin_lo && c->bin_hi == b->bin_hi && c->bin_hi == c->bin_lo + 1))
            ++bad;
    }
    TU_CHECK_EQ_U64(total, clvr_mesh_num_elements(m));
    uint64_t *cnt = calloc(p->count, sizeof *cnt);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        for (uint64_t e = 0; e < m->num_cells[t]; ++e) {
            const uint32_t q = clvr_partition_of(p, first + e), c = coarse(m, &p->box, t, e);
            if (q >= p->count || c < p->parts[q].bin_lo || c >= p->parts[q].bin_hi) ++bad;
            else ++cnt[q];
        }
        first += m->num_cells[t];
    }
    for (uint32_t k = 0; k < p->count; ++k) bad += cnt[k] != p->parts[k].num_elements;
    free(cnt);
    if (bad) fprintf(stderr, "%s: %llu plan violations\n", name, (unsigned long long)bad);
    TU_CHECK_EQ_U64(bad, 0);
}

static uint64_t elem_hash(const uint32_t *idx, uint32_t vpe, uint32_t t)
{
    uint64_t h = 0x9e3779b97f4a7c15ull * (t + 1);
    for (uint32_t j = 0; j < vpe; ++j) h = (h ^ idx[j]) * 0x100000001b3ull;
    return h * 0xbf58476d1ce4e5b9ull;
}

static void test_plans(void)
{
    clvr_error err = {0};
    clvr_mesh m = {0};
    TU_CHECK_STATUS(fx_grid_mesh(7, FX_MIXED, 0.2f, 1.0f, 0.0f, 3, &m, &err), CLVR_OK, &err);
    clvr_mesh_update_ranges(&m);
    const uint64_t N = clvr_mesh_num_elements(&m);
    const uint32_t counts[] = {1, 2, 3, 7, 64, (uint32_t)N, (uint32_t)N + 50, 300};
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; ++i) {
        clvr_partition_plan p;
        char name[64];
        snprintf(name, sizeof name, "mixed 7^3, K=%u", counts[i]);
        TU_CHECK_STATUS(clvr_partition_plan_make(&m, counts[i], 0, &p, &err), CLVR_OK, &err);
        TU_CHECK_EQ_U64(p.count, counts[i]);
        check_plan(name, &m, &p);
        uint64_t largest = 0, empty = 0;
        for (uint32_t k = 0; k < p.count; ++k) {
            largest = p.parts[k].num_elements > largest ? p.parts[k].num_elements : largest;
            empty += p.parts[k].num_elements == 0;
        }
        if (counts[i] > N) TU_CHECK(empty >= counts[i] - N); /* K above the element count: empties */
        /* near-equal shares: a coarse bin holds few elements of this mesh */
        if (counts[i] <= 7) TU_CHECK(largest <= N / counts[i] + N / 10 + 8);
        clvr_partition_plan_free(&p);
    }
    /* Bounded sizes without a count. */
    {
        clvr_partition_plan p;
        TU_CHECK_STATUS(clvr_partition_plan_make(&m, 0, 100, &p, &err), CLVR_OK, &err);
        check_plan("mixed 7^3, <= 100 per partition", &m, &p);
        uint64_t over = 0;
        for (uint32_t k = 0; k < p.count; ++k) over += p.parts[k].num_elements > 100;
        TU_CHECK_EQ_U64(over, 0);
        TU_CHECK(p.count >= N / 100);
        /* Reorder: each partition's range holds the same elements it had. */
        uint64_t *before = calloc(p.count, sizeof *before), *after = calloc(p.count, sizeof *after), first = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            const uint32_t vpe = clvr_cell_vertex_count(t);
            for (uint64_t e = 0; e < m.num_cells[t]; ++e)
                before[clvr_partition_of(&p, first + e)] += elem_hash(m.indices[t] + e * vpe, vpe, t);
            first += m.num_cells[t];
        }
        clvr_partition_plan_reorder(&m, &p);
        TU_CHECK(p.reordered);
        for (uint32_t k = 0; k < p.count; ++k)
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
                const uint32_t vpe = clvr_cell_vertex_count(t);
                for (uint64_t e = 0; e < p.parts[k].num_cells[t]; ++e)
                    after[k] += elem_hash(m.indices[t] + (p.parts[k].first_cell[t] + e) * vpe, vpe, t);
            }
        uint64_t diff = 0;
        for (uint32_t k = 0; k < p.count; ++k) diff += before[k] != after[k];
        TU_CHECK_EQ_U64(diff, 0);
        /* Extraction after a reorder: renumbered indices within the sub-mesh's vertices. */
        uint32_t *vmap = malloc(m.num_vertices * sizeof *vmap);
        memset(vmap, 0xff, m.num_vertices * sizeof *vmap);
        uint64_t got = 0, out_of_range = 0;
        for (uint32_t k = 0; k < p.count; ++k) {
            clvr_mesh sub;
            TU_CHECK_STATUS(clvr_partition_extract(&m, &p, k, vmap, &sub, NULL, &err), CLVR_OK, &err);
            got += clvr_mesh_num_elements(&sub);
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
                for (uint64_t j = 0; j < clvr_mesh_num_indices(&sub, t); ++j) out_of_range += sub.indices[t][j] >= sub.num_vertices;
            clvr_mesh_free(&sub);
        }
        uint64_t dirty = 0;
        for (uint64_t v = 0; v < m.num_vertices; ++v) dirty += vmap[v] != UINT32_MAX;
        TU_CHECK_EQ_U64(got, N);
        TU_CHECK_EQ_U64(out_of_range, 0);
        TU_CHECK_EQ_U64(dirty, 0); /* the flag array is clean for the next partition */
        free(vmap);
        free(before);
        free(after);
        clvr_partition_plan_free(&p);
    }
    /* At most one element per partition: every bin of two or more is split;
     * partitions of exactly one element, none empty. */
    {
        clvr_partition_plan p;
        TU_CHECK_STATUS(clvr_partition_plan_make(&m, 0, 1, &p, &err), CLVR_OK, &err);
        check_plan("mixed 7^3, 1 per partition", &m, &p);
        TU_CHECK_EQ_U64(p.count, N);
        uint64_t not_one = 0;
        for (uint32_t k = 0; k < p.count; ++k) not_one += p.parts[k].num_elements != 1;
        TU_CHECK_EQ_U64(not_one, 0);
        clvr_partition_plan_free(&p);
    }
    clvr_mesh_free(&m);
    /* Every element in one spot of the grid (one coarse bin): still bounded partitions. */
    {
        clvr_mesh pile = {0};
        uint64_t c[4] = {1000, 0, 0, 0};
        TU_CHECK_STATUS(clvr_mesh_alloc(&pile, 4, c, &err), CLVR_OK, &err);
        const float pos[12] = {0, 0, 0, 1e-6f, 0, 0, 0, 1e-6f, 0, 0, 0, 1e-6f};
        memcpy(pile.positions, pos, sizeof pos);
        for (uint32_t i = 0; i < 4; ++i) pile.scalars[i] = (float)i;
        for (uint64_t i = 0; i < 4000; ++i) pile.indices[0][i] = (uint32_t)(i % 4);
        clvr_mesh_update_ranges(&pile);
        /* the box is the whole mesh here; put a far vertex so the pile is one bin */
        clvr_partition_plan p;
        TU_CHECK_STATUS(clvr_partition_plan_make(&pile, 0, 64, &p, &err), CLVR_OK, &err);
        check_plan("1000 tets in one spot, <= 64 per partition", &pile, &p);
        uint64_t over = 0;
        for (uint32_t k = 0; k < p.count; ++k) over += p.parts[k].num_elements > 64;
        TU_CHECK_EQ_U64(over, 0);
        TU_CHECK_EQ_U64(p.count, 16); /* ceil(1000 / 64) */
        clvr_partition_plan_free(&p);
        clvr_mesh_free(&pile);
    }
    /* One element; K = 4 leaves three partitions empty. */
    {
        clvr_mesh one = {0};
        uint64_t c[4] = {1, 0, 0, 0};
        TU_CHECK_STATUS(clvr_mesh_alloc(&one, 4, c, &err), CLVR_OK, &err);
        const float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
        memcpy(one.positions, pos, sizeof pos);
        for (uint32_t i = 0; i < 4; ++i) { one.scalars[i] = (float)i; one.indices[0][i] = i; }
        clvr_mesh_update_ranges(&one);
        clvr_partition_plan p;
        TU_CHECK_STATUS(clvr_partition_plan_make(&one, 4, 0, &p, &err), CLVR_OK, &err);
        check_plan("one tet, K=4", &one, &p);
        uint64_t nonempty = 0;
        for (uint32_t k = 0; k < p.count; ++k) nonempty += p.parts[k].num_elements != 0;
        TU_CHECK_EQ_U64(nonempty, 1);
        clvr_partition_plan_free(&p);
        clvr_mesh_free(&one);
    }
}

/* Host point location over a downloaded clustered mesh. */
typedef struct located {
    clvr_clustered_host h;
    clvr_bvh_host b;
    clvr_instance *inst;
    clvr_mesh_view mv;
} located;

static int located_open(clvr_cl *cl, const clvr_clustered *c, located *L)
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
}

/* K partitions against one: counts, then points. */
static void compare_points(clvr_cl *cl, clvr_mesh *m, const char *name, uint32_t K)
{
    clvr_error err = {0};
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    clvr_clustered c1 = {0}, ck = {0};
    uint32_t n1 = 0, nk = 0;
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, m, &o, 1, 0, 0, &c1, &n1, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, m, &o, K, 0, 0, &ck, &nk, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(n1, 1);
    TU_CHECK_EQ_U64(nk, K);
    TU_CHECK_EQ_U64(ck.num_elements, c1.num_elements);
    TU_CHECK_EQ_U64(ck.num_idx16 + ck.num_idx32, c1.num_idx16 + c1.num_idx32);
    TU_CHECK(ck.num_vertices >= c1.num_vertices); /* more cuts, more duplicated vertices, never fewer */
    TU_CHECK(ck.num_instances >= c1.num_instances);
    TU_CHECK_EQ_U64(ck.bounds.lo[3] == c1.bounds.lo[3] && ck.bounds.hi[3] == c1.bounds.hi[3], 1);
    located a, b;
    if (located_open(cl, &c1, &a) == 0 && located_open(cl, &ck, &b) == 0) {
        /* every original element exactly once in the partitioned order */
        uint8_t *seen = calloc(ck.num_elements, 1);
        uint64_t dup = 0;
        for (uint64_t i = 0; i < ck.num_elements; ++i) dup += seen[b.h.order[i]]++ != 0;
        TU_CHECK_EQ_U64(dup, 0);
        free(seen);
        uint64_t rs = 99 + K, found = 0, differ = 0;
        const uint32_t nq = 4000;
        for (uint32_t i = 0; i < nq; ++i) {
            float p[3];
            for (int k = 0; k < 3; ++k)
                p[k] = m->bounds_lo[k] + (m->bounds_hi[k] - m->bounds_lo[k]) * (0.02f + 0.96f * tu_randf(&rs));
            float sa = 0, sb = 0;
            uint32_t ea = 0, eb = 0;
            int oa = clvr_locate(&a.mv, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &sa, &ea);
            int ob = clvr_locate(&b.mv, p[0], p[1], p[2], CLVR_LOCATE_COHERENT, &sb, &eb);
            found += oa;
            int same = oa == ob && (!oa || (a.h.order[ea] == b.h.order[eb] && memcmp(&sa, &sb, sizeof sa) == 0));
            if (!same && differ++ < 5)
                fprintf(stderr, "%s K=%u: point (%.9g %.9g %.9g): K=1 %d elem %u %.9g, K=%u %d elem %u %.9g\n", name, K,
                        p[0], p[1], p[2], oa, oa ? a.h.order[ea] : 0, sa, K, ob, ob ? b.h.order[eb] : 0, sb);
        }
        TU_CHECK_EQ_U64(differ, 0);
        TU_CHECK(found > nq / 2); /* the points do hit the mesh */
    }
    located_close(&a);
    located_close(&b);
    clvr_clustered_release(cl, &c1);
    clvr_clustered_release(cl, &ck);
}

/* A caller's quantization box (MPI ranks share the whole mesh's, so their
 * shares are pieces of one Hilbert curve) reaches every partition and the
 * plan's coarse keys: K partitions over a larger, off-centre box list each
 * type's elements in the order one partition over that box does (at least
 * 95% of them, for ties of fine keys). Measured on mixed 12^3: 6480 of 6480;
 * 46 when the plan quantizes over the mesh's own bounds instead. */
static void test_shared_box(clvr_cl *cl, clvr_mesh *m)
{
    clvr_error err = {0};
    clvr_box big;
    for (int k = 0; k < 3; ++k) {
        const float ext = m->bounds_hi[k] - m->bounds_lo[k];
        big.lo[k] = m->bounds_lo[k] - 1.3f * ext - 0.25f;
        big.hi[k] = m->bounds_hi[k] + 0.7f * ext + 0.5f;
    }
    big.lo[3] = big.hi[3] = 0.0f;
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    o.quantize_box = &big;
    clvr_clustered c1 = {0}, ck = {0};
    uint32_t n1 = 0, nk = 0;
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, m, &o, 1, 0, 0, &c1, &n1, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, m, &o, 3, 0, 0, &ck, &nk, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(nk, 3);
    located a, b;
    if (located_open(cl, &c1, &a) == 0 && located_open(cl, &ck, &b) == 0) {
        /* Keys put the element type above the curve, so compare each type's
         * elements in their order of appearance: original ids are numbered
         * tets first, then pyramids, wedges and hexes. */
        uint64_t first[CLVR_CELL_TYPE_COUNT + 1] = {0};
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) first[t + 1] = first[t] + m->num_cells[t];
        uint64_t same = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            uint64_t ia = 0, ib = 0;
            for (;;) {
                while (ia < c1.num_elements && !(a.h.order[ia] >= first[t] && a.h.order[ia] < first[t + 1])) ++ia;
                while (ib < ck.num_elements && !(b.h.order[ib] >= first[t] && b.h.order[ib] < first[t + 1])) ++ib;
                if (ia >= c1.num_elements || ib >= ck.num_elements) break;
                same += a.h.order[ia++] == b.h.order[ib++];
            }
        }
        fprintf(stderr, "shared quantization box: %llu of %llu elements in the one-partition order of their type\n",
                (unsigned long long)same, (unsigned long long)c1.num_elements);
        TU_CHECK(same * 100 >= c1.num_elements * 95);
    }
    located_close(&a);
    located_close(&b);
    clvr_clustered_release(cl, &c1);
    clvr_clustered_release(cl, &ck);
}

/* The consumed mode: same counts as kept, and the index lists are gone. */
static void test_consume(clvr_cl *cl)
{
    clvr_error err = {0};
    clvr_mesh m = {0}, m2 = {0};
    TU_CHECK_STATUS(fx_grid_mesh(9, FX_MIXED, 0.25f, 1.0f, 0.0f, 5, &m, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(fx_grid_mesh(9, FX_MIXED, 0.25f, 1.0f, 0.0f, 5, &m2, &err), CLVR_OK, &err);
    clvr_mesh_update_ranges(&m);
    clvr_mesh_update_ranges(&m2);
    clvr_clustered a = {0}, b = {0};
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, &m, NULL, 5, 0, 0, &a, NULL, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, &m2, NULL, 5, 0, 1, &b, NULL, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(a.num_elements, b.num_elements);
    TU_CHECK_EQ_U64(a.num_idx16, b.num_idx16);
    TU_CHECK_EQ_U64(a.num_sampling, b.num_sampling);
    TU_CHECK(m2.indices[0] == NULL && m2.indices[3] == NULL && m2.positions != NULL);
    TU_CHECK(m.indices[0] != NULL);
    /* keep_order cannot be honoured once the lists are reordered */
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    o.keep_order = 1;
    clvr_clustered c = {0};
    TU_CHECK_STATUS(clvr_preprocess_partitioned(cl, &m, &o, 3, 0, 1, &c, NULL, &err), CLVR_ERR_USAGE, &err);
    clvr_clustered_release(cl, &a);
    clvr_clustered_release(cl, &b);
    clvr_mesh_free(&m);
    clvr_mesh_free(&m2);
}

/* Renders n independent frames and returns per-pixel mean and variance. */
static int render_moments(clvr_cl *cl, const clvr_mesh *m, uint32_t K, uint32_t W, uint32_t H, uint32_t n,
                          float **mean, float **var)
{
    clvr_error err = {0};
    clvr_clustered c = {0};
    clvr_accel a = {0};
    clvr_render_settings set;
    clvr_render_settings_default(&set);
    set.width = W;
    set.height = H;
    set.sampler = CLVR_SAMPLER_INDEPENDENT; /* per-pixel error bars need independent frames */
    clvr_mesh mm = *m; /* not consumed: a shallow copy is enough */
    clvr_status s = clvr_preprocess_partitioned(cl, &mm, NULL, K, 0, 0, &c, NULL, &err);
    if (s == CLVR_OK) s = clvr_accel_build(cl, &c, &a, &err);
    if (s == CLVR_OK) s = fx_render_moments(cl, m, &c, &a, &set, n, mean, var, &err);
    else {
        *mean = calloc((size_t)W * H * 4, sizeof(float));
        *var = calloc((size_t)W * H * 4, sizeof(float));
    }
    if (s != CLVR_OK) fprintf(stderr, "render K=%u: %s\n", K, err.msg);
    clvr_accel_release(cl, &a);
    clvr_clustered_release(cl, &c);
    return s != CLVR_OK;
}

static void test_render_same(clvr_cl *cl)
{
    clvr_error err = {0};
    clvr_mesh m = {0};
    TU_CHECK_STATUS(fx_grid_mesh(10, FX_MIXED, 0.25f, 1.0f, 0.0f, 11, &m, &err), CLVR_OK, &err);
    clvr_mesh_update_ranges(&m);
    const uint32_t W = 32, H = 32, n = 96;
    float *m1, *v1, *mk, *vk;
    int bad1 = render_moments(cl, &m, 1, W, H, n, &m1, &v1), badk = render_moments(cl, &m, 6, W, H, n, &mk, &vk);
    TU_CHECK(!bad1 && !badk);
    if (!bad1 && !badk) {
        /* Per pixel and channel, then per 4x4 block (a small bias spread
         * over many pixels shows there), as tests/test_render.c. */
        const fx_moments_diff r = fx_compare_moments(m1, v1, mk, vk, W, H, n, K_SIGMA);
        TU_CHECK_EQ_U64(r.pixels, 0);
        TU_CHECK(r.opacity > 0.05 * W * H); /* the volume covers part of the image: the test can fail */
        TU_CHECK_EQ_U64(r.blocks, 0);
        TU_CHECK_EQ_U64(r.channels, 0);
    }
    free(m1);
    free(v1);
    free(mk);
    free(vk);
    clvr_mesh_free(&m);
}

/* The duplicate scan in bounded memory finds what the one-group scan finds. */
static void test_scan_budget(void)
{
    clvr_error err = {0};
    clvr_mesh m = {0};
    TU_CHECK_STATUS(fx_grid_mesh(30, FX_MIXED, 0.0f, 1.0f, 0.0f, 3, &m, &err), CLVR_OK, &err);
    /* Duplicate a few hexes (vertex order rotated) and tets onto later slots. */
    const uint64_t nh = m.num_cells[3], nt = m.num_cells[0];
    for (uint64_t k = 0; k < 5; ++k) {
        uint32_t *d = m.indices[3] + (nh - 1 - 37 * k) * 8, *src = m.indices[3] + (11 + 53 * k) * 8;
        for (int j = 0; j < 8; ++j) d[j] = src[(j + 3) % 8];
    }
    memcpy(m.indices[0] + (nt - 2) * 4, m.indices[0] + 7 * 4, 16);
    clvr_mesh_update_ranges(&m);
    clvr_limits_report a, b;
    clvr_limits_scan(&m, &a);
    clvr_limits_scan_budget(&m, 12 * 1000, &b); /* many groups: 1000 pairs each */
    TU_CHECK(a.duplicates_checked && b.duplicates_checked);
    TU_CHECK_EQ_U64(a.duplicates, 6);
    TU_CHECK_EQ_U64(b.duplicates, a.duplicates);
    TU_CHECK_EQ_U64(b.first_duplicate, a.first_duplicate);
    TU_CHECK_EQ_U64(b.first_duplicate_type, a.first_duplicate_type);
    TU_CHECK_EQ_U64(b.duplicate_of, a.duplicate_of);
    clvr_mesh_free(&m);
}

static void test_host_check(void)
{
    clvr_error err = {0};
    const uint64_t cells[4] = {0, 0, 0, 30000000ull};
    clvr_mem_limits l = {UINT64_MAX, UINT64_MAX, 2500000ull * 1024 - 200000000ull, 0, NULL};
    l.limit = l.as_left;
    l.binding = "the address-space limit (ulimit -v, RLIMIT_AS)";
    TU_CHECK_STATUS(clvr_limits_check_host("big.bin", 31000000ull, cells, 4u << 20, 512, 512, 0, &l, &err),
                    CLVR_ERR_NO_MEMORY, &err);
    TU_CHECK(strstr(err.msg, "big.bin") && strstr(err.msg, "30000000 elements") && strstr(err.msg, "ulimit -v"));
    l.as_left = l.limit = 64ull << 30;
    TU_CHECK_STATUS(clvr_limits_check_host("big.bin", 31000000ull, cells, 4u << 20, 512, 512, 0, &l, &err), CLVR_OK,
                    &err);
    /* The estimate grows with the partition size and never undercuts the input. */
    clvr_host_estimate a, b;
    clvr_limits_host_estimate(31000000ull, cells, 1u << 20, 64, 64, &a);
    clvr_limits_host_estimate(31000000ull, cells, 0, 64, 64, &b);
    TU_CHECK(a.scratch_bytes < b.scratch_bytes);
    TU_CHECK(a.mesh_bytes == 31000000ull * 16 + 30000000ull * 32);
    /* Device estimate in partitions: the preprocessing buffers are one
     * partition's, so 80M hexes in 4M-element partitions have the 16-bit
     * local indices (2 bytes per slot of the whole mesh) as largest buffer. */
    clvr_mesh counts = {0};
    counts.num_vertices = 81000000ull;
    counts.num_cells[3] = 80000000ull;
    clvr_limits_estimate d1, dk;
    clvr_limits_estimate_parts(&counts, NULL, 0, 64, 64, &d1);
    clvr_limits_estimate_parts(&counts, NULL, 4u << 20, 64, 64, &dk);
    TU_CHECK(strcmp(d1.largest_buffer, "element indices") == 0 && d1.largest_buffer_bytes == 80000000ull * 32);
    TU_CHECK(strcmp(dk.largest_buffer, "16-bit indices") == 0 && dk.largest_buffer_bytes == 80000000ull * 16);
    TU_CHECK(dk.preprocess_peak_bytes * 10 < d1.preprocess_peak_bytes);
    clvr_mem_limits real;
    clvr_mem_limits_read(&real);
    TU_CHECK(real.limit > 0 && real.binding != NULL);
    uint64_t cur = 0, peak = 0;
    clvr_mem_rss(&cur, &peak);
    TU_CHECK(cur > 0 && peak >= cur);
}

int main(void)
{
    test_plans();
    test_scan_budget();
    test_host_check();
    clvr_cl cl;
    tu_open_device(&cl);
    clvr_error err = {0};
    {
        clvr_mesh m = {0};
        /* Conforming meshes (planar shared faces: a jittered mix would
         * overlap where a hex's bilinear face meets a tet's triangles, and a
         * point there may be found in either): unjittered mixed, jittered tets. */
        TU_CHECK_STATUS(fx_grid_mesh(12, FX_MIXED, 0.0f, 1.0f, 0.0f, 7, &m, &err), CLVR_OK, &err);
        clvr_mesh_update_ranges(&m);
        compare_points(&cl, &m, "mixed 12^3", 2);
        compare_points(&cl, &m, "mixed 12^3", 7);
        test_shared_box(&cl, &m);
        clvr_mesh_free(&m);
        TU_CHECK_STATUS(fx_grid_mesh(10, FX_TETS, 0.3f, 1.0f, 0.0f, 7, &m, &err), CLVR_OK, &err);
        clvr_mesh_update_ranges(&m);
        compare_points(&cl, &m, "jittered tets 10^3", 5);
        clvr_mesh_free(&m);
    }
    {
        /* K above the element count: empty partitions and partitions of one element. */
        clvr_mesh m = {0};
        TU_CHECK_STATUS(fx_grid_mesh(3, FX_MIXED, 0.0f, 1.0f, 0.0f, 9, &m, &err), CLVR_OK, &err);
        clvr_mesh_update_ranges(&m);
        compare_points(&cl, &m, "mixed 3^3", (uint32_t)clvr_mesh_num_elements(&m) + 13);
        clvr_mesh_free(&m);
    }
    test_consume(&cl);
    test_render_same(&cl);
    clvr_cl_destroy(&cl);
    return tu_finish("test_partition");
}
