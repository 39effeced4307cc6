/* clvr_shared.h: the one header of plain data shared by the C host and every
 * OpenCL program. Only fixed-width scalars and explicit padding live here
 * (never float3, size_t, bool or pointers), so that a struct has the same
 * layout on both sides; the host checks every size with CLVR_STATIC_ASSERT.
 *
 * Sections are owned by modules: base, mesh, preprocess, bvh, render.
 * Helpers that are compiled twice (host reference and kernel) use
 * CLVR_INLINE and CLVR_GLOBAL so both sides run the very same code. */
#ifndef CLVR_SHARED_H
#define CLVR_SHARED_H

/* ---------------------------------------------------------------- base */
#ifdef __OPENCL_VERSION__
typedef uchar clvr_u8;
typedef ushort clvr_u16;
typedef uint clvr_u32;
typedef int clvr_i32;
typedef ulong clvr_u64;
typedef long clvr_i64;
#define CLVR_GLOBAL __global
#define CLVR_CONSTANT __constant
#define CLVR_INLINE inline
/* For small hot helpers of per-element kernels: inlined, no call is left
 * in the work-item loop a CPU device compiles the kernel into. static: no
 * out-of-line copy is emitted, whose loops (with a runtime count, e.g.
 * clvr_pp_element_box's vpe) could not honour CLVR_UNROLL and made PoCL's
 * compiler warn "loop not unrolled" on every cold-cache build. */
#define CLVR_FORCE_INLINE static inline __attribute__((always_inline))
/* Full unrolling of a short fixed-count loop in such kernels. */
#define CLVR_UNROLL _Pragma("unroll")
#define CLVR_STATIC_ASSERT(cond, msg)
#else
#include <stdint.h>
typedef uint8_t clvr_u8;
typedef uint16_t clvr_u16;
typedef uint32_t clvr_u32;
typedef int32_t clvr_i32;
typedef uint64_t clvr_u64;
typedef int64_t clvr_i64;
#define CLVR_GLOBAL
#define CLVR_CONSTANT const
#define CLVR_INLINE static inline
#define CLVR_FORCE_INLINE static inline
#define CLVR_UNROLL
#define CLVR_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#endif

/* A hint to start loading the cache line at p (no fault, no effect on
 * results). Point location on a CPU device is bound by dependent cache
 * misses; asking for the next lines before they are needed overlaps them.
 * In kernels only where the host defines CLVR_DEVICE_PREFETCH (PoCL's CPU
 * devices, whose address spaces are one): NVIDIA's OpenCL compiler rejects
 * the __global pointer the builtin would get ("changes address space of
 * pointer"), and a GPU gains nothing from it. The host's own compile of
 * these helpers always has it. A no-op where the compiler lacks the builtin. */
#if defined(__has_builtin) && (!defined(__OPENCL_VERSION__) || defined(CLVR_DEVICE_PREFETCH))
#if __has_builtin(__builtin_prefetch)
#define CLVR_PREFETCH(p) __builtin_prefetch((CLVR_GLOBAL const void *)(p))
#endif
#endif
#ifndef CLVR_PREFETCH
#define CLVR_PREFETCH(p) ((void)(p))
#endif
/* Bytes per cache line that CLVR_PREFETCH fetches (x86, most ARM cores). */
#define CLVR_CACHE_LINE 64u

/* ---------------------------------------------------------------- mesh */
/* Element types, in the order of the mesh's four index lists. Vertex order
 * within an element is VTK's (VTK_TETRA 10, VTK_PYRAMID 14, VTK_WEDGE 13,
 * VTK_HEXAHEDRON 12). */
#define CLVR_CELL_TET 0u
#define CLVR_CELL_PYRAMID 1u
#define CLVR_CELL_WEDGE 2u
#define CLVR_CELL_HEX 3u
#define CLVR_CELL_TYPE_COUNT 4u
/* Largest vertex count of any element type (the hexahedron). */
#define CLVR_CELL_MAX_VERTS 8u

/* Every element type once, in CLVR_CELL_* order: X(id, name, vertex count).
 * The per-type code is generated from this list: the vertex count below,
 * the element dispatchers of kernels/elements.h (which call
 * clvr_<name>_shape, _inside and _start), the preprocessing's key kernels
 * (clvr_pp_keys_<name>) and leaf-box loops. A new type is one line here,
 * its element functions and its loader mapping (docs/extending.md). */
#define CLVR_CELL_TYPES(X)              \
    X(CLVR_CELL_TET, tet, 4u)           \
    X(CLVR_CELL_PYRAMID, pyramid, 5u)   \
    X(CLVR_CELL_WEDGE, wedge, 6u)       \
    X(CLVR_CELL_HEX, hex, 8u)

/* Vertices per element of the type (CLVR_CELL_MAX_VERTS for an unknown
 * one). A chain of selects, not a table: it folds to a constant wherever
 * the type is one (the per-type kernels). */
CLVR_INLINE clvr_u32 clvr_cell_vertex_count(clvr_u32 type)
{
#define CLVR_CELL_NV_(id, name, nv) type == (id) ? (nv) :
    return CLVR_CELL_TYPES(CLVR_CELL_NV_) CLVR_CELL_MAX_VERTS;
#undef CLVR_CELL_NV_
}

/* The inverse of clvr_hex_collapsed (kernels/elements.h) on vertex ids:
 * h[0..7] = the 8-node hex that reads back as the element v (vertex ids in
 * VTK order, clvr_cell_vertex_count(type) of them): tet a b c c d d d d,
 * pyramid a b c d e e e e, wedge a b c c d e f f, a hex itself.
 * Preprocessing with one curve (clvr_preprocess_options.one_curve) stores
 * every cell of a mixed mesh this way, so that one Hilbert curve, one fixed
 * stride and one instance type hold them all. */
