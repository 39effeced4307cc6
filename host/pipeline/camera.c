/* camera.c: pinhole camera construction, automatic framing of a box, and
 * the --camera string parser. The ray generator itself lives in
 * kernels/clvr_shared.h (clvr_camera_ray) so host and kernels agree. */
#include "camera.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void sub3(const float *a, const float *b, float *o)
{
    o[0] = a[0] - b[0];
    o[1] = a[1] - b[1];
    o[2] = a[2] - b[2];
}
static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross3(const float *a, const float *b, float *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}
static float norm3(const float *a) { return sqrtf(dot3(a, a)); }
static int finite3(const float *a) { return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]); }

clvr_status clvr_camera_look_at(clvr_camera *cam, const float eye[3], const float target[3], const float up[3],
                                float fovy_deg, uint32_t width, uint32_t height, clvr_error *err)
{
    if (!finite3(eye) || !finite3(target) || !finite3(up))
        return clvr_error_set(err, CLVR_ERR_USAGE, "camera: eye, look-at point and up vector must be finite numbers");
    if (!(fovy_deg > 0.0f && fovy_deg < 180.0f))
        return clvr_error_set(err, CLVR_ERR_USAGE, "camera: vertical field of view %g degrees is outside (0, 180)",
                              (double)fovy_deg);
    if (width == 0 || height == 0)
        return clvr_error_set(err, CLVR_ERR_USAGE, "camera: image size %ux%u is empty", width, height);
    float f[3], r[3], u[3];
    sub3(target, eye, f);
    float fl = norm3(f);
    if (!(fl > 0.0f) || !isfinite(fl))
        return clvr_error_set(err, CLVR_ERR_USAGE,
                              "camera: eye (%g, %g, %g) and look-at point coincide; give two different points",
                              (double)eye[0], (double)eye[1], (double)eye[2]);
    for (int k = 0; k < 3; ++k) f[k] /= fl;
    float ul = norm3(up);
    cross3(f, up, r);
    float rl = norm3(r);
    /* Parallel within ~0.06 degrees: the basis would be dominated by
     * rounding and the image would spin unpredictably. */
    if (!(ul > 0.0f) || !(rl > 1e-3f * ul))
        return clvr_error_set(err, CLVR_ERR_USAGE,
                              "camera: up vector (%g, %g, %g) is zero or parallel to the view direction; "
                              "choose an up vector across the line of sight",
                              (double)up[0], (double)up[1], (double)up[2]);
    for (int k = 0; k < 3; ++k) r[k] /= rl;
    cross3(r, f, u);

    memset(cam, 0, sizeof *cam);
    float th = tanf(0.5f * fovy_deg * (float)M_PI / 180.0f);
    float aspect = (float)width / (float)height;
    float tw = th * aspect;
    for (int k = 0; k < 3; ++k) {
        cam->origin[k] = eye[k];
        cam->target[k] = target[k];
        cam->forward[k] = f[k];
        cam->right[k] = r[k];
        cam->up[k] = u[k];
        cam->corner[k] = f[k] - tw * r[k] + th * u[k];
        cam->du[k] = r[k] * (2.0f * tw / (float)width);
        cam->dv[k] = -u[k] * (2.0f * th / (float)height);
    }
    cam->fovy = fovy_deg;
    cam->aspect = aspect;
    cam->width = width;
    cam->height = height;
    return CLVR_OK;
}

float clvr_camera_project(const clvr_camera *cam, const float p[3], float *px, float *py)
{
    float q[3];
    sub3(p, cam->origin, q);
    float depth = dot3(q, cam->forward);
    float th = tanf(0.5f * cam->fovy * (float)M_PI / 180.0f), tw = th * cam->aspect;
    float x = dot3(q, cam->right) / depth, y = dot3(q, cam->up) / depth;
    *px = (x + tw) / (2.0f * tw) * (float)cam->width;
    *py = (th - y) / (2.0f * th) * (float)cam->height;
    return depth;
}

void clvr_camera_view_default(clvr_camera_view *v)
{
    memset(v, 0, sizeof *v);
    v->up[1] = 1.0f;
    v->zoom = 1.0f;
}

