/* test_elements.c: containment and interpolation of kernels/elements.h on
 * the host (the very code the kernels run): round trips through the forward
 * map, exact reproduction of linear fields, points on faces, edges and
 * vertices, points outside, Newton hexes against their tet decomposition,
 * non-planar shared faces seen by both neighbours, degenerate, inverted and
 * NaN input; and kernels/cell_ray.h, where a ray leaves a cell, against
 * bisection on the containment test. */
#include "test_util.h"

#include "../kernels/elements.h"
#include "../kernels/cell_ray.h"

static const char *type_name(uint32_t t)
{
    static const char *n[4] = {"tet", "pyramid", "wedge", "hex"};
    return n[t & 3];
}

/* Reference element in VTK order, optionally distorted by `jit` (fraction
 * of the edge length) and scaled/offset. */
static void make_element(uint32_t type, float jit, float scale, float offset, uint64_t *rs, clvr_vec4 *v)
{
    static const float hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    static const float tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    static const float pyr[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}};
    static const float wdg[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
    const uint32_t nv = clvr_cell_vertex_count(type);
    for (uint32_t i = 0; i < nv; ++i) {
        const float *p = type == CLVR_CELL_TET ? tet[i] : type == CLVR_CELL_PYRAMID ? pyr[i]
                         : type == CLVR_CELL_WEDGE ? wdg[i] : hex[i];
        float q[3];
        for (int a = 0; a < 3; ++a) q[a] = (p[a] + jit * (2.0f * tu_randf(rs) - 1.0f)) * scale + offset;
        v[i].x = q[0]; v[i].y = q[1]; v[i].z = q[2];
        v[i].w = 0.0f;
    }
}

/* Linear field used to check interpolation exactly. */
static float lin(float x, float y, float z, float offset) { return 1.5f + 0.3f * (x - offset) - 0.7f * (y - offset) + 0.2f * (z - offset); }

static void random_param(uint32_t type, float margin, uint64_t *rs, float *u, float *v, float *w)
{
    for (;;) {
        *u = margin + (1.0f - 2.0f * margin) * tu_randf(rs);
        *v = margin + (1.0f - 2.0f * margin) * tu_randf(rs);
        *w = margin + (1.0f - 2.0f * margin) * tu_randf(rs);
        if (type == CLVR_CELL_TET && *u + *v + *w > 1.0f - margin) continue;
        if (type == CLVR_CELL_WEDGE && *u + *v > 1.0f - margin) continue;
        return;
    }
}

/* Inside points round-trip, interpolate a linear field exactly and come
 * back with their parametric coordinates. */
static void test_inside_linear(uint32_t type, float jit, float scale, float offset)
{
    uint64_t rs = 1234 + type;
    int bad_inside = 0, bad_value = 0, bad_param = 0;
    double worst = 0.0;
    for (int trial = 0; trial < 50; ++trial) {
        clvr_vec4 v[CLVR_CELL_MAX_VERTS];
        make_element(type, jit, scale, offset, &rs, v);
        for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) v[i].w = lin(v[i].x, v[i].y, v[i].z, offset);
        for (int k = 0; k < 40; ++k) {
            float u, vv, w, x, y, z, s = -1.0f;
            random_param(type, 0.01f, &rs, &u, &vv, &w);
            clvr_element_forward(type, v, u, vv, w, &x, &y, &z);
            if (!clvr_element_sample(type, v, x, y, z, &s)) { ++bad_inside; continue; }
            const double want = lin(x, y, z, offset);
            const double e = fabs(s - want) / fabs(want);
            if (e > worst) worst = e;
            if (e > 1e-4) ++bad_value;
            float pu, pv, pw;
            /* pyramid u, v are ill-conditioned near the apex: compare u (1 - w) */
            const float sc = type == CLVR_CELL_PYRAMID ? 1.0f - w : 1.0f;
            if (!clvr_element_invert(type, v, x, y, z, &pu, &pv, &pw) || fabsf(pu - u) * sc > 1e-3f ||
                fabsf(pv - vv) * sc > 1e-3f || fabsf(pw - w) > 1e-3f)
                ++bad_param;
        }
    }
    if (bad_inside || bad_value || bad_param)
        fprintf(stderr, "%s jit %g scale %g offset %g: %d not inside, %d wrong value (worst rel %g), %d wrong params\n",
                type_name(type), jit, scale, offset, bad_inside, bad_value, worst, bad_param);
    TU_CHECK_EQ_U64(bad_inside, 0);
    TU_CHECK_EQ_U64(bad_value, 0);
    TU_CHECK_EQ_U64(bad_param, 0);
}

/* Points on the boundary (faces, edges, vertices) are inside; points pushed
 * out of the parametric domain by 0.02 are outside. */
