/* Proves the optional denoiser (kernels/denoise.h, clvr --denoise):
 *  - the device passes equal the plain-C reference (clvr_denoise_ref) on
 *    random images and guides of sizes 0x0, 1x1, 1x7, 7x1, 37x53 (primes),
 *    131x67 and 256x3 (not multiples of the 8x8 work-group), with the
 *    default parameters, with one pass, and with the noise taken from given
 *    variances (from 2 frames on) instead of the Laplacians;
 *  - pixels whose guide depth is < 0 (background) come out bit for bit;
 *  - a constant image with constant guides stays constant;
 *  - a noisy two-region image whose albedo steps between the regions keeps
 *    the step (each side's mean within 1%) while its noise falls;
 *  - through the public API (clvr_tracer_read_denoised): on a smooth medium
 *    with shadows, 1 denoised frame is closer to 64 frames than the raw
 *    frame is, by at least 15% (a filter that does nothing fails), and 64
 *    and 16 frames denoised stay close to themselves (the bias, bounded by
 *    0.8 of their own noise, e1 / sqrt(frames)); on the built-in
 *    scene (structure at the pixel scale) it still gains and its background
 *    pixels come out as they went in; the calls' misuse is refused with the
 *    call to make. */
#include "clvr.h"
#include "denoiser.h"
#include "test_util.h"

static float frand(uint64_t *st) { return (float)(tu_rand(st) >> 40) * (1.0f / 16777216.0f); }

/* Random rgba in [0, 2) and guides: albedo in [0, 1), depth in [1, 3) or -1
 * (background) for about 15% of the pixels. */
static void random_inputs(uint32_t w, uint32_t h, uint64_t seed, float *rgba, float *guide)
{
    uint64_t st = seed;
    for (size_t i = 0; i < (size_t)w * h; ++i) {
        for (int k = 0; k < 4; ++k) rgba[4 * i + (size_t)k] = 2.0f * frand(&st);
        for (int k = 0; k < 3; ++k) guide[4 * i + (size_t)k] = frand(&st);
        guide[4 * i + 3] = frand(&st) < 0.15f ? -1.0f : 1.0f + 2.0f * frand(&st);
    }
}

static void test_device_vs_reference(clvr_cl *cl, clvr_denoiser *dn)
{
    static const uint32_t sizes[][2] = {{0, 0}, {1, 1}, {1, 7}, {7, 1}, {37, 53}, {131, 67}, {256, 3}};
    clvr_error err = {0};
    for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; ++si) {
        const uint32_t w = sizes[si][0], h = sizes[si][1];
        const size_t n = (size_t)w * h * 4 + 4;
        float *in = malloc(n * sizeof(float)), *g = malloc(n * sizeof(float));
        float *dev = malloc(n * sizeof(float)), *ref = malloc(n * sizeof(float));
        float *var = malloc(((size_t)w * h + 1) * sizeof(float));
        random_inputs(w, h, 1000 + si, in, g);
        {
            uint64_t st = 77 + si;
            for (size_t p = 0; p < (size_t)w * h; ++p) var[p] = 0.05f * frand(&st);
        }
        /* The defaults, one pass, and the noise from given variances. */
        for (int variant = 0; variant < 3; ++variant) {
            clvr_dn_params prm = clvr_dn_params_default();
            if (variant == 1) prm.passes = 1;
            const float *v = variant == 2 ? var : NULL;
            memset(dev, 0, n * sizeof(float));
            memset(ref, 0, n * sizeof(float));
            TU_CHECK_STATUS(clvr_denoiser_run(dn, w, h, in, g, v, prm, dev, &err), CLVR_OK, &err);
            TU_CHECK_STATUS(clvr_denoise_ref(w, h, in, g, v, prm, ref, &err), CLVR_OK, &err);
            double worst = 0.0;
            uint64_t bg_changed = 0, changed = 0;
            for (size_t p = 0; p < (size_t)w * h; ++p)
                for (int k = 0; k < 4; ++k) {
                    const size_t i = 4 * p + (size_t)k;
                    const double d = fabs((double)dev[i] - (double)ref[i]) / (1.0 + fabs((double)ref[i]));
                    if (d > worst) worst = d;
                    if (g[4 * p + 3] < 0.0f) bg_changed += memcmp(&dev[i], &in[i], sizeof(float)) != 0;
                    else changed += dev[i] != in[i];
                }
            if (worst > 1e-4)
                fprintf(stderr, "%ux%u passes %u: device and reference differ by %g\n", w, h, prm.passes, worst);
            TU_CHECK(worst <= 1e-4);
            TU_CHECK_EQ_U64(bg_changed, 0);
            /* Not a copy: with more than one medium pixel, the filter moves values. */
            if ((size_t)w * h >= 7) TU_CHECK(changed > 0);
        }
        free(in);
        free(g);
        free(dev);
        free(ref);
        free(var);
    }
    (void)cl;
}

