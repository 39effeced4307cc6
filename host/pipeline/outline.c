/* outline.c: box edges over the rendered image (outline.h). */
#include "outline.h"

#include <math.h>

#include "camera.h"

static float depth_of(const clvr_camera *cam, const float p[3])
{
    return (p[0] - cam->origin[0]) * cam->forward[0] + (p[1] - cam->origin[1]) * cam->forward[1] +
           (p[2] - cam->origin[2]) * cam->forward[2];
}

/* Distance from (x, y) to the segment a-b in pixels. */
static float segment_distance(float x, float y, float ax, float ay, float bx, float by)
{
    float dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
    float t = l2 > 0.0f ? ((x - ax) * dx + (y - ay) * dy) / l2 : 0.0f;
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    float ex = ax + t * dx - x, ey = ay + t * dy - y;
    return sqrtf(ex * ex + ey * ey);
}

static void draw_segment(float *rgba, const clvr_camera *cam, const float p[3], const float q[3],
                         const float colour[3], float width_px, float near)
{
    float a[3] = {p[0], p[1], p[2]}, b[3] = {q[0], q[1], q[2]};
    float da = depth_of(cam, a), db = depth_of(cam, b);
    if (da < near && db < near) return;
    /* Cut at the near plane: the part behind it would project inverted. */
    if (da < near || db < near) {
        float t = (near - da) / (db - da);
        float *m = da < near ? a : b;
        for (int k = 0; k < 3; ++k) m[k] = p[k] + t * (q[k] - p[k]);
    }
    float ax, ay, bx, by;
    clvr_camera_project(cam, a, &ax, &ay);
    clvr_camera_project(cam, b, &bx, &by);
    if (!(isfinite(ax) && isfinite(ay) && isfinite(bx) && isfinite(by))) return;
    const float reach = 0.5f * width_px + 1.0f;
    const int w = (int)cam->width, h = (int)cam->height;
    float fx0 = fminf(ax, bx) - reach, fx1 = fmaxf(ax, bx) + reach;
    float fy0 = fminf(ay, by) - reach, fy1 = fmaxf(ay, by) + reach;
    if (fx1 < 0.0f || fy1 < 0.0f || fx0 > (float)w || fy0 > (float)h) return;
    int x0 = fx0 < 0.0f ? 0 : (int)fx0, x1 = fx1 > (float)(w - 1) ? w - 1 : (int)fx1;
    int y0 = fy0 < 0.0f ? 0 : (int)fy0, y1 = fy1 > (float)(h - 1) ? h - 1 : (int)fy1;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            float d = segment_distance((float)x + 0.5f, (float)y + 0.5f, ax, ay, bx, by);
            float c = 0.5f * width_px + 1.0f - d;
            if (c <= 0.0f) continue;
            if (c > 1.0f) c = 1.0f;
            float *px = rgba + 4 * ((size_t)y * (size_t)w + (size_t)x);
            for (int k = 0; k < 3; ++k) px[k] = px[k] * (1.0f - c) + colour[k] * c;
            px[3] = px[3] + (1.0f - px[3]) * c;
        }
}

void clvr_outline_draw_box(float *rgba, const clvr_camera *cam, const float lo[3], const float hi[3],
                           const float colour[3], float width_px)
{
    float corner[8][3];
    for (int i = 0; i < 8; ++i)
        for (int k = 0; k < 3; ++k) corner[i][k] = (i >> k) & 1 ? hi[k] : lo[k];
    /* Near plane: a small fraction of the eye's distance to the box centre. */
    float c[3] = {0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2])};
    float dc[3] = {c[0] - cam->origin[0], c[1] - cam->origin[1], c[2] - cam->origin[2]};
    float near = 1e-4f * sqrtf(dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2]);
    if (!(near > 0.0f)) near = 1e-6f;
    /* Corners i and i | (1 << k) differ along axis k: the 12 edges. */
    for (int i = 0; i < 8; ++i)
        for (int k = 0; k < 3; ++k)
            if (!(i & (1 << k))) draw_segment(rgba, cam, corner[i], corner[i | (1 << k)], colour, width_px, near);
}
