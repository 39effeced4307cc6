/* Proves the camera: the shared ray generator's conventions (centre ray hits
 * the look-at point, top-left is up-left, unit directions, field of view),
 * projection as its inverse, automatic framing that keeps every box corner
 * inside the image, and the --camera parser's errors. */
#include "camera.h"
#include "test_util.h"

static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static float len3(const float *a) { return sqrtf(dot3(a, a)); }

static void test_look_at_axes(void)
{
    clvr_error err = {0};
    clvr_camera cam;
    const float eye[3] = {0, 0, 5}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at, up, 40.0f, 64, 48, &err), CLVR_OK, &err);
    float o[3], d[3];
    clvr_camera_ray(&cam, 32.0f, 24.0f, o, d);
    TU_CHECK_NEAR(d[0], 0.0, 1e-6);
    TU_CHECK_NEAR(d[1], 0.0, 1e-6);
    TU_CHECK_NEAR(d[2], -1.0, 1e-6);
    TU_CHECK_NEAR(o[2], 5.0, 0.0);
    /* Pixel (0, 0) is the top-left corner: up and to the left (-x). */
    clvr_camera_ray(&cam, 0.0f, 0.0f, o, d);
    TU_CHECK(d[0] < 0.0f && d[1] > 0.0f);
    /* Middle of the top edge: half the vertical field of view above the axis. */
    clvr_camera_ray(&cam, 32.0f, 0.0f, o, d);
    TU_CHECK_NEAR(atan2(d[1], -d[2]) * 180.0 / M_PI, 20.0, 1e-4);
    /* Middle of the right edge: horizontal half-angle from the aspect ratio. */
    clvr_camera_ray(&cam, 64.0f, 24.0f, o, d);
    TU_CHECK_NEAR(d[0] / -d[2], tan(20.0 * M_PI / 180.0) * 64.0 / 48.0, 1e-5);
    TU_CHECK_EQ_U64(cam.width, 64);
    TU_CHECK_EQ_U64(cam.height, 48);
}

static void test_random_cameras(void)
{
    uint64_t rng = 7;
    clvr_error err = {0};
    int bad_center = 0, bad_norm = 0, bad_proj = 0;
    double worst_center = 0.0, worst_norm = 0.0, worst_proj = 0.0;
    for (int t = 0; t < 200; ++t) {
        float eye[3], at[3], up[3];
        for (int k = 0; k < 3; ++k) {
            eye[k] = (tu_randf(&rng) - 0.5f) * 200.0f;
            at[k] = (tu_randf(&rng) - 0.5f) * 20.0f;
            up[k] = tu_randf(&rng) - 0.5f;
        }
        uint32_t w = 1 + (uint32_t)(tu_rand(&rng) % 997), h = 1 + (uint32_t)(tu_rand(&rng) % 601);
        float fov = 5.0f + 150.0f * tu_randf(&rng);
        clvr_camera cam;
        if (clvr_camera_look_at(&cam, eye, at, up, fov, w, h, &err) != CLVR_OK) continue; /* rare: up ~ parallel */
        float o[3], d[3], f[3];
        clvr_camera_ray(&cam, 0.5f * (float)w, 0.5f * (float)h, o, d);
        for (int k = 0; k < 3; ++k) f[k] = at[k] - eye[k];
        float fl = len3(f);
        double c = 1.0 - dot3(d, f) / fl;
        if (c > worst_center) worst_center = c;
        bad_center += c > 1e-6;
        for (int i = 0; i < 20; ++i) {
            float px = tu_randf(&rng) * (float)w, py = tu_randf(&rng) * (float)h;
            clvr_camera_ray(&cam, px, py, o, d);
            double n = fabs(len3(d) - 1.0);
            if (n > worst_norm) worst_norm = n;
            bad_norm += n > 1e-6;
            float p[3], qx, qy;
            for (int k = 0; k < 3; ++k) p[k] = o[k] + d[k] * 10.0f;
            float depth = clvr_camera_project(&cam, p, &qx, &qy);
            double e = fmax(fabs(qx - px) / w, fabs(qy - py) / h);
            if (!(depth > 0.0f)) e = 1.0;
            if (e > worst_proj) worst_proj = e;
            bad_proj += e > 1e-4;
        }
    }
    printf("random cameras: worst 1-cos(centre ray, look-at) %.3g, worst | |dir| - 1 | %.3g, worst reprojection "
           "%.3g image widths\n", worst_center, worst_norm, worst_proj);
    TU_CHECK_EQ_U64(bad_center, 0);
    TU_CHECK_EQ_U64(bad_norm, 0);
    TU_CHECK_EQ_U64(bad_proj, 0);
}

