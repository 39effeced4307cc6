/* bench_points.h: the query points of the point-location benchmarks
 * (bench_locate, bench_locate_embree), so that every method sees the same
 * points. Header-only, static. */
#ifndef CLVR_BENCH_POINTS_H
#define CLVR_BENCH_POINTS_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "../tests/bvh_fixture.h"

/* ------------------------------------------------------------ query points */

typedef struct pkey {
    uint64_t key;
    uint32_t id;
} pkey;

static inline int pkey_cmp(const void *a, const void *b)
{
    const pkey *x = a, *y = b;
    return (x->key > y->key) - (x->key < y->key);
}

/* Uniform random points in the mesh bounds (the generator of bench_locate);
 * sorted: reordered along a Morton curve, as neighbouring rays' samples. */
static inline float (*bench_make_points(const clvr_mesh *m, uint32_t nq, int sorted))[4]
{
    float (*pts)[4] = malloc((size_t)(nq ? nq : 1) * sizeof *pts);
    if (!pts) return NULL;
    uint64_t rs = 42;
    for (uint32_t i = 0; i < nq; ++i) {
        for (int a = 0; a < 3; ++a) {
            rs += 0x9e3779b97f4a7c15ull;
            uint64_t z = rs;
            z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
            z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
            z ^= z >> 31;
            const float r = (float)(z >> 40) * (1.0f / 16777216.0f);
            pts[i][a] = m->bounds_lo[a] + r * (m->bounds_hi[a] - m->bounds_lo[a]);
        }
        pts[i][3] = 0.0f;
    }
    if (!sorted) return pts;
    pkey *k = malloc((size_t)(nq ? nq : 1) * sizeof *k);
    float (*tmp)[4] = malloc((size_t)(nq ? nq : 1) * sizeof *tmp);
    if (!k || !tmp) {
        free(k);
        free(tmp);
        free(pts);
        return NULL;
    }
    for (uint32_t i = 0; i < nq; ++i) {
        uint64_t q[3];
        for (int a = 0; a < 3; ++a) {
            const float ext = m->bounds_hi[a] - m->bounds_lo[a];
            const float f = ext > 0 ? (pts[i][a] - m->bounds_lo[a]) / ext : 0.0f;
            q[a] = (uint64_t)(fminf(fmaxf(f, 0.0f), 1.0f) * 65535.0f);
        }
        k[i].key = fx_spread(q[0]) | fx_spread(q[1]) << 1 | fx_spread(q[2]) << 2;
        k[i].id = i;
    }
    qsort(k, nq, sizeof *k, pkey_cmp);
    for (uint32_t i = 0; i < nq; ++i) memcpy(tmp[i], pts[k[i].id], sizeof tmp[i]);
    free(k);
    free(pts);
    return tmp;
}

/* The query hint of --hint NAME (NULL: coherent for sorted points,
 * incoherent for random ones) into *hints (CLVR_LOCATE_*); the name it took
 * into *name. Returns 0, or -1 when NAME is neither. */
static inline int bench_query_hint(const char *hint, int sorted, const char **name, unsigned *hints)
{
    if (!hint) hint = sorted ? "coherent" : "incoherent";
    if (strcmp(hint, "coherent") != 0 && strcmp(hint, "incoherent") != 0) return -1;
    *name = hint;
    *hints = !strcmp(hint, "coherent") ? CLVR_LOCATE_COHERENT : CLVR_LOCATE_INCOHERENT;
    return 0;
}

#endif /* CLVR_BENCH_POINTS_H */