CLVR_INLINE void clvr_hex_collapse_ids(clvr_u32 type, const clvr_u32 *v, clvr_u32 *h)
{
    if (type == CLVR_CELL_TET) {
        h[0] = v[0]; h[1] = v[1]; h[2] = h[3] = v[2];
        h[4] = h[5] = h[6] = h[7] = v[3];
    } else if (type == CLVR_CELL_PYRAMID) {
        h[0] = v[0]; h[1] = v[1]; h[2] = v[2]; h[3] = v[3];
        h[4] = h[5] = h[6] = h[7] = v[4];
    } else if (type == CLVR_CELL_WEDGE) {
        h[0] = v[0]; h[1] = v[1]; h[2] = h[3] = v[2];
        h[4] = v[3]; h[5] = v[4]; h[6] = h[7] = v[5];
    } else {
        for (int k = 0; k < 8; ++k) h[k] = v[k];
    }
}

/* Where each type's elements and index slots start in the concatenated
 * type lists (elements of type t: global ids first[t] .. first[t + 1] - 1,
 * the last type ending at the element count; their indices from slot[t],
 * vertex_count(t) each). Passed by value to the preprocessing kernels.
 * 48 bytes, no padding (slot is 8-aligned at offset 16). */
typedef struct clvr_type_layout {
    clvr_u32 first[CLVR_CELL_TYPE_COUNT];
    clvr_u64 slot[CLVR_CELL_TYPE_COUNT];
} clvr_type_layout;
CLVR_STATIC_ASSERT(sizeof(clvr_type_layout) == 12 * CLVR_CELL_TYPE_COUNT, "clvr_type_layout layout");

/* An axis-aligned box; w lanes are padding (kept zero) so that the box maps
 * onto two float4 loads on the device. 32 bytes. */
typedef struct clvr_box {
    float lo[4];
    float hi[4];
} clvr_box;
CLVR_STATIC_ASSERT(sizeof(clvr_box) == 32, "clvr_box layout");

/* ---------------------------------------------------------------- clustered mesh
 * The contract between preprocessing (which writes it), bvh/ (which builds
 * trees over it) and the renderer (which reads it). Decisions (docs/how-it-works.md,
 * "Decisions, measured where it mattered"):
 * - Each element type is sorted along its own Hilbert curve (same
 *   quantization grid: the mesh bounds, or a box the caller gives so that
 *   partitions of one mesh share it), so every cluster holds one element
 *   type and elements are addressed with a fixed stride, no per-element tag.
 *   Or, with one curve (host/pipeline/preprocess.h, one_curve; the default
 *   for most meshes of mixed types), every cell is sorted along one curve
 *   and stored as a hex, a tet, pyramid or wedge as its collapsed hex
 *   (clvr_hex_collapse_ids): the clusters are hexes and hold every type of
 *   their region, and readers that need a cell's own type take it from its
 *   repeated corners (kernels/locate.h clvr_load_cell_in).
 * - Global sorted element ids are the concatenation of the four sorted
 *   lists: tets [0, T), pyramids [T, T+P), wedges, hexes.
 * - Instance clusters are consecutive runs of one type's sorted elements
 *   whose referenced vertex count stays below 2^16 (then 16-bit indices) or
 *   that fall back to 32-bit indices. Their vertices are copied (duplicates
 *   across clusters kept, as in the paper) into one array of float4
 *   (x, y, z, scalar), so one load gives position and value.
 * - Leaf clusters are consecutive runs of leaf_size elements inside one
 *   instance (the last one may be shorter); leaf i of instance c covers
 *   elements c.first_element + (i - c.first_leaf) * leaf_size, ... .
 * - Sampling clusters are consecutive runs of sampling_size elements inside
 *   one element type, with bounds and the scalar range of their vertices. */

/* Per-axis bits of the space-filling-curve keys (48-bit keys, as the paper). */
#define CLVR_SFC_BITS 16u
/* Instance clusters use 16-bit local indices when they reference fewer than
 * this many vertices. */
#define CLVR_INSTANCE_MAX_VERTS16 65536u

/* Most pieces an array of the clustered mesh is cut into (docs/large-meshes.md):
 * the arrays whose entries belong to instance clusters (clustered vertices,
 * 16- and 32-bit local indices, element boxes) are cut at instance
 * boundaries so that no device buffer exceeds CL_DEVICE_MAX_MEM_ALLOC_SIZE.
 * Kernels take each piece as its own __global pointer (OpenCL 1.2 has no
 * arrays of buffers), so this is also the number of such arguments. */
#define CLVR_MAX_SPLITS 4u

typedef struct clvr_instance {
    clvr_box bounds;          /* bounds of its elements (w lanes zero) */
    clvr_u16 type;            /* CLVR_CELL_* of every element in it */
    clvr_u16 index_bits;      /* 16: indices in idx16[]; 32: in idx32[] */
    clvr_u32 piece;           /* piece (0 .. CLVR_MAX_SPLITS - 1) of the split arrays that hold its
                                 vertices, indices and element boxes; 0 when they are not split */
    clvr_u32 first_element;   /* global sorted element id of its first element */
    clvr_u32 num_elements;
    clvr_u32 first_vertex;    /* into its piece of the clustered vertices (float4 x y z scalar) */
    clvr_u32 num_vertices;
    clvr_u64 first_index;     /* into its piece of idx16[] or idx32[]; element e's indices start at
                                 first_index + (e - first_element) * vertex_count(type),
                                 each relative to first_vertex */
    clvr_u32 first_leaf;      /* its leaf clusters: first_leaf .. first_leaf + num_leaves - 1 */
    clvr_u32 num_leaves;
    clvr_u32 bvh_root;        /* root of its bottom-level tree in the BLAS node array (bvh/) */
    clvr_u32 piece_first_element; /* global sorted id of its piece's first element: element e's
                                     box is entry e - piece_first_element of the piece's element
                                     boxes (0 when not split) */
} clvr_instance;
CLVR_STATIC_ASSERT(sizeof(clvr_instance) == 80, "clvr_instance layout");

/* Entry grid of one instance cluster (kernels/locate.h, "entry grids"): a
 * uniform grid over the instance's element bounds whose cells name the node
 * of its bottom-level tree where a point's walk starts. A point's cell on
 * axis k is clvr_entry_coord(p_k, lo[k], scale[k], res[k]). */
