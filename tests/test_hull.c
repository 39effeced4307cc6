/* test_hull: the mesh's boundary faces and the ray query over them
 * (kernels/hull.h, host/pipeline/hull.h).
 * 1. The face tables: every face of every type has distinct slots in range,
 *    and every edge of an element lies on exactly two of its faces (a
 *    closed surface), so a wrong slot in a table fails here.
 * 2. Boundary faces of lattices of 1, 2 and 7 cubes per axis, each type
 *    and mixed, jittered: the device's faces against the plain-C reference
 *    bit for bit, and their count against the lattice's (12 n^2 triangles
 *    of tets, 6 n^2 quads of pyramids and hexahedra, 4 n^2 triangles and
 *    4 n^2 quads of wedges).
 *    Keys cut to a few bits, so that many different faces share one: the
 *    host's and the device's flags agree and are still exact.
 * 3. The ray query on the device against brute force over every face, on
 *    random rays from outside and from inside the box, and against the
 *    exact entry and exit of the unjittered hex lattice (a cube); rays
 *    aimed at the lattice's boundary vertices and edges (where faces meet)
 *    must not slip through. Every crossing (clvr_hull_gaps): no face is
 *    crossed inside a gap, each gap ends at a crossing, the cut is
 *    clvr_hull_clip's, and a ray with more crossings than it keeps says so;
 *    on a lattice with a hole (gaps through it occur) and on a sieve of
 *    slabs (rays past CLVR_HULL_MAX_HITS crossings occur).
 * 4. Renders with and without the hull, same in distribution (per pixel
 *    and per 4x4 block, difference of means within 5 standard errors), urm
 *    and delta, on a lattice with a hole and a corner cut away (the medium
 *    starts inside the box, and a ray leaves and re-enters it: urm's camera
 *    rays skip the stretches between crossings that lie outside), from
 *    outside and from a camera inside the box, and on two real meshes:
 *    PLOT3D's post (a flow domain with a cylinder through it) and an FE
 *    notched specimen.
 * 5. The automatic mode: no hull for a mesh that fills its box, the hull
 *    kept for meshes that do not, and the first probe (through the
 *    clusters' boxes) never above the hull's. */
#include "accel.h"
#include "bvh_fixture.h"
#include "camera.h"
#include "hull.h"
#include "mesh_io.h"
#include "render.h"
#include "render_fixture.h"
#include "test_util.h"
#include "tf.h"

#include "../kernels/hull.h"

#include <stdlib.h>

#define K_SIGMA 5.0

/* ------------------------------------------------------------ 1. tables */
static void test_tables(void)
{
    for (clvr_u32 type = 0; type < CLVR_CELL_TYPE_COUNT; ++type) {
        const clvr_u32 nv = clvr_cell_vertex_count(type), nf = clvr_hull_face_count(type);
        int edges[8][8] = {{0}};
        int ok = 1;
        for (clvr_u32 f = 0; f < nf; ++f) {
            const clvr_u32 code = clvr_hull_face_code(type, f), n = (code >> 12) == 0xFu ? 3u : 4u;
            clvr_u32 s[4];
            for (clvr_u32 k = 0; k < n; ++k) {
                s[k] = (code >> (4 * k)) & 0xFu;
                ok &= s[k] < nv;
                for (clvr_u32 j = 0; j < k; ++j) ok &= s[j] != s[k];
            }
            if (!ok) break;
            for (clvr_u32 k = 0; k < n; ++k) {
                const clvr_u32 a = s[k], b = s[(k + 1) % n];
                edges[a][b]++;
                edges[b][a]++;
            }
        }
        TU_CHECK(ok);
        int closed = ok;
        for (int a = 0; a < 8 && ok; ++a)
            for (int b = 0; b < 8; ++b) closed &= edges[a][b] == 0 || edges[a][b] == 2;
        TU_CHECK(closed);
        /* Euler: V - E + F = 2 for each element's surface. */
        int ne = 0;
        for (int a = 0; a < 8; ++a)
            for (int b = a + 1; b < 8; ++b) ne += edges[a][b] > 0;
        TU_CHECK_EQ_U64((uint64_t)((int)nv - ne + (int)nf), 2);
    }
}

/* ------------------------------------------------------------ fixtures */
typedef struct fx_mesh {
    clvr_mesh m;
    clvr_clustered c;
    clvr_accel a;
} fx_mesh;

/* x's mesh clustered with the default options (no trees yet). */
static clvr_status fx_hull_cluster(clvr_cl *cl, fx_mesh *x, clvr_error *err)
{
    clvr_preprocess_options o;
    clvr_preprocess_options_default(&o);
    clvr_mesh_update_ranges(&x->m);
    return clvr_preprocess(cl, &x->m, &o, &x->c, err);
}

/* Clustered, with every tree and the hull always kept (CLVR_HULL_ON). */
static clvr_status fx_prepare(clvr_cl *cl, fx_mesh *x, clvr_error *err)
{
    clvr_status s = fx_hull_cluster(cl, x, err);
    if (s == CLVR_OK) s = clvr_accel_build_hull(cl, &x->c, CLVR_HULL_ON, &x->a, err);
    return s;
}

static void fx_free(clvr_cl *cl, fx_mesh *x)
{
    clvr_accel_release(cl, &x->a);
    clvr_clustered_release(cl, &x->c);
    clvr_mesh_free(&x->m);
}

