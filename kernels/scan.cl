/* scan.cl: exclusive prefix sums of uint arrays and the flagged select
 * built on them (paper 3.3: "an inclusive prefix sum (minus one) over an
 * array of isUsed flags"). Three tiled phases for any length: per-tile
 * totals, a scan of the (few) totals, then each tile rescans its chunk from
 * its offset. Work-item t owns [t * chunk, min(n, (t + 1) * chunk)). */
#include "clvr_shared.h"

/* sums[t] = sum of in[] over tile t; flags != 0: count of nonzero in[]. */
__kernel void clvr_pp_scan_reduce(__global const uint *in, ulong n, ulong chunk, uint ntiles, int flags,
                                  __global uint *sums)
{
    uint t = (uint)get_global_id(0);
    if (t >= ntiles) return;
    ulong b = (ulong)t * chunk, e = min(n, b + chunk);
    uint s = 0;
    if (flags)
        for (ulong i = b; i < e; ++i) s += in[i] != 0u;
    else
        for (ulong i = b; i < e; ++i) s += in[i];
    sums[t] = s;
}

/* Exclusive scan of sums[0..ntiles-1] in place; sums[ntiles] = total. One
 * work-item: there are only a few tiles. */
__kernel void clvr_pp_scan_sums(__global uint *sums, uint ntiles)
{
    if (get_global_id(0) != 0) return;
    uint acc = 0;
    for (uint t = 0; t < ntiles; ++t) {
        uint v = sums[t];
        sums[t] = acc;
        acc += v;
    }
    sums[ntiles] = acc;
}

/* out[i] = sums[t] + in[b] + ... + in[i - 1]. in may equal out. */
__kernel void clvr_pp_scan_apply(__global const uint *in, __global uint *out, ulong n, ulong chunk, uint ntiles,
                                 __global const uint *sums)
{
    uint t = (uint)get_global_id(0);
    if (t >= ntiles) return;
    ulong b = (ulong)t * chunk, e = min(n, b + chunk);
    uint acc = sums[t];
    for (ulong i = b; i < e; ++i) {
        uint v = in[i];
        out[i] = acc;
        acc += v;
    }
}

/* Flagged select: out[k] = values[i] (or i when use_ids) for the k-th i
 * with flags[i] != 0, in order. sums come from scan_reduce(flags=1) and
 * scan_sums. */
__kernel void clvr_pp_select_scatter(__global const uint *flags, __global const uint *values, int use_ids, ulong n,
                                     ulong chunk, uint ntiles, __global const uint *sums, __global uint *out)
{
    uint t = (uint)get_global_id(0);
    if (t >= ntiles) return;
    ulong b = (ulong)t * chunk, e = min(n, b + chunk);
    uint k = sums[t];
    for (ulong i = b; i < e; ++i)
        if (flags[i] != 0u) out[k++] = use_ids ? (uint)i : values[i];
}