static void test_constant_and_step(clvr_denoiser *dn)
{
    clvr_error err = {0};
    const uint32_t w = 64, h = 48;
    const size_t npix = (size_t)w * h;
    float *in = malloc(npix * 4 * sizeof(float)), *g = malloc(npix * 4 * sizeof(float));
    float *out = malloc(npix * 4 * sizeof(float));
    /* Constant: every weight is the centre's, the mean of equal values. */
    for (size_t i = 0; i < npix; ++i) {
        const float c[4] = {0.3f, 0.2f, 0.1f, 0.7f}, a[4] = {0.5f, 0.4f, 0.3f, 2.0f};
        memcpy(in + 4 * i, c, sizeof c);
        memcpy(g + 4 * i, a, sizeof a);
    }
    TU_CHECK_STATUS(clvr_denoiser_run(dn, w, h, in, g, NULL, clvr_dn_params_default(), out, &err), CLVR_OK, &err);
    double worst = 0.0;
    for (size_t i = 0; i < npix * 4; ++i) worst = fmax(worst, fabs((double)out[i] - (double)in[i]));
    TU_CHECK(worst < 1e-6);
    /* Two regions: left albedo 0.2, colour 0.2; right albedo 0.8, colour 0.8;
     * both with 10% noise in the colour, the depth constant. */
    uint64_t st = 99;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const size_t p = (size_t)y * w + x;
            const float base = x < w / 2 ? 0.2f : 0.8f;
            for (int k = 0; k < 3; ++k) {
                in[4 * p + (size_t)k] = base * (1.0f + 0.2f * (frand(&st) - 0.5f) * 1.7320508f);
                g[4 * p + (size_t)k] = base;
            }
            in[4 * p + 3] = 1.0f;
            g[4 * p + 3] = 2.0f;
        }
    TU_CHECK_STATUS(clvr_denoiser_run(dn, w, h, in, g, NULL, clvr_dn_params_default(), out, &err), CLVR_OK, &err);
    double mean_in[2] = {0, 0}, mean_out[2] = {0, 0}, var_in[2] = {0, 0}, var_out[2] = {0, 0}, cnt[2] = {0, 0};
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const size_t p = (size_t)y * w + x;
            const int side = x >= w / 2;
            const double base = side ? 0.8 : 0.2;
            mean_in[side] += in[4 * p];
            mean_out[side] += out[4 * p];
            var_in[side] += (in[4 * p] - base) * (in[4 * p] - base);
            var_out[side] += (out[4 * p] - base) * (out[4 * p] - base);
            cnt[side] += 1.0;
        }
    for (int side = 0; side < 2; ++side) {
        const double base = side ? 0.8 : 0.2;
        printf("step side %d: mean %.4f -> %.4f (true %.1f), rms error %.4f -> %.4f\n", side, mean_in[side] / cnt[side],
               mean_out[side] / cnt[side], base, sqrt(var_in[side] / cnt[side]), sqrt(var_out[side] / cnt[side]));
        TU_CHECK(fabs(mean_out[side] / cnt[side] - base) < 0.01 * base);
        TU_CHECK(sqrt(var_out[side] / cnt[side]) < 0.5 * sqrt(var_in[side] / cnt[side]));
    }
    free(in);
    free(g);
    free(out);
}

/* Relative RMSE of a against ref over the pixels with mask set (rgb). */
static double rel_rmse(const float *a, const float *ref, const uint8_t *mask, size_t npix)
{
    double se = 0.0, sum = 0.0;
    size_t n = 0;
    for (size_t p = 0; p < npix; ++p) {
        if (!mask[p]) continue;
        for (int k = 0; k < 3; ++k) {
            const double d = (double)a[4 * p + (size_t)k] - (double)ref[4 * p + (size_t)k];
            se += d * d;
            sum += ref[4 * p + (size_t)k];
        }
        ++n;
    }
    return n && sum > 0 ? sqrt(se / (3.0 * (double)n)) / (sum / (3.0 * (double)n)) : 0.0;
}

