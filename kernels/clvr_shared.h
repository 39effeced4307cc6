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
#define CLVR_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#endif

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

CLVR_INLINE clvr_u32 clvr_cell_vertex_count(clvr_u32 type)
{
    return type == CLVR_CELL_TET ? 4u : type == CLVR_CELL_PYRAMID ? 5u : type == CLVR_CELL_WEDGE ? 6u : 8u;
}

/* An axis-aligned box; w lanes are padding (kept zero) so that the box maps
 * onto two float4 loads on the device. 32 bytes. */
typedef struct clvr_box {
    float lo[4];
    float hi[4];
} clvr_box;
CLVR_STATIC_ASSERT(sizeof(clvr_box) == 32, "clvr_box layout");

/* ---------------------------------------------------------------- clustered mesh
 * The contract between preprocessing (which writes it), bvh/ (which builds
 * trees over it) and the renderer (which reads it). Decisions, see DESIGN:
 * - Each element type is sorted along its own Hilbert curve (same
 *   quantization grid: the mesh bounds), so every cluster holds one element
 *   type and elements are addressed with a fixed stride, no per-element tag.
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

typedef struct clvr_instance {
    clvr_box bounds;          /* bounds of its elements (w lanes zero) */
    clvr_u32 type;            /* CLVR_CELL_* of every element in it */
    clvr_u32 index_bits;      /* 16: indices in idx16[]; 32: in idx32[] */
    clvr_u32 first_element;   /* global sorted element id of its first element */
    clvr_u32 num_elements;
    clvr_u32 first_vertex;    /* into the clustered vertex array (float4 x y z scalar) */
    clvr_u32 num_vertices;
    clvr_u64 first_index;     /* into idx16[] or idx32[]; element e's indices start at
                                 first_index + (e - first_element) * vertex_count(type),
                                 each relative to first_vertex */
    clvr_u32 first_leaf;      /* its leaf clusters: first_leaf .. first_leaf + num_leaves - 1 */
    clvr_u32 num_leaves;
    clvr_u32 bvh_root;        /* root of its bottom-level tree in the BLAS node array (bvh/) */
    clvr_u32 pad0;
} clvr_instance;
CLVR_STATIC_ASSERT(sizeof(clvr_instance) == 80, "clvr_instance layout");

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

/* ---------------------------------------------------------------- bvh
 * (owned by bvh/: node layout, sentinels) */

/* ---------------------------------------------------------------- render
 * (owned by the renderer: camera, transfer function, light, frame params) */

/* ---------------------------------------------------------------- frame
 * (owned by the renderer: host/render.c, kernels/render.cl) */

/* Methods, the values of clvr_frame.method (same order as host/cli.h). */
#define CLVR_RENDER_MARCH 0u
#define CLVR_RENDER_TRACK 1u
#define CLVR_RENDER_BINS 2u
#define CLVR_RENDER_DDA 3u
/* Largest --bins (the paper's 32 ray payload registers). */
#define CLVR_RENDER_MAX_BINS 32u

/* Everything one frame of the render kernel needs besides the buffers.
 * Vectors are float[4] with w unused, loaded with vload3. 144 bytes. */
typedef struct clvr_frame {
    float vol_lo[4];          /* bounds of the mesh */
    float vol_hi[4];
    float light_dir[4];       /* unit vector toward the directional light */
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
} clvr_frame;
CLVR_STATIC_ASSERT(sizeof(clvr_frame) == 144, "clvr_frame layout");

/* [frame: types] */

#endif /* CLVR_SHARED_H */
