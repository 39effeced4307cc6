/* hull.h: the mesh's boundary faces (its hull) and the ray query over them,
 * compiled for the host (reference, tests) and for kernels: the same code
 * on both sides.
 *
 * Why: a camera ray that enters the medium inside the bounding box (a mesh
 * that fills a third of its box, a body with holes) meets a jump from
 * nothing to medium that the macrocell grid cannot place, and the urm
 * quadrature converges only as 1/N across a jump. Knowing where the ray
 * first and last crosses the mesh's boundary, the estimators integrate
 * exactly the interval that can hold medium. Outside it the extinction is
 * zero by definition, so cutting it off changes nothing in expectation.
 *
 * A face of an element is a boundary face when no other element has the
 * same face (the same corner positions, bit for bit: the clustered mesh
 * keeps a copy of a vertex per instance, so positions, not indices,
 * identify a face across instances) on the other side of it. Faces that
 * only look like boundary faces (a non-conforming mesh's big face against
 * four small ones, two elements that do not share vertices, duplicate
 * elements) lie inside the mesh, between the true first and last
 * crossings: the first crossing of all faces is still the true entry and
 * the last the true exit. Extra faces
 * cost traversal time, never correctness.
 *
 * Quad faces (pyramid base, wedge sides, hexahedra) are bilinear patches,
 * not planar: each is stored as its four corners and tested as the
 * tetrahedron they span (its four triangles), which contains the patch, so
 * the first hit of the tetrahedron is never after the ray's crossing of the
 * patch, and its last never before. Triangles use the watertight test of
 * Woop, Benthin and Wald (JCGT 2013): a ray through an edge or a vertex
 * shared by faces hits at least one of them, so no ray slips through. */
#ifndef CLVR_HULL_H
#define CLVR_HULL_H

#include "clvr_shared.h"
#include "locate.h"

#ifndef __OPENCL_VERSION__
#include <math.h>
#include <string.h>
#endif

/* Faces per element of the type. */
CLVR_INLINE clvr_u32 clvr_hull_face_count(clvr_u32 type)
{
    return type == CLVR_CELL_TET ? 4u : type == CLVR_CELL_HEX ? 6u : 5u;
}

/* Vertex slots of face f of an element of the type (VTK vertex order),
 * 4 bits each from the lowest: s0 | s1 << 4 | s2 << 8 | s3 << 12, s3 = 0xF
 * for a triangle. */
CLVR_INLINE clvr_u32 clvr_hull_face_code(clvr_u32 type, clvr_u32 f)
{
    if (type == CLVR_CELL_TET) return f == 0u ? 0xF310u : f == 1u ? 0xF321u : f == 2u ? 0xF302u : 0xF120u;
    if (type == CLVR_CELL_PYRAMID)
        return f == 0u ? 0x1230u : f == 1u ? 0xF410u : f == 2u ? 0xF421u : f == 3u ? 0xF432u : 0xF403u;
    if (type == CLVR_CELL_WEDGE)
        return f == 0u ? 0xF210u : f == 1u ? 0xF453u : f == 2u ? 0x1430u : f == 3u ? 0x2541u : 0x0352u;
    return f == 0u ? 0x1230u : f == 1u ? 0x7654u : f == 2u ? 0x4510u : f == 3u ? 0x5621u : f == 4u ? 0x6732u : 0x7403u;
}

CLVR_INLINE clvr_u32 clvr_hull_bits(float x)
{
#ifdef __OPENCL_VERSION__
    return as_uint(x);
#else
    clvr_u32 u;
    memcpy(&u, &x, sizeof u);
    return u;
#endif
}

/* p before q in the canonical order of a face's corners (x, y, z bit
 * patterns, lexicographic). */
CLVR_INLINE int clvr_hull_before(const float *p, const float *q)
{
    for (int k = 0; k < 3; ++k) {
        const clvr_u32 a = clvr_hull_bits(p[k]), b = clvr_hull_bits(q[k]);
        if (a != b) return a < b;
    }
    return 0;
}

/* Face f of element e (global sorted id, of instance inst) with its corners
 * in canonical order: out->p[k][0..2], k < corners; a triangle repeats its
 * last corner in slot 3; p[0][3] = the corner count, p[1][3] = the side of
 * the face the element lies on (+1, -1; 0: degenerate), the other w 0.
 * Returns the corner count. The element is taken as the cell it is
 * (clvr_load_cell_in): a collapsed hex has its own type's faces in its
 * first slots, and its slots past them hold no face (0 corners, all zero:
 * never a boundary face, never anyone's twin). */