int clvr_camera_parse_axis(const char *text, float out[3])
{
    if (!text) return 1;
    float sign = 1.0f;
    if (*text == '-' || *text == '+') sign = *text++ == '-' ? -1.0f : 1.0f;
    if (!text[0] || text[1] || text[0] < 'x' || text[0] > 'z') return 1;
    out[0] = out[1] = out[2] = 0.0f;
    out[text[0] - 'x'] = sign;
    return 0;
}

void clvr_camera_rotate_about(const float p[3], const float centre[3], const float axis[3], float deg, float out[3])
{
    /* Rodrigues: v' = v cos + (k x v) sin + k (k.v)(1 - cos), in double so
     * that N turntable steps land back on the start to float precision. */
    double k[3] = {axis[0], axis[1], axis[2]};
    double kl = sqrt(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
    double v[3], a = deg * M_PI / 180.0, c = cos(a), sn = sin(a);
    for (int i = 0; i < 3; ++i) {
        k[i] /= kl;
        v[i] = (double)p[i] - (double)centre[i];
    }
    double kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    double kx[3] = {k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
    for (int i = 0; i < 3; ++i) out[i] = (float)((double)centre[i] + v[i] * c + kx[i] * sn + k[i] * kv * (1.0 - c));
}

int clvr_camera_view_direction(const clvr_camera_view *v, float dir[3])
{
    if (!finite3(v->up) || !(norm3(v->up) > 0.0f)) return 1;
    double u[3], s[3] = {0, 0, 0}, f[3];
    double ul = norm3(v->up);
    for (int k = 0; k < 3; ++k) u[k] = v->up[k] / ul;
    /* Side: +x unless up is closest to the x axis, then +y; made
     * orthogonal to up. Front = side x up, so (side, up, front) is the
     * right-handed frame that is (x, y, z) for +y up. */
    int ax = fabs(u[0]) >= fabs(u[1]) && fabs(u[0]) >= fabs(u[2]);
    s[ax ? 1 : 0] = 1.0;
    double su = s[0] * u[0] + s[1] * u[1] + s[2] * u[2];
    for (int k = 0; k < 3; ++k) s[k] -= su * u[k];
    double sl = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int k = 0; k < 3; ++k) s[k] /= sl;
    f[0] = s[1] * u[2] - s[2] * u[1];
    f[1] = s[2] * u[0] - s[0] * u[2];
    f[2] = s[0] * u[1] - s[1] * u[0];
    /* The default view in that frame, as azimuth and elevation angles. */
    double h_side = CLVR_CAMERA_VIEW_X, h_front = CLVR_CAMERA_VIEW_Z, vert = CLVR_CAMERA_VIEW_Y;
    double az = atan2(h_side, h_front) + (double)v->azimuth_deg * M_PI / 180.0;
    double el = atan2(vert, sqrt(h_side * h_side + h_front * h_front)) + (double)v->elevation_deg * M_PI / 180.0;
    const double lim = 89.0 * M_PI / 180.0;
    el = el > lim ? lim : el < -lim ? -lim : el;
    for (int k = 0; k < 3; ++k)
        dir[k] = (float)(cos(el) * (sin(az) * s[k] + cos(az) * f[k]) + sin(el) * u[k]);
    return 0;
}

clvr_status clvr_camera_frame_box(clvr_camera *cam, const float lo[3], const float hi[3], float fovy_deg,
                                  uint32_t width, uint32_t height, clvr_error *err)
{
    clvr_camera_view v;
    clvr_camera_view_default(&v);
    return clvr_camera_frame_view(cam, lo, hi, &v, fovy_deg, width, height, err);
}

clvr_status clvr_camera_frame_view(clvr_camera *cam, const float lo[3], const float hi[3],
                                   const clvr_camera_view *view, float fovy_deg, uint32_t width, uint32_t height,
                                   clvr_error *err)
{
    if (!finite3(lo) || !finite3(hi) || lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2])
        return clvr_error_set(err, CLVR_ERR_BAD_VALUE,
                              "camera: cannot frame the box (%g, %g, %g)-(%g, %g, %g): bounds must be finite with lo <= hi",
                              (double)lo[0], (double)lo[1], (double)lo[2], (double)hi[0], (double)hi[1], (double)hi[2]);
    if (!(fovy_deg > 0.0f && fovy_deg < 180.0f))
        return clvr_error_set(err, CLVR_ERR_USAGE, "camera: vertical field of view %g degrees is outside (0, 180)",
                              (double)fovy_deg);
    if (width == 0 || height == 0)
        return clvr_error_set(err, CLVR_ERR_USAGE, "camera: image size %ux%u is empty", width, height);
    if (!(view->zoom > 0.0f) || !isfinite(view->zoom))
        return clvr_error_set(err, CLVR_ERR_USAGE, "camera: zoom %g must be a positive number", (double)view->zoom);
    float d[3];
    if (clvr_camera_view_direction(view, d) != 0)
        return clvr_error_set(err, CLVR_ERR_USAGE, "camera: the up axis (%g, %g, %g) must be a non-zero vector",
                              (double)view->up[0], (double)view->up[1], (double)view->up[2]);
    float dl = norm3(d);
    for (int k = 0; k < 3; ++k) d[k] /= dl;
    float c[3], f[3] = {-d[0], -d[1], -d[2]}, r[3], u[3];
    for (int k = 0; k < 3; ++k) c[k] = 0.5f * lo[k] + 0.5f * hi[k];
    cross3(f, view->up, r);
    float rl = norm3(r);
    for (int k = 0; k < 3; ++k) r[k] /= rl;
    cross3(r, f, u);
    /* A corner q (relative to the centre) seen from eye = c + t d has depth
     * t - q.d and image offsets q.r, q.u; it fits when |q.r| <= tw * depth
     * and |q.u| <= th * depth, i.e. t >= q.d + |q.r| / tw (and the same with
     * th). The distance is the largest such bound over the corners, computed
     * in double so the fit is exact up to float rounding. */
    double th = tan(0.5 * fovy_deg * M_PI / 180.0) * CLVR_CAMERA_FRAME_FILL;
    double tw = th * (double)width / (double)height;
    double t = 0.0;
    for (int i = 0; i < 8; ++i) {
        double q[3];
        for (int k = 0; k < 3; ++k) q[k] = (double)((i >> k) & 1 ? hi[k] : lo[k]) - (double)c[k];
        double qd = q[0] * d[0] + q[1] * d[1] + q[2] * d[2];
        double qr = q[0] * r[0] + q[1] * r[1] + q[2] * r[2];
        double qu = q[0] * u[0] + q[1] * u[1] + q[2] * u[2];
        double need = qd + fmax(fabs(qr) / tw, fabs(qu) / th);
        if (need > t) t = need;
    }
    /* Leave room for the rounding of the float camera: 0.1% farther. */
    t *= 1.001;
    if (!(t > 0.0)) t = 1.0; /* a point: any distance shows it */
    /* Zoom as a dolly toward the centre: the centre's plane grows by zoom,
     * and zooming far enough flies into the volume. */
    t /= (double)view->zoom;
    float eye[3];
    for (int k = 0; k < 3; ++k) eye[k] = (float)((double)c[k] + t * (double)d[k]);
    return clvr_camera_look_at(cam, eye, c, view->up, fovy_deg, width, height, err);
}

