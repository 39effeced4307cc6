/* mpi_composite.c: front-to-back compositing of per-rank urm records. */
#include "mpi_composite.h"

#include <math.h>

/* A uniform in [0, 1) from (seed, frame, pixel): splitmix64 of the key. */
static double key_uniform(uint64_t seed, uint32_t frame, uint32_t pixel)
{
    uint64_t z = seed ^ ((uint64_t)frame << 32 | pixel) * 0x9E3779B97F4A7C15ull;
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

void clvr_mpi_composite_pixel(const clvr_mpi_record *rec, size_t stride, uint32_t nranks,
                              const clvr_mpi_composite_params *p, uint32_t pixel, float rgba[4],
                              clvr_mpi_shadow_pick *pick)
{
    enum { MAXR = 4096 };
    uint32_t order[MAXR];
    double prefix[MAXR], w[MAXR];
    uint32_t n = nranks < MAXR ? nranks : MAXR;
    if (p->broken == CLVR_MPI_BREAK_RANK0 && n > 1) n = 1;
    /* Segments in depth order (insertion sort: N is small, and mostly
     * sorted from one pixel to the next would not help a gather anyway).
     * Rays that miss a region have a = +inf, tau = 1 and nothing to add. */
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t j = i;
        if (p->broken != CLVR_MPI_BREAK_ORDER)
            while (j > 0 && rec[order[j - 1] * stride].a > rec[i * stride].a) {
                order[j] = order[j - 1];
                --j;
            }
        order[j] = i;
    }
    double c[3] = {0, 0, 0}, T = 1.0, wtot = 0.0;
    for (uint32_t k = 0; k < n; ++k) {
        const clvr_mpi_record *r = rec + order[k] * stride;
        prefix[k] = T;
        for (int a = 0; a < 3; ++a) c[a] += T * r->e[a];
        /* The points of rank k weigh |prefix| W_k in the combined reservoir:
         * the prefix scales every one of their weights alike. */
        w[k] = fabs(T) * r->wsum;
        wtot += w[k];
        T *= r->tau;
    }
    for (int a = 0; a < 3; ++a) rgba[a] = (float)(c[a] + T * p->background[a]);
    rgba[3] = (float)(1.0 - T);
    pick->t = -1.0f;
    pick->g = 0.0f;
    pick->factor[0] = pick->factor[1] = pick->factor[2] = 0.0f;
    if (!p->shadows || !(wtot > 0.0)) return;
    /* One rank by |prefix| W, then its own pick: the point has probability
     * |prefix_k| w_i / wtot, so its term prefix_k g_i (T_light - G) divided
     * by that is sign(prefix_k) wtot (g_i / w_i) (T_light - G). */
    const double u = key_uniform(p->seed, p->frame, pixel) * wtot;
    double acc = 0.0;
    uint32_t k = 0;
    for (; k + 1 < n; ++k) {
        acc += w[k];
        if (u < acc && w[k] > 0.0) break;
    }
    while (k > 0 && !(w[k] > 0.0)) --k; /* rounding at the top end: the last rank with weight */
    const clvr_mpi_record *r = rec + order[k] * stride;
    const double sgn = prefix[k] < 0.0 ? -1.0 : 1.0;
    pick->t = r->pick[3];
    pick->g = r->pick_g;
    for (int a = 0; a < 3; ++a) pick->factor[a] = (float)(sgn * wtot * p->light_intensity * r->pick[a]);
}