/* The device hull read back: faces and tree. */
static int read_hull(clvr_cl *cl, const clvr_hull *h, clvr_hull_face **faces, clvr_bvh_node **nodes)
{
    *faces = malloc((size_t)h->num_faces * sizeof **faces + 1);
    *nodes = malloc((size_t)h->num_nodes * sizeof **nodes + 1);
    if (!*faces || !*nodes) return 0;
    if (h->num_faces == 0) return 1;
    return clEnqueueReadBuffer(cl->queue, h->faces, CL_TRUE, 0, (size_t)h->num_faces * sizeof **faces, *faces, 0,
                               NULL, NULL) == CL_SUCCESS &&
           clEnqueueReadBuffer(cl->queue, h->nodes, CL_TRUE, 0, (size_t)h->num_nodes * sizeof **nodes, *nodes, 0,
                               NULL, NULL) == CL_SUCCESS;
}

/* ------------------------------------------------------------ 2. faces */
static void test_faces(clvr_cl *cl)
{
    static const uint32_t sizes[] = {1, 2, 7};
    static const char *kinds[] = {"tets", "pyramids", "wedges", "hexes", "mixed"};
    for (uint32_t kind = 0; kind <= FX_MIXED; ++kind)
        for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; ++si) {
            const uint64_t n = sizes[si];
            clvr_error err = {0};
            fx_mesh x = {0};
            TU_CHECK_STATUS(fx_grid_mesh((uint32_t)n, kind, 0.15f, 1.0f, 0.0f, 11 + n, &x.m, &err), CLVR_OK, &err);
            TU_CHECK_STATUS(fx_prepare(cl, &x, &err), CLVR_OK, &err);
            if (err.status != CLVR_OK) {
                fx_free(cl, &x);
                continue;
            }
            clvr_clustered_host h = {0};
            TU_CHECK_STATUS(clvr_clustered_download(cl, &x.c, &h, &err), CLVR_OK, &err);
            clvr_hull_face *rf = NULL;
            float *rb = NULL;
            uint32_t rn = 0;
            TU_CHECK_STATUS(clvr_hull_build_ref(&h, x.c.num_instances, &rf, &rb, &rn, &err), CLVR_OK, &err);
            clvr_hull_face *df = NULL;
            clvr_bvh_node *dn = NULL;
            TU_CHECK(read_hull(cl, &x.a.hull, &df, &dn));
            TU_CHECK_EQ_U64(x.a.hull.num_faces, rn);
            TU_CHECK(rn == x.a.hull.num_faces && (rn == 0 || memcmp(df, rf, (size_t)rn * sizeof *rf) == 0));
            uint64_t tris = 0, quads = 0;
            for (uint32_t i = 0; i < x.a.hull.num_faces; ++i) {
                tris += df[i].p[0][3] == 3.0f;
                quads += df[i].p[0][3] == 4.0f;
            }
            const uint64_t n2 = n * n;
            const uint64_t want_t[] = {12 * n2, 0, 4 * n2, 0}, want_q[] = {0, 6 * n2, 4 * n2, 6 * n2};
            if (kind != FX_MIXED) {
                TU_CHECK_EQ_U64(tris, want_t[kind]);
                TU_CHECK_EQ_U64(quads, want_q[kind]);
            } else {
                TU_CHECK(tris + quads >= 6 * n2); /* non-conforming between types: more, never fewer */
            }
            printf("%s %llu^3: %llu elements, %llu face slots, %u boundary faces (%llu triangles, %llu quads)\n",
                   kinds[kind], (unsigned long long)n, (unsigned long long)x.c.num_elements,
                   (unsigned long long)x.a.hull.num_slots, x.a.hull.num_faces, (unsigned long long)tris,
                   (unsigned long long)quads);
            free(rf);
            free(rb);
            free(df);
            free(dn);
            clvr_clustered_host_free(&h);
            fx_free(cl, &x);
        }
}

/* Keys that collide: the same lattices' face slots with their keys cut to
 * K_BITS bits, so that runs of equal keys hold many different faces (the
 * 32-bit keys make a few hundred such pairs per million faces; duplicate
 * elements make runs too). The flags of clvr_hull_boundary on the host and
 * of the device's flags pass (whose short cuts handle runs of one and two)
 * must agree slot for slot and flag exactly the true boundary faces. */
#define K_BITS 10u

