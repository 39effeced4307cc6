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

/* Query orders: uniform random points in the mesh bounds; the same points
 * sorted along a Morton curve (neighbouring queries close in space); or
 * renderer-like rays: BENCH_RAY_SAMPLES stratified, jittered points along
 * each random chord of the bounds (a random point and direction, clipped
 * to the box), one ray after another, as urm's quadrature points are. */
enum { BENCH_ORDER_RANDOM = 0, BENCH_ORDER_SORTED = 1, BENCH_ORDER_RAYS = 2 };
#define BENCH_RAY_SAMPLES 24u

/* --order NAME into BENCH_ORDER_*, or -1. */
static inline int bench_order_from_name(const char *name)
{
    if (!strcmp(name, "random")) return BENCH_ORDER_RANDOM;
    if (!strcmp(name, "sorted")) return BENCH_ORDER_SORTED;
    if (!strcmp(name, "rays")) return BENCH_ORDER_RAYS;
    return -1;
}

/* Points a work item takes in sequence with one ray's hint: a ray's
 * samples for BENCH_ORDER_RAYS, 1 otherwise. */
static inline unsigned bench_order_chain(int order)
{
    return order == BENCH_ORDER_RAYS ? BENCH_RAY_SAMPLES : 1u;
}

static inline float bench_uniform(uint64_t *rs)
{
    *rs += 0x9e3779b97f4a7c15ull;
    uint64_t z = *rs;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (float)(z >> 40) * (1.0f / 16777216.0f);
}

/* BENCH_RAY_SAMPLES points per ray from nq / BENCH_RAY_SAMPLES rays (the
 * last ray shorter when nq is not a multiple). */
static inline void bench_ray_points(const clvr_mesh *m, uint32_t nq, float (*pts)[4])
{
    uint64_t rs = 4242;
    const float *lo = m->bounds_lo, *hi = m->bounds_hi;
    for (uint32_t first = 0; first < nq; first += BENCH_RAY_SAMPLES) {
        float o[3], d[3];
        for (int a = 0; a < 3; ++a) o[a] = lo[a] + bench_uniform(&rs) * (hi[a] - lo[a]);
        const float z = 2.0f * bench_uniform(&rs) - 1.0f, phi = 6.2831853f * bench_uniform(&rs);
        const float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        d[0] = r * cosf(phi);
        d[1] = r * sinf(phi);
        d[2] = z;
        /* the chord: slabs of the bounds around the interior point o */
        float t0 = -INFINITY, t1 = INFINITY;
        for (int a = 0; a < 3; ++a) {
            if (fabsf(d[a]) < 1e-12f) continue;
            float ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
            if (ta > tb) { float t = ta; ta = tb; tb = t; }
            t0 = fmaxf(t0, ta);
            t1 = fminf(t1, tb);
        }
        if (!(t0 <= t1) || !isfinite(t0) || !isfinite(t1)) t0 = t1 = 0.0f;
        for (uint32_t k = 0; k < BENCH_RAY_SAMPLES && first + k < nq; ++k) {
            const float t = t0 + ((float)k + bench_uniform(&rs)) / (float)BENCH_RAY_SAMPLES * (t1 - t0);
            for (int a = 0; a < 3; ++a) pts[first + k][a] = fminf(fmaxf(o[a] + t * d[a], lo[a]), hi[a]);
            pts[first + k][3] = 0.0f;
        }
    }
}

/* nq query points of the given order (BENCH_ORDER_*); NULL when out of memory. */
static inline float (*bench_make_points(const clvr_mesh *m, uint32_t nq, int order))[4]
{
    float (*pts)[4] = malloc((size_t)(nq ? nq : 1) * sizeof *pts);
    if (!pts) return NULL;
    if (order == BENCH_ORDER_RAYS) {
        bench_ray_points(m, nq, pts);
        return pts;
    }
    uint64_t rs = 42;
    for (uint32_t i = 0; i < nq; ++i) {
        for (int a = 0; a < 3; ++a) {
            const float r = bench_uniform(&rs);
            pts[i][a] = m->bounds_lo[a] + r * (m->bounds_hi[a] - m->bounds_lo[a]);
        }
        pts[i][3] = 0.0f;
    }
    if (order != BENCH_ORDER_SORTED) return pts;
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

/* The query hint of --hint NAME (NULL: coherent, for every order: the
 * incoherent walk's prefetches lost on random points too, see
 * CLVR_LOCATE_INCOHERENT) into *hints (CLVR_LOCATE_*); the name it took
 * into *name. Returns 0, or -1 when NAME is neither. */
static inline int bench_query_hint(const char *hint, const char **name, unsigned *hints)
{
    if (!hint) hint = "coherent";
    if (strcmp(hint, "coherent") != 0 && strcmp(hint, "incoherent") != 0) return -1;
    *name = hint;
    *hints = !strcmp(hint, "coherent") ? CLVR_LOCATE_COHERENT : CLVR_LOCATE_INCOHERENT;
    return 0;
}

#endif /* CLVR_BENCH_POINTS_H */