CLVR_INLINE clvr_u32 clvr_hull_face_load(const clvr_mesh_view *m, const clvr_instance *inst, clvr_u32 e, clvr_u32 f,
                                         clvr_hull_face *out)
{
    clvr_vec4 v[CLVR_CELL_MAX_VERTS];
    const clvr_piece_arrays pa = clvr_view_piece(m, inst);
    const clvr_u32 type = clvr_load_cell_in(&pa, inst, e, v);
    if (f >= clvr_hull_face_count(type)) {
        for (int k = 0; k < 4; ++k) out->p[k][0] = out->p[k][1] = out->p[k][2] = out->p[k][3] = 0.0f;
        return 0u;
    }
    const clvr_u32 code = clvr_hull_face_code(type, f);
    const clvr_u32 n = (code >> 12) == 0xFu ? 3u : 4u;
    /* Newell's normal of the face in the element's own (cyclic) order, and
     * the face's centre. */
    float N[3] = {0.0f, 0.0f, 0.0f}, F[3] = {0.0f, 0.0f, 0.0f};
    for (clvr_u32 k = 0; k < n; ++k) {
        const clvr_vec4 a = v[(code >> (4u * k)) & 0xFu], b = v[(code >> (4u * ((k + 1u) % n))) & 0xFu];
        N[0] += (a.y - b.y) * (a.z + b.z);
        N[1] += (a.z - b.z) * (a.x + b.x);
        N[2] += (a.x - b.x) * (a.y + b.y);
        F[0] += a.x;
        F[1] += a.y;
        F[2] += a.z;
    }
    for (clvr_u32 k = 0; k < 4u; ++k) {
        const clvr_vec4 q = v[k < n ? (code >> (4u * k)) & 0xFu : code >> 8 & 0xFu];
        out->p[k][0] = q.x;
        out->p[k][1] = q.y;
        out->p[k][2] = q.z;
        out->p[k][3] = 0.0f;
    }
    /* Insertion sort of the n corners. */
    for (clvr_u32 i = 1; i < n; ++i)
        for (clvr_u32 j = i; j > 0u && clvr_hull_before(out->p[j], out->p[j - 1u]); --j)
            for (int k = 0; k < 3; ++k) {
                const float t = out->p[j][k];
                out->p[j][k] = out->p[j - 1u][k];
                out->p[j - 1u][k] = t;
            }
    for (int k = 0; k < 3; ++k) out->p[3][k] = out->p[n - 1u][k];
    out->p[0][3] = (float)n;
    /* The side the element lies on: the sign of its centre against the
     * face's plane (Newell's normal through the face's centre, which fits a
     * warped quad), the normal turned to agree with that of the first three
     * canonical corners so that every element with this face uses the same
     * one; 0 when that is degenerate. */
    const float ax = out->p[1][0] - out->p[0][0], ay = out->p[1][1] - out->p[0][1], az = out->p[1][2] - out->p[0][2];
    const float bx = out->p[2][0] - out->p[0][0], by = out->p[2][1] - out->p[0][1], bz = out->p[2][2] - out->p[0][2];
    const float cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
    const float agree = N[0] * cx + N[1] * cy + N[2] * cz;
    float E[3] = {0.0f, 0.0f, 0.0f};
    const clvr_u32 nv = clvr_cell_vertex_count(type);
    for (clvr_u32 k = 0; k < nv; ++k) {
        E[0] += v[k].x;
        E[1] += v[k].y;
        E[2] += v[k].z;
    }
    const float inv_nv = 1.0f / (float)nv, inv_n = 1.0f / (float)n;
    const float d = N[0] * (E[0] * inv_nv - F[0] * inv_n) + N[1] * (E[1] * inv_nv - F[1] * inv_n) +
                    N[2] * (E[2] * inv_nv - F[2] * inv_n);
    const float side = agree > 0.0f ? d : agree < 0.0f ? -d : 0.0f;
    out->p[1][3] = side > 0.0f ? 1.0f : side < 0.0f ? -1.0f : 0.0f;
    return n;
}

/* The key of a slot that holds no face (clvr_hull_face_load): the largest,
 * so such slots sort last. A real face may share it (then the run of equal
 * keys is searched, which never pairs a face with no face). */
#define CLVR_HULL_NO_FACE_KEY 0xffffffffull

/* 32-bit hash of a canonical face's corners (the same face from either
 * side, the same key), in the low half of a 64-bit key: the sort then runs
 * over 4 digits instead of 8 (the hull's build on post-tets: sort 0.076 ->
 * 0.03-0.05 s of 0.18-0.23). Different faces that share a key (a few hundred pairs among millions
 * of faces) only lengthen a run of equal keys: clvr_hull_boundary compares
 * corners exactly. */
