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
 * scrambled Sobol' sequence over the frame index instead of the hash
 * chain: point n of the first five Sobol' dimensions (Joe and Kuo 2008
 * direction numbers), each Owen-scrambled by a hash of pixel, seed and
 * dimension (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4),
 * with the Laine-Karras permutation). Each frame alone is uniform (the
 * scramble is), so every frame stays an unbiased estimate. The frames of one
 * pixel are stratified: the first 2^k frames put exactly one value in each
 * of the 2^k equal intervals of every dimension, and the sub-pixel pair
 * (dimensions 0, 1) is a (0, k, 2)-net. Two frames of urm therefore sample
 * a pixel with two quadrature grids offset by half a step, one in each half
 * of the pixel. Measured at 256^2 (bench_render --converge, relative RMSE,
 * the issue-14 criterion), against the randomly shifted Kronecker (R_d)
 * sequence this replaced: post-tets no shadows 2 frames 2.23% -> 1.60%,
 * 4 frames 1.35% -> 0.81%; tets-1M no shadows 3 frames 2.38% -> 1.89%;
 * post-tets with shadows 4 frames 2.00% -> 1.55%. A digital shift (XOR)
 * instead of the Owen scramble gained about half as much.
 * Frames of one pixel are NOT independent: per-pixel variance estimates from
 * the running moments are not the variance of the mean (use the independent
 * sampler, or independent replicates with different seeds, for error bars). */
/* Dimensions: sub-pixel x and y, the camera ray's first free flight or
 * quadrature offset, the shadow ray's, and (urm) the pick of the shadow
 * ray's origin. */
#define CLVR_LD_DIMS 5u

#ifdef __OPENCL_VERSION__
#define CLVR_SOBOL_TABLE __constant
#else
#define CLVR_SOBOL_TABLE static const
#endif
/* Direction numbers of Sobol' dimensions 2 to 5 (the first is the bit
 * reversal of n): (s, a, m) = (1, 0, {1}), (2, 1, {1, 3}),
 * (3, 1, {1, 3, 1}), (3, 2, {1, 1, 1}); test_render recomputes them by the
 * recurrence. */
CLVR_SOBOL_TABLE clvr_u32 clvr_sobol_dirs[CLVR_LD_DIMS - 1u][32] = {
    {0x80000000u, 0xc0000000u, 0xa0000000u, 0xf0000000u, 0x88000000u, 0xcc000000u, 0xaa000000u, 0xff000000u,
     0x80800000u, 0xc0c00000u, 0xa0a00000u, 0xf0f00000u, 0x88880000u, 0xcccc0000u, 0xaaaa0000u, 0xffff0000u,
     0x80008000u, 0xc000c000u, 0xa000a000u, 0xf000f000u, 0x88008800u, 0xcc00cc00u, 0xaa00aa00u, 0xff00ff00u,
     0x80808080u, 0xc0c0c0c0u, 0xa0a0a0a0u, 0xf0f0f0f0u, 0x88888888u, 0xccccccccu, 0xaaaaaaaau, 0xffffffffu},
    {0x80000000u, 0xc0000000u, 0x60000000u, 0x90000000u, 0xe8000000u, 0x5c000000u, 0x8e000000u, 0xc5000000u,
     0x68800000u, 0x9cc00000u, 0xee600000u, 0x55900000u, 0x80680000u, 0xc09c0000u, 0x60ee0000u, 0x90550000u,
     0xe8808000u, 0x5cc0c000u, 0x8e606000u, 0xc5909000u, 0x6868e800u, 0x9c9c5c00u, 0xeeee8e00u, 0x5555c500u,
     0x8000e880u, 0xc0005cc0u, 0x60008e60u, 0x9000c590u, 0xe8006868u, 0x5c009c9cu, 0x8e00eeeeu, 0xc5005555u},
    {0x80000000u, 0xc0000000u, 0x20000000u, 0x50000000u, 0xf8000000u, 0x74000000u, 0xa2000000u, 0x93000000u,
     0xd8800000u, 0x25400000u, 0x59e00000u, 0xe6d00000u, 0x78080000u, 0xb40c0000u, 0x82020000u, 0xc3050000u,
     0x208f8000u, 0x51474000u, 0xfbea2000u, 0x75d93000u, 0xa0858800u, 0x914e5400u, 0xdbe79e00u, 0x25db6d00u,
     0x58800080u, 0xe54000c0u, 0x79e00020u, 0xb6d00050u, 0x800800f8u, 0xc00c0074u, 0x200200a2u, 0x50050093u},
    {0x80000000u, 0x40000000u, 0x20000000u, 0xb0000000u, 0xf8000000u, 0xdc000000u, 0x7a000000u, 0x9d000000u,
     0x5a800000u, 0x2fc00000u, 0xa1600000u, 0xf0b00000u, 0xda880000u, 0x6fc40000u, 0x81620000u, 0x40bb0000u,
     0x22878000u, 0xb3c9c000u, 0xfb65a000u, 0xddb2d000u, 0x78022800u, 0x9c0b3c00u, 0x5a0fb600u, 0x2d0ddb00u,
     0xa2878080u, 0xf3c9c040u, 0xdb65a020u, 0x6db2d0b0u, 0x800228f8u, 0x400b3cdcu, 0x200fb67au, 0xb00ddb9du}};

