/* Proves the space-filling curves: the Hilbert key is a bijection on full
 * grids of 1..5 bits per axis whose consecutive keys are face-adjacent cells
 * (the property that makes its clusters compact), encode(decode(h)) == h and
 * adjacency hold on random stretches of the 48-bit curve, Morton's bit
 * spreading inverts, and the device computes the same element keys (box ->
 * centre -> grid -> Hilbert or Morton) as the host, bit for bit, for element
 * counts 0, 1, 2, 1031 and 65537 of all four types. */
#include "bounds.h"
#include "preprocess_stages.h"
#include "sfc.h"
#include "test_util.h"

static int adjacent(const uint32_t *a, const uint32_t *b)
{
    uint32_t d = 0;
    for (int k = 0; k < 3; ++k) d += a[k] > b[k] ? a[k] - b[k] : b[k] - a[k];
    return d == 1;
}

static void test_small_grids(void)
{
    for (uint32_t bits = 1; bits <= 5; ++bits) {
        const uint32_t side = 1u << bits;
        const uint64_t cells = (uint64_t)side * side * side;
        unsigned char *seen = calloc(cells, 1);
        uint64_t bad_range = 0, bad_dup = 0, bad_adj = 0, bad_inv = 0;
        uint32_t prev[3] = {0, 0, 0};
        for (uint64_t h = 0; h < cells; ++h) {
            uint32_t c[3];
            clvr_hilbert3_decode(h, bits, c);
            if (c[0] >= side || c[1] >= side || c[2] >= side) { ++bad_range; continue; }
            uint64_t id = ((uint64_t)c[0] * side + c[1]) * side + c[2];
            bad_dup += seen[id]++;
            bad_inv += clvr_hilbert3_bits(c[0], c[1], c[2], bits) != h;
            if (h > 0) bad_adj += !adjacent(prev, c);
            memcpy(prev, c, sizeof prev);
        }
        TU_CHECK_EQ_U64(bad_range, 0);
        TU_CHECK_EQ_U64(bad_dup, 0);
        TU_CHECK_EQ_U64(bad_adj, 0);
        TU_CHECK_EQ_U64(bad_inv, 0);
        /* Every cell was reached, so encode is a bijection onto [0, 8^bits). */
        uint64_t missing = 0;
        for (uint64_t i = 0; i < cells; ++i) missing += seen[i] == 0;
        TU_CHECK_EQ_U64(missing, 0);
        free(seen);
    }
    /* The curve starts at the origin corner. */
    TU_CHECK_EQ_U64(clvr_hilbert3(0, 0, 0), 0);
}

static void test_full_curve(void)
{
    uint64_t rng = 7, bad_adj = 0, bad_inv = 0, bad_range = 0;
    for (int r = 0; r < 2000; ++r) {
        uint64_t h = tu_rand(&rng) & ((1ull << 48) - 1);
        if (h > (1ull << 48) - 64) h -= 64;
        uint32_t prev[3];
        clvr_hilbert3_decode(h, 16, prev);
        for (int j = 1; j < 32; ++j) {
            uint32_t c[3];
            clvr_hilbert3_decode(h + j, 16, c);
            bad_adj += !adjacent(prev, c);
            bad_range += c[0] > 65535 || c[1] > 65535 || c[2] > 65535;
            bad_inv += clvr_hilbert3(c[0], c[1], c[2]) != h + j;
            memcpy(prev, c, sizeof prev);
        }
    }
    TU_CHECK_EQ_U64(bad_adj, 0);
    TU_CHECK_EQ_U64(bad_inv, 0);
    TU_CHECK_EQ_U64(bad_range, 0);
    /* Keys use exactly 48 bits. */
    TU_CHECK(clvr_hilbert3(65535, 65535, 65535) < (1ull << 48));
    TU_CHECK(clvr_hilbert3(65535, 0, 0) >= (1ull << 47));
    /* Morton: spread and compact invert; x is the most significant axis; the
     * byte-table encoder equals the shift-mask spreading. */
    uint64_t bad_m = 0;
    for (int r = 0; r < 10000; ++r) {
        uint32_t v = (uint32_t)tu_rand(&rng) & 0xffff;
        bad_m += clvr_sfc_compact3(clvr_sfc_spread3(v)) != v;
        uint32_t x = (uint32_t)tu_rand(&rng) & 0xffff, y = (uint32_t)tu_rand(&rng) & 0xffff,
                 z = (uint32_t)tu_rand(&rng) & 0xffff;
        bad_m += clvr_morton3(x, y, z) != ((clvr_sfc_spread3(x) << 2) | (clvr_sfc_spread3(y) << 1) | clvr_sfc_spread3(z));
    }
    TU_CHECK_EQ_U64(bad_m, 0);
    TU_CHECK_EQ_U64(clvr_morton3(1, 0, 0), 4);
    TU_CHECK_EQ_U64(clvr_morton3(0, 1, 0), 2);
    TU_CHECK_EQ_U64(clvr_morton3(0, 0, 1), 1);
    TU_CHECK_EQ_U64(clvr_morton3(65535, 65535, 65535), (1ull << 48) - 1);
}