typedef struct clvr_entry_grid {
    float lo[4];      /* xyz: low corner; w unused (0) */
    float scale[4];   /* xyz: cells per unit length, 0 on an axis of one cell; w unused (0) */
    clvr_u32 res[4];  /* xyz: cells per axis (>= 1); w: the instance's first cell in the cell array (the
                       * occupancy grid: its first u32 word there, locate.h) */
} clvr_entry_grid;
CLVR_STATIC_ASSERT(sizeof(clvr_entry_grid) == 48, "clvr_entry_grid layout");

/* A sampling cluster (paper 3.4.1): box with the scalar range in the w lanes:
 * lo[3] = minimum scalar, hi[3] = maximum scalar of its elements' vertices. */
typedef struct clvr_sampling_cluster {
    float lo[4];
    float hi[4];
} clvr_sampling_cluster;
CLVR_STATIC_ASSERT(sizeof(clvr_sampling_cluster) == 32, "clvr_sampling_cluster layout");

/* ---------------------------------------------------------------- preprocess
 * (owned by the preprocessing module: kernels/bounds, sfc, sort, scan,
 * cluster, reindex) */

/* Radix sort digits: 8 bits, so 48-bit curve keys plus the 2-bit type need
 * at most 7 passes, fewer when a digit is the same for every key. */
#define CLVR_PP_RADIX_BITS 8u
#define CLVR_PP_RADIX 256u

/* One instance cluster as the greedy split (kernels/reindex.cl) finds it,
 * before the offsets of the clustered arrays are known. 24 bytes. */
typedef struct clvr_pp_instance_rec {
    clvr_u64 vsrc;            /* where its vertex ids (first-use order) start in the scratch vertex map */
    clvr_u32 first_element;   /* global sorted element id */
    clvr_u32 num_elements;
    clvr_u32 num_vertices;    /* distinct vertices its elements reference */
    clvr_u32 type;            /* CLVR_CELL_* */
} clvr_pp_instance_rec;
CLVR_STATIC_ASSERT(sizeof(clvr_pp_instance_rec) == 24, "clvr_pp_instance_rec layout");

/* bvh_root of an instance before bvh/ has built its tree. */
#define CLVR_PP_NO_ROOT 0xffffffffu

/* ---------------------------------------------------------------- bvh
 * (owned by bvh/: node layout, sentinels)
 *
 * A vertex of the clustered mesh: x, y, z and the scalar in w. On the device
 * it is float4 (one 16-byte load); on the host a POD with the same fields, so
 * code written against .x .y .z .w compiles on both sides. */
#ifdef __OPENCL_VERSION__
typedef float4 clvr_vec4;
#else
typedef struct clvr_vec4 {
    float x, y, z, w;
} clvr_vec4;
CLVR_STATIC_ASSERT(sizeof(clvr_vec4) == 16, "clvr_vec4 layout");
#endif

/* Every tree (top level over instances, bottom level per instance over its
 * leaf clusters, single level over sampling clusters) is a 4-wide BVH packed
 * bottom-up from primitives in Hilbert order (a Hilbert R-tree, Kamel and
 * Faloutsos 1994): primitives 4m..4m+3 form node m of the lowest level,
 * nodes 4m..4m+3 of a level form node m of the next. A tree over n
 * primitives has ceil(log4 n) levels (1 when n <= 4; an empty tree is one
 * node with four empty slots). Nodes of one tree are stored root first,
 * level by level, so the root is the tree's first node; child references
 * are absolute indices into the node array the tree lives in.
 *
 * Node: the four child boxes as structure-of-arrays (one float4 per bound
 * component) and four child references. 112 bytes, 16-byte aligned.
 * About n/3 nodes per tree: ~37 bytes per primitive, so with leaf clusters of
 * N elements the bottom level costs ~37/N bytes per element. */
typedef struct clvr_bvh_node {
    float lo_x[4], lo_y[4], lo_z[4];
    float hi_x[4], hi_y[4], hi_z[4];
    clvr_u32 child[4];  /* CLVR_BVH_EMPTY, an inner node index, or CLVR_BVH_LEAF_BIT | primitive id */
} clvr_bvh_node;
CLVR_STATIC_ASSERT(sizeof(clvr_bvh_node) == 112, "clvr_bvh_node layout");

/* Children per node. */
#define CLVR_BVH_WIDTH 4u
/* child[] of an unused slot; its box is empty (lo = +inf, hi = -inf). */
#define CLVR_BVH_EMPTY 0xffffffffu
/* child[] with this bit set names a primitive (leaf cluster, instance or
 * box), the other 31 bits its index: at most 2^31 - 1 primitives per tree. */
#define CLVR_BVH_LEAF_BIT 0x80000000u
#define CLVR_BVH_MAX_PRIMS 0x7fffffffu
/* Element id reported by point location when no element contains the point. */
#define CLVR_BVH_NOT_FOUND 0xffffffffu
/* Query hints of point location (kernels/locate.h, the clvr_locate_points
 * kernel), in the spirit of Embree's coherent/incoherent ray flags; they
 * change speed, never a result. COHERENT: neighbouring queries are close
 * (the renderer's samples, sorted points): the tree walk as is.
 * INCOHERENT: queries are scattered (random points): the walk prefetches
 * every hit child's lines, a lowest-level node's leaf index blocks and a
 * hit leaf's tet vertices before searching, so that the cache misses that
 * bound it overlap. Measured on PoCL, 1M tets, leaves of 8, before the
 * element boxes: random points +23% to +40% queries/s; sorted points lost
 * 12% to 20%, hence the hint. Remeasured with the element boxes and leaves
 * of 16 (2-core Intel Xeon, PoCL 3.1, bench_locate --order random,
 * interleaved runs), INCOHERENT loses on random points too: queries/s
 * 6.63 -> 6.11M on the combustor as tets, 1.84 -> 1.64M on 1M tets, 4.31 ->
 * 3.92M post, 6.77 -> 6.08M blunt fin, 3.78 -> 3.38M gmsh point-graded,
 * 4.59 -> 4.48M the AMR-like 6M tets; prefetching only the hit children or
 * only the leaves' boxes did no better, and without element boxes it was
 * even or lost. So every caller here passes COHERENT; INCOHERENT stays for
 * machines where the misses overlap better (the figures above). */