static void test_collisions(clvr_cl *cl)
{
    static const uint32_t kinds[] = {FX_TETS, FX_MIXED};
    for (size_t ki = 0; ki < sizeof kinds / sizeof kinds[0]; ++ki) {
        clvr_error err = {0};
        fx_mesh x = {0};
        TU_CHECK_STATUS(fx_grid_mesh(7, kinds[ki], 0.15f, 1.0f, 0.0f, 41, &x.m, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(fx_prepare(cl, &x, &err), CLVR_OK, &err);
        clvr_clustered_host h = {0};
        if (err.status == CLVR_OK) TU_CHECK_STATUS(clvr_clustered_download(cl, &x.c, &h, &err), CLVR_OK, &err);
        if (err.status != CLVR_OK) {
            fx_free(cl, &x);
            continue;
        }
        const uint64_t ni = x.c.num_instances;
        uint32_t *ff = malloc((ni + 1) * sizeof *ff), *slots = NULL, n = 0;
        uint64_t *keys = NULL;
        TU_CHECK_STATUS(clvr_hull_sorted_slots_ref(&h, ni, K_BITS, ff, &keys, &slots, &n, &err), CLVR_OK, &err);
        const clvr_mesh_view m = {NULL, NULL, h.instances, (const clvr_vec4 *)h.vertices, h.idx16, h.idx32, 0, 0,
                                  NULL, CLVR_VIEW_ONE_PIECE, NULL, NULL};
        uint32_t *hf = malloc(n * sizeof *hf + 1), *df = malloc(n * sizeof *df + 1);
        uint32_t longest = 0, run = 0, boundary = 0;
        for (uint32_t i = 0; i < n; ++i) {
            run = i > 0 && keys[i] == keys[i - 1] ? run + 1 : 1;
            longest = run > longest ? run : longest;
        }
        for (uint32_t i = 0; i < n; ++i) {
            hf[slots[i]] = clvr_hull_boundary(&m, h.instances, ff, (uint32_t)ni, n, keys, slots, i);
            boundary += hf[slots[i]];
        }
        /* Runs stay under CLVR_HULL_RUN, so the host's answer is exact. */
        TU_CHECK(longest >= 3 && longest <= CLVR_HULL_RUN);
        TU_CHECK_EQ_U64(boundary, x.a.hull.num_faces);
        /* The device's flags pass over the same sorted pairs. */
        cl_mem bff = NULL, bk = NULL, bs = NULL, bf = NULL;
        clvr_clustered_pieces pc;
        clvr_clustered_get_pieces(&x.c, &pc);
        const cl_uint cni = (cl_uint)ni, cn = n;
        clvr_status s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (ni + 1) * 4, ff, "ff", &bff, &err);
        if (s == CLVR_OK) s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)n * 8, keys, "k", &bk, &err);
        if (s == CLVR_OK) s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, (size_t)n * 4, slots, "s", &bs, &err);
        if (s == CLVR_OK) s = clvr_cl_buffer(cl, CL_MEM_READ_WRITE, (size_t)n * 4, NULL, "f", &bf, &err);
        cl_kernel k = x.a.kernels.hull_flags;
        if (s == CLVR_OK)
            s = CLVR_CL_ARGS(k, &err, CLVR_ARG(x.c.instances), CLVR_ARG(cni), CLVR_ARG(bff), CLVR_ARG(cn), CLVR_ARG(bk),
                             CLVR_ARG(bs), CLVR_ARG(bf), CLVR_ARG(pc.vertices[0]), CLVR_ARG(pc.idx16[0]),
                             CLVR_ARG(pc.idx32[0]), CLVR_ARG(pc.vertices[1]), CLVR_ARG(pc.idx16[1]),
                             CLVR_ARG(pc.idx32[1]), CLVR_ARG(pc.vertices[2]), CLVR_ARG(pc.idx16[2]),
                             CLVR_ARG(pc.idx32[2]), CLVR_ARG(pc.vertices[3]), CLVR_ARG(pc.idx16[3]),
                             CLVR_ARG(pc.idx32[3]));
        if (s == CLVR_OK) s = clvr_cl_run1d(cl, k, n, 64, NULL, &err);
        if (s == CLVR_OK && clEnqueueReadBuffer(cl->queue, bf, CL_TRUE, 0, (size_t)n * 4, df, 0, NULL, NULL) != CL_SUCCESS)
            s = CLVR_ERR_OPENCL;
        TU_CHECK_STATUS(s, CLVR_OK, &err);
        uint32_t differ = 0;
        for (uint32_t i = 0; s == CLVR_OK && i < n; ++i) differ += df[i] != hf[i];
        printf("colliding keys (%u bits), %s 7^3: %u slots, longest run %u, %u boundary faces, %u device flags differ\n",
               K_BITS, ki == 0 ? "tets" : "mixed", n, longest, boundary, differ);
        TU_CHECK_EQ_U64(differ, 0);
        clvr_cl_release(cl, &bff);
        clvr_cl_release(cl, &bk);
        clvr_cl_release(cl, &bs);
        clvr_cl_release(cl, &bf);
        free(keys);
        free(slots);
        free(hf);
        free(df);
        free(ff);
        clvr_clustered_host_free(&h);
        fx_free(cl, &x);
    }
}

/* ------------------------------------------------------------ 3. rays */

/* A random point on the sphere of the given radius around (c, c, c). */
static void sphere_point(uint64_t *rs, float c, float radius, float o[3])
{
    float u[3], l = 0;
    for (int k = 0; k < 3; ++k) {
        u[k] = tu_randf(rs) - 0.5f;
        l += u[k] * u[k];
    }
    l = sqrtf(l) + 1e-6f;
    for (int k = 0; k < 3; ++k) o[k] = c + radius * u[k] / l;
}

/* First and last crossing of the line org + t dir with every face. */
static void brute(const clvr_hull_face *f, uint32_t n, const float o[3], const float d[3], float *lo, float *hi)
{
    const clvr_hull_ray r = clvr_hull_ray_make(o[0], o[1], o[2], d[0], d[1], d[2]);
    *lo = INFINITY;
    *hi = -INFINITY;
    for (uint32_t i = 0; i < n; ++i) clvr_hull_ray_face(&r, &f[i], lo, hi);
}

