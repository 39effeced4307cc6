/* Proves the scan, flagged-select and radix-sort kernels against their C
 * references on random inputs of sizes 0, 1, 2, primes and non-multiples of
 * every tile and work-group size, up to 2^20 + 7 (and 2^24 + 3 with --big):
 * exclusive sums equal, selections equal, and the sort equals a stable
 * reference sort for full 64-bit keys, 48-bit curve-like keys and keys with
 * many duplicates (stability: equal keys keep their input order, which the
 * values, set to the input positions, reveal). The sort is checked in its
 * three shapes: the device's default, hybrid at every size (top digit, then
 * the bucket kernel) and plain LSD at every size. */
#include "preprocess_stages.h"
#include "test_util.h"

static cl_mem upload(clvr_cl *cl, const void *p, size_t bytes)
{
    cl_mem b = NULL;
    clvr_error err = {0};
    TU_CHECK_STATUS(clvr_cl_buffer(cl, CL_MEM_READ_WRITE, bytes, NULL, "test buffer", &b, &err), CLVR_OK, &err);
    if (b && bytes && p) clEnqueueWriteBuffer(cl->queue, b, CL_TRUE, 0, bytes, p, 0, NULL, NULL);
    return b;
}

static void download(clvr_cl *cl, cl_mem b, void *p, size_t bytes)
{
    if (bytes) clEnqueueReadBuffer(cl->queue, b, CL_TRUE, 0, bytes, p, 0, NULL, NULL);
}

static void test_scan_select(clvr_cl *cl, clvr_pp *pp, uint64_t n, uint64_t *rng)
{
    clvr_error err = {0};
    uint32_t *in = malloc((n + 1) * 4), *ref = malloc((n + 1) * 4), *dev = malloc((n + 1) * 4);
    for (uint64_t i = 0; i < n; ++i) in[i] = (uint32_t)(tu_rand(rng) % 1000);
    uint32_t tref = clvr_pp_ref_scan(in, ref, n), tdev = 12345;
    cl_mem bi = upload(cl, in, n * 4), bo = upload(cl, NULL, n * 4);
    TU_CHECK_STATUS(clvr_pp_scan(pp, bi, bo, n, &tdev, NULL, &err), CLVR_OK, &err);
    download(cl, bo, dev, n * 4);
    TU_CHECK_EQ_U64(tdev, tref);
    TU_CHECK_EQ_U64(n ? memcmp(dev, ref, n * 4) : 0, 0);
    /* in place */
    TU_CHECK_STATUS(clvr_pp_scan(pp, bi, bi, n, &tdev, NULL, &err), CLVR_OK, &err);
    download(cl, bi, dev, n * 4);
    TU_CHECK_EQ_U64(n ? memcmp(dev, ref, n * 4) : 0, 0);
    /* flagged select of values and of ids, with about 1/3 flags set */
    uint32_t *flags = malloc((n + 1) * 4), *vals = malloc((n + 1) * 4);
    for (uint64_t i = 0; i < n; ++i) { flags[i] = tu_rand(rng) % 3 == 0 ? (uint32_t)(1 + i % 5) : 0; vals[i] = (uint32_t)tu_rand(rng); }
    cl_mem bf = upload(cl, flags, n * 4), bv = upload(cl, vals, n * 4);
    for (int ids = 0; ids <= 1; ++ids) {
        uint32_t cref = clvr_pp_ref_select(flags, ids ? NULL : vals, ref, n), cdev = 777;
        TU_CHECK_STATUS(clvr_pp_select(pp, bf, ids ? NULL : bv, bo, n, &cdev, NULL, &err), CLVR_OK, &err);
        TU_CHECK_EQ_U64(cdev, cref);
        download(cl, bo, dev, (size_t)cref * 4);
        TU_CHECK_EQ_U64(cref ? memcmp(dev, ref, (size_t)cref * 4) : 0, 0);
    }
    clvr_cl_release(cl, &bi); clvr_cl_release(cl, &bo); clvr_cl_release(cl, &bf); clvr_cl_release(cl, &bv);
    free(in); free(ref); free(dev); free(flags); free(vals);
}

/* kind 0: full 64-bit keys; 1: 48-bit keys with a 2-bit type above; 2: 5 distinct keys; 3: all keys equal
 * (no pass runs). */