#define CLVR_LOCATE_COHERENT 0u
#define CLVR_LOCATE_INCOHERENT 1u
/* Traversal stack entries. A packed tree over n < 2^32 primitives has at
 * most 16 levels and needs at most 3 * 16 + 1 entries. */
#ifndef CLVR_BVH_STACK_SIZE
#define CLVR_BVH_STACK_SIZE 52
#endif
/* Tolerances shared by containment and boxes. A point whose parametric
 * coordinates are outside the element by at most CLVR_ELEMENT_EPS still
 * counts as inside, so a point on a shared face, edge or vertex is found in
 * every neighbour (never lost between them). Boxes are padded by
 * CLVR_BVH_BOX_PAD_REL times their largest extent (plus a few ulps of their
 * coordinates) so that such points also pass every box test on the way. */
#define CLVR_ELEMENT_EPS 1e-5f
#define CLVR_BVH_BOX_PAD_REL 1e-4f

/* One tree in a node array, for the level-by-level builder (host reference
 * and kernels/bvh.cl): primitives first_prim .. first_prim + num_prims - 1 of
 * a box array, nodes from node_base. 16 bytes. */
typedef struct clvr_bvh_tree {
    clvr_u32 node_base;
    clvr_u32 first_prim;
    clvr_u32 num_prims;
    clvr_u32 pad0;
} clvr_bvh_tree;
CLVR_STATIC_ASSERT(sizeof(clvr_bvh_tree) == 16, "clvr_bvh_tree layout");

/* ---------------------------------------------------------------- render
 * (owned by the renderer: camera, transfer function, light, frame params) */

/* camera + transfer function (host/pipeline/camera.c, host/io/tf.c) */
#ifdef __OPENCL_VERSION__
#define CLVR_SQRTF sqrt
#define CLVR_FLOORF floor
#define CLVR_FMINF fmin
#define CLVR_FMAXF fmax
#else
#include <math.h>
#define CLVR_SQRTF sqrtf
#define CLVR_FLOORF floorf
#define CLVR_FMINF fminf
#define CLVR_FMAXF fmaxf
#endif

/* A pinhole camera as the primary-ray generator reads it. Pixel (px, py) are
 * continuous image coordinates: px in [0, width) from left to right, py in
 * [0, height) from the TOP row down (rows are stored top to bottom), so pixel
 * (x, y) with sub-pixel jitter (u, v) in [0, 1)^2 is (x + u, y + v) and its
 * centre is (x + 0.5, y + 0.5). The image plane sits at distance 1 along
 * `forward`; the ray through (px, py) has direction
 * corner + px * du + py * dv (then normalised). Built by clvr_camera_look_at;
 * vectors are float[4] with w = 0. 144 bytes. */
typedef struct clvr_camera {
    float origin[4];  /* eye position, world units */
    float corner[4];  /* eye -> top-left corner of the image plane (pixel coordinates (0, 0)) */
    float du[4];      /* image-plane step of one pixel to the right */
    float dv[4];      /* image-plane step of one pixel down */
    float forward[4]; /* unit view direction (eye -> target) */
    float right[4];   /* unit, image x axis */
    float up[4];      /* unit, image y axis (upwards), orthogonal to forward and right */
    float target[4];  /* the look-at point (viewers orbit around it) */
    float fovy;       /* vertical field of view, degrees, (0, 180) */
    float aspect;     /* width / height */
    clvr_u32 width, height;
} clvr_camera;
CLVR_STATIC_ASSERT(sizeof(clvr_camera) == 144, "clvr_camera layout");

/* Primary ray through continuous pixel coordinates (px, py), see
 * clvr_camera: org = eye, dir = unit direction. */
CLVR_INLINE void clvr_camera_ray(const clvr_camera *cam, float px, float py, float *org, float *dir)
{
    float d0 = cam->corner[0] + px * cam->du[0] + py * cam->dv[0];
    float d1 = cam->corner[1] + px * cam->du[1] + py * cam->dv[1];
    float d2 = cam->corner[2] + px * cam->du[2] + py * cam->dv[2];
    float inv = 1.0f / CLVR_SQRTF(d0 * d0 + d1 * d1 + d2 * d2);
    org[0] = cam->origin[0];
    org[1] = cam->origin[1];
    org[2] = cam->origin[2];
    dir[0] = d0 * inv;
    dir[1] = d1 * inv;
    dir[2] = d2 * inv;
}

/* The baked transfer function is a table of n >= 2 entries of 4 floats
 * (linear r, g, b, then extinction per unit density in 1/world length; see
 * docs/transfer-function.md), entry i at scalar lo + i * (hi - lo) / (n - 1).
 * A scalar s maps to the continuous table position
 *   p = clamp((s - lo) * (n - 1) / (hi - lo), 0, n - 1)
 * (scalars outside the window take the end entries; NaN maps to 0) and the
 * lookup interpolates linearly between entries floor(p) and floor(p) + 1
 * (the last pair for p = n - 1). On the device pass the float4 table cast to
 * (__global const float *). */
#define CLVR_TF_DEFAULT_SIZE 256u

/* Table position of scalar s (see above). Monotone non-decreasing in s, which
 * the majorant relies on. */
CLVR_INLINE float clvr_tf_position(float s, float lo, float hi, clvr_u32 n)
{
    float scale = hi > lo ? (float)(n - 1u) / (hi - lo) : 0.0f;
    /* fmax/fmin return the other operand for NaN, so NaN lands on 0. */
    return CLVR_FMINF(CLVR_FMAXF((s - lo) * scale, 0.0f), (float)(n - 1u));
}