static void test_rays(clvr_cl *cl)
{
    static const uint32_t kinds[] = {FX_TETS, FX_HEXES, FX_WEDGES, FX_MIXED, FX_HEXES};
    for (size_t ki = 0; ki < sizeof kinds / sizeof kinds[0]; ++ki) {
        const int cube = ki == 4; /* unjittered hexes: the hull is the cube [0, 5]^3 */
        const uint32_t N = 5;
        clvr_error err = {0};
        fx_mesh x = {0};
        TU_CHECK_STATUS(fx_grid_mesh(N, kinds[ki], cube ? 0.0f : 0.35f, 1.0f, 0.0f, 3 + ki, &x.m, &err), CLVR_OK,
                        &err);
        TU_CHECK_STATUS(fx_prepare(cl, &x, &err), CLVR_OK, &err);
        clvr_hull_face *df = NULL;
        clvr_bvh_node *dn = NULL;
        if (err.status != CLVR_OK || !read_hull(cl, &x.a.hull, &df, &dn)) {
            TU_CHECK(0);
            free(df);
            free(dn);
            fx_free(cl, &x);
            continue;
        }
        enum { NR = 2000, NV = 36 };
        const uint32_t nr = NR + NV;
        float *org = calloc(4 * nr, sizeof(float)), *dir = calloc(4 * nr, sizeof(float)),
              *res = calloc(4 * nr, sizeof(float));
        uint64_t rs = 99 + ki;
        for (uint32_t i = 0; i < NR; ++i) {
            /* From a random point on a sphere around the box (or, one ray in
             * four, inside the box) toward a random point of the box grown by
             * 20% (some rays miss). */
            float o[3], t[3];
            const int inside = i % 4 == 3;
            for (int c = 0; c < 3; ++c) t[c] = -1.0f + 7.0f * tu_randf(&rs);
            if (inside) {
                for (int c = 0; c < 3; ++c) o[c] = 0.2f + 4.6f * tu_randf(&rs);
            } else {
                sphere_point(&rs, 2.5f, 12.0f, o);
            }
            for (int c = 0; c < 3; ++c) {
                org[4 * i + c] = o[c];
                dir[4 * i + c] = t[c] - o[c];
            }
        }
        /* Rays from outside aimed at lattice points inside the bottom face
         * (where 4 to 8 boundary triangles meet) and at edge midpoints. */
        for (uint32_t i = 0; i < NV; ++i) {
            const uint32_t k = NR + i;
            const float t[3] = {(float)(1 + i % 4), (float)(1 + (i / 4) % 4) - (i % 2 ? 0.5f : 0.0f), 0.0f};
            const float o[3] = {2.1f + 0.37f * (float)(i % 5), 1.3f + 0.21f * (float)(i % 7), -7.0f};
            for (int c = 0; c < 3; ++c) {
                org[4 * k + c] = o[c];
                dir[4 * k + c] = t[c] - o[c];
            }
        }
        TU_CHECK_STATUS(clvr_hull_rays(cl, &x.a.kernels, &x.a.hull, org, dir, nr, res, &err), CLVR_OK, &err);
        uint32_t bad_hit = 0, bad_t = 0, slipped = 0, bad_cube = 0, hits = 0;
        for (uint32_t i = 0; i < nr; ++i) {
            const float *o = org + 4 * i, *d = dir + 4 * i, *r = res + 4 * i;
            const int inside = i < NR && i % 4 == 3;
            float lo, hi;
            brute(df, x.a.hull.num_faces, o, d, &lo, &hi);
            /* Crossings ahead of the origin only decide a hit, from outside
             * the box and from inside it alike. */
            const int want_hit = hi >= 0.0f;
            const int hit = r[2] != 0.0f;
            hits += hit;
            if (i >= NR) slipped += !hit;
            if (hit != want_hit) {
                ++bad_hit;
                if (getenv("HULL_DEBUG"))
                    fprintf(stderr, "ray %u o %g %g %g d %g %g %g: device %g %g %g, brute %g %g\n", i, o[0], o[1], o[2],
                            d[0], d[1], d[2], r[0], r[1], r[2], lo, hi);
            }
            if (!hit || !want_hit) continue;
            const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            const float tol = 2e-4f * (15.0f / len);
            const float w0 = inside ? 0.0f : fmaxf(lo, 0.0f);
            /* Never cut medium off: t0 at or before the first crossing,
             * t1 at or after the last; and not far from them. */
            if (!(r[0] <= w0 + 1e-6f && r[0] >= w0 - tol)) ++bad_t;
            if (!(r[1] >= hi - 1e-6f && r[1] <= hi + tol)) ++bad_t;
            if (cube) {
                /* The cube [0, 5]^3: the slab test's entry and exit. */
                float a = 0.0f, b = INFINITY;
                for (int c = 0; c < 3; ++c) {
                    const float inv = 1.0f / d[c], t0 = (0.0f - o[c]) * inv, t1 = (5.0f - o[c]) * inv;
                    a = fmaxf(a, fminf(t0, t1));
                    b = fminf(b, fmaxf(t0, t1));
                }
                if (!(fabsf(r[0] - a) <= tol && fabsf(r[1] - b) <= tol)) ++bad_cube;
            }
        }
        printf("rays, lattice kind %u%s: %u of %u hit, %u wrong hit/miss, %u intervals off, %u slipped through, "
               "%u off the cube\n",
               kinds[ki], cube ? " (cube)" : "", hits, nr, bad_hit, bad_t, slipped, bad_cube);
        TU_CHECK(hits > nr / 4 && hits < nr); /* both outcomes occur: the test can fail */
        TU_CHECK_EQ_U64(bad_hit, 0);
        TU_CHECK_EQ_U64(bad_t, 0);
        TU_CHECK_EQ_U64(slipped, 0);
        TU_CHECK_EQ_U64(bad_cube, 0);
        free(org);
        free(dir);
        free(res);
        free(df);
        free(dn);
        fx_free(cl, &x);
    }
}

/* ------------------------------------------------------------ 4. renders */

/* out: the cells of m whose centroid c passes keep(c, ctx) (m is freed). */
static clvr_status filter_mesh(clvr_mesh *m, int (*keep_cell)(const float *c, const float *ctx), const float *ctx,
                               clvr_mesh *out, clvr_error *err)
{
    uint64_t counts[CLVR_CELL_TYPE_COUNT] = {0};
    uint8_t *keep[CLVR_CELL_TYPE_COUNT] = {0};
    clvr_status s = CLVR_OK;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        keep[t] = malloc(m->num_cells[t] + 1);
        if (!keep[t]) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory filtering a test mesh");
            goto cleanup;
        }
        for (uint64_t e = 0; e < m->num_cells[t]; ++e) {
            float c[3] = {0, 0, 0};
            for (uint32_t k = 0; k < nv; ++k)
                for (int a = 0; a < 3; ++a) c[a] += m->positions[3 * (uint64_t)m->indices[t][e * nv + k] + a] / nv;
            keep[t][e] = (uint8_t)keep_cell(c, ctx);
            counts[t] += keep[t][e];
        }
    }
    s = clvr_mesh_alloc(out, m->num_vertices, counts, err);
    if (s == CLVR_OK) {
        memcpy(out->positions, m->positions, m->num_vertices * 3 * sizeof(float));
        memcpy(out->scalars, m->scalars, m->num_vertices * sizeof(float));
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            const uint32_t nv = clvr_cell_vertex_count(t);
            uint64_t k = 0;
            for (uint64_t e = 0; e < m->num_cells[t]; ++e)
                if (keep[t][e]) memcpy(out->indices[t] + nv * k++, m->indices[t] + nv * e, nv * sizeof(uint32_t));
        }
        clvr_mesh_update_ranges(out);
    }