CLVR_INLINE clvr_u64 clvr_hull_face_key(const clvr_hull_face *h)
{
    if (h->p[0][3] == 0.0f) return CLVR_HULL_NO_FACE_KEY;
    clvr_u64 x = 0x9E3779B97F4A7C15ull ^ clvr_hull_bits(h->p[0][3]);
    for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c) {
            x ^= clvr_hull_bits(h->p[k][c]);
            x *= 0xff51afd7ed558ccdull;
            x ^= x >> 32;
        }
    x *= 0xc4ceb9fe1a85ec53ull;
    return (x ^ (x >> 29)) >> 32;
}

/* a and b are the same face seen from opposite sides: two elements meet
 * there, one on each side, so it is inside the mesh. */
CLVR_INLINE int clvr_hull_opposite(const clvr_hull_face *a, const clvr_hull_face *b)
{
    if (a->p[0][3] != b->p[0][3] || !(a->p[1][3] * b->p[1][3] < 0.0f)) return 0;
    for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c)
            if (clvr_hull_bits(a->p[k][c]) != clvr_hull_bits(b->p[k][c])) return 0;
    return 1;
}

/* Element and face of face slot `slot`: face_first[i] (num_instances + 1
 * entries) is the first slot of instance i, whose elements own
 * clvr_hull_face_count(type) consecutive slots each. */
CLVR_INLINE void clvr_hull_slot_face(CLVR_GLOBAL const clvr_instance *instances, CLVR_GLOBAL const clvr_u32 *face_first,
                                     clvr_u32 num_instances, clvr_u32 slot, clvr_u32 *inst, clvr_u32 *e, clvr_u32 *f)
{
    clvr_u32 lo = 0, hi = num_instances; /* last i with face_first[i] <= slot */
    while (hi - lo > 1u) {
        const clvr_u32 mid = (lo + hi) / 2u;
        if (face_first[mid] <= slot) lo = mid;
        else hi = mid;
    }
    const clvr_u32 nf = clvr_hull_face_count(instances[lo].type), r = slot - face_first[lo];
    *inst = lo;
    *e = instances[lo].first_element + r / nf;
    *f = r % nf;
}

/* Faces with the same key as the one at sorted position i searched on each
 * side; a longer run (thousands of elements sharing one face: degenerate
 * input) leaves the face a boundary face, which is always safe. */
#define CLVR_HULL_RUN 32u

/* The face in slot `slot` (canonical corners). */
CLVR_INLINE void clvr_hull_slot_load(const clvr_mesh_view *m, CLVR_GLOBAL const clvr_instance *instances,
                                     CLVR_GLOBAL const clvr_u32 *face_first, clvr_u32 num_instances, clvr_u32 slot,
                                     clvr_hull_face *h)
{
    clvr_u32 i, e, f;
    clvr_hull_slot_face(instances, face_first, num_instances, slot, &i, &e, &f);
    const clvr_instance inst = instances[i];
    clvr_hull_face_load(m, &inst, e, f, h);
}

/* clvr_hull_twin of the face at sorted position i, already loaded in *h
 * (clvr_hull_slot_load of slots[i]). */
CLVR_INLINE clvr_u32 clvr_hull_twin_of(const clvr_mesh_view *m, CLVR_GLOBAL const clvr_instance *instances,
                                       CLVR_GLOBAL const clvr_u32 *face_first, clvr_u32 num_instances,
                                       clvr_u32 num_slots, CLVR_GLOBAL const clvr_u64 *keys,
                                       CLVR_GLOBAL const clvr_u32 *slots, clvr_u32 i, const clvr_hull_face *h)
{
    const clvr_u64 key = keys[i];
    clvr_hull_face o;
    clvr_u32 ii, e, f;
    if (h->p[0][3] == 0.0f) return CLVR_BVH_NOT_FOUND; /* a slot with no face */
    clvr_u32 j = i;
    for (; j > 0u && i - j < CLVR_HULL_RUN && keys[j - 1u] == key; --j) {
        clvr_hull_slot_load(m, instances, face_first, num_instances, slots[j - 1u], &o);
        if (clvr_hull_opposite(h, &o)) {
            clvr_hull_slot_face(instances, face_first, num_instances, slots[j - 1u], &ii, &e, &f);
            return e;
        }
    }
    for (j = i + 1u; j < num_slots && j - i <= CLVR_HULL_RUN && keys[j] == key; ++j) {
        clvr_hull_slot_load(m, instances, face_first, num_instances, slots[j], &o);
        if (clvr_hull_opposite(h, &o)) {
            clvr_hull_slot_face(instances, face_first, num_instances, slots[j], &ii, &e, &f);
            return e;
        }
    }
    return CLVR_BVH_NOT_FOUND;
}