static void test_boundary_and_outside(uint32_t type)
{
    uint64_t rs = 99 + type;
    int lost = 0, false_in = 0;
    for (int trial = 0; trial < 40; ++trial) {
        clvr_vec4 v[CLVR_CELL_MAX_VERTS];
        make_element(type, 0.08f, 2.0f, -1.0f, &rs, v);
        for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) v[i].w = (float)i;
        /* vertices */
        for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) {
            float s = 0.0f;
            if (!clvr_element_sample(type, v, v[i].x, v[i].y, v[i].z, &s) || fabsf(s - (float)i) > 1e-4f) {
                ++lost;
                fprintf(stderr, "%s vertex %u lost or wrong (%g)\n", type_name(type), i, s);
            }
        }
        for (int k = 0; k < 60; ++k) {
            float u, vv, w, x, y, z, s = 0.0f;
            random_param(type, 0.0f, &rs, &u, &vv, &w);
            /* snap one or two coordinates to the domain boundary */
            const int which = k % 6;
            float *c[3] = {&u, &vv, &w};
            const int a = which % 3, b = (which + 1) % 3;
            if (type == CLVR_CELL_TET && which == 5) {
                /* slanted face u + v + w = 1 */
                const float sum = u + vv + w;
                u /= sum; vv /= sum; w /= sum;
            } else if (type == CLVR_CELL_WEDGE && which == 5) {
                const float sum = u + vv;
                u /= sum; vv /= sum;
            } else {
                *c[a] = (k & 1) && type != CLVR_CELL_TET ? 1.0f : 0.0f;
                if (which >= 3) *c[b] = 0.0f; /* an edge */
                if (type == CLVR_CELL_WEDGE && a < 2 && (k & 1)) { *c[a] = 1.0f; *c[1 - a] = 0.0f; }
            }
            clvr_element_forward(type, v, u, vv, w, &x, &y, &z);
            if (!clvr_element_sample(type, v, x, y, z, &s)) {
                ++lost;
                fprintf(stderr, "%s boundary point (%g %g %g) lost\n", type_name(type), u, vv, w);
            }
            /* outside: push a face coordinate 0.02 beyond the boundary */
            float ou = u, ov = vv, ow = w;
            if (type == CLVR_CELL_TET) {
                if (which == 5) { ou *= 1.03f; ov *= 1.03f; ow *= 1.03f; } else ou = -0.02f;
            } else if (type == CLVR_CELL_WEDGE && which == 5) {
                ou *= 1.03f; ov *= 1.03f;
            } else {
                float *oc[3] = {&ou, &ov, &ow};
                *oc[a] = *oc[a] > 0.5f ? 1.02f : -0.02f;
                if (type == CLVR_CELL_PYRAMID && a == 2 && ow > 0.5f) continue; /* beyond the apex: still a cone */
                /* near the apex a parametric push of 0.02 moves the point by
                 * 0.02 (1 - w): below the tolerance */
                if (type == CLVR_CELL_PYRAMID && ow > 0.9f) continue;
                if (type == CLVR_CELL_WEDGE && a < 2 && ou + ov > 1.0f) { ou = -0.02f; }
            }
            clvr_element_forward(type, v, ou, ov, ow, &x, &y, &z);
            if (clvr_element_sample(type, v, x, y, z, &s)) {
                ++false_in;
                fprintf(stderr, "%s outside point (%g %g %g) reported inside\n", type_name(type), ou, ov, ow);
            }
        }
    }
    TU_CHECK_EQ_U64(lost, 0);
    TU_CHECK_EQ_U64(false_in, 0);
}

/* An undistorted parallelepiped hex contains a point exactly when one of
 * its 6 Kuhn tets does: Newton against barycentrics, two independent paths. */
static void test_hex_vs_tets(void)
{
    clvr_vec4 h[8];
    const float e0[3] = {1.0f, 0.1f, 0.0f}, e1[3] = {0.2f, 0.9f, 0.1f}, e2[3] = {-0.1f, 0.2f, 1.1f};
    static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    for (int i = 0; i < 8; ++i) {
        h[i].x = 3.0f + off[i][0] * e0[0] + off[i][1] * e1[0] + off[i][2] * e2[0];
        h[i].y = -2.0f + off[i][0] * e0[1] + off[i][1] * e1[1] + off[i][2] * e2[1];
        h[i].z = 0.5f + off[i][0] * e0[2] + off[i][1] * e1[2] + off[i][2] * e2[2];
        h[i].w = h[i].x - 2.0f * h[i].y + 0.5f * h[i].z;
    }
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    uint64_t rs = 7;
    int disagree = 0, inside = 0, value = 0;
    for (int k = 0; k < 20000; ++k) {
        const float x = 2.7f + 2.0f * tu_randf(&rs), y = -2.3f + 1.8f * tu_randf(&rs), z = 0.3f + 1.6f * tu_randf(&rs);
        float sh = 0, st = 0;
        clvr_vec4 tv[4] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
        const int in_h = clvr_element_sample(CLVR_CELL_HEX, h, x, y, z, &sh);
        int in_t = 0;
        for (int t = 0; t < 6 && !in_t; ++t) {
            int b[3] = {0, 0, 0};
            tv[0] = h[0];
            for (int s2 = 0; s2 < 3; ++s2) {
                b[perm[t][s2]] = 1;
                for (int q = 0; q < 8; ++q)
                    if (off[q][0] == b[0] && off[q][1] == b[1] && off[q][2] == b[2]) tv[1 + s2] = h[q];
            }
            in_t = clvr_element_sample(CLVR_CELL_TET, tv, x, y, z, &st);
        }
        inside += in_h;
        if (in_h != in_t) ++disagree;
        else if (in_h && fabsf(sh - st) > 1e-4f * (1.0f + fabsf(st))) ++value;
    }
    TU_CHECK(inside > 2000);
    TU_CHECK_EQ_U64(disagree, 0);
    TU_CHECK_EQ_U64(value, 0);
}

/* Two hexes sharing a strongly non-planar quad face: points on the shared
 * bilinear patch are inside both; points just off it are inside exactly one. */
