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
 * (3, 1, {1, 3, 1}), (3, 2, {1, 1, 1}), each bit-reversed: the scramble
 * below works on reversed fractions, so the XOR of reversed direction
 * numbers is its input as is (test_render recomputes them by the
 * recurrence). */
CLVR_SOBOL_TABLE clvr_u32 clvr_sobol_dirs_rev[CLVR_LD_DIMS - 1u][32] = {
    {0x00000001u, 0x00000003u, 0x00000005u, 0x0000000fu, 0x00000011u, 0x00000033u, 0x00000055u, 0x000000ffu,
     0x00000101u, 0x00000303u, 0x00000505u, 0x00000f0fu, 0x00001111u, 0x00003333u, 0x00005555u, 0x0000ffffu,
     0x00010001u, 0x00030003u, 0x00050005u, 0x000f000fu, 0x00110011u, 0x00330033u, 0x00550055u, 0x00ff00ffu,
     0x01010101u, 0x03030303u, 0x05050505u, 0x0f0f0f0fu, 0x11111111u, 0x33333333u, 0x55555555u, 0xffffffffu},
    {0x00000001u, 0x00000003u, 0x00000006u, 0x00000009u, 0x00000017u, 0x0000003au, 0x00000071u, 0x000000a3u,
     0x00000116u, 0x00000339u, 0x00000677u, 0x000009aau, 0x00001601u, 0x00003903u, 0x00007706u, 0x0000aa09u,
     0x00010117u, 0x0003033au, 0x00060671u, 0x000909a3u, 0x00171616u, 0x003a3939u, 0x00717777u, 0x00a3aaaau,
     0x01170001u, 0x033a0003u, 0x06710006u, 0x09a30009u, 0x16160017u, 0x3939003au, 0x77770071u, 0xaaaa00a3u},
    {0x00000001u, 0x00000003u, 0x00000004u, 0x0000000au, 0x0000001fu, 0x0000002eu, 0x00000045u, 0x000000c9u,
     0x0000011bu, 0x000002a4u, 0x0000079au, 0x00000b67u, 0x0000101eu, 0x0000302du, 0x00004041u, 0x0000a0c3u,
     0x0001f104u, 0x0002e28au, 0x000457dfu, 0x000c9baeu, 0x0011a105u, 0x002a7289u, 0x0079e7dbu, 0x00b6dba4u,
     0x0100011au, 0x030002a7u, 0x0400079eu, 0x0a000b6du, 0x1f001001u, 0x2e003003u, 0x45004004u, 0xc900a00au},
    {0x00000001u, 0x00000002u, 0x00000004u, 0x0000000du, 0x0000001fu, 0x0000003bu, 0x0000005eu, 0x000000b9u,
     0x0000015au, 0x000003f4u, 0x00000685u, 0x00000d0fu, 0x0000115bu, 0x000023f6u, 0x00004681u, 0x0000dd02u,
     0x0001e144u, 0x000393cdu, 0x0005a6dfu, 0x000b4dbbu, 0x0014401eu, 0x003cd039u, 0x006df05au, 0x00dbb0b4u,
     0x0101e145u, 0x020393cfu, 0x0405a6dbu, 0x0d0b4db6u, 0x1f144001u, 0x3b3cd002u, 0x5e6df004u, 0xb9dbb00du}};

CLVR_INLINE clvr_u32 clvr_reverse_bits(clvr_u32 n)
{
    n = ((n >> 1) & 0x55555555u) | ((n & 0x55555555u) << 1);
    n = ((n >> 2) & 0x33333333u) | ((n & 0x33333333u) << 2);
    n = ((n >> 4) & 0x0f0f0f0fu) | ((n & 0x0f0f0f0fu) << 4);
    n = ((n >> 8) & 0x00ff00ffu) | ((n & 0x00ff00ffu) << 8);
    return (n >> 16) | (n << 16);
}

/* The Laine-Karras permutation of a bit-reversed fraction x keyed by seed
 * (it flips each bit by a hash of the bits below it, the fraction's higher
 * ones), returned in plain order: a nested uniform (Owen) scramble of the
 * fraction (Burley 2020). */
CLVR_INLINE clvr_u32 clvr_owen_scramble_rev(clvr_u32 x, clvr_u32 seed)
{
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
    /* Point `frame` of each dimension, bit-reversed (dimension 0, the bit
     * reversal of frame, is frame itself): the XOR of the reversed direction
     * numbers of frame's set bits, all four dimensions in one pass: half
     * the bit reversals of scrambling plain fractions (the function went
     * from 7.1% to 5.0% of the notch's walk frames on PoCL, the same bits
     * out; test_render compares it with the plain form). */
    clvr_u32 x[CLVR_LD_DIMS] = {frame, 0u, 0u, 0u, 0u};
    for (clvr_u32 k = 0u, n = frame; n; ++k, n >>= 1)
        if (n & 1u)
            for (clvr_u32 d = 1u; d < CLVR_LD_DIMS; ++d) x[d] ^= clvr_sobol_dirs_rev[d - 1u][k];
    for (clvr_u32 k = 0; k < CLVR_LD_DIMS; ++k)
        u[k] = (float)(clvr_owen_scramble_rev(x[k], seed[k]) >> 8) * (1.0f / 16777216.0f);
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