clvr_status clvr_camera_parse(const char *text, float out[9], clvr_error *err)
{
    static const char *names[9] = {"eye x", "eye y", "eye z", "look-at x", "look-at y", "look-at z", "up x", "up y", "up z"};
    const char *p = text;
    if (!text) return clvr_error_set(err, CLVR_ERR_USAGE, "--camera: missing value");
    for (int i = 0; i < 9; ++i) {
        while (*p == ' ' || *p == '\t') ++p;
        char *end = NULL;
        errno = 0;
        double v = strtod(p, &end);
        if (end == p)
            return clvr_error_set(err, CLVR_ERR_USAGE,
                                  "--camera \"%s\": value %d (%s) at character %d is not a number; expected "
                                  "px,py,pz,lx,ly,lz,ux,uy,uz",
                                  text, i + 1, names[i], (int)(p - text) + 1);
        if (!isfinite(v) || fabs(v) > 3.0e38)
            return clvr_error_set(err, CLVR_ERR_USAGE, "--camera \"%s\": value %d (%s) %.*s is not a finite float",
                                  text, i + 1, names[i], (int)(end - p), p);
        out[i] = (float)v;
        p = end;
        while (*p == ' ' || *p == '\t') ++p;
        if (i < 8) {
            if (!*p)
                return clvr_error_set(err, CLVR_ERR_USAGE,
                                      "--camera \"%s\": only %d of 9 values; expected px,py,pz,lx,ly,lz,ux,uy,uz",
                                      text, i + 1);
            if (*p != ',')
                return clvr_error_set(err, CLVR_ERR_USAGE,
                                      "--camera \"%s\": expected ',' after value %d (%s), found '%c'; expected 9 "
                                      "comma-separated numbers px,py,pz,lx,ly,lz,ux,uy,uz",
                                      text, i + 1, names[i], *p);
            ++p;
        } else if (*p) {
            return clvr_error_set(err, CLVR_ERR_USAGE,
                                  "--camera \"%s\": unexpected \"%s\" after the 9th value; expected exactly 9 numbers",
                                  text, p);
        }
    }
    return CLVR_OK;
}

