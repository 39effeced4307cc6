/* Proves the per-pixel control variates of the image read
 * (kernels/pixel_cv.h, clvr_renderer_read):
 *  - the device pass (render.cl's clvr_pixel_cv_image) equals the plain-C
 *    reference (the same header run on the host) on random sums and
 *    controls of sizes 1x1, 1x7, 7x1, 2x2, 37x53 (primes), 131x67 and 256x3
 *    (not multiples of the 8x8 work-group), after 1 and 3 frames, with a
 *    NaN pixel (its neighbours stay finite: it is left out of their fits);
 *  - with all controls 0 the image is the plain mean, bit for bit;
 *  - on an image linear in the rays' positions, the fit finds the gradient:
 *    every pixel comes out as the value at its centre;
 *  - through the renderer, 1-frame images of a mixed-cell scene with
 *    structure at the pixel scale, 192 seeds: the corrected image minus
 *    the plain one has mean 0 per 4x4 block and channel within 5 standard
 *    errors (the control variates keep each pixel's expected value; a fit
 *    that reads the pixel's own sample fails here), and the corrected
 *    pixels' variance is at most 0.8 of the plain ones' (a correction of
 *    the wrong sign or scale fails). */
#include "camera.h"
#include "pixel_cv.h"
#include "preprocess.h"
#include "render.h"
#include "scene.h"
#include "accel.h"
#include "test_util.h"

/* The device pass over sum and ctl (w x h, 4 floats per pixel each), and
 * refine (8 floats per pixel) and nsamp when refine is not NULL, into out. */
static int run_device(clvr_cl *cl, cl_kernel k, const float *sum, const float *ctl, float inv_n, const float *refine,
                      const uint32_t *nsamp, uint32_t frames, uint32_t w, uint32_t h, float *out)
{
    clvr_error err = {0};
    clvr_status s = CLVR_OK;
    const size_t npix = (size_t)w * h, bytes = npix * 4 * sizeof(float);
    cl_mem bs = NULL, bc = NULL, bo = NULL, br = NULL, bn = NULL;
    const size_t local[2] = {8, 8};
    const float zero[8] = {0.0f};
    const uint32_t one = 1;
    s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, (void *)sum, "sums", &bs, &err);
    if (s == CLVR_OK)
        s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, (void *)ctl, "controls", &bc, &err);
    if (s == CLVR_OK)
        s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, refine ? npix * 8 * sizeof(float) : sizeof zero,
                           refine ? (void *)refine : (void *)zero, "refine sums", &br, &err);
    if (s == CLVR_OK)
        s = clvr_cl_buffer(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, refine ? npix * sizeof(uint32_t) : sizeof one,
                           refine ? (void *)nsamp : (void *)&one, "sample counts", &bn, &err);
    if (s == CLVR_OK) s = clvr_cl_buffer(cl, CL_MEM_WRITE_ONLY, bytes, NULL, "image", &bo, &err);
    const cl_uint cw = w, ch = h, refine_frames = refine ? frames : 0u;
    const cl_uint4 live = {{0u, 0u, w, h}}; /* every pixel fitted, as the reference */
    const cl_float cn = inv_n;
    if (s == CLVR_OK)
        s = CLVR_CL_ARGS(k, &err, CLVR_ARG(bs), CLVR_ARG(bc), CLVR_ARG(cn), CLVR_ARG(cw), CLVR_ARG(ch), CLVR_ARG(br),
                         CLVR_ARG(bn), CLVR_ARG(refine_frames), CLVR_ARG(live), CLVR_ARG(bo));
    if (s == CLVR_OK) s = clvr_cl_run2d(cl, k, w, h, local, NULL, &err);
    if (s == CLVR_OK && clEnqueueReadBuffer(cl->queue, bo, CL_TRUE, 0, bytes, out, 0, NULL, NULL) != CL_SUCCESS)
        s = clvr_error_set(&err, CLVR_ERR_OPENCL, "clEnqueueReadBuffer(image) failed");
    clvr_cl_release(cl, &bs);
    clvr_cl_release(cl, &bc);
    clvr_cl_release(cl, &bo);
    clvr_cl_release(cl, &br);
    clvr_cl_release(cl, &bn);
    if (s != CLVR_OK) {
        fprintf(stderr, "device pass: %s\n", err.msg);
        ++tu_fail_;
        return 1;
    }
    return 0;
}