static void test_nonplanar_shared_face(void)
{
    clvr_vec4 a[8], b[8];
    static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    /* shared face x = 1 of a (vertices 1 2 6 5) = face x = 0 of b (0 3 7 4), twisted */
    const float twist[2][2] = {{0.0f, 0.3f}, {-0.25f, 0.0f}}; /* x offset at (y, z) corners */
    for (int i = 0; i < 8; ++i) {
        a[i].x = (float)off[i][0] + (off[i][0] ? twist[off[i][1]][off[i][2]] : 0.0f);
        a[i].y = (float)off[i][1];
        a[i].z = (float)off[i][2];
        b[i].x = 1.0f + (float)off[i][0] + (off[i][0] ? 0.0f : twist[off[i][1]][off[i][2]]);
        b[i].y = (float)off[i][1];
        b[i].z = (float)off[i][2];
        a[i].w = a[i].x * a[i].x + a[i].y;
        b[i].w = b[i].x * b[i].x + b[i].y;
    }
    uint64_t rs = 3;
    int both = 0, none_or_two = 0, value = 0;
    for (int k = 0; k < 2000; ++k) {
        const float y = tu_randf(&rs), z = tu_randf(&rs);
        float x, yy, zz, sa = 0.0f, sb = 0.0f;
        clvr_element_forward(CLVR_CELL_HEX, a, 1.0f, y, z, &x, &yy, &zz);
        const int ia = clvr_element_sample(CLVR_CELL_HEX, a, x, yy, zz, &sa);
        const int ib = clvr_element_sample(CLVR_CELL_HEX, b, x, yy, zz, &sb);
        both += ia && ib;
        if (ia && ib && fabsf(sa - sb) > 1e-4f) ++value;
        /* off the patch along x by 1e-3: exactly one contains it */
        const float d = (k & 1) ? 1e-3f : -1e-3f;
        const int ja = clvr_element_sample(CLVR_CELL_HEX, a, x + d, yy, zz, &sa);
        const int jb = clvr_element_sample(CLVR_CELL_HEX, b, x + d, yy, zz, &sb);
        if (ja + jb != 1) ++none_or_two;
    }
    TU_CHECK_EQ_U64(both, 2000);
    TU_CHECK_EQ_U64(value, 0);
    TU_CHECK_EQ_U64(none_or_two, 0);
}

/* Degenerate, inverted and NaN input neither crash, loop nor claim points. */
static void test_degenerate(void)
{
    uint64_t rs = 5;
    for (uint32_t t = 0; t < 4; ++t) {
        clvr_vec4 v[CLVR_CELL_MAX_VERTS];
        float s = 0;
        /* all vertices equal */
        for (int i = 0; i < 8; ++i) { v[i].x = 1.0f; v[i].y = 2.0f; v[i].z = 3.0f; v[i].w = 1.0f; }
        TU_CHECK(!clvr_element_sample(t, v, 1.5f, 2.0f, 3.0f, &s));
        /* flat: every vertex in the plane z = 0 */
        make_element(t, 0.0f, 1.0f, 0.0f, &rs, v);
        for (int i = 0; i < 8; ++i) v[i].z = 0.0f;
        TU_CHECK(!clvr_element_sample(t, v, 0.2f, 0.2f, 0.1f, &s));
        (void)clvr_element_sample(t, v, 0.2f, 0.2f, 0.0f, &s); /* must return, either answer */
        /* NaN vertex and NaN point */
        make_element(t, 0.0f, 1.0f, 0.0f, &rs, v);
        v[1].x = NAN;
        TU_CHECK(!clvr_element_sample(t, v, 0.2f, 0.2f, 0.2f, &s));
        make_element(t, 0.0f, 1.0f, 0.0f, &rs, v);
        TU_CHECK(!clvr_element_sample(t, v, NAN, 0.2f, 0.2f, &s));
        TU_CHECK(!clvr_element_sample(t, v, INFINITY, 0.2f, 0.2f, &s));
        /* a valid point still works in the same element */
        TU_CHECK(clvr_element_sample(t, v, 0.2f, 0.2f, 0.2f, &s));
    }
    /* inverted tet (two vertices swapped) still contains its interior */
    clvr_vec4 tv[4] = {{0, 0, 0, 0}, {0, 1, 0, 2}, {1, 0, 0, 1}, {0, 0, 1, 3}};
    float s = 0;
    TU_CHECK(clvr_element_sample(CLVR_CELL_TET, tv, 0.2f, 0.1f, 0.3f, &s));
    TU_CHECK_NEAR(s, 0.2f * 1 + 0.1f * 2 + 0.3f * 3, 1e-5);
    /* inside-out hex (top and bottom swapped): Newton still inverts it */
    clvr_vec4 h[8];
    make_element(CLVR_CELL_HEX, 0.0f, 1.0f, 0.0f, &rs, h);
    for (int i = 0; i < 4; ++i) { clvr_vec4 tmp = h[i]; h[i] = h[i + 4]; h[i + 4] = tmp; }
    for (int i = 0; i < 8; ++i) h[i].w = h[i].z;
    TU_CHECK(clvr_element_sample(CLVR_CELL_HEX, h, 0.3f, 0.6f, 0.25f, &s));
    TU_CHECK_NEAR(s, 0.25f, 1e-5);
    /* a hex bent so far it folds over itself: bounded work, no hang */
    make_element(CLVR_CELL_HEX, 0.0f, 1.0f, 0.0f, &rs, h);
    h[6].x = -2.0f; h[6].y = -2.0f; h[6].z = -1.0f;
    int n_in = 0;
    for (int k = 0; k < 1000; ++k)
        n_in += clvr_element_sample(CLVR_CELL_HEX, h, 2 * tu_randf(&rs) - 1, 2 * tu_randf(&rs) - 1, 2 * tu_randf(&rs) - 1, &s);
    TU_CHECK(n_in < 1000);
}

