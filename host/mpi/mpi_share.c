/* mpi_share.c: region bisection and share helpers (no MPI calls; see mpi_share.h). */
#include "mpi_share.h"

#include <stdlib.h>
#include <string.h>

/* Partial sort: after it, c[k] (by axis) is the k-th smallest and
 * c[0..k) <= c[k] <= c(k..n). Hoare-style quickselect on 3-float records
 * with the median of three as pivot; iterative, so deep inputs cannot
 * overflow the stack. */
static void swap3(float *a, float *b)
{
    float t[3];
    memcpy(t, a, sizeof t);
    memcpy(a, b, sizeof t);
    memcpy(b, t, sizeof t);
}

static void select_kth(float *c, uint64_t n, uint64_t k, int axis)
{
    uint64_t lo = 0, hi = n - 1;
    while (lo < hi) {
        uint64_t mid = lo + (hi - lo) / 2;
        float a = c[3 * lo + axis], b = c[3 * mid + axis], d = c[3 * hi + axis];
        float pivot = a < b ? (b < d ? b : (a < d ? d : a)) : (a < d ? a : (b < d ? d : b));
        uint64_t i = lo, j = hi;
        while (i <= j) {
            while (c[3 * i + axis] < pivot) ++i;
            while (c[3 * j + axis] > pivot) --j;
            if (i <= j) {
                swap3(c + 3 * i, c + 3 * j);
                ++i;
                if (j == 0) break;
                --j;
            }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else return;
    }
}

/* One level of the bisection: box [blo, bhi] with centroids c[0..n) and
 * ranks [r0, r0 + k). An explicit stack keeps it iterative. */
typedef struct {
    uint64_t first, n;
    uint32_t r0, k;
    float lo[3], hi[3];
} region_job;

clvr_status clvr_mpi_regions(float *centroids, uint64_t n, const float lo[3], const float hi[3], uint32_t nranks,
                             float *regions, clvr_error *err)
{
    if (nranks == 0) return clvr_error_set(err, CLVR_ERR_USAGE, "MPI regions: zero ranks");
    for (int a = 0; a < 3; ++a)
        if (!(lo[a] <= hi[a]))
            return clvr_error_set(err, CLVR_ERR_USAGE, "MPI regions: empty or NaN bounds on axis %d", a);
    /* Depth is at most ceil(log2(nranks)) + 1 and each level pushes two:
     * 2 * 33 entries cover any uint32_t rank count. */
    region_job stack[72];
    int top = 0;
    region_job j0 = {0, n, 0, nranks, {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    stack[top++] = j0;
    while (top > 0) {
        region_job j = stack[--top];
        if (j.k == 1) {
            memcpy(regions + 6u * j.r0, j.lo, sizeof j.lo);
            memcpy(regions + 6u * j.r0 + 3, j.hi, sizeof j.hi);
            continue;
        }
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (j.hi[a] - j.lo[a] > j.hi[axis] - j.lo[axis]) axis = a;
        const uint32_t kl = j.k / 2;
        /* The low side gets kl/k of the centroids: the split plane is the
         * centroid at that rank, clamped into the box (a sample's centroids
         * lie inside it; the clamp guards rounding). No centroids: halve the
         * box in proportion. */
        float split;
        uint64_t nl = (uint64_t)((double)j.n * kl / j.k);
        float *c = centroids + 3 * j.first;
        if (j.n > 0) {
            uint64_t kth = nl < j.n ? nl : j.n - 1;
            select_kth(c, j.n, kth, axis);
            split = c[3 * kth + axis];
            nl = kth;
        } else {
            split = j.lo[axis] + (j.hi[axis] - j.lo[axis]) * (float)kl / (float)j.k;
        }
        if (split < j.lo[axis]) split = j.lo[axis];
        if (split > j.hi[axis]) split = j.hi[axis];
        region_job a = j, b = j;
        a.n = nl;
        a.k = kl;
        a.hi[axis] = split;
        b.first = j.first + nl;
        b.n = j.n - nl;
        b.r0 = j.r0 + kl;
        b.k = j.k - kl;
        b.lo[axis] = split;
        stack[top++] = b;
        stack[top++] = a;
    }
    return CLVR_OK;
}

uint32_t clvr_mpi_region_of(const float *regions, uint32_t nranks, const float p[3])
{
    /* Bounds' upper faces: the maximum of the regions' upper corners. */
    float top[3] = {regions[3], regions[4], regions[5]};
    for (uint32_t r = 1; r < nranks; ++r)
        for (int a = 0; a < 3; ++a)
            if (regions[6u * r + 3 + a] > top[a]) top[a] = regions[6u * r + 3 + a];
    uint32_t best = 0;
    float best_d = -1.0f;
    for (uint32_t r = 0; r < nranks; ++r) {
        const float *lo = regions + 6u * r, *hi = lo + 3;
        int in = 1;
        float d = 0.0f;
        for (int a = 0; a < 3; ++a) {
            int inside = p[a] >= lo[a] && (p[a] < hi[a] || (hi[a] == top[a] && p[a] <= hi[a]));
            if (!inside) in = 0;
            float e = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0.0f);
            d += e * e;
        }
        if (in) return r;
        if (best_d < 0.0f || d < best_d) { best_d = d; best = r; }
    }
    return best;
}

int clvr_mpi_boxes_overlap(const float alo[3], const float ahi[3], const float blo[3], const float bhi[3])
{
    for (int a = 0; a < 3; ++a)
        if (ahi[a] < blo[a] || bhi[a] < alo[a]) return 0;
    return 1;
}

void clvr_mpi_share_free(clvr_mpi_share *s)
{
    if (!s) return;
    clvr_mesh_free(&s->mesh);
    free(s->owned);
    memset(s, 0, sizeof *s);
}
