/* rng.h: counter-based random numbers keyed by (pixel, frame, seed), so an
 * image is reproducible on any device and independent of scheduling.
 * The stream state is a PCG-style hash chain: each draw hashes the key with a
 * counter (Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 2020:
 * pcg3d / pcg hash). Shared by host tests and kernels. */
#ifndef CLVR_RNG_H
#define CLVR_RNG_H

#include "clvr_shared.h"

typedef struct clvr_rng {
    clvr_u32 key;     /* hash of pixel, frame and seed */
    clvr_u32 counter; /* draws so far */
} clvr_rng;

CLVR_INLINE clvr_u32 clvr_pcg_hash(clvr_u32 v)
{
    clvr_u32 state = v * 747796405u + 2891336453u;
    clvr_u32 word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

CLVR_INLINE clvr_rng clvr_rng_make(clvr_u32 pixel, clvr_u32 frame, clvr_u32 seed_lo, clvr_u32 seed_hi)
{
    clvr_rng r;
    r.key = clvr_pcg_hash(pixel ^ clvr_pcg_hash(frame ^ clvr_pcg_hash(seed_lo ^ clvr_pcg_hash(seed_hi))));
    r.counter = 0u;
    return r;
}

/* Uniform in [0, 1): 24 random bits, so 1.0f is never returned. */
CLVR_INLINE float clvr_rng_next(clvr_rng *r)
{
    clvr_u32 v = clvr_pcg_hash(r->key ^ clvr_pcg_hash(r->counter++));
    return (float)(v >> 8) * (1.0f / 16777216.0f);
}

/* ------------------------------------------------------------ low discrepancy
 * The first CLVR_LD_DIMS uniforms of a pixel's frame can come from a
 * randomly shifted Kronecker sequence over the frame index instead (the R_d
 * sequence of Roberts 2018: alpha_k = phi_4^-k mod 1 with phi_4^5 = phi_4 + 1
 * for the first four; the fifth, added later, is 1/phi (golden ratio), which
 * kept every 2D projection as even as R4's own in test_render, where R5's
 * constants did not;
 * Cranley & Patterson 1976 rotation by a hash of pixel and seed, no frame):
 *   u_k(n) = frac(shift_k(pixel, seed) + n * alpha_k),
 * in 32-bit fixed point so that n * alpha wraps exactly for any n. Each
 * frame alone is uniform (the shift is), so every frame stays an unbiased
 * estimate, while the frames of one pixel fill [0,1)^5 evenly and their
 * average converges faster than independent frames. Frames of one pixel are
 * therefore NOT independent: per-pixel variance estimates from the running
 * moments are not the variance of the mean (use the independent sampler, or
 * independent replicates with different seeds, for error bars). */
/* Dimensions: sub-pixel x and y, the camera ray's first free flight or
 * quadrature offset, the shadow ray's, and (urm) the pick of the shadow
 * ray's origin. */
#define CLVR_LD_DIMS 5u

/* pcg4d (Jarzynski & Olano 2020): four 32-bit inputs to four well-mixed
 * outputs in a few multiplies, cheaper than four chained pcg hashes. */
CLVR_INLINE void clvr_pcg4d(clvr_u32 v[4])
{
    for (int k = 0; k < 4; ++k) v[k] = v[k] * 1664525u + 1013904223u;
    v[0] += v[1] * v[3];
    v[1] += v[2] * v[0];
    v[2] += v[0] * v[1];
    v[3] += v[1] * v[2];
    for (int k = 0; k < 4; ++k) v[k] ^= v[k] >> 16u;
    v[0] += v[1] * v[3];
    v[1] += v[2] * v[0];
    v[2] += v[0] * v[1];
    v[3] += v[1] * v[2];
}

/* The CLVR_LD_DIMS uniforms of (pixel, frame) for the seed. The shifts hash
 * pixel and seed only (they must stay fixed across frames), with a constant
 * that keeps them unrelated to clvr_rng_make's keys. */
CLVR_INLINE void clvr_ld_sample(clvr_u32 pixel, clvr_u32 frame, clvr_u32 seed_lo, clvr_u32 seed_hi, float *u)
{
    const clvr_u32 alpha[5] = {3679390609u, 3152041523u, 2700274805u, 2313257605u, 2654435769u};
    clvr_u32 v[4] = {pixel, seed_lo, seed_hi, 0x5bd1e995u};
    clvr_pcg4d(v);
    const clvr_u32 shift[5] = {v[0], v[1], v[2], v[3], clvr_pcg_hash(v[0] ^ v[3])};
    for (int k = 0; k < 5; ++k) u[k] = (float)((shift[k] + frame * alpha[k]) >> 8) * (1.0f / 16777216.0f);
}

#endif