static void run_ref(const float *sum, const float *ctl, float inv_n, const float *refine, const uint32_t *nsamp,
                    uint32_t frames, uint32_t w, uint32_t h, float *out)
{
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            clvr_pixel_cv(sum, ctl, inv_n, refine, nsamp, frames, w, h, x, y, out + 4 * ((size_t)y * w + x));
}

static void test_device_vs_reference(clvr_cl *cl, cl_kernel k)
{
    static const uint32_t sizes[][2] = {{1, 1}, {1, 7}, {7, 1}, {2, 2}, {37, 53}, {131, 67}, {256, 3}};
    for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; ++si)
        for (uint32_t variant = 0; variant < 3; ++variant) {
            /* 1 frame, 3 frames, 3 frames with refine samples in a random
             * third of the pixels (adaptive sampling). */
            const uint32_t frames = variant ? 3 : 1, w = sizes[si][0], h = sizes[si][1];
            const size_t npix = (size_t)w * h, n = npix * 4;
            float *sum = malloc(n * sizeof(float)), *ctl = malloc(n * sizeof(float));
            float *dev = malloc(n * sizeof(float)), *ref = malloc(n * sizeof(float));
            float *refine = variant == 2 ? calloc(npix * 8, sizeof(float)) : NULL;
            uint32_t *nsamp = variant == 2 ? malloc(npix * sizeof(uint32_t)) : NULL;
            uint64_t st = 1000 + si * 10 + variant;
            for (size_t i = 0; i < n; ++i) {
                sum[i] = (float)frames * 2.0f * tu_randf(&st);
                /* controls: sums of frames draws in [-1/2, 1/2) */
                ctl[i] = (i % 4 == 3) ? 0.0f : (float)frames * (tu_randf(&st) - 0.5f);
            }
            for (size_t p = 0; refine && p < npix; ++p) {
                const uint32_t extra = tu_randf(&st) < 1.0f / 3.0f ? 1u + (uint32_t)(2.0f * tu_randf(&st)) : 0u;
                nsamp[p] = frames + extra;
                /* A pixel without refine samples has never-written sums: NaN
                 * here, which must not reach its image. */
                for (int c = 0; c < 8 && !extra; ++c) refine[8 * p + (size_t)c] = NAN;
                for (int c = 0; c < 4 && extra; ++c) {
                    refine[8 * p + (size_t)c] = (float)extra * 2.0f * tu_randf(&st);
                    refine[8 * p + 4 + (size_t)c] = c == 3 ? 0.0f : (float)extra * (tu_randf(&st) - 0.5f);
                }
            }
            const int nan_pixel = w * h >= 9;
            const size_t np = ((size_t)(h / 2) * w + w / 2);
            if (nan_pixel) sum[4 * np + 1] = NAN;
            const float inv_n = 1.0f / (float)frames;
            if (!run_device(cl, k, sum, ctl, inv_n, refine, nsamp, frames, w, h, dev)) {
                run_ref(sum, ctl, inv_n, refine, nsamp, frames, w, h, ref);
                double worst = 0.0;
                uint64_t nonfinite = 0, changed = 0;
                for (size_t p = 0; p < npix; ++p)
                    for (int c = 0; c < 4; ++c) {
                        const size_t i = 4 * p + (size_t)c;
                        if (nan_pixel && p == np) continue;
                        nonfinite += !isfinite(dev[i]);
                        const double d = fabs((double)dev[i] - (double)ref[i]) / (1.0 + fabs((double)ref[i]));
                        if (d > worst) worst = d;
                        const float mean = refine && nsamp[p] > frames ? (sum[i] + refine[8 * p + (size_t)c]) / (float)nsamp[p]
                                                                       : sum[i] * inv_n;
                        changed += dev[i] != mean;
                    }
                if (worst > 1e-4)
                    fprintf(stderr, "%ux%u, %u frames%s: device and reference differ by %g\n", w, h, frames,
                            refine ? " and refine samples" : "", worst);
                TU_CHECK(worst <= 1e-4);
                TU_CHECK_EQ_U64(nonfinite, 0);
                /* 1x1 has no neighbour (nothing to fit): the mean; larger ones move. */
                if (w * h == 1) TU_CHECK_EQ_U64(changed, 0);
                if (w * h >= 9) TU_CHECK(changed > 0);
            }
            free(sum);
            free(ctl);
            free(dev);
            free(ref);
            free(refine);
            free(nsamp);
        }
}

