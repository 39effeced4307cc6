/* sort.cl: stable LSD radix sort of (ulong key, uint value) pairs, 8-bit
 * digits (the paper uses CUB's device radix sort; this is the same LSD
 * scheme shaped for CPU devices). Each pass: per-tile digit histograms,
 * an exclusive scan of the digit-major histogram table (scan.cl), then a
 * scatter in which every tile walks its chunk in order from its own
 * offsets, which keeps the sort stable. Tiles are long contiguous chunks
 * (work-item t owns [t * chunk, min(n, (t + 1) * chunk))), so a CPU device
 * streams through memory with 256 private counters per tile.
 * Passes whose digit is equal for all keys are skipped by the host, which
 * learns them from the AND and OR of all keys (clvr_pp_radix_andor). */
#include "clvr_shared.h"

/* Per-tile AND and OR of the keys: out[2t] = AND, out[2t + 1] = OR. */
__kernel void clvr_pp_radix_andor(__global const ulong *keys, ulong n, ulong chunk, uint ntiles, __global ulong *out)
{
    uint t = (uint)get_global_id(0);
    if (t >= ntiles) return;
    ulong b = (ulong)t * chunk, e = min(n, b + chunk);
    ulong a = ~0ul, o = 0ul;
    for (ulong i = b; i < e; ++i) {
        ulong k = keys[i];
        a &= k;
        o |= k;
    }
    out[2 * t] = a;
    out[2 * t + 1] = o;
}

/* hist[d * ntiles + t] = number of keys of tile t whose digit at `shift` is d
 * (digit-major, so an exclusive scan of hist gives every (digit, tile) its
 * first output position). */
__kernel void clvr_pp_radix_hist(__global const ulong *keys, ulong n, ulong chunk, uint ntiles, uint shift,
                                 __global uint *hist)
{
    uint t = (uint)get_global_id(0);
    if (t >= ntiles) return;
    uint h[CLVR_PP_RADIX];
    for (uint d = 0; d < CLVR_PP_RADIX; ++d) h[d] = 0;
    ulong b = (ulong)t * chunk, e = min(n, b + chunk);
    for (ulong i = b; i < e; ++i) ++h[(uint)(keys[i] >> shift) & (CLVR_PP_RADIX - 1u)];
    for (uint d = 0; d < CLVR_PP_RADIX; ++d) hist[d * ntiles + t] = h[d];
}

/* Stable scatter of tile t from the scanned histogram table. */
__kernel void clvr_pp_radix_scatter(__global const ulong *keys, __global const uint *vals, ulong n, ulong chunk,
                                    uint ntiles, uint shift, __global const uint *offs, __global ulong *keys_out,
                                    __global uint *vals_out)
{
    uint t = (uint)get_global_id(0);
    if (t >= ntiles) return;
    uint o[CLVR_PP_RADIX];
    for (uint d = 0; d < CLVR_PP_RADIX; ++d) o[d] = offs[d * ntiles + t];
    ulong b = (ulong)t * chunk, e = min(n, b + chunk);
    for (ulong i = b; i < e; ++i) {
        ulong k = keys[i];
        uint p = o[(uint)(k >> shift) & (CLVR_PP_RADIX - 1u)]++;
        keys_out[p] = k;
        vals_out[p] = vals[i];
    }
}
