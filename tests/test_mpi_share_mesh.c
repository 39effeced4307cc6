/* test_mpi_share_mesh: the host parts of MPI mode without mpirun.
 *  - clvr_mpi_share_cut on the built-in scene for N = 1..5 ranks: every
 *    element is owned by exactly one rank (owned counts sum to the mesh's),
 *    a rank keeps exactly the elements whose vertex box overlaps its region
 *    (brute force over the whole mesh), local indices are in range and point
 *    at the same coordinates and scalars as the original vertices, and the
 *    global bounds and range are the whole mesh's.
 *  - clvr_mpi_composite_pixel against hand-computed composites: depth order
 *    whatever the rank order, prefix products, background, and the shadow
 *    pick: over many pixels, rank k is picked with frequency |P_k| W_k / W
 *    (binomial, 5 standard errors), with factor sign(P_k) W I g/w. */
#include "mpi_composite.h"
#include "mpi_share_mesh.h"
#include "scene.h"
#include "test_util.h"

#include <float.h>

static void box_of(const clvr_mesh *m, uint32_t t, uint64_t e, float lo[3], float hi[3])
{
    const uint32_t nv = clvr_cell_vertex_count(t);
    for (int a = 0; a < 3; ++a) { lo[a] = FLT_MAX; hi[a] = -FLT_MAX; }
    for (uint32_t k = 0; k < nv; ++k) {
        const float *p = m->positions + 3 * (uint64_t)m->indices[t][e * nv + k];
        for (int a = 0; a < 3; ++a) {
            lo[a] = fminf(lo[a], p[a]);
            hi[a] = fmaxf(hi[a], p[a]);
        }
    }
}

static void test_cut(void)
{
    clvr_error err = {0};
    clvr_mesh whole = {0};
    TU_CHECK(clvr_scene_default(&whole, &err) == CLVR_OK);
    const uint64_t n = clvr_mesh_num_elements(&whole);
    for (uint32_t nr = 1; nr <= 5; ++nr) {
        uint64_t owned = 0;
        for (uint32_t r = 0; r < nr; ++r) {
            clvr_mpi_share sh;
            TU_CHECK(clvr_mpi_share_cut(&whole, r, nr, &sh, &err) == CLVR_OK);
            owned += sh.owned_elements;
            TU_CHECK_EQ_U64(sh.global_elements, n);
            TU_CHECK(memcmp(sh.bounds_lo, whole.bounds_lo, sizeof sh.bounds_lo) == 0);
            TU_CHECK(memcmp(sh.bounds_hi, whole.bounds_hi, sizeof sh.bounds_hi) == 0);
            TU_CHECK(sh.scalar_min == whole.scalar_min && sh.scalar_max == whole.scalar_max);
            TU_CHECK(clvr_mesh_validate(&sh.mesh, "share", &err) == CLVR_OK);
            /* Brute force: the elements overlapping the region, in order,
             * are the share's, vertex by vertex. */
            int same = 1;
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
                const uint32_t nv = clvr_cell_vertex_count(t);
                uint64_t j = 0;
                for (uint64_t e = 0; e < whole.num_cells[t]; ++e) {
                    float lo[3], hi[3];
                    box_of(&whole, t, e, lo, hi);
                    if (!clvr_mpi_boxes_overlap(lo, hi, sh.region_lo, sh.region_hi)) continue;
                    if (j >= sh.mesh.num_cells[t]) { same = 0; break; }
                    for (uint32_t k = 0; k < nv; ++k) {
                        const uint32_t gv = whole.indices[t][e * nv + k], lv = sh.mesh.indices[t][j * nv + k];
                        if (lv >= sh.mesh.num_vertices ||
                            memcmp(whole.positions + 3 * (uint64_t)gv, sh.mesh.positions + 3 * (uint64_t)lv,
                                   3 * sizeof(float)) ||
                            whole.scalars[gv] != sh.mesh.scalars[lv])
                            same = 0;
                    }
                    ++j;
                }
                if (j != sh.mesh.num_cells[t]) same = 0;
            }
            TU_CHECK(same);
            if (nr > 1) TU_CHECK(clvr_mesh_num_elements(&sh.mesh) < n);
            clvr_mpi_share_free(&sh);
        }
        TU_CHECK_EQ_U64(owned, n);
    }
    clvr_mesh_free(&whole);
}