/* The sorted element id of the element on the other side of the face at
 * sorted position i (clvr_hull_opposite), or CLVR_BVH_NOT_FOUND: a boundary
 * face, a slot with no face, or a run of equal keys too long to search
 * (always safe: the walk that reads this falls back to a lookup). */
CLVR_INLINE clvr_u32 clvr_hull_twin(const clvr_mesh_view *m, CLVR_GLOBAL const clvr_instance *instances,
                                    CLVR_GLOBAL const clvr_u32 *face_first, clvr_u32 num_instances, clvr_u32 num_slots,
                                    CLVR_GLOBAL const clvr_u64 *keys, CLVR_GLOBAL const clvr_u32 *slots, clvr_u32 i)
{
    clvr_hull_face h;
    clvr_hull_slot_load(m, instances, face_first, num_instances, slots[i], &h);
    return clvr_hull_twin_of(m, instances, face_first, num_instances, num_slots, keys, slots, i, &h);
}

/* 1 when the face at sorted position i (keys, slots: (key, slot) pairs
 * sorted by key) is a boundary face: no face with its key is the same face
 * seen from the other side. Duplicate elements (the same face from the same
 * side) do not make a face inside; a run too long to search keeps the face
 * too: a face kept needlessly costs time only, a face dropped wrongly would
 * cut medium off. */
CLVR_INLINE clvr_u32 clvr_hull_boundary(const clvr_mesh_view *m, CLVR_GLOBAL const clvr_instance *instances,
                                        CLVR_GLOBAL const clvr_u32 *face_first, clvr_u32 num_instances,
                                        clvr_u32 num_slots, CLVR_GLOBAL const clvr_u64 *keys,
                                        CLVR_GLOBAL const clvr_u32 *slots, clvr_u32 i)
{
    clvr_hull_face h;
    clvr_hull_slot_load(m, instances, face_first, num_instances, slots[i], &h);
    if (h.p[0][3] == 0.0f) return 0u; /* a slot with no face */
    return clvr_hull_twin_of(m, instances, face_first, num_instances, num_slots, keys, slots, i, &h) ==
           CLVR_BVH_NOT_FOUND;
}

/* The face in slot `slot` and its box (8 floats: lo xyz 0, hi xyz 0). */
CLVR_INLINE void clvr_hull_face_at(const clvr_mesh_view *m, CLVR_GLOBAL const clvr_instance *instances,
                                   CLVR_GLOBAL const clvr_u32 *face_first, clvr_u32 num_instances, clvr_u32 slot,
                                   clvr_hull_face *h, CLVR_GLOBAL float *box)
{
    clvr_hull_slot_load(m, instances, face_first, num_instances, slot, h);
    for (int c = 0; c < 3; ++c) {
        float lo = h->p[0][c], hi = h->p[0][c];
        for (int k = 1; k < 4; ++k) {
            lo = fmin(lo, h->p[k][c]);
            hi = fmax(hi, h->p[k][c]);
        }
        box[c] = lo;
        box[4 + c] = hi;
    }
    box[3] = 0.0f;
    box[7] = 0.0f;
}

/* ------------------------------------------------------------ ray query */

/* Watertight ray-triangle test (Woop, Benthin, Wald 2013) in coordinates
 * relative to the ray origin, with the ray's shear (kx, ky, kz, sx, sy, sz)
 * precomputed: a hit at t widens [*lo, *hi] to include t. The edge
 * functions are differences of products written so that the two faces of a
 * shared edge compute exact negations of each other (no contraction into
 * fma, FP_CONTRACT off): that is what makes the test watertight. An edge
 * function that is exactly zero counts as inside, so an edge or vertex hit
 * is a hit of every face there. */
typedef struct clvr_hull_ray {
    float o[3];
    int kx, ky, kz;
    float sx, sy, sz;
} clvr_hull_ray;