/* How much the denoiser changes an image of `frames` frames (seed seed): rel
 * RMSE of the denoised image against the image itself, over mask. raw, dn:
 * npix rgba each (scratch). The "bias" checks below bound it by 0.8 e1 /
 * sqrt(frames), e1 the error of one frame: an image of N frames has about
 * e1 / sqrt(N) of noise (independent frames; less with ld), and a filter
 * that mostly removes noise changes the image by less than that, while a
 * bias that does not fall with N (a fixed noise scale: the Laplacians alone)
 * fails as N grows. */
static double denoise_change(clvr_tracer *tr, uint32_t frames, uint64_t seed, float *raw, float *dn,
                             const uint8_t *mask, size_t npix);

#define API_OK(expr)                                                                                   \
    do {                                                                                               \
        clvr_result r_ = (expr);                                                                       \
        if (r_ == CLVR_RESULT_OK) ++tu_pass_;                                                          \
        else { ++tu_fail_; fprintf(stderr, "%s:%d: FAILED: %s: %s\n", __FILE__, __LINE__, #expr, msg.text); } \
    } while (0)

static double denoise_change(clvr_tracer *tr, uint32_t frames, uint64_t seed, float *raw, float *dn,
                             const uint8_t *mask, size_t npix)
{
    clvr_message msg;
    API_OK(clvr_tracer_set_seed(tr, seed, &msg));
    API_OK(clvr_tracer_render(tr, frames, &msg));
    API_OK(clvr_tracer_read_image(tr, raw, npix * 4, &msg));
    API_OK(clvr_tracer_read_denoised(tr, dn, npix * 4, &msg));
    return rel_rmse(dn, raw, mask, npix);
}

/* A 6^3 lattice of hexes over the unit cube with the scalar x: a smooth
 * medium whose only noise is the estimator's. */
static clvr_dataset *smooth_cube(clvr_message *msg)
{
    enum { N = 6, P = N + 1 };
    static float xyz[3 * P * P * P], val[P * P * P];
    static uint32_t idx[8 * N * N * N];
    for (int z = 0; z < P; ++z)
        for (int y = 0; y < P; ++y)
            for (int x = 0; x < P; ++x) {
                const int i = (z * P + y) * P + x;
                xyz[3 * i] = (float)x / N;
                xyz[3 * i + 1] = (float)y / N;
                xyz[3 * i + 2] = (float)z / N;
                val[i] = (float)x / N;
            }
    for (int z = 0, c = 0; z < N; ++z)
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x, ++c) {
                const uint32_t b = (uint32_t)((z * P + y) * P + x), dy = P, dz = P * P;
                const uint32_t v[8] = {b, b + 1, b + dy + 1, b + dy, b + dz, b + dz + 1, b + dz + dy + 1, b + dz + dy};
                memcpy(idx + 8 * c, v, sizeof v);
            }
    clvr_dataset *ds = NULL;
    if (clvr_dataset_create(P * P * P, xyz, CLVR_COPY, &ds, msg) != CLVR_RESULT_OK) return NULL;
    if (clvr_dataset_add_cells(ds, "hexahedron", N * N * N, idx, CLVR_COPY, msg) != CLVR_RESULT_OK ||
        clvr_dataset_add_field(ds, "x", val, CLVR_COPY, msg) != CLVR_RESULT_OK) {
        clvr_dataset_destroy(ds);
        return NULL;
    }
    return ds;
}

/* On the smooth cube with shadows, one urm frame denoised is closer to 64
 * frames than the frame is, by 15% or more (a filter that does nothing
 * fails; measured 23%), and the 64 frames denoised stay within a tenth of
 * that frame's error of themselves (measured 0.05), 16 frames within 0.2
 * (0.8 / sqrt(16), denoise_change; measured 0.09). */
static void test_smooth(clvr_context *ctx)
{
    clvr_message msg;
    clvr_tracer *tr = NULL;
    clvr_dataset *ds = smooth_cube(&msg);
    const uint32_t w = 64, h = 64;
    const size_t npix = (size_t)w * h;
    float *ref = malloc(npix * 4 * sizeof(float)), *ref_dn = malloc(npix * 4 * sizeof(float));
    float *raw = malloc(npix * 4 * sizeof(float)), *dn = malloc(npix * 4 * sizeof(float));
    uint8_t *medium = calloc(npix, 1);
    TU_CHECK(ds != NULL);
    if (ds) API_OK(clvr_tracer_create(ctx, ds, NULL, w, h, &tr, &msg));
    if (!tr) goto done;
    /* The point pixel filter: no sub-pixel jitter, whose coverage noise at
     * the cube's silhouette no filter can remove; what is left is the
     * estimator's noise (shadow rays, quadrature). */
    API_OK(clvr_tracer_set_pixel_filter(tr, "point", &msg));
    API_OK(clvr_tracer_set_denoise(tr, 1, &msg));
    API_OK(clvr_tracer_set_seed(tr, 5, &msg));
    API_OK(clvr_tracer_render(tr, 64, &msg));
    API_OK(clvr_tracer_read_image(tr, ref, npix * 4, &msg));
    API_OK(clvr_tracer_read_denoised(tr, ref_dn, npix * 4, &msg));
    for (size_t p = 0; p < npix; ++p) medium[p] = ref[4 * p + 3] > 0.01f;
    API_OK(clvr_tracer_set_seed(tr, 11, &msg));
    API_OK(clvr_tracer_render(tr, 1, &msg));
    API_OK(clvr_tracer_read_image(tr, raw, npix * 4, &msg));
    API_OK(clvr_tracer_read_denoised(tr, dn, npix * 4, &msg));
    const double e_raw = rel_rmse(raw, ref, medium, npix), e_dn = rel_rmse(dn, ref, medium, npix);
    const double bias = rel_rmse(ref_dn, ref, medium, npix);
    printf("smooth cube %ux%u, 1 urm frame against 64: rel RMSE raw %.4f, denoised %.4f; bias %.4f\n", w, h, e_raw,
           e_dn, bias);
    TU_CHECK(e_dn < 0.85 * e_raw);
    TU_CHECK(bias < 0.1 * e_raw);
    const double bias16 = denoise_change(tr, 16, 7, raw, dn, medium, npix);
    printf("smooth cube: 16 frames denoised against themselves %.4f (bound %.4f)\n", bias16, 0.2 * e_raw);
    TU_CHECK(bias16 < 0.8 / sqrt(16.0) * e_raw);
done:
    clvr_tracer_destroy(tr);
    clvr_dataset_destroy(ds);
    free(ref);
    free(ref_dn);
    free(raw);
    free(dn);
    free(medium);
}

static void test_render(void)
{
    clvr_message msg;
    clvr_context *ctx = NULL;
    clvr_dataset *ds = NULL;
    clvr_tracer *tr = NULL;
    const uint32_t w = 96, h = 80;
    const size_t npix = (size_t)w * h;
    float *ref = malloc(npix * 4 * sizeof(float)), *ref_dn = malloc(npix * 4 * sizeof(float));
    float *raw = malloc(npix * 4 * sizeof(float)), *dn = malloc(npix * 4 * sizeof(float));
    uint8_t *medium = calloc(npix, 1);
    API_OK(clvr_context_create(tu_device_spec(), &ctx, &msg));
    API_OK(clvr_dataset_create_demo(&ds, &msg));
    if (ctx && ds) API_OK(clvr_tracer_create(ctx, ds, NULL, w, h, &tr, &msg));
    if (!tr) goto done;
    TU_CHECK(clvr_tracer_denoise(tr) == 0);
    /* Before the guides are asked for, no denoised image. */
    API_OK(clvr_tracer_render(tr, 1, &msg));
    TU_CHECK(clvr_tracer_read_denoised(tr, raw, npix * 4, &msg) == CLVR_RESULT_ERR_USAGE);
    TU_CHECK(strstr(msg.text, "clvr_tracer_set_denoise") != NULL);
    API_OK(clvr_tracer_set_denoise(tr, 1, &msg));
    TU_CHECK(clvr_tracer_denoise(tr) == 1);
    /* A change restarts the accumulation: nothing to read yet. */
    TU_CHECK(clvr_tracer_read_denoised(tr, raw, npix * 4, &msg) == CLVR_RESULT_ERR_USAGE);
    TU_CHECK(clvr_tracer_read_denoised(tr, raw, 3, &msg) == CLVR_RESULT_ERR_USAGE);
    /* Plain frames, one sample per pixel each: the bounds below were set
     * against them (adaptive sampling lowers the 1-frame error the bias is
     * compared with). */
    API_OK(clvr_tracer_set_adaptive(tr, 0.0f, &msg));
    /* The reference: 64 frames, seed 5. */
    API_OK(clvr_tracer_set_seed(tr, 5, &msg));
    API_OK(clvr_tracer_render(tr, 64, &msg));
    API_OK(clvr_tracer_read_image(tr, ref, npix * 4, &msg));
    API_OK(clvr_tracer_read_denoised(tr, ref_dn, npix * 4, &msg));
    /* Pixels the medium shows (opacity > 1%); the background ones must come
     * out of the denoiser as they went in. */
    uint64_t bg_changed = 0;
    size_t nmed = 0;
    for (size_t p = 0; p < npix; ++p) {
        medium[p] = ref[4 * p + 3] > 0.01f;
        nmed += medium[p];
        if (ref[4 * p + 3] == 0.0f)
            for (int k = 0; k < 4; ++k) bg_changed += ref_dn[4 * p + (size_t)k] != ref[4 * p + (size_t)k];
    }
    TU_CHECK(nmed > npix / 10);
    TU_CHECK_EQ_U64(bg_changed, 0);
    const double bias = rel_rmse(ref_dn, ref, medium, npix);
    /* One frame, another seed: on this scene (fine structure at the pixel
     * scale) the filter gains little (measured 10%), but must gain. */
    API_OK(clvr_tracer_set_seed(tr, 11, &msg));
    API_OK(clvr_tracer_render(tr, 1, &msg));
    API_OK(clvr_tracer_read_image(tr, raw, npix * 4, &msg));
    API_OK(clvr_tracer_read_denoised(tr, dn, npix * 4, &msg));
    const double e_raw = rel_rmse(raw, ref, medium, npix), e_dn = rel_rmse(dn, ref, medium, npix);
    printf("built-in scene %ux%u, 1 frame against 64: rel RMSE raw %.4f, denoised %.4f; bias (the 64 frames "
           "denoised) %.4f\n", w, h, e_raw, e_dn, bias);
    TU_CHECK(e_dn < e_raw);
    /* The 64 frames' own variance caps the noise scale (0.09 of e_raw
     * measured; the Laplacians alone gave 0.13), and 16 frames' too
     * (denoise_change's bound 0.8 / sqrt(N); 0.14 measured). At 256 frames
     * the change reaches 0.94 of that bound here (structure at the pixel
     * scale: the edge-stopping's bias falls slower than the noise), and 256
     * frames take 12 s under PoCL: not checked. */
    TU_CHECK(bias < 0.8 / sqrt(64.0) * e_raw);
    const double bias16 = denoise_change(tr, 16, 7, raw, dn, medium, npix);
    printf("built-in scene: 16 frames denoised against themselves %.4f (bound %.4f)\n", bias16, 0.2 * e_raw);
    TU_CHECK(bias16 < 0.8 / sqrt(16.0) * e_raw);
    test_smooth(ctx);
    API_OK(clvr_tracer_set_denoise(tr, 0, &msg));
    TU_CHECK(clvr_tracer_denoise(tr) == 0);
done:
    clvr_tracer_destroy(tr);
    clvr_dataset_destroy(ds);
    clvr_context_destroy(ctx);
    free(ref);
    free(ref_dn);
    free(raw);
    free(dn);
    free(medium);
}

int main(void)
{
    clvr_cl cl;
    clvr_error err = {0};
    tu_open_device(&cl);
    clvr_denoiser *dn = NULL;
    TU_CHECK_STATUS(clvr_denoiser_create(&cl, &dn, &err), CLVR_OK, &err);
    if (dn) {
        test_device_vs_reference(&cl, dn);
        test_constant_and_step(dn);
    }
    clvr_denoiser_destroy(dn);
    clvr_cl_destroy(&cl);
    test_render();
    return tu_finish("test_denoise");
}