/* The table-driven encoder (clvr_hilbert3) equals the Butz-Moore/Skilling
 * sweep (clvr_hilbert3_bits at 16 bits) on random points, on every corner
 * and edge value, and on every point of a 32^3 block at the origin and at
 * the far corner (which walk every state of the table). */
static void test_table_encoder(void)
{
    uint64_t rng = 3, bad = 0, n = 0;
    for (int r = 0; r < 1000000; ++r, ++n) {
        uint32_t x = (uint32_t)tu_rand(&rng) & 0xffff, y = (uint32_t)tu_rand(&rng) & 0xffff,
                 z = (uint32_t)tu_rand(&rng) & 0xffff;
        bad += clvr_hilbert3(x, y, z) != clvr_hilbert3_bits(x, y, z, 16);
    }
    const uint32_t edge[] = {0, 1, 2, 0x7fff, 0x8000, 0x8001, 0xfffe, 0xffff};
    for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b)
            for (int c = 0; c < 8; ++c, ++n)
                bad += clvr_hilbert3(edge[a], edge[b], edge[c]) != clvr_hilbert3_bits(edge[a], edge[b], edge[c], 16);
    for (uint32_t base = 0; base <= 0xffe0; base += 0xffe0)
        for (uint32_t i = 0; i < 32; ++i)
            for (uint32_t j = 0; j < 32; ++j)
                for (uint32_t k = 0; k < 32; ++k, ++n)
                    bad += clvr_hilbert3(base + i, base + j, base + k) != clvr_hilbert3_bits(base + i, base + j, base + k, 16);
    if (bad) fprintf(stderr, "table encoder differs on %llu of %llu points\n", (unsigned long long)bad, (unsigned long long)n);
    TU_CHECK_EQ_U64(bad, 0);
}