/* First entry of the interpolation pair at position p (at most n - 2). */
CLVR_INLINE clvr_u32 clvr_tf_entry(float p, clvr_u32 n)
{
    clvr_u32 i = (clvr_u32)p;
    return n < 2u ? 0u : (i > n - 2u ? n - 2u : i);
}

/* Transfer function at scalar s: out = (r, g, b, density * extinction).
 * a + f * (b - a) is used (not a * (1 - f) + b * f) so that equal neighbours
 * give exactly their value. */
CLVR_INLINE void clvr_tf_lookup(CLVR_GLOBAL const float *table, clvr_u32 n, float lo, float hi, float density,
                                float s, float *out)
{
    float p = clvr_tf_position(s, lo, hi, n);
    clvr_u32 i = clvr_tf_entry(p, n);
    clvr_u32 j = n < 2u ? 0u : i + 1u;
    float f = n < 2u ? 0.0f : p - (float)i;
    CLVR_GLOBAL const float *a = table + 4u * i;
    CLVR_GLOBAL const float *b = table + 4u * j;
    out[0] = a[0] + f * (b[0] - a[0]);
    out[1] = a[1] + f * (b[1] - a[1]);
    out[2] = a[2] + f * (b[2] - a[2]);
    out[3] = density * (a[3] + f * (b[3] - a[3]));
}

/* Relative slack of the majorant: covers the rounding of the interpolation
 * (a few ulps, possibly fused differently on the device) so that the
 * majorant is a true upper bound; it costs ~0.002% more null collisions. */
#define CLVR_TF_MAJORANT_SLACK (1.0f + 1.0f / 65536.0f)

/* Majorant: an upper bound of the looked-up extinction (clvr_tf_lookup's
 * out[3]) for every scalar in [a, b] (a > b is treated as [b, a]; NaN ends
 * as the position 0). It is the maximum over the table entries from the
 * first entry of a's interpolation pair to the second entry of b's, times
 * density and CLVR_TF_MAJORANT_SLACK. Cost: O(entries covered). */
CLVR_INLINE float clvr_tf_majorant(CLVR_GLOBAL const float *table, clvr_u32 n, float lo, float hi, float density,
                                   float a, float b)
{
    float pa = clvr_tf_position(a, lo, hi, n), pb = clvr_tf_position(b, lo, hi, n);
    if (pa > pb) { float t = pa; pa = pb; pb = t; }
    clvr_u32 i0 = clvr_tf_entry(pa, n);
    clvr_u32 i1 = n < 2u ? 0u : clvr_tf_entry(pb, n) + 1u;
    float m = 0.0f;
    for (clvr_u32 i = i0; i <= i1; ++i) m = CLVR_FMAXF(m, table[4u * i + 3u]);
    return m * density * CLVR_TF_MAJORANT_SLACK;
}

#ifdef __OPENCL_VERSION__
/* Device conveniences over float4 tables. */
inline float4 clvr_tf_sample4(__global const float4 *tf, uint n, float lo, float hi, float density, float s)
{
    float o[4];
    clvr_tf_lookup((__global const float *)tf, n, lo, hi, density, s, o);
    return (float4)(o[0], o[1], o[2], o[3]);
}
inline float clvr_tf_max_extinction(__global const float4 *tf, uint n, float lo, float hi, float density, float a,
                                    float b)
{
    return clvr_tf_majorant((__global const float *)tf, n, lo, hi, density, a, b);
}
#endif
/* end camera + transfer function */

/* ---------------------------------------------------------------- frame
 * (owned by the renderer: host/pipeline/render.c, kernels/render.cl) */

/* Methods, the values of clvr_frame.method: where majorants come from.
 * Names in clvr_render_method_name (host/pipeline/render.c), in this order. */
#define CLVR_RENDER_MARCH 0u
#define CLVR_RENDER_TRACK 1u
#define CLVR_RENDER_BINS 2u
#define CLVR_RENDER_DDA 3u
#define CLVR_RENDER_COUNT 4u

/* Estimators, the values of clvr_frame.estimator (track, bins and dda; march
 * has its own): delta: delta tracking, a 0/1 collision and a 0/1 shadow
 * visibility; urm: unbiased ray marching, a weighted quadrature with residual
 * ratio-tracked transmittance; walk: cell by cell across shared faces, each
 * tet's extinction integrated exactly, other cells' through a control and a
 * correction (kernels/render_volume.h). Same expected value;
 * names in clvr_render_estimator_name (host/pipeline/render.c), in this order. */
#define CLVR_ESTIMATOR_DELTA 0u
#define CLVR_ESTIMATOR_URM 1u
#define CLVR_ESTIMATOR_WALK 2u
/* auto (the default): walk through tets, with shadows or not (the renderer
 * falls back to urm where the walk cannot run). At cells that are not tets
 * a pilot before the first frame picks, by variance x counted cost, the
 * walk through them or urm from the first of them (clvr_frame.walk_cells;
 * host/pipeline/render.c, pilot_pick). Measured
 * (bench_render --converge, 256^2, seconds to 2% relative RMSE, medians of
 * 3 seeds): without shadows walk
 * reached 2% first on the combustor, fire_ug and the notch cut into tets
 * (about 2x) and was up to 30% slower on post, the 1M tets and the blunt
 * fin, all far under VTK's frame. With shadows (session 41, two runs of
 * seven meshes with the 64-column grid, one with the 96-column grid of
 * CLVR_URM_DEFAULT_LIGHT_RES): walk 1.5-2x sooner on fire_ug, the notch
 * cut, the 1M tets and (96 columns) post, urm 18-27% sooner on the blunt
 * fin (both one frame) and 0-8% on the combustor and the built-in scene
 * (both two frames). Sessions 39-40 took urm with shadows above 400k
 * elements; no bound by size fitted both the 1M tets and post. Settings
 * only: the renderer resolves it (clvr_estimator_auto,
 * host/pipeline/render.c), a frame never carries it. */