cleanup:
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) free(keep[t]);
    clvr_mesh_free(m);
    return s;
}

/* ctx: n. Outside the ball of radius n/4 around the centre and the octant
 * above (0.6n, 0.6n, 0.6n). */
static int keep_holed(const float *c, const float *ctx)
{
    const float n = ctx[0], h = 0.5f * n, r2 = n * n / 16.0f, cut = 0.6f * n;
    const float d2 = (c[0] - h) * (c[0] - h) + (c[1] - h) * (c[1] - h) + (c[2] - h) * (c[2] - h);
    return !(d2 < r2) && !(c[0] > cut && c[1] > cut && c[2] > cut);
}

/* Every other slab of cells across x. */
static int keep_sieve(const float *c, const float *ctx)
{
    (void)ctx;
    return ((int)floorf(c[0])) % 2 == 0;
}

/* The lattice of n^3 cubes of the kind (FX_*) with a ball of radius n/4
 * around the centre and the octant above (0.6n, 0.6n, 0.6n) removed. */
static clvr_status holed_mesh_of(uint32_t n, uint32_t kind, clvr_mesh *out, clvr_error *err)
{
    clvr_mesh m = {0};
    const float ctx[1] = {(float)n};
    clvr_status s = fx_grid_mesh(n, kind, 0.25f, 1.0f, 0.0f, 5, &m, err);
    if (s != CLVR_OK) return s;
    return filter_mesh(&m, keep_holed, ctx, out, err);
}

/* ... of mixed cubes. */
static clvr_status holed_mesh(uint32_t n, clvr_mesh *out, clvr_error *err)
{
    return holed_mesh_of(n, FX_MIXED, out, err);
}

/* ------------------------------------------------------------ 3b. gaps */

/* clvr_hull_gaps on the device against brute force over every face: random
 * rays from outside and inside the box through the holed lattice (a ray
 * through the ball leaves the medium and comes back) and through a sieve
 * of slabs (a ray along x crosses more faces than CLVR_HULL_MAX_HITS). */
