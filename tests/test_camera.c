/* Proves the camera: the shared ray generator's conventions (centre ray hits
 * the look-at point, top-left is up-left, unit directions, field of view),
 * projection as its inverse, automatic framing that keeps every box corner
 * inside the image, the view options (up axis, azimuth, elevation, zoom) and
 * turntable rotation, the rectangle of pixels a frame traces, and the
 * --camera parser's errors. */
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

/* The framing's view options: the default view is the documented oblique
 * direction; for every up axis the image's up is that axis, the view is
 * front-right-above in that axis's frame with the documented elevation;
 * azimuth turns about up; elevation adds and clamps; zoom divides the
 * distance; random views still keep the box inside the image; a turntable of
 * N steps returns to its start and keeps the distance and height. */
static void test_views(void)
{
    clvr_error err = {0};
    clvr_camera cam, base;
    clvr_camera_view v;
    const float lo[3] = {-1, -2, -3}, hi[3] = {2, 1, 0}, c[3] = {0.5f, -0.5f, -1.5f};
    float dir[3], def[3] = {CLVR_CAMERA_VIEW_X, CLVR_CAMERA_VIEW_Y, CLVR_CAMERA_VIEW_Z};
    float dl = len3(def);
    clvr_camera_view_default(&v);
    TU_CHECK(clvr_camera_view_direction(&v, dir) == 0);
    for (int k = 0; k < 3; ++k) TU_CHECK_NEAR(dir[k], def[k] / dl, 1e-6);
    const double el0 = atan2(CLVR_CAMERA_VIEW_Y, hypot(CLVR_CAMERA_VIEW_X, CLVR_CAMERA_VIEW_Z)) * 180.0 / M_PI;

    const char *axes[6] = {"x", "y", "z", "-x", "-y", "-z"};
    for (int a = 0; a < 6; ++a) {
        clvr_camera_view_default(&v);
        TU_CHECK(clvr_camera_parse_axis(axes[a], v.up) == 0);
        TU_CHECK_STATUS(clvr_camera_frame_view(&cam, lo, hi, &v, 30.0f, 64, 64, &err), CLVR_OK, &err);
        /* The camera's up is the axis (the view is not along it), and the
         * eye is el0 degrees above the horizon of that axis. */
        TU_CHECK(dot3(cam.up, v.up) > 0.9f);
        float e[3] = {cam.origin[0] - c[0], cam.origin[1] - c[1], cam.origin[2] - c[2]};
        TU_CHECK_NEAR(asin(dot3(e, v.up) / len3(e)) * 180.0 / M_PI, el0, 1e-3);
        /* The up axis projects to an upward vertical line in the image. */
        float top[3] = {c[0] + v.up[0], c[1] + v.up[1], c[2] + v.up[2]}, px, py, cx, cy;
        clvr_camera_project(&cam, c, &cx, &cy);
        clvr_camera_project(&cam, top, &px, &py);
        TU_CHECK(py < cy);
        TU_CHECK_NEAR(px, cx, 1e-3);
    }
    /* +z up (Exodus, OpenFOAM): seen from -y, x to the right. */
    clvr_camera_view_default(&v);
    clvr_camera_parse_axis("z", v.up);
    clvr_camera_view_direction(&v, dir);
    TU_CHECK(dir[1] < 0.0f && dir[2] > 0.0f);
    TU_CHECK_STATUS(clvr_camera_frame_view(&cam, lo, hi, &v, 30.0f, 64, 64, &err), CLVR_OK, &err);
    TU_CHECK(cam.right[0] > 0.5f);
    float bad_axis[3] = {0, 0, 0};
    TU_CHECK(clvr_camera_parse_axis("w", bad_axis) != 0 && clvr_camera_parse_axis("xy", bad_axis) != 0 &&
             clvr_camera_parse_axis("", bad_axis) != 0 && clvr_camera_parse_axis("--x", bad_axis) != 0);

    /* Azimuth: the eye turns about up by that angle, same height and distance. */
    clvr_camera_view_default(&v);
    TU_CHECK_STATUS(clvr_camera_frame_view(&base, lo, hi, &v, 30.0f, 64, 64, &err), CLVR_OK, &err);
    v.azimuth_deg = 90.0f;
    clvr_camera_view_direction(&v, dir);
    TU_CHECK_NEAR(dir[1], def[1] / dl, 1e-6);
    /* Counterclockwise seen from +y: (x, z) -> (z, -x). */
    TU_CHECK_NEAR(dir[0], def[2] / dl, 1e-6);
    TU_CHECK_NEAR(dir[2], -def[0] / dl, 1e-6);
    /* Elevation adds, and is clamped at 89 degrees. */
    clvr_camera_view_default(&v);
    v.elevation_deg = 30.0f;
    clvr_camera_view_direction(&v, dir);
    TU_CHECK_NEAR(asin(dir[1]) * 180.0 / M_PI, el0 + 30.0, 1e-3);
    v.elevation_deg = 150.0f;
    clvr_camera_view_direction(&v, dir);
    TU_CHECK_NEAR(asin(dir[1]) * 180.0 / M_PI, 89.0, 1e-3);
    TU_CHECK_STATUS(clvr_camera_frame_view(&cam, lo, hi, &v, 30.0f, 64, 64, &err), CLVR_OK, &err);
    /* Zoom 2: half the distance to the centre, same direction. */
    clvr_camera_view_default(&v);
    v.zoom = 2.0f;
    TU_CHECK_STATUS(clvr_camera_frame_view(&cam, lo, hi, &v, 30.0f, 64, 64, &err), CLVR_OK, &err);
    float e0[3], e1[3];
    for (int k = 0; k < 3; ++k) {
        e0[k] = base.origin[k] - c[k];
        e1[k] = cam.origin[k] - c[k];
    }
    TU_CHECK_NEAR(len3(e1) / len3(e0), 0.5, 1e-5);
    TU_CHECK_NEAR(dot3(e0, e1) / (len3(e0) * len3(e1)), 1.0, 1e-6);
    v.zoom = 0.0f;
    TU_CHECK_STATUS(clvr_camera_frame_view(&cam, lo, hi, &v, 30.0f, 64, 64, &err), CLVR_ERR_USAGE, &err);
    clvr_camera_view_default(&v);
    v.up[1] = 0.0f;
    TU_CHECK_STATUS(clvr_camera_frame_view(&cam, lo, hi, &v, 30.0f, 64, 64, &err), CLVR_ERR_USAGE, &err);

    /* Random views (any axis, azimuth, elevation) at zoom 1 keep every corner inside. */
    uint64_t rng = 5;
    int outside = 0;
    for (int t = 0; t < 200; ++t) {
        clvr_camera_view_default(&v);
        clvr_camera_parse_axis(axes[tu_rand(&rng) % 6], v.up);
        v.azimuth_deg = 720.0f * tu_randf(&rng) - 360.0f;
        v.elevation_deg = 200.0f * tu_randf(&rng) - 100.0f;
        uint32_t w = 1 + (uint32_t)(tu_rand(&rng) % 1000), h = 1 + (uint32_t)(tu_rand(&rng) % 1000);
        if (clvr_camera_frame_view(&cam, lo, hi, &v, 30.0f, w, h, &err) != CLVR_OK) { ++outside; continue; }
        for (int i = 0; i < 8; ++i) {
            float p[3], px, py;
            for (int k = 0; k < 3; ++k) p[k] = (i >> k) & 1 ? hi[k] : lo[k];
            float depth = clvr_camera_project(&cam, p, &px, &py);
            outside += !(depth > 0.0f && px >= -1e-3f * w && px <= 1.001f * w && py >= -1e-3f * h && py <= 1.001f * h);
        }
    }
    TU_CHECK_EQ_U64(outside, 0);

    /* Turntable: N steps of 360/N about up come back to the start; each
     * keeps the distance to the centre and the height along the axis. */
    const float axis[3] = {0, 0, 1}, eye[3] = {3, -4, 2};
    float p[3] = {eye[0], eye[1], eye[2]};
    for (int i = 0; i < 7; ++i) {
        float q[3];
        clvr_camera_rotate_about(p, c, axis, 360.0f / 7.0f, q);
        float d0[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]}, d1[3] = {q[0] - c[0], q[1] - c[1], q[2] - c[2]};
        TU_CHECK_NEAR(len3(d1), len3(d0), 1e-4);
        TU_CHECK_NEAR(q[2], p[2], 1e-5);
        memcpy(p, q, sizeof p);
    }
    for (int k = 0; k < 3; ++k) TU_CHECK_NEAR(p[k], eye[k], 1e-4);
    /* A quarter turn about +z is counterclockwise seen from above: x -> y. */
    const float ex[3] = {1, 0, 0}, zero[3] = {0, 0, 0};
    clvr_camera_rotate_about(ex, zero, axis, 90.0f, p);
    TU_CHECK_NEAR(p[0], 0.0, 1e-6);
    TU_CHECK_NEAR(p[1], 1.0, 1e-6);
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