/* Every corner of the box in front of the camera and inside the image; the
 * farthest-out corner close to the margin (the framing is tight); the centre
 * ray towards the box centre. */
static void check_framing(const float lo[3], const float hi[3], float fov, uint32_t w, uint32_t h, int *bad,
                          double *tightest)
{
    clvr_error err = {0};
    clvr_camera cam;
    if (clvr_camera_frame_box(&cam, lo, hi, fov, w, h, &err) != CLVR_OK) {
        fprintf(stderr, "frame_box failed: %s\n", err.msg);
        ++*bad;
        return;
    }
    double reach = 0.0;
    for (int i = 0; i < 8; ++i) {
        float p[3], px, py;
        for (int k = 0; k < 3; ++k) p[k] = (i >> k) & 1 ? hi[k] : lo[k];
        float depth = clvr_camera_project(&cam, p, &px, &py);
        int inside = depth > 0.0f && px >= 0.0f && px <= (float)w && py >= 0.0f && py <= (float)h;
        if (!inside) {
            fprintf(stderr, "corner %d of box (%g %g %g)-(%g %g %g) outside: depth %g, pixel (%g, %g) of %ux%u\n", i,
                    lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], depth, px, py, w, h);
            ++*bad;
        }
        double rx = fabs(px - 0.5 * w) / (0.5 * w), ry = fabs(py - 0.5 * h) / (0.5 * h);
        reach = fmax(reach, fmax(rx, ry));
    }
    /* The box must fill the frame up to the margin (0.9), not a sphere bound. */
    if (!(reach > 0.85 && reach <= 0.9 + 1e-3)) {
        fprintf(stderr, "box (%g %g %g)-(%g %g %g): farthest corner at %.4f of the half-image (want ~0.9)\n", lo[0],
                lo[1], lo[2], hi[0], hi[1], hi[2], reach);
        ++*bad;
    }
    if (reach < *tightest) *tightest = reach;
    float o[3], d[3], c[3];
    clvr_camera_ray(&cam, 0.5f * w, 0.5f * h, o, d);
    for (int k = 0; k < 3; ++k) c[k] = 0.5f * (lo[k] + hi[k]) - o[k];
    if (1.0 - dot3(d, c) / len3(c) > 1e-6) ++*bad;
}