/* Newton's accuracy where it stops (elements.h, CLVR_NEWTON_STEP_TOL): on
 * cells distorted by a quarter of their edge, the coordinates returned lie
 * within 1e-5 of the true ones (those the point was made from) and the
 * interpolated scalar matches them, from the type's own start (far) and
 * from a start 0.03 away (a ray's next point in the same cell,
 * clvr_element_sample_near). test_inside_linear's 1e-3 would not see a
 * solve stopped after a step of 1e-2; this fails then (one step from the
 * near start leaves about 1e-4). */
static void test_newton_accuracy(uint32_t type)
{
    uint64_t rs = 4242 + type;
    int bad = 0, tried = 0;
    double worst = 0.0;
    for (int trial = 0; trial < 200; ++trial) {
        clvr_vec4 v[CLVR_CELL_MAX_VERTS];
        make_element(type, 0.25f, 1.0f, 0.0f, &rs, v);
        for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) v[i].w = tu_randf(&rs);
        for (int k = 0; k < 20; ++k) {
            float u, vv, w, x, y, z;
            random_param(type, 0.05f, &rs, &u, &vv, &w);
            if (type == CLVR_CELL_PYRAMID && w > 0.8f) continue; /* u, v ill-conditioned near the apex */
            clvr_element_forward(type, v, u, vv, w, &x, &y, &z);
            float N[CLVR_CELL_MAX_VERTS], Nu[CLVR_CELL_MAX_VERTS], Nv[CLVR_CELL_MAX_VERTS], Nw[CLVR_CELL_MAX_VERTS];
            clvr_element_shape(type, u, vv, w, N, Nu, Nv, Nw);
            double want = 0.0;
            for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) want += (double)N[i] * v[i].w;
            for (int near = 0; near < 2; ++near) {
                float pu = u + 0.03f * (2.0f * tu_randf(&rs) - 1.0f), pv = vv + 0.03f * (2.0f * tu_randf(&rs) - 1.0f),
                      pw = w + 0.03f * (2.0f * tu_randf(&rs) - 1.0f), s = -1.0f;
                ++tried;
                if (!clvr_element_sample_near(type, v, x, y, z, near, &pu, &pv, &pw, &s)) {
                    ++bad;
                    continue;
                }
                const double e = fmax(fmax(fabs(pu - u), fabs(pv - vv)), fabs(pw - w));
                if (e > worst) worst = e;
                if (e > 1e-5 || fabs(s - want) > 1e-5) ++bad;
            }
        }
    }
    if (bad) fprintf(stderr, "%s: %d of %d Newton solves off by more than 1e-5 (worst %g)\n", type_name(type), bad,
                     tried, worst);
    TU_CHECK(tried > 1000);
    TU_CHECK_EQ_U64(bad, 0);
}

/* Hexes whose map is affine in float, as axis-aligned solver meshes have
 * (snappyHexMesh's far field, AMR lattices, fire_ug.vtu): boxes of every
 * aspect down to 1e-4, 100 units from the origin, and sheared
 * parallelepipeds built from dyadic edge vectors (exact differences);
 * points inside and outside by at least 1e-3 of the parametric range
 * (against the coordinates of the float point itself, in double):
 * containment right, coordinates within 1e-5, the scalar the trilinear
 * one. Then a box with one vertex moved by 1e-3 of an edge: Newton must
 * still reach 1e-5. Session 52 measured a shortcut that stops after one
 * step when the bilinear and trilinear terms are exactly zero (host: a
 * hex test 96 -> 82 ns on fire_ug; PoCL: no change) and dropped it; a
 * shortcut with a tolerance instead of exact zeros fails the second part
 * (one step leaves about 1e-4 there). */