/* Random elements (random vertices of a random cloud) of every type. */
static void test_device_keys(clvr_cl *cl, clvr_pp *pp)
{
    const uint64_t sizes[] = {0, 1, 2, 1031, 65537};
    uint64_t rng = 11;
    for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; ++si)
        for (int variant = 0; variant < 4; ++variant) {
            const int morton = variant & 1, one_curve = variant >> 1;
            clvr_error err = {0};
            uint64_t counts[4];
            for (int t = 0; t < 4; ++t) counts[t] = sizes[(si + (size_t)t) % (sizeof sizes / sizeof sizes[0])] / (t + 1);
            if (si == 0) counts[0] = counts[1] = counts[2] = counts[3] = 0;
            clvr_pp_layout L;
            clvr_pp_layout_make(&L, counts);
            const uint64_t V = 5000;
            float *pos = malloc(V * 12), *scal = malloc(V * 4);
            uint32_t *idx = malloc((L.num_slots + 1) * 4);
            for (uint64_t i = 0; i < V; ++i) {
                pos[3 * i] = -3.0f + 7.0f * tu_randf(&rng);
                pos[3 * i + 1] = 100.0f + 0.5f * tu_randf(&rng);
                pos[3 * i + 2] = 1e-3f * tu_randf(&rng);
                scal[i] = tu_randf(&rng);
            }
            for (uint64_t i = 0; i < L.num_slots; ++i) idx[i] = (uint32_t)(tu_rand(&rng) % V);
            clvr_box b;
            clvr_pp_ref_bounds(pos, scal, V, &b);
            uint64_t *hk = malloc((L.num_elements + 1) * 8), *dk = malloc((L.num_elements + 1) * 8);
            uint32_t *hv = malloc((L.num_elements + 1) * 4), *dv = malloc((L.num_elements + 1) * 4);
            clvr_pp_ref_keys(pos, idx, &L, &b, morton, one_curve, hk, hv);
            cl_mem bp = NULL, bi = NULL, bk = NULL, bv = NULL;
            TU_CHECK_STATUS(clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, V * 12, pos, "pos", &bp, &err), CLVR_OK, &err);
            /* No COPY_HOST_PTR: clvr_cl_buffer keeps that flag for empty arrays, which OpenCL rejects. */
            TU_CHECK_STATUS(clvr_cl_buffer(cl, CL_MEM_READ_ONLY, L.num_slots * 4, NULL, "idx", &bi, &err), CLVR_OK, &err);
            if (L.num_slots) clEnqueueWriteBuffer(cl->queue, bi, CL_TRUE, 0, L.num_slots * 4, idx, 0, NULL, NULL);
            TU_CHECK_STATUS(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, L.num_elements * 8, NULL, "keys", &bk, &err), CLVR_OK, &err);
            TU_CHECK_STATUS(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, L.num_elements * 4, NULL, "vals", &bv, &err), CLVR_OK, &err);
            TU_CHECK_STATUS(clvr_pp_keys(pp, bp, bi, &L, &b, morton, one_curve, bk, bv, NULL, &err), CLVR_OK, &err);
            if (L.num_elements) {
                clEnqueueReadBuffer(cl->queue, bk, CL_TRUE, 0, L.num_elements * 8, dk, 0, NULL, NULL);
                clEnqueueReadBuffer(cl->queue, bv, CL_TRUE, 0, L.num_elements * 4, dv, 0, NULL, NULL);
            }
            uint64_t bad = 0, badtype = 0;
            for (uint64_t i = 0; i < L.num_elements; ++i) {
                bad += dk[i] != hk[i] || dv[i] != hv[i];
                /* one curve: every key carries the hex type, so the sort merges the types */
                badtype += (hk[i] >> 48) != (one_curve ? CLVR_CELL_HEX : clvr_pp_type_of(i, L.first[1], L.first[2], L.first[3]));
            }
            if (bad)
                fprintf(stderr, "keys differ for %llu elements (morton %d, one curve %d)\n",
                        (unsigned long long)L.num_elements, morton, one_curve);
            TU_CHECK_EQ_U64(bad, 0);
            TU_CHECK_EQ_U64(badtype, 0);
            clvr_cl_release(cl, &bp); clvr_cl_release(cl, &bi); clvr_cl_release(cl, &bk); clvr_cl_release(cl, &bv);
            free(pos); free(scal); free(idx); free(hk); free(dk); free(hv); free(dv);
        }
}

int main(void)
{
    test_small_grids();
    test_full_curve();
    test_table_encoder();
    clvr_cl cl;
    clvr_pp pp;
    clvr_error err = {0};
    tu_open_device(&cl);
    TU_CHECK_STATUS(clvr_pp_create(&cl, &pp, &err), CLVR_OK, &err);
    if (pp.prog) test_device_keys(&cl, &pp);
    clvr_pp_destroy(&pp);
    clvr_cl_destroy(&cl);
    return tu_finish("test_sfc");
}