static void test_sort(clvr_cl *cl, clvr_pp *pp, uint64_t n, int kind, int iota, uint64_t hint, uint64_t *rng)
{
    clvr_error err = {0};
    uint64_t *keys = malloc((n + 1) * 8), *rk = malloc((n + 1) * 8), *dk = malloc((n + 1) * 8);
    uint32_t *vals = malloc((n + 1) * 4), *rv = malloc((n + 1) * 4), *dv = malloc((n + 1) * 4);
    for (uint64_t i = 0; i < n; ++i) {
        uint64_t r = tu_rand(rng);
        keys[i] = kind == 0   ? r
                  : kind == 1 ? ((r >> 62) << 48) | (r & ((1ull << 48) - 1))
                  : kind == 2 ? (r % 5) * 0x0101010101ull
                              : 42;
        vals[i] = (uint32_t)i;
    }
    memcpy(rk, keys, n * 8);
    memcpy(rv, vals, n * 4);
    TU_CHECK_EQ_U64(clvr_pp_ref_sort(rk, rv, n), 0);
    /* iota: the values are not uploaded (the buffer holds garbage) and the
     * sort makes them; they are the reference's values 0..n-1 either way. */
    for (uint64_t i = 0; iota && i < n; ++i) vals[i] = 0xdeadbeefu;
    cl_mem bk = upload(cl, keys, n * 8), bv = upload(cl, vals, n * 4), tk = upload(cl, NULL, n * 8),
           tv = upload(cl, NULL, n * 4);
    TU_CHECK_STATUS(clvr_pp_sort(pp, &bk, &bv, &tk, &tv, n, iota, hint, NULL, &err), CLVR_OK, &err);
    download(cl, bk, dk, n * 8);
    download(cl, bv, dv, n * 4);
    uint64_t bad_k = 0, bad_v = 0, unsorted = 0, unstable = 0;
    for (uint64_t i = 0; i < n; ++i) {
        bad_k += dk[i] != rk[i];
        bad_v += dv[i] != rv[i];
        if (i) {
            unsorted += dk[i - 1] > dk[i];
            unstable += dk[i - 1] == dk[i] && dv[i - 1] > dv[i];
        }
    }
    if (bad_k || bad_v)
        fprintf(stderr, "sort n=%llu kind=%d iota=%d: %llu keys, %llu values differ\n", (unsigned long long)n, kind, iota,
                (unsigned long long)bad_k, (unsigned long long)bad_v);
    TU_CHECK_EQ_U64(bad_k, 0);
    TU_CHECK_EQ_U64(bad_v, 0);
    TU_CHECK_EQ_U64(unsorted, 0);
    TU_CHECK_EQ_U64(unstable, 0);
    /* The reference really is sorted and stable too (so the comparison means something). */
    uint64_t ref_bad = 0;
    for (uint64_t i = 1; i < n; ++i) ref_bad += rk[i - 1] > rk[i] || (rk[i - 1] == rk[i] && rv[i - 1] > rv[i]);
    TU_CHECK_EQ_U64(ref_bad, 0);
    clvr_cl_release(cl, &bk); clvr_cl_release(cl, &bv); clvr_cl_release(cl, &tk); clvr_cl_release(cl, &tv);
    free(keys); free(rk); free(dk); free(vals); free(rv); free(dv);
}

int main(int argc, char **argv)
{
    int big = argc > 1 && strcmp(argv[1], "--big") == 0;
    clvr_cl cl;
    clvr_pp pp;
    clvr_error err = {0};
    tu_open_device(&cl);
    TU_CHECK_STATUS(clvr_pp_create(&cl, &pp, &err), CLVR_OK, &err);
    if (!pp.prog) return tu_finish("test_sort");
    uint64_t rng = 1234;
    const uint64_t hybrid_default = pp.sort_hybrid_min, hybrid_min[] = {hybrid_default, 0, UINT64_MAX};
    if (big) {
        for (size_t m = 0; m < 3; ++m) {
            pp.sort_hybrid_min = hybrid_min[m];
            test_sort(&cl, &pp, (1ull << 24) + 3, 1, (int)(m & 1), m == 0 ? (3ull << 48) | ((1ull << 48) - 1) : 0, &rng);
        }
        test_scan_select(&cl, &pp, (1ull << 24) + 3, &rng);
    } else {
        /* Varying-bit hints: none, all bits, and the preprocessing's (type
         * bits over a 48-bit curve key), a superset of kinds 1..3's varying
         * bits but not of kind 0's, which gets all bits instead. */
        const uint64_t pp_hint = (3ull << 48) | ((1ull << 48) - 1);
        const uint64_t sizes[] = {0, 1, 2, 3, 255, 256, 257, 1031, 4097, 65537, 100003, (1u << 20) + 7};
        for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
            test_scan_select(&cl, &pp, sizes[i], &rng);
            for (size_t m = 0; m < 3; ++m) {
                pp.sort_hybrid_min = hybrid_min[m];
                for (int kind = 0; kind < 4; ++kind)
                    for (int iota = 0; iota <= 1; ++iota)
                        for (int h = 0; h < 3; ++h)
                            test_sort(&cl, &pp, sizes[i], kind, iota,
                                      h == 0 ? 0 : h == 1 || kind == 0 ? ~0ull : pp_hint, &rng);
            }
        }
    }
    clvr_pp_destroy(&pp);
    clvr_cl_destroy(&cl);
    return tu_finish(big ? "test_sort --big" : "test_sort");
}