CLVR_INLINE clvr_u32 clvr_reverse_bits(clvr_u32 n)
{
    n = ((n >> 1) & 0x55555555u) | ((n & 0x55555555u) << 1);
    n = ((n >> 2) & 0x33333333u) | ((n & 0x33333333u) << 2);
    n = ((n >> 4) & 0x0f0f0f0fu) | ((n & 0x0f0f0f0fu) << 4);
    n = ((n >> 8) & 0x00ff00ffu) | ((n & 0x00ff00ffu) << 8);
    return (n >> 16) | (n << 16);
}

/* Point n of Sobol' dimension dim (0 .. CLVR_LD_DIMS - 1) as the 32 bits of
 * a fraction: the XOR of the direction numbers of n's set bits. */
CLVR_INLINE clvr_u32 clvr_sobol_bits(clvr_u32 n, clvr_u32 dim)
{
    if (dim == 0u) return clvr_reverse_bits(n);
    clvr_u32 x = 0u;
    for (clvr_u32 k = 0u; n; ++k, n >>= 1)
        if (n & 1u) x ^= clvr_sobol_dirs[dim - 1u][k];
    return x;
}

/* Nested uniform (Owen) scramble of the fraction x keyed by seed: the
 * Laine-Karras permutation, which flips each bit by a hash of the bits
 * above it, applied to the reversed bits (Burley 2020). */
CLVR_INLINE clvr_u32 clvr_owen_scramble(clvr_u32 x, clvr_u32 seed)
{
    x = clvr_reverse_bits(x);
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return clvr_reverse_bits(x);
}

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

/* The CLVR_LD_DIMS uniforms of (pixel, frame) for the seed. The scramble
 * seeds hash pixel and seed only (they must stay fixed across frames), with
 * a constant that keeps them unrelated to clvr_rng_make's keys. */
CLVR_INLINE void clvr_ld_sample(clvr_u32 pixel, clvr_u32 frame, clvr_u32 seed_lo, clvr_u32 seed_hi, float *u)
{
    clvr_u32 v[4] = {pixel, seed_lo, seed_hi, 0x5bd1e995u};
    clvr_pcg4d(v);
    const clvr_u32 seed[5] = {v[0], v[1], v[2], v[3], clvr_pcg_hash(v[0] ^ v[3])};
    for (clvr_u32 k = 0; k < CLVR_LD_DIMS; ++k)
        u[k] = (float)(clvr_owen_scramble(clvr_sobol_bits(frame, k), seed[k]) >> 8) * (1.0f / 16777216.0f);
}

/* The camera ray's position in its pixel, [0, 1)^2: dimensions 0 and 1 of
 * ld, or the next two draws of rng when ld is NULL; the centre for the point
 * filter (the draws are made all the same, so that the other dimensions
 * keep their streams). The render kernel traces through it; in MPI mode
 * rank 0 draws it again on the host for the image's control variate
 * (kernels/pixel_cv.h), so both must come from here. */
CLVR_INLINE void clvr_pixel_jitter(const float *ld, clvr_rng *rng, clvr_u32 pixel_filter, float *jx, float *jy)
{
    *jx = ld ? ld[0] : clvr_rng_next(rng);
    *jy = ld ? ld[1] : clvr_rng_next(rng);
    if (pixel_filter == CLVR_PIXEL_POINT) *jx = *jy = 0.5f;
}

#endif