static void test_hex_affine(void)
{
    uint64_t rs = 777;
    int wrong = 0, tried = 0, off = 0;
    double worst = 0.0;
    for (int trial = 0; trial < 300; ++trial) {
        const int kind = trial % 3; /* 0 box, 1 thin box, 2 parallelepiped */
        double o[3], e[3][3] = {{0}};
        for (int k = 0; k < 3; ++k) o[k] = floor(200.0 * tu_randf(&rs)) - 100.0;
        if (kind < 2) {
            for (int k = 0; k < 3; ++k) e[k][k] = (0.25 + 4.0 * tu_randf(&rs)) * (kind == 1 && k == trial % 9 / 3 ? 1e-4 : 1.0);
        } else {
            for (int a = 0; a < 3; ++a)
                for (int k = 0; k < 3; ++k) e[a][k] = (a == k ? 8.0 : 0.0) + floor(8.0 * tu_randf(&rs) - 4.0) / 8.0;
        }
        clvr_vec4 v[8];
        static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
        for (int i = 0; i < 8; ++i) {
            double p[3];
            for (int k = 0; k < 3; ++k)
                p[k] = o[k] + corner[i][0] * e[0][k] + corner[i][1] * e[1][k] + corner[i][2] * e[2][k];
            v[i].x = (float)p[0];
            v[i].y = (float)p[1];
            v[i].z = (float)p[2];
            v[i].w = tu_randf(&rs);
        }
        /* the edges the float vertices have (a thin box's rounded ones) */
        static const int edge_end[3] = {1, 3, 4};
        for (int a = 0; a < 3; ++a) {
            const clvr_vec4 d = v[edge_end[a]];
            e[a][0] = (double)d.x - v[0].x;
            e[a][1] = (double)d.y - v[0].y;
            e[a][2] = (double)d.z - v[0].z;
        }
        for (int q = 0; q < 40; ++q) {
            const double a0 = 1.4 * tu_randf(&rs) - 0.2, a1 = 1.4 * tu_randf(&rs) - 0.2, a2 = 1.4 * tu_randf(&rs) - 0.2;
            float pt[3];
            for (int k = 0; k < 3; ++k) pt[k] = (float)(o[k] + a0 * e[0][k] + a1 * e[1][k] + a2 * e[2][k]);
            /* the parametric coordinates of the float point itself (Cramer in double) */
            double c[3], r[3];
            for (int k = 0; k < 3; ++k) r[k] = (double)pt[k] - (double)v[0].x * (k == 0) - (double)v[0].y * (k == 1) -
                                               (double)v[0].z * (k == 2);
            const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                               e[1][0] * (e[0][1] * e[2][2] - e[0][2] * e[2][1]) +
                               e[2][0] * (e[0][1] * e[1][2] - e[0][2] * e[1][1]);
            for (int j = 0; j < 3; ++j) {
                double m[3][3];
                for (int a = 0; a < 3; ++a)
                    for (int k = 0; k < 3; ++k) m[a][k] = a == j ? r[k] : e[a][k];
                c[j] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[1][0] * (m[0][1] * m[2][2] - m[0][2] * m[2][1]) +
                        m[2][0] * (m[0][1] * m[1][2] - m[0][2] * m[1][1])) / det;
            }
            const double lo = fmin(fmin(c[0], c[1]), c[2]), hi = fmax(fmax(c[0], c[1]), c[2]);
            const int inside = lo > 1e-3 && hi < 1.0 - 1e-3, outside = lo < -1e-3 || hi > 1.0 + 1e-3;
            if (!inside && !outside) continue;
            float pu = 0.0f, pv = 0.0f, pw = 0.0f, s = -1.0f;
            ++tried;
            const int found = clvr_element_sample_near(CLVR_CELL_HEX, v, pt[0], pt[1], pt[2], 0, &pu, &pv, &pw, &s);
            if (found != inside) {
                ++wrong;
                continue;
            }
            if (!found) continue;
            const double err = fmax(fmax(fabs(pu - c[0]), fabs(pv - c[1])), fabs(pw - c[2]));
            worst = fmax(worst, err);
            float N[8], Nu[8], Nv[8], Nw[8];
            clvr_element_shape(CLVR_CELL_HEX, (float)c[0], (float)c[1], (float)c[2], N, Nu, Nv, Nw);
            double want = 0.0;
            for (int i = 0; i < 8; ++i) want += (double)N[i] * v[i].w;
            if (err > 1e-5 || fabs(s - want) > 1e-5) ++off;
        }
    }
    if (wrong || off)
        fprintf(stderr, "affine hexes: %d of %d points on the wrong side, %d off (worst %g)\n", wrong, tried, off,
                worst);
    TU_CHECK(tried > 8000);
    TU_CHECK_EQ_U64(wrong, 0);
    TU_CHECK_EQ_U64(off, 0);
    /* a hair from affine: must iterate */
    int bad = 0, n = 0;
    for (int trial = 0; trial < 100; ++trial) {
        clvr_vec4 v[8];
        make_element(CLVR_CELL_HEX, 0.0f, 1.0f, 0.0f, &rs, v);
        v[6].x += 1e-3f * (tu_randf(&rs) < 0.5f ? 1.0f : -1.0f);
        v[6].z += 1e-3f;
        for (int q = 0; q < 20; ++q) {
            float u, vv, w, x, y, z;
            random_param(CLVR_CELL_HEX, 0.05f, &rs, &u, &vv, &w);
            clvr_element_forward(CLVR_CELL_HEX, v, u, vv, w, &x, &y, &z);
            float pu = 0.0f, pv = 0.0f, pw = 0.0f, s;
            ++n;
            if (!clvr_element_sample_near(CLVR_CELL_HEX, v, x, y, z, 0, &pu, &pv, &pw, &s) ||
                fmax(fmax(fabs(pu - u), fabs(pv - vv)), fabs(pw - w)) > 1e-5)
                ++bad;
        }
    }
    if (bad) fprintf(stderr, "nearly affine hexes: %d of %d solves off by more than 1e-5\n", bad, n);
    TU_CHECK_EQ_U64(bad, 0);
}

/* clvr_element_sample_near_settled's flag (the renderer skips a kept cell
 * in its next walk only when it is set): set for a point found inside and
 * for one Newton places outside, clear where Newton gives up (a cell
 * collapsed to a plane: singular Jacobian everywhere). */
static void test_settled(void)
{
    clvr_vec4 v[8];
    uint64_t rs = 5;
    make_element(CLVR_CELL_HEX, 0.1f, 1.0f, 0.0f, &rs, v);
    float u = 0.5f, vv = 0.5f, w = 0.5f, s = 0.0f;
    int settled = -1;
    TU_CHECK(clvr_element_sample_near_settled(CLVR_CELL_HEX, v, 0.5f, 0.5f, 0.5f, 1, &u, &vv, &w, &s, &settled));
    TU_CHECK_EQ_U64(settled, 1);
    u = vv = w = 0.5f;
    settled = -1;
    TU_CHECK(!clvr_element_sample_near_settled(CLVR_CELL_HEX, v, 1.6f, 0.5f, 0.5f, 1, &u, &vv, &w, &s, &settled));
    TU_CHECK_EQ_U64(settled, 1);
    for (int i = 0; i < 8; ++i) v[i].z = 0.0f; /* flat */
    u = vv = w = 0.5f;
    settled = -1;
    TU_CHECK(!clvr_element_sample_near_settled(CLVR_CELL_HEX, v, 0.5f, 0.5f, 0.0f, 1, &u, &vv, &w, &s, &settled));
    TU_CHECK_EQ_U64(settled, 0);
}