CLVR_INLINE clvr_hull_ray clvr_hull_ray_make(float ox, float oy, float oz, float dx, float dy, float dz)
{
    clvr_hull_ray r;
    const float d[3] = {dx, dy, dz};
    r.o[0] = ox;
    r.o[1] = oy;
    r.o[2] = oz;
    r.kz = fabs(dx) >= fabs(dy) ? (fabs(dx) >= fabs(dz) ? 0 : 2) : (fabs(dy) >= fabs(dz) ? 1 : 2);
    r.kx = r.kz == 2 ? 0 : r.kz + 1;
    r.ky = r.kx == 2 ? 0 : r.kx + 1;
    if (d[r.kz] < 0.0f) {
        const int t = r.kx;
        r.kx = r.ky;
        r.ky = t;
    }
    r.sx = d[r.kx] / d[r.kz];
    r.sy = d[r.ky] / d[r.kz];
    r.sz = 1.0f / d[r.kz];
    return r;
}

CLVR_INLINE float clvr_hull_diff_of_products(float a, float b, float c, float d)
{
#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#endif
    const float ab = a * b, cd = c * d;
    return ab - cd;
}

CLVR_INLINE void clvr_hull_ray_tri(const clvr_hull_ray *r, CLVR_GLOBAL const float *a, CLVR_GLOBAL const float *b,
                                   CLVR_GLOBAL const float *c, float *lo, float *hi)
{
#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#endif
    const float az_ = a[r->kz] - r->o[r->kz], bz_ = b[r->kz] - r->o[r->kz], cz_ = c[r->kz] - r->o[r->kz];
    const float ax = (a[r->kx] - r->o[r->kx]) - r->sx * az_, ay = (a[r->ky] - r->o[r->ky]) - r->sy * az_;
    const float bx = (b[r->kx] - r->o[r->kx]) - r->sx * bz_, by = (b[r->ky] - r->o[r->ky]) - r->sy * bz_;
    const float cx = (c[r->kx] - r->o[r->kx]) - r->sx * cz_, cy = (c[r->ky] - r->o[r->ky]) - r->sy * cz_;
    const float u = clvr_hull_diff_of_products(cx, by, cy, bx);
    const float v = clvr_hull_diff_of_products(ax, cy, ay, cx);
    const float w = clvr_hull_diff_of_products(bx, ay, by, ax);
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return;
    const float det = u + v + w;
    if (!(det != 0.0f)) return; /* ray in the triangle's plane: its neighbours answer */
    const float t = (u * (r->sz * az_) + v * (r->sz * bz_) + w * (r->sz * cz_)) / det;
    if (!(fabs(t) < INFINITY)) return;
    *lo = fmin(*lo, t);
    *hi = fmax(*hi, t);
}

/* Face h: a triangle, or a quad as the tetrahedron of its corners. */
CLVR_INLINE void clvr_hull_ray_face(const clvr_hull_ray *r, CLVR_GLOBAL const clvr_hull_face *h, float *lo, float *hi)
{
    CLVR_GLOBAL const float *p0 = h->p[0], *p1 = h->p[1], *p2 = h->p[2], *p3 = h->p[3];
    clvr_hull_ray_tri(r, p0, p1, p2, lo, hi);
    if (h->p[0][3] == 4.0f) {
        clvr_hull_ray_tri(r, p0, p2, p3, lo, hi);
        clvr_hull_ray_tri(r, p0, p1, p3, lo, hi);
        clvr_hull_ray_tri(r, p1, p2, p3, lo, hi);
    }
}

/* The slab test of the four children of node n against the ray r with
 * inverse direction (ix, iy, iz): bit c of the result is set when the line
 * crosses child c's box (an empty slot never), and a[c], b[c] are its entry
 * and exit along the line (set for every child, meaningful where its bit
 * is). The same operations per child on the host and on float4 lanes in
 * kernels (a node stores its four children's bounds side by side): one
 * child at a time, these tests were 6.5% of the PLOT3D combustor's urm
 * frame (perf), the walks that find where camera rays cross the hull. */