static void test_exact_cases(clvr_cl *cl, cl_kernel k)
{
    const uint32_t w = 23, h = 19;
    const size_t n = (size_t)w * h * 4;
    float *sum = malloc(n * sizeof(float)), *ctl = calloc(n, sizeof(float)), *out = malloc(n * sizeof(float));
    uint64_t st = 5;
    /* Controls all 0: the fit's terms vanish, the image is the mean. */
    for (size_t i = 0; i < n; ++i) sum[i] = 3.0f * tu_randf(&st);
    if (!run_device(cl, k, sum, ctl, 1.0f, NULL, NULL, 1, w, h, out)) TU_CHECK(memcmp(out, sum, n * sizeof(float)) == 0);
    /* Linear in the rays' positions (centre + jitter), the first uniform
     * at 1/2: each pixel comes out as the value at its centre. */
    const float a[4] = {0.5f, 1.0f, -0.25f, 0.75f}, gx[4] = {0.02f, -0.03f, 0.01f, 0.0f},
                gy[4] = {-0.01f, 0.02f, 0.03f, 0.015f};
    for (size_t p = 0; p < (size_t)w * h; ++p) {
        const float dx = tu_randf(&st) - 0.5f, dy = tu_randf(&st) - 0.5f;
        const float x = (float)(p % w), y = (float)(p / w);
        ctl[4 * p] = dx;
        ctl[4 * p + 1] = dy;
        ctl[4 * p + 2] = 0.0f;
        for (int c = 0; c < 4; ++c) sum[4 * p + (size_t)c] = a[c] + gx[c] * (x + dx) + gy[c] * (y + dy);
    }
    if (!run_device(cl, k, sum, ctl, 1.0f, NULL, NULL, 1, w, h, out)) {
        double worst = 0.0, moved = 0.0;
        for (size_t p = 0; p < (size_t)w * h; ++p)
            for (int c = 0; c < 4; ++c) {
                const double want = a[c] + gx[c] * (float)(p % w) + gy[c] * (float)(p / w);
                worst = fmax(worst, fabs(out[4 * p + (size_t)c] - want));
                moved = fmax(moved, fabs(sum[4 * p + (size_t)c] - want));
            }
        if (worst > 2e-5) fprintf(stderr, "linear image: off the centre values by %g (the means by %g)\n", worst, moved);
        TU_CHECK(worst <= 2e-5);
        TU_CHECK(moved > 0.01);
    }
    /* A flat background (columns 0-11 all one value, one pixel in it apart)
     * beside a noisy region, random controls: a pixel whose neighbours all
     * hold one value is its own mean, bit for bit, also the pixel apart
     * (the shortcut reads the neighbours only); the device's pixels equal
     * the reference's there, and elsewhere within 1e-5. */
    {
        const uint32_t px = 5, py = 9;
        float *ref = malloc(n * sizeof(float));
        for (size_t p = 0; p < (size_t)w * h; ++p) {
            const uint32_t x = (uint32_t)(p % w), y = (uint32_t)(p / w);
            for (int c = 0; c < 4; ++c) {
                sum[4 * p + (size_t)c] = x < 12 ? 0.7f : 3.0f * tu_randf(&st);
                ctl[4 * p + (size_t)c] = c == 3 ? 0.0f : tu_randf(&st) - 0.5f;
            }
            if (x == px && y == py)
                for (int c = 0; c < 4; ++c) sum[4 * p + (size_t)c] = 2.0f;
        }
        if (ref && !run_device(cl, k, sum, ctl, 1.0f, NULL, NULL, 1, w, h, out)) {
            run_ref(sum, ctl, 1.0f, NULL, NULL, 1, w, h, ref);
            uint64_t flat = 0, flat_bad = 0, off = 0;
            for (size_t p = 0; p < (size_t)w * h; ++p) {
                const uint32_t x = (uint32_t)(p % w), y = (uint32_t)(p / w);
                const int near_apart = (x + 1 >= px && x <= px + 1 && y + 1 >= py && y <= py + 1) && !(x == px && y == py);
                for (int c = 0; c < 4; ++c) {
                    const size_t i = 4 * p + (size_t)c;
                    if (x <= 10 && !near_apart) {
                        flat += c == 0;
                        flat_bad += out[i] != sum[i] || ref[i] != sum[i];
                    } else {
                        off += fabs((double)out[i] - (double)ref[i]) > 1e-5 * (1.0 + fabs((double)ref[i]));
                    }
                }
            }
            TU_CHECK_EQ_U64(flat, 11u * h - 8u);
            TU_CHECK_EQ_U64(flat_bad, 0);
            TU_CHECK_EQ_U64(off, 0);
        }
        free(ref);
    }
    free(sum);
    free(ctl);
    free(out);
}

