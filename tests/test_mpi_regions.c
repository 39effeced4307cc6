/* test_mpi_regions.c: the MPI mode's regions (mpi_share.h) without MPI:
 * the boxes tile the bounds (volumes add up, no two overlap with positive
 * volume), every point of the bounds has exactly one owner by the
 * half-open rule the header states (checked on points on every shared face
 * and on the bounds' upper faces, not only random ones), region_of returns
 * that owner, the counts are balanced, and the result does not depend on
 * the order of the centroids (what makes every rank's regions identical). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mpi_share.h"
#include "test_util.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static float frand(void) /* [0, 1) */
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (float)(rng_state >> 40) / (float)(1u << 24);
}

/* The owner rule of mpi_share.h written out: lo <= p < hi per axis, with
 * hi included where it is the bounds' upper face. */
static int owns(const float *box, const float top[3], const float p[3])
{
    for (int a = 0; a < 3; ++a)
        if (!(p[a] >= box[a] && (p[a] < box[3 + a] || (box[3 + a] == top[a] && p[a] <= box[3 + a])))) return 0;
    return 1;
}

static int owner_count(const float *regions, uint32_t nr, const float top[3], const float p[3], uint32_t *who)
{
    int n = 0;
    for (uint32_t r = 0; r < nr; ++r)
        if (owns(regions + 6 * r, top, p)) {
            ++n;
            *who = r;
        }
    return n;
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

static void check_case(uint64_t n, uint32_t nr, const float lo[3], const float hi[3], int clustered)
{
    float *c = malloc((n ? n : 1) * 3 * sizeof(float)), *c2 = malloc((n ? n : 1) * 3 * sizeof(float));
    float *orig = malloc((n ? n : 1) * 3 * sizeof(float));
    float *reg = malloc(6u * nr * sizeof(float)), *reg2 = malloc(6u * nr * sizeof(float));
    clvr_error err;
    for (uint64_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            float u = frand();
            if (clustered) u = u * u * u; /* most centroids near lo: bisection must still balance */
            c[3 * i + a] = lo[a] + (hi[a] - lo[a]) * u;
        }
    memcpy(orig, c, (n ? n : 1) * 3 * sizeof(float));
    /* The same centroids reversed give the same boxes. */
    for (uint64_t i = 0; i < n; ++i) memcpy(c2 + 3 * i, c + 3 * (n - 1 - i), 3 * sizeof(float));
    TU_CHECK_STATUS(clvr_mpi_regions(c, n, lo, hi, nr, reg, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_mpi_regions(c2, n, lo, hi, nr, reg2, &err), CLVR_OK, &err);
    TU_CHECK(memcmp(reg, reg2, 6u * nr * sizeof(float)) == 0);

    /* Tiling: inside the bounds, volumes add up, no positive-volume overlap. */
    double vol = 0.0, total = (double)(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    int inside = 1, overlap = 0;
    for (uint32_t r = 0; r < nr; ++r) {
        const float *b = reg + 6 * r;
        for (int a = 0; a < 3; ++a)
            if (!(b[a] >= lo[a] && b[3 + a] <= hi[a] && b[a] <= b[3 + a])) inside = 0;
        vol += (double)(b[3] - b[0]) * (b[4] - b[1]) * (b[5] - b[2]);
        for (uint32_t q = r + 1; q < nr; ++q) {
            const float *d = reg + 6 * q;
            double iv = 1.0;
            for (int a = 0; a < 3; ++a) {
                float l = b[a] > d[a] ? b[a] : d[a], h = b[3 + a] < d[3 + a] ? b[3 + a] : d[3 + a];
                iv *= h > l ? (double)(h - l) : 0.0;
            }
            if (iv > 0.0) overlap = 1;
        }
    }
    TU_CHECK(inside);
    TU_CHECK(!overlap);
    TU_CHECK_NEAR(vol, total, 1e-5 * total);

    /* Exactly one owner for every point on a grid made of every face
     * coordinate (each region's lo and hi), the midpoints between them and
     * the bounds: all shared faces, edges, corners and upper faces. */
    float *ax[3];
    uint32_t nax[3];
    for (int a = 0; a < 3; ++a) {
        ax[a] = malloc((4u * nr + 2) * sizeof(float));
        uint32_t k = 0;
        ax[a][k++] = lo[a];
        ax[a][k++] = hi[a];
        for (uint32_t r = 0; r < nr; ++r) {
            ax[a][k++] = reg[6 * r + a];
            ax[a][k++] = reg[6 * r + 3 + a];
        }
        qsort(ax[a], k, sizeof(float), cmp_float);
        uint32_t u = 0;
        for (uint32_t i = 0; i < k; ++i)
            if (u == 0 || ax[a][i] != ax[a][u - 1]) ax[a][u++] = ax[a][i];
        uint32_t m = u;
        for (uint32_t i = 0; i + 1 < u; ++i) ax[a][m++] = 0.5f * (ax[a][i] + ax[a][i + 1]);
        nax[a] = m;
    }
    const float top[3] = {hi[0], hi[1], hi[2]};
    int one_owner = 1, of_agrees = 1;
    for (uint32_t i = 0; i < nax[0]; ++i)
        for (uint32_t j = 0; j < nax[1]; ++j)
            for (uint32_t k = 0; k < nax[2]; ++k) {
                const float p[3] = {ax[0][i], ax[1][j], ax[2][k]};
                uint32_t who = UINT32_MAX;
                if (owner_count(reg, nr, top, p, &who) != 1) one_owner = 0;
                else if (clvr_mpi_region_of(reg, nr, p) != who) of_agrees = 0;
            }
    TU_CHECK(one_owner);
    TU_CHECK(of_agrees);
    for (int a = 0; a < 3; ++a) free(ax[a]);

    /* Balance: each region owns about n / nr of the centroids; each level
     * of the bisection rounds down once, so within the depth. */
    if (n > 0 && !clustered) {
        uint64_t *cnt = calloc(nr, sizeof *cnt);
        for (uint64_t i = 0; i < n; ++i) ++cnt[clvr_mpi_region_of(reg, nr, orig + 3 * i)];
        uint32_t depth = 0;
        while ((1u << depth) < nr) ++depth;
        int balanced = 1;
        for (uint32_t r = 0; r < nr; ++r) {
            double want = (double)n / nr;
            if ((double)cnt[r] < want - depth - 1 || (double)cnt[r] > want + depth + 1) {
                balanced = 0;
                fprintf(stderr, "n %llu ranks %u: region %u owns %llu, want %.1f\n", (unsigned long long)n, nr, r,
                        (unsigned long long)cnt[r], want);
            }
        }
        TU_CHECK(balanced);
        free(cnt);
    }
    if (n > 0 && clustered) { /* skewed centroids: still no empty region when n >= nr */
        uint64_t *cnt = calloc(nr, sizeof *cnt);
        for (uint64_t i = 0; i < n; ++i) ++cnt[clvr_mpi_region_of(reg, nr, orig + 3 * i)];
        int none_empty = 1;
        for (uint32_t r = 0; r < nr; ++r)
            if (n >= 8u * nr && cnt[r] == 0) none_empty = 0;
        TU_CHECK(none_empty);
        free(cnt);
    }
    free(c);
    free(c2);
    free(orig);
    free(reg);
    free(reg2);
}

int main(void)
{
    const float lo[3] = {-1.0f, -2.0f, 0.5f}, hi[3] = {3.0f, 1.0f, 1.5f};
    const uint64_t ns[] = {0, 1, 2, 13, 97, 1009, 20000};
    for (uint32_t nr = 1; nr <= 7; ++nr)
        for (size_t i = 0; i < sizeof ns / sizeof ns[0]; ++i) {
            check_case(ns[i], nr, lo, hi, 0);
            check_case(ns[i], nr, lo, hi, 1);
        }
    check_case(5000, 16, lo, hi, 0);
    check_case(5000, 13, lo, hi, 1);

    /* One rank: the bounds themselves, and every point is rank 0's. */
    {
        float reg[6], c[3] = {0, 0, 1};
        clvr_error err;
        TU_CHECK_STATUS(clvr_mpi_regions(c, 1, lo, hi, 1, reg, &err), CLVR_OK, &err);
        TU_CHECK(memcmp(reg, lo, sizeof lo) == 0 && memcmp(reg + 3, hi, sizeof hi) == 0);
        TU_CHECK(clvr_mpi_region_of(reg, 1, hi) == 0);
    }
    /* A flat mesh (zero extent on an axis) still tiles. */
    {
        const float flo[3] = {0, 0, 2}, fhi[3] = {1, 1, 2};
        check_case(100, 5, flo, fhi, 0);
    }
    /* Errors: zero ranks, NaN or inverted bounds. */
    {
        float reg[12], c[3] = {0, 0, 0};
        const float bad[3] = {NAN, 0, 0};
        clvr_error err;
        TU_CHECK_STATUS(clvr_mpi_regions(c, 1, lo, hi, 0, reg, &err), CLVR_ERR_USAGE, &err);
        TU_CHECK_STATUS(clvr_mpi_regions(c, 1, bad, hi, 2, reg, &err), CLVR_ERR_USAGE, &err);
        TU_CHECK_STATUS(clvr_mpi_regions(c, 1, hi, lo, 2, reg, &err), CLVR_ERR_USAGE, &err);
    }
    /* Box overlap: touching counts, a gap does not. */
    {
        const float a0[3] = {0, 0, 0}, a1[3] = {1, 1, 1}, b0[3] = {1, 0, 0}, b1[3] = {2, 1, 1};
        const float c0[3] = {1.0001f, 0, 0}, c1[3] = {2, 1, 1};
        TU_CHECK(clvr_mpi_boxes_overlap(a0, a1, b0, b1));
        TU_CHECK(!clvr_mpi_boxes_overlap(a0, a1, c0, c1));
        TU_CHECK(clvr_mpi_boxes_overlap(a0, a1, a0, a1));
    }
    return tu_finish("test_mpi_regions");
}