static void test_frame_box(void)
{
    uint64_t rng = 11;
    int bad = 0;
    double tightest = 1.0;
    const float unit_lo[3] = {0, 0, 0}, unit_hi[3] = {1, 1, 1};
    check_framing(unit_lo, unit_hi, 40.0f, 512, 512, &bad, &tightest);
    const float flat_lo[3] = {-5, 2, -1}, flat_hi[3] = {5, 2, 1}; /* zero thickness */
    check_framing(flat_lo, flat_hi, 40.0f, 800, 200, &bad, &tightest);
    for (int t = 0; t < 300; ++t) {
        float lo[3], hi[3];
        float scale = powf(10.0f, (tu_randf(&rng) - 0.5f) * 8.0f);
        for (int k = 0; k < 3; ++k) {
            float c = (tu_randf(&rng) - 0.5f) * 10.0f * scale, e = tu_randf(&rng) * scale;
            lo[k] = c - e;
            hi[k] = c + e;
        }
        float fov = 10.0f + 120.0f * tu_randf(&rng);
        uint32_t w = 1 + (uint32_t)(tu_rand(&rng) % 2000), h = 1 + (uint32_t)(tu_rand(&rng) % 2000);
        check_framing(lo, hi, fov, w, h, &bad, &tightest);
    }
    printf("framing: smallest farthest-corner reach %.4f of the half-image\n", tightest);
    TU_CHECK_EQ_U64(bad, 0);

    /* A point is still viewable. */
    clvr_error err = {0};
    clvr_camera cam;
    const float pt[3] = {3, 4, 5};
    TU_CHECK_STATUS(clvr_camera_frame_box(&cam, pt, pt, 40.0f, 16, 16, &err), CLVR_OK, &err);
    const float inv_lo[3] = {1, 0, 0}, inv_hi[3] = {0, 1, 1};
    TU_CHECK_STATUS(clvr_camera_frame_box(&cam, inv_lo, inv_hi, 40.0f, 16, 16, &err), CLVR_ERR_BAD_VALUE, &err);
    const float nan_hi[3] = {1, NAN, 1};
    TU_CHECK_STATUS(clvr_camera_frame_box(&cam, unit_lo, nan_hi, 40.0f, 16, 16, &err), CLVR_ERR_BAD_VALUE, &err);
}

static void test_errors(void)
{
    clvr_error err = {0};
    clvr_camera cam;
    const float eye[3] = {1, 2, 3}, at[3] = {1, 2, 3}, at2[3] = {1, 5, 3}, up[3] = {0, 1, 0}, zero[3] = {0, 0, 0};
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at, up, 40.0f, 8, 8, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "coincide") != NULL);
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at2, up, 40.0f, 8, 8, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "parallel") != NULL);
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at2, zero, 40.0f, 8, 8, &err), CLVR_ERR_USAGE, &err);
    const float side[3] = {1, 0, 0};
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at2, side, 0.0f, 8, 8, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "field of view") != NULL);
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at2, side, 180.0f, 8, 8, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at2, side, 40.0f, 0, 8, &err), CLVR_ERR_USAGE, &err);
    const float inf_eye[3] = {INFINITY, 0, 0};
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, inf_eye, at2, side, 40.0f, 8, 8, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye, at2, side, 40.0f, 8, 8, &err), CLVR_OK, &err);
}

static void test_parse(void)
{
    clvr_error err = {0};
    float v[9];
    TU_CHECK_STATUS(clvr_camera_parse("1,2,3, 4 ,5,6,0,1e0,-0.5", v, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(v[0], 1.0, 0.0);
    TU_CHECK_NEAR(v[4], 5.0, 0.0);
    TU_CHECK_NEAR(v[7], 1.0, 0.0);
    TU_CHECK_NEAR(v[8], -0.5, 0.0);
    struct { const char *text, *needle; } bad[] = {
        {"1,2,3", "only 3 of 9"},
        {"", "not a number"},
        {"1,2,x,4,5,6,7,8,9", "value 3 (eye z)"},
        {"1,2,3,4,5,6,7,8,9,10", "after the 9th value"},
        {"1,2,3,4,5,6,7,8,9 junk", "after the 9th value"},
        {"1;2;3;4;5;6;7;8;9", "expected ','"},
        {"nan,2,3,4,5,6,7,8,9", "not a finite"},
        {"1,2,3,4,5,6,7,8,1e39", "not a finite"},
        {"1,2,3,4,5,6,7,8,", "not a number"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        err.msg[0] = '\0';
        TU_CHECK_STATUS(clvr_camera_parse(bad[i].text, v, &err), CLVR_ERR_USAGE, &err);
        if (!strstr(err.msg, bad[i].needle) || !strstr(err.msg, "--camera")) {
            fprintf(stderr, "message for \"%s\" lacks \"%s\": %s\n", bad[i].text, bad[i].needle, err.msg);
            TU_CHECK(0);
        }
    }
}

int main(void)
{
    test_look_at_axes();
    test_random_cameras();
    test_frame_box();
    test_errors();
    test_parse();
    return tu_finish("test_camera");
}
