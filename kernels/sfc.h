/* sfc.h: space-filling-curve keys of quantized 3D points, compiled twice
 * (host reference/tests and kernels) so both sides produce the very same
 * bits.
 *
 * Hilbert: the non-recursive Cartesian-to-Hilbert transform of Butz (1971),
 * in the simplified form of Moore and of Skilling ("Programming the Hilbert
 * curve", AIP Conf. Proc. 707, 2004): an "inverse undo" sweep from the top
 * bit down, a Gray encode, then the bits of the three transposed words are
 * interleaved (x highest) into one key of 3 * bits bits. With bits == 16
 * this is the paper's 48-bit key (section 3.2.1). The curve starts at the
 * origin, so keys [0, 8^k) cover exactly the cube [0, 2^k)^3, and
 * consecutive keys are face-adjacent cells.
 *
 * Morton: the same quantized coordinates with their bits interleaved, kept
 * for comparison (paper Fig. 4). */
#ifndef CLVR_SFC_H
#define CLVR_SFC_H

#include "clvr_shared.h"

/* Spreads the low 16 bits of v so that bit i moves to bit 3i. */
CLVR_FORCE_INLINE clvr_u64 clvr_sfc_spread3(clvr_u32 v)
{
    clvr_u64 x = v & 0xffffu;
    x = (x | (x << 32)) & 0x1f00000000ffffull;
    x = (x | (x << 16)) & 0x1f0000ff0000ffull;
    x = (x | (x << 8)) & 0x100f00f00f00f00full;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
    x = (x | (x << 2)) & 0x1249249249249249ull;
    return x;
}

/* Inverse of clvr_sfc_spread3. */
CLVR_INLINE clvr_u32 clvr_sfc_compact3(clvr_u64 x)
{
    x &= 0x1249249249249249ull;
    x = (x | (x >> 2)) & 0x10c30c30c30c30c3ull;
    x = (x | (x >> 4)) & 0x100f00f00f00f00full;
    x = (x | (x >> 8)) & 0x1f0000ff0000ffull;
    x = (x | (x >> 16)) & 0x1f00000000ffffull;
    x = (x | (x >> 32)) & 0xffffull;
    return (clvr_u32)x;
}

/* Hilbert key of (x, y, z), each < 2^bits, 1 <= bits <= 16; the key has
 * 3 * bits significant bits. */
CLVR_INLINE clvr_u64 clvr_hilbert3_bits(clvr_u32 x, clvr_u32 y, clvr_u32 z, clvr_u32 bits)
{
    clvr_u32 X0 = x, X1 = y, X2 = z, t;
    const clvr_u32 M = 1u << (bits - 1u);
    /* Inverse undo: for each bit from the top, either invert the lower bits
     * of X0 or exchange them with the axis being looked at. */
    for (clvr_u32 Q = M; Q > 1u; Q >>= 1) {
        const clvr_u32 P = Q - 1u;
        if (X0 & Q) X0 ^= P;
        /* axis 0 against itself: an exchange is a no-op */
        if (X1 & Q) X0 ^= P;
        else { t = (X0 ^ X1) & P; X0 ^= t; X1 ^= t; }
        if (X2 & Q) X0 ^= P;
        else { t = (X0 ^ X2) & P; X0 ^= t; X2 ^= t; }
    }
    /* Gray encode. */
    X1 ^= X0;
    X2 ^= X1;
    t = 0;
    for (clvr_u32 Q = M; Q > 1u; Q >>= 1)
        if (X2 & Q) t ^= Q - 1u;
    X0 ^= t;
    X1 ^= t;
    X2 ^= t;
    /* The transposed form holds the key's bits round-robin: X0 carries the
     * most significant bit of every triple. */
    return (clvr_sfc_spread3(X0) << 2) | (clvr_sfc_spread3(X1) << 1) | clvr_sfc_spread3(X2);
}

/* Program-scope constant tables: __constant on the device, static const on
 * the host (a plain const would have external linkage in C). */