/* The box's corners in pixel coordinates: 0, or 1 when some pixel ray may
 * meet it at any angle (a corner beside or behind the eye, degenerate ray
 * vectors), 2 when none can (the box wholly behind the eye). */
static int project_box(const clvr_camera *cam, const float lo[3], const float hi[3], double xy[8][2])
{
    /* The ray through pixel coordinates (px, py) is along corner + px du +
     * py dv: a corner q of the box lies on it where q - eye = a corner + b du
     * + c dv with a > 0, at px = b / a, py = c / a (Cramer's rule). */
    const double C[3] = {cam->corner[0], cam->corner[1], cam->corner[2]}, U[3] = {cam->du[0], cam->du[1], cam->du[2]},
                 V[3] = {cam->dv[0], cam->dv[1], cam->dv[2]};
    const double UxV[3] = {U[1] * V[2] - U[2] * V[1], U[2] * V[0] - U[0] * V[2], U[0] * V[1] - U[1] * V[0]};
    const double det = C[0] * UxV[0] + C[1] * UxV[1] + C[2] * UxV[2];
    if (!(fabs(det) > 0.0) || !isfinite(det)) return 1;
    int behind = 0;
    for (int k = 0; k < 8; ++k) {
        const double q[3] = {((k & 1) ? hi[0] : lo[0]) - cam->origin[0], ((k & 2) ? hi[1] : lo[1]) - cam->origin[1],
                             ((k & 4) ? hi[2] : lo[2]) - cam->origin[2]};
        const double a = (q[0] * UxV[0] + q[1] * UxV[1] + q[2] * UxV[2]) / det;
        /* det(C, q, V) and det(C, U, q), over det(C, U, V) */
        const double b = (C[0] * (q[1] * V[2] - q[2] * V[1]) + C[1] * (q[2] * V[0] - q[0] * V[2]) +
                          C[2] * (q[0] * V[1] - q[1] * V[0])) / det;
        const double c = (C[0] * (U[1] * q[2] - U[2] * q[1]) + C[1] * (U[2] * q[0] - U[0] * q[2]) +
                          C[2] * (U[0] * q[1] - U[1] * q[0])) / det;
        /* A corner at or behind the eye's plane (or nearly in it: its
         * projection far outside any image). */
        const double qn = fabs(q[0]) + fabs(q[1]) + fabs(q[2]);
        if (a < -1e-6 * qn) {
            ++behind;
            continue;
        }
        if (!(a > 1e-6 * qn) || !isfinite(b) || !isfinite(c)) return 1;
        xy[k][0] = b / a;
        xy[k][1] = c / a;
    }
    /* Every ray point has a > 0: a box wholly behind the eye is seen by
     * no pixel; one partly behind, by any. */
    return behind == 8 ? 2 : behind ? 1 : 0;
}

static double cross2(const double o[2], const double a[2], const double b[2])
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