CLVR_INLINE clvr_u32 clvr_hull_node_spans(CLVR_GLOBAL const clvr_bvh_node *n, const clvr_hull_ray *r, float ix,
                                          float iy, float iz, float *a, float *b)
{
#ifdef __OPENCL_VERSION__
    CLVR_GLOBAL const float4 *q = (CLVR_GLOBAL const float4 *)n; /* lo x y z, hi x y z, child */
    const float4 ax = (q[0] - r->o[0]) * ix, bx = (q[3] - r->o[0]) * ix;
    const float4 ay = (q[1] - r->o[1]) * iy, by = (q[4] - r->o[1]) * iy;
    const float4 az = (q[2] - r->o[2]) * iz, bz = (q[5] - r->o[2]) * iz;
    const float4 a4 = fmax(fmax(fmin(ax, bx), fmin(ay, by)), fmin(az, bz));
    const float4 b4 = fmin(fmin(fmax(ax, bx), fmax(ay, by)), fmax(az, bz));
    vstore4(a4, 0, a);
    vstore4(b4, 0, b);
    const int4 hit = (q[0] <= q[3]) & (a4 <= b4);
    return (clvr_u32)((hit.x & 1) | (hit.y & 2) | (hit.z & 4) | (hit.w & 8));
#else
    clvr_u32 mask = 0;
    for (int c = 0; c < 4; ++c) {
        const float ax = (n->lo_x[c] - r->o[0]) * ix, bx = (n->hi_x[c] - r->o[0]) * ix;
        const float ay = (n->lo_y[c] - r->o[1]) * iy, by = (n->hi_y[c] - r->o[1]) * iy;
        const float az = (n->lo_z[c] - r->o[2]) * iz, bz = (n->hi_z[c] - r->o[2]) * iz;
        a[c] = fmax(fmax(fmin(ax, bx), fmin(ay, by)), fmin(az, bz));
        b[c] = fmin(fmin(fmax(ax, bx), fmax(ay, by)), fmax(az, bz));
        mask |= (clvr_u32)(n->lo_x[c] <= n->hi_x[c] && a[c] <= b[c]) << c;
    }
    return mask;
#endif
}

/* The first (far = 0) or last (far = 1) crossing of the ray with the faces
 * under the tree `nodes` (root 0, primitive i = face i): with far = 0,
 * lowers *t to the smallest hit below it; with far = 1, raises it to the
 * largest above it. Children are visited nearest first (farthest first)
 * and skipped once they cannot improve *t. */
CLVR_INLINE void clvr_hull_crossing(CLVR_GLOBAL const clvr_bvh_node *nodes, CLVR_GLOBAL const clvr_hull_face *faces,
                                    const clvr_hull_ray *r, float dx, float dy, float dz, int far, float *t)
{
    const float ix = clvr_bvh_safe_inv(dx), iy = clvr_bvh_safe_inv(dy), iz = clvr_bvh_safe_inv(dz);
    clvr_u32 stack[CLVR_BVH_STACK_SIZE];
    clvr_u32 sp = 1;
    stack[0] = 0u;
    while (sp > 0u) {
        const clvr_u32 ref = stack[--sp];
        if (ref & CLVR_BVH_LEAF_BIT) {
            float lo = INFINITY, hi = -INFINITY;
            clvr_hull_ray_face(r, faces + (ref & CLVR_BVH_MAX_PRIMS), &lo, &hi);
            *t = far ? fmax(*t, hi) : fmin(*t, lo);
            continue;
        }
        CLVR_GLOBAL const clvr_bvh_node *n = nodes + ref;
        clvr_u32 ch[4];
        float key[4], a4[4], b4[4];
        clvr_u32 cnt = 0;
        const clvr_u32 mask = clvr_hull_node_spans(n, r, ix, iy, iz, a4, b4);
        for (int c = 0; c < 4; ++c) {
            const float a = a4[c], b = b4[c];
            if (!((mask >> c) & 1u)) continue;
            if (far ? !(b > *t) : !(a < *t)) continue;
            /* Pushed so that the most promising child pops first. */
            const float k = far ? b : -a;
            clvr_u32 j = cnt++;
            for (; j > 0u && key[j - 1u] > k; --j) {
                key[j] = key[j - 1u];
                ch[j] = ch[j - 1u];
            }
            key[j] = k;
            ch[j] = n->child[c];
        }
        for (clvr_u32 j = 0; j < cnt && sp < CLVR_BVH_STACK_SIZE; ++j) stack[sp++] = ch[j];
    }
}

/* Where a query of the ray (o, d) over the faces under `nodes` starts: the
 * faces' (padded) box, the union of the root's children; whether the origin
 * lies outside it; the ray made from s = the box entry when outside, else
 * from the origin (coordinates relative to a nearby origin, for precision),
 * its distances then relative to s; and the margin `pad` by which a cut is
 * widened so that rounding of t never cuts medium off (1e-5 of the chord
 * through the box, 1e-6 of s). Returns 0 when the ray misses the box. */
typedef struct clvr_hull_query {
    clvr_hull_ray r;
    int outside;
    float s, pad;
} clvr_hull_query;