/* The region frame f traces for the box seen by cam (clvr_camera_live),
 * read with the kernel's own test (clvr_frame_traces). */
static void live_of(const clvr_camera *cam, const float lo[3], const float hi[3], uint32_t margin, clvr_frame *f)
{
    memset(f, 0, sizeof *f);
    clvr_camera_live(cam, lo, hi, margin, f->live, f->live_edges);
}

/* The pixels a frame traces (clvr_camera_live, clvr_frame_traces): no ray
 * through a pixel left out meets the box (rays sampled on an 8 x 8 grid in
 * every pixel, as the kernel makes them, in float); with a margin of 3,
 * every pixel within 3 of one whose rays meet the box is traced (what the
 * pixel control variates need to stay bit for bit, kernels/render.cl); the
 * rectangle is tight to a pixel and every traced pixel is next to one
 * whose rays meet the box when the whole box is in view, and the edges
 * leave out pixels the rectangle keeps; every pixel with the eye inside the
 * box, none with the box behind it, every pixel that sees it with the box
 * beside the eye (partly behind). A wrong region would blank pixels that
 * see the medium. */
static void test_live_region(void)
{
    uint64_t rng = 11;
    clvr_error err = {0};
    int cases = 0, tight_cases = 0, escaped = 0, loose = 0, partial = 0, far = 0, near_missed = 0;
    long rect_px = 0, traced_px = 0;
    static unsigned char hit[48 * 40];
    for (int t = 0; t < 400; ++t) {
        float lo[3], hi[3], eye[3], at[3], up[3] = {0.0f, 0.0f, 0.0f};
        for (int k = 0; k < 3; ++k) {
            lo[k] = (tu_randf(&rng) - 0.5f) * 10.0f;
            hi[k] = lo[k] + 0.01f + 5.0f * tu_randf(&rng);
            eye[k] = (tu_randf(&rng) - 0.5f) * (t % 4 == 0 ? 12.0f : 60.0f);
            at[k] = 0.5f * (lo[k] + hi[k]) + (tu_randf(&rng) - 0.5f) * (t % 3 == 0 ? 30.0f : 3.0f);
        }
        up[t % 3] = 1.0f;
        const uint32_t w = 1 + (uint32_t)(tu_rand(&rng) % 48), h = 1 + (uint32_t)(tu_rand(&rng) % 40);
        clvr_camera cam;
        if (clvr_camera_look_at(&cam, eye, at, up, 5.0f + 150.0f * tu_randf(&rng), w, h, &err) != CLVR_OK) continue;
        clvr_frame f, f3;
        live_of(&cam, lo, hi, 0u, &f);
        live_of(&cam, lo, hi, 3u, &f3);
        /* Tight where every corner is in front and inside the image: the
         * rectangle is that of the box's whole projection (the corners'
         * convex hull), which elsewhere may reach past the image. */
        int in_view = 1;
        for (int c = 0; c < 8; ++c) {
            const float q[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
            float px, py;
            in_view &= clvr_camera_project(&cam, q, &px, &py) > 1e-3f && px >= 0.0f && py >= 0.0f &&
                       px <= (float)w && py <= (float)h;
        }
        int64_t hx0 = w, hy0 = h, hx1 = -1, hy1 = -1;
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x) {
                hit[y * w + x] = 0;
                for (int j = 0; j < 64; ++j) {
                    float o[3], d[3];
                    clvr_camera_ray(&cam, (float)x + ((float)(j % 8) + 0.5f) / 8.0f,
                                    (float)y + ((float)(j / 8) + 0.5f) / 8.0f, o, d);
                    if (!clvr_ray_hits_box(o, d, lo, hi)) continue;
                    hit[y * w + x] = 1;
                    escaped += !clvr_frame_traces(&f, x, y);
                    if (x < hx0) hx0 = x;
                    if (y < hy0) hy0 = y;
                    if ((int64_t)x > hx1) hx1 = x;
                    if ((int64_t)y > hy1) hy1 = y;
                }
            }
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x) {
                int hit_near1 = 0, hit_near3 = 0;
                for (int dy = -3; dy <= 3; ++dy)
                    for (int dx = -3; dx <= 3; ++dx) {
                        const int64_t xx = (int64_t)x + dx, yy = (int64_t)y + dy;
                        if (xx < 0 || yy < 0 || xx >= w || yy >= h || !hit[yy * w + xx]) continue;
                        hit_near3 = 1;
                        hit_near1 |= dx >= -1 && dx <= 1 && dy >= -1 && dy <= 1;
                    }
                near_missed += hit_near3 && !clvr_frame_traces(&f3, x, y);
                if (in_view && hx1 >= 0) {
                    far += clvr_frame_traces(&f, x, y) && !hit_near1;
                    rect_px += x >= f.live[0] && x < f.live[2] && y >= f.live[1] && y < f.live[3];
                    traced_px += clvr_frame_traces(&f, x, y);
                }
            }
        ++cases;
        const int whole = f.live[0] == 0 && f.live[1] == 0 && f.live[2] == w && f.live[3] == h;
        partial += !whole;
        if (in_view && hx1 >= 0) {
            ++tight_cases;
            loose += hx0 - (int64_t)f.live[0] > 1 || hy0 - (int64_t)f.live[1] > 1 ||
                     (int64_t)f.live[2] - (hx1 + 1) > 1 || (int64_t)f.live[3] - (hy1 + 1) > 1;
        }
    }
    printf("live region: %d cameras (%d not the whole image, %d with the whole box in view): %d sampled rays outside "
           "it met the box, %d pixels within 3 of a hit left out with a margin of 3, %d rectangles more than a pixel "
           "wider than the hits, %d traced pixels with no hit next to them; the edges leave out %.0f%% of the "
           "rectangles' pixels\n", cases, partial, tight_cases, escaped, near_missed, loose, far,
           rect_px ? 100.0 * (double)(rect_px - traced_px) / (double)rect_px : 0.0);
    TU_CHECK(cases > 300 && tight_cases > 50 && partial > 50);
    TU_CHECK_EQ_U64(escaped, 0);
    TU_CHECK_EQ_U64(near_missed, 0);
    TU_CHECK_EQ_U64(loose, 0);
    TU_CHECK_EQ_U64(far, 0);
    TU_CHECK(traced_px < rect_px * 9 / 10);

    /* The eye inside the box: every pixel; the box behind the eye: none;
     * the margin widens the rectangle, cut to the image. */
    const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1}, up[3] = {0, 1, 0};
    const float eye_in[3] = {0.2f, 0.1f, 0.3f}, at_in[3] = {0, 0, -5};
    clvr_camera cam;
    clvr_frame f, wide;
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye_in, at_in, up, 40.0f, 64, 48, &err), CLVR_OK, &err);
    live_of(&cam, lo, hi, 0u, &f);
    int all = 1;
    for (uint32_t y = 0; y < 48; ++y)
        for (uint32_t x = 0; x < 64; ++x) all &= clvr_frame_traces(&f, x, y);
    TU_CHECK(all);
    /* Beside: the box below the eye and half behind it, seen at a wide
     * angle (rays toward its near part run far out of the projection of
     * the corners in front). */
    const float eye_side[3] = {0.0f, 0.0f, 1.5f}, at_side[3] = {5.0f, 0.0f, 1.5f}, up_z[3] = {0, 0, 1};
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye_side, at_side, up_z, 150.0f, 64, 64, &err), CLVR_OK, &err);
    live_of(&cam, lo, hi, 0u, &f);
    int side_hits = 0, side_escaped = 0;
    for (uint32_t y = 0; y < 64; ++y)
        for (uint32_t x = 0; x < 64; ++x)
            for (int j = 0; j < 16; ++j) {
                float o[3], d[3];
                clvr_camera_ray(&cam, (float)x + ((float)(j % 4) + 0.5f) / 4.0f, (float)y + ((float)(j / 4) + 0.5f) / 4.0f,
                                o, d);
                if (!clvr_ray_hits_box(o, d, lo, hi)) continue;
                ++side_hits;
                side_escaped += !clvr_frame_traces(&f, x, y);
            }
    TU_CHECK(side_hits > 1000);
    TU_CHECK_EQ_U64(side_escaped, 0);
    const float eye_out[3] = {0, 0, 10}, at_away[3] = {0, 0, 20}, at_box[3] = {0, 0, 0};
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye_out, at_away, up, 40.0f, 64, 48, &err), CLVR_OK, &err);
    live_of(&cam, lo, hi, 0u, &f);
    int none = 1;
    for (uint32_t y = 0; y < 48; ++y)
        for (uint32_t x = 0; x < 64; ++x) none &= !clvr_frame_traces(&f, x, y);
    TU_CHECK(none && f.live[2] != 0u);
    TU_CHECK_STATUS(clvr_camera_look_at(&cam, eye_out, at_box, up, 40.0f, 64, 48, &err), CLVR_OK, &err);
    live_of(&cam, lo, hi, 0u, &f);
    live_of(&cam, lo, hi, 3u, &wide);
    printf("live rectangle of a box seen from 10 box half-widths: [%u, %u) x [%u, %u) of 64 x 48, with a margin of 3 "
           "[%u, %u) x [%u, %u)\n", f.live[0], f.live[2], f.live[1], f.live[3], wide.live[0], wide.live[2],
           wide.live[1], wide.live[3]);
    TU_CHECK(f.live[0] > 10 && f.live[2] < 54 && f.live[1] > 5 && f.live[3] < 43);
    TU_CHECK(wide.live[0] == f.live[0] - 3 && wide.live[2] == f.live[2] + 3 && wide.live[1] == f.live[1] - 3 &&
             wide.live[3] == f.live[3] + 3);
}

int main(void)
{
    test_look_at_axes();
    test_random_cameras();
    test_live_region();
    test_frame_box();
    test_views();
    test_errors();
    test_parse();
    return tu_finish("test_camera");
}