#ifdef __OPENCL_VERSION__
#define CLVR_SFC_TABLE __constant
#else
#define CLVR_SFC_TABLE static const
#endif
#include "sfc_tables.h"

/* Morton key of (x, y, z), each < 2^16: x's bits are the most significant of
 * each triple. Equal to spread3(x) << 2 | spread3(y) << 1 | spread3(z),
 * a byte at a time from clvr_sfc_spread3_table: 6 loads instead of 3 x 5
 * shift-mask steps, which were a fifth of the key kernel's instructions. */
CLVR_FORCE_INLINE clvr_u64 clvr_morton3(clvr_u32 x, clvr_u32 y, clvr_u32 z)
{
    const clvr_u32 lo = (clvr_sfc_spread3_table[x & 255u] << 2) | (clvr_sfc_spread3_table[y & 255u] << 1) |
                        clvr_sfc_spread3_table[z & 255u];
    const clvr_u32 hi = (clvr_sfc_spread3_table[(x >> 8) & 255u] << 2) |
                        (clvr_sfc_spread3_table[(y >> 8) & 255u] << 1) | clvr_sfc_spread3_table[(z >> 8) & 255u];
    return ((clvr_u64)hi << 24) | lo;
}

/* The paper's 48-bit Hilbert key (16 bits per axis) from the Morton code
 * m = clvr_morton3(x, y, z); equal to clvr_hilbert3_bits(x, y, z, 16). The
 * same curve as a Butz-Moore state machine (tools/gen_sfc_tables.py): the
 * top level from a 64-bit constant, then five steps of three levels each
 * through clvr_hilbert3_table3 (24 KB). The key kernels are bound by
 * instruction count, not latency (PoCL runs many work-items' chains side by
 * side): five 3-level steps replaced eight 2-level ones. */
CLVR_FORCE_INLINE clvr_u64 clvr_hilbert3_from_morton(clvr_u64 m)
{
    clvr_u32 e = (clvr_u32)(CLVR_HILBERT3_TOP >> (8u * (clvr_u32)((m >> 45) & 7u))) & 255u;
    clvr_u64 key = e & 7u;
    clvr_u32 state = (e >> 3) << 9; /* next state, times 512 */
    CLVR_UNROLL
    for (int shift = 36; shift >= 0; shift -= 9) {
        e = clvr_hilbert3_table3[state | (clvr_u32)((m >> shift) & 511u)];
        key = (key << 9) | (e & 511u);
        state = e & ~511u;
    }
    return key;
}

CLVR_INLINE clvr_u64 clvr_hilbert3(clvr_u32 x, clvr_u32 y, clvr_u32 z)
{
    return clvr_hilbert3_from_morton(clvr_morton3(x, y, z));
}

/* Inverse of clvr_hilbert3_bits (Skilling's TransposetoAxes): writes the
 * cell of key h into xyz[0..2]. Used by tests to check bijection and
 * adjacency. */
CLVR_INLINE void clvr_hilbert3_decode(clvr_u64 h, clvr_u32 bits, clvr_u32 *xyz)
{
    clvr_u32 X0 = clvr_sfc_compact3(h >> 2), X1 = clvr_sfc_compact3(h >> 1), X2 = clvr_sfc_compact3(h), t;
    const clvr_u32 N = 2u << (bits - 1u);
    /* Gray decode by H ^ (H/2). */
    t = X2 >> 1;
    X2 ^= X1;
    X1 ^= X0;
    X0 ^= t;
    /* Undo excess work. */
    for (clvr_u32 Q = 2u; Q != N; Q <<= 1) {
        const clvr_u32 P = Q - 1u;
        if (X2 & Q) X0 ^= P;
        else { t = (X0 ^ X2) & P; X0 ^= t; X2 ^= t; }
        if (X1 & Q) X0 ^= P;
        else { t = (X0 ^ X1) & P; X0 ^= t; X1 ^= t; }
        if (X0 & Q) X0 ^= P;
    }
    xyz[0] = X0;
    xyz[1] = X1;
    xyz[2] = X2;
}

#endif /* CLVR_SFC_H */
