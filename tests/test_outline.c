/* Proves the outline (host/pipeline/outline.h): the box's edges land where
 * the camera projects its corners and edges, nothing is drawn away from
 * them, the composite keeps premultiplied alpha, and a box around the eye
 * draws only what is in front without blowing up. */
#include "camera.h"
#include "outline.h"
#include "test_util.h"

static float alpha_at(const float *img, uint32_t w, uint32_t h, float px, float py)
{
    int x = (int)floorf(px), y = (int)floorf(py);
    if (x < 0 || y < 0 || x >= (int)w || y >= (int)h) return -1.0f;
    return img[4 * ((size_t)y * w + (size_t)x) + 3];
}

int main(void)
{
    clvr_error err = {0};
    const uint32_t W = 160, H = 120;
    const float lo[3] = {-1.0f, 0.0f, 2.0f}, hi[3] = {3.0f, 1.0f, 4.0f};
    const float white[3] = {1, 1, 1};
    clvr_camera cam;
    TU_CHECK_STATUS(clvr_camera_frame_box(&cam, lo, hi, 30.0f, W, H, &err), CLVR_OK, &err);
    float *img = calloc((size_t)W * H * 4, sizeof(float));
    if (!img) return 1;
    clvr_outline_draw_box(img, &cam, lo, hi, white, 1.5f);
    /* Every corner and every edge's points (at 1/8 steps) are covered. */
    int checked = 0;
    for (int i = 0; i < 8; ++i)
        for (int k = 0; k < 3; ++k) {
            if (i & (1 << k)) continue;
            float a[3], b[3];
            for (int j = 0; j < 3; ++j) {
                a[j] = (i >> j) & 1 ? hi[j] : lo[j];
                b[j] = ((i | (1 << k)) >> j) & 1 ? hi[j] : lo[j];
            }
            for (int s = 0; s <= 8; ++s) {
                float p[3], px, py;
                for (int j = 0; j < 3; ++j) p[j] = a[j] + (b[j] - a[j]) * (float)s / 8.0f;
                TU_CHECK(clvr_camera_project(&cam, p, &px, &py) > 0.0f);
                float al = alpha_at(img, W, H, px, py);
                if (!(al > 0.99f)) {
                    fprintf(stderr, "edge %d/%d point %d at (%.2f, %.2f): alpha %g, expected 1\n", i, k, s, px, py,
                            al);
                    ++tu_fail_;
                } else {
                    ++tu_pass_;
                }
                ++checked;
            }
        }
    TU_CHECK_EQ_U64(checked, 12 * 9);
    /* The image corners are untouched (the framing keeps a margin). */
    TU_CHECK(alpha_at(img, W, H, 0.5f, 0.5f) == 0.0f);
    TU_CHECK(alpha_at(img, W, H, W - 0.5f, H - 0.5f) == 0.0f);
    size_t drawn = 0;
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        drawn += img[4 * i + 3] > 0.0f;
        /* Premultiplied white over black: rgb equals alpha. */
        if (fabsf(img[4 * i] - img[4 * i + 3]) > 1e-6f) { ++tu_fail_; break; }
    }
    /* Lines, not fills: well under a fifth of the image. */
    TU_CHECK(drawn > 200 && drawn < (size_t)W * H / 5);

    /* Over a grey opaque image the colour blends and alpha stays 1. */
    for (size_t i = 0; i < (size_t)W * H * 4; ++i) img[i] = (i % 4 == 3) ? 1.0f : 0.25f;
    const float red[3] = {1, 0, 0};
    clvr_outline_draw_box(img, &cam, lo, hi, red, 1.5f);
    float px, py;
    clvr_camera_project(&cam, lo, &px, &py);
    float *p = img + 4 * ((size_t)floorf(py) * W + (size_t)floorf(px));
    TU_CHECK_NEAR(p[0], 1.0, 1e-6);
    TU_CHECK_NEAR(p[1], 0.0, 1e-6);
    TU_CHECK_NEAR(p[3], 1.0, 1e-6);

    /* The eye inside the box: edges cut at the near plane, still finite. */
    memset(img, 0, (size_t)W * H * 4 * sizeof(float));
    const float eye[3] = {1.0f, 0.5f, 3.0f}, at[3] = {1.0f, 0.5f, 5.0f}, up[3] = {0, 1, 0};
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at, up, 60.0f, W, H, &err), CLVR_OK, &err);
    const float deep_hi[3] = {3.0f, 1.0f, 9.0f};
    clvr_outline_draw_box(img, &cam, lo, deep_hi, white, 1.0f);
    drawn = 0;
    int finite = 1;
    for (size_t i = 0; i < (size_t)W * H * 4; ++i) finite &= isfinite(img[i]) && img[i] >= 0.0f && img[i] <= 1.0f;
    for (size_t i = 0; i < (size_t)W * H; ++i) drawn += img[4 * i + 3] > 0.0f;
    TU_CHECK(finite);
    TU_CHECK(drawn > 0);
    /* The far face's corner (x = -1, y = 0, z = 9) is in front: covered. */
    const float far_corner[3] = {-1.0f, 0.0f, 9.0f};
    TU_CHECK(clvr_camera_project(&cam, far_corner, &px, &py) > 0.0f);
    TU_CHECK(alpha_at(img, W, H, px, py) > 0.99f);
    free(img);
    return tu_finish("test_outline");
}