#define CLVR_ESTIMATOR_AUTO 3u
#define CLVR_ESTIMATOR_COUNT 4u
/* urm defaults (clvr_render_settings; measured with bench/render-vs-vtk.sh):
 * at least this many quadrature points per ray, and at most this much
 * majorant optical depth between two of them. */
#define CLVR_URM_DEFAULT_STEPS 24u
#define CLVR_URM_DEFAULT_KAPPA 0.25f
/* urm and walk with shadows: the light grid (a control variate for the
 * shadow rays, kernels/render_volume.h) lies in light space: r x r columns
 * along the light over the grid domain's extent across it, each with
 * clvr_light_depth(r) nodes from the domain's light side to its far side
 * (clvr_light_space gives the frame). r is at most CLVR_URM_LIGHT_RES,
 * CLVR_URM_DEFAULT_LIGHT_RES by default on meshes of 221k elements or
 * more, fewer below (clvr_light_res_for: at most 2 nodes per element).
 * 96 instead of 64 columns (session 41, 256^2, walk, shadows, error after
 * one frame; the grid's ms): post 2.29 -> 1.82-1.96% (one frame instead
 * of two, 0.56 -> 0.31 s), combustor 2.47 -> 2.19-2.23%, 1M tets 1.78 ->
 * 1.60%, built-in 2.30 -> 2.23%, blunt fin 1.20 -> 1.18%; the grid 19 ->
 * 41 ms on post, 21 -> 42 on the combustor, 41 -> 100 on the 1M tets, a
 * cost of the first frame only. Columns replaced an axis-aligned grid of 24^3
 * cells swept slice by slice toward the light (session 40): a column's
 * nodes share one integration toward the light, so the same time buys
 * about 8 times the nodes, and shadow edges, which run along the light,
 * lie along the columns. 256^2, fire_ug cut into 62,772 tets, walk, error
 * after 1 / 2 shadowed frames: 24^3 swept 2.55 / 1.77%; 64^3 swept (10x
 * the time) 1.95 / 1.21%; columns 40^2 x 20 2.23 / 1.42%, 48^2 x 14 2.68
 * / 1.77%, 64^2 x 32 1.86 / 1.16%, 56^2 x 40 1.85 / 1.15%
 * (bench/results/render-converge/2026-11-29-s40-light-step.md). */
#define CLVR_URM_LIGHT_RES 96u
#define CLVR_URM_DEFAULT_LIGHT_RES 96u
/* Nodes per column of a light grid of r x r columns, and in all. */
/* (one column of one node, r = 1: G = 1 everywhere, for tests) */
CLVR_INLINE clvr_u32 clvr_light_depth(clvr_u32 r) { return r >= 4u ? r / 2u : r < 2u ? r : 2u; }
CLVR_INLINE clvr_u32 clvr_light_nodes(clvr_u32 r) { return r * r * clvr_light_depth(r); }
/* Index of node j (from the light) of column (a, b). */
CLVR_INLINE int clvr_light_node(int a, int b, int j, int r) { return (j * r + b) * r + a; }
/* A column integrates the optical depth between two nodes at
 * CLVR_LIGHT_COLUMN_POINTS jittered points per node interval plus one per
 * CLVR_LIGHT_COLUMN_DEPTH of majorant optical depth. The grid is a control
 * variate, so its integration error costs variance: a depth of 0.125
 * instead of 0.5 (session 41, 64 columns, walk, shadows, error after one
 * frame) took the combustor 2.47 -> 2.36%, post 2.29 -> 2.16%, at 2-4 ms
 * more grid; 4 points per interval instead of 1 did as well (2.35 / 2.23%)
 * at 4 ms more (bench/results/render-converge/2026-11-29-s41-grid.md). */
#ifndef CLVR_LIGHT_COLUMN_POINTS
#define CLVR_LIGHT_COLUMN_POINTS 1.0f
#endif
#ifndef CLVR_LIGHT_COLUMN_DEPTH
#define CLVR_LIGHT_COLUMN_DEPTH 0.125f
#endif

/* Index of macrocell (x, y, z) in a grid of r cells per axis (x fastest):
 * the one definition shared by the majorant kernels and the DDA. */
CLVR_INLINE int clvr_grid_index(int x, int y, int z, int r) { return (z * r + y) * r + x; }

/* A boundary face of the mesh (kernels/hull.h): corners p[0..n-1] in
 * canonical order (xyz, w 0), p[0][3] = n (3 or 4); a triangle repeats
 * p[2] in p[3]. 64 bytes. */
typedef struct clvr_hull_face {
    float p[4][4];
} clvr_hull_face;
CLVR_STATIC_ASSERT(sizeof(clvr_hull_face) == 64, "clvr_hull_face layout");

/* The device arrays the renderer reads, listed once in kernel-argument
 * order (after the frame and the camera): X(kernel type, name). This list
 * generates the render kernel's parameters and the fields of its
 * clvr_volume (kernels/render.cl, render_volume.h) and the host's binding
 * (host/pipeline/render.c), so the three cannot drift apart. */