/* Pyramid apex (singular Jacobian) and wedge/pyramid interpolation at a
 * few hand-computed points. */
static void test_known_values(void)
{
    clvr_vec4 p[5] = {{0, 0, 0, 1}, {2, 0, 0, 2}, {2, 2, 0, 3}, {0, 2, 0, 4}, {1, 1, 2, 10}};
    float s = 0;
    TU_CHECK(clvr_element_sample(CLVR_CELL_PYRAMID, p, 1, 1, 2, &s));
    TU_CHECK_NEAR(s, 10.0, 1e-4);
    TU_CHECK(clvr_element_sample(CLVR_CELL_PYRAMID, p, 1, 1, 0, &s));
    TU_CHECK_NEAR(s, 2.5, 1e-5);
    TU_CHECK(clvr_element_sample(CLVR_CELL_PYRAMID, p, 1, 1, 1, &s)); /* half-way up the axis */
    TU_CHECK_NEAR(s, 0.5 * 2.5 + 0.5 * 10.0, 1e-5);
    TU_CHECK(!clvr_element_sample(CLVR_CELL_PYRAMID, p, 0.2f, 0.2f, 1.5f, &s));
    clvr_vec4 w[6] = {{0, 0, 0, 1}, {1, 0, 0, 2}, {0, 1, 0, 3}, {0, 0, 1, 4}, {1, 0, 1, 5}, {0, 1, 1, 6}};
    TU_CHECK(clvr_element_sample(CLVR_CELL_WEDGE, w, 0.25f, 0.25f, 0.5f, &s));
    TU_CHECK_NEAR(s, 0.5 * (0.5 * 1 + 0.25 * 2 + 0.25 * 3) + 0.5 * (0.5 * 4 + 0.25 * 5 + 0.25 * 6), 1e-5);
    TU_CHECK(!clvr_element_sample(CLVR_CELL_WEDGE, w, 0.6f, 0.6f, 0.5f, &s));
}


/* Inside test of world point p in cell v, no slack. */
static int inside_exact(uint32_t type, const clvr_vec4 *v, const double *p)
{
    float u, vv, w;
    return clvr_element_invert(type, v, (float)p[0], (float)p[1], (float)p[2], &u, &vv, &w) &&
           clvr_element_param_inside(type, u, vv, w, 0.0f);
}

/* The cell's own interpolation at world point p (its coordinates by
 * Newton, a point on a face a hair outside taken as it comes). */
static double interp_at(uint32_t type, const clvr_vec4 *v, const double *p)
{
    float u, vv, w, N[CLVR_CELL_MAX_VERTS], Nu[CLVR_CELL_MAX_VERTS], Nv[CLVR_CELL_MAX_VERTS], Nw[CLVR_CELL_MAX_VERTS];
    if (!clvr_element_invert(type, v, (float)p[0], (float)p[1], (float)p[2], &u, &vv, &w)) return NAN;
    clvr_element_shape(type, u, vv, w, N, Nu, Nv, Nw);
    double s = 0.0;
    for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) s += (double)N[i] * v[i].w;
    return s;
}

/* clvr_cell_exit (the walk's step through a cell that is not a tet) on
 * cells distorted by `jit` of their edge, so that quad faces are twisted
 * bilinear patches: from random inside points in random directions, the
 * exit's t against a march and bisection on the containment test (the
 * first point outside), and its scalar against the cell's interpolation
 * there. Then backward: the face the ray came in by, and from that entry,
 * skipping that face, the same exit again. */