static void test_gaps(clvr_cl *cl)
{
    for (int which = 0; which < 2; ++which) {
        const uint32_t N = which == 0 ? 8u : 36u;
        clvr_error err = {0};
        fx_mesh x = {0};
        if (which == 0) {
            TU_CHECK_STATUS(holed_mesh(N, &x.m, &err), CLVR_OK, &err);
        } else {
            clvr_mesh m = {0};
            TU_CHECK_STATUS(fx_grid_mesh(N, FX_HEXES, 0.0f, 1.0f, 0.0f, 7, &m, &err), CLVR_OK, &err);
            if (err.status == CLVR_OK) TU_CHECK_STATUS(filter_mesh(&m, keep_sieve, NULL, &x.m, &err), CLVR_OK, &err);
        }
        if (err.status == CLVR_OK) TU_CHECK_STATUS(fx_prepare(cl, &x, &err), CLVR_OK, &err);
        clvr_hull_face *df = NULL;
        clvr_bvh_node *dn = NULL;
        if (err.status != CLVR_OK || !read_hull(cl, &x.a.hull, &df, &dn) || x.a.hull.num_faces == 0) {
            TU_CHECK(0);
            free(df);
            free(dn);
            fx_free(cl, &x);
            continue;
        }
        enum { NR = 1500 };
        const float L = (float)N;
        float *org = calloc(4 * NR, sizeof(float)), *dir = calloc(4 * NR, sizeof(float));
        float *res = calloc((size_t)NR * CLVR_HULL_GAP_STRIDE, sizeof(float)), *clip = calloc(4 * NR, sizeof(float));
        float *hlo = malloc(x.a.hull.num_faces * sizeof(float)), *hhi = malloc(x.a.hull.num_faces * sizeof(float));
        uint64_t rs = 71 + (uint64_t)which;
        for (uint32_t i = 0; i < NR; ++i) {
            float o[3], t[3];
            const int inside = i % 4 == 3;
            for (int c = 0; c < 3; ++c) t[c] = L * (-0.1f + 1.2f * tu_randf(&rs));
            if (which == 1 && i % 3 == 0) t[1] = t[2] = 0.5f * L; /* along x, nearly */
            if (inside) {
                for (int c = 0; c < 3; ++c) o[c] = L * (0.05f + 0.9f * tu_randf(&rs));
            } else {
                sphere_point(&rs, 0.5f * L, 2.5f * L, o);
                if (which == 1 && i % 3 == 0) {
                    o[0] = -2.0f * L;
                    o[1] = 0.5f * L + 0.3f * L * (tu_randf(&rs) - 0.5f);
                    o[2] = 0.5f * L + 0.3f * L * (tu_randf(&rs) - 0.5f);
                }
            }
            for (int c = 0; c < 3; ++c) {
                org[4 * i + c] = o[c];
                dir[4 * i + c] = t[c] - o[c];
            }
        }
        TU_CHECK_STATUS(clvr_hull_gap_rays(cl, &x.a.kernels, &x.a.hull, org, dir, NR, res, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(clvr_hull_rays(cl, &x.a.kernels, &x.a.hull, org, dir, NR, clip, &err), CLVR_OK, &err);
        uint32_t with_gaps = 0, gaps = 0, overflow = 0, bad_clip = 0, crossed = 0, missed = 0, bad_overflow = 0;
        uint32_t in_ball = 0; /* holed lattice: gaps through the removed ball, which the renderer must skip */
        for (uint32_t i = 0; i < NR && err.status == CLVR_OK; ++i) {
            const float *o = org + 4 * i, *d = dir + 4 * i, *r = res + (size_t)i * CLVR_HULL_GAP_STRIDE;
            const int inside = i % 4 == 3; /* the origin inside the box, as made above */
            const clvr_hull_ray ray = clvr_hull_ray_make(o[0], o[1], o[2], d[0], d[1], d[2]);
            uint32_t nh = 0, all = 0;
            for (uint32_t f = 0; f < x.a.hull.num_faces; ++f) {
                float a = INFINITY, b = -INFINITY;
                clvr_hull_ray_face(&ray, &df[f], &a, &b);
                if (!(a <= b)) continue;
                ++all;
                if (b < 0.0f) continue; /* behind the origin */
                hlo[nh] = a;
                hhi[nh++] = b;
            }
            const int ng = (int)r[2];
            if (ng == -2) { /* too many crossings: the caller takes clvr_hull_clip */
                ++overflow;
                if (all <= CLVR_HULL_MAX_HITS) ++bad_overflow;
                continue;
            }
            const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            const float tol = 2e-4f * (3.0f * L / len);
            /* The cut is clvr_hull_clip's (the same interval, or a miss). */
            int off = (ng >= 0) != (clip[4 * i + 2] != 0.0f);
            for (int e = 0; e < 2 && !off && ng >= 0; ++e)
                off = !(r[e] == clip[4 * i + e] || fabsf(r[e] - clip[4 * i + e]) <= tol); /* == : both infinite */
            if (off && getenv("HULL_DEBUG"))
                fprintf(stderr, "gap ray %u (%s): gaps %d [%g, %g], clip %g [%g, %g]\n", i, inside ? "inside" : "outside",
                        ng, r[0], r[1], clip[4 * i + 2], clip[4 * i], clip[4 * i + 1]);
            bad_clip += (uint32_t)off;
            if (ng <= 0) continue;
            ++with_gaps;
            gaps += (uint32_t)ng;
            for (int g = 0; g < ng; ++g) {
                const float a = r[4 + 2 * g], b = r[5 + 2 * g];
                float mid2 = 0.0f;
                for (int c = 0; c < 3; ++c) {
                    const float q = o[c] + 0.5f * (a + b) * d[c] - 0.5f * L;
                    mid2 += q * q;
                }
                in_ball += which == 0 && mid2 < (0.25f * L - 1.0f) * (0.25f * L - 1.0f);
                /* No face is crossed inside a gap (what keeps the image
                 * unbiased), and a crossing lies within tol of each end. */
                int near_a = 0, near_b = 0;
                for (uint32_t h = 0; h < nh; ++h) {
                    if (hhi[h] >= a && hlo[h] <= b) ++crossed;
                    near_a |= fabsf(hhi[h] - a) <= tol;
                    near_b |= fabsf(hlo[h] - b) <= tol;
                }
                /* Only a ray from inside the box may start in a gap (its
                 * origin outside the mesh): the first gap then begins at the
                 * ray's start, before the first crossing. */
                const int from_inside = inside && g == 0 && fabsf(a - r[0]) <= tol;
                missed += !(near_a || from_inside) || !near_b;
                if (!(a < b) || (g > 0 && !(a > r[3 + 2 * g]))) ++missed; /* empty, or out of order */
            }
        }
        printf("gaps, %s: %u of %u rays with gaps (%u gaps), %u past %d crossings; %u cuts off clvr_hull_clip, %u "
               "crossings inside a gap, %u gap ends off a crossing, %u overflows without cause, %u gaps through the "
               "ball\n",
               which == 0 ? "holed lattice" : "sieve", with_gaps, NR, gaps, overflow, CLVR_HULL_MAX_HITS, bad_clip,
               crossed, missed, bad_overflow, in_ball);
        TU_CHECK(with_gaps > NR / 20); /* gaps occur: the test can fail */
        if (which == 0) TU_CHECK(in_ball > NR / 50); /* and some lie outside the mesh (test_renders' image) */
        if (which == 1) TU_CHECK(overflow > 0);
        TU_CHECK_EQ_U64(bad_clip, 0);
        TU_CHECK_EQ_U64(crossed, 0);
        TU_CHECK_EQ_U64(missed, 0);
        TU_CHECK_EQ_U64(bad_overflow, 0);
        free(org);
        free(dir);
        free(res);
        free(clip);
        free(hlo);
        free(hhi);
        free(df);
        free(dn);
        fx_free(cl, &x);
    }
}

/* Per pixel and channel mean and variance of `frames` independent frames;
 * eye NULL: the automatic camera on the mesh's bounds. */
static clvr_status moments(clvr_cl *cl, fx_mesh *x, const clvr_render_settings *set, const float *eye,
                           const float *target, float density, uint32_t frames, float **mean, float **var,
                           clvr_error *err)
{
    return fx_render_moments_at(cl, &x->m, &x->c, &x->a, set, eye, target, density, frames, mean, var, err);
}

/* Renders x with the hull and without (urm and delta, shadows on; walk
 * without shadows, where it crosses the tets: with the hull it re-enters
 * past the stretches outside the mesh, without it hands the ray to urm at
 * the first boundary; auto on a mesh of tets and other cells, shadows on,
 * whose tet walk hands the ray to urm at its first other cell, with the
 * hull's gaps past that point where it has them) and compares them per
 * pixel and per 4x4 block. */
static void renders_agree(clvr_cl *cl, fx_mesh *x, const char *name, const float *eye, const float *target,
                          float density)
{
    enum { W = 32, H = 32, FRAMES = 96 };
    static const uint32_t est[4] = {CLVR_ESTIMATOR_URM, CLVR_ESTIMATOR_DELTA, CLVR_ESTIMATOR_WALK,
                                    CLVR_ESTIMATOR_AUTO};
    /* auto only where it differs from the rows above: a mesh of tets and
     * other cells (elsewhere it is the walk, or the pilot's pick of urm or
     * the walk, both checked already). */
    const int mixed = x->m.num_cells[CLVR_CELL_TET] > 0 &&
                      x->m.num_cells[CLVR_CELL_PYRAMID] + x->m.num_cells[CLVR_CELL_WEDGE] + x->m.num_cells[CLVR_CELL_HEX] > 0;
    for (int ei = 0; ei < 3 + mixed; ++ei) {
        clvr_error err = {0};
        float *m[2] = {0}, *v[2] = {0};
        for (int hull = 0; hull < 2; ++hull) {
            clvr_render_settings set;
            clvr_render_settings_default(&set);
            set.width = W;
            set.height = H;
            set.estimator = est[ei];
            set.shadows = est[ei] != CLVR_ESTIMATOR_WALK;
            set.hull = hull;
            set.seed = 1000 + (uint64_t)hull; /* independent images */
            set.sampler = CLVR_SAMPLER_INDEPENDENT;
            TU_CHECK_STATUS(moments(cl, x, &set, eye, target, density, FRAMES, &m[hull], &v[hull], &err), CLVR_OK, &err);
        }
        /* The image with the hull first: its opacity is the one checked. */
        const fx_moments_diff r = fx_compare_moments(m[1], v[1], m[0], v[0], W, H, FRAMES, K_SIGMA);
        printf("%s, %s: hull against none: %zu pixels and %zu blocks beyond %.0f sigma, largest block |z| %.2f, "
               "mean opacity %.3f\n",
               name, clvr_render_estimator_name(est[ei]), r.pixels, r.blocks, K_SIGMA, r.worst_block_z,
               r.opacity / (W * H));
        TU_CHECK(r.opacity > 0.05 * W * H); /* the medium covers part of the image: the test can fail */
        TU_CHECK_EQ_U64(r.pixels, 0);
        TU_CHECK_EQ_U64(r.blocks, 0);
        TU_CHECK_EQ_U64(r.channels, 0);
        for (int hull = 0; hull < 2; ++hull) {
            free(m[hull]);
            free(v[hull]);
        }
    }
}

static void test_renders(clvr_cl *cl)
{
    clvr_error err = {0};
    fx_mesh x = {0};
    TU_CHECK_STATUS(holed_mesh(12, &x.m, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(fx_prepare(cl, &x, &err), CLVR_OK, &err);
    if (err.status == CLVR_OK) {
        printf("holed lattice: %llu elements, %u boundary faces, empty fraction %.3f\n",
               (unsigned long long)x.c.num_elements, x.a.hull.num_faces, (double)x.a.hull.empty_fraction);
        renders_agree(cl, &x, "holed lattice", NULL, NULL, 2.0f);
        /* From inside the box, in the removed octant, looking through the
         * hole: the start is not cut, the end is. */
        const float eye[3] = {11.0f, 11.5f, 11.0f}, target[3] = {4.0f, 5.0f, 3.0f};
        renders_agree(cl, &x, "holed lattice, camera inside the box", eye, target, 2.0f);
    }
    fx_free(cl, &x);
    {
        /* All tets: the walk crosses the whole lattice, leaves it at the
         * ball and re-enters past it (with the hull) or hands the ray to urm
         * there (without). */
        fx_mesh t = {0};
        TU_CHECK_STATUS(holed_mesh_of(10, FX_TETS, &t.m, &err), CLVR_OK, &err);
        TU_CHECK_STATUS(fx_prepare(cl, &t, &err), CLVR_OK, &err);
        if (err.status == CLVR_OK) {
            renders_agree(cl, &t, "holed tet lattice", NULL, NULL, 2.0f);
            const float eye[3] = {9.2f, 9.6f, 9.2f}, target[3] = {3.3f, 4.2f, 2.5f};
            renders_agree(cl, &t, "holed tet lattice, camera inside the box", eye, target, 2.0f);
        }
        fx_free(cl, &t);
    }
    static const char *files[] = {"vtk/post.vtk", "vtk/notch_stress.vtk"};
    static const float density[] = {2.0f, 100.0f}; /* the notch is thin at 2 */
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s", tu_data_dir(), files[i]);
        fx_mesh y = {0};
        TU_CHECK_STATUS(clvr_mesh_load(path, NULL, &y.m, &err), CLVR_OK, &err);
        if (err.status == CLVR_OK) TU_CHECK_STATUS(fx_prepare(cl, &y, &err), CLVR_OK, &err);
        if (err.status == CLVR_OK) {
            printf("%s: %llu elements, %u boundary faces, empty fraction %.3f\n", files[i],
                   (unsigned long long)y.c.num_elements, y.a.hull.num_faces, (double)y.a.hull.empty_fraction);
            renders_agree(cl, &y, files[i], NULL, NULL, density[i]);
        }
        fx_free(cl, &y);
    }
}

/* ------------------------------------------------------------ 5. automatic
 * CLVR_HULL_AUTO builds nothing for a mesh that fills its box (a lattice)
 * and keeps the hull of one that does not (post; the holed lattice's
 * clusters of one cell type span several cells and hide its hole); its
 * first probe, through the sampling clusters' boxes, never finds more
 * empty space than the hull's (the boxes contain the mesh): a probe that
 * did would drop hulls that save time. */
static void test_auto(clvr_cl *cl)
{
    clvr_error err = {0};
    for (int which = 0; which < 3; ++which) {
        fx_mesh x = {0};
        const char *name = which == 0 ? "lattice" : which == 1 ? "holed lattice" : "vtk/post.vtk";
        clvr_status s;
        if (which == 0) s = fx_grid_mesh(12, FX_MIXED, 0.25f, 1.0f, 0.0f, 5, &x.m, &err);
        else if (which == 1) s = holed_mesh(12, &x.m, &err);
        else {
            char path[512];
            snprintf(path, sizeof path, "%s/%s", tu_data_dir(), name);
            s = clvr_mesh_load(path, NULL, &x.m, &err);
        }
        TU_CHECK_STATUS(s, CLVR_OK, &err);
        float on_fraction = -1.0f;
        if (s == CLVR_OK) s = fx_prepare(cl, &x, &err);
        if (s == CLVR_OK) {
            on_fraction = x.a.hull.empty_fraction;
            TU_CHECK(x.a.hull.kept && x.a.hull.num_faces > 0 && x.a.hull.box_fraction == -1.0f);
            clvr_accel_release(cl, &x.a);
            s = clvr_accel_build_hull(cl, &x.c, CLVR_HULL_AUTO, &x.a, &err);
        }
        TU_CHECK_STATUS(s, CLVR_OK, &err);
        if (s == CLVR_OK) {
            const clvr_hull *h = &x.a.hull;
            printf("auto, %s: box probe %.3f, hull probe %.3f, %s\n", name, (double)h->box_fraction,
                   (double)on_fraction, h->kept ? "kept" : h->boxes_only ? "not built" : "dropped");
            TU_CHECK(h->box_fraction >= 0.0f && h->box_fraction <= on_fraction + 1e-6f);
            /* Each outcome as its probes say. */
            if (h->boxes_only) {
                TU_CHECK(h->box_fraction < CLVR_HULL_MIN_BOX_EMPTY);
                TU_CHECK(!h->kept && !h->faces && !h->nodes && h->num_faces == 0 && clvr_hull_bytes(h) == 0);
            } else {
                TU_CHECK(h->box_fraction >= CLVR_HULL_MIN_BOX_EMPTY && h->empty_fraction == on_fraction);
                TU_CHECK(h->kept == (on_fraction >= CLVR_HULL_MIN_EMPTY));
            }
            if (h->kept) TU_CHECK(h->faces && h->nodes && h->num_faces > 0 &&
                                  clvr_hull_bytes(h) >= (uint64_t)h->num_faces * sizeof(clvr_hull_face));
            /* The lattice fills its box: nothing is built; post does not. */
            if (which == 0) TU_CHECK(on_fraction < CLVR_HULL_MIN_EMPTY && h->boxes_only);
            if (which == 2) TU_CHECK(on_fraction >= CLVR_HULL_MIN_EMPTY && h->kept);
        }
        fx_free(cl, &x);
    }
    /* Too little free memory for the build's transient buffers (the
     * device's memory lowered to what is in use plus a little): the
     * automatic mode renders without a hull and says why; the forced one
     * fails with the numbers. */
    {
        fx_mesh z = {0};
        char path[512];
        snprintf(path, sizeof path, "%s/vtk/post.vtk", tu_data_dir());
        TU_CHECK_STATUS(clvr_mesh_load(path, NULL, &z.m, &err), CLVR_OK, &err);
        if (err.status == CLVR_OK) TU_CHECK_STATUS(fx_hull_cluster(cl, &z, &err), CLVR_OK, &err);
        if (err.status == CLVR_OK) {
            const cl_ulong saved = cl->global_mem_bytes;
            cl->global_mem_bytes = cl->allocated_bytes + (1u << 20); /* the trees (a few 100 kB) fit, the build not */
            TU_CHECK_STATUS(clvr_accel_build_hull(cl, &z.c, CLVR_HULL_AUTO, &z.a, &err), CLVR_OK, &err);
            printf("auto, post.vtk, 1 MB free: %s\n", z.a.hull_skipped);
            TU_CHECK(!z.a.hull.kept && !z.a.hull.faces && strstr(z.a.hull_skipped, "face slots"));
            clvr_accel_release(cl, &z.a);
            TU_CHECK_STATUS(clvr_accel_build_hull(cl, &z.c, CLVR_HULL_ON, &z.a, &err), CLVR_ERR_DEVICE_MEMORY, &err);
            TU_CHECK(strstr(err.msg, "free") != NULL);
            err = (clvr_error){0};
            clvr_accel_release(cl, &z.a);
            cl->global_mem_bytes = saved;
        }
        fx_free(cl, &z);
    }
    /* Off: nothing at all. */
    fx_mesh y = {0};
    TU_CHECK_STATUS(holed_mesh(6, &y.m, &err), CLVR_OK, &err);
    if (err.status == CLVR_OK) {
        TU_CHECK_STATUS(fx_hull_cluster(cl, &y, &err), CLVR_OK, &err);
        if (err.status == CLVR_OK) {
            TU_CHECK_STATUS(clvr_accel_build_hull(cl, &y.c, CLVR_HULL_OFF, &y.a, &err), CLVR_OK, &err);
            TU_CHECK(!y.a.hull.kept && !y.a.hull.faces && y.a.hull.num_faces == 0);
        }
    }
    fx_free(cl, &y);
}

int main(void)
{
    test_tables();
    clvr_cl cl;
    tu_open_device(&cl);
    test_faces(&cl);
    test_collisions(&cl);
    test_rays(&cl);
    test_gaps(&cl);
    test_renders(&cl);
    test_auto(&cl);
    clvr_cl_destroy(&cl);
    return tu_finish("test_hull");
}