#define CLVR_VOLUME_ARRAYS(X)                                                                                          \
    X(float4, tf)                           /* transfer function table: rgb + extinction */                             \
    X(float, tf_prefix)                     /* walk: prefix sums of the table's extinction */                            \
    X(float4, vertices)                     /* clustered vertices: xyz + scalar */                                       \
    X(ushort, idx16)                        /* 16-bit local indices */                                                   \
    X(uint, idx32)                          /* 32-bit indices of large instances */                                      \
    X(clvr_instance, instances)                                                                                        \
    X(clvr_bvh_node, tlas)                                                                                             \
    X(clvr_bvh_node, blas)                                                                                             \
    X(float, grid)                          /* dda: macrocell majorants */                                              \
    X(float, blocks)                        /* dda: block majorants, see CLVR_DDA_BLOCK */                              \
    X(clvr_bvh_node, sampling_bvh)          /* bins: tree over sampling clusters */                                     \
    X(clvr_sampling_cluster, sampling)                                                                                 \
    X(float, cluster_majorants)             /* bins, track: per sampling cluster */                                    \
    X(float, light)                         /* urm: transmittance toward the light, light_res^3 cell centres */ \
    X(uchar, ebox)                          /* quantized element boxes (locate.h) */                    \
    X(clvr_entry_grid, entry_grids)         /* occupancy grid, then one entry grid per instance (locate.h), or NULL */ \
    X(uint, entry_cells)                    /* their cells (start node, hint leaf), then occupancy bits */ \
    X(clvr_bvh_node, hull_bvh)              /* tree over the boundary faces (kernels/hull.h) */        \
    X(clvr_hull_face, hull)                 /* the boundary faces, in the tree's primitive order */    \
    X(uint, face_first)                     /* walk: first face slot per instance (kernels/hull.h) */  \
    X(uint, adj)                            /* walk: element across each face slot */                 \
    /* pieces 1 .. CLVR_MAX_SPLITS - 1 of the split arrays (piece 0 above; a */                                      \
    /* small dummy buffer where the mesh has fewer pieces) */                                                        \
    X(float4, vertices1) X(float4, vertices2) X(float4, vertices3)                                                     \
    X(ushort, idx16_1) X(ushort, idx16_2) X(ushort, idx16_3)                                                           \
    X(uint, idx32_1) X(uint, idx32_2) X(uint, idx32_3)                                                                 \
    X(uchar, ebox1) X(uchar, ebox2) X(uchar, ebox3)

/* Samplers, the values of clvr_frame.sampler. independent: every uniform of
 * a frame from the counter-based generator keyed by (pixel, frame, seed),
 * frames independent. ld: the first CLVR_LD_DIMS uniforms (sub-pixel
 * position, first free flight of the primary and of the shadow ray, the
 * march offset) from a per-pixel Owen-scrambled Sobol' sequence over the
 * frame index (kernels/rng.h), the rest as independent; each frame is still
 * unbiased, the running mean converges faster, but frames are correlated. */
#define CLVR_SAMPLER_INDEPENDENT 0u
#define CLVR_SAMPLER_LD 1u
/* Pixel filters, the values of clvr_frame.pixel_filter: which image the
 * frames converge to. box (default): each pixel the mean over its square,
 * camera rays jittered across it (antialiased edges; the jitter is part of
 * a frame's noise). point: each pixel the value of the ray through its
 * centre, as VTK's and ParaView's ray casters draw it (one ray per pixel
 * centre, aliased edges that no frame count removes; no jitter noise). */
#define CLVR_PIXEL_BOX 0u
#define CLVR_PIXEL_POINT 1u
/* Largest --bins (the paper's 32 ray payload registers). */
#define CLVR_RENDER_MAX_BINS 32u

/* dda: the macrocell grid has a second, coarse level of blocks of
 * CLVR_DDA_BLOCK^3 cells (partial blocks at the far faces), each with the
 * largest majorant of its cells. A ray walks the blocks; it descends into a
 * block's cells only where the block's expected tentative collisions
 * (majorant times chord) exceed CLVR_DDA_DESCEND, otherwise it tracks the
 * block as one segment with the block majorant (still a true majorant, so
 * unbiased; the choice depends on the ray only, never on its random
 * numbers). Sparse or thin media then cost a few block steps per ray
 * instead of dozens of cell steps. Both measured on amr-1M and tets-1M
 * (bench/bench_render.c). */
#ifndef CLVR_DDA_BLOCK
#define CLVR_DDA_BLOCK 4
#endif
#ifndef CLVR_DDA_DESCEND
#define CLVR_DDA_DESCEND 0.1f
#endif

/* dda with macrocells 0 (automatic, the default): the elements are
 * rasterized into a CLVR_MACROCELLS_FINE^3 grid; for each transfer function
 * the mean majorant of its cells is compared with the mean of its blocks'
 * (a grid CLVR_DDA_BLOCK times coarser whose cells bound theirs), and the
 * fine grid is used where its mean is below CLVR_MACROCELLS_GAIN times the
 * coarse one's, else the coarse grid. A finer grid is not free: more cell
 * steps, and urm, which spends its points by the majorant, converged more
 * slowly with tighter ones (built-in scene, mean ratio 0.72: 2.8 -> 3.9 spp
 * to 2% at 128^3, shadows off; the walk did not move), and the igloo's
 * twin of even cells (ratio 0.66) rendered as fast either way. The mixed
 * OpenFOAM igloo (ratio 0.33), whose thin hot layers a coarse grid smears
 * over large cells, gains (issue #19). Measured in
 * bench/results/graded/2026-12-02-s58-macrocells.md. */
#define CLVR_MACROCELLS_FINE 128u
#ifndef CLVR_MACROCELLS_GAIN
#define CLVR_MACROCELLS_GAIN 0.5f
#endif

/* Most clip planes of a frame (--clip). */
#define CLVR_MAX_CLIP_PLANES 6u

/* Everything one frame of the render kernel needs besides the buffers.
 * Vectors are float[4] with w unused, loaded with vload3. 504 bytes. */
/* Edges of the box's projection a frame keeps (clvr_frame.live_edges): a
 * box's silhouette has at most 6. */
