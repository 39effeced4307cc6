/* camera.h: the pinhole camera (kernels/clvr_shared.h: clvr_camera, and
 * clvr_camera_ray, shared with the render kernel). Built from eye, look-at
 * point and up vector, or framed automatically around a bounding box.
 * World units are the mesh's; angles are degrees. */
#ifndef CLVR_CAMERA_H
#define CLVR_CAMERA_H

#include <stdint.h>

#include "clvr_shared.h"
#include "status.h"

/* Margin kept by clvr_camera_frame_box: the box's projection stays inside
 * this fraction of the half-width and half-height of the image. */
#define CLVR_CAMERA_FRAME_FILL 0.9f

/* Builds a camera at eye looking at target; up need not be orthogonal to the
 * view direction (it is orthogonalised) but must not be parallel to it.
 * fovy_deg in (0, 180) is the vertical field of view; width, height >= 1.
 * Errors (CLVR_ERR_USAGE): non-finite input, eye == target, up parallel to
 * the view direction or zero, fov out of range, empty image. */
clvr_status clvr_camera_look_at(clvr_camera *cam, const float eye[3], const float target[3], const float up[3],
                                float fovy_deg, uint32_t width, uint32_t height, clvr_error *err);

/* Default oblique view direction of clvr_camera_frame_box, from the target
 * towards the eye (unnormalised): front-right-above, about 23 degrees of
 * elevation, with +y up (VTK/ParaView convention). */
#define CLVR_CAMERA_VIEW_X 1.0f
#define CLVR_CAMERA_VIEW_Y 0.8f
#define CLVR_CAMERA_VIEW_Z 1.6f

/* Frames the box [lo, hi]: looks at its centre from the default oblique
 * direction with +y up, at the smallest distance at which all 8 corners
 * project inside CLVR_CAMERA_FRAME_FILL of the image (exact for the box, not
 * a bounding-sphere estimate). A degenerate box (a point) is viewed from
 * distance 1. Errors: non-finite or inverted bounds (CLVR_ERR_BAD_VALUE),
 * bad fov/size as clvr_camera_look_at. */
clvr_status clvr_camera_frame_box(clvr_camera *cam, const float lo[3], const float hi[3], float fovy_deg,
                                  uint32_t width, uint32_t height, clvr_error *err);

/* How the automatic framing looks at a box: relative to the default oblique
 * view (CLVR_CAMERA_VIEW_*), re-expressed about an up axis. */
typedef struct clvr_camera_view {
    float up[3];         /* world up axis; need not be unit, must be non-zero */
    float azimuth_deg;   /* turn about up, counterclockwise seen from +up (right-hand rule) */
    float elevation_deg; /* added to the default elevation (about 23 degrees); the sum is
                          * clamped to [-89, 89] so that up stays across the line of sight */
    float zoom;          /* > 0: the fitted distance from the box centre is divided by zoom */
} clvr_camera_view;

/* +y up, no turn, zoom 1: clvr_camera_frame_box's view. */
void clvr_camera_view_default(clvr_camera_view *v);

/* Unit direction from the box centre toward the eye for view v (the
 * "forward" of the camera is its negative), and the orthonormal basis it is
 * built from: side x up = front. For up = +y the basis is x, y, z, so the
 * default view is CLVR_CAMERA_VIEW_* exactly; for +z (Exodus, OpenFOAM) it is
 * x, z, -y: the camera looks from -y and front-right-above as for +y. For
 * an up along x the side is y. Returns nonzero for a zero or non-finite up. */
int clvr_camera_view_direction(const clvr_camera_view *v, float dir[3]);

/* As clvr_camera_frame_box, seen from view v: the eye lies on the centre +
 * t * clvr_camera_view_direction line at the smallest t that fits the box
 * (then divided by v->zoom), the camera's up is v->up. Errors as
 * clvr_camera_frame_box, and CLVR_ERR_USAGE for a zero up or zoom <= 0. */
clvr_status clvr_camera_frame_view(clvr_camera *cam, const float lo[3], const float hi[3],
                                   const clvr_camera_view *v, float fovy_deg, uint32_t width, uint32_t height,
                                   clvr_error *err);

/* Rotates point p about the line through centre along axis (non-zero) by
 * deg degrees, counterclockwise seen from the tip of axis (Rodrigues). For
 * turntables: the eye about the look-at point. */
void clvr_camera_rotate_about(const float p[3], const float centre[3], const float axis[3], float deg, float out[3]);

/* Parses "x", "y", "z", "-x", "-y", "-z" (also "+x", ...) into a unit axis;
 * returns nonzero for anything else (out untouched). */
int clvr_camera_parse_axis(const char *text, float out[3]);

/* Parses "px,py,pz,lx,ly,lz,ux,uy,uz" (eye, look-at point, up; 9 finite
 * decimal numbers separated by commas, spaces around them allowed) into
 * out[9]. Errors name the position and the text: CLVR_ERR_USAGE. */
clvr_status clvr_camera_parse(const char *text, float out[9], clvr_error *err);

/* Projects world point p into continuous pixel coordinates (px, py) (same
 * convention as clvr_camera_ray) and returns its depth along forward;
 * depth <= 0 means behind the eye (px, py then meaningless). For tests and
 * viewers. */
float clvr_camera_project(const clvr_camera *cam, const float p[3], float *px, float *py);

/* 1 when the ray from org along dir (t >= 0) meets the box [lo, hi]: which
 * pixels see a volume (auto's pilot, bench_render's inside pixels). */
int clvr_ray_hits_box(const float org[3], const float dir[3], const float lo[3], const float hi[3]);

/* The pixels whose camera rays (clvr_camera_ray through any point of the
 * pixel) can meet the box [lo, hi], widened by `margin` pixels on every
 * side, as clvr_frame.live and .live_edges (clvr_frame_traces tells a
 * pixel): the rectangle of the box's projection cut to the image, and the
 * edges of that projection (the convex hull of the box's corners projected
 * through the camera's own ray vectors, in double). Every pixel when a
 * corner is beside or behind the eye (the eye in or next to the box:
 * the projection is unbounded) or the ray vectors are degenerate; none
 * when the box is wholly behind the eye. The render kernel writes pixels
 * it does not trace as background (kernels/render.cl). */
void clvr_camera_live(const clvr_camera *cam, const float lo[3], const float hi[3], uint32_t margin, clvr_u32 live[4],
                      float edges[CLVR_LIVE_EDGES][4]);

#endif /* CLVR_CAMERA_H */