static void test_cell_exit(uint32_t type, float jit)
{
    uint64_t rs = 777 + type + (uint64_t)(jit * 1000.0f);
    int tried = 0, bad_t = 0, bad_s = 0, bad_skip = 0, none = 0;
    double worst_t = 0.0, worst_s = 0.0;
    for (int trial = 0; trial < 300; ++trial) {
        clvr_vec4 v[CLVR_CELL_MAX_VERTS];
        make_element(type, jit, 2.0f, 5.0f, &rs, v);
        for (uint32_t i = 0; i < clvr_cell_vertex_count(type); ++i) v[i].w = 10.0f * tu_randf(&rs) - 3.0f;
        for (int k = 0; k < 10; ++k) {
            float pu, pv, pw, x, y, z;
            random_param(type, 0.1f, &rs, &pu, &pv, &pw);
            if (type == CLVR_CELL_PYRAMID && pw > 0.7f) continue;
            clvr_element_forward(type, v, pu, pv, pw, &x, &y, &z);
            float d[3];
            double dl = 0.0;
            for (int a = 0; a < 3; ++a) {
                d[a] = 2.0f * tu_randf(&rs) - 1.0f;
                dl += (double)d[a] * d[a];
            }
            if (dl < 0.01) continue;
            /* The ray starts 3 units before the point, so t_in = 3. */
            const float org[3] = {x - 3.0f * d[0], y - 3.0f * d[1], z - 3.0f * d[2]};
            const double P[3] = {x, y, z};
            if (!inside_exact(type, v, P)) continue;
            ++tried;
            float t_out = NAN, s_out = NAN;
            const int f = clvr_cell_exit(type, v, org, d, 3.0f, -1, &t_out, &s_out);
            if (f < 0) {
                ++none;
                continue;
            }
            /* March (steps of 1/400 of the cell's 2-unit size) to the first
             * point outside, then bisect. */
            const double h = 0.005 / sqrt(dl);
            double a = 0.0, b = 0.0;
            for (int i = 1; i < 4000; ++i) {
                const double q[3] = {x + d[0] * h * i, y + d[1] * h * i, z + d[2] * h * i};
                if (!inside_exact(type, v, q)) {
                    b = h * i;
                    a = h * (i - 1);
                    break;
                }
            }
            for (int i = 0; i < 40 && b > 0.0; ++i) {
                const double m = 0.5 * (a + b), q[3] = {x + d[0] * m, y + d[1] * m, z + d[2] * m};
                if (inside_exact(type, v, q)) a = m;
                else b = m;
            }
            const double te = 3.0 + 0.5 * (a + b), et = fabs(t_out - te) * sqrt(dl);
            if (et > worst_t) worst_t = et;
            if (!(et < 1e-3)) {
                if (bad_t < 3)
                    fprintf(stderr, "%s jit %g: exit at t %.6f, bisection %.6f (face %d)\n", type_name(type),
                            (double)jit, (double)t_out, te, f);
                ++bad_t;
                continue;
            }
            const double q[3] = {org[0] + d[0] * te, org[1] + d[1] * te, org[2] + d[2] * te};
            const double want = interp_at(type, v, q), es = fabs(s_out - want);
            if (es > worst_s) worst_s = es;
            if (!(es < 1e-2)) ++bad_s;
            /* Backward to the entry face, then forward from the entry
             * skipping it. */
            const float back[3] = {-d[0], -d[1], -d[2]};
            float t_back, s_back;
            const int fin = clvr_cell_exit(type, v, org, back, -3.0f, -1, &t_back, &s_back);
            float t2 = NAN, s2 = NAN;
            const int f2 = fin < 0 ? -1 : clvr_cell_exit(type, v, org, d, -t_back, fin, &t2, &s2);
            if (f2 != f || !(fabs(t2 - t_out) * sqrt(dl) < 1e-3)) ++bad_skip;
        }
    }
    if (bad_t || bad_s || bad_skip || none)
        fprintf(stderr, "%s jit %g: %d rays: %d exits off in t (worst %g), %d in the scalar (worst %g), "
                "%d not found again from the entry, %d without an exit\n", type_name(type), (double)jit, tried, bad_t,
                worst_t, bad_s, worst_s, bad_skip, none);
    TU_CHECK(tried > 1500);
    TU_CHECK_EQ_U64(bad_t, 0);
    TU_CHECK_EQ_U64(bad_s, 0);
    TU_CHECK(bad_skip <= tried / 500);
    TU_CHECK_EQ_U64(none, 0);
}

/* Newton's answer alone for a pyramid (clvr_element_sample starts with the
 * side planes this test checks against it). */
static int pyramid_newton(const clvr_vec4 *v, float x, float y, float z, float *s)
{
    float u, vv, w;
    return clvr_element_sample_near(CLVR_CELL_PYRAMID, v, x, y, z, 0, &u, &vv, &w, s);
}

/* clvr_pyramid_sides_hold never rejects a point Newton accepts: random
 * pyramids (from the reference one up to strongly warped and with an apex
 * pushed aside or below the base; scaled and far from the origin too),
 * points in and around their boxes and on their boundaries; and it does
 * reject most points outside that pass the box test (its reason to be).
 * Eight pyramids around a cube's centre (a split polyhedron): a point in
 * the cube passes several of their boxes and the test leaves one. */