#define CLVR_LIVE_EDGES 6
typedef struct clvr_frame {
    float vol_lo[4];          /* clip box of the rays (the mesh bounds by default) */
    float vol_hi[4];
    float grid_lo[4];         /* domain of the macrocell grid (majorants: must cover the mesh) */
    float grid_hi[4];
    float light_dir[4];       /* unit vector toward the directional light */
    /* The light grid's frame (clvr_light_space): rows 0-2 the unit axes
     * e1, e2 across the light and L = light_dir, each with in [3] the
     * smallest e1 and e2 coordinate and the largest L coordinate of the
     * grid domain; row 3 the column spacing along e1 and e2 and the node
     * spacing along L. Node (a, b, j) lies at (u0 + (a + 1/2) du) e1 +
     * (v0 + (b + 1/2) dv) e2 + (w1 - j dw) L. */
    float light_space[4][4];
    float background[4];      /* linear rgb of rays that leave the volume */
    float ambient;            /* light that reaches every collision */
    float light_intensity;    /* light from light_dir when the shadow ray gets through */
    float step;               /* march step, world units */
    float global_majorant;    /* track: max extinction over the whole volume */
    float tf_lo, tf_hi;       /* scalar window of the transfer-function table */
    float density;            /* extinction scale applied to the table's w */
    clvr_u32 tf_size;         /* entries in the table */
    clvr_u32 width, height;
    clvr_u32 frame_index;     /* 0 for the first frame (overwrites the accumulator) */
    clvr_u32 method;          /* CLVR_RENDER_* */
    clvr_u32 seed_lo, seed_hi;
    clvr_u32 shadows;         /* nonzero: shadow rays toward the light */
    clvr_u32 bins, segments;  /* bins method: N bins per segment, M segments per ray */
    clvr_u32 grid_res;        /* dda method: macrocells per axis */
    clvr_u32 leaf_size;       /* elements per leaf cluster */
    clvr_u32 tlas_root;       /* root node of the top-level tree */
    clvr_u32 sampler;         /* CLVR_SAMPLER_* */
    clvr_u32 estimator;       /* CLVR_ESTIMATOR_* */
    clvr_u32 urm_steps;       /* urm: at least this many quadrature points per ray */
    float urm_kappa;          /* urm: at most this majorant optical depth between two points */
    clvr_u32 light_res;       /* with shadows: light grid columns per axis (clvr_light_nodes) */
    clvr_u32 num_clip_planes; /* planes in use, 0..CLVR_MAX_CLIP_PLANES */
    /* MPI mode (docs/mpi-compositing.md): mixed into the random streams of
     * the estimator (not of the sub-pixel position, which every rank must
     * share) so that ranks draw independently; 0 outside MPI mode. */
    clvr_u32 mpi_rank_key;
    clvr_u32 hull_faces;      /* boundary faces in the volume's hull arrays (kernels/hull.h); 0: none,
                                 rays keep their clipped box interval */
    clvr_u32 pixel_filter;    /* CLVR_PIXEL_* */
    /* Nonzero: clvr_render_frame also accumulates the denoiser's guides
     * (albedo and depth, kernels/denoise.h) into its guide buffer. */
    clvr_u32 guides;
    clvr_u32 num_instances;   /* instance clusters of the mesh (the walk's element -> instance search) */
    /* Half-spaces that clip the medium, (nx, ny, nz, d) with a unit normal:
     * points with n.p <= d are kept (ParaView's Clip with its default
     * "Invert": the side the normal points away from). Every ray, camera
     * and shadow alike, is cut to them (clvr_ray_clip), so the medium
     * outside is gone, as in ParaView; the majorants are left as they are
     * (still bounds on a shorter interval). */
    float clip_planes[CLVR_MAX_CLIP_PLANES][4];
    /* Adaptive sampling (render.h settings.adaptive): 0 for a frame over
     * every pixel; else a refine pass, one work item per pixel of its list,
     * whose sample goes to the refine sums (clvr_render_frame). */
    clvr_u32 pass_pixels;
    /* The walk (CLVR_ESTIMATOR_WALK): nonzero (walk, or auto where its
     * pilot picked it), through every cell type; 0 (auto otherwise),
     * through tets, handing the ray to urm at any other cell. */
    clvr_u32 walk_cells;
    /* auto's pilot (host/pipeline/render.c, pilot_pick): 0 for frames and
     * refine passes; way + 1 for a pass over the pilot's list (each pixel
     * twice: two samples), written to refine[way x pass_pixels + i] alone. */
    clvr_u32 pilot;
    /* The pixels a frame traces (clvr_frame_traces): those in the
     * rectangle [live[0], live[2]) x [live[1], live[3]) and on the inner
     * side of every edge (nx, ny, c): nx (x + 1/2) + ny (y + 1/2) <= c.
     * The camera rays of the others cannot meet the clip box
     * (host/pipeline/camera.c clvr_camera_live), and the frame writes them
     * as a ray that misses it, without drawing their streams
     * (kernels/render.cl). live[2] == 0: every pixel is traced. */
    clvr_u32 live[4];
    float live_edges[CLVR_LIVE_EDGES][4];
} clvr_frame;
CLVR_STATIC_ASSERT(sizeof(clvr_frame) == 504, "clvr_frame layout");

/* Whether frame f traces pixel (x, y) (clvr_frame.live). */
CLVR_INLINE int clvr_frame_traces(CLVR_GLOBAL const clvr_frame *f, clvr_u32 x, clvr_u32 y)
{
    if (f->live[2] == 0u) return 1;
    if (x < f->live[0] || x >= f->live[2] || y < f->live[1] || y >= f->live[3]) return 0;
    const float px = (float)x + 0.5f, py = (float)y + 0.5f;
    for (int k = 0; k < CLVR_LIVE_EDGES; ++k)
        if (f->live_edges[k][0] * px + f->live_edges[k][1] * py > f->live_edges[k][2]) return 0;
    return 1;
}

/* MPI mode, phase 1 (kernels/render.cl clvr_render_mpi_record): what one
 * rank's urm estimate along a camera ray inside its region is, for rank 0 to
 * composite front to back (host/mpi/mpi_composite.h). 48 bytes per pixel. */
typedef struct clvr_mpi_record {
    float a;       /* entry distance into the rank's region; +inf: the ray misses it */
    float tau;     /* transmittance estimate across the rank's interval */
    float wsum;    /* reservoir: total weight of the rank's points */
    float pick_g;  /* light grid G at the picked point */
    float e[4];    /* emission (rgb, ambient and light-grid lit term), transmittance inside the interval only */
    float pick[4]; /* rgb: weighted colour over weight of the pick; [3]: its distance t along the ray */
} clvr_mpi_record;
CLVR_STATIC_ASSERT(sizeof(clvr_mpi_record) == 48, "clvr_mpi_record layout");

#endif /* CLVR_SHARED_H */