/* 1-frame images of one scene under many seeds, with and without the
 * control variates: same expected value per 4x4 block, lower variance. */
static void test_renderer(clvr_cl *cl)
{
    enum { W = 32, H = 32, RUNS = 192, B = 4 };
    clvr_error err = {0};
    clvr_scene_box_params p;
    clvr_scene_box_params_init(&p);
    p.nx = p.ny = p.nz = 6;
    p.mix = CLVR_SCENE_MIX_MIXED;
    p.field = CLVR_SCENE_FIELD_BLOBS;
    clvr_mesh m;
    clvr_clustered c;
    clvr_accel a;
    clvr_renderer *r = NULL;
    memset(&c, 0, sizeof c);
    memset(&a, 0, sizeof a);
    TU_CHECK_STATUS(clvr_scene_box(&p, &m, &err), CLVR_OK, &err);
    clvr_preprocess_options po;
    clvr_preprocess_options_default(&po);
    clvr_render_settings set;
    clvr_render_settings_default(&set);
    set.width = W;
    set.height = H;
    set.sampler = CLVR_SAMPLER_INDEPENDENT;
    clvr_status s = clvr_preprocess(cl, &m, &po, &c, &err);
    if (s == CLVR_OK) s = clvr_accel_build(cl, &c, &a, &err);
    if (s == CLVR_OK) s = clvr_renderer_create(cl, &c, &a, &set, &r, &err);
    clvr_camera cam;
    if (s == CLVR_OK) s = clvr_camera_frame_box(&cam, m.bounds_lo, m.bounds_hi, 40.0f, W, H, &err);
    if (s == CLVR_OK) s = clvr_renderer_set_camera(r, &cam, &err);
    const float table[8] = {1.0f, 0.6f, 0.2f, 0.0f, 0.2f, 0.4f, 1.0f, 12.0f};
    if (s == CLVR_OK) s = clvr_renderer_set_tf(r, table, 2, 0.0f, 1.0f, 1.0f, &err);
    const size_t n = (size_t)W * H * 4;
    double *ps = calloc(n, sizeof(double)), *pq = calloc(n, sizeof(double));
    double *cs = calloc(n, sizeof(double)), *cq = calloc(n, sizeof(double));
    float *img = malloc(n * sizeof(float)), *plain = malloc(n * sizeof(float));
    enum { NB = (W / B) * (H / B) * 4 };
    double bsum[NB] = {0}, bsq[NB] = {0};
    for (uint32_t run = 0; s == CLVR_OK && run < RUNS; ++run) {
        set.seed = 1000 + run;
        s = clvr_renderer_set_settings(r, &set, &err);
        if (s == CLVR_OK) s = clvr_renderer_frame(r, &err);
        if (s == CLVR_OK) s = clvr_renderer_read(r, img, NULL, &err);
        if (s == CLVR_OK) s = clvr_renderer_read_moments(r, plain, NULL, &err); /* 1 frame: the sample */
        for (size_t i = 0; s == CLVR_OK && i < n; ++i) {
            ps[i] += plain[i];
            pq[i] += (double)plain[i] * plain[i];
            cs[i] += img[i];
            cq[i] += (double)img[i] * img[i];
        }
        /* This run's block sums of the differences. */
        for (uint32_t b = 0; s == CLVR_OK && b < NB; ++b) {
            const uint32_t ch = b % 4, blk = b / 4, bx = (blk % (W / B)) * B, by = (blk / (W / B)) * B;
            double d = 0.0;
            for (uint32_t y = by; y < by + B; ++y)
                for (uint32_t x = bx; x < bx + B; ++x) {
                    const size_t i = 4 * ((size_t)y * W + x) + ch;
                    d += (double)img[i] - plain[i];
                }
            bsum[b] += d;
            bsq[b] += d * d;
        }
    }
    TU_CHECK_STATUS(s, CLVR_OK, &err);
    if (s == CLVR_OK) {
        /* Block means of the difference against their standard errors
         * over the runs (a block's pixels are correlated through their
         * fits; the runs are independent). */
        int bad = 0;
        double worst = 0.0;
        for (uint32_t b = 0; b < NB; ++b) {
            const double mean = bsum[b] / RUNS, v = bsq[b] / RUNS - mean * mean;
            const double se = sqrt((v > 0 ? v : 0) / (RUNS - 1));
            const double z = fabs(mean) / (se > 0 ? se : 1e-30);
            if (fabs(mean) > 5.0 * se + 1e-6) {
                ++bad;
                if (z > worst) worst = z;
            }
        }
        if (bad) fprintf(stderr, "control variates: %d blocks biased (worst %.1f SE)\n", bad, worst);
        TU_CHECK_EQ_U64(bad, 0);
        double vp = 0.0, vc = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const double mp = ps[i] / RUNS, mc = cs[i] / RUNS;
            vp += pq[i] / RUNS - mp * mp;
            vc += cq[i] / RUNS - mc * mc;
        }
        printf("1-frame variance over %d seeds: plain %.4g, with control variates %.4g (%.2f)\n", RUNS, vp, vc,
               vc / vp);
        TU_CHECK(vc <= 0.8 * vp);
    }
    free(ps); free(pq); free(cs); free(cq); free(img); free(plain);
    clvr_renderer_destroy(r);
    clvr_accel_release(cl, &a);
    clvr_clustered_release(cl, &c);
    clvr_mesh_free(&m);
}

int main(void)
{
    clvr_cl cl;
    clvr_error err = {0};
    tu_open_device(&cl);
    cl_program prog = NULL;
    cl_kernel k = NULL;
    clvr_status s = clvr_cl_build(&cl, "render.cl", NULL, &prog, &err);
    if (s == CLVR_OK) s = clvr_cl_kernel(prog, "clvr_pixel_cv_image", &k, &err);
    TU_CHECK_STATUS(s, CLVR_OK, &err);
    if (s == CLVR_OK) {
        test_device_vs_reference(&cl, k);
        test_exact_cases(&cl, k);
    }
    if (k) clReleaseKernel(k);
    if (prog) clReleaseProgram(prog);
    test_renderer(&cl);
    clvr_cl_destroy(&cl);
    return tu_finish("test_pixel_cv");
}