static clvr_mpi_record rec(float a, float tau, float w, float e, float pick, float t, float g)
{
    clvr_mpi_record r;
    memset(&r, 0, sizeof r);
    r.a = a;
    r.tau = tau;
    r.wsum = w;
    r.pick_g = g;
    r.e[0] = r.e[1] = r.e[2] = e;
    r.pick[0] = r.pick[1] = r.pick[2] = pick;
    r.pick[3] = t;
    return r;
}

static void test_composite(void)
{
    clvr_mpi_composite_params p;
    memset(&p, 0, sizeof p);
    p.background[0] = p.background[1] = p.background[2] = 0.5f;
    p.light_intensity = 2.0f;
    p.shadows = 1;
    p.seed = 7;
    float rgba[4];
    clvr_mpi_shadow_pick pk;
    /* Three ranks, given out of depth order; rank 1 misses the ray. Depth
     * order: rank 2 (a = 1), rank 0 (a = 4), rank 1 (a = inf). */
    const clvr_mpi_record r3[3] = {rec(4.0f, 0.5f, 3.0f, 0.2f, 0.1f, 4.5f, 0.7f),
                                   rec(INFINITY, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f),
                                   rec(1.0f, -0.4f, 1.0f, 0.3f, 0.05f, 1.5f, 0.9f)};
    clvr_mpi_composite_pixel(r3, 1, 3, &p, 0, rgba, &pk);
    /* c = 0.3 + (-0.4)(0.2) + (-0.4)(0.5)(0) ; T = -0.4 * 0.5 * 1 = -0.2 */
    TU_CHECK_NEAR(rgba[0], 0.3 - 0.4 * 0.2 + (-0.2) * 0.5, 1e-6);
    TU_CHECK_NEAR(rgba[3], 1.2, 1e-6);
    /* Weights: rank 2: |1| * 1 = 1; rank 0: |-0.4| * 3 = 1.2; W = 2.2. */
    const int n = 200000;
    int picked0 = 0, bad = 0;
    for (int px = 0; px < n; ++px) {
        clvr_mpi_composite_pixel(r3, 1, 3, &p, (uint32_t)px, rgba, &pk);
        if (pk.t == 4.5f) {
            ++picked0;
            /* sign(P) = -1: factor = -W I pick = -2.2 * 2 * 0.1 */
            if (fabsf(pk.factor[0] - (-0.44f)) > 1e-5f || pk.g != 0.7f) ++bad;
        } else if (pk.t == 1.5f) {
            if (fabsf(pk.factor[0] - 0.22f) > 1e-5f || pk.g != 0.9f) ++bad;
        } else
            ++bad;
    }
    TU_CHECK_EQ_U64(bad, 0);
    const double q = 1.2 / 2.2, se = sqrt(q * (1 - q) / n);
    TU_CHECK_NEAR((double)picked0 / n, q, 5 * se);
    /* No shadows: no pick. The test hooks change the result. */
    p.shadows = 0;
    clvr_mpi_composite_pixel(r3, 1, 3, &p, 0, rgba, &pk);
    TU_CHECK(pk.t < 0.0f);
    float good = rgba[0];
    p.broken = CLVR_MPI_BREAK_ORDER;
    clvr_mpi_composite_pixel(r3, 1, 3, &p, 0, rgba, &pk);
    TU_CHECK(fabsf(rgba[0] - good) > 1e-3f);
    p.broken = CLVR_MPI_BREAK_NONE;
    /* One rank: one process's formula (e + tau bg, pick factor W I g/w). */
    p.shadows = 1;
    clvr_mpi_composite_pixel(r3, 1, 1, &p, 3, rgba, &pk);
    TU_CHECK_NEAR(rgba[0], 0.2 + 0.5 * 0.5, 1e-6);
    TU_CHECK_NEAR(pk.factor[0], 3.0 * 2.0 * 0.1, 1e-6);
    TU_CHECK(pk.t == 4.5f);
}

int main(void)
{
    test_cut();
    test_composite();
    return tu_finish("test_mpi_share_mesh");
}