CLVR_INLINE int clvr_hull_query_begin(CLVR_GLOBAL const clvr_bvh_node *nodes, float ox, float oy, float oz, float dx,
                                      float dy, float dz, clvr_hull_query *q)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 4; ++c) {
        lo[0] = fmin(lo[0], nodes->lo_x[c]);
        lo[1] = fmin(lo[1], nodes->lo_y[c]);
        lo[2] = fmin(lo[2], nodes->lo_z[c]);
        hi[0] = fmax(hi[0], nodes->hi_x[c]);
        hi[1] = fmax(hi[1], nodes->hi_y[c]);
        hi[2] = fmax(hi[2], nodes->hi_z[c]);
    }
    q->outside = ox < lo[0] || oy < lo[1] || oz < lo[2] || ox > hi[0] || oy > hi[1] || oz > hi[2];
    const float ix = clvr_bvh_safe_inv(dx), iy = clvr_bvh_safe_inv(dy), iz = clvr_bvh_safe_inv(dz);
    const float ax = (lo[0] - ox) * ix, bx = (hi[0] - ox) * ix, ay = (lo[1] - oy) * iy, by = (hi[1] - oy) * iy;
    const float az = (lo[2] - oz) * iz, bz = (hi[2] - oz) * iz;
    const float ta = fmax(fmax(fmax(fmin(ax, bx), fmin(ay, by)), fmin(az, bz)), 0.0f);
    const float tb = fmin(fmin(fmax(ax, bx), fmax(ay, by)), fmax(az, bz));
    if (!(ta <= tb)) return 0;
    q->s = q->outside ? ta : 0.0f;
    q->pad = 1e-5f * (tb - ta) + 1e-6f * fabs(q->s);
    q->r = clvr_hull_ray_make(ox + dx * q->s, oy + dy * q->s, oz + dz * q->s, dx, dy, dz);
    return 1;
}

/* Cuts [*t0, *t1] of the ray org + t dir to its part between the first
 * and the last crossing of the hull (nodes, faces: a tree of clvr_hull_build,
 * at least one face); returns 0 when the ray crosses no face (it misses the
 * mesh). The start is cut only when the origin lies outside the box of the
 * faces: from inside, the first crossing may be an exit. The crossings are
 * computed from the box entry (precision: coordinates relative to a nearby
 * origin) and widened by a tiny margin so that rounding of t never cuts
 * medium off. */
CLVR_INLINE int clvr_hull_clip(CLVR_GLOBAL const clvr_bvh_node *nodes, CLVR_GLOBAL const clvr_hull_face *faces,
                               float ox, float oy, float oz, float dx, float dy, float dz, float *t0, float *t1)
{
    clvr_hull_query q;
    if (!clvr_hull_query_begin(nodes, ox, oy, oz, dx, dy, dz, &q)) return 0;
    float first = -INFINITY, last = -INFINITY;
    if (q.outside) {
        first = INFINITY;
        clvr_hull_crossing(nodes, faces, &q.r, dx, dy, dz, 0, &first);
        if (!(first < INFINITY)) return 0;
        last = first;
    }
    clvr_hull_crossing(nodes, faces, &q.r, dx, dy, dz, 1, &last);
    if (!(last > -INFINITY)) return q.outside ? 0 : 1;
    if (q.outside) *t0 = fmax(*t0, q.s + first - q.pad);
    *t1 = fmin(*t1, q.s + last + q.pad);
    return *t0 <= *t1;
}

/* ------------------------------------------------------------ every crossing
 * The first and last crossings cut a ray to the mesh's extent; between
 * them a ray through a mesh that is not convex (the combustor's duct, the
 * post's cylinder, kiefer's hollows) leaves the medium and comes back. In
 * such a gap the extinction is 0 like outside, but the macrocells that
 * straddle the boundary give it a majorant, so the estimators spend points
 * there, and urm's control (linear between its quadrature points) jumps
 * across each boundary. clvr_hull_gaps finds every crossing instead (one
 * walk without pruning), so that the renderer can give each gap that lies
 * outside the mesh the majorant 0. */
#ifndef CLVR_HULL_MAX_HITS
#define CLVR_HULL_MAX_HITS 16
#endif
/* Floats per ray of the test kernel clvr_hull_gap_rays. */
#define CLVR_HULL_GAP_STRIDE (4 + 2 * CLVR_HULL_MAX_HITS)

/* Every face the ray r crosses under `nodes`: the distances [lo[i], hi[i]]
 * where it may cross face i (a quad's tetrahedron gives an interval, a
 * triangle one point), sorted by lo; returns their count, or -1 past
 * `max`. */
