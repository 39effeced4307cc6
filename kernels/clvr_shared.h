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

/* ---------------------------------------------------------------- preprocess
 * (owned by the preprocessing module: kernels/bounds, sfc, sort, scan,
 * cluster, reindex) */

/* ---------------------------------------------------------------- bvh
 * (owned by bvh/: node layout, sentinels) */

/* ---------------------------------------------------------------- render
 * (owned by the renderer: camera, transfer function, light, frame params) */

#endif /* CLVR_SHARED_H */