static void test_pyramid_sides(void)
{
    uint64_t rs = 4242;
    int wrong = 0, outside_in_box = 0, rejected = 0;
    const float jits[5] = {0.0f, 0.05f, 0.2f, 0.45f, 0.8f}, scales[3] = {1.0f, 1e-3f, 0.5f}, offs[3] = {0.0f, 0.0f, 1000.0f};
    for (int trial = 0; trial < 600; ++trial) {
        clvr_vec4 v[CLVR_CELL_MAX_VERTS];
        const int j = trial % 5, k = trial / 5 % 3;
        make_element(CLVR_CELL_PYRAMID, jits[j], scales[k], offs[k], &rs, v);
        for (int q = 0; q < 200; ++q) {
            float x, y, z, s;
            if (q % 4 == 0) { /* on the boundary: one coordinate at 0 or 1 */
                float u, vv, w;
                random_param(CLVR_CELL_PYRAMID, 0.0f, &rs, &u, &vv, &w);
                float *c[3] = {&u, &vv, &w};
                *c[q / 4 % 3] = (q / 12) % 2 ? 1.0f : 0.0f;
                clvr_element_forward(CLVR_CELL_PYRAMID, v, u, vv, w, &x, &y, &z);
            } else {
                float lo[3], hi[3];
                clvr_element_vertex_box(CLVR_CELL_PYRAMID, v, lo, hi);
                x = lo[0] + (hi[0] - lo[0]) * (1.2f * tu_randf(&rs) - 0.1f);
                y = lo[1] + (hi[1] - lo[1]) * (1.2f * tu_randf(&rs) - 0.1f);
                z = lo[2] + (hi[2] - lo[2]) * (1.2f * tu_randf(&rs) - 0.1f);
            }
            const int in = pyramid_newton(v, x, y, z, &s);
            const int hold = clvr_pyramid_sides_hold(v, x, y, z);
            if (in && !hold) {
                if (wrong < 5) fprintf(stderr, "pyramid jit %g: (%g %g %g) inside but rejected\n", jits[j], x, y, z);
                ++wrong;
            }
            if (!in && clvr_element_box_test(CLVR_CELL_PYRAMID, v, x, y, z) && jits[j] <= 0.05f) {
                ++outside_in_box;
                rejected += !hold;
            }
        }
    }
    TU_CHECK_EQ_U64(wrong, 0);
    TU_CHECK(outside_in_box > 1000 && rejected > outside_in_box * 9 / 10);
    /* a unit cube split into 6 pyramids around its centre */
    static const int face[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    static const float cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    int multi = 0, bad_count = 0;
    for (int q = 0; q < 2000; ++q) {
        const float p[3] = {tu_randf(&rs), tu_randf(&rs), tu_randf(&rs)};
        int boxes = 0, held = 0, inside = 0;
        for (int f = 0; f < 6; ++f) {
            clvr_vec4 v[5];
            for (int i = 0; i < 4; ++i) {
                v[i].x = cube[face[f][i]][0]; v[i].y = cube[face[f][i]][1]; v[i].z = cube[face[f][i]][2]; v[i].w = 0.0f;
            }
            v[4].x = v[4].y = v[4].z = 0.5f;
            v[4].w = 0.0f;
            float s;
            boxes += clvr_element_box_test(CLVR_CELL_PYRAMID, v, p[0], p[1], p[2]);
            held += clvr_pyramid_sides_hold(v, p[0], p[1], p[2]);
            inside += pyramid_newton(v, p[0], p[1], p[2], &s);
        }
        multi += boxes >= 3;
        bad_count += held < inside || held > inside + 1; /* near a shared face two may hold it */
    }
    TU_CHECK(multi > 500);
    TU_CHECK_EQ_U64(bad_count, 0);
}

/* A tet, pyramid or wedge written as a collapsed 8-node hex (Exodus II's
 * degenerate HEX8, and preprocessing's one curve: clvr_hex_collapse_ids) is
 * recognised, and clvr_element_sample(HEX) answers as the type's own test,
 * bit for bit; corners one float step apart keep a hex a hex, and real
 * hexes are never taken for another type. */
static void test_collapsed_hex(void)
{
    static const uint32_t map[3][8] = {{0, 1, 2, 2, 3, 3, 3, 3}, {0, 1, 2, 3, 4, 4, 4, 4}, {0, 1, 2, 2, 3, 4, 5, 5}};
    uint64_t rs = 99;
    for (uint32_t t = CLVR_CELL_TET; t <= CLVR_CELL_WEDGE; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t), ids[8] = {0, 1, 2, 3, 4, 5, 6, 7};
        uint32_t hm[8];
        clvr_hex_collapse_ids(t, ids, hm); /* the forms above, which clvr_hex_collapsed reads back */
        TU_CHECK(memcmp(hm, map[t], sizeof hm) == 0);
        int wrong_type = 0, differ = 0, inside = 0, apart = 0;
        for (int trial = 0; trial < 300; ++trial) {
            clvr_vec4 v[8], h[8], c[8];
            make_element(t, 0.15f, 2.0f, -1.0f, &rs, v);
            for (uint32_t i = 0; i < nv; ++i) v[i].w = 10.0f * tu_randf(&rs);
            for (int k = 0; k < 8; ++k) h[k] = v[hm[k]];
            if (clvr_hex_collapsed(h, c) != t || memcmp(c, v, nv * sizeof *v) != 0) ++wrong_type;
            for (int q = 0; q < 60; ++q) {
                const float x = 2.6f * tu_randf(&rs) - 1.3f, y = 2.6f * tu_randf(&rs) - 1.3f,
                            z = 2.6f * tu_randf(&rs) - 1.3f;
                float sa = 0.0f, sb = 0.0f;
                const int a = clvr_element_sample(t, v, x, y, z, &sa), b = clvr_element_sample(CLVR_CELL_HEX, h, x, y, z, &sb);
                inside += a;
                if (a != b || (a && sa != sb)) ++differ;
            }
            /* a corner whose repetition makes the pattern, one step apart (moving
             * a tet's corner 3 instead leaves a pyramid with a sliver base: also right) */
            h[t == CLVR_CELL_WEDGE ? 3 : 7].x = nextafterf(h[t == CLVR_CELL_WEDGE ? 3 : 7].x, INFINITY);
            apart += clvr_hex_collapsed(h, c) != CLVR_CELL_HEX;
        }
        TU_CHECK_EQ_U64(wrong_type, 0);
        TU_CHECK_EQ_U64(differ, 0);
        TU_CHECK_EQ_U64(apart, 0);
        TU_CHECK(inside > 1000);
    }
    int taken = 0;
    for (int trial = 0; trial < 1000; ++trial) {
        clvr_vec4 v[8], c[8];
        make_element(CLVR_CELL_HEX, 0.15f, 2.0f, -1.0f, &rs, v);
        taken += clvr_hex_collapsed(v, c) != CLVR_CELL_HEX;
    }
    TU_CHECK_EQ_U64(taken, 0);
}

int main(void)
{
    test_pyramid_sides();
    for (uint32_t t = 0; t < 4; ++t) {
        test_inside_linear(t, 0.0f, 1.0f, 0.0f);
        test_inside_linear(t, 0.12f, 0.01f, 0.0f);
        test_inside_linear(t, 0.12f, 0.5f, 1000.0f); /* far from the origin */
        test_boundary_and_outside(t);
    }
    for (uint32_t t = CLVR_CELL_PYRAMID; t <= CLVR_CELL_HEX; ++t) test_newton_accuracy(t);
    test_settled();
    test_hex_affine();
    test_hex_vs_tets();
    test_nonplanar_shared_face();
    test_degenerate();
    test_collapsed_hex();
    test_known_values();
    for (uint32_t t = CLVR_CELL_PYRAMID; t <= CLVR_CELL_HEX; ++t) {
        test_cell_exit(t, 0.0f);
        test_cell_exit(t, 0.2f);
    }
    return tu_finish("test_elements");
}
