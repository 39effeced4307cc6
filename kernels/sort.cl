/* sort.cl: stable LSD radix sort of (ulong key, uint value) pairs, 8-bit
 * digits (the paper uses CUB's device radix sort; this is the same LSD
 * scheme shaped for CPU devices). Each pass: per-tile digit histograms,
 * an exclusive scan of the digit-major histogram table (scan.cl), then a
 * scatter in which every tile walks its chunk in order from its own
 * offsets, which keeps the sort stable. Tiles are long contiguous chunks
 * (work-item t owns [t * chunk, min(n, (t + 1) * chunk))), so a CPU device
 * streams through memory with 256 private counters per tile.
 * Passes whose digit is equal for all keys are skipped by the host, which
 * learns them from the AND and OR of all keys (clvr_pp_radix_andor).
 *
 * Large sorts on CPU devices go hybrid (host/pipeline/preprocess.c decides): one
 * such pass on the top varying 8 bits splits the keys into 256 buckets in
 * memory order, then clvr_pp_radix_buckets finishes each bucket with the
 * remaining LSD passes. A bucket of n/256 keys fits a core's L2 cache, so
 * those passes run from cache instead of streaming the whole array through
 * memory each time. */
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

/* Stable scatter of tile t from the scanned histogram table. iota != 0:
 * the values are the indices 0..n-1, made here instead of read (the sort's
 * first pass over element ids, which nobody had to write). */
__kernel void clvr_pp_radix_scatter(__global const ulong *keys, __global const uint *vals, ulong n, ulong chunk,
                                    uint ntiles, uint shift, __global const uint *offs, __global ulong *keys_out,
                                    __global uint *vals_out, uint iota)
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
        vals_out[p] = iota ? (uint)i : vals[i];
    }
}

/* vals[i] = i: the values of a sort that has no pass to make them. */
__kernel void clvr_pp_iota(__global uint *vals, uint n)
{
    uint i = (uint)get_global_id(0);
    if (i < n) vals[i] = i;
}

/* Work-item d finishes bucket d of the hybrid sort: after the stable top-digit
 * scatter, bucket d is [offs[d * ntiles], offs[(d + 1) * ntiles]) (the end of
 * the last is n), all its keys share the top digit, in input order. Stable
 * LSD passes on the digits whose bit is set in `digits` (bit j: shift 8j)
 * ping-pong over the bucket's own range between (ka, va) and (kb, vb), so the
 * result is in (kb, vb) when the number of passes is odd, else in (ka, va),
 * for every bucket alike. */
__kernel void clvr_pp_radix_buckets(__global ulong *ka, __global uint *va, __global ulong *kb, __global uint *vb,
                                    __global const uint *offs, uint ntiles, ulong n, uint digits)
{
    uint d = (uint)get_global_id(0);
    if (d >= CLVR_PP_RADIX) return;
    ulong b = offs[d * ntiles], e = d + 1u < CLVR_PP_RADIX ? (ulong)offs[(d + 1u) * ntiles] : n;
    uint o[CLVR_PP_RADIX], o2[CLVR_PP_RADIX];
    for (uint j = 0; j < 64u / CLVR_PP_RADIX_BITS; ++j) {
        if (((digits >> j) & 1u) == 0u) continue;
        uint shift = j * CLVR_PP_RADIX_BITS;
        /* Two counter sets, for even and odd keys: neighbouring keys often
         * share a digit, and one set would chain their increments through
         * the same counter's store and reload (10M keys: -7% sort time). */
        for (uint x = 0; x < CLVR_PP_RADIX; ++x) o[x] = o2[x] = 0;
        ulong i = b;
        for (; i + 1u < e; i += 2u) {
            ++o[(uint)(ka[i] >> shift) & (CLVR_PP_RADIX - 1u)];
            ++o2[(uint)(ka[i + 1u] >> shift) & (CLVR_PP_RADIX - 1u)];
        }
        if (i < e) ++o[(uint)(ka[i] >> shift) & (CLVR_PP_RADIX - 1u)];
        uint acc = 0;
        for (uint x = 0; x < CLVR_PP_RADIX; ++x) {
            uint c = o[x] + o2[x];
            o[x] = acc;
            acc += c;
        }
        for (ulong i = b; i < e; ++i) {
            ulong k = ka[i];
            ulong p = b + o[(uint)(k >> shift) & (CLVR_PP_RADIX - 1u)]++;
            kb[p] = k;
            vb[p] = va[i];
        }
        __global ulong *tk = ka;
        ka = kb;
        kb = tk;
        __global uint *tv = va;
        va = vb;
        vb = tv;
    }
}
