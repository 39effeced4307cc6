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

#endif