CLVR_INLINE int clvr_hull_hits(CLVR_GLOBAL const clvr_bvh_node *nodes, CLVR_GLOBAL const clvr_hull_face *faces,
                               const clvr_hull_ray *r, float dx, float dy, float dz, float *lo, float *hi, int max)
{
    const float ix = clvr_bvh_safe_inv(dx), iy = clvr_bvh_safe_inv(dy), iz = clvr_bvh_safe_inv(dz);
    clvr_u32 stack[CLVR_BVH_STACK_SIZE];
    clvr_u32 sp = 1;
    int n = 0;
    stack[0] = 0u;
    while (sp > 0u) {
        const clvr_u32 ref = stack[--sp];
        if (ref & CLVR_BVH_LEAF_BIT) {
            float a = INFINITY, b = -INFINITY;
            clvr_hull_ray_face(r, faces + (ref & CLVR_BVH_MAX_PRIMS), &a, &b);
            if (!(a <= b)) continue;
            if (n == max) return -1;
            int j = n++;
            for (; j > 0 && lo[j - 1] > a; --j) {
                lo[j] = lo[j - 1];
                hi[j] = hi[j - 1];
            }
            lo[j] = a;
            hi[j] = b;
            continue;
        }
        CLVR_GLOBAL const clvr_bvh_node *nd = nodes + ref;
        float a4[4], b4[4];
        const clvr_u32 mask = clvr_hull_node_spans(nd, r, ix, iy, iz, a4, b4);
        for (int c = 0; c < 4; ++c)
            if (((mask >> c) & 1u) && sp < CLVR_BVH_STACK_SIZE) stack[sp++] = nd->child[c];
    }
    return n;
}

/* clvr_hull_clip, and the candidate gaps: the stretches of [*t0, *t1]
 * between two consecutive crossings (after merging crossings that overlap
 * or lie within the clip's margin of each other), and, when the origin is
 * inside the faces' box, the stretch before the first crossing: each lies
 * wholly inside or wholly outside the mesh (only a crossing separates
 * them), which the caller decides by one lookup at its middle. Writes at
 * most CLVR_HULL_MAX_HITS gaps [glo[i], ghi[i]] in order and returns their
 * count; -1 when the ray misses the mesh (as clvr_hull_clip's 0); -2 when
 * it crosses more faces than CLVR_HULL_MAX_HITS (the caller then takes
 * clvr_hull_clip). */
CLVR_INLINE int clvr_hull_gaps(CLVR_GLOBAL const clvr_bvh_node *nodes, CLVR_GLOBAL const clvr_hull_face *faces,
                               float ox, float oy, float oz, float dx, float dy, float dz, float *t0, float *t1,
                               float *glo, float *ghi)
{
    clvr_hull_query q;
    if (!clvr_hull_query_begin(nodes, ox, oy, oz, dx, dy, dz, &q)) return -1;
    const int outside = q.outside;
    const float s = q.s, pad = q.pad;
    float hlo[CLVR_HULL_MAX_HITS], hhi[CLVR_HULL_MAX_HITS];
    const int n = clvr_hull_hits(nodes, faces, &q.r, dx, dy, dz, hlo, hhi, CLVR_HULL_MAX_HITS);
    if (n < 0) return -2;
    if (n == 0) return outside ? -1 : 0;
    /* From inside, crossings behind the origin only bound the end (as in
     * clvr_hull_clip: if all are behind, the ray misses); gaps start at the
     * first crossing ahead. */
    int k = 0;
    while (!outside && k < n - 1 && hhi[k] < 0.0f) ++k;
    int ng = 0;
    if (outside) *t0 = fmax(*t0, s + hlo[k] - pad);
    else if (hlo[k] - pad > *t0 - s) { /* from inside: before the first crossing */
        glo[ng] = *t0;
        ghi[ng++] = s + hlo[k] - pad;
    }
    float end = hhi[k];
    for (int j = 0; j < k; ++j) end = fmax(end, hhi[j]); /* behind the origin: below 0, as the walk's last */
    /* The stretch after the first crossing of a ray from outside is medium
     * (the ray enters there), and so is the one before the last crossing
     * (it leaves there): they are no candidates. Keeping a stretch as medium
     * is always safe; only a gap must be free of it. */
    const int first = ng;
    int skip_first = outside;
    for (++k; k < n; ++k) {
        if (hlo[k] - end > 2.0f * pad) { /* a stretch between two crossings */
            if (skip_first) {
                skip_first = 0;
            } else {
                glo[ng] = s + end + pad;
                ghi[ng++] = s + hlo[k] - pad;
            }
        }
        end = fmax(end, hhi[k]);
    }
    if (ng > first) --ng; /* the last stretch ends at the last crossing */
    *t1 = fmin(*t1, s + end + pad);
    return *t0 <= *t1 ? ng : -1;
}

#endif /* CLVR_HULL_H */