void clvr_camera_live(const clvr_camera *cam, const float lo[3], const float hi[3], uint32_t margin, clvr_u32 live[4],
                      float edges[CLVR_LIVE_EDGES][4])
{
    const uint32_t w = cam->width, h = cam->height;
    for (int k = 0; k < CLVR_LIVE_EDGES; ++k) {
        edges[k][0] = edges[k][1] = edges[k][3] = 0.0f;
        edges[k][2] = 1.0f; /* 0 > 1: cuts nothing */
    }
    live[0] = live[1] = 0;
    live[2] = w;
    live[3] = h;
    double xy[8][2];
    const int seen = project_box(cam, lo, hi, xy);
    if (seen == 1) return;
    if (seen == 2) {
        live[0] = w; /* [w, w): none (live[2] == 0 would mean every pixel) */
        return;
    }
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int k = 0; k < 8; ++k) {
        xmin = fmin(xmin, xy[k][0]);
        xmax = fmax(xmax, xy[k][0]);
        ymin = fmin(ymin, xy[k][1]);
        ymax = fmax(ymax, xy[k][1]);
    }
    /* The box's projection is the corners' convex hull; pixel x covers
     * [x, x + 1). Cut to the image before converting. */
    const double m = (double)margin;
    const double x0 = fmax(floor(xmin) - m, 0.0), x1 = fmin(floor(xmax) + 1.0 + m, (double)w);
    const double y0 = fmax(floor(ymin) - m, 0.0), y1 = fmin(floor(ymax) + 1.0 + m, (double)h);
    live[0] = x0 < (double)w ? (uint32_t)x0 : w;
    live[1] = y0 < (double)h ? (uint32_t)y0 : h;
    live[2] = x1 > 0.0 ? (uint32_t)x1 : 0u;
    live[3] = y1 > 0.0 ? (uint32_t)y1 : 0u;
    if (live[2] == 0u) { /* the box left of the image: none */
        live[0] = live[2] = w;
        return;
    }
    /* The hull's edges (Andrew's monotone chain over the 8 points sorted
     * by x then y), each the half-plane n.p <= c with n outward: a pixel
     * whose square, widened by the margin, lies beyond one edge sees
     * nothing of the box. Keeping fewer edges only widens the region. */
    double pts[8][2], hull[17][2];
    memcpy(pts, xy, sizeof pts);
    for (int i = 1; i < 8; ++i)
        for (int j = i; j > 0 && (pts[j][0] < pts[j - 1][0] || (pts[j][0] == pts[j - 1][0] && pts[j][1] < pts[j - 1][1]));
             --j) {
            double t0 = pts[j][0], t1 = pts[j][1];
            pts[j][0] = pts[j - 1][0];
            pts[j][1] = pts[j - 1][1];
            pts[j - 1][0] = t0;
            pts[j - 1][1] = t1;
        }
    int n = 0;
    for (int i = 0; i < 8; ++i) {
        while (n >= 2 && cross2(hull[n - 2], hull[n - 1], pts[i]) <= 0.0) --n;
        hull[n][0] = pts[i][0];
        hull[n++][1] = pts[i][1];
    }
    for (int i = 6, lower = n + 1; i >= 0; --i) {
        while (n >= lower && cross2(hull[n - 2], hull[n - 1], pts[i]) <= 0.0) --n;
        hull[n][0] = pts[i][0];
        hull[n++][1] = pts[i][1];
    }
    --n; /* the last point is the first */
    const double half = 0.5 + m;
    int e = 0;
    for (int i = 0; i < n && e < CLVR_LIVE_EDGES; ++i) {
        const double *p = hull[i], *q = hull[i + 1 < n ? i + 1 : 0];
        /* The chain runs counter-clockwise (x right, y up; cross2 > 0 turns
         * left): the outward normal is the edge turned clockwise. */
        const double len = sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]));
        if (!(len > 1e-9 * (1.0 + fabs(p[0]) + fabs(p[1])))) continue;
        const double nx = (q[1] - p[1]) / len, ny = (p[0] - q[0]) / len, c = nx * p[0] + ny * p[1];
        /* The pixel's widened square: centre (x + 1/2, y + 1/2), half
         * width `half`; beyond the edge when its nearest corner is. A
         * hundredth of a pixel for the float test in the kernel. */
        edges[e][0] = (float)nx;
        edges[e][1] = (float)ny;
        edges[e][2] = (float)(c + half * (fabs(nx) + fabs(ny)) + 0.01 + 1e-6 * fabs(c));
        ++e;
    }
}

int clvr_ray_hits_box(const float org[3], const float dir[3], const float lo[3], const float hi[3])
{
    double t0 = 0.0, t1 = INFINITY;
    for (int k = 0; k < 3; ++k) {
        double inv = 1.0 / dir[k], a = (lo[k] - org[k]) * inv, b = (hi[k] - org[k]) * inv;
        if (a > b) { double t = a; a = b; b = t; }
        if (a > t0) t0 = a;
        if (b < t1) t1 = b;
    }
    return t0 <= t1;
}
